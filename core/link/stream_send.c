/* The live output stream's sender (fp_stream.h; the format: docs/osc.md, "Stream"). */
#define _GNU_SOURCE
#include "fp_stream.h"

#include "fp_clock.h"
#include "fp_error.h"
#include "fp_stats.h"
#include "facepuppet/decimal.h"
#include "facepuppet/plugin_util.h"

#include <errno.h>
#include <lo/lo.h>
#include <math.h>
#include <netdb.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#define TIMES 4096               /* per-frame send times kept for the percentiles */
#define RECORD_BYTES 8           /* u16 index gap, 3 x i16 offset (after a u32 count) */
#define MAX_GAP 65535u
#define BLOCK 64                 /* vertices compared with the last frame's at once (memcmp) */
#define SLOT_SLACK 256           /* a packet's slot: mtu plus this */

struct fp_stream {
    fp_stream_options o;
    char host[256], port[8];
    double step_mm;              /* quantisation step */
    unsigned key_period;         /* frames between keyframes */
    unsigned mtu;                /* bytes of a datagram at most */
    size_t max_records;          /* records per packet */
    int sock;
    int16_t *sent;               /* n x 3: the quantised offsets last sent */
    float *last;                 /* n x 3: the positions last quantised */
    unsigned char *slots;        /* the frame's packets, serialised, nslots x slot_size */
    size_t nslots, slot_size;
    struct mmsghdr *msgs;        /* one sendmmsg for them */
    struct iovec *iov;
    uint32_t *idx;               /* the frame's records: vertex indices */
    size_t *starts;              /* the record each packet of the frame starts at */
    int16_t *q;                  /* ... and their offsets (3 each) */
    unsigned char *blob;         /* one packet's records */
    uint32_t seq;                /* packets sent */
    uint64_t frame;              /* frames sent */
    bool key_requested;
    int64_t t0_ns;
    double drop_p;               /* the test knob */
    uint64_t drop_frames;        /* 0: every frame */
    uint64_t rng;
    fp_stream_stats st;
    double times[TIMES];
};

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
    fp_stream s;
    return parse(spec, &s, err, errlen);
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
    size_t head = 128 + 5 * o->nchannels;
    s->max_records = (s->mtu - head) / RECORD_BYTES;
    struct addrinfo hints = {.ai_family = AF_INET, .ai_socktype = SOCK_DGRAM}, *ai = NULL;
    int g = getaddrinfo(s->host, s->port, &hints, &ai);
    if (g) {
        rc = fp_errorf(err, errlen, -ENOENT, "%s: host %s: %s", o->spec, s->host, gai_strerror(g));
        goto fail;
    }
    s->sock = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    int big = 4 << 20;
    if (s->sock >= 0) setsockopt(s->sock, SOL_SOCKET, SO_SNDBUF, &big, sizeof big);
    if (s->sock < 0 || connect(s->sock, ai->ai_addr, ai->ai_addrlen) != 0) {
        rc = fp_errorf(err, errlen, -errno, "%s: %s", o->spec, strerror(errno));
        freeaddrinfo(ai);
        goto fail;
    }
    freeaddrinfo(ai);
    s->sent = calloc(3 * o->n, sizeof *s->sent);
    s->idx = malloc(o->n * sizeof *s->idx);
    s->q = malloc(3 * o->n * sizeof *s->q);
    s->blob = malloc(4 + s->max_records * RECORD_BYTES);
    s->starts = malloc((o->n + 1) * sizeof *s->starts);
    s->last = malloc(3 * o->n * sizeof *s->last);
    s->slot_size = s->mtu + SLOT_SLACK;
    if (!s->sent || !s->idx || !s->q || !s->blob || !s->starts || !s->last) {
        rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory for %zu vertices", o->spec, o->n);
        goto fail;
    }
    memcpy(s->last, o->neutral, 3 * o->n * sizeof *s->last); /* (sent: all 0, the neutral's) */
    s->key_requested = true; /* the first frame is a keyframe */
    drop_knob(s);
    *out = s;
    return 0;
fail:
    fp_stream_close(&s);
    return rc;
}

void fp_stream_origin(fp_stream *st, int64_t t0_ns) { st->t0_ns = t0_ns; }
void fp_stream_request_key(fp_stream *st) { st->key_requested = true; }

static bool drop_now(fp_stream *s)
{
    if (!(s->drop_p > 0) || (s->drop_frames && s->frame >= s->drop_frames)) return false;
    s->rng ^= s->rng << 13; s->rng ^= s->rng >> 7; s->rng ^= s->rng << 17;
    return (double)(s->rng >> 11) * 0x1p-53 < s->drop_p;
}

/* Room for k packets in the slots (grown, rarely: a frame larger than any before). */
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
static void queue_message(fp_stream *s, lo_message m, const char *path, size_t *used)
{
    size_t size = lo_message_length(m, path);
    s->st.packets++;
    unsigned char *slot = s->slots + *used * s->slot_size;
    if (*used >= s->nslots || size > s->slot_size || !lo_message_serialise(m, path, slot, &size)) {
        s->st.send_errors++;
        return;
    }
    s->seq++;
    if (drop_now(s)) {
        s->st.dropped++;
        return;
    }
    s->iov[*used] = (struct iovec){slot, size};
    s->msgs[*used] = (struct mmsghdr){.msg_hdr = {.msg_iov = &s->iov[*used], .msg_iovlen = 1}};
    s->st.bytes += size;
    (*used)++;
}

/* Send the frame's queued packets: one sendmmsg (more when the kernel takes fewer). */
static void flush(fp_stream *s, size_t used)
{
    for (size_t at = 0; at < used;) {
        int k = sendmmsg(s->sock, s->msgs + at, (unsigned)(used - at), 0);
        if (k <= 0) { /* the rest is lost (counted) */
            s->st.send_errors += used - at;
            return;
        }
        at += (size_t)k;
    }
}

/* The info message: serialised and sent alone (its path may be long). */
static void send_message(fp_stream *s, lo_message m, const char *path)
{
    size_t size = lo_message_length(m, path);
    s->st.packets++;
    void *buf = lo_message_serialise(m, path, NULL, &size);
    if (!buf) {
        s->st.send_errors++;
        return;
    }
    s->seq++;
    if (drop_now(s)) s->st.dropped++;
    else if (send(s->sock, buf, size, 0) < 0) s->st.send_errors++;
    else s->st.bytes += size;
    free(buf);
}

/* /fp/stream/info before a keyframe. */
static void send_info(fp_stream *s)
{
    lo_message m = lo_message_new();
    if (!m) { s->st.send_errors++; return; }
    lo_message_add_int32(m, (int32_t)s->seq);
    lo_message_add_int32(m, (int32_t)s->o.n);
    lo_message_add_double(m, s->o.mm_per_unit);
    lo_message_add_double(m, s->step_mm);
    lo_message_add_int32(m, (int32_t)s->key_period);
    lo_message_add_double(m, s->o.fps);
    lo_message_add_int32(m, (int32_t)s->o.mesh_crc32);
    lo_message_add_string(m, s->o.mesh_path ? s->o.mesh_path : "");
    for (size_t c = 0; c < s->o.nchannels; c++) lo_message_add_string(m, s->o.channels[c]);
    send_message(s, m, "/fp/stream/info");
    lo_message_free(m);
}

static void put16(unsigned char *p, uint16_t v) { p[0] = (unsigned char)(v >> 8); p[1] = (unsigned char)v; }

/* One packet: the records [a, b) of the frame covering vertices [lo, hi). */
static void send_packet(fp_stream *s, size_t a, size_t b, uint32_t lo, uint32_t hi, int part, int parts,
                        bool key, double t, const char *tc, const float *channels, size_t *used)
{
    uint32_t prev = lo, count = (uint32_t)(b - a);
    for (int k = 0; k < 4; k++) s->blob[k] = (unsigned char)(count >> (24 - 8 * k)); /* (never empty) */
    for (size_t r = a; r < b; r++) {
        unsigned char *p = s->blob + 4 + (r - a) * RECORD_BYTES;
        put16(p, (uint16_t)(s->idx[r] - prev));
        prev = s->idx[r];
        for (int k = 0; k < 3; k++) put16(p + 2 + 2 * k, (uint16_t)s->q[3 * r + k]);
    }
    lo_blob blob = lo_blob_new((int32_t)(4 + (b - a) * RECORD_BYTES), s->blob);
    lo_message m = lo_message_new();
    if (!m || !blob) {
        s->st.send_errors++;
        if (m) lo_message_free(m);
        if (blob) lo_blob_free(blob);
        return;
    }
    lo_message_add_int32(m, (int32_t)s->seq);
    lo_message_add_int32(m, (int32_t)s->frame);
    lo_message_add_int32(m, key ? 1 : 0);
    lo_message_add_double(m, t);
    lo_message_add_string(m, tc);
    lo_message_add_int32(m, part);
    lo_message_add_int32(m, parts);
    lo_message_add_int32(m, (int32_t)lo);
    lo_message_add_int32(m, (int32_t)hi);
    lo_message_add_blob(m, blob);
    for (size_t c = 0; c < s->o.nchannels; c++) lo_message_add_float(m, channels ? channels[c] : 0.0f);
    queue_message(s, m, "/fp/stream/frame", used);
    lo_message_free(m);
    lo_blob_free(blob);
    s->st.records += b - a;
}

/* The frame's records: every non-zero offset (key) or every changed one, into idx and q. */
static size_t collect(fp_stream *s, const float *pos, bool key, const uint32_t *ranges, size_t nranges)
{
    const float *nu = s->o.neutral;
    const double scale = s->o.mm_per_unit / s->step_mm;
    const size_t n = s->o.n;
    size_t m = 0, r = 0;
    const bool all = nranges == SIZE_MAX || (!ranges && nranges); /* (0 ranges: none moved) */
    for (size_t b0 = 0; b0 < n; b0 += BLOCK) {
        const size_t b1 = b0 + BLOCK < n ? b0 + BLOCK : n, bytes = 3 * (b1 - b0) * sizeof(float);
        bool in = all; /* the block meets a touched range */
        while (!in && r < nranges && (size_t)ranges[2 * r] + ranges[2 * r + 1] <= b0) r++;
        if (!in && r < nranges && ranges[2 * r] < b1) in = true;
        if (!in && !key) {
            if (r >= nranges) break; /* (nothing further moved) */
            b0 = (size_t)ranges[2 * r] / BLOCK * BLOCK - BLOCK; /* (the next touched block) */
            continue;
        }
        const bool moved = in && memcmp(pos + 3 * b0, s->last + 3 * b0, bytes) != 0; /* (most do not) */
        if (!moved && !key) continue;
        if (moved) memcpy(s->last + 3 * b0, pos + 3 * b0, bytes);
        for (size_t v = b0; v < b1; v++) {
            int16_t *old = s->sent + 3 * v;
            bool changed = false;
            if (moved) {
                int16_t q[3];
                for (int k = 0; k < 3; k++) {
                    double d = (double)(pos[3 * v + k] - nu[3 * v + k]) * scale;
                    long r = isfinite(d) ? lrint(d) : 0;
                    if (r > 32767 || r < -32767) { r = r > 0 ? 32767 : -32767; s->st.clipped++; }
                    q[k] = (int16_t)r;
                }
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

int fp_stream_frame(fp_stream *s, const float *pos, const float *channels, int64_t now_ns,
                    const char *timecode)
{
    return fp_stream_frame_ranges(s, pos, NULL, SIZE_MAX, channels, now_ns, timecode);
}

int fp_stream_frame_ranges(fp_stream *s, const float *pos, const uint32_t *ranges, size_t nranges,
                           const float *channels, int64_t now_ns, const char *timecode)
{
    int64_t t_start = fp_now_ns();
    bool key = s->key_requested || s->frame % s->key_period == 0;
    s->key_requested = false;
    char tc[16];
    snprintf(tc, sizeof tc, "%s", timecode ? timecode : "");
    const double t = (double)(now_ns - s->t0_ns) * 1e-9;
    size_t m = collect(s, pos, key, ranges, nranges);
    /* the packets: at most max_records each; an index gap above MAX_GAP starts a new one */
    size_t nparts = 1;
    s->starts[0] = 0;
    for (size_t r = 0, lo = 0; r < m; r++) {
        size_t count = r - s->starts[nparts - 1];
        size_t gap = s->idx[r] - (count ? s->idx[r - 1] : lo);
        if (count >= s->max_records || gap > MAX_GAP) {
            s->starts[nparts++] = r;
            lo = s->idx[r];
        }
    }
    uint64_t p0 = s->st.packets;
    if (key) {
        send_info(s);
        s->st.keyframes++;
    }
    size_t used = 0;
    if (slots_reserve(s, nparts)) nparts = 0; /* (out of memory: the frame is lost, counted) */
    for (size_t k = 0; k < nparts; k++) {
        size_t a = s->starts[k], b = k + 1 < nparts ? s->starts[k + 1] : m;
        uint32_t lo = k == 0 ? 0 : s->idx[a];
        uint32_t hi = k + 1 < nparts ? s->idx[b] : (uint32_t)s->o.n;
        send_packet(s, a, b, lo, hi, (int)k, (int)nparts, key, t, tc, channels, &used);
    }
    flush(s, used);
    s->st.frames++;
    s->frame++;
    s->times[(s->st.frames - 1) % TIMES] = (double)(fp_now_ns() - t_start) * 1e-3;
    return (int)(s->st.packets - p0);
}

void fp_stream_stats_get(const fp_stream *s, fp_stream_stats *out)
{
    *out = s->st;
    size_t n = s->st.frames < TIMES ? (size_t)s->st.frames : TIMES;
    double *copy = n ? malloc(n * sizeof *copy) : NULL;
    if (!copy) return;
    memcpy(copy, s->times, n * sizeof *copy);
    out->send_us_median = fp_median(copy, n);
    out->send_us_p99 = fp_percentile(copy, n, 0.99);
    out->send_us_max = fp_percentile(copy, n, 1.0);
    free(copy);
}

void fp_stream_describe(const fp_stream *s, char *buf, size_t n)
{
    snprintf(buf, n, "to %s:%s, %zu vertices, step %.3g mm (a vertex within %.3g mm), keyframe every "
             "%u frames, packets of at most %u bytes (%zu offsets)", s->host, s->port, s->o.n, s->step_mm,
             s->step_mm * sqrt(3.0) / 2, s->key_period, s->mtu, s->max_records);
}

void fp_stream_summary(const fp_stream *s, char *buf, size_t n)
{
    fp_stream_stats st;
    fp_stream_stats_get(s, &st);
    snprintf(buf, n, "%llu frames (%llu keyframes), %llu packets, %llu bytes, %llu offsets; send "
             "median %.1f us, p99 %.1f us a frame; dropped by FP_STREAM_DROP %llu, send errors %llu, "
             "clipped %llu", (unsigned long long)st.frames, (unsigned long long)st.keyframes,
             (unsigned long long)st.packets, (unsigned long long)st.bytes, (unsigned long long)st.records,
             st.send_us_median, st.send_us_p99, (unsigned long long)st.dropped,
             (unsigned long long)st.send_errors, (unsigned long long)st.clipped);
}

void fp_stream_close(fp_stream **sp)
{
    fp_stream *s = sp ? *sp : NULL;
    if (!s) return;
    if (s->sock >= 0) close(s->sock);
    free(s->sent);
    free(s->idx);
    free(s->q);
    free(s->blob);
    free(s->starts);
    free(s->last);
    free(s->slots);
    free(s->msgs);
    free(s->iov);
    free(s);
    *sp = NULL;
}
