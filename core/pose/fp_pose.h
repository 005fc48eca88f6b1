/*
 * fp_pose.h: step 2 of the frame (docs/architecture.md): hand poses and the workspace
 * calibration. Input events (plugin.h: joint positions, joint angles, wrist poses, status)
 * update a per-hand state; fp_pose_build turns it into fp_hand_pose joints in mesh units:
 * joint positions as a tracker gave them, or forward kinematics (core/hand, fp_hand_fk) from
 * joint angles and the wrist pose (a default wrist placement for a glove that reports none),
 * then p_mesh = scale * p_mm + offset (the workspace calibration).
 *
 * Units: hand events in millimetres in the device frame (+x right, +y up, +z toward the
 * performer, taken as the mesh's +x, +y, +z); poses out in mesh units.
 * Errors: nothing here fails; bad input (a hand index outside left/right) is ignored.
 * Threads: an fp_pose_state belongs to one thread (the session thread); the free functions
 * are pure and reentrant. No allocation, no I/O.
 */
#ifndef FP_POSE_H
#define FP_POSE_H

#include "fp_hand.h"

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Workspace calibration: p_mesh = scale * p_mm + offset (hands: mm, device frame; the
 *  device's +x right, +y up, +z toward the performer, as the mesh's +x, +y, +z). */
typedef struct fp_calibration {
    double scale;        /* mesh units per millimetre */
    double offset[3];    /* mesh units */
} fp_calibration;

/** What is known of one hand from its events (millimetres, device frame). */
typedef struct fp_pose_hand {
    bool present;                 /* seen, and not disconnected since */
    bool have_positions;          /* the latest hand event gave joint positions */
    bool have_angles;             /* ... or joint angles (forward kinematics) */
    bool have_wrist;              /* a wrist pose was given (else the default placement) */
    fp_event_joint_angles angles;
    float wrist_pos[3], wrist_rot[4];     /* mm; unit quaternion w, x, y, z */
    float joints_mm[FP_HAND_JOINTS][3];   /* fp_hand_joint layout */
    int64_t time_ns;                      /* the latest hand event's host time */
} fp_pose_hand;

/** The pose step's state: both hands, the hand model, the calibration, and the poses of the
 *  latest fp_pose_build. */
typedef struct fp_pose_state {
    fp_pose_hand hands[FP_HANDS];
    fp_hand_model model;
    fp_calibration calib;
    fp_hand_pose poses[FP_HANDS];   /* mesh units; poses[h].present as hands[h].present */
} fp_pose_state;

/** Start with no hand seen, the mean adult hand (fp_hand_model_init) scaled by hand_size
 *  when > 0, and calibration c. */
void fp_pose_init(fp_pose_state *p, double hand_size, const fp_calibration *c);

/** Take one input event: joint positions (replace the joints; positions win over angles
 *  until angles come again), joint angles, a wrist pose, or a DISCONNECTED status (the hand
 *  is absent until its next event). Other events and events without a hand are ignored. */
void fp_pose_take_event(fp_pose_state *p, const fp_event *ev);

/** Build p->poses from the hands' state: forward kinematics where only angles came (with the
 *  given wrist pose, else fp_pose_default_wrist), then the calibration. Call once a frame
 *  after the events are taken. */
void fp_pose_build(fp_pose_state *p);

/** Default wrist placement for a glove that reports no wrist pose: the two hands side by
 *  side 80 mm from the middle (left at -x), 200 mm above the device and 60 mm toward the
 *  performer, identity rotation (fingers pointing away, -z). pos mm, rot w, x, y, z. */
void fp_pose_default_wrist(int hand, float pos[3], float rot[4]);

/** The workspace assumed when no input tells its own: where a desktop tracker sees hands
 *  (the Leap Motion interaction box, mm): x -150..150, y 80..330, z -120..120. */
void fp_pose_default_workspace(float ws_min[3], float ws_max[3]);

/** Union of the workspaces the inputs tell through the FP_EXT_WORKSPACE extension
 *  (inputs: n instances, NULL entries skipped). Returns true and the box when at least one
 *  input tells one; false (box untouched) otherwise. Main thread (calls the plugins). */
bool fp_pose_inputs_workspace(fp_input *const *inputs, size_t n, float ws_min[3], float ws_max[3]);

/** Fit the hands' workspace (mm) to the face's bounds (mesh units): the workspace's width
 *  spans the face's width (scale = the smaller of the width and height ratios), its centre
 *  in x and y lands on the face's centre, and its deepest point (-z, farthest from the
 *  performer) reaches 15% of the face's depth behind the face's front (max z), so that the
 *  performer's forward reach touches the face. Extents below 1 mm count as 1 mm. */
void fp_pose_fit_workspace(fp_calibration *c, const float ws_min[3], const float ws_max[3],
                           const float face_min[3], const float face_max[3]);

/** p_mesh = c->scale * p_mm + c->offset, in double, rounded to float. */
void fp_pose_to_mesh(const fp_calibration *c, const float mm[3], float out[3]);

#ifdef __cplusplus
}
#endif
#endif
