/* The OSC control surface's socket, network thread and queue (fp_control.h). The messages'
 * checks are in control_parse.c. */
#define _GNU_SOURCE
#include "fp_control.h"
#include "control_internal.h"

#include "fp_error.h"
#include "fp_net.h"
#include "facepuppet/decimal.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <lo/lo.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define TICK_MS 50
#define BURST 64               /* datagrams read per wake-up before the stop pipe is looked at */

static void problem(fp_control *c, fp_control_problem p)
{
    atomic_fetch_add_explicit(&c->problems[p], 1, memory_order_relaxed);
}

void fp__control_problem(fp_control *c, fp_control_problem p) { problem(c, p); }

/* Queue cmds, all or none (the network thread: the ring's only producer). */
bool fp__control_queue_all(fp_control *c, const fp_control_cmd *cmds, size_t n)
{
    size_t head = atomic_load_explicit(&c->head, memory_order_relaxed);
    size_t tail = atomic_load_explicit(&c->tail, memory_order_acquire);
    if (n > FP_CONTROL_RING - (head - tail)) return false;
    for (size_t k = 0; k < n; k++) c->ring[(head + k) % FP_CONTROL_RING] = cmds[k];
    atomic_store_explicit(&c->head, head + n, memory_order_release);
    atomic_fetch_add_explicit(&c->queued, n, memory_order_relaxed);
    return true;
}

bool fp_control_next(fp_control *c, fp_control_cmd *cmd)
{
    if (!c) return false;
    size_t tail = atomic_load_explicit(&c->tail, memory_order_relaxed);
    size_t head = atomic_load_explicit(&c->head, memory_order_acquire);
    if (tail == head) return false;
    *cmd = c->ring[tail % FP_CONTROL_RING];
    atomic_store_explicit(&c->tail, tail + 1, memory_order_release);
    return true;
}

static void *control_thread(void *arg)
{
    fp_control *c = arg;
    struct pollfd fds[3] = {{c->stop_pipe[0], POLLIN, 0}, {c->sock, POLLIN, 0}, {c->sock6, POLLIN, 0}};
    for (;;) {
        int rc = poll(fds, 3, TICK_MS); /* (a negative sock6 is left out by poll) */
        if (rc < 0 && errno != EINTR) return NULL;
        if (fds[0].revents) return NULL;
        for (int s = 1; s < 3; s++)
        for (int i = 0; i < BURST && rc > 0 && (fds[s].revents & POLLIN); i++) {
            fp_control_cmd from = {0};
            from.fromlen = sizeof from.from;
            ssize_t n = recvfrom(fds[s].fd, c->buf, sizeof c->buf, MSG_DONTWAIT | MSG_TRUNC,
                                 (struct sockaddr *)&from.from, &from.fromlen);
            if (n < 0) break; /* EAGAIN: drained */
            atomic_fetch_add_explicit(&c->packets, 1, memory_order_relaxed);
            if ((size_t)n > sizeof c->buf) {
                problem(c, FP_CTL_MALFORMED);
                continue;
            }
            fp__control_packet(c, c->buf, (size_t)n, &from);
        }
    }
}

/* "osc:PORT[,bind=ADDR]" into *port and bind (a copy in buf). */
static int parse_spec(const char *spec, long *port, char *bind_addr, size_t n, char *err,
                      size_t errlen)
{
    if (!spec || strncmp(spec, "osc:", 4))
        return fp_errorf(err, errlen, -EINVAL, "--control %s: expected osc:PORT[,bind=ADDR]",
                         spec ? spec : "(null)");
    const char *p = spec + 4, *comma = strchr(p, ',');
    char digits[16];
    size_t len = comma ? (size_t)(comma - p) : strlen(p);
    if (len == 0 || len >= sizeof digits)
        return fp_errorf(err, errlen, -EINVAL, "--control %s: PORT must be 0..65535", spec);
    memcpy(digits, p, len);
    digits[len] = '\0';
    unsigned long long v;
    if (!fp_parse_whole(digits, 65535, &v))
        return fp_errorf(err, errlen, -EINVAL, "--control %s: PORT must be 0..65535", spec);
    *port = (long)v;
    snprintf(bind_addr, n, "127.0.0.1");
    if (comma) {
        if (strncmp(comma + 1, "bind=", 5) != 0 || strchr(comma + 1, ','))
            return fp_errorf(err, errlen, -EINVAL, "--control %s: the only key is bind=ADDR", spec);
        snprintf(bind_addr, n, "%s", comma + 6);
    }
    return 0;
}

/* bind= as fp_udp_listen takes it (fp_net.h): an IP literal (IPv4, IPv6 bare or in brackets,
 * with a %scope where link-local) or localhost; -EINVAL with err otherwise. */
static int check_bind(const char *spec, const char *bind_addr, char *err, size_t errlen)
{
    unsigned char a[sizeof(struct in6_addr)];
    char text[INET6_ADDRSTRLEN + 24];
    size_t n = strlen(bind_addr);
    if (n >= 2 && bind_addr[0] == '[' && bind_addr[n - 1] == ']')
        snprintf(text, sizeof text, "%.*s", (int)(n - 2), bind_addr + 1);
    else
        snprintf(text, sizeof text, "%s", bind_addr);
    char *scope = strchr(text, '%');
    if (scope && strchr(text, ':')) *scope = '\0'; /* (the scope is checked by the bind) */
    if (strcmp(text, "localhost") == 0 || inet_pton(AF_INET, text, a) == 1 ||
        inet_pton(AF_INET6, text, a) == 1)
        return 0;
    return fp_errorf(err, errlen, -EINVAL, "--control %s: bind=%s: expected an IP address "
                     "(127.0.0.1, 0.0.0.0, ::1, ::, ...) or localhost", spec, bind_addr);
}

int fp_control_spec_check(const char *spec, char *err, size_t errlen)
{
    long port;
    char bind_addr[64];
    int rc = parse_spec(spec, &port, bind_addr, sizeof bind_addr, err, errlen);
    return rc ? rc : check_bind(spec, bind_addr, err, errlen);
}

int fp_control_open(const char *spec, fp_control **out, char *warning, size_t wlen, char *err,
                    size_t errlen)
{
    *out = NULL;
    if (warning && wlen) warning[0] = '\0';
    long port = 0;
    char bind_addr[64], why[384];
    int rc = parse_spec(spec, &port, bind_addr, sizeof bind_addr, err, errlen);
    if (rc || (rc = check_bind(spec, bind_addr, err, errlen))) return rc;
    fp_udp_listener ls;
    if ((rc = fp_udp_listen(bind_addr, port, &ls, why, sizeof why)))
        return fp_errorf(err, errlen, rc, "--control %s: %s", spec, why);
    fp_control *c = calloc(1, sizeof *c);
    if (!c) {
        close(ls.sock);
        if (ls.sock6 >= 0) close(ls.sock6);
        return fp_errorf(err, errlen, -ENOMEM, "--control: out of memory");
    }
    c->sock = ls.sock;
    c->sock6 = ls.sock6;
    c->port = ls.port;
    snprintf(c->where, sizeof c->where, "%s", ls.text);
    if (warning && wlen) {
        if (!ls.loopback)
            snprintf(warning, wlen, "--control listens on %s beyond loopback: any host that can "
                     "reach it can start takes and drive the session (OSC has no authentication)%s%s",
                     ls.text, ls.warning[0] ? "; " : "", ls.warning);
        else if (ls.warning[0])
            snprintf(warning, wlen, "--control: %s", ls.warning);
    }
    if (pipe2(c->stop_pipe, O_CLOEXEC) != 0 ||
        pthread_create(&c->thread, NULL, control_thread, c) != 0) {
        int e = errno ? errno : EAGAIN;
        close(c->sock);
        if (c->sock6 >= 0) close(c->sock6);
        if (c->stop_pipe[0] > 0) { close(c->stop_pipe[0]); close(c->stop_pipe[1]); }
        free(c);
        return fp_errorf(err, errlen, -e, "--control: cannot start its thread: %s", strerror(e));
    }
    *out = c;
    return 0;
}

unsigned fp_control_port(const fp_control *c) { return c ? c->port : 0; }

const char *fp_control_where(const fp_control *c) { return c ? c->where : ""; }

bool fp_control_hears_ipv6(const fp_control *c) { return c && c->sock6 >= 0; }

void fp_control_stats_get(fp_control *c, fp_control_stats *st)
{
    memset(st, 0, sizeof *st);
    if (!c) return;
    st->packets = atomic_load_explicit(&c->packets, memory_order_relaxed);
    st->messages = atomic_load_explicit(&c->messages, memory_order_relaxed);
    st->queued = atomic_load_explicit(&c->queued, memory_order_relaxed);
    for (int k = 0; k < FP_CTL_PROBLEMS; k++) {
        st->problems[k] = atomic_load_explicit(&c->problems[k], memory_order_relaxed);
        st->refused += st->problems[k];
    }
    st->replies = c->replies;
    st->pushes = c->pushes;
    st->send_errors = c->send_errors;
}

/* One /fp/status message to `to`. */
static int send_status(fp_control *c, const struct sockaddr *to, socklen_t tolen, const char *address,
                       const char *result, const fp_control_status *st)
{
    lo_message m = lo_message_new();
    if (!m) return -ENOMEM;
    fp_control_stats cs;
    fp_control_stats_get(c, &cs);
    lo_message_add_string(m, address);
    lo_message_add_string(m, result);
    lo_message_add_string(m, st->state ? st->state : "idle");
    lo_message_add_string(m, st->timecode ? st->timecode : "");
    lo_message_add_string(m, st->slate ? st->slate : "");
    lo_message_add_int32(m, (int32_t)st->take);
    lo_message_add_int32(m, st->recording ? 1 : 0);
    lo_message_add_float(m, (float)st->time_s);
    lo_message_add_int32(m, (int32_t)(st->frame & 0x7fffffff));
    lo_message_add_int32(m, (int32_t)(cs.refused & 0x7fffffff));
    unsigned char buf[2048];
    size_t size = lo_message_length(m, "/fp/status");
    int rc = 0;
    if (size > sizeof buf || !lo_message_serialise(m, "/fp/status", buf, &size)) rc = -EMSGSIZE;
    else {
        /* the one it came on: [::1] beside 127.0.0.1, else the one socket (IPv4, IPv6, or
         * [::] dual-stack, where IPv4 senders are ::ffff:a.b.c.d) */
        int sock = to->sa_family == AF_INET6 && c->sock6 >= 0 ? c->sock6 : c->sock;
        if (sock < 0) rc = -EAFNOSUPPORT;
        else if (sendto(sock, buf, size, MSG_DONTWAIT, to, tolen) < 0) rc = -errno;
    }
    lo_message_free(m);
    if (rc) c->send_errors++;
    return rc;
}

int fp_control_reply(fp_control *c, const fp_control_cmd *cmd, const char *result,
                     const fp_control_status *st)
{
    int rc = send_status(c, (const struct sockaddr *)&cmd->from, cmd->fromlen, cmd->address, result, st);
    if (!rc) c->replies++;
    return rc;
}

int fp_control_push(fp_control *c, const fp_control_status *st)
{
    int n = 0;
    if (!c) return 0;
    for (size_t i = 0; i < c->nsubs; i++)
        if (!send_status(c, (const struct sockaddr *)&c->subs[i], c->sublen[i], "push", "ok", st)) n++;
    c->pushes += (uint64_t)n;
    return n;
}

int fp_control_subscribe(fp_control *c, const fp_control_cmd *cmd, bool on)
{
    struct sockaddr_storage a = cmd->from;
    if (cmd->port > 0) {
        if (a.ss_family == AF_INET) ((struct sockaddr_in *)&a)->sin_port = htons((uint16_t)cmd->port);
        else if (a.ss_family == AF_INET6) ((struct sockaddr_in6 *)&a)->sin6_port = htons((uint16_t)cmd->port);
    }
    for (size_t i = 0; i < c->nsubs; i++) {
        if (c->sublen[i] != cmd->fromlen || memcmp(&c->subs[i], &a, cmd->fromlen)) continue;
        if (on) return 0; /* (subscribed already) */
        c->subs[i] = c->subs[c->nsubs - 1];
        c->sublen[i] = c->sublen[c->nsubs - 1];
        c->nsubs--;
        return 0;
    }
    if (!on) return -ENOENT;
    if (c->nsubs == FP_CONTROL_MAX_SUBSCRIBERS) return -ENOSPC;
    c->subs[c->nsubs] = a;
    c->sublen[c->nsubs++] = cmd->fromlen;
    return 0;
}

size_t fp_control_subscribers(const fp_control *c) { return c ? c->nsubs : 0; }

void fp_control_close(fp_control **cp)
{
    fp_control *c = cp ? *cp : NULL;
    if (!c) return;
    ssize_t w = write(c->stop_pipe[1], "x", 1);
    (void)w;
    pthread_join(c->thread, NULL);
    close(c->stop_pipe[0]);
    close(c->stop_pipe[1]);
    close(c->sock);
    if (c->sock6 >= 0) close(c->sock6);
    free(c);
    *cp = NULL;
}
