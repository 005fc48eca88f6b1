/* wave.h: the soundtrack's waveform on the viewer's timeline (internal to ui/viewer; issue 54
 * item 4): a lane above the take strip, its label "soundtrack", the soundtrack's peaks from
 * its offset on (a take's time 0) as columns, and the playhead. The peaks are computed once
 * (the largest |sample| of every 10 ms, over the channels), so a frame draws at most one
 * column a pixel in one draw call.
 *
 * Threads: the viewer's. */
#ifndef FP_UI_WAVE_H
#define FP_UI_WAVE_H

#include "fp_audio.h"
#include "render.h"

#include <stdbool.h>
#include <stddef.h>

#define FP_VWAVE_BLOCK_S 0.01
#define FP_VWAVE_LABEL_PX 150  /* the lanes' label column, x scale (overdub.c's too) */

typedef struct fp_vwave {
    float *peak;        /* n blocks of FP_VWAVE_BLOCK_S from the offset on, in [0, 1] */
    size_t n;
    double length_s;    /* the soundtrack from the offset to its end */
} fp_vwave;

/** The peaks of st from offset_s seconds on (NULL st: none, *w zeroed). Returns 0 or
 *  -ENOMEM. */
int fp_vwave_init(fp_vwave *w, const fp_soundtrack *st, double offset_s);
void fp_vwave_free(fp_vwave *w);
/** Whether there is a waveform to draw. */
bool fp_vwave_on(const fp_vwave *w);

/** One lane at (x, y), lw x lh pixels: the label, then the peaks of [0, span_s] seconds in
 *  the rest (centred on the lane's middle, in the waveform's colour), and a playhead at t_s
 *  (NAN: none). */
void fp_vwave_draw(const fp_vwave *w, fp_render *r, int fbw, int fbh, float x, float y, float lw,
                   float lh, float scale, double span_s, double t_s);

/** The lane alone, just above the take strip (fp_vtakes_strip_rect), over the soundtrack's
 *  length (or t_s, when longer): the timeline without a stack (overdub.h draws it under the
 *  layers' lanes otherwise). */
void fp_vwave_draw_lane(const fp_vwave *w, fp_render *r, int fbw, int fbh, double t_s);

#endif
