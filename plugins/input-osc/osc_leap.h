/*
 * osc_leap.h: the input-osc plugin's Leap Motion bridge frames (docs/osc.md, "format=leap"),
 * private to the plugin: osc_leap.c assembles a frame from a palm message (/hand<s>) and five
 * tip messages (/finger<s>-<n>), decides each Leap hand's side and places the joints the
 * bridge does not send; input_osc.c checks the messages and pushes the events.
 * No I/O, no allocation, no locks: all of it on the plugin's receive thread.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FP_OSC_LEAP_H
#define FP_OSC_LEAP_H

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stdint.h>

#define OSC_LEAP_SLOTS 2  /* /hand0, /hand1 */
#define OSC_LEAP_IDS 4    /* Leap hand ids whose side is remembered */

/* A frame being assembled in one slot. */
typedef struct osc_leap_slot {
    bool have_palm;
    bool in_packet;                /* has data from the datagram being read (a bundle) */
    int32_t id;                    /* the Leap hand id of its palm and tips */
    unsigned tips;                 /* bit per finger */
    int64_t t;                     /* event time (ns, host clock): the palm's */
    float palm[3], tip[FP_FINGERS][3];
} osc_leap_slot;

/* A complete frame: palm and five tips (mm, device frame). */
typedef struct osc_leap_frame {
    int32_t id;
    int slot;
    int64_t t;
    float palm[3], tip[FP_FINGERS][3];
} osc_leap_frame;

/* A new Leap id this close (mm, palm to palm) to the one other present id's last palm is
 * that hand re-acquired (fp__osc_leap_sides). */
#define OSC_LEAP_REACQUIRE_MM 100.0f

/* A Leap hand id and the side it was given. */
typedef struct osc_leap_side {
    bool used;
    int32_t id;
    int side;                      /* FP_HAND_LEFT or FP_HAND_RIGHT */
    int64_t last_ns;               /* host time of its latest frame */
    int64_t gap_ns;                /* ... and the spacing before it (0: one frame so far) */
    float palm[3];                 /* its latest frame's palm, mm */
} osc_leap_side;

/* All of a sender's Leap state; all zeros is the empty state (memset to reset). */
typedef struct osc_leap {
    osc_leap_slot slot[OSC_LEAP_SLOTS];
    osc_leap_side ids[OSC_LEAP_IDS];
} osc_leap;

/** Parses "/hand<s>" or "/finger<s>-<n>" (s 0..1, n 0..4 thumb..pinky): 1 a palm (*slot
 *  set), 2 a tip (*slot and *finger set), 0 neither (nothing set). */
int fp__osc_leap_address(const char *path, int *slot, int *finger);

/** Takes one checked message: kind 1 a palm, 2 a tip (`finger`), of Leap hand `id` in `slot`
 *  (0..1), position v (mm, finite), event time t (ns). in_bundle: the message is inside a
 *  bundle, whose messages form frames in any order (tips before the palm too) and whose
 *  frames come out at its end (fp__osc_leap_end_packet); outside a bundle the palm comes first
 *  and a frame comes out with its fifth tip. A message that repeats a part of the frame being
 *  assembled (a second palm, a tip again) or names another id begins the next frame.
 *  Writes the frames completed now to out (at most 1) and returns their count; adds to
 *  *incomplete the frames dropped unfinished. */
int fp__osc_leap_take(osc_leap *l, int kind, int slot, int finger, int32_t id, const float v[3],
                      int64_t t, bool in_bundle, osc_leap_frame out[1], unsigned *incomplete);

/** The end of a datagram: the frames its bundle completed, to out (at most OSC_LEAP_SLOTS, slot
 *  order), returned as a count; tips that never got their palm in the bundle are dropped (added
 *  to *incomplete); a palm still waiting for tips waits on (a sender that bundles each message
 *  alone). */
int fp__osc_leap_end_packet(osc_leap *l, osc_leap_frame out[OSC_LEAP_SLOTS], unsigned *incomplete);

/** The side (FP_HAND_LEFT / FP_HAND_RIGHT) of each of the n (<= OSC_LEAP_SLOTS) frames of one
 *  datagram, into side[]: a Leap id keeps the side it was given when it first came; a new id
 *  takes the side no present id holds; two new ids at once (and nothing present) take left
 *  for the smaller palm x; otherwise a new id alone is left at palm x < 0. A new id alone in
 *  its datagram while one other id is present, absent from it and quiet for half its frames'
 *  spacing or more, with its last palm within OSC_LEAP_REACQUIRE_MM of the new palm, is
 *  that hand found again under a new id (a Leap
 *  renumbers a hand it lost): it takes that id's side, and the old id is forgotten. An id is present
 *  while its last frame is at most keep_ns (the input's timeout) before now_ns; older ones are
 *  forgotten. */
void fp__osc_leap_sides(osc_leap *l, const osc_leap_frame *fr, int n, int64_t now_ns,
                        int64_t keep_ns, int side[]);

/** The 21 joints of a frame (plugin.h order, mm): the palm and tips as sent, MCP, PIP, DIP
 *  (CMC, MCP, IP for the thumb) on the straight line from palm to tip at the Buryanov & Kotiuk
 *  bone proportions (shared/docs/devices.md). */
void fp__osc_leap_joints(const osc_leap_frame *f, float mm[FP_HAND_JOINTS][3]);

#endif
