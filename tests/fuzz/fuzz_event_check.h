/* fuzz_event_check.h: what every decoded fp_event must satisfy, whatever the input: a known
 * type with its struct's size, hand -1, 0 or 1, every float finite, angles' valid mask within
 * the 22 sensors, status text NUL-terminated, a channel's name printable ASCII. Aborts
 * otherwise. Test code only. */
#ifndef FP_FUZZ_EVENT_CHECK_H
#define FP_FUZZ_EVENT_CHECK_H

#include <facepuppet/plugin.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void fuzz_check_floats(const float *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) abort();
}

static void fuzz_check_event(const fp_event *e)
{
    const fp_event_header *h = &e->header;
    if (h->hand < -1 || h->hand > 1) abort();
    switch (h->type) {
    case FP_EVENT_JOINT_ANGLES:
        if (h->size < sizeof e->angles || e->angles.valid >> FP_GLOVE_SENSORS) abort();
        fuzz_check_floats(e->angles.radians, FP_GLOVE_SENSORS);
        break;
    case FP_EVENT_JOINT_POSITIONS:
        if (h->size < sizeof e->positions) abort();
        fuzz_check_floats(&e->positions.mm[0][0], FP_HAND_JOINTS * 3);
        break;
    case FP_EVENT_WRIST_POSE:
        if (h->size < sizeof e->wrist) abort();
        fuzz_check_floats(e->wrist.position_mm, 3);
        fuzz_check_floats(e->wrist.rotation, 4);
        break;
    case FP_EVENT_BUTTON:
        if (h->size < sizeof e->button) abort();
        break;
    case FP_EVENT_STATUS:
        if (h->size < sizeof e->status || !memchr(e->status.text, 0, sizeof e->status.text))
            abort();
        break;
    case FP_EVENT_CHANNEL: { /* a name of printable ASCII without spaces, a finite value */
        if (h->size < sizeof e->channel) abort();
        const char *z = memchr(e->channel.name, 0, sizeof e->channel.name);
        if (!z || z == e->channel.name) abort();
        for (const char *q = e->channel.name; q < z; q++)
            if (*q <= ' ' || *q > '~') abort();
        fuzz_check_floats(&e->channel.value, 1);
        break;
    }
    default:
        abort();
    }
}

#endif
