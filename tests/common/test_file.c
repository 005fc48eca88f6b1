/* test_file.c: fp_file_temp_beside and fp_file_new_mode (core/common/fp_file.h): the
 * temporary file's name, folder and flags, its errors, and the mode against umask(2). */
#define _GNU_SOURCE /* mkdtemp */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fp_file.h"

static char dir[64];

static int make_dir(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/fp-test-file-XXXXXX");
    return mkdtemp(dir) ? 0 : -1;
}

static int remove_dir(void **state)
{
    (void)state;
    return rmdir(dir);
}

/* the name: ".NAME<tag>.XXXXXX" in the target's folder, six characters filled in */
static void check_name(const char *tmp, const char *folder, const char *name, const char *tag)
{
    char want[256];
    snprintf(want, sizeof want, "%s%s.%s%s.", folder, folder[0] ? "/" : "", name, tag);
    size_t wl = strlen(want);
    assert_int_equal(strlen(tmp), wl + 6);
    assert_memory_equal(tmp, want, wl);
    assert_null(strchr(tmp + wl, '/'));
    assert_string_not_equal(tmp + wl, "XXXXXX");
}

static void test_beside(void **state)
{
    (void)state;
    char path[128], tmp[160];
    snprintf(path, sizeof path, "%s/take.glb", dir);
    int fd = fp_file_temp_beside(path, "frames", tmp, sizeof tmp);
    assert_true(fd >= 0);
    check_name(tmp, dir, "take.glb", "frames");
    struct stat st;
    assert_int_equal(fstat(fd, &st), 0);
    assert_true(S_ISREG(st.st_mode));
    assert_int_equal(st.st_size, 0);
    assert_int_equal(fcntl(fd, F_GETFD) & FD_CLOEXEC, FD_CLOEXEC);
    assert_int_equal(access(path, F_OK), -1); /* the target is not made */
    /* a second one is another file */
    char tmp2[160];
    int fd2 = fp_file_temp_beside(path, NULL, tmp2, sizeof tmp2);
    assert_true(fd2 >= 0);
    check_name(tmp2, dir, "take.glb", "");
    assert_string_not_equal(tmp, tmp2);
    close(fd), close(fd2);
    assert_int_equal(unlink(tmp), 0);
    assert_int_equal(unlink(tmp2), 0);
}

static void test_working_folder(void **state)
{
    (void)state;
    char old[4096], tmp[64];
    assert_non_null(getcwd(old, sizeof old));
    assert_int_equal(chdir(dir), 0);
    int fd = fp_file_temp_beside("face.obj", "", tmp, sizeof tmp);
    assert_true(fd >= 0);
    check_name(tmp, "", "face.obj", "");
    close(fd);
    assert_int_equal(unlink(tmp), 0);
    assert_int_equal(chdir(old), 0);
}

static void test_errors(void **state)
{
    (void)state;
    char path[128], tmp[160];
    snprintf(path, sizeof path, "%s/no/such/folder/x.csv", dir);
    strcpy(tmp, "old");
    assert_int_equal(fp_file_temp_beside(path, "", tmp, sizeof tmp), -ENOENT);
    assert_string_equal(tmp, "");
    snprintf(path, sizeof path, "%s/x.csv", dir);
    /* too small by one for the name and its NUL */
    size_t need = strlen(dir) + strlen("/.x.csv.XXXXXX") + 1;
    strcpy(tmp, "old");
    assert_int_equal(fp_file_temp_beside(path, "", tmp, need - 1), -ENAMETOOLONG);
    assert_string_equal(tmp, "");
    int fd = fp_file_temp_beside(path, "", tmp, need);
    assert_true(fd >= 0);
    close(fd);
    unlink(tmp);
    assert_int_equal(fp_file_temp_beside(NULL, "", tmp, sizeof tmp), -EINVAL);
    assert_int_equal(fp_file_temp_beside(path, "", NULL, 10), -EINVAL);
}

static void test_new_mode(void **state)
{
    (void)state;
    const mode_t masks[] = {022, 077, 0, 002};
    mode_t was = umask(022);
    for (size_t i = 0; i < sizeof masks / sizeof *masks; i++) {
        umask(masks[i]);
        assert_int_equal(fp_file_new_mode(), 0666 & ~masks[i]);
    }
    umask(was);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_beside),
        cmocka_unit_test(test_working_folder),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_new_mode),
    };
    return cmocka_run_group_tests(tests, make_dir, remove_dir);
}
