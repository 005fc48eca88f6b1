/*
 * history.h: step 6 of the frame (docs/architecture.md): the base and its history. A commit
 * folds the deformed shape into the base (one undo snapshot per gesture: the first commit of
 * a gesture saves the base before it, later commits of the same gesture do not); undo goes
 * back one commit along a ring of FP_HISTORY_LEVELS snapshots (the oldest is overwritten);
 * reset goes back to the loaded shape (itself undoable); set_base replaces the base.
 * Whoever calls these re-indexes the base for the engine (fp_engine_step_set_base) when
 * they return true.
 *
 * Memory: a snapshot is n x 3 floats, allocated the first time its slot is used (up to
 * FP_HISTORY_LEVELS of them). A failed allocation skips the snapshot (the commit still
 * happens; that level cannot be undone).
 * Threads: the session thread.
 */
#ifndef FP_HISTORY_H
#define FP_HISTORY_H

#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Undo levels kept (= FP_SESSION_UNDO_LEVELS). */
#define FP_HISTORY_LEVELS 32

typedef struct fp_history {
    size_t n;                          /* vertices */
    float *base;                       /* the base: n x 3 floats, owned by the caller */
    float *snap[FP_HISTORY_LEVELS];    /* undo ring */
    size_t count;                      /* snapshots that can be undone */
    size_t next;                       /* the slot the next snapshot goes to */
    bool gesture_open;                 /* a commit of the current gesture was taken */
    unsigned long gestures;            /* committed gestures in the base since the loaded
                                        * shape (undo restores it, reset zeroes it) */
    unsigned long snap_gestures[FP_HISTORY_LEVELS]; /* gestures of each snapshot */
} fp_history;

/** Start an empty history over the caller's base array (n x 3 floats, mesh units). */
void fp_history_init(fp_history *h, size_t n, float *base);
/** Free the snapshots. */
void fp_history_free(fp_history *h);

/** Save the base as one undo level. */
void fp_history_push(fp_history *h);

/** Commit: deformed (n x 3 floats) becomes the base; the first commit of a gesture pushes
 *  the base before it. */
void fp_history_commit(fp_history *h, const float *deformed);

/** The frame had no deformation: the gesture ended (the next commit opens a new level). */
void fp_history_end_gesture(fp_history *h);

/** Copy src (n x 3 floats) into the base and end the gesture (no undo level). */
void fp_history_set_base(fp_history *h, const float *src);

/** Go back one level: the base becomes the latest snapshot. False when none is left. */
bool fp_history_undo(fp_history *h);

/** Back to the loaded shape: pushes the base when it differs from loaded, then sets it. */
void fp_history_reset(fp_history *h, const float *loaded);

#ifdef __cplusplus
}
#endif
#endif
