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
#include "fp_head.h"

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Workspace calibration: p_mesh = scale * R p_mm + offset + hand_offset[hand] (hands: mm,
 *  device frame; the device's +x right, +y up, +z toward the performer, as the mesh's +x,
 *  +y, +z when R is the identity). A rotation of all zeros counts as the identity, so
 *  {scale, {x, y, z}} initialisers keep their meaning. docs/calibration.md has the file. */
typedef struct fp_calibration {
    double scale;                   /* mesh units per millimetre (1 / mm_per_unit) */
    double offset[3];               /* mesh units, both hands */
    double rotation[4];             /* device -> mesh, unit quaternion w, x, y, z */
    double hand_offset[FP_HANDS][3];/* mesh units, added per hand (left, right) */
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
    bool glove_placed;                          /* fp_pose_place_gloves ran */
    float glove_pos[FP_HANDS][3], glove_rot[FP_HANDS][4];  /* its wrists, device mm */
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
 *  given wrist pose, else the glove placement of fp_pose_place_gloves, else
 *  fp_pose_default_wrist), then the calibration. Call once a frame
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

/** The life-size calibration: scale = 1 / mm_per_unit (hands and head at the same physical
 *  scale), rotation identity, the workspace's centre in x and y on the head box's centre, and
 *  in depth its front (ws_min z, the reach toward the face: a tracker sees the hands fingers
 *  first, so the 2nd percentile of every joint's depth is where the fingertips usually reach)
 *  FP_POSE_REACH_PRESS_MM behind the face's frontmost point (head_max z, the nose tip). The
 *  hands at rest hover in front of the face (on the ICT face the fingertips of the real
 *  recordings sit a median 25-40 mm off the surface under them), the usual forward reach
 *  touches the face's front, a reach beyond it presses in; moving across the face brings
 *  the fingertips near the surface and away (the anchored mapping engages and lets go).
 *  head_min is unused (kept for the callers). mm_per_unit <= 0 or non-finite counts as 1. */
#define FP_POSE_REACH_PRESS_MM 0.0
void fp_pose_fit_workspace(fp_calibration *c, double mm_per_unit, const float ws_min[3],
                           const float ws_max[3], const float head_min[3], const float head_max[3]);

/** Place gloves that report no wrist pose (p->calib set first): each hand's wrist in front
 *  of its half of the face (the head box of `head`), palm toward the face (-z), fingers up
 *  (+y), the open hand's middle fingertip at the head box's centre height and a quarter of
 *  its width from the middle; the hand is then moved along z until its open fingertips and
 *  DIP joints are FP_POSE_GLOVE_GAP_MM in front of the surface under them
 *  (fp_head_surface_z within 15 mm), so that curling the fingers presses the tips in.
 *  pos: the mesh's n vertices (mesh units). Stores the wrists in device mm (the inverse of
 *  the calibration) in p->glove_pos/glove_rot and sets p->glove_placed. */
#define FP_POSE_GLOVE_GAP_MM 8.0
void fp_pose_place_gloves(fp_pose_state *p, const float *pos, size_t n, const fp_head *head);

/** p_mesh = c->scale * R p_mm + c->offset + c->hand_offset[hand], in double, rounded to
 *  float (hand outside left/right: no hand offset). */
void fp_pose_to_mesh(const fp_calibration *c, int hand, const float mm[3], float out[3]);


#ifdef __cplusplus
}
#endif
#endif
