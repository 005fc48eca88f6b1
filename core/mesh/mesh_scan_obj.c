/* The strict OBJ scan (fp__obj_scan, mesh_internal.h): every line checked before OpenMesh's
 * reader sees the text. */
#include "mesh_scan.h"

#include <limits.h>
#include <stdint.h>

/* Statements of the OBJ format (Wavefront, "Object Files (.obj)" appendix B1) that we accept
 * and, except v/vt/vn/f, ignore. */
static const char *const obj_known[] = {
    "v", "vt", "vn", "vp", "f", "fo", "l", "p", "o", "g", "s", "mg", "usemtl", "mtllib",
    "usemap", "maplib", "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm",
    "trim", "hole", "scrv", "sp", "end", "con", "lod", "shadow_obj", "trace_obj", "ctech",
    "stech", "bevel", "c_interp", "d_interp", "call", "csh", NULL};

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
                if (is_v) seen.v++, seen.colours += count >= 6;
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
            seen.colours = total.colours;
            total = seen;
        }
    }
    *info = total;
    return FP_MESH_OK;
}

size_t fp__obj_join_continuations(char *text, size_t len)
{
    /* o <= i: the text is rewritten in place; held: line ends moved to the joined line's end,
     * held_crlf of them a CR LF (a Windows file keeps its line ends) */
    size_t o = 0, held = 0, held_crlf = 0, joined = 0;
    for (size_t i = 0; i < len; i++) {
        if (text[i] == '\\') {
            size_t j = i + 1;
            while (j < len && is_blank(text[j]))
                j++;
            if (j == len || text[j] == '\n') {
                const bool crlf = j < len && text[j - 1] == '\r';
                for (; i < j - crlf; i++)
                    text[o++] = ' ';
                i = j;
                held += j < len;
                held_crlf += crlf;
                joined += j < len;
                continue; /* i is at the newline (skipped) or the end */
            }
        }
        text[o++] = text[i];
        for (; text[i] == '\n' && held > 0; held--) {
            if (held_crlf > 0) {
                held_crlf--;
                text[o++] = '\r';
            }
            text[o++] = '\n';
        }
    }
    for (; held > 0; held--) {
        if (held_crlf > 0) {
            held_crlf--;
            text[o++] = '\r';
        }
        text[o++] = '\n';
    }
    return joined;
}
