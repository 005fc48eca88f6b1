/* The session's frame thread (frame_thread.h, fp_session_options.frame_thread).
 *  - fp_frame_thread_run: every call runs exactly once, on the thread its return value
 *    names, its effects seen by the caller when it returns; through graces of 0 (the caller
 *    takes what is not claimed at once), 2 us and 1 s, and across the thread's sleep;
 *  - a polling thread takes the calls (with a 1 s grace, most of 50 back-to-back calls);
 *  - a session stepping its frames there shows what one without a frame thread shows, bit
 *    for bit, frame by frame: the ICT face, the three-claps recording on its own clock, the
 *    anchored mapping, rig and contact guard on. */
#define _GNU_SOURCE
#include "frame_thread.h"
#include "fp_session.h"
#include "fp_test_support.h"

#include <math.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

typedef struct probe {
    pthread_t caller;
    unsigned long runs;     /* calls run, all told */
    bool elsewhere;         /* the last one ran on a thread other than the caller's */
    uint64_t payload[8];    /* written by the call, read by the caller after it */
} probe;

static void probe_fn(void *u)
{
    probe *p = u;
    p->runs++;
    p->elsewhere = !pthread_equal(pthread_self(), p->caller);
    for (int i = 0; i < 8; i++) p->payload[i] = p->runs * 8 + (uint64_t)i;
}

static void test_each_call_once(void **state)
{
    (void)state;
    fp_frame_thread *ft = NULL;
    assert_int_equal(fp_frame_thread_create(&ft), 0);
    probe p = {.caller = pthread_self()};
    static const int64_t graces[] = {0, 2000, 1000000000};
    unsigned long there = 0, calls = 0;
    for (int round = 0; round < 2; round++) {
        if (round) fp_test_nap_ms(60); /* past FP_FRAME_THREAD_IDLE_NS: it sleeps again */
        /* a sleeping thread's calls run here and wake it: a 1 s grace until it takes one,
         * then the three graces in turn */
        unsigned long there0 = there;
        int64_t t0 = fp_test_mono_ns();
        for (int i = 0; i < 10000; i++) {
            bool waking = there == there0;
            if (waking && i) { /* (its wake-up may take a millisecond or more) */
                assert_true(fp_test_mono_ns() - t0 < 10000000000LL);
                fp_test_nap_ms(1);
                i = 0;
            }
            int r = fp_frame_thread_run(ft, probe_fn, &p, waking ? 1000000000 : graces[i % 3]);
            calls++;
            assert_true(r == 0 || r == 1);
            assert_int_equal(p.runs, calls);       /* once, and done when it returns */
            assert_int_equal(p.elsewhere, r == 1); /* where it says */
            for (int k = 0; k < 8; k++) assert_int_equal(p.payload[k], calls * 8 + (uint64_t)k);
            there += (unsigned long)r;
        }
        assert_true(there > there0);
    }
    unsigned long t, h;
    fp_frame_thread_counts(ft, &t, &h);
    assert_int_equal(t, there);
    assert_int_equal(t + h, calls);
    assert_true(h > 0); /* (a grace of 0: the caller takes what is not claimed at once) */
    printf("# %lu of %lu calls ran on the frame thread\n", there, calls);
    fp_frame_thread_destroy(&ft);
    assert_null(ft);
    fp_frame_thread_destroy(&ft); /* NULL: nothing */
    /* no thread: the caller's */
    p.runs = 0;
    assert_int_equal(fp_frame_thread_run(NULL, probe_fn, &p, 0), 0);
    assert_int_equal(p.runs, 1);
    assert_false(p.elsewhere);
}

static void test_polling_thread_takes_calls(void **state)
{
    (void)state;
    fp_frame_thread *ft = NULL;
    assert_int_equal(fp_frame_thread_create(&ft), 0);
    probe p = {.caller = pthread_self()};
    /* asleep at first: the first calls run here and wake it; then it polls */
    int64_t t0 = fp_test_mono_ns();
    while (fp_frame_thread_run(ft, probe_fn, &p, 1000000000) != 1)
        assert_true(fp_test_mono_ns() - t0 < 5000000000LL);
    int there = 0;
    for (int i = 0; i < 50; i++) there += fp_frame_thread_run(ft, probe_fn, &p, 1000000000);
    printf("# a polling frame thread took %d of 50 calls\n", there);
    assert_true(there >= 25);
    fp_frame_thread_destroy(&ft);
}

/* one session on the ICT face, three-claps on its own clock; frame_thread as given */
static fp_session *open_session(int frame_thread, const fp_plugin_path *path)
{
    char mesh[4300], input[4400], err[2048];
    snprintf(mesh, sizeof mesh, "%s/faces/ict-facekit/generic_neutral_mesh.obj", fp_test_data_dir());
    snprintf(input, sizeof input, "replay:%s/hands/leap-motion/three-claps_joints_mm.csv,fast=1",
             fp_test_data_dir());
    fp_session_options so = {0};
    so.mesh_path = mesh;
    so.inputs[0] = input;
    so.input_count = 1;
    so.mapping = "anchored";
    so.plugin_path = path;
    so.input_clock = true;
    so.rig_dir = FP_TEST_RIGS_DIR;
    so.frame_thread = frame_thread;
    fp_session *s = NULL;
    int rc = fp_session_create(&so, &s, err, sizeof err);
    if (!rc) rc = fp_session_start(s, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    return s;
}

static void test_session_same_frames(void **state)
{
    (void)state;
    const char *dirs[] = {fp_test_plugin_dir()};
    fp_plugin_path path;
    fp_plugin_path_init(&path, dirs, 1, NULL);
    /* b: its frames wait for the frame thread (a 1 s grace), so that they run there even on a
     * busy machine (CI's, its 2 cores shared with other tests: with the 20 us grace, none of
     * 225 did); only a frame after the thread fell asleep (20 ms without one) runs here */
    fp_session *a = open_session(-1, &path), *b = open_session(2, &path);
    size_t n = fp_session_vertex_count(a);
    assert_int_equal(fp_session_vertex_count(b), n);
    int64_t t0a = fp_test_session_t0(a), t0b = fp_test_session_t0(b);
    unsigned long frames = 0, active = 0, committed = 0, scaled = 0, there = 0;
    for (uint64_t k = 0; !fp_session_finished(a) || !fp_session_finished(b); k++) {
        assert_true(k < 100000);
        /* each on its recording's clock */
        int64_t ta = fp_test_frame_time(a, t0a, k, 60), tb = fp_test_frame_time(b, t0b, k, 60);
        fp_frame_stats sa, sb;
        fp_session_step(a, ta, &sa);
        fp_session_step(b, tb, &sb);
        assert_false(sa.frame_thread);
        there += sb.frame_thread;
        assert_int_equal(sa.active, sb.active);
        assert_int_equal(sa.committed, sb.committed);
        assert_int_equal(sa.events, sb.events);
        assert_true(sa.collide_t == sb.collide_t);
        if (memcmp(fp_session_positions(a), fp_session_positions(b), n * 3 * sizeof(float)) ||
            memcmp(fp_session_base(a), fp_session_base(b), n * 3 * sizeof(float)))
            fail_msg("frame %llu: the shapes differ", (unsigned long long)k);
        frames++;
        active += sa.active;
        committed += sa.committed;
        scaled += sa.collide_t < 1;
    }
    printf("# %lu frames (%lu deforming, %lu committing, %lu scaled back by the contact guard) "
           "equal bit for bit; %lu ran on the frame thread\n",
           frames, active, committed, scaled, there);
    assert_true(active > 50 && committed > 0);
    assert_true(there >= frames / 4);
    fp_session_destroy(&a);
    fp_session_destroy(&b);
    fp_plugin_path_clear(&path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_each_call_once),
        cmocka_unit_test(test_polling_thread_takes_calls),
        cmocka_unit_test(test_session_same_frames),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
