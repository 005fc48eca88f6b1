/* take_writer.c: take numbering and the synchronous writer (signature, header chunk, frames
 * batched into chunks, end chunk). The recorder runs one on its own thread. */
#include "take_internal.h"

#include "fp_error.h"
#include "fp_file.h"

#include <assert.h>
#include <cjson/cJSON.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include <zlib.h>

/* ---- naming --------------------------------------------------------------------------- */

int fp_take_filename(const char *slate, uint32_t take, char *buf, size_t n)
{
    if (!fp_take_slate_valid(slate) || !take) return -EINVAL;
    int k = snprintf(buf, n, "%s_T%03" PRIu32 "%s", slate, take, FP_TAKE_EXTENSION);
    return (k < 0 || (size_t)k >= n) ? -EINVAL : 0;
}

int fp_take_audio_in_name(const char *slate, uint32_t take, char *buf, size_t n)
{
    if (!fp_take_slate_valid(slate) || !take) return -EINVAL;
    int k = snprintf(buf, n, "%s_T%03" PRIu32 ".mic.wav", slate, take);
    return (k < 0 || (size_t)k >= n) ? -EINVAL : 0;
}

/* The take number of `name` if it is SLATE_TNNN.fptake of this slate, else 0. */
static uint32_t name_take(const char *name, const char *slate)
{
    size_t sl = strlen(slate), el = strlen(FP_TAKE_EXTENSION), nl = strlen(name);
    if (nl <= sl + 2 + el || strncmp(name, slate, sl) || name[sl] != '_' || name[sl + 1] != 'T' ||
        strcmp(name + nl - el, FP_TAKE_EXTENSION))
        return 0;
    uint64_t v = 0;
    const char *p = name + sl + 2, *end = name + nl - el;
    if (end - p > 10) return 0;
    for (; p < end; p++) {
        if (*p < '0' || *p > '9') return 0;
        v = 10 * v + (uint64_t)(*p - '0');
    }
    return v > UINT32_MAX - 1 ? 0 : (uint32_t)v;
}

int fp_take_next_number(const char *dir, const char *slate, uint32_t *take, char *err,
                        size_t errlen)
{
    if (!dir || !take || !fp_take_slate_valid(slate))
        return fp_errorf(err, errlen, -EINVAL, "take: invalid slate \"%s\"", slate ? slate : "(null)");
    DIR *d = opendir(dir);
    if (!d) {
        if (errno == ENOENT) {
            *take = 1;
            return 0;
        }
        return fp_errorf(err, errlen, -errno, "%s: %s", dir, strerror(errno));
    }
    uint32_t best = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        uint32_t t = name_take(e->d_name, slate);
        if (t > best) best = t;
    }
    closedir(d);
    *take = best + 1;
    return 0;
}

/* ---- writer --------------------------------------------------------------------------- */

struct fp_take_writer {
    int fd;
    char *path;
    uint32_t take;
    fp_take_rate rate;
    fp_timecode tc_in;
    int64_t origin_ns;
    fp_take_writer_options opt;
    uint8_t *buf;           /* [16 chunk header][payload][4 crc] */
    size_t cap, used;       /* used: payload bytes; TAKE_CHUNK_OVERHEAD + used <= cap */
    uint32_t pending;       /* frames in the payload: 0 exactly when used is 0 (between
                               chunks; a JSON chunk is written from an empty payload) */
    uint64_t offset;        /* bytes on disk = end of the last whole chunk */
    uint64_t synced;        /* bytes fdatasync'd (offset where every chunk was synced) */
    uint64_t frames;        /* frames on disk */
    int64_t last_time_ns;
    bool any_frame;
    int error;
    char errmsg[512];       /* the write error's message */
    fp_take_reach reach;    /* for the TAIL (vectors = 0: none) */
};

void fp_take_writer_set_reach(fp_take_writer *w, const fp_take_reach *reach)
{
    if (w && reach) w->reach = *reach;
}

const char *fp_take_writer_path(const fp_take_writer *w) { return w->path; }
uint32_t fp_take_writer_take(const fp_take_writer *w) { return w->take; }
size_t fp_take_writer_pending(const fp_take_writer *w) { return w->pending; }
uint64_t take_writer_frames(const fp_take_writer *w) { return w->frames; }
uint64_t take_writer_bytes(const fp_take_writer *w) { return w->offset; }

/* write() all of it, or fail with the errno (ENOSPC from a short write's retry). */
static int write_all(int fd, const void *p, size_t n)
{
    const uint8_t *b = p;
    while (n) {
        ssize_t k = write(fd, b, n);
        if (k < 0) {
            if (errno == EINTR) continue;
            return -errno;
        }
        if (k == 0) return -EIO;
        b += k;
        n -= (size_t)k;
    }
    return 0;
}

static int reserve(fp_take_writer *w, size_t payload)
{
    size_t need = TAKE_CHUNK_OVERHEAD + payload;
    if (need <= w->cap) return 0;
    size_t c = w->cap ? w->cap : 65536;
    while (c < need) c *= 2;
    uint8_t *b = realloc(w->buf, c);
    if (!b) return -ENOMEM;
    w->buf = b;
    w->cap = c;
    return 0;
}

/* The chunk state between calls: the payload fits the buffer and the format's chunk limit,
 * and frames are pending exactly when the payload holds bytes. */
static void assert_chunk_state(const fp_take_writer *w)
{
    assert(w->used == 0 || (w->buf && TAKE_CHUNK_OVERHEAD + w->used <= w->cap));
    assert(w->used <= TAKE_CHUNK_MAX_PAYLOAD);
    assert((w->pending == 0) == (w->used == 0));
    assert(w->offset >= TAKE_SIG_SIZE || w->offset == 0);
    (void)w;
}

/* Whether the open file no longer has a name (unlinked, or its folder removed): every write
 * still succeeds, and the take is gone when the file is closed. */
static bool file_gone(int fd)
{
    struct stat st;
    return fstat(fd, &st) == 0 && st.st_nlink == 0;
}

/* Write one chunk from w->buf (payload already at buf + 16; a file deleted meanwhile is an
 * error, -ENOENT, checked after each chunk). */
static int write_chunk(fp_take_writer *w, const char type[4], uint32_t count, char *err,
                       size_t errlen)
{
    if (w->error) return w->error;
    assert(w->buf && TAKE_CHUNK_OVERHEAD + w->used <= w->cap && w->used <= TAKE_CHUNK_MAX_PAYLOAD);
    assert(count == w->pending); /* FRMS: every pending frame; HEAD and TAIL: none pending */
    take_chunk_head(w->buf, type, (uint32_t)w->used, count);
    uint32_t crc = (uint32_t)crc32(0L, w->buf, (uInt)(TAKE_CHUNK_HEAD_SIZE + w->used));
    le_put32(w->buf + TAKE_CHUNK_HEAD_SIZE + w->used, crc);
    size_t n = TAKE_CHUNK_OVERHEAD + w->used;
    int rc = write_all(w->fd, w->buf, n);
    bool later = w->opt.sync_later && !memcmp(type, TAKE_TYPE_FRAMES, 4); /* (the caller's) */
    if (!rc && !w->opt.no_sync && !later && fdatasync(w->fd) < 0 && errno != EINVAL && errno != EROFS)
        rc = -errno;
    bool gone = !rc && file_gone(w->fd);
    if (gone) rc = -ENOENT;
    if (rc) {
        w->error = rc;
        /* Cut back to the last whole chunk so the file ends cleanly (ftruncate frees space). */
        if (ftruncate(w->fd, (off_t)w->offset) == 0) lseek(w->fd, (off_t)w->offset, SEEK_SET);
        if (gone) /* (writes to a file no folder holds succeed: the take would vanish at close) */
            fp_errorf(w->errmsg, sizeof w->errmsg, rc, "%s: the file was deleted while recording "
                      "(its folder removed?): its %" PRIu64 " frames are lost", w->path,
                      w->frames + w->pending);
        else
            fp_errorf(w->errmsg, sizeof w->errmsg, rc, "%s: writing a %.4s chunk at byte %" PRIu64
                      ": %s", w->path, type, w->offset, strerror(-rc));
        return fp_errorf(err, errlen, rc, "%s", w->errmsg);
    }
    w->offset += n;
    if (!later) w->synced = w->offset;
    w->used = 0;
    return 0;
}

int fp_take_writer_sync(fp_take_writer *w, char *err, size_t errlen)
{
    if (w->error) return w->error;
    if (w->opt.no_sync || w->synced == w->offset) return 0;
    if (fdatasync(w->fd) < 0 && errno != EINVAL && errno != EROFS) {
        int rc = -errno;
        w->error = rc; /* (what is in the file stays: only the disk's copy is in doubt) */
        fp_errorf(w->errmsg, sizeof w->errmsg, rc, "%s: syncing to disk at byte %" PRIu64 ": %s", w->path,
                  w->offset, strerror(-rc));
        return fp_errorf(err, errlen, rc, "%s", w->errmsg);
    }
    w->synced = w->offset;
    return 0;
}

static int write_json_chunk(fp_take_writer *w, const char type[4], char *text, char *err,
                            size_t errlen)
{
    if (!text) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", w->path);
    size_t n = strlen(text);
    assert(w->used == 0 && w->pending == 0); /* (no frame waits: the payload is free) */
    int rc = reserve(w, n);
    if (!rc) {
        memcpy(w->buf + TAKE_CHUNK_HEAD_SIZE, text, n);
        w->used = n;
        rc = write_chunk(w, type, 0, err, errlen);
    } else {
        fp_errorf(err, errlen, rc, "%s: out of memory", w->path);
    }
    free(text);
    return rc;
}

static void free_writer(fp_take_writer *w)
{
    if (!w) return;
    if (w->fd >= 0) close(w->fd);
    free(w->path);
    free(w->buf);
    free(w);
}

int fp_take_writer_create(const char *dir, const fp_take_header *header,
                          const fp_take_writer_options *opt, fp_take_writer **out, char *err,
                          size_t errlen)
{
    *out = NULL;
    if (!dir || !*dir) return fp_errorf(err, errlen, -EINVAL, "take: no folder given");
    int rc = take_header_check(header, err, errlen);
    if (rc) return rc;
    if ((rc = fp_file_mkdirs(dir))) /* (with its parents, as mkdir -p) */
        return fp_errorf(err, errlen, rc, "%s: cannot make the folder: %s", dir, strerror(-rc));
    fp_take_writer *w = calloc(1, sizeof *w);
    if (!w) return fp_errorf(err, errlen, -ENOMEM, "take: out of memory");
    w->fd = -1;
    if (opt) w->opt = *opt;
    if (!w->opt.chunk_frames) w->opt.chunk_frames = 30;
    if (!w->opt.chunk_bytes) w->opt.chunk_bytes = 1u << 20;
    if (w->opt.chunk_bytes > TAKE_CHUNK_MAX_PAYLOAD / 2) w->opt.chunk_bytes = TAKE_CHUNK_MAX_PAYLOAD / 2;
    w->rate = header->rate;
    w->tc_in = header->timecode_in;
    w->origin_ns = header->time_origin_ns;

    uint32_t take = w->opt.take;
    if (!take && (rc = fp_take_next_number(dir, header->slate, &take, err, errlen))) goto fail;
    size_t plen = strlen(dir) + FP_TAKE_SLATE_MAX + 32;
    w->path = malloc(plen);
    if (!w->path) {
        rc = fp_errorf(err, errlen, -ENOMEM, "take: out of memory");
        goto fail;
    }
    for (int tries = 0;; tries++, take++) {
        char name[FP_TAKE_SLATE_MAX + 32];
        fp_take_filename(header->slate, take, name, sizeof name);
        snprintf(w->path, plen, "%s/%s", dir, name);
        w->fd = open(w->path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
        if (w->fd >= 0) break;
        if (errno != EEXIST || tries > 1000 || w->opt.take) {
            int e = errno;
            rc = fp_errorf(err, errlen, -e, "%s: %s%s", w->path, strerror(e),
                           e == EEXIST ? " (a take is never overwritten)" : "");
            goto fail;
        }
    }
    w->take = take;

    fp_take_header h = *header;
    h.take = take;
    char mic[FP_TAKE_SLATE_MAX + 32];
    h.audio_in_path = NULL;
    if (h.audio_in_device && !fp_take_audio_in_name(h.slate, take, mic, sizeof mic)) h.audio_in_path = mic;
    if (!h.date[0]) {
        time_t now = time(NULL);
        struct tm tm;
        gmtime_r(&now, &tm);
        strftime(h.date, sizeof h.date, "%Y-%m-%dT%H:%M:%SZ", &tm);
    }
    uint8_t sig[TAKE_SIG_SIZE];
    take_signature(sig);
    rc = write_all(w->fd, sig, sizeof sig);
    if (rc) {
        fp_errorf(err, errlen, rc, "%s: writing the signature: %s", w->path, strerror(-rc));
        goto fail_unlink;
    }
    w->offset = TAKE_SIG_SIZE;
    rc = write_json_chunk(w, TAKE_TYPE_HEAD, take_header_to_json(&h), err, errlen);
    if (rc) goto fail_unlink;
    *out = w;
    return 0;
fail_unlink:
    unlink(w->path);
fail:
    free_writer(w);
    return rc;
}

int fp_take_writer_flush(fp_take_writer *w, char *err, size_t errlen)
{
    if (w->error) return w->error;
    if (!w->pending) return 0;
    uint32_t n = w->pending;
    int rc = write_chunk(w, TAKE_TYPE_FRAMES, n, err, errlen);
    if (!rc) {
        w->frames += n;
        w->pending = 0;
    }
    assert_chunk_state(w);
    return rc;
}

/* Room for a record of `size` bytes at the end of the payload (flushing first when the chunk
 * would outgrow chunk_bytes). */
static int make_room(fp_take_writer *w, size_t size, char *err, size_t errlen)
{
    if (w->error)
        return fp_errorf(err, errlen, w->error, "%s: the take stopped after an error: %s", w->path,
                         w->errmsg);
    assert_chunk_state(w);
    if (w->pending && w->used + size > w->opt.chunk_bytes) {
        int rc = fp_take_writer_flush(w, err, errlen);
        if (rc) return rc;
    }
    if (reserve(w, w->used + size)) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", w->path);
    return 0;
}

/* The record of `size` bytes now at the end of the payload joins the chunk. */
static int commit_record(fp_take_writer *w, size_t size, char *err, size_t errlen)
{
    const uint8_t *r = w->buf + TAKE_CHUNK_HEAD_SIZE + w->used;
    assert(TAKE_CHUNK_OVERHEAD + w->used + size <= w->cap); /* make_room reserved it */
    assert(size >= TAKE_FRAME_FIXED && le_get32(r) == size);  /* a whole record, its own size */
    w->last_time_ns = (int64_t)le_get64(r + 16);
    w->any_frame = true;
    w->used += size;
    w->pending++;
    if (w->pending >= w->opt.chunk_frames || w->used >= w->opt.chunk_bytes)
        return fp_take_writer_flush(w, err, errlen);
    return 0;
}

int fp_take_writer_add_encoded(fp_take_writer *w, const void *record, size_t size, char *err,
                               size_t errlen)
{
    const uint8_t *r = record;
    if (size < TAKE_FRAME_FIXED || size > TAKE_CHUNK_MAX_PAYLOAD / 2 || le_get32(r) != size)
        return fp_errorf(err, errlen, -EINVAL, "%s: malformed frame record", w->path);
    int rc = make_room(w, size, err, errlen);
    if (rc) return rc;
    memcpy(w->buf + TAKE_CHUNK_HEAD_SIZE + w->used, record, size);
    return commit_record(w, size, err, errlen);
}

int fp_take_writer_add(fp_take_writer *w, const fp_take_frame *frame, char *err, size_t errlen)
{
    size_t n = fp_take_frame_size(frame);
    if (!n || n > TAKE_CHUNK_MAX_PAYLOAD / 2)
        return fp_errorf(err, errlen, -EINVAL, "%s: frame %" PRIu64 " cannot be recorded (NULL "
                         "arrays or counts too large)", w->path, frame ? frame->frame : 0);
    int rc = make_room(w, n, err, errlen);
    if (rc) return rc;
    const size_t put = fp_take_frame_encode(frame, w->buf + TAKE_CHUNK_HEAD_SIZE + w->used,
                                            w->cap - TAKE_CHUNK_OVERHEAD - w->used);
    assert(put == n); /* the room make_room reserved, and the size fp_take_frame_size gave */
    (void)put;
    return commit_record(w, n, err, errlen);
}

int fp_take_writer_close(fp_take_writer **wp, uint64_t dropped, int status, char *err,
                         size_t errlen)
{
    fp_take_writer *w = wp ? *wp : NULL;
    if (!w) return 0;
    *wp = NULL;
    char msg[512] = "";
    int rc = fp_take_writer_flush(w, msg, sizeof msg);
    if (!rc && !w->error) {
        cJSON *o = cJSON_CreateObject();
        char buf[32];
        fp_timecode tc = w->tc_in;
        uint64_t f0 = 0;
        fp_timecode_to_frames(&w->tc_in, w->rate, &f0);
        if (w->any_frame)
            fp_timecode_from_frames(f0 + fp_take_frames_at(w->last_time_ns - w->origin_ns, w->rate),
                                    w->rate, w->tc_in.drop, &tc);
        cJSON_AddNumberToObject(o, "frames", (double)w->frames);
        cJSON_AddNumberToObject(o, "dropped", (double)dropped);
        cJSON_AddNumberToObject(o, "status", status);
        cJSON_AddStringToObject(o, "status_text", status ? fp_strerror(status) : "ok");
        fp_timecode_format(&tc, buf, sizeof buf);
        cJSON_AddStringToObject(o, "timecode_out", buf);
        snprintf(buf, sizeof buf, "%" PRId64, w->last_time_ns);
        cJSON_AddStringToObject(o, "last_time_ns", buf);
        if (w->reach.vectors) {
            cJSON *r = cJSON_AddObjectToObject(o, "reach");
            cJSON_AddNumberToObject(r, "vectors", (double)w->reach.vectors);
            cJSON_AddNumberToObject(r, "median", w->reach.median);
            cJSON_AddNumberToObject(r, "p10", w->reach.p10);
            cJSON_AddNumberToObject(r, "longest_drag_mm", w->reach.longest_drag_mm);
            if (w->reach.held) cJSON_AddNumberToObject(r, "held", (double)w->reach.held);
        }
        char *text = cJSON_PrintUnformatted(o);
        cJSON_Delete(o);
        rc = write_json_chunk(w, TAKE_TYPE_TAIL, text, msg, sizeof msg);
    }
    if (!rc && w->error) rc = w->error;
    if (close(w->fd) < 0 && !rc) {
        rc = -errno;
        snprintf(msg, sizeof msg, "%s: close: %s", w->path, strerror(errno));
    }
    w->fd = -1;
    if (rc && err && errlen) {
        if (w->errmsg[0]) snprintf(err, errlen, "%s", w->errmsg);
        else if (msg[0]) snprintf(err, errlen, "%s", msg);
        else fp_errorf(err, errlen, rc, "%s: %s", w->path, fp_strerror(rc));
    }
    free_writer(w);
    return rc;
}
