/* The strict scans of OFF (ASCII and binary, fp__off_scan) and STL (fp__stl_ascii_scan, and
 * fp__stl_binary_scan for the corners; a binary STL's size is checked in mesh_openmesh.cpp),
 * mesh_internal.h:
 * what OpenMesh's readers would consume, checked before they see it. */
#include "mesh_scan.h"

#include <assert.h>

#include <ctype.h>
#include <stdint.h>

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

int fp__stl_binary_scan(const char *path, const char *data, size_t len, char *err, size_t errlen)
{
    uint32_t count;
    assert(len >= 84);
    memcpy(&count, data + 80, 4);
    assert(len == 84 + 50 * (uint64_t)count);
    for (uint32_t i = 0; i < count; i++) {
        const char *t = data + 84 + 50 * (size_t)i;
        for (int k = 3; k < 12; k++) { /* after the facet normal: 3 corners of x, y, z */
            float v;
            memcpy(&v, t + 4 * k, 4); /* (little-endian floats: the STL's and this machine's) */
            if (!isfinite(v) || fabsf(v) > FLT_MAX)
                return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                      "triangle %lu (byte %zu): corner %d's %c is not a finite number",
                                      (unsigned long)i + 1, (size_t)(t + 4 * k - data), (k - 3) / 3 + 1,
                                      "xyz"[(k - 3) % 3]);
        }
    }
    return FP_MESH_OK;
}
