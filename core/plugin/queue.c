/* Bounded MPSC event queue after Dmitry Vyukov's bounded MPMC queue: each cell carries a
 * sequence number; a producer claims a slot with one CAS on head, writes, then publishes
 * by storing seq = pos + 1. Lock-free, no allocation after init. */
#include "fp_plugin_host.h"

#include <assert.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

struct fp_event_cell {
    atomic_size_t seq;
    int64_t since_ns; /* fp_event_queue_push_at's; written and read as the event is */
    fp_event event;
};

int fp_event_queue_init(fp_event_queue *q, size_t capacity)
{
    size_t n = 2;
    while (n < capacity) n <<= 1;
    memset(q, 0, sizeof *q);
    q->cells = calloc(n, sizeof *q->cells);
    if (!q->cells) return -ENOMEM;
    for (size_t i = 0; i < n; i++) atomic_init(&q->cells[i].seq, i);
    q->mask = n - 1;
    atomic_init(&q->head, 0);
    atomic_init(&q->tail, 0);
    atomic_init(&q->dropped, 0);
    atomic_init(&q->refused, 0);
    return 0;
}

void fp_event_queue_destroy(fp_event_queue *q)
{
    free(q->cells);
    q->cells = NULL;
}

/* A refused event's identity: FNV-1a over its bytes, never 0 */
static uint64_t event_key(const fp_event_header *ev)
{
    const unsigned char *b = (const unsigned char *)ev;
    uint64_t h = 1469598103934665603ull;
    for (uint32_t i = 0; i < ev->size; i++) h = (h ^ b[i]) * 1099511628211ull;
    return h | 1u;
}

/* The queue refused ev: one more dropped event, unless it is the one refused last (pushed
 * again: counted once). dropped is counted before refused names the event, so that
 * fp_event_queue_dropped never subtracts what is not counted yet. */
static void refused(fp_event_queue *q, const fp_event_header *ev)
{
    const uint64_t k = event_key(ev);
    uint64_t old = atomic_load_explicit(&q->refused, memory_order_relaxed);
    if (old == k) return;
    atomic_fetch_add_explicit(&q->dropped, 1, memory_order_relaxed);
    while (!atomic_compare_exchange_weak_explicit(&q->refused, &old, k, memory_order_relaxed,
                                                  memory_order_relaxed))
        if (old == k) { /* another producer named the same event meanwhile, and counted it */
            atomic_fetch_sub_explicit(&q->dropped, 1, memory_order_relaxed);
            return;
        }
}

/* The queue took ev: where it is the event last refused (pushed again, as a producer that
 * waits for room does), it was not dropped after all; another event: the refused one was
 * given up, its drop stays. Either way refused is cleared, so that a push after a drop
 * hashes its event once, not every time. */
static void taken(fp_event_queue *q, const fp_event_header *ev)
{
    uint64_t old = atomic_load_explicit(&q->refused, memory_order_relaxed);
    if (!old) return;
    const bool again = old == event_key(ev);
    if (atomic_compare_exchange_strong_explicit(&q->refused, &old, 0, memory_order_relaxed,
                                                memory_order_relaxed) && again)
        atomic_fetch_sub_explicit(&q->dropped, 1, memory_order_relaxed);
}

/* A pose (angles, positions, wrist) finds the queue full FP_EVENT_QUEUE_RESERVE of its
 * capacity early: the rest is kept for the events that are not repeated (statuses, the end
 * of a stream above all; buttons; channels), so that an input flooding poses cannot push
 * them out. (head - tail is read without a lock: a soft bound, never past the capacity.) */
static bool pose_room(fp_event_queue *q, const fp_event_header *ev)
{
    if (ev->type != FP_EVENT_JOINT_ANGLES && ev->type != FP_EVENT_JOINT_POSITIONS &&
        ev->type != FP_EVENT_WRIST_POSE)
        return true;
    const size_t capacity = q->mask + 1, reserve = capacity / FP_EVENT_QUEUE_RESERVE;
    const size_t head = atomic_load_explicit(&q->head, memory_order_relaxed);
    const size_t tail = atomic_load_explicit(&q->tail, memory_order_relaxed);
    return head - tail < capacity - reserve;
}

bool fp_event_queue_push(fp_event_queue *q, const fp_event_header *ev)
{
    return fp_event_queue_push_at(q, ev, ev ? ev->time_ns : 0);
}

bool fp_event_queue_push_at(fp_event_queue *q, const fp_event_header *ev, int64_t since_ns)
{
    if (!ev || ev->size < sizeof *ev || ev->size > sizeof(fp_event)) {
        atomic_fetch_add_explicit(&q->dropped, 1, memory_order_relaxed);
        return false;
    }
    assert(q->cells && (q->mask & (q->mask + 1)) == 0); /* initialised; capacity a power of 2 */
    if (!pose_room(q, ev)) {
        refused(q, ev);
        return false; /* full for poses */
    }
    size_t pos = atomic_load_explicit(&q->head, memory_order_relaxed);
    for (;;) {
        struct fp_event_cell *c = &q->cells[pos & q->mask];
        size_t seq = atomic_load_explicit(&c->seq, memory_order_acquire);
        intptr_t dif = (intptr_t)seq - (intptr_t)pos;
        if (dif == 0) {
            if (atomic_compare_exchange_weak_explicit(&q->head, &pos, pos + 1,
                                                      memory_order_relaxed,
                                                      memory_order_relaxed)) {
                memcpy(&c->event, ev, ev->size);
                c->since_ns = since_ns;
                atomic_store_explicit(&c->seq, pos + 1, memory_order_release);
                taken(q, ev);
                return true;
            }
        } else if (dif < 0) {
            refused(q, ev);
            return false; /* full */
        } else {
            pos = atomic_load_explicit(&q->head, memory_order_relaxed);
        }
    }
}

unsigned long fp_event_queue_dropped(const fp_event_queue *q)
{
    fp_event_queue *w = (fp_event_queue *)q; /* (atomic loads only) */
    const unsigned long d = atomic_load_explicit(&w->dropped, memory_order_relaxed);
    const unsigned long waiting = atomic_load_explicit(&w->refused, memory_order_relaxed) != 0;
    return d > waiting ? d - waiting : 0;
}

bool fp_event_queue_pop(fp_event_queue *q, fp_event *out)
{
    size_t pos = atomic_load_explicit(&q->tail, memory_order_relaxed);
    struct fp_event_cell *c = &q->cells[pos & q->mask];
    size_t seq = atomic_load_explicit(&c->seq, memory_order_acquire);
    if ((intptr_t)seq - (intptr_t)(pos + 1) < 0) return false; /* empty */
    /* The cell was published (seq == pos + 1, after the producer's CAS on head): head is past
     * pos by at most the capacity, and the event is one push took (a size it accepted). */
    assert(seq == pos + 1);
    assert(atomic_load_explicit(&q->head, memory_order_relaxed) - pos - 1 <= q->mask);
    assert(c->event.header.size >= sizeof(fp_event_header) && c->event.header.size <= sizeof(fp_event));
    memcpy(out, &c->event, c->event.header.size);
    q->popped_since_ns = c->since_ns;
    atomic_store_explicit(&c->seq, pos + q->mask + 1, memory_order_release);
    atomic_store_explicit(&q->tail, pos + 1, memory_order_relaxed);
    return true;
}
