/*
 * twist_path.h: the path a composed step takes where fingertips turn together (step 5,
 * step_engine.c; csrbf_guard.via).
 *
 * The composed step moves each start point along the straight line to its end point, in
 * injective maps (csrbf_guarded_step). Fingertips that turn together, a pinch twisted or a
 * hand rolled, meet on straight lines: the line between two of them turns with the hand, and
 * the straight paths bring them towards one point on the way, where no injective map goes, so
 * the guard stops the step short there. (Lee Perry-Smith's three-claps with thumb and index
 * pinched, tools/hands-variants: two tips 7.6 mm apart at the grab and 13.9-18.5 mm at the
 * frame came within 0.9-1.4 mm of each other on the straight paths; 28-38% of the motion
 * was reached in 64 maps.)
 *
 * The path instead, per cluster of fingertips whose supports overlap (start points within 2R,
 * the engine's clusters): the turn that carries the cluster's start points onto its end
 * points best (fp_rotation_fit: angle theta about an axis), the centroid moving straight and
 * what the turn leaves (r_i) added in proportion:
 *
 *     arc_i(u) = c_s + u (c_e - c_s) + R(u theta) (s_i - c_s) + u r_i,
 *     r_i = e_i - c_e - R(theta) (s_i - c_s),   u in [0, 1]
 *
 * so fingertips that keep their places on the hand keep their distances on the way. It is
 * blended with the straight line, p_i(u) = (1 - w) line_i(u) + w arc_i(u), by how near the
 * straight paths bring the cluster's closest pair: rho = min over its pairs of (their least
 * distance along the lines) / (the smaller of their distances at start and end); w = 1 where
 * rho <= FP_TWIST_RHO_ARC, 0 where rho >= FP_TWIST_RHO_LINE, smoothstep between. So a drag, a
 * stretch and fingertips closing onto one point (rho 1) keep the straight line, bit for bit,
 * and the path is a continuous function of the control set (deterministic: the same frame,
 * the same path, so a take plays back bit for bit). Waypoints: the path at u = k / (K + 1),
 * k = 1 .. K, K = ceil(theta / 45 degrees) - 1 for the largest theta of a bent cluster, at
 * least 1: each leg turns by 45 degrees or less, so a pair on a leg's line keeps at least
 * cos 22.5 = 92% of its distance.
 *
 * With a rig: the rig's finger limit bounds the push toward bone over the straight line's
 * capsule (fp_rig.h); a bent path leaves it by at most its turn's chord, and a fold it then
 * makes in the rig's ramp is a flipped triangle the contact guard holds back, as for fields
 * that add up.
 *
 * Threads: pure, [any-thread]; no allocation. Link: fp_session (fp_common's rotation fit).
 */
#ifndef FP_TWIST_PATH_H
#define FP_TWIST_PATH_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The closeness ratio at or below which a cluster takes the turn's path, and at or above
 *  which it keeps the straight line (rho above). */
#define FP_TWIST_RHO_ARC 0.4
#define FP_TWIST_RHO_LINE 0.7
/** At most this many waypoints (legs of 45 degrees over a half turn). */
#define FP_TWIST_MAX_VIA 3

/** Waypoints for n control vectors (start, end: n x 3 floats, mesh units; radius: the
 *  support radius R > 0): writes K x n x 3 floats to via (capacity FP_TWIST_MAX_VIA x n x 3),
 *  the layout of csrbf_guard.via, and returns K; 0 (via untouched) where every cluster keeps
 *  the straight line. Points in clusters that keep it get waypoints on their lines. n may be
 *  0 (returns 0). */
size_t fp_twist_path(size_t n, const float (*start)[3], const float (*end)[3], double radius, float *via);

#ifdef __cplusplus
}
#endif
#endif
