/* Hands that arrive: placement as the hands run, and the hint when they never reach the face
 * (step_arrive.h). */
#include "step_arrive.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FP_ARRIVE_MAX_STEP_S 0.25 /* a gap between frames counts at most this much */
#define FP_ARRIVE_FAR_EVERY_NS 100000000 /* the unbounded nearest query: at most 10 a second */

static void bring_in_live(fp_arrive_step *r, fp_pose_state *ps, const fp_calibration *before,
                          const fp_head *head, double radius, const fp_engine_step *e, const fp_slog *log);

int fp_arrive_step_init(fp_arrive_step *r, fp_arrive_placement how)
{
    memset(r, 0, sizeof *r);
    r->how = how;
    r->nearest = INFINITY;
    if (how != FP_ARRIVE_PLACED_AUTO) return 0;
    r->live_tips = malloc(FP_FINGERS * FP_ARRIVE_LIVE_SAMPLES * sizeof *r->live_tips);
    r->live_hand = malloc(FP_ARRIVE_LIVE_SAMPLES * sizeof *r->live_hand);
    r->live_q = malloc(FP_FINGERS * FP_ARRIVE_LIVE_SAMPLES * sizeof *r->live_q);
    r->live_d = malloc(FP_FINGERS * FP_ARRIVE_LIVE_SAMPLES * sizeof *r->live_d);
    if (!r->live_tips || !r->live_hand || !r->live_q || !r->live_d || fp_pose_auto_create(&r->place)) {
        fp_arrive_step_free(r);
        return -ENOMEM;
    }
    return 0;
}

void fp_arrive_step_free(fp_arrive_step *r)
{
    fp_pose_auto_destroy(&r->place);
    free(r->live_tips);
    free(r->live_hand);
    free(r->live_q);
    free(r->live_d);
    r->live_tips = NULL;
    r->live_hand = NULL;
    r->live_q = NULL;
    r->live_d = NULL;
}

void fp_arrive_step_event(fp_arrive_step *r, const fp_event *ev)
{
    if (r->place) fp_pose_auto_take(r->place, ev);
}

void fp_arrive_step_place(fp_arrive_step *r, fp_pose_state *p, bool engaged, const fp_head *head,
                         double radius, const fp_engine_step *e, const fp_slog *log)
{
    double hover = radius > 0 ? FP_ARRIVE_HOVER * radius : 0;
    if (!r->place) return;
    /* the first bring-in at once; held hands awaiting their approach: every frame */
    bool now = r->bring_on && (!r->bring_tried || r->awaiting) && !engaged;
    fp_calibration before = p->calib; /* (kept where a push in effect cannot be made again now) */
    if (!fp_pose_auto_refit(r->place, p, engaged, head->mm_per_unit, head->min, head->max, hover)) {
        if (now) bring_in_live(r, p, &before, head, radius, e, log);
        return;
    }
    if (r->bring_on && !fp_pose_auto_still(r->place)) bring_in_live(r, p, &before, head, radius, e, log);
    double mm = head->mm_per_unit > 0 ? head->mm_per_unit : 1.0;
    bool still = fp_pose_auto_still(r->place) && hover > 0;
    if (r->placed_said) {
        if (r->hovered && !still)
            fp_slog_printf(log, FP_LOG_INFO, "session",
                           "%shands moved: placed by their range now, no longer held %.0f mm out",
                           r->who, hover * mm);
        r->hovered = still;
        return;
    }
    r->placed_said = true;
    r->hovered = still;
    float lo[3], hi[3];
    fp_pose_auto_box(r->place, lo, hi);
    char held[160] = "";
    if (still)
        snprintf(held, sizeof held, "; until a fingertip moves %.0f mm they are held %.0f mm out, "
                 "hovering in front of the face", FP_POSE_STILL_MM, hover * mm);
    fp_slog_printf(log, FP_LOG_INFO, "session",
                   "%shands placed life-size in front of the face from their first frame (no input "
                   "states a workspace: x %.0f..%.0f, y %.0f..%.0f, z %.0f..%.0f mm so far), "
                   "refined as they move%s; --calibration FILE fixes the placement",
                   r->who, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], held);
}

/* ---- hands that never come near ---- */

typedef struct tips_in {
    float (*mm)[3];   /* FP_FINGERS fingertips a sample, device mm */
    int *hand;
    size_t stride;    /* every stride-th sample of each hand is kept */
    size_t seen, kept, cap;
    size_t seen_hand[FP_HANDS]; /* (counted per hand: two hands' samples come interleaved,
                                   and every 2nd of all kept one hand alone) */
} tips_in;

static void count_one(void *ctx, int hand, const float (*mm)[3])
{
    (void)hand, (void)mm;
    ((tips_in *)ctx)->seen++;
}

static void keep_one(void *ctx, int hand, const float (*mm)[3])
{
    tips_in *t = ctx;
    if (hand != FP_HAND_LEFT && hand != FP_HAND_RIGHT) return;
    if (t->seen_hand[hand]++ % t->stride || t->kept == t->cap) return;
    for (int f = 0; f < FP_FINGERS; f++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(mm[FP_JOINT_TIP(f)][k])) return; /* (a sample the replay would not make) */
    for (int f = 0; f < FP_FINGERS; f++) memcpy(t->mm[FP_FINGERS * t->kept + f], mm[FP_JOINT_TIP(f)], sizeof *t->mm);
    t->hand[t->kept++] = hand;
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Which fingertips act (acts[hand][finger]): those that move at least half as far as the one
 * that moves most (the largest side of the box between the 2nd and 98th percentiles of its
 * kept samples, per axis, device mm: one glitch sample moves it no more than it does the
 * workspace), so that a hand held still while two fingers pinch is brought in by the
 * pinching ones; every fingertip where none moves. Returns how far the one that moves most
 * moves (device mm). buf: room for the kept samples. */
static double acting(const tips_in *t, float *buf, bool acts[FP_HANDS][FP_FINGERS])
{
    double ext[FP_HANDS][FP_FINGERS], most = 0;
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++) {
            ext[h][f] = 0;
            for (int k = 0; k < 3; k++) {
                size_t m = 0;
                for (size_t i = 0; i < t->kept; i++)
                    if (t->hand[i] == h) buf[m++] = t->mm[FP_FINGERS * i + f][k];
                if (!m) continue;
                qsort(buf, m, sizeof *buf, cmp_float);
                double lo = buf[(size_t)(0.02 * (double)(m - 1) + 0.5)], hi = buf[(size_t)(0.98 * (double)(m - 1) + 0.5)];
                ext[h][f] = fmax(ext[h][f], hi - lo);
            }
            most = fmax(most, ext[h][f]);
        }
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++) acts[h][f] = !(ext[h][f] < 0.5 * most);
    return most;
}

/* The nearest the fingertips `acts` names come (all: NULL), pushed p toward the face (mesh
 * units), each query bounded by `bound` (farther: INFINITY); q: room for the kept tips, d:
 * their distances. */
static double nearest_at(const tips_in *t, const fp_calibration *c, double p, float bound,
                         const bool acts[FP_HANDS][FP_FINGERS], const fp_engine_step *e, float (*q)[3], float *d)
{
    fp_calibration at = *c;
    at.offset[2] -= p;
    size_t nq = 0;
    for (size_t i = 0; i < t->kept; i++)
        for (int f = 0; f < FP_FINGERS; f++)
            if (!acts || acts[t->hand[i]][f]) fp_pose_to_mesh(&at, t->hand[i], t->mm[FP_FINGERS * i + f], q[nq++]);
    if (!nq || csrbf_points_nearest(e->points, &q[0][0], nq, bound, d, NULL) < 0) return INFINITY;
    double m = INFINITY;
    for (size_t i = 0; i < nq; i++) m = fmin(m, d[i]);
    return m;
}

/* Every joint sample of the inputs that state a workspace and give their joints, to fn. */
static void each_sample(fp_input *const *ins, size_t n, void (*fn)(void *ctx, int hand, const float (*mm)[3]),
                        tips_in *t)
{
    for (size_t i = 0; i < n; i++) {
        fp_input *in = ins[i];
        if (!in || !in->get_extension || !in->get_extension(in, FP_EXT_WORKSPACE)) continue;
        const fp_input_recording_joints *x = in->get_extension(in, FP_EXT_RECORDING_JOINTS);
        if (x && x->each) x->each(in, fn, t);
    }
}

/* The bring-in on the kept samples t (step_arrive.h, fp_arrive_bring_in): *d0 the nearest
 * any fingertip comes at *c, *p the push toward the face (mesh units, along depth) that brings
 * the fingertips that act to FP_ARRIVE_BRING_TO x radius, *dp their nearest after it. q, d:
 * room for FP_FINGERS x t->kept points and floats. BRING_STILL: the hands never move
 * (FP_POSE_STILL_MM); BRING_NONE: near already, or no push within the head's depth brings
 * them near (*p 0); BRING_PUSH: *p > 0. */
enum { BRING_NONE, BRING_STILL, BRING_PUSH };
static int bring_push(const tips_in *t, const fp_calibration *c, double radius, const fp_head *head,
                      const fp_engine_step *e, float (*q)[3], float *d, double *d0, double *p, double *dp,
                      bool acts[FP_HANDS][FP_FINGERS])
{
    const double near = FP_ARRIVE_NEAR * radius, to = FP_ARRIVE_BRING_TO * radius;
    const double deepest = (double)head->max[2] - head->min[2];
    *p = 0;
    *d0 = *dp = INFINITY;
    double most = acting(t, d, acts); /* (d: room for a float a kept fingertip) */
    if (t->kept && most < FP_POSE_STILL_MM) return BRING_STILL;
    *d0 = nearest_at(t, c, 0, INFINITY, NULL, e, q, d);
    if (!(*d0 > near) || !isfinite(*d0)) return BRING_NONE; /* near already (or nothing to measure) */
    /* the march, on the fingertips that act: a push of dp - to moves none of them nearer
     * than to, so none is passed */
    double x = nearest_at(t, c, 0, INFINITY, acts, e, q, d), push = 0;
    for (int it = 0; it < 64 && x > to; it++) {
        push += fmax(x - to, 1e-3 * radius);
        if (!(push <= deepest)) return BRING_NONE; /* none comes near within the head's depth */
        x = nearest_at(t, c, push, (float)(x + (x - to) + radius), acts, e, q, d);
    }
    if (!(x <= near)) return BRING_NONE;
    *p = push;
    *dp = x;
    return BRING_PUSH;
}

int fp_arrive_bring_in(fp_calibration *c, fp_input *const *ins, size_t n, double radius, const fp_head *head,
                       const fp_engine_step *e, const char *who, const fp_slog *log)
{
    tips_in t = {.stride = 1};
    each_sample(ins, n, count_one, &t);
    if (!t.seen || !(radius > 0) || !e || !e->points) return 0;
    double mm = head->mm_per_unit > 0 ? head->mm_per_unit : 1.0;
    t.stride = (t.seen + FP_ARRIVE_BRING_SAMPLES - 1) / FP_ARRIVE_BRING_SAMPLES;
    t.cap = (t.seen + t.stride - 1) / t.stride + FP_HANDS; /* (each hand's count rounded up) */
    t.mm = malloc(FP_FINGERS * t.cap * sizeof *t.mm);
    t.hand = malloc(t.cap * sizeof *t.hand);
    float(*q)[3] = malloc(FP_FINGERS * t.cap * sizeof *q);
    float *d = malloc(FP_FINGERS * t.cap * sizeof *d);
    int rc = 0;
    if (!t.mm || !t.hand || !q || !d) {
        rc = -ENOMEM;
        goto out;
    }
    t.seen = 0;
    each_sample(ins, n, keep_one, &t);
    double d0, p, dp;
    bool acts[FP_HANDS][FP_FINGERS];
    switch (bring_push(&t, c, radius, head, e, q, d, &d0, &p, &dp, acts)) {
    case BRING_STILL: /* hands that never move hover, as live ones do */
        c->offset[2] += FP_ARRIVE_HOVER * radius;
        fp_slog_printf(log, FP_LOG_INFO, "session",
                       "%sthe recording's hands never move (every fingertip within %.0f mm): held "
                       "%.0f mm out, hovering in front of the face (docs/calibration.md)",
                       who ? who : "", FP_POSE_STILL_MM, FP_ARRIVE_HOVER * radius * mm);
        rc = 1;
        break;
    case BRING_PUSH:
        c->offset[2] -= p;
        fp_slog_printf(log, FP_LOG_INFO, "session",
                       "%sthe recording's fingertips never come within %.0f mm of the face where its "
                       "range places them (the nearest %.0f mm away): brought %.0f mm closer, so that "
                       "the fingertips that move come within %.0f mm (docs/calibration.md; "
                       "--calibration FILE fixes the placement)",
                       who ? who : "", FP_ARRIVE_NEAR * radius * mm, d0 * mm, p * mm, dp * mm);
        break;
    default:
        break;
    }
out:
    free(t.mm);
    free(t.hand);
    free(q);
    free(d);
    return rc;
}

/* each hand's newest sample's fingertips (device mm) */
typedef struct newest_tips {
    float mm[FP_HANDS][FP_FINGERS][3];
    bool have[FP_HANDS];
} newest_tips;

static void keep_newest(void *ctx, int hand, const float (*mm)[3])
{
    newest_tips *n = ctx;
    if (hand != FP_HAND_LEFT && hand != FP_HAND_RIGHT) return;
    for (int f = 0; f < FP_FINGERS; f++) memcpy(n->mm[hand][f], mm[FP_JOINT_TIP(f)], sizeof n->mm[hand][f]);
    n->have[hand] = true;
}

/* Where the hands as they are now (each hand's newest sample) would be at c: LAND_AWAY no
 * fingertip within FP_ARRIVE_NEAR x radius of the face (a push made now grabs nothing at once),
 * LAND_ACTING some fingertip that acts (acts: acting()) within it (a push made now grabs with
 * the fingertips that move, at their approach), LAND_STILL only fingertips that do not act.
 * *act_d: the nearest of the fingertips that act within it (+INFINITY: none). */
enum { LAND_AWAY, LAND_ACTING, LAND_STILL };
static int lands(const fp_arrive_step *r, const fp_calibration *c, const bool acts[FP_HANDS][FP_FINGERS],
                 double radius, const fp_engine_step *e, double *act_d)
{
    *act_d = INFINITY;
    newest_tips n = {0};
    fp_pose_auto_each(r->place, keep_newest, &n);
    float q[FP_HANDS * FP_FINGERS][3], d[FP_HANDS * FP_FINGERS];
    bool act[FP_HANDS * FP_FINGERS];
    size_t nq = 0;
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; n.have[h] && f < FP_FINGERS; f++) {
            act[nq] = acts[h][f];
            fp_pose_to_mesh(c, h, n.mm[h][f], q[nq++]);
        }
    float near = (float)(FP_ARRIVE_NEAR * radius);
    if (!nq || csrbf_points_nearest(e->points, &q[0][0], nq, near, d, NULL) < 0) return LAND_AWAY;
    int at = LAND_AWAY;
    for (size_t i = 0; i < nq; i++)
        if (d[i] <= near) {
            at = act[i] ? LAND_ACTING : at == LAND_ACTING ? at : LAND_STILL;
            if (act[i]) *act_d = fmin(*act_d, d[i]);
        }
    return at;
}

/* The same for a live input's hands at a refit (step_arrive.h): on the estimator's samples,
 * each hand's every stride-th, at most FP_ARRIVE_LIVE_SAMPLES in all, into r's buffers;
 * p->calib, the range's placement just made (`before`: the placement in effect before that
 * refit), moved by the push when its time has come (step_arrive.h, FP_ARRIVE_BRING_WAIT_S:
 * a push that would put the hands as they are now into a grab waits; meanwhile a push in
 * effect stays). The first push is said on log. */
static void bring_in_live(fp_arrive_step *r, fp_pose_state *ps, const fp_calibration *before,
                          const fp_head *head, double radius, const fp_engine_step *e, const fp_slog *log)
{
    bool had = r->pushed; /* (p->calib is the range's placement now, or as it was) */
    r->pushed = false;
    r->awaiting = false; /* (set again below while held hands await their approach) */
    r->bring_tried = true; /* (later tries come with the refits only) */
    size_t n = fp_pose_auto_samples(r->place);
    if (!n || !r->live_tips || !e || !e->points || !(radius > 0)) return;
    tips_in t = {.mm = r->live_tips, .hand = r->live_hand, .cap = FP_ARRIVE_LIVE_SAMPLES,
                 .stride = (n + FP_ARRIVE_LIVE_SAMPLES - FP_HANDS - 1) /
                           (FP_ARRIVE_LIVE_SAMPLES - FP_HANDS)};
    /* (each hand's count rounded up: at most n / stride + FP_HANDS kept, within the cap) */
    fp_pose_auto_each(r->place, keep_one, &t);
    double d0, p, dp, mm = head->mm_per_unit > 0 ? head->mm_per_unit : 1.0;
    bool acts[FP_HANDS][FP_FINGERS];
    if (bring_push(&t, &ps->calib, radius, head, e, r->live_q, r->live_d, &d0, &p, &dp, acts) != BRING_PUSH)
        return; /* (the range's placement stands) */
    fp_calibration c = ps->calib;
    c.offset[2] -= p;
    /* when (step_arrive.h): a push that grabs nothing at once, from FP_ARRIVE_BRING_AFTER_S
     * away; one that grabs with the fingertips that move, at their approach, from a wait later;
     * any from two waits later */
    double waited = r->moving_away_s - FP_ARRIVE_BRING_AFTER_S + 1e-6;
    bool held = fp_pose_auto_held(r->place); /* (held in place: at the acting ones' approach) */
    double act_d;
    int at = waited < 2 * FP_ARRIVE_BRING_WAIT_S ? lands(r, &c, acts, radius, e, &act_d) : LAND_AWAY;
    if (held && !had && at != LAND_STILL && waited < 2 * FP_ARRIVE_BRING_WAIT_S &&
        !(act_d <= dp + FP_ARRIVE_APPROACH * radius)) {
        r->awaiting = true; /* (tried again every frame: step_arrive.h) */
        return;
    }
    if (at == LAND_STILL || (at == LAND_ACTING && !held && waited < FP_ARRIVE_BRING_WAIT_S)) {
        if (had) { /* (the push in effect stays; again at the next refit) */
            fp_pose_recalibrate(ps, before);
            r->pushed = true;
        }
        return;
    }
    fp_pose_recalibrate(ps, &c);
    r->pushed = true;
    if (r->brought) return;
    r->brought = true;
    fp_slog_printf(log, FP_LOG_INFO, "session",
                   "%sthe hands' fingertips would not come within %.0f mm of the face where their "
                   "range places them (the nearest %.0f mm away so far): brought %.0f mm closer, so "
                   "that the fingertips that move come within %.0f mm, as a recording's are; "
                   "refined as they move (docs/calibration.md; --calibration FILE fixes the placement)",
                   r->who, FP_ARRIVE_NEAR * radius * mm, d0 * mm, p * mm, dp * mm);
}

/* What the hint says of the placement. */
static const char *placed_words(fp_arrive_placement how)
{
    switch (how) {
    case FP_ARRIVE_PLACED_WORKSPACE:
        return "The workspace the input states places them (a recording's range, osc's box=): "
               "state the volume your hands use";
    case FP_ARRIVE_PLACED_CALIBRATION:
        return "The calibration places them: make it again where you stand";
    default:
        return "They are placed from their own range (the front of where they went at the nose "
               "tip): reach toward the face";
    case FP_ARRIVE_PLACED_STILL:
        return "They have not moved, so they are held out, hovering in front of the face: reach "
               "toward it";
    }
}

/* The hint, once a stretch (r->warned): how long, how near, how the hands are placed. */
static void say(fp_arrive_step *r, const fp_slog *log)
{
    r->warned = true;
    r->hints++;
    char far[64];
    if (isfinite(r->nearest)) snprintf(far, sizeof far, "%.0f mm", r->nearest * r->mm);
    else snprintf(far, sizeof far, "(unknown)");
    fp_slog_printf(log, FP_LOG_WARNING, "session",
                   "%shands present for %.*f s, but no fingertip came within %.0f mm of the face "
                   "(half the face's default support radius: where the anchored mapping grabs); the nearest "
                   "stayed %s away. %s, or calibrate: `facepuppet calibrate --mesh FACE --input "
                   "SPEC --out cal.json`, then --calibration cal.json; a face that does not look "
                   "along +z with +y up: --up and --facing (docs/calibration.md)",
                   r->who, r->away_s < FP_ARRIVE_HINT_S - 1e-6 ? 1 : 0, r->away_s, r->near_mm, far,
                   placed_words(r->hovered ? FP_ARRIVE_PLACED_STILL : r->how));
}

void fp_arrive_step_check(fp_arrive_step *r, int64_t now_ns, const fp_hand_pose hands[FP_HANDS],
                         const float tip[FP_HANDS][FP_FINGERS], bool engaged, double radius,
                         double mm_per_unit, const fp_engine_step *e, const fp_slog *log)
{
    /* the time since the last frame counts when hands were there at both ends */
    double dt = r->have_last ? (double)(now_ns - r->last_ns) * 1e-9 : 0.0;
    if (!(dt > 0)) dt = 0; /* (time going backwards) */
    if (dt > FP_ARRIVE_MAX_STEP_S) dt = FP_ARRIVE_MAX_STEP_S;
    bool present = false;
    double nearest = INFINITY;
    for (int h = 0; h < FP_HANDS; h++) {
        if (!hands[h].present) continue;
        present = true;
        for (int f = 0; f < FP_FINGERS; f++)
            if (tip[h][f] < nearest) nearest = tip[h][f];
    }
    r->last_ns = now_ns;
    r->have_last = present;
    if (engaged || nearest <= FP_ARRIVE_NEAR * radius) { /* near: a new stretch begins */
        r->away_s = r->moving_away_s = 0;
        r->nearest = INFINITY;
        r->reached = true;
        return;
    }
    if (!present || r->reached) return;
    if (r->place && !r->hovered) { /* moving hands, placed by their range */
        /* (after the hint too: the bring-in's waits are timed by it, step_arrive.h; frozen at
         * the hint, a push waiting for 2 or 3 s of it never came) */
        r->moving_away_s += dt;
        /* (hands held in place, fingers acting: their range is where they are held, and the
         * replay's push is there from the first frame; no wait) */
        if (r->moving_away_s >= FP_ARRIVE_BRING_AFTER_S - 1e-6 || fp_pose_auto_held(r->place)) r->bring_on = true;
    }
    if (r->warned) return;
    r->away_s += dt;
    bool due = r->away_s >= FP_ARRIVE_HINT_S - 1e-6; /* (a sum of frame steps: 180 x 1/60) */
    /* beyond the tip distances' reach: how far, unbounded (a tree search; throttled, and
     * always on the hint's frame) */
    if (!isfinite(nearest) && e && (due || !r->far_asked || now_ns - r->far_ns >= FP_ARRIVE_FAR_EVERY_NS)) {
        r->far_asked = true;
        r->far_ns = now_ns;
        float d[FP_HANDS][FP_FINGERS];
        fp_engine_step_tip_distances(e, hands, INFINITY, d);
        for (int h = 0; h < FP_HANDS; h++)
            for (int f = 0; f < FP_FINGERS; f++)
                if (d[h][f] < nearest) nearest = d[h][f];
    }
    if (nearest < r->nearest) r->nearest = nearest;
    r->mm = mm_per_unit > 0 ? mm_per_unit : 1.0;
    r->near_mm = FP_ARRIVE_NEAR * radius * r->mm;
    if (due) say(r, log);
}

void fp_arrive_step_finish(fp_arrive_step *r, const fp_slog *log)
{
    if (!r->warned && !r->reached && r->away_s >= FP_ARRIVE_END_S - 1e-6) say(r, log);
}
