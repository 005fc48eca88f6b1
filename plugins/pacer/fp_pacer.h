/*
 * fp_pacer.h: the pacing every replaying input plugin needs (input-replay, input-take): wait
 * on CLOCK_MONOTONIC until an event's moment in a way stop() interrupts at once, and push
 * events into the host's queue without ever dropping one (a full queue is retried every
 * millisecond until the event goes in or stop is asked: a recording holds every sample, and
 * a headless run that steps on the recording's clock must see each one).
 *
 * Threads: fp_pacer_init/destroy [main-thread]; fp_pacer_stop [main-thread], wakes a waiting
 * thread; fp_pacer_rearm before starting the thread; the waits and pushes on the plugin's one
 * [input-thread]. Static library `fp_pacer` (PIC, hidden symbols), linked into plugins.
 */
#ifndef FP_PACER_H
#define FP_PACER_H

#include <facepuppet/plugin.h>

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

typedef struct fp_pacer {
    const fp_host *host;     /* where events are pushed; not owned */
    pthread_mutex_t mutex;
    pthread_cond_t cond;     /* on CLOCK_MONOTONIC; broadcast by fp_pacer_stop */
    atomic_bool stop;
} fp_pacer;

/** Set up *p for host (kept by pointer). Returns 0 or a negative errno. */
int fp_pacer_init(fp_pacer *p, const fp_host *host);
void fp_pacer_destroy(fp_pacer *p);
/** Clear a previous stop, before the thread starts again. */
void fp_pacer_rearm(fp_pacer *p);
/** Ask the thread to stop and wake it from any wait. */
void fp_pacer_stop(fp_pacer *p);
/** True once fp_pacer_stop was called (and not rearmed). */
bool fp_pacer_stopped(fp_pacer *p);
/** CLOCK_MONOTONIC in nanoseconds. */
int64_t fp_pacer_now_ns(void);
/** Wait until CLOCK_MONOTONIC reaches deadline_ns (ns). Returns false when stop was asked. */
bool fp_pacer_wait_until(fp_pacer *p, int64_t deadline_ns);
/** Push ev (ev->header.size bytes), retrying a full queue every millisecond. Returns false
 *  when stop was asked before it went in. */
bool fp_pacer_push(fp_pacer *p, const fp_event *ev);
/** Push a status event (fp_status_code) with printf-style text (truncated to the event's
 *  116 bytes), stamped time_ns, hand -1. As fp_pacer_push. */
bool fp_pacer_push_status(fp_pacer *p, int64_t time_ns, uint32_t code, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

#endif
