/* Step 2 of the frame: hand poses from events, forward kinematics, workspace calibration. */
#include "fp_pose.h"

#include <math.h>
#include <string.h>

void fp_pose_init(fp_pose_state *p, double hand_size, const fp_calibration *c)
{
    memset(p, 0, sizeof *p);
    fp_hand_model_init(&p->model);
    if (hand_size > 0) p->model.size = (float)hand_size;
    if (c) p->calib = *c;
}

void fp_pose_take_event(fp_pose_state *p, const fp_event *ev)
{
    int h = ev->header.hand;
    if (h != FP_HAND_LEFT && h != FP_HAND_RIGHT) return;
    fp_pose_hand *hs = &p->hands[h];
    switch (ev->header.type) {
    case FP_EVENT_JOINT_POSITIONS:
        memcpy(hs->joints_mm, ev->positions.mm, sizeof ev->positions.mm);
        hs->have_positions = hs->present = true;
        hs->time_ns = ev->header.time_ns;
        break;
    case FP_EVENT_JOINT_ANGLES:
        hs->angles = ev->angles;
        hs->have_angles = hs->present = true;
        hs->have_positions = false;
        hs->time_ns = ev->header.time_ns;
        break;
    case FP_EVENT_WRIST_POSE:
        memcpy(hs->wrist_pos, ev->wrist.position_mm, sizeof hs->wrist_pos);
        memcpy(hs->wrist_rot, ev->wrist.rotation, sizeof hs->wrist_rot);
        hs->have_wrist = true;
        break;
    case FP_EVENT_STATUS:
        if (ev->status.code == FP_STATUS_DISCONNECTED) hs->present = false;
        break;
    default:
        break;
    }
}

void fp_pose_default_wrist(int hand, float pos[3], float rot[4])
{
    pos[0] = hand == FP_HAND_LEFT ? -80.f : 80.f;
    pos[1] = 200.f;
    pos[2] = 60.f;
    rot[0] = 1.f;
    rot[1] = rot[2] = rot[3] = 0.f;
}

void fp_pose_build(fp_pose_state *p)
{
    for (int h = 0; h < FP_HANDS; h++) {
        fp_pose_hand *hs = &p->hands[h];
        fp_hand_pose *out = &p->poses[h];
        out->present = hs->present;
        if (!hs->present) continue;
        out->time_ns = hs->time_ns;
        if (!hs->have_positions && hs->have_angles) {
            float pos[3], rot[4];
            if (hs->have_wrist) {
                memcpy(pos, hs->wrist_pos, sizeof pos);
                memcpy(rot, hs->wrist_rot, sizeof rot);
            } else {
                fp_pose_default_wrist(h, pos, rot);
            }
            /* A failure (non-finite angle or pose) leaves the joints it could not compute
             * as they were: the last good pose stays. */
            fp_hand_fk(&p->model, (fp_hand_side)h, hs->angles.radians, hs->angles.valid, pos, rot,
                       hs->joints_mm);
        }
        for (int j = 0; j < FP_HAND_JOINTS; j++) fp_pose_to_mesh(&p->calib, hs->joints_mm[j], out->joints[j]);
    }
}

void fp_pose_default_workspace(float ws_min[3], float ws_max[3])
{
    static const float lo[3] = {-150.f, 80.f, -120.f}, hi[3] = {150.f, 330.f, 120.f};
    memcpy(ws_min, lo, sizeof lo);
    memcpy(ws_max, hi, sizeof hi);
}

bool fp_pose_inputs_workspace(fp_input *const *inputs, size_t n, float ws_min[3], float ws_max[3])
{
    float wmin[3] = {INFINITY, INFINITY, INFINITY}, wmax[3] = {-INFINITY, -INFINITY, -INFINITY};
    bool known = false;
    for (size_t i = 0; i < n; i++) {
        fp_input *in = inputs[i];
        if (!in) continue;
        const fp_input_workspace *ws = in->get_extension ? in->get_extension(in, FP_EXT_WORKSPACE) : NULL;
        float a[3], b[3];
        if (ws && ws->get && ws->get(in, a, b)) {
            known = true;
            for (int k = 0; k < 3; k++) {
                wmin[k] = fminf(wmin[k], a[k]);
                wmax[k] = fmaxf(wmax[k], b[k]);
            }
        }
    }
    if (known) {
        memcpy(ws_min, wmin, sizeof wmin);
        memcpy(ws_max, wmax, sizeof wmax);
    }
    return known;
}

void fp_pose_fit_workspace(fp_calibration *c, const float ws_min[3], const float ws_max[3],
                           const float face_min[3], const float face_max[3])
{
    double ws_w = fmax(ws_max[0] - ws_min[0], 1.0);
    double ws_h = fmax(ws_max[1] - ws_min[1], 1.0);
    double sx = (face_max[0] - face_min[0]) / ws_w, sy = (face_max[1] - face_min[1]) / ws_h;
    c->scale = fmin(sx, sy);
    for (int i = 0; i < 2; i++)
        c->offset[i] = 0.5 * (face_min[i] + face_max[i]) - c->scale * 0.5 * (ws_min[i] + ws_max[i]);
    double depth = face_max[2] - face_min[2];
    c->offset[2] = (face_max[2] - 0.15 * depth) - c->scale * ws_min[2];
}

void fp_pose_to_mesh(const fp_calibration *c, const float mm[3], float out[3])
{
    for (int i = 0; i < 3; i++) out[i] = (float)(c->scale * mm[i] + c->offset[i]);
}
