/* facepuppet export: a take's frames (reproduced from its stored control sets, as play does:
 * fp_take_player) out as glTF/GLB morph-target animation, PC2 or MDD point caches, or one
 * mesh file per frame (core/export, docs/export.md). */
#define _GNU_SOURCE
#include "app_export.h"
#include "app_util.h"
#include "command.h"
#include "fp_take_player.h"
#include "fp_error.h"
#ifdef FP_HAVE_UI
#include "fp_frame_render.h"
#endif

#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* Where frames go: an exporter (core/export), or PNG files rendered headless (png-seq). */
typedef struct sink {
    fp_exporter *x;
#ifdef FP_HAVE_UI
    fp_frame_renderer *png;
#endif
    const char *dir, *stem;
    uint64_t frames, bytes;
} sink;

static int sink_add(sink *k, const float *pos, double t, char *err, size_t errlen)
{
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
        "usage: facepuppet export TAKE --format gltf|glb|pc2|mdd|obj-seq|png-seq [--out PATH]\n"
        "                         [--range IN-OUT] [--fps F] [--max-error MM] [--mesh FILE]\n"
        "                         [--size WxH] [--camera YAW,PITCH[,ZOOM]]\n\n"
        "Play a take's frames from the control sets it stored (as `play`: bit-identical to the\n"
        "recording) and write them for an animator's tools:\n"
        "  gltf, glb   glTF 2.0: the mesh with its UVs and materials, K morph targets and one\n"
        "              animation whose weights channel has a key at every frame (Blender,\n"
        "              Unreal, Unity). K is the fewest principal components of the frames'\n"
        "              displacements that keep every vertex of every frame within --max-error.\n"
        "  pc2, mdd    point caches: every frame's positions exactly (float32), in the mesh's\n"
        "              vertex order (Blender's Mesh Cache modifier, Maya, 3ds Max)\n"
        "  obj-seq     one mesh per frame in a folder, written back as the input came in\n"
        "              (quads, UV seams, groups, materials kept)\n"
        "  png-seq     one PNG per frame, drawn as the live viewer draws the face, headless\n"
        "              (needs a display: xvfb-run on a server)\n\n"
        "  -f, --format F        the format (required)\n"
        "  -o, --out PATH        the file (a folder for obj-seq); default: the take's path with\n"
        "                        the format's extension (obj-seq: TAKE_frames/)\n"
        "      --range IN-OUT    only these frames: 0-based frame indices of the take or\n"
        "                        timecodes HH:MM:SS:FF (either side may be left out: 120-, -300);\n"
        "                        frames before IN are still played (commits carry over)\n"
        "      --fps F           resample to F frames per second (each sample shows the latest\n"
        "                        frame at its time); default: every frame at its own time\n"
        "      --max-error MM    glTF: the largest error allowed, millimetres (default 0.1);\n"
        "                        mm per mesh unit from the take's calibration, else the rig's\n"
        "                        or the head's\n"
        "      --max-targets K   glTF: at most K morph targets (the error is then what it is)\n"
        "      --step            glTF: STEP interpolation between keys (default LINEAR)\n"
        "      --size WxH        png-seq: the picture's size in pixels (default 1280x720)\n"
        "      --camera Y,P[,Z]  png-seq: turn the framed view by yaw Y and pitch P degrees,\n"
        "                        zoom Z (default 0,0,1: the face from the front)\n"
        "  -m, --mesh FILE       the take's mesh from another path (its crc32 must match)\n"
        "      --plugin-dir DIR  look for plugins in DIR first\n"
        "  -q, --quiet           no progress and no summary, nor the engine's and contact\n"
        "                        guard's notes on each gesture; errors and a damaged take's\n"
        "                        warning still print\n"
        "  -h, --help            this text\n\n"
        "Exit status: 0 done, 64 usage, 65 a damaged take or another mesh, 66 missing,\n"
        "66 no display for png-seq, 69 png-seq in a build without the viewer, 73 an output not written (facepuppet --help has the whole table).\n");
}

/* One end of --range: "" (open), a frame index, or a timecode. */
typedef struct range_end {
    bool set, timecode;
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
    return tc_in + fp_take_frames_in(t_ns - h->time_origin_ns, h->rate);
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

static int export_main(int argc, char **argv)
{
    enum { OPT_RANGE = 0x200, OPT_FPS, OPT_MAX_ERROR, OPT_MAX_TARGETS, OPT_STEP, OPT_PLUGIN_DIR,
           OPT_SIZE, OPT_CAMERA };
    static const struct option opts[] = {
        {"format", required_argument, 0, 'f'},   {"out", required_argument, 0, 'o'},
        {"range", required_argument, 0, OPT_RANGE}, {"fps", required_argument, 0, OPT_FPS},
        {"max-error", required_argument, 0, OPT_MAX_ERROR},
        {"max-targets", required_argument, 0, OPT_MAX_TARGETS},
        {"step", no_argument, 0, OPT_STEP},      {"mesh", required_argument, 0, 'm'},
        {"plugin-dir", required_argument, 0, OPT_PLUGIN_DIR},
        {"quiet", no_argument, 0, 'q'},          {"help", no_argument, 0, 'h'},
        {"size", required_argument, 0, OPT_SIZE}, {"camera", required_argument, 0, OPT_CAMERA},
        {0, 0, 0, 0}};
    int width = 1280, height = 720;
    double yaw = 0, pitch = 0, zoom = 1;
    const char *format = NULL, *out = NULL, *range = NULL, *mesh = NULL, *dirs[8];
    size_t ndirs = 0;
    double fps = 0, max_error = 0.1;
    int max_targets = 0, step = 0;
    bool quiet = false;
    unsigned long long whole; /* an integer option (fp_parse_whole) */
    optind = 1;
    for (int c; (c = getopt_long(argc, argv, "f:o:m:qh", opts, NULL)) != -1;) {
        switch (c) {
        case 'f': format = optarg; break;
        case 'o': out = optarg; break;
        case OPT_RANGE: range = optarg; break;
        case OPT_FPS:
            if (!fp_parse_decimal(optarg, &fps) || !(fps > 0 && fps <= 10000)) {
                fprintf(stderr, "facepuppet export: --fps must be in (0, 10000], got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_MAX_ERROR:
            if (!fp_parse_decimal(optarg, &max_error) || !(max_error > 0)) {
                fprintf(stderr, "facepuppet export: --max-error must be > 0 mm, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_MAX_TARGETS:
            if (!fp_parse_whole(optarg, INT_MAX, &whole) || whole < 1) {
                fprintf(stderr, "facepuppet export: --max-targets must be a whole number from 1 to 2147483647, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            max_targets = (int)whole;
            break;
        case OPT_STEP: step = 1; break;
        case OPT_SIZE:
            /* (and nothing after: "1280x720x3" was read as 1280x720) */
            if (!fp_app_parse_size(optarg, 16, 8192, &width, &height)) {
                fprintf(stderr, "facepuppet export: --size WxH, 16..8192 each, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_CAMERA: {
            double v[3] = {0, 0, 1};
            const size_t k = fp_parse_decimal_list(optarg, ',', v, 3);
            yaw = v[0], pitch = v[1], zoom = v[2];
            if (k < 2 || !(zoom > 0 && zoom < 1000)) {
                fprintf(stderr, "facepuppet export: --camera YAW,PITCH[,ZOOM] in degrees (zoom > 0), "
                        "got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        }
        case 'm': mesh = optarg; break;
        case OPT_PLUGIN_DIR:
            if (ndirs < 8) dirs[ndirs++] = optarg;
            break;
        case 'q': quiet = true; break;
        case 'h': usage(stdout); return FP_EXIT_OK;
        default: usage(stderr); return FP_EXIT_USAGE;
        }
    }
    if (argc - optind != 1) {
        fprintf(stderr, "facepuppet export: give one TAKE file (see --help)\n");
        return FP_EXIT_USAGE;
    }
    if (!format) {
        fprintf(stderr, "facepuppet export: give --format gltf|glb|pc2|mdd|obj-seq|png-seq\n");
        return FP_EXIT_USAGE;
    }
    const bool png = strcmp(format, "png-seq") == 0;
#ifndef FP_HAVE_UI
    if (png) {
        fprintf(stderr, "facepuppet export: png-seq needs the viewer, and this build has none "
                "(FP_BUILD_UI off)\n");
        return FP_EXIT_UNAVAILABLE;
    }
#endif
    fp_export_format fmt = FP_EXPORT_OBJ_SEQ;
    if (!png && fp_export_format_parse(format, &fmt)) {
        fprintf(stderr, "facepuppet export: unknown --format '%s' (gltf, glb, pc2, mdd, obj-seq, "
                "png-seq)\n", format);
        return FP_EXIT_USAGE;
    }
    const char *take_path = argv[optind];
    char err[2048];
    fp_plugin_path path;
    fp_app_plugin_path(&path, dirs, ndirs);
    fp_take_player *p = NULL;
    int rc = fp_take_player_open_logged(take_path, mesh, &path,
                                        quiet ? fp_app_log_line_quiet : fp_app_log_line, NULL, &p,
                                        err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet export: %s\n", err);
        fp_plugin_path_clear(&path);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    int status = FP_EXIT_OK;
    sink k = {0};
    float *held = NULL;
    const fp_take_header *h = fp_take_player_header(p);
    fp_take_reader *r = fp_take_player_reader(p);
    if ((status = fp_app_take_intact("facepuppet export", "export", take_path, r))) goto done;
    range_end in = {0}, outr = {0};
    if (range) {
        const char *dash = strchr(range, '-');
        char a[64], b[64];
        if (!dash || (size_t)(dash - range) >= sizeof a || strlen(dash + 1) >= sizeof b) {
            fprintf(stderr, "facepuppet export: --range '%s': give IN-OUT (frames or "
                    "timecodes, either side may be left out)\n", range);
            status = FP_EXIT_USAGE;
            goto done;
        }
        snprintf(a, sizeof a, "%.*s", (int)(dash - range), range);
        snprintf(b, sizeof b, "%s", dash + 1);
        if (parse_end(a, h->rate, &in, err, sizeof err) ||
            parse_end(b, h->rate, &outr, err, sizeof err)) {
            fprintf(stderr, "facepuppet export: --range '%s': %s\n", range, err);
            status = FP_EXIT_USAGE;
            goto done;
        }
    }
    uint64_t tc_in = 0;
    fp_timecode_to_frames(&h->timecode_in, h->rate, &tc_in);
    /* the output: given, or beside the take */
    char def_out[4200];
    if (!out) {
        const char *dot = strrchr(take_path, '.'), *slash = strrchr(take_path, '/');
        int stem = dot && (!slash || dot > slash) ? (int)(dot - take_path) : (int)strlen(take_path);
        if (png)
            snprintf(def_out, sizeof def_out, "%.*s_png", stem, take_path);
        else if (fmt == FP_EXPORT_OBJ_SEQ)
            snprintf(def_out, sizeof def_out, "%.*s_frames", stem, take_path);
        else
            snprintf(def_out, sizeof def_out, "%.*s.%s", stem, take_path,
                     fp_export_format_extension(fmt));
        out = def_out;
    }
    if (fmt == FP_EXPORT_GLTF || fmt == FP_EXPORT_GLB) { /* the mesh writer goes by the name */
        const char *dot = strrchr(out, '.'), *slash = strrchr(out, '/');
        if (!dot || (slash && dot < slash) || strcasecmp(dot + 1, fp_export_format_extension(fmt))) {
            fprintf(stderr, "facepuppet export: --out %s: give a name ending .%s for --format %s\n",
                    out, fp_export_format_extension(fmt), fp_export_format_extension(fmt));
            status = FP_EXIT_USAGE;
            goto done;
        }
    }
    const double mm_per_unit = fp_take_player_mm_per_unit(p);
    fp_session *s = fp_take_player_session(p);
    char name[96];
    snprintf(name, sizeof name, "%s_T%03u", h->slate, h->take);
    fp_export_options eo = {.format = fmt, .path = out, .max_error_mm = max_error,
                            .mm_per_unit = mm_per_unit, .max_targets = max_targets,
                            .step = step, .name = name, .stem = name};
    if (!png && (rc = fp_export_begin(fp_session_mesh(s), &eo, &k.x, err, sizeof err))) {
        fprintf(stderr, "facepuppet export: %s\n", err);
        status = fp_app_exit_code(rc, FP_APP_OUTPUT);
        goto done;
    }
#ifdef FP_HAVE_UI
    if (png) {
        k.dir = out;
        k.stem = name;
        if (mkdir(out, 0777) != 0 && errno != EEXIST) {
            fprintf(stderr, "facepuppet export: %s: %s\n", out, strerror(errno));
            status = fp_app_exit_code(-errno, FP_APP_OUTPUT);
            goto done;
        }
        fp_frame_render_options ro = {.width = width, .height = height, .yaw_deg = yaw,
                                      .pitch_deg = pitch, .zoom = zoom};
        if ((rc = fp_frame_renderer_open(fp_session_mesh(s), &ro, &k.png, err, sizeof err))) {
            fprintf(stderr, "facepuppet export: %s\n", err);
            status = fp_app_exit_code(rc, FP_APP_INPUT);
            goto done;
        }
    }
#else
    (void)width; (void)height; (void)yaw; (void)pitch; (void)zoom;
#endif
    const size_t n = fp_session_vertex_count(s), total = fp_take_reader_frames(r);
    const bool bar = !quiet && isatty(STDERR_FILENO);
    held = malloc(n * 3 * sizeof(float));
    if (!held) {
        fprintf(stderr, "facepuppet export: out of memory\n");
        status = FP_EXIT_SOFTWARE;
        goto done;
    }
    /* play every frame; export those in the range, at their own times or resampled */
    int64_t first_ns = 0, held_ns = 0;
    bool started = false, have_held = false;
    uint64_t sample = 0;
    size_t index = 0;
    fp_take_frame f;
    double last_bar = -1;
    while ((rc = fp_take_player_next(p, &f, NULL, err, sizeof err)) == 1) {
        const size_t i = index++;
        const bool after_in = !in.set || position(&in, i, f.time_ns, h, tc_in) >= in.value;
        const bool before_out = !outr.set || position(&outr, i, f.time_ns, h, tc_in) <= outr.value;
        if (after_in && before_out) {
            const float *pos = fp_session_positions(s);
            if (!started) {
                started = true;
                first_ns = f.time_ns;
            }
            if (fps <= 0) {
                rc = sink_add(&k, pos, (double)(f.time_ns - first_ns) * 1e-9, err, sizeof err);
            } else {
                /* samples before this frame's time show the frame held before it */
                rc = 0;
                for (double t; have_held && !rc &&
                               (t = (double)sample / fps) < (double)(f.time_ns - first_ns) * 1e-9;
                     sample++)
                    rc = sink_add(&k, held, t, err, sizeof err);
                memcpy(held, pos, n * 3 * sizeof(float));
                held_ns = f.time_ns;
                have_held = true;
            }
            if (rc) {
                fprintf(stderr, "%sfacepuppet export: %s\n", bar ? "\n" : "", err);
                status = fp_app_exit_code(rc, FP_APP_OUTPUT);
                goto done;
            }
        } else if (started && outr.set) {
            break;   /* past OUT */
        }
        if (bar && (i + 1 == total || (double)i - last_bar >= (double)total / 100)) {
            progress(true, i + 1, total, sink_frames(&k));
            last_bar = (double)i;
        }
    }
    if (rc < 0) {
        fprintf(stderr, "%sfacepuppet export: %s\n", bar ? "\n" : "", err);
        status = fp_app_exit_code(rc, FP_APP_INPUT);
        goto done;
    }
    if (bar && index < total)
        progress(true, total, total, sink_frames(&k));
    if (fps > 0 && have_held) {   /* the held frame's own sample times, up to its time */
        for (double t; (t = (double)sample / fps) <= (double)(held_ns - first_ns) * 1e-9 + 1e-12;
             sample++)
            if ((rc = sink_add(&k, held, t, err, sizeof err))) {
                fprintf(stderr, "facepuppet export: %s\n", err);
                status = fp_app_exit_code(rc, FP_APP_OUTPUT);
                goto done;
            }
    }
    if (!started) {
        fprintf(stderr, "facepuppet export: %s%s%sholds none of the take's %zu frames\n",
                range ? "--range " : "the take ", range ? range : "", range ? " " : "", total);
        status = FP_EXIT_USAGE;
        goto done;
    }
    if (png) {
        if (!quiet)
            printf("facepuppet export: wrote %llu PNG frames (%dx%d) to %s: %.2f MB\n",
                   (unsigned long long)k.frames, width, height, out, (double)k.bytes / 1e6);
        goto done;
    }
    status = fp_app_export_close("facepuppet export", NULL, &k.x, fmt, out, max_error, quiet, stdout);
    if (!quiet && status == FP_EXIT_OK && (fmt == FP_EXPORT_GLTF || fmt == FP_EXPORT_GLB))
        printf("facepuppet export: %.6g mm per mesh unit; frame rate %u/%u%s\n", mm_per_unit,
               h->rate.num, h->rate.den, fps > 0 ? " (resampled)" : "");
done:
    fp_export_abort(&k.x);
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
