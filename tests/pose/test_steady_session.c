/* Steady hands end to end (issue 51's Done-when), through the session on the recordings'
 * clock at 60 frames a second, the ICT face with its rig and `--mapping onehand,still=0`
 * (the one-hand recording moves the jaw and the landmarks, so the face deforms every frame):
 *
 *  - jitter: a copy of the real HandSplay recording (108 Hz, one right hand; and resampled at
 *    57 Hz, a second test) with Gaussian
 *    noise of sigma 1 mm on every joint coordinate (fixed seed), replayed unfiltered and
 *    through the One Euro filter (`filter=oneeuro`, its defaults), in lockstep with the clean
 *    recording: during still holds (frames where the clean hand's fastest joint moves slower
 *    than HOLD_MM_S) the frame-to-frame motion beyond the clean one (the jitter) of the hand's
 *    joints and of the face's vertices is at least 5x smaller filtered than unfiltered;
 *  - lag: the filtered hand's joints, and the face's vertices (every 16th), against the clean
 *    ones shifted by s frames (s from -4 to 4 by 0.05, the clean frames interpolated): the s
 *    of least squared difference, each coordinate's mean difference taken out (the
 *    cross-correlation's peak), is at most one frame; the face's criteria and the hand's lag
 *    also on grab and Waiting (at their rate and at 57 Hz) and three-claps (its rate);
 *  - the same criteria on a still hand pinching (a copy the test makes of HandSplay's middle
 *    pose, thumb and index closing and opening every 1.5 s), with two seeds of the noise;
 *  - stutter: the clean recording (108 Hz, its three real gaps of 27 ms included) and a 57 Hz
 *    copy resampled from it give no two consecutive frames with the same hand joints while
 *    the hand moves (after the hand's first two frames: a single sample shows no motion).
 *
 * The noisy and resampled copies are written by the test into a temporary folder. For
 * trying other settings or recordings (figures printed; the thresholds still apply):
 * FP_TEST_FILTER_KEYS=",beta=0.05" (appended to the filtered input's SPEC),
 * FP_TEST_STEADY_CLIP=grab (a *_joints_mm.csv of ../shared/data/hands/leap-motion),
 * FP_TEST_STEADY_HZ=57 (the first jitter test's recording resampled first, as the 57 Hz copy;
 * the second is resampled at 57 Hz always), FP_TEST_STEADY_MAPPING=anchored (instead of
 * onehand; the face then moves only while a fingertip touches), FP_TEST_STEADY_SEED=7 (the
 * noise's seed instead of 51), FP_TEST_STUTTER_SPEC=replay:FILE,fast=1 (test_no_stutter alone,
 * on that input instead: its repeated frames listed; FP_TEST_STUTTER_TIMES=1 prints each
 * frame's time since the right hand's latest sample). Each run also prints its
 * pops: frames where the clean run's face moved over twice as far as the hand's fastest
 * joint and 1 mm more (a clamp or a guard letting go at once; not asserted: the contact
 * guard's held skin catches up in one frame where it lets go, docs/performance.md). */
#define _GNU_SOURCE
#include "fp_plugin_host.h"
#include "fp_session.h"
#include "fp_test_support.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#define FPS 60
#define HOLD_MM_S 40.0      /* a frame of a still hold: the clean hand's joints all slower */
#define MAX_FRAMES 4096
#define NJ FP_HAND_JOINTS
#define MAPPING "onehand,still=0"

static char g_dir[256];
static uint64_t g_seed = 51;   /* the noise's seed (FP_TEST_STEADY_SEED) */

/* ---- the recordings ------------------------------------------------------------------- */

typedef struct rows {
    char header[4096];
    size_t n;
    long frame[1024];
    long long t_us[1024];
    char lead[1024][32];     /* hand_id,hand_type */
    double v[1024][69];
} rows;

static void read_rows(const char *path, rows *r)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    memset(r, 0, sizeof *r);
    assert_non_null(fgets(r->header, sizeof r->header, f));
    char line[8192];
    while (fgets(line, sizeof line, f)) {
        assert_true(r->n < 1024);
        char *save = NULL, *tok = strtok_r(line, ",\n", &save);
        r->frame[r->n] = strtol(tok, NULL, 10);
        r->t_us[r->n] = strtoll(strtok_r(NULL, ",\n", &save), NULL, 10);
        const char *id = strtok_r(NULL, ",\n", &save), *side = strtok_r(NULL, ",\n", &save);
        snprintf(r->lead[r->n], sizeof r->lead[0], "%s,%s", id, side);
        for (int i = 0; i < 69; i++) {
            tok = strtok_r(NULL, ",\n", &save);
            assert_non_null(tok);
            r->v[r->n][i] = strtod(tok, NULL);
        }
        r->n++;
    }
    fclose(f);
}

static void write_rows(const char *path, const rows *r)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(r->header, f);
    for (size_t i = 0; i < r->n; i++) {
        fprintf(f, "%ld,%lld,%s", r->frame[i], r->t_us[i], r->lead[i]);
        for (int k = 0; k < 69; k++) fprintf(f, ",%.4f", r->v[i][k]);
        fputc('\n', f);
    }
    assert_int_equal(fclose(f), 0);
}

/* splitmix64, then Box-Muller: the same noise on every machine */
static uint64_t g_rng;
static double uniform01(void)
{
    uint64_t z = (g_rng += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return ((double)(z >> 11) + 0.5) / 9007199254740992.0;
}
static double gauss(void)
{
    double u = uniform01(), v = uniform01();
    return sqrt(-2 * log(u)) * cos(6.283185307179586 * v);
}

/* Every joint coordinate (the palm centre, columns 0-2 of the values, and the 20 finger
 * joints, columns 9-68) plus sigma_mm of Gaussian noise; the palm normal and direction (the
 * wrist pose's, unused by a joint-position hand) kept. */
static void add_noise(rows *r, double sigma_mm, uint64_t seed)
{
    g_rng = seed;
    for (size_t i = 0; i < r->n; i++)
        for (int k = 0; k < 69; k++)
            if (k < 3 || k >= 9) r->v[i][k] += sigma_mm * gauss();
}

/* The last of a hand's rows r[a..m) before a gap over 100 ms (or its last row). */
static size_t stretch_end(const rows *in, const size_t *r, size_t m, size_t a)
{
    size_t b = a;
    while (b + 1 < m && in->t_us[r[b + 1]] - in->t_us[r[b]] <= 100000) b++;
    return b;
}

/* The recording resampled at hz, each hand (hand id and side) on its own: row k at
 * t_first + k / hz (t_first the recording's first row, so two hands' rows share frame k's
 * number and time) for each hand within a stretch of its rows without a gap over 100 ms (a
 * hand away stays away), every value interpolated linearly between the hand's rows around it;
 * in time order, the hands of a frame in the order they first appear. */
static void resample(const rows *in, double hz, rows *out)
{
    enum { MAX_HANDS = 8 };
    static size_t idx[MAX_HANDS][1024];      /* each hand's rows */
    size_t m[MAX_HANDS] = {0}, a[MAX_HANDS] = {0}, b[MAX_HANDS], j[MAX_HANDS] = {0};
    size_t hands = 0;
    for (size_t i = 0; i < in->n; i++) {
        size_t h = 0;
        while (h < hands && strcmp(in->lead[idx[h][0]], in->lead[i])) h++;
        assert_true(h < MAX_HANDS);
        hands += h == hands;
        idx[h][m[h]++] = i;
    }
    for (size_t h = 0; h < hands; h++) b[h] = stretch_end(in, idx[h], m[h], 0); /* idx[h][a..b] */
    memcpy(out->header, in->header, sizeof out->header);
    out->n = 0;
    const double t0 = (double)in->t_us[0], t_end = (double)in->t_us[in->n - 1];
    for (long k = 0;; k++) {
        const double t = t0 + (double)k * 1e6 / hz;
        if (t > t_end) break;
        for (size_t h = 0; h < hands; h++) {
            const size_t *r = idx[h];
            while (t > (double)in->t_us[r[b[h]]] && b[h] + 1 < m[h]) { /* the next stretch */
                j[h] = a[h] = b[h] + 1;
                b[h] = stretch_end(in, r, m[h], a[h]);
            }
            if (t < (double)in->t_us[r[a[h]]] || t > (double)in->t_us[r[b[h]]]) continue; /* away */
            while (j[h] + 1 < b[h] && (double)in->t_us[r[j[h] + 1]] <= t) j[h]++;
            const size_t r0 = r[j[h]], r1 = r[j[h] < b[h] ? j[h] + 1 : j[h]];
            const double w = r1 == r0 ? 0 : (t - (double)in->t_us[r0]) / (double)(in->t_us[r1] - in->t_us[r0]);
            assert_true(out->n < 1024);
            out->frame[out->n] = k;
            out->t_us[out->n] = llround(t);
            snprintf(out->lead[out->n], sizeof out->lead[0], "%s", in->lead[r0]);
            for (int c = 0; c < 69; c++) out->v[out->n][c] = (1 - w) * in->v[r0][c] + w * in->v[r1][c];
            out->n++;
        }
    }
}

/* The value column (0..68, after frame, timestamp, hand id and side) named name in r's
 * header. */
static int value_column(const rows *r, const char *name)
{
    char header[4096];
    snprintf(header, sizeof header, "%s", r->header);
    int col = 0;
    char *save = NULL;
    for (char *tok = strtok_r(header, ",\r\n", &save); tok; tok = strtok_r(NULL, ",\r\n", &save), col++)
        if (!strcmp(tok, name)) return col - 4;
    fail_msg("no column %s", name);
    return -1;
}

/* A performer who holds the hand still and pinches: every row the recording's middle row,
 * its thumb and index tips drawn c of the way to their midpoint and their distal joints
 * half as far, c = 0.45 (1 - cos(2 pi t / 1.5 s)): closing to 90% and opening again every
 * 1.5 s, from the pose at engage (the gap at its widest there, so the jaw's stop at shut is
 * where the hand comes back to; tools/hands-variants' stillpinch). One hand. */
static void still_pinch(const rows *in, rows *out)
{
    *out = *in;
    const rows *mid = in;
    size_t m = in->n / 2;
    int tip[2][3], dip[2][3];
    static const char *const fingers[2] = {"thumb", "index"}, *const axes = "xyz";
    for (int f = 0; f < 2; f++)
        for (int a = 0; a < 3; a++) {
            char name[32];
            snprintf(name, sizeof name, "%s_tip_%c", fingers[f], axes[a]);
            tip[f][a] = value_column(in, name);
            snprintf(name, sizeof name, "%s_dip_%c", fingers[f], axes[a]);
            dip[f][a] = value_column(in, name);
        }
    for (size_t i = 0; i < out->n; i++) {
        memcpy(out->v[i], mid->v[m], sizeof out->v[i]);
        snprintf(out->lead[i], sizeof out->lead[i], "%s", mid->lead[m]);
        double c = 0.45 * (1 - cos(2 * M_PI * (double)(in->t_us[i] - in->t_us[0]) / 1.5e6));
        for (int a = 0; a < 3; a++) {
            double centre = 0.5 * (mid->v[m][tip[0][a]] + mid->v[m][tip[1][a]]);
            for (int f = 0; f < 2; f++) {
                out->v[i][tip[f][a]] += c * (centre - out->v[i][tip[f][a]]);
                out->v[i][dip[f][a]] += 0.5 * c * (centre - out->v[i][dip[f][a]]);
            }
        }
    }
}

/* ---- the sessions, in lockstep ----------------------------------------------------------- */

typedef struct run {
    fp_session *s;
    int64_t t0;
    size_t frames;
    float (*hand)[NJ][3];      /* MAX_FRAMES poses of the right hand, mesh units */
    bool *present;
    float *prev;               /* the last frame's face */
    float *face;               /* MAX_FRAMES x every FACE_STRIDE-th vertex of the face */
} run;

#define FACE_STRIDE 16

static void open_run(run *r, const char *spec)
{
    memset(r, 0, sizeof *r);
    fp_session_options so;
    fp_test_face_options(&so, getenv("FP_TEST_STEADY_MAPPING") ? getenv("FP_TEST_STEADY_MAPPING") : MAPPING, NULL);
    so.inputs[0] = spec;
    so.input_count = 1;
    so.input_clock = true;
    so.exact_frames = true;        /* the engine's shape, not the contact guard's hold */
    char err[2048];
    int rc = fp_session_create(&so, &r->s, err, sizeof err);
    if (!rc) rc = fp_session_start(r->s, err, sizeof err);
    if (rc) fprintf(stderr, "%s: %s\n", spec, err);
    assert_int_equal(rc, 0);
    r->hand = calloc(MAX_FRAMES, sizeof *r->hand);
    r->present = calloc(MAX_FRAMES, sizeof *r->present);
    r->prev = calloc(fp_session_vertex_count(r->s) * 3, sizeof(float));
    r->face = calloc((size_t)MAX_FRAMES * (fp_session_vertex_count(r->s) / FACE_STRIDE + 1) * 3, sizeof(float));
    r->t0 = fp_test_session_t0(r->s);
}

static void close_run(run *r)
{
    fp_session_destroy(&r->s);
    free(r->hand);
    free(r->present);
    free(r->prev);
    free(r->face);
}

/* Step frame k; false once the recording has ended. */
static bool step(run *r, size_t k)
{
    if (fp_session_finished(r->s) || k >= MAX_FRAMES) return false;
    fp_session_step(r->s, fp_test_frame_time(r->s, r->t0, k, FPS), NULL);
    const fp_hand_pose *h = fp_session_hand(r->s, FP_HAND_RIGHT);
    r->present[k] = h && h->present;
    if (r->present[k]) memcpy(r->hand[k], h->joints, sizeof r->hand[k]);
    if (getenv("FP_TEST_STUTTER_TIMES") && h) printf("  frame %zu: %.2f ms after the last sample (at %.2f ms)\n", k, (fp_test_frame_time(r->s, r->t0, k, FPS) - h->time_ns) / 1e6, (h->time_ns - r->t0) / 1e6);
    size_t n = fp_session_vertex_count(r->s), m = n / FACE_STRIDE + 1;
    const float *pos = fp_session_positions(r->s);
    for (size_t v = 0; v * FACE_STRIDE < n; v++)
        memcpy(&r->face[(k * m + v) * 3], &pos[v * FACE_STRIDE * 3], 3 * sizeof(float));
    r->frames = k + 1;
    return true;
}

static double d3(const float *a, const float *b)
{
    return sqrt(pow((double)a[0] - b[0], 2) + pow((double)a[1] - b[1], 2) + pow((double)a[2] - b[2], 2));
}

static char *copy_path(const char *name)
{
    static char p[4][512];
    static int i;
    char *s = p[i++ % 4];
    snprintf(s, 512, "%s/%s", g_dir, name);
    return s;
}

/* The recording clip (NULL: FP_TEST_STEADY_CLIP, else HandSplay) in the shared data; a clip
 * starting with '/' is a file's path (a copy the test made). */
static const char *clip_path(const char *clip)
{
    static char p[4300];
    if (!clip) clip = getenv("FP_TEST_STEADY_CLIP");
    if (clip && clip[0] == '/') return clip;
    snprintf(p, sizeof p, "%s/hands/leap-motion/%s_joints_mm.csv", fp_test_data_dir(),
             clip && *clip ? clip : "HandSplay-110fps");
    return p;
}

/* ---- jitter and lag ------------------------------------------------------------------ */

/* The shift s (frames, -4 to 4 by 0.05) that brings the clean trajectory nearest to the other:
 * the least mean squared difference between other[k] and clean at k - s (interpolated
 * between frames), each coordinate's mean difference taken out (a constant offset, such as
 * a mapping's zero taken from a noisy first pose, is no lag), over the frames where both saw
 * the hand: the cross-correlation's peak. Positive: the other lags. clean and other:
 * frames x npts points x 3. */
static double best_shift(const float *clean, const float *other, size_t npts, const bool *seen_clean,
                         const bool *seen_other, size_t frames)
{
    double best = INFINITY, best_s = 0;
    double *sum = calloc(npts * 3, sizeof *sum);
    for (int si = -80; si <= 80; si++) {
        double s = si * 0.05, e = 0;
        size_t m = 0;
        memset(sum, 0, npts * 3 * sizeof *sum);
        for (size_t k = 5; k + 5 < frames; k++) {
            double at = (double)k - s;
            size_t a = (size_t)floor(at);
            double w = at - (double)a;
            if (a + 1 >= frames || !seen_clean[a] || !seen_clean[a + 1] || !seen_other[k]) continue;
            for (size_t c = 0; c < npts * 3; c++) {
                double ref = (1 - w) * clean[a * npts * 3 + c] + w * clean[(a + 1) * npts * 3 + c];
                double d = other[k * npts * 3 + c] - ref;
                e += d * d;
                sum[c] += d;
            }
            m++;
        }
        if (!m) continue;
        for (size_t c = 0; c < npts * 3; c++) e -= sum[c] * sum[c] / (double)m;
        if (e / (double)m < best) {
            best = e / (double)m;
            best_s = s;
        }
    }
    free(sum);
    return best_s;
}

/* clip as clip_path takes it; hz > 0: resampled at hz first; hand_jitter: the hand's jitter
 * asserted too (else printed only) */
static void jitter_and_lag(const char *clip, double hz, bool hand_jitter)
{
    static rows clean, noisy, recorded;
    read_rows(clip_path(clip), &clean);
    const char *clean_csv = clip_path(clip);
    if (hz > 0) {
        recorded = clean;
        resample(&recorded, hz, &clean);
        clean_csv = copy_path("clean_joints_mm.csv");
        write_rows(clean_csv, &clean);
    }
    noisy = clean;
    add_noise(&noisy, 1.0, g_seed);
    const char *noisy_csv = copy_path("noisy_joints_mm.csv");
    write_rows(noisy_csv, &noisy);
    char spec[3][4400];
    snprintf(spec[0], sizeof spec[0], "replay:%s,fast=1", clean_csv);
    snprintf(spec[1], sizeof spec[1], "replay:%s,fast=1", noisy_csv);
    snprintf(spec[2], sizeof spec[2], "replay:%s,fast=1,filter=oneeuro%s", noisy_csv,
             getenv("FP_TEST_FILTER_KEYS") ? getenv("FP_TEST_FILTER_KEYS") : "");
    run r[3];
    for (int i = 0; i < 3; i++) open_run(&r[i], spec[i]);
    size_t n = fp_session_vertex_count(r[0].s);
    double mm = fp_session_head(r[0].s)->mm_per_unit;
    for (int i = 0; i < 3; i++) memcpy(r[i].prev, fp_session_positions(r[i].s), n * 3 * sizeof(float));

    double hand_j[3] = {0}, face_j[3] = {0};   /* sums of squares over the hold frames */
    size_t holds = 0, moving = 0, frames = 0, pops = 0;
    double pop_mm = 0;
    for (size_t k = 0;; k++) {
        bool on = true;
        for (int i = 0; i < 3; i++) on = step(&r[i], k) && on;
        if (!on) break;
        frames = k + 1;
        if (k == 0 || !r[0].present[k] || !r[0].present[k - 1] || !r[1].present[k - 1]) {
            for (int i = 0; i < 3; i++) memcpy(r[i].prev, fp_session_positions(r[i].s), n * 3 * sizeof(float));
            continue;
        }
        double fastest = 0;
        for (int j = 0; j < NJ; j++) fastest = fmax(fastest, d3(r[0].hand[k][j], r[0].hand[k - 1][j]) * mm * FPS);
        bool hold = fastest < HOLD_MM_S;
        /* a pop: the clean run's face moving in one frame over twice as far as the hand's
         * fastest joint, and 1 mm more (printed, not asserted: see the header) */
        double face_step = 0;
        const float *q = fp_session_positions(r[0].s);
        for (size_t v = 0; v < n; v++) face_step = fmax(face_step, d3(&q[3 * v], &r[0].prev[3 * v]) * mm);
        if (face_step > 2 * fastest / FPS + 1.0) {
            pops++;
            pop_mm = fmax(pop_mm, face_step);
        }
        holds += hold;
        moving += !hold;
        const float *clean_now = fp_session_positions(r[0].s);
        for (int i = 1; i < 3 && hold; i++) {
            for (int j = 0; j < NJ; j++)
                for (int c = 0; c < 3; c++) {
                    double e = ((double)r[i].hand[k][j][c] - r[i].hand[k - 1][j][c]) -
                               ((double)r[0].hand[k][j][c] - r[0].hand[k - 1][j][c]);
                    hand_j[i] += e * e;
                }
            const float *now = fp_session_positions(r[i].s);
            for (size_t v = 0; v < 3 * n; v++) {
                double e = ((double)now[v] - r[i].prev[v]) - ((double)clean_now[v] - r[0].prev[v]);
                face_j[i] += e * e;
            }
        }
        for (int i = 0; i < 3; i++) memcpy(r[i].prev, fp_session_positions(r[i].s), n * 3 * sizeof(float));
    }
    printf("pops in %s%s (the clean run's face moving in a frame over twice the hand's fastest joint "
           "+ 1 mm): %zu, largest %.1f mm\n", strrchr(clip_path(clip), '/') + 1, hz > 0 ? " resampled" : "",
           pops, pop_mm);
    assert_true(holds >= 10);
    assert_true(moving >= 10);
    double hand_rms[3], face_rms[3];
    for (int i = 1; i < 3; i++) {
        hand_rms[i] = sqrt(hand_j[i] / (double)(holds * NJ * 3)) * mm;
        face_rms[i] = sqrt(face_j[i] / (double)(holds * n * 3)) * mm;
    }
    /* Lag: the filtered (and, for scale, the unfiltered) hand and face against the clean ones
     * shifted by s frames, over the frames where all three saw the hand. */
    double hand_lag[3] = {0}, face_lag[3] = {0};
    size_t m = n / FACE_STRIDE + 1;
    for (int i = 1; i < 3; i++) {
        hand_lag[i] = best_shift(&r[0].hand[0][0][0], &r[i].hand[0][0][0], NJ, r[0].present, r[i].present, frames);
        face_lag[i] = best_shift(r[0].face, r[i].face, m, r[0].present, r[i].present, frames);
    }
    printf("steady: %s%s, %s: ", strrchr(clip_path(clip), '/') + 1, hz > 0 ? " resampled" : "",
           spec[2] + strlen(noisy_csv) + strlen("replay:,fast=1,"));
    if (hz > 0) printf("(%.0f Hz) ", hz);
    printf("%zu frames at %d fps, %zu still-hold frames (clean hand slower than %.0f mm/s), "
           "%zu moving\n  hand jitter in holds (RMS frame-to-frame beyond the clean motion): "
           "unfiltered %.3f mm, filtered %.3f mm: %.1fx less\n  face jitter in holds: unfiltered "
           "%.3g mm, filtered %.3g mm: %.1fx less\n  lag behind the clean motion (cross-correlation "
           "peak): hand unfiltered %.2f frames, filtered %.2f frames (%.1f ms); face unfiltered "
           "%.2f, filtered %.2f frames (%.1f ms)\n",
           frames, FPS, holds, HOLD_MM_S, moving, hand_rms[1], hand_rms[2], hand_rms[1] / hand_rms[2],
           face_rms[1], face_rms[2], face_rms[1] / face_rms[2], hand_lag[1], hand_lag[2],
           hand_lag[2] * 1e3 / FPS, face_lag[1], face_lag[2], face_lag[2] * 1e3 / FPS);
    if (hand_jitter) assert_true(hand_rms[1] >= 5 * hand_rms[2]);
    assert_true(face_rms[2] > 0 || face_rms[1] == 0);
    assert_true(face_rms[1] >= 5 * face_rms[2]);
    /* the unfiltered hand has no lag (a check of the measure); the unfiltered face's peak is
     * printed only: the noise through the mapping's clamps (the jaw closes no further than
     * shut) moves it (-0.35 frames here; on Waiting, whose face hardly moves but by the
     * noise, 1.7 frames, and the measure means nothing there) */
    assert_true(fabs(hand_lag[1]) <= 0.5);
    assert_true(hand_lag[2] <= 1.0);
    assert_true(face_lag[2] <= 1.0);
    for (int i = 0; i < 3; i++) close_run(&r[i]);
}

/* ---- stutter -------------------------------------------------------------------------- */

/* Frames whose right hand equals the last frame's bit for bit while the hand moves (the
 * clean recording's joints, here the hand itself: moving = it was seen in both frames and
 * any joint of the frame after or before moved). */
static size_t stutters(const char *spec, size_t *frames_out, size_t *moving_out)
{
    run r;
    open_run(&r, spec);
    size_t k = 0;
    while (step(&r, k)) k++;
    size_t rep = 0, moving = 0;
    size_t seen = 0;
    for (size_t i = 1; i + 1 < r.frames; i++) {
        if (!r.present[i - 1] || !r.present[i] || !r.present[i + 1]) continue;
        if (++seen <= 1) continue; /* the hand's first frames: one sample shows no motion yet */
        bool same = !memcmp(r.hand[i], r.hand[i - 1], sizeof r.hand[i]);
        bool moves = memcmp(r.hand[i + 1], r.hand[i - 1], sizeof r.hand[i]) != 0;
        moving += moves;
        rep += same && moves;
        if (same && moves && getenv("FP_TEST_STUTTER_SPEC")) printf("  repeated: frame %zu\n", i);
    }
    *frames_out = r.frames;
    *moving_out = moving;
    close_run(&r);
    return rep;
}

static void test_jitter_and_lag(void **state)
{
    (void)state;
    jitter_and_lag(NULL, getenv("FP_TEST_STEADY_HZ") ? atof(getenv("FP_TEST_STEADY_HZ")) : 0, true);
}

/* The same at 57 Hz (the recording resampled), a slower tracker's rate: each sample weighs
 * more in the filter, and a frame's prediction reaches further. */
static void test_jitter_and_lag_57hz(void **state)
{
    (void)state;
    jitter_and_lag(NULL, 57, true);
}

/* The face's criteria (5x less jitter, at most a frame of lag) on the other recordings, at
 * their rate and resampled at 57 Hz (three-claps' two hands each on its own). The hand's
 * jitter is printed, not asserted: between three-claps' claps (11 hold frames, each right
 * after a fast motion) it is 4.7x at its rate (core/pose/fp_filter.h); the issue asks it of
 * the face. */
static void test_jitter_and_lag_other_recordings(void **state)
{
    (void)state;
    if (getenv("FP_TEST_STEADY_CLIP")) skip(); /* a run for one clip: the tests above */
    static const struct { const char *clip; double hz; } runs[] = {
        {"grab", 0}, {"grab", 57}, {"Waiting-110fps", 0}, {"Waiting-110fps", 57},
        {"three-claps", 0}, {"three-claps", 57}};
    for (size_t i = 0; i < sizeof runs / sizeof runs[0]; i++) jitter_and_lag(runs[i].clip, runs[i].hz, false);
}

/* The criteria, the hand's jitter too, on a still hand pinching (still_pinch, from the
 * HandSplay recording's middle pose, at its 108 Hz and resampled at 57 Hz): the one-hand
 * mapping's jaw follows the thumb-to-index opening, which comes back to the pose at engage
 * every 1.5 s, where the jaw's stop at shut is. Before the jaw eased in (map-onehand's ease),
 * a noisy copy's zero (its first sample) put that stop about a millimetre off the clean
 * run's, and the filtered face's jitter in holds was only 2.6x less than the unfiltered one's
 * (8.7x now). */
static void test_jitter_and_lag_still_pinch(void **state)
{
    (void)state;
    static rows real, held;
    read_rows(clip_path(NULL), &real);
    still_pinch(&real, &held);
    char held_csv[512]; /* copy_path's buffers are reused by the runs below */
    snprintf(held_csv, sizeof held_csv, "%s", copy_path("stillpinch_joints_mm.csv"));
    write_rows(held_csv, &held);
    /* two seeds: the turns of the pinch make this copy's holds the most sensitive to the
     * noise drawn (at 57 Hz, before the trend's fade, fp_filter.h: seed 2 4.4x, seed 51 8.6x;
     * with it 5.6x and 10.9x) */
    const uint64_t seed = g_seed;
    for (int i = 0; i < 2; i++) {
        g_seed = i ? 2 : seed;
        jitter_and_lag(held_csv, 0, true);
        jitter_and_lag(held_csv, 57, true);
    }
    g_seed = seed;
}

static void test_no_stutter(void **state)
{
    (void)state;
    static rows clean, slow;
    read_rows(clip_path(NULL), &clean);
    resample(&clean, 57.0, &slow);
    const char *slow_csv = copy_path("57hz_joints_mm.csv");
    write_rows(slow_csv, &slow);
    char spec[2][4400];
    snprintf(spec[0], sizeof spec[0], "replay:%s,fast=1", clip_path(NULL));
    snprintf(spec[1], sizeof spec[1], "replay:%s,fast=1", slow_csv);
    size_t frames[2], moving[2], rep[2];
    if (getenv("FP_TEST_STUTTER_SPEC")) { /* another input instead (the figures printed) */
        size_t f, m, r = stutters(getenv("FP_TEST_STUTTER_SPEC"), &f, &m);
        printf("stutter at %d fps: %s: %zu repeated of %zu moving frames (%zu in all)\n", FPS,
               getenv("FP_TEST_STUTTER_SPEC"), r, m, f);
        assert_int_equal(r, 0);
        return;
    }
    for (int i = 0; i < 2; i++) rep[i] = stutters(spec[i], &frames[i], &moving[i]);
    printf("stutter at %d fps: 108 Hz recording %zu repeated of %zu moving frames (%zu in all); "
           "57 Hz copy (%zu rows) %zu of %zu (%zu)\n", FPS, rep[0], moving[0], frames[0], slow.n,
           rep[1], moving[1], frames[1]);
    assert_true(moving[0] > 100 && moving[1] > 100);
    assert_int_equal(rep[0], 0);
    assert_int_equal(rep[1], 0);
}

static int setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/fp_steady_XXXXXX");
    if (getenv("FP_TEST_STEADY_SEED")) g_seed = strtoull(getenv("FP_TEST_STEADY_SEED"), NULL, 10);
    return mkdtemp(g_dir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char p[600];
    snprintf(p, sizeof p, "%s/noisy_joints_mm.csv", g_dir);
    unlink(p);
    snprintf(p, sizeof p, "%s/57hz_joints_mm.csv", g_dir);
    unlink(p);
    snprintf(p, sizeof p, "%s/clean_joints_mm.csv", g_dir);
    unlink(p);
    snprintf(p, sizeof p, "%s/stillpinch_joints_mm.csv", g_dir);
    unlink(p);
    rmdir(g_dir);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_jitter_and_lag),
        cmocka_unit_test(test_jitter_and_lag_57hz),
        cmocka_unit_test(test_jitter_and_lag_other_recordings),
        cmocka_unit_test(test_jitter_and_lag_still_pinch),
        cmocka_unit_test(test_no_stutter),
    };
    if (getenv("FP_TEST_STUTTER_SPEC")) { /* that input's stutter check alone */
        const struct CMUnitTest one[] = {cmocka_unit_test(test_no_stutter)};
        return cmocka_run_group_tests(one, setup, teardown);
    }
    return cmocka_run_group_tests(tests, setup, teardown);
}
