/*
 * step_contact.h: the contact guard's step of the frame (step 5, after the engine and the
 * rig's blend; docs/architecture.md): the session's side of core/contact (fp_contact.h,
 * its incremental form). Each frame that shows a deformation, the frame's shape is checked
 * against the shape shown last (the guard's P), on the reference (the posed base): when it
 * adds self-crossings or flipped triangles against the reference, this frame's motion is
 * scaled back (fp_contact_step) and the guard's shape is shown instead. Without a rig, by
 * induction over commits, the shown surface never crosses itself where the loaded face did
 * not; a rig's own pose (its channels) is not checked.
 *
 * The guard's P and the reference are kept in step by a sync state (FP_CG_*): the frame's
 * check first catches P up with what happened since the last one (a gesture ended: the
 * reference was shown; a pose, undo, reset or a rig's commit: the reference changed, on
 * ranges kept in `ref`). Its transitions (asserted in debug builds):
 *   any -> SYNCED          the frame's check (fp_cg_run), a new guard (fp_cg_open)
 *   SYNCED -> SHOWN_REF    the reference is shown again (fp_cg_shown_ref; from SHOWN_REF or
 *                          REF_CHANGED nothing changes)
 *   SYNCED -> SHOWN_REF    a commit without a rig: P, the shape shown and checked this
 *                          frame, is the new reference (fp_cg_committed)
 *   any -> REF_CHANGED     the reference changed (fp_cg_reference_changed)
 * and while the guard exists, `ref` records nothing unless the state is REF_CHANGED.
 *
 * Threads: the session thread (the frame thread, when the frames run there). Errors: out of
 * memory in a frame makes the guard unusable: the reference is shown, and the guard is made
 * anew in the next frame that deforms (fp_cg_run).
 */
#ifndef FP_STEP_CONTACT_H
#define FP_STEP_CONTACT_H

#include "changed.h"
#include "fp_contact.h"
#include "fp_session.h"
#include "session_log.h"
#include "step_rig.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_CONTACT_BISECTIONS 6
/* The guard's broad phase (fp_contact_set_prewarm): envelopes up to this many triangles, the
 * hierarchy above; 0: the hierarchy on every mesh. Envelopes were the faster on face-sized
 * meshes while a frame moved the skin less than a triangle's size; with drags that carry the
 * skin tens of millimetres (issue 51) their boxes and lists grow with the motion: the
 * contact-limited frames of the ICT face's grab at 1.5 R took 0.2-0.6 s each with envelopes.
 * Same decisions either way (tests/session/test_contact.c); figures in docs/performance.md
 * (a build with -DFP_CG_PREWARM=262144 in CMAKE_C_FLAGS gives the envelopes to compare). */
#ifndef FP_CG_PREWARM
#define FP_CG_PREWARM 0
#endif
/* pairs within this many vertex rings of the input's own crossings are not the guard's
 * business (fp_contact_dilate_own): the eyes' intersection curves move under any motion */
#define FP_CONTACT_OWN_RINGS 1
/* fp_contact_hold's eps, a fraction of the loaded face's bounding-box diagonal: a vertex
 * that moved less than this since the last frame keeps its place until it moves more or a
 * commit (4.75 um on the ICT face, 47.5 cm across: about 1/25 of a pixel where the face
 * fills a 4K screen) */
#define FP_CONTACT_HOLD 1e-5

/* A gesture the guard held back for flipped triangles alone (a long drag turning skin over
 * without crossing anything: under a nostril, a lip) is widened: from the next frame its
 * support radius is FP_FLIP_WIDEN times the mapping's, again at each such hold, up to
 * FP_FLIP_WIDEN_MAX, until the gesture ends. The control vectors are the same, so the
 * fingertips' skin goes as far; the map is smoother, so the skin around turns less and the
 * guard need not stop it. Crossings do not widen: a wider support carries more of the face
 * (an eye's, an ear's close sheets) into the drag. Measured on the recordings and transformed
 * copies of them (tools/hands-variants; figures in docs/performance.md). */
#define FP_FLIP_WIDEN 1.5
#define FP_FLIP_WIDEN_MAX 2.25

/* The guard's P (the shape it last accepted) and the frame's reference, the posed base: */
enum {
    FP_CG_SYNCED = 0,   /* P is the shape shown, on the current reference */
    FP_CG_SHOWN_REF,    /* the reference was shown since (a gesture ended): P := ref at D_P */
    FP_CG_REF_CHANGED   /* the reference changed (a pose, undo, reset: anywhere; a commit with a
                           rig: on its ranges): compare there (ref) and at D_P */
};

typedef struct fp_cg_step {
    fp_contact *contact;          /* the guard (fp_contact.h); NULL: none (no_contact_guard,
                                     or lost) */
    const uint32_t *tris;         /* the mesh (fp_cg_open's, kept to make the guard anew) */
    size_t t, n;
    const float *loaded;          /* the loaded shape: the guard's weld shape */
    int sync;                     /* FP_CG_*: what the guard's P must catch up with */
    float pose[FP_RIG_MAX_CHANNELS]; /* the channel values its rest normals were posed by */
    bool posed;                   /* pose is set (fp_contact_set_pose was called) */
    bool lost;                    /* the guard ran out of memory: made anew, the base shown
                                     until then */
    unsigned long frames, limited; /* this gesture: frames checked, scaled back */
    unsigned long carried;        /* ... of those, the frames whose held skin was carried along
                                     (fp_contact_result.carried) */
    unsigned long turned;         /* ... of those, the frames held back for triangles turning
                                     over alone (no new crossing: fp_contact_result.pairs 0) */
    double t_least;               /* this gesture: smallest share of a frame's motion kept
                                     (fp_contact_result.kept) */
    float hold;                   /* fp_contact_hold's eps (mesh units): FP_CONTACT_HOLD of the
                                     loaded face's diagonal; 0: none (options.exact_frames) */
    fp_changed ref;               /* where the reference changed since the guard last took it
                                     (FP_CG_REF_CHANGED: fp_contact_reference compares there) */
    uint8_t *gc_mark;             /* fp_cg_ranges: a byte per block of 16 vertices (zero
                                     between calls) */
    uint32_t *gc_ranges;          /* its ranges */
    bool stepped;                 /* the last fp_cg_run checked its frame's shape (the guard's
                                     moved vertices are that check's: fp_cg_commit_ranges) */
} fp_cg_step;

/** The guard on the mesh (tris, t triangles over n vertices, loaded its loaded shape: kept by
 *  pointer), its own crossings widened by FP_CONTACT_OWN_RINGS, on two threads where there
 *  are two cores, flips judged from the rig's pose (rig->rig: base its unposed base), started
 *  on the shape shown (the posed base). Returns 0 or -ENOMEM (g->contact NULL). */
int fp_cg_open(fp_cg_step *g, const uint32_t *tris, size_t t, size_t n, const float *loaded,
               const fp_rig_step *rig, const float *base, const float *shown);

/** What the frame's check looks at. */
typedef struct fp_cg_frame {
    const float *ref;             /* the reference: the posed base */
    const float *shown;           /* the frame's shape: the engine's output (deformed) or the
                                     rig's blend of it (rig->shown); the reference: nothing */
    bool commit;                  /* the frame commits: no hold (the base gets the engine's) */
    fp_rig_step *rig;             /* its pose; its blend may be held (fp_contact_hold) */
    const float *base;            /* the unposed base (fp_contact_set_pose) */
    float *deformed;              /* the engine's output, which may be held */
    const uint32_t *touched;      /* the engine's touched ranges (first, count), where the */
    size_t ntouched;              /*   frame's shape may differ from the reference */
    double radius;                /* the support radius: a local scale-back's */
} fp_cg_frame;

/** The frame's check: returns the shape to show (f->shown, or the guard's shape when the
 *  motion was scaled back, or f->ref when the guard ran out of memory); its times and counts
 *  into st (collide_*). */
const float *fp_cg_run(fp_cg_step *g, const fp_cg_frame *f, fp_slog *log, fp_frame_stats *st);

/** True when shown is the guard's shape (its scaled-back P). */
bool fp_cg_shows(const fp_cg_step *g, const float *shown);

/** Where the guard's shape (P) and the engine's output may differ from the base: the blocks
 *  of 16 vertices holding the guard's D_P (fp_contact_differs) or a touched range (tr, nt),
 *  as increasing, disjoint vertex ranges in *out (g's); returns their number, SIZE_MAX when
 *  unknown (nt == SIZE_MAX) or out of memory. O(D_P + touched + n / 16): the marked
 *  blocks are read in order from a byte per block. Used by the commit of the guard's shape
 *  (step_commit.c) and by the shape shown's changed ranges (session.c). */
size_t fp_cg_ranges(fp_cg_step *g, const uint32_t *tr, size_t nt, const uint32_t **out);

/** Where a frame's commit must write when this frame's fp_cg_run checked its
 *  shape (with a rig, the base, the posed base and the index; the engine's output goes back
 *  to the posed base on the whole touched ranges, step_commit.c) (shown: the engine's output, or the guard's shape scaled back): the blocks of 16
 *  vertices holding the guard's D_P or a vertex that check found moved (fp_contact_moved),
 *  as fp_cg_ranges gives them. The shape shown differs from the base (the guard's reference,
 *  P before the check outside D_P) only in D_P; the engine's output differs from the shape
 *  shown only at the moved vertices a scale-back held back; elsewhere in its touched ranges
 *  it equals P before the check (so the base, outside D_P), and outside them the base (the
 *  engine rewrites what left a support). So a commit there leaves output, shape
 *  shown and base equal everywhere, as one over the touched ranges does, but its work follows
 *  the vertices that moved, not the supports (unanchored, which commits every frame: most of
 *  a support's vertices move by less than a float's rounding and keep their bits). SIZE_MAX
 *  when the last fp_cg_run did not check (no guard, lost, nothing moved from the reference)
 *  or out of memory. *out is g's, valid until its next call. Threads: the session's frame
 *  thread, after fp_cg_run and before the guard's next call (the moved vertices are its
 *  last step's). */
size_t fp_cg_commit_ranges(fp_cg_step *g, const uint32_t **out);

/** The reference (the posed base) changed on ranges (count SIZE_MAX: anywhere): the next
 *  check compares P there and at D_P (fp_contact_reference). */
void fp_cg_reference_changed(fp_cg_step *g, const uint32_t *ranges, size_t count);

/** The shape shown is the reference again (a frame without a deformation, an engine error):
 *  P catches up before the next check. */
void fp_cg_shown_ref(fp_cg_step *g);

/** A commit without a rig made the shape shown (the guard's P, checked this frame) the
 *  reference: only D_P to compare at the next check. */
void fp_cg_committed(fp_cg_step *g);

/** The gesture ended: one line when the guard scaled it back (FP_SLOG_CONTACT, a warning),
 *  naming what held the skin back: new crossings ("stopped the surface from passing through
 *  itself"), triangles turning over alone ("stopped the skin from folding over"), or each
 *  with its count of frames; then the gesture's counts start again. */
void fp_cg_end_gesture(fp_cg_step *g, fp_slog *log);

/** The support widening for a gesture's next frame (FP_FLIP_WIDEN), from this frame's
 *  (widen; below 1: none) and its stats: a frame held back for flips alone (st->active,
 *  st->collide_t < 1, st->collide_pairs 0) widens once more, up to FP_FLIP_WIDEN_MAX;
 *  otherwise the widening stays. The caller resets it to 1 when the gesture ends. Pure. */
double fp_cg_next_widen(double widen, const fp_frame_stats *st);

/** Free the guard and the buffers; *g zeroed. */
void fp_cg_free(fp_cg_step *g);

#ifdef __cplusplus
}
#endif
#endif
