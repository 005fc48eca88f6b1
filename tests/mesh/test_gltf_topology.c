/* glTF triangle strips and fans (glTF 2.0, 3.7.2.1 "Topology types"): loaded as the
 * triangles they stand for, wound as the specification says, a strip's degenerate restart
 * triangles left out; a deformed strip saved back keeps its mode and indices, its positions
 * moved. Before, a file of strips or fans was refused ("only points, lines, strips or fans").
 * Points and lines still are. Files go to a mkdtemp() folder. */
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

/* A glTF of one primitive of the given mode over the six vertices of a 3 x 2 grid in z = 0,
 * its indices those given (unsigned short); written as NAME.gltf and NAME.bin */
static const char *grid_gltf(const char *name, int mode, const uint16_t *idx, size_t n)
{
    const float pos[18] = {0, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 2, 0, 0, 2, 1, 0};
    unsigned char bin[128] = {0};
    memcpy(bin, pos, sizeof pos);
    memcpy(bin + 72, idx, n * sizeof *idx);
    char bin_name[64], json[2048];
    snprintf(bin_name, sizeof bin_name, "%s.bin", name);
    FILE *f = fopen(tmp_path(bin_name), "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bin, 1, 72 + 2 * n, f), 72 + 2 * n);
    fclose(f);
    const int len = snprintf(json, sizeof json,
        "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"mode\":%d}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":6,\"type\":\"VEC3\","
        "\"min\":[0,0,0],\"max\":[2,1,0]},{\"bufferView\":1,\"componentType\":5123,\"count\":%zu,\"type\":\"SCALAR\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":72},{\"buffer\":0,\"byteOffset\":72,\"byteLength\":%zu}],"
        "\"buffers\":[{\"byteLength\":%zu,\"uri\":\"%s\"}]}",
        mode, n, 2 * n, 72 + 2 * n, bin_name);
    assert_true(len > 0 && (size_t)len < sizeof json);
    char gltf_name[64];
    snprintf(gltf_name, sizeof gltf_name, "%s.gltf", name);
    const char *p = tmp_path(gltf_name);
    f = fopen(p, "wb");
    assert_non_null(f);
    fputs(json, f);
    fclose(f);
    return p;
}

/* z of triangle i's normal (e1 x e2) */
static float normal_z(const fp_mesh *m, size_t i)
{
    const uint32_t *t = m->triangles + 3 * i;
    const float *a = m->positions + 3 * t[0], *b = m->positions + 3 * t[1], *c = m->positions + 3 * t[2];
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* the triangles of m as index triples, each checked against want (n triples) in order */
static void expect_triangles(const fp_mesh *m, const uint32_t (*want)[3], size_t n)
{
    assert_int_equal(m->triangle_count, n);
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            if (m->triangles[3 * i + k] != want[i][k])
                fail_msg("triangle %zu: %u %u %u, want %u %u %u", i, m->triangles[3 * i],
                         m->triangles[3 * i + 1], m->triangles[3 * i + 2], want[i][0], want[i][1], want[i][2]);
}

/* A strip over the grid, ending in a repeated index (a restart's degenerate triangle):
 * four triangles, each wound as the first (all facing -z) */
static void test_strip(void **state)
{
    (void)state;
    const uint16_t idx[7] = {0, 1, 2, 3, 4, 5, 5};
    fp_mesh *m = NULL;
    if (fp_mesh_load(grid_gltf("strip", 5, idx, 7), &m, err, sizeof err)) fail_msg("%s", err);
    const uint32_t want[4][3] = {{0, 1, 2}, {1, 3, 2}, {2, 3, 4}, {3, 5, 4}};
    expect_triangles(m, want, 4);
    for (size_t i = 0; i < 4; i++)
        if (!(normal_z(m, i) < 0)) fail_msg("strip triangle %zu wound against the first", i);
    /* deformed and saved back: the same strip (mode and indices kept), the positions moved */
    m->positions[3 * 5 + 2] = 0.5f;
    const char *out = tmp_path("strip-out.gltf");
    if (fp_mesh_save(m, out, err, sizeof err)) fail_msg("%s", err);
    fp_mesh *back = NULL;
    if (fp_mesh_load(out, &back, err, sizeof err)) fail_msg("%s", err);
    expect_triangles(back, want, 4);
    assert_memory_equal(back->positions, m->positions, 18 * sizeof(float));
    FILE *f = fopen(out, "rb");
    assert_non_null(f);
    char text[8192];
    const size_t len = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[len] = 0;
    if (!strstr(text, "\"mode\": 5") && !strstr(text, "\"mode\":5")) fail_msg("the strip saved without its mode: %s", text);
    fp_mesh_free(&back);
    fp_mesh_free(&m);
}

/* A fan around vertex 0: triangle i is (v[i+1], v[i+2], v[0]), both facing +z */
static void test_fan(void **state)
{
    (void)state;
    const uint16_t idx[4] = {0, 2, 3, 1};
    fp_mesh *m = NULL;
    if (fp_mesh_load(grid_gltf("fan", 6, idx, 4), &m, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(m->vertex_count, 6);
    const uint32_t want[2][3] = {{2, 3, 0}, {3, 1, 0}};
    expect_triangles(m, want, 2);
    for (size_t i = 0; i < 2; i++)
        if (!(normal_z(m, i) > 0)) fail_msg("fan triangle %zu faces -z", i);
    fp_mesh_free(&m);
}

/* An index out of range in a strip is named by its place in the file's indices, even where
 * it lies only in a degenerate triangle (before: checked after the expansion, so [0, 1, 1, 9]
 * loaded, its 9 in no triangle kept, and another's place was a triangle list's) */
static void test_strip_index_out_of_range(void **state)
{
    (void)state;
    const uint16_t idx[4] = {0, 1, 1, 9};
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(grid_gltf("strip-bad", 5, idx, 4), &m, err, sizeof err), FP_MESH_ERR_FORMAT);
    if (!strstr(err, "index 3 = 9 is out of range (6 vertices)")) fail_msg("%s", err);
    assert_null(m);
}

/* Points and lines are still no surface: refused, saying so */
static void test_lines_refused(void **state)
{
    (void)state;
    const uint16_t idx[4] = {0, 1, 2, 3};
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(grid_gltf("lines", 1, idx, 4), &m, err, sizeof err), FP_MESH_ERR_UNSUPPORTED);
    assert_non_null(strstr(err, "no triangle primitives (only points or lines)"));
    assert_null(m);
}

static int setup(void **state)
{
    (void)state;
    return tmp_setup("fp-gltf-topo");
}

static int teardown(void **state)
{
    (void)state;
    return tmp_teardown();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_strip),
        cmocka_unit_test(test_fan),
        cmocka_unit_test(test_strip_index_out_of_range),
        cmocka_unit_test(test_lines_refused),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
