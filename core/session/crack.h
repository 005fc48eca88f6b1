/*
 * crack.h: cracked seams kept closed (issue 51). Where the loaded face stitches two sheets at
 * vertices its file wrote twice, apart by their rounding (the ICT face's eye blend shell on
 * its eyelid margin: welded at 321 vertices, 0.05-1 um apart at 44 more: cracks), the two
 * sheets' triangles meet at a crack with a corner a fraction of a float's last bit off the
 * other's plane (1.6e-7 cm on the ICT face). The rounding of any motion may put that corner
 * just through the other triangle: a crossing 0.1 um across, which the contact guard counts
 * (it is exact to the positions), and it then held the skin back around the crack (ICT
 * three-claps: 11 of the 17 frames it scaled back; the faces subdivided from it, most of
 * theirs; docs/performance.md).
 *
 * Each frame, after the rig's blend and before the contact guard, every pair of triangles
 * meeting at a crack (one from each side, sharing no vertex position) that moved is tested as
 * the guard tests a pair (fp_contact_tri_tri). A pair that crosses in the candidate and not in
 * the reference has a crack corner moved back across the other triangle's plane, to the side
 * it is on in the reference: along that triangle's unit normal by 1, 2, 4 ... float steps of
 * the corner's largest coordinate (FP_CRACK_STEPS tries: at most 128 steps, 1.2 um on the ICT
 * face, whose coordinates are under 16 cm), every vertex at the corner's position alike so that the weld stays
 * whole; first the second triangle's corners at a crack, then the first's; where none parts it,
 * the corner is left as it was and the guard holds the pair back, as without this step. So the
 * guard stays the last word; this step only undoes the rounding. Only a corner the frame moved
 * from the reference is moved back: a crack at the edge of a support, one side moved and the
 * other not, had its still side's corner moved, outside the engine's ranges, where the
 * contact guard, the commit and the stream never look (the guard then kept a shape other than
 * the one shown; tests/e2e/test_session saw a vertex outside every support a float step off
 * the base, under ASan).
 *
 * Built once on the loaded shape: a crack is two vertices at different positions within
 * FP_CRACK_TOL of the bounding box's diagonal of each other. Threads: build on the opening
 * thread; apply on the frame thread. Errors: -ENOMEM (nothing built). Memory: 32 bytes a pair
 * and 4 a vertex at a crack (the ICT face: 26 cracks, 848 pairs, 94 vertices).
 */
#ifndef FP_CRACK_H
#define FP_CRACK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* vertices at different positions this close, as a fraction of the bounding box's diagonal,
 * are a crack (the ICT face's: 2e-9 to 2e-8 of its 47.5 cm) */
#define FP_CRACK_TOL 1e-6
/* tries of a corner's move: 1, 2, 4 ... float steps */
#define FP_CRACK_STEPS 8

#define FP_CRACK_NONE UINT32_MAX

typedef struct fp_crack {
    size_t ncracks;
    uint32_t (*side)[2];    /* ncracks: the group on each side of the crack */
    uint32_t *first;        /* ncracks + 1: crack c's pairs are [first[c], first[c + 1]) */
    size_t npairs;
    uint32_t (*pair)[2];    /* npairs: two triangles meeting at a crack, one from each side,
                               sharing no position */
    uint32_t (*corner)[6];  /* npairs: the group of each of their vertices (the first's three,
                               the second's) that is at a crack, else FP_CRACK_NONE */
    uint32_t *group_start;  /* the vertices at one crack corner's position (a group): group gi */
    uint32_t *group;        /* is group[group_start[gi] .. group_start[gi + 1]) */
    size_t ngroups;
} fp_crack;

/** Finds the cracks of a mesh: pos n x 3 (mesh units), tris t x 3 (indices < n; not kept).
 *  Returns 0 (k filled, k->npairs may be 0) or -ENOMEM (k zeroed). O(n log n + t). Threads:
 *  any, k the caller's alone. */
int fp_crack_build(const float *pos, size_t n, const uint32_t *tris, size_t t, fp_crack *k);

/** Closes the cracks the rounding opened: tris the triangles k was built with, ref the
 *  reference (n x 3, mesh units: the contact guard's, the posed base), x the candidate (n x 3,
 *  changed in place only at crack corners x moved from ref: the vertices at a position whose
 *  first one moved, all of them in the supports that moved it, so in the engine's ranges).
 *  Only the pairs of a crack where x moved a side's vertex from ref are tested (a crack
 *  outside every support costs one comparison a side).
 *  Returns the number of pairs parted; no errors, no allocation. Threads: the frame thread;
 *  k read only. */
size_t fp_crack_apply(const fp_crack *k, const uint32_t *tris, const float *ref, float *x);

/** Frees what fp_crack_build made and zeroes k (k zeroed or built; safe twice). No errors.
 *  Threads: not while fp_crack_apply runs on k. */
void fp_crack_free(fp_crack *k);

#ifdef __cplusplus
}
#endif
#endif
