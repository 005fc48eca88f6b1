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

#include <stddef.h>

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

/** Result codes. */
enum {
    CSRBF_OK = 0,
    CSRBF_WARN_MERGED = 1,      /* coincident / near-coincident start points were merged */
    CSRBF_WARN_POLY_RANK = 2,   /* the linear polynomial was reduced: centres collinear,
                                   coplanar or fewer than 4 (csrbf.md pitfall 2) */
    CSRBF_WARN_FOLDOVER = 3,    /* some |alpha_i| exceeds the fold-over bound R / max|psi'|:
                                   the map may not be injective (csrbf.md pitfall 4) */
    CSRBF_ERR_INVALID = -1,     /* a bad argument; see csrbf_solver_message() */
    CSRBF_ERR_NOMEM = -2,       /* out of memory */
    CSRBF_ERR_NUMERIC = -3,     /* factorisation failed or a result was not finite */
    CSRBF_ERR_STATE = -4        /* called out of order (end points before start points) */
};

/** A static English text for a result code ("unknown result" for others). Thread-safe. */
const char *csrbf_strerror(int result);

/** Solver options. A zero-initialised struct is valid once radius is set.
 *  - kernel: CSRBF_PSI31 by default.
 *  - poly: CSRBF_POLY_NONE by default.
 *  - radius: support radius R in mesh units; required; finite, 1e-15 <= R <= 1e15.
 *  - merge_tolerance: start points closer than merge_tolerance * R are merged into one centre
 *    (csrbf.md pitfall 1). 0 selects the default CSRBF_DEFAULT_MERGE_TOLERANCE (1e-4: the
 *    2x2 block of two centres that far apart still has a condition number near 1e7 for every
 *    kernel, harmless in double). Must be finite and in [0, 0.5).
 *  - dense_limit: factor A with a dense Cholesky when the number of (merged) centres is at most
 *    this, else with CHOLMOD (supernodal or simplicial as CHOLMOD chooses, AMD, METIS where
 *    fill is high). 0 selects CSRBF_DEFAULT_DENSE_LIMIT (200); a negative value always uses
 *    CHOLMOD.
 *  - threads: OpenMP threads for csrbf_evaluate; 0 = the OpenMP default (omp_get_max_threads).
 *    Small work runs on one thread regardless. */
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
 *  psi31, 0.5 for psi30, 0.40 for psi32). A single centre with |alpha| below bound * R keeps
 *  T injective (det of the Jacobian > 0). Returns 0 for an unknown kernel. */
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

/** Bit mask (1u << code) of the warnings raised by the last set_start/set_end/solve call. */
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
 *  centres, column-scaled by D and restricted by V to the eigenvectors of D P^T P D whose
 *  singular values exceed 1e-6 of the largest: the directions that the centres cannot
 *  determine (collinear, coplanar, n < 4) are dropped from p, with CSRBF_WARN_POLY_RANK.
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
 *  them into blocks of 16 consecutive vertices (structure of arrays) with bounding boxes.
 *  Locality comes from the vertex order (grids, scanned and modelled meshes keep neighbours
 *  close in index); a scrambled order stays correct but skips fewer blocks.
 *  1 <= n < 2^32. Errors: CSRBF_ERR_INVALID (*out = NULL), CSRBF_ERR_NOMEM. */
int csrbf_points_create(size_t n, const float *xyz, csrbf_points **out);

/** Replace the positions (same n, same vertex order), e.g. after a commit in unanchored mode;
 *  block boxes are recomputed (O(n)). Errors: CSRBF_ERR_INVALID (points unchanged). */
int csrbf_points_update(csrbf_points *points, const float *xyz);

/** Number of vertices. */
size_t csrbf_points_count(const csrbf_points *points);

/** Free a vertex set; sets *points to NULL. NULL and *NULL are no-ops. */
void csrbf_points_destroy(csrbf_points **points);

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
    double min_jacobian_det;   /* min det dT/dx over the moved vertices (1 if none moved);
                                  <= 0 means fold-over. Only with CSRBF_EVAL_JACOBIAN, else 1 */
} csrbf_eval_stats;

/** deformed[v] = T(base[v]) for every vertex v (n x 3 floats, original vertex order; must not
 *  overlap the solver's or the points' memory). Only (vertex, centre) pairs whose block boxes
 *  meet the support are visited; the arithmetic is float (positions, coefficients), the
 *  coefficients having been solved in double. Without a polynomial a vertex outside every
 *  support gets exactly its base position, bit for bit. Vectorised (AVX-512 intrinsics with
 *  r from rsqrt14 + one Newton step where the CPU has it, else target_clones of portable C
 *  for x86-64-v3 / baseline, chosen at run time) and parallel over blocks with OpenMP
 *  (options.threads; one thread below about 50k vertex-centre tests).
 *  stats may be NULL (fastest); with stats the pair count, moved count and maximum
 *  displacement are filled in, and with flags & CSRBF_EVAL_JACOBIAN the minimum Jacobian
 *  determinant too. Errors: CSRBF_ERR_INVALID (NULL, unknown flag), CSRBF_ERR_STATE (no start
 *  points). Thread-safe on a const solver and const points. Source: the map T above. */
int csrbf_evaluate(const csrbf_solver *solver, const csrbf_points *base, float *deformed,
                   unsigned flags, csrbf_eval_stats *stats);

#ifdef __cplusplus
}
#endif
#endif
