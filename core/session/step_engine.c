/* Step 5 of the frame: factor or reuse, solve, guard, evaluate; fingertip distances. */
#include "step_engine.h"

#include "fp_plugin_host.h"

#include <errno.h>
#include <math.h>
#include <string.h>

int fp_engine_step_init(fp_engine_step *e, size_t n, const float *base, int threads)
{
    memset(e, 0, sizeof *e);
    e->threads = threads;
    return csrbf_points_create(n, base, &e->points) == CSRBF_OK ? 0 : -ENOMEM;
}

void fp_engine_step_free(fp_engine_step *e)
{
    csrbf_solver_destroy(&e->solver);
    csrbf_points_destroy(&e->points);
}

void fp_engine_step_set_base(fp_engine_step *e, const float *base)
{
    csrbf_points_update(e->points, base);
    e->factored = false;
}

void fp_engine_step_invalidate(fp_engine_step *e) { e->factored = false; }

int fp_engine_step_guard(fp_engine_step *e, const fp_control_set *cs)
{
    (void)e;
    (void)cs;
    return 0;
}

static int run(fp_engine_step *e, const fp_control_set *cs, float *deformed, fp_engine_result *res)
{
    int rc;
    if (cs->count > FP_ENGINE_MAX_CONTROL) return CSRBF_ERR_INVALID;
    if (!e->solver || e->solver_radius != cs->radius) {
        csrbf_solver_destroy(&e->solver);
        csrbf_options o = {0};
        o.radius = cs->radius;
        o.threads = e->threads;
        if ((rc = csrbf_solver_create(&o, &e->solver)) < 0) return rc;
        e->solver_radius = cs->radius;
        e->factored = false;
    }
    if (!e->factored || e->factored_count != cs->count ||
        memcmp(e->factored_start, cs->start, cs->count * sizeof cs->start[0])) {
        if ((rc = csrbf_solver_set_start_points(e->solver, cs->count, &cs->start[0][0])) < 0) {
            e->factored = false;
            return rc;
        }
        memcpy(e->factored_start, cs->start, cs->count * sizeof cs->start[0]);
        e->factored_count = cs->count;
        e->factored = true;
        res->refactored = true;
    }
    if ((rc = csrbf_solver_set_end_points(e->solver, &cs->end[0][0])) < 0) return rc;
    if ((rc = fp_engine_step_guard(e, cs)) < 0) return rc;
    csrbf_eval_stats es = {0};
    if ((rc = csrbf_evaluate(e->solver, e->points, deformed, 0, &es)) < 0) return rc;
    res->pairs = es.pairs;
    return 0;
}

int fp_engine_step_run(fp_engine_step *e, const fp_control_set *cs, float *deformed,
                       fp_engine_result *res, const fp_slog *log)
{
    memset(res, 0, sizeof *res);
    int64_t t0 = fp_now_ns();
    int rc = run(e, cs, deformed, res);
    res->update_ms = (double)(fp_now_ns() - t0) / 1e6;
    if (rc < 0) {
        fp_slog_repeat_report(&e->errors, log, FP_LOG_ERROR, "engine", rc, "%s%s%s; keeping the last shape",
                              csrbf_strerror(rc), e->solver ? ": " : "",
                              e->solver ? csrbf_solver_message(e->solver) : "");
        return rc;
    }
    fp_slog_repeat_flush(&e->errors, log);
    return 0;
}

const csrbf_solver *fp_engine_step_solver(const fp_engine_step *e) { return e->solver; }

void fp_engine_step_flush(fp_engine_step *e, const fp_slog *log) { fp_slog_repeat_flush(&e->errors, log); }

void fp_engine_tip_distances(const float *base, size_t n, const fp_hand_pose hands[FP_HANDS],
                             float d[FP_HANDS][FP_FINGERS])
{
    float tips[FP_HANDS * FP_FINGERS][3];
    float best[FP_HANDS * FP_FINGERS];
    int nt = 0;
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++) {
            d[h][f] = INFINITY;
            if (!hands[h].present) continue;
            memcpy(tips[nt], hands[h].joints[FP_JOINT_TIP(f)], sizeof tips[nt]);
            best[nt++] = INFINITY;
        }
    if (!nt) return;
    for (int t = 0; t < nt; t++) {
        float m = INFINITY, tx = tips[t][0], ty = tips[t][1], tz = tips[t][2];
        for (size_t v = 0; v < n; v++) {
            float dx = base[3 * v] - tx, dy = base[3 * v + 1] - ty, dz = base[3 * v + 2] - tz;
            float q = dx * dx + dy * dy + dz * dz;
            m = q < m ? q : m;
        }
        best[t] = sqrtf(m);
    }
    nt = 0;
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++)
            if (hands[h].present) d[h][f] = best[nt++];
}
