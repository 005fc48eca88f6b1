/* facepuppet play: a take's frames again, from its stored control sets (no input devices,
 * no mapping): bit-identical to the frames the recording session showed. */
#define _GNU_SOURCE
#include "app_util.h"
#include "command.h"
#include "fp_session.h"
#include "fp_session_take.h"
#include "fp_mesh.h"

#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void usage(FILE *f)
{
    fprintf(f,
        "usage: facepuppet play TAKE [--frames-out DIR] [--out FILE] [--mesh FILE]\n\n"
        "Reproduce a take's frames from the control sets it stored (no input devices, no\n"
        "mapping): the take's mesh (checked against the crc32 in the take), each frame's\n"
        "control set through the same engine step (fold-over guard included), commits,\n"
        "undo and reset as recorded. The meshes are bit-identical to the recording run's.\n\n"
        "  -o, --out FILE         the last frame's mesh (default: none); format by extension\n"
        "      --frames-out DIR   one mesh per frame, DIR/frame_NNNNNN_tS.SSSs.obj (session\n"
        "                         frame number, time since the take's timecode in)\n"
        "  -m, --mesh FILE        the take's mesh from another path (its crc32 must match)\n"
        "      --plugin-dir DIR   look for plugins in DIR first\n"
        "  -q, --quiet            no summary line\n"
        "  -h, --help             this text\n\n"
        "Exit status: 0 done, 64 usage, 65 a damaged take or another mesh, 66 missing,\n"
        "73 an output not written (facepuppet --help has the whole table).\n");
}

static int play_main(int argc, char **argv)
{
    enum { OPT_FRAMES_OUT = 0x200, OPT_PLUGIN_DIR };
    static const struct option opts[] = {
        {"out", required_argument, 0, 'o'},      {"frames-out", required_argument, 0, OPT_FRAMES_OUT},
        {"mesh", required_argument, 0, 'm'},     {"plugin-dir", required_argument, 0, OPT_PLUGIN_DIR},
        {"quiet", no_argument, 0, 'q'},          {"help", no_argument, 0, 'h'},
        {0, 0, 0, 0}};
    const char *out = NULL, *frames_out = NULL, *mesh = NULL, *dirs[8];
    size_t ndirs = 0;
    bool quiet = false;
    optind = 1;
    for (int c; (c = getopt_long(argc, argv, "o:m:qh", opts, NULL)) != -1;) {
        switch (c) {
        case 'o': out = optarg; break;
        case OPT_FRAMES_OUT: frames_out = optarg; break;
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
        fprintf(stderr, "facepuppet play: give one TAKE file (see --help)\n");
        return FP_EXIT_USAGE;
    }
    const char *take_path = argv[optind];
    char err[2048];
    fp_take_reader *r = NULL;
    int rc = fp_take_reader_open(take_path, &r, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet play: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    if (fp_take_reader_warning(r)[0])
        fprintf(stderr, "facepuppet play: warning: %s; playing the %zu intact frames\n",
                fp_take_reader_warning(r), fp_take_reader_frames(r));
    const fp_take_header *h = fp_take_reader_header(r);
    if (!mesh) mesh = h->mesh_path;
    if (!mesh) {
        fprintf(stderr, "facepuppet play: %s names no mesh: give --mesh FILE\n", take_path);
        fp_take_reader_close(&r);
        return FP_EXIT_USAGE;
    }
    if (frames_out && mkdir(frames_out, 0777) && errno != EEXIST) {
        fprintf(stderr, "facepuppet play: --frames-out %s: %s\n", frames_out, strerror(errno));
        fp_take_reader_close(&r);
        return fp_app_exit_code(-errno, FP_APP_OUTPUT);
    }
    /* The mesh first: the take's (checksum) before any rig is bound to it. */
    {
        fp_mesh *m = NULL;
        if ((rc = fp_mesh_load(mesh, &m, err, sizeof err))) {
            fprintf(stderr, "facepuppet play: %s\n", err);
            fp_take_reader_close(&r);
            return fp_app_exit_code(rc, FP_APP_INPUT);
        }
        rc = fp_take_check_positions(m->positions, m->vertex_count, mesh, h, err, sizeof err);
        fp_mesh_free(&m);
        if (rc) {
            fprintf(stderr, "facepuppet play: %s: %s\n", take_path, err);
            fp_take_reader_close(&r);
            return fp_app_exit_code(rc, FP_APP_INPUT);
        }
    }
    /* A session on the take's mesh with no inputs; its mapping is never called. */
    fp_plugin_path path;
    fp_app_plugin_path(&path, dirs, ndirs);
    fp_session_options so = {.mesh_path = mesh, .mapping = "anchored", .radius = h->radius,
                             .plugin_path = &path, .rig_path = h->rig_path ? h->rig_path : "none"};
    fp_session *s = NULL;
    int status = FP_EXIT_OK;
    if ((rc = fp_session_create(&so, &s, err, sizeof err))) {
        fprintf(stderr, "facepuppet play: %s\n", err);
        status = fp_app_exit_code(rc, FP_APP_INPUT);
        goto done;
    }
    if ((rc = fp_session_take_check_mesh(s, mesh, h, err, sizeof err))) {
        fprintf(stderr, "facepuppet play: %s: %s\n", take_path, err);
        status = fp_app_exit_code(rc, FP_APP_INPUT);
        goto done;
    }
    uint64_t frames = 0, commits = 0, active = 0;
    fp_take_frame f;
    while ((rc = fp_take_reader_next(r, &f, err, sizeof err)) == 1) {
        fp_frame_stats st;
        fp_session_play_frame(s, &f, &st);
        frames++;
        commits += st.committed;
        active += st.active;
        if (frames_out) {
            char file[4400];
            snprintf(file, sizeof file, "%s/frame_%06llu_t%.3fs.obj", frames_out,
                     (unsigned long long)f.frame, (double)(f.time_ns - h->time_origin_ns) * 1e-9);
            if ((rc = fp_session_save(s, file, err, sizeof err))) {
                fprintf(stderr, "facepuppet play: %s\n", err);
                status = fp_app_exit_code(rc, FP_APP_OUTPUT);
                goto done;
            }
        }
    }
    if (rc < 0) {
        fprintf(stderr, "facepuppet play: %s\n", err);
        status = fp_app_exit_code(rc, FP_APP_INPUT);
        goto done;
    }
    if (out && (rc = fp_session_save(s, out, err, sizeof err))) {
        fprintf(stderr, "facepuppet play: %s\n", err);
        status = fp_app_exit_code(rc, FP_APP_OUTPUT);
        goto done;
    }
    if (!quiet) {
        char in[32], tcout[32];
        fp_timecode_format(&h->timecode_in, in, sizeof in);
        fp_timecode_format(&fp_take_reader_summary(r)->timecode_out, tcout, sizeof tcout);
        printf("played %s (%s take %u, %s - %s): frames %llu, deforming %llu, committed %llu%s%s\n",
               take_path, h->slate, h->take, in, tcout, (unsigned long long)frames,
               (unsigned long long)active, (unsigned long long)commits, out ? "; wrote " : "",
               out ? out : "");
    }
done:
    fp_session_destroy(&s);
    fp_plugin_path_clear(&path);
    fp_take_reader_close(&r);
    return status;
}

const fp_command fp_command_play = {"play", "reproduce a take's frames from its control sets",
                                    play_main};
