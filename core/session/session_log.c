/* The session's log: one callback, repeated errors counted instead of repeated. */
#include "session_log.h"

#include <facepuppet/plugin.h>

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static void vsend(const fp_slog *log, int level, const char *source, const char *fmt, va_list ap)
{
    if (!log || !log->fn) return;
    char msg[512];
    vsnprintf(msg, sizeof msg, fmt, ap);
    log->fn(log->user, level, source ? source : "session", msg);
}

bool fp_slog_is_note(int level, const char *source)
{
    return level > FP_LOG_ERROR && source &&
           (!strcmp(source, FP_SLOG_ENGINE) || !strcmp(source, FP_SLOG_CONTACT));
}

void fp_slog_printf(const fp_slog *log, int level, const char *source, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsend(log, level, source, fmt, ap);
    va_end(ap);
}

void fp_slog_repeat_flush(fp_slog_repeat *r, const fp_slog *log)
{
    if (r->code && r->repeats)
        fp_slog_printf(log, r->level, r->source, "%s (repeated %lu more time%s)", r->message,
                       r->repeats, r->repeats == 1 ? "" : "s");
    r->code = 0;
    r->repeats = 0;
}

bool fp_slog_repeat_report(fp_slog_repeat *r, const fp_slog *log, int level, const char *source,
                           int code, const char *fmt, ...)
{
    r->total++;
    if (!source) source = "session";
    if (r->code && r->code == code && !strcmp(r->source, source)) {
        r->repeats++;
        return false;
    }
    fp_slog_repeat_flush(r, log);
    r->code = code ? code : -1;
    r->level = level;
    snprintf(r->source, sizeof r->source, "%s", source);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->message, sizeof r->message, fmt, ap);
    va_end(ap);
    fp_slog_printf(log, level, r->source, "%s", r->message);
    return true;
}
