/*
 * step_commit.h: the commit (step 6 of the frame, docs/architecture.md): a frame whose
 * control set carries FP_INTENT_COMMIT folds the shape shown into the base (history.h, one
 * undo level per gesture), and the engine re-indexes what changed. What is committed
 * depends on what is shown, one function per case (step_commit.c):
 *   plain          no rig, the engine's output: the base takes it on the touched ranges
 *   guard ranges   no rig, the contact guard's scaled-back shape: on the guard's D_P and
 *                  the touched ranges (fp_cg_ranges)
 *   guard whole    the same over the whole mesh (those ranges unknown, or
 *                  whole_rig_commit asked)
 *   rig ranges     a rig: the blend unposed and committed on the touched ranges (and the
 *                  guard's D_P when its shape is shown), posed again there (fp_rig_step_*)
 *   rig whole      a rig, the whole mesh: unposed, committed, posed and re-indexed
 * and one ending shared by all: the shape shown becomes the (posed) base, the changed sets
 * (fp_session_touched, fp_session_base_touched) get the ranges changed, and the contact
 * guard learns what its reference became (fp_cg_committed: its shape is the new reference;
 * with a rig, fp_cg_reference_changed on the ranges). Each case is bit for bit what the
 * whole-mesh commit gives. fp_commit_step_base_changed is that ending for a base changed
 * by undo or reset.
 *
 * Threads: the session thread. Errors: none (an undo level that cannot grow drops the
 * levels, history.h).
 */
#ifndef FP_STEP_COMMIT_H
#define FP_STEP_COMMIT_H

#include "fp_session.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The frame's commit, after the engine, the rig's blend and the contact guard showed
 *  s's shape; its time into st->stage_ms[FP_STAGE_COMMIT], st->committed. */
void fp_commit_step_run(fp_session *s, fp_frame_stats *st);

/** The base changed (commit of the whole mesh with a rig, undo, reset): the rig poses it, the
 *  engine re-indexes the posed base, which is shown; everything changed. */
void fp_commit_step_base_changed(fp_session *s);

#ifdef __cplusplus
}
#endif
#endif
