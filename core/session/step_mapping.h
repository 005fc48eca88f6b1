/*
 * step_mapping.h: step 3 of the frame (docs/architecture.md): the mapping call. Builds the
 * mapping's fp_frame_input (poses, this frame's button/status events, the mesh view, the
 * radius, the requested intents, the fingertip distances), calls the mapping plugin's
 * process() and validates the control set it wrote: count <= capacity, radius > 0 and
 * finite, every start and end point of the first `count` finite. A failed call or an
 * invalid set deactivates the control set for this frame (no deformation is shown, the base
 * stays) and is reported through the log ONCE with a count (fp_slog_repeat), not every frame.
 *
 * Threads: the session thread ([session-thread] of plugin.h's mapping callbacks).
 */
#ifndef FP_STEP_MAPPING_H
#define FP_STEP_MAPPING_H

#include "session_log.h"

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Entries of canary after each host array a mapping fills (start, end, channels). */
#define FP_MAPPING_GUARD 8
/** The default budget of one process() call, milliseconds. */
#define FP_MAPPING_BUDGET_MS 2.0

typedef struct fp_mapping_step {
    fp_slog_repeat errors;    /* the mapping's repeated error, reported once with a count */
    fp_slog_repeat slow;      /* process() over the budget, reported once with its time, counted */
    double budget_ms;         /* process() budget; 0: FP_MAPPING_BUDGET_MS */
    bool stopped;             /* stopped for a fault (a write past capacity): never called again */
    int fault;                /* FP_EPLUGIN_FAULT once stopped, else 0 */
    char fault_message[256];  /* why it was stopped */
    unsigned long slow_calls; /* process() calls over the budget */
    double slow_max_ms;       /* the slowest of them */
    /* The host's arrays, each followed by FP_MAPPING_GUARD canary entries (bound to a
     * control set by fp_mapping_step_init). */
    float start[FP_CONTROL_CAPACITY + FP_MAPPING_GUARD][3];
    float end[FP_CONTROL_CAPACITY + FP_MAPPING_GUARD][3];
    fp_channel channels[FP_CHANNEL_CAPACITY + FP_MAPPING_GUARD];
    bool guarded;             /* the canaries are in place */
} fp_mapping_step;

/** (Re)initialise the step for a new mapping instance: clears the fault and counters, fills
 *  the canaries and points cs at the step's arrays (capacity FP_CONTROL_CAPACITY, channel
 *  capacity FP_CHANNEL_CAPACITY), count 0, inactive. budget_ms 0: FP_MAPPING_BUDGET_MS.
 *  Flush pending repeated errors first (fp_mapping_step_flush). */
void fp_mapping_step_init(fp_mapping_step *st, fp_control_set *cs, double budget_ms);

/** Check a control set as a mapping wrote it, by the one rule the plugin validator also
 *  holds plugins to (core/plugin/fp_control_check.h). Returns 0, -ERANGE (count above
 *  capacity, or channel_count above channel_capacity), -EINVAL (a NULL array with count > 0;
 *  a start or end point among the first count not finite or beyond FP_CONTROL_COORD_MAX
 *  (plugin.h); active with a radius outside [FP_CONTROL_RADIUS_MIN, FP_CONTROL_RADIUS_MAX]
 *  mesh units, NaN included). */
int fp_control_set_check(const fp_control_set *cs);

/** Call mapping->process(in, cs) and check cs. `name` is the mapping instance's name (the
 *  SPEC's NAME); messages go through log with the source "mapping 'NAME'" and name the
 *  frame and the cause, e.g. "process returned -28 (No space left on device) on frame 12".
 *  The call is bracketed for the crash handler (fp_plugin_call_enter(name, "process",
 *  frame)) and timed: a call over the budget is reported once with its time (a warning),
 *  later ones counted. When cs uses the step's arrays (fp_mapping_step_init), the canaries
 *  after them are checked after every call: an overwritten canary (a write past capacity)
 *  is reported, the canaries restored, and the mapping stopped (st->stopped, st->fault =
 *  FP_EPLUGIN_FAULT): it is not called again and every later frame shows the base. So is a
 *  mapping whose process returns FP_EPLUGIN_FAULT (an isolated one's proxy says so when its
 *  helper wrote past the arrays; the proxy has said it in the log). On an
 *  error (the mapping's negative code, fp_control_set_check's, or the fault) the set is
 *  emptied: inactive, no intents, no vectors nor channels, in->radius as its radius (a take
 *  records it as such: what the mapping wrote is not kept); the error is reported the first
 *  time, then counted. On success
 *  a pending repeated error is flushed. Returns 0 or the error code. */
int fp_mapping_step_run(fp_mapping_step *st, fp_mapping *mapping, const char *name,
                        const fp_frame_input *in, fp_control_set *cs, const fp_slog *log);

/** Report pending repeated errors and slow calls ("repeated N more times"); call at
 *  destruction and before fp_mapping_step_init for a new instance. */
void fp_mapping_step_flush(fp_mapping_step *st, const fp_slog *log);

#ifdef __cplusplus
}
#endif
#endif
