/* The session's frame thread (frame_thread.h). */
#define _GNU_SOURCE /* sched_yield, pthread_sigmask */
#include "frame_thread.h"

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
    pthread_t th;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool wake, quit;              /* under mu */
    atomic_bool polling;          /* the thread polls for calls (not asleep) */
    atomic_bool stop;             /* quit, for the polling */
    atomic_int cpu;               /* the CPU it polled or ran on last (sched_getcpu) */
    /* a call's number: posted by the caller, then claimed (taken) by one thread, which sets
     * done when it ran there; fn and arg are written before posted is */
    atomic_uint posted, taken, done;
    void (*fn)(void *);
    void *arg;
    unsigned long there, here;    /* the caller's counts */
    char alt[64 * 1024];          /* its signal stack (a crash handler's, fp_plugin_crash.h) */
};

static int64_t now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000LL + t.tv_nsec;
}

/* written, so that the first frames do not fault its pages in */
static void touch_stack(void)
{
    volatile char pad[256 * 1024];
    for (size_t i = 0; i < sizeof pad; i += 4096) pad[i] = 0;
}

static inline void cpu_pause(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

/* The polling's rhythm: the flags are read in a spin of pauses, and the core is offered to
 * other threads (sched_yield) every FP_FRAME_THREAD_YIELD_NS: a yield is a system call (1 to
 * several us on a VM), so a thread that yielded at every read noticed a call or its end
 * that much later. */
#define FP_FRAME_THREAD_YIELD_NS 20000

static void *thread_main(void *u)
{
    fp_frame_thread *ft = u;
    touch_stack();
    /* a fatal signal in a frame (a mapping plugin's crash) is handled as on the caller's
     * thread: on a stack of its own, so that an overflow is named too */
    stack_t ss = {.ss_sp = ft->alt, .ss_size = sizeof ft->alt, .ss_flags = 0};
    sigaltstack(&ss, NULL);
    for (;;) {
        pthread_mutex_lock(&ft->mu);
        while (!ft->wake && !ft->quit) pthread_cond_wait(&ft->cv, &ft->mu);
        ft->wake = false;
        bool quit = ft->quit;
        pthread_mutex_unlock(&ft->mu);
        if (quit) {
            ss.ss_flags = SS_DISABLE; /* (its memory is freed after the join) */
            sigaltstack(&ss, NULL);
            return NULL;
        }
        atomic_store(&ft->cpu, sched_getcpu());
        atomic_store(&ft->polling, true);
        for (int64_t idle = now_ns(), yielded = idle;;) {
            /* taken first: then posted is taken or the one after it (a call is posted only
             * when the last was claimed and done). Read the other way round, a posted value
             * read before the caller claimed it and posted the next could be "claimed" over
             * the next one's claim, and the call run twice (ThreadSanitizer and
             * test_frame_thread saw it) */
            unsigned t = atomic_load(&ft->taken), p = atomic_load(&ft->posted);
            if (p == t + 1) {
                if (atomic_compare_exchange_strong(&ft->taken, &t, p)) {
                    atomic_store(&ft->cpu, sched_getcpu());
                    ft->fn(ft->arg);
                    atomic_store(&ft->done, p);
                    idle = yielded = now_ns();
                }
                continue;
            }
            for (int i = 0; i < 64; i++) cpu_pause();
            int64_t t1 = now_ns();
            if (t1 - idle > FP_FRAME_THREAD_IDLE_NS || atomic_load(&ft->stop)) break;
            if (t1 - yielded > FP_FRAME_THREAD_YIELD_NS) {
                sched_yield();
                atomic_store(&ft->cpu, sched_getcpu());
                yielded = t1;
            }
        }
        /* a call posted from here on is not claimed here: its caller's grace runs out */
        atomic_store(&ft->polling, false);
    }
}

int fp_frame_thread_create(fp_frame_thread **out)
{
    *out = NULL;
    fp_frame_thread *ft = calloc(1, sizeof *ft);
    if (!ft) return -ENOMEM;
    atomic_init(&ft->polling, false);
    atomic_init(&ft->stop, false);
    atomic_init(&ft->cpu, -1);
    atomic_init(&ft->posted, 0);
    atomic_init(&ft->taken, 0);
    atomic_init(&ft->done, 0);
    int rc = pthread_mutex_init(&ft->mu, NULL);
    if (rc) {
        free(ft);
        return -rc;
    }
    if ((rc = pthread_cond_init(&ft->cv, NULL))) {
        pthread_mutex_destroy(&ft->mu);
        free(ft);
        return -rc;
    }
    /* the thread starts with every signal blocked but the synchronous ones, which a blocked
     * mask would turn into a plain kill, past the crash handler */
    sigset_t all, old;
    sigfillset(&all);
    static const int fatal[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS};
    for (size_t i = 0; i < sizeof fatal / sizeof fatal[0]; i++) sigdelset(&all, fatal[i]);
    pthread_sigmask(SIG_BLOCK, &all, &old);
    rc = pthread_create(&ft->th, NULL, thread_main, ft);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    if (rc) {
        pthread_cond_destroy(&ft->cv);
        pthread_mutex_destroy(&ft->mu);
        free(ft);
        return -rc;
    }
    *out = ft;
    return 0;
}

void fp_frame_thread_destroy(fp_frame_thread **p)
{
    fp_frame_thread *ft = p ? *p : NULL;
    if (!ft) return;
    atomic_store(&ft->stop, true);
    pthread_mutex_lock(&ft->mu);
    ft->quit = true;
    pthread_cond_signal(&ft->cv);
    pthread_mutex_unlock(&ft->mu);
    pthread_join(ft->th, NULL);
    pthread_cond_destroy(&ft->cv);
    pthread_mutex_destroy(&ft->mu);
    free(ft);
    *p = NULL;
}

/* the thread polls for the next calls (it sleeps: woken; it polls: nothing) */
static void wake(fp_frame_thread *ft)
{
    pthread_mutex_lock(&ft->mu);
    ft->wake = true;
    pthread_cond_signal(&ft->cv);
    pthread_mutex_unlock(&ft->mu);
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
        int64_t t0 = now_ns();
        /* the waits spin, but yield when the thread was last on this CPU (this thread's
         * wake-up may have taken its core) */
        for (;;) { /* claimed there, or here once the grace is over */
            unsigned t = atomic_load(&ft->taken);
            if (t == seq) break;
            if (now_ns() - t0 > grace_ns && atomic_compare_exchange_strong(&ft->taken, &t, seq)) {
                fn(arg);
                ft->here++;
                return 0;
            }
            if (atomic_load(&ft->cpu) == sched_getcpu()) sched_yield();
            else cpu_pause();
        }
        while (atomic_load(&ft->done) != seq)
            if (atomic_load(&ft->cpu) == sched_getcpu()) sched_yield();
            else cpu_pause();
        ft->there++;
        return 1;
    }
    fn(arg);
    ft->here++;
    wake(ft); /* for the next calls */
    return 0;
}

void fp_frame_thread_counts(const fp_frame_thread *ft, unsigned long *there, unsigned long *here)
{
    *there = ft ? ft->there : 0;
    *here = ft ? ft->here : 0;
}
