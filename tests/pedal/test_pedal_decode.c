/*
 * test_pedal_decode.c: the pure report decoder and SPEC parser of input-pedal (no libusb).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "pedal_decode.h"

#define L FP_BUTTON_LEFT
#define M FP_BUTTON_MIDDLE
#define R FP_BUTTON_RIGHT

static const fp_pedal_keymap abc = FP_PEDAL_KEYMAP_DEFAULT;

static void check(const fp_pedal_change *c, uint32_t button, uint32_t down, uint32_t mask)
{
    assert_int_equal(c->button, button);
    assert_int_equal(c->down, down);
    assert_int_equal(c->mask, mask);
}

static void test_vec_single_pedals(void **state)
{
    (void)state;
    fp_pedal_change ch[3];
    uint32_t mask = 0xdead;
    const uint32_t bits[3] = {L, M, R};
    for (int i = 0; i < 3; i++) {
        uint8_t down[2] = {(uint8_t)(1u << i), 0};
        assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_VEC, NULL, down, 2, 0, &mask, ch), 1);
        assert_int_equal(mask, bits[i]);
        check(&ch[0], bits[i], 1, bits[i]);
        uint8_t up[2] = {0, 0};
        assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_VEC, NULL, up, 2, mask, &mask, ch), 1);
        assert_int_equal(mask, 0);
        check(&ch[0], bits[i], 0, 0);
    }
}

static void test_vec_chords_and_no_change(void **state)
{
    (void)state;
    fp_pedal_change ch[3];
    uint32_t mask;
    /* left+right from nothing: two downs, in order, the mask growing */
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_VEC, NULL, (const uint8_t[]){0x05, 0}, 2,
                                     0, &mask, ch), 2);
    check(&ch[0], L, 1, L);
    check(&ch[1], R, 1, L | R);
    assert_int_equal(mask, L | R);
    /* the same report again: nothing */
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_VEC, NULL, (const uint8_t[]){0x05, 0}, 2,
                                     mask, &mask, ch), 0);
    assert_int_equal(mask, L | R);
    /* swap left for middle: the release comes first */
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_VEC, NULL, (const uint8_t[]){0x06, 0}, 2,
                                     mask, &mask, ch), 2);
    check(&ch[0], L, 0, R);
    check(&ch[1], M, 1, M | R);
    /* all three, then none */
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_VEC, NULL, (const uint8_t[]){0x07, 0}, 2,
                                     mask, &mask, ch), 1);
    check(&ch[0], L, 1, L | M | R);
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_VEC, NULL, (const uint8_t[]){0x00, 0}, 2,
                                     mask, &mask, ch), 3);
    check(&ch[0], L, 0, M | R);
    check(&ch[1], M, 0, R);
    check(&ch[2], R, 0, 0);
    /* bits above the three pedals and the high byte are not pedals */
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_VEC, NULL, (const uint8_t[]){0xf8, 0xff},
                                     2, 0, &mask, ch), 0);
    assert_int_equal(mask, 0);
    /* a 1-byte report still decodes; an empty one is an error that keeps the state */
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_VEC, NULL, (const uint8_t[]){0x02}, 1, 0,
                                     &mask, ch), 1);
    assert_int_equal(mask, M);
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_VEC, NULL, NULL, 0, M, &mask, ch),
                     FP_PEDAL_ERR_SHORT);
    assert_int_equal(mask, M);
}

static void test_keyboard_report_id(void **state)
{
    (void)state;
    fp_pedal_change ch[3];
    uint32_t mask;
    const uint8_t b_down[9] = {0x01, 0x00, 0x00, 0x05, 0, 0, 0, 0, 0};
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_KEYBOARD, &abc, b_down, 9, 0, &mask, ch), 1);
    check(&ch[0], M, 1, M);
    const uint8_t chord[9] = {0x01, 0x00, 0x00, 0x06, 0x04, 0x05, 0, 0, 0};
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_KEYBOARD, &abc, chord, 9, mask, &mask, ch), 2);
    check(&ch[0], L, 1, L | M);
    check(&ch[1], R, 1, L | M | R);
    const uint8_t release[9] = {0x01, 0, 0, 0, 0, 0, 0, 0, 0};
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_KEYBOARD, &abc, release, 9, mask, &mask, ch),
                     3);
    assert_int_equal(mask, 0);
    /* an unbound key (z) and the key in the last slot */
    const uint8_t z[9] = {0x01, 0, 0, 0x1d, 0, 0, 0, 0, 0x06};
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_KEYBOARD, &abc, z, 9, 0, &mask, ch), 1);
    check(&ch[0], R, 1, R);
}

static void test_keyboard_boot_other_ids_rollover(void **state)
{
    (void)state;
    fp_pedal_change ch[3];
    uint32_t mask;
    /* 8-byte boot report: mods 00 k1..k6 */
    const uint8_t boot[8] = {0x00, 0x00, 0x04, 0, 0, 0, 0, 0};
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_KEYBOARD, &abc, boot, 8, 0, &mask, ch), 1);
    check(&ch[0], L, 1, L);
    /* mouse report (id 2) of a composite unit: no change, state kept */
    const uint8_t mouse[5] = {0x02, 0x01, 0x00, 0x00, 0x00};
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_KEYBOARD, &abc, mouse, 5, L, &mask, ch), 0);
    assert_int_equal(mask, L);
    /* ErrorRollOver: unknown state, nothing changes */
    const uint8_t roll[9] = {0x01, 0, 0, 1, 1, 1, 1, 1, 1};
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_KEYBOARD, &abc, roll, 9, L, &mask, ch), 0);
    assert_int_equal(mask, L);
    /* too short for id 1 */
    const uint8_t shortr[4] = {0x01, 0, 0, 0x04};
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_KEYBOARD, &abc, shortr, 4, L, &mask, ch),
                     FP_PEDAL_ERR_SHORT);
    assert_int_equal(mask, L);
    /* modifier bindings come from the mods byte */
    fp_pedal_keymap mods = {{0xe0, 0xe1, 0xe6}};   /* ctrl, shift, ralt */
    const uint8_t m[9] = {0x01, 0x01 | 0x40, 0, 0, 0, 0, 0, 0, 0};
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_KEYBOARD, &mods, m, 9, 0, &mask, ch), 2);
    assert_int_equal(mask, L | R);
    /* no layout is an error */
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_ANY, &abc, m, 9, 0, &mask, ch),
                     FP_PEDAL_ERR_LAYOUT);
    assert_int_equal(fp_pedal_decode(FP_PEDAL_LAYOUT_KEYBOARD, NULL, m, 9, 0, &mask, ch),
                     FP_PEDAL_ERR_ARG);
}

static void test_diff_release_all(void **state)
{
    (void)state;
    fp_pedal_change ch[3];
    assert_int_equal(fp_pedal_diff(L | R, 0, ch), 2);
    check(&ch[0], L, 0, R);
    check(&ch[1], R, 0, 0);
    assert_int_equal(fp_pedal_diff(0, 0, ch), 0);
}

static void test_parse_keys(void **state)
{
    (void)state;
    uint8_t u;
    assert_int_equal(fp_pedal_parse_key("a", &u), 0);
    assert_int_equal(u, 0x04);
    assert_int_equal(fp_pedal_parse_key("B", &u), 0);
    assert_int_equal(u, 0x05);
    assert_int_equal(fp_pedal_parse_key("z", &u), 0);
    assert_int_equal(u, 0x1d);
    assert_int_equal(fp_pedal_parse_key("1", &u), 0);
    assert_int_equal(u, 0x1e);
    assert_int_equal(fp_pedal_parse_key("0", &u), 0);
    assert_int_equal(u, 0x27);
    assert_int_equal(fp_pedal_parse_key("f1", &u), 0);
    assert_int_equal(u, 0x3a);
    assert_int_equal(fp_pedal_parse_key("F12", &u), 0);
    assert_int_equal(u, 0x45);
    assert_int_equal(fp_pedal_parse_key("space", &u), 0);
    assert_int_equal(u, 0x2c);
    assert_int_equal(fp_pedal_parse_key("0x2c", &u), 0);
    assert_int_equal(u, 0x2c);
    /* a number is decimal unless it starts 0x (before: strtol's base 0 read "040" as octal
     * 32, and refused "08") */
    assert_int_equal(fp_pedal_parse_key("040", &u), 0);
    assert_int_equal(u, 40);
    assert_int_equal(fp_pedal_parse_key("08", &u), 0);
    assert_int_equal(u, 8);
    assert_int_equal(fp_pedal_parse_key("ctrl", &u), 0);
    assert_int_equal(u, 0xe0);
    assert_int_equal(fp_pedal_parse_key("-", &u), 0);
    assert_int_equal(u, 0);
    assert_int_equal(fp_pedal_parse_key("f13", &u), -1);
    assert_int_equal(fp_pedal_parse_key("zz", &u), -1);
    assert_int_equal(fp_pedal_parse_key("256", &u), -1);
    assert_int_equal(fp_pedal_parse_key("", &u), -1);
}

static void test_parse_vidpid(void **state)
{
    (void)state;
    uint16_t v, p;
    assert_int_equal(fp_pedal_parse_vidpid("05f3:00ff", &v, &p), 0);
    assert_int_equal(v, 0x05f3);
    assert_int_equal(p, 0x00ff);
    assert_int_equal(fp_pedal_parse_vidpid("0x1A86:E026", &v, &p), 0);
    assert_int_equal(v, 0x1a86);
    assert_int_equal(p, 0xe026);
    assert_int_equal(fp_pedal_parse_vidpid("05f3", &v, &p), -1);
    assert_int_equal(fp_pedal_parse_vidpid("12345:1", &v, &p), -1);
    assert_int_equal(fp_pedal_parse_vidpid("05g3:00ff", &v, &p), -1);
    assert_int_equal(fp_pedal_parse_vidpid(":00ff", &v, &p), -1);
}

static void test_config(void **state)
{
    (void)state;
    fp_pedal_config c;
    char err[200];
    /* zero params: any known pedal, default keys a b c */
    assert_int_equal(fp_pedal_config_parse(NULL, NULL, 0, &c, err, sizeof err), 0);
    fp_pedal_keymap k = fp_pedal_config_keys(&c);
    assert_memory_equal(k.usage, abc.usage, 3);
    fp_pedal_layout l;
    assert_true(fp_pedal_config_matches(&c, 0x05f3, 0x00ff, &l));
    assert_int_equal(l, FP_PEDAL_LAYOUT_VEC);
    assert_true(fp_pedal_config_matches(&c, 0x3553, 0xb001, &l));
    assert_int_equal(l, FP_PEDAL_LAYOUT_KEYBOARD);
    assert_false(fp_pedal_config_matches(&c, 0x046d, 0xc077, &l));   /* a mouse */

    /* keys=b,c,d as a host that splits at commas passes it */
    const fp_param split[] = {{"keys", "b"}, {"c", NULL}, {"d", ""}, {"strict", "1"}};
    assert_int_equal(fp_pedal_config_parse(NULL, split, 4, &c, err, sizeof err), 0);
    assert_int_equal(c.keys.usage[0], 0x05);
    assert_int_equal(c.keys.usage[1], 0x06);
    assert_int_equal(c.keys.usage[2], 0x07);
    assert_true(c.strict);
    /* ... and unsplit, with other separators */
    const fp_param joined[] = {{"keys", "b,-/f1"}};
    assert_int_equal(fp_pedal_config_parse(NULL, joined, 1, &c, err, sizeof err), 0);
    assert_int_equal(c.keys.usage[0], 0x05);
    assert_int_equal(c.keys.usage[1], 0x00);
    assert_int_equal(c.keys.usage[2], 0x3a);
    /* pedals=1: b is the left button */
    const fp_param one[] = {{"pedals", "1"}};
    assert_int_equal(fp_pedal_config_parse(NULL, one, 1, &c, err, sizeof err), 0);
    k = fp_pedal_config_keys(&c);
    assert_int_equal(k.usage[0], 0x05);
    assert_int_equal(k.usage[1], 0);
    /* layout filter */
    const fp_param vec[] = {{"layout", "vec"}};
    assert_int_equal(fp_pedal_config_parse(NULL, vec, 1, &c, err, sizeof err), 0);
    assert_false(fp_pedal_config_matches(&c, 0x0c45, 0x7403, &l));
    assert_true(fp_pedal_config_matches(&c, 0x05f3, 0x00ff, &l));
    /* an unknown device with a layout; only that device */
    const fp_param kb[] = {{"layout", "keyboard"}};
    assert_int_equal(fp_pedal_config_parse("1234:abcd", kb, 1, &c, err, sizeof err), 0);
    assert_true(fp_pedal_config_matches(&c, 0x1234, 0xabcd, &l));
    assert_int_equal(l, FP_PEDAL_LAYOUT_KEYBOARD);
    assert_false(fp_pedal_config_matches(&c, 0x05f3, 0x00ff, &l));
    /* a known device read with another layout on request */
    assert_int_equal(fp_pedal_config_parse("05f3:00ff", kb, 1, &c, err, sizeof err), 0);
    assert_true(fp_pedal_config_matches(&c, 0x05f3, 0x00ff, &l));
    assert_int_equal(l, FP_PEDAL_LAYOUT_KEYBOARD);
}

static void test_config_errors(void **state)
{
    (void)state;
    fp_pedal_config c;
    char err[200];
    struct { const char *arg; fp_param p; const char *needle; } cases[] = {
        {NULL, {"layout", "midi"}, "midi"},
        {NULL, {"keys", "a/b/c/d"}, "at most 3"},
        {NULL, {"keys", "q/ww"}, "ww"},
        {NULL, {"keys", ""}, "keys"},
        {NULL, {"pedals", "2"}, "pedals"},
        {NULL, {"strict", "maybe"}, "strict"},
        {NULL, {"colour", "red"}, "colour"},
        {"1234:5678", {"strict", "0"}, "layout"},
        {"05f3", {"strict", "0"}, "05f3"},
        {NULL, {"c", NULL}, "\"c\""},     /* a bare item not after keys= */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        err[0] = '\0';
        assert_int_equal(fp_pedal_config_parse(cases[i].arg, &cases[i].p, 1, &c, err, sizeof err),
                         -EINVAL);
        if (!strstr(err, cases[i].needle))
            fail_msg("case %zu: \"%s\" lacks \"%s\"", i, err, cases[i].needle);
    }
    const fp_param both[] = {{"pedals", "1"}, {"keys", "a"}};
    assert_int_equal(fp_pedal_config_parse(NULL, both, 2, &c, err, sizeof err), -EINVAL);
}

static void test_access_error_text(void **state)
{
    (void)state;
    char t[116];
    fp_pedal_format_access_error(t, sizeof t, 1, 5, 0x05f3, 0x00ff);
    assert_non_null(strstr(t, "05f3:00ff"));
    assert_non_null(strstr(t, "bus 001 address 005"));
    assert_non_null(strstr(t, "70-facepuppet-pedal.rules"));
    assert_true(strlen(t) < sizeof t - 1);   /* fits an fp_event_status text uncut */
}

/* A 9-byte report with id 1 read 8 bytes at a time (wMaxPacketSize 8): the first 8 bytes are
 * not a boot report whose modifier byte (the id, 0x01) is left Ctrl; the whole report is. */
static void test_keyboard_formats_split_report(void **state)
{
    (void)state;
    fp_pedal_change ch[3];
    uint32_t mask = 0;
    const fp_pedal_keymap ctrl_b_c = {{0xe0, 0x05, 0x06}};
    const uint8_t whole[9] = {0x01, 0x00, 0x00, 0x05, 0, 0, 0, 0, 0};
    assert_int_equal(fp_pedal_decode_keyboard(FP_PEDAL_KBD_ID, 1, &ctrl_b_c, whole, 8, 0, &mask,
                                              ch), FP_PEDAL_ERR_SHORT);
    assert_int_equal(mask, 0);
    assert_int_equal(fp_pedal_decode_keyboard(FP_PEDAL_KBD_ID, 1, &ctrl_b_c, whole + 8, 1, 0,
                                              &mask, ch), 0);   /* the tail: id 0, not ours */
    assert_int_equal(mask, 0);
    assert_int_equal(fp_pedal_decode_keyboard(FP_PEDAL_KBD_ID, 1, &ctrl_b_c, whole, 9, 0, &mask,
                                              ch), 1);
    check(&ch[0], M, 1, M);
    /* ctrl really held (mods 0x01 after the id) is left */
    const uint8_t ctrl[9] = {0x01, 0x01, 0x00, 0, 0, 0, 0, 0, 0};
    assert_int_equal(fp_pedal_decode_keyboard(FP_PEDAL_KBD_ID, 1, &ctrl_b_c, ctrl, 9, M, &mask,
                                              ch), 2);
    check(&ch[0], M, 0, 0);
    check(&ch[1], L, 1, L);
    /* another id of the unit (mouse, id 2) changes nothing; a keyboard under id 3 is read */
    const uint8_t id3[9] = {0x03, 0x00, 0x00, 0x06, 0, 0, 0, 0, 0};
    assert_int_equal(fp_pedal_decode_keyboard(FP_PEDAL_KBD_ID, 1, &ctrl_b_c, id3, 9, 0, &mask,
                                              ch), 0);
    assert_int_equal(fp_pedal_decode_keyboard(FP_PEDAL_KBD_ID, 3, &ctrl_b_c, id3, 9, 0, &mask,
                                              ch), 1);
    check(&ch[0], R, 1, R);
    /* boot framing: byte 0 is the modifier byte, whatever the length beyond 8 */
    const uint8_t boot[8] = {0x01, 0x00, 0x06, 0, 0, 0, 0, 0};
    assert_int_equal(fp_pedal_decode_keyboard(FP_PEDAL_KBD_BOOT, 0, &ctrl_b_c, boot, 8, 0,
                                              &mask, ch), 2);
    assert_int_equal(mask, L | R);
    assert_int_equal(fp_pedal_decode_keyboard(FP_PEDAL_KBD_BOOT, 0, &ctrl_b_c, boot, 7, 0,
                                              &mask, ch), FP_PEDAL_ERR_SHORT);
    assert_int_equal(fp_pedal_kbd_report_size(FP_PEDAL_KBD_ID), 9);
    assert_int_equal(fp_pedal_kbd_report_size(FP_PEDAL_KBD_BOOT), 8);
}

/* Items other report descriptors use (HID 1.11 6.2.2.7-8): a 4-byte Usage naming its page
 * (0x0b: Generic Desktop / Keyboard as 0x00010006) for the keyboard collection, and Push /
 * Pop around another report's items, the keyboard's Input after the Pop under its own id.
 * (Before: the 4-byte usage's page was taken from the Collection item's size, not the
 * usage's, so the keyboard was not seen; Push and Pop were ignored, so the Input was taken
 * as id 5's and every id-1 report ignored: a pedal that never pressed.) */
static void test_report_descriptor_items(void **state)
{
    (void)state;
    fp_pedal_hid_info info;
    const uint8_t extended[] = {
        0x0b, 0x06, 0x00, 0x01, 0x00, 0xa1, 0x01, 0x85, 0x01, 0x05, 0x07, 0x19, 0xe0, 0x29,
        0xe7, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02, 0x95, 0x01, 0x75,
        0x08, 0x81, 0x01, 0x95, 0x06, 0x75, 0x08, 0x19, 0x00, 0x29, 0xff, 0x81, 0x00, 0xc0};
    assert_int_equal(fp_pedal_parse_report_descriptor(extended, sizeof extended, &info), 0);
    assert_true(info.keyboard && info.has_ids && !info.vendor);
    assert_int_equal(info.keyboard_id, 1);
    const uint8_t pushed[] = {
        0x05, 0x01, 0x09, 0x06, 0xa1, 0x01, 0x85, 0x01,
        0xa4, 0x85, 0x05, 0x06, 0x00, 0xff, 0xb4,           /* Push, id 5 on a vendor page, Pop */
        0x05, 0x07, 0x19, 0xe0, 0x29, 0xe7, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x08,
        0x81, 0x02, 0x95, 0x07, 0x75, 0x08, 0x81, 0x00, 0xc0};
    assert_int_equal(fp_pedal_parse_report_descriptor(pushed, sizeof pushed, &info), 0);
    assert_true(info.keyboard && info.has_ids && !info.vendor);
    assert_int_equal(info.keyboard_id, 1);
    /* a Pop with nothing pushed is a broken descriptor */
    const uint8_t popped[] = {0x05, 0x01, 0x09, 0x06, 0xb4, 0xa1, 0x01, 0x81, 0x00, 0xc0};
    assert_int_equal(fp_pedal_parse_report_descriptor(popped, sizeof popped, &info), -1);
}

static void test_report_descriptor(void **state)
{
    (void)state;
    fp_pedal_hid_info info;
    /* keyboard, report id 1 (declared inside the collection), then a mouse under id 2 */
    const uint8_t kbd_id[] = {
        0x05, 0x01, 0x09, 0x06, 0xa1, 0x01, 0x85, 0x01, 0x05, 0x07, 0x19, 0xe0, 0x29, 0xe7,
        0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02, 0x95, 0x01, 0x75, 0x08,
        0x81, 0x01, 0x95, 0x06, 0x75, 0x08, 0x15, 0x00, 0x26, 0xff, 0x00, 0x05, 0x07, 0x19,
        0x00, 0x2a, 0xff, 0x00, 0x81, 0x00, 0xc0,
        0x05, 0x01, 0x09, 0x02, 0xa1, 0x01, 0x85, 0x02, 0x09, 0x01, 0xa1, 0x00, 0x05, 0x09,
        0x19, 0x01, 0x29, 0x03, 0x95, 0x03, 0x75, 0x01, 0x81, 0x02, 0xc0, 0xc0};
    assert_int_equal(fp_pedal_parse_report_descriptor(kbd_id, sizeof kbd_id, &info), 0);
    assert_true(info.keyboard && info.has_ids && !info.vendor);
    assert_int_equal(info.keyboard_id, 1);
    /* the same keyboard under id 3, the mouse first */
    uint8_t swapped[sizeof kbd_id];
    memcpy(swapped, kbd_id + 49, sizeof kbd_id - 49);
    memcpy(swapped + sizeof kbd_id - 49, kbd_id, 49);
    swapped[sizeof kbd_id - 49 + 7] = 0x03;
    assert_int_equal(fp_pedal_parse_report_descriptor(swapped, sizeof swapped, &info), 0);
    assert_true(info.keyboard && info.has_ids);
    assert_int_equal(info.keyboard_id, 3);
    /* a boot keyboard: no ids */
    uint8_t boot[49 - 2];
    memcpy(boot, kbd_id, 6);
    memcpy(boot + 6, kbd_id + 8, 41);
    assert_int_equal(fp_pedal_parse_report_descriptor(boot, sizeof boot, &info), 0);
    assert_true(info.keyboard && !info.has_ids);
    assert_int_equal(info.keyboard_id, 0);
    /* a vendor configuration interface (page 0xff00), with a long item to skip */
    const uint8_t vendor[] = {0x06, 0x00, 0xff, 0x09, 0x01, 0xa1, 0x01, 0xfe, 0x02, 0x10,
                              0xaa, 0xbb, 0x15, 0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95,
                              0x08, 0x09, 0x01, 0x81, 0x02, 0xc0};
    assert_int_equal(fp_pedal_parse_report_descriptor(vendor, sizeof vendor, &info), 0);
    assert_true(info.vendor && !info.keyboard && !info.has_ids);
    /* truncated inside an item, empty, no collection */
    assert_int_equal(fp_pedal_parse_report_descriptor(kbd_id, 37, &info), -1);
    assert_false(info.keyboard);
    assert_int_equal(fp_pedal_parse_report_descriptor(kbd_id, 0, &info), -1);
    assert_int_equal(fp_pedal_parse_report_descriptor(kbd_id, 4, &info), -1);
}

static void test_models(void **state)
{
    (void)state;
    assert_int_equal(fp_pedal_model_count, 6);
    const uint16_t kb[5][2] = {{0x0c45, 0x7403}, {0x0c45, 0x7404}, {0x413d, 0x2107},
                               {0x1a86, 0xe026}, {0x3553, 0xb001}};
    for (int i = 0; i < 5; i++) {
        const fp_pedal_model *m = fp_pedal_find_model(kb[i][0], kb[i][1]);
        assert_non_null(m);
        assert_int_equal(m->layout, FP_PEDAL_LAYOUT_KEYBOARD);
    }
    assert_int_equal(fp_pedal_find_model(0x05f3, 0x00ff)->layout, FP_PEDAL_LAYOUT_VEC);
    assert_null(fp_pedal_find_model(0x05f3, 0x00fe));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vec_single_pedals),
        cmocka_unit_test(test_vec_chords_and_no_change),
        cmocka_unit_test(test_keyboard_report_id),
        cmocka_unit_test(test_keyboard_boot_other_ids_rollover),
        cmocka_unit_test(test_diff_release_all),
        cmocka_unit_test(test_parse_keys),
        cmocka_unit_test(test_parse_vidpid),
        cmocka_unit_test(test_config),
        cmocka_unit_test(test_config_errors),
        cmocka_unit_test(test_access_error_text),
        cmocka_unit_test(test_models),
        cmocka_unit_test(test_keyboard_formats_split_report),
        cmocka_unit_test(test_report_descriptor),
        cmocka_unit_test(test_report_descriptor_items),
    };
    return cmocka_run_group_tests_name("pedal_decode", tests, NULL, NULL);
}
