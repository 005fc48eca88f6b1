/* facepuppet run: a headless session (the main job). */
#define _GNU_SOURCE
#include "app_util.h"
#include "fp_text.h"
#include "command.h"
#include "fp_session.h"
#include "fp_session_take.h"
#include "app_export.h"
#include "session_opts.h"
#include "fp_stats.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

static volatile sig_atomic_t interrupted;
static void on_signal(int sig) { (void)sig; interrupted = 1; }

static void usage(FILE *f)
{
    fprintf(f,
        "usage: facepuppet run [--mesh FILE] --input SPEC [--input SPEC] --mapping NAME\n"
        "                      [--radius R] [--out FILE] [--frames-out DIR] [--speed X]\n\n"
        "Run a headless puppeteering session: the inputs drive the mapping, the mapping\n"
        "drives the CSRBF engine, the face deforms; writes the final mesh.\n"
        "With no options it runs the demo: the ICT face, the three-claps recording, the\n"
        "anchored mapping, written to facepuppet-demo.obj.\n\n"
        "Session options (shared with `facepuppet live`):\n");
    fp_session_opts_help(f);
    fprintf(f,
        "Options of run:\n"
        "  -o, --out FILE         final mesh (default facepuppet-out.obj; demo:\n"
        "                         facepuppet-demo.obj); format by extension\n"
        "      --frames-out DIR   also write one mesh per frame, every frame at --fps\n"
        "                         (DIR/frame_000123_t2.050s.obj: number, time on the input clock)\n"
        "      --fps N            frames per second of the session loop (default 60)\n"
        "      --export FILE      every frame into FILE: .gltf/.glb (morph-target animation,\n"
        "                         0.1 mm), .pc2/.mdd (point caches); see facepuppet export\n"
        "      --take-dir DIR     record the run as a take in DIR (SLATE_TNNN.fptake; see\n"
        "                         facepuppet takes, play, --input take:FILE); its path,\n"
        "                         frames and timecode are said at the end, -q or not\n"
        "      --slate NAME       the take's slate (default \"take\"); numbers go up per slate\n"
        "      --take-description TEXT  a line stored in the take's header\n"
        "      --budget MS        report a mapping process() slower than MS (default 2)\n\n"
        "The run steps on the recordings' own clock (frame k at t0 + k/fps), not the wall\n"
        "clock: the same inputs and options give bit-identical meshes whatever --speed,\n"
        "speed=, fast=1 or the machine's load (--speed only changes how long it takes).\n"
        "  -h, --help             this text\n\n"
        "Exit status: 0 done, 64 usage, 65 bad input data, 66 input missing, 73 output\n"
        "not writable, 78 plugin missing or incompatible, or the mapping stopped for a\n"
        "fault (it wrote past the host's arrays), 1 other failure\n"
        "(facepuppet --help has the whole table).\n");
}

static void sleep_until(int64_t t_ns)
{
    struct timespec ts = {(time_t)(t_ns / 1000000000LL), (long)(t_ns % 1000000000LL)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
}

/* --out, before any work: a format we write (by extension) and a folder we can write in.
 * Returns 0 or the exit status (64 unknown extension, 73 folder missing or not writable). */
static int check_out(const char *out)
{
    int rc = fp_app_check_mesh_name("facepuppet run", "--out", out);
    if (rc) return rc;
    return fp_app_check_output("facepuppet run", "--out", out);
}

static int run_main(int argc, char **argv)
{
    enum { OPT_FRAMES_OUT = FP_SESSION_OPTS_FIRST_FREE, OPT_FPS, OPT_BUDGET, OPT_TAKE_DIR,
           OPT_SLATE, OPT_TAKE_DESC, OPT_EXPORT };
    static const struct option own[] = {
        {"out", required_argument, 0, 'o'},        {"frames-out", required_argument, 0, OPT_FRAMES_OUT},
        {"fps", required_argument, 0, OPT_FPS},    {"help", no_argument, 0, 'h'},
        {"budget", required_argument, 0, OPT_BUDGET},
        {"take-dir", required_argument, 0, OPT_TAKE_DIR}, {"slate", required_argument, 0, OPT_SLATE},
        {"take-description", required_argument, 0, OPT_TAKE_DESC},
        {"export", required_argument, 0, OPT_EXPORT},
        {0, 0, 0, 0}};
    struct option opts[FP_SESSION_OPTS_COUNT + sizeof own / sizeof own[0]];
    memcpy(opts + fp_session_opts_longopts(opts), own, sizeof own);
    fp_session_options so = {0};
    int rc;
    fp_session_opts sopt;
    fp_session_opts_init(&sopt, &so);
    const char *out = NULL, *frames_out = NULL;
    const char *take_dir = NULL, *slate = NULL, *take_desc = NULL, *export_file = NULL;
    double fps = 60;
    optind = 1;
    for (int c; (c = getopt_long(argc, argv, FP_SESSION_OPTS_SHORT "o:h", opts, NULL)) != -1;) {
        int shared = fp_session_opts_parse(&sopt, c, optarg, "run");
        if (shared < 0) return fp_app_exit_code(shared, FP_APP_INPUT);
        if (shared) continue;
        switch (c) {
        case 'o': out = optarg; break;
        case OPT_FRAMES_OUT: frames_out = optarg; break;
        case OPT_FPS:
            if (!fp_parse_decimal(optarg, &fps) || !(fps >= 1 && fps <= 10000)) {
                fprintf(stderr, "facepuppet run: --fps must be in 1..10000, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_TAKE_DIR: take_dir = optarg; break;
        case OPT_SLATE: slate = optarg; break;
        case OPT_TAKE_DESC:
            if (!fp_text_ok(optarg, true)) {
                fprintf(stderr, "facepuppet run: --take-description must be UTF-8 text without "
                                "control characters (tabs and line breaks allowed)\n");
                return FP_EXIT_USAGE;
            }
            take_desc = optarg;
            break;
        case OPT_EXPORT: export_file = optarg; break;
        case OPT_BUDGET:
            if (!fp_parse_decimal(optarg, &so.mapping_budget_ms) ||
                !(so.mapping_budget_ms > 0 && so.mapping_budget_ms <= 1000)) {
                fprintf(stderr, "facepuppet run: --budget must be in (0, 1000] ms, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case 'h': usage(stdout); return FP_EXIT_OK;
        default: usage(stderr); return FP_EXIT_USAGE;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "facepuppet run: unexpected argument '%s'\n", argv[optind]);
        return FP_EXIT_USAGE;
    }
    double speed = sopt.speed, duration = sopt.duration_s;
    bool quiet = sopt.quiet;
    /* The demo: no mesh and no input given. */
    bool mesh_given = so.mesh_path != NULL;
    fp_app_inputs inputs_buf;
    bool demo = fp_app_session_defaults(&so, speed, &inputs_buf);
    if (mesh_given && !so.input_count) {
        fprintf(stderr, "facepuppet run: give at least one --input SPEC (see --help)\n");
        return FP_EXIT_USAGE;
    }
    if (!out) out = demo ? "facepuppet-demo.obj" : "facepuppet-out.obj";
    /* Outputs are checked before any work: a folder we can write into, a format we write. */
    if ((rc = check_out(out))) return rc;
    if (frames_out) {
        struct stat st;
        if (mkdir(frames_out, 0777) && errno != EEXIST) {
            fprintf(stderr, "facepuppet run: --frames-out %s: %s\n", frames_out, strerror(errno));
            return fp_app_exit_code(-errno, FP_APP_OUTPUT);
        }
        if (stat(frames_out, &st) || !S_ISDIR(st.st_mode)) {
            fprintf(stderr, "facepuppet run: --frames-out %s: not a folder\n", frames_out);
            return FP_EXIT_CANTCREAT;
        }
        if (access(frames_out, W_OK | X_OK)) {
            fprintf(stderr, "facepuppet run: --frames-out %s: %s\n", frames_out, strerror(errno));
            return FP_EXIT_CANTCREAT;
        }
    }

    fp_export_format export_fmt;
    if (export_file && fp_export_format_from_path(export_file, &export_fmt)) {
        fprintf(stderr, "facepuppet run: --export %s: give a file ending in .gltf, .glb, .pc2 "
                "or .mdd\n", export_file);
        return FP_EXIT_USAGE;
    }
    if ((slate || take_desc) && !take_dir) {
        fprintf(stderr, "facepuppet run: --slate and --take-description need --take-dir\n");
        return FP_EXIT_USAGE;
    }
    if (slate && !fp_take_slate_valid(slate)) {
        fprintf(stderr, "facepuppet run: --slate '%s': use 1-63 of A-Z a-z 0-9 . _ - (not "
                "starting with '.')\n", slate);
        return FP_EXIT_USAGE;
    }
    /* --take-dir: the session's record sink feeds the take recorder (fp_session_take.h). */
    fp_session_take take;
    fp_session_take_options take_opt = {.dir = take_dir, .slate = slate,
                                        .description = take_desc, .rate = fp_app_take_rate(fps)};
    fp_session_take_init(&take, &take_opt, &so);
    if (take_dir) {
        so.record = fp_session_take_sink;
        so.record_user = &take;
    }

    fp_plugin_path path;
    fp_app_plugin_path(&path, sopt.plugin_dirs, sopt.nplugin_dirs);
    so.plugin_path = &path;
    /* (input status, mapping and engine errors, recordings; -q: without the engine's notes) */
    so.log = quiet ? fp_app_log_line_quiet : fp_app_log_line;
    so.input_clock = true;
    so.measure_jacobian = true; /* min det J in the summary (the same shape, a slower path) */
    fp_app_open_progress opening; /* a large face takes a while: its steps on a terminal */
    fp_app_open_progress_init(&opening, "facepuppet run", quiet);
    so.progress = fp_app_open_progress_fn;
    so.progress_user = &opening;
    char err[2048];
    fp_session *s = NULL;
    rc = fp_session_create(&so, &s, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet run: %s\n", err);
        fp_plugin_path_clear(&path);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    if (!quiet) {
        fprintf(stderr, "facepuppet run: %s, %zu vertices, rig %s, mapping %s, radius %.4g, %zu input(s); "
                "scale: %.4g mm per mesh unit (%s)\n", so.mesh_path, fp_session_vertex_count(s),
                fp_session_rig_how(s), so.mapping, fp_session_radius(s), so.input_count, fp_session_head(s)->mm_per_unit, fp_session_head(s)->how);
    }
    /* --export: every frame into one animation file (core/export), finished after the run */
    fp_exporter *ex = NULL;
    if (export_file && (rc = fp_app_export_open("facepuppet run", export_file, fp_session_mesh(s),
                                                fp_session_head(s)->mm_per_unit, "run", &ex))) {
        fp_session_destroy(&s);
        fp_plugin_path_clear(&path);
        return rc;
    }
    if ((rc = fp_session_start(s, err, sizeof err))) {
        fprintf(stderr, "facepuppet run: %s\n", err);
        fp_export_abort(&ex);
        fp_session_destroy(&s);
        fp_plugin_path_clear(&path);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);

    size_t cap = 1024, nupdates = 0;
    double *update_ms = malloc(cap * sizeof *update_ms);
    fp_app_reach reach = {0};
    uint64_t frames = 0, commits = 0, engages = 0, active_frames = 0, guarded = 0, limited = 0;
    double min_det_j = INFINITY, collide_t = 1.0;
    uint64_t collided = 0;
    int status = FP_EXIT_OK;
    /* The clock: the recordings' own (frame k at t0 + k/fps, each step only once every
     * recording has delivered past it), else the wall clock (live devices only). */
    int64_t t0 = 0, wall0 = fp_now_ns(), last_report = wall0;
    int clock;
    while ((clock = fp_session_input_start(s, &t0)) == 0 && !interrupted) sleep_until(fp_now_ns() + 200000);
    bool input_clock = clock == 1;
    if (!input_clock) t0 = wall0;
    /* The take's time origin (timecode in) is the first frame's time. */
    if (take_dir && !interrupted && (rc = fp_session_take_start(&take, s, t0, err, sizeof err))) {
        fprintf(stderr, "facepuppet run: take: %s\n", err);
        status = fp_app_exit_code(rc, FP_APP_OUTPUT);
        interrupted = 1;
    }
    for (uint64_t k = 0; !interrupted; k++) {
        int64_t now = t0 + (int64_t)llround((double)k * 1e9 / fps);
        if (input_clock) {
            while (!fp_session_inputs_ready(s, now) && !interrupted) sleep_until(fp_now_ns() + 200000);
            if (interrupted) break;
        } else {
            sleep_until(now);
        }
        fp_frame_stats st;
        fp_session_step(s, now, &st);
        frames++;
        commits += st.committed;
        engages += st.engaged;
        active_frames += st.active;
        if (st.active) {
            guarded += st.guard_limited > 0 || st.guard_substeps > 1;
            limited += st.guard_reached < 1.0;
            if (st.min_det_j < min_det_j) min_det_j = st.min_det_j;
        }
        if (st.collide_t < 1.0) {
            collided++;
            if (st.collide_t < collide_t) collide_t = st.collide_t;
        }
        fp_app_reach_add(&reach, &st); /* how far the skin followed */
        if (st.active) {
            if (nupdates == cap) {
                double *grown = realloc(update_ms, 2 * cap * sizeof *update_ms);
                if (grown) { update_ms = grown; cap *= 2; }
            }
            if (nupdates < cap) update_ms[nupdates++] = st.update_ms;
        }
        if (ex && (rc = fp_export_add(ex, fp_session_positions(s), (double)(now - t0) * 1e-9, err,
                                      sizeof err))) {
            fprintf(stderr, "facepuppet run: --export: %s\n", err);
            status = fp_app_exit_code(rc, FP_APP_OUTPUT);
            break;
        }
        if (frames_out) {
            char file[4400];
            snprintf(file, sizeof file, "%s/frame_%06llu_t%.3fs.obj", frames_out, (unsigned long long)k,
                     (double)(now - t0) * 1e-9);
            if ((rc = fp_session_save(s, file, err, sizeof err))) {
                fprintf(stderr, "facepuppet run: %s\n", err);
                status = fp_app_exit_code(rc, FP_APP_OUTPUT);
                break;
            }
        }
        int64_t wall = fp_now_ns();
        if (!quiet && wall - last_report >= 1000000000LL) {
            fprintf(stderr, "  %6.1f s  frame %-6llu %s  %zu control vectors  update %.3f ms\n",
                    (now - t0) / 1e9, (unsigned long long)frames, st.active ? "deforming" : "idle     ",
                    st.control_vectors, st.update_ms);
            last_report = wall;
        }
        if (fp_session_finished(s)) break;
        if (duration > 0 && now - t0 >= (int64_t)(duration * 1e9)) break;
    }
    if (interrupted && !quiet) fprintf(stderr, "facepuppet run: interrupted; saving what was done\n");
    /* Close the take: a failed write (ENOSPC) fails the run with 73. */
    int take_rc = 0;
    char take_err[1024] = "";
    if (fp_session_take_recording(&take)) {
        fp_session_take_result tr;
        take_rc = fp_session_take_stop(&take, &tr, take_err, sizeof take_err);
        fp_app_print_take(stderr, "facepuppet run", &tr);
    }
    /* Close the record=FILE recordings: a failed write must fail the run. */
    char record_err[1024] = "";
    bool record_failed = fp_session_stop(s, record_err, sizeof record_err) != 0;
    /* The summary: displacement of the final shape from the loaded one. */
    const float *a = fp_session_loaded(s), *b = fp_session_positions(s);
    size_t n = fp_session_vertex_count(s), moved = 0;
    double sum = 0, max = 0;
    bool finite = true;
    for (size_t v = 0; v < n; v++) {
        double dx = b[3 * v] - a[3 * v], dy = b[3 * v + 1] - a[3 * v + 1], dz = b[3 * v + 2] - a[3 * v + 2];
        double d = sqrt(dx * dx + dy * dy + dz * dz);
        if (!isfinite(d)) finite = false;
        sum += d;
        if (d > max) max = d;
        if (d > 0) moved++;
    }
    unsigned dropped = 0;
    if (status == FP_EXIT_OK) {
        /* a large face takes seconds to write: a status line on a terminal (as its opening) */
        fp_app_open_progress writing;
        fp_app_open_progress_init(&writing, "facepuppet run", quiet);
        writing.phase = "writing";
        snprintf(writing.done, sizeof writing.done, "wrote %s", out);
        char what[600];
        snprintf(what, sizeof what, "%s (%zu vertices)", out, n);
        fp_app_open_progress_fn(&writing, what);
        rc = fp_session_save_ex(s, out, &dropped, err, sizeof err);
        fp_app_open_progress_fn(&writing, NULL);
        if (rc) {
            fprintf(stderr, "facepuppet run: %s\n", err);
            status = fp_app_exit_code(rc, FP_APP_OUTPUT);
        }
    }
    fp_app_print_dropped("facepuppet run", out, dropped, quiet);
    if (ex && status == FP_EXIT_OK)
        status = fp_app_export_close("facepuppet run", "--export", &ex, export_fmt, export_file, 0.1, quiet,
                                     stderr);
    fp_export_abort(&ex);
    double med = fp_median(update_ms, nupdates), mmu = fp_session_head(s)->mm_per_unit;
    char reach_text[200];
    fp_app_reach_text(&reach, mmu, reach_text, sizeof reach_text);
    fp_app_reach_free(&reach);
    printf("frames %llu, deforming %llu, engaged %llu, committed %llu; vertices moved %zu of %zu; "
           "displacement mean %.3g mm max %.3g mm (%.6g, %.6g mesh units of %.4g mm)%s; update median "
           "%.3f ms over %zu updates; "
           "fold-over guard acted on %llu frames (stopped short on %llu), min det J %.3g; "
           "contact guard scaled back %llu frames (least kept %.0f%%); events dropped %lu%s%s\n",
           (unsigned long long)frames, (unsigned long long)active_frames, (unsigned long long)engages,
           (unsigned long long)commits, moved, n, n ? sum / n * mmu : 0.0, max * mmu, n ? sum / n : 0.0,
           max, mmu, reach_text, med, nupdates,
           (unsigned long long)guarded, (unsigned long long)limited,
           active_frames ? min_det_j : 1.0, (unsigned long long)collided, 100.0 * collide_t,
           fp_session_dropped(s), status == FP_EXIT_OK ? "; wrote " : "",
           status == FP_EXIT_OK ? out : "");
    const char *input_error;
    if (fp_session_input_errors(s, &input_error) && status == FP_EXIT_OK) {
        fprintf(stderr, "facepuppet run: an input reported an error: %s\n", input_error);
        status = FP_EXIT_DATAERR;
    }
    if (take_rc) {
        fprintf(stderr, "facepuppet run: the take was not written whole: %s\n", take_err);
        if (status == FP_EXIT_OK) status = fp_app_exit_code(take_rc, FP_APP_OUTPUT);
    }
    if (record_failed && status == FP_EXIT_OK) {
        fprintf(stderr, "facepuppet run: %s\n", record_err);
        status = FP_EXIT_CANTCREAT;
    }
    if (fp_session_mapping_fault(s, err, sizeof err)) {
        fprintf(stderr, "facepuppet run: %s\n", err);
        if (status == FP_EXIT_OK) status = fp_app_exit_code(FP_EPLUGIN_FAULT, FP_APP_INPUT);
    }
    if (!finite) {
        fprintf(stderr, "facepuppet run: non-finite vertex in the result\n");
        status = FP_EXIT_SOFTWARE;
    }
    free(update_ms);
    fp_session_destroy(&s);
    fp_plugin_path_clear(&path);
    return status;
}

const fp_command fp_command_run = {"run", "run a headless session (no options: the demo)", run_main};
