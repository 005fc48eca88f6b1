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
    int stop_pipe[2];
    pthread_t thread;
    unsigned char buf[65536];                 /* one datagram (the network thread's) */
    fp_control_cmd ring[FP_CONTROL_RING];     /* single producer (network), single consumer */
    _Atomic size_t head, tail;
    _Atomic uint64_t packets, messages, queued;
    _Atomic uint64_t problems[FP_CTL_PROBLEMS];
    /* the frame thread's */
    struct sockaddr_storage subs[FP_CONTROL_MAX_SUBSCRIBERS];
    socklen_t sublen[FP_CONTROL_MAX_SUBSCRIBERS];
    size_t nsubs;
    uint64_t replies, pushes, send_errors;
};

/** Walk one datagram or bundle element (depth: bundles nested so far); each message checked
 *  and queued, or counted. `from` carries the sender. [network thread] */
void fp__control_packet(fp_control *c, unsigned char *data, size_t size, const fp_control_cmd *from,
                        int depth);
void fp__control_queue(fp_control *c, const fp_control_cmd *cmd);
void fp__control_problem(fp_control *c, fp_control_problem p);

#endif
