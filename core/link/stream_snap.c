/* The stream's snapshots, the frame thread's side (stream_internal.h): a frame hands the sender
 * thread a copy of its touched blocks, so that the frame thread's part of --stream is a copy
 * (the sender quantises: stream_collect.c). A handful of snapshots of the whole mesh, made
 * and touched at the opening (no page fault in a frame), each the frame thread's from its
 * copy until the sender has quantised it; only the frame's blocks of a snapshot are copied
 * and read. On a large mesh a frame over many vertices is copied by two threads: a helper (an
 * fp_worker, SCHED_BATCH) takes the upper half. */
#define _GNU_SOURCE
#include "stream_internal.h"

#include "fp_worker.h"
#include "facepuppet/decimal.h"

#include <errno.h>
#include <sched.h>
#include <stdlib.h>
#include <string.h>

#define SPLIT_MIN 131072u          /* touched vertices from which a frame's copy is shared
                                      (ICT: 26,719; the test knob FP_STREAM_SPLIT=N sets it) */
#define SNAP_BUDGET (64u << 20)    /* bytes of snapshots in all, at most (at least 2 of them) */
#define HELPER_IDLE_NS 20000000    /* the helper polls (yielding) this long, then parks */
#define SPIN_YIELD 4096            /* the frame thread's pauses before it yields, waiting */

/* pos into snap over the ranges' vertices in [from, to). */
static void copy_part(const float *pos, float *snap, const stream_hand *h, size_t from, size_t to)
{
    for (size_t r = 0; r < h->nranges; r++) {
        size_t a = h->ranges[2 * r], b = a + h->ranges[2 * r + 1];
        if (b <= from) continue;
        if (a >= to) break;
        a = a > from ? a : from;
        b = b < to ? b : to;
        memcpy(snap + 3 * a, pos + 3 * a, 3 * (b - a) * sizeof *pos);
    }
}

/* The helper's poll: the part it was woken for. */
static bool helper_poll(void *user, fp_worker *w)
{
    fp_stream *s = user;
    const uint32_t g = fp_worker_wakes(w);
    if (g == atomic_load_explicit(&s->help_done, memory_order_relaxed)) return false;
    copy_part(s->help_pos, s->help_snap, s->help_hand, s->help_from, s->o.n);
    atomic_store_explicit(&s->help_done, g, memory_order_release);
    fp_worker_served(w, g);
    return true;
}

/* SCHED_BATCH, as the sender thread (fp__stream_batch). */
static void helper_enter(void *user)
{
    (void)user;
    fp__stream_batch();
}

int fp__stream_snap_open(fp_stream *s)
{
    const size_t bytes = 3 * s->o.n * sizeof(float);
    size_t k = SNAP_BUDGET / bytes;
    s->nsnaps = k < 2 ? 2 : k > STREAM_SNAPS_MAX ? STREAM_SNAPS_MAX : (int)k;
    for (int i = 0; i < s->nsnaps; i++) {
        if (!(s->snaps[i] = malloc(bytes))) return -ENOMEM;
        memcpy(s->snaps[i], s->o.neutral, bytes); /* (touched now, not in a frame) */
        atomic_init(&s->snap_busy[i], false);
    }
    const char *knob = getenv("FP_STREAM_SPLIT");
    unsigned long long w = 0;
    s->split_min = knob && fp_parse_whole(knob, UINT32_MAX, &w) && w >= 2 * STREAM_BLOCK ? (size_t)w : SPLIT_MIN;
    if (s->o.n < s->split_min) return 0;
    const fp_worker_spec spec = {.poll = helper_poll, .user = s, .idle_ns = HELPER_IDLE_NS,
                                 .yield_ns = 0, .pauses = 0, .enter = helper_enter};
    return fp_worker_create(&spec, &s->helper);
}

void fp__stream_snap_free(fp_stream *s)
{
    fp_worker_destroy(&s->helper);
    for (int i = 0; i < s->nsnaps; i++) free(s->snaps[i]);
    for (int k = 0; k < STREAM_JOBS; k++) free(s->jobs[k].ranges);
}

int fp__stream_snap_take(fp_stream *s)
{
    for (int i = 0; i < s->nsnaps; i++)
        if (!atomic_load_explicit(&s->snap_busy[i], memory_order_acquire)) {
            atomic_store_explicit(&s->snap_busy[i], true, memory_order_relaxed);
            return i;
        }
    return -1;
}

int fp__stream_snap_ranges(stream_hand *h, const uint32_t *ranges, size_t nranges, bool all, size_t n)
{
    const size_t need = all ? 1 : nranges;
    if (need > h->cap_ranges) {
        uint32_t *grown = realloc(h->ranges, 2 * need * sizeof *grown);
        if (!grown) return -ENOMEM;
        h->ranges = grown;
        h->cap_ranges = need;
    }
    size_t k = 0;
    if (all) {
        h->ranges[0] = 0, h->ranges[1] = (uint32_t)n;
        k = 1;
    }
    for (size_t r = 0; !all && r < nranges; r++) {
        size_t a = ranges[2 * r] / STREAM_BLOCK * STREAM_BLOCK;
        size_t b = ((size_t)ranges[2 * r] + ranges[2 * r + 1] + STREAM_BLOCK - 1) / STREAM_BLOCK * STREAM_BLOCK;
        if (b > n) b = n;
        if (k && a <= (size_t)h->ranges[2 * k - 2] + h->ranges[2 * k - 1]) { /* (meets the last) */
            h->ranges[2 * k - 1] = (uint32_t)(b - h->ranges[2 * k - 2]);
            continue;
        }
        h->ranges[2 * k] = (uint32_t)a, h->ranges[2 * k + 1] = (uint32_t)(b - a);
        k++;
    }
    h->nranges = k;
    return 0;
}

/* Where a frame's copy is shared: the block boundary at half its vertices (*total). */
static size_t split_at(const stream_hand *h, size_t *total)
{
    size_t t = 0;
    for (size_t r = 0; r < h->nranges; r++) t += h->ranges[2 * r + 1];
    *total = t;
    for (size_t r = 0, seen = 0; r < h->nranges; r++) {
        const size_t count = h->ranges[2 * r + 1];
        if (seen + count >= t / 2) return (h->ranges[2 * r] + (t / 2 - seen)) / STREAM_BLOCK * STREAM_BLOCK;
        seen += count;
    }
    return 0;
}

void fp__stream_snap_copy(fp_stream *s, const stream_hand *h, const float *pos)
{
    float *snap = s->snaps[h->snap];
    size_t total;
    const size_t mid = split_at(h, &total);
    if (!s->helper || total < s->split_min || mid == 0) {
        copy_part(pos, snap, h, 0, s->o.n);
        return;
    }
    s->help_pos = pos, s->help_snap = snap, s->help_hand = h, s->help_from = mid;
    /* (seen by the helper's poll of this wake: fp_worker_wake takes its lock) */
    const uint32_t g = fp_worker_wake(s->helper, NULL, NULL);
    copy_part(pos, snap, h, 0, mid);
    for (unsigned spin = 0; atomic_load_explicit(&s->help_done, memory_order_acquire) != g; spin++) {
        if (spin < SPIN_YIELD) fp_cpu_pause();
        else sched_yield();
    }
}
