/* Hands that arrive: placement as the hands run, and the hint when they never reach the face
 * (step_arrive.h). */
#include "step_arrive.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define FP_ARRIVE_MAX_STEP_S 0.25 /* a gap between frames counts at most this much */
#define FP_ARRIVE_FAR_EVERY_NS 100000000 /* the unbounded nearest query: at most 10 a second */

int fp_arrive_step_init(fp_arrive_step *r, fp_arrive_placement how)
{
    memset(r, 0, sizeof *r);
    r->how = how;
    r->nearest = INFINITY;
    if (how == FP_ARRIVE_PLACED_AUTO) return fp_pose_auto_create(&r->place);
    return 0;
}

void fp_arrive_step_free(fp_arrive_step *r) { fp_pose_auto_destroy(&r->place); }

void fp_arrive_step_event(fp_arrive_step *r, const fp_event *ev)
{
    if (r->place) fp_pose_auto_take(r->place, ev);
}

void fp_arrive_step_place(fp_arrive_step *r, fp_pose_state *p, bool engaged, const fp_head *head,
                         const fp_slog *log)
{
    if (!r->place || !fp_pose_auto_refit(r->place, p, engaged, head->mm_per_unit, head->min, head->max))
        return;
    if (r->placed_said) return;
    r->placed_said = true;
    float lo[3], hi[3];
    fp_pose_auto_box(r->place, lo, hi);
    fp_slog_printf(log, FP_LOG_INFO, "session",
                   "%shands placed life-size in front of the face from their first frame (no input "
                   "states a workspace: x %.0f..%.0f, y %.0f..%.0f, z %.0f..%.0f mm so far), "
                   "refined as they move; --calibration FILE fixes the placement",
                   r->who, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
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
                   "(half the support radius: where the anchored mapping grabs); the nearest "
                   "stayed %s away. %s, or calibrate: `facepuppet calibrate --mesh FACE --input "
                   "SPEC --out cal.json`, then --calibration cal.json (docs/calibration.md)",
                   r->who, r->away_s < FP_ARRIVE_HINT_S - 1e-6 ? 1 : 0, r->away_s, r->near_mm, far,
                   placed_words(r->how));
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
        r->away_s = 0;
        r->nearest = INFINITY;
        r->reached = true;
        return;
    }
    if (!present || r->warned || r->reached) return;
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
