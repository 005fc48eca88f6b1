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

/* fp_file_target: the file a save replaces. A new name or a regular file: itself; a link
 * chain: its end (relative links beside the link, absolute ones as written, a dangling one's
 * missing file); a folder, a FIFO: refused; a loop: -ELOOP. */
static void test_target(void **state)
{
    (void)state;
    char p[256], q[256], real[256];
    snprintf(p, sizeof p, "%s/new.obj", dir);
    assert_int_equal(fp_file_target(p, real, sizeof real), 0);
    assert_string_equal(real, p);
    snprintf(q, sizeof q, "%s/file.obj", dir);
    FILE *f = fopen(q, "w");
    assert_non_null(f);
    fclose(f);
    assert_int_equal(fp_file_target(q, real, sizeof real), 0);
    assert_string_equal(real, q);
    /* relative link -> link -> file */
    snprintf(p, sizeof p, "%s/l1", dir);
    assert_int_equal(symlink("file.obj", p), 0);
    snprintf(p, sizeof p, "%s/l2", dir);
    assert_int_equal(symlink("l1", p), 0);
    assert_int_equal(fp_file_target(p, real, sizeof real), 0);
    assert_string_equal(real, q);
    /* absolute dangling link: its missing file */
    snprintf(p, sizeof p, "%s/l3", dir);
    snprintf(q, sizeof q, "%s/absent.obj", dir);
    assert_int_equal(symlink(q, p), 0);
    assert_int_equal(fp_file_target(p, real, sizeof real), 0);
    assert_string_equal(real, q);
    /* a folder, a FIFO (also through a link), a loop, too small a buffer */
    assert_int_equal(fp_file_target(dir, real, sizeof real), -EISDIR);
    snprintf(q, sizeof q, "%s/fifo", dir);
    assert_int_equal(mkfifo(q, 0600), 0);
    assert_int_equal(fp_file_target(q, real, sizeof real), -ENXIO);
    snprintf(p, sizeof p, "%s/l4", dir);
    assert_int_equal(symlink("fifo", p), 0);
    assert_int_equal(fp_file_target(p, real, sizeof real), -ENXIO);
    snprintf(p, sizeof p, "%s/loop", dir);
    assert_int_equal(symlink("loop", p), 0);
    assert_int_equal(fp_file_target(p, real, sizeof real), -ELOOP);
    snprintf(p, sizeof p, "%s/file.obj", dir);
    assert_int_equal(fp_file_target(p, real, 8), -ENAMETOOLONG);
    assert_int_equal(fp_file_target(NULL, real, sizeof real), -EINVAL);
    assert_non_null(strstr(fp_file_error_text(-ENXIO), "not a regular file"));
    assert_non_null(strstr(fp_file_error_text(-EISDIR), "folder"));
    static const char *made[] = {"l1", "l2", "l3", "l4", "loop", "fifo", "file.obj"};
    for (size_t i = 0; i < sizeof made / sizeof made[0]; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, made[i]);
        assert_int_equal(unlink(p), 0);
    }
}

/* fp_file_open_regular: a file opens (blocking again); a FIFO with no writer is refused at
 * once instead of holding the open (a blocking open would never return here); a folder too. */
static void test_open_regular(void **state)
{
    (void)state;
    char p[256];
    snprintf(p, sizeof p, "%s/r.txt", dir);
    FILE *f = fopen(p, "w");
    assert_non_null(f);
    fputs("abc", f);
    fclose(f);
    int fd = fp_file_open_regular(p);
    assert_true(fd >= 0);
    assert_int_equal(fcntl(fd, F_GETFL) & O_NONBLOCK, 0);
    assert_true((fcntl(fd, F_GETFD) & FD_CLOEXEC) != 0);
    char buf[4];
    assert_int_equal(read(fd, buf, sizeof buf), 3);
    close(fd);
    int code = 0;
    f = fp_file_fopen_regular(p, &code);
    assert_non_null(f);
    fclose(f);
    assert_int_equal(unlink(p), 0);
    assert_int_equal(fp_file_open_regular(p), -ENOENT);
    assert_null(fp_file_fopen_regular(p, &code));
    assert_int_equal(code, -ENOENT);
    snprintf(p, sizeof p, "%s/fifo", dir);
    assert_int_equal(mkfifo(p, 0600), 0);
    assert_int_equal(fp_file_open_regular(p), -ENXIO);
    assert_int_equal(unlink(p), 0);
    assert_int_equal(fp_file_open_regular(dir), -EISDIR);
}

/* fp_file_output_code: the errno of a failed output call as the project reports it */
static void test_output_code(void **state)
{
    (void)state;
    static const int cases[][2] = {{ENOENT, -ENOENT}, {ENOTDIR, -ENOENT}, {EACCES, -EACCES},
                                   {EPERM, -EACCES},  {EROFS, -EACCES},   {ENOSPC, -ENOSPC},
                                   {EDQUOT, -ENOSPC}, {ENOMEM, -ENOMEM},  {EIO, -EIO},
                                   {EFBIG, -EIO}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        assert_int_equal(fp_file_output_code(cases[i][0]), cases[i][1]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_beside),
        cmocka_unit_test(test_working_folder),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_new_mode),
        cmocka_unit_test(test_target),
        cmocka_unit_test(test_open_regular),
        cmocka_unit_test(test_output_code),
    };
    return cmocka_run_group_tests(tests, make_dir, remove_dir);
}
