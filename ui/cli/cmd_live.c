/* facepuppet live: perform with the face in a window (the viewer, ui/viewer). Compiled in
 * where the viewer is built (FP_BUILD_UI, GLFW and epoxy found: ui/cli/CMakeLists.txt
 * defines FP_HAVE_UI); elsewhere the command says it is not built. */
#define _GNU_SOURCE
#include "app_getopt.h"
#include "command.h"

#include <stdio.h>

#ifdef FP_HAVE_UI
#include "app_audio.h"
#include "app_stop.h"
#include "app_link.h"
#include "fp_clock.h"
#include "app_util.h"
#include "app_stack.h"
#include "fp_error.h"
#include "fp_file.h"
#include "fp_session.h"
#include "fp_viewer.h"
#include "session_opts.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define LIVE_SCRIPT_MAX ((size_t)1 << 20) /* --script @FILE: bytes at most */

static void usage(FILE *f)
{
    fprintf(f,
        "usage: facepuppet live [--mesh FILE] [--input SPEC]... [--mapping SPEC] [--radius R]\n"
        "                       [--speed X] [--size WxH] [--frames N] [--screenshot FILE.png]\n"
        "                       [--script TEXT|@FILE] [--gpu-warp] [--vsync] [--out FILE [--force]]\n"
        "                       [--audio FILE [--audio-out SPEC] [--audio-offset S]] [--timecode SRC]\n"
        "                       [--audio-in DEVICE]\n\n"
        "Perform with the face in a window: the inputs drive the mapping, the mapping drives\n"
        "the CSRBF engine, the face deforms as you watch. With no mesh and no input it plays\n"
        "the demo: the ICT face and the three-claps recording.\n\n"
        "Session options (shared with `facepuppet run`):\n");
    fp_session_opts_help(f);
    fprintf(f,
        "Options of live:\n"
        "  -o, --out FILE         write the final shape when the window closes (a file that\n"
        "                         exists is refused before the window opens, exit 73)\n"
        "      --force            overwrite an --out or --screenshot that exists\n"
        "      --size WxH         window size (default 1280x720)\n"
        "      --frames N         stop after N frames\n"
        "      --screenshot FILE  write the last frame as PNG (with --frames N: run N frames,\n"
        "                         write, exit; FILE ends in .png, and one that exists is\n"
        "                         refused as --out is)\n"
        "      --script TEXT      scripted actions, or @FILE to read them from FILE:\n"
        "                         'wait hands|end|frames N|seconds S; key K; shot FILE;\n"
        "                         radius R; drop FILE; print hud|messages; close' (seconds\n"
        "                         on the wall clock, which inputs keep, frames as drawn;\n"
        "                         docs/architecture.md, the viewer)\n"
        "      --gpu-warp         evaluate the warp in the vertex shader (with a rig: its pose\n"
        "                         and blend weights from the CPU, the warp on the GPU); checked\n"
        "                         against the CPU engine by transform feedback (reported at\n"
        "                         exit); frames it cannot draw (the contact guard's) come from\n"
        "                         the CPU, the reason said once\n"
        "      --vsync            wait for the display (default: never, swap interval 0)\n"
        "      --take-dir DIR     T (or the pedal's middle button) records takes in DIR (made\n"
        "                         with its parents when missing; checked before the window)\n"
        "      --slate NAME       the takes' slate (default \"scene1\"); numbers go up per slate\n"
        "      --countdown S      count S seconds down before a take starts\n"
        "      --over STACK_OR_TAKE  overdub: each take is a pass over it (needs --take-dir):\n"
        "                         T plays it from its start under you (pre-roll), I or the\n"
        "                         pedal punches in, then out, T (or the pedal) stops; a new\n"
        "                         stack SLATE_SNNN.fpstack holds the pass on top (docs/stack.md)\n"
        "      --layer REGION[:MODE]  the passes' region and mode (default mouth:replace; see\n"
        "                         facepuppet run --help)\n");
    fp_app_audio_help(f, true);
    fprintf(f,
        "  With --take-dir the soundtrack plays from --audio-offset at each take's start (as the\n"
        "  stack of --over does) until it stops; without, from the first frame on. An LTC file's\n"
        "  first sample is the first take's start.\n"
        "  -h, --help             this text\n\n"
        "Keys: space pause, E engage, C commit, X cancel, Z undo, R reset, 1 anchored,\n"
        "2 unanchored, [ ] radius, W wireframe, S screenshot, F frame, H hands, Tab HUD,\n"
        "J / K open / close the jaw (a rig's jaw.open), G the rig (regions, landmarks, hinge),\n"
        "? keys, Esc quit (in a review: back to live), T take start/stop, V review the last\n"
        "take (again: back to live; so does the next engage), P play/pause it, , . a frame\n"
        "back/on. The HUD's badge: idle grey, committed teal, ENGAGED green, LIMITED amber\n"
        "(the fold-over guard stopped the gesture short: fingertips converging onto one point),\n"
        "HELD pink (the contact guard scaled the last frame back: the skin would have\n"
        "crossed or folded over), PAUSED white, REC red, PLAYING blue, REVIEW purple; fingertip\n"
        "spheres turn green where they reach the skin, a line joins each to its nearest skin\n"
        "point.\n"
        "I punches in, then out, in a take over a stack (--over); so does the pedal. L selects\n"
        "a layer of that stack, M mutes it, O solos it (the stack under you plays so, and the\n"
        "new stack records it). Lanes above the strip: a layer each, the pass with its punch\n"
        "points, and the soundtrack's waveform (--audio).\n"
        "Mouse: left orbit (on the take strip: scrub), right pan, wheel zoom. Drop a mesh.\n"
        "Script: also 'scrub F' (the take strip at fraction F), 'camera YAW PITCH [ZOOM]'\n"
        "(degrees; the framed view turned, as export's --camera), 'size WxH' (the window\n"
        "resized; the framing is kept), 'wait reload' (until the mapping's file was reloaded,\n"
        "or failed to), 'print mapping' (a line: the mapping's name, id, version), keys J K G.\n"
        "At exit it prints the frame time and the input-event-to-frame latency (median, in ms\n"
        "and in frames, p99; a replay's or take's events from when they arrive, whatever its\n"
        "speed=); the HUD shows the same lag over the last second beside the frame time.\n\n"
        "SIGINT (Ctrl-C) or SIGTERM ends the session as closing the window does (a take\n"
        "recording closed, --out written; exit 0; while the session opens, at once); a frame\n"
        "stuck 0.1 s in a plugin call that never returns is abandoned (the take closed with\n"
        "the frames before it, --out of the last whole frame, exit 128 + the signal: 130,\n"
        "143), as in facepuppet run.\n\n"
        "Exit status: 0 done, 64 usage (an unknown audio device too), 65 bad input data, 66 input\n"
        "or display missing (a soundtrack, LTC or --audio-in file too),\n"
        "73 output not writable, 78 plugin missing or incompatible, 130/143 ended by\n"
        "SIGINT/SIGTERM with a plugin stuck, 1 other failure\n"
        "(facepuppet --help has the whole table).\n");
}

/* What the watchdog's take-over (app_stop.h) ends when a signal finds a frame stuck: the
 * session and the take the viewer gave (fp_viewer_options.opened), --out. */
typedef struct live_stuck {
    fp_session *s;
    fp_session_take *take;
    const char *out;
    bool quiet;
    bool installed;    /* app_stop's handlers, from the session's first opening on */
    fp_app_link_options link_opt;  /* --control, --stream: opened with the session */
    fp_app_link *link;
    int link_status;   /* the link's open failure: the exit status */
    uint64_t frame;
} live_stuck;

static live_stuck *live_current; /* (stop_requested takes no user: /fp/quit ends the loop) */

static bool live_stop_requested(void)
{
    return fp_app_stop_requested() || (live_current && (fp_app_link_quit(live_current->link) ||
                                                        live_current->link_status));
}

static void live_frame_begin(void *user, int64_t now_ns)
{
    live_stuck *c = user;
    fp_app_link_before(c->link, now_ns, c->frame);
}

static void live_frame_end(void *user, int64_t now_ns)
{
    live_stuck *c = user;
    fp_app_link_after(c->link, now_ns, c->frame++);
}

/* Paused (space): the commands answered and the status pushed, as between frames (before,
 * nothing was answered until the performer went on). */
static void live_frame_paused(void *user, int64_t now_ns)
{
    live_stuck *c = user;
    fp_app_link_before(c->link, now_ns, c->frame);
    fp_app_link_idle(c->link, now_ns, c->frame);
}

static void live_take_over(void *user, int sig, bool in_plugin);

/* fp_viewer_options.opened: the session and take for the take-over; the first time, the
 * handlers (a signal while the window and the session open still ends the process at once,
 * as before). [the viewer's thread, between frames] */
static void live_opened(void *user, fp_session *s, struct fp_session_take *take)
{
    live_stuck *c = user;
    c->s = s;
    c->take = take;
    if ((c->link_opt.control || c->link_opt.stream) && !c->link_status) {
        c->link_opt.s = s;
        c->link_opt.take = take && take->opt.dir ? take : NULL;
        if (c->link) { /* a dropped mesh: the control surface stays (its port, its subscribers),
                        * the stream opens again on the new mesh, named by its path */
            if (take && take->so && take->so->mesh_path) c->link_opt.mesh_path = take->so->mesh_path;
            c->link_status = fp_app_link_reopen(c->link, s, c->link_opt.take, c->link_opt.mesh_path, fp_now_ns());
            if (!c->link_status && c->link_opt.stream)
                fprintf(stderr, "facepuppet live: --stream opened again on the new mesh\n");
        } else if ((c->link_status = fp_app_link_open(&c->link_opt, &c->link)) == 0) {
            fp_app_link_origin(c->link, fp_now_ns());
        }
    }
    if (c->installed) return;
    c->installed = true;
    int rc = fp_app_stop_install("facepuppet live", live_take_over, c);
    if (rc) fprintf(stderr, "facepuppet live: warning: no watchdog for a stuck plugin: %s\n", strerror(-rc));
}

/* fp_app_stop_fn: the take closed (sealed first), --out written when the frame is stuck in
 * a plugin (the shown mesh is the last whole frame's). [the watchdog thread] */
static void live_take_over(void *user, int sig, bool in_plugin)
{
    live_stuck *c = user;
    (void)sig;
    if (c->take) {
        fp_session_take_seal(c->take);
        if (fp_session_take_recording(c->take)) {
            fp_session_take_result tr;
            char err[1024] = "";
            if (fp_session_take_stop(c->take, &tr, err, sizeof err))
                fprintf(stderr, "facepuppet live: the take was not written whole: %s\n", err);
            fp_app_print_take(stderr, "facepuppet live", &tr);
        }
    }
    if (!c->out || !c->s) return;
    char err[2048];
    if (!in_plugin)
        fprintf(stderr, "facepuppet live: %s not written (the frame was not in a plugin)\n", c->out);
    else if (fp_session_save(c->s, c->out, err, sizeof err))
        fprintf(stderr, "facepuppet live: %s\n", err);
    else if (!c->quiet)
        fprintf(stderr, "facepuppet live: wrote %s (the last whole frame)\n", c->out);
}

/* The soundtrack, the microphone and the stage timecode (--audio, --audio-in, --timecode)
 * through the viewer's hooks (fp_viewer_sound). [the viewer's thread] */
typedef struct live_sound {
    fp_app_audio audio;
    bool takes;          /* --take-dir: the soundtrack plays with each take */
    bool quiet;
    bool running;        /* the soundtrack advancing from origin */
    bool recording;      /* a take records */
    int64_t origin;      /* host time of the soundtrack's --audio-offset */
    int64_t end_ns;      /* the end of the take's last frame */
    int status;          /* the first failure's exit status */
} live_sound;

#define LIVE_PERIOD_NS 16666667 /* a frame's end: one 60 fps period after its time */

static void sound_fail(live_sound *l, int status)
{
    if (status && !l->status) l->status = status;
}

static void sound_starting(void *user, int64_t origin_ns, fp_session_take_options *o)
{
    live_sound *l = user;
    if (l->audio.have_ltc && !l->audio.ltc.at_ns) l->audio.ltc.at_ns = origin_ns; /* (a file's) */
    fp_app_audio_take_options(&l->audio, origin_ns, o);
    if (!l->takes) return;
    fp_app_audio_restart(&l->audio);
    l->origin = origin_ns;
    l->running = true;
}

static void sound_started(void *user, const fp_session_take *take, int64_t origin_ns)
{
    live_sound *l = user;
    l->recording = true;
    l->end_ns = origin_ns;
    sound_fail(l, fp_app_audio_take_started(&l->audio, take, origin_ns, "live"));
}

static void sound_stopped(void *user)
{
    live_sound *l = user;
    if (!l->recording) return;
    l->recording = false;
    sound_fail(l, fp_app_audio_take_stopped(&l->audio, l->end_ns, "live", l->quiet));
    if (!l->takes || !l->running) return;
    sound_fail(l, fp_app_audio_advance_live(&l->audio, (double)(l->end_ns - l->origin) * 1e-9, "live"));
    l->running = false; /* (silence until the next take) */
}

static void sound_frame(void *user, int64_t now_ns)
{
    live_sound *l = user;
    if (!l->takes && !l->running) {
        l->origin = now_ns;
        l->running = true;
    }
    if (l->recording) l->end_ns = now_ns + LIVE_PERIOD_NS;
    if (l->running && !l->status)
        sound_fail(l, fp_app_audio_advance_live(&l->audio, (double)(now_ns + LIVE_PERIOD_NS - l->origin) * 1e-9, "live"));
}

/* The soundtrack, the timecode and the microphone, before the window, and the viewer's hooks.
 * Returns 0 or the exit status (66, 65, 64, 73; --audio-in without --take-dir: 64). */
static int sound_prepare(live_sound *l, fp_viewer_options *vo, bool quiet)
{
    if (l->audio.in_spec && !vo->take_dir) {
        fprintf(stderr, "facepuppet live: --audio-in records beside a take: give --take-dir\n");
        return FP_EXIT_USAGE;
    }
    int rc = fp_app_audio_prepare(&l->audio, "live", NULL, false);
    if (rc) return rc;
    l->takes = vo->take_dir != NULL;
    l->quiet = quiet;
    vo->sound = (fp_viewer_sound){sound_starting, sound_started, sound_stopped, sound_frame, l,
                                  l->audio.playing ? &l->audio.track : NULL, l->audio.offset_s};
    return 0;
}

/* --control, --stream: opened with the session (live_opened), the frames bracketed, /fp/quit
 * ending the loop (vo->stop_requested). */
static void live_link_setup(live_stuck *c, fp_viewer_options *vo, const fp_session_opts *sopt,
                            const fp_plugin_path *path)
{
    c->link_opt = (fp_app_link_options){.cmd = "live", .control = sopt->control, .stream = sopt->stream,
                                        .mesh_path = sopt->session->mesh_path, .plugin_path = path,
                                        .fps = 60, .quiet = sopt->quiet};
    live_current = c;
    vo->stop_requested = live_stop_requested;
    vo->frame_begin = live_frame_begin;
    vo->frame_end = live_frame_end;
    vo->frame_paused = live_frame_paused;
}

/* --script @FILE: the file's text into *text (the caller frees it); TEXT itself: *text NULL.
 * A regular file of 1 MiB at most, never a FIFO waited on. Returns 0 or the exit status (said). */
static int read_script(const char *arg, char **text)
{
    *text = NULL;
    if (!arg || arg[0] != '@') return 0;
    size_t len;
    int code = fp_file_read_all(arg + 1, LIVE_SCRIPT_MAX, text, &len);
    if (!code) return 0;
    fprintf(stderr, "facepuppet live: --script %s: %s\n", arg + 1,
            code == -EFBIG ? "larger than 1 MiB" : fp_file_error_text(code));
    return fp_app_exit_code(code == -EFBIG ? -EBADMSG : code, FP_APP_INPUT);
}

/* The measurements at exit, on stdout. */
static void print_report(const fp_viewer_report *r, bool gpu_warp)
{
    if (!r->frames) return;
    printf("frames %llu; frame time median %.2f ms, p99 %.2f ms; event-to-frame latency median "
           "%.2f ms (%.1f frames), p99 %.2f ms over %zu events; engine update median %.3f ms; "
           "events dropped %lu\n",
           (unsigned long long)r->frames, r->frame_ms_median, r->frame_ms_p99,
           r->latency_ms_median, r->latency_frames_median, r->latency_ms_p99, r->latency_samples,
           r->engine_ms_median, r->dropped);
    printf("upload (normals + GL) median %.3f ms, p99 %.3f ms over %zu frames that changed "
           "(all frames: median %.3f ms, p99 %.3f ms)", r->upload_ms_median, r->upload_ms_p99,
           r->uploads, r->upload_all_ms_median, r->upload_all_ms_p99);
    if (r->upload_checked)
        printf("; %lu partial uploads checked, %lu differ from the whole", r->upload_checked,
               r->upload_mismatches);
    printf("\n");
    if (gpu_warp)
        printf("gpu-warp: %zu checks against the CPU engine; max |GPU - CPU| %.3g mesh units, "
               "%.3g of the max displacement %.4g; %zu frames drawn from the CPU\n", r->warp_checks,
               r->warp_max_error,
               r->warp_max_displacement > 0 ? r->warp_max_error / r->warp_max_displacement : 0.0,
               r->warp_max_displacement, r->warp_cpu_frames);
}


/* --screenshot FILE's usage, before the window: a PNG's name (x.jpg holding PNG data would
 * mislead every viewer), and a run that ends (--frames N or a --script that closes).
 * 0 or FP_EXIT_USAGE, said. */
static int screenshot_usage(const char *path, bool ends)
{
    if (!path) return 0;
    size_t k = strlen(path);
    if (k < 4 || strcasecmp(path + k - 4, ".png")) {
        fprintf(stderr, "facepuppet live: --screenshot %s: a screenshot is a PNG; name it FILE.png\n", path);
        return FP_EXIT_USAGE;
    }
    if (!ends) {
        fprintf(stderr, "facepuppet live: --screenshot needs --frames N (or a --script that closes)\n");
        return FP_EXIT_USAGE;
    }
    return 0;
}
static int live_main(int argc, char **argv)
{
    enum { OPT_SIZE = FP_SESSION_OPTS_FIRST_FREE, OPT_FRAMES, OPT_SHOT, OPT_SCRIPT, OPT_GPU,
           OPT_VSYNC, OPT_TAKE_DIR, OPT_SLATE, OPT_COUNTDOWN, OPT_OVER, OPT_LAYER, OPT_FORCE };
    static const struct option own[] = {
        {"out", required_argument, 0, 'o'},        {"force", no_argument, 0, OPT_FORCE},
        {"size", required_argument, 0, OPT_SIZE},  {"frames", required_argument, 0, OPT_FRAMES},
        {"screenshot", required_argument, 0, OPT_SHOT}, {"script", required_argument, 0, OPT_SCRIPT},
        {"gpu-warp", no_argument, 0, OPT_GPU},     {"vsync", no_argument, 0, OPT_VSYNC},
        {"take-dir", required_argument, 0, OPT_TAKE_DIR}, {"slate", required_argument, 0, OPT_SLATE},
        {"countdown", required_argument, 0, OPT_COUNTDOWN},
        {"over", required_argument, 0, OPT_OVER}, {"layer", required_argument, 0, OPT_LAYER},
        {"help", no_argument, 0, 'h'},             {0, 0, 0, 0}};
    struct option opts[FP_SESSION_OPTS_COUNT + FP_APP_AUDIO_OPTS_COUNT + sizeof own / sizeof own[0]];
    size_t nshared = fp_session_opts_longopts(opts);
    nshared += fp_app_audio_longopts(opts + nshared, true);
    memcpy(opts + nshared, own, sizeof own);
    static live_sound snd; /* (static: its strings are some 9 kB) */
    memset(&snd, 0, sizeof snd);
    fp_viewer_options vo = {0};
    fp_session_options *so = &vo.session;
    fp_session_opts sopt;
    fp_session_opts_init(&sopt, so);
    const char *script_arg = NULL;
    bool force = false;
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, FP_SESSION_OPTS_SHORT "o:h", opts)) != -1;) {
        int shared = fp_session_opts_parse(&sopt, c, optarg, "live");
        if (shared < 0) return fp_app_exit_code(shared, FP_APP_INPUT);
        if (shared) continue;
        int audio = fp_app_audio_parse(&snd.audio, c, optarg, "live");
        if (audio > 1) return audio;
        if (audio) continue;
        switch (c) {
        case 'o': vo.out = optarg; break;
        case OPT_FORCE: force = true; break;
        case OPT_SIZE:
            if (!fp_app_parse_size(optarg, 16, 16384, &vo.width, &vo.height)) {
                fprintf(stderr, "facepuppet live: --size must be WxH (16..16384), got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_FRAMES: {
            unsigned long long n;
            if (!fp_parse_whole(optarg, UINT64_MAX, &n) || !n) {
                fprintf(stderr, "facepuppet live: --frames must be a whole number > 0, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            vo.frames = n;
            break;
        }
        case OPT_SHOT: vo.screenshot = optarg; break;
        case OPT_SCRIPT: script_arg = optarg; break;
        case OPT_GPU: vo.gpu_warp = true; break;
        case OPT_VSYNC: vo.vsync = true; break;
        case OPT_TAKE_DIR: vo.take_dir = optarg; break;
        case OPT_SLATE:
            if (!fp_take_slate_valid(optarg)) {
                fprintf(stderr, "facepuppet live: --slate '%s': use 1-63 of A-Z a-z 0-9 . _ -\n", optarg);
                return FP_EXIT_USAGE;
            }
            vo.slate = optarg;
            break;
        case OPT_COUNTDOWN: {
            if (!fp_parse_decimal(optarg, &vo.countdown_s) || !(vo.countdown_s >= 0 && vo.countdown_s <= 60)) {
                fprintf(stderr, "facepuppet live: --countdown must be 0..60 seconds, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        }
        case OPT_OVER: vo.over = optarg; break;
        case OPT_LAYER: vo.layer = optarg; break;
        case 'h': usage(stdout); return FP_EXIT_OK;
        default: usage(stderr); return FP_EXIT_USAGE;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "facepuppet live: unexpected argument '%s'\n", argv[optind]);
        return FP_EXIT_USAGE;
    }
    fp_app_over over = {.over = vo.over, .layer = vo.layer}; /* checked before the window */
    int orc = fp_app_over_check(&over, "facepuppet live", vo.take_dir);
    if (!orc && snd.audio.path && !snd.audio.offset_given) /* the line where the base heard it */
        fp_app_over_soundtrack_offset(&over, &snd.audio.offset_s);
    if (!orc) orc = fp_app_link_check("live", sopt.control, sopt.stream);
    if (!orc && vo.take_dir) orc = fp_app_check_take_dir("facepuppet live", vo.take_dir);
    /* an --out or --screenshot that exists is refused before the window (README: no command overwrites a
     * file without being asked) */
    if (!orc && vo.out) orc = fp_app_check_new_output("facepuppet live", "--out", vo.out, force);
    if (!orc && vo.screenshot)
        orc = fp_app_check_new_output("facepuppet live", "--screenshot", vo.screenshot, force);
    fp_app_over_free(&over);
    if (orc) return orc;
    vo.duration_s = sopt.duration_s;
    vo.quiet = sopt.quiet;
    if ((orc = screenshot_usage(vo.screenshot, vo.frames || script_arg))) return orc;
    /* The demo when no mesh and no input are given; --speed for replay inputs; a take of
     * several inputs: one take input for each of them. */
    fp_app_inputs inputs_buf;
    if ((orc = fp_app_session_defaults("facepuppet live", so, sopt.speed, &inputs_buf, NULL)))
        return orc;
    /* the files the session reads, named before the window can fail for want of a display */
    if ((orc = fp_app_check_input_files("facepuppet live", so))) return orc;
    char *script_text = NULL;
    if ((orc = read_script(script_arg, &script_text))) return orc;
    vo.script = script_text ? script_text : script_arg;
    int arc = sound_prepare(&snd, &vo, sopt.quiet); /* before the window */
    if (arc) {
        free(script_text);
        return arc;
    }

    fp_plugin_path path;
    fp_app_plugin_path(&path, sopt.plugin_dirs, sopt.nplugin_dirs);
    so->plugin_path = &path;
    fp_app_open_progress opening; /* a large face takes a while: its steps on a terminal */
    fp_app_open_progress_init(&opening, "facepuppet live", sopt.quiet);
    so->progress = fp_app_open_progress_fn;
    so->progress_user = &opening;
    char err[2048] = "";
    fp_viewer_report rep = {0};
    /* SIGINT, SIGTERM, once the session is open: the loop ends before the next frame; a frame
     * stuck in a plugin is abandoned (app_stop.h) */
    live_stuck stuck = {.out = vo.out, .quiet = sopt.quiet};
    live_link_setup(&stuck, &vo, &sopt, &path);
    vo.step_begin = fp_app_stop_step_begin;
    vo.step_end = fp_app_stop_step_end;
    vo.opened = live_opened;
    vo.user = &stuck;
    int rc = fp_viewer_run(&vo, &rep, err, sizeof err);
    fp_app_stop_uninstall(); /* (nothing when never installed) */
    fp_app_link_close(&stuck.link);
    live_current = NULL;
    int status = stuck.link_status;
    if (rc) {
        fprintf(stderr, "facepuppet live: %s\n", err);
        /* fp_viewer_run's codes: the session's (inputs), -ENODEV no display, -EINVAL a bad
         * script, -EIO a screenshot or --out not written: all in the one table. */
        status = fp_app_exit_code(rc, FP_APP_INPUT);
    }
    sound_stopped(&snd); /* (a take the watchdog closed) */
    int astatus = fp_app_audio_finish(&snd.audio, "live", sopt.quiet);
    if (status == FP_EXIT_OK) status = snd.status ? snd.status : astatus;
    print_report(&rep, vo.gpu_warp);
    free(script_text);
    fp_plugin_path_clear(&path);
    return status;
}

#else /* !FP_HAVE_UI */

static int live_main(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "facepuppet live: not built: this facepuppet was configured without the viewer "
                    "(FP_BUILD_UI=OFF); use `facepuppet run`\n");
    return FP_EXIT_UNAVAILABLE;
}

#endif /* FP_HAVE_UI */

const fp_command fp_command_live = {"live", "perform with the face in a window (no options: the demo)",
                                    live_main};
