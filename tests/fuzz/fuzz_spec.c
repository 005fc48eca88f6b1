/* fuzz_spec.c: libFuzzer target for SPEC strings (core/plugin/spec.c: NAME[:ARG][,key=value],
 * what --input, --mapping and the viewer's scripts pass). The input up to its first NUL is
 * parsed. A parse must give a valid name (a key, or a path holding '/'), at most
 * FP_SPEC_MAX_PARAMS unique valid keys, and
 * the same text when put back together; fp_spec_take gives each value once. A refusal: -EINVAL
 * and a message. The host's filter keys of an input SPEC (core/pose/fp_filter.h:
 * fp_filter_parse on filter=, mincutoff=, beta=, dcutoff=, trend=, as fp_input_instance_open takes
 * them) give a filter within the documented ranges, or -EINVAL and a message with the
 * config untouched. Seeds: tests/fuzz/corpus/fuzz_spec. */
#define _POSIX_C_SOURCE 200809L
#include "fp_plugin_host.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>

#include <ctype.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int valid_key(const char *k)
{
    if (!*k) return 0;
    for (; *k; k++)
        if (!isalnum((unsigned char)*k) && *k != '_' && *k != '-') return 0;
    return 1;
}

/* A NAME: a key, or a plugin file's path where it holds a '/' (any bytes but control
 * characters, ':' and ','; fp_plugin_host.h fp_spec_parse). */
static int valid_name(const char *n)
{
    if (!strchr(n, '/')) return valid_key(n);
    for (; *n; n++)
        if ((unsigned char)*n < 0x20 || *n == 0x7f || *n == ':' || *n == ',') return 0;
    return 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = malloc(size + 1), *back = malloc(size + 2);
    if (!text || !back) abort();
    memcpy(text, data, size);
    text[size] = '\0';
    fp_spec s;
    char err[256];
    err[0] = '\0';
    int rc = fp_spec_parse(text, &s, err, sizeof err);
    if (rc) {
        if (rc != -EINVAL || !err[0] || s.buffer) abort();
    } else {
        if (!s.name || !valid_name(s.name) || s.nparams > FP_SPEC_MAX_PARAMS) abort();
        size_t n = 0;
        n += (size_t)snprintf(back + n, size + 2 - n, "%s", s.name);
        if (s.arg) n += (size_t)snprintf(back + n, size + 2 - n, ":%s", s.arg);
        for (size_t i = 0; i < s.nparams; i++) {
            if (!valid_key(s.params[i].key) || !s.params[i].value) abort();
            for (size_t j = 0; j < i; j++)
                if (!strcmp(s.params[i].key, s.params[j].key)) abort();
            if (n > size) abort();
            n += (size_t)snprintf(back + n, size + 2 - n, ",%s=%s", s.params[i].key,
                                  s.params[i].value);
        }
        if (n != strlen(text) || strcmp(back, text) != 0) abort();
        /* the filter keys, looked up as the host takes them out */
        const char *fk[5] = {NULL, NULL, NULL, NULL, NULL};
        const char *names[5] = {"filter", "mincutoff", "beta", "dcutoff", "trend"};
        for (size_t i = 0; i < s.nparams; i++)
            for (int k = 0; k < 5; k++)
                if (!strcmp(s.params[i].key, names[k])) fk[k] = s.params[i].value;
        fp_filter_config fc, keep;
        memset(&fc, 0x5a, sizeof fc);
        keep = fc;
        char ferr[256] = "";
        int frc = fp_filter_parse(s.name, fk[0], fk[1], fk[2], fk[3], fk[4], &fc, ferr, sizeof ferr);
        if (frc) {
            if (frc != -EINVAL || !ferr[0] || memcmp(&fc, &keep, sizeof fc)) abort();
        } else {
            if (fc.kind != FP_FILTER_OFF && fc.kind != FP_FILTER_ONEEURO && fc.kind != FP_FILTER_AUTO) abort();
            if (!(fc.mincutoff > 0 && fc.mincutoff <= 1000) || !(fc.beta >= 0 && fc.beta <= 100) ||
                !(fc.dcutoff > 0 && fc.dcutoff <= 1000) || !(fc.trend >= 0 && fc.trend <= 1000))
                abort();
            double lag = fp_oneeuro_lag(&fc, 200, 60); /* 0 with a trend: a ramp followed */
            if (!(fc.trend > 0 ? lag == 0 : lag > 0) || !isfinite(lag)) abort();
            char line[512];
            if (fp_filter_describe(&fc, line, sizeof line) <= 0) abort();
        }
        size_t np = s.nparams;
        for (size_t i = 0; i < np; i++) {
            char *key = strdup(s.params[0].key);
            if (!key) abort();
            if (!fp_spec_take(&s, key) || fp_spec_take(&s, key) || s.nparams != np - i - 1)
                abort();
            free(key);
        }
        fp_spec_clear(&s);
    }
    free(text);
    free(back);
    return 0;
}
