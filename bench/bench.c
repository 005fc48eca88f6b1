/* facepuppet bench: medians of the CSRBF engine's per-update time on the paper's Table 1
 * set-up (Sato, Savchenko, Ohbuchi, Cyberworlds 2004), a 1M-vertex grid and large centre
 * sets, each beside a reference measured in the same run (a plain scalar brute-force loop,
 * or a fresh factorisation). */
#define _GNU_SOURCE /* getloadavg, sched_setaffinity */
#include "fp_bench.h"
#ifdef FP_BENCH_HAVE_LINK
#include "fp_stream.h"
#endif
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include "csrbf.h"
#include "fp_error.h"
#include "fp_stats.h"
#include "fp_mesh.h"
#include "fp_rig.h"
#include "fp_session.h"
#include "step_engine.h"

#include <errno.h>
#include <inttypes.h>
#include <fcntl.h>
#include <math.h>
#include <sched.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

typedef struct {
    int quick, json, rounds;
} bench_opts;

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

/* ------------------------------------------------------------------------ the set-up */

/* The paper's Table 1 (csrbf.md): fps and (vertex, centre) pairs, 10 control vectors. */
static const int table_vertices[4] = {1089, 4225, 16641, 33025};
static const double table_radius[5] = {10, 20, 40, 60, 80};
static const double paper_anchored_fps[4][5] = {{496.3, 502.1, 499.2, 427.4, 423.6},
                                                {162.6, 138.0, 119.7, 113.1, 112.0},
                                                {41.3, 34.8, 30.0, 28.2, 28.0},
                                                {20.0, 16.7, 14.4, 13.6, 13.4}};
static const long paper_pairs[4][5] = {{698, 2414, 7342, 10124, 10890},
                                       {2646, 9526, 28686, 39476, 42250},
                                       {10510, 37562, 113282, 115812, 166410},
                                       {20790, 74482, 225714, 309476, 330250}};
static const double paper_unanchored_fps[4][5] = {{446.3, 427.6, 380.2, 367.0, 364.0},
                                                  {132.6, 114.4, 101.5, 97.5, 96.1},
                                                  {32.9, 28.2, 24.9, 23.9, 23.4},
                                                  {15.9, 13.5, 11.9, 11.4, 10.9}};

/* A planar grid over [0, 64]^2 (z = 0) with exactly nv vertices: the square grids 33^2,
 * 65^2, 129^2 of the paper and, for 33025 (no square; the paper's pair counts show twice the
 * density of 129^2), 129 x 256 plus one vertex at the centre. Generic nv: a near-square
 * grid, the remainder on the last row. */
static float *make_grid(size_t nv)
{
    size_t nx, ny;
    if (nv == 33025) {
        nx = 129;
        ny = 256;
    } else {
        nx = (size_t)llround(sqrt((double)nv));
        ny = nv / nx;
    }
    float *p = malloc(nv * 3 * sizeof *p);
    if (!p) return NULL;
    size_t k = 0;
    for (size_t j = 0; j < ny && k < nv; j++)
        for (size_t i = 0; i < nx && k < nv; i++, k++) {
            p[3 * k] = (float)(64.0 * i / (nx - 1));
            p[3 * k + 1] = (float)(64.0 * j / (ny - 1));
            p[3 * k + 2] = 0.0f;
        }
    for (size_t extra = 0; k < nv; k++, extra++) { /* the remainder, spread near the centre */
        p[3 * k] = (float)(32.0 + 0.1 * (double)extra);
        p[3 * k + 1] = 32.0f;
        p[3 * k + 2] = 0.0f;
    }
    return p;
}

/* Ten fingertips in two rows of five over the middle of the plane: x = 2, 17, ..., 62,
 * y = 21 and 43, z = 0, 0.1 or 0.2 (not coplanar, so that a linear polynomial is defined:
 * bench/peers feeds the same points to scipy). Fitted so that the pair counts on the 33^2,
 * 65^2 and 129^2 grids come within about 10% of the paper's; every vertex of [0, 64]^2 lies
 * within 80 of each. */
static void fingertips(float *start)
{
    for (int i = 0; i < 5; i++)
        for (int j = 0; j < 2; j++) {
            float *s = start + 3 * (2 * i + j);
            s[0] = 2.0f + 15.0f * (float)i;
            s[1] = j ? 43.0f : 21.0f;
            s[2] = 0.1f * (float)((2 * i + j) % 3);
        }
}

/* Frame f of a glove motion: each fingertip presses and slides a little (amplitude 0.6,
 * below the fold-over bound at R = 10). */
static void motion(const float *rest, float *out, int n, int frame, double amp)
{
    for (int i = 0; i < n; i++) {
        double ph = 0.7 * i + 0.05 * frame;
        out[3 * i] = rest[3 * i] + (float)(amp * 0.5 * sin(ph));
        out[3 * i + 1] = rest[3 * i + 1] + (float)(amp * 0.5 * cos(1.3 * ph));
        out[3 * i + 2] = rest[3 * i + 2] + (float)(amp * sin(0.9 * ph + 1.0));
    }
}

/* The reference: every (vertex, centre) pair, plain scalar double, no index, no threads. */
static void bruteforce(const csrbf_solver *s, size_t nv, const float *base, float *out,
                       double *cbuf, double *abuf, double R)
{
    size_t m = csrbf_solver_centres(s);
    csrbf_solver_get_coefficients(s, cbuf, abuf, NULL);
    for (size_t v = 0; v < nv; v++) {
        double x = base[3 * v], y = base[3 * v + 1], z = base[3 * v + 2];
        double tx = x, ty = y, tz = z;
        for (size_t j = 0; j < m; j++) {
            double dx = x - cbuf[3 * j], dy = y - cbuf[3 * j + 1], dz = z - cbuf[3 * j + 2];
            double r = sqrt(dx * dx + dy * dy + dz * dz) / R;
            if (r < 1.0) {
                double t = 1.0 - r, w = t * t * t * t * (4.0 * r + 1.0);
                tx += abuf[3 * j] * w;
                ty += abuf[3 * j + 1] * w;
                tz += abuf[3 * j + 2] * w;
            }
        }
        out[3 * v] = (float)tx;
        out[3 * v + 1] = (float)ty;
        out[3 * v + 2] = (float)tz;
    }
}

/* ------------------------------------------------------------------------ reporting */

typedef struct {
    const char *name, *mode;
    size_t vertices, centres;
    double radius;
    long pairs, paper_pairs;      /* -1: none */
    double ms, ms_brute, paper_fps; /* < 0: none */
    double ms_ref;                /* centres case: fresh factor-and-solve, else < 0 */
    double ms_touched;            /* the same update through csrbf_evaluate_touched with
                                     statistics (the session's evaluation); < 0: none */
    size_t written;               /* vertices the last touched update wrote (0: none) */
} row;

static void json_num(const char *key, double v, int last)
{
    if (v < 0)
        printf("\"%s\":null%s", key, last ? "" : ",");
    else
        printf("\"%s\":%.6g%s", key, v, last ? "" : ",");
}

static void print_header(const bench_opts *o)
{
    if (o->json) return;
    printf("%-8s %-10s %8s %7s %6s %9s %9s %10s %10s %8s %9s %9s %9s %9s\n", "case", "mode",
           "vertices", "centres", "R", "pairs", "paper", "ms_median", "ms_ref", "ratio",
           "paper_fps", "fps", "ms_touch", "fps_touch");
}

static void print_row(const bench_opts *o, const row *r)
{
    double ref = r->ms_brute >= 0 ? r->ms_brute : r->ms_ref;
    if (o->json) {
        printf("{\"case\":\"%s\",\"mode\":\"%s\",\"vertices\":%zu,\"centres\":%zu,", r->name,
               r->mode, r->vertices, r->centres);
        json_num("radius", r->radius, 0);
        if (r->pairs < 0)
            printf("\"pairs\":null,");
        else
            printf("\"pairs\":%ld,", r->pairs);
        if (r->paper_pairs < 0)
            printf("\"paper_pairs\":null,");
        else
            printf("\"paper_pairs\":%ld,", r->paper_pairs);
        json_num("ms_median", r->ms, 0);
        json_num("ms_bruteforce", r->ms_brute, 0);
        json_num("ms_fresh", r->ms_ref, 0);
        json_num("ms_touched", r->ms_touched, 0);
        json_num("paper_fps", r->paper_fps, 1);
        printf("}\n");
    } else {
        char pairs[32] = "-", paper[32] = "-", refs[32] = "-", ratio[32] = "-", pf[32] = "-";
        if (r->pairs >= 0) snprintf(pairs, sizeof pairs, "%ld", r->pairs);
        if (r->paper_pairs >= 0) snprintf(paper, sizeof paper, "%ld", r->paper_pairs);
        if (ref >= 0) {
            snprintf(refs, sizeof refs, "%.4f", ref);
            snprintf(ratio, sizeof ratio, "%.1fx", ref / r->ms);
        }
        if (r->paper_fps >= 0) snprintf(pf, sizeof pf, "%.1f", r->paper_fps);
        char mt[32] = "-", ft[32] = "-";
        if (r->ms_touched >= 0) {
            snprintf(mt, sizeof mt, "%.4f", r->ms_touched);
            snprintf(ft, sizeof ft, "%.0f", 1000.0 / r->ms_touched);
        }
        printf("%-8s %-10s %8zu %7zu %6g %9s %9s %10.4f %10s %8s %9s %9.0f %9s %9s\n", r->name,
               r->mode, r->vertices, r->centres, r->radius, pairs, paper, r->ms, refs, ratio, pf,
               1000.0 / r->ms, mt, ft);
    }
    fflush(stdout);
}

/* ------------------------------------------------------------------- deformation cases */

enum { NCTRL = 10, FRAMES = 64 };

typedef struct {
    csrbf_solver *s;
    csrbf_points *pts;
    csrbf_touch *touch; /* persistent output out2 (TIME_TOUCHED) */
    size_t nv;
    const float *base;
    float *out, *out2;
    double R;
    int anchored;
    float rest[3 * NCTRL];
} deform_case;

enum { TIME_ENGINE = 0, TIME_BRUTE = 1, TIME_TOUCHED = 2 };

/* Median ms of count timed updates (after warm-up ones): [set_start +] set_end + evaluate
 * (TIME_ENGINE: csrbf_evaluate writing every vertex, no statistics), + the brute-force loop
 * (TIME_BRUTE), or + csrbf_evaluate_touched with statistics into a persistent output
 * (TIME_TOUCHED: the session's evaluation). -1 on an engine error. */
static double time_updates(deform_case *c, int count, int brute, double *times)
{
    float st[3 * NCTRL], en[3 * NCTRL];
    double cbuf[3 * NCTRL], abuf[3 * NCTRL];
    int warm = brute == TIME_BRUTE ? 1 : (count < 20 ? 2 : count / 10);
    for (int it = -warm; it < count; it++) {
        int f = (it + warm) % FRAMES;
        motion(c->rest, en, NCTRL, f, 0.6);
        if (!c->anchored) {
            motion(c->rest, st, NCTRL, f + 17, 0.3); /* the start points move too */
            for (int i = 0; i < 3 * NCTRL; i++) en[i] += st[i] - c->rest[i];
        }
        double t0 = now_ms();
        if (!c->anchored && csrbf_solver_set_start_points(c->s, NCTRL, st) < 0) return -1;
        if (csrbf_solver_set_end_points(c->s, en) < 0) return -1;
        if (brute == TIME_ENGINE) {
            if (csrbf_evaluate(c->s, c->pts, c->out, 0, NULL) < 0) return -1;
        } else if (brute == TIME_TOUCHED) {
            csrbf_eval_stats es;
            if (csrbf_evaluate_touched(c->s, c->pts, c->touch, c->out2, 0, &es) < 0) return -1;
        } else {
            bruteforce(c->s, c->nv, c->base, c->out, cbuf, abuf, c->R);
        }
        double t1 = now_ms();
        if (it >= 0) times[it] = t1 - t0;
    }
    return fp_median(times, (size_t)count);
}

/* The row run_deform printed last. */
static row last_row;

/* One (grid, R, mode) measurement: engine median, brute-force median, one row. */
static int run_deform(const bench_opts *o, const char *name, size_t nv, double R, int anchored,
                      int reps, int brute_reps, double paper_fps, long paper_pair_count,
                      int touched)
{
    int rc = 0;
    deform_case c = {0};
    c.nv = nv;
    c.R = R;
    c.anchored = anchored;
    fingertips(c.rest);
    float *base = make_grid(nv);
    c.base = base;
    c.out = malloc(nv * 3 * sizeof *c.out);
    double *times = malloc((size_t)(reps > brute_reps ? reps : brute_reps) * sizeof *times);
    csrbf_options opt = {0};
    opt.radius = R;
    if (touched) c.out2 = malloc(nv * 3 * sizeof *c.out2);
    if (!base || !c.out || !times || (touched && !c.out2) || csrbf_solver_create(&opt, &c.s) ||
        csrbf_points_create(nv, base, &c.pts) || (touched && csrbf_touch_create(c.pts, &c.touch))) {
        fprintf(stderr, "bench: set-up failed for %s (%zu vertices)\n", name, nv);
        rc = -ENOMEM;
        goto done;
    }
    float en[3 * NCTRL];
    motion(c.rest, en, NCTRL, 0, 0.6);
    csrbf_eval_stats stats;
    if (csrbf_solver_set_start_points(c.s, NCTRL, c.rest) < 0 ||
        csrbf_solver_set_end_points(c.s, en) < 0 || csrbf_evaluate(c.s, c.pts, c.out, 0, &stats) < 0)
        goto engine_fail;
    if (R >= 80 && stats.pairs != nv * NCTRL)
        fprintf(stderr, "bench: R = %g leaves %zu of %zu pairs outside the support\n", R,
                nv * NCTRL - stats.pairs, nv * NCTRL);
    /* rounds: the machine is shared; each figure is the lowest of the rounds' medians */
    double ms = -1, msb = -1, mst = -1;
    for (int round = 0; round < o->rounds; round++) {
        double a = time_updates(&c, reps, TIME_ENGINE, times);
        if (a < 0) goto engine_fail;
        if (ms < 0 || a < ms) ms = a;
        if (brute_reps > 0) {
            double b = time_updates(&c, brute_reps, TIME_BRUTE, times);
            if (b < 0) goto engine_fail;
            if (msb < 0 || b < msb) msb = b;
        }
        if (touched) {
            double t = time_updates(&c, reps, TIME_TOUCHED, times);
            if (t < 0) goto engine_fail;
            if (mst < 0 || t < mst) mst = t;
        }
    }
    if (touched) { /* the persistent output equals a full evaluation of the last update */
        if (csrbf_evaluate(c.s, c.pts, c.out, 0, NULL) < 0) goto engine_fail;
        if (memcmp(c.out, c.out2, nv * 3 * sizeof *c.out)) {
            fprintf(stderr, "bench: touched output differs from the full evaluation\n");
            rc = FP_ENUMERIC;
            goto done;
        }
    }
    size_t written = 0; /* by the last touched update: its ranges */
    if (touched) {
        const uint32_t *rg;
        size_t nr = csrbf_touch_ranges(c.touch, &rg);
        for (size_t i = 0; i < nr; i++) written += rg[2 * i + 1];
    }
    row r = {name, anchored ? "anchored" : "unanchored", nv, NCTRL, R, (long)stats.pairs,
             paper_pair_count, ms, msb, paper_fps, -1, mst, written};
    print_row(o, &r);
    last_row = r;
done:
    csrbf_touch_destroy(&c.touch);
    csrbf_points_destroy(&c.pts);
    csrbf_solver_destroy(&c.s);
    free(base);
    free(c.out);
    free(c.out2);
    free(times);
    return rc;
engine_fail:
    fprintf(stderr, "bench: engine call failed: %s\n", csrbf_solver_message(c.s));
    rc = FP_ENUMERIC;
    goto done;
}

static int case_table1(const bench_opts *o)
{
    print_header(o);
    row at[2][2] = {{{0}}}; /* 33,025 vertices, [unanchored, anchored][R = 10, R = 80] */
    for (int g = 0; g < 4; g++)
        for (int anchored = 1; anchored >= 0; anchored--)
            for (int ri = 0; ri < 5; ri++) {
                size_t nv = (size_t)table_vertices[g];
                int reps = o->quick ? 300 : 2000;
                if (nv > 10000) reps /= 2;
                int brute = o->quick ? 5 : 21;
                fprintf(stderr, "bench: table1 %zu vertices R = %g %s\n", nv, table_radius[ri],
                        anchored ? "anchored" : "unanchored");
                double fps = anchored ? paper_anchored_fps[g][ri] : paper_unanchored_fps[g][ri];
                int rc = run_deform(o, "table1", nv, table_radius[ri], anchored, reps, brute, fps,
                                    paper_pairs[g][ri], 1);
                if (rc) return rc;
                if (g == 3 && (ri == 0 || ri == 4)) at[anchored][ri == 4] = last_row;
            }
    for (int anchored = 1; anchored >= 0; anchored--) {
        const row *r10 = &at[anchored][0], *r80 = &at[anchored][1];
        if (!o->json && r10->ms > 0 && r10->ms_touched > 0)
            printf("table1 33025 %s: R=80 / R=10 time = %.2fx (csrbf_evaluate), %.2fx "
                   "(touched, statistics); pairs %.1fx, vertices written (touched) %.2fx\n",
                   anchored ? "anchored" : "unanchored", r80->ms / r10->ms,
                   r80->ms_touched / r10->ms_touched,
                   r10->pairs > 0 ? (double)r80->pairs / (double)r10->pairs : 0.0,
                   r10->written ? (double)r80->written / (double)r10->written : 0.0);
    }
    /* The anchored update's least memory traffic: each written vertex's base read and position
     * write (12 bytes each) and one cached 4-byte weight per pair (the weight cache stores
     * whole 16-lane blocks, so this is a lower bound). Where both updates run at the same
     * bandwidth, their time ratio cannot pass this bytes ratio. */
    const row *a10 = &at[1][0], *a80 = &at[1][1];
    if (!o->json && a10->written && a80->written && a10->ms_touched > 0 && a80->ms_touched > 0) {
        double b10 = 24.0 * (double)a10->written + 4.0 * (double)a10->pairs,
               b80 = 24.0 * (double)a80->written + 4.0 * (double)a80->pairs;
        printf("table1 33025 anchored: least memory traffic of an update (12 B base read + 12 B "
               "position write a written vertex, 4 B weight a pair): R=80 %.2f MB, R=10 %.2f MB "
               "= %.2fx; at the touched medians R=80 moves %.0f GB/s, R=10 %.0f GB/s\n",
               b80 / 1e6, b10 / 1e6, b80 / b10, b80 / (a80->ms_touched * 1e6),
               b10 / (a10->ms_touched * 1e6));
    }
    return 0;
}

static int case_scale(const bench_opts *o)
{
    print_header(o);
    fprintf(stderr, "bench: scale, 1000 x 1000 grid, 10 control vectors, R = 80\n");
    return run_deform(o, "scale", 1000000, 80.0, 1, o->quick ? 40 : 200, o->quick ? 3 : 5, -1,
                      -1, 0);
}

/* Large centre sets (rig-like constraints): random centres at a density giving about 27
 * nonzeros a row of A (csrbf.md). Factor time (set_start_points), per-update time reusing the
 * factor (set_end_points), and a fresh factor-and-solve (csrbf_solver_solve). */
static int case_centres(const bench_opts *o)
{
    print_header(o);
    static const size_t sizes[2] = {1000, 5000};
    for (int si = 0; si < 2; si++) {
        size_t n = sizes[si];
        double side = 100.0 * cbrt((double)n / 5000.0), R = 10.9;
        fprintf(stderr, "bench: centres N = %zu\n", n);
        float *st = malloc(n * 3 * sizeof *st), *en = malloc(n * 3 * sizeof *en);
        unsigned long long x = 12345 + n;
        for (size_t i = 0; i < 3 * n; i++) {
            x = x * 6364136223846793005ull + 1442695040888963407ull;
            st[i] = (float)(side * (double)(x >> 11) * 0x1p-53);
        }
        int reps_f = o->quick ? 5 : 15, reps_u = o->quick ? 50 : 300;
        double *times = malloc((size_t)reps_u * sizeof *times);
        csrbf_options opt = {0};
        opt.radius = R;
        csrbf_solver *s = NULL;
        int rc = csrbf_solver_create(&opt, &s);
        for (int it = 0; it < reps_f && rc >= 0; it++) {
            double t0 = now_ms();
            rc = csrbf_solver_set_start_points(s, n, st);
            times[it] = now_ms() - t0;
        }
        double ms_factor = fp_median(times, (size_t)reps_f);
        for (int it = 0; it < reps_f && rc >= 0; it++) {
            for (size_t i = 0; i < 3 * n; i++) en[i] = st[i] + 0.3f * (float)sin(0.1 * (double)(i + 7 * it));
            double t0 = now_ms();
            rc = csrbf_solver_solve(s, n, st, en);
            times[it] = now_ms() - t0;
        }
        double ms_fresh = fp_median(times, (size_t)reps_f);
        for (int it = -5; it < reps_u && rc >= 0; it++) {
            for (size_t i = 0; i < 3 * n; i++) en[i] = st[i] + 0.3f * (float)sin(0.1 * (double)(i + 7 * it));
            double t0 = now_ms();
            rc = csrbf_solver_set_end_points(s, en);
            if (it >= 0) times[it] = now_ms() - t0;
        }
        double ms_reused = fp_median(times, (size_t)reps_u);
        if (rc < 0) {
            fprintf(stderr, "bench: engine call failed: %s\n", csrbf_solver_message(s));
            csrbf_solver_destroy(&s);
            free(st);
            free(en);
            free(times);
            return FP_ENUMERIC;
        }
        row f = {"centres", "factor", 0, csrbf_solver_centres(s), R, -1, -1, ms_factor, -1, -1,
                 -1, -1, 0};
        row u = {"centres", "reused", 0, csrbf_solver_centres(s), R, -1, -1, ms_reused, -1, -1,
                 ms_fresh, -1, 0};
        row fr = {"centres", "fresh", 0, csrbf_solver_centres(s), R, -1, -1, ms_fresh, -1, -1,
                  -1, -1, 0};
        print_row(o, &f);
        print_row(o, &fr);
        print_row(o, &u);
        csrbf_solver_destroy(&s);
        free(st);
        free(en);
        free(times);
    }
    return 0;
}

/* ------------------------------------------------------------- the fold-over guard */

/* Options of the guard case (kept apart from the command line, which lives elsewhere). */
typedef struct {
    int quick, json, rounds;
    const char *face; /* OBJ path; NULL: $FP_SHARED_DATA or ../shared/data, ICT FaceKit */
} guard_bench_opts;

/* m fingertip-like start points on the face: front-facing vertices (normal z > 0.5, in the
 * front 40% of the depth) nearest to targets on a grid over the middle of the face, pushed
 * 0.3 R inward along the normal, as a pressing fingertip is. */
static void face_fingertips(const fp_mesh *f, double R, int m, float *start)
{
    float lo[3], hi[3];
    fp_mesh_bounds(f, lo, hi);
    double zcut = lo[2] + 0.6 * (hi[2] - lo[2]);
    int cols = m >= 10 ? (m + 1) / 2 : m, rows = (m + cols - 1) / cols;
    if (m > 10) {
        cols = (int)ceil(sqrt(m * 1.5));
        rows = (m + cols - 1) / cols;
    }
    for (int i = 0; i < m; i++) {
        int r = i / cols, c = i % cols;
        double tx = lo[0] + (hi[0] - lo[0]) * (0.25 + 0.5 * (c + 0.5) / cols);
        double ty = lo[1] + (hi[1] - lo[1]) * (0.3 + 0.4 * (r + 0.5) / rows);
        size_t best = 0;
        double bd = INFINITY;
        for (size_t v = 0; v < f->vertex_count; v++) {
            const float *p = f->positions + 3 * v, *nn = f->normals + 3 * v;
            if (nn[2] < 0.5f || p[2] < zcut) continue;
            double d = (p[0] - tx) * (p[0] - tx) + (p[1] - ty) * (p[1] - ty);
            if (d < bd) {
                bd = d;
                best = v;
            }
        }
        for (int a = 0; a < 3; a++)
            start[3 * i + a] = f->positions[3 * best + a] - (float)(0.3 * R) * f->normals[3 * best + a];
    }
}

/* Frame f of a pressing, sliding hand over m fingertips (amplitude amp, mesh units). */
static void face_motion(const float *rest, float *out, int m, int frame, double amp)
{
    for (int i = 0; i < m; i++) {
        double ph = 0.7 * i + 0.05 * frame;
        out[3 * i] = rest[3 * i] + (float)(amp * 0.6 * sin(ph));
        out[3 * i + 1] = rest[3 * i + 1] + (float)(amp * 0.6 * cos(1.3 * ph));
        out[3 * i + 2] = rest[3 * i + 2] - (float)(amp * fabs(sin(0.9 * ph + 1.0)));
    }
}

/* Median ms of plain updates and guarded ones, interleaved frame by frame (same frames, same
 * run). anchored: set_end + evaluate vs set_end + limit + evaluate; unanchored: set_start +
 * set_end + evaluate vs csrbf_guarded_step. Counts the frames where the guard acted. */
static int guard_run(const guard_bench_opts *g, const fp_mesh *f, csrbf_points *pts, double R,
                     int m, int anchored, double amp)
{
    int reps = g->quick ? 400 : 2000, acted = 0, sub = 0;
    float *rest = malloc((size_t)m * 3 * sizeof *rest), *st = malloc((size_t)m * 3 * sizeof *st),
          *en = malloc((size_t)m * 3 * sizeof *en);
    float *out = malloc(f->vertex_count * 3 * sizeof *out);
    double *tp = malloc((size_t)reps * sizeof *tp), *tg = malloc((size_t)reps * sizeof *tg);
    csrbf_options opt = {0};
    opt.radius = R;
    csrbf_solver *sv[2] = {NULL, NULL}, *s = NULL; /* plain, guarded: each its own factor */
    int rc = !rest || !st || !en || !out || !tp || !tg ? CSRBF_ERR_NOMEM
                                                       : csrbf_solver_create(&opt, &sv[0]);
    if (rc >= 0) rc = csrbf_solver_create(&opt, &sv[1]);
    if (rc >= 0) {
        face_fingertips(f, R, m, rest);
        for (int k = 0; k < 2 && rc >= 0; k++)
            rc = csrbf_solver_set_start_points(sv[k], (size_t)m, rest);
    }
    double best_p = -1, best_g = -1, Lmax = 0;
    for (int round = 0; round < g->rounds && rc >= 0; round++) {
        acted = sub = 0;
        for (int it = -20; it < reps && rc >= 0; it++) {
            int fr = (it + 20) % 200;
            face_motion(rest, en, m, fr, amp);
            memcpy(st, rest, (size_t)m * 3 * sizeof *st);
            if (!anchored) { /* the start points move too: last frame's end points */
                face_motion(rest, st, m, fr - 1, amp);
            }
            for (int guarded = 0; guarded < 2 && rc >= 0; guarded++) {
                s = sv[guarded];
                double t0 = now_ms();
                csrbf_guard_stats gs;
                if (anchored) {
                    rc = csrbf_solver_set_end_points(s, en);
                    if (rc >= 0 && guarded) rc = csrbf_solver_limit_end_points(s, 0, &gs);
                    if (rc >= 0) rc = csrbf_evaluate(s, pts, out, 0, NULL);
                } else if (!guarded) {
                    rc = csrbf_solver_set_start_points(s, (size_t)m, st);
                    if (rc >= 0) rc = csrbf_solver_set_end_points(s, en);
                    if (rc >= 0) rc = csrbf_evaluate(s, pts, out, 0, NULL);
                } else {
                    csrbf_guard gd = {0};
                    rc = csrbf_guarded_step(s, pts, (size_t)m, st, en, &gd, out, &gs);
                }
                double t1 = now_ms();
                if (it >= 0) (guarded ? tg : tp)[it] = t1 - t0;
                if (guarded && rc >= 0 && it >= 0) {
                    acted += gs.clusters_limited > 0;
                    sub += gs.substeps > 1;
                    if (gs.bound_before > Lmax) Lmax = gs.bound_before;
                }
            }
        }
        if (rc < 0) break;
        double a = fp_median(tp, reps), b = fp_median(tg, reps);
        if (best_p < 0 || a < best_p) best_p = a;
        if (best_g < 0 || b < best_g) best_g = b;
    }
    if (rc < 0) {
        fprintf(stderr, "bench: engine call failed: %s\n", s ? csrbf_solver_message(s) : csrbf_strerror(rc));
    } else if (g->json) {
        printf("{\"case\":\"guard\",\"mode\":\"%s\",\"vertices\":%zu,\"centres\":%d,\"radius\":%.6g,"
               "\"ms_plain\":%.6g,\"ms_guarded\":%.6g,\"ratio\":%.4f,\"frames\":%d,"
               "\"frames_limited\":%d,\"frames_substeps\":%d,\"max_bound\":%.4g}\n",
               anchored ? "anchored" : "unanchored", f->vertex_count, m, R, best_p, best_g,
               best_g / best_p, reps, acted, sub, Lmax);
    } else {
        printf("%-8s %-10s %8zu %7d %6.3g %10.4f %10.4f %8.3f %6d %7d %8d %8.3g\n", "guard",
               anchored ? "anchored" : "unanchored", f->vertex_count, m, R, best_p, best_g,
               best_g / best_p, reps, acted, sub, Lmax);
    }
    fflush(stdout);
    csrbf_solver_destroy(&sv[0]);
    csrbf_solver_destroy(&sv[1]);
    free(rest);
    free(st);
    free(en);
    free(out);
    free(tp);
    free(tg);
    return rc < 0;
}

/* The guard's cost per update on the ICT face, as a ratio to the same update without it. */
static int bench_guard(const guard_bench_opts *g)
{
    char path[4096];
    const char *face = g->face;
    if (!face) {
        const char *root = getenv("FP_SHARED_DATA");
        snprintf(path, sizeof path, "%s/faces/ict-facekit/generic_neutral_mesh.obj",
                 root && *root ? root : "../shared/data");
        face = path;
    }
    char err[512];
    fp_mesh *f = NULL;
    if (fp_mesh_load(face, &f, err, sizeof err) < 0) {
        fprintf(stderr, "bench: %s\n", err);
        return 1;
    }
    float lo[3], hi[3];
    fp_mesh_bounds(f, lo, hi);
    double diag = sqrt((double)(hi[0] - lo[0]) * (hi[0] - lo[0]) +
                       (double)(hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (double)(hi[2] - lo[2]) * (hi[2] - lo[2]));
    double R = 0.06 * diag; /* the session's default radius */
    csrbf_points *pts = NULL;
    if (csrbf_points_create(f->vertex_count, f->positions, &pts) < 0) {
        fp_mesh_free(&f);
        return 1;
    }
    if (!g->json)
        printf("%-8s %-10s %8s %7s %6s %10s %10s %8s %6s %7s %8s %8s\n", "case", "mode", "vertices",
               "centres", "R", "ms_plain", "ms_guard", "ratio", "frames", "limited", "substeps",
               "max_L");
    fprintf(stderr, "bench: guard on %s (%zu vertices), R = %.3g\n", face, f->vertex_count, R);
    int rc = 0;
    static const int counts[2] = {10, 42};
    for (int c = 0; c < 2 && !rc; c++)
        for (int anchored = 1; anchored >= 0 && !rc; anchored--)
            rc = guard_run(g, f, pts, R, counts[c], anchored, 0.3 * R);
    csrbf_points_destroy(&pts);
    fp_mesh_free(&f);
    return rc;
}

static int case_guard(const bench_opts *o)
{
    guard_bench_opts g = {o->quick, o->json, o->rounds, NULL};
    return bench_guard(&g);
}

/* --------------------------------------------------- work that follows the supports */

/* Options of the support case. */
typedef struct {
    int quick, json, rounds;
} support_bench_opts;

/* Anchored updates (set_end_points + evaluation) on a grid: csrbf_evaluate (writes every
 * vertex) vs csrbf_evaluate_touched (persistent output), interleaved, with statistics asked
 * for (as the session does), medians. */
static int support_run(const support_bench_opts *g, const char *name, size_t nv, double R,
                       double amp)
{
    int reps = g->quick ? 200 : 1000;
    if (nv > 500000) reps /= 4;
    float *base = make_grid(nv), *o1 = malloc(nv * 3 * sizeof *o1), *o2 = malloc(nv * 3 * sizeof *o2);
    double *t1 = malloc((size_t)reps * sizeof *t1), *t2 = malloc((size_t)reps * sizeof *t2);
    float rest[3 * NCTRL], en[3 * NCTRL];
    fingertips(rest);
    csrbf_options opt = {0};
    opt.radius = R;
    csrbf_solver *s = NULL;
    csrbf_points *pts = NULL;
    csrbf_touch *tc = NULL;
    int rc = !base || !o1 || !o2 || !t1 || !t2 ? CSRBF_ERR_NOMEM : csrbf_solver_create(&opt, &s);
    if (rc >= 0) rc = csrbf_points_create(nv, base, &pts);
    if (rc >= 0) rc = csrbf_touch_create(pts, &tc);
    if (rc >= 0) rc = csrbf_solver_set_start_points(s, NCTRL, rest);
    double best1 = -1, best2 = -1;
    size_t pairs = 0, written = 0;
    for (int round = 0; round < g->rounds && rc >= 0; round++) {
        for (int it = -10; it < reps && rc >= 0; it++) {
            motion(rest, en, NCTRL, (it + 10) % FRAMES, amp);
            csrbf_eval_stats es;
            double a = now_ms();
            rc = csrbf_solver_set_end_points(s, en);
            if (rc >= 0) rc = csrbf_evaluate(s, pts, o1, 0, &es);
            double b = now_ms();
            if (rc >= 0) rc = csrbf_solver_set_end_points(s, en);
            if (rc >= 0) rc = csrbf_evaluate_touched(s, pts, tc, o2, 0, &es);
            double c = now_ms();
            if (it >= 0) {
                t1[it] = b - a;
                t2[it] = c - b;
            }
            pairs = es.pairs;
            const uint32_t *rg;
            size_t nr = csrbf_touch_ranges(tc, &rg);
            written = 0;
            for (size_t r = 0; r < nr; r++) written += rg[2 * r + 1];
        }
        if (rc < 0) break;
        double a = fp_median(t1, reps), b = fp_median(t2, reps);
        if (best1 < 0 || a < best1) best1 = a;
        if (best2 < 0 || b < best2) best2 = b;
    }
    if (rc >= 0 && memcmp(o1, o2, nv * 3 * sizeof *o1)) {
        fprintf(stderr, "bench: touched output differs from the full evaluation\n");
        rc = CSRBF_ERR_NUMERIC;
    }
    if (rc < 0) {
        fprintf(stderr, "bench: %s failed: %s\n", name, s ? csrbf_solver_message(s) : csrbf_strerror(rc));
    } else if (g->json) {
        printf("{\"case\":\"support\",\"mode\":\"%s\",\"vertices\":%zu,\"centres\":%d,\"radius\":%.6g,"
               "\"pairs\":%zu,\"written\":%zu,\"ms_full\":%.6g,\"ms_touched\":%.6g}\n",
               name, nv, NCTRL, R, pairs, written, best1, best2);
    } else {
        printf("%-8s %-10s %8zu %7d %6.3g %9zu %9zu %10.4f %10.4f %8.2fx\n", "support", name, nv,
               NCTRL, R, pairs, written, best1, best2, best1 / best2);
    }
    fflush(stdout);
    csrbf_touch_destroy(&tc);
    csrbf_points_destroy(&pts);
    csrbf_solver_destroy(&s);
    free(base);
    free(o1);
    free(o2);
    free(t1);
    free(t2);
    return rc < 0;
}

/* Table 1's 33,025 grid at R = 10 and 80, and 1M / 1.8M grids with about 1% of the vertices
 * in a support (10 supports of radius 0.36 over 64 x 64). */
static int bench_support(const support_bench_opts *g)
{
    if (!g->json)
        printf("%-8s %-10s %8s %7s %6s %9s %9s %10s %10s %9s\n", "case", "mode", "vertices",
               "centres", "R", "pairs", "written", "ms_full", "ms_touch", "speedup");
    fprintf(stderr, "bench: support (anchored; full vs touched evaluation, statistics on)\n");
    int rc = support_run(g, "anchored", 33025, 10.0, 0.6);
    if (!rc) rc = support_run(g, "anchored", 33025, 80.0, 0.6);
    if (!rc) rc = support_run(g, "anchored", 1000000, 0.361, 0.02);
    if (!rc) rc = support_run(g, "anchored", 1800000, 0.361, 0.02);
    return rc;
}

static int case_support(const bench_opts *o)
{
    support_bench_opts g = {o->quick, o->json, o->rounds};
    return bench_support(&g);
}


/* ---------------------------------------------------------------- the whole frame */

static const char *fp_bench_data_dir(void)
{
    const char *root = getenv("FP_SHARED_DATA");
    return root && *root ? root : "../shared/data";
}

static double pct(double *v, size_t n, double p) { return n ? fp_percentile(v, n, p / 100.0) : 0.0; }

/* The time this thread has waited on a run queue, ms (Linux's /proc/thread-self/schedstat,
 * its second field, ns; fd opened on it, or -1: NaN): the frames' "waiting for a CPU" row
 * (since the end of the frame before: the wait to wake from the pacing sleep counts too)
 * tells a frame the system held off its core from one the session itself made slow. */
static double runqueue_ms(int fd)
{
    char buf[96];
    ssize_t k = fd < 0 ? -1 : pread(fd, buf, sizeof buf - 1, 0);
    if (k <= 0) return NAN;
    buf[k] = '\0';
    unsigned long long run, wait;
    return sscanf(buf, "%llu %llu", &run, &wait) == 2 ? (double)wait / 1e6 : NAN;
}

/* The contact guard's walk (fp_frame_stats.collide_*): a frame it checked into w[0..5) of
 * row m of cap, each count a check's (the frame's sums over its checks divided by them) */
static void walk_take(double *w, size_t cap, size_t m, const fp_frame_stats *t)
{
    double k = t->collide_checks;
    w[m] = (double)t->collide_node_pairs / k;
    w[cap + m] = (double)t->collide_leaf_pairs / k;
    w[2 * cap + m] = (double)t->collide_tested / k;
    w[3 * cap + m] = (double)t->collide_certified / k;
    w[4 * cap + m] = (double)t->collide_moved;
}

/* walk_take's m rows: their medians, a line of the table */
static void walk_row(double *w, size_t cap, size_t m)
{
    if (m)
        printf("  contact walk: a check reaches %.0f node pairs and %.0f leaf pairs, tests %.0f triangle "
               "pairs exactly and certifies %.0f patches (medians over the %zu frames it checked; %.0f "
               "vertices moved a frame)\n",
               pct(w, m, 50), pct(w + cap, m, 50), pct(w + 2 * cap, m, 50), pct(w + 3 * cap, m, 50), m,
               pct(w + 4 * cap, m, 50));
}

/* --stream measured in the frame case: its part on the frame thread (fp_stream_frame_ranges:
 * the offsets quantised where the mesh moved, the records handed to its sender thread), the
 * sender sending to a socket on loopback that this thread drains after each frame (not
 * timed), so that none is dropped for a full buffer. */
typedef struct bench_stream {
    int sink;
#ifdef FP_BENCH_HAVE_LINK
    fp_stream *st;
#else
    void *st;
#endif
    uint64_t packets, bytes;
} bench_stream;

static void bench_stream_open(bench_stream *b, fp_session *s)
{
    memset(b, 0, sizeof *b);
    b->sink = -1;
#ifdef FP_BENCH_HAVE_LINK
    struct sockaddr_in sa = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    socklen_t len = sizeof sa;
    int big = 8 << 20;
    b->sink = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (b->sink < 0 || bind(b->sink, (struct sockaddr *)&sa, sizeof sa) ||
        getsockname(b->sink, (struct sockaddr *)&sa, &len))
        return;
    setsockopt(b->sink, SOL_SOCKET, SO_RCVBUF, &big, sizeof big);
    char spec[64], err[512];
    snprintf(spec, sizeof spec, "osc:127.0.0.1:%u", (unsigned)ntohs(sa.sin_port));
    const float *neutral = fp_session_loaded(s);
    fp_stream_options o = {.spec = spec, .neutral = neutral, .n = fp_session_vertex_count(s),
                           .mm_per_unit = fp_session_head(s)->mm_per_unit, .fps = 60};
    if (fp_stream_open(&o, &b->st, err, sizeof err))
        fprintf(stderr, "bench: frame: no stream: %s\n", err);
#else
    (void)s;
#endif
}

/* One frame streamed: microseconds of the sender; the sink drained. */
static double bench_stream_frame(bench_stream *b, fp_session *s, int64_t now)
{
#ifdef FP_BENCH_HAVE_LINK
    if (!b->st) return 0;
    int64_t a = fp_now_ns();
    const uint32_t *ranges;
    size_t nranges = fp_session_touched(s, &ranges); /* (as run and play stream) */
    fp_stream_frame_ranges(b->st, fp_session_positions(s), ranges, nranges, NULL, now, "");
    double us = (double)(fp_now_ns() - a) / 1e3;
    static unsigned char buf[65536];
    for (ssize_t k; (k = recv(b->sink, buf, sizeof buf, 0)) > 0;) {
        b->packets++;
        b->bytes += (uint64_t)k;
    }
    return us;
#else
    (void)b, (void)s, (void)now;
    return 0;
#endif
}

/* The sender thread's time a frame (quantising the copy, making and sending the packets), on
 * the other CPU: printed beside the frame thread's part, after every frame was sent. */
static void bench_stream_sender_row(bench_stream *b)
{
#ifdef FP_BENCH_HAVE_LINK
    fp_stream_stats st;
    fp_stream_finish(b->st);
    fp_stream_stats_get(b->st, &st);
    printf("  %-22s %10.4f %10.4f (not the frame's: --stream's sender thread a frame, quantising "
           "the copy and sending; %llu frames not sent as it was behind)\n", "stream, sender",
           st.tx_us_median / 1e3, st.tx_us_p99 / 1e3, (unsigned long long)st.busy);
#else
    (void)b;
#endif
}

static void bench_stream_close(bench_stream *b)
{
#ifdef FP_BENCH_HAVE_LINK
    fp_stream_close(&b->st);
#endif
    if (b->sink >= 0) close(b->sink);
}

/* One replay of three-claps at its own pace through the session API, 60 frames a second
 * (--every-frame: on the recording's own clock, every frame stepped, a late one delaying the
 * next instead of skipping periods):
 * per-stage times (fp_frame_stats.stage_ms), the whole frame, the frames a slow one made the
 * loop skip, the committing frames. For reference, the brute-force fingertip distances on
 * every 8th frame's hands, computed after the replay (on the last base: during it, their
 * cost at 1.7M vertices, several frame periods (docs/performance.md), would make the paced
 * loop skip frames), beside the indexed ones on the same
 * base, which must equal them within the session's reach and say "far" beyond it. The
 * session is opened with real-time memory, as live opens it (fp_session_realtime_memory: its
 * malloc settings hold for the rest of the process, which is why frame is the last case). */
static void nap_ms(int ms)
{
    struct timespec ts = {0, (long)ms * 1000000L};
    nanosleep(&ts, NULL);
}

static int frame_run(const bench_opts *o, const fp_bench_options *bo, const char *label,
                     const fp_mesh *mesh, const char *rig_path)
{
    char input[4300];
    snprintf(input, sizeof input, "replay:%s/hands/leap-motion/three-claps_joints_mm.csv%s",
             fp_bench_data_dir(), bo->every_frame ? ",fast=1" : "");
    fp_session_options so = {0};
    so.mesh = mesh;
    so.inputs[0] = input;
    so.input_count = 1;
    so.mapping = bo->mapping ? bo->mapping : "anchored";
    so.plugin_path = bo->plugin_path;
    so.no_contact_guard = bo->no_contact_guard;
    so.exact_frames = bo->exact_frames;
    so.input_clock = bo->every_frame; /* (--every-frame: stepped on the recording's clock) */
    if (bo->no_rig) so.rig_path = "none";
    else if (rig_path) so.rig_path = rig_path; /* (a subdivided face's: ICT's, carried) */
    char err[1024];
    fp_session *s = NULL;
    int64_t open0 = fp_now_ns(); /* the session's index and contact guard, the input */
    int rc = fp_session_create(&so, &s, err, sizeof err);
    if (!rc && (rc = fp_session_realtime_memory(s, 0, err, sizeof err)) == -ENOTSUP) /* as live */
        rc = 0;
    if (!rc) rc = fp_session_start(s, err, sizeof err);
    double open_s = (double)(fp_now_ns() - open0) / 1e9;
    if (rc) {
        fprintf(stderr, "bench: frame: %s\n", err);
        fp_session_destroy(&s);
        return rc;
    }
    enum { CAP = 4096 };
    size_t nf = 0, nact = 0, ncommit = 0, nengage = 0, dropped = 0, late = 0; /* late: --every-frame */
    double *st_ms[FP_STAGE_COUNT], *total = malloc(CAP * sizeof *total),
           *act = malloc(CAP * sizeof *act), *com = malloc(CAP * sizeof *com),
           *eng = malloc(CAP * sizeof *eng);
    fp_hand_pose(*hands)[FP_HANDS] = calloc(CAP, sizeof *hands);
    for (int k = 0; k < FP_STAGE_COUNT; k++) st_ms[k] = malloc(CAP * sizeof(double));
    double *contact_ms = malloc(CAP * sizeof *contact_ms); /* the contact guard (collide_ms) */
    double *held = malloc(CAP * sizeof *held); /* the frame's wait for a CPU (runqueue_ms) */
    double *wwait = malloc(CAP * sizeof *wwait); /* its wait for the contact worker */
    int *cpu = malloc(CAP * sizeof *cpu);        /* the CPU it ended on (sched_getcpu) */
    double *on_cpu = malloc(CAP * sizeof *on_cpu); /* the frames that ended on one CPU */
    double *walk = malloc(5 * CAP * sizeof *walk); /* the contact guard's walk (walk_take) */
    fp_frame_stats *fst = bo->trace ? malloc(CAP * sizeof *fst) : NULL; /* --trace's rows */
    size_t *skipped = bo->trace ? malloc(CAP * sizeof *skipped) : NULL;
    bool oom = !total || !act || !com || !eng || !hands || !contact_ms || !held || !wwait || !cpu ||
               !on_cpu || !walk || (bo->trace && (!fst || !skipped));
    for (int k = 0; k < FP_STAGE_COUNT; k++) oom |= !st_ms[k];
    if (oom) {
        for (int k = 0; k < FP_STAGE_COUNT; k++) free(st_ms[k]);
        free(total), free(act), free(com), free(eng), free(hands), free(contact_ms), free(held);
        free(wwait), free(cpu), free(on_cpu), free(walk), free(fst), free(skipped);
        fp_session_destroy(&s);
        fprintf(stderr, "bench: frame: out of memory\n");
        return -ENOMEM;
    }
    bench_stream bs;
    bench_stream_open(&bs, s);
    double *stream_us = malloc(CAP * sizeof *stream_us); /* --stream's sender (fp_stream.h) */
    int sched_fd = open("/proc/thread-self/schedstat", O_RDONLY | O_CLOEXEC);
    size_t nheld = 0, nwwait = 0, nthere = 0; /* nthere: frames run on the frame thread */
    size_t nhold = 0; /* vertices the contact guard's hold kept in place, all frames */
    size_t nwalk = 0; /* frames the contact guard checked (walk) */
    double w0 = runqueue_ms(sched_fd); /* read after each frame only: a read just before one
                                          slowed the ICT frame (docs/performance.md) */
    int64_t period = 1000000000LL / 60, start = fp_now_ns(), next = start, clock0 = 0;
    bool no_events = false;
    size_t n = fp_session_vertex_count(s);
    if (bo->every_frame) { /* the recording's time zero (its first event), 30 s at most */
        int ic, waited = 0;
        while ((ic = fp_session_input_start(s, &clock0)) == 0 && waited++ < 30000) nap_ms(1);
        if (ic == 0) {
            fprintf(stderr, "bench: frame: the recording gave no event in 30 s\n");
            no_events = true; /* (no frame stepped; the case fails) */
        }
        if (ic < 0) clock0 = start;
    }
    while (!no_events && !fp_session_finished(s) && nf < CAP) {
        fp_frame_stats st;
        int64_t when = clock0 + (int64_t)nf * period; /* --every-frame: the frame's time */
        while (bo->every_frame && !fp_session_inputs_ready(s, when)) nap_ms(1);
        int64_t a = fp_now_ns();
        fp_session_step(s, bo->every_frame ? when : a, &st);
        int64_t b = fp_now_ns();
        if (stream_us) stream_us[nf] = bench_stream_frame(&bs, s, a);
        cpu[nf] = sched_getcpu();
        double w1 = runqueue_ms(sched_fd), h = w1 - w0;
        w0 = w1;
        held[nf] = h == h ? h : 0.0; /* (NaN: no schedstat) */
        nheld += held[nf] >= 1.0;
        total[nf] = (double)(b - a) / 1e6;
        if (st.active) act[nact++] = total[nf];
        if (st.committed) com[ncommit++] = total[nf];
        if (st.engaged) eng[nengage++] = total[nf];
        for (int k = 0; k < FP_STAGE_COUNT; k++) st_ms[k][nf] = st.stage_ms[k];
        contact_ms[nf] = st.collide_ms;
        wwait[nf] = st.collide_wait_ms;
        nhold += st.collide_held;
        if (st.collide_checks > 0) walk_take(walk, CAP, nwalk++, &st);
        nwwait += wwait[nf] >= 1.0;
        nthere += st.frame_thread;
        for (int h = 0; h < FP_HANDS; h++)
            if (fp_session_hand(s, h)) hands[nf][h] = *fp_session_hand(s, h);
        if (fst) {
            fst[nf] = st;
            skipped[nf] = 0;
        }
        nf++;
        next += period;
        int64_t now = fp_now_ns();
        if (next > now) { /* (paced as live: the contact guard's worker runs between frames) */
            struct timespec ts = {(time_t)((next - now) / 1000000000LL), (long)((next - now) % 1000000000LL)};
            nanosleep(&ts, NULL);
        } else if (bo->every_frame) { /* late: none skipped, the next frame only delayed */
            late++;
            next = now;
        } else { /* late: the frames whose time passed meanwhile are skipped */
            dropped += (size_t)((now - next) / period);
            if (skipped) skipped[nf - 1] = (size_t)((now - next) / period);
            next = now;
        }
    }
    double seconds = (double)(fp_now_ns() - start) / 1e9;
    if (bo->trace) /* after the replay (a write in the paced loop would be timed with
                       it), before pct sorts the columns */
        for (size_t f = 0; f < nf; f++) {
            const fp_frame_stats *t = &fst[f];
            fprintf(bo->trace, "%s,%zu,%.6g", label, f, total[f]);
            for (int k = 0; k < FP_STAGE_COUNT; k++) fprintf(bo->trace, ",%.6g", t->stage_ms[k]);
            fprintf(bo->trace, ",%.6g,%.6g,", t->collide_ms, t->collide_wait_ms);
            if (sched_fd >= 0) fprintf(bo->trace, "%.6g", held[f]);
            fprintf(bo->trace, ",%d,%d,%d,%d,%d,%zu,%" PRIu64 ",%d,%.6g,%ld,%zu,%d,%zu,%zu,%zu,%zu,%zu,%zu\n",
                    cpu[f], t->active, t->engaged, t->committed, t->refactored, t->control_vectors,
                    t->pairs, t->guard_substeps, t->collide_t, t->collide_pairs, t->collide_held,
                    t->collide_checks, t->collide_moved, t->collide_node_pairs, t->collide_leaf_pairs,
                    t->collide_tested, t->collide_certified, skipped[f]);
        }
    /* the reference, and the indexed distances checked against it (same base, same hands) */
    size_t nbrute = 0, within = 0, far = 0, wrong = 0;
    double *brute = malloc((nf / 8 + 1) * sizeof *brute), *indexed = malloc((nf / 8 + 1) * sizeof *indexed);
    const float reach = (float)(FP_TIP_DISTANCE_REACH * fp_session_radius(s));
    fp_engine_step e;
    if (fp_engine_step_init(&e, n, fp_session_base(s), 1)) rc = -ENOMEM;
    for (size_t f = 0; f < nf && !rc; f += 8) {
        float d[FP_HANDS][FP_FINGERS], q[FP_HANDS][FP_FINGERS];
        int64_t c = fp_now_ns();
        fp_engine_tip_distances(fp_session_base(s), n, hands[f], d);
        int64_t c1 = fp_now_ns();
        fp_engine_step_tip_distances(&e, hands[f], reach, q);
        indexed[nbrute] = (double)(fp_now_ns() - c1) / 1e6;
        brute[nbrute++] = (double)(c1 - c) / 1e6;
        for (int h = 0; h < FP_HANDS; h++)
            for (int t = 0; t < FP_FINGERS && hands[f][h].present; t++) {
                bool in = d[h][t] <= reach;
                within += in;
                far += !in;
                wrong += in ? memcmp(&d[h][t], &q[h][t], sizeof(float)) != 0 : !isinf(q[h][t]);
            }
    }
    if (!rc) fp_engine_step_free(&e);
    static const char *names[FP_STAGE_COUNT] = {"events", "hands", "distances", "mapping",
                                                "solve", "evaluate", "shape", "commit"};
    /* the whole frame by the CPU it ended on (the first FRAME_CPUS CPUs; -1: none there):
     * on a shared VM one CPU's caches may be another guest's too (print_machine's chase) */
    enum { FRAME_CPUS = 4 };
    size_t ncpu[FRAME_CPUS] = {0};
    double cpu_med[FRAME_CPUS];
    for (int c = 0; c < FRAME_CPUS; c++) {
        for (size_t f = 0; f < nf; f++)
            if (cpu[f] == c) on_cpu[ncpu[c]++] = total[f];
        cpu_med[c] = ncpu[c] ? pct(on_cpu, ncpu[c], 50) : -1;
    }
    int cpus_seen = 0;
    for (int c = 0; c < FRAME_CPUS; c++)
        if (ncpu[c]) cpus_seen = c + 1;
    if (o->json) {
        printf("{\"case\":\"frame\",\"mesh\":\"%s\",\"vertices\":%zu,\"frames\":%zu,\"frames_dropped\":%zu,"
               "\"every_frame\":%s,\"frames_late\":%zu,"
               "\"seconds_open\":%.4g,\"seconds\":%.4g,\"deforming\":%zu,\"commits\":%zu,\"ms_median\":%.6g,\"ms_p99\":%.6g,"
               "\"ms_deforming_median\":%.6g,\"ms_deforming_p99\":%.6g,\"ms_commit_median\":%.6g,"
               "\"ms_commit_max\":%.6g,\"ms_engage_median\":%.6g,\"ms_engage_max\":%.6g,"
               "\"ms_distances_bruteforce_median\":%.6g,"
               "\"ms_distances_indexed_median\":%.6g,\"distances_within_reach\":%zu,"
               "\"distances_far\":%zu,\"distances_wrong\":%zu,\"contact_guard\":%s,\"frames_on_frame_thread\":%zu,"
               "\"contact_hold\":%s,\"held_vertices_per_deforming_frame\":%.6g",
               label, n, nf, dropped, bo->every_frame ? "true" : "false", late, open_s, seconds, nact, ncommit, pct(total, nf, 50), pct(total, nf, 99),
               pct(act, nact, 50), pct(act, nact, 99), pct(com, ncommit, 50), pct(com, ncommit, 100),
               pct(eng, nengage, 50), pct(eng, nengage, 100), pct(brute, nbrute, 50), pct(indexed, nbrute, 50), within, far, wrong,
               bo->no_contact_guard ? "false" : "true", nthere,
               bo->no_contact_guard || bo->exact_frames ? "false" : "true", nact ? (double)nhold / nact : 0.0);
        for (int k = 0; k < FP_STAGE_COUNT; k++)
            printf(",\"%s_median\":%.6g,\"%s_p99\":%.6g", names[k], pct(st_ms[k], nf, 50),
                   names[k], pct(st_ms[k], nf, 99));
        printf(",\"contact_median\":%.6g,\"contact_p99\":%.6g", pct(contact_ms, nf, 50),
               pct(contact_ms, nf, 99));
        if (bs.st && stream_us)
            printf(",\"stream_send_median\":%.6g,\"stream_send_p99\":%.6g", pct(stream_us, nf, 50) / 1e3,
                   pct(stream_us, nf, 99) / 1e3);
        if (sched_fd >= 0)
            printf(",\"cpu_wait_median\":%.6g,\"cpu_wait_p99\":%.6g,\"frames_cpu_wait_1ms\":%zu",
                   pct(held, nf, 50), pct(held, nf, 99), nheld);
        printf(",\"contact_worker_wait_median\":%.6g,\"contact_worker_wait_p99\":%.6g,"
               "\"frames_contact_worker_wait_1ms\":%zu", pct(wwait, nf, 50), pct(wwait, nf, 99), nwwait);
        printf(",\"frames_by_cpu\":[");
        for (int c = 0; c < cpus_seen; c++) printf("%s%zu", c ? "," : "", ncpu[c]);
        printf("],\"ms_median_by_cpu\":[");
        for (int c = 0; c < cpus_seen; c++) {
            if (cpu_med[c] < 0) printf("%snull", c ? "," : "");
            else printf("%s%.6g", c ? "," : "", cpu_med[c]);
        }
        printf("]}\n");
    } else {
        char skips[96];
        if (bo->every_frame)
            snprintf(skips, sizeof skips, "every one stepped; %zu ended past the next's time", late);
        else
            snprintf(skips, sizeof skips, "%zu skipped: a late frame's periods", dropped);
        printf("frame %-14s %8zu vertices, opened in %.2f s, %zu frames in %.2f s (%s), %zu deforming, "
               "%zu commits, contact guard %s, %zu run on the frame thread\n",
               label, n, open_s, nf, seconds, skips, nact, ncommit, bo->no_contact_guard ? "off" : "on",
               nthere);
        if (rig_path && !bo->no_rig)
            printf("  rig: the ICT face's, carried through each subdivision (bench_rig.c: a midpoint in a "
                   "region when both ends are)\n");
        else
            printf("  rig: %s\n", fp_session_rig_how(s));
        if (!bo->no_contact_guard)
            printf("  contact hold %s: %.0f vertices a deforming frame kept in place (moved under "
                   "1e-5 of the face's diagonal since the last frame)\n",
                   bo->exact_frames ? "off (--exact-frames)" : "on", nact ? (double)nhold / nact : 0.0);
        if (!bo->no_contact_guard) walk_row(walk, CAP, nwalk);
        printf("  %-22s %10s %10s\n", "stage", "median_ms", "p99_ms");
        for (int k = 0; k < FP_STAGE_COUNT; k++)
            printf("  %-22s %10.4f %10.4f\n", names[k], pct(st_ms[k], nf, 50), pct(st_ms[k], nf, 99));
        printf("  %-22s %10.4f %10.4f\n", "contact", pct(contact_ms, nf, 50), pct(contact_ms, nf, 99));
        if (bs.st && stream_us) {
            printf("  %-22s %10.4f %10.4f (after the frame: --stream's part on the frame thread, "
                   "copying the touched blocks and handing them over; its sender thread sent %.0f "
                   "packets, %.0f bytes a frame to a loopback socket)\n", "stream", pct(stream_us, nf, 50) / 1e3,
                   pct(stream_us, nf, 99) / 1e3, (double)bs.packets / (nf ? nf : 1), (double)bs.bytes / (nf ? nf : 1));
            bench_stream_sender_row(&bs);
        }
        printf("  %-22s %10.4f %10.4f\n", "whole frame", pct(total, nf, 50), pct(total, nf, 99));
        if (sched_fd >= 0)
            printf("  %-22s %10.4f %10.4f (%zu frames 1 ms or more: the system ran something else "
                   "on this thread's core)\n", "waiting for a CPU", pct(held, nf, 50), pct(held, nf, 99), nheld);
        printf("  %-22s %10.4f %10.4f (%zu frames 1 ms or more: the contact guard's worker thread "
               "was held off its core mid-task)\n", "waiting for the worker", pct(wwait, nf, 50),
               pct(wwait, nf, 99), nwwait);
        for (int c = 0; c < cpus_seen; c++)
            if (ncpu[c])
                printf("  whole frame, on cpu%-3d %10.4f %10s (%zu frames ended there)\n", c, cpu_med[c],
                       "-", ncpu[c]);
        printf("  %-22s %10.4f %10.4f\n", "whole frame, deforming", pct(act, nact, 50), pct(act, nact, 99));
        printf("  %-22s %10.4f %10.4f (max)\n", "whole frame, commit", pct(com, ncommit, 50), pct(com, ncommit, 100));
        printf("  %-22s %10.4f %10.4f (max; %zu frames)\n", "whole frame, engage", pct(eng, nengage, 50),
               pct(eng, nengage, 100), nengage);
        printf("  %-22s %10.4f %10.4f\n", "distances, brute force", pct(brute, nbrute, 50), pct(brute, nbrute, 99));
        printf("  %-22s %10.4f %10.4f (%zu tips within %.2g R equal to the brute force, %zu far, "
               "%zu wrong)\n", "distances, indexed", pct(indexed, nbrute, 50), pct(indexed, nbrute, 99),
               within, FP_TIP_DISTANCE_REACH, far, wrong);
    }
    fflush(stdout);
    for (int k = 0; k < FP_STAGE_COUNT; k++) free(st_ms[k]);
    free(fst);
    free(walk);
    free(skipped);
    free(stream_us);
    bench_stream_close(&bs);
    free(contact_ms);
    free(held);
    free(wwait);
    free(cpu);
    free(on_cpu);
    if (sched_fd >= 0) close(sched_fd);
    free(total);
    free(brute);
    free(indexed);
    free(act);
    free(com);
    free(eng);
    free(hands);
    fp_session_destroy(&s);
    if (rc) fprintf(stderr, "bench: frame: out of memory for the reference\n");
    if (!rc && no_events) rc = -EIO;
    if (!rc && wrong) {
        fprintf(stderr, "bench: frame: %zu indexed fingertip distances differ from the brute force\n", wrong);
        rc = -EIO;
    }
    return rc;
}

static const fp_bench_options *frame_bo;

static int case_frame(const bench_opts *o)
{
    if (!frame_bo || !frame_bo->plugin_path) {
        fprintf(stderr, "bench: frame: no plugin path; skipped\n");
        return 0;
    }
    char path[4300], err[512];
    snprintf(path, sizeof path, "%s/faces/ict-facekit/generic_neutral_mesh.obj", fp_bench_data_dir());
    fp_mesh *m = NULL;
    if (fp_mesh_load(path, &m, err, sizeof err)) {
        fprintf(stderr, "bench: %s\n", err);
        return -ENOENT;
    }
    fprintf(stderr, "bench: frame (the session's whole frame; three-claps at its own pace, 60 fps, %s)\n",
            frame_bo->mapping ? frame_bo->mapping : "anchored");
    if (frame_bo->trace) fputs(FP_BENCH_TRACE_HEADER, frame_bo->trace);
    int rc = frame_run(o, frame_bo, "ict", m, NULL);
    if (!rc) rc = fp_bench_isolate(stdout, frame_bo, m, "ict", fp_bench_data_dir(), o->json); /* issue 56 */
    if (!rc) rc = fp_bench_isolate_small(stdout, frame_bo, fp_bench_data_dir(), o->json);
    unsigned levels = frame_bo->subdivide ? frame_bo->subdivide : 1u << 3;
    /* the subdivided faces carry the ICT face's rig (bench_rig.c), unless --no-rig */
    fp_bench_rig *rig = NULL;
    char rdir[4096], rpath[4300];
    if (!rc && !frame_bo->no_rig && levels > 1 &&
        !fp_rig_find(fp_rig_default_dir(NULL, rdir, sizeof rdir), m->vertex_count, m->positions, rpath,
                     sizeof rpath, err, sizeof err) &&
        fp_bench_rig_open(rpath, &rig, err, sizeof err))
        fprintf(stderr, "bench: frame: the subdivided faces without a rig: %s\n", err);
    fp_mesh *sub = m;
    for (int l = 1; l <= FP_BENCH_MAX_LEVEL && levels >> l && !rc; l++) {
        fp_mesh *next = fp_mesh_subdivide(sub);
        if (!next) rc = -ENOMEM;
        if (!rc && rig && fp_bench_rig_subdivide(rig, sub, next, err, sizeof err)) {
            fprintf(stderr, "bench: frame: the subdivided faces without a rig: %s\n", err);
            fp_bench_rig_free(&rig);
        }
        if (sub != m) fp_mesh_free(&sub);
        sub = next;
        char label[32], tmp[4300] = "";
        snprintf(label, sizeof label, "ict-subdiv%d", l);
        if (!rc && (levels >> l & 1u) && rig && fp_bench_rig_write(rig, tmp, sizeof tmp, err, sizeof err)) {
            fprintf(stderr, "bench: frame: %s without a rig: %s\n", label, err);
            *tmp = '\0';
        }
        if (!rc && (levels >> l & 1u)) rc = frame_run(o, frame_bo, label, sub, *tmp ? tmp : NULL);
        if (*tmp) unlink(tmp);
    }
    fp_bench_rig_free(&rig);
    if (sub != m) fp_mesh_free(&sub);
    fp_mesh_free(&m);
    return rc;
}


/* The recorder's cost on the session thread (bench_take.c). */
static int case_take(const bench_opts *o) { return fp_bench_take(stdout, o->quick, o->json); }

/* Nanoseconds a load of a pointer chase (one random cycle through every 64-byte line) over
 * `bytes`, on the calling thread's CPU: `loads` loads after one warm lap. -1 without memory. */
static double chase_ns(size_t bytes, long loads)
{
    size_t n = bytes / 64;
    size_t *a = aligned_alloc(64, n * 64), *perm = malloc(n * sizeof *perm);
    double ns = -1;
    if (a && perm && n > 1) {
        uint64_t x = 88172645463325252ull; /* xorshift: the same cycle every run */
        for (size_t i = 0; i < n; i++) perm[i] = i;
        for (size_t i = n - 1; i > 0; i--) {
            x ^= x << 13, x ^= x >> 7, x ^= x << 17;
            size_t j = (size_t)(x % (i + 1)), t = perm[i];
            perm[i] = perm[j];
            perm[j] = t;
        }
        for (size_t i = 0; i < n; i++) a[8 * perm[i]] = 8 * perm[(i + 1) % n];
        volatile size_t sink;
        size_t q = 0;
        for (size_t i = 0; i < n; i++) q = a[q];
        double t0 = now_ms();
        for (long i = 0; i < loads; i++) q = a[q];
        ns = (now_ms() - t0) * 1e6 / (double)loads;
        sink = q;
        (void)sink;
    }
    free(a);
    free(perm);
    return ns;
}

/* Chases on each CPU the bench may run on (at most 8), into line (the calling thread's CPUs
 * are restored): over 3/4 of a core's L2, and over 8 MiB (past L2: the shared cache, or
 * memory). On a shared virtual machine other guests take these caches minute by minute,
 * the two CPUs unlike and the shared cache at times holding nothing of ours, while compute
 * loops stay equal (docs/performance.md has one VM's figures). A snapshot at the run's
 * start: the state changes within seconds, so it tells a run's conditions roughly, and frame
 * medians do not follow it in order. */
static void probe_cpus(long l2, char *line, size_t cap)
{
    cpu_set_t old;
    line[0] = '\0';
    if (sched_getaffinity(0, sizeof old, &old)) return;
    const size_t sizes[2] = {(size_t)(l2 > 0 ? l2 : 1 << 20) / 4 * 3, (size_t)8 << 20};
    const long loads[2] = {1L << 21, 1L << 18};
    double ns[2][8];
    int cpus[8], nc = 0;
    for (int c = 0; c < CPU_SETSIZE && nc < 8; c++) {
        if (!CPU_ISSET(c, &old)) continue;
        cpu_set_t one;
        CPU_ZERO(&one);
        CPU_SET(c, &one);
        if (sched_setaffinity(0, sizeof one, &one)) continue;
        for (int k = 0; k < 2; k++) ns[k][nc] = chase_ns(sizes[k], loads[k]);
        cpus[nc++] = c;
    }
    sched_setaffinity(0, sizeof old, &old);
    size_t len = (size_t)snprintf(line, cap, "chases, ns a load:");
    for (int k = 0; k < 2 && len < cap; k++) {
        len += (size_t)snprintf(line + len, cap - len, "%s %zu KiB", k ? ";" : "", sizes[k] / 1024);
        for (int i = 0; i < nc && len < cap; i++)
            len += (size_t)snprintf(line + len, cap - len, " cpu%d %.1f", cpus[i], ns[k][i]);
    }
}

/* The machine the figures come from, one line on stderr (stdout stays the table or the
 * JSON): the CPU's model (Linux's /proc/cpuinfo), its cores, the second-level cache of a
 * core, the engine's instruction set (csrbf_simd_path), the kernel's transparent huge pages
 * mode and DAMON monitors (kdamond) running, the load average, and the chases of each CPU
 * (probe_cpus). */
static void print_machine(void)
{
    char model[128] = "unknown CPU";
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (f) {
        char line[256];
        while (fgets(line, sizeof line, f))
            if (!strncmp(line, "model name", 10)) {
                const char *c = strchr(line, ':');
                if (c) {
                    snprintf(model, sizeof model, "%s", c + 1 + (c[1] == ' '));
                    model[strcspn(model, "\n")] = '\0';
                }
                break;
            }
        fclose(f);
    }
    long cores = sysconf(_SC_NPROCESSORS_ONLN), l2 = sysconf(_SC_LEVEL2_CACHE_SIZE);
    double la[3] = {-1, -1, -1};
    int nla = getloadavg(la, 3);
    char l2s[32] = "unknown";
    if (l2 > 0) snprintf(l2s, sizeof l2s, "%ld KiB", l2 / 1024);
    /* the kernel's memory settings that move a frame's tail on a virtual machine: the
     * transparent huge pages mode (the bracketed word) and DAMON's monitors running
     * (kdamond: its scans of physical memory hold a 1.7M-vertex frame up now and then;
     * docs/performance.md, and docs/architecture.md, bench) */
    char thp[16] = "unknown", line[64];
    f = fopen("/sys/kernel/mm/transparent_hugepage/enabled", "r");
    if (f) {
        if (fgets(line, sizeof line, f)) {
            const char *lb = strchr(line, '['), *rb = lb ? strchr(lb, ']') : NULL;
            if (lb && rb && rb - lb - 1 < (long)sizeof thp) snprintf(thp, sizeof thp, "%.*s", (int)(rb - lb - 1), lb + 1);
        }
        fclose(f);
    }
    int damon = 0;
    for (int i = 0; i < 64; i++) {
        char path[96];
        snprintf(path, sizeof path, "/sys/kernel/mm/damon/admin/kdamonds/%d/state", i);
        if (!(f = fopen(path, "r"))) break;
        damon += fgets(line, sizeof line, f) && !strncmp(line, "on", 2);
        fclose(f);
    }
    char probe[256];
    probe_cpus(l2, probe, sizeof probe);
    fprintf(stderr, "bench: machine: %s, %ld cores, L2 %s a core; engine fast path: %s; transparent huge "
            "pages %s; DAMON monitors running %d; load average ",
            model, cores, l2s, csrbf_simd_path(), thp, damon);
    if (nla == 3) fprintf(stderr, "%.2f %.2f %.2f", la[0], la[1], la[2]);
    else fprintf(stderr, "unknown");
    fprintf(stderr, "; %s\n", probe[0] ? probe : "chases not run");
}

/* frame last: it sets the process's malloc for real-time memory (frame_run) */
const char *const fp_bench_cases[] = {"table1", "scale", "centres", "guard", "support", "take", "frame", NULL};

int fp_bench_run(const fp_bench_options *opt)
{
    static int (*const run[])(const bench_opts *) = {case_table1, case_scale, case_centres,
                                                     case_guard, case_support, case_take, case_frame};
    frame_bo = opt;
    bench_opts o = {opt->quick, opt->json, opt->quick ? 2 : 3};
    int found = 0;
    for (size_t c = 0; fp_bench_cases[c] && !found; c++)
        found = !opt->only || !strcmp(opt->only, fp_bench_cases[c]);
    if (!found) return -EINVAL;
    print_machine();
    found = 0;
    for (size_t c = 0; fp_bench_cases[c]; c++) {
        if (opt->only && strcmp(opt->only, fp_bench_cases[c])) continue;
        found = 1;
        int rc = run[c](&o);
        if (rc) return rc;
    }
    return found ? 0 : -EINVAL;
}
