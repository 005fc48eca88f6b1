/*
 * session_log.h: how the session's steps report (the session never prints). A message goes
 * to the log callback of fp_session_options (level as plugin.h's fp_log_level, the source
 * naming the input SPEC's name, the mapping's name or "engine"); NULL callback = silent.
 * A runtime error that repeats every frame is reported once, then its count when it changes
 * or at the end ("... repeated N times"), through fp_slog_repeat.
 *
 * Threads: the session thread only (the callback is called on it and must not block long).
 */
#ifndef FP_SESSION_LOG_H
#define FP_SESSION_LOG_H

#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The log callback: level is an fp_log_level (FP_LOG_ERROR .. FP_LOG_DEBUG), source names
 *  who speaks ("replay", "anchored", "engine", "record"), message has no trailing newline.
 *  Both strings are valid during the call only. */
typedef void (*fp_session_log_fn)(void *user, int level, const char *source, const char *message);

/** The sources of the steps that note how each gesture went: the engine (the fold-over
 *  guard: "limited the deformation to N%", "composed N steps") and the contact guard
 *  ("N frames scaled back"); their errors use them too. */
#define FP_SLOG_ENGINE "engine"
#define FP_SLOG_CONTACT "contact"

/** Whether a line is one of those notes: below FP_LOG_ERROR and from FP_SLOG_ENGINE or
 *  FP_SLOG_CONTACT. What a quiet program (-q) leaves out; the inputs', recordings', the
 *  mapping's and the rig's lines, and every error, are none. level: fp_log_level; source:
 *  the line's source name (NULL: none, never a note). Pure: [any-thread], no allocation. */
bool fp_slog_is_note(int level, const char *source);

/** A log target: the callback (may be NULL: messages are dropped) and its user pointer. */
typedef struct fp_slog {
    fp_session_log_fn fn;
    void *user;
} fp_slog;

/** Format and send one message (truncated to 512 bytes). Nothing when log or log->fn is NULL. */
void fp_slog_printf(const fp_slog *log, int level, const char *source, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/** One kind of repeated error: reported at its first occurrence; later occurrences with the
 *  same source and code are only counted; a different one (or fp_slog_repeat_flush) first
 *  reports "SOURCE: MESSAGE (repeated N more times)" for the previous one when N > 0. */
typedef struct fp_slog_repeat {
    int code;                  /* 0: nothing pending */
    int level;
    unsigned long repeats;     /* occurrences after the first, not yet reported */
    unsigned long total;       /* every occurrence since creation */
    char source[64];
    char message[256];         /* the first occurrence's text */
} fp_slog_repeat;

/** Report an occurrence of error `code` (non-zero) from source. Returns true when this call
 *  sent a line for it (a first occurrence), false when it was only counted. */
bool fp_slog_repeat_report(fp_slog_repeat *r, const fp_slog *log, int level, const char *source,
                           int code, const char *fmt, ...) __attribute__((format(printf, 6, 7)));

/** Send the pending "repeated N more times" line, if any, and forget the error (so that the
 *  next occurrence is reported as new): call when the error ends and at destruction. */
void fp_slog_repeat_flush(fp_slog_repeat *r, const fp_slog *log);

#ifdef __cplusplus
}
#endif
#endif
