/*
 * fp_record.h: the recording of an input's events (record=FILE on its SPEC) without I/O on
 * the consumer's thread. The consumer (the session thread) pushes each event it drains into
 * a bounded lock-free queue (fp_event_queue); one writer thread per recording pops them and
 * writes them with fp_eventlog (docs/eventlog.md). Closing writes what is queued, joins the
 * thread and returns the first error: a failed write is never silent.
 *
 * A failed write (disk full: -ENOSPC) stops the recording at once: the file keeps every
 * whole line written before it, later events are dropped, and the error is kept for
 * fp_event_recorder_error (the session logs it the frame it happens) and close.
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

/** Flags of fp_event_recorder_create. */
#define FP_RECORD_OVERWRITE 1u /* truncate an existing file (record=FILE,force=1) */

/** Create the event log and start its writer thread. An existing file is never overwritten
 *  without FP_RECORD_OVERWRITE: the first free name of PATH, STEM-1.EXT, ..., STEM-999.EXT
 *  (PATH-N without an extension) is taken instead, created with O_EXCL so that two
 *  recorders never share one. `used` (usedlen bytes; may be NULL) receives the path opened;
 *  the caller says so when it differs from path. Returns 0 or a negative code with
 *  "PATH: reason" in err: -EIO when the file cannot be created (the message says why),
 *  -ENOSPC or -EDQUOT (no room), -EEXIST when all 1000 names exist, -ENOMEM, -EAGAIN (its
 *  writer thread could not be started). */
int fp_event_recorder_create(const char *path, unsigned flags, char *used, size_t usedlen,
                             fp_event_recorder **out, char *err, size_t errlen);

/** fp_event_recorder_create with FP_RECORD_OVERWRITE (truncates an existing file). */
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
