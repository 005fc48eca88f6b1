/* facepuppet run: a headless session (the main job). */
#define _GNU_SOURCE
#include "app_getopt.h"
#include "app_util.h"
#include "fp_text.h"
#include "command.h"
#include "fp_session.h"
#include "fp_session_take.h"
#include "app_stack.h"
#include "app_export.h"
#include "app_audio.h"
#include "app_stop.h"
#include "app_link.h"
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

static void usage(FILE *f)
{
    fprintf(f,
        "usage: facepuppet run [--mesh FILE] --input SPEC [--input SPEC] --mapping SPEC\n"
        "                      [--radius R] [--out FILE] [--frames-out DIR] [--speed X] [--force]\n"
        "                      [--audio FILE [--audio-out SPEC] [--audio-offset S]] [--timecode SRC]\n"
        "                      [--audio-in DEVICE]\n\n"
        "Run a headless puppeteering session: the inputs drive the mapping, the mapping\n"
        "drives the CSRBF engine, the face deforms; writes the final mesh.\n"
        "With no options it runs the demo: the ICT face, the three-claps recording, the\n"
        "anchored mapping, written to facepuppet-demo.obj.\n\n"
        "Session options (shared with `facepuppet live`):\n");
    fp_session_opts_help(f);
    fprintf(f,
        "Options of run:\n"
        "  -o, --out FILE         final mesh (default facepuppet-out.obj; demo:\n"
        "                         facepuppet-demo.obj; when the default exists, the next free\n"
        "                         name, facepuppet-out-1.obj ..., and said); format by extension\n"
        "      --frames-out DIR   also write one mesh per frame, every frame at --fps\n"
        "                         (DIR/frame_000123_t2.050s.obj: number, time on the input clock);\n"
        "                         its size is estimated before the run (a warning over 1 GiB;\n"
        "                         with --duration, refused (73) where it is more than the room\n"
        "                         free there, as is --export's point cache)\n"
        "      --force            overwrite outputs that exist (--out, --export, frames in\n"
        "                         --frames-out: an earlier run's frames there are removed\n"
        "                         before the first); without it they are refused before any work\n"
        "      --fps N            frames per second of the session loop (default 60)\n"
        "      --export FILE      every frame into FILE: .gltf/.glb (morph-target animation,\n"
        "                         0.1 mm), .pc2/.mdd (point caches: with --duration, a\n"
        "                         warning over 1 GiB); see facepuppet export\n"
        "      --take-dir DIR     record the run as a take in DIR (SLATE_TNNN.fptake; see\n"
        "                         facepuppet takes, play, --input take:FILE), made with its\n"
        "                         parents when missing (checked before any work); its path,\n"
        "                         frames and timecode are said at the end, -q or not\n"
        "      --slate NAME       the take's slate (default \"scene1\"); numbers go up per slate\n"
        "      --take-description TEXT  a line stored in the take's header\n"
        "      --over STACK_OR_TAKE  overdub: the run is a new pass over a stack (.fpstack) or\n"
        "                         a take; after it a new stack SLATE_SNNN.fpstack in --take-dir\n"
        "                         holds the old layers and the pass on top (the old one kept)\n"
        "      --layer REGION[:MODE]  the pass's region and mode (default mouth:replace):\n"
        "                         mouth, brows, jaw, all, rig:NAME, landmark:NAME[,NAME],\n"
        "                         channels:NAME[,NAME], vertices:A-B[,C], [@FALLOFF_MM]; MODE\n"
        "                         replace or add (docs/stack.md)\n"
        "      --punch IN:OUT     the pass counts only from IN to OUT seconds of the stack,\n"
        "                         cross-faded inside the range\n"
        "      --budget MS        report a mapping process() slower than MS (default 2)\n");
    fp_app_audio_help(f, true);
    fprintf(f, "\n"
        "The run steps on the recordings' own clock (frame k at t0 + k/fps), not the wall\n"
        "clock: the same inputs and options give bit-identical meshes whatever --speed,\n"
        "speed=, fast=1 or the machine's load (--speed only changes how long it takes).\n"
        "  -h, --help             this text\n\n"
        "SIGINT (Ctrl-C) or SIGTERM: the run ends after the frame in progress, the take closed and\n"
        "the outputs written (exit 0). When that frame does not end within 0.1 s because a\n"
        "plugin's call never returns (a mapping's process() that spins), the run ends without\n"
        "it: one line names the plugin, the call and the frame; the take is closed with every\n"
        "frame before it, --export and --out are written up to the frame before, and the exit\n"
        "status is 128 + the signal (130 SIGINT, 143 SIGTERM; the frames of --frames-out are\n"
        "written as they go). A second signal a second later ends the run at once, 128 + it.\n\n"
        "Exit status: 0 done, 64 usage (an unknown audio device too), 65 bad input data (an\n"
        "LTC file without LTC, a soundtrack that is no sound file or has samples that are not\n"
        "numbers too), 66 input missing (a soundtrack or LTC file missing or unreadable too), 73 output not writable or existing without --force, 78 plugin\n"
        "missing or incompatible, or the mapping stopped for a fault (it wrote past the host's\n"
        "arrays), 130/143 ended by SIGINT/SIGTERM with a plugin stuck (above), 1 other failure\n"
        "(facepuppet --help has the whole table).\n");
}

static void sleep_until(int64_t t_ns)
{
    struct timespec ts = {(time_t)(t_ns / 1000000000LL), (long)(t_ns % 1000000000LL)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
}

/* What the command line asked for (run_parse), with the defaults settled (run_settle). */
typedef struct run_args {
    fp_session_options so;
    fp_session_opts sopt;          /* the shared options; points at so */
    fp_app_inputs inputs_buf;      /* the demo's and the defaults' strings, which so points into */
    const char *out, *frames_out;
    bool frames_out_made;          /* this run made the --frames-out folder (rmdir if refused) */
    const char *take_dir, *slate, *take_desc, *export_file;
    fp_export_format export_fmt;   /* of export_file */
    double fps;
    bool demo;
    bool force;                    /* --force: outputs that exist are overwritten */
    char free_out[4200];           /* the default --out's next free name, when it exists */
    fp_app_audio audio;            /* --audio, --audio-out, --audio-offset, --timecode */
    fp_app_over over;              /* --over, --layer, --punch (app_stack.h) */
    int64_t take_end_ns;           /* the end of the take's last frame (its mic WAV's end) */
    int control_status;            /* the first failure of a take's microphone WAV begun or
                                      ended over --control (the run's exit status) */
    fp_app_link *link;             /* --control, --stream (app_link.h) */
} run_args;

/* --out, before any work: a format we write (by extension), a folder we can write in, and no
 * file there unless --force. The default name (not given) takes the next free name instead,
 * said. Returns 0 or the exit status (64 unknown extension, 73 folder missing or not
 * writable, or the file exists). */
static int check_out(run_args *a, bool given)
{
    int rc = fp_app_check_mesh_name("facepuppet run", "--out", a->out);
    if (rc) return rc;
    if (!given && !a->force) {
        if ((rc = fp_app_check_output("facepuppet run", "--out", a->out))) return rc;
        if (!fp_app_free_name(a->out, a->free_out, sizeof a->free_out)) {
            fprintf(stderr, "facepuppet run: %s and %s-1 .. -999 exist (--out names another, "
                    "--force overwrites)\n", a->out, a->out);
            return FP_EXIT_CANTCREAT;
        }
        if (strcmp(a->free_out, a->out))
            fprintf(stderr, "facepuppet run: %s exists: writing %s instead (--out names the "
                    "file, --force overwrites)\n", a->out, a->free_out);
        a->out = a->free_out;
        return 0;
    }
    return fp_app_check_new_output("facepuppet run", "--out", a->out, a->force);
}

/* Parse the command line into *a (zeroed by the caller). Returns -1 to go on, or the exit
 * status (0 after --help). */
static int run_parse(int argc, char **argv, run_args *a)
{
    enum { OPT_FRAMES_OUT = FP_SESSION_OPTS_FIRST_FREE, OPT_FPS, OPT_BUDGET, OPT_TAKE_DIR,
           OPT_SLATE, OPT_TAKE_DESC, OPT_EXPORT, OPT_FORCE, OPT_OVER, OPT_LAYER, OPT_PUNCH };
    static const struct option own[] = {
        {"out", required_argument, 0, 'o'},        {"frames-out", required_argument, 0, OPT_FRAMES_OUT},
        {"fps", required_argument, 0, OPT_FPS},    {"help", no_argument, 0, 'h'},
        {"budget", required_argument, 0, OPT_BUDGET},
        {"take-dir", required_argument, 0, OPT_TAKE_DIR}, {"slate", required_argument, 0, OPT_SLATE},
        {"take-description", required_argument, 0, OPT_TAKE_DESC},
        {"export", required_argument, 0, OPT_EXPORT},
        {"force", no_argument, 0, OPT_FORCE},
        {"over", required_argument, 0, OPT_OVER}, {"layer", required_argument, 0, OPT_LAYER},
        {"punch", required_argument, 0, OPT_PUNCH},
        {0, 0, 0, 0}};
    struct option opts[FP_SESSION_OPTS_COUNT + FP_APP_AUDIO_OPTS_COUNT + sizeof own / sizeof own[0]];
    size_t nshared = fp_session_opts_longopts(opts);
    nshared += fp_app_audio_longopts(opts + nshared, true);
    memcpy(opts + nshared, own, sizeof own);
    fp_session_opts_init(&a->sopt, &a->so);
    a->fps = 60;
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, FP_SESSION_OPTS_SHORT "o:h", opts)) != -1;) {
        int shared = fp_session_opts_parse(&a->sopt, c, optarg, "run");
        if (shared < 0) return fp_app_exit_code(shared, FP_APP_INPUT);
        if (shared) continue;
        int audio = fp_app_audio_parse(&a->audio, c, optarg, "run");
        if (audio > 1) return audio;
        if (audio) continue;
        switch (c) {
        case 'o': a->out = optarg; break;
        case OPT_FRAMES_OUT: a->frames_out = optarg; break;
        case OPT_FPS:
            if (!fp_parse_decimal(optarg, &a->fps) || !(a->fps >= 1 && a->fps <= 10000)) {
                fprintf(stderr, "facepuppet run: --fps must be in 1..10000, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_TAKE_DIR: a->take_dir = optarg; break;
        case OPT_SLATE: a->slate = optarg; break;
        case OPT_TAKE_DESC:
            if (!fp_text_ok(optarg, true)) {
                fprintf(stderr, "facepuppet run: --take-description must be UTF-8 text without "
                                "control characters (tabs and line breaks allowed)\n");
                return FP_EXIT_USAGE;
            }
            a->take_desc = optarg;
            break;
        case OPT_EXPORT: a->export_file = optarg; break;
        case OPT_FORCE: a->force = true; break;
        case OPT_OVER: a->over.over = optarg; break;
        case OPT_LAYER: a->over.layer = optarg; break;
        case OPT_PUNCH: a->over.punch = optarg; break;
        case OPT_BUDGET:
            if (!fp_parse_decimal(optarg, &a->so.mapping_budget_ms) ||
                !(a->so.mapping_budget_ms > 0 && a->so.mapping_budget_ms <= 1000)) {
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
    return -1;
}

/* The defaults (the demo when neither mesh nor input is given; --out's name), then every
 * output and the take's options checked before any work. Returns 0 or the exit status. */
static int run_settle(run_args *a)
{
    int rc;
    bool mesh_given = a->so.mesh_path != NULL;
    if ((rc = fp_app_session_defaults("facepuppet run", &a->so, a->sopt.speed, &a->inputs_buf,
                                      &a->demo)))
        return rc;
    if (mesh_given && !a->so.input_count) {
        fprintf(stderr, "facepuppet run: give at least one --input SPEC (see --help)\n");
        return FP_EXIT_USAGE;
    }
    const bool out_given = a->out != NULL;
    if (!a->out) a->out = a->demo ? "facepuppet-demo.obj" : "facepuppet-out.obj";
    /* Outputs are checked before any work: a folder we can write into, a format we write, and
     * nothing there overwritten without --force. */
    if ((rc = check_out(a, out_given))) return rc;
    if (a->export_file && fp_export_format_from_path(a->export_file, &a->export_fmt)) {
        fprintf(stderr, "facepuppet run: --export %s: give a file ending in .gltf, .glb, .pc2 "
                "or .mdd\n", a->export_file);
        return FP_EXIT_USAGE;
    }
    if (a->export_file && (rc = fp_app_check_new_output("facepuppet run", "--export", a->export_file,
                                                        a->force)))
        return rc;
    if (a->frames_out && (rc = fp_app_check_output_dir("facepuppet run", "--frames-out", a->frames_out,
                                                       "frame_", ".obj", true, a->force,
                                                       &a->frames_out_made)))
        return rc;
    if ((a->slate || a->take_desc) && !a->take_dir) {
        fprintf(stderr, "facepuppet run: --slate and --take-description need --take-dir\n");
        return FP_EXIT_USAGE;
    }
    if (a->audio.in_spec && !a->take_dir) {
        fprintf(stderr, "facepuppet run: --audio-in records beside a take: give --take-dir\n");
        return FP_EXIT_USAGE;
    }
    if (a->slate && !fp_take_slate_valid(a->slate)) {
        fprintf(stderr, "facepuppet run: --slate '%s': use 1-63 of A-Z a-z 0-9 . _ - (not "
                "starting with '.')\n", a->slate);
        return FP_EXIT_USAGE;
    }
    if ((rc = fp_app_link_check("run", a->sopt.control, a->sopt.stream))) return rc;
    if ((rc = fp_app_over_check(&a->over, "facepuppet run", a->take_dir))) return rc;
    if (a->take_dir && (rc = fp_app_check_take_dir("facepuppet run", a->take_dir))) return rc;
    if (a->audio.path && !a->audio.offset_given) /* the line where the base take heard it */
        fp_app_over_soundtrack_offset(&a->over, &a->audio.offset_s);
    return 0;
}

/* What the frames did, for the summary line. */
typedef struct run_totals {
    uint64_t frames, commits, engages, active_frames;
    uint64_t guarded, limited;     /* frames the fold-over guard acted on / stopped short */
    double min_det_j;
    uint64_t collided;             /* frames the contact guard scaled back */
    uint64_t folded;               /* ... of those, for triangles turning over alone (no new
                                      crossing: the skin would have folded over) */
    double collide_t;              /* the least share of a frame's motion it kept */
    double *update_ms;             /* each deforming frame's update time */
    size_t nupdates, cap;
    fp_app_reach reach;            /* how far the skin followed (app_util.h) */
} run_totals;

static void totals_init(run_totals *t)
{
    memset(t, 0, sizeof *t);
    t->min_det_j = INFINITY;
    t->collide_t = 1.0;
    t->cap = 1024;
    t->update_ms = malloc(t->cap * sizeof *t->update_ms);
    if (!t->update_ms) t->cap = 0; /* (no update times: the median is that of none) */
}

static void totals_add(run_totals *t, const fp_frame_stats *st)
{
    t->frames++;
    t->commits += st->committed;
    t->engages += st->engaged;
    t->active_frames += st->active;
    if (st->active) {
        t->guarded += st->guard_limited > 0 || st->guard_substeps > 1;
        t->limited += st->guard_reached < 1.0;
        if (st->min_det_j < t->min_det_j) t->min_det_j = st->min_det_j;
    }
    if (st->collide_t < 1.0) {
        t->collided++;
        t->folded += st->collide_pairs == 0;
        if (st->collide_kept < t->collide_t) t->collide_t = st->collide_kept;
    }
    fp_app_reach_add(&t->reach, st); /* how far the skin followed */
    if (st->active) {
        if (t->nupdates == t->cap && t->cap) {
            double *grown = realloc(t->update_ms, 2 * t->cap * sizeof *t->update_ms);
            if (grown) { t->update_ms = grown; t->cap *= 2; }
        }
        if (t->nupdates < t->cap) t->update_ms[t->nupdates++] = st->update_ms;
    }
}

/* One frame's outputs besides the final mesh: --export's frame, --frames-out's mesh.
 * Returns 0 or the exit status of a failed write (said on stderr). */
static int write_frame(fp_session *s, const run_args *a, fp_exporter *ex, uint64_t k, double t_s)
{
    char err[2048];
    int rc;
    if (ex && (rc = fp_export_add(ex, fp_session_positions(s), t_s, err, sizeof err))) {
        fprintf(stderr, "facepuppet run: --export: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_OUTPUT);
    }
    if (a->frames_out) {
        char file[4400];
        snprintf(file, sizeof file, "%s/frame_%06llu_t%.3fs.obj", a->frames_out, (unsigned long long)k,
                 t_s);
        if ((rc = fp_session_save(s, file, err, sizeof err))) {
            fprintf(stderr, "facepuppet run: %s\n", err);
            return fp_app_exit_code(rc, FP_APP_OUTPUT);
        }
    }
    return 0;
}

/* fp_app_link_take_fn: a take started or stopped over --control records its microphone
 * (--audio-in) beside it, and with --over is a pass with a new stack, as the take run
 * records from its first frame does. [frame thread] */
static void run_control_take(void *user, const fp_session_take *t, const fp_session_take_result *res)
{
    run_args *a = user;
    int st = res ? fp_app_audio_take_stopped(&a->audio, a->take_end_ns, "run", a->sopt.quiet)
                 : fp_app_audio_take_started(&a->audio, t, t->header.time_origin_ns, "run");
    if (res && a->over.over && !res->error && res->frames) {
        int over = fp_app_over_save(&a->over, "facepuppet run", a->take_dir, res->path, t->header.slate);
        if (!st) st = over;
    }
    if (st && !a->control_status) a->control_status = st;
}

/* A take whose write failed (a full disk, its file deleted) said at once, on the frame the
 * recorder stopped at, once per take: the run goes on (its other outputs), the take keeps its
 * frames up to its last whole chunk, and the end says it again and exits 73. */
static void say_take_failed(const fp_session_take *take, uint32_t *said, uint64_t frame, double t_s)
{
    char err[1024];
    if (!fp_session_take_recording(take) || *said == take->header.take ||
        !fp_session_take_failed(take, err, sizeof err))
        return;
    *said = take->header.take;
    fprintf(stderr, "facepuppet run: take %u stopped recording at frame %llu (%.2f s): %s; the run "
            "goes on without it (the take keeps the frames before; exit 73 at the end)\n",
            take->header.take, (unsigned long long)frame, t_s, err);
}

/* The session's frames, until the inputs end, --duration, an interrupt or a failed write.
 * The clock: the recordings' own (frame k at t0 + k/fps, each step only once every
 * recording has delivered past it), else the wall clock (live devices only). The take (if
 * any) starts at the first frame's time. Returns FP_EXIT_OK or the exit status of a failure. */
static int run_frames(fp_session *s, run_args *a, fp_session_take *take, fp_exporter *ex,
                      run_totals *t)
{
    char err[2048];
    int rc, status = FP_EXIT_OK;
    int64_t t0 = 0, wall0 = fp_now_ns(), last_report = wall0;
    int clock;
    while ((clock = fp_session_input_start(s, &t0)) == 0 && !fp_app_stop_requested())
        sleep_until(fp_now_ns() + 200000);
    bool input_clock = clock == 1;
    if (!input_clock) t0 = wall0;
    /* The take's time origin (timecode in) is the first frame's time; its soundtrack and stage
     * timecode (--audio, --timecode) are those at that time. */
    fp_app_audio_take_options(&a->audio, t0, &take->opt);
    fp_app_link_origin(a->link, t0);
    /* with --control the take starts when the control surface says (/fp/record/start) */
    if (a->take_dir && !a->sopt.control && !fp_app_stop_requested() &&
        (rc = fp_session_take_start(take, s, t0, err, sizeof err))) {
        fprintf(stderr, "facepuppet run: take: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_OUTPUT);
    }
    a->take_end_ns = t0;
    if (fp_session_take_recording(take) && (status = fp_app_audio_take_started(&a->audio, take, t0, "run")))
        return status;
    uint32_t said_take = 0; /* the take whose failed write was said */
    for (uint64_t k = 0; !fp_app_stop_requested(); k++) {
        int64_t now = t0 + (int64_t)llround((double)k * 1e9 / a->fps);
        if (input_clock) {
            for (int64_t w0 = fp_now_ns(), said = 0; !fp_session_inputs_ready(s, now) && !fp_app_stop_requested();) {
                sleep_until(fp_now_ns() + 200000);
                if (fp_now_ns() - w0 > (said + 1) * 3000000000LL) { /* every 3 s: who, and why */
                    char names[256];
                    said++;
                    if (fp_session_inputs_waiting(s, now, names, sizeof names))
                        fprintf(stderr, "facepuppet run: waiting %lld s for %s to deliver past %.3f s "
                                "(a forwarded recording: is its sender running?)\n", (long long)said * 3,
                                names, (double)(now - t0) * 1e-9);
                }
            }
            if (fp_app_stop_requested()) break;
        } else {
            sleep_until(now);
        }
        fp_app_link_before(a->link, now, k); /* the control surface's commands, answered */
        if (fp_app_link_quit(a->link)) break;
        fp_frame_stats st;
        fp_app_stop_step_begin(); /* (a frame stuck in a plugin is abandoned on a signal) */
        fp_session_step(s, now, &st);
        fp_app_stop_step_end();
        fp_app_link_after(a->link, now, k); /* status pushed, the frame streamed */
        totals_add(t, &st);
        say_take_failed(take, &said_take, k, (double)(now - t0) * 1e-9);
        a->take_end_ns = now + (int64_t)llround(1e9 / a->fps);
        if ((status = write_frame(s, a, ex, k, (double)(now - t0) * 1e-9))) break;
        /* the soundtrack up to the end of this frame (its samples follow the frames) */
        if ((status = fp_app_audio_advance(&a->audio, (double)(now - t0) * 1e-9 + 1.0 / a->fps, "run")))
            break;
        int64_t wall = fp_now_ns();
        if (!a->sopt.quiet && wall - last_report >= 1000000000LL) {
            fprintf(stderr, "  %6.1f s  frame %-6llu %s  %zu control vectors  update %.3f ms\n",
                    (now - t0) / 1e9, (unsigned long long)t->frames, st.active ? "deforming" : "idle     ",
                    st.control_vectors, st.update_ms);
            last_report = wall;
        }
        if (fp_session_finished(s)) break;
        if (a->sopt.duration_s > 0 && now - t0 >= (int64_t)(a->sopt.duration_s * 1e9)) break;
    }
    return status;
}

/* How far the final shape moved from the loaded one. */
typedef struct run_displacement {
    size_t n, moved;
    double sum, max;
    bool finite;
} run_displacement;

static run_displacement measure_displacement(const fp_session *s)
{
    const float *a = fp_session_loaded(s), *b = fp_session_positions(s);
    run_displacement d = {.n = fp_session_vertex_count(s), .finite = true};
    for (size_t v = 0; v < d.n; v++) {
        double dx = b[3 * v] - a[3 * v], dy = b[3 * v + 1] - a[3 * v + 1], dz = b[3 * v + 2] - a[3 * v + 2];
        double len = sqrt(dx * dx + dy * dy + dz * dz);
        if (!isfinite(len)) d.finite = false;
        d.sum += len;
        if (len > d.max) d.max = len;
        if (len > 0) d.moved++;
    }
    return d;
}

/* --out, with a status line on a terminal (a large face takes seconds to write, as its
 * opening). Returns FP_EXIT_OK or the exit status of a failed write; *dropped as
 * fp_session_save_ex. */
static int save_out(fp_session *s, const char *out, size_t n, bool quiet, unsigned *dropped)
{
    char err[2048];
    fp_app_open_progress writing;
    fp_app_open_progress_init(&writing, "facepuppet run", quiet);
    writing.phase = "writing";
    snprintf(writing.done, sizeof writing.done, "wrote %s", out);
    char what[600];
    snprintf(what, sizeof what, "%s (%zu vertices)", out, n);
    fp_app_open_progress_fn(&writing, what);
    int rc = fp_session_save_ex(s, out, dropped, err, sizeof err);
    fp_app_open_progress_fn(&writing, NULL);
    if (rc) {
        fprintf(stderr, "facepuppet run: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_OUTPUT);
    }
    return FP_EXIT_OK;
}

/* The summary line on stdout (the mesh's unit in mm: fp_session_head). */
static void print_summary(const fp_session *s, run_totals *t, const run_displacement *d,
                          int status, const char *out)
{
    double med = fp_median(t->update_ms, t->nupdates), mmu = fp_session_head(s)->mm_per_unit;
    char reach_text[400], why[160] = "";
    fp_app_reach_text(&t->reach, mmu, false, reach_text, sizeof reach_text);
    /* what held the skin back (step_contact.h's closing line, over the run) */
    if (t->collided && t->folded == t->collided)
        snprintf(why, sizeof why, "; each where the skin would have folded over");
    else if (t->folded)
        snprintf(why, sizeof why, "; %llu where the skin would have folded over, %llu where it would "
                 "have passed through itself", (unsigned long long)t->folded,
                 (unsigned long long)(t->collided - t->folded));
    printf("frames %llu, deforming %llu, engaged %llu, committed %llu; vertices moved %zu of %zu; "
           "displacement mean %.3g mm max %.3g mm (%.6g, %.6g mesh units of %.4g mm)%s; update median "
           "%.3f ms over %zu updates; "
           "fold-over guard acted on %llu frames (stopped short on %llu), min det J %.3g; "
           "contact guard scaled back %llu frames (least kept %.0f%%%s); events dropped %lu%s%s\n",
           (unsigned long long)t->frames, (unsigned long long)t->active_frames,
           (unsigned long long)t->engages, (unsigned long long)t->commits, d->moved, d->n,
           d->n ? d->sum / d->n * mmu : 0.0, d->max * mmu, d->n ? d->sum / d->n : 0.0, d->max, mmu,
           reach_text, med, t->nupdates, (unsigned long long)t->guarded,
           (unsigned long long)t->limited, t->active_frames ? t->min_det_j : 1.0,
           (unsigned long long)t->collided, 100.0 * t->collide_t, why, fp_session_dropped(s),
           status == FP_EXIT_OK ? "; wrote " : "", status == FP_EXIT_OK ? out : "");
}

/* What the run's end found, in the order it is said: an input's error (65), a take not
 * written whole, a record=FILE that failed (73), a mapping stopped for a fault (78), a
 * non-finite vertex (70). Returns the status the run exits with. */
static int final_status(fp_session *s, int status, int take_rc, const char *take_err,
                        bool record_failed, const char *record_err, bool finite)
{
    char err[2048];
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
    return status;
}

/* Open the session (plugins, mesh, rig) with the run's settings; says what it opened unless
 * -q. Returns 0 or the exit status (the message on stderr). */
static int open_session(run_args *a, fp_plugin_path *path, fp_session_take *take, fp_session **s)
{
    fp_session_options *so = &a->so;
    bool quiet = a->sopt.quiet;
    if (a->take_dir) { /* the session's record sink feeds the take recorder (fp_session_take.h) */
        so->record = fp_session_take_sink;
        so->record_user = take;
    }
    fp_app_plugin_path(path, a->sopt.plugin_dirs, a->sopt.nplugin_dirs);
    so->plugin_path = path;
    /* (input status, mapping and engine errors, recordings; -q: without the engine's notes) */
    so->log = quiet ? fp_app_log_line_quiet : fp_app_log_line;
    so->input_clock = true;
    so->measure_jacobian = true; /* min det J in the summary (the same shape, a slower path) */
    fp_app_open_progress opening; /* a large face takes a while: its steps on a terminal */
    fp_app_open_progress_init(&opening, "facepuppet run", quiet);
    so->progress = fp_app_open_progress_fn;
    so->progress_user = &opening;
    char err[2048];
    int rc = fp_session_create(so, s, err, sizeof err);
    so->progress = NULL; /* (opening lives in this frame only) */
    so->progress_user = NULL;
    if (rc) {
        fprintf(stderr, "facepuppet run: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    if (!quiet) {
        fprintf(stderr, "facepuppet run: %s, %zu vertices, rig %s, mapping %s, radius %.4g, %zu input(s); "
                "scale: %.4g mm per mesh unit (%s)\n", so->mesh_path, fp_session_vertex_count(*s),
                fp_session_rig_how(*s), so->mapping, fp_session_radius(*s), so->input_count,
                fp_session_head(*s)->mm_per_unit, fp_session_head(*s)->how);
    }
    return 0;
}

/* What the watchdog's take-over (app_stop.h) ends when a signal finds the frame loop stuck
 * in a frame: all of it the loop's, which waits inside fp_session_step meanwhile. */
typedef struct run_stuck {
    fp_session *s;
    run_args *a;
    fp_session_take *take;
    fp_exporter **ex;
} run_stuck;

/* fp_app_stop_fn: the take closed (sealed first: the stuck frame, should it end, records
 * nothing), the soundtrack and --export finished, --out written when the frame is stuck in
 * a plugin (the shown mesh is then the last whole frame's; elsewhere the frame may be
 * writing it). [the watchdog thread] */
static void run_take_over(void *user, int sig, bool in_plugin)
{
    run_stuck *c = user;
    const bool quiet = c->a->sopt.quiet;
    (void)sig;
    if (fp_session_take_recording(c->take)) {
        fp_session_take_seal(c->take);
        fp_session_take_result tr;
        char err[1024] = "";
        if (fp_session_take_stop(c->take, &tr, err, sizeof err))
            fprintf(stderr, "facepuppet run: the take was not written whole: %s\n", err);
        fp_app_print_take(stderr, "facepuppet run", &tr);
    }
    fp_app_audio_take_stopped(&c->a->audio, c->a->take_end_ns, "run", quiet);
    fp_app_audio_finish(&c->a->audio, "run", quiet);
    if (*c->ex)
        fp_app_export_close("facepuppet run", "--export", c->ex, c->a->export_fmt, c->a->export_file,
                            0.1, quiet, stderr);
    if (!in_plugin) {
        fprintf(stderr, "facepuppet run: %s not written (the frame was not in a plugin)\n", c->a->out);
        return;
    }
    unsigned dropped = 0;
    if (save_out(c->s, c->a->out, fp_session_vertex_count(c->s), quiet, &dropped) == FP_EXIT_OK && !quiet)
        fprintf(stderr, "facepuppet run: wrote %s (the last whole frame)\n", c->a->out);
}

/* An end before the frames: what run_main opened so far released (each takes NULL), the
 * soundtrack's output discarded, a freed; returns status. */
/* A run refused before its first frame: what it made taken away (an empty --frames-out folder it
 * made; the export's temporary file), a that was settled freed. */
static int run_abandon(run_args *a, fp_exporter **ex, fp_session **s, fp_plugin_path *path, int status)
{
    if (a->frames_out_made) rmdir(a->frames_out);
    fp_export_abort(ex);
    fp_session_destroy(s);
    fp_plugin_path_clear(path);
    fp_audio_out_abort(&a->audio.out);
    fp_app_audio_finish(&a->audio, "run", true);
    fp_app_over_free(&a->over);
    free(a);
    return status;
}

static int run_main(int argc, char **argv)
{
    run_args *a = calloc(1, sizeof *a); /* (the defaults' strings: some 40 kB) */
    if (!a) {
        fprintf(stderr, "facepuppet run: out of memory\n");
        return FP_EXIT_SOFTWARE;
    }
    int rc = run_parse(argc, argv, a); /* (-1: go on; 0 after --help) */
    if (rc >= 0 || (rc = run_settle(a)) ||
        (rc = fp_app_audio_prepare(&a->audio, "run", NULL, a->force))) { /* before any work */
        if (a->frames_out_made) rmdir(a->frames_out);
        free(a);
        return rc;
    }
    const bool quiet = a->sopt.quiet;
    fp_session_take take;
    fp_session_take_options take_opt = {.dir = a->take_dir, .slate = a->slate,
                                        .description = a->take_desc, .rate = fp_app_take_rate(a->fps)};
    fp_session_take_init(&take, &take_opt, &a->so);
    fp_plugin_path path;
    fp_session *s = NULL;
    fp_exporter *ex = NULL; /* --export: every frame into one animation file (core/export) */
    char err[2048];
    /* the frames written, when known before the run (--duration): the outputs' sizes checked */
    const double frames = a->sopt.duration_s > 0 ? ceil(a->sopt.duration_s * a->fps) + 1 : 0;
    if ((rc = open_session(a, &path, &take, &s)) ||
        (rc = fp_app_over_check_mesh(&a->over, "facepuppet run", s, a->so.mesh_path)) ||
        (a->frames_out && (rc = fp_app_frames_estimate("facepuppet run", "--frames-out", a->frames_out,
                                                       frames, a->fps, fp_session_mesh(s), quiet,
                                                       "a shorter --duration"))) ||
        (a->export_file && (rc = fp_app_export_open("facepuppet run", a->export_file, s,
                                                    fp_session_head(s)->mm_per_unit, "run", frames,
                                                    &ex))) ||
        (a->frames_out && a->force && (rc = fp_app_frames_out_clear("facepuppet run", a->frames_out, quiet)))) {
        return run_abandon(a, &ex, &s, &path, rc);
    }
    if ((rc = fp_session_start(s, err, sizeof err))) {
        fprintf(stderr, "facepuppet run: %s\n", err);
        return run_abandon(a, &ex, &s, &path, fp_app_exit_code(rc, FP_APP_INPUT));
    }
    fp_app_link_options lo = {.cmd = "run", .control = a->sopt.control, .stream = a->sopt.stream,
                              .s = s, .mesh_path = a->so.mesh_path, .take = a->take_dir ? &take : NULL,
                              .plugin_path = &path, .fps = a->fps, .quiet = quiet, .touched = true};
    if ((rc = fp_app_link_open(&lo, &a->link))) return run_abandon(a, &ex, &s, &path, rc);
    fp_app_link_set_take_hook(a->link, run_control_take, a);
    /* SIGINT, SIGTERM: the loop ends after the frame; a frame stuck in a plugin is abandoned */
    run_stuck stuck = {s, a, &take, &ex};
    if ((rc = fp_app_stop_install("facepuppet run", run_take_over, &stuck)))
        fprintf(stderr, "facepuppet run: warning: no watchdog for a stuck plugin: %s\n", strerror(-rc));
    run_totals t;
    totals_init(&t);
    int status = run_frames(s, a, &take, ex, &t);
    fp_app_stop_loop_end();
    if (fp_app_stop_requested() && !quiet) fprintf(stderr, "facepuppet run: interrupted; saving what was done\n");
    /* Close the take: a failed write (ENOSPC) fails the run with 73. */
    int take_rc = 0;
    char take_err[1024] = "";
    if (fp_session_take_recording(&take)) {
        fp_session_take_result tr;
        take_rc = fp_session_take_stop(&take, &tr, take_err, sizeof take_err);
        fp_app_print_take(stderr, "facepuppet run", &tr);
        int in_status = fp_app_audio_take_stopped(&a->audio, a->take_end_ns, "run", quiet);
        if (status == FP_EXIT_OK) status = in_status;
        if (a->over.over && !take_rc && tr.frames) { /* the pass on top of a new stack */
            int st = fp_app_over_finish(&a->over, "facepuppet run", a->take_dir, tr.path,
                                        take.header.slate); /* (the take's: --slate or /fp/record/start's) */
            if (status == FP_EXIT_OK) status = st;
        }
    }
    int audio_status = fp_app_audio_finish(&a->audio, "run", quiet); /* (a file renamed into place) */
    if (status == FP_EXIT_OK) status = audio_status;
    if (status == FP_EXIT_OK) status = a->control_status;
    fp_app_over_free(&a->over);
    /* Close the record=FILE recordings: a failed write must fail the run. */
    char record_err[1024] = "";
    bool record_failed = fp_session_stop(s, record_err, sizeof record_err) != 0;
    /* The summary: displacement of the final shape from the loaded one. */
    const run_displacement d = measure_displacement(s);
    unsigned dropped = 0;
    if (status == FP_EXIT_OK) {
        const int out_status = save_out(s, a->out, d.n, quiet, &dropped);
        fp_app_print_dropped("facepuppet run", a->out, dropped, quiet);
        /* the export is finished even when --out could not be written: each output stands alone */
        const int ex_status = ex ? fp_app_export_close("facepuppet run", "--export", &ex, a->export_fmt,
                                                       a->export_file, 0.1, quiet, stderr) : FP_EXIT_OK;
        status = out_status ? out_status : ex_status;
    }
    fp_export_abort(&ex);
    print_summary(s, &t, &d, status, a->out);
    status = final_status(s, status, take_rc, take_err, record_failed, record_err, d.finite);
    fp_app_link_close(&a->link);
    free(t.update_ms);
    fp_app_reach_free(&t.reach);
    fp_app_stop_uninstall();
    fp_session_destroy(&s);
    fp_plugin_path_clear(&path);
    free(a);
    return status;
}

const fp_command fp_command_run = {"run", "run a headless session (no options: the demo)", run_main};
