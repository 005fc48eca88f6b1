/* The viewer's partial normal update (ui/viewer/vnormals.c, core/mesh's fp_mesh_normals_at):
 * after the engine deforms a few blocks of the face (csrbf_evaluate_touched, its ranges), the
 * normals updated there equal fp_mesh_normals over the whole deformed mesh bit for bit, the
 * ranges to upload cover every position and normal that changed, and they are a small part
 * of the mesh. On the ICT face, on it subdivided once (new vertices far from their
 * neighbours in index order), and on a small mesh with an isolated vertex, a repeated corner
 * and a zero-area triangle. No display needed. */
#define _GNU_SOURCE
#include "csrbf.h"
#include "fp_mesh.h"
#include "vnormals.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

static fp_mesh *load_face(void)
{
    const char *data = getenv("FP_SHARED_DATA");
    char path[4096], err[512];
    snprintf(path, sizeof path, "%s/faces/ict-facekit/generic_neutral_mesh.obj", data ? data : "../shared/data");
    fp_mesh *m = NULL;
    if (fp_mesh_load(path, &m, err, sizeof err)) fail_msg("%s", err);
    return m;
}

/* Frames of three control vectors near three vertices: evaluate the touched blocks, update
 * the mirror by ranges, compare with the whole computation. */
static void run_frames(const fp_mesh *m, int frames)
{
    size_t n = m->vertex_count, bytes = n * 3 * sizeof(float);
    float *def = malloc(bytes), *pos = malloc(bytes), *nrm = malloc(bytes), *ref = malloc(bytes),
          *prev_ref = malloc(bytes);
    unsigned char *cover = malloc(n);
    assert_true(def && pos && nrm && ref && prev_ref && cover);
    memcpy(def, m->positions, bytes);
    memcpy(pos, m->positions, bytes);
    assert_int_equal(fp_mesh_normals(m->triangles, m->triangle_count, pos, n, nrm), 0);
    memcpy(prev_ref, nrm, bytes);

    float lo[3], hi[3];
    fp_mesh_bounds(m, lo, hi);
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    csrbf_options o = {0};
    o.radius = 0.03 * diag;
    csrbf_solver *s = NULL;
    csrbf_points *pts = NULL;
    csrbf_touch *touch = NULL;
    assert_int_equal(csrbf_solver_create(&o, &s), 0);
    assert_int_equal(csrbf_points_create(n, m->positions, &pts), 0);
    assert_int_equal(csrbf_touch_create(pts, &touch), 0);
    fp_vnormals vn;
    assert_int_equal(fp_vnormals_init(&vn, m->triangles, m->triangle_count, n), 0);

    size_t moved_total = 0, uploaded_total = 0;
    for (int f = 0; f < frames; f++) {
        /* the gesture moves to other vertices halfway: blocks are restored to the base too */
        /* on the skin (the ICT face's vertices 0..9408, first also when subdivided) */
        uint32_t at[3] = {1000, 4000, 7000};
        if (f >= frames / 2)
            for (int i = 0; i < 3; i++) at[i] += 500;
        float start[9], end[9];
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++) {
                start[3 * i + k] = m->positions[3 * at[i] + k];
                end[3 * i + k] = start[3 * i + k] + (float)(0.1 * o.radius * sin(0.7 * f + i + 2.0 * k));
            }
        assert_true(csrbf_solver_set_start_points(s, 3, start) >= 0);
        assert_true(csrbf_solver_set_end_points(s, end) >= 0);
        assert_true(csrbf_evaluate_touched(s, pts, touch, def, 0, NULL) >= 0);
        const uint32_t *ranges;
        size_t nr = csrbf_touch_ranges(touch, &ranges);
        /* the viewer's update: positions by ranges, then the normals that depend on them */
        for (size_t r = 0; r < nr; r++)
            memcpy(pos + 3 * (size_t)ranges[2 * r], def + 3 * (size_t)ranges[2 * r], ranges[2 * r + 1] * 3 * sizeof(float));
        const uint32_t *up;
        size_t nu = fp_vnormals_update(&vn, pos, ranges, nr, nrm, &up);
        assert_memory_equal(pos, def, bytes);
        assert_int_equal(fp_mesh_normals(m->triangles, m->triangle_count, def, n, ref), 0);
        if (memcmp(nrm, ref, bytes)) {
            for (size_t v = 0; v < n; v++)
                if (memcmp(nrm + 3 * v, ref + 3 * v, 12))
                    fail_msg("frame %d: vertex %zu: normal %.9g %.9g %.9g, whole %.9g %.9g %.9g", f, v,
                             nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2], ref[3 * v], ref[3 * v + 1], ref[3 * v + 2]);
        }
        /* the upload ranges: increasing, disjoint, within the mesh, covering every change */
        memset(cover, 0, n);
        size_t covered = 0;
        for (size_t k = 0; k < nu; k++) {
            if (k) assert_true(up[2 * k] > up[2 * k - 2] + up[2 * k - 1]);
            assert_true((size_t)up[2 * k] + up[2 * k + 1] <= n);
            memset(cover + up[2 * k], 1, up[2 * k + 1]);
            covered += up[2 * k + 1];
        }
        size_t moved = 0;
        for (size_t r = 0; r < nr; r++)
            for (uint32_t v = ranges[2 * r]; v < ranges[2 * r] + ranges[2 * r + 1]; v++) {
                if (!cover[v]) fail_msg("frame %d: changed vertex %u not uploaded", f, v);
                moved++;
            }
        for (size_t v = 0; v < n; v++)
            if (!cover[v] && memcmp(ref + 3 * v, prev_ref + 3 * v, 12))
                fail_msg("frame %d: vertex %zu's normal changed and is not uploaded", f, v);
        memcpy(prev_ref, ref, bytes);
        if (f == 0) continue; /* the engine's first call writes every block */
        moved_total += moved;
        uploaded_total += covered; /* the engine's first call writes every block */
    }
    print_message("%zu vertices, %d frames: %.1f%% of the vertices in the engine's ranges, %.1f%% uploaded\n",
                  n, frames, 100.0 * (double)moved_total / ((double)n * (frames - 1)),
                  100.0 * (double)uploaded_total / ((double)n * (frames - 1)));
    assert_true(moved_total > 0);
    assert_true(uploaded_total < (size_t)(frames - 1) * n / 2); /* a few blocks, not the mesh */
    fp_vnormals_free(&vn);
    csrbf_touch_destroy(&touch);
    csrbf_points_destroy(&pts);
    csrbf_solver_destroy(&s);
    free(def); free(pos); free(nrm); free(ref); free(prev_ref); free(cover);
}

static void test_ict(void **state)
{
    (void)state;
    fp_mesh *m = load_face();
    run_frames(m, 12);
    fp_mesh_free(&m);
}

static void test_ict_subdivided(void **state)
{
    (void)state;
    fp_mesh *m = load_face();
    fp_mesh *sub = fp_mesh_subdivide(m);
    assert_non_null(sub);
    run_frames(sub, 6);
    fp_mesh_free(&sub);
    fp_mesh_free(&m);
}

/* A strip of 4 triangles, one naming a vertex twice, one of zero area, and a vertex in no
 * triangle: every vertex moved in turn, the normals against the whole computation. */
static void test_odd_mesh(void **state)
{
    (void)state;
    enum { N = 7, T = 5 };
    uint32_t tris[3 * T] = {0, 1, 2, 1, 3, 2, 2, 3, 4, 3, 3, 5, 0, 2, 4}; /* 3 3 5: repeated */
    float pos[3 * N] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0.2f, 0, 2, 0, 2, 2, 0, 9, 9, 9};
    pos[3 * 4] = 0; pos[3 * 4 + 1] = 2; /* 0 2 4: collinear, zero area */
    float nrm[3 * N], ref[3 * N];
    assert_int_equal(fp_mesh_normals(tris, T, pos, N, nrm), 0);
    fp_vnormals vn;
    assert_int_equal(fp_vnormals_init(&vn, tris, T, N), 0);
    for (uint32_t v = 0; v < N; v++) {
        pos[3 * v + 2] += 0.25f * (float)(v + 1);
        uint32_t r[2] = {v, 1};
        const uint32_t *up;
        size_t nu = fp_vnormals_update(&vn, pos, r, 1, nrm, &up);
        assert_true(nu >= 1);
        assert_int_equal(fp_mesh_normals(tris, T, pos, N, ref), 0);
        assert_memory_equal(nrm, ref, sizeof ref);
    }
    assert_int_equal(ref[3 * 6] == 0 && ref[3 * 6 + 1] == 0 && ref[3 * 6 + 2] == 0, 1); /* isolated */
    fp_vnormals_free(&vn);
    uint32_t bad[3] = {0, 1, N};
    assert_int_not_equal(fp_vnormals_init(&vn, bad, 1, N), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ict),
        cmocka_unit_test(test_ict_subdivided),
        cmocka_unit_test(test_odd_mesh),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
