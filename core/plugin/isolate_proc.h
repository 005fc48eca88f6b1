/*
 * isolate_proc.h: one helper process of an isolated mapping, host side (internal to
 * core/plugin; fp_isolate.h is the interface). Spawns `EXE __plugin-helper ...` with the
 * shared memory (isolate_shm.h), its eventfds and its socket, waits for its create result,
 * makes one round trip with a deadline, and ends or kills it. No policy here: the restarts,
 * the held control set and the reports are isolate.c's.
 *
 * Threads: one thread at a time per fp_iso_proc.
 */
#ifndef FP_ISOLATE_PROC_H
#define FP_ISOLATE_PROC_H

#include "fp_isolate.h"
#include "isolate_shm.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

/* Outcomes of a wait besides 0 (answered) and a negative errno. */
#define FP_ISO_HUNG 1     /* the deadline passed */
#define FP_ISO_DIED 2     /* the helper hung up (it exited or was killed) */
#define FP_ISO_PENDING 3  /* no answer yet (a wait of 0 ms) */

typedef void (*fp_iso_log_fn)(void *user, int level, const char *message);
/** An isolated input's event as its helper sent it: `bytes` (at most sizeof(fp_event); the
 *  header's size as the plugin set it). */
typedef void (*fp_iso_event_fn)(void *user, const void *bytes, size_t n);

typedef struct fp_iso_proc {
    pid_t pid;               /* 0: none */
    int memfd, go, done, sock;
    fp_iso_shm *shm;
    size_t mapped;
    int64_t started_ns;
    bool ready;              /* its READY came */
    int ready_rc;            /* create's code */
    char ready_text[1000];   /* create's message */
    fp_iso_event_fn on_event; /* an input's events on the socket (NULL: dropped) */
    void *event_user;
} fp_iso_proc;

/** A zeroed process with every descriptor -1. */
void fp_iso_proc_init(fp_iso_proc *p);

/** Make the shared memory (at least `bytes`, with `offers`; `fill` writes into it before the
 *  helper starts, e.g. the rig for the plugin's create), the eventfds and the socket, and
 *  spawn `exe` in helper mode `mode` (FP_ISOLATE_HELPER_ARG, FP_ISOLATE_INPUT_HELPER_ARG) for
 *  the plugin `file` named `name` with `params`; file_fd
 *  (-1: none) is a descriptor the helper inherits (`file` may then be /proc/self/fd/N). Returns 0 or
 *  a negative errno (nothing is left open). Does not wait for the helper. */
int fp_iso_proc_spawn(fp_iso_proc *p, const char *exe, const char *mode, const char *file, int file_fd,
                      const char *name,
                      const fp_param *params, size_t nparams, size_t bytes, uint32_t offers,
                      void (*fill)(void *user, fp_iso_shm *shm), void *fill_user);

/** Grow the shared memory to `bytes` (rounded to pages); the helper maps the new size at its
 *  next request. 0 or a negative errno. */
int fp_iso_proc_reserve(fp_iso_proc *p, size_t bytes);

/** Wait up to timeout_ms for the helper's create result (p->ready_rc, p->ready_text); log
 *  lines that come meanwhile go to log_fn. Returns 0 (it came), FP_ISO_HUNG, FP_ISO_DIED. */
int fp_iso_proc_wait_ready(fp_iso_proc *p, double timeout_ms, fp_iso_log_fn log_fn, void *user);
/** The same without waiting: 0, FP_ISO_PENDING or FP_ISO_DIED. */
int fp_iso_proc_poll_ready(fp_iso_proc *p, fp_iso_log_fn log_fn, void *user);

/** One request `op` (the shared memory already written) and its answer within deadline_ms;
 *  a surface query of the helper's meanwhile is answered by surface(user, shm), which fills
 *  surf_hits and returns the code. Returns 0 (answered), FP_ISO_HUNG or FP_ISO_DIED. */
int fp_iso_proc_call(fp_iso_proc *p, uint32_t op, double deadline_ms,
                     int (*surface)(void *user, fp_iso_shm *shm), fp_iso_log_fn log_fn, void *user);

/** Hand the log lines waiting on the socket to log_fn (and an input's events to on_event).
 *  False when the helper hung up. */
bool fp_iso_proc_drain_log(fp_iso_proc *p, fp_iso_log_fn log_fn, void *user);

/** Map the shared memory again where the helper grew it (shm->size). 0 or a negative errno. */
int fp_iso_proc_follow(fp_iso_proc *p);

/** SIGKILL the helper unless it has exited, reap it, close everything. `why` (may be NULL)
 *  gets how it ended: "died of SIGSEGV", "exited with status 3". */
void fp_iso_proc_kill(fp_iso_proc *p, char *why, size_t whylen);

/** Ask the helper to quit (destroy, deinit), wait up to wait_ms for it, then kill. */
void fp_iso_proc_end(fp_iso_proc *p, double wait_ms, fp_iso_log_fn log_fn, void *user);

/** A copy of the keys in an fp_spec of the caller's (they must outlive the SPEC they came
 *  from; free with fp_spec_clear). 0 or -ENOMEM. */
int fp_iso_copy_keys(fp_spec *spec, const fp_param *params, size_t nparams);

/* The helpers' side (isolate_helper.c), shared by the input's (isolate_input_helper.c): a
 * descriptor from argv (-1: not one); oom_score_adj 1000, so that the kernel's OOM killer
 * takes the helper first. */
int fp_iso_helper_arg_fd(const char *s);
void fp_iso_helper_oom_first(void);
/** The SPEC's keys from argv[8..] ("KEY=VALUE", split in place; other words skipped) into
 *  params (at most FP_SPEC_MAX_PARAMS); returns their count. */
size_t fp_iso_helper_params(int argc, char **argv, fp_param *params);
/** A helper's start, shared by both: argv[2..5] (at least 6 words, checked by the caller) the
 *  shared memory's descriptor, the go and done eventfds and the socket; the plugin's stdout
 *  to the host's stderr; SIGPIPE ignored; OOM-killed first; a 1 MiB send buffer; the shared
 *  memory mapped (*shm, its size *mapped) and its magic and version checked. Returns 0 or
 *  the helper's exit status: 64 a bad descriptor, 70 a failed dup2, 66 a bad shared memory
 *  (*shm NULL). Once per process, before any thread. */
int fp_iso_helper_begin(char **argv, int *memfd, int *go, int *done, int *sock, fp_iso_shm **shm,
                        size_t *mapped);
/** Load the plugin `file` of `kind` by its path alone (no search), as fp_plugin_load. */
int fp_iso_helper_load(fp_plugin_kind kind, const char *file, fp_plugin *plugin, char *err, size_t errlen);

/* The host's side: the plugin file opened as a regular file only, without waiting (a FIFO
 * named like a plugin in a plugin folder: open() waited for a writer and hung `run` before
 * any output, where the in-process loader refuses it). The descriptor, or -1 with err set
 * (FP_EPLUGIN_DLOPEN in *rc). */
int fp_iso_open_plugin_file(const char *file, int *rc, char *err, size_t errlen);

#endif
