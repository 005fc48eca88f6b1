/* fp_selfx: count the self-intersections of a triangle mesh, exactly, for tests and the
 * fp-selfx tool (the trust issue's "no new self-crossings" check).
 *
 * Two triangles cross when they share a point and no vertex (after welding vertices at
 * identical positions, so that OBJ seams with duplicated vertices are adjacency, not
 * crossings); triangles that share a vertex or an edge are adjacent and never counted,
 * degenerate (zero-area) triangles are skipped. The test is CGAL's exact
 * do_intersect(Triangle_3, Triangle_3) with the Exact_predicates_inexact_constructions_kernel
 * (float inputs are exact in double), over candidate pairs from CGAL's box_intersection_d
 * (a sweep over the triangles' bounding boxes). Cost O((t + k) log t) for t triangles and k
 * box overlaps: well under a second for a 50k-triangle face.
 *
 * Errors: a negative errno (-EINVAL for NULL arrays or a triangle index >= n_vertices,
 * -ENOMEM). Thread rules: reentrant. Test support only (C++ inside, C API outside). */
#ifndef FP_SELFX_H
#define FP_SELFX_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Crossing triangle pairs of the mesh (pos: n_vertices x 3 floats, tris: n_tris x 3
 *  indices). Returns the count (>= 0) or a negative errno. */
long fp_selfx_count(const float *pos, size_t n_vertices, const uint32_t *tris, size_t n_tris);

/** Pairs that cross in `after` but not in `before` (same vertex count and triangles; the
 *  input's own crossings are not counted). Vertices are welded by their `before` positions.
 *  When pairs is not NULL, up to max_pairs new pairs (triangle indices a < b) are written to
 *  pairs[2k], pairs[2k+1] in increasing order. Returns the number of new pairs (all of them,
 *  not only those written) or a negative errno; *own_before (may be NULL) gets the crossings
 *  `before` already had. */
long fp_selfx_count_new(const float *before, const float *after, size_t n_vertices,
                        const uint32_t *tris, size_t n_tris, uint32_t *pairs, size_t max_pairs,
                        long *own_before);

/** fp_selfx_count_new restricted to pairs away from the input's own crossings (the trust
 *  issue's measure): a new pair is left out (and counted in *near_own, may be NULL) when
 *  either triangle has a vertex within `rings` vertex rings (through welded vertices) of a
 *  triangle that crosses in `before`. Surfaces that already interpenetrate in the input (the
 *  ICT face's eyes and mouth interior: 6,935 crossings) move their intersection curve under
 *  any deformation, however injective; those pairs are not fold-overs. rings = 0 leaves out
 *  only pairs with a triangle that itself crosses in before. Returns the pairs away from
 *  them (written to pairs as fp_selfx_count_new) or a negative errno. */
long fp_selfx_count_new_away(const float *before, const float *after, size_t n_vertices,
                             const uint32_t *tris, size_t n_tris, int rings, uint32_t *pairs,
                             size_t max_pairs, long *own_before, long *near_own);

#ifdef __cplusplus
}
#endif
#endif
