/*
 * cyberglove.c: input plugin for CyberGlove I/II/III data gloves on a serial line.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * SPEC: cyberglove:/dev/ttyUSB0[,baud=115200][,cal=FILE][,hand=left|right][,rate=HZ]
 *                  [,mode=stream|poll][,bits=8|16][,timeout=MS]
 *
 * One instance = one glove on one port, one thread (no global state: two gloves on two
 * ports are two instances). The thread opens the port raw (termios, 8N1, O_NOCTTY), probes
 * the glove (?G ?S ?R ?V ?D, `D 0` where ?D is unanswered, then U 1 to get the status
 * byte), sets the sample period with the ASCII command `t w1 w2\r` (period = w1*w2/115200
 * s, shared/docs/devices.md), then streams (`S`) or polls (`G` at `rate`), or in 16-bit
 * mode sends `1eu` then `1S`.
 * Records are decoded (glove_decode.h, pure), calibrated (glove_cal.h) and pushed as fp_event_joint_angles stamped
 * with fp_host.now_ns taken when the chunk holding the record's last byte was read.
 *
 * Faults (each reported as fp_event_status; the session keeps the last pose since no angles
 * are pushed meanwhile):
 *  - glove unplugged from its box: status bit0 clear or an `eg` pair -> DISCONNECTED; the
 *    port stays open, CONNECTED again when records say plugged;
 *  - cable pulled: EOF, EIO or POLLHUP -> DISCONNECTED, then RECONNECTING with exponential
 *    backoff (100 ms doubling to 2 s): the device path is re-opened and the glove re-probed;
 *  - line noise: bytes that do not form a record are skipped until the next plausible record
 *    (start byte, non-zero sensor bytes, 0x00 terminator at the right place) -> WARNING;
 *  - silence: no record for `timeout` ms (default 3 record periods, at least 250 ms and 3
 *    records' time on the line at `baud`) ->
 *    DISCONNECTED, then as for a pulled cable.
 */
#define _GNU_SOURCE
#include <facepuppet/plugin_util.h> /* fp_parse_decimal: numbers as in every key */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "cyberglove.h"
#include "fp_error.h"
#include "fp_stats.h"
#include "facepuppet/plugin.h"
#include "glove_cal.h"
#include "glove_decode.h"
#include "glove_outage.h"

#define LAT_CAP 65536
#define BACKOFF_MIN_MS 100
#define BACKOFF_MAX_MS 2000

typedef struct glove {
    fp_input input;
    const fp_host *host;

    /* configuration (SPEC) */
    char path[PATH_MAX];
    int baud;
    speed_t speed;
    fpg_cal cal;
    char cal_path[PATH_MAX];
    int hand_opt;       /* -1 from ?R */
    double rate_hz;
    bool poll_mode;
    int bits;
    int timeout_ms;     /* no record this long: the glove stopped answering */
    int timeout_base_ms; /* timeout= or 3 periods at rate=, at least 250 (create) */
    bool timeout_given; /* timeout= said it: kept whatever the line */

    /* thread */
    pthread_t thread;
    bool thread_started;
    int wake[2];
    atomic_bool stopping;
    int fd;

    /* from the probe */
    int sensors;
    int sampled;                 /* values a record carries (?N; sensors unless fewer) */
    int right;          /* ?R */
    bool ts_on, status_on;
    char version[64];
    int hand;           /* used in events */

    /* decoder (glove_decode.h) */
    fpg_decoder dec;
    bool in_noise;
    uint64_t noise_episode;
    bool unplugged;
    bool warned_fast;
    bool warned_nonfinite, warned_line; /* (the last: baud cannot carry rate, said once) */
    int rec_len;        /* bytes of a record as the probe expects it (16-bit: the shortest) */
    int64_t last_record_ns;
    uint64_t units;     /* records and bare error messages decoded */
    fpg_lenmeter meter; /* the records' length as sent (a box the probe misread) */
    fpg_outage outage;  /* an outage is said in few lines (glove_outage.h) */
    bool up_pending;    /* the probe answered, no unit yet: CONNECTED at the first */

    /* statistics */
    pthread_mutex_t lock;
    fp_cyberglove_stats st;
    int32_t *lat;       /* ns, ring of LAT_CAP */
    uint64_t lat_n;
} glove;

/* ------------------------------------------------------------------------------------- */
/* Small helpers                                                                         */

static int64_t now_ns(const glove *g)
{
    if (g->host && g->host->now_ns)
        return g->host->now_ns(g->host);
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void logf_(const glove *g, fp_log_level lvl, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (g->host && g->host->log)
        g->host->log(g->host, lvl, msg);
}

/* The event's text names the port ("PATH: text" unless the text names it already). The host
 * says warnings, errors and disconnections itself, one line each (docs/plugins.md), so only
 * CONNECTED is logged here too (RECONNECTING, one per attempt, is summed up: glove_outage.h).
 * t: the event's time, 0 now (push_status). */
static void push_status_at(glove *g, int64_t t, fp_status_code code, const char *fmt, ...)
{
    fp_event_status ev;
    memset(&ev, 0, sizeof ev);
    ev.header.size = sizeof ev;
    ev.header.type = FP_EVENT_STATUS;
    ev.header.time_ns = t ? t : now_ns(g);
    ev.header.hand = g->hand;
    ev.code = code;
    char text[400], full[PATH_MAX + sizeof text + 2]; /* full: the logged line, whole */
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    const char *sep = strstr(text, g->path) ? "" : ": ";
    snprintf(full, sizeof full, "%s%s%s", *sep ? g->path : "", sep, text);
    if (snprintf(ev.text, sizeof ev.text, "%s", full) >= (int)sizeof ev.text) /* cut: says so */
        memcpy(ev.text + sizeof ev.text - 4, "...", 4);
    g->host->push_event(g->host, &ev.header);
    if (code == FP_STATUS_CONNECTED)
        logf_(g, FP_LOG_INFO, "%s", full);
}

#define push_status(g, ...) push_status_at((g), 0, __VA_ARGS__)

static bool stopping(glove *g) { return atomic_load(&g->stopping); }

/* Wait for `events` on fd or the stop pipe. Returns 1 ready, 0 timeout, -ECANCELED when
 * stopping, -EPIPE on hang-up or error of the port (with no data left to read). */
static int wait_fd(glove *g, int fd, short events, int timeout_ms)
{
    struct pollfd p[2] = {{.fd = g->wake[0], .events = POLLIN}, {.fd = fd, .events = events}};
    int n = fd >= 0 ? 2 : 1;
    for (;;) {
        int r = poll(p, (nfds_t)n, timeout_ms);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return -errno;
        if (stopping(g) || (p[0].revents & POLLIN))
            return -ECANCELED;
        if (r == 0)
            return 0;
        if (p[1].revents & events)
            return 1;
        if (p[1].revents & (POLLHUP | POLLERR | POLLNVAL))
            return -EPIPE;
        return 0;
    }
}

/* Sleep up to ms, interruptible by stop. Returns -ECANCELED when stopping. */
static int nap(glove *g, int ms)
{
    int r = wait_fd(g, -1, 0, ms);
    return r == -ECANCELED ? r : 0;
}

static int write_all(glove *g, const void *buf, size_t n)
{
    const uint8_t *p = buf;
    while (n) {
        ssize_t w = write(g->fd, p, n);
        if (w > 0) {
            p += w;
            n -= (size_t)w;
            continue;
        }
        if (w < 0 && errno == EINTR)
            continue;
        if (w < 0 && errno == EAGAIN) {
            int r = wait_fd(g, g->fd, POLLOUT, 500);
            if (r < 0)
                return r;
            if (r == 0)
                return -ETIMEDOUT;
            continue;
        }
        return w < 0 ? -errno : -EIO;
    }
    return 0;
}

/* Read the reply to a command: skips bytes until `c0` `c1` (c1 < 0: only c0), then collects
 * `fixed` value bytes whatever they are (a value may be 0, e.g. ?R of a left glove) or, with
 * fixed == 0, the bytes up to the 0x00 terminator. An `e` `?` reply gives -ENOTSUP; the
 * other error replies, `e` X 0x00, their box_error_code (-ENODEV for `eg`, ...). Returns
 * the number of value bytes, one of those codes, -ETIMEDOUT, -ECANCELED, -EPIPE or -EIO. */
static int read_reply_n(glove *g, int c0, int c1, size_t fixed, uint8_t *out, size_t cap,
                        int timeout_ms)
{
    int64_t deadline = now_ns(g) + (int64_t)timeout_ms * 1000000;
    int state = 0; /* 0 seek c0, 1 seek c1, 2 value, 3 after 'e', 4 after `e` X: its 0x00 */
    size_t n = 0;
    int box_err = 0;
    for (;;) {
        int64_t left = (deadline - now_ns(g)) / 1000000;
        if (left < 0)
            return -ETIMEDOUT;
        int r = wait_fd(g, g->fd, POLLIN, (int)left + 1);
        if (r < 0)
            return r;
        if (r == 0)
            continue;
        uint8_t buf[128];
        ssize_t got = read(g->fd, buf, sizeof buf);
        if (got == 0)
            return -EPIPE;
        if (got < 0) {
            if (errno == EAGAIN || errno == EINTR)
                continue;
            return errno == EIO ? -EPIPE : -errno;
        }
        for (ssize_t i = 0; i < got; i++) {
            uint8_t b = buf[i];
            switch (state) {
            case 0:
                if (b == c0)
                    state = c1 < 0 ? 2 : 1;
                else if (b == 'e')
                    state = 3;
                break;
            case 1:
                state = b == c1 ? 2 : (b == c0 ? 1 : 0);
                break;
            case 2:
                if (fixed && n < fixed) {
                    if (n < cap)
                        out[n] = b;
                    n++;
                    break;
                }
                if (b == 0)
                    return (int)(n < cap ? n : cap);
                if (fixed)
                    return -EPROTO;   /* more value bytes than the query has */
                if (n < cap)
                    out[n++] = b;
                break;
            case 3:
                if (b == '?')
                    return -ENOTSUP;
                if ((box_err = fpg_box_error_code(b)) != 0) {
                    state = 4;
                    break;
                }
                state = b == c0 ? (c1 < 0 ? 2 : 1) : 0;
                break;
            case 4: /* (`eg` without its 0x00 is not the box's reply: seek on) */
                if (b == 0)
                    return box_err;
                state = b == c0 ? (c1 < 0 ? 2 : 1) : b == 'e' ? 3 : 0;
                break;
            }
        }
    }
}

static int read_reply(glove *g, int c0, int c1, uint8_t *out, size_t cap, int timeout_ms)
{
    return read_reply_n(g, c0, c1, 0, out, cap, timeout_ms);
}

/* Send a query `?X` and read its value bytes (`fixed` of them, 0: up to the terminator). */
static int query(glove *g, char x, size_t fixed, uint8_t *out, size_t cap)
{
    uint8_t cmd[2] = {'?', (uint8_t)x};
    int r = write_all(g, cmd, 2);
    if (r < 0)
        return r;
    return read_reply_n(g, '?', x, fixed, out, cap, 500);
}

/* ------------------------------------------------------------------------------------- */
/* Port                                                                                  */

static int speed_of(int baud, speed_t *out)
{
    static const struct { int baud; speed_t s; } t[] = {
        {1200, B1200}, {2400, B2400}, {4800, B4800}, {9600, B9600}, {19200, B19200},
        {38400, B38400}, {57600, B57600}, {115200, B115200}, {230400, B230400},
        {460800, B460800}, {921600, B921600}};
    for (size_t i = 0; i < sizeof t / sizeof t[0]; i++)
        if (t[i].baud == baud) {
            *out = t[i].s;
            return 0;
        }
    return -1;
}

/* Open the port raw, 8N1, at the configured speed. Returns fd or -errno (message in err). */
static int open_port(const glove *g, char *err, size_t errlen)
{
    int fd = open(g->path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        int e = errno;
        return fp_errorf(err, errlen, -e, "cannot open %s: %s%s", g->path, strerror(e),
                    e == EACCES ? " (join the dialout group or add a udev rule, see "
                                  "docs/cyberglove.md)" : "");
    }
    struct termios t;
    if (tcgetattr(fd, &t) != 0) {
        int e = errno;
        close(fd);
        /* (ENOTTY: a file or another device; -ENODEV: an input device that cannot be
         * opened as one, exit 66) */
        return fp_errorf(err, errlen, e == ENOTTY ? -ENODEV : -e, "%s is not a serial port: %s",
                         g->path, strerror(e));
    }
    t.c_iflag &= ~(tcflag_t)(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON |
                             IXOFF | IXANY | INPCK);
    t.c_oflag &= ~(tcflag_t)OPOST;
    t.c_lflag &= ~(tcflag_t)(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
    t.c_cflag &= ~(tcflag_t)(CSIZE | PARENB | CSTOPB | CRTSCTS);
    t.c_cflag |= CS8 | CREAD | CLOCAL;
    t.c_cc[VMIN] = 1;
    t.c_cc[VTIME] = 0;
    cfsetispeed(&t, g->speed);
    cfsetospeed(&t, g->speed);
    if (tcsetattr(fd, TCSANOW, &t) != 0) {
        int e = errno;
        close(fd);
        return fp_errorf(err, errlen, -e, "cannot configure %s: %s", g->path, strerror(e));
    }
    tcflush(fd, TCIOFLUSH);
    return fd;
}

/* Stop any stream and read until the line is quiet for 30 ms (at most 500 ms). The stop is
 * sent both ways docs/devices.md names, 0x03 and `^c` (a box that knows one answers the other
 * with `e?`, drained here). */
static int drain(glove *g)
{
    const uint8_t stop[3] = {0x03, '^', 'c'};
    int r = write_all(g, stop, sizeof stop);
    if (r < 0)
        return r;
    int64_t end = now_ns(g) + 500000000;
    while (now_ns(g) < end) {
        r = wait_fd(g, g->fd, POLLIN, 30);
        if (r < 0)
            return r;
        if (r == 0)
            break;
        uint8_t buf[256];
        ssize_t got = read(g->fd, buf, sizeof buf);
        if (got == 0 || (got < 0 && errno == EIO))
            return -EPIPE;
    }
    tcflush(g->fd, TCIFLUSH);
    return 0;
}

/* The glove sensors a record carries, where ?N says fewer than the glove has: their count,
 * order[] the glove sensor of each value (the software mask ?M's bits, low first; without a
 * mask, 18 of 22 are the 18-sensor glove's). Returns that count, 0 when every sensor is
 * sampled (or ?N goes unanswered), or a negative code with a message in err. */
static int sampled_order(glove *g, int sensors, uint8_t order[FPG_SENSORS], char *err, size_t errlen)
{
    uint8_t v[64];
    int r = query(g, 'N', 1, v, sizeof v);
    if (r == -EPIPE || r == -ECANCELED)
        return fp_errorf(err, errlen, r, "line lost");
    if (r < 1 || v[0] == sensors)
        return 0;
    int n = v[0];
    if (n < 1 || n > sensors)
        return fp_errorf(err, errlen, -EPROTO, "?N = %d sensors sampled of the glove's %d (?S)", n,
                         sensors);
    r = query(g, 'M', 3, v, sizeof v);
    if (r == -EPIPE || r == -ECANCELED)
        return fp_errorf(err, errlen, r, "line lost");
    uint32_t mask = r == 3 ? (uint32_t)v[0] | (uint32_t)v[1] << 8 | (uint32_t)v[2] << 16 : 0;
    if (r != 3 || __builtin_popcount(mask) != n || (mask >> FPG_SENSORS)) {
        if (!(n == 18 && sensors == 22))
            return fp_errorf(err, errlen, -EPROTO,
                             "?N = %d sensors sampled of %d, and the software mask (?M) does not "
                             "say which (%s)", n, sensors, r == 3 ? "its bits disagree" : "no answer");
        mask = ((1u << FPG_SENSORS) - 1) & ~(1u << 6 | 1u << 9 | 1u << 13 | 1u << 17); /* no DIJ */
    }
    int k = 0;
    for (int i = 0; i < FPG_SENSORS; i++)
        if (mask & (1u << i))
            order[k++] = (uint8_t)i;
    return k;
}

/* Probe the glove and start it. Returns 0, or a negative code with a message in err. */
static int probe(glove *g, char *err, size_t errlen)
{
    uint8_t v[64];
    int r = drain(g);
    if (r < 0)
        return fp_errorf(err, errlen, r, "%s: line lost while draining", g->path);
    /* A CyberGlove III in 16-bit mode needs only `1eu` `1S` (docs/devices.md): its ?G and
     * ?S are asked, and a box that answers them e? or not at all is taken as plugged, 22 */
    const bool optional = g->bits == 16;
    r = query(g, 'G', 1, v, sizeof v);
    if (!(optional && (r == -ETIMEDOUT || r == -ENOTSUP))) {
        if (r == -ETIMEDOUT)
            return fp_errorf(err, errlen, r, "no answer to ?G (is the glove box on, baud %d?)", g->baud);
        if (r == -ENODEV)
            return fp_errorf(err, errlen, r, "glove not plugged into its box (?G answered eg)");
        if (r < 1)
            return fp_errorf(err, errlen, r < 0 ? r : -EPROTO, "bad answer to ?G%s%s%s",
                             r < 0 ? " (" : "", r < 0 ? fpg_reply_text(r) : "", r < 0 ? ")" : "");
        if ((v[0] & 3) != 3) /* bit 0 initialised, bit 1 glove plugged */
            return fp_errorf(err, errlen, -ENODEV, "glove not plugged into its box (?G = %d)", v[0]);
    }
    r = query(g, 'S', 1, v, sizeof v);
    if (optional && (r == -ETIMEDOUT || r == -ENOTSUP)) {
        v[0] = 22;
    } else if (r == -ENODEV) {
        return fp_errorf(err, errlen, r, "glove not plugged into its box (?S answered eg)");
    } else if (r < 1) {
        return fp_errorf(err, errlen, r < 0 ? r : -EPROTO, "bad answer to ?S%s%s%s",
                         r < 0 ? " (" : "", r < 0 ? fpg_reply_text(r) : "", r < 0 ? ")" : "");
    }
    if (v[0] != 18 && v[0] != 22)
        return fp_errorf(err, errlen, -EPROTO, "unsupported sensor count %d (?S)", v[0]);
    if (g->bits == 16 && v[0] != 22)
        return fp_errorf(err, errlen, -EPROTO, "bits=16 needs a 22-sensor CyberGlove III (?S = %d)",
                    v[0]);
    int sensors = v[0];
    /* The sensors sampled (?N) make the record; where not all, the software mask (?M) says
     * which. Optional: a box that does not answer ?N samples every sensor. */
    uint8_t order[FPG_SENSORS];
    int sampled = sensors;
    if (g->bits == 8) { /* (a 16-bit frame carries all 22: r still holds ?S's byte count) */
        if ((r = sampled_order(g, sensors, order, err, errlen)) < 0)
            return r;
        if (r > 0)
            sampled = r;
    }
    /* ?R, ?V, ?D and U are optional: a box that answers them with e? or not at all (a
     * minimal one; the late reply of a slow one is skipped by the next read, which seeks its
     * own header) leaves their defaults */
    r = query(g, 'R', 1, v, sizeof v);
    int right = r >= 1 ? (v[0] != 0) : -1;
    if (r < 0 && !fpg_unanswered(r))
        return fp_errorf(err, errlen, r, "bad answer to ?R");
    char version[64] = "";
    r = query(g, 'V', 0, v, sizeof v - 1);
    if (r < 0 && !fpg_unanswered(r))
        return fp_errorf(err, errlen, r, "bad answer to ?V");
    if (r > 0) {
        for (int i = 0; i < r && i < (int)sizeof version - 1; i++)
            version[i] = (v[i] >= 32 && v[i] < 127) ? (char)v[i] : '.';
        version[r < (int)sizeof version ? r : (int)sizeof version - 1] = '\0';
    }
    bool ts_on = false, status_on = false, status_unknown = false;
    if (g->bits == 8) {
        r = query(g, 'D', 1, v, sizeof v);
        if (r < 0 && !fpg_unanswered(r))
            return fp_errorf(err, errlen, r, "bad answer to ?D");
        ts_on = r >= 1 && v[0] != 0;
        if (r < 1) { /* ?D said nothing: turn the timestamps off, so that "off" is true */
            uint8_t d0[2] = {'D', 0};
            if ((r = write_all(g, d0, 2)) < 0)
                return fp_errorf(err, errlen, r, "line lost");
            r = read_reply(g, 'D', -1, v, sizeof v, 300);
            if (r == -EPIPE || r == -ECANCELED)
                return fp_errorf(err, errlen, r, "line lost");
        }
        uint8_t u[2] = {'U', 1};
        if ((r = write_all(g, u, 2)) < 0)
            return fp_errorf(err, errlen, r, "line lost");
        r = read_reply(g, 'U', -1, v, sizeof v, 500);
        if (r < 0 && !fpg_unanswered(r))
            return fp_errorf(err, errlen, r, "bad answer to U 1");
        status_on = r >= 0;
        /* ?U decides where it answers (the record layout depends on it): U 1 may have been
         * taken without an acknowledgement */
        int q = query(g, 'U', 1, v, sizeof v);
        if (q >= 1)
            status_on = v[0] != 0;
        else if (q == -EPIPE || q == -ECANCELED)
            return fp_errorf(err, errlen, q, "line lost");
        else if (r == -ETIMEDOUT)
            status_unknown = true; /* neither U 1 nor ?U answered: the records will show it */
    }
    /* sample period: ASCII `t w1 w2\r`, period = w1*w2/115200 s */
    double w = 115200.0 / g->rate_hz;
    unsigned w2 = 1;
    while (w / w2 > 65535.0)
        w2++;
    unsigned w1 = (unsigned)(w / w2 + 0.5);
    if (w1 < 1)
        w1 = 1;
    char tcmd[32];
    int tn = snprintf(tcmd, sizeof tcmd, "t %u %u\r", w1, w2);
    if ((r = write_all(g, tcmd, (size_t)tn)) < 0)
        return fp_errorf(err, errlen, r, "line lost");
    r = read_reply(g, 't', -1, v, sizeof v, 300);
    if (r == -EPIPE || r == -ECANCELED)
        return fp_errorf(err, errlen, r, "line lost");
    if (r < 0)
        logf_(g, FP_LOG_WARNING, "%s: sample period command `t %u %u` not acknowledged (%s)",
              g->path, w1, w2, fpg_reply_text(r));

    g->sensors = sensors;
    g->right = right;
    g->ts_on = ts_on;
    g->status_on = status_on;
    snprintf(g->version, sizeof g->version, "%s", version);
    g->hand = g->hand_opt >= 0 ? g->hand_opt : (right >= 0 ? right : FP_HAND_RIGHT);
    fpg_decoder_init(&g->dec, g->bits, sensors, ts_on, status_on);
    if (sampled != sensors)
        (void)fpg_decoder_set_order(&g->dec, sampled, order); /* (checked by sampled_order) */
    g->sampled = sampled;
    g->dec.status_seen = status_unknown;
    g->in_noise = false;
    g->unplugged = false;
    g->warned_fast = false;
    g->meter = (fpg_lenmeter){0};
    g->rec_len = g->bits == 16 ? 3 + 8 + 1 + 44 : 1 + sampled + (ts_on ? 5 : 0) + status_on + 1;
    g->timeout_ms = g->timeout_given ? g->timeout_base_ms
                                      : fpg_line_timeout_ms(g->baud, g->rec_len, g->timeout_base_ms);

    if (g->bits == 16) {
        if ((r = write_all(g, "1eu", 3)) < 0 || (r = write_all(g, "1S", 2)) < 0)
            return fp_errorf(err, errlen, r, "line lost");
    } else if (!g->poll_mode) {
        if ((r = write_all(g, "S", 1)) < 0)
            return fp_errorf(err, errlen, r, "line lost");
    }
    pthread_mutex_lock(&g->lock);
    g->st.connects++;
    g->st.sensors = sensors;
    g->st.right_hand = right;
    snprintf(g->st.version, sizeof g->st.version, "%s", version);
    pthread_mutex_unlock(&g->lock);
    if (g->hand_opt >= 0 && right >= 0 && right != g->hand_opt)
        push_status(g, FP_STATUS_WARNING, "hand=%s but the glove says %s (?R); using %s",
                    g->hand_opt ? "right" : "left", right ? "right" : "left",
                    g->hand_opt ? "right" : "left");
    return 0;
}

/* ------------------------------------------------------------------------------------- */
/* Decoding                                                                              */

static void emit_angles(glove *g, const fpg_unit *u, int64_t t_read)
{
    fp_event_joint_angles ev;
    memset(&ev, 0, sizeof ev);
    ev.header.size = sizeof ev;
    ev.header.type = FP_EVENT_JOINT_ANGLES;
    ev.header.time_ns = t_read;
    ev.header.hand = g->hand;
    if (fpg_angles_from_raw(&g->cal, u, ev.radians, &ev.valid) && !g->warned_nonfinite) {
        g->warned_nonfinite = true;
        logf_(g, FP_LOG_WARNING, "%s: calibration gives a non-finite angle; sensor left out",
              g->path);
    }
    bool ok = g->host->push_event(g->host, &ev.header);
    int64_t lat = now_ns(g) - t_read;
    pthread_mutex_lock(&g->lock);
    if (ok)
        g->st.events++;
    else
        g->st.dropped++;
    g->lat[g->lat_n % LAT_CAP] = (int32_t)(lat > INT32_MAX ? INT32_MAX : lat);
    g->lat_n++;
    pthread_mutex_unlock(&g->lock);
}

/* The session's first unit: CONNECTED, the outage over. Until then it is one more attempt
 * (a box whose records never match the probe: an outage, not a line pair per probe). */
static void say_up(glove *g, int64_t t)
{
    char sampled[32] = "", back[64];
    g->up_pending = false;
    if (g->sampled != g->sensors)
        snprintf(sampled, sizeof sampled, " (%d sampled)", g->sampled);
    fpg_outage_up(&g->outage, now_ns(g), back, sizeof back);
    /* (at its first record's time: a recording's times only grow) */
    push_status_at(g, t, FP_STATUS_CONNECTED, "%d sensors%s, %s hand, %s %s%s%s%s", g->sensors,
                sampled, g->hand ? "right" : "left", g->bits == 16 ? "16-bit" : "8-bit",
                g->poll_mode ? "poll" : "stream", g->version[0] ? ", version " : "",
                g->version, back); /* (no version field where ?V went unanswered) */
    char slow[160]; /* a line too slow for the rate: said once, at the first connect */
    if (!g->warned_line &&
        (g->warned_line = fpg_line_too_slow(g->baud, g->rate_hz, g->rec_len, slow, sizeof slow)))
        push_status(g, FP_STATUS_WARNING, "%s", slow);
}

static void on_record(glove *g, const fpg_unit *u, int64_t t)
{
    bool plugged = u->plugged;
    int errc = u->errc;
    g->last_record_ns = t;
    g->units++;
    pthread_mutex_lock(&g->lock);
    g->st.records++;
    pthread_mutex_unlock(&g->lock);
    if (g->in_noise) {
        g->in_noise = false;
        logf_(g, FP_LOG_INFO, "%s: resynchronised after %llu noise bytes", g->path,
              (unsigned long long)g->noise_episode);
    }
    if (errc == 'g')
        plugged = false;
    if (errc == 's' && !g->warned_fast) {
        g->warned_fast = true;
        push_status(g, FP_STATUS_WARNING, "glove reports sampling too fast (es) at %g Hz",
                    g->rate_hz);
    }
    if (!plugged) {
        if (!g->unplugged) {
            g->unplugged = true;
            push_status(g, FP_STATUS_DISCONNECTED, "glove unplugged from its box%s",
                        errc == 'g' ? " (eg)" : " (status bit clear)");
        }
        return;
    }
    if (g->unplugged) {
        g->unplugged = false;
        push_status(g, FP_STATUS_CONNECTED, "glove plugged into its box again");
    }
    emit_angles(g, u, t);
}

/* A bare error message `e` X 0x00 (no record): the box is alive. */
static void on_bare_error(glove *g, uint8_t c, int64_t t)
{
    g->last_record_ns = t;
    g->units++;
    if (c == 'g' && !g->unplugged) {
        g->unplugged = true;
        push_status(g, FP_STATUS_DISCONNECTED, "glove unplugged from its box (eg)");
    } else if (c == 's' && !g->warned_fast) {
        g->warned_fast = true;
        push_status(g, FP_STATUS_WARNING, "glove reports sampling too fast (es) at %g Hz",
                    g->rate_hz);
    } else if (c != 'g' && c != 's') {
        logf_(g, FP_LOG_WARNING, "%s: glove answered error e%c", g->path, c);
    }
}

static void on_noise(glove *g, size_t n)
{
    if (!g->in_noise) {
        g->in_noise = true;
        g->noise_episode = 0;
        pthread_mutex_lock(&g->lock);
        g->st.resyncs++;
        pthread_mutex_unlock(&g->lock);
        if (!g->up_pending) /* (before any record: the attempt's failure says it) */
            push_status(g, FP_STATUS_WARNING, "line noise on %s: resynchronising", g->path);
    }
    g->noise_episode += n;
    pthread_mutex_lock(&g->lock);
    g->st.noise_bytes += n;
    pthread_mutex_unlock(&g->lock);
}

/* The decoder's units, as they come (glove_decode.h). */
typedef struct feed_ctx {
    glove *g;
    int64_t t;
} feed_ctx;

static void on_unit(void *user, const fpg_unit *u)
{
    feed_ctx *c = user;
    if (c->g->up_pending && u->kind != FPG_UNIT_NOISE)
        say_up(c->g, c->t);
    if (u->kind == FPG_UNIT_RECORD)
        on_record(c->g, u, c->t);
    else if (u->kind == FPG_UNIT_ERROR)
        on_bare_error(c->g, (uint8_t)u->errc, c->t);
    else
        on_noise(c->g, u->noise);
}

static void feed(glove *g, const uint8_t *data, size_t n, int64_t t)
{
    feed_ctx c = {g, t};
    fpg_decoder_feed(&g->dec, data, n, on_unit, &c);
}

/* ------------------------------------------------------------------------------------- */
/* The input thread                                                                      */

enum { END_STOP = 0, END_LOST = 1, END_SILENT = 2 };

#define SETTLE_MS 20 /* a polled answer's end: the line quiet this long */

/* Read and decode until the line is lost, the glove goes silent, or stop. */
static int session(glove *g, char *why, size_t whylen)
{
    const int64_t period = (int64_t)(1e9 / g->rate_hz);
    const int64_t timeout = (int64_t)g->timeout_ms * 1000000;
    int64_t t0 = now_ns(g);
    g->last_record_ns = t0;
    int64_t next_poll = t0, poll_sent = t0, last_read = t0;
    bool awaiting = false;
    for (;;) {
        int64_t now = now_ns(g);
        if (g->poll_mode && !awaiting && now >= next_poll) {
            uint8_t c = 'G';
            int r = write_all(g, &c, 1);
            if (r == -ECANCELED)
                return END_STOP;
            if (r < 0) {
                snprintf(why, whylen, "cable pulled? write failed: %s", strerror(-r));
                return END_LOST;
            }
            awaiting = true;
            poll_sent = now;
            next_poll += period;
            if (next_poll < now)
                next_poll = now + period;
        }
        int64_t deadline = g->poll_mode ? (awaiting ? poll_sent + timeout : next_poll)
                                        : g->last_record_ns + timeout;
        if (now >= deadline && (!g->poll_mode || awaiting)) {
            pthread_mutex_lock(&g->lock);
            g->st.timeouts++;
            pthread_mutex_unlock(&g->lock);
            if (g->in_noise && g->noise_episode > 0) /* it answers, in records not its own */
                fpg_noise_text(why, whylen, g->bits, g->timeout_ms, g->noise_episode, g->rec_len,
                               g->meter.seen);
            else
                snprintf(why, whylen, "glove stopped answering (no record for %d ms)", g->timeout_ms);
            return END_SILENT;
        }
        int wait_ms = (int)((deadline - now + 999999) / 1000000);
        if (wait_ms < 0)
            wait_ms = 0;
        /* a polled answer whose end cannot tell a status 0 from the terminator (status
         * unknown) is read as ended once the line stays quiet (fpg_decoder_settle) */
        bool held = g->poll_mode && awaiting && g->dec.status_seen && g->dec.len > 0;
        if (held && wait_ms > SETTLE_MS)
            wait_ms = SETTLE_MS;
        int r = wait_fd(g, g->fd, POLLIN, wait_ms);
        if (r == -ECANCELED)
            return END_STOP;
        if (r == -EPIPE) {
            snprintf(why, whylen, "cable pulled (hang-up)");
            return END_LOST;
        }
        if (r == 0 && held) {
            uint64_t before = g->units;
            feed_ctx c = {g, last_read};
            fpg_decoder_settle(&g->dec, on_unit, &c);
            if (g->units != before)
                awaiting = false;
        }
        if (r <= 0)
            continue;
        uint8_t buf[4096];
        ssize_t got = read(g->fd, buf, sizeof buf);
        int64_t t = now_ns(g);
        if (got == 0) {
            snprintf(why, whylen, "cable pulled (end of file)");
            return END_LOST;
        }
        if (got < 0) {
            if (errno == EAGAIN || errno == EINTR)
                continue;
            snprintf(why, whylen, "cable pulled (%s)", strerror(errno));
            return END_LOST;
        }
        uint64_t before = g->units;
        last_read = t;
        fpg_lenmeter_feed(&g->meter, buf, (size_t)got);
        feed(g, buf, (size_t)got, t);
        if (g->poll_mode && g->units != before)
            awaiting = false;
    }
}

static void close_port(glove *g, bool polite)
{
    if (g->fd < 0)
        return;
    if (polite) { /* the stops of both kinds of box (docs/devices.md): 0x03, then ^c */
        const uint8_t stop[3] = {0x03, '^', 'c'};
        (void)!write(g->fd, stop, sizeof stop);
    }
    close(g->fd);
    g->fd = -1;
}

static void *thread_main(void *arg)
{
    glove *g = arg;
    int backoff = BACKOFF_MIN_MS;
    unsigned attempt = 0;
    char why[160], line[400];
    fpg_outage *out = &g->outage;
    for (;;) {
        if (g->fd < 0) {
            if (fpg_outage_attempt(out, now_ns(g), g->path, line, sizeof line))
                logf_(g, FP_LOG_WARNING, "%s", line);
            push_status(g, FP_STATUS_RECONNECTING, "reopening %s in %d ms (attempt %u)", g->path,
                        backoff, ++attempt);
            if (nap(g, backoff) < 0)
                break;
            backoff = backoff * 2 > BACKOFF_MAX_MS ? BACKOFF_MAX_MS : backoff * 2;
            int fd = open_port(g, why, sizeof why);
            if (fd < 0) {
                logf_(g, FP_LOG_DEBUG, "%s", why);
                (void)fpg_outage_failed(out, why); /* (the summary's last reason; the loss was said) */
                continue;
            }
            g->fd = fd;
        }
        int r = probe(g, why, sizeof why), end = END_LOST;
        if (r == -ECANCELED)
            break;
        g->up_pending = r >= 0; /* CONNECTED at the session's first unit (say_up) */
        if (r >= 0 && (end = session(g, why, sizeof why)) == END_STOP)
            break;
        close_port(g, r >= 0 && end == END_SILENT);
        if (r < 0 || g->up_pending) { /* the probe failed, or it answered and no record came */
            int how = fpg_outage_failed(out, why); /* the loss once, a new reason as an event */
            if (how)
                push_status(g, how == 2 ? FP_STATUS_DISCONNECTED : FP_STATUS_RECONNECTING, "%s", why);
            continue;
        }
        backoff = BACKOFF_MIN_MS;
        attempt = 0;
        push_status(g, FP_STATUS_DISCONNECTED, "%s", why);
        fpg_outage_lost(out, why);
    }
    close_port(g, true);
    return NULL;
}

/* ------------------------------------------------------------------------------------- */
/* Statistics                                                                            */

static void get_stats(const fp_input *in, fp_cyberglove_stats *out)
{
    glove *g = in->plugin_data;
    fp_cyberglove_stats s;
    double *tmp = NULL;
    size_t n;
    pthread_mutex_lock(&g->lock);
    s = g->st;
    n = g->lat_n < LAT_CAP ? (size_t)g->lat_n : LAT_CAP;
    if (n)
        tmp = malloc(n * sizeof *tmp);
    if (tmp)
        for (size_t i = 0; i < n; i++) tmp[i] = g->lat[i];
    pthread_mutex_unlock(&g->lock);
    s.latency_samples = tmp ? n : 0;
    s.latency_median_us = s.latency_p99_us = 0;
    if (tmp) {
        s.latency_median_us = fp_median(tmp, n) / 1e3;
        s.latency_p99_us = fp_percentile(tmp, n, 0.99) / 1e3;
        free(tmp);
    }
    uint32_t size = out->size && out->size < sizeof s ? out->size : (uint32_t)sizeof s;
    s.size = size;
    memcpy(out, &s, size);
}

static const fp_cyberglove_ext EXT = {.size = sizeof(fp_cyberglove_ext), .get_stats = get_stats};

static const void *input_get_extension(const fp_input *self, const char *id)
{
    return strcmp(id, FP_CYBERGLOVE_EXT_ID) == 0 ? &EXT : NULL;
}

/* ------------------------------------------------------------------------------------- */
/* fp_input                                                                              */

static int input_start(fp_input *self, char *err, size_t errlen)
{
    glove *g = self->plugin_data;
    if (g->thread_started)
        return fp_errorf(err, errlen, -EALREADY, "cyberglove %s: already started", g->path);
    int fd = open_port(g, err, errlen);
    if (fd < 0)
        return fd;
    g->fd = fd;
    atomic_store(&g->stopping, false);
    int e = pthread_create(&g->thread, NULL, thread_main, g);
    if (e) {
        close(fd);
        g->fd = -1;
        return fp_errorf(err, errlen, -e, "cyberglove %s: cannot start thread: %s", g->path,
                    strerror(e));
    }
    g->thread_started = true;
    return 0;
}

static void input_stop(fp_input *self)
{
    glove *g = self->plugin_data;
    if (!g->thread_started)
        return;
    atomic_store(&g->stopping, true);
    (void)!write(g->wake[1], "x", 1);
    pthread_join(g->thread, NULL);
    g->thread_started = false;
    uint8_t sink[64];
    while (read(g->wake[0], sink, sizeof sink) > 0) {
    }
    fp_cyberglove_stats s = {.size = sizeof s};
    get_stats(self, &s);
    logf_(g, FP_LOG_INFO,
          "%s: %llu records, %llu events (%llu dropped), latency last byte -> event median "
          "%.1f us p99 %.1f us over %llu, %llu noise bytes in %llu resyncs, %llu connects, "
          "%llu timeouts",
          g->path, (unsigned long long)s.records, (unsigned long long)s.events,
          (unsigned long long)s.dropped, s.latency_median_us, s.latency_p99_us,
          (unsigned long long)s.latency_samples, (unsigned long long)s.noise_bytes,
          (unsigned long long)s.resyncs, (unsigned long long)s.connects,
          (unsigned long long)s.timeouts);
}

static void input_destroy(fp_input *self)
{
    glove *g = self->plugin_data;
    input_stop(self);
    close(g->wake[0]);
    close(g->wake[1]);
    pthread_mutex_destroy(&g->lock);
    free(g->lat);
    free(g);
}

/* ------------------------------------------------------------------------------------- */
/* Factory                                                                               */

static const char USAGE[] =
    "cyberglove:DEVICE[,baud=115200][,cal=FILE][,hand=left|right][,rate=HZ][,mode=stream|poll]"
    "[,bits=8|16][,timeout=MS]\n"
    "  DEVICE   serial port of the glove box, e.g. /dev/ttyUSB0\n"
    "  baud     line speed, 8N1 (default 115200; older VTI boxes use 19200)\n"
    "  cal      calibration file: asr two-point (22 lines `rad1:raw1 rad2:raw2`) or\n"
    "           `SENSOR GAIN OFFSET` lines (radians); default raw 1..254 -> 0..90 degrees\n"
    "  hand     left or right (default: the glove's answer to ?R)\n"
    "  rate     records per second (default 100): sample period in stream mode, G rate in poll\n"
    "  mode     stream (S, default) or poll (G per record)\n"
    "  bits     8 (default) or 16 (CyberGlove III USB: 1eu, 1S)\n"
    "  timeout  ms without a record before reconnecting (default 3 periods, at least 250\n"
    "           and 3 records' time at baud)\n";

/* A whole number in lo..hi (lo >= 0), as every integer option reads one (fp_parse_whole: an
 * optional '+' and digits; strtol took a leading blank). */
static int parse_int(const char *s, long lo, long hi, long *out)
{
    unsigned long long v;
    if (!fp_parse_whole(s, (unsigned long long)hi, &v) || v < (unsigned long long)lo)
        return -1;
    *out = (long)v;
    return 0;
}

static int create(const fp_host *host, const char *arg, const fp_param *params, size_t nparams,
                  fp_input **out, char *err, size_t errlen)
{
    if (!host || !host->push_event || !out)
        return fp_errorf(err, errlen, -EINVAL, "cyberglove: bad host");
    if (!arg || !*arg)
        return fp_errorf(err, errlen, -EINVAL,
                    "cyberglove: missing device path, e.g. cyberglove:/dev/ttyUSB0");
    if (strlen(arg) >= PATH_MAX)
        return fp_errorf(err, errlen, -ENAMETOOLONG, "cyberglove: device path too long");
    glove *g = calloc(1, sizeof *g);
    if (!g)
        return fp_errorf(err, errlen, -ENOMEM, "cyberglove: out of memory");
    g->lat = calloc(LAT_CAP, sizeof *g->lat);
    if (!g->lat) {
        free(g);
        return fp_errorf(err, errlen, -ENOMEM, "cyberglove: out of memory");
    }
    g->host = host;
    g->fd = -1;
    g->wake[0] = g->wake[1] = -1;
    snprintf(g->path, sizeof g->path, "%s", arg);
    g->baud = 115200;
    g->hand_opt = -1;
    g->rate_hz = 100;
    g->bits = 8;
    fpg_cal_default(&g->cal);
    long timeout = 0;
    int rc = 0;
    for (size_t i = 0; i < nparams; i++) {
        const char *k = params[i].key, *v = params[i].value ? params[i].value : "";
        long n;
        if (strcmp(k, "baud") == 0) {
            if (parse_int(v, 1, 4000000, &n) != 0 || speed_of((int)n, &g->speed) != 0) {
                rc = fp_errorf(err, errlen, -EINVAL, "cyberglove: baud=%s: not a supported speed "
                          "(1200..921600, standard rates)", v);
                goto fail;
            }
            g->baud = (int)n;
        } else if (strcmp(k, "cal") == 0) {
            char e2[256];
            int r = fpg_cal_load(v, &g->cal, e2, sizeof e2);
            if (r < 0) {
                rc = fp_errorf(err, errlen, r, "cyberglove: cal=%s", e2);
                goto fail;
            }
            snprintf(g->cal_path, sizeof g->cal_path, "%s", v);
        } else if (strcmp(k, "hand") == 0) {
            if (strcmp(v, "left") == 0)
                g->hand_opt = FP_HAND_LEFT;
            else if (strcmp(v, "right") == 0)
                g->hand_opt = FP_HAND_RIGHT;
            else {
                rc = fp_errorf(err, errlen, -EINVAL, "cyberglove: hand=%s: expected left or right", v);
                goto fail;
            }
        } else if (strcmp(k, "rate") == 0) {
            double r;
            if (!fp_parse_decimal(v, &r) || !(r >= 1.0 && r <= 10000.0)) {
                rc = fp_errorf(err, errlen, -EINVAL, "cyberglove: rate=%s: expected 1..10000 Hz", v);
                goto fail;
            }
            g->rate_hz = r;
        } else if (strcmp(k, "mode") == 0) {
            if (strcmp(v, "stream") == 0)
                g->poll_mode = false;
            else if (strcmp(v, "poll") == 0)
                g->poll_mode = true;
            else {
                rc = fp_errorf(err, errlen, -EINVAL, "cyberglove: mode=%s: expected stream or poll", v);
                goto fail;
            }
        } else if (strcmp(k, "bits") == 0) {
            if (strcmp(v, "8") == 0)
                g->bits = 8;
            else if (strcmp(v, "16") == 0)
                g->bits = 16;
            else {
                rc = fp_errorf(err, errlen, -EINVAL, "cyberglove: bits=%s: expected 8 or 16", v);
                goto fail;
            }
        } else if (strcmp(k, "timeout") == 0) {
            if (parse_int(v, 10, 600000, &timeout) != 0) {
                rc = fp_errorf(err, errlen, -EINVAL, "cyberglove: timeout=%s: expected 10..600000 ms",
                          v);
                goto fail;
            }
        } else {
            rc = fp_errorf(err, errlen, -EINVAL, "cyberglove: unknown key `%s` (keys: baud, cal, hand, "
                      "rate, mode, bits, timeout%s)", k,
                      strcmp(k, "record") == 0 ? "; record= is the host's" : "");
            goto fail;
        }
    }
    g->hand = g->hand_opt;   /* -1 (no hand) in status events until ?R answers */
    if (g->bits == 16 && g->poll_mode) {
        rc = fp_errorf(err, errlen, -EINVAL, "cyberglove: bits=16 works with mode=stream only");
        goto fail;
    }
    if (!g->speed)
        speed_of(g->baud, &g->speed);
    g->timeout_given = timeout != 0;
    if (timeout == 0) {
        timeout = (long)(3000.0 / g->rate_hz + 0.5);
        if (timeout < 250)
            timeout = 250;
    }
    g->timeout_ms = g->timeout_base_ms = (int)timeout;
    if (pipe2(g->wake, O_CLOEXEC | O_NONBLOCK) != 0) {
        rc = fp_errorf(err, errlen, -errno, "cyberglove: pipe: %s", strerror(errno));
        goto fail;
    }
    if (pthread_mutex_init(&g->lock, NULL) != 0) {
        rc = fp_errorf(err, errlen, -ENOMEM, "cyberglove: mutex");
        goto fail;
    }
    g->st.size = sizeof g->st;
    g->st.right_hand = -1;
    g->input.size = sizeof g->input;
    g->input.plugin_data = g;
    g->input.start = input_start;
    g->input.stop = input_stop;
    g->input.destroy = input_destroy;
    g->input.get_extension = input_get_extension;
    *out = &g->input;
    return 0;
fail:
    if (g->wake[0] >= 0) {
        close(g->wake[0]);
        close(g->wake[1]);
    }
    free(g->lat);
    free(g);
    return rc;
}

/* The keys, typed (ABI 1.1), for `facepuppet plugins` and `plugins check`; create parses
 * them itself. A default of "" means: none, decided at run time. */
static const fp_param_info KEYS[] = {
    {.name = "baud", .type = FP_PARAM_INT, .min = 1200, .max = 921600, .default_value = "115200",
     .unit = "baud", .description = "line speed, 8N1 (standard rates)"},
    {.name = "cal", .type = FP_PARAM_PATH, .default_value = "",
     .description = "calibration file (asr two-point or SENSOR GAIN OFFSET)"},
    {.name = "hand", .type = FP_PARAM_ENUM, .default_value = "", .choices = "left|right",
     .description = "which hand (default: the glove's answer to ?R)"},
    {.name = "rate", .type = FP_PARAM_FLOAT, .min = 1, .max = 10000, .default_value = "100",
     .unit = "Hz", .description = "records per second"},
    {.name = "mode", .type = FP_PARAM_ENUM, .default_value = "stream", .choices = "stream|poll",
     .description = "stream (S) or poll (G per record)"},
    {.name = "bits", .type = FP_PARAM_ENUM, .default_value = "8", .choices = "8|16",
     .description = "record format (16: CyberGlove III USB)"},
    {.name = "timeout", .type = FP_PARAM_INT, .min = 10, .max = 600000, .default_value = "",
     .unit = "ms", .description = "silence before reconnecting (default 3 periods, >= 250)"},
    {.name = NULL},
};

static const fp_input_factory FACTORY = {
    .size = sizeof(fp_input_factory),
    .name = "cyberglove",
    .description = "CyberGlove I/II/III data glove on a serial port (8-bit or 16-bit records)",
    .usage = USAGE,
    .create = create,
    .params = KEYS,
};

static const void *entry_get_factory(const char *id)
{
    return strcmp(id, FP_INPUT_FACTORY_ID) == 0 ? &FACTORY : NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.input-cyberglove",
    .version = "0.1.0",
    .get_factory = entry_get_factory,
};
