/* What changed in a shape since its consumer last asked (changed.h). */
#include "changed.h"

#include <stdlib.h>
#include <string.h>

void fp_changed_free(fp_changed *c)
{
    free(c->r);
    free(c->tmp);
    free(c->out);
    memset(c, 0, sizeof *c);
}

void fp_changed_all(fp_changed *c)
{
    c->all = true;
    c->n = 0;
}

static bool reserve(uint32_t **buf, size_t *cap, size_t pairs)
{
    if (pairs <= *cap) return true;
    size_t want = *cap ? *cap : 64;
    while (want < pairs) want *= 2;
    uint32_t *grown = realloc(*buf, want * 2 * sizeof *grown);
    if (!grown) return false;
    *buf = grown;
    *cap = want;
    return true;
}

/* Append [first, end) to out (m pairs), joining it to the last pair when they meet. */
static void push(uint32_t *out, size_t *m, uint64_t first, uint64_t end)
{
    if (*m) {
        uint64_t last_end = (uint64_t)out[2 * *m - 2] + out[2 * *m - 1];
        if (first <= last_end) {
            if (end > last_end) out[2 * *m - 1] = (uint32_t)(end - out[2 * *m - 2]);
            return;
        }
    }
    out[2 * *m] = (uint32_t)first;
    out[2 * *m + 1] = (uint32_t)(end - first);
    (*m)++;
}

void fp_changed_add(fp_changed *c, const uint32_t *ranges, size_t count)
{
    if (!c->tracking || c->all || count == 0) return;
    if (count == SIZE_MAX || !ranges || !reserve(&c->tmp, &c->tmp_cap, c->n + count)) {
        fp_changed_all(c);
        return;
    }
    size_t i = 0, j = 0, m = 0;
    while (i < c->n || j < count) {
        const uint32_t *p = j == count || (i < c->n && c->r[2 * i] <= ranges[2 * j]) ? &c->r[2 * i++]
                                                                                     : &ranges[2 * j++];
        if (p[1]) push(c->tmp, &m, p[0], (uint64_t)p[0] + p[1]);
    }
    uint32_t *t = c->r;
    size_t tc = c->cap;
    c->r = c->tmp;
    c->cap = c->tmp_cap;
    c->tmp = t;
    c->tmp_cap = tc;
    c->n = m;
}

size_t fp_changed_take(fp_changed *c, const uint32_t **ranges)
{
    *ranges = NULL;
    if (!c->tracking || c->all) {
        c->tracking = true;
        c->all = false;
        c->n = 0;
        return SIZE_MAX;
    }
    uint32_t *t = c->out;
    size_t tc = c->out_cap, n = c->n;
    c->out = c->r;
    c->out_cap = c->cap;
    c->r = t;
    c->cap = tc;
    c->n = 0;
    *ranges = n ? c->out : NULL;
    return n;
}
