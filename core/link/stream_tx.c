/* The stream's sender thread (stream_internal.h): each frame handed over by the frame thread
 * is quantised from its snapshot (stream_collect.c), its records split into packets of at
 * most mtu bytes over consecutive vertex ranges, serialised by liblo (docs/osc.md, "Stream")
 * and sent with one sendmmsg; /fp/stream/info before each keyframe; the test knob
 * FP_STREAM_DROP drops packets here. */
#define _GNU_SOURCE
#include "stream_internal.h"

#include "fp_clock.h"

#include <errno.h>
#include <lo/lo.h>
#include <pthread.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RECORD_BYTES 8           /* u16 index gap, 3 x i16 offset (after a u32 count) */
#define MAX_GAP 65535u
#define SLOT_SLACK 256           /* a packet's slot: mtu plus this */

static void bump(_Atomic uint64_t *c, uint64_t k) { atomic_fetch_add_explicit(c, k, memory_order_relaxed); }

int fp__stream_tx_init(fp_stream *s)
{
    s->slot_size = s->mtu + SLOT_SLACK;
    s->blob = malloc(4 + s->max_records * RECORD_BYTES);
    s->tx_state = calloc(3 * s->o.n, sizeof *s->tx_state);
    return s->blob && s->tx_state ? 0 : -ENOMEM;
}

void fp__stream_tx_free(fp_stream *s)
{
    free(s->blob);
    free(s->slots);
    free(s->msgs);
    free(s->iov);
    free(s->starts);
    free(s->tx_state);
    free(s->tx_key.idx);
    free(s->tx_key.q);
    free(s->tx_rec.idx);
    free(s->tx_rec.q);
}

/* The job to send: j, or for a keyframe every non-zero offset of the state, with j's header
 * (NULL: no memory, counted). */
static const stream_job *keyframe(fp_stream *s, const stream_job *j)
{
    if (!j->key) return j;
    stream_job *k = &s->tx_key;
    size_t m = 0;
    for (size_t v = 0; v < s->o.n; v++) {
        const int16_t *q = s->tx_state + 3 * v;
        if (!(q[0] | q[1] | q[2])) continue;
        if (m == k->cap && fp__stream_reserve(k, 2 * k->cap + 1024)) return NULL;
        k->idx[m] = (uint32_t)v;
        memcpy(k->q + 3 * m, q, 3 * sizeof *q);
        m++;
    }
    k->frame = j->frame, k->key = true, k->t = j->t, k->m = m;
    memcpy(k->tc, j->tc, sizeof k->tc);
    memcpy(k->channels, j->channels, sizeof k->channels);
    return k;
}

static bool drop_now(fp_stream *s, uint64_t frame)
{
    if (!(s->drop_p > 0) || (s->drop_frames && frame >= s->drop_frames)) return false;
    s->rng ^= s->rng << 13; s->rng ^= s->rng >> 7; s->rng ^= s->rng << 17;
    return (double)(s->rng >> 11) * 0x1p-53 < s->drop_p;
}

/* Room for k packets (grown, rarely: a frame larger than any before). */
static int slots_reserve(fp_stream *s, size_t k)
{
    if (k <= s->nslots) return 0;
    unsigned char *slots = realloc(s->slots, k * s->slot_size);
    if (slots) s->slots = slots;
    struct mmsghdr *msgs = realloc(s->msgs, k * sizeof *msgs);
    if (msgs) s->msgs = msgs;
    struct iovec *iov = realloc(s->iov, k * sizeof *iov);
    if (iov) s->iov = iov;
    if (!slots || !msgs || !iov) return -ENOMEM;
    s->nslots = k;
    return 0;
}

/* Serialise m at path into the frame's next slot (*used of them), or drop it (the knob). */
static void queue_message(fp_stream *s, lo_message m, const char *path, size_t *used, uint64_t frame)
{
    size_t size = lo_message_length(m, path);
    bump(&s->packets, 1);
    unsigned char *slot = s->slots + *used * s->slot_size;
    if (*used >= s->nslots || size > s->slot_size || !lo_message_serialise(m, path, slot, &size)) {
        bump(&s->send_errors, 1);
        return;
    }
    s->seq++;
    if (drop_now(s, frame)) {
        bump(&s->dropped, 1);
        return;
    }
    s->iov[*used] = (struct iovec){slot, size};
    s->msgs[*used] = (struct mmsghdr){.msg_hdr = {.msg_iov = &s->iov[*used], .msg_iovlen = 1}};
    bump(&s->bytes, size);
    (*used)++;
}

/* Send the frame's queued packets: one sendmmsg (more when the kernel takes fewer). */
static void flush(fp_stream *s, size_t used)
{
    for (size_t at = 0; at < used;) {
        int k = sendmmsg(s->sock, s->msgs + at, (unsigned)(used - at), 0);
        if (k <= 0) { /* the rest is lost (counted) */
            bump(&s->send_errors, used - at);
            return;
        }
        at += (size_t)k;
    }
}

/* /fp/stream/info before a keyframe: serialised and sent alone (its path may be long). */
static void send_info(fp_stream *s, uint64_t frame)
{
    lo_message m = lo_message_new();
    if (!m) { bump(&s->send_errors, 1); return; }
    lo_message_add_int32(m, (int32_t)s->seq);
    lo_message_add_int32(m, (int32_t)s->o.n);
    lo_message_add_double(m, s->o.mm_per_unit);
    lo_message_add_double(m, s->step_mm);
    lo_message_add_int32(m, (int32_t)s->key_period);
    lo_message_add_double(m, s->o.fps);
    lo_message_add_int32(m, (int32_t)s->o.mesh_crc32);
    lo_message_add_string(m, s->o.mesh_path ? s->o.mesh_path : "");
    for (size_t c = 0; c < s->o.nchannels; c++) lo_message_add_string(m, s->o.channels[c]);
    size_t size = lo_message_length(m, "/fp/stream/info");
    void *buf = lo_message_serialise(m, "/fp/stream/info", NULL, &size);
    bump(&s->packets, 1);
    if (!buf) bump(&s->send_errors, 1);
    else {
        s->seq++;
        if (drop_now(s, frame)) bump(&s->dropped, 1);
        else if (send(s->sock, buf, size, 0) < 0) bump(&s->send_errors, 1);
        else bump(&s->bytes, size);
    }
    free(buf);
    lo_message_free(m);
}

static void put16(unsigned char *p, uint16_t v) { p[0] = (unsigned char)(v >> 8); p[1] = (unsigned char)v; }

/* One packet: the job's records [a, b), covering vertices [lo, hi). */
static void packet(fp_stream *s, const stream_job *j, size_t a, size_t b, uint32_t lo, uint32_t hi,
                   int part, int parts, size_t *used)
{
    uint32_t prev = lo, count = (uint32_t)(b - a);
    for (int k = 0; k < 4; k++) s->blob[k] = (unsigned char)(count >> (24 - 8 * k)); /* (never empty) */
    for (size_t r = a; r < b; r++) {
        unsigned char *p = s->blob + 4 + (r - a) * RECORD_BYTES;
        put16(p, (uint16_t)(j->idx[r] - prev));
        prev = j->idx[r];
        for (int k = 0; k < 3; k++) put16(p + 2 + 2 * k, (uint16_t)j->q[3 * r + k]);
    }
    lo_blob blob = lo_blob_new((int32_t)(4 + (b - a) * RECORD_BYTES), s->blob);
    lo_message m = lo_message_new();
    if (!m || !blob) {
        bump(&s->send_errors, 1);
        if (m) lo_message_free(m);
        if (blob) lo_blob_free(blob);
        return;
    }
    lo_message_add_int32(m, (int32_t)s->seq);
    lo_message_add_int32(m, (int32_t)j->frame);
    lo_message_add_int32(m, j->key ? 1 : 0);
    lo_message_add_double(m, j->t);
    lo_message_add_string(m, j->tc);
    lo_message_add_int32(m, part);
    lo_message_add_int32(m, parts);
    lo_message_add_int32(m, (int32_t)lo);
    lo_message_add_int32(m, (int32_t)hi);
    lo_message_add_blob(m, blob);
    for (size_t c = 0; c < s->o.nchannels; c++) lo_message_add_float(m, j->channels[c]);
    queue_message(s, m, "/fp/stream/frame", used, j->frame);
    lo_message_free(m);
    lo_blob_free(blob);
    bump(&s->records, b - a);
}

/* One frame out: split (at most max_records a packet; an index gap above MAX_GAP starts a
 * new one), serialised, sent. */
static void send_records(fp_stream *s, const stream_job *j)
{
    if (j->m + 1 > s->nstarts) {
        size_t *grown = realloc(s->starts, (j->m + 1) * sizeof *grown);
        if (!grown) { bump(&s->send_errors, 1); return; }
        s->starts = grown;
        s->nstarts = j->m + 1;
    }
    size_t nparts = 1;
    s->starts[0] = 0;
    for (size_t r = 0, lo = 0; r < j->m; r++) {
        size_t count = r - s->starts[nparts - 1];
        size_t gap = j->idx[r] - (count ? j->idx[r - 1] : lo);
        if (count >= s->max_records || gap > MAX_GAP) {
            s->starts[nparts++] = r;
            lo = j->idx[r];
        }
    }
    if (j->key) send_info(s, j->frame);
    size_t used = 0;
    if (slots_reserve(s, nparts)) nparts = 0; /* (out of memory: the frame is lost, counted) */
    for (size_t k = 0; k < nparts; k++) {
        size_t a = s->starts[k], b = k + 1 < nparts ? s->starts[k + 1] : j->m;
        uint32_t lo = k == 0 ? 0 : j->idx[a];
        uint32_t hi = k + 1 < nparts ? j->idx[b] : (uint32_t)s->o.n;
        packet(s, j, a, b, lo, hi, (int)k, (int)nparts, &used);
    }
    flush(s, used);
}

/* One frame handed over: its snapshot quantised into records (the snapshot then freed), a
 * keyframe when due or owed (records lost for want of memory), sent. */
static void send_hand(fp_stream *s, const stream_hand *h)
{
    int64_t t_start = fp_now_ns();
    const int rc = fp__stream_collect(s, h);
    atomic_store_explicit(&s->snap_busy[h->snap], false, memory_order_release);
    if (s->o.wait) { /* (a frame thread may wait for a snapshot) */
        pthread_mutex_lock(&s->mu);
        pthread_cond_signal(&s->space);
        pthread_mutex_unlock(&s->mu);
    }
    stream_job *rec = &s->tx_rec;
    rec->frame = h->head.frame;
    rec->key = h->head.key || rc || s->tx_key_owed;
    rec->t = h->head.t;
    memcpy(rec->tc, h->head.tc, sizeof rec->tc);
    memcpy(rec->channels, h->head.channels, sizeof rec->channels);
    const stream_job *j = keyframe(s, rec);
    s->tx_key_owed = !j;
    if (j) send_records(s, j);
    else bump(&s->send_errors, 1);
    uint64_t done = atomic_load_explicit(&s->sent_frames, memory_order_relaxed);
    s->tx_times[done % STREAM_TIMES] = (double)(fp_now_ns() - t_start) * 1e-3;
    atomic_store_explicit(&s->sent_frames, done + 1, memory_order_release);
}

void fp__stream_batch(void)
{
    const struct sched_param batch = {0};
    (void)pthread_setschedparam(pthread_self(), SCHED_BATCH, &batch);
}

void *fp__stream_tx(void *arg)
{
    fp_stream *s = arg;
    fp__stream_batch();
    for (;;) {
        pthread_mutex_lock(&s->mu);
        while (atomic_load_explicit(&s->tail, memory_order_relaxed) ==
                   atomic_load_explicit(&s->head, memory_order_acquire) && !s->stop)
            pthread_cond_wait(&s->cond, &s->mu);
        bool stop = s->stop;
        pthread_mutex_unlock(&s->mu);
        size_t tail = atomic_load_explicit(&s->tail, memory_order_relaxed);
        size_t head = atomic_load_explicit(&s->head, memory_order_acquire);
        for (; tail != head; tail++) {
            send_hand(s, &s->jobs[tail % STREAM_JOBS]);
            atomic_store_explicit(&s->tail, tail + 1, memory_order_release);
            if (s->o.wait) { /* (a frame thread may wait for room) */
                pthread_mutex_lock(&s->mu);
                pthread_cond_signal(&s->space);
                pthread_mutex_unlock(&s->mu);
            }
        }
        if (stop && tail == atomic_load_explicit(&s->head, memory_order_acquire)) return NULL;
    }
}
