/*
 * sheet_bind.h: close sheets carried together (issue 51). Where the loaded face holds two
 * sheets of skin a fraction of a triangle apart that are far apart on the mesh (an eyelid on
 * its eyeball, closed lips, a scan's folds), the engine's map moves both smoothly, but each
 * sheet is a piecewise-linear surface between its own vertices: under a long drag their
 * interpolation errors (about h^2 / 6 times the map's second derivative, h a triangle's
 * edge) differ by more than the gap, and the sheets cross, which the contact guard then
 * stops by holding the whole gesture back. Binding carries each close vertex of one sheet
 * (the follower) with the other sheet's triangle beneath it (the leader), at its offset from
 * that triangle in the reference: the follower's normal offset turns with the leader
 * triangle's normal, its tangential offset is kept. So the gap is kept where it matters,
 * and the guard stays the last word on crossings.
 *
 * Built once on the loaded shape: each vertex within FP_SHEET_BIND_GAP of its mean edge
 * length of a triangle with no vertex within FP_SHEET_BIND_RINGS rings of it (vertices
 * welded by position), or within FP_SHEET_BIND_TUCK of one that has but is not its own (a
 * tuck: a file's vertex lying on a triangle of its own sheet, across a sliver folded flat,
 * which any bend puts through it), is a candidate; candidates are taken nearest first, a vertex never
 * both a follower and a leader's corner, so a bound vertex follows vertices the engine
 * placed. Applied each deforming frame to the engine's output against the reference (the
 * posed base): a follower moves only where the engine moved it (outside every support the
 * shape stays the base, bit for bit) and its offset in the reference is still under the gap
 * (a jaw the rig opened parts the lips: they are then left to the map), fully up to half the
 * gap and less up to the gap.
 *
 * Threads: build on the session's opening thread; apply on the frame thread. Errors:
 * -ENOMEM (nothing bound). Memory: about 40 bytes a bound vertex.
 */
#ifndef FP_SHEET_BIND_H
#define FP_SHEET_BIND_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* a vertex this close to another sheet, as a fraction of its mean edge length, is bound */
#define FP_SHEET_BIND_GAP 0.1
/* triangles with a vertex within this many rings of a vertex are its own sheet */
#define FP_SHEET_BIND_RINGS 2
/* ... unless the vertex lies this close to one of them (a fraction of its mean edge): a tuck
 * of the file, a vertex on a triangle of its own sheet that it is not a corner of */
#define FP_SHEET_BIND_TUCK 0.01

typedef struct fp_sheet_bind {
    size_t count;           /* bound vertices */
    uint32_t *follower;     /* count: the bound vertex */
    uint32_t (*leader)[3];  /* count: the leader triangle's vertices */
    float (*bary)[3];       /* count: barycentric coordinates of the nearest point on it */
    float *gap;             /* count: the binding's full distance (mesh units) */
} fp_sheet_bind;

/** Finds the close sheets of a mesh: pos n x 3 (mesh units), tris t x 3. Returns 0 (b
 *  filled, b->count may be 0) or -ENOMEM (b zeroed). O(n log n + near pairs). */
int fp_sheet_bind_build(const float *pos, size_t n, const uint32_t *tris, size_t t,
                        fp_sheet_bind *b);

/** Carries each follower with its leader triangle: ref the reference (n x 3), x the
 *  engine's output (n x 3, changed in place at followers). Only followers in [lo, hi)
 *  ranges (ranges: count pairs of first vertex and count; NULL: all) are touched. Returns
 *  the number of followers moved. */
size_t fp_sheet_bind_apply(const fp_sheet_bind *b, const float *ref, float *x,
                           const uint32_t *ranges, size_t nranges);

void fp_sheet_bind_free(fp_sheet_bind *b);

#ifdef __cplusplus
}
#endif
#endif
