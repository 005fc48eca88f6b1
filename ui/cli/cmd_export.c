/* facepuppet export: a take's frames (reproduced from its stored control sets, as play does:
 * fp_take_player) out as glTF/GLB morph-target animation, PC2 or MDD point caches, or one
 * mesh file per frame (core/export, docs/export.md). */
#define _GNU_SOURCE
#include "app_export.h"
#include "app_util.h"
#include "command.h"
#include "fp_take_player.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void usage(FILE *f)
{
    fprintf(f,
        "usage: facepuppet export TAKE --format gltf|glb|pc2|mdd|obj-seq|png-seq [--out PATH]\n"
        "                         [--range IN-OUT] [--fps F] [--max-error MM] [--mesh FILE]\n\n"
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
        "  png-seq     not available yet (see docs/export.md)\n\n"
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
        "  -m, --mesh FILE       the take's mesh from another path (its crc32 must match)\n"
        "      --plugin-dir DIR  look for plugins in DIR first\n"
        "  -q, --quiet           no progress and no summary\n"
        "  -h, --help            this text\n\n"
        "Exit status: 0 done, 64 usage, 65 a damaged take or another mesh, 66 missing,\n"
        "69 png-seq, 73 an output not written (facepuppet --help has the whole table).\n");
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
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (*end || errno || s[0] == '-') {
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
    enum { OPT_RANGE = 0x200, OPT_FPS, OPT_MAX_ERROR, OPT_MAX_TARGETS, OPT_STEP, OPT_PLUGIN_DIR };
    static const struct option opts[] = {
        {"format", required_argument, 0, 'f'},   {"out", required_argument, 0, 'o'},
        {"range", required_argument, 0, OPT_RANGE}, {"fps", required_argument, 0, OPT_FPS},
        {"max-error", required_argument, 0, OPT_MAX_ERROR},
        {"max-targets", required_argument, 0, OPT_MAX_TARGETS},
        {"step", no_argument, 0, OPT_STEP},      {"mesh", required_argument, 0, 'm'},
        {"plugin-dir", required_argument, 0, OPT_PLUGIN_DIR},
        {"quiet", no_argument, 0, 'q'},          {"help", no_argument, 0, 'h'},
        {0, 0, 0, 0}};
    const char *format = NULL, *out = NULL, *range = NULL, *mesh = NULL, *dirs[8];
    size_t ndirs = 0;
    double fps = 0, max_error = 0.1;
    int max_targets = 0, step = 0;
    bool quiet = false;
    char *end;
    optind = 1;
    for (int c; (c = getopt_long(argc, argv, "f:o:m:qh", opts, NULL)) != -1;) {
        switch (c) {
        case 'f': format = optarg; break;
        case 'o': out = optarg; break;
        case OPT_RANGE: range = optarg; break;
        case OPT_FPS:
            fps = strtod(optarg, &end);
            if (*end || !(fps > 0 && fps <= 10000)) {
                fprintf(stderr, "facepuppet export: --fps must be in (0, 10000], got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_MAX_ERROR:
            max_error = strtod(optarg, &end);
            if (*end || !(max_error > 0 && isfinite(max_error))) {
                fprintf(stderr, "facepuppet export: --max-error must be > 0 mm, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_MAX_TARGETS:
            max_targets = (int)strtol(optarg, &end, 10);
            if (*end || max_targets < 1) {
                fprintf(stderr, "facepuppet export: --max-targets must be >= 1, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_STEP: step = 1; break;
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
    if (strcmp(format, "png-seq") == 0) {
        fprintf(stderr, "facepuppet export: png-seq is not available yet: render frames with "
                "`facepuppet play --frames-out DIR` and the viewer's screenshots, or export "
                "obj-seq (docs/export.md)\n");
        return FP_EXIT_UNAVAILABLE;
    }
    fp_export_format fmt;
    if (fp_export_format_parse(format, &fmt)) {
        fprintf(stderr, "facepuppet export: unknown --format '%s' (gltf, glb, pc2, mdd, obj-seq, "
                "png-seq)\n", format);
        return FP_EXIT_USAGE;
    }
    const char *take_path = argv[optind];
    char err[2048];
    fp_plugin_path path;
    fp_app_plugin_path(&path, dirs, ndirs);
    fp_take_player *p = NULL;
    int rc = fp_take_player_open(take_path, mesh, &path, &p, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet export: %s\n", err);
        fp_plugin_path_clear(&path);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    int status = FP_EXIT_OK;
    fp_exporter *x = NULL;
    float *held = NULL;
    const fp_take_header *h = fp_take_player_header(p);
    fp_take_reader *r = fp_take_player_reader(p);
    if (fp_take_reader_warning(r)[0])
        fprintf(stderr, "facepuppet export: warning: %s; exporting the %zu intact frames\n",
                fp_take_reader_warning(r), fp_take_reader_frames(r));
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
        if (fmt == FP_EXPORT_OBJ_SEQ)
            snprintf(def_out, sizeof def_out, "%.*s_frames", stem, take_path);
        else
            snprintf(def_out, sizeof def_out, "%.*s.%s", stem, take_path,
                     fp_export_format_extension(fmt));
        out = def_out;
    }
    const double mm_per_unit = fp_take_player_mm_per_unit(p);
    fp_session *s = fp_take_player_session(p);
    char name[96];
    snprintf(name, sizeof name, "%s_T%03u", h->slate, h->take);
    fp_export_options eo = {.format = fmt, .path = out, .max_error_mm = max_error,
                            .mm_per_unit = mm_per_unit, .max_targets = max_targets,
                            .step = step, .name = name, .stem = name};
    if ((rc = fp_export_begin(fp_session_mesh(s), &eo, &x, err, sizeof err))) {
        fprintf(stderr, "facepuppet export: %s\n", err);
        status = fp_app_exit_code(rc, FP_APP_OUTPUT);
        goto done;
    }
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
                rc = fp_export_add(x, pos, (double)(f.time_ns - first_ns) * 1e-9, err, sizeof err);
            } else {
                /* samples before this frame's time show the frame held before it */
                rc = 0;
                for (double t; have_held && !rc &&
                               (t = (double)sample / fps) < (double)(f.time_ns - first_ns) * 1e-9;
                     sample++)
                    rc = fp_export_add(x, held, t, err, sizeof err);
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
            progress(true, i + 1, total, fp_export_frames(x));
            last_bar = (double)i;
        }
    }
    if (rc < 0) {
        fprintf(stderr, "%sfacepuppet export: %s\n", bar ? "\n" : "", err);
        status = fp_app_exit_code(rc, FP_APP_INPUT);
        goto done;
    }
    if (bar && index < total)
        progress(true, total, total, fp_export_frames(x));
    if (fps > 0 && have_held) {   /* the held frame's own sample times, up to its time */
        for (double t; (t = (double)sample / fps) <= (double)(held_ns - first_ns) * 1e-9 + 1e-12;
             sample++)
            if ((rc = fp_export_add(x, held, t, err, sizeof err))) {
                fprintf(stderr, "facepuppet export: %s\n", err);
                status = fp_app_exit_code(rc, FP_APP_OUTPUT);
                goto done;
            }
    }
    if (!started) {
        fprintf(stderr, "facepuppet export: --range %s holds none of the take's %zu frames\n",
                range ? range : "", total);
        status = FP_EXIT_USAGE;
        goto done;
    }
    status = fp_app_export_close("facepuppet export", &x, fmt, out, max_error, quiet, stdout);
    if (!quiet && status == FP_EXIT_OK && (fmt == FP_EXPORT_GLTF || fmt == FP_EXPORT_GLB))
        printf("facepuppet export: %.6g mm per mesh unit; frame rate %u/%u%s\n", mm_per_unit,
               h->rate.num, h->rate.den, fps > 0 ? " (resampled)" : "");
done:
    fp_export_abort(&x);
    free(held);
    fp_take_player_close(&p);
    fp_plugin_path_clear(&path);
    return status;
}

const fp_command fp_command_export = {"export", "a take out as glTF animation, point caches "
                                      "or mesh files", export_main};
