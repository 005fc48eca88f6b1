/*
 * test_replay.c: the input-replay plugin, loaded with dlopen from the build tree through its
 * facepuppet_plugin_entry, driven by a fake host whose push_event appends to an array.
 * Reference values come from this file's own CSV reading of shared/data.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "fp_eventlog.h"
#include "fp_test_support.h"

#include <facepuppet/plugin.h>

#include <dlfcn.h>
#include <errno.h>
#include <ftw.h>
#include <math.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#define LEAP "../shared/data/hands/leap-motion/"
#define WAIT_LIMIT_NS 30000000000LL /* a replay that does not end within 30 s has hung */

static char tmpdir[256];
static void *plugin_handle;
static const fp_plugin_entry *entry;
static const fp_input_factory *factory;

/* ------------------------------------------------------------------------------------- */
/* Plugin                                                                                 */

static int rm_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb, (void)flag, (void)ftw;
    return remove(path);
}

static int group_setup(void **state)
{
    factory = fp_test_plugin_open("input-replay.so", FP_INPUT_FACTORY_ID, &plugin_handle);
    if (!factory) return -1;
    entry = dlsym(plugin_handle, FP_PLUGIN_ENTRY_SYMBOL);
    const char *base = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%s/fp-replay-XXXXXX", base && *base ? base : "/tmp");
    return mkdtemp(tmpdir) ? 0 : -1;
}

static int group_teardown(void **state)
{
    fp_test_plugin_close(&plugin_handle);
    return tmpdir[0] ? nftw(tmpdir, rm_entry, 16, FTW_DEPTH | FTW_PHYS) : 0;
}

/* Creates an instance from FILE and "k=v,k=v" keys. Returns create's code. */
static int create(fp_test_host *h, const char *file, const char *keys, fp_input **in, char *err,
                  size_t errlen)
{
    char buf[256];
    fp_param params[8];
    size_t n = 0;
    snprintf(buf, sizeof buf, "%s", keys ? keys : "");
    for (char *save = NULL, *kv = strtok_r(buf, ",", &save); kv && n < 8;
         kv = strtok_r(NULL, ",", &save)) {
        char *eq = strchr(kv, '=');
        assert_non_null(eq);
        *eq = '\0';
        params[n++] = (fp_param){kv, eq + 1};
    }
    err[0] = '\0';
    return factory->create(&h->host, file, params, n, in, err, errlen);
}

/* Replays to the end of stream; returns the host with every event. */
static fp_test_host *replay_all(const char *file, const char *keys, size_t cap)
{
    fp_test_host *h = fp_test_host_new(cap);
    fp_input *in = NULL;
    char err[512];
    int rc = create(h, file, keys, &in, err, sizeof err);
    if (rc) fail_msg("create %s [%s]: %d %s", file, keys ? keys : "", rc, err);
    assert_int_equal(in->start(in, err, sizeof err), 0);
    if (fp_test_host_wait(h, 0, WAIT_LIMIT_NS)) fail_msg("replay of %s did not end", file);
    in->stop(in);
    in->destroy(in);
    return h;
}

static size_t count_type(const fp_test_host *h, int type, int hand)
{
    size_t n = 0;
    for (size_t i = 0; i < h->count; i++)
        if (h->events[i].header.type == type && (hand < 0 || h->events[i].header.hand == hand)) n++;
    return n;
}

/* ------------------------------------------------------------------------------------- */
/* Reference CSV reading                                                                  */

typedef struct csv_row {
    int hand;
    long long ts;
    int nfields;
    char field[80][24];
} csv_row;

/* Reads every data row of a CSV into a malloc'ed array. */
static csv_row *read_csv(const char *path, size_t *nrows)
{
    FILE *f = fopen(path, "r");
    if (!f) fail_msg("cannot open %s", path);
    static char line[16384];
    size_t cap = 1024, n = 0;
    csv_row *rows = malloc(cap * sizeof *rows);
    assert_non_null(fgets(line, sizeof line, f)); /* header */
    while (fgets(line, sizeof line, f)) {
        line[strcspn(line, "\r\n")] = '\0';
        if (n == cap) rows = realloc(rows, (cap *= 2) * sizeof *rows);
        csv_row *r = &rows[n++];
        memset(r, 0, sizeof *r);
        char *p = line, *tok;
        while ((tok = strsep(&p, ",")) != NULL) {
            assert_true(r->nfields < 80);
            snprintf(r->field[r->nfields++], sizeof r->field[0], "%s", tok);
        }
        r->hand = strcmp(r->field[3], "left") == 0 ? FP_HAND_LEFT : FP_HAND_RIGHT;
        r->ts = atoll(r->field[1]);
    }
    fclose(f);
    *nrows = n;
    return rows;
}

static void tmp_path(char *buf, size_t len, const char *name)
{
    snprintf(buf, len, "%s/%s", tmpdir, name);
}

static char *read_header(const char *csv)
{
    static char header[4096];
    FILE *f = fopen(csv, "r");
    assert_non_null(f);
    assert_non_null(fgets(header, sizeof header, f));
    fclose(f);
    return header; /* with its newline */
}

/* A synthetic joints CSV: rows rows, step_us apart, one right hand. Row r's values: palm
 * (r, 100, -r), normal (0,-1,0), direction (0,0,-1), finger value k: k * 0.5 + r. Returns the
 * text of each row in lines[] when given (without newline). */
static void write_joints_csv(const char *path, int rows, long long step_us, const char *hand)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(read_header(LEAP "grab_joints_mm.csv"), f);
    for (int r = 0; r < rows; r++) {
        fprintf(f, "%d,%lld,7,%s,%d,100,%d,0,-1,0,0,0,-1", r, 1000000 + r * step_us, hand, r, -r);
        for (int k = 0; k < 60; k++) fprintf(f, ",%g", k * 0.5 + r);
        fputc('\n', f);
    }
    fclose(f);
}

/* ------------------------------------------------------------------------------------- */
/* Tests                                                                                  */

static void factory_describes_itself(void **state)
{
    assert_string_equal(entry->id, "org.facepuppet.input-replay");
    assert_null(entry->get_factory(FP_MAPPING_FACTORY_ID));
    assert_string_equal(factory->name, "replay");
    assert_int_equal(factory->size, sizeof(fp_input_factory));
    const char *keys[] = {"replay:FILE", "speed=", "loop=", "fast=", "hands=", "joints_mm",
                          "angles_deg", "event log", "end-of-stream"};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++)
        if (!strstr(factory->usage, keys[i])) fail_msg("usage lacks \"%s\"", keys[i]);
}

/* Frame counts of every shared recording, both CSV kinds, equal the CSV row counts per hand. */
static void frame_counts_match_csv_rows(void **state)
{
    const char *names[] = {"HandSplay-110fps", "Waiting-110fps", "grab", "three-claps"};
    for (size_t i = 0; i < 4; i++) {
        for (int kind = 0; kind < 2; kind++) {
            char path[512];
            snprintf(path, sizeof path, LEAP "%s_%s.csv", names[i],
                     kind ? "cyberglove_like_angles_deg" : "joints_mm");
            size_t nrows;
            csv_row *rows = read_csv(path, &nrows);
            size_t per_hand[2] = {0, 0};
            for (size_t r = 0; r < nrows; r++) per_hand[rows[r].hand]++;
            fp_test_host *h = replay_all(path, "fast=1", 8 * nrows + 16);
            for (int hand = 0; hand < 2; hand++) {
                if (kind == 0) {
                    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, hand), per_hand[hand]);
                    assert_int_equal(count_type(h, FP_EVENT_WRIST_POSE, hand), per_hand[hand]);
                    assert_int_equal(count_type(h, FP_EVENT_JOINT_ANGLES, -1), 0);
                } else {
                    assert_int_equal(count_type(h, FP_EVENT_JOINT_ANGLES, hand), per_hand[hand]);
                    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, -1), 0);
                }
            }
            if (strcmp(names[i], "three-claps") == 0) {
                assert_int_equal(per_hand[0], 403);
                assert_int_equal(per_hand[1], 403);
            }
            /* First a connected status, last the end of stream; times never go backwards. */
            assert_int_equal(h->events[0].header.type, FP_EVENT_STATUS);
            assert_int_equal(h->events[0].status.code, FP_STATUS_CONNECTED);
            const fp_event *last = &h->events[h->count - 1];
            assert_int_equal(last->header.type, FP_EVENT_STATUS);
            assert_int_equal(last->status.code, FP_STATUS_END_OF_STREAM);
            assert_int_equal(h->eos, 1);
            for (size_t e = 1; e < h->count; e++)
                assert_true(h->events[e].header.time_ns >= h->events[e - 1].header.time_ns);
            /* Emulated times span the recording: last - first = last ts - first ts. */
            assert_int_equal(h->events[h->count - 2].header.time_ns - h->events[1].header.time_ns,
                             (rows[nrows - 1].ts - rows[0].ts) * 1000);
            fp_test_host_free(h);
            free(rows);
        }
    }
}

/* Rotates v by the unit quaternion q (w, x, y, z). */
static void quat_rotate(const float q[4], const double v[3], double out[3])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                      {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                      {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    for (int i = 0; i < 3; i++) out[i] = r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2];
}

static void positions_and_wrist_equal_csv(void **state)
{
    const char *path = LEAP "three-claps_joints_mm.csv";
    size_t nrows;
    csv_row *rows = read_csv(path, &nrows);
    fp_test_host *h = replay_all(path, "fast=1", 4 * nrows + 16);
    size_t row = 0;
    for (size_t e = 0; e < h->count; e++) {
        const fp_event *ev = &h->events[e];
        if (ev->header.type == FP_EVENT_JOINT_POSITIONS) {
            assert_true(row < nrows);
            const csv_row *r = &rows[row];
            assert_int_equal(r->nfields, 73);
            assert_int_equal(ev->header.hand, r->hand);
            assert_int_equal(ev->header.size, sizeof(fp_event_joint_positions));
            for (int c = 0; c < 3; c++)
                assert_true(ev->positions.mm[FP_JOINT_PALM][c] == strtof(r->field[4 + c], NULL));
            /* fingers: thumb, index, middle, ring, pinky; mcp, pip, dip, tip; from column 13 */
            for (int f = 0; f < FP_FINGERS; f++)
                for (int k = 0; k < 4; k++)
                    for (int c = 0; c < 3; c++) {
                        float want = strtof(r->field[13 + 12 * f + 3 * k + c], NULL);
                        if (ev->positions.mm[FP_JOINT(f, k)][c] != want)
                            fail_msg("row %zu finger %d joint %d axis %d: %g != %g", row, f, k, c,
                                     ev->positions.mm[FP_JOINT(f, k)][c], want);
                    }
            /* the wrist pose follows, same time and hand */
            const fp_event *w = &h->events[e + 1];
            assert_int_equal(w->header.type, FP_EVENT_WRIST_POSE);
            assert_int_equal(w->header.hand, r->hand);
            assert_int_equal(w->header.time_ns, ev->header.time_ns);
            for (int c = 0; c < 3; c++)
                assert_true(w->wrist.position_mm[c] == ev->positions.mm[FP_JOINT_PALM][c]);
            const float *q = w->wrist.rotation;
            double qn = sqrt((double)q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            assert_true(fabs(qn - 1) < 1e-6);
            assert_true(q[0] >= 0);
            double n[3], d[3], ln = 0, ld = 0;
            for (int c = 0; c < 3; c++) {
                n[c] = atof(r->field[7 + c]);
                d[c] = atof(r->field[10 + c]);
                ln += n[c] * n[c];
                ld += d[c] * d[c];
            }
            const double up[3] = {0, 1, 0}, fwd[3] = {0, 0, -1};
            double back[3], fingers[3];
            quat_rotate(q, up, back);   /* +y: back of the hand = -normal */
            quat_rotate(q, fwd, fingers); /* -z: toward the fingers = direction */
            for (int c = 0; c < 3; c++) {
                if (fabs(fingers[c] - d[c] / sqrt(ld)) > 1e-5)
                    fail_msg("row %zu: -z maps to %g, direction %g", row, fingers[c], d[c]);
                if (fabs(back[c] + n[c] / sqrt(ln)) > 0.01) /* CSV normal ~ orthogonal */
                    fail_msg("row %zu: +y maps to %g, -normal %g", row, back[c], -n[c]);
            }
            /* +x = y cross z (a proper rotation): toward the pinky of a right hand and the
             * thumb of a left hand (see docs/arch/replay.md on plugin.h's wording). */
            const double ex[3] = {1, 0, 0};
            double side[3], across = 0;
            quat_rotate(q, ex, side);
            for (int c = 0; c < 3; c++)
                across += side[c] * (ev->positions.mm[FP_JOINT_TIP(0)][c] -
                                     ev->positions.mm[FP_JOINT_TIP(4)][c]);
            if (r->hand == FP_HAND_RIGHT ? across >= 0 : across <= 0)
                fail_msg("row %zu: +x . (thumb tip - pinky tip) = %g", row, across);
            row++;
        }
    }
    assert_int_equal(row, nrows);
    fp_test_host_free(h);
    free(rows);
}

/* FP_EXT_RECORDING_JOINTS: the joint positions given before start are the joint-position
 * events the replay then pushes, in order, bit for bit, with their hands; workspace=0 (the
 * range kept to itself) gives neither the workspace nor the joints; an angles recording has
 * no positions to give. */
typedef struct joints_seen {
    const fp_test_host *h;
    size_t e, n;
    int bad;
} joints_seen;

static void joints_cb(void *ctx, int hand, const float (*mm)[3])
{
    joints_seen *j = ctx;
    while (j->e < j->h->count && j->h->events[j->e].header.type != FP_EVENT_JOINT_POSITIONS) j->e++;
    if (j->e == j->h->count) {
        j->bad++;
        return;
    }
    const fp_event *ev = &j->h->events[j->e++];
    j->bad += ev->header.hand != hand || memcmp(ev->positions.mm, mm, sizeof ev->positions.mm) != 0;
    j->n++;
}

static void joints_given_in_advance(void **state)
{
    (void)state;
    const char *path = LEAP "three-claps_joints_mm.csv";
    size_t nrows;
    csv_row *rows = read_csv(path, &nrows);
    fp_test_host *h = replay_all(path, "fast=1", 4 * nrows + 16);
    fp_test_host *h2 = fp_test_host_new(16);
    fp_input *in = NULL;
    char err[512];
    assert_int_equal(create(h2, path, "fast=1", &in, err, sizeof err), 0);
    assert_non_null(in->get_extension(in, FP_EXT_WORKSPACE));
    const fp_input_recording_joints *x = in->get_extension(in, FP_EXT_RECORDING_JOINTS);
    assert_non_null(x);
    joints_seen j = {.h = h};
    assert_int_equal(x->each(in, joints_cb, &j), nrows);
    assert_int_equal(j.n, nrows);
    assert_int_equal(j.bad, 0);
    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, -1), nrows);
    in->destroy(in);
    assert_int_equal(create(h2, path, "fast=1,workspace=0", &in, err, sizeof err), 0);
    assert_null(in->get_extension(in, FP_EXT_WORKSPACE));
    assert_null(in->get_extension(in, FP_EXT_RECORDING_JOINTS));
    in->destroy(in);
    assert_int_equal(create(h2, LEAP "grab_cyberglove_like_angles_deg.csv", "fast=1", &in, err, sizeof err), 0);
    x = in->get_extension(in, FP_EXT_RECORDING_JOINTS);
    joints_seen none = {.h = h};
    assert_true(!x || x->each(in, joints_cb, &none) == 0);
    assert_int_equal(none.n, 0);
    in->destroy(in);
    fp_test_host_free(h2);
    fp_test_host_free(h);
    free(rows);
}

/* A Leap playback original (*.json.lz, core/hand/leapjson.h) replays as its CSV conversion:
 * the same events in the same order and times, positions within the CSV's 4 decimals */
static void leap_original_replays_as_its_csv(void **state)
{
    (void)state;
    const char *lz = LEAP "three-claps.json.lz", *csv = LEAP "three-claps_joints_mm.csv";
    size_t nrows;
    csv_row *rows = read_csv(csv, &nrows);
    fp_test_host *a = replay_all(lz, "fast=1", 4 * nrows + 16);
    fp_test_host *b = replay_all(csv, "fast=1", 4 * nrows + 16);
    assert_int_equal(a->count, b->count);
    assert_int_equal(count_type(a, FP_EVENT_JOINT_POSITIONS, -1), nrows);
    double worst = 0;
    for (size_t e = 0; e < a->count; e++) {
        const fp_event *x = &a->events[e], *y = &b->events[e];
        assert_int_equal(x->header.type, y->header.type);
        assert_int_equal(x->header.hand, y->header.hand);
        assert_int_equal(x->header.time_ns - a->events[0].header.time_ns,
                         y->header.time_ns - b->events[0].header.time_ns);
        if (x->header.type != FP_EVENT_JOINT_POSITIONS) continue;
        for (int j = 0; j < FP_HAND_JOINTS; j++)
            for (int c = 0; c < 3; c++) {
                double d = fabs((double)x->positions.mm[j][c] - y->positions.mm[j][c]);
                worst = d > worst ? d : worst;
            }
    }
    printf("three-claps.json.lz: %zu events, as its CSV's; positions within %.2g mm\n", a->count, worst);
    assert_true(worst <= 6e-5);
    fp_test_host_free(a);
    fp_test_host_free(b);
    free(rows);
}

static void angles_in_radians_empty_invalid(void **state)
{
    const char *path = LEAP "three-claps_cyberglove_like_angles_deg.csv";
    size_t nrows;
    csv_row *rows = read_csv(path, &nrows);
    fp_test_host *h = replay_all(path, "fast=1", nrows + 16);
    size_t row = 0;
    for (size_t e = 0; e < h->count; e++) {
        const fp_event *ev = &h->events[e];
        if (ev->header.type != FP_EVENT_JOINT_ANGLES) continue;
        const csv_row *r = &rows[row++];
        assert_int_equal(r->nfields, 26);
        assert_int_equal(ev->header.hand, r->hand);
        uint32_t want_valid = 0;
        for (int s = 0; s < FP_GLOVE_SENSORS; s++) {
            const char *fld = r->field[4 + s];
            if (!*fld) {
                assert_true(ev->angles.radians[s] == 0.0f);
                continue;
            }
            want_valid |= 1u << s;
            double want = atof(fld) * M_PI / 180.0;
            if (fabs(ev->angles.radians[s] - want) > 1.2e-7 * fabs(want) + 1e-12) /* float rounding */
                fail_msg("row %zu sensor %d: %.9g rad, expected %.9g", row, s,
                         ev->angles.radians[s], want);
        }
        assert_int_equal(ev->angles.valid, want_valid);
        /* thumb rotation, palm arch and wrist angles are empty in these recordings */
        assert_int_equal(ev->angles.valid & ((1u << FP_SENSOR_THUMB_ROTATE) |
                                             (1u << FP_SENSOR_PALM_ARCH) |
                                             (1u << FP_SENSOR_WRIST_PITCH) |
                                             (1u << FP_SENSOR_WRIST_YAW)), 0);
        assert_true(ev->angles.valid & (1u << FP_SENSOR_INDEX_MPJ));
    }
    assert_int_equal(row, nrows);
    fp_test_host_free(h);
    free(rows);
}

static void hands_filter(void **state)
{
    fp_test_host *h = replay_all(LEAP "three-claps_joints_mm.csv", "fast=1,hands=left", 2000);
    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, FP_HAND_LEFT), 403);
    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, FP_HAND_RIGHT), 0);
    assert_int_equal(count_type(h, FP_EVENT_WRIST_POSE, FP_HAND_RIGHT), 0);
    fp_test_host_free(h);
    /* a right-only recording has nothing for the left hand: an error at create */
    h = fp_test_host_new(4);
    fp_input *in = NULL;
    char err[512];
    assert_int_equal(create(h, LEAP "grab_joints_mm.csv", "hands=left", &in, err, sizeof err),
                     -EINVAL);
    assert_null(in);
    assert_non_null(strstr(err, "no events to replay (hands=left)"));
    fp_test_host_free(h);
}

/* A hand the recording loses while the other goes on: the right hand's rows stop at 0.5 s
 * and resume at 2.5 s, the left's run from 0 to 3 s, a third hand-free stretch ends it (the
 * right hand's last row 1.5 s before the left's). With timeout=1 the right hand is reported
 * gone at 1.5 s and again at 4.0 s (its last row 3.0 s, the recording's end 4.5 s), the left
 * never; timeout=0 reports none; timeout=1.6 only the first, at 2.1 s. */
static void lost_hand_reported(void **state)
{
    (void)state;
    char path[512];
    tmp_path(path, sizeof path, "lost_hand_joints_mm.csv");
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(read_header(LEAP "grab_joints_mm.csv"), f);
    int id = 0;
    for (long long t = 0; t <= 4500000; t += 10000) {
        for (int hand = 0; hand < 2; hand++) {
            const bool right = hand == 1;
            if (right ? !((t <= 500000) || (t >= 2500000 && t <= 3000000)) : t > 4500000) continue;
            fprintf(f, "%d,%lld,7,%s,%d,100,0,0,-1,0,0,0,-1", id++, 1000000 + t, right ? "right" : "left",
                    right ? 50 : -50);
            for (int k = 0; k < 60; k++) fprintf(f, ",%g", k * 0.5);
            fputc('\n', f);
        }
    }
    fclose(f);
    static const struct { const char *keys; int gone; int64_t at_ms[2]; } cases[] = {
        {"fast=1", 2, {1500, 4000}},
        {"fast=1,timeout=1", 2, {1500, 4000}},
        {"fast=1,timeout=0", 0, {0, 0}},
        {"fast=1,timeout=1.6", 1, {2100, 0}}, /* the 1.5 s before the end is under 1.6 */
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        fp_test_host *h = replay_all(path, cases[c].keys, 4000);
        int64_t t0 = h->events[1].header.time_ns; /* the first pose */
        int gone = 0;
        for (size_t i = 0; i < h->count; i++) {
            const fp_event *e = &h->events[i];
            if (i) assert_true(e->header.time_ns >= h->events[i - 1].header.time_ns);
            if (e->header.type != FP_EVENT_STATUS || e->status.code != FP_STATUS_DISCONNECTED) continue;
            assert_int_equal(e->header.hand, FP_HAND_RIGHT);
            assert_true(gone < 2);
            assert_int_equal((e->header.time_ns - t0) / 1000000, cases[c].at_ms[gone]);
            assert_non_null(strstr(e->status.text, "right hand: not in the recording"));
            /* the right hand's poses: none between its last before the loss and the loss */
            for (size_t j = i; j-- > 0;)
                if (h->events[j].header.type == FP_EVENT_JOINT_POSITIONS && h->events[j].header.hand == FP_HAND_RIGHT) {
                    assert_true(e->header.time_ns - h->events[j].header.time_ns > 0);
                    break;
                }
            gone++;
        }
        if (gone != cases[c].gone) fail_msg("%s: %d losses reported, expected %d", cases[c].keys, gone, cases[c].gone);
        assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, FP_HAND_RIGHT), 51 + 51);
        fp_test_host_free(h);
    }
}

/* speed=4 on 21 rows 20 ms apart (400 ms): about 100 ms of wall time, event times 5 ms apart. */
static void pacing_follows_speed(void **state)
{
    char path[512];
    tmp_path(path, sizeof path, "pace_joints.csv");
    write_joints_csv(path, 21, 20000, "right");
    fp_test_host *h = fp_test_host_new(200);
    fp_input *in = NULL;
    char err[512];
    assert_int_equal(create(h, path, "speed=4", &in, err, sizeof err), 0);
    int64_t t0 = fp_test_mono_ns();
    assert_int_equal(in->start(in, err, sizeof err), 0);
    assert_int_equal(fp_test_host_wait(h, 0, WAIT_LIMIT_NS), 0);
    double took = (double)(fp_test_mono_ns() - t0) * 1e-9;
    in->stop(in);
    in->destroy(in);
    print_message("speed=4 replay of a 0.4 s recording took %.3f s (expected 0.1 s; machine "
                  "may be loaded)\n", took);
    assert_true(took >= 0.05 && took <= 0.3);
    int64_t prev = 0;
    size_t n = 0;
    for (size_t e = 0; e < h->count; e++) {
        const fp_event *ev = &h->events[e];
        if (ev->header.type != FP_EVENT_JOINT_POSITIONS) continue;
        assert_true(ev->header.time_ns >= t0);
        /* Stamps on the recording's clock: 20 ms apart whatever the speed. */
        if (n++) assert_int_equal(ev->header.time_ns - prev, 20000000);
        prev = ev->header.time_ns;
    }
    assert_int_equal(n, 21);
    fp_test_host_free(h);
}

/* fast=1 on 500 rows 1 s apart (8 min recorded) ends at once, and a queue that refuses every
 * third push loses nothing. */
static void fast_never_drops(void **state)
{
    char path[512];
    tmp_path(path, sizeof path, "fast_joints.csv");
    write_joints_csv(path, 500, 1000000, "left");
    fp_test_host *h = fp_test_host_new(2000);
    h->refuse_every = 3;
    fp_input *in = NULL;
    char err[512];
    assert_int_equal(create(h, path, "fast=1", &in, err, sizeof err), 0);
    assert_int_equal(in->start(in, err, sizeof err), 0);
    assert_int_equal(fp_test_host_wait(h, 0, WAIT_LIMIT_NS), 0);
    in->stop(in);
    in->destroy(in);
    assert_true(h->refused > 300);
    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, FP_HAND_LEFT), 500);
    assert_int_equal(count_type(h, FP_EVENT_WRIST_POSE, FP_HAND_LEFT), 500);
    /* in order, row r's palm x is r, emulated times 1 s apart */
    size_t r = 0;
    int64_t first = 0;
    for (size_t e = 0; e < h->count; e++) {
        const fp_event *ev = &h->events[e];
        if (ev->header.type != FP_EVENT_JOINT_POSITIONS) continue;
        assert_true(ev->positions.mm[0][0] == (float)r);
        if (r == 0) first = ev->header.time_ns;
        assert_int_equal(ev->header.time_ns - first, (int64_t)r * 1000000000);
        r++;
    }
    fp_test_host_free(h);
}

/* Paced mode with a full queue: nothing is dropped (a full queue is retried), so that a run
 * on the recording's clock sees every sample. */
static void paced_drops_poses_not_status(void **state)
{
    char path[512];
    tmp_path(path, sizeof path, "paced_joints.csv");
    write_joints_csv(path, 10, 1000, "right"); /* 10 rows 1 ms apart */
    fp_test_host *h = fp_test_host_new(100);
    h->refuse_every = 2; /* connected goes in; then every second push is refused */
    fp_input *in = NULL;
    char err[512];
    assert_int_equal(create(h, path, NULL, &in, err, sizeof err), 0);
    assert_int_equal(in->start(in, err, sizeof err), 0);
    assert_int_equal(fp_test_host_wait(h, 0, WAIT_LIMIT_NS), 0);
    in->stop(in);
    in->destroy(in);
    assert_int_equal(h->events[0].status.code, FP_STATUS_CONNECTED);
    assert_int_equal(h->eos, 1);
    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, -1) +
                     count_type(h, FP_EVENT_WRIST_POSE, -1), 20); /* refused pushes retried */
    fp_test_host_free(h);
}

/* loop=1: the rows come again, times keep increasing by the loop period, no end of stream. */
static void loop_repeats_with_increasing_times(void **state)
{
    char path[512];
    tmp_path(path, sizeof path, "loop_joints.csv");
    write_joints_csv(path, 5, 10000, "right"); /* 40 ms long, 10 ms steps: period 50 ms */
    fp_test_host *h = fp_test_host_new(1 + 3 * 5 * 2);
    fp_input *in = NULL;
    char err[512];
    assert_int_equal(create(h, path, "loop=1,fast=1", &in, err, sizeof err), 0);
    assert_int_equal(in->start(in, err, sizeof err), 0);
    assert_int_equal(fp_test_host_wait(h, h->cap, WAIT_LIMIT_NS), 0);
    in->stop(in);
    in->destroy(in);
    assert_int_equal(h->eos, 0);
    const fp_event *pos[15];
    size_t n = 0;
    for (size_t e = 0; e < h->count && n < 15; e++)
        if (h->events[e].header.type == FP_EVENT_JOINT_POSITIONS) pos[n++] = &h->events[e];
    assert_int_equal(n, 15);
    for (size_t k = 0; k + 5 < n; k++) {
        assert_memory_equal(pos[k]->positions.mm, pos[k + 5]->positions.mm,
                            sizeof pos[k]->positions.mm);
        assert_int_equal(pos[k + 5]->header.time_ns - pos[k]->header.time_ns, 50000000);
    }
    for (size_t k = 1; k < n; k++) assert_true(pos[k]->header.time_ns > pos[k - 1]->header.time_ns);
    fp_test_host_free(h);
}

/* stop() wakes the thread out of a long wait at once, and nothing is pushed after it. */
static void stop_is_prompt(void **state)
{
    char path[512];
    tmp_path(path, sizeof path, "slow_joints.csv");
    write_joints_csv(path, 3, 100000000, "right"); /* rows 100 s apart */
    fp_test_host *h = fp_test_host_new(100);
    fp_input *in = NULL;
    char err[512];
    assert_int_equal(create(h, path, NULL, &in, err, sizeof err), 0);
    assert_int_equal(in->start(in, err, sizeof err), 0);
    assert_int_equal(fp_test_host_wait(h, 3, WAIT_LIMIT_NS), 0); /* connected, row 0's two events */
    usleep(20000);
    int64_t t0 = fp_test_mono_ns();
    in->stop(in);
    double took = (double)(fp_test_mono_ns() - t0) * 1e-9;
    print_message("stop() took %.6f s\n", took);
    assert_true(took < 1.0);
    size_t count = h->count;
    assert_int_equal(count, 3);
    /* start again after a stop: a fresh replay from the beginning */
    assert_int_equal(in->start(in, err, sizeof err), 0);
    assert_int_equal(in->start(in, err, sizeof err), -EBUSY);
    assert_int_equal(fp_test_host_wait(h, 6, WAIT_LIMIT_NS), 0);
    in->stop(in);
    in->destroy(in);
    assert_int_equal(h->count, 6);
    assert_true(h->events[4].positions.mm[0][0] == 0.0f);
    fp_test_host_free(h);
}

/* Creates and expects failure with a message starting "PATH:LINE:COL: reason". */
static void expect_create_error(const char *path, const char *keys, long line, long col,
                                const char *reason)
{
    fp_test_host *h = fp_test_host_new(4);
    fp_input *in = (fp_input *)1;
    char err[1024], want[1024];
    int rc = create(h, path, keys, &in, err, sizeof err);
    assert_true(rc < 0);
    if (line) assert_int_equal(rc, -EBADMSG); /* a malformed file; else a bad key: -EINVAL */
    assert_null(in);
    if (line)
        snprintf(want, sizeof want, "%s:%ld:%ld: %s", path, line, col, reason);
    else
        snprintf(want, sizeof want, "%s", reason);
    if (!strstr(err, want)) fail_msg("message \"%s\"\n   expected \"%s\"", err, want);
    assert_int_equal(h->count, 0);
    fp_test_host_free(h);
}

/* 1-based column of field i (0-based) of a CSV line. */
static long field_col(const char *line, int i)
{
    const char *p = line;
    for (int k = 0; k < i; k++) p = strchr(p, ',') + 1;
    return (long)(p - line) + 1;
}

/* Writes a copy of the synthetic CSV with line `line` (1-based) replaced by `text`. */
static void write_with_line(const char *src, const char *dst, int line, const char *text)
{
    FILE *in = fopen(src, "r"), *out = fopen(dst, "w");
    assert_non_null(in);
    assert_non_null(out);
    static char buf[16384];
    for (int n = 1; fgets(buf, sizeof buf, in); n++) {
        if (n == line)
            fprintf(out, "%s\n", text);
        else
            fputs(buf, out);
    }
    fclose(in);
    fclose(out);
}

static void get_line(const char *path, int line, char *buf, size_t len)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    for (int n = 1; n <= line; n++) assert_non_null(fgets(buf, (int)len, f));
    buf[strcspn(buf, "\n")] = '\0';
    fclose(f);
}

static void malformed_rows_fail_create(void **state)
{
    char good[512], bad[512], line[16384], mod[16384];
    tmp_path(good, sizeof good, "good_joints.csv");
    write_joints_csv(good, 6, 10000, "right");
    tmp_path(bad, sizeof bad, "bad_joints.csv");

    /* a bad number in line 3, column palm_y (field 5) */
    get_line(good, 3, line, sizeof line);
    long col = field_col(line, 5);
    snprintf(mod, sizeof mod, "%.*s1x0%s", (int)(col - 1), line, strchr(line + col - 1, ','));
    write_with_line(good, bad, 3, mod);
    expect_create_error(bad, NULL, 3, col, "bad number \"1x0\" in column palm_y");
    /* numbers are decimals: strtod's hexadecimal float was read as 8 */
    snprintf(mod, sizeof mod, "%.*s0x1p3%s", (int)(col - 1), line, strchr(line + col - 1, ','));
    write_with_line(good, bad, 3, mod);
    expect_create_error(bad, NULL, 3, col, "bad number \"0x1p3\" in column palm_y");
    snprintf(mod, sizeof mod, "%.*sinfinity%s", (int)(col - 1), line, strchr(line + col - 1, ','));
    write_with_line(good, bad, 3, mod);
    expect_create_error(bad, NULL, 3, col, "\"infinity\" in column palm_y is not a finite number");

    /* a row cut to 40 fields in line 4 */
    get_line(good, 4, line, sizeof line);
    col = field_col(line, 40);
    line[col - 2] = '\0'; /* drop the comma before field 40 and the rest */
    write_with_line(good, bad, 4, line);
    expect_create_error(bad, NULL, 4, (long)strlen(line) + 1,
                        "expected 73 fields, found 40 (row too short)");

    /* an unknown hand_type in line 2 */
    get_line(good, 2, line, sizeof line);
    col = field_col(line, 3);
    snprintf(mod, sizeof mod, "%.*smiddle%s", (int)(col - 1), line, strchr(line + col - 1, ','));
    write_with_line(good, bad, 2, mod);
    expect_create_error(bad, NULL, 2, col, "unknown hand_type \"middle\"");

    /* an empty position field (not allowed in the joints CSV) in line 7, last column */
    get_line(good, 7, line, sizeof line);
    line[strlen(line) - strlen(strrchr(line, ',')) + 1] = '\0';
    write_with_line(good, bad, 7, line);
    expect_create_error(bad, NULL, 7, (long)strlen(line) + 1, "empty field in column pinky_tip_z");

    /* a timestamp going backwards in line 5 */
    get_line(good, 5, line, sizeof line);
    col = field_col(line, 1);
    snprintf(mod, sizeof mod, "4,5,%s", strchr(strchr(line, ',') + 1, ',') + 1);
    write_with_line(good, bad, 5, mod);
    expect_create_error(bad, NULL, 5, col, "timestamp_us 5 goes backwards");

    /* the angles CSV: a bad number in line 2, column index_mcp (field 8) */
    char angles[512];
    tmp_path(angles, sizeof angles, "bad_angles.csv");
    FILE *f = fopen(angles, "w");
    assert_non_null(f);
    fputs(read_header(LEAP "grab_cyberglove_like_angles_deg.csv"), f);
    /* thumb_rotation empty, 18 numbers with "4..5" as sensor 4, three empty */
    snprintf(line, sizeof line, "0,100,1,left,");
    for (int s = 0; s < FP_GLOVE_SENSORS; s++) {
        size_t n = strlen(line);
        if (s == 0 || s >= 19)
            snprintf(line + n, sizeof line - n, "%s", s < 21 ? "," : "");
        else if (s == FP_SENSOR_INDEX_MPJ)
            snprintf(line + n, sizeof line - n, "4..5,");
        else
            snprintf(line + n, sizeof line - n, "%d%s", s, s < 21 ? "," : "");
    }
    fprintf(f, "%s\n", line);
    fclose(f);
    expect_create_error(angles, NULL, 2, field_col(line, 4 + FP_SENSOR_INDEX_MPJ),
                        "bad number \"4..5\" in column index_mcp");
    /* the same with a hexadecimal angle ("0x10", read as 16 before) */
    f = fopen(angles, "w");
    assert_non_null(f);
    fputs(read_header(LEAP "grab_cyberglove_like_angles_deg.csv"), f);
    char *dots = strstr(line, "4..5");
    fprintf(f, "%.*s0x10%s\n", (int)(dots - line), line, dots + 4);
    fclose(f);
    expect_create_error(angles, NULL, 2, field_col(line, 4 + FP_SENSOR_INDEX_MPJ),
                        "bad number \"0x10\" in column index_mcp");

    /* a joints header with one column too many (74 of 73): the error names the extra
     * column (this once read past a 73-field array and printed a stack address) */
    const char *hdr = read_header(LEAP "grab_joints_mm.csv");
    size_t hlen = strcspn(hdr, "\r\n");
    f = fopen(bad, "w");
    assert_non_null(f);
    fprintf(f, "%.*s,extra\n", (int)hlen, hdr);
    get_line(good, 2, line, sizeof line);
    fprintf(f, "%s\n", line);
    fclose(f);
    snprintf(mod, sizeof mod, "header has 74 columns, expected 73");
    expect_create_error(bad, NULL, 1, (long)hlen + 2, mod);

    /* a joints header with palm_x and palm_y swapped: named at the column (before: "header
     * has 73 columns, expected 26", the angles CSV's count) */
    const char *px = strstr(hdr, "palm_x,palm_y,");
    assert_non_null(px);
    f = fopen(bad, "w");
    assert_non_null(f);
    fprintf(f, "%.*spalm_y,palm_x,%.*s\n", (int)(px - hdr), hdr, (int)(hlen - (size_t)(px - hdr) - 14), px + 14);
    fprintf(f, "%s\n", line);
    fclose(f);
    expect_create_error(bad, NULL, 1, (long)(px - hdr) + 1, "header column 5 is \"palm_y\", expected \"palm_x\"");

    /* a file in no known format, a missing file */
    tmp_path(bad, sizeof bad, "unknown.txt");
    f = fopen(bad, "w");
    fputs("hello\n", f);
    fclose(f);
    expect_create_error(bad, NULL, 1, 1, "unknown format");
    tmp_path(bad, sizeof bad, "does-not-exist.csv");
    snprintf(mod, sizeof mod, "%s: cannot open", bad);
    expect_create_error(bad, NULL, 0, 0, mod);
}

/* A last line cut mid-row ends the replay at the row before, with a warning naming the line. */
static void truncated_file_replays_to_last_full_row(void **state)
{
    const char *src = LEAP "three-claps_joints_mm.csv";
    char cut[512];
    tmp_path(cut, sizeof cut, "cut_joints.csv");
    FILE *in = fopen(src, "r"), *out = fopen(cut, "w");
    assert_non_null(in);
    assert_non_null(out);
    static char buf[16384];
    for (int n = 1; n <= 101 && fgets(buf, sizeof buf, in); n++) {
        if (n == 101)
            fwrite(buf, 1, 50, out); /* line 101 cut after 50 bytes, no newline */
        else
            fputs(buf, out);
    }
    fclose(in);
    fclose(out);
    fp_test_host *h = replay_all(cut, "fast=1", 1000);
    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, -1), 99); /* lines 2..100 */
    const fp_event *warn = &h->events[h->count - 2], *eos = &h->events[h->count - 1];
    assert_int_equal(warn->header.type, FP_EVENT_STATUS);
    assert_int_equal(warn->status.code, FP_STATUS_ERROR);
    assert_non_null(strstr(warn->status.text, "cut_joints.csv:101:"));
    assert_int_equal(eos->status.code, FP_STATUS_END_OF_STREAM);
    assert_non_null(strstr(h->log, "cut_joints.csv:101:"));
    fp_test_host_free(h);
}

/* Lines 1..101 of three-claps, the last without its newline: whole (the file simply ends
 * without one, as many writers leave it: replayed, no warning) or cut inside its last number
 * ("-42.37" of "-42.3741": it parses, but with fewer decimals than the row before: dropped,
 * said). Before, a whole last row without a newline was dropped as cut off. */
static void write_unterminated(const char *path, size_t cut_last)
{
    FILE *in = fopen(LEAP "three-claps_joints_mm.csv", "r"), *out = fopen(path, "w");
    assert_non_null(in);
    assert_non_null(out);
    static char buf[16384];
    for (int n = 1; n <= 101 && fgets(buf, sizeof buf, in); n++) {
        size_t len = strlen(buf);
        if (n == 101) {
            assert_true(len > cut_last + 1 && buf[len - 1] == '\n');
            fwrite(buf, 1, len - 1 - cut_last, out); /* no newline, cut_last bytes less */
        } else {
            fputs(buf, out);
        }
    }
    fclose(in);
    fclose(out);
}

static void unterminated_last_row(void **state)
{
    (void)state;
    char path[512];
    tmp_path(path, sizeof path, "unterminated_joints.csv");
    write_unterminated(path, 0);
    fp_test_host *h = replay_all(path, "fast=1", 1000);
    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, -1), 100); /* lines 2..101 */
    assert_null(strstr(h->log, "unterminated_joints.csv:101:"));
    assert_int_equal(h->events[h->count - 1].status.code, FP_STATUS_END_OF_STREAM);
    assert_int_equal(h->events[h->count - 2].header.type, FP_EVENT_WRIST_POSE);
    fp_test_host_free(h);
    write_unterminated(path, 2); /* the last number without its last two decimals */
    h = replay_all(path, "fast=1", 1000);
    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, -1), 99);
    assert_non_null(strstr(h->log, "unterminated_joints.csv:101: last line cut short"));
    fp_test_host_free(h);
}

/* A row at its hand's previous row's time (a sample sent twice) replays, with a warning
 * naming the first such line; a recording whose every row has one time spans no time and is
 * refused as bad data (before: its 374 rows played as one frame without a word). */
static void repeated_times(void **state)
{
    (void)state;
    const char *good = LEAP "grab_joints_mm.csv";
    char once[512], same[512], line[16384], prev[16384], mod[16384];
    tmp_path(once, sizeof once, "repeat_once.csv");
    tmp_path(same, sizeof same, "repeat_all.csv");
    get_line(good, 51, prev, sizeof prev); /* lines 51 and 52: the right hand's */
    get_line(good, 52, line, sizeof line);
    assert_non_null(strstr(prev, ",right,"));
    assert_non_null(strstr(line, ",right,"));
    long c1 = field_col(line, 1), c2 = field_col(line, 2), p1 = field_col(prev, 1), p2 = field_col(prev, 2);
    snprintf(mod, sizeof mod, "%.*s%.*s%s", (int)(c1 - 1), line, (int)(p2 - p1), prev + p1 - 1, line + c2 - 1);
    write_with_line(good, once, 52, mod);
    fp_test_host *h = replay_all(once, "fast=1", 2000);
    assert_int_equal(count_type(h, FP_EVENT_JOINT_POSITIONS, -1), 374); /* both kept */
    assert_non_null(strstr(h->log, "1 row repeats the time of the hand's row before (the first: line 52)"));
    fp_test_host_free(h);

    FILE *in = fopen(good, "r"), *out = fopen(same, "w");
    assert_non_null(in);
    assert_non_null(out);
    char ts[64] = "";
    for (int n = 1; fgets(line, sizeof line, in); n++) {
        if (n == 1) {
            fputs(line, out);
            continue;
        }
        long a = field_col(line, 1), b = field_col(line, 2);
        if (!ts[0]) snprintf(ts, sizeof ts, "%.*s", (int)(b - a), line + a - 1);
        fprintf(out, "%.*s%s%s", (int)(a - 1), line, ts, line + b - 1);
    }
    fclose(in);
    fclose(out);
    h = fp_test_host_new(4);
    fp_input *inp = NULL;
    char err[1024];
    assert_int_equal(create(h, same, NULL, &inp, err, sizeof err), -EBADMSG);
    assert_null(inp);
    if (!strstr(err, "every row has the same time") || !strstr(err, "374 rows would play as one"))
        fail_msg("message \"%s\"", err);
    fp_test_host_free(h);
}

static void spec_errors(void **state)
{
    const char *file = LEAP "grab_joints_mm.csv";
    expect_create_error(file, "sped=2", 0, 0, "unknown key \"sped\"");
    expect_create_error(file, "speed=0", 0, 0, "speed=0: expected a number from 0.001 to 1e6");
    expect_create_error(file, "speed=1e-9", 0, 0, "speed=1e-9: expected a number from 0.001 to 1e6"); /* (a century) */
    expect_create_error(file, "speed=abc", 0, 0, "speed=abc");
    expect_create_error(file, "speed=nan", 0, 0, "speed=nan");
    expect_create_error(file, "loop=2", 0, 0, "loop=2: expected 0 or 1");
    expect_create_error(file, "fast=maybe", 0, 0, "fast=maybe: expected 0 or 1"); /* (yes, on: accepted, as every plugin's on/off keys) */
    expect_create_error(file, "hands=middle", 0, 0, "hands=middle: expected left, right or both");
    expect_create_error(file, "timeout=0.001", 0, 0, "timeout=0.001: expected 0 (never) or seconds from 0.01 to 3600");
    expect_create_error(file, "timeout=-1", 0, 0, "timeout=-1: expected 0 (never)");
    expect_create_error(file, "timeout=0x10", 0, 0, "timeout=0x10: expected 0 (never)");
    expect_create_error(file, "timeout=inf", 0, 0, "timeout=inf: expected 0 (never)");
    fp_test_host *h = fp_test_host_new(4);
    fp_input *in = NULL;
    char err[512];
    assert_int_equal(factory->create(&h->host, NULL, NULL, 0, &in, err, sizeof err), -EINVAL);
    assert_non_null(strstr(err, "no FILE given"));
    fp_test_host_free(h);
}

/* An event log written with fp_eventlog replays event for event, spacing kept. */
static void eventlog_replays_as_recorded(void **state)
{
    char path[512], err[512];
    tmp_path(path, sizeof path, "take.fplog");
    fp_eventlog_writer *w = fp_eventlog_writer_open(path, err, sizeof err);
    assert_non_null(w);
    fp_event ev[6];
    memset(ev, 0, sizeof ev);
    for (int i = 0; i < 6; i++) {
        ev[i].header.time_ns = 5000000000LL + i * 2000000LL; /* 2 ms apart */
        ev[i].header.hand = i % 2;
    }
    ev[0].header.type = FP_EVENT_JOINT_ANGLES, ev[0].header.size = sizeof ev[0].angles;
    ev[0].angles.valid = 0x3;
    ev[0].angles.radians[0] = 0.25f, ev[0].angles.radians[1] = -1.5f;
    ev[1].header.type = FP_EVENT_JOINT_POSITIONS, ev[1].header.size = sizeof ev[1].positions;
    for (int j = 0; j < FP_HAND_JOINTS; j++) ev[1].positions.mm[j][1] = 100.125f + (float)j;
    ev[2].header.type = FP_EVENT_WRIST_POSE, ev[2].header.size = sizeof ev[2].wrist;
    ev[2].wrist.rotation[0] = 1, ev[2].wrist.position_mm[2] = -3;
    ev[3].header.type = FP_EVENT_BUTTON, ev[3].header.size = sizeof ev[3].button;
    ev[3].header.hand = -1, ev[3].button = (fp_event_button){ev[3].header, 1, 1, 1};
    ev[4].header.type = FP_EVENT_STATUS, ev[4].header.size = sizeof ev[4].status;
    ev[4].header.hand = -1, ev[4].status.code = FP_STATUS_WARNING;
    strcpy(ev[4].status.text, "glove \"left\" resynced");
    ev[5].header.type = FP_EVENT_JOINT_POSITIONS, ev[5].header.size = sizeof ev[5].positions;
    for (int i = 0; i < 6; i++) assert_int_equal(fp_eventlog_writer_write(w, &ev[i]), 0);
    assert_int_equal(fp_eventlog_writer_close(&w, err, sizeof err), 0);

    fp_test_host *h = replay_all(path, "fast=1", 64);
    assert_int_equal(h->count, 8); /* connected, 6, end of stream */
    for (int i = 0; i < 6; i++) {
        fp_event got = h->events[1 + i], want = ev[i];
        assert_int_equal(got.header.time_ns - h->events[1].header.time_ns, i * 2000000LL);
        got.header.time_ns = want.header.time_ns = 0;
        if (memcmp(&got, &want, sizeof got) != 0) fail_msg("event %d differs", i);
    }
    fp_test_host_free(h);

    /* hands=right keeps the right hand's and the handless events */
    h = replay_all(path, "fast=1,hands=right", 64);
    assert_int_equal(h->count, 2 + 4); /* connected, 4, end of stream */
    assert_int_equal(count_type(h, FP_EVENT_JOINT_ANGLES, -1), 0);
    assert_int_equal(count_type(h, FP_EVENT_BUTTON, -1), 1);
    fp_test_host_free(h);

    /* an event-log syntax error fails create with the reader's FILE:LINE:COLUMN */
    FILE *f = fopen(path, "a");
    fputs("5000000099 wrist right 1 2 3 4 5 6\n", f);
    fclose(f);
    expect_create_error(path, NULL, 8, 35, "line ends where a quaternion component was expected");
}

/* Event logs that are bad data give bad-data codes (exit 65), each naming the file and line:
 * another version -ENOTSUP, time going back -EBADMSG, a header with no events -EBADMSG; a
 * hands= choice that leaves nothing stays the option's fault (-EINVAL, as for a CSV). */
static void eventlog_bad_data_codes(void **state)
{
    (void)state;
    static const struct { const char *name, *text; int code; const char *want; } cases[] = {
        {"v2.log", "# facepuppet-eventlog 2\n", -ENOTSUP, "v2.log:1:23: unsupported event-log version"},
        {"back.log",
         "# facepuppet-eventlog 1\n"
         "2000 button - 1 1 1\n"
         "1000 button - 1 0 0\n",
         -EBADMSG, "back.log:3:1: time 1000 goes backwards"},
        {"empty.log", "# facepuppet-eventlog 1\n", -EBADMSG, "the recording holds no events"},
        {"none.log", "# facepuppet-eventlog 1\n2000 wrist left 1 2 3 1 0 0 0\n", -EINVAL,
         "no events to replay (hands=right)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[600];
        snprintf(path, sizeof path, "%s/%s", tmpdir, cases[i].name);
        fp_test_write_file(path, cases[i].text);
        fp_test_host *h = fp_test_host_new(4);
        fp_input *in = NULL;
        char err[1024];
        int rc = create(h, path, i == 3 ? "hands=right" : NULL, &in, err, sizeof err);
        if (rc != cases[i].code || !strstr(err, cases[i].want))
            fail_msg("%s: %d \"%s\", expected %d \"%s\"", cases[i].name, rc, err, cases[i].code,
                     cases[i].want);
        assert_null(in);
        fp_test_host_free(h);
        unlink(path);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(factory_describes_itself),
        cmocka_unit_test(frame_counts_match_csv_rows),
        cmocka_unit_test(positions_and_wrist_equal_csv),
        cmocka_unit_test(leap_original_replays_as_its_csv),
        cmocka_unit_test(angles_in_radians_empty_invalid),
        cmocka_unit_test(hands_filter),
        cmocka_unit_test(lost_hand_reported),
        cmocka_unit_test(pacing_follows_speed),
        cmocka_unit_test(fast_never_drops),
        cmocka_unit_test(paced_drops_poses_not_status),
        cmocka_unit_test(loop_repeats_with_increasing_times),
        cmocka_unit_test(stop_is_prompt),
        cmocka_unit_test(joints_given_in_advance),
        cmocka_unit_test(malformed_rows_fail_create),
        cmocka_unit_test(truncated_file_replays_to_last_full_row),
        cmocka_unit_test(unterminated_last_row),
        cmocka_unit_test(repeated_times),
        cmocka_unit_test(spec_errors),
        cmocka_unit_test(eventlog_replays_as_recorded),
        cmocka_unit_test(eventlog_bad_data_codes),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
