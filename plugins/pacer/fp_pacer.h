/*
 * fp_pacer.h: the pacing every replaying input plugin needs (input-replay, input-take): wait
 * on CLOCK_MONOTONIC until an event's moment in a way stop() interrupts at once, and push
 * events into the host's queue without ever dropping one (a full queue is retried every
 * millisecond until the event goes in or stop is asked: a recording holds every sample, and
 * a headless run that steps on the recording's clock must see each one).
 *
 * It also owns that plugin's one thread: fp_pacer_start and fp_pacer_stop are a replaying
 * input's fp_input.start and stop (the plugin passes its thread function), and
 * fp_pacer_destroy stops the thread before releasing the pacer.
 *
 * Threads: fp_pacer_init, _start, _stop and _destroy [main-thread]; the waits and pushes on
 * the plugin's one [input-thread] (the function given to fp_pacer_start). Static library
 * `fp_pacer` (PIC, hidden symbols), linked into plugins.
 */
#ifndef FP_PACER_H
#define FP_PACER_H

#include <facepuppet/plugin.h>

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct fp_pacer {
    const fp_host *host;     /* where events are pushed; not owned */
    pthread_mutex_t mutex;
    pthread_cond_t cond;     /* on CLOCK_MONOTONIC; broadcast by fp_pacer_stop */
    atomic_bool stop;        /* asked by fp_pacer_stop; cleared by fp_pacer_start */
    pthread_t thread;
    bool running;            /* [main-thread] started and not yet joined */
} fp_pacer;

/** Set up *p for host (kept by pointer). Returns 0 or a negative errno. */
int fp_pacer_init(fp_pacer *p, const fp_host *host);
/** Stop the thread (fp_pacer_stop), then release *p. */
void fp_pacer_destroy(fp_pacer *p);
/** Start run(arg) on the pacer's thread. Returns 0; -EBUSY when it already runs, or a
 *  negative errno when the thread cannot be made, each with a message in err that begins
 *  with `who` ("replay: already started"). The input's fp_input.start. */
int fp_pacer_start(fp_pacer *p, void *(*run)(void *), void *arg, const char *who, char *err,
                   size_t errlen);
/** Ask the thread to stop, wake it from any wait and join it; nothing when it does not run.
 *  No push after it returns. The input's fp_input.stop. */
void fp_pacer_stop(fp_pacer *p);
/** [input-thread] True once fp_pacer_stop was asked (since the last start). */
bool fp_pacer_stopped(fp_pacer *p);
/** The `speed=X` key of a replaying input: a decimal (fp_decimal_span: no hexadecimal, inf or
 *  nan), read in the C locale, from 0.001 to 1e6 (1e-9 stretched a 3 s recording over a
 *  century; 1e-300 overflowed). true and *out set; false with *out untouched (the caller
 *  reports "NAME: speed=V: expected a number from 0.001 to 1e6"). [any-thread] */
bool fp_pacer_parse_speed(const char *v, double *out);
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
