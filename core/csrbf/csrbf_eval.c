/* csrbf_evaluate: T(x) at every vertex. Blocks of CSRBF_BLOCK Morton-sorted vertices are
 * matched against the centres whose support meets the block's box; within a block the loop
 * runs over the selected centres and vectorises over the vertices (SIMD clones for AVX-512,
 * AVX2+FMA and the baseline, picked at load time). Blocks run in parallel with OpenMP. */
#include "internal.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__ELF__)
#define CSRBF_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define CSRBF_CLONES
#endif

#define B CSRBF_BLOCK

/* Per-thread work arrays: the block's selected centres, structure of arrays. */
typedef struct {
    uint32_t *list;
    float *c[3], *a[3];
} thread_work;

/* The block kernel: acc (initialised to -0.0f by the caller so that a vertex outside every
 * support keeps its base bit for bit) += a_j psi(|x - c_j| / R); cnt += pairs in support.
 * r = sqrt(r2): sqrt is vectorised (vsqrtps) under -fno-math-errno. */
#define DEFINE_BLOCK_KERNEL(NAME, PSI)                                                         \
    CSRBF_CLONES static void NAME(const float *restrict x, const float *restrict y,           \
                                  const float *restrict z, size_t k,                          \
                                  const float *restrict cx, const float *restrict cy,         \
                                  const float *restrict cz, const float *restrict ax,         \
                                  const float *restrict ay, const float *restrict az,         \
                                  float inv_r2, float *restrict accx, float *restrict accy,   \
                                  float *restrict accz, int *restrict cnt)                    \
    {                                                                                          \
        for (size_t j = 0; j < k; j++) {                                                       \
            const float px = cx[j], py = cy[j], pz = cz[j];                                    \
            const float qx = ax[j], qy = ay[j], qz = az[j];                                    \
            _Pragma("omp simd") for (int v = 0; v < B; v++)                                    \
            {                                                                                  \
                float dx = x[v] - px, dy = y[v] - py, dz = z[v] - pz;                          \
                float r2 = (dx * dx + dy * dy + dz * dz) * inv_r2;                             \
                float r = sqrtf(r2 < 1.0f ? r2 : 1.0f);                                        \
                float t = 1.0f - r;                                                            \
                float w = PSI;                                                                 \
                int in = r2 < 1.0f;                                                            \
                accx[v] = in ? accx[v] + qx * w : accx[v];                                     \
                accy[v] = in ? accy[v] + qy * w : accy[v];                                     \
                accz[v] = in ? accz[v] + qz * w : accz[v];                                     \
                cnt[v] += in;                                                                  \
            }                                                                                  \
        }                                                                                      \
    }

DEFINE_BLOCK_KERNEL(block_psi31, (t * t) * (t * t) * (4.0f * r + 1.0f))
DEFINE_BLOCK_KERNEL(block_psi30, t * t)
DEFINE_BLOCK_KERNEL(block_psi32,
                    ((t * t) * (t * t) * (t * t)) * ((35.0f / 3.0f) * r2 + 6.0f * r + 1.0f))

typedef void (*block_fn)(const float *, const float *, const float *, size_t, const float *,
                         const float *, const float *, const float *, const float *,
                         const float *, float, float *, float *, float *, int *);

/* Does the support of centre c (radius R) meet the box [lo, hi]? Conservative by a hair. */
static inline int meets(const double c[3], const float lo[3], const float hi[3], double R2)
{
    double d2 = 0.0;
    for (int a = 0; a < 3; a++) {
        double e = c[a] < lo[a] ? lo[a] - c[a] : c[a] > hi[a] ? c[a] - hi[a] : 0.0;
        d2 += e * e;
    }
    return d2 < R2 * (1.0 + 1e-6);
}

/* Centres whose support meets block b; returns their count (list may be NULL: count only
 * until the first hit). */
static size_t select_centres(const csrbf_solver *s, const csrbf_points *P, size_t b,
                             uint32_t *list, int any)
{
    float lo[3] = {P->lo[0][b], P->lo[1][b], P->lo[2][b]};
    float hi[3] = {P->hi[0][b], P->hi[1][b], P->hi[2][b]};
    double R2 = s->R * s->R;
    size_t k = 0, m = s->m;
    const csrbf_grid *g = &s->cgrid;
    int64_t c0[3], c1[3];
    double cells = 1.0;
    for (int a = 0; a < 3; a++) {
        c0[a] = csrbf_grid_coord(g, lo[a] - s->R, a);
        c1[a] = csrbf_grid_coord(g, hi[a] + s->R, a);
        cells *= (double)(c1[a] - c0[a] + 1);
    }
    if (m <= 32 || cells > (double)m) {
        for (size_t i = 0; i < m; i++)
            if (meets(s->c + 3 * i, lo, hi, R2)) {
                if (any) return 1;
                list[k++] = (uint32_t)i;
            }
        return k;
    }
    for (int64_t z = c0[2]; z <= c1[2]; z++)
        for (int64_t y = c0[1]; y <= c1[1]; y++)
            for (int64_t x = c0[0]; x <= c1[0]; x++) {
                size_t bk = csrbf_grid_bucket(g, x, y, z);
                for (size_t t = g->start[bk]; t < g->start[bk + 1]; t++) {
                    uint32_t i = g->items[t];
                    if (g->cell[3 * i] != x || g->cell[3 * i + 1] != y || g->cell[3 * i + 2] != z)
                        continue;
                    if (meets(s->c + 3 * (size_t)i, lo, hi, R2)) {
                        if (any) return 1;
                        list[k++] = i;
                    }
                }
            }
    return k;
}

static size_t align64(size_t bytes) { return (bytes + 63) & ~(size_t)63; }

/* Jacobian determinant of T at x (double), over the listed centres. */
static double jacobian_det(const csrbf_solver *s, const double x[3], const uint32_t *list,
                           size_t k)
{
    double J[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double R2 = s->R * s->R, inv_r2 = 1.0 / R2;
    for (size_t t = 0; t < k; t++) {
        const double *c = s->c + 3 * (size_t)list[t];
        double d[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
        double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if (r2 >= R2) continue;
        double q = csrbf_dpsi_over_r(s->opt.kernel, sqrt(r2) * s->inv_R) * inv_r2;
        const double *al = s->alpha + 3 * (size_t)list[t];
        for (int a = 0; a < 3; a++)
            for (int bb = 0; bb < 3; bb++) J[a * 3 + bb] += al[a] * q * d[bb];
    }
    if (s->k > 0)
        for (int a = 0; a < 3; a++)
            for (int l = 0; l < 3; l++) J[a * 3 + l] += s->g[l + 1][a] * s->inv_R;
    return J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) +
           J[2] * (J[3] * J[7] - J[4] * J[6]);
}

int csrbf_evaluate(const csrbf_solver *cs, const csrbf_points *P, float *out, unsigned flags,
                   csrbf_eval_stats *st)
{
    if (!cs || !P || !out || (flags & ~(unsigned)CSRBF_EVAL_JACOBIAN)) return CSRBF_ERR_INVALID;
    if (!cs->have_start) return CSRBF_ERR_STATE;
    /* The scratch buffer is the only state evaluate touches; a concurrent caller that finds it
     * busy allocates its own. The solver itself is read-only here. */
    csrbf_solver *s = (csrbf_solver *)cs;
    const size_t n = P->n, nb = P->nblocks, m = s->m;
    const int poly = s->k > 0, want_jac = st && (flags & CSRBF_EVAL_JACOBIAN);
    int nt = s->opt.threads > 0 ? s->opt.threads : omp_get_max_threads();
    if (nt < 1) nt = 1;

    /* every centre's support holds the whole vertex box: no selection needed */
    int all_in = 1;
    double R2 = s->R * s->R;
    for (size_t i = 0; i < m && all_in; i++) {
        double d2 = 0.0;
        for (int a = 0; a < 3; a++) {
            double c = s->c[3 * i + a];
            double e = fmax(fabs(c - P->blo[a]), fabs(c - P->bhi[a]));
            d2 += e * e;
        }
        all_in = d2 < R2 * (1.0 - 1e-6);
    }
    block_fn kern = s->opt.kernel == CSRBF_PSI30   ? block_psi30
                    : s->opt.kernel == CSRBF_PSI32 ? block_psi32
                                                   : block_psi31;

    size_t per_thread = align64(m * sizeof(uint32_t)) + 6 * align64(m * sizeof(float));
    size_t need = align64(nb) + (size_t)nt * per_thread;
    void *mem = NULL;
    int own = 0;
    if (!atomic_flag_test_and_set(&s->scratch_busy)) {
        if (s->scratch_cap < need) {
            void *q = realloc(s->scratch, need);
            if (!q) {
                atomic_flag_clear(&s->scratch_busy);
                return CSRBF_ERR_NOMEM;
            }
            s->scratch = q;
            s->scratch_cap = need;
        }
        mem = s->scratch;
    } else {
        mem = malloc(need);
        if (!mem) return CSRBF_ERR_NOMEM;
        own = 1;
    }
    unsigned char *touched = mem;
    unsigned char *tbase = (unsigned char *)mem + align64(nb);

    /* pass 1 (local map, partial cover): which blocks meet a support */
    size_t touched_vertices = n;
    int select = !all_in;
    int copy_all = 0;
    if (!poly && !all_in) {
        size_t tv = 0;
#pragma omp parallel for schedule(static) reduction(+ : tv) num_threads(nt) if (nb * m > 20000)
        for (size_t b = 0; b < nb; b++) {
            touched[b] = select_centres(s, P, b, NULL, 1) > 0;
            if (touched[b]) tv += b + 1 < nb ? B : n - b * B;
        }
        touched_vertices = tv;
        /* few blocks touched: one contiguous copy beats scattering the untouched ones */
        copy_all = tv * 2 < n;
        if (copy_all) memcpy(out, P->xyz, n * 3 * sizeof(float));
    }
    size_t work = touched_vertices * (m < 16 ? m : 16);
    int threads = work > 60000 ? nt : 1;

    size_t pairs = 0, moved = 0;
    double maxd = 0.0, minjac = 1.0;
    const float inv_r2 = (float)(1.0 / R2);
    const float pc0 = s->fpc[0], pc1 = s->fpc[1], pc2 = s->fpc[2];
    const float *G = s->fG, *g0 = s->fg0;

#pragma omp parallel num_threads(threads) reduction(+ : pairs, moved) reduction(max : maxd) \
    reduction(min : minjac)
    {
        int tid = omp_get_thread_num();
        unsigned char *tb = tbase + (size_t)tid * per_thread;
        thread_work w;
        w.list = (uint32_t *)tb;
        tb += align64(m * sizeof(uint32_t));
        for (int a = 0; a < 3; a++) {
            w.c[a] = (float *)tb;
            tb += align64(m * sizeof(float));
            w.a[a] = (float *)tb;
            tb += align64(m * sizeof(float));
        }
        if (!select) { /* all centres, once */
            for (size_t i = 0; i < m; i++) {
                w.list[i] = (uint32_t)i;
                for (int a = 0; a < 3; a++) {
                    w.c[a][i] = s->fc[a][i];
                    w.a[a][i] = s->fa[a][i];
                }
            }
        }
        _Alignas(64) float accx[B], accy[B], accz[B];
        _Alignas(64) int cnt[B];
#pragma omp for schedule(dynamic, 4)
        for (size_t b = 0; b < nb; b++) {
            size_t k0 = b * B, nv = b + 1 < nb ? B : n - k0;
            const uint32_t *perm = P->perm + k0;
            size_t k = m;
            if (select) {
                if (!poly && !touched[b]) {
                    if (!copy_all)
                        for (size_t v = 0; v < nv; v++)
                            memcpy(out + 3 * (size_t)perm[v], P->xyz + 3 * (size_t)perm[v],
                                   3 * sizeof(float));
                    continue;
                }
                k = select_centres(s, P, b, w.list, 0);
                for (size_t t = 0; t < k; t++)
                    for (int a = 0; a < 3; a++) {
                        w.c[a][t] = s->fc[a][w.list[t]];
                        w.a[a][t] = s->fa[a][w.list[t]];
                    }
            }
            for (int v = 0; v < B; v++) {
                accx[v] = accy[v] = accz[v] = -0.0f;
                cnt[v] = 0;
            }
            const float *x = P->s[0] + k0, *y = P->s[1] + k0, *z = P->s[2] + k0;
            kern(x, y, z, k, w.c[0], w.c[1], w.c[2], w.a[0], w.a[1], w.a[2], inv_r2, accx, accy,
                 accz, cnt);
            if (poly)
                for (size_t v = 0; v < nv; v++) {
                    float ex = x[v] - pc0, ey = y[v] - pc1, ez = z[v] - pc2;
                    accx[v] += g0[0] + G[0] * ex + G[1] * ey + G[2] * ez;
                    accy[v] += g0[1] + G[3] * ex + G[4] * ey + G[5] * ez;
                    accz[v] += g0[2] + G[6] * ex + G[7] * ey + G[8] * ez;
                }
            for (size_t v = 0; v < nv; v++) {
                float *o = out + 3 * (size_t)perm[v];
                o[0] = x[v] + accx[v];
                o[1] = y[v] + accy[v];
                o[2] = z[v] + accz[v];
            }
            if (st) {
                for (size_t v = 0; v < nv; v++) {
                    pairs += (size_t)cnt[v];
                    moved += poly || cnt[v] > 0;
                    double d = (double)accx[v] * accx[v] + (double)accy[v] * accy[v] +
                               (double)accz[v] * accz[v];
                    if (d > maxd) maxd = d;
                    if (want_jac && (poly || cnt[v] > 0)) {
                        double xv[3] = {x[v], y[v], z[v]};
                        double det = jacobian_det(s, xv, w.list, k);
                        if (det < minjac) minjac = det;
                    }
                }
            }
        }
    }
    if (own)
        free(mem);
    else
        atomic_flag_clear(&s->scratch_busy);
    if (st) {
        st->pairs = pairs;
        st->moved = moved;
        st->max_displacement = sqrt(maxd);
        st->min_jacobian_det = minjac;
    }
    return CSRBF_OK;
}
