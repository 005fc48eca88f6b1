/* fp_net.c: a UDP socket connected to HOST:PORT, and the IPv6 loopback beside 127.0.0.1
 * (fp_net.h). */
#define _GNU_SOURCE /* SOCK_CLOEXEC */
#include "fp_net.h"

#include <errno.h>
#include <netdb.h>
#include <netinet/in.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

int fp_udp_connect(const char *host, const char *port, int flags, char *why, size_t whylen)
{
    char name[256];
    size_t n = host ? strlen(host) : 0;
    if (n >= 2 && host[0] == '[' && host[n - 1] == ']') /* an IPv6 address in brackets */
        snprintf(name, sizeof name, "%.*s", (int)(n - 2), host + 1);
    else
        snprintf(name, sizeof name, "%s", host ? host : "");
    struct addrinfo hints = {.ai_family = AF_UNSPEC, .ai_socktype = SOCK_DGRAM}, *ai = NULL;
    int g = getaddrinfo(name, port, &hints, &ai);
    if (g) {
        if (why && whylen) snprintf(why, whylen, "%s", gai_strerror(g));
        return g == EAI_SYSTEM && errno ? -errno : -ENOENT;
    }
    /* IPv4 addresses first: a UDP connect succeeds whoever listens, so the first address is
     * the one sent to, and a name such as localhost, which resolves to ::1 first where
     * /etc/hosts lists both, would miss a receiver bound to 127.0.0.1 (as most are) */
    int sock = -1, e = EADDRNOTAVAIL;
    for (int pass = 0; pass < 2 && sock < 0; pass++)
        for (const struct addrinfo *a = ai; a && sock < 0; a = a->ai_next) {
            if ((a->ai_family == AF_INET) != (pass == 0)) continue;
            sock = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | flags, a->ai_protocol);
            if (sock >= 0 && connect(sock, a->ai_addr, a->ai_addrlen) != 0) {
                e = errno;
                close(sock);
                sock = -1;
            } else if (sock < 0) {
                e = errno;
            }
        }
    freeaddrinfo(ai);
    if (sock < 0 && why && whylen) snprintf(why, whylen, "%s", strerror(e));
    return sock >= 0 ? sock : -e;
}

int fp_udp_bind_loopback6(unsigned port, int flags)
{
    if (port == 0 || port > 65535) {
        errno = EINVAL;
        return -1;
    }
    struct sockaddr_in6 sa = {.sin6_family = AF_INET6, .sin6_port = htons((uint16_t)port),
                              .sin6_addr = IN6ADDR_LOOPBACK_INIT};
    int s = socket(AF_INET6, SOCK_DGRAM | SOCK_CLOEXEC | flags, 0), one = 1;
    if (s < 0) return -1;
    if (setsockopt(s, IPPROTO_IPV6, IPV6_V6ONLY, &one, sizeof one) != 0 ||
        bind(s, (struct sockaddr *)&sa, sizeof sa) != 0) {
        int e = errno;
        close(s);
        errno = e;
        return -1;
    }
    return s;
}
