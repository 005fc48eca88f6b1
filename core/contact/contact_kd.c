/* The contact guard's k-d tree over a local scale-back's blocking vertices (contact_kd.h):
 * nearest distances for the ramp, weighted motion sums for the carry. */
#include "contact_kd.h"
#include "contact_internal.h" /* reserve, dmin, dmax */

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FP_KD_MOMENTS (4 * FP_KD_TERMS) /* a node's: weight 1 and the motion's three axes */

/* the node over ix[first .. first + n) and those below it into kd->node[kd->n ..); its index */
static uint32_t build(fpc_kd *kd, uint32_t first, uint32_t n)
{
    const float *pos = kd->pos;
    uint32_t *ix = kd->ix;
    uint32_t x = (uint32_t)kd->n++;
    fpc_kdnode *d = &kd->node[x];
    for (int a = 0; a < 3; a++) d->lo[a] = INFINITY, d->hi[a] = -INFINITY;
    for (uint32_t i = first; i < first + n; i++)
        for (int a = 0; a < 3; a++) {
            d->lo[a] = dmin(d->lo[a], pos[3 * (size_t)ix[i] + a]);
            d->hi[a] = dmax(d->hi[a], pos[3 * (size_t)ix[i] + a]);
        }
    d->first = first;
    d->count = n;
    d->left = d->right = 0;
    if (n <= FP_KD_LEAF) return x;
    int ax = 0; /* split at the median of the longest side */
    for (int a = 1; a < 3; a++)
        if (d->hi[a] - d->lo[a] > d->hi[ax] - d->lo[ax]) ax = a;
    fp_select_mid(ix, first, first + n, first + n / 2, ax, pos);
    uint32_t l = build(kd, first, n / 2);
    uint32_t r = build(kd, first + n / 2, n - n / 2);
    kd->node[x].left = l;
    kd->node[x].right = r;
    return x;
}

int fpc_kd_build(fpc_kd *kd, const uint32_t *verts, size_t n, const float *pos)
{
    assert(n < UINT32_MAX);
    kd->n = kd->nix = 0;
    kd->pos = pos;
    if (!n) return 0;
    if (reserve((void **)&kd->ix, &kd->cap_ix, n, sizeof *kd->ix) ||
        reserve((void **)&kd->node, &kd->cap_node, 2 * n, sizeof *kd->node))
        return -ENOMEM;
    memcpy(kd->ix, verts, n * sizeof *verts);
    kd->nix = n;
    build(kd, 0, (uint32_t)n);
    for (int a = 0; a < 3; a++) kd->o[a] = 0.5 * (kd->node[0].lo[a] + kd->node[0].hi[a]);
    return 0;
}

/* the least and the largest squared distance from p to the node's box */
static inline double lb2(const fpc_kdnode *d, const double *p)
{
    double s = 0;
    for (int a = 0; a < 3; a++) {
        double e = dmax(dmax(d->lo[a] - p[a], p[a] - d->hi[a]), 0.0);
        s += e * e;
    }
    return s;
}

static inline double ub2(const fpc_kdnode *d, const double *p)
{
    double s = 0;
    for (int a = 0; a < 3; a++) {
        double e = dmax(p[a] - d->lo[a], d->hi[a] - p[a]);
        s += e * e;
    }
    return s;
}

double fpc_kd_nearest2(const fpc_kd *kd, const double p[3], double bound2, double enough2, uint32_t *hint)
{
    if (!kd->n) return bound2;
    const fpc_kdnode *node = kd->node;
    const uint32_t *ix = kd->ix;
    const float *q = kd->pos;
    uint32_t w = *hint < kd->nix ? *hint : 0;
    const float *qw = q + 3 * (size_t)ix[w];
    double best = bound2, dx = p[0] - qw[0], dy = p[1] - qw[1], dz = p[2] - qw[2];
    double dw = dx * dx + dy * dy + dz * dz;
    if (dw < best) best = dw;
    uint32_t stack[64], top = 0;
    stack[top++] = 0;
    while (top && best > enough2) {
        const fpc_kdnode *d = &node[stack[--top]];
        if (lb2(d, p) >= best) continue;
        if (!d->left) {
            for (uint32_t j = d->first; j < d->first + d->count; j++) {
                const float *qj = q + 3 * (size_t)ix[j];
                dx = p[0] - qj[0], dy = p[1] - qj[1], dz = p[2] - qj[2];
                double d2 = dx * dx + dy * dy + dz * dz;
                if (d2 < best) best = d2, w = j;
            }
            continue;
        }
        double ll = lb2(&node[d->left], p), lr = lb2(&node[d->right], p);
        uint32_t nearer = ll <= lr ? d->left : d->right, farther = ll <= lr ? d->right : d->left;
        if ((ll <= lr ? lr : ll) < best) stack[top++] = farther; /* (one a level: < 64) */
        if ((ll <= lr ? ll : lr) < best) stack[top++] = nearer;
    }
    *hint = w;
    return best;
}

/* the 15 terms of q (about o): (1, q, s, qx^2, qy^2, qz^2, qx qy, qx qz, qy qz, s q, s^2),
 * s = |q|^2 */
static void terms(const double q[3], double v[FP_KD_TERMS])
{
    double s = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
    double t[FP_KD_TERMS] = {1,           q[0],        q[1],        q[2],        s,           q[0] * q[0],
                             q[1] * q[1], q[2] * q[2], q[0] * q[1], q[0] * q[2], q[1] * q[2], s * q[0],
                             s * q[1],    s * q[2],    s * s};
    memcpy(v, t, sizeof t);
}

/* coef(p) (p about o): coef . terms(q) = (1 - |p - q|^2 / R2)^2, the square of alpha +
 * beta . q + gamma |q|^2 with alpha = 1 - |p|^2 / R2, beta = 2 p / R2, gamma = -1 / R2 */
static void coef(const double p[3], double R2, double c[FP_KD_TERMS])
{
    double al = 1 - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) / R2, ga = -1 / R2;
    double b[3] = {2 * p[0] / R2, 2 * p[1] / R2, 2 * p[2] / R2};
    double t[FP_KD_TERMS] = {al * al,         2 * al * b[0],   2 * al * b[1],   2 * al * b[2],
                             2 * al * ga,     b[0] * b[0],     b[1] * b[1],     b[2] * b[2],
                             2 * b[0] * b[1], 2 * b[0] * b[2], 2 * b[1] * b[2], 2 * ga * b[0],
                             2 * ga * b[1],   2 * ga * b[2],   ga * ga};
    memcpy(c, t, sizeof t);
}

int fpc_kd_moments(fpc_kd *kd, const float *cand)
{
    if (!kd->n) return 0;
    if (reserve((void **)&kd->mom, &kd->cap_mom, kd->n * FP_KD_MOMENTS, sizeof *kd->mom)) return -ENOMEM;
    const float *q = kd->pos;
    for (size_t x = kd->n; x-- > 0;) { /* children first: they follow their parent */
        const fpc_kdnode *d = &kd->node[x];
        double *m = kd->mom + x * FP_KD_MOMENTS;
        if (d->left) {
            const double *l = kd->mom + (size_t)d->left * FP_KD_MOMENTS, *r = kd->mom + (size_t)d->right * FP_KD_MOMENTS;
            for (int t = 0; t < FP_KD_MOMENTS; t++) m[t] = l[t] + r[t];
            continue;
        }
        memset(m, 0, FP_KD_MOMENTS * sizeof *m);
        for (uint32_t j = d->first; j < d->first + d->count; j++) {
            const float *qj = q + 3 * (size_t)kd->ix[j], *cj = cand + 3 * (size_t)kd->ix[j];
            double qo[3] = {qj[0] - kd->o[0], qj[1] - kd->o[1], qj[2] - kd->o[2]}, v[FP_KD_TERMS];
            terms(qo, v);
            for (int a = 0; a < 4; a++) {
                double w = a == 0 ? 1.0 : (double)cj[a - 1] - qj[a - 1];
                for (int t = 0; t < FP_KD_TERMS; t++) m[a * FP_KD_TERMS + t] += w * v[t];
            }
        }
    }
    return 0;
}

void fpc_kd_sums(const fpc_kd *kd, const float *cand, const double p[3], double R2, double acc[4])
{
    acc[0] = acc[1] = acc[2] = acc[3] = 0;
    if (!kd->n) return;
    const fpc_kdnode *node = kd->node;
    const float *q = kd->pos;
    double c[FP_KD_TERMS];
    bool have_coef = false;
    uint32_t stack[64], top = 0;
    stack[top++] = 0;
    while (top) {
        const uint32_t x = stack[--top];
        const fpc_kdnode *d = &node[x];
        if (lb2(d, p) >= R2) continue;
        if (ub2(d, p) < R2) { /* wholly inside: its moments */
            if (!have_coef) {
                double po[3] = {p[0] - kd->o[0], p[1] - kd->o[1], p[2] - kd->o[2]};
                coef(po, R2, c);
                have_coef = true;
            }
            const double *m = kd->mom + (size_t)x * FP_KD_MOMENTS;
            for (int a = 0; a < 4; a++) {
                double s = 0;
                for (int t = 0; t < FP_KD_TERMS; t++) s += c[t] * m[a * FP_KD_TERMS + t];
                acc[a] += s;
            }
            continue;
        }
        if (!d->left) {
            for (uint32_t j = d->first; j < d->first + d->count; j++) {
                const float *qj = q + 3 * (size_t)kd->ix[j], *cj = cand + 3 * (size_t)kd->ix[j];
                double e2 = 0;
                for (int a = 0; a < 3; a++) e2 += (p[a] - qj[a]) * (p[a] - qj[a]);
                if (e2 >= R2) continue;
                double u = 1 - e2 / R2, w = u * u;
                acc[0] += w;
                for (int a = 0; a < 3; a++) acc[1 + a] += w * ((double)cj[a] - qj[a]);
            }
            continue;
        }
        stack[top++] = d->left; /* (a level each: < 64) */
        stack[top++] = d->right;
    }
}

void fpc_kd_free(fpc_kd *kd)
{
    free(kd->node);
    free(kd->ix);
    free(kd->mom);
    memset(kd, 0, sizeof *kd);
}
