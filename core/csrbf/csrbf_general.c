/* csrbf_evaluate's general path, for what the fast path leaves (a polynomial, the Jacobian
 * determinant, more than CSRBF_FAST_MAX_CENTRES centres, a CPU or compiler without the fast
 * path's instruction sets): every block in turn, its centres from the tree's masks, all of
 * them (all in), or the centre grid; the per-block kernel (the fast path's where there is
 * one, else target_clones of portable C) over the B vertices as SIMD lanes, then the
 * polynomial, the store and the statistics. */
#include "eval_internal.h"

#include <math.h>
#include <omp.h>

/* The block kernel over one block of B vertices: acc (initialised to -0.0f so that a vertex
 * outside every support keeps its base bit for bit) += a_j psi(|x - c_j| / R) over the listed
 * centres; cnt += pairs in support. The centre loop is outside, the B vertices are the SIMD
 * lanes. r = sqrt(r2): vsqrtps under -fno-math-errno. */
#define DEFINE_BLOCK_KERNEL(NAME, PSI)                                                         \
    CSRBF_CLONES static void NAME(const float *restrict x, const float *restrict y,           \
                                  const float *restrict z, const uint32_t *restrict list,     \
                                  size_t k, const float *restrict cx,                         \
                                  const float *restrict cy, const float *restrict cz,         \
                                  const float *restrict ax, const float *restrict ay,         \
                                  const float *restrict az, float inv_r2,                     \
                                  float *restrict accx, float *restrict accy,                 \
                                  float *restrict accz, int *restrict cnt)                    \
    {                                                                                          \
        float sx[B], sy[B], sz[B];                                                             \
        int sc[B];                                                                             \
        for (int v = 0; v < B; v++) {                                                          \
            sx[v] = sy[v] = sz[v] = -0.0f;                                                     \
            sc[v] = 0;                                                                         \
        }                                                                                      \
        for (size_t t = 0; t < k; t++) {                                                       \
            const uint32_t j = list[t];                                                        \
            const float px = cx[j], py = cy[j], pz = cz[j];                                    \
            const float qx = ax[j], qy = ay[j], qz = az[j];                                    \
            _Pragma("omp simd") for (int v = 0; v < B; v++)                                    \
            {                                                                                  \
                float dx = x[v] - px, dy = y[v] - py, dz = z[v] - pz;                          \
                float r2 = (dx * dx + dy * dy + dz * dz) * inv_r2;                             \
                float r = sqrtf(r2 < 1.0f ? r2 : 1.0f);                                        \
                float t1 = 1.0f - r;                                                           \
                float w = PSI;                                                                 \
                int in = r2 < 1.0f;                                                            \
                sx[v] = in ? sx[v] + qx * w : sx[v];                                           \
                sy[v] = in ? sy[v] + qy * w : sy[v];                                           \
                sz[v] = in ? sz[v] + qz * w : sz[v];                                           \
                sc[v] += in;                                                                   \
            }                                                                                  \
        }                                                                                      \
        for (int v = 0; v < B; v++) {                                                          \
            accx[v] = sx[v];                                                                   \
            accy[v] = sy[v];                                                                   \
            accz[v] = sz[v];                                                                   \
            cnt[v] = sc[v];                                                                    \
        }                                                                                      \
    }

DEFINE_BLOCK_KERNEL(block_psi31, (t1 * t1) * (t1 * t1) * (4.0f * r + 1.0f))
DEFINE_BLOCK_KERNEL(block_psi30, t1 * t1)
DEFINE_BLOCK_KERNEL(block_psi32,
                    ((t1 * t1) * (t1 * t1) * (t1 * t1)) * ((35.0f / 3.0f) * r2 + 6.0f * r + 1.0f))

/* out[3v + a] = base + acc (+ p(x)) for the nv <= B vertices of a block: contiguous stores. */
CSRBF_CLONES static void write_block(float *restrict out, const float *restrict x,
                                     const float *restrict y, const float *restrict z,
                                     const float *restrict accx, const float *restrict accy,
                                     const float *restrict accz, size_t nv)
{
    if (nv == B) {
#pragma omp simd
        for (int v = 0; v < B; v++) {
            out[3 * v] = x[v] + accx[v];
            out[3 * v + 1] = y[v] + accy[v];
            out[3 * v + 2] = z[v] + accz[v];
        }
    } else {
        for (size_t v = 0; v < nv; v++) {
            out[3 * v] = x[v] + accx[v];
            out[3 * v + 1] = y[v] + accy[v];
            out[3 * v + 2] = z[v] + accz[v];
        }
    }
}

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

/* The portable kernels, [ki]: psi31, psi30, psi32. */
static const block_fn portable_kern[3] = {block_psi31, block_psi30, block_psi32};

/* A thread's statistics (reduced over the threads). */
typedef struct {
    size_t pairs, moved;
    double maxd, minjac; /* squared displacement; Jacobian determinant */
} gen_stats;

/* The centres of block b into list (its count returned); all in: list holds every centre
 * already. */
static inline size_t block_centres(const eval_plan *p, size_t b, uint32_t *list)
{
    if (p->all_in) return p->m;
    if (!p->use_tree) return csrbf_sel_centres(p->s, p->P, b, list, 0);
    size_t k = 0;
    for (uint64_t mk = p->gen_mask[b]; mk; mk &= mk - 1) list[k++] = (uint32_t)__builtin_ctzll(mk);
    return k;
}

/* acc += p(x) at the B vertices x, y, z (the polynomial, float). */
static inline void add_poly(const csrbf_solver *s, const float *x, const float *y,
                            const float *z, float *accx, float *accy, float *accz)
{
    const float pc0 = s->fpc[0], pc1 = s->fpc[1], pc2 = s->fpc[2];
    const float *G = s->fG, *g0 = s->fg0;
    for (int v = 0; v < B; v++) {
        float ex = x[v] - pc0, ey = y[v] - pc1, ez = z[v] - pc2;
        accx[v] += g0[0] + G[0] * ex + G[1] * ey + G[2] * ez;
        accy[v] += g0[1] + G[3] * ex + G[4] * ey + G[5] * ez;
        accz[v] += g0[2] + G[6] * ex + G[7] * ey + G[8] * ez;
    }
}

/* The statistics of a block's nv vertices (list: its k centres, for the Jacobian). */
static inline void block_stats_add(const eval_plan *p, const float *x, const float *y,
                                   const float *z, const float *accx, const float *accy,
                                   const float *accz, const int *cnt, size_t nv,
                                   const uint32_t *list, size_t k, gen_stats *gs)
{
    const int poly = p->poly;
    for (size_t v = 0; v < nv; v++) {
        gs->pairs += (size_t)cnt[v];
        gs->moved += poly || cnt[v] > 0;
        double d = (double)accx[v] * accx[v] + (double)accy[v] * accy[v] +
                   (double)accz[v] * accz[v];
        if (d > gs->maxd) gs->maxd = d;
        if (p->want_jac && (poly || cnt[v] > 0)) {
            double xv[3] = {x[v], y[v], z[v]};
            double det = jacobian_det(p->s, xv, list, k);
            if (det < gs->minjac) gs->minjac = det;
        }
    }
}

/* Block b: outside every support (no polynomial, no Jacobian) its base, restored only where
 * the last call wrote it; else the kernel over its centres, the polynomial, the store. */
static inline void general_block(const eval_plan *p, block_fn kern, size_t b, uint32_t *list,
                                 gen_stats *gs)
{
    const csrbf_solver *s = p->s;
    const csrbf_points *P = p->P;
    const csrbf_touch *touch = p->touch;
    const size_t k0 = b * B, nv = b + 1 < p->nb ? B : p->n - k0;
    float *o = p->out + 3 * k0;
    const size_t k = block_centres(p, b, list);
    if (!k && !p->all_in && !p->poly && !p->want_jac) { /* outside every support: the base */
        if (touch) p->tcur[b] = 0;
        if (!touch || p->tprev[b]) memcpy(o, P->xyz + 3 * k0, nv * 3 * sizeof(float));
        return;
    }
    if (touch) p->tcur[b] = 1;
    _Alignas(64) float accx[B], accy[B], accz[B];
    _Alignas(64) int cnt[B];
    const float *x = P->s[0] + k0, *y = P->s[1] + k0, *z = P->s[2] + k0;
    kern(x, y, z, list, k, s->fc[0], s->fc[1], s->fc[2], s->fa[0], s->fa[1], s->fa[2],
         p->inv_r2, accx, accy, accz, cnt);
    if (p->poly) add_poly(s, x, y, z, accx, accy, accz);
    if (p->isa && nv == B) p->isa->write_block(o, x, y, z, accx, accy, accz);
    else write_block(o, x, y, z, accx, accy, accz, nv);
    if (p->st) block_stats_add(p, x, y, z, accx, accy, accz, cnt, nv, list, k, gs);
}

void csrbf_run_general(eval_plan *p)
{
    const size_t nb = p->nb, m = p->m;
    if (p->use_tree) {
        memset(p->gen_mask, 0, nb * sizeof *p->gen_mask);
        for (size_t i = 0; i < p->S.k; i++) p->gen_mask[p->S.blk[i]] = p->S.msk[i];
    }
    if (p->touch) csrbf_touch_mark_prev(p->touch, p->tprev, p->full_write);
    const size_t cost = p->use_tree ? p->S.cum[p->S.k]
                        : p->all_in ? nb * ITEM_COST(m)
                                    : nb * ITEM_COST(1);
    const int threads =
        cost > PARALLEL_COST || (m > CSRBF_FAST_MAX_CENTRES && !p->all_in) ? p->nt : 1;
    const block_fn kern = p->isa ? p->isa->kern[p->ki] : portable_kern[p->ki];
    size_t pairs = 0, moved = 0;
    /* (the minimum starts at +inf, not 1: where every moved vertex has det > 1, that is
     * the minimum; 1 is said only when no vertex moved) */
    double maxd = 0.0, minjac = INFINITY;
#pragma omp parallel num_threads(threads) reduction(+ : pairs, moved) reduction(max : maxd) \
    reduction(min : minjac)
    {
        uint32_t *list = (uint32_t *)(p->tbase + (size_t)omp_get_thread_num() * p->per_thread);
        if (p->all_in)
            for (size_t i = 0; i < m; i++) list[i] = (uint32_t)i;
        gen_stats gs = {0, 0, 0.0, INFINITY};
#pragma omp for schedule(dynamic, 64)
        for (size_t b = 0; b < nb; b++) general_block(p, kern, b, list, &gs);
        pairs += gs.pairs;
        moved += gs.moved;
        if (gs.maxd > maxd) maxd = gs.maxd;
        if (gs.minjac < minjac) minjac = gs.minjac;
    }
    p->pairs += pairs;
    p->moved += moved;
    p->maxd = maxd;
    p->minjac = minjac < INFINITY ? minjac : 1.0;
    if (p->touch) csrbf_touch_after_general(p->touch, p->tcur, p->tprev);
}
