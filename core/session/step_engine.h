/*
 * step_engine.h: step 5 of the frame (docs/architecture.md): the CSRBF engine (core/csrbf)
 * on the control set. Sato, Savchenko, Ohbuchi (Cyberworlds 2004), eq. 1-3: the space map
 * T(x) = x + sum_i alpha_i psi31(|x - s_i| / R) through the start points s_i, solved so
 * that T(s_i) = d_i (the end points), evaluated at every base vertex: deformed = T(base).
 *
 * Per frame: a solver is created when the support radius changes; the system is factored
 * when the start points differ (bitwise) from the ones last factored, else the factor is
 * reused (anchored gestures: only the end points move); the end points are solved; the
 * fold-over guard makes the map injective; the base is evaluated. Also here: each
 * fingertip's distance to the base surface, which the mapping reads
 * (fp_frame_input.tip_distance).
 *
 * The fold-over guard (issue 10 item 1; csrbf.h "fold-over guard", csrbf.md pitfall 4):
 * every map the session applies has the engine's injectivity bound L <= FP_ENGINE_GUARD_MARGIN
 * (L < 1 means T injective with det dT/dx > 0 everywhere, so the surface cannot cross
 * itself), decided from the solved coefficients, per cluster of overlapping supports:
 *  - the map from the start points to the end points is solved and limited per cluster
 *    (csrbf_solver_limit_end_points); where nothing is limited it is applied as one map
 *    (an anchored gesture reuses its factor from frame to frame);
 *  - where a cluster would be limited, the step is composed instead (csrbf_guarded_step):
 *    up to FP_ENGINE_MAX_SUBSTEPS injective maps, each start point travelling its
 *    cluster's share of the straight path to its end point, until every end point is
 *    reached; beyond that the rest is dropped (a composition of injective maps is
 *    injective). An unanchored step is composed on the shape so far; an anchored gesture's
 *    map is composed anew from its base every frame (so the shape depends on this frame's
 *    control set alone, and a take plays back bit for bit).
 * So the face follows the fingers: a drag reaches its end points in sub-steps, and only
 * points that converge (where no injective map of FP_ENGINE_MAX_SUBSTEPS steps can bring
 * them together) stop short. What the guard did is in fp_engine_result (per frame) and,
 * once per gesture (not per frame), a log line: "fold-over guard composed ..." or
 * "fold-over guard limited the deformation to 63% this gesture ...".
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

/** The guard's margin: a map is applied when its bound L <= 0.9. L bounds the Lipschitz
 *  constant of T - id, so every singular value of dT/dx lies in [1 - L, 1 + L]: 0.9 keeps a
 *  surface from being compressed more than tenfold by one map while losing only 10% of the
 *  reach that injectivity allows per map (a single centre folds at |alpha| = R / max|psi'|,
 *  0.474 R for psi31). Smaller margins cost more sub-steps. */
#define FP_ENGINE_GUARD_MARGIN 0.9

/** The composed step's limits (csrbf_guard max_substeps, max_pairs): up to 64 maps, those
 *  past the engine's default 16 only while the maps so far evaluated under 4M (vertex,
 *  centre) pairs (about 9 ms on the project's 2-core VM). Fingertips that grab skin a few
 *  millimetres apart and pull it apart need dozens of maps, as each map may stretch the gap
 *  between them by only so much (a three-claps played backwards on the ICT face would take
 *  60 maps, 5.4M pairs: the budget stops it at 47); on a large mesh, whose maps each
 *  evaluate millions of pairs, the 16 stay the limit. Deterministic: the count depends on
 *  the control set and the mesh, not on time (docs/performance.md has the figures). */
#define FP_ENGINE_MAX_SUBSTEPS 64
#define FP_ENGINE_MAX_PAIRS 4000000u

typedef struct fp_engine_step {
    csrbf_solver *solver;         /* NULL until the first run */
    uint64_t base_version;        /* counts the base's changes (set_base, commit, commit_ranges):
                                     an isolated mapping's copy of the base is renewed when it
                                     moves (FP_HOST_EXT_BASE_VERSION) */
    double solver_radius;         /* the radius the solver was made for */
    csrbf_points *points;         /* the base vertices, blocked for evaluation */
    csrbf_touch *touch;           /* which blocks of the (persistent) output differ from the base */
    csrbf_points *inter;          /* a composed step's shape so far (csrbf_guarded_step_touched):
                                     the base's vertices between runs, kept with points; made
                                     at the first composed step (NULL until then) */
    csrbf_touch *inter_touch;     /* its touch */
    bool inter_stale;             /* the base changed whole since (set_base): copied from
                                     points at the next composed step, not at each change */
    bool touched_valid;           /* the last write of the output was csrbf_evaluate_touched */
    float *scratch;               /* n x 3: the Jacobian evaluation's output (e->jacobian) */
    int threads;                  /* csrbf_options.threads */
    bool factored;                /* factored_start holds the factored start points */
    size_t factored_count;
    float factored_start[FP_ENGINE_MAX_CONTROL][3];
    fp_slog_repeat errors;        /* the engine's repeated error */
    bool jacobian;                /* measure min det dT/dx (fp_engine_result.min_det_j) */
    /* the surface service (FP_HOST_EXT_SURFACE): triangles around each vertex */
    const uint32_t *tris;         /* the mesh's triangles (not owned) */
    uint32_t *vt_start, *vt;      /* vertex v's triangles: vt[vt_start[v] .. vt_start[v+1]) */
    /* the current gesture, for the guard's one line per gesture */
    unsigned long g_frames, g_limited, g_composed;
    double g_reached;             /* smallest fraction reached over the gesture */
    int g_substeps;               /* most sub-steps in one frame */
    double g_bound;               /* largest requested bound */
} fp_engine_step;

/** What one run did. */
typedef struct fp_engine_result {
    bool refactored;              /* factored anew (start points or radius changed) */
    uint64_t pairs;               /* vertex-centre pairs evaluated */
    double update_ms;             /* factor/solve + guard + evaluate, milliseconds (without
                                     the Jacobian measurement) */
    double eval_ms;               /* of update_ms: the evaluation (a composed step: all of it) */
    double jacobian_ms;           /* the min det J evaluation (e->jacobian), milliseconds */
    double bound;                 /* injectivity bound L of the requested map (first map) */
    size_t clusters;              /* clusters of overlapping supports */
    size_t clusters_limited;      /* clusters the guard scaled back (first map) */
    int substeps;                 /* maps composed (1: one map) */
    double reached;               /* smallest fraction of a control vector reached (1: all) */
    double min_det_j;             /* min det dT/dx over the moved vertices and the maps
                                     applied when e->jacobian, else NAN */
} fp_engine_result;

/** Index n base vertices (n x 3 floats, mesh units; not copied: csrbf_points copies them
 *  into blocks, and into Morton-ordered blocks for the fingertips' distances,
 *  csrbf_points_index_nearest) for `threads` engine threads (csrbf_options.threads). Returns
 *  0 or -ENOMEM. Free with fp_engine_step_free. */
int fp_engine_step_init(fp_engine_step *e, size_t n, const float *base, int threads);
void fp_engine_step_free(fp_engine_step *e);

/** The base changed to something the output buffer does not show (undo, reset, a new
 *  base): re-index it whole, forget the factor, and the next run rewrites the whole output. */
void fp_engine_step_set_base(fp_engine_step *e, const float *base);

/** The caller's output buffer equals the indexed base bit for bit (a fresh copy of it, at
 *  creation): no block differs from the base, so a run writes only the blocks in a support
 *  (csrbf_touch_commit) and the touched ranges are known from the first run on. */
void fp_engine_step_output_is_base(fp_engine_step *e);

/** A commit: base is now the output buffer of the last run (deformed copied into it).
 *  Re-indexes only the vertex ranges that run wrote (csrbf_points_update_ranges, on points
 *  and inter), csrbf_touch_commit, forgets the factor. */
void fp_engine_step_commit(fp_engine_step *e, const float *base);

/** A commit of another shape on known ranges: base (n x 3 floats, the caller's, changed only
 *  there) and the output buffer both hold it now (the caller copied it into both); re-indexes
 *  those ranges ((first, count) vertex pairs, increasing, disjoint, within n) on points and
 *  inter, csrbf_touch_commit, forgets the factor. No errors reported: ranges outside n or
 *  positions past CSRBF_MAX_COORD are refused by csrbf_points_update_ranges, which then
 *  re-indexes nothing, as in fp_engine_step_commit. Threads: the session thread. */
void fp_engine_step_commit_ranges(fp_engine_step *e, const float *base, const uint32_t *ranges, size_t nr);

/** The vertex ranges ((first, count) pairs) of the output that the last run rewrote, for a
 *  viewer's partial upload; SIZE_MAX (and *ranges NULL) when the whole output may have
 *  changed (a new base, an engine error). */
size_t fp_engine_step_touched(const fp_engine_step *e, const uint32_t **ranges);

/** Forget the factor (a new gesture, a new mapping): the next run factors anew. */
void fp_engine_step_invalidate(fp_engine_step *e);

/** Run the engine on cs (cs->count <= FP_ENGINE_MAX_CONTROL, radius > 0, checked by the
 *  mapping step) and write deformed (n x 3 floats; the same buffer on every call, written by
 *  nobody else: only the blocks in a support now or at the last run are rewritten,
 *  csrbf_evaluate_touched, bit for bit what a full evaluation gives): T(base) with the fold-over guard (see
 *  above: limited when the start points are those last factored or the step is not
 *  committed this frame, composed when the start points are new and cs commits).
 *  Returns 0 (warnings of csrbf, CSRBF_WARN_LIMITED included, are not errors) or a negative
 *  csrbf code, unchanged; on error deformed may be partly written and must not be shown; the
 *  error is reported through log (once, then counted). */
int fp_engine_step_run(fp_engine_step *e, const fp_control_set *cs, float *deformed,
                       fp_engine_result *res, const fp_slog *log);

/** The solver of the last run (its coefficients: csrbf_solver_get_coefficients), or NULL
 *  before the first. */
const csrbf_solver *fp_engine_step_solver(const fp_engine_step *e);

/** The gesture ended (a frame without a deformation, a cancel, destruction): when the guard
 *  acted during it, one log line (source "engine"): FP_LOG_WARNING "fold-over guard limited
 *  the deformation to P% this gesture (...)" when some end point was not reached, else
 *  FP_LOG_INFO "fold-over guard composed N steps ... this gesture". Then forgets it. */
void fp_engine_step_end_gesture(fp_engine_step *e, const fp_slog *log);

/** Report a pending repeated error and the gesture's guard line; call at destruction. */
void fp_engine_step_flush(fp_engine_step *e, const fp_slog *log);

/** The nearest index takes the last commit's positions (fp_engine_step_commit_ranges leaves
 *  it to the next frame: csrbf_points_update_ranges_later); the session calls this before
 *  fp_engine_step_tip_distances. Until then the distances are the same, from the engine's own
 *  blocks. Same thread as the rest of e. */
void fp_engine_step_sync(fp_engine_step *e);

/** Distance from each fingertip (FP_JOINT_TIP) of each present hand to the nearest base
 *  vertex (mesh units) where it is at most `reach` (mesh units; the session passes
 *  FP_TIP_DISTANCE_REACH x radius), +INFINITY beyond it and for an absent hand:
 *  csrbf_points_nearest on the engine's nearest index (Morton-ordered blocks), visiting only
 *  blocks whose boxes are within reach; equal bit for bit to fp_engine_tip_distances on the same base wherever that
 *  is <= reach. reach: >= 0, +INFINITY for no bound. No allocation. */
void fp_engine_step_tip_distances(const fp_engine_step *e, const fp_hand_pose hands[FP_HANDS],
                                  float reach, float d[FP_HANDS][FP_FINGERS]);

/** Give the engine the mesh's triangles (t x 3, kept by pointer, must outlive e) for
 *  fp_engine_step_surface: builds each vertex's triangle list. Returns 0 or -ENOMEM. */
int fp_engine_step_set_topology(fp_engine_step *e, const uint32_t *tris, size_t t);

/** The host's surface service (plugin.h FP_HOST_EXT_SURFACE) on the current base: for each
 *  query point (count x 3, mesh units) the nearest base vertex within max_distance
 *  (csrbf_points_nearest: equal to a brute force), its position, distance and unit normal
 *  (the area-weighted normal of fp_mesh_normals, computed for that vertex alone from its
 *  triangles); vertex UINT32_MAX, distance INFINITY and zeros where none is within reach.
 *  base: the base the engine indexes (n x 3). Returns 0, -EINVAL (NULL, a non-finite query,
 *  a NaN or negative max_distance) or -ENODATA (no topology). No allocation. */
int fp_engine_step_surface(const fp_engine_step *e, const float *base, const float (*points)[3],
                           size_t count, float max_distance, fp_surface_hit *out);

/** The reference: the same distances by a scalar brute-force loop over the n base vertices
 *  (tests and `bench --case frame`; about 0.45 ms on the ICT face). */
void fp_engine_tip_distances(const float *base, size_t n, const fp_hand_pose hands[FP_HANDS],
                             float d[FP_HANDS][FP_FINGERS]);

#ifdef __cplusplus
}
#endif
#endif
