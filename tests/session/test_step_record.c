/* core/session/step_record: the frame's record reaches the sink; a record=FILE recording
 * (core/plugin fp_record.h, written on its own thread) that fails to write reports it. */
#define _GNU_SOURCE
#include "fp_record.h"
#include "log_capture.h"
#include "fp_session.h"
#include "step_record.h"

#include <errno.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>
#include <cmocka.h>

static fp_frame_record got;
static fp_event got_events[8];
static int sink_calls;

static void sink(void *user, const fp_frame_record *r)
{
    (void)user;
    got = *r;
    for (size_t i = 0; i < r->event_count && i < 8; i++) got_events[i] = r->events[i];
    sink_calls++;
}

static fp_event button(int which)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.header.size = sizeof ev.button;
    ev.header.type = FP_EVENT_BUTTON;
    ev.header.hand = -1;
    ev.header.time_ns = 1000 + which;
    ev.button.button = which;
    ev.button.down = true;
    return ev;
}

static void test_sink(void **state)
{
    (void)state;
    fp_record_step r;
    fp_record_step_init(&r, sink, NULL);
    fp_control_set cs = {0};
    for (int f = 0; f < 3; f++) {
        fp_record_step_begin(&r);
        for (int k = 0; k <= f; k++) {
            fp_event ev = button(k);
            fp_record_step_event(&r, &ev);
        }
        fp_frame_stats st = {0};
        st.reach_vectors = (size_t)f;
        st.reach[0] = 0.5f;
        st.reach_asked_max = 2.0 * f;
        fp_record_step_end(&r, (uint64_t)f, 5000 + f, FP_INTENT_ENGAGE, &cs, &st, NULL, 0, NULL);
        assert_int_equal(got.reach_count, f); /* the frame's reach, for the take */
        assert_true(got.reach_asked_max == 2.0 * f);
        if (f) assert_true(got.reach[0] == 0.5f);
        assert_int_equal(sink_calls, f + 1);
        assert_int_equal(got.frame, f);
        assert_int_equal(got.time_ns, 5000 + f);
        assert_int_equal(got.event_count, f + 1);
        assert_int_equal(got.requested, FP_INTENT_ENGAGE);
        assert_ptr_equal(got.controls, &cs);
        assert_int_equal(got_events[f].button.button, f);
    }
    /* many events: the buffer grows */
    fp_record_step_begin(&r);
    for (int k = 0; k < 1000; k++) {
        fp_event ev = button(1);
        fp_record_step_event(&r, &ev);
    }
    fp_record_step_end(&r, 9, 0, 0, &cs, NULL, NULL, 0, NULL);
    assert_int_equal(got.reach_count, 0);
    assert_int_equal(got.event_count, 1000);
    assert_int_equal(got.events_lost, 0);
    fp_record_step_free(&r);
    /* no sink: nothing kept, nothing called */
    fp_record_step_init(&r, NULL, NULL);
    fp_event ev = button(0);
    fp_record_step_event(&r, &ev);
    assert_int_equal(r.count, 0);
    fp_record_step_free(&r);
}

/* A recording that writes fine: every pushed event is in the file after close. */
static void test_recorder_writes(void **state)
{
    (void)state;
    char path[] = "/tmp/fp-rec-XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    fp_event_recorder *rec = NULL;
    char err[512];
    assert_int_equal(fp_event_recorder_open(path, &rec, err, sizeof err), 0);
    for (int k = 0; k < 500; k++) {
        fp_event ev = button(k % 3);
        assert_true(fp_event_recorder_push(rec, &ev));
    }
    assert_int_equal(fp_event_recorder_close(&rec, err, sizeof err), 0);
    assert_null(rec);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[256];
    int lines = 0;
    while (fgets(line, sizeof line, f))
        if (line[0] != '#') lines++;
    fclose(f);
    assert_int_equal(lines, 500);
    unlink(path);
}

/* A write that fails (file size limit) is reported by the recorder and by the record step's
 * log, once, naming the input. */
static void test_recorder_write_error(void **state)
{
    (void)state;
    char path[] = "/tmp/fp-rec-XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    struct rlimit old, lim;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    signal(SIGXFSZ, SIG_IGN);
    lim = old;
    lim.rlim_cur = 2048;
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    fp_input_instance in;
    memset(&in, 0, sizeof in);
    snprintf(in.name, sizeof in.name, "glove");
    char err[512];
    assert_int_equal(fp_event_recorder_open(path, &in.record, err, sizeof err), 0);
    for (int k = 0; k < 400; k++) {
        fp_event ev = button(k % 3);
        fp_event_recorder_push(in.record, &ev);
    }
    fp_record_step r;
    fp_record_step_init(&r, NULL, NULL);
    log_capture cap = {0};
    fp_slog log = {capture_log, &cap};
    for (int tries = 0; tries < 2000 && !cap.count; tries++) {
        fp_record_step_end(&r, 0, 0, 0, NULL, NULL, &in, 1, &log);
        usleep(1000);
    }
    fp_record_step_end(&r, 1, 0, 0, NULL, NULL, &in, 1, &log);
    assert_int_equal(cap.count, 1);
    assert_int_equal(cap.level, FP_LOG_ERROR);
    assert_string_equal(cap.source, "glove");
    assert_non_null(strstr(cap.lines[0], path));
    int rc = fp_event_recorder_close(&in.record, err, sizeof err);
    assert_true(rc < 0);
    assert_non_null(strstr(err, path));
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &old), 0);
    fp_record_step_free(&r);
    unlink(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sink),
        cmocka_unit_test(test_recorder_writes),
        cmocka_unit_test(test_recorder_write_error),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
