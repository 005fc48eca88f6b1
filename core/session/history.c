/* Step 6 of the frame: commit into the base, the undo ring, reset. */
#include "history.h"

#include <stdlib.h>
#include <string.h>

void fp_history_init(fp_history *h, size_t n, float *base)
{
    memset(h, 0, sizeof *h);
    h->n = n;
    h->base = base;
}

void fp_history_free(fp_history *h)
{
    for (size_t i = 0; i < FP_HISTORY_LEVELS; i++) {
        free(h->snap[i]);
        h->snap[i] = NULL;
    }
    h->count = h->next = 0;
}

void fp_history_push(fp_history *h)
{
    size_t bytes = h->n * 3 * sizeof(float);
    float **slot = &h->snap[h->next];
    if (!*slot) *slot = malloc(bytes ? bytes : 1);
    if (!*slot) return;
    memcpy(*slot, h->base, bytes);
    h->snap_gestures[h->next] = h->gestures;
    h->next = (h->next + 1) % FP_HISTORY_LEVELS;
    if (h->count < FP_HISTORY_LEVELS) h->count++;
}

void fp_history_commit(fp_history *h, const float *deformed)
{
    if (!h->gesture_open) {
        fp_history_push(h);
        h->gestures++;
    }
    h->gesture_open = true;
    memcpy(h->base, deformed, h->n * 3 * sizeof(float));
}

void fp_history_end_gesture(fp_history *h) { h->gesture_open = false; }

void fp_history_set_base(fp_history *h, const float *src)
{
    memcpy(h->base, src, h->n * 3 * sizeof(float));
    h->gesture_open = false;
}

bool fp_history_undo(fp_history *h)
{
    if (!h->count) return false;
    h->next = (h->next + FP_HISTORY_LEVELS - 1) % FP_HISTORY_LEVELS;
    h->count--;
    fp_history_set_base(h, h->snap[h->next]);
    h->gestures = h->snap_gestures[h->next];
    return true;
}

void fp_history_reset(fp_history *h, const float *loaded)
{
    if (memcmp(h->base, loaded, h->n * 3 * sizeof(float))) fp_history_push(h);
    fp_history_set_base(h, loaded);
    h->gestures = 0;
}
