/* take_edit.c: a take's rating and description rewritten in place (fp_take_edit_header):
 * the HEAD chunk's JSON gets the two members anew, every other byte of the file is copied as
 * it was, into a temporary file renamed over the take. */
#include "take_internal.h"

#include "fp_error.h"
#include "fp_file.h"
#include "fp_text.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

/* The end of the JSON value that starts at text[i] (i at its first byte): the index just past
 * it, or 0 where the text ends first. Strings' escapes and nested brackets are followed; the
 * reader has already parsed the text, so no more checking is needed. */
static size_t value_end(const char *t, size_t n, size_t i)
{
    int depth = 0;
    bool str = false;
    for (; i < n; i++) {
        const char c = t[i];
        if (str) {
            if (c == '\\') i++;
            else if (c == '"') {
                str = false;
                if (!depth) return i + 1;
            }
        } else if (c == '"') {
            str = true;
        } else if (c == '{' || c == '[') {
            depth++;
        } else if (c == '}' || c == ']') {
            if (!depth) return i; /* (the enclosing object's end: a bare value ended) */
            if (!--depth) return i + 1;
        } else if (!depth && (c == ',' || c == ' ' || c == '\t' || c == '\n' || c == '\r')) {
            return i;
        }
    }
    return 0;
}

static size_t skip_space(const char *t, size_t n, size_t i)
{
    while (i < n && (t[i] == ' ' || t[i] == '\t' || t[i] == '\n' || t[i] == '\r')) i++;
    return i;
}

/* The span [*a, *b) of the value of the top-level member `key` of the JSON object text (n
 * bytes). Returns true when found. */
static bool member_span(const char *t, size_t n, const char *key, size_t *a, size_t *b)
{
    size_t i = skip_space(t, n, 0), kl = strlen(key);
    if (i >= n || t[i] != '{') return false;
    for (i++;;) {
        i = skip_space(t, n, i);
        if (i >= n || t[i] != '"') return false;
        const size_t k0 = i + 1, k1 = value_end(t, n, i); /* the key, a string */
        if (!k1) return false;
        i = skip_space(t, n, k1);
        if (i >= n || t[i] != ':') return false;
        const size_t v0 = skip_space(t, n, i + 1), v1 = value_end(t, n, v0);
        if (!v1 || v1 <= v0) return false;
        if (k1 - 1 - k0 == kl && !memcmp(t + k0, key, kl)) {
            *a = v0;
            *b = v1;
            return true;
        }
        i = skip_space(t, n, v1);
        if (i >= n || t[i] != ',') return false;
        i++;
    }
}

/* text (n bytes) with the top-level member key's value replaced by `value` (JSON), or the
 * member added before the closing brace. malloc()ed, its length in *out_n; NULL when out of
 * memory or the text is no object. */
static char *splice_member(const char *t, size_t n, const char *key, const char *value, size_t *out_n)
{
    size_t a, b;
    char *out;
    const size_t vl = strlen(value);
    if (member_span(t, n, key, &a, &b)) {
        out = malloc(n - (b - a) + vl + 1);
        if (!out) return NULL;
        memcpy(out, t, a);
        memcpy(out + a, value, vl);
        memcpy(out + a + vl, t + b, n - b);
        *out_n = n - (b - a) + vl;
    } else {
        size_t end = n;
        while (end > 0 && t[end - 1] != '}') end--;
        if (!end) return NULL;
        end--; /* at '}' */
        size_t j = end;
        while (j > 0 && (t[j - 1] == ' ' || t[j - 1] == '\t' || t[j - 1] == '\n' || t[j - 1] == '\r')) j--;
        const bool empty = j > 0 && t[j - 1] == '{';
        const size_t add = (empty ? 0 : 1) + strlen(key) + 3 + vl;
        out = malloc(n + add + 1);
        if (!out) return NULL;
        int k = snprintf(out, n + add + 1, "%.*s%s\"%s\":%s%.*s", (int)end, t, empty ? "" : ",", key,
                         value, (int)(n - end), t + end);
        *out_n = (size_t)k;
    }
    out[*out_n] = '\0';
    return out;
}

/* The HEAD chunk's JSON with edit applied: malloc()ed text and its length, or NULL (-ENOMEM,
 * or -EBADMSG where the spliced text does not read back as the header asked for). */
static char *edited_json(const char *json, size_t n, const fp_take_edit *e, size_t *out_n, int *rc)
{
    char *text = malloc(n + 1), *next;
    *rc = -ENOMEM;
    if (!text) return NULL;
    memcpy(text, json, n);
    text[n] = '\0';
    if (e->description) {
        cJSON *s = cJSON_CreateString(e->description);
        char *v = s ? cJSON_PrintUnformatted(s) : NULL;
        cJSON_Delete(s);
        next = v ? splice_member(text, n, "description", v, &n) : NULL;
        free(v);
        free(text);
        if (!(text = next)) return NULL;
    }
    if (e->set_rating) {
        char v[16];
        snprintf(v, sizeof v, "%d", e->rating);
        next = splice_member(text, n, "rating", v, &n);
        free(text);
        if (!(text = next)) return NULL;
    }
    /* read back: the header parses, with the rating and description asked for */
    fp_take_header h;
    char *store = NULL, msg[256];
    size_t bad_at;
    *rc = take_header_from_json(text, n, &h, &store, &bad_at, msg, sizeof msg);
    if (!*rc && ((e->set_rating && h.rating != e->rating) ||
                 (e->description && strcmp(h.description ? h.description : "", e->description))))
        *rc = -EBADMSG;
    free(store);
    if (*rc) {
        free(text);
        return NULL;
    }
    *out_n = n;
    return text;
}

/* Write n bytes to fd. Returns 0 or -errno. */
static int put(int fd, const void *p, size_t n)
{
    for (size_t done = 0; done < n;) {
        ssize_t k = write(fd, (const uint8_t *)p + done, n - done);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return k < 0 ? -errno : -EIO;
        done += (size_t)k;
    }
    return 0;
}

/* Copy src's bytes from off to its end onto dst. Returns 0 or -errno (-EIO: the file
 * shrank). */
static int copy_rest(int src, uint64_t off, uint64_t size, int dst)
{
    static const size_t block = 1 << 20;
    uint8_t *buf = malloc(block);
    int rc = buf ? 0 : -ENOMEM;
    while (!rc && off < size) {
        size_t want = size - off < block ? (size_t)(size - off) : block;
        ssize_t k = pread(src, buf, want, (off_t)off);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) rc = k < 0 ? -errno : -EIO;
        else if (!(rc = put(dst, buf, (size_t)k))) off += (uint64_t)k;
    }
    free(buf);
    return rc;
}

/* Read the signature and HEAD chunk of the take open on fd: the chunk's payload (malloc()ed)
 * with its length and record count, and the offset just past the chunk. Returns 0 or a
 * negative code with err. */
static int read_head(int fd, const char *path, uint8_t **payload, uint32_t *len, uint32_t *count,
                     uint64_t *after, char *err, size_t errlen)
{
    uint8_t h[TAKE_SIG_SIZE + TAKE_CHUNK_HEAD_SIZE];
    if (pread(fd, h, sizeof h, 0) != (ssize_t)sizeof h || memcmp(h + TAKE_SIG_SIZE, TAKE_CHUNK_MAGIC, 4) ||
        memcmp(h + TAKE_SIG_SIZE + 4, TAKE_TYPE_HEAD, 4))
        return fp_errorf(err, errlen, -EBADMSG, "%s: the header chunk changed while it was read", path);
    *len = le_get32(h + TAKE_SIG_SIZE + 8);
    *count = le_get32(h + TAKE_SIG_SIZE + 12);
    if (*len > TAKE_CHUNK_MAX_PAYLOAD) return fp_errorf(err, errlen, -EBADMSG, "%s: bad header chunk", path);
    *payload = malloc((size_t)*len + 1);
    if (!*payload) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", path);
    if (pread(fd, *payload, *len, TAKE_SIG_SIZE + TAKE_CHUNK_HEAD_SIZE) != (ssize_t)*len) {
        free(*payload);
        *payload = NULL;
        return fp_errorf(err, errlen, -EIO, "%s: cannot read the header chunk", path);
    }
    *after = TAKE_SIG_SIZE + TAKE_CHUNK_OVERHEAD + (uint64_t)*len;
    return 0;
}

/* Write the take anew onto o's temporary: its signature (as it was), the HEAD chunk of the
 * JSON text (n bytes, count as it was), then src's bytes from `after` to `size`. Returns 0 or
 * -errno. */
static int write_take(int src, const char *json, size_t n, uint32_t count, uint64_t after,
                      uint64_t size, int dst)
{
    uint8_t sig[TAKE_SIG_SIZE], head[TAKE_CHUNK_HEAD_SIZE], crc[4];
    if (pread(src, sig, sizeof sig, 0) != (ssize_t)sizeof sig) return -EIO;
    take_chunk_head(head, TAKE_TYPE_HEAD, (uint32_t)n, count);
    uLong c = crc32(0L, head, sizeof head);
    c = crc32(c, (const Bytef *)json, (uInt)n);
    le_put32(crc, (uint32_t)c);
    int rc = put(dst, sig, sizeof sig);
    if (!rc) rc = put(dst, head, sizeof head);
    if (!rc) rc = put(dst, json, n);
    if (!rc) rc = put(dst, crc, sizeof crc);
    if (!rc) rc = copy_rest(src, after, size, dst);
    return rc;
}

/* The checks before a rewrite: the edit's values, and the take read whole (signature, header,
 * every chunk), refused while it has no end chunk unless e->open_ok. */
static int check_edit(const char *path, const fp_take_edit *e, char *err, size_t errlen)
{
    if (e->set_rating && (e->rating < 0 || e->rating > 5))
        return fp_errorf(err, errlen, -EINVAL, "%s: rating %d not in 0..5", path, e->rating);
    if (e->description && !fp_text_ok(e->description, true))
        return fp_errorf(err, errlen, -EINVAL, "%s: the description must be UTF-8 text without "
                         "control characters (tabs and line breaks allowed)", path);
    fp_take_reader *r = NULL;
    int rc = fp_take_reader_open(path, &r, err, errlen);
    if (rc) return rc;
    const fp_take_summary *s = fp_take_reader_summary(r);
    /* no end chunk: still recording, or its recorder died (a take read mid-write looks cut
     * too: its last chunk half written) */
    const bool open = !s->complete;
    char cut[600];
    snprintf(cut, sizeof cut, "%s", fp_take_reader_warning(r));
    fp_take_reader_close(&r);
    if (open && !e->open_ok)
        return fp_errorf(err, errlen, -EBUSY, "%s: no end chunk%s%s%s: it may still be recording (a "
                         "rewrite would lose what its recorder writes next)", path,
                         cut[0] ? " (" : "", cut, cut[0] ? ")" : "");
    return 0;
}

int fp_take_edit_header(const char *path, const fp_take_edit *e, char *err, size_t errlen)
{
    if (!path || !e) return fp_errorf(err, errlen, -EINVAL, "fp_take_edit_header: NULL argument");
    int rc = check_edit(path, e, err, errlen);
    if (rc) return rc;
    int fd = fp_file_open_regular(path);
    if (fd < 0) return fp_errorf(err, errlen, fd, "%s: %s", path, fp_file_error_text(fd));
    struct stat st;
    uint8_t *payload = NULL;
    uint32_t len = 0, count = 0;
    uint64_t after = 0;
    char *json = NULL;
    size_t n = 0;
    fp_file_output o = {.fd = -1};
    if (fstat(fd, &st)) rc = fp_errorf(err, errlen, -errno, "%s: %s", path, strerror(errno));
    if (!rc) rc = read_head(fd, path, &payload, &len, &count, &after, err, errlen);
    if (!rc && !(json = edited_json((const char *)payload, len, e, &n, &rc)))
        rc = fp_errorf(err, errlen, rc, "%s: %s", path, rc == -ENOMEM ? "out of memory"
                                                      : "the header could not be rewritten");
    if (!rc && n > TAKE_CHUNK_MAX_PAYLOAD)
        rc = fp_errorf(err, errlen, -EINVAL, "%s: the header would pass 64 MiB", path);
    if (!rc && (rc = fp_file_open_output(path, NULL, NULL, FP_FILE_OUTPUT_KEEP_MODE |
                                         FP_FILE_OUTPUT_SYNC_FOLDER, &o)))
        rc = fp_errorf(err, errlen, rc, "%s: %s", path, fp_file_error_text(rc));
    if (!rc && (rc = write_take(fd, json, n, count, after, (uint64_t)st.st_size, o.fd)))
        rc = fp_errorf(err, errlen, fp_file_output_code(-rc), "%s: write failed: %s", o.tmp,
                       strerror(-rc));
    if (!rc && (rc = fp_file_output_commit(&o)))
        rc = fp_errorf(err, errlen, fp_file_output_code(-rc), "%s: %s", path, strerror(-rc));
    fp_file_output_abort(&o);
    free(json);
    free(payload);
    close(fd);
    return rc;
}
