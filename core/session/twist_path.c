/* The path a composed step takes where fingertips turn together (twist_path.h). */
#define _GNU_SOURCE /* M_PI */
#include "twist_path.h"

#include "fp_similarity.h"
#include "fp_vec.h"

#include <assert.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#define MAX_POINTS 64 /* FP_ENGINE_MAX_CONTROL */

/* the root of i's cluster (union-find, paths halved) */
static size_t root(size_t *up, size_t i)
{
    while (up[i] != i) i = up[i] = up[up[i]];
    return i;
}

/* the least |a + u (b - a)| over u in [0, 1] */
static double least_on_line(const double a[3], const double b[3])
{
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double u = dd > 0 ? -(a[0] * d[0] + a[1] * d[1] + a[2] * d[2]) / dd : 0;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    double p[3] = {a[0] + u * d[0], a[1] + u * d[1], a[2] + u * d[2]};
    return sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
}

static double len3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* the cluster's blend w (twist_path.h: rho) over its members m[0 .. k) */
static double blend(const size_t *m, size_t k, const float (*start)[3], const float (*end)[3])
{
    double rho = 1.0;
    for (size_t x = 0; x < k; x++)
        for (size_t y = x + 1; y < k; y++) {
            double a[3], b[3];
            for (int c = 0; c < 3; c++) {
                a[c] = (double)start[m[x]][c] - start[m[y]][c];
                b[c] = (double)end[m[x]][c] - end[m[y]][c];
            }
            double lo = fmin(len3(a), len3(b));
            if (lo > 0 && least_on_line(a, b) / lo < rho) rho = least_on_line(a, b) / lo;
        }
    if (rho >= FP_TWIST_RHO_LINE) return 0.0;
    if (rho <= FP_TWIST_RHO_ARC) return 1.0;
    double x = (FP_TWIST_RHO_LINE - rho) / (FP_TWIST_RHO_LINE - FP_TWIST_RHO_ARC);
    return x * x * (3 - 2 * x);
}

size_t fp_twist_path(size_t n, const float (*start)[3], const float (*end)[3], double radius, float *via)
{
    assert(n <= MAX_POINTS && radius > 0);
    if (n < 2 || n > MAX_POINTS) return 0;
    size_t up[MAX_POINTS];
    for (size_t i = 0; i < n; i++) up[i] = i;
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            double d2 = 0;
            for (int c = 0; c < 3; c++) d2 += ((double)start[i][c] - start[j][c]) * ((double)start[i][c] - start[j][c]);
            if (d2 < 4 * radius * radius) up[root(up, i)] = root(up, j);
        }
    /* per cluster (by its root): w, the turn q and its angle, the centroids */
    double w[MAX_POINTS] = {0}, q[MAX_POINTS][4], cs[MAX_POINTS][3], ce[MAX_POINTS][3], theta_max = 0;
    for (size_t r = 0; r < n; r++) {
        if (root(up, r) != r) continue;
        size_t m[MAX_POINTS], k = 0;
        for (size_t i = 0; i < n; i++)
            if (root(up, i) == r) m[k++] = i;
        if (k < 2 || !((w[r] = blend(m, k, start, end)) > 0)) continue;
        double a[MAX_POINTS][3], b[MAX_POINTS][3];
        for (size_t x = 0; x < k; x++)
            for (int c = 0; c < 3; c++) a[x][c] = start[m[x]][c], b[x][c] = end[m[x]][c];
        fp_rotation_fit((const double(*)[3])a, (const double(*)[3])b, k, q[r]);
        for (int c = 0; c < 3; c++) {
            cs[r][c] = ce[r][c] = 0;
            for (size_t x = 0; x < k; x++) cs[r][c] += a[x][c] / (double)k, ce[r][c] += b[x][c] / (double)k;
        }
        double theta = 2 * atan2(sqrt(q[r][1] * q[r][1] + q[r][2] * q[r][2] + q[r][3] * q[r][3]), q[r][0]);
        if (theta > theta_max) theta_max = theta;
    }
    bool bent = false;
    for (size_t i = 0; i < n; i++) bent |= w[i] > 0;
    if (!bent) return 0;
    size_t K = (size_t)ceil(theta_max / (M_PI / 4)) - 1;
    K = K < 1 ? 1 : K > FP_TWIST_MAX_VIA ? FP_TWIST_MAX_VIA : K;
    for (size_t i = 0; i < n; i++) {
        size_t r = root(up, i);
        double arm[3] = {0, 0, 0}, turned[3], res[3] = {0, 0, 0};
        if (w[r] > 0) { /* r_i = e_i - c_e - R(theta) (s_i - c_s) */
            for (int c = 0; c < 3; c++) arm[c] = start[i][c] - cs[r][c];
            fp_qrot(q[r], arm, turned);
            for (int c = 0; c < 3; c++) res[c] = end[i][c] - ce[r][c] - turned[c];
        }
        for (size_t k = 1; k <= K; k++) {
            double u = (double)k / (double)(K + 1), p[3];
            for (int c = 0; c < 3; c++) p[c] = start[i][c] + u * ((double)end[i][c] - start[i][c]);
            if (w[r] > 0) { /* R(u theta): the half angle scaled, the same axis */
                double s = sqrt(q[r][1] * q[r][1] + q[r][2] * q[r][2] + q[r][3] * q[r][3]);
                double h = u * atan2(s, q[r][0]), qu[4] = {cos(h), 0, 0, 0};
                for (int c = 0; c < 3; c++) qu[1 + c] = s > 0 ? sin(h) * q[r][1 + c] / s : 0;
                fp_qrot(qu, arm, turned);
                for (int c = 0; c < 3; c++) {
                    double arc = cs[r][c] + u * (ce[r][c] - cs[r][c]) + turned[c] + u * res[c];
                    p[c] = (1 - w[r]) * p[c] + w[r] * arc;
                }
            }
            for (int c = 0; c < 3; c++) via[((k - 1) * n + i) * 3 + c] = (float)p[c];
        }
    }
    return K;
}
