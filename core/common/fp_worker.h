/*
 * fp_worker.h: a worker thread that spins, then parks (issue 18's two workers: the contact
 * guard's, core/contact/contact_worker.c, and the session's frame thread,
 * core/session/frame_thread.c).
 *
 * Why both spin. A thread that sleeps between frames wakes with its caches cold and takes
 * a millisecond or more to wake on a busy 2-core VM (frame_thread.h and fp_contact.h have
 * the measurements), so after its work the thread polls for more, offering its core to
 * other threads between polls, and parks (a condition variable) only when no work has come
 * for idle_ns. Through a performance at 60 frames a second it never parks.
 *
 * How. The owner wakes it (fp_worker_wake: a wake number, under the worker's lock, so that
 * a parked worker cannot miss it) and publishes work in its own atomics; the worker calls
 * spec.poll, which claims and runs what work there is and says whether it ran any. Between
 * polls: spec.pauses CPU pauses, then the clock; past idle_ns since the last work (or at
 * fp_worker_destroy) it parks; past yield_ns since the last yield (0: at every poll) it
 * calls sched_yield. It parks only when no wake came since the last it served: a wake
 * while it polls makes it poll once more after its idle time, unless the poll said it
 * served that wake (fp_worker_served: the contact guard's jobs are numbered by their wakes).
 *
 * Threads: create, wake and destroy from the owner's thread; spec's callbacks run on the
 * worker. The thread starts with the caller's signal mask (block signals around create to
 * keep them off it). Errors: negative errno. Link: fp_worker (core/common).
 */
#ifndef FP_WORKER_H
#define FP_WORKER_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct fp_worker fp_worker;

typedef struct fp_worker_spec {
    /** One poll, on the worker: claim and run the work there is; true when it ran some (the
     *  idle time starts again, the next poll comes at once). Required. */
    bool (*poll)(void *user, fp_worker *w);
    void *user;                    /* the callbacks' argument */
    int64_t idle_ns;               /* polls this long after its last work, then parks */
    int64_t yield_ns;              /* sched_yield between polls once this long since the
                                      last (0: after every poll) */
    int pauses;                    /* CPU pauses (fp_cpu_pause) between polls */
    /* optional, on the worker (NULL: nothing): */
    void (*enter)(void *user);     /* first, when the thread starts */
    void (*leave)(void *user);     /* last, before the thread ends */
    void (*awake)(void *user);     /* woken from parking, before its first poll */
    void (*asleep)(void *user);    /* its polling over, before it parks */
    void (*yielded)(void *user);   /* after each sched_yield */
} fp_worker_spec;

/** Start the thread, parked until the first wake (spec is copied). Returns 0, -ENOMEM or
 *  pthread's code negated (-EAGAIN: no thread could be made); *out owned by the caller. */
int fp_worker_create(const fp_worker_spec *spec, fp_worker **out);

/** Stop the thread (a poll in progress finishes; it is not woken for more) and join it;
 *  *w = NULL. NULL or *w NULL: nothing. */
void fp_worker_destroy(fp_worker **w);

/** Wake the worker (parked: it starts polling; polling: it polls once more before it
 *  parks, unless a poll serves this wake). publish (may be NULL) runs first, under the
 *  worker's lock, with the new wake's number: what the owner stores there is seen by the
 *  worker's next poll that reads fp_worker_wakes. Returns the wake's number (1, 2, ...). */
uint32_t fp_worker_wake(fp_worker *w, void (*publish)(void *arg, uint32_t wake), void *arg);

/** The number of the latest wake (acquire): for a poll. */
uint32_t fp_worker_wakes(fp_worker *w);

/** On the worker, in a poll: the wakes up to `wake` are served; the worker parks when its
 *  idle time is over and no later wake came. */
void fp_worker_served(fp_worker *w, uint32_t wake);

/** One CPU pause in a spin (x86 pause, Arm yield; nothing elsewhere). */
static inline void fp_cpu_pause(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

#ifdef __cplusplus
}
#endif
#endif
