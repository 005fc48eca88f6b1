/* take_format.c: the byte layout of docs/take-format.md: frame records, events, the header's
 * JSON, chunk framing and the file signature. */
#include "take_internal.h"

#include "fp_error.h"
#include "fp_text.h"
#include "fp_file.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <zlib.h>

/* ---- events --------------------------------------------------------------------------- */

static size_t event_body_size(uint32_t type)
{
    switch (type) {
    case FP_EVENT_JOINT_ANGLES: return 4 + 4 * FP_GLOVE_SENSORS;
    case FP_EVENT_JOINT_POSITIONS: return 4 * 3 * FP_HAND_JOINTS;
    case FP_EVENT_WRIST_POSE: return 4 * 7;
    case FP_EVENT_BUTTON: return 12;
    case FP_EVENT_STATUS: return 4 + sizeof(((fp_event_status *)0)->text);
    case FP_EVENT_CHANNEL: return sizeof(((fp_event_channel *)0)->name) + 4;   /* 1.2 */
    default: return 0;
    }
}

/* The f32 fields of a type's body: *first their offset in it, the count returned (0: none). */
static size_t event_floats(uint32_t type, size_t *first)
{
    *first = 0;
    switch (type) {
    case FP_EVENT_JOINT_ANGLES: *first = 4; return FP_GLOVE_SENSORS;
    case FP_EVENT_JOINT_POSITIONS: return 3 * FP_HAND_JOINTS;
    case FP_EVENT_WRIST_POSE: return 7;
    case FP_EVENT_CHANNEL: *first = sizeof(((fp_event_channel *)0)->name); return 1;
    default: return 0;
    }
}

size_t take_event_size(const fp_event *e)
{
    size_t b = event_body_size(e->header.type);
    return b ? TAKE_EVENT_HEAD + b : 0;
}

static size_t event_encode(const fp_event *e, uint8_t *p)
{
    size_t n = take_event_size(e);
    le_put32(p, (uint32_t)n);
    le_put16(p + 4, e->header.type);
    le_put16(p + 6, e->header.flags);
    le_put64(p + 8, (uint64_t)e->header.time_ns);
    le_put32(p + 16, e->header.source);
    le_put32(p + 20, (uint32_t)e->header.hand);
    uint8_t *b = p + TAKE_EVENT_HEAD;
    switch (e->header.type) {
    case FP_EVENT_JOINT_ANGLES:
        le_put32(b, e->angles.valid);
        for (int i = 0; i < FP_GLOVE_SENSORS; i++) le_putf(b + 4 + 4 * i, e->angles.radians[i]);
        break;
    case FP_EVENT_JOINT_POSITIONS:
        for (int j = 0; j < FP_HAND_JOINTS; j++)
            for (int k = 0; k < 3; k++) le_putf(b + 12 * j + 4 * k, e->positions.mm[j][k]);
        break;
    case FP_EVENT_WRIST_POSE:
        for (int k = 0; k < 3; k++) le_putf(b + 4 * k, e->wrist.position_mm[k]);
        for (int k = 0; k < 4; k++) le_putf(b + 12 + 4 * k, e->wrist.rotation[k]);
        break;
    case FP_EVENT_BUTTON:
        le_put32(b, e->button.button);
        le_put32(b + 4, e->button.down);
        le_put32(b + 8, e->button.mask);
        break;
    case FP_EVENT_STATUS: {
        size_t cap = sizeof e->status.text;
        le_put32(b, e->status.code);
        size_t len = strnlen(e->status.text, cap - 1);
        memcpy(b + 4, e->status.text, len);
        memset(b + 4 + len, 0, cap - len);
        break;
    }
    case FP_EVENT_CHANNEL: {
        size_t cap = sizeof e->channel.name;
        size_t len = strnlen(e->channel.name, cap - 1);
        memcpy(b, e->channel.name, len);
        memset(b + len, 0, cap - len);
        le_putf(b + cap, e->channel.value);
        break;
    }
    default: break;
    }
    return n;
}

static void event_decode(const uint8_t *p, fp_event *e)
{
    uint16_t type = le_get16(p + 4);
    memset(e, 0, sizeof *e);
    e->header.type = type;
    e->header.flags = le_get16(p + 6);
    e->header.time_ns = (int64_t)le_get64(p + 8);
    e->header.source = le_get32(p + 16);
    e->header.hand = (int32_t)le_get32(p + 20);
    const uint8_t *b = p + TAKE_EVENT_HEAD;
    switch (type) {
    case FP_EVENT_JOINT_ANGLES:
        e->header.size = sizeof(fp_event_joint_angles);
        e->angles.valid = le_get32(b);
        for (int i = 0; i < FP_GLOVE_SENSORS; i++) e->angles.radians[i] = le_getf(b + 4 + 4 * i);
        break;
    case FP_EVENT_JOINT_POSITIONS:
        e->header.size = sizeof(fp_event_joint_positions);
        for (int j = 0; j < FP_HAND_JOINTS; j++)
            for (int k = 0; k < 3; k++) e->positions.mm[j][k] = le_getf(b + 12 * j + 4 * k);
        break;
    case FP_EVENT_WRIST_POSE:
        e->header.size = sizeof(fp_event_wrist_pose);
        for (int k = 0; k < 3; k++) e->wrist.position_mm[k] = le_getf(b + 4 * k);
        for (int k = 0; k < 4; k++) e->wrist.rotation[k] = le_getf(b + 12 + 4 * k);
        break;
    case FP_EVENT_BUTTON:
        e->header.size = sizeof(fp_event_button);
        e->button.button = le_get32(b);
        e->button.down = le_get32(b + 4);
        e->button.mask = le_get32(b + 8);
        break;
    case FP_EVENT_STATUS:
        e->header.size = sizeof(fp_event_status);
        e->status.code = le_get32(b);
        memcpy(e->status.text, b + 4, sizeof e->status.text);
        e->status.text[sizeof e->status.text - 1] = '\0';
        break;
    case FP_EVENT_CHANNEL:
        e->header.size = sizeof(fp_event_channel);
        memcpy(e->channel.name, b, sizeof e->channel.name);
        e->channel.name[sizeof e->channel.name - 1] = '\0';
        e->channel.value = le_getf(b + sizeof e->channel.name);
        break;
    default: break;
    }
}

/* ---- frame records -------------------------------------------------------------------- */

size_t fp_take_frame_size(const fp_take_frame *f)
{
    if (!f || (f->event_count && !f->events)) return 0;
    size_t n = TAKE_FRAME_FIXED;
    const fp_control_set *c = f->control;
    if (c) {
        if (c->count >= TAKE_COUNT_MAX || c->channel_count >= TAKE_COUNT_MAX) return 0;
        if ((c->count && (!c->start || !c->end)) || (c->channel_count && !c->channels)) return 0;
        n += TAKE_VECTOR_SIZE * c->count;
        for (size_t i = 0; i < c->channel_count; i++) n += TAKE_CHANNEL_SIZE * !!isfinite(c->channels[i].value);
    }
    if (f->event_count >= TAKE_COUNT_MAX) return 0;
    for (size_t i = 0; i < f->event_count; i++) n += take_event_size(&f->events[i]);
    return n;
}

size_t fp_take_frame_encode(const fp_take_frame *f, void *buf, size_t cap)
{
    size_t n = fp_take_frame_size(f);
    if (!n || n > cap || n > UINT32_MAX) return 0;
    uint8_t *p = buf;
    const fp_control_set *c = f->control;
    uint32_t flags = c ? TAKE_FRAME_FLAG_CONTROL | (c->active ? TAKE_FRAME_FLAG_ACTIVE : 0) : 0;
    uint32_t events = 0, channels = 0;
    for (size_t i = 0; i < f->event_count; i++) events += take_event_size(&f->events[i]) != 0;
    for (size_t i = 0; c && i < c->channel_count; i++) channels += isfinite(c->channels[i].value) != 0;
    le_put32(p, (uint32_t)n);
    le_put32(p + 4, flags);
    le_put64(p + 8, f->frame);
    le_put64(p + 16, (uint64_t)f->time_ns);
    le_put32(p + 24, f->requested);
    le_put32(p + 28, c ? c->intents : 0);
    le_putd(p + 32, c ? c->radius : 0.0);
    le_put32(p + 40, c ? (uint32_t)c->count : 0);
    le_put32(p + 44, channels);
    le_put32(p + 48, events);
    le_put32(p + 52, 0);
    p += TAKE_FRAME_FIXED;
    if (c) {
        for (size_t i = 0; i < c->count; i++, p += TAKE_VECTOR_SIZE)
            for (int k = 0; k < 3; k++) {
                le_putf(p + 4 * k, c->start[i][k]);
                le_putf(p + 12 + 4 * k, c->end[i][k]);
            }
        for (size_t i = 0; i < c->channel_count; i++) {
            if (!isfinite(c->channels[i].value)) continue; /* not recorded: fp_take.h */
            size_t len = strnlen(c->channels[i].name, sizeof c->channels[i].name - 1);
            memcpy(p, c->channels[i].name, len);
            memset(p + len, 0, 32 - len);
            le_putf(p + 32, c->channels[i].value);
            p += TAKE_CHANNEL_SIZE;
        }
    }
    for (size_t i = 0; i < f->event_count; i++)
        if (take_event_size(&f->events[i])) p += event_encode(&f->events[i], p);
    return n;
}

int take_frame_check(const uint8_t *rec, size_t n, size_t inputs, size_t *bad_at, char *why, size_t whylen)
{
#define BAD(off, ...) do { *bad_at = (off); snprintf(why, whylen, __VA_ARGS__); return -EBADMSG; } while (0)
    if (n < TAKE_FRAME_FIXED) BAD(0, "frame record shorter than its fixed part (56 bytes)");
    if (le_get32(rec) != n) BAD(0, "frame record size field disagrees with the chunk");
    uint32_t vc = le_get32(rec + 40), cc = le_get32(rec + 44), ec = le_get32(rec + 48);
    if (vc >= TAKE_COUNT_MAX) BAD(40, "control vector count out of range");
    if (cc >= TAKE_COUNT_MAX) BAD(44, "channel count out of range");
    if (ec >= TAKE_COUNT_MAX) BAD(48, "event count out of range");
    uint32_t flags = le_get32(rec + 4);
    if (flags & ~(TAKE_FRAME_FLAG_ACTIVE | TAKE_FRAME_FLAG_CONTROL))
        BAD(4, "unknown frame flags");
    size_t off = TAKE_FRAME_FIXED + (size_t)vc * TAKE_VECTOR_SIZE + (size_t)cc * TAKE_CHANNEL_SIZE;
    if (off > n) BAD(40, "control vectors and channels run past the frame record");
    if (flags & TAKE_FRAME_FLAG_CONTROL) {
        /* a control set the engine cannot take (it would show the base, frame after frame,
         * with nothing said of the file): the solver's radius range, finite vectors */
        const double radius = le_getd(rec + 32);
        if (!(radius >= TAKE_RADIUS_MIN && radius <= TAKE_RADIUS_MAX))
            BAD(32, "control set radius not finite and in [1e-15, 1e15] mesh units");
        for (size_t i = 0; i < (size_t)vc * 6; i++)
            if (!isfinite(le_getf(rec + TAKE_FRAME_FIXED + 4 * i)))
                BAD(TAKE_FRAME_FIXED + (i / 6) * TAKE_VECTOR_SIZE, "control vector not finite");
    }
    for (size_t i = 0, at = TAKE_FRAME_FIXED + (size_t)vc * TAKE_VECTOR_SIZE; i < cc; i++, at += TAKE_CHANNEL_SIZE)
        if (!isfinite(le_getf(rec + at + 32))) { /* (the rig would ignore it, or pin it to a bound) */
            char name[32], clean[100]; /* (a damaged file's name: no control bytes to the terminal) */
            memcpy(name, rec + at, 31);
            name[31] = '\0';
            BAD(at + 32, "channel \"%s\" value not finite", fp_text_clean(name, clean, sizeof clean));
        }
    for (uint32_t i = 0; i < ec; i++) {
        if (n - off < TAKE_EVENT_HEAD) BAD(off, "event header runs past the frame record");
        uint32_t es = le_get32(rec + off);
        if (es < TAKE_EVENT_HEAD || es > n - off) BAD(off, "event size out of range");
        uint16_t type = le_get16(rec + off + 4);
        size_t body = event_body_size(type);
        if (body && es < TAKE_EVENT_HEAD + body) BAD(off, "event shorter than its type needs");
        size_t first, nf = event_floats(type, &first); /* (an input refuses such events live) */
        for (size_t k = 0; k < nf; k++)
            if (!isfinite(le_getf(rec + off + TAKE_EVENT_HEAD + first + 4 * k)))
                BAD(off + TAKE_EVENT_HEAD + first + 4 * k, "event %" PRIu32 " (type %u): a value not finite",
                    i, (unsigned)type);
        int32_t hand = (int32_t)le_get32(rec + off + 20);
        if (hand < -1 || hand >= FP_HANDS) BAD(off + 20, "event hand out of range");
        if (le_get32(rec + off + 16) >= inputs) /* (an input the header does not list) */
            BAD(off + 16, "event source beyond the header's \"inputs\"");
        off += es;
    }
    if (off != n) BAD(off, "bytes left over after the frame's events");
    return 0;
#undef BAD
}

static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return 0;
    size_t c = *cap ? *cap : 8;
    while (c < need) c *= 2;
    void *q = realloc(*p, c * elem);
    if (!q) return -ENOMEM;
    *p = q;
    *cap = c;
    return 0;
}

int take_frame_decode(const uint8_t *rec, size_t n, take_frame_buf *b, fp_take_frame *f)
{
    (void)n;
    uint32_t flags = le_get32(rec + 4);
    uint32_t vc = le_get32(rec + 40), cc = le_get32(rec + 44), ec = le_get32(rec + 48);
    size_t vcap = b->vec_cap;
    if (grow((void **)&b->start, &vcap, vc, sizeof *b->start)) return -ENOMEM;
    vcap = b->vec_cap;
    if (grow((void **)&b->end, &vcap, vc, sizeof *b->end)) return -ENOMEM;
    b->vec_cap = vcap;
    if (grow((void **)&b->channels, &b->chan_cap, cc, sizeof *b->channels)) return -ENOMEM;
    if (grow((void **)&b->events, &b->events_cap, ec, sizeof *b->events)) return -ENOMEM;
    memset(f, 0, sizeof *f);
    f->frame = le_get64(rec + 8);
    f->time_ns = (int64_t)le_get64(rec + 16);
    f->requested = le_get32(rec + 24);
    fp_control_set *c = &b->control;
    memset(c, 0, sizeof *c);
    c->size = sizeof *c;
    c->active = (flags & TAKE_FRAME_FLAG_ACTIVE) != 0;
    c->intents = le_get32(rec + 28);
    c->radius = le_getd(rec + 32);
    c->capacity = b->vec_cap;
    c->count = vc;
    c->start = b->start;
    c->end = b->end;
    c->channel_capacity = b->chan_cap;
    c->channel_count = cc;
    c->channels = b->channels;
    const uint8_t *p = rec + TAKE_FRAME_FIXED;
    for (uint32_t i = 0; i < vc; i++, p += TAKE_VECTOR_SIZE)
        for (int k = 0; k < 3; k++) {
            b->start[i][k] = le_getf(p + 4 * k);
            b->end[i][k] = le_getf(p + 12 + 4 * k);
        }
    for (uint32_t i = 0; i < cc; i++, p += TAKE_CHANNEL_SIZE) {
        memcpy(b->channels[i].name, p, 32);
        b->channels[i].name[31] = '\0';
        b->channels[i].value = le_getf(p + 32);
    }
    size_t kept = 0;
    for (uint32_t i = 0; i < ec; i++) {
        uint32_t es = le_get32(p);
        if (event_body_size(le_get16(p + 4))) event_decode(p, &b->events[kept++]);
        p += es;   /* an event type this version does not know is skipped */
    }
    f->events = b->events;
    f->event_count = kept;
    f->control = (flags & TAKE_FRAME_FLAG_CONTROL) ? c : NULL;
    return 0;
}

void take_frame_buf_free(take_frame_buf *b)
{
    free(b->events);
    free(b->start);
    free(b->end);
    free(b->channels);
    memset(b, 0, sizeof *b);
}

/* ---- chunks and signature ------------------------------------------------------------- */

void take_chunk_head(uint8_t h[TAKE_CHUNK_HEAD_SIZE], const char type[4], uint32_t length,
                     uint32_t count)
{
    memcpy(h, TAKE_CHUNK_MAGIC, 4);
    memcpy(h + 4, type, 4);
    le_put32(h + 8, length);
    le_put32(h + 12, count);
}

void take_signature(uint8_t s[TAKE_SIG_SIZE])
{
    memcpy(s, TAKE_SIG_MAGIC, 8);
    le_put16(s + 8, FP_TAKE_VERSION_MAJOR);
    le_put16(s + 10, FP_TAKE_VERSION_MINOR);
    le_put32(s + 12, (uint32_t)crc32(0L, s, 12));
}

uint32_t fp_take_crc32_positions(const float *pos, size_t n)
{
    uLong crc = crc32(0L, Z_NULL, 0);
    uint8_t buf[4096];
    size_t k = 0;
    for (size_t i = 0; i < 3 * n; i++) {
        le_putf(buf + k, pos[i]);
        k += 4;
        if (k == sizeof buf) {
            crc = crc32(crc, buf, (uInt)k);
            k = 0;
        }
    }
    return (uint32_t)crc32(crc, buf, (uInt)k);
}

int fp_take_crc32_file(const char *path, uint32_t *out, char *err, size_t errlen)
{
    int code;
    FILE *f = fp_file_fopen_regular(path, &code); /* (a FIFO cannot hold it) */
    if (!f) return fp_errorf(err, errlen, code, "%s: %s", path, fp_file_error_text(code));
    uLong crc = crc32(0L, Z_NULL, 0);
    unsigned char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) crc = crc32(crc, buf, (uInt)n);
    int bad = ferror(f);
    fclose(f);
    if (bad) return fp_errorf(err, errlen, -EIO, "%s: read error", path);
    *out = (uint32_t)crc;
    return 0;
}

/* ---- header JSON ---------------------------------------------------------------------- */

bool fp_take_slate_valid(const char *s)
{
    if (!s || !*s || *s == '.') return false;
    size_t n = 0;
    for (; s[n]; n++) {
        char c = s[n];
        if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
              c == '.' || c == '_' || c == '-'))
            return false;
    }
    return n < FP_TAKE_SLATE_MAX;
}

static bool finite3(const double *v, int n)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i])) return false;
    return true;
}

/* A frame rate a take may have: 1 to TAKE_RATE_MAX frames a second (run's --fps range). */
#define TAKE_RATE_MAX 10000
static bool take_rate_ok(fp_take_rate r)
{
    return r.den && (uint64_t)r.num >= r.den && (uint64_t)r.num <= (uint64_t)TAKE_RATE_MAX * r.den;
}

int take_header_check(const fp_take_header *h, char *err, size_t errlen)
{
    if (!h) return fp_errorf(err, errlen, -EINVAL, "take header: NULL");
    if (!fp_take_slate_valid(h->slate))
        return fp_errorf(err, errlen, -EINVAL,
                         "take header: slate \"%.64s\" must be 1-63 characters of A-Z a-z 0-9 . _ - "
                         "not starting with '.'", h->slate);
    if (!h->rate.num || !h->rate.den || !take_rate_ok(h->rate))
        return fp_errorf(err, errlen, -EINVAL, "take header: frame rate %u/%u (1 to %d fps)",
                         h->rate.num, h->rate.den, TAKE_RATE_MAX);
    uint64_t f;
    if (fp_timecode_to_frames(&h->timecode_in, h->rate, &f))
        return fp_errorf(err, errlen, -EINVAL, "take header: timecode in out of range for %u/%u fps",
                         h->rate.num, h->rate.den);
    if (h->mapping_key_count > FP_TAKE_MAX_KEYS || h->input_count > FP_TAKE_MAX_INPUTS)
        return fp_errorf(err, errlen, -EINVAL, "take header: too many mapping keys or inputs");
    for (size_t i = 0; i < h->mapping_key_count; i++)
        if (!h->mapping_keys[i].key || !h->mapping_keys[i].value)
            return fp_errorf(err, errlen, -EINVAL, "take header: mapping key %zu is NULL", i);
    for (size_t i = 0; i < h->input_count; i++)
        if (!h->inputs[i])
            return fp_errorf(err, errlen, -EINVAL, "take header: input %zu is NULL", i);
    if (h->rating < 0 || h->rating > 5)
        return fp_errorf(err, errlen, -EINVAL, "take header: rating %d not in 0..5", h->rating);
    if (!fp_text_ok(h->description, true)) /* (stored in the header's JSON, shown by info) */
        return fp_errorf(err, errlen, -EINVAL, "take header: the description is not UTF-8 text "
                         "without control characters (tabs and line breaks allowed)");
    if (!isfinite(h->radius) || h->radius < 0)
        return fp_errorf(err, errlen, -EINVAL, "take header: radius not finite and >= 0");
    for (int k = 0; k < FP_HANDS; k++) {
        const fp_take_calibration *c = &h->calibration[k];
        if (c->present && (!isfinite(c->scale) || !finite3(c->rotation, 4) || !finite3(c->offset, 3)))
            return fp_errorf(err, errlen, -EINVAL, "take header: calibration of hand %d not finite", k);
    }
    if (h->performer_count > FP_PERFORMER_CAPACITY)
        return fp_errorf(err, errlen, -EINVAL, "take header: %zu performers (at most %d)", h->performer_count,
                         FP_PERFORMER_CAPACITY);
    for (size_t k = 0; k < h->performer_count; k++) {
        const fp_take_performer *p = &h->performers[k];
        if (!p->name || !fp_text_ok(p->name, false) || !(p->scale > 0) || !isfinite(p->scale) ||
            !finite3(p->rotation, 4) || !finite3(p->offset, 3) || !finite3(p->hand_offset[0], 3) ||
            !finite3(p->hand_offset[1], 3))
            return fp_errorf(err, errlen, -EINVAL, "take header: performer %zu: a name and a finite "
                             "placement (scale > 0) expected", k + 1);
    }
    if (h->mesh_crc_of && strcmp(h->mesh_crc_of, "positions") && strcmp(h->mesh_crc_of, "file"))
        return fp_errorf(err, errlen, -EINVAL, "take header: mesh_crc_of must be positions or file");
    return 0;
}

static void add_str(cJSON *o, const char *key, const char *v)
{
    if (v) cJSON_AddStringToObject(o, key, v);
    else cJSON_AddNullToObject(o, key);
}

static void add_i64(cJSON *o, const char *key, int64_t v)
{
    char buf[32];
    snprintf(buf, sizeof buf, "%" PRId64, v);
    cJSON_AddStringToObject(o, key, buf);
}

/* A JSON number that reads back as the same double (cJSON's own printing compares with an
 * epsilon and may lose the last bit): the shortest of %.15g, %.16g, %.17g that round-trips. */
static cJSON *exact_number(double d)
{
    char buf[40];
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(buf, sizeof buf, "%.*g", prec, d);
        if (strtod(buf, NULL) == d) break;
    }
    return cJSON_CreateRaw(buf);
}

static void add_number(cJSON *o, const char *key, double d)
{
    cJSON_AddItemToObject(o, key, exact_number(d));
}

static cJSON *darray(const double *v, int n)
{
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; i < n; i++) cJSON_AddItemToArray(a, exact_number(v[i]));
    return a;
}

char *take_header_to_json(const fp_take_header *h)
{
    cJSON *o = cJSON_CreateObject();
    char tc[32], crc[16];
    if (!o) return NULL;
    cJSON_AddStringToObject(o, "format", "facepuppet-take");
    cJSON_AddStringToObject(o, "slate", h->slate);
    cJSON_AddNumberToObject(o, "take", h->take);
    cJSON *rate = cJSON_AddObjectToObject(o, "frame_rate");
    cJSON_AddNumberToObject(rate, "num", h->rate.num);
    cJSON_AddNumberToObject(rate, "den", h->rate.den);
    fp_timecode_format(&h->timecode_in, tc, sizeof tc);
    cJSON_AddStringToObject(o, "timecode_in", tc);
    add_i64(o, "time_origin_ns", h->time_origin_ns);
    cJSON_AddStringToObject(o, "date", h->date);
    cJSON *mesh = cJSON_AddObjectToObject(o, "mesh");
    add_str(mesh, "path", h->mesh_path);
    snprintf(crc, sizeof crc, "%08" PRIx32, h->mesh_crc32);
    cJSON_AddStringToObject(mesh, "crc32", crc);
    add_str(mesh, "crc_of", h->mesh_crc_of ? h->mesh_crc_of : "positions");
    cJSON_AddNumberToObject(mesh, "vertices", (double)h->mesh_vertices);
    add_str(o, "rig", h->rig_path);
    cJSON *map = cJSON_AddObjectToObject(o, "mapping");
    add_str(map, "name", h->mapping);
    cJSON *keys = cJSON_AddObjectToObject(map, "keys");
    for (size_t i = 0; i < h->mapping_key_count; i++)
        cJSON_AddStringToObject(keys, h->mapping_keys[i].key, h->mapping_keys[i].value);
    cJSON *inputs = cJSON_AddArrayToObject(o, "inputs");
    for (size_t i = 0; i < h->input_count; i++)
        cJSON_AddItemToArray(inputs, cJSON_CreateString(h->inputs[i]));
    cJSON *cal = cJSON_AddArrayToObject(o, "calibration");
    for (int k = 0; k < FP_HANDS; k++) {
        const fp_take_calibration *c = &h->calibration[k];
        if (!c->present) {
            cJSON_AddItemToArray(cal, cJSON_CreateNull());
            continue;
        }
        cJSON *e = cJSON_CreateObject();
        add_number(e, "scale", c->scale);
        cJSON_AddItemToObject(e, "rotation", darray(c->rotation, 4));
        cJSON_AddItemToObject(e, "offset", darray(c->offset, 3));
        cJSON_AddItemToArray(cal, e);
    }
    if (h->performer_count) { /* 1.3 */
        cJSON *ps = cJSON_AddArrayToObject(o, "performers");
        for (size_t k = 0; k < h->performer_count; k++) {
            const fp_take_performer *p = &h->performers[k];
            cJSON *e = cJSON_CreateObject();
            cJSON_AddStringToObject(e, "name", p->name);
            add_number(e, "scale", p->scale);
            cJSON_AddItemToObject(e, "rotation", darray(p->rotation, 4));
            cJSON_AddItemToObject(e, "offset", darray(p->offset, 3));
            cJSON *ho = cJSON_AddArrayToObject(e, "hand_offset");
            for (int hand = 0; hand < FP_HANDS; hand++) cJSON_AddItemToArray(ho, darray(p->hand_offset[hand], 3));
            cJSON_AddItemToArray(ps, e);
        }
    }
    if (h->face_up[0] || h->face_up[1] || h->face_up[2]) { /* 1.4 */
        cJSON *f = cJSON_AddObjectToObject(o, "face");
        cJSON_AddItemToObject(f, "up", darray(h->face_up, 3));
        cJSON_AddItemToObject(f, "facing", darray(h->face_facing, 3));
    }
    add_number(o, "radius", h->radius);
    add_str(o, "description", h->description ? h->description : "");
    cJSON_AddNumberToObject(o, "rating", h->rating);
    if (h->soundtrack_path) { /* 1.2: written only where there is one (takes without stay as 1.1 wrote them) */
        cJSON *st = cJSON_AddObjectToObject(o, "soundtrack");
        add_str(st, "path", h->soundtrack_path);
        snprintf(crc, sizeof crc, "%08" PRIx32, h->soundtrack_crc32);
        cJSON_AddStringToObject(st, "crc32", crc);
        add_number(st, "offset_s", h->soundtrack_offset_s);
    }
    if (h->timecode_source) add_str(o, "timecode_source", h->timecode_source);
    if (h->audio_in_path) { /* 1.2, optional: the microphone's WAV beside the take */
        cJSON *ai = cJSON_AddObjectToObject(o, "audio_in");
        add_str(ai, "path", h->audio_in_path);
        add_str(ai, "device", h->audio_in_device ? h->audio_in_device : "");
    }
    char *text = cJSON_PrintUnformatted(o);
    cJSON_Delete(o);
    return text;
}

/* Strings of a parsed header live in one block: measure, then copy. */
typedef struct strstore {
    char *buf;
    size_t used, cap;
} strstore;

static const char *keep(strstore *s, const char *v)
{
    if (!v) return NULL;
    size_t n = strlen(v) + 1;
    if (!s->buf) {
        s->used += n;   /* measuring pass */
        return "";
    }
    char *p = s->buf + s->used;
    memcpy(p, v, n);
    s->used += n;
    return p;
}

static const char *jstr(const cJSON *o, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsString(v) ? v->valuestring : NULL;
}

static bool jnum(const cJSON *o, const char *key, double *out)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) return false;
    *out = v->valuedouble;
    return true;
}

/* Array a of n finite numbers into out. */
static bool jdvec(const cJSON *a, double *out, int n)
{
    if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) != n) return false;
    for (int i = 0; i < n; i++) {
        const cJSON *v = cJSON_GetArrayItem(a, i);
        if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) return false;
        out[i] = v->valuedouble;
    }
    return true;
}

static bool jdarray(const cJSON *o, const char *key, double *out, int n)
{
    return jdvec(cJSON_GetObjectItemCaseSensitive(o, key), out, n);
}

/* The header's "face" (1.4, optional): two axes as --up and --facing gave them, 3 numbers
 * each, neither a zero vector. 0 or -EBADMSG with the message. */
static int read_face(const cJSON *o, fp_take_header *h, char *msg, size_t msglen)
{
    const cJSON *face = cJSON_GetObjectItemCaseSensitive(o, "face");
    if (!face) return 0;
    if (!(cJSON_IsObject(face) && jdarray(face, "up", h->face_up, 3) && jdarray(face, "facing", h->face_facing, 3)))
        return fp_errorf(msg, msglen, -EBADMSG, "header: invalid \"face\" (up and facing, 3 numbers each)");
    double nu = 0, nf = 0;
    for (int i = 0; i < 3; i++) nu += h->face_up[i] * h->face_up[i], nf += h->face_facing[i] * h->face_facing[i];
    if (!(nu > 1e-12) || !(nf > 1e-12))
        return fp_errorf(msg, msglen, -EBADMSG, "header: invalid \"face\" (up or facing is a zero vector)");
    return 0;
}

static int fill_header(const cJSON *o, fp_take_header *h, strstore *st, char *msg, size_t msglen)
{
    double d;
    const char *s;
    memset(h, 0, sizeof *h);
    if (!cJSON_IsObject(o)) return fp_errorf(msg, msglen, -EBADMSG, "header is not a JSON object");
    s = jstr(o, "format");
    if (!s || strcmp(s, "facepuppet-take"))
        return fp_errorf(msg, msglen, -EBADMSG, "header: \"format\" is not \"facepuppet-take\"");
    s = jstr(o, "slate");
    if (!s || !fp_take_slate_valid(s))
        return fp_errorf(msg, msglen, -EBADMSG, "header: missing or invalid \"slate\"");
    snprintf(h->slate, sizeof h->slate, "%s", s);
    if (!jnum(o, "take", &d) || d < 1 || d > UINT32_MAX || d != floor(d)) /* (numbers start at 1) */
        return fp_errorf(msg, msglen, -EBADMSG, "header: missing or invalid \"take\"");
    h->take = (uint32_t)d;
    const cJSON *rate = cJSON_GetObjectItemCaseSensitive(o, "frame_rate");
    double num, den;
    if (!jnum(rate, "num", &num) || !jnum(rate, "den", &den) || num < 1 || den < 1 ||
        num > UINT32_MAX || den > UINT32_MAX || num != floor(num) || den != floor(den))
        return fp_errorf(msg, msglen, -EBADMSG, "header: missing or invalid \"frame_rate\"");
    h->rate.num = (uint32_t)num;
    h->rate.den = (uint32_t)den;
    if (!take_rate_ok(h->rate)) /* (2^31 fps made timecodes like 15:37:04:1109533224) */
        return fp_errorf(msg, msglen, -EBADMSG, "header: \"frame_rate\" %u/%u is not 1 to %d fps",
                         h->rate.num, h->rate.den, TAKE_RATE_MAX);
    s = jstr(o, "timecode_in");
    char tcerr[128];
    if (!s || fp_timecode_parse(s, h->rate, &h->timecode_in, tcerr, sizeof tcerr))
        return fp_errorf(msg, msglen, -EBADMSG, "header: missing or invalid \"timecode_in\"");
    s = jstr(o, "time_origin_ns");
    char *end;
    errno = 0;
    long long t = s ? strtoll(s, &end, 10) : 0;
    if (!s || !*s || *end || errno)
        return fp_errorf(msg, msglen, -EBADMSG, "header: missing or invalid \"time_origin_ns\"");
    h->time_origin_ns = t;
    s = jstr(o, "date");
    snprintf(h->date, sizeof h->date, "%s", s ? s : "");
    const cJSON *mesh = cJSON_GetObjectItemCaseSensitive(o, "mesh");
    if (!cJSON_IsObject(mesh)) return fp_errorf(msg, msglen, -EBADMSG, "header: missing \"mesh\"");
    h->mesh_path = keep(st, jstr(mesh, "path"));
    s = jstr(mesh, "crc32");
    unsigned long crc = s ? strtoul(s, &end, 16) : 0;
    if (!s || !*s || *end || crc > 0xffffffffUL)
        return fp_errorf(msg, msglen, -EBADMSG, "header: missing or invalid \"mesh.crc32\"");
    h->mesh_crc32 = (uint32_t)crc;
    h->mesh_crc_of = keep(st, jstr(mesh, "crc_of"));
    if (jnum(mesh, "vertices", &d) && d >= 0) h->mesh_vertices = (uint64_t)d;
    h->rig_path = keep(st, jstr(o, "rig"));
    /* mapping: an object (or null) whose keys are an object of strings; inputs: an array of
     * strings. (cJSON_ArrayForEach walks objects and arrays alike: "inputs" as an object was
     * read, and "keys" as an array gave keys without a name.) */
    const cJSON *map = cJSON_GetObjectItemCaseSensitive(o, "mapping");
    if (map && !cJSON_IsObject(map) && !cJSON_IsNull(map))
        return fp_errorf(msg, msglen, -EBADMSG, "header: \"mapping\" is not an object");
    h->mapping = keep(st, jstr(map, "name"));
    const cJSON *keys = cJSON_GetObjectItemCaseSensitive(map, "keys"), *k;
    if (keys && !cJSON_IsObject(keys))
        return fp_errorf(msg, msglen, -EBADMSG, "header: \"mapping.keys\" is not an object");
    cJSON_ArrayForEach(k, keys) {
        if (h->mapping_key_count >= FP_TAKE_MAX_KEYS)
            return fp_errorf(msg, msglen, -EBADMSG, "header: \"mapping.keys\" has more than %d "
                             "keys", FP_TAKE_MAX_KEYS);
        if (!cJSON_IsString(k))
            return fp_errorf(msg, msglen, -EBADMSG, "header: \"mapping.keys\" key %zu is not a "
                             "string", h->mapping_key_count);
        h->mapping_keys[h->mapping_key_count].key = keep(st, k->string);
        h->mapping_keys[h->mapping_key_count++].value = keep(st, k->valuestring);
    }
    const cJSON *inputs = cJSON_GetObjectItemCaseSensitive(o, "inputs");
    if (inputs && !cJSON_IsArray(inputs))
        return fp_errorf(msg, msglen, -EBADMSG, "header: \"inputs\" is not an array");
    cJSON_ArrayForEach(k, inputs) {
        if (h->input_count >= FP_TAKE_MAX_INPUTS)
            return fp_errorf(msg, msglen, -EBADMSG, "header: \"inputs\" has more than %d entries",
                             FP_TAKE_MAX_INPUTS);
        if (!cJSON_IsString(k))
            return fp_errorf(msg, msglen, -EBADMSG, "header: \"inputs[%zu]\" is not a string",
                             h->input_count);
        h->inputs[h->input_count++] = keep(st, k->valuestring);
    }
    const cJSON *cal = cJSON_GetObjectItemCaseSensitive(o, "calibration");
    if (cal && !(cJSON_IsArray(cal) && cJSON_GetArraySize(cal) == FP_HANDS))
        return fp_errorf(msg, msglen, -EBADMSG, "header: \"calibration\" is not an array of 2");
    for (int i = 0; cal && i < FP_HANDS; i++) {
        const cJSON *c = cJSON_GetArrayItem(cal, i);
        if (cJSON_IsNull(c)) continue;
        fp_take_calibration *hc = &h->calibration[i];
        if (!jnum(c, "scale", &hc->scale) || !jdarray(c, "rotation", hc->rotation, 4) ||
            !jdarray(c, "offset", hc->offset, 3))
            return fp_errorf(msg, msglen, -EBADMSG, "header: invalid \"calibration\" of hand %d", i);
        hc->present = true;
    }
    const cJSON *ps = cJSON_GetObjectItemCaseSensitive(o, "performers"); /* 1.3 */
    if (ps && !(cJSON_IsArray(ps) && cJSON_GetArraySize(ps) <= FP_PERFORMER_CAPACITY))
        return fp_errorf(msg, msglen, -EBADMSG, "header: \"performers\" is not an array of at most %d",
                         FP_PERFORMER_CAPACITY);
    for (int i = 0; ps && i < cJSON_GetArraySize(ps); i++) {
        const cJSON *c = cJSON_GetArrayItem(ps, i), *ho = cJSON_GetObjectItemCaseSensitive(c, "hand_offset");
        fp_take_performer *p = &h->performers[h->performer_count];
        const char *name = jstr(c, "name");
        if (!name || !fp_text_ok(name, false) || !jnum(c, "scale", &p->scale) || !(p->scale > 0) ||
            !jdarray(c, "rotation", p->rotation, 4) || !jdarray(c, "offset", p->offset, 3) ||
            !(cJSON_IsArray(ho) && cJSON_GetArraySize(ho) == FP_HANDS))
            return fp_errorf(msg, msglen, -EBADMSG, "header: invalid \"performers\"[%d]", i);
        for (int hand = 0; hand < FP_HANDS; hand++)
            if (!jdvec(cJSON_GetArrayItem(ho, hand), p->hand_offset[hand], 3))
                return fp_errorf(msg, msglen, -EBADMSG, "header: invalid \"performers\"[%d] hand_offset", i);
        p->name = keep(st, name);
        h->performer_count++;
    }
    int rc = read_face(o, h, msg, msglen);
    if (rc) return rc;
    if (!jnum(o, "radius", &h->radius) || h->radius < 0)
        return fp_errorf(msg, msglen, -EBADMSG, "header: missing or invalid \"radius\"");
    h->description = keep(st, jstr(o, "description"));
    if (jnum(o, "rating", &d)) {
        if (d < 0 || d > 5) return fp_errorf(msg, msglen, -EBADMSG, "header: \"rating\" not in 0..5");
        h->rating = (int)d;
    }
    const cJSON *snd = cJSON_GetObjectItemCaseSensitive(o, "soundtrack"); /* 1.2 */
    if (snd && !cJSON_IsNull(snd)) {
        const char *path = jstr(snd, "path"), *crc = jstr(snd, "crc32");
        char *end = NULL;
        unsigned long v = crc ? strtoul(crc, &end, 16) : 0;
        if (!cJSON_IsObject(snd) || !path || !crc || !*crc || *end || v > 0xffffffffUL ||
            !jnum(snd, "offset_s", &h->soundtrack_offset_s) || !isfinite(h->soundtrack_offset_s))
            return fp_errorf(msg, msglen, -EBADMSG, "header: invalid \"soundtrack\"");
        h->soundtrack_path = keep(st, path);
        h->soundtrack_crc32 = (uint32_t)v;
    }
    h->timecode_source = keep(st, jstr(o, "timecode_source"));
    const cJSON *ai = cJSON_GetObjectItemCaseSensitive(o, "audio_in"); /* 1.2, optional */
    if (ai && !cJSON_IsNull(ai)) {
        const char *path = jstr(ai, "path"), *dev = jstr(ai, "device");
        if (!cJSON_IsObject(ai) || !path || !*path || strchr(path, '/'))
            return fp_errorf(msg, msglen, -EBADMSG, "header: invalid \"audio_in\" (a file name in the take's folder)");
        h->audio_in_path = keep(st, path);
        h->audio_in_device = keep(st, dev ? dev : "");
    }
    return 0;
}

/* Where the header's JSON (n bytes) holds a NUL: a NUL byte, which cJSON passes over (as
 * white space between tokens; inside a string as a character that ends the C string early),
 * or a \u0000 escape in a string (which cJSON decodes to one). Returns false when none; else
 * true with *at its byte offset and in `where` the place, naming the field: "in \"mesh.path\"",
 * "in \"inputs[1]\"", "in a key of \"mapping.keys\"", "between the fields of the header",
 * "outside the JSON object". A scanner of the JSON's strings and brackets only: all a NUL's
 * place needs (cJSON, after it, checks the rest). */
static bool json_nul(const char *text, size_t n, size_t *at, char *where, size_t len)
{
    enum { DEPTH = 8 };
    struct { bool object, expect_key; unsigned index; const char *key; size_t keylen; } st[DEPTH];
    int depth = 0; /* (containers past DEPTH are counted, not named) */
    bool in_key = false;
    size_t i = 0;
    for (; i < n; i++) {
        const char c = text[i];
        if (c == '\0') break;
        if (c == '"') {
            const size_t start = ++i;
            bool nul = false;
            for (; i < n && text[i] != '"'; i++) {
                if (text[i] == '\0') { nul = true; break; }
                if (text[i] == '\\') {
                    if (n - i >= 6 && !memcmp(text + i + 1, "u0000", 5)) { nul = true; break; }
                    i++;
                }
            }
            in_key = depth > 0 && depth <= DEPTH && st[depth - 1].object && st[depth - 1].expect_key;
            if (nul) break;
            if (in_key) {
                st[depth - 1].key = text + start;
                st[depth - 1].keylen = i - start;
                in_key = false;
            }
            continue;
        }
        if (c == '{' || c == '[') {
            if (depth < DEPTH) {
                st[depth].object = st[depth].expect_key = c == '{';
                st[depth].index = 0;
                st[depth].key = NULL;
                st[depth].keylen = 0;
            }
            depth++;
        } else if ((c == '}' || c == ']') && depth > 0) {
            depth--;
        } else if (c == ',' && depth > 0 && depth <= DEPTH) {
            if (st[depth - 1].object) st[depth - 1].expect_key = true;
            else st[depth - 1].index++;
        } else if (c == ':' && depth > 0 && depth <= DEPTH) {
            st[depth - 1].expect_key = false;
        }
    }
    if (i >= n) return false;
    *at = i;
    if (depth == 0) {
        snprintf(where, len, "outside the JSON object");
        return true;
    }
    /* the path: each container's member that holds the next, and the innermost's, unless the
     * NUL is in a key or between members (then the innermost container is the place) */
    const int top = (depth < DEPTH ? depth : DEPTH) - 1;
    const bool member = !(st[top].object && st[top].expect_key);
    char path[128];
    size_t w = 0;
    for (int d = 0; d <= top - (member ? 0 : 1) && w + 1 < sizeof path; d++) {
        if (st[d].object) {
            if (w && w + 1 < sizeof path) path[w++] = '.';
            for (size_t k = 0; k < st[d].keylen && k < 40 && w + 1 < sizeof path; k++) {
                const unsigned char ch = (unsigned char)st[d].key[k]; /* as plain text */
                path[w++] = ch >= 0x20 && ch < 0x7f && ch != '"' && ch != '\\' ? (char)ch : '?';
            }
        } else {
            int k = snprintf(path + w, sizeof path - w, "[%u]", st[d].index);
            w = k > 0 && (size_t)k < sizeof path - w ? w + (size_t)k : sizeof path - 1;
        }
    }
    path[w] = '\0';
    if (member)
        snprintf(where, len, "in \"%s\"", path);
    else if (w)
        snprintf(where, len, "%s \"%s\"", in_key ? "in a key of" : "between the fields of", path);
    else
        snprintf(where, len, "%s the header", in_key ? "in a key of" : "between the fields of");
    return true;
}

static int name_cmp(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* A key given twice in any object of the header, its path into `where` ("take",
 * "mapping.keys.engage"): cJSON finds the first, so the second would be read nowhere. 1 when
 * one is, -ENOMEM, else 0. Sorted names: a hostile header of a million keys stays n log n. */
static int json_dup(const cJSON *o, const char *path, char *where, size_t len)
{
    size_t k = 0, i = 0;
    for (const cJSON *m = o->child; m; m = m->next) k++;
    if (cJSON_IsObject(o) && k > 1) {
        const char **names = malloc(k * sizeof *names);
        if (!names) return -ENOMEM;
        for (const cJSON *m = o->child; m; m = m->next) names[i++] = m->string ? m->string : "";
        qsort(names, k, sizeof *names, name_cmp);
        for (i = 1; i < k && strcmp(names[i - 1], names[i]); i++) {}
        if (i < k) snprintf(where, len, "%s%s%s", path, *path ? "." : "", names[i]);
        free(names);
        if (i < k) return 1;
    }
    i = 0;
    for (const cJSON *m = o->child; m; m = m->next, i++) {
        if (!cJSON_IsObject(m) && !cJSON_IsArray(m)) continue;
        char sub[200];
        if (cJSON_IsObject(o)) snprintf(sub, sizeof sub, "%s%s%s", path, *path ? "." : "", m->string ? m->string : "");
        else snprintf(sub, sizeof sub, "%s[%zu]", path, i);
        int rc = json_dup(m, sub, where, len);
        if (rc) return rc;
    }
    return 0;
}

int take_header_from_json(const char *text, size_t n, fp_take_header *h, char **store,
                          size_t *bad_at, char *msg, size_t msglen)
{
    *store = NULL;
    *bad_at = 0;
    char where[200];
    if (json_nul(text, n, bad_at, where, sizeof where)) /* (the format says: no NUL) */
        return fp_errorf(msg, msglen, -EBADMSG, "header: a NUL %s", where);
    const char *end = NULL;
    cJSON *o = cJSON_ParseWithLengthOpts(text, n, &end, 0);
    if (!o) {
        *bad_at = (end && end >= text && end <= text + n) ? (size_t)(end - text) : 0;
        return fp_errorf(msg, msglen, -EBADMSG, "header: malformed JSON");
    }
    size_t rest = end && end >= text && end <= text + n ? (size_t)(end - text) : n;
    while (rest < n && (text[rest] == ' ' || text[rest] == '\t' || text[rest] == '\n' ||
                        text[rest] == '\r'))
        rest++;
    if (rest < n) { /* one JSON object: what follows it is damage, not more header */
        cJSON_Delete(o);
        *bad_at = rest;
        return fp_errorf(msg, msglen, -EBADMSG, "header: text after the JSON object");
    }
    int dup = json_dup(o, "", where, sizeof where);
    if (dup) {
        cJSON_Delete(o);
        if (dup < 0) return fp_errorf(msg, msglen, dup, "header: out of memory");
        return fp_errorf(msg, msglen, -EBADMSG, "header: \"%s\" given twice", where);
    }
    strstore st = {0};
    int rc = fill_header(o, h, &st, msg, msglen);   /* measuring pass */
    if (!rc) {
        st.buf = malloc(st.used ? st.used : 1);
        st.cap = st.used;
        st.used = 0;
        rc = st.buf ? fill_header(o, h, &st, msg, msglen) : -ENOMEM;
    }
    cJSON_Delete(o);
    if (rc) {
        free(st.buf);
        return rc;
    }
    *store = st.buf;
    return 0;
}
