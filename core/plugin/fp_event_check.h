/*
 * fp_event_check.h: what makes an input event malformed, by its content alone. One rule for
 * the host, which refuses such events at push_event (core/plugin/input.c: a user's plugin
 * that sends a NaN, a position kilometres away or a torn struct never reaches a hand), and
 * for the plugin validator (check.c, `facepuppet plugins check`, which adds the times).
 *
 * The rule, by fp_event_type (plugin.h): a known type whose header.size is its struct's;
 * hand -1, 0 or 1, and 0 or 1 for the pose events (angles, positions, wrist); every float
 * finite; joint and wrist positions within FP_EVENT_MAX_MM of the device's origin on every
 * axis; a wrist rotation of norm 1 within 1e-2 (of its square); a button one fp_button bit,
 * down 0 or 1, mask under 8; a known status code and a NUL-terminated text; a channel's
 * name NUL-terminated and not empty.
 * Threads: pure functions, any thread. SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FP_EVENT_CHECK_H
#define FP_EVENT_CHECK_H

#include <facepuppet/plugin.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The reasons an event is refused, for counting; FP_EVENT_OK (0) when it is well formed. */
typedef enum fp_event_fault {
    FP_EVENT_OK = 0,
    FP_EVENT_BAD_TYPE,      /* unknown type */
    FP_EVENT_BAD_SIZE,      /* size is not that of its type */
    FP_EVENT_BAD_HAND,      /* hand not -1, 0 or 1, or a pose event without a hand */
    FP_EVENT_NOT_FINITE,    /* a NaN or an infinity */
    FP_EVENT_TOO_FAR,       /* a position beyond FP_EVENT_MAX_MM */
    FP_EVENT_BAD_ROTATION,  /* not a unit quaternion */
    FP_EVENT_BAD_FIELD,     /* a button, status or channel field out of its range */
    FP_EVENT_FAULTS
} fp_event_fault;

/** Why ev is malformed (an fp_event_fault, FP_EVENT_OK when it is not). *why (may be NULL)
 *  gets a static English phrase saying which field, e.g. "a joint position is not finite".
 *  ev: a whole fp_event (at least header.size bytes, as the queue holds them). */
fp_event_fault fp_event_check(const fp_event *ev, const char **why);

#ifdef __cplusplus
}
#endif
#endif
