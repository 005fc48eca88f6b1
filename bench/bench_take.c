/* bench_take.c: what recording a take costs. (1) The session thread's share: the time of
 * fp_take_recorder_push per frame (median, p99, max) while the recorder thread writes the
 * take to disk; (2) a take's size per minute at 60 fps. The frame is the typical one of a
 * performance on the ICT face with two tracked hands: 10 control vectors (anchored mapping,
 * five fingertips a hand), and per frame one joint-positions and one wrist-pose event a hand
 * (the Leap recordings' rows), i.e. 4 events. */
#define _POSIX_C_SOURCE 200809L
#include "fp_bench.h"

#include "fp_take.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static int64_t now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

typedef struct bench_frame {
    fp_take_frame f;
    fp_control_set cs;
    float start[10][3], end[10][3];
    fp_event ev[4];
} bench_frame;

/* Frame n of a smooth made-up performance (values change every frame, as live ones do). */
static void make_frame(bench_frame *b, uint64_t n, int64_t t0)
{
    double t = (double)n / 60.0;
    b->cs.size = sizeof b->cs;
    b->cs.active = true;
    b->cs.radius = 2.4;
    b->cs.capacity = 10;
    b->cs.count = 10;
    b->cs.start = b->start;
    b->cs.end = b->end;
    for (int i = 0; i < 10; i++)
        for (int k = 0; k < 3; k++) {
            b->start[i][k] = (float)(i + 0.1 * k);
            b->end[i][k] = (float)(i + 0.1 * k + 0.3 * sin(t + i + k));
        }
    for (int i = 0; i < 4; i++) {
        fp_event *e = &b->ev[i];
        e->header.time_ns = t0 + (int64_t)n * 16666667 - 2000000;
        e->header.source = 0;
        e->header.hand = i & 1;
        if (i < 2) {
            e->header.type = FP_EVENT_JOINT_POSITIONS;
            e->header.size = sizeof e->positions;
            for (int j = 0; j < FP_HAND_JOINTS; j++)
                for (int k = 0; k < 3; k++)
                    e->positions.mm[j][k] = (float)(100 * sin(0.3 * t + j) + 10 * k);
        } else {
            e->header.type = FP_EVENT_WRIST_POSE;
            e->header.size = sizeof e->wrist;
            for (int k = 0; k < 3; k++) e->wrist.position_mm[k] = (float)(50 * cos(t + k));
            e->wrist.rotation[0] = 1.0f;
        }
    }
    b->f.frame = n;
    b->f.time_ns = t0 + (int64_t)n * 16666667;
    b->f.events = b->ev;
    b->f.event_count = 4;
    b->f.requested = 0;
    b->f.control = &b->cs;
}

static void header(fp_take_header *h)
{
    memset(h, 0, sizeof *h);
    snprintf(h->slate, sizeof h->slate, "bench");
    h->rate = (fp_take_rate){60, 1};
    h->mesh_path = "../shared/data/faces/ict/neutral.obj";
    h->mesh_vertices = 26719;
    h->mapping = "anchored";
    h->inputs[0] = "replay:three-claps_joints_mm.csv";
    h->input_count = 1;
    h->radius = 2.4;
}

static void rm_dir(const char *dir)
{
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd)) { /* best effort */ }
}

int fp_bench_take(FILE *out, int quick, int json)
{
    char dir[] = "/tmp/fp-bench-take-XXXXXX", err[512];
    if (!mkdtemp(dir)) {
        fprintf(stderr, "bench take: mkdtemp: %s\n", strerror(errno));
        return 1;
    }
    fp_take_header h;
    header(&h);

    /* (1) push cost, with the recorder thread writing (a chunk of what it took every 2 ms at
     * most, fdatasync every 0.25 s, as a take does).
     * Frames are offered at 4 kHz, faster than any session, so the ring and the writer are
     * busy while we time. */
    const int n = quick ? 4000 : 20000;
    int64_t *ns = malloc((size_t)n * sizeof *ns);
    bench_frame *b = calloc(1, sizeof *b);
    fp_take_recorder *rec;
    if (!ns || !b || fp_take_recorder_start(dir, &h, NULL, &rec, err, sizeof err)) {
        fprintf(stderr, "bench take: %s\n", ns && b ? err : "out of memory");
        free(ns);
        free(b);
        rm_dir(dir);
        return 1;
    }
    int64_t t0 = now_ns();
    struct timespec gap = {0, 250000};
    for (int i = 0; i < n; i++) {
        make_frame(b, (uint64_t)i, t0);
        int64_t a = now_ns();
        fp_take_recorder_push(rec, &b->f);
        ns[i] = now_ns() - a;
        nanosleep(&gap, NULL);
    }
    fp_take_recorder_status st;
    int rc = fp_take_recorder_close(&rec, &st, err, sizeof err);
    if (rc) {
        fprintf(stderr, "bench take: %s\n", err);
        free(ns);
        free(b);
        rm_dir(dir);
        return 1;
    }
    /* the clock's own cost, to subtract */
    int64_t clk[1000];
    for (int i = 0; i < 1000; i++) {
        int64_t a = now_ns();
        clk[i] = now_ns() - a;
    }
    qsort(clk, 1000, sizeof *clk, cmp_i64);
    qsort(ns, (size_t)n, sizeof *ns, cmp_i64);
    double med = (double)(ns[n / 2] - clk[500]) / 1e3, p99 = (double)(ns[(size_t)(0.99 * n)] - clk[500]) / 1e3;
    double mx = (double)(ns[n - 1] - clk[500]) / 1e3;

    /* (2) size of one minute at 60 fps: 3600 frames at 60 fps times through the writer with
     * the recorder's chunking at 60 fps (a chunk a frame: it writes what it took from the
     * ring every 2 ms at most, 20 bytes of chunk a frame). */
    size_t rec_size = fp_take_frame_size(&b->f);
    fp_take_writer_options wo = {.chunk_frames = 1, .no_sync = true};
    fp_take_writer *w;
    rc = fp_take_writer_create(dir, &h, &wo, &w, err, sizeof err);
    char path[600] = "";
    for (uint64_t i = 0; !rc && i < 3600; i++) {
        if (i == 0) snprintf(path, sizeof path, "%s", fp_take_writer_path(w));
        make_frame(b, i, t0);
        rc = fp_take_writer_add(w, &b->f, err, sizeof err);
    }
    if (!rc) rc = fp_take_writer_close(&w, 0, 0, err, sizeof err);
    struct stat sb;
    if (rc || stat(path, &sb)) {
        fprintf(stderr, "bench take: %s\n", rc ? err : strerror(errno));
        free(ns);
        free(b);
        rm_dir(dir);
        return 1;
    }
    double mb_min = (double)sb.st_size / 1e6;
    if (json)
        fprintf(out, "{\"case\":\"take\",\"push_median_us\":%.3f,\"push_p99_us\":%.3f,"
                "\"push_max_us\":%.3f,\"frames\":%d,\"dropped\":%llu,\"frame_bytes\":%zu,"
                "\"take_mb_per_minute_60fps\":%.3f}\n", med, p99, mx, n,
                (unsigned long long)st.dropped, rec_size, mb_min);
    else
        fprintf(out, "take     recorder push per frame (10 vectors, 4 events, %zu bytes): median "
                "%.3f us, p99 %.3f us, max %.1f us over %d frames (%llu dropped); take size at "
                "60 fps: %.2f MB per minute\n", rec_size, med, p99, mx, n,
                (unsigned long long)st.dropped, mb_min);
    free(ns);
    free(b);
    rm_dir(dir);
    return 0;
}
