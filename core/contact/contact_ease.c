/* The guard's easing (fp_contact_ease): where the shape shown lags the map (skin a scale-back
 * held or carried), the lag closes at a bounded speed instead of all at once. */
#include "contact_internal.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

/* one lagging vertex's ease (entry i of ease_v): its candidate q rewritten where the lag is
 * over s; true when rewritten */
static bool ease_one(struct track *k, size_t i, float *cand, float step)
{
    const uint32_t v = k->ease_v[i];
    float *q = cand + 3 * (size_t)v, *t = k->ease_t + 3 * i;
    const float *p = k->p + 3 * (size_t)v;
    double lag[3], l2 = 0, m2 = 0;
    for (int j = 0; j < 3; j++) {
        lag[j] = (double)t[j] - p[j];
        l2 += lag[j] * lag[j];
        m2 += ((double)q[j] - t[j]) * ((double)q[j] - t[j]);
    }
    /* the lag may shrink by step plus the map's own motion there this frame */
    const double s = step + sqrt(m2), l = sqrt(l2);
    memcpy(t, q, 3 * sizeof(float)); /* where the map puts it now */
    if (!(l > s)) return false;
    for (int j = 0; j < 3; j++) q[j] = (float)((double)q[j] - lag[j] * (1 - s / l));
    return true;
}

size_t fp_contact_ease(fp_contact *c, float *cand, const uint32_t *ranges, size_t nranges, float step)
{
    if (!c || !c->tk || !cand || !(step >= 0) || (!ranges && nranges != SIZE_MAX)) return 0;
    struct track *k = c->tk;
    size_t eased = 0;
    if (nranges == SIZE_MAX)
        for (size_t i = 0; i < k->nease; i++) eased += ease_one(k, i, cand, step);
    else /* (the ranges' vertices looked up: as fp_contact_hold, O(their length)) */
        for (size_t r = 0; k->nease && r < nranges; r++) {
            const size_t f = ranges[2 * r], e = f + ranges[2 * r + 1];
            for (size_t v = f; v < e && v < c->n; v++)
                if (k->ease_at[v]) eased += ease_one(k, k->ease_at[v] - 1, cand, step);
        }
    k->eased = true;
    return eased;
}

/* appends v with target t (ease_v, ease_t, ease_at); 0 or -ENOMEM */
static int ease_add(fp_contact *c, uint32_t v, const float *t)
{
    struct track *k = c->tk;
    if (reserve((void **)&k->ease_v, &k->cap_ease_v, k->nease + 1, sizeof *k->ease_v) ||
        reserve((void **)&k->ease_t, &k->cap_ease_t, 3 * (k->nease + 1), sizeof *k->ease_t))
        return -ENOMEM;
    k->ease_v[k->nease] = v;
    memcpy(k->ease_t + 3 * k->nease, t, 3 * sizeof(float));
    k->ease_at[v] = (uint32_t)++k->nease;
    return 0;
}

int fpc_ease_record(fp_contact *c, const float *cand, bool whole)
{
    struct track *k = c->tk;
    /* without fp_contact_ease this step, the candidate is where the map puts the vertices */
    if (!k->eased && k->nease)
        for (size_t i = 0; i < k->nmv; i++)
            if (k->ease_at[k->mv[i]])
                memcpy(k->ease_t + 3 * (size_t)(k->ease_at[k->mv[i]] - 1), cand + 3 * (size_t)k->mv[i],
                       3 * sizeof(float));
    k->eased = false;
    /* a scale-back: the moved vertices P holds away from the candidate join */
    for (size_t i = 0; !whole && i < k->nmv; i++) {
        const uint32_t v = k->mv[i];
        if (k->ease_at[v] || !memcmp(k->p + 3 * (size_t)v, cand + 3 * (size_t)v, 3 * sizeof(float)))
            continue;
        if (ease_add(c, v, cand + 3 * (size_t)v)) return -ENOMEM;
    }
    /* those P caught up with leave */
    size_t m = 0;
    for (size_t i = 0; i < k->nease; i++) {
        const uint32_t v = k->ease_v[i];
        const float *t = k->ease_t + 3 * i;
        if (!memcmp(k->p + 3 * (size_t)v, t, 3 * sizeof(float))) {
            k->ease_at[v] = 0;
            continue;
        }
        k->ease_v[m] = v;
        memmove(k->ease_t + 3 * m, t, 3 * sizeof(float));
        k->ease_at[v] = (uint32_t)++m;
    }
    k->nease = m;
    return 0;
}
