/*
 * fp_record.h: the recording of an input's events (record=FILE on its SPEC) without I/O on
 * the consumer's thread. The consumer (the session thread) pushes each event it drains into
 * a bounded lock-free queue (fp_event_queue); one writer thread per recording pops them and
 * writes them with fp_eventlog (docs/eventlog.md). Closing writes what is queued, joins the
 * thread and returns the first error: a failed write is never silent.
 *
 * Errors: 0 or a negative code: the event log's code for an open or write failure (message
 * "PATH: reason"), -ENOBUFS when events were dropped because the queue was full (the writer
 * fell behind: the recording is incomplete), -ENOMEM.
 * Threads: open and close [main-thread]; push from one thread at a time (the consumer),
 * never blocks; fp_event_recorder_error from any thread.
 */
#ifndef FP_RECORD_H
#define FP_RECORD_H

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct fp_event_recorder fp_event_recorder;

/** Create (truncate) the event log at path and start its writer thread. Returns 0 or a
 *  negative code with "PATH: reason" in err. */
int fp_event_recorder_open(const char *path, fp_event_recorder **out, char *err, size_t errlen);

/** Queue a copy of ev for writing. Never blocks; false when the queue is full (the event is
 *  counted as dropped and close reports -ENOBUFS). */
bool fp_event_recorder_push(fp_event_recorder *r, const fp_event *ev);

/** The first error so far (0 when none); its message into err. */
int fp_event_recorder_error(fp_event_recorder *r, char *err, size_t errlen);

/** Write what is queued, stop and join the thread, close the file, free; *r = NULL. Returns
 *  0 or the first error (message in err). Safe on NULL. */
int fp_event_recorder_close(fp_event_recorder **r, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
