/*
 * input_pedal.c: USB foot pedals through libusb (SPEC name "pedal").
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * One instance owns one libusb context and one thread ([input-thread]). The thread looks
 * for a pedal every 500 ms while none is open (libusb_get_device_list; a hotplug arrival,
 * where libusb offers hotplug, only makes it look sooner), opens it with the kernel driver
 * detached automatically, claims the interface with the interrupt IN endpoint, and keeps
 * one asynchronous interrupt transfer in flight, serviced by
 * libusb_handle_events_timeout_completed. Each completed report goes through
 * fp_pedal_decode (pedal_decode.c) and becomes fp_event_button events. A transfer that ends
 * with LIBUSB_TRANSFER_NO_DEVICE closes the pedal: held buttons are released, an
 * FP_STATUS_DISCONNECTED event is pushed, and the search starts again.
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
#define MAX_ERRORS 5               /* consecutive failed transfers before we reopen */
#define REPORT_MAX 64

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
    uint16_t vid, pid;
    int bus, address;
    struct libusb_transfer *transfer;
    bool in_flight;
    bool gone;                       /* the device left: close and look again */
    int errors;
    uint32_t mask;
    uint8_t buffer[REPORT_MAX];

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

static void LIBUSB_CALL transfer_cb(struct libusb_transfer *t)
{
    pedal *p = t->user_data;
    p->in_flight = false;
    switch (t->status) {
    case LIBUSB_TRANSFER_COMPLETED: {
        p->errors = 0;
        uint32_t mask;
        fp_pedal_change ch[3];
        int n = fp_pedal_decode(p->layout, &p->keys, t->buffer, (size_t)t->actual_length,
                                p->mask, &mask, ch);
        if (n < 0) {
            host_log(p, FP_LOG_DEBUG, "ignored a %d-byte report (%s layout)", t->actual_length,
                     fp_pedal_layout_name(p->layout));
        } else {
            p->mask = mask;
            push_changes(p, ch, n, now_ns(p));
        }
        break;
    }
    case LIBUSB_TRANSFER_TIMED_OUT:   /* the pedal had nothing to say: ask again */
        break;
    case LIBUSB_TRANSFER_CANCELLED:   /* stop or close asked for it */
        return;
    case LIBUSB_TRANSFER_NO_DEVICE:
        p->gone = true;
        return;
    case LIBUSB_TRANSFER_STALL:
        libusb_clear_halt(p->handle, p->endpoint);
        /* fall through */
    default:
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
    } else {
        if (r != LIBUSB_ERROR_NO_DEVICE)
            host_log(p, FP_LOG_WARNING, "resubmitting the read failed: %s", libusb_strerror(r));
        p->gone = true;
    }
}

/* ----------------------------------------------------------------------------------- */
/* Opening and closing a pedal                                                         */

/* Find the interface and interrupt IN endpoint to read: for a keyboard-layout pedal the
 * boot keyboard interface when there is one, else the first with an interrupt IN. */
static int find_endpoint(libusb_device *dev, fp_pedal_layout layout, int *iface, uint8_t *ep,
                         int *maxpacket)
{
    struct libusb_config_descriptor *cd = NULL;
    if (libusb_get_active_config_descriptor(dev, &cd) != 0 &&
        libusb_get_config_descriptor(dev, 0, &cd) != 0)
        return LIBUSB_ERROR_NOT_FOUND;
    int best = -1, best_score = -1;
    for (int i = 0; i < cd->bNumInterfaces; i++) {
        if (cd->interface[i].num_altsetting < 1)
            continue;
        const struct libusb_interface_descriptor *id = &cd->interface[i].altsetting[0];
        for (int e = 0; e < id->bNumEndpoints; e++) {
            const struct libusb_endpoint_descriptor *ed = &id->endpoint[e];
            if ((ed->bEndpointAddress & LIBUSB_ENDPOINT_DIR_MASK) != LIBUSB_ENDPOINT_IN ||
                (ed->bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_INTERRUPT)
                continue;
            int score = 1;
            if (layout == FP_PEDAL_LAYOUT_KEYBOARD && id->bInterfaceClass == LIBUSB_CLASS_HID &&
                id->bInterfaceProtocol == 1)
                score = 2;
            if (score > best_score) {
                best_score = score;
                best = i;
                *iface = id->bInterfaceNumber;
                *ep = ed->bEndpointAddress;
                *maxpacket = ed->wMaxPacketSize;
            }
            break;
        }
    }
    libusb_free_config_descriptor(cd);
    return best >= 0 ? 0 : LIBUSB_ERROR_NOT_FOUND;
}

/* Cancel the transfer and run the event loop until its callback has run. */
static void cancel_and_wait(pedal *p)
{
    if (!p->in_flight)
        return;
    libusb_cancel_transfer(p->transfer);
    int64_t deadline = now_ns(p) + (int64_t)CANCEL_WAIT_MS * 1000000;
    while (p->in_flight && now_ns(p) < deadline) {
        struct timeval tv = {0, 50000};
        libusb_handle_events_timeout_completed(p->ctx, &tv, NULL);
    }
    if (p->in_flight)
        host_log(p, FP_LOG_WARNING, "the cancelled read did not complete in %d ms",
                 CANCEL_WAIT_MS);
}

/* Let go of an opened pedal: the interface released when claimed, the kernel driver given
 * back when we detached it, the handle closed (each fails harmlessly when the device is gone). */
static void give_back(libusb_device_handle *h, int iface, bool claimed, bool detached)
{
    if (claimed) libusb_release_interface(h, iface);
    if (detached) libusb_attach_kernel_driver(h, iface);
    libusb_close(h);
}

/* Close the open pedal. `report`: release held buttons and push DISCONNECTED. */
static void close_pedal(pedal *p, bool report)
{
    if (!p->handle)
        return;
    cancel_and_wait(p);
    if (!p->in_flight) {
        libusb_free_transfer(p->transfer);
    } /* else: leak it rather than free memory libusb may still write (logged above) */
    p->transfer = NULL;
    give_back(p->handle, p->iface, true, p->detached);
    p->detached = false;
    p->handle = NULL;
    if (report) {
        fp_pedal_change ch[3];
        int n = fp_pedal_diff(p->mask, 0, ch);
        push_changes(p, ch, n, now_ns(p));
        push_status(p, FP_STATUS_DISCONNECTED,
                    "pedal %04x:%04x at bus %03d address %03d left; looking every %d ms",
                    p->vid, p->pid, p->bus, p->address, SCAN_PERIOD_MS);
        p->announced = 1;
    }
    p->mask = 0;
    p->gone = false;
}

/* Try to open one matching device. Returns 0, or a libusb error. */
static int open_pedal(pedal *p, libusb_device *dev, uint16_t vid, uint16_t pid,
                      fp_pedal_layout layout)
{
    int bus = libusb_get_bus_number(dev), addr = libusb_get_device_address(dev);
    int iface = 0, maxpacket = 0;
    uint8_t ep = 0;
    int r = find_endpoint(dev, layout, &iface, &ep, &maxpacket);
    if (r) {
        host_log(p, FP_LOG_WARNING, "%04x:%04x at bus %03d address %03d has no interrupt IN "
                 "endpoint", vid, pid, bus, addr);
        return r;
    }
    libusb_device_handle *h = NULL;
    r = libusb_open(dev, &h);
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
    /* A kernel driver (usbhid) bound to the interface is detached by hand and given back at
     * close, not through libusb_set_auto_detach_kernel_driver: that claims with
     * USBDEVFS_DISCONNECT_CLAIM, then GETDRIVER and USBDEVFS_IOCTL(DISCONNECT), and fails the
     * claim when the node answers those with ENOTTY, as umockdev's in-process handler of
     * docs/devices.md's recipe does. A driver query that fails is taken as no driver. */
    bool detached = false;
    if (libusb_kernel_driver_active(h, iface) == 1) {
        int d = libusb_detach_kernel_driver(h, iface);
        if (d == 0)
            detached = true;
        else if (d != LIBUSB_ERROR_NOT_FOUND && d != LIBUSB_ERROR_NOT_SUPPORTED)
            host_log(p, FP_LOG_WARNING, "cannot detach the kernel driver from interface %d of "
                     "%04x:%04x: %s", iface, vid, pid, libusb_strerror(d));
    }
    r = libusb_claim_interface(h, iface);
    if (r) {
        host_log(p, r == LIBUSB_ERROR_NO_DEVICE ? FP_LOG_DEBUG : FP_LOG_WARNING,
                 "cannot claim interface %d of %04x:%04x: %s%s", iface, vid, pid,
                 libusb_strerror(r),
                 r == LIBUSB_ERROR_BUSY ? " (is another program reading the pedal?)" : "");
        give_back(h, iface, false, detached);
        return r;
    }
    struct libusb_transfer *t = libusb_alloc_transfer(0);
    if (!t) {
        give_back(h, iface, true, detached);
        return LIBUSB_ERROR_NO_MEM;
    }
    int len = maxpacket > 0 && maxpacket <= REPORT_MAX ? maxpacket : REPORT_MAX;
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
    /* The read's length: wMaxPacketSize (what the kernel and real pedals take). A umockdev
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

static int LIBUSB_CALL hotplug_cb(libusb_context *ctx, libusb_device *dev,
                                  libusb_hotplug_event event, void *user_data)
{
    (void)ctx;
    (void)dev;
    (void)event;
    ((pedal *)user_data)->rescan = true;
    return 0;
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
        r = libusb_hotplug_register_callback(p->ctx, LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED, 0,
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
