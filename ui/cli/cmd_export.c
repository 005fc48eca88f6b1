/* facepuppet export: a take's frames (reproduced from its stored control sets, as play does:
 * fp_take_player) out as glTF/GLB morph-target animation, PC2 or MDD point caches, or one
 * mesh file per frame (core/export, docs/export.md). */
#define _GNU_SOURCE
#include "app_getopt.h"
#include "app_export.h"
#include "app_audio.h"
#include "app_util.h"
#include "command.h"
#include "fp_take_player.h"
#include "fp_stack_player.h"
#include "app_stack.h"
#include "fp_error.h"
#ifdef FP_HAVE_UI
#include "fp_frame_render.h"
#endif

#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* SIGINT or SIGTERM since the export began (0: none). The walk stops at the next frame or
 * sample, the exporter is aborted (its temporary file removed) and the status is 128 + the
 * signal, as `run` ends (130, 143). */
static volatile sig_atomic_t stop_signal;

static void on_stop_signal(int sig)
{
    if (!stop_signal) stop_signal = sig;
}

/* Catch SIGINT and SIGTERM (old: the actions to restore), or give them back. */
static void stop_signals(bool on, struct sigaction old[2])
{
    static const int sigs[2] = {SIGINT, SIGTERM};
    if (!on) {
        for (int i = 0; i < 2; i++) sigaction(sigs[i], &old[i], NULL);
        return;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART; /* (a write in progress finishes; the walk looks after it) */
    stop_signal = 0;
    for (int i = 0; i < 2; i++) sigaction(sigs[i], &sa, &old[i]);
}

/* The walk saw a signal: said, and its status (128 + the signal). */
static int stopped(bool bar)
{
    const int sig = stop_signal;
    fprintf(stderr, "%sfacepuppet export: %s: stopped; the output not written (its temporary file "
            "removed; obj-seq and png-seq keep the frames already written)\n",
            bar ? "\n" : "", sig == SIGINT ? "SIGINT" : "SIGTERM");
    return 128 + sig;
}

/* Where frames go: an exporter (core/export), or PNG files rendered headless (png-seq). */
typedef struct sink {
    fp_exporter *x;
#ifdef FP_HAVE_UI
    fp_frame_renderer *png;
#endif
    const char *dir, *stem;
    uint64_t frames, bytes;
    double last_t;       /* the last frame's time, seconds from the first */
} sink;

static int sink_add(sink *k, const float *pos, double t, char *err, size_t errlen)
{
    k->last_t = t;
    if (k->x)
        return fp_export_add(k->x, pos, t, err, errlen);
#ifdef FP_HAVE_UI
    char file[4400];
    snprintf(file, sizeof file, "%s/%s_%06llu.png", k->dir, k->stem, (unsigned long long)k->frames);
    int rc = fp_frame_renderer_png(k->png, pos, file, err, errlen);
    if (rc)
        return rc;
    struct stat st;
    if (stat(file, &st) == 0)
        k->bytes += (uint64_t)st.st_size;
    k->frames++;
    return 0;
#else
    (void)pos; (void)t;
    return fp_errorf(err, errlen, -ENOTSUP, "png-seq needs the viewer (FP_BUILD_UI)");
#endif
}

static uint64_t sink_frames(const sink *k)
{
    return k->x ? fp_export_frames(k->x) : k->frames;
}

static void usage(FILE *f)
{
    fprintf(f,
        "usage: facepuppet export TAKE|STACK --format gltf|glb|pc2|mdd|obj-seq|png-seq [--out PATH]\n"
        "                         [--range IN-OUT] [--resample F] [--max-error MM] [--mesh FILE]\n"
        "                         [--size WxH] [--camera YAW,PITCH[,ZOOM]] [--force]\n\n"
        "Play a take's frames from the control sets it stored (as `play`: bit-identical to the\n"
        "recording; a STACK, .fpstack: its layers composed as `play` does) and write them\n"
        "for an animator's tools:\n"
        "  gltf, glb   glTF 2.0: the mesh with its UVs and materials, K morph targets and one\n"
        "              animation whose weights channel has a key at every frame (Blender,\n"
        "              Unreal, Unity). K is the fewest principal components of the frames'\n"
        "              displacements that keep every vertex of every frame within --max-error.\n"
        "              In metres: a root node scales the mesh by mm per unit / 1000; the rate\n"
        "              is named in asset.extras.frameRate.\n"
        "  pc2, mdd    point caches: every frame's positions exactly (float32, mesh units), in\n"
        "              the mesh's vertex order (Blender's Mesh Cache modifier, Maya, 3ds Max).\n"
        "              MDD stores each frame's time; PC2 no rate: play it in a scene at the\n"
        "              take's (the README's Blender recipe)\n"
        "  obj-seq     one mesh per frame in a folder, written back as the input came in\n"
        "              (quads, UV seams, groups, materials kept)\n"
        "  png-seq     one PNG per frame, drawn as the live viewer draws the face, headless\n"
        "              (needs a display: xvfb-run on a server)\n"
        "The summary line names the frame rate (the take's, or --resample) and the mesh's unit\n"
        "(the glTF's root scale, the caches' scale to metres). A point cache's or an OBJ\n"
        "sequence's size is reckoned before any frame, from the frames' stored times (with\n"
        "--resample, their first-to-last time): said over 1 GiB, and refused (73) where the\n"
        "folder it goes to has less room free; a glTF's frames over 46340 are refused (64),\n"
        "and it stops as soon as the frames show its morph targets will not fit in memory\n"
        "(70, docs/export.md). Frame times that do not increase are a damaged\n"
        "take (65). SIGINT or SIGTERM stops the export at the next frame: its temporary file\n"
        "is removed (an output that existed is left as it was) and the status is 128 + the\n"
        "signal (130, 143). One that comes after the last frame, while the output is being\n"
        "finished (a glTF's morph targets, the write), lets it finish: the output is written\n"
        "whole, \"stopped after the output was written whole\" is said, and the status is\n"
        "still 128 + the signal.\n\n"
        "  -f, --format F        the format (required)\n"
        "  -o, --out PATH        the file (a folder for obj-seq); default: the take's path with\n"
        "                        the format's extension (obj-seq: TAKE_frames/)\n"
        "      --range IN-OUT    only these frames: 0-based frame indices of the take or\n"
        "                        timecodes HH:MM:SS:FF (a drop-frame take's HH:MM:SS;FF; either\n"
        "                        side may be left out: 120-, -300); frames before IN are still\n"
        "                        played (commits carry over). A take across midnight: a\n"
        "                        timecode after it counts on into the next day. Checked\n"
        "                        before any frame is played: IN past the take's last frame, OUT\n"
        "                        before its first or IN after OUT is refused (64, naming the\n"
        "                        take's frames and timecodes); an end past the take is clipped\n"
        "                        to it with a warning\n"
        "      --resample F      resample to F frames per second (each sample shows the latest\n"
        "                        frame at its time); default: every frame at its own time\n"
        "                        (--fps F: the same, its older name; run's --fps is the session rate)\n"
        "      --max-error MM    glTF: the largest error allowed, millimetres (default 0.1);\n"
        "                        mm per mesh unit from the take's calibration, else the rig's\n"
        "                        or the head's\n"
        "      --max-targets K   glTF: at most K morph targets (the error is then what it is)\n"
        "      --step            glTF: STEP interpolation between keys (default LINEAR)\n"
        "      --size WxH        png-seq: the picture's size in pixels (default 1280x720)\n"
        "      --camera Y,P[,Z]  png-seq: turn the framed view by yaw Y and pitch P degrees,\n"
        "                        zoom Z (default 0,0,1: the face from the front)\n"
        "      --force           overwrite an output that exists (the file; obj-seq and\n"
        "                        png-seq: the frames in the folder, and once the new ones are\n"
        "                        written an earlier export's frames numbered past them are\n"
        "                        removed); without it the export is\n"
        "                        refused before any work (73); an output that is the take,\n"
        "                        a stack's take, the mesh or the soundtrack is refused even so\n"
        "  -m, --mesh FILE       the take's mesh from another path (its crc32 must match)\n"
        "  -P, --plugin-dir DIR  look for plugins in DIR too, after the built-in folder\n"
        "  -q, --quiet           no progress and no summary, nor the engine's and contact\n"
        "                        guard's notes on each gesture; errors and a damaged take's\n"
        "                        warning still print\n"
        "  -h, --help            this text\n\n"
        "Exit status: 0 done, 64 usage, 65 a damaged take or another mesh, 66 missing,\n"
        "66 no display for png-seq, 69 png-seq in a build without the viewer, 73 an output not written\n"
        "or existing without --force, 130/143 stopped by SIGINT/SIGTERM (facepuppet --help has the\n"
        "whole table).\n");
}

/* One end of --range: "" (open), a frame index, or a timecode. */
typedef struct range_end {
    bool set, timecode;
    bool drop;               /* a timecode written HH:MM:SS;FF (drop-frame counting) */
    uint64_t value;          /* index, or frames since 00:00:00:00 */
} range_end;

static int parse_end(const char *s, fp_take_rate rate, range_end *e, char *err, size_t n)
{
    memset(e, 0, sizeof *e);
    if (!*s)
        return 0;
    e->set = true;
    if (strchr(s, ':') || strchr(s, ';')) {
        fp_timecode tc;
        if (fp_timecode_parse(s, rate, &tc, err, n))
            return -EINVAL;
        e->timecode = true;
        e->drop = tc.drop;
        return fp_timecode_to_frames(&tc, rate, &e->value) ? -EINVAL : 0;
    }
    unsigned long long v;
    if (!fp_parse_whole(s, UINT64_MAX, &v)) { /* (digits: no blank, no '-' wrapped round) */
        snprintf(err, n, "'%s' is neither a frame index nor a timecode HH:MM:SS:FF", s);
        return -EINVAL;
    }
    e->value = v;
    return 0;
}

/* Where frame `index` (time t_ns) lies against a range end: its index, or its timecode's
 * frame count (timecode in + the take's frames since the time origin). */
static uint64_t position(const range_end *e, size_t index, int64_t t_ns,
                         const fp_take_header *h, uint64_t tc_in)
{
    if (!e->timecode)
        return index;
    return tc_in + fp_take_frames_at(t_ns - h->time_origin_ns, h->rate);
}

static void progress(bool on, size_t done, size_t total, uint64_t written)
{
    if (!on || total == 0)
        return;
    const int width = 40;
    int fill = (int)((double)done / (double)total * width);
    char bar[64];
    for (int i = 0; i < width; i++)
        bar[i] = i < fill ? '#' : '.';
    bar[width] = '\0';
    fprintf(stderr, "\r  [%s] %3d%%  frame %zu/%zu, %llu exported", bar,
            (int)(100.0 * (double)done / (double)total), done, total,
            (unsigned long long)written);
    if (done == total)
        fputc('\n', stderr);
    fflush(stderr);
}

/* What the command line asked for (export_parse). */
typedef struct export_args {
    const char *format, *out, *range, *mesh, *take_path, *dirs[8];
    size_t ndirs;
    double fps, max_error;
    int max_targets, step;
    bool quiet;
    bool force;                    /* --force: an output that exists is overwritten */
    int width, height;             /* png-seq */
    double yaw, pitch, zoom;       /* png-seq */
    bool png;                      /* --format png-seq (no exporter: fmt unused) */
    fp_export_format fmt;
} export_args;

/* Parse the command line into *a. Returns -1 to go on, or the exit status (0 after --help). */
static int export_parse(int argc, char **argv, export_args *a)
{
    enum { OPT_RANGE = 0x200, OPT_FPS, OPT_MAX_ERROR, OPT_MAX_TARGETS, OPT_STEP, OPT_PLUGIN_DIR,
           OPT_SIZE, OPT_CAMERA, OPT_FORCE };
    static const struct option opts[] = {
        {"format", required_argument, 0, 'f'},   {"out", required_argument, 0, 'o'},
        {"range", required_argument, 0, OPT_RANGE}, {"resample", required_argument, 0, OPT_FPS}, {"fps", required_argument, 0, OPT_FPS},
        {"max-error", required_argument, 0, OPT_MAX_ERROR},
        {"max-targets", required_argument, 0, OPT_MAX_TARGETS},
        {"step", no_argument, 0, OPT_STEP},      {"mesh", required_argument, 0, 'm'},
        {"plugin-dir", required_argument, 0, 'P'},
        {"quiet", no_argument, 0, 'q'},          {"help", no_argument, 0, 'h'},
        {"size", required_argument, 0, OPT_SIZE}, {"camera", required_argument, 0, OPT_CAMERA},
        {"force", no_argument, 0, OPT_FORCE},
        {0, 0, 0, 0}};
    *a = (export_args){.width = 1280, .height = 720, .zoom = 1, .max_error = 0.1,
                       .fmt = FP_EXPORT_OBJ_SEQ};
    unsigned long long whole; /* an integer option (fp_parse_whole) */
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, "f:o:m:P:qh", opts)) != -1;) {
        switch (c) {
        case 'f': a->format = optarg; break;
        case 'o': a->out = optarg; break;
        case OPT_RANGE: a->range = optarg; break;
        case OPT_FPS:
            if (!fp_parse_decimal(optarg, &a->fps) || !(a->fps > 0 && a->fps <= 10000)) {
                fprintf(stderr, "facepuppet export: --resample must be in (0, 10000] frames per second, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_MAX_ERROR:
            if (!fp_parse_decimal(optarg, &a->max_error) || !(a->max_error > 0)) {
                fprintf(stderr, "facepuppet export: --max-error must be > 0 mm, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_MAX_TARGETS:
            if (!fp_parse_whole(optarg, INT_MAX, &whole) || whole < 1) {
                fprintf(stderr, "facepuppet export: --max-targets must be a whole number from 1 to 2147483647, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            a->max_targets = (int)whole;
            break;
        case OPT_STEP: a->step = 1; break;
        case OPT_SIZE:
            /* (and nothing after: "1280x720x3" was read as 1280x720) */
            if (!fp_app_parse_size(optarg, 16, 8192, &a->width, &a->height)) {
                fprintf(stderr, "facepuppet export: --size WxH, 16..8192 each, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_CAMERA: {
            double v[3] = {0, 0, 1};
            const size_t k = fp_parse_decimal_list(optarg, ',', v, 3);
            a->yaw = v[0], a->pitch = v[1], a->zoom = v[2];
            if (k < 2 || !(a->zoom > 0 && a->zoom < 1000)) {
                fprintf(stderr, "facepuppet export: --camera YAW,PITCH[,ZOOM] in degrees (zoom > 0), "
                        "got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        }
        case 'm': a->mesh = optarg; break;
        case 'P':
            if (a->ndirs < 8) a->dirs[a->ndirs++] = optarg;
            break;
        case 'q': a->quiet = true; break;
        case OPT_FORCE: a->force = true; break;
        case 'h': usage(stdout); return FP_EXIT_OK;
        default: usage(stderr); return FP_EXIT_USAGE;
        }
    }
    if (argc - optind != 1) {
        fprintf(stderr, "facepuppet export: give one TAKE or STACK file (see --help)\n");
        return FP_EXIT_USAGE;
    }
    a->take_path = argv[optind];
    if (a->out && !*a->out) {   /* (said "export: no mesh, options or output path") */
        fprintf(stderr, "facepuppet export: --out: give a file or folder name (it is empty)\n");
        return FP_EXIT_USAGE;
    }
    if (!a->format) {
        fprintf(stderr, "facepuppet export: give --format gltf|glb|pc2|mdd|obj-seq|png-seq\n");
        return FP_EXIT_USAGE;
    }
    a->png = strcmp(a->format, "png-seq") == 0;
#ifndef FP_HAVE_UI
    if (a->png) {
        fprintf(stderr, "facepuppet export: png-seq needs the viewer, and this build has none "
                "(FP_BUILD_UI off)\n");
        return FP_EXIT_UNAVAILABLE;
    }
#endif
    if (!a->png && fp_export_format_parse(a->format, &a->fmt)) {
        fprintf(stderr, "facepuppet export: unknown --format '%s' (gltf, glb, pc2, mdd, obj-seq, "
                "png-seq)\n", a->format);
        return FP_EXIT_USAGE;
    }
    return -1;
}

/* --range IN-OUT into its two ends (either may be open). Returns 0 or FP_EXIT_USAGE (said). */
static int parse_range(const char *range, fp_take_rate rate, range_end *in, range_end *out)
{
    const char *dash = strchr(range, '-');
    char a[64], b[64], err[2048];
    if (!dash || (size_t)(dash - range) >= sizeof a || strlen(dash + 1) >= sizeof b) {
        fprintf(stderr, "facepuppet export: --range '%s': give IN-OUT (frames or "
                "timecodes, either side may be left out)\n", range);
        return FP_EXIT_USAGE;
    }
    snprintf(a, sizeof a, "%.*s", (int)(dash - range), range);
    snprintf(b, sizeof b, "%s", dash + 1);
    if (parse_end(a, rate, in, err, sizeof err) || parse_end(b, rate, out, err, sizeof err)) {
        fprintf(stderr, "facepuppet export: --range '%s': %s\n", range, err);
        return FP_EXIT_USAGE;
    }
    return 0;
}

/* The take's first and last frame on an end's scale: indices 0 .. frames-1, or the timecodes'
 * frame counts of the first and last frame. */
static void take_span(const range_end *e, const fp_take_header *h, const fp_take_summary *sum,
                      size_t frames, uint64_t tc_in, uint64_t *first, uint64_t *last)
{
    *first = e->timecode ? tc_in + fp_take_frames_at(sum->first_time_ns - h->time_origin_ns, h->rate) : 0;
    *last = e->timecode ? tc_in + fp_take_frames_at(sum->last_time_ns - h->time_origin_ns, h->rate)
                        : frames - 1;
}

/* One end in words: "frame 120" or "timecode 00:00:02:00". */
static void end_text(const range_end *e, uint64_t v, fp_take_rate rate, bool drop, char *buf, size_t n)
{
    fp_timecode tc;
    if (e->timecode && !fp_timecode_from_frames(v, rate, drop, &tc)) {
        char t[32];
        fp_timecode_format(&tc, t, sizeof t);
        snprintf(buf, n, "timecode %s", t);
    } else {
        snprintf(buf, n, "frame %llu", (unsigned long long)v);
    }
}

/* A timecode end before the take's first frame (on its scale, tc_in + frames since the time
 * origin, which runs on past 24 h) may be one after midnight: a take from 23:59:58:00 to
 * 00:00:01:22 holds 00:00:00:00 a day on (it was "OUT is before the take's first frame").
 * The end is taken on the day that puts it nearer the take's frames [first, last]. */
static void unwrap_day(range_end *e, uint64_t first, uint64_t last, fp_take_rate rate)
{
    const fp_timecode end_of_day = {23, 59, 59, fp_timecode_base(rate) - 1, e->drop};
    uint64_t day;
    if (!e->set || !e->timecode || e->value >= first || fp_timecode_to_frames(&end_of_day, rate, &day))
        return;
    day++;
    const uint64_t next = e->value + day;
    if ((next <= last ? 0 : next - last) < first - e->value) e->value = next;
}

/* --range against the take, before any frame is played (issue 53): IN past the last frame, OUT
 * before the first, or IN after OUT (both of one kind) is refused (64); an end past the take is
 * clipped to it with a warning naming what is exported. Returns 0 or FP_EXIT_USAGE (said). */
static int check_range(const export_args *a, range_end *in, range_end *out, const fp_take_header *h,
                       const fp_take_summary *sum, size_t frames, uint64_t tc_in)
{
    uint64_t f_in = 0, l_in = 0, f_out = 0, l_out = 0;
    take_span(in, h, sum, frames, tc_in, &f_in, &l_in);
    take_span(out, h, sum, frames, tc_in, &f_out, &l_out);
    char tc0[32], tc1[32], x[48], y[48], have[160];
    fp_timecode_format(&h->timecode_in, tc0, sizeof tc0);
    fp_timecode_format(&sum->timecode_out, tc1, sizeof tc1);
    snprintf(have, sizeof have, "the take has frames 0-%zu, timecodes %s - %s", frames - 1, tc0, tc1);
    const bool drop = h->timecode_in.drop;
    const char *why = NULL;
    /* a timecode counts frames as the take's do: 19:40:44:00 against a drop-frame take
     * (19:40:43;09 - 19:40:46;09) was a non-drop count 2,124 frames on, "past the last frame" */
    if ((in->set && in->timecode && in->drop != drop) || (out->set && out->timecode && out->drop != drop)) {
        fprintf(stderr, "facepuppet export: --range %s: the take's timecodes are %s (%s - %s): "
                "write them HH:MM:SS%sFF\n", a->range, drop ? "drop-frame" : "non-drop", tc0, tc1,
                drop ? ";" : ":");
        return FP_EXIT_USAGE;
    }
    unwrap_day(in, f_in, l_in, h->rate);
    unwrap_day(out, f_out, l_out, h->rate);
    if (in->set && in->value > l_in) why = "IN is past the take's last frame";
    else if (out->set && out->value < f_out) why = "OUT is before the take's first frame";
    else if (in->set && out->set && in->timecode == out->timecode && in->value > out->value)
        why = "IN is after OUT";
    if (why) {
        fprintf(stderr, "facepuppet export: --range %s: %s (%s)\n", a->range, why, have);
        return FP_EXIT_USAGE;
    }
    bool clipped = false;
    if (in->set && in->value < f_in) {
        end_text(in, in->value, h->rate, drop, x, sizeof x);
        end_text(in, f_in, h->rate, drop, y, sizeof y);
        fprintf(stderr, "facepuppet export: warning: --range %s: IN (%s) is before the take's first "
                "frame (%s): clipped to it\n", a->range, x, y);
        in->value = f_in;
        clipped = true;
    }
    if (out->set && out->value > l_out) {
        end_text(out, out->value, h->rate, drop, x, sizeof x);
        end_text(out, l_out, h->rate, drop, y, sizeof y);
        fprintf(stderr, "facepuppet export: warning: --range %s: OUT (%s) is past the take's last "
                "frame (%s): clipped to it\n", a->range, x, y);
        out->value = l_out;
        clipped = true;
    }
    if (clipped && !in->timecode && !out->timecode)
        fprintf(stderr, "facepuppet export: warning: exporting frames %llu-%llu (%llu of the take's "
                "%zu)\n", (unsigned long long)(in->set ? in->value : 0),
                (unsigned long long)(out->set ? out->value : frames - 1),
                (unsigned long long)((out->set ? out->value : frames - 1) - (in->set ? in->value : 0) + 1),
                frames);
    return 0;
}

/* The output, before any frame is played: one of the inputs (the take or stack, a stack's
 * takes, the mesh) is refused, --force or not; a file that exists, or a folder (obj-seq,
 * png-seq) holding frames of this take's name, is refused without --force. Returns 0 or 73
 * (said). */
static int check_out(const export_args *a, fp_take_player *p, const char *out, const char *name)
{
    const char *opt = a->out ? "--out" : "output";
    const char *cmd = "facepuppet export";
    const fp_stack *st = fp_take_player_stack(p) ? fp_stack_player_stack(fp_take_player_stack(p)) : NULL;
    int rc = fp_app_check_not_input(cmd, opt, out, a->take_path, st ? "the stack" : "the take");
    if (!rc) rc = fp_app_check_not_input(cmd, opt, out, fp_take_player_mesh_path(p), "the mesh");
    for (size_t i = 0; !rc && st && i < st->layer_count; i++) {
        char take[4200];
        if (!fp_stack_take_path(st, i, take, sizeof take))
            rc = fp_app_check_not_input(cmd, opt, out, take, "a take of the stack");
    }
    if (rc) return rc;
    if (a->png || a->fmt == FP_EXPORT_OBJ_SEQ) {
        char prefix[128];
        snprintf(prefix, sizeof prefix, "%s_", name);
        return fp_app_check_output_dir("facepuppet export", opt, out, prefix, a->png ? ".png" : "",
                                       false, a->force, NULL);
    }
    return fp_app_check_new_output("facepuppet export", opt, out, a->force);
}

/* --resample: a frame whose time is within this of a sample's is at that sample's time (frame
 * times are stored in whole ns, so a frame exactly on the sample grid can read up to 0.5 ns
 * late; a sample lasts at least 100 us, 1 / 10000 fps). */
#define SAMPLE_SLACK_S 1e-9

/* The frames an export writes, from the frames' stored times (fp_take_reader_time), before
 * any is played: the range's frames (those walk_take hands the sink), or with --resample the
 * samples over their stored first-to-last time (what walk_frame writes: a take whose first
 * frame said -1e18 ns wrote 30 GB unwarned, the estimate having gone by the frame count).
 * Frame times in the range that do not increase are damaged data (65, said: the frames and
 * their times). Returns 0 and *count, or the exit status. */
static int frames_out(const export_args *a, const range_end *in, const range_end *out,
                      const fp_take_header *h, fp_take_reader *r, uint64_t tc_in, double *count)
{
    const size_t frames = fp_take_reader_frames(r);
    size_t first = SIZE_MAX, last = 0;
    *count = 0;
    for (size_t i = 0; i < frames; i++) {
        const int64_t t = fp_take_reader_time(r, i);
        const bool after_in = !in->set || position(in, i, t, h, tc_in) >= in->value;
        const bool before_out = !out->set || position(out, i, t, h, tc_in) <= out->value;
        if (!after_in || !before_out) {
            if (first != SIZE_MAX && out->set) break;   /* past OUT: walk_take stops there */
            continue;
        }
        if (first != SIZE_MAX && t <= fp_take_reader_time(r, last)) {
            fprintf(stderr, "facepuppet export: %s: frame %zu's time (%lld ns) is not after frame "
                    "%zu's (%lld ns): a take's frame times increase (a damaged take)\n",
                    a->take_path, i, (long long)t, last, (long long)fp_take_reader_time(r, last));
            return FP_EXIT_DATAERR;
        }
        if (first == SIZE_MAX) first = i;
        last = i;
    }
    if (first == SIZE_MAX) return 0;
    if (!(a->fps > 0)) {
        *count = (double)(last - first + 1);
        return 0;
    }
    const double span_s = (double)(fp_take_reader_time(r, last) - fp_take_reader_time(r, first)) * 1e-9;
    *count = floor((span_s + SAMPLE_SLACK_S) * a->fps) + 1;   /* as walk_take's samples */
    return 0;
}

/* A point cache's or an OBJ sequence's size, about, before any frame (a --fps of 10000 for 100
 * wrote 10.6 GB of a 3.3 s take unasked): said over FP_APP_FRAMES_WARN_BYTES, and refused (73)
 * when the output's file system has less room free. glTF (its morph targets reduced) and
 * PNG sizes are not known ahead. Returns 0 or FP_EXIT_CANTCREAT (said). */
static int check_size(const export_args *a, const char *out, double frames, const fp_mesh *mesh)
{
    const size_t vertices = mesh->vertex_count;
    const double per_frame = fp_app_export_frame_bytes(a->fmt, mesh);
    if (a->png || !(per_frame > 0)) return 0;
    const double bytes = frames * per_frame;
    return fp_app_output_fits("facepuppet export", out, out, bytes, frames, vertices,
                              "a smaller --resample or --range");
}

/* The output when --out is not given: beside the take, TAKE_png/, TAKE_frames/ (obj-seq) or
 * TAKE.EXT. */
static void default_out(const export_args *a, char *buf, size_t len)
{
    const char *take_path = a->take_path;
    const char *dot = strrchr(take_path, '.'), *slash = strrchr(take_path, '/');
    int stem = dot && (!slash || dot > slash) ? (int)(dot - take_path) : (int)strlen(take_path);
    if (a->png)
        snprintf(buf, len, "%.*s_png", stem, take_path);
    else if (a->fmt == FP_EXPORT_OBJ_SEQ)
        snprintf(buf, len, "%.*s_frames", stem, take_path);
    else
        snprintf(buf, len, "%.*s.%s", stem, take_path, fp_export_format_extension(a->fmt));
}

/* A point cache's name may end in anything but another export format's extension (an MDD
 * written to x.pc2 was read as a PC2 by what goes by the name: `info`, a file browser's
 * filter). After check_out: an output that is an input is refused as that first. Returns 0
 * or FP_EXIT_USAGE (said). */
static int check_cache_name(const char *out, fp_export_format fmt)
{
    fp_export_format named;
    if ((fmt != FP_EXPORT_PC2 && fmt != FP_EXPORT_MDD) || fp_export_format_from_path(out, &named) ||
        named == fmt)
        return 0;
    fprintf(stderr, "facepuppet export: --out %s: the name says %s, not %s: give a name ending .%s "
            "for --format %s\n", out, fp_export_format_name(named), fp_export_format_name(fmt),
            fp_export_format_extension(fmt), fp_export_format_name(fmt));
    return FP_EXIT_USAGE;
}

/* glTF and GLB: the mesh writer goes by the name, so --out must end in the format's
 * extension. Returns 0 or FP_EXIT_USAGE (said). */
static int check_gltf_name(const char *out, fp_export_format fmt)
{
    if (fmt != FP_EXPORT_GLTF && fmt != FP_EXPORT_GLB) return 0;
    const char *dot = strrchr(out, '.'), *slash = strrchr(out, '/');
    if (!dot || (slash && dot < slash) || strcasecmp(dot + 1, fp_export_format_extension(fmt))) {
        fprintf(stderr, "facepuppet export: --out %s: give a name ending .%s for --format %s\n",
                out, fp_export_format_extension(fmt), fp_export_format_extension(fmt));
        return FP_EXIT_USAGE;
    }
    return 0;
}

/* Where the frames go: the exporter (core/export), or for png-seq the folder `out` (made if
 * missing) and a headless renderer. Returns 0 or the exit status (said). */
static int open_sink(sink *k, const export_args *a, const fp_session *s, const char *out,
                     const char *name, double mm_per_unit, double frame_rate, double frames)
{
    char err[2048];
    int rc;
    fp_export_options eo = {.format = a->fmt, .path = out, .max_error_mm = a->max_error,
                            .mm_per_unit = mm_per_unit, .max_targets = a->max_targets,
                            .step = a->step, .name = name, .stem = name,
                            .frame_rate = frame_rate};
    float up[3], facing[3];   /* the take's face axes (its player's session has them) */
    fp_session_face_axes(s, up, facing);
    for (int i = 0; i < 3; i++) eo.up[i] = up[i], eo.facing[i] = facing[i];
    /* a glTF's frames and the memory its finish needs: refused before the frames, or as soon
     * as they show it (before: out of memory after playing the whole take) */
    if ((rc = fp_app_export_gltf_plan("facepuppet export", out, "a smaller --resample or --range",
                                      frames, fp_session_mesh(s), a->quiet, &eo)))
        return rc;
    if (!a->png && (rc = fp_export_begin(fp_session_mesh(s), &eo, &k->x, err, sizeof err))) {
        fprintf(stderr, "facepuppet export: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_OUTPUT);
    }
#ifdef FP_HAVE_UI
    if (a->png) {
        k->dir = out;
        k->stem = name;
        if (mkdir(out, 0777) != 0 && errno != EEXIST) {
            fprintf(stderr, "facepuppet export: %s: %s\n", out, strerror(errno));
            return fp_app_exit_code(-errno, FP_APP_OUTPUT);
        }
        fp_frame_render_options ro = {.width = a->width, .height = a->height, .yaw_deg = a->yaw,
                                      .pitch_deg = a->pitch, .zoom = a->zoom};
        fp_session_face_axes(s, ro.up, ro.forward); /* (a turned face: seen from its front) */
        if ((rc = fp_frame_renderer_open(fp_session_mesh(s), &ro, &k->png, err, sizeof err))) {
            fprintf(stderr, "facepuppet export: %s\n", err);
            return fp_app_exit_code(rc, FP_APP_INPUT);
        }
    }
#endif
    return 0;
}

/* The frames' walk: every frame of the take is played; those in the range go to the sink, at
 * their own times or resampled at --fps (each sample shows the latest frame at its time). */
typedef struct export_walk {
    const export_args *a;
    fp_take_player *p;
    const fp_session *s;
    const fp_take_header *h;
    range_end in, out;             /* --range */
    uint64_t tc_in;                /* the take's timecode in, in frames */
    sink *k;
    float *held;                   /* --fps: the last frame in the range, n x 3 */
    size_t n, total;               /* vertices; the take's frames */
    bool bar;                      /* a progress bar on stderr */
    bool started, have_held;
    int64_t first_ns, held_ns;     /* the first frame in the range; the held one */
    uint64_t sample;               /* --fps: the next sample */
} export_walk;

/* One frame in the range (positions pos, time t_ns) into the sink. Returns 0 or the sink's
 * negative code (message in err). */
static int walk_frame(export_walk *w, const float *pos, int64_t t_ns, char *err, size_t errlen)
{
    if (!w->started) {
        w->started = true;
        w->first_ns = t_ns;
    }
    if (w->a->fps <= 0) return sink_add(w->k, pos, (double)(t_ns - w->first_ns) * 1e-9, err, errlen);
    /* samples before this frame's time show the frame held before it; a sample at the
     * frame's time shows the frame (its time stored to the nearest ns: 10/60 s is 166666667
     * ns, after the sample at 4/24 s, which then showed frame 9) */
    int rc = 0;
    for (double t; w->have_held && !rc && !stop_signal &&
                   (t = (double)w->sample / w->a->fps) + SAMPLE_SLACK_S < (double)(t_ns - w->first_ns) * 1e-9;
         w->sample++)
        rc = sink_add(w->k, w->held, t, err, errlen);
    memcpy(w->held, pos, w->n * 3 * sizeof(float));
    w->held_ns = t_ns;
    w->have_held = true;
    return rc;
}

/* Play the whole take through walk_frame, then (--fps) the held frame's own sample times, up
 * to its time. Returns FP_EXIT_OK or the exit status (said). */
static int walk_take(export_walk *w)
{
    char err[2048];
    int rc = 0;
    size_t index = 0;
    fp_take_frame f;
    double last_bar = -1;
    while (!stop_signal && (rc = fp_take_player_next(w->p, &f, NULL, err, sizeof err)) == 1) {
        const size_t i = index++;
        const bool after_in = !w->in.set || position(&w->in, i, f.time_ns, w->h, w->tc_in) >= w->in.value;
        const bool before_out = !w->out.set || position(&w->out, i, f.time_ns, w->h, w->tc_in) <= w->out.value;
        if (after_in && before_out) {
            if ((rc = walk_frame(w, fp_take_player_positions(w->p), f.time_ns, err, sizeof err))) {
                fprintf(stderr, "%sfacepuppet export: %s\n", w->bar ? "\n" : "", err);
                return fp_app_exit_code(rc, FP_APP_OUTPUT);
            }
        } else if (w->started && w->out.set) {
            break;   /* past OUT */
        }
        if (w->bar && (i + 1 == w->total || (double)i - last_bar >= (double)w->total / 100)) {
            progress(true, i + 1, w->total, sink_frames(w->k));
            last_bar = (double)i;
        }
    }
    if (stop_signal) return stopped(w->bar);
    if (rc < 0) {
        fprintf(stderr, "%sfacepuppet export: %s\n", w->bar ? "\n" : "", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    if (w->bar && index < w->total)
        progress(true, w->total, w->total, sink_frames(w->k));
    if (w->a->fps > 0 && w->have_held) {   /* the held frame's own sample times, up to its time */
        for (double t; (t = (double)w->sample / w->a->fps) <= (double)(w->held_ns - w->first_ns) * 1e-9 + SAMPLE_SLACK_S;
             w->sample++) {
            if (stop_signal) return stopped(false);
            if ((rc = sink_add(w->k, w->held, t, err, sizeof err))) {
                fprintf(stderr, "facepuppet export: %s\n", err);
                return fp_app_exit_code(rc, FP_APP_OUTPUT);
            }
        }
    }
    return stop_signal ? stopped(false) : FP_EXIT_OK;
}

/* A sequence written whole over an earlier one (--force): that one's frames numbered past
 * the new ones are removed (10 frames exported over 113 left 103 of the old take after them,
 * which a sequence importer played on). Returns 0 or 73 (said). */
static int remove_stale(const export_args *a, const fp_mesh *mesh, const char *out, const char *name,
                        uint64_t written)
{
    char prefix[128], first[512], suffix[64] = ".png";
    snprintf(prefix, sizeof prefix, "%s_", name);
    if (!a->png) { /* obj-seq: the mesh's own extension, as core/export names the files */
        const char *dot = mesh->source_path ? strrchr(mesh->source_path, '.') : NULL;
        snprintf(suffix, sizeof suffix, ".%s", dot && !strchr(dot, '/') ? dot + 1 : "obj");
    }
    const long n = fp_app_remove_stale_frames(out, prefix, suffix, written, first, sizeof first);
    if (n < 0) {
        fprintf(stderr, "facepuppet export: %s/%s: an earlier export's frame past the %llu written "
                "could not be removed: %s\n", out, first, (unsigned long long)written,
                strerror((int)-n));
        return FP_EXIT_CANTCREAT;
    }
    if (n > 0 && !a->quiet)
        printf("facepuppet export: removed %ld frame%s of an earlier export from %s (%s%s), "
               "numbered past these\n", n, n == 1 ? "" : "s", out, first, n > 1 ? " ..." : "");
    return 0;
}

/* Export the opened take p as *a asks. Returns the exit status. */
static int export_take(const export_args *a, fp_take_player *p, sink *k, float **held)
{
    int status;
    const fp_take_header *h = fp_take_player_header(p);
    fp_take_reader *r = fp_take_player_reader(p);
    if ((status = fp_app_take_intact("facepuppet export", "export", a->take_path, r))) return status;
    if (fp_take_player_stack(p) && fp_stack_player_warning(fp_take_player_stack(p))[0])
        fprintf(stderr, "facepuppet export: warning: %s\n", fp_stack_player_warning(fp_take_player_stack(p)));
    export_walk w = {.a = a, .p = p, .h = h, .k = k};
    if (a->range && (status = parse_range(a->range, h->rate, &w.in, &w.out))) return status;
    fp_timecode_to_frames(&h->timecode_in, h->rate, &w.tc_in);
    if (a->range && (status = check_range(a, &w.in, &w.out, h, fp_take_reader_summary(r),
                                          fp_take_reader_frames(r), w.tc_in)))
        return status;
    char def_out[4200];
    const char *out = a->out;
    if (!out) { /* the output: given, or beside the take */
        default_out(a, def_out, sizeof def_out);
        out = def_out;
    }
    if ((status = check_gltf_name(out, a->fmt))) return status;
    const double mm_per_unit = fp_take_player_mm_per_unit(p);
    fp_session *s = fp_take_player_session(p);
    char name[96];
    fp_app_export_name(a->take_path, fp_take_player_stack(p) != NULL, h->slate, h->take, name,
                       sizeof name);
    /* the output's rate: --fps, else the take's (named in the file and the summary) */
    const double rate = a->fps > 0 ? a->fps
                        : h->rate.den ? (double)h->rate.num / (double)h->rate.den : 0;
    if ((status = check_out(a, p, out, name)) || (status = check_cache_name(out, a->fmt)))
        return status;
    double count;
    if ((status = frames_out(a, &w.in, &w.out, h, r, w.tc_in, &count)) ||
        (status = check_size(a, out, count, fp_session_mesh(s))))
        return status;
    char wav[4400]; /* the soundtrack under the frames, beside them (NAME.wav) */
    if ((status = fp_app_audio_export_check(h, out, a->force, wav, sizeof wav, "export"))) return status;
    if ((status = open_sink(k, a, s, out, name, mm_per_unit, rate, count))) return status;
    w.s = s;
    w.n = fp_session_vertex_count(s);
    w.total = fp_take_reader_frames(r);
    w.bar = !a->quiet && isatty(STDERR_FILENO);
    w.held = *held = malloc(w.n * 3 * sizeof(float));
    if (!w.held) {
        fprintf(stderr, "facepuppet export: out of memory\n");
        return FP_EXIT_SOFTWARE;
    }
    if ((status = walk_take(&w))) return status;
    if (!w.started) {
        fprintf(stderr, "facepuppet export: %s%s%sholds none of the take's %zu frames\n",
                a->range ? "--range " : "the take ", a->range ? a->range : "", a->range ? " " : "",
                w.total);
        return FP_EXIT_USAGE;
    }
    const uint64_t written = sink_frames(k);
    if (a->png) {
        if (!a->quiet)
            printf("facepuppet export: wrote %llu PNG frames (%dx%d) to %s: %.2f MB\n",
                   (unsigned long long)k->frames, a->width, a->height, out, (double)k->bytes / 1e6);
    } else if ((status = fp_app_export_close("facepuppet export", NULL, &k->x, a->fmt, out, a->max_error,
                                             a->quiet, stdout))) {
        return status;
    }
    if ((a->png || a->fmt == FP_EXPORT_OBJ_SEQ) && a->force &&
        (status = remove_stale(a, fp_session_mesh(s), out, name, written)))
        return status;
    fp_app_stack_limited_note("export", a->take_path, fp_take_player_stack(p), a->quiet);
    return fp_app_audio_export_write(h, wav, w.first_ns, k->last_t + (rate > 0 ? 1.0 / rate : 0), a->force,
                                     a->quiet, stdout, "export");
}

static int export_main(int argc, char **argv)
{
    export_args a;
    int status = export_parse(argc, argv, &a);
    if (status >= 0) return status;
    char err[2048];
    fp_plugin_path path;
    fp_app_plugin_path(&path, a.dirs, a.ndirs);
    fp_take_player *p = NULL;
    int rc = fp_take_player_open_logged(a.take_path, a.mesh, &path,
                                        a.quiet ? fp_app_log_line_warnings : fp_app_log_line, NULL, &p,
                                        err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet export: %s\n", err);
        fp_plugin_path_clear(&path);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    sink k = {0};
    float *held = NULL;
    struct sigaction old[2];
    stop_signals(true, old);
    status = export_take(&a, p, &k, &held);
    fp_export_abort(&k.x);
    if (stop_signal && status == FP_EXIT_OK) { /* it came while the output was being finished */
        fprintf(stderr, "facepuppet export: %s: stopped after the output was written whole\n",
                stop_signal == SIGINT ? "SIGINT" : "SIGTERM");
        status = 128 + stop_signal;
    }
    stop_signals(false, old);
#ifdef FP_HAVE_UI
    fp_frame_renderer_close(&k.png);
#endif
    free(held);
    fp_take_player_close(&p);
    fp_plugin_path_clear(&path);
    return status;
}

const fp_command fp_command_export = {"export", "a take out as glTF animation, point caches "
                                      "or mesh files", export_main};
