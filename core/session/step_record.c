/* Step 7 of the frame: the frame's record to the sink; watching record=FILE writers. */
#include "step_record.h"

#include "fp_session.h"

#include <stdlib.h>
#include <string.h>

void fp_record_step_init(fp_record_step *r, fp_frame_record_fn sink, void *user)
{
    memset(r, 0, sizeof *r);
    r->sink = sink;
    r->user = user;
}

void fp_record_step_free(fp_record_step *r)
{
    free(r->events);
    r->events = NULL;
    r->count = r->capacity = 0;
}

void fp_record_step_begin(fp_record_step *r)
{
    r->count = 0;
    r->lost = 0;
}

void fp_record_step_event(fp_record_step *r, const fp_event *ev)
{
    if (!r->sink) return;
    if (r->count == r->capacity) {
        size_t cap = r->capacity ? 2 * r->capacity : 256;
        fp_event *grown = realloc(r->events, cap * sizeof *grown);
        if (!grown) {
            r->lost++;
            return;
        }
        r->events = grown;
        r->capacity = cap;
    }
    r->events[r->count++] = *ev;
}

void fp_record_step_end(fp_record_step *r, uint64_t frame, int64_t time_ns, uint32_t requested,
                        const fp_control_set *controls, const struct fp_frame_stats *st,
                        fp_input_instance *inputs, size_t n, const fp_slog *log)
{
    if (r->sink) {
        fp_frame_record rec = {frame, time_ns, r->events, r->count, r->lost, requested, controls,
                               st ? st->reach : NULL, st ? st->reach_vectors : 0,
                               st ? st->reach_asked_max : 0, st ? st->reach_held : 0};
        r->sink(r->user, &rec);
    }
    for (size_t i = 0; i < n && i < sizeof r->reported / sizeof r->reported[0]; i++) {
        if (r->reported[i] || !inputs[i].record) continue;
        char msg[512];
        if (fp_input_instance_record_error(&inputs[i], msg, sizeof msg)) {
            fp_slog_printf(log, FP_LOG_ERROR, inputs[i].name, "record: %s", msg);
            r->reported[i] = true;
        }
    }
}
