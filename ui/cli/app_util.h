/* Helpers shared by the subcommands: plugin search path, data paths, error -> exit code. */
#ifndef FP_APP_UTIL_H
#define FP_APP_UTIL_H

#include "fp_plugin_host.h"
#include "fp_session.h"

#include <stdbool.h>

/** The plugin path: --plugin-dir folders, FACEPUPPET_PLUGIN_PATH, the built-in folder. */
void fp_app_plugin_path(fp_plugin_path *path, const char *const *dirs, size_t ndirs);

/** A file under the shared data folder (FP_SHARED_DATA in the environment, else the one
 *  beside the source tree): writes "<data>/<rel>" into buf. */
const char *fp_app_data_path(const char *rel, char *buf, size_t len);

/** The exit code (enum fp_exit) for a negative code from session or plugin calls. */
int fp_app_exit_code(int rc);

/** Storage for the strings fp_app_session_defaults puts into a fp_session_options; it must
 *  outlive the options' use. */
typedef struct fp_app_inputs {
    char demo_mesh[4096];
    char demo_input[4200];
    char specs[FP_SESSION_MAX_INPUTS][4300];
} fp_app_inputs;

/** Defaults shared by `run` and `live`. With neither a mesh nor an input the session is the
 *  demo: the ICT face and the three-claps recording (returns true). Without a mesh: the ICT
 *  face. Without a mapping: "anchored". A speed other than 1 is appended as `,speed=X` to
 *  every replay input that sets none. Strings point into *buf. */
bool fp_app_session_defaults(fp_session_options *so, double speed, fp_app_inputs *buf);

#endif
