/*
 * fp_pose_auto.h: hands that arrive. Placement of a live input's hands (OSC, a glove with a
 * position tracker, any tracker that states no workspace) from the joints it has sent so
 * far: the same rule a replay gets in advance from its whole recording (fp_pose.h,
 * fp_pose_fit_workspace on the 2nd-98th percentiles of every joint position, per axis), here
 * on a running estimate of those percentiles over the recent joints.
 *
 * The estimate: every joint position event (FP_EVENT_JOINT_POSITIONS, left or right hand)
 * is kept, at most FP_POSE_AUTO_RATE_HZ samples a second per hand (by the events' own
 * times), for FP_POSE_AUTO_WINDOW_S seconds of the newest sample's time; each sample's 21
 * joints go into a per-axis histogram of FP_POSE_AUTO_BIN_MM bins over +-FP_POSE_AUTO_SPAN_MM
 * (values beyond fall into the end bins: a glitch 3 m away moves a 2nd percentile no more than
 * it does in the replay's sort). The percentiles are read off the histograms: within half a
 * bin of the replay's sorted-index rule on the same samples.
 *
 * Two hands: while both hands have samples kept, the placement's sideways and vertical centre
 * is the middle of the two hands' own 2nd-98th percentile centres (each hand's joints alone),
 * not the middle of the box of both (its width and the front in depth stay the box's). A box
 * of both hands is the hands' outer extremes, and hands that start apart and then work
 * together (three-claps: 230 mm wide at its first frame, 147 mm over the recording) move its
 * centre far as the range fills in: 11 mm from the whole recording's at the start, 7 mm at
 * the first grab (0.93 s), and the skin a clapping grab drags is that sensitive (the replay
 * shifted 5 mm to the side moves 1723 vertices, not 11710). Each hand's own centre is set by
 * its own motion and settles sooner: 2.4, 2.3, 0.1 mm off at 0, 0.5 and 1 s, ending 1.5 mm
 * off. One hand: the box, as before, bit for bit.
 *
 * When it refits (fp_pose_auto_refit, once a frame before the poses are built): from the
 * first sample on (one hand frame's 21 joints already span the hand: on the four Leap
 * recordings the first 50 ms give the whole recording's centre within 2-6 mm and its front
 * within 3-5 mm), at every frame while the samples kept span less than
 * FP_POSE_AUTO_SETTLE_S, then at most every FP_POSE_AUTO_REFIT_S of the samples' clock; never
 * while the caller says a gesture is engaged (the hands never jump under a grab or a drag);
 * and at once when still hands (FP_POSE_STILL_MM), placed hovering, first move.
 * Everything is decided on the events' times and the frames' order: the same events and
 * engagements give the same calibrations, bit for bit.
 *
 * Units: millimetres in the device frame in, the calibration in mesh units (fp_calibration).
 * Errors: fp_pose_auto_create returns -ENOMEM; nothing else fails.
 * Threads: an fp_pose_auto belongs to one thread (the session thread). No allocation after
 * create, no I/O.
 */
#ifndef FP_POSE_AUTO_H
#define FP_POSE_AUTO_H

#include "fp_pose.h"

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_POSE_AUTO_WINDOW_S 20.0   /* seconds of recent samples the estimate keeps */
#define FP_POSE_AUTO_RATE_HZ 64.0    /* samples kept per hand per second, at most */
#define FP_POSE_AUTO_SETTLE_S 1.0    /* while the samples span less: a refit every frame */
#define FP_POSE_AUTO_REFIT_S 0.25    /* afterwards: at most one refit per this much time */
#define FP_POSE_AUTO_BIN_MM 1.0      /* histogram bin width */
#define FP_POSE_AUTO_SPAN_MM 4096.0  /* histogram range: -span .. +span on every axis */
/** Hands that have not moved: until some fingertip of a hand has been FP_POSE_STILL_MM or
 *  more (on an axis) from where that hand's first sample put it, in two samples kept in a
 *  row (one glitch sample is not a move), the hands are still, and a refit places them
 *  `hover` in front of where their range would (fp_pose_auto_refit). Their range is then
 *  the hand's own size, and its front (a fingertip or a knuckle, whatever the pose) would
 *  sit at the nose tip's depth, touching the face or not by chance; a hand held still in
 *  front of the tracker hovers instead, and the hint tells the performer to reach. */
#define FP_POSE_STILL_MM 10.0

typedef struct fp_pose_auto fp_pose_auto;

/** A new estimator with no sample (about 0.7 MiB: the samples' ring and the histograms, of
 *  both hands and of each).
 *  Returns 0 and *out (owned by the caller: fp_pose_auto_destroy), or -ENOMEM (*out NULL). */
int fp_pose_auto_create(fp_pose_auto **out);

/** Free it and set *a to NULL; NULL or *a NULL: nothing. */
void fp_pose_auto_destroy(fp_pose_auto **a);

/** Take one input event: a joint positions event of the left or right hand whose joints are
 *  all finite becomes a sample (unless its hand's last sample is less than
 *  1 / FP_POSE_AUTO_RATE_HZ older, by the events' times; a time going backwards starts that
 *  hand's spacing anew); samples older than FP_POSE_AUTO_WINDOW_S before it are dropped,
 *  and the oldest when the ring is full. Every other event is ignored. ev: not NULL. */
void fp_pose_auto_take(fp_pose_auto *a, const fp_event *ev);

/** Number of samples kept now (each one hand's 21 joints). */
size_t fp_pose_auto_samples(const fp_pose_auto *a);

/** Every sample kept, oldest first, to fn: its hand (FP_HAND_LEFT or FP_HAND_RIGHT) and its
 *  FP_HAND_JOINTS joints (mm, device frame) at the middles of their FP_POSE_AUTO_BIN_MM bins
 *  (a valid pointer during the call only). For a placement that measures the hands against
 *  the face (step_arrive.h's bring-in). a, fn: not NULL. Cannot fail; no allocation; a's
 *  thread (the rule above). */
void fp_pose_auto_each(const fp_pose_auto *a, void (*fn)(void *ctx, int hand, const float (*mm)[3]), void *ctx);

/** The estimated workspace: per axis the 2nd and 98th percentiles of every joint of the
 *  samples kept (mm, device frame; the rank rule of the replay's workspace, read to the
 *  middle of a FP_POSE_AUTO_BIN_MM bin). Returns false (boxes untouched) with no sample. */
bool fp_pose_auto_box(const fp_pose_auto *a, float ws_min[3], float ws_max[3]);

/** Once a frame, after the frame's events were taken and before fp_pose_build: when a refit
 *  is due (see the header: any new sample since the last, not engaged, the schedule), the
 *  calibration p->calib becomes fp_pose_fit_workspace(mm_per_unit, the estimated box (with
 *  two hands, moved sideways and up to centre between the hands' own centres: the header),
 *  head_min, head_max), moved `hover` (mesh units, >= 0) away from the face in depth while
 *  the hands are still (FP_POSE_STILL_MM; fp_pose_auto_still), and gloves placed by fp_pose_place_gloves keep their place on the
 *  face (their device-frame wrists move by the offset's change; every fit is life-size at
 *  the same mm_per_unit without rotation, so only the offset changes). engaged: a gesture is
 *  engaged now (the session's last frame), and nothing changes. Returns true when
 *  p->calib was refitted (the first time: the first placement), false otherwise.
 *  mm_per_unit as fp_pose_fit_workspace's; head_min/head_max: the head box (fp_head). */
bool fp_pose_auto_refit(fp_pose_auto *a, fp_pose_state *p, bool engaged, double mm_per_unit,
                        const float head_min[3], const float head_max[3], double hover);

/** Whether no hand has moved yet (FP_POSE_STILL_MM): true before any sample. */
bool fp_pose_auto_still(const fp_pose_auto *a);

/** Whether the hands are held in place: a fingertip moved (not fp_pose_auto_still), the
 *  samples kept so far span FP_POSE_HELD_S or more (the newest sample's time against the
 *  first's), and no hand's base (its palm centre and every finger's first joint,
 *  FP_JOINT(f, 0)) has been FP_POSE_STILL_MM or more (on an axis) from where that hand's
 *  first sample put it, in two samples kept in a row: a hand held in place whose fingers act
 *  (a pinch), whose range is its own reach from where it is held. (The four Leap
 *  recordings' bases move so far within 0.05-0.88 s, a hand that reaches sooner still.) Once
 *  a base moved, false for good. */
#define FP_POSE_HELD_S 1.0
bool fp_pose_auto_held(const fp_pose_auto *a);

/** Refits done so far (the first one is the first placement). */
unsigned long fp_pose_auto_refits(const fp_pose_auto *a);

#ifdef __cplusplus
}
#endif
#endif
