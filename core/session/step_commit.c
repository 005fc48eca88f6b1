/* The commit: one function per case, one shared ending (step_commit.h). */
#include "step_commit.h"

#include "fp_clock.h"
#include "session_internal.h"

#include <string.h>

/* What a commit changed, for the ending all the cases share (commit_end). */
typedef struct commit_done {
    const float *shown;           /* the shape shown from now: the base, or the posed base */
    const uint32_t *ranges;       /* where the base and the shape shown changed: (first, */
    size_t count;                 /*   count) pairs; SIZE_MAX: anywhere */
    bool ref_moved;               /* a rig: the guard's reference (the posed base) changed
                                     there; else the guard's shape is the new reference */
} commit_done;

/* The one ending: the shape shown, the changed sets, the contact guard. (The plain case's
 * ranges are the frame's touched ranges, which the frame added to the shape shown already:
 * a union that changes nothing there.) */
static void commit_end(fp_session *s, const commit_done *d)
{
    s->shown = d->shown;
    s->shown_kind = SHOWN_POSED;
    if (d->count == SIZE_MAX) {
        fp_changed_all(&s->shown_changed);
        fp_changed_all(&s->base_changed);
    } else {
        fp_changed_add(&s->shown_changed, d->ranges, d->count);
        fp_changed_add(&s->base_changed, d->ranges, d->count);
    }
    if (d->ref_moved) fp_cg_reference_changed(&s->cg, d->ranges, d->count);
    else fp_cg_committed(&s->cg);
}

/* The base changed everywhere: the rig poses it, the engine re-indexes the posed base. */
static commit_done rebased(fp_session *s)
{
    fp_rig_step_base_changed(&s->rig);
    fp_rig_step_update(&s->rig, NULL, s->base, &s->log);
    const float *posed = fp_rig_step_posed(&s->rig, s->base);
    fp_engine_step_set_base(&s->engine, posed);
    return (commit_done){posed, NULL, SIZE_MAX, true};
}

void fp_commit_step_base_changed(fp_session *s)
{
    commit_done d = rebased(s);
    commit_end(s, &d);
}

/* No rig, the engine's output: it becomes the base on the touched ranges only, and only
 * those are re-indexed (the whole buffer where they are unknown); the anchored gesture
 * ended, unanchored restarts anyway. The base changed where the output did. */
static commit_done commit_plain(fp_session *s)
{
    const uint32_t *r;
    size_t nr = fp_engine_step_touched(&s->engine, &r);
    if (nr == SIZE_MAX)
        fp_history_commit(&s->history, s->deformed);
    else
        fp_history_commit_ranges(&s->history, s->deformed, r, nr);
    fp_engine_step_commit(&s->engine, s->base); /* (keeps r's contents) */
    return (commit_done){s->base, r, nr, false};
}

/* No rig, the guard checked the frame's shape (fp_cg_commit_ranges): the output becomes the
 * base where it may differ from it (gr), and only there is it re-indexed. The shape shown
 * is the output: the guard accepted it whole. */
static commit_done commit_plain_ranges(fp_session *s, const uint32_t *gr, size_t ng)
{
    fp_history_commit_ranges(&s->history, s->deformed, gr, ng);
    fp_engine_step_commit_ranges(&s->engine, s->base, gr, ng);
    return (commit_done){s->base, gr, ng, false};
}

/* No rig, the guard scaled the motion back: its shape goes into the output buffer and the
 * base where either may differ from the base (gr: D_P and this frame's touched ranges; bit
 * for bit the whole path below), and only those ranges are re-indexed. The guard's P is
 * that shape. */
static commit_done commit_guard_ranges(fp_session *s, const uint32_t *gr, size_t ng)
{
    for (size_t r = 0; r < ng; r++)
        memcpy(s->deformed + 3 * (size_t)gr[2 * r], s->shown + 3 * (size_t)gr[2 * r],
               3 * (size_t)gr[2 * r + 1] * sizeof(float));
    fp_history_commit_ranges(&s->history, s->deformed, gr, ng);
    fp_engine_step_commit_ranges(&s->engine, s->base, gr, ng);
    return (commit_done){s->base, gr, ng, false};
}

/* No rig, the guard scaled the motion back: its shape goes into the base and the output
 * buffer (it may differ from the base outside this frame's touched ranges: earlier frames
 * scaled back); the engine re-indexes the whole base. The guard's P is that shape. */
static commit_done commit_guard_whole(fp_session *s)
{
    memcpy(s->deformed, s->shown, s->n * 3 * sizeof(float));
    fp_history_commit(&s->history, s->deformed);
    fp_engine_step_set_base(&s->engine, s->base);
    return (commit_done){s->base, NULL, SIZE_MAX, false};
}

/* A rig, on the ranges gr only: the touched ranges, where the blend may differ from the
 * posed base, and with the guard's shape shown its D_P too (fp_cg_ranges), so the commit
 * shape equals the base outside them (fp_rig_unpose_range keeps unmoved vertices), and the
 * base, the posed base, the engine's output and index change there only. Bit for bit the
 * whole path. */
static commit_done commit_rig_ranges(fp_session *s, const uint32_t *gr, size_t ng)
{
    const float *cshape = fp_rig_step_commit_ranges(&s->rig, s->base, s->shown, gr, ng);
    fp_history_commit_ranges(&s->history, cshape, gr, ng);
    fp_rig_step_rebase_ranges(&s->rig, s->base, s->deformed, gr, ng);
    fp_engine_step_commit_ranges(&s->engine, fp_rig_step_posed(&s->rig, s->base), gr, ng);
    return (commit_done){fp_rig_step_posed(&s->rig, s->base), gr, ng, true};
}

/* A rig, where this frame's check of the guard ran (fp_cg_commit_ranges, gr): the base, the
 * posed base and the engine's index change only on the blocks holding D_P or a vertex that
 * check found moved, not on the whole supports (tr). Elsewhere in tr the shape shown is the
 * posed base already (a vertex neither moved nor in D_P is where P and the reference, the
 * posed base, have it), so the commit shape there is the base (fp_rig_unpose_range keeps
 * unmoved vertices) and only the engine's output, which may hold a rigid vertex's
 * displacement the blend ignored, goes back to the posed base. Bit for bit
 * commit_rig_ranges over tr and D_P, for a fraction of the work where most of a support
 * keeps its bits (unanchored, which commits every frame). */
static commit_done commit_rig_moved(fp_session *s, const uint32_t *tr, size_t nt, const uint32_t *gr,
                                    size_t ng)
{
    const float *cshape = fp_rig_step_commit_ranges(&s->rig, s->base, s->shown, gr, ng);
    fp_history_commit_ranges(&s->history, cshape, gr, ng);
    fp_rig_step_rebase_ranges(&s->rig, s->base, s->deformed, gr, ng);
    const float *posed = fp_rig_step_posed(&s->rig, s->base);
    for (size_t r = 0; r < nt; r++)
        memcpy(s->deformed + 3 * (size_t)tr[2 * r], posed + 3 * (size_t)tr[2 * r],
               3 * (size_t)tr[2 * r + 1] * sizeof(float));
    fp_engine_step_commit_ranges(&s->engine, posed, gr, ng);
    return (commit_done){posed, gr, ng, true};
}

/* A rig, the whole mesh: only the fingers' part goes into the base; the whole mesh is
 * unposed, committed, posed and re-indexed (the anchored gesture ended; unanchored
 * restarts anyway) */
static commit_done commit_rig_whole(fp_session *s)
{
    fp_history_commit(&s->history, fp_rig_step_commit_shape(&s->rig, s->base, s->shown));
    return rebased(s);
}

void fp_commit_step_run(fp_session *s, fp_frame_stats *st)
{
    int64_t t0 = fp_now_ns();
    const uint32_t *tr;
    size_t nt = fp_engine_step_touched(&s->engine, &tr);
    /* the contact guard's shape may differ from the posed base outside this frame's
     * touched ranges (earlier frames scaled back), within its D_P: committed on both
     * (fp_cg_ranges); with a rig as the blend is, on those ranges */
    bool guard_shown = fp_cg_shows(&s->cg, s->shown);
    const uint32_t *gr = tr;
    size_t ng = nt;
    bool rig_whole = s->rig.rig && (nt == SIZE_MAX || s->whole_rig_commit ||
                                    !fp_rig_step_posed_current(&s->rig));
    commit_done d;
    /* where this frame's check of the guard ran: only where a vertex moved
     * (fp_cg_commit_ranges), not the whole supports */
    size_t nm = !s->whole_rig_commit && nt != SIZE_MAX && !rig_whole ? fp_cg_commit_ranges(&s->cg, &gr)
                                                                  : SIZE_MAX;
    if (nm == SIZE_MAX && s->rig.rig && !rig_whole && guard_shown)
        rig_whole = (ng = fp_cg_ranges(&s->cg, tr, nt, &gr)) == SIZE_MAX;
    if (nm != SIZE_MAX && s->rig.rig)
        d = commit_rig_moved(s, tr, nt, gr, nm);
    else if (nm != SIZE_MAX)
        d = guard_shown ? commit_guard_ranges(s, gr, nm) : commit_plain_ranges(s, gr, nm);
    else if (rig_whole)
        d = commit_rig_whole(s);
    else if (!s->rig.rig && guard_shown && !s->whole_rig_commit &&
             (ng = fp_cg_ranges(&s->cg, tr, nt, &gr)) != SIZE_MAX)
        d = commit_guard_ranges(s, gr, ng);
    else if (!s->rig.rig && guard_shown)
        d = commit_guard_whole(s);
    else if (s->rig.rig)
        d = commit_rig_ranges(s, gr, ng);
    else
        d = commit_plain(s);
    commit_end(s, &d);
    st->stage_ms[FP_STAGE_COMMIT] = (double)(fp_now_ns() - t0) / 1e6;
    st->committed = true;
}
