/*
 * skin_reach.h: how far the skin follows the fingertips (issue 51), in the performer's
 * terms. For each control vector whose start point lies on the skin (within
 * FP_REACH_TOUCH x R of a vertex of the surface the fingers touch: the anchored mapping's
 * grabbed points lie on it exactly), the vertex nearest the start point is the grabbed skin;
 * its reach is how far it moved in the shape shown (against the surface of the frame) over
 * how far the control vector asked, |d_i - s_i|, the mapping's vector before a rig's clamp
 * (a take stores the clamped one, so playing it measures against that). 1 is the whole way;
 * the guards (a rig's clamp, the fold-over and contact guards) are what can make it less. Vectors asking under FP_REACH_MIN_ASK x R are left
 * out (a resting fingertip asks nothing).
 *
 * Per frame into fp_frame_stats (reach, reach_vectors, reach_asked_max); per gesture a
 * summary (fp_skin_reach_gesture) the session logs at the gesture's end. With a rig, the
 * same against what the rig allowed (fp_skin_reach_frame's `allowed` and `mobility`): the
 * vector its clamp left, times the grabbed vertex's mobility (the blend lets that share of the
 * fingers' motion through; fp_rig.h): how far the skin followed where the skull and jaw let
 * it, so that a push into the cheekbone, held back on purpose, reads as such, and a fingertip
 * that grabbed the skull or the jaw themselves (mobility 0: the rig keeps them still) is
 * named, not counted as skin that failed to follow.
 * Threads: the session thread. No allocation, no I/O.
 */
#ifndef FP_SKIN_REACH_H
#define FP_SKIN_REACH_H

#include "csrbf.h"
#include "fp_session.h"
#include "session_log.h"

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_REACH_TOUCH 0.5     /* a start point within this x R of the skin is on it */
#define FP_REACH_MIN_ASK 1e-4  /* x R: shorter control vectors are not counted */

/** One gesture's reach so far (zero-initialise; fp_skin_reach_gesture_reset). */
typedef struct fp_skin_reach_gesture {
    size_t vectors;           /* counted (vector, frame) pairs */
    size_t below_90;          /* of those, reaching under 90% */
    double sum_reach;         /* sum of the reaches (their mean = sum_reach / vectors) */
    double least;             /* the smallest reach */
    double asked_max;         /* the longest control vector counted, mesh units */
    size_t held;              /* against what a rig allowed: vectors whose grabbed vertex the
                                 rig keeps still (allowed under FP_REACH_MIN_ASK x R), left
                                 out of the others */
    bool played;              /* the vectors measured against are a take's, which a rig has
                                 already cut (play, export): how far the fingertips asked is
                                 not known, so the gesture's line gives only the reach against
                                 what the rig allowed. Set by the session; the reset clears it */
} fp_skin_reach_gesture;

/** The frame's reach: for each of cs's control vectors (cs->count <= FP_ENGINE_MAX_CONTROL)
 *  whose start point is within FP_REACH_TOUCH x cs->radius of a vertex of `points` (the
 *  surface the fingers touched, indexed: csrbf_points_nearest), reach = |shown[v] - ref[v]|
 *  / |end - start| at that vertex v. ref, shown: the points' vertex count x 3 floats, mesh
 *  units (the surface before the frame's deformation, the shape shown). Writes
 *  st->reach_vectors, st->reach[0 .. reach_vectors) and st->reach_asked_max, and adds them
 *  to g (may be NULL). allowed (NULL: none, and st->reach_allowed_vectors 0): a rig's clamped
 *  copy of cs (its vectors start where cs's do, at most as many), each of the same vectors'
 *  reach against it into st->reach_allowed and g_allowed (may be NULL; a vector the rig held
 *  under FP_REACH_MIN_ASK x R is left out). mobility (NULL: 1 everywhere): the rig's per-vertex
 *  mobility (the points' vertex count floats, fp_rig_mobility), which scales what the rig
 *  allowed at the grabbed vertex; a vector whose allowed motion so comes under
 *  FP_REACH_MIN_ASK x R is counted in st->reach_held and g_allowed->held instead (the skull or
 *  the jaw grabbed). One nearest query for both. Nothing is written where the index fails
 *  (the counts 0). */
void fp_skin_reach_frame(const csrbf_points *points, const float *ref, const float *shown,
                         const fp_control_set *cs, const fp_control_set *allowed, const float *mobility,
                         fp_frame_stats *st, fp_skin_reach_gesture *g, fp_skin_reach_gesture *g_allowed);

/** Forget the gesture (its end). */
void fp_skin_reach_gesture_reset(fp_skin_reach_gesture *g);

/** At a gesture's end: where it counted any vector, log (source FP_SLOG_ENGINE, a note that
 *  -q leaves out) "the skin followed the fingertips 97% this gesture (mean of N; least 81%,
 *  under 90% in M; longest drag 23.5 mm)", mm from mm_per_unit (mesh units where it is not
 *  positive), and where `allowed` (the reach against what a rig allowed, NULL without one)
 *  differs by half a point or more, "; 100% of what the rig allowed: it holds back a push
 *  toward the skull or the jaw", and where it held vectors (allowed->held), "; 12 of them
 *  grabbed the skull or the jaw, which the rig keeps still" (all of them: "; they grabbed
 *  ..."); where g->played and allowed is given (a take played with a rig), instead "the skin
 *  followed 100% of what the rig allowed this gesture (mean of N; least 100%, under 90% in 0;
 *  longest drag 24.3 mm; the take holds the rig's vectors, not how far the fingertips
 *  asked)" from allowed's figures, with the held clause; then reset g and allowed. */
void fp_skin_reach_gesture_end(fp_skin_reach_gesture *g, fp_skin_reach_gesture *allowed, double mm_per_unit,
                               const fp_slog *log);

#ifdef __cplusplus
}
#endif
#endif
