/* Listing plugins: every candidate file on the search path, loaded, described, unloaded. */
#define _GNU_SOURCE
#include "fp_plugin_host.h"

#include <dirent.h>
#include <errno.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

void fp_plugin_describe(const fp_plugin *p, fp_plugin_about *out)
{
    memset(out, 0, sizeof *out);
    if (!p || !p->factory) return;
    if (p->kind == FP_PLUGIN_INPUT) {
        const fp_input_factory *f = p->factory;
        out->name = f->name;
        out->description = FP_HAS_FIELD(f, fp_input_factory, description) ? f->description : NULL;
        out->usage = FP_HAS_FIELD(f, fp_input_factory, usage) ? f->usage : NULL;
        out->params = FP_HAS_FIELD(f, fp_input_factory, params) ? f->params : NULL;
    } else {
        const fp_mapping_factory *f = p->factory;
        out->name = f->name;
        out->description = FP_HAS_FIELD(f, fp_mapping_factory, description) ? f->description : NULL;
        out->usage = FP_HAS_FIELD(f, fp_mapping_factory, usage) ? f->usage : NULL;
        out->params = FP_HAS_FIELD(f, fp_mapping_factory, params) ? f->params : NULL;
    }
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The NAME of PREFIX-NAME.so, or NULL. */
static const char *plugin_name(const char *file, const char *prefix, char *buf, size_t len)
{
    size_t n = strlen(file), p = strlen(prefix);
    if (n <= p + 3 || strncmp(file, prefix, p) || strcmp(file + n - 3, ".so")) return NULL;
    snprintf(buf, len, "%.*s", (int)(n - p - 3), file + p);
    return buf;
}

size_t fp_plugin_scan(const fp_plugin_path *path,
                      void (*fn)(void *user, const fp_plugin_scan_item *item), void *user)
{
    size_t passed = 0;
    for (size_t d = 0; d < path->count; d++) {
        DIR *dir = opendir(path->dirs[d]);
        if (!dir) continue;
        char **names = NULL;
        size_t n = 0, cap = 0;
        for (struct dirent *e; (e = readdir(dir));) {
            char tmp[256];
            if (!plugin_name(e->d_name, "input-", tmp, sizeof tmp) &&
                !plugin_name(e->d_name, "map-", tmp, sizeof tmp))
                continue;
            if (n == cap) {
                char **grown = realloc(names, (cap = cap ? 2 * cap : 16) * sizeof *names);
                if (!grown) break;
                names = grown;
            }
            if (!(names[n] = strdup(e->d_name))) break;
            n++;
        }
        closedir(dir);
        qsort(names, n, sizeof *names, by_name);
        for (size_t i = 0; i < n; i++) {
            fp_plugin_scan_item it;
            memset(&it, 0, sizeof it);
            char name[256], file[4096], err[1024] = "", why[128];
            it.kind = plugin_name(names[i], "input-", name, sizeof name) ? FP_PLUGIN_INPUT : FP_PLUGIN_MAPPING;
            if (it.kind == FP_PLUGIN_MAPPING) plugin_name(names[i], "map-", name, sizeof name);
            snprintf(file, sizeof file, "%s/%s", path->dirs[d], names[i]);
            it.dir = path->dirs[d];
            it.file = file;
            it.name = name;
            for (size_t e = 0; e < d && !it.shadowed; e++) {
                char other[4096];
                snprintf(other, sizeof other, "%s/%s", path->dirs[e], names[i]);
                struct stat st; /* (stat, not open: a FIFO there is not waited on) */
                if (stat(other, &st) == 0) it.shadowed = true;
            }
            fp_plugin p;
            memset(&p, 0, sizeof p);
            if (d != path->builtin && fp_plugin_path_unsafe(file, why, sizeof why)) {
                it.code = -EACCES;
                snprintf(err, sizeof err, "%.800s skipped: %.120s", file, why);
            } else {
                it.code = fp_plugin_load(path, it.kind, file, &p, err, sizeof err);
            }
            it.error = it.code ? err : NULL;
            it.plugin = it.code ? NULL : &p;
            fn(user, &it);
            passed++;
            if (!it.code) fp_plugin_unload(&p);
            free(names[i]);
        }
        free(names);
    }
    return passed;
}
