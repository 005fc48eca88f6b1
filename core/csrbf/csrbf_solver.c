/* csrbf solver: kernels, centre merging, assembly and factorisation of A, the polynomial
 * block, and the per-frame coefficient solve. See csrbf.h and ../shared/docs/csrbf.md. */
#include "internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ messages and codes */

const char *csrbf_strerror(int result)
{
    switch (result) {
    case CSRBF_OK: return "success";
    case CSRBF_WARN_MERGED: return "coincident start points were merged";
    case CSRBF_WARN_POLY_RANK: return "the linear polynomial was reduced (degenerate centres)";
    case CSRBF_WARN_FOLDOVER: return "a coefficient exceeds the fold-over bound";
    case CSRBF_WARN_LIMITED: return "the fold-over guard limited the motion";
    case CSRBF_WARN_SUBSTEPS: return "the fold-over guard split the step into sub-steps";
    case CSRBF_ERR_INVALID: return "invalid argument";
    case CSRBF_ERR_NOMEM: return "out of memory";
    case CSRBF_ERR_NUMERIC: return "numerical failure";
    case CSRBF_ERR_STATE: return "call out of order";
    default: return "unknown result";
    }
}

static _Thread_local char options_msg[256];

const char *csrbf_options_message(void) { return options_msg; }

static int fail(csrbf_solver *s, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int fail(csrbf_solver *s, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(s->msg, sizeof s->msg, fmt, ap);
    va_end(ap);
    s->lim_note.pending = 0;
    return code;
}

void csrbf_msg_flush(csrbf_solver *s)
{
    if (!s->lim_note.pending) return;
    s->lim_note.pending = 0;
    size_t used = strlen(s->msg);
    if (used < sizeof s->msg)
        snprintf(s->msg + used, sizeof s->msg - used,
                 "%sthe fold-over guard scaled %zu of %zu clusters back (bound %.3g > %.3g; "
                 "smallest scale %.3g)",
                 used ? "; " : "", s->lim_note.limited, s->lim_note.clusters, s->lim_note.before,
                 s->lim_note.margin, s->lim_note.tmin);
}

/* Append a warning sentence to the message. */
static void warn(csrbf_solver *s, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void warn(csrbf_solver *s, int code, const char *fmt, ...)
{
    csrbf_msg_flush(s);
    size_t used = strlen(s->msg);
    if (used && used + 2 < sizeof s->msg) {
        strcpy(s->msg + used, "; ");
        used += 2;
    }
    va_list ap;
    va_start(ap, fmt);
    if (used < sizeof s->msg) vsnprintf(s->msg + used, sizeof s->msg - used, fmt, ap);
    va_end(ap);
    s->warnings |= 1u << code;
}

static int first_warning(unsigned w)
{
    for (int c = 1; c < 32; c++)
        if (w & (1u << c)) return c;
    return CSRBF_OK;
}

const char *csrbf_solver_message(const csrbf_solver *s)
{
    if (!s) return "no solver";
    csrbf_msg_flush((csrbf_solver *)s); /* the solver is the caller's, not const storage */
    return s->msg;
}
unsigned csrbf_solver_warnings(const csrbf_solver *s) { return s ? s->warnings : 0; }
size_t csrbf_solver_centres(const csrbf_solver *s) { return s && s->have_start ? s->m : 0; }

/* ------------------------------------------------------------------------------ kernels */

double csrbf_psi(csrbf_kernel k, double r)
{
    double t = 1.0 - r;
    switch (k) {
    case CSRBF_PSI30: return t * t;
    case CSRBF_PSI32: {
        double t2 = t * t, t6 = t2 * t2 * t2;
        return t6 * (35.0 * r * r + 18.0 * r + 3.0) / 3.0;
    }
    case CSRBF_PSI31:
    default: {
        double t2 = t * t;
        return t2 * t2 * (4.0 * r + 1.0);
    }
    }
}

double csrbf_dpsi_over_r(csrbf_kernel k, double r)
{
    double t = 1.0 - r;
    switch (k) {
    case CSRBF_PSI30: return r > 0.0 ? -2.0 * t / r : 0.0;
    case CSRBF_PSI32: {
        double t2 = t * t, t5 = t2 * t2 * t;
        return -56.0 * t5 * (5.0 * r + 1.0) / 3.0;
    }
    case CSRBF_PSI31:
    default: return -20.0 * t * t * t;
    }
}

int csrbf_kernel_eval(csrbf_kernel kernel, double r, double *psi, double *dpsi_dr)
{
    if ((unsigned)kernel > CSRBF_PSI32 || !(r >= 0.0) || (!psi && !dpsi_dr))
        return CSRBF_ERR_INVALID;
    double p = 0.0, d = 0.0;
    if (r < 1.0) {
        p = csrbf_psi(kernel, r);
        d = kernel == CSRBF_PSI30 ? -2.0 * (1.0 - r) : csrbf_dpsi_over_r(kernel, r) * r;
    }
    if (psi) *psi = p;
    if (dpsi_dr) *dpsi_dr = d;
    return CSRBF_OK;
}

double csrbf_kernel_foldover_bound(csrbf_kernel kernel)
{
    /* 1 / max |psi'(r)| on [0, 1]: psi30 max 2 at r = 0; psi31 max 20 r (1-r)^3 at r = 1/4;
     * psi32 max (56/3) r (1-r)^5 (5r+1) where its derivative (1-r)^4 (1 + 4r - 35r^2) is 0:
     * r = (2 + sqrt 39) / 35 (closed form; a scan of 1e5 steps agrees to 1e-10, and unlike
     * the scan it kept in a static, nothing is shared between threads) */
    switch (kernel) {
    case CSRBF_PSI30: return 0.5;
    case CSRBF_PSI31: return 1.0 / (20.0 * 0.25 * 0.75 * 0.75 * 0.75);
    case CSRBF_PSI32: {
        const double r = (2.0 + sqrt(39.0)) / 35.0;
        return 1.0 / fabs(csrbf_dpsi_over_r(CSRBF_PSI32, r) * r);
    }
    default: return 0.0;
    }
}

/* ---------------------------------------------------------------------------- hash grid */

void csrbf_grid_free(csrbf_grid *g)
{
    free(g->start);
    free(g->items);
    free(g->cell);
    memset(g, 0, sizeof *g);
}

int csrbf_grid_build(csrbf_grid *g, const double *p, size_t n, double h)
{
    csrbf_grid_free(g);
    double lo[3] = {p[0], p[1], p[2]}, hi[3] = {p[0], p[1], p[2]};
    for (size_t i = 1; i < n; i++)
        for (int a = 0; a < 3; a++) {
            if (p[3 * i + a] < lo[a]) lo[a] = p[3 * i + a];
            if (p[3 * i + a] > hi[a]) hi[a] = p[3 * i + a];
        }
    double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    /* keep cell coordinates far from int64 overflow; candidates are distance-checked, so a
     * coarser grid stays correct */
    if (h < ext * 0x1p-40) h = ext * 0x1p-40;
    g->h = h;
    g->inv_h = 1.0 / h;
    memcpy(g->origin, lo, sizeof lo);
    g->n = n;
    if (n <= CSRBF_SCAN_ALL_MAX) return CSRBF_OK; /* no table: every point is a candidate */
    size_t ts = 16;
    while (ts < 2 * n) ts *= 2;
    g->tsize = ts;
    g->start = calloc(ts + 1, sizeof *g->start);
    g->items = malloc((n ? n : 1) * sizeof *g->items);
    g->cell = malloc((n ? n : 1) * 3 * sizeof *g->cell);
    size_t *bucket = malloc((n ? n : 1) * sizeof *bucket);
    if (!g->start || !g->items || !g->cell || !bucket) {
        free(bucket);
        csrbf_grid_free(g);
        return CSRBF_ERR_NOMEM;
    }
    for (size_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) g->cell[3 * i + a] = csrbf_grid_coord(g, p[3 * i + a], a);
        bucket[i] = csrbf_grid_bucket(g, g->cell[3 * i], g->cell[3 * i + 1], g->cell[3 * i + 2]);
        g->start[bucket[i] + 1]++;
    }
    for (size_t b = 0; b < ts; b++) g->start[b + 1] += g->start[b];
    size_t *fill = bucket; /* reuse: per-point slot */
    size_t *next = malloc(ts * sizeof *next);
    if (!next) {
        free(bucket);
        csrbf_grid_free(g);
        return CSRBF_ERR_NOMEM;
    }
    memcpy(next, g->start, ts * sizeof *next);
    for (size_t i = 0; i < n; i++) g->items[next[fill[i]]++] = (uint32_t)i;
    free(next);
    free(bucket);
    return CSRBF_OK;
}

/* -------------------------------------------------------------------- create / destroy */

int csrbf_solver_create(const csrbf_options *o, csrbf_solver **out)
{
    options_msg[0] = '\0';
    if (!out) {
        snprintf(options_msg, sizeof options_msg, "out is NULL");
        return CSRBF_ERR_INVALID;
    }
    *out = NULL;
    if (!o) {
        snprintf(options_msg, sizeof options_msg, "options is NULL");
        return CSRBF_ERR_INVALID;
    }
    if ((unsigned)o->kernel > CSRBF_PSI32) {
        snprintf(options_msg, sizeof options_msg, "options.kernel %d is unknown", (int)o->kernel);
        return CSRBF_ERR_INVALID;
    }
    if ((unsigned)o->poly > CSRBF_POLY_LINEAR) {
        snprintf(options_msg, sizeof options_msg, "options.poly %d is unknown", (int)o->poly);
        return CSRBF_ERR_INVALID;
    }
    if (!(o->radius >= 1e-15 && o->radius <= 1e15)) {
        snprintf(options_msg, sizeof options_msg,
                 "options.radius %g must be finite and in [1e-15, 1e15] mesh units", o->radius);
        return CSRBF_ERR_INVALID;
    }
    if (!(o->merge_tolerance >= 0.0 && o->merge_tolerance < 0.5)) {
        snprintf(options_msg, sizeof options_msg,
                 "options.merge_tolerance %g must be in [0, 0.5) (a fraction of the radius)",
                 o->merge_tolerance);
        return CSRBF_ERR_INVALID;
    }
    if (o->threads < 0) {
        snprintf(options_msg, sizeof options_msg, "options.threads %d is negative", o->threads);
        return CSRBF_ERR_INVALID;
    }
    csrbf_solver *s = calloc(1, sizeof *s);
    if (!s) {
        snprintf(options_msg, sizeof options_msg, "out of memory");
        return CSRBF_ERR_NOMEM;
    }
    s->opt = *o;
    if (s->opt.merge_tolerance == 0.0) s->opt.merge_tolerance = CSRBF_DEFAULT_MERGE_TOLERANCE;
    if (s->opt.dense_limit == 0) s->opt.dense_limit = CSRBF_DEFAULT_DENSE_LIMIT;
    s->R = o->radius;
    s->inv_R = 1.0 / o->radius;
    s->merge_abs = s->opt.merge_tolerance * s->R;
    s->fold_bound = csrbf_kernel_foldover_bound(o->kernel) * s->R;
    atomic_flag_clear(&s->scratch_busy);
    *out = s;
    return CSRBF_OK;
}

static void free_factor(csrbf_solver *s)
{
    if (s->cc_started) {
        cholmod_free_factor(&s->F, &s->cc);
        cholmod_free_dense(&s->Bh, &s->cc);
        cholmod_free_dense(&s->Xh, &s->cc);
        cholmod_free_dense(&s->Wk_Y, &s->cc);
        cholmod_free_dense(&s->Wk_E, &s->cc);
    }
    free(s->L);
    s->L = NULL;
}

void csrbf_solver_destroy(csrbf_solver **sp)
{
    if (!sp || !*sp) return;
    csrbf_solver *s = *sp;
    free_factor(s);
    if (s->cc_started) cholmod_finish(&s->cc);
    free(s->group);
    free(s->s_in);
    free(s->inv_count);
    free(s->c);
    free(s->alpha);
    for (int a = 0; a < 3; a++) {
        free(s->fc[a]);
        free(s->fa[a]);
    }
    free(s->Y);
    free(s->Q);
    free(s->W);
    csrbf_grid_free(&s->cgrid);
    csrbf_guard_free(s);
    free(s->scratch);
    free(s->sel_blk);
    free(s->sel_msk);
    free(s->sel_cum);
    free(s->sel_wmem);
    free(s);
    *sp = NULL;
}

/* ---------------------------------------------------------------------- validation */

static const char *axis_name(int a) { return a == 0 ? "x" : a == 1 ? "y" : "z"; }

static int check_coords(csrbf_solver *s, const char *what, size_t n, const float *p)
{
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            float v = p[3 * i + a];
            if (isnan(v))
                return fail(s, CSRBF_ERR_INVALID, "%s point %zu has a NaN %s coordinate", what, i,
                            axis_name(a));
            if (!(fabsf(v) <= (float)CSRBF_MAX_COORD))
                return fail(s, CSRBF_ERR_INVALID,
                            "%s point %zu has %s coordinate %g beyond +-%g", what, i,
                            axis_name(a), (double)v, CSRBF_MAX_COORD);
        }
    return CSRBF_OK;
}

/* ----------------------------------------------------------------------- dense linear */

/* In-place Cholesky of the m x m row-major matrix (lower triangle used). 0 or -1 if not SPD. */
static int dense_cholesky(double *L, size_t m)
{
    for (size_t j = 0; j < m; j++) {
        double d = L[j * m + j];
        for (size_t k = 0; k < j; k++) d -= L[j * m + k] * L[j * m + k];
        if (!(d > 0.0)) return -1;
        d = sqrt(d);
        L[j * m + j] = d;
        double inv = 1.0 / d;
        for (size_t i = j + 1; i < m; i++) {
            double v = L[i * m + j];
            const double *li = L + i * m, *lj = L + j * m;
            for (size_t k = 0; k < j; k++) v -= li[k] * lj[k];
            L[i * m + j] = v * inv;
        }
        for (size_t k = j + 1; k < m; k++) L[j * m + k] = 0.0;
    }
    return 0;
}

/* Solve L L^T X = B in place; B column-major m x ncol. */
static void dense_solve(const double *L, size_t m, double *B, size_t ncol)
{
    /* up to 4 columns at a time, interleaved: each column's arithmetic is the plain forward
     * and back substitution (same operations, same order), but the columns' dependency
     * chains overlap instead of running one after the other */
    for (size_t c0 = 0; c0 < ncol; c0 += 4) {
        const size_t nc = ncol - c0 < 4 ? ncol - c0 : 4;
        double *b[4];
        for (size_t c = 0; c < 4; c++) b[c] = B + (c0 + (c < nc ? c : 0)) * m;
        for (size_t i = 0; i < m; i++) {
            const double *li = L + i * m;
            double v[4] = {b[0][i], b[1][i], b[2][i], b[3][i]};
            for (size_t k = 0; k < i; k++)
                for (size_t c = 0; c < 4; c++) v[c] -= li[k] * b[c][k];
            for (size_t c = nc; c-- > 0;) b[c][i] = v[c] / li[i];
        }
        for (size_t i = m; i-- > 0;) {
            double v[4] = {b[0][i], b[1][i], b[2][i], b[3][i]};
            for (size_t k = i + 1; k < m; k++)
                for (size_t c = 0; c < 4; c++) v[c] -= L[k * m + i] * b[c][k];
            for (size_t c = nc; c-- > 0;) b[c][i] = v[c] / L[i * m + i];
        }
    }
}

/* Solve A X = B in place (B column-major m x ncol, ncol <= 4) with the current factor. */
static int solve_A(csrbf_solver *s, double *B, size_t ncol)
{
    size_t m = s->m;
    if (s->dense) {
        dense_solve(s->L, m, B, ncol);
        return CSRBF_OK;
    }
    /* CHOLMOD: the rhs lives in s->Bh (m x 4 allocated), viewed with ncol columns */
    s->Bh->ncol = ncol;
    s->Bh->nzmax = m * ncol;
    memcpy(s->Bh->x, B, m * ncol * sizeof(double));
    if (s->Xh && s->Xh->ncol != ncol) cholmod_free_dense(&s->Xh, &s->cc);
    if (!cholmod_solve2(CHOLMOD_A, s->F, s->Bh, NULL, &s->Xh, NULL, &s->Wk_Y, &s->Wk_E, &s->cc))
        return s->cc.status == CHOLMOD_OUT_OF_MEMORY ? CSRBF_ERR_NOMEM : CSRBF_ERR_NUMERIC;
    memcpy(B, s->Xh->x, m * ncol * sizeof(double));
    return CSRBF_OK;
}

/* Symmetric 4x4 (first k x k used) eigen-decomposition by cyclic Jacobi. a is destroyed,
 * w gets the eigenvalues, v (row-major, columns = eigenvectors) the vectors. */
static void jacobi4(double a[4][4], int k, double w[4], double v[4][4])
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) v[i][j] = i == j;
    for (int sweep = 0; sweep < 60; sweep++) {
        double off = 0.0;
        for (int p = 0; p < k; p++)
            for (int q = p + 1; q < k; q++) off += a[p][q] * a[p][q];
        if (off < 1e-300) break;
        for (int p = 0; p < k; p++)
            for (int q = p + 1; q < k; q++) {
                if (a[p][q] == 0.0) continue;
                double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), sn = t * c;
                for (int r = 0; r < k; r++) { /* columns p, q */
                    double arp = a[r][p], arq = a[r][q];
                    a[r][p] = c * arp - sn * arq;
                    a[r][q] = sn * arp + c * arq;
                }
                for (int r = 0; r < k; r++) { /* rows p, q */
                    double apr = a[p][r], aqr = a[q][r];
                    a[p][r] = c * apr - sn * aqr;
                    a[q][r] = sn * apr + c * aqr;
                }
                for (int r = 0; r < k; r++) {
                    double vrp = v[r][p], vrq = v[r][q];
                    v[r][p] = c * vrp - sn * vrq;
                    v[r][q] = sn * vrp + c * vrq;
                }
            }
    }
    for (int i = 0; i < k; i++) w[i] = a[i][i];
}

/* Cholesky of a small k x k SPD matrix (row-major, stride 4); -1 if not SPD. */
static int small_cholesky(double a[16], int k)
{
    for (int j = 0; j < k; j++) {
        double d = a[j * 4 + j];
        for (int q = 0; q < j; q++) d -= a[j * 4 + q] * a[j * 4 + q];
        if (!(d > 0.0)) return -1;
        d = sqrt(d);
        a[j * 4 + j] = d;
        for (int i = j + 1; i < k; i++) {
            double v = a[i * 4 + j];
            for (int q = 0; q < j; q++) v -= a[i * 4 + q] * a[j * 4 + q];
            a[i * 4 + j] = v / d;
        }
    }
    return 0;
}

static void small_solve(const double l[16], int k, double *b)
{
    for (int i = 0; i < k; i++) {
        double v = b[i];
        for (int q = 0; q < i; q++) v -= l[i * 4 + q] * b[q];
        b[i] = v / l[i * 4 + i];
    }
    for (int i = k; i-- > 0;) {
        double v = b[i];
        for (int q = i + 1; q < k; q++) v -= l[q * 4 + i] * b[q];
        b[i] = v / l[i * 4 + i];
    }
}

/* ----------------------------------------------------------------------- start points */

static int grow(void **p, size_t count, size_t size)
{
    void *q = realloc(*p, (count ? count : 1) * size);
    if (!q) return -1;
    *p = q;
    return 0;
}

static int ensure_capacity(csrbf_solver *s, size_t n)
{
    if (n <= s->cap_n) return 0;
    /* centres m <= n: size everything for n */
    if (grow((void **)&s->group, n, sizeof *s->group) || grow((void **)&s->s_in, n, 3 * sizeof(double)) ||
        grow((void **)&s->inv_count, n, sizeof(double)) || grow((void **)&s->c, n, 3 * sizeof(double)) ||
        grow((void **)&s->alpha, n, 3 * sizeof(double)) || grow((void **)&s->Y, n, 3 * sizeof(double)) ||
        grow((void **)&s->Q, n, 4 * sizeof(double)) || grow((void **)&s->W, n, 4 * sizeof(double)))
        return -1;
    for (int a = 0; a < 3; a++)
        if (grow((void **)&s->fc[a], n, sizeof(float)) || grow((void **)&s->fa[a], n, sizeof(float)))
            return -1;
    s->cap_n = s->cap_m = n;
    return 0;
}

/* merge_points' test of point j (csrbf_grid_near): an earlier point (j < i) that leads its
 * centre (its position is the centre's) within the tolerance of point i: the smaller centre
 * wins. */
typedef struct {
    const csrbf_solver *s;
    const double *p; /* point i */
    uint32_t i, best;
    double tol2;
} merge_ctx;

static int merge_try(void *ctx, uint32_t j)
{
    merge_ctx *q = ctx;
    const csrbf_solver *s = q->s;
    if (j >= q->i) return 0;
    const double *p = q->p;
    uint32_t *best = &q->best;
    uint32_t gj = s->group[j];
    const double *cj = s->c + 3 * (size_t)gj;
    if (cj[0] != s->s_in[3 * j] || cj[1] != s->s_in[3 * j + 1] || cj[2] != s->s_in[3 * j + 2])
        return 0;
    double d0 = p[0] - cj[0], d1 = p[1] - cj[1], d2 = p[2] - cj[2];
    if (d0 * d0 + d1 * d1 + d2 * d2 <= q->tol2 && (*best == UINT32_MAX || gj < *best)) *best = gj;
    return 0;
}

/* Greedy merge of start points within merge_abs: fills group[], c[], inv_count[], m. */
static int merge_points(csrbf_solver *s)
{
    size_t n = s->n;
    csrbf_grid g = {0};
    int rc = csrbf_grid_build(&g, s->s_in, n, s->merge_abs);
    if (rc) return rc;
    const uint32_t NONE = UINT32_MAX;
    for (size_t i = 0; i < n; i++) s->group[i] = NONE;
    /* leader[c] = input index of centre c's first point */
    size_t m = 0;
    double tol2 = s->merge_abs * s->merge_abs;
    for (size_t i = 0; i < n; i++) {
        const double *p = s->s_in + 3 * i;
        merge_ctx q = {s, p, (uint32_t)i, NONE, tol2};
        csrbf_grid_near(&g, p, 1, merge_try, &q);
        uint32_t best = q.best;
        if (best == NONE) {
            best = (uint32_t)m++;
            memcpy(s->c + 3 * (size_t)best, p, 3 * sizeof(double));
            s->inv_count[best] = 0.0;
        }
        s->group[i] = best;
        s->inv_count[best] += 1.0;
    }
    for (size_t c = 0; c < m; c++) s->inv_count[c] = 1.0 / s->inv_count[c];
    s->m = m;
    csrbf_grid_free(&g);
    return CSRBF_OK;
}

typedef struct { uint32_t row; double v; } entry;

static int cmp_entry(const void *a, const void *b)
{
    uint32_t x = ((const entry *)a)->row, y = ((const entry *)b)->row;
    return (x > y) - (x < y);
}

/* factor_A's entry (i, j) of column j (csrbf_grid_near), for i >= j where centres i and j
 * lie within R: into the dense factor's lower triangle, or appended to the column's entries
 * col[ncol] (sparse). */
typedef struct {
    csrbf_solver *s;
    size_t j, ncol;
    double R2;
    entry *col;
} a_ctx;

static int a_entry(void *ctx, uint32_t i)
{
    a_ctx *q = ctx;
    csrbf_solver *s = q->s;
    if (i < q->j) return 0;
    const double *ci = s->c + 3 * (size_t)i, *cj = s->c + 3 * q->j;
    double d0 = ci[0] - cj[0], d1 = ci[1] - cj[1], d2 = ci[2] - cj[2];
    double r2 = d0 * d0 + d1 * d1 + d2 * d2;
    if (r2 >= q->R2) return 0;
    double v = csrbf_psi(s->opt.kernel, sqrt(r2) * s->inv_R);
    if (s->dense) {
        s->L[(size_t)i * s->m + q->j] = v;
    } else {
        q->col[q->ncol].row = i;
        q->col[q->ncol].v = v;
        q->ncol++;
    }
    return 0;
}

/* Assemble A over the centre grid and factor it. */
static int factor_A(csrbf_solver *s)
{
    size_t m = s->m;
    double R2 = s->R * s->R;
    s->dense = s->opt.dense_limit > 0 && m <= (size_t)s->opt.dense_limit;
    if (s->dense) {
        s->L = calloc(m * m, sizeof(double));
        if (!s->L) return fail(s, CSRBF_ERR_NOMEM, "out of memory for a %zu x %zu dense factor", m, m);
    }
    /* CSC lower triangle for CHOLMOD, built column by column */
    size_t cap = 0, nnz = 0;
    uint32_t *rows = NULL;
    double *vals = NULL;
    size_t *colp = NULL;
    entry *col = NULL;
    if (!s->dense) {
        cap = 16 * m + 16;
        rows = malloc(cap * sizeof *rows);
        vals = malloc(cap * sizeof *vals);
        colp = malloc((m + 1) * sizeof *colp);
        col = malloc(m * sizeof *col);
        if (!rows || !vals || !colp || !col) goto nomem;
    }
    for (size_t j = 0; j < m; j++) {
        a_ctx q = {s, j, 0, R2, col};
        csrbf_grid_near(&s->cgrid, s->c + 3 * j, 1, a_entry, &q);
        size_t ncol = q.ncol;
        if (!s->dense) {
            qsort(col, ncol, sizeof *col, cmp_entry);
            if (nnz + ncol > cap) {
                while (nnz + ncol > cap) cap *= 2;
                uint32_t *r2p = realloc(rows, cap * sizeof *rows);
                if (!r2p) goto nomem;
                rows = r2p;
                double *v2p = realloc(vals, cap * sizeof *vals);
                if (!v2p) goto nomem;
                vals = v2p;
            }
            colp[j] = nnz;
            for (size_t t = 0; t < ncol; t++) {
                rows[nnz] = col[t].row;
                vals[nnz] = col[t].v;
                nnz++;
            }
        }
    }
    if (s->dense) {
        if (dense_cholesky(s->L, m))
            return fail(s, CSRBF_ERR_NUMERIC,
                        "the interpolation matrix is not positive definite (near-coincident "
                        "start points; raise merge_tolerance)");
        return CSRBF_OK;
    }
    colp[m] = nnz;
    if (!s->cc_started) {
        cholmod_start(&s->cc);
        s->cc.print = 0;          /* the library never prints */
        s->cc.error_handler = NULL;
        s->cc_started = 1;
    }
    cholmod_sparse *A = cholmod_allocate_sparse(m, m, nnz, 1, 1, -1, CHOLMOD_REAL, &s->cc);
    if (!A) goto nomem;
    int *Ap = A->p, *Ai = A->i;
    double *Ax = A->x;
    for (size_t j = 0; j <= m; j++) Ap[j] = (int)colp[j];
    for (size_t t = 0; t < nnz; t++) {
        Ai[t] = (int)rows[t];
        Ax[t] = vals[t];
    }
    free(rows);
    free(vals);
    free(colp);
    free(col);
    rows = NULL;
    vals = NULL;
    colp = NULL;
    col = NULL;
    s->F = cholmod_analyze(A, &s->cc);
    int ok = s->F && cholmod_factorize(A, s->F, &s->cc);
    cholmod_free_sparse(&A, &s->cc);
    if (!ok || s->cc.status == CHOLMOD_OUT_OF_MEMORY)
        return fail(s, CSRBF_ERR_NOMEM, "out of memory in the sparse factorisation (%zu centres)", m);
    if (s->cc.status == CHOLMOD_NOT_POSDEF || s->F->minor < m)
        return fail(s, CSRBF_ERR_NUMERIC,
                    "the interpolation matrix is not positive definite (near-coincident "
                    "start points; raise merge_tolerance)");
    s->Bh = cholmod_allocate_dense(m, 4, m, CHOLMOD_REAL, &s->cc);
    if (!s->Bh) goto nomem;
    return CSRBF_OK;
nomem:
    free(rows);
    free(vals);
    free(colp);
    free(col);
    return fail(s, CSRBF_ERR_NOMEM, "out of memory assembling the %zu x %zu matrix", m, m);
}

/* The polynomial block: Q, W = A^-1 Q, chol(S). */
static int setup_poly(csrbf_solver *s)
{
    size_t m = s->m;
    double pc[3] = {0, 0, 0};
    for (size_t i = 0; i < m; i++)
        for (int a = 0; a < 3; a++) pc[a] += s->c[3 * i + a];
    for (int a = 0; a < 3; a++) pc[a] /= (double)m;
    memcpy(s->pc, pc, sizeof pc);
    /* P columns: 1, (x - pc)/R. D scales the constant column to unit norm and the three
     * coordinate columns by one common factor (their joint norm; 0 when every centre is at
     * pc), so that the eigenvectors below are the centres' principal axes whatever the
     * orientation of their line or plane: a direction dropped is the line's or plane's
     * normal, and p stays constant along it. (A factor per column made the dropped direction
     * depend on the frame: for centres on a line a hair off an axis, p's gradient pointed
     * across the line and a vertex 1 unit off it moved 10,000.) */
    double M[4][4] = {{0}}, D[4];
    for (size_t i = 0; i < m; i++) {
        double q[4] = {1.0, (s->c[3 * i] - pc[0]) * s->inv_R, (s->c[3 * i + 1] - pc[1]) * s->inv_R,
                       (s->c[3 * i + 2] - pc[2]) * s->inv_R};
        for (int a = 0; a < 4; a++)
            for (int b = 0; b < 4; b++) M[a][b] += q[a] * q[b];
    }
    const double tr = M[1][1] + M[2][2] + M[3][3];
    D[0] = 1.0 / sqrt(M[0][0]); /* m >= 1 */
    for (int a = 1; a < 4; a++) D[a] = tr > 0.0 ? 1.0 / sqrt(tr) : 0.0;
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 4; b++) M[a][b] *= D[a] * D[b];
    double w[4], V[4][4];
    jacobi4(M, 4, w, V);
    double wmax = 0.0, cmax = 0.0;
    int e0 = 0; /* the constant's eigenvector (M is block-diagonal: the columns are centred) */
    for (int a = 0; a < 4; a++) {
        wmax = fmax(wmax, w[a]);
        if (fabs(V[0][a]) > fabs(V[0][e0])) e0 = a;
    }
    /* The centres are floats: each coordinate stands for anything within half an ulp of it,
     * up to 2^-24 cmax. A direction whose singular value is within 4x what that rounding
     * gives the m centres (sqrt(3m) 2^-24 cmax / R) is not one they determine: a flat hand
     * 1e4 mesh units from the origin lies off its plane by 1e-4 of its span in float alone,
     * and p fitted along that normal moved vertices 20-30 times the control vectors. */
    for (size_t i = 0; i < 3 * m; i++) cmax = fmax(cmax, fabs(s->c[i]));
    const double fl = 4.0 * sqrt(3.0 * (double)m) * 0x1p-24 * cmax * s->inv_R;
    const double wfloor = tr > 0.0 ? fl * fl / tr : 0.0;
    int k = 0;
    memset(s->DV, 0, sizeof s->DV);
    for (int e = 0; e < 4; e++) {
        /* singular value below 1e-6 of the largest, or within the rounding above */
        if (e != e0 && !(w[e] > 1e-12 * wmax && w[e] > wfloor)) continue;
        for (int a = 0; a < 4; a++) s->DV[a * 4 + k] = D[a] * V[a][e];
        k++;
    }
    s->k = k;
    if (k < 4)
        warn(s, CSRBF_WARN_POLY_RANK,
             "the linear polynomial keeps %d of 4 terms: the %zu centres are %s", k, m,
             k == 1 ? "a single point" : k == 2 ? "collinear" : "coplanar");
    for (size_t i = 0; i < m; i++) {
        double q[4] = {1.0, (s->c[3 * i] - pc[0]) * s->inv_R, (s->c[3 * i + 1] - pc[1]) * s->inv_R,
                       (s->c[3 * i + 2] - pc[2]) * s->inv_R};
        for (int e = 0; e < k; e++) {
            double v = 0.0;
            for (int a = 0; a < 4; a++) v += q[a] * s->DV[a * 4 + e];
            s->Q[e * m + i] = v;
        }
    }
    memcpy(s->W, s->Q, m * (size_t)k * sizeof(double));
    int rc = solve_A(s, s->W, (size_t)k);
    if (rc) return fail(s, rc, "solving for the polynomial block failed");
    memset(s->Sl, 0, sizeof s->Sl);
    for (int a = 0; a < k; a++)
        for (int b = 0; b < k; b++) {
            double v = 0.0;
            for (size_t i = 0; i < m; i++) v += s->Q[a * m + i] * s->W[b * m + i];
            s->Sl[a * 4 + b] = v;
        }
    for (int a = 0; a < k; a++) /* symmetrise rounding */
        for (int b = 0; b < a; b++) s->Sl[a * 4 + b] = s->Sl[b * 4 + a] = 0.5 * (s->Sl[a * 4 + b] + s->Sl[b * 4 + a]);
    if (small_cholesky(s->Sl, k))
        return fail(s, CSRBF_ERR_NUMERIC, "the polynomial block Q^T A^-1 Q is not positive definite");
    return CSRBF_OK;
}

static void reset_coefficients(csrbf_solver *s)
{
    size_t m = s->m;
    memset(s->alpha, 0, m * 3 * sizeof(double));
    memset(s->anorm, 0, m * sizeof(double));
    for (int a = 0; a < 3; a++) {
        memset(s->fa[a], 0, m * sizeof(float));
        for (size_t i = 0; i < m; i++) s->fc[a][i] = (float)s->c[3 * i + a];
        s->fpc[a] = (float)s->pc[a];
        s->fg0[a] = 0.0f;
    }
    memset(s->g, 0, sizeof s->g);
    memset(s->fG, 0, sizeof s->fG);
}

int csrbf_solver_set_start_points(csrbf_solver *s, size_t n, const float *start)
{
    if (!s) return CSRBF_ERR_INVALID;
    s->msg[0] = '\0';
    s->lim_note.pending = 0;
    s->warnings = 0;
    s->have_start = 0;
    s->centres_stamp = csrbf_new_stamp(); /* a cached block selection no longer applies */
    if (!start) return fail(s, CSRBF_ERR_INVALID, "start is NULL");
    if (n == 0) return fail(s, CSRBF_ERR_INVALID, "n is 0: at least one start point is needed");
    if (n >= UINT32_MAX) return fail(s, CSRBF_ERR_INVALID, "n %zu is too large (< 2^32 - 1)", n);
    int rc = check_coords(s, "start", n, start);
    if (rc) return rc;
    free_factor(s);
    if (ensure_capacity(s, n)) return fail(s, CSRBF_ERR_NOMEM, "out of memory for %zu start points", n);
    s->n = n;
    for (size_t i = 0; i < 3 * n; i++) s->s_in[i] = start[i];
    rc = merge_points(s);
    if (rc) return fail(s, rc, "out of memory merging start points");
    if (s->m < n)
        warn(s, CSRBF_WARN_MERGED, "%zu start points within %g of another were merged (%zu centres)",
             n - s->m, s->merge_abs, s->m);
    rc = csrbf_grid_build(&s->cgrid, s->c, s->m, s->R);
    if (rc) return fail(s, rc, "out of memory building the centre grid");
    rc = factor_A(s);
    if (rc) return rc;
    rc = csrbf_guard_prepare(s);
    if (rc) return fail(s, rc, "out of memory for the fold-over guard's neighbour lists");
    s->k = 0;
    memset(s->pc, 0, sizeof s->pc);
    if (s->opt.poly == CSRBF_POLY_LINEAR) {
        rc = setup_poly(s);
        if (rc) return rc;
    }
    reset_coefficients(s);
    s->have_start = 1;
    return first_warning(s->warnings);
}

/* ------------------------------------------------------------------------- end points */

int csrbf_solver_set_end_points(csrbf_solver *s, const float *end)
{
    if (!s) return CSRBF_ERR_INVALID;
    s->msg[0] = '\0';
    s->lim_note.pending = 0;
    s->warnings = 0;
    if (!s->have_start)
        return fail(s, CSRBF_ERR_STATE, "end points set before start points (or the last "
                                        "set_start_points failed)");
    if (!end) return fail(s, CSRBF_ERR_INVALID, "end is NULL");
    size_t n = s->n, m = s->m;
    int rc = check_coords(s, "end", n, end);
    if (rc) return rc;
    double *Y = s->Y; /* column-major m x 3 */
    memset(Y, 0, m * 3 * sizeof(double));
    for (size_t i = 0; i < n; i++) {
        size_t g = s->group[i];
        for (int a = 0; a < 3; a++) Y[a * m + g] += (double)end[3 * i + a] - s->s_in[3 * i + a];
    }
    for (int a = 0; a < 3; a++)
        for (size_t g = 0; g < m; g++) Y[a * m + g] *= s->inv_count[g];
    rc = solve_A(s, Y, 3);
    if (rc) return fail(s, rc, "the triangular solves failed");
    double c[4][3] = {{0}};
    int k = s->k;
    if (k > 0) {
        for (int a = 0; a < 3; a++) {
            double b[4] = {0, 0, 0, 0};
            for (int e = 0; e < k; e++) {
                double v = 0.0;
                for (size_t i = 0; i < m; i++) v += s->Q[e * m + i] * Y[a * m + i];
                b[e] = v;
            }
            small_solve(s->Sl, k, b);
            for (int e = 0; e < k; e++) c[e][a] = b[e];
        }
    }
    /* alpha = Y - W c, checked before anything is committed */
    int finite = 1;
    double amax2 = 0.0;
    size_t worst = 0;
    for (size_t i = 0; i < m; i++) {
        double n2 = 0.0;
        for (int a = 0; a < 3; a++) {
            double v = Y[a * m + i];
            for (int e = 0; e < k; e++) v -= s->W[e * m + i] * c[e][a];
            Y[a * m + i] = v;
            n2 += v * v;
        }
        if (!isfinite(n2)) finite = 0;
        if (n2 > amax2) {
            amax2 = n2;
            worst = i;
        }
    }
    double g[4][3] = {{0}};
    for (int l = 0; l < 4; l++)
        for (int a = 0; a < 3; a++) {
            double v = 0.0;
            for (int e = 0; e < k; e++) v += s->DV[l * 4 + e] * c[e][a];
            g[l][a] = v;
            if (!isfinite(v)) finite = 0;
        }
    if (!finite || !(amax2 < 1e60))
        return fail(s, CSRBF_ERR_NUMERIC, "the coefficients are not finite or out of range");
    for (size_t i = 0; i < m; i++) {
        double n2 = 0.0;
        for (int a = 0; a < 3; a++) {
            s->alpha[3 * i + a] = Y[a * m + i];
            s->fa[a][i] = (float)Y[a * m + i];
            n2 += Y[a * m + i] * Y[a * m + i];
        }
        s->anorm[i] = sqrt(n2);
    }
    memcpy(s->g, g, sizeof g);
    for (int a = 0; a < 3; a++) {
        s->fg0[a] = (float)g[0][a];
        for (int l = 0; l < 3; l++) s->fG[a * 3 + l] = (float)(g[l + 1][a] * s->inv_R);
    }
    if (sqrt(amax2) > s->fold_bound)
        warn(s, CSRBF_WARN_FOLDOVER,
             "centre %zu has |alpha| = %g beyond the fold-over bound %g: split the motion into "
             "smaller steps", worst, sqrt(amax2), s->fold_bound);
    return first_warning(s->warnings);
}

int csrbf_solver_solve(csrbf_solver *s, size_t n, const float *start, const float *end)
{
    int r1 = csrbf_solver_set_start_points(s, n, start);
    if (r1 < 0) return r1;
    unsigned w1 = s->warnings;
    csrbf_msg_flush(s);
    char m1[sizeof s->msg];
    memcpy(m1, s->msg, sizeof m1);
    int r2 = csrbf_solver_set_end_points(s, end);
    if (r2 < 0) return r2;
    s->warnings |= w1;
    if (m1[0]) { /* keep both messages */
        char m2[sizeof s->msg];
        csrbf_msg_flush(s);
        memcpy(m2, s->msg, sizeof m2);
        snprintf(s->msg, sizeof s->msg, "%.126s%s%.126s", m1, m2[0] ? "; " : "", m2);
    }
    return r2 > 0 ? r2 : r1;
}

/* --------------------------------------------------------------------------- map point */

int csrbf_solver_get_coefficients(const csrbf_solver *s, double *centres, double *alpha,
                                  double poly[12])
{
    if (!s) return CSRBF_ERR_INVALID;
    if (!s->have_start) return CSRBF_ERR_STATE;
    if (centres) memcpy(centres, s->c, s->m * 3 * sizeof(double));
    if (alpha) memcpy(alpha, s->alpha, s->m * 3 * sizeof(double));
    if (poly) {
        memset(poly, 0, 12 * sizeof(double));
        if (s->k > 0)
            for (int a = 0; a < 3; a++) {
                poly[a] = s->g[0][a];
                for (int l = 0; l < 3; l++) {
                    double Bal = s->g[l + 1][a] * s->inv_R;
                    poly[3 + 3 * a + l] = Bal;
                    poly[a] -= Bal * s->pc[l];
                }
            }
    }
    return CSRBF_OK;
}

int csrbf_solver_map_point(const csrbf_solver *s, const double x[3], double out[3], double jac[9])
{
    if (!s || !x || !out) return CSRBF_ERR_INVALID;
    if (!s->have_start) return CSRBF_ERR_STATE;
    if (!isfinite(x[0]) || !isfinite(x[1]) || !isfinite(x[2])) return CSRBF_ERR_INVALID;
    double T[3] = {x[0], x[1], x[2]}, J[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double R2 = s->R * s->R, invR2 = 1.0 / R2;
    for (size_t i = 0; i < s->m; i++) {
        const double *c = s->c + 3 * i;
        double d[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
        double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if (r2 >= R2) continue;
        double r = sqrt(r2) * s->inv_R;
        double p = csrbf_psi(s->opt.kernel, r), q = csrbf_dpsi_over_r(s->opt.kernel, r) * invR2;
        for (int a = 0; a < 3; a++) {
            T[a] += s->alpha[3 * i + a] * p;
            for (int b = 0; b < 3; b++) J[a * 3 + b] += s->alpha[3 * i + a] * q * d[b];
        }
    }
    if (s->k > 0)
        for (int a = 0; a < 3; a++) {
            T[a] += s->g[0][a];
            for (int l = 0; l < 3; l++) {
                T[a] += s->g[l + 1][a] * (x[l] - s->pc[l]) * s->inv_R;
                J[a * 3 + l] += s->g[l + 1][a] * s->inv_R;
            }
        }
    memcpy(out, T, sizeof T);
    if (jac) memcpy(jac, J, sizeof J);
    return CSRBF_OK;
}
