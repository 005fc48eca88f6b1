/* test_stack_check: checks a two-layer stack made by test_stack_cli.sh (issue 54's "Done
 * when" lines 1 and 2), frame by frame, against its takes played alone (fp_take_player).
 *
 *   test_stack_check mouth STACK   a region layer over the whole take: outside the region's
 *       support (weight 0) every vertex equals the base take's frame bit for bit; where the
 *       region's weight is 1 and the layer's weight in time is 1, every vertex equals the
 *       layer's frame bit for bit; the layer shows (some frame differs from the base inside
 *       the region); no new self-crossings away from the face's own (fp_selfx, CGAL) in
 *       sampled frames and every frame the layer is cross-faded in.
 *   test_stack_check punch STACK IN OUT   a layer punched in at IN and out at OUT seconds:
 *       frames at t <= IN and t >= OUT equal the base's bit for bit (every vertex); inside
 *       the layer shows; its weight in time rises from 0 inside [IN, IN + fade] and falls
 *       to 0 inside [OUT - fade, OUT] (the cross-fades lie inside the range; elsewhere it is
 *       below 1 only in a frame where the fold bound scaled it).
 *   test_stack_check channels TAKE DIR   a channel layer: writes DIR/jaw_T001.fptake, TAKE's
 *       frames with jaw.open set to 0.8, and DIR/jaw_S001.fpstack, TAKE under a jaw layer
 *       (channels jaw.open, replace, no fade); the stack's frames equal the jaw take's played
 *       alone bit for bit but for the first and last (the ends of the layer's range,
 *       where its weight is 0), and differ from TAKE's.
 *   test_stack_check mute STACK   fp_stack_player_set_layer (live's M and O keys): layer 1
 *       muted for the middle third of the frames: there every frame equals the base take's
 *       bit for bit; before and after (unmuted again) every frame equals the stack's played
 *       without a change, bit for bit (the layer went on playing: in step); soloing layer 1
 *       changes nothing in a two-layer stack; the base cannot be muted (-EINVAL).
 * Prints the figures; exit 0 when every check holds, 1 otherwise. */
#define _GNU_SOURCE
#include "fp_mesh.h"
#include "fp_plugin_host.h"
#include "fp_test_support.h"
#include "fp_stack_player.h"
#include "fp_take_player.h"
#include "selfx.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int fails;
#define CHECK(cond, ...)                                                                    \
    do {                                                                                    \
        if (!(cond)) {                                                                      \
            printf("FAIL: " __VA_ARGS__);                                                   \
            printf("\n");                                                                   \
            fails++;                                                                        \
        }                                                                                   \
    } while (0)

static bool same3(const float *a, const float *b) { return !memcmp(a, b, 3 * sizeof *a); }

/* New crossings of pos away from the loaded shape's own (rings 0, as test_rig_session). */
static long crossings(const fp_session *s, const float *pos)
{
    const fp_mesh *m = fp_session_mesh(s);
    return fp_selfx_count_new_away(fp_session_loaded(s), pos, fp_session_vertex_count(s),
                                   m->triangles, m->triangle_count, 0, NULL, 0, NULL, NULL);
}

/* The channels mode (see the top). */
static int channels_check(const char *take, const char *dir, const fp_plugin_path *pp)
{
    char err[4096], jaw_path[4200], stack_path[4200];
    fp_take_reader *r = NULL;
    fp_take_writer *w = NULL;
    if (fp_take_reader_open(take, &r, err, sizeof err)) { printf("FAIL: %s\n", err); return 1; }
    fp_take_header h = *fp_take_reader_header(r);
    snprintf(h.slate, sizeof h.slate, "jaw");
    fp_take_writer_options wo = {.no_sync = true};
    if (fp_take_writer_create(dir, &h, &wo, &w, err, sizeof err)) { printf("FAIL: %s\n", err); return 1; }
    snprintf(jaw_path, sizeof jaw_path, "%s", fp_take_writer_path(w));
    fp_take_frame f;
    size_t set = 0;
    while (fp_take_reader_next(r, &f, err, sizeof err) == 1) {
        fp_control_set cs;
        fp_channel ch[64];
        if (f.control) {
            cs = *f.control;
            memcpy(ch, cs.channels, cs.channel_count * sizeof *ch);
            for (size_t k = 0; k < cs.channel_count; k++)
                if (!strcmp(ch[k].name, "jaw.open")) ch[k].value = 0.8f, set++;
            cs.channels = ch;
            f.control = &cs;
        }
        if (fp_take_writer_add(w, &f, err, sizeof err)) { printf("FAIL: %s\n", err); return 1; }
    }
    fp_take_writer_close(&w, 0, 0, err, sizeof err);
    CHECK(set > 0, "the take has no jaw.open channel (a take with a rig, format 1.1)");
    fp_stack *s = fp_stack_create();
    fp_stack_layer l;
    fp_stack_layer_init(&l, take[0] == '/' ? take : realpath(take, NULL));
    fp_stack_append(s, &l, err, sizeof err);
    fp_stack_layer_init(&l, strrchr(jaw_path, '/') + 1);
    fp_stack_layer_spec("jaw", &l.region, &l.mode, err, sizeof err);
    l.fade_s = 0;
    fp_stack_append(s, &l, err, sizeof err);
    fp_stack_region_clear(&l.region);
    snprintf(stack_path, sizeof stack_path, "%s/jaw_S001.fpstack", dir);
    if (fp_stack_save(s, stack_path, err, sizeof err)) { printf("FAIL: %s\n", err); return 1; }
    fp_stack_free(&s);
    fp_take_reader_close(&r);
    fp_take_player *ps = NULL, *pj = NULL, *pb = NULL;
    if (fp_take_player_open(stack_path, NULL, pp, &ps, err, sizeof err) ||
        fp_take_player_open(jaw_path, NULL, pp, &pj, err, sizeof err) ||
        fp_take_player_open(take, NULL, pp, &pb, err, sizeof err)) {
        printf("FAIL: %s\n", err);
        return 1;
    }
    const size_t n = fp_session_vertex_count(fp_take_player_session(pb));
    size_t frames = 0, same_jaw = 0, differ_base = 0, total = fp_take_reader_frames(fp_take_player_reader(pb));
    fp_take_frame g;
    while (fp_take_player_next(ps, &f, NULL, err, sizeof err) == 1 &&
           fp_take_player_next(pj, &g, NULL, err, sizeof err) == 1 &&
           fp_take_player_next(pb, &g, NULL, err, sizeof err) == 1) {
        const float *c = fp_take_player_positions(ps);
        if (frames++ == 0 || frames == total) continue; /* the range's ends: weight 0 */
        const bool eq = !memcmp(c, fp_take_player_positions(pj), n * 3 * sizeof *c);
        if (!eq) printf("frame %zu differs from the jaw take's\n", frames - 1);
        same_jaw += eq;
        differ_base += memcmp(c, fp_take_player_positions(pb), n * 3 * sizeof *c) != 0;
    }
    printf("%s: channel layer jaw.open 0.8 over %zu frames: %zu equal the jaw take's, %zu differ "
           "from the base's\n", stack_path, frames, same_jaw, differ_base);
    CHECK(frames > 2 && same_jaw == frames - 2, "the channel layer's composite is not the jaw take");
    CHECK(differ_base == frames - 2, "the channel layer did not move the jaw");
    fp_take_player_close(&ps);
    fp_take_player_close(&pj);
    fp_take_player_close(&pb);
    printf("%s\n", fails ? "FAILED" : "ok");
    return fails ? 1 : 0;
}

static int mute_check(const char *path, const fp_plugin_path *pp)
{
    char err[4096], base_path[8192];
    fp_take_player *a = NULL, *b = NULL, *base = NULL;
    if (fp_take_player_open(path, NULL, pp, &a, err, sizeof err) ||
        fp_take_player_open(path, NULL, pp, &b, err, sizeof err)) {
        printf("FAIL: %s\n", err);
        return 1;
    }
    fp_stack_player *sp = fp_take_player_stack(a);
    fp_stack_take_path(fp_stack_player_stack(sp), 0, base_path, sizeof base_path);
    if (fp_take_player_open(base_path, NULL, pp, &base, err, sizeof err)) {
        printf("FAIL: %s\n", err);
        return 1;
    }
    CHECK(fp_stack_player_set_layer(sp, 0, true, false) == -EINVAL, "the base was muted");
    CHECK(fp_stack_player_set_layer(sp, 2, true, false) == -EINVAL, "a layer past the top was muted");
    const size_t n = fp_session_vertex_count(fp_take_player_session(base));
    const size_t total = fp_take_reader_frames(fp_take_player_reader(base));
    fp_take_frame f;
    size_t k = 0, muted = 0, muted_diff = 0, on = 0, on_diff = 0, shows = 0;
    while (fp_take_player_next(a, &f, NULL, err, sizeof err) == 1) {
        if (fp_take_player_next(b, &f, NULL, err, sizeof err) != 1 ||
            fp_take_player_next(base, &f, NULL, err, sizeof err) != 1) {
            CHECK(0, "the players ended apart");
            break;
        }
        const float *ca = fp_take_player_positions(a), *cb = fp_take_player_positions(b),
                    *cbase = fp_take_player_positions(base);
        const bool mid = k >= total / 3 && k < 2 * total / 3;
        if (mid) {
            muted++;
            muted_diff += memcmp(ca, cbase, n * 3 * sizeof *ca) != 0;
        } else {
            on++;
            on_diff += memcmp(ca, cb, n * 3 * sizeof *ca) != 0;
            shows += memcmp(cb, cbase, n * 3 * sizeof *cb) != 0;
        }
        k++; /* the next frame: muted in the middle third, soloed (a no-op here) after */
        if (k == total / 3) CHECK(!fp_stack_player_set_layer(sp, 1, true, false), "mute");
        if (k == 2 * total / 3) CHECK(!fp_stack_player_set_layer(sp, 1, false, true), "solo");
    }
    printf("mute: %zu frames muted, %zu differ from the base; %zu frames playing, %zu differ from "
           "the stack unchanged (the layer shows in %zu of them)\n", muted, muted_diff, on, on_diff, shows);
    CHECK(muted > 0 && muted_diff == 0, "muted frames differ from the base");
    CHECK(on > 0 && on_diff == 0, "frames with the layer on differ from the stack played unchanged");
    CHECK(shows > 0, "the layer never shows: the check proves nothing");
    fp_take_player_close(&a);
    fp_take_player_close(&b);
    fp_take_player_close(&base);
    printf("%s\n", fails ? "FAILED" : "ok");
    return fails ? 1 : 0;
}

int main(int argc, char **argv)
{
    if (argc == 3 && !strcmp(argv[1], "mute")) {
        fp_plugin_path pp;
        const char *dirs[] = {fp_test_plugin_dir()};
        fp_plugin_path_init(&pp, dirs, 1, NULL);
        int rc = mute_check(argv[2], &pp);
        fp_plugin_path_clear(&pp);
        return rc;
    }
    if (argc == 4 && !strcmp(argv[1], "channels")) {
        fp_plugin_path pp;
        const char *dirs[] = {fp_test_plugin_dir()};
        fp_plugin_path_init(&pp, dirs, 1, NULL);
        int rc = channels_check(argv[2], argv[3], &pp);
        fp_plugin_path_clear(&pp);
        return rc;
    }
    if (argc < 3 || (strcmp(argv[1], "mouth") && strcmp(argv[1], "punch")) ||
        (!strcmp(argv[1], "punch") && argc != 5)) {
        fprintf(stderr, "usage: test_stack_check mouth STACK | punch STACK IN OUT | channels TAKE DIR\n");
        return 2;
    }
    const bool punch = !strcmp(argv[1], "punch");
    const double t_in = punch ? atof(argv[3]) : 0, t_out = punch ? atof(argv[4]) : 0;
    char err[4096], base_path[8192];
    fp_take_player *stack = NULL, *base = NULL;
    fp_plugin_path pp;
    const char *dirs[] = {fp_test_plugin_dir()};
    fp_plugin_path_init(&pp, dirs, 1, NULL);
    if (fp_take_player_open(argv[2], NULL, &pp, &stack, err, sizeof err)) {
        printf("FAIL: %s\n", err);
        return 1;
    }
    fp_stack_player *sp = fp_take_player_stack(stack);
    const fp_stack *st = fp_stack_player_stack(sp);
    CHECK(st->layer_count == 2, "%zu layers, want 2", st->layer_count);
    fp_stack_take_path(st, 0, base_path, sizeof base_path);
    if (fp_take_player_open(base_path, NULL, &pp, &base, err, sizeof err)) {
        printf("FAIL: %s\n", err);
        return 1;
    }
    const fp_session *bs = fp_take_player_session(base);
    const size_t n = fp_session_vertex_count(bs);
    const float *w = fp_stack_player_region_weights(sp, 1);
    size_t outside = 0, core = 0;
    for (size_t v = 0; v < n; v++) outside += w[v] == 0, core += w[v] == 1;
    printf("%s: region %zu vertices of %zu (%zu at weight 1), %zu outside\n", argv[2], n - outside,
           n, core, outside);
    CHECK(core > 0 && outside > n / 2, "the region is not a part of the face");
    fp_take_frame f, g;
    int64_t first = 0;
    size_t frames = 0, showing = 0, outside_diff = 0, core_diff = 0, before_after = 0, ba_diff = 0;
    size_t fading = 0, sampled = 0;
    long new_x = 0;
    double fmax = 0;
    int rc;
    unsigned long limited = 0;
    while ((rc = fp_take_player_next(stack, &f, NULL, err, sizeof err)) == 1) {
        const bool bounded = fp_stack_player_limited(sp) != limited; /* the fold bound scaled it */
        limited = fp_stack_player_limited(sp);
        if (fp_take_player_next(base, &g, NULL, err, sizeof err) != 1) {
            CHECK(0, "the base take ended before the stack");
            break;
        }
        if (!frames) first = f.time_ns;
        const double t = (double)(f.time_ns - first) * 1e-9, lw = fp_stack_player_layer_weight(sp, 1);
        const float *c = fp_take_player_positions(stack), *b = fp_take_player_positions(base);
        const float *l = fp_stack_player_layer_positions(sp, 1);
        bool shows = false;
        for (size_t v = 0; v < n; v++) {
            const bool eq = same3(c + 3 * v, b + 3 * v);
            if (w[v] == 0 && !eq) outside_diff++;
            if (w[v] > 0 && !eq) shows = true;
            if (w[v] == 1 && lw == 1 && !same3(c + 3 * v, l + 3 * v)) core_diff++;
        }
        showing += shows;
        if (punch && (t <= t_in || t >= t_out)) {
            before_after++;
            ba_diff += memcmp(c, b, n * 3 * sizeof *c) != 0;
            CHECK(lw == 0, "t %.3f s outside the punch: layer weight %g", t, lw);
        }
        if (punch && t > t_in && t < t_out && lw > 0 && lw < 1 && !bounded) {
            const double fade = st->layers[1].fade_s;
            fading++;
            CHECK((t - t_in < fade + 1e-9) || (t_out - t < fade + 1e-9),
                  "t %.3f s: weight %g outside the cross-fades (fade %g s)", t, lw, fade);
        }
        fmax = fmax > lw ? fmax : lw;
        /* crossings: every 20th frame, and every frame cross-faded with the layer showing */
        if (shows && (frames % 20 == 0 || (lw > 0 && lw < 1))) {
            long x = crossings(bs, c);
            sampled++;
            if (x > 0) { /* the passes' own, or the blend's? */
                long xb = crossings(bs, b), xl = crossings(bs, l);
                printf("t %.3f s: %ld new crossings in the composite (base %ld, layer %ld)\n", t, x, xb, xl);
                if (x > (xb > xl ? xb : xl)) new_x += x;
            }
        }
        frames++;
    }
    CHECK(rc == 0, "play: %s", err);
    printf("frames %zu: the layer shows in %zu; outside the support %zu vertex-frames differ from "
           "the base; at weight 1 %zu differ from the layer; max layer weight %g; blend limited "
           "%lu times; composite frames checked for crossings %zu, new crossings beyond the "
           "passes' own %ld\n", frames, showing, outside_diff, core_diff, fmax,
           fp_stack_player_limited(sp), sampled, new_x);
    CHECK(frames > 0, "no frames");
    CHECK(outside_diff == 0, "vertices outside the region's support differ from the base");
    CHECK(core_diff == 0, "vertices at weight 1 differ from the layer's frame");
    CHECK(showing > 0, "the second pass never shows in the region");
    CHECK(new_x == 0, "the composite crosses itself where neither pass does");
    if (punch) {
        printf("punch %g - %g s: %zu frames before or after, %zu differ from the base; %zu frames "
               "in the cross-fades\n", t_in, t_out, before_after, ba_diff, fading);
        CHECK(before_after > 0 && ba_diff == 0, "frames outside the punch differ from the base");
        CHECK(fading > 0, "no frame inside the cross-fades");
    }
    fp_take_player_close(&base);
    fp_take_player_close(&stack);
    fp_plugin_path_clear(&pp);
    printf("%s\n", fails ? "FAILED" : "ok");
    return fails ? 1 : 0;
}
