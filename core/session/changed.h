/*
 * changed.h: what changed in a shape since its consumer last asked (fp_session_touched,
 * fp_session_base_touched): vertex ranges, or "anything". The session adds each frame's
 * ranges (the engine's, fp_engine_step_touched, and the contact guard's D_P where its shape
 * is shown) or marks everything (undo, reset, a rig pose); the viewer takes the union at its
 * upload and re-normals and uploads only those ranges (--stream copies only those). Nothing
 * is recorded before the first take, so a session nobody asks pays nothing.
 *
 * Ranges are (first, count) pairs of uint32, increasing, disjoint and not adjacent.
 * Errors: none; an allocation that fails turns the record into "anything" (the consumer
 * then does the whole shape, which is always correct). Threads: one (the session thread).
 */
#ifndef FP_SESSION_CHANGED_H
#define FP_SESSION_CHANGED_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct fp_changed {
    bool tracking;        /* taken once: changes are recorded from then on */
    bool all;             /* anything may have changed since the last take */
    uint32_t *r;          /* the union so far: n pairs */
    size_t n, cap;        /* pairs, capacity in pairs */
    uint32_t *tmp;        /* the merge's output, swapped with r */
    size_t tmp_cap;
    uint32_t *out;        /* what the last take handed out (valid until the next take) */
    size_t out_cap;
} fp_changed;

/** Free the buffers; *c is zeroed (not tracking). */
void fp_changed_free(fp_changed *c);

/** Anything may have changed. */
void fp_changed_all(fp_changed *c);

/** Ranges changed: count pairs (first, count), increasing and disjoint (adjacent allowed);
 *  count SIZE_MAX: anything (as fp_changed_all). O(recorded + count). */
void fp_changed_add(fp_changed *c, const uint32_t *ranges, size_t count);

/** The union of everything added since the last take: its number of pairs (0: nothing),
 *  or SIZE_MAX with *ranges NULL for "anything" (always at the first take, which starts the
 *  record). Clears the record. *ranges is owned by c, valid until the next take. */
size_t fp_changed_take(fp_changed *c, const uint32_t **ranges);

#endif
