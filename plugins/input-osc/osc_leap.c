/*
 * osc_leap.c: Leap Motion bridge frames for the input-osc plugin (osc_leap.h, docs/osc.md).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "osc_leap.h"

#include <string.h>

/* Straight-finger estimate of the joints a Leap bridge does not send: for each finger the
 * lengths (mm) from the palm centre to MCP (CMC for the thumb), MCP-PIP, PIP-DIP, DIP-tip
 * (with the soft tip), after Buryanov & Kotiuk 2010 (shared/docs/devices.md); fingers use half
 * the metacarpal from the palm centre, the thumb 30 mm to its CMC. */
static const float leap_chain_mm[FP_FINGERS][4] = {
    {30.0f, 46.2f, 31.6f, 27.4f},  /* thumb: palm-CMC, metacarpal, proximal, distal + tip */
    {34.05f, 39.8f, 22.4f, 19.6f}, /* index */
    {32.3f, 44.6f, 26.3f, 21.4f},  /* middle */
    {29.0f, 41.4f, 25.7f, 21.3f},  /* ring */
    {26.85f, 32.6f, 18.1f, 19.7f}, /* pinky */
};

#define ALL_TIPS ((1u << FP_FINGERS) - 1)

int fp__osc_leap_address(const char *path, int *slot, int *finger)
{
    const char *p;
    if (strncmp(path, "/hand", 5) == 0)
        p = path + 5;
    else if (strncmp(path, "/finger", 7) == 0)
        p = path + 7;
    else
        return 0;
    if (*p < '0' || *p > '1' || (p[1] >= '0' && p[1] <= '9')) return 0;
    if (path[1] == 'h') {
        if (p[1] != 0) return 0;
        *slot = *p - '0';
        return 1;
    }
    if (p[1] != '-' || p[2] < '0' || p[2] > '4' || p[3] != 0) return 0;
    *slot = *p - '0';
    *finger = p[2] - '0';
    return 2;
}

static bool complete(const osc_leap_slot *ls) { return ls->have_palm && ls->tips == ALL_TIPS; }

static void frame_of(const osc_leap_slot *ls, int slot, osc_leap_frame *out)
{
    out->id = ls->id;
    out->slot = slot;
    out->t = ls->t;
    memcpy(out->palm, ls->palm, sizeof out->palm);
    memcpy(out->tip, ls->tip, sizeof out->tip);
}

int fp__osc_leap_take(osc_leap *l, int kind, int slot, int finger, int32_t id, const float v[3],
                      int64_t t, bool in_bundle, osc_leap_frame out[1], unsigned *incomplete)
{
    osc_leap_slot *ls = &l->slot[slot];
    const unsigned bit = kind == 1 ? 0u : 1u << finger;
    int n = 0;
    bool counted = false;
    if ((ls->have_palm || ls->tips) &&
        (id != ls->id || (kind == 1 ? ls->have_palm : (ls->tips & bit) != 0))) {
        /* this message begins the next frame: the one assembled is done with */
        if (complete(ls)) { /* (only in a bundle, waiting for its end) */
            frame_of(ls, slot, &out[n++]);
        } else if (!(kind == 1 && ls->have_palm && !ls->tips && id == ls->id)) {
            (*incomplete)++; /* (a palm again before any tip just replaces it, as ever) */
            counted = true;
        }
        memset(ls, 0, sizeof *ls);
    }
    if (kind == 2 && !ls->have_palm && !in_bundle) { /* outside a bundle the palm comes first */
        if (!counted) (*incomplete)++;
        memset(ls, 0, sizeof *ls);
        return n;
    }
    ls->id = id;
    if (kind == 1) {
        ls->have_palm = true;
        memcpy(ls->palm, v, sizeof ls->palm);
        ls->t = t;
    } else {
        memcpy(ls->tip[finger], v, sizeof ls->tip[finger]);
        ls->tips |= bit;
    }
    ls->in_packet |= in_bundle;
    if (!in_bundle && complete(ls)) {
        frame_of(ls, slot, &out[n++]);
        memset(ls, 0, sizeof *ls);
    }
    return n;
}

int fp__osc_leap_end_packet(osc_leap *l, osc_leap_frame out[OSC_LEAP_SLOTS], unsigned *incomplete)
{
    int n = 0;
    for (int s = 0; s < OSC_LEAP_SLOTS; s++) {
        osc_leap_slot *ls = &l->slot[s];
        if (!ls->in_packet) continue;
        ls->in_packet = false;
        if (complete(ls)) {
            frame_of(ls, s, &out[n++]);
            memset(ls, 0, sizeof *ls);
        } else if (!ls->have_palm) { /* tips whose palm never came */
            (*incomplete)++;
            memset(ls, 0, sizeof *ls);
        }
    }
    return n;
}

/* The remembered entry of id, or NULL. */
static osc_leap_side *find_id(osc_leap *l, int32_t id)
{
    for (int i = 0; i < OSC_LEAP_IDS; i++)
        if (l->ids[i].used && l->ids[i].id == id) return &l->ids[i];
    return NULL;
}

/* A free entry for a new id: an unused one, else the one seen longest ago. */
static osc_leap_side *new_id(osc_leap *l)
{
    osc_leap_side *best = &l->ids[0];
    for (int i = 0; i < OSC_LEAP_IDS; i++) {
        if (!l->ids[i].used) return &l->ids[i];
        if (l->ids[i].last_ns < best->last_ns) best = &l->ids[i];
    }
    return best;
}

void fp__osc_leap_sides(osc_leap *l, const osc_leap_frame *fr, int n, int64_t now_ns,
                        int64_t keep_ns, int side[])
{
    unsigned taken = 0; /* bit per side held by a present id */
    for (int i = 0; i < OSC_LEAP_IDS; i++) {
        if (l->ids[i].used && now_ns - l->ids[i].last_ns > keep_ns) l->ids[i].used = false;
        if (l->ids[i].used) taken |= 1u << l->ids[i].side;
    }
    int order[OSC_LEAP_SLOTS], unknown = 0;
    for (int i = 0; i < n; i++) {
        const osc_leap_side *e = find_id(l, fr[i].id);
        side[i] = e ? e->side : -1;
        if (!e) order[unknown++] = i;
    }
    if (unknown == 1 && n == 1) { /* the one present hand found again under a new id? */
        osc_leap_side *held = NULL;
        int present = 0;
        for (int i = 0; i < OSC_LEAP_IDS; i++)
            if (l->ids[i].used) held = &l->ids[i], present++;
        /* ... and gone quiet: no frame for half its own spacing (a second hand a bridge sends in
         * a datagram of its own comes within the first's frame, not a frame later) */
        if (present == 1 && now_ns - held->last_ns >= held->gap_ns / 2) {
            float d2 = 0;
            for (int k = 0; k < 3; k++)
                d2 += (fr[0].palm[k] - held->palm[k]) * (fr[0].palm[k] - held->palm[k]);
            if (d2 <= OSC_LEAP_REACQUIRE_MM * OSC_LEAP_REACQUIRE_MM) {
                held->id = fr[0].id; /* the same hand: its entry, its side */
                held->gap_ns = now_ns - held->last_ns;
                held->last_ns = now_ns;
                memcpy(held->palm, fr[0].palm, sizeof held->palm);
                side[0] = held->side;
                return;
            }
        }
    }
    if (unknown == 2 && fr[order[1]].palm[0] < fr[order[0]].palm[0]) {
        int k = order[0];
        order[0] = order[1];
        order[1] = k;
    }
    for (int u = 0; u < unknown; u++) { /* by palm x, smaller first */
        const int i = order[u];
        const unsigned both = 1u << FP_HAND_LEFT | 1u << FP_HAND_RIGHT, free = both & ~taken;
        int s;
        if (free == both && u + 1 < unknown)
            s = FP_HAND_LEFT; /* two new hands at once: the one at smaller x is the left */
        else if (free == (1u << FP_HAND_LEFT) || free == (1u << FP_HAND_RIGHT))
            s = free == (1u << FP_HAND_LEFT) ? FP_HAND_LEFT : FP_HAND_RIGHT;
        else
            s = fr[i].palm[0] < 0 ? FP_HAND_LEFT : FP_HAND_RIGHT;
        osc_leap_side *e = new_id(l);
        *e = (osc_leap_side){.used = true, .id = fr[i].id, .side = s, .last_ns = now_ns,
                             .palm = {fr[i].palm[0], fr[i].palm[1], fr[i].palm[2]}};
        taken |= 1u << s;
        side[i] = s;
    }
    for (int i = 0; i < n; i++) {
        osc_leap_side *e = find_id(l, fr[i].id);
        if (e) {
            if (now_ns > e->last_ns) e->gap_ns = now_ns - e->last_ns;
            e->last_ns = now_ns;
            memcpy(e->palm, fr[i].palm, sizeof e->palm);
        }
    }
}

void fp__osc_leap_joints(const osc_leap_frame *f, float mm[FP_HAND_JOINTS][3])
{
    memcpy(mm[FP_JOINT_PALM], f->palm, sizeof mm[0]);
    for (int fi = 0; fi < FP_FINGERS; fi++) {
        const float *c = leap_chain_mm[fi];
        float total = c[0] + c[1] + c[2] + c[3], acc = 0;
        for (int k = 0; k < 3; k++) {
            acc += c[k];
            float s = acc / total;
            for (int i = 0; i < 3; i++)
                mm[FP_JOINT(fi, k)][i] = f->palm[i] + s * (f->tip[fi][i] - f->palm[i]);
        }
        memcpy(mm[FP_JOINT_TIP(fi)], f->tip[fi], sizeof mm[0]);
    }
}
