/*
 * leapjson.c: Leap Motion playback recordings (leapjson.h): LZ-string's base64 stream
 * decoded, then the JSON frames walked with cJSON into joints rows.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "leapjson.h"

#include "fp_error.h"
#include "fp_file.h"
#include "fp_text.h"

#include <cJSON.h>

#include <assert.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- LZ-string ------------------------------------------------------------------------- */

/* The stream: 6-bit values (the base64 alphabet's places), read low bit first from bit 5
 * down (LZ-string's resetValue 32); past the end, zeros. */
typedef struct lz_in {
    const char *s;
    size_t len, idx; /* idx: the next value's place */
    int val, pos;
    size_t bad;      /* the place of a character outside the alphabet, or SIZE_MAX */
} lz_in;

static int b64_value(unsigned char c)
{
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : c == '=' ? 64 : -1;
}

static uint32_t lz_bits(lz_in *z, int n)
{
    uint32_t b = 0;
    for (int i = 0; i < n; i++) {
        int r = z->val & z->pos;
        z->pos >>= 1;
        if (!z->pos) {
            z->pos = 32;
            int v = 0;
            if (z->idx < z->len && (v = b64_value((unsigned char)z->s[z->idx])) < 0) {
                if (z->bad == SIZE_MAX) z->bad = z->idx;
                v = 0;
            }
            z->val = v;
            z->idx++;
        }
        if (r) b |= 1u << i;
    }
    return b;
}

/* The output: UTF-16 code units as UTF-8, a surrogate pair joined across entries */
typedef struct lz_out {
    char *buf;
    size_t len, cap, max;
    uint32_t high; /* a high surrogate waiting for its low one, or 0 */
} lz_out;

static int out_bytes(lz_out *o, const char *b, size_t n)
{
    if (o->len + n > o->max) return -EFBIG;
    if (o->len + n + 1 > o->cap) {
        size_t cap = o->cap ? o->cap : 1 << 16;
        while (cap < o->len + n + 1) cap = cap > SIZE_MAX / 2 ? SIZE_MAX : cap * 2;
        char *nb = realloc(o->buf, cap);
        if (!nb) return -ENOMEM;
        o->buf = nb;
        o->cap = cap;
    }
    memcpy(o->buf + o->len, b, n);
    o->len += n;
    return 0;
}

static int out_char(lz_out *o, uint32_t c)
{
    char b[4];
    size_t n;
    if (c < 0x80) {
        b[0] = (char)c;
        n = 1;
    } else if (c < 0x800) {
        b[0] = (char)(0xC0 | c >> 6);
        b[1] = (char)(0x80 | (c & 0x3F));
        n = 2;
    } else if (c < 0x10000) {
        b[0] = (char)(0xE0 | c >> 12);
        b[1] = (char)(0x80 | (c >> 6 & 0x3F));
        b[2] = (char)(0x80 | (c & 0x3F));
        n = 3;
    } else {
        b[0] = (char)(0xF0 | c >> 18);
        b[1] = (char)(0x80 | (c >> 12 & 0x3F));
        b[2] = (char)(0x80 | (c >> 6 & 0x3F));
        b[3] = (char)(0x80 | (c & 0x3F));
        n = 4;
    }
    return out_bytes(o, b, n);
}

static int out_unit(lz_out *o, uint32_t u)
{
    int rc = 0;
    if (o->high) {
        uint32_t h = o->high;
        o->high = 0;
        if (u >= 0xDC00 && u <= 0xDFFF) return out_char(o, 0x10000 + ((h - 0xD800) << 10) + (u - 0xDC00));
        if ((rc = out_char(o, 0xFFFD))) return rc; /* a lone high surrogate */
    }
    if (u >= 0xD800 && u <= 0xDBFF) {
        o->high = u;
        return 0;
    }
    return out_char(o, u >= 0xDC00 && u <= 0xDFFF ? 0xFFFD : u);
}

/* The dictionary: entry e is entry prefix[e] (LZ_NONE: nothing) followed by unit[e]; its
 * length len[e] and first unit first[e]. Entries 0, 1 and 2 are the codes' markers. */
#define LZ_NONE UINT32_MAX
typedef struct lz_dict {
    uint32_t *prefix, *len;
    uint16_t *unit, *first;
    size_t size, cap;
    uint16_t *scratch; /* an entry's units, in order */
    size_t scratch_cap;
} lz_dict;

static int dict_add(lz_dict *d, uint32_t prefix, uint16_t unit)
{
    if (d->size == d->cap) {
        size_t cap = d->cap ? 2 * d->cap : 4096;
        uint32_t *p = realloc(d->prefix, cap * sizeof *p);
        if (p) d->prefix = p;
        uint32_t *l = realloc(d->len, cap * sizeof *l);
        if (l) d->len = l;
        uint16_t *u = realloc(d->unit, cap * sizeof *u);
        if (u) d->unit = u;
        uint16_t *f = realloc(d->first, cap * sizeof *f);
        if (f) d->first = f;
        if (!p || !l || !u || !f) return -ENOMEM;
        d->cap = cap;
    }
    size_t e = d->size++;
    d->prefix[e] = prefix;
    d->unit[e] = unit;
    d->len[e] = prefix == LZ_NONE ? 1 : d->len[prefix] + 1;
    d->first[e] = prefix == LZ_NONE ? unit : d->first[prefix];
    return 0;
}

static int emit(lz_dict *d, lz_out *o, uint32_t e)
{
    size_t n = d->len[e];
    if (o->len + n > o->max) return -EFBIG; /* (every unit is a byte or more) */
    if (n > d->scratch_cap) {
        uint16_t *s = realloc(d->scratch, 2 * n * sizeof *s);
        if (!s) return -ENOMEM;
        d->scratch = s;
        d->scratch_cap = 2 * n;
    }
    for (size_t i = n; i-- > 0; e = d->prefix[e]) d->scratch[i] = d->unit[e];
    for (size_t i = 0; i < n; i++) {
        int rc = out_unit(o, d->scratch[i]);
        if (rc) return rc;
    }
    return 0;
}

int fp_lzstring_decode_base64(const char *in, size_t len, size_t max_out, char **out,
                              size_t *out_len, char *why, size_t whylen)
{
    if (out) *out = NULL;
    if (out_len) *out_len = 0;
    if (!in || !out || !out_len) return fp_errorf(why, whylen, -EINVAL, "NULL argument");
    while (len && strchr(" \t\r\n", in[len - 1]) && in[len - 1]) len--;
    if (!len) return fp_errorf(why, whylen, -EBADMSG, "no compressed text");
    lz_in z = {.s = in, .len = len, .idx = 1, .pos = 32, .bad = SIZE_MAX};
    if ((z.val = b64_value((unsigned char)in[0])) < 0) z.bad = 0, z.val = 0;
    lz_out o = {.max = max_out};
    lz_dict d = {0};
    int rc = 0;
    for (int k = 0; k < 3 && !rc; k++) rc = dict_add(&d, LZ_NONE, 0); /* the markers */
    /* LZ-string's _decompress: a first character, then codes of nb bits (nb grows as the
     * dictionary does): 0 and 1 a new 8- or 16-bit character, 2 the end, else an entry */
    uint32_t c = rc ? 2 : lz_bits(&z, 2), w;
    if (c < 2) {
        rc = dict_add(&d, LZ_NONE, (uint16_t)lz_bits(&z, c ? 16 : 8));
        w = (uint32_t)d.size - 1;
        if (!rc) rc = emit(&d, &o, w);
        int nb = 3;
        uint32_t enlarge = 4; /* codes left before nb grows (LZ-string's enlargeIn) */
        for (;;) {
            if (rc) break;
            if (z.idx > z.len) {
                rc = fp_errorf(why, whylen, -EBADMSG, "the stream ends before its end mark (cut short?)");
                break;
            }
            c = lz_bits(&z, nb);
            if (c == 2) break;
            if (c < 2) {
                if ((rc = dict_add(&d, LZ_NONE, (uint16_t)lz_bits(&z, c ? 16 : 8)))) break;
                c = (uint32_t)d.size - 1;
                if (--enlarge == 0) enlarge = 1u << nb++;
            }
            if (c > d.size || nb > 30) {
                rc = fp_errorf(why, whylen, -EBADMSG, "bad code %u (the dictionary holds %zu entries)", c,
                               d.size);
                break;
            }
            /* the new entry: w and the first unit of c (c == size: of w, as c is that entry) */
            uint16_t f = c < d.size ? d.first[c] : d.first[w];
            if ((rc = dict_add(&d, w, f)) || (rc = emit(&d, &o, c))) break;
            w = c;
            if (--enlarge == 0) enlarge = 1u << nb++;
        }
    } else if (c != 2) {
        rc = fp_errorf(why, whylen, -EBADMSG, "bad first code %u", c);
    }
    if (!rc && z.bad != SIZE_MAX)
        rc = fp_errorf(why, whylen, -EBADMSG, "not base64 at byte %zu", z.bad);
    if (!rc && o.high) rc = out_char(&o, 0xFFFD);
    if (!rc && !o.buf) rc = out_bytes(&o, "", 0);
    if (rc == -EFBIG) fp_errorf(why, whylen, rc, "decompresses to more than %zu bytes", max_out);
    if (rc == -ENOMEM) fp_errorf(why, whylen, rc, "out of memory");
    free(d.prefix), free(d.len), free(d.unit), free(d.first), free(d.scratch);
    if (rc) {
        free(o.buf);
        return rc;
    }
    o.buf[o.len] = '\0';
    *out = o.buf;
    *out_len = o.len;
    return 0;
}

/* ---- the JSON frames ------------------------------------------------------------------- */

typedef struct walk {
    const char *path;
    char *err;
    size_t errlen;
} walk;

#define bad(W, ...) fp_error_at((W)->err, (W)->errlen, -EBADMSG, (W)->path, 0, 0, __VA_ARGS__)

/* obj[name], three finite numbers within FP_EVENT_MAX_MM (positions) or any size (vectors),
 * into v */
static int vec3(const walk *W, const cJSON *obj, const char *where, const char *name, bool position,
                double v[3])
{
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) != 3)
        return bad(W, "%s.%s: expected 3 numbers", where, name);
    int i = 0;
    for (const cJSON *e = a->child; e; e = e->next, i++) {
        if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble) || fabs(e->valuedouble) > FLT_MAX)
            return bad(W, "%s.%s[%d]: expected a finite number", where, name, i);
        if (position && fabs(e->valuedouble) > FP_EVENT_MAX_MM)
            return bad(W, "%s.%s[%d]: %g is beyond 10 m of the tracker (FP_EVENT_MAX_MM, in mm): "
                          "not a hand", where, name, i, e->valuedouble);
        v[i] = e->valuedouble;
    }
    return 0;
}

/* an integer within +-lim */
static int integer(const walk *W, const cJSON *obj, const char *where, const char *name, double lim,
                   int64_t *out)
{
    const cJSON *n = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (!cJSON_IsNumber(n) || !(fabs(n->valuedouble) <= lim) || n->valuedouble != floor(n->valuedouble))
        return bad(W, "%s.%s: expected an integer within %.0f either side of 0", where, name, lim);
    *out = (int64_t)n->valuedouble;
    return 0;
}

static const char *const finger_name[FP_FINGERS] = {"thumb", "index", "middle", "ring", "pinky"};
static const char *const joint_field[4] = {"mcpPosition", "pipPosition", "dipPosition", "tipPosition"};

/* hand h of frame f into row (its fingers from the frame's pointables) */
static int hand_row(const walk *W, const cJSON *frame, const char *fw, const cJSON *hand,
                    const char *where, fp_leapcsv_row *row)
{
    int64_t id = 0;
    int rc;
    if ((rc = integer(W, hand, where, "id", 2147483647.0, &id))) return rc;
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(hand, "type");
    const char *ts = cJSON_GetStringValue(type);
    if (ts && !strcmp(ts, "left"))
        row->side = FP_HAND_LEFT;
    else if (ts && !strcmp(ts, "right"))
        row->side = FP_HAND_RIGHT;
    else
        return bad(W, "%s.type: expected \"left\" or \"right\"", where);
    row->hand_id = (long)id;
    double *v = row->value;
    if ((rc = vec3(W, hand, where, "palmPosition", true, v)) ||
        (rc = vec3(W, hand, where, "palmNormal", false, v + 3)) ||
        (rc = vec3(W, hand, where, "direction", false, v + 6)))
        return rc;
    const cJSON *ps = cJSON_GetObjectItemCaseSensitive(frame, "pointables");
    if (ps && !cJSON_IsArray(ps)) return bad(W, "%s.pointables: expected an array", fw);
    unsigned seen = 0;
    int k = 0;
    for (const cJSON *p = ps ? ps->child : NULL; p; p = p->next, k++) {
        char pw[96];
        snprintf(pw, sizeof pw, "%.40s.pointables[%d]", fw, k);
        if (!cJSON_IsObject(p)) return bad(W, "%s: expected an object", pw);
        if (cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(p, "tool"))) continue;
        int64_t hid = 0, ft = 0;
        if ((rc = integer(W, p, pw, "handId", 2147483647.0, &hid))) return rc;
        if (hid != id) continue;
        if (cJSON_GetObjectItemCaseSensitive(p, "type")) {
            if ((rc = integer(W, p, pw, "type", 4, &ft))) return rc;
            if (ft < 0) return bad(W, "%s.type: expected 0 (thumb) to 4 (pinky)", pw);
        } else { /* (format 2 packs no type): Leap's finger id is 10 x its hand's id + its type */
            int64_t fid = 0;
            if ((rc = integer(W, p, pw, "id", 2147483647.0 * 11, &fid))) return rc;
            ft = fid - 10 * hid;
            if (ft < 0 || ft > 4)
                return bad(W, "%s: no type, and its id %lld is not 10 x its hand's id %lld + 0 (thumb) "
                              "to 4 (pinky)", pw, (long long)fid, (long long)hid);
        }
        if (seen >> ft & 1) return bad(W, "%s: a second %s of hand %lld", pw, finger_name[ft], (long long)id);
        seen |= 1u << ft;
        for (int j = 0; j < 4; j++)
            if ((rc = vec3(W, p, pw, joint_field[j], true, v + 9 + 3 * (4 * ft + j)))) return rc;
    }
    for (int f = 0; f < FP_FINGERS; f++)
        if (!(seen >> f & 1))
            return bad(W, "%s: hand %lld has no %s (a pointable of type %d)", where, (long long)id,
                       finger_name[f], f);
    for (int i = 0; i < FP_LEAPCSV_JOINT_VALUES; i++) row->valuef[i] = (float)v[i];
    return 0;
}

/* leapjs-playback's format 2 (recording.js, unPackArray): a packed value `data` unfolded by
 * the packing structure `st` (frames[0]) into a new object (its leaves references into data,
 * so it must be deleted before data): a name takes the value at its place; a nested array
 * makes a list of each of data's items unfolded by it (hands, pointables); {key: st2} makes
 * key the value at its place unfolded by st2. NULL with *rc set on an error. */
static cJSON *unpack(const walk *W, const cJSON *st, const cJSON *data, const char *where, int *rc)
{
    if (!cJSON_IsArray(st)) {
        *rc = bad(W, "frames[0]: expected an array of names (format 2's packing structure)");
        return NULL;
    }
    if (!cJSON_IsArray(data)) {
        *rc = bad(W, "%s: expected an array (a packed frame, format 2)", where);
        return NULL;
    }
    cJSON *out = cJSON_CreateObject();
    bool ok = out != NULL;
    const cJSON *d = data->child;
    for (const cJSON *s = st->child; ok && s; s = s->next, d = d ? d->next : NULL) {
        if (cJSON_IsString(s)) { /* (past data's end: absent, as in recording.js) */
            ok = !d || cJSON_AddItemReferenceToObject(out, s->valuestring, (cJSON *)d);
        } else if (cJSON_IsArray(s)) { /* a list: every item of data by s */
            cJSON_Delete(out);
            ok = (out = cJSON_CreateArray()) != NULL;
            int k = 0;
            for (const cJSON *e = data->child; ok && e; e = e->next, k++) {
                char ew[96];
                snprintf(ew, sizeof ew, "%.80s[%d]", where, k);
                cJSON *u = unpack(W, s, e, ew, rc);
                ok = u && cJSON_AddItemToArray(out, u);
                if (!ok) cJSON_Delete(u);
            }
            break;
        } else if (cJSON_IsObject(s) && s->child && s->child->string) {
            if (!d) continue;
            char kw[96];
            snprintf(kw, sizeof kw, "%.60s.%.30s", where, s->child->string);
            cJSON *u = unpack(W, s->child, d, kw, rc);
            ok = u && cJSON_AddItemToObject(out, s->child->string, u);
            if (!ok) cJSON_Delete(u);
        } else {
            *rc = bad(W, "frames[0]: expected names, arrays and {name: [...]} (format 2's packing structure)");
            ok = false;
        }
    }
    if (ok) return out;
    cJSON_Delete(out);
    if (!*rc) *rc = fp_error_at(W->err, W->errlen, -ENOMEM, W->path, 0, 0, "out of memory");
    return NULL;
}

/* frame f (where: its JSON path in the file), the recording's frame i, into a row for each
 * hand (row: the row so far, its timestamp the frame before's when *have_ts) */
static int frame_rows(const walk *W, const cJSON *f, const char *where, long i, fp_leapcsv_row *row,
                      bool *have_ts, fp_leapcsv_row_fn fn, void *user)
{
    if (!cJSON_IsObject(f)) return bad(W, "%s: expected an object", where);
    int64_t ts = 0;
    int rc = integer(W, f, where, "timestamp", (double)FP_LEAPCSV_TIME_MAX_US, &ts);
    if (rc) return rc;
    if (*have_ts && ts < row->timestamp_us)
        return bad(W, "%s.timestamp: %lld goes backwards (the frame before has %lld)", where,
                   (long long)ts, (long long)row->timestamp_us);
    *have_ts = true;
    row->timestamp_us = ts;
    row->frame = i;
    const cJSON *hands = cJSON_GetObjectItemCaseSensitive(f, "hands");
    if (hands && !cJSON_IsArray(hands)) return bad(W, "%s.hands: expected an array", where);
    int h = 0;
    for (const cJSON *hand = hands ? hands->child : NULL; hand; hand = hand->next, h++) {
        char hw[80];
        snprintf(hw, sizeof hw, "%.60s.hands[%d]", where, h);
        if (!cJSON_IsObject(hand)) return bad(W, "%s: expected an object", hw);
        if ((rc = hand_row(W, f, where, hand, hw, row))) return rc;
        if ((rc = fn(user, row, W->err, W->errlen))) return rc;
    }
    return 0;
}

static int walk_frames(const walk *W, const cJSON *root, fp_leapcsv_row_fn fn, void *user)
{
    if (!cJSON_IsObject(root)) return bad(W, "expected a JSON object (a Leap playback recording)");
    const cJSON *frames = cJSON_GetObjectItemCaseSensitive(root, "frames");
    if (!cJSON_IsArray(frames)) return bad(W, "frames: expected an array (a Leap playback recording)");
    fp_leapcsv_row row;
    memset(&row, 0, sizeof row);
    row.path = W->path;
    row.format = FP_LEAPCSV_JOINTS;
    row.nvalues = FP_LEAPCSV_JOINT_VALUES;
    row.valid = (1u << FP_GLOVE_SENSORS) - 1u; /* as the joints CSV's rows */
    /* format 2: frames[0] the packing structure, then a packed frame each */
    const cJSON *meta = cJSON_GetObjectItemCaseSensitive(root, "metadata");
    const cJSON *version = cJSON_GetObjectItemCaseSensitive(meta, "formatVersion");
    const cJSON *st = cJSON_IsNumber(version) && version->valuedouble == 2 ? frames->child : NULL;
    if (st && !cJSON_IsArray(st))
        return bad(W, "frames[0]: expected an array of names (format 2's packing structure)");
    bool have_ts = false;
    long i = 0;
    int rc = 0;
    for (const cJSON *f = st ? st->next : frames->child; f; f = f->next, i++) {
        char where[64];
        snprintf(where, sizeof where, "frames[%ld]", i + (st != NULL));
        if (cJSON_IsArray(f) && !st)
            return bad(W, "%s: a packed frame, but metadata.formatVersion is not 2 (leapjs-playback's "
                          "packed format)", where);
        cJSON *unpacked = st ? unpack(W, st, f, where, &rc) : NULL;
        if (rc) return rc;
        rc = frame_rows(W, unpacked ? unpacked : f, where, i, &row, &have_ts, fn, user);
        cJSON_Delete(unpacked);
        if (rc) return rc;
    }
    return 0;
}

int fp_leapjson_read(const char *path, fp_leapcsv_row_fn fn, void *user, char *err, size_t errlen)
{
    if (!path || !fn) return fp_errorf(err, errlen, -EINVAL, "fp_leapjson_read: NULL argument");
    walk W = {path, err, errlen};
    char *raw;
    size_t len;
    int rc = fp_file_read_all(path, FP_LEAPJSON_MAX_TEXT, &raw, &len);
    if (rc == -EFBIG)
        return fp_error_at(err, errlen, rc, path, 0, 0, "larger than %zu bytes", FP_LEAPJSON_MAX_TEXT);
    if (rc == -ENOMEM) return fp_error_at(err, errlen, rc, path, 0, 0, "out of memory");
    if (rc == -EIO) return fp_error_at(err, errlen, rc, path, 0, 0, "read error");
    if (rc) return fp_error_at(err, errlen, rc, path, 0, 0, "cannot open: %s", fp_file_error_text(rc));
    const char *start = raw;
    if (len >= 3 && !memcmp(start, "\xEF\xBB\xBF", 3)) start += 3; /* a BOM */
    start = fp_text_after_space(start, raw + len);
    if (!start) {
        free(raw);
        return fp_error_at(err, errlen, -EBADMSG, path, 0, 0, "empty: not a Leap playback recording");
    }
    char *text = raw;
    bool packed = *start != '{';
    if (packed && (size_t)(raw + len - start) > FP_LEAPJSON_MAX_PACKED) {
        free(raw);
        return fp_error_at(err, errlen, -EFBIG, path, 0, 0, "not plain JSON, and larger than %zu bytes "
                           "for LZ-string base64", FP_LEAPJSON_MAX_PACKED);
    }
    if (packed) {
        char why[160];
        rc = fp_lzstring_decode_base64(start, (size_t)(raw + len - start), FP_LEAPJSON_MAX_TEXT, &text,
                                       &len, why, sizeof why);
        free(raw);
        if (rc) return fp_error_at(err, errlen, rc, path, 0, 0, "not a Leap playback recording "
                                   "(JSON, or LZ-string base64 as *.json.lz): %s", why);
    }
    const char *json = packed ? text : start; /* (after the BOM) */
    len -= packed ? 0 : (size_t)(start - raw);
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(json, len, &end, false);
    if (!root) {
        const char *at = cJSON_GetErrorPtr();
        if (!(at && at >= json && at <= json + len)) at = json;
        long line;
        fp_text_line_col(text, at, &line, NULL);
        rc = root ? 0 : fp_error_at(err, errlen, -EBADMSG, path, 0, 0, "not valid JSON near line %ld%s",
                                    line, packed ? " of the decompressed text" : "");
    } else if ((end = fp_text_after_space(end, json + len))) {
        /* one recording per file: what follows it is damage (two pasted into one file: the
         * second was ignored in silence), as the calibration, rig and stack readers refuse it */
        long line;
        fp_text_line_col(text, end, &line, NULL);
        rc = fp_error_at(err, errlen, -EBADMSG, path, 0, 0, "text after the JSON object, at line %ld%s",
                         line, packed ? " of the decompressed text" : "");
        cJSON_Delete(root);
    } else {
        rc = walk_frames(&W, root, fn, user);
        cJSON_Delete(root);
    }
    free(text);
    return rc;
}

bool fp_leapjson_looks_like(const char *head)
{
    const char *p = head + (strncmp(head, "\xEF\xBB\xBF", 3) ? 0 : 3);
    p += strspn(p, " \t\r\n");
    if (*p == '{') return true;
    size_t n = strspn(head, "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/=");
    return n >= 16 && head[n + strspn(head + n, " \t\r\n")] == '\0';
}

typedef struct joints_rows {
    fp_leap_joints_row *r;
    size_t n, cap;
} joints_rows;

static int on_joints(void *user, const fp_leapcsv_row *in, char *err, size_t errlen)
{
    joints_rows *R = user;
    if (R->n == R->cap) {
        size_t cap = R->cap ? 2 * R->cap : 1024;
        fp_leap_joints_row *r = realloc(R->r, cap * sizeof *r);
        if (!r) return fp_error_at(err, errlen, -ENOMEM, in->path, 0, 0, "out of memory");
        R->r = r;
        R->cap = cap;
    }
    fp_leap_joints_from_row(in, &R->r[R->n++]);
    return 0;
}

int fp_leapjson_read_joints(const char *path, fp_leap_joints_row **rows, size_t *n, char *err,
                            size_t errlen)
{
    if (rows) *rows = NULL;
    if (n) *n = 0;
    if (!rows || !n) return fp_errorf(err, errlen, -EINVAL, "fp_leapjson_read_joints: NULL argument");
    joints_rows R = {0};
    int rc = fp_leapjson_read(path, on_joints, &R, err, errlen);
    if (!rc && !R.n) rc = fp_error_at(err, errlen, -EBADMSG, path, 0, 0, "the recording holds no hands");
    if (rc) {
        free(R.r);
        return rc;
    }
    *rows = R.r;
    *n = R.n;
    return 0;
}
