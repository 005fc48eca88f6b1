/* core/session/history: one undo level per gesture, a ring of FP_HISTORY_LEVELS, reset. */
#include "history.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#define N 5

static void fill(float *v, float x)
{
    for (int i = 0; i < 3 * N; i++) v[i] = x + (float)i;
}

static void test_commit_and_undo(void **state)
{
    (void)state;
    float base[3 * N], loaded[3 * N], d[3 * N], want[3 * N];
    fill(loaded, 0);
    memcpy(base, loaded, sizeof base);
    fp_history h;
    fp_history_init(&h, N, base);
    assert_false(fp_history_undo(&h));
    /* one gesture, two commits: one level */
    fill(d, 1);
    fp_history_commit(&h, d);
    fill(d, 2);
    fp_history_commit(&h, d);
    assert_memory_equal(base, d, sizeof d);
    fp_history_end_gesture(&h);
    fill(d, 3);
    fp_history_commit(&h, d); /* a second gesture */
    assert_int_equal(h.count, 2);
    assert_true(fp_history_undo(&h));
    fill(want, 2);
    assert_memory_equal(base, want, sizeof want);
    assert_true(fp_history_undo(&h));
    assert_memory_equal(base, loaded, sizeof loaded);
    assert_false(fp_history_undo(&h));
    /* reset is undoable when the base differed, and not otherwise */
    fill(d, 7);
    fp_history_commit(&h, d);
    fp_history_reset(&h, loaded);
    assert_memory_equal(base, loaded, sizeof loaded);
    assert_int_equal(h.count, 2);
    fp_history_reset(&h, loaded);
    assert_int_equal(h.count, 2);
    assert_true(fp_history_undo(&h));
    assert_memory_equal(base, d, sizeof d);
    fp_history_free(&h);
}

/* More gestures than levels: the newest FP_HISTORY_LEVELS can be undone, in order. */
static void test_ring(void **state)
{
    (void)state;
    float base[3 * N], d[3 * N], want[3 * N];
    fill(base, 0);
    fp_history h;
    fp_history_init(&h, N, base);
    const int gestures = FP_HISTORY_LEVELS + 10;
    for (int g = 1; g <= gestures; g++) {
        fill(d, (float)g * 100);
        fp_history_commit(&h, d);
        fp_history_end_gesture(&h);
    }
    assert_int_equal(h.count, FP_HISTORY_LEVELS);
    for (int k = 1; k <= FP_HISTORY_LEVELS; k++) {
        assert_true(fp_history_undo(&h));
        fill(want, (float)(gestures - k) * 100);
        assert_memory_equal(base, want, sizeof want);
    }
    assert_false(fp_history_undo(&h));
    fp_history_free(&h);
}

/* Ranged commits against a model that snapshots the whole base before every gesture: random
 * gestures of 1-4 commits, each over random ranges (piece-aligned as the engine's, or not),
 * changing the vertices inside them; undo (down to the loaded shape), reset and its undo give
 * the model's base bit for bit, including -0.0 vs 0.0 and NaN payloads; a level holds only
 * the pieces its gesture changed. */
#define NV 1003 /* not a multiple of the piece */
static float model[FP_HISTORY_LEVELS + 1][3 * NV];

static size_t random_ranges(uint32_t *r, bool aligned)
{
    size_t nr = 0, v = (size_t)rand() % 200;
    while (v < NV && nr < 8) {
        size_t c = 1 + (size_t)rand() % 120;
        if (aligned) {
            v -= v % FP_HISTORY_PIECE;
            c = (c + FP_HISTORY_PIECE - 1) / FP_HISTORY_PIECE * FP_HISTORY_PIECE;
        }
        if (c > NV - v) c = NV - v;
        r[2 * nr] = (uint32_t)v;
        r[2 * nr + 1] = (uint32_t)c;
        nr++;
        v += c + (size_t)rand() % 300;
    }
    return nr;
}

static void test_ranged_commits_undo_exact(void **state)
{
    (void)state;
    static float base[3 * NV], loaded[3 * NV], d[3 * NV];
    srand(5);
    for (size_t i = 0; i < 3 * NV; i++) loaded[i] = (float)rand() / (float)RAND_MAX;
    loaded[7] = -0.0f;
    uint32_t nanbits = 0x7fc01234u;
    memcpy(&loaded[11], &nanbits, sizeof nanbits);
    memcpy(base, loaded, sizeof base);
    fp_history h;
    assert_int_equal(fp_history_init(&h, NV, base), 0);
    int levels = 0;
    for (int g = 0; g < 20; g++) {
        memcpy(model[levels], base, sizeof base); /* before the gesture */
        size_t changed_pieces = 0;
        static uint8_t touched[(NV + FP_HISTORY_PIECE - 1) / FP_HISTORY_PIECE];
        memset(touched, 0, sizeof touched);
        int commits = 1 + rand() % 4;
        for (int c = 0; c < commits; c++) {
            uint32_t r[16];
            size_t nr = random_ranges(r, g % 2 == 0);
            memcpy(d, base, sizeof d); /* equal to the base outside the ranges */
            for (size_t k = 0; k < nr; k++)
                for (size_t v = r[2 * k]; v < r[2 * k] + r[2 * k + 1]; v++) {
                    if (rand() % 3 == 0) continue; /* some vertices in a range do not move */
                    for (int a = 0; a < 3; a++) d[3 * v + a] += 0.25f * (float)(1 + c);
                    if (!touched[v / FP_HISTORY_PIECE]) changed_pieces++;
                    touched[v / FP_HISTORY_PIECE] = 1;
                }
            fp_history_commit_ranges(&h, d, r, nr);
            assert_memory_equal(base, d, sizeof d);
        }
        fp_history_end_gesture(&h);
        levels++;
        assert_int_equal(h.level[(h.next + FP_HISTORY_LEVELS - 1) % FP_HISTORY_LEVELS].count, changed_pieces);
    }
    /* reset (its pieces only), then undo it, then every gesture back to the loaded shape */
    memcpy(model[levels], base, sizeof base);
    fp_history_reset(&h, loaded);
    assert_memory_equal(base, loaded, sizeof base);
    assert_true(fp_history_undo(&h));
    assert_memory_equal(base, model[levels], sizeof base);
    for (int l = levels - 1; l >= 0; l--) {
        assert_true(fp_history_undo(&h));
        assert_memory_equal(base, model[l], sizeof base);
    }
    assert_memory_equal(base, loaded, sizeof base);
    assert_false(fp_history_undo(&h));
    /* a whole-mesh commit stores only the changed pieces; undo mid-gesture goes back before it */
    memcpy(d, base, sizeof d);
    d[3 * 500] += 1.0f;
    fp_history_commit(&h, d);
    assert_int_equal(h.level[(h.next + FP_HISTORY_LEVELS - 1) % FP_HISTORY_LEVELS].count, 1);
    uint32_t r[2] = {0, NV};
    d[3 * 20] += 1.0f;
    fp_history_commit_ranges(&h, d, r, 1);
    assert_true(fp_history_undo(&h));
    assert_memory_equal(base, loaded, sizeof base);
    /* after the undo the next commit opens a new level (the marks were cleared) */
    fp_history_commit_ranges(&h, d, r, 1);
    assert_int_equal(h.level[(h.next + FP_HISTORY_LEVELS - 1) % FP_HISTORY_LEVELS].count, 2);
    assert_true(fp_history_undo(&h));
    assert_memory_equal(base, loaded, sizeof base);
    fp_history_free(&h);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_commit_and_undo),
        cmocka_unit_test(test_ring),
        cmocka_unit_test(test_ranged_commits_undo_exact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
