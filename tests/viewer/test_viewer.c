/* `facepuppet live` end to end, under Xvfb (Mesa llvmpipe): screenshots of the ICT face,
 * a scripted engaged deformation driven by a two-pose recording, undo, closing by Esc and by
 * the close button, a dropped mesh, the mapping keys, and command-line errors.
 * The run is deterministic: the recording holds pose A at 0 s and pose B at 1.5 s; the script
 * waits for the first pose, engages (start points = A's fingertips), waits for the end of the
 * recording (end points = B's fingertips), commits, undoes. Hands and HUD are hidden (keys H,
 * Tab) so that the images show the face alone. */
#define _GNU_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stb_image.h>

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static char tmp[256];
static char bin[4096];
static char face[4096];
static char rec[512];

#define SIZE "--size 320x240"

/* Run `facepuppet live ARGS` with stdout and stderr into tmp/out.txt; the exit status. */
static int live(const char *fmt, ...)
{
    char args[4096], cmd[16384];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof args, fmt, ap);
    va_end(ap);
    snprintf(cmd, sizeof cmd, "'%s' live -q " SIZE " --mesh '%s' %s >'%s/out.txt' 2>&1", bin, face,
             args, tmp);
    int st = system(cmd);
    char out[4096] = "";
    snprintf(cmd, sizeof cmd, "%s/out.txt", tmp);
    FILE *f = fopen(cmd, "r");
    if (f) {
        size_t n = fread(out, 1, sizeof out - 1, f);
        out[n] = '\0';
        fclose(f);
    }
    print_message("live %s\n-> %s", args, out);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static bool out_contains(const char *needle)
{
    char path[512], out[8192] = "";
    snprintf(path, sizeof path, "%s/out.txt", tmp);
    FILE *f = fopen(path, "r");
    if (!f) return false;
    size_t n = fread(out, 1, sizeof out - 1, f);
    out[n] = '\0';
    fclose(f);
    return strstr(out, needle) != NULL;
}

typedef struct image {
    int w, h;
    unsigned char *px;  /* RGB */
} image;

static image load(const char *name)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", tmp, name);
    image im = {0};
    int n;
    im.px = stbi_load(path, &im.w, &im.h, &n, 3);
    assert_non_null(im.px);
    assert_int_equal(im.w, 320);
    assert_int_equal(im.h, 240);
    return im;
}

static const unsigned char *at(const image *im, int x, int y) { return im->px + 3 * (y * im->w + x); }
static int diff(const unsigned char *a, const unsigned char *b)
{
    int d = 0;
    for (int k = 0; k < 3; k++) d = abs(a[k] - b[k]) > d ? abs(a[k] - b[k]) : d;
    return d;
}

/* The background: the four corners' 16x16 blocks are one colour; returns it. */
static void check_background(const image *im, unsigned char bg[3])
{
    memcpy(bg, at(im, 0, 0), 3);
    int xs[2] = {0, im->w - 16}, ys[2] = {0, im->h - 16};
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++)
            for (int y = ys[j]; y < ys[j] + 16; y++)
                for (int x = xs[i]; x < xs[i] + 16; x++) assert_int_equal(diff(at(im, x, y), bg), 0);
}

/* The face shows in the middle: most pixels of the central 40x40 block differ from bg. */
static void check_face_in_middle(const image *im, const unsigned char bg[3])
{
    int differ = 0;
    for (int y = im->h / 2 - 20; y < im->h / 2 + 20; y++)
        for (int x = im->w / 2 - 20; x < im->w / 2 + 20; x++) differ += diff(at(im, x, y), bg) > 8;
    assert_true(differ > 40 * 40 * 9 / 10);
}

static void test_screenshot_shows_face(void **state)
{
    (void)state;
    assert_int_equal(live("--frames 3 --screenshot '%s/face.png' --script 'key H; key Tab'", tmp), 0);
    image im = load("face.png");
    unsigned char bg[3];
    check_background(&im, bg);
    check_face_in_middle(&im, bg);
    assert_true(out_contains("frame time median"));
    assert_true(out_contains("event-to-frame latency"));
    stbi_image_free(im.px);
}

static void test_deform_commit_undo(void **state)
{
    (void)state;
    /* --rig none: this checks the viewer's engage, commit and undo, not the rig (whose skull
     * and finger clamp keep the recording's grab small on the ICT face) */
    assert_int_equal(live("--rig none -i 'replay:%s,timeout=0' -M anchored,auto=0 --frames 2000 --script "
                          "'key H; key Tab; wait hands; shot %s/a.png; key E; wait end; key C; "
                          "shot %s/b.png; key Z; shot %s/c.png; key Esc'",
                          rec, tmp, tmp, tmp),
                     0);
    image a = load("a.png"), b = load("b.png"), c = load("c.png");
    unsigned char bg[3];
    check_background(&a, bg);
    check_face_in_middle(&a, bg);
    /* b differs from a, inside the face: every differing pixel is a face pixel in a or b. */
    int changed = 0, outside = 0, undo_off = 0;
    for (int y = 0; y < a.h; y++)
        for (int x = 0; x < a.w; x++) {
            const unsigned char *pa = at(&a, x, y), *pb = at(&b, x, y);
            if (diff(pa, pb) > 3) {
                changed++;
                if (!diff(pa, bg) && !diff(pb, bg)) outside++;
            }
            undo_off += diff(pa, at(&c, x, y)) > 1;
        }
    print_message("deformation changed %d pixels (%d outside the face); undo left %d off\n",
                  changed, outside, undo_off);
    assert_true(changed >= 30);
    assert_int_equal(outside, 0);
    unsigned char bgb[3];
    check_background(&b, bgb);
    assert_int_equal(diff(bg, bgb), 0);
    /* Undo returns the first image. */
    assert_int_equal(undo_off, 0);
    stbi_image_free(a.px);
    stbi_image_free(b.px);
    stbi_image_free(c.px);
}

/* Partial uploads (fp_session_touched, ui/viewer/vnormals.c) show the same pixels as whole
 * ones (FACEPUPPET_VIEWER_UPLOAD=full, the viewer before them) while engaged, committed and
 * undone; =check compares every partial upload with the whole computation in the run. */
static void test_partial_upload_same_pixels(void **state)
{
    (void)state;
    const char *modes[2] = {"full", "check"};
    for (int m = 0; m < 2; m++) {
        setenv("FACEPUPPET_VIEWER_UPLOAD", modes[m], 1);
        int rc = live("--rig none -i 'replay:%s,timeout=0' -M anchored,auto=0 --frames 2000 --script "
                      "'key H; key Tab; wait hands; key E; wait end; wait frames 2; shot %s/%s-e.png; "
                      "key C; wait frames 2; shot %s/%s-c.png; key Z; wait frames 2; shot %s/%s-z.png; key Esc'",
                      rec, tmp, modes[m], tmp, modes[m], tmp, modes[m]);
        unsetenv("FACEPUPPET_VIEWER_UPLOAD");
        assert_int_equal(rc, 0);
        if (m == 1) {
            assert_true(out_contains(" partial uploads checked, 0 differ from the whole"));
            assert_false(out_contains("; 0 partial uploads checked"));
        }
    }
    const char *shots[3] = {"e", "c", "z"};
    for (int k = 0; k < 3; k++) {
        char a[64], b[64];
        snprintf(a, sizeof a, "full-%s.png", shots[k]);
        snprintf(b, sizeof b, "check-%s.png", shots[k]);
        image full = load(a), part = load(b);
        int differ = 0;
        for (int i = 0; i < full.w * full.h * 3; i++) differ += full.px[i] != part.px[i];
        print_message("%s: %d bytes differ between whole and partial uploads\n", shots[k], differ);
        assert_int_equal(differ, 0);
        stbi_image_free(full.px);
        stbi_image_free(part.px);
    }
}

/* The same check with the ICT face's rig (its mobility blend, the commit re-posing the base). */
static void test_partial_upload_rig(void **state)
{
    (void)state;
    setenv("FACEPUPPET_VIEWER_UPLOAD", "check", 1);
    int rc = live("-i 'replay:%s,timeout=0' -M anchored,auto=0 --frames 2000 --script "
                  "'wait hands; key E; wait end; wait frames 2; key C; wait frames 2; key E; "
                  "wait frames 2; key Z; wait frames 2; key R; wait frames 2; key Esc'", rec);
    unsetenv("FACEPUPPET_VIEWER_UPLOAD");
    assert_int_equal(rc, 0);
    assert_true(out_contains(" partial uploads checked, 0 differ from the whole"));
}

/* The HUD follows the session (issue 10): ENGAGED clears and the commit count goes back on
 * undo, reset and a dropped mesh; `print hud` prints what the HUD shows. */
static void test_hud_follows_undo_reset_drop(void **state)
{
    (void)state;
    /* --rig none: the scale then comes from the head, as the expected lines say */
    assert_int_equal(live("--rig none -i 'replay:%s,timeout=0' -M anchored,auto=0 --frames 2000 --script "
                          "'wait hands; key E; wait frames 3; print hud; key C; wait frames 3; "
                          "key E; wait frames 3; key C; wait frames 3; print hud; "
                          "key E; wait frames 3; key Z; print hud; key Z; print hud; "
                          "key E; wait frames 3; key C; wait frames 3; key R; print hud; "
                          "key E; wait frames 3; drop %s; wait frames 1; print hud; close'",
                          rec, face),
                     0);
    assert_true(out_contains("state ENGAGED commits 0 scale 10.24 mm per mesh unit (detected from the head"));
    assert_true(out_contains("state committed commits 2 "));
    assert_true(out_contains("state idle commits 1 "));  /* undo while engaged: the gesture */
    assert_true(out_contains("state idle commits 0 "));  /* is dropped, the base goes back */
    assert_false(out_contains("state ENGAGED commits 1"));
    assert_false(out_contains("state ENGAGED commits 2"));
    /* reset and the dropped mesh: idle, no commits (three lines, counted below) */
    char path[512], out[8192] = "";
    snprintf(path, sizeof path, "%s/out.txt", tmp);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    out[fread(out, 1, sizeof out - 1, f)] = '\0';
    fclose(f);
    int idle0 = 0;
    for (const char *p = out; (p = strstr(p, "state idle commits 0 ")); p++) idle0++;
    assert_int_equal(idle0, 3);
}

static void test_close_button_and_esc(void **state)
{
    (void)state;
    assert_int_equal(live("-i 'replay:%s,timeout=0' --frames 1000 --script 'wait frames 2; close'", rec), 0);
    assert_true(out_contains("frames 3;"));
    assert_int_equal(live("-i 'replay:%s,timeout=0' --frames 1000 --script 'wait frames 1; key Esc'", rec), 0);
    assert_true(out_contains("frames 2;"));
    /* the same script from a file (--script @FILE, read as every input file is) */
    char path[512];
    snprintf(path, sizeof path, "%s/close.script", tmp);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("wait frames 2; close\n", f);
    fclose(f);
    assert_int_equal(live("-i 'replay:%s,timeout=0' --frames 1000 --script @%s", rec, path), 0);
    assert_true(out_contains("frames 3;"));
}

static void test_drop_mesh_and_mapping_keys(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof path, "%s/cube.obj", tmp);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
          "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\n"
          "f 1 8 4\nf 2 3 7\nf 2 7 6\n", f);
    fclose(f);
    /* A missing file keeps the face; the cube then replaces it and fills the middle. */
    assert_int_equal(live("-i 'replay:%s,timeout=0' --frames 100 --script 'key H; key Tab; key 2; key 1; "
                          "drop %s/missing.obj; wait frames 1; drop %s; wait frames 1; "
                          "shot %s/cube.png; close'", rec, tmp, path, tmp), 0);
    assert_true(out_contains("cannot load"));
    image im = load("cube.png");
    unsigned char bg[3];
    check_background(&im, bg);
    check_face_in_middle(&im, bg);
    stbi_image_free(im.px);
}

static void test_command_line_errors(void **state)
{
    (void)state;
    assert_int_equal(live("--script 'jump 3' --frames 2"), 64);
    assert_true(out_contains("jump"));
    assert_int_equal(live("--size 0x0"), 64);
    assert_int_equal(live("--screenshot '%s/x.png'", tmp), 64);
    /* a screenshot is a PNG: another name is refused before the window, not written as PNG */
    assert_int_equal(live("--frames 1 --screenshot '%s/x.jpg'", tmp), 64);
    assert_true(out_contains("a screenshot is a PNG"));
    assert_int_equal(live("--frames 2 -M nosuchmapping"), 78);
    /* A screenshot that cannot be written: exit 73. */
    assert_int_equal(live("--frames 1 --screenshot /nonexistent-dir/x.png"), 73);
}

/* Takes in live: T records (REC in red at the top right), T again stops and the timeline
 * strip shows the take as a block; scrubbing the strip from the first frame (pose A, the
 * engage: no deformation) to the last (pose B) changes the face. */
static void test_take_rec_timeline_scrub(void **state)
{
    (void)state;
    /* --rig none: the deformation checked here is the fingers', not the rig's clamp */
    assert_int_equal(live("--rig none --input 'replay:%s,timeout=0' --take-dir '%s/takes' --slate scene --script "
                          "'wait hands; key T; key E; wait end; wait frames 3; shot %s/rec.png; "
                          "key T; wait frames 2; shot %s/strip.png; scrub 0; wait frames 1; "
                          "shot %s/a.png; scrub 1; wait frames 1; shot %s/b.png; close'",
                          rec, tmp, tmp, tmp, tmp, tmp), 0);
    char path[512];
    snprintf(path, sizeof path, "%s/takes/scene_T001.fptake", tmp);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    image r = load("rec.png"), s = load("strip.png"), a = load("a.png"), b = load("b.png");
    /* REC: red pixels in the top right (the box and the letters) while recording, none after */
    int red_rec = 0, red_after = 0;
    for (int y = 0; y < 40; y++)
        for (int x = r.w / 2; x < r.w; x++) {
            const unsigned char *p = at(&r, x, y), *q = at(&s, x, y);
            red_rec += p[0] > 200 && p[1] < 80 && p[2] < 80;
            red_after += q[0] > 200 && q[1] < 80 && q[2] < 80;
        }
    print_message("red pixels: %d recording, %d after\n", red_rec, red_after);
    assert_true(red_rec > 100);
    assert_int_equal(red_after, 0);
    /* the strip (bottom, y 194..212 at 320x240): the reviewed take's block, light blue */
    int block = 0, block_before = 0;
    for (int y = 194; y < 212; y++)
        for (int x = 8; x < 312; x++) {
            const unsigned char *p = at(&s, x, y), *q = at(&r, x, y);
            block += diff(p, (const unsigned char[]){115, 178, 255}) < 12;
            block_before += diff(q, (const unsigned char[]){115, 178, 255}) < 12;
        }
    print_message("strip block pixels: %d (before the take: %d)\n", block, block_before);
    assert_true(block > 2000);
    assert_int_equal(block_before, 0);
    /* scrubbing changes the face: pixels of the face area that differ between frames */
    int changed = 0;
    for (int y = 40; y < 180; y++)
        for (int x = 60; x < 260; x++) changed += diff(at(&a, x, y), at(&b, x, y)) > 8;
    print_message("face pixels changed by scrubbing: %d\n", changed);
    assert_true(changed > 50);
    free(r.px);
    free(s.px);
    free(a.px);
    free(b.px);
}

/* The take's label at the top right ("T: record  scene take 1", then "REC  TIMECODE  scene
 * take 1") stays on the badge's row, clear of the HUD's text under it: at 320x240 (scale 1)
 * the badge spans rows 8..22 and the HUD's first line (the mesh, its vertices, the mapping:
 * wider than the window's right half) starts at row 27. Before, the label was drawn at rows
 * 22..29, over the first line's "mapping anchored" (at 960x600: rows 36..50 over 46..60). */
static void test_take_label_clear_of_hud(void **state)
{
    (void)state;
    assert_int_equal(live("--rig none --take-dir '%s/label-takes' --slate scene --script "
                          "'wait frames 2; shot %s/label.png; key T; wait frames 3; shot %s/label-rec.png; "
                          "key T; wait frames 1; close'", tmp, tmp, tmp), 0);
    image a = load("label.png"), b = load("label-rec.png");
    static const unsigned char dim[3] = {204, 217, 230}; /* takes.c's dim, 0.8 0.85 0.9 */
    int label = 0, label_low = 0, rec = 0, rec_low = 0, white_first_line = 0;
    for (int y = 0; y < 60; y++)
        for (int x = a.w / 2; x < a.w; x++) {
            const unsigned char *p = at(&a, x, y), *q = at(&b, x, y);
            bool d = diff(p, dim) <= 3, red = q[0] > 200 && q[1] < 80 && q[2] < 80;
            label += d;
            label_low += d && y >= 23;
            rec += red;
            rec_low += red && y >= 23;
            white_first_line += y >= 27 && y < 35 && p[0] > 235 && p[1] > 235 && p[2] > 225;
        }
    print_message("top right: label pixels %d (%d under the badge's row), REC pixels %d (%d under), "
                  "the HUD's first line there %d\n", label, label_low, rec, rec_low, white_first_line);
    assert_true(label > 40);
    assert_true(rec > 40);
    assert_true(white_first_line > 20); /* (the line the label used to cover is there) */
    assert_int_equal(label_low, 0);
    assert_int_equal(rec_low, 0);
    free(a.px);
    free(b.px);
}

/* Pixels of the rig overlay's colours (ui/viewer/viewer.c, key G) in an image: shaded region
 * colours told apart from the skin (which has r > g > b, r - g under 50), the hinge axis and
 * the landmarks in their exact colours (lines and points are not shaded). */
typedef struct rig_pixels {
    int skull, jaw, soft, hinge, landmark;
    double skull_y, jaw_y, hinge_x, hinge_y;   /* mean rows and columns */
} rig_pixels;

static rig_pixels count_rig(const image *im)
{
    rig_pixels c = {0};
    for (int y = 0; y < im->h; y++)
        for (int x = 0; x < im->w; x++) {
            const unsigned char *p = at(im, x, y);
            int r = p[0], g = p[1], b = p[2];
            if (b > r + 50 && b > g + 30) {
                c.skull++;
                c.skull_y += y;
            } else if (r > g + 70 && r > b + 70) {
                c.jaw++;
                c.jaw_y += y;
            } else if (g > r + 50 && g > b + 50 && r > 8) {
                c.soft++;
            }
            if (diff(p, (const unsigned char[]){0, 230, 255}) < 6) {
                c.hinge++;
                c.hinge_x += x;
                c.hinge_y += y;
            }
            c.landmark += r >= 250 && g >= 250 && b >= 250;
        }
    if (c.skull) c.skull_y /= c.skull;
    if (c.jaw) c.jaw_y /= c.jaw;
    if (c.hinge) c.hinge_x /= c.hinge, c.hinge_y /= c.hinge;
    print_message("rig colours: skull %d (mean row %.1f), jaw %d (mean row %.1f), soft %d, hinge %d "
                  "(mean %.1f, %.1f), landmarks %d\n", c.skull, c.skull_y, c.jaw, c.jaw_y, c.soft,
                  c.hinge, c.hinge_x, c.hinge_y, c.landmark);
    return c;
}

/* G shows the rig (issue 11): regions coloured (skull above the jaw), the hinge axis across
 * the head between them, the landmarks; J opens the jaw (its colour moves down), K closes it
 * again (the same image), G again hides it all (the plain face again). */
static void test_rig_overlay_and_jaw_keys(void **state)
{
    (void)state;
    assert_int_equal(live("--frames 100 --script 'key H; key Tab; wait frames 1; shot %s/off.png; "
                          "key G; wait frames 1; shot %s/on.png; key J; key J; key J; key J; key J; "
                          "wait frames 1; shot %s/open.png; key K; key K; key K; key K; key K; "
                          "wait frames 1; shot %s/closed.png; key G; wait frames 1; shot %s/off2.png; "
                          "close'", tmp, tmp, tmp, tmp, tmp), 0);
    image off = load("off.png"), on = load("on.png"), open = load("open.png"), closed = load("closed.png"),
          off2 = load("off2.png");
    rig_pixels a = count_rig(&off), b = count_rig(&on), o = count_rig(&open);
    /* off: none of the overlay's colours on the skin */
    assert_true(a.skull + a.jaw + a.soft < 10);
    assert_int_equal(a.hinge, 0);
    assert_int_equal(a.landmark, 0);
    /* on: every colour, in place: the cranium above the jaw, the hinge between, centred */
    assert_true(b.skull > 1000);
    assert_true(b.jaw > 100);
    assert_true(b.soft > 3000);
    assert_true(b.hinge > 40);
    assert_true(b.landmark > 40);
    assert_true(b.skull_y + 20 < b.jaw_y);
    assert_true(b.hinge_y > b.skull_y && b.hinge_y < b.jaw_y);
    assert_true(fabs(b.hinge_x - on.w / 2.0) < on.w / 10.0);
    /* J x5: jaw.open 0.5, the chin goes down; K x5 closes it: the image before J again */
    assert_true(o.jaw_y > b.jaw_y + 2);
    int open_changed = 0, closed_off = 0, off_off = 0;
    for (int y = 0; y < on.h; y++)
        for (int x = 0; x < on.w; x++) {
            open_changed += diff(at(&on, x, y), at(&open, x, y)) > 8;
            closed_off += diff(at(&on, x, y), at(&closed, x, y)) > 1;
            off_off += diff(at(&off, x, y), at(&off2, x, y)) > 1;
        }
    print_message("jaw open changed %d pixels; closed again: %d differ; G off again: %d differ\n",
                  open_changed, closed_off, off_off);
    assert_true(open_changed > 200);
    assert_int_equal(closed_off, 0);
    assert_int_equal(off_off, 0);
    free(off.px);
    free(on.px);
    free(open.px);
    free(closed.px);
    free(off2.px);
}

static void write_recording(void)
{
    /* Leap joints CSV, one right hand: pose A on the left cheek (x about 40 mm), pose B 35 mm
     * up and 35 mm toward the performer, 1.5 s later. Fingers point at the face (-z). The
     * tests replay it with timeout=0: the hand holds pose A between the two samples (with the
     * default 1 s it would be a hand the tracker lost, gone before pose B). */
    snprintf(rec, sizeof rec, "%s/two-poses_joints_mm.csv", tmp);
    FILE *f = fopen(rec, "w");
    assert_non_null(f);
    fputs("frame,timestamp_us,hand_id,hand_type,palm_x,palm_y,palm_z,palm_nx,palm_ny,palm_nz,"
          "dir_x,dir_y,dir_z", f);
    const char *fingers[] = {"thumb", "index", "middle", "ring", "pinky"};
    const char *joints[] = {"mcp", "pip", "dip", "tip"};
    for (int fi = 0; fi < 5; fi++)
        for (int j = 0; j < 4; j++) fprintf(f, ",%s_%s_x,%s_%s_y,%s_%s_z", fingers[fi], joints[j],
                                             fingers[fi], joints[j], fingers[fi], joints[j]);
    fputs("\n", f);
    for (int row = 0; row < 2; row++) {
        double dy = row ? 35 : 0, dz = row ? 35 : 0;
        fprintf(f, "%d,%d,7,right,40,%.1f,%.1f,0,-1,0,0,0,-1", row, row ? 1500000 : 0, 200 + dy, -40 + dz);
        for (int fi = 0; fi < 5; fi++) {
            double x = 22 + 9 * fi, y = (fi ? 212 : 200) + dy;
            double z[4] = {-70, -88, -102, -112};
            for (int j = 0; j < 4; j++) fprintf(f, ",%.1f,%.1f,%.1f", x, y, z[j] + dz);
        }
        fputs("\n", f);
    }
    fclose(f);
}

static int setup(void **state)
{
    (void)state;
    const char *build = getenv("FP_BUILD_DIR");
    snprintf(bin, sizeof bin, "%s/bin/facepuppet", build ? build : "build");
    const char *data = getenv("FP_SHARED_DATA");
    snprintf(face, sizeof face, "%s/faces/ict-facekit/generic_neutral_mesh.obj",
             data ? data : "../shared/data");
    snprintf(tmp, sizeof tmp, "/tmp/fp-test-viewer-XXXXXX");
    if (!mkdtemp(tmp)) return -1;
    write_recording();
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
        cmocka_unit_test(test_screenshot_shows_face),
        cmocka_unit_test(test_deform_commit_undo),
        cmocka_unit_test(test_partial_upload_same_pixels),
        cmocka_unit_test(test_partial_upload_rig),
        cmocka_unit_test(test_hud_follows_undo_reset_drop),
        cmocka_unit_test(test_close_button_and_esc),
        cmocka_unit_test(test_drop_mesh_and_mapping_keys),
        cmocka_unit_test(test_command_line_errors),
        cmocka_unit_test(test_take_rec_timeline_scrub),
        cmocka_unit_test(test_take_label_clear_of_hud),
        cmocka_unit_test(test_rig_overlay_and_jaw_keys),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
