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

struct fp_event_recorder {
    fp_event_queue queue;
    fp_eventlog_writer *writer;
    pthread_t thread;
    atomic_bool stop;
    atomic_int error;                /* first error; message valid once it is non-zero */
    char message[512];
    atomic_ulong dropped;            /* pushes refused: the queue was full */
    char path[256];
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

int fp_event_recorder_open(const char *path, fp_event_recorder **out, char *err, size_t errlen)
{
    *out = NULL;
    fp_event_recorder *r = calloc(1, sizeof *r);
    if (!r || fp_event_queue_init(&r->queue, FP_RECORD_QUEUE_CAPACITY)) {
        free(r);
        snprintf(err, errlen, "%s: out of memory", path);
        return -ENOMEM;
    }
    snprintf(r->path, sizeof r->path, "%s", path);
    r->writer = fp_eventlog_writer_open(path, err, errlen);
    if (!r->writer) {
        fp_event_queue_destroy(&r->queue);
        free(r);
        return -EIO;
    }
    if (pthread_create(&r->thread, NULL, writer_main, r)) {
        fp_eventlog_writer_close(&r->writer, NULL, 0);
        fp_event_queue_destroy(&r->queue);
        free(r);
        snprintf(err, errlen, "%s: cannot start the writer thread", path);
        return -EAGAIN;
    }
    *out = r;
    return 0;
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
