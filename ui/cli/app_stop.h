/*
 * app_stop.h: SIGINT and SIGTERM end a command's session cleanly, even with a plugin stuck
 * in a call that never returns (issue 56, item 3).
 *
 * The handler only records the signal and writes a byte to a pipe (async-signal-safe). The
 * command's frame loop sees fp_app_stop_requested() after the frame in progress and ends as
 * it always did (the take closed, the outputs written, its usual exit status). The frame in
 * progress is bracketed by fp_app_stop_step_begin/end; a watchdog thread, woken by the pipe,
 * watches it: when the frame has not ended FP_APP_STOP_GRACE_NS after the signal and a
 * plugin call has been in progress that long (fp_plugin_call_oldest: a process() that spins
 * forever), or FP_APP_STOP_STEP_LIMIT_NS after the signal whatever it is doing, the watchdog
 * takes the frame loop's place (an atomic claim: the loop, should its frame end after all,
 * waits in fp_app_stop_step_end for the process to end), prints one line naming the plugin,
 * the call, its frame and how long it has run, calls the command's take-over function (which
 * closes the take and writes what it can: whatever the frame loop owns is the watchdog's
 * now, the session thread being inside the step) and ends the process with _exit(128 +
 * the signal) without joining the stuck thread: 130 for SIGINT, 143 for SIGTERM. An alarm
 * (FP_APP_STOP_TAKEOVER_S) ends the process with the same status should the take-over
 * itself hang. A second SIGINT or SIGTERM, a second or more after the first, ends the
 * process at once with 128 + that signal, writing nothing more (one sooner is taken for the
 * first's echo: timeout(1) signals the command, then its process group, which holds it).
 *
 * Threads: install, the step brackets, loop_end and uninstall from the command's main
 * thread (its frame loop); requested from any thread; the take-over function runs on the
 * watchdog thread (every signal blocked there). One command at a time per process.
 */
#ifndef FP_APP_STOP_H
#define FP_APP_STOP_H

#include <stdbool.h>
#include <stdint.h>

#define FP_APP_STOP_GRACE_NS 100000000LL      /* a plugin call this long after the signal */
#define FP_APP_STOP_STEP_LIMIT_NS 3000000000LL /* any frame this long after the signal */
#define FP_APP_STOP_TAKEOVER_S 3              /* the take-over's own limit */
#define FP_APP_STOP_REPEAT_NS 1000000000LL    /* a second signal sooner is the first's echo */

/** The take-over (on the watchdog thread): close the take and write what outputs it can
 *  from state the frame loop owns; in_plugin: the frame is stuck in a plugin call (the
 *  mesh's shown positions are those of the last whole frame), else somewhere else in the
 *  frame (better not read what it may be writing). Its return is followed by _exit. */
typedef void (*fp_app_stop_fn)(void *user, int sig, bool in_plugin);

/** Install the SIGINT and SIGTERM handlers and start the watchdog; cmd ("facepuppet run")
 *  prefixes its lines (a string that outlives uninstall). Returns 0 or a negative errno
 *  (pipe, pthread_create): then the handlers are installed without the watchdog (the loop
 *  still ends after the frame in progress, a second signal at once). */
int fp_app_stop_install(const char *cmd, fp_app_stop_fn takeover, void *user);

/** Whether SIGINT or SIGTERM came since install; the signal's number, or 0. */
bool fp_app_stop_requested(void);
int fp_app_stop_signal(void);

/** The frame loop enters a frame (before fp_session_step) and leaves it (after). When the
 *  watchdog took the frame over meanwhile, step_end does not return: the process ends on
 *  the watchdog's thread. Without install: nothing. */
void fp_app_stop_step_begin(void);
void fp_app_stop_step_end(void);

/** The frame loop is over: the watchdog stands down (the command ends on its own; a second
 *  signal still ends it at once). */
void fp_app_stop_loop_end(void);

/** Stop and join the watchdog, restore the default handlers. Without install: nothing. */
void fp_app_stop_uninstall(void);

#endif
