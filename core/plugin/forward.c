/* forward=osc:HOST:PORT: an input's events sent again in the OSC input's format (fp_forward.h). */
#define _GNU_SOURCE
#include "fp_forward.h"

#include "fp_error.h"
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
    struct addrinfo hints = {.ai_family = AF_INET, .ai_socktype = SOCK_DGRAM}, *ai = NULL;
    int g = getaddrinfo(host, port, &hints, &ai);
    if (g) return fp_errorf(err, errlen, -ENOENT, "forward=%s: host %s: %s", spec, host, gai_strerror(g));
    fp_event_forwarder *f = calloc(1, sizeof *f);
    if (!f) {
        freeaddrinfo(ai);
        return fp_errorf(err, errlen, -ENOMEM, "forward: out of memory");
    }
    f->sock = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (f->sock < 0 || connect(f->sock, ai->ai_addr, ai->ai_addrlen) != 0) {
        int e = errno;
        if (f->sock >= 0) close(f->sock);
        free(f);
        freeaddrinfo(ai);
        return fp_errorf(err, errlen, -e, "forward=%s: %s", spec, strerror(e));
    }
    freeaddrinfo(ai);
    snprintf(f->target, sizeof f->target, "%s:%s", host, port);
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
    default: return NULL;
    }
}

void fp_event_forwarder_push(fp_event_forwarder *f, const fp_event *ev)
{
    char path[64];
    lo_message m = message(ev, path, sizeof path);
    if (!m) {
        atomic_fetch_add_explicit(&f->skipped, 1, memory_order_relaxed);
        return;
    }
    /* the event's time as the bundle's timetag (1 s added: never the "immediate" 0) */
    const int64_t t = ev->header.time_ns > 0 ? ev->header.time_ns : 0;
    lo_timetag tt = {(uint32_t)(t / 1000000000 + 1), (uint32_t)(((uint64_t)(t % 1000000000) << 32) / 1000000000u)};
    /* the bundle by hand around liblo's message: "#bundle", the timetag, the size, it */
    unsigned char buf[1024];
    size_t size = lo_message_length(m, path);
    bool ok = size + 20 <= sizeof buf && lo_message_serialise(m, path, buf + 20, &size);
    if (ok) {
        memcpy(buf, "#bundle", 8);
        const uint32_t words[3] = {tt.sec, tt.frac, (uint32_t)size};
        for (int w = 0; w < 3; w++)
            for (int k = 0; k < 4; k++) buf[8 + 4 * w + k] = (unsigned char)(words[w] >> (24 - 8 * k));
        ok = send(f->sock, buf, size + 20, 0) == (ssize_t)(size + 20);
    }
    atomic_fetch_add_explicit(ok ? &f->sent : &f->errors, 1, memory_order_relaxed);
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
