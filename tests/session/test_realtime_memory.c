/* fp_session_realtime_memory: no page fault in a session's frames. The ICT face with its
 * rig and the contact guard, gestures driven by control sets (fp_session_apply_controls) at
 * several places, growing until the guard renews envelopes, each ended by a commit (a new
 * undo level each); the session thread's minor page faults (getrusage RUSAGE_THREAD) counted
 * around every frame. Each run is a child process, as the call's malloc settings are
 * process-wide and for good: with the call no frame faults; without it (the control, what
 * the test would see if the call did nothing) the same frames do. Skipped where the malloc is
 * not glibc's (under a sanitizer's allocator the call returns -ENOTSUP). */
#define _GNU_SOURCE
#include "fp_mesh.h"
#include "fp_session.h"
#include "fp_test_support.h"

#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

typedef struct outcome {
    long faults;        /* minor faults of the session thread inside the frames, all told */
    long faulting;      /* frames with one or more */
    long frames, commits, limited;
    double ms, ms_max;  /* the frames' wall time, all told and the longest (shown, not tested:
                           speed is the bench's) */
    int rc;             /* fp_session_realtime_memory's, or 0 when not called */
} outcome;

static long thread_faults(void)
{
    struct rusage ru;
    return getrusage(RUSAGE_THREAD, &ru) ? -1 : ru.ru_minflt;
}

/* The gestures on one session: returns what the frames did */
static outcome run(bool realtime)
{
    outcome o = {0};
    char err[2048];
    fp_session_options so;
    fp_test_face_options(&so, "anchored", FP_TEST_RIGS_DIR);
    fp_session *s = NULL;
    o.rc = fp_session_create(&so, &s, err, sizeof err);
    if (o.rc) {
        fprintf(stderr, "%s\n", err);
        return o;
    }
    if (realtime && (o.rc = fp_session_realtime_memory(s, 0, err, sizeof err))) {
        fprintf(stderr, "%s\n", err);
        fp_session_destroy(&s);
        return o;
    }
    size_t n = fp_session_vertex_count(s);
    float lo[3], hi[3], start[3][3], end[3][3];
    fp_mesh_bounds(fp_session_mesh(s), lo, hi);
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    fp_control_set cs = {.size = sizeof cs, .radius = 0.06 * diag, .capacity = 3, .start = start, .end = end};
    int64_t t = 0;
    for (int g = 0; g < 6; g++) {
        const float *base = fp_session_base(s);
        for (int i = 0; i < 3; i++) { /* three vertices spread over the face */
            size_t v = ((size_t)g * 7919 + (size_t)i * 104729) % n;
            memcpy(start[i], &base[3 * v], sizeof start[i]);
        }
        for (int f = 0; f <= 40; f++) {
            uint32_t intents = f == 0 ? FP_INTENT_ENGAGE : f == 40 ? FP_INTENT_COMMIT : 0;
            double amp = 0.01 * f; /* up to 0.4 R: fast enough to renew envelopes */
            for (int i = 0; i < 3; i++)
                for (int k = 0; k < 3; k++)
                    end[i][k] = start[i][k] + (float)(amp * cs.radius * sin(0.3 * f + i + 2.1 * k));
            cs.active = true;
            cs.count = 3;
            cs.intents = intents;
            fp_frame_stats st;
            long before = thread_faults();
            int64_t a = fp_test_mono_ns();
            fp_session_apply_controls(s, t += 16666667, &cs, intents, &st);
            double ms = (double)(fp_test_mono_ns() - a) / 1e6;
            long got = thread_faults() - before;
            o.ms += ms;
            o.ms_max = ms > o.ms_max ? ms : o.ms_max;
            o.faults += got;
            o.faulting += got > 0;
            o.frames++;
            o.commits += st.committed;
            o.limited += st.collide_t < 1.0;
        }
        cs.active = false;
        cs.count = 0;
        cs.intents = 0;
        long before = thread_faults();
        fp_session_apply_controls(s, t += 16666667, &cs, 0, NULL);
        long got = thread_faults() - before;
        o.faults += got;
        o.faulting += got > 0;
        o.frames++;
    }
    fp_session_destroy(&s);
    return o;
}

/* run(realtime) in a child process; its outcome through a pipe */
static outcome run_apart(bool realtime)
{
    int fd[2];
    assert_int_equal(pipe(fd), 0);
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        close(fd[0]);
        outcome o = run(realtime);
        ssize_t w = write(fd[1], &o, sizeof o);
        _exit(w == (ssize_t)sizeof o ? 0 : 1);
    }
    close(fd[1]);
    outcome o;
    ssize_t r = read(fd[0], &o, sizeof o);
    close(fd[0]);
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    assert_int_equal(r, (ssize_t)sizeof o);
    return o;
}

static void test_no_fault_in_frames(void **state)
{
    (void)state;
    outcome with = run_apart(true), without = run_apart(false);
    fprintf(stderr, "real-time memory: %ld frames, %ld commits, %ld scaled back by the contact guard; "
            "page faults in frames: %ld (in %ld frames) with it, %ld (in %ld frames) without; "
            "deforming frames %.1f ms all told (longest %.2f) with it, %.1f (%.2f) without\n",
            with.frames, with.commits, with.limited, with.faults, with.faulting, without.faults, without.faulting,
            with.ms, with.ms_max, without.ms, without.ms_max);
    assert_int_equal(without.rc, 0);
    if (with.rc == -ENOTSUP) { /* not glibc's malloc (a sanitizer's allocator refuses mallopt) */
        fprintf(stderr, "real-time memory: not supported here; skipped\n");
        skip();
    }
    assert_int_equal(with.rc, 0);
    assert_int_equal(with.commits, 6);
    assert_int_equal(without.commits, 6);
    assert_int_equal(with.faults, 0);
    /* the control: these frames do fault where nothing was prepared */
    assert_true(without.faults > 0);
}

static void test_errors(void **state)
{
    (void)state;
    char err[256] = "";
    assert_int_equal(fp_session_realtime_memory(NULL, 0, err, sizeof err), -EINVAL);
    assert_non_null(strstr(err, "no session"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_no_fault_in_frames),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
