/*
 * replay_load.c: input-replay's loader (see replay_load.h). The CSV formats are described in
 * shared/data/README.md; the event log in docs/eventlog.md.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "replay_load.h"

#include "fp_eventlog.h"

#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_LOOP_GAP_NS 10000000 /* 10 ms: the loop gap of a one-moment recording */

static const char *const finger_names[FP_FINGERS] = {"thumb", "index", "middle", "ring", "pinky"};
static const char *const segment_names[4] = {"mcp", "pip", "dip", "tip"};
static const char *const angle_columns[FP_GLOVE_SENSORS] = {
    "thumb_rotation", "thumb_mcp", "thumb_ip", "thumb_abduction", "index_mcp", "index_pip",
    "index_dip", "middle_mcp", "middle_pip", "middle_dip", "middle_index_abduction", "ring_mcp",
    "ring_pip", "ring_dip", "ring_middle_abduction", "pinky_mcp", "pinky_pip", "pinky_dip",
    "pinky_ring_abduction", "palm_arch", "wrist_pitch", "wrist_yaw"};

#define LEAD_COLUMNS 4                                   /* frame, timestamp_us, id, type */
#define JOINT_COLUMNS (LEAD_COLUMNS + 9 + 4 * FP_FINGERS * 3) /* 73 */
#define ANGLE_COLUMNS (LEAD_COLUMNS + FP_GLOVE_SENSORS)      /* 26 */
#define MAX_COLUMNS JOINT_COLUMNS

static void put_msg(char *buf, size_t len, const char *fmt, ...)
{
    if (!buf || len == 0) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, len, fmt, ap);
    va_end(ap);
}

/* ------------------------------------------------------------------------------------- */
/* Geometry                                                                               */

static double norm3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

int replay_wrist_rotation(const double normal[3], const double direction[3], float q[4])
{
    double z[3], y[3], x[3];
    double ld = norm3(direction), ln = norm3(normal);
    if (!(ld > 1e-9) || !(ln > 1e-9)) return -1;
    for (int i = 0; i < 3; i++) z[i] = -direction[i] / ld;  /* -z toward the fingers */
    for (int i = 0; i < 3; i++) y[i] = -normal[i] / ln;     /* +y back of the hand */
    double d = y[0] * z[0] + y[1] * z[1] + y[2] * z[2];
    for (int i = 0; i < 3; i++) y[i] -= d * z[i];           /* Gram-Schmidt against z */
    double ly = norm3(y);
    if (!(ly > 1e-6)) return -1;
    for (int i = 0; i < 3; i++) y[i] /= ly;
    x[0] = y[1] * z[2] - y[2] * z[1];                       /* right-handed: x = y x z */
    x[1] = y[2] * z[0] - y[0] * z[2];
    x[2] = y[0] * z[1] - y[1] * z[0];
    /* R's columns are the hand axes in the device frame; quaternion by Shepperd's method. */
    double r[3][3];
    for (int i = 0; i < 3; i++) {
        r[i][0] = x[i];
        r[i][1] = y[i];
        r[i][2] = z[i];
    }
    double w, qx, qy, qz, tr = r[0][0] + r[1][1] + r[2][2];
    if (tr > 0) {
        double s = sqrt(tr + 1.0) * 2;
        w = s / 4, qx = (r[2][1] - r[1][2]) / s, qy = (r[0][2] - r[2][0]) / s,
        qz = (r[1][0] - r[0][1]) / s;
    } else if (r[0][0] > r[1][1] && r[0][0] > r[2][2]) {
        double s = sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]) * 2;
        w = (r[2][1] - r[1][2]) / s, qx = s / 4, qy = (r[0][1] + r[1][0]) / s,
        qz = (r[0][2] + r[2][0]) / s;
    } else if (r[1][1] > r[2][2]) {
        double s = sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]) * 2;
        w = (r[0][2] - r[2][0]) / s, qx = (r[0][1] + r[1][0]) / s, qy = s / 4,
        qz = (r[1][2] + r[2][1]) / s;
    } else {
        double s = sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]) * 2;
        w = (r[1][0] - r[0][1]) / s, qx = (r[0][2] + r[2][0]) / s, qy = (r[1][2] + r[2][1]) / s,
        qz = s / 4;
    }
    double l = sqrt(w * w + qx * qx + qy * qy + qz * qz);
    if (w < 0) l = -l;
    q[0] = (float)(w / l);
    q[1] = (float)(qx / l);
    q[2] = (float)(qy / l);
    q[3] = (float)(qz / l);
    return 0;
}

/* ------------------------------------------------------------------------------------- */
/* Growing item list                                                                      */

typedef struct loader {
    const char *path;
    int hands;
    locale_t c_locale;
    replay_recording *rec;
    size_t cap;
    char *err;
    size_t errlen;
} loader;

static replay_item *push_item(loader *L)
{
    replay_recording *rec = L->rec;
    if (rec->count == L->cap) {
        size_t cap = L->cap ? L->cap * 2 : 1024;
        replay_item *items = realloc(rec->items, cap * sizeof *items);
        if (!items) return NULL;
        rec->items = items;
        L->cap = cap;
    }
    replay_item *it = &rec->items[rec->count++];
    memset(it, 0, sizeof *it);
    return it;
}

static int fail(loader *L, int code, long line, long col, const char *fmt, ...)
{
    int n;
    if (line > 0)
        n = snprintf(L->err, L->errlen, "%s:%ld:%ld: ", L->path, line, col);
    else
        n = snprintf(L->err, L->errlen, "%s: ", L->path);
    if (L->err && n >= 0 && (size_t)n < L->errlen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(L->err + n, L->errlen - (size_t)n, fmt, ap);
        va_end(ap);
    }
    return code;
}

static int oom(loader *L)
{
    return fail(L, -ENOMEM, 0, 0, "out of memory");
}

/* ------------------------------------------------------------------------------------- */
/* CSV                                                                                    */

typedef struct field {
    char *s;   /* NUL-terminated in place */
    long col;  /* 1-based column of its first byte */
} field;

/* Splits `line` (NUL-terminated) at commas in place. Returns the number of fields (which may
 * exceed max; only max are stored). */
static int split_csv(char *line, field *f, int max)
{
    int n = 0;
    char *p = line;
    for (;;) {
        if (n < max) f[n] = (field){p, (long)(p - line) + 1};
        n++;
        char *comma = strchr(p, ',');
        if (!comma) break;
        *comma = '\0';
        p = comma + 1;
    }
    return n;
}

static void column_name(replay_format fmt, int i, char *buf, size_t len)
{
    static const char *const lead[LEAD_COLUMNS] = {"frame", "timestamp_us", "hand_id",
                                                   "hand_type"};
    static const char *const palm[9] = {"palm_x",  "palm_y",  "palm_z", "palm_nx", "palm_ny",
                                        "palm_nz", "dir_x",   "dir_y",  "dir_z"};
    if (i < LEAD_COLUMNS) {
        snprintf(buf, len, "%s", lead[i]);
    } else if (fmt == REPLAY_FORMAT_ANGLES_CSV) {
        snprintf(buf, len, "%s", angle_columns[i - LEAD_COLUMNS]);
    } else if (i < LEAD_COLUMNS + 9) {
        snprintf(buf, len, "%s", palm[i - LEAD_COLUMNS]);
    } else {
        int k = i - LEAD_COLUMNS - 9;
        snprintf(buf, len, "%s_%s_%c", finger_names[k / 12], segment_names[(k / 3) % 4],
                 "xyz"[k % 3]);
    }
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

/* 0 and the value; 1 for an empty field; -1 for a bad number; -2 for a non-finite one. */
static int parse_number(loader *L, const char *s, double *out)
{
    if (!*s) return 1;
    char *end;
    double v = strtod_l(s, &end, L->c_locale);
    if (end == s || *end) return -1;
    if (!isfinite(v)) return -2;
    *out = v;
    return 0;
}

static int number_error(loader *L, long line, const field *f, int rc, const char *col)
{
    if (rc == 1) return fail(L, -EBADMSG, line, f->col, "empty field in column %s", col);
    if (rc == -2)
        return fail(L, -EBADMSG, line, f->col, "\"%s\" in column %s is not a finite number", f->s,
                    col);
    return fail(L, -EBADMSG, line, f->col, "bad number \"%s\" in column %s", f->s, col);
}

/* One data row of either CSV format. */
static int csv_row(loader *L, replay_format fmt, long line, char *text, long long *last_ts,
                   int *have_ts)
{
    field f[MAX_COLUMNS];
    int want = fmt == REPLAY_FORMAT_JOINTS_CSV ? JOINT_COLUMNS : ANGLE_COLUMNS;
    long line_len = (long)strlen(text);
    int n = split_csv(text, f, MAX_COLUMNS);
    if (n < want)
        return fail(L, -EBADMSG, line, line_len + 1, "expected %d fields, found %d (row too short)",
                    want, n);
    if (n > want)
        return fail(L, -EBADMSG, line, f[want < MAX_COLUMNS ? want : 0].col,
                    "expected %d fields, found %d (row too long)", want, n);
    char name[64];
    long long frame, ts, id;
    if (parse_int64(f[0].s, &frame))
        return fail(L, -EBADMSG, line, f[0].col, "bad frame number \"%s\"", f[0].s);
    if (parse_int64(f[1].s, &ts) || ts > INT64_MAX / 1000 || ts < INT64_MIN / 1000)
        return fail(L, -EBADMSG, line, f[1].col, "bad timestamp_us \"%s\"", f[1].s);
    if (parse_int64(f[2].s, &id))
        return fail(L, -EBADMSG, line, f[2].col, "bad hand_id \"%s\"", f[2].s);
    int hand;
    if (strcmp(f[3].s, "left") == 0)
        hand = FP_HAND_LEFT;
    else if (strcmp(f[3].s, "right") == 0)
        hand = FP_HAND_RIGHT;
    else
        return fail(L, -EBADMSG, line, f[3].col, "unknown hand_type \"%s\" (left or right)", f[3].s);
    if (*have_ts && ts < *last_ts)
        return fail(L, -EBADMSG, line, f[1].col,
                    "timestamp_us %lld goes backwards (the row before has %lld)", ts, *last_ts);
    *last_ts = ts;
    *have_ts = 1;

    double v[MAX_COLUMNS - LEAD_COLUMNS];
    uint32_t valid = 0;
    for (int i = LEAD_COLUMNS; i < want; i++) {
        int rc = parse_number(L, f[i].s, &v[i - LEAD_COLUMNS]);
        if (rc == 1 && fmt == REPLAY_FORMAT_ANGLES_CSV) {
            v[i - LEAD_COLUMNS] = 0;
            continue;
        }
        if (rc) {
            column_name(fmt, i, name, sizeof name);
            return number_error(L, line, &f[i], rc, name);
        }
        if (fmt == REPLAY_FORMAT_ANGLES_CSV) valid |= 1u << (i - LEAD_COLUMNS);
    }
    if (!(L->hands & (1 << hand))) return 0; /* parsed for errors, not kept */

    int64_t t_ns = (int64_t)ts * 1000; /* made relative to the first kept item later */
    if (fmt == REPLAY_FORMAT_ANGLES_CSV) {
        replay_item *it = push_item(L);
        if (!it) return oom(L);
        it->t_ns = t_ns;
        fp_event_joint_angles *a = &it->event.angles;
        a->header = (fp_event_header){.size = sizeof *a, .type = FP_EVENT_JOINT_ANGLES,
                                      .hand = hand};
        a->valid = valid;
        for (int s = 0; s < FP_GLOVE_SENSORS; s++)
            a->radians[s] = (valid >> s & 1) ? (float)(v[s] * (M_PI / 180.0)) : 0.0f;
    } else {
        float q[4];
        if (replay_wrist_rotation(&v[3], &v[6], q))
            return fail(L, -EBADMSG, line, f[LEAD_COLUMNS + 3].col,
                        "palm normal and hand direction are zero or parallel");
        replay_item *it = push_item(L);
        if (!it) return oom(L);
        it->t_ns = t_ns;
        fp_event_joint_positions *p = &it->event.positions;
        p->header = (fp_event_header){.size = sizeof *p, .type = FP_EVENT_JOINT_POSITIONS,
                                      .hand = hand};
        /* Columns as strtof reads them: the nearest float to the CSV text. */
        for (int c = 0; c < 3; c++) p->mm[FP_JOINT_PALM][c] = strtof_l(f[4 + c].s, NULL, L->c_locale);
        for (int j = 0; j < 4 * FP_FINGERS; j++)
            for (int c = 0; c < 3; c++)
                p->mm[FP_JOINT_FINGER0 + j][c] =
                    strtof_l(f[LEAD_COLUMNS + 9 + 3 * j + c].s, NULL, L->c_locale);
        replay_item *wi = push_item(L);
        if (!wi) return oom(L);
        wi->t_ns = t_ns;
        fp_event_wrist_pose *w = &wi->event.wrist;
        w->header = (fp_event_header){.size = sizeof *w, .type = FP_EVENT_WRIST_POSE, .hand = hand};
        for (int c = 0; c < 3; c++) w->position_mm[c] = L->rec->items[L->rec->count - 2].event.positions.mm[0][c];
        memcpy(w->rotation, q, sizeof q);
    }
    L->rec->frames++;
    return 0;
}

static int check_csv_header(loader *L, replay_format fmt, char *text)
{
    field f[MAX_COLUMNS];
    int want = fmt == REPLAY_FORMAT_JOINTS_CSV ? JOINT_COLUMNS : ANGLE_COLUMNS;
    int n = split_csv(text, f, MAX_COLUMNS);
    char name[64];
    for (int i = 0; i < want && i < n; i++) {
        column_name(fmt, i, name, sizeof name);
        if (strcmp(f[i].s, name) != 0)
            return fail(L, -EBADMSG, 1, f[i].col, "header column %d is \"%s\", expected \"%s\"",
                        i + 1, f[i].s, name);
    }
    if (n != want)
        return fail(L, -EBADMSG, 1, n < want ? (long)strlen(text) + 1 : f[want].col,
                    "header has %d columns, expected %d", n, want);
    return 0;
}

static int read_file(loader *L, char **data, size_t *len)
{
    FILE *f = fopen(L->path, "rb");
    if (!f) return fail(L, -errno, 0, 0, "cannot open: %s", strerror(errno));
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap + 1);
    while (buf) {
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (n < cap) break;
        char *bigger = realloc(buf, cap * 2 + 1);
        if (!bigger) {
            free(buf);
            buf = NULL;
            break;
        }
        buf = bigger;
        cap *= 2;
    }
    int bad = ferror(f);
    fclose(f);
    if (!buf) return oom(L);
    if (bad) {
        free(buf);
        return fail(L, -EIO, 0, 0, "cannot read");
    }
    buf[n] = '\0';
    *data = buf;
    *len = n;
    return 0;
}

static int load_csv(loader *L, replay_format fmt, char *data, size_t len)
{
    long line = 0;
    long long last_ts = 0;
    int have_ts = 0;
    char *p = data, *end = data + len;
    while (p < end) {
        char *nl = memchr(p, '\n', (size_t)(end - p));
        line++;
        if (!nl) {
            /* The last line has no newline: cut short (a crash, a copy cut off). */
            if (line == 1) return fail(L, -EBADMSG, 1, 1, "header line not terminated");
            L->rec->truncated_line = line;
            break;
        }
        *nl = '\0';
        size_t n = (size_t)(nl - p);
        if (n > 0 && p[n - 1] == '\r') p[--n] = '\0';
        if (strlen(p) != n) return fail(L, -EBADMSG, line, (long)strlen(p) + 1, "NUL byte in line");
        int rc;
        if (line == 1)
            rc = check_csv_header(L, fmt, p);
        else if (*p == '\0')
            rc = 0; /* blank line */
        else
            rc = csv_row(L, fmt, line, p, &last_ts, &have_ts);
        if (rc) return rc;
        p = nl + 1;
    }
    return 0;
}

/* ------------------------------------------------------------------------------------- */
/* Event log                                                                              */

static int load_eventlog(loader *L)
{
    fp_eventlog_reader *r = fp_eventlog_reader_open(L->path, L->err, L->errlen);
    if (!r) return -EBADMSG;
    fp_event ev;
    int rc, own = 0; /* own: rc is this loader's -errno, with its message in err */
    int64_t last = 0;
    int have = 0;
    while ((rc = fp_eventlog_reader_next(r, &ev)) == 1) {
        if (have && ev.header.time_ns < last) {
            rc = fail(L, -EBADMSG, fp_eventlog_reader_line(r), 1,
                      "time %lld goes backwards (the event before has %lld)",
                      (long long)ev.header.time_ns, (long long)last);
            own = 1;
            break;
        }
        last = ev.header.time_ns;
        have = 1;
        if (ev.header.hand >= 0 && !(L->hands & (1 << ev.header.hand))) continue;
        replay_item *it = push_item(L);
        if (!it) {
            rc = oom(L);
            own = 1;
            break;
        }
        it->t_ns = ev.header.time_ns;
        it->event = ev;
        it->event.header.source = 0;
        L->rec->frames++;
    }
    if (rc < 0 && !own) {
        put_msg(L->err, L->errlen, "%s", fp_eventlog_reader_error(r));
    }
    L->rec->truncated_line = fp_eventlog_reader_truncated_line(r);
    fp_eventlog_reader_close(&r);
    return rc < 0 ? rc : 0;
}

/* ------------------------------------------------------------------------------------- */

void replay_recording_free(replay_recording *rec)
{
    if (!rec) return;
    free(rec->items);
    memset(rec, 0, sizeof *rec);
}

static const char *hands_name(int hands)
{
    return hands == REPLAY_HAND_LEFT ? "left" : hands == REPLAY_HAND_RIGHT ? "right" : "both";
}

int replay_load(const char *path, int hands, replay_recording *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    loader L = {path, hands, newlocale(LC_ALL_MASK, "C", (locale_t)0), out, 0, err, errlen};
    if (L.c_locale == (locale_t)0) return oom(&L);
    char *data = NULL;
    size_t len = 0;
    int rc = read_file(&L, &data, &len);
    if (rc) {
        freelocale(L.c_locale);
        return rc;
    }
    static const char csv_lead[] = "frame,timestamp_us,hand_id,hand_type,";
    static const char log_lead[] = "# " FP_EVENTLOG_MAGIC;
    if (strncmp(data, log_lead, sizeof log_lead - 1) == 0) {
        out->format = REPLAY_FORMAT_EVENTLOG;
        free(data);
        data = NULL;
        rc = load_eventlog(&L);
    } else if (strncmp(data, csv_lead, sizeof csv_lead - 1) == 0) {
        const char *next = data + sizeof csv_lead - 1;
        out->format = strncmp(next, "palm_x,", 7) == 0 ? REPLAY_FORMAT_JOINTS_CSV
                                                       : REPLAY_FORMAT_ANGLES_CSV;
        rc = load_csv(&L, out->format, data, len);
    } else {
        rc = fail(&L, -EBADMSG, 1, 1,
                  "unknown format: expected a facepuppet event log (\"# %s 1\") or a Leap CSV "
                  "(header \"%s...\")", FP_EVENTLOG_MAGIC, csv_lead);
    }
    free(data);
    freelocale(L.c_locale);
    if (!rc && out->count == 0)
        rc = fail(&L, -EINVAL, 0, 0, "no events to replay (hands=%s)", hands_name(hands));
    if (rc) {
        replay_recording_free(out);
        return rc;
    }
    /* Times relative to the first kept event; loop period = duration + mean distinct step. */
    int64_t t0 = out->items[0].t_ns;
    size_t distinct = 1;
    for (size_t i = 0; i < out->count; i++) {
        out->items[i].t_ns -= t0;
        if (i > 0 && out->items[i].t_ns != out->items[i - 1].t_ns) distinct++;
    }
    out->duration_ns = out->items[out->count - 1].t_ns;
    int64_t gap = distinct > 1 ? out->duration_ns / (int64_t)(distinct - 1) : DEFAULT_LOOP_GAP_NS;
    if (gap <= 0) gap = DEFAULT_LOOP_GAP_NS;
    out->loop_period_ns = out->duration_ns + gap;
    return 0;
}
