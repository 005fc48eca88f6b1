/* The One Euro filter (Casiez, Roussel, Vogel, CHI 2012) with Holt's trend, and an input's
 * filter keys. */
#include "fp_filter.h"

#include <facepuppet/plugin_util.h>

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define TWO_PI 6.283185307179586476925

void fp_filter_default(const char *name, fp_filter_config *out)
{
    memset(out, 0, sizeof *out);
    out->mincutoff = FP_FILTER_MINCUTOFF;
    out->beta = FP_FILTER_BETA;
    out->dcutoff = FP_FILTER_DCUTOFF;
    out->trend = FP_FILTER_TREND;
    if (!name) return;
    if (!strcmp(name, "osc")) {
        out->kind = FP_FILTER_AUTO;
    } else if (!strcmp(name, "cyberglove")) {
        out->kind = FP_FILTER_ONEEURO;
        out->mincutoff = FP_FILTER_GLOVE_MINCUTOFF;
        out->beta = FP_FILTER_GLOVE_BETA;
        out->dcutoff = FP_FILTER_GLOVE_DCUTOFF;
        out->trend = 0.0;
    }
}

/* v a decimal in (lo, hi] (lo_open) or [lo, hi]. */
static bool in_range(const char *v, double lo, bool lo_open, double hi, double *out)
{
    double x;
    if (!fp_parse_decimal(v, &x)) return false;
    if (lo_open ? !(x > lo) : !(x >= lo)) return false;
    if (!(x <= hi)) return false;
    *out = x;
    return true;
}

int fp_filter_parse(const char *name, const char *filter, const char *mincutoff,
                    const char *beta, const char *dcutoff, const char *trend, fp_filter_config *out,
                    char *err, size_t errlen)
{
    fp_filter_config c;
    fp_filter_default(name, &c);
    if (filter) {
        if (!strcmp(filter, "oneeuro")) c.kind = FP_FILTER_ONEEURO;
        else if (!strcmp(filter, "auto")) c.kind = FP_FILTER_AUTO;
        else if (!strcmp(filter, "off")) c.kind = FP_FILTER_OFF;
        else {
            if (err && errlen) snprintf(err, errlen, "filter=%s: expected oneeuro, auto or off", filter);
            return -EINVAL;
        }
    }
    const char *key = mincutoff ? "mincutoff" : beta ? "beta" : dcutoff ? "dcutoff" : trend ? "trend" : NULL;
    if (key && c.kind == FP_FILTER_OFF) {
        if (err && errlen)
            snprintf(err, errlen, "%s= tunes the One Euro filter, which is off for this input%s: "
                     "add filter=oneeuro", key, filter ? " (filter=off)" : "");
        return -EINVAL;
    }
    if (mincutoff && !in_range(mincutoff, 0, true, 1000, &c.mincutoff)) {
        if (err && errlen) snprintf(err, errlen, "mincutoff=%s: expected a number of Hz above 0, at most 1000", mincutoff);
        return -EINVAL;
    }
    if (beta && !in_range(beta, 0, false, 100, &c.beta)) {
        if (err && errlen) snprintf(err, errlen, "beta=%s: expected a number from 0 to 100 (Hz per mm/s)", beta);
        return -EINVAL;
    }
    if (dcutoff && !in_range(dcutoff, 0, true, 1000, &c.dcutoff)) {
        if (err && errlen) snprintf(err, errlen, "dcutoff=%s: expected a number of Hz above 0, at most 1000", dcutoff);
        return -EINVAL;
    }
    if (trend && !in_range(trend, 0, false, 1000, &c.trend)) {
        if (err && errlen) snprintf(err, errlen, "trend=%s: expected a number of Hz from 0 (off) to 1000", trend);
        return -EINVAL;
    }
    *out = c;
    return 0;
}

int fp_filter_describe(const fp_filter_config *c, char *buf, size_t len)
{
    if (c->kind == FP_FILTER_OFF) return snprintf(buf, len, "filter off");
    const char *where = c->kind == FP_FILTER_AUTO ? " where the tracker does not smooth them (MediaPipe's "
                                                    "landmarks; a Leap's joints as sent)" : "";
    if (c->trend > 0)
        return snprintf(buf, len, "hands filtered in the session%s (oneeuro mincutoff=%g beta=%g dcutoff=%g "
                        "trend=%g): a steady motion is followed without lag once its trend has "
                        "settled (about %.0f ms after it starts or turns)",
                        where, c->mincutoff, c->beta, c->dcutoff, c->trend, 1e3 / (TWO_PI * c->trend));
    return snprintf(buf, len, "hands filtered in the session%s (oneeuro mincutoff=%g beta=%g dcutoff=%g): "
                    "a steady motion lags "
                    "%.0f ms at 200 mm/s, %.0f ms at 50 mm/s (samples at %.0f Hz; at most %.0f and "
                    "%.0f ms at any rate)",
                    where, c->mincutoff, c->beta, c->dcutoff,
                    1e3 * fp_oneeuro_lag(c, 200, FP_FILTER_DESCRIBE_HZ),
                    1e3 * fp_oneeuro_lag(c, 50, FP_FILTER_DESCRIBE_HZ), FP_FILTER_DESCRIBE_HZ,
                    1e3 * fp_oneeuro_lag(c, 200, 0), 1e3 * fp_oneeuro_lag(c, 50, 0));
}

void fp_oneeuro_reset(fp_oneeuro *f) { memset(f, 0, sizeof *f); }

double fp_oneeuro_alpha(double cutoff_hz, double te_s)
{
    double tau = 1.0 / (TWO_PI * cutoff_hz);
    return 1.0 / (1.0 + tau / te_s);
}

/* The first half of a sample: T_e, dX_i and dXhat_i; returns |dXhat_i| x mm_per_unit, or -1
 * where the sample is passed through (the filter's first, or not finite: it then starts
 * afresh) and its smoothing skipped. */
static double oneeuro_speed(fp_oneeuro *f, const fp_filter_config *c, int dim, double mm_per_unit,
                            const double *x, int64_t t_ns)
{
    if (dim < 1) return -1;
    if (dim > FP_ONEEURO_MAX_DIM) dim = FP_ONEEURO_MAX_DIM;
    bool finite = true;
    for (int k = 0; k < dim; k++) finite = finite && isfinite(x[k]);
    if (!finite || !f->started) {
        fp_oneeuro_reset(f);
        if (finite) {
            for (int k = 0; k < dim; k++) f->x[k] = x[k];
            f->te = 1.0 / 120.0;
            f->t_ns = t_ns;
            f->started = true;
        }
        return -1;
    }
    if (t_ns > f->t_ns) f->te = (double)(t_ns - f->t_ns) * 1e-9;
    f->t_ns = t_ns > f->t_ns ? t_ns : f->t_ns;
    const double te = f->te, ad = fp_oneeuro_alpha(c->dcutoff, te);
    double speed2 = 0;
    for (int k = 0; k < dim; k++) {
        double d = (x[k] - f->x[k]) / te;            /* dX_i = (X_i - Xhat_{i-1}) / T_e */
        f->dx[k] = ad * d + (1 - ad) * f->dx[k];     /* dXhat_i */
        speed2 += f->dx[k] * f->dx[k];
    }
    return sqrt(speed2) * mm_per_unit;
}

/* The second half: Xhat_i at cutoff_hz, from the prediction Xhat_{i-1} + g T_e B_{i-1}
 * (Holt), g fading from 1 to 0 as the sample falls behind Xhat_{i-1} along B from
 * FP_FILTER_TREND_SLACK_MM to FP_FILTER_TREND_STOP_MM (then from Xhat_{i-1}, B decaying);
 * after a gap over FP_FILTER_TREND_GAP_S, B starts at 0; and B_i at trend_hz (0: none, B
 * stays 0: the paper's filter, bit for bit). */
static void oneeuro_smooth(fp_oneeuro *f, double cutoff_hz, double trend_hz, double mm_per_unit, int dim,
                           const double *x, double *out)
{
    const double a = fp_oneeuro_alpha(cutoff_hz, f->te);
    if (!(trend_hz > 0)) {
        for (int k = 0; k < dim; k++) {
            f->x[k] = a * x[k] + (1 - a) * f->x[k];  /* Xhat_i */
            out[k] = f->x[k];
        }
        return;
    }
    const double b = fp_oneeuro_alpha(trend_hz, f->te);
    double along = 0, tr2 = 0;
    for (int k = 0; k < dim; k++) {
        along += (x[k] - f->x[k]) * f->tr[k];
        tr2 += f->tr[k] * f->tr[k];
    }
    /* the motion stopping or turning: the sample behind Xhat_{i-1} along B by s mm; the
     * prediction and the trend's update fade from s = FP_FILTER_TREND_SLACK_MM to none at
     * FP_FILTER_TREND_STOP_MM (a ramp: the output stays continuous in the sample) */
    const double behind_mm = tr2 > 0 ? -along * mm_per_unit / sqrt(tr2) : 0;
    const double g = 1 - fmin(1, fmax(0, (behind_mm - FP_FILTER_TREND_SLACK_MM) /
                                             (FP_FILTER_TREND_STOP_MM - FP_FILTER_TREND_SLACK_MM)));
    assert(g >= 0 && g <= 1);
    if (f->te > FP_FILTER_TREND_GAP_S) /* the hand was away: no motion is guessed across it */
        for (int k = 0; k < dim; k++) f->tr[k] = 0;
    for (int k = 0; k < dim; k++) {
        const double last = f->x[k];
        f->x[k] = a * x[k] + (1 - a) * (last + g * f->te * f->tr[k]);       /* Xhat_i */
        f->tr[k] = g * b * (f->x[k] - last) / f->te + (1 - b) * f->tr[k];   /* B_i */
        out[k] = f->x[k];
    }
}

void fp_oneeuro_filter(fp_oneeuro *f, const fp_filter_config *c, int dim, double mm_per_unit,
                       const double *x, int64_t t_ns, double *out)
{
    if (dim < 1) return;
    if (dim > FP_ONEEURO_MAX_DIM) dim = FP_ONEEURO_MAX_DIM;
    double speed = oneeuro_speed(f, c, dim, mm_per_unit, x, t_ns);
    if (speed < 0) {
        if (out != x) memmove(out, x, (size_t)dim * sizeof *out);
        return;
    }
    oneeuro_smooth(f, c->mincutoff + c->beta * speed, c->trend, mm_per_unit, dim, x, out);
}

void fp_oneeuro_filter_joints(fp_oneeuro *f, size_t count, const fp_filter_config *c,
                              double (*x)[3], int64_t t_ns)
{
    assert(count <= FP_ONEEURO_MAX_JOINTS);
    double speed[FP_ONEEURO_MAX_JOINTS], fastest = 0;
    for (size_t j = 0; j < count && j < FP_ONEEURO_MAX_JOINTS; j++) {
        speed[j] = oneeuro_speed(&f[j], c, 3, 1.0, x[j], t_ns);
        if (speed[j] > fastest) fastest = speed[j];
    }
    const double cutoff = c->mincutoff + c->beta * fastest;
    for (size_t j = 0; j < count && j < FP_ONEEURO_MAX_JOINTS; j++)
        if (speed[j] >= 0) oneeuro_smooth(&f[j], cutoff, c->trend, 1.0, 3, x[j], x[j]);
}

double fp_oneeuro_lag(const fp_filter_config *c, double speed_mm_s, double rate_hz)
{
    if (c->trend > 0) return 0.0; /* Holt's trend follows a steady ramp exactly, once settled */
    double v = fabs(speed_mm_s);
    double b = TWO_PI * (c->mincutoff + c->beta * v);
    if (!(rate_hz > 0) || !isfinite(rate_hz) || !(v > 0) || !(c->beta > 0)) return 1.0 / b;
    /* lambda 2 pi (mincutoff + beta v + beta v lambda rate) = 1:
     * a lambda^2 + b lambda - 1 = 0, a = 2 pi beta v rate; the positive root, written so that
     * it does not cancel: 2 / (b + sqrt(b^2 + 4 a)). */
    double a = TWO_PI * c->beta * v * rate_hz;
    return 2.0 / (b + sqrt(b * b + 4 * a));
}
