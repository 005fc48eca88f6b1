/*
 * osc.h: the input-osc plugin's extension (statistics), for hosts, tests and tools.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Ask an input created by the "osc" factory with
 *     const fp_osc_ext *x = input->get_extension(input, FP_OSC_EXT_ID);
 * and call x->get_stats(input, &stats) [any thread but the session thread; takes a short
 * lock that the receive thread holds only for its bookkeeping]. The address space and the
 * formats are in docs/osc.md.
 */
#ifndef FACEPUPPET_OSC_H
#define FACEPUPPET_OSC_H

#include <stdint.h>

#include "facepuppet/plugin.h"

#define FP_OSC_EXT_ID "org.facepuppet.osc-stats/3" /* /2: FP_OSC_UNTIMED; /3: FP_OSC_STALE,
                                                      FP_OSC_KERNEL_DROPPED */

/** What went wrong with a packet or message; each kind is counted, and reported once (host
 *  log + a warning status) about a second after its first occurrence, with the count by
 *  then; the totals are logged at stop. */
typedef enum fp_osc_problem {
    FP_OSC_MALFORMED = 0,   /* not an OSC packet: liblo cannot decode it, or a bad bundle */
    FP_OSC_BAD_TYPES,       /* a known address with the right count but wrong type tags */
    FP_OSC_BAD_COUNT,       /* a known address with the wrong number of arguments */
    FP_OSC_NONFINITE,       /* a NaN or infinity among the values */
    FP_OSC_OUT_OF_RANGE,    /* a position beyond 10 m, an angle beyond 2 pi, a bad quaternion
                               or button */
    FP_OSC_UNKNOWN_ADDRESS, /* an address outside the chosen format's space */
    FP_OSC_INCOMPLETE,      /* a frame assembled from several messages (leap, mediapipe) that
                               was superseded before it was complete */
    FP_OSC_QUEUE_FULL,      /* an event the host refused (its bounded queue was full) */
    FP_OSC_UNTIMED,         /* clock=recording: a message outside a timed bundle, or before the
                               sender's /facepuppet/origin (no time on the recording's clock) */
    FP_OSC_STALE,           /* a pose older than the last of its kind pushed for that hand (a
                               bundle that arrived out of order), dropped */
    FP_OSC_KERNEL_DROPPED,  /* datagrams the kernel dropped, its socket buffer full (Linux
                               SO_RXQ_OVFL; 0 where the system does not say) */
    FP_OSC_PROBLEMS
} fp_osc_problem;

typedef struct fp_osc_stats {
    uint32_t size;              /* set by the caller: sizeof(fp_osc_stats) */
    uint16_t port;              /* the UDP port listened on (the one chosen, for port 0) */
    uint64_t packets;           /* UDP datagrams received */
    uint64_t messages;          /* OSC messages decoded (inside bundles too) */
    uint64_t bundles;           /* OSC bundles (nested ones too) */
    uint64_t events;            /* events pushed and accepted by the host (status ones too) */
    uint64_t filtered;          /* well-formed messages for a hand not selected (hand=) */
    uint64_t problems[FP_OSC_PROBLEMS]; /* per fp_osc_problem; [FP_OSC_QUEUE_FULL] = drops */
    uint64_t connects;          /* silence -> traffic transitions (CONNECTED pushed) */
    uint64_t disconnects;       /* traffic -> silence for `timeout` (DISCONNECTED pushed) */
    int64_t timetag_offset_ns;  /* host clock - sender clock: arrival - timetag of the sender's
                                   bundle that came soonest (clock=arrival; docs/osc.md, Time) */
    uint64_t latency_samples;   /* packets behind the two figures below (last <= 65536) */
    double latency_median_us;   /* packet received (recvfrom returned) -> its last event pushed */
    double latency_p99_us;
    uint64_t hands_lost;        /* a hand silent for `timeout` while the sender went on
                                   (DISCONNECTED pushed for that hand alone) */
} fp_osc_stats;

typedef struct fp_osc_ext {
    uint32_t size;
    /** Copy the statistics so far. Safe while the input runs and after stop. */
    void (*get_stats)(const fp_input *input, fp_osc_stats *out);
    /** The name of a problem kind ("malformed", "bad-types", ...); "?" when out of range. */
    const char *(*problem_name)(int kind);
} fp_osc_ext;

#endif
