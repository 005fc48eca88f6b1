/* log_relay: plugin log lines from any thread to their owner's (log_relay.h). */
#include "log_relay.h"

#include <errno.h>
#include <facepuppet/plugin.h>
#include <stdio.h>
#include <string.h>

int fp_log_relay_init(fp_log_relay *r)
{
    memset(r, 0, sizeof *r);
    atomic_init(&r->pending, 0);
    if (pthread_mutex_init(&r->lock, NULL)) return -ENOMEM;
    r->ready = true;
    return 0;
}

void fp_log_relay_push(fp_log_relay *r, int level, const char *message)
{
    if (!r || !r->ready) return;
    pthread_mutex_lock(&r->lock);
    if (r->count == FP_LOG_RELAY_LINES) {
        if (!r->dropped++) atomic_fetch_add_explicit(&r->pending, 1, memory_order_release);
    } else {
        unsigned at = (r->head + r->count) % FP_LOG_RELAY_LINES;
        r->level[at] = level;
        snprintf(r->line[at], sizeof r->line[at], "%s", message ? message : "");
        r->count++;
        atomic_fetch_add_explicit(&r->pending, 1, memory_order_release);
    }
    pthread_mutex_unlock(&r->lock);
}

size_t fp_log_relay_drain(fp_log_relay *r, const char *source, fp_log_relay_fn fn, void *user)
{
    if (!r || !r->ready || !atomic_load_explicit(&r->pending, memory_order_acquire)) return 0;
    size_t handed = 0;
    char line[FP_LOG_RELAY_BYTES];
    for (;;) { /* one line at a time, copied out: fn runs without the lock */
        pthread_mutex_lock(&r->lock);
        if (!r->count) break; /* (still locked: the dropped count is read below) */
        int level = r->level[r->head];
        memcpy(line, r->line[r->head], sizeof line);
        r->head = (r->head + 1) % FP_LOG_RELAY_LINES;
        r->count--;
        atomic_fetch_sub_explicit(&r->pending, 1, memory_order_relaxed);
        pthread_mutex_unlock(&r->lock);
        if (fn) fn(user, level, source ? source : "plugin", line);
        handed++;
    }
    unsigned long dropped = r->dropped;
    if (dropped) atomic_fetch_sub_explicit(&r->pending, 1, memory_order_relaxed);
    r->dropped = 0;
    pthread_mutex_unlock(&r->lock);
    if (dropped) {
        snprintf(line, sizeof line, "%lu log line%s dropped (logged faster than read: %d kept at a time)",
                 dropped, dropped == 1 ? "" : "s", FP_LOG_RELAY_LINES);
        if (fn) fn(user, FP_LOG_WARNING, source ? source : "plugin", line);
        handed++;
    }
    return handed;
}

void fp_log_relay_destroy(fp_log_relay *r)
{
    if (!r || !r->ready) return;
    pthread_mutex_destroy(&r->lock);
    memset(r, 0, sizeof *r);
}
