/* A mapping written as a plugin author outside the project writes one (issue 56's tests of
 * isolation): built out of tree against the installed SDK by tests/plugin/test_isolate.sh,
 * and in tree for the soak. Each fingertip within the support radius of the face grabs the
 * skin nearest to it (the host's surface service: FP_HOST_EXT_SURFACE) and pulls it `gain`
 * of the way to the tip (no commit, nothing kept between frames), and on session frame `at` (default
 * 29, its 30th frame) it faults, by the build's FAULT_MODE:
 *   0 steady  never faults (the reference the others are compared with)
 *   1 crash   writes through a null pointer (SIGSEGV)
 *   2 hang    spins forever
 *   3 chaos   from frame `at` on, in each window of `mean` frames, at a random frame of its
 *             first half: a crash (40%), a hang (40%) or nothing (a xorshift of `seed` and
 *             the window's number)
 * With commit=1 each step is committed and its start read from the frame's mesh->base (the
 * test that an isolated mapping's copy of the base follows the commits). With overcount=1,
 * on the frame before `at` it returns an active set of count capacity + 1 (its first
 * capacity vectors written), which the host refuses (fp_control_check.h). With logs=N it
 * logs N lines at the start of each process (against plugin.h's rule: a log flood).
 * It keeps no state, so after a restart it deforms as it did before. */
#include <facepuppet/mapping_util.h>
#include <facepuppet/plugin.h>

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#ifndef FAULT_MODE
#define FAULT_MODE 0
#endif

typedef struct fault {
    fp_mapping mapping;
    const fp_host *host;
    const fp_host_surface *surface;
    double gain, at, mean, seed;
    double logs;
    bool commit, overcount;
} fault;

static void crash(void)
{
    volatile int *volatile nowhere = NULL;
    *nowhere = 1;
}

static void hang(void)
{
    for (volatile unsigned long spin = 0;; spin++) {}
}

static int process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    fault *f = self->plugin_data;
    for (double i = 0; i < f->logs && f->host->log; i++) /* (against the rule: a flood) */
        f->host->log(f->host, FP_LOG_INFO, "fault: a line logged from process");
    if (FAULT_MODE == 1 && in->frame == (uint64_t)f->at) crash();
    if (FAULT_MODE == 2 && in->frame == (uint64_t)f->at) hang();
    if (FAULT_MODE == 3 && in->frame >= (uint64_t)f->at) {
        /* one fault at most in each window of `mean` frames, at a random frame of its first
         * half: a crash (40%), a hang (40%) or none */
        uint64_t n = (uint64_t)(f->mean >= 2 ? f->mean : 2), w = (in->frame - (uint64_t)f->at) / n;
        uint64_t x = (uint64_t)f->seed * 0x9E3779B97F4A7C15ull + w * 0xBF58476D1CE4E5B9ull + 1;
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        if ((in->frame - (uint64_t)f->at) % n == x % (n / 2)) {
            unsigned kind = (unsigned)((x >> 32) % 10);
            if (kind < 4) crash();
            if (kind < 8) hang();
        }
    }
    out->active = false;
    out->intents = 0;
    out->count = 0;
    out->channel_count = 0;
    out->radius = in->radius;
    float tips[FP_HANDS * FP_FINGERS][3];
    size_t n = 0;
    for (int h = 0; h < FP_HANDS; h++) {
        if (!in->hands[h].present) continue;
        float t[FP_FINGERS][3];
        fp_hand_tips(in, h, t);
        for (int k = 0; k < FP_FINGERS; k++)
            if (in->tip_distance[h][k] < in->radius) memcpy(tips[n++], t[k], sizeof t[k]);
    }
    if (f->overcount && in->frame + 1 == (uint64_t)f->at) {
        for (size_t i = 0; i < out->capacity; i++)
            for (int k = 0; k < 3; k++) out->start[i][k] = out->end[i][k] = (float)k;
        out->count = out->capacity + 1;
        out->active = true;
        return 0;
    }
    if (!n || !f->surface) return 0;
    fp_surface_hit hits[FP_HANDS * FP_FINGERS];
    int rc = f->surface->nearest(f->host, (const float(*)[3])tips, n, (float)in->radius, hits);
    if (rc) return rc;
    for (size_t i = 0; i < n && out->count < out->capacity; i++) {
        if (hits[i].vertex == UINT32_MAX) continue;
        /* commit=1 reads the start from the frame's base (its copy, isolated) */
        const float *p = f->commit && in->mesh && in->mesh->base ? &in->mesh->base[3 * (size_t)hits[i].vertex]
                                                                  : hits[i].position;
        for (int k = 0; k < 3; k++) {
            out->start[out->count][k] = p[k];
            out->end[out->count][k] = p[k] + (float)f->gain * (tips[i][k] - p[k]);
        }
        out->count++;
    }
    out->active = out->count > 0;
    if (f->commit && out->active) out->intents = FP_INTENT_COMMIT; /* each step into the base */
    return 0;
}

static void destroy(fp_mapping *self) { free(self->plugin_data); }

static const fp_param_info keys[] = {
    {"gain", FP_PARAM_FLOAT, 0, 1, "0.5", NULL, NULL, "how far the skin follows the fingertip"},
    {"at", FP_PARAM_INT, 0, 1e9, "29", NULL, "frame", "the session frame of the (first) fault"},
    {"mean", FP_PARAM_INT, 2, 1e9, "240", NULL, "frames", "chaos: at most one fault in this many frames"},
    {"seed", FP_PARAM_INT, 0, 1e9, "1", NULL, NULL, "chaos: the random sequence"},
    {"commit", FP_PARAM_BOOL, 0, 1, "0", NULL, NULL, "commit each step, its start read from the frame's base"},
    {"overcount", FP_PARAM_BOOL, 0, 1, "0", NULL, NULL, "on the frame before `at`, a set over capacity"},
    {"logs", FP_PARAM_INT, 0, 1e6, "0", NULL, "lines", "log this many lines in each process, first"},
    {NULL, 0, 0, 0, NULL, NULL, NULL, NULL},
};

static int create(const fp_host *host, const fp_param *params, size_t nparams, fp_mapping **out,
                  char *err, size_t errlen)
{
    fpmu_value v[7];
    int rc = fpmu_params_parse("fault", keys, params, nparams, v, err, errlen);
    if (rc) return rc;
    fault *f = calloc(1, sizeof *f);
    if (!f) return -12;
    f->host = host;
    f->surface = host && host->get_extension ? host->get_extension(host, FP_HOST_EXT_SURFACE) : NULL;
    f->gain = v[0].number;
    f->at = v[1].number;
    f->mean = v[2].number;
    f->seed = v[3].number;
    f->commit = v[4].number != 0;
    f->overcount = v[5].number != 0;
    f->logs = v[6].number;
    f->mapping = (fp_mapping){.size = sizeof(fp_mapping), .plugin_data = f, .process = process,
                              .destroy = destroy};
    *out = &f->mapping;
    return 0;
}

static const fp_mapping_factory factory = {
    .size = sizeof(fp_mapping_factory),
    .name = "fault",
    .description = "pulls the skin to the fingertips; faults on a chosen frame (isolation tests)",
    .usage = "gain=G, at=FRAME, mean=N, seed=S, commit=0|1, overcount=0|1, logs=N",
    .create = create,
    .params = keys,
};

static const void *get_factory(const char *id)
{
    return strcmp(id, FP_MAPPING_FACTORY_ID) ? NULL : &factory;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.example.map-fault",
    .version = "1",
    .get_factory = get_factory,
};
