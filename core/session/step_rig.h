/*
 * step_rig.h: step 4 of the frame (docs/architecture.md): the rig (core/rig, rigs/README.md).
 *
 * With a rig attached, each frame:
 *   - channel values: the viewer's requests (fp_rig_step_set_channel) and the mapping's
 *     fp_control_set.channels (by name, clamped to the channel's range; a value persists until
 *     set again; a name the rig lacks is reported once per name);
 *   - the posed base: fp_rig_pose(base, values) (the jaw about its hinge, the soft tissue by
 *     the rig's falloff), recomputed only when the base or a value changed; the engine's
 *     points follow it (the session re-indexes them), so fingers start on the posed surface;
 *   - the fingers' control vectors are clamped by fp_rig_finger_clamp_indexed (the push
 *     toward a bone cut to what keeps the mobility blend from folding, by its bound, the rest
 *     of the vector kept; a pull away or along it not at all: fp_rig.h), in a copy of the
 *     control set; the copy's
 *     channels are every channel of the rig with the value posed this frame (whoever set it:
 *     the viewer's keys, the host's API, the mapping), so that the frame's record (step 7, a
 *     take) holds the pose and playing it (fp_session_apply_controls) poses the same;
 *   - after the engine: shown = fp_rig_apply_mobility(posed, T(posed)): skull and jaw
 *     vertices exactly as posed (the skull bit-identical to the base), soft tissue moved by
 *     the fingers weighted by its mobility;
 *   - a commit keeps only the fingers' part: the base becomes fp_rig_unpose(shown) (the jaw
 *     does not turn twice; skull and jaw vertices, and every vertex the fingers did not
 *     move, keep their base values bit for bit). Ranged (fp_rig_step_commit_ranges,
 *     fp_rig_step_rebase_ranges): where the engine knows its touched ranges, only they are
 *     unposed, committed, posed again and re-indexed, so a commit costs what the fingers
 *     moved, not the mesh; bit for bit the whole commit.
 * Without a rig (rig == NULL) the step passes the control set through and shows T(base).
 *
 * For mappings: an fp_rig_view (plugin.h, ABI 1.1) built once from the rig; landmark
 * positions (from the posed base) and channel values refreshed each frame.
 *
 * Threads: the session thread. Allocation only in init; no I/O.
 */
#ifndef FP_STEP_RIG_H
#define FP_STEP_RIG_H

#include "fp_rig.h"
#include "session_log.h"

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_RIG_STEP_MAX_CONTROL 64   /* = FP_ENGINE_MAX_CONTROL */
#define FP_RIG_STEP_UNKNOWN 16       /* unknown channel names remembered (reported once) */

typedef struct fp_rig_step {
    fp_rig *rig;                                  /* owned; NULL: pass-through */
    size_t n;
    float values[FP_RIG_MAX_CHANNELS];            /* current channel values */
    float posed_values[FP_RIG_MAX_CHANNELS];      /* the values `posed` was made with */
    bool dirty;                                   /* base or values changed since posing */
    float *posed;                                 /* n x 3: the base posed by the channels */
    float *shown;                                 /* n x 3: posed + fingers (mobility blend) */
    bool shown_valid;                             /* shown is the blend of the current posed
                                                   * base (false after posing anew) */
    float *commit;                                /* n x 3: the shape a commit folds in */
    double max_displacement;                      /* worst-case finger clamp (ramp / 3), for reports */
    fp_control_set cs;                            /* the clamped copy the engine takes */
    fp_rig_slope_index *slopes;                   /* the limits' blocks on the posed base
                                                   * (fp_rig.h), set with each pose */
    uint32_t *slope_pend;                         /* ranges (first, count) of the posed base
                                                   * that a commit changed (rebase_ranges) and
                                                   * slopes has not taken yet: taken before the
                                                   * next limits (fp_rig_step_run), out of the
                                                   * commit's frame */
    size_t slope_npend, slope_pend_cap;
    float start[FP_RIG_STEP_MAX_CONTROL][3], end[FP_RIG_STEP_MAX_CONTROL][3];
    fp_rig_view view;                             /* for mappings */
    fp_rig_landmark landmarks[FP_RIG_MAX_LANDMARKS];
    fp_rig_channel_info channels[FP_RIG_MAX_CHANNELS];
    fp_channel applied[FP_RIG_MAX_CHANNELS];      /* cs.channels: every channel, posed values */
    char unknown[FP_RIG_STEP_UNKNOWN][32];        /* unknown channel names already reported */
    size_t unknown_count;
    bool nan_said;                                /* a NaN channel value was reported */
} fp_rig_step;

/** Attach `rig` (bound to the session's mesh, n vertices; owned by the step from here on,
 *  even on error) or NULL for none. base: the base, n x 3 floats. The blend starts as that
 *  of an engine output equal to the posed base (fp_rig_step_finish's ranges then need cover
 *  only where the output differs from it). Returns 0 or -ENOMEM. */
int fp_rig_step_init(fp_rig_step *st, fp_rig *rig, size_t n, const float *base);
void fp_rig_step_free(fp_rig_step *st);

/** Set one channel (the viewer's keys): clamped to its range. Returns 0, -ENOENT (no such
 *  channel or no rig), -ERANGE (NaN). */
int fp_rig_step_set_channel(fp_rig_step *st, const char *name, float value);
/** The current value of a channel (its neutral value before any is set); NaN if unknown. */
float fp_rig_step_channel(const fp_rig_step *st, const char *name);
/** All channels to neutral. */
void fp_rig_step_neutral(fp_rig_step *st);

/** The base changed (commit, undo, reset): pose it again at the next update. */
void fp_rig_step_base_changed(fp_rig_step *st);

/** Take the control set's channels (may be NULL), then pose the base if it or a value
 *  changed. Returns true when `posed` was recomputed (the engine must re-index it). Unknown
 *  channel names go to log once each (source "rig"). */
bool fp_rig_step_update(fp_rig_step *st, const fp_control_set *cs, const float *base, const fp_slog *log);

/** The surface the fingers work on: the posed base, or base without a rig. */
const float *fp_rig_step_posed(const fp_rig_step *st, const float *base);

/** The control set the engine takes: cs itself without a rig, else a copy with every control
 *  vector end - start clamped to max_displacement (same direction) and, as its channels, all
 *  the rig's channels with the values posed (call after fp_rig_step_update). */
const fp_control_set *fp_rig_step_run(fp_rig_step *st, const fp_control_set *cs);

/** After the engine wrote deformed = T(posed): the shape to show (the mobility blend), or
 *  deformed itself without a rig. ranges (pairs first vertex, count; nranges of them): where
 *  deformed may differ from what the last call saw (the engine's touched ranges: deformed
 *  equals posed outside them), so only they are blended again; nranges SIZE_MAX: unknown,
 *  every vertex is. Bit for bit fp_rig_apply_mobility(posed, deformed) either way. */
const float *fp_rig_step_finish(fp_rig_step *st, const float *deformed, const uint32_t *ranges,
                                size_t nranges);

/** The shape a commit folds into the base: `shown` itself without a rig, else its fingers'
 *  part taken back to the rest pose (fp_rig_unpose). */
const float *fp_rig_step_commit_shape(fp_rig_step *st, const float *base, const float *shown);

/** The ranged commit, bit for bit fp_rig_step_commit_shape on those ranges: the commit shape
 *  (fp_rig_unpose_range of shown) on the vertex ranges only, for fp_history_commit_ranges.
 *  The caller guarantees shown equals the posed base outside the ranges (the engine's
 *  touched ranges for the blend; with the contact guard's shape, its D_P too). Returns the step's commit
 *  buffer (n x 3; valid on the ranges), or shown without a rig. O(vertices in the ranges). */
const float *fp_rig_step_commit_ranges(fp_rig_step *st, const float *base, const float *shown,
                                       const uint32_t *ranges, size_t nranges);

/** Whether the posed base is current for ranged updates: posed with the current channel
 *  values from the current base (no re-pose pending). False without a rig. */
bool fp_rig_step_posed_current(const fp_rig_step *st);

/** After a ranged commit (base changed only on the ranges, fp_rig_step_posed_current before
 *  it): the posed base is posed again there (fp_rig_pose_range; elsewhere it already equals
 *  the pose of the base), `deformed` (the engine's output buffer, n x 3) is set to it there
 *  (the engine's output equals its base after a commit: fp_engine_step_commit), the blend
 *  buffer there too, and the landmarks refreshed; the
 *  limits' boxes grow there at the next fp_rig_step_run (the ranges kept until then, out of
 *  the commit's frame). No-op without a rig. O(vertices in the ranges + landmarks). */
void fp_rig_step_rebase_ranges(fp_rig_step *st, const float *base, float *deformed,
                               const uint32_t *ranges, size_t nranges);

/** The view for mappings (NULL without a rig), landmarks at the posed base, channel values. */
const fp_rig_view *fp_rig_step_view(fp_rig_step *st);

#ifdef __cplusplus
}
#endif
#endif
