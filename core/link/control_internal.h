/* control_internal.h: the control surface's state, shared by control_server.c (socket,
 * thread, queue, replies) and control_parse.c (the messages' checks). Not installed. */
#ifndef FP_CONTROL_INTERNAL_H
#define FP_CONTROL_INTERNAL_H

#include "fp_control.h"

#include <pthread.h>
#include <stdatomic.h>

struct fp_control {
    int sock;
    int sock6;                                /* [::1] at the same port beside 127.0.0.1, or -1 */
    unsigned port;
    char where[96];                           /* fp_udp_listener.text: "127.0.0.1:9001 and [::1]:9001" */
    int stop_pipe[2];
    pthread_t thread;
    unsigned char buf[65536];                 /* one datagram (the network thread's) */
    fp_control_cmd ring[FP_CONTROL_RING];     /* single producer (network), single consumer */
    fp_control_cmd stage[FP_CONTROL_RING];    /* one datagram's commands, until it is checked whole */
    _Atomic size_t head, tail;
    _Atomic uint64_t packets, messages, queued;
    _Atomic uint64_t problems[FP_CTL_PROBLEMS];
    /* the frame thread's */
    struct sockaddr_storage subs[FP_CONTROL_MAX_SUBSCRIBERS];
    socklen_t sublen[FP_CONTROL_MAX_SUBSCRIBERS];
    size_t nsubs;
    uint64_t replies, pushes, send_errors;
};

/** Walk one datagram (bundles, nesting up to 8): checked whole before any of it is queued.
 *  Every message in it is queued together (one release of the ring's head), or none is and
 *  the datagram is counted once, as its first refusal (a malformed part before any other),
 *  with no reply. `from` carries the sender. [network thread] */
void fp__control_packet(fp_control *c, unsigned char *data, size_t size, const fp_control_cmd *from);
/** Queue n commands together, or none (false: the ring lacks room for all). [network thread] */
bool fp__control_queue_all(fp_control *c, const fp_control_cmd *cmds, size_t n);
void fp__control_problem(fp_control *c, fp_control_problem p);

#endif
