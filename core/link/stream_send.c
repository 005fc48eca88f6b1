/* The live output stream, the frame thread's side (fp_stream.h; the format: docs/osc.md,
 * "Stream"): the options, the offsets quantised where the mesh moved, the frame's records
 * handed to the sender thread (stream_tx.c), which makes and sends the packets. */
#define _GNU_SOURCE
#include "stream_internal.h"

#include "fp_clock.h"
#include "fp_error.h"
#include "fp_stats.h"
#include "facepuppet/decimal.h"
#include "facepuppet/plugin_util.h"

#include <errno.h>
#include <math.h>
#include <netdb.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define RECORD_BYTES 8           /* (stream_tx.c's) */
#define BLOCK 64                 /* vertices compared with the last frame's at once (memcmp) */

/* "osc:HOST:PORT[,step=MM][,key=N][,mtu=B]" into *s (host, port, step, key, mtu). */
static int parse(const char *spec, fp_stream *s, char *err, size_t errlen)
{
    s->step_mm = 0.05;
    s->key_period = 30;
    s->mtu = 1400;
    if (!spec || strncmp(spec, "osc:", 4))
        return fp_errorf(err, errlen, -EINVAL, "%s: expected osc:HOST:PORT[,step=MM][,key=FRAMES][,mtu=BYTES]",
                         spec ? spec : "(null)");
    const char *p = spec + 4, *comma = strchr(p, ','), *end = comma ? comma : p + strlen(p);
    const char *colon = NULL;
    for (const char *q = p; q < end; q++)
        if (*q == ':') colon = q;
    if (!colon || colon == p || (size_t)(colon - p) >= sizeof s->host || end - colon - 1 >= (long)sizeof s->port)
        return fp_errorf(err, errlen, -EINVAL, "%s: expected osc:HOST:PORT", spec);
    snprintf(s->host, sizeof s->host, "%.*s", (int)(colon - p), p);
    snprintf(s->port, sizeof s->port, "%.*s", (int)(end - colon - 1), colon + 1);
    unsigned long long port;
    if (!fp_parse_whole(s->port, 65535, &port) || port == 0)
        return fp_errorf(err, errlen, -EINVAL, "%s: PORT must be 1..65535", spec);
    while (comma) {
        const char *k = comma + 1;
        comma = strchr(k, ',');
        char kv[64];
        snprintf(kv, sizeof kv, "%.*s", comma ? (int)(comma - k) : (int)strlen(k), k);
        char *eq = strchr(kv, '=');
        double v;
        unsigned long long w;
        if (!eq) return fp_errorf(err, errlen, -EINVAL, "%s: key '%s' without a value", spec, kv);
        *eq++ = '\0';
        if (!strcmp(kv, "step")) {
            if (!fp_parse_decimal(eq, &v) || !(v >= 0.001 && v <= 0.1))
                return fp_errorf(err, errlen, -EINVAL, "%s: step must be 0.001..0.1 mm", spec);
            s->step_mm = v;
        } else if (!strcmp(kv, "key")) {
            if (!fp_parse_whole(eq, 100000, &w) || w < 1)
                return fp_errorf(err, errlen, -EINVAL, "%s: key must be 1..100000 frames", spec);
            s->key_period = (unsigned)w;
        } else if (!strcmp(kv, "mtu")) {
            if (!fp_parse_whole(eq, 65000, &w) || w < 576)
                return fp_errorf(err, errlen, -EINVAL, "%s: mtu must be 576..65000 bytes", spec);
            s->mtu = (unsigned)w;
        } else {
            return fp_errorf(err, errlen, -EINVAL, "%s: unknown key '%s' (step, key, mtu)", spec, kv);
        }
    }
    return 0;
}

int fp_stream_spec_check(const char *spec, char *err, size_t errlen)
{
    fp_stream *s = calloc(1, sizeof *s); /* (some 100 kB: not on the stack) */
    if (!s) return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    int rc = parse(spec, s, err, errlen);
    free(s);
    return rc;
}

/* The test knob FP_STREAM_DROP=P[:FRAMES], FP_STREAM_SEED. */
static void drop_knob(fp_stream *s)
{
    const char *d = getenv("FP_STREAM_DROP"), *seed = getenv("FP_STREAM_SEED");
    s->rng = 0x9E3779B97F4A7C15ull ^ (seed ? strtoull(seed, NULL, 10) : 1);
    if (!d) return;
    char buf[64];
    snprintf(buf, sizeof buf, "%s", d);
    char *colon = strchr(buf, ':');
    if (colon) *colon++ = '\0';
    double p;
    unsigned long long f = 0;
    if (fp_parse_decimal(buf, &p) && p >= 0 && p <= 1 && (!colon || fp_parse_whole(colon, UINT64_MAX, &f))) {
        s->drop_p = p;
        s->drop_frames = f;
    }
}

/* The socket to HOST:PORT (connected: send() needs no address). */
static int open_socket(fp_stream *s, char *err, size_t errlen)
{
    struct addrinfo hints = {.ai_family = AF_INET, .ai_socktype = SOCK_DGRAM}, *ai = NULL;
    int g = getaddrinfo(s->host, s->port, &hints, &ai);
    if (g) return fp_errorf(err, errlen, -ENOENT, "%s: host %s: %s", s->o.spec, s->host, gai_strerror(g));
    s->sock = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    int big = 4 << 20, rc = 0;
    if (s->sock >= 0) setsockopt(s->sock, SOL_SOCKET, SO_SNDBUF, &big, sizeof big);
    if (s->sock < 0 || connect(s->sock, ai->ai_addr, ai->ai_addrlen) != 0)
        rc = fp_errorf(err, errlen, -errno, "%s: %s", s->o.spec, strerror(errno));
    freeaddrinfo(ai);
    return rc;
}

int fp_stream_open(const fp_stream_options *o, fp_stream **out, char *err, size_t errlen)
{
    *out = NULL;
    if (!o->neutral || !o->n || !(o->mm_per_unit > 0) || o->nchannels > FP_STREAM_MAX_CHANNELS ||
        o->n > UINT32_MAX / 2)
        return fp_errorf(err, errlen, -EINVAL, "a stream needs a mesh, its unit and at most %d channels",
                         FP_STREAM_MAX_CHANNELS);
    fp_stream *s = calloc(1, sizeof *s);
    if (!s) return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    int rc = parse(o->spec, s, err, errlen);
    if (rc) { free(s); return rc; }
    s->o = *o;
    s->sock = -1;
    s->max_records = (s->mtu - 128 - 5 * o->nchannels) / RECORD_BYTES;
    pthread_mutex_init(&s->mu, NULL);
    pthread_cond_init(&s->cond, NULL);
    pthread_cond_init(&s->space, NULL);
    if ((rc = open_socket(s, err, errlen))) goto fail;
    s->sent = calloc(3 * o->n, sizeof *s->sent);
    s->idx = malloc(o->n * sizeof *s->idx);
    s->q = malloc(3 * o->n * sizeof *s->q);
    s->last = malloc(3 * o->n * sizeof *s->last);
    if (!s->sent || !s->idx || !s->q || !s->last || fp__stream_tx_init(s)) {
        rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory for %zu vertices", o->spec, o->n);
        goto fail;
    }
    memcpy(s->last, o->neutral, 3 * o->n * sizeof *s->last); /* (sent: all 0, the neutral's) */
    s->key_requested = true; /* the first frame is a keyframe */
    drop_knob(s);
    if ((rc = -pthread_create(&s->thread, NULL, fp__stream_tx, s))) {
        fp_errorf(err, errlen, rc, "%s: cannot start the sender thread: %s", o->spec, strerror(-rc));
        goto fail;
    }
    s->thread_ok = true;
    *out = s;
    return 0;
fail:
    fp_stream_close(&s);
    return rc;
}

void fp_stream_origin(fp_stream *st, int64_t t0_ns) { st->t0_ns = t0_ns; }
void fp_stream_request_key(fp_stream *st) { st->key_requested = true; }

/* The block [b0, b1) meets a touched range (ranges from *r on, which is advanced). */
static bool block_touched(const uint32_t *ranges, size_t nranges, size_t *r, size_t b0, size_t b1)
{
    while (*r < nranges && (size_t)ranges[2 * *r] + ranges[2 * *r + 1] <= b0) (*r)++;
    return *r < nranges && ranges[2 * *r] < b1;
}

/* An offset in steps (d: mesh units x scale), rounded half away from zero, in float (the
 * decoder's tolerance holds: within half a step, plus float rounding); beyond +-32767
 * clipped (counted), not finite 0. */
static inline int16_t quantise(float d, uint64_t *clipped)
{
    if (!(d > -32767.5f && d < 32767.5f)) {
        if (d == d) (*clipped)++;
        return d > 0 ? 32767 : d < 0 ? -32767 : 0;
    }
    return (int16_t)(d + (d >= 0 ? 0.5f : -0.5f));
}

/* The frame's records into idx and q: every changed offset, or every non-zero one (key: after
 * a frame's records were lost; a keyframe is made by the sender thread from what it was
 * handed, so the frame thread never scans the whole mesh for one); the blocks compared are
 * those in the touched ranges (all: ranges NULL with nranges > 0, or SIZE_MAX, or a full
 * scan owed after a frame not handed over). */
static size_t collect(fp_stream *s, const float *pos, bool key, const uint32_t *ranges, size_t nranges)
{
    const float *nu = s->o.neutral;
    const float scale = (float)(s->o.mm_per_unit / s->step_mm);
    const size_t n = s->o.n;
    size_t m = 0, r = 0;
    const bool all = nranges == SIZE_MAX || (!ranges && nranges) || s->full_scan;
    s->full_scan = false;
    for (size_t b0 = 0; b0 < n; b0 += BLOCK) {
        const size_t b1 = b0 + BLOCK < n ? b0 + BLOCK : n, bytes = 3 * (b1 - b0) * sizeof(float);
        const bool in = all || block_touched(ranges, nranges, &r, b0, b1);
        if (!in && !key) {
            if (r >= nranges) break; /* (nothing further moved) */
            b0 = (size_t)ranges[2 * r] / BLOCK * BLOCK - BLOCK; /* (on to the next touched block) */
            continue;
        }
        const bool moved = in && memcmp(pos + 3 * b0, s->last + 3 * b0, bytes) != 0; /* (most do not) */
        for (size_t v = b0; v < b1 && (moved || key); v++) {
            int16_t *old = s->sent + 3 * v;
            const float *p = pos + 3 * v, *l = s->last + 3 * v;
            bool changed = false;
            if (moved && (p[0] != l[0] || p[1] != l[1] || p[2] != l[2])) { /* (NaN: always) */
                int16_t q[3];
                for (int k = 0; k < 3; k++) q[k] = quantise((p[k] - nu[3 * v + k]) * scale, &s->clipped);
                memcpy(s->last + 3 * v, p, 3 * sizeof *p);
                changed = q[0] != old[0] || q[1] != old[1] || q[2] != old[2];
                if (changed) memcpy(old, q, sizeof q);
            }
            if (key ? (old[0] | old[1] | old[2]) != 0 : changed) {
                s->idx[m] = (uint32_t)v;
                memcpy(s->q + 3 * m, old, 3 * sizeof *old);
                m++;
            }
        }
    }
    return m;
}

/* The job's arrays for m records (grown, rarely). */
static int job_reserve(stream_job *j, size_t m)
{
    if (m <= j->cap) return 0;
    size_t cap = m + m / 2 + 64;
    uint32_t *idx = realloc(j->idx, cap * sizeof *idx);
    if (idx) j->idx = idx;
    int16_t *q = realloc(j->q, 3 * cap * sizeof *q);
    if (q) j->q = q;
    if (!idx || !q) return -ENOMEM;
    j->cap = cap;
    return 0;
}

int fp_stream_frame(fp_stream *s, const float *pos, const float *channels, int64_t now_ns,
                    const char *timecode)
{
    return fp_stream_frame_ranges(s, pos, NULL, SIZE_MAX, channels, now_ns, timecode);
}

int fp_stream_frame_ranges(fp_stream *s, const float *pos, const uint32_t *ranges, size_t nranges,
                           const float *channels, int64_t now_ns, const char *timecode)
{
    int64_t t_start = fp_now_ns();
    const uint64_t frame = s->frame++;
    size_t head = atomic_load_explicit(&s->head, memory_order_relaxed);
    int rc = 0;
    if (s->o.wait && head - atomic_load_explicit(&s->tail, memory_order_acquire) >= STREAM_JOBS) {
        pthread_mutex_lock(&s->mu); /* (run, play: no frame lost; the sender frees a job soon) */
        while (head - atomic_load_explicit(&s->tail, memory_order_acquire) >= STREAM_JOBS)
            pthread_cond_wait(&s->space, &s->mu);
        pthread_mutex_unlock(&s->mu);
    }
    if (head - atomic_load_explicit(&s->tail, memory_order_acquire) >= STREAM_JOBS) {
        /* the sender is behind: the frame is not sent (a receiver sees it lost), the next
         * one is a keyframe over every block */
        s->busy++;
        s->key_requested = s->full_scan = true;
        rc = -EAGAIN;
    } else {
        const bool key = s->key_requested || frame % s->key_period == 0, full = s->resync;
        s->key_requested = false;
        size_t m = collect(s, pos, full, ranges, nranges);
        stream_job *j = &s->jobs[head % STREAM_JOBS];
        if (job_reserve(j, m)) {
            /* (its changes are lost: the next job carries every offset) */
            s->key_requested = s->full_scan = s->resync = true;
            rc = -ENOMEM;
        } else {
            s->resync = false;
            j->frame = frame;
            j->key = key;
            j->full = full;
            j->t = (double)(now_ns - s->t0_ns) * 1e-9;
            snprintf(j->tc, sizeof j->tc, "%s", timecode ? timecode : "");
            for (size_t c = 0; c < s->o.nchannels; c++) j->channels[c] = channels ? channels[c] : 0.0f;
            j->m = m;
            if (m) { /* (none moved: the buffers may not exist yet) */
                memcpy(j->idx, s->idx, m * sizeof *j->idx);
                memcpy(j->q, s->q, 3 * m * sizeof *j->q);
            }
            atomic_store_explicit(&s->head, head + 1, memory_order_release);
            pthread_mutex_lock(&s->mu);
            pthread_cond_signal(&s->cond);
            pthread_mutex_unlock(&s->mu);
            s->keyframes += key;
        }
    }
    s->times[s->frames % STREAM_TIMES] = (double)(fp_now_ns() - t_start) * 1e-3;
    s->frames++;
    return rc;
}

/* Median, p99 and max of the last n (at most STREAM_TIMES) of v. */
static void percentiles(const double *v, uint64_t count, double out[3])
{
    size_t n = count < STREAM_TIMES ? (size_t)count : STREAM_TIMES;
    double *copy = n ? malloc(n * sizeof *copy) : NULL;
    out[0] = out[1] = out[2] = 0;
    if (!copy) return;
    memcpy(copy, v, n * sizeof *copy);
    out[0] = fp_median(copy, n);
    out[1] = fp_percentile(copy, n, 0.99);
    out[2] = fp_percentile(copy, n, 1.0);
    free(copy);
}

void fp_stream_stats_get(const fp_stream *s, fp_stream_stats *out)
{
    memset(out, 0, sizeof *out);
    out->frames = s->frames;
    out->keyframes = s->keyframes;
    out->clipped = s->clipped;
    out->busy = s->busy;
    out->packets = atomic_load_explicit(&s->packets, memory_order_relaxed);
    out->bytes = atomic_load_explicit(&s->bytes, memory_order_relaxed);
    out->records = atomic_load_explicit(&s->records, memory_order_relaxed);
    out->dropped = atomic_load_explicit(&s->dropped, memory_order_relaxed);
    out->send_errors = atomic_load_explicit(&s->send_errors, memory_order_relaxed);
    double p[3];
    percentiles(s->times, s->frames, p);
    out->send_us_median = p[0], out->send_us_p99 = p[1], out->send_us_max = p[2];
    uint64_t sent = atomic_load_explicit(&s->sent_frames, memory_order_acquire);
    percentiles(s->tx_times, sent, p);
    out->tx_us_median = p[0], out->tx_us_p99 = p[1];
}

void fp_stream_describe(const fp_stream *s, char *buf, size_t n)
{
    snprintf(buf, n, "to %s:%s, %zu vertices, step %.3g mm (a vertex within %.3g mm), keyframe every "
             "%u frames, packets of at most %u bytes (%zu offsets)", s->host, s->port, s->o.n, s->step_mm,
             s->step_mm * sqrt(3.0) / 2, s->key_period, s->mtu, s->max_records);
}

void fp_stream_summary(fp_stream *s, char *buf, size_t n)
{
    fp_stream_finish(s);
    fp_stream_stats st;
    fp_stream_stats_get(s, &st);
    snprintf(buf, n, "%llu frames (%llu keyframes), %llu packets, %llu bytes, %llu offsets; the frame "
             "thread's part median %.1f us, p99 %.1f us a frame, the sender thread's median %.1f us, "
             "p99 %.1f us; frames not sent (sender behind) %llu, dropped by FP_STREAM_DROP %llu, send "
             "errors %llu, clipped %llu", (unsigned long long)st.frames, (unsigned long long)st.keyframes,
             (unsigned long long)st.packets, (unsigned long long)st.bytes, (unsigned long long)st.records,
             st.send_us_median, st.send_us_p99, st.tx_us_median, st.tx_us_p99,
             (unsigned long long)st.busy, (unsigned long long)st.dropped,
             (unsigned long long)st.send_errors, (unsigned long long)st.clipped);
}

void fp_stream_finish(fp_stream *s)
{
    if (!s || !s->thread_ok) return;
    pthread_mutex_lock(&s->mu);
    s->stop = true;
    pthread_cond_signal(&s->cond);
    pthread_mutex_unlock(&s->mu);
    pthread_join(s->thread, NULL);
    s->thread_ok = false;
}

void fp_stream_close(fp_stream **sp)
{
    fp_stream *s = sp ? *sp : NULL;
    if (!s) return;
    fp_stream_finish(s);
    if (s->sock >= 0) close(s->sock);
    for (int k = 0; k < STREAM_JOBS; k++) {
        free(s->jobs[k].idx);
        free(s->jobs[k].q);
    }
    fp__stream_tx_free(s);
    free(s->sent);
    free(s->idx);
    free(s->q);
    free(s->last);
    pthread_mutex_destroy(&s->mu);
    pthread_cond_destroy(&s->cond);
    pthread_cond_destroy(&s->space);
    free(s);
    *sp = NULL;
}
