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
 * has its own record); register/unregister [main-thread] (the loader calls them).
 */
#ifndef FP_PLUGIN_CRASH_H
#define FP_PLUGIN_CRASH_H

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

/** The loader records each loaded shared object's address range under its path, so a crash
 *  on a plugin's own thread can be attributed; unregister before dlclose. */
void fp_plugin_crash_register(void *dl_handle, const char *path);
void fp_plugin_crash_unregister(void *dl_handle);

#ifdef __cplusplus
}
#endif
#endif
