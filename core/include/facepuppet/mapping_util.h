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
#include <facepuppet/plugin_util.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Which hands a mapping listens to: FP_HANDMASK_* and fp_parse_hands, in plugin_util.h. */

/** The paper's activation rule (Sato et al. 2004, sec. 2.3): a hand is active while one of
 *  its fingertips is within `factor` x the support radius of the surface. */
static inline bool fp_hand_is_near(const fp_frame_input *in, int hand, double factor)
{
    if (!in->hands[hand].present) return false;
    for (int f = 0; f < FP_FINGERS; f++)
        if (in->tip_distance[hand][f] < factor * in->radius) return true;
    return false;
}

/** Copy hand `hand`'s five fingertips (thumb..pinky) into tips[5][3], mesh units. */
static inline void fp_hand_tips(const fp_frame_input *in, int hand, float tips[FP_FINGERS][3])
{
    for (int f = 0; f < FP_FINGERS; f++)
        memcpy(tips[f], in->hands[hand].joints[FP_JOINT_TIP(f)], sizeof tips[f]);
}

/** Shorten the control vector start -> end to at most max_len (mesh units); max_len <= 0
 *  leaves it. Keeps the warp injective when max_len < 0.47 R for psi_{3,1}
 *  (shared/docs/csrbf.md, pitfall 4). */
static inline void fp_clamp_vector(const float start[3], float end[3], double max_len)
{
    if (max_len <= 0) return;
    double d[3] = {end[0] - start[0], end[1] - start[1], end[2] - start[2]};
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (len <= max_len) return;
    double k = max_len / len;
    for (int i = 0; i < 3; i++) end[i] = (float)(start[i] + d[i] * k);
}

/** Parse a finite double in [lo, hi]; false where the text is not one. */
static inline bool fp_parse_double(const char *v, double lo, double hi, double *out)
{
    char *end;
    double x = strtod(v, &end);
    if (end == v || *end || !isfinite(x) || x < lo || x > hi) return false;
    *out = x;
    return true;
}

#endif
