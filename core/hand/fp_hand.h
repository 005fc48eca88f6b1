/*
 * fp_hand.h: the hand skeleton ("VR Hand" of Sato, Savchenko, Ohbuchi, Cyberworlds 2004):
 * forward kinematics from CyberGlove joint angles to the 21 joint positions of
 * facepuppet/plugin.h, the reverse conversion from measured joint positions, and fitting of
 * the hand size and rest geometry to measured joints.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Threads: every function here is pure and reentrant ([any-thread]); none allocates, locks,
 * does I/O or keeps state between calls, so all may run on the session thread.
 *
 * Errors (fp_error.h): functions return 0 or a negative errno: -EINVAL (NULL pointer, bad
 * side, size <= 0, too few frames), -ERANGE (a NaN or infinite value in the input), -EDOM
 * (degenerate geometry: zero quaternion, parallel frame axes, coincident joints);
 * fp_hand_strerror says which in the hand's words. On error the outputs are left untouched
 * (never partly written, never NaN).
 *
 * ## The hand's own frame
 * Right-handed, in millimetres. Origin: the wrist, placed at the base of the middle
 * metacarpal. +y: out of the back of the hand; -z: toward the fingers (along the middle
 * metacarpal); +x = y cross z. So +x points toward the little finger of a RIGHT hand and
 * toward the thumb of a LEFT hand: the left hand is the mirror image (x -> -x) of the right.
 * (plugin.h's fp_event_wrist_pose says the same since ABI 1.1; 1.0 said "+x toward the thumb
 * side for a right hand", a left-handed frame with +y and -z as given, which no rotation
 * quaternion can produce. This module reads the quaternion as a proper rotation of it.)
 *
 * ## Angles (radians, enum fp_glove_sensor order, 22 values)
 * Conventions are those of the "cyberglove_like" Leap recordings in shared/data
 * (hands/leap-motion/README in ../shared/data/README.md), so that the two agree:
 *  - finger MPJ: flexion of the proximal phalanx measured in the plane of the hand
 *    direction and the palm normal (projected angle), + toward the palm;
 *  - PIJ, DIJ: flexion between consecutive phalanges, + toward the palm;
 *  - abductions: angle between adjacent proximal phalanges in the palm plane, + when they
 *    spread apart. The split is symmetric around the middle finger: the middle finger keeps
 *    its rest direction (model.middle_yaw_rad), the index turns toward the thumb by
 *    MIDDLE_INDEX_AB, the ring toward the little finger by RING_MIDDLE_AB, the little finger
 *    by RING_MIDDLE_AB + PINKIE_RING_AB;
 *  - THUMB_AB: angle in the palm plane between the thumb metacarpal and the index proximal
 *    phalanx; THUMB_ROTATE: elevation of the thumb metacarpal out of the palm plane toward
 *    the palm (opposition); THUMB_MPJ, THUMB_IJ: flexion at the thumb MCP and IP joints,
 *    in the plane given by model.thumb_twist_rad (tip moves toward the little finger);
 *  - PALM_ARCH: the little finger's metacarpal turns about the middle metacarpal axis
 *    toward the palm by this angle, the ring finger's by half of it;
 *  - WRIST_PITCH (+ flexion toward the palm) and WRIST_YAW (+ toward the thumb) turn the
 *    whole hand about the wrist origin.
 * 18-sensor gloves have no DIJ sensors: where a DIJ bit is clear but the PIJ bit of the same
 * finger is set, DIP = 2/3 PIP (the usual coupling of the distal to the proximal
 * interphalangeal joint). Any other cleared bit takes model.rest_rad[i].
 *
 * ## Bone lengths
 * Mean adult lengths of Buryanov & Kotiuk 2010, "Proportions of hand segments", Int. J.
 * Morphol. 28(3):755-758 (shared/docs/devices.md), times model.size. Tips lie at the end of
 * the distal phalanx plus model.tip_pad times the soft tip (1 = the finger pad, 0 = the bone
 * end, which is where the Leap Motion puts its "tip").
 */
#ifndef FP_HAND_H
#define FP_HAND_H

#include <stddef.h>
#include <stdint.h>

#include "facepuppet/plugin.h"

#ifdef __cplusplus
extern "C" {
#endif

/** [any-thread] A static English message for a code of this module: -ERANGE and -EDOM in
 *  the hand's words, anything else as fp_strerror. */
const char *fp_hand_strerror(int code);

/** All bit masks of the 22 sensors; FP_HAND_DIJ_BITS are the four DIJ sensors. */
#define FP_HAND_ALL_SENSORS 0x3FFFFFu
#define FP_HAND_DIJ_BITS                                                                   \
    ((1u << FP_SENSOR_INDEX_DIJ) | (1u << FP_SENSOR_MIDDLE_DIJ) | (1u << FP_SENSOR_RING_DIJ) | \
     (1u << FP_SENSOR_PINKIE_DIJ))

/** Finger bones, index of fp_hand_model.bone_mm[f][b]. The thumb has no middle phalanx. */
enum fp_hand_bone { FP_BONE_METACARPAL = 0, FP_BONE_PROXIMAL, FP_BONE_MIDDLE, FP_BONE_DISTAL };

/** A hand model. Fill with fp_hand_model_init, then change what you measured. All lengths
 *  and positions are of the mean adult RIGHT hand (size 1) and are multiplied by `size`. */
typedef struct fp_hand_model {
    float size;                /* hand size factor, > 0; 1 = mean adult */
    float bone_mm[FP_FINGERS][4];  /* fp_hand_bone order; thumb [0][FP_BONE_MIDDLE] = 0 */
    float tip_pad_mm[FP_FINGERS];  /* soft tip beyond the distal phalanx */
    float tip_pad;             /* 0..1: share of tip_pad_mm in the tip joint */
    float base_mm[FP_FINGERS][3];  /* hand frame: thumb CMC, then index..little MCP */
    float palm_mm[3];          /* hand frame: palm centre (joint FP_JOINT_PALM) */
    float middle_yaw_rad;      /* rest direction of the middle proximal phalanx in the palm
                                  plane, + toward the thumb */
    float thumb_twist_rad;     /* turn of the thumb's flexion axis about its metacarpal */
    float rest_rad[FP_GLOVE_SENSORS]; /* default pose, used for masked-out sensors */
} fp_hand_model;

/** [any-thread] Fill *m with the mean adult right hand: size 1, tip_pad 1, Buryanov & Kotiuk
 *  2010 bone lengths, and the rest geometry below. Sources of the defaults: MCP/CMC offsets,
 *  palm centre, middle_yaw_rad (-11.0 deg) and rest THUMB_ROTATE (9.0 deg) and THUMB_AB
 *  (45 deg) are the means of the five hands in the shared Leap Motion recordings, each
 *  divided by its fitted size factor, moved so that the middle MCP lies at 64.6 mm (the
 *  middle metacarpal) along -z from the wrist origin. thumb_twist_rad = 90 deg (thumb pad
 *  facing the index, as at rest). All other rest angles are 0 (a flat hand). */
void fp_hand_model_init(fp_hand_model *m);

/** [any-thread] Forward kinematics: joint angles -> the 21 joint positions (fp_hand_joint
 *  layout: palm, then thumb CMC/MCP/IP/tip, then each finger MCP/PIP/DIP/tip), computed from
 *  the model's rest geometry on every call (nothing accumulates between calls).
 *  angles_rad: 22 values, radians, fp_glove_sensor order (see the top of this file); may be
 *  NULL when valid_mask is 0. valid_mask: bit i set where angles_rad[i] was measured;
 *  cleared sensors take model->rest_rad[i] (DIJ: 2/3 of a valid PIJ).
 *  wrist_pos_mm, wrist_rot_wxyz: the pose of the hand frame in the device frame (plugin.h
 *  fp_event_wrist_pose; the quaternion need not be unit, it is normalised); both NULL: the
 *  joints are given in the hand's own frame. One NULL and not the other: -EINVAL.
 *  side: the left hand is the right mirrored in x in the hand frame.
 *  joints_mm: out, millimetres. Errors: -EINVAL (NULL model/joints, bad side,
 *  size <= 0), -ERANGE (NaN/inf in a valid angle, in the pose or in the model),
 *  -EDOM (quaternion of norm < 1e-6). */
int fp_hand_fk(const fp_hand_model *model, fp_hand_side side, const float angles_rad[22],
               uint32_t valid_mask, const float wrist_pos_mm[3], const float wrist_rot_wxyz[4],
               float joints_mm[FP_HAND_JOINTS][3]);

/** [any-thread] The hand frame from a tracker's palm: palm centre (mm), palm normal (out of
 *  the palm) and hand direction (toward the fingers), as in the Leap *_joints_mm.csv
 *  (palm_*, palm_n*, dir_*). Neither vector need be unit; the direction is made orthogonal
 *  to the normal. Writes the wrist pose (position mm, quaternion w,x,y,z) that puts the
 *  model's palm centre (scaled by model->size, mirrored for the left hand) at palm_mm, in the
 *  form fp_hand_fk takes. The palm's axes are those of the hand frame at rest WRIST_PITCH and
 *  WRIST_YAW (0 by default): a tracker's palm already includes the wrist turn. Errors: -EINVAL, -ERANGE, -EDOM
 *  (a zero vector, or normal parallel to direction). */
int fp_hand_frame_from_palm(const fp_hand_model *model, fp_hand_side side,
                            const float palm_mm[3], const float palm_normal[3],
                            const float direction[3], float wrist_pos_mm[3],
                            float wrist_rot_wxyz[4]);

/** [any-thread] Move n points from the device frame into the hand frame whose pose is
 *  (wrist_pos_mm, wrist_rot_wxyz): out = R^T (in - pos). in and out may be the same array.
 *  Errors: -EINVAL, -ERANGE, -EDOM (zero quaternion). */
int fp_hand_to_hand_frame(const float wrist_pos_mm[3], const float wrist_rot_wxyz[4],
                          const float (*in_mm)[3], size_t n, float (*out_mm)[3]);

/** Joint angles plus wrist pose: what fp_hand_fk takes. */
typedef struct fp_hand_angles {
    float radians[FP_GLOVE_SENSORS];
    uint32_t valid;             /* fp_glove_sensor bits */
    float wrist_pos_mm[3];      /* pose of the hand frame in the device frame */
    float wrist_rot_wxyz[4];
} fp_hand_angles;

/** [any-thread] Joint positions (an fp_event_joint_positions mm array, device frame,
 *  fp_hand_joint layout) -> the angle representation fp_hand_fk takes, so that trackers that
 *  measure positions drive the same pipeline as gloves. The hand frame is found from the
 *  palm centre and the index and little-finger MCPs, matched to the model's rest geometry
 *  (model->base_mm, palm_mm, size); angles follow the conventions at the top of this file
 *  (abductions are signed here, crossing fingers give negative values). Sets every bit of
 *  out->valid except PALM_ARCH, WRIST_PITCH and WRIST_YAW, which a frame found from the palm
 *  cannot separate from the wrist pose (they stay at rest; the pose carries them).
 *  fp_hand_fk(model, side, out...) reproduces the input exactly when the input was itself
 *  made by fp_hand_fk with the same model and rest palm arch/wrist angles.
 *  Errors: -EINVAL, -ERANGE, -EDOM (coincident joints). */
int fp_hand_from_positions(const fp_hand_model *model, fp_hand_side side,
                           const float joints_mm[FP_HAND_JOINTS][3], fp_hand_angles *out);

/** [any-thread] The five fingertips (thumb first) of one hand's joints: tips[f] =
 *  joints[FP_JOINT_TIP(f)]. Errors: -EINVAL (NULL). */
int fp_hand_fingertips(const float joints_mm[FP_HAND_JOINTS][3], float tips_mm[FP_FINGERS][3]);

/** [any-thread] The ten fingertips of both hands: tips[0..4] left thumb..little, tips[5..9]
 *  right. A NULL hand leaves its five rows untouched. Errors: -EINVAL (tips NULL). */
int fp_hand_fingertips2(const float left_mm[FP_HAND_JOINTS][3],
                        const float right_mm[FP_HAND_JOINTS][3], float tips_mm[10][3]);

/** [any-thread] Least-squares hand size factor from measured joint positions (any frame):
 *  minimises sum over frames and the 14 measured segments (thumb CMC-MCP-IP-tip, each finger
 *  MCP-PIP-DIP-tip) of (|measured| - size * model length)^2, closed form
 *  size = sum(l m) / sum(m^2) with m the model's size-1 length (the distal segment includes
 *  tip_pad * tip_pad_mm). joints_mm: n frames of 21 x 3 mm. Frames with a non-finite value
 *  are skipped. Errors: -EINVAL (NULL, n == 0, no usable frame). */
int fp_hand_fit_size(const fp_hand_model *model, const float (*joints_mm)[FP_HAND_JOINTS][3],
                     size_t n, float *size_out);

/** [any-thread] Fit the model to a recording: joints_hand_mm are n frames of 21 x 3 mm
 *  already in the hand frame of fp_hand_frame_from_palm (built with this model), or any frame
 *  with the same axes. Sets, in this order: size (fp_hand_fit_size); base_mm (thumb CMC and
 *  finger MCPs) to the mean measured position relative to the palm centre, divided by size,
 *  plus palm_mm (the palm stays where it was); middle_yaw_rad to the mean direction of the
 *  middle proximal phalanx; rest_rad[THUMB_ROTATE] to the mean elevation of the thumb
 *  metacarpal. Left-hand data are mirrored into the right-hand model. Frames with a
 *  non-finite value are skipped. Errors: as fp_hand_fit_size; *model unchanged on error. */
int fp_hand_fit_geometry(fp_hand_model *model, fp_hand_side side,
                         const float (*joints_hand_mm)[FP_HAND_JOINTS][3], size_t n);

/** [any-thread] Unit quaternion -> rotation matrix: q = (w, x, y, z) need not be unit (it is
 *  normalised in double); r[i][j] is row i, column j, so r's columns are the rotated axes.
 *  Returns 0, or -EINVAL (r untouched) when |q| < 1e-6 or q is not finite. */
int fp_hand_quat_to_mat(const float q_wxyz[4], double r[3][3]);

/** [any-thread] Rotation matrix -> unit quaternion (w, x, y, z) with w >= 0, by Shepperd's
 *  method (S. W. Shepperd, "Quaternion from rotation matrix", J. Guidance and Control 1(3),
 *  1978): the largest of w, x, y, z is taken from the diagonal, the others from the
 *  off-diagonal sums and differences, which stays accurate near 180-degree turns. r must be
 *  a proper rotation (orthonormal, det +1; no check); r as in fp_hand_quat_to_mat. */
void fp_hand_mat_to_quat(const double r[3][3], float q_wxyz[4]);

#ifdef __cplusplus
}
#endif
#endif /* FP_HAND_H */
