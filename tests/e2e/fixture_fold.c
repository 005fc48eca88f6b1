/*
 * map-fixture-fold (tests only, build/tests/plugins): a mapping that ignores the hands and
 * pulls two close points of the face apart, a configuration known to fold (csrbf.md
 * pitfall 4: two centres 0.1 R apart with opposite control vectors of 0.44 R give
 * coefficients near 5 R, ten times the fold-over bound, although each control vector is
 * under the mappings' 0.45 R clamp).
 *
 * The two start points sit 0.05 R either side (along x) of the base vertex farthest along +z
 * (the nose tip on the three faces). Frame k of a gesture (k = 1..10) pulls them apart by
 * k/10 of 0.44 R each; frame 10 commits; after `gap` idle frames a new gesture begins.
 * Keys: commit=0|1 (0: anchored, start points fixed for the gesture, commit at frame 10;
 * 1: unanchored, each frame from the last end points to the new, committed at once).
 */
#include <facepuppet/plugin.h>

#include <errno.h>
#include <stdlib.h>
#include <string.h>

typedef struct fold {
    fp_mapping mapping;
    int every_frame;
    unsigned k;                 /* frame within the cycle */
    float centre[3];
    float last[2][3];
} fold;

static int process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    fold *f = self->plugin_data;
    out->active = false;
    out->intents = 0;
    out->count = 0;
    out->channel_count = 0;
    out->radius = in->radius;
    unsigned k = f->k++ % 14; /* 10 frames of gesture, 4 idle */
    if (k == 0) {             /* a new gesture on the current base */
        const float *b = in->mesh->base;
        size_t best = 0;
        for (size_t v = 1; v < in->mesh->vertex_count; v++)
            if (b[3 * v + 2] > b[3 * best + 2]) best = v;
        memcpy(f->centre, b + 3 * best, sizeof f->centre);
        float h = (float)(0.05 * in->radius);
        for (int i = 0; i < 2; i++) {
            memcpy(f->last[i], f->centre, sizeof f->centre);
            f->last[i][0] += i ? h : -h;
        }
    }
    if (k >= 10 || out->capacity < 2) return 0;
    float pull = (float)(0.44 * in->radius * (k + 1) / 10.0), h = (float)(0.05 * in->radius);
    for (int i = 0; i < 2; i++) {
        float sign = i ? 1.f : -1.f;
        memcpy(out->start[i], f->centre, sizeof f->centre);
        out->start[i][0] += sign * h;
        memcpy(out->end[i], out->start[i], sizeof f->centre);
        out->end[i][0] += sign * pull;
        if (f->every_frame) {
            memcpy(out->start[i], f->last[i], sizeof f->centre);
            memcpy(f->last[i], out->end[i], sizeof f->centre);
        }
    }
    out->count = 2;
    out->active = true;
    if (k == 0) out->intents |= FP_INTENT_ENGAGE;
    if (f->every_frame || k == 9) out->intents |= FP_INTENT_COMMIT;
    return 0;
}

static void destroy(fp_mapping *self) { free(self->plugin_data); }

static int create(const fp_host *host, const fp_param *params, size_t nparams, fp_mapping **out,
                  char *err, size_t errlen)
{
    (void)host;
    (void)err;
    (void)errlen;
    fold *f = calloc(1, sizeof *f);
    if (!f) return -ENOMEM;
    for (size_t i = 0; i < nparams; i++)
        if (!strcmp(params[i].key, "commit")) f->every_frame = atoi(params[i].value) != 0;
    f->mapping.size = sizeof f->mapping;
    f->mapping.plugin_data = f;
    f->mapping.process = process;
    f->mapping.destroy = destroy;
    *out = &f->mapping;
    return 0;
}

static const fp_mapping_factory factory = {
    .size = sizeof(fp_mapping_factory),
    .name = "fixture-fold",
    .description = "tests: two close points pulled apart (a fold without the guard)",
    .usage = "fixture-fold[,commit=0|1]",
    .create = create,
};

static const void *get_factory(const char *id)
{
    return !strcmp(id, FP_MAPPING_FACTORY_ID) ? &factory : NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.test.map-fixture-fold",
    .version = "1.0",
    .get_factory = get_factory,
};
