/* A mesh loaded from PLY or STL is saved to PLY or STL in the encoding it was read in: an
 * ASCII PLY comes back ASCII, a big-endian PLY big-endian, an ASCII STL ASCII (before, every
 * PLY and STL save was binary little-endian, so `facepuppet run --out face.ply` of an ASCII
 * face gave the user a binary file). A mesh from another format is still written binary
 * little-endian. Each save is loaded back and its moved vertex checked. Files go to a
 * mkdtemp() folder. */
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

static const char *write_file(const char *name, const void *bytes, size_t n)
{
    const char *p = tmp_write(name, bytes, n);
    assert_non_null(p);
    return p;
}

/* the first n bytes of the file at p into buf (NUL-terminated); its size */
static long read_head(const char *p, char *buf, size_t n)
{
    FILE *f = fopen(p, "rb");
    assert_non_null(f);
    const size_t got = fread(buf, 1, n - 1, f);
    buf[got] = '\0';
    assert_int_equal(fseek(f, 0, SEEK_END), 0);
    const long size = ftell(f);
    fclose(f);
    return size;
}

/* Load in_path, move vertex 0 by +0.25 in x, save as out_name; the saved file's first
 * bytes must start with `head`; loaded back, vertex 0 is where it was moved. The saved size. */
static long move_and_save(const char *in_path, const char *out_name, const char *head)
{
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(in_path, &m, err, sizeof err), FP_MESH_OK);
    const float x = m->positions[0] + 0.25f;
    m->positions[0] = x;
    const char *out = tmp_path(out_name);
    assert_int_equal(fp_mesh_save(m, out, err, sizeof err), FP_MESH_OK);
    fp_mesh_free(&m);
    char got[256];
    const long size = read_head(out, got, sizeof got);
    if (strncmp(got, head, strlen(head)) != 0)
        fail_msg("%s starts with '%.60s', not '%s'", out_name, got, head);
    fp_mesh *back = NULL;
    assert_int_equal(fp_mesh_load(out, &back, err, sizeof err), FP_MESH_OK);
    assert_int_equal(back->vertex_count, 4);
    assert_int_equal(back->triangle_count, 2);
    assert_float_equal(back->positions[0], x, 1e-6);
    fp_mesh_free(&back);
    return size;
}

static const char ascii_ply[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                                "property float y\nproperty float z\nelement face 2\n"
                                "property list uchar int vertex_indices\nend_header\n"
                                "0 0 0\n1 1 0\n0 1 0\n1 0 0\n3 0 3 1\n3 0 1 2\n";

static void test_ascii_ply_stays_ascii(void **state)
{
    (void)state;
    move_and_save(write_file("in.ply", ascii_ply, strlen(ascii_ply)), "out.ply",
                  "ply\nformat ascii 1.0\n");
    /* and to STL, ASCII too */
    move_and_save(tmp_path("in.ply"), "ply-out.stl", "solid");
}

/* x y z as big-endian floats; faces as uchar count, big-endian int indices */
static size_t put_be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24); p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8); p[3] = (unsigned char)v;
    return 4;
}

static const char *binary_ply(const char *name, int big)
{
    static const float pos[12] = {0, 0, 0, 1, 1, 0, 0, 1, 0, 1, 0, 0};
    static const uint32_t tri[6] = {0, 3, 1, 0, 1, 2};
    unsigned char bytes[512];
    size_t n = (size_t)snprintf((char *)bytes, sizeof bytes,
                                "ply\nformat binary_%s_endian 1.0\nelement vertex 4\n"
                                "property float x\nproperty float y\nproperty float z\n"
                                "element face 2\nproperty list uchar int vertex_indices\n"
                                "end_header\n", big ? "big" : "little");
    for (int i = 0; i < 12; i++) {
        uint32_t u;
        memcpy(&u, &pos[i], 4);
        if (big) n += put_be32(bytes + n, u);
        else { memcpy(bytes + n, &u, 4); n += 4; }
    }
    for (int f = 0; f < 2; f++) {
        bytes[n++] = 3;
        for (int k = 0; k < 3; k++) {
            if (big) n += put_be32(bytes + n, tri[3 * f + k]);
            else { memcpy(bytes + n, &tri[3 * f + k], 4); n += 4; }
        }
    }
    return write_file(name, bytes, n);
}

static void test_binary_ply_keeps_byte_order(void **state)
{
    (void)state;
    move_and_save(binary_ply("be.ply", 1), "be-out.ply", "ply\nformat binary_big_endian 1.0\n");
    move_and_save(binary_ply("le.ply", 0), "le-out.ply", "ply\nformat binary_little_endian 1.0\n");
}

static void test_stl_keeps_encoding(void **state)
{
    (void)state;
    static const char stl[] =
        "solid quad\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\n"
        "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\n"
        "vertex 0 1 0\nendloop\nendfacet\nendsolid quad\n";
    move_and_save(write_file("in.stl", stl, strlen(stl)), "out.stl", "solid");
    /* a binary STL stays binary: 80-byte header, count, 50 bytes a triangle */
    const long size = move_and_save(binary_ply("le2.ply", 0), "bin-out.stl", "");
    assert_int_equal(size, 84 + 50 * 2);
    const long size2 = move_and_save(tmp_path("bin-out.stl"), "bin-out2.stl", "");
    assert_int_equal(size2, 84 + 50 * 2);
}

static void test_other_formats_write_binary(void **state)
{
    (void)state;
    static const char obj[] = "v 0 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 0\nf 1 4 2\nf 1 2 3\n";
    move_and_save(write_file("in.obj", obj, strlen(obj)), "obj-out.ply",
                  "ply\nformat binary_little_endian 1.0\n");
}

static int setup(void **state)
{
    (void)state;
    return tmp_setup("fp-ply-enc");
}

static int teardown(void **state)
{
    (void)state;
    return tmp_teardown();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ascii_ply_stays_ascii),
        cmocka_unit_test(test_binary_ply_keeps_byte_order),
        cmocka_unit_test(test_stl_keeps_encoding),
        cmocka_unit_test(test_other_formats_write_binary),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
