/* Placing a rig on a moved copy of its mesh (fp_rig.h, fp_rig_placement): the similarity that
 * carries the landmarks' positions on the rig's own mesh to their vertices on the mesh bound
 * (Horn 1987, closed form with unit quaternions), and the rig's geometry carried by it. */
#define _GNU_SOURCE /* M_PI */
#include "fp_rig_internal.h"

#include "fp_vec.h"

#include <assert.h>
#include <math.h>
#include <string.h>

/* ---- the file's geometry, kept and restored ---- */

static void geom_get(const fp_rig *r, rig_geom *g)
{
    g->mm_per_unit = r->mm_per_unit;
    memcpy(g->up, r->up, sizeof g->up);
    memcpy(g->fwd, r->fwd, sizeof g->fwd);
    memcpy(g->left, r->left, sizeof g->left);
    memcpy(g->hinge_r, r->hinge_r, sizeof g->hinge_r);
    memcpy(g->hinge_l, r->hinge_l, sizeof g->hinge_l);
    memcpy(g->axis, r->axis, sizeof g->axis);
    memcpy(g->glide, r->glide, sizeof g->glide);
    memcpy(g->mouth, r->mouth, sizeof g->mouth);
    g->lip_band = r->lip_band, g->cheek_band = r->cheek_band, g->cheek_distance = r->cheek_distance;
    g->corner_inset = r->corner_inset, g->inner_depth = r->inner_depth;
    memcpy(g->menton, r->menton, sizeof g->menton);
    memcpy(g->gonion, r->gonion, sizeof g->gonion);
    g->neck_band = r->neck_band, g->back_band = r->back_band, g->ramp = r->ramp;
}

static void geom_set(fp_rig *r, const rig_geom *g)
{
    r->mm_per_unit = g->mm_per_unit;
    memcpy(r->up, g->up, sizeof r->up);
    memcpy(r->fwd, g->fwd, sizeof r->fwd);
    memcpy(r->left, g->left, sizeof r->left);
    memcpy(r->hinge_r, g->hinge_r, sizeof r->hinge_r);
    memcpy(r->hinge_l, g->hinge_l, sizeof r->hinge_l);
    memcpy(r->axis, g->axis, sizeof r->axis);
    memcpy(r->glide, g->glide, sizeof r->glide);
    memcpy(r->mouth, g->mouth, sizeof r->mouth);
    r->lip_band = g->lip_band, r->cheek_band = g->cheek_band, r->cheek_distance = g->cheek_distance;
    r->corner_inset = g->corner_inset, r->inner_depth = g->inner_depth;
    memcpy(r->menton, g->menton, sizeof r->menton);
    memcpy(r->gonion, g->gonion, sizeof r->gonion);
    r->neck_band = g->neck_band, r->back_band = g->back_band, r->ramp = g->ramp;
}

void fpr_geom_keep(fp_rig *r) { geom_get(r, &r->parsed); }

/* ---- the fit ---- */

/* The unit eigenvector of the largest eigenvalue of the symmetric 4 x 4 matrix a (destroyed):
 * cyclic Jacobi rotations until the off-diagonal part vanishes (double precision; a handful
 * of sweeps for 4 x 4). */
static void top_eigenvector(double a[4][4], double q[4])
{
    double v[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    for (int sweep = 0; sweep < 64; sweep++) {
        double off = 0, diag = 0;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++) {
                if (i == j) diag += a[i][j] * a[i][j];
                else off += a[i][j] * a[i][j];
            }
        if (off <= 1e-30 * diag || off == 0) break;
        for (int p = 0; p < 3; p++)
            for (int k = p + 1; k < 4; k++) {
                if (a[p][k] == 0) continue;
                double th = (a[k][k] - a[p][p]) / (2 * a[p][k]);
                double t = (th >= 0 ? 1 : -1) / (fabs(th) + sqrt(th * th + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int i = 0; i < 4; i++) { /* columns p, k */
                    double aip = a[i][p], aik = a[i][k];
                    a[i][p] = c * aip - s * aik;
                    a[i][k] = s * aip + c * aik;
                }
                for (int i = 0; i < 4; i++) { /* rows p, k */
                    double api = a[p][i], aki = a[k][i];
                    a[p][i] = c * api - s * aki;
                    a[k][i] = s * api + c * aki;
                }
                for (int i = 0; i < 4; i++) {
                    double vip = v[i][p], vik = v[i][k];
                    v[i][p] = c * vip - s * vik;
                    v[i][k] = s * vip + c * vik;
                }
            }
    }
    int best = 0;
    for (int i = 1; i < 4; i++)
        if (a[i][i] > a[best][best]) best = i;
    double l = 0;
    for (int i = 0; i < 4; i++) l += v[i][best] * v[i][best];
    for (int i = 0; i < 4; i++) q[i] = v[i][best] / sqrt(l);
}

typedef struct simil {
    double s, R[3][3], t[3];
} simil;

static void apply(const simil *m, const double x[3], double out[3])
{
    double y[3];
    for (int i = 0; i < 3; i++) y[i] = m->s * (m->R[i][0] * x[0] + m->R[i][1] * x[1] + m->R[i][2] * x[2]) + m->t[i];
    memcpy(out, y, sizeof y);
}

static void rotate(const simil *m, double x[3])
{
    double y[3];
    for (int i = 0; i < 3; i++) y[i] = m->R[i][0] * x[0] + m->R[i][1] * x[1] + m->R[i][2] * x[2];
    memcpy(x, y, sizeof y);
}

/* The similarity b ~ s R a + t over the k pairs (Horn 1987: R from the quaternion maximising
 * sum b'.(R a'), primes about the centroids, section 4; s the symmetric scale of section 2.D,
 * sqrt(sum |b'|^2 / sum |a'|^2)). Returns false when either set has no spread. */
static bool fit(const double (*a)[3], const double (*b)[3], size_t k, simil *m, double *spread_b)
{
    double ca[3] = {0, 0, 0}, cb[3] = {0, 0, 0};
    for (size_t i = 0; i < k; i++)
        for (int j = 0; j < 3; j++) ca[j] += a[i][j] / (double)k, cb[j] += b[i][j] / (double)k;
    double S[3][3] = {{0}}, sa = 0, sb = 0;
    for (size_t i = 0; i < k; i++) {
        double p[3], q[3];
        for (int j = 0; j < 3; j++) p[j] = a[i][j] - ca[j], q[j] = b[i][j] - cb[j];
        for (int x = 0; x < 3; x++)
            for (int y = 0; y < 3; y++) S[x][y] += p[x] * q[y];
        sa += p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        sb += q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
    }
    *spread_b = sqrt(sb / (double)k);
    if (!(sa > 0) || !(sb > 0)) return false;
    double N[4][4] = {
        {S[0][0] + S[1][1] + S[2][2], S[1][2] - S[2][1], S[2][0] - S[0][2], S[0][1] - S[1][0]},
        {S[1][2] - S[2][1], S[0][0] - S[1][1] - S[2][2], S[0][1] + S[1][0], S[2][0] + S[0][2]},
        {S[2][0] - S[0][2], S[0][1] + S[1][0], -S[0][0] + S[1][1] - S[2][2], S[1][2] + S[2][1]},
        {S[0][1] - S[1][0], S[2][0] + S[0][2], S[1][2] + S[2][1], -S[0][0] - S[1][1] + S[2][2]}};
    double q[4];
    top_eigenvector(N, q);
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double R[3][3] = {{w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)},
                      {2 * (y * x + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)},
                      {2 * (z * x - w * y), 2 * (z * y + w * x), w * w - x * x - y * y + z * z}};
    memcpy(m->R, R, sizeof R);
    m->s = sqrt(sb / sa);
    double ra[3] = {ca[0], ca[1], ca[2]};
    rotate(m, ra);
    for (int j = 0; j < 3; j++) m->t[j] = cb[j] - m->s * ra[j];
    return true;
}

/* ---- the placement ---- */

void fpr_place(fp_rig *r, const float *pos)
{
    geom_set(r, &r->parsed);
    memset(&r->placement, 0, sizeof r->placement);
    r->placement.scale = 1;
    size_t k = r->landmark_count;
    if (!r->has_ref || k < 3) return;
    double a[FP_RIG_MAX_LANDMARKS][3], b[FP_RIG_MAX_LANDMARKS][3];
    for (size_t i = 0; i < k; i++)
        for (int j = 0; j < 3; j++) {
            a[i][j] = r->landmarks[i].ref[j];
            b[i][j] = pos[3 * (size_t)r->landmarks[i].vertex + j];
        }
    simil m;
    double spread;
    if (!fit((const double (*)[3])a, (const double (*)[3])b, k, &m, &spread)) return;
    double moved = 0, rss = 0;
    for (size_t i = 0; i < k; i++) {
        double y[3], dm = 0, dr = 0;
        apply(&m, a[i], y);
        for (int j = 0; j < 3; j++) {
            dm += (y[j] - a[i][j]) * (y[j] - a[i][j]);
            dr += (y[j] - b[i][j]) * (y[j] - b[i][j]);
        }
        moved = fmax(moved, sqrt(dm));
        rss += dr;
    }
    fp_rig_placement *pl = &r->placement;
    pl->rms = sqrt(rss / (double)k);
    pl->spread = spread;
    double tr = m.R[0][0] + m.R[1][1] + m.R[2][2];
    pl->degrees = acos(fmax(-1.0, fmin(1.0, 0.5 * (tr - 1)))) * 180.0 / M_PI;
    if (moved <= FP_RIG_PLACE_SAME * spread || pl->rms > FP_RIG_PLACE_MISFIT * spread) return;
    pl->placed = 1;
    pl->scale = m.s;
    memcpy(pl->shift, m.t, sizeof pl->shift);
    /* the rig's coordinates carried, its directions turned, its lengths scaled */
    rotate(&m, r->up);
    rotate(&m, r->fwd);
    rotate(&m, r->left);
    rotate(&m, r->axis);
    apply(&m, r->hinge_r, r->hinge_r);
    apply(&m, r->hinge_l, r->hinge_l);
    for (size_t i = 0; i < r->mouth_count; i++) apply(&m, r->mouth[i], r->mouth[i]);
    apply(&m, r->menton, r->menton);
    apply(&m, r->gonion, r->gonion);
    double *len[] = {&r->glide[0], &r->glide[1], &r->lip_band, &r->cheek_band, &r->cheek_distance,
                     &r->corner_inset, &r->inner_depth, &r->neck_band, &r->back_band, &r->ramp};
    for (size_t i = 0; i < sizeof len / sizeof len[0]; i++) *len[i] *= m.s;
    r->mm_per_unit /= m.s;
    assert(fabs(r->up[0] * r->fwd[0] + r->up[1] * r->fwd[1] + r->up[2] * r->fwd[2]) < 1e-6);
}

fp_rig_placement fp_rig_get_placement(const fp_rig *r)
{
    fp_rig_placement none = {0};
    return r ? r->placement : none;
}

void fp_rig_face_rotation(const fp_rig *r, double q[4])
{
    q[0] = 1, q[1] = q[2] = q[3] = 0;
    if (r) fp_quat_from_axes(r->left, r->up, r->fwd, q); /* (left = up x forward, fp_rig_parse) */
}
