/* The contact guard's filtered orientation predicates and its triangle-triangle test
 * (fp_contact.h; the planes made once, tplane, in contact_internal.h). */
#include "contact_internal.h"

#include <math.h>

/* ---- the triangle-triangle test ---------------------------------------------------------- */

/* Signs of orientation determinants, filtered: a determinant within its rounding error
 * bound (Shewchuk, "Adaptive precision floating-point arithmetic and fast robust geometric
 * predicates", 1997: errboundA, which covers the differences too) has sign 0, as if exactly
 * degenerate. Every decision below treats 0 as "may touch", so an uncertain case counts as
 * meeting: the test is exact where the signs are certain and errs towards a crossing where
 * they are not. The guard's bisection drives triangles towards touching, frame after frame
 * (each frame keeps the largest passing share), until within rounding; there a plain sign
 * could let through what an exact test (CGAL, in the tests) sees as touching. */
#define FP_EPS 1.1102230246251565e-16 /* 2^-53 */

static int orient3d(const double *p, const double *q, const double *r, const double *s)
{
    double ax = q[0] - p[0], ay = q[1] - p[1], az = q[2] - p[2];
    double bx = r[0] - p[0], by = r[1] - p[1], bz = r[2] - p[2];
    double cx = s[0] - p[0], cy = s[1] - p[1], cz = s[2] - p[2];
    double m1 = by * cz, m2 = bz * cy, m3 = bx * cz, m4 = bz * cx, m5 = bx * cy, m6 = by * cx;
    double det = ax * (m1 - m2) - ay * (m3 - m4) + az * (m5 - m6);
    double perm = fabs(ax) * (fabs(m1) + fabs(m2)) + fabs(ay) * (fabs(m3) + fabs(m4)) +
                  fabs(az) * (fabs(m5) + fabs(m6));
    double bound = (7.0 + 56.0 * FP_EPS) * FP_EPS * perm;
    return det > bound ? 1 : det < -bound ? -1 : 0;
}

static int orient2d(const double *p, const double *q, const double *r)
{
    double l = (q[0] - p[0]) * (r[1] - p[1]), rr = (q[1] - p[1]) * (r[0] - p[0]), det = l - rr;
    double bound = (3.0 + 16.0 * FP_EPS) * FP_EPS * (fabs(l) + fabs(rr));
    return det > bound ? 1 : det < -bound ? -1 : 0;
}

/* closed segments pq and ab in a plane: they meet iff each one's endpoints are not strictly
 * on one side of the other's line, or, collinear, their boxes overlap (an uncertain sign is 0:
 * a meeting) */
static bool seg_seg2(const double *p, const double *q, const double *a, const double *b)
{
    int d1 = orient2d(p, q, a), d2 = orient2d(p, q, b);
    int d3 = orient2d(a, b, p), d4 = orient2d(a, b, q);
    if ((!d1 && !d2) || (!d3 && !d4))
        return fmax(p[0], q[0]) >= fmin(a[0], b[0]) && fmax(a[0], b[0]) >= fmin(p[0], q[0]) &&
               fmax(p[1], q[1]) >= fmin(a[1], b[1]) && fmax(a[1], b[1]) >= fmin(p[1], q[1]);
    return d1 * d2 <= 0 && d3 * d4 <= 0;
}

static bool in_tri2(const double *p, const double t[3][2])
{
    int s1 = orient2d(t[0], t[1], p), s2 = orient2d(t[1], t[2], p), s3 = orient2d(t[2], t[0], p);
    return !((s1 > 0 || s2 > 0 || s3 > 0) && (s1 < 0 || s2 < 0 || s3 < 0));
}

/* segment pq and triangle t in one plane: project away the normal's largest axis */
static bool seg_tri_coplanar(const double *p, const double *q, const double t[3][3])
{
    double e1[3], e2[3], nrm[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = t[1][k] - t[0][k];
        e2[k] = t[2][k] - t[0][k];
    }
    nrm[0] = fabs(e1[1] * e2[2] - e1[2] * e2[1]);
    nrm[1] = fabs(e1[2] * e2[0] - e1[0] * e2[2]);
    nrm[2] = fabs(e1[0] * e2[1] - e1[1] * e2[0]);
    int drop = nrm[0] >= nrm[1] && nrm[0] >= nrm[2] ? 0 : nrm[1] >= nrm[2] ? 1 : 2;
    int i0 = drop == 0 ? 1 : 0, i1 = drop == 2 ? 1 : 2;
    double p2[2] = {p[i0], p[i1]}, q2[2] = {q[i0], q[i1]}, t2[3][2];
    for (int v = 0; v < 3; v++) {
        t2[v][0] = t[v][i0];
        t2[v][1] = t[v][i1];
    }
    if (in_tri2(p2, t2) || in_tri2(q2, t2)) return true;
    for (int v = 0; v < 3; v++)
        if (seg_seg2(p2, q2, t2[v], t2[(v + 1) % 3])) return true;
    return false;
}

/* closed segment pq against closed triangle t (not degenerate); op, oq: the signs of
 * orient3d(t[0], t[1], t[2], p) and (..., q) */
static bool seg_tri(const double *p, const double *q, const double t[3][3], int op, int oq)
{
    if (op * oq > 0) return false;
    if (!op && !oq) return seg_tri_coplanar(p, q, t);
    int s1 = orient3d(p, q, t[0], t[1]), s2 = orient3d(p, q, t[1], t[2]), s3 = orient3d(p, q, t[2], t[0]);
    return !((s1 > 0 || s2 > 0 || s3 > 0) && (s1 < 0 || s2 < 0 || s3 < 0));
}

/* the side of q against plane pl (tplane, contact_internal.h): orient3d(t[0], q, t[1], t[2])
 * bit for bit, filtered as orient3d */
static inline int plane_side(const tplane *pl, const double *q)
{
    double cx = q[0] - pl->o[0], cy = q[1] - pl->o[1], cz = q[2] - pl->o[2];
    double det = cx * pl->n[0] - cy * pl->n[1] + cz * pl->n[2];
    double perm = fabs(cx) * pl->f[0] + fabs(cy) * pl->f[1] + fabs(cz) * pl->f[2];
    double bound = (7.0 + 56.0 * FP_EPS) * FP_EPS * perm;
    return (det > bound) - (det < -bound);
}

/* fp_contact_tri_tri with the planes made (pa NULL: made here when needed) */
int fpc_tri_tri_pl(const double a[3][3], const tplane *pa, const double b[3][3], const tplane *pb)
{
    /* each vertex against the other's plane, once (every edge test starts with these); a
     * triangle certainly on one side of the other's plane shares no point with it */
    int oa[3], ob[3];
    for (int i = 0; i < 3; i++) oa[i] = plane_side(pb, a[i]);
    if (oa[0] && oa[0] == oa[1] && oa[1] == oa[2]) return 0;
    tplane own;
    if (!pa) {
        plane_of(a, &own);
        pa = &own;
    }
    for (int i = 0; i < 3; i++) ob[i] = plane_side(pa, b[i]);
    if (ob[0] && ob[0] == ob[1] && ob[1] == ob[2]) return 0;
    for (int e = 0; e < 3; e++) {
        int f = (e + 1) % 3;
        if (seg_tri(a[e], a[f], b, oa[e], oa[f]) || seg_tri(b[e], b[f], a, ob[e], ob[f])) return 1;
    }
    return 0;
}

int fp_contact_tri_tri(const double a[3][3], const double b[3][3])
{
    tplane pb;
    plane_of(b, &pb);
    return fpc_tri_tri_pl(a, NULL, b, &pb);
}
