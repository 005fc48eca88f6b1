/* Step 2 of the frame: hand poses from events, forward kinematics, workspace calibration. */
#include "fp_pose.h"

#include "fp_vec.h"

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
            } else if (p->glove_placed) {
                memcpy(pos, p->glove_pos[h], sizeof pos);
                memcpy(rot, p->glove_rot[h], sizeof rot);
            } else {
                fp_pose_default_wrist(h, pos, rot);
            }
            /* A failure (non-finite angle or pose) leaves the joints it could not compute
             * as they were: the last good pose stays. */
            fp_hand_fk(&p->model, (fp_hand_side)h, hs->angles.radians, hs->angles.valid, pos, rot,
                       hs->joints_mm);
        }
        for (int j = 0; j < FP_HAND_JOINTS; j++) fp_pose_to_mesh(&p->calib, h, hs->joints_mm[j], out->joints[j]);
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

/* The calibration's rotation, normalised; all zeros (or degenerate): the identity. */
static void calib_rotation(const fp_calibration *c, double q[4])
{
    double n = sqrt(c->rotation[0] * c->rotation[0] + c->rotation[1] * c->rotation[1] +
                    c->rotation[2] * c->rotation[2] + c->rotation[3] * c->rotation[3]);
    if (!(n > 1e-12) || !isfinite(n)) {
        q[0] = 1, q[1] = q[2] = q[3] = 0;
        return;
    }
    for (int i = 0; i < 4; i++) q[i] = c->rotation[i] / n;
}

static void qmul(const double a[4], const double b[4], double out[4])
{
    out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    out[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    out[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

void fp_pose_fit_workspace(fp_calibration *c, double mm_per_unit, const float ws_min[3],
                           const float ws_max[3], const float head_min[3], const float head_max[3])
{
    memset(c, 0, sizeof *c);
    if (!(mm_per_unit > 0) || !isfinite(mm_per_unit)) mm_per_unit = 1;
    c->scale = 1.0 / mm_per_unit;
    c->rotation[0] = 1;
    for (int i = 0; i < 2; i++)
        c->offset[i] = 0.5 * ((double)head_min[i] + head_max[i]) - c->scale * 0.5 * ((double)ws_min[i] + ws_max[i]);
    (void)head_min;
    c->offset[2] = ((double)head_max[2] - FP_POSE_REACH_PRESS_MM * c->scale) - c->scale * ws_min[2];
}

void fp_pose_to_mesh(const fp_calibration *c, int hand, const float mm[3], float out[3])
{
    double q[4], v[3] = {mm[0], mm[1], mm[2]}, r[3];
    calib_rotation(c, q);
    if (q[0] == 1) memcpy(r, v, sizeof r);
    else fp_qrot(q, v, r);
    bool h = hand == FP_HAND_LEFT || hand == FP_HAND_RIGHT;
    for (int i = 0; i < 3; i++)
        out[i] = (float)(c->scale * r[i] + c->offset[i] + (h ? c->hand_offset[hand][i] : 0.0));
}

void fp_pose_place_gloves(fp_pose_state *p, const float *pos, size_t n, const fp_head *head)
{
    const fp_calibration *c = &p->calib;
    double s = c->scale > 0 ? c->scale : 1;
    /* Palm toward the face (the back of the hand, +y of the hand frame, toward +z), fingers
     * (-z of the hand frame) up +y: a quarter turn about x. */
    const double qm[4] = {0.70710678118654752440, 0.70710678118654752440, 0, 0};
    const float qf[4] = {(float)qm[0], (float)qm[1], 0.f, 0.f}, zero[3] = {0, 0, 0};
    float cx = 0.5f * (head->min[0] + head->max[0]), cy = 0.5f * (head->min[1] + head->max[1]);
    float w = head->max[0] - head->min[0];
    float r = (float)(15.0 * s), gap = (float)(FP_POSE_GLOVE_GAP_MM * s);
    double q[4], qinv[4];
    calib_rotation(c, q);
    qinv[0] = q[0], qinv[1] = -q[1], qinv[2] = -q[2], qinv[3] = -q[3];
    for (int h = 0; h < FP_HANDS; h++) {
        float j[FP_HAND_JOINTS][3];
        /* The open hand (rest angles) at the origin, mesh axes, mm. */
        if (fp_hand_fk(&p->model, (fp_hand_side)h, NULL, 0, zero, qf, j)) return;
        const float *mid = j[FP_JOINT_TIP(2)];
        float wx = cx + (h == FP_HAND_LEFT ? -0.25f : 0.25f) * w - (float)(s * mid[0]);
        float wy = cy - (float)(s * mid[1]);
        float wz = -INFINITY;
        for (int f = 0; f < FP_FINGERS; f++)
            for (int k = 0; k < 2; k++) {
                int jj = FP_JOINT(f, k ? 3 : 2);
                float x = wx + (float)(s * j[jj][0]), y = wy + (float)(s * j[jj][1]), z;
                if (fp_head_surface_z(pos, n, x, y, r, head->neck_y, INFINITY, &z))
                    wz = fmaxf(wz, z + gap - (float)(s * j[jj][2]));
            }
        if (!isfinite(wz)) wz = head->max[2] + gap;
        /* Back to the device frame: mm = R^-1 (mesh - offset - hand offset) / scale. */
        double m[3] = {wx, wy, wz}, d[3], qd[4];
        for (int i = 0; i < 3; i++) m[i] = (m[i] - c->offset[i] - c->hand_offset[h][i]) / s;
        fp_qrot(qinv, m, d);
        qmul(qinv, qm, qd);
        for (int i = 0; i < 3; i++) p->glove_pos[h][i] = (float)d[i];
        for (int i = 0; i < 4; i++) p->glove_rot[h][i] = (float)qd[i];
    }
    p->glove_placed = true;
}
