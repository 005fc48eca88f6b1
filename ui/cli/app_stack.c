/* Overdub's command side (app_stack.h). */
#define _GNU_SOURCE
#include "app_stack.h"
#include "app_util.h"
#include "command.h"
#include "fp_session.h"
#include "fp_session_take.h"
#include "fp_take.h"
#include "fp_error.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* path as stored in a stack in dir: its name alone when it lies in dir, else absolute. */
static int stack_relative(const char *dir, const char *path, char *buf, size_t n)
{
    char rd[PATH_MAX], rp[PATH_MAX];
    if (!realpath(dir, rd) || !realpath(path, rp)) return -errno;
    const char *slash = strrchr(rp, '/');
    size_t k = strlen(rd);
    if (slash && (size_t)(slash - rp) == k && !strncmp(rp, rd, k))
        return snprintf(buf, n, "%s", slash + 1) < (int)n ? 0 : -ENAMETOOLONG;
    return snprintf(buf, n, "%s", rp) < (int)n ? 0 : -ENAMETOOLONG;
}

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
    int rc;
    if (fp_stack_is_stack_path(o->over)) {
        rc = fp_stack_load(o->over, &o->stack, err, sizeof err);
    } else {  /* a take: a stack of it alone (its path relative to the new stack's folder) */
        fp_take_reader *r = NULL;
        rc = fp_take_reader_open(o->over, &r, err, sizeof err);
        fp_take_reader_close(&r);
        fp_stack_layer base;
        fp_stack_layer_init(&base, o->over);
        if (!rc && !(o->stack = fp_stack_create())) rc = fp_errorf(err, sizeof err, -ENOMEM, "out of memory");
        if (!rc) rc = fp_stack_append(o->stack, &base, err, sizeof err);
    }
    if (rc) {
        fprintf(stderr, "%s: --over: %s\n", cmd, err);
        fp_app_over_free(o);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    return 0;
}

int fp_app_over_check_mesh(const fp_app_over *o, const char *cmd, const fp_session *s)
{
    if (!o->over) return 0;
    char path[FP_STACK_PATH_MAX + 512], err[8192], why[1024];
    if (fp_stack_is_stack_path(o->over)) fp_stack_take_path(o->stack, 0, path, sizeof path);
    else snprintf(path, sizeof path, "%s", o->over);
    fp_take_reader *r = NULL;
    int rc = fp_take_reader_open(path, &r, err, sizeof err);
    if (!rc) {
        const fp_take_header *h = fp_take_reader_header(r);
        rc = fp_take_check_positions(fp_session_loaded(s), fp_session_vertex_count(s),
                                     h->mesh_path ? h->mesh_path : "?", h, why, sizeof why);
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
    char err[8192], stack_path[FP_STACK_PATH_MAX + 512], p[FP_STACK_PATH_MAX + 512];
    int rc = 0;
    fp_stack *s = fp_stack_create();
    if (!s) rc = -ENOMEM, snprintf(err, sizeof err, "out of memory");
    /* the old layers, their takes as seen from the new stack's folder */
    for (size_t i = 0; !rc && i < o->stack->layer_count; i++) {
        fp_stack_layer l = o->stack->layers[i];
        if (fp_stack_is_stack_path(o->over)) fp_stack_take_path(o->stack, i, p, sizeof p);
        else snprintf(p, sizeof p, "%s", o->over);
        if ((rc = stack_relative(take_dir, p, l.take, sizeof l.take)))
            snprintf(err, sizeof err, "%s: %s", p, strerror(-rc));
        else rc = fp_stack_append(s, &l, err, sizeof err);
    }
    if (!rc && (rc = stack_relative(take_dir, take_path, o->new_layer.take, sizeof o->new_layer.take)))
        snprintf(err, sizeof err, "%s: %s", take_path, strerror(-rc));
    if (!rc) rc = fp_stack_append(s, &o->new_layer, err, sizeof err);
    if (!rc && (rc = fp_stack_next_path(take_dir, slate ? slate : "take", stack_path, sizeof stack_path)))
        snprintf(err, sizeof err, "%s: no stack name: %s", take_dir, strerror(-rc));
    if (!rc) rc = fp_stack_save(s, stack_path, err, sizeof err);
    int status = FP_EXIT_OK;
    if (rc) {
        fprintf(stderr, "%s: the stack was not written: %s\n", cmd, err);
        status = fp_app_exit_code(rc, FP_APP_OUTPUT);
    } else {
        char region[512];
        fprintf(stderr, "%s: stack %s: %zu layers, top: %s, %s, %s", cmd, stack_path, s->layer_count,
                o->new_layer.take, fp_stack_region_text(&o->new_layer.region, region, sizeof region),
                o->new_layer.mode == FP_STACK_ADD ? "add" : "replace");
        if (o->punch) fprintf(stderr, ", punched %g s to %g s", o->new_layer.in_s, o->new_layer.out_s);
        fprintf(stderr, "\n");
    }
    fp_stack_free(&s);
    fp_app_over_free(o);
    return status;
}

void fp_app_over_free(fp_app_over *o)
{
    fp_stack_free(&o->stack);
    fp_stack_region_clear(&o->new_layer.region);
}
