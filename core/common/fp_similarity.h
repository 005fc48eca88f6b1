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

/** The tie-break of fp_rotation_fit, as a share of sum |a'_i| |b'_i|. */
#define FP_ROTATION_FIT_BIAS 1e-3

/** The rotation alone b_i - mb ~ R (a_i - ma) over n >= 1 point pairs (primes about the
 *  centroids), by Horn's unit quaternion as fp_similarity_fit, for any set: where rotations
 *  fit equally (two points, or collinear ones: the turn about their line is free; one point,
 *  or coincident ones: any) the one nearest the identity, by a tie-break that adds
 *  FP_ROTATION_FIT_BIAS sum |a'_i| |b'_i| to the cross-covariance's diagonal (it moves a
 *  spanning set's fit by about that share of its angle). Out: q (unit quaternion w x y z,
 *  w >= 0: the turn is at most 180 degrees); the identity for coincident points. Pure,
 *  [any-thread], no allocation, no error. */
void fp_rotation_fit(const double (*a)[3], const double (*b)[3], size_t n, double q[4]);

#ifdef __cplusplus
}
#endif
#endif
