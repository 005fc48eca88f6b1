/*
 * osc_mediapipe.h: the input-osc plugin's MediaPipe hands (docs/osc.md, "format=mediapipe"),
 * private to the plugin: osc_mediapipe.c assembles a hand's frame from its /lx/ /ly/ [/lz/]
 * messages (a sender with z or without, a bundle's frame waiting for its z to the datagram's
 * end) and turns the normalised landmarks into millimetres; input_osc.c checks the messages
 * and pushes the events. No I/O, no allocation, no locks: all of it on the receive thread.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FP_OSC_MEDIAPIPE_H
#define FP_OSC_MEDIAPIPE_H

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stdint.h>

#define OSC_MP_LANDMARKS 21

/* One hand's frame being assembled. Zero-initialised: nothing yet, the sender's z unknown. */
typedef struct osc_mp_hand {
    unsigned have;                 /* bit 0 x, 1 y, 2 z since the last frame */
    bool z_seen;                   /* this sender sends z: wait for it (until it stops) */
    bool xy_only;                  /* the last frame was emitted from x and y alone */
    bool pending;                  /* x and y in a bundle, z not yet seen from this sender: the
                                      frame waits for the datagram's end (its z may be in it) */
    int64_t t;                     /* the time of the frame's latest part */
    float v[3][OSC_MP_LANDMARKS];
} osc_mp_hand;

/* The image's placement in the device frame (mm): the SPEC's width, aspect, height, depth,
 * mirror (docs/osc.md). */
typedef struct osc_mp_place {
    float width, aspect, height, depth;
    bool mirror;
} osc_mp_place;

/* A frame to push: plugin.h's joints (mm, device frame) at time t (ns, host clock). */
typedef struct osc_mp_frame {
    int64_t t;
    float mm[FP_HAND_JOINTS][3];
} osc_mp_frame;

/** Whether path is a MediaPipe hand's: "/lx", "/ly", "/lz", "/rx", ... with or without a
 *  trailing '/'. */
bool fp__osc_mp_address(const char *path);

/** Takes one coordinate (axis 0 x, 1 y, 2 z) of a hand's 21 landmarks (finite, normalised) at
 *  time t; in_bundle: the message came in a bundle. Writes the frames it completes to out (at
 *  most 2, in order) and returns their count; *incomplete grows by the frames a new one
 *  superseded before they were whole. */
int fp__osc_mp_take(osc_mp_hand *m, const osc_mp_place *pl, int axis,
                    const float v[OSC_MP_LANDMARKS], int64_t t, bool in_bundle,
                    osc_mp_frame out[2], unsigned *incomplete);

/** The end of a datagram: the frame that waited in it for a z that did not come, emitted flat
 *  (from now on x and y make a frame). Returns 1 with *out set, or 0. */
int fp__osc_mp_end_packet(osc_mp_hand *m, const osc_mp_place *pl, osc_mp_frame *out);

/** Forgets the frame being assembled and what the sender sends (its silence, a lost hand):
 *  the next sender may send no z. */
void fp__osc_mp_forget(osc_mp_hand *m);

#endif
