/*
 * fp_select.h: the median split shared by the project's spatial trees (the contact guard's
 * hierarchy and k-d tree, core/contact; the rig's nearest-rigid-vertex tree, core/rig).
 */
#ifndef FP_SELECT_H
#define FP_SELECT_H

#include <stddef.h>
#include <stdint.h>

/** Reorder order[lo .. hi) (indices into key) so that order[mid] holds the item whose key on
 *  axis a (0-2) is the mid-th smallest, those before it no larger and those after it no
 *  smaller: key[3 item + a], three floats an item (a position, a centroid), not NaN.
 *  lo <= mid < hi. Hoare partitions, median-of-three pivots: O(hi - lo) expected. The order
 *  among equal keys is this function's, deterministic for a given input. Only order is
 *  written; reentrant, [any-thread] on arrays no other thread writes. */
void fp_select_mid(uint32_t *order, size_t lo, size_t hi, size_t mid, int a, const float *key);

#endif
