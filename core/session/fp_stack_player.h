/*
 * fp_stack_player.h: a stack's frames (core/take/fp_stack.h, docs/stack.md) composed from its
 * layers' takes, the loop `play`, `export` and `info` run for a .fpstack (through
 * fp_take_player, which opens one of these for a stack).
 *
 * Every layer's take plays in its own session (fp_take_player: bit-identical to its
 * recording). The stack's clock is the base take's (layer 0): at each base frame, time t
 * from its first frame, every other layer has played its frames up to t - offset (sample and
 * hold). Then, with N the loaded (neutral) shape, P the composite so far (the base's frame),
 * L a layer's frame, w(v) = region weight (fp_stack.h) x time weight (1 inside [in, out],
 * cross-faded by smoothstep over `fade` seconds at both ends, inside the range; 0 outside)
 * x gain x the fold bound's scale s (below):
 *   replace: P = P + w (L - P)     (displacements from N: d = d + w (d_L - d)); w >= 1: P = L
 *   add:     P = P + w (L - N)     (d = d + w d_L)
 * in double, rounded to float once per layer; a vertex where w == 0 is not touched, so
 * outside every layer's support (and outside its time range) the composite is the base's
 * frame bit for bit. Channel layers (FP_STACK_REGION_CHANNELS) compose per rig channel
 * instead, v = v + w (v_L - v) (replace) or v + w (v_L - neutral) (add), into the base
 * frame's control set before the base session plays it (a base frame with no control set is
 * played as recorded).
 *
 * Not folding: each pass is a guarded deformation (engine, rig, contact guard). The blend
 * adds to the passes' interpolated Jacobian the term (L - P) grad(w)^T; the player bounds it
 * per layer and frame: g = max over the falloff band of |L - P| |w'(d)| f (|grad d| <= 1),
 * and where g > 1/2 (FP_STACK_BLEND_MARGIN, the rig's finger margin) the layer's weight that
 * frame is scaled by 1/2 / g (counted: fp_stack_player_limited). A region with no falloff has
 * a step at its edge that this bound does not cover (--layer gives rig regions and vertex
 * groups 10 mm by default).
 *
 * Errors: 0 or a negative errno-style code with err: the stack file's (fp_stack_load), a
 * layer's take (fp_take_player_open: -ENOENT, -EBADMSG, another mesh), -EINVAL (a layer that
 * is itself a stack, a region or landmark or channel the base's rig lacks, a vertex index
 * past the mesh, a layer on another vertex count), -ENOMEM. Nothing is printed.
 * Threads: one player belongs to one thread.
 */
#ifndef FP_STACK_PLAYER_H
#define FP_STACK_PLAYER_H

#include "fp_session.h"
#include "fp_stack.h"
#include "fp_take.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Bound of the blend's gradient term (see above). */
#define FP_STACK_BLEND_MARGIN 0.5

typedef struct fp_stack_player fp_stack_player;
struct fp_take_player;

/** Open the stack file and every layer's take (the base's session on mesh_path when given,
 *  else the take's mesh; each layer's take checked against it), and compute the regions'
 *  weights on the base's loaded shape. plugin_path, log, log_user: as
 *  fp_take_player_open_logged. Returns 0 and *out. */
int fp_stack_player_open(const char *stack_path, const char *mesh_path,
                         const fp_plugin_path *plugin_path, fp_session_log_fn log,
                         void *log_user, fp_stack_player **out, char *err, size_t errlen);

/** Compose the next frame of the stack (a base frame inside the base layer's [in, out]):
 *  1 and *frame (the base's frame as recorded, the reader's until the next call), *st (the
 *  base session's stats; may be NULL); 0 after the last; or a negative code with err. */
int fp_stack_player_next(fp_stack_player *p, fp_take_frame *frame, fp_frame_stats *st,
                         char *err, size_t errlen);

/** The composite of the last frame (the base's loaded shape before the first): n x 3
 *  floats, the player's, valid until the next call. */
const float *fp_stack_player_positions(const fp_stack_player *p);

/** The stack as read, and the base layer's player (owned by the stack player). */
const fp_stack *fp_stack_player_stack(const fp_stack_player *p);
struct fp_take_player *fp_stack_player_base(fp_stack_player *p);

/** Mute or solo layer i (1 .. layer_count - 1; the base always plays) from the next frame on,
 *  as the stack's file would: the layers that play follow (a solo anywhere plays the soloed
 *  layers only, muted ones never). The stack's copy (fp_stack_player_stack) changes too.
 *  Layers go on playing their frames either way, so a layer turned on again is in step.
 *  Returns 0 or -EINVAL (i out of range). For live's overdub keys. */
int fp_stack_player_set_layer(fp_stack_player *p, size_t i, bool mute, bool solo);

/** Layer i's region weight per vertex (n floats in [0, 1]; NULL for channel layers and
 *  i out of range), for tests and the viewer. */
const float *fp_stack_player_region_weights(const fp_stack_player *p, size_t i);

/** Layer i's own frame as its take plays it (its session's positions at the sample held for
 *  the last frame; n x 3 floats), NULL for channel layers and i out of range; for tests. */
const float *fp_stack_player_layer_positions(fp_stack_player *p, size_t i);

/** Layer i's weight in time at the last frame (time weight x gain x fold scale; 0 for a
 *  muted layer), and whether it is playing (not muted, solo rules). */
double fp_stack_player_layer_weight(const fp_stack_player *p, size_t i);

/** "" or a warning for a layer above the base whose take is cut (no end chunk, a damaged
 *  chunk): "STACK: layers[i]: TAKE: cut at byte N: reason; its K intact frames played" (the
 *  first such layer). A layer whose take has no intact frame fails fp_stack_player_open
 *  (-EBADMSG: the stack, the layer and the take named); the base's cut is its reader's
 *  warning (fp_take_reader_warning). */
const char *fp_stack_player_warning(const fp_stack_player *p);

/** Frames x layers whose weight the fold bound scaled down so far. */
unsigned long fp_stack_player_limited(const fp_stack_player *p);

/** A region's weights on a session's loaded shape (the base's): w (n floats in [0, 1]), the
 *  vertices where w > 0 (sup, nsup of them) and |w'(d)| there (slope, per mesh unit; 0 where
 *  the weight is flat). Owned: fp_stack_weights_free. */
typedef struct fp_stack_weights {
    float *w;
    uint32_t *sup;
    float *slope;
    size_t nsup;
} fp_stack_weights;

/** The weights of region (not a channel region) on base's loaded shape, core and falloff
 *  through mm_per_unit (> 0); landmarks and rig regions from base's rig. Returns 0 and *out,
 *  or -EINVAL (a name the rig lacks, no rig, a vertex past the mesh: said in err), -ENOMEM.
 *  Cost: O(vertices x region vertices) within the region's reach, once. */
int fp_stack_region_weights(const fp_stack_region *region, const fp_session *base,
                            double mm_per_unit, fp_stack_weights *out, char *err, size_t errlen);
/** Free w's arrays and zero *w. NULL-safe. */
void fp_stack_weights_free(fp_stack_weights *w);

/** One layer's blend into the composite `out` (n x 3, in place): the layer's frame `layer`,
 *  the neutral shape `neutral`, the region's weights, the weight in time x gain f, the mode
 *  (the formulas above), with the fold bound: returns the weight used (f, or f scaled down
 *  by the bound; *limited, may be NULL, says which). Vertices outside the support, and all
 *  when f <= 0, are not touched. [any-thread] on distinct arrays. */
double fp_stack_blend(float *out, const float *layer, const float *neutral,
                      const fp_stack_weights *w, double f, fp_stack_mode mode, bool *limited);

/** Close every layer's player, free the player, set *p to NULL. NULL-safe. */
void fp_stack_player_close(fp_stack_player **p);

#ifdef __cplusplus
}
#endif
#endif
