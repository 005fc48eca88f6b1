/* test_png_file.c: fp_png_write (ui/viewer/png_file.h) without a display: the pixels read
 * back by stb_image (bottom-up and top-down rows), the file's mode under the umask, errors
 * that name the file, and no temporary file left behind when the rename fails. */
#define _GNU_SOURCE /* mkdtemp */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <stb_image.h>

#include "png_file.h"

static char dir[64];

static int make_dir(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/fp-test-png-XXXXXX");
    return mkdtemp(dir) ? 0 : -1;
}

/* the folder's entries other than . and .. */
static int entries(void)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int k = 0;
    for (struct dirent *e; (e = readdir(d));) k += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    closedir(d);
    return k;
}

enum { W = 5, H = 3 };

static void image(unsigned char px[H][W][3])
{
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            px[y][x][0] = (unsigned char)(40 * x);
            px[y][x][1] = (unsigned char)(70 * y + 1);
            px[y][x][2] = (unsigned char)(x * y + 7);
        }
}

static void test_round_trip(void **state)
{
    (void)state;
    unsigned char px[H][W][3];
    image(px);
    char path[128], err[512];
    snprintf(path, sizeof path, "%s/a.png", dir);
    for (int bottom_up = 0; bottom_up <= 1; bottom_up++) {
        mode_t um = umask(bottom_up ? 022 : 077);
        assert_int_equal(fp_png_write(path, W, H, &px[0][0][0], bottom_up, err, sizeof err), 0);
        umask(um);
        struct stat sb;
        assert_int_equal(stat(path, &sb), 0);
        assert_int_equal(sb.st_mode & 0777, bottom_up ? 0644 : 0600);
        int w, h, n;
        unsigned char *back = stbi_load(path, &w, &h, &n, 3);
        assert_non_null(back);
        assert_int_equal(w, W);
        assert_int_equal(h, H);
        for (int y = 0; y < H; y++) /* bottom-up: the file's first row is the array's last */
            assert_memory_equal(back + (size_t)y * W * 3, px[bottom_up ? H - 1 - y : y], W * 3);
        stbi_image_free(back);
        assert_int_equal(entries(), 1);
    }
    assert_int_equal(unlink(path), 0);
}

static void test_errors(void **state)
{
    (void)state;
    unsigned char px[H][W][3];
    image(px);
    char path[128], err[512];
    snprintf(path, sizeof path, "%s/no/such/a.png", dir);
    assert_int_equal(fp_png_write(path, W, H, &px[0][0][0], 0, err, sizeof err), -ENOENT);
    assert_non_null(strstr(err, path));
    assert_int_equal(fp_png_write(path, 0, H, &px[0][0][0], 0, err, sizeof err), -EINVAL);
    /* the rename fails (the target is a folder): the temporary file goes, the folder stays */
    snprintf(path, sizeof path, "%s/sub.png", dir);
    assert_int_equal(mkdir(path, 0755), 0);
    assert_true(fp_png_write(path, W, H, &px[0][0][0], 0, err, sizeof err) < 0);
    assert_non_null(strstr(err, path));
    assert_int_equal(entries(), 1);
    assert_int_equal(rmdir(path), 0);
    assert_int_equal(entries(), 0);
    assert_int_equal(rmdir(dir), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, make_dir, NULL);
}
