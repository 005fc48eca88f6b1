/* record=FILE: events queued by the session thread, written by a thread of their own. */
#define _POSIX_C_SOURCE 200809L
#include "fp_record.h"

#include "fp_eventlog.h"
#include "fp_plugin_host.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define FP_RECORD_QUEUE_CAPACITY 16384   /* events; the input queues hold 4096 */
#define FP_RECORD_MAX_SUFFIX 999         /* FILE-1.ext .. FILE-999.ext */

struct fp_event_recorder {
    fp_event_queue queue;
    fp_eventlog_writer *writer;
    pthread_t thread;
    atomic_bool stop;
    atomic_int error;                /* first error; message valid once it is non-zero */
    char message[512];
    atomic_ulong dropped;            /* pushes refused: the queue was full */
    char path[4096];                 /* the file written (a free name, see create) */
};

static void fail(fp_event_recorder *r, int code, const char *msg)
{
    int none = 0;
    /* The message is written before the code is published (release), read after (acquire). */
    if (atomic_load(&r->error)) return;
    snprintf(r->message, sizeof r->message, "%s", msg);
    atomic_compare_exchange_strong(&r->error, &none, code);
}

static void *writer_main(void *arg)
{
    fp_event_recorder *r = arg;
    for (;;) {
        bool stopping = atomic_load(&r->stop);
        fp_event ev;
        bool any = false;
        while (fp_event_queue_pop(&r->queue, &ev)) {
            any = true;
            if (atomic_load(&r->error)) continue;   /* after a failure, drain and drop */
            int rc = fp_eventlog_writer_write(r->writer, &ev);
            if (rc < 0) fail(r, rc, fp_eventlog_writer_error(r->writer));
        }
        if (stopping) break;
        if (!any) {
            struct timespec ts = {0, 1000000};   /* 1 ms: the session thread never waits */
            nanosleep(&ts, NULL);
        }
    }
    return NULL;
}

/* Candidate n of a free name: PATH itself for n = 0, else STEM-n.EXT (STEM-n without an
 * extension). Returns false when it does not fit. */
static bool candidate(const char *path, unsigned n, char *out, size_t len)
{
    if (n == 0) return (size_t)snprintf(out, len, "%s", path) < len;
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(slash ? slash + 1 : path, '.');
    if (dot && (dot == (slash ? slash + 1 : path))) dot = NULL; /* ".hidden": no extension */
    int stem = dot ? (int)(dot - path) : (int)strlen(path);
    return (size_t)snprintf(out, len, "%.*s-%u%s", stem, path, n, dot ? dot : "") < len;
}

int fp_event_recorder_create(const char *path, unsigned flags, char *used, size_t usedlen,
                             fp_event_recorder **out, char *err, size_t errlen)
{
    *out = NULL;
    if (used && usedlen) used[0] = '\0';
    fp_event_recorder *r = calloc(1, sizeof *r);
    if (!r || fp_event_queue_init(&r->queue, FP_RECORD_QUEUE_CAPACITY)) {
        free(r);
        snprintf(err, errlen, "%s: out of memory", path);
        return -ENOMEM;
    }
    int rc = -EEXIST;
    for (unsigned n = 0; rc == -EEXIST && n <= FP_RECORD_MAX_SUFFIX; n++) {
        if (!candidate(path, n, r->path, sizeof r->path)) {
            rc = -ENAMETOOLONG;
            snprintf(err, errlen, "%s: name too long", path);
            break;
        }
        rc = fp_eventlog_writer_create(r->path, flags & FP_RECORD_OVERWRITE ? 0 : FP_EVENTLOG_EXCL,
                                       &r->writer, err, errlen);
    }
    if (rc == -EEXIST)
        snprintf(err, errlen, "%s: it and %s-1 .. -%u exist (force=1 overwrites it)", path, path,
                 FP_RECORD_MAX_SUFFIX);
    if (rc) {
        fp_event_queue_destroy(&r->queue);
        free(r);
        /* an output that cannot be created (exit 73 in the commands): -EIO unless the code
         * says more (full disk, no memory, every name taken) */
        return rc == -ENOMEM || rc == -ENOSPC || rc == -EDQUOT || rc == -EEXIST ? rc : -EIO;
    }
    if (pthread_create(&r->thread, NULL, writer_main, r)) {
        fp_eventlog_writer_close(&r->writer, NULL, 0);
        fp_event_queue_destroy(&r->queue);
        snprintf(err, errlen, "%s: cannot start the writer thread", r->path);
        free(r);
        return -EAGAIN;
    }
    if (used && usedlen) snprintf(used, usedlen, "%s", r->path);
    *out = r;
    return 0;
}

int fp_event_recorder_open(const char *path, fp_event_recorder **out, char *err, size_t errlen)
{
    return fp_event_recorder_create(path, FP_RECORD_OVERWRITE, NULL, 0, out, err, errlen);
}

bool fp_event_recorder_push(fp_event_recorder *r, const fp_event *ev)
{
    if (fp_event_queue_push(&r->queue, &ev->header)) return true;
    atomic_fetch_add(&r->dropped, 1);
    return false;
}

int fp_event_recorder_error(fp_event_recorder *r, char *err, size_t errlen)
{
    int rc = atomic_load(&r->error);
    if (rc) {
        snprintf(err, errlen, "%s", r->message);
        return rc;
    }
    unsigned long d = atomic_load(&r->dropped);
    if (d) {
        snprintf(err, errlen, "%s: %lu event%s not recorded (the writer fell behind)", r->path, d,
                 d == 1 ? "" : "s");
        return -ENOBUFS;
    }
    return 0;
}

int fp_event_recorder_close(fp_event_recorder **rp, char *err, size_t errlen)
{
    fp_event_recorder *r = rp ? *rp : NULL;
    if (!r) return 0;
    atomic_store(&r->stop, true);
    pthread_join(r->thread, NULL);
    char cerr[512] = "";
    int crc = fp_eventlog_writer_close(&r->writer, cerr, sizeof cerr);
    if (crc < 0) fail(r, crc, cerr);
    int rc = fp_event_recorder_error(r, err, errlen);
    fp_event_queue_destroy(&r->queue);
    free(r);
    *rp = NULL;
    return rc;
}
