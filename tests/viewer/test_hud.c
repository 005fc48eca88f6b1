/* The live viewer's HUD and review under Xvfb (issue 53 items 1-3): screenshots whose pixels
 * show each state's badge colour (hud.h) and no other, the key list on its backdrop over the
 * face and whole in narrow and short windows, messages wrapped inside the window at 640 and
 * 1280 px, take confirmations kept past the notes that follow, fingertip spheres that turn
 * green on the skin with their depth cue, a stopped take that leaves the live face and hands
 * shown (review only on V, left by Esc and by the next engage), --gpu-warp with the ICT
 * face's rig against the CPU's image, and a hand that goes (a replay's gap, as a lost tracker
 * or glove) said on the HUD's hands line until back.
 * Recordings (Leap joints CSV, one right hand) are written here: two poses 1.5 s apart. */
#define _GNU_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stb_image.h>

#include "hud.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

static char tmp[256], bin[4096], face[4096];
static char rec_far[512], rec_small[512], rec_pinch[512];
static char out[65536];

/* `facepuppet live -q ARGS` (stdout and stderr kept in `out`); the exit status. */
static int live(const char *fmt, ...)
{
    char args[8192], cmd[32768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof args, fmt, ap);
    va_end(ap);
    snprintf(cmd, sizeof cmd, "'%s' live -q --mesh '%s' %s >'%s/out.txt' 2>&1", bin, face, args, tmp);
    int st = system(cmd);
    snprintf(cmd, sizeof cmd, "%s/out.txt", tmp);
    out[0] = '\0';
    FILE *f = fopen(cmd, "r");
    if (f) {
        out[fread(out, 1, sizeof out - 1, f)] = '\0';
        fclose(f);
    }
    print_message("live %s\n-> %s", args, out);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* The n-th (from 0) stdout line starting with prefix, or NULL. */
static const char *line(const char *prefix, int n)
{
    for (const char *p = out; (p = strstr(p, prefix)); p++)
        if ((p == out || p[-1] == '\n') && n-- == 0) return p;
    return NULL;
}

static bool line_has(const char *prefix, int n, const char *needle)
{
    const char *l = line(prefix, n);
    if (!l) return false;
    const char *e = strchr(l, '\n'), *hit = strstr(l, needle);
    return hit && (!e || hit < e);
}

typedef struct image {
    int w, h;
    unsigned char *px;
} image;

static image load(const char *name, int w, int h)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", tmp, name);
    image im = {0};
    int n;
    im.px = stbi_load(path, &im.w, &im.h, &n, 3);
    assert_non_null(im.px);
    assert_int_equal(im.w, w);
    assert_int_equal(im.h, h);
    return im;
}

static const unsigned char *at(const image *im, int x, int y) { return im->px + 3 * (y * im->w + x); }
static int diff(const unsigned char *a, const unsigned char *b)
{
    int d = 0;
    for (int k = 0; k < 3; k++) d = abs(a[k] - b[k]) > d ? abs(a[k] - b[k]) : d;
    return d;
}

/* Pixels of the badge's box (top left, 64 x 15 at scale 1) within 6 of colour c. */
static int badge_pixels(const image *im, const float c[4])
{
    unsigned char ref[3] = {(unsigned char)lroundf(c[0] * 255), (unsigned char)lroundf(c[1] * 255),
                            (unsigned char)lroundf(c[2] * 255)};
    int n = 0;
    for (int y = 8; y < 8 + 15; y++)
        for (int x = 8; x < 8 + 64; x++) n += diff(at(im, x, y), ref) <= 6;
    return n;
}

/* Each shot shows its state's colour in the badge (most of the box) and no other state's. */
static void check_badge(const char *shot, fp_hud_badge want)
{
    image im = load(shot, 640, 480);
    for (int b = 0; b < FP_HUD_BADGES; b++) {
        int n = badge_pixels(&im, fp_hud_badge_color((fp_hud_badge)b));
        print_message("%s: %s's colour in %d badge pixels\n", shot, fp_hud_badge_name((fp_hud_badge)b), n);
        if (b == (int)want) assert_true(n > 500);
        else assert_int_equal(n, 0);
    }
    free(im.px);
}

/* Pixels of the recording's right hand's colour (the skeleton's lines, not shaded). */
static int hand_pixels(const image *im)
{
    int n = 0;
    for (int i = 0; i < im->w * im->h; i++) n += diff(im->px + 3 * i, (const unsigned char[]){255, 153, 64}) <= 8;
    return n;
}

static void test_badge_per_state(void **state)
{
    (void)state;
    assert_int_equal(live("--rig none --size 640x480 -i 'replay:%s,timeout=0' -M anchored,auto=0 --take-dir '%s/t1' "
                          "--frames 3000 --script 'key H; wait hands; wait frames 1; shot idle.png; "
                          "key E; wait frames 2; shot engaged.png; key T; wait frames 2; shot rec.png; "
                          "wait end; wait frames 2; key T; key C; wait frames 3; shot committed.png; "
                          "print messages; key V; wait frames 1; shot review.png; print hud; "
                          "key P; wait frames 1; shot playing.png; print hud; key Esc; key space; "
                          "wait frames 1; shot paused.png; key space; close'",
                          rec_far, tmp),
                     0);
    check_badge("idle.png", FP_HUD_IDLE);
    check_badge("engaged.png", FP_HUD_ENGAGED);
    check_badge("rec.png", FP_HUD_REC);
    check_badge("committed.png", FP_HUD_COMMITTED);
    check_badge("review.png", FP_HUD_REVIEW);
    check_badge("playing.png", FP_HUD_PLAYING);
    check_badge("paused.png", FP_HUD_PAUSED);
    assert_true(line_has("hud ", 0, " badge REVIEW "));
    assert_true(line_has("hud ", 1, " badge PLAYING "));
    /* the take's confirmation outlives the notes of the commit that followed it */
    assert_non_null(line("message ", 0));
    assert_true(strstr(out, "take kept alpha 1.00: take 1: "));
    assert_true(strstr(out, "note fading alpha 1.00: engine: "));
    /* converging fingertips: the fold-over guard holds the gesture back, LIMITED (apart=0:
     * this recording's fingertips, 9 mm apart, would otherwise share some of their skin) */
    assert_int_equal(live("--rig none --size 640x480 -i 'replay:%s,timeout=0' -M anchored,auto=0,apart=0 --frames 3000 "
                          "--script 'key H; wait hands; key E; wait end; wait frames 2; shot limited.png; "
                          "print hud; close'", rec_pinch),
                     0);
    assert_true(line_has("hud ", 0, " badge LIMITED "));
    check_badge("limited.png", FP_HUD_LIMITED);
}

/* ? shows the key list on a backdrop: over the face's middle no skin shows through. */
static void test_help_backdrop(void **state)
{
    (void)state;
    assert_int_equal(live("--rig none --size 640x480 --frames 100 --script 'key H; wait frames 1; "
                          "shot plain.png; key ?; wait frames 1; shot help.png; close'"),
                     0);
    image a = load("plain.png", 640, 480), b = load("help.png", 640, 480);
    const float *bd = fp_hud_backdrop_color();
    int skin_a = 0, skin_b = 0, dark_b = 0, total = 0;
    for (int y = 190; y < 290; y++)
        for (int x = 270; x < 370; x++) {
            const unsigned char *p = at(&a, x, y), *q = at(&b, x, y);
            skin_a += p[0] > 100 && p[0] > p[1] && p[1] > p[2];
            skin_b += q[0] > 100 && q[0] > q[1] && q[1] > q[2];
            dark_b += q[0] < 40 && q[1] < 40 && q[2] < 40;
            total++;
        }
    print_message("centre 100x100: skin %d without the key list, %d with it; dark %d (backdrop alpha %.2f)\n",
                  skin_a, skin_b, dark_b, bd[3]);
    assert_true(skin_a > total * 8 / 10);
    assert_int_equal(skin_b, 0);
    assert_true(dark_b > total * 6 / 10);
    free(a.px);
    free(b.px);
}

/* The key list fits narrow and short windows whole: its backdrop ends above the window's
 * bottom (the bottom rows in the middle are as without it), at 200x480 and 280x720 (narrow:
 * wrapped, at scale 1 where 2 does not fit) and 640x240 (short: two columns). Before, it was
 * wrapped to the width alone and cut off at the bottom in each (about 290 px wide or less). */
static void test_help_fits_narrow(void **state)
{
    (void)state;
    const int sizes[3][2] = {{200, 480}, {280, 720}, {640, 240}};
    for (int k = 0; k < 3; k++) {
        const int w = sizes[k][0], h = sizes[k][1];
        assert_int_equal(live("--rig none --size %dx%d --frames 100 --script 'key space; key H; wait frames 1; "
                              "shot plain.png; key ?; wait frames 1; shot help.png; close'", w, h),
                         0);
        image a = load("plain.png", w, h), b = load("help.png", w, h);
        int changed_bottom = 0, changed_middle = 0;
        for (int x = w / 2 - 5; x <= w / 2 + 5; x++) {
            for (int y = h - 2; y < h; y++) changed_bottom += diff(at(&a, x, y), at(&b, x, y)) > 8;
            changed_middle += diff(at(&a, x, h / 2), at(&b, x, h / 2)) > 8;
        }
        print_message("%dx%d: middle columns changed by the key list: %d at mid-height, %d in the bottom two rows\n",
                      w, h, changed_middle, changed_bottom);
        assert_true(changed_middle > 0);   /* the backdrop is there */
        assert_int_equal(changed_bottom, 0); /* and ends inside the window */
        free(a.px);
        free(b.px);
    }
}

/* A long message wraps inside the window: the right margin stays background, at 640 and
 * 1280 px wide. */
static void test_messages_wrap(void **state)
{
    (void)state;
    const int sizes[2][2] = {{640, 480}, {1280, 720}};
    for (int k = 0; k < 2; k++) {
        int w = sizes[k][0], h = sizes[k][1];
        assert_int_equal(live("--rig none --size %dx%d --frames 100 --script 'key H; drop %s/a-folder-whose-name"
                              "-is-long/another-folder-whose-name-is-longer-still/and-a-third-to-make-sure/"
                              "the-face-that-is-not-there.obj; wait frames 1; shot wrap%d.png; print messages; close'",
                              w, h, tmp, w),
                         0);
        assert_true(strstr(out, "info fading alpha 1.00: cannot load "));
        char name[32];
        snprintf(name, sizeof name, "wrap%d.png", w);
        image im = load(name, w, h);
        const unsigned char *bg = at(&im, w - 1, h - 1);
        int off = 0, text = 0;
        for (int y = 0; y < h / 2; y++) {
            for (int x = w - 7; x < w; x++) off += diff(at(&im, x, y), bg) > 2;
            for (int x = 8; x < w / 2; x++) text += diff(at(&im, x, y), bg) > 100;
        }
        print_message("%dx%d: %d pixels in the right margin differ from the background; %d text pixels\n", w, h,
                      off, text);
        assert_int_equal(off, 0);
        assert_true(text > 500);
        free(im.px);
    }
}

/* Spheres of fingertips on the skin (pose A: every tip within R) turn green; 35 mm back
 * (pose B) they do not, and each fingertip's cue line (grey, drawn over the face) shows. */
static void test_tip_spheres(void **state)
{
    (void)state;
    assert_int_equal(live("--rig none --size 640x480 -i 'replay:%s,timeout=0' -M anchored,auto=0 --frames 3000 --script 'key Tab; "
                          "wait hands; wait frames 1; shot touch.png; print hud; wait end; wait frames 2; "
                          "shot far.png; print hud; close'", rec_far),
                     0);
    assert_true(line_has("hud ", 0, " touching 5 of 5 "));
    assert_true(line_has("hud ", 1, " touching 0 of 5 "));
    image t = load("touch.png", 640, 480), f = load("far.png", 640, 480);
    int green_t = 0, green_f = 0, cue_t = 0, cue_f = 0;
    for (int i = 0; i < 640 * 480; i++) {
        const unsigned char *p = t.px + 3 * i, *q = f.px + 3 * i;
        green_t += p[1] > p[0] + 40 && p[1] > p[2] + 40;
        green_f += q[1] > q[0] + 40 && q[1] > q[2] + 40;
        cue_t += p[0] > 150 && p[2] > p[0] + 4 && p[2] >= p[1];
        cue_f += q[0] > 150 && q[2] > q[0] + 4 && q[2] >= q[1];
    }
    print_message("green pixels: %d touching, %d not; grey cue pixels: %d touching, %d not\n", green_t, green_f,
                  cue_t, cue_f);
    assert_true(green_t > 300);
    assert_true(green_f < 10);
    assert_true(cue_f > 10);
    free(t.px);
    free(f.px);
}

/* A take stopped in live: 30 frames later the live face and hands are shown (no review);
 * V opens the review (hands hidden), Esc leaves it and the run goes on; V again, then E: the
 * engage leaves it too. */
static void test_review_lets_go(void **state)
{
    (void)state;
    assert_int_equal(live("--rig none --size 640x480 -i 'replay:%s,timeout=0' -M anchored,auto=0 --take-dir '%s/t2' "
                          "--frames 3000 --script 'key Tab; wait hands; key T; key E; wait frames 5; key T; "
                          "wait frames 30; shot after.png; print hud; key V; wait frames 1; shot review.png; "
                          "print hud; key Esc; wait frames 1; shot back.png; print hud; key V; wait frames 1; "
                          "print hud; key E; wait frames 1; print hud; close'",
                          rec_far, tmp),
                     0);
    assert_true(line_has("hud ", 0, " badge ENGAGED "));
    assert_true(line_has("hud ", 1, " badge REVIEW "));
    assert_false(line_has("hud ", 2, " badge REVIEW "));
    assert_true(line_has("hud ", 3, " badge REVIEW "));
    assert_false(line_has("hud ", 4, " badge REVIEW "));
    assert_non_null(line("hud ", 4)); /* Esc left the review; it did not quit */
    image a = load("after.png", 640, 480), r = load("review.png", 640, 480), b = load("back.png", 640, 480);
    int ha = hand_pixels(&a), hr = hand_pixels(&r), hb = hand_pixels(&b);
    print_message("hand pixels: %d 30 frames after the stop, %d in review, %d after Esc\n", ha, hr, hb);
    assert_true(ha > 100);
    assert_int_equal(hr, 0);
    assert_true(hb > 100);
    free(a.px);
    free(r.px);
    free(b.px);
}

/* --gpu-warp with the ICT face's rig (jaw opened by J: the warp runs on the posed surface,
 * blended by the rig's mobility in the shader) draws the CPU path's image; where the fold-over
 * guard composes several maps (five close fingertips) it draws the CPU's, said in one line. */
static void test_gpu_warp_rig(void **state)
{
    (void)state;
    const char *script = "key H; key Tab; key J; key J; key J; wait hands; wait frames 1; shot %s-rest.png; "
                         "key E; wait end; wait frames 2; shot %s.png; print hud; close";
    char s[512];
    image im[2], rest;
    double err = -1, disp = -1;
    for (int g = 0; g < 2; g++) {
        const char *name = g ? "gpu" : "cpu";
        snprintf(s, sizeof s, script, name, name);
        assert_int_equal(live("--size 320x240 -i 'replay:%s,timeout=0' -M anchored,auto=0 --frames 3000 %s --script '%s'",
                              rec_small, g ? "--gpu-warp" : "", s),
                         0);
        assert_true(line_has("hud ", 0, "from the rig"));
        if (g) {
            assert_true(line_has("hud ", 0, " drawn gpu-warp"));
            const char *l = strstr(out, "gpu-warp: ");
            assert_non_null(l);
            size_t checks = 0;
            assert_int_equal(sscanf(l, "gpu-warp: %zu checks against the CPU engine; max |GPU - CPU| %lf mesh units, "
                                       "%*g of the max displacement %lf", &checks, &err, &disp), 3);
            assert_true(checks >= 1);
        } else {
            assert_true(line_has("hud ", 0, " drawn cpu"));
        }
        char file[32];
        snprintf(file, sizeof file, "%s.png", name);
        im[g] = load(file, 320, 240);
    }
    rest = load("cpu-rest.png", 320, 240);
    int moved = 0, off = 0, maxd = 0;
    double sum = 0;
    for (int y = 0; y < 240; y++)
        for (int x = 0; x < 320; x++) {
            int d = diff(at(&im[0], x, y), at(&im[1], x, y));
            moved += diff(at(&rest, x, y), at(&im[0], x, y)) > 8;
            off += d > 16;
            sum += d;
            maxd = d > maxd ? d : maxd;
        }
    print_message("gpu-warp with the rig: max |GPU - CPU| %.3g mesh units over a max displacement %.3g; image: "
                  "%d pixels differ by > 16 (max %d, mean %.4f); the deformation moved %d pixels\n",
                  err, disp, off, maxd, sum / (320 * 240), moved);
    assert_true(disp > 0.05);
    assert_true(err < 0.01 * disp);
    assert_true(moved > 30);
    assert_true(off <= 20);
    assert_true(sum / (320 * 240) < 0.5);
    assert_int_equal(live("--size 320x240 -i 'replay:%s,timeout=0' -M anchored,auto=0 --frames 3000 --gpu-warp --script "
                          "'key H; key Tab; wait hands; key E; wait end; wait frames 2; print hud; close'", rec_far),
                     0);
    assert_true(line_has("hud ", 0, " drawn cpu"));
    /* each reason once, however many frames it held */
    int said = 0, composed = 0, guard = 0;
    for (const char *p = out; (p = strstr(p, "; drawing those frames from the CPU")); p++) said++;
    for (const char *p = out; (p = strstr(p, "gpu-warp: the fold-over guard composed")); p++) composed++;
    for (const char *p = out; (p = strstr(p, "gpu-warp: the contact guard")); p++) guard++;
    print_message("fallback lines: %d (composed %d, contact guard %d)\n", said, composed, guard);
    assert_true(said >= 1);
    assert_true(composed <= 1 && guard <= 1);
    assert_int_equal(said, composed + guard);
    assert_null(strstr(out, "; 0 frames drawn from the CPU"));
    free(im[0].px);
    free(im[1].px);
    free(rest.px);
}

/* The header row of a joints CSV as the replay input reads it (../shared/data's
 * *_joints_mm.csv): palm, direction, 5 x 4 joints. */
static void write_csv_header(FILE *f)
{
    fputs("frame,timestamp_us,hand_id,hand_type,palm_x,palm_y,palm_z,palm_nx,palm_ny,palm_nz,"
          "dir_x,dir_y,dir_z", f);
    const char *fingers[] = {"thumb", "index", "middle", "ring", "pinky"}, *joints[] = {"mcp", "pip", "dip", "tip"};
    for (int fi = 0; fi < 5; fi++)
        for (int j = 0; j < 4; j++)
            fprintf(f, ",%s_%s_x,%s_%s_y,%s_%s_z", fingers[fi], joints[j], fingers[fi], joints[j], fingers[fi], joints[j]);
    fputs("\n", f);
}

/* Two poses of one right hand, 1.5 s apart: pose B moved dy up and dz toward the performer,
 * or (pinch) the five fingertips brought together; one: only the index finger near the face
 * (one centre: the fold-over guard's single map, which the shader draws). Replayed with
 * timeout=0: the hand holds pose A between the samples (the default 1 s would take it for
 * a hand the tracker lost). */
static void write_recording(char *path, size_t n, const char *name, double dy, double dz, bool pinch, bool one)
{
    snprintf(path, n, "%s/%s", tmp, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    write_csv_header(f);
    for (int row = 0; row < 2; row++) {
        double ry = row ? dy : 0, rz = row ? dz : 0;
        fprintf(f, "%d,%d,7,right,40,%.1f,%.1f,0,-1,0,0,0,-1", row, row ? 1500000 : 0, 200 + ry, -40 + rz);
        for (int fi = 0; fi < 5; fi++) {
            double x = 22 + 9 * fi, y = (fi ? 212 : 200) + ry, z[4] = {-70, -88, -102, -112};
            double back = one && fi != 1 ? 45 : 0; /* one: only the index near the face */
            for (int j = 0; j < 4; j++) {
                bool together = pinch && row && j == 3;
                fprintf(f, ",%.1f,%.1f,%.1f", together ? 40.0 : x, together ? 206.0 : y, z[j] + rz + back);
            }
        }
        fputs("\n", f);
    }
    fclose(f);
}

/* A right hand the tracker loses for 2.5 s while the left goes on (a replay's gap, default
 * timeout 1 s: as an osc sender's hand or a glove that stops; README "A hand the tracker
 * loses lets go"), then finds again: both hands every 100 ms over 6 s, but no right hand
 * from 0.5 s to 3 s. */
static void write_gap_recording(char *path, size_t n)
{
    snprintf(path, n, "%s/gap.csv", tmp);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    write_csv_header(f);
    for (int row = 0; row <= 60; row++)
        for (int side = 0; side < 2; side++) {
            if (side == 1 && row > 5 && row < 30) continue; /* the right hand lost */
            double sx = side ? 1 : -1; /* the left hand mirrored, 120 mm out (hovering) */
            fprintf(f, "%d,%d,%d,%s,%.1f,200,80,0,-1,0,0,0,-1", row, row * 100000, 7 + side,
                    side ? "right" : "left", sx * 40);
            for (int fi = 0; fi < 5; fi++)
                for (int j = 0; j < 4; j++)
                    fprintf(f, ",%.1f,%.1f,%.1f", sx * (22 + 9 * fi), fi ? 212.0 : 200.0, 50.0 - 10 * j);
            fputs("\n", f);
        }
    fclose(f);
}

/* A hand that goes (its input unplugged, its tracker lost it) stays said in the HUD for as
 * long as it is gone, with its input's word on it, and the line goes once it is back (before,
 * the input's note faded after a few seconds like any note and nothing said the hand was
 * gone; docs/cyberglove.md: "the HUD shows the input's state"). */
static void test_hand_gone_stays_said(void **state)
{
    (void)state;
    char gap[512];
    write_gap_recording(gap, sizeof gap);
    assert_int_equal(live("--size 640x400 --input 'replay:%s' --script 'wait hands; print hud; "
                          "wait seconds 2.3; print hud; wait seconds 1.5; print hud; close'", gap), 0);
    assert_non_null(line("hud ", 2));
    assert_true(line_has("hud ", 0, " hands ''"));           /* (one performer, both there) */
    assert_true(line_has("hud ", 1, " hands 'hands: left; gone: right (replay: right hand: "));
    assert_true(line_has("hud ", 2, " hands ''"));            /* back: nothing to say */
}

/* live keeps what exists (README: no command overwrites a file without being asked): an
 * --out that exists is refused before the window (exit 73, naming it) unless --force, and the
 * S key's screenshot takes the next name no file has, where before it wrote
 * facepuppet-shot-001.png over an earlier session's and --out replaced the file silently. */
static void test_outputs_kept(void **state)
{
    (void)state;
    FILE *f = fopen("kept.obj", "w");
    assert_non_null(f);
    fputs("# an earlier shape\n", f);
    fclose(f);
    f = fopen("facepuppet-shot-001.png", "w");
    assert_non_null(f);
    fputs("an earlier shot", f);
    fclose(f);
    assert_int_equal(live("--size 160x120 --frames 2 -o kept.obj"), 73);
    assert_non_null(strstr(out, "--out kept.obj: exists (--force to overwrite)"));
    assert_int_equal(live("--size 160x120 --script 'key S; wait frames 2; close'"), 0);
    char text[64] = "";
    f = fopen("facepuppet-shot-001.png", "r");
    assert_non_null(f);
    text[fread(text, 1, sizeof text - 1, f)] = '\0';
    fclose(f);
    assert_string_equal(text, "an earlier shot");
    image im = load("facepuppet-shot-002.png", 160, 120);
    free(im.px);
    assert_int_equal(live("--size 160x120 --frames 2 -o kept.obj --force"), 0);
    f = fopen("kept.obj", "r");
    assert_non_null(f);
    text[fread(text, 1, sizeof text - 1, f)] = '\0';
    fclose(f);
    assert_null(strstr(text, "an earlier shape"));
}

static int setup(void **state)
{
    (void)state;
    const char *build = getenv("FP_BUILD_DIR");
    snprintf(bin, sizeof bin, "%s/bin/facepuppet", build ? build : "build");
    const char *data = getenv("FP_SHARED_DATA");
    snprintf(face, sizeof face, "%s/faces/ict-facekit/generic_neutral_mesh.obj", data ? data : "../shared/data");
    char *abs_bin = realpath(bin, NULL), *abs_face = realpath(face, NULL);
    if (!abs_bin || !abs_face) return -1;
    snprintf(bin, sizeof bin, "%s", abs_bin);
    snprintf(face, sizeof face, "%s", abs_face);
    free(abs_bin);
    free(abs_face);
    snprintf(tmp, sizeof tmp, "/tmp/fp-test-hud-XXXXXX");
    if (!mkdtemp(tmp)) return -1;
    if (chdir(tmp)) return -1; /* (shots are written by relative name) */
    write_recording(rec_far, sizeof rec_far, "far.csv", 35, 35, false, false);
    write_recording(rec_small, sizeof rec_small, "small.csv", 10, 0, false, true);
    write_recording(rec_pinch, sizeof rec_pinch, "pinch.csv", 0, 0, true, false);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
    return system(cmd) == 0 ? 0 : -1;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_badge_per_state), cmocka_unit_test(test_help_backdrop),
        cmocka_unit_test(test_messages_wrap),   cmocka_unit_test(test_tip_spheres),
        cmocka_unit_test(test_review_lets_go),  cmocka_unit_test(test_gpu_warp_rig),
        cmocka_unit_test(test_hand_gone_stays_said), cmocka_unit_test(test_outputs_kept),
        cmocka_unit_test(test_help_fits_narrow),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
