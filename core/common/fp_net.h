/*
 * fp_net.h: the one way the project opens a UDP socket to a HOST:PORT it was given (--stream,
 * an input's forward=): IPv4 or IPv6, by address or by name; the IPv6 loopback beside a
 * listener on 127.0.0.1; and a listener on the address a user gave (the osc input's bind=,
 * --control's bind=: fp_udp_listen, in fp_net_listen.c).
 * Link: the static library `fp_common`.
 */
#ifndef FP_NET_H
#define FP_NET_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** A UDP socket connected to host:port (so that send() needs no address): host an IPv4
 *  address, an IPv6 one bare or in brackets ("::1", "[::1]", as in osc:[::1]:9000) or a name,
 *  its IPv4 addresses tried first (a name such as localhost that resolves to ::1 and
 *  127.0.0.1 reaches a receiver bound to 127.0.0.1), then its IPv6 ones; port decimal. Opened SOCK_CLOEXEC |
 *  flags (e.g. SOCK_NONBLOCK). Returns the socket (the caller closes it), or a negative
 *  errno-style code (-ENOENT: the name does not resolve) with the reason in why (whylen
 *  bytes: getaddrinfo's text or the system's). Thread-safe. */
int fp_udp_connect(const char *host, const char *port, int flags, char *why, size_t whylen);

/** A UDP socket bound to [::1]:port for IPv6 alone (IPV6_V6ONLY), beside a listener on
 *  127.0.0.1:port: a sender told "localhost" may resolve it to ::1 first (getaddrinfo's order
 *  where /etc/hosts lists both) and would otherwise send into nothing. Best effort: the
 *  socket (SOCK_CLOEXEC | flags; the caller closes it), or -1 where the machine has no IPv6
 *  loopback or the port is taken there (errno says why). port 1..65535. Thread-safe. */
int fp_udp_bind_loopback6(unsigned port, int flags);

struct sockaddr_storage;

/** What a listener listens on (fp_udp_listen). */
typedef struct fp_udp_listener {
    int sock;          /* the socket bound to the address (IPv4, IPv6, or [::] for both) */
    int sock6;         /* [::1] beside 127.0.0.1 (127.0.0.1 or localhost), else -1 */
    uint16_t port;     /* the port bound (port 0: the one picked) */
    bool loopback;     /* only this machine can reach it */
    char text[96];     /* where, for the log: "127.0.0.1:9000 and [::1]:9000", "[::]:9000 ..." */
    char warning[256]; /* "" or why IPv6 senders are not heard where they were meant to be */
} fp_udp_listener;

/** Opens the UDP sockets (SOCK_NONBLOCK | SOCK_CLOEXEC) for bind_addr at port (0..65535):
 *  - "127.0.0.1" or "localhost": 127.0.0.1, and [::1] at the same port where the machine has
 *    IPv6 (a sender's "localhost" may resolve to ::1 first);
 *  - "0.0.0.0" or "::": one IPv6 socket on [::] with IPV6_V6ONLY off, hearing IPv4 senders too
 *    (they arrive as ::ffff:a.b.c.d); for 0.0.0.0 where that cannot be had (no IPv6, the port
 *    taken on IPv6 alone), 0.0.0.0;
 *  - another IPv4 address: that one; another IPv6 literal (bare or in brackets, with a %scope
 *    where link-local): that one, IPv6 only.
 *  Where the IPv6 side of the first two cannot be bound, out->warning says why (the caller
 *  logs it). Returns 0 and *out (the caller closes out->sock and out->sock6 where >= 0), or a
 *  negative code with a message in err (errlen bytes; the caller prefixes who asked): -EINVAL
 *  (not an IP address nor localhost), -EBUSY (the port taken), -ENODEV (an address this
 *  machine does not have, or IPv6 asked for where there is none), another -errno. On failure
 *  no socket stays open. Thread-safe (no shared state). */
int fp_udp_listen(const char *bind_addr, long port, fp_udp_listener *out, char *err, size_t errlen);

/** A sender's address as "1.2.3.4:5" or "[::1]:5" (an IPv4 sender on a dual-stack socket,
 *  ::ffff:1.2.3.4, as IPv4), into text (textlen bytes, "?:0" when unknown). Thread-safe. */
void fp_udp_sender_text(const struct sockaddr_storage *from, char *text, size_t textlen);

#ifdef __cplusplus
}
#endif

#endif
