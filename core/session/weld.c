/* weld.c: vertices welded by position (weld.h). */
#include "weld.h"

#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

static int by_position(const void *a, const void *b)
{
    const fp_at_pos *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x->p[k] != y->p[k]) return x->p[k] < y->p[k] ? -1 : 1;
    return (x->v > y->v) - (x->v < y->v);
}

int fp_weld_by_position(const float *pos, size_t n, uint32_t *weld, fp_at_pos **order)
{
    if (order) *order = NULL;
    fp_at_pos *o = malloc((n ? n : 1) * sizeof *o);
    if (!o) return -ENOMEM;
    for (size_t v = 0; v < n; v++) {
        memcpy(o[v].p, pos + 3 * v, sizeof o[v].p);
        o[v].v = (uint32_t)v;
    }
    qsort(o, n, sizeof *o, by_position);
    for (size_t i = 0; i < n; i++) {
        bool same = i > 0 && !memcmp(o[i].p, o[i - 1].p, sizeof o[i].p);
        weld[o[i].v] = same ? weld[o[i - 1].v] : o[i].v;
    }
    if (order) *order = o;
    else free(o);
    return 0;
}
