/* core/session/intents: pedal binding, key requests, status counts and log lines, draining. */
#include "intents.h"
#include "fp_clock.h"
#include "log_capture.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>
#include <cmocka.h>

static fp_event button(int which, bool down)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.header.size = sizeof ev.button;
    ev.header.type = FP_EVENT_BUTTON;
    ev.header.hand = -1;
    ev.button.button = which;
    ev.button.down = down;
    return ev;
}

static fp_event status(int code, const char *text)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.header.size = sizeof ev.status;
    ev.header.type = FP_EVENT_STATUS;
    ev.header.hand = -1;
    ev.status.code = code;
    snprintf(ev.status.text, sizeof ev.status.text, "%s", text);
    return ev;
}

static void test_pedal_binding(void **state)
{
    (void)state;
    fp_intents it;
    fp_intents_init(&it);
    fp_event l = button(FP_BUTTON_LEFT, true), r = button(FP_BUTTON_RIGHT, true),
             m = button(FP_BUTTON_MIDDLE, true), up = button(FP_BUTTON_LEFT, false);
    fp_intents_take(&it, 0, "pedal", &l, false, NULL);
    assert_int_equal(fp_intents_take_requested(&it), FP_INTENT_ENGAGE);
    fp_intents_take(&it, 0, "pedal", &l, true, NULL);
    assert_int_equal(fp_intents_take_requested(&it), FP_INTENT_COMMIT);
    fp_intents_take(&it, 0, "pedal", &r, true, NULL);
    assert_int_equal(fp_intents_take_requested(&it), FP_INTENT_CANCEL);
    fp_intents_take(&it, 0, "pedal", &m, true, NULL);   /* reserved for takes */
    fp_intents_take(&it, 0, "pedal", &up, true, NULL);  /* releases do nothing */
    assert_int_equal(fp_intents_take_requested(&it), 0);
    /* key requests and pedal presses accumulate until the mapping takes them */
    fp_intents_request(&it, FP_INTENT_CANCEL);
    fp_intents_take(&it, 0, "pedal", &l, false, NULL);
    assert_int_equal(fp_intents_take_requested(&it), FP_INTENT_CANCEL | FP_INTENT_ENGAGE);
    assert_int_equal(fp_intents_take_requested(&it), 0);
    assert_int_equal(it.frame_event_count, 6); /* every button kept for the mapping */
}

static void test_status_counts_and_log(void **state)
{
    (void)state;
    fp_intents it;
    fp_intents_init(&it);
    log_capture cap = {0};
    fp_slog log = {capture_log, &cap};
    fp_event e = status(FP_STATUS_ERROR, "row 12: bad number"), w = status(FP_STATUS_WARNING, "truncated"),
             d = status(FP_STATUS_DISCONNECTED, "unplugged"), c = status(FP_STATUS_CONNECTED, "hello"),
             end = status(FP_STATUS_END_OF_STREAM, "end");
    fp_intents_take(&it, 1, "replay", &e, false, &log);
    assert_int_equal(cap.count, 1);
    assert_int_equal(cap.level, FP_LOG_ERROR);
    assert_string_equal(cap.source, "replay");
    assert_string_equal(cap.lines[0], "row 12: bad number");
    assert_int_equal(it.input_errors, 1);
    assert_string_equal(it.last_error, "row 12: bad number");
    fp_intents_take(&it, 1, "replay", &w, false, &log);
    fp_intents_take(&it, 1, "glove", &d, false, &log);
    assert_int_equal(cap.count, 3);
    assert_int_equal(cap.level, FP_LOG_WARNING);
    assert_string_equal(cap.source, "glove");
    fp_intents_take(&it, 1, "replay", &c, false, &log); /* connected: no line */
    assert_int_equal(cap.count, 3);
    /* a DISCONNECTED without text (an isolated input's hands released after its fault,
     * which its WARNING said): kept for the take, no line */
    fp_event quiet = status(FP_STATUS_DISCONNECTED, "");
    quiet.header.hand = FP_HAND_RIGHT;
    size_t kept = it.frame_event_count;
    fp_intents_take(&it, 1, "crashy", &quiet, false, &log);
    assert_int_equal(cap.count, 3);
    assert_int_equal(it.frame_event_count, kept + 1);
    assert_false(fp_intents_all_ended(&it, 2));
    fp_intents_take(&it, 1, "replay", &end, false, &log);
    assert_false(fp_intents_all_ended(&it, 2));
    fp_intents_take(&it, 0, "replay", &end, false, &log);
    assert_true(fp_intents_all_ended(&it, 2));
    assert_false(fp_intents_all_ended(&it, 0));
    /* a NULL log is silent */
    fp_intents_take(&it, 0, "replay", &e, false, NULL);
    assert_int_equal(it.input_errors, 2);
}

static size_t seen;
static void count_event(void *user, size_t input, const fp_event *ev)
{
    (void)user;
    (void)ev;
    assert_true(input < 2);
    seen++;
}

/* Draining real queues: every event once, in order, to the callback; the frame's kept
 * events start afresh each drain; more than 64 kept events are capped. */
static void test_drain(void **state)
{
    (void)state;
    fp_input_instance in[2];
    memset(in, 0, sizeof in);
    for (int i = 0; i < 2; i++) {
        assert_int_equal(fp_event_queue_init(&in[i].queue, 256), 0);
        snprintf(in[i].name, sizeof in[i].name, "in%d", i);
    }
    for (int k = 0; k < 50; k++) {
        fp_event b = button(FP_BUTTON_MIDDLE, true);
        assert_true(fp_event_queue_push(&in[0].queue, &b.header));
        assert_true(fp_event_queue_push(&in[1].queue, &b.header));
    }
    fp_intents it;
    fp_intents_init(&it);
    seen = 0;
    assert_int_equal(fp_intents_drain(&it, in, 2, false, NULL, count_event, NULL), 100);
    assert_int_equal(seen, 100);
    assert_int_equal(it.frame_event_count, FP_INTENTS_MAX_FRAME_EVENTS);
    assert_int_equal(fp_intents_drain(&it, in, 2, false, NULL, count_event, NULL), 0);
    assert_int_equal(it.frame_event_count, 0);
    for (int i = 0; i < 2; i++) fp_event_queue_destroy(&in[i].queue);
}

static fp_event stamped(int type_code, int64_t t)
{
    fp_event ev = type_code ? status(type_code, "s") : button(FP_BUTTON_MIDDLE, true);
    ev.header.time_ns = t;
    return ev;
}

static int64_t seen_t[16];
static size_t seen_n;
static void note_time(void *user, size_t input, const fp_event *ev)
{
    (void)user;
    if (seen_n < 16) seen_t[seen_n++] = (int64_t)input * 1000000000000LL + ev->header.time_ns;
}

/* The input clock: two recordings whose threads started 500 ns apart start together (each
 * one's first event is its time zero); a live input's event stamped after the frame waits
 * for the frame of its time, one stamped beyond the wall clock (another clock) is taken at
 * once. */
static void test_clock_aligns_and_holds(void **state)
{
    (void)state;
    fp_input_instance in[3];
    memset(in, 0, sizeof in);
    for (int i = 0; i < 3; i++) assert_int_equal(fp_event_queue_init(&in[i].queue, 64), 0);
    const int64_t zero[2] = {1000, 1500};
    for (int i = 0; i < 2; i++) {
        fp_event e = stamped(FP_STATUS_CONNECTED, zero[i]);
        assert_true(fp_event_queue_push(&in[i].queue, &e.header));
        for (int k = 1; k <= 2; k++) {
            e = stamped(0, zero[i] + 10 * k);
            assert_true(fp_event_queue_push(&in[i].queue, &e.header));
        }
    }
    fp_intents it;
    fp_intents_init(&it);
    it.clocked = it.waited[0] = it.waited[1] = true;
    int64_t t0 = 0;
    assert_int_equal(fp_intents_first_time(&it, in, 3, &t0), 1);
    assert_int_equal(t0, 1000);
    seen_n = 0;
    assert_true(fp_intents_ready(&it, in, 3, 1010));
    assert_int_equal(fp_intents_drain_until(&it, in, 2, 1010, false, NULL, note_time, NULL), 4);
    const int64_t want[4] = {1000, 1010, 1000000000000LL + 1000, 1000000000000LL + 1010};
    for (int k = 0; k < 4; k++) assert_int_equal(seen_t[k], want[k]);
    assert_false(fp_intents_ready(&it, in, 3, 1020)); /* nothing past 1020 yet: wait */
    /* the live input (2): stamped by the host clock */
    const int64_t now = fp_now_ns();
    const int64_t times[3] = {now - 1000, now + 10000000000LL, now + 1000000}; /* (in order) */
    for (int k = 0; k < 3; k++) {
        fp_event e = stamped(0, times[k]);
        assert_true(fp_event_queue_push(&in[2].queue, &e.header));
    }
    seen_n = 0;
    fp_intents_drain_until(&it, in, 3, now, false, NULL, note_time, NULL);
    assert_int_equal(seen_n, 4); /* 1020 and 1520 (shifted to 1020), then 2 live ones */
    assert_int_equal(seen_t[2], 2000000000000LL + times[0]);
    assert_int_equal(seen_t[3], 2000000000000LL + times[1]);
    seen_n = 0;
    fp_intents_drain_until(&it, in, 3, now + 1000000, false, NULL, note_time, NULL);
    assert_int_equal(seen_n, 1);
    assert_int_equal(seen_t[0], 2000000000000LL + times[2]);
    fp_intents_free(&it);
    for (int i = 0; i < 3; i++) fp_event_queue_destroy(&in[i].queue);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pedal_binding),
        cmocka_unit_test(test_status_counts_and_log),
        cmocka_unit_test(test_drain),
        cmocka_unit_test(test_clock_aligns_and_holds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
