/*
 * osc_mediapipe.c: MediaPipe hands over OSC, assembled and placed (osc_mediapipe.h).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "osc_mediapipe.h"

#include <string.h>

bool fp__osc_mp_address(const char *path)
{
    size_t n = strlen(path);
    return n >= 3 && n <= 4 && path[0] == '/' && (path[1] == 'l' || path[1] == 'r') &&
           (path[2] == 'x' || path[2] == 'y' || path[2] == 'z') && (n == 3 || path[3] == '/');
}

/* The frame of m's landmarks (z where m has it), at time t. */
static void frame_of(const osc_mp_hand *m, const osc_mp_place *pl, int64_t t, osc_mp_frame *out)
{
    float lm[OSC_MP_LANDMARKS][3];
    for (int j = 0; j < OSC_MP_LANDMARKS; j++) {
        float x = m->v[0][j], y = m->v[1][j], z = m->have & 4 ? m->v[2][j] : 0.f;
        if (pl->mirror) x = 1.f - x;
        lm[j][0] = (x - 0.5f) * pl->width;
        lm[j][1] = pl->height + (0.5f - y) * pl->width * pl->aspect;
        lm[j][2] = pl->depth + z * pl->width;
    }
    /* MediaPipe's 21 landmarks: 0 wrist, then thumb CMC MCP IP tip, then MCP PIP DIP tip of
     * index, middle, ring, pinky: plugin.h's layout from 1 on. The palm centre is the mean of
     * the wrist and the four finger MCPs. */
    out->t = t;
    for (int j = 1; j < OSC_MP_LANDMARKS; j++) memcpy(out->mm[j], lm[j], sizeof out->mm[j]);
    for (int i = 0; i < 3; i++)
        out->mm[FP_JOINT_PALM][i] = (lm[0][i] + lm[5][i] + lm[9][i] + lm[13][i] + lm[17][i]) / 5.f;
}

int fp__osc_mp_end_packet(osc_mp_hand *m, const osc_mp_place *pl, osc_mp_frame *out)
{
    if (!m->pending) return 0;
    m->pending = false;
    m->have &= 3u;
    frame_of(m, pl, m->t, out);
    m->have = 0;
    m->xy_only = true;
    return 1;
}

int fp__osc_mp_take(osc_mp_hand *m, const osc_mp_place *pl, int axis,
                    const float v[OSC_MP_LANDMARKS], int64_t t, bool in_bundle,
                    osc_mp_frame out[2], unsigned *incomplete)
{
    int n = 0;
    if (m->pending && axis != 2) n += fp__osc_mp_end_packet(m, pl, &out[n]); /* next frame's: no z */
    if (axis == 2 && !m->z_seen && m->have == 0 && m->xy_only) {
        /* the first z of a sender that sends z after x and y (plain messages): the frame just
         * emitted without depth is emitted again with it */
        memcpy(m->v[2], v, sizeof m->v[2]);
        m->z_seen = true;
        m->xy_only = false;
        m->have = 7;
        frame_of(m, pl, t, &out[n++]);
        m->have = 0;
        return n;
    }
    if (m->have & (1u << axis)) {
        if (m->z_seen && (m->have & 3u) == 3u && !(m->have & 4u)) {
            /* x and y came, then the next frame's before any z: the sender stopped sending z
             * (another sender, or the same without depth). The frame is emitted flat, and
             * from now on x and y make a frame. */
            m->z_seen = false;
            frame_of(m, pl, m->t, &out[n++]);
        } else {
            ++*incomplete; /* a new frame began before the last was complete */
        }
        m->have = 0;
    }
    memcpy(m->v[axis], v, sizeof m->v[axis]);
    m->t = t; /* the frame's time: its last part's */
    m->have |= 1u << axis;
    if (axis == 2) m->z_seen = true;
    unsigned need = m->z_seen ? 7u : 3u;
    m->xy_only = !m->z_seen;
    if ((m->have & need) == need) {
        if (!m->z_seen && in_bundle) { /* its z may follow in the bundle: at the datagram's end */
            m->pending = true;
            return n;
        }
        m->pending = false;
        frame_of(m, pl, t, &out[n++]);
        m->have = 0;
    }
    return n;
}

void fp__osc_mp_forget(osc_mp_hand *m)
{
    m->have = 0;
    m->z_seen = m->xy_only = m->pending = false;
}
