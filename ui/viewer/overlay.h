/* overlay.h: what the live viewer draws over the face (internal to ui/viewer): both hands'
 * skeletons, each fingertip's support sphere (radius R) and its depth cue, the control
 * vectors as arrows, and the rig overlay (key G: regions, landmarks, hinge axis, legend).
 *
 * Fingertip cues (issue 53 item 1): a fingertip "touches" when the nearest vertex of the
 * surface the fingers work on (fp_session_surface_nearest: the base posed by the rig) is
 * within the support radius R, i.e. its sphere reaches the skin, which is the paper's rule
 * for an active hand. Its sphere then turns from faint blue (fp_tip_far_sphere) to green
 * (fp_tip_touch_sphere). The depth cue: a line from each fingertip within
 * FP_TIP_CUE_REACH x R to its nearest skin point and a spot there, drawn over the face, so
 * that a front view shows where and how far each finger is from the skin.
 *
 * Drawing needs the renderer's context current; the cues are read on the session thread
 * between steps. Threads: the viewer's.
 */
#ifndef FP_UI_OVERLAY_H
#define FP_UI_OVERLAY_H

#include "fp_session.h"
#include "render.h"

#include <stdbool.h>
#include <stddef.h>

/** Fingertips farther than this many support radii from the skin get no depth cue. */
#define FP_TIP_CUE_REACH 3.0

/** The colours (RGBA): spheres of fingertips off and on the skin, their cue lines. */
extern const float fp_tip_far_sphere[4], fp_tip_touch_sphere[4], fp_tip_far_color[4],
    fp_tip_touch_color[4];

/** Each present hand's fingertips this frame and their nearest skin points: every
 *  performer's hands (fp_session_performer_hand), the first performer's first. */
#define FP_TIP_CUES_MAX (FP_PERFORMER_CAPACITY * FP_HANDS * FP_FINGERS)
typedef struct fp_tip_cues {
    size_t count;                              /* fingertips (5 per present hand) */
    float tip[FP_TIP_CUES_MAX][3];             /* mesh units */
    float skin[FP_TIP_CUES_MAX][3];            /* the nearest skin vertex (where dist finite) */
    float dist[FP_TIP_CUES_MAX];               /* mesh units; INFINITY beyond the cue's reach */
    bool touching[FP_TIP_CUES_MAX];            /* dist <= R */
    size_t touch_count;
    float nearest;                             /* the least dist; INFINITY: none in reach */
} fp_tip_cues;

/** The fingertips' cues on the session's current frame (out is filled; no hands: count 0).
 *  Session thread, between steps; no allocation. */
void fp_overlay_tip_cues(const fp_session *s, fp_tip_cues *out);

/** Draw the hands (bones, joints; every performer's, the left blue and the right orange, a
 *  later performer's paler), the fingertips' spheres and cues (cues from
 *  fp_overlay_tip_cues this frame) and, while engaged, the control vectors as arrows.
 *  pv, view: column-major 4x4. */
void fp_overlay_hands(fp_render *r, const fp_session *s, const fp_tip_cues *cues,
                      const float pv[16], const float view[16]);

/** Colour the shown shape by the session's rig regions (skull blue, jaw red, soft tissue
 *  green blending to red by its jaw weight) through fp_render_set_colors; n: the mesh's
 *  vertex count (nothing done where the rig's differs, or without a rig). */
void fp_overlay_rig_colors(fp_render *r, const fp_session *s, size_t n);

/** The rig's landmarks on pos (the shape drawn, n x 3; NULL: nothing) as points and the
 *  hinge axis through the two joints, over the face; w x h: the framebuffer. */
void fp_overlay_rig(fp_render *r, const fp_session *s, const float *pos, size_t n,
                    const float pv[16], int w, int h);

/** The height fp_overlay_rig_legend draws at scale (pixels). */
float fp_overlay_rig_legend_height(float scale);

/** The rig overlay's legend at (8, y), each name in its colour, the rows that fit in room
 *  pixels of height (a short window: the first ones, none where its heading and one row do
 *  not fit); returns the height
 *  drawn. */
float fp_overlay_rig_legend(fp_render *r, const fp_session *s, int w, int h, float y, float scale,
                            float room);

#endif
