/* Placing a rig on a moved copy of its mesh (fp_rig.h, fp_rig_placement): the similarity that
 * carries the landmarks' positions on the rig's own mesh to their vertices on the mesh bound
 * (fp_similarity_fit, as calibrate's touch fit), and the rig's geometry carried by it. */
#define _GNU_SOURCE /* M_PI */
#include "fp_rig_internal.h"

#include "fp_similarity.h"
#include "fp_vec.h"

#include <assert.h>
#include <math.h>
#include <string.h>

/* x := s R x + t (q: R) */
static void carry(double s, const double q[4], const double t[3], double x[3])
{
    double y[3];
    fp_qrot(q, x, y);
    for (int i = 0; i < 3; i++) x[i] = s * y[i] + t[i];
}

/* x := R x */
static void turn(const double q[4], double x[3])
{
    double y[3];
    fp_qrot(q, x, y);
    memcpy(x, y, sizeof y);
}

/* Whether the k landmarks a (the rig's) fit b (the mesh's) mirrored: a's x negated, then the
 * best similarity, within FP_RIG_PLACE_MIRROR x spread (b's RMS spread). A mirrored copy of a
 * rig's mesh (x -> -x in a modeller) has its vertex count and fits no similarity (the ICT
 * face's landmarks 4.14 units off against a spread of 6.1), so it was told it is another face. */
static int mirror_fits(const double (*a)[3], const double (*b)[3], size_t k, double spread)
{
    double m[FP_RIG_MAX_LANDMARKS][3], s, q[4], t[3], rss = 0;
    for (size_t i = 0; i < k; i++) m[i][0] = -a[i][0], m[i][1] = a[i][1], m[i][2] = a[i][2];
    if (fp_similarity_fit((const double (*)[3])m, b, k, &s, q, t)) return 0;
    for (size_t i = 0; i < k; i++) {
        double y[3] = {m[i][0], m[i][1], m[i][2]};
        carry(s, q, t, y);
        for (int j = 0; j < 3; j++) rss += (y[j] - b[i][j]) * (y[j] - b[i][j]);
    }
    return sqrt(rss / (double)k) <= FP_RIG_PLACE_MIRROR * spread;
}

void fpr_place(fp_rig *r, const float *pos)
{
    r->geom = r->parsed;
    memset(&r->placement, 0, sizeof r->placement);
    r->placement.scale = 1;
    size_t k = r->landmark_count;
    if (!r->has_ref || k < 3) return;
    double a[FP_RIG_MAX_LANDMARKS][3], b[FP_RIG_MAX_LANDMARKS][3], cb[3] = {0, 0, 0};
    for (size_t i = 0; i < k; i++)
        for (int j = 0; j < 3; j++) {
            a[i][j] = r->landmarks[i].ref[j];
            b[i][j] = pos[3 * (size_t)r->landmarks[i].vertex + j];
            cb[j] += b[i][j] / (double)k;
        }
    double s, q[4], t[3];
    if (fp_similarity_fit((const double (*)[3])a, (const double (*)[3])b, k, &s, q, t)) return;
    double moved = 0, rss = 0, spread = 0;
    for (size_t i = 0; i < k; i++) {
        double y[3] = {a[i][0], a[i][1], a[i][2]}, dm = 0, dr = 0;
        carry(s, q, t, y);
        for (int j = 0; j < 3; j++) {
            dm += (y[j] - a[i][j]) * (y[j] - a[i][j]);
            dr += (y[j] - b[i][j]) * (y[j] - b[i][j]);
            spread += (b[i][j] - cb[j]) * (b[i][j] - cb[j]);
        }
        moved = fmax(moved, sqrt(dm));
        rss += dr;
    }
    fp_rig_placement *pl = &r->placement;
    pl->rms = sqrt(rss / (double)k);
    pl->spread = sqrt(spread / (double)k);
    pl->degrees = 2 * acos(fmin(1.0, q[0])) * 180.0 / M_PI; /* (w >= 0) */
    pl->misfit = pl->rms > FP_RIG_PLACE_MISFIT * pl->spread;
    if (pl->misfit) pl->mirrored = mirror_fits((const double (*)[3])a, (const double (*)[3])b, k, pl->spread);
    if (moved <= FP_RIG_PLACE_SAME * pl->spread || pl->rms > FP_RIG_PLACE_MISFIT * pl->spread) return;
    pl->placed = 1;
    pl->scale = s;
    memcpy(pl->shift, t, sizeof pl->shift);
    /* the rig's coordinates carried, its directions turned, its lengths scaled */
    rig_geom *g = &r->geom;
    turn(q, g->up);
    turn(q, g->fwd);
    turn(q, g->left);
    turn(q, g->axis);
    carry(s, q, t, g->hinge_r);
    carry(s, q, t, g->hinge_l);
    for (size_t i = 0; i < r->mouth_count; i++) carry(s, q, t, g->mouth[i]);
    carry(s, q, t, g->menton);
    carry(s, q, t, g->gonion);
    double *len[] = {&g->glide[0], &g->glide[1], &g->lip_band, &g->cheek_band, &g->cheek_distance,
                     &g->corner_inset, &g->inner_depth, &g->neck_band, &g->back_band, &g->ramp};
    for (size_t i = 0; i < sizeof len / sizeof len[0]; i++) *len[i] *= s;
    g->mm_per_unit /= s;
    assert(fabs(fp_dot3(g->up, g->fwd)) < 1e-6);
}

fp_rig_placement fp_rig_get_placement(const fp_rig *r)
{
    fp_rig_placement none = {0};
    return r ? r->placement : none;
}

void fp_rig_face_rotation(const fp_rig *r, double q[4])
{
    q[0] = 1, q[1] = q[2] = q[3] = 0;
    if (r) fp_quat_from_axes(r->geom.left, r->geom.up, r->geom.fwd, q); /* (left = up x forward) */
}
