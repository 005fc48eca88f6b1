/* fp_net.c: a UDP socket connected to HOST:PORT (fp_net.h). */
#define _GNU_SOURCE /* SOCK_CLOEXEC */
#include "fp_net.h"

#include <errno.h>
#include <netdb.h>
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
