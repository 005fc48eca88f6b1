/* OBJ's line continuation (Wavefront "Object Files (.obj)", appendix B1: a backslash at the
 * end of a line continues it on the next). Before, such a file was refused ("malformed face
 * corner '\'"): now a continued v or f line is read as the one line it stands for, errors
 * still name the file's own line numbers, and a backslash inside a line is still refused.
 * Files go to a mkdtemp() folder. */
#define _DEFAULT_SOURCE
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>

#include "fp_mesh.h"
#include "mesh_tmp.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char err[1024];

static const char *write_tmp(const char *name, const char *text)
{
    const char *p = tmp_write(name, text, strlen(text));
    assert_non_null(p);
    return p;
}

static void test_continued_lines_read(void **state)
{
    (void)state;
    /* a quad's face over two lines (CRLF and a blank after one backslash), a vertex over
     * three, a continued comment */
    const char *text = "# a quad \\\n  continued comment\n"
                       "v 0 0 0\nv 1 \\\n 0 \\\n 0\nv 1 1 0\nv 0 1 0\n"
                       "f 1 2 \\ \r\n 3 4\n";
    fp_mesh *m = NULL;
    if (fp_mesh_load(write_tmp("cont.obj", text), &m, err, sizeof err) != FP_MESH_OK)
        fail_msg("%s", err);
    assert_int_equal(m->vertex_count, 4);
    assert_int_equal(m->triangle_count, 2);
    assert_float_equal(m->positions[3], 1.0f, 0);
    assert_float_equal(m->positions[4], 0.0f, 0);
    assert_float_equal(m->positions[5], 0.0f, 0);
    /* written back as it came in: loads again, the moved vertex where it was put */
    m->positions[3] = 2.0f;
    assert_int_equal(fp_mesh_save(m, tmp_path("cont-out.obj"), err, sizeof err), FP_MESH_OK);
    fp_mesh_free(&m);
    m = NULL;
    if (fp_mesh_load(tmp_path("cont-out.obj"), &m, err, sizeof err) != FP_MESH_OK)
        fail_msg("%s", err);
    assert_int_equal(m->triangle_count, 2);
    assert_float_equal(m->positions[3], 2.0f, 0);
    fp_mesh_free(&m);
}

static void test_errors_keep_line_numbers(void **state)
{
    (void)state;
    fp_mesh *m = NULL;
    /* line 5 is bad; lines 2-3 were joined before it */
    const char *p = write_tmp("bad.obj", "v 0 0 0\nv 1 \\\n0 0\nv 1 1 0\nf 1 2 x\n");
    assert_int_equal(fp_mesh_load(p, &m, err, sizeof err), FP_MESH_ERR_FORMAT);
    assert_non_null(strstr(err, "bad.obj: line 5: malformed face corner 'x'"));
    assert_null(m);
    /* a backslash that does not end its line is no continuation */
    p = write_tmp("mid.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 \\ 2 3\n");
    assert_int_equal(fp_mesh_load(p, &m, err, sizeof err), FP_MESH_ERR_FORMAT);
    assert_non_null(strstr(err, "mid.obj: line 4: malformed face corner '\\'"));
    assert_null(m);
}

/* A Windows file (CR LF line ends) with a continued line: read as one line, and written back
 * with CR LF line ends only (before: the line end moved to the joined line's end was a bare LF,
 * so the file written back mixed the two) */
static void test_crlf_kept(void **state)
{
    (void)state;
    fp_mesh *m = NULL;
    const char *p = write_tmp("crlf.obj", "v 0 0 0\r\nv 1 \\\r\n0 0\r\nv 0 1 0\r\nf 1 2 3\r\n");
    if (fp_mesh_load(p, &m, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(m->vertex_count, 3);
    assert_true(m->positions[3] == 1 && m->positions[4] == 0 && m->positions[5] == 0);
    m->positions[7] = 2;
    const char *out = tmp_path("crlf-out.obj");
    if (fp_mesh_save(m, out, err, sizeof err)) fail_msg("%s", err);
    FILE *f = fopen(out, "rb");
    assert_non_null(f);
    char text[4096];
    const size_t len = fread(text, 1, sizeof text, f);
    fclose(f);
    for (size_t i = 0; i < len; i++)
        if (text[i] == '\n' && (i == 0 || text[i - 1] != '\r'))
            fail_msg("a bare LF at byte %zu of the file written back", i);
    fp_mesh_free(&m);
}

static int setup(void **state)
{
    (void)state;
    return tmp_setup("fp-obj-cont");
}

static int teardown(void **state)
{
    (void)state;
    return tmp_teardown();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_continued_lines_read),
        cmocka_unit_test(test_errors_keep_line_numbers),
        cmocka_unit_test(test_crlf_kept),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
