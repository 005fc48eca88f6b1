/*
 * facepuppet/plugin_util.h: small inline helpers for any plugin author (input or mapping),
 * on top of facepuppet/plugin.h. Header-only, no allocation, reentrant, [any-thread].
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FACEPUPPET_PLUGIN_UTIL_H
#define FACEPUPPET_PLUGIN_UTIL_H

#include <facepuppet/plugin.h>
#include <string.h>

/** A set of hands: a bit per fp_hand_side (the `hands=` key of mappings and of replay). */
#define FP_HANDMASK_LEFT (1u << FP_HAND_LEFT)
#define FP_HANDMASK_RIGHT (1u << FP_HAND_RIGHT)
#define FP_HANDMASK_BOTH (FP_HANDMASK_LEFT | FP_HANDMASK_RIGHT)

/** The one parser of a `hands=` value: "left", "right" or "both" -> FP_HANDMASK_*; 0 for
 *  anything else (the caller reports "hands=V: expected left, right or both"). */
static inline unsigned fp_parse_hands(const char *v)
{
    if (!v) return 0;
    if (!strcmp(v, "left")) return FP_HANDMASK_LEFT;
    if (!strcmp(v, "right")) return FP_HANDMASK_RIGHT;
    if (!strcmp(v, "both")) return FP_HANDMASK_BOTH;
    return 0;
}

/** The one parser of an on/off key's value (mapping_util.h's FP_PARAM_BOOL uses it too):
 *  "1", "true", "yes", "on" -> 1; "0", "false", "no", "off" -> 0; anything else (NULL too)
 *  -> -1 (the caller reports "KEY=V: expected 0 or 1"). [any-thread], no allocation. */
static inline int fp_parse_bool(const char *v)
{
    if (!v) return -1;
    if (!strcmp(v, "1") || !strcmp(v, "true") || !strcmp(v, "yes") || !strcmp(v, "on")) return 1;
    if (!strcmp(v, "0") || !strcmp(v, "false") || !strcmp(v, "no") || !strcmp(v, "off")) return 0;
    return -1;
}

/** The `hands=` value naming mask: "left", "right" or "both" (any other mask). */
static inline const char *fp_hands_name(unsigned mask)
{
    return mask == FP_HANDMASK_LEFT ? "left" : mask == FP_HANDMASK_RIGHT ? "right" : "both";
}

#endif
