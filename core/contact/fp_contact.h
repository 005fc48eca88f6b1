/*
 * fp_contact.h: the contact guard (issue 10): a discrete check that a candidate shape adds no
 * self-crossings of the surface to a reference shape, and a bisection that scales the
 * motion back until it adds none. Two forms over one test:
 *  - the full check (fp_contact_count_new, fp_contact_guard): stateless, O(n + t) per call;
 *    the reference the tests hold the incremental form to;
 *  - the incremental guard (fp_contact_reference, fp_contact_step; issue 18): what the
 *    session runs every frame; it checks each candidate against the shape it accepted last,
 *    its work follows this frame's motion (argument below). Its candidate pairs come from
 *    per-triangle envelopes on face-sized meshes, from a hierarchy of certified patches on
 *    larger ones ("(3a)", "(3b)" below).
 *
 * fp_contact_create also finds the weld shape's own crossings (a full scan, once) and its
 * triangle normals. fp_contact_count_new checks only what moved: the triangles with a vertex
 * whose position differs (bitwise) between reference and candidate, against the triangles
 * near them, found through a uniform grid over the moved region (cell: the mean moved
 * triangle's extent in the candidate), its (cell, triangle) records sorted by cell so that
 * each cell's pairs are taken in one sweep, every pair once. Two triangles cross when they share a point
 * (closed triangles) and no vertex; vertices at identical positions in the shape given to
 * fp_contact_create are welded, so OBJ seams (duplicated vertices) are adjacency, as in
 * tests/support/selfx. Degenerate (zero-area) triangles are skipped. A pair is new when it
 * crosses in the candidate and not in the reference, so crossings the input already has (the
 * ICT face's eyes and mouth interior) never count. The triangle-triangle test: two closed
 * triangles meet iff an edge of one meets the other (their intersection is convex, its
 * boundary lies on an edge), each segment-triangle test from the signs of orient3d
 * determinants in double (float inputs; each vertex against the other's plane computed
 * once), with a 2D test for coplanar segments. A determinant within its rounding error
 * bound (Shewchuk's errboundA) counts as zero, i.e. touching: the test is exact where the
 * signs are certain and errs towards a crossing, never away from one, where they are not
 * (the bisection drives pairs towards touching frame after frame). CGAL's exact test agrees
 * on the real faces (tests/session/test_contact.c).
 *
 * Errors: negative errno (-EINVAL for NULL or a triangle index >= n, -ENOMEM). Threads: one
 * fp_contact per thread (it keeps scratch buffers and the incremental guard's state).
 * Link: the static library fp_contact (core/contact; its files by concern are listed in
 * contact_internal.h), which needs only fp_common (the clock), pthreads and libm.
 */
#ifndef FP_CONTACT_H
#define FP_CONTACT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "fp_vec.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct fp_contact fp_contact;

/** Index a mesh: tris (t x 3 indices < n, kept by pointer: must outlive c), weld positions
 *  weld (n x 3 floats, copied into a weld map; vertices at identical positions are one).
 *  Returns 0, -EINVAL or -ENOMEM; *out owned by the caller (fp_contact_destroy). */
int fp_contact_create(const uint32_t *tris, size_t t, size_t n, const float *weld, fp_contact **out);
void fp_contact_destroy(fp_contact **c);

/** Widen the input's own crossings by `rings` vertex rings (through welded vertices): a
 *  pair with a triangle that has a vertex within `rings` rings of an own-crossing triangle
 *  is left out as well (fp_selfx_count_new_away's rings; the intersection curve of surfaces
 *  that interpenetrate in the input, the ICT face's eyes, moves onto the neighbouring
 *  triangles under the smallest motion). Cumulative. Returns 0 or -ENOMEM. */
int fp_contact_dilate_own(fp_contact *c, int rings);

/** A triangle is turned over (flipped) when its normal is more than acos(this) from its rest
 *  normal (FP_FLIP_COS, fp_vec.h: 1e-5): 90 degrees less 0.0006 of a degree, a margin over the
 *  rest normal's rounding to float. The
 *  bisection drives a turning triangle to that edge; at exactly 90 degrees the rounding
 *  decided the sign, and an independent check in double (tests/e2e/test_guard) saw a flip
 *  the guard had let through (tests/session/test_contact.c test_flip_boundary). */
#define FP_CONTACT_FLIP_COS FP_FLIP_COS

/** What fp_contact_count_new saw besides the new pairs. */
typedef struct fp_contact_count {
    size_t moved_tris;   /* triangles with a moved vertex */
    size_t flipped;      /* moved triangles turned over (normal against the rest normal, the
                            weld shape's or fp_contact_set_pose's, FP_CONTACT_FLIP_COS) in
                            cand and not in ref, own-crossing ones included: the input's
                            own crossings excuse pairs, not a triangle turned over */
    long near_own;       /* new pairs left out: a triangle crosses in the weld shape */
} fp_contact_count;

/** New crossing pairs of cand against ref (both n x 3 floats): pairs with a moved triangle
 *  that cross in cand and not in ref, away from the input's own crossings (a pair with a
 *  triangle that crosses another in the weld shape given to fp_contact_create is left out,
 *  as fp_selfx_count_new_away with 0 rings: the ICT face's eyes and mouth interior
 *  interpenetrate, and their intersection curves move under any deformation). Up to
 *  max_pairs pairs (a < b) go to pairs[2k], pairs[2k+1] (may be NULL), unordered. info may
 *  be NULL. Returns the number of new pairs (>= 0) or -ENOMEM. */
long fp_contact_count_new(fp_contact *c, const float *ref, const float *cand, uint32_t *pairs,
                          size_t max_pairs, fp_contact_count *info);

/** What fp_contact_guard did. */
typedef struct fp_contact_result {
    double t;            /* the fraction of the motion kept (1: all, 0: the reference); with
                            local: near the blocking triangles (the rest more, see
                            fp_contact_set_local) */
    double kept;         /* the share of the candidate's motion kept, as the eye sees it: the
                            sum over the moved vertices of how far each moved over how far the
                            candidate had it move (1: all; t, unless the scale-back was local,
                            where the skin away from the blocking triangles moved whole) */
    long pairs;          /* new pairs of the full candidate */
    size_t flipped;      /* newly flipped triangles of the full candidate (these block too) */
    int checks;          /* checks of a shape (fp_contact_count_new calls) */
    size_t moved_tris;   /* moved triangles of the full candidate (fp_contact_step: not own) */
    size_t moved_verts;  /* fp_contact_step: vertices where the candidate differs from P */
    size_t renewed;      /* fp_contact_step: envelopes renewed */
    size_t certified;    /* fp_contact_step, the hierarchy: patches certified (their pairs
                            not tested) */
    int local;           /* fp_contact_step: 1 when the scale-back was local */
    double local_r;      /* fp_contact_step, local: the ramp's r (fp_contact_set_local's r / 4,
                            / 2 or r: the first that passed) */
    bool carried;        /* fp_contact_step, local: the ramp that passed carried the held
                            skin (fp_contact_set_carry) */
    size_t shared;       /* fp_contact_step, the hierarchy: checks whose refit and walk
                            two threads shared (fp_contact_set_threads) */
    double worker_wait_ms; /* fp_contact_step: how long the caller waited, at the ends of
                            its shared jobs, for a task the worker held (a worker the
                            system took off its core holds the step up until it is back) */
    /* fp_contact_step, the hierarchy: the walks' work, summed over the step's checks (both
       threads; 0 on envelopes), so a caller sees where a check's time goes */
    size_t node_pairs;   /* node pairs the walks reached (boxes compared; those the caller
                            passed while splitting the walk into tasks not counted) */
    size_t leaf_pairs;   /* leaf pairs whose boxes met, a leaf with itself included (their
                            triangles' boxes compared) */
    size_t tested;       /* triangle pairs tested exactly (boxes met, a moved one, neither
                            adjacent nor in a certified patch; a bisection's probes too) */
} fp_contact_result;

/** The guard: out = ref + t (cand - ref) per vertex (float), with the largest t of the
 *  bisection over [0, 1] (`iters` halvings after a failed t = 1) for which out adds no new
 *  pair and no newly flipped triangle to ref (fp_contact_count_new); t = 1 (out = cand bit for bit) when cand adds none, t = 0 (out = ref) when
 *  every tried t adds some. out (n x 3) may not alias ref or cand. Returns 0 or -ENOMEM
 *  (out then holds ref). */
int fp_contact_guard(fp_contact *c, const float *ref, const float *cand, float *out, int iters,
                     fp_contact_result *res);

/*
 * The incremental guard (fp_contact_reference, fp_contact_step): what a session calls per
 * frame. It keeps P, the shape it last accepted (n x 3, fp_contact_shape), and checks each
 * candidate against P instead of the reference, so its work follows this frame's motion,
 * not the gesture's, nor the mesh's size.
 *
 * Why this is exactly the check above. Let new(S) be the pairs fp_contact_count_new(ref, S)
 * counts (cross in S, not in ref, neither triangle own, not adjacent) and flip(S) its
 * newly flipped triangles (own triangles included: they are checked for flips, from a list
 * of their own, and for nothing else). Invariant: new(P) and flip(P) are empty; it holds for P = ref
 * (after fp_contact_reference) and for every shape fp_contact_step accepts.
 *  (1) A pair with no vertex that moved from P to the candidate C has the same triangles
 *      in P and in C, so it crosses in C iff in P; if it were in new(C) it would be in new(P).
 *      So new(C) = the pairs in new(C) with a moved triangle (one whose vertex differs
 *      bitwise between P and C), and likewise flip(C) = its moved triangles in flip(C).
 *  (2) The moved vertices are found without looking at all n: P differs from ref only at
 *      D_P (a vertex list kept with P) and C from ref only in the caller's ranges (the
 *      engine's touched blocks), so C differs from P only within D_P and the ranges.
 *  (3) Pairs (A, B) with A moved whose boxes in C meet are all tested, by the same
 *      triangle-triangle test as fp_contact_count_new, in C and then in ref, but for the
 *      pairs within a certified patch (3b), which cannot cross. The candidates come from one
 *      of two broad phases, chosen by the mesh's size (fp_contact_set_prewarm).
 * (3a) Envelopes (meshes up to FP_CONTACT_PREWARM triangles): every triangle (own ones left
 *      out) has an envelope (its box grown by a tenth of its extent) in a hash grid, all made
 *      at the first fp_contact_reference, renewed only when the box leaves it, with a list of
 *      the triangles whose envelopes met its own at its renewal; a renewed triangle also
 *      joins the lists of those it meets (stale entries are allowed: a list holds at least
 *      every triangle whose envelope meets its owner's now). Before the check of C each
 *      moved triangle's envelope is made to hold its box in C (unmoved ones hold theirs,
 *      P's), and before a bisection its box in P too, hence in every shape P + t (C - P)
 *      between them (rounding is monotonic), so two boxes that meet in the checked shape lie
 *      in envelopes that meet, and the pair is in the moved triangle's list. A pair of two
 *      moved triangles is tested once, from the lower index. Renewals are batched by grid
 *      cell (each cell's triangles read once for all the envelopes that cover it; a pair
 *      taken in the cell of its boxes' common lower corner); boxes over 4096 cells live in
 *      lists of their own. With a worker (fp_contact_set_threads 2), after each step the
 *      worker re-centres the envelopes of the step's moved triangles whose box in P came
 *      within half the skin of a side (a new envelope around that box, as a renewal makes
 *      it): a motion that goes on then leaves fewer envelopes in the next step. The job
 *      writes the grid, envelopes and lists only, never P or D_P, and every later call on c
 *      first waits for it, or drops it when the worker has not started it (the step then
 *      renews what it needs, as on one thread).
 * (3b) The hierarchy (larger meshes): a binary tree of patches over the triangles not own,
 *      built at the first fp_contact_reference from the weld shape's edges, bottom up: the
 *      triangles are the first clusters; each round pairs each cluster with the neighbour
 *      (across an edge (u, v) / (v, u)) it shares most edges with, first among those whose
 *      union faces a direction and (from 24 triangles on) stays a disc (they share one arc:
 *      one vertex more on both boundaries than shared edges), then among discs, then any;
 *      what finds no partner (a separate component) is joined at the top by median splits. A
 *      node of at most 24 triangles is a leaf. Every node keeps its box and a box holding its
 *      triangles' unit normals, in the shape checked: before each check the moved
 *      triangles' normals and boxes are made, and the nodes above them refit (the others
 *      hold P's, which the checked shape equals there). The check walks the tree as a self-collision test:
 *      within a node that holds a moved triangle, its children's own pairs and the pairs
 *      between them; between two nodes, nothing when neither holds a moved triangle or their
 *      boxes do not meet, else down the larger; between two leaves, every pair with a moved
 *      triangle whose boxes meet. Each pair is reached once, so with (1) every pair with a
 *      moved triangle whose boxes meet is tested, but for a certified node's own pairs:
 *      A node of 48 to 65,536 triangles whose boundary chain (its triangles' directed edges
 *      summed, (u, v) cancelling (v, u); vertex indices as stored, so a seam is boundary) is
 *      one cycle through distinct vertices may be certified. It is, in the shape checked,
 *      when (i) a, the centre of its normals' box (normalised), has n . a > 1e-4 for every
 *      unit normal n in that box, so every triangle keeps a positive area projected along a
 *      (a degenerate triangle, whose normal is rounding, fills the whole box: never), and
 *      (ii) the cycle projected along a is a simple polygon (every segment pair sharing a
 *      grid cell tested, first by their boxes in float rounded outwards, which hold the
 *      test's own; a sign within a margin far over the projection's rounding counts as
 *      touching, i.e. not simple). Then the projection p is one to one on the patch: for a
 *      point y off the projected edges, the triangles over y number the winding number of
 *      the projected cycle around y (all triangles positive, their boundaries summing to the
 *      cycle), 0 or 1 for a simple polygon; and two points with one image would make a
 *      region covered twice (two points off the cycle: their neighbourhoods' images are
 *      open and meet; one on it: the other's neighbourhood reaches outside the polygon,
 *      where nothing lies; both on it: the polygon is not simple). No two points of the
 *      patch meet in C then, so no two of its triangles cross. (The patches' normals
 *      boxes use unit normals rounded to float, within 1e-6 of the true direction: the
 *      1e-4 margin holds.)
 * So the candidate is accepted exactly when fp_contact_count_new(ref, C) would find no new
 * pair and no newly flipped triangle, and the bisection (shape P + t (C - P) at the moved
 * vertices, t on the grid of 2^iters steps: halvings, or after a step that kept little its t
 * first, doubled while it passes; only a t whose shape passed is kept) keeps the invariant. What
 * changes against fp_contact_guard: t scales this frame's motion (P -> C), not the gesture's
 * (ref -> C); the shape shown after a scaled frame is P's, and the next frame goes on from it.
 *
 * A local scale-back (fp_contact_set_local, radius r): instead of one t for the frame, vertex
 * v keeps the share w(v) = t + (1 - t) s(v) of its motion, s(v) = 0 within r of a vertex of
 * a blocking triangle (a triangle of a new pair or a newly flipped one, positions in P),
 * smoothstep up to 1 at 2r, so a finger stopped at the lips does not freeze a brow. The
 * shape with t = 0 must pass the check; when it does not, the triangles it blocks join the
 * blocking set and r doubles (rounds at r/4, r/2, then r: up to FP_CONTACT_LOCAL_ROUNDS = 5
 * rounds), then the global t as above. Starting narrow holds back as little skin as passes:
 * a pair blocked by the eye no longer stops the cheek a finger drags beside it (reach,
 * tests/e2e/test_reach: Lee Perry-Smith's grab, 10th percentile 23% with r from the start,
 * 62% so). The
 * bisection is then over t with w. Every vertex still lies on its segment P -> C (w in
 * [0, 1]), so (3) holds unchanged; every shape kept passed the same check, so the
 * invariant holds, and a fold at the border between scaled and kept motion is a flip or a
 * crossing that check sees. s(v) takes the nearest blocking vertex from a k-d tree over
 * them (exact: the brute force's distance wherever it is under 2r).
 * Carried rounds (fp_contact_set_carry, on by default; the hierarchy only): each of the
 * first FP_CONTACT_CARRY_ROUNDS rounds first tries the held skin carried: vertex v at
 * P(v) + T(v) + w(v) (C(v) - P(v) - T(v)), T(v) the mean motion C - P of the blocking
 * vertices within 2r of v, weighted by (1 - d^2 / 4r^2)^2 (0 with none near). Near one
 * blocked spot T is nearly constant, so the skin there moves on with the drag as one piece,
 * its triangles keeping their shapes and places among themselves, instead of staying
 * behind: a finger that drags a nostril's crease or an eyelid along keeps it under the
 * finger. Where the first check found flipped triangles and no new pair, and the blocking
 * vertices are one compact patch (their box in P at most FP_CONTACT_CARRY_RIGID r across,
 * contact_internal.h), T is exactly constant: every held vertex is carried by their mean
 * motion, so each held triangle keeps the normal it has in P.
 * A few triangles that earlier motion left 1-10 degrees short of turning over
 * (leapjs-playback's recordings on ICT and Lee Perry-Smith) had been turned past it by the
 * small differences of the weighted T across them, every carried round
 * failed, and the held rounds kept the fingertip's skin back for up to 38 frames
 * (tests/session/test_contact_rigid_carry; docs/performance.md "Skin left near a right
 * angle"). When that shape passes, it is the round's, and the bisection goes over t from it
 * (P + T + w (C - P - T)); when it does not, the round goes on held as above. A carried
 * vertex leaves the segment P -> C, which the envelopes' argument (3a) needs, so carried
 * rounds run on the hierarchy alone (3b: its check refits the shape it is given, wherever
 * the moved vertices are); a vertex with s(v) = 1 is still where C has it, so the check
 * looks only at the others, as below. Every shape kept still passed the full check. Reach
 * (tests/e2e/test_reach, 10th percentiles): ICT grab 92% -> 100%; transformed copies
 * (tools/hands-variants): ICT mirrored grab 72% -> 100%, MediaPipe 1.6x faster grab 76% ->
 * 97.5%, Lee Perry-Smith pinched grab 58.7% -> 96% (docs/performance.md). A step that
 * moves more than FP_CONTACT_CARRY_MAX_TRIS triangles tries none: a carried check that
 * fails is one check more, and on the 1.7M face one costs 0.1-1 s.
 * On the hierarchy the candidate's check keeps its new pairs' triangles and its newly
 * flipped ones: they are the blocking set (no second check of the candidate: on the 1.68M
 * face that second walk had cost 115-230 ms of a contact-limited frame), and a bisection's
 * check first tests the triangles the last failing check found flipped and up to 8 new
 * pairs per thread it found: one still flipped, or a pair still crossing in the shape and
 * not in ref (neither own nor adjacent: one of the full check's new pairs, whatever moved),
 * decides it before the refit and the walk. A vertex with
 * s(v) = 1 is where C has it, in every shape of the scale-back, and a triangle of such
 * vertices is not a blocking one: a pair of them (or with unmoved ones) is as in C, where it
 * added nothing. So on the hierarchy the check of each ramp and, once one passed, the
 * bisection's look only at the triangles of the vertices with s(v) < 1.
 * tests/session/test_contact.c holds every decision to the full check's.
 *
 * Cost: per frame, the vertices in the ranges and D_P, then
 *  - envelopes: each moved triangle (boxes, its flip, its list: about 100 ns on a large
 *    mesh, mostly cache misses) and each renewed envelope (about 1 us on ICT: 0.3 in its
 *    cells, 0.6-0.7 making its list, by cell, each registered envelope tested against
 *    the cell's requests in one vectorised loop; renewed when a triangle moved a tenth of
 *    its size since its last renewal). The per-frame loops store and add where a test
 *    would be decided by the data (the moved vertices, their triangles' stamps, a list's
 *    both-moved rule and box test: a misprediction an entry had cost a third of the
 *    check), and the exact test makes each triangle's plane once (tplane). A frame on ICT:
 *    about 480 moved vertices, 1,100 moved triangles, 2,400 list entries, 200 exact tests;
 *    its step 60-100 us (collect 5-12, mark 8-23, envelopes 13-25, renew 2-5, check 33-45),
 *    varying with the machine's load. In its slow minutes one step in three took 150-330
 *    us: a gesture's first frames and a fast clap's renew 40-125 envelopes (about 2 us each
 *    with their cells and lists, the caches cold after the replay's sleep), and in the
 *    others one phase alone stalled 60-120 us with the usual counts and list lengths (the
 *    lists do not grow over a gesture: 2,300-2,900 entries, 7 at most). Measured
 *    (`facepuppet bench --case frame`, contact row, three-claps anchored, 2-core machine,
 *    shared): the ICT face (up to 125 renewed in a gesture's first frames and a fast
 *    clap's) 0.058-0.11 ms median, 0.16-0.25 ms p99 (the full check: about 2.7 ms). With
 *    the worker re-centring, the replay's steps renewed 698-757 envelopes in 16-17
 *    frames, against 1,856-1,872 in 75-78 on one thread; the deforming frames' contact
 *    was about a fifth lower at the median and a third at the 90th percentile (6 runs
 *    each, alternated), for about 0.12 ms of the worker's time a frame (median). The
 *    frame: median 0.129 against 0.149 ms, p99 0.310 against 0.351 in 8 alternated runs;
 *    with the session's thread pinned, 0.12 against 0.13 and 0.29 against 0.33 (12 runs
 *    each, half on each CPU); unpinned, the polling worker moves the session's thread to
 *    the other CPU, whichever is slower that minute (12 more runs: no difference). The
 *    worker polls between frames as for the hierarchy: one that slept after each
 *    re-centring (woken by the next) made the frame slower than no re-centring (0.170 ms
 *    median against 0.149). On ICT
 *    subdivided to 1.68M vertices (50,000-66,000 moved triangles a frame, moving about
 *    their own size in a fast frame) up to all of them renew: 5.4-7.3 ms median, 47-103
 *    ms p99, 15-25 frames of 225 skipped. Larger skins renew less but lengthen the lists
 *    and each renewal: no gain measured.
 *  - the hierarchy: each moved vertex stamped (one store; a vertex that joins D_P also
 *    stamps its triangles' blocks of 64 and 4096 places in the tree's order: the region,
 *    which holds every triangle with a vertex in D_P and is emptied with it), the nodes that
 *    may hold a moved triangle found from the root through the region's blocks, the moved
 *    triangles there by their vertices' stamps (the marking of the 1.68M face's 31,000
 *    moved vertices: 0.21-0.23 ms on two threads against 0.54-0.57 when each stamped its
 *    six triangles' places; the refit 0.1-0.15 ms more), each moved triangle's normal, flip
 *    and box (about 17 ns), the walk (along the borders of the certified patches: with
 *    leaves of 8 triangles about 43,000 node pairs and 4,600 leaf pairs, 2.1 ms, on the
 *    1.68M face; leaves of 24 visit fewer node pairs for more box tests in each, the
 *    frame's contact 2.9-3.1 ms median on two threads against 3.2-3.3; with them, by
 *    local timers on two threads: 37,000 node pairs, 2,700 leaf pairs at 390-530 ns, 950
 *    exact tests (0.07-0.11 ms; a leaf pair's tests as the set bits of a mask, not a branch
 *    for each triangle: 592-620 ns a call against 627-667, alternating in the same frames
 *    under other timers; about 210 ns when the same call is repeated, its data then in
 *    the cache), the walk's 2.7-3.6 ms of work split evenly, each thread
 *    1.45-1.65 ms of tasks, the caller 0.15-0.18 ms making them; the marking 0.13-0.28
 *    ms, the update (the refit job and the top) 0.8-1.1) and the
 *    certificates (about 45 ns a cycle vertex: 0.8 ms; 28 patches a frame, 17,900 cycle
 *    vertices; the longest cycle, 3,593 vertices, 161 us: its projection 28, the segments'
 *    cells and boxes 42, the grid 27, the pairs in a cell 65, against 110-154 before their
 *    float boxes filtered them). P := the
 *    candidate and D_P's update run as the walk job's last tasks, ahead of its verdict (the
 *    walk reads the candidate and ref, never P; a candidate that fails gets P back), so they
 *    fill the threads' ends of the walk instead of a serial tail (0.08-0.12 ms on the 1.68M
 *    face). Figures are one thread's; see fp_contact_set_threads for two.
 *    Nothing is renewed, so a fast frame costs what a slow one does: 1.68M vertices 6.2-6.3
 *    ms median, 7.5-11.7 ms p99, no frame skipped. On the ICT face it
 *    is 3-4 times slower than envelopes (0.36-0.45 ms: its patches, 32 to 1,000 triangles
 *    of a strongly curved face, certify less and their borders are most of the walk),
 *    hence the size threshold. Building it: about 5 s for 1.68M vertices (the clusters 3.6
 *    s, the boundary cycles 1.3 s), at the first fp_contact_reference.
 *  - either way, the memory a step writes (stamps, D_P, the hierarchy's per-thread scratch
 *    for its longest certified cycle and a support of up to n/16 vertices) is made and
 *    written at the build: left to the first frames, its fresh pages faulted (10 faults in
 *    the ICT face's first deforming frame, which took 0.4-1.3 ms, its marking 0.07-0.26 ms
 *    against 0.03 now; 68 in the 1.68M face's).
 */

/** Start (or restart) the incremental guard on reference ref (n x 3): P := ref. ranges:
 *  (first vertex, count) pairs where ref may differ from the shape P held so far (besides
 *  D_P, which the guard adds), nranges of them; nranges == SIZE_MAX: anywhere (all n are
 *  compared). Call it when the reference changes (commit, undo, a new pose) and when the
 *  shape shown went back to the reference (a gesture ended, a cancel): then ranges may be
 *  empty (0), only D_P is restored. The first call builds the broad phase (O(t)). Returns
 *  0, -EINVAL (NULL) or -ENOMEM (the guard is then unusable: destroy it). */
int fp_contact_reference(fp_contact *c, const float *ref, const uint32_t *ranges, size_t nranges);

/** One frame: the candidate cand (n x 3) against the last accepted shape P, on the reference
 *  given to fp_contact_reference (the same ref, unchanged since). ranges / nranges: where
 *  cand may differ from ref (e.g. fp_engine_step_touched: (first, count) pairs; SIZE_MAX:
 *  anywhere). Accepts cand (res->t = 1, P := cand, bit for bit) when it adds no new pair and
 *  no newly flipped triangle to ref (the argument above), else P := P + t (cand - P) at the
 *  moved vertices with t from the bisection on the grid of 2^iters steps (`iters` halvings,
 *  0 to 24; 0: P stays). After a step that scaled back to t at most 1/16 (FP_CONTACT_GALLOP),
 *  a step of at least fp_contact_set_gallop's triangles first tries that t (or 1 step) and
 *  doubles it while it passes, then halves the bracket: skin held frame after frame then
 *  costs about 2 checks instead of iters, and t is one whose shape passed, as before (not
 *  necessarily the largest such t: neither was the halvings'). Deterministic: the same
 *  calls give the same shapes.
 *  Nothing moved (cand = P where looked): no work. The shape to show is cand when
 *  res->t == 1, else fp_contact_shape. Work: the vertices in ranges and D_P, the moved
 *  triangles and their lists; envelopes renewed where a box left its own (with a worker,
 *  the step then posts the re-centring of (3a) and returns without waiting). Returns 0,
 *  -EINVAL or -ENOMEM (the guard is then unusable, every later call says -ENOMEM: destroy
 *  it; show the reference meanwhile). */
int fp_contact_step(fp_contact *c, const float *ref, const float *cand, const uint32_t *ranges,
                    size_t nranges, int iters, fp_contact_result *res);

/** The hold (issue 18): before fp_contact_step, where the candidate cand (n x 3 floats, the caller's, written in place, not kept)
 *  moved less than eps (mesh units, in every coordinate) from P (fp_contact_shape) since the
 *  last step, it gets P's vertex back, bit for bit, so that vertex is no moved vertex of the
 *  step and its triangles need no check. A vertex where cand equals the reference ref (bit
 *  for bit) is never held: it returns exactly (so a held vertex lies where an engine wrote a
 *  displacement this frame, which it writes again next frame: the engine's buffer may be
 *  cand). The shape shown then differs from the engine's by less than eps at each vertex,
 *  and by nothing where it moved eps or more; what fp_contact_step decides about cand is as
 *  exact as ever (it checks the held shape). Why: most vertices in a support's outer ring
 *  move by far less than a pixel from frame to frame (the Wendland function's tail), yet
 *  each one makes its triangles moved ones: on the ICT three-claps replay, 1e-5 of the
 *  face's diagonal (4.75 um) held 414 of 485 moved vertices a step and left 286 of 1,089
 *  moved triangles (1.7M face: 18,512 of 60,054; contact 2.25-2.53 ms median against
 *  4.63-4.86 there, a replay of the session's calls). Looks at the vertices in ranges
 *  (first, count pairs, clipped to n; nranges SIZE_MAX: every vertex), as fp_contact_step
 *  does. eps <= 0 or NaN, c NULL, or before the first fp_contact_reference: nothing (a
 *  caller about to commit passes 0, so a commit is the engine's shape). Returns how many
 *  vertices were held. Threads: as every call on c. */
size_t fp_contact_hold(fp_contact *c, const float *ref, float *cand, const uint32_t *ranges,
                       size_t nranges, float eps);

/** Meshes with at most this many triangles use envelopes ("(3a)"), every envelope and list
 *  made at the first fp_contact_reference, in one batch (about 1 us a triangle: 85 ms for
 *  the ICT face), so that a gesture's first touch of a region costs its frame no more than
 *  the next; larger ones use the hierarchy ("(3b)"), also built then. Default
 *  FP_CONTACT_PREWARM; 0: the hierarchy for every mesh (the tests run both ways). Call
 *  before the first fp_contact_reference. */
#define FP_CONTACT_PREWARM 262144
void fp_contact_set_prewarm(fp_contact *c, size_t max_tris);

/** The hierarchy's patch certificates ("(3b)") on (default) or off: off, every pair of
 *  triangles whose boxes meet is tested, as if no patch were certified (the tests run both
 *  ways); decisions are the same either way, only the work differs. Takes effect at the next
 *  check; no effect on envelopes. c NULL: nothing. No errors. Threads: as every call on c
 *  (one thread at a time). */
void fp_contact_set_certify(fp_contact *c, bool on);

/** Threads for the hierarchy's checks ("(3b)") and the envelopes' re-centring ("(3a)"): 1
 *  (default) or 2 (more count as 2). With 2, a worker thread, started at the first check
 *  that needs it (with envelopes: when they are made, at the first fp_contact_reference)
 *  and joined by
 *  fp_contact_destroy, takes a share of a step's marking (looking for the moved vertices
 *  and stamping their triangles) when it looks at min_moved / 2 vertices or more, and of a
 *  check's refit below its top nodes (with the moved triangles' boxes and normals) and its
 *  walk when the check moves min_moved triangles or more (0: the default,
 *  FP_CONTACT_SHARE_MIN; the tests pass 1). After a job it polls, yielding its core between
 *  polls, until no job has come for 20 ms (through a deformation at 60 fps it does not sleep
 *  between frames). Tasks are claimed one at a time, as the caller adds them, and the
 *  caller waits only for a task the worker holds, never for a worker that has not started,
 *  so a busy machine costs the worker's share, not a time slice. Decisions, counts and P
 *  are the same with 1 or 2, the checks that record blocking triangles (a local scale-back)
 *  included (each thread keeps its own list, merged after the job). With envelopes the
 *  worker only re-centres them after each step ("(3a)"), between the frames; a check there
 *  is too short to share (measured: the ICT face's envelope check shared, its boxes and
 *  pairs in tasks, cut its contact median 12-20% but raised the frame's p99 8-30%, the
 *  caller waiting up to 0.2-0.7 ms for a worker held off its core mid-task; see
 *  fp_contact_result.worker_wait_ms, which also counts a wait for the re-centring). The
 *  decisions, counts and P are the same with or without it (only which envelopes are
 *  renewed, fp_contact_result.renewed, differs).
 *  No thread could be made: 1, silently. c NULL: nothing. Threads: as every call on c (one
 *  thread at a time); the worker is internal. Measured (`bench --case frame`, 1.7M
 *  vertices, 2 cores): contact 2.5-2.65 ms median on two threads, varying with the
 *  machine's load (6.1-6.2 ms when the marking, refit and walk all ran on one). */
#define FP_CONTACT_SHARE_MIN 4096
void fp_contact_set_threads(fp_contact *c, int threads, size_t min_moved);

/** Flips are judged against rest normals: the weld shape's (as made), or, after this call
 *  with a rig's pose (base: the unposed reference, posed: the reference the rig made of it,
 *  both n x 3), the weld shape's normals carried by the pose (each triangle's turned by the
 *  least rotation that takes its normal in base to its normal in posed; a triangle the pose
 *  turned over: posed's normal) and the weld shape's as well: a triangle is newly turned
 *  over when it is past 90 degrees from one of the two that it is not past in the reference.
 *  So the fingers turn no triangle over from where the pose put it, nor from the loaded face
 *  (a triangle the jaw turned 60 degrees may turn 30 more, not 90: before, the one-hand
 *  mapping's landmarks and jaw together turned 1-19 triangles over against the loaded face
 *  in 7 of tests/e2e/test_guard's 12 runs); a triangle the pose itself turned past 90
 *  degrees from the loaded face is excused that, not a fold from where the pose put it (the
 *  rig keeps its pose from turning any: fp_rig_unfold_jaw). base == posed or both NULL: the
 *  weld shape's normals again. Call it when the reference changes, before
 *  fp_contact_reference (whose P := ref keeps the invariant below: a pair or flip of ref is
 *  never new). O(t). Returns 0, -EINVAL (NULL c, one of base / posed NULL) or -ENOMEM. */
int fp_contact_set_pose(fp_contact *c, const float *base, const float *posed);

/** fp_contact_step scales back locally (the argument above): radius r > 0 in mesh units
 *  (the session gives its support radius: the motion within r of a blocking triangle comes
 *  from control points whose supports reach it); 0 (default), NaN or negative: the whole
 *  frame's motion by one t. Extra cost of a scale-back: up to 4 more checks, and the moved
 *  vertices inside the blocking vertices' box grown by 2r x the blocking vertices (test_guard,
 *  unanchored ICT three-claps: check p99 3.1 ms against 2.7 ms global; noisy, 2 cores). */
void fp_contact_set_local(fp_contact *c, double radius);

/** A local scale-back's carried rounds (the argument above), on (the default) or off (the
 *  held rounds alone, as before issue 51's carry: tests and comparisons). Threads: as
 *  every call on c. */
void fp_contact_set_carry(fp_contact *c, bool on);

/** The scale-back's search from the last step's t (fp_contact_step: after a step that kept at
 *  most 1/16, that t tried first and doubled) applies to steps that move at least min_tris
 *  triangles; smaller ones halve from [0, 1] (their t as before it: where a check costs
 *  microseconds the halvings may find a larger t, pass and fail not being monotone in t).
 *  Default FP_CONTACT_GALLOP_MIN_TRIS; 0: every step (tests). Threads: as every call on c. */
void fp_contact_set_gallop(fp_contact *c, size_t min_tris);
#define FP_CONTACT_GALLOP_MIN_TRIS 200000

/** P, the shape fp_contact_step last accepted (n x 3, owned by c, valid until its next
 *  call), or NULL before the first fp_contact_reference. */
const float *fp_contact_shape(const fp_contact *c);

/** D_P: the vertices where P (fp_contact_shape) may differ from the reference last given to
 *  fp_contact_reference (a superset: a vertex that went back stays listed), indices < n, no
 *  repeats, in no order; *verts owned by c, valid until its next call. Returns their number
 *  (0, *verts NULL, before the first fp_contact_reference and for c NULL). No errors.
 *  Threads: as every call on c. So a caller that makes P its new reference (a commit)
 *  copies these vertices only. */
size_t fp_contact_differs(const fp_contact *c, const uint32_t **verts);

/** The vertices the last fp_contact_step (or fp_contact_reference) found moved: where its
 *  candidate differed bitwise from P as it was before the call (indices < n, no repeats, in
 *  no order; the step's P differs from the earlier P at these only). *verts owned by c, valid
 *  until its next call. Returns their number (0, *verts NULL, before the first
 *  fp_contact_reference and for c NULL). No errors. Threads: as every call on c. So a
 *  caller whose buffer held the candidate learns where the shape it shows may differ from
 *  that buffer (a scale-back's vertices) without comparing the two. */
size_t fp_contact_moved(const fp_contact *c, const uint32_t **verts);

/** The triangle-triangle test alone (closed triangles, 3 x 3 doubles each): 1 when they
 *  share a point, else 0. Exposed for tests. */
int fp_contact_tri_tri(const double a[3][3], const double b[3][3]);

#ifdef __cplusplus
}
#endif
#endif
