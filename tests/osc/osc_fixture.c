/*
 * osc_fixture.c: the input-osc tests' fake host and plugin fixture (osc_fixture.h).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "osc_fixture.h"

#include <dlfcn.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cmocka.h>

const fp_input_factory *factory;
static void *plugin_handle;

/* ------------------------------------------------------------------------------------- */
/* Fake host: a bounded event store; a full store refuses, as the host's queue does.      */


int64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

void sleep_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000};
    nanosleep(&ts, NULL);
}

static bool fake_push(const fp_host *host, const fp_event_header *ev)
{
    fake_host *h = (fake_host *)host;
    bool ok = true;
    pthread_mutex_lock(&h->mutex);
    if (!h->store) {
        h->pushed++;
        if (h->pushed % 4 == 0) { /* a queue drained at a quarter of the rate: some refusals */
            h->refused++;
            if (ev->type != FP_EVENT_STATUS) h->refused_poses++; /* status events are retried */
            ok = false;
        }
    } else if (h->count < h->cap) {
        fp_event *e = &h->events[h->count++];
        memset(e, 0, sizeof *e);
        memcpy(e, ev, ev->size < sizeof *e ? ev->size : sizeof *e);
    } else {
        h->refused++;
        ok = false;
    }
    pthread_mutex_unlock(&h->mutex);
    return ok;
}

static int64_t fake_now(const fp_host *host)
{
    (void)host;
    return mono_ns();
}

static void fake_log(const fp_host *host, fp_log_level level, const char *message)
{
    fake_host *h = (fake_host *)host;
    pthread_mutex_lock(&h->mutex);
    size_t n = strlen(h->log);
    if (n < sizeof h->log - 1) snprintf(h->log + n, sizeof h->log - n, "%d %s\n", (int)level, message);
    pthread_mutex_unlock(&h->mutex);
}

fake_host *fake_new(size_t cap)
{
    fake_host *h = calloc(1, sizeof *h);
    assert_non_null(h);
    h->host = (fp_host){.size = sizeof(fp_host), .abi = {FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR},
                        .push_event = fake_push, .now_ns = fake_now, .log = fake_log};
    pthread_mutex_init(&h->mutex, NULL);
    h->events = calloc(cap, sizeof *h->events);
    assert_non_null(h->events);
    h->cap = cap;
    h->store = true;
    return h;
}

void fake_free(fake_host *h)
{
    pthread_mutex_destroy(&h->mutex);
    free(h->events);
    free(h);
}

size_t count_type(fake_host *h, int type, int code)
{
    size_t n = 0;
    pthread_mutex_lock(&h->mutex);
    for (size_t i = 0; i < h->count; i++)
        if (h->events[i].header.type == type && (code < 0 || h->events[i].status.code == (uint32_t)code)) n++;
    pthread_mutex_unlock(&h->mutex);
    return n;
}

/* Waits until `n` events of `type` (status `code` where >= 0) are stored; false after 5 s. */
bool wait_type(fake_host *h, int type, int code, size_t n)
{
    for (int64_t end = mono_ns() + 5000000000LL; mono_ns() < end; sleep_ms(2))
        if (count_type(h, type, code) >= n) return true;
    return false;
}

/* ------------------------------------------------------------------------------------- */
/* Plugin                                                                                 */


int create(fake_host *h, const char *keys, fp_input **in, char *err, size_t errlen)
{
    char buf[256];
    fp_param params[8];
    size_t n = 0;
    snprintf(buf, sizeof buf, "%s", keys ? keys : "");
    for (char *save = NULL, *kv = strtok_r(buf, ",", &save); kv && n < 8; kv = strtok_r(NULL, ",", &save)) {
        char *eq = strchr(kv, '=');
        assert_non_null(eq);
        *eq = '\0';
        params[n++] = (fp_param){kv, eq + 1};
    }
    err[0] = '\0';
    return factory->create(&h->host, "0", params, n, in, err, errlen);
}

void open_fixture(osc_fixture *f, const char *keys, size_t cap)
{
    memset(f, 0, sizeof *f);
    f->h = fake_new(cap);
    char err[512];
    int rc = create(f->h, keys, &f->in, err, sizeof err);
    if (rc) fail_msg("create [%s]: %d %s", keys ? keys : "", rc, err);
    f->ext = f->in->get_extension(f->in, FP_OSC_EXT_ID);
    assert_non_null(f->ext);
    fp_osc_stats st = {.size = sizeof st};
    f->ext->get_stats(f->in, &st);
    assert_true(st.port > 0);
    snprintf(f->port, sizeof f->port, "%u", (unsigned)st.port);
    assert_int_equal(f->in->start(f->in, err, sizeof err), 0);
    f->to = lo_address_new("127.0.0.1", f->port);
    assert_non_null(f->to);
}

void close_fixture(osc_fixture *f)
{
    f->in->stop(f->in);
    f->in->destroy(f->in);
    lo_address_free(f->to);
    fake_free(f->h);
}

fp_osc_stats stats(osc_fixture *f)
{
    fp_osc_stats st = {.size = sizeof st};
    f->ext->get_stats(f->in, &st);
    return st;
}

/* Waits until the plugin has read `packets` datagrams, or read none for 1 s (the kernel may
 * drop datagrams when the socket buffer overflows; a loaded machine may hold the plugin's
 * thread off its core for a good part of that, hence not less), or 5 s passed. */
void wait_packets(osc_fixture *f, uint64_t packets)
{
    uint64_t last = 0;
    int64_t end = mono_ns() + 5000000000LL, progress = mono_ns();
    while (mono_ns() < end && mono_ns() - progress < 1000000000) {
        uint64_t n = stats(f).packets;
        if (n >= packets) return;
        if (n != last) progress = mono_ns(), last = n;
        sleep_ms(1);
    }
}

/* The i-th joint_positions event (in arrival order). */
const fp_event *nth_positions(fake_host *h, size_t i)
{
    size_t k = 0;
    for (size_t e = 0; e < h->count; e++)
        if (h->events[e].header.type == FP_EVENT_JOINT_POSITIONS && k++ == i) return &h->events[e];
    return NULL;
}

int osc_fixture_load(void)
{
    const char *build = getenv("FP_BUILD_DIR");
    char path[1024];
    snprintf(path, sizeof path, "%s/lib/facepuppet/input-osc.so", build ? build : "build");
    plugin_handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!plugin_handle) {
        fprintf(stderr, "dlopen %s: %s\n", path, dlerror());
        return -1;
    }
    const fp_plugin_entry *entry = dlsym(plugin_handle, FP_PLUGIN_ENTRY_SYMBOL);
    if (!entry || (entry->init && !entry->init(path))) return -1; /* init may be NULL */
    factory = entry->get_factory(FP_INPUT_FACTORY_ID);
    return factory ? 0 : -1;
}

void osc_fixture_unload(void)
{
    if (plugin_handle) dlclose(plugin_handle);
    plugin_handle = NULL;
    factory = NULL;
}
