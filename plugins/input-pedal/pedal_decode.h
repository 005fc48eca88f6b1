/*
 * pedal_decode.h: the pure part of the USB foot pedal input (no libusb): the table of known
 * pedals, the SPEC parser, and the report decoder. Private to plugins/input-pedal; the tests
 * compile pedal_decode.c directly.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Report formats (shared/docs/devices.md, "USB foot pedals"; rgerganov/footswitch;
 * fenimore/scribouillage driver.go):
 *   VEC Infinity IN-USB-2: 2 bytes, a little-endian bitmask, 0x01 left, 0x02 middle,
 *     0x04 right; 0 = all released; chords OR together.
 *   PCsensor FootSwitch family: a HID keyboard report with report id 1,
 *     `01 mods 00 k1 k2 k3 k4 k5 k6`, all keys zero on release. A keyboard whose HID report
 *     descriptor declares no report ids sends `mods 00 k1..k6` (8 bytes, the boot layout).
 *     Which of the two a device sends is said by its report descriptor
 *     (fp_pedal_parse_report_descriptor), not by a report's length: a 9-byte report read
 *     8 bytes at a time arrives as 8 + 1 bytes, and its first 8 bytes must not be taken for
 *     a boot report whose modifier byte is the report id.
 *
 * Thread rules: every function here is pure and reentrant ([any-thread]).
 */
#ifndef FP_PEDAL_DECODE_H
#define FP_PEDAL_DECODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "facepuppet/plugin.h"

/** How a pedal's reports are laid out. */
typedef enum fp_pedal_layout {
    FP_PEDAL_LAYOUT_ANY = 0,      /* not chosen: any known pedal, each with its own layout */
    FP_PEDAL_LAYOUT_VEC = 1,      /* bitmask report (VEC Infinity) */
    FP_PEDAL_LAYOUT_KEYBOARD = 2  /* HID keyboard report (PCsensor FootSwitch) */
} fp_pedal_layout;

/** A pedal model the plugin finds by itself. */
typedef struct fp_pedal_model {
    uint16_t vid, pid;
    fp_pedal_layout layout;
    const char *name;
} fp_pedal_model;

/** The known pedals and their count. */
extern const fp_pedal_model fp_pedal_models[];
extern const size_t fp_pedal_model_count;

/** The known model with this VID:PID, or NULL. */
const fp_pedal_model *fp_pedal_find_model(uint16_t vid, uint16_t pid);

/** "vec", "keyboard" or "any". */
const char *fp_pedal_layout_name(fp_pedal_layout layout);

/** Which HID keyboard usage (HUT 1.12 page 0x07) drives each button: usage[0] left,
 *  usage[1] middle, usage[2] right; 0 leaves the button unbound. Modifier usages 0xE0..0xE7
 *  (ctrl, shift, alt, gui; left then right) are read from the report's modifier byte. */
typedef struct fp_pedal_keymap {
    uint8_t usage[3];
} fp_pedal_keymap;

/** The default for a 3-pedal PCsensor unit: a, b, c -> left, middle, right. */
#define FP_PEDAL_KEYMAP_DEFAULT {{0x04, 0x05, 0x06}}
/** The default for a single-pedal unit (`pedals=1`): b -> left. */
#define FP_PEDAL_KEYMAP_SINGLE {{0x05, 0x00, 0x00}}

/** One button change decoded from a report. */
typedef struct fp_pedal_change {
    uint32_t button;   /* one fp_button bit */
    uint32_t down;     /* 1 pressed, 0 released */
    uint32_t mask;     /* every button held after this change */
} fp_pedal_change;

/** Results of fp_pedal_decode besides a count of changes. */
enum {
    FP_PEDAL_ERR_SHORT = -1,    /* the report is too short for its layout */
    FP_PEDAL_ERR_LAYOUT = -2,   /* layout is FP_PEDAL_LAYOUT_ANY or unknown */
    FP_PEDAL_ERR_ARG = -3       /* a NULL pointer where one is required */
};

/**
 * Decode one input report into button changes.
 *
 * report/len: the bytes the interrupt IN endpoint delivered. prev_mask: the buttons held
 * before (fp_button bits). keys: the key bindings, read for FP_PEDAL_LAYOUT_KEYBOARD only
 * (may be NULL for VEC). On success writes the held set after the report to *new_mask and at
 * most 3 changes to out[] (releases first, then presses, each in the order left, middle,
 * right; each change's mask is the held set right after it), and returns their count, 0 when
 * nothing changed. A keyboard report with another report id (2, 3: mouse or consumer
 * reports of composite units) or a phantom state (all six keys 0x01, rollover) changes
 * nothing and returns 0. Returns a negative FP_PEDAL_ERR_* with *new_mask = prev_mask and
 * nothing written to out on a malformed report.
 */
int fp_pedal_decode(fp_pedal_layout layout, const fp_pedal_keymap *keys, const uint8_t *report,
                    size_t len, uint32_t prev_mask, uint32_t *new_mask, fp_pedal_change out[3]);

/** How a keyboard pedal's reports are framed. */
typedef enum fp_pedal_kbd_format {
    FP_PEDAL_KBD_AUTO = 0,  /* unknown: by length (8 bytes: boot; 9+ starting with 1: id 1) */
    FP_PEDAL_KBD_BOOT = 1,  /* no report id: `mods 00 k1..k6`, 8 bytes */
    FP_PEDAL_KBD_ID = 2     /* report id first: `id mods 00 k1..k6`, 9 bytes */
} fp_pedal_kbd_format;

/**
 * Decode one keyboard report framed as `format` says. `id` (FP_PEDAL_KBD_ID only): the
 * keyboard report's id; a report with another first byte (a mouse or consumer report of a
 * composite unit) changes nothing and returns 0. A report shorter than its format's 8
 * (BOOT) or 9 (ID) bytes returns FP_PEDAL_ERR_SHORT and changes nothing: a report cut at a
 * packet boundary is never read as a shorter format. FP_PEDAL_KBD_AUTO is what
 * fp_pedal_decode does for FP_PEDAL_LAYOUT_KEYBOARD. Otherwise as fp_pedal_decode.
 */
int fp_pedal_decode_keyboard(fp_pedal_kbd_format format, uint8_t id, const fp_pedal_keymap *keys,
                             const uint8_t *report, size_t len, uint32_t prev_mask,
                             uint32_t *new_mask, fp_pedal_change out[3]);

/** The size of a whole keyboard report in `format`: 8 (BOOT), 9 (ID), 0 (AUTO: unknown). */
size_t fp_pedal_kbd_report_size(fp_pedal_kbd_format format);

/** What a HID report descriptor (HID 1.11 section 6.2.2, short and long items) says. */
typedef struct fp_pedal_hid_info {
    bool keyboard;        /* an application collection Generic Desktop (0x01) / Keyboard (0x06)
                             with an Input item */
    bool has_ids;         /* a Report ID item anywhere: every report starts with its id */
    uint8_t keyboard_id;  /* the report id of the keyboard's first Input item; 0 without ids */
    bool vendor;          /* every application collection is on a vendor page (0xff00..0xffff):
                             a configuration interface, not the pedal's keys */
} fp_pedal_hid_info;

/**
 * Parse a HID report descriptor of `len` bytes into *info (zeroed first). A 4-byte Usage
 * names its own page (high half); Push and Pop save and restore the usage page and report
 * id. Returns 0, or -1 (*info zeroed) when the descriptor is empty, truncated inside an
 * item, pops more than it pushed or pushes deeper than 8, or has no application collection.
 */
int fp_pedal_parse_report_descriptor(const uint8_t *desc, size_t len, fp_pedal_hid_info *info);

/** The button changes that lead from `prev_mask` to `mask` (only bits 0..2 count), in the
 *  order fp_pedal_decode uses; returns their count (0..3). Used for releasing held buttons
 *  when a pedal leaves (mask = 0). */
int fp_pedal_diff(uint32_t prev_mask, uint32_t mask, fp_pedal_change out[3]);

/** Parse a key name into a HID keyboard usage: a..z, 0..9, f1..f12, enter, esc, backspace,
 *  tab, space, up, down, left, right, pageup, pagedown, home, end, insert, delete,
 *  ctrl/shift/alt/win (left modifiers), rctrl/rshift/ralt/rwin, or a number 1..255 in
 *  decimal or 0x-hex. "-" and "none" give 0 (unbound). Case-insensitive. Returns 0, or -1
 *  for an unknown name. */
int fp_pedal_parse_key(const char *name, uint8_t *usage);

/** Parse "VID:PID" (hex, 1 to 4 digits each, optional 0x). Returns 0 or -1. */
int fp_pedal_parse_vidpid(const char *text, uint16_t *vid, uint16_t *pid);

/** The plugin's settings, from `pedal[:VID:PID][,layout=vec|keyboard][,keys=K,...]
 *  [,pedals=1|3][,strict=0|1]`. Zero-initialised it means "any known pedal, default keys,
 *  not strict". */
typedef struct fp_pedal_config {
    bool have_vidpid;       /* only the device VID:PID */
    uint16_t vid, pid;
    fp_pedal_layout layout; /* ANY: each known pedal's own */
    bool have_keys;
    fp_pedal_keymap keys;   /* valid when have_keys; else the default applies */
    bool strict;            /* start fails when no usable pedal is present */
} fp_pedal_config;

/**
 * Fill *cfg from a SPEC's ARG (NULL where none) and keys. The key list of `keys` may be
 * separated by ',', '/', '+' or ':'; where the host's SPEC splitter has cut `keys=a,b,c`
 * at its commas, the bare items that follow (key "b" with a NULL or empty value) are taken
 * as further keys. A VID:PID that is not a known pedal needs `layout`. Returns 0, or -22
 * (-EINVAL) after writing a message naming the offending key or value to err.
 */
int fp_pedal_config_parse(const char *arg, const fp_param *params, size_t nparams,
                          fp_pedal_config *cfg, char *err, size_t errlen);

/** The key bindings that apply: cfg->keys when given, else FP_PEDAL_KEYMAP_DEFAULT. */
fp_pedal_keymap fp_pedal_config_keys(const fp_pedal_config *cfg);

/** True when a device with this VID:PID is one the config asks for; *layout gets the layout
 *  to decode it with. */
bool fp_pedal_config_matches(const fp_pedal_config *cfg, uint16_t vid, uint16_t pid,
                             fp_pedal_layout *layout);

/** The status text for a pedal that cannot be opened for lack of permission: names the
 *  device and the udev rule. Writes at most textlen bytes, NUL-terminated. */
void fp_pedal_format_access_error(char *text, size_t textlen, int bus, int address,
                                  uint16_t vid, uint16_t pid);

#endif /* FP_PEDAL_DECODE_H */
