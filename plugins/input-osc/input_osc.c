/*
 * input_osc.c: the input-osc plugin. Hand tracking over OSC (UDP): the project's own
 * address space, Leap Motion bridges and MediaPipe hands (docs/osc.md).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Flow: create() parses the SPEC and binds the UDP sockets (fp_udp_listen, fp_net.h: 127.0.0.1 and [::1]
 * unless bind= says otherwise), so that a taken port or a bad address fails before the
 * session starts. Leap bridge frames are assembled in osc_leap.c, MediaPipe ones in
 * osc_mediapipe.c. start()
 * runs one pthread: poll() on the socket and a stop pipe (50 ms ticks); each datagram is read
 * with recvmsg() into one fixed 64 KiB buffer (the kernel's own drops counted) and stamped with the host clock at once; a
 * bundle is walked here (timetags, nesting), each message is decoded by liblo
 * (lo_message_deserialise), checked (address, type tags, count, finite, range) and turned into
 * events pushed to the host's bounded queue. Nothing grows with traffic: one buffer, one
 * liblo message at a time, fixed assembly state per hand, a fixed latency ring.
 * stop() writes to the pipe and joins.
 */
#define _GNU_SOURCE
#include "fp_osc_arg.h"
#include "osc.h"
#include "osc_leap.h"
#include "osc_mediapipe.h"
#include "osc_spec.h"
#include "fp_net.h"

#include <facepuppet/plugin.h>
#include <facepuppet/plugin_util.h>

#include <lo/lo.h>
#include <lo/lo_lowlevel.h>

#include <errno.h>
#include <fcntl.h>
#include <locale.h>
#include <float.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define PACKET_MAX 65536           /* a UDP datagram never exceeds it */
#define BURST 256                  /* datagrams read per wake before timers are looked at */
#define TICK_MS 50                 /* poll timeout: timers are checked at least this often */
#define MAX_DEPTH 8                /* nested bundles */
#define MAX_RADIANS 6.2831853f     /* 2 pi */
#define LATENCY_RING 65536
#define REPORT_DELAY_NS 1000000000LL /* a problem kind is reported 1 s after it first occurs */
#define REANCHOR_NS 1000000000LL   /* timetag mapping re-anchored beyond 1 s from arrival */
#define STATUS_RETRY_NS 100000000LL /* a status event is retried for up to 100 ms */


static const char *const problem_names[FP_OSC_PROBLEMS] = {
    "malformed", "bad-types", "bad-count", "non-finite", "out-of-range", "unknown-address",
    "incomplete", "queue-full", "untimed", "stale", "kernel-dropped"};
static const char *const problem_text[FP_OSC_PROBLEMS] = {
    "malformed packets (not OSC, or a bad bundle)", "messages with wrong type tags",
    "messages with a wrong argument count", "messages with NaN or infinite values",
    "messages with values out of range (beyond 10 m, 2 pi, a bad quaternion or button)",
    "messages to addresses outside the format", "incomplete frames superseded",
    "events dropped (host queue full)",
    "messages without a time on the sender's recording clock (needs a session's forward=)",
    "poses older than one already pushed for that hand (bundles out of order)",
    "datagrams the kernel dropped (its socket buffer full: the sender outran this input)"};

typedef struct osc_input {
    fp_input input;
    const fp_host *host;
    /* configuration */
    int format, hands, clock;
    double timeout_s;
    osc_mp_place mp_place;         /* format=mediapipe's image placement */
    bool have_box;
    float box[6];                  /* box=: the tracking volume, mm (workspace extension) */
    char bind_text[96];            /* where it listens, for the log (fp_udp_listener.text) */
    uint16_t port;
    /* socket and thread */
    int sock;
    uint32_t kernel_total[2]; /* SO_RXQ_OVFL's last running total, sock and sock6 */
    int sock6; /* [::1]:port beside 127.0.0.1:port (a sender's "localhost" may be ::1), -1 none
                  (fp_net.h) */
    int stop_pipe[2];
    pthread_t thread;
    bool running;
    unsigned char buf[PACKET_MAX] __attribute__((aligned(8)));
    /* receive-thread state */
    bool connected;
    int64_t last_valid_ns;
    unsigned hands_seen;           /* bit per hand that got a pose since the connect */
    unsigned hands_lost;           /* bit per seen hand reported gone while the sender went on */
    int64_t hand_last_ns[FP_HANDS];/* receive time of each hand's latest pose */
    char sender[64];               /* the current sender's ADDR:PORT, as statuses name it */
    struct sockaddr_storage sender_addr; /* its address */
    int64_t sender_last_ns;        /* receive time of its latest valid message */
    struct sockaddr_storage pkt_from; /* the sender of the latest datagram */
    bool have_offset;
    int64_t offset_ns;
    struct sockaddr_storage offset_from; /* the sender whose timetags offset_ns maps */
    /* clock=recording: event time = origin_ns + (timetag - the sender's origin timetag) */
    int64_t origin_ns;             /* host time at start(): the recording's time zero here */
    bool have_sender_origin, ended;
    int64_t heard_ns;              /* the latest datagram's arrival; 0: none yet */
    int64_t sender_origin_tt;      /* the sender's /facepuppet/origin, ns on the timetag scale */
    int64_t clock_t;               /* the last message's time (statuses are pushed at it) */
    uint32_t buttons;
    osc_leap leap;                 /* Leap frames being assembled, Leap ids' sides */
    int64_t last_pose_t[FP_HANDS][3]; /* per hand: the time of its last joints, angles, wrist
                                         pushed (a staler one is dropped); INT64_MIN none */
    osc_mp_hand mp[FP_HANDS];
    int64_t report_at[FP_OSC_PROBLEMS]; /* 0: not pending; -1: reported */
    char unknown_first[64];        /* the first unknown address, for its report ("" none) */
    char bad_first[2][160];        /* the first bad-count and bad-types message, said ("" none) */
    const char *cur_path;          /* the address of the message being checked */
    bool packet_pushed;
    /* statistics (mutex) */
    pthread_mutex_t lock;
    fp_osc_stats st;
    float *lat_us;                 /* LATENCY_RING samples, microseconds */
    uint64_t lat_n;
} osc_input;

/* ------------------------------------------------------------------------------------- */
/* Helpers                                                                                */

static void logf_(osc_input *o, fp_log_level level, const char *fmt, ...)
{
    if (!o->host->log) return;
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    o->host->log(o->host, level, msg);
}

static int64_t now_ns(const osc_input *o) { return o->host->now_ns(o->host); }

static void sleep_ns(int64_t ns)
{
    struct timespec ts = {(time_t)(ns / 1000000000), (long)(ns % 1000000000)};
    nanosleep(&ts, NULL);
}

/* n more of a problem counted; its report is due a second after the first */
static void count_n(osc_input *o, int kind, uint64_t n)
{
    pthread_mutex_lock(&o->lock);
    o->st.problems[kind] += n;
    pthread_mutex_unlock(&o->lock);
    if (o->report_at[kind] == 0) o->report_at[kind] = now_ns(o) + REPORT_DELAY_NS;
}

static void count(osc_input *o, int kind) { count_n(o, kind, 1); }

/* An unknown address counted; the first is kept for the report (receive thread). */
static void count_unknown(osc_input *o, const char *path)
{
    if (!o->unknown_first[0])
        snprintf(o->unknown_first, sizeof o->unknown_first, "%s", path);
    count(o, FP_OSC_UNKNOWN_ADDRESS);
}

/* The addresses a format takes (docs/osc.md, "Address spaces"). */
static const char *format_space(int fmt)
{
    switch (fmt) {
    case FMT_FACEPUPPET: return "/facepuppet/...";
    case FMT_LEAP: return "/hand<s> and /finger<s>-<n>";
    case FMT_MEDIAPIPE: return "/lx/ ... /rz/";
    default: return "/facepuppet/..., /hand<s>, /finger<s>-<n> and /lx/ ... /rz/";
    }
}

/* What an unknown address is, where shared/docs/devices.md names its sender's format. */
static const char *foreign_space(const char *path)
{
    if (strcmp(path, "/found") == 0 || strncmp(path, "/pose/", 6) == 0 ||
        strncmp(path, "/gesture/", 9) == 0 || strcmp(path, "/raw") == 0)
        return ": FaceOSC's face data, not hand input";
    if (strncmp(path, "/VMC/", 5) == 0)
        return ": the VMC protocol's avatar data, not supported";
    return "";
}

/* The kernel's count of datagrams a socket dropped (SO_RXQ_OVFL's control message, a running
 * total per socket): what it grew by since the last, counted. */
static void kernel_drops(osc_input *o, int s, const struct msghdr *mh)
{
#ifdef SO_RXQ_OVFL
    for (struct cmsghdr *c = CMSG_FIRSTHDR((struct msghdr *)mh); c; c = CMSG_NXTHDR((struct msghdr *)mh, c)) {
        if (c->cmsg_level != SOL_SOCKET || c->cmsg_type != SO_RXQ_OVFL || c->cmsg_len < CMSG_LEN(sizeof(uint32_t)))
            continue;
        uint32_t total;
        memcpy(&total, CMSG_DATA(c), sizeof total);
        uint32_t grew = total - o->kernel_total[s]; /* (wraps as the kernel's counter does) */
        o->kernel_total[s] = total;
        if (grew) count_n(o, FP_OSC_KERNEL_DROPPED, grew);
    }
#else
    (void)o, (void)s, (void)mh;
#endif
}

static void bump(osc_input *o, uint64_t *field)
{
    pthread_mutex_lock(&o->lock);
    (*field)++;
    pthread_mutex_unlock(&o->lock);
}

/* Pushes a pose or button; a full queue drops it (counted): the next pose supersedes it.
 * Returns whether the host took it. */
static bool push_event(osc_input *o, fp_event *ev)
{
    if (o->host->push_event(o->host, &ev->header)) {
        bump(o, &o->st.events);
        o->packet_pushed = true;
        return true;
    }
    count(o, FP_OSC_QUEUE_FULL);
    return false;
}

/* The pose kinds whose times are kept per hand (o->last_pose_t). */
enum { POSE_JOINTS, POSE_ANGLES, POSE_WRIST };

/* Forgets the poses' times: a sender's clock begins again (disconnect, timetag re-anchored,
 * a new origin), so its next pose is never stale. */
static void forget_pose_times(osc_input *o)
{
    for (int h = 0; h < FP_HANDS; h++)
        for (int k = 0; k < 3; k++) o->last_pose_t[h][k] = INT64_MIN;
}

/* Whether a pose of hand at time t is older than the last of its kind pushed (a bundle that
 * arrived out of order): then counted stale, to be dropped. */
static bool stale(osc_input *o, int hand, int kind, int64_t t)
{
    if (t >= o->last_pose_t[hand][kind]) return false;
    count(o, FP_OSC_STALE);
    return true;
}

/* Pushes a pose (hand >= 0) and keeps its time when the host took it. */
static void push_pose(osc_input *o, fp_event *ev, int kind)
{
    const int hand = ev->header.hand;
    if (push_event(o, ev)) o->last_pose_t[hand][kind] = ev->header.time_ns;
}

/* Pushes a status event, retrying for up to 100 ms while the queue is full. */
static void push_status(osc_input *o, uint32_t code, int hand, const char *fmt, ...)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    /* on the recording's clock, at the last message's time: never ahead of the samples */
    const int64_t t = o->clock == CLOCK_RECORDING ? o->clock_t : now_ns(o);
    ev.status.header = (fp_event_header){.size = sizeof ev.status, .type = FP_EVENT_STATUS,
                                         .time_ns = t, .hand = hand};
    ev.status.code = code;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(ev.status.text, sizeof ev.status.text, fmt, ap);
    va_end(ap);
    for (int64_t waited = 0; !o->host->push_event(o->host, &ev.header); waited += 1000000) {
        if (waited >= STATUS_RETRY_NS) {
            count(o, FP_OSC_QUEUE_FULL);
            return;
        }
        sleep_ns(1000000);
    }
    bump(o, &o->st.events);
}

static bool finite_all(const float *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) return false;
    return true;
}

static bool within(const float *v, size_t n, float limit)
{
    for (size_t i = 0; i < n; i++)
        if (fabsf(v[i]) > limit) return false;
    return true;
}

/* The first bad-count or bad-types message kept for its report (receive thread): its
 * address and what was wrong, so that a sender's mistake can be found. */
static void note_bad(osc_input *o, int kind, const char *fmt, ...)
{
    char *out = o->bad_first[kind == FP_OSC_BAD_COUNT ? 0 : 1];
    if (!out[0]) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(out, sizeof o->bad_first[0], fmt, ap);
        va_end(ap);
    }
    count(o, kind);
}

/* What a type tag `want` takes, for a report. */
static const char *wanted_text(char want)
{
    return want == 'f' ? "a number (f, d, i or h)" : want == 'i' ? "an integer (i or h)" : "a timetag (t)";
}

/* types against want, where an 'f' takes any number's tag and an 'i' any integer's; a
 * mismatch counted (bad-count or bad-types) and the first of each kept for its report;
 * base: the arguments before `types` (an optional leading one already taken) */
static bool check_types_at(osc_input *o, const char *types, const char *want, size_t base)
{
    const char *path = o->cur_path ? o->cur_path : "?";
    const size_t n = strlen(want);
    if (strlen(types) != n) {
        note_bad(o, FP_OSC_BAD_COUNT, "%s with %zu arguments, wants %zu", path, base + strlen(types),
                 base + n);
        return false;
    }
    for (size_t i = 0; i < n; i++)
        if (want[i] == 'f'   ? !fp_osc_number_type(types[i])
            : want[i] == 'i' ? !fp_osc_integer_type(types[i])
                             : types[i] != want[i]) {
            note_bad(o, FP_OSC_BAD_TYPES, "%s: argument %zu is '%c', wants %s", path, base + i + 1,
                     types[i], wanted_text(want[i]));
            return false;
        }
    return true;
}

static bool check_types(osc_input *o, const char *types, const char *want)
{
    return check_types_at(o, types, want, 0);
}

/* A number argument (a tag check_types let through) as a float, read through fp_osc_arg.h
 * (memcpy: liblo's argv is 4-byte aligned); a double beyond float's range becomes inf
 * (refused later as not finite), not a conversion out of range. */
static float arg_f(lo_arg *a, char type)
{
    double d = fp_osc_number(type, a);
    return type == 'd' && fabs(d) > FLT_MAX ? (float)copysign(INFINITY, d) : (float)d;
}

/* An integer argument, an int64 clamped to int32. */
static int32_t arg_i(lo_arg *a, char type)
{
    double v = fp_osc_number(type, a);
    return v < INT32_MIN ? INT32_MIN : v > INT32_MAX ? INT32_MAX : (int32_t)v;
}

static void floats_of(lo_arg **argv, const char *types, int first, int n, float *out)
{
    for (int i = 0; i < n; i++) out[i] = arg_f(argv[first + i], types[first + i]);
}

static bool hand_wanted(const osc_input *o, int h) { return o->hands & (1 << h); }

/* Whether two senders are one (address and port; IPv4 or IPv6). */
static bool same_sender(const struct sockaddr_storage *a, const struct sockaddr_storage *b)
{
    if (a->ss_family != b->ss_family) return false;
    if (a->ss_family == AF_INET) {
        const struct sockaddr_in *x = (const void *)a, *y = (const void *)b;
        return x->sin_port == y->sin_port && x->sin_addr.s_addr == y->sin_addr.s_addr;
    }
    if (a->ss_family != AF_INET6) return true;
    const struct sockaddr_in6 *x = (const void *)a, *y = (const void *)b;
    return x->sin6_port == y->sin6_port && !memcmp(&x->sin6_addr, &y->sin6_addr, sizeof x->sin6_addr);
}

/* Another sender's valid message while connected: it takes over (statuses name it from now
 * on, said once) where the current sender has been quiet for TAKEOVER (a quarter of the
 * timeout, at most 250 ms: a sender replaced with no silence in between); two senders that
 * interleave leave the first in place. */
static void maybe_take_over(osc_input *o, int64_t recv_ns)
{
    int64_t quiet = (int64_t)(o->timeout_s * 0.25e9);
    if (quiet > 250000000) quiet = 250000000;
    if (same_sender(&o->pkt_from, &o->sender_addr) || recv_ns - o->sender_last_ns < quiet)
        return;
    char old[sizeof o->sender];
    memcpy(old, o->sender, sizeof old);
    o->sender_addr = o->pkt_from;
    fp_udp_sender_text(&o->pkt_from, o->sender, sizeof o->sender);
    bump(o, &o->st.connects);
    push_status(o, FP_STATUS_CONNECTED, -1, "osc %s: sender %s on port %u (took over from %s)",
                fp__osc_format_names[o->format], o->sender, (unsigned)o->port, old);
    logf_(o, FP_LOG_INFO, "port %u: sender %s took over from %s", (unsigned)o->port, o->sender, old);
}

/* Called for every message that produced a pose or button: connection bookkeeping. */
static void note_valid(osc_input *o, int64_t recv_ns, int hand)
{
    if (!o->connected) {
        o->connected = true;
        bump(o, &o->st.connects);
        o->hands_seen = o->hands_lost = 0;
        o->sender_addr = o->pkt_from;
        push_status(o, FP_STATUS_CONNECTED, -1, "osc %s: sender %s on port %u",
                    fp__osc_format_names[o->format], o->sender, (unsigned)o->port);
    } else {
        maybe_take_over(o, recv_ns);
    }
    if (same_sender(&o->pkt_from, &o->sender_addr)) o->sender_last_ns = recv_ns;
    o->last_valid_ns = recv_ns;
    if (hand >= 0) {
        o->hands_seen |= 1u << hand;
        o->hands_lost &= ~(1u << hand); /* back: its pose makes it present again */
        o->hand_last_ns[hand] = recv_ns;
    }
}

static void header_for(fp_event *ev, size_t size, uint16_t type, int64_t t, int hand)
{
    memset(ev, 0, sizeof *ev);
    ev->header = (fp_event_header){.size = (uint32_t)size, .type = type, .time_ns = t,
                                   .hand = hand};
}

/* flags: the event's header.flags (FP_EVENT_FLAG_UNSMOOTHED for MediaPipe's landmarks) */
static void push_joints(osc_input *o, int hand, int64_t t, int64_t recv_ns,
                        const float mm[FP_HAND_JOINTS][3], uint16_t flags)
{
    if (!finite_all(&mm[0][0], FP_HAND_JOINTS * 3)) {
        count(o, FP_OSC_NONFINITE);
        return;
    }
    if (!within(&mm[0][0], FP_HAND_JOINTS * 3, HUGE_MM)) {
        count(o, FP_OSC_OUT_OF_RANGE);
        return;
    }
    if (stale(o, hand, POSE_JOINTS, t)) return;
    note_valid(o, recv_ns, hand);
    fp_event ev;
    header_for(&ev, sizeof ev.positions, FP_EVENT_JOINT_POSITIONS, t, hand);
    ev.header.flags = flags;
    memcpy(ev.positions.mm, mm, sizeof ev.positions.mm);
    push_pose(o, &ev, POSE_JOINTS);
}

/* ------------------------------------------------------------------------------------- */
/* format=facepuppet                                                                      */

static void fmt_facepuppet(osc_input *o, const char *path, const char *types, lo_arg **argv,
                           int64_t t, int64_t recv_ns)
{
    if (strcmp(path, "/facepuppet/button") == 0) {
        if (!check_types(o, types, "ii")) return;
        int32_t index = arg_i(argv[0], types[0]), down = arg_i(argv[1], types[1]);
        if (index < 0 || index > 2 || (down != 0 && down != 1)) {
            count(o, FP_OSC_OUT_OF_RANGE);
            return;
        }
        note_valid(o, recv_ns, -1);
        uint32_t bit = 1u << index;
        o->buttons = down ? (o->buttons | bit) : (o->buttons & ~bit);
        fp_event ev;
        header_for(&ev, sizeof ev.button, FP_EVENT_BUTTON, t, -1);
        ev.button.button = bit;
        ev.button.down = (uint32_t)down;
        ev.button.mask = o->buttons;
        push_event(o, &ev);
        return;
    }
    static const char prefix[] = "/facepuppet/hand/";
    if (strncmp(path, prefix, sizeof prefix - 1) != 0) {
        count_unknown(o, path);
        return;
    }
    const char *rest = path + sizeof prefix - 1;
    int hand;
    if (strncmp(rest, "left/", 5) == 0)
        hand = FP_HAND_LEFT, rest += 5;
    else if (strncmp(rest, "right/", 6) == 0)
        hand = FP_HAND_RIGHT, rest += 6;
    else {
        count_unknown(o, path);
        return;
    }
    fp_event ev;
    if (strcmp(rest, "joints") == 0) {
        char want[64];
        memset(want, 'f', 63);
        want[63] = 0;
        if (!check_types(o, types, want)) return;
        if (!hand_wanted(o, hand)) {
            bump(o, &o->st.filtered);
            return;
        }
        float mm[FP_HAND_JOINTS][3];
        floats_of(argv, types, 0, 63, &mm[0][0]);
        push_joints(o, hand, t, recv_ns, (const float(*)[3])mm, 0);
    } else if (strcmp(rest, "angles") == 0) {
        /* 22 floats (all valid), or an int mask of the valid sensors and 22 floats */
        char want[32];
        memset(want, 'f', 22);
        want[22] = 0;
        int first = 0;
        uint32_t valid = (1u << FP_GLOVE_SENSORS) - 1;
        if (fp_osc_integer_type(types[0]) && strlen(types) == 23) {
            if (!check_types_at(o, types + 1, want, 1)) return;
            first = 1;
            valid = (uint32_t)arg_i(argv[0], types[0]) & ((1u << FP_GLOVE_SENSORS) - 1);
        } else if (!check_types(o, types, want)) {
            return;
        }
        if (!hand_wanted(o, hand)) {
            bump(o, &o->st.filtered);
            return;
        }
        float rad[FP_GLOVE_SENSORS];
        floats_of(argv, types, first, FP_GLOVE_SENSORS, rad);
        if (!finite_all(rad, FP_GLOVE_SENSORS)) {
            count(o, FP_OSC_NONFINITE);
            return;
        }
        if (!within(rad, FP_GLOVE_SENSORS, MAX_RADIANS)) {
            count(o, FP_OSC_OUT_OF_RANGE);
            return;
        }
        if (stale(o, hand, POSE_ANGLES, t)) return;
        note_valid(o, recv_ns, hand);
        header_for(&ev, sizeof ev.angles, FP_EVENT_JOINT_ANGLES, t, hand);
        ev.angles.valid = valid;
        for (int i = 0; i < FP_GLOVE_SENSORS; i++) ev.angles.radians[i] = valid >> i & 1 ? rad[i] : 0.f;
        push_pose(o, &ev, POSE_ANGLES);
    } else if (strcmp(rest, "wrist") == 0) {
        if (!check_types(o, types, "fffffff")) return;
        if (!hand_wanted(o, hand)) {
            bump(o, &o->st.filtered);
            return;
        }
        float v[7];
        floats_of(argv, types, 0, 7, v);
        if (!finite_all(v, 7)) {
            count(o, FP_OSC_NONFINITE);
            return;
        }
        double n = sqrt((double)v[3] * v[3] + (double)v[4] * v[4] + (double)v[5] * v[5] +
                        (double)v[6] * v[6]);
        if (!within(v, 3, HUGE_MM) || fabs(n - 1.0) > 0.1) {
            count(o, FP_OSC_OUT_OF_RANGE);
            return;
        }
        if (stale(o, hand, POSE_WRIST, t)) return;
        note_valid(o, recv_ns, -1); /* a wrist alone does not make a hand present */
        header_for(&ev, sizeof ev.wrist, FP_EVENT_WRIST_POSE, t, hand);
        memcpy(ev.wrist.position_mm, v, sizeof ev.wrist.position_mm);
        for (int i = 0; i < 4; i++) ev.wrist.rotation[i] = (float)(v[3 + i] / n);
        push_pose(o, &ev, POSE_WRIST);
    } else {
        count_unknown(o, path);
    }
}

/* ------------------------------------------------------------------------------------- */
/* format=leap                                                                            */

/* Pushes Leap frames, each as the side its Leap id has (hand=both) or as the one hand asked. */
static void leap_push(osc_input *o, const osc_leap_frame *fr, int n, int64_t recv_ns)
{
    int side[OSC_LEAP_SLOTS];
    if (o->hands == HANDS_BOTH)
        fp__osc_leap_sides(&o->leap, fr, n, recv_ns, (int64_t)(o->timeout_s * 1e9), side);
    for (int i = 0; i < n; i++) {
        int hand = o->hands == HANDS_BOTH ? side[i] : o->hands == HANDS_LEFT ? FP_HAND_LEFT : FP_HAND_RIGHT;
        float mm[FP_HAND_JOINTS][3];
        fp__osc_leap_joints(&fr[i], mm);
        push_joints(o, hand, fr[i].t, recv_ns, (const float(*)[3])mm, 0);
    }
}

static void leap_count_incomplete(osc_input *o, unsigned incomplete)
{
    while (incomplete--) count(o, FP_OSC_INCOMPLETE);
}

/* depth: the message's bundle nesting (0: a plain message) */
static void fmt_leap(osc_input *o, const char *path, const char *types, lo_arg **argv,
                     int64_t t, int64_t recv_ns, int depth)
{
    int slot = 0, finger = 0, kind = fp__osc_leap_address(path, &slot, &finger);
    if (!kind) {
        count_unknown(o, path);
        return;
    }
    if (!check_types(o, types, "iifff")) return;
    if (o->hands != HANDS_BOTH && slot != 0) {
        bump(o, &o->st.filtered);
        return;
    }
    float v[3];
    floats_of(argv, types, 2, 3, v);
    if (!finite_all(v, 3)) {
        count(o, FP_OSC_NONFINITE);
        return;
    }
    if (!within(v, 3, HUGE_MM)) {
        count(o, FP_OSC_OUT_OF_RANGE);
        return;
    }
    osc_leap_frame fr[1];
    unsigned incomplete = 0;
    int n = fp__osc_leap_take(&o->leap, kind, slot, finger, arg_i(argv[0], types[0]), v, t,
                              depth > 0, fr, &incomplete);
    leap_count_incomplete(o, incomplete);
    leap_push(o, fr, n, recv_ns);
}

/* The end of a datagram: the Leap frames its bundle completed, in any order of its messages. */
static void leap_end_packet(osc_input *o, int64_t recv_ns)
{
    osc_leap_frame fr[OSC_LEAP_SLOTS];
    unsigned incomplete = 0;
    int n = fp__osc_leap_end_packet(&o->leap, fr, &incomplete);
    leap_count_incomplete(o, incomplete);
    leap_push(o, fr, n, recv_ns);
}

/* ------------------------------------------------------------------------------------- */
/* format=mediapipe (assembled in osc_mediapipe.c)                                        */

static void mp_push(osc_input *o, int hand, const osc_mp_frame *fr, int n, int64_t recv_ns)
{
    for (int i = 0; i < n; i++)
        push_joints(o, hand, fr[i].t, recv_ns, (const float(*)[3])fr[i].mm, FP_EVENT_FLAG_UNSMOOTHED);
}

/* The end of a datagram: MediaPipe frames that waited in it for a z that did not come. */
static void mp_end_packet(osc_input *o, int64_t recv_ns)
{
    for (int h = 0; h < FP_HANDS; h++) {
        osc_mp_frame fr;
        mp_push(o, h, &fr, fp__osc_mp_end_packet(&o->mp[h], &o->mp_place, &fr), recv_ns);
    }
}

/* depth: the message's bundle nesting (0: a plain message) */
static void fmt_mediapipe(osc_input *o, const char *path, const char *types, lo_arg **argv,
                          int64_t t, int64_t recv_ns, int depth)
{
    if (!fp__osc_mp_address(path)) {
        count_unknown(o, path);
        return;
    }
    char want[22];
    memset(want, 'f', 21);
    want[21] = 0;
    if (!check_types(o, types, want)) return;
    int hand = path[1] == 'l' ? FP_HAND_LEFT : FP_HAND_RIGHT, axis = path[2] - 'x';
    if (!hand_wanted(o, hand)) {
        bump(o, &o->st.filtered);
        return;
    }
    float v[OSC_MP_LANDMARKS];
    floats_of(argv, types, 0, OSC_MP_LANDMARKS, v);
    if (!finite_all(v, OSC_MP_LANDMARKS)) {
        count(o, FP_OSC_NONFINITE);
        return;
    }
    osc_mp_frame fr[2];
    unsigned incomplete = 0;
    int n = fp__osc_mp_take(&o->mp[hand], &o->mp_place, axis, v, t, depth > 0, fr, &incomplete);
    if (incomplete) count_n(o, FP_OSC_INCOMPLETE, incomplete);
    mp_push(o, hand, fr, n, recv_ns);
}

/* ------------------------------------------------------------------------------------- */
/* Packets, bundles, timetags                                                             */

static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

#define UNTIMED INT64_MIN /* clock=recording: a message with no time on the recording's clock */

static int64_t timetag_ns(uint32_t sec, uint32_t frac)
{
    return (int64_t)sec * 1000000000 + (int64_t)(((uint64_t)frac * 1000000000u) >> 32);
}

/* clock=recording: the host time of a bundle's timetag, the sender's recording time after its
 * origin counted from this input's start; UNTIMED for "immediate" or before the origin. */
static int64_t recording_time(const osc_input *o, uint32_t sec, uint32_t frac)
{
    if ((sec == 0 && frac <= 1) || !o->have_sender_origin) return UNTIMED;
    return o->origin_ns + (timetag_ns(sec, frac) - o->sender_origin_tt);
}

/* Host time of an OSC timetag: sender time plus an offset, arrival - timetag of the bundle
 * that came soonest (the least transit delay seen: so a first bundle that waited in the socket
 * before the thread read it, or came late, does not leave every later event stamped late by
 * its wait), so the sender's spacing is kept and its jitter in transit is not added. The
 * offset is fixed again (its pose times forgotten) when the result strays more than 1 s
 * from the arrival (the sender restarted, its clock stepped) and when the datagram comes
 * from another sender than the one it was fixed by (a sender restarted on a new port, with a
 * clock of its own). Immediate (0, 1) means the arrival. */
static int64_t map_timetag(osc_input *o, uint32_t sec, uint32_t frac, int64_t recv_ns)
{
    if (sec == 0 && frac <= 1) return recv_ns;
    int64_t tt = timetag_ns(sec, frac);
    const bool other = o->have_offset && !same_sender(&o->pkt_from, &o->offset_from);
    if (!o->have_offset || other || llabs(tt + o->offset_ns - recv_ns) > REANCHOR_NS) {
        o->have_offset = true;
        o->offset_ns = recv_ns - tt;
        o->offset_from = o->pkt_from;
        forget_pose_times(o); /* the sender's clock began again */
    } else if (tt + o->offset_ns > recv_ns) {
        /* sooner than the offset says (the bundles before waited): never stamped after its
         * arrival; later times keep their order (each is at least this arrival) */
        o->offset_ns = recv_ns - tt;
    } else {
        return tt + o->offset_ns;
    }
    pthread_mutex_lock(&o->lock);
    o->st.timetag_offset_ns = o->offset_ns;
    pthread_mutex_unlock(&o->lock);
    return tt + o->offset_ns;
}

/* The addresses of forward= (fp_forward.h) that carry no hand, in any format:
 * /facepuppet/origin t (the sender's time zero) and /facepuppet/end (its recording ended). With
 * clock=recording a message without a time on that clock is dropped here (counted). Returns
 * true when the message was taken (or dropped) here. */
static bool transport_message(osc_input *o, const char *path, const char *types, lo_arg **argv,
                              int64_t t)
{
    if (strcmp(path, "/facepuppet/origin") == 0) {
        if (check_types(o, types, "t")) {
            int64_t origin = timetag_ns(argv[0]->t.sec, argv[0]->t.frac);
            if (o->have_sender_origin && origin != o->sender_origin_tt) forget_pose_times(o);
            o->sender_origin_tt = origin;
            o->have_sender_origin = true;
        }
        return true;
    }
    if (o->clock == CLOCK_RECORDING) {
        if (t == UNTIMED) {
            count(o, FP_OSC_UNTIMED);
            return true;
        }
        if (t > o->clock_t) o->clock_t = t;
    }
    if (strcmp(path, "/facepuppet/end") == 0) {
        if (check_types(o, types, "") && o->clock == CLOCK_RECORDING && !o->ended) {
            o->ended = true;
            push_status(o, FP_STATUS_END_OF_STREAM, -1, "osc: %s's recording ended", o->sender);
        }
        return true;
    }
    return false;
}

static void handle_message(osc_input *o, unsigned char *data, size_t size, int64_t t,
                           int64_t recv_ns, int depth)
{
    int result = 0;
    lo_message m = lo_message_deserialise(data, size, &result);
    if (!m) {
        count(o, FP_OSC_MALFORMED);
        return;
    }
    bump(o, &o->st.messages);
    const char *path = (const char *)data; /* validated by lo_message_deserialise */
    const char *types = lo_message_get_types(m);
    lo_arg **argv = lo_message_get_argv(m);
    if (!types) types = "";
    o->cur_path = path;
    if (transport_message(o, path, types, argv, t)) {
        o->cur_path = NULL;
        lo_message_free(m);
        return;
    }
    int fmt = o->format;
    if (fmt == FMT_AUTO) { /* each message by its address space (they do not overlap) */
        int slot, finger;
        if (strncmp(path, "/facepuppet/", 12) == 0) fmt = FMT_FACEPUPPET;
        else if (fp__osc_leap_address(path, &slot, &finger)) fmt = FMT_LEAP;
        else if (fp__osc_mp_address(path)) fmt = FMT_MEDIAPIPE;
        else
            count_unknown(o, path);
    }
    switch (fmt) {
    case FMT_FACEPUPPET: fmt_facepuppet(o, path, types, argv, t, recv_ns); break;
    case FMT_LEAP: fmt_leap(o, path, types, argv, t, recv_ns, depth); break;
    case FMT_MEDIAPIPE: fmt_mediapipe(o, path, types, argv, t, recv_ns, depth); break;
    default: break;
    }
    o->cur_path = NULL;
    lo_message_free(m);
}

/* A packet or bundle element: "#bundle\0", timetag, then (int32 size, element)*. */
static void handle_packet(osc_input *o, unsigned char *data, size_t size, int64_t t,
                          int64_t recv_ns, int depth)
{
    if (size >= 8 && memcmp(data, "#bundle", 8) == 0) {
        if (size < 16 || depth >= MAX_DEPTH) {
            count(o, FP_OSC_MALFORMED);
            return;
        }
        bump(o, &o->st.bundles);
        const uint32_t sec = be32(data + 8), frac = be32(data + 12);
        const bool rec = o->clock == CLOCK_RECORDING;
        const int64_t bt = rec ? UNTIMED : map_timetag(o, sec, frac, recv_ns);
        size_t at = 16;
        while (at < size) {
            if (size - at < 4) {
                count(o, FP_OSC_MALFORMED);
                return;
            }
            uint32_t n = be32(data + at);
            at += 4;
            if (n == 0 || n % 4 || n > size - at) {
                count(o, FP_OSC_MALFORMED);
                return;
            }
            /* (recording: after each element, which may be the sender's origin) */
            handle_packet(o, data + at, n, rec ? recording_time(o, sec, frac) : bt, recv_ns, depth + 1);
            at += n;
        }
        return;
    }
    if (size < 4 || size % 4 || data[0] != '/') {
        count(o, FP_OSC_MALFORMED);
        return;
    }
    handle_message(o, data, size, o->clock == CLOCK_RECORDING && depth == 0 ? UNTIMED : t, recv_ns,
                   depth);
}

static void record_latency(osc_input *o, int64_t recv_ns)
{
    float us = (float)((double)(now_ns(o) - recv_ns) / 1e3);
    pthread_mutex_lock(&o->lock);
    o->lat_us[o->lat_n % LATENCY_RING] = us;
    o->lat_n++;
    pthread_mutex_unlock(&o->lock);
}

static void timers(osc_input *o, int64_t now)
{
    if (o->connected && now - o->last_valid_ns > (int64_t)(o->timeout_s * 1e9)) {
        o->connected = false;
        bump(o, &o->st.disconnects);
        for (int h = 0; h < FP_HANDS; h++)
            if (o->hands_seen & (1u << h))
                push_status(o, FP_STATUS_DISCONNECTED, h, "osc: %s hand: no data from %s for %.3g s",
                            h == FP_HAND_LEFT ? "left" : "right", o->sender, o->timeout_s);
        if (!o->hands_seen)
            push_status(o, FP_STATUS_DISCONNECTED, -1, "osc: no data from %s for %.3g s", o->sender,
                        o->timeout_s);
        memset(&o->leap, 0, sizeof o->leap);
        forget_pose_times(o);
        o->have_offset = false; /* the next sender's timetags: on a clock of their own */
        for (int h = 0; h < FP_HANDS; h++) /* the next sender may send no z */
            fp__osc_mp_forget(&o->mp[h]);
        if (o->clock == CLOCK_RECORDING && !o->ended) { /* a stopped clock: never wait on it */
            o->ended = true;
            push_status(o, FP_STATUS_END_OF_STREAM, -1, "osc: %s's recording stopped without its "
                        "end (no data for %.3g s): taken as ended", o->sender, o->timeout_s);
        }
    }
    /* clock=recording: a sender that never connected (every message untimed: not a session's
     * forward=, no /facepuppet/origin) and then went quiet is a stopped clock too: its input
     * ends, so that run does not wait on it for ever */
    if (o->clock == CLOCK_RECORDING && !o->ended && !o->connected && o->heard_ns &&
        now - o->heard_ns > (int64_t)(o->timeout_s * 1e9)) {
        o->ended = true;
        pthread_mutex_lock(&o->lock);
        unsigned long long untimed = (unsigned long long)o->st.problems[FP_OSC_UNTIMED];
        pthread_mutex_unlock(&o->lock);
        push_status(o, FP_STATUS_END_OF_STREAM, -1, "osc: %s sent nothing on a recording's clock "
                    "(%llu messages without a time on it: clock=recording takes a session's forward=) "
                    "and has been quiet for %.3g s: taken as ended", o->sender, untimed, o->timeout_s);
        logf_(o, FP_LOG_WARNING, "port %u: %s sent nothing on a recording's clock (%llu messages "
              "without a time on it: clock=recording takes a session's forward=, docs/osc.md) and "
              "has been quiet for %.3g s: taken as ended", (unsigned)o->port, o->sender, untimed,
              o->timeout_s);
    }
    /* A hand the tracker lost while the sender goes on (out of a camera's view, or a Leap
     * frame without it): gone after the same silence, so its grab lets go as a stopped
     * sender's does; its next pose brings it back. */
    for (int h = 0; o->connected && h < FP_HANDS; h++) {
        const unsigned bit = 1u << h;
        if (!(o->hands_seen & bit) || (o->hands_lost & bit) ||
            now - o->hand_last_ns[h] <= (int64_t)(o->timeout_s * 1e9))
            continue;
        o->hands_lost |= bit;
        bump(o, &o->st.hands_lost);
        push_status(o, FP_STATUS_DISCONNECTED, h, "osc: %s hand: not in %s's data for %.3g s "
                    "(the tracker lost it): taken as gone until it comes back",
                    h == FP_HAND_LEFT ? "left" : "right", o->sender, o->timeout_s);
        fp__osc_mp_forget(&o->mp[h]);
    }
    for (int k = 0; k < FP_OSC_PROBLEMS; k++) {
        if (o->report_at[k] <= 0 || now < o->report_at[k]) continue;
        o->report_at[k] = -1;
        pthread_mutex_lock(&o->lock);
        unsigned long long n = (unsigned long long)o->st.problems[k];
        pthread_mutex_unlock(&o->lock);
        char first[256] = "";
        if (k == FP_OSC_UNKNOWN_ADDRESS && o->unknown_first[0])
            snprintf(first, sizeof first, " (first: %s%s; format %s takes %s)", o->unknown_first,
                     foreign_space(o->unknown_first), fp__osc_format_names[o->format],
                     format_space(o->format));
        else if ((k == FP_OSC_BAD_COUNT || k == FP_OSC_BAD_TYPES) && o->bad_first[k == FP_OSC_BAD_TYPES][0])
            snprintf(first, sizeof first, " (first: %s; docs/osc.md)", o->bad_first[k == FP_OSC_BAD_TYPES]);
        logf_(o, FP_LOG_WARNING, "port %u: %llu %s%s in the first second (dropped; further ones "
              "are counted, totals at stop)", (unsigned)o->port, n, problem_text[k], first);
        push_status(o, FP_STATUS_WARNING, -1, "osc: %llu %s (%s)", n, problem_names[k],
                    "dropped, counted");
    }
}

static void *osc_thread(void *arg)
{
    osc_input *o = arg;
    struct pollfd fds[3] = {{o->stop_pipe[0], POLLIN, 0}, {o->sock, POLLIN, 0}, {o->sock6, POLLIN, 0}};
    for (;;) {
        int rc = poll(fds, 3, TICK_MS); /* (a negative sock6 is left out by poll) */
        if (rc < 0 && errno != EINTR) {
            push_status(o, FP_STATUS_ERROR, -1, "osc: poll: %s", strerror(errno));
            return NULL;
        }
        if (fds[0].revents) return NULL;
        for (int s = 1; s < 3; s++)
        for (int i = 0; i < BURST && rc > 0 && (fds[s].revents & POLLIN); i++) {
            struct sockaddr_storage from;
            union { char buf[CMSG_SPACE(sizeof(uint32_t))]; struct cmsghdr align; } ctl;
            struct iovec iov = {o->buf, sizeof o->buf};
            struct msghdr mh = {.msg_name = &from, .msg_namelen = sizeof from, .msg_iov = &iov,
                                .msg_iovlen = 1, .msg_control = ctl.buf, .msg_controllen = sizeof ctl.buf};
            ssize_t n = recvmsg(fds[s].fd, &mh, MSG_DONTWAIT | MSG_TRUNC);
            if (n < 0) break; /* EAGAIN: drained */
            kernel_drops(o, s - 1, &mh);
            int64_t recv_ns = now_ns(o);
            bump(o, &o->st.packets);
            if ((size_t)n > sizeof o->buf) {
                count(o, FP_OSC_MALFORMED);
                continue;
            }
            if (!o->connected) fp_udp_sender_text(&from, o->sender, sizeof o->sender);
            o->packet_pushed = false;
            o->pkt_from = from;
            o->heard_ns = recv_ns;
            handle_packet(o, o->buf, (size_t)n, recv_ns, recv_ns, 0);
            leap_end_packet(o, recv_ns);
            mp_end_packet(o, recv_ns);
            if (o->packet_pushed) record_latency(o, recv_ns);
        }
        timers(o, now_ns(o));
    }
}

/* ------------------------------------------------------------------------------------- */
/* fp_input                                                                               */

static int osc_start(fp_input *self, char *err, size_t errlen)
{
    osc_input *o = self->plugin_data;
    if (o->running) {
        snprintf(err, errlen, "osc: already started");
        return -EBUSY;
    }
    if (pipe2(o->stop_pipe, O_CLOEXEC | O_NONBLOCK) != 0) {
        int e = errno;
        snprintf(err, errlen, "osc: pipe: %s", strerror(e));
        return -e;
    }
    o->connected = false;
    o->origin_ns = o->clock_t = now_ns(o);
    o->have_sender_origin = o->ended = false;
    o->heard_ns = 0;
    if (o->clock == CLOCK_RECORDING) /* the recording's time zero here: its first event */
        push_status(o, FP_STATUS_CONNECTED, -1, "osc: port %u, on the sender's recording clock "
                    "(clock=recording): waiting for a forwarded recording", (unsigned)o->port);
    int rc = pthread_create(&o->thread, NULL, osc_thread, o);
    if (rc) {
        close(o->stop_pipe[0]);
        close(o->stop_pipe[1]);
        snprintf(err, errlen, "osc: cannot start its thread: %s", strerror(rc));
        return -rc;
    }
    o->running = true;
    logf_(o, FP_LOG_INFO, "listening on %s (format %s)", o->bind_text,
          fp__osc_format_names[o->format]);
    return 0;
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static void get_stats(const fp_input *in, fp_osc_stats *out)
{
    osc_input *o = in->plugin_data;
    uint32_t want = out->size && out->size < sizeof(fp_osc_stats) ? out->size : sizeof(fp_osc_stats);
    float *tmp = malloc(LATENCY_RING * sizeof *tmp);
    fp_osc_stats s;
    pthread_mutex_lock(&o->lock);
    s = o->st;
    size_t n = !tmp ? 0 : o->lat_n < LATENCY_RING ? (size_t)o->lat_n : LATENCY_RING;
    if (n) memcpy(tmp, o->lat_us, n * sizeof *tmp);
    pthread_mutex_unlock(&o->lock);
    s.size = want;
    s.port = o->port;
    s.latency_samples = n;
    s.latency_median_us = s.latency_p99_us = 0;
    if (n) {
        qsort(tmp, n, sizeof *tmp, cmp_float);
        s.latency_median_us = n % 2 ? tmp[n / 2] : 0.5 * ((double)tmp[n / 2 - 1] + tmp[n / 2]);
        size_t k = (size_t)ceil(0.99 * (double)n) - 1;
        s.latency_p99_us = tmp[k < n ? k : n - 1];
    }
    free(tmp);
    memcpy(out, &s, want);
}

static void osc_stop(fp_input *self)
{
    osc_input *o = self->plugin_data;
    if (!o->running) return;
    ssize_t w = write(o->stop_pipe[1], "x", 1);
    (void)w;
    pthread_join(o->thread, NULL);
    close(o->stop_pipe[0]);
    close(o->stop_pipe[1]);
    o->running = false;
    fp_osc_stats s = {.size = sizeof s};
    get_stats(self, &s);
    char problems[512] = "";
    size_t len = 0;
    for (int k = 0; k < FP_OSC_PROBLEMS; k++)
        if (s.problems[k] && len < sizeof problems)
            len += (size_t)snprintf(problems + len, sizeof problems - len, "%s%s %llu", len ? ", " : "",
                                    problem_names[k], (unsigned long long)s.problems[k]);
    logf_(o, FP_LOG_INFO, "port %u: %llu packets, %llu messages, %llu bundles, %llu events, "
          "%llu hands lost; latency packet -> event median %.1f us, p99 %.1f us (%llu packets); problems: %s",
          (unsigned)s.port, (unsigned long long)s.packets, (unsigned long long)s.messages,
          (unsigned long long)s.bundles, (unsigned long long)s.events,
          (unsigned long long)s.hands_lost, s.latency_median_us,
          s.latency_p99_us, (unsigned long long)s.latency_samples, len ? problems : "none");
}

static void osc_destroy(fp_input *self)
{
    if (!self) return;
    osc_input *o = self->plugin_data;
    osc_stop(self);
    if (o->sock >= 0) close(o->sock);
    if (o->sock6 >= 0) close(o->sock6);
    pthread_mutex_destroy(&o->lock);
    free(o->lat_us);
    free(o);
}

static const char *problem_name(int kind)
{
    return kind >= 0 && kind < FP_OSC_PROBLEMS ? problem_names[kind] : "?";
}

static const fp_osc_ext osc_ext = {.size = sizeof(fp_osc_ext), .get_stats = get_stats,
                                   .problem_name = problem_name};

static bool osc_workspace(const fp_input *self, float min_mm[3], float max_mm[3])
{
    const osc_input *o = self->plugin_data;
    if (!o->have_box) return false;
    memcpy(min_mm, o->box, 3 * sizeof(float));
    memcpy(max_mm, o->box + 3, 3 * sizeof(float));
    return true;
}

static const fp_input_workspace workspace_ext = {.get = osc_workspace};

static bool osc_on_recording_clock(const fp_input *self)
{
    return ((const osc_input *)self->plugin_data)->clock == CLOCK_RECORDING;
}

static const fp_input_clock clock_ext = {.on_recording_clock = osc_on_recording_clock};

static const void *osc_get_extension(const fp_input *self, const char *id)
{
    const osc_input *o = self->plugin_data;
    if (id && strcmp(id, FP_EXT_INPUT_CLOCK) == 0 && o->clock == CLOCK_RECORDING) return &clock_ext;
    if (id && strcmp(id, FP_OSC_EXT_ID) == 0) return &osc_ext;
    if (id && strcmp(id, FP_EXT_WORKSPACE) == 0 && o->have_box) return &workspace_ext;
    return NULL;
}

/* ------------------------------------------------------------------------------------- */
/* Factory                                                                                */

static int osc_create(const fp_host *host, const char *arg, const fp_param *params,
                      size_t nparams, fp_input **out, char *err, size_t errlen)
{
    *out = NULL;
    if (!host || !host->push_event || !host->now_ns) {
        snprintf(err, errlen, "osc: the host lacks push_event or now_ns");
        return -EINVAL;
    }
    osc_settings set;
    int rc = fp__osc_parse_spec(arg, params, nparams, &set, err, errlen);
    if (rc) return rc;
    osc_input *o = calloc(1, sizeof *o);
    if (!o || !(o->lat_us = calloc(LATENCY_RING, sizeof *o->lat_us))) {
        free(o);
        snprintf(err, errlen, "osc: out of memory");
        return -ENOMEM;
    }
    fp_udp_listener ls;
    char why[384];
    if ((rc = fp_udp_listen(set.bind_addr, set.port, &ls, why, sizeof why))) {
        snprintf(err, errlen, "osc: %s", why);
        free(o->lat_us);
        free(o);
        return rc;
    }
    o->sock = ls.sock;
    o->sock6 = ls.sock6;
    o->kernel_total[0] = o->kernel_total[1] = 0;
#ifdef SO_RXQ_OVFL
    { /* the kernel's drops, counted (kernel_drops); where refused, they go uncounted */
        int on = 1;
        (void)setsockopt(o->sock, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);
        if (o->sock6 >= 0) (void)setsockopt(o->sock6, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);
    }
#endif
    o->port = ls.port;
    snprintf(o->bind_text, sizeof o->bind_text, "%s", ls.text);
    forget_pose_times(o);
    o->host = host;
    o->format = set.format;
    o->hands = set.hands;
    o->clock = set.clock;
    o->timeout_s = set.timeout;
    o->mp_place = (osc_mp_place){(float)set.width, (float)set.aspect, (float)set.height,
                                 (float)set.depth, set.mirror};
    o->have_box = set.have_box;
    memcpy(o->box, set.box, sizeof set.box);
    pthread_mutex_init(&o->lock, NULL);
    o->st.size = sizeof o->st;
    o->st.port = o->port;
    o->input = (fp_input){.size = sizeof(fp_input), .plugin_data = o, .start = osc_start,
                          .stop = osc_stop, .destroy = osc_destroy,
                          .get_extension = osc_get_extension};
    if (!ls.loopback)
        logf_(o, FP_LOG_WARNING, "listening on %s beyond loopback: any host that can reach "
              "this port can drive the hands", o->bind_text);
    if (ls.warning[0]) logf_(o, FP_LOG_WARNING, "%s", ls.warning);
    *out = &o->input;
    return 0;
}

static const fp_input_factory osc_factory = {
    .size = sizeof(fp_input_factory),
    .name = "osc",
    .description = "hand tracking over OSC/UDP (facepuppet, Leap Motion bridges, MediaPipe hands)",
    .usage = fp__osc_usage,
    .create = osc_create,
    .params = fp__osc_keys,
};

static const void *osc_get_factory(const char *factory_id)
{
    if (factory_id && strcmp(factory_id, FP_INPUT_FACTORY_ID) == 0) return &osc_factory;
    return NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.input-osc",
    .version = "1.0.0",
    .get_factory = osc_get_factory,
};
