/*
 * map-fixture-surface (tests only, build/tests/plugins): a mapping that asks the host's
 * FP_HOST_EXT_SURFACE service every frame and reports the answers in its control set (never
 * active, so nothing deforms), for test_guard's surface test:
 * query i (0..5) = base[(4409 i + 17) mod n] + (0.05, -0.02, 0.1) i, max_distance +inf;
 * query 6 = bounds_max + (1000, 0, 0) with max_distance 1 (no hit).
 * start[i] = hit position, end[i] = hit normal, channels[2i] = vertex (float, exact below
 * 2^24; -1 for none), channels[2i+1] = distance. create fails with -ENOTSUP when the host
 * does not offer the service.
 */
#include <facepuppet/plugin.h>

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NQ 7

typedef struct surf {
    fp_mapping mapping;
    const fp_host *host;
    const fp_host_surface *svc;
} surf;

static int process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    surf *f = self->plugin_data;
    out->active = false;
    out->intents = 0;
    out->count = 0;
    out->channel_count = 0;
    out->radius = in->radius;
    size_t n = in->mesh->vertex_count;
    if (out->capacity < NQ || out->channel_capacity < 2 * NQ || !n) return 0;
    float q[NQ][3];
    for (int i = 0; i < NQ - 1; i++) {
        const float *b = in->mesh->base + 3 * ((4409u * (unsigned)i + 17u) % n);
        q[i][0] = b[0] + 0.05f * i;
        q[i][1] = b[1] - 0.02f * i;
        q[i][2] = b[2] + 0.1f * i;
    }
    memcpy(q[NQ - 1], in->mesh->bounds_max, sizeof q[0]);
    q[NQ - 1][0] += 1000.f;
    fp_surface_hit hit[NQ];
    int rc = f->svc->nearest(f->host, (const float(*)[3])q, NQ - 1, INFINITY, hit);
    if (!rc) rc = f->svc->nearest(f->host, (const float(*)[3])&q[NQ - 1], 1, 1.0f, &hit[NQ - 1]);
    if (rc) return rc;
    for (int i = 0; i < NQ; i++) {
        memcpy(out->start[i], hit[i].position, sizeof hit[i].position);
        memcpy(out->end[i], hit[i].normal, sizeof hit[i].normal);
        strcpy(out->channels[2 * i].name, "vertex");
        out->channels[2 * i].value = hit[i].vertex == UINT32_MAX ? -1.f : (float)hit[i].vertex;
        strcpy(out->channels[2 * i + 1].name, "distance");
        out->channels[2 * i + 1].value = hit[i].distance;
    }
    out->count = NQ;
    out->channel_count = 2 * NQ;
    return 0;
}

static void destroy(fp_mapping *self) { free(self->plugin_data); }

static int create(const fp_host *host, const fp_param *params, size_t nparams, fp_mapping **out,
                  char *err, size_t errlen)
{
    (void)params;
    (void)nparams;
    (void)err;
    (void)errlen;
    const fp_host_surface *svc = host->get_extension ? host->get_extension(host, FP_HOST_EXT_SURFACE) : NULL;
    if (!svc || !svc->nearest) return -ENOTSUP;
    surf *f = calloc(1, sizeof *f);
    if (!f) return -ENOMEM;
    f->host = host;
    f->svc = svc;
    f->mapping.size = sizeof f->mapping;
    f->mapping.plugin_data = f;
    f->mapping.process = process;
    f->mapping.destroy = destroy;
    *out = &f->mapping;
    return 0;
}

static const fp_mapping_factory factory = {
    .size = sizeof(fp_mapping_factory),
    .name = "fixture-surface",
    .description = "tests: asks the host's surface service",
    .usage = "fixture-surface",
    .create = create,
};

static const void *get_factory(const char *id)
{
    return !strcmp(id, FP_MAPPING_FACTORY_ID) ? &factory : NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.test.map-fixture-surface",
    .version = "1.0",
    .get_factory = get_factory,
};
