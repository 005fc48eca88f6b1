/*
 * map-anchored: the anchored mapping of Sato, Savchenko, Ohbuchi (Cyberworlds 2004,
 * sec. 2.3.1), grabbing the skin. At engage each point of contact of the engaged hands that
 * touches the face (within engage x R of the surface) grabs the skin under it: its start
 * point s_i is the nearest point of the base surface (the host's surface service,
 * FP_HOST_EXT_SURFACE), and from then on its end point is that skin point plus how far the
 * fingertip moved since engage, d_i = s_i + (p_i(now) - p_i(engage)). So the grabbed skin
 * moves exactly as the fingertip moves (T(s_i) = d_i), whatever the gap between finger and
 * skin at engage; points that do not touch pull nothing (they are not in the control set).
 * The start points stay fixed for the gesture, so the host reuses one factorization; commit
 * folds the deformed shape into the base, cancel drops it. (The paper's start points are the
 * fingertips themselves, which engage up to R/2 off the skin, where the Wendland function is
 * psi(0.5) = 0.19: the skin then got a fifth of the finger's motion at most.)
 *
 * How far one gesture goes is the host's business: a drag longer than one injective map is
 * composed of certified sub-steps from the grabbed points to the end points (step_engine.h),
 * so the default has no clamp.
 *
 * Engage and commit come from the performer's requests (FP_INTENT_ENGAGE / _COMMIT /
 * _CANCEL: pedal, keys) and, unless auto=0, from the paper's rule: engage when a hand's
 * fingertip comes within engage x R of the surface; commit when every engaged hand's
 * fingertips are farther than release x R from the base (the hand has let go). A requested
 * engage grabs what touches too; with nothing within engage x R it grabs each point's
 * nearest skin within release x R (a pedal pressed with the hand hovering), and with
 * nothing there either, the skin nearest the one point of contact nearest the face. A 1.0 host
 * without the surface service gets the paper's start points (the points themselves).
 * Touch is measured in the face's default R (fp_touch_radius), not the support's: a wider
 * --radius moves more skin around the same grab, it never engages farther off the skin nor
 * lets go later (which made a wider brush move the skin less).
 *
 * Every performer's hands grab (ABI 1.3, fp_frame_input.extra_hands: two right hands from
 * two performers are two hands, each grabbing its own skin); hands= picks the sides for all
 * of them. The control set holds FP_CONTROL_CAPACITY points: the first performer's grab
 * first, a later performer's points beyond it are left out (only with points=all, or
 * tips+palm and more than five hands).
 *
 * Keys: hands=left|right|both (both), auto=0|1 (1), engage=F (0.5, in R), release=F (1.0, in R;
 *       at least engage, else a hand would let go as it engages: refused at create),
 *       clamp=F (0: none; else the longest control vector in R, a performer's limit),
 *       points=tips|tips+palm|all (tips: the paper's fingertips; tips+palm adds the palm
 *       centre and the knuckles, all every joint: 5, 11 or 21 points per hand,
 *       mapping_util.h fp_points), widen=F (0.5, in R: fp_drag_radius), apart=F (0.2, in R:
 *       points whose grabbed skin lies within apart x R grab it once, the point nearest its
 *       skin holding it: a fingertip is about 15 mm across, so only fingertips pinched
 *       together, or hovering over one bit of skin such as the nose's tip, share; 0: each
 *       grabs its own).
 */
#include <facepuppet/mapping_util.h>
#include <facepuppet/plugin.h>

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct anchored {
    fp_mapping mapping;
    unsigned hands;              /* FP_HANDMASK_* listened to */
    bool automatic;
    double engage, release, clamp, widen, apart;
    int points;                  /* fp_points mode */
    size_t per_hand;             /* points per hand (FP_POINTS_*_COUNT) */
    bool engaged;
    unsigned engaged_hands;      /* hands whose points grabbed the skin (bit: an index of
                                    fp_frame_hand_count's list, every performer's) */
    size_t count;                /* grabbed points (control vectors) */
    float start[FP_CONTROL_CAPACITY][3];    /* the grabbed skin points, mesh units */
    float offset[FP_CONTROL_CAPACITY][3];   /* start - the point at engage */
    uint8_t hand_of[FP_CONTROL_CAPACITY];   /* which hand ... */
    uint8_t point_of[FP_CONTROL_CAPACITY];  /* ... and which of its points grabbed */
    float last_end[FP_CONTROL_CAPACITY][3];
    const fp_host *host;
    const fp_host_surface *surface; /* FP_HOST_EXT_SURFACE, or NULL (a 1.0 host) */
    float rest_of[FP_CONTROL_CAPACITY][3];  /* where that skin was at rest (widen) */
    float gap[FP_CONTROL_CAPACITY];         /* the point's distance to the skin it grabbed */
    float *rest;                 /* the first base seen (the loaded face), rest_n x 3 */
    size_t rest_n;
} anchored;

/* The paper's rule with `factor` x R: the host's tip distances where they reach that far,
 * else the surface service with that reach (a 1.0 host's distances are exact anyway). */
static bool hand_near(const anchored *a, const fp_frame_input *in, int h, double factor)
{
    if (factor <= FP_TIP_DISTANCE_REACH || !a->surface || !a->surface->nearest)
        return fp_hand_is_near(in, h, factor);
    if (!fp_frame_hand(in, h)->present) return false;
    float tips[FP_FINGERS][3];
    fp_surface_hit hit[FP_FINGERS];
    fp_hand_tips(in, h, tips);
    const double touch = fp_touch_radius(in);
    if (a->surface->nearest(a->host, (const float (*)[3])tips, FP_FINGERS, (float)(factor * touch), hit))
        return fp_hand_is_near(in, h, factor);
    for (int f = 0; f < FP_FINGERS; f++)
        if (hit[f].distance < factor * touch) return true;
    return false;
}

/* Append control vector k: hand h's point p grabs `skin` (its start point, base vertex
 * `vertex` or UINT32_MAX), the point now at `point`, `gap` from it (the surface hit's
 * distance); the offset skin - point is kept for the gesture, and where that skin was at
 * rest. */
static void add_point(anchored *a, int h, size_t p, const float skin[3], const float point[3],
                      uint32_t vertex, float gap)
{
    size_t k = a->count++;
    a->gap[k] = gap;
    if (a->rest && vertex < a->rest_n)
        memcpy(a->rest_of[k], a->rest + 3 * (size_t)vertex, sizeof a->rest_of[k]);
    else
        memcpy(a->rest_of[k], skin, sizeof a->rest_of[k]);
    memcpy(a->start[k], skin, sizeof a->start[k]);
    for (int c = 0; c < 3; c++) a->offset[k][c] = skin[c] - point[c];
    a->hand_of[k] = (uint8_t)h;
    a->point_of[k] = (uint8_t)p;
}

/* Grab: the points of hand h within `reach` of the surface, appended to the control set
 * (start on the skin, offset kept). Returns how many grabbed, or -1 where the host has no
 * surface service (the caller then takes the points themselves). */
static int grab(anchored *a, const fp_frame_input *in, int h, double reach, size_t room)
{
    if (!a->surface || !a->surface->nearest) return -1;
    float pts[FP_POINTS_MAX][3];
    fp_surface_hit hit[FP_POINTS_MAX];
    size_t n = fp_hand_points(in, h, a->points, pts);
    const double touch = fp_touch_radius(in);
    if (a->surface->nearest(a->host, (const float (*)[3])pts, n, (float)(reach * touch), hit))
        return -1;
    int got = 0;
    for (size_t p = 0; p < n && (size_t)got < room; p++) {
        if (hit[p].vertex == UINT32_MAX || !(hit[p].distance <= reach * touch)) continue;
        add_point(a, h, p, hit[p].position, pts[p], hit[p].vertex, hit[p].distance);
        got++;
    }
    return got;
}

/* A requested engage with nothing within release x R (a pedal pressed with the hand away
 * from the face): the one point of contact nearest the skin grabs the skin nearest it, so
 * the request always takes hold. Returns 1, 0 (no point, or no room), or -1 as grab. */
static int grab_nearest(anchored *a, const fp_frame_input *in, int h, size_t room)
{
    if (!a->surface || !a->surface->nearest) return -1;
    if (!room) return 0;
    float pts[FP_POINTS_MAX][3];
    fp_surface_hit hit[FP_POINTS_MAX];
    size_t n = fp_hand_points(in, h, a->points, pts), best = n;
    if (a->surface->nearest(a->host, (const float (*)[3])pts, n, INFINITY, hit)) return -1;
    for (size_t p = 0; p < n; p++)
        if (hit[p].vertex != UINT32_MAX && (best == n || hit[p].distance < hit[best].distance)) best = p;
    if (best == n) return 0;
    add_point(a, h, best, hit[best].position, pts[best], hit[best].vertex, hit[best].distance);
    return 1;
}

/* The paper's start points (a host without the surface service): the points themselves. */
static void take_points(anchored *a, const fp_frame_input *in, int h, size_t room)
{
    float pts[FP_POINTS_MAX][3];
    size_t n = fp_hand_points(in, h, a->points, pts);
    for (size_t p = 0; p < n && p < room; p++) add_point(a, h, p, pts[p], pts[p], UINT32_MAX, 0);
}

/* One grab per bit of skin: the points taken nearest their skin first (ties: the earlier),
 * each kept unless a point kept already grabbed skin within `apart` (mesh units) of its
 * own; the others let go. So two fingertips pinched together grab the skin once, and
 * opening them does not ask one bit of skin to go two ways (start points a fingertip's
 * width apart lie a triangle or two apart: no map of the mesh can pull them far apart
 * without folding it, and the fold-over guard then held the gesture to a few percent).
 * The kept points stay in their order. */
static void one_grab_per_skin(anchored *a, double apart)
{
    if (!(apart > 0) || a->count < 2) return;
    size_t order[FP_CONTROL_CAPACITY];
    for (size_t i = 0; i < a->count; i++) order[i] = i;
    for (size_t i = 1; i < a->count; i++) /* insertion sort by (gap, index): a few dozen */
        for (size_t j = i; j > 0 && a->gap[order[j]] < a->gap[order[j - 1]]; j--) {
            size_t t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    bool keep[FP_CONTROL_CAPACITY] = {false};
    for (size_t o = 0; o < a->count; o++) {
        size_t i = order[o];
        keep[i] = true;
        for (size_t q = 0; q < o && keep[i]; q++) {
            size_t j = order[q];
            if (!keep[j]) continue;
            double d2 = 0;
            for (int c = 0; c < 3; c++)
                d2 += ((double)a->start[i][c] - a->start[j][c]) * ((double)a->start[i][c] - a->start[j][c]);
            if (d2 < apart * apart) keep[i] = false;
        }
    }
    size_t kept = 0;
    for (size_t i = 0; i < a->count; i++) {
        if (!keep[i]) continue;
        if (kept != i) {
            memcpy(a->start[kept], a->start[i], sizeof a->start[i]);
            memcpy(a->offset[kept], a->offset[i], sizeof a->offset[i]);
            memcpy(a->rest_of[kept], a->rest_of[i], sizeof a->rest_of[i]);
            a->hand_of[kept] = a->hand_of[i];
            a->point_of[kept] = a->point_of[i];
            a->gap[kept] = a->gap[i];
        }
        kept++;
    }
    a->count = kept;
}

static int engage(anchored *a, const fp_frame_input *in, bool requested, size_t capacity)
{
    unsigned which = 0;
    int nh = fp_frame_hand_count(in);
    for (int h = 0; h < nh; h++) { /* every performer's hands: side h % FP_HANDS */
        if (!(a->hands & (1u << (h % FP_HANDS))) || !fp_frame_hand(in, h)->present) continue;
        if (requested || hand_near(a, in, h, a->engage)) which |= 1u << h;
    }
    if (!which) return 0;
    a->count = 0;
    unsigned grabbed = 0;
    size_t cap = capacity < FP_CONTROL_CAPACITY ? capacity : FP_CONTROL_CAPACITY;
    for (int h = 0; h < nh; h++) {
        if (!(which & (1u << h))) continue;
        int got = grab(a, in, h, a->engage, cap - a->count);
        if (got == 0 && requested) got = grab(a, in, h, a->release, cap - a->count);
        if (got == 0 && requested) got = grab_nearest(a, in, h, cap - a->count);
        if (got < 0) {
            take_points(a, in, h, cap - a->count);
            got = 1;
        }
        if (got > 0) grabbed |= 1u << h;
    }
    if (!a->count) return 0;
    one_grab_per_skin(a, a->apart * fp_touch_radius(in));
    a->engaged = true;
    a->engaged_hands = grabbed;
    memcpy(a->last_end, a->start, a->count * sizeof a->start[0]);
    return 1;
}

/* The rest shape for widen: the first base this instance sees (the loaded face, or the
 * rig's posed base at the first frame), copied once; again if the vertex count changes. */
static int keep_rest(anchored *a, const fp_frame_input *in)
{
    if (!in->mesh || !in->mesh->base || (a->rest && a->rest_n == in->mesh->vertex_count)) return 0;
    free(a->rest);
    a->rest_n = 0;
    if (!(a->rest = malloc(in->mesh->vertex_count * 3 * sizeof *a->rest))) return -ENOMEM;
    memcpy(a->rest, in->mesh->base, in->mesh->vertex_count * 3 * sizeof *a->rest);
    a->rest_n = in->mesh->vertex_count;
    return 0;
}

static int process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    anchored *a = self->plugin_data;
    out->active = false;
    out->intents = 0;
    out->count = 0;
    out->channel_count = 0;
    out->radius = in->radius;
    if (a->widen > 0 && keep_rest(a, in) < 0) return -ENOMEM;
    if (a->engaged && (in->requested & FP_INTENT_CANCEL)) {
        a->engaged = false;
        out->intents = FP_INTENT_CANCEL;
        return 0;
    }
    if (!a->engaged) {
        bool requested = in->requested & FP_INTENT_ENGAGE;
        if (!requested && !a->automatic) return 0;
        if (!engage(a, in, requested, out->capacity)) return 0;
        out->intents |= FP_INTENT_ENGAGE;
    }
    if (out->capacity < a->count) return -ENOSPC;
    /* End points: each grabbed skin point plus how far its point of contact moved since
     * engage (a hand that vanished keeps its last). */
    bool still_near = false;
    float pts[FP_MAX_FRAME_HANDS][FP_POINTS_MAX][3];
    int nh = fp_frame_hand_count(in);
    for (int h = 0; h < nh; h++) {
        if (!(a->engaged_hands & (1u << h)) || !fp_frame_hand(in, h)->present) continue;
        fp_hand_points(in, h, a->points, pts[h]);
        if (hand_near(a, in, h, a->release)) still_near = true;
    }
    for (size_t i = 0; i < a->count; i++) {
        int h = a->hand_of[i];
        if (h < nh && fp_frame_hand(in, h)->present)
            for (int c = 0; c < 3; c++) a->last_end[i][c] = pts[h][a->point_of[i]][c] + a->offset[i][c];
        memcpy(out->start[i], a->start[i], sizeof a->start[i]);
        memcpy(out->end[i], a->last_end[i], sizeof a->last_end[i]);
        fp_clamp_vector(out->start[i], out->end[i], a->clamp * in->radius);
    }
    out->count = a->count;
    out->active = true;
    /* a drag that carries the skin far widens the support (fp_drag_radius) */
    out->radius = fp_drag_radius(in->radius, a->widen, (const float (*)[3])a->rest_of,
                                 (const float (*)[3])out->start, (const float (*)[3])out->end, a->count);
    bool commit = (in->requested & FP_INTENT_COMMIT) ||
                  (a->automatic && !(out->intents & FP_INTENT_ENGAGE) && !still_near);
    if (commit) {
        out->intents |= FP_INTENT_COMMIT;
        a->engaged = false;
    }
    return 0;
}

static void reset(fp_mapping *self)
{
    anchored *a = self->plugin_data;
    a->engaged = false;
    a->count = 0;
}

static void destroy(fp_mapping *self)
{
    anchored *a = self->plugin_data;
    free(a->rest);
    free(a);
}

/* The keys, typed (ABI 1.1): `facepuppet plugins` prints them, fpmu_params_parse checks
 * them. The order is that of the values create reads. */
enum { KEY_HANDS, KEY_AUTO, KEY_RELEASE, KEY_CLAMP, KEY_ENGAGE, KEY_POINTS, KEY_WIDEN, KEY_APART, KEY_COUNT };
static const fp_param_info keys[KEY_COUNT + 1] = {
    {.name = "hands", .type = FP_PARAM_ENUM, .default_value = "both", .choices = "left|right|both",
     .description = "which hands deform"},
    {.name = "auto", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "1",
     .description = "engage when a fingertip comes within engage x R of the surface, commit when the hand lets go"},
    {.name = "release", .type = FP_PARAM_FLOAT, .min = 0.1, .max = 100, .default_value = "1.0",
     .unit = "R",
     .description = "auto commit once every engaged fingertip is farther than release x R (at least engage)"},
    {.name = "clamp", .type = FP_PARAM_FLOAT, .min = 0, .max = 100, .default_value = "0",
     .unit = "R",
     .description = "longest control vector (0: no limit; the host composes long drags injectively)"},
    {.name = "engage", .type = FP_PARAM_FLOAT, .min = 0.01, .max = 100, .default_value = "0.5",
     .unit = "R",
     .description = "auto engage once a fingertip is within engage x R of the surface"},
    {.name = "points", .type = FP_PARAM_ENUM, .default_value = "tips", .choices = FP_POINTS_CHOICES,
     .description = "points of contact per hand: the 5 tips, + palm centre and knuckles (11), every joint (21)"},
    {.name = "widen", .type = FP_PARAM_FLOAT, .min = 0, .max = 100, .default_value = "0.5",
     .unit = "R",
     .description = "skin dragged farther than widen x R from rest widens the support to that distance / widen, so the skin around follows (0: the radius stays)"},
    {.name = "apart", .type = FP_PARAM_FLOAT, .min = 0, .max = 100, .default_value = "0.2",
     .unit = "R",
     .description = "points whose grabbed skin lies within apart x R grab it once: the one nearest the skin holds it (0: every point grabs)"},
    {.name = NULL},
};
static const unsigned hand_masks[] = {FP_HANDMASK_LEFT, FP_HANDMASK_RIGHT, FP_HANDMASK_BOTH};

static int create(const fp_host *host, const fp_param *params, size_t nparams,
                  fp_mapping **out, char *err, size_t errlen)
{
    fpmu_value v[KEY_COUNT];
    int rc = fpmu_params_parse("anchored", keys, params, nparams, v, err, errlen);
    if (rc) return rc;
    if (v[KEY_ENGAGE].number > v[KEY_RELEASE].number) { /* (it would commit as it engages) */
        snprintf(err, errlen, "anchored: key 'engage' (%g) is beyond key 'release' (%g): a hand "
                 "engages within engage x R and lets go beyond release x R, so engage <= release",
                 v[KEY_ENGAGE].number, v[KEY_RELEASE].number);
        return -EINVAL;
    }
    anchored *a = calloc(1, sizeof *a);
    if (!a) return -ENOMEM;
    a->hands = hand_masks[(int)v[KEY_HANDS].number];
    a->automatic = v[KEY_AUTO].number != 0;
    a->engage = v[KEY_ENGAGE].number;
    a->release = v[KEY_RELEASE].number;
    a->clamp = v[KEY_CLAMP].number;
    a->points = (int)v[KEY_POINTS].number;
    a->widen = v[KEY_WIDEN].number;
    a->apart = v[KEY_APART].number;
    int joints[FP_POINTS_MAX];
    a->per_hand = fp_points_joints(a->points, joints);
    a->host = host;
    a->surface = host && host->get_extension ? host->get_extension(host, FP_HOST_EXT_SURFACE) : NULL;
    a->mapping.size = sizeof a->mapping;
    a->mapping.plugin_data = a;
    a->mapping.process = process;
    a->mapping.reset = reset;
    a->mapping.destroy = destroy;
    *out = &a->mapping;
    return 0;
}

static const fp_mapping_factory factory = {
    .size = sizeof(fp_mapping_factory),
    .name = "anchored",
    .description = "the paper's anchored mode, grabbing the skin: start points on the skin at engage, end points follow the fingers",
    .usage = "anchored[,hands=left|right|both][,auto=0|1][,engage=F][,release=F][,clamp=F]\n"
             "        [,points=tips|tips+palm|all][,widen=F][,apart=F]\n"
             "  auto=1 engages when a fingertip comes within engage*R of the surface (0.5)\n"
             "  and commits when the hand lets go (farther than release*R, 1.0; engage <=\n"
             "  release; R here: the face's default radius, whatever --radius makes the\n"
             "  support). The points touching the face (within engage*R) grab the skin under\n"
             "  them: the grabbed skin moves as the fingertip moves; the others pull nothing.\n"
             "  clamp limits each control vector to clamp*R (0: none, the default).\n"
             "  points: the fingertips (5 per hand, the paper's), tips+palm (+ palm centre and\n"
             "  knuckles: 11) or all (every joint: 21 per hand, 42 for two).\n"
             "  widen: skin dragged farther than widen*R from where it was at rest widens the\n"
             "  support to that distance / widen (0.5), so the skin around follows; 0: never.\n"
             "  apart: points whose grabbed skin lies within apart*R of each other (0.2; a\n"
             "  fingertip's width) grab it once, the one nearest its skin holding it: two\n"
             "  fingertips pinched together and then opened do not pull one bit of skin two\n"
             "  ways; 0: each point grabs its own.\n"
             "  Every performer's hands grab (inputs' performer=NAME): hands= picks the sides.",
    .create = create,
    .params = keys,
};

static const void *get_factory(const char *id)
{
    return !strcmp(id, FP_MAPPING_FACTORY_ID) ? &factory : NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.map-anchored",
    .version = "1.0",
    .get_factory = get_factory,
};
