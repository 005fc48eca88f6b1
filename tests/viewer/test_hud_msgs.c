/* The HUD's word wrap and message stack (ui/viewer/hud.c), without a display: every wrapped
 * line fits the width at the viewer's two scales and window widths, nothing is lost; a take's
 * confirmation stays through notes until the next take's replaces it; notes fade and go. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "hud.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static void test_wrap_fits(void **state)
{
    (void)state;
    const char *text = "mapping 'anchored': reload of /a/rather/long/path/to/libmap-anchored.so failed: "
                       "undefined symbol fp_mapping_entry_with_a_name_longer_than_any_line_could_hold_at_all_"
                       "even_at_the_smallest_scale_of_the_hud_and_then_some_more_characters_to_pass_the_width_of_a_line_of_six_hundred_"
                       "and_twenty_four_pixels_at_the_scale_of_one; keeping the old one";
    const float widths[2] = {640 - 16, 1280 - 16}, scales[2] = {1, 2};
    for (int k = 0; k < 2; k++) {
        char out[2048];
        size_t lines = fp_hud_wrap(text, widths[k], scales[k], out, sizeof out);
        size_t counted = 1, kept = 0;
        for (char *l = out, *e; l; l = e ? e + 1 : NULL) {
            e = strchr(l, '\n');
            char one[2048];
            snprintf(one, sizeof one, "%.*s", e ? (int)(e - l) : (int)strlen(l), l);
            float w = fp_render_text_width(one, scales[k]);
            print_message("%4.0f px: [%s] %.0f px\n", widths[k], one, w);
            assert_true(w <= widths[k]);
            counted += e != NULL;
        }
        for (const char *p = out; *p; p++) kept += *p != '\n';
        size_t want = 0;
        for (const char *p = text; *p; p++) want += *p != ' ';
        size_t spaces_left = 0;
        for (const char *p = out; *p; p++) spaces_left += *p == ' ';
        assert_int_equal(lines, counted);
        assert_true(lines >= 2);
        assert_int_equal(kept - spaces_left, want); /* every non-space character kept */
    }
    char small[16];
    fp_hud_wrap("a text longer than the buffer", 1000, 1, small, sizeof small);
    assert_true(strlen(small) < sizeof small);
}

static void test_confirmations_kept_notes_fade(void **state)
{
    (void)state;
    fp_hud_msgs s = {0};
    const int64_t sec = 1000000000LL;
    const fp_hud_msg *live[FP_HUD_MSGS];
    float alpha[FP_HUD_MSGS];
    fp_hud_say(&s, FP_HUD_TAKE, 0, "take 2: 40 frames");
    for (int i = 0; i < 10; i++) { /* more notes than the stack holds */
        char t[64];
        snprintf(t, sizeof t, "contact: note %d", i);
        fp_hud_say(&s, FP_HUD_NOTE, i * sec / 10, t);
    }
    size_t n = fp_hud_live(&s, sec, live, alpha);
    assert_int_equal(n, FP_HUD_MSGS);
    assert_string_equal(live[0]->text, "take 2: 40 frames"); /* oldest, still there */
    assert_string_equal(live[n - 1]->text, "contact: note 9");
    /* the same note again renews it rather than adding a line */
    fp_hud_say(&s, FP_HUD_NOTE, sec, "contact: note 9");
    assert_int_equal(fp_hud_live(&s, sec, live, alpha), FP_HUD_MSGS);
    /* fading: whole until the last second, half way through it, gone after */
    n = fp_hud_live(&s, (int64_t)((1.0 + FP_HUD_NOTE_S - 1.1) * sec), live, alpha);
    float a = -1;
    for (size_t i = 0; i < n; i++)
        if (!strcmp(live[i]->text, "contact: note 9")) a = alpha[i];
    assert_true(a > 0.95f);
    n = fp_hud_live(&s, (int64_t)((1.0 + FP_HUD_NOTE_S - 0.5) * sec), live, alpha);
    assert_true(n >= 2);
    assert_float_equal(alpha[n - 1], 0.5f, 0.02f);
    n = fp_hud_live(&s, 60 * sec, live, alpha);
    assert_int_equal(n, 1);
    assert_string_equal(live[0]->text, "take 2: 40 frames");
    assert_float_equal(alpha[0], 1.f, 0);
    /* replaced by its own kind only */
    fp_hud_say(&s, FP_HUD_SETTING, 61 * sec, "mapping unanchored");
    fp_hud_say(&s, FP_HUD_TAKE, 62 * sec, "take 3: 12 frames");
    n = fp_hud_live(&s, 3600 * sec, live, alpha);
    assert_int_equal(n, 2);
    assert_string_equal(live[0]->text, "mapping unanchored");
    assert_string_equal(live[1]->text, "take 3: 12 frames");
}

/* A warning (the hint that the hands never reach the face) outlives the notes after it: under
 * Xvfb, an OSC sender restarting every 0.15 s sent six 'sender ... took over' notes within a
 * second of the hint, and it was gone from the HUD (the stack's six lines all notes). */
static void test_warning_outlives_notes(void **state)
{
    (void)state;
    fp_hud_msgs s = {0};
    const int64_t sec = 1000000000LL;
    const fp_hud_msg *live[FP_HUD_MSGS];
    fp_hud_say(&s, FP_HUD_WARN, 0, "session: hands present for 3 s, but no fingertip came within 14 mm");
    for (int i = 0; i < 10; i++) {
        char t[64];
        snprintf(t, sizeof t, "osc: port 9125: sender %d took over", i);
        fp_hud_say(&s, FP_HUD_NOTE, i * sec / 10, t);
    }
    size_t n = fp_hud_live(&s, sec, live, NULL);
    assert_int_equal(n, FP_HUD_MSGS);
    assert_int_equal(live[0]->kind, FP_HUD_WARN);
    assert_string_equal(live[n - 1]->text, "osc: port 9125: sender 9 took over");
    /* it fades as a note does */
    assert_int_equal(fp_hud_live(&s, (int64_t)(FP_HUD_NOTE_S * sec) - 1, live, NULL) >= 1, 1);
    assert_int_equal(live[0]->kind, FP_HUD_WARN);
    /* in a room for two lines, it and the newest note */
    n = fp_hud_fit(&s, sec, 1008, 2, 2 * (fp_render_text_height("x", 2) + 4), live, NULL);
    assert_int_equal(n, 2);
    assert_int_equal(live[0]->kind, FP_HUD_WARN);
    assert_string_equal(live[1]->text, "osc: port 9125: sender 9 took over");
}

/* The stack fits the room left above the window's bottom (the take strip, its lanes, "? keys"):
 * before, six long notes ran 400 px down a 640 px window, past the strip, and the take's
 * confirmation, drawn last as the newest, lay under the strip, never seen. Now the oldest
 * fading notes are left out first and the take's line stays. */
static void test_fit_room(void **state)
{
    (void)state;
    fp_hud_msgs s = {0};
    const int64_t sec = 1000000000LL;
    const fp_hud_msg *live[FP_HUD_MSGS];
    float alpha[FP_HUD_MSGS];
    const float width = 1024 - 16, scale = 2;
    char t[400];
    for (int i = 0; i < 5; i++) {
        snprintf(t, sizeof t, "engine: the skin followed the fingertips %d%% this gesture (mean of 15; least 22%%, "
                 "under 90%% in 10; longest drag 100.8 mm; 100%% of what the rig allowed: it holds back a push "
                 "toward the skull or the jaw)", 50 + i);
        fp_hud_say(&s, FP_HUD_NOTE, i * sec / 10, t);
    }
    fp_hud_say(&s, FP_HUD_TAKE, sec, "take 1: 74 frames, 0 dropped, 23:57:17:49 - 23:57:19:17, "
                                     "takes/scene1_T001.fptake   V: review");
    /* all of them, as drawn: more than the room between the HUD's figures and the strip */
    size_t all = fp_hud_live(&s, sec, live, alpha);
    assert_int_equal(all, 6);
    float whole = 0;
    for (size_t i = 0; i < all; i++) {
        char w[2 * FP_HUD_MSG_LEN];
        fp_hud_wrap(live[i]->text, width, scale, w, sizeof w);
        whole += fp_render_text_height(w, scale) + 2 * scale;
    }
    const float room = 300; /* 640 px: the strip's text at 536, the messages from 228 */
    assert_true(whole > room);
    assert_int_equal(fp_hud_fit(&s, sec, width, scale, 1e6f, live, alpha), all); /* room for all */
    size_t n = fp_hud_fit(&s, sec, width, scale, room, live, alpha);
    assert_true(n >= 2 && n < all);
    float used = 0;
    uint64_t last_seq = 0;
    for (size_t i = 0; i < n; i++) {
        char w[2 * FP_HUD_MSG_LEN];
        fp_hud_wrap(live[i]->text, width, scale, w, sizeof w);
        used += fp_render_text_height(w, scale) + 2 * scale;
        assert_true(i == 0 || live[i]->seq > last_seq); /* oldest first */
        last_seq = live[i]->seq;
        assert_float_equal(alpha[i], 1.f, 0);
    }
    assert_true(used <= room);
    assert_string_equal(live[n - 1]->text, "take 1: 74 frames, 0 dropped, 23:57:17:49 - 23:57:19:17, "
                                           "takes/scene1_T001.fptake   V: review");
    assert_non_null(strstr(live[n - 2]->text, "54%")); /* the newest note kept, the oldest gone */
    /* a room under one message: none, the take's line neither (nothing drawn past the room) */
    assert_int_equal(fp_hud_fit(&s, sec, width, scale, 10, live, alpha), 0);
    /* a room for the take's line alone keeps it over every note */
    n = fp_hud_fit(&s, sec, width, scale, 60, live, NULL);
    assert_int_equal(n, 1);
    assert_int_equal(live[0]->kind, FP_HUD_TAKE);
}

/* The reach line: the least reach and the drag; with a rig whose clamp held a push back, what
 * it allowed too; fingertips on the skull or the jaw named; nothing without a touching
 * vector. */
static void test_reach_line(void **state)
{
    (void)state;
    char out[200];
    const float r[3] = {1.0f, 0.09f, 0.5f}, a[3] = {1.0f, 1.0f, 1.0f}, z[3] = {0.f, 0.f, 0.f};
    fp_hud_reach_line(r, 3, NULL, 0, 0, 76.44, out, sizeof out);
    assert_string_equal(out, "\nskin follows the fingertips 9%  (drag 76.4 mm)");
    fp_hud_reach_line(r, 3, a, 3, 0, 76.44, out, sizeof out);
    assert_string_equal(out, "\nskin follows the fingertips 9%  (drag 76.4 mm; 100% of what the rig allows)");
    fp_hud_reach_line(a, 3, a, 3, 0, 10.0, out, sizeof out); /* the rig held nothing back */
    assert_string_equal(out, "\nskin follows the fingertips 100%  (drag 10.0 mm)");
    fp_hud_reach_line(r, 0, a, 3, 0, 10.0, out, sizeof out);
    assert_string_equal(out, "");
    /* one of three grabbed the skull: the other two followed all the rig allowed */
    fp_hud_reach_line(r, 3, a, 2, 1, 20.0, out, sizeof out);
    assert_string_equal(out, "\nskin follows the fingertips 9%  (drag 20.0 mm; 100% of what the rig allows; "
                             "1 on the skull or the jaw, kept still)");
    /* all on the skull: the 0% is the rig's, said so */
    fp_hud_reach_line(z, 3, NULL, 0, 3, 20.0, out, sizeof out);
    assert_string_equal(out, "\nskin follows the fingertips 0%  (drag 20.0 mm; on the skull or the jaw: the rig "
                             "keeps them still)");
}

/* The contact line: nothing for a whole frame; what held a scaled-back one, and how much of
 * its motion was kept (before, the badge said ENGAGED and nothing said why the face stopped) */
static void test_contact_line(void **state)
{
    (void)state;
    char out[200];
    fp_hud_contact_line(1.0, 1.0, 0, out, sizeof out);
    assert_string_equal(out, "");
    fp_hud_contact_line(0.0, 0.083, 0, out, sizeof out);
    assert_string_equal(out, "\ncontact guard kept 8% of this frame's motion: the skin would have folded over");
    fp_hud_contact_line(0.5, 0.9, 3, out, sizeof out);
    assert_string_equal(out, "\ncontact guard kept 90% of this frame's motion: the surface would have passed "
                             "through itself");
    /* held back by a hair: not "kept 100%" beside the HELD badge (before: 100%) */
    fp_hud_contact_line(0.9, 0.996, 0, out, sizeof out);
    assert_string_equal(out, "\ncontact guard kept over 99% of this frame's motion: the skin would have folded over");
    fp_hud_contact_line(0.9, 0.994, 0, out, sizeof out);
    assert_string_equal(out, "\ncontact guard kept 99% of this frame's motion: the skin would have folded over");
    fp_hud_contact_line(0.5, 0.9, 3, out, 1);
    assert_string_equal(out, "");
}

/* The unit's line: a face in metres reads 1000 mm per mesh unit (before: "1e+03 mm per mesh
 * unit", %.3g), as run and calibrate print it; the how up to its first ':'. */
static void test_scale_line(void **state)
{
    (void)state;
    char out[120];
    assert_string_equal(fp_hud_scale_line(1000, "from the rig rigs/ict-facekit.json: placed", out, sizeof out),
                        "1000 mm per mesh unit, from the rig rigs/ict-facekit.json");
    assert_string_equal(fp_hud_scale_line(49.0345, "detected from the head", out, sizeof out),
                        "49.03 mm per mesh unit, detected from the head");
    assert_string_equal(fp_hud_scale_line(10, "--mm-per-unit", out, sizeof out), "10 mm per mesh unit, --mm-per-unit");
}

/* The gesture's badge: "limited" only where the fold-over guard stopped it short; the
 * contact guard scaling a frame back is HELD, not LIMITED (before, both read LIMITED) */
static void test_gesture_badge(void **state)
{
    (void)state;
    assert_int_equal(fp_hud_gesture_badge(1.0, 1.0), FP_HUD_ENGAGED);
    assert_int_equal(fp_hud_gesture_badge(0.35, 1.0), FP_HUD_LIMITED);
    assert_int_equal(fp_hud_gesture_badge(0.35, 0.5), FP_HUD_LIMITED);
    assert_int_equal(fp_hud_gesture_badge(1.0, 0.5), FP_HUD_HELD);
    assert_string_equal(fp_hud_badge_name(FP_HUD_HELD), "HELD");
    assert_string_equal(fp_hud_badge_name(FP_HUD_LIMITED), "LIMITED");
    /* every badge's colour its own */
    for (int a = 0; a < FP_HUD_BADGES; a++)
        for (int b = a + 1; b < FP_HUD_BADGES; b++) {
            const float *x = fp_hud_badge_color((fp_hud_badge)a), *y = fp_hud_badge_color((fp_hud_badge)b);
            assert_true(fabsf(x[0] - y[0]) + fabsf(x[1] - y[1]) + fabsf(x[2] - y[2]) > 0.3f);
        }
}

/* The key list's layout (fp_hud_help_layout_make) fits whole every window from 200x400,
 * 280x300 and 640x240 (two columns) to 1280x720: the backdrop inside the window, each
 * column's lines within its share of the width, every character of the list kept (blanks
 * aside). A list as live's: aligned columns of keys, long lines of words. Smaller windows
 * get the smallest layout from the top, its last lines cut. */
static void test_help_layout_fits(void **state)
{
    (void)state;
    const char *text = "keys\n space  pause / run\n E      engage      C  commit\n"
                       " X      cancel      Z  undo commit\n R      back to the loaded shape\n"
                       " J / K  open / close the jaw (rig)\n G      rig: regions, landmarks, hinge axis\n"
                       " 1 / 2  anchored / unanchored\n [ / ]  radius down / up\n"
                       " W wireframe  S screenshot  F frame\n H hands  Tab HUD  ? this list\n"
                       " T      record a take (start / stop)\n V      review the last take / back to live\n"
                       " P      play / pause the last take\n , / .  a frame back / on; mouse on the strip scrubs\n"
                       " Esc    leave the review; else quit\n I punch in/out; L layer, M mute, O solo (--over)\n"
                       "mouse: left orbit, right pan, wheel zoom\ndrop a mesh file on the window to load it\n"
                       "spheres: green where a fingertip's support reaches the skin;\n"
                       "lines: each fingertip to its nearest skin point";
    size_t want = 0;
    for (const char *p = text; *p; p++) want += *p != ' ' && *p != '\n';
    const int ws[] = {200, 240, 280, 320, 480, 640, 1280}, hs[] = {240, 300, 360, 400, 480, 600, 720};
    for (size_t i = 0; i < sizeof ws / sizeof *ws; i++)
        for (size_t j = 0; j < sizeof hs / sizeof *hs; j++) {
            const int w = ws[i], h = hs[j];
            if ((w < 280 && h < 400) || (w < 640 && h < 300)) continue; /* (too small: cut, said) */
            const float scale = h >= 600 ? 2.f : 1.f; /* (the viewer's) */
            fp_hud_help_layout l;
            assert_int_equal(fp_hud_help_layout_make(text, w, h, scale, &l), 0);
            print_message("%4dx%-4d: scale %.0f, %d column(s), pad %.0f, box %.0fx%.0f at %.0f,%.0f\n", w, h,
                          l.scale, l.columns, l.pad, l.w, l.h, l.x, l.y);
            assert_true(l.fits);
            assert_true(l.x >= 0 && l.y >= 0 && l.x + l.w <= (float)w && l.y + l.h <= (float)h);
            size_t kept = 0;
            for (int c = 0; c < l.columns; c++) {
                assert_non_null(l.text[c]);
                float right = c + 1 < l.columns ? l.col_x[c + 1] : l.w - l.pad + 0.5f;
                assert_true(l.col_x[c] + fp_render_text_width(l.text[c], l.scale) <= right);
                for (const char *p = l.text[c]; *p; p++) kept += *p != ' ' && *p != '\n';
            }
            assert_int_equal(kept, want);
            fp_hud_help_layout_free(&l);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gesture_badge),
        cmocka_unit_test(test_contact_line),
        cmocka_unit_test(test_wrap_fits),
        cmocka_unit_test(test_help_layout_fits),
        cmocka_unit_test(test_confirmations_kept_notes_fade),
        cmocka_unit_test(test_warning_outlives_notes),
        cmocka_unit_test(test_fit_room),
        cmocka_unit_test(test_scale_line),
        cmocka_unit_test(test_reach_line),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
