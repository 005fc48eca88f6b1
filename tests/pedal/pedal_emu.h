/*
 * pedal_emu.h: byte-exact USB foot pedals emulated in-process with a umockdev testbed.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * The testbed provides the sysfs device (descriptors, busnum, devnum) that libusb enumerates
 * and a usbfs node /dev/bus/usb/001/DDD whose ioctls (SUBMITURB, REAPURBNDELAY, DISCARDURB,
 * CLAIMINTERFACE, DISCONNECT_CLAIM, RELEASEINTERFACE, GETDRIVER, USBDEVFS_IOCTL(DISCONNECT,
 * CONNECT), GET_CAPABILITIES) are answered by a handler on umockdev's worker thread, as in
 * libusb's own tests/umockdev.c; a kernel driver ("usbhid") is bound to the pedal's
 * interfaces until the reader detaches it. With emu_set_minimal the handler answers only
 * what docs/devices.md's in-process recipe covers (SUBMITURB, REAPURB(NDELAY), DISCARDURB,
 * CLAIMINTERFACE), everything else failing with ENOTTY, as an outside emulator built from
 * that recipe does. Reports
 * queued with emu_send complete the interrupt IN URB that the reader has in flight, one
 * report per URB, cut into packets of the endpoint's wMaxPacketSize as a host controller
 * moves them: a URB ends at a short packet or when its buffer is full, so a 9-byte report
 * read 8 bytes at a time takes two URBs (8, then 1). A control URB asking for an interface's
 * HID report descriptor is answered (not with emu_set_minimal). emu_unplug completes the in-flight URB with -ESHUTDOWN (as the kernel does
 * on disconnect), fails every later ioctl with ENODEV and removes the sysfs device.
 * The process must run with libumockdev-preload loaded (the test links it first).
 */
#ifndef PEDAL_EMU_H
#define PEDAL_EMU_H

#include <stddef.h>
#include <stdint.h>

typedef enum emu_kind {
    EMU_VEC = 0,       /* 05f3:00ff, one HID interface, EP 0x81, 2-byte bitmask reports */
    EMU_PCSENSOR = 1,  /* 0c45:7403, interface 0 vendor HID (EP 0x82), interface 1 boot
                          keyboard (EP 0x81, 16-byte packets), 9-byte reports with id 1 */
    EMU_PCSENSOR_MP8 = 2, /* 0c45:7403, interface 0 boot keyboard (EP 0x81, 8-byte packets:
                          a 9-byte report is two packets, 8 + 1), interface 1 vendor HID */
    EMU_CONFIG_FIRST = 3, /* 3553:b001, interface 0 HID with a vendor report descriptor
                          (configuration, EP 0x82), interface 1 HID keyboard that is not a
                          boot interface (protocol 0; EP 0x81, 16-byte packets), id 1 */
    EMU_BOOT_NOID = 4  /* 0c45:7404, one boot keyboard interface (EP 0x81, 8-byte packets)
                          whose report descriptor has no report id: 8-byte reports */
} emu_kind;

typedef struct emu emu;

/** What the reader asked of the device so far (counts since the last emu_plug). */
typedef struct emu_stats {
    int disconnect_claims;     /* USBDEVFS_DISCONNECT_CLAIM (auto-detach of the kernel driver) */
    int claimed_interface;     /* interface of the last claim, -1 none */
    char claim_driver[16];     /* the driver named in DISCONNECT_CLAIM ("usbfs") */
    unsigned claim_flags;
    int releases;              /* USBDEVFS_RELEASEINTERFACE */
    int detaches;              /* USBDEVFS_IOCTL(USBDEVFS_DISCONNECT): kernel driver off */
    int reattaches;            /* USBDEVFS_IOCTL(USBDEVFS_CONNECT): kernel driver back */
    int submits;               /* SUBMITURB accepted */
    int bad_submits;           /* SUBMITURB of the wrong type or endpoint */
    int discards;              /* DISCARDURB of a flying URB (cancel, timeout) */
    int flying;                /* URBs submitted and not yet reaped */
    int delivered;             /* reports delivered */
    int queued;                /* reports waiting for a URB */
    int last_endpoint;         /* endpoint of the last interrupt SUBMITURB */
    int split_transfers;       /* URBs that took part of a report (the rest in the next) */
    int report_descriptor_reads; /* GET_DESCRIPTOR(HID report) answered */
} emu_stats;

/** A testbed with no device. NULL when umockdev is not active (preload missing). */
emu *emu_new(void);
void emu_free(emu **e);

/** Plug a pedal of `kind` at bus 1 address `devnum`. Returns 0 or -1. */
int emu_plug(emu *e, emu_kind kind, int devnum);

/** Unplug the pedal: the in-flight URB ends with -ESHUTDOWN, the device leaves sysfs. */
void emu_unplug(emu *e);

/** From now on, emu_unplug leaves the URB in flight uncompleted and fails every ioctl on
 *  the node with ENODEV (REAPURBNDELAY and DISCARDURB included), as a dead usbfs fd whose
 *  URBs the kernel never gives back; the device still leaves sysfs. */
void emu_set_unplug_silent(emu *e, int on);

/** The pedal dies where it stands: every ioctl on its node fails with ENODEV and the URB in
 *  flight never completes, but the device stays in sysfs (no hotplug event). */
void emu_kill(emu *e);

/** Queue one report (at most 64 bytes) for the reader. */
void emu_send(emu *e, const uint8_t *report, size_t len);

/** Take read and write permission on the plugged pedal's usbfs node away from everyone
 *  (mode 0000). Only effective on a process without CAP_DAC_OVERRIDE. Returns 0 or -1. */
int emu_deny_access(emu *e);

/** Answer only the ioctls of docs/devices.md's in-process recipe (SUBMITURB, REAPURB,
 *  REAPURBNDELAY, DISCARDURB, CLAIMINTERFACE); every other one fails with ENOTTY. Takes
 *  effect at once; off by default (emu_new). */
void emu_set_minimal(emu *e, int on);

/** A snapshot of the statistics. */
emu_stats emu_get_stats(emu *e);

#endif
