/*
 * fp_eventlog.c: writer and reader of the facepuppet event log (docs/eventlog.md).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "fp_eventlog.h"
#include "fp_error.h"
#include "fp_file.h"

#include <facepuppet/decimal.h> /* fp_decimal_span: the one syntax of a number */

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <limits.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define LINE_MAX_BYTES 4096 /* the longest line the writer makes is about 1.1 kB */
/* The longest line the reader takes: a longer one (a file of NULs a crash left, a hostile
 * one) is refused as it passes this, never held whole (3 GiB of NULs after the header were
 * read into 3 GB of memory, then called "no events") */
#define READ_LINE_MAX 65536
#define TEXT_BYTES ((int)sizeof(((fp_event_status *)0)->text))

static const char *const type_names[] = {NULL, "angles", "positions", "wrist", "button", "status", "channel"};
static const char *const status_names[] = {NULL, "connected", "disconnected", "reconnecting",
                                           "warning", "error", "end-of-stream"};

const char *fp_eventlog_type_name(int type)
{
    return type >= 1 && type <= FP_EVENT_CHANNEL ? type_names[type] : NULL;
}

const char *fp_eventlog_status_name(uint32_t code)
{
    return code >= 1 && code <= 6 ? status_names[code] : NULL;
}

static size_t type_size(int type)
{
    switch (type) {
    case FP_EVENT_JOINT_ANGLES: return sizeof(fp_event_joint_angles);
    case FP_EVENT_JOINT_POSITIONS: return sizeof(fp_event_joint_positions);
    case FP_EVENT_WRIST_POSE: return sizeof(fp_event_wrist_pose);
    case FP_EVENT_BUTTON: return sizeof(fp_event_button);
    case FP_EVENT_STATUS: return sizeof(fp_event_status);
    case FP_EVENT_CHANNEL: return sizeof(fp_event_channel);
    default: return 0;
    }
}

/* A message for a caller's buffer (core/common/fp_error.h). */
#define put_msg(buf, len, ...) ((void)fp_errorf((buf), (len), 0, __VA_ARGS__))

/* The C locale, created once per object (newlocale is cheap and thread-safe). */
static locale_t c_locale_new(void)
{
    return newlocale(LC_ALL_MASK, "C", (locale_t)0);
}

/* ------------------------------------------------------------------------------------- */
/* Writer                                                                                 */

struct fp_eventlog_writer {
    int fd;
    off_t whole;            /* bytes of whole lines written: a failed write is cut back to it */
    char *path;
    locale_t c_locale;
    char error[512];
    char line[LINE_MAX_BYTES];
};

/* Write all of s[0..n) or fail with -errno (-EIO for errors without a better code). */
static int write_all(int fd, const char *s, size_t n)
{
    while (n) {
        ssize_t put = write(fd, s, n);
        if (put < 0 && errno == EINTR) continue;
        if (put <= 0) {
            int e = put < 0 ? errno : ENOSPC;
            return e == ENOSPC || e == EDQUOT || e == EFBIG ? -e : -EIO;
        }
        s += put;
        n -= (size_t)put;
    }
    return 0;
}

int fp_eventlog_writer_create(const char *path, unsigned flags, fp_eventlog_writer **out,
                              char *err, size_t errlen)
{
    *out = NULL;
    if (!path) return fp_errorf(err, errlen, -EINVAL, "(null): no path given");
    fp_eventlog_writer *w = calloc(1, sizeof *w);
    if (w) w->path = strdup(path);
    if (w) w->c_locale = c_locale_new();
    if (!w || !w->path || w->c_locale == (locale_t)0) {
        if (w && w->c_locale != (locale_t)0) freelocale(w->c_locale);
        if (w) free(w->path);
        free(w);
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", path);
    }
    int oflags = O_WRONLY | O_CREAT | O_CLOEXEC | O_NOCTTY |
                 (flags & FP_EVENTLOG_EXCL ? O_EXCL : O_TRUNC);
    w->fd = open(path, oflags, 0666);
    int rc = 0;
    if (w->fd < 0) {
        int e = errno;
        rc = fp_errorf(err, errlen, e == EEXIST ? -EEXIST : -e, "%s: cannot create: %s", path,
                       strerror(e));
    } else {
        char head[64];
        int n = snprintf(head, sizeof head, "# %s %d\n", FP_EVENTLOG_MAGIC, FP_EVENTLOG_VERSION);
        rc = write_all(w->fd, head, (size_t)n);
        if (rc) {
            fp_errorf(err, errlen, rc, "%s: cannot write: %s", path, strerror(-rc));
            if (ftruncate(w->fd, 0)) {} /* nothing half-written, not even the header */
        }
        w->whole = n;
    }
    if (rc) {
        if (w->fd >= 0) close(w->fd);
        freelocale(w->c_locale);
        free(w->path);
        free(w);
        return rc;
    }
    *out = w;
    return 0;
}

fp_eventlog_writer *fp_eventlog_writer_open(const char *path, char *err, size_t errlen)
{
    fp_eventlog_writer *w = NULL;
    fp_eventlog_writer_create(path, 0, &w, err, errlen);
    return w;
}

const char *fp_eventlog_writer_error(const fp_eventlog_writer *w)
{
    return w ? w->error : "";
}

/* Appends to a line buffer; `pos` grows past `cap` on overflow, checked once at the end. */
typedef struct line_buf {
    char *s;
    size_t cap, pos;
} line_buf;

static void lb_printf(line_buf *b, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    size_t room = b->pos < b->cap ? b->cap - b->pos : 0;
    int n = vsnprintf(room ? b->s + b->pos : NULL, room, fmt, ap);
    va_end(ap);
    if (n > 0) b->pos += (size_t)n;
}

static int lb_floats(line_buf *b, const float *v, int n)
{
    for (int i = 0; i < n; i++) {
        if (!isfinite(v[i])) return i + 1;
        lb_printf(b, " %.9g", (double)v[i]);
    }
    return 0;
}

/* A channel name's bytes, as the writer writes them and the reader takes them: printable
 * ASCII, no space. The first byte of name[0, len) that is not one, or NULL. */
static const char *channel_bad_byte(const char *name, size_t len)
{
    for (size_t i = 0; i < len; i++)
        if (name[i] <= ' ' || name[i] > '~') return name + i;
    return NULL;
}

static int writer_fail(fp_eventlog_writer *w, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fp_verrorf(w->error, sizeof w->error, code, fmt, ap);
    va_end(ap);
    return fp_error_prefix(w->error, sizeof w->error, code, "%s", w->path);
}

/* One write() per line where the kernel takes it whole; a line the disk took only part of is
 * cut off again, so the file always ends with a whole line. */
static int write_line(fp_eventlog_writer *w, const char *s, size_t n)
{
    int rc = write_all(w->fd, s, n);
    if (rc) {
        if (ftruncate(w->fd, w->whole) == 0) lseek(w->fd, w->whole, SEEK_SET);
        return writer_fail(w, rc, "cannot write: %s", strerror(-rc));
    }
    w->whole += (off_t)n;
    return 0;
}

static int format_event(fp_eventlog_writer *w, const fp_event *e, line_buf *b)
{
    const fp_event_header *h = &e->header;
    const char *name = fp_eventlog_type_name(h->type);
    if (!name) return writer_fail(w, -EINVAL, "unknown event type %u", h->type);
    if (h->size < type_size(h->type))
        return writer_fail(w, -EINVAL, "%s event of size %u, smaller than %zu", name,
                           h->size, type_size(h->type));
    if (h->hand < -1 || h->hand > 1)
        return writer_fail(w, -EINVAL, "%s event with hand %d (not -1, 0 or 1)", name,
                           (int)h->hand);
    const char *hand = h->hand == FP_HAND_LEFT ? "left" : h->hand == FP_HAND_RIGHT ? "right" : "-";
    if (h->time_ns > FP_EVENTLOG_TIME_MAX || h->time_ns < -FP_EVENTLOG_TIME_MAX)
        return writer_fail(w, -EINVAL, "%s event at time %" PRId64 " ns, beyond +-%lld", name,
                           h->time_ns, (long long)FP_EVENTLOG_TIME_MAX);
    lb_printf(b, "%" PRId64 " %s %s", h->time_ns, name, hand);
    int bad = 0;
    switch (h->type) {
    case FP_EVENT_JOINT_ANGLES:
        if (e->angles.valid >> FP_GLOVE_SENSORS)
            return writer_fail(w, -EINVAL, "angles valid mask 0x%x has bits beyond %d",
                               e->angles.valid, FP_GLOVE_SENSORS);
        lb_printf(b, " 0x%06x", e->angles.valid);
        bad = lb_floats(b, e->angles.radians, FP_GLOVE_SENSORS);
        break;
    case FP_EVENT_JOINT_POSITIONS:
        bad = lb_floats(b, &e->positions.mm[0][0], FP_HAND_JOINTS * 3);
        break;
    case FP_EVENT_WRIST_POSE:
        bad = lb_floats(b, e->wrist.position_mm, 3);
        if (!bad) {
            bad = lb_floats(b, e->wrist.rotation, 4);
            if (bad) bad += 3;
        }
        break;
    case FP_EVENT_BUTTON:
        lb_printf(b, " %" PRIu32 " %" PRIu32 " %" PRIu32, e->button.button, e->button.down,
                  e->button.mask);
        break;
    case FP_EVENT_CHANNEL: { /* NAME VALUE (a name of printable non-space ASCII) */
        size_t len = strnlen(e->channel.name, sizeof e->channel.name);
        if (!len || len >= sizeof e->channel.name)
            return writer_fail(w, -EINVAL, "channel name empty or not NUL-terminated");
        if (channel_bad_byte(e->channel.name, len))
            return writer_fail(w, -EINVAL, "channel name with a space or a non-ASCII byte");
        lb_printf(b, " %s", e->channel.name);
        bad = lb_floats(b, &e->channel.value, 1);
        break;
    }
    case FP_EVENT_STATUS: {
        const char *code = fp_eventlog_status_name(e->status.code);
        if (code)
            lb_printf(b, " %s \"", code);
        else
            lb_printf(b, " %" PRIu32 " \"", e->status.code);
        size_t len = strnlen(e->status.text, TEXT_BYTES);
        if (len >= (size_t)TEXT_BYTES)
            return writer_fail(w, -EINVAL, "status text not NUL-terminated");
        for (size_t i = 0; i < len; i++) {
            unsigned char c = (unsigned char)e->status.text[i];
            switch (c) {
            case '"': lb_printf(b, "\\\""); break;
            case '\\': lb_printf(b, "\\\\"); break;
            case '\n': lb_printf(b, "\\n"); break;
            case '\r': lb_printf(b, "\\r"); break;
            case '\t': lb_printf(b, "\\t"); break;
            default:
                if (c < 0x20 || c == 0x7f)
                    lb_printf(b, "\\x%02x", c);
                else
                    lb_printf(b, "%c", c);
            }
        }
        lb_printf(b, "\"");
        break;
    }
    }
    if (bad)
        return writer_fail(w, -EINVAL, "%s event: float %d is not finite", name, bad);
    if (h->source) lb_printf(b, " source=%" PRIu32, h->source);
    if (h->flags) lb_printf(b, " flags=%u", (unsigned)h->flags);
    lb_printf(b, "\n");
    if (b->pos >= b->cap) return writer_fail(w, -EINVAL, "line too long");
    return 0;
}

int fp_eventlog_writer_write(fp_eventlog_writer *w, const fp_event *event)
{
    if (!w) return -EINVAL;
    if (!event) return writer_fail(w, -EINVAL, "no event given");
    line_buf b = {w->line, sizeof w->line, 0};
    locale_t old = uselocale(w->c_locale);
    int rc = format_event(w, event, &b);
    uselocale(old);
    if (rc) return rc;
    return write_line(w, b.s, b.pos);
}

int fp_eventlog_writer_comment(fp_eventlog_writer *w, const char *text)
{
    if (!w) return -EINVAL;
    line_buf b = {w->line, sizeof w->line, 0};
    lb_printf(&b, "# ");
    for (const char *p = text ? text : ""; *p && b.pos + 2 < b.cap; p++)
        lb_printf(&b, "%c", (*p == '\n' || *p == '\r') ? ' ' : *p);
    lb_printf(&b, "\n");
    return write_line(w, b.s, b.pos < b.cap ? b.pos : b.cap);
}

int fp_eventlog_writer_close(fp_eventlog_writer **pw, char *err, size_t errlen)
{
    if (!pw || !*pw) return 0;
    fp_eventlog_writer *w = *pw;
    *pw = NULL;
    int rc = 0;
    if (fsync(w->fd) != 0 && errno != EINVAL && errno != EROFS) {
        int e = errno;
        rc = e == ENOSPC || e == EDQUOT ? -e : -EIO;
        put_msg(err, errlen, "%s: cannot write: %s", w->path, strerror(e));
    }
    if (close(w->fd) != 0 && rc == 0) {
        put_msg(err, errlen, "%s: cannot close: %s", w->path, strerror(errno));
        rc = -EIO;
    }
    freelocale(w->c_locale);
    free(w->path);
    free(w);
    return rc;
}

/* ------------------------------------------------------------------------------------- */
/* Reader                                                                                 */

struct fp_eventlog_reader {
    FILE *f;
    char *path;
    locale_t c_locale;
    char *line;        /* the line read (READ_LINE_MAX + 1 bytes) */
    size_t line_cap;
    long line_no;      /* lines read so far */
    long event_line;   /* line of the last event returned */
    long truncated_line;
    int status;        /* 0, or the sticky error */
    char error[512];
};

const char *fp_eventlog_reader_error(const fp_eventlog_reader *r)
{
    return r ? r->error : "";
}

long fp_eventlog_reader_line(const fp_eventlog_reader *r)
{
    return r ? r->event_line : 0;
}

long fp_eventlog_reader_truncated_line(const fp_eventlog_reader *r)
{
    return r ? r->truncated_line : 0;
}

void fp_eventlog_reader_close(fp_eventlog_reader **pr)
{
    if (!pr || !*pr) return;
    fp_eventlog_reader *r = *pr;
    *pr = NULL;
    if (r->f) fclose(r->f);
    if (r->c_locale != (locale_t)0) freelocale(r->c_locale);
    free(r->line);
    free(r->path);
    free(r);
}

/* Reads one line into r->line without its "\n" (and "\r"). Returns 1 for a complete line, 2 for
 * a last line without newline, 0 at the end, -E2BIG for a line past READ_LINE_MAX bytes (not
 * read on), -ENOMEM or -EIO. */
static int read_line(fp_eventlog_reader *r, size_t *len)
{
    errno = 0;
    if (!r->line && !(r->line = malloc(READ_LINE_MAX + 1))) return -ENOMEM;
    r->line_cap = READ_LINE_MAX + 1;
    size_t n = 0;
    int c;
    while ((c = getc_unlocked(r->f)) != EOF) {
        if (n == READ_LINE_MAX) {
            r->line_no++;
            return -E2BIG;
        }
        r->line[n++] = (char)c;
        if (c == '\n') break;
    }
    r->line[n] = '\0';
    if (n == 0) {
        if (ferror(r->f)) return -EIO;
        return 0;
    }
    r->line_no++;
    int complete = r->line[n - 1] == '\n';
    if (complete) r->line[--n] = '\0';
    if (n > 0 && r->line[n - 1] == '\r') r->line[--n] = '\0';
    *len = (size_t)n;
    return complete ? 1 : 2;
}

/* A syntax error at column `col` (1-based) of the current line. */
static int reader_fail(fp_eventlog_reader *r, int code, long col, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fp_verrorf(r->error, sizeof r->error, code, fmt, ap);
    va_end(ap);
    if (col > 0)
        fp_error_prefix(r->error, sizeof r->error, code, "%s:%ld:%ld", r->path, r->line_no, col);
    else
        fp_error_prefix(r->error, sizeof r->error, code, "%s", r->path);
    r->status = code;
    return code;
}

fp_eventlog_reader *fp_eventlog_reader_open(const char *path, char *err, size_t errlen)
{
    return fp_eventlog_reader_open_code(path, NULL, err, errlen);
}

fp_eventlog_reader *fp_eventlog_reader_open_code(const char *path, int *code_out, char *err,
                                                 size_t errlen)
{
    int dummy;
    int *cd = code_out ? code_out : &dummy;
    *cd = -EINVAL;
    if (!path) {
        put_msg(err, errlen, "(null): no path given");
        return NULL;
    }
    *cd = -ENOMEM;
    fp_eventlog_reader *r = calloc(1, sizeof *r);
    if (r) r->path = strdup(path);
    if (r) r->c_locale = c_locale_new();
    if (!r || !r->path || r->c_locale == (locale_t)0) {
        put_msg(err, errlen, "%s: out of memory", path);
        fp_eventlog_reader_close(&r);
        return NULL;
    }
    int code;
    r->f = fp_file_fopen_regular(path, &code); /* a FIFO or a device cannot hold it */
    if (!r->f) {
        *cd = code;
        put_msg(err, errlen, "%s: cannot open: %s", path, fp_file_error_text(code));
        fp_eventlog_reader_close(&r);
        return NULL;
    }
    size_t len = 0;
    int rc = read_line(r, &len);
    if (rc < 0 && rc != -E2BIG) {
        *cd = rc;
        put_msg(err, errlen, "%s: cannot read: %s", path, rc == -ENOMEM ? "out of memory" : strerror(errno));
        fp_eventlog_reader_close(&r);
        return NULL;
    }
    *cd = -EBADMSG;
    const char *magic = "# " FP_EVENTLOG_MAGIC " ";
    size_t mlen = strlen(magic);
    if (rc <= 0 || strncmp(r->line, magic, mlen) != 0) {
        put_msg(err, errlen, "%s:1:1: not a facepuppet event log (the first line must be "
                "\"# %s %d\")", path, FP_EVENTLOG_MAGIC, FP_EVENTLOG_VERSION);
        fp_eventlog_reader_close(&r);
        return NULL;
    }
    const char *v = r->line + mlen;
    char *end;
    errno = 0;
    long version = strtol(v, &end, 10);
    while (*end == ' ' || *end == '\t') end++;
    if (end == v || *end || errno || version != FP_EVENTLOG_VERSION) {
        if (end != v && !*end && !errno) *cd = -ENOTSUP; /* a number, not this one */
        put_msg(err, errlen, "%s:1:%ld: unsupported event-log version \"%s\" (this reader "
                "knows %d)", path, (long)mlen + 1, v, FP_EVENTLOG_VERSION);
        fp_eventlog_reader_close(&r);
        return NULL;
    }
    *cd = 0;
    return r;
}

/* Cursor over one line. */
typedef struct cursor {
    fp_eventlog_reader *r;
    char *line;
    char *p;
} cursor;

static long col_of(const cursor *c, const char *p)
{
    return (long)(p - c->line) + 1;
}

static void skip_blanks(cursor *c)
{
    while (*c->p == ' ' || *c->p == '\t') c->p++;
}

/* Next blank-separated token: NUL-terminates it in place (the separator is overwritten, so the
 * cursor moves past it). Returns NULL at the end of the line. */
static char *next_token(cursor *c, char **start)
{
    skip_blanks(c);
    if (!*c->p) return NULL;
    *start = c->p;
    while (*c->p && *c->p != ' ' && *c->p != '\t') c->p++;
    if (*c->p) *c->p++ = '\0';
    return *start;
}

static int need_token(cursor *c, char **tok, const char *what)
{
    char *start = NULL;
    if (!next_token(c, &start)) {
        return reader_fail(c->r, -EBADMSG, col_of(c, c->p),
                           "line ends where %s was expected", what);
    }
    *tok = start;
    return 0;
}

static int parse_float(cursor *c, float *out, const char *what)
{
    char *tok = NULL;
    int rc = need_token(c, &tok, what);
    if (rc) return rc;
    char *end;
    errno = 0;
    float v = strtof_l(tok, &end, c->r->c_locale);
    if (end == tok || *end)
        return reader_fail(c->r, -EBADMSG, col_of(c, tok), "bad number \"%s\" for %s",
                           tok, what);
    if (!isfinite(v))
        return reader_fail(c->r, -EBADMSG, col_of(c, tok),
                           "%s is \"%s\", not a finite number", what, tok);
    if (fp_decimal_span(tok) != (size_t)(end - tok)) /* hexadecimal ("0x1p3"): decimals only */
        return reader_fail(c->r, -EBADMSG, col_of(c, tok), "bad number \"%s\" for %s",
                           tok, what);
    *out = v;
    return 0;
}

static int parse_floats(cursor *c, float *out, int n, const char *what)
{
    for (int i = 0; i < n; i++) {
        int rc = parse_float(c, &out[i], what);
        if (rc) return rc;
    }
    return 0;
}

static int parse_u32(cursor *c, const char *tok, int base, uint32_t *out, const char *what)
{
    char *end;
    errno = 0;
    unsigned long long v = strtoull(tok, &end, base);
    if (end == tok || *end || tok[0] == '-' || tok[0] == '+' || errno || v > UINT32_MAX)
        return reader_fail(c->r, -EBADMSG, col_of(c, tok),
                           "bad %s \"%s\" (an unsigned 32-bit integer)", what, tok);
    *out = (uint32_t)v;
    return 0;
}

static int parse_u32_token(cursor *c, int base, uint32_t *out, const char *what)
{
    char *tok = NULL;
    int rc = need_token(c, &tok, what);
    return rc ? rc : parse_u32(c, tok, base, out, what);
}

static int hex_digit(int ch)
{
    if (ch >= '0' && ch <= '9') return ch - '0';
    if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
    if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
    return -1;
}

static int parse_text(cursor *c, char *text)
{
    skip_blanks(c);
    if (*c->p != '"')
        return reader_fail(c->r, -EBADMSG, col_of(c, c->p),
                           "expected the status text in double quotes");
    char *open = c->p++;
    int n = 0;
    for (;;) {
        char *at = c->p;
        int ch = (unsigned char)*c->p++;
        if (ch == '\0')
            return reader_fail(c->r, -EBADMSG, col_of(c, open),
                               "status text has no closing quote");
        if (ch == '"') break;
        if (ch == '\\') {
            int e = (unsigned char)*c->p++;
            switch (e) {
            case '"': ch = '"'; break;
            case '\\': ch = '\\'; break;
            case 'n': ch = '\n'; break;
            case 'r': ch = '\r'; break;
            case 't': ch = '\t'; break;
            case 'x': {
                int hi = hex_digit((unsigned char)c->p[0]);
                int lo = hi < 0 ? -1 : hex_digit((unsigned char)c->p[1]);
                if (hi < 0 || lo < 0 || (hi == 0 && lo == 0))
                    return reader_fail(c->r, -EBADMSG, col_of(c, at),
                                       "bad escape: \\x needs two hex digits, not 00");
                ch = hi * 16 + lo;
                c->p += 2;
                break;
            }
            default:
                return reader_fail(c->r, -EBADMSG, col_of(c, at),
                                   "unknown escape \\%c in status text", e ? e : '0');
            }
        }
        if (n >= TEXT_BYTES - 1)
            return reader_fail(c->r, -EBADMSG, col_of(c, at),
                               "status text longer than %d bytes", TEXT_BYTES - 1);
        text[n++] = (char)ch;
    }
    if (*c->p && *c->p != ' ' && *c->p != '\t')
        return reader_fail(c->r, -EBADMSG, col_of(c, c->p),
                           "expected a blank after the status text");
    return 0;
}

static int parse_event(fp_eventlog_reader *r, char *line, fp_event *out)
{
    cursor c = {r, line, line};
    fp_event_header *h = &out->header;
    char *tok = NULL;
    int rc = need_token(&c, &tok, "the time in ns");
    if (rc) return rc;
    char *end;
    errno = 0;
    long long t = strtoll(tok, &end, 10);
    if (end == tok || *end || (errno && errno != ERANGE))
        return reader_fail(r, -EBADMSG, col_of(&c, tok),
                           "bad time \"%s\" (a signed 64-bit integer of ns)", tok);
    if (errno == ERANGE || t > FP_EVENTLOG_TIME_MAX || t < -FP_EVENTLOG_TIME_MAX)
        return reader_fail(r, -EBADMSG, col_of(&c, tok),
                           "time %s out of range (at most %lld ns either side of 0, so that "
                           "differences of times never overflow)", tok,
                           (long long)FP_EVENTLOG_TIME_MAX);
    h->time_ns = (int64_t)t;

    if ((rc = need_token(&c, &tok, "the event type"))) return rc;
    int type = 0;
    for (int i = 1; i <= FP_EVENT_CHANNEL; i++)
        if (strcmp(tok, type_names[i]) == 0) type = i;
    if (!type)
        return reader_fail(r, -EBADMSG, col_of(&c, tok),
                           "unknown event type \"%s\" (angles, positions, wrist, button, "
                           "status, channel)", tok);
    h->type = (uint16_t)type;
    h->size = (uint32_t)type_size(type);

    if ((rc = need_token(&c, &tok, "the hand"))) return rc;
    if (strcmp(tok, "left") == 0)
        h->hand = FP_HAND_LEFT;
    else if (strcmp(tok, "right") == 0)
        h->hand = FP_HAND_RIGHT;
    else if (strcmp(tok, "-") == 0)
        h->hand = -1;
    else
        return reader_fail(r, -EBADMSG, col_of(&c, tok),
                           "unknown hand \"%s\" (left, right or -)", tok);

    switch (type) {
    case FP_EVENT_JOINT_ANGLES:
        if ((rc = need_token(&c, &tok, "the valid mask"))) return rc;
        if ((rc = parse_u32(&c, tok, 0, &out->angles.valid, "valid mask"))) return rc;
        if (out->angles.valid >> FP_GLOVE_SENSORS)
            return reader_fail(r, -EBADMSG, col_of(&c, tok),
                               "valid mask %s has bits beyond the %d sensors", tok,
                               FP_GLOVE_SENSORS);
        rc = parse_floats(&c, out->angles.radians, FP_GLOVE_SENSORS, "an angle in radians");
        break;
    case FP_EVENT_JOINT_POSITIONS:
        rc = parse_floats(&c, &out->positions.mm[0][0], FP_HAND_JOINTS * 3,
                          "a joint coordinate in mm");
        break;
    case FP_EVENT_WRIST_POSE:
        rc = parse_floats(&c, out->wrist.position_mm, 3, "a wrist coordinate in mm");
        if (!rc) rc = parse_floats(&c, out->wrist.rotation, 4, "a quaternion component");
        break;
    case FP_EVENT_BUTTON:
        rc = parse_u32_token(&c, 10, &out->button.button, "button");
        if (!rc) rc = parse_u32_token(&c, 10, &out->button.down, "down");
        if (!rc) rc = parse_u32_token(&c, 10, &out->button.mask, "mask");
        break;
    case FP_EVENT_STATUS:
        if ((rc = need_token(&c, &tok, "the status code"))) return rc;
        out->status.code = 0;
        for (uint32_t i = 1; i <= 6; i++)
            if (strcmp(tok, status_names[i]) == 0) out->status.code = i;
        if (!out->status.code) {
            if (tok[0] < '0' || tok[0] > '9')
                return reader_fail(r, -EBADMSG, col_of(&c, tok),
                                   "unknown status code \"%s\"", tok);
            if ((rc = parse_u32(&c, tok, 10, &out->status.code, "status code"))) return rc;
        }
        rc = parse_text(&c, out->status.text);
        break;
    case FP_EVENT_CHANNEL:
        if ((rc = need_token(&c, &tok, "the channel name"))) return rc;
        if (strlen(tok) >= sizeof out->channel.name)
            return reader_fail(r, -EBADMSG, col_of(&c, tok), "channel name longer than %zu bytes",
                               sizeof out->channel.name - 1);
        const char *bad = channel_bad_byte(tok, strlen(tok)); /* what the writer writes */
        if (bad)
            return reader_fail(r, -EBADMSG, col_of(&c, bad),
                               "channel name with byte 0x%02x (printable ASCII only)",
                               (unsigned)(unsigned char)*bad);
        snprintf(out->channel.name, sizeof out->channel.name, "%s", tok);
        rc = parse_floats(&c, &out->channel.value, 1, "the channel's value");
        break;
    }
    if (rc) return rc;

    /* Optional attributes. */
    int seen_source = 0, seen_flags = 0;
    while (next_token(&c, &tok)) {
        uint32_t v = 0;
        if (strncmp(tok, "source=", 7) == 0 && !seen_source) {
            if ((rc = parse_u32(&c, tok + 7, 10, &v, "source"))) return rc;
            h->source = v;
            seen_source = 1;
        } else if (strncmp(tok, "flags=", 6) == 0 && !seen_flags) {
            if ((rc = parse_u32(&c, tok + 6, 10, &v, "flags"))) return rc;
            if (v > UINT16_MAX)
                return reader_fail(r, -EBADMSG, col_of(&c, tok + 6),
                                   "flags %s beyond 16 bits", tok + 6);
            h->flags = (uint16_t)v;
            seen_flags = 1;
        } else {
            return reader_fail(r, -EBADMSG, col_of(&c, tok),
                               "unexpected \"%s\" after the %s fields (only source=N and "
                               "flags=N may follow, once each)", tok, type_names[type]);
        }
    }
    return 0;
}

int fp_eventlog_reader_next(fp_eventlog_reader *r, fp_event *out)
{
    if (!r || !out) return -EINVAL;
    if (r->status) return r->status;
    for (;;) {
        size_t len = 0;
        int rc = read_line(r, &len);
        if (rc == -E2BIG)
            return reader_fail(r, -EBADMSG, READ_LINE_MAX + 1, "a line longer than %d bytes (an event's "
                               "line is about 1 kB at most)", READ_LINE_MAX);
        if (rc == -ENOMEM) return reader_fail(r, -ENOMEM, 0, "out of memory");
        if (rc < 0) return reader_fail(r, -EIO, 0, "cannot read: %s", strerror(errno));
        if (rc == 0) return 0;
        if (rc == 2) {
            /* An unterminated last line: cut short by a crash; never parsed. */
            r->truncated_line = r->line_no;
            return 0;
        }
        if (strlen(r->line) != len)
            return reader_fail(r, -EBADMSG, (long)strlen(r->line) + 1,
                               "NUL byte in line");
        const char *p = r->line;
        while (*p == ' ' || *p == '\t') p++;
        if (*p == '\0' || *p == '#') continue;
        memset(out, 0, sizeof *out);
        locale_t old = uselocale(r->c_locale);
        rc = parse_event(r, r->line, out);
        uselocale(old);
        if (rc) {
            memset(out, 0, sizeof *out);
            return rc;
        }
        r->event_line = r->line_no;
        return 1;
    }
}
