/*
 * step_arrive.h: hands that arrive, the session's side (issue 51). Two jobs around step 2 of
 * the frame (docs/architecture.md):
 *
 *  - Placement as it runs: where no calibration is given and no input states its workspace
 *    (a live tracker: OSC without box=, any input without FP_EXT_WORKSPACE), the joint
 *    positions drained go to a running estimate of their range (core/pose fp_pose_auto.h) and
 *    the calibration is refitted from it before the poses are built: from the hands' first
 *    frame, then refined, never while a gesture is engaged (one held only on skin the rig
 *    keeps still does not count, and is cancelled when the placement moves: session_performers.c,
 *    FP_SESSION_STILL_MOBILITY). One info line (source
 *    "session") says when the hands were first placed.
 *  - The hint: when hands have been present for FP_ARRIVE_HINT_S seconds (frame time: the
 *    steps between consecutive frames that both had a hand, each at most 0.25 s) and no
 *    fingertip came within FP_ARRIVE_NEAR x the touch radius of the face (the anchored
 *    mapping's default engage distance; fingertip-to-surface distances as the mapping gets
 *    them) and the mapping engaged nothing, one warning (source "session") says how near the
 *    nearest fingertip came, in mm, how the hands are placed, and to calibrate. Once, and
 *    never after a fingertip came near (or the mapping engaged): hands that have reached the
 *    face are placed well, and a performer resting them away from it is told nothing. A
 *    session that ends sooner (a short replay) says it at its end (fp_arrive_step_finish).
 *
 * Threads: the session thread. Allocation only in fp_arrive_step_init.
 */
#ifndef FP_STEP_ARRIVE_H
#define FP_STEP_ARRIVE_H

#include "fp_head.h"
#include "fp_pose.h"
#include "fp_pose_auto.h"
#include "session_log.h"
#include "step_engine.h"

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_ARRIVE_HINT_S 3.0   /* seconds of hands present and away before the hint */
#define FP_ARRIVE_NEAR 0.5     /* "near": a fingertip within this x radius of the face */
#define FP_ARRIVE_END_S 1.0    /* at the end, hands present and away this long get the hint */

/** How the hands are placed (what the hint says). */
typedef enum fp_arrive_placement {
    FP_ARRIVE_PLACED_AUTO = 0,      /* estimated as they run (fp_pose_auto) */
    FP_ARRIVE_PLACED_WORKSPACE,     /* from the workspace an input states (a recording, box=) */
    FP_ARRIVE_PLACED_CALIBRATION,   /* a calibration given (--calibration, a take's) */
    FP_ARRIVE_PLACED_STILL          /* (the hint's words) estimated, the hands still: held out */
} fp_arrive_placement;

typedef struct fp_arrive_step {
    fp_arrive_placement how;
    fp_pose_auto *place;           /* FP_ARRIVE_PLACED_AUTO: the estimator; else NULL */
    bool placed_said;              /* the first placement's info line was sent */
    double away_s;                 /* seconds with hands present and none near, since near */
    double nearest;                /* mesh units: the nearest fingertip over those seconds */
    int64_t last_ns;               /* the last frame's time */
    bool have_last;                /* ... and it had a hand */
    bool warned;                   /* the hint was said for this stretch */
    bool reached;               /* a fingertip came near (or the mapping engaged): no hint since */
    bool far_asked;                /* the unbounded nearest query ran ... */
    int64_t far_ns;                /* ... last at this frame time */
    unsigned long hints;           /* hints said so far */
    double near_mm;                /* the last check's "near" (FP_ARRIVE_NEAR x radius), mm */
    double mm;                     /* the last check's mm_per_unit */
    bool hovered;                  /* the hands are still: placed FP_ARRIVE_HOVER x radius out */
    double moving_away_s;          /* of away_s: seconds the hands moved, placed by their range */
    bool bring_on;                 /* FP_ARRIVE_BRING_AFTER_S of those came: bring them in */
    bool bring_tried;              /* the live bring-in ran (outside a refit: once) */
    bool brought;                  /* the live bring-in was said */
    bool pushed;                   /* the placement in effect holds a live bring-in's push */
    bool awaiting;                 /* held hands: the push waits for the acting tips' approach */
    float (*live_tips)[3];         /* FP_ARRIVE_PLACED_AUTO: its buffers (FP_ARRIVE_LIVE_SAMPLES */
    int *live_hand;                /* samples' fingertips, hands, their points in mesh units */
    float (*live_q)[3];            /* and distances) */
    float *live_d;
    char who[80];                  /* whose hands, before its lines ("performer 'B': "; set
                                      after init by a session of several performers), or "" */
} fp_arrive_step;

/** Start: how the hands are placed; FP_ARRIVE_PLACED_AUTO makes the estimator. Returns 0 or
 *  -ENOMEM (r then holds nothing to free, and fp_arrive_step_free is still safe). */
int fp_arrive_step_init(fp_arrive_step *r, fp_arrive_placement how);

/** Free the estimator; r may be zeroed or initialised. */
void fp_arrive_step_free(fp_arrive_step *r);

/** A drained event (the session's event callback): joint positions feed the estimator when
 *  there is one; nothing otherwise. */
void fp_arrive_step_event(fp_arrive_step *r, const fp_event *ev);

/** Before fp_pose_build: with the estimator, refit p->calib when due (fp_pose_auto_refit;
 *  engaged: the last frame's gesture is engaged, nothing moves), at head's mm_per_unit and
 *  head box; hands that have not moved yet (FP_POSE_STILL_MM) are held FP_ARRIVE_HOVER x
 *  radius (the touch radius, mesh units: the face's default support radius) out from the
 *  face in depth: every fingertip then lies that far in front of the nose tip's depth, so
 *  no still pose touches the face by chance, and the hint says to reach. The first placement is said once on log
 *  (FP_LOG_INFO, "session"), and the end of the hover when the hands move.
 *  At each refit of hands that moved, they are then brought in as a recording is
 *  (fp_arrive_bring_in's rule and march, on the estimator's samples so far, at most
 *  FP_ARRIVE_LIVE_SAMPLES of them, against e's index): a placement by the range whose
 *  fingertips would not come within FP_ARRIVE_NEAR x radius of the face is pushed in depth
 *  until the nearest approach of those that move lies FP_ARRIVE_BRING_TO x radius from it,
 *  as the same hands replayed from a recording are (so the same motion grabs the same skin
 *  live and replayed); one info line the first time. Cost: one march over the fingertips of at most 64
 *  samples, 1.6-2.6 ms (ICT face), at a refit (every FP_POSE_AUTO_REFIT_S at most, never
 *  engaged). Gloves placed on the face keep their place (fp_pose_recalibrate).
 *  When the push is made (the replay's is there from the first frame, a live one is a guess
 *  that the hands will not come near by themselves): the hands as they are now (each hand's
 *  newest sample) are placed pushed. A push that leaves every fingertip beyond FP_ARRIVE_NEAR x
 *  radius (it grabs nothing at once) is made from FP_ARRIVE_BRING_AFTER_S of moving away; one
 *  that would put a fingertip that acts within it (a grab with the fingertips that move, at
 *  their approach, as the replay's grab starts) from FP_ARRIVE_BRING_WAIT_S later; one that
 *  would put only fingertips that do not act there (a still finger resting in the skin, the
 *  moving ones away: a grab they would not move), and any, from two waits later. Until then
 *  a push in effect stays and the range's placement stands where there is none; the hands
 *  that come near by themselves meanwhile (HandSplay's hover for 1.4 s, then a reach) are
 *  never pushed, as the replay does not push them. Hands held in place (fp_pose_auto_held: a
 *  fingertip moved, no hand's base over FP_POSE_HELD_S) are due at once, without the
 *  moving away nor the wait for a push that lands a fingertip that acts; before a push is in
 *  effect it is tried every frame (a march each, while not engaged) and made when the
 *  fingertips that act, as they are now, lie within FP_ARRIVE_APPROACH x radius of the
 *  nearest the march brought them to (their approach: the grab starts with the fingertips
 *  near there, as the replay's does), or from two waits later; one that rests only still
 *  fingertips in the skin waits as above. */
#define FP_ARRIVE_HOVER 1.0
#define FP_ARRIVE_BRING_AFTER_S 1.0
#define FP_ARRIVE_BRING_WAIT_S 1.0
#define FP_ARRIVE_APPROACH 0.1
#define FP_ARRIVE_LIVE_SAMPLES 64
void fp_arrive_step_place(fp_arrive_step *r, fp_pose_state *p, bool engaged, const fp_head *head,
                         double radius, const fp_engine_step *e, const fp_slog *log);

/** After the mapping ran: the hint's bookkeeping for the frame at now_ns (the frame clock;
 *  the step from the last frame counts when both had a hand, at most 0.25 s). hands: the frame's poses (mesh units);
 *  tip: the fingertip distances the mapping got (mesh units, +INFINITY beyond its reach);
 *  engaged: the mapping's control set is active; radius: the touch radius (mesh units: the
 *  face's default support radius, which --radius leaves, as the mapping measures touch);
 *  mm_per_unit: the mesh's unit; e: the engine, asked the nearest surface without a bound
 *  while every fingertip is beyond the tip distances' reach (fp_engine_step_tip_distances;
 *  at most every 0.1 s of frame time, and on the hint's frame), so that the hint says how
 *  far. The hint goes to log (FP_LOG_WARNING, "session"). */
void fp_arrive_step_check(fp_arrive_step *r, int64_t now_ns, const fp_hand_pose hands[FP_HANDS],
                         const float tip[FP_HANDS][FP_FINGERS], bool engaged, double radius,
                         double mm_per_unit, const fp_engine_step *e, const fp_slog *log);

/** Hands that never move or never come near (issue 51, "hands that arrive"). A recording
 *  whose fingertips never move (each within FP_POSE_STILL_MM: the 2nd-98th percentile box of
 *  its samples, largest side) is held FP_ARRIVE_HOVER x radius out in depth (c->offset[2]
 *  increased), as a live input's still hands are (fp_arrive_step_place), and said so on an
 *  info line. Otherwise a recording placed by its
 *  range (fp_pose_fit_workspace: its front at the nose tip's depth) whose fingertips would
 *  never come within FP_ARRIVE_NEAR x radius of the face (a hand held in place, its front
 *  before the brow or an eye rather than the nose) is brought toward the face, along depth,
 *  until its nearest approach lies FP_ARRIVE_BRING_TO x radius from the surface. ins: the n
 *  inputs of one performer; those stating a workspace and giving their joints in advance
 *  (FP_EXT_RECORDING_JOINTS) are read, every k-th sample of each hand where they hold more
 *  than FP_ARRIVE_BRING_SAMPLES (of each hand, not of all: a two-hand recording's rows
 *  alternate, and every 2nd row was one hand alone); their fingertips are placed by *c and
 *  measured against the face's vertices (e's index, as the mapping's fingertip distances
 *  are). Where some fingertip comes near already (every recording in ../shared/data does,
 *  but three-claps on the MediaPipe face at its rig's scale: brought 7 mm), or none is
 *  given, or no push up to the head's depth (head box, mesh units) brings one near, *c is left as
 *  it is. The push: a march in depth by the nearest distance less the target, which cannot
 *  step past a nearer placement (a distance changes no faster than the push; it is
 *  subtracted from c->offset[2]). One info line (source "session") says how far they were
 *  and how far they were moved, in mm. Returns 1 (held out, still), 0 (as it was, or brought
 *  in) or -ENOMEM (*c untouched). Main thread, at the opening. */
#define FP_ARRIVE_BRING_TO 0.25
#define FP_ARRIVE_BRING_SAMPLES 4096
int fp_arrive_bring_in(fp_calibration *c, fp_input *const *ins, size_t n, double radius, const fp_head *head,
                       const fp_engine_step *e, const char *who, const fp_slog *log);

/** At the session's end (a replay shorter than FP_ARRIVE_HINT_S, or hands that left before
 *  it): when hands were present and away for FP_ARRIVE_END_S seconds or more, none came
 *  near and the hint was not said for that stretch, it is said now, with the seconds they
 *  were there (a run that moved nothing says why). Nothing otherwise. */
void fp_arrive_step_finish(fp_arrive_step *r, const fp_slog *log);

#ifdef __cplusplus
}
#endif
#endif
