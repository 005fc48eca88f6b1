/*
 * fp_similarity.h: the similarity (scale, rotation, translation) that carries one point set
 * onto another best, in the least-squares sense: calibrate's touch fit (core/pose) and a
 * rig placed on a moved copy of its mesh (core/rig) share it. Pure, reentrant, [any-thread];
 * no allocation. Core only (not in the installed headers).
 */
#ifndef FP_SIMILARITY_H
#define FP_SIMILARITY_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The similarity b_i ~ s R a_i + t over n >= 3 point pairs (a, b: n x 3, any one unit),
 *  least squares: R from Horn's unit quaternion (the top eigenvector of his symmetric 4 x 4
 *  matrix; B. K. P. Horn, "Closed-form solution of absolute orientation using unit
 *  quaternions", J. Opt. Soc. Am. A 4(4):629-642, 1987), s Umeyama's (sum b'.R a' / sum
 *  |a'|^2, primes about the centroids; S. Umeyama, IEEE TPAMI 13(4):376-380, 1991), t from the
 *  centroids. Out: *s > 0, q (unit quaternion w x y z, w >= 0), t (b's unit). Returns 0, or
 *  -EDOM where either set spans no plane (fewer than 3, collinear or coincident points) or
 *  the scale comes out non-positive or not finite (outputs then undefined). */
int fp_similarity_fit(const double (*a)[3], const double (*b)[3], size_t n, double *s, double q[4],
                      double t[3]);

#ifdef __cplusplus
}
#endif
#endif
