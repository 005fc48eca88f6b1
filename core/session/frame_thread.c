/* The session's frame thread (frame_thread.h). */
#define _GNU_SOURCE /* sched_yield, pthread_sigmask */
#include "frame_thread.h"

#include "fp_clock.h"
#include "fp_worker.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct fp_frame_thread {
    fp_worker *w;                 /* the thread: spins, then parks (fp_worker.h) */
    atomic_bool polling;          /* the thread polls for calls (not asleep) */
    atomic_int cpu;               /* the CPU it polled or ran on last (sched_getcpu) */
    /* a call's number: posted by the caller, then claimed (taken) by one thread, which sets
     * done when it ran there; fn and arg are written before posted is */
    atomic_uint posted, taken, done;
    void (*fn)(void *);
    void *arg;
    unsigned long there, here;    /* the caller's counts */
    char alt[64 * 1024];          /* its signal stack (a crash handler's, fp_plugin_crash.h) */
};

/* written, so that the first frames do not fault its pages in */
static void touch_stack(void)
{
    volatile char pad[256 * 1024];
    for (size_t i = 0; i < sizeof pad; i += 4096) pad[i] = 0;
}

/* The polling's rhythm: the flags are read in a spin of pauses, and the core is offered to
 * other threads (sched_yield) every FP_FRAME_THREAD_YIELD_NS: a yield is a system call (1 to
 * several us on a VM), so a thread that yielded at every read noticed a call or its end
 * that much later. */
#define FP_FRAME_THREAD_YIELD_NS 20000

/* The worker's hooks (fp_worker.h): first, it writes its stack and handles a fatal signal in a
 * frame (a mapping plugin's crash) as on the caller's thread: on a stack of its own, so that
 * an overflow is named too; last, that stack is left (its memory is freed after the join) */
static void enter(void *u)
{
    fp_frame_thread *ft = u;
    touch_stack();
    stack_t ss = {.ss_sp = ft->alt, .ss_size = sizeof ft->alt, .ss_flags = 0};
    sigaltstack(&ss, NULL);
}

static void leave(void *u)
{
    fp_frame_thread *ft = u;
    stack_t ss = {.ss_sp = ft->alt, .ss_size = sizeof ft->alt, .ss_flags = SS_DISABLE};
    sigaltstack(&ss, NULL);
}

/* woken: it polls, on this CPU */
static void awake(void *u)
{
    fp_frame_thread *ft = u;
    atomic_store(&ft->cpu, sched_getcpu());
    atomic_store(&ft->polling, true);
}

/* a call posted from here on is not claimed here: its caller's grace runs out */
static void asleep(void *u)
{
    fp_frame_thread *ft = u;
    atomic_store(&ft->polling, false);
}

static void yielded(void *u)
{
    fp_frame_thread *ft = u;
    atomic_store(&ft->cpu, sched_getcpu());
}

/* One poll: the call posted, claimed and run here. Taken is read first: then posted is
 * taken or the one after it (a call is posted only when the last was claimed and done).
 * Read the other way round, a posted value read before the caller claimed it and posted the
 * next could be "claimed" over the next one's claim, and the call run twice
 * (ThreadSanitizer and test_frame_thread saw it). */
static bool poll_call(void *u, fp_worker *w)
{
    (void)w;
    fp_frame_thread *ft = u;
    for (;;) {
        unsigned t = atomic_load(&ft->taken), p = atomic_load(&ft->posted);
        if (p != t + 1) return false;
        if (atomic_compare_exchange_strong(&ft->taken, &t, p)) {
            atomic_store(&ft->cpu, sched_getcpu());
            ft->fn(ft->arg);
            atomic_store(&ft->done, p);
            return true;
        }
    }
}

int fp_frame_thread_create(fp_frame_thread **out)
{
    *out = NULL;
    fp_frame_thread *ft = calloc(1, sizeof *ft);
    if (!ft) return -ENOMEM;
    atomic_init(&ft->polling, false);
    atomic_init(&ft->cpu, -1);
    atomic_init(&ft->posted, 0);
    atomic_init(&ft->taken, 0);
    atomic_init(&ft->done, 0);
    /* the polling's rhythm: the flags read in a spin of pauses, the core offered to other
     * threads every FP_FRAME_THREAD_YIELD_NS */
    const fp_worker_spec spec = {.poll = poll_call, .user = ft, .idle_ns = FP_FRAME_THREAD_IDLE_NS,
                                 .yield_ns = FP_FRAME_THREAD_YIELD_NS, .pauses = 64, .enter = enter,
                                 .leave = leave, .awake = awake, .asleep = asleep, .yielded = yielded};
    /* the thread starts with every signal blocked but the synchronous ones, which a blocked
     * mask would turn into a plain kill, past the crash handler */
    sigset_t all, old;
    sigfillset(&all);
    static const int fatal[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS};
    for (size_t i = 0; i < sizeof fatal / sizeof fatal[0]; i++) sigdelset(&all, fatal[i]);
    pthread_sigmask(SIG_BLOCK, &all, &old);
    int rc = fp_worker_create(&spec, &ft->w);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    if (rc) {
        free(ft);
        return rc;
    }
    *out = ft;
    return 0;
}

void fp_frame_thread_destroy(fp_frame_thread **p)
{
    fp_frame_thread *ft = p ? *p : NULL;
    if (!ft) return;
    fp_worker_destroy(&ft->w);
    free(ft);
    *p = NULL;
}

int fp_frame_thread_run(fp_frame_thread *ft, void (*fn)(void *), void *arg, int64_t grace_ns)
{
    if (!ft) {
        fn(arg);
        return 0;
    }
    if (atomic_load(&ft->polling)) {
        unsigned seq = atomic_load(&ft->posted) + 1; /* (only this thread posts) */
        ft->fn = fn;
        ft->arg = arg;
        atomic_store(&ft->posted, seq);
        int64_t t0 = fp_now_ns();
        /* the waits spin, but yield when the thread was last on this CPU (this thread's
         * wake-up may have taken its core) */
        for (;;) { /* claimed there, or here once the grace is over */
            unsigned t = atomic_load(&ft->taken);
            if (t == seq) break;
            if (fp_now_ns() - t0 > grace_ns && atomic_compare_exchange_strong(&ft->taken, &t, seq)) {
                fn(arg);
                ft->here++;
                return 0;
            }
            if (atomic_load(&ft->cpu) == sched_getcpu()) sched_yield();
            else fp_cpu_pause();
        }
        /* a long call (a large face's frame, a plugin that never returns): past
         * FP_FRAME_THREAD_NAP_AFTER_NS the caller naps between looks, its core given back
         * (to the watchdog that ends a run with a plugin stuck: ui/cli/app_stop.h) */
        bool napping = false;
        for (unsigned n = 1; atomic_load(&ft->done) != seq; n++) {
            if (napping) {
                /* a hundredth of the wait so far, at most FP_FRAME_THREAD_NAP_MAX_NS */
                int64_t ns = (fp_now_ns() - t0) / 100;
                struct timespec nap = {0, ns < FP_FRAME_THREAD_NAP_MAX_NS ? (long)ns : FP_FRAME_THREAD_NAP_MAX_NS};
                nanosleep(&nap, NULL);
            } else if (!(n & 1023) && fp_now_ns() - t0 > FP_FRAME_THREAD_NAP_AFTER_NS) {
                napping = true;
            } else if (atomic_load(&ft->cpu) == sched_getcpu()) {
                sched_yield();
            } else {
                fp_cpu_pause();
            }
        }
        ft->there++;
        return 1;
    }
    fn(arg);
    ft->here++;
    fp_worker_wake(ft->w, NULL, NULL); /* it polls for the next calls */
    return 0;
}

void fp_frame_thread_counts(const fp_frame_thread *ft, unsigned long *there, unsigned long *here)
{
    *there = ft ? ft->there : 0;
    *here = ft ? ft->here : 0;
}
