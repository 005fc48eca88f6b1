/* The least-squares similarity between two point sets (fp_similarity.h). */
#include "fp_similarity.h"

#include "fp_vec.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>

/* Eigenvector of the largest eigenvalue of a symmetric 4x4 matrix (cyclic Jacobi). */
static void top_eigenvector(double a[4][4], double v[4])
{
    double e[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    for (int sweep = 0; sweep < 64; sweep++) {
        double off = 0;
        for (int p = 0; p < 4; p++)
            for (int q = p + 1; q < 4; q++) off += a[p][q] * a[p][q];
        if (off < 1e-30) break;
        for (int p = 0; p < 4; p++)
            for (int q = p + 1; q < 4; q++) {
                if (fabs(a[p][q]) < 1e-300) continue;
                double theta = 0.5 * (a[q][q] - a[p][p]) / a[p][q];
                double t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 4; k++) { /* columns p, q */
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 4; k++) { /* rows p, q */
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 4; k++) {
                    double ekp = e[k][p], ekq = e[k][q];
                    e[k][p] = c * ekp - s * ekq;
                    e[k][q] = s * ekp + c * ekq;
                }
            }
    }
    int best = 0;
    for (int i = 1; i < 4; i++)
        if (a[i][i] > a[best][best]) best = i;
    for (int k = 0; k < 4; k++) v[k] = e[k][best];
}

/* Whether the points span a plane: the largest triangle with the first point, against the
 * spread. */
static bool spans_plane(const double (*p)[3], size_t n)
{
    double spread = 0, area = 0;
    for (size_t i = 1; i < n; i++) {
        double d[3] = {p[i][0] - p[0][0], p[i][1] - p[0][1], p[i][2] - p[0][2]};
        spread = fmax(spread, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (size_t j = i + 1; j < n; j++) {
            double e[3] = {p[j][0] - p[0][0], p[j][1] - p[0][1], p[j][2] - p[0][2]};
            double c[3] = {d[1] * e[2] - d[2] * e[1], d[2] * e[0] - d[0] * e[2], d[0] * e[1] - d[1] * e[0]};
            area = fmax(area, sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]));
        }
    }
    return spread > 0 && area > 1e-3 * spread;
}

int fp_similarity_fit(const double (*a)[3], const double (*b)[3], size_t n, double *s, double q[4],
                      double t[3])
{
    if (n < 3 || !spans_plane(a, n) || !spans_plane(b, n)) return -EDOM;
    double ma[3] = {0, 0, 0}, mb[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) ma[k] += a[i][k] / (double)n, mb[k] += b[i][k] / (double)n;
    double S[3][3] = {{0}}, va = 0;
    for (size_t i = 0; i < n; i++) {
        double pa[3], pb[3];
        for (int k = 0; k < 3; k++) pa[k] = a[i][k] - ma[k], pb[k] = b[i][k] - mb[k];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) S[r][c] += pa[r] * pb[c];
        va += pa[0] * pa[0] + pa[1] * pa[1] + pa[2] * pa[2];
    }
    /* Horn's N matrix (Sxy = sum a_x b_y); its top eigenvector is the rotation a -> b. */
    double N[4][4] = {
        {S[0][0] + S[1][1] + S[2][2], S[1][2] - S[2][1], S[2][0] - S[0][2], S[0][1] - S[1][0]},
        {S[1][2] - S[2][1], S[0][0] - S[1][1] - S[2][2], S[0][1] + S[1][0], S[2][0] + S[0][2]},
        {S[2][0] - S[0][2], S[0][1] + S[1][0], -S[0][0] + S[1][1] - S[2][2], S[1][2] + S[2][1]},
        {S[0][1] - S[1][0], S[2][0] + S[0][2], S[1][2] + S[2][1], -S[0][0] - S[1][1] + S[2][2]}};
    top_eigenvector(N, q);
    double nq = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int k = 0; k < 4; k++) q[k] /= nq;
    if (q[0] < 0)
        for (int k = 0; k < 4; k++) q[k] = -q[k];
    /* Umeyama's scale: sum b' . R a' / sum |a'|^2. */
    double num = 0;
    for (size_t i = 0; i < n; i++) {
        double pa[3], r[3];
        for (int k = 0; k < 3; k++) pa[k] = a[i][k] - ma[k];
        fp_qrot(q, pa, r);
        for (int k = 0; k < 3; k++) num += r[k] * (b[i][k] - mb[k]);
    }
    *s = num / va;
    if (!(*s > 0) || !isfinite(*s)) return -EDOM;
    double rm[3];
    fp_qrot(q, ma, rm);
    for (int k = 0; k < 3; k++) t[k] = mb[k] - *s * rm[k];
    return 0;
}
