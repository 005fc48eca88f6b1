/*
 * gloveemu.c: CyberGlove emulator on a pseudo-terminal (see gloveemu.h).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "gloveemu.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "fp_error.h"
#include "glove_cal.h"
#include <facepuppet/decimal.h> /* fp_decimal_span: the one syntax of a number */

#define OUT_CAP 65536
#define FAST_LOW_WATER 2048

static const int DIJ[4] = {6, 9, 13, 17};

struct fp_gloveemu {
    fp_gloveemu_options o;
    char link[PATH_MAX];
    char version[64];
    fpg_cal cal;
    float (*deg)[22];   /* recording, NaN = not measured */
    size_t nframes, frame;
    uint32_t present;

    pthread_t thread;
    int wake[2];
    pthread_mutex_t lock;
    pthread_cond_t cond;
    bool stop;
    int req;            /* 1 pull, 2 replug, done when 0 again */
    int req_result;

    int master, slave;
    char slave_path[64];

    /* faults */
    bool plugged, silent, cable_in;
    double slow;
    uint8_t garbage[4096];
    size_t garbage_len;
    bool fixed;
    uint8_t raw8[22];
    uint32_t sampled;   /* the software mask (options' sampled, or every sensor) */

    /* protocol */
    int streaming;
    bool sixteen, ts_on, status_on;
    double period_s;
    int64_t next_ns;
    uint8_t cmd[64];
    size_t cmdlen;
    fp_gloveemu_stats st;
    int64_t t0;

    uint8_t out[OUT_CAP];
    size_t out_len;

    fp_gloveemu_record *hist;
    size_t hist_cap;
};

static int64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

/* ------------------------------------------------------------------------------------- */
/* Recording                                                                             */

static int load_csv(fp_gloveemu *e, const char *path, char *err, size_t errlen)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return fp_errorf(err, errlen, -errno, "%s: %s", path, strerror(errno));
    char line[4096];
    int lineno = 0, rc = 0;
    size_t cap = 0, n = 0, nright = 0;
    float (*rows)[22] = NULL;
    bool *right = NULL;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        if (lineno == 1) {
            if (strncmp(line, "frame,timestamp_us,hand_id,hand_type,", 37) != 0) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:1: not a joint-angle CSV (header)", path);
                goto out;
            }
            continue;
        }
        if (line[0] == '\n' || line[0] == '\0')
            continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 256;
            void *r1 = realloc(rows, cap * sizeof *rows), *r2 = realloc(right, cap);
            if (r1)
                rows = r1;
            if (r2)
                right = r2;
            if (!r1 || !r2) {
                rc = fp_errorf(err, errlen, -ENOMEM, "out of memory");
                goto out;
            }
        }
        char *p = line;
        int col = 0;
        bool is_right = false;
        while (col < 26) {
            char *comma = strpbrk(p, ",\n\r");
            size_t len = comma ? (size_t)(comma - p) : strlen(p);
            if (col == 3)
                is_right = len == 5 && strncmp(p, "right", 5) == 0;
            if (col >= 4) {
                if (len == 0) {
                    rows[n][col - 4] = NAN;
                } else {
                    char *end;
                    double v = strtod(p, &end); /* a decimal, as every number (no hex) */
                    if (end != p + len || !isfinite(v) || fp_decimal_span(p) != len) {
                        rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: column %d is not a number",
                                  path, lineno, col + 1);
                        goto out;
                    }
                    rows[n][col - 4] = (float)v;
                }
            }
            col++;
            if (!comma || *comma != ',')
                break;
            p = comma + 1;
        }
        if (col != 26) {
            rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: %d columns, expected 26", path, lineno, col);
            goto out;
        }
        right[n] = is_right;
        nright += is_right;
        n++;
    }
    if (n == 0) {
        rc = fp_errorf(err, errlen, -EBADMSG, "%s: no frames", path);
        goto out;
    }
    /* keep the frames of this glove's hand when the recording has any */
    bool want_right = !e->o.left;
    size_t nwant = want_right ? nright : n - nright;
    if (nwant) {
        size_t k = 0;
        for (size_t i = 0; i < n; i++)
            if (right[i] == want_right)
                memmove(rows[k++], rows[i], sizeof rows[0]);
        n = k;
    }
    e->deg = rows;
    rows = NULL;
    e->nframes = n;
out:
    free(rows);
    free(right);
    fclose(f);
    return rc;
}

/* ------------------------------------------------------------------------------------- */
/* Pty                                                                                   */

static int open_pty(fp_gloveemu *e)
{
    int m = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (m < 0)
        return -errno;
    char name[64];
    if (grantpt(m) != 0 || unlockpt(m) != 0 || ptsname_r(m, name, sizeof name) != 0) {
        int err = errno;
        close(m);
        return -err;
    }
    int s = open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (s < 0) {
        int err = errno;
        close(m);
        return -err;
    }
    /* power-up line state: 9600, cooked input but no echo, so that what the reader sets is
     * visible (and no echo bounces our bytes back before it sets raw mode) */
    struct termios t;
    if (tcgetattr(s, &t) == 0) {
        t.c_lflag &= ~(tcflag_t)(ECHO | ECHOE | ECHOK | ECHONL);
        cfsetispeed(&t, B9600);
        cfsetospeed(&t, B9600);
        tcsetattr(s, TCSANOW, &t);
    }
    fcntl(m, F_SETFL, fcntl(m, F_GETFL) | O_NONBLOCK);
    e->master = m;
    e->slave = s;
    snprintf(e->slave_path, sizeof e->slave_path, "%s", name);
    if (e->link[0]) {
        char tmp[PATH_MAX + 8];
        snprintf(tmp, sizeof tmp, "%s.new", e->link);
        unlink(tmp);
        if (symlink(name, tmp) != 0 || rename(tmp, e->link) != 0) {
            int err = errno;
            close(s);
            close(m);
            e->master = e->slave = -1;
            return -err;
        }
    }
    e->cable_in = true;
    e->out_len = 0;
    e->cmdlen = 0;
    return 0;
}

static void close_pty(fp_gloveemu *e)
{
    if (e->master >= 0)
        close(e->master);
    if (e->slave >= 0)
        close(e->slave);
    e->master = e->slave = -1;
    e->cable_in = false;
    e->streaming = 0;
    e->out_len = 0;
    e->cmdlen = 0;
}

/* ------------------------------------------------------------------------------------- */
/* Output                                                                                */

static void put(fp_gloveemu *e, const void *p, size_t n)
{
    if (e->out_len + n > OUT_CAP)
        return;   /* nobody reads: the bytes are lost, as on a real line */
    memcpy(e->out + e->out_len, p, n);
    e->out_len += n;
}

static void put3(fp_gloveemu *e, uint8_t a, uint8_t b, uint8_t c)
{
    uint8_t x[3] = {a, b, c};
    put(e, x, 3);
}

static void flush_out(fp_gloveemu *e)
{
    while (e->out_len && e->master >= 0) {
        ssize_t w = write(e->master, e->out, e->out_len);
        if (w <= 0)
            return;
        memmove(e->out, e->out + w, e->out_len - (size_t)w);
        e->out_len -= (size_t)w;
    }
}

/* Build one record from the current frame and queue it (after any garbage). */
static void send_record(fp_gloveemu *e, uint8_t start, int bits)
{
    if (e->garbage_len) {
        put(e, e->garbage, e->garbage_len);
        e->st.garbage_sent += e->garbage_len;
        e->garbage_len = 0;
    }
    if (bits == 16 && !e->plugged)
        return;   /* a CyberGlove III without its glove sends no frames */
    if (bits == 8 && !e->plugged && e->o.error_frames) {
        uint8_t f[4] = {start, 'e', 'g', 0};
        put(e, f, sizeof f);
        return;
    }
    const uint32_t carried = bits == 8 ? e->present & e->sampled : e->present;
    fp_gloveemu_record *r = &e->hist[e->st.records % e->hist_cap];
    memset(r, 0, sizeof *r);
    r->seq = e->st.records;
    r->bits = bits;
    r->start = start;
    r->plugged = e->plugged;
    r->present = carried;
    const float *row = e->nframes ? e->deg[e->frame] : NULL;
    double scale = bits == 16 ? 16.0 : 1.0;
    int hi = bits == 16 ? 4094 : 254;
    for (int i = 0; i < 22; i++) {
        if (!(carried & (1u << i)))
            continue;
        int clamped = 0;
        if (e->fixed || !row) {
            int v = e->fixed ? e->raw8[i] : 128;
            r->raw[i] = (uint16_t)(bits == 16 ? v * 16 : v);
            r->radians[i] = fpg_cal_angle(&e->cal, i, v);
        } else {
            double rad = isnan(row[i]) ? 0.0 : row[i] * (3.14159265358979323846 / 180.0);
            r->raw[i] = (uint16_t)fpg_cal_inverse(&e->cal, i, rad, scale, 1, hi, &clamped);
            r->radians[i] = (float)rad;
        }
        if (clamped)
            r->clamped |= 1u << i;
    }
    if (row && !e->fixed && e->nframes) {
        if (e->frame + 1 < e->nframes)
            e->frame++;
        else if (e->o.loop)
            e->frame = 0;
    }
    uint8_t b[128];
    size_t n = 0;
    if (bits == 8) {
        b[n++] = start;
        for (int i = 0; i < 22; i++)
            if (carried & (1u << i))
                b[n++] = (uint8_t)r->raw[i];
        if (e->ts_on) {
            uint64_t ticks = (uint64_t)((mono_ns() - e->t0) / 10000);
            for (int k = 4; k >= 0; k--)
                b[n++] = (uint8_t)(ticks >> (8 * k));
        }
        if (e->status_on)
            b[n++] = e->plugged ? 0x01 : 0x00;
        if (!e->plugged) {
            b[n++] = 'e';
            b[n++] = 'g';
        }
        b[n++] = 0;
    } else {
        b[n++] = 0x0D;
        b[n++] = 0x0A;
        b[n++] = 0x00;
        int64_t cs = (mono_ns() - e->t0) / 10000000;   /* hundredths */
        char ts[32];
        snprintf(ts, sizeof ts, "%02d:%02d:%02d:%02d:%02d", (int)(cs / 360000 % 100),
                 (int)(cs / 6000 % 60), (int)(cs / 100 % 60), (int)(cs % 100),
                 (int)(r->seq % 100));
        memcpy(b + n, ts, 14);
        n += 14;
        b[n++] = 'S';
        for (int i = 0; i < 22; i++) {
            b[n++] = (uint8_t)(r->raw[i] >> 8);
            b[n++] = (uint8_t)r->raw[i];
        }
    }
    put(e, b, n);
    r->sent_ns = mono_ns();
    e->st.records++;
}

/* ------------------------------------------------------------------------------------- */
/* Commands                                                                              */

static void reply_query(fp_gloveemu *e, uint8_t x)
{
    uint8_t v[80];
    size_t n = 0;
    if (x && e->o.unanswered && strchr(e->o.unanswered, x)) return;
    switch (x) {
    case 'G': v[n++] = e->plugged ? 3 : 1; e->st.session_seq = e->st.records; break;
    case 'S': v[n++] = (uint8_t)(e->o.claim_sensors ? e->o.claim_sensors : e->o.sensors); break;
    case 'N': v[n++] = (uint8_t)(e->o.claim_sensors ? e->o.claim_sensors
                                                    : __builtin_popcount(e->present & e->sampled)); break;
    case 'R': v[n++] = e->o.left ? 0 : 1; break;
    case 'D': v[n++] = e->ts_on; break;
    case 'U': v[n++] = e->status_on; break;
    case 'B': v[n++] = 1; break;   /* divisor of 115200 */
    case 'P': v[n++] = 0; break;
    case 'K': case 'M': {
        uint32_t m = x == 'K' ? e->present : e->present & e->sampled;
        v[n++] = (uint8_t)m;
        v[n++] = (uint8_t)(m >> 8);
        v[n++] = (uint8_t)(m >> 16);
        break;
    }
    case 'T': {
        unsigned w1 = e->st.period_w1 ? e->st.period_w1 : (unsigned)(115200 * e->period_s);
        unsigned w2 = e->st.period_w2 ? e->st.period_w2 : 1;
        v[n++] = (uint8_t)(w1 >> 8); v[n++] = (uint8_t)w1;
        v[n++] = (uint8_t)(w2 >> 8); v[n++] = (uint8_t)w2;
        break;
    }
    case 'V':
        n = strlen(e->version);
        memcpy(v, e->version, n);
        break;
    default:
        put3(e, 'e', '?', 0);
        e->st.unknown++;
        return;
    }
    uint8_t h[2] = {'?', x};
    put(e, h, 2);
    put(e, v, n);
    uint8_t z = 0;
    put(e, &z, 1);
}

static void set_period(fp_gloveemu *e, unsigned w1, unsigned w2)
{
    e->st.period_w1 = w1;
    e->st.period_w2 = w2;
    e->period_s = (double)w1 * w2 / 115200.0;
}

/* Bytes a command starting with c needs in all (0: variable, ends with CR). */
static size_t cmd_len(const uint8_t *c, size_t have)
{
    switch (c[0]) {
    case '?': case '^': return 2;
    case 'T': return 5;
    case 'M': return 4;
    case 'D': case 'U': case 'N': case 'F': case 'L': case 'J': case 'W': case 'Q': case 'B':
        return 2;
    case 't': return 0;
    case '1': return have >= 2 && c[1] == 'e' ? 3 : 2;
    default: return 1;
    }
}

static void execute(fp_gloveemu *e, const uint8_t *c, size_t n)
{
    e->st.commands++;
    switch (c[0]) {
    case '?': e->st.queries++; reply_query(e, c[1]); return;
    case 'G':
        e->st.polls++;
        send_record(e, 'G', 8);
        return;
    case 'S': e->streaming = 8; e->next_ns = mono_ns(); return;
    case 0x03:
        if (!e->o.caret_stop_only) e->streaming = 0;
        return;
    case '^':
        if (c[1] == 'c' || c[1] == 'C') {
            e->streaming = 0;
        } else if (c[1] == 'I' || c[1] == 'R') {
            uint8_t r[5] = {'^', c[1], '\r', '\n', 0};
            e->streaming = 0;
            put(e, r, 5);
        } else {
            put3(e, 'e', '?', 0);
            e->st.unknown++;
        }
        return;
    case 't': {
        unsigned w1, w2;
        char s[64];
        memcpy(s, c, n);
        s[n] = '\0';
        if (sscanf(s, "t %u %u", &w1, &w2) == 2 && w1 >= 1 && w2 >= 1 && w1 <= 65535 &&
            w2 <= 65535) {
            set_period(e, w1, w2);
            uint8_t r[2] = {'t', 0};
            put(e, r, 2);
        } else {
            put3(e, 'e', 'n', 0);
        }
        return;
    }
    case 'T':
        set_period(e, (unsigned)c[1] << 8 | c[2], (unsigned)c[3] << 8 | c[4]);
        break;
    case 'D': e->ts_on = c[1] != 0; break;
    case 'U': e->status_on = c[1] != 0; break;
    case 'N': case 'F': case 'L': case 'J': case 'W': case 'Q': case 'B': case 'M': break;
    case '1':
        if (n == 3 && c[1] == 'e' && c[2] == 'u') {
            e->sixteen = true;
            return;
        }
        if (n == 2 && c[1] == 'S') {
            e->sixteen = true;
            e->streaming = 16;
            e->next_ns = mono_ns();
            return;
        }
        put3(e, 'e', '?', 0);
        e->st.unknown++;
        return;
    default:
        put3(e, 'e', '?', 0);
        e->st.unknown++;
        return;
    }
    if (e->o.unanswered && strchr(e->o.unanswered, c[0])) return;
    uint8_t r[2] = {c[0], 0};
    put(e, r, 2);
}

static void on_input(fp_gloveemu *e, const uint8_t *b, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (e->silent)
            continue;
        if (e->cmdlen == 0 && b[i] == 0x03) {   /* stop works at any time */
            execute(e, b + i, 1);
            continue;
        }
        if (e->cmdlen < sizeof e->cmd)
            e->cmd[e->cmdlen++] = b[i];
        size_t need = cmd_len(e->cmd, e->cmdlen);
        if (need == 0) {   /* t ... \r */
            if (b[i] == '\r') {
                execute(e, e->cmd, e->cmdlen - 1);
                e->cmdlen = 0;
            } else if (e->cmdlen == sizeof e->cmd) {
                put3(e, 'e', 'n', 0);
                e->cmdlen = 0;
            }
        } else if (e->cmdlen >= need) {
            execute(e, e->cmd, e->cmdlen);
            e->cmdlen = 0;
        }
    }
}

/* ------------------------------------------------------------------------------------- */
/* Thread                                                                                */

static void *serve(void *arg)
{
    fp_gloveemu *e = arg;
    pthread_mutex_lock(&e->lock);
    for (;;) {
        if (e->stop)
            break;
        if (e->req) {
            if (e->req == 1) {
                /* the pts number is free for anyone now: remove the link, so that a reader
                 * cannot reach another process's pty that got the same number */
                if (e->link[0])
                    unlink(e->link);
                close_pty(e);
                e->req_result = 0;
            } else {
                e->req_result = e->cable_in ? 0 : open_pty(e);
            }
            e->req = 0;
            pthread_cond_broadcast(&e->cond);
        }
        int64_t now = mono_ns();
        bool can_stream = e->streaming && !e->silent && e->cable_in;
        int timeout = -1;
        if (can_stream) {
            if (e->o.fast) {
                timeout = e->out_len < FAST_LOW_WATER ? 0 : -1;
            } else {
                if (now >= e->next_ns) {
                    if (e->out_len < 8192)
                        send_record(e, 'S', e->streaming);
                    double p = e->period_s * (e->slow > 0 ? e->slow : 1.0);
                    e->next_ns += (int64_t)(p * 1e9);
                    if (e->next_ns < now)
                        e->next_ns = now;   /* fell behind (reader or machine slow): no burst */
                }
                timeout = (int)((e->next_ns - now + 999999) / 1000000);
            }
        }
        if (can_stream && e->o.fast) {
            while (e->out_len < FAST_LOW_WATER)
                send_record(e, 'S', e->streaming);
        }
        flush_out(e);
        struct pollfd p[2] = {{.fd = e->wake[0], .events = POLLIN},
                              {.fd = e->master, .events = POLLIN}};
        if (e->out_len && e->master >= 0)
            p[1].events |= POLLOUT;
        if (e->o.fast && can_stream)
            timeout = e->out_len ? -1 : 0;
        pthread_mutex_unlock(&e->lock);
        int r = poll(p, e->master >= 0 ? 2 : 1, timeout);
        pthread_mutex_lock(&e->lock);
        if (r < 0)
            continue;
        if (p[0].revents & POLLIN) {
            uint8_t sink[64];
            while (read(e->wake[0], sink, sizeof sink) > 0) {
            }
        }
        if (e->master >= 0 && (p[1].revents & POLLIN)) {
            uint8_t buf[512];
            ssize_t n = read(e->master, buf, sizeof buf);
            if (n > 0)
                on_input(e, buf, (size_t)n);
        }
    }
    pthread_mutex_unlock(&e->lock);
    return NULL;
}

static void wake(fp_gloveemu *e) { (void)!write(e->wake[1], "x", 1); }

/* ------------------------------------------------------------------------------------- */
/* Public                                                                                */

int fp_gloveemu_create(const fp_gloveemu_options *opts, fp_gloveemu **out, char *err,
                       size_t errlen)
{
    fp_gloveemu_options o = opts ? *opts : (fp_gloveemu_options){0};
    if (o.sensors == 0)
        o.sensors = 22;
    if (o.sensors != 18 && o.sensors != 22)
        return fp_errorf(err, errlen, -EINVAL, "sensors=%d: expected 18 or 22", o.sensors);
    if (o.rate_hz == 0)
        o.rate_hz = 100;
    if (!(o.rate_hz > 0 && o.rate_hz <= 100000))
        return fp_errorf(err, errlen, -EINVAL, "rate %g: expected 0..100000 Hz", o.rate_hz);
    if (o.history == 0)
        o.history = 8192;
    fp_gloveemu *e = calloc(1, sizeof *e);
    if (!e)
        return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    e->o = o;
    e->master = e->slave = -1;
    e->wake[0] = e->wake[1] = -1;
    snprintf(e->version, sizeof e->version, "%s", o.version ? o.version : "CyberGlove emu 1.0");
    if (o.link_path)
        snprintf(e->link, sizeof e->link, "%s", o.link_path);
    e->present = (1u << 22) - 1;
    if (o.sensors == 18)
        for (int k = 0; k < 4; k++)
            e->present &= ~(1u << DIJ[k]);
    e->sampled = o.sampled ? o.sampled : e->present;
    if (!(e->present & e->sampled)) {
        free(e);
        return fp_errorf(err, errlen, -EINVAL, "sampled=%#x: none of the glove's sensors", o.sampled);
    }
    int rc;
    fpg_cal_default(&e->cal);
    if (o.calibration && (rc = fpg_cal_load(o.calibration, &e->cal, err, errlen)) < 0)
        goto fail;
    if (o.recording && (rc = load_csv(e, o.recording, err, errlen)) < 0)
        goto fail;
    e->hist_cap = o.history;
    e->hist = calloc(e->hist_cap, sizeof *e->hist);
    if (!e->hist) {
        rc = fp_errorf(err, errlen, -ENOMEM, "out of memory");
        goto fail;
    }
    e->plugged = true;
    e->slow = 1.0;
    e->ts_on = o.timestamps;
    e->period_s = 1.0 / o.rate_hz;
    e->streaming = o.streaming_at_start ? 8 : 0;
    e->next_ns = mono_ns();
    e->t0 = mono_ns();
    if (pipe2(e->wake, O_CLOEXEC | O_NONBLOCK) != 0) {
        rc = fp_errorf(err, errlen, -errno, "pipe: %s", strerror(errno));
        goto fail;
    }
    if ((rc = open_pty(e)) < 0) {
        fp_errorf(err, errlen, rc, "cannot make a pty%s%s: %s", e->link[0] ? " linked at " : "",
             e->link, strerror(-rc));
        goto fail;
    }
    pthread_mutex_init(&e->lock, NULL);
    pthread_cond_init(&e->cond, NULL);
    if ((rc = pthread_create(&e->thread, NULL, serve, e)) != 0) {
        rc = fp_errorf(err, errlen, -rc, "cannot start the emulator thread");
        pthread_mutex_destroy(&e->lock);
        pthread_cond_destroy(&e->cond);
        close_pty(e);
        goto fail;
    }
    *out = e;
    return 0;
fail:
    if (e->wake[0] >= 0) {
        close(e->wake[0]);
        close(e->wake[1]);
    }
    if (e->link[0] && e->master >= 0)
        unlink(e->link);
    free(e->hist);
    free(e->deg);
    free(e);
    return rc;
}

void fp_gloveemu_destroy(fp_gloveemu **pe)
{
    if (!pe || !*pe)
        return;
    fp_gloveemu *e = *pe;
    pthread_mutex_lock(&e->lock);
    e->stop = true;
    pthread_mutex_unlock(&e->lock);
    wake(e);
    pthread_join(e->thread, NULL);
    close_pty(e);
    if (e->link[0])
        unlink(e->link);
    close(e->wake[0]);
    close(e->wake[1]);
    pthread_mutex_destroy(&e->lock);
    pthread_cond_destroy(&e->cond);
    free(e->hist);
    free(e->deg);
    free(e);
    *pe = NULL;
}

void fp_gloveemu_slave_path(fp_gloveemu *e, char *buf, size_t len)
{
    pthread_mutex_lock(&e->lock);
    snprintf(buf, len, "%s", e->slave_path);
    pthread_mutex_unlock(&e->lock);
}

const char *fp_gloveemu_path(const fp_gloveemu *e)
{
    return e->link[0] ? e->link : e->slave_path;
}

#define LOCKED(e, stmt)                                                                       \
    do {                                                                                      \
        pthread_mutex_lock(&(e)->lock);                                                       \
        stmt;                                                                                 \
        pthread_mutex_unlock(&(e)->lock);                                                     \
        wake(e);                                                                              \
    } while (0)

void fp_gloveemu_set_plugged(fp_gloveemu *e, bool plugged) { LOCKED(e, e->plugged = plugged); }
void fp_gloveemu_set_silent(fp_gloveemu *e, bool silent) { LOCKED(e, e->silent = silent); }
void fp_gloveemu_set_slow(fp_gloveemu *e, double f) { LOCKED(e, e->slow = f >= 1e-3 ? f : 1.0); }

void fp_gloveemu_set_raw(fp_gloveemu *e, const uint8_t raw[22])
{
    LOCKED(e, {
        for (int i = 0; i < 22; i++)
            e->raw8[i] = raw[i] ? raw[i] : 1;
        e->fixed = true;
    });
}

void fp_gloveemu_inject_garbage(fp_gloveemu *e, const uint8_t *bytes, size_t n)
{
    LOCKED(e, {
        size_t room = sizeof e->garbage - e->garbage_len;
        size_t k = n < room ? n : room;
        memcpy(e->garbage + e->garbage_len, bytes, k);
        e->garbage_len += k;
    });
}

static int request(fp_gloveemu *e, int what)
{
    pthread_mutex_lock(&e->lock);
    while (e->req)
        pthread_cond_wait(&e->cond, &e->lock);
    e->req = what;
    pthread_mutex_unlock(&e->lock);
    wake(e);
    pthread_mutex_lock(&e->lock);
    while (e->req)
        pthread_cond_wait(&e->cond, &e->lock);
    int r = e->req_result;
    pthread_mutex_unlock(&e->lock);
    return r;
}

int fp_gloveemu_pull_cable(fp_gloveemu *e) { return request(e, 1); }
int fp_gloveemu_replug_cable(fp_gloveemu *e) { return request(e, 2); }

int fp_gloveemu_get_record(fp_gloveemu *e, uint64_t seq, fp_gloveemu_record *out)
{
    int rc = -ENOENT;
    pthread_mutex_lock(&e->lock);
    if (seq < e->st.records && e->st.records - seq <= e->hist_cap) {
        *out = e->hist[seq % e->hist_cap];
        rc = 0;
    }
    pthread_mutex_unlock(&e->lock);
    return rc;
}

void fp_gloveemu_get_stats(fp_gloveemu *e, fp_gloveemu_stats *out)
{
    pthread_mutex_lock(&e->lock);
    *out = e->st;
    out->streaming = e->silent ? 0 : e->streaming;
    out->status_byte = e->status_on;
    out->timestamps = e->ts_on;
    out->period_s = e->period_s;
    out->cable_in = e->cable_in;
    pthread_mutex_unlock(&e->lock);
}

static int baud_of(speed_t s)
{
    static const struct { speed_t s; int b; } t[] = {
        {B50, 50}, {B75, 75}, {B110, 110}, {B134, 134}, {B150, 150}, {B200, 200}, {B300, 300},
        {B600, 600}, {B1200, 1200}, {B1800, 1800}, {B2400, 2400}, {B4800, 4800},
        {B9600, 9600}, {B19200, 19200}, {B38400, 38400}, {B57600, 57600}, {B115200, 115200},
        {B230400, 230400}, {B460800, 460800}, {B921600, 921600}};
    for (size_t i = 0; i < sizeof t / sizeof t[0]; i++)
        if (t[i].s == s)
            return t[i].b;
    return 0;
}

int fp_gloveemu_line_settings(fp_gloveemu *e, fp_gloveemu_line *out)
{
    struct termios t;
    int rc = 0;
    memset(out, 0, sizeof *out);
    pthread_mutex_lock(&e->lock);
    if (e->master < 0)
        rc = -ENODEV;
    else if (tcgetattr(e->master, &t) != 0)
        rc = -errno;
    pthread_mutex_unlock(&e->lock);
    if (rc)
        return rc;
    out->baud = baud_of(cfgetospeed(&t));
    out->ibaud = baud_of(cfgetispeed(&t));
    switch (t.c_cflag & CSIZE) {
    case CS5: out->data_bits = 5; break;
    case CS6: out->data_bits = 6; break;
    case CS7: out->data_bits = 7; break;
    default: out->data_bits = 8; break;
    }
    out->parity = (t.c_cflag & PARENB) != 0;
    out->two_stop_bits = (t.c_cflag & CSTOPB) != 0;
    out->crtscts = (t.c_cflag & CRTSCTS) != 0;
    out->clocal = (t.c_cflag & CLOCAL) != 0;
    out->cread = (t.c_cflag & CREAD) != 0;
    out->echo = (t.c_lflag & ECHO) != 0;
    out->raw = !(t.c_lflag & (ICANON | ISIG | IEXTEN | ECHO)) &&
               !(t.c_iflag & (ICRNL | INLCR | IGNCR | IXON | ISTRIP | BRKINT | PARMRK)) &&
               !(t.c_oflag & OPOST);
    snprintf(out->text, sizeof out->text, "%d %d%c%d %s%s", out->baud, out->data_bits,
             out->parity ? ((t.c_cflag & PARODD) ? 'O' : 'E') : 'N', out->two_stop_bits ? 2 : 1,
             out->raw ? "raw" : "cooked", out->crtscts ? " rtscts" : "");
    return 0;
}
