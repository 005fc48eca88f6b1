/*
 * osc_net.h: the input-osc plugin's listening sockets (bind=, docs/osc.md), private to the
 * plugin: osc_net.c parses the address and binds, input_osc.c reads the sockets.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FP_OSC_NET_H
#define FP_OSC_NET_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

struct sockaddr_storage;

/* What the input listens on. */
typedef struct osc_listen {
    int sock;          /* the socket bound to bind= (IPv4, IPv6, or [::] for both) */
    int sock6;         /* [::1] beside 127.0.0.1 (bind=127.0.0.1 or localhost), else -1 */
    uint16_t port;     /* the port bound (PORT 0: the one picked) */
    bool loopback;     /* only this machine can reach it */
    char text[96];     /* where, for the log: "127.0.0.1:9000 and [::1]:9000", "[::]:9000 ..." */
    char warning[256]; /* "" or why IPv6 senders are not heard where they were meant to be */
} osc_listen;

/** Opens the UDP sockets (SOCK_NONBLOCK | SOCK_CLOEXEC) for bind_addr at port (0..65535):
 *  - "127.0.0.1" (the default) or "localhost": 127.0.0.1, and [::1] at the same port where the
 *    machine has IPv6 (a sender's "localhost" may resolve to ::1 first);
 *  - "0.0.0.0" or "::": one IPv6 socket on [::] with IPV6_V6ONLY off, hearing IPv4 senders too;
 *    for 0.0.0.0 where that cannot be had (no IPv6, the port taken on IPv6 alone), 0.0.0.0;
 *  - another IPv4 address: that one; another IPv6 literal (bare or in brackets, with a %scope
 *    where link-local): that one, IPv6 only.
 *  Where the IPv6 side of the first two cannot be bound, out->warning says why (the input
 *  logs it). Returns 0, or a negative code with a message in err: -EINVAL (not an IP address
 *  nor localhost), -EBUSY (the port taken), -ENODEV (an address this machine does not have,
 *  or IPv6 asked for where there is none), another -errno. On failure no socket stays open.
 *  Thread-safe (no shared state). */
int fp__osc_listen(const char *bind_addr, long port, osc_listen *out, char *err, size_t errlen);

/** A sender's address as "1.2.3.4:5" or "[::1]:5" (an IPv4 sender on a dual-stack socket,
 *  ::ffff:1.2.3.4, as IPv4), into text (textlen bytes, "?" when unknown). */
void fp__osc_sender_text(const struct sockaddr_storage *from, char *text, size_t textlen);

#endif
