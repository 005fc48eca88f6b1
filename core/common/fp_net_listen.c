/*
 * fp_net_listen.c: a UDP listener on the address a user gave (fp_net.h, fp_udp_listen): the osc
 * input's bind= and --control's bind= (docs/osc.md).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "fp_net.h"

#include <arpa/inet.h>
#include <errno.h>
#include <net/if.h>
#include <netdb.h>
#include <netinet/in.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

enum bind_kind { BIND_V4, BIND_LOOPBACK, BIND_ANY, BIND_V6 };

/* A socket of family bound to sa; v6only for AF_INET6 (0: IPv4 too). -errno on failure. */
static int bound(int family, const struct sockaddr *sa, socklen_t len, int v6only)
{
    int s = socket(family, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (s < 0) return -errno;
    if ((family == AF_INET6 && setsockopt(s, IPPROTO_IPV6, IPV6_V6ONLY, &v6only, sizeof v6only)) ||
        bind(s, sa, len) != 0) {
        int e = errno;
        close(s);
        return -e;
    }
    return s;
}

/* The port a socket is bound to. */
static uint16_t port_of(int s)
{
    struct sockaddr_storage ss;
    socklen_t len = sizeof ss;
    if (getsockname(s, (struct sockaddr *)&ss, &len) != 0) return 0;
    return ss.ss_family == AF_INET6 ? ntohs(((struct sockaddr_in6 *)&ss)->sin6_port)
                                    : ntohs(((struct sockaddr_in *)&ss)->sin_port);
}

/* -EBUSY for a taken port, -ENODEV for an address or family this machine lacks. */
static int open_code(int e)
{
    return e == EADDRINUSE ? -EBUSY : (e == EADDRNOTAVAIL || e == EAFNOSUPPORT) ? -ENODEV : -e;
}

/* bind_addr as one of enum bind_kind, its address in sa (port unset); -EINVAL if neither an
 * IP address nor localhost. */
static int parse_bind(const char *bind_addr, struct sockaddr_storage *sa, socklen_t *len)
{
    char text[INET6_ADDRSTRLEN + IF_NAMESIZE + 4];
    size_t n = strlen(bind_addr);
    if (n >= sizeof text) return -EINVAL;
    if (n >= 2 && bind_addr[0] == '[' && bind_addr[n - 1] == ']')
        snprintf(text, sizeof text, "%.*s", (int)(n - 2), bind_addr + 1);
    else
        snprintf(text, sizeof text, "%s", bind_addr);
    memset(sa, 0, sizeof *sa);
    struct sockaddr_in *a4 = (struct sockaddr_in *)sa;
    if (strcmp(text, "localhost") == 0 || strchr(text, ':') == NULL) {
        a4->sin_family = AF_INET;
        *len = sizeof *a4;
        if (strcmp(text, "localhost") == 0) {
            a4->sin_addr.s_addr = htonl(INADDR_LOOPBACK);
            return BIND_LOOPBACK;
        }
        if (inet_pton(AF_INET, text, &a4->sin_addr) != 1) return -EINVAL;
        return a4->sin_addr.s_addr == htonl(INADDR_LOOPBACK) ? BIND_LOOPBACK
               : a4->sin_addr.s_addr == htonl(INADDR_ANY)    ? BIND_ANY
                                                              : BIND_V4;
    }
    struct addrinfo hints = {.ai_family = AF_INET6, .ai_socktype = SOCK_DGRAM,
                             .ai_flags = AI_NUMERICHOST | AI_PASSIVE}, *ai = NULL;
    if (getaddrinfo(text, NULL, &hints, &ai) != 0 || !ai) return -EINVAL;
    memcpy(sa, ai->ai_addr, ai->ai_addrlen);
    *len = ai->ai_addrlen;
    freeaddrinfo(ai);
    const struct in6_addr *a6 = &((struct sockaddr_in6 *)sa)->sin6_addr;
    return IN6_IS_ADDR_UNSPECIFIED(a6) ? BIND_ANY : BIND_V6;
}

/* Opens out->sock (and out->sock6) for kind; 0 or -errno (out->sock closed). */
static int open_kind(int kind, const char *bind_addr, struct sockaddr_storage *sa,
                     socklen_t len, long port, fp_udp_listener *out)
{
    const bool asked_v6 = sa->ss_family == AF_INET6;
    if (asked_v6)
        ((struct sockaddr_in6 *)sa)->sin6_port = htons((uint16_t)port);
    else
        ((struct sockaddr_in *)sa)->sin_port = htons((uint16_t)port);
    if (kind == BIND_ANY) {
        struct sockaddr_in6 any = {.sin6_family = AF_INET6, .sin6_port = htons((uint16_t)port),
                                   .sin6_addr = IN6ADDR_ANY_INIT};
        out->sock = bound(AF_INET6, (struct sockaddr *)&any, sizeof any, 0);
        if (out->sock >= 0) {
            out->port = port_of(out->sock);
            snprintf(out->text, sizeof out->text, "[::]:%u (IPv4 and IPv6)", (unsigned)out->port);
            return 0;
        }
        if (asked_v6) return out->sock; /* bind=:: where there is no IPv6 */
        snprintf(out->warning, sizeof out->warning, "IPv6 senders are not heard: [::]:%ld "
                 "(IPv4 and IPv6) cannot be bound (%s); listening on 0.0.0.0 (IPv4) alone", port,
                 strerror(-out->sock));
    }
    out->sock = bound(sa->ss_family, (struct sockaddr *)sa, len, 1);
    if (out->sock < 0) return out->sock;
    out->port = port_of(out->sock);
    snprintf(out->text, sizeof out->text, asked_v6 && bind_addr[0] != '[' ? "[%s]:%u" : "%s:%u",
             kind == BIND_LOOPBACK ? "127.0.0.1" : bind_addr, (unsigned)out->port);
    if (kind != BIND_LOOPBACK) return 0;
    out->sock6 = fp_udp_bind_loopback6(out->port, SOCK_NONBLOCK);
    if (out->sock6 >= 0) {
        snprintf(out->text, sizeof out->text, "127.0.0.1:%u and [::1]:%u", (unsigned)out->port,
                 (unsigned)out->port);
    } else {
        int e = errno;
        snprintf(out->warning, sizeof out->warning, "[::1]:%u cannot be bound (%s%s): a sender "
                 "whose localhost is ::1 is not heard; listening on 127.0.0.1 alone",
                 (unsigned)out->port, strerror(e), e == EADDRINUSE ? ": another program has it" : "");
    }
    return 0;
}

int fp_udp_listen(const char *bind_addr, long port, fp_udp_listener *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    out->sock = out->sock6 = -1;
    struct sockaddr_storage sa;
    socklen_t len = 0;
    int kind = parse_bind(bind_addr, &sa, &len);
    if (kind < 0) {
        snprintf(err, errlen, "bind=%s: expected an IP address (127.0.0.1, 0.0.0.0, ::1, ::, "
                 "...) or localhost", bind_addr);
        return -EINVAL;
    }
    int rc = open_kind(kind, bind_addr, &sa, len, port, out);
    if (rc < 0) {
        snprintf(err, errlen, "cannot listen on %s:%ld (UDP): %s", bind_addr, port, strerror(-rc));
        out->sock = -1;
        return open_code(-rc);
    }
    if (kind == BIND_LOOPBACK)
        out->loopback = true;
    else if (sa.ss_family == AF_INET)
        out->loopback = (ntohl(((struct sockaddr_in *)&sa)->sin_addr.s_addr) >> 24) == 127;
    else if (kind == BIND_V6)
        out->loopback = IN6_IS_ADDR_LOOPBACK(&((struct sockaddr_in6 *)&sa)->sin6_addr);
    return 0;
}

void fp_udp_sender_text(const struct sockaddr_storage *from, char *text, size_t textlen)
{
    char addr[INET6_ADDRSTRLEN] = "?";
    unsigned port = 0;
    bool v6 = false;
    if (from->ss_family == AF_INET) {
        const struct sockaddr_in *a = (const struct sockaddr_in *)from;
        inet_ntop(AF_INET, &a->sin_addr, addr, sizeof addr);
        port = ntohs(a->sin_port);
    } else if (from->ss_family == AF_INET6) {
        const struct sockaddr_in6 *a = (const struct sockaddr_in6 *)from;
        port = ntohs(a->sin6_port);
        if (IN6_IS_ADDR_V4MAPPED(&a->sin6_addr)) {
            inet_ntop(AF_INET, &a->sin6_addr.s6_addr[12], addr, sizeof addr);
        } else {
            inet_ntop(AF_INET6, &a->sin6_addr, addr, sizeof addr);
            v6 = true;
        }
    }
    snprintf(text, textlen, v6 ? "[%s]:%u" : "%s:%u", addr, port);
}
