/* The contact guard's step (fp_contact_step): the moved vertices' first check, the local
 * scale-back (its ramp and carry, from contact_kd.c's tree over the blocking vertices), the
 * bisection; and the hold (fp_contact_hold). */
#include "contact_internal.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* P at the moved vertices := P + t (candidate - P), as fp_contact_guard's lerp; ramp (not
 * NULL): vertex i's share is t + (1 - t) ramp[i] (a local scale-back) */
static void track_lerp(struct track *k, double t, const double *ramp)
{
    const bool carry = ramp && k->carry_on;
    for (size_t i = 0; i < k->nmv; i++) {
        float *p = k->p + 3 * (size_t)k->mv[i];
        const float *a = k->pv + 3 * i, *b = k->cv + 3 * i;
        double w = ramp ? t + (1 - t) * ramp[i] : t;
        if (carry && w < 1) {
            /* a carried round: from P moved by the carry toward the candidate */
            const float *d = k->carry + 3 * i;
            for (int j = 0; j < 3; j++) {
                double a2 = (double)a[j] + d[j];
                p[j] = (float)(a2 + w * ((double)b[j] - a2));
            }
            continue;
        }
        for (int j = 0; j < 3; j++)
            p[j] = w >= 1 ? b[j] : w <= 0 || a[j] == b[j] ? a[j] : (float)((double)a[j] + w * ((double)b[j] - a[j]));
    }
}

/* a new clock (tick), and the moved vertices whose share of the motion is below 1 (ramp
 * NULL: all) stamped with it: the hierarchy's next checks look at their triangles only */
static void stamp_scaled(fp_contact *c, const double *ramp)
{
    struct track *k = c->tk;
    fpc_tick(c);
    for (size_t i = 0; i < k->nmv; i++)
        if (!ramp || ramp[i] < 1) k->vstamp[k->mv[i]] = k->tclock;
}

/* ramp[i] for the moved vertices: 0 within local_r of a vertex in off (positions in P, as
 * pv holds them), 1 beyond 2 local_r, smooth between. The nearest off vertex within 2r comes
 * from a k-d tree over them, the search bounded first by the previous moved vertex's nearest
 * (its neighbour in memory, mostly on the surface): the brute force's distance where it
 * matters. A blocked frame on the 1.7M face (114,000 moved vertices, 866 triangles turned
 * over) took 74 ms in the brute force; a grid of 2r cells helped nothing (every moved vertex
 * lay within 2r: 50 ms for 93,000 against 493 blocking vertices); the tree, 1-9 ms. 0 or
 * -ENOMEM. */
static int local_ramp(fp_contact *c, double r)
{
    struct track *k = c->tk;
    double r2 = r * r, r4 = 4 * r2;
    if (!k->noff) {
        for (size_t i = 0; i < k->nmv; i++) k->ramp[i] = 1;
        return 0;
    }
    if (fpc_kd_build(&k->kd, k->off, k->noff, k->p)) return -ENOMEM;
    uint32_t w = 0; /* the last nearest (a bound for the next search) */
    for (size_t i = 0; i < k->nmv; i++) {
        const float *pf = k->pv + 3 * i;
        double p[3] = {pf[0], pf[1], pf[2]};
        double best = fpc_kd_nearest2(&k->kd, p, r4, r2, &w);
        double u = best <= r2 ? 0 : best >= r4 ? 1 : (sqrt(best) - r) / r;
        k->ramp[i] = u * u * (3 - 2 * u);
    }
    return 0;
}

/* carry_build's share of the held vertices mv[x .. y) (ramp < 1): each one's carry from its
 * sums, on either thread (FP_JOB_CARRY); it writes only their carry */
void fpc_carry_range(fp_contact *c, uint32_t x, uint32_t y)
{
    struct track *k = c->tk;
    for (uint32_t i = x; i < y; i++) {
        if (k->ramp[i] >= 1) continue;
        const float *pf = k->pv + 3 * (size_t)i;
        double p[3] = {pf[0], pf[1], pf[2]}, acc[4];
        fpc_kd_sums(&k->kd, k->carry_cand, p, k->carry_r2, acc);
        /* (the weight is a sum of positive terms, and 0 with no blocking vertex within 2r) */
        if (acc[0] > 0)
            for (int a = 0; a < 3; a++) k->carry[3 * (size_t)i + a] = (float)(acc[1 + a] / acc[0]);
    }
}

/* vertices a carry task takes at least (FP_JOB_CARRY; more where that makes over 256 tasks,
 * as a job's list holds 1,024 at most and the caller runs those beyond at once) */
#define FP_CARRY_TASK 256

/* A compact blocking set's carry (carry_build, where the first check found flipped triangles
 * and no new pair): when the blocking vertices' box in P spans at most FP_CONTACT_CARRY_RIGID
 * r, every held vertex (ramp < 1) is carried by one translation, their mean motion
 * (candidate - P), so the held skin moves on as a rigid piece: each of its triangles keeps
 * the normal it has in P, which passed the check. Returns false (nothing written) for a set
 * wider than that, or none. */
static bool carry_rigid(fp_contact *c, double r, const float *cand)
{
    struct track *k = c->tk;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double m[3] = {0, 0, 0};
    for (size_t j = 0; j < k->noff; j++) {
        const float *q = k->p + 3 * (size_t)k->off[j], *cq = cand + 3 * (size_t)k->off[j];
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], q[a]);
            hi[a] = fmax(hi[a], q[a]);
            m[a] += (double)cq[a] - q[a];
        }
    }
    double d2 = 0;
    for (int a = 0; a < 3; a++) d2 += (hi[a] - lo[a]) * (hi[a] - lo[a]);
    if (!k->noff || !(d2 <= FP_CONTACT_CARRY_RIGID * FP_CONTACT_CARRY_RIGID * r * r)) return false;
    float d[3];
    for (int a = 0; a < 3; a++) d[a] = (float)(m[a] / (double)k->noff);
    for (size_t i = 0; i < k->nmv; i++)
        if (k->ramp[i] < 1) memcpy(k->carry + 3 * i, d, sizeof d);
    return true;
}

/* A carried round's translation (carry, per moved vertex): rigid, carry_rigid's one
 * translation; otherwise each vertex held back (ramp < 1) is carried by the mean motion
 * (candidate - P) of the blocking vertices within 2r of it, weighted by (1 - d^2 / 4r^2)^2,
 * so the held skin moves on with the drag as one piece (its triangles keep their shapes and
 * relative places) instead of staying behind; the ramp then blends it into the candidate.
 * The sums are exact to rounding (fpc_kd_sums: the k-d nodes wholly within 2r add their
 * moments), shared with the worker in tasks of at least FP_CARRY_TASK vertices where there
 * are two threads and more than one task. Each vertex walked the tree, and nodes under r / 4 across counted as their points' mean, until
 * ICT's confidence2-49fps (leapjs-playback) took up to 1.1 s a call: 24,000 held vertices,
 * each with about 10,000 blocking ones within 2r (docs/performance.md). Called after
 * local_ramp(c, r), with P in k->p. rigid: carry_rigid's one translation where the blocking
 * set is compact, else the weighted carry. 0 or -ENOMEM. */
static int carry_build(fp_contact *c, double r, const float *cand, bool rigid)
{
    struct track *k = c->tk;
    if (reserve((void **)&k->carry, &k->cap_carry, 3 * k->nmv, sizeof *k->carry)) return -ENOMEM;
    memset(k->carry, 0, 3 * k->nmv * sizeof *k->carry);
    if ((rigid && carry_rigid(c, r, cand)) || !k->noff) return 0;
    if (fpc_kd_moments(&k->kd, cand)) return -ENOMEM;
    k->carry_r2 = 4 * r * r;
    k->carry_cand = cand;
    pool *p = c->threads > 1 && k->nmv > FP_CARRY_TASK ? fpc_pool_get(c) : NULL;
    if (!p || fpc_job_open(c, p, FP_JOB_CARRY, cand, NULL, false)) {
        fpc_carry_range(c, 0, (uint32_t)k->nmv);
        return 0;
    }
    const size_t step = k->nmv / 256 > FP_CARRY_TASK ? k->nmv / 256 : FP_CARRY_TASK;
    for (size_t x = 0; x < k->nmv; x += step)
        fpc_add_task(c, p, (uint32_t)x, (uint32_t)(x + step < k->nmv ? x + step : k->nmv), 0);
    fpc_job_finish(c, p);
    return 0;
}

/* A shape's check inside a step (s: P at the moved vertices), by the mesh's broad phase: the
 * new pairs and (*flips) the newly flipped triangles; record: their vertices into off (a local scale-back's blocking
 * set), every one counted. Without record (the bisection, which asks only whether the shape
 * adds any) a flip decides it: the pairs are not looked for (0, *flips >= 1). */
static long check(fp_contact *c, const float *s, const float *ref, size_t *flips, bool record)
{
    return c->tk->tree ? fpc_tree_check(c, s, ref, flips, record, NULL) : fpc_track_check(c, s, ref, false, flips, record);
}

static int step(fp_contact *c, const float *ref, const float *cand, const uint32_t *ranges,
                size_t nranges, int iters, fp_contact_result *res);

int fp_contact_step(fp_contact *c, const float *ref, const float *cand, const uint32_t *ranges,
                    size_t nranges, int iters, fp_contact_result *res)
{
    memset(res, 0, sizeof *res);
    res->t = res->kept = 1;
    if (!c || !ref || !cand || (nranges != SIZE_MAX && nranges && !ranges)) return -EINVAL;
    if (!c->tk && fpc_track_build(c)) return -ENOMEM;
    int64_t w0 = c->tk->waited_ns;
    fpc_bg_join(c); /* (a wait for it is the step's) */
    if (c->tk->broken) return -ENOMEM;
    int rc = step(c, ref, cand, ranges, nranges, iters, res);
    res->worker_wait_ms = (double)(c->tk->waited_ns - w0) / 1e6;
    if (rc) c->tk->broken = true;
    else fpc_bg_post(c);
    return rc;
}

/* The hierarchy's first check of the candidate: its walk job also accepts the candidate ahead
 * (accept_range, *accepted), so that P's copy costs the threads' idle ends, not a serial
 * tail; pv holds the old P, given back when the candidate fails. The new pairs (*fl: the
 * newly flipped triangles), or -ENOMEM. */
static long first_check_tree(fp_contact *c, const float *ref, const float *cand, size_t *fl, bool *accepted,
                             fp_contact_result *res)
{
    struct track *k = c->tk;
    size_t cap = k->cap_pv;
    if (reserve((void **)&k->pv, &cap, 3 * k->nmv, sizeof *k->pv) ||
        reserve((void **)&k->cv, &k->cap_pv, 3 * k->nmv, sizeof *k->cv))
        return -ENOMEM;
    long found = fpc_tree_check(c, cand, ref, fl, false, accepted);
    if (found < 0) return -ENOMEM;
    res->moved_tris = k->nmt;
    if (*accepted && (found || *fl)) /* it fails: P back */
        for (size_t i = 0; i < k->nmv; i++)
            memcpy(k->p + 3 * (size_t)k->mv[i], k->pv + 3 * i, 3 * sizeof(float));
    return found;
}

/* The envelopes' first check of the candidate: envelopes that hold each moved triangle in
 * the candidate (and, before a bisection, in P too, so in every shape between them: the
 * scale-back's), renewed where they do not, then the check over their lists. The new pairs
 * (*fl: the newly flipped triangles), or -ENOMEM. */
static long first_check_envelopes(fp_contact *c, const float *ref, const float *cand, size_t *fl)
{
    struct track *k = c->tk;
    if (reserve((void **)&k->mbox, &k->cap_mbox, k->nmt, sizeof *k->mbox)) return -ENOMEM;
    for (size_t i = 0; i < k->nmt; i++) {
        /* the triangle's vertices, slot and envelope fetched ahead: dependent loads that
         * would otherwise miss the cache in turn */
        if (i + 16 < k->nmt) {
            __builtin_prefetch(c->tris + 3 * (size_t)k->mt[i + 16]);
            __builtin_prefetch(k->slot + k->mt[i + 16]);
        }
        if (i + 8 < k->nmt) {
            const uint32_t *w = c->tris + 3 * (size_t)k->mt[i + 8];
            __builtin_prefetch(cand + 3 * (size_t)w[0]);
            __builtin_prefetch(cand + 3 * (size_t)w[1]);
            __builtin_prefetch(cand + 3 * (size_t)w[2]);
            __builtin_prefetch(c->nrm[k->mt[i + 8]]);
            const uint32_t sl = k->slot[k->mt[i + 8]];
            if (sl != FP_TRACK_NONE) __builtin_prefetch(k->dyn[sl].env);
        }
        uint32_t a = k->mt[i];
        const uint32_t *va = c->tris + 3 * (size_t)a;
        tri_box(cand, va, k->mbox[i]);
        if ((k->slot[a] == FP_TRACK_NONE || !box_holds(k->dyn[k->slot[a]].env, k->mbox[i])) &&
            fpc_envelope(c, a, k->mbox[i]))
            return -ENOMEM;
        if (fpc_new_flip(c, fpc_flips(c, cand, va, a), ref, va, a)) (*fl)++;
    }
    *fl += (size_t)fpc_own_flips(c, cand, ref, false);
    if (fpc_renew_lists(c)) return -ENOMEM;
    return fpc_track_check(c, cand, ref, true, fl, false);
}

/* Before a scale-back: the envelopes hold P's boxes too (the bisection's shapes lie between
 * P and the candidate), and pv, cv hold the moved vertices in P and in the candidate. 0 or
 * -ENOMEM. */
static int scale_back_prepare(fp_contact *c, const float *cand)
{
    struct track *k = c->tk;
    for (size_t i = 0; !k->tree && i < k->nmt; i++) {
        uint32_t a = k->mt[i];
        float hull[6];
        tri_box(k->p, c->tris + 3 * (size_t)a, hull);
        for (int j = 0; j < 3; j++) {
            hull[j] = min_f(hull[j], k->mbox[i][j]);
            hull[3 + j] = max_f(hull[3 + j], k->mbox[i][3 + j]);
        }
        if (!box_holds(k->dyn[k->slot[a]].env, hull) && fpc_envelope(c, a, hull)) return -ENOMEM;
    }
    if (!k->tree && fpc_renew_lists(c)) return -ENOMEM;
    size_t cap = k->cap_pv;
    if (reserve((void **)&k->pv, &cap, 3 * k->nmv, sizeof *k->pv) ||
        reserve((void **)&k->cv, &k->cap_pv, 3 * k->nmv, sizeof *k->cv))
        return -ENOMEM;
    float *pv = k->pv, *cv = k->cv;
    for (size_t i = 0; i < k->nmv; i++) {
        memcpy(pv + 3 * i, k->p + 3 * (size_t)k->mv[i], 3 * sizeof(float));
        memcpy(cv + 3 * i, cand + 3 * (size_t)k->mv[i], 3 * sizeof(float));
    }
    return 0;
}

/* A local scale-back (fp_contact_set_local): the motion near the blocking triangles is
 * scaled, the rest kept (ramp); the shape with none of the near motion must pass (else the
 * triangles it blocks join, FP_CONTACT_LOCAL_ROUNDS times). The ramp starts narrow
 * (local_r / FP_CONTACT_LOCAL_NARROW) and doubles each round up to local_r, so a blocked
 * pair holds back as little of the skin around it as passes the check: the skin a finger
 * drags past a crease keeps following it. *ramp: the ramp of the round that passed, or
 * NULL (the global scale-back then). found: the first check's new pairs; *fl
 * its flips, then each check's. 0 or -ENOMEM. */
static int local_scale_back(fp_contact *c, const float *ref, const float *cand, long found, size_t *fl,
                            fp_contact_result *res, const double **ramp)
{
    struct track *k = c->tk;
    if (reserve((void **)&k->ramp, &k->cap_ramp, k->nmv, sizeof *k->ramp)) return -ENOMEM;
    for (size_t i = 0; i < k->noff; i++) k->off_mark[k->off[i]] = 0;
    k->noff = 0;
    /* the blocking triangles: on the hierarchy, the first check's (the lanes' rec: its
     * update's flips and its walk's new pairs, rec_pairs) and the own flipped ones; on the
     * envelopes a check that records them */
    long m = k->tree ? (fpc_rec_merge(c) || fpc_own_flips(c, cand, ref, true) < 0 ? -ENOMEM : found)
                     : check(c, cand, ref, fl, true);
    if (m < 0) return -ENOMEM;
    double r = c->local_r / FP_CONTACT_LOCAL_NARROW;
    /* carried rounds: on the hierarchy only (the envelopes hold the segment P -> C, which a
     * carried vertex leaves), and where a check is cheap enough to try one more */
    const bool carry = c->carry && k->tree && k->nmt <= FP_CONTACT_CARRY_MAX_TRIS;
    for (int round = 0; m > 0 || *fl; round++, r = fmin(2 * r, c->local_r)) {
        if (m < 0) return -ENOMEM;
        if (round == FP_CONTACT_LOCAL_ROUNDS) break;
        assert(!k->carry_on); /* (set only by a carried round that passed, which ends them) */
        track_lerp(k, 0, NULL); /* P, where the distances are taken */
        if (local_ramp(c, r)) return -ENOMEM;
        if (carry && round < FP_CONTACT_CARRY_ROUNDS) {
            /* carried first: the held skin moved on as one piece; held back for flips alone
             * (no new pair), a compact blocking set by one translation (carry_rigid) */
            if (carry_build(c, r, cand, found == 0)) return -ENOMEM;
            k->carry_on = true;
            track_lerp(k, 0, k->ramp);
            stamp_scaled(c, k->ramp);
            size_t cfl = 0;
            long cm = check(c, k->p, ref, &cfl, false);
            res->checks++;
            if (cm < 0) return -ENOMEM;
            if (!cm && !cfl) {
                *fl = 0;
                *ramp = k->ramp;
                res->local_r = r;
                res->carried = true;
                break;
            }
            k->carry_on = false;
        }
        track_lerp(k, 0, k->ramp);
        if (k->tree) {
            /* a vertex kept whole (share 1) is where the candidate has it, and a
             * triangle of such vertices is not a blocking one, so a pair of them, or
             * with unmoved ones, added nothing in the candidate: the check looks only
             * at the triangles of the others (a new stamp; the rest hold the
             * candidate's boxes and normals from its check) */
            stamp_scaled(c, k->ramp);
        }
        m = check(c, k->p, ref, fl, true);
        res->checks++;
        if (!m && !*fl) {
            *ramp = k->ramp;
            res->local_r = r;
        }
    }
    /* carry_on stays set when a carried round passed: the bisection's shapes carry too */
    assert(!k->carry_on || (*ramp && k->tree));
    track_lerp(k, 0, NULL); /* (no ramp: P itself) */
    return 0;
}

/* The shape at t (track_lerp with ramp) checked: 1 it passes, 0 it fails (*fl its flips),
 * -ENOMEM. *held: t when the check updated the hierarchy's boxes and normals (not a probe). */
static int try_t(fp_contact *c, const float *ref, double t, const double *ramp, size_t *fl,
                 fp_contact_result *res, double *held)
{
    struct track *k = c->tk;
    track_lerp(k, t, ramp);
    size_t u0 = k->updates;
    long m = check(c, k->p, ref, fl, false);
    res->checks++;
    if (m < 0) return -ENOMEM;
    if (k->updates != u0) *held = t;
    return !m && !*fl;
}

/* The candidate added pairs or flips (found, *fl): P := P + t (cand - P) at the moved
 * vertices, t on the grid of 2^iters steps whose shape passed (halvings, after t_hint's
 * doublings), after a local scale-back
 * where one passes (its ramp then shapes each vertex's share). *fl: the last check's flips.
 * 0 or -ENOMEM. */
static int scale_back(fp_contact *c, const float *ref, const float *cand, int iters, long found, size_t *fl,
                      fp_contact_result *res)
{
    struct track *k = c->tk;
    if (scale_back_prepare(c, cand)) return -ENOMEM;
    const double *ramp = NULL;
    k->carry_on = false;
    if (c->local_r > 0 && iters > 0 && local_scale_back(c, ref, cand, found, fl, res, &ramp)) return -ENOMEM;
    /* with a ramp the stamps stay the last round's: a vertex kept whole (share 1) is in
     * place for every t, and its triangles as in the candidate; without one (the rounds
     * failed) every moved vertex depends on t */
    if (!ramp && k->tree && c->local_r > 0) stamp_scaled(c, NULL);
    /* t on the grid j / 2^iters: jlo's shape passes (0: the ramp's or P), jhi's fails (the
     * candidate's). After a step that kept little (t_hint), a step of gallop_min moved
     * triangles or more tries its j first and doubles it while it passes: skin a blocked
     * finger holds keeps about the same t frame after frame (1.7M face: 65 of 99 blocked
     * frames after a blocked one within 1/64 of the last), which then takes 2 checks instead
     * of iters. Then halvings, as without a hint. Not on smaller steps: there a check is
     * cheap, and the halvings may find a larger t (on the ICT face's grab, with its rig, the
     * gallop kept 77% of a frame where they keep 86%). */
    const int steps = 1 << (iters < 0 ? 0 : iters > 24 ? 24 : iters);
    int jlo = 0, jhi = steps;
    double held = ramp ? 0 : NAN; /* the t whose shape the hierarchy holds (the ramp's: 0) */
    const uint32_t hint = k->nmt >= c->gallop_min ? k->t_hint : 0;
    for (int j = hint > 1 ? (int)hint - 1 : 1; hint && j < jhi; j *= 2) {
        int r = try_t(c, ref, (double)j / steps, ramp, fl, res, &held);
        if (r < 0) return -ENOMEM;
        if (!r) {
            jhi = j;
            break;
        }
        jlo = j;
    }
    while (jhi - jlo > 1) {
        int mid = (jlo + jhi) / 2;
        int r = try_t(c, ref, (double)mid / steps, ramp, fl, res, &held);
        if (r < 0) return -ENOMEM;
        if (r) jlo = mid;
        else jhi = mid;
    }
    double lo = (double)jlo / steps;
    k->t_hint = jlo <= steps / FP_CONTACT_GALLOP ? (uint32_t)jlo + 1 : 0;
    track_lerp(k, lo, ramp);
    res->t = lo;
    res->local = ramp != NULL;
    /* the share of the motion kept: how far the moved vertices went, over how far the
     * candidate took them (pv: P's positions, cv: the candidate's; k->p: the shape kept) */
    double asked = 0, went = 0;
    for (size_t i = 0; i < k->nmv; i++) {
        const float *q = k->p + 3 * (size_t)k->mv[i], *a = k->pv + 3 * i, *b = k->cv + 3 * i;
        double da = 0, dw = 0;
        for (int j = 0; j < 3; j++) {
            da += ((double)b[j] - a[j]) * ((double)b[j] - a[j]);
            dw += ((double)q[j] - a[j]) * ((double)q[j] - a[j]);
        }
        asked += sqrt(da);
        went += sqrt(dw);
    }
    res->kept = asked > 0 ? fmin(1.0, went / asked) : lo; /* (t itself where t is uniform,
                                                             but for the floats' rounding) */
    /* the hierarchy: the normals and boxes of the shape kept, unless the last check that
     * updated them had it */
    if (k->tree && !(held == lo) && fpc_tree_update(c, k->p, NULL, false) < 0) return -ENOMEM;
    return 0;
}

/* D_P: where P may differ from the reference. P changed only at the moved vertices, so
 * only they may join it; one that went back to the reference stays in it (a superset is
 * enough for (2); fp_contact_reference empties it), so the step costs its motion, not
 * the whole gesture's. from_lanes: the walk job's accept_range found them */
static void dp_update(fp_contact *c, const float *ref, bool from_lanes)
{
    struct track *k = c->tk;
    if (from_lanes) {
        for (int j = 0; j < FP_CONTACT_MAX_THREADS; j++)
            for (size_t i = 0; i < k->lane[j].nmv; i++) {
                k->in_dp[k->lane[j].mv[i]] = 1;
                k->dp[k->ndp++] = k->lane[j].mv[i];
            }
        return;
    }
    for (size_t i = 0; i < k->nmv; i++) {
        uint32_t v = k->mv[i];
        if (!k->in_dp[v] && vert_differs(k->p, ref, v)) {
            k->in_dp[v] = 1;
            k->dp[k->ndp++] = v;
        }
    }
}

static int step(fp_contact *c, const float *ref, const float *cand, const uint32_t *ranges,
                size_t nranges, int iters, fp_contact_result *res)
{
    struct track *k = c->tk;
    fpc_tick(c);
    k->nmv = k->nmt = k->nmo = k->nmq = k->nprobe = k->npair_probe = 0;
    size_t renewed0 = k->renewed;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++)
        k->lane[i].certified = k->lane[i].tested = k->lane[i].node_pairs = k->lane[i].leaf_pairs = 0;
    k->shared = 0;

    /* the moved vertices: where cand differs from P */
    if (k->tree ? fpc_collect_mark(c, cand, ranges, nranges) : fpc_collect_moved(c, cand, ranges, nranges))
        return -ENOMEM;
    res->moved_verts = k->nmv;
    if (!k->nmv) return 0; /* nothing moved: P is the candidate */
    for (size_t i = 0; !k->tree && i < k->nmv; i++) {
        /* the vertex's triangle range, its triangles and their stamps fetched ahead: three
         * dependent loads that would otherwise miss the cache in turn (the marking of the
         * ICT replay's 480 moved vertices: 15-21 us against 19-28) */
        if (i + 16 < k->nmv) __builtin_prefetch(k->vt_start + k->mv[i + 16]);
        if (i + 8 < k->nmv) __builtin_prefetch(k->vt + k->vt_start[k->mv[i + 8]]);
        if (i + 4 < k->nmv)
            for (uint32_t j = k->vt_start[k->mv[i + 4]]; j < k->vt_start[k->mv[i + 4] + 1]; j++)
                __builtin_prefetch(k->tstamp + k->vt[j], 1);
        if (fpc_mark_tris(c, k->mv[i])) return -ENOMEM;
    }
    res->moved_tris = k->nmt; /* (the hierarchy counts them in its check's refit) */

    size_t fl = 0; /* newly flipped triangles of the candidate */
    bool accepted = false; /* the walk job made P the candidate ahead (tree_check) */
    long found = k->tree ? first_check_tree(c, ref, cand, &fl, &accepted, res)
                         : first_check_envelopes(c, ref, cand, &fl);
    if (found < 0) return -ENOMEM;
    res->checks = 1;
    res->pairs = found;
    res->flipped = fl;
    if (found || fl) {
        if (scale_back(c, ref, cand, iters, found, &fl, res)) return -ENOMEM;
    } else {
        k->t_hint = 0; /* (passed whole) */
        if (!accepted)
            for (size_t i = 0; i < k->nmv; i++)
                memcpy(k->p + 3 * (size_t)k->mv[i], cand + 3 * (size_t)k->mv[i], 3 * sizeof(float));
    }
    res->renewed = k->renewed - renewed0;
    res->shared = k->shared;
    res->certified = res->node_pairs = res->leaf_pairs = res->tested = 0;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) {
        res->certified += k->lane[i].certified;
        res->node_pairs += k->lane[i].node_pairs;
        res->leaf_pairs += k->lane[i].leaf_pairs;
        res->tested += k->lane[i].tested;
    }
    dp_update(c, ref, accepted && !found && !fl);
    return 0;
}

/* the vertices v in [f, e) where cand moved from P by less than eps in every coordinate,
 * and differs from ref: P's vertex back into cand (fp_contact_hold); returns their number */
static size_t hold_in(const float *p, const float *ref, float *cand, size_t f, size_t e, float eps)
{
    size_t held = 0;
    for (size_t v = f; v < e; v++) {
        float *q = cand + 3 * v;
        const float *a = p + 3 * v, *r = ref + 3 * v;
        bool near = fabsf(q[0] - a[0]) < eps && fabsf(q[1] - a[1]) < eps &&
                    fabsf(q[2] - a[2]) < eps; /* (false with a NaN) */
        if (!near || !memcmp(q, a, 3 * sizeof(float)) || !memcmp(q, r, 3 * sizeof(float))) continue;
        memcpy(q, a, 3 * sizeof(float));
        held++;
    }
    return held;
}

size_t fp_contact_hold(fp_contact *c, const float *ref, float *cand, const uint32_t *ranges,
                       size_t nranges, float eps)
{
    if (!c || !c->tk || !ref || !cand || !(eps > 0) || (!ranges && nranges != SIZE_MAX)) return 0;
    const float *p = c->tk->p;
    if (nranges == SIZE_MAX) return hold_in(p, ref, cand, 0, c->n, eps);
    size_t held = 0;
    for (size_t r = 0; r < nranges; r++) {
        size_t f = ranges[2 * r], e = f + ranges[2 * r + 1];
        if (f < c->n) held += hold_in(p, ref, cand, f, e < c->n ? e : c->n, eps);
    }
    return held;
}

