/* csrbf internals shared by the solver (csrbf_solver.c), the vertex index (csrbf_points.c)
 * and the evaluation (csrbf_eval.c and the files eval_internal.h names). Not part of the
 * public API. */
#ifndef CSRBF_INTERNAL_H
#define CSRBF_INTERNAL_H

#include "csrbf.h"

#include <math.h>
#include <stdatomic.h>
#include <stdint.h>

#include <cholmod.h>

/* Vertices per evaluation block: one AVX-512 vector of floats, a multiple of every SIMD
 * width. Blocks are runs of consecutive vertex indices, so output stays contiguous. */
#define CSRBF_BLOCK 16

/* Fan-out of the block tree (csrbf_points: one AVX-512 vector of boxes holds a node's
 * children) and its deepest possible level count (nblocks < 2^28 = CSRBF_FAN^7). */
#define CSRBF_FAN 16
#define CSRBF_TREE_MAX 8

/* A hash grid over points (double, AoS n x 3) with cubic cells of side h. Cells hash into a
 * power-of-two table; each point keeps its integer cell so that colliding cells are told
 * apart. */
typedef struct csrbf_grid {
    double origin[3], h, inv_h;
    size_t n, tsize;        /* points, table size (power of two; 0: no table, n at most
                               CSRBF_SCAN_ALL_MAX) */
    size_t *start;          /* tsize + 1: bucket b holds items[start[b] .. start[b+1]) */
    uint32_t *items;        /* n point indices, grouped by bucket */
    int64_t *cell;          /* n x 3 cell coordinates */
} csrbf_grid;

/* A grid of at most this many points has no table (tsize 0): its neighbour searches
 * (csrbf_grid_near; the general path's centres of a block) test every point instead of
 * probing 27 or 125 hashed cells per point, which costs more than the scan for so few
 * (docs/performance.md). The pairs a caller keeps by distance are the same (its cells are at
 * least as wide as its reach). */
#define CSRBF_SCAN_ALL_MAX 32

int csrbf_grid_build(csrbf_grid *g, const double *p, size_t n, double h);
void csrbf_grid_free(csrbf_grid *g);
/* visit(ctx, i) for every point i of g in the cells within `reach` cells (each axis) of the
 * cell holding x, each once (without a table: every point, in index order); the first
 * non-zero result stops the walk and is returned, else 0. */
typedef int (*csrbf_grid_visit)(void *ctx, uint32_t i);
static inline size_t csrbf_grid_bucket(const csrbf_grid *g, int64_t x, int64_t y, int64_t z)
{
    uint64_t k = (uint64_t)x * 73856093u ^ (uint64_t)y * 19349663u ^ (uint64_t)z * 83492791u;
    k ^= k >> 29;
    k *= 0xbf58476d1ce4e5b9ull;
    k ^= k >> 32;
    return (size_t)(k & (g->tsize - 1));
}
static inline int64_t csrbf_grid_coord(const csrbf_grid *g, double x, int axis)
{
    return (int64_t)floor((x - g->origin[axis]) * g->inv_h);
}
/* (inlined, so that each caller's visit is too) */
static inline __attribute__((always_inline)) int csrbf_grid_near(const csrbf_grid *g, const double x[3], int reach,
                                                                 csrbf_grid_visit visit, void *ctx)
{
    int rc = 0;
    if (!g->tsize) {
        for (size_t i = 0; i < g->n && !rc; i++) rc = visit(ctx, (uint32_t)i);
        return rc;
    }
    const int64_t cx = csrbf_grid_coord(g, x[0], 0), cy = csrbf_grid_coord(g, x[1], 1),
                  cz = csrbf_grid_coord(g, x[2], 2);
    for (int dz = -reach; dz <= reach; dz++)
        for (int dy = -reach; dy <= reach; dy++)
            for (int dx = -reach; dx <= reach; dx++) {
                int64_t cxd = cx + dx, cyd = cy + dy, czd = cz + dz;
                size_t b = csrbf_grid_bucket(g, cxd, cyd, czd);
                for (size_t t = g->start[b]; t < g->start[b + 1]; t++) {
                    uint32_t i = g->items[t];
                    if (g->cell[3 * i] != cxd || g->cell[3 * i + 1] != cyd || g->cell[3 * i + 2] != czd)
                        continue; /* (another cell in the same bucket) */
                    if ((rc = visit(ctx, i))) return rc;
                }
            }
    return 0;
}

/* Appends the solver's pending guard sentence (lim_note) to msg; the message functions call
 * it before they read or extend msg, those that replace msg clear lim_note.pending. */
void csrbf_msg_flush(csrbf_solver *s);

struct csrbf_solver {
    csrbf_options opt;       /* resolved: defaults filled in */
    double R, inv_R, merge_abs;
    double fold_bound;       /* fold-over bound * R */
    char msg[256];
    unsigned warnings;
    /* the fold-over guard's last scale-back (csrbf_solver_limit_end_points), its sentence not
     * yet in msg: written by csrbf_msg_flush when the message is read or extended (formatting
     * its three doubles costs more than the rest of a frame's solve: docs/performance.md) */
    struct {
        int pending;
        size_t limited, clusters;
        double before, margin, tmin;
    } lim_note;
    int have_start;

    size_t n, m;             /* input points, merged centres */
    size_t cap_n, cap_m;
    uint32_t *group;         /* n: centre of each input point */
    double *s_in;            /* n x 3 input start points */
    double *inv_count;       /* m: 1 / members of the centre */
    double *c;               /* m x 3 centres */
    double *alpha;           /* m x 3 coefficients */
    float *fc[3], *fa[3];    /* m each: centres and coefficients, float, structure of arrays */
    double *Y;               /* m x 3 column-major work: H, then A^-1 H */

    /* factor of A */
    int dense;
    double *L;               /* dense: m x m row-major lower Cholesky factor */
    cholmod_common cc;
    int cc_started;
    cholmod_factor *F;
    cholmod_dense *Bh, *Xh, *Wk_Y, *Wk_E;   /* rhs m x 3, solution, CHOLMOD workspaces */

    /* linear polynomial: p(x) = g0 + sum_l g_l (x_l - pc_l) / R, in reduced basis Q = P D V */
    int k;                   /* kept polynomial directions (0 without polynomial) */
    double pc[3];            /* centres' mean */
    double DV[16];           /* 4 x k (row-major, stride 4): D V */
    double *Q;               /* m x k column-major */
    double *W;               /* m x k column-major: A^-1 Q */
    double Sl[16];           /* k x k Cholesky factor of S = Q^T W (row-major, stride 4) */
    double g[4][3];          /* polynomial in the basis [1, (x - pc)/R], per output axis */
    float fpc[3], fg0[3], fG[9]; /* float: p(x) = fg0 + fG (x - fpc), fG row-major */

    /* centre grid for evaluation (cell R), built with the start points */
    csrbf_grid cgrid;

    /* fold-over guard (csrbf_guard.c), built with the start points: for centre i its
     * neighbours within 2R gn_idx[gn_start[i] .. gn_start[i+1]) (i itself included) with
     * weights gn_w = w(|s_i - s_j| / R - 1) / R; clusters = components of that graph */
    size_t *gn_start;        /* m + 1 */
    uint32_t *gn_idx;        /* gn_start[m] */
    double *gn_w;
    size_t gn_cap;
    uint32_t *cluster;       /* m: cluster of each centre, 0 .. nclusters-1 */
    size_t nclusters;
    double *cl_L, *cl_t;     /* m each: per-cluster bound and scale (scratch) */
    double *anorm;           /* m: |alpha_j| (scratch) */
    uint32_t *gg_u32;        /* close groups (csrbf_guard.c close_groups): 4 m + 1: each
                                centre's group or UINT32_MAX (gg_group), the groups' member
                                lists gg_start (ngroups + 1) and gg_idx */
    uint32_t *gg_group, *gg_start, *gg_idx;
    double *gg_f64;          /* 4 m + 1: each group's mean centre gg_c (3 per group), each
                                centre's distance to its group's mean gg_r */
    double *gg_c, *gg_r;
    size_t ngroups;
    int g_paired;            /* the bounds use the group terms (csrbf_guard.c: a composed
                                step's last maps); 0 outside guarded() */
    float *g_p, *g_e;        /* guarded step: current start and end points, n x 3 */
    size_t g_cap;
    csrbf_points *g_tmp;     /* guarded step: index of the intermediate shape */
    uint32_t *g_blk;         /* csrbf_guarded_step_touched: block lists (4 x nblocks) and
                                vertex ranges (2 x (nblocks + 1)) */
    size_t g_bcap;           /* nblocks they were made for */

    /* csrbf_evaluate's block selection (blocks meeting a support, centre masks), kept for
     * the points stamp sel_pts and the centres stamp sel_ctr: anchored frames (same centres,
     * same points) reuse it. Used only by the holder of scratch_busy. */
    uint64_t centres_stamp;  /* a fresh csrbf_new_stamp() at every set_start_points */
    uint64_t sel_pts, sel_ctr;
    uint64_t sel_id;         /* a fresh stamp whenever the kept selection changes */
    int sel_refined;         /* the kept selection has been refined (csrbf_eval.c) */
    uint32_t *sel_blk;       /* sel_cap each: blocks, increasing */
    uint64_t *sel_msk;       /* their centre masks (bit j: centre j) */
    size_t *sel_cum;         /* sel_cap + 1: prefix costs of the blocks (csrbf_select.c) */
    size_t sel_k, sel_evals, sel_cap; /* blocks listed, sum of their mask bits */

    /* evaluation scratch: one user at a time; concurrent callers allocate their own */
    atomic_flag scratch_busy;
    void *scratch;
    size_t scratch_cap;
    /* the kept selection's weight cache (csrbf_sched.c), filled once it is refined, for frames
     * small enough to stay in cache: valid while sel_w_id == sel_id. One aligned block of sel_wbytes:
     * the pairs' weights (16 floats each), their support masks (uint16), the items' first
     * pairs (uint32, sel_k + 1) and prefix costs (size_t, sel_k + 1); and the selection's
     * statistics that do not change while the centres stay (vertex-centre pairs in support,
     * vertices with one or more), counted once at the fill instead of every frame. */
    uint64_t sel_w_id;
    size_t sel_w_pairs, sel_w_moved;
    void *sel_wmem;
    size_t sel_wbytes;
};

struct csrbf_points {
    size_t n, nblocks;
    uint64_t stamp;          /* a fresh csrbf_new_stamp() at every create / update */
    float *xyz;              /* n x 3, original order */
    float *s[3];             /* nblocks * CSRBF_BLOCK each: coordinates, structure of arrays,
                                the last block padded with copies of its first vertex */
    float *lo[3], *hi[3];    /* nblocks each: block bounding boxes */
    float blo[3], bhi[3];    /* bounding box of all vertices */
    /* box tree over the blocks (csrbf_evaluate's block selection): level 0 is lo/hi (the
     * blocks), node i of level l + 1 bounds nodes CSRBF_FAN i .. CSRBF_FAN i + CSRBF_FAN - 1
     * of level l; the top level has at most CSRBF_FAN nodes. Every level is allocated to a
     * multiple of CSRBF_FAN, the padding holding empty boxes (lo = +inf, hi = -inf), so that
     * a node's children are always one full group. tlo[0] / thi[0] alias lo / hi. */
    int tlevels;             /* levels including the blocks' (1 when nblocks <= CSRBF_FAN) */
    size_t tcount[CSRBF_TREE_MAX];            /* nodes per level (unpadded) */
    float *tlo[CSRBF_TREE_MAX][3], *thi[CSRBF_TREE_MAX][3];
    struct csrbf_near *near; /* csrbf_points_index_nearest's index, or NULL */
    uint32_t *pend;          /* the vertices whose new positions the index has not taken yet
                                (csrbf_points_update_ranges_later: those of its ranges whose
                                position changed, bitwise); npend of them, room for pend_cap */
    size_t npend, pend_cap;
};

/* csrbf_points_index_nearest's index: the vertices in Morton order of their positions when it
 * was made (kept since: positions change, places do not), cut into blocks of CSRBF_BLOCK
 * places with a box tree laid out as csrbf_points' own (level 0 the blocks, each node of
 * level l + 1 bounding CSRBF_FAN of level l, every level padded to a multiple of CSRBF_FAN
 * with empty boxes). A mesh's own order may scatter 16 consecutive vertices over the face;
 * these blocks stay compact whatever it is. */
struct csrbf_near {
    size_t nblocks;
    uint32_t *vert;          /* nblocks * CSRBF_BLOCK: the vertex at each place (the last
                                block padded with its first place's vertex) */
    uint32_t *place;         /* n: each vertex's place */
    float *s[3];             /* by place: coordinates */
    int levels;
    size_t count[CSRBF_TREE_MAX];
    float *lo[CSRBF_TREE_MAX][3], *hi[CSRBF_TREE_MAX][3];
    uint8_t *dirty[CSRBF_TREE_MAX]; /* by node: to refit (csrbf_points_update_ranges) */
};

/* A process-wide increasing counter (thread-safe, never 0): stamps of point contents and
 * centre sets, so that a cached block selection is never taken for another one. */
uint64_t csrbf_new_stamp(void);

/* csrbf_guarded_step_touched's access to a touch (csrbf_touch.c). csrbf_touch_prev: the
 * blocks the last call computed from the kernel (increasing; *k of them) and, in *full (may
 * be NULL), whether the next call writes every block. csrbf_touch_set: the state a composed
 * step leaves: the blocks computed := blk[0 .. k) (increasing: where the output may differ
 * from the base), the blocks written := wr[0 .. kw) (increasing; they hold blk), or every
 * block when all; the kept-selection shortcut is dropped. csrbf_touch_for: t was made for p.
 * csrbf_block_ranges: increasing blocks blk[0 .. k) of n vertices as vertex ranges (first,
 * count) in ranges (room for 2 k), runs of consecutive blocks joined; returns their number. */
size_t csrbf_block_ranges(const uint32_t *blk, size_t k, size_t n, uint32_t *ranges);
const uint32_t *csrbf_touch_prev(const csrbf_touch *t, size_t *k, int *full);
void csrbf_touch_set(csrbf_touch *t, const uint32_t *blk, size_t k, const uint32_t *wr, size_t kw,
                     int all);
int csrbf_touch_for(const csrbf_touch *t, const csrbf_points *p);

/* Build the guard's neighbour lists and clusters for the current centres (solver.c calls it
 * from set_start_points); free them (destroy). */
int csrbf_guard_prepare(csrbf_solver *s);
void csrbf_guard_free(csrbf_solver *s);

/* psi(r) for r in [0, 1) in double (no range check). */
double csrbf_psi(csrbf_kernel k, double r);
/* dpsi/dr divided by r, for r in [0, 1): the gradient of phi(|x - s| / R) in x is
 * dpsi_over_r * (x - s) / R^2. For psi30 (gradient undefined at 0) 0 is returned at r = 0. */
double csrbf_dpsi_over_r(csrbf_kernel k, double r);

#endif
