/* csrbf fold-over guard: the injectivity bound of the solved map (a Lipschitz bound on
 * f = T - id from the coefficients, per cluster of overlapping supports), the anchored limit
 * (scale a cluster's coefficients back) and the unanchored guarded step (composed
 * sub-steps). The maths is in csrbf.h ("fold-over guard") and ../shared/docs/csrbf.md
 * pitfall 4. */
#include "internal.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* |psi'(r)| on [0, 1] and its maximiser r*: |psi'| rises on [0, r*] and falls on [r*, 1]
 * for the three kernels (psi30: r* = 0; psi31: 20 r (1-r)^3, r* = 1/4; psi32:
 * (56/3) r (1-r)^5 (5r+1), whose derivative is a multiple of (1-r)^4 (1 + 4r - 35r^2), so
 * r* = (2 + sqrt(39)) / 35). */
static double dpsi_abs(csrbf_kernel k, double r)
{
    if (r >= 1.0) return 0.0;
    if (k == CSRBF_PSI30) return 2.0 * (1.0 - r);
    return fabs(csrbf_dpsi_over_r(k, r) * r);
}

static double dpsi_argmax(csrbf_kernel k)
{
    switch (k) {
    case CSRBF_PSI30: return 0.0;
    case CSRBF_PSI32: return (2.0 + sqrt(39.0)) / 35.0;
    case CSRBF_PSI31:
    default: return 0.25;
    }
}

/* w(a) = max over r in [max(a, 0), 1] of |psi'(r)|. */
static double dpsi_max_from(csrbf_kernel k, double a)
{
    double rs = dpsi_argmax(k);
    return dpsi_abs(k, a > rs ? a : rs);
}

void csrbf_guard_free(csrbf_solver *s)
{
    free(s->gn_start);
    free(s->gn_idx);
    free(s->gn_w);
    free(s->cluster);
    free(s->cl_L);
    free(s->cl_t);
    free(s->anorm);
    free(s->gg_u32);
    free(s->gg_f64);
    free(s->g_p);
    free(s->g_e);
    free(s->g_blk);
    csrbf_points_destroy(&s->g_tmp);
    s->gn_start = NULL;
    s->gn_idx = NULL;
    s->gn_w = NULL;
    s->cluster = NULL;
    s->cl_L = s->cl_t = s->anorm = NULL;
    s->gg_u32 = s->gg_group = s->gg_start = s->gg_idx = NULL;
    s->gg_f64 = s->gg_c = s->gg_r = NULL;
    s->ngroups = 0;
    s->g_p = s->g_e = NULL;
    s->g_blk = NULL;
    s->gn_cap = s->g_cap = s->g_bcap = 0;
}

static uint32_t uf_find(uint32_t *par, uint32_t i)
{
    while (par[i] != i) {
        par[i] = par[par[i]];
        i = par[i];
    }
    return i;
}

/* csrbf_guard_prepare's test of centre j as a neighbour of centre i (csrbf_grid_near; within
 * 2R, R2x4 = 4R^2): appended to the lists (gn_idx, gn_w from nnz on) and joined to i's
 * cluster. 0 or CSRBF_ERR_NOMEM. */
typedef struct {
    csrbf_solver *s;
    size_t i, nnz;
    double R2x4;
} neighbour_ctx;

static int neighbour_try(void *ctx, uint32_t j)
{
    neighbour_ctx *q = ctx;
    csrbf_solver *s = q->s;
    const double *ci = s->c + 3 * q->i, *cj = s->c + 3 * (size_t)j;
    double d0 = ci[0] - cj[0], d1 = ci[1] - cj[1], d2 = ci[2] - cj[2];
    double r2 = d0 * d0 + d1 * d1 + d2 * d2;
    if (r2 >= q->R2x4) return CSRBF_OK;
    if (q->nnz == s->gn_cap) {
        size_t cap = 2 * s->gn_cap;
        uint32_t *ni = realloc(s->gn_idx, cap * sizeof *ni);
        if (!ni) return CSRBF_ERR_NOMEM;
        s->gn_idx = ni;
        double *nw = realloc(s->gn_w, cap * sizeof *nw);
        if (!nw) return CSRBF_ERR_NOMEM;
        s->gn_w = nw;
        s->gn_cap = cap;
    }
    s->gn_idx[q->nnz] = j;
    s->gn_w[q->nnz] = dpsi_max_from(s->opt.kernel, sqrt(r2) * s->inv_R - 1.0) * s->inv_R;
    q->nnz++;
    uint32_t *cl = s->cluster, ri = uf_find(cl, (uint32_t)q->i), rj = uf_find(cl, j);
    if (ri != rj) cl[ri > rj ? ri : rj] = ri < rj ? ri : rj;
    return CSRBF_OK;
}

/* The largest norm of the Hessian of psi(|x|) over x, max over r of |psi''(r)| and
 * |psi'(r) / r| (the eigenvalues), for the kernels whose Hessian is bounded: psi31
 * (psi' = -20 r (1-r)^3, psi'' = -20 (1-r)^2 (1 - 4r): 20 at r = 0) and psi32 (psi' / r =
 * -(56/3) (1-r)^5 (5r+1), psi'' = -(56/3) (1-r)^4 (1 + 4r - 35r^2): 56/3 at r = 0). 0 for
 * psi30, a cone at its centre: no pair term. */
static double hessian_max(csrbf_kernel k)
{
    switch (k) {
    case CSRBF_PSI31: return 20.0;
    case CSRBF_PSI32: return 56.0 / 3.0;
    case CSRBF_PSI30:
    default: return 0.0;
    }
}

/* Close groups for the bound's group terms (group_term): each centre joins the first group
 * whose leader (its first centre) lies under CSRBF_GUARD_GROUP_GAP x R from it, else leads
 * a new one; groups of one centre are dropped. Fills gg_group, gg_start, gg_idx, gg_c, gg_r,
 * ngroups. m is a few dozen fingertips at most: O(m^2). */
static void close_groups(csrbf_solver *s)
{
    const size_t m = s->m;
    const double gap2 = CSRBF_GUARD_GROUP_GAP * CSRBF_GUARD_GROUP_GAP * s->R * s->R;
    uint32_t *lead = s->gg_idx, *count = s->gg_start; /* scratch first */
    size_t nl = 0;
    s->ngroups = 0;
    for (size_t i = 0; i < m; i++) s->gg_group[i] = UINT32_MAX;
    if (hessian_max(s->opt.kernel) == 0.0) return;
    for (size_t i = 0; i < m; i++) {
        const double *ci = s->c + 3 * i;
        size_t g = nl;
        for (size_t l = 0; l < nl && g == nl; l++) {
            const double *cl = s->c + 3 * (size_t)lead[l];
            double d0 = ci[0] - cl[0], d1 = ci[1] - cl[1], d2 = ci[2] - cl[2];
            if (d0 * d0 + d1 * d1 + d2 * d2 < gap2) g = l;
        }
        if (g == nl) {
            lead[nl] = (uint32_t)i;
            count[nl++] = 0;
        }
        s->gg_group[i] = (uint32_t)g;
        count[g]++;
    }
    /* number the groups of two or more 0..ngroups-1 (the provisional number g >= the new) */
    size_t ng = 0;
    for (size_t l = 0; l < nl; l++) lead[l] = count[l] > 1 ? (uint32_t)ng++ : UINT32_MAX;
    for (size_t i = 0; i < m; i++) s->gg_group[i] = lead[s->gg_group[i]];
    s->ngroups = ng;
    memset(s->gg_start, 0, (ng + 1) * sizeof *s->gg_start);
    for (size_t i = 0; i < m; i++)
        if (s->gg_group[i] != UINT32_MAX) s->gg_start[s->gg_group[i] + 1]++;
    for (size_t g = 0; g < ng; g++) s->gg_start[g + 1] += s->gg_start[g];
    memset(s->gg_c, 0, 3 * ng * sizeof *s->gg_c);
    for (size_t g = 0; g < ng; g++) s->gg_r[g] = 0.0; /* (fill counts, in gg_r for now) */
    for (size_t i = 0; i < m; i++) {
        uint32_t g = s->gg_group[i];
        if (g == UINT32_MAX) continue;
        s->gg_idx[s->gg_start[g] + (size_t)s->gg_r[g]] = (uint32_t)i;
        s->gg_r[g] += 1.0;
        for (int a = 0; a < 3; a++) s->gg_c[3 * g + a] += s->c[3 * i + a];
    }
    for (size_t g = 0; g < ng; g++)
        for (int a = 0; a < 3; a++) s->gg_c[3 * g + a] /= (double)(s->gg_start[g + 1] - s->gg_start[g]);
    for (size_t i = 0; i < m; i++) {
        uint32_t g = s->gg_group[i];
        double r2 = 0.0;
        if (g != UINT32_MAX)
            for (int a = 0; a < 3; a++) r2 += (s->c[3 * i + a] - s->gg_c[3 * g + a]) * (s->c[3 * i + a] - s->gg_c[3 * g + a]);
        s->gg_r[i] = sqrt(r2);
    }
}

int csrbf_guard_prepare(csrbf_solver *s)
{
    size_t m = s->m;
    size_t *st = realloc(s->gn_start, (m + 1) * sizeof *st);
    if (!st) return CSRBF_ERR_NOMEM;
    s->gn_start = st;
    uint32_t *cl = realloc(s->cluster, (m ? m : 1) * sizeof *cl);
    if (!cl) return CSRBF_ERR_NOMEM;
    s->cluster = cl;
    double *a = realloc(s->cl_L, (m ? m : 1) * sizeof *a);
    if (!a) return CSRBF_ERR_NOMEM;
    s->cl_L = a;
    a = realloc(s->cl_t, (m ? m : 1) * sizeof *a);
    if (!a) return CSRBF_ERR_NOMEM;
    s->cl_t = a;
    a = realloc(s->anorm, (m ? m : 1) * sizeof *a);
    if (!a) return CSRBF_ERR_NOMEM;
    s->anorm = a;
    memset(s->anorm, 0, (m ? m : 1) * sizeof *a);
    uint32_t *gu = realloc(s->gg_u32, (4 * m + 1) * sizeof *gu);
    if (!gu) return CSRBF_ERR_NOMEM;
    s->gg_u32 = gu;
    s->gg_group = gu;
    s->gg_start = gu + m;
    s->gg_idx = gu + 2 * m + 1;
    double *gf = realloc(s->gg_f64, (4 * m + 1) * sizeof *gf);
    if (!gf) return CSRBF_ERR_NOMEM;
    s->gg_f64 = gf;
    s->gg_c = gf;
    s->gg_r = gf + 3 * m;
    if (!s->gn_cap) {
        s->gn_cap = 16 * (m ? m : 1);
        s->gn_idx = malloc(s->gn_cap * sizeof *s->gn_idx);
        s->gn_w = malloc(s->gn_cap * sizeof *s->gn_w);
        if (!s->gn_idx || !s->gn_w) {
            s->gn_cap = 0;
            return CSRBF_ERR_NOMEM;
        }
    }
    for (size_t i = 0; i < m; i++) cl[i] = (uint32_t)i; /* union-find parents */
    neighbour_ctx q = {s, 0, 0, 4.0 * s->R * s->R};
    for (size_t i = 0; i < m; i++) {
        st[i] = q.nnz;
        q.i = i;
        /* cells have side h >= R: neighbours within 2R lie within two cells */
        int rc = csrbf_grid_near(&s->cgrid, s->c + 3 * i, 2, neighbour_try, &q);
        if (rc) return rc;
    }
    size_t nnz = q.nnz;
    st[m] = nnz;
    /* number the clusters 0..nclusters-1 in order of their smallest centre */
    size_t nc = 0;
    for (size_t i = 0; i < m; i++) {
        uint32_t r = uf_find(cl, (uint32_t)i);
        if (r == i)
            s->cl_L[i] = (double)nc++; /* the root's new number, kept in cl_L for now */
    }
    for (size_t i = 0; i < m; i++) {
        uint32_t r = uf_find(cl, (uint32_t)i);
        s->cl_t[i] = s->cl_L[r];
    }
    for (size_t i = 0; i < m; i++) cl[i] = (uint32_t)s->cl_t[i];
    s->nclusters = nc;
    close_groups(s);
    return CSRBF_OK;
}

/* w(|c_i - p| / R - 1) / R, the largest |grad psi(|x - p| / R)| over centre i's support (0
 * where the supports do not overlap: neighbour_try's test) */
static double weight_at(const csrbf_solver *s, size_t i, const double *p)
{
    const double *ci = s->c + 3 * i;
    double d0 = ci[0] - p[0], d1 = ci[1] - p[1], d2 = ci[2] - p[2];
    double r2 = d0 * d0 + d1 * d1 + d2 * d2;
    if (r2 >= 4.0 * s->R * s->R) return 0.0;
    return dpsi_max_from(s->opt.kernel, sqrt(r2) * s->inv_R - 1.0) * s->inv_R;
}

/* A close group's share of row i's bound. With c its mean centre, the group's gradient
 * terms are (sum_j alpha_j) grad psi_c + sum_j alpha_j (grad psi_j - grad psi_c), and
 * |grad psi_j - grad psi_c| <= min(H |c_j - c| / R^2, w_ij + w_ic) (H: hessian_max; the
 * gradient of psi(|x - p| / R) is H / R^2-Lipschitz in p, psi31 and psi32 being C^2).
 * Fingertips on close skin moving apart, together or round each other have large
 * coefficients of opposite signs whose fields cancel but for their differences, which the
 * plain terms count whole: skin pulled apart from 0.01 R needed 13 maps under this bound
 * from the 4th map on, where 16 plain ones delivered 1.4% (tests/csrbf/test_guard.c). The smaller of this and the plain terms. */
static double group_term(const csrbf_solver *s, size_t i, uint32_t g)
{
    const double wc = weight_at(s, i, s->gg_c + 3 * (size_t)g);
    const double h = hessian_max(s->opt.kernel) * s->inv_R * s->inv_R;
    double sum[3] = {0, 0, 0}, plain = 0.0, spread = 0.0;
    for (uint32_t t = s->gg_start[g]; t < s->gg_start[g + 1]; t++) {
        size_t j = s->gg_idx[t];
        double wj = weight_at(s, i, s->c + 3 * j);
        for (int a = 0; a < 3; a++) sum[a] += s->alpha[3 * j + a];
        plain += s->anorm[j] * wj;
        spread += s->anorm[j] * fmin(h * s->gg_r[j], wj + wc);
    }
    double grouped = sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]) * wc + spread;
    return fmin(grouped, plain);
}

/* Row i of the bound: sum over the centres j within 2R of |alpha_j| w_ij; with g_paired,
 * close groups by group_term, each once (at its first member within 2R of centre i). */
static double row_bound(const csrbf_solver *s, size_t i)
{
    double L = 0.0;
    for (size_t t = s->gn_start[i]; t < s->gn_start[i + 1]; t++) {
        size_t j = s->gn_idx[t];
        uint32_t g = s->g_paired ? s->gg_group[j] : UINT32_MAX;
        if (g == UINT32_MAX) {
            L += s->gn_w[t] * s->anorm[j];
            continue;
        }
        bool first = true;
        for (uint32_t u = s->gg_start[g]; u < s->gg_start[g + 1] && first; u++) {
            size_t k = s->gg_idx[u];
            if (k < j && weight_at(s, i, s->c + 3 * k) > 0.0) first = false;
        }
        if (first) L += group_term(s, i, g);
    }
    return L;
}

/* Per-cluster bounds into cl_L (without the polynomial term); returns ||B||_F. */
static double cluster_bounds(const csrbf_solver *s, double *cl_L)
{
    for (size_t c = 0; c < s->nclusters; c++) cl_L[c] = 0.0;
    for (size_t i = 0; i < s->m; i++) {
        double L = row_bound(s, i);
        size_t c = s->cluster[i];
        if (L > cl_L[c]) cl_L[c] = L;
    }
    double b2 = 0.0;
    if (s->k > 0)
        for (int l = 1; l < 4; l++)
            for (int a = 0; a < 3; a++) b2 += s->g[l][a] * s->g[l][a];
    return sqrt(b2) * s->inv_R;
}

static double total_bound(const csrbf_solver *s)
{
    double L = 0.0;
    for (size_t i = 0; i < s->m; i++) {
        double v = row_bound(s, i);
        if (v > L) L = v;
    }
    double b2 = 0.0;
    if (s->k > 0)
        for (int l = 1; l < 4; l++)
            for (int a = 0; a < 3; a++) b2 += s->g[l][a] * s->g[l][a];
    return L + sqrt(b2) * s->inv_R;
}

int csrbf_solver_injectivity(const csrbf_solver *s, double *bound)
{
    if (!s || !bound) return CSRBF_ERR_INVALID;
    if (!s->have_start) return CSRBF_ERR_STATE;
    *bound = total_bound(s);
    return CSRBF_OK;
}

static void scale_centre(csrbf_solver *s, size_t i, double t)
{
    for (int a = 0; a < 3; a++) {
        s->alpha[3 * i + a] *= t;
        s->fa[a][i] = (float)s->alpha[3 * i + a];
    }
    s->anorm[i] *= t;
}

int csrbf_solver_limit_end_points(csrbf_solver *s, double margin, csrbf_guard_stats *st)
{
    if (!s) return CSRBF_ERR_INVALID;
    if (margin == 0.0) margin = CSRBF_GUARD_MARGIN;
    if (!(margin > 0.0 && margin < 1.0)) {
        snprintf(s->msg, sizeof s->msg, "margin %g must be in (0, 1)", margin);
        s->lim_note.pending = 0;
        return CSRBF_ERR_INVALID;
    }
    if (!s->have_start) {
        snprintf(s->msg, sizeof s->msg, "limit_end_points before start points");
        s->lim_note.pending = 0;
        return CSRBF_ERR_STATE;
    }
    size_t nc = s->nclusters, limited = 0;
    double Bf = cluster_bounds(s, s->cl_L);
    double before = Bf, tmin = 1.0;
    for (size_t c = 0; c < nc; c++) before = fmax(before, s->cl_L[c] + Bf);
    if (s->k > 0) { /* the polynomial couples every centre: one scale for the whole map */
        double t = before > margin ? margin / before : 1.0;
        for (size_t c = 0; c < nc; c++) s->cl_t[c] = t;
        if (t < 1.0) {
            limited = nc;
            tmin = t;
            for (size_t i = 0; i < s->m; i++) scale_centre(s, i, t);
            for (int l = 0; l < 4; l++)
                for (int a = 0; a < 3; a++) s->g[l][a] *= t;
            for (int a = 0; a < 3; a++) {
                s->fg0[a] = (float)s->g[0][a];
                for (int l = 0; l < 3; l++) s->fG[a * 3 + l] = (float)(s->g[l + 1][a] * s->inv_R);
            }
        }
    } else {
        for (size_t c = 0; c < nc; c++) {
            double L = s->cl_L[c];
            s->cl_t[c] = L > margin ? margin / L : 1.0;
            if (s->cl_t[c] < 1.0) {
                limited++;
                if (s->cl_t[c] < tmin) tmin = s->cl_t[c];
            }
        }
        if (limited)
            for (size_t i = 0; i < s->m; i++) {
                double t = s->cl_t[s->cluster[i]];
                if (t < 1.0) scale_centre(s, i, t);
            }
    }
    if (st) {
        memset(st, 0, sizeof *st);
        st->bound_before = before;
        st->bound_after = limited ? total_bound(s) : before;
        st->clusters = nc;
        st->clusters_limited = limited;
        st->min_scale = tmin;
        st->substeps = 1;
        st->reached = tmin;
        st->eval.min_jacobian_det = 1.0;
    }
    if (!limited) return CSRBF_OK;
    csrbf_msg_flush(s); /* an earlier call's note first */
    /* the sentence is written when the message is read (csrbf_msg_flush) */
    s->lim_note.pending = 1;
    s->lim_note.limited = limited;
    s->lim_note.clusters = nc;
    s->lim_note.before = before;
    s->lim_note.margin = margin;
    s->lim_note.tmin = tmin;
    s->warnings |= 1u << CSRBF_WARN_LIMITED;
    return CSRBF_WARN_LIMITED;
}

/* The support-following form's state (csrbf_guarded_step_touched): U, the blocks where the
 * output may differ from the shape (increasing); C, the blocks the last sub-step computed;
 * W, the blocks the touch's last call had computed (written again: restored or computed);
 * M, a merge's scratch; R, vertex ranges. */
typedef struct follow {
    csrbf_touch *touch, *itouch;
    csrbf_points *inter;
    uint32_t *U, *C, *W, *M, *R;
    size_t ku, kc, kw;
    int wall;      /* the touch's last call was to write every block */
    int inter_set; /* inter holds an intermediate shape at U's blocks */
} follow;

/* out := the increasing lists a[0 .. ka) and b[0 .. kb) merged, each block once; returns
 * its length */
static size_t merge_blocks(const uint32_t *a, size_t ka, const uint32_t *b, size_t kb, uint32_t *out)
{
    size_t i = 0, j = 0, k = 0;
    while (i < ka || j < kb) {
        if (j == kb || (i < ka && a[i] < b[j])) out[k++] = a[i++];
        else {
            if (i < ka && a[i] == b[j]) i++;
            out[k++] = b[j++];
        }
    }
    return k;
}

/* U := U and C, through M */
static void follow_union(follow *f)
{
    size_t k = merge_blocks(f->U, f->ku, f->C, f->kc, f->M);
    uint32_t *t = f->U;
    f->U = f->M;
    f->M = t;
    f->ku = k;
}

/* A composed step's moved count and max displacement against the input shape, where the
 * output may differ from it (every vertex, or the follow's U blocks). */
static void composed_moved(const csrbf_points *shape, const follow *fw, const float *deformed,
                           csrbf_eval_stats *ev)
{
    const float *b = shape->xyz;
    const size_t nv = csrbf_points_count(shape);
    size_t moved = 0, nb = fw ? fw->ku : 1;
    double md = 0.0;
    for (size_t k = 0; k < nb; k++) {
        size_t v0 = fw ? (size_t)fw->U[k] * CSRBF_BLOCK : 0,
               v1 = fw ? (v0 + CSRBF_BLOCK < nv ? v0 + CSRBF_BLOCK : nv) : nv;
        for (size_t v = v0; v < v1; v++) {
            double d0 = (double)deformed[3 * v] - b[3 * v], d1 = (double)deformed[3 * v + 1] - b[3 * v + 1],
                   d2 = (double)deformed[3 * v + 2] - b[3 * v + 2];
            double d = d0 * d0 + d1 * d1 + d2 * d2;
            moved += d > 0.0;
            if (d > md) md = d;
        }
    }
    ev->moved = moved;
    ev->max_displacement = sqrt(md);
}

/* guarded's move of the start points P (n x 3) toward the ends E after a sub-step: P_i +
 * t_C (E_i - P_i) (E_i itself when t_C = 1), t_C the scale of its cluster; for points merged
 * into one centre (more than one member), P_i + t_C H_g with H_g their mean E - P, which is
 * where the map took them. s->Y (set_end_points' scratch, room for 3 n) holds the sums. */
static void track_start_points(csrbf_solver *s, size_t n, float *P, const float *E)
{
    const size_t m = s->m;
    double *H = s->Y;
    if (m < n) {
        memset(H, 0, m * 3 * sizeof *H);
        for (size_t i = 0; i < n; i++)
            for (int a = 0; a < 3; a++)
                H[3 * s->group[i] + a] += (double)E[3 * i + a] - P[3 * i + a];
    }
    for (size_t i = 0; i < n; i++) {
        const size_t g = s->group[i];
        const double t = s->cl_t[s->cluster[g]];
        if (m < n && s->inv_count[g] < 1.0) {
            for (int a = 0; a < 3; a++)
                P[3 * i + a] = (float)(P[3 * i + a] + t * H[3 * g + a] * s->inv_count[g]);
            continue;
        }
        for (int a = 0; a < 3; a++)
            P[3 * i + a] = t < 1.0 ? (float)(P[3 * i + a] + t * (E[3 * i + a] - P[3 * i + a]))
                                   : E[3 * i + a];
    }
}

/* The sub-step from which guarded's maps are certified with the group terms: the last
 * quarter (at least 12) of the maps it may compose, max_substeps or, with a pair budget, the
 * map at which the budget will stop it at the pairs the maps so far averaged (j maps,
 * `pairs` pairs). Before it the plain bound (a long drag's many small maps, whose shape the
 * contact guard's figures were measured on); from it, skin pulled apart from a close pair
 * that the plain bound would stop short gets there in a few larger maps, still each one
 * injective. */
static int paired_from(int j, int maxk, uint64_t max_pairs, uint64_t pairs)
{
    int stop = maxk;
    if (max_pairs && j > 0 && pairs > 0) {
        double per = (double)pairs / j, at = ceil((double)max_pairs / per);
        int budget = at > CSRBF_GUARD_MAX_SUBSTEPS ? (at < maxk ? (int)at : maxk) : CSRBF_GUARD_MAX_SUBSTEPS;
        if (budget < stop) stop = budget;
    }
    int last = stop / 4 > 12 ? stop / 4 : 12;
    return stop - last;
}

static int guarded_maps(csrbf_solver *s, const csrbf_points *shape, follow *fw, size_t n,
                        const float *start, const float *end, const csrbf_guard *guard, float *deformed,
                        csrbf_guard_stats *st);

static int guarded(csrbf_solver *s, const csrbf_points *shape, follow *fw, size_t n,
                   const float *start, const float *end, const csrbf_guard *guard, float *deformed,
                   csrbf_guard_stats *st)
{
    s->g_paired = 0;
    int rc = guarded_maps(s, shape, fw, n, start, end, guard, deformed, st);
    s->g_paired = 0; /* the plain bound for every other caller */
    return rc;
}

static int guarded_maps(csrbf_solver *s, const csrbf_points *shape, follow *fw, size_t n,
                        const float *start, const float *end, const csrbf_guard *guard, float *deformed,
                        csrbf_guard_stats *st)
{
    double margin = guard && guard->margin != 0.0 ? guard->margin : CSRBF_GUARD_MARGIN;
    int maxk = guard && guard->max_substeps != 0 ? guard->max_substeps : CSRBF_GUARD_MAX_SUBSTEPS;
    unsigned flags = guard ? guard->eval_flags : 0u;
    const uint64_t max_pairs = guard ? guard->max_pairs : 0u;
    const bool counted = st || max_pairs; /* the evaluations' statistics are needed */
    if (!(margin > 0.0 && margin < 1.0) || maxk < 1) {
        s->lim_note.pending = 0;
        snprintf(s->msg, sizeof s->msg,
                 "guarded_step: margin %g must be in (0, 1) and max_substeps %d >= 1", margin, maxk);
        return CSRBF_ERR_INVALID;
    }
    if (n > s->g_cap) {
        float *p = realloc(s->g_p, n * 3 * sizeof *p);
        if (!p) return CSRBF_ERR_NOMEM;
        s->g_p = p;
        p = realloc(s->g_e, n * 3 * sizeof *p);
        if (!p) return CSRBF_ERR_NOMEM;
        s->g_e = p;
        s->g_cap = n;
    }
    float *P = s->g_p, *E = s->g_e;
    memcpy(P, start, n * 3 * sizeof *P);
    memcpy(E, end, n * 3 * sizeof *E);
    int reuse = s->have_start && s->n == n;
    for (size_t i = 0; i < 3 * n && reuse; i++) reuse = (double)start[i] == s->s_in[i];

    const csrbf_points *cur = shape;
    const size_t nv = csrbf_points_count(shape);
    csrbf_guard_stats out;
    memset(&out, 0, sizeof out);
    out.min_scale = 1.0;
    out.eval.min_jacobian_det = INFINITY; /* 1 at the end if no map moved a vertex */
    int rc;
    for (int j = 0;; j++) {
        if (j > 0 || !reuse) {
            rc = csrbf_solver_set_start_points(s, n, P);
            if (rc < 0) return rc;
        }
        rc = csrbf_solver_set_end_points(s, E);
        if (rc < 0) return rc;
        if (maxk > 1 && j >= paired_from(j, maxk, max_pairs, out.eval.pairs)) s->g_paired = 1;
        csrbf_guard_stats ls;
        rc = csrbf_solver_limit_end_points(s, margin, &ls);
        if (rc < 0) return rc;
        if (j == 0) {
            out.bound_before = ls.bound_before;
            out.clusters = ls.clusters;
            out.clusters_limited = ls.clusters_limited;
            out.min_scale = ls.min_scale;
        }
        if (ls.bound_after > out.bound_after) out.bound_after = ls.bound_after;
        csrbf_eval_stats es;
        if (!fw) {
            rc = csrbf_evaluate(s, cur, deformed, flags, counted ? &es : NULL);
        } else if (j == 0) { /* the shape's own touch: its blocks of the last call restored */
            const uint32_t *w = csrbf_touch_prev(fw->touch, &fw->kw, &fw->wall);
            memcpy(fw->W, w, fw->kw * sizeof *w);
            rc = csrbf_evaluate_touched(s, shape, fw->touch, deformed, flags, counted ? &es : NULL);
            const uint32_t *c = csrbf_touch_prev(fw->touch, &fw->kc, NULL);
            memcpy(fw->C, c, fw->kc * sizeof *c);
            memcpy(fw->U, c, fw->kc * sizeof *c);
            fw->ku = fw->kc;
        } else { /* on inter, the shape so far: only the blocks in this map's supports */
            csrbf_touch_commit(fw->itouch);
            rc = csrbf_evaluate_touched(s, fw->inter, fw->itouch, deformed, flags, counted ? &es : NULL);
            const uint32_t *c = csrbf_touch_prev(fw->itouch, &fw->kc, NULL);
            memcpy(fw->C, c, fw->kc * sizeof *c);
            follow_union(fw);
        }
        if (rc < 0) return rc;
        out.substeps = j + 1;
        if (counted) {
            out.eval.pairs += es.pairs; /* (also the budget's count) */
            if (es.moved && es.min_jacobian_det < out.eval.min_jacobian_det)
                out.eval.min_jacobian_det = es.min_jacobian_det;
            if (j == 0) {
                out.eval.moved = es.moved;
                out.eval.max_displacement = es.max_displacement;
            }
        }
        /* each start point travels its cluster's share of the rest of its control vector;
         * start points merged into one centre travel that share of their mean (the map
         * moves them together: set_start_points), which stops them short of their own ends */
        track_start_points(s, n, P, E);
        if (ls.clusters_limited == 0 || j + 1 >= maxk) break;
        if (max_pairs && j + 1 >= CSRBF_GUARD_MAX_SUBSTEPS && out.eval.pairs >= max_pairs) break;
        /* the next map acts on the shape so far */
        if (fw) { /* which differs from inter only where this map computed */
            fw->inter_set = 1;
            size_t nr = csrbf_block_ranges(fw->C, fw->kc, nv, fw->R);
            rc = csrbf_points_update_ranges(fw->inter, deformed, fw->R, nr);
            if (rc < 0) return rc;
            continue;
        }
        if (s->g_tmp && csrbf_points_count(s->g_tmp) != nv) csrbf_points_destroy(&s->g_tmp);
        rc = s->g_tmp ? csrbf_points_update(s->g_tmp, deformed)
                      : csrbf_points_create(nv, deformed, &s->g_tmp);
        if (rc < 0) return rc;
        cur = s->g_tmp;
    }
    /* how far each start point got along its control vector */
    double reached = 1.0;
    for (size_t i = 0; i < n; i++) {
        double full = 0.0, left = 0.0;
        for (int a = 0; a < 3; a++) {
            double f = (double)end[3 * i + a] - start[3 * i + a];
            double l = (double)end[3 * i + a] - P[3 * i + a];
            full += f * f;
            left += l * l;
        }
        if (full > 0.0) { /* (0: none of it, also for a merged point taken elsewhere) */
            double u = fmax(0.0, 1.0 - sqrt(left / full));
            if (u < reached) reached = u;
        }
    }
    out.reached = reached;
    if (!(out.eval.min_jacobian_det < INFINITY)) out.eval.min_jacobian_det = 1.0;
    if (st) {
        if (out.substeps > 1) composed_moved(shape, fw, deformed, &out.eval);
        *st = out;
    }
    if (reached < 1.0) {
        s->warnings |= 1u << CSRBF_WARN_LIMITED;
        return CSRBF_WARN_LIMITED;
    }
    if (out.substeps > 1) {
        s->warnings |= 1u << CSRBF_WARN_SUBSTEPS;
        return CSRBF_WARN_SUBSTEPS;
    }
    return CSRBF_OK;
}

/* the common argument checks of the two forms; 0 or CSRBF_ERR_INVALID (message set) */
static int guarded_args(csrbf_solver *s, const csrbf_points *shape, size_t n, const float *start,
                        const float *end, const float *deformed)
{
    if (!shape || !start || !end || !deformed || n == 0) {
        s->lim_note.pending = 0;
        snprintf(s->msg, sizeof s->msg, "guarded_step: %s",
                 !shape ? "shape is NULL" : !start ? "start is NULL" : !end ? "end is NULL"
                 : !deformed ? "deformed is NULL" : "n is 0");
        return CSRBF_ERR_INVALID;
    }
    return CSRBF_OK;
}

int csrbf_guarded_step(csrbf_solver *s, const csrbf_points *shape, size_t n, const float *start,
                       const float *end, const csrbf_guard *guard, float *deformed,
                       csrbf_guard_stats *st)
{
    if (!s) return CSRBF_ERR_INVALID;
    int rc = guarded_args(s, shape, n, start, end, deformed);
    return rc < 0 ? rc : guarded(s, shape, NULL, n, start, end, guard, deformed, st);
}

int csrbf_guarded_step_touched(csrbf_solver *s, const csrbf_points *shape, csrbf_touch *touch,
                               csrbf_points *inter, csrbf_touch *inter_touch, size_t n,
                               const float *start, const float *end, const csrbf_guard *guard,
                               float *deformed, csrbf_guard_stats *st)
{
    if (!s) return CSRBF_ERR_INVALID;
    int rc = guarded_args(s, shape, n, start, end, deformed);
    if (rc < 0) return rc;
    if (!csrbf_touch_for(touch, shape) || !csrbf_touch_for(inter_touch, inter) || inter == shape ||
        csrbf_points_count(inter) != csrbf_points_count(shape)) {
        s->lim_note.pending = 0;
        snprintf(s->msg, sizeof s->msg, "guarded_step_touched: %s",
                 !csrbf_touch_for(touch, shape) ? "touch was not made for shape"
                 : !csrbf_touch_for(inter_touch, inter) ? "inter_touch was not made for inter"
                 : "inter must be another csrbf_points of shape's vertex count");
        return CSRBF_ERR_INVALID;
    }
    size_t nb = shape->nblocks;
    if (s->g_bcap != nb) {
        uint32_t *b = realloc(s->g_blk, (4 * nb + 2 * (nb + 1)) * sizeof *b);
        if (!b) return CSRBF_ERR_NOMEM;
        s->g_blk = b;
        s->g_bcap = nb;
    }
    follow f = {touch, inter_touch, inter, s->g_blk, s->g_blk + nb, s->g_blk + 2 * nb,
                s->g_blk + 3 * nb, s->g_blk + 4 * nb, 0, 0, 0, 0, 0};
    rc = guarded(s, shape, &f, n, start, end, guard, deformed, st);
    /* inter back to the shape where a sub-step wrote it (a superset: U) */
    if (f.inter_set) {
        size_t nr = csrbf_block_ranges(f.U, f.ku, shape->n, f.R);
        int r2 = csrbf_points_update_ranges(inter, shape->xyz, f.R, nr);
        if (r2 < 0 && rc >= 0) rc = r2;
    }
    if (rc < 0) {
        csrbf_touch_reset(touch); /* the output is unspecified: the next call writes it whole */
        return rc;
    }
    /* written: the blocks the first map restored or computed (W), and every map's (U) */
    csrbf_touch_set(touch, f.U, f.ku, f.M, merge_blocks(f.W, f.kw, f.U, f.ku, f.M), f.wall);
    return rc;
}
