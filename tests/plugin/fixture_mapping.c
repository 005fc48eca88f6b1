/* Mapping fixtures for `facepuppet plugins check`, the host's protections and hot reload, one
 * behaviour each, selected at compile time:
 *   (none)                 A: engages while a hand is present: five control vectors from the
 *                             fingertips, moved by `gain` x 0.01 along +z; version "A"
 *   FIXTURE_B              B: the same file name's next build: never engages; version "B"
 *   FIXTURE_OVERRUN        writes capacity + 2 control vectors, claims count = capacity
 *   FIXTURE_NAN            a NaN end point while active
 *   FIXTURE_SLOW           process busy-waits 5 ms
 *   FIXTURE_NO_INSTANCE    create returns 0 without an instance
 *   FIXTURE_SEGV           process dereferences a null pointer from frame 3 on
 *   FIXTURE_SPIN           process spins forever on its 30th call (SIGTERM's watchdog)
 *   FIXTURE_EXIT           process calls exit(0) on frame 3 (the checker's guard)
 *   FIXTURE_ABORT          create calls abort() (SIGABRT: the guard; an isolated create)
 *   FIXTURE_PRINT          A, printing a line to stdout in create and in every process (an
 *                             isolated helper's stdout is facepuppet's stderr)
 *   FIXTURE_ENGINE_FAIL    A with a support radius of 1e20 (finite and positive, but past the
 *                             engine's [1e-15, 1e15]: the host refuses it as the mapping's
 *                             error every frame, before the engine or a take sees it)
 *   FIXTURE_EXTRA_WRITE    A, and writes into the host's const extra_hands (ABI 1.3)
 *   FIXTURE_EXTRA_READ     A, and a control vector from every further hand the ABI allows
 *                             (FP_PERFORMER_CAPACITY - 1 performers), not the extra_performers
 *                             given (ABI 1.3)
 *   FIXTURE_UNDERWRITE     A, and from frame 3 writes the 7 entries before its start array
 *                          (in a helper: the shared control set's scalars, its capacity
 *                          among them) and claims a count of 10 million (isolated runs only)
 *   FIXTURE_ERR_FILL       create fills err to its very end (no NUL) and fails
 *   FIXTURE_OOM            A, and create logs its process's oom_score_adj
 *   FIXTURE_NO_PROCESS     A whose instance has no process() (NULL)
 *   FIXTURE_NO_NAME        its factory has no name (a broken factory, not a missing one)
 *   FIXTURE_ABI_MAJOR=2    built for ABI 2.0; FIXTURE_ABI_MINOR=3: 1.3 (else 1.0) */
#define _POSIX_C_SOURCE 200809L
#include <facepuppet/mapping_util.h>
#include <facepuppet/plugin.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef FIXTURE_ABI_MAJOR
#define FIXTURE_ABI_MAJOR FP_PLUGIN_ABI_MAJOR
#endif
#ifndef FIXTURE_ABI_MINOR
#define FIXTURE_ABI_MINOR 0
#endif
#ifdef FIXTURE_B
#define FIXTURE_VERSION "B"
#else
#define FIXTURE_VERSION "A"
#endif

typedef struct fixture {
    fp_mapping mapping;
    double gain;
    unsigned long calls;   /* process calls so far */
} fixture;

static int process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    fixture *fx = self->plugin_data;
#ifdef FIXTURE_SLOW
    struct timespec t0, t;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    do clock_gettime(CLOCK_MONOTONIC, &t);
    while ((t.tv_sec - t0.tv_sec) * 1e9 + (t.tv_nsec - t0.tv_nsec) < 5e6);
#endif
#ifdef FIXTURE_SPIN
    if (++fx->calls == 30)
        for (volatile unsigned long spin = 0;; spin++) {} /* never returns */
#else
    fx->calls++;
#endif
#ifdef FIXTURE_EXIT
    if (in->frame == 3) exit(0);
#endif
#ifdef FIXTURE_PRINT
    printf("fixture-print: stdout of process, frame %llu\n", (unsigned long long)in->frame);
    fflush(stdout);
#endif
#ifdef FIXTURE_SEGV
    if (in->frame >= 3) {
        volatile int *volatile nowhere = (int *)16; /* not NULL: UBSan would stop that first */
        *nowhere = 1;
    }
#endif
    out->active = false;
    out->intents = 0;
    out->count = 0;
    out->channel_count = 0;
    out->radius = in->radius;
#ifdef FIXTURE_B
    return 0;
#endif
    for (int h = 0; h < FP_HANDS; h++) {
        if (!in->hands[h].present) continue;
        float tips[FP_FINGERS][3];
        fp_hand_tips(in, h, tips);
        for (int f = 0; f < FP_FINGERS && out->count < out->capacity; f++) {
            memcpy(out->start[out->count], tips[f], sizeof tips[f]);
            memcpy(out->end[out->count], tips[f], sizeof tips[f]);
            out->end[out->count][2] += (float)(0.01 * fx->gain * in->radius);
            out->count++;
        }
        out->active = true;
    }
#ifdef FIXTURE_ENGINE_FAIL
    out->radius = 1e20;
#endif
#ifdef FIXTURE_NAN
    if (out->active) out->end[0][1] = NAN;
#endif
#ifdef FIXTURE_EXTRA_WRITE
    if (FP_HAS_FIELD(in, fp_frame_input, extra_tip_distance) && in->extra_performers && in->extra_hands)
        ((fp_hand_pose *)in->extra_hands)[0].joints[0][0] += 1; /* (the host's, const) */
#endif
#ifdef FIXTURE_EXTRA_READ
    if (FP_HAS_FIELD(in, fp_frame_input, extra_tip_distance) && in->extra_hands)
        for (int h = 0; h < FP_HANDS * (FP_PERFORMER_CAPACITY - 1) && out->count < out->capacity; h++) {
            if (!in->extra_hands[h].present) continue; /* past extra_performers x FP_HANDS too */
            memcpy(out->start[out->count], in->extra_hands[h].joints[FP_JOINT_TIP(1)], sizeof out->start[0]);
            memcpy(out->end[out->count], out->start[out->count], sizeof out->end[0]);
            out->end[out->count++][2] += (float)(0.01 * in->radius);
            out->active = true;
        }
#endif
#ifdef FIXTURE_UNDERWRITE
    if (in->frame >= 3) { /* (isolated only: in process this is the host's heap) */
        for (int i = -7; i < 0; i++) out->start[i][0] = out->start[i][1] = out->start[i][2] = 1e30f;
        out->count = 10000000;
    }
#endif
#ifdef FIXTURE_OVERRUN
    for (size_t i = 0; i < out->capacity + 2; i++) {
        out->start[i][0] = out->end[i][0] = 0.1f * (float)i;
        out->start[i][1] = out->end[i][1] = out->start[i][2] = out->end[i][2] = 0;
    }
    out->count = out->capacity;
    out->active = true;
#endif
    return 0;
}

static void reset(fp_mapping *self) { (void)self; }
static void destroy(fp_mapping *self) { free(self->plugin_data); }

static const fp_param_info keys[] = {
    {"gain", FP_PARAM_FLOAT, 0, 10, "1", NULL, "R/100", "how far the fingertips push"},
    {NULL, 0, 0, 0, NULL, NULL, NULL, NULL},
};

static int create(const fp_host *host, const fp_param *params, size_t nparams, fp_mapping **out,
                  char *err, size_t errlen)
{
    fpmu_value v[1];
    int rc = fpmu_params_parse("fixture", keys, params, nparams, v, err, errlen);
    if (rc) return rc;
#ifdef FIXTURE_ABORT
    abort();
#endif
#ifdef FIXTURE_ERR_FILL
    memset(err, 'E', errlen);
    return -22;
#endif
#ifdef FIXTURE_PRINT
    printf("fixture-print: stdout of create\n");
    fflush(stdout);
#endif
#ifdef FIXTURE_NO_INSTANCE
    (void)host;
    (void)process;
    (void)reset;
    (void)destroy;
    return 0;
#else
    fixture *fx = calloc(1, sizeof *fx);
    if (!fx) return -12;
    fx->gain = v[0].number;
    fx->mapping.size = sizeof fx->mapping;
    fx->mapping.plugin_data = fx;
    fx->mapping.process = process;
    fx->mapping.reset = reset;
    fx->mapping.destroy = destroy;
#ifdef FIXTURE_NO_PROCESS
    fx->mapping.process = NULL;
#endif
    *out = &fx->mapping;
    if (host && host->log) host->log(host, FP_LOG_INFO, "fixture " FIXTURE_VERSION " created");
#ifdef FIXTURE_OOM
    char adj[32] = "?";
    FILE *f = fopen("/proc/self/oom_score_adj", "r");
    if (f && fgets(adj, sizeof adj, f)) adj[strcspn(adj, "\n")] = '\0';
    if (f) fclose(f);
    char line[64];
    snprintf(line, sizeof line, "oom_score_adj %s", adj);
    if (host && host->log) host->log(host, FP_LOG_INFO, line);
#endif
    return 0;
#endif
}

static const fp_mapping_factory factory = {
    .size = sizeof(fp_mapping_factory),
#ifndef FIXTURE_NO_NAME
    .name = "fixture",
#endif
    .description = "test fixture (build " FIXTURE_VERSION ")",
    .usage = "fixture[,gain=F]",
    .create = create,
    .params = keys,
};

static const void *get_factory(const char *id)
{
    return !strcmp(id, FP_MAPPING_FACTORY_ID) ? &factory : NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    {FIXTURE_ABI_MAJOR, FIXTURE_ABI_MINOR}, "org.facepuppet.test.map-fixture", FIXTURE_VERSION, NULL, NULL, get_factory,
};
