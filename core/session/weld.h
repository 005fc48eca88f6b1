/*
 * weld.h: a mesh's vertices welded by position, for the steps that reason across sheets
 * (sheet_bind.h, crack.h): vertices at bitwise identical positions are one (an OBJ's seams,
 * a shell stitched to the skin), as the contact guard welds them (fp_contact.h).
 *
 * Threads: any (no state). Errors: -ENOMEM. Memory: 16 bytes a vertex while it sorts.
 */
#ifndef FP_WELD_H
#define FP_WELD_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** A vertex and its position, as fp_weld_by_position sorts them. */
typedef struct fp_at_pos {
    float p[3];
    uint32_t v;
} fp_at_pos;

/** weld (n, the caller's): weld[v] is the least index at v's position (pos: n x 3, finite).
 *  order not NULL: *order := the n vertices sorted by x, then y, then z, then index (the
 *  caller frees it). Returns 0 or -ENOMEM (*order NULL). O(n log n). */
int fp_weld_by_position(const float *pos, size_t n, uint32_t *weld, fp_at_pos **order);

#ifdef __cplusplus
}
#endif
#endif
