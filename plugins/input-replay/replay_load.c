/*
 * replay_load.c: input-replay's loader (see replay_load.h). The CSV formats are described in
 * shared/data/README.md; the event log in docs/eventlog.md.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "replay_load.h"

#include "fp_error.h"
#include "fp_file.h"
#include "fp_text.h"
#include "fp_eventlog.h"
#include "fp_hand.h"
#include "leapcsv.h"
#include "leapjson.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_LOOP_GAP_NS 10000000 /* 10 ms: the loop gap of a one-moment recording */

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
    /* R's columns are the hand axes in the device frame. */
    double r[3][3];
    for (int i = 0; i < 3; i++) {
        r[i][0] = x[i];
        r[i][1] = y[i];
        r[i][2] = z[i];
    }
    fp_hand_mat_to_quat((const double (*)[3])r, q);
    return 0;
}

/* ------------------------------------------------------------------------------------- */
/* Growing item list                                                                      */

typedef struct loader {
    const char *path;
    int hands;
    replay_recording *rec;
    size_t cap;
    size_t seen; /* events or rows read, whatever their hand */
    int64_t last_t[FP_HANDS]; /* CSV/JSON: the time of each hand's last kept row ... */
    bool has_last[FP_HANDS];  /* ... once it has one */
    long first_repeat;        /* the first row repeating its hand's time: line, or frame */
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

/* "PATH:LINE:COL: reason", or "PATH: reason" when line is 0 (fp_error_at). */
#define fail(L, code, line, col, ...) fp_error_at((L)->err, (L)->errlen, code, (L)->path, line, col, __VA_ARGS__)

static int oom(loader *L)
{
    return fail(L, -ENOMEM, 0, 0, "out of memory");
}

/* ------------------------------------------------------------------------------------- */
/* Leap CSV (core/hand/leapcsv.h reads and checks; this keeps the hands asked for)        */

static int csv_row(void *user, const fp_leapcsv_row *row, char *err, size_t errlen)
{
    (void)err, (void)errlen; /* the loader's own buffer */
    loader *L = user;
    int hand = row->side;
    L->seen++;
    if (!(L->hands & (1 << hand))) return 0; /* parsed for errors, not kept */
    int64_t t_ns = row->timestamp_us * 1000; /* made relative to the first kept item later */
    if (L->has_last[hand] && t_ns == L->last_t[hand] && !L->rec->repeated++)
        L->first_repeat = row->line > 0 ? row->line : row->frame;
    L->last_t[hand] = t_ns;
    L->has_last[hand] = true;
    const double *v = row->value;
    if (row->format == FP_LEAPCSV_ANGLES) {
        replay_item *it = push_item(L);
        if (!it) return oom(L);
        it->t_ns = t_ns;
        fp_event_joint_angles *a = &it->event.angles;
        a->header = (fp_event_header){.size = sizeof *a, .type = FP_EVENT_JOINT_ANGLES,
                                      .hand = hand};
        a->valid = row->valid;
        for (int s = 0; s < FP_GLOVE_SENSORS; s++)
            a->radians[s] = (row->valid >> s & 1) ? (float)(v[s] * (M_PI / 180.0)) : 0.0f;
    } else {
        float q[4];
        if (replay_wrist_rotation(&v[3], &v[6], q))
            return row->line > 0 ? fail(L, -EBADMSG, row->line, row->col[FP_LEAPCSV_LEAD + 3],
                                        "palm normal and hand direction are zero or parallel")
                                 : fail(L, -EBADMSG, 0, 0, "frames[%ld], hand %ld: palm normal and hand "
                                        "direction are zero or parallel", row->frame, row->hand_id);
        replay_item *it = push_item(L);
        if (!it) return oom(L);
        it->t_ns = t_ns;
        fp_event_joint_positions *p = &it->event.positions;
        p->header = (fp_event_header){.size = sizeof *p, .type = FP_EVENT_JOINT_POSITIONS,
                                      .hand = hand};
        /* Columns as strtof reads them: the nearest float to the CSV text. */
        for (int c = 0; c < 3; c++) p->mm[FP_JOINT_PALM][c] = row->valuef[c];
        for (int j = 0; j < 4 * FP_FINGERS; j++)
            for (int c = 0; c < 3; c++) p->mm[FP_JOINT_FINGER0 + j][c] = row->valuef[9 + 3 * j + c];
        replay_item *wi = push_item(L);
        if (!wi) return oom(L);
        wi->t_ns = t_ns;
        fp_event_wrist_pose *w = &wi->event.wrist;
        w->header = (fp_event_header){.size = sizeof *w, .type = FP_EVENT_WRIST_POSE, .hand = hand};
        for (int c = 0; c < 3; c++) w->position_mm[c] = row->valuef[c];
        memcpy(w->rotation, q, sizeof q);
    }
    L->rec->frames++;
    return 0;
}

/* ------------------------------------------------------------------------------------- */
/* Event log                                                                              */

static int load_eventlog(loader *L)
{
    int code;
    fp_eventlog_reader *r = fp_eventlog_reader_open_code(L->path, &code, L->err, L->errlen);
    if (!r) return code; /* (-EBADMSG, -ENOTSUP: 65; the file's own: 66) */
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
        L->seen++;
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
        fp_errorf(L->err, L->errlen, 0, "%s", fp_eventlog_reader_error(r)); /* rc is an errno */
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

/* The first bytes of the file, NUL-terminated, to tell the formats apart. */
static int read_head(loader *L, char *head, size_t len)
{
    int code;
    FILE *f = fp_file_fopen_regular(L->path, &code); /* a FIFO or a device cannot hold it */
    if (!f) return fail(L, code, 0, 0, "cannot open: %s", fp_file_error_text(code));
    size_t n = fread(head, 1, len - 1, f);
    int bad = ferror(f);
    fclose(f);
    if (bad) return fail(L, -EIO, 0, 0, "cannot read");
    head[n] = '\0';
    return 0;
}

int replay_load(const char *path, int hands, replay_recording *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    loader L = {.path = path, .hands = hands, .rec = out, .err = err, .errlen = errlen};
    static const char csv_lead[] = "frame,timestamp_us,hand_id,hand_type,";
    static const char log_lead[] = "# " FP_EVENTLOG_MAGIC;
    char head_bytes[64];
    int rc = read_head(&L, head_bytes, sizeof head_bytes);
    if (rc) return rc;
    const char *head = head_bytes + fp_text_bom(head_bytes, strlen(head_bytes)); /* (CSV, JSON) */
    if (strncmp(head, log_lead, sizeof log_lead - 1) == 0) {
        out->format = REPLAY_FORMAT_EVENTLOG;
        rc = load_eventlog(&L);
    } else if (strncmp(head, csv_lead, sizeof csv_lead - 1) == 0) {
        fp_leapcsv_format fmt = FP_LEAPCSV_ANY;
        rc = fp_leapcsv_read(path, FP_LEAPCSV_ANY, &fmt, csv_row, &L, &out->truncated_line, err,
                             errlen);
        out->format = fmt == FP_LEAPCSV_JOINTS ? REPLAY_FORMAT_JOINTS_CSV : REPLAY_FORMAT_ANGLES_CSV;
    } else if (fp_leapjson_looks_like(head)) {
        out->format = REPLAY_FORMAT_LEAP_JSON;
        rc = fp_leapjson_read(path, csv_row, &L, err, errlen);
    } else {
        rc = fail(&L, -EBADMSG, 1, 1,
                  "unknown format: expected a facepuppet event log (\"# %s 1\"), a Leap CSV "
                  "(header \"%s...\") or a Leap playback recording (JSON, or LZ-string base64 as "
                  "*.json.lz)", FP_EVENTLOG_MAGIC, csv_lead);
    }
    if (!rc && out->count == 0)
        rc = L.seen ? fail(&L, -EINVAL, 0, 0, "no events to replay (hands=%s)", /* the option's */
                           fp_hands_name((unsigned)hands))
                    : fail(&L, -EBADMSG, 0, 0, "the recording holds no events");
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
    if (distinct == 1 && out->repeated) { /* every row of a hand at one time: no motion to play */
        rc = fail(&L, -EBADMSG, 0, 0, "every row has the same time (%s %lld): the recording spans no "
                  "time, so its %zu rows would play as one", out->format == REPLAY_FORMAT_LEAP_JSON
                  ? "timestamp" : "timestamp_us", (long long)(t0 / 1000), out->frames);
        replay_recording_free(out);
        return rc;
    }
    out->first_repeat = L.first_repeat;
    out->duration_ns = out->items[out->count - 1].t_ns;
    int64_t gap = distinct > 1 ? out->duration_ns / (int64_t)(distinct - 1) : DEFAULT_LOOP_GAP_NS;
    if (gap <= 0) gap = DEFAULT_LOOP_GAP_NS;
    out->loop_period_ns = out->duration_ns + gap;
    return 0;
}
