/* Pacing and lossless pushing for replaying input plugins (fp_pacer.h). */
#define _GNU_SOURCE /* strtod_l */
#include "fp_pacer.h"

#include <facepuppet/decimal.h>

#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stdlib.h>
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
    p->running = false;
    return 0;
}

void fp_pacer_destroy(fp_pacer *p)
{
    fp_pacer_stop(p);
    pthread_cond_destroy(&p->cond);
    pthread_mutex_destroy(&p->mutex);
}

int fp_pacer_start(fp_pacer *p, void *(*run)(void *), void *arg, const char *who, char *err,
                   size_t errlen)
{
    if (p->running) {
        snprintf(err, errlen, "%s: already started", who);
        return -EBUSY;
    }
    atomic_store(&p->stop, false); /* a previous stop's request is done with */
    int rc = pthread_create(&p->thread, NULL, run, arg);
    if (rc) {
        snprintf(err, errlen, "%s: cannot start its thread: %s", who, strerror(rc));
        return -rc;
    }
    p->running = true;
    return 0;
}

void fp_pacer_stop(fp_pacer *p)
{
    if (!p->running) return;
    pthread_mutex_lock(&p->mutex);
    atomic_store(&p->stop, true);
    pthread_cond_broadcast(&p->cond);
    pthread_mutex_unlock(&p->mutex);
    pthread_join(p->thread, NULL);
    p->running = false;
}

bool fp_pacer_stopped(fp_pacer *p) { return atomic_load(&p->stop); }

bool fp_pacer_parse_speed(const char *v, double *out)
{
    locale_t c = newlocale(LC_ALL_MASK, "C", (locale_t)0);
    if (c == (locale_t)0) return false;
    char *end = NULL;
    const double s = strtod_l(v, &end, c);
    freelocale(c);
    const size_t n = fp_decimal_span(v);
    if (!n || end != v + n || *end || !isfinite(s) || !(s >= 1e-3) || s > 1e6) return false;
    *out = s;
    return true;
}

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
