/* Internal to core/mesh: the text helpers the strict scans share (mesh_scan_obj.c,
 * mesh_scan_offstl.c, mesh_scan_ply.c), inline so that each scan's per-token loop stays as
 * fast as one file's static functions made it. */
#ifndef FP_MESH_SCAN_H
#define FP_MESH_SCAN_H

#include "mesh_internal.h"

#include <facepuppet/decimal.h> /* fp_decimal_span: the one syntax of a number */

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A line of text, or what is left of it. */
typedef struct obj_line {
    const char *p, *end; /* cursor and end of the line (before \r\n) */
} obj_line;

static inline int is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* Next whitespace-separated token of the line; 0 at the end. */
static inline int next_token(obj_line *l, const char **tok, size_t *toklen)
{
    while (l->p < l->end && is_blank(*l->p))
        l->p++;
    if (l->p >= l->end)
        return 0;
    const char *s = l->p;
    while (l->p < l->end && !is_blank(*l->p))
        l->p++;
    *tok = s;
    *toklen = (size_t)(l->p - s);
    return 1;
}

/* One number token: a decimal (fp_decimal_span, the one syntax of a number: C++ streams,
 * OpenMesh's, read no more), or strtod's "inf"/"nan" words, which read as non-finite for the
 * caller to name. Hexadecimal floats are malformed. */
static inline int parse_number(const char *tok, size_t len, double *out)
{
    char *e = NULL;
    errno = 0;
    double d = strtod(tok, &e);
    const char *w = tok + (*tok == '+' || *tok == '-');
    const int word = *w == 'i' || *w == 'I' || *w == 'n' || *w == 'N';
    if (e != tok + len || (!word && fp_decimal_span(tok) != len))
        return 0;
    /* a value beyond float range reads as infinite (the mesh stores floats) */
    *out = isfinite(d) && fabs(d) > FLT_MAX ? (d > 0 ? INFINITY : -INFINITY) : d;
    return 1;
}

/* A count: digits only (no sign), within unsigned long. */
static inline int parse_count(const char *tok, size_t len, unsigned long *out)
{
    char *e = NULL;
    if (len == 0 || tok[0] == '-' || tok[0] == '+')
        return 0;
    errno = 0;
    unsigned long v = strtoul(tok, &e, 10);
    if (e != tok + len || errno == ERANGE)
        return 0;
    *out = v;
    return 1;
}

static inline int token_is(const char *tok, size_t len, const char *word)
{
    return strlen(word) == len && memcmp(tok, word, len) == 0;
}

/* Lines of a text, counted. */
typedef struct text_lines {
    const char *p, *end;
    size_t line_no;
} text_lines;

/* The next line holding a token (blank lines are skipped, as OpenMesh's >> does). */
static inline int next_nonblank_line(text_lines *t, obj_line *l)
{
    while (t->p < t->end) {
        t->line_no++;
        const char *eol = memchr(t->p, '\n', (size_t)(t->end - t->p));
        if (!eol)
            eol = t->end;
        l->p = t->p;
        l->end = eol;
        t->p = eol + 1;
        obj_line probe = *l;
        const char *tok;
        size_t len;
        if (next_token(&probe, &tok, &len))
            return 1;
    }
    return 0;
}

/* A token in a message: quoted, at most 40 characters. */
#define TOK_FMT "'%.*s'"
#define TOK_ARG(t, n) (int)((n) > 40 ? 40 : (n)), (t)

#endif
