/* The live output stream, the frame thread's side (fp_stream.h; the format: docs/osc.md,
 * "Stream"): the options, the frame's touched blocks copied into a snapshot (stream_snap.c)
 * and handed to the sender thread, which quantises them (stream_collect.c), makes and sends
 * the packets (stream_tx.c); the statistics. */
#define _GNU_SOURCE
#include "stream_internal.h"

#include "fp_clock.h"
#include "fp_error.h"
#include "fp_net.h"
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

/* The socket to HOST:PORT (connected: send() needs no address; IPv4 or IPv6: fp_net.h). */
static int open_socket(fp_stream *s, char *err, size_t errlen)
{
    char why[256];
    s->sock = fp_udp_connect(s->host, s->port, 0, why, sizeof why);
    if (s->sock < 0) return fp_errorf(err, errlen, s->sock, "%s: host %s: %s", s->o.spec, s->host, why);
    int big = 4 << 20;
    setsockopt(s->sock, SOL_SOCKET, SO_SNDBUF, &big, sizeof big);
    return 0;
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
    if (fp__stream_tx_init(s) || fp__stream_snap_open(s)) {
        rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory for %zu vertices", o->spec, o->n);
        goto fail;
    }
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

int fp_stream_frame(fp_stream *s, const float *pos, const float *channels, int64_t now_ns,
                    const char *timecode)
{
    return fp_stream_frame_ranges(s, pos, NULL, SIZE_MAX, channels, now_ns, timecode);
}

/* Room for the frame at head: a free place in the ring and a free snapshot (*snap); with
 * o.wait (run, play: no frame lost) it waits for the sender to free them. */
static bool room(fp_stream *s, size_t head, int *snap)
{
    *snap = -1;
    if (!s->o.wait)
        return head - atomic_load_explicit(&s->tail, memory_order_acquire) < STREAM_JOBS &&
               (*snap = fp__stream_snap_take(s)) >= 0;
    pthread_mutex_lock(&s->mu);
    while (head - atomic_load_explicit(&s->tail, memory_order_acquire) >= STREAM_JOBS ||
           (*snap = fp__stream_snap_take(s)) < 0)
        pthread_cond_wait(&s->space, &s->mu);
    pthread_mutex_unlock(&s->mu);
    return true;
}

int fp_stream_frame_ranges(fp_stream *s, const float *pos, const uint32_t *ranges, size_t nranges,
                           const float *channels, int64_t now_ns, const char *timecode)
{
    int64_t t_start = fp_now_ns();
    const uint64_t frame = s->frame++;
    size_t head = atomic_load_explicit(&s->head, memory_order_relaxed);
    stream_hand *h = &s->jobs[head % STREAM_JOBS];
    const bool all = nranges == SIZE_MAX || (!ranges && nranges) || s->full_scan;
    int rc = 0, snap;
    if (!room(s, head, &snap)) {
        /* the sender is behind: the frame is not sent (a receiver sees it lost), the next
         * one is a keyframe over every block */
        s->busy++;
        s->key_requested = s->full_scan = true;
        rc = -EAGAIN;
    } else if (fp__stream_snap_ranges(h, ranges, nranges, all, s->o.n)) {
        atomic_store_explicit(&s->snap_busy[snap], false, memory_order_release);
        s->key_requested = s->full_scan = true; /* (the same: not sent) */
        rc = -ENOMEM;
    } else {
        const bool key = s->key_requested || frame % s->key_period == 0;
        s->key_requested = s->full_scan = false;
        h->snap = snap;
        fp__stream_snap_copy(s, h, pos);
        stream_job *j = &h->head;
        j->frame = frame;
        j->key = key;
        j->t = (double)(now_ns - s->t0_ns) * 1e-9;
        snprintf(j->tc, sizeof j->tc, "%s", timecode ? timecode : "");
        for (size_t c = 0; c < s->o.nchannels; c++) j->channels[c] = channels ? channels[c] : 0.0f;
        atomic_store_explicit(&s->head, head + 1, memory_order_release);
        pthread_mutex_lock(&s->mu);
        pthread_cond_signal(&s->cond);
        pthread_mutex_unlock(&s->mu);
        s->keyframes += key;
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
    out->clipped = atomic_load_explicit(&s->clipped, memory_order_relaxed);
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
    fp__stream_snap_free(s);
    fp__stream_tx_free(s);
    pthread_mutex_destroy(&s->mu);
    pthread_cond_destroy(&s->cond);
    pthread_cond_destroy(&s->space);
    free(s);
    *sp = NULL;
}
