/* test_file.c: core/common/fp_file.h: fp_file_temp_beside (the temporary file's name, folder
 * and flags, its errors), fp_file_new_mode against umask(2), fp_file_target, the readers'
 * fp_file_open_regular, and the writers' fp_file_open_output / commit / abort (the whole file
 * with the new mode, nothing left by an abort or a failed commit, folders and FIFOs refused). */
#define _GNU_SOURCE /* mkdtemp */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
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

/* the name: ".NAME<tag>.PID.XXXXXX" in the target's folder, six characters filled in */
static void check_name(const char *tmp, const char *folder, const char *name, const char *tag)
{
    char want[256];
    snprintf(want, sizeof want, "%s%s.%s%s.%ld.", folder, folder[0] ? "/" : "", name, tag, (long)getpid());
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
    char pid[32];
    snprintf(pid, sizeof pid, "%ld.", (long)getpid());
    size_t need = strlen(dir) + strlen("/.x.csv.XXXXXX") + strlen(pid) + 1;
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

/* fp_file_read_all: a file whole and NUL-ended, up to max bytes exactly; one byte more,
 * -EFBIG and nothing returned; an empty file ""; what is not a regular file refused as
 * fp_file_open_regular refuses it */
static void test_read_all(void **state)
{
    (void)state;
    char p[256];
    snprintf(p, sizeof p, "%s/all.bin", dir);
    const size_t size = 20000; /* past the first 8 KiB buffer: it grows */
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    for (size_t i = 0; i < size; i++) fputc(i % 7 ? 'a' + (int)(i % 26) : 0, f); /* NULs too */
    fclose(f);
    char *b = (char *)1;
    size_t n = 1;
    assert_int_equal(fp_file_read_all(p, size, &b, &n), 0);
    assert_int_equal(n, size);
    for (size_t i = 0; i < size; i++) assert_int_equal(b[i], i % 7 ? 'a' + (int)(i % 26) : 0);
    assert_int_equal(b[size], 0);
    free(b);
    assert_int_equal(fp_file_read_all(p, size - 1, &b, &n), -EFBIG);
    assert_null(b);
    assert_int_equal(n, 0);
    assert_int_equal(fp_file_read_all(p, SIZE_MAX, &b, &n), 0); /* (no limit: max + 1 not wrapped) */
    assert_int_equal(n, size);
    free(b);
    f = fopen(p, "wb");
    fclose(f);
    assert_int_equal(fp_file_read_all(p, 0, &b, &n), 0);
    assert_int_equal(n, 0);
    assert_string_equal(b, "");
    free(b);
    /* a file already past max (a sparse 2 TiB, max 1 TiB): -EFBIG from its size, before a byte
     * is read (reading up to max first ran out of memory: -ENOMEM) */
    if (truncate(p, (off_t)1 << 41) == 0) {
        assert_int_equal(fp_file_read_all(p, (size_t)1 << 40, &b, &n), -EFBIG);
        assert_null(b);
        assert_int_equal(truncate(p, 0), 0);
    }
    assert_int_equal(unlink(p), 0);
    assert_int_equal(fp_file_read_all(p, 10, &b, &n), -ENOENT);
    assert_null(b);
    assert_int_equal(fp_file_read_all(dir, 10, &b, &n), -EISDIR);
    snprintf(p, sizeof p, "%s/fifo2", dir);
    assert_int_equal(mkfifo(p, 0600), 0);
    assert_int_equal(fp_file_read_all(p, 10, &b, &n), -ENXIO);
    assert_int_equal(unlink(p), 0);
    assert_int_equal(fp_file_read_all(NULL, 10, &b, &n), -EINVAL);
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

/* the names in dir that start with '.' (temporaries), "." and ".." aside */
static int hidden_files(void)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    for (struct dirent *e; (e = readdir(d));)
        if (e->d_name[0] == '.' && strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
            n++;
    closedir(d);
    return n;
}

static void write_file(const char *p, const char *text, mode_t mode)
{
    FILE *f = fopen(p, "w");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
    assert_int_equal(chmod(p, mode), 0);
}

static void check_file(const char *p, const char *text, mode_t mode)
{
    char buf[256] = "";
    FILE *f = fopen(p, "r");
    assert_non_null(f);
    size_t got = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[got] = '\0';
    assert_string_equal(buf, text);
    struct stat st;
    assert_int_equal(stat(p, &st), 0);
    assert_int_equal(st.st_mode & 07777, mode);
}

/* A save killed before its commit or abort (SIGKILL) left its temporary beside the target:
 * the next fp_file_open_output of that target and tag removes it (its PID names no process),
 * and leaves a live process's, this one's, another tag's and a name without a PID. */
static void test_output_stale(void **state)
{
    (void)state;
    pid_t child = fork();
    assert_true(child >= 0);
    if (!child) _exit(0);
    assert_int_equal(waitpid(child, NULL, 0), child); /* (gone: its pid names no process) */
    /* (a folder of its own: this thread's last read of another is kept for a second) */
    char sub[128], p[256], dead[300], live[300], mine[300], other[300], nopid[300];
    snprintf(sub, sizeof sub, "%s/stale", dir);
    assert_int_equal(mkdir(sub, 0700), 0);
    snprintf(p, sizeof p, "%s/take.pc2", sub);
    snprintf(dead, sizeof dead, "%s/.take.pc2.%ld.aB3dE9", sub, (long)child);
    snprintf(live, sizeof live, "%s/.take.pc2.1.aB3dE9", sub); /* init: always there */
    snprintf(mine, sizeof mine, "%s/.take.pc2.%ld.zZ9yY8", sub, (long)getpid());
    snprintf(other, sizeof other, "%s/.take.pc2frames.%ld.aB3dE9", sub, (long)child);
    snprintf(nopid, sizeof nopid, "%s/.take.pc2.aB3dE9", sub);
    const char *all[] = {dead, live, mine, other, nopid};
    for (size_t i = 0; i < 5; i++) write_file(all[i], "part", 0600);
    fp_file_output o;
    assert_int_equal(fp_file_open_output(p, "", "wb", 0, &o), 0);
    assert_int_equal(o.stale, 1);
    assert_int_equal(access(dead, F_OK), -1);
    for (size_t i = 1; i < 5; i++) assert_int_equal(access(all[i], F_OK), 0);
    assert_int_equal(fp_file_output_commit(&o), 0);
    /* the next save of another tag in that folder (the folder's read kept): the other tag's */
    assert_int_equal(fp_file_open_output(p, "frames", "wb", 0, &o), 0);
    assert_int_equal(o.stale, 1);
    assert_int_equal(access(other, F_OK), -1);
    fp_file_output_abort(&o);
    const char *kept[] = {live, mine, nopid};
    for (size_t i = 0; i < 3; i++) assert_int_equal(unlink(kept[i]), 0);
    assert_int_equal(unlink(p), 0);
    assert_int_equal(rmdir(sub), 0);
}

/* fp_file_open_output + commit: the temporary beside the target while it is written (the
 * target as it was), then the whole content under the target's name with the mode a new file
 * gets (a replaced file's own with FP_FILE_OUTPUT_KEEP_MODE), nothing left beside it; a
 * symbolic link written through. */
static void test_output_commit(void **state)
{
    (void)state;
    mode_t was = umask(027);
    char p[256], l[256];
    snprintf(p, sizeof p, "%s/out.json", dir);
    write_file(p, "old", 0600);
    fp_file_output o;
    assert_int_equal(fp_file_open_output(p, "", "wb", 0, &o), 0);
    assert_int_equal(o.failed, FP_FILE_STEP_NONE);
    assert_string_equal(o.path, p);
    check_name(o.tmp, dir, "out.json", "");
    assert_non_null(o.f);
    assert_int_equal(fileno(o.f), o.fd);
    assert_int_equal(fcntl(o.fd, F_GETFD) & FD_CLOEXEC, FD_CLOEXEC);
    struct stat st;
    assert_int_equal(fstat(o.fd, &st), 0);
    assert_int_equal(st.st_mode & 07777, 0640); /* 0666 & ~027, already while written */
    assert_int_equal(fputs("{\"whole\": 1}\n", o.f) >= 0, 1);
    check_file(p, "old", 0600);
    assert_int_equal(hidden_files(), 1);
    assert_int_equal(fp_file_output_commit(&o), 0);
    assert_int_equal(o.failed, FP_FILE_STEP_NONE);
    assert_string_equal(o.tmp, "");
    assert_int_equal(o.fd, -1);
    assert_null(o.f);
    assert_string_equal(o.path, p); /* kept for messages */
    check_file(p, "{\"whole\": 1}\n", 0640);
    assert_int_equal(hidden_files(), 0);
    fp_file_output_abort(&o); /* after a commit: nothing, the file stays */
    check_file(p, "{\"whole\": 1}\n", 0640);
    /* through a link, on the descriptor, keeping the replaced file's mode, the folder synced */
    assert_int_equal(chmod(p, 0604), 0);
    snprintf(l, sizeof l, "%s/link.json", dir);
    assert_int_equal(symlink("out.json", l), 0);
    assert_int_equal(fp_file_open_output(l, "x", NULL,
                                         FP_FILE_OUTPUT_KEEP_MODE | FP_FILE_OUTPUT_SYNC_FOLDER,
                                         &o), 0);
    assert_null(o.f);
    assert_string_equal(o.path, p);
    check_name(o.tmp, dir, "out.json", "x");
    assert_int_equal(write(o.fd, "new", 3), 3);
    assert_int_equal(fp_file_output_commit(&o), 0);
    check_file(p, "new", 0604);
    assert_int_equal(lstat(l, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_int_equal(hidden_files(), 0);
    /* a new file with KEEP_MODE: the new mode */
    assert_int_equal(unlink(p), 0);
    assert_int_equal(fp_file_open_output(p, "", NULL, FP_FILE_OUTPUT_KEEP_MODE, &o), 0);
    assert_int_equal(fp_file_output_commit(&o), 0);
    check_file(p, "", 0640);
    assert_int_equal(unlink(l), 0);
    assert_int_equal(unlink(p), 0);
    umask(was);
}

/* fp_file_output_abort, and a commit that fails: the temporary removed, the target as it was */
static void test_output_abort(void **state)
{
    (void)state;
    char p[256];
    snprintf(p, sizeof p, "%s/keep.csv", dir);
    write_file(p, "precious", 0600);
    fp_file_output o;
    assert_int_equal(fp_file_open_output(p, "frames", "w+b", 0, &o), 0);
    assert_int_equal(fputs("half a", o.f) >= 0, 1);
    assert_int_equal(fflush(o.f), 0);
    assert_int_equal(hidden_files(), 1);
    fp_file_output_abort(&o);
    assert_string_equal(o.tmp, "");
    assert_int_equal(o.fd, -1);
    assert_null(o.f);
    assert_int_equal(hidden_files(), 0);
    check_file(p, "precious", 0600);
    fp_file_output_abort(&o);  /* twice: nothing */
    fp_file_output_abort(NULL);
    fp_file_output zero;
    memset(&zero, 0, sizeof zero);
    fp_file_output_abort(&zero); /* a zeroed one holds nothing (fd 0 is not closed) */
    assert_int_not_equal(fcntl(0, F_GETFD), -1);
    assert_int_equal(fp_file_output_commit(&zero), -EINVAL);
    /* a write the stream failed before (a read on a write-only stream sets its error) */
    assert_int_equal(fp_file_open_output(p, "", "wb", 0, &o), 0);
    assert_int_equal(fputs("all", o.f) >= 0, 1);
    assert_int_equal(fgetc(o.f), EOF);
    assert_true(ferror(o.f));
    assert_int_equal(fp_file_output_commit(&o), -EIO);
    assert_int_equal(o.failed, FP_FILE_STEP_SYNC);
    assert_int_equal(hidden_files(), 0);
    check_file(p, "precious", 0600);
    /* the rename fails: the target became a folder meanwhile */
    char q[256];
    snprintf(q, sizeof q, "%s/late.obj", dir);
    assert_int_equal(fp_file_open_output(q, "", NULL, 0, &o), 0);
    assert_int_equal(mkdir(q, 0700), 0);
    assert_int_equal(fp_file_output_commit(&o), -EISDIR);
    assert_int_equal(o.failed, FP_FILE_STEP_RENAME);
    assert_int_equal(hidden_files(), 0);
    assert_int_equal(rmdir(q), 0);
    check_file(p, "precious", 0600);
    assert_int_equal(unlink(p), 0);
}

/* what fp_file_open_output refuses, and with which step: a folder (-EISDIR) and a FIFO
 * (-ENXIO) as the target, kept, no temporary made (the writers report both as -EEXIST, exit
 * 73); no such folder (-ENOENT, the temporary's, with the path resolved); NULL (-EINVAL) */
static void test_output_refused(void **state)
{
    (void)state;
    char p[256], sub[256];
    fp_file_output o;
    snprintf(sub, sizeof sub, "%s/folder.png", dir);
    assert_int_equal(mkdir(sub, 0700), 0);
    assert_int_equal(fp_file_open_output(sub, "", "wb", 0, &o), -EISDIR);
    assert_int_equal(o.failed, FP_FILE_STEP_TARGET);
    assert_string_equal(o.tmp, "");
    assert_int_equal(o.fd, -1);
    assert_null(o.f);
    fp_file_output_abort(&o); /* after a failed open: nothing */
    snprintf(p, sizeof p, "%s/fifo.obj", dir);
    assert_int_equal(mkfifo(p, 0600), 0);
    assert_int_equal(fp_file_open_output(p, "", NULL, 0, &o), -ENXIO);
    assert_int_equal(o.failed, FP_FILE_STEP_TARGET);
    struct stat st;
    assert_int_equal(lstat(p, &st), 0);
    assert_true(S_ISFIFO(st.st_mode));
    assert_int_equal(hidden_files(), 0);
    assert_int_equal(unlink(p), 0);
    assert_int_equal(rmdir(sub), 0);
    snprintf(p, sizeof p, "%s/no/such/t.csv", dir);
    assert_int_equal(fp_file_open_output(p, "", "w", 0, &o), -ENOENT);
    assert_int_equal(o.failed, FP_FILE_STEP_TEMP);
    assert_string_equal(o.path, p);
    assert_string_equal(o.tmp, "");
    assert_int_equal(fp_file_open_output(NULL, "", "w", 0, &o), -EINVAL);
    assert_int_equal(o.failed, FP_FILE_STEP_TARGET);
    assert_int_equal(fp_file_open_output(p, "", "w", 0, NULL), -EINVAL);
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
        cmocka_unit_test(test_read_all),
        cmocka_unit_test(test_output_code),
        cmocka_unit_test(test_output_commit),
        cmocka_unit_test(test_output_stale),
        cmocka_unit_test(test_output_abort),
        cmocka_unit_test(test_output_refused),
    };
    return cmocka_run_group_tests(tests, make_dir, remove_dir);
}
