/* SPEC strings: NAME[:ARG][,key=value...]. */
#define _POSIX_C_SOURCE 200809L
#include "fp_plugin_host.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static bool valid_key(const char *k)
{
    if (!*k) return false;
    for (; *k; k++)
        if (!isalnum((unsigned char)*k) && *k != '_' && *k != '-') return false;
    return true;
}

/* A NAME holding a '/' is a plugin file's path (docs/plugin-guide.md, "Names"): any text but
 * control characters (':' and ',' end it, as they end any NAME). */
static bool valid_name(const char *n)
{
    if (!strchr(n, '/')) return valid_key(n);
    for (; *n; n++)
        if ((unsigned char)*n < 0x20 || *n == 0x7f) return false;
    return true;
}

int fp_spec_parse(const char *text, fp_spec *spec, char *err, size_t errlen)
{
    memset(spec, 0, sizeof *spec);
    if (!text || !*text) {
        snprintf(err, errlen, "empty SPEC (expected NAME[:ARG][,key=value...])");
        return -EINVAL;
    }
    spec->buffer = strdup(text);
    if (!spec->buffer) return -ENOMEM;
    char *s = spec->buffer;
    char *comma = strchr(s, ',');
    if (comma) *comma = '\0';
    char *colon = strchr(s, ':');
    if (colon) {
        *colon = '\0';
        spec->arg = colon + 1;
    }
    spec->name = s;
    if (!valid_name(spec->name)) {
        snprintf(err, errlen, "SPEC '%s': bad name '%s' (letters, digits, '_' and '-'; or a "
                 "plugin file's path, holding a '/')", text,
                 spec->name);
        fp_spec_clear(spec);
        return -EINVAL;
    }
    for (char *p = comma ? comma + 1 : NULL; p;) {
        char *next = strchr(p, ',');
        if (next) *next++ = '\0';
        char *eq = strchr(p, '=');
        if (!eq && spec->nparams > 0) {
            /* a value runs to the next `,key=`: `keys=a,b,c` is keys "a,b,c" (docs/pedal.md);
             * the value before is contiguous in the buffer, its comma was cut at p[-1] */
            p[-1] = ',';
            p = next;
            continue;
        }
        if (!eq) {
            snprintf(err, errlen, "SPEC '%s': '%s' is not key=value", text, p);
            fp_spec_clear(spec);
            return -EINVAL;
        }
        *eq = '\0';
        if (!valid_key(p)) {
            snprintf(err, errlen, "SPEC '%s': bad key '%s'", text, p);
            fp_spec_clear(spec);
            return -EINVAL;
        }
        for (size_t i = 0; i < spec->nparams; i++)
            if (!strcmp(spec->params[i].key, p)) {
                snprintf(err, errlen, "SPEC '%s': key '%s' given twice", text, p);
                fp_spec_clear(spec);
                return -EINVAL;
            }
        if (spec->nparams == FP_SPEC_MAX_PARAMS) {
            snprintf(err, errlen, "SPEC '%s': more than %d keys", text, FP_SPEC_MAX_PARAMS);
            fp_spec_clear(spec);
            return -EINVAL;
        }
        spec->params[spec->nparams].key = p;
        spec->params[spec->nparams].value = eq + 1;
        spec->nparams++;
        p = next;
    }
    return 0;
}

const char *fp_spec_take(fp_spec *spec, const char *key)
{
    for (size_t i = 0; i < spec->nparams; i++)
        if (!strcmp(spec->params[i].key, key)) {
            const char *v = spec->params[i].value;
            memmove(&spec->params[i], &spec->params[i + 1],
                    (spec->nparams - i - 1) * sizeof spec->params[0]);
            spec->nparams--;
            return v;
        }
    return NULL;
}

void fp_spec_clear(fp_spec *spec)
{
    free(spec->buffer);
    memset(spec, 0, sizeof *spec);
}
