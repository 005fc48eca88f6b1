/* The contact guard's carried rounds on skin left near a right angle (core/contact,
 * carry_rigid in contact_step.c; issue 51's reach on leapjs-playback's recordings): a flat
 * sheet (the loaded face: every rest normal +z) whose reference shape holds a small mesa, its
 * walls one cell wide and WALL_DEG from the rest normal, as earlier gestures leave a few
 * triangles by a nostril or a lip, just short of turning over. The candidate carries the mesa
 * a long way (MOVE) and turns it a little (TURN degrees about y), one smooth map of space, as a
 * long drag does to the skin a fingertip's width from the grab: one wall then faces more than
 * a right angle from the loaded face, and the guard must hold it back.
 *
 * Carried as one piece (a single translation, the blocking vertices' mean motion) the wall
 * keeps the normal it had, so the held skin goes on with the drag: the mesa's top moves 90% of
 * the candidate's motion or more. A carry that varied over the wall (each held vertex moved by
 * the motion of the blocking vertices nearest it, as before) turned it part of the way, past
 * the right angle: the carried round failed, and the held rounds kept the mesa back (its top
 * moved 39% of the way; with the translation, 93%). Every shape kept passes the guard's full
 * check and CGAL. */
#define _GNU_SOURCE /* M_PI */
#include "fp_contact.h"
#include "fp_test_support.h"
#include "selfx.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#define K 100          /* the grid: K x K cells over [0, 1]^2 */
#define MESA_LO 0.45   /* the mesa's top: [MESA_LO, MESA_HI]^2 ... */
#define MESA_HI 0.55
#define WALL_DEG 88.0  /* ... its walls (one cell wide) this far from +z */
#define MOVE 0.1       /* the candidate's translation of the mesa (x and z) */
#define TURN 5.0       /* ... and its turn about y, degrees */
#define WIDTH 0.5      /* the motion's support about the mesa's middle */
#define RADIUS 0.4     /* fp_contact_set_local's r */

typedef struct mesh {
    float *flat, *ref;
    uint32_t *tris;
    size_t n, t;
} mesh;

/* the flat grid (the loaded face) and the reference with the mesa on it */
static void make(mesh *m)
{
    m->n = (size_t)(K + 1) * (K + 1);
    m->t = 2 * (size_t)K * K;
    m->flat = malloc(m->n * 3 * sizeof(float));
    m->ref = malloc(m->n * 3 * sizeof(float));
    m->tris = malloc(m->t * 3 * sizeof(uint32_t));
    assert_non_null(m->flat);
    assert_non_null(m->ref);
    assert_non_null(m->tris);
    const double h = tan(WALL_DEG * M_PI / 180) / K; /* the wall's height over one cell */
    for (int i = 0; i <= K; i++)
        for (int j = 0; j <= K; j++) {
            size_t v = (size_t)i * (K + 1) + j;
            double x = (double)i / K, y = (double)j / K;
            m->flat[3 * v] = m->ref[3 * v] = (float)x;
            m->flat[3 * v + 1] = m->ref[3 * v + 1] = (float)y;
            m->flat[3 * v + 2] = 0;
            bool top = x >= MESA_LO - 1e-9 && x <= MESA_HI + 1e-9 && y >= MESA_LO - 1e-9 && y <= MESA_HI + 1e-9;
            m->ref[3 * v + 2] = top ? (float)h : 0.f;
        }
    size_t t = 0;
    for (int i = 0; i < K; i++)
        for (int j = 0; j < K; j++) {
            uint32_t a = (uint32_t)(i * (K + 1) + j), b = a + 1, c = a + (uint32_t)(K + 1), d = c + 1;
            uint32_t q[6] = {a, c, b, b, c, d};
            memcpy(m->tris + 3 * t, q, sizeof q);
            t += 2;
        }
}

/* the candidate: each vertex p of the reference moved by w(p) (MOVE (1, 0, 1) + the turn of p
 * about y through the mesa's middle), w = (1 - d^2)^2 within WIDTH of the middle in the plane */
static void candidate(const mesh *m, float *out)
{
    const double cx = 0.5, cz = 0, a = TURN * M_PI / 180;
    for (size_t v = 0; v < m->n; v++) {
        const float *p = m->ref + 3 * v;
        double d = hypot(p[0] - 0.5, p[1] - 0.5) / WIDTH, w = d < 1 ? (1 - d * d) * (1 - d * d) : 0;
        double x = p[0] - cx, z = p[2] - cz;
        double tx = cos(a) * x + sin(a) * z - x, tz = -sin(a) * x + cos(a) * z - z;
        out[3 * v] = (float)(p[0] + w * (MOVE + tx));
        out[3 * v + 1] = p[1];
        out[3 * v + 2] = (float)(p[2] + w * (MOVE + tz));
    }
}

static void test_rigid_carry_keeps_the_wall(void **state)
{
    (void)state;
    mesh m;
    make(&m);
    float *cand = malloc(m.n * 3 * sizeof(float));
    assert_non_null(cand);
    candidate(&m, cand);
    fp_contact *full, *tk;
    assert_int_equal(fp_contact_create(m.tris, m.t, m.n, m.flat, &full), 0);
    fp_contact_count info;
    /* the reference is clean; the candidate turns one wall over and crosses nothing */
    assert_int_equal(fp_contact_count_new(full, m.flat, m.ref, NULL, 0, &info), 0);
    assert_int_equal(info.flipped, 0);
    assert_int_equal(fp_contact_count_new(full, m.ref, cand, NULL, 0, &info), 0);
    assert_true(info.flipped > 0);

    assert_int_equal(fp_contact_create(m.tris, m.t, m.n, m.flat, &tk), 0);
    fp_contact_set_prewarm(tk, 0); /* the hierarchy: carried rounds run there */
    fp_contact_set_local(tk, RADIUS);
    assert_int_equal(fp_contact_reference(tk, m.ref, NULL, SIZE_MAX), 0);
    fp_contact_result r;
    assert_int_equal(fp_contact_step(tk, m.ref, cand, NULL, SIZE_MAX, 6, &r), 0);
    const float *kept = fp_contact_shape(tk);
    /* the mesa's middle (on its top) */
    size_t mid = (size_t)(K / 2) * (K + 1) + K / 2;
    double want = 0, went = 0;
    for (int a = 0; a < 3; a++) {
        want += pow((double)cand[3 * mid + a] - m.ref[3 * mid + a], 2);
        went += pow((double)kept[3 * mid + a] - m.ref[3 * mid + a], 2);
    }
    printf("a mesa's walls %.0f degrees from the loaded face, the mesa carried %.2f and turned %.0f "
           "degrees (%zu triangles turned over): scaled back %s, carried %s, the mesa's top moved "
           "%.1f%% of the way, %.1f%% of the motion kept\n",
           WALL_DEG, MOVE * sqrt(2), TURN, info.flipped, r.t < 1 ? "yes" : "no", r.carried ? "yes" : "no",
           100 * sqrt(went / want), 100 * r.kept);
    assert_true(r.t < 1);       /* the wall must not turn over */
    assert_true(r.carried);     /* ... and the held skin is carried, as one piece */
    assert_true(sqrt(went / want) >= 0.9);
    /* what is kept turns nothing over and crosses nothing (the guard's check and CGAL) */
    assert_int_equal(fp_contact_count_new(full, m.ref, kept, NULL, 0, &info), 0);
    assert_int_equal(info.flipped, 0);
    assert_int_equal(fp_selfx_count_new(m.ref, kept, m.n, m.tris, m.t, NULL, 0, NULL), 0);
    fp_contact_destroy(&tk);
    fp_contact_destroy(&full);
    free(cand);
    free(m.flat);
    free(m.ref);
    free(m.tris);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rigid_carry_keeps_the_wall),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
