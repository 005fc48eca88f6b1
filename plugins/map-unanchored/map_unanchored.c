/*
 * map-unanchored: the unanchored mapping of Sato, Savchenko, Ohbuchi (Cyberworlds 2004,
 * sec. 2.3.2). Every frame runs a small deformation from the last fingertip positions
 * (start points) to the new ones (end points) and folds it into the base, so the surface
 * follows the fingers' trajectories: large drags become compositions of small steps.
 *
 * A hand acts while one of its fingertips is within the support radius of the surface
 * (the paper's rule; auto=0 turns it off), or while the performer holds the deformation
 * engaged (FP_INTENT_ENGAGE until FP_INTENT_COMMIT or _CANCEL). Each step is already in the
 * base, so cancel only ends the gesture; it cannot take steps back.
 *
 * Every performer's hands step (ABI 1.3, fp_frame_input.extra_hands: two right hands from two
 * performers are two hands); hands= picks the sides for all of them. A later performer's hand
 * whose points no longer fit the control set (points=all: more than three hands) is left out.
 *
 * Keys: hands=left|right|both (both), auto=0|1 (1), clamp=F (0.45, longest step in R),
 *       points=tips|tips+palm|all (5, 11 or 21 points per hand, mapping_util.h fp_points).
 */
#include <facepuppet/mapping_util.h>
#include <facepuppet/plugin.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct unanchored {
    fp_mapping mapping;
    unsigned hands;
    bool automatic;
    double clamp;
    int points;                                /* fp_points mode */
    bool held;                                 /* engaged by request */
    bool have_last[FP_MAX_FRAME_HANDS];        /* by fp_frame_hand_count's index */
    float last[FP_MAX_FRAME_HANDS][FP_POINTS_MAX][3];
} unanchored;

static int process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    unanchored *u = self->plugin_data;
    out->active = false;
    out->intents = 0;
    out->count = 0;
    out->channel_count = 0;
    out->radius = in->radius;
    if (in->requested & FP_INTENT_ENGAGE) {
        u->held = true;
        out->intents |= FP_INTENT_ENGAGE;
    }
    if (in->requested & (FP_INTENT_COMMIT | FP_INTENT_CANCEL)) u->held = false;
    size_t k = 0;
    int nh = fp_frame_hand_count(in);
    for (int h = 0; h < nh; h++) { /* every performer's hands: side h % FP_HANDS */
        if (!(u->hands & (1u << (h % FP_HANDS))) || !fp_frame_hand(in, h)->present) {
            u->have_last[h] = false;
            continue;
        }
        bool acts = u->held || (u->automatic && fp_hand_is_near(in, h, 1.0));
        float pts[FP_POINTS_MAX][3];
        size_t n = fp_hand_points(in, h, u->points, pts);
        if (acts && u->have_last[h] && out->capacity < k + n && h >= FP_HANDS) {
            u->have_last[h] = false; /* a later performer's hand past the capacity: left out */
            continue;
        }
        if (acts && u->have_last[h]) {
            if (out->capacity < k + n) return -ENOSPC;
            for (size_t f = 0; f < n; f++, k++) {
                memcpy(out->start[k], u->last[h][f], sizeof pts[f]);
                memcpy(out->end[k], pts[f], sizeof pts[f]);
                fp_clamp_vector(out->start[k], out->end[k], u->clamp * in->radius);
            }
        }
        memcpy(u->last[h], pts, n * sizeof pts[0]);
        u->have_last[h] = true;
    }
    out->count = k;
    if (k) {
        out->active = true;
        out->intents |= FP_INTENT_COMMIT; /* every step folds into the base */
    }
    return 0;
}

static void reset(fp_mapping *self)
{
    unanchored *u = self->plugin_data;
    u->held = false;
    memset(u->have_last, 0, sizeof u->have_last);
}

static void destroy(fp_mapping *self)
{
    free(self->plugin_data);
}

/* The keys, typed (ABI 1.1). */
enum { KEY_HANDS, KEY_AUTO, KEY_CLAMP, KEY_POINTS, KEY_COUNT };
static const fp_param_info keys[KEY_COUNT + 1] = {
    {.name = "hands", .type = FP_PARAM_ENUM, .default_value = "both", .choices = "left|right|both",
     .description = "which hands deform"},
    {.name = "auto", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "1",
     .description = "a hand acts while a fingertip is within R of the surface"},
    {.name = "clamp", .type = FP_PARAM_FLOAT, .min = 0, .max = 100, .default_value = "0.45",
     .unit = "R", .description = "longest step (0: no limit)"},
    {.name = "points", .type = FP_PARAM_ENUM, .default_value = "tips", .choices = FP_POINTS_CHOICES,
     .description = "points of contact per hand: the 5 tips, + palm centre and knuckles (11), every joint (21)"},
    {.name = NULL},
};
static const unsigned hand_masks[] = {FP_HANDMASK_LEFT, FP_HANDMASK_RIGHT, FP_HANDMASK_BOTH};

static int create(const fp_host *host, const fp_param *params, size_t nparams,
                  fp_mapping **out, char *err, size_t errlen)
{
    (void)host;
    fpmu_value v[KEY_COUNT];
    int rc = fpmu_params_parse("unanchored", keys, params, nparams, v, err, errlen);
    if (rc) return rc;
    unanchored *u = calloc(1, sizeof *u);
    if (!u) return -ENOMEM;
    u->hands = hand_masks[(int)v[KEY_HANDS].number];
    u->automatic = v[KEY_AUTO].number != 0;
    u->clamp = v[KEY_CLAMP].number;
    u->points = (int)v[KEY_POINTS].number;
    u->mapping.size = sizeof u->mapping;
    u->mapping.plugin_data = u;
    u->mapping.process = process;
    u->mapping.reset = reset;
    u->mapping.destroy = destroy;
    *out = &u->mapping;
    return 0;
}

static const fp_mapping_factory factory = {
    .size = sizeof(fp_mapping_factory),
    .name = "unanchored",
    .description = "the paper's unanchored mode: each step from the last fingertips to the new",
    .usage = "unanchored[,hands=left|right|both][,auto=0|1][,clamp=F][,points=tips|tips+palm|all]\n"
             "  a hand acts while a fingertip is within R of the surface (auto=1) or while\n"
             "  engaged; each step is folded into the base at once. points: the fingertips\n"
             "  (5 per hand), tips+palm (+ palm centre and knuckles: 11) or all (21 per hand).\n"
             "  Every performer's hands act (inputs' performer=NAME): hands= picks the sides.",
    .create = create,
    .params = keys,
};

static const void *get_factory(const char *id)
{
    return !strcmp(id, FP_MAPPING_FACTORY_ID) ? &factory : NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.map-unanchored",
    .version = "1.0",
    .get_factory = get_factory,
};
