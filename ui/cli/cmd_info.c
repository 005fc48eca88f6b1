/* facepuppet info: what a mesh, recording, rig, hand or glove calibration, take, stack, sound file or
 * point cache holds. */
#define _GNU_SOURCE
#include "app_util.h"
#include "command.h"
#include "fp_file.h"
#include "fp_mesh.h"
#include "app_audio.h"
#include "app_export.h"
#include "app_stack.h"
#include "fp_calib_file.h"
#include "glove_cal.h" /* (plugins/input-cyberglove: the glove input's own reader) */

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* The first n bytes of the file at path into h (a FIFO or a folder gives none: never waited
 * on); how many were read. The signatures info tells files apart by. */
static size_t file_head(const char *path, unsigned char *h, size_t n)
{
    int code;
    FILE *f = fp_file_fopen_regular(path, &code);
    if (!f) return 0;
    size_t got = fread(h, 1, n, f);
    fclose(f);
    return got;
}

/* A take: its extension (.fptake) or its signature's first bytes ("\x89FPTAKE\n"). */
static bool is_take(const char *path, const unsigned char *h, size_t n)
{
    const char *dot = strrchr(path, '.');
    if (dot && !strcasecmp(dot, ".fptake")) return true;
    return n >= 8 && !memcmp(h, "\x89" "FPTAKE\n", 8);
}

/* What a .json holds, from its first 64 KiB: a rig names its format ("facepuppet-rig"); else
 * a Leap playback recording holds its frames ("frames"); else a hand calibration (calibrate
 * --out) its unit ("mm_per_unit" or "scale"); anything else is read as a rig, whose reader
 * names what is wrong. */
enum json_kind { JSON_RIG, JSON_RECORDING, JSON_CALIBRATION };

static enum json_kind json_kind(const char *path)
{
    static char head[65537];
    int code;
    FILE *f = fp_file_fopen_regular(path, &code);
    if (!f) return JSON_RIG;
    size_t n = fread(head, 1, sizeof head - 1, f);
    fclose(f);
    head[n] = '\0';
    if (strstr(head, "\"facepuppet-rig\"")) return JSON_RIG;
    if (strstr(head, "\"frames\"")) return JSON_RECORDING;
    return strstr(head, "\"mm_per_unit\"") || strstr(head, "\"scale\"") ? JSON_CALIBRATION : JSON_RIG;
}

/* A hand calibration file, read as run --calibration reads it (fp_calib_file.h). */
static int calibration_info(const char *path)
{
    fp_calibration c;
    char err[1024];
    int rc = fp_calibration_load(path, &c, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet info: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    const double w = fmin(1, fabs(c.rotation[0])), s = sqrt(fmax(0, 1 - w * w));
    const double sign = c.rotation[0] < 0 ? -1 : 1;
    printf("%s\n  format    hand calibration (calibrate --out; docs/calibration.md)\n"
           "  unit      %g mm per mesh unit\n  rotation  %.3g degrees", path, 1 / c.scale,
           2 * acos(w) * 180 / 3.14159265358979323846);
    if (s > 1e-12)
        printf(" about (%.4g, %.4g, %.4g)", sign * c.rotation[1] / s, sign * c.rotation[2] / s,
               sign * c.rotation[3] / s);
    printf(" (tracker to mesh)\n  offset    %g %g %g mesh units\n", c.offset[0], c.offset[1], c.offset[2]);
    for (int h = 0; h < FP_HANDS; h++)
        printf("  %-9s offset %g %g %g mesh units\n", h == FP_HAND_LEFT ? "left" : "right",
               c.hand_offset[h][0], c.hand_offset[h][1], c.hand_offset[h][2]);
    printf("  use       --calibration %s\n", path);
    return FP_EXIT_OK;
}

static bool is_mesh(const char *path)
{
    static const char *exts[] = {".obj", ".ply", ".off", ".stl", ".gltf", ".glb"};
    const char *dot = strrchr(path, '.');
    for (size_t i = 0; dot && i < sizeof exts / sizeof exts[0]; i++)
        if (!strcasecmp(dot, exts[i])) return true;
    return false;
}

/* Mesh files carry no units; guess from the size of a head (about 0.25 m across). */
static const char *guess_units(double extent)
{
    if (extent > 0.05 && extent < 1.0) return "probably metres";
    if (extent >= 5 && extent < 100) return "probably centimetres";
    if (extent >= 50 && extent < 1000) return "probably millimetres";
    return "unknown";
}

static const char *plural(size_t n) { return n == 1 ? "" : "s"; }

/* A glTF's document beyond the triangles: what an export put there (morph targets, the
 * animation's keys and rate, the root node's scale to metres), so an animator sees what a
 * tool will import. The bounds above are the scene's, the nodes' transforms applied. */
static void gltf_info(const fp_mesh *m)
{
    fp_mesh_gltf_info g;
    if (fp_mesh_gltf_summary(m, &g) != FP_MESH_OK) return;
    printf("  glTF      %zu mesh%s, %zu node%s, %zu material%s%s%s%s\n", g.meshes, g.meshes == 1 ? "" : "es",
           g.nodes, plural(g.nodes), g.materials, plural(g.materials), g.generator[0] ? "; generator \"" : "",
           g.generator, g.generator[0] ? "\"" : "");
    if (g.morph_targets) printf("  targets   %zu morph target%s\n", g.morph_targets, plural(g.morph_targets));
    if (g.animations) {
        printf("  animation %s%s%s%zu channel%s (%zu of morph weights), %zu keys, 0 .. %.3f s", g.animation[0] ? "\"" : "",
               g.animation, g.animation[0] ? "\": " : "", g.channels, plural(g.channels), g.weights_channels,
               g.keys, g.duration_s);
        if (g.frame_rate > 0) printf(", %g fps (asset.extras.frameRate)", g.frame_rate);
        if (g.animations > 1)
            printf("; %zu animations: the name is the first's, the keys and the time the most of any",
                   g.animations);
        printf("\n");
    }
    if (g.root_scale > 0 && g.root_scale != 1)
        printf("  scale     root node %g: the vertices are in units of %g m (%g mm)%s\n", g.root_scale,
               g.root_scale, g.root_scale * 1000, g.metres_per_unit > 0 ? ", as asset.extras.metresPerUnit says" : "");
}

static int mesh_info(const char *path)
{
    fp_mesh *m = NULL;
    char err[1024];
    int rc = fp_app_load_mesh("facepuppet info", false, path, &m, err, sizeof err);
    if (rc < 0) {
        fprintf(stderr, "facepuppet info: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    /* the surface's bounds, as the session sizes the face: points in no triangle left out */
    uint8_t *used;
    size_t unused;
    (void)fp_mesh_surface_mask(m, &used, &unused); /* (out of memory: every vertex's bounds) */
    float lo[3], hi[3];
    fp_mesh_bounds_used(m, used, lo, hi);
    free(used);
    double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    printf("%s\n  vertices  %zu\n  triangles %zu\n  uvs       %s\n"
           "  bounds    [%g, %g, %g] .. [%g, %g, %g]\n  size      %g x %g x %g\n  units     %s\n",
           path, m->vertex_count, m->triangle_count, m->uvs ? "yes" : "no", lo[0], lo[1], lo[2],
           hi[0], hi[1], hi[2], hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], guess_units(ext));
    if (unused)
        printf("  unused    %zu vertices in no triangle (left out of the bounds, as run leaves them "
               "out of the face's size)\n", unused);
    /* far from the origin the floats step coarsely (FP_SESSION_MAX_STEP_DIAGONALS): run refuses */
    double far = 0, diag = 0;
    for (int k = 0; k < 3; k++) {
        far = fmax(far, fmax(fabs(lo[k]), fabs(hi[k])));
        diag += ((double)hi[k] - lo[k]) * ((double)hi[k] - lo[k]);
    }
    const double step = far > 0 ? (double)nextafterf((float)far, INFINITY) - (double)(float)far : 0;
    if (step > FP_SESSION_MAX_STEP_DIAGONALS * sqrt(diag))
        printf("  precision the surface lies %g units from the origin, where its floats step by %g "
               "units, coarse for its size (run refuses it: move it near the origin)\n", far, step);
    gltf_info(m);
    fp_mesh_free(&m);
    return FP_EXIT_OK;
}

static int recording_info(const char *path)
{
    fp_plugin_path pp;
    fp_app_plugin_path(&pp, NULL, 0);
    char spec[4200], err[2048];
    snprintf(spec, sizeof spec, "replay:%s", path);
    fp_input_instance inst;
    int rc = fp_input_instance_open(&inst, &pp, spec, 0, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet info: %s\n", err);
        fp_plugin_path_clear(&pp);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    fp_input_instance_set_log(&inst, fp_app_log_line, NULL);
    fp_input_instance_drain_log(&inst); /* what its create said */
    const fp_input_recording *ext =
        inst.input->get_extension ? inst.input->get_extension(inst.input, FP_EXT_RECORDING_INFO) : NULL;
    fp_recording_info ri;
    memset(&ri, 0, sizeof ri);
    int status = FP_EXIT_OK;
    if (ext && ext->get && ext->get(inst.input, &ri)) {
        printf("%s\n  format    %s\n  frames    %llu\n  rate      %.1f Hz\n  hands     %s\n"
               "  duration  %.3f s\n", path, ri.format, (unsigned long long)ri.frames, ri.rate_hz,
               ri.hands == 3 ? "left, right" : ri.hands == 1 ? "left" : ri.hands == 2 ? "right" : "none",
               ri.duration_s);
        const fp_input_workspace *ws =
            inst.input->get_extension ? inst.input->get_extension(inst.input, FP_EXT_WORKSPACE) : NULL;
        float lo[3], hi[3];
        if (ws && ws->get && ws->get(inst.input, lo, hi))
            printf("  workspace x %.1f..%.1f y %.1f..%.1f z %.1f..%.1f mm\n", lo[0], hi[0], lo[1],
                   hi[1], lo[2], hi[2]);
    } else {
        fprintf(stderr, "facepuppet info: %s: the replay input gives no recording info\n", path);
        status = FP_EXIT_FAILURE;
    }
    fp_input_instance_close(&inst);
    fp_plugin_path_clear(&pp);
    return status;
}

/* A CyberGlove calibration (.cal), read as the glove input reads it (glove_cal.h): its format
 * and, per sensor in the glove's order, the joint angle it gives at the 8-bit extremes. */
static int cal_info(const char *path)
{
    fpg_cal cal;
    char err[1024];
    int rc = fpg_cal_load(path, &cal, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet info: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    int used = __builtin_popcount(cal.used);
    const double deg = 180.0 / 3.14159265358979323846;
    printf("%s\n  format    CyberGlove calibration, %s%s\n  sensors   %d of %d calibrated", path,
           fpg_cal_format_name(cal.format),
           cal.format == FPG_CAL_GAIN_OFFSET ? " (sensors it does not list keep the default map)" : "",
           used, FPG_SENSORS);
    const char *sep = " (unused:";
    for (int i = 0; i < FPG_SENSORS; i++)
        if (!(cal.used >> i & 1)) printf("%s %d %s", sep, i, fpg_sensor_name(i)), sep = ",";
    printf("%s\n  sensor            degrees at raw 1 .. 254 (an 18-sensor glove has no DIJ sensors)\n",
           used < FPG_SENSORS ? ")" : "");
    for (int i = 0; i < FPG_SENSORS; i++) {
        if (!(cal.used >> i & 1)) continue;
        printf("  %2d %-14s %7.1f .. %.1f\n", i, fpg_sensor_name(i), fpg_cal_angle(&cal, i, 1) * deg,
               fpg_cal_angle(&cal, i, 254) * deg);
    }
    printf("  use       --input cyberglove:DEVICE,cal=%s\n", path);
    return FP_EXIT_OK;
}

static int info_main(int argc, char **argv)
{
    if (argc != 2 || !strcmp(argv[1], "-h") || !strcmp(argv[1], "--help")) {
        FILE *f = argc == 2 ? stdout : stderr;
        fprintf(f, "usage: facepuppet info FILE\n\n"
                   "A mesh (OBJ, PLY, OFF, STL, glTF): vertices, triangles, bounds, units; a glTF's\n"
                   "  morph targets, animation (keys, duration, rate) and root scale too.\n"
                   "A recording (joints CSV, angles CSV, Leap playback original, event log): frames,\n"
                   "  rate, hands, duration.\n"
                   "A rig (RIG.json): regions, landmarks, hinge, channels; checked against its mesh.\n"
                   "A take (.fptake): its header, frames, timecode, and where it was cut if it was.\n"
                   "A stack (.fpstack): its layers (take, region, mode, range, gain, mute, solo).\n"
                   "A hand calibration (calibrate --out, JSON): unit, rotation, offsets.\n"
                   "A CyberGlove calibration (.cal): its format and each sensor's angle range.\n"
                   "A sound file (WAV, FLAC, Ogg, AIFF): rate, channels, duration, peak, its LTC.\n"
                   "A point cache (.pc2, .mdd, as export writes them): points, frames, times.\n");
        return argc == 2 ? FP_EXIT_OK : FP_EXIT_USAGE;
    }
    if (argv[1][0] == '-' && argv[1][1]) { /* an option it does not have (a file: ./-name) */
        fprintf(stderr, "facepuppet info: unknown option '%s' (info takes one FILE; see --help)\n",
                argv[1]);
        return FP_EXIT_USAGE;
    }
    const char *dot = strrchr(argv[1], '.');
    unsigned char head[12];
    const size_t nh = file_head(argv[1], head, sizeof head);
    /* (a calibration, a point cache or a sound file is not a recording: its reader's "unknown
     * format" misled) */
    if (dot && !strcasecmp(dot, ".cal")) return cal_info(argv[1]);
    if (fp_app_is_point_cache(argv[1], head, nh)) return fp_app_cache_info(argv[1]);
    if (fp_app_is_sound(head, nh)) return fp_app_sound_info(argv[1]);
    if (dot && !strcasecmp(dot, ".json")) {
        const enum json_kind k = json_kind(argv[1]);
        if (k == JSON_CALIBRATION) return calibration_info(argv[1]);
        if (k == JSON_RIG) return fp_app_rig_info(argv[1]);
    }
    if (fp_stack_is_stack_path(argv[1])) return fp_app_stack_info(argv[1]);
    if (is_take(argv[1], head, nh)) return fp_app_take_info(argv[1]);
    return is_mesh(argv[1]) ? mesh_info(argv[1]) : recording_info(argv[1]);
}

const fp_command fp_command_info = {"info", "what a mesh, recording, rig, take or other file of ours holds", info_main};
