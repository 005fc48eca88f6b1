/*
 * test_osc_hands.c: input-osc against senders as docs/osc.md and shared/docs/devices.md ("OSC")
 * describe them, the cases an outside audit found wrong: a MediaPipe sender without z after one
 * with z; a Leap bundle with its tips before its palm; a Leap hand's side kept by its id;
 * bundles out of order; listening on IPv6 (bind=::1, ::, localhost, dual stack on 0.0.0.0).
 * Loopback UDP only (127.0.0.1, and ::1 where the machine has it: those parts are skipped,
 * never failed, where socket(AF_INET6) or a bind to ::1 fails).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "osc_fixture.h"

#include <arpa/inet.h>
#include <errno.h>
#include <math.h>
#include <netinet/in.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmocka.h>

/* ------------------------------------------------------------------------------------- */
/* Senders                                                                                */

/* 21 floats a + b * j: one MediaPipe coordinate (landmark j) */
static void send_mp(osc_fixture *f, const char *path, float a, float b)
{
    lo_message m = lo_message_new();
    for (int j = 0; j < 21; j++) lo_message_add_float(m, a + b * (float)j);
    assert_true(lo_send_message(f->to, path, m) > 0);
    lo_message_free(m);
}

static lo_message leap_msg(int32_t id, int32_t second, float x, float y, float z)
{
    lo_message m = lo_message_new();
    lo_message_add_int32(m, id);
    lo_message_add_int32(m, second);
    lo_message_add_float(m, x);
    lo_message_add_float(m, y);
    lo_message_add_float(m, z);
    return m;
}

/* Adds slot's Leap frame to b: palm at (x, 200, 0), tip n at (x + 10 n, 280, -20); the palm
 * after tip `palm_after` (-1: first, 4: last). */
static void add_leap_frame(lo_bundle b, int slot, int32_t id, float x, int palm_after)
{
    char path[32];
    snprintf(path, sizeof path, "/hand%d", slot);
    if (palm_after < 0) lo_bundle_add_message(b, path, leap_msg(id, 0, x, 200.f, 0.f));
    for (int n = 0; n < FP_FINGERS; n++) {
        snprintf(path, sizeof path, "/finger%d-%d", slot, n);
        lo_bundle_add_message(b, path, leap_msg(id, n, x + 10.f * (float)n, 280.f, -20.f));
        if (n == palm_after) {
            snprintf(path, sizeof path, "/hand%d", slot);
            lo_bundle_add_message(b, path, leap_msg(id, 0, x, 200.f, 0.f));
        }
    }
}

static void send_bundle(osc_fixture *f, lo_bundle b)
{
    assert_true(lo_send_bundle(f->to, b) > 0);
    lo_bundle_free_recursive(b);
}

static lo_timetag timetag_plus(lo_timetag base, double s)
{
    uint64_t frac = (uint64_t)base.frac + (uint64_t)(s * 4294967296.0);
    return (lo_timetag){base.sec + (uint32_t)(frac >> 32), (uint32_t)frac};
}

/* The joint_positions events' palm x and hands, in order; returns their count. */
static size_t poses(fake_host *h, float *palm_x, int *hand, size_t cap)
{
    size_t n = 0;
    pthread_mutex_lock(&h->mutex);
    for (size_t e = 0; e < h->count && n < cap; e++)
        if (h->events[e].header.type == FP_EVENT_JOINT_POSITIONS) {
            palm_x[n] = h->events[e].positions.mm[FP_JOINT_PALM][0];
            hand[n++] = h->events[e].header.hand;
        }
    pthread_mutex_unlock(&h->mutex);
    return n;
}

/* Whether this machine has an IPv6 loopback (a UDP socket binds to [::1]). */
static bool have_ipv6_loopback(void)
{
    int s = socket(AF_INET6, SOCK_DGRAM, 0);
    struct sockaddr_in6 a = {.sin6_family = AF_INET6, .sin6_addr = IN6ADDR_LOOPBACK_INIT};
    bool ok = s >= 0 && bind(s, (struct sockaddr *)&a, sizeof a) == 0;
    if (s >= 0) close(s);
    return ok;
}

/* Whether the host's log has a line at `level` that contains `text`. */
static bool log_has(fake_host *h, fp_log_level level, const char *text)
{
    char head[16];
    snprintf(head, sizeof head, "%d ", (int)level);
    bool found = false;
    pthread_mutex_lock(&h->mutex);
    for (const char *line = h->log; *line && !found;) {
        const char *end = strchr(line, '\n');
        size_t n = end ? (size_t)(end - line) : strlen(line);
        const char *hit = strstr(line, text);
        found = strncmp(line, head, strlen(head)) == 0 && hit && hit < line + n;
        line += n + (end != NULL);
    }
    pthread_mutex_unlock(&h->mutex);
    return found;
}

/* Sends /facepuppet/button i i (1, 1) from a fresh socket to host:port (v6: [::1]). */
static void send_button(bool v6, unsigned port)
{
    lo_message m = lo_message_new();
    lo_message_add_int32(m, 1);
    lo_message_add_int32(m, 1);
    size_t len = 0;
    void *bytes = lo_message_serialise(m, "/facepuppet/button", NULL, &len);
    lo_message_free(m);
    int s = socket(v6 ? AF_INET6 : AF_INET, SOCK_DGRAM, 0);
    assert_true(s >= 0);
    struct sockaddr_in6 a6 = {.sin6_family = AF_INET6, .sin6_port = htons((uint16_t)port),
                              .sin6_addr = IN6ADDR_LOOPBACK_INIT};
    struct sockaddr_in a4 = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port),
                             .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    ssize_t n = v6 ? sendto(s, bytes, len, 0, (struct sockaddr *)&a6, sizeof a6)
                   : sendto(s, bytes, len, 0, (struct sockaddr *)&a4, sizeof a4);
    assert_int_equal(n, (ssize_t)len);
    free(bytes);
    close(s);
}

/* ------------------------------------------------------------------------------------- */
/* MediaPipe                                                                              */

/* A sender with z (/rx /ry /rz) stops; after the timeout one without z (Handmate-OSC's /rx/
 * /ry/) starts on the same port: its frames come out as flat hands (z = depth). And a sender
 * that stops sending z without a pause: from its second frame without z on, every frame. */
static void mediapipe_z_then_no_z(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "format=mediapipe,timeout=0.2,depth=10", 256);
    for (int k = 0; k < 5; k++) {
        send_mp(&f, "/rx", 0.4f, 0.01f);
        send_mp(&f, "/ry", 0.5f, 0.01f);
        send_mp(&f, "/rz", 0.1f, 0.f);
        wait_packets(&f, 3u * (unsigned)k + 3);
    }
    /* the first frame twice (x y at once, then again with z), then 4 */
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, 6));
    assert_true(wait_type(f.h, FP_EVENT_STATUS, FP_STATUS_DISCONNECTED, 1)); /* quiet 0.2 s */
    size_t before = count_type(f.h, FP_EVENT_JOINT_POSITIONS, -1);
    for (int k = 0; k < 5; k++) {
        send_mp(&f, "/rx/", 0.4f, 0.01f);
        send_mp(&f, "/ry/", 0.5f, 0.01f);
        wait_packets(&f, 15u + 2u * (unsigned)k + 2);
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, before + 5));
    const fp_event *e = nth_positions(f.h, before + 4);
    for (int j = 0; j < FP_HAND_JOINTS; j++) assert_float_equal(e->positions.mm[j][2], 10.f, 1e-4);
    /* z again (with z: 0.1 x 400 mm beyond depth), then no z without a pause */
    uint64_t sent = 25;
    for (int k = 0; k < 3; k++) {
        send_mp(&f, "/rx", 0.4f, 0.01f);
        send_mp(&f, "/ry", 0.5f, 0.01f);
        send_mp(&f, "/rz", 0.1f, 0.f);
        wait_packets(&f, sent += 3);
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, before + 5 + 3));
    e = nth_positions(f.h, before + 7);
    assert_float_equal(e->positions.mm[FP_JOINT_TIP(1)][2], 50.f, 1e-3);
    before = count_type(f.h, FP_EVENT_JOINT_POSITIONS, -1);
    for (int k = 0; k < 5; k++) {
        send_mp(&f, "/rx/", 0.4f, 0.01f);
        send_mp(&f, "/ry/", 0.5f, 0.01f);
        wait_packets(&f, sent += 2);
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, before + 4));
    close_fixture(&f);
}

/* 21 floats a + b * j added to bundle b at path */
static void add_mp(lo_bundle b, const char *path, float a, float c)
{
    lo_message m = lo_message_new();
    for (int j = 0; j < 21; j++) lo_message_add_float(m, a + c * (float)j);
    lo_bundle_add_message(b, path, m);
}

/* A sender with z that sends each frame as one bundle (/rx /ry /rz): one frame a bundle, the
 * first one too, with its depth. (Before: the first frame came twice at one time, flat from
 * x and y and again with z: the session took it as a hand jumping 40 mm in no time, "the
 * right hand jumped farther and faster than a hand moves", and placed the hands from a flat
 * first frame.) And a sender without z in bundles: one flat frame a bundle. */
static void mediapipe_bundle_with_z_once(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "format=mediapipe,depth=10", 256);
    for (int k = 0; k < 3; k++) {
        lo_timetag tt;
        lo_timetag_now(&tt);
        lo_bundle b = lo_bundle_new(tt);
        add_mp(b, "/rx", 0.4f, 0.01f);
        add_mp(b, "/ry", 0.5f, 0.01f);
        add_mp(b, "/rz", 0.1f, 0.f);
        send_bundle(&f, b);
        wait_packets(&f, (uint64_t)k + 1);
        sleep_ms(10);
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, 3));
    sleep_ms(50);
    assert_int_equal(count_type(f.h, FP_EVENT_JOINT_POSITIONS, -1), 3);
    for (size_t k = 0; k < 3; k++) /* depth 10 + 0.1 x 400 mm */
        assert_float_equal(nth_positions(f.h, k)->positions.mm[FP_JOINT_TIP(1)][2], 50.f, 1e-3);
    close_fixture(&f);

    open_fixture(&f, "format=mediapipe,depth=10", 256);
    for (int k = 0; k < 3; k++) {
        lo_bundle b = lo_bundle_new(LO_TT_IMMEDIATE);
        add_mp(b, "/lx/", 0.4f, 0.01f);
        add_mp(b, "/ly/", 0.5f, 0.01f);
        send_bundle(&f, b);
        wait_packets(&f, (uint64_t)k + 1);
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, 3));
    sleep_ms(50);
    assert_int_equal(count_type(f.h, FP_EVENT_JOINT_POSITIONS, -1), 3);
    for (size_t k = 0; k < 3; k++) {
        assert_int_equal(nth_positions(f.h, k)->header.hand, FP_HAND_LEFT);
        assert_float_equal(nth_positions(f.h, k)->positions.mm[FP_JOINT_TIP(1)][2], 10.f, 1e-4);
    }
    fp_osc_stats st = stats(&f);
    for (int k = 0; k < FP_OSC_PROBLEMS; k++) assert_int_equal(st.problems[k], 0);
    close_fixture(&f);
}

/* ------------------------------------------------------------------------------------- */
/* Leap                                                                                   */

/* In a bundle the order of a frame's messages does not matter: tips then palm, or the palm in
 * the middle, give each bundle's own frame (no frame lost, no palm of the bundle before). */
static void leap_bundle_any_order(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "format=leap", 256);
    for (int k = 0; k < 10; k++) {
        lo_timetag tt;
        lo_timetag_now(&tt);
        lo_bundle b = lo_bundle_new(tt);
        add_leap_frame(b, 0, 7, 50.f + (float)k, k % 2 ? 4 : 1);
        send_bundle(&f, b);
        wait_packets(&f, (uint64_t)k + 1);
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, 10));
    sleep_ms(20);
    assert_int_equal(count_type(f.h, FP_EVENT_JOINT_POSITIONS, -1), 10);
    for (size_t k = 0; k < 10; k++) {
        const fp_event *e = nth_positions(f.h, k);
        assert_float_equal(e->positions.mm[FP_JOINT_PALM][0], 50.f + (float)k, 0);
        for (int n = 0; n < FP_FINGERS; n++)
            assert_float_equal(e->positions.mm[FP_JOINT_TIP(n)][0], 50.f + (float)k + 10.f * (float)n, 0);
    }
    assert_int_equal(stats(&f).problems[FP_OSC_INCOMPLETE], 0);
    close_fixture(&f);
}

/* A hand keeps its side by its Leap id: one hand crossing x = 0 stays the hand it was. */
static void leap_side_kept_by_id(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "format=leap", 256);
    for (int k = 0; k < 30; k++) {
        lo_timetag tt;
        lo_timetag_now(&tt);
        lo_bundle b = lo_bundle_new(tt);
        add_leap_frame(b, 0, 7, 30.f - 2.f * (float)k, -1);
        send_bundle(&f, b);
        wait_packets(&f, (uint64_t)k + 1);
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, 30));
    float x[64];
    int hand[64];
    assert_int_equal(poses(f.h, x, hand, 64), 30);
    for (int k = 0; k < 30; k++) assert_int_equal(hand[k], FP_HAND_RIGHT);
    close_fixture(&f);
}

/* A Leap gives a hand a new id when it loses it and finds it again: the one right hand,
 * re-acquired under a new id a frame later at the same place, stays the right hand (before:
 * the new id took the side the old, still "present" id did not hold, and the right hand
 * became the left one for the timeout). A second hand that comes while the first is in the
 * same frame still takes the other side. */
static void leap_reacquired_hand_keeps_side(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "format=leap", 256);
    for (int k = 0; k < 20; k++) {
        lo_timetag tt;
        lo_timetag_now(&tt);
        lo_bundle b = lo_bundle_new(tt);
        add_leap_frame(b, 0, k < 10 ? 7 : 8, 40.f + (float)k, -1); /* id 7, then 8 */
        send_bundle(&f, b);
        wait_packets(&f, (uint64_t)k + 1);
        sleep_ms(10); /* a Leap's frames, about 100 a second */
    }
    lo_timetag tt;
    lo_timetag_now(&tt);
    lo_bundle b = lo_bundle_new(tt); /* id 8 and a new hand 9 beside it in one frame */
    add_leap_frame(b, 0, 8, 60.f, -1);
    add_leap_frame(b, 1, 9, 90.f, -1);
    send_bundle(&f, b);
    wait_packets(&f, 21);
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, 22));
    float x[64];
    int hand[64];
    assert_int_equal(poses(f.h, x, hand, 64), 22);
    for (int k = 0; k < 21; k++) {
        if (hand[k] != FP_HAND_RIGHT) fprintf(stderr, "pose %d: hand %d\n", k, hand[k]);
        assert_int_equal(hand[k], FP_HAND_RIGHT);
    }
    assert_int_equal(hand[21], FP_HAND_LEFT);
    close_fixture(&f);
}

/* A bridge that sends each hand in a datagram of its own: a second hand that comes beside
 * the first, its datagram within the first's frame, is the other hand, not the first one
 * found again under a new id (it came while the first was not quiet). */
static void leap_second_hand_own_datagram(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "format=leap", 256);
    uint64_t sent = 0;
    for (int k = 0; k < 6; k++) {
        lo_timetag tt;
        lo_timetag_now(&tt);
        lo_bundle b = lo_bundle_new(tt);
        add_leap_frame(b, 0, 7, 40.f + (float)k, -1);
        send_bundle(&f, b);
        wait_packets(&f, ++sent);
        if (k == 5) { /* the second hand, 50 mm away, in its own datagram of the same frame */
            lo_timetag_now(&tt);
            b = lo_bundle_new(tt);
            add_leap_frame(b, 1, 9, 90.f, -1);
            send_bundle(&f, b);
            wait_packets(&f, ++sent);
        }
        sleep_ms(10);
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, 7));
    float x[64];
    int hand[64];
    assert_int_equal(poses(f.h, x, hand, 64), 7);
    for (int k = 0; k < 6; k++) assert_int_equal(hand[k], FP_HAND_RIGHT);
    assert_int_equal(hand[6], FP_HAND_LEFT);
    close_fixture(&f);
}

/* Two Leap hands at once get two sides, the one at smaller x left, even both at x > 0; each
 * keeps it when they cross. */
static void leap_two_hands_two_sides(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "format=leap", 256);
    for (int k = 0; k < 10; k++) {
        lo_timetag tt;
        lo_timetag_now(&tt);
        lo_bundle b = lo_bundle_new(tt);
        /* slot 0: id 9 from x 150 to 60; slot 1: id 4 from x 20 to 110 (they cross) */
        add_leap_frame(b, 0, 9, 150.f - 10.f * (float)k, k % 2 ? 4 : -1);
        add_leap_frame(b, 1, 4, 20.f + 10.f * (float)k, -1);
        send_bundle(&f, b);
        wait_packets(&f, (uint64_t)k + 1);
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, 20));
    float x[64];
    int hand[64];
    assert_int_equal(poses(f.h, x, hand, 64), 20);
    /* each bundle: one left, one right; the left one is id 4 (x 20 + 10 k: the smaller x
     * when both first came), the right one id 9, before and after they cross */
    for (int k = 0; k < 10; k++)
        for (int s = 0; s < 2; s++) {
            const int i = 2 * k + s;
            assert_int_equal(hand[i], x[i] == 20.f + 10.f * (float)k ? FP_HAND_LEFT : FP_HAND_RIGHT);
            assert_true(x[i] == 20.f + 10.f * (float)k || x[i] == 150.f - 10.f * (float)k);
        }
    assert_int_not_equal(hand[0], hand[1]);
    close_fixture(&f);
}

/* ------------------------------------------------------------------------------------- */
/* Problems named                                                                         */

/* A sender's message with extra trailing arguments (a bridge that adds a velocity) and one
 * with a wrong type: each kind's warning names the first such message, its address and what
 * was wrong. (Before: "messages with a wrong argument count", nothing to find it by.) */
static void bad_messages_named(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, NULL, 64);
    lo_bundle b = lo_bundle_new(LO_TT_IMMEDIATE);
    lo_message palm = leap_msg(7, 0, 1.f, 2.f, 3.f), wrist = lo_message_new();
    lo_message_add_float(palm, 0.5f);
    lo_message_add_float(palm, 0.5f);
    lo_message_add_float(wrist, 1.f);
    lo_message_add_string(wrist, "y");
    for (int i = 0; i < 5; i++) lo_message_add_float(wrist, 0.f);
    lo_bundle_add_message(b, "/hand0", palm);
    lo_bundle_add_message(b, "/facepuppet/hand/right/wrist", wrist);
    send_bundle(&f, b);
    wait_packets(&f, 1);
    assert_true(wait_type(f.h, FP_EVENT_STATUS, FP_STATUS_WARNING, 2));
    sleep_ms(50);
    if (!log_has(f.h, FP_LOG_WARNING, "first: /hand0 with 7 arguments, wants 5") ||
        !log_has(f.h, FP_LOG_WARNING, "first: /facepuppet/hand/right/wrist: argument 2 is 's', wants a number")) {
        pthread_mutex_lock(&f.h->mutex);
        fprintf(stderr, "log:\n%s", f.h->log);
        pthread_mutex_unlock(&f.h->mutex);
        fail();
    }
    fp_osc_stats st = stats(&f);
    assert_int_equal(st.problems[FP_OSC_BAD_COUNT], 1);
    assert_int_equal(st.problems[FP_OSC_BAD_TYPES], 1);
    close_fixture(&f);
}

/* ------------------------------------------------------------------------------------- */
/* Time                                                                                   */

/* Bundles out of order (timetags 0, 1, 3, 2, 4 x 100 ms): the stale one (2, after 3) is
 * dropped and counted; event times never step back. */
static void out_of_order_bundle_dropped(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "format=leap", 256);
    lo_timetag base;
    lo_timetag_now(&base);
    static const int order[] = {0, 1, 3, 2, 4};
    for (int i = 0; i < 5; i++) {
        lo_bundle b = lo_bundle_new(timetag_plus(base, 0.1 * order[i]));
        add_leap_frame(b, 0, 7, 10.f * (float)order[i] + 5.f, -1);
        send_bundle(&f, b);
        wait_packets(&f, (uint64_t)i + 1);
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, 4));
    sleep_ms(50);
    assert_int_equal(count_type(f.h, FP_EVENT_JOINT_POSITIONS, -1), 4);
    static const float want[] = {5.f, 15.f, 35.f, 45.f};
    for (size_t i = 0; i < 4; i++) {
        const fp_event *e = nth_positions(f.h, i);
        assert_float_equal(e->positions.mm[FP_JOINT_PALM][0], want[i], 0);
        if (i) assert_true(e->header.time_ns > nth_positions(f.h, i - 1)->header.time_ns);
    }
    fp_osc_stats st = stats(&f);
    assert_int_equal(st.problems[FP_OSC_STALE], 1);
    for (int k = 0; k < FP_OSC_PROBLEMS; k++)
        if (k != FP_OSC_STALE) assert_int_equal(st.problems[k], 0);
    close_fixture(&f);
}

/* A first bundle that waited (its timetag 300 ms before the others': it sat in the socket
 * before the input read it, as a sender started before facepuppet leaves its first ones)
 * does not leave every later event stamped 300 ms late: no event is stamped after its
 * arrival, and the bundles' spacing is kept. (Before: the first bundle fixed the offset, and
 * every later event was stamped 300 ms after it arrived, the hands shown that late.) */
static void first_bundle_late_not_kept(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "format=leap", 256);
    lo_timetag base;
    lo_timetag_now(&base);
    base.sec -= 1; /* (timetag_plus adds: 0.3 s before now is 1 s before plus 0.7) */
    int64_t seen[6];
    for (int k = 0; k < 6; k++) {
        lo_timetag tt;
        lo_timetag_now(&tt);
        lo_bundle b = lo_bundle_new(k == 0 ? timetag_plus(base, 0.7) : tt);
        add_leap_frame(b, 0, 7, 10.f * (float)k, -1);
        send_bundle(&f, b);
        wait_packets(&f, (uint64_t)k + 1);
        assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, (size_t)k + 1));
        seen[k] = mono_ns(); /* the event is in: it arrived before now */
        sleep_ms(20);
    }
    for (size_t k = 0; k < 6; k++) {
        const fp_event *e = nth_positions(f.h, k);
        if (e->header.time_ns > seen[k])
            fail_msg("bundle %zu stamped %.1f ms after it was received", k,
                     (double)(e->header.time_ns - seen[k]) / 1e6);
        if (k) assert_true(e->header.time_ns > nth_positions(f.h, k - 1)->header.time_ns);
    }
    fp_osc_stats st = stats(&f);
    for (int k = 0; k < FP_OSC_PROBLEMS; k++) assert_int_equal(st.problems[k], 0);
    close_fixture(&f);
}

/* A sender restarted on a new port, its clock begun again (timetags from 1000 s on its own
 * scale, 20 ms apart), 0.3 s after the first stopped: its bundles are its own, neither
 * stale nor stamped on the first sender's clock. (Before: they mapped 0.4 s into the past
 * through the first sender's offset, under the 1 s that fixes it again, so every one was
 * dropped as "stale".) */
static void restarted_sender_not_stale(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "format=leap", 256);
    const lo_timetag zero = {1000, 0};
    uint64_t sent = 0;
    int64_t t_first_end = 0;
    for (int run = 0; run < 2; run++) {
        lo_address to = run ? lo_address_new("127.0.0.1", f.port) : f.to; /* a new source port */
        for (int k = 0; k < 5; k++) {
            lo_bundle b = lo_bundle_new(timetag_plus(zero, 0.02 * k));
            add_leap_frame(b, 0, 7, (float)(100 * run + k), -1);
            assert_true(lo_send_bundle(to, b) > 0);
            lo_bundle_free_recursive(b);
            wait_packets(&f, ++sent);
            sleep_ms(20);
        }
        if (run) lo_address_free(to);
        t_first_end = run ? t_first_end : mono_ns();
        sleep_ms(300); /* the first sender quiet: the second takes over */
    }
    assert_true(wait_type(f.h, FP_EVENT_JOINT_POSITIONS, -1, 10));
    fp_osc_stats st = stats(&f);
    assert_int_equal(st.problems[FP_OSC_STALE], 0);
    for (size_t k = 5; k < 10; k++) {
        const fp_event *e = nth_positions(f.h, k);
        assert_float_equal(e->positions.mm[FP_JOINT_PALM][0], 100.f + (float)(k - 5), 0);
        if (e->header.time_ns < t_first_end)
            fail_msg("the new sender's bundle %zu stamped %.1f ms before the first sender stopped",
                     k - 5, (double)(t_first_end - e->header.time_ns) / 1e6);
        assert_true(e->header.time_ns > nth_positions(f.h, k - 1)->header.time_ns);
    }
    close_fixture(&f);
}

/* clock=recording with a sender that is not a session's forward= (plain messages: nothing on
 * a recording's clock) that then goes quiet: the input ends after the timeout, so `run`
 * does not wait on it for ever. (Before: no end, and `run --duration 5` waited until killed,
 * "waiting 39 s for 'osc' to deliver past 0.000 s".) */
static void recording_clock_untimed_sender_ends(void **state)
{
    (void)state;
    osc_fixture f;
    open_fixture(&f, "clock=recording,timeout=0.2", 64);
    for (int i = 0; i < 3; i++) send_button(false, (unsigned)atoi(f.port));
    wait_packets(&f, 3);
    assert_int_equal(stats(&f).problems[FP_OSC_UNTIMED], 3);
    assert_true(wait_type(f.h, FP_EVENT_STATUS, FP_STATUS_END_OF_STREAM, 1));
    assert_true(log_has(f.h, FP_LOG_WARNING, "sent nothing on a recording's clock (3 messages"));
    close_fixture(&f);
}

/* ------------------------------------------------------------------------------------- */
/* Binding                                                                                */

/* bind=::1, [::1], ::, localhost are taken; an address that is not one (a name other than
 * localhost) is refused. On 0.0.0.0 (and ::) one socket hears IPv4 and IPv6 senders. */
static void bind_ipv6_and_localhost(void **state)
{
    (void)state;
    const bool v6 = have_ipv6_loopback();
    static const char *const binds[] = {"bind=localhost", "bind=0.0.0.0", "bind=::", "bind=::1",
                                        "bind=[::1]"};
    for (size_t i = 0; i < sizeof binds / sizeof binds[0]; i++) {
        const bool needs_v6 = strstr(binds[i], ":") != NULL;
        if (needs_v6 && !v6) continue; /* no IPv6 here: that part skipped */
        osc_fixture f;
        open_fixture(&f, binds[i], 64);
        unsigned port = (unsigned)atoi(f.port), want = 0;
        if (strcmp(binds[i], "bind=::1") && strcmp(binds[i], "bind=[::1]")) {
            send_button(false, port);
            want++;
            assert_true(wait_type(f.h, FP_EVENT_BUTTON, -1, want));
            /* an IPv4 sender named as such, on a dual-stack socket too (not ::ffff:127.0.0.1) */
            assert_true(wait_type(f.h, FP_EVENT_STATUS, FP_STATUS_CONNECTED, 1));
            pthread_mutex_lock(&f.h->mutex);
            for (size_t e = 0; e < f.h->count; e++)
                if (f.h->events[e].header.type == FP_EVENT_STATUS &&
                    !strstr(f.h->events[e].status.text, "sender 127.0.0.1:"))
                    fail_msg("%s: \"%s\"", binds[i], f.h->events[e].status.text);
            pthread_mutex_unlock(&f.h->mutex);
        }
        if (v6) {
            send_button(true, port);
            want++;
            if (!wait_type(f.h, FP_EVENT_BUTTON, -1, want)) fail_msg("%s: [::1] not heard", binds[i]);
        }
        close_fixture(&f);
    }
    fake_host *h = fake_new(4);
    fp_input *in = NULL;
    char err[512];
    assert_int_equal(create(h, "bind=localhost.invalid", &in, err, sizeof err), -EINVAL);
    assert_int_equal(create(h, "bind=::g", &in, err, sizeof err), -EINVAL);
    fake_free(h);
}

/* On the default 127.0.0.1, [::1] at the same port taken by another program: the input
 * listens on 127.0.0.1 and says, as a warning, that [::1] is not heard. */
static void ipv6_side_taken_warned(void **state)
{
    (void)state;
    if (!have_ipv6_loopback()) skip();
    int other = socket(AF_INET6, SOCK_DGRAM, 0), one = 1;
    assert_true(other >= 0);
    assert_int_equal(setsockopt(other, IPPROTO_IPV6, IPV6_V6ONLY, &one, sizeof one), 0);
    struct sockaddr_in6 a = {.sin6_family = AF_INET6, .sin6_addr = IN6ADDR_LOOPBACK_INIT};
    assert_int_equal(bind(other, (struct sockaddr *)&a, sizeof a), 0);
    socklen_t len = sizeof a;
    assert_int_equal(getsockname(other, (struct sockaddr *)&a, &len), 0);
    char port[16];
    snprintf(port, sizeof port, "%u", (unsigned)ntohs(a.sin6_port));
    fake_host *h = fake_new(16);
    fp_input *in = NULL;
    char err[512] = "";
    int rc = factory->create(&h->host, port, NULL, 0, &in, err, sizeof err);
    if (rc == -EBUSY) { /* 127.0.0.1 at that port taken too, by chance: nothing to say */
        close(other);
        fake_free(h);
        skip();
    }
    assert_int_equal(rc, 0);
    if (!log_has(h, FP_LOG_WARNING, "[::1]")) fail_msg("no warning about [::1]: log \"%s\"", h->log);
    assert_int_equal(in->start(in, err, sizeof err), 0);
    send_button(false, (unsigned)atoi(port));
    assert_true(wait_type(h, FP_EVENT_BUTTON, -1, 1));
    in->stop(in);
    in->destroy(in);
    close(other);
    fake_free(h);
}

/* bind=0.0.0.0 with [::]:PORT taken on IPv6 alone by another program: the input listens on
 * 0.0.0.0 (IPv4) and warns that IPv6 senders are not heard. */
static void dual_stack_falls_back_to_ipv4(void **state)
{
    (void)state;
    int other = socket(AF_INET6, SOCK_DGRAM, 0), one = 1;
    if (other < 0) skip(); /* no IPv6 here */
    assert_int_equal(setsockopt(other, IPPROTO_IPV6, IPV6_V6ONLY, &one, sizeof one), 0);
    struct sockaddr_in6 a = {.sin6_family = AF_INET6, .sin6_addr = IN6ADDR_ANY_INIT};
    if (bind(other, (struct sockaddr *)&a, sizeof a) != 0) {
        close(other);
        skip();
    }
    socklen_t len = sizeof a;
    assert_int_equal(getsockname(other, (struct sockaddr *)&a, &len), 0);
    char port[16];
    snprintf(port, sizeof port, "%u", (unsigned)ntohs(a.sin6_port));
    fake_host *h = fake_new(16);
    fp_input *in = NULL;
    char err[512] = "";
    fp_param bind = {"bind", "0.0.0.0"};
    int rc = factory->create(&h->host, port, &bind, 1, &in, err, sizeof err);
    if (rc == -EBUSY) { /* 0.0.0.0 at that port taken too, by chance */
        close(other);
        fake_free(h);
        skip();
    }
    assert_int_equal(rc, 0);
    if (!log_has(h, FP_LOG_WARNING, "IPv6 senders are not heard"))
        fail_msg("no warning about IPv6: log \"%s\"", h->log);
    assert_int_equal(in->start(in, err, sizeof err), 0);
    send_button(false, (unsigned)atoi(port));
    assert_true(wait_type(h, FP_EVENT_BUTTON, -1, 1));
    in->stop(in);
    in->destroy(in);
    close(other);
    fake_free(h);
}

static int group_setup(void **state)
{
    (void)state;
    return osc_fixture_load();
}

static int group_teardown(void **state)
{
    (void)state;
    osc_fixture_unload();
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(mediapipe_z_then_no_z),
        cmocka_unit_test(mediapipe_bundle_with_z_once),
        cmocka_unit_test(leap_bundle_any_order),
        cmocka_unit_test(leap_side_kept_by_id),
        cmocka_unit_test(leap_reacquired_hand_keeps_side),
        cmocka_unit_test(leap_second_hand_own_datagram),
        cmocka_unit_test(leap_two_hands_two_sides),
        cmocka_unit_test(bad_messages_named),
        cmocka_unit_test(out_of_order_bundle_dropped),
        cmocka_unit_test(first_bundle_late_not_kept),
        cmocka_unit_test(restarted_sender_not_stale),
        cmocka_unit_test(recording_clock_untimed_sender_ends),
        cmocka_unit_test(bind_ipv6_and_localhost),
        cmocka_unit_test(ipv6_side_taken_warned),
        cmocka_unit_test(dual_stack_falls_back_to_ipv4),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
