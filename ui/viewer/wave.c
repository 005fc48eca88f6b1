/* The soundtrack's waveform on the viewer's timeline (wave.h). */
#include "wave.h"
#include "takes.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int fp_vwave_init(fp_vwave *w, const fp_soundtrack *st, double offset_s)
{
    memset(w, 0, sizeof *w);
    if (!st || !st->frames || st->rate <= 0) return 0;
    const double start = offset_s > 0 ? offset_s : 0;
    w->length_s = (double)st->frames / st->rate - start;
    if (w->length_s <= 0) return 0;
    w->n = (size_t)ceil(w->length_s / FP_VWAVE_BLOCK_S);
    if (!(w->peak = calloc(w->n, sizeof *w->peak))) {
        w->n = 0;
        return -ENOMEM;
    }
    const size_t ch = (size_t)st->channels;
    const uint64_t first = (uint64_t)llround(start * st->rate);
    for (uint64_t k = first; k < st->frames; k++) {
        size_t b = (size_t)((double)(k - first) / st->rate / FP_VWAVE_BLOCK_S);
        if (b >= w->n) break;
        for (size_t c = 0; c < ch; c++) {
            float a = fabsf(st->samples[k * ch + c]);
            if (a > w->peak[b]) w->peak[b] = a > 1 ? 1 : a;
        }
    }
    return 0;
}

void fp_vwave_free(fp_vwave *w)
{
    free(w->peak);
    memset(w, 0, sizeof *w);
}

bool fp_vwave_on(const fp_vwave *w) { return w && w->n > 0; }

void fp_vwave_draw(const fp_vwave *w, fp_render *r, int fbw, int fbh, float x, float y, float lw,
                   float lh, float scale, double span_s, double t_s)
{
    static const float bg[4] = {0.05f, 0.05f, 0.07f, 0.7f}, white[4] = {0.95f, 0.95f, 0.92f, 1.f},
                       wave[4] = {0.3f, 0.85f, 0.95f, 1.f}, head[4] = {1.f, 0.85f, 0.2f, 1.f};
    if (!fp_vwave_on(w)) return;
    const float lx = x + FP_VWAVE_LABEL_PX * scale, bw = lw - FP_VWAVE_LABEL_PX * scale;
    fp_render_rect(r, fbw, fbh, x, y, lw, lh - 2, bg);
    fp_render_text(r, fbw, fbh, x + 3, y + 2, scale * 0.8f, "soundtrack", white);
    if (!(span_s > 0) || bw < 1) return;
    const size_t cols = (size_t)bw;
    float *xywh = malloc(cols * 4 * sizeof *xywh);
    size_t n = 0;
    const float mid = y + (lh - 2) / 2, half = (lh - 6) / 2;
    for (size_t c = 0; xywh && c < cols; c++) { /* the largest peak under each pixel column */
        size_t a = (size_t)(span_s * (double)c / (double)cols / FP_VWAVE_BLOCK_S);
        size_t b = (size_t)(span_s * (double)(c + 1) / (double)cols / FP_VWAVE_BLOCK_S);
        float p = 0;
        for (size_t k = a; k <= b && k < w->n; k++) p = fmaxf(p, w->peak[k]);
        if (p <= 0) continue;
        float hh = fmaxf(1, p * half);
        float *o = xywh + 4 * n++;
        o[0] = lx + (float)c, o[1] = mid - hh, o[2] = 1, o[3] = 2 * hh;
    }
    if (xywh) fp_render_rects(r, fbw, fbh, xywh, n, wave);
    free(xywh);
    if (isfinite(t_s) && t_s >= 0) {
        float px = lx + bw * (float)fmin(1, t_s / span_s);
        fp_render_rect(r, fbw, fbh, px - scale, y, 2 * scale, lh - 2, head);
    }
}

void fp_vwave_draw_lane(const fp_vwave *w, fp_render *r, int fbw, int fbh, double t_s)
{
    if (!fp_vwave_on(w)) return;
    float scale = fbh >= 600 ? 2.f : 1.f, x, y, sw, sh;
    fp_vtakes_strip_rect(fbw, fbh, &x, &y, &sw, &sh);
    const float lh = 12 * scale;
    double span = isfinite(t_s) && t_s > w->length_s ? t_s : w->length_s;
    fp_vwave_draw(w, r, fbw, fbh, x, y - 8 * scale - lh, sw, lh, scale, span, t_s);
}
