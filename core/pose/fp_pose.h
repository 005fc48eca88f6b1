/*
 * fp_pose.h: step 2 of the frame (docs/architecture.md): hand poses and the workspace
 * calibration. Input events (plugin.h: joint positions, joint angles, wrist poses, status)
 * update a per-hand state; fp_pose_build turns it into fp_hand_pose joints in mesh units:
 * joint positions as a tracker gave them, or forward kinematics (core/hand, fp_hand_fk) from
 * joint angles and the wrist pose (a default wrist placement for a glove that reports none),
 * then p_mesh = scale * p_mm + offset (the workspace calibration).
 *
 * Steady hands (issue 51): each hand event may first go through its input's One Euro filter
 * (fp_filter.h; fp_pose_take_event_filtered, the event's source choosing the filter's state),
 * and fp_pose_build_at gives each hand at the frame's time, not as its last sample held: from
 * the last two samples of each kind (joint positions, joint angles, wrist pose) the frame
 * sees x1 + u (x1 - x0), u = (now - t1) / (t1 - t0), at least -1: interpolated between
 * them for a frame before the latest sample, predicted after it, less than one sampling
 * period ahead (u bent smoothly toward 1 past FP_POSE_KNEE), held there when the samples stop
 * (no runaway). A 57 Hz tracker read at 60 frames a second thus gives a new pose every frame
 * instead of repeating one every 20th, and so does a frame in a gap of a dropped sample.
 *
 * Units: hand events in millimetres in the device frame (+x right, +y up, +z toward the
 * performer, taken as the mesh's +x, +y, +z); poses out in mesh units.
 * Errors: nothing here fails; bad input (a hand index outside left/right) is ignored.
 * Threads: an fp_pose_state belongs to one thread (the session thread); the free functions
 * are pure and reentrant. No allocation, no I/O.
 */
#ifndef FP_POSE_H
#define FP_POSE_H

#include "fp_filter.h"
#include "fp_hand.h"
#include "fp_head.h"

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Workspace calibration: p_mesh = F (scale * R p_mm + offset + hand_offset[hand]) (hands: mm,
 *  device frame; the device's +x right, +y up, +z toward the performer, as the mesh's +x,
 *  +y, +z when R and F are the identity). A rotation of all zeros counts as the identity, so
 *  {scale, {x, y, z}} initialisers keep their meaning. docs/calibration.md has the file.
 *  F, the face's frame, is the session's: where a rig placed on a turned copy of its mesh
 *  (fp_rig_placement) says the face looks along another axis than +z or up is not +y, F
 *  turns the face's frame (its left, up and forward as x, y, z) into the mesh's; the head
 *  box and every fit of the hands (fp_pose_fit_workspace, the arrival's) then work in the
 *  face's frame, as for a face that looks along +z. Files and takes hold it folded into R
 *  and the offsets (fp_calibration_flatten). */
typedef struct fp_calibration {
    double scale;                   /* mesh units per millimetre (1 / mm_per_unit) */
    double offset[3];               /* mesh units, both hands */
    double rotation[4];             /* device -> mesh, unit quaternion w, x, y, z */
    double hand_offset[FP_HANDS][3];/* mesh units, added per hand (left, right) */
    double face[4];                 /* F: face's frame -> mesh, unit quaternion; all zeros: none */
} fp_calibration;

/** A face frame turned from +x, +y, +z by more than this (degrees) is one; less is none (the
 *  face's frame of the session and of calibrate --mode hold). */
#define FP_FACE_TURNED_DEG 0.5

/** Whether the unit quaternion q turns by more than FP_FACE_TURNED_DEG. Pure; any thread. */
bool fp_face_turned(const double q[4]);

/** The face frame whose up and facing (the axis the face looks along) in the mesh are given:
 *  q (unit quaternion w, x, y, z) turns +y into up and +z into facing. Returns 0, or -EINVAL
 *  where either is not of unit length or they are not at a right angle (within 1e-3; zeros:
 *  not given). Pure; any thread. */
int fp_face_from_axes(const float up[3], const float facing[3], double q[4]);

/** Whether c has a face frame (face neither all zeros nor the identity). Pure; any thread. */
bool fp_calibration_has_face(const fp_calibration *c);

/** c with its face frame folded into the rest (out->face all zeros; the same p_mesh for every
 *  hand and point): what a take or a file records. out may be c. Pure; any thread. */
void fp_calibration_flatten(const fp_calibration *c, fp_calibration *out);

/** One stream of a hand's positions under the jump rule (FP_POSE_JUMP_MM): the joints, or
 *  the wrist's position (its first point). */
typedef struct fp_pose_jumps {
    float raw[FP_HAND_JOINTS][3];         /* the latest taken, as they came (unfiltered) */
    float held[FP_HAND_JOINTS][3];        /* a sample held back as a jump */
    int64_t held_t_ns;
    int64_t seen_t_ns;                    /* the latest sample's time, taken or not */
    bool pending;                         /* held holds a sample */
} fp_pose_jumps;

/** What is known of one hand from its events (millimetres, device frame), as filtered: the
 *  latest sample of each kind and the one before it (prev_*), each with its event time. */
typedef struct fp_pose_hand {
    bool present;                 /* seen, and not disconnected since */
    bool have_positions;          /* the latest hand event gave joint positions */
    bool have_angles;             /* ... or joint angles (forward kinematics) */
    bool have_wrist;              /* a wrist pose was given (else the default placement) */
    fp_event_joint_angles angles;
    float wrist_pos[3], wrist_rot[4];     /* mm; unit quaternion w, x, y, z */
    float joints_mm[FP_HAND_JOINTS][3];   /* fp_hand_joint layout */
    int64_t time_ns;                      /* the latest hand event's host time */
    /* the samples before the latest (valid where prev_* is set; cleared on a disconnect) */
    bool prev_positions, prev_angles, prev_wrist;
    float prev_joints_mm[FP_HAND_JOINTS][3];
    float prev_radians[FP_GLOVE_SENSORS];
    uint32_t prev_valid;
    float prev_wrist_pos[3], prev_wrist_rot[4];
    int64_t joints_t_ns, prev_joints_t_ns;   /* the event times of joints_mm, prev_joints_mm */
    int64_t angles_t_ns, prev_angles_t_ns;
    int64_t wrist_t_ns, prev_wrist_t_ns;
    float built_mm[FP_HAND_JOINTS][3];    /* the joints of the latest build (device mm) */
    /* jumps (FP_POSE_JUMP_MM) of the joints and of the wrist's position; a hand found
     * elsewhere is absent until absent_until_ns */
    fp_pose_jumps joint_jumps, wrist_jumps;
    int64_t absent_until_ns;
    unsigned long jumps;                  /* hands found elsewhere (confirmed jumps) */
    unsigned long glitches;               /* single samples dropped as jumps */
} fp_pose_hand;

/** The inputs whose filter state is kept (an event's header.source below it; = the
 *  session's FP_SESSION_MAX_INPUTS). Events of other sources are not filtered. */
#define FP_POSE_MAX_INPUTS 8
/** Samples farther apart than this are not extrapolated between (a hand found again after a
 *  pause): the frame holds the latest. */
#define FP_POSE_MAX_PERIOD_NS 100000000LL
/** The prediction follows the last two samples' line up to this fraction of a sampling
 *  period past the latest sample, then bends smoothly toward one whole period, which it
 *  never reaches (fp_pose_build_at). */
#define FP_POSE_KNEE 0.9

/** Jumps: a joint positions sample whose joints moved more than FP_POSE_JUMP_MM from the
 *  hand's latest (some joint, as they came), and faster than FP_POSE_JUMP_MM_S, is not a hand
 *  moving (the real recordings' fingertips move 28 mm at most between samples, 1.7 m/s at
 *  most; the speed over the time since the sample before, taken or held back, so that a
 *  tracker sending nonsense at its rate never passes) but a tracker's glitch: a hand swapped
 *  for the other, or lost and found elsewhere.
 *  It is held back, the hand staying where it was. The next sample decides: near where the
 *  hand was, the glitch is dropped (fp_pose_hand.glitches); near the held one, the hand was
 *  found elsewhere (.jumps): it starts afresh there (no motion across the jump, its filter
 *  reset) and is absent for frames before FP_POSE_JUMP_ABSENT_NS past that sample, so a
 *  gesture it held lets go instead of dragging the skin across the jump; far from both, it is
 *  held back in turn. A hand held back longer than FP_POSE_MAX_PERIOD_NS is absent. A wrist
 *  pose's position (a glove's tracker) goes by the same rule. */
#define FP_POSE_JUMP_MM 60.0
#define FP_POSE_JUMP_MM_S 5000.0
#define FP_POSE_JUMP_ABSENT_NS 50000000LL

/** One input's One Euro filters for one hand: a joint each (positions, mm), a glove sensor
 *  each (radians), the wrist's position (mm) and rotation (the quaternion as a 4-vector). */
typedef struct fp_pose_filter {
    fp_oneeuro joints[FP_HAND_JOINTS];
    fp_oneeuro angles[FP_GLOVE_SENSORS];
    fp_oneeuro wrist_pos, wrist_rot;
} fp_pose_filter;

/** The pose step's state: both hands, the hand model, the calibration, the filters, and the
 *  poses of the latest fp_pose_build. */
typedef struct fp_pose_state {
    fp_pose_hand hands[FP_HANDS];
    fp_pose_filter filters[FP_POSE_MAX_INPUTS][FP_HANDS];  /* by event source, then hand */
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
 *  is absent until its next event; its earlier samples are forgotten). Other events and
 *  events without a hand are ignored. The event is taken as it is (no filter):
 *  fp_pose_take_event_filtered with NULL. */
void fp_pose_take_event(fp_pose_state *p, const fp_event *ev);

/** fp_pose_take_event through the One Euro filter `filter` (fp_filter.h; NULL or kind
 *  FP_FILTER_OFF: none; FP_FILTER_AUTO: only for an event flagged FP_EVENT_FLAG_UNSMOOTHED)
 *  of the event's input: the state of p->filters[ev->header.source]
 *  [hand] (a source at or beyond FP_POSE_MAX_INPUTS: none), the event's time_ns driving the
 *  filter's rate. Joint positions per joint (mm; a hand's joints sharing one cutoff,
 *  fp_oneeuro_filter_joints), joint angles per valid sensor (radians,
 *  speed counted at FP_FILTER_ARM_MM), a wrist pose's position and rotation (the quaternion
 *  sign-aligned with the last one, renormalised). A DISCONNECTED status resets that input's
 *  filters of the hand. [session-thread]; no allocation. */
void fp_pose_take_event_filtered(fp_pose_state *p, const fp_event *ev, const fp_filter_config *filter);

/** Build p->poses from the hands' latest samples as they are (no resampling): forward
 *  kinematics where only angles came (with the given wrist pose, else the glove placement of
 *  fp_pose_place_gloves, else fp_pose_default_wrist), then the calibration. For a frame,
 *  prefer fp_pose_build_at. poses[h].time_ns is the latest hand event's time. */
void fp_pose_build(fp_pose_state *p);

/** fp_pose_build at the frame's time now_ns (host clock, as the events' times): each kind of
 *  sample (joint positions; joint angles, per sensor valid in both; the wrist pose, its
 *  rotation by normalised linear extrapolation) is taken as x1 + u (x1 - x0) from its last
 *  two samples (x0 at t0, x1 at t1), u = (now_ns - t1) / (t1 - t0) at least -1 (a frame
 *  between them interpolates) and, past FP_POSE_KNEE, FP_POSE_KNEE + (1 - FP_POSE_KNEE)
 *  (1 - e^-(u - FP_POSE_KNEE) / (1 - FP_POSE_KNEE)) (a frame after t1 is predicted less than
 *  one sampling period ahead, and held there as the samples stop); u = 0 where there is no
 *  earlier sample since the hand appeared, or t1 - t0 is not in (0, FP_POSE_MAX_PERIOD_NS]. Deterministic: the same events and frame
 *  times give the same poses bit for bit. poses[h].time_ns stays the latest hand event's
 *  time (a viewer's latency is measured from it). Call once a frame after the events are
 *  taken. [session-thread]. */
void fp_pose_build_at(fp_pose_state *p, int64_t now_ns);

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

/** The rotation c applies, as a unit quaternion w, x, y, z into q: c->rotation normalised;
 *  all zeros, degenerate or not finite: the identity (an unset rotation). Pure; any thread. */
void fp_calibration_rotation(const fp_calibration *c, double q[4]);

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

/** A new calibration c for hands placed as they run (fp_pose_auto.h, step_arrive.h): p->calib
 *  = c, and gloves placed by fp_pose_place_gloves keep their place on the face (their
 *  device-frame wrists move by the offset's change: g' = (s_old g + o_old - o_new) / s_new;
 *  both calibrations without rotation, as fp_pose_fit_workspace makes them). Cannot fail;
 *  no allocation; the thread that owns p (the session thread). */
void fp_pose_recalibrate(fp_pose_state *p, const fp_calibration *c);

/** p_mesh = c->scale * R p_mm + c->offset + c->hand_offset[hand], in double, rounded to
 *  float (hand outside left/right: no hand offset). */
void fp_pose_to_mesh(const fp_calibration *c, int hand, const float mm[3], float out[3]);


#ifdef __cplusplus
}
#endif
#endif
