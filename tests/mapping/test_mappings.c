/* The anchored and unanchored mapping plugins (Sato et al. 2004, sec. 2.3.1 and 2.3.2),
 * driven through the plugin ABI with synthetic frames. */
#define _GNU_SOURCE
#include "fp_plugin_host.h"
#include "fp_test_support.h"
#include <facepuppet/mapping_util.h>

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#define R 1.0

typedef struct rig {
    fp_plugin plugin;
    fp_mapping *m;
    fp_host host;
    fp_control_set cs;
    float start[64][3], end[64][3];
    fp_channel ch[4];
    fp_frame_input in;
} rig;

/* r's control set and frame input, empty, for the host's radius R */
static void rig_buffers(rig *r)
{
    r->cs.size = sizeof r->cs;
    r->cs.capacity = 64;
    r->cs.start = r->start;
    r->cs.end = r->end;
    r->cs.channels = r->ch;
    r->cs.channel_capacity = 4;
    r->in.size = sizeof r->in;
    r->in.radius = R;
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++) r->in.tip_distance[h][f] = INFINITY;
}

static int open_mapping(rig *r, const char *name, const fp_param *params, size_t n, char *err)
{
    memset(r, 0, sizeof *r);
    int rc = fp_plugin_load(fp_test_plugin_path(), FP_PLUGIN_MAPPING, name, &r->plugin, err, 1024);
    if (rc) return rc;
    fp_host_init_for_mapping(&r->host, name);
    const fp_mapping_factory *f = r->plugin.factory;
    rc = f->create(&r->host, params, n, &r->m, err, 1024);
    rig_buffers(r);
    return rc;
}

/* The anchored mapping on a mapping host whose surface service is `nearest` (mh: kept by the
 * caller for the mapping's life); the keys must be accepted. */
static void open_anchored_on(rig *r, fp_mapping_host *mh, fp_mapping_services *services,
                             int (*nearest)(const fp_host *, const float (*)[3], size_t, float, fp_surface_hit *),
                             const fp_param *params, size_t n)
{
    char err[1024];
    memset(r, 0, sizeof *r);
    assert_int_equal(fp_plugin_load(fp_test_plugin_path(), FP_PLUGIN_MAPPING, "anchored", &r->plugin, err, 1024), 0);
    memset(services, 0, sizeof *services);
    services->surface.nearest = nearest;
    fp_mapping_host_init(mh, "anchored", NULL, NULL);
    mh->services = services;
    const fp_mapping_factory *f = r->plugin.factory;
    assert_int_equal(f->create(&mh->host, params, n, &r->m, err, 1024), 0);
    rig_buffers(r);
}

static void close_mapping(rig *r)
{
    if (r->m) r->m->destroy(r->m);
    fp_plugin_unload(&r->plugin);
}

/* Put the right hand's fingertips at x0 + f along x, y, z; `dist` from the surface. */
static void place_right(rig *r, float x0, float y, float z, float dist)
{
    fp_hand_pose *p = &r->in.hands[FP_HAND_RIGHT];
    p->present = true;
    for (int f = 0; f < FP_FINGERS; f++) {
        p->joints[FP_JOINT_TIP(f)][0] = x0 + (float)f;
        p->joints[FP_JOINT_TIP(f)][1] = y;
        p->joints[FP_JOINT_TIP(f)][2] = z;
        r->in.tip_distance[FP_HAND_RIGHT][f] = dist;
    }
}

static void step(rig *r, uint32_t requested)
{
    r->in.requested = requested;
    assert_int_equal(r->m->process(r->m, &r->in, &r->cs), 0);
    r->in.frame++;
}

static void test_anchored_auto(void **state)
{
    (void)state;
    rig r;
    char err[1024];
    assert_int_equal(open_mapping(&r, "anchored", NULL, 0, err), 0);
    place_right(&r, 0, 0, 5, 3 * R); /* far from the surface: nothing */
    step(&r, 0);
    assert_false(r.cs.active);
    assert_int_equal(r.cs.intents, 0);

    place_right(&r, 0, 0, 0.7f, 0.7f * R); /* within R but beyond engage (0.5 R): nothing */
    step(&r, 0);
    assert_false(r.cs.active);

    place_right(&r, 0, 0, 0.5f, 0.45f * R); /* within 0.5 R: engage, start = end = tips */
    step(&r, 0);
    assert_true(r.cs.active);
    assert_true(r.cs.intents & FP_INTENT_ENGAGE);
    assert_int_equal(r.cs.count, 5);
    float s0[5][3];
    memcpy(s0, r.start, sizeof s0);
    assert_memory_equal(r.start, r.end, sizeof s0);
    assert_float_equal(r.start[2][0], 2.0, 0);

    place_right(&r, 0.2f, 0.1f, 0.4f, 0.4f * R); /* fingers move: start fixed, end follows */
    step(&r, 0);
    assert_true(r.cs.active);
    assert_int_equal(r.cs.intents, 0);
    assert_memory_equal(r.start, s0, sizeof s0); /* bit for bit: the host reuses its factor */
    assert_float_equal(r.end[2][0], 2.2, 1e-6);
    assert_float_equal(r.end[2][1], 0.1, 1e-6);

    place_right(&r, 10, 0, 0.5f, 0.9f * R); /* a huge jump is followed in full (no clamp by
                                             * default: the host composes long drags); still
                                             * held (release beyond R) */
    step(&r, 0);
    assert_true(r.cs.active);
    assert_int_equal(r.cs.intents, 0);
    for (int i = 0; i < 5; i++) {
        double d = 0;
        for (int k = 0; k < 3; k++) d += pow(r.end[i][k] - r.start[i][k], 2);
        assert_true(sqrt(d) > 0.45 * R);
    }

    place_right(&r, 0.2f, 0, 3, 2 * R); /* the hand lets go: commit */
    step(&r, 0);
    assert_true(r.cs.active);
    assert_true(r.cs.intents & FP_INTENT_COMMIT);
    step(&r, 0);
    assert_false(r.cs.active);
    close_mapping(&r);
}

/* Touch is measured in the face's default radius (fp_frame_input.touch_radius): a support of
 * 1.5 R engages at 0.5 R from the skin as R does, not at 0.75 R; a host that does not give it
 * (touch_radius 0) has touch measured in the support radius, as before. */
static void test_anchored_touch_radius(void **state)
{
    (void)state;
    for (int given = 0; given < 2; given++) {
        rig r;
        char err[1024];
        assert_int_equal(open_mapping(&r, "anchored", NULL, 0, err), 0);
        r.in.radius = 1.5 * R;
        r.in.touch_radius = given ? R : 0;
        place_right(&r, 0, 0, 0.6f, 0.6f * R); /* within 0.5 x 1.5 R, beyond 0.5 R */
        step(&r, 0);
        assert_int_equal(r.cs.active, !given);
        place_right(&r, 0, 0, 0.45f, 0.45f * R);
        step(&r, 0);
        assert_true(r.cs.active);
        assert_true(fabs(r.cs.radius - 1.5 * R) < 1e-9); /* the support stays the wider one */
        close_mapping(&r);
    }
}

static void test_anchored_requests(void **state)
{
    (void)state;
    rig r;
    char err[1024];
    fp_param p[] = {{"auto", "0"}};
    assert_int_equal(open_mapping(&r, "anchored", p, 1, err), 0);
    place_right(&r, 0, 0, 0, 0.1f * R); /* near, but auto=0: nothing until asked */
    step(&r, 0);
    assert_false(r.cs.active);
    step(&r, FP_INTENT_ENGAGE);
    assert_true(r.cs.active);
    assert_true(r.cs.intents & FP_INTENT_ENGAGE);
    place_right(&r, 0, 0, 5, 5 * R); /* far away, still engaged: no auto commit */
    step(&r, 0);
    assert_true(r.cs.active);
    assert_false(r.cs.intents & FP_INTENT_COMMIT);
    step(&r, FP_INTENT_CANCEL);
    assert_false(r.cs.active);
    assert_true(r.cs.intents & FP_INTENT_CANCEL);
    step(&r, FP_INTENT_ENGAGE);
    step(&r, FP_INTENT_COMMIT);
    assert_true(r.cs.intents & FP_INTENT_COMMIT);
    close_mapping(&r);
}

/* A surface service over the plane z = 0 (every query's nearest point straight below it),
 * counting its calls: what a 1.1 host offers as FP_HOST_EXT_SURFACE. */
static int plane_calls;
static int plane_nearest(const fp_host *host, const float (*points)[3], size_t count, float max_distance,
                         fp_surface_hit *out)
{
    (void)host;
    plane_calls++;
    for (size_t i = 0; i < count; i++) {
        float d = fabsf(points[i][2]);
        memset(&out[i], 0, sizeof out[i]);
        out[i].vertex = d <= max_distance ? (uint32_t)i : UINT32_MAX;
        out[i].distance = d <= max_distance ? d : INFINITY;
        out[i].normal[2] = 1.f;
    }
    return 0;
}

/* Factors beyond the host's tip distances (FP_TIP_DISTANCE_REACH x R; +INFINITY farther out):
 * engage=1.5 and release=3 ask the surface service with their own reach, so a hand at 1.2 R
 * engages and one at 2.5 R is still held although tip_distance says "far"; within the reach
 * (the defaults) the service is never asked. */
static void test_anchored_beyond_reach(void **state)
{
    (void)state;
    assert_true(FP_TIP_DISTANCE_REACH < 1.5);
    rig r;
    fp_param p[] = {{"engage", "1.5"}, {"release", "3"}};
    static fp_mapping_services services;
    static fp_mapping_host mh;
    open_anchored_on(&r, &mh, &services, plane_nearest, p, 2);
    plane_calls = 0;
    place_right(&r, 0, 0, 1.6f, INFINITY); /* beyond 1.5 R: nothing */
    step(&r, 0);
    assert_false(r.cs.active);
    assert_true(plane_calls > 0);
    place_right(&r, 0, 0, 1.2f, INFINITY); /* within 1.5 R, beyond the host's reach */
    step(&r, 0);
    assert_true(r.cs.active);
    assert_true(r.cs.intents & FP_INTENT_ENGAGE);
    place_right(&r, 0, 0, 2.5f, INFINITY); /* within release = 3 R: held */
    step(&r, 0);
    assert_true(r.cs.active);
    assert_false(r.cs.intents & FP_INTENT_COMMIT);
    place_right(&r, 0, 0, 3.5f, INFINITY); /* let go */
    step(&r, 0);
    assert_true(r.cs.intents & FP_INTENT_COMMIT);
    close_mapping(&r);

    /* the defaults (0.5 and 1.0 R) read the host's distances only; the service is asked once,
     * at engage, for the skin the points grab */
    open_anchored_on(&r, &mh, &services, plane_nearest, NULL, 0);
    plane_calls = 0;
    place_right(&r, 0, 0, 0.4f, 0.4f);
    step(&r, 0);
    assert_true(r.cs.active);
    place_right(&r, 0, 0, 1.4f, INFINITY);
    step(&r, 0);
    assert_true(r.cs.intents & FP_INTENT_COMMIT);
    assert_int_equal(plane_calls, 1);
    close_mapping(&r);
}

/* The plane z = 0 with each hit at the foot of its point (the skin right under it). */
static int plane_foot(const fp_host *host, const float (*points)[3], size_t count, float max_distance,
                      fp_surface_hit *out)
{
    int rc = plane_nearest(host, points, count, max_distance, out);
    for (size_t i = 0; i < count; i++) {
        out[i].position[0] = points[i][0];
        out[i].position[1] = points[i][1];
        out[i].position[2] = 0;
    }
    return rc;
}

/* One grab per bit of skin (key apart, 0.2 R by default): thumb and index pinched together
 * (their tips 0.05 R apart, the thumb 0.1 R off the skin, the index 0.3 R) grab the skin
 * once, the thumb's (nearer its skin) holding it, and opening the pinch moves that skin with
 * the thumb alone; fingertips R apart each grab their own. want: the grabs. */
static void pinch_case(const char *apart, float third_at, size_t want)
{
    rig r;
    fp_param p[] = {{"apart", apart}};
    static fp_mapping_services services;
    static fp_mapping_host mh;
    open_anchored_on(&r, &mh, &services, plane_foot, apart ? p : NULL, apart ? 1 : 0);
    fp_hand_pose *h = &r.in.hands[FP_HAND_RIGHT];
    h->present = true;
    const float tip[FP_FINGERS][3] = {{0, 0, 0.1f}, {0.05f, 0, 0.3f}, {third_at, 0, 0.2f}, {3, 0, 0.2f}, {4, 0, 0.2f}};
    for (int f = 0; f < FP_FINGERS; f++) {
        memcpy(h->joints[FP_JOINT_TIP(f)], tip[f], sizeof tip[f]);
        r.in.tip_distance[FP_HAND_RIGHT][f] = tip[f][2];
    }
    step(&r, 0);
    assert_true(r.cs.active);
    printf("apart=%s, the middle fingertip %.2f R from the thumb: %zu grabs\n", apart ? apart : "(0.2)",
           third_at, r.cs.count);
    assert_int_equal(r.cs.count, want);
    /* open the pinch: the thumb 0.5 R to -x, the index 0.5 R to +x */
    h->joints[FP_JOINT_TIP(0)][0] -= 0.5f;
    h->joints[FP_JOINT_TIP(1)][0] += 0.5f;
    step(&r, 0);
    assert_true(r.cs.active);
    assert_int_equal(r.cs.count, want);
    assert_true(fabsf(r.cs.start[0][0]) < 1e-6f);            /* the thumb's skin, first */
    assert_true(fabsf(r.cs.end[0][0] + 0.5f) < 1e-6f);       /* ... goes with the thumb */
    if (want == 5) /* every point grabs: the index's own skin goes +x */
        assert_true(fabsf(r.cs.end[1][0] - 0.55f) < 1e-6f);
    for (size_t i = 1; i < r.cs.count && want < 5; i++)
        assert_true(fabsf(r.cs.start[i][0] - 0.05f) > 1e-6f); /* the index let go */
    close_mapping(&r);
}

static void test_anchored_apart(void **state)
{
    (void)state;
    pinch_case(NULL, 2.0f, 4);   /* the index lets go: thumb, middle, ring, little */
    pinch_case("0", 2.0f, 5);    /* every fingertip grabs its own */
    pinch_case(NULL, 0.25f, 4);  /* the middle 0.25 R from the thumb's skin keeps its own */
    pinch_case("0.3", 0.25f, 3); /* within 0.3 R of the thumb's skin: the thumb's */
}

static void test_unanchored(void **state)
{
    (void)state;
    rig r;
    char err[1024];
    assert_int_equal(open_mapping(&r, "unanchored", NULL, 0, err), 0);
    place_right(&r, 0, 0, 0, 0.2f * R);
    step(&r, 0); /* the first sight gives no step yet */
    assert_false(r.cs.active);
    place_right(&r, 0.1f, 0, 0, 0.2f * R);
    step(&r, 0); /* from the last tips to the new ones, folded in at once */
    assert_true(r.cs.active);
    assert_true(r.cs.intents & FP_INTENT_COMMIT);
    assert_int_equal(r.cs.count, 5);
    assert_float_equal(r.start[1][0], 1.0, 1e-6);
    assert_float_equal(r.end[1][0], 1.1, 1e-6);
    place_right(&r, 0.3f, 0, 0, 0.2f * R);
    step(&r, 0);
    assert_float_equal(r.start[1][0], 1.1, 1e-6); /* trajectories: start = last end */
    assert_float_equal(r.end[1][0], 1.3, 1e-6);
    place_right(&r, 0.4f, 0, 9, 9 * R); /* away from the surface: no step */
    step(&r, 0);
    assert_false(r.cs.active);
    close_mapping(&r);
}

static void test_bad_keys(void **state)
{
    (void)state;
    rig r;
    char err[1024];
    fp_param p[] = {{"bogus", "1"}};
    assert_int_not_equal(open_mapping(&r, "anchored", p, 1, err), 0);
    assert_non_null(strstr(err, "unknown key 'bogus'"));
    close_mapping(&r);
    fp_param q[] = {{"clamp", "abc"}};
    assert_int_not_equal(open_mapping(&r, "unanchored", q, 1, err), 0);
    assert_non_null(strstr(err, "unanchored: key 'clamp': 'abc' is not a number in [0, 100] R"));
    close_mapping(&r);
    fp_param h[] = {{"hands", "up"}};
    assert_int_not_equal(open_mapping(&r, "anchored", h, 1, err), 0);
    assert_non_null(strstr(err, "anchored: key 'hands': 'up' is not one of left|right|both"));
    close_mapping(&r);
    fp_param b[] = {{"auto", "maybe"}};
    assert_int_not_equal(open_mapping(&r, "anchored", b, 1, err), 0);
    assert_non_null(strstr(err, "key 'auto': bad value 'maybe'"));
    close_mapping(&r);
    fp_param ok[] = {{"hands", "left"}, {"auto", "off"}, {"release", "2.5"}};
    assert_int_equal(open_mapping(&r, "anchored", ok, 3, err), 0);
    close_mapping(&r);
    /* engage beyond release (the hysteresis upside down: a hand would let go as it engages),
     * given or against the other's default, is refused naming both keys; equal is taken */
    static const fp_param upside[][2] = {{{"engage", "0.8"}, {"release", "0.5"}},
                                         {{"release", "0.3"}, {"engage", "0.5"}},
                                         {{"engage", "1.5"}, {"auto", "1"}}};
    for (size_t i = 0; i < 3; i++) {
        assert_int_equal(open_mapping(&r, "anchored", upside[i], 2, err), -EINVAL);
        assert_non_null(strstr(err, "anchored: key 'engage'"));
        assert_non_null(strstr(err, "is beyond key 'release'"));
        assert_non_null(strstr(err, "engage <= release"));
        close_mapping(&r);
    }
    assert_non_null(strstr(err, "key 'engage' (1.5) is beyond key 'release' (1)"));
    fp_param same[] = {{"engage", "0.7"}, {"release", "0.7"}};
    assert_int_equal(open_mapping(&r, "anchored", same, 2, err), 0);
    close_mapping(&r);
    assert_int_equal(open_mapping(&r, "no-such-mapping", NULL, 0, err), FP_EPLUGIN_NOT_FOUND);
    assert_non_null(strstr(err, "no mapping plugin named 'no-such-mapping'"));
    assert_non_null(strstr(err, "anchored"));
    close_mapping(&r);
}

/* Numbers in keys are decimals (plugin_util.h's fp_parse_decimal, which fpmu_params_parse and
 * fp_parse_double use): an optional sign, digits with at most one '.', an optional exponent;
 * finite. strtod also reads hexadecimal, "inf", "infinity" and "nan": refused, by the helpers
 * and by the mappings' keys, while every decimal form still reads. */
static void test_decimal_keys(void **state)
{
    (void)state;
    static const struct { const char *text; double value; } good[] = {
        {"5", 5}, {"-0.5", -0.5}, {".5", 0.5}, {"5.", 5}, {"+2", 2}, {"1e-3", 1e-3},
        {"2E+2", 200}, {"0", 0}, {"-0", 0}, {"007", 7}, {"1.5e1", 15}, {"1e-999", 0}};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        double x = -1;
        assert_true(fp_parse_decimal(good[i].text, &x));
        assert_true(x == good[i].value);
        assert_true(fp_parse_double(good[i].text, -1e9, 1e9, &x));
        assert_int_equal(fp_decimal_span(good[i].text), strlen(good[i].text));
    }
    static const char *const bad[] = {"0x10", "0x1p3", "0X1P-2", "inf", "-inf", "infinity", "nan",
                                      "NAN(1)", "1e999", "-1e999", "", " 5", "5 ", "+", ".", "e5",
                                      "1e", "1e+", "1.2.3", "5x", "1,5", "--1", "\t1"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        double x = 42;
        assert_false(fp_parse_decimal(bad[i], &x));
        assert_false(fp_parse_double(bad[i], -INFINITY, INFINITY, &x));
        assert_true(x == 42);
    }
    assert_int_equal(fp_decimal_span("0x10"), 1);   /* "0", then the caller sees the x */
    assert_int_equal(fp_decimal_span("1e"), 1);
    assert_int_equal(fp_decimal_span("12/3"), 2);
    double v[3] = {0, 0, 0};
    assert_int_equal(fp_parse_decimal_list("1,-2.5,3e1", ',', v, 3), 3);
    assert_true(v[0] == 1 && v[1] == -2.5 && v[2] == 30);
    assert_int_equal(fp_parse_decimal_list("  -35 \t10 ", ' ', v, 3), 2);
    assert_true(v[0] == -35 && v[1] == 10);
    static const char *const badlist[] = {"1,0x2", "1,,2", "1,2,", "1,2,3,4", "0x1,2", "1,inf", "1;2"};
    for (size_t i = 0; i < sizeof badlist / sizeof badlist[0]; i++)
        assert_int_equal(fp_parse_decimal_list(badlist[i], ',', v, 3), 0);
    assert_int_equal(fp_parse_decimal_list("1 2 3 4", ' ', v, 3), 0);
    /* whole numbers (decimal.h's fp_parse_whole, the integer options'): an optional '+' and
     * digits, at most the bound, never wrapped round */
    unsigned long long w = 0;
    assert_true(fp_parse_whole("0", 10, &w) && w == 0);
    assert_true(fp_parse_whole("+7", 10, &w) && w == 7);
    assert_true(fp_parse_whole("010", 10, &w) && w == 10);
    assert_true(fp_parse_whole("18446744073709551615", ULLONG_MAX, &w) && w == ULLONG_MAX);
    assert_true(fp_parse_whole("2147483647", INT_MAX, &w) && w == INT_MAX);
    static const struct { const char *text; unsigned long long max; } notwhole[] = {
        {"11", 10}, {"7", 5}, {"18446744073709551616", ULLONG_MAX}, {"2147483648", INT_MAX},
        {"4294967297", INT_MAX}, {"", 10}, {" 5", 10}, {"5 ", 10}, {"\t5", 10}, {"-5", 10},
        {"-0", 10}, {"5.0", 10}, {"5e0", 10}, {"0x5", 10}, {"+", 10}, {"++5", 10}, {"+-5", 10}};
    for (size_t i = 0; i < sizeof notwhole / sizeof notwhole[0]; i++) {
        w = 42;
        assert_false(fp_parse_whole(notwhole[i].text, notwhole[i].max, &w));
        assert_true(w == 42);
    }

    /* the mappings' number keys */
    rig r;
    char err[1024];
    static const char *const keys[] = {"0x1p-2", "0x10", "inf", "infinity", "nan", "1e999"};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        fp_param p[] = {{"clamp", keys[i]}};
        assert_int_equal(open_mapping(&r, "anchored", p, 1, err), -EINVAL);
        char want[128];
        snprintf(want, sizeof want, "anchored: key 'clamp': '%s' is not a number in [0, 100] R", keys[i]);
        assert_non_null(strstr(err, want));
        close_mapping(&r);
        assert_int_equal(open_mapping(&r, "unanchored", p, 1, err), -EINVAL);
        assert_non_null(strstr(err, "unanchored: key 'clamp'"));
        close_mapping(&r);
    }
    static const char *const fine[] = {"1.5", ".5", "2.", "+3", "1e-1", "1E+1"};
    for (size_t i = 0; i < sizeof fine / sizeof fine[0]; i++) {
        fp_param p[] = {{"release", fine[i]}, {"engage", "0.05"}};
        assert_int_equal(open_mapping(&r, "anchored", p, 2, err), 0);
        close_mapping(&r);
    }
}

/* Put every joint of hand h at a distinct point: joint j at (base + j, 10 h, z). */
static void place_joints(rig *r, int h, float base, float z, float dist)
{
    fp_hand_pose *p = &r->in.hands[h];
    p->present = true;
    for (int j = 0; j < FP_HAND_JOINTS; j++) {
        p->joints[j][0] = base + (float)j;
        p->joints[j][1] = 10.0f * (float)h;
        p->joints[j][2] = z;
    }
    for (int f = 0; f < FP_FINGERS; f++) r->in.tip_distance[h][f] = dist;
}

/* points=tips|tips+palm|all: 5, 11 or 21 points per hand, 42 for two; the tips first, then
 * (tips+palm) the palm centre and the five knuckles, or (all) every other joint in layout
 * order; end points follow the same joints. */
static void test_points(void **state)
{
    (void)state;
    static const struct { const char *mode; size_t per_hand; int extra[6]; } modes[] = {
        {"tips", 5, {-1}},
        {"tips+palm", 11, {FP_JOINT_PALM, FP_JOINT(0, 1), FP_JOINT(1, 0), FP_JOINT(2, 0),
                           FP_JOINT(3, 0), FP_JOINT(4, 0)}},
        {"all", 21, {-1}},
    };
    for (size_t m = 0; m < 3; m++) {
        for (int anchored = 0; anchored <= 1; anchored++) {
            rig r;
            char err[1024];
            fp_param p[] = {{"points", modes[m].mode}};
            assert_int_equal(open_mapping(&r, anchored ? "anchored" : "unanchored", p, 1, err), 0);
            /* within R/2 of the surface: the anchored mapping engages there by default */
            place_joints(&r, FP_HAND_LEFT, 0, 0.5f, 0.4f * R);
            place_joints(&r, FP_HAND_RIGHT, 100, 0.5f, 0.4f * R);
            step(&r, 0);
            if (!anchored) { /* unanchored: a step from the last points to the new */
                place_joints(&r, FP_HAND_LEFT, 0.1f, 0.5f, 0.4f * R);
                place_joints(&r, FP_HAND_RIGHT, 100.1f, 0.5f, 0.4f * R);
                step(&r, 0);
            }
            assert_true(r.cs.active);
            size_t n = modes[m].per_hand;
            assert_int_equal(r.cs.count, 2 * n);
            assert_true(r.cs.count <= FP_CONTROL_CAPACITY);
            for (int h = 0; h < FP_HANDS; h++) {
                float base = h ? 100.0f : 0.0f;
                bool seen[FP_HAND_JOINTS] = {false};
                for (size_t i = 0; i < n; i++) {
                    int j = (int)lroundf(r.start[h * n + i][0] - base);
                    assert_true(j >= 0 && j < FP_HAND_JOINTS);
                    assert_false(seen[j]);
                    seen[j] = true;
                    if (i < 5) assert_int_equal(j, FP_JOINT_TIP(i));    /* the tips first */
                    else if (modes[m].extra[0] >= 0) assert_int_equal(j, modes[m].extra[i - 5]);
                    assert_float_equal(r.start[h * n + i][1], 10.0 * h, 0);
                    if (!anchored) assert_float_equal(r.end[h * n + i][0] - r.start[h * n + i][0], 0.1, 1e-4);
                }
            }
            if (anchored) { /* the joints move: start fixed, every end follows its joint */
                float s0[42][3];
                memcpy(s0, r.start, sizeof s0);
                place_joints(&r, FP_HAND_LEFT, 0.2f, 0.5f, 0.4f * R);
                place_joints(&r, FP_HAND_RIGHT, 100.2f, 0.5f, 0.4f * R);
                step(&r, 0);
                assert_int_equal(r.cs.count, 2 * n);
                assert_memory_equal(r.start, s0, 2 * n * sizeof s0[0]);
                for (size_t i = 0; i < 2 * n; i++)
                    assert_float_equal(r.end[i][0] - r.start[i][0], 0.2, 1e-4);
            }
            /* a host with less room than the points: -ENOSPC, nothing written past it */
            r.cs.capacity = 2 * n - 1;
            r.in.requested = FP_INTENT_ENGAGE;
            place_joints(&r, FP_HAND_LEFT, 0.3f, 0.5f, 0.4f * R);
            assert_int_equal(r.m->process(r.m, &r.in, &r.cs), -ENOSPC);
            close_mapping(&r);
        }
    }
    rig r;
    char err[1024];
    fp_param bad[] = {{"points", "palm"}};
    assert_int_not_equal(open_mapping(&r, "anchored", bad, 1, err), 0);
    assert_non_null(strstr(err, "anchored: key 'points': 'palm' is not one of tips|tips+palm|all"));
    close_mapping(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_anchored_auto),
        cmocka_unit_test(test_anchored_touch_radius), cmocka_unit_test(test_anchored_requests),
        cmocka_unit_test(test_unanchored), cmocka_unit_test(test_bad_keys),
        cmocka_unit_test(test_points), cmocka_unit_test(test_anchored_beyond_reach),
        cmocka_unit_test(test_decimal_keys),
        cmocka_unit_test(test_anchored_apart),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
