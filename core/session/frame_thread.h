/*
 * frame_thread.h: the session's frame thread (issue 18): a thread that stays on its core
 * between frames during a performance and runs each frame while the caller waits.
 *
 * Why. A thread that sleeps between frames wakes with its caches cold: on the 2-core VM, a
 * pointer chase over 100-600 KiB after 16 ms asleep ran at 48-72 ns a line, against 19-44
 * for a thread that polled (sched_yield) meanwhile (and data another core had just read
 * came no faster than memory), and the ICT frame, whose data fit in one core's L2, ran at
 * 0.12-0.14 ms median stepped by a sleeping loop (the bench's, the viewer's behind its
 * vsync) against 0.06-0.10 on a thread that polled. The caller's loop should not have to
 * spin for that: the frame runs on this thread instead, which polls (yielding its core)
 * for FP_FRAME_THREAD_IDLE_NS after each frame, then sleeps until the next one. Measured
 * (`bench --case frame`, 27 runs alternated with the build before it): the ICT frame's
 * median 0.088 ms (median of the runs; lower in 20 of the 27) against 0.126, its p99
 * unchanged (0.295 against 0.293). Its cost: one core polled through a performance, as the
 * contact guard's worker (fp_contact.h) does after each step; with both polling, the caller's
 * loop waits longer to be woken (the bench's "waiting for a CPU", p99 0.04-0.41 ms against
 * 0.01-0.08 in one batch), a delay before the frame, not in it. A sleeping frame thread
 * costs nothing.
 *
 * How. The thread is an fp_worker (core/common/fp_worker.h, as the contact guard's worker):
 * it spins, then parks. fp_frame_thread_run posts the call and waits for it (yielding, then
 * napping past FP_FRAME_THREAD_NAP_AFTER_NS: a call that never returns, a plugin's that
 * spins, must not hold the caller's core too, which the watchdog of `run` needs); the
 * thread claims it within about a microsecond when it polls. When it sleeps (no frame for
 * FP_FRAME_THREAD_IDLE_NS), or has not claimed the call within the grace (the system holds it
 * off its core), the caller claims the call and runs it itself, then wakes the thread for
 * the next ones. A call is run once, by one thread, and its effects are visible to the
 * caller when run returns (the claim and the end are atomic release/acquire): to the code
 * run, the two threads are one thread taking turns.
 *
 * Threads: create, destroy and run from one thread (the caller's); fn runs on either thread,
 * never two calls at once. The thread blocks every signal but the synchronous fatal ones
 * (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS: the others go to the process's
 * other threads), and handles those on a signal stack of its own, so a plugin's crash in a
 * frame is named by fp_plugin_crash.h as on the caller's thread. Errors: negative errno.
 */
#ifndef FP_FRAME_THREAD_H
#define FP_FRAME_THREAD_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_FRAME_THREAD_IDLE_NS 20000000 /* polls this long after a frame, then sleeps */
#define FP_FRAME_THREAD_GRACE_NS 20000   /* the caller runs a call not claimed within this */
/* the caller waits for a call's end spinning, then, past this, naps between looks: a
 * hundredth of the wait so far, at most FP_FRAME_THREAD_NAP_MAX_NS (a long frame ends at
 * most 1% later to the caller; a stuck one costs no core) */
#define FP_FRAME_THREAD_NAP_AFTER_NS 20000000
#define FP_FRAME_THREAD_NAP_MAX_NS 1000000

typedef struct fp_frame_thread fp_frame_thread;

/** Start the thread, asleep until the first call; it writes 256 KiB of its stack first (no
 *  page fault in a frame). Returns 0, -ENOMEM, or pthread_create's code negated (-EAGAIN);
 *  *out owned by the caller (fp_frame_thread_destroy). */
int fp_frame_thread_create(fp_frame_thread **out);

/** Stop and join the thread (it finishes nothing: no call is in progress between runs);
 *  *ft = NULL. NULL or *ft NULL: nothing. */
void fp_frame_thread_destroy(fp_frame_thread **ft);

/** Call fn(arg) on the frame thread when it polls and claims the call within grace_ns
 *  (FP_FRAME_THREAD_GRACE_NS; a test may give more), else on the caller's; returns when fn
 *  has returned, 1 when it ran on the frame thread, 0 on the caller's. ft NULL: fn runs on
 *  the caller's. */
int fp_frame_thread_run(fp_frame_thread *ft, void (*fn)(void *), void *arg, int64_t grace_ns);

/** How many calls ran on the frame thread (there) and on the caller's (here) so far. */
void fp_frame_thread_counts(const fp_frame_thread *ft, unsigned long *there, unsigned long *here);

#ifdef __cplusplus
}
#endif
#endif
