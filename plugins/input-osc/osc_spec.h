/*
 * osc_spec.h: the input-osc plugin's SPEC (its keys, their defaults and --help text), private
 * to the plugin: osc_spec.c parses, input_osc.c uses the settings.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FP_OSC_SPEC_H
#define FP_OSC_SPEC_H

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>

#define DEFAULT_PORT 9000
#define HUGE_MM FP_EVENT_MAX_MM     /* 10 m: beyond it a position is hostile or broken */

enum osc_format { FMT_FACEPUPPET, FMT_LEAP, FMT_MEDIAPIPE, FMT_VMC, FMT_AUTO };
enum { HANDS_LEFT = 1, HANDS_RIGHT = 2, HANDS_BOTH = 3 };
/* clock=: how bundles' timetags become event times */
enum osc_clock { CLOCK_ARRIVAL, CLOCK_RECORDING };

/** "facepuppet", "leap", "mediapipe", "vmc", "auto" by enum osc_format. */
extern const char *const fp__osc_format_names[];
/** The factory's usage text and typed keys. */
extern const char fp__osc_usage[];
extern const fp_param_info fp__osc_keys[];

/* What the SPEC asked for (parse_spec). */
typedef struct osc_settings {
    long port;
    int format, hands, clock;
    double timeout, width, aspect, height, depth;
    bool mirror, have_box;
    float box[6];
    const char *bind_addr;
} osc_settings;

/** The SPEC: [:PORT] and its keys, into *o (defaults first). Returns 0 or a negative code
 *  (-EINVAL, -ENOTSUP for format=vmc) with a message naming the key in err. */
int fp__osc_parse_spec(const char *arg, const fp_param *params, size_t nparams, osc_settings *o,
                       char *err, size_t errlen);

#endif
