/*
 * leapcsv.c: reader of the Leap Motion recording CSVs (see leapcsv.h).
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "leapcsv.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_FIELDS 80

static const char *const joints_header[] = {
    "frame", "timestamp_us", "hand_id", "hand_type", "palm_x", "palm_y", "palm_z", "palm_nx",
    "palm_ny", "palm_nz", "dir_x", "dir_y", "dir_z"};
static const char *const finger_names[FP_FINGERS] = {"thumb", "index", "middle", "ring", "pinky"};
static const char *const joint_names[4] = {"mcp", "pip", "dip", "tip"};
static const char *const angles_header[4 + FP_GLOVE_SENSORS] = {
    "frame", "timestamp_us", "hand_id", "hand_type", "thumb_rotation", "thumb_mcp", "thumb_ip",
    "thumb_abduction", "index_mcp", "index_pip", "index_dip", "middle_mcp", "middle_pip",
    "middle_dip", "middle_index_abduction", "ring_mcp", "ring_pip", "ring_dip",
    "ring_middle_abduction", "pinky_mcp", "pinky_pip", "pinky_dip", "pinky_ring_abduction",
    "palm_arch", "wrist_pitch", "wrist_yaw"};

typedef struct reader {
    const char *path;
    FILE *f;
    char *line;
    size_t cap;
    long lineno;
    char *field[MAX_FIELDS];
    int nfield;
    char *err;
    size_t errlen;
} reader;

static int fail(reader *r, int code, int column, const char *name, const char *fmt, ...)
{
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (r->err && r->errlen) {
        if (column > 0)
            snprintf(r->err, r->errlen, "%s:%ld: column %d (%s): %s", r->path, r->lineno, column,
                     name ? name : "?", msg);
        else if (r->lineno > 0)
            snprintf(r->err, r->errlen, "%s:%ld: %s", r->path, r->lineno, msg);
        else
            snprintf(r->err, r->errlen, "%s: %s", r->path, msg);
    }
    return code;
}

/* Next line split at commas (no quoting in these files). 1: a line, 0: end of file. */
static int next_line(reader *r)
{
    ssize_t len;
    for (;;) {
        errno = 0;
        len = getline(&r->line, &r->cap, r->f);
        if (len < 0)
            return ferror(r->f) ? fail(r, -EIO, 0, NULL, "read error: %s", strerror(errno)) : 0;
        r->lineno++;
        while (len > 0 && (r->line[len - 1] == '\n' || r->line[len - 1] == '\r'))
            r->line[--len] = '\0';
        if (len > 0)
            break; /* skip blank lines (a trailing newline at the end) */
    }
    r->nfield = 0;
    char *p = r->line;
    for (;;) {
        if (r->nfield == MAX_FIELDS)
            return fail(r, -EBADMSG, 0, NULL, "more than %d fields", MAX_FIELDS);
        r->field[r->nfield++] = p;
        char *c = strchr(p, ',');
        if (!c)
            break;
        *c = '\0';
        p = c + 1;
    }
    return 1;
}

static int open_reader(reader *r, const char *path, char *err, size_t errlen)
{
    memset(r, 0, sizeof *r);
    r->path = path;
    r->err = err;
    r->errlen = errlen;
    r->f = fopen(path, "r");
    if (!r->f)
        return fail(r, errno ? -errno : -EIO, 0, NULL, "cannot open: %s", strerror(errno));
    return 0;
}

static void close_reader(reader *r)
{
    if (r->f)
        fclose(r->f);
    free(r->line);
}

static int check_header(reader *r, const char *const *names, int count)
{
    int rc = next_line(r);
    if (rc < 0)
        return rc;
    if (rc == 0)
        return fail(r, -EBADMSG, 0, NULL, "empty file, expected a header line");
    if (r->nfield != count)
        return fail(r, -EBADMSG, 0, NULL, "header has %d columns, expected %d", r->nfield, count);
    for (int i = 0; i < count; i++)
        if (strcmp(r->field[i], names[i]) != 0)
            return fail(r, -EBADMSG, i + 1, names[i], "header reads '%s'", r->field[i]);
    return 0;
}

static int parse_long(reader *r, int i, const char *name, long *out)
{
    char *end;
    errno = 0;
    long v = strtol(r->field[i], &end, 10);
    if (end == r->field[i] || *end || errno)
        return fail(r, -EBADMSG, i + 1, name, "not an integer: '%s'", r->field[i]);
    *out = v;
    return 0;
}

static int parse_i64(reader *r, int i, const char *name, int64_t *out)
{
    char *end;
    errno = 0;
    long long v = strtoll(r->field[i], &end, 10);
    if (end == r->field[i] || *end || errno)
        return fail(r, -EBADMSG, i + 1, name, "not an integer: '%s'", r->field[i]);
    *out = (int64_t)v;
    return 0;
}

/* 1: a number, 0: empty (allowed only if allow_empty), negative: error. */
static int parse_float(reader *r, int i, const char *name, bool allow_empty, float *out)
{
    const char *s = r->field[i];
    if (!*s) {
        if (allow_empty)
            return 0;
        return fail(r, -EBADMSG, i + 1, name, "empty field");
    }
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end || errno == ERANGE || !isfinite(v) || !isfinite((float)v))
        return fail(r, -EBADMSG, i + 1, name, "not a finite number: '%s'", s);
    *out = (float)v;
    return 1;
}

static int parse_side(reader *r, int i, fp_hand_side *side)
{
    if (strcmp(r->field[i], "left") == 0)
        *side = FP_HAND_LEFT;
    else if (strcmp(r->field[i], "right") == 0)
        *side = FP_HAND_RIGHT;
    else
        return fail(r, -EBADMSG, i + 1, "hand_type", "expected 'left' or 'right', got '%s'", r->field[i]);
    return 0;
}

static int grow(reader *r, void **rows, size_t *cap, size_t n, size_t elem)
{
    if (n < *cap)
        return 0;
    size_t nc = *cap ? *cap * 2 : 256;
    void *p = realloc(*rows, nc * elem);
    if (!p)
        return fail(r, -ENOMEM, 0, NULL, "out of memory");
    *rows = p;
    *cap = nc;
    return 0;
}

int fp_leapcsv_read_joints(const char *path, fp_leap_joints_row **rows, size_t *n, char *err,
                           size_t errlen)
{
    if (!path || !rows || !n) {
        if (err && errlen)
            snprintf(err, errlen, "fp_leapcsv_read_joints: NULL argument");
        return -EINVAL;
    }
    enum { NCOL = 13 + FP_FINGERS * 4 * 3 };
    char names[NCOL][24];
    const char *np[NCOL];
    for (int i = 0; i < 13; i++)
        snprintf(names[i], sizeof names[i], "%s", joints_header[i]);
    for (int f = 0, c = 13; f < FP_FINGERS; f++)
        for (int k = 0; k < 4; k++)
            for (int a = 0; a < 3; a++, c++)
                snprintf(names[c], sizeof names[c], "%s_%s_%c", finger_names[f], joint_names[k], "xyz"[a]);
    for (int i = 0; i < NCOL; i++)
        np[i] = names[i];

    reader r;
    fp_leap_joints_row *out = NULL;
    size_t count = 0, cap = 0;
    int rc = open_reader(&r, path, err, errlen);
    if (!rc)
        rc = check_header(&r, np, NCOL);
    while (!rc) {
        rc = next_line(&r);
        if (rc <= 0)
            break;
        rc = 0;
        if (r.nfield != NCOL) {
            rc = fail(&r, -EBADMSG, 0, NULL, "%d fields, expected %d", r.nfield, NCOL);
            break;
        }
        if ((rc = grow(&r, (void **)&out, &cap, count, sizeof *out)))
            break;
        fp_leap_joints_row *row = &out[count];
        memset(row, 0, sizeof *row);
        if ((rc = parse_long(&r, 0, np[0], &row->frame)) || (rc = parse_i64(&r, 1, np[1], &row->timestamp_us)) ||
            (rc = parse_long(&r, 2, np[2], &row->hand_id)) || (rc = parse_side(&r, 3, &row->side)))
            break;
        float v[NCOL];
        for (int i = 4; i < NCOL && rc >= 0; i++)
            rc = parse_float(&r, i, np[i], false, &v[i]);
        if (rc < 0)
            break;
        rc = 0;
        for (int k = 0; k < 3; k++) {
            row->palm_mm[k] = v[4 + k];
            row->normal[k] = v[7 + k];
            row->direction[k] = v[10 + k];
            row->joints_mm[FP_JOINT_PALM][k] = v[4 + k];
        }
        for (int f = 0; f < FP_FINGERS; f++)
            for (int j = 0; j < 4; j++)
                for (int k = 0; k < 3; k++)
                    row->joints_mm[FP_JOINT(f, j)][k] = v[13 + (f * 4 + j) * 3 + k];
        count++;
    }
    if (!rc && count == 0)
        rc = fail(&r, -EBADMSG, 0, NULL, "no data rows");
    close_reader(&r);
    if (rc) {
        free(out);
        return rc;
    }
    *rows = out;
    *n = count;
    return 0;
}

int fp_leapcsv_read_angles(const char *path, fp_leap_angles_row **rows, size_t *n, char *err,
                           size_t errlen)
{
    if (!path || !rows || !n) {
        if (err && errlen)
            snprintf(err, errlen, "fp_leapcsv_read_angles: NULL argument");
        return -EINVAL;
    }
    enum { NCOL = 4 + FP_GLOVE_SENSORS };
    reader r;
    fp_leap_angles_row *out = NULL;
    size_t count = 0, cap = 0;
    int rc = open_reader(&r, path, err, errlen);
    if (!rc)
        rc = check_header(&r, angles_header, NCOL);
    while (!rc) {
        rc = next_line(&r);
        if (rc <= 0)
            break;
        rc = 0;
        if (r.nfield != NCOL) {
            rc = fail(&r, -EBADMSG, 0, NULL, "%d fields, expected %d", r.nfield, NCOL);
            break;
        }
        if ((rc = grow(&r, (void **)&out, &cap, count, sizeof *out)))
            break;
        fp_leap_angles_row *row = &out[count];
        memset(row, 0, sizeof *row);
        if ((rc = parse_long(&r, 0, angles_header[0], &row->frame)) ||
            (rc = parse_i64(&r, 1, angles_header[1], &row->timestamp_us)) ||
            (rc = parse_long(&r, 2, angles_header[2], &row->hand_id)) || (rc = parse_side(&r, 3, &row->side)))
            break;
        for (int i = 0; i < FP_GLOVE_SENSORS; i++) {
            rc = parse_float(&r, 4 + i, angles_header[4 + i], true, &row->degrees[i]);
            if (rc < 0)
                break;
            if (rc == 1)
                row->valid |= 1u << i;
            rc = 0;
        }
        if (rc)
            break;
        count++;
    }
    if (!rc && count == 0)
        rc = fail(&r, -EBADMSG, 0, NULL, "no data rows");
    close_reader(&r);
    if (rc) {
        free(out);
        return rc;
    }
    *rows = out;
    *n = count;
    return 0;
}
