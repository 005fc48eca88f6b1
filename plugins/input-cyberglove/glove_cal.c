/*
 * glove_cal.c: CyberGlove calibration files (see glove_cal.h).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "glove_cal.h"
#include "fp_error.h"
#include "fp_file.h"
#include "fp_text.h"

#include <facepuppet/decimal.h> /* fp_decimal_span: the one syntax of a number */

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const int FPG_ASR_LINE_SENSOR[FPG_SENSORS] = {
    21, 20, 3, 0, 1, 2, 4, 10, 5, 6, 7, 19, 8, 9, 11, 14, 12, 13, 15, 18, 16, 17
};

const char *fpg_sensor_name(int i)
{
    static const char *const names[FPG_SENSORS] = {
        "ThumbRotate", "ThumbMPJ", "ThumbIJ", "ThumbAb", "IndexMPJ", "IndexPIJ", "IndexDIJ",
        "MiddleMPJ", "MiddlePIJ", "MiddleDIJ", "MiddleIndexAb", "RingMPJ", "RingPIJ", "RingDIJ",
        "RingMiddleAb", "PinkieMPJ", "PinkiePIJ", "PinkieDIJ", "PinkieRingAb", "PalmArch",
        "WristPitch", "WristYaw"};
    return i >= 0 && i < FPG_SENSORS ? names[i] : "?";
}

const char *fpg_cal_format_name(fpg_cal_format f)
{
    return f == FPG_CAL_ASR ? "asr two-point" : f == FPG_CAL_GAIN_OFFSET ? "gain/offset" : "default map";
}

void fpg_cal_default(fpg_cal *cal)
{
    const double g = (3.14159265358979323846 / 2.0) / 253.0;
    memset(cal, 0, sizeof *cal);
    cal->format = FPG_CAL_DEFAULT;
    for (int i = 0; i < FPG_SENSORS; i++) {
        cal->gain[i] = (float)g;
        cal->offset[i] = (float)(-g);
    }
    cal->used = (1u << FPG_SENSORS) - 1u;
}

/* True when v is finite and stays finite as a float (what the calibration stores). */
static bool finite_float(double v)
{
    return isfinite(v) && isfinite((float)v);
}

/* Strip comments and whitespace; returns the first non-blank char or NULL when empty. */
static char *trim_line(char *s)
{
    char *hash = strchr(s, '#');
    if (hash)
        *hash = '\0';
    while (*s == ' ' || *s == '\t')
        s++;
    size_t n = strlen(s);
    while (n > 0 && (s[n - 1] == '\n' || s[n - 1] == '\r' || s[n - 1] == ' ' || s[n - 1] == '\t'))
        s[--n] = '\0';
    return *s ? s : NULL;
}

/* Parse one double from *p, skipping leading white space (as strtod did); accepts only a
 * finite decimal (fp_decimal_span: no hexadecimal, inf or nan). */
static int parse_num(char **p, double *out)
{
    char *s = *p, *end;
    while (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\v' || *s == '\f' || *s == '\r')
        s++;
    const size_t n = fp_decimal_span(s);
    errno = 0;
    double v = n ? strtod(s, &end) : 0;
    if (!n || end != s + n || errno == ERANGE || !isfinite(v)) /* ("0x10": strtod reads on) */
        return -1;
    *p = end;
    *out = v;
    return 0;
}

static int parse_asr_line(char *s, double v[4])
{
    char *p = s;
    for (int k = 0; k < 4; k++) {
        while (*p == ' ' || *p == '\t')
            p++;
        if (parse_num(&p, &v[k]) != 0)
            return -1;
        if (k == 0 || k == 2) {
            if (*p != ':')
                return -1;
            p++;
        } else if (k == 1) {
            if (*p != ' ' && *p != '\t')
                return -1;
        }
    }
    while (*p == ' ' || *p == '\t')
        p++;
    return *p ? -1 : 0;
}

int fpg_cal_load(const char *path, fpg_cal *cal, char *err, size_t errlen)
{
    int code;
    FILE *f = fp_file_fopen_regular(path, &code); /* (a folder or FIFO: refused, never read) */
    if (!f)
        return fp_errorf(err, errlen, code, "%s: cannot open calibration file: %s", path,
                         fp_file_error_text(code));
    fpg_cal_default(cal);
    char buf[512];
    int lineno = 0, rows = 0, rc = 0;
    fpg_cal_format fmt = FPG_CAL_DEFAULT;
    uint32_t seen = 0;
    while (fgets(buf, sizeof buf, f)) {
        lineno++;
        if (!strchr(buf, '\n') && !feof(f)) {
            rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: line too long", path, lineno);
            goto out;
        }
        char *s = trim_line(buf + (lineno == 1 ? fp_text_bom(buf, strlen(buf)) : 0));
        if (!s)
            continue;
        if (fmt == FPG_CAL_DEFAULT) {
            fmt = strchr(s, ':') ? FPG_CAL_ASR : FPG_CAL_GAIN_OFFSET;
            cal->format = fmt;
            if (fmt == FPG_CAL_ASR)
                cal->used = 0;
        }
        if (fmt == FPG_CAL_ASR) {
            double v[4];
            if (rows >= FPG_SENSORS) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: more than %d calibration lines (asr "
                          "format)", path, lineno, FPG_SENSORS);
                goto out;
            }
            if (parse_asr_line(s, v) != 0) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: expected `rad1:raw1 rad2:raw2` (asr "
                          "format), got \"%.60s\"", path, lineno, s); /* (shown safe: fp_error.h) */
                goto out;
            }
            if (v[1] < 0 || v[1] > 255 || v[3] < 0 || v[3] > 255) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: raw value outside 0..255", path, lineno);
                goto out;
            }
            if (v[1] == v[3]) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: raw1 equals raw2 (%g): no slope", path,
                          lineno, v[1]);
                goto out;
            }
            int s_idx = FPG_ASR_LINE_SENSOR[rows];
            double g = (v[2] - v[0]) / (v[3] - v[1]);
            if (!finite_float(g) || !finite_float(v[0] - g * v[1])) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: gain or offset beyond float range",
                               path, lineno);
                goto out;
            }
            cal->gain[s_idx] = (float)g;
            cal->offset[s_idx] = (float)(v[0] - g * v[1]);
            if (g != 0.0)
                cal->used |= 1u << s_idx;
            rows++;
        } else {
            char *p = s, *end;
            errno = 0;
            long idx = strtol(p, &end, 10);
            double g, o;
            if (end == p || errno || (*end != ' ' && *end != '\t')) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: expected `SENSOR GAIN OFFSET`, got "
                          "\"%.60s\"", path, lineno, s);
                goto out;
            }
            if (idx < 0 || idx >= FPG_SENSORS) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: sensor %ld outside 0..%d", path, lineno,
                          idx, FPG_SENSORS - 1);
                goto out;
            }
            p = end;
            if (parse_num(&p, &g) != 0 || parse_num(&p, &o) != 0) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: expected finite GAIN and OFFSET after "
                          "sensor %ld", path, lineno, idx);
                goto out;
            }
            while (*p == ' ' || *p == '\t')
                p++;
            if (*p) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: unexpected text \"%.30s\"", path, lineno,
                          p);
                goto out;
            }
            if (seen & (1u << idx)) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: sensor %ld given twice", path, lineno, idx);
                goto out;
            }
            if (!finite_float(g) || !finite_float(o)) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: GAIN or OFFSET beyond float range",
                               path, lineno);
                goto out;
            }
            seen |= 1u << idx;
            cal->gain[idx] = (float)g;
            cal->offset[idx] = (float)o;
            if (g == 0.0)
                cal->used &= ~(1u << idx);
            rows++;
        }
    }
    if (ferror(f)) {
        rc = fp_errorf(err, errlen, -EIO, "%s: read error", path);
        goto out;
    }
    if (rows == 0) {
        rc = fp_errorf(err, errlen, -EBADMSG, "%s: no calibration lines", path);
        goto out;
    }
    if (fmt == FPG_CAL_ASR && rows != FPG_SENSORS) {
        rc = fp_errorf(err, errlen, -EBADMSG, "%s:%d: only %d of %d calibration lines (asr format)",
                  path, lineno, rows, FPG_SENSORS);
        goto out;
    }
out:
    fclose(f);
    return rc;
}

int fpg_cal_inverse(const fpg_cal *cal, int i, double radians, double scale, int lo, int hi,
                    int *clamped)
{
    if (clamped)
        *clamped = 0;
    if (!(cal->used & (1u << i)) || cal->gain[i] == 0.0f)
        return (lo + hi) / 2;
    double raw = (radians - cal->offset[i]) / cal->gain[i] * scale;
    if (raw >= hi + 0.5) { /* before lround, which has no answer for |raw| beyond long */
        if (clamped)
            *clamped = 1;
        return hi;
    }
    long r = !(raw > lo - 0.5) ? lo - 1 : lround(raw);
    if (r < lo) {
        if (clamped)
            *clamped = 1;
        return lo;
    }
    if (r > hi) {
        if (clamped)
            *clamped = 1;
        return hi;
    }
    return (int)r;
}
