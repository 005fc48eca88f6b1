/* facepuppet play: a take's frames again, from its stored control sets (no input devices,
 * no mapping): bit-identical to the frames the recording session showed. */
#define _GNU_SOURCE
#include "app_getopt.h"
#include "app_util.h"
#include "command.h"
#include "fp_session.h"
#include "fp_session_take.h"
#include "fp_take_player.h"
#include "fp_stack_player.h"
#include "app_stack.h"
#include "app_export.h"
#include "app_audio.h"
#include "app_link.h"
#include "fp_clock.h"
#include "fp_mesh.h"
#include "fp_text.h"

#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static void usage(FILE *f)
{
    fprintf(f,
        "usage: facepuppet play TAKE|STACK [--frames-out DIR] [--out FILE] [--export FILE]\n"
        "                            [--mesh FILE] [--force] [--audio FILE] [--audio-out SPEC]\n"
        "                            [--audio-offset S]\n\n"
        "Reproduce a take's frames from the control sets it stored (no input devices, no\n"
        "mapping): the take's mesh (checked against the crc32 in the take), each frame's\n"
        "control set through the same engine step (fold-over guard included), commits,\n"
        "undo and reset as recorded. The meshes are bit-identical to the recording run's.\n"
        "A STACK (.fpstack, docs/stack.md) plays every layer's take and composes them per\n"
        "vertex by region, mode, range, gain, mute and solo (the base's frames are its clock).\n\n"
        "  -o, --out FILE         the last frame's mesh (default: none); format by extension\n"
        "      --frames-out DIR   one mesh per frame, DIR/frame_NNNNNN_tS.SSSs.obj (session\n"
        "                         frame number, time since the take's timecode in); its size\n"
        "                         is said before any frame (a warning over 1 GiB)\n"
        "      --export FILE      every frame into FILE: .gltf/.glb (morph-target animation,\n"
        "                         0.1 mm), .pc2/.mdd (point caches); see facepuppet export\n"
        "                         (a point cache over 1 GiB is a warning; --frames-out and a\n"
        "                         point cache larger than the room free where they go are\n"
        "                         refused before any frame, 73)\n"
        "      --force            overwrite outputs that exist (--out, --export, frames in\n"
        "                         --frames-out: an earlier run's frames there are removed\n"
        "                         before the first); without it they are refused before any work\n"
        "  -m, --mesh FILE        the take's mesh from another path (its crc32 must match)\n"
        "      --stream SPEC      osc:HOST:PORT[,step=MM][,key=N][,mtu=B]: every frame sent\n"
        "                         over OSC at the take's pace, with its time and timecode\n"
        "                         (docs/osc.md, Stream; the Blender add-on receives it)\n"
        "      --control SPEC     osc:PORT[,bind=ADDR]: a transport over OSC (docs/osc.md):\n"
        "                         cued at the first frame, /fp/play, /fp/stop, /fp/seek S,\n"
        "                         /fp/status, /fp/quit; the take is paced in real time; not\n"
        "                         with --out, --export, --frames-out or --audio-out\n");
    fp_app_audio_help(f, false);
    fprintf(f,
        "                         A take made with --audio plays its recorded soundtrack when\n"
        "                         --audio-out is given (--audio FILE: another copy of it;\n"
        "                         a different crc32 is said); its samples follow the frames\n"
        "  -P, --plugin-dir DIR   look for plugins in DIR too, after the built-in folder\n"
        "  -q, --quiet            no summary line, nor the engine's and contact guard's\n"
        "                         notes on each gesture; errors and a damaged take's\n"
        "                         warning still print\n"
        "  -h, --help             this text\n\n"
        "Exit status: 0 done, 64 usage or an unknown audio device, 65 a damaged take or another\n"
        "mesh, 66 missing (the take, or its soundtrack),\n"
        "73 an output not written or existing without --force (facepuppet --help has the\n"
        "whole table).\n");
}

/* The soundtrack: --audio FILE, else the take's own when --audio-out is given; the take's
 * offset unless --audio-offset. A file whose crc32 is not the take's is said. Returns 0 or
 * the exit status (fp_app_audio_prepare's). */
static int play_audio_prepare(fp_app_audio *a, const fp_take_header *h, bool force, bool quiet)
{
    const char *fallback = a->out_spec && h->soundtrack_path ? h->soundtrack_path : NULL;
    if (!a->offset_given && h->soundtrack_path) a->offset_s = h->soundtrack_offset_s;
    if (a->out_spec && !a->path && !fallback) {
        fprintf(stderr, "facepuppet play: the take has no soundtrack: give --audio FILE\n");
        return FP_EXIT_USAGE;
    }
    struct stat st;
    if (!a->path && fallback && stat(fallback, &st) && errno == ENOENT) { /* (fp_app_audio_prepare: "--audio: X") */
        fprintf(stderr, "facepuppet play: the take's soundtrack %s is not there from this folder (a "
                "relative path is the one given to the recording run, from the folder it ran in): "
                "give it with --audio FILE\n", fallback);
        return FP_EXIT_NOINPUT;
    }
    int rc = fp_app_audio_prepare(a, "play", fallback, force);
    if (rc) return rc;
    if (a->playing && h->soundtrack_path && a->track.crc32 != h->soundtrack_crc32 && !quiet)
        fprintf(stderr, "facepuppet play: --audio %s has crc32 %08x, the take's soundtrack %s had "
                "%08x: another file?\n", a->path, (unsigned)a->track.crc32, h->soundtrack_path,
                (unsigned)h->soundtrack_crc32);
    return 0;
}

/* The summary line: the take, its timecodes, rating and description, what was played. How
 * far the skin followed is the take's own (its end chunk, as `info` and the recording run
 * said it) where it has one and is played alone: the control sets it stores are what the rig
 * allowed, so a reach measured against them on playback says 100% where the performer's
 * fingertips asked for more; what the rig allowed is measured here, as run says it. A stack,
 * or a take cut before its end chunk: measured here, with a rig (played_rig) only against
 * what it allowed. */
static void print_played(const char *take_path, const fp_take_reader *r, bool stack, bool played_rig,
                         fp_app_reach *reach, double mm_per_unit, const uint64_t counts[3],
                         const char *out)
{
    const fp_take_header *h = fp_take_reader_header(r);
    const fp_take_summary *sum = fp_take_reader_summary(r);
    char in[32], tcout[32];
    fp_timecode_format(&h->timecode_in, in, sizeof in);
    fp_timecode_format(&sum->timecode_out, tcout, sizeof tcout);
    char reach_text[600];
    if (!stack && sum->reach.vectors) { /* with run's clause of what the rig allowed, measured here */
        char rig[256];
        fp_app_reach_rig_clause(reach, sum->reach.median, sum->reach.p10, rig, sizeof rig);
        reach_text[0] = ';';
        reach_text[1] = ' ';
        fp_app_reach_sentence(reach_text + 2, sizeof reach_text - 2, sum->reach.median,
                              (size_t)sum->reach.vectors, sum->reach.p10,
                              sum->reach.longest_drag_mm, rig, (size_t)sum->reach.held);
    } else {
        fp_app_reach_text(reach, mm_per_unit, played_rig, reach_text, sizeof reach_text);
    }
    char rated[16] = "", desc[600] = ""; /* the take's rating and description, when set */
    if (h->rating) snprintf(rated, sizeof rated, ", rated %d/5", h->rating);
    if (h->description && h->description[0]) {
        char clean[512];
        snprintf(desc, sizeof desc, ", \"%s\"", fp_text_clean(h->description, clean, sizeof clean));
    }
    printf("played %s (%s take %u%s%s, %s - %s): frames %llu, deforming %llu, committed %llu%s%s%s\n",
           take_path, h->slate, h->take, rated, desc, in, tcout, (unsigned long long)counts[0],
           (unsigned long long)counts[1], (unsigned long long)counts[2], reach_text,
           out ? "; wrote " : "", out ? out : "");
}

/* The frame's timecode: the take's timecode in plus the frames of its rate since its origin. */
static void frame_timecode(const fp_take_header *h, int64_t time_ns, char *buf, size_t n)
{
    uint64_t f0;
    fp_timecode tc;
    buf[0] = '\0';
    /* (the take's formula, docs/take-format.md: rounding instead put a 60 fps frame on a
     * 25 fps LTC frame not yet begun) */
    if (time_ns < h->time_origin_ns || fp_timecode_to_frames(&h->timecode_in, h->rate, &f0) ||
        fp_timecode_from_frames(f0 + fp_take_frames_at(time_ns - h->time_origin_ns, h->rate), h->rate,
                                h->timecode_in.drop, &tc))
        return;
    fp_timecode_format(&tc, buf, n);
}

/* What the stream sends: a stack's composite, or NULL for a take's session (its touched
 * ranges: app_link.h). */
static const float *play_positions(fp_take_player *p)
{
    return fp_take_player_stack(p) ? fp_take_player_positions(p) : NULL;
}

static void sleep_until_ns(int64_t t_ns)
{
    struct timespec ts = {(time_t)(t_ns / 1000000000LL), (long)(t_ns % 1000000000LL)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
}

/* play --control: the transport (app_link.h). */
typedef struct play_ctl {
    const char *take_path, *mesh;
    const fp_plugin_path *path;
    bool quiet;
    fp_take_player *player;
    fp_app_link *link;
    bool playing, ended;
    double pos_s;          /* the shown frame's time since the first frame */
    int64_t first_ns;      /* the first frame's time (the take's clock) */
    int64_t wall_base;     /* wall time of pos 0 while playing */
    uint64_t frames;       /* frames shown (the stream's count) */
    uint64_t applied;      /* frames of the take applied since it was opened: the playhead's
                            * frame is applied - 1 */
    char tc[32];           /* the status's timecode: the take's at the playhead */
    int error;             /* a reader's code that ended the transport */
} play_ctl;

/* Reopen the take and apply its frames up to the first at or after t (seconds). */
static int play_seek(play_ctl *c, double t, char *msg, size_t n)
{
    fp_take_player *p = NULL;
    char err[2048];
    int rc = fp_take_player_open_logged(c->take_path, c->mesh, c->path,
                                        c->quiet ? fp_app_log_line_warnings : fp_app_log_line, NULL, &p,
                                        err, sizeof err);
    if (rc) return snprintf(msg, n, "%.900s", err), rc;
    fp_take_player_close(&c->player);
    c->player = p;
    fp_app_link_set_session(c->link, fp_take_player_session(p));
    fp_take_frame f;
    c->pos_s = 0;
    c->applied = 0;
    c->ended = false;
    while ((rc = fp_take_player_next(p, &f, NULL, err, sizeof err)) == 1) {
        c->applied++;
        c->pos_s = (double)(f.time_ns - c->first_ns) * 1e-9;
        if (c->pos_s >= t - 1e-9) break;
    }
    if (rc < 0) return snprintf(msg, n, "%.900s", err), rc;
    if (rc == 0) c->ended = true;
    c->wall_base = fp_now_ns() - (int64_t)llround(c->pos_s * 1e9);
    return 0;
}

static int play_transport(void *user, int kind, double seek_s, char *msg, size_t n)
{
    play_ctl *c = user;
    if (kind == FP_APP_LINK_STOP) {
        c->playing = false;
        return 0;
    }
    if (kind == FP_APP_LINK_SEEK || c->ended) {
        int rc = play_seek(c, kind == FP_APP_LINK_SEEK ? seek_s : 0, msg, n);
        if (rc) return rc;
    }
    if (kind == FP_APP_LINK_PLAY) {
        c->playing = true;
        c->wall_base = fp_now_ns() - (int64_t)llround(c->pos_s * 1e9);
    }
    return 0;
}

/* The status at the playhead: the played take's frame (0 at its first), timecode, slate and
 * take number, and the time since its first frame */
static const char *play_state(void *user, fp_app_link_playhead *at)
{
    play_ctl *c = user;
    const fp_take_header *h = fp_take_player_header(c->player);
    at->time_s = c->pos_s;
    at->frame = c->applied ? c->applied - 1 : 0;
    frame_timecode(h, c->first_ns + (int64_t)llround(c->pos_s * 1e9), c->tc, sizeof c->tc);
    if (c->tc[0]) at->timecode = c->tc;
    at->slate = h->slate;
    at->take = h->take;
    return c->playing ? "playing" : c->ended ? "ended" : "stopped";
}

/* The transport's loop until /fp/quit: frames at the take's pace while playing, streamed.
 * h: the first player's header, for the origin only: a seek reopens the take (a new player,
 * the old one's header freed), so the frames' timecodes take the current player's. */
static int play_controlled(play_ctl *c, const fp_take_header *h)
{
    char err[2048], tc[32];
    fp_app_link_set_transport(c->link, play_transport, play_state, c);
    c->first_ns = h->time_origin_ns;
    fp_app_link_origin(c->link, h->time_origin_ns);
    while (!fp_app_link_quit(c->link)) {
        fp_app_link_before(c->link, c->first_ns + (int64_t)llround(c->pos_s * 1e9), c->frames);
        if (fp_app_link_quit(c->link)) break;
        if (!c->playing) {
            fp_app_link_idle(c->link, c->first_ns + (int64_t)llround(c->pos_s * 1e9), c->frames);
            sleep_until_ns(fp_now_ns() + 5000000);
            continue;
        }
        fp_take_frame f;
        int rc = fp_take_player_next(c->player, &f, NULL, err, sizeof err);
        if (rc <= 0) {
            if (rc < 0) fprintf(stderr, "facepuppet play: %s\n", err);
            c->playing = false;
            c->ended = true;
            continue;
        }
        c->applied++;
        c->pos_s = (double)(f.time_ns - c->first_ns) * 1e-9;
        sleep_until_ns(c->wall_base + (int64_t)llround(c->pos_s * 1e9));
        frame_timecode(fp_take_player_header(c->player), f.time_ns, tc, sizeof tc);
        fp_app_link_after_frame(c->link, f.time_ns, c->frames++, play_positions(c->player), tc);
    }
    return FP_EXIT_OK;
}

/* --control and --stream opened (*link; NULL when neither), and with --control the
 * transport run to its end. Returns 0 or the exit status. */
static int play_link_open(play_ctl *c, const char *control, const char *stream, const fp_take_header *h,
                          fp_app_link **link)
{
    fp_app_link_options lo = {.cmd = "play", .control = control, .stream = stream,
                              .s = fp_take_player_session(c->player),
                              .mesh_path = fp_take_player_mesh_path(c->player),
                              .fps = (double)h->rate.num / h->rate.den, .quiet = c->quiet,
                              .touched = true};
    int status = fp_app_link_open(&lo, link);
    if (status) return status;
    c->link = *link;
    if (control) return play_controlled(c, h);
    fp_app_link_origin(*link, h->time_origin_ns);
    return 0;
}

/* --stream without --control: frame f at wall time `at` (the take's pace), its time and
 * timecode. */
static void play_stream_frame(fp_app_link *link, const fp_take_header *h, fp_take_player *player,
                              const fp_take_frame *f, int64_t at, uint64_t frame)
{
    char tc[32];
    sleep_until_ns(at);
    frame_timecode(h, f->time_ns, tc, sizeof tc);
    fp_app_link_after_frame(link, f->time_ns, frame, play_positions(player), tc);
}

/* What play writes and sends, checked before any work. */
typedef struct play_outputs {
    const char *out, *export_file, *frames_out, *control, *stream, *audio_out;
    bool force;
    const char *take, *mesh;   /* inputs: never written over (--mesh: NULL when not given) */
} play_outputs;

/* --control and --stream's SPECs; --out, --export (its format into *fmt), --frames-out: a
 * name we write, nothing there unless --force (*made: the folder was made here); none of them
 * with --control. Returns 0 or the exit status (said). */
static int play_check_outputs(const play_outputs *o, fp_export_format *fmt, bool *made)
{
    int oc = fp_app_link_check("play", o->control, o->stream);
    const char *opts[2] = {"--out", "--export"}, *outs[2] = {o->out, o->export_file};
    for (int i = 0; i < 2 && !oc; i++) {   /* (an input written over, --force or not) */
        oc = fp_app_check_not_input("facepuppet play", opts[i], outs[i], o->take, "the take");
        if (!oc) oc = fp_app_check_not_input("facepuppet play", opts[i], outs[i], o->mesh, "the mesh");
    }
    if (oc) return oc;
    if (o->control && (o->out || o->export_file || o->frames_out || o->audio_out)) {
        fprintf(stderr, "facepuppet play: --control is a transport (play, stop, seek): give --out, "
                "--export, --frames-out or --audio-out without it\n");
        return FP_EXIT_USAGE;
    }
    if (o->out) { /* the name and the place, before any work (as run and pose) */
        oc = fp_app_check_mesh_name("facepuppet play", "--out", o->out);
        if (!oc) oc = fp_app_check_new_output("facepuppet play", "--out", o->out, o->force);
        if (oc) return oc;
    }
    if (o->export_file && fp_export_format_from_path(o->export_file, fmt)) {
        fprintf(stderr, "facepuppet play: --export %s: give a file ending in .gltf, .glb, .pc2 "
                "or .mdd\n", o->export_file);
        return FP_EXIT_USAGE;
    }
    oc = o->export_file ? fp_app_check_new_output("facepuppet play", "--export", o->export_file, o->force) : 0;
    if (!oc && o->frames_out)
        oc = fp_app_check_output_dir("facepuppet play", "--frames-out", o->frames_out, "frame_", ".obj",
                                     true, o->force, made);
    return oc;
}

/* --frames-out: frame f as DIR/frame_NNNNNN_tS.SSSs.obj. Returns 0 or the exit status (said). */
static int play_write_frame(fp_take_player *player, const char *dir, const fp_take_frame *f,
                            const fp_take_header *h)
{
    char file[4400], err[2048];
    snprintf(file, sizeof file, "%s/frame_%06llu_t%.3fs.obj", dir, (unsigned long long)f->frame,
             (double)(f->time_ns - h->time_origin_ns) * 1e-9);
    int rc = fp_take_player_save(player, file, NULL, err, sizeof err);
    if (rc) fprintf(stderr, "facepuppet play: %s\n", err);
    return rc ? fp_app_exit_code(rc, FP_APP_OUTPUT) : FP_EXIT_OK;
}

/* After the last frame: --out written and *ex finished (when given), the export even when --out
 * could not be written (each output stands alone). Returns 0 or the first exit status (said). */
static int play_finish_outputs(fp_take_player *player, const char *out, fp_exporter **ex,
                               fp_export_format fmt, const char *export_file, bool quiet)
{
    int status = FP_EXIT_OK, rc;
    unsigned dropped = 0;
    char err[2048];
    if (out && (rc = fp_take_player_save(player, out, &dropped, err, sizeof err))) {
        fprintf(stderr, "facepuppet play: %s\n", err);
        status = fp_app_exit_code(rc, FP_APP_OUTPUT);
    } else if (out) {
        fp_app_print_dropped("facepuppet play", out, dropped, quiet);
    }
    const int ex_status = *ex ? fp_app_export_close("facepuppet play", "--export", ex, fmt,
                                                    export_file, 0.1, quiet, stdout) : FP_EXIT_OK;
    return status ? status : ex_status;
}

static int play_main(int argc, char **argv)
{
    enum { OPT_FRAMES_OUT = 0x200, OPT_PLUGIN_DIR, OPT_EXPORT, OPT_FORCE, OPT_CONTROL, OPT_STREAM };
    static const struct option opts[] = {
        {"out", required_argument, 0, 'o'},      {"frames-out", required_argument, 0, OPT_FRAMES_OUT},
        {"mesh", required_argument, 0, 'm'},     {"plugin-dir", required_argument, 0, 'P'},
        {"export", required_argument, 0, OPT_EXPORT}, {"force", no_argument, 0, OPT_FORCE},
        {"quiet", no_argument, 0, 'q'},          {"help", no_argument, 0, 'h'},
        {"control", required_argument, 0, OPT_CONTROL}, {"stream", required_argument, 0, OPT_STREAM},
        {0, 0, 0, 0}};
    struct option all[sizeof opts / sizeof opts[0] + FP_APP_AUDIO_OPTS_COUNT];
    size_t nall = fp_app_audio_longopts(all, false);
    memcpy(all + nall, opts, sizeof opts);
    fp_app_audio audio = {0};
    const char *out = NULL, *frames_out = NULL, *mesh = NULL, *export_file = NULL, *dirs[8];
    const char *control = NULL, *stream = NULL;
    size_t ndirs = 0;
    bool quiet = false, force = false;
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, "o:m:P:qh", all)) != -1;) {
        int ac = fp_app_audio_parse(&audio, c, optarg, "play");
        if (ac > 1) return ac;
        if (ac) continue;
        switch (c) {
        case 'o': out = optarg; break;
        case OPT_FRAMES_OUT: frames_out = optarg; break;
        case OPT_EXPORT: export_file = optarg; break;
        case 'm': mesh = optarg; break;
        case 'P':
            if (ndirs < 8) dirs[ndirs++] = optarg;
            break;
        case 'q': quiet = true; break;
        case OPT_FORCE: force = true; break;
        case OPT_CONTROL: control = optarg; break;
        case OPT_STREAM: stream = optarg; break;
        case 'h': usage(stdout); return FP_EXIT_OK;
        default: usage(stderr); return FP_EXIT_USAGE;
        }
    }
    if (argc - optind != 1) {
        fprintf(stderr, "facepuppet play: give one TAKE or STACK file (see --help)\n");
        return FP_EXIT_USAGE;
    }
    const char *take_path = argv[optind];
    char err[2048];
    fp_export_format export_fmt;
    const play_outputs po = {out, export_file, frames_out, control, stream, audio.out_spec, force,
                             take_path, mesh};
    bool frames_made = false; /* the --frames-out folder made here: taken away if refused before a frame */
    int oc = play_check_outputs(&po, &export_fmt, &frames_made);
    if (oc) return oc;
    /* The take's session and frame loop (fp_take_player, shared with export). */
    fp_plugin_path path;
    fp_app_plugin_path(&path, dirs, ndirs);
    fp_take_player *player = NULL;
    fp_exporter *ex = NULL;
    fp_app_link *link = NULL; /* --control, --stream */
    int status = FP_EXIT_OK;
    fp_app_reach reach = {0}; /* how far the skin followed, over the take */
    int rc = fp_take_player_open_logged(take_path, mesh, &path,
                                        quiet ? fp_app_log_line_warnings : fp_app_log_line, NULL,
                                        &player, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet play: %s\n", err);
        fp_plugin_path_clear(&path);
        if (frames_made) rmdir(frames_out);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    fp_take_reader *r = fp_take_player_reader(player);
    fp_session *s = fp_take_player_session(player);
    const fp_take_header *h = fp_take_reader_header(r);
    if ((status = fp_app_take_intact("facepuppet play", "play", take_path, r))) goto done;
    if (fp_take_player_stack(player) && fp_stack_player_warning(fp_take_player_stack(player))[0])
        fprintf(stderr, "facepuppet play: warning: %s\n", fp_stack_player_warning(fp_take_player_stack(player)));
    if ((status = play_audio_prepare(&audio, h, force, quiet))) goto done;
    const double take_frames = (double)fp_take_reader_frames(r); /* outputs' sizes, before any */
    if (frames_out && (status = fp_app_frames_estimate("facepuppet play", "--frames-out", frames_out,
                                                       take_frames, 0, fp_session_mesh(s), quiet, NULL)))
        goto done;
    char name[96]; /* (as export names it: SLATE_TNNN, a stack's file name) */
    fp_app_export_name(take_path, fp_take_player_stack(player) != NULL, h->slate, h->take, name,
                       sizeof name);
    if (export_file && (status = fp_app_export_open("facepuppet play", export_file, s,
                                                    fp_take_player_mm_per_unit(player),
                                                    name, take_frames, &ex)))
        goto done;
    play_ctl c = {.take_path = take_path, .mesh = mesh, .path = &path, .quiet = quiet, .player = player};
    if ((status = play_link_open(&c, control, stream, h, &link)) || control) {
        player = c.player; /* (a seek reopens it) */
        goto done;
    }
    if (frames_out && force && (status = fp_app_frames_out_clear("facepuppet play", frames_out, quiet)))
        goto done;
    frames_made = false; /* (frames are written from here on) */
    int64_t wall0 = fp_now_ns();
    uint64_t frames = 0, commits = 0, active = 0;
    fp_frame_stats st;
    fp_take_frame f;
    int64_t first_ns = 0;
    while ((rc = fp_take_player_next(player, &f, &st, err, sizeof err)) == 1) {
        if (frames == 0)
            first_ns = f.time_ns;
        if (link) play_stream_frame(link, h, player, &f, wall0 + (f.time_ns - first_ns), frames);
        if (ex && (rc = fp_export_add(ex, fp_take_player_positions(player),
                                      (double)(f.time_ns - first_ns) * 1e-9, err, sizeof err))) {
            fprintf(stderr, "facepuppet play: --export: %s\n", err);
            status = fp_app_exit_code(rc, FP_APP_OUTPUT);
            goto done;
        }
        /* the soundtrack up to the end of this frame (one period of the take's rate) */
        if ((status = fp_app_audio_advance(&audio, (double)(f.time_ns - h->time_origin_ns) * 1e-9 +
                                                       (double)h->rate.den / h->rate.num, "play")))
            goto done;
        frames++;
        commits += st.committed;
        active += st.active;
        fp_app_reach_add(&reach, &st);
        if (frames_out && (status = play_write_frame(player, frames_out, &f, h))) goto done;
    }
    if (rc < 0) {
        fprintf(stderr, "facepuppet play: %s\n", err);
        status = fp_app_exit_code(rc, FP_APP_INPUT);
        goto done;
    }
    if ((status = play_finish_outputs(player, out, &ex, export_fmt, export_file, quiet))) goto done;
    if (!quiet) {
        const uint64_t counts[3] = {frames, active, commits};
        print_played(take_path, r, fp_take_player_stack(player) != NULL,
                     fp_session_rig(fp_take_player_session(player)) != NULL, &reach,
                     fp_take_player_mm_per_unit(player), counts, out);
    }
    fp_app_stack_limited_note("play", take_path, fp_take_player_stack(player), quiet);
done:
    if (frames_made) rmdir(frames_out);
    fp_app_link_close(&link);
    if (status) fp_audio_out_abort(&audio.out);
    else status = fp_app_audio_finish(&audio, "play", quiet);
    fp_app_audio_finish(&audio, "play", true);
    fp_app_reach_free(&reach);
    fp_export_abort(&ex);
    fp_take_player_close(&player);
    fp_plugin_path_clear(&path);
    return status;
}

const fp_command fp_command_play = {"play", "reproduce a take's frames from its control sets",
                                    play_main};
