/* session_opts.h: the options `facepuppet run` and `facepuppet live` share, in one table:
 * parsed once, their --help text printed from the same table. */
#ifndef FP_CLI_SESSION_OPTS_H
#define FP_CLI_SESSION_OPTS_H

#include "fp_session.h"

#include <getopt.h>
#include <stdbool.h>
#include <stdio.h>

/** The short letters of the shared options, for getopt_long's optstring. */
#define FP_SESSION_OPTS_SHORT "m:i:M:r:s:qP:"
/** How many entries fp_session_opts_longopts writes. */
#define FP_SESSION_OPTS_COUNT 18
/** A command's own long-only options take values from here up (the shared ones use 0x100..). */
#define FP_SESSION_OPTS_FIRST_FREE 0x200
#define FP_SESSION_OPTS_MAX_PLUGIN_DIRS 8

/** The parsed shared options. The strings point into argv. */
typedef struct fp_session_opts {
    fp_session_options *session;  /* --mesh, --input (repeatable), --mapping, --radius, --hand-size */
    double speed;                 /* --speed: replay speed factor, default 1 */
    double duration_s;            /* --duration: stop after this many seconds; 0: no limit */
    bool quiet;                   /* --quiet: no progress or status lines, nor the engine's
                                     notes (fp_slog_is_note; fp_app_log_line_quiet) */
    const char *plugin_dirs[FP_SESSION_OPTS_MAX_PLUGIN_DIRS]; /* --plugin-dir (repeatable) */
    size_t nplugin_dirs;
    fp_calibration calibration;   /* --calibration FILE, loaded (session->calibration points here) */
    const char *control;          /* --control osc:PORT: the OSC control surface (app_link.h) */
    const char *stream;           /* --stream osc:HOST:PORT: the live output stream */
} fp_session_opts;

/** Zero *o, point it at `session` (zeroed by the caller) and set the defaults. */
void fp_session_opts_init(fp_session_opts *o, fp_session_options *session);

/** Write the FP_SESSION_OPTS_COUNT getopt_long entries of the shared options to out; the
 *  caller appends its own and the terminating zero entry. Returns FP_SESSION_OPTS_COUNT. */
size_t fp_session_opts_longopts(struct option *out);

/** Parse one option as getopt_long returned it (c and its argument). Returns 1 when c is a
 *  shared option and its value is good, 0 when c is not a shared option, -EINVAL when the
 *  value is bad, the calibration file's code (fp_calibration_load: -ENOENT, -EBADMSG,
 *  -ERANGE) for --calibration (the message, prefixed "facepuppet CMD: ", is on stderr). */
int fp_session_opts_parse(fp_session_opts *o, int c, const char *arg, const char *cmd);

/** --up and --facing's AXIS: +x, -x, +y, -y, +z, -z (or x, y, z) into a unit axis; false for
 *  anything else (out untouched). */
bool fp_session_opts_axis(const char *arg, float out[3]);

/** Print the shared options' help lines (one table for both commands). */
void fp_session_opts_help(FILE *f);

#endif
