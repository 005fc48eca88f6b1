/* Step 5 of the frame: factor or reuse, solve, guard, evaluate; fingertip distances. */
#include "step_engine.h"

#include "fp_plugin_host.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* One tiny evaluation on 16 points of our own: the engine's first use in a process pays
 * for its code pages and the OpenMP runtime's first parallel region (measured about 0.05 ms
 * on the ICT face's first gesture); here, at creation, not in a frame. Errors are ignored
 * (the real runs report their own). */
static void warm_up(int threads)
{
    float p[16][3] = {{0}}, c[3] = {0.5f, 0, 0}, d[3] = {0.6f, 0, 0}, out[16][3];
    for (int i = 0; i < 16; i++) p[i][0] = (float)i / 16;
    csrbf_points *pts = NULL;
    csrbf_touch *t = NULL;
    csrbf_solver *s = NULL;
    csrbf_options o = {0};
    o.radius = 0.25;
    o.threads = threads;
    if (csrbf_points_create(16, &p[0][0], &pts) == CSRBF_OK && csrbf_touch_create(pts, &t) == CSRBF_OK &&
        csrbf_solver_create(&o, &s) >= 0 && csrbf_solver_set_start_points(s, 1, c) >= 0 &&
        csrbf_solver_set_end_points(s, d) >= 0)
        csrbf_evaluate_touched(s, pts, t, &out[0][0], 0u, NULL);
    csrbf_solver_destroy(&s);
    csrbf_touch_destroy(&t);
    csrbf_points_destroy(&pts);
}

int fp_engine_step_init(fp_engine_step *e, size_t n, const float *base, int threads)
{
    memset(e, 0, sizeof *e);
    e->threads = threads;
    if (csrbf_points_create(n, base, &e->points) != CSRBF_OK ||
        csrbf_points_index_nearest(e->points) != CSRBF_OK || /* the fingertips' distances */
        csrbf_touch_create(e->points, &e->touch) != CSRBF_OK) {
        fp_engine_step_free(e);
        return -ENOMEM;
    }
    warm_up(threads);
    return 0;
}

void fp_engine_step_free(fp_engine_step *e)
{
    free(e->vt_start);
    free(e->vt);
    free(e->scratch);
    e->vt_start = e->vt = NULL;
    e->scratch = NULL;
    csrbf_touch_destroy(&e->touch);
    csrbf_touch_destroy(&e->inter_touch);
    csrbf_solver_destroy(&e->solver);
    csrbf_points_destroy(&e->points);
    csrbf_points_destroy(&e->inter);
}

void fp_engine_step_set_base(fp_engine_step *e, const float *base)
{
    e->base_version++;
    csrbf_points_update(e->points, base);
    e->inter_stale = true; /* (a rig's channel changes the base every frame it moves) */
    csrbf_touch_reset(e->touch); /* the output buffer no longer matches the base */
    e->touched_valid = false;
    e->factored = false;
}

void fp_engine_step_commit_ranges(fp_engine_step *e, const float *base, const uint32_t *ranges, size_t nr)
{
    e->base_version++;
    /* the nearest index takes the commit at the next frame's distances (fp_engine_step_sync) */
    csrbf_points_update_ranges_later(e->points, base, ranges, nr);
    if (e->inter && !e->inter_stale) csrbf_points_update_ranges(e->inter, base, ranges, nr);
    csrbf_touch_commit(e->touch); /* the output buffer is the base now */
    e->touched_valid = true;
    e->factored = false;
}

void fp_engine_step_commit(fp_engine_step *e, const float *base)
{
    e->base_version++;
    const uint32_t *ranges;
    size_t nr = csrbf_touch_ranges(e->touch, &ranges);
    if (e->touched_valid) { /* only the blocks the last evaluation wrote differ */
        fp_engine_step_commit_ranges(e, base, ranges, nr);
        return;
    }
    csrbf_points_update(e->points, base);
    e->inter_stale = true;
    csrbf_touch_commit(e->touch);
    e->touched_valid = true;
    e->factored = false;
}

void fp_engine_step_output_is_base(fp_engine_step *e)
{
    csrbf_touch_commit(e->touch);
    e->touched_valid = true;
}

size_t fp_engine_step_touched(const fp_engine_step *e, const uint32_t **ranges)
{
    if (!e->touched_valid) {
        if (ranges) *ranges = NULL;
        return SIZE_MAX;
    }
    return csrbf_touch_ranges(e->touch, ranges);
}

void fp_engine_step_invalidate(fp_engine_step *e) { e->factored = false; }

static bool same_start(const fp_engine_step *e, const fp_control_set *cs)
{
    return e->factored && e->factored_count == cs->count &&
           !memcmp(e->factored_start, cs->start, cs->count * sizeof cs->start[0]);
}

static void keep_start(fp_engine_step *e, const fp_control_set *cs)
{
    memcpy(e->factored_start, cs->start, cs->count * sizeof cs->start[0]);
    e->factored_count = cs->count;
    e->factored = true;
}

static void take_guard(fp_engine_result *res, const csrbf_guard_stats *gs)
{
    res->bound = gs->bound_before;
    res->clusters = gs->clusters;
    res->clusters_limited = gs->clusters_limited;
    res->substeps = gs->substeps;
    res->reached = gs->reached;
}

/* The composed step (csrbf_guarded_step_touched) of cs from the base into deformed; *gs
 * its statistics. On return the solver holds the last sub-step's start points, so the next
 * frame factors anew (e->factored false). */
static int composed(fp_engine_step *e, const fp_control_set *cs, float *deformed, fp_engine_result *res,
                    csrbf_guard_stats *gs)
{
    int rc;
    csrbf_guard g = {FP_ENGINE_GUARD_MARGIN, FP_ENGINE_MAX_SUBSTEPS, 0u, FP_ENGINE_MAX_PAIRS};
    if (e->jacobian) {
        csrbf_guard gj = g;
        gj.eval_flags = CSRBF_EVAL_JACOBIAN;
        csrbf_guard_stats js;
        if (!e->scratch && !(e->scratch = malloc(csrbf_points_count(e->points) * 3 * sizeof(float))))
            return CSRBF_ERR_NOMEM;
        int64_t j0 = fp_now_ns();
        rc = csrbf_guarded_step(e->solver, e->points, cs->count, &cs->start[0][0], &cs->end[0][0], &gj,
                                e->scratch, &js);
        res->jacobian_ms += (double)(fp_now_ns() - j0) / 1e6;
        if (rc < 0) {
            e->factored = false;
            return rc;
        }
        res->min_det_j = js.eval.min_jacobian_det;
    }
    /* each map rewrites only the blocks in its supports; the touch then lists every block
     * any of them computed. inter: made at the first composed step, copied after the base
     * changed whole (both O(n), once) */
    int64_t ev0 = fp_now_ns();
    if (!e->inter) {
        if ((rc = csrbf_points_clone(e->points, &e->inter)) < 0 ||
            (rc = csrbf_touch_create(e->inter, &e->inter_touch)) < 0) {
            csrbf_points_destroy(&e->inter);
            return rc;
        }
        e->inter_stale = false;
    } else if (e->inter_stale) {
        if ((rc = csrbf_points_copy(e->inter, e->points)) < 0) return rc;
        e->inter_stale = false;
    }
    rc = csrbf_guarded_step_touched(e->solver, e->points, e->touch, e->inter, e->inter_touch, cs->count,
                                    &cs->start[0][0], &cs->end[0][0], &g, deformed, gs);
    res->eval_ms = (double)(fp_now_ns() - ev0) / 1e6; /* sub-steps' solves included */
    e->factored = false; /* the solver holds the last sub-step's start points */
    e->touched_valid = rc >= 0; /* (on error the touch was reset) */
    return rc;
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
    /* The shape always comes from the flag-free fast path (bit-identical with or without
     * the Jacobian); min det J, when asked, from a second evaluation into a scratch buffer. */
    csrbf_guard_stats gs;
    csrbf_eval_stats es = {0};
    res->min_det_j = NAN;
    bool fresh = !same_start(e, cs);
    /* one map from the start points (a gesture keeps its factor from frame to frame; a
     * one-shot step factors once), limited per cluster to the margin */
    if (fresh) {
        if ((rc = csrbf_solver_set_start_points(e->solver, cs->count, &cs->start[0][0])) < 0) {
            e->factored = false;
            return rc;
        }
        keep_start(e, cs);
        res->refactored = true;
    }
    if ((rc = csrbf_solver_set_end_points(e->solver, &cs->end[0][0])) < 0 ||
        (rc = csrbf_solver_limit_end_points(e->solver, FP_ENGINE_GUARD_MARGIN, &gs)) < 0) {
        e->factored = false;
        return rc;
    }
    if (gs.clusters_limited) {
        /* one map would stop short: composed injective sub-steps from the start points to
         * the end points along their straight paths, for an anchored gesture (re-made from
         * its base every frame, so the shape depends on this frame's control set alone) as
         * for an unanchored step */
        rc = composed(e, cs, deformed, res, &gs);
        if (rc < 0) return rc;
        es = gs.eval;
        goto done;
    }
    /* one map: only the blocks in a support now or at the last evaluation are written */
    int64_t ev0 = fp_now_ns();
    rc = csrbf_evaluate_touched(e->solver, e->points, e->touch, deformed, 0u, &es);
    res->eval_ms = (double)(fp_now_ns() - ev0) / 1e6;
    if (rc < 0) {
        csrbf_touch_reset(e->touch);
        return rc;
    }
    e->touched_valid = true;
    if (e->jacobian) {
        csrbf_eval_stats js;
        if (!e->scratch && !(e->scratch = malloc(csrbf_points_count(e->points) * 3 * sizeof(float))))
            return CSRBF_ERR_NOMEM;
        int64_t j0 = fp_now_ns();
        if ((rc = csrbf_evaluate(e->solver, e->points, e->scratch, CSRBF_EVAL_JACOBIAN, &js)) < 0) return rc;
        res->jacobian_ms += (double)(fp_now_ns() - j0) / 1e6;
        res->min_det_j = js.min_jacobian_det;
    }
done:
    take_guard(res, &gs);
    res->pairs = es.pairs;
    return 0;
}

int fp_engine_step_run(fp_engine_step *e, const fp_control_set *cs, float *deformed,
                       fp_engine_result *res, const fp_slog *log)
{
    memset(res, 0, sizeof *res);
    res->reached = 1.0;
    int64_t t0 = fp_now_ns();
    int rc = run(e, cs, deformed, res);
    res->update_ms = (double)(fp_now_ns() - t0) / 1e6 - res->jacobian_ms;
    if (rc < 0) {
        fp_slog_repeat_report(&e->errors, log, FP_LOG_ERROR, FP_SLOG_ENGINE, rc, "%s%s%s; the base shown",
                              csrbf_strerror(rc), e->solver ? ": " : "",
                              e->solver ? csrbf_solver_message(e->solver) : "");
        return rc;
    }
    fp_slog_repeat_flush(&e->errors, log);
    if (!e->g_frames) {
        e->g_reached = 1.0;
        e->g_substeps = 1;
        e->g_bound = 0.0;
    }
    e->g_frames++;
    e->g_limited += res->reached < 1.0;
    e->g_composed += res->substeps > 1;
    if (res->reached < e->g_reached) e->g_reached = res->reached;
    if (res->substeps > e->g_substeps) e->g_substeps = res->substeps;
    if (res->bound > e->g_bound) e->g_bound = res->bound;
    return 0;
}

void fp_engine_step_end_gesture(fp_engine_step *e, const fp_slog *log)
{
    if (e->g_limited)
        fp_slog_printf(log, FP_LOG_WARNING, FP_SLOG_ENGINE,
                       "fold-over guard limited the deformation to %.0f%% this gesture (%lu of %lu "
                       "frames limited, largest fold-over bound %.2f > %.2f)",
                       100.0 * e->g_reached, e->g_limited, e->g_frames, e->g_bound,
                       FP_ENGINE_GUARD_MARGIN);
    else if (e->g_composed)
        fp_slog_printf(log, FP_LOG_INFO, FP_SLOG_ENGINE,
                       "fold-over guard composed %lu of %lu steps from up to %d injective maps this "
                       "gesture (largest fold-over bound %.2f)",
                       e->g_composed, e->g_frames, e->g_substeps, e->g_bound);
    e->g_frames = e->g_limited = e->g_composed = 0;
}

const csrbf_solver *fp_engine_step_solver(const fp_engine_step *e) { return e->solver; }

void fp_engine_step_flush(fp_engine_step *e, const fp_slog *log)
{
    fp_slog_repeat_flush(&e->errors, log);
    fp_engine_step_end_gesture(e, log);
}

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

void fp_engine_step_sync(fp_engine_step *e) { csrbf_points_sync_nearest(e->points); }

void fp_engine_step_tip_distances(const fp_engine_step *e, const fp_hand_pose hands[FP_HANDS],
                                  float reach, float d[FP_HANDS][FP_FINGERS])
{
    float tips[FP_HANDS * FP_FINGERS][3], best[FP_HANDS * FP_FINGERS];
    size_t nt = 0;
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++) {
            d[h][f] = INFINITY;
            if (hands[h].present) memcpy(tips[nt++], hands[h].joints[FP_JOINT_TIP(f)], sizeof tips[0]);
        }
    if (!nt || csrbf_points_nearest(e->points, &tips[0][0], nt, reach, best, NULL) < 0) return;
    nt = 0;
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++)
            if (hands[h].present) d[h][f] = best[nt++];
}

int fp_engine_step_set_topology(fp_engine_step *e, const uint32_t *tris, size_t t)
{
    size_t n = csrbf_points_count(e->points);
    uint32_t *st = calloc(n + 1, sizeof *st), *vt = malloc((t ? 3 * t : 1) * sizeof *vt);
    if (!st || !vt) {
        free(st);
        free(vt);
        return -ENOMEM;
    }
    for (size_t i = 0; i < 3 * t; i++) st[tris[i] + 1]++;
    for (size_t v = 0; v < n; v++) st[v + 1] += st[v];
    for (size_t i = 0; i < t; i++)
        for (int k = 0; k < 3; k++) vt[st[tris[3 * i + k]]++] = (uint32_t)i;
    for (size_t v = n; v > 0; v--) st[v] = st[v - 1]; /* the fill moved each start to the next */
    st[0] = 0;
    free(e->vt_start);
    free(e->vt);
    e->vt_start = st;
    e->vt = vt;
    e->tris = tris;
    return 0;
}

int fp_engine_step_surface(const fp_engine_step *e, const float *base, const float (*points)[3],
                           size_t count, float max_distance, fp_surface_hit *out)
{
    if (!e || !base || (count && (!points || !out))) return -EINVAL;
    if (!e->vt_start) return -ENODATA;
    enum { CHUNK = 64 };
    for (size_t q0 = 0; q0 < count; q0 += CHUNK) {
        size_t m = count - q0 < CHUNK ? count - q0 : CHUNK;
        float d[CHUNK];
        uint32_t idx[CHUNK];
        int rc = csrbf_points_nearest(e->points, &points[q0][0], m, max_distance, d, idx);
        if (rc < 0) return rc;
        for (size_t i = 0; i < m; i++) {
            fp_surface_hit *h = &out[q0 + i];
            memset(h, 0, sizeof *h);
            h->vertex = idx[i];
            h->distance = d[i];
            if (idx[i] == UINT32_MAX) continue;
            const float *p = base + 3 * (size_t)idx[i];
            memcpy(h->position, p, sizeof h->position);
            /* fp_mesh_normals at one vertex: the sum of its triangles' cross products */
            float nx = 0, ny = 0, nz = 0;
            for (uint32_t k = e->vt_start[idx[i]]; k < e->vt_start[idx[i] + 1]; k++) {
                const uint32_t *t = e->tris + 3 * (size_t)e->vt[k];
                const float *a = base + 3 * (size_t)t[0], *b = base + 3 * (size_t)t[1],
                            *c = base + 3 * (size_t)t[2];
                float ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
                float vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
                nx += uy * vz - uz * vy;
                ny += uz * vx - ux * vz;
                nz += ux * vy - uy * vx;
            }
            float len = sqrtf(nx * nx + ny * ny + nz * nz);
            if (len > 0) {
                h->normal[0] = nx / len;
                h->normal[1] = ny / len;
                h->normal[2] = nz / len;
            }
        }
    }
    return 0;
}
