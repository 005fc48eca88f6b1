/* fp_stack_player: a stack's layers composed frame by frame (fp_stack_player.h). */
#include "fp_stack_player.h"
#include "fp_take_player.h"
#include "fp_session_take.h"
#include "fp_error.h"
#include "fp_rig.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct layer {
    fp_take_player *tp;        /* its take (layer 0: the base) */
    size_t next, frames;       /* next frame index to play, intact frames */
    int64_t first_ns, last_ns; /* its first and last frame's time */
    int64_t offset_ns;
    bool played;               /* a frame of it has played */
    bool on;                   /* not muted, solo rules */
    bool channels;             /* a channel layer */
    fp_stack_weights wt;       /* vertex layers: the region's weights */
    float chan[FP_STACK_MAX_NAMES]; /* channel layers: the last values of their channels */
    bool chan_set[FP_STACK_MAX_NAMES];
    double f;                  /* weight in time at the last frame */
} layer;

struct fp_stack_player {
    fp_stack *stack;
    layer layers[FP_STACK_MAX_LAYERS];
    size_t n;                  /* vertices */
    float *out;                /* the composite */
    unsigned long limited;
    char warning[1024];        /* "" or the first cut layer above the base (fp_stack_player_warning) */
};

static double smooth(double u) { return u <= 0 ? 0 : u >= 1 ? 1 : u * u * (3 - 2 * u); }

/* The seeds of a region: vertices at distance 0. *seeds malloc'ed. */
static int region_seeds(const fp_stack_region *r, const fp_session *base, size_t n,
                        uint32_t **seeds, size_t *count, char *err, size_t errlen)
{
    const struct fp_rig *rig = fp_session_rig(base);
    size_t cap = r->kind == FP_STACK_REGION_VERTICES ? r->vertex_count
                 : r->kind == FP_STACK_REGION_RIG ? n : r->name_count;
    uint32_t *s = malloc((cap ? cap : 1) * sizeof *s);
    if (!s) return fp_errorf(err, errlen, -ENOMEM, "stack: out of memory");
    size_t k = 0;
    int rc = 0;
    if (r->kind != FP_STACK_REGION_VERTICES && !rig)
        rc = fp_errorf(err, errlen, -EINVAL, "the region names the rig's %s, and the "
                       "base take has no rig", r->kind == FP_STACK_REGION_RIG ? "regions" : "landmarks");
    else if (r->kind == FP_STACK_REGION_VERTICES) {
        for (size_t i = 0; i < r->vertex_count && !rc; i++)
            if (r->vertices[i] >= n)
                rc = fp_errorf(err, errlen, -EINVAL, "vertex %u past the mesh's %zu",
                               r->vertices[i], n);
            else s[k++] = r->vertices[i];
    } else if (r->kind == FP_STACK_REGION_RIG) {
        size_t want = 0;
        for (size_t i = 0; i < fp_rig_region_count(rig); i++) {
            fp_rig_region_desc d;
            if (!fp_rig_region_get(rig, i, &d) && !strcmp(d.name, r->names[0])) want = i + 1;
        }
        const uint8_t *owner = fp_rig_vertex_regions(rig);
        if (!want) rc = fp_errorf(err, errlen, -EINVAL, "the rig %s has no region \"%s\"",
                                  fp_rig_name(rig), r->names[0]);
        for (size_t v = 0; v < n && !rc; v++)
            if (owner[v] == want) s[k++] = (uint32_t)v;
    } else {
        for (size_t i = 0; i < r->name_count && !rc; i++) {
            long v = fp_rig_landmark_index(rig, r->names[i]);
            if (v < 0 || (size_t)v >= n)
                rc = fp_errorf(err, errlen, -EINVAL, "the rig %s has no landmark \"%s\"",
                               fp_rig_name(rig), r->names[i]);
            else s[k++] = (uint32_t)v;
        }
    }
    if (rc) { free(s); return rc; }
    *seeds = s;
    *count = k;
    return 0;
}

int fp_stack_region_weights(const fp_stack_region *region, const fp_session *base,
                            double mm_per_unit, fp_stack_weights *L, char *err, size_t errlen)
{
    memset(L, 0, sizeof *L);
    if (!region || !base || region->kind == FP_STACK_REGION_CHANNELS || !(mm_per_unit > 0))
        return fp_errorf(err, errlen, -EINVAL, "fp_stack_region_weights: bad argument");
    size_t n = fp_session_vertex_count(base);
    const float *x = fp_session_loaded(base);
    L->w = calloc(n, sizeof *L->w);
    L->sup = malloc(n * sizeof *L->sup);
    L->slope = calloc(n, sizeof *L->slope);
    if (!L->w || !L->sup || !L->slope) {
        fp_stack_weights_free(L);
        return fp_errorf(err, errlen, -ENOMEM, "stack: out of memory");
    }
    if (region->kind == FP_STACK_REGION_ALL) {
        for (size_t v = 0; v < n; v++) L->w[v] = 1, L->sup[v] = (uint32_t)v;
        L->nsup = n;
        return 0;
    }
    uint32_t *seeds = NULL;
    size_t ns = 0;
    int rc = region_seeds(region, base, n, &seeds, &ns, err, errlen);
    if (rc) {
        fp_stack_weights_free(L);
        return rc;
    }
    double core = region->core_mm / mm_per_unit, fall = region->falloff_mm / mm_per_unit;
    double reach = core + fall, lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < ns; i++) {
        L->w[seeds[i]] = 2; /* marks a seed; 1 below */
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], x[3 * seeds[i] + a] - reach);
            hi[a] = fmax(hi[a], x[3 * seeds[i] + a] + reach);
        }
    }
    for (size_t v = 0; v < n; v++) {
        double d = 0;
        if (L->w[v] != 2) {
            const float *p = x + 3 * v;
            if (p[0] < lo[0] || p[0] > hi[0] || p[1] < lo[1] || p[1] > hi[1] || p[2] < lo[2] || p[2] > hi[2])
                continue;
            double best = INFINITY;
            for (size_t i = 0; i < ns; i++) {
                const float *q = x + 3 * seeds[i];
                double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
                double dd = dx * dx + dy * dy + dz * dz;
                if (dd < best) best = dd;
            }
            d = sqrt(best);
        }
        double w = 1, slope = 0;
        if (d > core) {
            double u = fall > 0 ? (d - core) / fall : 1;
            w = 1 - smooth(u);
            slope = u < 1 && fall > 0 ? 6 * u * (1 - u) / fall : 0;
        }
        L->w[v] = (float)w;
        L->slope[v] = (float)slope;
        if (L->w[v] > 0) L->sup[L->nsup++] = (uint32_t)v;
    }
    free(seeds);
    return 0;
}

void fp_stack_weights_free(fp_stack_weights *w)
{
    if (!w) return;
    free(w->w);
    free(w->sup);
    free(w->slope);
    memset(w, 0, sizeof *w);
}

/* Open layer i's take and, for vertex layers, its weights. */
static int open_layer(fp_stack_player *p, size_t i, const char *mesh_path,
                      const fp_plugin_path *plugin_path, fp_session_log_fn log, void *log_user,
                      char *err, size_t errlen)
{
    char path[FP_STACK_PATH_MAX + 512], why[2048];
    const fp_stack_layer *l = &p->stack->layers[i];
    layer *L = &p->layers[i];
    if (fp_stack_take_path(p->stack, i, path, sizeof path))
        return fp_errorf(err, errlen, -ENAMETOOLONG, "%s: layers[%zu]: path too long", p->stack->path, i);
    if (fp_stack_is_stack_path(path))
        return fp_errorf(err, errlen, -EBADMSG, "%s: layers[%zu]: %s is a stack; a layer is a take",
                         p->stack->path, i, path);
    fp_take_player *base = i ? p->layers[0].tp : NULL;
    const char *mesh = base ? fp_take_player_mesh_path(base) : mesh_path;
    int rc = fp_take_player_open_logged(path, mesh, plugin_path, i ? NULL : log, log_user, &L->tp,
                                        why, sizeof why);
    if (rc) return fp_errorf(err, errlen, rc, "%s: layers[%zu]: %s", p->stack->path, i, why);
    fp_take_reader *r = fp_take_player_reader(L->tp);
    L->frames = fp_take_reader_frames(r);
    const char *cut = fp_take_reader_warning(r);
    if (!L->frames) /* (it would add nothing, said nowhere; the take alone is refused, 65) */
        return fp_errorf(err, errlen, -EBADMSG, "%s: layers[%zu]: %s: no intact frame to play%s%s%s",
                         p->stack->path, i, path, cut[0] ? " (" : "", cut, cut[0] ? ")" : "");
    if (cut[0] && i > 0 && !p->warning[0]) /* (the base's: the command's own take warning) */
        snprintf(p->warning, sizeof p->warning, "%.300s: layers[%zu]: %.600s; its %zu intact frames played",
                 p->stack->path, i, cut, L->frames);
    const fp_take_summary *sum = fp_take_reader_summary(r);
    L->first_ns = sum->first_time_ns;
    L->last_ns = sum->last_time_ns;
    L->offset_ns = llround(l->offset_s * 1e9);
    L->channels = l->region.kind == FP_STACK_REGION_CHANNELS;
    if (i == 0) {
        p->n = fp_session_vertex_count(fp_take_player_session(L->tp));
        L->f = 1;
        return 0;
    }
    if (fp_session_vertex_count(fp_take_player_session(L->tp)) != p->n)
        return fp_errorf(err, errlen, -EBADMSG, "%s: layers[%zu]: %s is on a mesh of another vertex count",
                         p->stack->path, i, path);
    if (L->channels) {
        const struct fp_rig *rig = fp_session_rig(fp_take_player_session(base));
        for (size_t c = 0; c < l->region.name_count; c++)
            if (!rig || fp_rig_channel_index(rig, l->region.names[c]) < 0)
                return fp_errorf(err, errlen, -EBADMSG, "%s: layers[%zu]: the base take's rig has no "
                                 "channel \"%s\"", p->stack->path, i, l->region.names[c]);
        return 0;
    }
    rc = fp_stack_region_weights(&l->region, fp_take_player_session(base),
                                 fp_take_player_mm_per_unit(base), &L->wt, why, sizeof why);
    /* (a region the file names that the base cannot give is the file's data, not a usage: 65) */
    return rc ? fp_errorf(err, errlen, rc == -EINVAL ? -EBADMSG : rc, "%s: layers[%zu]: %s",
                          p->stack->path, i, why) : 0;
}

int fp_stack_player_open(const char *stack_path, const char *mesh_path,
                         const fp_plugin_path *plugin_path, fp_session_log_fn log,
                         void *log_user, fp_stack_player **out, char *err, size_t errlen)
{
    if (out) *out = NULL;
    if (!stack_path || !out) return fp_errorf(err, errlen, -EINVAL, "play: no stack");
    fp_stack_player *p = calloc(1, sizeof *p);
    if (!p) return fp_errorf(err, errlen, -ENOMEM, "play: out of memory");
    int rc = fp_stack_load(stack_path, &p->stack, err, errlen);
    bool solo = false;
    for (size_t i = 1; !rc && i < p->stack->layer_count; i++) solo |= p->stack->layers[i].solo;
    for (size_t i = 0; !rc && i < p->stack->layer_count; i++) {
        const fp_stack_layer *l = &p->stack->layers[i];
        p->layers[i].on = i == 0 || (!l->mute && (!solo || l->solo));
        rc = open_layer(p, i, mesh_path, plugin_path, log, log_user, err, errlen);
    }
    if (!rc && !(p->out = malloc(p->n * 3 * sizeof *p->out)))
        rc = fp_errorf(err, errlen, -ENOMEM, "play: out of memory");
    if (rc) {
        fp_stack_player_close(&p);
        return rc;
    }
    memcpy(p->out, fp_session_loaded(fp_take_player_session(p->layers[0].tp)), p->n * 3 * sizeof *p->out);
    *out = p;
    return 0;
}

/* Play layer i's frames up to stack time t_ns; a channel layer only reads its values. */
static int advance(fp_stack_player *p, size_t i, int64_t t_ns, char *err, size_t errlen)
{
    layer *L = &p->layers[i];
    const fp_stack_layer *l = &p->stack->layers[i];
    while (L->next < L->frames) {
        fp_take_frame f;
        int rc = fp_take_reader_read(fp_take_player_reader(L->tp), L->next, &f, err, errlen);
        if (rc) return rc;
        if (f.time_ns - L->first_ns + L->offset_ns > t_ns) break;
        L->next++;
        L->played = true;
        if (!L->channels) {
            fp_frame_stats st;
            fp_session_play_frame(fp_take_player_session(L->tp), &f, &st);
            continue;
        }
        for (size_t c = 0; f.control && c < l->region.name_count; c++)
            for (size_t k = 0; k < f.control->channel_count; k++)
                if (!strncmp(f.control->channels[k].name, l->region.names[c], sizeof f.control->channels[k].name)) {
                    L->chan[c] = f.control->channels[k].value;
                    L->chan_set[c] = true;
                }
    }
    return 0;
}

/* Layer i's weight in time at t (seconds on the stack's clock), gain included. */
static double time_weight(const fp_stack_player *p, size_t i, double t)
{
    const layer *L = &p->layers[i];
    const fp_stack_layer *l = &p->stack->layers[i];
    if (!L->on || !L->played) return 0;
    double a = fmax(l->in_s, l->offset_s);
    double b = fmin(l->out_s, l->offset_s + (double)(L->last_ns - L->first_ns) * 1e-9);
    if (!(t > a && t < b)) return 0;
    double fade = fmin(l->fade_s, (b - a) / 2), f = 1;
    if (fade > 0) f = smooth((t - a) / fade) * smooth((b - t) / fade);
    return f * l->gain;
}

/* The base frame's control set with the channel layers composed into a copy. */
static const fp_control_set *compose_channels(fp_stack_player *p, const fp_control_set *cs,
                                              fp_control_set *copy, fp_channel *ch, size_t cap)
{
    if (!cs) return cs;
    const fp_session *s = fp_take_player_session(p->layers[0].tp);
    const struct fp_rig *rig = fp_session_rig(s);
    bool any = false;
    for (size_t i = 1; i < p->stack->layer_count; i++) any |= p->layers[i].channels && p->layers[i].f > 0;
    if (!any || !rig) return cs;
    *copy = *cs;
    size_t n = cs->channel_count < cap ? cs->channel_count : cap;
    memcpy(ch, cs->channels, n * sizeof *ch);
    for (size_t i = 1; i < p->stack->layer_count; i++) {
        const layer *L = &p->layers[i];
        const fp_stack_layer *l = &p->stack->layers[i];
        if (!L->channels || L->f <= 0) continue;
        for (size_t c = 0; c < l->region.name_count; c++) {
            if (!L->chan_set[c]) continue;
            size_t k = 0;
            while (k < n && strncmp(ch[k].name, l->region.names[c], sizeof ch[k].name)) k++;
            if (k == n) {  /* the base frame lacks it: its current value in the base session */
                if (n == cap) continue;
                snprintf(ch[k].name, sizeof ch[k].name, "%s", l->region.names[c]);
                ch[k].value = (float)fp_session_channel(s, l->region.names[c]);
                n++;
            }
            fp_rig_channel_desc d = {0};
            fp_rig_channel_get(rig, (size_t)fp_rig_channel_index(rig, l->region.names[c]), &d);
            double v = ch[k].value, w = L->f;
            if (l->mode == FP_STACK_ADD) v += w * ((double)L->chan[c] - d.neutral);
            else v = w >= 1 ? L->chan[c] : v + w * ((double)L->chan[c] - v);
            ch[k].value = (float)v;
        }
    }
    copy->channels = ch;
    copy->channel_count = n;
    copy->channel_capacity = cap;
    return copy;
}

double fp_stack_blend(float *o, const float *y, const float *x0, const fp_stack_weights *L,
                      double f, fp_stack_mode mode, bool *limited)
{
    const bool add = mode == FP_STACK_ADD;
    double g = 0; /* the blend's gradient term, |L - P| |w'| f, over the falloff band */
    for (size_t k = 0; k < L->nsup; k++) {
        uint32_t v = L->sup[k];
        if (L->slope[v] <= 0) continue;
        const float *ref = add ? x0 + 3 * v : o + 3 * v;
        double dx = (double)y[3 * v] - ref[0], dy = (double)y[3 * v + 1] - ref[1],
               dz = (double)y[3 * v + 2] - ref[2];
        double t = sqrt(dx * dx + dy * dy + dz * dz) * L->slope[v] * f;
        if (t > g) g = t;
    }
    if (limited) *limited = g > FP_STACK_BLEND_MARGIN;
    if (g > FP_STACK_BLEND_MARGIN) f *= FP_STACK_BLEND_MARGIN / g;
    for (size_t k = 0; k < L->nsup && f > 0; k++) {
        uint32_t v = L->sup[k];
        double w = L->w[v] * f;
        for (int a = 0; a < 3; a++) {
            size_t j = 3 * (size_t)v + (size_t)a;
            if (add) o[j] = (float)(o[j] + w * ((double)y[j] - x0[j]));
            else o[j] = w >= 1 ? y[j] : (float)(o[j] + w * ((double)y[j] - o[j]));
        }
    }
    return f;
}

/* Layer i composed into p->out with its weight in time f. */
static void compose_layer(fp_stack_player *p, size_t i)
{
    layer *L = &p->layers[i];
    bool limited = false;
    L->f = fp_stack_blend(p->out, fp_session_positions(fp_take_player_session(L->tp)),
                          fp_session_loaded(fp_take_player_session(p->layers[0].tp)), &L->wt, L->f,
                          p->stack->layers[i].mode, &limited);
    p->limited += limited;
}

int fp_stack_player_next(fp_stack_player *p, fp_take_frame *frame, fp_frame_stats *st,
                         char *err, size_t errlen)
{
    layer *B = &p->layers[0];
    const fp_stack_layer *bl = &p->stack->layers[0];
    fp_take_reader *r = fp_take_player_reader(B->tp);
    fp_frame_stats local;
    for (;;) {
        int rc = fp_take_reader_next(r, frame, err, errlen);
        if (rc != 1) return rc;
        int64_t t_ns = frame->time_ns - B->first_ns;
        double t = (double)t_ns * 1e-9;
        for (size_t i = 1; i < p->stack->layer_count; i++) {
            if ((rc = advance(p, i, t_ns, err, errlen))) return rc;
            p->layers[i].f = time_weight(p, i, t);
        }
        fp_control_set copy;
        fp_channel ch[FP_RIG_MAX_CHANNELS + FP_STACK_MAX_NAMES];
        fp_take_frame f = *frame;
        f.control = compose_channels(p, frame->control, &copy, ch, sizeof ch / sizeof *ch);
        fp_session_play_frame(fp_take_player_session(B->tp), &f, st ? st : &local);
        if (t < bl->in_s || t > bl->out_s) continue;  /* the base's range trims the stack */
        memcpy(p->out, fp_session_positions(fp_take_player_session(B->tp)), p->n * 3 * sizeof *p->out);
        for (size_t i = 1; i < p->stack->layer_count; i++)
            if (!p->layers[i].channels && p->layers[i].f > 0) compose_layer(p, i);
        return 1;
    }
}

const float *fp_stack_player_positions(const fp_stack_player *p) { return p->out; }
const fp_stack *fp_stack_player_stack(const fp_stack_player *p) { return p->stack; }
fp_take_player *fp_stack_player_base(fp_stack_player *p) { return p->layers[0].tp; }
const char *fp_stack_player_warning(const fp_stack_player *p) { return p->warning; }

unsigned long fp_stack_player_limited(const fp_stack_player *p) { return p->limited; }

/* Which layers play: the base; a layer not muted when no layer is soloed, else a soloed one. */
static void set_on(fp_stack_player *p)
{
    bool solo = false;
    for (size_t i = 1; i < p->stack->layer_count; i++) solo |= p->stack->layers[i].solo;
    for (size_t i = 0; i < p->stack->layer_count; i++) {
        const fp_stack_layer *l = &p->stack->layers[i];
        p->layers[i].on = i == 0 || (!l->mute && (!solo || l->solo));
    }
}

int fp_stack_player_set_layer(fp_stack_player *p, size_t i, bool mute, bool solo)
{
    if (!p || i == 0 || i >= p->stack->layer_count) return -EINVAL;
    p->stack->layers[i].mute = mute;
    p->stack->layers[i].solo = solo;
    set_on(p);
    return 0;
}

const float *fp_stack_player_region_weights(const fp_stack_player *p, size_t i)
{
    return p && i < p->stack->layer_count ? p->layers[i].wt.w : NULL;
}

const float *fp_stack_player_layer_positions(fp_stack_player *p, size_t i)
{
    if (!p || i >= p->stack->layer_count || p->layers[i].channels) return NULL;
    return fp_session_positions(fp_take_player_session(p->layers[i].tp));
}

double fp_stack_player_layer_weight(const fp_stack_player *p, size_t i)
{
    return p && i < p->stack->layer_count ? p->layers[i].f : 0;
}

void fp_stack_player_close(fp_stack_player **pp)
{
    if (!pp || !*pp) return;
    fp_stack_player *p = *pp;
    for (size_t i = 0; i < FP_STACK_MAX_LAYERS; i++) {
        fp_take_player_close(&p->layers[i].tp);
        fp_stack_weights_free(&p->layers[i].wt);
    }
    fp_stack_free(&p->stack);
    free(p->out);
    free(p);
    *pp = NULL;
}
