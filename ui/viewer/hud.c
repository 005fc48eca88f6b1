/* The live viewer's HUD parts: badge, message stack, key list backdrop, word wrap (hud.h). */
#define _GNU_SOURCE
#include "hud.h"
#include "fp_text.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the badge -------------------------------------------------------------------------- */

static const char *const badge_names[FP_HUD_BADGES] = {
    "idle", "committed", "ENGAGED", "LIMITED", "HELD", "PAUSED", "REC", "PLAYING", "REVIEW"};

/* Far apart in hue (the tests tell them apart by colour), none of the skin's, the hands'
 * (blue, orange) or the background's. */
static const float badge_colors[FP_HUD_BADGES][4] = {
    {0.45f, 0.47f, 0.5f, 1.f},   /* idle: grey */
    {0.1f, 0.6f, 0.62f, 1.f},    /* committed: teal */
    {0.2f, 0.78f, 0.25f, 1.f},   /* ENGAGED: green */
    {1.f, 0.7f, 0.f, 1.f},       /* LIMITED: amber */
    {0.95f, 0.3f, 0.62f, 1.f},   /* HELD: pink */
    {0.92f, 0.92f, 0.92f, 1.f},  /* PAUSED: white */
    {0.9f, 0.08f, 0.08f, 1.f},   /* REC: red */
    {0.15f, 0.35f, 0.95f, 1.f},  /* PLAYING: blue */
    {0.65f, 0.25f, 0.85f, 1.f},  /* REVIEW: purple */
};

fp_hud_badge fp_hud_gesture_badge(double guard_reached, double collide_t)
{
    if (guard_reached < 1.0) return FP_HUD_LIMITED;
    return collide_t < 1.0 ? FP_HUD_HELD : FP_HUD_ENGAGED;
}

const char *fp_hud_badge_name(fp_hud_badge b)
{
    return (unsigned)b < FP_HUD_BADGES ? badge_names[b] : "?";
}

const float *fp_hud_badge_color(fp_hud_badge b)
{
    return badge_colors[(unsigned)b < FP_HUD_BADGES ? b : FP_HUD_IDLE];
}

/* The badge's text: its state's word, then its detail (REC's timecode). */
static void badge_text(fp_hud_badge b, const char *detail, char *text, size_t n)
{
    snprintf(text, n, "%s%s%s", fp_hud_badge_name(b), detail && *detail ? "  " : "", detail ? detail : "");
}

float fp_hud_badge_width(fp_hud_badge b, const char *detail, float scale)
{
    char text[128];
    badge_text(b, detail, text, sizeof text);
    return fmaxf(64 * scale, fp_render_text_width(text, scale) + 12 * scale);
}

float fp_hud_draw_badge(fp_render *r, int w, int h, float x, float y, float scale,
                        fp_hud_badge b, const char *detail)
{
    static const float ink[4] = {0.04f, 0.04f, 0.06f, 1.f};
    char text[128];
    badge_text(b, detail, text, sizeof text);
    float bw = fp_hud_badge_width(b, detail, scale), bh = 15 * scale;
    fp_render_rect(r, w, h, x, y, bw, bh, fp_hud_badge_color(b));
    fp_render_text(r, w, h, x + 6 * scale, y + 4 * scale, scale, text, ink);
    return bh;
}

/* ---- word wrap -------------------------------------------------------------------------- */

size_t fp_hud_wrap(const char *text, float max_px, float scale, char *out, size_t n)
{
    if (!n) return 0;
    size_t o = 0, start = 0, space = SIZE_MAX, lines = 1;
    out[0] = '\0';
    for (const char *p = text; *p && o + 2 < n; p++) {
        if (*p == '\n') {
            out[o++] = '\n';
            start = o;
            space = SIZE_MAX;
            lines++;
            continue;
        }
        out[o++] = *p;
        out[o] = '\0';
        if (*p == ' ') {
            space = o - 1;
            continue;
        }
        while (o - start > 1 && fp_render_text_width(out + start, scale) > max_px) {
            if (space != SIZE_MAX && space > start) { /* at the last space */
                out[space] = '\n';
                start = space + 1;
            } else { /* a word longer than the line: its last character to a new line */
                if (o + 2 >= n) {
                    out[--o] = '\0';
                    return lines;
                }
                out[o] = out[o - 1];
                out[o - 1] = '\n';
                start = o++;
                out[o] = '\0';
            }
            space = SIZE_MAX;
            lines++;
        }
    }
    out[o] = '\0';
    return lines;
}

/* ---- the message stack ------------------------------------------------------------------ */

static bool kept_kind(int kind) { return kind == FP_HUD_TAKE || kind == FP_HUD_SETTING; }

/* The order messages make room in: notes and answers (0), warnings (1), confirmations (2). */
static int drop_rank(int kind) { return kept_kind(kind) ? 2 : kind == FP_HUD_WARN; }

static void drop_expired(fp_hud_msgs *s, int64_t now)
{
    for (size_t i = 0; i < s->count;) {
        if (s->m[i].until <= now) s->m[i] = s->m[--s->count];
        else i++;
    }
}

void fp_hud_say(fp_hud_msgs *s, int kind, int64_t now, const char *text)
{
    if (kind < 0 || kind >= FP_HUD_KINDS) kind = FP_HUD_INFO;
    drop_expired(s, now);
    fp_hud_msg *slot = NULL;
    for (size_t i = 0; i < s->count && !slot; i++)
        if (s->m[i].kind == kind && (kept_kind(kind) || !strncmp(s->m[i].text, text, FP_HUD_MSG_LEN - 1)))
            slot = &s->m[i];
    if (!slot && s->count < FP_HUD_MSGS) slot = &s->m[s->count++];
    if (!slot) { /* full: the oldest note or answer makes room, else warning, else the oldest */
        fp_hud_msg *oldest = NULL, *oldest_fading = NULL, *oldest_plain = NULL;
        for (size_t i = 0; i < s->count; i++) {
            fp_hud_msg *m = &s->m[i];
            if (!oldest || m->seq < oldest->seq) oldest = m;
            if (!kept_kind(m->kind) && (!oldest_fading || m->seq < oldest_fading->seq)) oldest_fading = m;
            if (drop_rank(m->kind) == 0 && (!oldest_plain || m->seq < oldest_plain->seq)) oldest_plain = m;
        }
        slot = oldest_plain ? oldest_plain : oldest_fading ? oldest_fading : oldest;
    }
    slot->kind = kind;
    slot->seq = s->next_seq++;
    slot->until = kept_kind(kind) ? INT64_MAX
                                  : now + (int64_t)((kind == FP_HUD_INFO ? FP_HUD_INFO_S : FP_HUD_NOTE_S) * 1e9);
    snprintf(slot->text, sizeof slot->text, "%s", text);
}

static int by_seq(const void *a, const void *b)
{
    const fp_hud_msg *x = *(const fp_hud_msg *const *)a, *y = *(const fp_hud_msg *const *)b;
    return x->seq < y->seq ? -1 : x->seq > y->seq;
}

size_t fp_hud_live(fp_hud_msgs *s, int64_t now, const fp_hud_msg *out[FP_HUD_MSGS],
                   float alpha[FP_HUD_MSGS])
{
    drop_expired(s, now);
    for (size_t i = 0; i < s->count; i++) out[i] = &s->m[i];
    qsort(out, s->count, sizeof *out, by_seq);
    for (size_t i = 0; alpha && i < s->count; i++) {
        double left = out[i]->until == INT64_MAX ? 1.0 : (double)(out[i]->until - now) * 1e-9;
        alpha[i] = (float)fmin(1.0, fmax(0.0, left));
    }
    return s->count;
}

/* The height one message takes wrapped to max_px at scale, with the gap after it. */
static float msg_height(const char *text, float max_px, float scale)
{
    char wrapped[2 * FP_HUD_MSG_LEN];
    fp_hud_wrap(text, max_px, scale, wrapped, sizeof wrapped);
    return fp_render_text_height(wrapped, scale) + 2 * scale;
}

size_t fp_hud_fit(fp_hud_msgs *s, int64_t now, float max_px, float scale, float room,
                  const fp_hud_msg *out[FP_HUD_MSGS], float alpha[FP_HUD_MSGS])
{
    const fp_hud_msg *live[FP_HUD_MSGS];
    float a[FP_HUD_MSGS], hgt[FP_HUD_MSGS], total = 0;
    bool keep[FP_HUD_MSGS];
    size_t n = fp_hud_live(s, now, live, a);
    for (size_t i = 0; i < n; i++) {
        hgt[i] = msg_height(live[i]->text, max_px, scale);
        total += hgt[i];
        keep[i] = true;
    }
    /* leave out the oldest notes, then warnings, then confirmations, until the rest fit */
    for (int pass = 0; pass < 3; pass++)
        for (size_t i = 0; i < n && total > room; i++)
            if (keep[i] && drop_rank(live[i]->kind) <= pass) {
                keep[i] = false;
                total -= hgt[i];
            }
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        if (keep[i]) {
            if (alpha) alpha[k] = a[i];
            out[k++] = live[i];
        }
    return k;
}

float fp_hud_draw_msgs(fp_hud_msgs *s, fp_render *r, int w, int h, float x, float y,
                       float max_px, float scale, float room, const float color[4], int64_t now)
{
    const fp_hud_msg *live[FP_HUD_MSGS];
    float alpha[FP_HUD_MSGS];
    size_t n = fp_hud_fit(s, now, max_px, scale, room, live, alpha);
    float y0 = y;
    char wrapped[2 * FP_HUD_MSG_LEN];
    for (size_t i = 0; i < n; i++) {
        float c[4] = {color[0], color[1], color[2], color[3] * alpha[i]};
        fp_hud_wrap(live[i]->text, max_px, scale, wrapped, sizeof wrapped);
        y += fp_render_text(r, w, h, x, y, scale, wrapped, c) + 2 * scale;
    }
    return y - y0;
}

/* ---- the key list ----------------------------------------------------------------------- */

static const float backdrop[4] = {0.03f, 0.035f, 0.05f, 0.93f};

const float *fp_hud_backdrop_color(void) { return backdrop; }

void fp_hud_draw_help(fp_render *r, int w, int h, float scale, const char *text,
                      const float color[4])
{
    fp_hud_help_layout l;
    if (fp_hud_help_layout_make(text, w, h, scale, &l)) return;
    fp_render_rect(r, w, h, l.x, l.y, l.w, l.h, backdrop);
    for (int c = 0; c < l.columns; c++)
        if (l.text[c]) fp_render_text(r, w, h, l.x + l.col_x[c], l.y + l.pad, l.scale, l.text[c], color);
    fp_hud_help_layout_free(&l);
}

/* The smallest of n reaches (0 for none). */
static float least_of(const float *r, size_t n)
{
    float least = n ? r[0] : 0.f;
    for (size_t i = 1; i < n; i++) least = r[i] < least ? r[i] : least;
    return least;
}

void fp_hud_reach_line(const float *reach, size_t n, const float *allowed, size_t na, size_t held,
                       double drag_mm, char *out, size_t len)
{
    if (!len) return;
    out[0] = 0;
    if (!n) return;
    float least = least_of(reach, n), least_allowed = least_of(allowed, na);
    char rig[128] = ""; /* a push toward the bone held back, the bone itself kept still */
    int k = 0;
    if (na && fabsf(least_allowed - least) >= 0.005f)
        k = snprintf(rig, sizeof rig, "; %.0f%% of what the rig allows", 100.0 * least_allowed);
    if (held && k >= 0 && (size_t)k < sizeof rig) {
        if (held < n)
            snprintf(rig + k, sizeof rig - (size_t)k, "; %zu on the skull or the jaw, kept still", held);
        else
            snprintf(rig + k, sizeof rig - (size_t)k, "; on the skull or the jaw: the rig keeps them still");
    }
    snprintf(out, len, "\nskin follows the fingertips %.0f%%  (drag %.1f mm%s)", 100.0 * least, drag_mm, rig);
}

void fp_hud_contact_line(double t, double kept, long pairs, char *out, size_t len)
{
    if (!len) return;
    out[0] = 0;
    if (!(t < 1.0)) return;
    char share[16]; /* (a frame held back by a hair: "over 99%", not "100%" beside HELD) */
    fp_text_share_held(kept, share, sizeof share);
    snprintf(out, len, "\ncontact guard kept %s of this frame's motion: %s", share,
             pairs ? "the surface would have passed through itself" : "the skin would have folded over");
}

const char *fp_hud_scale_line(double mm_per_unit, const char *how, char *out, size_t len)
{
    if (len) snprintf(out, len, "%.4g mm per mesh unit, %.*s", mm_per_unit, (int)strcspn(how, ":"), how);
    return out;
}
