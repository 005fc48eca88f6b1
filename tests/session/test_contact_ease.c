/* The contact guard's ease (core/contact/fp_contact.h, fp_contact_ease): skin a scale-back
 * held back returns to the map at a bounded speed, not in one frame. On test_contact_carry's
 * sheets (a coarse sheet 0.05 over a fine one with a mound 0.003 under it, both lifted by one
 * smooth bump of 0.3), the lift is held back (carried rounds off: the skin about the blocked
 * pairs stays behind, about 0.26 under the map); the next frames the map moves the coarse
 * sheet up by up to NUDGE (0.04, a smooth bump) where it cut into the mound, so its candidate passes whole.
 *
 *  - without the ease the guard shows that candidate at once: held skin jumps about 0.26 in
 *    one frame while the map moved 0.04 at most (the pop issue 51's audit saw on the MediaPipe face:
 *    9.65 mm while the hand moved 0.4 mm);
 *  - with it (step STEP), no vertex moves further in a frame than STEP plus twice the map's
 *    own motion there (the lag shrinks by at most STEP plus that motion), every shape shown passes the guard's full check and CGAL's, and after
 *    enough still frames the shape is the candidate, bit for bit. */
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

#define GAP 0.05f
#define MOUND 0.047 /* the lower sheet's mound under the middle: 0.003 from the upper one */
#define MOUND_R 0.06
#define MID 0.54 /* the mound's and the lift's middle: inside a coarse triangle, where its
                    interpolation is farthest from its corners */
#define LIFT 0.3
#define WIDTH 0.35
#define RADIUS 0.4 /* fp_contact_set_local's r (the session gives its support radius) */

typedef struct mesh {
    float *pos;
    uint32_t *tris;
    size_t n, t, upper; /* upper: the first vertex of the coarse upper sheet */
} mesh;

/* a k x k grid of [0, 1]^2 at height z, into m (its vertices and triangles appended) */
static void grid(mesh *m, int k, float z)
{
    size_t o = m->n;
    m->pos = realloc(m->pos, (m->n + (size_t)(k + 1) * (k + 1)) * 3 * sizeof(float));
    m->tris = realloc(m->tris, (m->t + 2 * (size_t)k * k) * 3 * sizeof(uint32_t));
    assert_non_null(m->pos);
    assert_non_null(m->tris);
    for (int i = 0; i <= k; i++)
        for (int j = 0; j <= k; j++, m->n++) {
            m->pos[3 * m->n] = (float)i / k;
            m->pos[3 * m->n + 1] = (float)j / k;
            m->pos[3 * m->n + 2] = z;
        }
    for (int i = 0; i < k; i++)
        for (int j = 0; j < k; j++) {
            uint32_t a = (uint32_t)(o + (size_t)i * (k + 1) + j), b = a + 1, c = a + (uint32_t)(k + 1), d = c + 1;
            uint32_t q[6] = {a, c, b, b, c, d};
            memcpy(m->tris + 3 * m->t, q, sizeof q);
            m->t += 2;
        }
}

static void sheets(mesh *m)
{
    memset(m, 0, sizeof *m);
    grid(m, 50, 0.0f);
    for (size_t v = 0; v < m->n; v++) { /* the mound */
        double d = hypot(m->pos[3 * v] - MID, m->pos[3 * v + 1] - MID) / MOUND_R;
        if (d < 1) m->pos[3 * v + 2] = (float)(MOUND * (1 - d * d) * (1 - d * d));
    }
    m->upper = m->n;
    grid(m, 10, GAP);
}

/* the lift at share s of LIFT: every vertex up by s LIFT (1 - d^2)^2 within WIDTH of the
 * middle (one smooth map of space: z += its bump at (x, y)) */
static void lift(const mesh *m, double s, float *out)
{
    memcpy(out, m->pos, m->n * 3 * sizeof(float));
    for (size_t v = 0; v < m->n; v++) {
        double d = hypot(m->pos[3 * v] - MID, m->pos[3 * v + 1] - MID) / WIDTH;
        if (d < 1) out[3 * v + 2] += (float)(s * LIFT * (1 - d * d) * (1 - d * d));
    }
}

#define NUDGE 0.04f
#define STEP 0.02f
#define FRAMES 40

/* the lift, the coarse sheet nudged up by NUDGE (1 - d^2)^2 within WIDTH of the middle */
static void nudged(const mesh *m, float *out)
{
    lift(m, 1.0, out);
    for (size_t v = m->upper; v < m->n; v++) {
        double d = hypot(m->pos[3 * v] - MID, m->pos[3 * v + 1] - MID) / WIDTH;
        if (d < 1) out[3 * v + 2] += (float)(NUDGE * (1 - d * d) * (1 - d * d));
    }
}

static double dist3(const float *a, const float *b)
{
    return sqrt(((double)a[0] - b[0]) * ((double)a[0] - b[0]) + ((double)a[1] - b[1]) * ((double)a[1] - b[1]) +
                ((double)a[2] - b[2]) * ((double)a[2] - b[2]));
}

/* frame 1 the lift (held back), then FRAMES frames of the nudged lift; ease or not. Returns
 * the largest motion of a vertex in a frame beyond twice the map's own there (frames 2..), every
 * shape kept checked; *converged: the last shape is the candidate, bit for bit */
static double run(const mesh *m, bool ease, bool *converged)
{
    fp_contact *tk, *full;
    assert_int_equal(fp_contact_create(m->tris, m->t, m->n, m->pos, &tk), 0);
    assert_int_equal(fp_contact_create(m->tris, m->t, m->n, m->pos, &full), 0);
    fp_contact_set_prewarm(tk, 0);
    fp_contact_set_local(tk, RADIUS);
    fp_contact_set_carry(tk, false);
    assert_int_equal(fp_contact_reference(tk, m->pos, NULL, SIZE_MAX), 0);
    const size_t sz = m->n * 3 * sizeof(float);
    float *cand = malloc(sz), *raw = malloc(sz), *last = malloc(sz), *prev = malloc(sz);
    assert_non_null(cand);
    assert_non_null(raw);
    assert_non_null(last);
    assert_non_null(prev);
    double worst = 0;
    for (int f = 1; f <= 1 + FRAMES; f++) {
        memcpy(prev, raw, sz);
        if (f == 1) lift(m, 1.0, raw);
        else nudged(m, raw);
        memcpy(cand, raw, sz);
        memcpy(last, fp_contact_shape(tk), sz);
        if (ease) fp_contact_ease(tk, cand, NULL, SIZE_MAX, STEP);
        fp_contact_result r;
        assert_int_equal(fp_contact_step(tk, m->pos, cand, NULL, SIZE_MAX, 6, &r), 0);
        if (f == 1) assert_true(r.t < 1); /* the lift is held back */
        const float *kept = fp_contact_shape(tk);
        fp_contact_count info;
        assert_int_equal(fp_contact_count_new(full, m->pos, kept, NULL, 0, &info), 0);
        assert_int_equal(info.flipped, 0);
        assert_int_equal(fp_selfx_count_new(m->pos, kept, m->n, m->tris, m->t, NULL, 0, NULL), 0);
        for (size_t v = 0; f > 1 && v < m->n; v++) {
            double extra = dist3(kept + 3 * v, last + 3 * v) - 2 * dist3(raw + 3 * v, prev + 3 * v);
            if (extra > worst) worst = extra;
        }
    }
    *converged = !memcmp(fp_contact_shape(tk), raw, sz);
    free(cand), free(raw), free(last), free(prev);
    fp_contact_destroy(&tk);
    fp_contact_destroy(&full);
    return worst;
}

static void test_ease(void **state)
{
    (void)state;
    mesh m;
    sheets(&m);
    float *c = malloc(m.n * 3 * sizeof(float));
    assert_non_null(c);
    fp_contact *full;
    assert_int_equal(fp_contact_create(m.tris, m.t, m.n, m.pos, &full), 0);
    lift(&m, 1.0, c);
    assert_true(fp_contact_count_new(full, m.pos, c, NULL, 0, NULL) > 0); /* the lift crosses */
    nudged(&m, c);
    fp_contact_count info;
    assert_int_equal(fp_contact_count_new(full, m.pos, c, NULL, 0, &info), 0); /* the nudged one not */
    assert_int_equal(info.flipped, 0);
    fp_contact_destroy(&full);
    bool conv_pop, conv_ease;
    double pop = run(&m, false, &conv_pop), eased = run(&m, true, &conv_ease);
    printf("held skin returning to the map: without the ease a vertex moved %.4f beyond twice the "
           "map's own motion in one frame; with it (step %.3f) %.4f\n", pop, (double)STEP, eased);
    assert_true(pop > 5 * STEP); /* the pop the ease removes */
    assert_true(eased <= STEP + 1e-5);
    assert_true(conv_pop && conv_ease); /* both end on the map, bit for bit */
    free(c);
    free(m.pos);
    free(m.tris);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ease),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
