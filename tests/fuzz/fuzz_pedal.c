/* fuzz_pedal.c: libFuzzer target for the USB foot pedal's pure part
 * (plugins/input-pedal/pedal_decode.h): the input's bytes as a run of HID reports a device
 * sends (each: one length byte, then that many bytes), decoded in both layouts with the
 * default and a fuzzed key map, and the same bytes as the SPEC's ARG and a key list. A
 * report is decoded or refused (FP_PEDAL_ERR_SHORT) with the held set unchanged; every held
 * set and change stays within the three buttons; the changes lead from the set before to the
 * set after, releases first, each change's mask the set right after it; the keyboard decoder
 * told its framing (boot, or report id) decodes no report shorter than that framing's. The
 * same bytes as a HID report descriptor parse or are refused with the result zeroed. A parse
 * either succeeds or writes a message. Seeds: tests/fuzz/corpus/fuzz_pedal. */
#include "pedal_decode.h"

#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define BUTTONS 7u /* left, middle, right */

static void check_changes(int n, uint32_t after, const fp_pedal_change ch[3], uint32_t *held);

static void check_decode(fp_pedal_layout layout, const fp_pedal_keymap *keys, const uint8_t *r,
                         size_t len, uint32_t *held)
{
    fp_pedal_change ch[3];
    uint32_t after = 0xdeadbeef;
    int n = fp_pedal_decode(layout, keys, r, len, *held, &after, ch);
    check_changes(n, after, ch, held);
}

/* The keyboard decoder told the framing (the report descriptor's): the same rules. */
static void check_keyboard(fp_pedal_kbd_format format, uint8_t id, const fp_pedal_keymap *keys,
                           const uint8_t *r, size_t len, uint32_t *held)
{
    fp_pedal_change ch[3];
    uint32_t after = 0xdeadbeef;
    int n = fp_pedal_decode_keyboard(format, id, keys, r, len, *held, &after, ch);
    if ((n > 0 || (n == 0 && after != *held)) && format != FP_PEDAL_KBD_AUTO &&
        len < fp_pedal_kbd_report_size(format))
        abort(); /* (another id's report, even a short one, changes nothing: 0) */
    check_changes(n, after, ch, held);
}

static void check_changes(int n, uint32_t after, const fp_pedal_change ch[3], uint32_t *held)
{
    if (n < 0) {
        if (n != FP_PEDAL_ERR_SHORT || after != *held) abort();
        return;
    }
    if (n > 3 || (after & ~BUTTONS)) abort();
    uint32_t m = *held;
    bool pressed = false;
    for (int i = 0; i < n; i++) {
        uint32_t b = ch[i].button;
        if (b & ~BUTTONS || !b || (b & (b - 1))) abort();       /* one button */
        if (ch[i].down ? (m & b) : !(m & b)) abort();           /* a change, not a repeat */
        if (ch[i].down) pressed = true;
        else if (pressed) abort();                              /* releases first */
        m = ch[i].down ? (m | b) : (m & ~b);
        if (ch[i].mask != m) abort();
    }
    if (m != after) abort();
    *held = after;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* reports: the first two bytes pick a key map, then (length, bytes) records */
    fp_pedal_keymap fuzzed = {{size > 0 ? data[0] : 0, size > 1 ? data[1] : 0, size > 2 ? data[2] : 0}};
    const fp_pedal_keymap def = FP_PEDAL_KEYMAP_DEFAULT;
    uint32_t held[5] = {0, 0, 0, 0, 0};
    for (size_t i = size > 3 ? 3 : size; i < size;) {
        size_t len = data[i++];
        if (len > size - i) len = size - i;
        check_decode(FP_PEDAL_LAYOUT_VEC, NULL, data + i, len, &held[0]);
        check_decode(FP_PEDAL_LAYOUT_KEYBOARD, &def, data + i, len, &held[1]);
        check_decode(FP_PEDAL_LAYOUT_KEYBOARD, &fuzzed, data + i, len, &held[2]);
        check_keyboard(FP_PEDAL_KBD_BOOT, 0, &fuzzed, data + i, len, &held[3]);
        check_keyboard(FP_PEDAL_KBD_ID, size > 0 ? data[0] : 1, &def, data + i, len, &held[4]);
        i += len;
    }
    /* the same bytes as a HID report descriptor: parsed or refused (info zeroed) */
    fp_pedal_hid_info info;
    memset(&info, 0xa5, sizeof info);
    if (fp_pedal_parse_report_descriptor(data, size, &info)) {
        if (info.keyboard || info.has_ids || info.keyboard_id || info.vendor) abort();
    } else if (info.keyboard_id && !info.has_ids) {
        abort();
    }
    fp_pedal_change ch[3];
    if (fp_pedal_diff(held[1], 0, ch) < 0) abort();
    /* the same bytes as text: a SPEC's ARG (VID:PID) and a key list */
    char *text = malloc(size + 1);
    if (!text) abort();
    memcpy(text, data, size);
    text[size] = 0;
    uint16_t vid, pid;
    uint8_t usage;
    (void)fp_pedal_parse_vidpid(text, &vid, &pid);
    (void)fp_pedal_parse_key(text, &usage);
    fp_param params[2] = {{.key = "keys", .value = text}, {.key = "layout", .value = "keyboard"}};
    fp_pedal_config cfg;
    char err[512] = "";
    int rc = fp_pedal_config_parse(text, params, 2, &cfg, err, sizeof err);
    if (rc && (rc != -22 || !err[0])) abort();
    if (!rc) {
        fp_pedal_keymap k = fp_pedal_config_keys(&cfg);
        (void)k;
        fp_pedal_layout layout;
        (void)fp_pedal_config_matches(&cfg, 0x05f3, 0x00ff, &layout);
    }
    free(text);
    return 0;
}
