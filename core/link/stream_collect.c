/* The stream's records of a frame, on the sender thread (stream_internal.h,
 * fp__stream_collect): each block of the frame's snapshot quantised and compared with the
 * offsets sent so far (tx_state), the changed ones recorded. Built with -fno-trapping-math
 * (core/link/CMakeLists.txt): the quantiser's loop vectorises only where floating-point
 * exceptions are not observed, and nothing here reads them. */
#include "stream_internal.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

/* A block's k offsets in steps (d = (p - nu) x scale), rounded half away from zero in float
 * (the decoder's tolerance holds: within half a step, plus float rounding); beyond +-32767
 * clipped, not finite 0. Branch-free, so that it vectorises. Returns the values clipped. */
static size_t quantise_block(const float *restrict p, const float *restrict nu, float scale, size_t k,
                             int16_t *restrict q)
{
    int clipped = 0;
    for (size_t i = 0; i < k; i++) {
        const float d = (p[i] - nu[i]) * scale;
        float c = d < 32767.0f ? d : 32767.0f;
        c = c > -32767.0f ? c : -32767.0f;
        c = d == d ? c : 0.0f;
        const float h = c < 0.0f ? -0.5f : 0.5f;
        clipped += (d >= 32767.5f) | (d <= -32767.5f);
        q[i] = (int16_t)(int32_t)(c + h);
    }
    return (size_t)clipped;
}

int fp__stream_reserve(stream_job *j, size_t m)
{
    if (m <= j->cap) return 0;
    size_t cap = m + m / 2 + 64;
    uint32_t *idx = realloc(j->idx, cap * sizeof *idx);
    if (idx) j->idx = idx;
    int16_t *q = idx ? realloc(j->q, 3 * cap * sizeof *q) : NULL;
    if (q) j->q = q;
    if (!idx || !q) return -ENOMEM;
    j->cap = cap;
    return 0;
}

int fp__stream_collect(fp_stream *s, const stream_hand *h)
{
    const float *pos = s->snaps[h->snap], *nu = s->o.neutral;
    const float scale = (float)(s->o.mm_per_unit / s->step_mm);
    stream_job *rec = &s->tx_rec;
    int16_t qb[3 * STREAM_BLOCK];
    size_t m = 0, clipped = 0;
    bool lost = false;
    for (size_t r = 0; r < h->nranges; r++) {
        const size_t first = h->ranges[2 * r], end = first + h->ranges[2 * r + 1];
        for (size_t b0 = first; b0 < end; b0 += STREAM_BLOCK) {
            const size_t b1 = b0 + STREAM_BLOCK < end ? b0 + STREAM_BLOCK : end, k = 3 * (b1 - b0);
            int16_t *sent = s->tx_state + 3 * b0;
            clipped += quantise_block(pos + 3 * b0, nu + 3 * b0, scale, k, qb);
            if (!memcmp(qb, sent, k * sizeof *qb)) continue; /* (most blocks) */
            if (!lost && fp__stream_reserve(rec, m + STREAM_BLOCK)) lost = true;
            for (size_t v = b0; !lost && v < b1; v++) {
                const int16_t *nq = qb + 3 * (v - b0), *old = sent + 3 * (v - b0);
                if (nq[0] != old[0] || nq[1] != old[1] || nq[2] != old[2]) {
                    rec->idx[m] = (uint32_t)v;
                    memcpy(rec->q + 3 * m, nq, 3 * sizeof *nq);
                    m++;
                }
            }
            memcpy(sent, qb, k * sizeof *qb);
        }
    }
    atomic_fetch_add_explicit(&s->clipped, clipped, memory_order_relaxed);
    rec->m = lost ? 0 : m;
    return lost ? -ENOMEM : 0;
}
