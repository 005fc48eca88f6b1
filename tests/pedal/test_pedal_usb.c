/*
 * test_pedal_usb.c: the input-pedal plugin, loaded through plugin.h alone (dlopen of
 * build/lib/facepuppet/input-pedal.so), reading emulated pedals (pedal_emu.c, umockdev).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <linux/capability.h>

#include <cmocka.h>

#include "facepuppet/plugin.h"
#include "fp_test_support.h"
#include "pedal_emu.h"

/* ----------------------------------------------------------------------------------- */
/* A host that records what the plugin pushes                                          */

#define MAX_EVENTS 256

/* Events whose header does not fit a pedal's: hand -1, no flags, button or status of the
 * right size. */
static int bad_headers(fp_test_host *r)
{
    int bad = 0;
    pthread_mutex_lock(&r->lock);
    for (size_t i = 0; i < r->count; i++) {
        const fp_event_header *ev = &r->events[i].header;
        if (ev->hand != -1 || ev->flags != 0 ||
            (ev->type == FP_EVENT_BUTTON && ev->size != sizeof(fp_event_button)) ||
            (ev->type == FP_EVENT_STATUS && ev->size != sizeof(fp_event_status)) ||
            (ev->type != FP_EVENT_BUTTON && ev->type != FP_EVENT_STATUS))
            bad++;
    }
    pthread_mutex_unlock(&r->lock);
    return bad;
}

/* The pedal's host: keeps MAX_EVENTS, refuses more, echoes warnings. */
static void rec_init(fp_test_host *r)
{
    fp_test_host_init(r, MAX_EVENTS);
    r->refuse_when_full = true;
    r->echo_level = getenv("PEDAL_TEST_VERBOSE") ? FP_LOG_DEBUG : FP_LOG_WARNING;
}

/* ----------------------------------------------------------------------------------- */
/* Fixture                                                                             */

typedef struct fixture {
    void *so;
    const fp_input_factory *factory;
    emu *emu;
    fp_test_host rec;
    fp_input *input;
} fixture;

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    f->factory = fp_test_plugin_open("input-pedal.so", FP_INPUT_FACTORY_ID, &f->so);
    if (!f->factory) {
        free(f);
        return -1;
    }
    f->emu = emu_new();
    if (!f->emu) {
        fprintf(stderr, "umockdev is not active: run with libumockdev-preload\n");
        fp_test_plugin_close(&f->so);
        free(f);
        return -1;
    }
    rec_init(&f->rec);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    if (f->input) {
        f->input->stop(f->input);
        f->input->destroy(f->input);
    }
    emu_free(&f->emu);
    fp_test_plugin_close(&f->so);
    fp_test_host_clear(&f->rec);
    free(f);
    return 0;
}

/* Create and start with `arg` and up to 4 key=value pairs (NULL-terminated). */
static int start_plugin(fixture *f, const char *arg, const fp_param *params, size_t n)
{
    char err[256] = "";
    int r = f->factory->create(&f->rec.host, arg, params, n, &f->input, err, sizeof err);
    if (r) {
        fprintf(stderr, "create: %s\n", err);
        return r;
    }
    r = f->input->start(f->input, err, sizeof err);
    if (r)
        fprintf(stderr, "start: %s\n", err);
    return r;
}

static void expect_status(fixture *f, fp_status_code code, const char *contains)
{
    fp_event ev;
    assert_true(fp_test_host_next(&f->rec, &ev, 5000));
    assert_int_equal(ev.header.type, FP_EVENT_STATUS);
    if (ev.status.code != (uint32_t)code)
        fprintf(stderr, "status %u \"%s\", expected %d\n", ev.status.code, ev.status.text, code);
    assert_int_equal(ev.status.code, code);
    if (contains)
        assert_non_null(strstr(ev.status.text, contains));
}

static void expect_button(fixture *f, uint32_t button, uint32_t down, uint32_t mask)
{
    fp_event ev;
    assert_true(fp_test_host_next(&f->rec, &ev, 3000));
    if (ev.header.type != FP_EVENT_BUTTON)
        fprintf(stderr, "got status %u \"%s\"\n", ev.status.code, ev.status.text);
    assert_int_equal(ev.header.type, FP_EVENT_BUTTON);
    assert_int_equal(ev.button.button, button);
    assert_int_equal(ev.button.down, down);
    assert_int_equal(ev.button.mask, mask);
    assert_true(ev.header.time_ns > 0 && ev.header.time_ns <= fp_test_mono_ns());
}

static void expect_quiet(fixture *f, int ms)
{
    fp_event ev;
    if (fp_test_host_next(&f->rec, &ev, ms)) {
        fprintf(stderr, "unexpected event type %u\n", ev.header.type);
        fail();
    }
}

static void send(fixture *f, const uint8_t *bytes, size_t len)
{
    emu_send(f->emu, bytes, len);
}

#define VEC(f, lo) send((f), (const uint8_t[]){(lo), 0x00}, 2)
#define KBD(f, ...) send((f), (const uint8_t[9]){0x01, 0x00, 0x00, __VA_ARGS__}, 9)

/* Wait until the emulator has a URB in flight again (the reader resubmitted). */
static void wait_flying(fixture *f)
{
    for (int i = 0; i < 300; i++) {
        if (emu_get_stats(f->emu).flying > 0)
            return;
        struct timespec ts = {0, 10000000};
        nanosleep(&ts, NULL);
    }
    fail_msg("no URB in flight after 3 s");
}

/* ----------------------------------------------------------------------------------- */
/* Tests                                                                               */

static void test_vec_press_release_chords(void **state)
{
    fixture *f = *state;
    assert_int_equal(emu_plug(f->emu, EMU_VEC, 5), 0);
    assert_int_equal(start_plugin(f, NULL, NULL, 0), 0);
    expect_status(f, FP_STATUS_CONNECTED, "05f3:00ff at bus 001 address 005");
    wait_flying(f);

    emu_stats s = emu_get_stats(f->emu);
    assert_int_equal(s.detaches, 1);                   /* the kernel driver (usbhid) detached */
    assert_int_equal(s.disconnect_claims, 0);
    assert_int_equal(s.claimed_interface, 0);
    assert_int_equal(s.last_endpoint, 0x81);
    assert_int_equal(s.bad_submits, 0);

    VEC(f, 0x01);
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    VEC(f, 0x00);
    expect_button(f, FP_BUTTON_LEFT, 0, 0);
    VEC(f, 0x02);
    expect_button(f, FP_BUTTON_MIDDLE, 1, FP_BUTTON_MIDDLE);
    VEC(f, 0x00);
    expect_button(f, FP_BUTTON_MIDDLE, 0, 0);
    VEC(f, 0x04);
    expect_button(f, FP_BUTTON_RIGHT, 1, FP_BUTTON_RIGHT);
    VEC(f, 0x00);
    expect_button(f, FP_BUTTON_RIGHT, 0, 0);

    /* Chord: left, then middle while left stays down; the same report again is no change. */
    VEC(f, 0x01);
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    VEC(f, 0x03);
    expect_button(f, FP_BUTTON_MIDDLE, 1, FP_BUTTON_LEFT | FP_BUTTON_MIDDLE);
    VEC(f, 0x03);
    /* Two pedals at once from nothing, after releasing both in one report. */
    VEC(f, 0x00);
    expect_button(f, FP_BUTTON_LEFT, 0, FP_BUTTON_MIDDLE);
    expect_button(f, FP_BUTTON_MIDDLE, 0, 0);
    VEC(f, 0x05);
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    expect_button(f, FP_BUTTON_RIGHT, 1, FP_BUTTON_LEFT | FP_BUTTON_RIGHT);
    send(f, (const uint8_t[]){0x00, 0x00}, 2);
    expect_button(f, FP_BUTTON_LEFT, 0, FP_BUTTON_RIGHT);
    expect_button(f, FP_BUTTON_RIGHT, 0, 0);
    expect_quiet(f, 200);
    assert_int_equal(bad_headers(&f->rec), 0);

    /* Stop: the transfer is cancelled (discarded), the interface released and the kernel
     * driver given back. */
    f->input->stop(f->input);
    s = emu_get_stats(f->emu);
    assert_int_equal(s.flying, 0);
    assert_true(s.discards >= 1);
    assert_int_equal(s.releases, 1);
    assert_int_equal(s.reattaches, 1);
    assert_int_equal(s.delivered, 12);
}

/* An emulator built from docs/devices.md's in-process recipe answers only SUBMITURB,
 * REAPURB(NDELAY), DISCARDURB and CLAIMINTERFACE (ENOTTY for the rest): the pedal is still
 * claimed and read. (libusb's auto-detach asked for DISCONNECT_CLAIM, then GETDRIVER and
 * USBDEVFS_IOCTL(DISCONNECT), and failed the claim with LIBUSB_ERROR_OTHER on the ENOTTY.) */
static void test_spec_minimal_emulator(void **state)
{
    fixture *f = *state;
    emu_set_minimal(f->emu, 1);
    assert_int_equal(emu_plug(f->emu, EMU_VEC, 5), 0);
    assert_int_equal(start_plugin(f, NULL, NULL, 0), 0);
    expect_status(f, FP_STATUS_CONNECTED, "05f3:00ff at bus 001 address 005");
    wait_flying(f);
    VEC(f, 0x01);
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    VEC(f, 0x00);
    expect_button(f, FP_BUTTON_LEFT, 0, 0);
    f->input->stop(f->input);
    emu_stats s = emu_get_stats(f->emu);
    assert_int_equal(s.claimed_interface, 0);
    assert_int_equal(s.disconnect_claims + s.detaches + s.reattaches, 0); /* none answered */
    assert_int_equal(s.delivered, 2);
}

static void test_pcsensor_default_keys(void **state)
{
    fixture *f = *state;
    assert_int_equal(emu_plug(f->emu, EMU_PCSENSOR, 7), 0);
    assert_int_equal(start_plugin(f, NULL, NULL, 0), 0);
    expect_status(f, FP_STATUS_CONNECTED, "0c45:7403");
    wait_flying(f);
    emu_stats s = emu_get_stats(f->emu);
    assert_int_equal(s.claimed_interface, 1);   /* the boot keyboard, not the vendor one */
    assert_int_equal(s.last_endpoint, 0x81);

    KBD(f, 0x05, 0, 0, 0, 0, 0);                   /* b: middle */
    expect_button(f, FP_BUTTON_MIDDLE, 1, FP_BUTTON_MIDDLE);
    KBD(f, 0, 0, 0, 0, 0, 0);
    expect_button(f, FP_BUTTON_MIDDLE, 0, 0);
    KBD(f, 0x04, 0, 0, 0, 0, 0);                   /* a: left */
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    KBD(f, 0x04, 0x06, 0, 0, 0, 0);                /* a + c: chord */
    expect_button(f, FP_BUTTON_RIGHT, 1, FP_BUTTON_LEFT | FP_BUTTON_RIGHT);
    KBD(f, 0x06, 0x04, 0, 0, 0, 0);                /* same keys, other slots: no change */
    KBD(f, 0x06, 0, 0, 0, 0, 0);
    expect_button(f, FP_BUTTON_LEFT, 0, FP_BUTTON_RIGHT);
    KBD(f, 0x07, 0, 0, 0, 0, 0);                   /* d: unbound, so c is released */
    expect_button(f, FP_BUTTON_RIGHT, 0, 0);
    send(f, (const uint8_t[]){0x02, 0x01, 0x00, 0x00}, 4);   /* a mouse report: ignored */
    KBD(f, 0, 0, 0, 0, 0, 0);
    expect_quiet(f, 200);
    assert_int_equal(bad_headers(&f->rec), 0);
}

static void test_pcsensor_single_key(void **state)
{
    fixture *f = *state;
    assert_int_equal(emu_plug(f->emu, EMU_PCSENSOR, 8), 0);
    /* keys=b as the host passes it; 0c45:7403 given explicitly. */
    const fp_param p[] = {{"keys", "b"}};
    assert_int_equal(start_plugin(f, "0c45:7403", p, 1), 0);
    expect_status(f, FP_STATUS_CONNECTED, "bus 001 address 008");
    KBD(f, 0x05, 0, 0, 0, 0, 0);
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    KBD(f, 0, 0, 0, 0, 0, 0);
    expect_button(f, FP_BUTTON_LEFT, 0, 0);
    KBD(f, 0x04, 0, 0, 0, 0, 0);                   /* a is not bound now */
    expect_quiet(f, 200);
}

/* The audit's unit: the boot keyboard's EP 0x81 moves 8 bytes a packet, so a 9-byte report
 * with id 1 is two packets. Read 8 bytes at a time it came as 8 + 1, and the 8 were decoded
 * as a boot report whose modifier byte was the id 0x01 (left Ctrl): keys=ctrl/b/c gave a
 * spurious left with every key, keys=ctrl/-/- a left held for good. */
static void test_split_report_not_boot(void **state)
{
    fixture *f = *state;
    assert_int_equal(emu_plug(f->emu, EMU_PCSENSOR_MP8, 5), 0);
    const fp_param p[] = {{"keys", "ctrl/b/c"}};
    assert_int_equal(start_plugin(f, NULL, p, 1), 0);
    expect_status(f, FP_STATUS_CONNECTED, "0c45:7403");
    wait_flying(f);
    emu_stats s = emu_get_stats(f->emu);
    assert_int_equal(s.claimed_interface, 0);
    assert_int_equal(s.last_endpoint, 0x81);
    KBD(f, 0x05, 0, 0, 0, 0, 0);                   /* b: middle, and nothing else */
    expect_button(f, FP_BUTTON_MIDDLE, 1, FP_BUTTON_MIDDLE);
    KBD(f, 0, 0, 0, 0, 0, 0);
    expect_button(f, FP_BUTTON_MIDDLE, 0, 0);
    send(f, (const uint8_t[9]){0x01, 0x01, 0x00, 0, 0, 0, 0, 0, 0}, 9);   /* ctrl: left */
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    KBD(f, 0x06, 0, 0, 0, 0, 0);                   /* c alone: left up, right down */
    expect_button(f, FP_BUTTON_LEFT, 0, 0);
    expect_button(f, FP_BUTTON_RIGHT, 1, FP_BUTTON_RIGHT);
    KBD(f, 0, 0, 0, 0, 0, 0);
    expect_button(f, FP_BUTTON_RIGHT, 0, 0);
    expect_quiet(f, 300);
    s = emu_get_stats(f->emu);
    assert_int_equal(s.delivered, 5);
    assert_int_equal(s.split_transfers, 0);   /* the read takes a whole report */
    assert_int_equal(s.bad_submits, 0);
}

/* The same unit under an emulator that cannot answer the report descriptor request (the
 * in-process recipe): the format comes from the known model (id 1), and a read cut at 8
 * bytes is put back together, never decoded as a boot report. keys=ctrl/-/-: a b press
 * must not hold left. */
static void test_split_report_minimal_emulator(void **state)
{
    fixture *f = *state;
    emu_set_minimal(f->emu, 1);
    assert_int_equal(emu_plug(f->emu, EMU_PCSENSOR_MP8, 5), 0);
    const fp_param p[] = {{"keys", "ctrl/-/-"}};
    assert_int_equal(start_plugin(f, NULL, p, 1), 0);
    expect_status(f, FP_STATUS_CONNECTED, "0c45:7403");
    wait_flying(f);
    KBD(f, 0x05, 0, 0, 0, 0, 0);                   /* b: unbound */
    KBD(f, 0, 0, 0, 0, 0, 0);
    expect_quiet(f, 400);
    send(f, (const uint8_t[9]){0x01, 0x01, 0x00, 0, 0, 0, 0, 0, 0}, 9);
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    KBD(f, 0, 0, 0, 0, 0, 0);
    expect_button(f, FP_BUTTON_LEFT, 0, 0);
    expect_quiet(f, 200);
}

/* A keyboard pedal whose report descriptor has no report id sends 8-byte boot reports:
 * byte 0 is the modifier byte there. */
static void test_boot_reports_by_descriptor(void **state)
{
    fixture *f = *state;
    assert_int_equal(emu_plug(f->emu, EMU_BOOT_NOID, 5), 0);
    const fp_param p[] = {{"keys", "ctrl/b/c"}};
    assert_int_equal(start_plugin(f, NULL, p, 1), 0);
    expect_status(f, FP_STATUS_CONNECTED, "0c45:7404");
    wait_flying(f);
    send(f, (const uint8_t[8]){0x01, 0x00, 0x06, 0, 0, 0, 0, 0}, 8);   /* ctrl + c */
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    expect_button(f, FP_BUTTON_RIGHT, 1, FP_BUTTON_LEFT | FP_BUTTON_RIGHT);
    send(f, (const uint8_t[8]){0x00, 0x00, 0, 0, 0, 0, 0, 0}, 8);
    expect_button(f, FP_BUTTON_LEFT, 0, FP_BUTTON_RIGHT);
    expect_button(f, FP_BUTTON_RIGHT, 0, 0);
    assert_true(emu_get_stats(f->emu).report_descriptor_reads >= 1);
}

/* Defect 3: the configuration interface (a HID interface with a vendor report descriptor)
 * comes first and the keyboard interface is not a boot interface: the keyboard is read. */
static void test_keyboard_interface_not_first(void **state)
{
    fixture *f = *state;
    assert_int_equal(emu_plug(f->emu, EMU_CONFIG_FIRST, 5), 0);
    assert_int_equal(start_plugin(f, NULL, NULL, 0), 0);
    expect_status(f, FP_STATUS_CONNECTED, "3553:b001");
    wait_flying(f);
    emu_stats s = emu_get_stats(f->emu);
    assert_int_equal(s.claimed_interface, 1);
    assert_int_equal(s.last_endpoint, 0x81);
    assert_int_equal(s.bad_submits, 0);
    KBD(f, 0x04, 0, 0, 0, 0, 0);
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    KBD(f, 0, 0, 0, 0, 0, 0);
    expect_button(f, FP_BUTTON_LEFT, 0, 0);
    /* stop gives both interfaces back to the kernel driver */
    f->input->stop(f->input);
    s = emu_get_stats(f->emu);
    assert_int_equal(s.detaches, s.reattaches);
}

static void test_read_timeout_no_spurious_events(void **state)
{
    fixture *f = *state;
    assert_int_equal(emu_plug(f->emu, EMU_VEC, 5), 0);
    assert_int_equal(start_plugin(f, NULL, NULL, 0), 0);
    expect_status(f, FP_STATUS_CONNECTED, NULL);
    VEC(f, 0x02);
    expect_button(f, FP_BUTTON_MIDDLE, 1, FP_BUTTON_MIDDLE);
    /* Nothing for 2.5 s: the 1 s read timeout fires (the URB is discarded and submitted
     * again) at least twice, and no event comes out of it. */
    expect_quiet(f, 2500);
    emu_stats s = emu_get_stats(f->emu);
    assert_true(s.discards >= 2);
    assert_true(s.submits >= 3);
    /* Still alive: the held middle pedal is released by the next report. */
    VEC(f, 0x00);
    expect_button(f, FP_BUTTON_MIDDLE, 0, 0);
    VEC(f, 0x04);
    expect_button(f, FP_BUTTON_RIGHT, 1, FP_BUTTON_RIGHT);
}

static void test_unplug_and_return(void **state)
{
    fixture *f = *state;
    assert_int_equal(emu_plug(f->emu, EMU_VEC, 5), 0);
    assert_int_equal(start_plugin(f, NULL, NULL, 0), 0);
    expect_status(f, FP_STATUS_CONNECTED, "address 005");
    VEC(f, 0x01);
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    VEC(f, 0x05);
    expect_button(f, FP_BUTTON_RIGHT, 1, FP_BUTTON_LEFT | FP_BUTTON_RIGHT);
    wait_flying(f);

    /* Pulled with two pedals held: both are released, then the disconnect is reported. */
    emu_unplug(f->emu);
    expect_button(f, FP_BUTTON_LEFT, 0, FP_BUTTON_RIGHT);
    expect_button(f, FP_BUTTON_RIGHT, 0, 0);
    /* said as an unplug, the model named once (before: "pedal 05f3:00ff ... left", read
     * "pedal: pedal ... left" on stage, "left" taken for the left pedal) */
    expect_status(f, FP_STATUS_DISCONNECTED,
                  "VEC Infinity IN-USB-2 05f3:00ff at bus 001 address 005 unplugged; looking every 500 ms");
    expect_quiet(f, 800);   /* looking, not finding, not repeating itself */

    /* Back at a new address, as the kernel numbers it. */
    assert_int_equal(emu_plug(f->emu, EMU_VEC, 6), 0);
    expect_status(f, FP_STATUS_CONNECTED, "address 006");
    VEC(f, 0x02);
    expect_button(f, FP_BUTTON_MIDDLE, 1, FP_BUTTON_MIDDLE);
    VEC(f, 0x00);
    expect_button(f, FP_BUTTON_MIDDLE, 0, 0);
    assert_int_equal(bad_headers(&f->rec), 0);
}

/* Defect 2: after the unplug every ioctl fails with ENODEV and the read in flight is never
 * completed (no -ESHUTDOWN reap). The pedal must still be seen to leave (held pedal
 * released, DISCONNECTED), come back when replugged, and stop must not wait for the read. */
static void test_unplug_silent(void **state)
{
    fixture *f = *state;
    emu_set_unplug_silent(f->emu, 1);
    assert_int_equal(emu_plug(f->emu, EMU_VEC, 5), 0);
    assert_int_equal(start_plugin(f, NULL, NULL, 0), 0);
    expect_status(f, FP_STATUS_CONNECTED, "address 005");
    VEC(f, 0x01);
    expect_button(f, FP_BUTTON_LEFT, 1, FP_BUTTON_LEFT);
    wait_flying(f);
    int64_t t0 = fp_test_mono_ns();
    emu_unplug(f->emu);
    expect_button(f, FP_BUTTON_LEFT, 0, 0);
    expect_status(f, FP_STATUS_DISCONNECTED, "05f3:00ff");
    assert_true(fp_test_mono_ns() - t0 < 2500000000LL);
    assert_int_equal(emu_plug(f->emu, EMU_VEC, 6), 0);
    expect_status(f, FP_STATUS_CONNECTED, "address 006");
    VEC(f, 0x02);
    expect_button(f, FP_BUTTON_MIDDLE, 1, FP_BUTTON_MIDDLE);
    emu_unplug(f->emu);   /* gone again, silently, with middle held; then stop at once */
    t0 = fp_test_mono_ns();
    f->input->stop(f->input);
    assert_true(fp_test_mono_ns() - t0 < 1000000000LL);
}

/* The pedal dies in place (every ioctl ENODEV, the read never completes) and stays listed:
 * no hotplug event tells; the read that outlives its timeout does. */
static void test_dead_in_place(void **state)
{
    fixture *f = *state;
    assert_int_equal(emu_plug(f->emu, EMU_VEC, 5), 0);
    assert_int_equal(start_plugin(f, NULL, NULL, 0), 0);
    expect_status(f, FP_STATUS_CONNECTED, "address 005");
    VEC(f, 0x04);
    expect_button(f, FP_BUTTON_RIGHT, 1, FP_BUTTON_RIGHT);
    wait_flying(f);
    emu_kill(f->emu);
    expect_button(f, FP_BUTTON_RIGHT, 0, 0);
    expect_status(f, FP_STATUS_DISCONNECTED, "05f3:00ff");
    int64_t t0 = fp_test_mono_ns();
    f->input->stop(f->input);
    assert_true(fp_test_mono_ns() - t0 < 1000000000LL);
}

static void test_absent_at_start_then_plugged(void **state)
{
    fixture *f = *state;
    assert_int_equal(start_plugin(f, NULL, NULL, 0), 0);   /* not an error */
    expect_status(f, FP_STATUS_RECONNECTING, "no USB foot pedal found");
    expect_quiet(f, 700);
    assert_int_equal(emu_plug(f->emu, EMU_PCSENSOR, 9), 0);
    expect_status(f, FP_STATUS_CONNECTED, "0c45:7403");
    KBD(f, 0x06, 0, 0, 0, 0, 0);
    expect_button(f, FP_BUTTON_RIGHT, 1, FP_BUTTON_RIGHT);
}

static void test_strict_without_pedal_fails(void **state)
{
    fixture *f = *state;
    const fp_param p[] = {{"strict", "1"}};
    char err[256] = "";
    assert_int_equal(f->factory->create(&f->rec.host, NULL, p, 1, &f->input, err, sizeof err),
                     0);
    assert_int_equal(f->input->start(f->input, err, sizeof err), -ENODEV);
    assert_non_null(strstr(err, "no known USB foot pedal"));
    assert_int_equal((int)fp_test_host_unread(&f->rec), 0);
    /* With the pedal there, strict starts and is connected before start returns. */
    f->input->destroy(f->input);
    f->input = NULL;
    assert_int_equal(emu_plug(f->emu, EMU_VEC, 5), 0);
    assert_int_equal(start_plugin(f, "05f3:00ff", p, 1), 0);
    assert_true((int)fp_test_host_unread(&f->rec) >= 1);
    expect_status(f, FP_STATUS_CONNECTED, NULL);
}

static void test_other_device_not_taken(void **state)
{
    fixture *f = *state;
    /* Only 05f3:00ff asked for; a PCsensor pedal on the bus is left alone. */
    assert_int_equal(emu_plug(f->emu, EMU_PCSENSOR, 4), 0);
    assert_int_equal(start_plugin(f, "05f3:00ff", NULL, 0), 0);
    expect_status(f, FP_STATUS_RECONNECTING, NULL);
    expect_quiet(f, 700);
    assert_int_equal(emu_get_stats(f->emu).disconnect_claims + emu_get_stats(f->emu).detaches, 0);
}

static void test_create_errors(void **state)
{
    fixture *f = *state;
    char err[256];
    fp_input *in = NULL;
    const fp_param bad_key[] = {{"keys", "a/zz"}};
    assert_int_equal(f->factory->create(&f->rec.host, NULL, bad_key, 1, &in, err, sizeof err),
                     -EINVAL);
    assert_null(in);
    assert_non_null(strstr(err, "zz"));
    const fp_param unknown[] = {{"speed", "3"}};
    assert_int_equal(f->factory->create(&f->rec.host, NULL, unknown, 1, &in, err, sizeof err),
                     -EINVAL);
    assert_non_null(strstr(err, "speed"));
    assert_int_equal(f->factory->create(&f->rec.host, "1234:5678", NULL, 0, &in, err, sizeof err),
                     -EINVAL);
    assert_non_null(strstr(err, "layout"));
    assert_int_equal(f->factory->create(&f->rec.host, "nonsense", NULL, 0, &in, err, sizeof err),
                     -EINVAL);
    assert_non_null(strstr(err, "nonsense"));
    /* stop and destroy without start are fine */
    assert_int_equal(f->factory->create(&f->rec.host, NULL, NULL, 0, &in, err, sizeof err), 0);
    in->stop(in);
    in->destroy(in);
    assert_string_equal(f->factory->name, "pedal");
}

/* Drop (or restore) CAP_DAC_OVERRIDE and CAP_DAC_READ_SEARCH from this thread's effective
 * set, keeping them permitted; threads created afterwards (the plugin's) inherit it. */
static int set_dac_override(bool on)
{
    struct __user_cap_header_struct h = {_LINUX_CAPABILITY_VERSION_3, 0};
    struct __user_cap_data_struct d[2];
    if (syscall(SYS_capget, &h, d))
        return -1;
    uint32_t bits = (1u << CAP_DAC_OVERRIDE) | (1u << CAP_DAC_READ_SEARCH);
    if (on)
        d[0].effective |= bits & d[0].permitted;
    else
        d[0].effective &= ~bits;
    return (int)syscall(SYS_capset, &h, d);
}

static void test_permission_error_names_device(void **state)
{
    fixture *f = *state;
    if (getuid() == 0 && set_dac_override(false) != 0)
        skip();
    assert_int_equal(emu_plug(f->emu, EMU_VEC, 5), 0);
    assert_int_equal(emu_deny_access(f->emu), 0);
    int r = start_plugin(f, NULL, NULL, 0);
    set_dac_override(true);
    assert_int_equal(r, 0);   /* not strict: report and keep looking */
    expect_status(f, FP_STATUS_ERROR, "05f3:00ff at bus 001 address 005");
    fp_event ev = f->rec.events[f->rec.read - 1];
    assert_non_null(strstr(ev.status.text, "70-facepuppet-pedal.rules"));
    /* Named once, not at every scan (500 ms); no other event, nothing claimed. */
    expect_quiet(f, 1200);
    assert_int_equal(emu_get_stats(f->emu).disconnect_claims + emu_get_stats(f->emu).detaches, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_vec_press_release_chords, setup, teardown),
        cmocka_unit_test_setup_teardown(test_spec_minimal_emulator, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pcsensor_default_keys, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pcsensor_single_key, setup, teardown),
        cmocka_unit_test_setup_teardown(test_split_report_not_boot, setup, teardown),
        cmocka_unit_test_setup_teardown(test_split_report_minimal_emulator, setup, teardown),
        cmocka_unit_test_setup_teardown(test_boot_reports_by_descriptor, setup, teardown),
        cmocka_unit_test_setup_teardown(test_keyboard_interface_not_first, setup, teardown),
        cmocka_unit_test_setup_teardown(test_read_timeout_no_spurious_events, setup, teardown),
        cmocka_unit_test_setup_teardown(test_unplug_and_return, setup, teardown),
        cmocka_unit_test_setup_teardown(test_unplug_silent, setup, teardown),
        cmocka_unit_test_setup_teardown(test_dead_in_place, setup, teardown),
        cmocka_unit_test_setup_teardown(test_absent_at_start_then_plugged, setup, teardown),
        cmocka_unit_test_setup_teardown(test_strict_without_pedal_fails, setup, teardown),
        cmocka_unit_test_setup_teardown(test_other_device_not_taken, setup, teardown),
        cmocka_unit_test_setup_teardown(test_create_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(test_permission_error_names_device, setup, teardown),
    };
    return cmocka_run_group_tests_name("pedal_usb", tests, NULL, NULL);
}
