/* csrbf: space deformation by compactly supported radial basis functions (Wendland CSRBFs).
 *
 * The map (Kojekine, Savchenko, Senin, Hagiwara, Eurographics 2002 short paper; Sato,
 * Savchenko, Ohbuchi, "3D Freeform Design: Interactive Shape Deformations by the Use of
 * CyberGlove", Cyberworlds 2004):
 *
 *     T(x) = x + sum_i alpha_i * phi(|x - s_i| / R) + p(x),       alpha_i in R^3
 *     T(s_i) = d_i                       (interpolation of the control vectors s_i -> d_i)
 *     sum_i alpha_i q(s_i) = 0           (for every q in the span of p; only with p)
 *
 * phi is a Wendland function (zero beyond r = 1), R the support radius in mesh units, p an
 * optional linear polynomial. A csrbf_solver holds the centres s_i, the factor of
 * A_ij = phi(|s_i - s_j| / R) and the coefficients; a csrbf_points holds the mesh vertices
 * with a spatial index; csrbf_evaluate applies T to every vertex.
 *
 * Typical use, anchored (start points fixed, end points follow the glove every frame):
 *
 *     csrbf_options o = {0}; o.radius = 20.0;
 *     csrbf_solver *s; csrbf_solver_create(&o, &s);
 *     csrbf_points *pts; csrbf_points_create(nv, base_xyz, &pts);
 *     csrbf_solver_set_start_points(s, n, start);      // factor once
 *     for each frame:
 *         csrbf_solver_set_end_points(s, end);         // two triangular solves
 *         csrbf_evaluate(s, pts, out_xyz, 0, NULL);    // T at every vertex
 *
 * Results: CSRBF_OK (0), positive warnings (the call succeeded), negative errors (the call
 * changed nothing unless its documentation says otherwise). csrbf_solver_message() names the
 * offending argument of the last call on a solver. The library never prints.
 *
 * Thread safety: a csrbf_solver is not thread-safe, except that csrbf_evaluate and
 * csrbf_solver_map_point may run concurrently on the same solver (and the same points) from
 * several threads as long as no other call modifies either. csrbf_evaluate runs its own
 * OpenMP team. Everything else (kernel evaluation, strerror) is thread-safe.
 */
#ifndef CSRBF_H
#define CSRBF_H

#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Wendland functions psi_{3,k}(r) on 0 <= r <= 1 (Wendland 1995, Adv. Comput. Math. 4:389;
 *  Wendland 2005, ch. 9), all positive definite in R^3 and normalised so that psi(0) = 1:
 *    CSRBF_PSI31: (1-r)^4 (4r+1)                  C2, the default
 *    CSRBF_PSI30: (1-r)^2                         C0 (its gradient jumps at the centre)
 *    CSRBF_PSI32: (1-r)^6 (35r^2+18r+3) / 3       C4 (the /3 normalises psi(0) to 1) */
typedef enum { CSRBF_PSI31 = 0, CSRBF_PSI30, CSRBF_PSI32 } csrbf_kernel;

/** The polynomial part p(x). NONE keeps the map local (vertices outside every support do not
 *  move); LINEAR adds p(x) = b + B x, which reproduces affine motions exactly but is global
 *  (csrbf.md pitfall 3). */
typedef enum { CSRBF_POLY_NONE = 0, CSRBF_POLY_LINEAR } csrbf_poly;

/** Result codes. Errors are negative errno values (the project's convention,
 *  core/common/fp_error.h; the engine stays standalone and does not include it) and warnings
 *  are small positive numbers: a caller may return an error code as it is. */
enum {
    CSRBF_OK = 0,
    CSRBF_WARN_MERGED = 1,      /* coincident / near-coincident start points were merged */
    CSRBF_WARN_POLY_RANK = 2,   /* the linear polynomial was reduced: centres collinear,
                                   coplanar or fewer than 4 (csrbf.md pitfall 2) */
    CSRBF_WARN_FOLDOVER = 3,    /* some |alpha_i| exceeds the fold-over bound R / max|psi'|:
                                   the map may not be injective (csrbf.md pitfall 4) */
    CSRBF_WARN_LIMITED = 4,     /* the fold-over guard scaled control vectors back: the map
                                   stops short of some end points (csrbf_solver_limit_end_points,
                                   csrbf_guarded_step) */
    CSRBF_WARN_SUBSTEPS = 5,    /* csrbf_guarded_step split the step into composed sub-steps
                                   and reached every end point */
    CSRBF_ERR_INVALID = -EINVAL, /* a bad argument; see csrbf_solver_message() */
    CSRBF_ERR_NOMEM = -ENOMEM,  /* out of memory */
    CSRBF_ERR_NUMERIC = -1101,  /* factorisation failed or a result was not finite; equal to
                                   the project's FP_ENUMERIC */
    CSRBF_ERR_STATE = -ENODATA  /* called out of order: no start points (or no end points
                                   where the call needs coefficients) */
};

/** A static English text for a result code ("unknown result" for others). Thread-safe. */
const char *csrbf_strerror(int result);

/** The instruction set csrbf_evaluate's fast path runs on in this process: "avx512" (AVX-512F),
 *  "avx2" (AVX2 + FMA; the kernels are the same code on two 8-lane halves) or "portable" (no
 *  fast path: the general path's compiler-vectorised C). Chosen once, at the first call or
 *  evaluation, from the CPU; the environment variable CSRBF_ISA=avx2 or CSRBF_ISA=none (or
 *  =portable) asks for less (tests, comparisons); any other value changes nothing. A static string; thread-safe. For benchmark headers and bug
 *  reports: the engine's speed differs several-fold between them. */
const char *csrbf_simd_path(void);

/** Solver options. A zero-initialised struct is valid once radius is set.
 *  - kernel: CSRBF_PSI31 by default.
 *  - poly: CSRBF_POLY_NONE by default.
 *  - radius: support radius R in mesh units; required; finite, 1e-15 <= R <= 1e15.
 *  - merge_tolerance: start points closer than merge_tolerance * R are merged into one centre
 *    (csrbf.md pitfall 1). 0 selects the default CSRBF_DEFAULT_MERGE_TOLERANCE (1e-4: the
 *    2x2 block of two centres that far apart has a condition number of 2e7 for psi31 and
 *    psi32, 1e4 for psi30, harmless in double; ten centres within 3e-4 R of each other reach
 *    1e11 to 1e13). csrbf_evaluate sums in float: centres that close whose control vectors
 *    differ get coefficients up to the condition number times them, of opposite signs, and
 *    the float sum then misses T by about 2^-24 |alpha| (a pair 2e-4 R apart pulled 0.06 R
 *    different ways: 55% of the control vectors for psi31, 67% for psi32, 0.03% for psi30;
 *    csrbf_solver_map_point, in double, 1e-7); such a map folds over anyway
 *    (CSRBF_WARN_FOLDOVER), and csrbf_solver_limit_end_points scales it back, the error
 *    with it (5e-7). Must be finite and in [0, 0.5).
 *  - dense_limit: factor A with a dense Cholesky when the number of (merged) centres is at most
 *    this, else with CHOLMOD (supernodal or simplicial as CHOLMOD chooses, AMD, METIS where
 *    fill is high). 0 selects CSRBF_DEFAULT_DENSE_LIMIT (200); a negative value always uses
 *    CHOLMOD.
 *  - threads: OpenMP threads for csrbf_evaluate; 0 = the OpenMP default (omp_get_max_threads).
 *    Work below about 8 us on one core (counted from the blocks actually visited) runs on the
 *    calling thread regardless. */
typedef struct csrbf_options {
    csrbf_kernel kernel;
    csrbf_poly poly;
    double radius;
    double merge_tolerance;
    int dense_limit;
    int threads;
} csrbf_options;

#define CSRBF_DEFAULT_MERGE_TOLERANCE 1e-4
#define CSRBF_DEFAULT_DENSE_LIMIT 200

/** Largest accepted |coordinate| of any start, end or base point, in mesh units. */
#define CSRBF_MAX_COORD 1e15

typedef struct csrbf_solver csrbf_solver;
typedef struct csrbf_points csrbf_points;

/** psi(r) and dpsi/dr of a kernel at r >= 0 (both 0 for r >= 1), in double.
 *  Errors: CSRBF_ERR_INVALID for an unknown kernel, a NaN or negative r, or NULL outputs
 *  (one of psi / dpsi_dr may be NULL, not both). Thread-safe. Source: csrbf.md table. */
int csrbf_kernel_eval(csrbf_kernel kernel, double r, double *psi, double *dpsi_dr);

/** The fold-over bound of a kernel as a fraction of R: 1 / max_r |psi'(r)| (about 0.474 for
 *  psi31, 0.5 for psi30, 0.40 for psi32, each in closed form). A single centre with |alpha|
 *  below bound * R keeps T injective (det of the Jacobian > 0). Returns 0 for an unknown
 *  kernel. Thread-safe. Source: docs/csrbf.md, pitfall 4 (fold-over). */
double csrbf_kernel_foldover_bound(csrbf_kernel kernel);

/** Create a solver. *out receives the solver (NULL on error); free it with
 *  csrbf_solver_destroy. Errors: CSRBF_ERR_INVALID (bad options; no solver exists to hold the
 *  message, so the text is available from csrbf_options_message()), CSRBF_ERR_NOMEM. */
int csrbf_solver_create(const csrbf_options *options, csrbf_solver **out);

/** The reason the last csrbf_solver_create on this thread failed ("" if it did not).
 *  Thread-local storage; valid until the next create on this thread. */
const char *csrbf_options_message(void);

/** Free a solver and everything it owns; sets *solver to NULL. NULL and *NULL are no-ops. */
void csrbf_solver_destroy(csrbf_solver **solver);

/** The last call's message on this solver: "" after success, else a sentence naming the
 *  argument, e.g. "start point 3 has a NaN coordinate", or describing the warning.
 *  Owned by the solver; valid until the next call on it. */
const char *csrbf_solver_message(const csrbf_solver *solver);

/** Bit mask (1u << code) of the warnings raised by the last set_start_points, set_end_points,
 *  solve, limit_end_points or guarded_step call (the last two add LIMITED and SUBSTEPS). */
unsigned csrbf_solver_warnings(const csrbf_solver *solver);

/** Set the control vectors' start points (the centres) and factor the system.
 *  start: n x 3 floats (row i = s_i), mesh units, finite, |coord| <= CSRBF_MAX_COORD;
 *  n >= 1. The data is copied.
 *  Work: neighbours of each centre through a hash grid of cell R (O(n k), k = neighbours);
 *  merge start points closer than merge_tolerance * R (greedy in index order: a point joins
 *  the first earlier merged centre within the tolerance; the merged centre sits at that first
 *  point and its displacement is the mean displacement d_i - s_i of its members, so merged
 *  points share one coefficient); build A_ij = phi(|s_i - s_j| / R); factor A = L L^T (dense
 *  or CHOLMOD, see dense_limit). With CSRBF_POLY_LINEAR also W = A^-1 Q and S = Q^T W, where
 *  Q = P D V holds the polynomial basis q(x) = [1, (x - c)/R] (c the centres' mean) at the
 *  centres, scaled by D (the constant column to unit norm, the three coordinate columns by
 *  one common factor, so that the eigenvectors are the centres' principal axes in any
 *  orientation) and restricted by V to the eigenvectors of D P^T P D whose singular values
 *  exceed 1e-6 of the largest and 4x what the float rounding of the start points gives
 *  (sqrt(3m) 2^-24 max|coordinate| / R): the directions that the centres cannot determine
 *  (collinear, coplanar, n < 4, within rounding of it) are dropped from p, which is then
 *  constant along them (along the line's or plane's normals), with CSRBF_WARN_POLY_RANK.
 *  The factor is reused by every set_end_points until the next set_start_points. The
 *  coefficients are reset to zero (T = identity) until end points are set.
 *  Returns CSRBF_OK, CSRBF_WARN_MERGED / CSRBF_WARN_POLY_RANK (success, see
 *  csrbf_solver_warnings for all raised), or CSRBF_ERR_INVALID (NULL, n == 0, a bad
 *  coordinate; message names the point), CSRBF_ERR_NOMEM, CSRBF_ERR_NUMERIC; after an error
 *  the solver has no start points (set_end_points gives CSRBF_ERR_STATE).
 *  Source: csrbf.md "Solving" (block elimination of the saddle system). */
int csrbf_solver_set_start_points(csrbf_solver *solver, size_t n, const float *start);

/** Set the end points and compute the coefficients, reusing the factor (anchored mode).
 *  end: n x 3 floats for the n of the last set_start_points, same order, same rules.
 *  H = d - s; Y = A^-1 H (two triangular solves); with the polynomial c = S^-1 Q^T Y and
 *  alpha = Y - W c. No allocation. Returns CSRBF_OK, CSRBF_WARN_FOLDOVER (some merged centre
 *  has |alpha| > csrbf_kernel_foldover_bound * R; the coefficients are set), or
 *  CSRBF_ERR_INVALID / CSRBF_ERR_STATE / CSRBF_ERR_NUMERIC (coefficients unchanged). */
int csrbf_solver_set_end_points(csrbf_solver *solver, const float *end);

/** set_start_points(n, start) then set_end_points(end). Returns the first error, else the
 *  end-point call's warning if any, else the start-point call's. */
int csrbf_solver_solve(csrbf_solver *solver, size_t n, const float *start, const float *end);

/** Number of centres after merging (0 before start points are set). */
size_t csrbf_solver_centres(const csrbf_solver *solver);

/** Copy out the current map: centres (m x 3, merged, in first-occurrence order), alpha
 *  (m x 3) and the polynomial p(x) = b + B x as poly[0..2] = b, poly[3..11] = B row-major
 *  (B[3*i+j] multiplies x_j in component i; all zero without a polynomial). Any output may
 *  be NULL; m = csrbf_solver_centres(). Errors: CSRBF_ERR_INVALID (NULL solver),
 *  CSRBF_ERR_STATE (no start points). Thread-safe on a const solver. */
int csrbf_solver_get_coefficients(const csrbf_solver *solver, double *centres, double *alpha,
                                  double poly[12]);

/** Exact T(x) in double at one point, and its Jacobian dT/dx (row-major 3x3, jac[3*i+j] =
 *  dT_i/dx_j) if jac is not NULL. For psi30 the gradient at a centre is taken as 0.
 *  Errors: CSRBF_ERR_INVALID (NULL, non-finite x), CSRBF_ERR_STATE (no start points).
 *  Thread-safe on a const solver. O(number of centres). */
int csrbf_solver_map_point(const csrbf_solver *solver, const double x[3], double out[3],
                           double jac[9]);

/** Create a vertex set: copies n x 3 floats (finite, |coord| <= CSRBF_MAX_COORD) and cuts
 *  them into blocks of 16 consecutive vertices (structure of arrays) with bounding boxes, and
 *  a tree of boxes over the blocks (each node bounds 16 consecutive nodes of the level below)
 *  through which csrbf_evaluate finds the blocks a support meets without scanning them all.
 *  Locality comes from the vertex order (grids, scanned and modelled meshes keep neighbours
 *  close in index); a scrambled order stays correct but skips fewer blocks.
 *  1 <= n < 2^32. Errors: CSRBF_ERR_INVALID (*out = NULL), CSRBF_ERR_NOMEM. */
int csrbf_points_create(size_t n, const float *xyz, csrbf_points **out);

/** Replace the positions (same n, same vertex order), e.g. after a commit in unanchored mode;
 *  block boxes and the tree are recomputed (O(n)). Errors: CSRBF_ERR_INVALID (points
 *  unchanged). Not while any other call (an evaluate, a nearest query) reads these points:
 *  the caller orders them (the session does all on its thread). */
int csrbf_points_update(csrbf_points *points, const float *xyz);

/** Replace the positions of some vertices only: the ranges (first vertex, count) pairs,
 *  e.g. those csrbf_touch_ranges reports after a commit; xyz is the full n x 3 array, of
 *  which only the listed vertices are read. Their blocks' boxes are recomputed (O(vertices
 *  listed)), and the tree nodes above them; the whole-set box only grows, which keeps every
 *  test conservative.
 *  Errors: CSRBF_ERR_INVALID (NULL, a range beyond n, a bad coordinate: nothing changed). */
int csrbf_points_update_ranges(csrbf_points *points, const float *xyz, const uint32_t *ranges,
                               size_t nranges);

/** csrbf_points_update_ranges (xyz: the full n x 3 array, mesh units, of which only the
 *  listed vertices are read; ranges: nranges (first vertex, count) pairs), but the nearest
 *  index (csrbf_points_index_nearest), if any, takes the new positions later: at csrbf_points_sync_nearest, or first thing in the next
 *  update or csrbf_points_index_nearest. Until then csrbf_points_nearest answers from the
 *  points' own blocks (the same answers, slower on a scrambled vertex order). For a commit in
 *  a real-time frame: the index's scattered writes (most of a commit's update on a large face:
 *  docs/performance.md) move to the next frame's sync, and only the listed vertices whose position changed
 *  (bitwise) are kept for it, not the whole ranges (out of memory for them: the index is
 *  updated now). Same errors as csrbf_points_update_ranges; same thread rules. */
int csrbf_points_update_ranges_later(csrbf_points *points, const float *xyz,
                                     const uint32_t *ranges, size_t nranges);

/** The nearest index takes the positions csrbf_points_update_ranges_later left to it (the
 *  scattered writes and its boxes' refit, O(vertices listed)); nothing pending or no index:
 *  nothing. Modifies the points (no concurrent call on them). NULL: nothing. */
void csrbf_points_sync_nearest(csrbf_points *points);

/** Number of vertices. */
size_t csrbf_points_count(const csrbf_points *points);

/** A new csrbf_points holding src's vertices, as csrbf_points_create on them; *out owned by
 *  the caller (csrbf_points_destroy). Errors: CSRBF_ERR_INVALID (NULL), CSRBF_ERR_NOMEM.
 *  O(n). Thread-safe on a const src. */
int csrbf_points_clone(const csrbf_points *src, csrbf_points **out);

/** dst := src's vertices, their blocks, boxes and tree copied (one memcpy per array, no box
 *  recomputed), for two csrbf_points of one vertex count; dst's nearest index, when it has
 *  one (csrbf_points_index_nearest; src's is not copied), refilled from the new positions
 *  (O(n)). Errors: CSRBF_ERR_INVALID (NULL, other counts). O(n) copies. Not thread-safe on
 *  dst. */
int csrbf_points_copy(csrbf_points *dst, const csrbf_points *src);

/** A spatial index for csrbf_points_nearest: the vertices in Morton order of their positions
 *  now (21 bits an axis over their box, ties by index), cut into blocks of 16 with a box tree
 *  as the points' own, so that a query opens only blocks near it whatever the vertex order.
 *  A mesh's own order may scatter 16 consecutive vertices over the face, and then a query
 *  opens hundreds of blocks it has nothing in: the ICT face's own blocks' boxes are 4.6 mesh
 *  units across on average (Morton blocks: 2.1), on a face 47.5 across; subdivided to 1.7M
 *  vertices, 1.31 (Morton: 0.31), where a fingertip 13 units from the face opened 414
 *  blocks within the reach of 2.85 through the own blocks. The order is fixed here; csrbf_points_update and
 *  csrbf_points_update_ranges keep the index current at little cost (the vertices whose
 *  position changed, found in their own pass over the blocks, go to their places, and only
 *  those blocks and the nodes above them are refit: a rig's pose that moves the jaw does not
 *  refill the whole index; its cost, in docs/performance.md, is mostly the moved vertices'
 *  stores at their places, none in the cache, the refit little),
 *  csrbf_points_copy by refilling it (O(n)). Results are the same
 *  with or without it, bit for bit; only the work differs. Memory: about 22 bytes a vertex.
 *  O(n log n) (a sort); a second call does nothing. csrbf_points_clone makes none.
 *  Errors: CSRBF_ERR_INVALID (NULL), CSRBF_ERR_NOMEM (points unchanged). Not thread-safe on
 *  points. */
int csrbf_points_index_nearest(csrbf_points *points);

/** Nearest vertex of each query point: out_dist[i] = min over vertices v of |v - q_i| within
 *  max_dist (mesh units; INFINITY for no limit), computed in float as
 *  sqrtf(dx*dx + dy*dy + dz*dz) so that it equals a scalar brute-force loop bit for bit;
 *  out_index[i] (may be NULL) the vertex (the smallest index among equals). Where no vertex
 *  is within max_dist (sqrtf of the squared distance > max_dist): INFINITY and UINT32_MAX.
 *  queries: nq x 3 floats, finite.
 *  Work, per query: a descent of the box tree (csrbf_points_index_nearest's when made, else
 *  the points' own), each node's 16 children's boxes in one vectorised pass, the nearest
 *  first, then those within both max_dist and the best so far; 16 vertices per vectorised
 *  step at the blocks. A finite max_dist is what keeps it cheap: a query farther than it
 *  opens nothing.
 *  Errors: CSRBF_ERR_INVALID (NULL, a non-finite query, a NaN or negative max_dist).
 *  Thread-safe on const points; no allocation. */
int csrbf_points_nearest(const csrbf_points *points, const float *queries, size_t nq,
                         float max_dist, float *out_dist, uint32_t *out_index);

/** Free a vertex set; sets *points to NULL. NULL and *NULL are no-ops. */
void csrbf_points_destroy(csrbf_points **points);

/** Up to this many (merged) centres csrbf_evaluate selects blocks and their centres through
 *  the points' block tree with one 64-bit mask per block and runs the fused AVX-512 path;
 *  beyond, it searches the centre grid per block (a slower general path, still correct). */
#define CSRBF_FAST_MAX_CENTRES 64

/** Flags for csrbf_evaluate. */
enum {
    CSRBF_EVAL_JACOBIAN = 1u   /* also compute stats->min_jacobian_det (slower path) */
};

/** Statistics of one csrbf_evaluate call. */
typedef struct csrbf_eval_stats {
    size_t pairs;              /* (vertex, centre) pairs inside the support: the paper's
                                  "number of displacement calculations" */
    size_t moved;              /* vertices inside at least one support (all with a polynomial) */
    double max_displacement;   /* max |T(x) - x| over the vertices, mesh units */
    double min_jacobian_det;   /* min det dT/dx over the moved vertices, above 1 where every
                                  one has det > 1 (1 if none moved); <= 0 means fold-over.
                                  Only with CSRBF_EVAL_JACOBIAN, else 1 */
} csrbf_eval_stats;

/** deformed[v] = T(base[v]) for every vertex v (n x 3 floats, original vertex order; must not
 *  overlap the solver's or the points' memory). Only (vertex, centre) pairs whose block boxes
 *  meet the support are visited: with up to CSRBF_FAST_MAX_CENTRES centres the blocks and a
 *  64-bit mask of their centres come from a walk of the points' block tree for all centres at
 *  once (cost: the tree nodes near a support, not the mesh; where every support holds every
 *  vertex, no walk at the first use: every pair is computed), kept in the solver from its
 *  second use on while the centres and the points are unchanged (anchored frames), then
 *  trimmed to the pairs whose support holds a vertex of the block, and then with each pair's
 *  kernel weights cached (they depend on the centres and the vertices only: an anchored frame
 *  adds alpha_j w, bit for bit what the kernel gives; used while the frame's data stays in
 *  cache, at most 66 bytes per pair); blocks outside every support are copied from the base. A selection used once (new
 *  centres: unanchored frames) is walked and evaluated part by part inside the threads.
 *  The arithmetic is float (positions, coefficients), the coefficients having been solved in
 *  double. Without a polynomial a vertex outside every
 *  support gets exactly its base position, bit for bit. Vectorised (AVX-512 intrinsics with
 *  r from rsqrt14 + one Newton step where the CPU has it, else the same code on AVX2 + FMA
 *  (rsqrt + one Newton step), else target_clones of portable C; chosen at run time, and the
 *  environment variable CSRBF_ISA=avx2 or =none asks for less) and parallel over blocks with OpenMP
 *  (options.threads), one contiguous part of equal cost per thread (a thread done with its
 *  own takes what is left of the others'); work below about 8 us on
 *  one core, counted from the blocks visited, stays on the calling thread.
 *  stats may be NULL; with stats the pair count, moved count and maximum
 *  displacement are filled in, counted per block inside the vectorised kernel (the fast path
 *  stays, at a small cost: docs/performance.md), and with flags & CSRBF_EVAL_JACOBIAN the minimum Jacobian
 *  determinant too (a slower general path, as are the polynomial and more than
 *  CSRBF_FAST_MAX_CENTRES centres). Errors: CSRBF_ERR_INVALID (NULL, unknown flag),
 *  CSRBF_ERR_STATE (no start points), CSRBF_ERR_NOMEM. Thread-safe on a const solver and const
 *  points (a concurrent caller works in its own memory). Source: the map T above. */
int csrbf_evaluate(const csrbf_solver *solver, const csrbf_points *base, float *deformed,
                   unsigned flags, csrbf_eval_stats *stats);

/* ------------------------------------------------- work that follows the supports
 *
 * csrbf_evaluate writes every vertex. For a frame loop whose output buffer persists, a
 * csrbf_touch remembers which blocks (16 consecutive vertices) the last call rewrote from
 * the kernel; csrbf_evaluate_touched then rewrites only the blocks inside a support this call
 * (computed) or the last (restored to the base) and leaves the others alone: they equal the
 * base already. Contract: the same points and the same output buffer on every call with one
 * touch; nothing else writes the buffer. After the base changes in a way the output does not
 * already show (csrbf_points_update on other data, an undo, a new mesh) call
 * csrbf_touch_reset: the next call writes every block. After a commit that makes the output
 * the new base (base := deformed, csrbf_points_update_ranges with the reported ranges),
 * call csrbf_touch_commit: no block then differs from the base. */

typedef struct csrbf_touch csrbf_touch;

/** A touch state for `points` (which it refers to, not copies: the points must outlive the
 *  touch; the first evaluate writes everything). Free with csrbf_touch_destroy. A touch is
 *  used by one evaluate at a time (the thread rules of the solver it goes with). Errors:
 *  CSRBF_ERR_INVALID, CSRBF_ERR_NOMEM. */
int csrbf_touch_create(const csrbf_points *points, csrbf_touch **out);
/** Free; sets *touch to NULL. NULL and *NULL are no-ops. */
void csrbf_touch_destroy(csrbf_touch **touch);
/** The next csrbf_evaluate_touched writes every block (the base changed). */
void csrbf_touch_reset(csrbf_touch *touch);
/** The output buffer has become the base: no block differs from it any more (also after a
 *  csrbf_touch_reset or a fresh touch: the next call writes only the blocks in a support). */
void csrbf_touch_commit(csrbf_touch *touch);
/** The vertex ranges the last csrbf_evaluate_touched wrote, as *ranges[2k] = first vertex,
 *  [2k+1] = count, increasing and disjoint; returns their number (0 before any call and after
 *  csrbf_touch_commit). The viewer uploads and re-normals only these. Owned by the touch,
 *  valid until its next use. */
size_t csrbf_touch_ranges(const csrbf_touch *touch, const uint32_t **ranges);

/** csrbf_evaluate with a persistent output (contract above): deformed equals T(base) on return,
 *  bit for bit what csrbf_evaluate writes, but only the blocks in a support now or at the last
 *  call are written, so the cost follows the supports, not the mesh: the blocks come from the
 *  block tree (or the solver's kept selection), the bookkeeping is O(blocks written), and a
 *  call whose blocks are those of the last call (anchored frames) skips it. Statistics as
 *  csrbf_evaluate.
 *  With the linear polynomial every vertex moves and every block is written.
 *  Errors: as csrbf_evaluate, and CSRBF_ERR_INVALID when touch was made for other points.
 *  Not thread-safe on one touch. */
int csrbf_evaluate_touched(const csrbf_solver *solver, const csrbf_points *base,
                           csrbf_touch *touch, float *deformed, unsigned flags,
                           csrbf_eval_stats *stats);

/* ------------------------------------------------------------------ fold-over guard
 *
 * T(x) = x + f(x) is injective and has det dT/dx > 0 everywhere when f's Lipschitz constant
 * L is below 1: |T(x) - T(y)| >= (1 - L) |x - y|, and ||Df|| < 1 keeps every eigenvalue of
 * I + Df off the negative axis (csrbf.md pitfall 4). With M = max_r |psi'(r)| and the
 * gradient |grad phi(|x - s_j| / R)| = |psi'(r_j)| / R,
 *
 *     ||Df(x)|| <= sum_{j : |x - s_j| < R} |alpha_j| |psi'(r_j)| / R  +  ||B||_F
 *
 * (B the linear polynomial's matrix, 0 without one). The engine bounds the sum per centre
 * i: every x inside i's support has r_j >= |s_i - s_j| / R - 1 for each j containing it,
 * and only j with |s_i - s_j| < 2R can contain it, so
 *
 *     L <= max_i sum_{j : |s_i - s_j| < 2R} |alpha_j| w(|s_i - s_j| / R - 1) / R + ||B||_F,
 *     w(a) = max_{r in [max(a, 0), 1]} |psi'(r)|   (= M while a <= argmax |psi'|)
 *
 * a rigorous bound, exact for one centre (fold-over starts at |alpha| = R / M there). The
 * neighbour lists (centres within 2R, through the centre grid) and the clusters (connected
 * components of "supports overlap", |s_i - s_j| < 2R) are built by set_start_points; the
 * bound then costs O(sum of neighbour counts) per update (about m^2 for m <= 10 fingertips).
 * Without the polynomial A is block-diagonal over clusters, so a cluster's coefficients
 * depend only on its own control vectors, linearly: scaling its displacements d_i - s_i by
 * t scales its alphas and its bound by t. */

/** Default margin of the guard: a map is accepted when its bound L <= 0.9. */
#define CSRBF_GUARD_MARGIN 0.9
/** Default limit of composed sub-steps in csrbf_guarded_step. */
#define CSRBF_GUARD_MAX_SUBSTEPS 16
/** Close groups in the bound of a composed step's last maps (csrbf_guarded_step): each
 *  centre joins the first group whose first centre lies under this x R from it. For a
 *  group G with mean centre c, row i's terms sum_{j in G} |alpha_j| w_ij become, where
 *  smaller, |sum_j alpha_j| w_ic + sum_j |alpha_j| min(H |s_j - c| / R^2, w_ij + w_ic), H the
 *  largest norm of the kernel's Hessian (20 for psi31, 56/3 for psi32; psi30 is not
 *  grouped): still rigorous, and close skin pulled apart or shuffled, whose fields cancel but
 *  for their differences, gets there in fewer maps (skin pulled apart from 0.01 R: 13 under
 *  the default 16 maps, where the plain bound delivered 1.4%; 31 of the engine's 64, whose
 *  first 48 keep the plain bound). */
#define CSRBF_GUARD_GROUP_GAP 0.25

/** The injectivity bound L of the current map (see above); L < 1 implies T injective with
 *  det dT/dx > 0 everywhere. 0 before end points are set (T = identity).
 *  Errors: CSRBF_ERR_INVALID (NULL), CSRBF_ERR_STATE (no start points). Thread-safe on a
 *  const solver. Cost O(sum over centres of the centres within 2R). */
int csrbf_solver_injectivity(const csrbf_solver *solver, double *bound);

/** What the guard did (any pointer to one may be NULL where it is accepted). */
typedef struct csrbf_guard_stats {
    double bound_before;      /* L of the requested map (first sub-step, before limiting) */
    double bound_after;       /* largest L over the maps applied (<= margin) */
    size_t clusters;          /* clusters of overlapping supports (first sub-step) */
    size_t clusters_limited;  /* clusters scaled back (first sub-step) */
    double min_scale;         /* smallest cluster scale t of the first sub-step (1: none) */
    int substeps;             /* maps composed (1: the step was applied in one map) */
    double reached;           /* smallest fraction of its control vector that any start
                                 point travelled, 1 - |end - where it got| / |end - start|,
                                 at least 0 (1: every end point reached) */
    csrbf_eval_stats eval;    /* csrbf_guarded_step only: pairs summed over the sub-steps,
                                 moved / max_displacement against the input shape,
                                 min_jacobian_det the minimum over the sub-steps' maps */
} csrbf_guard_stats;

/** Anchored guard: after set_end_points, scale back the clusters whose bound exceeds margin.
 *  Each cluster C (connected component of overlapping supports) gets
 *  t_C = min(1, margin / L_C) and alpha_j *= t_C for its centres: exactly the coefficients
 *  that end points s_i + t_C (d_i - s_i) would give (alpha is linear in the displacements and
 *  A is block-diagonal over clusters), without a solve; clusters with t_C = 1 keep their
 *  coefficients bit for bit. The factor stays valid (the next set_end_points starts afresh).
 *  With CSRBF_POLY_LINEAR the polynomial couples all clusters: the whole map (alphas and p)
 *  is scaled by one t = min(1, margin / L) instead. margin: in (0, 1); 0 selects
 *  CSRBF_GUARD_MARGIN. stats (may be NULL) gets bound_before/after, clusters, clusters_limited,
 *  min_scale (substeps = 1, reached = min_scale, eval zeroed).
 *  Returns CSRBF_OK, CSRBF_WARN_LIMITED (some cluster was scaled), CSRBF_ERR_INVALID (NULL,
 *  bad margin), CSRBF_ERR_STATE (no start points). O(neighbour pairs), no allocation.
 *  Source: csrbf.md pitfall 4 (the Lipschitz bound above). */
int csrbf_solver_limit_end_points(csrbf_solver *solver, double margin, csrbf_guard_stats *stats);

/** Options of csrbf_guarded_step; a zero struct (or NULL) selects every default. */
typedef struct csrbf_guard {
    double margin;       /* accepted bound per map, in (0, 1); 0: CSRBF_GUARD_MARGIN */
    int max_substeps;    /* maps composed at most; 0: CSRBF_GUARD_MAX_SUBSTEPS; 1: limit only
                            (the anchored mode: the start points stay, the factor is reused) */
    unsigned eval_flags; /* flags for csrbf_evaluate (CSRBF_EVAL_JACOBIAN) */
    uint64_t max_pairs;  /* 0: none; else a map past the CSRBF_GUARD_MAX_SUBSTEPS-th is composed
                            only while the (vertex, centre) pairs the maps so far evaluated
                            are under it: the default's maps always, more where they are
                            cheap (a small support, a small mesh) */
} csrbf_guard;

/** One guarded step: deformed = T_k o ... o T_1 (shape), each T_j injective (bound <= margin),
 *  moving the n start points toward the end points as far as injective maps allow.
 *  shape: the csrbf_points of the current shape (its vertices are deformed, n_vertices =
 *  csrbf_points_count); start, end: n x 3 floats; deformed: n_vertices x 3 floats (must not
 *  overlap shape's memory). Sub-step j factors at the current start points p (p = start for
 *  j = 1), solves for the end points, limits per cluster (csrbf_solver_limit_end_points:
 *  t_C), evaluates on the shape so far, and moves p_i <- p_i + t_C (end_i - p_i) (start
 *  points merged into one centre move as the map moves them, by t_C times their mean
 *  end - p, and so stop short of their own ends: CSRBF_WARN_LIMITED); it stops
 *  when every t_C = 1 (T(start_i) = end_i, the composition of injective maps is injective)
 *  or after max_substeps maps, or past the CSRBF_GUARD_MAX_SUBSTEPS-th once the maps so far
 *  evaluated max_pairs pairs (the rest of the motion is dropped; CSRBF_WARN_LIMITED). The
 *  last quarter (at least 12; none when max_substeps is 1) of the maps it may compose (max_substeps, or where the budget
 *  will stop it at the pairs the maps so far averaged) are limited with the group terms
 *  (CSRBF_GUARD_GROUP_GAP), the earlier ones with the plain bound.
 *  When start equals the solver's current start points bit for bit, the factor is reused.
 *  Cost: a step that is injective already costs one update plus the bound (O(m^2) for m
 *  fingertips: a few per cent of the evaluation); otherwise each sub-step costs a
 *  factorisation, a solve, an evaluation and an O(n_vertices) re-index of the intermediate
 *  shape (a scratch csrbf_points owned by the solver, allocated on first need).
 *  Returns CSRBF_OK (one map, nothing limited), CSRBF_WARN_SUBSTEPS (composed, every end
 *  point reached), CSRBF_WARN_LIMITED (stopped short), or the first error of the calls it
 *  makes (CSRBF_ERR_INVALID for NULL arguments, n == 0 or a bad margin / max_substeps,
 *  CSRBF_ERR_NOMEM,
 *  CSRBF_ERR_NUMERIC); after an error deformed is unspecified. On return the solver holds the
 *  last sub-step's start points and (limited) coefficients. stats may be NULL.
 *  Not thread-safe (modifies the solver). Source: csrbf.md pitfall 4 (compose or scale). */
int csrbf_guarded_step(csrbf_solver *solver, const csrbf_points *shape, size_t n,
                       const float *start, const float *end, const csrbf_guard *guard,
                       float *deformed, csrbf_guard_stats *stats);

/** csrbf_guarded_step with a persistent output whose work follows the supports, as
 *  csrbf_evaluate_touched does for one map (the contract above: touch made for shape, the
 *  same output buffer deformed on every call with it, nobody else writing it). The first map
 *  is csrbf_evaluate_touched on shape; each further map T_j is evaluated, through
 *  inter_touch, on inter holding the shape so far, and rewrites only the blocks inside its
 *  supports (T_j is the identity outside them, so the other blocks already hold T_j of the
 *  shape so far). inter: a csrbf_points of shape's vertex count holding shape's vertices bit
 *  for bit on entry (the caller keeps it so: csrbf_points_update(_ranges) on both); the call
 *  rewrites its blocks in the supports and restores them before it returns, also on error.
 *  inter_touch: a touch made for inter, used by this call only. deformed on return: bit for
 *  bit csrbf_guarded_step's; touch then lists the blocks any map computed (where deformed
 *  may differ from shape: the next call, or csrbf_evaluate_touched, restores those outside
 *  its supports), and csrbf_touch_ranges gives them with the blocks the first map restored.
 *  Cost: csrbf_guarded_step's solves; its evaluations and re-indexing follow the supports,
 *  O(blocks in the maps' supports) instead of O(n_vertices) per map. Returns as
 *  csrbf_guarded_step, and CSRBF_ERR_INVALID when a touch was made for other points or
 *  inter is shape or of another count; on error the touch is reset (the next call writes
 *  every block) and inter restored. Not thread-safe (the solver, the touches, inter).
 *  Source: csrbf.md pitfall 4 (compose or scale), as csrbf_guarded_step. */
int csrbf_guarded_step_touched(csrbf_solver *solver, const csrbf_points *shape, csrbf_touch *touch,
                               csrbf_points *inter, csrbf_touch *inter_touch, size_t n,
                               const float *start, const float *end, const csrbf_guard *guard,
                               float *deformed, csrbf_guard_stats *stats);

#ifdef __cplusplus
}
#endif
#endif
