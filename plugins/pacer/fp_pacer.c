/* Pacing and lossless pushing for replaying input plugins (fp_pacer.h). */
#define _POSIX_C_SOURCE 200809L
#include "fp_pacer.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#define RETRY_WAIT_NS 1000000 /* a full queue is tried again after 1 ms */

int fp_pacer_init(fp_pacer *p, const fp_host *host)
{
    p->host = host;
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    int rc = pthread_cond_init(&p->cond, &ca);
    pthread_condattr_destroy(&ca);
    if (rc) return -rc;
    if ((rc = pthread_mutex_init(&p->mutex, NULL))) {
        pthread_cond_destroy(&p->cond);
        return -rc;
    }
    atomic_init(&p->stop, false);
    return 0;
}

void fp_pacer_destroy(fp_pacer *p)
{
    pthread_cond_destroy(&p->cond);
    pthread_mutex_destroy(&p->mutex);
}

void fp_pacer_rearm(fp_pacer *p) { atomic_store(&p->stop, false); }

void fp_pacer_stop(fp_pacer *p)
{
    pthread_mutex_lock(&p->mutex);
    atomic_store(&p->stop, true);
    pthread_cond_broadcast(&p->cond);
    pthread_mutex_unlock(&p->mutex);
}

bool fp_pacer_stopped(fp_pacer *p) { return atomic_load(&p->stop); }

int64_t fp_pacer_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

bool fp_pacer_wait_until(fp_pacer *p, int64_t deadline)
{
    struct timespec ts = {(time_t)(deadline / 1000000000), (long)(deadline % 1000000000)};
    pthread_mutex_lock(&p->mutex);
    while (!atomic_load(&p->stop) && fp_pacer_now_ns() < deadline)
        if (pthread_cond_timedwait(&p->cond, &p->mutex, &ts) == ETIMEDOUT) break;
    bool go_on = !atomic_load(&p->stop);
    pthread_mutex_unlock(&p->mutex);
    return go_on;
}

bool fp_pacer_push(fp_pacer *p, const fp_event *ev)
{
    while (!p->host->push_event(p->host, &ev->header))
        if (!fp_pacer_wait_until(p, fp_pacer_now_ns() + RETRY_WAIT_NS)) return false;
    return true;
}

bool fp_pacer_push_status(fp_pacer *p, int64_t time_ns, uint32_t code, const char *fmt, ...)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.status.header = (fp_event_header){.size = sizeof ev.status, .type = FP_EVENT_STATUS,
                                         .time_ns = time_ns, .hand = -1};
    ev.status.code = code;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(ev.status.text, sizeof ev.status.text, fmt, ap);
    va_end(ap);
    return fp_pacer_push(p, &ev);
}
