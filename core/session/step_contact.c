/* The contact guard's step of the frame: the session's side of core/contact (step_contact.h). */
#define _GNU_SOURCE /* sysconf's _SC_NPROCESSORS_ONLN */
#include "step_contact.h"

#include "fp_clock.h"
#include "fp_text.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The sync state's invariants (step_contact.h), at the end of each transition */
static void cg_check(const fp_cg_step *g)
{
    assert(g->sync >= FP_CG_SYNCED && g->sync <= FP_CG_REF_CHANGED);
    assert(!g->lost || !g->contact); /* a lost guard is gone until it is made anew */
    /* while the guard exists, ref records only what FP_CG_REF_CHANGED will compare */
    assert(!g->contact || g->sync == FP_CG_REF_CHANGED || (!g->ref.all && !g->ref.n));
    assert(g->limited <= g->frames && g->turned <= g->limited && g->carried <= g->limited);
    (void)g;
}

/* The guard on the loaded mesh (its own crossings widened by FP_CONTACT_OWN_RINGS), started
 * on the shape shown. Returns 0 or -ENOMEM (g->contact NULL). */
static int cg_make(fp_cg_step *g, const fp_rig_step *rig, const float *base, const float *shown)
{
    int rc = fp_contact_create(g->tris, g->t, g->n, g->loaded, &g->contact);
    if (!rc) rc = fp_contact_dilate_own(g->contact, FP_CONTACT_OWN_RINGS);
    /* the hierarchy on every mesh (FP_CG_PREWARM): its work follows the moved triangles'
     * count, not how far they moved, where an envelope's list grows with a fast drag */
    if (!rc) fp_contact_set_prewarm(g->contact, FP_CG_PREWARM);
    /* a large mesh's checks on two threads where there are two cores (fp_contact.h: the
     * caller never waits for a worker that has not started; small meshes stay on one) */
    if (!rc) fp_contact_set_threads(g->contact, sysconf(_SC_NPROCESSORS_ONLN) >= 2 ? 2 : 1, 0);
    /* flips judged from where the rig's pose put each triangle (O(t): here, once, not at the
     * first commit of a performance) */
    if (!rc && rig->rig) {
        rc = fp_contact_set_pose(g->contact, base, shown);
        memcpy(g->pose, rig->posed_values, sizeof g->pose);
        g->posed = !rc;
    }
    if (!rc) rc = fp_contact_reference(g->contact, shown, NULL, SIZE_MAX);
    if (rc) fp_contact_destroy(&g->contact);
    const uint32_t *r;
    fp_changed_take(&g->ref, &r); /* from here: where the reference changes */
    g->sync = FP_CG_SYNCED;
    return rc;
}

int fp_cg_open(fp_cg_step *g, const uint32_t *tris, size_t t, size_t n, const float *loaded,
               const fp_rig_step *rig, const float *base, const float *shown)
{
    g->tris = tris;
    g->t = t;
    g->n = n;
    g->loaded = loaded;
    int rc = cg_make(g, rig, base, shown);
    cg_check(g);
    return rc;
}

/* The reference's changes caught up with (step_contact.h), the rest normals posed as the
 * reference (fp_contact_set_pose, O(t): when the channels changed, not at every commit: the
 * open jaw turns the ICT mouth corners 89 degrees from the neutral face). 0 or -ENOMEM. */
static int cg_sync(fp_cg_step *g, const fp_cg_frame *f)
{
    int rc = 0;
    if (g->sync == FP_CG_REF_CHANGED && f->rig->rig &&
        (!g->posed || memcmp(g->pose, f->rig->posed_values, sizeof g->pose))) {
        rc = fp_contact_set_pose(g->contact, f->base, f->ref);
        memcpy(g->pose, f->rig->posed_values, sizeof g->pose);
        g->posed = true;
    }
    if (!rc && g->sync != FP_CG_SYNCED) {
        /* P differs from the old reference at D_P only, the new one from the old where
         * ref says (a rig's commit: its ranges, so not all n vertices compared: 0.08-0.12
         * ms on the ICT face, in the next gesture's first frame) */
        const uint32_t *rr = NULL;
        size_t nr = g->sync == FP_CG_REF_CHANGED ? fp_changed_take(&g->ref, &rr) : 0;
        rc = fp_contact_reference(g->contact, f->ref, rr, nr);
    }
    g->sync = FP_CG_SYNCED;
    return rc;
}

/* The guard looks only where the shape may have changed: the engine's touched ranges (the
 * rig's blend moves no vertex the fingers did not). */
const float *fp_cg_run(fp_cg_step *g, const fp_cg_frame *f, fp_slog *log, fp_frame_stats *st)
{
    const float *ref = f->ref, *shown = f->shown;
    g->stepped = false;
    if (g->lost && shown != ref) { /* the guard is made anew on the shape shown: ref */
        if (cg_make(g, f->rig, f->base, ref)) return ref; /* still no memory: the base stays */
        g->lost = false; /* P is ref, shown last frame; the rig's pose set by cg_make */
    }
    cg_check(g);
    if (!g->contact || shown == ref) return shown;
    int64_t t0 = fp_now_ns();
    fp_contact_set_local(g->contact, f->radius); /* a blocked finger stops alone */
    int rc = cg_sync(g, f);
    fp_contact_result r;
    /* the hold (fp_contact_hold): vertices that moved less than hold keep their place;
     * never in a commit's frame, so the base gets the engine's shape. The candidate is the
     * engine's output or the rig's blend of it, each rewritten next frame wherever it
     * differs from the posed base now (the engine's touched ranges then hold this frame's
     * supports), so a held vertex is never left behind */
    float *cand = shown == f->deformed ? f->deformed
                  : f->rig->rig && shown == f->rig->shown ? f->rig->shown : NULL;
    if (!rc && !f->commit && g->hold > 0 && cand)
        st->collide_held = fp_contact_hold(g->contact, ref, cand, f->touched, f->ntouched, g->hold);
    if (!rc)
        rc = fp_contact_step(g->contact, ref, shown, f->touched, f->ntouched, FP_CONTACT_BISECTIONS, &r);
    st->collide_ms += (double)(fp_now_ns() - t0) / 1e6;
    if (rc) { /* out of memory: the guard is unusable; show the reference, a new guard next frame */
        fp_contact_destroy(&g->contact);
        g->lost = true;
        fp_slog_printf(log, FP_LOG_ERROR, FP_SLOG_CONTACT, "contact guard: out of memory; showing the base");
        cg_check(g);
        return ref;
    }
    g->stepped = true;
    st->collide_pairs += r.pairs;
    st->collide_wait_ms += r.worker_wait_ms;
    st->collide_checks += r.checks;
    st->collide_moved += r.moved_verts;
    st->collide_node_pairs += r.node_pairs;
    st->collide_leaf_pairs += r.leaf_pairs;
    st->collide_tested += r.tested;
    st->collide_certified += r.certified;
    if (!g->frames) g->t_least = 1.0;
    g->frames++;
    if (r.t < 1) {
        shown = fp_contact_shape(g->contact);
        g->limited++;
        g->carried += r.carried;
        g->turned += r.pairs == 0;
        if (r.kept < g->t_least) g->t_least = r.kept;
        if (r.t < st->collide_t) st->collide_t = r.t;
        if (r.kept < st->collide_kept) st->collide_kept = r.kept;
    }
    assert(g->sync == FP_CG_SYNCED); /* P is the shape shown now */
    cg_check(g);
    return shown;
}

bool fp_cg_shows(const fp_cg_step *g, const float *shown)
{
    return g->contact && shown == fp_contact_shape(g->contact);
}

#define FP_GC_SHIFT 4 /* fp_cg_ranges: blocks of 16 vertices */

/* fp_cg_ranges and fp_cg_commit_ranges: the blocks of D_P, of the ranges tr and of the
 * vertices mv */
static size_t mark_blocks(fp_cg_step *g, const uint32_t *tr, size_t nt, const uint32_t *mv, size_t nmv,
                        const uint32_t **out)
{
    const size_t nb = (g->n >> FP_GC_SHIFT) + 1;
    if (nt == SIZE_MAX) return SIZE_MAX;
    if (!g->gc_mark) {
        g->gc_mark = calloc(nb, 1);
        g->gc_ranges = malloc(2 * nb * sizeof *g->gc_ranges);
        if (!g->gc_mark || !g->gc_ranges) {
            free(g->gc_mark), free(g->gc_ranges);
            g->gc_mark = NULL, g->gc_ranges = NULL;
            return SIZE_MAX;
        }
    }
    const uint32_t *dp;
    const size_t ndp = fp_contact_differs(g->contact, &dp);
    for (size_t i = 0; i < ndp; i++) g->gc_mark[dp[i] >> FP_GC_SHIFT] = 1;
    for (size_t i = 0; i < nmv; i++) g->gc_mark[mv[i] >> FP_GC_SHIFT] = 1;
    for (size_t r = 0; r < nt; r++) {
        if (!tr[2 * r + 1]) continue;
        size_t b0 = tr[2 * r] >> FP_GC_SHIFT, b1 = (tr[2 * r] + tr[2 * r + 1] - 1) >> FP_GC_SHIFT;
        memset(g->gc_mark + b0, 1, b1 - b0 + 1);
    }
    /* the marked blocks in order, a scan of n / 16 bytes (a sort of the 1.7M face's 100,000
     * blocks took milliseconds), the marks cleared on the way */
    size_t nr = 0;
    for (size_t b = 0; b < nb;) {
        if (!g->gc_mark[b]) {
            b++;
            continue;
        }
        const size_t b0 = b;
        while (b < nb && g->gc_mark[b]) g->gc_mark[b++] = 0;
        const size_t v0 = b0 << FP_GC_SHIFT, v1 = b << FP_GC_SHIFT;
        if (v0 >= g->n) break;
        g->gc_ranges[2 * nr] = (uint32_t)v0;
        g->gc_ranges[2 * nr + 1] = (uint32_t)((v1 < g->n ? v1 : g->n) - v0);
        nr++;
    }
    *out = g->gc_ranges;
    return nr;
}

size_t fp_cg_ranges(fp_cg_step *g, const uint32_t *tr, size_t nt, const uint32_t **out)
{
    return mark_blocks(g, tr, nt, NULL, 0, out);
}

size_t fp_cg_commit_ranges(fp_cg_step *g, const uint32_t **out)
{
    if (!g->stepped || !g->contact) return SIZE_MAX;
    const uint32_t *mv;
    size_t nmv = fp_contact_moved(g->contact, &mv);
    return mark_blocks(g, NULL, 0, mv, nmv, out);
}

void fp_cg_reference_changed(fp_cg_step *g, const uint32_t *ranges, size_t count)
{
    fp_changed_add(&g->ref, ranges, count);
    g->sync = FP_CG_REF_CHANGED;
    cg_check(g);
}

void fp_cg_shown_ref(fp_cg_step *g)
{
    if (g->sync == FP_CG_SYNCED) g->sync = FP_CG_SHOWN_REF;
    cg_check(g);
}

void fp_cg_committed(fp_cg_step *g)
{
    /* the frame's check ran (every frame that deforms without a rig shows a shape other
     * than the reference), so P is the shape shown, which the commit made the base */
    assert(!g->contact || g->sync == FP_CG_SYNCED);
    g->sync = FP_CG_SHOWN_REF;
    cg_check(g);
}

void fp_cg_end_gesture(fp_cg_step *g, fp_slog *log)
{
    char carried[96] = "";
    if (g->carried)
        snprintf(carried, sizeof carried, "; in %lu the skin held back was carried along with the drag",
                 g->carried);
    /* what held the skin back, in the performer's words: crossings (the surface passing
     * through itself), triangles turning over (the skin folding back), or both */
    char why[160];
    if (!g->turned)
        snprintf(why, sizeof why, "stopped the surface from passing through itself");
    else if (g->turned == g->limited)
        snprintf(why, sizeof why, "stopped the skin from folding over (triangles turning past a right "
                 "angle from the face's own)");
    else
        snprintf(why, sizeof why, "stopped the surface from passing through itself (%lu frames) and "
                 "the skin from folding over (%lu)", g->limited - g->turned, g->turned);
    char least[16]; /* (a frame held back by a hair: "over 99%", not "100%") */
    fp_text_share_held(g->t_least, least, sizeof least);
    if (g->limited)
        fp_slog_printf(log, FP_LOG_WARNING, FP_SLOG_CONTACT,
                       "contact guard %s: %lu of %lu frames scaled back (least share of a frame's "
                       "motion kept %s)%s",
                       why, g->limited, g->frames, least, carried);
    g->frames = g->limited = g->carried = g->turned = 0;
    cg_check(g);
}

double fp_cg_next_widen(double widen, const fp_frame_stats *st)
{
    if (!(widen >= 1.0)) widen = 1.0;
    if (st->active && st->collide_t < 1.0 && st->collide_pairs == 0)
        widen = fmin(widen * FP_FLIP_WIDEN, FP_FLIP_WIDEN_MAX);
    return widen;
}

void fp_cg_free(fp_cg_step *g)
{
    fp_contact_destroy(&g->contact);
    fp_changed_free(&g->ref);
    free(g->gc_mark);
    free(g->gc_ranges);
    memset(g, 0, sizeof *g);
}
