/* Two performers' hands through the mapping ABI (issue 55, item 4): fp_frame_input.extra_hands
 * (ABI 1.3) with the built-in anchored and unanchored mappings, in process and isolated in a
 * helper process (`facepuppet __plugin-helper`, the frame in shared memory), with synthetic
 * frames: two right hands from two performers are two hands. */
#define _GNU_SOURCE
#include "fp_isolate.h"
#include "fp_plugin_host.h"
#include "fp_test_support.h"
#include <facepuppet/mapping_util.h>

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#define R 1.0
#define CAP 64

typedef struct rig {
    fp_plugin plugin;
    fp_mapping *m;
    fp_host host;
    fp_control_set cs;
    float start[CAP][3], end[CAP][3];
    fp_channel ch[4];
    fp_frame_input in;
    fp_hand_pose extra[(FP_PERFORMER_CAPACITY - 1) * FP_HANDS];
    float extra_tips[(FP_PERFORMER_CAPACITY - 1) * FP_HANDS][FP_FINGERS];
} rig;

/* The mapping `name` with its keys; isolated: in a helper process (the build's facepuppet). */
static void open_mapping(rig *r, const char *name, const fp_param *params, size_t n, bool isolated)
{
    memset(r, 0, sizeof *r);
    char err[1024] = "";
    fp_host_init_for_mapping(&r->host, name);
    if (isolated) {
        char file[4096], helper[4096];
        bool builtin;
        assert_true(fp_plugin_find(fp_test_plugin_path(), FP_PLUGIN_MAPPING, name, file, sizeof file, &builtin,
                                   NULL, 0));
        snprintf(helper, sizeof helper, "%s/bin/facepuppet", fp_test_build_dir());
        fp_isolate_options opt = {.helper = helper, .deadline_ms = 5000 * fp_test_time_scale()};
        int rc = fp_isolate_mapping_create(&opt, file, name, &r->host, params, n, &r->m, err, sizeof err);
        if (rc) fail_msg("isolated %s: %s", name, err);
    } else {
        assert_int_equal(fp_plugin_load(fp_test_plugin_path(), FP_PLUGIN_MAPPING, name, &r->plugin, err, sizeof err), 0);
        const fp_mapping_factory *f = r->plugin.factory;
        assert_int_equal(f->create(&r->host, params, n, &r->m, err, sizeof err), 0);
    }
    r->cs.size = sizeof r->cs;
    r->cs.capacity = CAP;
    r->cs.start = r->start;
    r->cs.end = r->end;
    r->cs.channels = r->ch;
    r->cs.channel_capacity = 4;
    r->in.size = sizeof r->in;
    r->in.radius = R;
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++) r->in.tip_distance[h][f] = INFINITY;
    for (size_t h = 0; h < (FP_PERFORMER_CAPACITY - 1) * FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++) r->extra_tips[h][f] = INFINITY;
}

static void close_mapping(rig *r)
{
    if (r->m) r->m->destroy(r->m);
    fp_plugin_unload(&r->plugin);
}

/* `extra` further performers in the frame (0: the frame of one performer). */
static void performers(rig *r, uint32_t extra)
{
    r->in.extra_performers = extra;
    r->in.extra_hands = extra ? r->extra : NULL;
    r->in.extra_tip_distance = extra ? (const float (*)[FP_FINGERS])r->extra_tips : NULL;
}

/* Performer p's (0: the first) hand `side`: fingertips at x0 + f, y, z, every one `dist` from
 * the surface; the palm and other joints at x0, y, z + 1. */
static void place(rig *r, int p, int side, float x0, float y, float z, float dist)
{
    fp_hand_pose *pose = p ? &r->extra[FP_HANDS * (p - 1) + side] : &r->in.hands[side];
    float *tips = p ? r->extra_tips[FP_HANDS * (p - 1) + side] : r->in.tip_distance[side];
    pose->present = true;
    for (int j = 0; j < FP_HAND_JOINTS; j++) {
        pose->joints[j][0] = x0;
        pose->joints[j][1] = y;
        pose->joints[j][2] = z + 1;
    }
    for (int f = 0; f < FP_FINGERS; f++) {
        pose->joints[FP_JOINT_TIP(f)][0] = x0 + (float)f;
        pose->joints[FP_JOINT_TIP(f)][1] = y;
        pose->joints[FP_JOINT_TIP(f)][2] = z;
        tips[f] = dist;
    }
}

static void step(rig *r, uint32_t requested)
{
    r->in.requested = requested;
    assert_int_equal(r->m->process(r->m, &r->in, &r->cs), 0);
    r->in.frame++;
}

/* Whether control vector i starts at hand tip x (y, z as placed). */
static bool starts_at(const rig *r, size_t i, float x)
{
    return r->start[i][0] == x;
}

/* Anchored: the first performer's right hand and B's right hand both touch: ten vectors, the
 * first performer's five first and unchanged by B's; each end follows its own hand. */
static void anchored_two_right_hands(bool isolated)
{
    rig r;
    open_mapping(&r, "anchored", NULL, 0, isolated);
    performers(&r, 1);
    place(&r, 0, FP_HAND_RIGHT, 0, 0, 0.5f, 0.4f * R);
    place(&r, 1, FP_HAND_RIGHT, 20, 0, 0.5f, 0.4f * R);
    step(&r, 0);
    assert_true(r.cs.active);
    assert_true(r.cs.intents & FP_INTENT_ENGAGE);
    assert_int_equal(r.cs.count, 2 * FP_FINGERS);
    for (int f = 0; f < FP_FINGERS; f++) {
        assert_true(starts_at(&r, (size_t)f, (float)f));                 /* the first's own */
        assert_true(starts_at(&r, (size_t)(FP_FINGERS + f), 20.f + (float)f)); /* B's */
    }
    /* B's hand moves, the first's stays: only B's five ends move, by B's motion */
    place(&r, 1, FP_HAND_RIGHT, 20.5f, 0.25f, 0.5f, 0.4f * R);
    step(&r, 0);
    assert_int_equal(r.cs.count, 2 * FP_FINGERS);
    for (int f = 0; f < FP_FINGERS; f++) {
        assert_memory_equal(r.end[f], r.start[f], sizeof r.end[f]);
        assert_float_equal(r.end[FP_FINGERS + f][0], 20.5 + f, 1e-5);
        assert_float_equal(r.end[FP_FINGERS + f][1], 0.25, 1e-5);
    }
    /* both let go: commit */
    place(&r, 0, FP_HAND_RIGHT, 0, 0, 5, 3 * R);
    place(&r, 1, FP_HAND_RIGHT, 20, 0, 5, 3 * R);
    step(&r, 0);
    assert_true(r.cs.intents & FP_INTENT_COMMIT);
    close_mapping(&r);
}

static void test_anchored_two_performers(void **state)
{
    (void)state;
    anchored_two_right_hands(false);
}

/* The same frames through the helper process (--isolate all): the same control sets. */
static void test_anchored_two_performers_isolated(void **state)
{
    (void)state;
    anchored_two_right_hands(true);
}

/* Old frames: a frame that says no further performer, or a 1.2 host's frame (size short of
 * the ABI 1.3 fields), gives the first performer's hand alone, as before. */
static void test_anchored_old_frames(void **state)
{
    (void)state;
    for (int k = 0; k < 2; k++) {
        rig r;
        open_mapping(&r, "anchored", NULL, 0, false);
        performers(&r, 1);
        if (k == 0) r.in.extra_performers = 0;
        else r.in.size = (uint32_t)offsetof(fp_frame_input, extra_performers);
        place(&r, 0, FP_HAND_RIGHT, 0, 0, 0.5f, 0.4f * R);
        place(&r, 1, FP_HAND_RIGHT, 20, 0, 0.5f, 0.4f * R);
        step(&r, 0);
        assert_true(r.cs.active);
        assert_int_equal(r.cs.count, FP_FINGERS);
        for (int f = 0; f < FP_FINGERS; f++) assert_true(starts_at(&r, (size_t)f, (float)f));
        close_mapping(&r);
    }
}

/* hands=left applies to every performer: two right hands engage nothing; B's left does. */
static void test_anchored_sides(void **state)
{
    (void)state;
    rig r;
    fp_param p[] = {{"hands", "left"}};
    open_mapping(&r, "anchored", p, 1, false);
    performers(&r, 2);
    place(&r, 0, FP_HAND_RIGHT, 0, 0, 0.5f, 0.4f * R);
    place(&r, 1, FP_HAND_RIGHT, 20, 0, 0.5f, 0.4f * R);
    step(&r, 0);
    assert_false(r.cs.active);
    place(&r, 2, FP_HAND_LEFT, 40, 0, 0.5f, 0.4f * R);
    step(&r, 0);
    assert_true(r.cs.active);
    assert_int_equal(r.cs.count, FP_FINGERS);
    assert_true(starts_at(&r, 0, 40.f));
    close_mapping(&r);
}

/* Unanchored: every performer's touching hand steps; with points=all four performers' eight
 * hands (168 points) do not fit 64: the first performer's 42 always do, no error. */
static void unanchored_performers(bool isolated)
{
    rig r;
    open_mapping(&r, "unanchored", NULL, 0, isolated);
    performers(&r, 1);
    place(&r, 0, FP_HAND_RIGHT, 0, 0, 0.5f, 0.4f * R);
    place(&r, 1, FP_HAND_RIGHT, 20, 0, 0.5f, 0.4f * R);
    step(&r, 0); /* (the first step has no last points) */
    place(&r, 0, FP_HAND_RIGHT, 0.1f, 0, 0.5f, 0.4f * R);
    place(&r, 1, FP_HAND_RIGHT, 20.2f, 0, 0.5f, 0.4f * R);
    step(&r, 0);
    assert_true(r.cs.active);
    assert_int_equal(r.cs.count, 2 * FP_FINGERS);
    for (int f = 0; f < FP_FINGERS; f++) {
        assert_true(starts_at(&r, (size_t)f, (float)f));
        assert_float_equal(r.end[f][0], 0.1 + f, 1e-5);
        assert_true(starts_at(&r, (size_t)(FP_FINGERS + f), 20.f + (float)f));
        assert_float_equal(r.end[FP_FINGERS + f][0], 20.2 + f, 1e-5);
    }
    close_mapping(&r);
}

static void test_unanchored_two_performers(void **state)
{
    (void)state;
    unanchored_performers(false);
}

static void test_unanchored_two_performers_isolated(void **state)
{
    (void)state;
    unanchored_performers(true);
}

static void test_unanchored_capacity(void **state)
{
    (void)state;
    rig r;
    fp_param p[] = {{"points", "all"}};
    open_mapping(&r, "unanchored", p, 1, false);
    performers(&r, FP_PERFORMER_CAPACITY - 1);
    for (int k = 0; k < 2; k++) {
        for (int pf = 0; pf < FP_PERFORMER_CAPACITY; pf++)
            for (int side = 0; side < FP_HANDS; side++)
                place(&r, pf, side, 10.f * (float)(2 * pf + side) + 0.1f * (float)k, 0, 0.5f, 0.4f * R);
        step(&r, 0);
    }
    assert_true(r.cs.active);
    assert_true(r.cs.count <= CAP);
    assert_int_equal(r.cs.count, 3 * FP_POINTS_ALL_COUNT); /* the first's two hands, B's left */
    for (int pt = 0; pt < FP_POINTS_ALL_COUNT; pt++) /* the first performer's left hand first */
        assert_float_equal(r.end[pt][0] - r.start[pt][0], 0.1, 1e-5);
    close_mapping(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_anchored_two_performers),
        cmocka_unit_test(test_anchored_two_performers_isolated),
        cmocka_unit_test(test_anchored_old_frames),
        cmocka_unit_test(test_anchored_sides),
        cmocka_unit_test(test_unanchored_two_performers),
        cmocka_unit_test(test_unanchored_two_performers_isolated),
        cmocka_unit_test(test_unanchored_capacity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
