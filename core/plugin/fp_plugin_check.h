/*
 * fp_plugin_check.h: a validator for plugins, in the spirit of clap-validator
 * (`facepuppet plugins check FILE.so`). It loads one plugin file and exercises it through
 * plugin.h only, as the host would, and harder:
 *
 *  every plugin: the ABI and the factory (the loader's checks), create with the defaults,
 *    with every declared key set to its default, with an unknown key (must be refused with a
 *    message naming the key), with each INT/FLOAT/ENUM/BOOL key of its fp_param_info out of
 *    range (must be refused), create returning 0 without an instance (a failure);
 *  a mapping: a frame sequence over a small synthetic surface (a 9 x 9 grid, 2 units wide)
 *    with no hands, one hand far and touching, both hands touching, engage/commit/cancel
 *    requests and pedal events, edge poses without NaN (joints all at one point, a tip on a
 *    vertex, a hand 1e4 units away, at the bounds' corner), once without and once with a rig
 *    view; for a plugin of ABI 1.3 on, each half then has 40 frames with 1 and
 *    FP_PERFORMER_CAPACITY - 1 further performers (extra_hands far, touching, at the edge
 *    poses, gone; their tip distances as the session gives them; the rows past the frame's
 *    FP_HANDS x extra_performers are present hands with NaN joints, so that a read past them
 *    shows as a non-finite point), a plugin before 1.3 an INFO line instead (it cannot read
 *    them); after each process(): the return code, count <= capacity, channel_count <=
 *    channel_capacity, canaries after the host's start, end and channel arrays untouched,
 *    finite start and end points, radius > 0 and finite when active, extra_hands and
 *    extra_tip_distance unchanged (the host's, const), the call's time against the budget
 *    (the lower of two runs per frame, so a preemption does not fail it);
 *    then reset and the same sequence again: identical control sets (determinism); destroy;
 *  an input: `cycles` times create, start, 100 ms of events, stop, destroy; every event
 *    well-formed (size for its type, type, hand, finite values, unit quaternion, button
 *    bits, NUL-terminated status text) and none pushed after stop returned. A create or
 *    start failing with -ENOENT, -ENODEV, -EACCES, -EBUSY, -ENXIO and a message is a
 *    documented skip ("needs a device"), not a failure.
 *
 * The guard (fp_plugin_check): all of it, from the load on, runs in a child process (fork)
 * whose end the caller's process judges. The child tells the parent of each call into the
 * plugin before it is made (the call and the frame: the progress) and sends every finding
 * and at last its verdict through a pipe; a child that dies of a signal, ends (exit() in the
 * plugin) without a verdict, or makes no progress for `deadline_s`, is a failure naming the
 * signal, the exit status or the hang, and the call and frame it was in; what is left of it
 * is killed (SIGKILL) and reaped. The child's stdout is the caller's stderr: a plugin that
 * prints does not mix its text into the findings the caller prints.
 *
 * Threads: [main-thread], with no other thread running (it forks); calls into the plugin are
 * bracketed (fp_plugin_crash.h), so a crash in one also names the plugin and the call on
 * stderr (the crash handler, where the caller installed it).
 */
#ifndef FP_PLUGIN_CHECK_H
#define FP_PLUGIN_CHECK_H

#include "fp_plugin_host.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum fp_check_level {
    FP_CHECK_PASS = 0,
    FP_CHECK_FAIL = 1,
    FP_CHECK_SKIP = 2,
    FP_CHECK_INFO = 3
} fp_check_level;

typedef struct fp_check_options {
    const char *arg;          /* an input's ARG (e.g. a recording), NULL where none */
    const fp_param *params;   /* keys added to every create (e.g. fast=1), may be NULL */
    size_t nparams;
    double budget_ms;         /* a mapping's process() budget; 0: 2 ms */
    int cycles;               /* an input's create/start/stop/destroy cycles; 0: 5 */
    bool isolate;             /* a mapping whose sequence passed: the first pass again with it
                                 in a helper process (fp_isolate.h), its control sets compared
                                 frame for frame ("isolated"; the further performers' frames
                                 too) */
    const char *helper;       /* the helper's executable; NULL: /proc/self/exe */
    double deadline_s;        /* the guard: the longest a call into the plugin may go without
                                 progress (s); 0: FP_CHECK_DEADLINE_S */
} fp_check_options;

#define FP_CHECK_DEADLINE_S 10.0

/** What the check found, besides the lines it reported. */
typedef struct fp_check_summary {
    fp_plugin_kind kind;
    char id[128], version[64], name[64];
    unsigned passed, failed, skipped;
    size_t frames;            /* mapping: process() calls timed */
    double median_us, max_us; /* mapping: per-frame process() time (lower of the two runs) */
    size_t events;            /* input: events checked */
} fp_check_summary;

/** Called for each finding: level, the check's short name ("create", "unknown key",
 *  "process", "determinism", "cycle", "events"...) and a message naming the cause. */
typedef void (*fp_check_fn)(void *user, fp_check_level level, const char *check,
                            const char *message);

/** Told of each call into the plugin before it is made: `call` ("load", "create",
 *  "process", "reset", "destroy", "start", "stop", "create in a helper process"; a string
 *  literal) and the synthetic frame (0 where none). */
typedef void (*fp_check_progress_fn)(void *user, const char *call, uint64_t frame);

/** Check the plugin in `file` (a path; its kind from its name input-*.so / map-*.so, else
 *  whichever factory it offers) in a child process, guarded (above): fn is called in the
 *  caller's process, in order, for each finding the child made, then for the failure of a
 *  child that crashed, exited without a verdict or hung (check: the call it was in, e.g.
 *  "process"; message: "died of SIGSEGV during process (frame 3) ..."). Returns 0 when
 *  every check passed or was skipped, FP_EPLUGIN_FAULT when one failed (the guard's
 *  included; err "FILE: N check(s) failed"), the loader's FP_EPLUGIN_* code (message in
 *  err) when it cannot be loaded at all, or a negative errno when no child could be
 *  started (pipe, fork). summary: the child's, its counts those fn was called with. opt may
 *  be NULL (defaults). [main-thread, no other thread running] */
int fp_plugin_check(const char *file, const fp_check_options *opt, fp_check_fn fn, void *user,
                    fp_check_summary *summary, char *err, size_t errlen);

/** The same checks in the calling process, unguarded (what the guard's child runs): a
 *  plugin that crashes, exits or hangs takes the caller with it. progress (may be NULL) is
 *  called before each call into the plugin. Returns as fp_plugin_check. [main-thread] */
int fp_plugin_check_direct(const char *file, const fp_check_options *opt, fp_check_fn fn, void *user,
                           fp_check_progress_fn progress, void *progress_user,
                           fp_check_summary *summary, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
