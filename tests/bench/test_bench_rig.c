/*
 * test_bench_rig: the frame case's rig carried through a midpoint subdivision
 * (bench/bench_rig.c): the ICT face's rig carried onto ICT subdivided once binds to it (the
 * rig's own checks: sizes, regions, jaw weights on soft vertices only), the input's vertices
 * keep their kind and jaw weight, and each midpoint is of its ends' kind when they share it,
 * soft otherwise, against the subdivision's own edge list (recomputed here from the coarse
 * triangles, not from the fine mesh's layout that bench_rig.c reads).
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "fp_bench.h"
#include "fp_mesh.h"
#include "fp_rig.h"
#include "fp_test_support.h"

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static void carried_rig_binds_and_follows_the_rule(void **state)
{
    (void)state;
    char path[4300], err[512], rig_path[4300], tmp[4300];
    snprintf(path, sizeof path, "%s/faces/ict-facekit/generic_neutral_mesh.obj", fp_test_data_dir());
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(path, &m, err, sizeof err), 0);
    snprintf(rig_path, sizeof rig_path, "%s/rigs/ict-facekit.json", FP_TEST_SOURCE_DIR);
    fp_rig *coarse_rig = NULL;
    assert_int_equal(fp_rig_load_for_mesh(rig_path, m->vertex_count, m->positions, &coarse_rig, err, sizeof err), 0);
    fp_mesh *f = fp_mesh_subdivide(m);
    assert_non_null(f);
    fp_bench_rig *br = NULL;
    assert_int_equal(fp_bench_rig_open(rig_path, &br, err, sizeof err), 0);
    assert_int_equal(fp_bench_rig_subdivide(br, f, f, err, sizeof err), -EINVAL); /* not the coarse mesh */
    assert_int_equal(fp_bench_rig_subdivide(br, m, f, err, sizeof err), 0);
    assert_int_equal(fp_bench_rig_write(br, tmp, sizeof tmp, err, sizeof err), 0);
    fp_bench_rig_free(&br);
    fp_rig *fine_rig = NULL;
    int rc = fp_rig_load_for_mesh(tmp, f->vertex_count, f->positions, &fine_rig, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    unlink(tmp);
    assert_true(fp_rig_checksum_matches(fine_rig, f->vertex_count, f->positions));
    const uint8_t *kc = fp_rig_vertex_kinds(coarse_rig), *kf = fp_rig_vertex_kinds(fine_rig);
    const float *wc = fp_rig_jaw_weights(coarse_rig), *wf = fp_rig_jaw_weights(fine_rig);
    size_t n = m->vertex_count;
    for (size_t v = 0; v < n; v++) {
        assert_int_equal(kf[v], kc[v]);
        if (kc[v] != FP_RIG_SOFT) assert_true(wf[v] == wc[v]); /* 0 skull, 1 jaw */
    }
    /* the edges, sorted: midpoint n + i is edge i (fp_mesh.h) */
    size_t t = m->triangle_count, ne = 0;
    uint64_t *e = malloc(3 * t * sizeof *e);
    assert_non_null(e);
    for (size_t k = 0; k < t; k++)
        for (int j = 0; j < 3; j++) {
            uint64_t a = m->triangles[3 * k + j], b = m->triangles[3 * k + (j + 1) % 3];
            e[3 * k + j] = a < b ? a << 32 | b : b << 32 | a;
        }
    qsort(e, 3 * t, sizeof *e, cmp_u64);
    for (size_t i = 0; i < 3 * t; i++)
        if (!ne || e[ne - 1] != e[i]) e[ne++] = e[i];
    assert_int_equal(n + ne, f->vertex_count);
    size_t shared = 0;
    for (size_t i = 0; i < ne; i++) {
        uint32_t a = (uint32_t)(e[i] >> 32), b = (uint32_t)e[i];
        uint8_t want = kc[a] == kc[b] ? kc[a] : FP_RIG_SOFT;
        if (kf[n + i] != want && !(want == FP_RIG_SOFT || kf[n + i] == FP_RIG_SOFT))
            fail_msg("midpoint %zu of (%u, %u): kind %d, ends %d and %d", n + i, a, b, kf[n + i], kc[a], kc[b]);
        /* a rigid midpoint only between two ends of that kind (same region: a subset of it) */
        if (kf[n + i] != FP_RIG_SOFT) assert_true(kc[a] == kf[n + i] && kc[b] == kf[n + i]);
        shared += kf[n + i] != FP_RIG_SOFT;
    }
    printf("carried rig: %zu vertices, %zu rigid midpoints of %zu\n", f->vertex_count, shared, ne);
    assert_true(shared > 1000);
    free(e);
    fp_rig_free(&fine_rig);
    fp_rig_free(&coarse_rig);
    fp_mesh_free(&f);
    fp_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(carried_rig_binds_and_follows_the_rule)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
