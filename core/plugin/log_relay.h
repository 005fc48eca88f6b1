/*
 * log_relay.h: a plugin's log lines carried from whatever thread it logs on (an input's reader
 * thread, a device callback, create or process on the caller's) to the one thread that owns
 * the plugin (the session's, or a command's loop), which hands them to its log callback.
 * The session's log callback is called on the session thread only (fp_session.h), and the
 * host library never prints: a plugin's fp_host.log (plugin.h: any thread) pushes here, and
 * the owner drains at points of its own (each frame, after create, at close).
 *
 * A bounded ring (FP_LOG_RELAY_LINES lines of up to FP_LOG_RELAY_BYTES - 1 bytes, longer ones
 * truncated): a plugin that logs faster than the owner drains loses the newest lines, counted
 * and reported at the next drain. Thread rules: fp_log_relay_push from any thread (a mutex
 * held for one copy; never blocks on the owner's callback); init, drain and destroy on the
 * owner's thread.
 */
#ifndef FP_LOG_RELAY_H
#define FP_LOG_RELAY_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_LOG_RELAY_LINES 32
#define FP_LOG_RELAY_BYTES 512

typedef struct fp_log_relay {
    pthread_mutex_t lock;
    bool ready;                            /* initialised (a zeroed relay drops pushes) */
    unsigned head, count;                  /* oldest line, lines held */
    atomic_uint pending;                   /* lines held + 1 if any dropped: read without the
                                              lock, so an empty drain costs one load */
    unsigned long dropped;                 /* lines lost to a full ring since the last drain */
    int level[FP_LOG_RELAY_LINES];
    char line[FP_LOG_RELAY_LINES][FP_LOG_RELAY_BYTES];
} fp_log_relay;

/** The callback lines are drained into: level an fp_log_level, source the owner's name for
 *  the plugin, message without a trailing newline; both strings valid during the call. */
typedef void (*fp_log_relay_fn)(void *user, int level, const char *source, const char *message);

/** Make r empty and usable. Returns 0 or -ENOMEM (pthread_mutex_init). */
int fp_log_relay_init(fp_log_relay *r);

/** Keep one line (NULL: ""). A full ring drops it and counts it; an uninitialised (zeroed)
 *  relay drops it silently. Any thread. */
void fp_log_relay_push(fp_log_relay *r, int level, const char *message);

/** Hand every kept line, oldest first, to fn(user, level, source, line) on the calling
 *  thread, then, when lines were dropped, one FP_LOG_WARNING line saying how many. The lock
 *  is not held during fn (a plugin may log meanwhile; those lines wait for the next drain).
 *  fn NULL: the lines are discarded. Returns the lines handed (the dropped note included). */
size_t fp_log_relay_drain(fp_log_relay *r, const char *source, fp_log_relay_fn fn, void *user);

/** Discard what is left and release the lock; r is zeroed (a later push is dropped). */
void fp_log_relay_destroy(fp_log_relay *r);

#ifdef __cplusplus
}
#endif
#endif
