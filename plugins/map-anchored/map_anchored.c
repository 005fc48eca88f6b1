/*
 * map-anchored: the anchored mapping of Sato, Savchenko, Ohbuchi (Cyberworlds 2004,
 * sec. 2.3.1). At engage the start points s_i are the fingertips of the engaged hands and
 * stay fixed; the end points d_i follow the fingers every frame, so the host reuses one
 * factorization for the whole gesture; commit folds the deformed shape into the base,
 * cancel drops it.
 *
 * Engage and commit come from the performer's requests (FP_INTENT_ENGAGE / _COMMIT /
 * _CANCEL: pedal, keys) and, unless auto=0, from the paper's rule: engage when a hand's
 * fingertip comes within engage x R of the surface; commit when every engaged hand's
 * fingertips are farther than release x R from the base (the hand has let go). The start
 * points are the fingertips at engage: engaging at the support's edge (engage=1) would hold
 * the surface where the Wendland function is ~0 and move nothing, so the default engages at
 * half the radius (psi_{3,1}(0.5) = 0.19 there) and releases at R (hysteresis). The host's
 * fp_frame_input.tip_distance is exact up to FP_TIP_DISTANCE_REACH x R; an engage or release
 * factor beyond it asks the host's surface service (FP_HOST_EXT_SURFACE) for that reach.
 *
 * Keys: hands=left|right|both (both), auto=0|1 (1), engage=F (0.5, in R), release=F (1.0, in R;
 *       at least engage, else a hand would let go as it engages: refused at create),
 *       clamp=F (0.45, longest control vector in R; 0 = no limit; keeps the warp
 *       injective, shared/docs/csrbf.md pitfall 4), points=tips|tips+palm|all (tips: the
 *       paper's fingertips; tips+palm adds the palm centre and the knuckles, all every
 *       joint: 5, 11 or 21 points per hand, mapping_util.h fp_points).
 */
#include <facepuppet/mapping_util.h>
#include <facepuppet/plugin.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct anchored {
    fp_mapping mapping;
    unsigned hands;              /* FP_HANDMASK_* listened to */
    bool automatic;
    double engage, release, clamp;
    int points;                  /* fp_points mode */
    size_t per_hand;             /* points per hand (FP_POINTS_*_COUNT) */
    bool engaged;
    unsigned engaged_hands;      /* hands whose tips are the start points */
    size_t count;
    float start[FP_CONTROL_CAPACITY][3];
    float last_end[FP_CONTROL_CAPACITY][3];
    const fp_host *host;
    const fp_host_surface *surface; /* FP_HOST_EXT_SURFACE, or NULL (a 1.0 host) */
} anchored;

/* The paper's rule with `factor` x R: the host's tip distances where they reach that far,
 * else the surface service with that reach (a 1.0 host's distances are exact anyway). */
static bool hand_near(const anchored *a, const fp_frame_input *in, int h, double factor)
{
    if (factor <= FP_TIP_DISTANCE_REACH || !a->surface || !a->surface->nearest)
        return fp_hand_is_near(in, h, factor);
    if (!in->hands[h].present) return false;
    float tips[FP_FINGERS][3];
    fp_surface_hit hit[FP_FINGERS];
    fp_hand_tips(in, h, tips);
    if (a->surface->nearest(a->host, (const float (*)[3])tips, FP_FINGERS, (float)(factor * in->radius), hit))
        return fp_hand_is_near(in, h, factor);
    for (int f = 0; f < FP_FINGERS; f++)
        if (hit[f].distance < factor * in->radius) return true;
    return false;
}

static int engage(anchored *a, const fp_frame_input *in, bool requested)
{
    unsigned which = 0;
    for (int h = 0; h < FP_HANDS; h++) {
        if (!(a->hands & (1u << h)) || !in->hands[h].present) continue;
        if (requested || hand_near(a, in, h, a->engage)) which |= 1u << h;
    }
    if (!which) return 0;
    a->engaged = true;
    a->engaged_hands = which;
    a->count = 0;
    for (int h = 0; h < FP_HANDS; h++) {
        if (!(which & (1u << h))) continue;
        a->count += fp_hand_points(in, h, a->points, &a->start[a->count]);
    }
    memcpy(a->last_end, a->start, a->count * sizeof a->start[0]);
    return 1;
}

static int process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    anchored *a = self->plugin_data;
    out->active = false;
    out->intents = 0;
    out->count = 0;
    out->channel_count = 0;
    out->radius = in->radius;
    if (a->engaged && (in->requested & FP_INTENT_CANCEL)) {
        a->engaged = false;
        out->intents = FP_INTENT_CANCEL;
        return 0;
    }
    if (!a->engaged) {
        bool requested = in->requested & FP_INTENT_ENGAGE;
        if (!requested && !a->automatic) return 0;
        if (!engage(a, in, requested)) return 0;
        out->intents |= FP_INTENT_ENGAGE;
    }
    if (out->capacity < a->count) return -ENOSPC;
    /* End points: the engaged hands' fingertips now (a hand that vanished keeps its last). */
    size_t k = 0;
    bool still_near = false;
    for (int h = 0; h < FP_HANDS; h++) {
        if (!(a->engaged_hands & (1u << h))) continue;
        if (in->hands[h].present) {
            fp_hand_points(in, h, a->points, &a->last_end[k]);
            if (hand_near(a, in, h, a->release)) still_near = true;
        }
        k += a->per_hand;
    }
    for (size_t i = 0; i < a->count; i++) {
        memcpy(out->start[i], a->start[i], sizeof a->start[i]);
        memcpy(out->end[i], a->last_end[i], sizeof a->last_end[i]);
        fp_clamp_vector(out->start[i], out->end[i], a->clamp * in->radius);
    }
    out->count = a->count;
    out->active = true;
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
    free(self->plugin_data);
}

/* The keys, typed (ABI 1.1): `facepuppet plugins` prints them, fpmu_params_parse checks
 * them. The order is that of the values create reads. */
enum { KEY_HANDS, KEY_AUTO, KEY_RELEASE, KEY_CLAMP, KEY_ENGAGE, KEY_POINTS, KEY_COUNT };
static const fp_param_info keys[KEY_COUNT + 1] = {
    {.name = "hands", .type = FP_PARAM_ENUM, .default_value = "both", .choices = "left|right|both",
     .description = "which hands deform"},
    {.name = "auto", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "1",
     .description = "engage when a fingertip comes within engage x R of the surface, commit when the hand lets go"},
    {.name = "release", .type = FP_PARAM_FLOAT, .min = 0.1, .max = 100, .default_value = "1.0",
     .unit = "R",
     .description = "auto commit once every engaged fingertip is farther than release x R (at least engage)"},
    {.name = "clamp", .type = FP_PARAM_FLOAT, .min = 0, .max = 100, .default_value = "0.45",
     .unit = "R", .description = "longest control vector (0: no limit)"},
    {.name = "engage", .type = FP_PARAM_FLOAT, .min = 0.01, .max = 100, .default_value = "0.5",
     .unit = "R",
     .description = "auto engage once a fingertip is within engage x R of the surface"},
    {.name = "points", .type = FP_PARAM_ENUM, .default_value = "tips", .choices = FP_POINTS_CHOICES,
     .description = "points of contact per hand: the 5 tips, + palm centre and knuckles (11), every joint (21)"},
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
    .description = "the paper's anchored mode: start points fixed at engage, end points follow",
    .usage = "anchored[,hands=left|right|both][,auto=0|1][,engage=F][,release=F][,clamp=F]\n"
             "        [,points=tips|tips+palm|all]\n"
             "  auto=1 engages when a fingertip comes within engage*R of the surface (0.5)\n"
             "  and commits when the hand lets go (farther than release*R, 1.0; engage <=\n"
             "  release); clamp limits each control vector to clamp*R (0.45 keeps the warp free\n"
             "  of fold-over).\n"
             "  points: the fingertips (5 per hand, the paper's), tips+palm (+ palm centre and\n"
             "  knuckles: 11) or all (every joint: 21 per hand, 42 for two).",
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
