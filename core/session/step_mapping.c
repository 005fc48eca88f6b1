/* Step 3 of the frame: the mapping call and the check of its control set. */
#include "step_mapping.h"

#include "fp_error.h"

#include <errno.h>
#include <math.h>

int fp_control_set_check(const fp_control_set *cs)
{
    if (cs->count > cs->capacity || cs->channel_count > cs->channel_capacity) return -ERANGE;
    if (!(cs->radius > 0) || !isfinite(cs->radius)) return -EINVAL;
    if (cs->count && (!cs->start || !cs->end)) return -EINVAL;
    for (size_t i = 0; i < cs->count; i++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(cs->start[i][k]) || !isfinite(cs->end[i][k])) return -EINVAL;
    return 0;
}

int fp_mapping_step_run(fp_mapping_step *st, fp_mapping *mapping, const char *name,
                        const fp_frame_input *in, fp_control_set *cs, const fp_slog *log)
{
    int rc = mapping->process(mapping, in, cs);
    const char *what = "process() failed";
    if (rc >= 0) {
        rc = fp_control_set_check(cs);
        what = rc == -ERANGE ? "control set over capacity" : "invalid control set (radius or points)";
    }
    if (rc < 0) {
        fp_slog_repeat_report(&st->errors, log, FP_LOG_ERROR, name, rc,
                              "%s on frame %llu (%s); keeping the last shape", what,
                              (unsigned long long)in->frame, fp_strerror(rc));
        cs->active = false;
        cs->intents = 0;
        return rc;
    }
    fp_slog_repeat_flush(&st->errors, log);
    return 0;
}

void fp_mapping_step_flush(fp_mapping_step *st, const fp_slog *log) { fp_slog_repeat_flush(&st->errors, log); }
