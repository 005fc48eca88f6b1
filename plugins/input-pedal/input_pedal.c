/*
 * input_pedal.c: USB foot pedals through libusb (SPEC name "pedal").
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * One instance owns one libusb context and one thread ([input-thread]). The thread looks
 * for a pedal every 500 ms while none is open (libusb_get_device_list; a hotplug arrival,
 * where libusb offers hotplug, only makes it look sooner), opens it, detaches the kernel
 * driver from the interface it reads and claims it, and keeps one asynchronous interrupt
 * transfer of up to 64 bytes (whole packets) in flight, serviced by
 * libusb_handle_events_timeout_completed.
 *
 * The interface: for a keyboard pedal, the interfaces with an interrupt IN endpoint are
 * tried in the order boot keyboard, other HID, other class, vendor class; the first whose
 * HID report descriptor (GET_DESCRIPTOR 0x22) has a keyboard collection is read, or the
 * first whose descriptor cannot be read; when every descriptor says "not a keyboard" (a
 * configuration interface, say), the first in that order. A VEC pedal: the first HID
 * interface with an interrupt IN endpoint.
 *
 * The keyboard report's framing comes from that report descriptor: report ids declared ->
 * `id mods 00 k1..k6` with the keyboard collection's id; none -> the 8-byte `mods 00 k1..k6`.
 * Without a descriptor (an emulator that cannot answer control transfers), a known pedal's
 * documented framing (id 1, shared/docs/devices.md), else by length. A read that fills its
 * buffer with less than a whole report (a 9-byte report read 8 bytes at a time) is kept and
 * completed by the next read; a part is never decoded on its own.
 *
 * Leaving: a transfer that ends with LIBUSB_TRANSFER_NO_DEVICE, a hotplug DEVICE_LEFT for
 * the open device, the device missing from the list at a scan-period check, a cancel that
 * answers LIBUSB_ERROR_NO_DEVICE, or a read still in flight STUCK_MS after its own timeout
 * (its cancellation never completed: the node fails every request) close the pedal: held
 * buttons are released (button up events), FP_STATUS_DISCONNECTED is pushed, and the search
 * starts again. A read that will never complete is not waited for.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdarg.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <libusb.h>

#include "facepuppet/plugin.h"
#include "pedal_decode.h"

#define SCAN_PERIOD_MS 500
#define TRANSFER_TIMEOUT_MS 1000   /* a silent pedal: the transfer is resubmitted */
#define LOOP_TIMEOUT_MS 100        /* how often the thread checks `stopping` at worst */
#define CANCEL_WAIT_MS 2000        /* the most we wait for a cancelled transfer's callback */
#define CANCEL_SETTLE_MS 250       /* ... for one whose cancellation was already under way */
#define STUCK_MS 500               /* a read this long past its timeout is taken as dead */
#define MAX_ERRORS 5               /* consecutive failed transfers before we reopen */
#define REPORT_MAX 64
#define MAX_CANDIDATES 8           /* interfaces with an interrupt IN endpoint looked at */
#define RDESC_MAX 1024             /* the longest HID report descriptor read */

typedef struct pedal {
    fp_input input;
    const fp_host *host;
    fp_pedal_config cfg;
    fp_pedal_keymap keys;

    libusb_context *ctx;             /* NULL until libusb_init succeeds (thread retries) */
    atomic_bool ctx_ready;           /* ctx is set: stop may interrupt its event handler */
    pthread_t thread;
    bool thread_started;
    atomic_bool stopping;
    bool hotplug_registered;
    libusb_hotplug_callback_handle hotplug;
    bool rescan;                     /* a hotplug arrival asked for a scan now */

    /* The open pedal; only the thread touches these once started. */
    libusb_device_handle *handle;
    int iface;
    bool detached;                   /* we took the interface from a kernel driver: give it back */
    uint8_t endpoint;
    fp_pedal_layout layout;
    fp_pedal_kbd_format kbd_format;  /* keyboard layout: how reports are framed */
    uint8_t kbd_id;                  /* FP_PEDAL_KBD_ID: the keyboard report's id */
    uint16_t vid, pid;
    int bus, address;
    struct libusb_transfer *transfer;
    bool in_flight;
    bool gone;                       /* the device left: close and look again */
    bool watchdog;                   /* the thread cancelled a read stuck past its timeout */
    bool stuck;                      /* the read will not complete: close without waiting */
    int64_t submitted_ns;            /* when the read in flight was submitted */
    int errors;
    uint32_t mask;
    uint8_t buffer[REPORT_MAX];
    uint8_t pending[REPORT_MAX];     /* the first part of a report cut at the buffer's end */
    size_t npending;

    int announced;                   /* 0 nothing yet, 1 "looking", 2 connected */
    char access_reported[32];        /* "bus/address" last named in a permission error */
} pedal;

/* ----------------------------------------------------------------------------------- */

static void host_log(pedal *p, fp_log_level level, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void host_log(pedal *p, fp_log_level level, const char *fmt, ...)
{
    if (!p->host || !p->host->log)
        return;
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    p->host->log(p->host, level, msg);
}

static int64_t now_ns(pedal *p)
{
    if (p->host && p->host->now_ns)
        return p->host->now_ns(p->host);
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void push_status(pedal *p, fp_status_code code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void push_status(pedal *p, fp_status_code code, const char *fmt, ...)
{
    fp_event_status ev;
    memset(&ev, 0, sizeof ev);
    ev.header.size = sizeof ev;
    ev.header.type = FP_EVENT_STATUS;
    ev.header.time_ns = now_ns(p);
    ev.header.hand = -1;
    ev.code = (uint32_t)code;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(ev.text, sizeof ev.text, fmt, ap);
    va_end(ap);
    if (p->host && p->host->push_event)
        p->host->push_event(p->host, &ev.header);
    fp_log_level level = code == FP_STATUS_ERROR ? FP_LOG_ERROR
                         : code == FP_STATUS_WARNING ? FP_LOG_WARNING : FP_LOG_INFO;
    host_log(p, level, "%s", ev.text);
}

static void push_changes(pedal *p, const fp_pedal_change *ch, int n, int64_t t)
{
    for (int i = 0; i < n; i++) {
        fp_event_button ev;
        memset(&ev, 0, sizeof ev);
        ev.header.size = sizeof ev;
        ev.header.type = FP_EVENT_BUTTON;
        ev.header.time_ns = t;
        ev.header.hand = -1;
        ev.button = ch[i].button;
        ev.down = ch[i].down;
        ev.mask = ch[i].mask;
        if (p->host && p->host->push_event)
            p->host->push_event(p->host, &ev.header);
    }
}

/* ----------------------------------------------------------------------------------- */
/* The transfer                                                                        */

/* Decode one completed read. A read that filled its buffer with the first part of a
 * keyboard report (shorter than the framing's whole report) is kept in `pending` until the
 * next read completes it. */
static void handle_report(pedal *p, struct libusb_transfer *t)
{
    const uint8_t *data = t->buffer;
    size_t len = (size_t)t->actual_length;
    bool keyboard = p->layout == FP_PEDAL_LAYOUT_KEYBOARD;
    size_t whole = keyboard ? fp_pedal_kbd_report_size(p->kbd_format) : 0;
    bool full = t->actual_length == t->length;   /* the report may go on in the next read */
    if (p->npending > 0 ||
        (full && len > 0 && len < whole &&
         (p->kbd_format != FP_PEDAL_KBD_ID || data[0] == p->kbd_id))) {
        size_t room = sizeof p->pending - p->npending, n = len < room ? len : room;
        memcpy(p->pending + p->npending, data, n);
        p->npending += n;
        if (full && p->npending < whole)
            return;                                /* wait for the rest */
        data = p->pending;
        len = p->npending;
        p->npending = 0;
    }
    uint32_t mask;
    fp_pedal_change ch[3];
    int n = keyboard ? fp_pedal_decode_keyboard(p->kbd_format, p->kbd_id, &p->keys, data, len,
                                                p->mask, &mask, ch)
                     : fp_pedal_decode(p->layout, &p->keys, data, len, p->mask, &mask, ch);
    if (n < 0) {
        host_log(p, FP_LOG_DEBUG, "ignored a %zu-byte report (%s layout)", len,
                 fp_pedal_layout_name(p->layout));
    } else {
        p->mask = mask;
        push_changes(p, ch, n, now_ns(p));
    }
}

static void LIBUSB_CALL transfer_cb(struct libusb_transfer *t)
{
    pedal *p = t->user_data;
    p->in_flight = false;
    switch (t->status) {
    case LIBUSB_TRANSFER_COMPLETED:
        p->errors = 0;
        handle_report(p, t);
        break;
    case LIBUSB_TRANSFER_TIMED_OUT:   /* the pedal had nothing to say: ask again */
        p->npending = 0;
        break;
    case LIBUSB_TRANSFER_CANCELLED:
        if (!p->watchdog)
            return;                   /* stop or close asked for it */
        p->watchdog = false;          /* the thread's watchdog did: the read went on, ask again */
        p->npending = 0;
        break;
    case LIBUSB_TRANSFER_NO_DEVICE:
        p->gone = true;
        return;
    case LIBUSB_TRANSFER_STALL:
        libusb_clear_halt(p->handle, p->endpoint);
        /* fall through */
    default:
        p->npending = 0;
        if (++p->errors >= MAX_ERRORS) {
            host_log(p, FP_LOG_WARNING, "%d failed reads in a row (%s): reopening the pedal",
                     p->errors, libusb_error_name(t->status));
            p->gone = true;
            return;
        }
        break;
    }
    if (atomic_load(&p->stopping) || p->gone)
        return;
    int r = libusb_submit_transfer(t);
    if (r == 0) {
        p->in_flight = true;
        p->submitted_ns = now_ns(p);
    } else {
        if (r != LIBUSB_ERROR_NO_DEVICE)
            host_log(p, FP_LOG_WARNING, "resubmitting the read failed: %s", libusb_strerror(r));
        p->gone = true;
    }
}

/* ----------------------------------------------------------------------------------- */
/* Opening and closing a pedal                                                         */

/* An interface with an interrupt IN endpoint: a place the pedal's reports may come from. */
typedef struct candidate {
    int iface;
    uint8_t ep;
    int maxpacket;
    int score;           /* the order they are tried in, highest first */
    uint16_t rdesc_len;  /* the report descriptor's length from the HID descriptor, 0 unknown */
} candidate;

/* The report descriptor's length from the HID class descriptor (0x21) among an
 * interface's extra descriptors; 0 when there is none. */
static uint16_t hid_rdesc_len(const unsigned char *x, int len)
{
    for (int i = 0; i + 2 <= len && x[i] >= 2; i += x[i]) {
        if (x[i + 1] == 0x21 && x[i] >= 9 && i + 9 <= len && x[i + 6] == 0x22)
            return (uint16_t)(x[i + 7] | x[i + 8] << 8);
    }
    return 0;
}

/* The interfaces of the active (else the first) configuration that have an interrupt IN
 * endpoint, best first: for a keyboard pedal a boot keyboard (HID 1/1) 3, another HID
 * interface 2, another class 1, a vendor-class interface 0; for a VEC pedal HID 2, other 1,
 * vendor 0. Equal scores keep the interfaces' order. Returns how many (0..max). */
static int list_candidates(libusb_device *dev, fp_pedal_layout layout, candidate *c, int max)
{
    struct libusb_config_descriptor *cd = NULL;
    if (libusb_get_active_config_descriptor(dev, &cd) != 0 &&
        libusb_get_config_descriptor(dev, 0, &cd) != 0)
        return 0;
    int n = 0;
    for (int i = 0; i < cd->bNumInterfaces && n < max; i++) {
        if (cd->interface[i].num_altsetting < 1)
            continue;
        const struct libusb_interface_descriptor *id = &cd->interface[i].altsetting[0];
        for (int e = 0; e < id->bNumEndpoints; e++) {
            const struct libusb_endpoint_descriptor *ed = &id->endpoint[e];
            if ((ed->bEndpointAddress & LIBUSB_ENDPOINT_DIR_MASK) != LIBUSB_ENDPOINT_IN ||
                (ed->bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_INTERRUPT)
                continue;
            bool hid = id->bInterfaceClass == LIBUSB_CLASS_HID;
            int score = id->bInterfaceClass == LIBUSB_CLASS_VENDOR_SPEC ? 0 : hid ? 2 : 1;
            if (layout == FP_PEDAL_LAYOUT_KEYBOARD && hid && id->bInterfaceSubClass == 1 &&
                id->bInterfaceProtocol == 1)
                score = 3;
            candidate k = {id->bInterfaceNumber, ed->bEndpointAddress, ed->wMaxPacketSize, score,
                           hid ? hid_rdesc_len(id->extra, id->extra_length) : 0};
            int at = n++;
            while (at > 0 && c[at - 1].score < score) {   /* stable: after equal scores */
                c[at] = c[at - 1];
                at--;
            }
            c[at] = k;
            break;
        }
    }
    libusb_free_config_descriptor(cd);
    return n;
}

/* Read and parse interface c's HID report descriptor (the interface must be claimed).
 * Returns 0, or a libusb error (the device cannot answer, or the descriptor is malformed). */
static int read_report_info(libusb_device_handle *h, const candidate *c, fp_pedal_hid_info *info)
{
    uint8_t buf[RDESC_MAX];
    uint16_t len = c->rdesc_len > 0 && c->rdesc_len <= RDESC_MAX ? c->rdesc_len : 256;
    int r = libusb_control_transfer(h, LIBUSB_ENDPOINT_IN | LIBUSB_RECIPIENT_INTERFACE,
                                    LIBUSB_REQUEST_GET_DESCRIPTOR, 0x22 << 8,
                                    (uint16_t)c->iface, buf, len, 500);
    if (r < 0)
        return r;
    return fp_pedal_parse_report_descriptor(buf, (size_t)r, info) == 0 ? 0 : LIBUSB_ERROR_OTHER;
}

/* Cancel the transfer and run the event loop until its callback has run. Not waited for:
 * a read whose cancel says the device is gone (its callback never comes; libusb_close takes
 * it off libusb's lists). A cancellation already under way (libusb's own timeout) is given
 * CANCEL_SETTLE_MS. */
static void cancel_and_wait(pedal *p)
{
    if (!p->in_flight)
        return;
    p->watchdog = false;
    if (p->stuck)
        return;
    int r = libusb_cancel_transfer(p->transfer);
    if (r == LIBUSB_ERROR_NO_DEVICE) {
        p->gone = true;
        return;
    }
    int wait_ms = r == 0 ? CANCEL_WAIT_MS : CANCEL_SETTLE_MS;
    int64_t deadline = now_ns(p) + (int64_t)wait_ms * 1000000;
    while (p->in_flight && now_ns(p) < deadline) {
        struct timeval tv = {0, 50000};
        libusb_handle_events_timeout_completed(p->ctx, &tv, NULL);
    }
    if (p->in_flight)
        host_log(p, FP_LOG_WARNING, "the cancelled read did not complete in %d ms", wait_ms);
}

/* Let go of an opened pedal: the interface released when claimed, the kernel driver given
 * back when we detached it, the handle closed (each fails harmlessly when the device is gone). */
static void release_iface(libusb_device_handle *h, int iface, bool claimed, bool detached)
{
    if (claimed) libusb_release_interface(h, iface);
    if (detached) libusb_attach_kernel_driver(h, iface);
}

static void give_back(libusb_device_handle *h, int iface, bool claimed, bool detached)
{
    release_iface(h, iface, claimed, detached);
    libusb_close(h);
}

/* Close the open pedal. `report`: release held buttons and push DISCONNECTED. */
static void close_pedal(pedal *p, bool report)
{
    if (!p->handle)
        return;
    cancel_and_wait(p);
    give_back(p->handle, p->iface, true, p->detached);
    /* Freed after the close: a read that never completed (the device is gone) is off libusb's
     * in-flight list once its handle is closed, and the closed fd's URBs are the kernel's. */
    libusb_free_transfer(p->transfer);
    p->transfer = NULL;
    p->in_flight = false;
    p->watchdog = false;
    p->stuck = false;
    p->npending = 0;
    p->detached = false;
    p->handle = NULL;
    if (report) {
        fp_pedal_change ch[3];
        int n = fp_pedal_diff(p->mask, 0, ch);
        push_changes(p, ch, n, now_ns(p));
        const fp_pedal_model *m = fp_pedal_find_model(p->vid, p->pid); /* (no "pedal: pedal") */
        push_status(p, FP_STATUS_DISCONNECTED,
                    "%s%s%04x:%04x at bus %03d address %03d unplugged; looking every %d ms",
                    m ? m->name : "", m ? " " : "", p->vid, p->pid, p->bus, p->address,
                    SCAN_PERIOD_MS);
        p->announced = 1;
    }
    p->mask = 0;
    p->gone = false;
}

/* Detach a kernel driver (usbhid) from `iface` and claim it. The driver is detached by hand
 * and given back at close, not through libusb_set_auto_detach_kernel_driver: that claims
 * with USBDEVFS_DISCONNECT_CLAIM, then GETDRIVER and USBDEVFS_IOCTL(DISCONNECT), and fails
 * the claim when the node answers those with ENOTTY, as umockdev's in-process handler of
 * docs/devices.md's recipe does. A driver query that fails is taken as no driver.
 * Returns 0 (*detached: a driver was taken off), or a libusb error (nothing held). */
static int claim_iface(pedal *p, libusb_device_handle *h, int iface, uint16_t vid, uint16_t pid,
                       bool *detached)
{
    *detached = false;
    if (libusb_kernel_driver_active(h, iface) == 1) {
        int d = libusb_detach_kernel_driver(h, iface);
        if (d == 0)
            *detached = true;
        else if (d != LIBUSB_ERROR_NOT_FOUND && d != LIBUSB_ERROR_NOT_SUPPORTED)
            host_log(p, FP_LOG_WARNING, "cannot detach the kernel driver from interface %d of "
                     "%04x:%04x: %s", iface, vid, pid, libusb_strerror(d));
    }
    int r = libusb_claim_interface(h, iface);
    if (r) {
        host_log(p, r == LIBUSB_ERROR_NO_DEVICE ? FP_LOG_DEBUG : FP_LOG_WARNING,
                 "cannot claim interface %d of %04x:%04x: %s%s", iface, vid, pid,
                 libusb_strerror(r),
                 r == LIBUSB_ERROR_BUSY ? " (is another program reading the pedal?)" : "");
        if (*detached)
            libusb_attach_kernel_driver(h, iface);
        *detached = false;
    }
    return r;
}

/* The keyboard report's framing: from the report descriptor when it was read and has a
 * keyboard (`info`, else NULL); else a known pedal's documented id 1; else by length. */
static void set_kbd_format(pedal *p, uint16_t vid, uint16_t pid, const fp_pedal_hid_info *info)
{
    if (info && info->keyboard) {
        p->kbd_format = info->has_ids ? FP_PEDAL_KBD_ID : FP_PEDAL_KBD_BOOT;
        p->kbd_id = info->keyboard_id;
    } else if (fp_pedal_find_model(vid, pid)) {
        p->kbd_format = FP_PEDAL_KBD_ID;
        p->kbd_id = 1;
    } else {
        p->kbd_format = FP_PEDAL_KBD_AUTO;
        p->kbd_id = 1;
    }
}

/* Claim the interface to read (see the file comment for the order) and set the report
 * framing. Returns 0 with *chosen (an index into c) claimed, or a libusb error with nothing
 * held. */
static int choose_interface(pedal *p, libusb_device_handle *h, const candidate *c, int n,
                            fp_pedal_layout layout, uint16_t vid, uint16_t pid, int *chosen,
                            bool *detached)
{
    int first = -1, r = LIBUSB_ERROR_NOT_FOUND;
    for (int i = 0; i < n; i++) {
        r = claim_iface(p, h, c[i].iface, vid, pid, detached);
        if (r == LIBUSB_ERROR_NO_DEVICE)
            return r;
        if (r)
            continue;
        if (layout != FP_PEDAL_LAYOUT_KEYBOARD) {
            *chosen = i;
            return 0;
        }
        fp_pedal_hid_info info;
        int d = read_report_info(h, &c[i], &info);
        if (d != 0 || info.keyboard || n == 1) {
            host_log(p, FP_LOG_DEBUG, "%04x:%04x: reading interface %d (report descriptor: %s)",
                     vid, pid, c[i].iface, d != 0 ? libusb_error_name(d)
                     : info.keyboard ? (info.has_ids ? "keyboard with report ids" : "keyboard")
                                     : "no keyboard");
            set_kbd_format(p, vid, pid, d == 0 ? &info : NULL);
            *chosen = i;
            return 0;
        }
        host_log(p, FP_LOG_DEBUG, "%04x:%04x: interface %d is no keyboard (%s)", vid, pid,
                 c[i].iface, info.vendor ? "vendor page" : "no keyboard collection");
        if (first < 0)
            first = i;
        release_iface(h, c[i].iface, true, *detached);
        *detached = false;
    }
    if (first < 0)
        return r;
    /* No interface says it is a keyboard: the first that could be claimed. */
    r = claim_iface(p, h, c[first].iface, vid, pid, detached);
    if (r == 0) {
        set_kbd_format(p, vid, pid, NULL);
        *chosen = first;
    }
    return r;
}

/* Try to open one matching device. Returns 0, or a libusb error. */
static int open_pedal(pedal *p, libusb_device *dev, uint16_t vid, uint16_t pid,
                      fp_pedal_layout layout)
{
    int bus = libusb_get_bus_number(dev), addr = libusb_get_device_address(dev);
    candidate cands[MAX_CANDIDATES];
    int ncands = list_candidates(dev, layout, cands, MAX_CANDIDATES);
    if (ncands == 0) {
        host_log(p, FP_LOG_WARNING, "%04x:%04x at bus %03d address %03d has no interrupt IN "
                 "endpoint", vid, pid, bus, addr);
        return LIBUSB_ERROR_NOT_FOUND;
    }
    libusb_device_handle *h = NULL;
    int r = libusb_open(dev, &h);
    if (r == LIBUSB_ERROR_ACCESS) {
        char key[32];
        snprintf(key, sizeof key, "%d/%d", bus, addr);
        if (strcmp(key, p->access_reported) != 0) {   /* once per device, not every scan */
            snprintf(p->access_reported, sizeof p->access_reported, "%s", key);
            char text[116];
            fp_pedal_format_access_error(text, sizeof text, bus, addr, vid, pid);
            push_status(p, FP_STATUS_ERROR, "%s", text);
            p->announced = 1;   /* this says it all; no "no pedal found" after it */
            host_log(p, FP_LOG_ERROR, "/dev/bus/usb/%03d/%03d is not readable by this user; "
                     "copy plugins/input-pedal/70-facepuppet-pedal.rules to /etc/udev/rules.d/, "
                     "run `udevadm control --reload && udevadm trigger`, replug (docs/pedal.md)",
                     bus, addr);
        }
        return r;
    }
    if (r) {
        host_log(p, FP_LOG_WARNING, "cannot open %04x:%04x at bus %03d address %03d: %s", vid,
                 pid, bus, addr, libusb_strerror(r));
        return r;
    }
    int chosen = 0;
    bool detached = false;
    r = choose_interface(p, h, cands, ncands, layout, vid, pid, &chosen, &detached);
    if (r) {
        libusb_close(h);
        return r;
    }
    int iface = cands[chosen].iface, maxpacket = cands[chosen].maxpacket;
    uint8_t ep = cands[chosen].ep;
    struct libusb_transfer *t = libusb_alloc_transfer(0);
    if (!t) {
        give_back(h, iface, true, detached);
        return LIBUSB_ERROR_NO_MEM;
    }
    /* As many whole packets as REPORT_MAX holds: a report longer than one packet (a 9-byte
     * keyboard report on an 8-byte endpoint) arrives whole in one read. */
    int len = maxpacket > 0 && maxpacket <= REPORT_MAX ? REPORT_MAX / maxpacket * maxpacket
                                                       : REPORT_MAX;
    libusb_fill_interrupt_transfer(t, h, ep, p->buffer, len, transfer_cb, p, TRANSFER_TIMEOUT_MS);
    p->handle = h;
    p->transfer = t;
    p->iface = iface;
    p->detached = detached;
    p->endpoint = ep;
    p->layout = layout;
    p->vid = vid;
    p->pid = pid;
    p->bus = bus;
    p->address = addr;
    p->mask = 0;
    p->errors = 0;
    p->gone = false;
    p->watchdog = false;
    p->npending = 0;
    /* The read's length: whole packets up to 64 bytes (what the kernel and real pedals take). A umockdev
     * replay (docs/devices.md) only completes a URB whose buffer length equals its script's
     * buflen and fails any other submission with EIO, and a script written by hand may give
     * the report's size or 64 instead: on EIO the other usual lengths are tried in turn (a
     * real device never fails a submission that way, so this costs it nothing); the one
     * taken stays for the resubmissions. */
    const int lengths[] = {len, layout == FP_PEDAL_LAYOUT_VEC ? 2 : 9, 8, 64, 16, 32, 9, 2};
    r = LIBUSB_ERROR_IO;
    for (size_t i = 0; i < sizeof lengths / sizeof lengths[0] && r == LIBUSB_ERROR_IO; i++) {
        bool tried = false;
        for (size_t k = 0; k < i; k++) tried |= lengths[k] == lengths[i];
        if (tried || lengths[i] > REPORT_MAX) continue;
        t->length = lengths[i];
        r = libusb_submit_transfer(t);
    }
    if (r) {
        host_log(p, FP_LOG_WARNING, "cannot read %04x:%04x: %s", vid, pid, libusb_strerror(r));
        libusb_free_transfer(t);
        p->transfer = NULL;
        give_back(h, iface, true, detached);
        p->handle = NULL;
        return r;
    }
    p->in_flight = true;
    p->submitted_ns = now_ns(p);
    p->access_reported[0] = '\0';
    const fp_pedal_model *m = fp_pedal_find_model(vid, pid);
    push_status(p, FP_STATUS_CONNECTED, "%s %04x:%04x at bus %03d address %03d (%s layout)",
                m ? m->name : "pedal", vid, pid, bus, addr, fp_pedal_layout_name(layout));
    p->announced = 2;
    return 0;
}

/* Look through the bus once; open the first usable pedal. Returns 0 when one is open, else
 * LIBUSB_ERROR_NOT_FOUND, or LIBUSB_ERROR_ACCESS when a pedal was there but not ours to
 * open. */
static int scan(pedal *p)
{
    libusb_device **list = NULL;
    ssize_t n = libusb_get_device_list(p->ctx, &list);
    if (n < 0) {
        host_log(p, FP_LOG_WARNING, "cannot list USB devices: %s", libusb_strerror((int)n));
        return (int)n;
    }
    int result = LIBUSB_ERROR_NOT_FOUND;
    for (ssize_t i = 0; i < n && !p->handle; i++) {
        struct libusb_device_descriptor dd;
        if (libusb_get_device_descriptor(list[i], &dd) != 0)
            continue;
        fp_pedal_layout layout;
        if (!fp_pedal_config_matches(&p->cfg, dd.idVendor, dd.idProduct, &layout))
            continue;
        int r = open_pedal(p, list[i], dd.idVendor, dd.idProduct, layout);
        if (r == 0)
            result = 0;
        else if (r == LIBUSB_ERROR_ACCESS)
            result = r;
    }
    libusb_free_device_list(list, 1);
    return result;
}

/* Runs on the thread that handles libusb's events: ours, or start()'s during a strict scan. */
static int LIBUSB_CALL hotplug_cb(libusb_context *ctx, libusb_device *dev,
                                  libusb_hotplug_event event, void *user_data)
{
    (void)ctx;
    pedal *p = user_data;
    if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT) {
        if (p->handle && libusb_get_device(p->handle) == dev)
            p->gone = true;   /* the thread closes it: the read in flight may never end */
    } else {
        p->rescan = true;
    }
    return 0;
}

/* Is the open pedal still there? In libusb's device list (a removal that no hotplug event
 * and no failed read reported), and its node still answering a driver query (usbfs fails
 * every request with ENODEV once the device has left, even where its read is never given
 * back). A list that cannot be had, or a query the node does not know, says yes. */
static bool still_listed(pedal *p)
{
    if (libusb_kernel_driver_active(p->handle, p->iface) == LIBUSB_ERROR_NO_DEVICE)
        return false;
    libusb_device **list = NULL;
    ssize_t n = libusb_get_device_list(p->ctx, &list);
    if (n < 0)
        return true;
    libusb_device *mine = libusb_get_device(p->handle);
    bool found = false;
    for (ssize_t i = 0; i < n && !found; i++)
        found = list[i] == mine;
    libusb_free_device_list(list, 1);
    return found;
}

/* The read in flight outlived its timeout by STUCK_MS: its completion (or libusb's own
 * timeout cancellation) never came back. Cancel it once; when that cannot be done (the
 * device is gone, or a cancellation is already hanging) or it is still stuck STUCK_MS after,
 * the pedal is taken as gone. */
static void watch_read(pedal *p, int64_t t)
{
    if (!p->in_flight || p->gone ||
        t - p->submitted_ns < (int64_t)(TRANSFER_TIMEOUT_MS + STUCK_MS) * 1000000)
        return;
    int r = p->watchdog ? LIBUSB_ERROR_NOT_FOUND : libusb_cancel_transfer(p->transfer);
    if (r == 0) {
        p->watchdog = true;
        p->submitted_ns = t - (int64_t)TRANSFER_TIMEOUT_MS * 1000000;
        return;
    }
    host_log(p, FP_LOG_WARNING, "the read of %04x:%04x has not completed %d ms after its "
             "timeout (%s): taking the pedal as gone", p->vid, p->pid, STUCK_MS,
             libusb_error_name(r));
    p->gone = true;
    p->stuck = true;
}

/* Create the context and the hotplug callback. Returns 0 or a libusb error. */
static int open_context(pedal *p)
{
    int r = libusb_init(&p->ctx);
    if (r) {
        p->ctx = NULL;
        return r;
    }
    if (libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) {
        r = libusb_hotplug_register_callback(p->ctx, LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED |
                                             LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT, 0,
                                             LIBUSB_HOTPLUG_MATCH_ANY, LIBUSB_HOTPLUG_MATCH_ANY,
                                             LIBUSB_HOTPLUG_MATCH_ANY, hotplug_cb, p, &p->hotplug);
        p->hotplug_registered = r == 0;
    }
    atomic_store(&p->ctx_ready, true);
    return 0;
}

static void *pedal_thread(void *arg)
{
    pedal *p = arg;
    int64_t next_scan = 0;
    while (!atomic_load(&p->stopping)) {
        if (!p->ctx) {
            /* libusb could not start (no usbfs here yet): try again every scan period. */
            int64_t t = now_ns(p);
            if (t >= next_scan) {
                next_scan = t + (int64_t)SCAN_PERIOD_MS * 1000000;
                if (open_context(p) == 0)
                    next_scan = 0;
            }
            struct timespec ts = {0, LOOP_TIMEOUT_MS * 1000000L};
            nanosleep(&ts, NULL);
            continue;
        }
        if (p->handle) {   /* [input-thread] the checks that a read in flight cannot make */
            int64_t t = now_ns(p);
            watch_read(p, t);
            if (!p->gone && t >= next_scan) {   /* still there? (no hotplug, no failed read) */
                next_scan = t + (int64_t)SCAN_PERIOD_MS * 1000000;
                if (!still_listed(p))
                    p->gone = true;
            }
        }
        if (p->handle && p->gone)
            close_pedal(p, true);
        if (!p->handle) {
            int64_t t = now_ns(p);
            if (t >= next_scan || p->rescan) {
                p->rescan = false;
                next_scan = t + (int64_t)SCAN_PERIOD_MS * 1000000;
                if (scan(p) != 0 && p->announced == 0) {
                    push_status(p, FP_STATUS_RECONNECTING,
                                "no USB foot pedal found; looking every %d ms", SCAN_PERIOD_MS);
                    p->announced = 1;
                }
            }
        }
        struct timeval tv = {0, LOOP_TIMEOUT_MS * 1000};
        int r = libusb_handle_events_timeout_completed(p->ctx, &tv, NULL);
        if (r != 0 && r != LIBUSB_ERROR_INTERRUPTED && r != LIBUSB_ERROR_TIMEOUT) {
            host_log(p, FP_LOG_WARNING, "libusb event handling: %s", libusb_strerror(r));
            struct timespec ts = {0, 10 * 1000000};
            nanosleep(&ts, NULL);
        }
    }
    close_pedal(p, false);
    return NULL;
}

/* ----------------------------------------------------------------------------------- */
/* fp_input                                                                            */

static void pedal_stop(fp_input *self)
{
    pedal *p = self->plugin_data;
    if (p->thread_started) {
        atomic_store(&p->stopping, true);
        if (atomic_load(&p->ctx_ready))
            libusb_interrupt_event_handler(p->ctx);
        pthread_join(p->thread, NULL);
        p->thread_started = false;
    }
    if (p->ctx) {
        if (p->hotplug_registered)
            libusb_hotplug_deregister_callback(p->ctx, p->hotplug);
        p->hotplug_registered = false;
        close_pedal(p, false);   /* start() may have opened one without a thread */
        libusb_exit(p->ctx);
        p->ctx = NULL;
    }
    atomic_store(&p->ctx_ready, false);
}

static int pedal_start(fp_input *self, char *err, size_t errlen)
{
    pedal *p = self->plugin_data;
    if (p->ctx || p->thread_started) {
        snprintf(err, errlen, "pedal: already started");
        return -EBUSY;
    }
    atomic_store(&p->stopping, false);
    p->announced = 0;
    p->access_reported[0] = '\0';
    int r = open_context(p);
    if (r && p->cfg.strict) {
        snprintf(err, errlen, "pedal: libusb_init failed: %s", libusb_strerror(r));
        return -EIO;
    }
    if (r) {
        /* Not strict: say so and let the thread try again (a machine without usbfs yet). */
        push_status(p, FP_STATUS_ERROR, "libusb cannot start (%s); retrying every %d ms",
                    libusb_error_name(r), SCAN_PERIOD_MS);
        p->announced = 1;
    } else if (p->cfg.strict) {
        /* Strict: a pedal must be there now; open it before the thread runs. */
        r = scan(p);
        if (r != 0) {
            if (r == LIBUSB_ERROR_ACCESS)
                snprintf(err, errlen, "pedal: a pedal is present but not accessible to this "
                         "user; install 70-facepuppet-pedal.rules (docs/pedal.md)");
            else if (p->cfg.have_vidpid)
                snprintf(err, errlen, "pedal: no usable device %04x:%04x (strict)", p->cfg.vid,
                         p->cfg.pid);
            else
                snprintf(err, errlen, "pedal: no known USB foot pedal found (strict)");
            pedal_stop(self);
            return r == LIBUSB_ERROR_ACCESS ? -EACCES : -ENODEV;
        }
    }
    r = pthread_create(&p->thread, NULL, pedal_thread, p);
    if (r) {
        snprintf(err, errlen, "pedal: cannot create thread: %s", strerror(r));
        pedal_stop(self);
        return -r;
    }
    p->thread_started = true;
    return 0;
}

static void pedal_destroy(fp_input *self)
{
    if (!self)
        return;
    pedal_stop(self);
    free(self->plugin_data);
}

static const void *pedal_get_extension(const fp_input *self, const char *id)
{
    (void)self;
    (void)id;
    return NULL;
}

static int pedal_create(const fp_host *host, const char *arg, const fp_param *params,
                        size_t nparams, fp_input **out, char *err, size_t errlen)
{
    if (!out) {
        snprintf(err, errlen, "pedal: out is NULL");
        return -EINVAL;
    }
    *out = NULL;
    fp_pedal_config cfg;
    char msg[200];
    int r = fp_pedal_config_parse(arg, params, nparams, &cfg, msg, sizeof msg);
    if (r) {
        snprintf(err, errlen, "pedal: %s", msg);
        return r;
    }
    pedal *p = calloc(1, sizeof *p);
    if (!p) {
        snprintf(err, errlen, "pedal: out of memory");
        return -ENOMEM;
    }
    p->host = host;
    p->cfg = cfg;
    p->keys = fp_pedal_config_keys(&cfg);
    atomic_init(&p->stopping, false);
    atomic_init(&p->ctx_ready, false);
    p->input.size = sizeof p->input;
    p->input.plugin_data = p;
    p->input.start = pedal_start;
    p->input.stop = pedal_stop;
    p->input.destroy = pedal_destroy;
    p->input.get_extension = pedal_get_extension;
    *out = &p->input;
    return 0;
}

/* ----------------------------------------------------------------------------------- */
/* The entry                                                                           */

/* The keys, typed (ABI 1.1), for `facepuppet plugins` and `plugins check`; create parses
 * them itself (fp_pedal_config_parse). A default of "" means: none, from the device. */
static const fp_param_info pedal_keys[] = {
    {.name = "layout", .type = FP_PARAM_ENUM, .default_value = "", .choices = "vec|keyboard",
     .description = "report layout (default: from the known pedal)"},
    {.name = "keys", .type = FP_PARAM_STRING, .default_value = "a/b/c",
     .description = "keyboard layout: keys for left/middle/right, '-' unbound"},
    {.name = "pedals", .type = FP_PARAM_ENUM, .default_value = "", .choices = "1|3",
     .description = "1: a single-pedal unit (its key b is the left button)"},
    {.name = "strict", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "0",
     .description = "fail at start when no pedal is there"},
    {.name = NULL},
};

static const fp_input_factory pedal_factory = {
    .size = sizeof(fp_input_factory),
    .name = "pedal",
    .description = "USB foot pedal (VEC Infinity, PCsensor FootSwitch) through libusb",
    .usage =
        "pedal[:VID:PID][,layout=vec|keyboard][,keys=K/K/K][,pedals=1|3][,strict=1]\n"
        "  VID:PID  read this device only (hex); needs layout= unless it is a known pedal\n"
        "           (05f3:00ff VEC; 0c45:7403 0c45:7404 413d:2107 1a86:e026 3553:b001 PCsensor)\n"
        "  layout   vec: 2-byte bitmask report; keyboard: HID keyboard report\n"
        "  keys     keyboard layout: keys for left/middle/right (default a/b/c); '-' = unbound\n"
        "  pedals   1: a single-pedal unit, its key b is the left button (same as keys=b)\n"
        "  strict   1: fail at start when no pedal is there (default: report it, keep looking)",
    .create = pedal_create,
    .params = pedal_keys,
};

static const void *entry_get_factory(const char *id)
{
    if (id && !strcmp(id, FP_INPUT_FACTORY_ID))
        return &pedal_factory;
    return NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.input-pedal",
    .version = "0.1.0",
    .get_factory = entry_get_factory,
};
