/* The strict PLY scan (fp__ply_scan, mesh_internal.h): a strict header (ply_header and its
 * lines), the elements against the file's size (ply_layout), then a walk over every value of
 * the body (ply_walk), before OpenMesh's reader, which crashes or loops on bad input, sees
 * the file. */
#include "mesh_scan.h"

#include <stdint.h>
#include <stdio.h>

/* ---- PLY: a strict header, then a walk over every value ------------------------------ */

/* The scalar types of the PLY format (Turk 1994) with both spellings OpenMesh knows. */
static const struct ply_type_info {
    const char *name, *alias;
    int size, is_int, is_signed;
} ply_types[] = {
    {"char", "int8", 1, 1, 1},     {"uchar", "uint8", 1, 1, 0}, {"short", "int16", 2, 1, 1},
    {"ushort", "uint16", 2, 1, 0}, {"int", "int32", 4, 1, 1},   {"uint", "uint32", 4, 1, 0},
    {"float", "float32", 4, 0, 1}, {"double", "float64", 8, 0, 1}};
#define PLY_NTYPES (int)(sizeof ply_types / sizeof ply_types[0])

enum { PLY_MAX_ELEMENTS = 16, PLY_MAX_PROPS = 64 };
enum { PLY_OTHER, PLY_VERTEX, PLY_FACE };
enum { PLY_ROLE_OTHER, PLY_ROLE_VINDEX, PLY_ROLE_TEXCOORD };

typedef struct ply_prop {
    int type;       /* index into ply_types */
    int count_type; /* list count type, or -1 for a scalar */
    int role;
} ply_prop;

typedef struct ply_element {
    int kind;
    unsigned long long count;
    int nprops;
    ply_prop props[PLY_MAX_PROPS];
    size_t line;
    size_t xyz_line[3]; /* vertex: the lines of its x, y, z properties (0: none) */
} ply_element;

static int ply_type(const char *tok, size_t len)
{
    for (int i = 0; i < PLY_NTYPES; i++)
        if (token_is(tok, len, ply_types[i].name) || token_is(tok, len, ply_types[i].alias))
            return i;
    return -1;
}

/* Check one ASCII value of type `t`; *ival gets integers. 0 when fine, else an error code
 * with the message written. */
static int ply_ascii_value(const char *path, size_t line, const char *tok, size_t len, int t,
                           long long *ival, char *err, size_t errlen)
{
    const struct ply_type_info *ti = &ply_types[t];
    char buf[64];
    if (len >= sizeof buf)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: malformed number " TOK_FMT, line, TOK_ARG(tok, len));
    memcpy(buf, tok, len);
    buf[len] = '\0';
    char *e = NULL;
    errno = 0;
    if (ti->is_int) {
        long long v = strtoll(buf, &e, 10);
        long long lo = ti->is_signed ? -(1LL << (8 * ti->size - 1)) : 0;
        long long hi = ti->is_signed ? (1LL << (8 * ti->size - 1)) - 1
                                     : (long long)((1ULL << (8 * ti->size)) - 1);
        if (e == buf || *e || errno == ERANGE || v < lo || v > hi)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: " TOK_FMT " is not a %s", line, TOK_ARG(tok, len),
                                  ti->name);
        *ival = v;
        return 0;
    }
    double d = strtod(buf, &e);
    if (e == buf || *e)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: malformed number " TOK_FMT, line, TOK_ARG(tok, len));
    if (!isfinite(d) || fabs(d) > FLT_MAX)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: non-finite value " TOK_FMT, line, TOK_ARG(tok, len));
    if (fp_decimal_span(buf) != len) /* a decimal, as C++ streams read it: no hexadecimal */
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: malformed number " TOK_FMT, line, TOK_ARG(tok, len));
    *ival = 0;
    return 0;
}

/* A cursor over whitespace-separated tokens that counts lines. */
typedef struct tok_cursor {
    const char *p, *end;
    size_t line;
} tok_cursor;

static int cursor_next(tok_cursor *c, const char **tok, size_t *len)
{
    while (c->p < c->end && (is_blank(*c->p) || *c->p == '\n'))
        c->line += *c->p++ == '\n';
    if (c->p >= c->end)
        return 0;
    *tok = c->p;
    while (c->p < c->end && !is_blank(*c->p) && *c->p != '\n')
        c->p++;
    *len = (size_t)(c->p - *tok);
    return 1;
}

static uint64_t ply_read_uint(const unsigned char *p, int size, int big)
{
    uint64_t v = 0;
    for (int i = 0; i < size; i++)
        v |= (uint64_t)p[big ? size - 1 - i : i] << (8 * i);
    return v;
}

/* Value of type t at p (binary, size bytes), as a signed integer or a double. */
static void ply_binary_value(const unsigned char *p, int t, int big, long long *iv, double *dv)
{
    const struct ply_type_info *ti = &ply_types[t];
    uint64_t u = ply_read_uint(p, ti->size, big);
    *iv = 0;
    *dv = 0;
    if (ti->is_int) {
        if (ti->is_signed && ti->size < 8 && (u >> (8 * ti->size - 1)))
            *iv = (long long)u - (1LL << (8 * ti->size));
        else
            *iv = (long long)u;
    } else if (ti->size == 4) {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, 4);
        *dv = f;
    } else {
        memcpy(dv, &u, 8);
    }
}

/* Where a value of the body is, for a message: "line N" in ASCII; "byte N" (its offset in
 * the file) in a binary body, which has no lines (its errors used to cite the header's last). */
typedef struct ply_where {
    char text[32];
} ply_where;

static ply_where ply_at(int binary, size_t line, size_t byte)
{
    ply_where w;
    snprintf(w.text, sizeof w.text, binary ? "byte %zu" : "line %zu", binary ? byte : line);
    return w;
}

/* A scan: the file, the header's elements, where the body starts. */
typedef struct ply_scan {
    const char *path, *text, *end;
    char *err;
    size_t errlen;
    ply_element *el;           /* PLY_MAX_ELEMENTS of them, nel used */
    int nel, format;           /* format: -1 none yet, 0 ascii, 1 little endian, 2 big endian */
    const char *data;          /* the body: after the end_header line (NULL before it) */
    size_t line_no;            /* header lines read */
    unsigned long long nverts; /* the vertex element's count */
} ply_scan;

/* A format error of scan S: its message written, FP_MESH_ERR_FORMAT returned. */
#define PLY_FAIL(...)                                                                          \
    return fp__mesh_error(S->err, S->errlen, FP_MESH_ERR_FORMAT, S->path, __VA_ARGS__)

/* One header line's first tokens (at most 6; extra: more follow). */
typedef struct ply_line {
    const char *tok[6];
    size_t tl[6];
    int nt, extra;
    size_t no;
} ply_line;

/* 'format ascii|binary_little_endian|binary_big_endian 1.0' */
static int ply_format_line(ply_scan *S, const ply_line *h)
{
    const char *const *tok = h->tok;
    const size_t *tl = h->tl, line_no = h->no;
    if (S->format >= 0 || S->nel > 0)
        PLY_FAIL("line %zu: 'format' must come once, before any element", line_no);
    if (h->nt != 3 || h->extra || !token_is(tok[2], tl[2], "1.0"))
        PLY_FAIL("line %zu: expected 'format ascii|binary_little_endian|"
                 "binary_big_endian 1.0'", line_no);
    if (token_is(tok[1], tl[1], "ascii")) S->format = 0;
    else if (token_is(tok[1], tl[1], "binary_little_endian")) S->format = 1;
    else if (token_is(tok[1], tl[1], "binary_big_endian")) S->format = 2;
    else
        PLY_FAIL("line %zu: unknown PLY format " TOK_FMT, line_no, TOK_ARG(tok[1], tl[1]));
    return FP_MESH_OK;
}

/* 'element NAME COUNT' */
static int ply_element_line(ply_scan *S, const ply_line *h)
{
    const char *const *tok = h->tok;
    const size_t *tl = h->tl, line_no = h->no;
    ply_element *el = S->el;
    if (S->format < 0)
        PLY_FAIL("line %zu: 'element' before the 'format' line", line_no);
    if (h->nt != 3 || h->extra)
        PLY_FAIL("line %zu: expected 'element NAME COUNT'", line_no);
    unsigned long cnt;
    if (!parse_count(tok[2], tl[2], &cnt) || cnt > UINT32_MAX)
        PLY_FAIL("line %zu: element count " TOK_FMT " is not a number from 0 to %u",
                 line_no, TOK_ARG(tok[2], tl[2]), UINT32_MAX);
    if (S->nel == PLY_MAX_ELEMENTS)
        PLY_FAIL("line %zu: more than %d elements", line_no, PLY_MAX_ELEMENTS);
    ply_element *e = &el[S->nel++];
    e->kind = token_is(tok[1], tl[1], "vertex") ? PLY_VERTEX
              : token_is(tok[1], tl[1], "face") ? PLY_FACE : PLY_OTHER;
    e->count = cnt;
    e->line = line_no;
    for (int i = 0; i + 1 < S->nel; i++)
        if (e->kind != PLY_OTHER && el[i].kind == e->kind)
            PLY_FAIL("line %zu: a second '%.*s' element", line_no, (int)tl[1], tok[1]);
    return FP_MESH_OK;
}

/* 'property list COUNT_TYPE TYPE NAME' of element e into *pr, its name into *name. */
static int ply_list_property(ply_scan *S, const ply_line *h, const ply_element *e,
                             ply_prop *pr, const char **name, size_t *namelen)
{
    const char *const *tok = h->tok;
    const size_t *tl = h->tl, line_no = h->no;
    if (h->nt != 5 || h->extra)
        PLY_FAIL("line %zu: expected 'property list COUNT_TYPE TYPE NAME'", line_no);
    pr->count_type = ply_type(tok[2], tl[2]);
    pr->type = ply_type(tok[3], tl[3]);
    *name = tok[4];
    *namelen = tl[4];
    /* the count types OpenMesh's reader accepts */
    if (!token_is(tok[2], tl[2], "uchar") && !token_is(tok[2], tl[2], "uint8") &&
        !token_is(tok[2], tl[2], "uint16") && !token_is(tok[2], tl[2], "int"))
        PLY_FAIL("line %zu: list count type " TOK_FMT " is not supported (uchar, "
                 "uint8, uint16 or int)", line_no, TOK_ARG(tok[2], tl[2]));
    if (pr->type < 0)
        PLY_FAIL("line %zu: unknown PLY type " TOK_FMT, line_no, TOK_ARG(tok[3], tl[3]));
    if (e->kind != PLY_FACE)
        PLY_FAIL("line %zu: list properties are supported in the 'face' element "
                 "only", line_no);
    if (token_is(*name, *namelen, "vertex_indices") || token_is(*name, *namelen, "vertex_index")) {
        if (e->nprops != 0)
            PLY_FAIL("line %zu: 'vertex_indices' must be the face's first property", line_no);
        if (!ply_types[pr->type].is_int)
            PLY_FAIL("line %zu: vertex indices must have an integer type", line_no);
        pr->role = PLY_ROLE_VINDEX;
    } else if (token_is(*name, *namelen, "texcoord") && e->nprops > 0 &&
               e->props[0].role == PLY_ROLE_VINDEX) {
        pr->role = PLY_ROLE_TEXCOORD;
    } else {
        PLY_FAIL("line %zu: list property " TOK_FMT " is not supported (face "
                 "vertex_indices first, then texcoord)", line_no, TOK_ARG(*name, *namelen));
    }
    return FP_MESH_OK;
}

/* 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME', of the last element. */
static int ply_property_line(ply_scan *S, const ply_line *h)
{
    const char *const *tok = h->tok;
    const size_t *tl = h->tl, line_no = h->no;
    if (S->nel == 0)
        PLY_FAIL("line %zu: 'property' before any 'element'", line_no);
    ply_element *e = &S->el[S->nel - 1];
    if (e->nprops == PLY_MAX_PROPS)
        PLY_FAIL("line %zu: more than %d properties in one element", line_no, PLY_MAX_PROPS);
    ply_prop pr = {-1, -1, PLY_ROLE_OTHER};
    const char *name = NULL;
    size_t namelen = 0;
    if (h->nt >= 2 && token_is(tok[1], tl[1], "list")) {
        const int rc = ply_list_property(S, h, e, &pr, &name, &namelen);
        if (rc)
            return rc;
    } else {
        if (h->nt != 3 || h->extra)
            PLY_FAIL("line %zu: expected 'property TYPE NAME'", line_no);
        pr.type = ply_type(tok[1], tl[1]);
        name = tok[2];
        namelen = tl[2];
        if (pr.type < 0)
            PLY_FAIL("line %zu: unknown PLY type " TOK_FMT, line_no, TOK_ARG(tok[1], tl[1]));
    }
    if (ply_type(name, namelen) >= 0 || token_is(name, namelen, "list"))
        PLY_FAIL("line %zu: property name " TOK_FMT " is a type name", line_no,
                 TOK_ARG(name, namelen));
    /* OpenMesh reads a vertex's position from x, y and z by name, 0 for one that is
     * missing, the last one for a repeated one: the file's positions would be lost */
    const int axis = namelen == 1 && *name >= 'x' && *name <= 'z' ? *name - 'x' : -1;
    if (e->kind == PLY_VERTEX && axis >= 0 && pr.count_type < 0) {
        if (e->xyz_line[axis])
            PLY_FAIL("line %zu: vertex property '%c' again (first on line %zu)", line_no,
                     *name, e->xyz_line[axis]);
        e->xyz_line[axis] = line_no;
    }
    e->props[e->nprops++] = pr;
    return FP_MESH_OK;
}

/* The header, line by line, up to and with end_header: S->el, nel, format, data. */
static int ply_header(ply_scan *S)
{
    const char *p = S->text, *const end = S->end;
    int prev_was_decl = 0; /* the line before was an element/property line without trailing
                              blanks (OpenMesh finds binary data by that) */
    int prev_crlf = 0;
    while (!S->data) {
        if (p >= end)
            PLY_FAIL("no 'end_header' line: the PLY header does not end");
        const size_t line_no = ++S->line_no;
        const char *eol = memchr(p, '\n', (size_t)(end - p));
        if (!eol)
            PLY_FAIL("line %zu: no 'end_header' line: the PLY header does not end", line_no);
        if (memchr(p, '\0', (size_t)(eol - p)))
            PLY_FAIL("line %zu: NUL byte in the PLY header", line_no);
        const int crlf = eol > p && eol[-1] == '\r';
        /* a blank before the line end ("\r\n" alone has none: eol[-2] would be before p) */
        const int trailing = eol - p > crlf && is_blank(eol[crlf ? -2 : -1]);
        obj_line l = {p, eol};
        p = eol + 1;
        ply_line h = {.no = line_no};
        while (h.nt < 6 && next_token(&l, &h.tok[h.nt], &h.tl[h.nt]))
            h.nt++;
        const char *more;
        size_t morelen;
        h.extra = next_token(&l, &more, &morelen);
        const char *const *tok = h.tok;
        const size_t *tl = h.tl;
        if (line_no == 1) {
            if (h.nt != 1 || !token_is(tok[0], tl[0], "ply"))
                PLY_FAIL("line 1: not a PLY file (the first line is not 'ply')");
            continue;
        }
        int decl = 0, rc = FP_MESH_OK;
        if (h.nt == 0) {
            PLY_FAIL("line %zu: empty line in the PLY header", line_no);
        } else if (token_is(tok[0], tl[0], "comment") || token_is(tok[0], tl[0], "obj_info")) {
            /* free text, allowed anywhere after line 1 (Turk's PLY). OpenMesh mishandles them
             * (it reads obj_info's words as keywords; after a comment it finds a binary body
             * one byte late), so the loader hands it the text without these lines
             * (mesh_openmesh.cpp's ply_without_notes): prev_was_decl and prev_crlf stay those
             * of the line before them. */
            continue;
        } else if (token_is(tok[0], tl[0], "format")) {
            rc = ply_format_line(S, &h);
        } else if (token_is(tok[0], tl[0], "element")) {
            rc = ply_element_line(S, &h);
            decl = 1;
        } else if (token_is(tok[0], tl[0], "property")) {
            rc = ply_property_line(S, &h);
            decl = 1;
        } else if (token_is(tok[0], tl[0], "end_header")) {
            if (h.nt != 1 || h.extra)
                PLY_FAIL("line %zu: text after 'end_header'", line_no);
            if (S->format > 0 && (!prev_was_decl || prev_crlf != crlf || trailing ||
                                  (size_t)(eol - tok[0]) != 10u + (unsigned)crlf))
                PLY_FAIL("line %zu: in a binary PLY, 'end_header' must directly follow an "
                         "element or property line, alone on its line", line_no);
            S->data = p;
        } else {
            PLY_FAIL("line %zu: unknown PLY header keyword " TOK_FMT, line_no,
                     TOK_ARG(tok[0], tl[0]));
        }
        if (rc)
            return rc;
        prev_was_decl = decl && !trailing;
        prev_crlf = crlf;
    }
    return FP_MESH_OK;
}

/* The elements: vertex with x, y, z once each; their counts against the file's size.
 * *faces and *vertices get the header's counts (*faces before the size check, as ever). */
static int ply_layout(ply_scan *S, size_t *vertices, size_t *faces)
{
    const int format = S->format;
    if (format < 0)
        PLY_FAIL("no 'format' line in the PLY header");
    unsigned long long need = 0, nverts = 0;
    for (int i = 0; i < S->nel; i++) {
        const ply_element *e = &S->el[i];
        if (e->count > 0 && e->nprops == 0)
            PLY_FAIL("line %zu: element with %llu rows but no properties", e->line, e->count);
        for (int k = 0; k < 3 && e->kind == PLY_VERTEX; k++)
            if (!e->xyz_line[k])
                PLY_FAIL("line %zu: the vertex element has no property '%c' (x, y and z are "
                         "required)", e->line, 'x' + k);
        unsigned long long row = 0;
        for (int k = 0; k < e->nprops; k++)
            row += format == 0 ? 1u
                               : (unsigned)(e->props[k].count_type >= 0
                                                ? ply_types[e->props[k].count_type].size
                                                : ply_types[e->props[k].type].size);
        need += e->count * row;
        if (e->kind == PLY_VERTEX)
            nverts = e->count;
        if (e->kind == PLY_FACE)
            *faces = (size_t)e->count;
    }
    const size_t avail = (size_t)(S->end - S->data);
    if (need > avail)
        PLY_FAIL("the header's element counts need at least %llu bytes of data, the file "
                 "has %zu", need, avail);
    *vertices = (size_t)nverts;
    S->nverts = nverts;
    return FP_MESH_OK;
}

/* Where the walk is in the body: ASCII tokens with their lines, or binary bytes. */
typedef struct ply_body {
    tok_cursor c;
    const unsigned char *b, *bend;
    int big;
} ply_body;

/* The count of list property pr in row r of element e (number i) into *n, checked; a face's
 * vertex_indices count into *corners, against which its texcoord count is checked. */
static int ply_list_count(ply_scan *S, ply_body *y, const ply_element *e, int i,
                          unsigned long long r, const ply_prop *pr, long long *corners,
                          long long *n)
{
    const int format = S->format;
    long long cnt;
    const size_t cnt_byte = (size_t)((const char *)y->b - S->text);
    if (format == 0) {
        const char *t;
        size_t tlen;
        if (!cursor_next(&y->c, &t, &tlen))
            PLY_FAIL("the data ends in row %llu of %llu of element %d", r, e->count, i);
        const int rc = ply_ascii_value(S->path, y->c.line, t, tlen, pr->count_type, &cnt,
                                       S->err, S->errlen);
        if (rc)
            return rc;
    } else {
        const int cs = ply_types[pr->count_type].size;
        if ((size_t)(y->bend - y->b) < (size_t)cs)
            PLY_FAIL("the data ends in row %llu of %llu of element %d", r, e->count, i);
        double dv;
        ply_binary_value(y->b, pr->count_type, y->big, &cnt, &dv);
        y->b += cs;
    }
    const ply_where at = ply_at(format != 0, y->c.line, cnt_byte);
    if (cnt < 0)
        PLY_FAIL("%s: negative list count in row %llu", at.text, r);
    if (pr->role == PLY_ROLE_VINDEX) {
        if (cnt < 3)
            PLY_FAIL("%s: face %llu has %lld corners (at least 3)", at.text, r, cnt);
        *corners = cnt;
    } else if (pr->role == PLY_ROLE_TEXCOORD && cnt != 2 * *corners && cnt != 3 * *corners) {
        PLY_FAIL("%s: face %llu: %lld texture coordinates for %lld corners", at.text, r, cnt,
                 *corners);
    }
    *n = cnt;
    if (format != 0 &&
        (unsigned long long)*n * (unsigned)ply_types[pr->type].size > (size_t)(y->bend - y->b))
        PLY_FAIL("%s: face %llu: a list of %lld values runs past the file's end", at.text, r,
                 *n);
    return FP_MESH_OK;
}

/* One value of property pr in row r of element e (number i): its type and range, a float
 * finite, a vertex index below the vertex count. */
static int ply_value(ply_scan *S, ply_body *y, const ply_element *e, int i,
                     unsigned long long r, const ply_prop *pr)
{
    long long iv = 0;
    double dv = 0;
    size_t at = y->c.line;
    const size_t at_byte = (size_t)((const char *)y->b - S->text);
    if (S->format == 0) {
        const char *t;
        size_t tlen;
        if (!cursor_next(&y->c, &t, &tlen))
            PLY_FAIL("the data ends in row %llu of %llu of element %d", r, e->count, i);
        at = y->c.line;
        const int rc = ply_ascii_value(S->path, y->c.line, t, tlen, pr->type, &iv, S->err,
                                       S->errlen);
        if (rc)
            return rc;
    } else {
        const int sz = ply_types[pr->type].size;
        if ((size_t)(y->bend - y->b) < (size_t)sz)
            PLY_FAIL("the data ends in row %llu of %llu of element %d", r, e->count, i);
        ply_binary_value(y->b, pr->type, y->big, &iv, &dv);
        y->b += sz;
        if (!ply_types[pr->type].is_int && (!isfinite(dv) || fabs(dv) > FLT_MAX))
            PLY_FAIL("byte %zu: non-finite value in row %llu of element %d", at_byte, r, i);
    }
    if (pr->role == PLY_ROLE_VINDEX && (iv < 0 || (unsigned long long)iv >= S->nverts))
        PLY_FAIL("%s: face %llu references vertex %lld, but the file has %llu vertices",
                 ply_at(S->format != 0, at, at_byte).text, r, iv, S->nverts);
    return FP_MESH_OK;
}

/* The walk: every value's type and range, list counts, indices, finite floats; nothing after
 * the last element. */
static int ply_walk(ply_scan *S)
{
    ply_body y = {{S->data, S->end, S->line_no + 1},
                  (const unsigned char *)S->data,
                  (const unsigned char *)S->end,
                  S->format == 2};
    for (int i = 0; i < S->nel; i++) {
        const ply_element *e = &S->el[i];
        for (unsigned long long r = 0; r < e->count; r++) {
            long long corners = 0;
            for (int k = 0; k < e->nprops; k++) {
                const ply_prop *pr = &e->props[k];
                long long n = 1;
                int rc = pr->count_type >= 0 ? ply_list_count(S, &y, e, i, r, pr, &corners, &n)
                                             : FP_MESH_OK;
                for (long long j = 0; j < n && !rc; j++)
                    rc = ply_value(S, &y, e, i, r, pr);
                if (rc)
                    return rc;
            }
        }
    }
    if (S->format == 0) {
        const char *t;
        size_t tlen;
        if (cursor_next(&y.c, &t, &tlen))
            PLY_FAIL("line %zu: data after the last element: " TOK_FMT, y.c.line,
                     TOK_ARG(t, tlen));
    } else if (y.b != y.bend) {
        PLY_FAIL("%zu bytes after the last element (the header's counts do not fit the file)",
                 (size_t)(y.bend - y.b));
    }
    return FP_MESH_OK;
}
#undef PLY_FAIL

int fp__ply_scan(const char *path, const char *text, size_t len, size_t *vertices,
                 size_t *faces, int *format, char *err, size_t errlen)
{
    *vertices = *faces = 0;
    *format = -1;
    ply_element *el = calloc(PLY_MAX_ELEMENTS, sizeof *el);
    if (!el)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_NOMEM, path, "out of memory");
    ply_scan S = {path, text, text + len, err, errlen, el, 0, -1, NULL, 0, 0};
    int rc = ply_header(&S);
    if (rc == FP_MESH_OK)
        rc = ply_layout(&S, vertices, faces);
    if (rc == FP_MESH_OK)
        rc = ply_walk(&S);
    if (rc == FP_MESH_OK)
        *format = S.format;
    free(el);
    return rc;
}
