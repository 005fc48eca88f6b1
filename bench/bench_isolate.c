/* `bench --case frame`, the isolated mapping's cost (issue 56, item 4): the same paced replay
 * (three-claps, 60 frames a second, the frame case's mapping) on the same mesh, first with
 * the mapping in process, then in a helper process (fp_session_options.isolate = all); the
 * median of the frame's mapping stage (the mapping's call and the rig) of each, their
 * difference (the isolation's overhead a frame: the frame input and the control set copied,
 * the mesh's base among them, and the two wake-ups) and ratio, and the helper's resident
 * memory. Both runs in this one process, one after the other. */
#define _GNU_SOURCE
#include "fp_bench.h"

#include "fp_isolate.h"
#include "fp_mesh.h"
#include "fp_session.h"
#include "fp_stats.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* The resident memory of this process's first child (the helper), KiB; -1 where none. */
static long child_rss_kib(void)
{
    char path[64], buf[256];
    snprintf(path, sizeof path, "/proc/self/task/%d/children", (int)getpid());
    FILE *f = fopen(path, "r");
    int pid = 0;
    if (f) {
        if (fscanf(f, "%d", &pid) != 1) pid = 0;
        fclose(f);
    }
    if (pid <= 0) return -1;
    snprintf(path, sizeof path, "/proc/%d/status", pid);
    if (!(f = fopen(path, "r"))) return -1;
    long kib = -1;
    while (fgets(buf, sizeof buf, f))
        if (sscanf(buf, "VmRSS: %ld kB", &kib) == 1) break;
    fclose(f);
    return kib;
}

/* One paced replay; the mapping stage's and the whole frame's medians, ms. */
static int paced(const fp_bench_options *bo, const fp_mesh *mesh, const char *input, int isolate,
                 double *mapping_ms, double *frame_ms, size_t *frames, long *helper_kib)
{
    fp_session_options so = {0};
    so.mesh = mesh;
    so.inputs[0] = input;
    so.input_count = 1;
    so.mapping = bo->mapping ? bo->mapping : "anchored";
    so.plugin_path = bo->plugin_path;
    so.no_contact_guard = bo->no_contact_guard;
    so.exact_frames = bo->exact_frames;
    if (bo->no_rig) so.rig_path = "none";
    so.isolate = isolate;
    char err[1024];
    fp_session *s = NULL;
    int rc = fp_session_create(&so, &s, err, sizeof err);
    if (!rc) rc = fp_session_start(s, err, sizeof err);
    if (rc) {
        fprintf(stderr, "bench: frame, isolation: %s\n", err);
        fp_session_destroy(&s);
        return rc;
    }
    enum { CAP = 4096 };
    double *map = malloc(CAP * sizeof *map), *whole = malloc(CAP * sizeof *whole);
    size_t n = 0;
    int64_t period = 1000000000LL / 60, next = fp_now_ns();
    while (map && whole && !fp_session_finished(s) && n < CAP) {
        fp_frame_stats st;
        int64_t a = fp_now_ns();
        fp_session_step(s, a, &st);
        whole[n] = (double)(fp_now_ns() - a) / 1e6;
        map[n++] = st.stage_ms[FP_STAGE_MAPPING];
        if (n == 60) *helper_kib = isolate ? child_rss_kib() : -1;
        next += period;
        int64_t now = fp_now_ns();
        if (next > now) {
            struct timespec ts = {(time_t)((next - now) / 1000000000LL), (long)((next - now) % 1000000000LL)};
            nanosleep(&ts, NULL);
        } else {
            next = now;
        }
    }
    rc = map && whole ? 0 : -ENOMEM;
    *frames = n;
    *mapping_ms = n ? fp_percentile(map, n, 0.5) : 0;
    *frame_ms = n ? fp_percentile(whole, n, 0.5) : 0;
    free(map);
    free(whole);
    fp_session_destroy(&s);
    return rc;
}

int fp_bench_isolate(FILE *out, const fp_bench_options *bo, const fp_mesh *mesh, const char *label,
                     const char *data_dir, bool json)
{
    char input[4300];
    snprintf(input, sizeof input, "replay:%s/hands/leap-motion/three-claps_joints_mm.csv", data_dir);
    double map[2], whole[2];
    size_t frames[2];
    long kib = -1, none = -1;
    int rc = paced(bo, mesh, input, FP_ISOLATE_NONE, &map[0], &whole[0], &frames[0], &none);
    if (!rc) rc = paced(bo, mesh, input, FP_ISOLATE_ALL, &map[1], &whole[1], &frames[1], &kib);
    if (rc) return rc;
    double over_us = (map[1] - map[0]) * 1e3, ratio = map[0] > 0 ? map[1] / map[0] : 0;
    if (json)
        fprintf(out, "{\"case\":\"frame-isolation\",\"mesh\":\"%s\",\"vertices\":%zu,\"mapping\":\"%s\","
                "\"frames\":[%zu,%zu],\"mapping_ms_median_in_process\":%.6g,\"mapping_ms_median_isolated\":%.6g,"
                "\"overhead_us_median\":%.4g,\"ratio\":%.4g,\"frame_ms_median_in_process\":%.6g,"
                "\"frame_ms_median_isolated\":%.6g,\"helper_rss_kib\":%ld}\n",
                label, mesh->vertex_count, bo->mapping ? bo->mapping : "anchored", frames[0], frames[1],
                map[0], map[1], over_us, ratio, whole[0], whole[1], kib);
    else
        fprintf(out,
                "frame %-14s isolation (%s; %zu and %zu frames at 60 fps, one run after the other):\n"
                "  mapping stage median   %8.4f ms in process, %8.4f ms isolated: overhead %.1f us a "
                "frame (x%.2f)\n"
                "  whole frame median     %8.4f ms in process, %8.4f ms isolated; helper process "
                "resident memory %ld KiB\n",
                label, bo->mapping ? bo->mapping : "anchored", frames[0], frames[1], map[0], map[1], over_us,
                ratio, whole[0], whole[1], kib);
    fflush(out);
    return 0;
}

int fp_bench_isolate_small(FILE *out, const fp_bench_options *bo, const char *data_dir, bool json)
{
    char path[4300], err[512];
    snprintf(path, sizeof path, "%s/faces/mediapipe-canonical/canonical_face_model.obj", data_dir);
    fp_mesh *m = NULL;
    if (fp_mesh_load(path, &m, err, sizeof err)) {
        fprintf(stderr, "bench: %s\n", err);
        return -ENOENT;
    }
    int rc = fp_bench_isolate(out, bo, m, "mediapipe", data_dir, json);
    fp_mesh_free(&m);
    return rc;
}
