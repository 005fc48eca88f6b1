/*
 * history.h: step 6 of the frame (docs/architecture.md): the base and its history. A commit
 * folds the deformed shape into the base (one undo level per gesture: the first commit of a
 * gesture opens a level, and every commit of the gesture saves there the base before the
 * gesture for the pieces it changes, once each); undo goes back one level along a ring of
 * FP_HISTORY_LEVELS (the oldest is overwritten); reset goes back to the loaded shape (itself
 * undoable); set_base replaces the base.
 * Whoever calls these re-indexes the base for the engine (fp_engine_step_set_base, or
 * fp_engine_step_commit for the ranges a ranged commit wrote).
 *
 * Cost: a commit costs what it changes, not the mesh: fp_history_commit_ranges reads and
 * writes only the listed vertex ranges (the engine's touched ranges), and a level holds only
 * the pieces (FP_HISTORY_PIECE consecutive vertices) its gesture changed, with their values
 * before it. fp_history_commit (the whole mesh) compares every piece and stores the changed
 * ones. Undo rewrites only the pieces of its level; reset only the pieces that differ from
 * the loaded shape.
 *
 * Memory: a level's pieces grow with its gesture (12 bytes x FP_HISTORY_PIECE + 4 per piece),
 * kept for reuse when the ring comes round; one byte per piece marks the open level's. A
 * failed allocation drops every level (the commit still happens; nothing can be undone from
 * there, and nothing is undone wrongly).
 * Threads: the session thread.
 */
#ifndef FP_HISTORY_H
#define FP_HISTORY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Undo levels kept (= FP_SESSION_UNDO_LEVELS). */
#define FP_HISTORY_LEVELS 32
/** Vertices per saved piece (the engine's block: touched ranges start on piece boundaries). */
#define FP_HISTORY_PIECE 16

/** One undo level: the base before a gesture, on the pieces the gesture changed. */
typedef struct fp_history_level {
    uint32_t *pieces;                  /* piece indices, each once */
    float *values;                     /* FP_HISTORY_PIECE x 3 floats per piece (the last
                                        * piece's tail beyond n unused) */
    size_t count, capacity;            /* pieces held, pieces allocated */
    unsigned long gestures;            /* fp_history.gestures before the gesture */
} fp_history_level;

typedef struct fp_history {
    size_t n;                          /* vertices */
    size_t npieces;                    /* ceil(n / FP_HISTORY_PIECE) */
    float *base;                       /* the base: n x 3 floats, owned by the caller */
    fp_history_level level[FP_HISTORY_LEVELS]; /* undo ring */
    size_t count;                      /* levels that can be undone */
    size_t next;                       /* the slot the next level goes to */
    bool gesture_open;                 /* a commit of the current gesture was taken: its
                                        * level is the one before `next` */
    uint8_t *saved;                    /* npieces: 1 where the open level holds the piece */
    unsigned long gestures;            /* committed gestures in the base since the loaded
                                        * shape (undo restores it, reset zeroes it) */
} fp_history;

/** Start an empty history over the caller's base array (n x 3 floats, mesh units).
 *  Returns 0 or -ENOMEM (then the history keeps no levels but commits still work). */
int fp_history_init(fp_history *h, size_t n, float *base);
/** Free the levels. */
void fp_history_free(fp_history *h);

/** Commit: deformed (n x 3 floats) becomes the base; the gesture's level saves the base's
 *  pieces that change (O(n) compare). */
void fp_history_commit(fp_history *h, const float *deformed);

/** Commit only the vertex ranges (pairs first vertex, count; increasing or not, disjoint,
 *  within n): base[ranges] = deformed[ranges], the rest of deformed unread, the rest of the
 *  base unchanged. The caller guarantees deformed equals the base outside the ranges (the
 *  engine's touched ranges). O(vertices in the ranges). */
void fp_history_commit_ranges(fp_history *h, const float *deformed, const uint32_t *ranges,
                              size_t nranges);

/** The frame had no deformation: the gesture ended (the next commit opens a new level). */
void fp_history_end_gesture(fp_history *h);

/** Copy src (n x 3 floats) into the base and end the gesture (no undo level). */
void fp_history_set_base(fp_history *h, const float *src);

/** Go back one level: the base becomes what it was before the latest gesture (bit for bit).
 *  False when none is left. */
bool fp_history_undo(fp_history *h);

/** Back to the loaded shape: the pieces that differ from loaded form an undo level (none
 *  when the base equals it), then the base is set to loaded. */
void fp_history_reset(fp_history *h, const float *loaded);

#ifdef __cplusplus
}
#endif
#endif
