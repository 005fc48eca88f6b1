/* Takes in the live viewer: record toggle, countdown, REC, review on a timeline strip. */
#define _GNU_SOURCE
#include "takes.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void fp_vtakes_init(fp_vtakes *t, const char *dir, const char *slate, double countdown_s,
                    fp_session_options *so)
{
    memset(t, 0, sizeof *t);
    t->playhead = -1;
    t->countdown_s = countdown_s;
    fp_session_take_options o = {.dir = dir, .slate = slate};
    fp_session_take_init(&t->take, &o, so);
    snprintf(t->slate, sizeof t->slate, "%s", t->take.opt.slate);
    t->enabled = dir != NULL;
    if (t->enabled) {
        so->record = fp_session_take_sink;
        so->record_user = &t->take;
    }
}

/* A take opened for review: its reader and a session of the same mesh (no inputs). Made on
 * the opener's thread (below) or, where that could not start, when first asked. */
static int open_review(const char *mesh_path, const fp_plugin_path *plugin_path, const char *take_path,
                       fp_take_reader **reader, fp_session **rs, char *msg, size_t n)
{
    char err[1024];
    int rc = fp_take_reader_open(take_path, reader, err, sizeof err);
    if (rc) {
        snprintf(msg, n, "review: %.900s", err);
        return rc;
    }
    const fp_take_header *hd = fp_take_reader_header(*reader);
    fp_session_options ro = {.mesh_path = mesh_path, .mapping = "anchored", .radius = hd->radius,
                             .radius_name = "the take's radius", /* (not --radius: the file's) */
                             .plugin_path = plugin_path, .rig_path = hd->rig_path ? hd->rig_path : "none"};
    if ((rc = fp_session_create(&ro, rs, err, sizeof err))) {
        snprintf(msg, n, "review: %.900s", err);
        fp_take_reader_close(reader);
    }
    return rc;
}

static void *opener_main(void *arg)
{
    fp_vtakes_opener *o = arg;
    o->rc = open_review(o->mesh_path, o->plugin_path, o->take_path, &o->reader, &o->rs, o->err, sizeof o->err);
    return NULL;
}

/* Wait for the opener; its reader and session (NULL where it failed) into *reader, *rs. */
static int opener_join(fp_vtakes *t, fp_take_reader **reader, fp_session **rs)
{
    fp_vtakes_opener *o = &t->opener;
    if (!o->running) return -ENOENT;
    pthread_join(o->thread, NULL);
    o->running = false;
    *reader = o->reader;
    *rs = o->rs;
    o->reader = NULL;
    o->rs = NULL;
    return o->rc;
}

static void review_close(fp_vtakes *t)
{
    fp_take_reader *reader = NULL;
    fp_session *rs = NULL;
    if (!opener_join(t, &reader, &rs)) { /* (a review opened and never shown) */
        fp_session_destroy(&rs);
        fp_take_reader_close(&reader);
    }
    fp_session_destroy(&t->rs);
    fp_take_reader_close(&t->reader);
    t->frames = t->applied = 0;
    t->playhead = -1;
    t->playing = false;
}

void fp_vtakes_free(fp_vtakes *t) { review_close(t); }

/* Start opening the take just written for review on the opener's thread, so that V finds it
 * ready: a session made from the mesh file takes about half a second, which on the viewer's
 * thread was a frame that long. Where the thread cannot start, V opens it. */
static void opener_start(fp_vtakes *t)
{
    fp_vtakes_opener *o = &t->opener;
    const fp_session_options *so = t->take.so;
    if (!so->mesh_path || strlen(so->mesh_path) >= sizeof o->mesh_path ||
        strlen(t->last.path) >= sizeof o->take_path)
        return;
    snprintf(o->mesh_path, sizeof o->mesh_path, "%s", so->mesh_path); /* (copies: a mesh dropped */
    snprintf(o->take_path, sizeof o->take_path, "%s", t->last.path);  /*  on the window frees it) */
    o->plugin_path = so->plugin_path;
    o->reader = NULL;
    o->rs = NULL;
    o->running = pthread_create(&o->thread, NULL, opener_main, o) == 0;
}

/* The last take's review session: the opener's, else opened now. */
static bool review_ready(fp_vtakes *t)
{
    if (t->rs) return true;
    if (!t->have_last) return false;
    char err[1100];
    int rc = t->opener.running ? opener_join(t, &t->reader, &t->rs)
                               : open_review(t->take.so->mesh_path, t->take.so->plugin_path, t->last.path,
                                             &t->reader, &t->rs, err, sizeof err);
    if (rc) {
        t->have_last = false; /* (a take that cannot be read is not tried every frame) */
        return false;
    }
    t->frames = fp_take_reader_frames(t->reader);
    t->review_take = t->last.take;
    return true;
}

int fp_vtakes_review(fp_vtakes *t)
{
    if (fp_vtakes_reviewing(t)) {
        fp_vtakes_leave(t);
        return 0;
    }
    if (!review_ready(t)) return -ENOENT;
    fp_vtakes_scrub(t, 0);
    return 0;
}

bool fp_vtakes_reviewing(const fp_vtakes *t) { return fp_vtakes_shown(t) != NULL; }

static int start(fp_vtakes *t, fp_session *s, int64_t now, char *msg, size_t n)
{
    char err[1024];
    fp_vtakes_leave(t);
    const fp_viewer_sound *h = t->sound;
    if (h && h->take_starting) h->take_starting(h->user, now, &t->take.opt);
    int rc = fp_session_take_start(&t->take, s, now, err, sizeof err);
    if (rc) {
        snprintf(msg, n, "take: %s", err);
        return rc;
    }
    t->origin_ns = now;
    if (h && h->take_started) h->take_started(h->user, &t->take, now);
    snprintf(msg, n, "recording %s take %u", t->slate, t->take.header.take);
    return 0;
}

int fp_vtakes_stop(fp_vtakes *t, fp_session *s, char *msg, size_t n)
{
    (void)s;
    msg[0] = '\0';
    t->countdown_until = 0;
    if (!fp_session_take_recording(&t->take)) return 0;
    fp_session_take_result res;
    char err[1024] = "";
    int rc = fp_session_take_stop(&t->take, &res, err, sizeof err);
    if (t->sound && t->sound->take_stopped) t->sound->take_stopped(t->sound->user);
    char in[32], out[32];
    fp_timecode_format(&res.timecode_in, in, sizeof in);
    fp_timecode_format(&res.timecode_out, out, sizeof out);
    if (rc) {
        snprintf(msg, n, "take %u not written whole: %s", res.take, err);
        if (!t->failed) {
            t->failed = rc;
            snprintf(t->failed_msg, sizeof t->failed_msg, "%s", msg);
        }
        return rc;
    }
    snprintf(msg, n, "take %u: %llu frames, %llu dropped, %s - %s, %s%s", res.take,
             (unsigned long long)res.frames, (unsigned long long)res.dropped, in, out, res.path,
             res.frames ? "   V: review" : "");
    if (t->nblocks == FP_VTAKES_BLOCKS) {
        memmove(t->blocks, t->blocks + 1, sizeof t->blocks - sizeof t->blocks[0]);
        t->nblocks--;
    }
    t->blocks[t->nblocks].take = res.take;
    t->blocks[t->nblocks].frames = res.frames;
    t->nblocks++;
    /* the review is shown when asked (fp_vtakes_review): the live face and hands stay; its
     * session is made meanwhile */
    review_close(t);
    t->last = res;
    t->have_last = res.frames > 0;
    t->review_take = res.take; /* (the strip lights it) */
    if (t->have_last) opener_start(t);
    return 0;
}

int fp_vtakes_failed(const fp_vtakes *t, char *err, size_t errlen)
{
    if (!t->failed) return 0;
    snprintf(err, errlen, "%s", t->failed_msg);
    return t->failed == -ENOENT ? -EIO : t->failed; /* (its file deleted: an output lost) */
}

int fp_vtakes_toggle(fp_vtakes *t, fp_session *s, int64_t now, char *msg, size_t n)
{
    msg[0] = '\0';
    if (!t->enabled) {
        snprintf(msg, n, "no take folder: give --take-dir DIR to record takes");
        return -EINVAL;
    }
    if (fp_session_take_recording(&t->take)) return fp_vtakes_stop(t, s, msg, n);
    if (t->countdown_until) {       /* a second press cancels the countdown */
        t->countdown_until = 0;
        snprintf(msg, n, "countdown cancelled");
        return 0;
    }
    if (t->countdown_s > 0) {
        t->countdown_until = now + (int64_t)(t->countdown_s * 1e9);
        fp_vtakes_leave(t);
        return 0;
    }
    return start(t, s, now, msg, n);
}

/* Apply frames to the review session until `index` is shown (replaying from the start when
 * going back: commits accumulate). */
static void show(fp_vtakes *t, long index)
{
    if (!t->rs || !t->frames) return;
    if (index < 0) index = 0;
    if ((size_t)index >= t->frames) index = (long)t->frames - 1;
    if ((size_t)index + 1 < t->applied) {
        fp_session_reset(t->rs);
        t->applied = 0;
    }
    char err[512];
    while (t->applied <= (size_t)index) {
        fp_take_frame f;
        if (fp_take_reader_read(t->reader, t->applied, &f, err, sizeof err)) break;
        fp_session_play_frame(t->rs, &f, NULL);
        t->applied++;
    }
    t->playhead = index;
}

int fp_vtakes_tick(fp_vtakes *t, fp_session *s, int64_t now, char *msg, size_t n)
{
    msg[0] = '\0';
    if (fp_session_take_failed(&t->take, NULL, 0)) /* a full disk: said now, REC off, the
                                                       session goes on */
        return fp_vtakes_stop(t, s, msg, n);
    if (t->countdown_until && now >= t->countdown_until) {
        t->countdown_until = 0;
        return start(t, s, now, msg, n);
    }
    if (t->playing && t->rs) {
        fp_take_frame f;
        char err[512];
        long i = t->playhead < 0 ? 0 : t->playhead;
        /* the last frame whose take time is within the time played */
        while ((size_t)i + 1 < t->frames &&
               !fp_take_reader_read(t->reader, (size_t)i + 1, &f, err, sizeof err) &&
               f.time_ns - t->play_origin_ns <= now - t->play_start_ns)
            i++;
        show(t, i);
        if ((size_t)i + 1 >= t->frames) t->playing = false;
    }
    return 0;
}

const float *fp_vtakes_shown(const fp_vtakes *t)
{
    return t->rs && t->playhead >= 0 ? fp_session_positions(t->rs) : NULL;
}

void fp_vtakes_play_pause(fp_vtakes *t, int64_t now)
{
    if (!review_ready(t) || !t->frames) return;
    if (t->playing) {
        t->playing = false;
        return;
    }
    if (t->playhead < 0 || (size_t)t->playhead + 1 >= t->frames) show(t, 0);
    fp_take_frame f;
    char err[512];
    if (fp_take_reader_read(t->reader, (size_t)t->playhead, &f, err, sizeof err)) return;
    t->play_origin_ns = f.time_ns;
    t->play_start_ns = now;
    t->playing = true;
}

void fp_vtakes_step(fp_vtakes *t, long delta)
{
    if (!review_ready(t)) return;
    t->playing = false;
    show(t, (t->playhead < 0 ? 0 : t->playhead) + delta);
}

void fp_vtakes_scrub(fp_vtakes *t, double fraction)
{
    if (!review_ready(t) || !t->frames) return;
    t->playing = false;
    fraction = fmin(1.0, fmax(0.0, fraction));
    show(t, lround(fraction * (double)(t->frames - 1)));
}

void fp_vtakes_leave(fp_vtakes *t)
{
    t->playing = false;
    t->playhead = -1;
}

void fp_vtakes_strip_rect(int w, int h, float *x, float *y, float *sw, float *sh)
{
    float scale = h >= 600 ? 2.f : 1.f;
    *sh = 18 * scale;
    *x = 8;
    *sw = (float)w - 16;
    *y = (float)h - *sh - 28 * scale;
}

/* text cut at its last two blanks, a hint at a time ("...   P play/pause  , . step"), until it
 * is no wider than max_px at scale (the strip's line: a narrow window); returns text. */
static char *fit_hints(char *text, float max_px, float scale)
{
    char *cut;
    while (fp_render_text_width(text, scale) > max_px && (cut = strstr(text, "  "))) {
        char *last = cut;
        while ((cut = strstr(cut + 1, "  "))) last = cut;
        while (last > text && last[-1] == ' ') last--;
        *last = '\0';
    }
    return text;
}

/* The first of n texts that fits right-aligned between left and the window's right edge
 * (pad: pixels before it at scale 1, REC's square), or NULL. */
static const char *corner_fit(char texts[][160], int n, int w, float scale, float pad, float left)
{
    for (int i = 0; i < n; i++)
        if (texts[i][0] && (float)w - 8 - ((float)strlen(texts[i]) * 6 + pad) * scale >= left) return texts[i];
    return NULL;
}

void fp_vtakes_draw(fp_vtakes *t, fp_render *r, int w, int h, int64_t now, float left)
{
    if (!t->enabled) return;
    float scale = h >= 600 ? 2.f : 1.f;
    static const float red[4] = {0.95f, 0.15f, 0.12f, 1.f}, white[4] = {0.95f, 0.95f, 0.92f, 1.f},
                       dim[4] = {0.8f, 0.85f, 0.9f, 1.f};
    char text[160], fit[3][160] = {"", "", ""};
    const char *line;
    /* top right, on the badge's row (the badge at 8, 15 x scale high, its text 4 x scale
     * down: hud.c), where the HUD's text, which starts under the badge, never runs
     * (stb_easy_font: about 6 pixels a character); shortened, or left out, rather than
     * drawn over the badge (a narrow window, a long slate) */
    float ty = 8 + 4 * scale;
#define RIGHT(s, pad) ((float)w - 8 - ((float)strlen(s) * 6 + (pad)) * scale)
    if (fp_session_take_recording(&t->take)) {
        fp_timecode tc;
        char tcs[32] = "";
        if (!fp_session_take_timecode(&t->take, now, &tc)) fp_timecode_format(&tc, tcs, sizeof tcs);
        snprintf(fit[0], sizeof fit[0], "REC  %s  %s take %u", tcs, t->slate, t->take.header.take);
        snprintf(fit[1], sizeof fit[1], "%s take %u", t->slate, t->take.header.take);
        snprintf(fit[2], sizeof fit[2], "take %u", t->take.header.take);
        if ((line = corner_fit(fit, 3, w, scale, 20, left))) {
            float tx = RIGHT(line, 20);
            fp_render_rect(r, w, h, tx, ty - 2 * scale, 11 * scale, 11 * scale, red);
            fp_render_text(r, w, h, tx + 18 * scale, ty, scale, line, red);
        }
    } else if (t->countdown_until) {
        double left_s = (double)(t->countdown_until - now) * 1e-9;
        snprintf(fit[0], sizeof fit[0], "recording in %.0f ...", ceil(left_s > 0 ? left_s : 0));
        if ((line = corner_fit(fit, 1, w, scale, 20, left))) fp_render_text(r, w, h, RIGHT(line, 20), ty, scale, line, red);
    } else {
        uint32_t next = 0;
        char err[256];
        if (fp_take_next_number(t->take.opt.dir, t->slate, &next, err, sizeof err)) next = 0;
        snprintf(fit[0], sizeof fit[0], "T: record  %s take %u", t->slate, next);
        snprintf(fit[1], sizeof fit[1], "T: record");
        if ((line = corner_fit(fit, 2, w, scale, 20, left))) fp_render_text(r, w, h, RIGHT(line, 20), ty, scale, line, dim);
    }
    if (!t->nblocks) return;
    /* the strip: one block per take of this session, the reviewed one lit, a playhead */
    float x, y, sw, sh;
    fp_vtakes_strip_rect(w, h, &x, &y, &sw, &sh);
    static const float bg[4] = {0.05f, 0.05f, 0.07f, 0.8f}, block[4] = {0.35f, 0.45f, 0.6f, 1.f},
                       lit[4] = {0.45f, 0.7f, 1.f, 1.f}, head[4] = {1.f, 0.85f, 0.2f, 1.f};
    fp_render_rect(r, w, h, x, y, sw, sh, bg);
    /* the reviewed take fills most of the strip; earlier takes are small blocks on the left */
    size_t others = t->nblocks - 1;
    float small = others ? fminf(60 * scale, 0.3f * sw / (float)others) : 0;
    float bx = x + 2;
    for (size_t i = 0; i < t->nblocks; i++) {
        bool reviewed = t->blocks[i].take == t->review_take && i + 1 == t->nblocks;
        float bw = reviewed ? x + sw - 2 - bx : small - 3;
        fp_render_rect(r, w, h, bx, y + 2, bw, sh - 4, reviewed ? lit : block);
        snprintf(text, sizeof text, "T%u", t->blocks[i].take);
        fp_render_text(r, w, h, bx + 3, y + 3, scale * 0.9f, text, white);
        if (reviewed && t->frames) {
            float px = bx + bw * (t->playhead < 0 ? 0.f : (float)t->playhead / (float)(t->frames > 1 ? t->frames - 1 : 1));
            fp_render_rect(r, w, h, px - 1.5f * scale, y - 3 * scale, 3 * scale, sh + 6 * scale, head);
        }
        bx += bw + 3;
    }
    if (t->frames) {
        snprintf(text, sizeof text, "review take %u: frame %ld / %zu %s   P play/pause  , . step  Esc or V: live",
                 t->review_take, t->playhead + 1, t->frames, t->playing ? "playing" : t->playhead >= 0 ? "paused" : "live");
        fp_render_text(r, w, h, x, y - 14 * scale, scale, fit_hints(text, sw, scale), dim);
    } else if (t->have_last) {
        snprintf(text, sizeof text, "take %u: V review   P play   mouse on the strip: scrub", t->last.take);
        fp_render_text(r, w, h, x, y - 14 * scale, scale, fit_hints(text, sw, scale), dim);
    }
}
