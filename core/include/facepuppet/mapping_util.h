/*
 * facepuppet/mapping_util.h: small inline helpers for mapping plugin authors, on top of
 * facepuppet/plugin.h. Header-only; nothing here allocates, so every function is safe on
 * the [session-thread].
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FACEPUPPET_MAPPING_UTIL_H
#define FACEPUPPET_MAPPING_UTIL_H

#include <facepuppet/plugin.h>
#include <errno.h>
#include <facepuppet/plugin_util.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Which hands a mapping listens to: FP_HANDMASK_* and fp_parse_hands, in plugin_util.h. */

/** The radius touch distances are measured in (fp_frame_input.touch_radius: the face's
 *  default support radius, whatever --radius makes the support), or the support radius
 *  where the host does not give it. Mesh units; pure. */
static inline double fp_touch_radius(const fp_frame_input *in)
{
    return FP_HAS_FIELD(in, fp_frame_input, touch_radius) && in->touch_radius > 0 ? in->touch_radius
                                                                                   : in->radius;
}

/** Every performer's hands as one list (ABI 1.3): hand i is performer i / FP_HANDS's hand of
 *  side i % FP_HANDS (fp_hand_side), so 0 and 1 are fp_frame_input.hands (the first
 *  performer's) and from FP_HANDS on fp_frame_input.extra_hands. fp_frame_hand_count gives
 *  FP_HANDS x the performers (FP_HANDS from a host before 1.3, or with one performer; at
 *  most FP_HANDS x FP_PERFORMER_CAPACITY). The hand functions below take such an index. */
#define FP_MAX_FRAME_HANDS (FP_HANDS * FP_PERFORMER_CAPACITY)
static inline int fp_frame_hand_count(const fp_frame_input *in)
{
    if (!FP_HAS_FIELD(in, fp_frame_input, extra_tip_distance) || !in->extra_hands || !in->extra_tip_distance)
        return FP_HANDS;
    uint32_t extra = in->extra_performers < FP_PERFORMER_CAPACITY - 1 ? in->extra_performers
                                                                      : FP_PERFORMER_CAPACITY - 1;
    return FP_HANDS * (1 + (int)extra);
}

/** Hand i of fp_frame_hand_count's list (i below the count): its pose, mesh units. */
static inline const fp_hand_pose *fp_frame_hand(const fp_frame_input *in, int i)
{
    return i < FP_HANDS ? &in->hands[i] : &in->extra_hands[i - FP_HANDS];
}

/** Hand i's fingertip distances (FP_FINGERS of them, as fp_frame_input.tip_distance). */
static inline const float *fp_frame_tip_distance(const fp_frame_input *in, int i)
{
    return i < FP_HANDS ? in->tip_distance[i] : in->extra_tip_distance[i - FP_HANDS];
}

/** The paper's activation rule (Sato et al. 2004, sec. 2.3): a hand is active while one of
 *  its fingertips is within `factor` x the touch radius (fp_touch_radius: the support radius
 *  at the face's default) of the surface. Exact for factor <= FP_TIP_DISTANCE_REACH (the
 *  host's tip distances are +INFINITY beyond it); farther out, ask FP_HOST_EXT_SURFACE with
 *  that reach (map-anchored does). `hand`: an index of fp_frame_hand_count's list (0 left,
 *  1 right: the first performer's). */
static inline bool fp_hand_is_near(const fp_frame_input *in, int hand, double factor)
{
    if (!fp_frame_hand(in, hand)->present) return false;
    const double touch = fp_touch_radius(in);
    const float *d = fp_frame_tip_distance(in, hand);
    for (int f = 0; f < FP_FINGERS; f++)
        if (d[f] < factor * touch) return true;
    return false;
}

/** Copy hand `hand`'s five fingertips (thumb..pinky) into tips[5][3], mesh units (`hand` as
 *  fp_hand_is_near's). */
static inline void fp_hand_tips(const fp_frame_input *in, int hand, float tips[FP_FINGERS][3])
{
    const fp_hand_pose *p = fp_frame_hand(in, hand);
    for (int f = 0; f < FP_FINGERS; f++)
        memcpy(tips[f], p->joints[FP_JOINT_TIP(f)], sizeof tips[f]);
}

/** Points of contact of one hand (the `points=` key of the anchored and unanchored
 *  mappings; the paper's fingertips, or more "to cover the palm of a hand", sec. 4):
 *   FP_POINTS_TIPS       the five fingertips (the paper's; 10 for two hands),
 *   FP_POINTS_TIPS_PALM  the tips, the palm centre and the five knuckles (the four fingers'
 *                        MCP joints and the thumb's MCP),
 *   FP_POINTS_ALL        every joint of the hand (FP_HAND_JOINTS; 42 for two hands).
 *  The tips always come first, thumb to little, so the first five points of every mode are
 *  those of FP_POINTS_TIPS. FP_POINTS_CHOICES is the key's choices in enum order. */
typedef enum fp_points { FP_POINTS_TIPS = 0, FP_POINTS_TIPS_PALM = 1, FP_POINTS_ALL = 2 } fp_points;
#define FP_POINTS_CHOICES "tips|tips+palm|all"
/** Points per hand in each mode; FP_POINTS_MAX is the largest (two hands: 2 x it, within
 *  FP_CONTROL_CAPACITY; the fingertips of FP_MAX_FRAME_HANDS hands fit too, 40, but not
 *  every joint of more than three hands: a mapping leaves the later performers' out). */
#define FP_POINTS_TIPS_COUNT FP_FINGERS
#define FP_POINTS_TIPS_PALM_COUNT (2 * FP_FINGERS + 1)
#define FP_POINTS_ALL_COUNT FP_HAND_JOINTS
#define FP_POINTS_MAX FP_HAND_JOINTS

/** The joints (fp_hand_joint indices) of `mode` into joints[FP_POINTS_MAX]; returns how
 *  many (FP_POINTS_*_COUNT; 0 for an unknown mode). */
static inline size_t fp_points_joints(int mode, int joints[FP_POINTS_MAX])
{
    size_t n = 0;
    for (int f = 0; f < FP_FINGERS; f++) joints[n++] = FP_JOINT_TIP(f);
    if (mode == FP_POINTS_TIPS_PALM) {
        joints[n++] = FP_JOINT_PALM;
        joints[n++] = FP_JOINT(0, 1);                 /* the thumb's MCP */
        for (int f = 1; f < FP_FINGERS; f++) joints[n++] = FP_JOINT(f, 0);
    } else if (mode == FP_POINTS_ALL) {
        for (int j = 0; j < FP_HAND_JOINTS; j++)
            if (j < FP_JOINT(0, 0) || (j - FP_JOINT(0, 0)) % 4 != 3) joints[n++] = j;
    } else if (mode != FP_POINTS_TIPS) {
        return 0;
    }
    return n;
}

/** Copy hand `hand`'s points of contact of `mode` into pts (at least FP_POINTS_MAX rows),
 *  mesh units; returns how many (as fp_points_joints). `hand` as fp_hand_is_near's. */
static inline size_t fp_hand_points(const fp_frame_input *in, int hand, int mode,
                                    float pts[][3])
{
    int joints[FP_POINTS_MAX];
    size_t n = fp_points_joints(mode, joints);
    const fp_hand_pose *p = fp_frame_hand(in, hand);
    for (size_t i = 0; i < n; i++) memcpy(pts[i], p->joints[joints[i]], sizeof pts[i]);
    return n;
}

/** Shorten the control vector start -> end to at most max_len (mesh units); max_len <= 0
 *  leaves it. Keeps the warp of a single control vector injective when max_len < 0.47 R
 *  (the fold-over bound R / max|psi'| of the Wendland psi_{3,1}; with several close vectors
 *  the host's own fold-over guard still acts). */
static inline void fp_clamp_vector(const float start[3], float end[3], double max_len)
{
    if (max_len <= 0) return;
    double d[3] = {end[0] - start[0], end[1] - start[1], end[2] - start[2]};
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (len <= max_len) return;
    double k = max_len / len;
    for (int i = 0; i < 3; i++) end[i] = (float)(start[i] + d[i] * k);
}

/** The support radius for a drag that carries the skin far: max(radius, d / widen), d the
 *  largest distance from a control vector's end point to where its skin was at rest
 *  (rest[i], n x 3 mesh units: the grabbed vertex's position in the loaded face; a vector
 *  with no known rest point gives its start point) or to its start point (start[i]: a drag
 *  that pushes skin back toward its rest is still a drag from where it is). A single Wendland map folds beyond a
 *  drag of 0.47 R, and a composition of injective maps still turns the skin around a drag
 *  of a few R over on itself (the grabbed point runs ahead of a support that stays R wide);
 *  a support that grows with the drag makes the skin around follow, as clay does, with the
 *  same slope at any length. widen <= 0 keeps radius. rest, start, end: n x 3 each. Mesh units
 *  in and out; no errors; pure (any thread). */
static inline double fp_drag_radius(double radius, double widen, const float (*rest)[3],
                                    const float (*start)[3], const float (*end)[3], size_t n)
{
    if (!(widen > 0)) return radius;
    double r = radius;
    for (size_t i = 0; i < n; i++) {
        double d[3] = {end[i][0] - rest[i][0], end[i][1] - rest[i][1], end[i][2] - rest[i][2]};
        double e[3] = {end[i][0] - start[i][0], end[i][1] - start[i][1], end[i][2] - start[i][2]};
        double dd = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double de = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        double w = (dd > de ? dd : de) / widen;
        if (w > r) r = w;
    }
    return r;
}

/** Parse a finite decimal number in [lo, hi] (plugin_util.h's fp_parse_decimal: no hex, inf
 *  or nan); false where the text is not one. */
static inline bool fp_parse_double(const char *v, double lo, double hi, double *out)
{
    double x;
    if (!fp_parse_decimal(v, &x) || x < lo || x > hi) return false;
    *out = x;
    return true;
}

/* ---- table-driven keys (ABI 1.1 fp_param_info) --------------------------------------- */

/** One parsed key: `number` for BOOL, INT, FLOAT and ENUM (the index of the choice in
 *  "a|b|c"), `text` for STRING and PATH (points into the host's SPEC: valid only during
 *  create; copy it). */
typedef struct fpmu_value {
    double number;
    const char *text;
} fpmu_value;

/* The index of `v` among the '|'-separated `choices`, or -1. */
static inline int fpmu_choice_index(const char *choices, const char *v)
{
    size_t n = strlen(v);
    int k = 0;
    for (const char *c = choices; c && *c; k++) {
        const char *bar = strchr(c, '|');
        size_t len = bar ? (size_t)(bar - c) : strlen(c);
        if (len == n && !strncmp(c, v, n)) return k;
        if (!bar) break;
        c = bar + 1;
    }
    return -1;
}

/* Parse one value of `info`'s type into *out; false where it is not one. */
static inline bool fpmu_parse_value(const fp_param_info *info, const char *v, fpmu_value *out)
{
    out->text = v;
    switch (info->type) {
    case FP_PARAM_BOOL: { /* plugin_util.h's words, as every on/off key */
        const int b = fp_parse_bool(v);
        if (b < 0) return false;
        out->number = b;
        return true;
    }
    case FP_PARAM_INT:
    case FP_PARAM_FLOAT: /* a decimal, as every number key (plugin_util.h) */
        if (!fp_parse_decimal(v, &out->number)) return false;
        if (info->type == FP_PARAM_INT && out->number != floor(out->number)) return false;
        return out->number >= info->min && out->number <= info->max;
    case FP_PARAM_ENUM:
        out->number = fpmu_choice_index(info->choices, v);
        return out->number >= 0;
    case FP_PARAM_STRING:
    case FP_PARAM_PATH:
        return info->type == FP_PARAM_STRING || *v;
    }
    return false;
}

/** The most keys fpmu_params_parse takes in one list. */
#define FPMU_MAX_KEYS 64

/** Parse a SPEC's keys against a factory's typed key list `info` (ended by a NULL name, at
 *  most FPMU_MAX_KEYS entries, else -EINVAL naming the plugin's bug):
 *  out[i] receives info[i]'s value, its default where the key is absent. Errors (-EINVAL,
 *  a message in err that begins with `plugin`): an unknown key (the message lists the keys),
 *  a value of the wrong type or outside [min, max] (the message gives the range or the
 *  choices), a required key (default NULL) that is missing, a default that does not parse. out must have as many entries as
 *  info. [main-thread] (a create call); no allocation. */
static inline int fpmu_params_parse(const char *plugin, const fp_param_info *info,
                                    const fp_param *params, size_t nparams, fpmu_value *out,
                                    char *err, size_t errlen)
{
    size_t n = 0;
    while (info[n].name) n++;
    if (n > FPMU_MAX_KEYS) { /* (the keys given are marked in a fixed array) */
        snprintf(err, errlen, "%s: %zu keys declared, at most %d (a bug in the plugin)", plugin, n,
                 FPMU_MAX_KEYS);
        return -EINVAL;
    }
    for (size_t i = 0; i < n; i++) {
        out[i].number = 0;
        out[i].text = NULL;
        if (info[i].default_value && !fpmu_parse_value(&info[i], info[i].default_value, &out[i])) {
            snprintf(err, errlen, "%s: the default of key '%s' is not valid (a bug in the plugin)",
                     plugin, info[i].name);
            return -EINVAL;
        }
    }
    bool given[FPMU_MAX_KEYS] = {false};
    for (size_t p = 0; p < nparams; p++) {
        size_t i = 0;
        while (i < n && strcmp(info[i].name, params[p].key)) i++;
        if (i == n) {
            int w = snprintf(err, errlen, "%s: unknown key '%s' (keys:", plugin, params[p].key);
            for (size_t j = 0; j < n && w >= 0 && (size_t)w < errlen; j++)
                w += snprintf(err + w, errlen - (size_t)w, "%s %s", j ? "," : "", info[j].name);
            if (w >= 0 && (size_t)w < errlen) snprintf(err + w, errlen - (size_t)w, ")");
            return -EINVAL;
        }
        if (!fpmu_parse_value(&info[i], params[p].value, &out[i])) {
            if (info[i].type == FP_PARAM_ENUM)
                snprintf(err, errlen, "%s: key '%s': '%s' is not one of %s", plugin, info[i].name,
                         params[p].value, info[i].choices ? info[i].choices : "(none)");
            else if (info[i].type == FP_PARAM_INT || info[i].type == FP_PARAM_FLOAT)
                snprintf(err, errlen, "%s: key '%s': '%s' is not a%s number in [%g, %g]%s%s", plugin,
                         info[i].name, params[p].value, info[i].type == FP_PARAM_INT ? "n integer" : "",
                         info[i].min, info[i].max, info[i].unit ? " " : "", info[i].unit ? info[i].unit : "");
            else
                snprintf(err, errlen, "%s: key '%s': bad value '%s'", plugin, info[i].name,
                         params[p].value);
            return -EINVAL;
        }
        given[i] = true;
    }
    for (size_t i = 0; i < n; i++)
        if (!info[i].default_value && !given[i]) {
            snprintf(err, errlen, "%s: key '%s' is required (%s)", plugin, info[i].name,
                     info[i].description ? info[i].description : "no default");
            return -EINVAL;
        }
    return 0;
}

#endif
