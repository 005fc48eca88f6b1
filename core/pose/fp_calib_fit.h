/*
 * fp_calib_fit.h: make a calibration (fp_pose.h's fp_calibration) from a short recording of
 * the performer's hands, for `facepuppet calibrate` (docs/calibration.md):
 *  - hold:  the performer holds the hands where the face is for a few seconds; each hand's
 *           median palm position maps onto the face's surface in front of its half of the
 *           face (life-size: the scale is 1 / mm_per_unit, no rotation);
 *  - touch: the performer touches chin, nose tip and forehead in turn with one fingertip;
 *           the three longest still moments of that fingertip, in time order, are matched to
 *           those three landmarks and a similarity transform (scale, rotation, offset) is
 *           fitted by least squares (Umeyama 1991, "Least-squares estimation of
 *           transformation parameters between two point patterns", IEEE PAMI 13(4), eq.
 *           40-42; the rotation through Horn's unit quaternion, J. Opt. Soc. Am. A 4(4),
 *           1987, which is the same optimum and never a reflection).
 * Units: samples in mm (device frame), the mesh in mesh units. Errors: -EINVAL (NULL, too
 * few samples, no palm or fingertip positions), -EDOM (the touches could not be found, or
 * they are collinear), with a message in err. Pure: no I/O, no printing; thread-safe.
 */
#ifndef FP_CALIB_FIT_H
#define FP_CALIB_FIT_H

#include "fp_head.h"
#include "fp_pose.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** One hand sample of a recording: time (ns), hand (fp_hand_side), joints (fp_hand_joint
 *  layout, mm). */
typedef struct fp_calib_sample {
    int64_t t_ns;
    int hand;
    float joints[FP_HAND_JOINTS][3];
} fp_calib_sample;

/** The touch landmarks, in order. */
enum { FP_CALIB_CHIN = 0, FP_CALIB_NOSE_TIP, FP_CALIB_FOREHEAD, FP_CALIB_LANDMARKS };

/** Still moments shorter than this are not touches. */
#define FP_CALIB_MIN_STILL_S 0.25
/** A fingertip is still while it stays within this distance (mm) of where it stopped. */
#define FP_CALIB_STILL_MM 8.0

/** Touches closer than this (mm) to each other are refused. */
#define FP_CALIB_MIN_APART_MM 20.0
/** A touch fit whose rms residual (in mm at the fitted scale) exceeds this is refused: the
 *  touches do not have the face's shape. */
#define FP_CALIB_MAX_RESIDUAL_MM 15.0

/** Where "in front of each half of the face" is: the target of the left (h = 0) and right
 *  hand's palm, mesh units: x a quarter of the head box's width left / right of its middle,
 *  y the nose tip's height, z the frontmost surface there (fp_head_surface_z within 15 mm). */
void fp_calib_hold_target(const float *pos, size_t n, const fp_head *head, int hand, float out[3]);

/** A hold whose palm travels farther than this (mm, fp_calib_hold_travel) was not held:
 *  calibrate warns (the median palm of a moving hand is not where the face was held). */
#define FP_CALIB_HOLD_TRAVEL_MM 40.0

/** How far each hand's palm travelled during a hold, mm (the samples' unit): the diagonal of
 *  the box of its positions between the 2nd and 98th percentile per axis, so one glitch does
 *  not count (a palm held still by a person: under 30 mm on the shipped recordings, HandSplay
 *  28, Waiting 30; grab 57, three-claps 72-76); travel[h] = 0 where hand h has fewer than 3
 *  samples. Allocates scratch; on
 *  allocation failure the hand reads 0. Pure otherwise; any thread. */
void fp_calib_hold_travel(const fp_calib_sample *samples, size_t n, double travel[FP_HANDS]);

/** Hold mode: the median palm (per axis) of each hand in samples (n of them) is put on
 *  fp_calib_hold_target: scale 1 / head->mm_per_unit, rotation identity; with two hands the
 *  common offset is their mean and each hand's remainder goes to hand_offset. */
int fp_calib_fit_hold(const fp_calib_sample *samples, size_t n, const float *pos, size_t nv,
                      const fp_head *head, fp_calibration *out, char *err, size_t errlen);

/** Landmarks estimated from the head (no rig): the nose tip is the frontmost vertex above
 *  the neck; the chin the frontmost vertex within 1 cm of the nose tip's x between the neck
 *  and 25% of the way up to the nose tip; the forehead the frontmost surface at the nose
 *  tip's x, 45% of the way from the nose tip to the crown. out: mesh units. */
void fp_calib_head_landmarks(const float *pos, size_t n, const fp_head *head,
                             float out[FP_CALIB_LANDMARKS][3]);

/** The three longest still moments (>= FP_CALIB_MIN_STILL_S) of fingertip `finger` of the
 *  hand seen most, in time order: their median positions (mm) in touched[3], their start
 *  and end times in t_ns[3][2]. Returns 0 or -EDOM (fewer than three). */
int fp_calib_find_touches(const fp_calib_sample *samples, size_t n, int finger,
                          double touched[FP_CALIB_LANDMARKS][3], int64_t t_ns[FP_CALIB_LANDMARKS][2],
                          char *err, size_t errlen);

/** Touch mode: fp_calib_find_touches (index fingertip) matched to landmarks[3] (mesh units,
 *  chin, nose tip, forehead), then fp_similarity_fit (fp_similarity.h): scale s, rotation, offset t. The
 *  touch points in mm go to touched (may be NULL); rms the fit's residual, mesh units (may
 *  be NULL). -EDOM also for touches under FP_CALIB_MIN_APART_MM apart or a residual over
 *  FP_CALIB_MAX_RESIDUAL_MM. */
int fp_calib_fit_touch(const fp_calib_sample *samples, size_t n,
                       const float landmarks[FP_CALIB_LANDMARKS][3], fp_calibration *out,
                       double touched[FP_CALIB_LANDMARKS][3], double *rms, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
