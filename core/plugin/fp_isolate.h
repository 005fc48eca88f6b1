/*
 * fp_isolate.h: a mapping plugin in a helper process (issue 56). The host gets an fp_mapping
 * whose process(), reset() and destroy() forward to the plugin running in `facepuppet
 * __plugin-helper` (the same executable: nothing else is installed); the caller (the
 * session) calls it as any mapping. Each frame the frame input (hands, events, the mesh's
 * base, the rig) and the control set are copied through shared memory (memfd + mmap) with an
 * eventfd wake-up each way; the host's surface service (FP_HOST_EXT_SURFACE) is answered
 * during the call, the rig (FP_HOST_EXT_RIG) is copied, and the plugin's log lines come back
 * through the host's fp_host.log. Same calls in the same order, same control sets: a built-in
 * mapping gives bit-identical meshes isolated or not (tests/plugin/test_isolate.sh).
 *
 * The watchdog: a call that has not answered within the deadline, or a helper that died (any
 * signal, any exit), is a fault. The call returns at once with the last good control set
 * held (good: process returned >= 0 and the set passed the session's rule, fp_control_check.h,
 * so a set the session refused is never shown later; without its intents; an inactive set
 * where it committed), the fault is reported once
 * through fp_host.log naming the plugin, the call, the frame and the cause, the helper is
 * killed (SIGKILL) and reaped, and a new one is started in the background at the next frame,
 * created anew with the same keys; it serves from the first frame whose time
 * (fp_frame_input.time_ns: the frames' clock, not the wall's) is a back-off after the fault's
 * (FP_ISOLATE_BACKOFF_MS, doubling per fault in a row, at most FP_ISOLATE_BACKOFF_MAX_MS),
 * and that frame waits for it to be ready (at most FP_ISOLATE_CREATE_MS from its start; past
 * that it is a fault), so a run gives the same frames whatever its speed (fast=1, --speed,
 * real time) or the machine's; the frames meanwhile hold the set. After
 * FP_ISOLATE_MAX_FAULTS faults in a row (a helper that answered FP_ISOLATE_HEALTHY_CALLS
 * calls ends a row) it gives up: one error line, and every later call returns, with code 0,
 * the set held as while a helper restarts (the last good one without its intents; inactive
 * where it committed or was inactive), so the face stays as it was and the session runs on.
 *
 * Errors: as the in-process loader and factory (fp_plugin_load's FP_EPLUGIN_* codes, the
 * factory's own code with its message), plus the host's: -ENOMEM, -EIO (no helper could be
 * started), FP_EPLUGIN_FAULT (the helper died or hung during create).
 *
 * Threads: create and destroy [main-thread]; process and reset on the session's thread, one
 * call at a time (plugin.h's [session-thread]); they never block longer than the deadline,
 * except the frame a restart is due on, which waits for the new helper's create (above).
 */
#ifndef FP_ISOLATE_H
#define FP_ISOLATE_H

#include "fp_plugin_host.h"

#include <facepuppet/plugin.h>
#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Which mappings run in a helper: none (all in process), those not found in facepuppet's
 *  own plugin folder (the default of `run`, `live` and `plugins check`), or all. */
typedef enum fp_isolate_mode {
    FP_ISOLATE_NONE = 0,
    FP_ISOLATE_THIRD_PARTY = 1,
    FP_ISOLATE_ALL = 2
} fp_isolate_mode;

#define FP_ISOLATE_DEADLINE_MS 50.0     /* default deadline of one call (3 frames at 60 Hz) */
#define FP_ISOLATE_CREATE_MS 10000.0    /* the helper's load and create */
#define FP_ISOLATE_BACKOFF_MS 100.0     /* the first restart's wait, on the frames' clock */
#define FP_ISOLATE_BACKOFF_MAX_MS 2000.0
#define FP_ISOLATE_MAX_FAULTS 5         /* faults in a row before giving up */
#define FP_ISOLATE_HEALTHY_CALLS 60     /* calls answered that end a row of faults (1 s at 60 Hz) */

/** The first argument of the helper mode: `facepuppet __plugin-helper ...`. */
#define FP_ISOLATE_HELPER_ARG "__plugin-helper"

/** "none", "third-party" or "all" into *out; -EINVAL for anything else. */
int fp_isolate_mode_parse(const char *text, fp_isolate_mode *out);
/** The mode's name as parsed. */
const char *fp_isolate_mode_name(fp_isolate_mode mode);

/** Whether the plugin at `file` (found on `path`, fp_plugin_find) runs in a helper under
 *  `mode`: never for NONE, always for ALL; for THIRD_PARTY, unless `builtin` (one of
 *  facepuppet's own, found in the path's built-in folder: fp_plugin_find). */
bool fp_isolate_wanted(fp_isolate_mode mode, bool builtin);

typedef struct fp_isolate_options {
    const char *helper;        /* the executable run as the helper; NULL: /proc/self/exe */
    double deadline_ms;        /* 0: FP_ISOLATE_DEADLINE_MS */
    bool quiet_restarts;       /* true: no info line when a helper is back */
    bool never_wait;           /* true (live, on the wall clock): a restart never blocks a
                                  frame; a new helper not ready at its due frame is asked again
                                  each frame, the last set held, until the create's deadline.
                                  false (run, on the recording's clock): the due frame waits
                                  for it, so that every speed gives the same frames */
} fp_isolate_options;

/** Start a helper that loads the mapping plugin `file` (an absolute or relative path; the
 *  caller resolved it), calls its init, and creates an instance with `params` (the SPEC's
 *  keys); `name` (the SPEC's NAME) names it in messages. `host` is the fp_host the plugin
 *  would have had in process (its log, FP_HOST_EXT_SURFACE and FP_HOST_EXT_RIG are used);
 *  it must outlive the instance. On success *out is the proxy (free it with its destroy,
 *  which ends the helper). On failure, the plugin's message or the loader's in err (not naming
 *  the mapping: the caller does; a helper that died or hung says whether while loading the
 *  file or in the plugin's create), and
 *  the code (above): FP_EPLUGIN_DLOPEN, before any helper, where `file` is not a regular file
 *  (opened without blocking: a FIFO is refused, never waited on). [main-thread] */
int fp_isolate_mapping_create(const fp_isolate_options *opt, const char *file, const char *name,
                              const fp_host *host, const fp_param *params, size_t nparams,
                              fp_mapping **out, char *err, size_t errlen);

/** What a proxy has been through, for reports and tests: faults (deadlines missed, helpers
 *  dead), restarts done, frames held, whether it gave up, and the helper's pid (0: none).
 *  False where `m` is not an isolated mapping. [the session's thread] */
typedef struct fp_isolate_stats {
    unsigned long faults, restarts, held;
    bool gave_up;
    int pid;
} fp_isolate_stats;
bool fp_isolate_mapping_stats(const fp_mapping *m, fp_isolate_stats *out);

/** The plugin's entry id and version (fp_plugin_entry) as its helper loaded it: strings of
 *  the proxy, valid while it lives. False where `m` is not an isolated mapping. */
bool fp_isolate_mapping_about(const fp_mapping *m, const char **id, const char **version);

/* ---- isolated inputs ------------------------------------------------------------------
 * An input plugin in a helper process (`facepuppet __input-helper ...`): the host gets an
 * fp_input whose start, stop and destroy forward to the plugin there; every event the plugin
 * pushes (and every line it logs) crosses the helper's socket in order and is pushed, as it
 * was (its time_ns included), into the instance's own queue by a reader thread of the host's,
 * so the session sees the same events as in process. The extensions (FP_EXT_WORKSPACE,
 * FP_EXT_INPUT_CLOCK, FP_EXT_RECORDING_INFO, FP_EXT_RECORDING_JOINTS) are asked once in the
 * helper after create and answered from the copies.
 *
 * A helper that dies (any signal, any exit) while the input runs is a fault: its reader
 * pushes, after every event the plugin sent before, a status FP_STATUS_WARNING (hand -1) whose
 * text names the signal and what follows ("isolated: the helper process died of SIGSEGV;
 * hands released, restarts in 0.1 s (fault 1 in a row)": the session logs it under the input's
 * name and the take records it) and an FP_STATUS_DISCONNECTED with no text for each hand (so a
 * grab lets go, as an unplugged device's), then starts a new helper (create and start with the
 * same SPEC) after FP_ISOLATE_BACKOFF_MS on the wall clock, doubling per fault in a row up to
 * FP_ISOLATE_BACKOFF_MAX_MS; a helper that served FP_ISOLATE_INPUT_HEALTHY_MS ends a row.
 * After FP_ISOLATE_MAX_FAULTS in a row, or at the first fault of an input on a recording's
 * clock (a recording started again would repeat its times), it gives up: an
 * FP_STATUS_END_OF_STREAM follows, and the session goes on without the input. A stop that has
 * not returned within FP_ISOLATE_INPUT_STOP_MS kills the helper (nothing is abandoned). */
#define FP_ISOLATE_INPUT_HEALTHY_MS 1000.0
#define FP_ISOLATE_INPUT_STOP_MS 4000.0    /* under the host's own FP_INPUT_STOP_DEADLINE_MS */
#define FP_ISOLATE_INPUT_HELPER_ARG "__input-helper"

/** Start a helper that loads the input plugin `file` and creates an instance with `arg` (the
 *  SPEC's ARG; NULL: none) and `params`; `name` names it. `host` is the instance's fp_host
 *  (its push_event and log are used, from the caller's thread during create and start, from
 *  the reader thread after); it must outlive the instance. On success *out is the proxy:
 *  call its start, stop and destroy as an input's. On failure the plugin's message or the
 *  helper's fate in err (not naming the input: the caller does) and the code, as
 *  fp_isolate_mapping_create's. [main-thread] */
int fp_isolate_input_create(const fp_isolate_options *opt, const char *file, const char *name,
                            const fp_host *host, const char *arg, const fp_param *params, size_t nparams,
                            fp_input **out, char *err, size_t errlen);

/** Faults and restarts of an isolated input so far (gave_up: it ended its stream). False
 *  where `in` is not an isolated input. [any-thread] */
bool fp_isolate_input_stats(const fp_input *in, fp_isolate_stats *out);

/** The input helper's main: argv[1] is FP_ISOLATE_INPUT_HELPER_ARG (as fp_isolate_helper_main). */
int fp_isolate_input_helper_main(int argc, char **argv);

/** The helper's main: argv as the executable got it (argv[1] is FP_ISOLATE_HELPER_ARG).
 *  Returns the exit status (0 when the host asked it to quit or went away). Prints nothing:
 *  everything goes to the host; before the plugin is loaded its stdout is made its stderr
 *  (dup2), so what a plugin prints reaches the host's stderr, never the host's stdout. */
int fp_isolate_helper_main(int argc, char **argv);

#ifdef __cplusplus
}
#endif
#endif
