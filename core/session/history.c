/* Step 6 of the frame: commit into the base, the undo ring of changed pieces, reset. */
#include "history.h"

#include <assert.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#define P FP_HISTORY_PIECE

/* The ring's invariants (history.h), checked after every change in a debug build (O(levels
 * + pieces): nothing in a release build): the counts within the ring; each level's pieces
 * within its room and the mesh; the marks (saved) exactly the open level's pieces, each
 * once, while a gesture is open on a level, and none otherwise. */
static void check_ring(const fp_history *h)
{
#ifndef NDEBUG
    assert(h->count <= FP_HISTORY_LEVELS && h->next < FP_HISTORY_LEVELS);
    for (size_t i = 0; i < FP_HISTORY_LEVELS; i++) {
        const fp_history_level *l = &h->level[i];
        assert(l->count <= l->capacity && (!l->capacity || (l->pieces && l->values)));
    }
    if (!h->saved) return;
    const fp_history_level *open = &h->level[(h->next + FP_HISTORY_LEVELS - 1) % FP_HISTORY_LEVELS];
    size_t want = h->gesture_open && h->count ? open->count : 0, marked = 0;
    for (size_t k = 0; k < h->npieces; k++) marked += h->saved[k];
    for (size_t i = 0; i < want; i++)
        assert(open->pieces[i] < h->npieces && h->saved[open->pieces[i]] == 1);
    assert(marked == want); /* (so each piece is listed once) */
#else
    (void)h;
#endif
}

int fp_history_init(fp_history *h, size_t n, float *base)
{
    memset(h, 0, sizeof *h);
    h->n = n;
    h->npieces = (n + P - 1) / P;
    h->base = base;
    h->saved = calloc(h->npieces ? h->npieces : 1, 1);
    check_ring(h);
    return h->saved ? 0 : -ENOMEM;
}

void fp_history_free(fp_history *h)
{
    for (size_t i = 0; i < FP_HISTORY_LEVELS; i++) {
        free(h->level[i].pieces);
        free(h->level[i].values);
        memset(&h->level[i], 0, sizeof h->level[i]);
    }
    free(h->saved);
    h->saved = NULL;
    h->count = h->next = 0;
    h->gesture_open = false;
}

static fp_history_level *open_level(fp_history *h)
{
    return &h->level[(h->next + FP_HISTORY_LEVELS - 1) % FP_HISTORY_LEVELS];
}

/* The open gesture ends: its pieces' marks are cleared (O(its pieces)). */
static void close_gesture(fp_history *h)
{
    if (h->gesture_open && h->saved && h->count) {
        const fp_history_level *l = open_level(h);
        for (size_t i = 0; i < l->count; i++) h->saved[l->pieces[i]] = 0;
    }
    h->gesture_open = false;
}

/* A new level at `next` holding nothing yet; the gesture is open on it. */
static void open_gesture(fp_history *h)
{
    close_gesture(h);
    fp_history_level *l = &h->level[h->next];
    l->count = 0;
    l->gestures = h->gestures;
    h->next = (h->next + 1) % FP_HISTORY_LEVELS;
    if (h->count < FP_HISTORY_LEVELS) h->count++;
    h->gesture_open = true;
}

/* Out of memory: no level can be undone correctly any more; forget them all. */
static void drop_levels(fp_history *h)
{
    if (h->saved && h->count && h->gesture_open) {
        const fp_history_level *l = open_level(h);
        for (size_t i = 0; i < l->count; i++) h->saved[l->pieces[i]] = 0;
    }
    h->count = 0;
}

/* Save piece k of the base (before it changes) in the open level, once per gesture. */
static void save_piece(fp_history *h, size_t k)
{
    if (!h->count || !h->saved || h->saved[k]) return;
    fp_history_level *l = open_level(h);
    if (l->count == l->capacity) {
        size_t cap = l->capacity ? 2 * l->capacity : 64;
        uint32_t *pc = realloc(l->pieces, cap * sizeof *pc);
        if (pc) l->pieces = pc;
        float *v = pc ? realloc(l->values, cap * P * 3 * sizeof *v) : NULL;
        if (v) l->values = v;
        if (!pc || !v) {
            drop_levels(h);
            return;
        }
        l->capacity = cap;
    }
    size_t v0 = k * P, nv = v0 + P <= h->n ? P : h->n - v0;
    l->pieces[l->count] = (uint32_t)k;
    memcpy(l->values + l->count * P * 3, h->base + 3 * v0, nv * 3 * sizeof(float));
    l->count++;
    h->saved[k] = 1;
}

/* base[v0, v1) = src[v0, v1), saving each piece that changes first. */
static void commit_span(fp_history *h, const float *src, size_t v0, size_t v1)
{
    while (v0 < v1) {
        size_t k = v0 / P, e = (k + 1) * P < v1 ? (k + 1) * P : v1;
        size_t bytes = (e - v0) * 3 * sizeof(float);
        if (memcmp(h->base + 3 * v0, src + 3 * v0, bytes)) {
            save_piece(h, k);
            memcpy(h->base + 3 * v0, src + 3 * v0, bytes);
        }
        v0 = e;
    }
}

void fp_history_commit(fp_history *h, const float *deformed)
{
    if (!h->gesture_open) {
        open_gesture(h);
        h->gestures++;
    }
    commit_span(h, deformed, 0, h->n);
    check_ring(h);
}

void fp_history_commit_ranges(fp_history *h, const float *deformed, const uint32_t *ranges,
                              size_t nranges)
{
    if (!h->gesture_open) {
        open_gesture(h);
        h->gestures++;
    }
    for (size_t r = 0; r < nranges; r++) {
        size_t v0 = ranges[2 * r], c = ranges[2 * r + 1];
        if (v0 >= h->n) continue;
        commit_span(h, deformed, v0, c < h->n - v0 ? v0 + c : h->n);
    }
    check_ring(h);
}

void fp_history_end_gesture(fp_history *h)
{
    close_gesture(h);
    check_ring(h);
}

void fp_history_set_base(fp_history *h, const float *src)
{
    memcpy(h->base, src, h->n * 3 * sizeof(float));
    close_gesture(h);
    check_ring(h);
}

bool fp_history_undo(fp_history *h)
{
    if (!h->count) return false;
    close_gesture(h);
    h->next = (h->next + FP_HISTORY_LEVELS - 1) % FP_HISTORY_LEVELS;
    h->count--;
    const fp_history_level *l = &h->level[h->next];
    for (size_t i = 0; i < l->count; i++) {
        size_t v0 = (size_t)l->pieces[i] * P, nv = v0 + P <= h->n ? P : h->n - v0;
        memcpy(h->base + 3 * v0, l->values + i * P * 3, nv * 3 * sizeof(float));
    }
    h->gestures = l->gestures;
    check_ring(h);
    return true;
}

void fp_history_reset(fp_history *h, const float *loaded)
{
    close_gesture(h);
    if (memcmp(h->base, loaded, h->n * 3 * sizeof(float))) {
        open_gesture(h);
        commit_span(h, loaded, 0, h->n);
        close_gesture(h);
    }
    h->gestures = 0;
    check_ring(h);
}
