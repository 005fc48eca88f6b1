/*
 * map-onehand: one hand drives the whole face through the rig, as a puppeteer's hand drives
 * a hand puppet (issue 12; the paper's closing problem: "a hand-to-facial shape mapping that
 * requires only one hand", Sato, Savchenko, Ohbuchi, Cyberworlds 2004, sec. 4).
 *
 * Written against the public headers only (plugin.h ABI 1.1 and mapping_util.h), as a plugin
 * author outside the project would.
 *
 * Whose hand: the first performer's (fp_frame_input.hands, the inputs without performer=, or
 * the first named); further performers' hands (extra_hands, ABI 1.3) are ignored: one face,
 * one puppeteer's hand. Which of their hands: hand=auto (the default) takes the one that is
 * there, the right where both are, and keeps it while it stays: a left-handed performer, or
 * a tracker that sees only a left hand, drives the face without a key. When the driving hand
 * leaves and the other is there, that frame ends the gesture as the hand's leaving does
 * (hold=) and the next engages the other. hand=left|right takes only that one.
 *
 * What the hand does:
 *  - The thumb is the jaw: the gap between the thumb and the fingers (jaw=opening, the
 *    default: the distance of the thumb's tip from the index tip, as a hand puppet's mouth
 *    opens between the thumb and the fingers) or the thumb's flexion (jaw=flexion: the bend
 *    at its MCP plus its IP joint, from the joint positions; the curl) drives the rig channel
 *    jaw.open (issue 53). Calibrated against
 *    the neutral pose: the neutral value (0) at the neutral hand, rising by 1 (the channel's
 *    whole range) per flex_range degrees more flexion (or open_range mm more opening),
 *    clamped to the channel's range, monotonic in the thumb's motion; it eases in over the
 *    first ease x that range (0.3: the first 12 mm of opening; slope 0 at neutral, so a
 *    resting hand's tremor and a tracker's noise leave the shut jaw still), so it is fully
 *    open at (1 + ease/2) x the range: 46 mm of opening, 52 degrees of flexion (jaw_curve;
 *    ease=0: straight from neutral, fully open at the range).
 *  - The other fingertips drive control vectors whose start points are rig landmarks (the
 *    table below, key map= or targets=): each start point is the landmark's position as the
 *    host's rig view gives it this frame (on the base posed by the rig's channels), so start
 *    points stay bit-identical while the face's pose does not change and the host reuses its
 *    factorization (the anchored mode of sec. 2.3.1). When jaw.open changes, the host poses
 *    the base anew (and factors anew anyway); the landmarks the jaw carries (the mouth
 *    corners) then follow it, a frame behind the host's pose.
 *  - Relative to the performer's own neutral hand: the pose at engage is the zero.
 *    end = landmark + gain x (fingertip now - fingertip at neutral), the hand's motion
 *    taken in millimetres and expressed in the face's frame from the rig (the hand's right,
 *    up and toward-the-performer, read along the frame the host placed the hands in,
 *    fp_frame_input.face_*, become the face's left, up and forward: the face looks at
 *    the performer), then divided by the rig's mm_per_unit. gain is mm on the face per mm of
 *    hand: 1 (the default) moves a landmark as far as the fingertip moved, in physical units.
 *    The hand's millimetres: the host gives hands in mesh units after its workspace
 *    calibration, whose scale a mapping does not see; the plugin measures it on the hand at
 *    engage, as the length of the middle finger's proximal + middle phalanx in mesh units
 *    over finger_mm (70.9 mm, the mean adult of Buryanov & Kotiuk 2010), so a performer with
 *    a larger hand sets finger_mm to theirs.
 *  - Engage (the pose becomes the neutral): the engage intent (pedal, key E), or with auto=1
 *    (the default) the hand's first frame (still=0, the default: as a hand puppet, the
 *    puppet follows the hand from the moment it arrives, its pose then the zero), or, with
 *    still=S > 0, the hand held still (every fingertip and the palm within still_mm of where
 *    they were) for S seconds. Real hands are seldom that still: the four Leap recordings'
 *    hands never stay within 10 mm for 0.5 s, so that rule (the default until issue 51)
 *    never engaged on them. Commit (pedal, key C) folds the shape into the base and ends
 *    the gesture; cancel (key X) drops it. Both set jaw.open back to neutral; with auto=1
 *    and still=0 the next frame engages again with the hand's pose then as the zero (a
 *    cancel re-zeroes the hand, a commit keeps the shape and continues from it).
 *  - Rest: when the hand disappears (the input reports it gone), hold=0 drops the shape
 *    (a cancel); hold=1 keeps the last control set and jaw.open, and the next engage (still
 *    hand or request) continues from the held shape with the hand's new pose as the zero. An
 *    engage request while engaged with hold=1 does the same without the hand leaving (a
 *    clutch: keep the face, re-zero the hand).
 *  - Every control vector is clamped to clamp x R (0.45 R keeps one centre's warp
 *    injective, shared/docs/csrbf.md pitfall 4; the host's fold-over guard does the rest).
 *
 * Landmark tables (the right hand; for the left the names' _left and _right are swapped, so
 * that the finger nearer a corner on screen drives it):
 *   map=mouth (default): index -> mouth_corner_right, middle -> upper_lip,
 *                        ring -> mouth_corner_left, little -> brow_left + brow_right
 *   map=brows:           index -> brow_outer_right, middle -> brow_inner_right,
 *                        ring -> brow_inner_left, little -> brow_outer_left
 *   targets=I/M/R/L:     any landmarks of the rig for index/middle/ring/little, '+' between
 *                        two landmarks of one finger, '-' for none (not mirrored).
 *
 * Without a rig (fp_frame_input.rig NULL and no FP_HOST_EXT_RIG) the mapping logs "onehand
 * needs a rig (--rig)" at create (an error line) and every frame returns an inactive control
 * set (the host shows the base). A landmark the rig lacks is refused at create where the
 * host serves the rig then (FP_HOST_EXT_RIG), else left out of the control set.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <facepuppet/mapping_util.h>
#include <facepuppet/plugin.h>

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define OH_FINGERS 4                       /* index, middle, ring, little drive landmarks */
#define OH_PER_FINGER 2                    /* landmarks one finger may drive */
#define OH_SLOTS (OH_FINGERS * OH_PER_FINGER)
#define OH_NAME 32                         /* landmark names, with the NUL */
#define OH_FINGER_MM 70.9                  /* Buryanov & Kotiuk 2010: middle proximal 44.6 +
                                              middle 26.3 mm, the mean adult hand */

typedef enum { JAW_FLEXION = 0, JAW_OPENING = 1 } jaw_mode;

typedef struct onehand {
    fp_mapping mapping;
    const fp_host *host;
    const fp_host_rig *rig_ext;            /* FP_HOST_EXT_RIG, or NULL */

    /* keys */
    bool hand_auto;                        /* hand=auto: the hand that is there */
    int hand;                              /* FP_HAND_LEFT / FP_HAND_RIGHT: the driving hand */
    jaw_mode jaw;
    double flex_range;                     /* radians of flexion per full jaw travel */
    double open_range;                     /* mm of thumb-index opening per full jaw travel */
    double ease;                           /* share of the range the jaw eases in over */
    double gain;                           /* mm on the face per mm of hand */
    double finger_mm;                      /* the performer's middle proximal + middle, mm */
    double clamp;                          /* longest control vector, in R */
    bool automatic, hold;
    double still_s, still_mm;

    /* the landmark table */
    size_t count;                          /* control vectors */
    int finger[OH_SLOTS];                  /* 1..4 (FP_JOINT_TIP finger) */
    char landmark[OH_SLOTS][OH_NAME];      /* for the right hand */
    char landmark_left[OH_SLOTS][OH_NAME]; /* for the left: mirrored (map=), or as given */

    /* the gesture */
    bool engaged;                          /* the hand drives the face now */
    bool posed;                            /* a shape is shown (engaged, or held) */
    double scale;                          /* mesh units per mm of hand, measured at engage */
    float neutral[FP_HAND_JOINTS][3];      /* the hand at engage, mesh units */
    double neutral_jaw;                    /* the jaw measure at engage (rad or mm) */
    float held[OH_SLOTS][3];               /* displacement kept from before a rest, mesh units */
    float last[OH_SLOTS][3];               /* this gesture's last displacement (no clamp) */
    double held_jaw, last_jaw;             /* jaw.open above neutral: kept, and the last */
    bool jaw_set;                          /* the last jaw.open it set was a shape's (posed),
                                              or none was set since create or reset: the next
                                              unposed frame sets it to neutral */

    /* still detection (auto=1) */
    bool have_anchor;
    float anchor[FP_FINGERS + 1][3];       /* tips and palm when the stillness began */
    int64_t anchor_ns;
} onehand;

/* ---- small geometry -------------------------------------------------------------------- */

static double dist3(const float a[3], const float b[3])
{
    double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
    return sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

/* Angle between the segments a->b and b->c (0 for a straight line), radians. */
static double bend(const float a[3], const float b[3], const float c[3])
{
    double u[3], v[3], uv = 0, uu = 0, vv = 0;
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - b[k];
        uv += u[k] * v[k];
        uu += u[k] * u[k];
        vv += v[k] * v[k];
    }
    if (!(uu > 0) || !(vv > 0)) return 0;
    double c0 = uv / sqrt(uu * vv);
    return acos(c0 > 1 ? 1 : c0 < -1 ? -1 : c0);
}

/* Mesh units per mm of this hand: the middle finger's proximal + middle phalanx (rigid
 * bones, so the same whatever the flexion) over finger_mm. 0 where degenerate. */
static double hand_scale(const onehand *o, const fp_hand_pose *h)
{
    double len = dist3(h->joints[FP_JOINT(2, 0)], h->joints[FP_JOINT(2, 1)]) +
                 dist3(h->joints[FP_JOINT(2, 1)], h->joints[FP_JOINT(2, 2)]);
    return isfinite(len) && len > 0 ? len / o->finger_mm : 0;
}

/* The jaw measure of a hand: thumb flexion (radians: bend at the MCP plus the IP joint) or
 * thumb-to-index opening (mm of hand, with the given scale). */
static double jaw_measure(const onehand *o, const fp_hand_pose *h, double scale)
{
    const float(*j)[3] = h->joints;
    if (o->jaw == JAW_FLEXION)
        return bend(j[FP_JOINT(0, 0)], j[FP_JOINT(0, 1)], j[FP_JOINT(0, 2)]) +
               bend(j[FP_JOINT(0, 1)], j[FP_JOINT(0, 2)], j[FP_JOINT_TIP(0)]);
    return dist3(j[FP_JOINT_TIP(0)], j[FP_JOINT_TIP(1)]) / scale;
}

/* ---- the rig ----------------------------------------------------------------------------- */

/* This frame's rig: fp_frame_input.rig (ABI 1.1), else the host extension. */
static const fp_rig_view *frame_rig(const onehand *o, const fp_frame_input *in)
{
    if (FP_HAS_FIELD(in, fp_frame_input, rig) && in->rig) return in->rig;
    return o->rig_ext && o->rig_ext->get ? o->rig_ext->get(o->host) : NULL;
}

static const fp_rig_landmark *find_landmark(const fp_rig_view *rig, const char *name)
{
    for (size_t i = 0; i < rig->landmark_count; i++)
        if (rig->landmarks[i].name && !strcmp(rig->landmarks[i].name, name)) return &rig->landmarks[i];
    return NULL;
}

static const fp_rig_channel_info *find_channel(const fp_rig_view *rig, const char *name)
{
    for (size_t i = 0; i < rig->channel_count; i++)
        if (rig->channels[i].name && !strcmp(rig->channels[i].name, name)) return &rig->channels[i];
    return NULL;
}

/* Landmark i of the driving hand's table. */
static const char *landmark(const onehand *o, size_t i)
{
    return o->hand == FP_HAND_LEFT ? o->landmark_left[i] : o->landmark[i];
}

/* The first landmark of the tables that the rig lacks (the hands the keys allow), or NULL. */
static const char *missing_landmark(const onehand *o, const fp_rig_view *rig)
{
    for (size_t i = 0; i < o->count; i++) {
        if ((o->hand_auto || o->hand == FP_HAND_RIGHT) && !find_landmark(rig, o->landmark[i]))
            return o->landmark[i];
        if ((o->hand_auto || o->hand == FP_HAND_LEFT) && !find_landmark(rig, o->landmark_left[i]))
            return o->landmark_left[i];
    }
    return NULL;
}

/* ---- the gesture ------------------------------------------------------------------------ */

static void end_gesture(onehand *o)
{
    o->engaged = false;
    o->posed = false;
    o->held_jaw = o->last_jaw = 0;
    memset(o->held, 0, sizeof o->held);
    memset(o->last, 0, sizeof o->last);
    o->have_anchor = false;
}

/* The hand's pose becomes the zero. A held shape (hold=1) is kept as an offset. A hand
 * whose scale cannot be measured (degenerate, not finite) does not engage: false. */
static bool engage(onehand *o, const fp_hand_pose *h)
{
    double scale = hand_scale(o, h);
    double zero = jaw_measure(o, h, scale);
    if (!(scale > 0) || !isfinite(zero)) return false;
    if (o->posed) {                        /* continue from the shape shown */
        for (size_t i = 0; i < o->count; i++)
            for (int k = 0; k < 3; k++) o->held[i][k] += o->last[i][k];
        o->held_jaw += o->last_jaw;
    }
    memset(o->last, 0, sizeof o->last);
    o->last_jaw = 0;
    o->scale = scale;
    memcpy(o->neutral, h->joints, sizeof o->neutral);
    o->neutral_jaw = zero;
    o->engaged = true;
    o->posed = true;
    o->have_anchor = false;
    return true;
}

/* auto=1: true once the hand has been still for still_s (tips and palm within still_mm). */
static bool held_still(onehand *o, const fp_hand_pose *h, int64_t now_ns)
{
    double scale = hand_scale(o, h);
    float pts[FP_FINGERS + 1][3];
    for (int f = 0; f < FP_FINGERS; f++) memcpy(pts[f], h->joints[FP_JOINT_TIP(f)], sizeof pts[f]);
    memcpy(pts[FP_FINGERS], h->joints[FP_JOINT_PALM], sizeof pts[FP_FINGERS]);
    bool moved = !o->have_anchor || !(scale > 0);
    for (int p = 0; p <= FP_FINGERS && !moved; p++)
        if (!(dist3(pts[p], o->anchor[p]) / scale <= o->still_mm)) moved = true;
    if (moved) {
        memcpy(o->anchor, pts, sizeof pts);
        o->anchor_ns = now_ns;
        o->have_anchor = true;
    }
    return scale > 0 && (double)(now_ns - o->anchor_ns) >= o->still_s * 1e9;
}

/* jaw.open above neutral (in the channel's range: 1 opens it fully) for u, the thumb's
 * measure beyond neutral over its range: with ease e > 0 it eases in from the neutral over
 * |u| < e (u^2 / 2e, a slope of 0 at neutral: a resting hand's tremor and a tracker's noise
 * about the pose at engage leave the shut jaw still, where a straight line there opened it
 * by every twitch and the jaw's stop at shut made that twitch one-sided), then rises
 * straight at the same slope as without it (|u| - e/2: never faster than the thumb asks),
 * so the jaw is fully open at u = 1 + e/2. Odd in u (a held open jaw closes the same way).
 * e = 0: u itself. */
static double jaw_curve(double u, double e)
{
    double a = fabs(u);
    return copysign(a < e ? a * a / (2 * e) : a - e / 2, u);
}

/* Follow the hand: this gesture's displacement of every landmark and the jaw. A frame with
 * a non-finite joint keeps the last displacement. */
static void follow(onehand *o, const fp_hand_pose *h, const fp_rig_view *rig, const fp_frame_input *in,
                   double mm_per_unit)
{
    /* The host places the hands in front of the face's frame and turns them with it (a turned
     * copy of the rig's mesh: fp_frame_input.face_*), so the hand's right, up and toward the
     * performer are those axes in the mesh, not +x, +y, +z: read the motion along them first
     * (a Z-up copy of the ICT face had its landmarks pulled toward the viewer by a hand moving
     * up, 12.6 mm off the face's own at the end of HandSplay). A 1.0 host: +x, +y, +z. */
    static const float ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    bool axes = FP_HAS_FIELD(in, fp_frame_input, face_left);
    const float *hx = axes ? in->face_left : ex, *hy = axes ? in->face_up : ey, *hz = axes ? in->face_forward : ez;
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int c = 0; c < 3; c++)
            if (!isfinite(h->joints[j][c])) return;
    /* mesh units of hand -> mm of hand -> mm on the face -> mesh units of face */
    double k = o->gain / (o->scale * mm_per_unit);
    for (size_t i = 0; i < o->count; i++) {
        const float *now = h->joints[FP_JOINT_TIP(o->finger[i])];
        const float *zero = o->neutral[FP_JOINT_TIP(o->finger[i])];
        double m[3] = {now[0] - zero[0], now[1] - zero[1], now[2] - zero[2]};
        /* the hand's right, up, toward the performer -> the face's left, up, forward */
        double d[3] = {m[0] * hx[0] + m[1] * hx[1] + m[2] * hx[2], m[0] * hy[0] + m[1] * hy[1] + m[2] * hy[2],
                       m[0] * hz[0] + m[1] * hz[1] + m[2] * hz[2]};
        for (int c = 0; c < 3; c++)
            o->last[i][c] = (float)(k * (d[0] * rig->left[c] + d[1] * rig->up[c] + d[2] * rig->forward[c]));
    }
    double u = (jaw_measure(o, h, o->scale) - o->neutral_jaw) /
               (o->jaw == JAW_FLEXION ? o->flex_range : o->open_range);
    if (isfinite(u)) o->last_jaw = jaw_curve(u, o->ease);
}

/* Write the control set of the shape shown: start = the landmark where the rig view has it
 * now, end = start + held + last. Landmarks the rig lacks are left out (create refuses them
 * where the host serves the rig at create; a rig given only per frame may lack some). */
static int emit(const onehand *o, const fp_rig_view *rig, const fp_frame_input *in,
                fp_control_set *out)
{
    if (o->count > out->capacity) return -ENOSPC;
    size_t n = 0;
    for (size_t i = 0; i < o->count; i++) {
        const fp_rig_landmark *lm = find_landmark(rig, landmark(o, i));
        if (!lm) continue;
        memcpy(out->start[n], lm->position, sizeof out->start[n]);
        for (int k = 0; k < 3; k++) out->end[n][k] = lm->position[k] + (o->held[i][k] + o->last[i][k]);
        fp_clamp_vector(out->start[n], out->end[n], o->clamp * in->radius);
        n++;
    }
    out->count = n;
    out->active = true;
    return 0;
}

/* jaw.open for this frame: neutral + (max - neutral) x (held + last), clamped, while a shape
 * is shown; neutral once when it goes; then nothing, so that another driver of the channel
 * (an input's channel events: the audio input's jaw flap) has it while the hand rests. */
static void emit_jaw(onehand *o, const fp_rig_view *rig, fp_control_set *out, bool shown)
{
    if (!shown && !o->jaw_set) return;
    o->jaw_set = shown;
    if (!FP_HAS_FIELD(out, fp_control_set, channels) || !out->channels ||
        out->channel_capacity < 1)
        return;
    const fp_rig_channel_info *ch = find_channel(rig, "jaw.open");
    if (!ch) return;
    double v = ch->neutral;
    if (shown) v += (ch->max - ch->neutral) * (o->held_jaw + o->last_jaw);
    if (!(v >= ch->min)) v = ch->min;      /* NaN too */
    if (v > ch->max) v = ch->max;
    memset(&out->channels[0], 0, sizeof out->channels[0]);
    snprintf(out->channels[0].name, sizeof out->channels[0].name, "%s", "jaw.open");
    out->channels[0].value = (float)v;
    out->channel_count = 1;
}

/* [session-thread]: no allocation, I/O or locks. */
static int process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    onehand *o = self->plugin_data;
    out->active = false;
    out->intents = 0;
    out->count = 0;
    out->channel_count = 0;
    out->radius = in->radius;
    const fp_rig_view *rig = frame_rig(o, in);
    if (!rig) return 0;                    /* "onehand needs a rig (--rig)", logged at create */
    double mm_per_unit = rig->mm_per_unit;
    if (FP_HAS_FIELD(in, fp_frame_input, mm_per_unit) && in->mm_per_unit > 0)
        mm_per_unit = in->mm_per_unit;
    if (!(mm_per_unit > 0) || !isfinite(mm_per_unit)) return -ERANGE;
    /* hand=auto: the other hand takes over where the driving one is gone; a gesture of the
     * one gone ends first (this frame, as its leaving does), the other engages next frame */
    int other = o->hand == FP_HAND_LEFT ? FP_HAND_RIGHT : FP_HAND_LEFT;
    bool take_other = o->hand_auto && !in->hands[o->hand].present && in->hands[other].present;
    if (take_other && !o->engaged && !o->posed) {
        o->hand = other;
        o->have_anchor = false;
        take_other = false;
    }
    const fp_hand_pose *h = &in->hands[o->hand];
    uint32_t req = in->requested;

    if (req & FP_INTENT_CANCEL) {
        if (o->posed) out->intents = FP_INTENT_CANCEL;
        end_gesture(o);
        emit_jaw(o, rig, out, false);
        return 0;
    }
    if (!h->present) {
        o->have_anchor = false;
        if (o->engaged && !o->hold) {      /* the hand left: the shape goes with it */
            end_gesture(o);
            out->intents = FP_INTENT_CANCEL;
        }
        o->engaged = false;                /* hold=1: the shape stays until the next engage */
    } else {
        bool asked = req & FP_INTENT_ENGAGE;
        bool still = o->automatic && !o->engaged && held_still(o, h, in->time_ns);
        if (((asked && (!o->engaged || o->hold)) || still) && engage(o, h))
            out->intents |= FP_INTENT_ENGAGE;
        if (o->engaged) follow(o, h, rig, in, mm_per_unit);
    }
    if (o->posed) {
        int rc = emit(o, rig, in, out);
        if (rc) return rc;
    }
    emit_jaw(o, rig, out, o->posed);
    if ((req & FP_INTENT_COMMIT) && o->posed) {
        out->intents |= FP_INTENT_COMMIT;  /* this frame's shape becomes the base */
        end_gesture(o);
    }
    if (take_other) { /* (a held shape, hold=1, stays: the other hand continues from it) */
        o->hand = other;
        o->have_anchor = false;
    }
    return 0;
}

/* Back to the first frame's state (plugin.h: the same frames then give the same control
 * sets): the next frame sets jaw.open neutral once, as the first one did, so that after an
 * undo mid-gesture the jaw closes with the shape */
static void reset(fp_mapping *self)
{
    onehand *o = self->plugin_data;
    end_gesture(o);
    o->jaw_set = true;
}
static void destroy(fp_mapping *self) { free(self->plugin_data); }

/* ---- keys ----------------------------------------------------------------------------------- */

enum {
    KEY_HAND, KEY_JAW, KEY_FLEX_RANGE, KEY_OPEN_RANGE, KEY_EASE, KEY_MAP, KEY_TARGETS, KEY_GAIN,
    KEY_FINGER_MM, KEY_AUTO, KEY_STILL, KEY_STILL_MM, KEY_HOLD, KEY_CLAMP, KEY_COUNT
};
static const fp_param_info keys[KEY_COUNT + 1] = {
    {.name = "hand", .type = FP_PARAM_ENUM, .default_value = "auto", .choices = "auto|left|right",
     .description = "the hand that drives the face: auto, the one there (the right where both are)"},
    {.name = "jaw", .type = FP_PARAM_ENUM, .default_value = "opening", .choices = "flexion|opening",
     .description = "jaw.open from the thumb-to-index opening (a hand puppet's mouth), or from the thumb's "
                    "flexion (its curl)"},
    {.name = "flex_range", .type = FP_PARAM_FLOAT, .min = 5, .max = 180, .default_value = "45",
     .unit = "deg",
     .description = "thumb flexion beyond neutral per full jaw travel (jaw=flexion; fully open "
                    "at (1 + ease/2) x this)"},
    {.name = "open_range", .type = FP_PARAM_FLOAT, .min = 5, .max = 300, .default_value = "40",
     .unit = "mm",
     .description = "thumb-to-index opening beyond neutral per full jaw travel (jaw=opening; "
                    "fully open at (1 + ease/2) x this)"},
    {.name = "ease", .type = FP_PARAM_FLOAT, .min = 0, .max = 1, .default_value = "0.3",
     .description = "share of flex_range or open_range over which the jaw eases in from shut "
                    "(a resting hand's tremor leaves it still; fully open at (1 + ease/2) x the "
                    "range; 0: straight from the start)"},
    {.name = "map", .type = FP_PARAM_ENUM, .default_value = "mouth", .choices = "mouth|brows",
     .description = "landmark table: mouth (index, ring: mouth corners; middle: upper lip; little: brows) "
                    "or brows (the four brow points)"},
    {.name = "targets", .type = FP_PARAM_STRING, .default_value = "",
     .description = "landmarks for index/middle/ring/little, '+' between two, '-' for none; overrides map"},
    {.name = "gain", .type = FP_PARAM_FLOAT, .min = 0, .max = 20, .default_value = "1",
     .unit = "mm/mm",
     .description = "mm a landmark moves per mm its fingertip moves (1: the hand's motion, 1:1)"},
    {.name = "finger_mm", .type = FP_PARAM_FLOAT, .min = 30, .max = 150, .default_value = "70.9",
     .unit = "mm",
     .description = "the performer's middle finger, proximal + middle phalanx: the hand's scale"},
    {.name = "auto", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "1",
     .description = "engage by itself: at the hand's first frame (still=0), or once it is held still"},
    {.name = "still", .type = FP_PARAM_FLOAT, .min = 0, .max = 60, .default_value = "0",
     .unit = "s",
     .description = "how long the hand must be held still to engage (0: at first sight, that pose the zero)"},
    {.name = "still_mm", .type = FP_PARAM_FLOAT, .min = 0, .max = 200, .default_value = "10",
     .unit = "mm", .description = "a hand is still while its tips and palm stay this close"},
    {.name = "hold", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "0",
     .description = "keep the face posed while the hand rests (gone, or re-zeroed by an engage request)"},
    {.name = "clamp", .type = FP_PARAM_FLOAT, .min = 0, .max = 100, .default_value = "0.45",
     .unit = "R", .description = "longest control vector (0: no limit)"},
    {.name = NULL},
};

/* Landmark tables for the right hand: index, middle, ring, little; '+' joins two. */
static const char *const tables[][OH_FINGERS] = {
    {"mouth_corner_right", "upper_lip", "mouth_corner_left", "brow_left+brow_right"},
    {"brow_outer_right", "brow_inner_right", "brow_inner_left", "brow_outer_left"},
};

/* name with its "_left" / "_right" swapped (the left hand's mirror). */
static void mirror_name(const char *in, char *out, size_t len)
{
    size_t n = strlen(in);
    if (n >= 5 && !strcmp(in + n - 5, "_left"))
        snprintf(out, len, "%.*s_right", (int)(n - 5), in);
    else if (n >= 6 && !strcmp(in + n - 6, "_right"))
        snprintf(out, len, "%.*s_left", (int)(n - 6), in);
    else
        snprintf(out, len, "%s", in);
}

/* Parse "I/M/R/L" (each "-", "name" or "name+name") into the tables: the right hand's as
 * written, the left's mirrored when `mirror` (map=), else the same (targets=). */
static int parse_targets(onehand *o, const char *text, bool mirror, char *err, size_t errlen)
{
    o->count = 0;
    const char *p = text;
    for (int f = 0; f < OH_FINGERS; f++) {
        size_t len = strcspn(p, "/");
        if (!*p && f) {
            snprintf(err, errlen, "onehand: key 'targets': '%s' names %d fingers; expected 4 "
                     "(index/middle/ring/little, '-' for none)", text, f);
            return -EINVAL;
        }
        const char *q = p, *end = p + len;
        int n = 0;
        while (q < end) {
            size_t l = strcspn(q, "+/");
            if (l > (size_t)(end - q)) l = (size_t)(end - q);
            bool none = l == 1 && *q == '-';
            if (!none) {
                if (!l || l >= OH_NAME || n == OH_PER_FINGER) {
                    snprintf(err, errlen, "onehand: key 'targets': '%s': %s", text,
                             !l ? "an empty landmark name"
                                : l >= OH_NAME ? "a landmark name longer than 31 characters"
                                               : "more than 2 landmarks for one finger");
                    return -EINVAL;
                }
                char name[OH_NAME];
                snprintf(name, sizeof name, "%.*s", (int)l, q);
                o->finger[o->count] = f + 1;
                snprintf(o->landmark[o->count], OH_NAME, "%s", name);
                if (mirror) mirror_name(name, o->landmark_left[o->count], OH_NAME);
                else snprintf(o->landmark_left[o->count], OH_NAME, "%s", name);
                o->count++;
                n++;
            }
            q += l;
            if (q < end && *q == '+') q++;
        }
        p = end;
        if (*p == '/') p++;
        else if (f < OH_FINGERS - 1) {
            snprintf(err, errlen, "onehand: key 'targets': '%s' names %d fingers; expected 4 "
                     "(index/middle/ring/little, '-' for none)", text, f + 1);
            return -EINVAL;
        }
    }
    if (*p) {
        snprintf(err, errlen, "onehand: key 'targets': '%s' names more than 4 fingers", text);
        return -EINVAL;
    }
    return 0;
}

static int create(const fp_host *host, const fp_param *params, size_t nparams, fp_mapping **out,
                  char *err, size_t errlen)
{
    fpmu_value v[KEY_COUNT];
    int rc = fpmu_params_parse("onehand", keys, params, nparams, v, err, errlen);
    if (rc) return rc;
    onehand *o = calloc(1, sizeof *o);
    if (!o) return -ENOMEM;
    o->host = host;
    o->jaw_set = true; /* the first frame sets jaw.open neutral once (as after reset) */
    o->hand_auto = v[KEY_HAND].number == 0;
    o->hand = v[KEY_HAND].number == 1 ? FP_HAND_LEFT : FP_HAND_RIGHT; /* (auto: the right first) */
    o->jaw = v[KEY_JAW].number == 0 ? JAW_FLEXION : JAW_OPENING;
    o->flex_range = v[KEY_FLEX_RANGE].number * (3.14159265358979323846 / 180.0);
    o->open_range = v[KEY_OPEN_RANGE].number;
    o->ease = v[KEY_EASE].number;
    o->gain = v[KEY_GAIN].number;
    o->finger_mm = v[KEY_FINGER_MM].number;
    o->automatic = v[KEY_AUTO].number != 0;
    o->still_s = v[KEY_STILL].number;
    o->still_mm = v[KEY_STILL_MM].number;
    o->hold = v[KEY_HOLD].number != 0;
    o->clamp = v[KEY_CLAMP].number;
    const char *targets = v[KEY_TARGETS].text;
    if (targets && *targets) {
        rc = parse_targets(o, targets, false, err, errlen);
    } else {
        const char *const *t = tables[(int)v[KEY_MAP].number];
        char text[4 * 2 * OH_NAME];
        snprintf(text, sizeof text, "%s/%s/%s/%s", t[0], t[1], t[2], t[3]);
        rc = parse_targets(o, text, true, err, errlen);
    }
    if (rc) {
        free(o);
        return rc;
    }
    /* The rig: per frame (fp_frame_input.rig), else through the host extension. */
    if (host && host->get_extension)
        o->rig_ext = host->get_extension(host, FP_HOST_EXT_RIG);
    const fp_rig_view *rig = o->rig_ext && o->rig_ext->get ? o->rig_ext->get(host) : NULL;
    if (rig) {
        const char *miss = missing_landmark(o, rig);
        if (miss) {
            snprintf(err, errlen, "onehand: landmark '%s' is not in rig '%s' (key %s)", miss,
                     rig->name ? rig->name : "?", targets && *targets ? "targets" : "map");
            free(o);
            return -EINVAL;
        }
        if (!find_channel(rig, "jaw.open") && host->log)
            host->log(host, FP_LOG_WARNING, "onehand: the rig has no channel jaw.open; the thumb "
                                            "drives nothing");
    } else if (host && host->log) {
        host->log(host, FP_LOG_ERROR, "onehand needs a rig (--rig): the face's landmarks and "
                                      "jaw; without one it deforms nothing");
    }
    o->mapping.size = sizeof o->mapping;
    o->mapping.plugin_data = o;
    o->mapping.process = process;
    o->mapping.reset = reset;
    o->mapping.destroy = destroy;
    *out = &o->mapping;
    return 0;
}

static const fp_mapping_factory factory = {
    .size = sizeof(fp_mapping_factory),
    .name = "onehand",
    .description = "one hand drives the face through its rig: the thumb the jaw, the fingers "
                   "landmarks",
    .usage =
        "onehand[,hand=auto|left|right][,jaw=opening|flexion][,flex_range=DEG][,open_range=MM]\n"
        "       [,ease=F][,map=mouth|brows][,targets=I/M/R/L][,gain=F][,finger_mm=MM][,auto=0|1]\n"
        "       [,still=S][,still_mm=MM][,hold=0|1][,clamp=F]\n"
        "  Needs a rig (--rig). hand=auto (default): the hand that is there (the right where\n"
        "  both are) drives, and keeps driving while it stays. The thumb drives jaw.open: 0 at\n"
        "  the neutral hand, +1 per open_range (40) mm more gap between the thumb's and the\n"
        "  index tip (jaw=opening, the default: a hand puppet's mouth) or flex_range (45)\n"
        "  degrees more thumb flexion (jaw=flexion: the curl, bend at the thumb's MCP + IP),\n"
        "  easing in over the first ease (0.3) of that range: slope 0 at neutral, so a\n"
        "  resting hand's tremor leaves the shut jaw still; fully open at (1 + ease/2) x the\n"
        "  range, 46 mm (ease=0: straight from neutral, fully open at the range).\n"
        "  The fingertips move landmarks: end = landmark + gain x (tip now - tip at neutral),\n"
        "  the hand's right, up and toward-you as the face's left, up and forward; gain in mm\n"
        "  per mm (1: 1:1), the hand's mm from its middle finger (finger_mm, 70.9 mm), the\n"
        "  face's from the rig.\n"
        "  map=mouth: index -> mouth_corner_right, middle -> upper_lip, ring ->\n"
        "    mouth_corner_left, little -> brow_left + brow_right; map=brows: index ->\n"
        "    brow_outer_right, middle -> brow_inner_right, ring -> brow_inner_left, little ->\n"
        "    brow_outer_left (a left hand swaps _left and _right); targets=I/M/R/L names any\n"
        "    landmarks ('+' joins two, '-' none).\n"
        "  Engage (the neutral hand): auto=1 (default) at the hand's first frame, its pose the\n"
        "  zero (still=0, default), or once the hand is held still (within still_mm) for\n"
        "  still=S seconds; pedal or key E (auto=0: only these). Commit: pedal or key C;\n"
        "  cancel: key X; on the defaults the next frame engages again (X re-zeroes the hand).\n"
        "  hold=1 keeps the face posed while the hand is gone and continues from it at the\n"
        "  next engage (an engage request while engaged re-zeroes the hand); hold=0 drops it\n"
        "  when the hand goes. Control vectors are clamped to clamp x R.\n"
        "  With several performers (inputs' performer=NAME) the first performer's hand drives\n"
        "  the face; the others' hands are ignored.",
    .create = create,
    .params = keys,
};

static const void *get_factory(const char *id)
{
    return !strcmp(id, FP_MAPPING_FACTORY_ID) ? &factory : NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.map-onehand",
    .version = "1.0",
    .get_factory = get_factory,
};
