/* The one error convention: codes, their text, and the message-buffer helpers. */
#include "fp_error.h"
#include "fp_text.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

const char *fp_strerror(int code)
{
    switch (code) {
    case 0: return "success";
    case FP_EPLUGIN_NOT_FOUND: return "plugin not found";
    case FP_EPLUGIN_DLOPEN: return "plugin could not be loaded";
    case FP_EPLUGIN_NO_ENTRY: return "plugin has no facepuppet_plugin_entry";
    case FP_EPLUGIN_ABI: return "plugin built for an incompatible ABI";
    case FP_EPLUGIN_INIT: return "plugin init failed";
    case FP_EPLUGIN_NO_FACTORY: return "plugin has no factory of that kind";
    case FP_EPLUGIN_FAULT: return "plugin misbehaved";
    case FP_ENUMERIC: return "numerical failure";
    case -EBADMSG: return "malformed data";
    default: break;
    }
    if (code < 0 && code > -4096) {
        /* strerror's text for errno values; its buffer is static for known codes on glibc,
         * and unknown ones fall through to the generic text below. */
        const char *s = strerror(-code);
        if (s && strncmp(s, "Unknown error", 13)) return s;
    }
    return code < 0 ? "unknown error" : "not an error";
}

int fp_error_is_plugin(int code)
{
    return code <= FP_EPLUGIN_NOT_FOUND && code >= FP_EPLUGIN_FAULT;
}

/* err (errlen bytes) made one line a terminal may show (fp_text_clean), where it is not */
static void clean(char *err, size_t errlen)
{
    if (fp_text_ok(err, false)) return;
    char raw[4096];
    snprintf(raw, sizeof raw, "%s", err);
    fp_text_clean(raw, err, errlen);
}

int fp_verrorf(char *err, size_t errlen, int code, const char *fmt, va_list ap)
{
    if (err && errlen) {
        vsnprintf(err, errlen, fmt, ap);
        clean(err, errlen);
    }
    return code;
}

int fp_errorf(char *err, size_t errlen, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fp_verrorf(err, errlen, code, fmt, ap);
    va_end(ap);
    return code;
}

int fp_error_prefix(char *err, size_t errlen, int code, const char *fmt, ...)
{
    if (!err || !errlen) return code;
    char old[1024];
    snprintf(old, sizeof old, "%s", err);
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
    if (n >= 0 && (size_t)n < errlen && old[0]) snprintf(err + n, errlen - (size_t)n, ": %s", old);
    clean(err, errlen);
    return code;
}

int fp_error_at(char *err, size_t errlen, int code, const char *path, long line, long col,
                const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fp_verrorf(err, errlen, code, fmt, ap);
    va_end(ap);
    if (line > 0 && col > 0)
        return fp_error_prefix(err, errlen, code, "%s:%ld:%ld", path, line, col);
    if (line > 0) return fp_error_prefix(err, errlen, code, "%s:%ld", path, line);
    return fp_error_prefix(err, errlen, code, "%s", path);
}
