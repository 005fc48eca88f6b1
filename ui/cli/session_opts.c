/* The options `run` and `live` share: one table for getopt, parsing and --help. */
#define _GNU_SOURCE
#include "session_opts.h"
#include "app_util.h"

#include "command.h"
#include "fp_rig.h"

#include "fp_calib_file.h"
#include "fp_isolate.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { OPT_DURATION = 0x100, OPT_HAND_SIZE, OPT_PLUGIN_DIR, OPT_MM_PER_UNIT, OPT_CALIBRATION, OPT_RIG,
       OPT_CONTROL, OPT_STREAM, OPT_ISOLATE, OPT_ISOLATE_DEADLINE, OPT_UP, OPT_FACING };

static const struct {
    const char *name;
    int has_arg, val;
    const char *arg, *help;   /* help: lines after the first are indented under it */
} table[FP_SESSION_OPTS_COUNT] = {
    {"mesh", required_argument, 'm', "FILE", "face mesh (OBJ, PLY, OFF, STL, glTF)"},
    {"input", required_argument, 'i', "SPEC",
     "NAME[:ARG][,key=value...] (repeatable), e.g.\n"
     "replay:../shared/data/hands/leap-motion/grab_joints_mm.csv\n"
     "any input also takes record=FILE (an event log of it),\n"
     "forward=osc:HOST:PORT (its events sent to another\n"
     "session, docs/osc.md) and the hand filter (One Euro, per\n"
     "joint, a hand's joints sharing the fastest one's cutoff):\n"
     "filter=oneeuro|auto|off, mincutoff=HZ (steadier when\n"
     "still: lower), beta=B (less lag when moving: higher),\n"
     "dcutoff=HZ, trend=HZ (Holt's trend: no lag on a steady\n"
     "motion; 0: off); auto by default for osc (mincutoff=0.3,\n"
     "beta=0.01,dcutoff=6,trend=6 on MediaPipe's landmarks, which\n"
     "jitter; a Leap's joints, smooth already, as sent), light\n"
     "for cyberglove (mincutoff=3,beta=0.025,dcutoff=8,trend=0),\n"
     "off for replay and take; each hand is shown at the\n"
     "frame's time (interpolated, or predicted up to one sample\n"
     "ahead); performer=NAME: whose\n"
     "hands (each performer has a left and a right hand and a\n"
     "placement of their own, at most 4; without it: the\n"
     "first input's performer), e.g. osc:9000,performer=B;\n"
     "calibration=FILE: that performer's own calibration"},
    {"mapping", required_argument, 'M', "SPEC", "anchored (default), unanchored, onehand or a plugin's NAME [,key=value...]"},
    {"radius", required_argument, 'r', "R",
     "support radius in mesh units (default 6% of the mesh's\nbounding-box diagonal, at least 25 mm)"},
    {"mm-per-unit", required_argument, OPT_MM_PER_UNIT, "X",
     "the mesh's unit in millimetres (default: detected from\nthe head, about 23 cm chin to crown)"},
    {"up", required_argument, OPT_UP, "AXIS",
     "the face's up in the mesh: +x, -x, +y, -y, +z or -z\n(with --facing; default: the rig's, else +y)"},
    {"facing", required_argument, OPT_FACING, "AXIS",
     "the axis the face looks along (with --up; default: the\nrig's, else +z): a Z-up export, --up +z --facing -y"},
    {"calibration", required_argument, OPT_CALIBRATION, "FILE",
     "hand calibration JSON (docs/calibration.md; made by\n`facepuppet calibrate`). Default: life-size, in front\n"
     "of the face: a recording fitted from its whole range,\na live tracker's hands as they arrive (refined as\n"
     "they move); either brought closer where their moving\nfingertips never come near (a live one after 1 s);\n"
     "a hint after 3 s of hands that never reach"},
    {"speed", required_argument, 's', "X", "replay speed factor for replay inputs (default 1)"},
    {"duration", required_argument, OPT_DURATION, "S", "stop after S seconds (default: when the inputs end)"},
    {"hand-size", required_argument, OPT_HAND_SIZE, "F", "performer's hand size, 1 = mean adult"},
    {"plugin-dir", required_argument, 'P', "DIR", "look for plugins in DIR too, after the built-in folder (repeatable)"},
    {"rig", required_argument, OPT_RIG, "R",
     "rig file (rigs/README.md); default: the mesh's rig found\nby checksum, else vertex count; 'none': no rig"},
    {"control", required_argument, OPT_CONTROL, "SPEC",
     "osc:PORT[,bind=ADDR]: take commands over OSC (record\nstart/stop with slate and take, engage, commit, undo,\n"
     "radius, mapping, channels...), each answered with the\nstatus; also Live Link Face's /RecordStart (docs/osc.md);\n"
     "with --take-dir, run records only when told"},
    {"stream", required_argument, OPT_STREAM, "SPEC",
     "osc:HOST:PORT[,step=MM][,key=N][,mtu=B]: send every frame\n(vertex offsets from the neutral, 0.05 mm steps; rig\n"
     "channels) over OSC, a keyframe every 30 frames; the\nBlender add-on receives it (docs/osc.md, Stream)"},
    {"isolate", required_argument, OPT_ISOLATE, "WHICH",
     "third-party (default): a mapping or input plugin not\nshipped with facepuppet runs in a helper process; a\n"
     "crash or hang there holds the mapping's last control\nset, or releases the input's hands, and restarts it;\n"
     "all: every plugin so; none: every one in process"},
    {"isolate-deadline", required_argument, OPT_ISOLATE_DEADLINE, "MS",
     "an isolated mapping's process() that has not answered\nwithin MS ms (default 50) is abandoned, its helper\nrestarted"},
    {"quiet", no_argument, 'q', NULL,
     "no progress or status lines, nor the engine's and\ncontact guard's notes on each gesture; the summary\n"
     "(stdout), errors and the lines of the inputs,\nrecordings, mapping, rig and session (the hands'\n"
     "placement, the hint) still print"},
};

void fp_session_opts_init(fp_session_opts *o, fp_session_options *session)
{
    memset(o, 0, sizeof *o);
    o->session = session;
    static char rig_dir[1024]; /* the rig folder next to the program (fp_rig_default_dir) */
    session->rig_dir = fp_rig_default_dir(fp_app_exe_dir(), rig_dir, sizeof rig_dir);
    o->speed = 1;
    session->isolate = FP_ISOLATE_THIRD_PARTY;
}

size_t fp_session_opts_longopts(struct option *out)
{
    for (size_t i = 0; i < FP_SESSION_OPTS_COUNT; i++)
        out[i] = (struct option){table[i].name, table[i].has_arg, NULL, table[i].val};
    return FP_SESSION_OPTS_COUNT;
}

/* A finite decimal number in (lo, hi) (exclusive bounds), the whole of arg (no hex, inf or
 * nan: fp_parse_decimal). */
static bool number(const char *arg, double lo, double hi, double *out)
{
    double v;
    if (!fp_parse_decimal(arg, &v) || !(v > lo && v < hi)) return false;
    *out = v;
    return true;
}

bool fp_session_opts_axis(const char *arg, float out[3])
{
    int sign = 1;
    if (*arg == '+' || *arg == '-') sign = *arg++ == '-' ? -1 : 1;
    if (!arg[0] || arg[1] || arg[0] < 'x' || arg[0] > 'z') return false;
    out[0] = out[1] = out[2] = 0;
    out[arg[0] - 'x'] = (float)sign;
    return true;
}

static int bad(const char *cmd, const char *what, const char *arg)
{
    fprintf(stderr, "facepuppet %s: %s, got '%s'\n", cmd, what, arg);
    return -EINVAL;
}

int fp_session_opts_parse(fp_session_opts *o, int c, const char *arg, const char *cmd)
{
    fp_session_options *so = o->session;
    switch (c) {
    case 'm': so->mesh_path = arg; return 1;
    case 'i':
        if (so->input_count == FP_SESSION_MAX_INPUTS) {
            fprintf(stderr, "facepuppet %s: at most %d --input\n", cmd, FP_SESSION_MAX_INPUTS);
            return -EINVAL;
        }
        char who[64]; /* ("facepuppet run") */
        snprintf(who, sizeof who, "facepuppet %s", cmd);
        if (fp_app_spec_looks_like_file(who, "--input", arg)) return -EINVAL;
        so->inputs[so->input_count++] = arg;
        return 1;
    case 'M': so->mapping = arg; return 1;
    case OPT_RIG: so->rig_path = arg; return 1;
    case 'r':
        return number(arg, 0, INFINITY, &so->radius) ? 1 : bad(cmd, "--radius must be a number > 0", arg);
    case 's':
        return number(arg, 0.999e-3, 1.000001e6, &o->speed) ? 1
               : bad(cmd, "--speed must be a number from 0.001 to 1e6", arg);
    case OPT_DURATION:
        return number(arg, 0, FP_APP_MAX_DURATION_S, &o->duration_s) ? 1
               : bad(cmd, "--duration must be > 0 seconds and under 1e7 (116 days)", arg);
    case OPT_HAND_SIZE:
        return number(arg, 0.2999999, 3.0000001, &so->hand_size) ? 1
               : bad(cmd, "--hand-size must be in 0.3..3", arg);
    case 'P':
        if (o->nplugin_dirs == FP_SESSION_OPTS_MAX_PLUGIN_DIRS) {
            fprintf(stderr, "facepuppet %s: at most %d --plugin-dir\n", cmd,
                    FP_SESSION_OPTS_MAX_PLUGIN_DIRS);
            return -EINVAL;
        }
        o->plugin_dirs[o->nplugin_dirs++] = arg;
        return 1;
    case OPT_MM_PER_UNIT:
        if (!number(arg, 0, INFINITY, &so->mm_per_unit)) return bad(cmd, "--mm-per-unit must be a number > 0", arg);
        so->mm_per_unit_source = "--mm-per-unit";
        return 1;
    case OPT_CALIBRATION: {
        char err[1024];
        int rc = fp_calibration_load(arg, &o->calibration, err, sizeof err);
        if (rc) {
            fprintf(stderr, "facepuppet %s: --calibration %s\n", cmd, err);
            return rc;
        }
        so->calibration = &o->calibration;
        so->calibration_source = arg;
        return 1;
    }
    case OPT_ISOLATE: {
        fp_isolate_mode mode;
        if (fp_isolate_mode_parse(arg, &mode)) return bad(cmd, "--isolate must be all, none or third-party", arg);
        so->isolate = (int)mode;
        return 1;
    }
    case OPT_ISOLATE_DEADLINE:
        return number(arg, 0.999, 60001, &so->isolate_deadline_ms) ? 1
               : bad(cmd, "--isolate-deadline must be 1 to 60000 ms", arg);
    case OPT_UP:
        return fp_session_opts_axis(arg, so->face_up) ? 1 : bad(cmd, "--up must be +x, -x, +y, -y, +z or -z", arg);
    case OPT_FACING:
        return fp_session_opts_axis(arg, so->face_facing) ? 1 : bad(cmd, "--facing must be +x, -x, +y, -y, +z or -z", arg);
    case 'q': o->quiet = true; return 1;
    case OPT_CONTROL: o->control = arg; return 1;
    case OPT_STREAM: o->stream = arg; return 1;
    default: return 0;
    }
}

void fp_session_opts_help(FILE *f)
{
    for (size_t i = 0; i < FP_SESSION_OPTS_COUNT; i++) {
        char flag[48];
        int n = table[i].val < 0x100 ? snprintf(flag, sizeof flag, "-%c, ", table[i].val)
                                     : snprintf(flag, sizeof flag, "    ");
        snprintf(flag + n, sizeof flag - (size_t)n, "--%s%s%s", table[i].name,
                 table[i].arg ? " " : "", table[i].arg ? table[i].arg : "");
        fprintf(f, "  %-22s ", flag);
        for (const char *h = table[i].help; *h;) {
            size_t len = strcspn(h, "\n");
            fprintf(f, "%.*s\n", (int)len, h);
            h += len;
            if (*h == '\n' && *++h) fprintf(f, "%25s", "");
        }
    }
}
