/* facepuppet calibrate: a calibration file from a short recording (docs/calibration.md). */
#define _GNU_SOURCE
#include "app_getopt.h"
#include "app_util.h"
#include "session_opts.h"
#include "command.h"
#include "fp_calib_file.h"
#include "fp_calib_fit.h"
#include "fp_head.h"
#include "fp_mesh.h"
#include "fp_plugin_host.h"
#include "fp_rig.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static void usage(FILE *f)
{
    fprintf(f,
        "usage: facepuppet calibrate --mesh FILE --input SPEC --out FILE.json\n"
        "                            [--mode hold|touch] [--mm-per-unit X] [--duration S]\n"
        "                            [--rig FILE] [--up AXIS --facing AXIS] [--plugin-dir DIR]\n"
        "                            [--force]\n\n"
        "Make a calibration file for `run --calibration` / `live --calibration` from a short\n"
        "recording of the performer's hands (a tracker's joint positions):\n"
        "  hold   (default) hold both hands where the face is, palms to the face, for a few\n"
        "         seconds: each hand's median palm goes onto the face in front of its half,\n"
        "         life-size (the mesh's unit as `run` detects it, or --mm-per-unit)\n"
        "  touch  touch chin, nose tip and forehead in turn with the index fingertip,\n"
        "         holding each for half a second: the three longest still moments are\n"
        "         matched to those landmarks (from the mesh's rig when one is found, else\n"
        "         estimated from the head) and scale, rotation and offset are fitted\n"
        "The input is read to its end (a recording; add fast=1 to read it at once) or for\n"
        "--duration seconds. The file is written atomically; an existing one is refused\n"
        "before any work unless --force.\n"
        "  -m, --mesh FILE        the face (default: the ICT face of the demo)\n"
        "  -i, --input SPEC       the recording or device (required)\n"
        "  -o, --out FILE         the calibration file to write (required)\n"
        "      --force            overwrite --out when it exists\n"
        "      --mode hold|touch  see above (default hold)\n"
        "      --mm-per-unit X    the mesh's unit, mm (hold; default: detected from the head)\n"
        "      --rig FILE         the rig whose landmarks touch uses (default: found by mesh)\n"
        "      --up AXIS, --facing AXIS  hold: the face's up and the axis it looks along\n"
        "                         (+x, -x, +y, -y, +z, -z; default: the rig's, else +y, +z)\n"
        "  -d, --duration S       stop reading after S seconds\n"
        "  -P, --plugin-dir DIR   more plugin folders\n"
        "  -h, --help             this text\n\n"
        "Exit status: 0 written, 64 usage, 65 the recording does not allow a calibration\n"
        "(no joint positions, touches not found), 66 input missing, 73 output not writable\n"
        "or existing without --force,\n"
        "78 plugin missing.\n");
}

/* Read every joint-position sample of the input until its end or `duration` seconds. */
static int read_samples(fp_input_instance *inst, double duration, fp_calib_sample **out, size_t *n,
                        size_t *angles_seen)
{
    size_t cap = 1024;
    fp_calib_sample *s = malloc(cap * sizeof *s);
    if (!s) return -ENOMEM;
    *n = 0;
    int64_t t0 = fp_now_ns();
    for (bool ended = false; !ended;) {
        fp_event ev;
        bool any = false;
        fp_input_instance_drain_log(inst);
        while (!ended && fp_input_instance_poll(inst, &ev)) {
            any = true;
            if (ev.header.type == FP_EVENT_STATUS && ev.status.code == FP_STATUS_END_OF_STREAM) ended = true;
            if (ev.header.type == FP_EVENT_JOINT_ANGLES) (*angles_seen)++;
            if (ev.header.type != FP_EVENT_JOINT_POSITIONS) continue;
            if (ev.header.hand != FP_HAND_LEFT && ev.header.hand != FP_HAND_RIGHT) continue;
            if (*n == cap) {
                fp_calib_sample *g = realloc(s, 2 * cap * sizeof *s);
                if (!g) {
                    free(s);
                    return -ENOMEM;
                }
                s = g, cap *= 2;
            }
            s[*n].t_ns = ev.header.time_ns;
            s[*n].hand = ev.header.hand;
            memcpy(s[*n].joints, ev.positions.mm, sizeof s[*n].joints);
            (*n)++;
        }
        if (duration > 0 && fp_now_ns() - t0 > (int64_t)(duration * 1e9)) break;
        if (!any) {
            struct timespec ts = {0, 2000000};
            nanosleep(&ts, NULL);
        }
    }
    *out = s;
    return 0;
}

/* Landmarks for touch: the rig's chin and nose_tip (and forehead when it has one) where a rig
 * was given or found (`rig`, at `rig_path`; calibrate_main loads it up front), the head's
 * estimate for the rest; `why`: why a rig found did not load ("" for none). Prints where
 * they came from. */
static void landmarks(const fp_mesh *m, const fp_head *head, const fp_rig *rig, const char *rig_path,
                      const char *why, float lm[FP_CALIB_LANDMARKS][3])
{
    fp_calib_head_landmarks(m->positions, m->vertex_count, head, lm);
    if (!rig) {
        printf("landmarks: estimated from the head%s%s\n", why[0] ? " (rig: " : "", why);
        if (why[0]) printf(")\n");
        return;
    }
    static const char *names[FP_CALIB_LANDMARKS] = {"chin", "nose_tip", "forehead"};
    printf("landmarks: rig %s:", rig_path);
    for (int i = 0; i < FP_CALIB_LANDMARKS; i++) {
        long v = fp_rig_landmark_index(rig, names[i]);
        if (v >= 0 && (size_t)v < m->vertex_count) {
            memcpy(lm[i], m->positions + 3 * v, sizeof lm[i]);
            printf(" %s = vertex %ld", names[i], v);
        } else {
            printf(" %s estimated", names[i]);
        }
    }
    printf("\n");
}

/* What the command line asked for (calibrate_parse). */
typedef struct calibrate_args {
    const char *mesh_path, *input, *out, *rig_path;
    bool touch;                    /* --mode touch (else hold) */
    bool no_rig;                   /* --rig none: the head's estimated landmarks, no rig looked for */
    char rig_why[1024];            /* why the rig found by the mesh did not load ("": none) */
    bool force;                    /* --force: an existing --out is overwritten */
    const char *dirs[8];
    size_t ndirs;
    double mm_per_unit, duration;
    float up[3], facing[3];        /* --up, --facing (zeros: not given) */
    char demo[4096];               /* the demo mesh's path, when --mesh is not given */
} calibrate_args;

/* Parse the command line into *a. Returns -1 to go on, or the exit status (0 after --help). */
static int calibrate_parse(int argc, char **argv, calibrate_args *a)
{
    static const struct option opts[] = {
        {"mesh", required_argument, 0, 'm'},     {"input", required_argument, 0, 'i'},
        {"out", required_argument, 0, 'o'},      {"mode", required_argument, 0, 'M'},
        {"mm-per-unit", required_argument, 0, 'u'}, {"duration", required_argument, 0, 'd'},
        {"rig", required_argument, 0, 'r'},      {"plugin-dir", required_argument, 0, 'P'},
        {"help", no_argument, 0, 'h'},           {"force", no_argument, 0, 'F'},
        {"up", required_argument, 0, 'U'},       {"facing", required_argument, 0, 'A'},
        {0, 0, 0, 0}};
    const char *mode = "hold";
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, "m:i:o:d:P:h", opts)) != -1;) {
        switch (c) {
        case 'm': a->mesh_path = optarg; break;
        case 'i':
            if (a->input) {
                fprintf(stderr, "facepuppet calibrate: one --input (given '%s' and '%s')\n", a->input, optarg);
                return FP_EXIT_USAGE;
            }
            if (fp_app_spec_looks_like_file("facepuppet calibrate", "--input", optarg))
                return FP_EXIT_USAGE;
            a->input = optarg;
            break;
        case 'o': a->out = optarg; break;
        case 'F': a->force = true; break;
        case 'M': mode = optarg; break;
        case 'r': a->rig_path = strcmp(optarg, "none") ? optarg : NULL, a->no_rig = !a->rig_path; break;
        case 'u':
            if (!fp_parse_decimal(optarg, &a->mm_per_unit) || !(a->mm_per_unit > 0)) {
                fprintf(stderr, "facepuppet calibrate: --mm-per-unit must be > 0, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case 'd':
            if (!fp_parse_decimal(optarg, &a->duration) ||
                !(a->duration > 0 && a->duration < FP_APP_MAX_DURATION_S)) {
                fprintf(stderr, "facepuppet calibrate: --duration must be > 0 s and under 1e7, got "
                        "'%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case 'P': if (a->ndirs < 8) a->dirs[a->ndirs++] = optarg; break;
        case 'U':
        case 'A':
            if (!fp_session_opts_axis(optarg, c == 'U' ? a->up : a->facing)) {
                fprintf(stderr, "facepuppet calibrate: --%s must be +x, -x, +y, -y, +z or -z, got '%s'\n",
                        c == 'U' ? "up" : "facing", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        case 'h': usage(stdout); return FP_EXIT_OK;
        default: usage(stderr); return FP_EXIT_USAGE;
        }
    }
    a->touch = !strcmp(mode, "touch");
    if (!a->touch && strcmp(mode, "hold")) {
        fprintf(stderr, "facepuppet calibrate: --mode must be hold or touch, got '%s'\n", mode);
        return FP_EXIT_USAGE;
    }
    if (!a->input || !a->out || optind != argc) {
        fprintf(stderr, "facepuppet calibrate: %s\n\n", !a->input ? "--input SPEC is required"
                        : !a->out ? "--out FILE is required" : "unexpected argument (see below)");
        usage(stderr);
        return FP_EXIT_USAGE;
    }
    double q[4];
    bool given = a->up[0] != 0 || a->up[1] != 0 || a->up[2] != 0 || a->facing[0] != 0 || a->facing[1] != 0 ||
                 a->facing[2] != 0;
    if (given && fp_face_from_axes(a->up, a->facing, q)) {
        fprintf(stderr, "facepuppet calibrate: give both --up and --facing, two axes at a right angle "
                "(e.g. --up +z --facing -y)\n");
        return FP_EXIT_USAGE;
    }
    int oc = fp_app_check_new_output("facepuppet calibrate", "--out", a->out, a->force);
    if (oc) return oc;
    if (!a->mesh_path &&
        !(a->mesh_path = fp_app_data_path("facepuppet calibrate", "faces/ict-facekit/generic_neutral_mesh.obj",
                                          a->demo, sizeof a->demo)))
        return FP_EXIT_NOINPUT;
    return -1;
}

/* The face's vertices (fp_mesh_face_mask: in a triangle, not far off the rest), or NULL when
 * every one is (or out of memory: then all count): the head is found on the surface, as the
 * session finds it. */
static uint8_t *surface_vertices(const fp_mesh *m)
{
    uint8_t *used;
    size_t unused, far;
    return fp_mesh_face_mask(m, &used, &unused, &far) ? NULL : used;
}

/* No rig and no --up/--facing: a face that probably looks elsewhere than +z said, as `run`
 * says it (fp_head_facing_hint): the hold's unit and place are found as for +z, +y up (a Z-up
 * copy of ICT gave 77.59 mm per unit, not 10.24, in silence). */
static void warn_facing(const calibrate_args *a, const fp_mesh *m)
{
    char msg[768];
    uint8_t *used = surface_vertices(m);
    if (fp_head_facing_hint(m->positions, m->vertex_count, used, msg, sizeof msg))
        fprintf(stderr, "facepuppet calibrate: warning: %s: %s\n", a->mesh_path, msg);
    free(used);
}

/* The face and its head: loaded, detected, and --mm-per-unit checked as run checks it (a face
 * under 1 mm or over 1 km is a slip). Returns 0 or the exit status (said); *m to free. */
static int load_face(const calibrate_args *a, fp_mesh **m, fp_head *head)
{
    char err[2048];
    int rc = fp_app_load_mesh("facepuppet calibrate", false, a->mesh_path, m, err, sizeof err);
    if (rc != FP_MESH_OK) {
        fprintf(stderr, "facepuppet calibrate: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    uint8_t *used = surface_vertices(*m);
    int hrc = fp_head_detect_used((*m)->positions, (*m)->vertex_count, used, head);
    float lo[3], hi[3];
    fp_mesh_bounds_used(*m, used, lo, hi); /* (the surface's, as the session's) */
    free(used);
    if (hrc) {
        fprintf(stderr, "facepuppet calibrate: %s: cannot find a head (flat or non-finite mesh)\n", a->mesh_path);
        return FP_EXIT_DATAERR;
    }
    if (a->mm_per_unit > 0) {
        const double diag = sqrt((double)(hi[0] - lo[0]) * (hi[0] - lo[0]) +
                                 (double)(hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                 (double)(hi[2] - lo[2]) * (hi[2] - lo[2]));
        double across;
        if (!fp_head_scale_plausible(diag, a->mm_per_unit, &across)) {
            fprintf(stderr, "facepuppet calibrate: --mm-per-unit %g makes the face %.3g mm across "
                            "(its diagonal %.4g mesh units); give millimetres per mesh unit\n",
                    a->mm_per_unit, across, diag);
            return FP_EXIT_USAGE;
        }
        head->mm_per_unit = a->mm_per_unit;
        snprintf(head->how, sizeof head->how, "from --mm-per-unit");
    }
    return 0;
}

/* Open the input, read its joint positions (read_samples), close it. Returns 0 or a
 * negative code (message in err, or none: strerror). */
static int record_samples(const calibrate_args *a, fp_calib_sample **smp, size_t *n,
                          size_t *angles, char *err, size_t errlen)
{
    fp_plugin_path path;
    fp_app_plugin_path(&path, a->dirs, a->ndirs);
    fp_input_instance inst;
    memset(&inst, 0, sizeof inst);
    int rc = fp_input_instance_open(&inst, &path, a->input, 0, err, errlen);
    if (!rc) fp_input_instance_set_log(&inst, fp_app_log_line, NULL); /* its log lines */
    if (!rc) rc = fp_input_instance_start(&inst, err, errlen);
    if (!rc) rc = read_samples(&inst, a->duration, smp, n, angles);
    fp_input_instance_close(&inst);
    fp_plugin_path_clear(&path);
    return rc;
}

/* The rig `run` finds for mesh m (fp_rig_find in the default folder, by checksum or vertex
 * count), loaded into *rig, its path in path; false where none fits (why stays "") or the one
 * found does not load (why says so). */
static bool find_rig(const fp_mesh *m, char *path, size_t len, fp_rig **rig, char *why, size_t whylen)
{
    char dir[4096], err[1024];
    fp_rig_default_dir(fp_app_exe_dir(), dir, sizeof dir);
    if (fp_rig_find(dir, m->vertex_count, m->positions, path, len, err, sizeof err)) return false;
    return fp_rig_load_for_mesh(path, m->vertex_count, m->positions, rig, why, whylen) == 0;
}

/* Hold mode: say when a hand moved through what should have been a hold. */
static void warn_unheld(const calibrate_args *a, const fp_calib_sample *smp, size_t n)
{
    double travel[FP_HANDS];
    fp_calib_hold_travel(smp, n, travel);
    for (int h = 0; h < FP_HANDS; h++)
        if (travel[h] > FP_CALIB_HOLD_TRAVEL_MM)
            fprintf(stderr, "facepuppet calibrate: warning: %s: the %s hand's palm travelled %.0f mm "
                    "during the hold (over %.0f mm: not held still); its median place is used, but "
                    "hold both hands still in front of the face, or use --mode touch "
                    "(docs/calibration.md)\n", a->input, h ? "right" : "left", travel[h],
                    FP_CALIB_HOLD_TRAVEL_MM);
}

/* Fit the calibration to the samples (hold or touch), write it atomically, say so. Returns
 * the exit status. */
static int fit_and_save(const calibrate_args *a, const fp_mesh *m, const fp_head *head,
                        fp_rig *given_rig, const fp_calib_sample *smp, size_t n)
{
    char err[2048];
    int rc;
    fp_calibration c;
    double touched[FP_CALIB_LANDMARKS][3], rms = 0;
    char how[sizeof head->how]; /* (hold: where the unit came from) */
    memcpy(how, head->how, sizeof how);
    if (a->touch) {
        float lm[FP_CALIB_LANDMARKS][3];
        landmarks(m, head, given_rig, a->rig_path, a->rig_why, lm);
        rc = fp_calib_fit_touch(smp, n, (const float(*)[3])lm, &c, touched, &rms, err, sizeof err);
    } else {
        warn_unheld(a, smp, n);
        /* a face turned in its mesh (its rig placed on a turned copy): held in front of the
         * face's own axes, the file holding the turn (fp_calibration.face, flattened) */
        double q[4] = {1, 0, 0, 0};
        if (a->up[0] != 0 || a->up[1] != 0 || a->up[2] != 0) fp_face_from_axes(a->up, a->facing, q); /* (checked) */
        else if (given_rig) fp_rig_face_rotation(given_rig, q);
        else warn_facing(a, m);
        float *turned = fp_face_turned(q) ? malloc(m->vertex_count * 3 * sizeof *turned) : NULL;
        fp_head th;
        uint8_t *used = turned ? surface_vertices(m) : NULL;
        int hrc = turned ? fp_head_detect_turned(m->positions, m->vertex_count, used, q, turned, &th) : -1;
        free(used);
        if (!hrc) {
            if (a->mm_per_unit > 0 || given_rig) { /* a given unit; else the face frame's detection */
                th.mm_per_unit = head->mm_per_unit;
                memcpy(th.how, head->how, sizeof th.how);
            }
            rc = fp_calib_fit_hold(smp, n, turned, m->vertex_count, &th, &c, err, sizeof err);
            memcpy(c.face, q, sizeof c.face);
            snprintf(how, sizeof how, "%s (the face's frame)", th.how);
        } else {
            rc = fp_calib_fit_hold(smp, n, m->positions, m->vertex_count, head, &c, err, sizeof err);
        }
        free(turned);
    }
    if (rc) {
        fprintf(stderr, "facepuppet calibrate: %s: %s\n", a->input, strncmp(err, "calibrate: ", 11) ? err : err + 11);
        return rc == -ENOMEM ? 1 : FP_EXIT_DATAERR;
    }
    char comment[512];
    if (a->touch)
        snprintf(comment, sizeof comment, "facepuppet calibrate --mode touch: %zu samples; touches "
                 "(mm) chin %.0f %.0f %.0f, nose tip %.0f %.0f %.0f, forehead %.0f %.0f %.0f; "
                 "residual %.3g mm", n, touched[0][0], touched[0][1], touched[0][2], touched[1][0],
                 touched[1][1], touched[1][2], touched[2][0], touched[2][1], touched[2][2], rms / c.scale);
    else
        snprintf(comment, sizeof comment, "facepuppet calibrate --mode hold: %zu samples; "
                 "%.4g mm per mesh unit, %s", n, 1.0 / c.scale, how);
    rc = fp_calibration_save(a->out, &c, comment, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet calibrate: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_OUTPUT);
    }
    printf("wrote %s: %.4g mm per mesh unit%s; %s\n", a->out, 1.0 / c.scale,
           a->touch ? " (fitted)" : "", comment);
    return FP_EXIT_OK;
}

static int calibrate_main(int argc, char **argv)
{
    calibrate_args a = {0};
    int status = calibrate_parse(argc, argv, &a);
    if (status >= 0) return status;
    fp_mesh *m = NULL;
    fp_head head;
    fp_rig *given_rig = NULL;
    fp_calib_sample *smp = NULL;
    char err[2048] = "";
    if ((status = load_face(&a, &m, &head))) goto done;
    /* a rig given is loaded (and bound to this mesh) before the recording is read: one that
     * does not fit the mesh is an error, not a silent fall back to estimated landmarks */
    int rc;
    if (a.rig_path && (rc = fp_rig_load_for_mesh(a.rig_path, m->vertex_count, m->positions, &given_rig,
                                                 err, sizeof err))) {
        fprintf(stderr, "facepuppet calibrate: --rig %s\n", err);
        status = fp_app_exit_code(rc, FP_APP_INPUT);
        goto done;
    }
    /* no --rig: the rig run would find for this mesh (its landmarks for touch, its scale) */
    char found[4096] = "";
    const char *rig_path = a.rig_path;
    if (!given_rig && !a.no_rig && find_rig(m, found, sizeof found, &given_rig, a.rig_why, sizeof a.rig_why))
        rig_path = found;
    if (given_rig && !(a.mm_per_unit > 0)) { /* the scale run uses: --mm-per-unit, the rig, the head */
        head.mm_per_unit = fp_rig_mm_per_unit(given_rig);
        snprintf(head.how, sizeof head.how, "from the rig %s", rig_path);
    }
    a.rig_path = rig_path;
    size_t n = 0, angles = 0;
    if ((rc = record_samples(&a, &smp, &n, &angles, err, sizeof err))) {
        fprintf(stderr, "facepuppet calibrate: %s\n", err[0] ? err : strerror(-rc));
        status = fp_app_exit_code(rc, FP_APP_INPUT);
        goto done;
    }
    if (!n) {
        fprintf(stderr, "facepuppet calibrate: %s: no joint positions%s: calibrate needs a tracker's "
                "positions (a glove alone is placed by default, docs/calibration.md)\n", a.input,
                angles ? " (only joint angles)" : "");
        status = FP_EXIT_DATAERR;
        goto done;
    }
    status = fit_and_save(&a, m, &head, given_rig, smp, n);
done:
    free(smp);
    fp_rig_free(&given_rig);
    fp_mesh_free(&m);
    return status;
}

const fp_command fp_command_calibrate = {"calibrate",
                                         "make a calibration file from a short recording (hold or touch)",
                                         calibrate_main};
