/* hud.h: the live viewer's HUD parts (internal to ui/viewer): the state badge, the message
 * stack and the key list's backdrop, and the word wrap they share (issue 53 item 1).
 *
 * The badge: a filled box at the top left in the state's colour (fp_hud_badge_color) with
 * the state's word (REC also its timecode) in near-black, so that the state reads at a
 * glance: idle grey, committed teal, ENGAGED green, LIMITED amber (the fold-over guard held
 * the gesture back: fp_hud_gesture_badge), HELD pink (the contact guard scaled its last frame
 * back), PAUSED white, REC red, PLAYING
 * blue, REVIEW purple.
 *
 * The message stack (fp_hud_msgs): a few lines under the HUD's figures, oldest first, each
 * wrapped to the window's width. Confirmations (kinds FP_HUD_TAKE, FP_HUD_SETTING: a take
 * written, a mapping set) stay until a message of their own kind replaces them; notes
 * (FP_HUD_NOTE: the session's log lines; FP_HUD_WARN: its warnings and errors) and answers
 * (FP_HUD_INFO: a key's reply, an error) stay FP_HUD_NOTE_S / FP_HUD_INFO_S seconds, fading
 * out over the last one. A note never pushes out a warning or a confirmation: when the stack
 * is full the oldest note or answer goes, else the oldest warning. The stack drawn stops
 * above the window's bottom (fp_hud_fit), leaving out messages in the same order.
 *
 * Everything here but the drawing functions is plain C (no GL): the wrap and the stack are
 * tested without a display (tests/viewer/test_hud_msgs.c). Drawing needs the renderer's
 * context current. Threads: the viewer's.
 */
#ifndef FP_UI_HUD_H
#define FP_UI_HUD_H

#include "render.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/** The badge's states, in the order the viewer picks them (the first that holds). */
typedef enum fp_hud_badge {
    FP_HUD_IDLE, FP_HUD_COMMITTED, FP_HUD_ENGAGED, FP_HUD_LIMITED, FP_HUD_HELD, FP_HUD_PAUSED,
    FP_HUD_REC, FP_HUD_PLAYING, FP_HUD_REVIEW, FP_HUD_BADGES
} fp_hud_badge;

/** The state's word ("idle", "committed", "ENGAGED", "LIMITED", "HELD", "PAUSED", "REC",
 *  "PLAYING", "REVIEW"); "?" out of range. Static storage. */
const char *fp_hud_badge_name(fp_hud_badge b);
/** An engaged gesture's badge from its last deforming frame's guards: FP_HUD_LIMITED where
 *  the fold-over guard stopped it short (guard_reached < 1: fingertips converging onto one
 *  point, which no injective map delivers), else FP_HUD_HELD where the contact guard scaled
 *  the frame back (collide_t < 1: the skin would have passed through itself or folded
 *  over; not a limit of the deformation), else FP_HUD_ENGAGED. Pure; any thread. */
fp_hud_badge fp_hud_gesture_badge(double guard_reached, double collide_t);

/** The badge's fill colour, RGBA in [0, 1] (alpha 1: drawn exactly, for pixel checks);
 *  idle's for a value out of range. Static storage. */
const float *fp_hud_badge_color(fp_hud_badge b);

/** The badge's width in pixels at scale (as fp_hud_draw_badge draws it). Plain C. */
float fp_hud_badge_width(fp_hud_badge b, const char *detail, float scale);
/** Draw the badge at pixel (x, y) from the top left of a w x h framebuffer: the state's
 *  word, then `detail` (the REC timecode; NULL or "" for none), on the state's colour, text
 *  scaled by `scale` (1 or 2). Returns the box's height in pixels. */
float fp_hud_draw_badge(fp_render *r, int w, int h, float x, float y, float scale,
                        fp_hud_badge b, const char *detail);

/** Word wrap for stb_easy_font text at `scale`: copy text to out (n bytes, always
 *  terminated), breaking lines (at spaces, or inside a word longer than a line) so that no
 *  line is wider than max_px pixels (fp_render_text_width); the text's own newlines are
 *  kept. A line never holds less than one character. Returns the number of lines written. */
size_t fp_hud_wrap(const char *text, float max_px, float scale, char *out, size_t n);

/** The HUD's reach line (skin_reach.h), into out (len bytes, always terminated): "\nskin
 *  follows the fingertips 9%  (drag 76.4 mm)", the least of the n reaches (fractions, 1: the
 *  whole way) of the last deforming frame and its longest drag in mm; where a rig's reach
 *  (the na reaches against what it allowed) differs by half a point or more, "...; 100% of
 *  what the rig allows)"; where `held` of the n grabbed the skull or the jaw (the rig keeps
 *  them still, fp_frame_stats.reach_held), "...; 2 on the skull or the jaw, kept still)", or
 *  with all of them held "...; on the skull or the jaw: the rig keeps them still)". Empty
 *  with n == 0. Plain C; any thread. */
void fp_hud_reach_line(const float *reach, size_t n, const float *allowed, size_t na, size_t held,
                       double drag_mm, char *out, size_t len);

/** The HUD's contact line, into out (len bytes, always terminated): where the contact guard
 *  scaled the last deforming frame back (t < 1: fp_frame_stats.collide_t), "\ncontact guard
 *  kept 8% of this frame's motion: the skin would have folded over" (pairs == 0: triangles
 *  turning over alone, fp_frame_stats.collide_pairs) or "...: the surface would have passed
 *  through itself"; kept: fp_frame_stats.collide_kept. Empty where t >= 1. Plain C; any
 *  thread. */
void fp_hud_contact_line(double t, double kept, long pairs, char *out, size_t len);

/* FP_HUD_WARN: a note from a warning or an error (the hint that the hands never reach the
 * face, a hand gone): it fades as a note does, but notes and answers make room before it. */
enum { FP_HUD_TAKE, FP_HUD_SETTING, FP_HUD_NOTE, FP_HUD_INFO, FP_HUD_WARN, FP_HUD_KINDS };
#define FP_HUD_MSGS 6          /* lines of the stack at most */
#define FP_HUD_MSG_LEN 512     /* bytes a message keeps (longer ones are cut) */
#define FP_HUD_NOTE_S 6.0      /* seconds a note stays (the last one fading) */
#define FP_HUD_INFO_S 4.0      /* seconds an answer stays */

typedef struct fp_hud_msg {
    int kind;                  /* FP_HUD_TAKE ... FP_HUD_INFO */
    int64_t until;             /* host time (ns) it is gone; INT64_MAX: kept (confirmations) */
    uint64_t seq;              /* arrival order */
    char text[FP_HUD_MSG_LEN];
} fp_hud_msg;

typedef struct fp_hud_msgs {
    fp_hud_msg m[FP_HUD_MSGS];
    size_t count;              /* entries in use (in no particular order; seq orders them) */
    uint64_t next_seq;
} fp_hud_msgs;

/** Add a message of `kind` at host time now (ns): a confirmation replaces the one of its
 *  kind; the same text as a live message of its kind renews that one; otherwise it is
 *  appended, the oldest note or answer (else the oldest warning, else the oldest) making room
 *  when the stack is full.
 *  Expired messages go first. A kind out of range counts as FP_HUD_INFO. */
void fp_hud_say(fp_hud_msgs *s, int kind, int64_t now, const char *text);

/** The live messages at now, oldest first: up to FP_HUD_MSGS pointers into s written to out;
 *  alpha (may be NULL) gets each one's opacity in [0, 1] (1 until its last second). Expired
 *  messages are dropped. Returns how many. */
size_t fp_hud_live(fp_hud_msgs *s, int64_t now, const fp_hud_msg *out[FP_HUD_MSGS],
                   float alpha[FP_HUD_MSGS]);

/** The live messages at now (as fp_hud_live) that fit `room` pixels of height, each wrapped
 *  to max_px at scale and followed by a 2 x scale gap, as fp_hud_draw_msgs draws them: where
 *  they do not all fit, the oldest notes and answers are left out first, then the oldest
 *  warnings, then the oldest confirmations, so that the newest confirmation (a take written) is the last to go. Written
 *  oldest first to out, with alpha (may be NULL) as fp_hud_live's. Returns how many (0 where
 *  room is under one message). Plain C, no GL. */
size_t fp_hud_fit(fp_hud_msgs *s, int64_t now, float max_px, float scale, float room,
                  const fp_hud_msg *out[FP_HUD_MSGS], float alpha[FP_HUD_MSGS]);

/** Draw the live messages that fit `room` pixels of height (fp_hud_fit) at (x, y), each
 *  wrapped to max_px, in `color` faded by its alpha; returns the height drawn (at most
 *  room). */
float fp_hud_draw_msgs(fp_hud_msgs *s, fp_render *r, int w, int h, float x, float y,
                       float max_px, float scale, float room, const float color[4], int64_t now);

/** The HUD's line of the mesh's unit into out (len bytes; returns out): "1000 mm per mesh
 *  unit, from the rig ..." (how: fp_head's, up to its first ':'), mm_per_unit in %.4g as the
 *  other commands print it (so a face in metres reads 1000, not 1e+03). */
const char *fp_hud_scale_line(double mm_per_unit, const char *how, char *out, size_t len);

/** The key list centred in the window on a near-opaque dark backdrop (so that it reads over
 *  the face), laid out by fp_hud_help_layout_make to fit the window. */
void fp_hud_draw_help(fp_render *r, int w, int h, float scale, const char *text,
                      const float color[4]);

/** The key list's layout in a w x h window (pixels): its text wrapped in one or two columns,
 *  each column's lines in text[c] (owned: fp_hud_help_layout_free) drawn at (x + col_x[c],
 *  y + pad) at `scale`, on the backdrop x, y, w, h (pixels). */
typedef struct fp_hud_help_layout {
    float scale, pad;
    int columns;              /* 1 or 2 */
    char *text[2];            /* each column's wrapped lines; NULL past columns */
    float col_x[2];           /* each column's left, from x */
    float x, y, w, h;         /* the backdrop */
    bool fits;                /* false: no layout fits; the smallest, from the top (cut) */
} fp_hud_help_layout;

/** Lay out text (lines, blanks aligning its columns) for a w x h window at the viewer's scale
 *  (1 or 2): the first that fits whole of the viewer's scale then 1, the text as written then
 *  without its alignment (runs of blanks shortened: fewer lines wrap), one column then two
 *  (a short window), a padding of 10 then 3 (x scale). Returns 0 (*l to be freed with
 *  fp_hud_help_layout_free), or -1 out of memory or a window too narrow for a character
 *  (*l empty). No GL: [any-thread]. */
int fp_hud_help_layout_make(const char *text, int w, int h, float scale, fp_hud_help_layout *l);
void fp_hud_help_layout_free(fp_hud_help_layout *l);

/** The backdrop's colour (RGBA): the test's reference. Static storage. */
const float *fp_hud_backdrop_color(void);

#endif
