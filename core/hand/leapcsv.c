/*
 * leapcsv.c: the reader of the Leap Motion recording CSVs (see leapcsv.h).
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "leapcsv.h"

#include "fp_error.h"
#include "fp_file.h"
#include "fp_text.h"

#include <facepuppet/decimal.h> /* fp_decimal_span: the one syntax of a number */

#include <errno.h>
#include <float.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char *const lead_names[FP_LEAPCSV_LEAD] = {"frame", "timestamp_us", "hand_id",
                                                        "hand_type"};
static const char *const palm_names[9] = {"palm_x",  "palm_y", "palm_z", "palm_nx", "palm_ny",
                                          "palm_nz", "dir_x",  "dir_y",  "dir_z"};
static const char *const finger_names[FP_FINGERS] = {"thumb", "index", "middle", "ring", "pinky"};
static const char *const segment_names[4] = {"mcp", "pip", "dip", "tip"};
static const char *const angle_names[FP_GLOVE_SENSORS] = {
    "thumb_rotation", "thumb_mcp", "thumb_ip", "thumb_abduction", "index_mcp", "index_pip",
    "index_dip", "middle_mcp", "middle_pip", "middle_dip", "middle_index_abduction", "ring_mcp",
    "ring_pip", "ring_dip", "ring_middle_abduction", "pinky_mcp", "pinky_pip", "pinky_dip",
    "pinky_ring_abduction", "palm_arch", "wrist_pitch", "wrist_yaw"};

/* "thumb_mcp_x" .. "pinky_tip_z": built once per call into a caller's buffer. */
static const char *joint_name(int k, char *buf, size_t len)
{
    snprintf(buf, len, "%s_%s_%c", finger_names[k / 12], segment_names[(k / 3) % 4], "xyz"[k % 3]);
    return buf;
}

const char *fp_leapcsv_column_name(fp_leapcsv_format format, int i)
{
    static _Thread_local char buf[32];
    if (i < 0) return "?";
    if (i < FP_LEAPCSV_LEAD) return lead_names[i];
    i -= FP_LEAPCSV_LEAD;
    if (format == FP_LEAPCSV_ANGLES) return i < FP_GLOVE_SENSORS ? angle_names[i] : "?";
    if (format != FP_LEAPCSV_JOINTS || i >= FP_LEAPCSV_JOINT_VALUES) return "?";
    if (i < 9) return palm_names[i];
    return joint_name(i - 9, buf, sizeof buf);
}

static int columns_of(fp_leapcsv_format format)
{
    return FP_LEAPCSV_LEAD + (format == FP_LEAPCSV_JOINTS ? FP_LEAPCSV_JOINT_VALUES : FP_GLOVE_SENSORS);
}

typedef struct reader {
    const char *path;
    locale_t c_locale;
    char *err;
    size_t errlen;
} reader;

/* "PATH:LINE:COL: reason", or "PATH: reason" when line is 0 (fp_error_at). Returns code. */
#define fail(r, code, line, col, ...) fp_error_at((r)->err, (r)->errlen, code, (r)->path, line, col, __VA_ARGS__)

/* Fields of one line, split at commas in place (no quoting in these files). One more than
 * the widest format is stored, so that the first extra field of a too-long line has a column. */
enum { MAX_STORED = FP_LEAPCSV_MAX_COLUMNS + 1 };
typedef struct fields {
    char *s[MAX_STORED];
    long col[MAX_STORED];
    int n; /* fields in the line, which may exceed MAX_STORED */
} fields;

static void split(char *line, fields *f)
{
    char *p = line;
    f->n = 0;
    for (;;) {
        if (f->n < MAX_STORED) {
            f->s[f->n] = p;
            f->col[f->n] = (long)(p - line) + 1;
        }
        f->n++;
        char *comma = strchr(p, ',');
        if (!comma) break;
        *comma = '\0';
        p = comma + 1;
    }
}

/* The column to blame for a wrong field count: the end of a short line, or the first extra
 * field of a long one (always stored: want < MAX_STORED). */
static long count_col(const fields *f, int want, long line_len)
{
    return f->n < want ? line_len + 1 : f->col[want];
}

static int check_header(reader *r, fp_leapcsv_format want, fp_leapcsv_format *format, char *text)
{
    long len = (long)strlen(text);
    fields f;
    split(text, &f);
    fp_leapcsv_format fmt = want;
    if (fmt == FP_LEAPCSV_ANY) /* by the first value column's name, else by the count */
        fmt = f.n > FP_LEAPCSV_LEAD && strcmp(f.s[FP_LEAPCSV_LEAD], "palm_x") == 0 ? FP_LEAPCSV_JOINTS
              : f.n > FP_LEAPCSV_LEAD && strcmp(f.s[FP_LEAPCSV_LEAD], fp_leapcsv_column_name(FP_LEAPCSV_ANGLES, FP_LEAPCSV_LEAD)) == 0
                  ? FP_LEAPCSV_ANGLES
              : f.n == columns_of(FP_LEAPCSV_JOINTS) ? FP_LEAPCSV_JOINTS
                                                     : FP_LEAPCSV_ANGLES;
    int ncol = columns_of(fmt);
    if (f.n != ncol)
        return fail(r, -EBADMSG, 1, count_col(&f, ncol, len), "header has %d columns, expected %d",
                    f.n, ncol);
    for (int i = 0; i < ncol; i++) {
        const char *name = fp_leapcsv_column_name(fmt, i);
        if (strcmp(f.s[i], name) != 0)
            return fail(r, -EBADMSG, 1, f.col[i], "header column %d is \"%s\", expected \"%s\"",
                        i + 1, f.s[i], name);
    }
    *format = fmt;
    return 0;
}

static int parse_int64(const char *s, long long *out)
{
    char *end;
    errno = 0;
    long long v = strtoll(s, &end, 10);
    if (end == s || *end || errno) return -1;
    *out = v;
    return 0;
}

/* One data row: checks it and fills *row (lead columns, values, columns). */
static int parse_row(reader *r, fp_leapcsv_format fmt, long line, char *text, fp_leapcsv_row *row,
                     int have_ts)
{
    int want = columns_of(fmt);
    long len = (long)strlen(text);
    fields f;
    split(text, &f);
    if (f.n < want)
        return fail(r, -EBADMSG, line, count_col(&f, want, len),
                    "expected %d fields, found %d (row too short)", want, f.n);
    if (f.n > want)
        return fail(r, -EBADMSG, line, count_col(&f, want, len),
                    "expected %d fields, found %d (row too long)", want, f.n);
    long long frame, ts, id;
    if (parse_int64(f.s[0], &frame) || (long long)(long)frame != frame)
        return fail(r, -EBADMSG, line, f.col[0], "bad frame number \"%s\"", f.s[0]);
    if (parse_int64(f.s[1], &ts))
        return fail(r, -EBADMSG, line, f.col[1], "bad timestamp_us \"%s\"", f.s[1]);
    if (ts > FP_LEAPCSV_TIME_MAX_US || ts < -FP_LEAPCSV_TIME_MAX_US)
        return fail(r, -EBADMSG, line, f.col[1],
                    "timestamp_us %lld out of range (at most %lld either side of 0)", ts,
                    (long long)FP_LEAPCSV_TIME_MAX_US);
    if (parse_int64(f.s[2], &id) || (long long)(long)id != id)
        return fail(r, -EBADMSG, line, f.col[2], "bad hand_id \"%s\"", f.s[2]);
    fp_hand_side side;
    /* any case: Leap's JavaScript gives "left", other writers "Left" or "LEFT" */
    if (strcasecmp(f.s[3], "left") == 0)
        side = FP_HAND_LEFT;
    else if (strcasecmp(f.s[3], "right") == 0)
        side = FP_HAND_RIGHT;
    else
        return fail(r, -EBADMSG, line, f.col[3], "unknown hand_type \"%s\" (left or right)", f.s[3]);
    if (have_ts && ts < row->timestamp_us)
        return fail(r, -EBADMSG, line, f.col[1],
                    "timestamp_us %lld goes backwards (the row before has %lld)", ts,
                    (long long)row->timestamp_us);
    row->format = fmt;
    row->line = line;
    row->frame = (long)frame;
    row->timestamp_us = ts;
    row->hand_id = (long)id;
    row->side = side;
    row->nvalues = want - FP_LEAPCSV_LEAD;
    row->valid = fmt == FP_LEAPCSV_JOINTS ? (1u << FP_GLOVE_SENSORS) - 1u : 0;
    for (int i = 0; i < want; i++) row->col[i] = f.col[i];
    for (int i = FP_LEAPCSV_LEAD; i < want; i++) {
        int k = i - FP_LEAPCSV_LEAD;
        const char *s = f.s[i];
        row->value[k] = 0;
        row->valuef[k] = 0;
        if (!*s) {
            if (fmt == FP_LEAPCSV_ANGLES) continue;
            return fail(r, -EBADMSG, line, f.col[i], "empty field in column %s",
                        fp_leapcsv_column_name(fmt, i));
        }
        char *end;
        double v = strtod_l(s, &end, r->c_locale);
        if (end == s || *end)
            return fail(r, -EBADMSG, line, f.col[i], "bad number \"%s\" in column %s", s,
                        fp_leapcsv_column_name(fmt, i));
        if (!isfinite(v) || fabs(v) > FLT_MAX)
            return fail(r, -EBADMSG, line, f.col[i], "\"%s\" in column %s is not a finite number",
                        s, fp_leapcsv_column_name(fmt, i));
        if (fp_decimal_span(s) != (size_t)(end - s)) /* hexadecimal ("0x1p3"): decimals only */
            return fail(r, -EBADMSG, line, f.col[i], "bad number \"%s\" in column %s", s,
                        fp_leapcsv_column_name(fmt, i));
        if (fmt == FP_LEAPCSV_JOINTS && fabs(v) > FP_EVENT_MAX_MM)
            return fail(r, -EBADMSG, line, f.col[i], "%s in column %s is beyond 10 m of the tracker "
                        "(FP_EVENT_MAX_MM, in mm): not a hand", s, fp_leapcsv_column_name(fmt, i));
        row->value[k] = v;
        row->valuef[k] = strtof_l(s, NULL, r->c_locale);
        if (!isfinite(row->valuef[k])) /* a value just above FLT_MAX that rounds up */
            return fail(r, -EBADMSG, line, f.col[i], "\"%s\" in column %s is not a finite number",
                        s, fp_leapcsv_column_name(fmt, i));
        if (fmt == FP_LEAPCSV_ANGLES) row->valid |= 1u << k;
    }
    return 0;
}

/* Digits after the decimal point in a line's last field (0 without a point). */
static int last_decimals(const char *text)
{
    const char *f = strrchr(text, ',');
    const char *dot = strchr(f ? f + 1 : text, '.');
    return dot ? (int)strspn(dot + 1, "0123456789") : 0;
}

/* The last line, without its newline: a row whole (a writer that ends the file without one),
 * or a recording cut off inside it. Whole when it parses as a row and its last field has as
 * many decimals as the row before's (d against prev; prev -1: no row before): a cut inside the
 * last number ("-42.37" of "-42.3741") parses, but with fewer decimals. 1: whole, *row filled;
 * 0: cut off (dropped: the caller reports the line, never its parse error). */
static int unterminated_row(reader *r, fp_leapcsv_format fmt, long line, char *text,
                            fp_leapcsv_row *row, int have_ts, int d, int prev)
{
    char *quiet = r->err; /* a cut row's parse error is not the read's */
    r->err = NULL;
    int rc = parse_row(r, fmt, line, text, row, have_ts);
    r->err = quiet;
    return !rc && d >= prev;
}

/* The file whole (fp_file_read_all: a regular file, FP_LEAPCSV_MAX_BYTES at most, refused by
 * its size before reading when larger). */
static int read_whole(reader *r, char **data, size_t *len)
{
    int rc = fp_file_read_all(r->path, FP_LEAPCSV_MAX_BYTES, data, len);
    if (rc == -EFBIG) return fail(r, -EBADMSG, 0, 0, "larger than 1 GiB (FP_LEAPCSV_MAX_BYTES)");
    if (rc == -ENOMEM) return fail(r, -ENOMEM, 0, 0, "out of memory");
    if (rc) return fail(r, rc, 0, 0, "cannot open: %s", fp_file_error_text(rc));
    return 0;
}

int fp_leapcsv_read(const char *path, fp_leapcsv_format want, fp_leapcsv_format *format,
                    fp_leapcsv_row_fn fn, void *user, long *truncated_line, char *err,
                    size_t errlen)
{
    reader r = {path ? path : "(null)", (locale_t)0, err, errlen};
    if (truncated_line) *truncated_line = 0;
    if (!path || !fn) return fail(&r, -EINVAL, 0, 0, "fp_leapcsv_read: NULL argument");
    fp_leapcsv_row *row = calloc(1, sizeof *row);
    r.c_locale = newlocale(LC_ALL_MASK, "C", (locale_t)0);
    char *data = NULL;
    size_t len = 0;
    int rc = !row || r.c_locale == (locale_t)0 ? fail(&r, -ENOMEM, 0, 0, "out of memory")
                                               : read_whole(&r, &data, &len);
    fp_leapcsv_format fmt = FP_LEAPCSV_ANY;
    long line = 0;
    int have_ts = 0, decimals = -1; /* decimals: the last field's in the row before (-1: none) */
    char *p = data ? data + fp_text_bom(data, len) : data, *end = data + len;
    while (!rc && p < end) {
        char *nl = memchr(p, '\n', (size_t)(end - p));
        line++;
        if (!nl && line == 1) {
            rc = fail(&r, -EBADMSG, 1, 1, "header line not terminated");
            break;
        }
        char *eol = nl ? nl : end; /* (data is NUL-ended: *end is '\0') */
        *eol = '\0';
        size_t n = (size_t)(eol - p);
        if (n > 0 && p[n - 1] == '\r') p[--n] = '\0';
        if (strlen(p) != n) {
            rc = fail(&r, -EBADMSG, line, (long)strlen(p) + 1, "NUL byte in line");
            break;
        }
        if (line == 1) {
            rc = check_header(&r, want, &fmt, p);
        } else if (*p) { /* blank lines are skipped */
            int d = last_decimals(p);
            row->path = path;
            if (!nl) { /* no newline: a whole row, or a recording cut off (unterminated_row) */
                if (!unterminated_row(&r, fmt, line, p, row, have_ts, d, decimals)) {
                    if (truncated_line) *truncated_line = line;
                    break;
                }
            } else {
                rc = parse_row(&r, fmt, line, p, row, have_ts);
            }
            if (!rc) rc = fn(user, row, err, errlen);
            have_ts = 1;
            decimals = d;
        }
        if (!nl) break;
        p = nl + 1;
    }
    if (!rc && line == 0) rc = fail(&r, -EBADMSG, 1, 1, "empty file, expected a header line");
    if (!rc && format) *format = fmt;
    free(data);
    free(row);
    if (r.c_locale != (locale_t)0) freelocale(r.c_locale);
    return rc;
}

/* ------------------------------------------------------------------------------------- */
/* Whole-file readers into row arrays                                                     */

typedef struct collect {
    void *rows;
    size_t n, cap, elem;
} collect;

static void *collect_next(collect *c)
{
    if (c->n == c->cap) {
        size_t nc = c->cap ? c->cap * 2 : 256;
        void *p = realloc(c->rows, nc * c->elem);
        if (!p) return NULL;
        c->rows = p;
        c->cap = nc;
    }
    void *slot = (char *)c->rows + c->n++ * c->elem;
    memset(slot, 0, c->elem);
    return slot;
}

/* The four lead columns, which both row types start with. */
#define COPY_LEAD(row, in) \
    ((row)->frame = (in)->frame, (row)->timestamp_us = (in)->timestamp_us, \
     (row)->hand_id = (in)->hand_id, (row)->side = (in)->side)

void fp_leap_joints_from_row(const fp_leapcsv_row *in, fp_leap_joints_row *row)
{
    COPY_LEAD(row, in);
    for (int k = 0; k < 3; k++) {
        row->palm_mm[k] = in->valuef[k];
        row->normal[k] = in->valuef[3 + k];
        row->direction[k] = in->valuef[6 + k];
        row->joints_mm[FP_JOINT_PALM][k] = in->valuef[k];
    }
    for (int f = 0; f < FP_FINGERS; f++)
        for (int j = 0; j < 4; j++)
            for (int k = 0; k < 3; k++)
                row->joints_mm[FP_JOINT(f, j)][k] = in->valuef[9 + (f * 4 + j) * 3 + k];
}

static int on_joints(void *user, const fp_leapcsv_row *in, char *err, size_t errlen)
{
    fp_leap_joints_row *row = collect_next(user);
    if (!row) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", in->path);
    fp_leap_joints_from_row(in, row);
    return 0;
}

static int on_angles(void *user, const fp_leapcsv_row *in, char *err, size_t errlen)
{
    fp_leap_angles_row *row = collect_next(user);
    if (!row) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", in->path);
    COPY_LEAD(row, in);
    row->valid = in->valid;
    for (int i = 0; i < FP_GLOVE_SENSORS; i++) row->degrees[i] = in->valuef[i];
    return 0;
}

static int read_rows(const char *path, fp_leapcsv_format fmt, fp_leapcsv_row_fn fn, size_t elem,
                     void **rows, size_t *n, char *err, size_t errlen)
{
    if (!rows || !n) return fp_errorf(err, errlen, -EINVAL, "fp_leapcsv_read: NULL argument");
    collect c = {NULL, 0, 0, elem};
    int rc = fp_leapcsv_read(path, fmt, NULL, fn, &c, NULL, err, errlen);
    if (!rc && c.n == 0) rc = fp_errorf(err, errlen, -EBADMSG, "%s: no data rows", path);
    if (rc) {
        free(c.rows);
        return rc;
    }
    *rows = c.rows;
    *n = c.n;
    return 0;
}

int fp_leapcsv_read_joints(const char *path, fp_leap_joints_row **rows, size_t *n, char *err,
                           size_t errlen)
{
    return read_rows(path, FP_LEAPCSV_JOINTS, on_joints, sizeof **rows, (void **)rows, n, err,
                     errlen);
}

int fp_leapcsv_read_angles(const char *path, fp_leap_angles_row **rows, size_t *n, char *err,
                           size_t errlen)
{
    return read_rows(path, FP_LEAPCSV_ANGLES, on_angles, sizeof **rows, (void **)rows, n, err,
                     errlen);
}
