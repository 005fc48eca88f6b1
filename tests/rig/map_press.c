/* Test fixture mapping "press" (map-press.so, built into build/tests/plugins): it reads the
 * session's rig through FP_HOST_EXT_RIG at create (refusing to work without one) and, every
 * frame, presses control vectors into the forehead: start points on the surface above the
 * four brow landmarks (0, 1.5 and 3 cm up, nearest base vertex), end points `depth` mm into
 * the face along -forward; it drives jaw.open = `jaw` (jaw=none: leaves the channel to the
 * host) and, with bogus=1, a channel the rig lacks. Engages on its first frame; commits on
 * frame `commit` (-1: never).
 * With at=lips, one finger on each lip middle and mouth corner instead.
 * Keys: jaw=F|none, depth=F (mm), commit=N, bogus=0|1, at=forehead|lips. */
#include <facepuppet/plugin.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct press {
    fp_mapping mapping;
    float jaw, depth_mm;
    long commit;
    int bogus;
    int lips; /* at=lips: one finger on each lip middle and mouth corner */
    const fp_rig_view *rig;
    long frames;
} press;

static int process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    press *p = self->plugin_data;
    const fp_rig_view *rig = in->rig;
    if (!rig || rig != p->rig || in->mm_per_unit <= 0) return -ENODEV;
    static const char *const brows[] = {"brow_left", "brow_right", "brow_inner_left", "brow_inner_right"};
    static const char *const lips[] = {"upper_lip", "lower_lip", "mouth_corner_left", "mouth_corner_right"};
    const char *const *targets = p->lips ? lips : brows;
    int rows = p->lips ? 1 : 3;
    out->count = 0;
    for (size_t b = 0; b < 4; b++) {
        const fp_rig_landmark *l = NULL;
        for (size_t i = 0; i < rig->landmark_count; i++)
            if (!strcmp(rig->landmarks[i].name, targets[b])) l = &rig->landmarks[i];
        if (!l) return -ENOENT;
        for (int k = 0; k < rows; k++) {
            float q[3], best = INFINITY;
            size_t bi = 0;
            for (int c = 0; c < 3; c++) q[c] = l->position[c] + in->face_up[c] * 15.0f * k / (float)in->mm_per_unit;
            for (size_t v = 0; v < in->mesh->vertex_count; v++) {
                const float *x = &in->mesh->base[3 * v];
                float d = (x[0] - q[0]) * (x[0] - q[0]) + (x[1] - q[1]) * (x[1] - q[1]) + (x[2] - q[2]) * (x[2] - q[2]);
                if (d < best) best = d, bi = v;
            }
            float *s = out->start[out->count], *e = out->end[out->count];
            for (int c = 0; c < 3; c++) {
                s[c] = in->mesh->base[3 * bi + c];
                e[c] = s[c] - in->face_forward[c] * p->depth_mm / (float)in->mm_per_unit;
            }
            out->count++;
        }
    }
    out->radius = in->radius;
    out->active = true;
    out->intents = p->frames == 0 ? FP_INTENT_ENGAGE : 0;
    if (p->frames == p->commit) out->intents |= FP_INTENT_COMMIT;
    out->channel_count = 0;
    if (!isnan(p->jaw)) {
        snprintf(out->channels[out->channel_count].name, sizeof out->channels[0].name, "jaw.open");
        out->channels[out->channel_count++].value = p->jaw;
    }
    if (p->bogus && out->channel_capacity > 1) {
        snprintf(out->channels[out->channel_count].name, sizeof out->channels[0].name, "brow.raise");
        out->channels[out->channel_count++].value = 1;
    }
    p->frames++;
    return 0;
}

static void reset(fp_mapping *self) { ((press *)self->plugin_data)->frames = 0; }
static void destroy(fp_mapping *self) { free(self->plugin_data); }

static int create(const fp_host *host, const fp_param *params, size_t nparams, fp_mapping **out,
                  char *err, size_t errlen)
{
    const fp_host_rig *ext = host->get_extension ? host->get_extension(host, FP_HOST_EXT_RIG) : NULL;
    const fp_rig_view *rig = ext ? ext->get(host) : NULL;
    if (!rig) {
        snprintf(err, errlen, "press: the host offers no rig (%s)", ext ? "get returned NULL" : "no extension");
        return -ENODEV;
    }
    press *p = calloc(1, sizeof *p);
    if (!p) return -ENOMEM;
    p->jaw = 1, p->depth_mm = 8, p->commit = -1, p->rig = rig;
    for (size_t i = 0; i < nparams; i++) {
        if (!strcmp(params[i].key, "jaw")) p->jaw = !strcmp(params[i].value, "none") ? NAN : strtof(params[i].value, NULL);
        else if (!strcmp(params[i].key, "depth")) p->depth_mm = strtof(params[i].value, NULL);
        else if (!strcmp(params[i].key, "commit")) p->commit = strtol(params[i].value, NULL, 10);
        else if (!strcmp(params[i].key, "bogus")) p->bogus = atoi(params[i].value);
        else if (!strcmp(params[i].key, "at") && (!strcmp(params[i].value, "lips") || !strcmp(params[i].value, "forehead")))
            p->lips = !strcmp(params[i].value, "lips");
        else {
            snprintf(err, errlen, "press: unknown key %s", params[i].key);
            free(p);
            return -EINVAL;
        }
    }
    p->mapping.size = sizeof p->mapping;
    p->mapping.plugin_data = p;
    p->mapping.process = process;
    p->mapping.reset = reset;
    p->mapping.destroy = destroy;
    *out = &p->mapping;
    return 0;
}

static const fp_mapping_factory factory = {
    .size = sizeof(fp_mapping_factory),
    .name = "press",
    .description = "test fixture: fingers pressing into the forehead, jaw.open driven",
    .usage = "press[,jaw=F][,depth=MM][,commit=N][,bogus=0|1][,at=forehead|lips]",
    .create = create,
};

static const void *get_factory(const char *id) { return !strcmp(id, FP_MAPPING_FACTORY_ID) ? &factory : NULL; }

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.test.map-press",
    .version = "1.0",
    .get_factory = get_factory,
};
