/* fp_test_support.c: the tests' shared helpers (fp_test_support.h). */
#define _GNU_SOURCE
#include "fp_test_support.h"

#include <setjmp.h>
#include <stdarg.h>
#include <cmocka.h>

#include <dirent.h>
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "fp_plugin_host.h"
#include "fp_session.h"

/* ---- folders and time ----------------------------------------------------------------- */

const char *fp_test_data_dir(void)
{
    const char *d = getenv("FP_SHARED_DATA");
    return d && *d ? d : "../shared/data";
}

const char *fp_test_build_dir(void)
{
    const char *b = getenv("FP_BUILD_DIR");
    return b && *b ? b : "build";
}

const char *fp_test_plugin_dir(void)
{
    static char dir[4096];
    snprintf(dir, sizeof dir, "%s/lib/facepuppet", fp_test_build_dir());
    return dir;
}

const char *fp_test_face_path(void)
{
    static char path[4200];
    snprintf(path, sizeof path, "%s/faces/ict-facekit/generic_neutral_mesh.obj",
             fp_test_data_dir());
    return path;
}

#define FP_TEST_JOINTS_SUFFIX "_joints_mm.csv"
/* what a recording's file name ends in: the joints CSV, a Leap playback original */
static const char *const suffixes[] = {FP_TEST_JOINTS_SUFFIX, ".json.lz", ".json"};

/* the length of the suffix file name f ends in with something before it, or 0 */
static size_t recording_suffix(const char *f)
{
    size_t n = strlen(f);
    for (size_t i = 0; i < sizeof suffixes / sizeof suffixes[0]; i++) {
        size_t k = strlen(suffixes[i]);
        if (n > k && strcmp(f + n - k, suffixes[i]) == 0) return k;
    }
    return 0;
}

static void add_recording(fp_test_recordings *out, const char *dir, const char *file)
{
    assert_true(out->n < FP_TEST_RECORDINGS_MAX);
    size_t i = out->n++;
    int w = snprintf(out->path[i], sizeof out->path[i], "%s/%s", dir, file);
    assert_true(w > 0 && (size_t)w < sizeof out->path[i]);
    snprintf(out->name[i], sizeof out->name[i], "%.*s", (int)(strlen(file) - recording_suffix(file)), file);
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

void fp_test_recordings_from(const char *env, fp_test_recordings *out)
{
    static const char *const four[] = {"HandSplay-110fps", "Waiting-110fps", "grab", "three-claps"};
    memset(out, 0, sizeof *out);
    const char *where = env ? getenv(env) : NULL;
    if (!where || !*where) {
        char dir[4200], file[256];
        snprintf(dir, sizeof dir, "%s/hands/leap-motion", fp_test_data_dir());
        for (size_t i = 0; i < sizeof four / sizeof four[0]; i++) {
            snprintf(file, sizeof file, "%s%s", four[i], FP_TEST_JOINTS_SUFFIX);
            add_recording(out, dir, file);
        }
        return;
    }
    struct stat st;
    if (stat(where, &st) != 0) {
        fprintf(stderr, "%s=%s: no such file or folder\n", env, where);
        fail();
    }
    if (!S_ISDIR(st.st_mode)) {
        /* one recording: its folder and file name */
        const char *slash = strrchr(where, '/');
        const char *file = slash ? slash + 1 : where;
        if (!recording_suffix(file)) {
            fprintf(stderr, "%s=%s: not a folder nor a *%s, *.json.lz or *.json\n", env, where,
                    FP_TEST_JOINTS_SUFFIX);
            fail();
        }
        char dir[4200];
        snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - where) : 1, slash ? where : ".");
        add_recording(out, dir, file);
        return;
    }
    DIR *d = opendir(where);
    assert_non_null(d);
    char *names[FP_TEST_RECORDINGS_MAX];
    size_t n = 0;
    for (struct dirent *e; (e = readdir(d));)
        if (recording_suffix(e->d_name)) {
            assert_true(n < FP_TEST_RECORDINGS_MAX);
            names[n] = strdup(e->d_name);
            assert_non_null(names[n++]);
        }
    closedir(d);
    if (!n) {
        fprintf(stderr, "%s=%s: no *%s, *.json.lz or *.json in that folder\n", env, where,
                FP_TEST_JOINTS_SUFFIX);
        fail();
    }
    qsort(names, n, sizeof names[0], by_name);
    for (size_t i = 0; i < n; i++) {
        add_recording(out, where, names[i]);
        free(names[i]);
    }
}

void fp_test_write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_true(fputs(text, f) >= 0);
    assert_int_equal(fclose(f), 0);
}

int64_t fp_test_mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

size_t fp_test_reversed(const float *a, const float *b, const uint32_t *tris, size_t t)
{
    size_t k = 0;
    for (size_t i = 0; i < t; i++) {
        const uint32_t *v = tris + 3 * i;
        double n[2][3];
        for (int w = 0; w < 2; w++) {
            const float *p = w ? b : a;
            double e1[3], e2[3];
            for (int c = 0; c < 3; c++) {
                e1[c] = (double)p[3 * v[1] + c] - p[3 * v[0] + c];
                e2[c] = (double)p[3 * v[2] + c] - p[3 * v[0] + c];
            }
            n[w][0] = e1[1] * e2[2] - e1[2] * e2[1];
            n[w][1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[w][2] = e1[0] * e2[1] - e1[1] * e2[0];
        }
        k += n[0][0] * n[1][0] + n[0][1] * n[1][1] + n[0][2] * n[1][2] < 0;
    }
    return k;
}

int fp_test_time_scale(void)
{
    const char *e = getenv("FP_TEST_TIME_SCALE");
    int s = e ? atoi(e) : 1;
    return s > 1 ? s : 1;
}

void fp_test_nap_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

/* ---- one plugin ------------------------------------------------------------------------ */

const void *fp_test_plugin_open(const char *file, const char *factory_id, void **handle)
{
    char path[4600];
    snprintf(path, sizeof path, "%s/%s", fp_test_plugin_dir(), file);
    *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!*handle) {
        fprintf(stderr, "dlopen %s: %s\n", path, dlerror());
        return NULL;
    }
    const fp_plugin_entry *entry = dlsym(*handle, FP_PLUGIN_ENTRY_SYMBOL);
    fp_version host = {FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR};
    /* init and deinit may be NULL (plugin.h), as the host's loader takes them */
    if (!entry || !fp_version_is_compatible(host, entry->abi) || (entry->init && !entry->init(path))) {
        fprintf(stderr, "%s: no compatible entry, or its init failed\n", path);
        return NULL;
    }
    const void *factory = entry->get_factory(factory_id);
    if (!factory) fprintf(stderr, "%s: no factory %s\n", path, factory_id);
    return factory;
}

void fp_test_plugin_close(void **handle)
{
    if (!handle || !*handle) return;
    const fp_plugin_entry *entry = dlsym(*handle, FP_PLUGIN_ENTRY_SYMBOL);
    if (entry && entry->deinit) entry->deinit();
    dlclose(*handle);
    *handle = NULL;
}

/* ---- the fake host --------------------------------------------------------------------- */

static bool host_push(const fp_host *host, const fp_event_header *ev)
{
    fp_test_host *h = host->host_data;
    pthread_mutex_lock(&h->lock);
    h->calls++;
    bool ok = true;
    if (ev->size > sizeof(fp_event)) {
        h->oversize++;
        ok = false;
    } else if (h->refuse_every && h->calls % h->refuse_every == 0) {
        ok = false;
    } else if (h->count_only && ev->type == FP_EVENT_JOINT_ANGLES) {
        h->angles++;
    } else {
        if (h->cap == 0 && h->count == h->alloc_) {
            size_t n = h->alloc_ ? 2 * h->alloc_ : 1024;
            fp_event *e = realloc(h->events, n * sizeof *e);
            if (e) h->events = e, h->alloc_ = n;
        }
        bool room = h->cap ? h->count < h->cap : h->count < h->alloc_;
        if (room) {
            fp_event *e = &h->events[h->count++];
            memset(e, 0, sizeof *e);
            memcpy(e, ev, ev->size);
            if (ev->type == FP_EVENT_STATUS && e->status.code == FP_STATUS_END_OF_STREAM)
                h->eos++;
        } else if (h->refuse_when_full) {
            ok = false;
        }
        if (ok && ev->type == FP_EVENT_JOINT_ANGLES) h->angles++;
    }
    if (!ok) h->refused++;
    pthread_cond_broadcast(&h->cond);
    pthread_mutex_unlock(&h->lock);
    return ok;
}

static int64_t host_now(const fp_host *host)
{
    (void)host;
    return fp_test_mono_ns();
}

static void host_log(const fp_host *host, fp_log_level level, const char *message)
{
    fp_test_host *h = host->host_data;
    pthread_mutex_lock(&h->lock);
    size_t n = strlen(h->log);
    snprintf(h->log + n, sizeof h->log - n, "%d %s\n", (int)level, message);
    snprintf(h->last_log, sizeof h->last_log, "%s", message);
    bool echo = level <= h->echo_level || getenv("FP_TEST_VERBOSE");
    pthread_mutex_unlock(&h->lock);
    if (echo) fprintf(stderr, "  [plugin %d] %s\n", (int)level, message);
}

static const void *host_extension(const fp_host *host, const char *id)
{
    (void)host, (void)id;
    return NULL;
}

void fp_test_host_init(fp_test_host *h, size_t cap)
{
    memset(h, 0, sizeof *h);
    h->host = (fp_host){.size = sizeof(fp_host),
                        .abi = {FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR},
                        .host_data = h,
                        .push_event = host_push,
                        .now_ns = host_now,
                        .log = host_log,
                        .get_extension = host_extension};
    pthread_mutex_init(&h->lock, NULL);
    pthread_cond_init(&h->cond, NULL);
    h->cap = cap;
    h->echo_level = FP_LOG_ERROR;
    if (cap) {
        h->events = calloc(cap, sizeof *h->events);
        assert_non_null(h->events);
        h->alloc_ = cap;
    }
}

void fp_test_host_clear(fp_test_host *h)
{
    pthread_mutex_destroy(&h->lock);
    pthread_cond_destroy(&h->cond);
    free(h->events);
    h->events = NULL;
}

fp_test_host *fp_test_host_new(size_t cap)
{
    fp_test_host *h = malloc(sizeof *h);
    assert_non_null(h);
    fp_test_host_init(h, cap);
    return h;
}

void fp_test_host_free(fp_test_host *h)
{
    if (!h) return;
    fp_test_host_clear(h);
    free(h);
}

size_t fp_test_host_count(fp_test_host *h)
{
    pthread_mutex_lock(&h->lock);
    size_t n = h->count;
    pthread_mutex_unlock(&h->lock);
    return n;
}

fp_event fp_test_host_get(fp_test_host *h, size_t i)
{
    pthread_mutex_lock(&h->lock);
    fp_event e = h->events[i];
    pthread_mutex_unlock(&h->lock);
    return e;
}

/* Wait on the condition for at most step_ms (the lock held). */
static void wait_step(fp_test_host *h, int step_ms)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    ts.tv_nsec += (long)step_ms * 1000000L;
    if (ts.tv_nsec >= 1000000000L) ts.tv_sec++, ts.tv_nsec -= 1000000000L;
    pthread_cond_timedwait(&h->cond, &h->lock, &ts);
}

int fp_test_host_wait(fp_test_host *h, size_t min_count, int64_t limit_ns)
{
    int64_t end = fp_test_mono_ns() + limit_ns;
    pthread_mutex_lock(&h->lock);
    bool ok;
    while (!(ok = min_count ? h->count >= min_count : h->eos > 0) && fp_test_mono_ns() < end)
        wait_step(h, 5);
    pthread_mutex_unlock(&h->lock);
    return ok ? 0 : -1;
}

long fp_test_host_wait_status(fp_test_host *h, size_t from, uint32_t code,
                              const char *text_part, int ms)
{
    int64_t deadline = fp_test_mono_ns() + (int64_t)ms * 1000000;
    pthread_mutex_lock(&h->lock);
    for (;;) {
        for (size_t i = from; i < h->count; i++)
            if (h->events[i].header.type == FP_EVENT_STATUS && h->events[i].status.code == code &&
                (!text_part || strstr(h->events[i].status.text, text_part))) {
                pthread_mutex_unlock(&h->lock);
                return (long)i;
            }
        from = h->count;
        if (fp_test_mono_ns() > deadline) break;
        wait_step(h, 20);
    }
    pthread_mutex_unlock(&h->lock);
    return -1;
}

long fp_test_host_wait_angles(fp_test_host *h, size_t from, size_t count, int ms)
{
    int64_t deadline = fp_test_mono_ns() + (int64_t)ms * 1000000;
    size_t seen = 0, i = from;
    pthread_mutex_lock(&h->lock);
    for (;;) {
        for (; i < h->count; i++)
            if (h->events[i].header.type == FP_EVENT_JOINT_ANGLES && ++seen == count) {
                pthread_mutex_unlock(&h->lock);
                return (long)i + 1;
            }
        if (fp_test_mono_ns() > deadline) break;
        wait_step(h, 20);
    }
    pthread_mutex_unlock(&h->lock);
    return -1;
}

bool fp_test_host_next(fp_test_host *h, fp_event *out, int timeout_ms)
{
    int64_t deadline = fp_test_mono_ns() + (int64_t)timeout_ms * 1000000;
    pthread_mutex_lock(&h->lock);
    while (h->read >= h->count && fp_test_mono_ns() < deadline) wait_step(h, 10);
    bool ok = h->read < h->count;
    if (ok) *out = h->events[h->read++];
    pthread_mutex_unlock(&h->lock);
    return ok;
}

size_t fp_test_host_unread(fp_test_host *h)
{
    pthread_mutex_lock(&h->lock);
    size_t n = h->count - h->read;
    pthread_mutex_unlock(&h->lock);
    return n;
}

/* ---- a session ------------------------------------------------------------------------- */

const struct fp_plugin_path *fp_test_plugin_path(void)
{
    static fp_plugin_path path;
    static bool done;
    if (!done) {
        const char *dirs[] = {fp_test_plugin_dir()};
        fp_plugin_path_init(&path, dirs, 1, NULL);
        done = true;
    }
    return &path;
}

void fp_test_face_options(fp_session_options *so, const char *mapping, const char *rig_dir)
{
    memset(so, 0, sizeof *so);
    so->mesh_path = fp_test_face_path();
    so->mapping = mapping;
    so->plugin_path = fp_test_plugin_path();
    so->rig_dir = rig_dir;
}

fp_session *fp_test_session_open(const fp_session_options *so)
{
    char err[2048];
    fp_session *s = NULL;
    int rc = fp_session_create(so, &s, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    rc = fp_session_start(s, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    return s;
}

fp_session *fp_test_session_start(const char *mapping, const char *const *inputs, int n)
{
    fp_session_options so;
    fp_test_face_options(&so, mapping, NULL);
    assert_true(n >= 0 && n <= (int)(sizeof so.inputs / sizeof so.inputs[0]));
    for (int i = 0; i < n; i++) so.inputs[i] = inputs[i];
    so.input_count = n;
    return fp_test_session_open(&so);
}

/* the waits' bound: 120 s, longer in slow builds */
static int64_t wait_limit(void) { return fp_test_mono_ns() + 120LL * 1000000000LL * fp_test_time_scale(); }

int64_t fp_test_session_t0(fp_session *s)
{
    int64_t t0 = 0, limit = wait_limit();
    int clock;
    while ((clock = fp_session_input_start(s, &t0)) == 0 && fp_test_mono_ns() < limit) fp_test_nap_ms(1);
    if (clock != 1) fail_msg("the session's input clock: %s", clock ? "no input is a recording" : "none within the wait");
    return t0;
}

int64_t fp_test_frame_time(fp_session *s, int64_t t0, uint64_t k, double fps)
{
    int64_t now = t0 + (int64_t)llround((double)k * 1e9 / fps), limit = wait_limit();
    while (!fp_session_inputs_ready(s, now)) {
        if (fp_test_mono_ns() >= limit) fail_msg("frame %llu: the inputs not ready within the wait", (unsigned long long)k);
        fp_test_nap_ms(1);
    }
    return now;
}
