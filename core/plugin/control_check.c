/* What makes a control set malformed (fp_control_check.h). */
#include "fp_control_check.h"

#include <math.h>

static int point_ok(const float p[3])
{
    for (int k = 0; k < 3; k++)
        if (!(fabsf(p[k]) <= FP_CONTROL_COORD_MAX)) return 0; /* (NaN fails too) */
    return 1;
}

fp_control_fault fp_control_check(const fp_control_set *cs, size_t *vector, int *is_start)
{
    if (cs->count > cs->capacity || cs->channel_count > cs->channel_capacity) return FP_CONTROL_OVER_CAPACITY;
    if (cs->count && (!cs->start || !cs->end)) return FP_CONTROL_NO_ARRAY;
    for (size_t i = 0; i < cs->count; i++) {
        const int s_ok = point_ok(cs->start[i]);
        if (s_ok && point_ok(cs->end[i])) continue;
        if (vector) *vector = i;
        if (is_start) *is_start = !s_ok;
        return FP_CONTROL_BAD_POINT;
    }
    /* the engine's range (plugin.h, csrbf.h), which a take's reader holds frames to */
    if (cs->active && !(cs->radius >= FP_CONTROL_RADIUS_MIN && cs->radius <= FP_CONTROL_RADIUS_MAX))
        return FP_CONTROL_BAD_RADIUS;
    return FP_CONTROL_OK;
}
