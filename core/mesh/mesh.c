/* fp_mesh: the C part: allocation, copies, normals, bounds, error text, the OBJ scan. */
#include "mesh_internal.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *fp_mesh_strerror(int result)
{
    switch (result) {
    case FP_MESH_OK: return "success";
    case FP_MESH_ERR_IO: return "file cannot be read or written";
    case FP_MESH_ERR_FORMAT: return "malformed mesh file";
    case FP_MESH_ERR_UNSUPPORTED: return "unsupported mesh format or feature";
    case FP_MESH_ERR_NOMEM: return "out of memory";
    case FP_MESH_ERR_INVALID: return "invalid argument";
    default: return "unknown fp_mesh result";
    }
}

int fp__mesh_error(char *err, size_t errlen, int code, const char *path, const char *fmt, ...)
{
    if (!err || errlen == 0)
        return code;
    int k = snprintf(err, errlen, "%s: ", path ? path : "(mesh)");
    if (k < 0)
        k = 0;
    if ((size_t)k < errlen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err + k, errlen - (size_t)k, fmt, ap);
        va_end(ap);
    }
    return code;
}

void fp__mesh_extension(const char *path, char *ext, size_t extlen)
{
    if (!ext || extlen == 0)
        return;
    ext[0] = '\0';
    if (!path)
        return;
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash))
        return;
    size_t i = 0;
    for (const char *p = dot + 1; *p && i + 1 < extlen; p++)
        ext[i++] = (char)tolower((unsigned char)*p);
    ext[i] = '\0';
}

/* ---- allocation ---------------------------------------------------------------------- */

static void *alloc_array(size_t count, size_t elem)
{
    if (count != 0 && elem > SIZE_MAX / count)
        return NULL;
    /* calloc(0) may return NULL; always ask for at least one byte so NULL means failure */
    return calloc(count ? count : 1, elem);
}

fp_mesh *fp_mesh_create(size_t vertex_count, size_t triangle_count, int with_uvs)
{
    fp_mesh *m = calloc(1, sizeof *m);
    if (!m)
        return NULL;
    m->vertex_count = vertex_count;
    m->triangle_count = triangle_count;
    int ok = vertex_count <= SIZE_MAX / 3 && triangle_count <= SIZE_MAX / 3;
    if (ok) {
        m->positions = alloc_array(vertex_count * 3, sizeof(float));
        m->normals = alloc_array(vertex_count * 3, sizeof(float));
        m->triangles = alloc_array(triangle_count * 3, sizeof(uint32_t));
        if (with_uvs)
            m->uvs = alloc_array(vertex_count * 2, sizeof(float));
        ok = m->positions && m->normals && m->triangles && (!with_uvs || m->uvs);
    }
    if (!ok)
        fp_mesh_free(&m);
    return m;
}

void fp_mesh_free(fp_mesh **mesh)
{
    if (!mesh || !*mesh)
        return;
    fp_mesh *m = *mesh;
    free(m->positions);
    free(m->normals);
    free(m->uvs);
    free(m->triangles);
    free(m->source_path);
    free(m);
    *mesh = NULL;
}

fp_mesh *fp_mesh_copy(const fp_mesh *mesh)
{
    if (!mesh)
        return NULL;
    fp_mesh *c = fp_mesh_create(mesh->vertex_count, mesh->triangle_count, mesh->uvs != NULL);
    if (!c)
        return NULL;
    size_t n = mesh->vertex_count, t = mesh->triangle_count;
    if (mesh->positions)
        memcpy(c->positions, mesh->positions, n * 3 * sizeof(float));
    if (mesh->normals) {
        memcpy(c->normals, mesh->normals, n * 3 * sizeof(float));
    } else {
        free(c->normals);
        c->normals = NULL;
    }
    if (mesh->uvs)
        memcpy(c->uvs, mesh->uvs, n * 2 * sizeof(float));
    if (mesh->triangles)
        memcpy(c->triangles, mesh->triangles, t * 3 * sizeof(uint32_t));
    if (mesh->source_path) {
        size_t len = strlen(mesh->source_path) + 1;
        c->source_path = malloc(len);
        if (!c->source_path) {
            fp_mesh_free(&c);
            return NULL;
        }
        memcpy(c->source_path, mesh->source_path, len);
    }
    return c;
}

/* ---- normals and bounds -------------------------------------------------------------- */

int fp_mesh_normals(const uint32_t *tris, size_t t, const float *pos, size_t n,
                    float *normals_out)
{
    if ((n > 0 && (!pos || !normals_out)) || (t > 0 && !tris))
        return FP_MESH_ERR_INVALID;
    if (n == 0)
        return t == 0 ? FP_MESH_OK : FP_MESH_ERR_INVALID;
    memset(normals_out, 0, n * 3 * sizeof(float));
    for (size_t k = 0; k < t; k++) {
        uint32_t a = tris[3 * k], b = tris[3 * k + 1], c = tris[3 * k + 2];
        if (a >= n || b >= n || c >= n) {
            memset(normals_out, 0, n * 3 * sizeof(float));
            return FP_MESH_ERR_INVALID;
        }
        const float *pa = pos + 3 * (size_t)a, *pb = pos + 3 * (size_t)b,
                    *pc = pos + 3 * (size_t)c;
        float e1x = pb[0] - pa[0], e1y = pb[1] - pa[1], e1z = pb[2] - pa[2];
        float e2x = pc[0] - pa[0], e2y = pc[1] - pa[1], e2z = pc[2] - pa[2];
        /* (pb - pa) x (pc - pa): length = twice the area, so the sum is area-weighted */
        float cx = e1y * e2z - e1z * e2y;
        float cy = e1z * e2x - e1x * e2z;
        float cz = e1x * e2y - e1y * e2x;
        float *na = normals_out + 3 * (size_t)a, *nb = normals_out + 3 * (size_t)b,
              *nc = normals_out + 3 * (size_t)c;
        na[0] += cx; na[1] += cy; na[2] += cz;
        nb[0] += cx; nb[1] += cy; nb[2] += cz;
        nc[0] += cx; nc[1] += cy; nc[2] += cz;
    }
    for (size_t i = 0; i < n; i++) {
        float *v = normals_out + 3 * i;
        float len = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (len > 0.0f && isfinite(len)) {
            float s = 1.0f / len;
            v[0] *= s; v[1] *= s; v[2] *= s;
        } else {
            v[0] = v[1] = v[2] = 0.0f; /* no area around it (or non-finite input) */
        }
    }
    return FP_MESH_OK;
}

int fp_mesh_compute_normals(fp_mesh *mesh)
{
    if (!mesh)
        return FP_MESH_ERR_INVALID;
    if (!mesh->normals) {
        mesh->normals = alloc_array(mesh->vertex_count * 3, sizeof(float));
        if (!mesh->normals)
            return FP_MESH_ERR_NOMEM;
    }
    return fp_mesh_normals(mesh->triangles, mesh->triangle_count, mesh->positions,
                           mesh->vertex_count, mesh->normals);
}

void fp_mesh_bounds(const fp_mesh *mesh, float min[3], float max[3])
{
    for (int k = 0; k < 3; k++)
        min[k] = max[k] = 0.0f;
    if (!mesh || mesh->vertex_count == 0 || !mesh->positions)
        return;
    for (int k = 0; k < 3; k++)
        min[k] = max[k] = mesh->positions[k];
    for (size_t i = 1; i < mesh->vertex_count; i++) {
        const float *p = mesh->positions + 3 * i;
        for (int k = 0; k < 3; k++) {
            if (p[k] < min[k]) min[k] = p[k];
            if (p[k] > max[k]) max[k] = p[k];
        }
    }
}

/* ---- OBJ scan ------------------------------------------------------------------------ */

/* Statements of the OBJ format (Wavefront, "Object Files (.obj)" appendix B1) that we accept
 * and, except v/vt/vn/f, ignore. */
static const char *const obj_known[] = {
    "v", "vt", "vn", "vp", "f", "fo", "l", "p", "o", "g", "s", "mg", "usemtl", "mtllib",
    "usemap", "maplib", "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm",
    "trim", "hole", "scrv", "sp", "end", "con", "lod", "shadow_obj", "trace_obj", "ctech",
    "stech", "bevel", "c_interp", "d_interp", "call", "csh", NULL};

typedef struct obj_line {
    const char *p, *end; /* cursor and end of the line (before \r\n) */
} obj_line;

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* Next whitespace-separated token of the line; 0 at the end. */
static int next_token(obj_line *l, const char **tok, size_t *toklen)
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

static int parse_number(const char *tok, size_t len, double *out)
{
    char *e = NULL;
    errno = 0;
    double d = strtod(tok, &e);
    if (e != tok + len)
        return 0;
    *out = d;
    return 1;
}

/* One corner index: [-]digits, ending at '/' or the token end. Returns 1 with *idx, 2 for an
 * empty field when allow_empty (*idx = 0), or 0 on a syntax error. */
static int parse_index(const char **p, const char *end, long *idx, int allow_empty)
{
    const char *s = *p;
    if (s == end || *s == '/') {
        *idx = 0;
        return allow_empty ? 2 : 0;
    }
    char *e = NULL;
    errno = 0;
    long v = strtol(s, &e, 10);
    if (e == s || e > end || (e < end && *e != '/') || errno == ERANGE)
        return 0;
    *idx = v;
    *p = e;
    return 1;
}

#define TOK_FMT "'%.*s'"
#define TOK_ARG(t, n) (int)((n) > 40 ? 40 : (n)), (t)

/* Check one index against the count known at this point (`seen`, for relative indices) and
 * the file's total (`total`, for absolute ones; forward references are allowed as OpenMesh
 * reads all vertices first). */
static int index_ok(long idx, size_t seen, size_t total)
{
    if (idx > 0)
        return (unsigned long)idx <= total;
    if (idx < 0)
        return (unsigned long)(-(idx + 1)) < seen; /* -1 is the last one seen */
    return 0;
}

int fp__obj_scan(const char *path, const char *text, size_t len, fp__obj_info *info,
                 char *err, size_t errlen)
{
    memset(info, 0, sizeof *info);
    const char *nul = memchr(text, '\0', len);
    if (nul) {
        size_t line = 1;
        for (const char *q = text; q < nul; q++)
            line += *q == '\n';
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: NUL byte in OBJ text (binary file?)", line);
    }
    fp__obj_info total = {0};
    /* pass 0: syntax, numbers, counts; pass 1: face index ranges against the totals */
    for (int pass = 0; pass < 2; pass++) {
        fp__obj_info seen = {0};
        size_t line_no = 0;
        const char *p = text, *text_end = text + len;
        while (p < text_end) {
            line_no++;
            const char *eol = memchr(p, '\n', (size_t)(text_end - p));
            if (!eol)
                eol = text_end;
            obj_line l = {p, eol};
            p = eol + 1;
            const char *kw;
            size_t kwlen;
            if (!next_token(&l, &kw, &kwlen) || kw[0] == '#')
                continue;
            int known = 0;
            for (const char *const *k = obj_known; *k; k++)
                if (strlen(*k) == kwlen && memcmp(*k, kw, kwlen) == 0)
                    known = 1;
            if (!known)
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: unknown OBJ statement " TOK_FMT, line_no,
                                      TOK_ARG(kw, kwlen));
            int is_v = kwlen == 1 && kw[0] == 'v';
            int is_vt = kwlen == 2 && kw[0] == 'v' && kw[1] == 't';
            int is_vn = kwlen == 2 && kw[0] == 'v' && kw[1] == 'n';
            int is_f = kwlen == 1 && kw[0] == 'f';
            if (is_v || is_vt || is_vn) {
                size_t lo = is_v ? 3 : is_vt ? 1 : 3, hi = is_v ? 7 : 3, count = 0;
                const char *tok;
                size_t toklen;
                while (next_token(&l, &tok, &toklen)) {
                    double d;
                    if (pass == 0 && !parse_number(tok, toklen, &d))
                        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                              "line %zu: malformed number " TOK_FMT
                                              " in '%.*s' statement",
                                              line_no, TOK_ARG(tok, toklen), (int)kwlen, kw);
                    if (pass == 0 && !isfinite(d))
                        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                              "line %zu: non-finite value " TOK_FMT
                                              " in '%.*s' statement",
                                              line_no, TOK_ARG(tok, toklen), (int)kwlen, kw);
                    count++;
                }
                if (count < lo || count > hi)
                    return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                          "line %zu: '%.*s' statement has %zu numbers, "
                                          "expected %zu%s",
                                          line_no, (int)kwlen, kw, count, lo,
                                          hi > lo ? " or more" : "");
                if (is_v) seen.v++;
                else if (is_vt) seen.vt++;
                else seen.vn++;
            } else if (is_f) {
                size_t corners = 0, distinct = 0;
                size_t first[3] = {0, 0, 0}; /* the first three distinct vertex indices */
                const char *tok;
                size_t toklen;
                while (next_token(&l, &tok, &toklen)) {
                    const char *q = tok, *qe = tok + toklen;
                    long iv = 0, it = 0, in = 0;
                    int ok = parse_index(&q, qe, &iv, 0);
                    int has_t = 0, has_n = 0;
                    if (ok && q < qe) { /* "/vt" */
                        q++;
                        ok = parse_index(&q, qe, &it, 1);
                        has_t = ok == 1;
                        if (ok && q < qe) { /* "/vn" */
                            q++;
                            ok = parse_index(&q, qe, &in, 0) && q == qe;
                            has_n = ok;
                        }
                    }
                    if (!ok)
                        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                              "line %zu: malformed face corner " TOK_FMT,
                                              line_no, TOK_ARG(tok, toklen));
                    if (pass == 1) {
                        const char *what = NULL;
                        size_t have = 0;
                        long bad = 0;
                        if (!index_ok(iv, seen.v, total.v)) {
                            what = "vertex"; have = total.v; bad = iv;
                        } else if (has_t && !index_ok(it, seen.vt, total.vt)) {
                            what = "texture coordinate"; have = total.vt; bad = it;
                        } else if (has_n && !index_ok(in, seen.vn, total.vn)) {
                            what = "normal"; have = total.vn; bad = in;
                        }
                        if (what)
                            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                                  "line %zu: face %s index %ld out of range "
                                                  "(the file has %zu)",
                                                  line_no, what, bad, have);
                        size_t v = iv > 0 ? (size_t)iv - 1 : seen.v - (size_t)(-iv);
                        int repeat = 0;
                        for (size_t d = 0; d < distinct && d < 3; d++)
                            repeat |= first[d] == v;
                        if (!repeat && distinct < 3)
                            first[distinct++] = v;
                    }
                    corners++;
                }
                if (corners < 3)
                    return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                          "line %zu: face with %zu corners (at least 3)",
                                          line_no, corners);
                seen.faces++;
                seen.triangles += corners - 2;
                seen.degenerate += pass == 1 && distinct < 3;
            }
        }
        total = seen;
    }
    *info = total;
    return FP_MESH_OK;
}

/* ---- OFF scan ------------------------------------------------------------------------ */

typedef struct text_lines {
    const char *p, *end;
    size_t line_no;
} text_lines;

/* The next line holding a token (blank lines are skipped, as OpenMesh's >> does). */
static int next_nonblank_line(text_lines *t, obj_line *l)
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

static int parse_count(const char *tok, size_t len, unsigned long *out)
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

int fp__off_scan(const char *path, const char *text, size_t len, char *err, size_t errlen)
{
    if (memchr(text, '\0', len) && !strstr(text, "BINARY"))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "NUL byte in ASCII OFF text");
    text_lines t = {text, text + len, 0};
    obj_line l;
    if (!next_nonblank_line(&t, &l))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path, "no OFF header");
    const char *tok = NULL;
    size_t toklen = 0;
    if (!next_token(&l, &tok, &toklen))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path, "no OFF header");
    /* [ST][C][N][4][n]OFF */
    const char *h = tok, *he = tok + toklen;
    int st = 0, c = 0, n = 0;
    if (he - h >= 2 && h[0] == 'S' && h[1] == 'T') { st = 1; h += 2; }
    if (h < he && *h == 'C') { c = 1; h++; }
    if (h < he && *h == 'N') { n = 1; h++; }
    if (he - h != 3 || memcmp(h, "OFF", 3) != 0)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: not an OFF header " TOK_FMT " (4D and nOFF are not "
                              "supported)", t.line_no, TOK_ARG(tok, toklen));
    if (next_token(&l, &tok, &toklen)) {
        if (toklen == 6 && memcmp(tok, "BINARY", 6) == 0)
            return FP_MESH_OK; /* binary OFF: OpenMesh's reader checks sizes */
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: put the vertex and face counts on their own line",
                              t.line_no);
    }
    (void)c;
    unsigned long counts[3];
    if (!next_nonblank_line(&t, &l))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path, "no vertex/face counts");
    for (int k = 0; k < 3; k++)
        if (!next_token(&l, &tok, &toklen) || !parse_count(tok, toklen, &counts[k]))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: expected three counts: vertices faces edges",
                                  t.line_no);
    const unsigned long nv = counts[0], nf = counts[1];
    const size_t need = 3 + (n ? 3u : 0u) + (st ? 2u : 0u);
    for (unsigned long i = 0; i < nv; i++) {
        if (!next_nonblank_line(&t, &l))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "file ends after %lu of %lu vertices", i, nv);
        size_t have = 0;
        while (next_token(&l, &tok, &toklen)) {
            double d;
            if (!parse_number(tok, toklen, &d))
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: malformed number " TOK_FMT " in vertex %lu",
                                      t.line_no, TOK_ARG(tok, toklen), i);
            if (!isfinite(d))
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: non-finite value " TOK_FMT " in vertex %lu",
                                      t.line_no, TOK_ARG(tok, toklen), i);
            have++;
        }
        if (have < need)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: vertex %lu has %zu numbers, expected %zu",
                                  t.line_no, i, have, need);
    }
    for (unsigned long i = 0; i < nf; i++) {
        if (!next_nonblank_line(&t, &l))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "file ends after %lu of %lu faces", i, nf);
        unsigned long k, idx;
        if (!next_token(&l, &tok, &toklen) || !parse_count(tok, toklen, &k) || k < 3)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: face %lu does not start with a corner count of "
                                  "3 or more", t.line_no, i);
        for (unsigned long j = 0; j < k; j++) {
            if (!next_token(&l, &tok, &toklen) || !parse_count(tok, toklen, &idx))
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: face %lu: expected %lu vertex indices",
                                      t.line_no, i, k);
            if (idx >= nv)
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: face %lu references vertex %lu, but the file "
                                      "has %lu vertices", t.line_no, i, idx, nv);
        }
    }
    return FP_MESH_OK;
}

/* ---- ASCII PLY and STL scans --------------------------------------------------------- */

/* Check that every token from line `l` on is a finite number (label names the part). */
static int numbers_only(const char *path, text_lines *t, const char *label, char *err,
                        size_t errlen)
{
    obj_line l;
    while (next_nonblank_line(t, &l)) {
        const char *tok;
        size_t toklen;
        while (next_token(&l, &tok, &toklen)) {
            double d;
            if (!parse_number(tok, toklen, &d))
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: malformed number " TOK_FMT " in %s",
                                      t->line_no, TOK_ARG(tok, toklen), label);
            if (!isfinite(d))
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: non-finite value " TOK_FMT " in %s",
                                      t->line_no, TOK_ARG(tok, toklen), label);
        }
    }
    return FP_MESH_OK;
}

static int token_is(const char *tok, size_t len, const char *word)
{
    return strlen(word) == len && memcmp(tok, word, len) == 0;
}

int fp__ply_scan(const char *path, const char *text, size_t len, char *err, size_t errlen)
{
    text_lines t = {text, text + len, 0};
    obj_line l;
    int ascii = 0;
    while (next_nonblank_line(&t, &l)) {
        const char *tok = NULL, *tok2 = NULL;
        size_t toklen = 0, toklen2 = 0;
        next_token(&l, &tok, &toklen);
        if (token_is(tok, toklen, "format") && next_token(&l, &tok2, &toklen2))
            ascii = token_is(tok2, toklen2, "ascii");
        if (token_is(tok, toklen, "end_header"))
            return ascii ? numbers_only(path, &t, "the PLY data", err, errlen) : FP_MESH_OK;
    }
    return FP_MESH_OK; /* no header end: OpenMesh's reader reports it */
}

int fp__stl_ascii_scan(const char *path, const char *text, size_t len, char *err,
                       size_t errlen)
{
    if (memchr(text, '\0', len))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "NUL byte in ASCII STL text");
    text_lines t = {text, text + len, 0};
    obj_line l;
    size_t vertices = 0;
    while (next_nonblank_line(&t, &l)) {
        const char *tok = NULL;
        size_t toklen = 0;
        next_token(&l, &tok, &toklen);
        int is_vertex = token_is(tok, toklen, "vertex");
        if (token_is(tok, toklen, "facet")) {
            if (!next_token(&l, &tok, &toklen) || !token_is(tok, toklen, "normal"))
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: 'facet' without 'normal'", t.line_no);
        } else if (!is_vertex) {
            static const char *const words[] = {"solid", "outer", "endloop", "endfacet",
                                                "endsolid", NULL};
            int known = 0;
            for (const char *const *w = words; *w; w++)
                known |= token_is(tok, toklen, *w);
            if (!known)
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: unknown STL keyword " TOK_FMT, t.line_no,
                                      TOK_ARG(tok, toklen));
            continue;
        }
        int count = 0;
        while (next_token(&l, &tok, &toklen)) {
            double d;
            if (!parse_number(tok, toklen, &d) || !isfinite(d))
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: %s value " TOK_FMT, t.line_no,
                                      parse_number(tok, toklen, &d) ? "non-finite"
                                                                    : "malformed",
                                      TOK_ARG(tok, toklen));
            count++;
        }
        if (count != 3)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: expected 3 numbers, found %d", t.line_no, count);
        vertices += is_vertex;
    }
    if (vertices % 3 != 0)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "%zu vertices, not a multiple of 3", vertices);
    return FP_MESH_OK;
}
