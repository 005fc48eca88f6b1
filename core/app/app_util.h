/* Helpers shared by the subcommands: plugin search path, data paths, error -> exit code. */
#ifndef FP_APP_UTIL_H
#define FP_APP_UTIL_H

#include "fp_plugin_host.h"

/** The plugin path: --plugin-dir folders, FACEPUPPET_PLUGIN_PATH, the built-in folder. */
void fp_app_plugin_path(fp_plugin_path *path, const char *const *dirs, size_t ndirs);

/** A file under the shared data folder (FP_SHARED_DATA in the environment, else the one
 *  beside the source tree): writes "<data>/<rel>" into buf. */
const char *fp_app_data_path(const char *rel, char *buf, size_t len);

/** The exit code (enum fp_exit) for a negative code from session or plugin calls. */
int fp_app_exit_code(int rc);

#endif
