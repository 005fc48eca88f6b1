/* forward=osc:HOST:PORT: an input's events sent again in the OSC input's format (fp_forward.h). */
#define _GNU_SOURCE
#include "fp_forward.h"

#include "fp_error.h"
#include "fp_net.h"
#include "facepuppet/decimal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef FP_HAVE_LIBLO
#include <lo/lo.h>
#include <netdb.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <sys/socket.h>
#include <unistd.h>

struct fp_event_forwarder {
    int sock;
    char target[300];
    _Atomic uint64_t sent, skipped, errors;
    _Atomic int64_t origin_ns; /* the first event's time: the input's time zero; INT64_MIN unset */
};

int fp_event_forwarder_create(const char *spec, fp_event_forwarder **out, char *err, size_t errlen)
{
    *out = NULL;
    char host[256], port[8];
    const char *p = spec && !strncmp(spec, "osc:", 4) ? spec + 4 : NULL, *colon = p ? strrchr(p, ':') : NULL;
    unsigned long long v;
    if (!colon || colon == p || (size_t)(colon - p) >= sizeof host || strlen(colon + 1) >= sizeof port ||
        !fp_parse_whole(colon + 1, 65535, &v) || v == 0)
        return fp_errorf(err, errlen, -EINVAL, "forward=%s: expected osc:HOST:PORT", spec ? spec : "");
    snprintf(host, sizeof host, "%.*s", (int)(colon - p), p);
    snprintf(port, sizeof port, "%s", colon + 1);
    char why[256];
    int sock = fp_udp_connect(host, port, SOCK_NONBLOCK, why, sizeof why); /* (fp_net.h) */
    if (sock < 0) return fp_errorf(err, errlen, sock, "forward=%s: host %s: %s", spec, host, why);
    fp_event_forwarder *f = calloc(1, sizeof *f);
    if (!f) {
        close(sock);
        return fp_errorf(err, errlen, -ENOMEM, "forward: out of memory");
    }
    f->sock = sock;
    snprintf(f->target, sizeof f->target, "%s:%s", host, port);
    atomic_init(&f->origin_ns, INT64_MIN);
    *out = f;
    return 0;
}

/* The message of one event at its address; NULL (counted) for what is not forwarded. */
static lo_message message(const fp_event *ev, char *path, size_t n)
{
    const int hand = ev->header.hand;
    const char *side = hand == FP_HAND_LEFT ? "left" : hand == FP_HAND_RIGHT ? "right" : NULL;
    lo_message m = NULL;
    switch (ev->header.type) {
    case FP_EVENT_JOINT_POSITIONS:
        if (!side || !(m = lo_message_new())) return NULL;
        snprintf(path, n, "/facepuppet/hand/%s/joints", side);
        for (int j = 0; j < FP_HAND_JOINTS; j++)
            for (int k = 0; k < 3; k++) lo_message_add_float(m, ev->positions.mm[j][k]);
        return m;
    case FP_EVENT_JOINT_ANGLES:
        if (!side || !(m = lo_message_new())) return NULL;
        snprintf(path, n, "/facepuppet/hand/%s/angles", side);
        lo_message_add_int32(m, (int32_t)ev->angles.valid);
        for (int k = 0; k < FP_GLOVE_SENSORS; k++) lo_message_add_float(m, ev->angles.radians[k]);
        return m;
    case FP_EVENT_WRIST_POSE:
        if (!side || !(m = lo_message_new())) return NULL;
        snprintf(path, n, "/facepuppet/hand/%s/wrist", side);
        for (int k = 0; k < 3; k++) lo_message_add_float(m, ev->wrist.position_mm[k]);
        for (int k = 0; k < 4; k++) lo_message_add_float(m, ev->wrist.rotation[k]);
        return m;
    case FP_EVENT_BUTTON: {
        const uint32_t b = ev->button.button;
        int index = b == FP_BUTTON_LEFT ? 0 : b == FP_BUTTON_MIDDLE ? 1 : b == FP_BUTTON_RIGHT ? 2 : -1;
        if (index < 0 || !(m = lo_message_new())) return NULL;
        snprintf(path, n, "/facepuppet/button");
        lo_message_add_int32(m, index);
        lo_message_add_int32(m, ev->button.down ? 1 : 0);
        return m;
    }
    case FP_EVENT_STATUS:
        if (ev->status.code != FP_STATUS_END_OF_STREAM || !(m = lo_message_new())) return NULL;
        snprintf(path, n, "/facepuppet/end");
        return m;
    default: return NULL;
    }
}

/* A time as an OSC timetag (1 s added: never the "immediate" 0). */
static lo_timetag timetag_of(int64_t t)
{
    if (t < 0) t = 0;
    return (lo_timetag){(uint32_t)(t / 1000000000 + 1), (uint32_t)(((uint64_t)(t % 1000000000) << 32) / 1000000000u)};
}

/* Append one bundle element (int32 size, then the message) at buf + *at. */
static bool append(unsigned char *buf, size_t cap, size_t *at, lo_message m, const char *path)
{
    size_t size = lo_message_length(m, path);
    if (*at + 4 + size > cap || !lo_message_serialise(m, path, buf + *at + 4, &size)) return false;
    for (int k = 0; k < 4; k++) buf[*at + (size_t)k] = (unsigned char)((uint32_t)size >> (24 - 8 * k));
    *at += 4 + size;
    return true;
}

void fp_event_forwarder_push(fp_event_forwarder *f, const fp_event *ev)
{
    int64_t unset = INT64_MIN; /* the input's first event, whatever it is, sets its time zero */
    atomic_compare_exchange_strong(&f->origin_ns, &unset, ev->header.time_ns);
    char path[64];
    lo_message m = message(ev, path, sizeof path);
    if (!m) {
        atomic_fetch_add_explicit(&f->skipped, 1, memory_order_relaxed);
        return;
    }
    /* the bundle by hand: "#bundle", the event's time as its timetag, then the sender's time
     * zero (/facepuppet/origin t: a receiver on clock=recording counts from it) and the event */
    lo_message origin = lo_message_new();
    bool ok = origin != NULL;
    if (ok) lo_message_add_timetag(origin, timetag_of(atomic_load(&f->origin_ns)));
    unsigned char buf[1024];
    const lo_timetag tt = timetag_of(ev->header.time_ns);
    memcpy(buf, "#bundle", 8);
    const uint32_t words[2] = {tt.sec, tt.frac};
    for (int w = 0; w < 2; w++)
        for (int k = 0; k < 4; k++) buf[8 + 4 * w + k] = (unsigned char)(words[w] >> (24 - 8 * k));
    size_t at = 16;
    ok = ok && append(buf, sizeof buf, &at, origin, "/facepuppet/origin") && append(buf, sizeof buf, &at, m, path);
    ok = ok && send(f->sock, buf, at, 0) == (ssize_t)at;
    atomic_fetch_add_explicit(ok ? &f->sent : &f->errors, 1, memory_order_relaxed);
    if (origin) lo_message_free(origin);
    lo_message_free(m);
}

void fp_event_forwarder_stats(const fp_event_forwarder *f, fp_forward_stats *st)
{
    st->sent = atomic_load_explicit(&f->sent, memory_order_relaxed);
    st->skipped = atomic_load_explicit(&f->skipped, memory_order_relaxed);
    st->errors = atomic_load_explicit(&f->errors, memory_order_relaxed);
}

const char *fp_event_forwarder_target(const fp_event_forwarder *f) { return f->target; }

void fp_event_forwarder_destroy(fp_event_forwarder **fp)
{
    fp_event_forwarder *f = fp ? *fp : NULL;
    if (!f) return;
    close(f->sock);
    free(f);
    *fp = NULL;
}

#else /* built without liblo */

struct fp_event_forwarder {
    int unused;
};

int fp_event_forwarder_create(const char *spec, fp_event_forwarder **out, char *err, size_t errlen)
{
    *out = NULL;
    return fp_errorf(err, errlen, -ENOTSUP, "forward=%s: left out of this build (liblo-dev was not found)",
                     spec ? spec : "");
}
void fp_event_forwarder_push(fp_event_forwarder *f, const fp_event *ev) { (void)f; (void)ev; }
void fp_event_forwarder_stats(const fp_event_forwarder *f, fp_forward_stats *st)
{
    (void)f;
    memset(st, 0, sizeof *st);
}
const char *fp_event_forwarder_target(const fp_event_forwarder *f) { (void)f; return ""; }
void fp_event_forwarder_destroy(fp_event_forwarder **f) { if (f) *f = NULL; }

#endif
