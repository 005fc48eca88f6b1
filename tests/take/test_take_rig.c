/* Takes with a rig (ICT face, rigs/ict-facekit.json): the jaw opened by the host's API
 * (fp_session_set_channel, the viewer's J/K keys) while a take records is in the take, so
 * that playing it (fp_take_player, as `play` and the viewer's review do) gives every frame's
 * shape bit for bit, and `facepuppet export` (PC2, GLB) carries the jaw's motion.
 *
 * The recording session: the fixture mapping map-press (tests/rig) pressing the forehead with
 * jaw=none (it leaves jaw.open to the host), committing once; jaw.open set from the API before
 * the take starts (the take must begin with it, not with the neutral jaw) and at several
 * frames during it, and a reset (jaw back to neutral) in the middle. */
#define _GNU_SOURCE
#include "fp_rig.h"
#include "fp_session.h"
#include "fp_session_take.h"
#include "fp_take.h"
#include "fp_take_player.h"
#include "fp_test_support.h"
#include "gltf_anim.h"

#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <zlib.h>

#define FRAMES 24

static char tmp[256];

static const fp_plugin_path *plugins(void)
{
    static fp_plugin_path path;
    static int done;
    if (!done) {
        const char *dirs[] = {FP_TEST_FIXTURE_DIR, fp_test_plugin_dir()};
        fp_plugin_path_init(&path, dirs, 2, NULL);
        done = 1;
    }
    return &path;
}

/* jaw.open set through the API before frame k (NAN: not set), and where the session resets. */
static float jaw_before(int k)
{
    switch (k) {
    case 4: return 0.6f;
    case 9: return 1.0f;
    case 15: return 0.1f;
    case 20: return 0.8f;
    default: return NAN;
    }
}
#define RESET_FRAME 18

typedef struct recorded {
    char path[4096];
    size_t n;
    uint32_t chin;
    float *pos;              /* FRAMES x n x 3: what the recording session showed */
    float jaw[FRAMES];       /* jaw.open after each frame */
} recorded;

static recorded rec;

static double chin_dist(const float *a, const float *b)
{
    double d = 0;
    for (int i = 0; i < 3; i++) d += pow((double)a[3 * rec.chin + i] - b[3 * rec.chin + i], 2);
    return sqrt(d);
}

static void record_take(void)
{
    fp_session_options so = {0};
    so.mesh_path = fp_test_face_path();
    so.mapping = "press,jaw=none,depth=6,commit=8";
    so.plugin_path = plugins();
    so.rig_dir = FP_TEST_RIGS_DIR;
    so.record = fp_session_take_sink;
    fp_session_take take;
    fp_session_take_options to = {.dir = tmp, .slate = "jaw"};
    fp_session_take_init(&take, &to, &so);
    so.record_user = &take;
    char err[2048] = "";
    fp_session *s = NULL;
    int rc = fp_session_create(&so, &s, err, sizeof err);
    if (rc) fail_msg("session: %s", err);
    const fp_rig *rig = fp_session_rig(s);
    assert_non_null(rig);
    long chin = fp_rig_landmark_index(rig, "chin");
    assert_true(chin >= 0);
    rec.chin = (uint32_t)chin;
    rec.n = fp_session_vertex_count(s);
    rec.pos = malloc(FRAMES * rec.n * 3 * sizeof(float));
    assert_non_null(rec.pos);

    int64_t t = 1000000000;
    /* before the take: the jaw half open, two frames */
    assert_int_equal(fp_session_set_channel(s, "jaw.open", 0.25), 0);
    for (int k = 0; k < 2; k++, t += 16666667) fp_session_step(s, t, NULL);
    rc = fp_session_take_start(&take, s, t, err, sizeof err);
    if (rc) fail_msg("take start: %s", err);
    for (int k = 0; k < FRAMES; k++, t += 16666667) {
        if (!isnan(jaw_before(k))) assert_int_equal(fp_session_set_channel(s, "jaw.open", jaw_before(k)), 0);
        if (k == RESET_FRAME) fp_session_reset(s);
        fp_frame_stats st;
        fp_session_step(s, t, &st);
        memcpy(&rec.pos[k * rec.n * 3], fp_session_positions(s), rec.n * 3 * sizeof(float));
        rec.jaw[k] = (float)fp_session_channel(s, "jaw.open");
        if (k == RESET_FRAME - 1) assert_int_equal(fp_session_commits(s), 1); /* mapping frame 8 */
    }
    fp_session_take_result res;
    rc = fp_session_take_stop(&take, &res, err, sizeof err);
    if (rc) fail_msg("take stop: %s", err);
    assert_int_equal(res.frames, FRAMES);
    assert_int_equal(res.dropped, 0);
    snprintf(rec.path, sizeof rec.path, "%s", res.path);
    assert_int_equal(fp_session_commits(s), 0); /* the reset dropped it */
    fp_session_destroy(&s);

    /* the jaw moved: the chin travels between the take's frames */
    double travel = 0;
    for (int k = 1; k < FRAMES; k++) travel = fmax(travel, chin_dist(&rec.pos[0], &rec.pos[k * rec.n * 3]));
    printf("recorded %s: chin travels up to %.3f units from frame 0 (jaw.open %.2f .. %.2f)\n", rec.path, travel,
           rec.jaw[RESET_FRAME], rec.jaw[9]);
    assert_true(travel > 0.3);
    assert_true(rec.jaw[0] == 0.25f && rec.jaw[9] == 1.0f && rec.jaw[RESET_FRAME] == 0.0f);
}

static int setup(void **state)
{
    (void)state;
    snprintf(tmp, sizeof tmp, "%s/fp-take-rig-XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    if (!mkdtemp(tmp)) return -1;
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    free(rec.pos);
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
    return system(cmd) == 0 ? 0 : -1;
}

/* Each frame record holds the rig's channels as applied that frame (docs/take-format.md). */
static void test_frames_hold_channels(void **state)
{
    (void)state;
    record_take();
    fp_take_reader *r = NULL;
    char err[1024];
    assert_int_equal(fp_take_reader_open(rec.path, &r, err, sizeof err), 0);
    assert_int_equal(fp_take_reader_frames(r), FRAMES);
    for (size_t k = 0; k < FRAMES; k++) {
        fp_take_frame f;
        assert_int_equal(fp_take_reader_read(r, k, &f, err, sizeof err), 0);
        assert_non_null(f.control);
        size_t found = 0;
        for (size_t c = 0; c < f.control->channel_count; c++)
            if (!strcmp(f.control->channels[c].name, "jaw.open")) {
                found++;
                if (f.control->channels[c].value != rec.jaw[k])
                    fail_msg("frame %zu: jaw.open %g recorded, %g applied", k, f.control->channels[c].value, rec.jaw[k]);
            }
        assert_int_equal(found, 1);
    }
    fp_take_reader_close(&r);
}

static unsigned char *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc(len > 0 ? (size_t)len : 1);
    *n = b ? fread(b, 1, (size_t)len, f) : 0;
    fclose(f);
    return b;
}

/* The file says 1.1 or later; the same take marked 1.0 (a take of the first version: same layout) is
 * still read, every frame. */
static void test_version(void **state)
{
    (void)state;
    size_t n = 0;
    unsigned char *b = slurp(rec.path, &n);
    assert_non_null(b);
    assert_true(n > 16);
    fp_take_reader *r = NULL;
    char err[1024];
    assert_int_equal(fp_take_reader_open_memory(b, n, "new", &r, err, sizeof err), 0);
    assert_int_equal(fp_take_reader_summary(r)->version_major, 1);
    assert_int_equal(fp_take_reader_summary(r)->version_minor, FP_TAKE_VERSION_MINOR);
    assert_true(FP_TAKE_VERSION_MINOR >= 1); /* (1.2 added keys and an event type only) */
    fp_take_reader_close(&r);
    b[10] = 0, b[11] = 0; /* minor 0, the signature's crc32 again */
    uint32_t crc = (uint32_t)crc32(0L, b, 12);
    for (int i = 0; i < 4; i++) b[12 + i] = (unsigned char)(crc >> (8 * i));
    assert_int_equal(fp_take_reader_open_memory(b, n, "old", &r, err, sizeof err), 0);
    assert_int_equal(fp_take_reader_summary(r)->version_minor, 0);
    assert_int_equal(fp_take_reader_frames(r), FRAMES);
    assert_false(fp_take_reader_summary(r)->cut);
    fp_take_reader_close(&r);
    free(b);
}

/* A copy of the recorded take whose header has `key`'s value (a JSON value's text, up to the
 * next ',' or '}') replaced by `value`, its chunk's crc32 made again: a take edited by hand
 * or by another tool, every check of the reader passed. Into path (n bytes). */
static void take_with_header_value(const char *key, const char *value, char *path, size_t n)
{
    FILE *f = fopen(rec.path, "rb");
    assert_non_null(f);
    static unsigned char b[1 << 20];
    size_t len = fread(b, 1, sizeof b, f);
    fclose(f);
    uint32_t hl;
    memcpy(&hl, b + 16 + 8, 4); /* the HEAD chunk's payload length (little-endian here) */
    char *json = calloc(1, hl + strlen(value) + 1), *out = calloc(1, hl + strlen(value) + 1);
    memcpy(json, b + 32, hl);
    char want[64];
    snprintf(want, sizeof want, "\"%s\":", key);
    char *at = strstr(json, want);
    assert_non_null(at);
    at += strlen(want);
    size_t end = strcspn(at, ",}");
    snprintf(out, hl + strlen(value) + 1, "%.*s%s%s", (int)(at - json), json, value, at + end);
    const uint32_t nl = (uint32_t)strlen(out);
    snprintf(path, n, "%s/edited.fptake", tmp);
    f = fopen(path, "wb");
    assert_non_null(f);
    unsigned char head[16];
    memcpy(head, b + 16, 16);
    memcpy(head + 8, &nl, 4);
    uLong crc = crc32(crc32(0L, Z_NULL, 0), head, 16);
    crc = crc32(crc, (const Bytef *)out, nl);
    const uint32_t c32 = (uint32_t)crc;
    fwrite(b, 1, 16, f);
    fwrite(head, 1, 16, f);
    fwrite(out, 1, nl, f);
    fwrite(&c32, 1, 4, f);
    fwrite(b + 32 + hl + 4, 1, len - (32 + hl + 4), f);
    fclose(f);
    free(json);
    free(out);
}

/* play of a take whose recorded session cannot be made again names the take: its rig gone
 * ("x.json: No such file or directory" alone, before, named neither the take nor that it was
 * the take's rig), or a radius the session refuses (said as a "--radius" that play has not,
 * and exit 64 for the take's damage, before: now -ERANGE, 65). */
static void test_play_names_the_take(void **state)
{
    (void)state;
    char path[4200], err[4096];
    fp_take_player *p = NULL;
    take_with_header_value("rig", "\"/nonexistent/rigs/face.json\"", path, sizeof path);
    int rc = fp_take_player_open(path, NULL, plugins(), &p, err, sizeof err);
    printf("rig gone: %d, %s\n", rc, err);
    assert_int_equal(rc, -ENOENT);
    assert_null(p);
    assert_non_null(strstr(err, path));
    assert_non_null(strstr(err, "the take's rig /nonexistent/rigs/face.json"));
    take_with_header_value("radius", "1e30", path, sizeof path);
    rc = fp_take_player_open(path, NULL, plugins(), &p, err, sizeof err);
    printf("radius 1e30: %d, %s\n", rc, err);
    assert_int_equal(rc, -ERANGE); /* a file's value: 65, as the calibration's scale */
    assert_null(p);
    assert_non_null(strstr(err, path));
    assert_non_null(strstr(err, "the take's radius 1e+30"));
    assert_null(strstr(err, "--radius"));
}

/* play: every frame bit for bit, the chin included; the channel as recorded. */
static void test_play_reproduces_jaw(void **state)
{
    (void)state;
    fp_take_player *p = NULL;
    char err[2048];
    int rc = fp_take_player_open(rec.path, NULL, plugins(), &p, err, sizeof err);
    if (rc) fail_msg("player: %s", err);
    fp_session *s = fp_take_player_session(p);
    assert_non_null(fp_session_rig(s));
    assert_int_equal(fp_session_vertex_count(s), rec.n);
    fp_take_frame f;
    int k = 0;
    double worst_chin = 0;
    size_t worst_vertices = 0;
    while ((rc = fp_take_player_next(p, &f, NULL, err, sizeof err)) == 1) {
        assert_true(k < FRAMES);
        const float *got = fp_session_positions(s), *want = &rec.pos[(size_t)k * rec.n * 3];
        size_t differ = 0;
        for (size_t v = 0; v < rec.n; v++) differ += memcmp(&got[3 * v], &want[3 * v], 12) != 0;
        double dc = 0;
        for (int i = 0; i < 3; i++) dc = fmax(dc, fabs((double)got[3 * rec.chin + i] - want[3 * rec.chin + i]));
        worst_chin = fmax(worst_chin, dc);
        if (differ > worst_vertices) worst_vertices = differ;
        if (differ || fp_session_channel(s, "jaw.open") != rec.jaw[k])
            fprintf(stderr, "frame %d: %zu vertices differ, chin off by %.6g units, jaw.open %g (recorded %g)\n", k,
                    differ, dc, fp_session_channel(s, "jaw.open"), rec.jaw[k]);
        k++;
    }
    assert_int_equal(rc, 0);
    assert_int_equal(k, FRAMES);
    printf("played: chin off by at most %.3g units, at most %zu vertices differ in a frame\n", worst_chin, worst_vertices);
    assert_true(worst_chin == 0);
    assert_int_equal(worst_vertices, 0);
    fp_take_player_close(&p);
}

static void run_export(const char *format, const char *out)
{
    char cmd[9000];
    snprintf(cmd, sizeof cmd, "'%s/bin/facepuppet' export '%s' --plugin-dir '%s' --format %s --out '%s'%s >'%s.log' 2>&1",
             fp_test_build_dir(), rec.path, fp_test_plugin_dir(), format, out,
             strcmp(format, "glb") ? "" : " --max-error 0.01", out);
    int rc = system(cmd);
    if (rc) {
        char log[4200];
        snprintf(log, sizeof log, "%s.log", out);
        size_t n = 0;
        unsigned char *b = slurp(log, &n);
        fail_msg("%s exited %d: %.*s", cmd, rc, (int)n, b ? (const char *)b : "");
    }
}

/* facepuppet export: the PC2 point cache holds every recorded frame bit for bit; the GLB's
 * morph targets, evaluated at each frame's time (tinygltf, tests/export/gltf_anim.cpp), move
 * the chin as recorded within the export's error (0.01 mm asked). */
static void test_export_carries_jaw(void **state)
{
    (void)state;
    char pc2[400], glb[400];
    snprintf(pc2, sizeof pc2, "%s/jaw.pc2", tmp);
    snprintf(glb, sizeof glb, "%s/jaw.glb", tmp);
    run_export("pc2", pc2);
    size_t len = 0;
    unsigned char *b = slurp(pc2, &len);
    assert_non_null(b);
    uint32_t points, samples;
    memcpy(&points, b + 16, 4);
    memcpy(&samples, b + 28, 4);
    assert_int_equal(points, rec.n);
    assert_int_equal(samples, FRAMES);
    assert_int_equal(len, 32 + (size_t)FRAMES * rec.n * 12);
    size_t bad = 0;
    for (int k = 0; k < FRAMES; k++) bad += memcmp(b + 32 + (size_t)k * rec.n * 12, &rec.pos[(size_t)k * rec.n * 3], rec.n * 12) != 0;
    printf("pc2: %zu of %d frames differ from the recorded ones\n", bad, FRAMES);
    assert_int_equal(bad, 0);
    free(b);

    run_export("glb", glb);
    fp_test_gltf_anim a;
    char err[1024];
    if (fp_test_gltf_anim_load(glb, rec.n, &a, err, sizeof err)) fail_msg("%s: %s", glb, err);
    assert_int_equal(a.keys, FRAMES);
    assert_true(a.targets >= 1);
    fp_take_player *p = NULL;
    if (fp_take_player_open(rec.path, NULL, plugins(), &p, err, sizeof err)) fail_msg("player: %s", err);
    const double mm_per_unit = fp_take_player_mm_per_unit(p); /* what export converts with */
    fp_take_player_close(&p);
    fp_take_reader *r = NULL;
    assert_int_equal(fp_take_reader_open(rec.path, &r, err, sizeof err), 0);
    float *w = calloc(a.targets, sizeof *w);
    assert_non_null(w);
    double worst = 0, travel = 0, first[3] = {0};
    size_t chin_copies = 0;
    int64_t t0 = 0;
    for (int k = 0; k < FRAMES; k++) {
        fp_take_frame f;
        assert_int_equal(fp_take_reader_read(r, (size_t)k, &f, err, sizeof err), 0);
        if (k == 0) t0 = f.time_ns;
        fp_test_gltf_anim_weights(&a, (double)(f.time_ns - t0) * 1e-9, w);
        for (size_t g = 0; g < a.vertices; g++) {
            if (a.source_vertex[g] != rec.chin) continue;
            if (k == 0) chin_copies++;
            double d = 0, q[3];
            for (int i = 0; i < 3; i++) {
                float x = a.base[3 * g + i];
                for (size_t t = 0; t < a.targets; t++) x += w[t] * a.target[(t * a.vertices + g) * 3 + i];
                q[i] = x;
                d += pow(x - rec.pos[((size_t)k * rec.n + rec.chin) * 3 + i], 2);
            }
            worst = fmax(worst, sqrt(d));
            if (k == 0) memcpy(first, q, sizeof first);
            travel = fmax(travel, sqrt(pow(q[0] - first[0], 2) + pow(q[1] - first[1], 2) + pow(q[2] - first[2], 2)));
        }
    }
    printf("glb: %zu targets; the chin travels %.3f units, at most %.3g units (%.3g mm) from the recorded chin\n",
           a.targets, travel, worst, worst * mm_per_unit);
    assert_true(chin_copies >= 1);
    assert_true(travel > 0.3);
    assert_true(worst * mm_per_unit < 0.01 + 1e-4); /* 0.01 mm asked, plus float32 rounding */
    free(w);
    fp_take_reader_close(&r);
    fp_test_gltf_anim_free(&a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frames_hold_channels),
        cmocka_unit_test(test_version),
        cmocka_unit_test(test_play_reproduces_jaw),
        cmocka_unit_test(test_play_names_the_take),
        cmocka_unit_test(test_export_carries_jaw),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
