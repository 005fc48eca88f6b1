/* fuzz_stack.c: libFuzzer target for stacks (core/take/stack.c, docs/stack.md): the .fpstack
 * JSON (fp_stack_parse) and the command line's --layer REGION[:MODE] (fp_stack_layer_spec),
 * both on every input. A refusal: -EBADMSG or -ENOMEM (-EINVAL for a spec) with a message,
 * the stack's starting with its name. A stack taken: 1 to FP_STACK_MAX_LAYERS layers, the base
 * the whole face in replace mode, each layer's numbers in their documented ranges, a region
 * of one kind (its names or vertices as counted, each vertex below 2^24), and written, read and
 * written again the same text. A region taken from a spec: the same region rules.
 * Seeds: tests/fuzz/corpus/fuzz_stack. */
#define _POSIX_C_SOURCE 200809L
#include "fp_stack.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_region(const fp_stack_region *r)
{
    if (!(r->core_mm >= 0) || !(r->falloff_mm >= 0) || !isfinite(r->core_mm) || !isfinite(r->falloff_mm)) abort();
    if (r->name_count > FP_STACK_MAX_NAMES) abort();
    for (size_t i = 0; i < r->name_count; i++)
        if (!r->names[i][0] || !memchr(r->names[i], 0, FP_STACK_NAME_MAX)) abort();
    if (!memchr(r->name, 0, sizeof r->name)) abort();
    switch (r->kind) {
    case FP_STACK_REGION_ALL:
        if (r->vertex_count || r->name_count) abort();
        break;
    case FP_STACK_REGION_RIG:
        if (r->name_count != 1 || r->vertex_count) abort();
        break;
    case FP_STACK_REGION_LANDMARKS:
    case FP_STACK_REGION_CHANNELS:
        if (!r->name_count || r->vertex_count) abort();
        break;
    case FP_STACK_REGION_VERTICES:
        if (!r->vertex_count || r->vertex_count > FP_STACK_MAX_GROUP || !r->vertices || r->name_count) abort();
        for (size_t i = 0; i < r->vertex_count; i++)
            if (r->vertices[i] >= 16777216u) abort();
        break;
    default:
        abort();
    }
    char text[256];
    if (fp_stack_region_text(r, text, sizeof text) != text || !memchr(text, 0, sizeof text)) abort();
}

static void check_stack(const fp_stack *s)
{
    if (s->layer_count < 1 || s->layer_count > FP_STACK_MAX_LAYERS) abort();
    for (size_t i = 0; i < s->layer_count; i++) {
        const fp_stack_layer *l = &s->layers[i];
        if (!memchr(l->take, 0, sizeof l->take)) abort();
        if (i == 0 && (l->region.kind != FP_STACK_REGION_ALL || l->mode != FP_STACK_REPLACE)) abort();
        if (l->mode != FP_STACK_REPLACE && l->mode != FP_STACK_ADD) abort();
        if (!isfinite(l->in_s) || !(l->out_s >= l->in_s) || !(l->fade_s >= 0) || !isfinite(l->offset_s) ||
            !(l->gain >= 0 && l->gain <= 2))
            abort();
        check_region(&l->region);
        char path[FP_STACK_PATH_MAX];
        int rc = fp_stack_take_path(s, i, path, sizeof path);
        if (rc && rc != -ENAMETOOLONG) abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *name = "fuzz.fpstack";
    char err[1024];
    fp_stack *s = NULL;
    int rc = fp_stack_parse((const char *)data, size, name, &s, err, sizeof err);
    if (rc) {
        if (s || (rc != -EBADMSG && rc != -ENOMEM) || strncmp(err, name, strlen(name))) abort();
    } else {
        check_stack(s);
        char *j1 = fp_stack_to_json(s);
        if (!j1) abort();
        fp_stack *t = NULL;
        if (fp_stack_parse(j1, strlen(j1), name, &t, err, sizeof err)) abort();
        check_stack(t);
        char *j2 = fp_stack_to_json(t);
        if (!j2 || strcmp(j1, j2)) abort();
        free(j1);
        free(j2);
        fp_stack_free(&t);
        fp_stack_free(&s);
    }
    /* the same bytes as a --layer spec (up to the first NUL) */
    char *spec = malloc(size + 1);
    if (!spec) abort();
    memcpy(spec, data, size);
    spec[size] = 0;
    fp_stack_region r;
    fp_stack_mode m;
    err[0] = 0;
    rc = fp_stack_layer_spec(spec, &r, &m, err, sizeof err);
    if (rc) {
        if (rc != -EINVAL && rc != -ENOMEM) abort();
        if (!err[0]) abort();
    } else {
        if (m != FP_STACK_REPLACE && m != FP_STACK_ADD) abort();
        check_region(&r);
        fp_stack_region_clear(&r);
    }
    free(spec);
    return 0;
}
