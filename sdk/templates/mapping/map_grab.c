/*
 * map-grab: a complete facepuppet mapping plugin, a template to copy.
 *
 * The face is grabbed by the fingertips of one or both hands: on engage (pedal, key E, or a
 * fingertip within R/2 of the surface when auto=1: a start point at the support's edge would
 * hold the surface where the Wendland function is ~0) each fingertip's position becomes a start
 * point; every frame the end points are start + gain x (fingertip now - fingertip at engage).
 * The start points stay fixed for the whole gesture, so the host reuses its factorization.
 * Commit (pedal, key C) folds the shape into the base; cancel (X) drops it.
 *
 * Everything a plugin needs is in <facepuppet/plugin.h>; <facepuppet/mapping_util.h> adds
 * header-only helpers (keys from a typed table, the paper's activation rule). Read
 * docs/plugin-guide.md (installed under share/doc/facepuppet) for threads, units, capacities
 * and errors.
 *
 * SPDX-License-Identifier: CC0-1.0 (copy it freely)
 */
#include <facepuppet/mapping_util.h>
#include <facepuppet/plugin.h>

#include <errno.h>
#include <stdlib.h>
#include <string.h>

typedef struct grab {
    fp_mapping mapping;            /* what the host calls through; plugin_data points back */
    unsigned hands;                /* FP_HANDMASK_* */
    double gain;
    bool automatic;
    bool engaged;
    size_t count;
    int hand_of[FP_HANDS * FP_FINGERS];
    float start[FP_HANDS * FP_FINGERS][3];
} grab;

/* [session-thread]: no allocation, no I/O, no locks. */
static int process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    grab *g = self->plugin_data;
    out->active = false;
    out->intents = 0;
    out->count = 0;
    out->channel_count = 0;
    out->radius = in->radius;
    if (g->engaged && (in->requested & FP_INTENT_CANCEL)) {
        g->engaged = false;
        out->intents = FP_INTENT_CANCEL; /* back to the base */
        return 0;
    }
    if (!g->engaged) {
        bool asked = in->requested & FP_INTENT_ENGAGE;
        g->count = 0;
        for (int h = 0; h < FP_HANDS; h++) {
            if (!(g->hands & (1u << h)) || !in->hands[h].present) continue;
            if (!asked && !(g->automatic && fp_hand_is_near(in, h, 0.5))) continue;
            float tips[FP_FINGERS][3];
            fp_hand_tips(in, h, tips);
            for (int f = 0; f < FP_FINGERS; f++, g->count++) {
                memcpy(g->start[g->count], tips[f], sizeof tips[f]);
                g->hand_of[g->count] = h;
            }
        }
        if (!g->count) return 0;
        g->engaged = true;
        out->intents |= FP_INTENT_ENGAGE;
    }
    if (g->count > out->capacity) return -ENOSPC; /* never write past the host's arrays */
    for (size_t i = 0; i < g->count; i++) {
        const fp_hand_pose *hand = &in->hands[g->hand_of[i]];
        const float *tip = hand->joints[FP_JOINT_TIP(i % FP_FINGERS)];
        for (int k = 0; k < 3; k++) {
            out->start[i][k] = g->start[i][k];
            out->end[i][k] = hand->present ? (float)(g->start[i][k] + g->gain * (tip[k] - g->start[i][k]))
                                           : g->start[i][k];
        }
        fp_clamp_vector(out->start[i], out->end[i], 0.45 * in->radius); /* no fold-over */
    }
    out->count = g->count;
    out->active = true;
    if (in->requested & FP_INTENT_COMMIT) { /* this frame's shape becomes the base */
        out->intents |= FP_INTENT_COMMIT;
        g->engaged = false;
    }
    return 0;
}

static void reset(fp_mapping *self) { ((grab *)self->plugin_data)->engaged = false; }
static void destroy(fp_mapping *self) { free(self->plugin_data); }

/* The keys, typed: `facepuppet plugins` prints them and fpmu_params_parse checks them. */
enum { KEY_HANDS, KEY_GAIN, KEY_AUTO, KEY_COUNT };
static const fp_param_info keys[KEY_COUNT + 1] = {
    {.name = "hands", .type = FP_PARAM_ENUM, .default_value = "both", .choices = "left|right|both",
     .description = "which hands grab"},
    {.name = "gain", .type = FP_PARAM_FLOAT, .min = 0, .max = 10, .default_value = "1.0",
     .description = "how far the face follows the fingers"},
    {.name = "auto", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "1",
     .description = "engage when a fingertip touches the face"},
    {.name = NULL},
};

/* [main-thread] */
static int create(const fp_host *host, const fp_param *params, size_t nparams, fp_mapping **out,
                  char *err, size_t errlen)
{
    (void)host;
    static const unsigned masks[] = {FP_HANDMASK_LEFT, FP_HANDMASK_RIGHT, FP_HANDMASK_BOTH};
    fpmu_value v[KEY_COUNT];
    int rc = fpmu_params_parse("grab", keys, params, nparams, v, err, errlen);
    if (rc) return rc;
    grab *g = calloc(1, sizeof *g);
    if (!g) return -ENOMEM;
    g->hands = masks[(int)v[KEY_HANDS].number];
    g->gain = v[KEY_GAIN].number;
    g->automatic = v[KEY_AUTO].number != 0;
    g->mapping.size = sizeof g->mapping;
    g->mapping.plugin_data = g;
    g->mapping.process = process;
    g->mapping.reset = reset;
    g->mapping.destroy = destroy;
    *out = &g->mapping;
    return 0;
}

static const fp_mapping_factory factory = {
    .size = sizeof(fp_mapping_factory),
    .name = "grab",
    .description = "template: the fingertips grab the face; gain scales how far it follows",
    .usage = "grab[,hands=left|right|both][,gain=F][,auto=0|1]",
    .create = create,
    .params = keys,
};

static const void *get_factory(const char *id)
{
    return !strcmp(id, FP_MAPPING_FACTORY_ID) ? &factory : NULL;
}

/* The one exported symbol. */
FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.example.map-grab",
    .version = "1.0",
    .get_factory = get_factory,
};
