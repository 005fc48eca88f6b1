/*
 * fp_plugin_crash.h: a fatal signal inside a plugin names the plugin before the process ends.
 *
 * The host brackets every call into a plugin with fp_plugin_call_enter/leave (thread-local,
 * no allocation, no lock: allowed on the session thread). A fatal signal (SIGSEGV, SIGBUS,
 * SIGFPE, SIGILL, SIGABRT) then prints one line to stderr, e.g.
 *   facepuppet: fatal signal SIGSEGV in plugin 'map-pinch' during process (frame 212)
 * and, for a crash on a thread a plugin owns (no call in progress), the plugin whose code was
 * running, found from the faulting instruction's address among the loaded plugins:
 *   facepuppet: fatal signal SIGSEGV in plugin /usr/lib/facepuppet/input-x.so (its own thread)
 * then restores the default action and re-raises, so the process ends as it would have
 * (exit status 128 + signal in a shell; a core dump where enabled). Takes and recordings
 * keep what their writer threads had flushed (core/take: all but the last chunk).
 *
 * Thread rules: install once from the main thread; enter/leave on any thread (each thread
 * has its own record, and its outermost call in progress is published for the others:
 * fp_plugin_call_oldest, which says what a stuck call is stuck in); register/unregister
 * [main-thread] (the loader calls them).
 */
#ifndef FP_PLUGIN_CRASH_H
#define FP_PLUGIN_CRASH_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Install the fatal-signal handlers (on an alternate stack, so a stack overflow is caught
 *  too). Returns 0 or a negative errno. Idempotent. */
int fp_plugin_crash_install(void);

/** The calling thread enters a call into plugin `who` (a name the user knows: the instance's
 *  SPEC name or file), `call` (a string literal: "create", "process", ...), at `frame`.
 *  The strings must outlive the call. Nests: only the innermost is reported. */
void fp_plugin_call_enter(const char *who, const char *call, uint64_t frame);
void fp_plugin_call_leave(void);

/** A plugin call in progress, seen from another thread (fp_plugin_call_oldest). */
typedef struct fp_plugin_call_info {
    const char *who;     /* as given to fp_plugin_call_enter (the innermost call's) */
    const char *call;
    uint64_t frame;
    int64_t since_ns;    /* when the outermost call began, CLOCK_MONOTONIC ns */
} fp_plugin_call_info;

/** The plugin call in progress that began first, on any thread (each thread's outermost
 *  call is published in one of 64 slots, claimed at enter and freed at leave; a thread that
 *  finds none free is not seen). For a watchdog: what a stuck thread is stuck in. Returns
 *  false when no call is in progress. The strings are the caller's of enter: they must live
 *  as long as whoever calls this may read them (the session's names live as long as it).
 *  [any thread; not async-signal-safe in principle, but takes no lock] */
bool fp_plugin_call_oldest(fp_plugin_call_info *out);

/** The loader records each loaded shared object's address range under its path, so a crash
 *  on a plugin's own thread can be attributed; unregister before dlclose. */
void fp_plugin_crash_register(void *dl_handle, const char *path);
void fp_plugin_crash_unregister(void *dl_handle);

#ifdef __cplusplus
}
#endif
#endif
