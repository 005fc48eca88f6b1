/*
 * fp_forward.h: the host key `forward=osc:HOST:PORT` of any input (issue 55, item 4;
 * docs/osc.md, "Forward"): every event the input pushes that the host's queue takes is sent
 * again over OSC/UDP in the OSC input's own format (format=facepuppet), so that another
 * facepuppet session receives this input as `--input osc:PORT`. Each event goes in a bundle
 * whose timetag is its time (the host clock), which the OSC input maps to its own clock: the
 * sender's spacing is kept exactly. The bundle's first element is the input's time zero (the
 * time of the first event it pushed: a replay's start), /facepuppet/origin t, so that a
 * receiver on `clock=recording` places each event at its time on the recording's clock.
 *   joint positions -> /facepuppet/hand/{left,right}/joints 63 x f
 *   joint angles    -> /facepuppet/hand/{left,right}/angles i (valid mask) + 22 x f
 *   wrist pose      -> /facepuppet/hand/{left,right}/wrist 7 x f
 *   button          -> /facepuppet/button i (0 left, 1 middle, 2 right) i (down)
 *   end of stream   -> /facepuppet/end (no arguments: the recording ended)
 * Other status and channel events, key requests and events without a hand are not forwarded
 * (counted). A failed send is counted, never fatal.
 *
 * Errors: 0 or a negative code with err: -EINVAL a bad SPEC, -ENOENT a host that does not
 * resolve, the socket's codes, -ENOTSUP in a build without liblo. Threads: push from any
 * thread (the input's; no lock, a message on the stack); create and destroy on the owner's.
 */
#ifndef FP_FORWARD_H
#define FP_FORWARD_H

#include "facepuppet/plugin.h"

#include <stddef.h>
#include <stdint.h>

typedef struct fp_event_forwarder fp_event_forwarder;

typedef struct fp_forward_stats {
    uint64_t sent, skipped, errors;
} fp_forward_stats;

int fp_event_forwarder_create(const char *spec, fp_event_forwarder **out, char *err, size_t errlen);
/** Forward one event (see above). [any thread] */
void fp_event_forwarder_push(fp_event_forwarder *f, const fp_event *ev);
void fp_event_forwarder_stats(const fp_event_forwarder *f, fp_forward_stats *st);
/** "127.0.0.1:9000" */
const char *fp_event_forwarder_target(const fp_event_forwarder *f);
/** Close the socket and free; *f NULL. NULL is fine. After the input's threads stopped. */
void fp_event_forwarder_destroy(fp_event_forwarder **f);

#endif
