/* facepuppet live: perform with the face in a window (the viewer, ui/). Built where the
 * viewer is (FP_BUILD_UI, GLFW and epoxy found): fp_ui defines FP_HAVE_UI for its users. */
#ifdef FP_HAVE_UI
#define _GNU_SOURCE
#include "app_util.h"
#include "command.h"
#include "fp_session.h"
#include "fp_viewer.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *f)
{
    fprintf(f,
        "usage: facepuppet live [--mesh FILE] [--input SPEC]... [--mapping NAME] [--radius R]\n"
        "                       [--speed X] [--size WxH] [--frames N] [--screenshot FILE.png]\n"
        "                       [--script TEXT|@FILE] [--gpu-warp] [--vsync] [--out FILE]\n\n"
        "Perform with the face in a window: the inputs drive the mapping, the mapping drives\n"
        "the CSRBF engine, the face deforms as you watch. With no mesh and no input it plays\n"
        "the demo: the ICT face and the three-claps recording.\n\n"
        "Options shared with `facepuppet run`:\n"
        "  -m, --mesh FILE        face mesh (OBJ, PLY, OFF, STL, glTF)\n"
        "  -i, --input SPEC       NAME[:ARG][,key=value...] (repeatable), e.g.\n"
        "                         replay:../shared/data/hands/leap-motion/grab_joints_mm.csv\n"
        "  -M, --mapping SPEC     anchored (default) or unanchored, [,key=value...]\n"
        "  -r, --radius R         support radius in mesh units (default 6%% of the diagonal)\n"
        "  -s, --speed X          replay speed factor for replay inputs (default 1)\n"
        "  -o, --out FILE         write the final shape when the window closes\n"
        "      --duration S       stop after S seconds\n"
        "      --hand-size F      performer's hand size, 1 = mean adult\n"
        "      --plugin-dir DIR   look for plugins in DIR first (repeatable)\n"
        "  -q, --quiet            no progress lines\n"
        "Viewer options:\n"
        "      --size WxH         window size (default 1280x720)\n"
        "      --frames N         stop after N frames\n"
        "      --screenshot FILE  write the last frame as PNG (with --frames N: run N frames,\n"
        "                         write, exit)\n"
        "      --script TEXT      scripted actions, or @FILE to read them from FILE:\n"
        "                         'wait hands|end|frames N; key K; shot FILE; radius R;\n"
        "                         drop FILE; close' (see docs/arch/viewer.md)\n"
        "      --gpu-warp         evaluate the warp in the vertex shader; checked against the\n"
        "                         CPU engine by transform feedback (reported at exit)\n"
        "      --vsync            wait for the display (default: never, swap interval 0)\n"
        "  -h, --help             this text\n\n"
        "Keys: space pause, E engage, C commit, X cancel, Z undo, R reset, 1 anchored,\n"
        "2 unanchored, [ ] radius, W wireframe, S screenshot, F frame, H hands, Tab HUD,\n"
        "? keys, Esc quit. Mouse: left orbit, right pan, wheel zoom. Drop a mesh to load it.\n"
        "At exit it prints the frame time and the input-event-to-frame latency (median, p99).\n\n"
        "Exit status: 0 done, 64 usage, 65 bad input data, 66 input or display missing,\n"
        "73 output not writable, 78 plugin missing or incompatible, 1 other failure.\n");
}

static char *read_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    size_t len = 0, cap = 0, got;
    char chunk[4096];
    while ((got = fread(chunk, 1, sizeof chunk, f)) > 0) {
        if (len + got + 1 > cap) {
            cap = 2 * (len + got + 1);
            char *grown = realloc(buf, cap);
            if (!grown) { free(buf); fclose(f); return NULL; }
            buf = grown;
        }
        memcpy(buf + len, chunk, got);
        len += got;
    }
    fclose(f);
    if (!buf) buf = calloc(1, 1);
    else buf[len] = '\0';
    return buf;
}

static int live_main(int argc, char **argv)
{
    enum { OPT_DURATION = 256, OPT_HAND, OPT_PLUGIN_DIR, OPT_SIZE, OPT_FRAMES, OPT_SHOT,
           OPT_SCRIPT, OPT_GPU, OPT_VSYNC };
    static const struct option opts[] = {
        {"mesh", required_argument, 0, 'm'},       {"input", required_argument, 0, 'i'},
        {"mapping", required_argument, 0, 'M'},    {"radius", required_argument, 0, 'r'},
        {"out", required_argument, 0, 'o'},        {"speed", required_argument, 0, 's'},
        {"duration", required_argument, 0, OPT_DURATION}, {"hand-size", required_argument, 0, OPT_HAND},
        {"plugin-dir", required_argument, 0, OPT_PLUGIN_DIR}, {"quiet", no_argument, 0, 'q'},
        {"size", required_argument, 0, OPT_SIZE},  {"frames", required_argument, 0, OPT_FRAMES},
        {"screenshot", required_argument, 0, OPT_SHOT}, {"script", required_argument, 0, OPT_SCRIPT},
        {"gpu-warp", no_argument, 0, OPT_GPU},     {"vsync", no_argument, 0, OPT_VSYNC},
        {"help", no_argument, 0, 'h'},             {0, 0, 0, 0}};
    fp_viewer_options vo = {0};
    fp_session_options *so = &vo.session;
    const char *plugin_dirs[8], *script_arg = NULL;
    size_t nplugin_dirs = 0;
    double speed = 1;
    char *end;
    optind = 1;
    for (int c; (c = getopt_long(argc, argv, "m:i:M:r:o:s:qh", opts, NULL)) != -1;) {
        switch (c) {
        case 'm': so->mesh_path = optarg; break;
        case 'i':
            if (so->input_count == FP_SESSION_MAX_INPUTS) {
                fprintf(stderr, "facepuppet live: at most %d --input\n", FP_SESSION_MAX_INPUTS);
                return FP_EXIT_USAGE;
            }
            so->inputs[so->input_count++] = optarg;
            break;
        case 'M': so->mapping = optarg; break;
        case 'r':
            so->radius = strtod(optarg, &end);
            if (*end || !(so->radius > 0) || !isfinite(so->radius)) {
                fprintf(stderr, "facepuppet live: --radius must be a number > 0, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case 'o': vo.out = optarg; break;
        case 's':
            speed = strtod(optarg, &end);
            if (*end || !(speed > 0) || !isfinite(speed)) {
                fprintf(stderr, "facepuppet live: --speed must be a number > 0, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_DURATION:
            vo.duration_s = strtod(optarg, &end);
            if (*end || !(vo.duration_s > 0) || !isfinite(vo.duration_s)) {
                fprintf(stderr, "facepuppet live: --duration must be > 0 seconds, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_HAND:
            so->hand_size = strtod(optarg, &end);
            if (*end || !(so->hand_size > 0.3 && so->hand_size < 3)) {
                fprintf(stderr, "facepuppet live: --hand-size must be in 0.3..3, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_PLUGIN_DIR:
            if (nplugin_dirs < 8) plugin_dirs[nplugin_dirs++] = optarg;
            break;
        case OPT_SIZE:
            if (sscanf(optarg, "%dx%d", &vo.width, &vo.height) != 2 || vo.width < 16 ||
                vo.height < 16 || vo.width > 16384 || vo.height > 16384) {
                fprintf(stderr, "facepuppet live: --size must be WxH (16..16384), got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case OPT_FRAMES: {
            unsigned long long n = strtoull(optarg, &end, 10);
            if (*end || !n || optarg[0] == '-') {
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
        case 'q': vo.quiet = true; break;
        case 'h': usage(stdout); return FP_EXIT_OK;
        default: usage(stderr); return FP_EXIT_USAGE;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "facepuppet live: unexpected argument '%s'\n", argv[optind]);
        return FP_EXIT_USAGE;
    }
    if (vo.screenshot && !vo.frames && !script_arg) {
        fprintf(stderr, "facepuppet live: --screenshot needs --frames N (or a --script that closes)\n");
        return FP_EXIT_USAGE;
    }
    /* The demo when no mesh and no input are given; --speed for replay inputs. */
    fp_app_inputs inputs_buf;
    fp_app_session_defaults(so, speed, &inputs_buf);
    char *script_text = NULL;
    if (script_arg && script_arg[0] == '@') {
        if (!(script_text = read_file(script_arg + 1))) {
            fprintf(stderr, "facepuppet live: --script %s: cannot read it\n", script_arg + 1);
            return FP_EXIT_NOINPUT;
        }
        vo.script = script_text;
    } else {
        vo.script = script_arg;
    }

    fp_plugin_path path;
    fp_app_plugin_path(&path, plugin_dirs, nplugin_dirs);
    so->plugin_path = &path;
    char err[2048] = "";
    fp_viewer_report rep = {0};
    int rc = fp_viewer_run(&vo, &rep, err, sizeof err);
    int status = FP_EXIT_OK;
    if (rc) {
        fprintf(stderr, "facepuppet live: %s\n", err);
        status = rc == -EIO ? FP_EXIT_CANTCREAT : rc == -ENODEV ? FP_EXIT_NOINPUT
               : !strncmp(err, "--script", 8) ? FP_EXIT_USAGE : fp_app_exit_code(rc);
    }
    if (rep.frames) {
        printf("frames %llu; frame time median %.2f ms, p99 %.2f ms; event-to-frame latency median "
               "%.2f ms, p99 %.2f ms over %zu events; engine update median %.3f ms; events dropped %lu\n",
               (unsigned long long)rep.frames, rep.frame_ms_median, rep.frame_ms_p99,
               rep.latency_ms_median, rep.latency_ms_p99, rep.latency_samples, rep.engine_ms_median,
               rep.dropped);
        if (vo.gpu_warp)
            printf("gpu-warp: %zu checks against the CPU engine; max |GPU - CPU| %.3g mesh units, "
                   "%.3g of the max displacement %.4g\n", rep.warp_checks, rep.warp_max_error,
                   rep.warp_max_displacement > 0 ? rep.warp_max_error / rep.warp_max_displacement : 0.0,
                   rep.warp_max_displacement);
    }
    free(script_text);
    fp_plugin_path_clear(&path);
    return status;
}

const fp_command fp_command_live = {"live", "perform with the face in a window (no options: the demo)",
                                    live_main};
#endif /* FP_HAVE_UI */
