/* A worker thread that spins, then parks (fp_worker.h). */
#define _POSIX_C_SOURCE 200809L /* sched_yield */
#include "fp_worker.h"

#include "fp_clock.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>

struct fp_worker {
    fp_worker_spec spec;
    pthread_t th;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool quit;                    /* under mu */
    uint32_t wakes;               /* under mu: the latest wake's number */
    atomic_uint awakes;           /* wakes, for the polls */
    atomic_bool stop;             /* quit, for the polling */
    uint32_t served;              /* the worker's own: the wakes it served */
};

/* Polls until no work has come for spec.idle_ns (or the worker is stopped). */
static void spin(fp_worker *w)
{
    const fp_worker_spec *sp = &w->spec;
    for (int64_t idle = fp_now_ns(), yielded = idle;;) {
        if (sp->poll(sp->user, w)) {
            idle = yielded = fp_now_ns();
            continue;
        }
        for (int i = 0; i < sp->pauses; i++) fp_cpu_pause();
        int64_t t1 = fp_now_ns();
        if (t1 - idle > sp->idle_ns || atomic_load(&w->stop)) break;
        if (!sp->yield_ns || t1 - yielded > sp->yield_ns) {
            sched_yield();
            if (sp->yielded) sp->yielded(sp->user);
            yielded = t1;
        }
    }
}

static void *worker_main(void *arg)
{
    fp_worker *w = arg;
    const fp_worker_spec *sp = &w->spec;
    if (sp->enter) sp->enter(sp->user);
    for (;;) {
        pthread_mutex_lock(&w->mu);
        while (!w->quit && w->wakes == w->served) pthread_cond_wait(&w->cv, &w->mu);
        w->served = w->wakes;
        bool quit = w->quit;
        pthread_mutex_unlock(&w->mu);
        if (quit) break;
        if (sp->awake) sp->awake(sp->user);
        spin(w);
        if (sp->asleep) sp->asleep(sp->user);
    }
    if (sp->leave) sp->leave(sp->user);
    return NULL;
}

int fp_worker_create(const fp_worker_spec *spec, fp_worker **out)
{
    *out = NULL;
    fp_worker *w = calloc(1, sizeof *w);
    if (!w) return -ENOMEM;
    w->spec = *spec;
    atomic_init(&w->awakes, 0);
    atomic_init(&w->stop, false);
    int rc = pthread_mutex_init(&w->mu, NULL);
    if (rc) {
        free(w);
        return -rc;
    }
    if ((rc = pthread_cond_init(&w->cv, NULL))) {
        pthread_mutex_destroy(&w->mu);
        free(w);
        return -rc;
    }
    if ((rc = pthread_create(&w->th, NULL, worker_main, w))) {
        pthread_cond_destroy(&w->cv);
        pthread_mutex_destroy(&w->mu);
        free(w);
        return -rc;
    }
    *out = w;
    return 0;
}

void fp_worker_destroy(fp_worker **wp)
{
    fp_worker *w = wp ? *wp : NULL;
    if (!w) return;
    atomic_store(&w->stop, true);
    pthread_mutex_lock(&w->mu);
    w->quit = true;
    pthread_cond_signal(&w->cv);
    pthread_mutex_unlock(&w->mu);
    pthread_join(w->th, NULL);
    pthread_cond_destroy(&w->cv);
    pthread_mutex_destroy(&w->mu);
    free(w);
    *wp = NULL;
}

uint32_t fp_worker_wake(fp_worker *w, void (*publish)(void *arg, uint32_t wake), void *arg)
{
    pthread_mutex_lock(&w->mu);
    uint32_t n = ++w->wakes;
    if (publish) publish(arg, n);
    atomic_store(&w->awakes, n);
    pthread_cond_signal(&w->cv);
    pthread_mutex_unlock(&w->mu);
    return n;
}

uint32_t fp_worker_wakes(fp_worker *w) { return atomic_load(&w->awakes); }

void fp_worker_served(fp_worker *w, uint32_t wake) { w->served = wake; }
