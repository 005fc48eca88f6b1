/* How far the skin follows the fingertips: skin_reach.h. */
#include "skin_reach.h"

#include "step_engine.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdbool.h>
#include <string.h>

/* One vector's reach r (it asked `asked`, mesh units) into out[*count] and g (may be NULL). */
static void add(double r, double asked, float *out, size_t *count, fp_skin_reach_gesture *g)
{
    assert(*count < FP_FRAME_REACH_MAX);
    out[(*count)++] = (float)r;
    if (!g) return;
    if (!g->vectors || r < g->least) g->least = r;
    g->vectors++;
    g->below_90 += r < 0.9;
    g->sum_reach += r;
    if (asked > g->asked_max) g->asked_max = asked;
}

/* How far vector i of cs asked (mesh units). */
static double asked_of(const fp_control_set *cs, size_t i)
{
    double q2 = 0;
    for (int a = 0; a < 3; a++) {
        double q = (double)cs->end[i][a] - cs->start[i][a];
        q2 += q * q;
    }
    return sqrt(q2);
}

/* How far vertex v moved from ref to shown (mesh units). */
static double moved_of(const float *ref, const float *shown, uint32_t v)
{
    double m2 = 0;
    for (int a = 0; a < 3; a++) {
        double m = (double)shown[3 * (size_t)v + a] - ref[3 * (size_t)v + a];
        m2 += m * m;
    }
    return sqrt(m2);
}

void fp_skin_reach_frame(const csrbf_points *points, const float *ref, const float *shown,
                         const fp_control_set *cs, const fp_control_set *allowed, const float *mobility,
                         fp_frame_stats *st, fp_skin_reach_gesture *g, fp_skin_reach_gesture *g_allowed)
{
    st->reach_vectors = st->reach_allowed_vectors = st->reach_held = 0;
    st->reach_asked_max = 0;
    size_t n = cs->count < FP_ENGINE_MAX_CONTROL ? cs->count : FP_ENGINE_MAX_CONTROL;
    if (!n || !(cs->radius > 0)) return;
    /* the skin under each start point, once for both sets (a rig's clamp keeps the starts) */
    float dist[FP_ENGINE_MAX_CONTROL];
    uint32_t idx[FP_ENGINE_MAX_CONTROL];
    if (csrbf_points_nearest(points, &cs->start[0][0], n, (float)(FP_REACH_TOUCH * cs->radius), dist, idx) < 0)
        return;
    size_t nv = csrbf_points_count(points);
    for (size_t i = 0; i < n; i++) {
        if (idx[i] == UINT32_MAX || idx[i] >= nv) continue;
        double asked = asked_of(cs, i);
        if (!(asked >= FP_REACH_MIN_ASK * cs->radius)) continue;
        double moved = moved_of(ref, shown, idx[i]);
        add(moved / asked, asked, st->reach, &st->reach_vectors, g);
        if (asked > st->reach_asked_max) st->reach_asked_max = asked;
        if (!allowed || i >= allowed->count) continue;
        assert(!memcmp(allowed->start[i], cs->start[i], sizeof cs->start[i]));
        double asked_allowed = asked_of(allowed, i);
        double m = mobility ? (double)mobility[idx[i]] : 1.0; /* the blend's share there */
        if (!(asked_allowed >= FP_REACH_MIN_ASK * allowed->radius)) continue; /* all held back */
        if (!(m * asked_allowed >= FP_REACH_MIN_ASK * allowed->radius)) { /* the bone itself */
            st->reach_held++;
            if (g_allowed) g_allowed->held++;
            continue;
        }
        add(moved / asked_allowed / m, m * asked_allowed, st->reach_allowed, &st->reach_allowed_vectors,
            g_allowed);
    }
}

void fp_skin_reach_gesture_reset(fp_skin_reach_gesture *g) { memset(g, 0, sizeof *g); }

/* A played take's gesture with a rig: only the reach against what the rig allowed is known
 * (the take stores the clamped vectors). */
static void end_played(const fp_skin_reach_gesture *g, const fp_skin_reach_gesture *allowed, double mm_per_unit,
                       const fp_slog *log)
{
    bool mm = mm_per_unit > 0 && isfinite(mm_per_unit);
    if (!allowed->vectors) {
        if (allowed->held)
            fp_slog_printf(log, FP_LOG_INFO, FP_SLOG_ENGINE, "the fingertips grabbed the skull or the jaw this "
                           "gesture, which the rig keeps still (%zu vector%s)", allowed->held,
                           allowed->held == 1 ? "" : "s");
        return;
    }
    char held[128] = "";
    if (allowed->held)
        snprintf(held, sizeof held, "; %zu more grabbed the skull or the jaw, which the rig keeps still",
                 allowed->held);
    fp_slog_printf(log, FP_LOG_INFO, FP_SLOG_ENGINE,
                   "the skin followed %.0f%% of what the rig allowed this gesture (mean of %zu; least %.0f%%, "
                   "under 90%% in %zu; longest drag %.1f %s; the take holds the rig's vectors, not how far "
                   "the fingertips asked%s)",
                   100.0 * allowed->sum_reach / (double)allowed->vectors, allowed->vectors,
                   100.0 * allowed->least, allowed->below_90, g->asked_max * (mm ? mm_per_unit : 1.0),
                   mm ? "mm" : "mesh units", held);
}

void fp_skin_reach_gesture_end(fp_skin_reach_gesture *g, fp_skin_reach_gesture *allowed, double mm_per_unit,
                               const fp_slog *log)
{
    if (g->vectors && g->played && allowed) {
        end_played(g, allowed, mm_per_unit, log);
    } else if (g->vectors) {
        bool mm = mm_per_unit > 0 && isfinite(mm_per_unit);
        double mean = g->sum_reach / (double)g->vectors;
        double mean_allowed = allowed && allowed->vectors ? allowed->sum_reach / (double)allowed->vectors : mean;
        char rig[256] = "";
        size_t held = allowed ? allowed->held : 0;
        int k = 0;
        if (fabs(mean_allowed - mean) >= 0.005 && (!held || allowed->vectors))
            k = snprintf(rig, sizeof rig, "; %.0f%% of what the rig allowed: it holds back a push toward "
                         "the skull or the jaw", 100.0 * mean_allowed);
        if (held && k >= 0 && (size_t)k < sizeof rig) {
            if (held < g->vectors)
                snprintf(rig + k, sizeof rig - (size_t)k, "; %zu of them grabbed the skull or the jaw, "
                         "which the rig keeps still", held);
            else
                snprintf(rig + k, sizeof rig - (size_t)k, "; they grabbed the skull or the jaw, which "
                         "the rig keeps still");
        }
        fp_slog_printf(log, FP_LOG_INFO, FP_SLOG_ENGINE,
                       "the skin followed the fingertips %.0f%% this gesture (mean of %zu; least "
                       "%.0f%%, under 90%% in %zu; longest drag %.1f %s%s)",
                       100.0 * mean, g->vectors, 100.0 * g->least, g->below_90,
                       g->asked_max * (mm ? mm_per_unit : 1.0), mm ? "mm" : "mesh units", rig);
    }
    fp_skin_reach_gesture_reset(g);
    if (allowed) fp_skin_reach_gesture_reset(allowed);
}
