/* The key list's layout (hud.h, fp_hud_help_layout): the largest scale, the fullest form and
 * the fewest columns at which the whole list fits the window, so that every key stays
 * readable in a narrow or short window (before: wrapped to the width alone, and cut off at
 * the bottom where the wrapped lines outgrew the height, under about 290 px wide). */
#define _GNU_SOURCE
#include "hud.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define HELP_GAP 12.f /* between two columns, at scale 1 */

/* text with its alignment dropped: no blank at a line's start, a run of blanks as two (one
 * between a key and its words would read as one phrase). Returns a new string or NULL. */
static char *compact(const char *text)
{
    char *out = malloc(strlen(text) + 1);
    if (!out) return NULL;
    size_t o = 0;
    bool start = true;
    for (const char *p = text; *p; p++) {
        if (*p == ' ' && (start || (o >= 2 && out[o - 1] == ' ' && out[o - 2] == ' '))) continue;
        out[o++] = *p;
        start = *p == '\n';
    }
    out[o] = '\0';
    return out;
}

/* Split text's lines in two near the middle (at a line's end): the first column's length. */
static size_t half(const char *text)
{
    size_t lines = 1;
    for (const char *p = text; *p; p++) lines += *p == '\n';
    size_t want = (lines + 1) / 2, seen = 0;
    for (const char *p = text; *p; p++)
        if (*p == '\n' && ++seen == want) return (size_t)(p - text);
    return strlen(text);
}

void fp_hud_help_layout_free(fp_hud_help_layout *l)
{
    for (int c = 0; c < 2; c++) {
        free(l->text[c]);
        l->text[c] = NULL;
    }
}

/* text in `columns` columns at scale s and pad, wrapped to the window's width: into *l;
 * whether it fits the window. */
static bool try_layout(const char *text, int w, int h, float s, float pad, int columns, fp_hud_help_layout *l)
{
    fp_hud_help_layout_free(l);
    memset(l, 0, sizeof *l);
    l->scale = s;
    l->pad = pad;
    l->columns = columns;
    const float gap = HELP_GAP * s, room = (float)w - 4 * pad - (float)(columns - 1) * gap;
    if (room < 8 * s) return false;
    size_t len = strlen(text), cut = columns == 2 ? half(text) : len;
    float width = 0, height = 0;
    for (int c = 0; c < columns; c++) {
        const char *part = c ? text + cut + (cut < len) : text;
        size_t n = c ? len - cut : cut, cap = 2 * n + 64;
        char *one = strndup(part, n);
        l->text[c] = malloc(cap);
        if (!one || !l->text[c]) {
            free(one);
            return false;
        }
        fp_hud_wrap(one, room / (float)columns, s, l->text[c], cap);
        free(one);
        l->col_x[c] = pad + width + (c ? gap : 0);
        width += (c ? gap : 0) + fp_render_text_width(l->text[c], s);
        height = fmaxf(height, fp_render_text_height(l->text[c], s));
    }
    l->w = width + 2 * pad;
    l->h = height + 2 * pad;
    l->x = floorf(((float)w - l->w) / 2);
    l->y = floorf(fmaxf(0, ((float)h - l->h) / 2));
    return l->w <= (float)w && l->h <= (float)h;
}

int fp_hud_help_layout_make(const char *text, int w, int h, float scale, fp_hud_help_layout *l)
{
    memset(l, 0, sizeof *l);
    char *tight = compact(text);
    if (!tight) return -1;
    const char *forms[2] = {text, tight};
    const float scales[2] = {scale, 1.f};
    for (int k = 0; k < (scale > 1.f ? 2 : 1); k++) /* the viewer's scale, then the smallest */
        for (int f = 0; f < 2; f++)                   /* as written, then without alignment */
            for (int columns = 1; columns <= 2; columns++) /* one column, then two */
                for (int p = 0; p < 2; p++) {         /* the usual padding, then a thin one */
                    float s = scales[k];
                    if (try_layout(forms[f], w, h, s, p ? 3 * s : 10 * s, columns, l)) {
                        l->fits = true;
                        free(tight);
                        return 0;
                    }
                }
    /* none fits: the smallest, compact, in one column, from the top (the bottom cut) */
    bool ok = try_layout(tight, w, h, 1.f, 3.f, 1, l) || l->text[0];
    free(tight);
    return ok ? 0 : -1;
}
