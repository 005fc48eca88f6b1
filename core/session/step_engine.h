/*
 * step_engine.h: step 5 of the frame (docs/architecture.md): the CSRBF engine (core/csrbf)
 * on the control set. Sato, Savchenko, Ohbuchi (Cyberworlds 2004), eq. 1-3: the space map
 * T(x) = x + sum_i alpha_i psi31(|x - s_i| / R) through the start points s_i, solved so
 * that T(s_i) = d_i (the end points), evaluated at every base vertex: deformed = T(base).
 *
 * Per frame: a solver is created when the support radius changes; the system is factored
 * when the start points differ (bitwise) from the ones last factored, else the factor is
 * reused (anchored gestures: only the end points move); the end points are solved; the
 * guard hook runs (a no-op today: the fold-over guard of the trust issue goes there); the
 * base is evaluated. Also here: each fingertip's distance to the base surface, which the
 * mapping reads (fp_frame_input.tip_distance).
 *
 * Errors: the engine's codes (csrbf.h: CSRBF_ERR_*) are returned unchanged and reported
 * through the log once with a count (source "engine", csrbf_strerror and the solver's
 * message). Threads: the session thread; the solver may be read (csrbf_evaluate,
 * csrbf_solver_get_coefficients) by the same thread between frames.
 */
#ifndef FP_STEP_ENGINE_H
#define FP_STEP_ENGINE_H

#include "csrbf.h"
#include "session_log.h"

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_ENGINE_MAX_CONTROL 64   /* the session's control-set capacity */

typedef struct fp_engine_step {
    csrbf_solver *solver;         /* NULL until the first run */
    double solver_radius;         /* the radius the solver was made for */
    csrbf_points *points;         /* the base vertices, blocked for evaluation */
    int threads;                  /* csrbf_options.threads */
    bool factored;                /* factored_start holds the factored start points */
    size_t factored_count;
    float factored_start[FP_ENGINE_MAX_CONTROL][3];
    fp_slog_repeat errors;        /* the engine's repeated error */
} fp_engine_step;

/** What one run did. */
typedef struct fp_engine_result {
    bool refactored;              /* factored anew (start points or radius changed) */
    uint64_t pairs;               /* vertex-centre pairs evaluated */
    double update_ms;             /* factor/solve + guard + evaluate, milliseconds */
} fp_engine_result;

/** Index n base vertices (n x 3 floats, mesh units; not copied: csrbf_points copies them
 *  into blocks) for `threads` engine threads (csrbf_options.threads). Returns 0 or
 *  -ENOMEM. Free with fp_engine_step_free. */
int fp_engine_step_init(fp_engine_step *e, size_t n, const float *base, int threads);
void fp_engine_step_free(fp_engine_step *e);

/** The base changed (commit, undo, reset): re-index it and forget the factor. */
void fp_engine_step_set_base(fp_engine_step *e, const float *base);

/** Forget the factor (a new gesture, a new mapping): the next run factors anew. */
void fp_engine_step_invalidate(fp_engine_step *e);

/** The guard hook, between solve and evaluate: may check or limit the solved coefficients
 *  (csrbf_kernel_foldover_bound). Today a no-op that returns 0; the trust issue's fold-over
 *  guard goes here. A negative return stops the run with that code. */
int fp_engine_step_guard(fp_engine_step *e, const fp_control_set *cs);

/** Run the engine on cs (cs->count <= FP_ENGINE_MAX_CONTROL, radius > 0, checked by the
 *  mapping step) and write deformed (n x 3 floats). Returns 0 (warnings of csrbf are not
 *  errors) or a negative csrbf code, unchanged; on error deformed may be partly written and
 *  must not be shown; the error is reported through log (once, then counted). */
int fp_engine_step_run(fp_engine_step *e, const fp_control_set *cs, float *deformed,
                       fp_engine_result *res, const fp_slog *log);

/** The solver of the last run (its coefficients: csrbf_solver_get_coefficients), or NULL
 *  before the first. */
const csrbf_solver *fp_engine_step_solver(const fp_engine_step *e);

/** Report a pending repeated error; call at destruction. */
void fp_engine_step_flush(fp_engine_step *e, const fp_slog *log);

/** Distance from each fingertip (FP_JOINT_TIP) of each present hand to the nearest of the n
 *  base vertices (mesh units), +INFINITY for an absent hand: brute force over the base
 *  (10 tips x 27k vertices is about 0.1 ms). */
void fp_engine_tip_distances(const float *base, size_t n, const fp_hand_pose hands[FP_HANDS],
                             float d[FP_HANDS][FP_FINGERS]);

#ifdef __cplusplus
}
#endif
#endif
