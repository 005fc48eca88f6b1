/*
 * fp_event_check.h: what makes an input event malformed, by its content alone. One rule for
 * the host, which refuses such events at push_event (core/plugin/input.c: a user's plugin
 * that sends a NaN, a position kilometres away or a torn struct never reaches a hand), and
 * for the plugin validator (check.c, `facepuppet plugins check`). Both apply the content
 * rule (fp_event_check) and the time rule (fp_event_check_time) alike.
 *
 * The rule, by fp_event_type (plugin.h): a known type whose header.size is its struct's;
 * hand -1, 0 or 1, and 0 or 1 for the pose events (angles, positions, wrist); every float
 * finite; joint and wrist positions within FP_EVENT_MAX_MM of the device's origin on every
 * axis; a wrist rotation of norm 1 within 1e-2 (of its square); a button one fp_button bit,
 * down 0 or 1, mask under 8; a known status code and a NUL-terminated text; a channel's
 * name NUL-terminated and not empty. Its time (fp_event_check_time): time_ns not negative,
 * and not more than FP_EVENT_MAX_AHEAD_NS past the host's clock (fp_now_ns) when it was
 * pushed, unless the input keeps its own clock (it answers FP_EXT_RECORDING_INFO or
 * FP_EXT_INPUT_CLOCK: a recording's times run ahead of the host's with fast=1 or a speed).
 * Threads: pure functions, any thread. SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FP_EVENT_CHECK_H
#define FP_EVENT_CHECK_H

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stdint.h>

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
    FP_EVENT_BAD_TIME,      /* time_ns negative, or in the future (fp_event_check_time) */
    FP_EVENT_FAULTS
} fp_event_fault;

/** Why ev is malformed (an fp_event_fault, FP_EVENT_OK when it is not). *why (may be NULL)
 *  gets a static English phrase saying which field, e.g. "a joint position is not finite".
 *  ev: a whole fp_event (at least header.size bytes, as the queue holds them). */
fp_event_fault fp_event_check(const fp_event *ev, const char **why);

/** What an event of `type` (an fp_event_type) is, in English for messages: "joint angles",
 *  "joint positions", "wrist pose", "button", "status", "channel"; "an unknown type" for any
 *  other value. A static string. Any thread. */
const char *fp_event_type_name(uint32_t type);

/** How far past the host's clock an event's time_ns may be (ns, 1 s): a device's events are
 *  measured by the time they are pushed, with leeway for a clock read a little ahead. */
#define FP_EVENT_MAX_AHEAD_NS 1000000000LL

/** Why ev's time is refused: FP_EVENT_BAD_TIME when header.time_ns < 0, or when !own_clock
 *  and time_ns > now_ns + FP_EVENT_MAX_AHEAD_NS; FP_EVENT_OK otherwise. now_ns: the host's
 *  clock (fp_now_ns, CLOCK_MONOTONIC ns) when the event was pushed (the validator: when it
 *  reads the queue, a later time, so never stricter). own_clock: the input answers
 *  FP_EXT_RECORDING_INFO or FP_EXT_INPUT_CLOCK. *why (may be NULL): a static phrase. */
fp_event_fault fp_event_check_time(const fp_event *ev, int64_t now_ns, bool own_clock, const char **why);

/** Whether the input keeps its own clock for fp_event_check_time (its get_extension answers
 *  FP_EXT_RECORDING_INFO or FP_EXT_INPUT_CLOCK). Calls into the plugin: [main-thread], after
 *  create; in NULL: false. */
bool fp_input_own_clock(fp_input *in);

#ifdef __cplusplus
}
#endif
#endif
