/*
 * fp_control_check.h: what makes a mapping's control set malformed. One rule for the host,
 * which refuses such a set (core/session/step_mapping.c: nothing deformed, nothing recorded),
 * and for the plugin validator (check.c, `facepuppet plugins check`, which names the vector
 * and its point in its finding), so a plugin the validator passes is never refused by the
 * host for its control set, and the reverse.
 *
 * The rule (plugin.h's fp_control_set): count <= capacity and channel_count <=
 * channel_capacity; start and end not NULL when count > 0; each of the first count start
 * and end points finite with every coordinate within FP_CONTROL_COORD_MAX mesh units; and,
 * when the set is active, a radius within [FP_CONTROL_RADIUS_MIN, FP_CONTROL_RADIUS_MAX]
 * mesh units (an inactive set deforms nothing: its radius is not the mapping's to keep, the
 * host gives it the session's before recording it). Channels are not part of it: the rig
 * step ignores a NaN value and reads a name as at most its array's length.
 * Threads: pure function, any thread. SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FP_CONTROL_CHECK_H
#define FP_CONTROL_CHECK_H

#include <stddef.h>

#include <facepuppet/plugin.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Why a control set is malformed; FP_CONTROL_OK (0) when it is not. */
typedef enum fp_control_fault {
    FP_CONTROL_OK = 0,
    FP_CONTROL_OVER_CAPACITY, /* count > capacity or channel_count > channel_capacity */
    FP_CONTROL_NO_ARRAY,      /* start or end NULL with count > 0 */
    FP_CONTROL_BAD_POINT,     /* a start or end point not finite or beyond FP_CONTROL_COORD_MAX */
    FP_CONTROL_BAD_RADIUS     /* active, radius outside the host's range (NaN included) */
} fp_control_fault;

/** Check cs (not NULL) against the rule above. On FP_CONTROL_BAD_POINT, *vector (may be
 *  NULL) gets the first offending control vector's index and *is_start whether its start
 *  point (else its end point) is the offending one (may be NULL). Reads the first count
 *  entries of cs->start and cs->end; writes nothing else. */
fp_control_fault fp_control_check(const fp_control_set *cs, size_t *vector, int *is_start);

#ifdef __cplusplus
}
#endif

#endif
