/*
 * osc_spec.c: the input-osc plugin's SPEC parsed into osc_settings (osc_spec.h).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "osc_spec.h"

#include <facepuppet/decimal.h>
#include <facepuppet/plugin_util.h>

#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const fp__osc_format_names[] = {"facepuppet", "leap", "mediapipe", "vmc", "auto"};

const char fp__osc_usage[] =
    "osc[:PORT][,format=auto|facepuppet|leap|mediapipe][,bind=ADDR][,hand=left|right|both]\n"
    "   [,timeout=SECONDS][,box=X0/Y0/Z0/X1/Y1/Z1][,width=MM][,aspect=H/W][,height=MM]\n"
    "   [,depth=MM][,mirror=1][,clock=arrival|recording]\n"
    "  Hand tracking over OSC (UDP), decoded with liblo; address spaces in docs/osc.md.\n"
    "  PORT     UDP port (default 9000; 0 picks a free one, logged at start)\n"
    "  format   auto (default): each message by its address, any of the three below\n"
    "           facepuppet: /facepuppet/hand/{left,right}/{joints,angles,wrist}, /facepuppet/button\n"
    "           leap: /hand<s> i i f f f (palm), /finger<s>-<n> i i f f f (tips; the other\n"
    "             joints are estimated on the straight line from palm to tip)\n"
    "           mediapipe: /lx/ /ly/ [/lz/] /rx/ /ry/ [/rz/], 21 normalised floats each\n"
    "           (vmc is not supported yet); a number may be sent as f, d, i or h, an\n"
    "           integer as i or h\n"
    "  bind     address to listen on (default 127.0.0.1, with [::1] too; localhost the same;\n"
    "           an IPv4 or IPv6 address, 0.0.0.0 or :: for both IPv4 and IPv6; beyond\n"
    "           loopback it is logged as a warning)\n"
    "  hand     which hands to take (default both; for leap, left/right takes slot 0 as that hand)\n"
    "  timeout  seconds of silence before the sender is reported disconnected, and of a\n"
    "           hand's absence (the sender going on without it) before that hand is\n"
    "           reported gone (default 1)\n"
    "  box      the volume the hands move in, mm, device frame: fitted to the face by the host\n"
    "           (default: the host's desktop-tracker box)\n"
    "  mediapipe: width = mm across the image (default 400), aspect = image height / width\n"
    "    (default 0.75), height = device y of the image centre (default 200 mm), depth = device\n"
    "    z of the landmarks' z = 0 (default 0), mirror=1 flips x.\n"
    "  clock    how bundles' timetags become event times: arrival (default): the sender's\n"
    "           clock, offset fixed by the first timed bundle; recording: the time on the\n"
    "           sender's recording clock (its /facepuppet/origin, sent by another session's\n"
    "           forward=), from this input's start: `run` then steps on it as on a recording\n"
    "           (each frame waits for the sender's events up to its time; the sender's\n"
    "           /facepuppet/end, or silence for `timeout`, ends it), so a forwarded\n"
    "           recording deforms the face as it would in one process (docs/osc.md, Forward)\n";

static int parse_number(const char *key, const char *v, double lo, double hi, double *out,
                        char *err, size_t errlen)
{
    locale_t c = newlocale(LC_ALL_MASK, "C", (locale_t)0);
    char *end = NULL;
    double x = c != (locale_t)0 ? strtod_l(v, &end, c) : NAN;
    if (c != (locale_t)0) freelocale(c);
    const size_t n = fp_decimal_span(v); /* a decimal: no hex, inf or nan */
    if (!n || !end || end != v + n || *end || !isfinite(x) || x < lo || x > hi) {
        snprintf(err, errlen, "osc: %s=%s: expected a number in [%g, %g]", key, v, lo, hi);
        return -EINVAL;
    }
    *out = x;
    return 0;
}


/* aspect=H/W (the image's height over its width, docs/osc.md: `480/640`) or the ratio as one
 * number (0.75): 0.01..100. Returns 0 or -EINVAL with a message. */
static int parse_aspect(const char *v, double *out, char *err, size_t errlen)
{
    const char *slash = strchr(v, '/');
    if (!slash) return parse_number("aspect", v, 0.01, 100, out, err, errlen);
    char h[64], msg[8];
    double hv, wv;
    const size_t n = (size_t)(slash - v);
    if (n >= sizeof h || parse_number("aspect", slash + 1, 1e-9, 1e9, &wv, msg, sizeof msg) != 0)
        goto bad;
    memcpy(h, v, n);
    h[n] = '\0';
    if (parse_number("aspect", h, 1e-9, 1e9, &hv, msg, sizeof msg) != 0 || !(hv / wv >= 0.01) ||
        !(hv / wv <= 100))
        goto bad;
    *out = hv / wv;
    return 0;
bad:
    snprintf(err, errlen, "osc: aspect=%s: expected H/W, the image's height over its width "
             "(480/640), or their ratio (0.75), within [0.01, 100]", v);
    return -EINVAL;
}

/* format=V into *format (FMT_*). Returns 0, -ENOTSUP (vmc) or -EINVAL, with a message. */
static int parse_format(const char *v, int *format, char *err, size_t errlen)
{
    *format = -1;
    for (int f = 0; f <= FMT_AUTO; f++)
        if (strcmp(v, fp__osc_format_names[f]) == 0) *format = f;
    if (*format == FMT_VMC) {
        snprintf(err, errlen, "osc: format=vmc: the VMC protocol is not supported yet "
                 "(see docs/osc.md); use auto, facepuppet, leap or mediapipe");
        return -ENOTSUP;
    }
    if (*format < 0) {
        snprintf(err, errlen, "osc: format=%s: expected auto, facepuppet, leap or mediapipe", v);
        return -EINVAL;
    }
    return 0;
}

/* hand=V into *hands (HANDS_*). Returns 0 or -EINVAL with a message. */
static int parse_hand(const char *v, int *hands, char *err, size_t errlen)
{
    if (strcmp(v, "left") == 0)
        *hands = HANDS_LEFT;
    else if (strcmp(v, "right") == 0)
        *hands = HANDS_RIGHT;
    else if (strcmp(v, "both") == 0)
        *hands = HANDS_BOTH;
    else {
        snprintf(err, errlen, "osc: hand=%s: expected left, right or both", v);
        return -EINVAL;
    }
    return 0;
}

/* box=x0/y0/z0/x1/y1/z1 in mm: the volume the hands move in (workspace extension). Returns 0
 * or -EINVAL with a message. */
static int parse_box(const char *v, float box[6], char *err, size_t errlen)
{
    locale_t c = newlocale(LC_ALL_MASK, "C", (locale_t)0);
    const char *p = v;
    int got = 0;
    for (; got < 6 && c != (locale_t)0; got++) {
        char *end = NULL;
        double x = strtod_l(p, &end, c);
        if (end == p || end != p + fp_decimal_span(p) || !isfinite(x) || fabs(x) > HUGE_MM) break;
        box[got] = (float)x;
        p = end;
        if (got < 5 && *p++ != '/') {
            got++;
            break;
        }
    }
    if (c != (locale_t)0) freelocale(c);
    if (got != 6 || *p || !(box[0] < box[3] && box[1] < box[4] && box[2] < box[5])) {
        snprintf(err, errlen, "osc: box=%s: expected x0/y0/z0/x1/y1/z1 in mm with x0 < x1, "
                 "y0 < y1, z0 < z1", v);
        return -EINVAL;
    }
    return 0;
}

/* One key of the SPEC into *o. Returns 0 or a negative code with a message. */
static int parse_key(const char *k, const char *v, osc_settings *o, char *err, size_t errlen)
{
    if (strcmp(k, "format") == 0) return parse_format(v, &o->format, err, errlen);
    if (strcmp(k, "bind") == 0) {
        o->bind_addr = v;
        return 0;
    }
    if (strcmp(k, "hand") == 0) return parse_hand(v, &o->hands, err, errlen);
    if (strcmp(k, "clock") == 0) {
        if (strcmp(v, "arrival") && strcmp(v, "recording")) {
            snprintf(err, errlen, "osc: clock=%s: expected arrival or recording", v);
            return -EINVAL;
        }
        o->clock = v[0] == 'r' ? CLOCK_RECORDING : CLOCK_ARRIVAL;
        return 0;
    }
    if (strcmp(k, "timeout") == 0) return parse_number(k, v, 0.01, 3600, &o->timeout, err, errlen);
    if (strcmp(k, "width") == 0) return parse_number(k, v, 1, 10000, &o->width, err, errlen);
    if (strcmp(k, "aspect") == 0) return parse_aspect(v, &o->aspect, err, errlen);
    if (strcmp(k, "height") == 0) return parse_number(k, v, -10000, 10000, &o->height, err, errlen);
    if (strcmp(k, "depth") == 0) return parse_number(k, v, -10000, 10000, &o->depth, err, errlen);
    if (strcmp(k, "box") == 0) {
        int rc = parse_box(v, o->box, err, errlen);
        o->have_box = rc == 0;
        return rc;
    }
    if (strcmp(k, "mirror") == 0) {
        if (strcmp(v, "1") && strcmp(v, "0")) {
            snprintf(err, errlen, "osc: mirror=%s: expected 0 or 1", v);
            return -EINVAL;
        }
        o->mirror = v[0] == '1';
        return 0;
    }
    snprintf(err, errlen, "osc: unknown key \"%s\" (known: format, bind, hand, timeout, "
             "width, aspect, height, depth, mirror, box, clock)", k);
    return -EINVAL;
}

/* The SPEC: [:PORT] and its keys, into *o (defaults first). Returns 0 or a negative code
 * with a message naming the key. */
int fp__osc_parse_spec(const char *arg, const fp_param *params, size_t nparams, osc_settings *o,
                      char *err, size_t errlen)
{
    *o = (osc_settings){.port = DEFAULT_PORT, .format = FMT_AUTO, .hands = HANDS_BOTH,
                        .timeout = 1.0, .width = 400, .aspect = 0.75, .height = 200, .depth = 0,
                        .bind_addr = "127.0.0.1"};
    if (arg && *arg) {
        unsigned long long p; /* digits, as every integer option (fp_parse_whole: no blank) */
        if (!fp_parse_whole(arg, 65535, &p)) {
            snprintf(err, errlen, "osc:%s: PORT must be a number in 0..65535", arg);
            return -EINVAL;
        }
        o->port = (long)p;
    }
    for (size_t i = 0; i < nparams; i++) {
        const char *k = params[i].key ? params[i].key : "", *v = params[i].value ? params[i].value : "";
        int rc = parse_key(k, v, o, err, errlen);
        if (rc) return rc;
    }
    return 0;
}

/* The keys, typed (ABI 1.1), for `facepuppet plugins` and `plugins check`; osc_create parses
 * them itself (the same ranges). A default of "": none (box: the host's desktop-tracker box). */
const fp_param_info fp__osc_keys[] = {
    {.name = "format", .type = FP_PARAM_ENUM, .default_value = "auto",
     .choices = "auto|facepuppet|leap|mediapipe",
     .description = "address space: auto takes each message by its address"},
    {.name = "bind", .type = FP_PARAM_STRING, .default_value = "127.0.0.1",
     .description = "IPv4 address to listen on (beyond loopback: a warning)"},
    {.name = "hand", .type = FP_PARAM_ENUM, .default_value = "both", .choices = "left|right|both",
     .description = "which hands to take (leap: left/right takes slot 0 as that hand)"},
    {.name = "clock", .type = FP_PARAM_ENUM, .default_value = "arrival", .choices = "arrival|recording",
     .description = "recording: step on the sender's recording clock (another session's forward=)"},
    {.name = "timeout", .type = FP_PARAM_FLOAT, .min = 0.01, .max = 3600, .default_value = "1",
     .unit = "s", .description = "silence before the sender is reported disconnected, or a hand gone"},
    {.name = "box", .type = FP_PARAM_STRING, .default_value = "", .unit = "mm",
     .description = "X0/Y0/Z0/X1/Y1/Z1: the volume the hands move in, device frame"},
    {.name = "width", .type = FP_PARAM_FLOAT, .min = 1, .max = 10000, .default_value = "400",
     .unit = "mm", .description = "mediapipe: the width the image spans at the hand"},
    {.name = "aspect", .type = FP_PARAM_FLOAT, .min = 0.01, .max = 100, .default_value = "0.75",
     .description = "mediapipe: image height / width"},
    {.name = "height", .type = FP_PARAM_FLOAT, .min = -10000, .max = 10000, .default_value = "200",
     .unit = "mm", .description = "mediapipe: device y of the image centre"},
    {.name = "depth", .type = FP_PARAM_FLOAT, .min = -10000, .max = 10000, .default_value = "0",
     .unit = "mm", .description = "mediapipe: device z of the landmarks' z = 0"},
    {.name = "mirror", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "0",
     .description = "mediapipe: flip x (a selfie camera)"},
    {.name = NULL},
};

