/* Calibrations from a short recording: hold and touch (fp_calib_fit.h says how). */
#include "fp_calib_fit.h"

#include "fp_error.h"
#include "fp_similarity.h"
#include "fp_vec.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Axis k of joint `joint` over the samples [from, to) of `hand` (-1: any), sorted into v
 * (room for every sample of the hand). Returns how many. */
static size_t joint_axis_sorted(const fp_calib_sample *s, size_t from, size_t to, int hand, int joint,
                                int k, double *v)
{
    size_t c = 0;
    for (size_t i = from; i < to; i++)
        if (hand < 0 || s[i].hand == hand) v[c++] = s[i].joints[joint][k];
    qsort(v, c, sizeof *v, cmp_double);
    return c;
}

/* Per-axis median of joint `joint` over the samples [from, to) of `hand` (-1: any). Returns
 * the number of samples used. */
static size_t median_joint(const fp_calib_sample *s, size_t from, size_t to, int hand, int joint,
                           double out[3])
{
    size_t m = 0;
    for (size_t i = from; i < to; i++) m += hand < 0 || s[i].hand == hand;
    if (!m) return 0;
    double *v = malloc(m * sizeof *v);
    if (!v) return 0;
    for (int k = 0; k < 3; k++) {
        size_t c = joint_axis_sorted(s, from, to, hand, joint, k, v);
        out[k] = c % 2 ? v[c / 2] : 0.5 * (v[c / 2 - 1] + v[c / 2]);
    }
    free(v);
    return m;
}

static void nose_tip(const float *pos, size_t n, const fp_head *head, float out[3])
{
    float best = -INFINITY;
    memset(out, 0, 3 * sizeof *out);
    for (size_t v = 0; v < n; v++)
        if (pos[3 * v + 1] >= head->neck_y && pos[3 * v + 2] > best) {
            best = pos[3 * v + 2];
            memcpy(out, pos + 3 * v, 3 * sizeof *out);
        }
}

void fp_calib_hold_target(const float *pos, size_t n, const fp_head *head, int hand, float out[3])
{
    float nose[3];
    nose_tip(pos, n, head, nose);
    float w = head->max[0] - head->min[0], cx = 0.5f * (head->min[0] + head->max[0]);
    float r = (float)(15.0 / (head->mm_per_unit > 0 ? head->mm_per_unit : 1));
    out[0] = cx + (hand == FP_HAND_LEFT ? -0.25f : 0.25f) * w;
    out[1] = nose[1];
    if (!fp_head_surface_z(pos, n, out[0], out[1], r, head->neck_y, INFINITY, &out[2])) out[2] = head->max[2];
}

void fp_calib_hold_travel(const fp_calib_sample *samples, size_t n, double travel[FP_HANDS])
{
    for (int h = 0; h < FP_HANDS; h++) {
        travel[h] = 0;
        size_t m = 0;
        for (size_t i = 0; samples && i < n; i++) m += samples[i].hand == h;
        if (m < 3) continue;
        double *v = malloc(m * sizeof *v), q = 0;
        if (!v) continue;
        for (int k = 0; k < 3; k++) {
            size_t c = joint_axis_sorted(samples, 0, n, h, FP_JOINT_PALM, k, v);
            assert(c == m);
            double lo = v[(size_t)floor(0.02 * (double)(c - 1))], hi = v[(size_t)ceil(0.98 * (double)(c - 1))];
            q += (hi - lo) * (hi - lo);
        }
        travel[h] = sqrt(q);
        free(v);
    }
}

int fp_calib_fit_hold(const fp_calib_sample *samples, size_t n, const float *pos, size_t nv,
                      const fp_head *head, fp_calibration *out, char *err, size_t errlen)
{
    if (!samples || !pos || !head || !out) return fp_errorf(err, errlen, -EINVAL, "calibrate: NULL argument");
    double s = 1.0 / (head->mm_per_unit > 0 ? head->mm_per_unit : 1);
    double off[FP_HANDS][3];
    bool have[FP_HANDS] = {false, false};
    for (int h = 0; h < FP_HANDS; h++) {
        double palm[3];
        if (median_joint(samples, 0, n, h, FP_JOINT_PALM, palm) < 3) continue;
        float target[3];
        fp_calib_hold_target(pos, nv, head, h, target);
        for (int k = 0; k < 3; k++) off[h][k] = target[k] - s * palm[k];
        have[h] = true;
    }
    if (!have[0] && !have[1])
        return fp_errorf(err, errlen, -EINVAL, "calibrate: no hand held still: %zu sample(s) of joint "
                         "positions (hold mode needs a tracker's palm positions)", n);
    memset(out, 0, sizeof *out);
    out->scale = s;
    out->rotation[0] = 1;
    for (int k = 0; k < 3; k++) {
        out->offset[k] = have[0] && have[1] ? 0.5 * (off[0][k] + off[1][k]) : have[0] ? off[0][k] : off[1][k];
        for (int h = 0; h < FP_HANDS; h++) out->hand_offset[h][k] = have[h] ? off[h][k] - out->offset[k] : 0;
    }
    return 0;
}

void fp_calib_head_landmarks(const float *pos, size_t n, const fp_head *head,
                             float out[FP_CALIB_LANDMARKS][3])
{
    float nose[3];
    nose_tip(pos, n, head, nose);
    memcpy(out[FP_CALIB_NOSE_TIP], nose, sizeof nose);
    double cm = 10.0 / (head->mm_per_unit > 0 ? head->mm_per_unit : 1);
    float y_hi = head->neck_y + 0.25f * (nose[1] - head->neck_y), best = -INFINITY;
    memcpy(out[FP_CALIB_CHIN], nose, sizeof nose);
    out[FP_CALIB_CHIN][1] = head->neck_y;
    for (size_t v = 0; v < n; v++) {
        const float *p = pos + 3 * v;
        if (p[1] < head->neck_y || p[1] > y_hi || fabs(p[0] - nose[0]) > cm || p[2] <= best) continue;
        best = p[2];
        memcpy(out[FP_CALIB_CHIN], p, 3 * sizeof *p);
    }
    float *fh = out[FP_CALIB_FOREHEAD];
    fh[0] = nose[0];
    fh[1] = nose[1] + 0.45f * (head->max[1] - nose[1]);
    if (!fp_head_surface_z(pos, n, fh[0], fh[1], (float)(1.5 * cm), head->neck_y, INFINITY, &fh[2]))
        fh[2] = nose[2];
}

typedef struct still { size_t from, to; int64_t t0, t1; } still;

static int by_length(const void *a, const void *b)
{
    const still *x = a, *y = b;
    int64_t lx = x->t1 - x->t0, ly = y->t1 - y->t0;
    return (lx < ly) - (lx > ly);
}

static int by_start(const void *a, const void *b)
{
    const still *x = a, *y = b;
    return (x->t0 > y->t0) - (x->t0 < y->t0);
}

int fp_calib_find_touches(const fp_calib_sample *samples, size_t n, int finger,
                          double touched[FP_CALIB_LANDMARKS][3], int64_t t_ns[FP_CALIB_LANDMARKS][2],
                          char *err, size_t errlen)
{
    size_t count[FP_HANDS] = {0, 0};
    for (size_t i = 0; i < n; i++)
        if (samples[i].hand == FP_HAND_LEFT || samples[i].hand == FP_HAND_RIGHT) count[samples[i].hand]++;
    int hand = count[1] > count[0] ? 1 : 0;
    if (!count[hand]) return fp_errorf(err, errlen, -EINVAL, "calibrate: no hand samples");
    /* This hand's samples, in order. */
    fp_calib_sample *h = malloc(count[hand] * sizeof *h);
    still *st = malloc(count[hand] * sizeof *st);
    if (!h || !st) {
        free(h);
        free(st);
        return fp_errorf(err, errlen, -ENOMEM, "calibrate: out of memory");
    }
    size_t m = 0, ns = 0;
    for (size_t i = 0; i < n; i++)
        if (samples[i].hand == hand) h[m++] = samples[i];
    int joint = FP_JOINT_TIP(finger);
    for (size_t i = 0; i < m;) {
        const float *a = h[i].joints[joint];
        size_t j = i + 1;
        while (j < m) {
            const float *p = h[j].joints[joint];
            double d = sqrt(pow(p[0] - a[0], 2) + pow(p[1] - a[1], 2) + pow(p[2] - a[2], 2));
            if (!(d < FP_CALIB_STILL_MM)) break;
            j++;
        }
        if ((double)(h[j - 1].t_ns - h[i].t_ns) >= FP_CALIB_MIN_STILL_S * 1e9) {
            st[ns++] = (still){i, j, h[i].t_ns, h[j - 1].t_ns};
            i = j;
        } else {
            i++;
        }
    }
    int rc = 0;
    if (ns < FP_CALIB_LANDMARKS) {
        rc = fp_errorf(err, errlen, -EDOM, "calibrate: found %zu still moment(s) of the %s hand's "
                       "fingertip (at least %.2f s within %.0f mm), need 3: touch chin, nose tip and "
                       "forehead in turn, holding each", ns, hand ? "right" : "left",
                       FP_CALIB_MIN_STILL_S, FP_CALIB_STILL_MM);
    } else {
        qsort(st, ns, sizeof *st, by_length);
        qsort(st, FP_CALIB_LANDMARKS, sizeof *st, by_start);
        for (int k = 0; k < FP_CALIB_LANDMARKS; k++) {
            median_joint(h, st[k].from, st[k].to, hand, joint, touched[k]);
            if (t_ns) t_ns[k][0] = st[k].t0, t_ns[k][1] = st[k].t1;
        }
    }
    free(h);
    free(st);
    return rc;
}

int fp_calib_fit_touch(const fp_calib_sample *samples, size_t n,
                       const float landmarks[FP_CALIB_LANDMARKS][3], fp_calibration *out,
                       double touched[FP_CALIB_LANDMARKS][3], double *rms, char *err, size_t errlen)
{
    if (!samples || !landmarks || !out) return fp_errorf(err, errlen, -EINVAL, "calibrate: NULL argument");
    double a[FP_CALIB_LANDMARKS][3], b[FP_CALIB_LANDMARKS][3];
    int rc = fp_calib_find_touches(samples, n, 1, a, NULL, err, errlen);
    if (rc) return rc;
    for (int i = 0; i < FP_CALIB_LANDMARKS; i++)
        for (int k = 0; k < 3; k++) b[i][k] = landmarks[i][k];
    for (int i = 0; i < FP_CALIB_LANDMARKS; i++)
        for (int j = i + 1; j < FP_CALIB_LANDMARKS; j++) {
            double d = sqrt(pow(a[i][0] - a[j][0], 2) + pow(a[i][1] - a[j][1], 2) + pow(a[i][2] - a[j][2], 2));
            if (d < FP_CALIB_MIN_APART_MM)
                return fp_errorf(err, errlen, -EDOM, "calibrate: touches %d and %d are %.3g mm apart "
                                 "(under %.0f mm): touch chin, nose tip and forehead in turn",
                                 i + 1, j + 1, d, FP_CALIB_MIN_APART_MM);
        }
    double s, q[4], t[3];
    if (fp_similarity_fit((const double (*)[3])a, (const double (*)[3])b, FP_CALIB_LANDMARKS, &s, q, t))
        return fp_errorf(err, errlen, -EDOM, "calibrate: the three touches (%.4g %.4g %.4g), (%.4g %.4g "
                         "%.4g), (%.4g %.4g %.4g) mm lie on a line: touch chin, nose tip and forehead",
                         a[0][0], a[0][1], a[0][2], a[1][0], a[1][1], a[1][2], a[2][0], a[2][1], a[2][2]);
    double e = 0;
    for (int i = 0; i < FP_CALIB_LANDMARKS; i++) {
        double r[3];
        fp_qrot(q, a[i], r);
        for (int k = 0; k < 3; k++) e += pow(s * r[k] + t[k] - b[i][k], 2);
    }
    e = sqrt(e / FP_CALIB_LANDMARKS);
    if (e / s > FP_CALIB_MAX_RESIDUAL_MM)
        return fp_errorf(err, errlen, -EDOM, "calibrate: the touches do not have the shape of chin, "
                         "nose tip and forehead (residual %.4g mm, over %.0f mm)", e / s,
                         FP_CALIB_MAX_RESIDUAL_MM);
    memset(out, 0, sizeof *out);
    out->scale = s;
    memcpy(out->rotation, q, sizeof out->rotation);
    memcpy(out->offset, t, sizeof out->offset);
    if (touched) memcpy(touched, a, sizeof a);
    if (rms) *rms = e;
    return 0;
}
