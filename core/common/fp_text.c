/* fp_text.c: UTF-8 text checked or cleaned (fp_text.h). */
#include "fp_text.h"

#include <stdio.h>
#include <string.h>

/* The code point of the well-formed UTF-8 sequence at s and its length in *len; -1 (and
 * *len 1) when the bytes there are not one (RFC 3629: shortest form, no surrogates). */
static long decode(const unsigned char *s, size_t *len)
{
    *len = 1;
    unsigned c = s[0];
    if (c < 0x80) return (long)c;
    size_t k = c >= 0xF0 && c <= 0xF4 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 && c <= 0xDF ? 2 : 0;
    if (!k || (k == 3 && c > 0xEF)) return -1;
    long v = (long)(c & (0x7F >> k));
    for (size_t i = 1; i < k; i++) {
        if ((s[i] & 0xC0) != 0x80) return -1; /* (a NUL ends it here too) */
        v = (v << 6) | (s[i] & 0x3F);
    }
    if ((k == 3 && v < 0x800) || (k == 4 && (v < 0x10000 || v > 0x10FFFF)) ||
        (v >= 0xD800 && v <= 0xDFFF))
        return -1;
    *len = k;
    return v;
}

static bool control(long v, bool lines)
{
    return (v < 0x20 && !(lines && (v == '\t' || v == '\n'))) || (v >= 0x7F && v <= 0x9F);
}

bool fp_text_ok(const char *s, bool lines)
{
    if (!s) return true;
    const unsigned char *p = (const unsigned char *)s;
    while (*p) {
        size_t len;
        long v = decode(p, &len);
        if (v < 0 || control(v, lines)) return false;
        p += len;
    }
    return true;
}

char *fp_text_clean(const char *s, char *out, size_t n)
{
    if (!n) return out;
    size_t w = 0;
    const unsigned char *p = (const unsigned char *)(s ? s : "");
    while (*p) {
        size_t len;
        long v = decode(p, &len);
        const bool bad = v < 0 || control(v, false);
        const char *put = bad ? "\xEF\xBF\xBD" : (const char *)p; /* U+FFFD */
        const size_t plen = bad ? 3 : len;
        if (w + plen >= n) break;
        memcpy(out + w, put, plen);
        w += plen;
        p += len;
    }
    out[w] = '\0';
    return out;
}

const char *fp_text_after_space(const char *p, const char *stop)
{
    while (p && p < stop && (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r')) p++;
    return p && p < stop ? p : NULL;
}

void fp_text_share_held(double share, char *out, size_t n)
{
    if (!n) return;
    if (100.0 * share >= 99.5) snprintf(out, n, "over 99%%");
    else snprintf(out, n, "%.0f%%", 100.0 * share);
}

size_t fp_text_bom(const char *p, size_t len)
{
    return p && len >= 3 && !memcmp(p, "\xEF\xBB\xBF", 3) ? 3 : 0;
}

void fp_text_line_col(const char *text, const char *at, long *line, long *col)
{
    long l = 1, c = 1;
    for (const char *p = text; p && p < at; p++) {
        if (*p == '\n') l++, c = 1;
        else c++;
    }
    if (line) *line = l;
    if (col) *col = c;
}
