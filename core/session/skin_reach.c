/* How far the skin follows the fingertips: skin_reach.h. */
#include "skin_reach.h"

#include "step_engine.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdbool.h>
#include <string.h>

/* The reaches of cs's vectors that start on the skin into out[0 .. *count), the longest ask
 * into *asked_max, and into g (may be NULL). */
static void measure(const csrbf_points *points, const float *ref, const float *shown, const fp_control_set *cs,
                    float *out, size_t *count, double *asked_max, fp_skin_reach_gesture *g)
{
    *count = 0;
    *asked_max = 0;
    size_t n = cs->count < FP_ENGINE_MAX_CONTROL ? cs->count : FP_ENGINE_MAX_CONTROL;
    if (!n || !(cs->radius > 0)) return;
    float dist[FP_ENGINE_MAX_CONTROL];
    uint32_t idx[FP_ENGINE_MAX_CONTROL];
    if (csrbf_points_nearest(points, &cs->start[0][0], n, (float)(FP_REACH_TOUCH * cs->radius), dist, idx) < 0)
        return;
    size_t nv = csrbf_points_count(points);
    for (size_t i = 0; i < n; i++) {
        if (idx[i] == UINT32_MAX || idx[i] >= nv) continue;
        double asked = 0, moved = 0;
        for (int a = 0; a < 3; a++) {
            double q = (double)cs->end[i][a] - cs->start[i][a];
            double m = (double)shown[3 * (size_t)idx[i] + a] - ref[3 * (size_t)idx[i] + a];
            asked += q * q;
            moved += m * m;
        }
        asked = sqrt(asked);
        if (!(asked >= FP_REACH_MIN_ASK * cs->radius)) continue;
        double r = sqrt(moved) / asked;
        assert(*count < FP_FRAME_REACH_MAX);
        out[(*count)++] = (float)r;
        if (asked > *asked_max) *asked_max = asked;
        if (g) {
            if (!g->vectors || r < g->least) g->least = r;
            g->vectors++;
            g->below_90 += r < 0.9;
            g->sum_reach += r;
            if (asked > g->asked_max) g->asked_max = asked;
        }
    }
}

void fp_skin_reach_frame(const csrbf_points *points, const float *ref, const float *shown,
                         const fp_control_set *cs, fp_frame_stats *st, fp_skin_reach_gesture *g)
{
    measure(points, ref, shown, cs, st->reach, &st->reach_vectors, &st->reach_asked_max, g);
}

void fp_skin_reach_allowed(const csrbf_points *points, const float *ref, const float *shown,
                           const fp_control_set *cs, fp_frame_stats *st, fp_skin_reach_gesture *g)
{
    double longest;
    measure(points, ref, shown, cs, st->reach_allowed, &st->reach_allowed_vectors, &longest, g);
}

void fp_skin_reach_gesture_reset(fp_skin_reach_gesture *g) { memset(g, 0, sizeof *g); }

void fp_skin_reach_gesture_end(fp_skin_reach_gesture *g, fp_skin_reach_gesture *allowed, double mm_per_unit,
                               const fp_slog *log)
{
    if (g->vectors) {
        bool mm = mm_per_unit > 0 && isfinite(mm_per_unit);
        double mean = g->sum_reach / (double)g->vectors;
        double mean_allowed = allowed && allowed->vectors ? allowed->sum_reach / (double)allowed->vectors : mean;
        char rig[128] = "";
        if (fabs(mean_allowed - mean) >= 0.005)
            snprintf(rig, sizeof rig, "; %.0f%% of what the rig allowed: it holds back a push toward "
                     "the skull or the jaw", 100.0 * mean_allowed);
        fp_slog_printf(log, FP_LOG_INFO, FP_SLOG_ENGINE,
                       "the skin followed the fingertips %.0f%% this gesture (mean of %zu; least "
                       "%.0f%%, under 90%% in %zu; longest drag %.1f %s%s)",
                       100.0 * mean, g->vectors, 100.0 * g->least, g->below_90,
                       g->asked_max * (mm ? mm_per_unit : 1.0), mm ? "mm" : "mesh units", rig);
    }
    fp_skin_reach_gesture_reset(g);
    if (allowed) fp_skin_reach_gesture_reset(allowed);
}
