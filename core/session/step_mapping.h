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

typedef struct fp_mapping_step {
    fp_slog_repeat errors;    /* the mapping's repeated error, reported once with a count */
} fp_mapping_step;

/** Check a control set as a mapping wrote it. Returns 0, -ERANGE (count above capacity,
 *  or channel_count above channel_capacity), -EINVAL (radius not > 0 and finite, a NULL
 *  array with count > 0, a non-finite start or end point among the first count). */
int fp_control_set_check(const fp_control_set *cs);

/** Call mapping->process(in, cs) and check cs. On an error (the mapping's negative code, or
 *  fp_control_set_check's) cs->active and cs->intents are cleared, and the error is
 *  reported through log with source `name` (the first time, then counted). On success a
 *  pending repeated error is flushed. Returns 0 or the error code. */
int fp_mapping_step_run(fp_mapping_step *st, fp_mapping *mapping, const char *name,
                        const fp_frame_input *in, fp_control_set *cs, const fp_slog *log);

/** Report a pending repeated error ("repeated N more times"); call at destruction. */
void fp_mapping_step_flush(fp_mapping_step *st, const fp_slog *log);

#ifdef __cplusplus
}
#endif
#endif
