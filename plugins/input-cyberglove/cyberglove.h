/*
 * cyberglove.h: the input-cyberglove plugin's extension (statistics), for hosts and tests.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Ask an input created by the "cyberglove" factory with
 *     const fp_cyberglove_ext *x = input->get_extension(input, FP_CYBERGLOVE_EXT_ID);
 * and call x->get_stats(input, &stats) [main-thread or any-thread; takes a short lock held
 * only by the input thread's bookkeeping; never call it from the session thread].
 */
#ifndef FACEPUPPET_CYBERGLOVE_H
#define FACEPUPPET_CYBERGLOVE_H

#include <stdint.h>

#include "facepuppet/plugin.h"

#define FP_CYBERGLOVE_EXT_ID "org.facepuppet.cyberglove-stats/1"

typedef struct fp_cyberglove_stats {
    uint32_t size;              /* set by the caller: sizeof(fp_cyberglove_stats) */
    uint64_t records;           /* well-formed records decoded (all connections) */
    uint64_t events;            /* joint-angle events pushed and accepted by the host */
    uint64_t dropped;           /* joint-angle events the host refused (queue full) */
    uint64_t noise_bytes;       /* bytes skipped while resynchronising */
    uint64_t resyncs;           /* resynchronisation episodes */
    uint64_t connects;          /* successful probes (1 + reconnections) */
    uint64_t timeouts;          /* times the glove stopped answering */
    uint64_t latency_samples;   /* samples behind the two figures below (last <= 65536) */
    double latency_median_us;   /* record's last byte read -> event pushed, microseconds */
    double latency_p99_us;
    int32_t sensors;            /* from the last probe: 18 or 22; 0 before */
    int32_t right_hand;         /* from the last probe (?R): 1 right, 0 left, -1 unknown */
    char version[64];           /* ?V reply of the last probe */
} fp_cyberglove_stats;

typedef struct fp_cyberglove_ext {
    uint32_t size;
    /** Copy the statistics so far. Safe while the input runs and after stop. */
    void (*get_stats)(const fp_input *input, fp_cyberglove_stats *out);
} fp_cyberglove_ext;

#endif
