/* Checks shared by the rig tests (tests/rig): the best rigid fit of a vertex set (Horn's
 * quaternion method, an independent reference for "the lower teeth move rigidly") and folds
 * of a posed surface (left out with RIG_CHECK_NO_FOLDS). Test-only, header-only (static
 * functions). */
#ifndef FP_TEST_RIG_CHECK_H
#define FP_TEST_RIG_CHECK_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

/* Jacobi eigen-decomposition of a symmetric 4x4 matrix (destroyed): the eigenvector of the
 * largest eigenvalue. */
static void rig_check_eig4_max(double A[4][4], double v[4])
{
    double V[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    for (int sweep = 0; sweep < 100; sweep++) {
        double off = 0;
        for (int p = 0; p < 4; p++)
            for (int q = p + 1; q < 4; q++) off += A[p][q] * A[p][q];
        if (off < 1e-30) break;
        for (int p = 0; p < 4; p++)
            for (int q = p + 1; q < 4; q++) {
                if (fabs(A[p][q]) < 1e-300) continue;
                double th = 0.5 * atan2(2 * A[p][q], A[q][q] - A[p][p]);
                double c = cos(th), s = sin(th);
                for (int k = 0; k < 4; k++) {
                    double akp = A[k][p], akq = A[k][q];
                    A[k][p] = c * akp - s * akq, A[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 4; k++) {
                    double apk = A[p][k], aqk = A[q][k];
                    A[p][k] = c * apk - s * aqk, A[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 4; k++) {
                    double vkp = V[k][p], vkq = V[k][q];
                    V[k][p] = c * vkp - s * vkq, V[k][q] = s * vkp + c * vkq;
                }
            }
    }
    int best = 0;
    for (int i = 1; i < 4; i++)
        if (A[i][i] > A[best][best]) best = i;
    for (int i = 0; i < 4; i++) v[i] = V[i][best];
}

/* Best rigid fit (Horn 1987, the quaternion method) of the vertices with sel[v] != 0 from a
 * to b (n x 3 floats each): the RMS residual and RMS displacement (mesh units), the rotation
 * angle (degrees) and its unit axis (may be NULL). Returns the number of vertices fitted. */
static size_t rig_check_rigid_fit(const float *a, const float *b, const uint8_t *sel, size_t n, double *resid,
                                  double *disp, double *angle_deg, double axis[3])
{
    double ca[3] = {0}, cb[3] = {0};
    size_t k = 0;
    for (size_t v = 0; v < n; v++)
        if (sel[v]) {
            for (int i = 0; i < 3; i++) ca[i] += a[3 * v + i], cb[i] += b[3 * v + i];
            k++;
        }
    if (k < 3) return k;
    for (int i = 0; i < 3; i++) ca[i] /= (double)k, cb[i] /= (double)k;
    double S[3][3] = {{0}};
    for (size_t v = 0; v < n; v++)
        if (sel[v])
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++) S[i][j] += (a[3 * v + i] - ca[i]) * (b[3 * v + j] - cb[j]);
    double N[4][4] = {
        {S[0][0] + S[1][1] + S[2][2], S[1][2] - S[2][1], S[2][0] - S[0][2], S[0][1] - S[1][0]},
        {S[1][2] - S[2][1], S[0][0] - S[1][1] - S[2][2], S[0][1] + S[1][0], S[2][0] + S[0][2]},
        {S[2][0] - S[0][2], S[0][1] + S[1][0], -S[0][0] + S[1][1] - S[2][2], S[1][2] + S[2][1]},
        {S[0][1] - S[1][0], S[2][0] + S[0][2], S[1][2] + S[2][1], -S[0][0] - S[1][1] + S[2][2]}};
    double q[4];
    rig_check_eig4_max(N, q);
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double R[9] = {w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y),
                   2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x),
                   2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z};
    double r2 = 0, d2 = 0;
    for (size_t v = 0; v < n; v++)
        if (sel[v]) {
            double p[3] = {a[3 * v] - ca[0], a[3 * v + 1] - ca[1], a[3 * v + 2] - ca[2]};
            for (int i = 0; i < 3; i++) {
                double t = cb[i] + R[3 * i] * p[0] + R[3 * i + 1] * p[1] + R[3 * i + 2] * p[2];
                r2 += (t - b[3 * v + i]) * (t - b[3 * v + i]);
                d2 += (b[3 * v + i] - a[3 * v + i]) * (b[3 * v + i] - a[3 * v + i]);
            }
        }
    *resid = sqrt(r2 / (double)k);
    *disp = sqrt(d2 / (double)k);
    *angle_deg = acos(fmin(1, fmax(-1, (R[0] + R[4] + R[8] - 1) / 2))) * 180 / M_PI;
    if (axis) {
        double l = sqrt(x * x + y * y + z * z);
        double sg = w < 0 ? -1 : 1;
        axis[0] = l > 0 ? sg * x / l : 0, axis[1] = l > 0 ? sg * y / l : 0, axis[2] = l > 0 ? sg * z / l : 0;
    }
    return k;
}

#ifndef RIG_CHECK_NO_FOLDS
static void rig_check_normal(const float *p, const uint32_t *t, double nrm[3])
{
    double u[3], v[3];
    for (int i = 0; i < 3; i++) u[i] = p[3 * t[1] + i] - p[3 * t[0] + i], v[i] = p[3 * t[2] + i] - p[3 * t[0] + i];
    nrm[0] = u[1] * v[2] - u[2] * v[1], nrm[1] = u[2] * v[0] - u[0] * v[2], nrm[2] = u[0] * v[1] - u[1] * v[0];
    double l = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    for (int i = 0; i < 3; i++) nrm[i] = l > 0 ? nrm[i] / l : 0;
}

typedef struct rig_check_edge {
    uint32_t a, b; /* vertices, a < b */
    uint32_t t;    /* triangle */
} rig_check_edge;

static int rig_check_edge_cmp(const void *x, const void *y)
{
    const rig_check_edge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return (p->t > q->t) - (p->t < q->t);
}

/* Folds: edges shared by exactly two triangles whose normals agree at rest (dot > 0, a
 * dihedral turn under 90 degrees) and oppose in `after` (dot < -1/2: the surface doubled back
 * past 120 degrees). Also counts, in *turned (may be NULL), the triangles whose own normal
 * turned more than 90 degrees from rest (test_guard's "flipped"; a stretched crease may do
 * that without folding). Returns the number of folded edges, or -1 without memory. */
static long rig_check_folds(const float *rest, const float *after, const uint32_t *tris, size_t nt, long *turned)
{
    rig_check_edge *e = malloc(3 * nt * sizeof *e);
    if (!e) return -1;
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t u = tris[3 * t + k], v = tris[3 * t + (k + 1) % 3];
            e[3 * t + k] = (rig_check_edge){u < v ? u : v, u < v ? v : u, (uint32_t)t};
        }
    qsort(e, 3 * nt, sizeof *e, rig_check_edge_cmp);
    long folds = 0;
    for (size_t i = 0; i + 1 < 3 * nt; i++) {
        if (e[i].a != e[i + 1].a || e[i].b != e[i + 1].b) continue;
        if (i + 2 < 3 * nt && e[i + 2].a == e[i].a && e[i + 2].b == e[i].b) continue; /* non-manifold */
        if (i > 0 && e[i - 1].a == e[i].a && e[i - 1].b == e[i].b) continue;
        double n0[3], n1[3], m0[3], m1[3];
        rig_check_normal(rest, &tris[3 * (size_t)e[i].t], n0);
        rig_check_normal(rest, &tris[3 * (size_t)e[i + 1].t], n1);
        rig_check_normal(after, &tris[3 * (size_t)e[i].t], m0);
        rig_check_normal(after, &tris[3 * (size_t)e[i + 1].t], m1);
        double c0 = n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2], c1 = m0[0] * m1[0] + m0[1] * m1[1] + m0[2] * m1[2];
        if (c0 > 0 && c1 < -0.5) folds++;
    }
    if (turned) {
        *turned = 0;
        for (size_t t = 0; t < nt; t++) {
            double n0[3], n1[3];
            rig_check_normal(rest, &tris[3 * t], n0);
            rig_check_normal(after, &tris[3 * t], n1);
            *turned += n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2] < 0;
        }
    }
    free(e);
    return folds;
}
#endif

#endif
