/* fp_mesh: the C part: allocation, copies, normals, bounds, error text, the OBJ scan. */
#include "mesh_internal.h"
#include "fp_error.h"

#include <facepuppet/decimal.h> /* fp_decimal_span: the one syntax of a number */

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *fp_mesh_strerror(int result) { return fp_strerror(result); }

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
    fp__mesh_source_unref(m->source);
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
    c->source = mesh->source ? fp__mesh_source_ref(mesh->source) : NULL;
    return c;
}

/* ---- normals and bounds -------------------------------------------------------------- */

/* Triangle tri's (pb - pa) x (pc - pa): length = twice its area, so that sums of them are
 * area-weighted. fp_mesh_normals and fp_mesh_normals_at share it, and unit_normal, so that
 * both give the same bits. */
static inline void tri_cross(const uint32_t *tri, const float *pos, float c[3])
{
    const float *pa = pos + 3 * (size_t)tri[0], *pb = pos + 3 * (size_t)tri[1],
                *pc = pos + 3 * (size_t)tri[2];
    float e1x = pb[0] - pa[0], e1y = pb[1] - pa[1], e1z = pb[2] - pa[2];
    float e2x = pc[0] - pa[0], e2y = pc[1] - pa[1], e2z = pc[2] - pa[2];
    c[0] = e1y * e2z - e1z * e2y;
    c[1] = e1z * e2x - e1x * e2z;
    c[2] = e1x * e2y - e1y * e2x;
}

/* A vertex's sum of cross products, normalised in place. */
static inline void unit_normal(float *v)
{
    /* in double: the sums of tiny (denormal) triangles would lose their unit length */
    const double x = v[0], y = v[1], z = v[2];
    const double len = sqrt(x * x + y * y + z * z);
    if (len > 0.0 && isfinite(len)) {
        v[0] = (float)(x / len); v[1] = (float)(y / len); v[2] = (float)(z / len);
    } else {
        v[0] = v[1] = v[2] = 0.0f; /* no area around it (or non-finite input) */
    }
}

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
        float cr[3];
        tri_cross(tris + 3 * k, pos, cr);
        float *na = normals_out + 3 * (size_t)a, *nb = normals_out + 3 * (size_t)b,
              *nc = normals_out + 3 * (size_t)c;
        na[0] += cr[0]; na[1] += cr[1]; na[2] += cr[2];
        nb[0] += cr[0]; nb[1] += cr[1]; nb[2] += cr[2];
        nc[0] += cr[0]; nc[1] += cr[1]; nc[2] += cr[2];
    }
    for (size_t i = 0; i < n; i++)
        unit_normal(normals_out + 3 * i);
    return FP_MESH_OK;
}

int fp_mesh_vertex_triangles(const uint32_t *tris, size_t t, size_t n, uint32_t **vt_start,
                             uint32_t **vt)
{
    if (!vt_start || !vt)
        return FP_MESH_ERR_INVALID;
    *vt_start = *vt = NULL;
    if ((t > 0 && !tris) || n >= UINT32_MAX || 3 * t >= UINT32_MAX)
        return FP_MESH_ERR_INVALID;
    for (size_t i = 0; i < 3 * t; i++)
        if (tris[i] >= n)
            return FP_MESH_ERR_INVALID;
    uint32_t *st = calloc(n + 1, sizeof *st), *v = malloc((t ? 3 * t : 1) * sizeof *v);
    if (!st || !v) {
        free(st);
        free(v);
        return FP_MESH_ERR_NOMEM;
    }
    for (size_t i = 0; i < 3 * t; i++) st[tris[i] + 1]++;
    for (size_t i = 0; i < n; i++) st[i + 1] += st[i];
    /* in triangle order, corner by corner: each vertex's list increases, as the sums of
     * fp_mesh_normals do */
    for (size_t i = 0; i < 3 * t; i++) v[st[tris[i]]++] = (uint32_t)(i / 3);
    for (size_t i = n; i > 0; i--) st[i] = st[i - 1]; /* the fill moved each start on */
    st[0] = 0;
    *vt_start = st;
    *vt = v;
    return FP_MESH_OK;
}

void fp_mesh_normals_at(const uint32_t *tris, const uint32_t *vt_start, const uint32_t *vt,
                        const float *pos, const uint32_t *verts, size_t count,
                        float *normals_out)
{
    for (size_t i = 0; i < count; i++) {
        uint32_t v = verts[i];
        float sum[3] = {0.0f, 0.0f, 0.0f};
        for (uint32_t k = vt_start[v]; k < vt_start[v + 1]; k++) {
            float cr[3];
            tri_cross(tris + 3 * (size_t)vt[k], pos, cr);
            sum[0] += cr[0]; sum[1] += cr[1]; sum[2] += cr[2];
        }
        unit_normal(sum);
        memcpy(normals_out + 3 * (size_t)v, sum, sizeof sum);
    }
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

/* One number token: a decimal (fp_decimal_span, the one syntax of a number: C++ streams,
 * OpenMesh's, read no more), or strtod's "inf"/"nan" words, which read as non-finite for the
 * caller to name. Hexadecimal floats are malformed. */
static int parse_number(const char *tok, size_t len, double *out)
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

/* One corner index: [-]digits, ending at '/' or the token end. Returns 1 with *idx, 2 for an
 * empty field when allow_empty (*idx = 0), or 0 on a syntax error. */
static int parse_index(const char **p, const char *end, long *idx, int allow_empty)
{
    const char *s = *p;
    if (s == end || *s == '/') {
        *idx = 0;
        return allow_empty ? 2 : 0;
    }
    /* [+-]digits, as strtol reads them (the token has no blanks), without its locale and
     * errno (a face's indices were a sixth of a 1.7M-vertex face's load): beyond LONG_MAX
     * in magnitude (ERANGE for strtol) is a syntax error */
    const char *q = s;
    int neg = *q == '-';
    if (*q == '-' || *q == '+') q++;
    unsigned long v = 0;
    const char *d0 = q;
    for (; q < end && *q >= '0' && *q <= '9'; q++) {
        unsigned digit = (unsigned)(*q - '0');
        if (v > ((unsigned long)LONG_MAX - digit) / 10) return 0;
        v = v * 10 + digit;
    }
    if (q == d0 || (q < end && *q != '/'))
        return 0;
    *idx = neg ? -(long)v : (long)v;
    *p = q;
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
            int is_v = kwlen == 1 && kw[0] == 'v';
            int is_vt = kwlen == 2 && kw[0] == 'v' && kw[1] == 't';
            int is_vn = kwlen == 2 && kw[0] == 'v' && kw[1] == 'n';
            int is_f = kwlen == 1 && kw[0] == 'f';
            /* the table only for the rare statements (v, vt, vn and f are nearly every line:
             * the table's 40 compares were an eighth of a 1.7M-vertex face's load) */
            int known = is_v || is_vt || is_vn || is_f;
            for (const char *const *k = obj_known; *k && !known; k++)
                if (strlen(*k) == kwlen && memcmp(*k, kw, kwlen) == 0)
                    known = 1;
            if (!known)
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: unknown OBJ statement " TOK_FMT, line_no,
                                      TOK_ARG(kw, kwlen));
            if (pass == 0 && kwlen == 6 && !memcmp(kw, "usemtl", 6)) seen.usemtl++;
            if (pass == 0 && kwlen == 1 && (kw[0] == 'g' || kw[0] == 'o')) seen.groups++;
            if (pass == 0 && kwlen == 6 && !memcmp(kw, "mtllib", 6)) seen.mtllib++;
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
        if (pass == 0) total = seen;
        else {
            seen.usemtl = total.usemtl;
            seen.groups = total.groups;
            seen.mtllib = total.mtllib;
            total = seen;
        }
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

/* Binary OFF as OpenMesh reads it: the header line, then little-endian uint32 counts
 * (vertices, faces, edges), vertices of 3 [+3 normal] [+2 texture] floats, faces as a uint32
 * corner count and that many uint32 indices. Everything is checked against the file's end. */
static int off_binary_scan(const char *path, const char *text, size_t len, const char *data,
                           int st, int c, int n, size_t *nv_out, size_t *nf_out, char *err,
                           size_t errlen)
{
    if (c)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                              "binary OFF with colours (COFF BINARY) is not supported");
    const unsigned char *b = (const unsigned char *)data, *end = (const unsigned char *)text + len;
    if (end - b < 12)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "binary OFF: the file ends before the vertex/face counts");
    uint32_t cnt[3];
    memcpy(cnt, b, 12); /* little-endian hosts only, like OpenMesh's reader */
    b += 12;
    const uint64_t nv = cnt[0], nf = cnt[1];
    const uint64_t per_vertex = 4u * (3u + (n ? 3u : 0u) + (st ? 2u : 0u));
    if (nv * per_vertex + nf * 16u > (uint64_t)(end - b))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "binary OFF: %llu vertices and %llu faces need at least %llu "
                              "bytes, the file has %zu after its counts",
                              (unsigned long long)nv, (unsigned long long)nf,
                              (unsigned long long)(nv * per_vertex + nf * 16u),
                              (size_t)(end - b));
    for (uint64_t i = 0; i < nv * (per_vertex / 4); i++) {
        float f;
        memcpy(&f, b + 4 * i, 4);
        if (!isfinite(f))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "binary OFF: vertex %llu has a non-finite value",
                                  (unsigned long long)(i / (per_vertex / 4)));
    }
    b += nv * per_vertex;
    for (uint64_t f = 0; f < nf; f++) {
        uint32_t k;
        if (end - b < 4)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "binary OFF: the file ends after %llu of %llu faces",
                                  (unsigned long long)f, (unsigned long long)nf);
        memcpy(&k, b, 4);
        b += 4;
        if (k < 3 || (uint64_t)k * 4u > (uint64_t)(end - b))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "binary OFF: face %llu has %u corners (3 or more, within the "
                                  "file)", (unsigned long long)f, k);
        for (uint32_t j = 0; j < k; j++) {
            uint32_t idx;
            memcpy(&idx, b + 4 * (size_t)j, 4);
            if (idx >= nv)
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "binary OFF: face %llu references vertex %u, but the "
                                      "file has %llu vertices", (unsigned long long)f, idx,
                                      (unsigned long long)nv);
        }
        b += 4 * (size_t)k;
    }
    if (b != end)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "binary OFF: %zu bytes after the last face", (size_t)(end - b));
    *nv_out = (size_t)nv;
    *nf_out = (size_t)nf;
    return FP_MESH_OK;
}

/* How OpenMesh's OFF reader counts the colour values in the rest of a line (getColorType):
 * the text trimmed of white space at both ends, then one more than its single spaces (0 for
 * an empty rest). It prints to stderr for a count it does not know, so the scan refuses
 * those (the caller subtracts ST's two texture values first, as OpenMesh does). */
static int om_color_items(const char *p, const char *end)
{
    while (p < end && isspace((unsigned char)*p))
        p++;
    while (end > p && isspace((unsigned char)end[-1]))
        end--;
    if (p == end)
        return 0;
    int count = 1;
    for (; p < end; p++)
        count += *p == ' ' && count < 1000;
    return count;
}

int fp__off_scan(const char *path, const char *text, size_t len, size_t *nv_out,
                 size_t *nf_out, char *err, size_t errlen)
{
    *nv_out = *nf_out = 0;
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
    const char *const hdr = tok, *const hdr_end = he;
    int st = 0, c = 0, n = 0;
    if (he - h >= 2 && h[0] == 'S' && h[1] == 'T') { st = 1; h += 2; }
    if (h < he && *h == 'C') { c = 1; h++; }
    if (h < he && *h == 'N') { n = 1; h++; }
    if (he - h != 3 || memcmp(h, "OFF", 3) != 0)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: not an OFF header " TOK_FMT " (4D and nOFF are not "
                              "supported)", t.line_no, TOK_ARG(tok, toklen));
    if (next_token(&l, &tok, &toklen)) {
        if (toklen == 6 && memcmp(tok, "BINARY", 6) == 0) {
            /* OpenMesh takes the header as one line "[ST][C][N]OFF BINARY" */
            if (hdr != text || hdr_end + 1 != tok || *hdr_end != ' ' || tok + 6 >= text + len ||
                tok[6] != '\n')
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: a binary OFF starts with exactly "
                                      "'[ST][N]OFF BINARY' and a newline", t.line_no);
            return off_binary_scan(path, text, len, t.p, st, c, n, nv_out, nf_out, err,
                                   errlen);
        }
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: put the vertex and face counts on their own line",
                              t.line_no);
    }
    unsigned long counts[3];
    if (!next_nonblank_line(&t, &l))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path, "no vertex/face counts");
    for (int k = 0; k < 3; k++)
        if (!next_token(&l, &tok, &toklen) || !parse_count(tok, toklen, &counts[k]))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: expected three counts: vertices faces edges",
                                  t.line_no);
    /* OpenMesh reads the counts, vertices' coordinates and faces as one stream: a fourth
     * value here would be read as the first vertex's x, and so on out of step */
    if (next_token(&l, &tok, &toklen))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: " TOK_FMT " after the three counts (vertices faces "
                              "edges)", t.line_no, TOK_ARG(tok, toklen));
    if (counts[2] > UINT32_MAX)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: edge count %lu is beyond 32 bits", t.line_no, counts[2]);
    const unsigned long nv = counts[0], nf = counts[1];
    const size_t need = 3 + (n ? 3u : 0u) + (st ? 2u : 0u);
    if (nv > UINT32_MAX || nf > UINT32_MAX || nv * need + nf * 4 > len)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "line %zu: %lu vertices and %lu faces cannot fit in a file of "
                              "%zu bytes", t.line_no, nv, nf, len);
    for (unsigned long i = 0; i < nv; i++) {
        if (!next_nonblank_line(&t, &l))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "file ends after %lu of %lu vertices", i, nv);
        size_t have = 0;
        const char *rest = NULL; /* after the values OpenMesh reads as a stream */
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
            if (++have == 3u + (n ? 3u : 0u))
                rest = l.p;
        }
        if (have < need)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: vertex %lu has %zu numbers, expected %zu",
                                  t.line_no, i, have, need);
        int items = om_color_items(rest, l.end);
        if (c && items > 0 && st)
            items -= 2;
        if (c && (items < 0 || items > 6))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: vertex %lu: a COFF colour has 1 to 4 values "
                                  "(single spaces between them)", t.line_no, i);
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
        /* OpenMesh reads a face's tokens as a stream and only skips the rest of the line
         * for a colour header (COFF): elsewhere a value after the indices would be read as
         * the next face's corner count, which it then allocates for. */
        if (c && om_color_items(l.p, l.end) > 6)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: face %lu: a COFF colour has 1 to 4 values "
                                  "(single spaces between them)", t.line_no, i);
        if (!c && next_token(&l, &tok, &toklen))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: face %lu has " TOK_FMT " after its %lu indices "
                                  "(face colours need a COFF header)",
                                  t.line_no, i, TOK_ARG(tok, toklen), k);
    }
    *nv_out = nv;
    *nf_out = nf;
    return FP_MESH_OK;
}

/* ---- ASCII PLY and STL scans --------------------------------------------------------- */

static int token_is(const char *tok, size_t len, const char *word)
{
    return strlen(word) == len && memcmp(tok, word, len) == 0;
}

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

int fp__ply_scan(const char *path, const char *text, size_t len, size_t *vertices,
                 size_t *faces, char *err, size_t errlen)
{
    *vertices = *faces = 0;
    ply_element *el = calloc(PLY_MAX_ELEMENTS, sizeof *el);
    if (!el)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_NOMEM, path, "out of memory");
    int nel = 0, format = -1; /* 0 ascii, 1 little endian, 2 big endian */
    int rc = FP_MESH_OK;
    const char *p = text, *end = text + len, *data = NULL;
    size_t line_no = 0;
    int prev_was_decl = 0; /* the line before was an element/property line without trailing
                              blanks (OpenMesh finds binary data by that) */
    int prev_crlf = 0;
#define PLY_FAIL(...) do { rc = fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path, __VA_ARGS__); goto done; } while (0)
    while (!data) {
        if (p >= end)
            PLY_FAIL("no 'end_header' line: the PLY header does not end");
        line_no++;
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
        const char *tok[6];
        size_t tl[6];
        int nt = 0;
        while (nt < 6 && next_token(&l, &tok[nt], &tl[nt]))
            nt++;
        const char *more;
        size_t morelen;
        const int extra = next_token(&l, &more, &morelen);
        if (line_no == 1) {
            if (nt != 1 || !token_is(tok[0], tl[0], "ply"))
                PLY_FAIL("line 1: not a PLY file (the first line is not 'ply')");
            continue;
        }
        int decl = 0;
        if (nt == 0) {
            PLY_FAIL("line %zu: empty line in the PLY header", line_no);
        } else if (token_is(tok[0], tl[0], "comment") || token_is(tok[0], tl[0], "obj_info")) {
            /* free text, allowed anywhere after line 1 (Turk's PLY). OpenMesh mishandles them
             * (it reads obj_info's words as keywords; after a comment it finds a binary body
             * one byte late), so the loader hands it the text without these lines
             * (mesh_io.cpp's ply_without_notes): prev_was_decl and prev_crlf stay those of
             * the line before them. */
            continue;
        } else if (token_is(tok[0], tl[0], "format")) {
            if (format >= 0 || nel > 0)
                PLY_FAIL("line %zu: 'format' must come once, before any element", line_no);
            if (nt != 3 || extra || !token_is(tok[2], tl[2], "1.0"))
                PLY_FAIL("line %zu: expected 'format ascii|binary_little_endian|"
                         "binary_big_endian 1.0'", line_no);
            if (token_is(tok[1], tl[1], "ascii")) format = 0;
            else if (token_is(tok[1], tl[1], "binary_little_endian")) format = 1;
            else if (token_is(tok[1], tl[1], "binary_big_endian")) format = 2;
            else
                PLY_FAIL("line %zu: unknown PLY format " TOK_FMT, line_no,
                         TOK_ARG(tok[1], tl[1]));
        } else if (token_is(tok[0], tl[0], "element")) {
            if (format < 0)
                PLY_FAIL("line %zu: 'element' before the 'format' line", line_no);
            if (nt != 3 || extra)
                PLY_FAIL("line %zu: expected 'element NAME COUNT'", line_no);
            unsigned long cnt;
            if (!parse_count(tok[2], tl[2], &cnt) || cnt > UINT32_MAX)
                PLY_FAIL("line %zu: element count " TOK_FMT " is not a number from 0 to %u",
                         line_no, TOK_ARG(tok[2], tl[2]), UINT32_MAX);
            if (nel == PLY_MAX_ELEMENTS)
                PLY_FAIL("line %zu: more than %d elements", line_no, PLY_MAX_ELEMENTS);
            ply_element *e = &el[nel++];
            e->kind = token_is(tok[1], tl[1], "vertex") ? PLY_VERTEX
                      : token_is(tok[1], tl[1], "face") ? PLY_FACE : PLY_OTHER;
            e->count = cnt;
            e->line = line_no;
            for (int i = 0; i + 1 < nel; i++)
                if (e->kind != PLY_OTHER && el[i].kind == e->kind)
                    PLY_FAIL("line %zu: a second '%.*s' element", line_no, (int)tl[1], tok[1]);
            decl = 1;
        } else if (token_is(tok[0], tl[0], "property")) {
            if (nel == 0)
                PLY_FAIL("line %zu: 'property' before any 'element'", line_no);
            ply_element *e = &el[nel - 1];
            if (e->nprops == PLY_MAX_PROPS)
                PLY_FAIL("line %zu: more than %d properties in one element", line_no,
                         PLY_MAX_PROPS);
            ply_prop pr = {-1, -1, PLY_ROLE_OTHER};
            const char *name;
            size_t namelen;
            if (nt >= 2 && token_is(tok[1], tl[1], "list")) {
                if (nt != 5 || extra)
                    PLY_FAIL("line %zu: expected 'property list COUNT_TYPE TYPE NAME'", line_no);
                pr.count_type = ply_type(tok[2], tl[2]);
                pr.type = ply_type(tok[3], tl[3]);
                name = tok[4];
                namelen = tl[4];
                /* the count types OpenMesh's reader accepts */
                if (!token_is(tok[2], tl[2], "uchar") && !token_is(tok[2], tl[2], "uint8") &&
                    !token_is(tok[2], tl[2], "uint16") && !token_is(tok[2], tl[2], "int"))
                    PLY_FAIL("line %zu: list count type " TOK_FMT " is not supported (uchar, "
                             "uint8, uint16 or int)", line_no, TOK_ARG(tok[2], tl[2]));
                if (pr.type < 0)
                    PLY_FAIL("line %zu: unknown PLY type " TOK_FMT, line_no,
                             TOK_ARG(tok[3], tl[3]));
                if (e->kind != PLY_FACE)
                    PLY_FAIL("line %zu: list properties are supported in the 'face' element "
                             "only", line_no);
                if (token_is(name, namelen, "vertex_indices") ||
                    token_is(name, namelen, "vertex_index")) {
                    if (e->nprops != 0)
                        PLY_FAIL("line %zu: 'vertex_indices' must be the face's first property",
                                 line_no);
                    if (!ply_types[pr.type].is_int)
                        PLY_FAIL("line %zu: vertex indices must have an integer type", line_no);
                    pr.role = PLY_ROLE_VINDEX;
                } else if (token_is(name, namelen, "texcoord") && e->nprops > 0 &&
                           e->props[0].role == PLY_ROLE_VINDEX) {
                    pr.role = PLY_ROLE_TEXCOORD;
                } else {
                    PLY_FAIL("line %zu: list property " TOK_FMT " is not supported (face "
                             "vertex_indices first, then texcoord)", line_no,
                             TOK_ARG(name, namelen));
                }
            } else {
                if (nt != 3 || extra)
                    PLY_FAIL("line %zu: expected 'property TYPE NAME'", line_no);
                pr.type = ply_type(tok[1], tl[1]);
                name = tok[2];
                namelen = tl[2];
                if (pr.type < 0)
                    PLY_FAIL("line %zu: unknown PLY type " TOK_FMT, line_no,
                             TOK_ARG(tok[1], tl[1]));
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
            decl = 1;
        } else if (token_is(tok[0], tl[0], "end_header")) {
            if (nt != 1 || extra)
                PLY_FAIL("line %zu: text after 'end_header'", line_no);
            if (format > 0 && (!prev_was_decl || prev_crlf != crlf || trailing ||
                               (size_t)(eol - tok[0]) != 10u + (unsigned)crlf))
                PLY_FAIL("line %zu: in a binary PLY, 'end_header' must directly follow an "
                         "element or property line, alone on its line", line_no);
            data = p;
        } else {
            PLY_FAIL("line %zu: unknown PLY header keyword " TOK_FMT, line_no,
                     TOK_ARG(tok[0], tl[0]));
        }
        prev_was_decl = decl && !trailing;
        prev_crlf = crlf;
    }
    if (format < 0)
        PLY_FAIL("no 'format' line in the PLY header");
    /* the elements: vertex with x, y, z once each; counts against the file's size */
    unsigned long long need = 0, nverts = 0;
    for (int i = 0; i < nel; i++) {
        ply_element *e = &el[i];
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
    const size_t avail = (size_t)(end - data);
    if (need > avail)
        PLY_FAIL("the header's element counts need at least %llu bytes of data, the file "
                 "has %zu", need, avail);
    *vertices = (size_t)nverts;
    /* the walk: every value's type and range, list counts, indices, finite floats */
    tok_cursor c = {data, end, line_no + 1};
    const unsigned char *b = (const unsigned char *)data, *bend = (const unsigned char *)end;
    const int big = format == 2;
    for (int i = 0; i < nel; i++) {
        const ply_element *e = &el[i];
        for (unsigned long long r = 0; r < e->count; r++) {
            long long corners = 0;
            for (int k = 0; k < e->nprops; k++) {
                const ply_prop *pr = &e->props[k];
                long long n = 1;
                if (pr->count_type >= 0) {
                    long long cnt;
                    const size_t cnt_byte = (size_t)((const char *)b - text);
                    if (format == 0) {
                        const char *t;
                        size_t tlen;
                        if (!cursor_next(&c, &t, &tlen))
                            PLY_FAIL("the data ends in row %llu of %llu of element %d", r,
                                     e->count, i);
                        rc = ply_ascii_value(path, c.line, t, tlen, pr->count_type, &cnt, err,
                                             errlen);
                        if (rc)
                            goto done;
                    } else {
                        const int cs = ply_types[pr->count_type].size;
                        if ((size_t)(bend - b) < (size_t)cs)
                            PLY_FAIL("the data ends in row %llu of %llu of element %d", r,
                                     e->count, i);
                        double dv;
                        ply_binary_value(b, pr->count_type, big, &cnt, &dv);
                        b += cs;
                    }
                    const ply_where at = ply_at(format != 0, c.line, cnt_byte);
                    if (cnt < 0)
                        PLY_FAIL("%s: negative list count in row %llu", at.text, r);
                    if (pr->role == PLY_ROLE_VINDEX) {
                        if (cnt < 3)
                            PLY_FAIL("%s: face %llu has %lld corners (at least 3)", at.text, r,
                                     cnt);
                        corners = cnt;
                    } else if (pr->role == PLY_ROLE_TEXCOORD && cnt != 2 * corners &&
                               cnt != 3 * corners) {
                        PLY_FAIL("%s: face %llu: %lld texture coordinates for %lld corners",
                                 at.text, r, cnt, corners);
                    }
                    n = cnt;
                    if (format != 0 &&
                        (unsigned long long)n * (unsigned)ply_types[pr->type].size >
                            (size_t)(bend - b))
                        PLY_FAIL("%s: face %llu: a list of %lld values runs past the file's end",
                                 at.text, r, n);
                }
                for (long long j = 0; j < n; j++) {
                    long long iv = 0;
                    double dv = 0;
                    size_t at = c.line;
                    const size_t at_byte = (size_t)((const char *)b - text);
                    if (format == 0) {
                        const char *t;
                        size_t tlen;
                        if (!cursor_next(&c, &t, &tlen))
                            PLY_FAIL("the data ends in row %llu of %llu of element %d", r,
                                     e->count, i);
                        at = c.line;
                        rc = ply_ascii_value(path, c.line, t, tlen, pr->type, &iv, err, errlen);
                        if (rc)
                            goto done;
                    } else {
                        const int sz = ply_types[pr->type].size;
                        if ((size_t)(bend - b) < (size_t)sz)
                            PLY_FAIL("the data ends in row %llu of %llu of element %d", r,
                                     e->count, i);
                        ply_binary_value(b, pr->type, big, &iv, &dv);
                        b += sz;
                        if (!ply_types[pr->type].is_int && (!isfinite(dv) || fabs(dv) > FLT_MAX))
                            PLY_FAIL("byte %zu: non-finite value in row %llu of element %d",
                                     at_byte, r, i);
                    }
                    if (pr->role == PLY_ROLE_VINDEX && (iv < 0 || (unsigned long long)iv >= nverts))
                        PLY_FAIL("%s: face %llu references vertex %lld, but the file has "
                                 "%llu vertices", ply_at(format != 0, at, at_byte).text, r, iv,
                                 nverts);
                }
            }
        }
    }
    if (format == 0) {
        const char *t;
        size_t tlen;
        if (cursor_next(&c, &t, &tlen))
            PLY_FAIL("line %zu: data after the last element: " TOK_FMT, c.line,
                     TOK_ARG(t, tlen));
    } else if (b != bend) {
        PLY_FAIL("%zu bytes after the last element (the header's counts do not fit the file)",
                 (size_t)(bend - b));
    }
#undef PLY_FAIL
done:
    free(el);
    return rc;
}

int fp__stl_ascii_scan(const char *path, const char *text, size_t len, char *err,
                       size_t errlen)
{
    if (memchr(text, '\0', len))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "NUL byte in ASCII STL text");
    /* solid NAME, then per facet: facet normal n n n / outer loop / vertex x y z (3 times) /
     * endloop / endfacet; then endsolid [NAME]. Several solids may follow each other. */
    static const char *const expect[] = {"solid", "facet", "outer", "vertex", "vertex",
                                         "vertex", "endloop", "endfacet"};
    text_lines t = {text, text + len, 0};
    obj_line l;
    int state = 0; /* index into expect; in state 1 'endsolid' is allowed too */
    while (next_nonblank_line(&t, &l)) {
        const char *tok = NULL;
        size_t toklen = 0;
        next_token(&l, &tok, &toklen);
        if (state == 1 && token_is(tok, toklen, "endsolid")) {
            state = 0;
            continue; /* a name may follow */
        }
        if (!token_is(tok, toklen, expect[state]))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: expected '%s'%s, found " TOK_FMT, t.line_no,
                                  expect[state], state == 1 ? " or 'endsolid'" : "",
                                  TOK_ARG(tok, toklen));
        const int numbers = state == 1 || (state >= 3 && state <= 5);
        if (state == 1 && (!next_token(&l, &tok, &toklen) || !token_is(tok, toklen, "normal")))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: 'facet' without 'normal'", t.line_no);
        if (state == 2 && (!next_token(&l, &tok, &toklen) || !token_is(tok, toklen, "loop")))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: 'outer' without 'loop'", t.line_no);
        state = state == 7 ? 1 : state + 1;
        if (state == 1 && token_is(tok, toklen, "solid"))
            continue; /* the solid's name */
        int count = 0;
        while (next_token(&l, &tok, &toklen)) {
            double d;
            const int parsed = parse_number(tok, toklen, &d);
            if (!numbers || !parsed || !isfinite(d) ||
                fabs(d) > FLT_MAX)
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "line %zu: %s " TOK_FMT, t.line_no,
                                      !numbers ? "unexpected"
                                      : parsed && (!isfinite(d) || fabs(d) > FLT_MAX)
                                          ? "non-finite value"
                                          : "malformed value",
                                      TOK_ARG(tok, toklen));
            count++;
        }
        if (numbers && count != 3)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "line %zu: expected 3 numbers, found %d", t.line_no, count);
    }
    if (state != 0)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "the file ends inside a solid (expected '%s')", expect[state]);
    return FP_MESH_OK;
}
