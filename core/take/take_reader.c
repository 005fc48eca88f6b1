/* take_reader.c: open a take (signature, header, a scan of every chunk that indexes each
 * intact frame), read frames by index, and list a folder's takes. */
#include "take_internal.h"

#include "fp_error.h"
#include "fp_file.h"

#include <cjson/cJSON.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

typedef struct take_index {
    uint64_t offset;   /* of the frame record in the file */
    uint32_t size;
    int64_t time_ns;   /* the record's time (fp_take_reader_time) */
} take_index;

struct fp_take_reader {
    char *name;
    int fd;                 /* -1 when reading from memory */
    uint8_t *mem;
    uint64_t size;
    fp_take_header header;
    char *store;            /* the header's strings */
    fp_take_summary sum;
    char warning[640];
    take_index *index;
    size_t frames, index_cap;
    size_t next;
    uint8_t *buf;           /* chunk or record bytes */
    size_t buf_cap;
    take_frame_buf fb;
};

/* Read n bytes at off; returns bytes read (short at the end of the file) or -errno. */
static ssize_t src_read(fp_take_reader *r, uint64_t off, void *dst, size_t n)
{
    if (off >= r->size) return 0;
    if (n > r->size - off) n = (size_t)(r->size - off);
    if (r->fd < 0) {
        memcpy(dst, r->mem + off, n);
        return (ssize_t)n;
    }
    size_t got = 0;
    while (got < n) {
        ssize_t k = pread(r->fd, (uint8_t *)dst + got, n - got, (off_t)(off + got));
        if (k < 0) {
            if (errno == EINTR) continue;
            return -errno;
        }
        if (k == 0) break;
        got += (size_t)k;
    }
    return (ssize_t)got;
}

static int buf_reserve(fp_take_reader *r, size_t n)
{
    if (n <= r->buf_cap) return 0;
    size_t c = r->buf_cap ? r->buf_cap : 65536;
    while (c < n) c *= 2;
    uint8_t *b = realloc(r->buf, c);
    if (!b) return -ENOMEM;
    r->buf = b;
    r->buf_cap = c;
    return 0;
}

/* Outcome of looking at one chunk. */
typedef struct chunk_view {
    char type[5];
    uint32_t length, count;
    const uint8_t *payload;   /* r->buf + 16 */
    uint64_t bad_at;          /* file offset of the fault */
    char why[256];
} chunk_view;

/* 1: a whole chunk is in r->buf; 0: the clean end of the file; -EBADMSG: damage (cv->bad_at,
 * cv->why); -errno: I/O. */
static int load_chunk(fp_take_reader *r, uint64_t off, chunk_view *cv)
{
    uint8_t h[TAKE_CHUNK_HEAD_SIZE];
    memset(cv, 0, sizeof *cv);
    if (off == r->size) return 0;
    ssize_t k = src_read(r, off, h, sizeof h);
    if (k < 0) return (int)k;
    cv->bad_at = off;
    if ((size_t)k < sizeof h) {
        snprintf(cv->why, sizeof cv->why, "chunk header cut short (%zd of 16 bytes)", k);
        return -EBADMSG;
    }
    if (memcmp(h, TAKE_CHUNK_MAGIC, 4)) {
        snprintf(cv->why, sizeof cv->why, "bad chunk magic (expected \"FPCK\")");
        return -EBADMSG;
    }
    memcpy(cv->type, h + 4, 4);
    for (int i = 0; i < 4; i++)
        if (cv->type[i] < 0x20 || cv->type[i] > 0x7e) cv->type[i] = '?';
    cv->length = le_get32(h + 8);
    cv->count = le_get32(h + 12);
    if (cv->length > TAKE_CHUNK_MAX_PAYLOAD) {
        cv->bad_at = off + 8;
        snprintf(cv->why, sizeof cv->why, "chunk length %" PRIu32 " beyond the 64 MiB limit",
                 cv->length);
        return -EBADMSG;
    }
    uint64_t total = TAKE_CHUNK_OVERHEAD + (uint64_t)cv->length;
    if (total > r->size - off) {
        snprintf(cv->why, sizeof cv->why,
                 "%.4s chunk of %" PRIu64 " bytes runs past the end of the file (%" PRIu64 " bytes)",
                 cv->type, total, r->size);
        return -EBADMSG;
    }
    if (buf_reserve(r, (size_t)total)) return -ENOMEM;
    k = src_read(r, off, r->buf, (size_t)total);
    if (k < 0) return (int)k;
    if ((uint64_t)k < total) {
        snprintf(cv->why, sizeof cv->why, "file ends inside the %.4s chunk", cv->type);
        return -EBADMSG;
    }
    uint32_t stored = le_get32(r->buf + TAKE_CHUNK_HEAD_SIZE + cv->length);
    uint32_t crc = (uint32_t)crc32(0L, r->buf, (uInt)(TAKE_CHUNK_HEAD_SIZE + cv->length));
    if (stored != crc) {
        snprintf(cv->why, sizeof cv->why,
                 "%.4s chunk crc32 mismatch (stored %08" PRIx32 ", computed %08" PRIx32 ")",
                 cv->type, stored, crc);
        return -EBADMSG;
    }
    cv->payload = r->buf + TAKE_CHUNK_HEAD_SIZE;
    return 1;
}

/* Index the frame records of a FRMS chunk at file offset off. */
static int index_frames(fp_take_reader *r, uint64_t off, chunk_view *cv)
{
    size_t pos = 0, n = cv->length;
    uint32_t i = 0;
    size_t start = r->frames;
    const fp_take_summary before = r->sum; /* (restored if this chunk is damaged) */
    for (; pos < n; i++) {
        uint64_t at = off + TAKE_CHUNK_HEAD_SIZE + pos;
        if (n - pos < 4) {
            cv->bad_at = at;
            snprintf(cv->why, sizeof cv->why, "frame record size cut short");
            goto bad;
        }
        uint32_t sz = le_get32(cv->payload + pos);
        if (sz < TAKE_FRAME_FIXED || sz > n - pos) {
            cv->bad_at = at;
            snprintf(cv->why, sizeof cv->why, "frame record size %" PRIu32 " out of range", sz);
            goto bad;
        }
        size_t bad_at;
        char why[128];
        if (take_frame_check(cv->payload + pos, sz, r->header.input_count, &bad_at, why, sizeof why)) {
            cv->bad_at = at + bad_at;
            snprintf(cv->why, sizeof cv->why, "frame %zu (its record at byte %" PRIu64 "): %s",
                     r->frames, at, why);
            goto bad;
        }
        {   /* frames in order: numbers and times never go back (a clock's jump or a patched
             * record would play out of order, or end a replay early) */
            const uint64_t fn = le_get64(cv->payload + pos + 8);
            const int64_t t = (int64_t)le_get64(cv->payload + pos + 16);
            if (r->frames > 0 && fn < r->sum.last_frame) {
                cv->bad_at = at + 8;
                snprintf(cv->why, sizeof cv->why,
                         "frame record at byte %" PRIu64 ": frame %" PRIu64 " after frame %" PRIu64,
                         at, fn, r->sum.last_frame);
                goto bad;
            }
            if (r->frames > 0 && t < r->sum.last_time_ns) {
                cv->bad_at = at + 16;
                snprintf(cv->why, sizeof cv->why,
                         "frame record at byte %" PRIu64 ": time %" PRId64 " ns goes back from %" PRId64,
                         at, t, r->sum.last_time_ns);
                goto bad;
            }
        }
        if (r->frames == r->index_cap) {
            size_t c = r->index_cap ? 2 * r->index_cap : 1024;
            take_index *x = realloc(r->index, c * sizeof *x);
            if (!x) return -ENOMEM;
            r->index = x;
            r->index_cap = c;
        }
        r->index[r->frames].offset = at;
        r->index[r->frames].time_ns = (int64_t)le_get64(cv->payload + pos + 16);
        r->index[r->frames++].size = sz;
        const uint8_t *rec = cv->payload + pos;
        uint64_t fn = le_get64(rec + 8);
        int64_t t = (int64_t)le_get64(rec + 16);
        if (r->sum.frames == 0 && r->frames == 1) {
            r->sum.first_frame = fn;
            r->sum.first_time_ns = t;
        }
        r->sum.last_frame = fn;
        r->sum.last_time_ns = t;
        pos += sz;
    }
    if (i != cv->count) {
        cv->bad_at = off + 12;
        snprintf(cv->why, sizeof cv->why, "FRMS chunk says %" PRIu32 " frames, holds %" PRIu32,
                 cv->count, i);
        goto bad;
    }
    return 0;
bad:
    r->frames = start;   /* none of a damaged chunk's frames are played, nor summed */
    r->sum = before;
    return -EBADMSG;
}

static int read_tail(fp_take_reader *r, chunk_view *cv, uint64_t off)
{
    cJSON *o = cJSON_ParseWithLength((const char *)cv->payload, cv->length);
    const cJSON *v;
    if (!o) {
        cv->bad_at = off + TAKE_CHUNK_HEAD_SIZE;
        snprintf(cv->why, sizeof cv->why, "TAIL chunk: malformed JSON");
        return -EBADMSG;
    }
    /* the frames the writer wrote (take_writer.c): fewer here is a chunk of them gone from
     * the middle, its neighbours whole; the take is cut, not closed normally */
    if (cJSON_IsNumber(v = cJSON_GetObjectItemCaseSensitive(o, "frames")) && v->valuedouble != (double)r->frames) {
        cv->bad_at = off + TAKE_CHUNK_HEAD_SIZE;
        snprintf(cv->why, sizeof cv->why, "TAIL chunk says %.0f frames, the file holds %zu before it "
                 "(a chunk of frames is missing)", v->valuedouble, r->frames);
        cJSON_Delete(o);
        return -EBADMSG;
    }
    r->sum.complete = true;
    if (cJSON_IsNumber(v = cJSON_GetObjectItemCaseSensitive(o, "dropped")) && v->valuedouble >= 0)
        r->sum.dropped = (uint64_t)v->valuedouble;
    if (cJSON_IsNumber(v = cJSON_GetObjectItemCaseSensitive(o, "status")))
        r->sum.end_status = (int)v->valuedouble;
    const cJSON *re = cJSON_GetObjectItemCaseSensitive(o, "reach"), *n, *md, *p, *l;
    if (cJSON_IsObject(re) && cJSON_IsNumber(n = cJSON_GetObjectItemCaseSensitive(re, "vectors")) &&
        cJSON_IsNumber(md = cJSON_GetObjectItemCaseSensitive(re, "median")) &&
        cJSON_IsNumber(p = cJSON_GetObjectItemCaseSensitive(re, "p10")) && n->valuedouble >= 1 &&
        n->valuedouble < 1e18 && isfinite(md->valuedouble) && isfinite(p->valuedouble)) {
        r->sum.reach.vectors = (uint64_t)n->valuedouble;
        r->sum.reach.median = md->valuedouble;
        r->sum.reach.p10 = p->valuedouble;
        l = cJSON_GetObjectItemCaseSensitive(re, "longest_drag_mm");
        r->sum.reach.longest_drag_mm = cJSON_IsNumber(l) && isfinite(l->valuedouble) ? l->valuedouble : 0;
        l = cJSON_GetObjectItemCaseSensitive(re, "held"); /* (vectors on the skull or the jaw) */
        if (cJSON_IsNumber(l) && l->valuedouble >= 1 && l->valuedouble <= n->valuedouble)
            r->sum.reach.held = (uint64_t)l->valuedouble;
    }
    cJSON_Delete(o);
    return 0;
}

/* A cut at r->sum.cut_offset: what lies after it (summary.after_*), from a scan for whole
 * chunks (each "FPCK" whose chunk checks: magic, length, crc32; its frames not indexed), and
 * said after the warning. Best effort: an I/O error ends the scan. */
static void note_after_cut(fp_take_reader *r)
{
    const uint64_t cut = r->sum.cut_offset;
    r->sum.after_bytes = r->size - cut;
    uint8_t win[4096];
    chunk_view cv;
    for (uint64_t off = cut + 1; off + TAKE_CHUNK_OVERHEAD <= r->size;) {
        ssize_t k = src_read(r, off, win, sizeof win);
        if (k < 4) break;
        size_t i = 0;
        while (i + 4 <= (size_t)k && memcmp(win + i, TAKE_CHUNK_MAGIC, 4)) i++;
        if (i + 4 > (size_t)k) { /* (the magic may straddle the window's end) */
            off += (uint64_t)k - 3;
            continue;
        }
        off += i;
        if (load_chunk(r, off, &cv) != 1) {
            off++;
            continue;
        }
        if (!memcmp(cv.type, TAKE_TYPE_FRAMES, 4)) {
            r->sum.after_frames += cv.count;
        } else if (!memcmp(cv.type, TAKE_TYPE_TAIL, 4)) {
            cJSON *o = cJSON_ParseWithLength((const char *)cv.payload, cv.length);
            const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, "frames");
            if (cJSON_IsNumber(v) && v->valuedouble >= 0 && v->valuedouble < 1e15)
                r->sum.after_total = (uint64_t)v->valuedouble;
            cJSON_Delete(o);
        }
        off += TAKE_CHUNK_OVERHEAD + cv.length;
    }
    size_t w = strlen(r->warning);
    char total[96] = "";
    if (r->sum.after_total)
        snprintf(total, sizeof total, ", of the %" PRIu64 " the end chunk counts", r->sum.after_total);
    snprintf(r->warning + w, sizeof r->warning - w, "; the %" PRIu64 " bytes from there are not read: "
             "%" PRIu64 " frames in whole chunks past the damage%s", r->sum.after_bytes,
             r->sum.after_frames, total);
}

static int open_common(fp_take_reader *r, char *err, size_t errlen)
{
    uint8_t sig[TAKE_SIG_SIZE], want[TAKE_SIG_SIZE];
    ssize_t k = src_read(r, 0, sig, sizeof sig);
    if (k < 0) return fp_errorf(err, errlen, (int)k, "%s: %s", r->name, strerror((int)-k));
    take_signature(want);
    if (memcmp(sig, want, k < 8 ? (size_t)k : 8) || k == 0)
        return fp_errorf(err, errlen, -EBADMSG, "%s: byte 0: not a facepuppet take (bad signature)",
                         r->name);
    if ((size_t)k < sizeof sig)
        return fp_errorf(err, errlen, -EBADMSG, "%s: byte %zd: file ends inside the signature "
                         "(%zd of 16 bytes)", r->name, k, k);
    if (le_get32(sig + 12) != (uint32_t)crc32(0L, sig, 12))
        return fp_errorf(err, errlen, -EBADMSG, "%s: byte 12: signature crc32 mismatch", r->name);
    unsigned major = le_get16(sig + 8), minor = le_get16(sig + 10);
    if (major != FP_TAKE_VERSION_MAJOR)
        return fp_errorf(err, errlen, -ENOTSUP, "%s: byte 8: take format version %u.%u; this "
                         "reader knows %d.x", r->name, major, minor, FP_TAKE_VERSION_MAJOR);
    r->sum.version_major = major;
    r->sum.version_minor = minor;

    chunk_view cv;
    uint64_t off = TAKE_SIG_SIZE;
    int rc = load_chunk(r, off, &cv);
    if (rc == 0)
        return fp_errorf(err, errlen, -EBADMSG, "%s: byte %" PRIu64 ": file ends before the "
                         "header chunk", r->name, off);
    if (rc == -EBADMSG)
        return fp_errorf(err, errlen, rc, "%s: byte %" PRIu64 ": header: %s", r->name, cv.bad_at,
                         cv.why);
    if (rc < 0) return fp_errorf(err, errlen, rc, "%s: %s", r->name, fp_strerror(rc));
    if (memcmp(cv.type, TAKE_TYPE_HEAD, 4))
        return fp_errorf(err, errlen, -EBADMSG, "%s: byte %" PRIu64 ": first chunk is %.4s, "
                         "expected HEAD", r->name, off + 4, cv.type);
    size_t bad_at;
    char msg[256];
    rc = take_header_from_json((const char *)cv.payload, cv.length, &r->header, &r->store,
                               &bad_at, msg, sizeof msg);
    if (rc)
        return fp_errorf(err, errlen, rc, "%s: byte %" PRIu64 ": %s", r->name,
                         off + TAKE_CHUNK_HEAD_SIZE + bad_at, msg);
    off += TAKE_CHUNK_OVERHEAD + cv.length;

    for (;;) {
        rc = load_chunk(r, off, &cv);
        if (rc == 0) break;
        if (rc == 1) {
            if (!memcmp(cv.type, TAKE_TYPE_FRAMES, 4)) rc = index_frames(r, off, &cv);
            else if (!memcmp(cv.type, TAKE_TYPE_TAIL, 4)) rc = read_tail(r, &cv, off);
            else if (!memcmp(cv.type, TAKE_TYPE_HEAD, 4)) {
                snprintf(cv.why, sizeof cv.why, "a second HEAD chunk");
                cv.bad_at = off;
                rc = -EBADMSG;
            } else {
                rc = 0;   /* a chunk type of a later minor version: skipped */
            }
        }
        if (rc == -ENOMEM) return fp_errorf(err, errlen, rc, "%s: out of memory", r->name);
        if (rc == -EBADMSG) {
            r->sum.cut = true;
            r->sum.cut_offset = off;
            if (cv.bad_at == off)
                snprintf(r->warning, sizeof r->warning, "%s: cut at byte %" PRIu64 ": %s", r->name,
                         off, cv.why);
            else
                snprintf(r->warning, sizeof r->warning, "%s: cut at byte %" PRIu64 ": %s (byte %"
                         PRIu64 ")", r->name, off, cv.why, cv.bad_at);
            note_after_cut(r);
            break;
        }
        if (rc < 0) return fp_errorf(err, errlen, rc, "%s: %s", r->name, fp_strerror(rc));
        off += TAKE_CHUNK_OVERHEAD + cv.length;
    }
    r->sum.frames = r->frames;
    r->sum.file_size = r->size;
    if (!r->frames) {
        r->sum.first_frame = r->sum.last_frame = 0;
        r->sum.first_time_ns = r->sum.last_time_ns = 0;
    }
    r->sum.duration_s = (double)(r->sum.last_time_ns - r->sum.first_time_ns) / 1e9;
    uint64_t f0 = 0;
    fp_timecode_to_frames(&r->header.timecode_in, r->header.rate, &f0);
    uint64_t df = r->frames ? fp_take_frames_at(r->sum.last_time_ns - r->header.time_origin_ns,
                                                r->header.rate) : 0;
    fp_timecode_from_frames(f0 + df, r->header.rate, r->header.timecode_in.drop,
                            &r->sum.timecode_out);
    return 0;
}

static fp_take_reader *new_reader(const char *name)
{
    fp_take_reader *r = calloc(1, sizeof *r);
    if (!r) return NULL;
    r->fd = -1;
    r->name = strdup(name ? name : "(memory)");
    if (!r->name) {
        free(r);
        return NULL;
    }
    return r;
}

int fp_take_reader_open(const char *path, fp_take_reader **out, char *err, size_t errlen)
{
    *out = NULL;
    if (!path) return fp_errorf(err, errlen, -EINVAL, "take: no file given");
    fp_take_reader *r = new_reader(path);
    if (!r) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", path);
    r->fd = fp_file_open_regular(path); /* a FIFO or a device cannot hold the open */
    struct stat st;
    int rc;
    if (r->fd < 0) {
        rc = fp_errorf(err, errlen, r->fd, "%s: %s", path, fp_file_error_text(r->fd));
        r->fd = -1;
    } else if (fstat(r->fd, &st) < 0) { /* for the size (fp_file_open_regular checked the type) */
        rc = fp_errorf(err, errlen, -errno, "%s: %s", path, strerror(errno));
    } else {
        r->size = (uint64_t)st.st_size;
        rc = open_common(r, err, errlen);
    }
    if (rc) {
        fp_take_reader_close(&r);
        return rc;
    }
    *out = r;
    return 0;
}

int fp_take_reader_open_memory(const void *data, size_t n, const char *name,
                               fp_take_reader **out, char *err, size_t errlen)
{
    *out = NULL;
    fp_take_reader *r = new_reader(name);
    if (!r || !(r->mem = malloc(n ? n : 1))) {
        fp_take_reader_close(&r);
        return fp_errorf(err, errlen, -ENOMEM, "take: out of memory");
    }
    if (n) memcpy(r->mem, data, n);
    r->size = n;
    int rc = open_common(r, err, errlen);
    if (rc) {
        fp_take_reader_close(&r);
        return rc;
    }
    *out = r;
    return 0;
}

const fp_take_header *fp_take_reader_header(const fp_take_reader *r) { return &r->header; }
const fp_take_summary *fp_take_reader_summary(const fp_take_reader *r) { return &r->sum; }
const char *fp_take_reader_warning(const fp_take_reader *r) { return r->warning; }
size_t fp_take_reader_frames(const fp_take_reader *r) { return r->frames; }
int64_t fp_take_reader_time(const fp_take_reader *r, size_t index)
{
    return index < r->frames ? r->index[index].time_ns : INT64_MIN;
}

int fp_take_reader_read(fp_take_reader *r, size_t index, fp_take_frame *frame, char *err,
                        size_t errlen)
{
    if (index >= r->frames)
        return fp_errorf(err, errlen, -ERANGE, "%s: frame %zu of %zu", r->name, index, r->frames);
    const take_index *x = &r->index[index];
    if (buf_reserve(r, x->size)) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", r->name);
    ssize_t k = src_read(r, x->offset, r->buf, x->size);
    if (k < 0) return fp_errorf(err, errlen, (int)k, "%s: %s", r->name, strerror((int)-k));
    size_t bad_at;
    char why[128] = "record cut short";
    if ((size_t)k != x->size ||
        take_frame_check(r->buf, x->size, r->header.input_count, &bad_at, why, sizeof why))
        return fp_errorf(err, errlen, -EBADMSG, "%s: byte %" PRIu64 ": the file changed: %s",
                         r->name, x->offset, why);
    if (take_frame_decode(r->buf, x->size, &r->fb, frame))
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", r->name);
    r->next = index + 1;
    return 0;
}

int fp_take_reader_next(fp_take_reader *r, fp_take_frame *frame, char *err, size_t errlen)
{
    if (r->next >= r->frames) return 0;
    int rc = fp_take_reader_read(r, r->next, frame, err, errlen);
    return rc ? rc : 1;
}

void fp_take_reader_close(fp_take_reader **rp)
{
    fp_take_reader *r = rp ? *rp : NULL;
    if (!r) return;
    if (r->fd >= 0) close(r->fd);
    free(r->mem);
    free(r->name);
    free(r->store);
    free(r->index);
    free(r->buf);
    take_frame_buf_free(&r->fb);
    free(r);
    *rp = NULL;
}

/* ---- listing -------------------------------------------------------------------------- */

static int info_cmp(const void *a, const void *b)
{
    const fp_take_info *x = a, *y = b;
    int c = strcmp(x->slate, y->slate);
    if (c) return c;
    if (x->take != y->take) return x->take < y->take ? -1 : 1;
    return strcmp(x->path, y->path);
}

int fp_take_list(const char *dir, fp_take_info **out, size_t *count, char *err, size_t errlen)
{
    *out = NULL;
    *count = 0;
    DIR *d = opendir(dir);
    if (!d) return fp_errorf(err, errlen, -errno, "%s: %s", dir, strerror(errno));
    fp_take_info *v = NULL;
    size_t n = 0, cap = 0;
    struct dirent *e;
    size_t el = strlen(FP_TAKE_EXTENSION);
    while ((e = readdir(d))) {
        size_t nl = strlen(e->d_name);
        if (nl <= el || strcmp(e->d_name + nl - el, FP_TAKE_EXTENSION) || e->d_name[0] == '.')
            continue;
        if (n == cap) {
            size_t c = cap ? 2 * cap : 16;
            fp_take_info *x = realloc(v, c * sizeof *x);
            if (!x) {
                free(v);
                closedir(d);
                return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", dir);
            }
            v = x;
            cap = c;
        }
        fp_take_info *t = &v[n++];
        memset(t, 0, sizeof *t);
        snprintf(t->path, sizeof t->path, "%s/%s", dir, e->d_name);
        fp_take_reader *r;
        t->error = fp_take_reader_open(t->path, &r, t->message, sizeof t->message);
        if (t->error) {
            /* Still list it under the slate and number its name gives. */
            snprintf(t->slate, sizeof t->slate, "%.*s", (int)(nl - el < sizeof t->slate - 1 ? nl - el
                                                                 : sizeof t->slate - 1), e->d_name);
            char *u = strrchr(t->slate, '_');
            if (u && u[1] == 'T') {
                t->take = (uint32_t)strtoul(u + 2, NULL, 10);
                *u = '\0';
            }
            continue;
        }
        const fp_take_header *h = fp_take_reader_header(r);
        const fp_take_summary *s = fp_take_reader_summary(r);
        snprintf(t->slate, sizeof t->slate, "%s", h->slate);
        t->take = h->take;
        t->rate = h->rate;
        t->timecode_in = h->timecode_in;
        t->timecode_out = s->timecode_out;
        t->duration_s = s->duration_s;
        t->frames = s->frames;
        snprintf(t->mesh, sizeof t->mesh, "%s", h->mesh_path ? h->mesh_path : "");
        snprintf(t->mapping, sizeof t->mapping, "%s", h->mapping ? h->mapping : "");
        t->rating = h->rating;
        snprintf(t->date, sizeof t->date, "%s", h->date);
        snprintf(t->description, sizeof t->description, "%s", h->description ? h->description : "");
        t->complete = s->complete;
        t->reach = s->reach;
        snprintf(t->message, sizeof t->message, "%s", fp_take_reader_warning(r));
        fp_take_reader_close(&r);
    }
    closedir(d);
    if (n) qsort(v, n, sizeof *v, info_cmp);
    *out = v;
    *count = n;
    return 0;
}
