/* fp_take_edit_header (issue 53, item 7): a take's rating and description rewritten, every
 * other byte as it was; the frames read back the same; the refusals (a rating outside 0..5,
 * a description that is no text, a take with no end chunk, a damaged header) leave the file
 * byte for byte as it was; the file's mode is kept. */
#define _GNU_SOURCE
#include "take_testutil.h"
#include "fp_take.h"

#include <errno.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cmocka.h>

/* The whole file (malloc()ed), its size in *n. */
static unsigned char *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long sz = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc((size_t)sz + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)sz, f), (size_t)sz);
    fclose(f);
    *n = (size_t)sz;
    return b;
}

/* A take of n rich frames in dir (closed: with an end chunk unless open). */
static void make_take(const char *dir, uint64_t n, bool open_end, char *path, size_t len,
                      fp_take_writer **keep)
{
    fp_take_header h;
    tt_header(&h, "ed");
    h.description = "first";
    h.rating = 2;
    fp_take_writer_options o = {.chunk_frames = 7, .no_sync = true};
    fp_take_writer *w;
    char err[512];
    if (fp_take_writer_create(dir, &h, &o, &w, err, sizeof err)) fail_msg("%s", err);
    snprintf(path, len, "%s", fp_take_writer_path(w));
    for (uint64_t i = 0; i < n; i++) {
        tt_frame t;
        tt_make(&t, i, 1);
        if (fp_take_writer_add(w, &t.f, err, sizeof err)) fail_msg("%s", err);
    }
    if (open_end) {
        if (fp_take_writer_flush(w, err, sizeof err)) fail_msg("%s", err);
        *keep = w;
        return;
    }
    if (fp_take_writer_close(&w, 0, 0, err, sizeof err)) fail_msg("%s", err);
}

/* The header chunk's payload length of a take's bytes (signature 16, chunk head 16). */
static size_t head_len(const unsigned char *b)
{
    return (size_t)b[24] | (size_t)b[25] << 8 | (size_t)b[26] << 16 | (size_t)b[27] << 24;
}

static void test_rewrite(void **state)
{
    (void)state;
    char dir[] = "/tmp/fp-take-edit-XXXXXX", path[4096], err[512];
    assert_non_null(mkdtemp(dir));
    make_take(dir, 40, false, path, sizeof path, NULL);
    assert_int_equal(chmod(path, 0640), 0);
    size_t n0, n1;
    unsigned char *b0 = slurp(path, &n0);
    fp_take_edit e = {.set_rating = true, .rating = 5, .description = "take \"two\"\nsecond line \xc3\xa9"};
    int rc = fp_take_edit_header(path, &e, err, sizeof err);
    if (rc) fail_msg("%s", err);
    unsigned char *b1 = slurp(path, &n1);
    /* the signature and everything after the header chunk byte-identical */
    const size_t l0 = head_len(b0), l1 = head_len(b1);
    assert_memory_equal(b0, b1, 16);
    assert_memory_equal(b0 + 28, b1 + 28, 4); /* (the chunk's record count) */
    assert_int_equal(n0 - (36 + l0), n1 - (36 + l1));
    assert_memory_equal(b0 + 36 + l0, b1 + 36 + l1, n0 - (36 + l0));
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0640);
    /* the header reads back with the new values, the frames as written */
    fp_take_reader *r;
    if (fp_take_reader_open(path, &r, err, sizeof err)) fail_msg("%s", err);
    assert_string_equal(fp_take_reader_warning(r), "");
    assert_int_equal(fp_take_reader_header(r)->rating, 5);
    assert_string_equal(fp_take_reader_header(r)->description, e.description);
    assert_string_equal(fp_take_reader_header(r)->slate, "ed");
    assert_true(fp_take_reader_summary(r)->complete);
    assert_int_equal(fp_take_reader_frames(r), 40);
    for (size_t i = 0; i < 40; i++) {
        fp_take_frame f;
        tt_frame want;
        if (fp_take_reader_read(r, i, &f, err, sizeof err)) fail_msg("%s", err);
        tt_make(&want, i, 1);
        assert_int_equal(tt_compare(&f, &want.f), 0);
    }
    fp_take_reader_close(&r);
    /* the rating alone: the description stays */
    fp_take_edit e2 = {.set_rating = true, .rating = 0};
    if (fp_take_edit_header(path, &e2, err, sizeof err)) fail_msg("%s", err);
    if (fp_take_reader_open(path, &r, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(fp_take_reader_header(r)->rating, 0);
    assert_string_equal(fp_take_reader_header(r)->description, e.description);
    fp_take_reader_close(&r);
    /* listed with its description; no temporary left beside it */
    fp_take_info *v;
    size_t count;
    if (fp_take_list(dir, &v, &count, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(count, 1);
    assert_string_equal(v[0].description, e.description);
    free(v);
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "test $(ls -A %s | wc -l) -eq 1", dir);
    assert_int_equal(system(cmd), 0);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
    free(b0);
    free(b1);
}

static void test_refusals(void **state)
{
    (void)state;
    char dir[] = "/tmp/fp-take-edit-XXXXXX", path[4096], open_path[4096], err[512];
    assert_non_null(mkdtemp(dir));
    make_take(dir, 10, false, path, sizeof path, NULL);
    size_t n0, n1;
    unsigned char *b0 = slurp(path, &n0);
    fp_take_edit bad_rating = {.set_rating = true, .rating = 6};
    assert_int_equal(fp_take_edit_header(path, &bad_rating, err, sizeof err), -EINVAL);
    assert_non_null(strstr(err, "0..5"));
    fp_take_edit bad_text = {.description = "esc \x1b[31m"};
    assert_int_equal(fp_take_edit_header(path, &bad_text, err, sizeof err), -EINVAL);
    unsigned char *b1 = slurp(path, &n1);
    assert_int_equal(n0, n1);
    assert_memory_equal(b0, b1, n0);
    free(b1);
    /* a take still being written: refused, and allowed with open_ok */
    fp_take_writer *w = NULL;
    make_take(dir, 10, true, open_path, sizeof open_path, &w);
    fp_take_edit e = {.set_rating = true, .rating = 3};
    assert_int_equal(fp_take_edit_header(open_path, &e, err, sizeof err), -EBUSY);
    assert_non_null(strstr(err, "no end chunk"));
    e.open_ok = true;
    if (fp_take_edit_header(open_path, &e, err, sizeof err)) fail_msg("%s", err);
    fp_take_writer_close(&w, 0, 0, err, sizeof err);
    /* cut mid-chunk (no end chunk, its last chunk half there): refused as well, the file as it
     * was (it was rewritten, rc 0, while the docs said a take without an end chunk is refused) */
    {
        size_t nc;
        unsigned char *bc = slurp(path, &nc);
        char cut_path[4200];
        snprintf(cut_path, sizeof cut_path, "%s/cut_T009.fptake", dir);
        FILE *fc = fopen(cut_path, "wb");
        assert_non_null(fc);
        assert_int_equal(fwrite(bc, 1, nc - 40, fc), nc - 40); /* (into the end chunk, past it) */
        fclose(fc);
        fp_take_edit ec = {.set_rating = true, .rating = 2};
        assert_int_equal(fp_take_edit_header(cut_path, &ec, err, sizeof err), -EBUSY);
        assert_non_null(strstr(err, "no end chunk"));
        size_t nc1;
        unsigned char *bc1 = slurp(cut_path, &nc1);
        assert_int_equal(nc1, nc - 40);
        assert_memory_equal(bc, bc1, nc1);
        free(bc1);
        ec.open_ok = true;
        if (fp_take_edit_header(cut_path, &ec, err, sizeof err)) fail_msg("%s", err);
        free(bc);
    }
    /* a damaged header: -EBADMSG, the file as it was */
    b0[40] ^= 0x20;
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(b0, 1, n0, f), n0);
    fclose(f);
    assert_int_equal(fp_take_edit_header(path, &e, err, sizeof err), -EBADMSG);
    b1 = slurp(path, &n1);
    assert_memory_equal(b0, b1, n0);
    /* missing */
    assert_int_equal(fp_take_edit_header("/nonexistent/x.fptake", &e, err, sizeof err), -ENOENT);
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
    free(b0);
    free(b1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_rewrite), cmocka_unit_test(test_refusals)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
