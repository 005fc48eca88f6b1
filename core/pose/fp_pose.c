/* Step 2 of the frame: hand poses from events (filtered, at the frame's time), forward
 * kinematics, workspace calibration. */
#include "fp_pose.h"

#include "fp_vec.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <string.h>

void fp_pose_init(fp_pose_state *p, double hand_size, const fp_calibration *c)
{
    memset(p, 0, sizeof *p);
    fp_hand_model_init(&p->model);
    if (hand_size > 0) p->model.size = (float)hand_size;
    if (c) p->calib = *c;
}

/* The filter state of the event's input for hand h, or NULL where none applies. */
static fp_pose_filter *filter_state(fp_pose_state *p, const fp_event *ev, int h, const fp_filter_config *c)
{
    if (!c || c->kind == FP_FILTER_OFF || ev->header.source >= FP_POSE_MAX_INPUTS) return NULL;
    if (c->kind == FP_FILTER_AUTO && !(ev->header.flags & FP_EVENT_FLAG_UNSMOOTHED)) return NULL;
    return &p->filters[ev->header.source][h];
}

static void take_positions(fp_pose_hand *hs, fp_pose_filter *fs, const fp_filter_config *c,
                           const fp_event_joint_positions *e)
{
    hs->prev_positions = hs->have_positions;
    memcpy(hs->prev_joints_mm, hs->joints_mm, sizeof hs->joints_mm);
    hs->prev_joints_t_ns = hs->joints_t_ns;
    double x[FP_HAND_JOINTS][3];
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++) x[j][k] = e->mm[j][k];
    if (fs) fp_oneeuro_filter_joints(fs->joints, FP_HAND_JOINTS, c, x, e->header.time_ns);
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++) hs->joints_mm[j][k] = (float)x[j][k];
    hs->joints_t_ns = e->header.time_ns;
}

/* Whether points b (at tb) jumped from a (at ta), n of them: FP_POSE_JUMP_MM and
 * FP_POSE_JUMP_MM_S. */
static bool jumped(const float (*a)[3], int64_t ta, const float (*b)[3], int64_t tb, int n)
{
    double step = 0;
    for (int j = 0; j < n; j++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) d2 += ((double)b[j][k] - a[j][k]) * ((double)b[j][k] - a[j][k]);
        if (d2 > step) step = d2;
    }
    step = sqrt(step);
    double dt = tb > ta ? (double)(tb - ta) * 1e-9 : 0.0;
    return step > FP_POSE_JUMP_MM && step > FP_POSE_JUMP_MM_S * dt;
}

/* Forget hand h's motion so far (a disconnect, or the hand found elsewhere): no motion is
 * guessed across the gap (the next sample has no earlier one: frame_fraction), the input's
 * filter of the hand starts afresh. */
static void hand_afresh(fp_pose_state *p, fp_pose_hand *hs, int h, uint32_t source)
{
    hs->prev_positions = hs->prev_angles = hs->prev_wrist = false;
    hs->joints_t_ns = hs->angles_t_ns = hs->wrist_t_ns = INT64_MIN;
    hs->joint_jumps.pending = hs->wrist_jumps.pending = false;
    if (source < FP_POSE_MAX_INPUTS) memset(&p->filters[source][h], 0, sizeof p->filters[0][0]);
}

/* The jump rule (FP_POSE_JUMP_MM) on sample x (n points, at t, from `source`) of stream j,
 * whose latest taken sample is at last_t (INT64_MIN: none, nothing to jump from): true where
 * x is to be taken (and then kept in j->raw). */
static bool jump_rule(fp_pose_state *p, fp_pose_hand *hs, int h, uint32_t source, fp_pose_jumps *j,
                      const float (*x)[3], int n, int64_t t, int64_t last_t)
{
    assert(n >= 1 && n <= FP_HAND_JOINTS);
    const int64_t seen = j->seen_t_ns;
    j->seen_t_ns = t;
    if (last_t == INT64_MIN || !jumped((const float (*)[3])j->raw, seen > last_t ? seen : last_t, x, t, n)) {
        hs->glitches += j->pending; /* (a held sample was a glitch) */
        j->pending = false;
    } else if (j->pending && !jumped((const float (*)[3])j->held, j->held_t_ns, x, t, n)) {
        hand_afresh(p, hs, h, source); /* found elsewhere */
        hs->absent_until_ns = t + FP_POSE_JUMP_ABSENT_NS;
        hs->jumps++;
    } else { /* held back: the next sample decides */
        j->pending = true;
        memcpy(j->held, x, (size_t)n * sizeof x[0]);
        j->held_t_ns = t;
        return false;
    }
    memcpy(j->raw, x, (size_t)n * sizeof x[0]);
    return true;
}

static void take_angles(fp_pose_hand *hs, fp_pose_filter *fs, const fp_filter_config *c,
                        const fp_event_joint_angles *e)
{
    hs->prev_angles = hs->have_angles;
    memcpy(hs->prev_radians, hs->angles.radians, sizeof hs->prev_radians);
    hs->prev_valid = hs->angles.valid;
    hs->prev_angles_t_ns = hs->angles_t_ns;
    hs->angles = *e;
    for (int i = 0; i < FP_GLOVE_SENSORS && fs; i++) {
        if (!(e->valid & (1u << i))) {
            fp_oneeuro_reset(&fs->angles[i]); /* a sensor coming back starts afresh */
            continue;
        }
        double x = e->radians[i];
        fp_oneeuro_filter(&fs->angles[i], c, 1, FP_FILTER_ARM_MM, &x, e->header.time_ns, &x);
        hs->angles.radians[i] = (float)x;
    }
    hs->angles_t_ns = e->header.time_ns;
}

static void take_wrist(fp_pose_hand *hs, fp_pose_filter *fs, const fp_filter_config *c,
                       const fp_event_wrist_pose *e)
{
    hs->prev_wrist = hs->have_wrist;
    memcpy(hs->prev_wrist_pos, hs->wrist_pos, sizeof hs->wrist_pos);
    memcpy(hs->prev_wrist_rot, hs->wrist_rot, sizeof hs->wrist_rot);
    hs->prev_wrist_t_ns = hs->wrist_t_ns;
    double pos[3] = {e->position_mm[0], e->position_mm[1], e->position_mm[2]};
    double q[4] = {e->rotation[0], e->rotation[1], e->rotation[2], e->rotation[3]};
    if (fs) {
        /* q and -q are one rotation: the one nearer the filter's, so that it averages the
         * rotation, not the sign */
        if (fs->wrist_rot.started &&
            q[0] * fs->wrist_rot.x[0] + q[1] * fs->wrist_rot.x[1] + q[2] * fs->wrist_rot.x[2] + q[3] * fs->wrist_rot.x[3] < 0)
            for (int k = 0; k < 4; k++) q[k] = -q[k];
        fp_oneeuro_filter(&fs->wrist_pos, c, 3, 1.0, pos, e->header.time_ns, pos);
        /* |dq/dt| is half the angular speed */
        fp_oneeuro_filter(&fs->wrist_rot, c, 4, 2 * FP_FILTER_ARM_MM, q, e->header.time_ns, q);
        double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (n > 1e-12 && isfinite(n))
            for (int k = 0; k < 4; k++) q[k] /= n;
    }
    for (int k = 0; k < 3; k++) hs->wrist_pos[k] = (float)pos[k];
    for (int k = 0; k < 4; k++) hs->wrist_rot[k] = (float)q[k];
    hs->wrist_t_ns = e->header.time_ns;
}

void fp_pose_take_event_filtered(fp_pose_state *p, const fp_event *ev, const fp_filter_config *filter)
{
    int h = ev->header.hand;
    if (h != FP_HAND_LEFT && h != FP_HAND_RIGHT) return;
    fp_pose_hand *hs = &p->hands[h];
    fp_pose_filter *fs = filter_state(p, ev, h, filter);
    switch (ev->header.type) {
    case FP_EVENT_JOINT_POSITIONS:
        if (!jump_rule(p, hs, h, ev->header.source, &hs->joint_jumps, ev->positions.mm, FP_HAND_JOINTS,
                       ev->header.time_ns, hs->present && hs->have_positions ? hs->joints_t_ns : INT64_MIN))
            break;
        take_positions(hs, fs, filter, &ev->positions);
        hs->have_positions = hs->present = true;
        hs->time_ns = ev->header.time_ns;
        break;
    case FP_EVENT_JOINT_ANGLES:
        take_angles(hs, fs, filter, &ev->angles);
        hs->have_angles = hs->present = true;
        hs->have_positions = false;
        hs->time_ns = ev->header.time_ns;
        break;
    case FP_EVENT_WRIST_POSE:
        if (!jump_rule(p, hs, h, ev->header.source, &hs->wrist_jumps, (const float (*)[3])ev->wrist.position_mm, 1,
                       ev->header.time_ns, hs->have_wrist ? hs->wrist_t_ns : INT64_MIN))
            break;
        take_wrist(hs, fs, filter, &ev->wrist);
        hs->have_wrist = true;
        break;
    case FP_EVENT_STATUS:
        if (ev->status.code == FP_STATUS_DISCONNECTED) {
            hs->present = false;
            hand_afresh(p, hs, h, ev->header.source);
        }
        break;
    default:
        break;
    }
}

void fp_pose_take_event(fp_pose_state *p, const fp_event *ev) { fp_pose_take_event_filtered(p, ev, NULL); }

void fp_pose_default_wrist(int hand, float pos[3], float rot[4])
{
    pos[0] = hand == FP_HAND_LEFT ? -80.f : 80.f;
    pos[1] = 200.f;
    pos[2] = 60.f;
    rot[0] = 1.f;
    rot[1] = rot[2] = rot[3] = 0.f;
}

/* How far the frame at now is past the latest sample t1, in periods t1 - t0, within [-1, 1]
 * (fp_pose_build_at): u = (now - t1) / (t1 - t0) down to -1 (interpolation), and ahead up to
 * FP_POSE_KNEE as it is, then bent smoothly toward 1 (FP_POSE_KNEE + (1 - FP_POSE_KNEE)
 * (1 - e^-(u - FP_POSE_KNEE) / (1 - FP_POSE_KNEE)): same value and slope at the knee), so
 * that the prediction never reaches a whole period ahead and yet two frames in a gap of the
 * tracker (a dropped sample) still differ (1 itself only in the limit: long after, or a
 * now - t1 beyond int64); 0 without an earlier sample (t0 INT64_MIN: none
 * since a disconnect), or when the period is not in (0, FP_POSE_MAX_PERIOD_NS]. */
static double frame_fraction(bool have_prev, int64_t t0, int64_t t1, int64_t now)
{
    if (!have_prev || t0 == INT64_MIN || t1 <= t0) return 0;
    uint64_t period = (uint64_t)t1 - (uint64_t)t0; /* (no overflow, whatever the stamps) */
    if (period > (uint64_t)FP_POSE_MAX_PERIOD_NS) return 0;
    int64_t d;
    if (__builtin_sub_overflow(now, t1, &d)) return now > t1 ? 1 : -1;
    double u = (double)d / (double)period;
    if (u < -1) return -1;
    if (u <= FP_POSE_KNEE) return u;
    const double k = 1 - FP_POSE_KNEE;
    return FP_POSE_KNEE + k * -expm1(-(u - FP_POSE_KNEE) / k);
}

/* x1 + u (x1 - x0), in double, rounded to float. */
static float ahead(float x0, float x1, double u)
{
    return (float)((double)x1 + u * ((double)x1 - (double)x0));
}

static void build(fp_pose_state *p, bool at, int64_t now_ns)
{
    for (int h = 0; h < FP_HANDS; h++) {
        fp_pose_hand *hs = &p->hands[h];
        fp_hand_pose *out = &p->poses[h];
        /* a hand found elsewhere is absent a moment; one held back too long is absent */
        out->present = hs->present &&
                       !(at && (now_ns < hs->absent_until_ns ||
                                (hs->joint_jumps.pending && now_ns - hs->joints_t_ns > FP_POSE_MAX_PERIOD_NS) ||
                                (hs->wrist_jumps.pending && now_ns - hs->wrist_t_ns > FP_POSE_MAX_PERIOD_NS)));
        if (!out->present) continue;
        out->time_ns = hs->time_ns;
        if (hs->have_positions) {
            double u = at ? frame_fraction(hs->prev_positions, hs->prev_joints_t_ns, hs->joints_t_ns, now_ns) : 0;
            for (int j = 0; j < FP_HAND_JOINTS; j++)
                for (int k = 0; k < 3; k++)
                    hs->built_mm[j][k] = u == 0 ? hs->joints_mm[j][k] : ahead(hs->prev_joints_mm[j][k], hs->joints_mm[j][k], u);
        } else if (hs->have_angles) {
            float pos[3], rot[4], rad[FP_GLOVE_SENSORS];
            memcpy(rad, hs->angles.radians, sizeof rad);
            double u = at ? frame_fraction(hs->prev_angles, hs->prev_angles_t_ns, hs->angles_t_ns, now_ns) : 0;
            if (u != 0)
                for (int i = 0; i < FP_GLOVE_SENSORS; i++)
                    if (hs->angles.valid & hs->prev_valid & (1u << i)) rad[i] = ahead(hs->prev_radians[i], rad[i], u);
            if (hs->have_wrist) {
                memcpy(pos, hs->wrist_pos, sizeof pos);
                memcpy(rot, hs->wrist_rot, sizeof rot);
                double w = at ? frame_fraction(hs->prev_wrist, hs->prev_wrist_t_ns, hs->wrist_t_ns, now_ns) : 0;
                if (w != 0) {
                    float q0[4];
                    double d = 0, n = 0;
                    memcpy(q0, hs->prev_wrist_rot, sizeof q0);
                    for (int k = 0; k < 4; k++) d += (double)q0[k] * rot[k];
                    for (int k = 0; k < 4 && d < 0; k++) q0[k] = -q0[k];
                    for (int k = 0; k < 3; k++) pos[k] = ahead(hs->prev_wrist_pos[k], pos[k], w);
                    double q[4];
                    for (int k = 0; k < 4; k++) q[k] = (double)rot[k] + w * ((double)rot[k] - q0[k]), n += q[k] * q[k];
                    n = sqrt(n);
                    if (n > 1e-12 && isfinite(n))
                        for (int k = 0; k < 4; k++) rot[k] = (float)(q[k] / n);
                }
            } else if (p->glove_placed) {
                memcpy(pos, p->glove_pos[h], sizeof pos);
                memcpy(rot, p->glove_rot[h], sizeof rot);
            } else {
                fp_pose_default_wrist(h, pos, rot);
            }
            /* A failure (non-finite angle or pose) leaves the joints it could not compute
             * as they were: the last good pose stays. */
            fp_hand_fk(&p->model, (fp_hand_side)h, rad, hs->angles.valid, pos, rot, hs->built_mm);
        }
        for (int j = 0; j < FP_HAND_JOINTS; j++) fp_pose_to_mesh(&p->calib, h, hs->built_mm[j], out->joints[j]);
    }
}

void fp_pose_build(fp_pose_state *p) { build(p, false, 0); }

void fp_pose_build_at(fp_pose_state *p, int64_t now_ns) { build(p, true, now_ns); }

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

void fp_calibration_rotation(const fp_calibration *c, double q[4])
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

/* c's face frame as a unit quaternion; false: none (all zeros, the identity or not finite) */
static bool face_frame(const fp_calibration *c, double f[4])
{
    double n = sqrt(c->face[0] * c->face[0] + c->face[1] * c->face[1] + c->face[2] * c->face[2] +
                    c->face[3] * c->face[3]);
    if (!(n > 1e-12) || !isfinite(n)) return false;
    for (int i = 0; i < 4; i++) f[i] = c->face[i] / n;
    return !(f[0] == 1 && f[1] == 0 && f[2] == 0 && f[3] == 0);
}

void fp_pose_to_mesh(const fp_calibration *c, int hand, const float mm[3], float out[3])
{
    double q[4], v[3] = {mm[0], mm[1], mm[2]}, r[3], f[4];
    fp_calibration_rotation(c, q);
    if (q[0] == 1) memcpy(r, v, sizeof r);
    else fp_qrot(q, v, r);
    bool h = hand == FP_HAND_LEFT || hand == FP_HAND_RIGHT;
    if (face_frame(c, f)) { /* in the face's frame, then turned into the mesh's */
        double a[3], b[3];
        for (int i = 0; i < 3; i++) a[i] = c->scale * r[i] + c->offset[i] + (h ? c->hand_offset[hand][i] : 0.0);
        fp_qrot(f, a, b);
        for (int i = 0; i < 3; i++) out[i] = (float)b[i];
        return;
    }
    for (int i = 0; i < 3; i++)
        out[i] = (float)(c->scale * r[i] + c->offset[i] + (h ? c->hand_offset[hand][i] : 0.0));
}

bool fp_calibration_has_face(const fp_calibration *c)
{
    double f[4];
    return face_frame(c, f);
}

bool fp_face_turned(const double q[4])
{
    return fabs(q[0]) < cos(0.5 * FP_FACE_TURNED_DEG * 3.14159265358979323846 / 180); /* (w = cos(angle / 2)) */
}

int fp_face_from_axes(const float up[3], const float facing[3], double q[4])
{
    double u[3] = {up[0], up[1], up[2]}, f[3] = {facing[0], facing[1], facing[2]}, l[3];
    if (fabs(fp_dot3(u, u) - 1) > 1e-3 || fabs(fp_dot3(f, f) - 1) > 1e-3 || fabs(fp_dot3(u, f)) > 1e-3)
        return -EINVAL;
    fp_cross3(u, f, l);
    fp_quat_from_axes(l, u, f, q);
    return 0;
}

void fp_calibration_flatten(const fp_calibration *c, fp_calibration *out)
{
    double f[4];
    if (!face_frame(c, f)) {
        if (out != c) *out = *c;
        memset(out->face, 0, sizeof out->face);
        return;
    }
    fp_calibration r = *c;
    double q[4], fq[4], v[3];
    fp_calibration_rotation(c, q);
    qmul(f, q, fq);
    memcpy(r.rotation, fq, sizeof fq);
    memcpy(v, c->offset, sizeof v);
    fp_qrot(f, v, r.offset);
    for (int h = 0; h < FP_HANDS; h++) {
        memcpy(v, c->hand_offset[h], sizeof v);
        fp_qrot(f, v, r.hand_offset[h]);
    }
    memset(r.face, 0, sizeof r.face);
    *out = r;
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
    fp_calibration_rotation(c, q);
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

void fp_pose_recalibrate(fp_pose_state *p, const fp_calibration *c)
{
    fp_calibration old = p->calib;
    p->calib = *c;
    if (!p->glove_placed || !(old.scale > 0) || !(c->scale > 0)) return;
    for (int h = 0; h < FP_HANDS; h++)
        for (int i = 0; i < 3; i++) {
            double m = old.scale * p->glove_pos[h][i] + old.offset[i] + old.hand_offset[h][i];
            p->glove_pos[h][i] = (float)((m - c->offset[i] - c->hand_offset[h][i]) / c->scale);
        }
}
