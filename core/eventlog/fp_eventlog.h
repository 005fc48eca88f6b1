/*
 * fp_eventlog.h: the facepuppet event log, a line-oriented text recording of plugin events.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * The format (docs/eventlog.md has the full grammar): a header line
 * `# facepuppet-eventlog 1`, then one event per line,
 *
 *     TIME_NS TYPE HAND FIELDS... [source=N] [flags=N]
 *
 * with TYPE one of angles, positions, wrist, button, status; HAND left, right or `-`; floats
 * printed with %.9g so that every finite float reads back bit for bit. Lines starting with
 * `#` and blank lines are comments.
 *
 * Used by the host to record live input (sessions, takes) and by plugins/input-replay to
 * replay it. A static library built position-independent so plugins may link it in.
 *
 * Errors: functions return 0 (or 1 for an event read) or a negative errno (fp_error.h); the
 * message of the last error is kept in the writer or reader (fp_eventlog_writer_error,
 * fp_eventlog_reader_error) and names the file, and for the reader the line and column.
 * Nothing is ever printed.
 *
 * Threads: a writer or reader is used by one thread at a time; different objects are
 * independent. Numbers are written and read in the C locale whatever the process locale is.
 */
#ifndef FP_EVENTLOG_H
#define FP_EVENTLOG_H

#include <facepuppet/plugin.h>

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The format name and the one version this code writes and reads. */
#define FP_EVENTLOG_MAGIC "facepuppet-eventlog"
#define FP_EVENTLOG_VERSION 1

/** The largest |TIME| in ns the format holds (10^18 ns, about 31.7 years): the difference of
 *  any two times, and a loop period of twice a duration, fit in int64_t. The writer refuses
 *  a time beyond it (-EINVAL), the reader a line with one (-EBADMSG, FILE:LINE:COLUMN). */
#define FP_EVENTLOG_TIME_MAX 1000000000000000000LL

/* ------------------------------------------------------------------------------------- */
/* Writer                                                                                 */

typedef struct fp_eventlog_writer fp_eventlog_writer;

/** Flags of fp_eventlog_writer_create. */
#define FP_EVENTLOG_EXCL 1u /* refuse an existing file (-EEXIST) instead of truncating it */

/** Create the file at `path` (truncate it, or with FP_EVENTLOG_EXCL refuse one that exists)
 *  and write the header line. Returns 0 and the writer in *out, or a negative errno
 *  (-EEXIST, -EACCES, -ENOENT, -ENOSPC, -EIO, -ENOMEM) with "PATH: reason" in err (errlen
 *  bytes; may be NULL). Owned by the caller: close it with fp_eventlog_writer_close. */
int fp_eventlog_writer_create(const char *path, unsigned flags, fp_eventlog_writer **out,
                              char *err, size_t errlen);

/** Create (or truncate) the file at `path` and write the header line.
 *  Returns the writer, or NULL after writing "PATH: reason" to err (errlen bytes; err may be
 *  NULL). Owned by the caller: close it with fp_eventlog_writer_close. */
fp_eventlog_writer *fp_eventlog_writer_open(const char *path, char *err, size_t errlen);

/** Append one event as one line. The line is formatted in full, checked, and only then
 *  written to the kernel (one write per line, no user-space buffer), so a crash of the
 *  process at any moment loses at most the line being written, and a rejected event writes
 *  nothing. A write the disk takes only in part (full) is cut back to the last whole line.
 *  Events: every fp_event_type of plugin.h; header.size must be at least the size of its
 *  type's struct (fields past it are not recorded); hand must be -1, 0 or 1; floats must be
 *  finite; angles.valid may use only the low FP_GLOVE_SENSORS bits; status text is recorded
 *  up to its NUL (at most 115 bytes); |time_ns| <= FP_EVENTLOG_TIME_MAX. source and flags
 *  are recorded as they are. Returns 0, -EINVAL (the file is unchanged), -ENOSPC, -EDQUOT,
 *  -EFBIG (disk full: the file ends with the line before) or -EIO; the message is
 *  in fp_eventlog_writer_error. Not for the [session-thread]: it does I/O. */
int fp_eventlog_writer_write(fp_eventlog_writer *w, const fp_event *event);

/** Append a comment line `# TEXT` (a slate, a note). Line breaks in text become spaces.
 *  Returns 0 or a write's code (-ENOSPC, -EIO, ...). It writes to the file: not on the
 *  session thread (the recorder's writer thread calls it, fp_record.h). */
int fp_eventlog_writer_comment(fp_eventlog_writer *w, const char *text);

/** The message of the writer's last error ("" when none). Valid until the next call. */
const char *fp_eventlog_writer_error(const fp_eventlog_writer *w);

/** Sync (fsync), close the file and free the writer; sets *w to NULL. NULL or *w NULL is a
 *  no-op. Returns 0, or -EIO / -ENOSPC when the final sync or close failed (the writer is freed
 *  anyway; err, if not NULL, receives the message). */
int fp_eventlog_writer_close(fp_eventlog_writer **w, char *err, size_t errlen);

/* ------------------------------------------------------------------------------------- */
/* Reader                                                                                 */

typedef struct fp_eventlog_reader fp_eventlog_reader;

/** Open the event log at `path` and check its header line.
 *  Returns the reader, or NULL after writing to err (errlen bytes; may be NULL)
 *  "PATH: reason" when the file cannot be opened, or "PATH:1:COLUMN: reason" when the first
 *  line is not `# facepuppet-eventlog VERSION` with a version this code reads.
 *  Close it with fp_eventlog_reader_close. */
fp_eventlog_reader *fp_eventlog_reader_open(const char *path, char *err, size_t errlen);

/** fp_eventlog_reader_open, with the failure's code in *code (0 on success): -ENOMEM, the
 *  open's (-ENOENT, -EACCES, -EISDIR a folder, -ENXIO a FIFO or device: fp_file_open_regular),
 *  -EIO (a read failed), -EBADMSG (not an event log), -ENOTSUP (a version this code does not
 *  read). code may be NULL. */
fp_eventlog_reader *fp_eventlog_reader_open_code(const char *path, int *code, char *err,
                                                 size_t errlen);

/** Read the next event into *out (the whole union is zeroed first; header.size is the size
 *  of the type's struct, status text is NUL-padded).
 *  Returns 1 for an event, 0 at the end of the file, or a negative errno (fp_error.h)
 *  (-EBADMSG with the message "PATH:LINE:COLUMN: reason", LINE and COLUMN
 *  counted from 1, COLUMN in bytes; -EIO). After an error every later call
 *  returns the same error.
 *  A last line that does not end with a newline is taken as cut short by a crash: it is not
 *  parsed, next returns 0, and fp_eventlog_reader_truncated_line gives its number. */
int fp_eventlog_reader_next(fp_eventlog_reader *r, fp_event *out);

/** The line number of the event last returned by next (0 before the first). */
long fp_eventlog_reader_line(const fp_eventlog_reader *r);

/** 0, or the number of the unterminated last line that next skipped (see next). */
long fp_eventlog_reader_truncated_line(const fp_eventlog_reader *r);

/** The message of the reader's last error ("" when none): the reader's, valid until its next
 *  call or close. */
const char *fp_eventlog_reader_error(const fp_eventlog_reader *r);

/** Close the file and free the reader; sets *r to NULL. NULL or *r NULL is a no-op. */
void fp_eventlog_reader_close(fp_eventlog_reader **r);

/* ------------------------------------------------------------------------------------- */
/* Names                                                                                  */

/** Format keyword of an event type ("angles", "positions", "wrist", "button", "status"),
 *  or NULL for an unknown type. */
const char *fp_eventlog_type_name(int type);

/** Format keyword of a status code ("connected", ..., "end-of-stream"), or NULL. */
const char *fp_eventlog_status_name(uint32_t code);

#ifdef __cplusplus
}
#endif
#endif /* FP_EVENTLOG_H */
