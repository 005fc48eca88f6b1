/* Step 3 of the frame: the mapping call, its time, its canaries and the check of its
 * control set. */
#define _POSIX_C_SOURCE 200809L
#include "step_mapping.h"

#include "fp_control_check.h"
#include "fp_error.h"
#include "fp_plugin_crash.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static const unsigned char canary = 0xA5;

int fp_control_set_check(const fp_control_set *cs)
{
    switch (fp_control_check(cs, NULL, NULL)) {
    case FP_CONTROL_OK: return 0;
    case FP_CONTROL_OVER_CAPACITY: return -ERANGE;
    default: return -EINVAL;
    }
}

static void fill_canaries(fp_mapping_step *st)
{
    memset(st->start[FP_CONTROL_CAPACITY], canary, sizeof st->start[0] * FP_MAPPING_GUARD);
    memset(st->end[FP_CONTROL_CAPACITY], canary, sizeof st->end[0] * FP_MAPPING_GUARD);
    memset(&st->channels[FP_CHANNEL_CAPACITY], canary, sizeof st->channels[0] * FP_MAPPING_GUARD);
}

/* The first array whose canary was overwritten, or NULL. */
static const char *overwritten(const fp_mapping_step *st)
{
    const unsigned char *p[3] = {(const unsigned char *)st->start[FP_CONTROL_CAPACITY],
                                 (const unsigned char *)st->end[FP_CONTROL_CAPACITY],
                                 (const unsigned char *)&st->channels[FP_CHANNEL_CAPACITY]};
    const size_t n[3] = {sizeof st->start[0] * FP_MAPPING_GUARD, sizeof st->end[0] * FP_MAPPING_GUARD,
                         sizeof st->channels[0] * FP_MAPPING_GUARD};
    static const char *names[3] = {"start", "end", "channels"};
    for (int a = 0; a < 3; a++)
        for (size_t i = 0; i < n[a]; i++)
            if (p[a][i] != canary) return names[a];
    return NULL;
}

void fp_mapping_step_init(fp_mapping_step *st, fp_control_set *cs, double budget_ms)
{
    memset(&st->errors, 0, sizeof st->errors);
    memset(&st->slow, 0, sizeof st->slow);
    st->budget_ms = budget_ms > 0 ? budget_ms : FP_MAPPING_BUDGET_MS;
    st->stopped = false;
    st->fault = 0;
    st->fault_message[0] = '\0';
    st->slow_calls = 0;
    st->slow_max_ms = 0;
    fill_canaries(st);
    st->guarded = true;
    cs->size = sizeof *cs;
    cs->active = false;
    cs->intents = 0;
    cs->count = 0;
    cs->channel_count = 0;
    cs->capacity = FP_CONTROL_CAPACITY;
    cs->start = st->start;
    cs->end = st->end;
    cs->channel_capacity = FP_CHANNEL_CAPACITY;
    cs->channels = st->channels;
}

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static const char *source_of(char buf[96], const char *name)
{
    snprintf(buf, 96, "mapping '%s'", name ? name : "?");
    return buf;
}

/* A set refused (the mapping's error, a fault, stopped): nothing deformed, and nothing of
 * what the mapping wrote kept, so that a take records an empty, valid set (the session's
 * radius): a reader would take a refused set's NaN or huge radius for damage and cut the
 * take there. */
static double session_radius(const fp_frame_input *in)
{
    return in->radius >= FP_CONTROL_RADIUS_MIN && in->radius <= FP_CONTROL_RADIUS_MAX ? in->radius : 1.0;
}

static void refuse(fp_control_set *cs, const fp_frame_input *in)
{
    cs->active = false;
    cs->intents = 0;
    cs->count = 0;
    cs->channel_count = 0;
    cs->radius = session_radius(in);
}

/* A set the host refuses (fp_control_check.h): reported naming what is wrong in it (the
 * vector, its start or end point and the values, the radius, the count), so that the author
 * sees the fault without running `plugins check`. Returns 0, -ERANGE (over a capacity) or
 * -EINVAL. */
static int refusal(const fp_control_set *cs, unsigned long long frame, fp_slog_repeat *errors,
                   const fp_slog *log, const char *source)
{
    size_t v = 0;
    int at_start = 0;
    switch (fp_control_check(cs, &v, &at_start)) {
    case FP_CONTROL_OK: return 0;
    case FP_CONTROL_OVER_CAPACITY:
        if (cs->count > cs->capacity)
            fp_slog_repeat_report(errors, log, FP_LOG_ERROR, source, -ERANGE,
                                  "control set over capacity: count %zu > capacity %zu on frame %llu; "
                                  "the base shown", cs->count, cs->capacity, frame);
        else
            fp_slog_repeat_report(errors, log, FP_LOG_ERROR, source, -ERANGE,
                                  "control set over capacity: channel_count %zu > channel_capacity %zu "
                                  "on frame %llu; the base shown", cs->channel_count,
                                  cs->channel_capacity, frame);
        return -ERANGE;
    case FP_CONTROL_NO_ARRAY:
        fp_slog_repeat_report(errors, log, FP_LOG_ERROR, source, -EINVAL,
                              "invalid control set: count %zu with a NULL %s array on frame %llu; "
                              "the base shown", cs->count, cs->start ? "end" : "start", frame);
        return -EINVAL;
    case FP_CONTROL_BAD_POINT: {
        const float *p = at_start ? cs->start[v] : cs->end[v];
        fp_slog_repeat_report(errors, log, FP_LOG_ERROR, source, -EINVAL,
                              "invalid control set: vector %zu's %s point (%g, %g, %g) is not finite "
                              "or beyond %g mesh units on frame %llu; the base shown", v,
                              at_start ? "start" : "end", (double)p[0], (double)p[1], (double)p[2],
                              FP_CONTROL_COORD_MAX, frame);
        return -EINVAL;
    }
    case FP_CONTROL_BAD_RADIUS:
        fp_slog_repeat_report(errors, log, FP_LOG_ERROR, source, -EINVAL,
                              "invalid control set: radius %g of an active set, outside [%g, %g] mesh "
                              "units on frame %llu; the base shown", cs->radius, FP_CONTROL_RADIUS_MIN,
                              FP_CONTROL_RADIUS_MAX, frame);
        return -EINVAL;
    }
    return -EINVAL;
}

int fp_mapping_step_run(fp_mapping_step *st, fp_mapping *mapping, const char *name,
                        const fp_frame_input *in, fp_control_set *cs, const fp_slog *log)
{
    char source[96]; /* the reports' source, "mapping 'NAME'", made only for a report */
    unsigned long long frame = (unsigned long long)in->frame;
    if (st->stopped) {
        refuse(cs, in);
        return st->fault;
    }
    fp_plugin_call_enter(name, "process", in->frame);
    double t0 = now_ms();
    int rc = mapping->process(mapping, in, cs);
    double ms = now_ms() - t0;
    fp_plugin_call_leave();
    double budget = st->budget_ms > 0 ? st->budget_ms : FP_MAPPING_BUDGET_MS;
    if (ms > budget) {
        st->slow_calls++;
        if (ms > st->slow_max_ms) st->slow_max_ms = ms;
        fp_slog_repeat_report(&st->slow, log, FP_LOG_WARNING, source_of(source, name), -ETIME,
                              "process took %.2f ms on frame %llu, over the budget of %g ms "
                              "(frames may be dropped)", ms, frame, budget);
    }
    const char *which = st->guarded && cs->start == st->start ? overwritten(st) : NULL;
    if (which) {
        size_t cap = !strcmp(which, "channels") ? cs->channel_capacity : cs->capacity;
        snprintf(st->fault_message, sizeof st->fault_message,
                 "wrote past the capacity of the host's %s array (%zu entries) on frame %llu; "
                 "the mapping is stopped, the base stays shown", which, cap, frame);
        fp_slog_printf(log, FP_LOG_ERROR, source_of(source, name), "%s", st->fault_message);
        fill_canaries(st);
        st->stopped = true;
        st->fault = FP_EPLUGIN_FAULT;
        refuse(cs, in);
        return st->fault;
    }
    if (rc == FP_EPLUGIN_FAULT) { /* an isolated mapping that wrote past the arrays (its proxy
                                   * said so and stopped it): stopped, as in process */
        snprintf(st->fault_message, sizeof st->fault_message,
                 "wrote past the capacity of the host's arrays on frame %llu (in its helper "
                 "process); the mapping is stopped, the base stays shown", frame);
        st->stopped = true;
        st->fault = FP_EPLUGIN_FAULT;
        refuse(cs, in);
        return st->fault;
    }
    if (rc < 0) {
        fp_slog_repeat_report(&st->errors, log, FP_LOG_ERROR, source_of(source, name), rc,
                              "process returned %d (%s) on frame %llu; the base shown", rc,
                              fp_strerror(rc), frame);
        refuse(cs, in);
        return rc;
    }
    rc = refusal(cs, frame, &st->errors, log, source_of(source, name));
    if (rc < 0) {
        refuse(cs, in);
        return rc;
    }
    /* an inactive set's radius is not the mapping's (fp_control_check.h); a take records it */
    if (!cs->active && !(cs->radius >= FP_CONTROL_RADIUS_MIN && cs->radius <= FP_CONTROL_RADIUS_MAX))
        cs->radius = session_radius(in);
    fp_slog_repeat_flush(&st->errors, log);
    return 0;
}

void fp_mapping_step_flush(fp_mapping_step *st, const fp_slog *log)
{
    fp_slog_repeat_flush(&st->errors, log);
    fp_slog_repeat_flush(&st->slow, log);
}
