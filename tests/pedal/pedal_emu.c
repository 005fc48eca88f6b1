/*
 * pedal_emu.c: see pedal_emu.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "pedal_emu.h"

#include <errno.h>
#include <stdbool.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>

#include <linux/ioctl.h>
#include <linux/usbdevice_fs.h>
#include <umockdev.h>

#define MAX_URBS 16
#define MAX_REPORTS 64

struct emu {
    UMockdevTestbed *testbed;
    UMockdevIoctlBase *handler;
    pthread_mutex_t lock;

    emu_kind kind;
    int devnum;                    /* 0: nothing plugged */
    char devnode[64];
    char syspath[128];
    int unplugged;
    int dead;                      /* every ioctl fails with ENODEV, no URB ever completes */
    int unplug_silent;             /* emu_set_unplug_silent: emu_unplug makes the node dead */
    int minimal;                   /* emu_set_minimal */
    unsigned driver_bound;         /* interfaces (bits) a kernel driver holds (emu_plug: all) */

    UMockdevIoctlData *flying[MAX_URBS];
    int nflying;
    UMockdevIoctlData *discarded[MAX_URBS];
    int ndiscarded;

    UMockdevIoctlData *ctrl_done[MAX_URBS];   /* control URBs answered, not yet reaped */
    int ctrl_status[MAX_URBS], ctrl_actual[MAX_URBS];
    int nctrl;

    uint8_t reports[MAX_REPORTS][64];
    size_t report_len[MAX_REPORTS];
    size_t report_off;             /* bytes of the head report already delivered */
    int rhead, rcount;

    emu_stats stats;
};

/* Descriptors as the kernel's sysfs `descriptors` file holds them: device, then config. */
static const char vec_descriptors[] =
    "12010002000000" "08" "f305" "ff00" "0001" "010200" "01"          /* device 05f3:00ff */
    "09022200" "01" "01" "00" "80" "32"                               /* config, 34 bytes */
    "0904" "00" "00" "01" "03" "00" "00" "00"                         /* if 0: HID */
    "092110010001" "22" "3f00"                                        /* HID descriptor */
    "0705" "81" "03" "0800" "0a";                                     /* EP 0x81 int, 8 */

static const char pcsensor_descriptors[] =
    "12011001000000" "08" "450c" "0374" "0001" "010200" "01"          /* device 0c45:7403 */
    "09023b00" "02" "01" "00" "80" "32"                               /* config, 59 bytes */
    "0904" "00" "00" "01" "03" "00" "00" "00"                         /* if 0: vendor HID */
    "092110010001" "22" "1900"
    "0705" "82" "03" "0800" "0a"                                      /* EP 0x82 int, 8 */
    "0904" "01" "00" "01" "03" "01" "01" "00"                         /* if 1: boot keyboard */
    "092110010001" "22" "4b00"
    "0705" "81" "03" "1000" "0a";                                     /* EP 0x81 int, 16 */

/* The audit's shape (kbd8.desc): the boot keyboard first, its EP 0x81 8 bytes a packet, so a
 * 9-byte report takes two packets (8 + 1); the vendor interface second. */
static const char pcsensor_mp8_descriptors[] =
    "12011001000000" "08" "450c" "0374" "0001" "010200" "01"          /* device 0c45:7403 */
    "09023b00" "02" "01" "00" "80" "32"                               /* config, 59 bytes */
    "0904" "00" "00" "01" "03" "01" "01" "00"                         /* if 0: boot keyboard */
    "092110010001" "22" "4b00"
    "0705" "81" "03" "0800" "0a"                                      /* EP 0x81 int, 8 */
    "0904" "01" "00" "01" "03" "00" "00" "00"                         /* if 1: vendor HID */
    "092110010001" "22" "1900"
    "0705" "82" "03" "0800" "0a";                                     /* EP 0x82 int, 8 */

/* A unit whose configuration interface comes first and whose keyboard interface is not a
 * boot interface (protocol 0): only the report descriptors tell them apart. */
static const char config_first_descriptors[] =
    "12011001000000" "08" "5335" "01b0" "0001" "010200" "01"          /* device 3553:b001 */
    "09023b00" "02" "01" "00" "80" "32"                               /* config, 59 bytes */
    "0904" "00" "00" "01" "03" "00" "00" "00"                         /* if 0: HID, vendor */
    "092110010001" "22" "1900"
    "0705" "82" "03" "0800" "0a"                                      /* EP 0x82 int, 8 */
    "0904" "01" "00" "01" "03" "00" "00" "00"                         /* if 1: HID keyboard */
    "092110010001" "22" "4b00"
    "0705" "81" "03" "1000" "0a";                                     /* EP 0x81 int, 16 */

/* A keyboard pedal whose report descriptor declares no report id: 8-byte boot reports. */
static const char boot_noid_descriptors[] =
    "12011001000000" "08" "450c" "0474" "0001" "010200" "01"          /* device 0c45:7404 */
    "09022200" "01" "01" "00" "80" "32"                               /* config, 34 bytes */
    "0904" "00" "00" "01" "03" "01" "01" "00"                         /* if 0: boot keyboard */
    "092110010001" "22" "2f00"
    "0705" "81" "03" "0800" "0a";                                     /* EP 0x81 int, 8 */

/* HID report descriptors: a keyboard under report id 1 and a mouse under id 2 (75 bytes);
 * a keyboard without ids (47); a vendor configuration page (25). */
static const char rdesc_kbd_id[] =
    "05010906a1018501050719e029e71500250175019508810295017508810195067508150026ff00050719002a"
    "ff008100c0" "05010902a10185020901a100050919012903950375018102c0c0";
static const char rdesc_boot[] =
    "05010906a101050719e029e71500250175019508810295017508810195067508150026ff00050719002aff00"
    "8100c0";
static const char rdesc_vendor[] = "0600ff0901a101150026ff00750895080901810209019102c0";

typedef struct emu_model {
    const char *name, *product, *vid, *pid, *descriptors;
    const char *rdesc[2];   /* report descriptor of interface 0 and 1 (hex), NULL none */
    int maxpacket;          /* wMaxPacketSize of EP 0x81, the one read */
} emu_model;

static const emu_model models[] = {
    [EMU_VEC] = {"1-1", "5f3/ff/100", "05f3", "00ff", vec_descriptors, {NULL, NULL}, 8},
    [EMU_PCSENSOR] = {"1-2", "c45/7403/100", "0c45", "7403", pcsensor_descriptors,
                      {rdesc_vendor, rdesc_kbd_id}, 16},
    [EMU_PCSENSOR_MP8] = {"1-3", "c45/7403/100", "0c45", "7403", pcsensor_mp8_descriptors,
                          {rdesc_kbd_id, rdesc_vendor}, 8},
    [EMU_CONFIG_FIRST] = {"1-4", "3553/b001/100", "3553", "b001", config_first_descriptors,
                          {rdesc_vendor, rdesc_kbd_id}, 16},
    [EMU_BOOT_NOID] = {"1-5", "c45/7404/100", "0c45", "7404", boot_noid_descriptors,
                       {rdesc_boot, NULL}, 8},
};

static int expected_endpoint(emu_kind kind)
{
    (void)kind;
    return 0x81;
}

/* Copy the struct an ioctl's pointer argument points to. */
static void read_arg(UMockdevIoctlData *arg, void *out, size_t len)
{
    UMockdevIoctlData *d = umockdev_ioctl_data_resolve(arg, 0, len, NULL);
    memcpy(out, d->data, len);
    g_object_unref(d);
}

static void take_urb_locked(struct emu *e, int i)
{
    e->flying[i] = e->flying[--e->nflying];
    e->stats.flying = e->nflying;
}

/* The bytes of the head report that one interrupt IN URB of `buflen` bytes takes, as the
 * host controller moves them: packets of wMaxPacketSize until a short packet ends the
 * transfer or the buffer is full (then the rest of the report waits for the next URB); a
 * packet larger than what is left of the buffer is babble (-EOVERFLOW, nothing delivered). */
static size_t next_transfer_locked(struct emu *e, int buflen, int *status)
{
    size_t maxp = (size_t)models[e->kind].maxpacket;
    size_t left = e->report_len[e->rhead] - e->report_off, n = 0;
    *status = 0;
    while (left > 0) {
        size_t pkt = left < maxp ? left : maxp;
        if (n + pkt > (size_t)(buflen > 0 ? buflen : 0)) {
            if (n == 0)
                *status = -EOVERFLOW;
            break;
        }
        n += pkt;
        left -= pkt;
        if (pkt < maxp)
            break;
    }
    if (*status == 0 && left > 0) {
        e->report_off += n;                 /* the rest comes with the next URB */
        e->stats.split_transfers++;
    } else {
        e->report_off = 0;
        e->rhead = (e->rhead + 1) % MAX_REPORTS;
        e->rcount--;
        e->stats.queued = e->rcount;
        if (*status == 0)
            e->stats.delivered++;
    }
    return *status == 0 ? n : 0;
}

/* A control URB on endpoint 0 (8-byte setup packet, then the data stage): GET_DESCRIPTOR of
 * an interface's HID report descriptor (0x81 06 22xx) is answered from the model; usbfs
 * refuses it (EBUSY) while a kernel driver holds that interface, as the kernel's implicit
 * claim does. Anything else stalls (-EPIPE). The URB is reaped as completed. */
static void submit_control_locked(struct emu *e, UMockdevIoctlClient *client,
                                  UMockdevIoctlData *urb_data)
{
    struct usbdevfs_urb *urb = (struct usbdevfs_urb *)urb_data->data;
    if (urb->buffer_length < 8 || e->nctrl >= MAX_URBS) {
        umockdev_ioctl_client_complete(client, -1, EINVAL);
        g_object_unref(urb_data);
        return;
    }
    UMockdevIoctlData *buf = umockdev_ioctl_data_resolve(
        urb_data, G_STRUCT_OFFSET(struct usbdevfs_urb, buffer), (gsize)urb->buffer_length, NULL);
    const uint8_t *setup = buf->data;
    unsigned wvalue = setup[2] | setup[3] << 8, windex = setup[4] | setup[5] << 8;
    unsigned wlength = setup[6] | setup[7] << 8;
    int status = -EPIPE, actual = 0;
    if (setup[0] == 0x81 && setup[1] == 0x06 && (wvalue >> 8) == 0x22) {
        if (windex < 8 && (e->driver_bound >> windex) & 1u) {
            umockdev_ioctl_client_complete(client, -1, EBUSY);
            g_object_unref(buf);
            g_object_unref(urb_data);
            return;
        }
        const char *hex = windex < 2 ? models[e->kind].rdesc[windex] : NULL;
        if (hex) {
            size_t n = strlen(hex) / 2;
            if (n > wlength) n = wlength;
            if (n > (size_t)urb->buffer_length - 8) n = (size_t)urb->buffer_length - 8;
            for (size_t i = 0; i < n; i++) {
                unsigned v;
                sscanf(hex + 2 * i, "%2x", &v);
                buf->data[8 + i] = (uint8_t)v;
            }
            status = 0;
            actual = (int)n;
            e->stats.report_descriptor_reads++;
        }
    }
    g_object_unref(buf);
    e->ctrl_done[e->nctrl] = urb_data;   /* keeps the reference */
    e->ctrl_status[e->nctrl] = status;
    e->ctrl_actual[e->nctrl] = actual;
    e->nctrl++;
    umockdev_ioctl_client_complete(client, 0, 0);
}

/* USBDEVFS_IOCTL: DISCONNECT takes the kernel driver off interface ifno (ENODATA when none
 * is bound), CONNECT gives it back; anything else is ENOTTY. */
static void driver_ioctl_locked(struct emu *e, UMockdevIoctlClient *client,
                                UMockdevIoctlData *arg)
{
    struct usbdevfs_ioctl io;
    read_arg(arg, &io, sizeof io);
    unsigned bit = io.ifno >= 0 && io.ifno < 8 ? 1u << io.ifno : 0u;
    if (io.ioctl_code == (int)USBDEVFS_CONNECT) {
        e->stats.reattaches++;
        e->driver_bound |= bit;
        umockdev_ioctl_client_complete(client, 0, 0);
    } else if (io.ioctl_code == (int)USBDEVFS_DISCONNECT) {
        if (e->driver_bound & bit) {
            e->stats.detaches++;
            e->driver_bound &= ~bit;
            umockdev_ioctl_client_complete(client, 0, 0);
        } else {
            umockdev_ioctl_client_complete(client, -1, ENODATA);
        }
    } else {
        umockdev_ioctl_client_complete(client, -1, ENOTTY);
    }
}

/* REAPURB(NDELAY): a completed control URB first, then a discarded one (-ENOENT), then the
 * URB in flight of a pedal that left (-ESHUTDOWN), then one filled from the head report. */
static void reap_locked(struct emu *e, UMockdevIoctlClient *client, UMockdevIoctlData *arg,
                        bool ours)
{
    UMockdevIoctlData *urb_data = NULL;
    int status = 0;
    const uint8_t *payload = NULL;
    size_t len = 0;
    int actual = -1;   /* >= 0: a control URB's data, written at submission */
    if (e->nctrl > 0) {
        urb_data = e->ctrl_done[0];
        status = e->ctrl_status[0];
        actual = e->ctrl_actual[0];
        e->nctrl--;
        memmove(e->ctrl_done, e->ctrl_done + 1, (size_t)e->nctrl * sizeof e->ctrl_done[0]);
        memmove(e->ctrl_status, e->ctrl_status + 1, (size_t)e->nctrl * sizeof(int));
        memmove(e->ctrl_actual, e->ctrl_actual + 1, (size_t)e->nctrl * sizeof(int));
    } else if (e->ndiscarded > 0) {
        urb_data = e->discarded[--e->ndiscarded];
        status = -ENOENT;
    } else if (e->nflying > 0 && (e->unplugged || !ours)) {
        urb_data = e->flying[0];
        take_urb_locked(e, 0);
        status = -ESHUTDOWN;
    } else if (e->nflying > 0 && e->rcount > 0) {
        urb_data = e->flying[0];
        take_urb_locked(e, 0);
        const struct usbdevfs_urb *u = (const struct usbdevfs_urb *)urb_data->data;
        payload = e->reports[e->rhead] + e->report_off;
        len = next_transfer_locked(e, u->buffer_length, &status);
    }
    if (!urb_data) {
        umockdev_ioctl_client_complete(client, -1, EAGAIN);
        return;
    }
    struct usbdevfs_urb *urb = (struct usbdevfs_urb *)urb_data->data;
    urb->status = status;
    urb->actual_length = actual > 0 ? actual : 0;
    if (payload && len > 0) {
        UMockdevIoctlData *buf = umockdev_ioctl_data_resolve(
            urb_data, G_STRUCT_OFFSET(struct usbdevfs_urb, buffer),
            (gsize)urb->buffer_length, NULL);
        memcpy(buf->data, payload, len);
        g_object_unref(buf);
        urb->actual_length = (int)len;
    }
    UMockdevIoctlData *out = umockdev_ioctl_data_resolve(arg, 0, sizeof(gpointer), NULL);
    umockdev_ioctl_data_set_ptr(out, 0, urb_data);
    umockdev_ioctl_client_complete(client, 0, 0);
    g_object_unref(out);
    g_object_unref(urb_data);
}

static gboolean handle_ioctl(UMockdevIoctlBase *handler, UMockdevIoctlClient *client,
                             gpointer user_data)
{
    struct emu *e = user_data;
    (void)handler;
    gulong request = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData *arg = umockdev_ioctl_client_get_arg(client);
    const char *node = umockdev_ioctl_client_get_devnode(client);
    gboolean handled = TRUE;

    pthread_mutex_lock(&e->lock);
    bool ours = e->devnum && node && strcmp(node, e->devnode) == 0;
    if (ours && e->dead) {
        /* A node that died without a word: no URB completes, nothing can be reaped. */
        umockdev_ioctl_client_complete(client, -1, ENODEV);
        goto out;
    }
    if (!ours || e->unplugged) {
        /* A node of a pedal that has left: everything fails as on a dead usbfs fd. */
        if (request == USBDEVFS_REAPURBNDELAY && e->ndiscarded == 0 && e->nflying == 0) {
            umockdev_ioctl_client_complete(client, -1, ENODEV);
            goto out;
        }
        if (request != USBDEVFS_REAPURBNDELAY && request != USBDEVFS_DISCARDURB) {
            umockdev_ioctl_client_complete(client, -1, ENODEV);
            goto out;
        }
    }

    if (e->minimal && request != USBDEVFS_SUBMITURB && request != USBDEVFS_REAPURB &&
        request != USBDEVFS_REAPURBNDELAY && request != USBDEVFS_DISCARDURB &&
        request != USBDEVFS_CLAIMINTERFACE) {
        handled = FALSE; /* umockdev answers ENOTTY */
        goto out;
    }
    switch (request) {
    case USBDEVFS_GETDRIVER: {
        UMockdevIoctlData *d =
            umockdev_ioctl_data_resolve(arg, 0, sizeof(struct usbdevfs_getdriver), NULL);
        struct usbdevfs_getdriver *gd = (struct usbdevfs_getdriver *)d->data;
        if (gd->interface < 8 && (e->driver_bound >> gd->interface) & 1u) {
            memset(gd->driver, 0, sizeof gd->driver);
            memcpy(gd->driver, "usbhid", 6);
            umockdev_ioctl_client_complete(client, 0, 0);
        } else {
            umockdev_ioctl_client_complete(client, -1, ENODATA);
        }
        g_object_unref(d);
        break;
    }
    case USBDEVFS_GET_CAPABILITIES: {
        UMockdevIoctlData *d = umockdev_ioctl_data_resolve(arg, 0, sizeof(uint32_t), NULL);
        uint32_t caps = USBDEVFS_CAP_BULK_CONTINUATION | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                        USBDEVFS_CAP_REAP_AFTER_DISCONNECT;
        memcpy(d->data, &caps, sizeof caps);
        umockdev_ioctl_client_complete(client, 0, 0);
        g_object_unref(d);
        break;
    }
    case USBDEVFS_DISCONNECT_CLAIM: {
        struct usbdevfs_disconnect_claim dc;
        read_arg(arg, &dc, sizeof dc);
        e->stats.disconnect_claims++;
        e->stats.claimed_interface = (int)dc.interface;
        e->stats.claim_flags = dc.flags;
        memcpy(e->stats.claim_driver, dc.driver, sizeof e->stats.claim_driver - 1);
        e->stats.claim_driver[sizeof e->stats.claim_driver - 1] = '\0';
        if (dc.interface < 8)
            e->driver_bound &= ~(1u << dc.interface);
        umockdev_ioctl_client_complete(client, 0, 0);
        break;
    }
    case USBDEVFS_CLAIMINTERFACE: {
        unsigned int ifno;
        read_arg(arg, &ifno, sizeof ifno);
        e->stats.claimed_interface = (int)ifno;
        umockdev_ioctl_client_complete(client, 0, 0);
        break;
    }
    case USBDEVFS_RELEASEINTERFACE:
        e->stats.releases++;
        umockdev_ioctl_client_complete(client, 0, 0);
        break;
    case USBDEVFS_IOCTL:
        driver_ioctl_locked(e, client, arg);
        break;
    case USBDEVFS_CLEAR_HALT:
    case USBDEVFS_RESETEP:
        umockdev_ioctl_client_complete(client, 0, 0);
        break;
    case USBDEVFS_SUBMITURB: {
        UMockdevIoctlData *urb_data =
            umockdev_ioctl_data_resolve(arg, 0, sizeof(struct usbdevfs_urb), NULL);
        struct usbdevfs_urb *urb = (struct usbdevfs_urb *)urb_data->data;
        if (urb->type == USBDEVFS_URB_TYPE_CONTROL && urb->endpoint == 0 && !e->minimal) {
            submit_control_locked(e, client, urb_data);   /* keeps or drops the reference */
            break;
        }
        e->stats.last_endpoint = urb->endpoint;
        if (urb->type != USBDEVFS_URB_TYPE_INTERRUPT ||
            urb->endpoint != expected_endpoint(e->kind) || e->nflying >= MAX_URBS) {
            e->stats.bad_submits++;
            umockdev_ioctl_client_complete(client, -1, EINVAL);
            g_object_unref(urb_data);
            break;
        }
        e->flying[e->nflying++] = urb_data;  /* keeps the reference */
        e->stats.flying = e->nflying;
        e->stats.submits++;
        umockdev_ioctl_client_complete(client, 0, 0);
        break;
    }
    case USBDEVFS_REAPURB:
    case USBDEVFS_REAPURBNDELAY:
        reap_locked(e, client, arg, ours);
        break;
    case USBDEVFS_DISCARDURB: {
        gulong addr = *(gulong *)arg->data;
        int found = -1;
        for (int i = 0; i < e->nflying; i++)
            if (e->flying[i]->client_addr == addr)
                found = i;
        if (found >= 0 && e->ndiscarded < MAX_URBS) {
            e->discarded[e->ndiscarded++] = e->flying[found];
            take_urb_locked(e, found);
            e->stats.discards++;
            umockdev_ioctl_client_complete(client, 0, 0);
        } else {
            umockdev_ioctl_client_complete(client, -1, EINVAL);
        }
        break;
    }
    default:
        handled = FALSE;
        break;
    }
out:
    pthread_mutex_unlock(&e->lock);
    return handled;
}

/* Is libumockdev-preload mapped into this process? (umockdev_in_mock_environment() says no
 * under umockdev-wrapper in 0.17.16, so look for the library itself.) */
static bool preload_active(void)
{
    FILE *f = fopen("/proc/self/maps", "r");
    if (!f)
        return false;
    char line[512];
    bool found = false;
    while (!found && fgets(line, sizeof line, f))
        found = strstr(line, "libumockdev-preload") != NULL;
    fclose(f);
    return found;
}

emu *emu_new(void)
{
    if (!preload_active())
        return NULL;
    struct emu *e = calloc(1, sizeof *e);
    if (!e)
        return NULL;
    pthread_mutex_init(&e->lock, NULL);
    e->testbed = umockdev_testbed_new();
    e->handler = umockdev_ioctl_base_new();
    g_signal_connect(e->handler, "handle-ioctl", G_CALLBACK(handle_ioctl), e);
    e->stats.claimed_interface = -1;
    return e;
}

static void drop_urbs(struct emu *e)
{
    for (int i = 0; i < e->nflying; i++)
        g_object_unref(e->flying[i]);
    for (int i = 0; i < e->ndiscarded; i++)
        g_object_unref(e->discarded[i]);
    for (int i = 0; i < e->nctrl; i++)
        g_object_unref(e->ctrl_done[i]);
    e->nflying = e->ndiscarded = e->nctrl = 0;
}

void emu_free(emu **pe)
{
    if (!pe || !*pe)
        return;
    struct emu *e = *pe;
    g_clear_object(&e->testbed);
    g_clear_object(&e->handler);
    drop_urbs(e);
    pthread_mutex_destroy(&e->lock);
    free(e);
    *pe = NULL;
}

int emu_plug(emu *e, emu_kind kind, int devnum)
{
    char node[64];
    snprintf(node, sizeof node, "/dev/bus/usb/001/%03d", devnum);
    /* The handler first, so that an open right after the add uevent works. */
    if (!umockdev_testbed_attach_ioctl(e->testbed, node, e->handler, NULL))
        return -1;
    pthread_mutex_lock(&e->lock);
    drop_urbs(e);
    e->kind = kind;
    e->devnum = devnum;
    snprintf(e->devnode, sizeof e->devnode, "%s", node);
    e->unplugged = 0;
    e->dead = 0;
    e->driver_bound = 0xffu;
    e->rhead = e->rcount = 0;
    e->report_off = 0;
    memset(&e->stats, 0, sizeof e->stats);
    e->stats.claimed_interface = -1;
    pthread_mutex_unlock(&e->lock);

    const emu_model *m = &models[kind];
    snprintf(e->syspath, sizeof e->syspath, "/sys/devices/pci0000:00/usb1/%s", m->name);
    char *s = g_strdup_printf(
        "P: /devices/pci0000:00/usb1/%s\n"
        "N: bus/usb/001/%03d\n"
        "E: SUBSYSTEM=usb\n"
        "E: DEVTYPE=usb_device\n"
        "E: DRIVER=usb\n"
        "E: BUSNUM=001\n"
        "E: DEVNUM=%03d\n"
        "E: DEVNAME=/dev/bus/usb/001/%03d\n"
        "E: PRODUCT=%s\n"
        "A: busnum=1\\n\n"
        "A: devnum=%d\\n\n"
        "A: bConfigurationValue=1\\n\n"
        "A: speed=12\\n\n"
        "A: idVendor=%s\\n\n"
        "A: idProduct=%s\\n\n"
        "H: descriptors=%s\n",
        m->name, devnum, devnum, devnum, m->product, devnum, m->vid, m->pid, m->descriptors);
    GError *err = NULL;
    gboolean ok = umockdev_testbed_add_from_string(e->testbed, s, &err);
    g_free(s);
    if (!ok) {
        fprintf(stderr, "emu_plug: %s\n", err ? err->message : "?");
        g_clear_error(&err);
        return -1;
    }
    return 0;
}

void emu_unplug(emu *e)
{
    pthread_mutex_lock(&e->lock);
    e->unplugged = 1;
    if (e->unplug_silent)
        e->dead = 1;
    pthread_mutex_unlock(&e->lock);
    umockdev_testbed_remove_device(e->testbed, e->syspath);
}

int emu_deny_access(emu *e)
{
    char *root = umockdev_testbed_get_root_dir(e->testbed);
    char *path = g_strdup_printf("%s%s", root, e->devnode);
    int r = chmod(path, 0);
    g_free(path);
    g_free(root);
    return r;
}

void emu_send(emu *e, const uint8_t *report, size_t len)
{
    pthread_mutex_lock(&e->lock);
    if (e->rcount < MAX_REPORTS && len <= 64) {
        int i = (e->rhead + e->rcount) % MAX_REPORTS;
        memcpy(e->reports[i], report, len);
        e->report_len[i] = len;
        e->rcount++;
        e->stats.queued = e->rcount;
    }
    pthread_mutex_unlock(&e->lock);
}

void emu_set_unplug_silent(emu *e, int on)
{
    pthread_mutex_lock(&e->lock);
    e->unplug_silent = on != 0;
    pthread_mutex_unlock(&e->lock);
}

void emu_kill(emu *e)
{
    pthread_mutex_lock(&e->lock);
    e->dead = 1;
    pthread_mutex_unlock(&e->lock);
}

void emu_set_minimal(emu *e, int on)
{
    pthread_mutex_lock(&e->lock);
    e->minimal = on != 0;
    pthread_mutex_unlock(&e->lock);
}

emu_stats emu_get_stats(emu *e)
{
    pthread_mutex_lock(&e->lock);
    emu_stats s = e->stats;
    pthread_mutex_unlock(&e->lock);
    return s;
}
