#include "app_util.h"

#include "command.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

#ifndef FP_PLUGIN_RELDIR
#define FP_PLUGIN_RELDIR "../lib/facepuppet"
#endif
#ifndef FP_SHARED_DATA
#define FP_SHARED_DATA "../shared/data"
#endif

void fp_app_plugin_path(fp_plugin_path *path, const char *const *dirs, size_t ndirs)
{
    char builtin[4096];
    snprintf(builtin, sizeof builtin, "%s/%s", fp_app_exe_dir(), FP_PLUGIN_RELDIR);
    fp_plugin_path_init(path, dirs, ndirs, builtin);
}

const char *fp_app_data_path(const char *rel, char *buf, size_t len)
{
    const char *root = getenv("FP_SHARED_DATA");
    snprintf(buf, len, "%s/%s", root && *root ? root : FP_SHARED_DATA, rel);
    return buf;
}

int fp_app_exit_code(int rc)
{
    if (rc <= -1001 && rc >= -1006) return FP_EXIT_PLUGIN;
    switch (-rc) {
    case 0: return FP_EXIT_OK;
    case ENOENT: case EACCES: case ENODEV: case EBUSY: return FP_EXIT_NOINPUT;
    case EINVAL: case EBADMSG: case EPROTO: case ERANGE: return FP_EXIT_DATAERR;
    case ENOMEM: return FP_EXIT_SOFTWARE;
    default: return FP_EXIT_FAILURE;
    }
}
