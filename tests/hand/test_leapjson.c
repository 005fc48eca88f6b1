/*
 * test_leapjson: the Leap playback originals' reader (core/hand/leapjson.h).
 *  - LZ-string: vectors made by the reference implementation (npm lz-string 1.5.0,
 *    compressToBase64) decode to their texts, UTF-16 surrogate pairs included; a character
 *    outside the alphabet, a cut stream, a bad code and a bomb past the limit are refused.
 *  - The four originals in shared/data give the rows of their CSV conversions (made by others
 *    from the same files): the same frames, times, hands, and every value within the CSV's
 *    rounding to 4 decimals.
 *  - Format 2: each original packed as leapjs-playback 0.2 saves it (recording.js packArray,
 *    its packing structure, no finger "type") reads as the original, row for row, bit for bit.
 *  - Hostile recordings get -EBADMSG and a message naming the file and the JSON path.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cJSON.h>
#include <cmocka.h>

#include "fp_test_support.h"
#include "leapcsv.h"
#include "leapjson.h"

/* compressToBase64(text) from lz-string 1.5.0 (node), and the text as UTF-8 */
static const struct {
    const char *packed, *text;
} vectors[] = {
    {"Q===", ""},
    {"IZA=", "a"},
    {"IY18ZVUA", "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"},
    {"BIUwNmD2A0AEDukBOYAmBCIA", "Hello, world!"},
    {"N4IgZgTghgtgpgZxALgNoF0A0J4BcoAmU+KouAlrgDZwogDGUYAlwASBcZK4LwbgsjsgC+/IA===",
     "{\"frames\":[],\"metadata\":{\"title\":\"caf\xC3\xA9 \xE2\x98\xBA \xF0\x9F\x91\x8D\"}}"},
    {"IYI17SIgCAVA8gIQKIIEoDkF0ajeaWOQA===", "abababababababababab TOBEORNOTTOBEORTOBEORNOT"},
};

static void lzstring_vectors(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof vectors / sizeof vectors[0]; i++) {
        char *out = NULL, why[160];
        size_t n = 99;
        int rc = fp_lzstring_decode_base64(vectors[i].packed, strlen(vectors[i].packed), 1 << 20, &out, &n,
                                           why, sizeof why);
        if (rc) fprintf(stderr, "vector %zu: %s\n", i, why);
        assert_int_equal(rc, 0);
        assert_int_equal(n, strlen(vectors[i].text));
        assert_string_equal(out, vectors[i].text);
        free(out);
        /* a newline at the end (a file's) changes nothing */
        char nl[256];
        snprintf(nl, sizeof nl, "%s\r\n", vectors[i].packed);
        assert_int_equal(fp_lzstring_decode_base64(nl, strlen(nl), 1 << 20, &out, &n, why, sizeof why), 0);
        assert_string_equal(out, vectors[i].text);
        free(out);
    }
}

static void lzstring_refusals(void **state)
{
    (void)state;
    char *out = (char *)1, why[160];
    size_t n;
    const char *hello = "BIUwNmD2A0AEDukBOYAmBCIA";
    /* a character outside the alphabet, named by its byte */
    const char *bad = "BIUwNmD2A0!EDukBOYAmBCIA";
    assert_int_equal(fp_lzstring_decode_base64(bad, 24, 1 << 20, &out, &n, why, sizeof why), -EBADMSG);
    assert_null(out);
    assert_non_null(strstr(why, "not base64 at byte 10"));
    /* cut short: the end mark never comes */
    for (size_t k = 1; k < 20; k++) {
        int rc = fp_lzstring_decode_base64(hello, k, 1 << 20, &out, &n, why, sizeof why);
        assert_int_equal(rc, -EBADMSG);
        assert_null(out);
    }
    assert_int_equal(fp_lzstring_decode_base64(hello, 12, 1 << 20, &out, &n, why, sizeof why), -EBADMSG);
    assert_non_null(strstr(why, "ends before its end mark"));
    /* a code past the dictionary (the reference's decompressFromBase64 gives null) */
    assert_int_equal(fp_lzstring_decode_base64("B//", 3, 1 << 20, &out, &n, why, sizeof why), -EBADMSG);
    assert_non_null(strstr(why, "bad code"));
    /* past the limit: 44 characters from 8, refused at 10 */
    assert_int_equal(fp_lzstring_decode_base64("IY18ZVUA", 8, 10, &out, &n, why, sizeof why), -EFBIG);
    assert_null(out);
    assert_non_null(strstr(why, "more than 10 bytes"));
    assert_int_equal(fp_lzstring_decode_base64("", 0, 10, &out, &n, why, sizeof why), -EBADMSG);
    assert_int_equal(fp_lzstring_decode_base64(NULL, 0, 10, &out, &n, why, sizeof why), -EINVAL);
}

/* rows collected */
typedef struct rows {
    fp_leapcsv_row *r;
    size_t n, cap;
} rows;

static int collect(void *user, const fp_leapcsv_row *row, char *err, size_t errlen)
{
    (void)err, (void)errlen;
    rows *R = user;
    if (R->n == R->cap) {
        R->cap = R->cap ? 2 * R->cap : 256;
        R->r = realloc(R->r, R->cap * sizeof *R->r);
        assert_non_null(R->r);
    }
    R->r[R->n++] = *row;
    return 0;
}

static void originals_equal_their_csv(void **state)
{
    (void)state;
    static const char *const recs[] = {"grab", "HandSplay-110fps", "Waiting-110fps", "three-claps"};
    for (size_t k = 0; k < sizeof recs / sizeof recs[0]; k++) {
        char jp[4200], cp[4200], err[512];
        snprintf(jp, sizeof jp, "%s/hands/leap-motion/%s.json.lz", fp_test_data_dir(), recs[k]);
        snprintf(cp, sizeof cp, "%s/hands/leap-motion/%s_joints_mm.csv", fp_test_data_dir(), recs[k]);
        rows J = {0}, C = {0};
        int rc = fp_leapjson_read(jp, collect, &J, err, sizeof err);
        if (rc) fprintf(stderr, "%s\n", err);
        assert_int_equal(rc, 0);
        assert_int_equal(fp_leapcsv_read(cp, FP_LEAPCSV_JOINTS, NULL, collect, &C, NULL, err, sizeof err), 0);
        printf("%-18s %zu rows from the original, %zu in the CSV", recs[k], J.n, C.n);
        assert_int_equal(J.n, C.n);
        double worst = 0;
        for (size_t i = 0; i < J.n; i++) {
            assert_int_equal(J.r[i].frame, C.r[i].frame);
            assert_int_equal(J.r[i].timestamp_us, C.r[i].timestamp_us);
            assert_int_equal(J.r[i].hand_id, C.r[i].hand_id);
            assert_int_equal(J.r[i].side, C.r[i].side);
            assert_int_equal(J.r[i].format, FP_LEAPCSV_JOINTS);
            assert_int_equal(J.r[i].nvalues, FP_LEAPCSV_JOINT_VALUES);
            assert_int_equal(J.r[i].valid, C.r[i].valid);
            for (int v = 0; v < FP_LEAPCSV_JOINT_VALUES; v++) {
                double d = fabs(J.r[i].value[v] - C.r[i].value[v]);
                worst = d > worst ? d : worst;
                assert_true(d <= 0.5e-4 + 1e-9 * fabs(C.r[i].value[v])); /* the CSV's 4 decimals */
                assert_true(J.r[i].valuef[v] == (float)J.r[i].value[v]);
            }
        }
        printf(", largest difference %.2g mm\n", worst);
        assert_true(worst > 0); /* the original is finer than its CSV: this read it, not the CSV */
        free(J.r);
        free(C.r);
    }
}

/* text written to path and read: refused with -EBADMSG, the message naming the file and
 * holding want (printed after label) */
static void refused(const char *path, const char *text, const char *label, const char *want)
{
    char err[512];
    fp_test_write_file(path, text);
    rows R = {0};
    int rc = fp_leapjson_read(path, collect, &R, err, sizeof err);
    printf("%-10s -> %s\n", label, err);
    assert_int_equal(rc, -EBADMSG);
    assert_non_null(strstr(err, path));
    assert_non_null(strstr(err, want));
    free(R.r);
}

/* recording.js (leapjs-playback 0.2) packArray: data's values in st's order (a name: its
 * value, null when absent; a nested array: each of data's items packed by it; {key: st2}:
 * data[key] packed by st2) */
static cJSON *pack(const cJSON *st, const cJSON *data)
{
    cJSON *out = cJSON_CreateArray();
    for (const cJSON *s = st->child; s; s = s->next) {
        if (cJSON_IsString(s)) {
            const cJSON *v = cJSON_GetObjectItemCaseSensitive(data, s->valuestring);
            cJSON_AddItemToArray(out, v ? cJSON_Duplicate(v, true) : cJSON_CreateNull());
        } else if (cJSON_IsArray(s)) {
            for (const cJSON *e = data ? data->child : NULL; e; e = e->next) cJSON_AddItemToArray(out, pack(s, e));
        } else {
            cJSON_AddItemToArray(out, pack(s->child, cJSON_GetObjectItemCaseSensitive(data, s->child->string)));
        }
    }
    return out;
}

/* leapjs-playback 0.2's packing structure (recording.js), as its format 2 files hold it:
 * the pointables without "type" */
static const char packing[] =
    "[\"id\",\"timestamp\",{\"hands\":[[\"id\",\"type\",\"direction\",\"palmNormal\",\"palmPosition\","
    "\"palmVelocity\",\"stabilizedPalmPosition\",\"pinchStrength\",\"grabStrength\",\"confidence\"]]},"
    "{\"pointables\":[[\"id\",\"direction\",\"handId\",\"length\",\"stabilizedTipPosition\",\"tipPosition\","
    "\"tipVelocity\",\"tool\",\"carpPosition\",\"mcpPosition\",\"pipPosition\",\"dipPosition\","
    "\"btipPosition\",\"bases\"]]},{\"interactionBox\":[\"center\",\"size\"]}]";

static void format2_reads_as_the_original(void **state)
{
    (void)state;
    char dir[] = "/tmp/fp_leapjson2XXXXXX";
    assert_non_null(mkdtemp(dir));
    static const char *const recs[] = {"grab", "three-claps"};
    for (size_t k = 0; k < sizeof recs / sizeof recs[0]; k++) {
        char jp[4200], pp[256], err[512];
        snprintf(jp, sizeof jp, "%s/hands/leap-motion/%s.json.lz", fp_test_data_dir(), recs[k]);
        snprintf(pp, sizeof pp, "%s/%s-packed.json", dir, recs[k]);
        /* the original's text, packed */
        char *raw = NULL, *text = NULL, why[160];
        size_t n = 0, tn = 0;
        FILE *f = fopen(jp, "rb");
        assert_non_null(f);
        raw = malloc(1 << 22);
        n = fread(raw, 1, 1 << 22, f);
        fclose(f);
        assert_int_equal(fp_lzstring_decode_base64(raw, n, FP_LEAPJSON_MAX_TEXT, &text, &tn, why, sizeof why), 0);
        free(raw);
        cJSON *orig = cJSON_Parse(text), *st = cJSON_Parse(packing);
        free(text);
        assert_non_null(orig);
        assert_non_null(st);
        cJSON *out = cJSON_CreateObject(), *frames = cJSON_AddArrayToObject(out, "frames");
        cJSON_AddItemToObject(out, "metadata", cJSON_Parse("{\"formatVersion\":2,\"generatedBy\":\"LeapJS Playback 0.2.0\"}"));
        cJSON_AddItemToArray(frames, cJSON_Duplicate(st, true));
        size_t nf = 0;
        for (const cJSON *fr = cJSON_GetObjectItemCaseSensitive(orig, "frames")->child; fr; fr = fr->next, nf++)
            cJSON_AddItemToArray(frames, pack(st, fr));
        char *packed = cJSON_PrintUnformatted(out);
        fp_test_write_file(pp, packed);
        free(packed);
        cJSON_Delete(out);
        cJSON_Delete(orig);
        cJSON_Delete(st);
        rows J = {0}, P = {0};
        assert_int_equal(fp_leapjson_read(jp, collect, &J, err, sizeof err), 0);
        int rc = fp_leapjson_read(pp, collect, &P, err, sizeof err);
        if (rc) fprintf(stderr, "%s\n", err);
        assert_int_equal(rc, 0);
        printf("%-12s %zu frames packed (format 2): %zu rows, the original %zu\n", recs[k], nf, P.n, J.n);
        assert_int_equal(P.n, J.n);
        assert_true(J.n > 300);
        for (size_t i = 0; i < J.n; i++) {
            assert_int_equal(P.r[i].frame, J.r[i].frame);
            assert_int_equal(P.r[i].timestamp_us, J.r[i].timestamp_us);
            assert_int_equal(P.r[i].hand_id, J.r[i].hand_id);
            assert_int_equal(P.r[i].side, J.r[i].side);
            assert_memory_equal(P.r[i].value, J.r[i].value, sizeof J.r[i].value);
        }
        free(J.r);
        free(P.r);
        unlink(pp);
    }
    /* hostile packed files: the code and what the message names */
    struct {
        const char *text, *want;
    } cases[] = {
        {"{\"metadata\":{\"formatVersion\":2},\"frames\":[{\"id\":1}]}", "frames[0]: expected an array of names"},
        {"{\"metadata\":{\"formatVersion\":2},\"frames\":[[\"timestamp\"],{\"timestamp\":1}]}",
         "frames[1]: expected an array (a packed frame"},
        {"{\"metadata\":{\"formatVersion\":2},\"frames\":[[\"timestamp\",7],[1]]}", "frames[0]: expected names"},
        {"{\"metadata\":{\"formatVersion\":2},\"frames\":[[\"timestamp\",{\"hands\":[[\"id\"]]}],[1,7]]}",
         "frames[1].hands: expected an array (a packed frame"},
        {"{\"frames\":[[\"timestamp\"],[1]]}", "frames[0]: a packed frame, but metadata.formatVersion is not 2"},
        {"{\"frames\":[{\"timestamp\":1,\"hands\":[{\"id\":7,\"type\":\"right\",\"palmPosition\":[1,2,3],"
         "\"palmNormal\":[0,-1,0],\"direction\":[0,0,-1]}],\"pointables\":[{\"handId\":7,\"id\":99}]}]}",
         "frames[0].pointables[0]: no type, and its id 99 is not 10 x its hand's id 7 + 0 (thumb) to 4"},
    };
    char path[256];
    snprintf(path, sizeof path, "%s/bad.json", dir);
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        char label[32];
        snprintf(label, sizeof label, "packed %zu", c);
        refused(path, cases[c].text, label, cases[c].want);
    }
    unlink(path);
    rmdir(dir);
}

/* A frame of one right hand (id 7) at time ts: five fingers and a tool */
static void frame_text(char *b, size_t n, long long ts, const char *hand_extra, int skip_finger)
{
    size_t k = (size_t)snprintf(b, n, "{\"timestamp\":%lld,\"hands\":[{\"id\":7,\"type\":\"right\","
                                "\"palmPosition\":[1,200,3],\"palmNormal\":[0,-1,0],\"direction\":[0,0,-1]%s}],"
                                "\"pointables\":[{\"tool\":true,\"handId\":7,\"type\":1}",
                                ts, hand_extra);
    for (int f = 0; f < 5; f++) {
        if (f == skip_finger) continue;
        k += (size_t)snprintf(b + k, n - k,
                              ",{\"handId\":7,\"type\":%d,\"mcpPosition\":[%d,201,0],\"pipPosition\":[%d,202,-10],"
                              "\"dipPosition\":[%d,203,-20],\"tipPosition\":[%d,204,-30]}",
                              f, 10 * f, 10 * f, 10 * f, 10 * f);
    }
    snprintf(b + k, n - k, "]}");
}

static void plain_json_and_hostile_files(void **state)
{
    (void)state;
    char dir[] = "/tmp/fp_leapjsonXXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[256], text[8192], f0[2048], f1[2048], err[512];
    snprintf(path, sizeof path, "%s/rec.json", dir);
    /* plain JSON (a BOM and blanks first): two frames, one hand, the tool passed over */
    frame_text(f0, sizeof f0, 1000, "", -1);
    frame_text(f1, sizeof f1, 1500, "", -1);
    snprintf(text, sizeof text, "\xEF\xBB\xBF \n{\"metadata\":{\"formatVersion\":1},\"frames\":[%s,%s]}",
             f0, f1);
    fp_test_write_file(path, text);
    rows R = {0};
    assert_int_equal(fp_leapjson_read(path, collect, &R, err, sizeof err), 0);
    assert_int_equal(R.n, 2);
    assert_int_equal(R.r[1].frame, 1);
    assert_int_equal(R.r[1].timestamp_us, 1500);
    assert_int_equal(R.r[1].hand_id, 7);
    assert_int_equal(R.r[1].side, FP_HAND_RIGHT);
    assert_true(R.r[1].value[1] == 200);                  /* palm y */
    assert_true(R.r[1].value[9 + 3 * (4 * 3 + 3)] == 30); /* ring tip x */
    assert_true(R.r[1].value[9 + 3 * (4 * 4 + 2) + 2] == -20); /* pinky dip z */
    free(R.r);
    R = (rows){0};

    /* each hostile file: the code and what the message must name */
    struct {
        const char *why, *want;
    } cases[] = {
        {"no frames", "frames: expected an array"},
        {"backwards", "frames[1].timestamp: 900 goes backwards"},
        {"no ring", "frames[0].hands[0]: hand 7 has no ring"},
        {"far palm", "frames[0].hands[0].palmPosition[1]: 20000 is beyond 10 m"},
        {"bad type", "frames[0].hands[0].type: expected \"left\" or \"right\""},
        {"packed", "frames[0]: a packed frame, but metadata.formatVersion is not 2"},
        {"not json", "not valid JSON near line 2"},
        /* two recordings pasted into one file: the second was ignored in silence */
        {"after", "text after the JSON object, at line 2"},
        {"fraction", "frames[0].timestamp: expected an integer"},
        {"not base64", "not a Leap playback recording (JSON, or LZ-string base64 as *.json.lz): "
                       "not base64 at byte 10"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const char *w = cases[c].why;
        if (!strcmp(w, "no frames")) snprintf(text, sizeof text, "{\"metadata\":{}}");
        if (!strcmp(w, "backwards")) {
            frame_text(f1, sizeof f1, 900, "", -1);
            snprintf(text, sizeof text, "{\"frames\":[%s,%s]}", f0, f1);
        }
        if (!strcmp(w, "no ring")) {
            frame_text(f1, sizeof f1, 1000, "", 3);
            snprintf(text, sizeof text, "{\"frames\":[%s]}", f1);
        }
        if (!strcmp(w, "far palm")) {
            frame_text(f1, sizeof f1, 1000, "", -1);
            char *p = strstr(f1, "[1,200,3]");
            memcpy(p, "[1,2e4,3]", 9);
            snprintf(text, sizeof text, "{\"frames\":[%s]}", f1);
        }
        if (!strcmp(w, "bad type")) {
            frame_text(f1, sizeof f1, 1000, "", -1);
            memcpy(strstr(f1, "\"right\""), "\"rihgt\"", 7);
            snprintf(text, sizeof text, "{\"frames\":[%s]}", f1);
        }
        if (!strcmp(w, "packed")) snprintf(text, sizeof text, "{\"frames\":[[1,2,3]]}");
        if (!strcmp(w, "not json")) snprintf(text, sizeof text, "{\"frames\":\n[}");
        if (!strcmp(w, "after")) snprintf(text, sizeof text, "{\"frames\":[%s]}\n {\"frames\":[]}\n", f0);
        if (!strcmp(w, "fraction")) snprintf(text, sizeof text, "{\"frames\":[{\"timestamp\":1.5}]}");
        if (!strcmp(w, "not base64")) snprintf(text, sizeof text, "BIUwNmD2A0?EDukBOYAmBCIA");
        refused(path, text, w, cases[c].want);
    }
    /* a compressed text that is not JSON; and a missing file */
    fp_test_write_file(path, "BIUwNmD2A0AEDukBOYAmBCIA\n");
    assert_int_equal(fp_leapjson_read(path, collect, &R, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "of the decompressed text"));
    unlink(path);
    assert_int_equal(fp_leapjson_read(path, collect, &R, err, sizeof err), -ENOENT);
    assert_non_null(strstr(err, path));
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(lzstring_vectors),
        cmocka_unit_test(lzstring_refusals),
        cmocka_unit_test(originals_equal_their_csv),
        cmocka_unit_test(format2_reads_as_the_original),
        cmocka_unit_test(plain_json_and_hostile_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
