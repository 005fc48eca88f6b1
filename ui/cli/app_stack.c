/* Overdub's command side (app_stack.h). */
#define _GNU_SOURCE
#include "app_stack.h"
#include "app_util.h"
#include "command.h"
#include "fp_session.h"
#include "fp_session_take.h"
#include "fp_take.h"
#include "fp_stack_player.h"
#include "fp_error.h"
#include "fp_text.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>

static int parse_punch(const char *v, double *in, double *out)
{
    char *end;
    *in = strtod(v, &end);
    if (end == v || *end != ':') return -1;
    const char *b = end + 1;
    *out = strtod(b, &end);
    return end != b && !*end && *in >= 0 && *out > *in && isfinite(*out) ? 0 : -1;
}

int fp_app_over_check(fp_app_over *o, const char *cmd, const char *take_dir)
{
    char err[2048];
    if (!o->over) {
        if (!o->layer && !o->punch) return 0;
        fprintf(stderr, "%s: --layer and --punch need --over STACK_OR_TAKE\n", cmd);
        return FP_EXIT_USAGE;
    }
    if (!take_dir) {
        fprintf(stderr, "%s: --over needs --take-dir DIR (the pass is recorded as a take)\n", cmd);
        return FP_EXIT_USAGE;
    }
    fp_stack_region region;
    fp_stack_mode mode;
    if (fp_stack_layer_spec(o->layer ? o->layer : "mouth", &region, &mode, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", cmd, err);
        return FP_EXIT_USAGE;
    }
    fp_stack_layer_init(&o->new_layer, "");
    o->new_layer.region = region;
    o->new_layer.mode = mode;
    if (o->punch && parse_punch(o->punch, &o->new_layer.in_s, &o->new_layer.out_s)) {
        fprintf(stderr, "%s: --punch %s: give IN:OUT, seconds on the stack's clock, 0 <= IN < OUT\n",
                cmd, o->punch);
        fp_app_over_free(o);
        return FP_EXIT_USAGE;
    }
    int rc = fp_stack_over_open(o->over, &o->stack, err, sizeof err);
    if (rc) {
        fprintf(stderr, "%s: --over: %s\n", cmd, err);
        fp_app_over_free(o);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    return 0;
}

bool fp_app_over_soundtrack_offset(const fp_app_over *o, double *offset_s)
{
    if (!o->over || !o->stack) return false;
    char path[FP_STACK_PATH_MAX + 512], err[2048];
    fp_stack_over_take_path(o->over, o->stack, 0, path, sizeof path);
    fp_take_reader *r = NULL;
    if (fp_take_reader_open(path, &r, err, sizeof err)) return false;
    const fp_take_header *h = fp_take_reader_header(r);
    const bool has = h->soundtrack_path != NULL;
    if (has) *offset_s = h->soundtrack_offset_s;
    fp_take_reader_close(&r);
    return has;
}

int fp_app_over_check_mesh(const fp_app_over *o, const char *cmd, const fp_session *s,
                           const char *mesh_path)
{
    if (!o->over) return 0;
    char path[FP_STACK_PATH_MAX + 512], err[8192], why[1024];
    fp_stack_over_take_path(o->over, o->stack, 0, path, sizeof path);
    fp_take_reader *r = NULL;
    int rc = fp_take_reader_open(path, &r, err, sizeof err);
    if (!rc) {
        const fp_take_header *h = fp_take_reader_header(r);
        rc = fp_take_check_positions(fp_session_loaded(s), fp_session_vertex_count(s),
                                     mesh_path ? mesh_path : "(the loaded mesh)", h, why, sizeof why);
        if (rc) snprintf(err, sizeof err, "%s: %s", path, why);
    }
    fp_take_reader_close(&r);
    if (!rc) return 0;
    fprintf(stderr, "%s: --over: %s\n", cmd, err);
    return fp_app_exit_code(rc, FP_APP_INPUT);
}

int fp_app_over_finish(fp_app_over *o, const char *cmd, const char *take_dir,
                       const char *take_path, const char *slate)
{
    int status = fp_app_over_save(o, cmd, take_dir, take_path, slate);
    fp_app_over_free(o);
    return status;
}

/* A punch that starts at or after the pass's last frame keeps none of it: said (the stack is
 * written as asked) */
static void punch_check(const fp_app_over *o, const char *cmd, const char *take_path)
{
    char err[2048];
    fp_take_reader *r = NULL;
    if (!o->punch || fp_take_reader_open(take_path, &r, err, sizeof err)) return;
    const double d = fp_take_reader_summary(r)->duration_s;
    if (o->new_layer.in_s >= d)
        fprintf(stderr, "%s: warning: --punch %s starts after the pass's last frame (%.3f s): the new "
                "layer changes nothing (the punch is on the stack's clock, where the pass starts at 0)\n",
                cmd, o->punch, d);
    fp_take_reader_close(&r);
}

int fp_app_over_save(const fp_app_over *o, const char *cmd, const char *take_dir,
                     const char *take_path, const char *slate)
{
    char err[8192], stack_path[FP_STACK_PATH_MAX + 512];
    int rc = fp_stack_over_save(o->over, o->stack, &o->new_layer, take_dir, take_path, slate,
                                stack_path, sizeof stack_path, err, sizeof err);
    int status = FP_EXIT_OK;
    if (rc) {
        fprintf(stderr, "%s: the stack was not written: %s\n", cmd, err);
        status = fp_app_exit_code(rc, FP_APP_OUTPUT);
    } else {
        char region[512];
        fprintf(stderr, "%s: stack %s: %zu layers, top: %s, %s, %s", cmd, stack_path,
                o->stack->layer_count + 1, strrchr(take_path, '/') ? strrchr(take_path, '/') + 1 : take_path,
                fp_stack_region_text(&o->new_layer.region, region, sizeof region),
                o->new_layer.mode == FP_STACK_ADD ? "add" : "replace");
        if (o->punch) fprintf(stderr, ", punched %g s to %g s", o->new_layer.in_s, o->new_layer.out_s);
        fprintf(stderr, "\n");
        punch_check(o, cmd, take_path);
    }
    return status;
}

void fp_app_over_free(fp_app_over *o)
{
    fp_stack_free(&o->stack);
    fp_stack_region_clear(&o->new_layer.region);
}

/* "0-inf" / "1-2" seconds */
static const char *range_text(const fp_stack_layer *l, char *buf, size_t n)
{
    if (isfinite(l->out_s)) snprintf(buf, n, "%g-%g s", l->in_s, l->out_s);
    else snprintf(buf, n, "%g s-end", l->in_s);
    return buf;
}

int fp_app_stack_info(const char *path)
{
    char err[2048];
    fp_stack *s = NULL;
    int rc = fp_stack_load(path, &s, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet info: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    printf("%s\n  format       facepuppet stack %d\n  layers       %zu\n", path, FP_STACK_FORMAT_VERSION,
           s->layer_count);
    for (size_t i = 0; i < s->layer_count; i++) {
        const fp_stack_layer *l = &s->layers[i];
        char tp[FP_STACK_PATH_MAX + 512], region[512], range[64], what[256];
        fp_take_reader *r = NULL;
        fp_stack_take_path(s, i, tp, sizeof tp);
        if (fp_take_reader_open(tp, &r, err, sizeof err)) snprintf(what, sizeof what, "unreadable: %.200s", err);
        else {
            const fp_take_summary *sum = fp_take_reader_summary(r);
            snprintf(what, sizeof what, "%llu frames, %.3f s%s", (unsigned long long)sum->frames,
                     sum->duration_s, sum->cut ? ", cut" : "");
        }
        fp_take_reader_close(&r);
        printf("  %2zu  %s  %s, %s, %s, fade %g s, offset %g s, gain %g%s%s  (%s)\n", i, l->take,
               i ? fp_stack_region_text(&l->region, region, sizeof region) : "base",
               l->mode == FP_STACK_ADD ? "add" : "replace", range_text(l, range, sizeof range),
               l->fade_s, l->offset_s, l->gain, l->mute ? ", muted" : "", l->solo ? ", solo" : "", what);
    }
    fp_stack_free(&s);
    return FP_EXIT_OK;
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The *.fpstack names of dir, sorted, into names (strdup'ed; NULL where out of memory).
 * Returns how many (256 at most). */
static size_t stack_names(const char *dir, char *names[256])
{
    DIR *d = opendir(dir);
    size_t n = 0;
    for (struct dirent *e; d && (e = readdir(d)) && n < 256;)
        if (fp_stack_is_stack_path(e->d_name) && e->d_name[0] != '.') names[n++] = strdup(e->d_name);
    if (d) closedir(d);
    qsort(names, n, sizeof *names, by_name);
    return n;
}

cJSON *fp_app_stack_list_json(const char *dir)
{
    char *names[256];
    size_t n = stack_names(dir, names);
    cJSON *arr = cJSON_CreateArray();
    for (size_t i = 0; arr && i < n; i++) {
        char path[8192], err[2048] = "out of memory", region[512], c[4 * 2048];
        snprintf(path, sizeof path, "%s/%s", dir, names[i] ? names[i] : "");
        fp_stack *s = NULL;
        cJSON *o = cJSON_CreateObject(), *layers = cJSON_CreateArray();
        const bool ok = names[i] && !fp_stack_load(path, &s, err, sizeof err);
        cJSON_AddStringToObject(o, "kind", "stack");
        cJSON_AddStringToObject(o, "path", fp_text_clean(path, c, sizeof c));
        cJSON_AddStringToObject(o, "state", ok ? "ok" : "unreadable");
        cJSON_AddStringToObject(o, "message", ok ? "" : fp_text_clean(err, c, sizeof c));
        for (size_t k = 0; ok && k < s->layer_count; k++) {
            const fp_stack_layer *l = &s->layers[k];
            cJSON *e = cJSON_CreateObject();
            cJSON_AddStringToObject(e, "take", fp_text_clean(l->take, c, sizeof c));
            cJSON_AddStringToObject(e, "region", k ? fp_stack_region_text(&l->region, region, sizeof region) : "base");
            cJSON_AddStringToObject(e, "mode", l->mode == FP_STACK_ADD ? "add" : "replace");
            cJSON_AddNumberToObject(e, "in_s", l->in_s);
            if (isfinite(l->out_s)) cJSON_AddNumberToObject(e, "out_s", l->out_s);
            else cJSON_AddNullToObject(e, "out_s"); /* (to the take's end) */
            cJSON_AddNumberToObject(e, "fade_s", l->fade_s);
            cJSON_AddNumberToObject(e, "offset_s", l->offset_s);
            cJSON_AddNumberToObject(e, "gain", l->gain);
            cJSON_AddBoolToObject(e, "mute", l->mute);
            cJSON_AddBoolToObject(e, "solo", l->solo);
            cJSON_AddItemToArray(layers, e);
        }
        cJSON_AddItemToObject(o, "layers", layers);
        cJSON_AddItemToArray(arr, o);
        fp_stack_free(&s);
        free(names[i]);
    }
    return arr;
}

void fp_app_stack_list(const char *dir)
{
    char *names[256];
    size_t n = stack_names(dir, names);
    for (size_t i = 0; i < n; i++) {
        char path[8192], err[2048], region[512], range[64];
        snprintf(path, sizeof path, "%s/%s", dir, names[i] ? names[i] : "");
        fp_stack *s = NULL;
        if (!i) printf("\n%-24s %s\n", "STACK", "LAYERS");
        if (!names[i] || fp_stack_load(path, &s, err, sizeof err)) {
            printf("%-24s unreadable: %s\n", names[i] ? names[i] : "?", names[i] ? err : "out of memory");
            free(names[i]);
            continue;
        }
        printf("%-24s %zu layers: ", names[i], s->layer_count);
        for (size_t k = 0; k < s->layer_count; k++) {
            const fp_stack_layer *l = &s->layers[k];
            if (!k) printf("%s (base)", l->take);
            else printf("; %s %s %s %s%s%s", l->take, fp_stack_region_text(&l->region, region, sizeof region),
                        l->mode == FP_STACK_ADD ? "add" : "replace", range_text(l, range, sizeof range),
                        l->mute ? " muted" : "", l->solo ? " solo" : "");
        }
        printf("\n");
        fp_stack_free(&s);
        free(names[i]);
    }
}

void fp_app_stack_limited_note(const char *cmd, const char *path, const fp_stack_player *sp, bool quiet)
{
    const unsigned long n = sp ? fp_stack_player_limited(sp) : 0;
    if (quiet || !n) return;
    fprintf(stderr, "facepuppet %s: %s: the blend's fold bound held a layer back on %lu layer frame%s: "
            "there the layer shows partly, not its own frame (docs/stack.md, \"The composite does not "
            "fold\")\n", cmd, path, n, n == 1 ? "" : "s");
}
