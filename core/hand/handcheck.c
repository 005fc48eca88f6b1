/*
 * handcheck.c: fingertip check of fp_hand_fk against the Leap recordings (handcheck.h).
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "handcheck.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "leapcsv.h"

#define DEG2RAD (3.14159265358979323846 / 180.0)

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

float fp_handcheck_quantile(float *v, size_t n, double q)
{
    if (!n)
        return NAN;
    qsort(v, n, sizeof *v, cmp_float);
    double pos = q * (double)(n - 1);
    size_t i = (size_t)pos;
    if (i + 1 >= n)
        return v[n - 1];
    double t = pos - (double)i;
    return (float)(v[i] * (1 - t) + v[i + 1] * t);
}

static float dist3(const float a[3], const float b[3])
{
    double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
    return (float)sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

/* Leap joints of rows idx[0..n) into the hand frame of `model`. */
static int to_hand_frames(const fp_hand_model *model, const fp_leap_joints_row *rows,
                          const size_t *idx, size_t n, float (*hand)[FP_HAND_JOINTS][3])
{
    for (size_t i = 0; i < n; i++) {
        const fp_leap_joints_row *r = &rows[idx[i]];
        float pos[3], rot[4];
        int rc = fp_hand_frame_from_palm(model, r->side, r->palm_mm, r->normal, r->direction, pos, rot);
        if (!rc)
            rc = fp_hand_to_hand_frame(pos, rot, (const float(*)[3])r->joints_mm, FP_HAND_JOINTS, hand[i]);
        if (rc)
            return rc;
    }
    return 0;
}

static int check_hand(const fp_leap_joints_row *jr, const size_t *idx, size_t n,
                      const fp_leap_angles_row *ar, size_t na, const fp_handcheck_options *opt,
                      const char *joints_csv, const char *angles_csv, fp_handcheck_hand *out,
                      char *err, size_t errlen)
{
    int rc = 0;
    float(*hand)[FP_HAND_JOINTS][3] = malloc(n * sizeof *hand);
    float *e = malloc(n * FP_FINGERS * sizeof *e);
    float *ef = malloc(n * sizeof *ef);
    size_t *match = malloc(n * sizeof *match);
    if (!hand || !e || !ef || !match) {
        snprintf(err, errlen, "out of memory");
        rc = -3;
        goto done;
    }
    /* Match angle rows on frame + hand_id, searching on from the last match. */
    size_t hint = 0;
    for (size_t i = 0; i < n; i++) {
        const fp_leap_joints_row *r = &jr[idx[i]];
        size_t k, found = na;
        for (k = 0; k < na; k++) {
            size_t c = (hint + k) % na;
            if (ar[c].frame == r->frame && ar[c].hand_id == r->hand_id) {
                found = c;
                break;
            }
        }
        if (found == na) {
            snprintf(err, errlen, "%s: no row for frame %ld, hand_id %ld of %s", angles_csv,
                     r->frame, r->hand_id, joints_csv);
            rc = -2;
            goto done;
        }
        if (ar[found].side != r->side) {
            snprintf(err, errlen, "%s: frame %ld, hand_id %ld: hand_type differs from %s",
                     angles_csv, r->frame, r->hand_id, joints_csv);
            rc = -2;
            goto done;
        }
        match[i] = found;
        hint = found + 1;
    }

    fp_hand_side side = jr[idx[0]].side;
    fp_hand_model m;
    fp_hand_model_init(&m);
    m.tip_pad = opt->tip_pad;
    if (opt->fit != FP_HANDCHECK_FIT_NONE) {
        if ((rc = to_hand_frames(&m, jr, idx, n, hand)))
            goto model_error;
        if (opt->fit == FP_HANDCHECK_FIT_GEOMETRY)
            rc = fp_hand_fit_geometry(&m, side, (const float(*)[FP_HAND_JOINTS][3])hand, n);
        else
            rc = fp_hand_fit_size(&m, (const float(*)[FP_HAND_JOINTS][3])hand, n, &m.size);
        if (rc)
            goto model_error;
    }
    if ((rc = to_hand_frames(&m, jr, idx, n, hand)))
        goto model_error;

    for (size_t i = 0; i < n; i++) {
        const fp_leap_angles_row *a = &ar[match[i]];
        float rad[FP_GLOVE_SENSORS], fk[FP_HAND_JOINTS][3];
        for (int s = 0; s < FP_GLOVE_SENSORS; s++)
            rad[s] = (float)(a->degrees[s] * DEG2RAD);
        if ((rc = fp_hand_fk(&m, side, rad, a->valid, NULL, NULL, fk)))
            goto model_error;
        for (int f = 0; f < FP_FINGERS; f++)
            e[f * n + i] = dist3(fk[FP_JOINT_TIP(f)], hand[i][FP_JOINT_TIP(f)]);
        /* Round trip through the position path on the Leap joints themselves. */
        fp_hand_angles ha;
        float rt[FP_HAND_JOINTS][3];
        if ((rc = fp_hand_from_positions(&m, side, (const float(*)[3])hand[i], &ha)) ||
            (rc = fp_hand_fk(&m, side, ha.radians, ha.valid, ha.wrist_pos_mm, ha.wrist_rot_wxyz, rt)))
            goto model_error;
        float tips[FP_FINGERS];
        for (int f = 0; f < FP_FINGERS; f++)
            tips[f] = dist3(rt[FP_JOINT_TIP(f)], hand[i][FP_JOINT_TIP(f)]);
        ef[i] = fp_handcheck_quantile(tips, FP_FINGERS, 0.5);
    }
    memset(out, 0, sizeof *out);
    out->hand_id = jr[idx[0]].hand_id;
    out->side = side;
    out->frames = n;
    out->model = m;
    for (int f = 0; f < FP_FINGERS; f++) {
        out->median_mm[f] = fp_handcheck_quantile(e + f * n, n, 0.5);
        out->p90_mm[f] = fp_handcheck_quantile(e + f * n, n, 0.9);
    }
    out->median_all_mm = fp_handcheck_quantile(e, n * FP_FINGERS, 0.5);
    out->p90_all_mm = fp_handcheck_quantile(e, n * FP_FINGERS, 0.9);
    out->roundtrip_median_mm = fp_handcheck_quantile(ef, n, 0.5);
    goto done;
model_error:
    snprintf(err, errlen, "%s: hand_id %ld: %s", joints_csv, jr[idx[0]].hand_id, fp_hand_strerror(rc));
done:
    free(hand);
    free(e);
    free(ef);
    free(match);
    return rc;
}

int fp_handcheck_recording(const char *joints_csv, const char *angles_csv,
                           const fp_handcheck_options *opt, fp_handcheck_hand *out, size_t cap,
                           size_t *nout, char *err, size_t errlen)
{
    static const fp_handcheck_options defaults = {0};
    char dummy[8];
    if (!err || !errlen)
        err = dummy, errlen = sizeof dummy;
    if (!joints_csv || !angles_csv || (cap && !out) || !nout) {
        snprintf(err, errlen, "fp_handcheck_recording: NULL argument");
        return -1;
    }
    if (!opt)
        opt = &defaults;
    fp_leap_joints_row *jr = NULL;
    fp_leap_angles_row *ar = NULL;
    size_t nj = 0, na = 0, *idx = NULL, hands = 0;
    int rc = fp_leapcsv_read_joints(joints_csv, &jr, &nj, err, errlen);
    if (!rc)
        rc = fp_leapcsv_read_angles(angles_csv, &ar, &na, err, errlen);
    if (!rc && !(idx = malloc(nj * sizeof *idx))) {
        snprintf(err, errlen, "out of memory");
        rc = -3;
    }
    /* Hands in order of first appearance. */
    for (size_t first = 0; !rc && first < nj; first++) {
        bool seen = false;
        for (size_t k = 0; k < first && !seen; k++)
            seen = jr[k].hand_id == jr[first].hand_id;
        if (seen)
            continue;
        size_t n = 0;
        for (size_t k = first; k < nj; k++)
            if (jr[k].hand_id == jr[first].hand_id)
                idx[n++] = k;
        if (hands < cap)
            rc = check_hand(jr, idx, n, ar, na, opt, joints_csv, angles_csv, &out[hands], err, errlen);
        hands++;
    }
    free(idx);
    free(jr);
    free(ar);
    if (!rc)
        *nout = hands < cap ? hands : cap;
    return rc;
}
