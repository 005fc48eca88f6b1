/*
 * pedal_decode.c: known pedals, SPEC parsing and report decoding (pure, no libusb).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pedal_decode.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const fp_pedal_model fp_pedal_models[] = {
    {0x05f3, 0x00ff, FP_PEDAL_LAYOUT_VEC, "VEC Infinity IN-USB-2"},
    {0x0c45, 0x7403, FP_PEDAL_LAYOUT_KEYBOARD, "PCsensor FootSwitch"},
    {0x0c45, 0x7404, FP_PEDAL_LAYOUT_KEYBOARD, "PCsensor FootSwitch"},
    {0x413d, 0x2107, FP_PEDAL_LAYOUT_KEYBOARD, "PCsensor FootSwitch"},
    {0x1a86, 0xe026, FP_PEDAL_LAYOUT_KEYBOARD, "PCsensor FootSwitch"},
    {0x3553, 0xb001, FP_PEDAL_LAYOUT_KEYBOARD, "PCsensor FootSwitch"},
};
const size_t fp_pedal_model_count = sizeof fp_pedal_models / sizeof fp_pedal_models[0];

static const uint32_t button_bits[3] = {FP_BUTTON_LEFT, FP_BUTTON_MIDDLE, FP_BUTTON_RIGHT};
#define ALL_BUTTONS (FP_BUTTON_LEFT | FP_BUTTON_MIDDLE | FP_BUTTON_RIGHT)

const fp_pedal_model *fp_pedal_find_model(uint16_t vid, uint16_t pid)
{
    for (size_t i = 0; i < fp_pedal_model_count; i++)
        if (fp_pedal_models[i].vid == vid && fp_pedal_models[i].pid == pid)
            return &fp_pedal_models[i];
    return NULL;
}

const char *fp_pedal_layout_name(fp_pedal_layout layout)
{
    switch (layout) {
    case FP_PEDAL_LAYOUT_VEC: return "vec";
    case FP_PEDAL_LAYOUT_KEYBOARD: return "keyboard";
    default: return "any";
    }
}

int fp_pedal_diff(uint32_t prev_mask, uint32_t mask, fp_pedal_change out[3])
{
    int n = 0;
    uint32_t held = prev_mask & ALL_BUTTONS;
    mask &= ALL_BUTTONS;
    /* Releases first, so that a change of pedal never shows a chord that was not held. */
    for (int i = 0; i < 3; i++) {
        uint32_t b = button_bits[i];
        if ((held & b) && !(mask & b)) {
            held &= ~b;
            out[n++] = (fp_pedal_change){b, 0, held};
        }
    }
    for (int i = 0; i < 3; i++) {
        uint32_t b = button_bits[i];
        if (!(held & b) && (mask & b)) {
            held |= b;
            out[n++] = (fp_pedal_change){b, 1, held};
        }
    }
    return n;
}

/* Is keyboard usage u held in this report (mods byte and six key slots)? */
static bool key_held(uint8_t u, uint8_t mods, const uint8_t *k)
{
    if (u == 0)
        return false;
    if (u >= 0xE0 && u <= 0xE7)
        return (mods >> (u - 0xE0)) & 1u;
    for (int i = 0; i < 6; i++)
        if (k[i] == u)
            return true;
    return false;
}

int fp_pedal_decode(fp_pedal_layout layout, const fp_pedal_keymap *keys, const uint8_t *report,
                    size_t len, uint32_t prev_mask, uint32_t *new_mask, fp_pedal_change out[3])
{
    if (!new_mask || !out || (!report && len > 0))
        return FP_PEDAL_ERR_ARG;
    *new_mask = prev_mask & ALL_BUTTONS;
    uint32_t mask = 0;
    switch (layout) {
    case FP_PEDAL_LAYOUT_VEC:
        if (len < 1)
            return FP_PEDAL_ERR_SHORT;
        /* Little-endian 16-bit bitmask; only the low three bits are pedals. */
        mask = (uint32_t)report[0] | (len >= 2 ? (uint32_t)report[1] << 8 : 0u);
        mask &= ALL_BUTTONS;
        break;
    case FP_PEDAL_LAYOUT_KEYBOARD:
        return fp_pedal_decode_keyboard(FP_PEDAL_KBD_AUTO, 1, keys, report, len, prev_mask,
                                        new_mask, out);
    default:
        return FP_PEDAL_ERR_LAYOUT;
    }
    *new_mask = mask;
    return fp_pedal_diff(prev_mask, mask, out);
}

size_t fp_pedal_kbd_report_size(fp_pedal_kbd_format format)
{
    return format == FP_PEDAL_KBD_BOOT ? 8 : format == FP_PEDAL_KBD_ID ? 9 : 0;
}

int fp_pedal_decode_keyboard(fp_pedal_kbd_format format, uint8_t id, const fp_pedal_keymap *keys,
                             const uint8_t *report, size_t len, uint32_t prev_mask,
                             uint32_t *new_mask, fp_pedal_change out[3])
{
    if (!new_mask || !out || (!report && len > 0))
        return FP_PEDAL_ERR_ARG;
    *new_mask = prev_mask & ALL_BUTTONS;
    if (!keys)
        return FP_PEDAL_ERR_ARG;
    uint8_t mods;
    const uint8_t *k;
    switch (format) {
    case FP_PEDAL_KBD_BOOT:
        if (len < 8)
            return FP_PEDAL_ERR_SHORT;
        mods = report[0];
        k = report + 2;
        break;
    case FP_PEDAL_KBD_ID:
        if (len >= 1 && report[0] != id)
            return 0;                        /* another report of a composite unit */
        if (len < 9)
            return FP_PEDAL_ERR_SHORT;       /* e.g. the first 8 bytes of a split report */
        mods = report[1];
        k = report + 3;
        break;
    case FP_PEDAL_KBD_AUTO:
        if (len == 8) {                      /* boot protocol: mods 00 k1..k6 */
            mods = report[0];
            k = report + 2;
        } else if (len >= 9 && report[0] == 1) { /* report id 1: 01 mods 00 k1..k6 */
            mods = report[1];
            k = report + 3;
        } else if (len >= 2 && report[0] != 1) {
            return 0;                        /* another report of a composite unit */
        } else {
            return FP_PEDAL_ERR_SHORT;
        }
        break;
    default:
        return FP_PEDAL_ERR_LAYOUT;
    }
    bool rollover = true;
    for (int i = 0; i < 6; i++)
        rollover = rollover && k[i] == 0x01;
    if (rollover)
        return 0;                            /* ErrorRollOver: the state is unknown */
    uint32_t mask = 0;
    for (int i = 0; i < 3; i++)
        if (key_held(keys->usage[i], mods, k))
            mask |= button_bits[i];
    *new_mask = mask;
    return fp_pedal_diff(prev_mask, mask, out);
}

/* ----------------------------------------------------------------------------------- */
/* HID report descriptors                                                              */

int fp_pedal_parse_report_descriptor(const uint8_t *d, size_t len, fp_pedal_hid_info *info)
{
    if (!info)
        return -1;
    memset(info, 0, sizeof *info);
    if (!d || len == 0)
        return -1;
    fp_pedal_hid_info r = {.vendor = true};
    uint32_t page = 0, usage = 0;
    bool usage_has_page = false;     /* a 4-byte Usage: its page in the high half */
    uint8_t report_id = 0;
    struct { uint32_t page; uint8_t report_id; } pushed[8]; /* Push / Pop of the globals read */
    int npushed = 0;
    int depth = 0, apps = 0;
    bool in_keyboard = false, have_kbd_input = false;
    size_t i = 0;
    while (i < len) {
        uint8_t b = d[i];
        if (b == 0xfe) {                     /* long item: 0xfe size tag data */
            if (i + 2 >= len || i + 3 + d[i + 1] > len)
                return -1;
            i += 3 + (size_t)d[i + 1];
            continue;
        }
        size_t size = (b & 3) == 3 ? 4 : (b & 3);
        if (i + 1 + size > len)
            return -1;
        uint32_t v = 0;
        for (size_t j = 0; j < size; j++)
            v |= (uint32_t)d[i + 1 + j] << (8 * j);
        int type = (b >> 2) & 3, tag = b >> 4;
        if (type == 1 && tag == 0) {         /* Usage Page */
            page = v;
        } else if (type == 1 && tag == 8) {  /* Report ID */
            report_id = (uint8_t)v;
            r.has_ids = true;
        } else if (type == 1 && tag == 0xa) { /* Push: the global items' state */
            if (npushed == (int)(sizeof pushed / sizeof pushed[0]))
                return -1;
            pushed[npushed].page = page;
            pushed[npushed++].report_id = report_id;
        } else if (type == 1 && tag == 0xb) { /* Pop */
            if (npushed == 0)
                return -1;
            page = pushed[--npushed].page;
            report_id = pushed[npushed].report_id;
        } else if (type == 2 && tag == 0) {  /* Usage (4 bytes: page in the high half) */
            usage = v;
            usage_has_page = size == 4;
        } else if (type == 0) {
            uint32_t upage = usage_has_page ? usage >> 16 : page, uid = usage & 0xffff;
            if (tag == 0xa) {                /* Collection */
                if (depth == 0 && v == 1) {  /* Application */
                    apps++;
                    in_keyboard = upage == 0x01 && uid == 0x06;
                    if (upage < 0xff00)
                        r.vendor = false;
                }
                depth++;
            } else if (tag == 0xc) {         /* End Collection */
                if (depth > 0 && --depth == 0)
                    in_keyboard = false;
            } else if (tag == 0x8 && in_keyboard && !have_kbd_input) {   /* Input */
                have_kbd_input = true;
                r.keyboard = true;
                r.keyboard_id = report_id;
            }
            usage = 0;                       /* local items end at a main item */
            usage_has_page = false;
        }
        i += 1 + size;
    }
    if (apps == 0)
        return -1;
    if (!r.has_ids)
        r.keyboard_id = 0;
    *info = r;
    return 0;
}

/* ----------------------------------------------------------------------------------- */
/* SPEC parsing                                                                        */

static const struct { const char *name; uint8_t usage; } key_names[] = {
    {"enter", 0x28}, {"return", 0x28}, {"esc", 0x29}, {"escape", 0x29}, {"backspace", 0x2a},
    {"tab", 0x2b}, {"space", 0x2c}, {"insert", 0x49}, {"home", 0x4a}, {"pageup", 0x4b},
    {"delete", 0x4c}, {"end", 0x4d}, {"pagedown", 0x4e}, {"right", 0x4f}, {"left", 0x50},
    {"down", 0x51}, {"up", 0x52},
    {"ctrl", 0xe0}, {"shift", 0xe1}, {"alt", 0xe2}, {"win", 0xe3},
    {"rctrl", 0xe4}, {"rshift", 0xe5}, {"ralt", 0xe6}, {"rwin", 0xe7},
};

int fp_pedal_parse_key(const char *name, uint8_t *usage)
{
    if (!name || !usage || !*name)
        return -1;
    char s[16];
    size_t n = strlen(name);
    if (n >= sizeof s)
        return -1;
    for (size_t i = 0; i <= n; i++)
        s[i] = (char)tolower((unsigned char)name[i]);
    if (!strcmp(s, "-") || !strcmp(s, "none")) {
        *usage = 0;
        return 0;
    }
    if (n == 1 && s[0] >= 'a' && s[0] <= 'z') {
        *usage = (uint8_t)(0x04 + (s[0] - 'a'));
        return 0;
    }
    if (n == 1 && s[0] >= '1' && s[0] <= '9') {
        *usage = (uint8_t)(0x1e + (s[0] - '1'));
        return 0;
    }
    if (n == 1 && s[0] == '0') {
        *usage = 0x27;
        return 0;
    }
    if (s[0] == 'f' && n >= 2 && n <= 3 && isdigit((unsigned char)s[1]) &&
        (n == 2 || isdigit((unsigned char)s[2]))) {
        int f = atoi(s + 1);
        if (f >= 1 && f <= 12) {
            *usage = (uint8_t)(0x3a + f - 1);
            return 0;
        }
        return -1;
    }
    for (size_t i = 0; i < sizeof key_names / sizeof key_names[0]; i++)
        if (!strcmp(s, key_names[i].name)) {
            *usage = key_names[i].usage;
            return 0;
        }
    if (isdigit((unsigned char)s[0])) {      /* a number: 1..255, decimal or 0x-hex */
        char *end;
        errno = 0;                           /* (base 10 unless 0x: "040" is 40, not octal) */
        long v = strtol(s, &end, s[0] == '0' && s[1] == 'x' ? 16 : 10);
        if (errno == 0 && *end == '\0' && v >= 1 && v <= 255) {
            *usage = (uint8_t)v;
            return 0;
        }
    }
    return -1;
}

static int parse_hex16(const char *s, size_t n, uint16_t *out)
{
    if (n >= 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        s += 2;
        n -= 2;
    }
    if (n < 1 || n > 4)
        return -1;
    unsigned v = 0;
    for (size_t i = 0; i < n; i++) {
        int c = (unsigned char)s[i];
        if (!isxdigit(c))
            return -1;
        v = v * 16 + (unsigned)(isdigit(c) ? c - '0' : tolower(c) - 'a' + 10);
    }
    *out = (uint16_t)v;
    return 0;
}

int fp_pedal_parse_vidpid(const char *text, uint16_t *vid, uint16_t *pid)
{
    if (!text)
        return -1;
    const char *colon = strchr(text, ':');
    if (!colon)
        return -1;
    uint16_t v, p;
    if (parse_hex16(text, (size_t)(colon - text), &v) ||
        parse_hex16(colon + 1, strlen(colon + 1), &p))
        return -1;
    *vid = v;
    *pid = p;
    return 0;
}

static int parse_bool(const char *v, bool *out)
{
    if (!v || !*v || !strcmp(v, "1") || !strcmp(v, "true") || !strcmp(v, "yes") ||
        !strcmp(v, "on")) {
        *out = true;
        return 0;
    }
    if (!strcmp(v, "0") || !strcmp(v, "false") || !strcmp(v, "no") || !strcmp(v, "off")) {
        *out = false;
        return 0;
    }
    return -1;
}

/* Append the keys of one list item (a single name or several joined by / + :). */
static int add_keys(const char *list, fp_pedal_keymap *km, int *count, char *err, size_t errlen)
{
    const char *p = list;
    for (;;) {
        size_t n = strcspn(p, ",/+:");
        char name[32];
        if (n == 0 || n >= sizeof name) {
            snprintf(err, errlen, "keys: empty or too long key name in \"%s\"", list);
            return -EINVAL;
        }
        memcpy(name, p, n);
        name[n] = '\0';
        uint8_t u;
        if (fp_pedal_parse_key(name, &u)) {
            snprintf(err, errlen, "keys: unknown key \"%s\" (a..z, 0..9, f1..f12, space, "
                     "enter, ctrl, ..., or a HID usage number)", name);
            return -EINVAL;
        }
        if (*count >= 3) {
            snprintf(err, errlen, "keys: at most 3 keys (left, middle, right)");
            return -EINVAL;
        }
        km->usage[(*count)++] = u;
        if (p[n] == '\0')
            return 0;
        p += n + 1;
    }
}

int fp_pedal_config_parse(const char *arg, const fp_param *params, size_t nparams,
                          fp_pedal_config *cfg, char *err, size_t errlen)
{
    char dummy[1];
    if (!err || errlen == 0) {
        err = dummy;
        errlen = sizeof dummy;
    }
    err[0] = '\0';
    if (!cfg)
        return -EINVAL;
    memset(cfg, 0, sizeof *cfg);
    if (arg && *arg) {
        if (fp_pedal_parse_vidpid(arg, &cfg->vid, &cfg->pid)) {
            snprintf(err, errlen, "bad device \"%s\": expected VID:PID in hex, e.g. 05f3:00ff",
                     arg);
            return -EINVAL;
        }
        cfg->have_vidpid = true;
    }
    int nkeys = 0, pedals = 0;
    bool in_keys = false;    /* the previous param was keys= (or a bare key after it) */
    for (size_t i = 0; i < nparams; i++) {
        const char *k = params[i].key ? params[i].key : "";
        const char *v = params[i].value;
        bool bare = !v || !*v;
        if (in_keys && bare && strcmp(k, "strict") != 0) {
            int r = add_keys(k, &cfg->keys, &nkeys, err, errlen);
            if (r)
                return r;
            continue;
        }
        in_keys = false;
        if (!strcmp(k, "layout")) {
            if (v && !strcmp(v, "vec")) {
                cfg->layout = FP_PEDAL_LAYOUT_VEC;
            } else if (v && !strcmp(v, "keyboard")) {
                cfg->layout = FP_PEDAL_LAYOUT_KEYBOARD;
            } else {
                snprintf(err, errlen, "layout: \"%s\" is neither vec nor keyboard", v ? v : "");
                return -EINVAL;
            }
        } else if (!strcmp(k, "keys")) {
            if (bare) {
                snprintf(err, errlen, "keys: needs a list, e.g. keys=a/b/c");
                return -EINVAL;
            }
            nkeys = 0;
            memset(&cfg->keys, 0, sizeof cfg->keys);
            int r = add_keys(v, &cfg->keys, &nkeys, err, errlen);
            if (r)
                return r;
            cfg->have_keys = true;
            in_keys = true;
        } else if (!strcmp(k, "pedals")) {
            if (v && !strcmp(v, "1")) {
                pedals = 1;
            } else if (v && !strcmp(v, "3")) {
                pedals = 3;
            } else {
                snprintf(err, errlen, "pedals: \"%s\" is neither 1 nor 3", v ? v : "");
                return -EINVAL;
            }
        } else if (!strcmp(k, "strict")) {
            if (parse_bool(v, &cfg->strict)) {
                snprintf(err, errlen, "strict: \"%s\" is not 0 or 1", v);
                return -EINVAL;
            }
        } else {
            snprintf(err, errlen, "unknown key \"%s\" (known: layout, keys, pedals, strict)", k);
            return -EINVAL;
        }
    }
    if (pedals && cfg->have_keys) {
        snprintf(err, errlen, "pedals: give either pedals= or keys=, not both");
        return -EINVAL;
    }
    if (pedals == 1) {
        cfg->keys = (fp_pedal_keymap)FP_PEDAL_KEYMAP_SINGLE;
        cfg->have_keys = true;
    } else if (pedals == 3) {
        cfg->keys = (fp_pedal_keymap)FP_PEDAL_KEYMAP_DEFAULT;
        cfg->have_keys = true;
    }
    if (cfg->have_vidpid && cfg->layout == FP_PEDAL_LAYOUT_ANY &&
        !fp_pedal_find_model(cfg->vid, cfg->pid)) {
        snprintf(err, errlen, "%04x:%04x is not a known pedal: give layout=vec or "
                 "layout=keyboard", cfg->vid, cfg->pid);
        return -EINVAL;
    }
    return 0;
}

fp_pedal_keymap fp_pedal_config_keys(const fp_pedal_config *cfg)
{
    if (cfg && cfg->have_keys)
        return cfg->keys;
    return (fp_pedal_keymap)FP_PEDAL_KEYMAP_DEFAULT;
}

bool fp_pedal_config_matches(const fp_pedal_config *cfg, uint16_t vid, uint16_t pid,
                             fp_pedal_layout *layout)
{
    const fp_pedal_model *m = fp_pedal_find_model(vid, pid);
    fp_pedal_layout l;
    if (cfg->have_vidpid) {
        if (vid != cfg->vid || pid != cfg->pid)
            return false;
        l = cfg->layout != FP_PEDAL_LAYOUT_ANY ? cfg->layout : (m ? m->layout : FP_PEDAL_LAYOUT_ANY);
    } else {
        if (!m)
            return false;
        if (cfg->layout != FP_PEDAL_LAYOUT_ANY && cfg->layout != m->layout)
            return false;
        l = m->layout;
    }
    if (l == FP_PEDAL_LAYOUT_ANY)
        return false;
    if (layout)
        *layout = l;
    return true;
}

void fp_pedal_format_access_error(char *text, size_t textlen, int bus, int address,
                                  uint16_t vid, uint16_t pid)
{
    snprintf(text, textlen, "no permission for pedal %04x:%04x at bus %03d address %03d: "
             "install 70-facepuppet-pedal.rules", vid, pid, bus, address);
}
