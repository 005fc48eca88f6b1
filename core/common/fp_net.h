/*
 * fp_net.h: the one way the project opens a UDP socket to a HOST:PORT it was given (--stream,
 * an input's forward=): IPv4 or IPv6, by address or by name; and the IPv6 loopback beside a
 * listener on 127.0.0.1 (--control).
 * Link: the static library `fp_common`.
 */
#ifndef FP_NET_H
#define FP_NET_H

#include <stddef.h>

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

#ifdef __cplusplus
}
#endif

#endif
