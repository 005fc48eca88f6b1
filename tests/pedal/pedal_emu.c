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
    int minimal;                   /* emu_set_minimal */
    int driver_bound;              /* a kernel driver holds the interfaces (emu_plug: yes) */

    UMockdevIoctlData *flying[MAX_URBS];
    int nflying;
    UMockdevIoctlData *discarded[MAX_URBS];
    int ndiscarded;

    uint8_t reports[MAX_REPORTS][64];
    size_t report_len[MAX_REPORTS];
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
    "092110010001" "22" "2200"
    "0705" "82" "03" "0800" "0a"                                      /* EP 0x82 int, 8 */
    "0904" "01" "00" "01" "03" "01" "01" "00"                         /* if 1: boot keyboard */
    "092110010001" "22" "4500"
    "0705" "81" "03" "1000" "0a";                                     /* EP 0x81 int, 16 */

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
        if (e->driver_bound) {
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
        e->driver_bound = 0;
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
    case USBDEVFS_IOCTL: {
        struct usbdevfs_ioctl io;
        read_arg(arg, &io, sizeof io);
        if (io.ioctl_code == (int)USBDEVFS_CONNECT) {
            e->stats.reattaches++;
            e->driver_bound = 1;
            umockdev_ioctl_client_complete(client, 0, 0);
        } else if (io.ioctl_code == (int)USBDEVFS_DISCONNECT) {
            if (e->driver_bound) {
                e->stats.detaches++;
                e->driver_bound = 0;
                umockdev_ioctl_client_complete(client, 0, 0);
            } else {
                umockdev_ioctl_client_complete(client, -1, ENODATA);
            }
        } else {
            umockdev_ioctl_client_complete(client, -1, ENOTTY);
        }
        break;
    }
    case USBDEVFS_CLEAR_HALT:
    case USBDEVFS_RESETEP:
        umockdev_ioctl_client_complete(client, 0, 0);
        break;
    case USBDEVFS_SUBMITURB: {
        UMockdevIoctlData *urb_data =
            umockdev_ioctl_data_resolve(arg, 0, sizeof(struct usbdevfs_urb), NULL);
        struct usbdevfs_urb *urb = (struct usbdevfs_urb *)urb_data->data;
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
    case USBDEVFS_REAPURBNDELAY: {
        UMockdevIoctlData *urb_data = NULL;
        int status = 0;
        const uint8_t *payload = NULL;
        size_t len = 0;
        if (e->ndiscarded > 0) {
            urb_data = e->discarded[--e->ndiscarded];
            status = -ENOENT;
        } else if (e->nflying > 0 && (e->unplugged || !ours)) {
            urb_data = e->flying[0];
            take_urb_locked(e, 0);
            status = -ESHUTDOWN;
        } else if (e->nflying > 0 && e->rcount > 0) {
            urb_data = e->flying[0];
            take_urb_locked(e, 0);
            payload = e->reports[e->rhead];
            len = e->report_len[e->rhead];
            e->rhead = (e->rhead + 1) % MAX_REPORTS;
            e->rcount--;
            e->stats.queued = e->rcount;
            e->stats.delivered++;
        }
        if (!urb_data) {
            umockdev_ioctl_client_complete(client, -1, EAGAIN);
            break;
        }
        struct usbdevfs_urb *urb = (struct usbdevfs_urb *)urb_data->data;
        urb->status = status;
        urb->actual_length = 0;
        if (payload) {
            if ((int)len > urb->buffer_length)
                len = (size_t)urb->buffer_length;  /* the host's buffer is the limit */
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
        break;
    }
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
    e->nflying = e->ndiscarded = 0;
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
    e->driver_bound = 1;
    e->rhead = e->rcount = 0;
    memset(&e->stats, 0, sizeof e->stats);
    e->stats.claimed_interface = -1;
    pthread_mutex_unlock(&e->lock);

    const char *name = kind == EMU_VEC ? "1-1" : "1-2";
    snprintf(e->syspath, sizeof e->syspath, "/sys/devices/pci0000:00/usb1/%s", name);
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
        name, devnum, devnum, devnum, kind == EMU_VEC ? "5f3/ff/100" : "c45/7403/100", devnum,
        kind == EMU_VEC ? "05f3" : "0c45", kind == EMU_VEC ? "00ff" : "7403",
        kind == EMU_VEC ? vec_descriptors : pcsensor_descriptors);
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
