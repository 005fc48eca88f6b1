/* overdub: a new pass over a stack in the live viewer (overdub.h). */
#include "overdub.h"
#include "fp_error.h"

#include <errno.h>
#include <stddef.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int fp_voverdub_init(fp_voverdub *o, const char *over, const char *layer, char *err,
                     size_t errlen)
{
    memset(o, 0, sizeof *o);
    if (!over) return 0;
    o->over = over;
    fp_stack_layer_init(&o->pass, "");
    int rc = fp_stack_layer_spec(layer ? layer : "mouth", &o->pass.region, &o->pass.mode, err, errlen);
    if (!rc) rc = fp_stack_over_open(over, &o->stack, err, errlen);
    if (rc) {
        fp_voverdub_free(o);
        return rc;
    }
    o->enabled = true;
    return 0;
}

static void stop_playback(fp_voverdub *o)
{
    fp_take_player_close(&o->player);
    fp_stack_weights_free(&o->wt);
    free(o->under);
    free(o->shown);
    o->under = o->shown = NULL;
    o->recording = o->pending = o->ended = o->have_under = false;
}

void fp_voverdub_free(fp_voverdub *o)
{
    stop_playback(o);
    fp_stack_free(&o->stack);
    fp_stack_region_clear(&o->pass.region);
    o->enabled = false;
}

/* A take began: play the stack from its start under it. */
static void start(fp_voverdub *o, fp_session *s, const fp_plugin_path *plugins, int64_t now,
                  char *msg, size_t n)
{
    char err[2048];
    o->recording = true;
    o->t0 = now;
    o->punch = 0;
    o->t = 0;
    o->written[0] = '\0';
    o->n = fp_session_vertex_count(s);
    int rc = fp_take_player_open(o->over, NULL, plugins, &o->player, err, sizeof err);
    if (!rc && fp_session_vertex_count(fp_take_player_session(o->player)) != o->n)
        rc = fp_errorf(err, sizeof err, -EINVAL, "%s is on another mesh", o->over);
    if (!rc && o->pass.region.kind != FP_STACK_REGION_CHANNELS)
        rc = fp_stack_region_weights(&o->pass.region, s, fp_take_player_mm_per_unit(o->player),
                                     &o->wt, err, sizeof err);
    if (!rc && (!(o->under = malloc(o->n * 3 * sizeof(float))) ||
                !(o->shown = malloc(o->n * 3 * sizeof(float)))))
        rc = fp_errorf(err, sizeof err, -ENOMEM, "out of memory");
    if (rc) {
        snprintf(msg, n, "overdub: %s: the take records without the stack", err);
        fp_take_player_close(&o->player);
        return;
    }
    fp_stack_player *sp = fp_take_player_stack(o->player); /* the layers as L, M, O left them */
    for (size_t i = 1; sp && i < o->stack->layer_count; i++)
        fp_stack_player_set_layer(sp, i, o->stack->layers[i].mute, o->stack->layers[i].solo);
    const fp_take_summary *sum = fp_take_reader_summary(fp_take_player_reader(o->player));
    o->first_ns = sum->first_time_ns;
    o->stack_s = (double)(sum->last_time_ns - sum->first_time_ns) * 1e-9;
    snprintf(msg, n, "overdub over %s: pre-roll; I (or the pedal) punches in", o->over);
}

/* The stack's frames up to the playhead: the latest one due is `under`. */
static void advance(fp_voverdub *o, char *msg, size_t n)
{
    char err[1024];
    for (;;) {
        if (!o->pending && !o->ended) {
            int rc = fp_take_player_next(o->player, &o->next, NULL, err, sizeof err);
            if (rc < 0) snprintf(msg, n, "overdub: %s", err);
            o->pending = rc == 1;
            o->ended = rc != 1;
        }
        if (!o->pending || (double)(o->next.time_ns - o->first_ns) * 1e-9 > o->t) return;
        memcpy(o->under, fp_take_player_positions(o->player), o->n * 3 * sizeof(float));
        o->have_under = true;
        o->pending = false;
    }
}

/* The pass's weight in time at the playhead (the punches, cross-faded). */
static double punch_weight(const fp_voverdub *o)
{
    double fade = o->pass.fade_s, t = o->t;
    if (o->punch == 0) return 0;
    double f = fade > 0 ? fmin(1, (t - o->pass.in_s) / fade) : 1;
    if (o->punch == 2) f = fmin(f, fade > 0 ? (o->pass.out_s - t) / fade : 0);
    f = fmax(0, f);
    return f * f * (3 - 2 * f) * o->pass.gain;
}

/* The take ended: the new stack with the pass on top. */
static void finish(fp_voverdub *o, fp_vtakes *takes, char *msg, size_t n)
{
    stop_playback(o);
    if (!takes->have_last) {
        snprintf(msg, n, "overdub: the take has no frames: no stack written");
        return;
    }
    fp_stack_layer l = o->pass;
    if (o->punch == 0) l.in_s = 0, l.out_s = INFINITY;   /* never punched in: the whole pass */
    if (o->punch == 1) l.out_s = INFINITY;
    char err[2048];
    int rc = fp_stack_over_save(o->over, o->stack, &l, takes->take.opt.dir, takes->last.path,
                                takes->slate, o->written, sizeof o->written, err, sizeof err);
    if (rc) {
        o->written[0] = '\0';
        snprintf(msg, n, "overdub: the stack was not written: %s", err);
    } else if (isfinite(l.out_s) || l.in_s > 0) {
        snprintf(msg, n, "stack %s: %zu layers, the pass from %.2f s to %.2f s", o->written,
                 o->stack->layer_count + 1, l.in_s, l.out_s);
    } else {
        snprintf(msg, n, "stack %s: %zu layers, the whole pass", o->written, o->stack->layer_count + 1);
    }
}

void fp_voverdub_frame(fp_voverdub *o, fp_vtakes *takes, fp_session *s,
                       const fp_plugin_path *plugins, int64_t now, char *msg, size_t n)
{
    msg[0] = '\0';
    if (!o->enabled) return;
    bool rec = fp_session_take_recording(&takes->take);
    if (rec && !o->recording) start(o, s, plugins, now, msg, n);
    else if (!rec && o->recording) finish(o, takes, msg, n);
    if (!o->recording || !o->player) return;
    o->t = (double)(now - o->t0) * 1e-9;
    advance(o, msg, n);
    if (!o->have_under) return;
    memcpy(o->shown, o->under, o->n * 3 * sizeof(float));
    double f = punch_weight(o);
    if (f > 0 && o->pass.region.kind != FP_STACK_REGION_CHANNELS)
        fp_stack_blend(o->shown, fp_session_positions(s), fp_session_loaded(s), &o->wt, f,
                       o->pass.mode, NULL);
}

bool fp_voverdub_punch(fp_voverdub *o, int64_t now, char *msg, size_t n)
{
    msg[0] = '\0';
    if (!o->enabled || !o->recording || o->punch == 2) return false;
    double t = (double)(now - o->t0) * 1e-9;
    if (o->punch == 0) {
        o->pass.in_s = t;
        o->pass.out_s = INFINITY;
        snprintf(msg, n, "punch in at %.2f s", t);
    } else {
        o->pass.out_s = t > o->pass.in_s ? t : o->pass.in_s;
        snprintf(msg, n, "punch out at %.2f s: T (or the pedal) ends the take", o->pass.out_s);
    }
    o->punch++;
    return true;
}

bool fp_voverdub_layer_key(fp_voverdub *o, char key, char *msg, size_t n)
{
    msg[0] = '\0';
    if (!o->enabled || !o->stack) return false;
    const size_t top = o->stack->layer_count;
    if (top < 2) {
        snprintf(msg, n, "the stack has only its base: no layer to mute or solo");
        return true;
    }
    if (key == 'L' || !o->selected) o->selected = o->selected + 1 < top && key == 'L' ? o->selected + 1 : 1;
    fp_stack_layer *l = &o->stack->layers[o->selected];
    if (key == 'M') l->mute = !l->mute;
    if (key == 'O') l->solo = !l->solo;
    fp_stack_player *sp = o->player ? fp_take_player_stack(o->player) : NULL;
    if (sp) fp_stack_player_set_layer(sp, o->selected, l->mute, l->solo);
    const char *name = strrchr(l->take, '/') ? strrchr(l->take, '/') + 1 : l->take;
    snprintf(msg, n, "layer %zu (%.60s)%s%s%s", o->selected, name, l->mute ? " muted" : "",
             l->solo ? " solo" : "", l->mute || l->solo ? "" : " plays");
    return true;
}

const float *fp_voverdub_shown(const fp_voverdub *o)
{
    return o->enabled && o->recording && o->have_under && o->pass.region.kind != FP_STACK_REGION_CHANNELS
               ? o->shown : NULL;
}

/* A short name for a region: its preset's, else its kind and first name. */
static const char *short_region(const fp_stack_region *r, char *buf, size_t n)
{
    static const char *const kinds[] = {"all", "rig", "landmarks", "vertices", "channels"};
    if (r->name[0]) snprintf(buf, n, "%s", r->name);
    else if (r->name_count) snprintf(buf, n, "%s %s%s", kinds[r->kind], r->names[0], r->name_count > 1 ? ",..." : "");
    else snprintf(buf, n, "%s", kinds[r->kind]);
    return buf;
}

/* One lane: its label, its range [a, b] of span seconds lit, its in and out points (ticks:
 * an in after 0, an out before the end), outlined when selected. */
static void lane(fp_render *r, int w, int h, float x, float y, float lw, float lh, float scale,
                 const char *label, double a, double b, double span, const float *col, bool ticks,
                 bool selected)
{
    static const float bg[4] = {0.05f, 0.05f, 0.07f, 0.7f}, white[4] = {0.95f, 0.95f, 0.92f, 1.f};
    float lx = x + FP_VWAVE_LABEL_PX * scale, bw = lw - FP_VWAVE_LABEL_PX * scale;
    fp_render_rect(r, w, h, x, y, lw, lh - 2, bg);
    if (selected) { /* an outline: top and bottom lines */
        fp_render_rect(r, w, h, x, y, lw, scale, white);
        fp_render_rect(r, w, h, x, y + lh - 2 - scale, lw, scale, white);
    }
    fp_render_text(r, w, h, x + 3, y + 2, scale * 0.8f, label, white);
    if (span <= 0) return;
    double ca = fmax(0, fmin(a, span)), cb = fmax(ca, fmin(b, span));
    fp_render_rect(r, w, h, lx + bw * (float)(ca / span), y + 2, bw * (float)((cb - ca) / span), lh - 6, col);
    if (ticks && a > 0 && a <= span)
        fp_render_rect(r, w, h, lx + bw * (float)(a / span) - scale, y, 2 * scale, lh - 2, white);
    if (ticks && isfinite(b) && b <= span)
        fp_render_rect(r, w, h, lx + bw * (float)(b / span) - scale, y, 2 * scale, lh - 2, white);
}

bool fp_voverdub_draw(const fp_voverdub *o, fp_render *r, int w, int h, const fp_vwave *wave)
{
    if (!o->enabled || !o->stack) return false;
    float scale = h >= 600 ? 2.f : 1.f, x, y, sw, sh;
    fp_vtakes_strip_rect(w, h, &x, &y, &sw, &sh);
    static const float base[4] = {0.35f, 0.45f, 0.6f, 1.f}, on[4] = {0.45f, 0.75f, 0.5f, 1.f},
                       off[4] = {0.3f, 0.3f, 0.3f, 1.f}, pass[4] = {0.95f, 0.3f, 0.25f, 1.f},
                       head[4] = {1.f, 0.85f, 0.2f, 1.f};
    const size_t lanes = o->stack->layer_count + 1, below = fp_vwave_on(wave) ? 1 : 0;
    const float lh = 12 * scale, top = y - 8 * scale - lh * (float)(lanes + below);
    double span = o->stack_s > 0 ? fmax(o->stack_s, o->t) : fmax(fp_vwave_on(wave) ? wave->length_s : 1, o->t);
    char text[320], region[80];
    bool solo = false;
    for (size_t i = 1; i < o->stack->layer_count; i++) solo |= o->stack->layers[i].solo;
    for (size_t i = 0; i < o->stack->layer_count; i++) {
        const fp_stack_layer *l = &o->stack->layers[i];
        const char *name = strrchr(l->take, '/') ? strrchr(l->take, '/') + 1 : l->take;
        /* the tags first (the label column is 150 px: a long label runs under the range) */
        int stem = (int)(strrchr(name, '.') ? strrchr(name, '.') - name : (ptrdiff_t)strlen(name));
        snprintf(text, sizeof text, "%zu%s%s %.*s %s %s", i, l->mute ? " M" : "", l->solo ? " S" : "",
                 stem < 20 ? stem : 20, name, i ? short_region(&l->region, region, sizeof region) : "base",
                 i == 0 ? "" : l->mode == FP_STACK_ADD ? "add" : "replace");
        text[48] = '\0';
        bool plays = i == 0 || (!l->mute && (!solo || l->solo));
        lane(r, w, h, x, top + lh * (float)i, sw, lh, scale, text, l->in_s, l->out_s, span,
             i == 0 ? base : plays ? on : off, i > 0, i > 0 && i == o->selected);
    }
    double a = o->punch ? o->pass.in_s : 0, b = o->punch == 2 ? o->pass.out_s : o->recording ? o->t : 0;
    snprintf(text, sizeof text, "pass %s %s%s", short_region(&o->pass.region, region, sizeof region),
             o->pass.mode == FP_STACK_ADD ? "add" : "replace", o->punch == 0 ? " (pre-roll)" : "");
    text[48] = '\0';
    lane(r, w, h, x, top + lh * (float)(lanes - 1), sw, lh, scale, text, o->punch || o->recording ? a : 0,
         o->punch ? b : 0, span, pass, o->punch > 0, false);
    if (below) /* the soundtrack under the lanes, on their time axis */
        fp_vwave_draw(wave, r, w, h, x, top + lh * (float)lanes, sw, lh, scale, span, NAN);
    if (o->recording) {
        float bw = sw - FP_VWAVE_LABEL_PX * scale, px = x + FP_VWAVE_LABEL_PX * scale + bw * (float)fmin(1, o->t / span);
        fp_render_rect(r, w, h, px - scale, top - 2 * scale, 2 * scale, lh * (float)(lanes + below) + 2 * scale, head);
    }
    return true;
}

float fp_voverdub_bottom_top(const fp_voverdub *o, const fp_vtakes *t, const fp_vwave *wave,
                             int w, int h)
{
    float scale = h >= 600 ? 2.f : 1.f, x, y, sw, sh, lh = 12 * scale;
    float top = (float)h - 16 * scale; /* the "? keys" line (viewer.c's draw_hud) */
    fp_vtakes_strip_rect(w, h, &x, &y, &sw, &sh);
    if (t->enabled && t->nblocks) top = fminf(top, y - 16 * scale); /* its line of text */
    if (o->enabled && o->stack) {
        size_t lanes = o->stack->layer_count + 1 + (fp_vwave_on(wave) ? 1 : 0);
        top = fminf(top, y - 10 * scale - lh * (float)lanes);
    } else if (fp_vwave_on(wave)) {
        top = fminf(top, y - 10 * scale - lh);
    }
    return top;
}
