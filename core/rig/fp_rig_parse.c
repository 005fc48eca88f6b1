/* fp_rig: reading rig files (fp_rig_parse, fp_rig_load): every field checked, every error
 * naming the file and the JSON path (fp_rig.h; the format in rigs/README.md). */
#define _GNU_SOURCE
#include "fp_rig_internal.h"

#include "fp_error.h"
#include "fp_text.h"
#include "fp_file.h"
#include "fp_vec.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------- */
/* Parsing helpers: every error names the file and the JSON path.                      */

int fpr_bad(const fpr_ctx *c, const char *path, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return fp_errorf(c->err, c->errlen, -EBADMSG, "%s: %s: %s", c->file, path[0] ? path : "(top)",
                     msg);
}


static const char *type_name(const cJSON *j)
{
    if (!j) return "nothing";
    if (cJSON_IsNumber(j)) return "a number";
    if (cJSON_IsString(j)) return "a string";
    if (cJSON_IsArray(j)) return "an array";
    if (cJSON_IsObject(j)) return "an object";
    if (cJSON_IsBool(j)) return "a boolean";
    if (cJSON_IsNull(j)) return "null";
    return "an invalid value";
}

static void join(char *out, size_t len, const char *path, const char *key)
{
    snprintf(out, len, "%s%s%s", path, path[0] ? "." : "", key);
}

/* Refuse fields not in `allowed` (NULL-terminated) and repeated fields. */
static int check_fields(const fpr_ctx *c, const cJSON *obj, const char *path, const char *const *allowed)
{
    for (const cJSON *it = obj->child; it; it = it->next) {
        char p[512];
        join(p, sizeof p, path, it->string ? it->string : "?");
        bool ok = false;
        for (size_t i = 0; allowed[i]; i++)
            if (it->string && !strcmp(it->string, allowed[i])) ok = true;
        if (!ok) return fpr_bad(c, p, "unknown field");
        for (const cJSON *jt = it->next; jt; jt = jt->next)
            if (jt->string && !strcmp(jt->string, it->string)) return fpr_bad(c, p, "field given twice");
    }
    return 0;
}

static int get_member(const fpr_ctx *c, const cJSON *obj, const char *path, const char *key,
                      bool required, const cJSON **out, char *p, size_t plen)
{
    join(p, plen, path, key);
    *out = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!*out && required) return fpr_bad(c, p, "missing");
    return 0;
}

static int get_number(const fpr_ctx *c, const cJSON *obj, const char *path, const char *key,
                      bool required, double lo, double hi, double *out)
{
    char p[512];
    const cJSON *j;
    int rc = get_member(c, obj, path, key, required, &j, p, sizeof p);
    if (rc || !j) return rc;
    if (!cJSON_IsNumber(j)) return fpr_bad(c, p, "expected a number, got %s", type_name(j));
    if (!isfinite(j->valuedouble) || j->valuedouble < lo || j->valuedouble > hi)
        return fpr_bad(c, p, "%g is outside [%g, %g]", j->valuedouble, lo, hi);
    *out = j->valuedouble;
    return 0;
}

static int get_string(const fpr_ctx *c, const cJSON *obj, const char *path, const char *key,
                      bool required, char *out, size_t len)
{
    char p[512];
    const cJSON *j;
    int rc = get_member(c, obj, path, key, required, &j, p, sizeof p);
    if (rc || !j) return rc;
    if (!cJSON_IsString(j)) return fpr_bad(c, p, "expected a string, got %s", type_name(j));
    if (strlen(j->valuestring) >= len) return fpr_bad(c, p, "longer than %zu bytes", len - 1);
    if (!fp_text_ok(j->valuestring, false)) /* (an ESC in a name recoloured info's terminal) */
        return fpr_bad(c, p, "not UTF-8 text without control characters");
    strcpy(out, j->valuestring);
    return 0;
}

static int vec3_of(const fpr_ctx *c, const cJSON *j, const char *p, double out[3])
{
    if (!cJSON_IsArray(j) || cJSON_GetArraySize(j) != 3)
        return fpr_bad(c, p, "expected an array of 3 numbers, got %s", type_name(j));
    int i = 0;
    for (const cJSON *e = j->child; e; e = e->next, i++) {
        char q[560];
        snprintf(q, sizeof q, "%s[%d]", p, i);
        if (!cJSON_IsNumber(e)) return fpr_bad(c, q, "expected a number, got %s", type_name(e));
        if (!isfinite(e->valuedouble)) return fpr_bad(c, q, "not a finite coordinate");
        if (fabs(e->valuedouble) > 1e12) return fpr_bad(c, q, "%g is beyond 1e12 mesh units", e->valuedouble);
        out[i] = e->valuedouble;
    }
    return 0;
}

static int get_vec3(const fpr_ctx *c, const cJSON *obj, const char *path, const char *key, double out[3])
{
    char p[512];
    const cJSON *j;
    int rc = get_member(c, obj, path, key, true, &j, p, sizeof p);
    return rc ? rc : vec3_of(c, j, p, out);
}

static int get_object(const fpr_ctx *c, const cJSON *obj, const char *path, const char *key,
                      bool required, const cJSON **out, char *p, size_t plen)
{
    int rc = get_member(c, obj, path, key, required, out, p, plen);
    if (rc || !*out) return rc;
    if (!cJSON_IsObject(*out)) return fpr_bad(c, p, "expected an object, got %s", type_name(*out));
    return 0;
}

static int get_array(const fpr_ctx *c, const cJSON *obj, const char *path, const char *key,
                     const cJSON **out, char *p, size_t plen)
{
    int rc = get_member(c, obj, path, key, true, out, p, plen);
    if (rc) return rc;
    if (!cJSON_IsArray(*out)) return fpr_bad(c, p, "expected an array, got %s", type_name(*out));
    return 0;
}

static bool valid_name(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n > FP_RIG_NAME_MAX) return false;
    for (size_t i = 0; i < n; i++) {
        char ch = s[i];
        if (!((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_' || ch == '.' ||
              ch == '-'))
            return false;
    }
    return true;
}

static int vertex_index(const fpr_ctx *c, const cJSON *e, const char *p, size_t n, uint32_t *out)
{
    if (!cJSON_IsNumber(e)) return fpr_bad(c, p, "expected a vertex index, got %s", type_name(e));
    double v = e->valuedouble;
    if (!isfinite(v) || v != floor(v) || v < 0) return fpr_bad(c, p, "%g is not a vertex index", v);
    if (v >= (double)n) /* (%g: %.0f wrote 1e308 as 309 digits) */
        return fpr_bad(c, p, "vertex %.15g is out of range (the mesh has %zu)", v, n);
    *out = (uint32_t)v;
    return 0;
}

/* One entry of a vertex list: an index, or a range [first, last] (inclusive) at path p;
 * *a..*b the vertices. */
static int vertex_span(const fpr_ctx *c, const cJSON *e, const char *p, size_t n, uint32_t *a, uint32_t *b)
{
    int rc;
    if (!cJSON_IsArray(e)) {
        if ((rc = vertex_index(c, e, p, n, a))) return rc;
        *b = *a;
        return 0;
    }
    if (cJSON_GetArraySize(e) != 2) return fpr_bad(c, p, "a range is [first, last]");
    char q[160];
    snprintf(q, sizeof q, "%s[0]", p);
    if ((rc = vertex_index(c, e->child, q, n, a))) return rc;
    snprintf(q, sizeof q, "%s[1]", p);
    if ((rc = vertex_index(c, e->child->next, q, n, b))) return rc;
    if (*b < *a) return fpr_bad(c, p, "range [%u, %u] runs backwards", *a, *b);
    return 0;
}

static void normalize(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0) v[0] /= l, v[1] /= l, v[2] /= l;
}

/* ---------------------------------------------------------------------------------- */

static int parse_mesh(const fpr_ctx *c, fp_rig *r, const cJSON *root)
{
    char p[512];
    const cJSON *m;
    int rc = get_object(c, root, "", "mesh", true, &m, p, sizeof p);
    if (rc) return rc;
    static const char *const f[] = {"name", "vertex_count", "positions_crc32", "landmark_positions", NULL};
    if ((rc = check_fields(c, m, "mesh", f))) return rc;
    if ((rc = get_string(c, m, "mesh", "name", false, r->mesh_name, sizeof r->mesh_name))) return rc;
    double n = 0;
    if ((rc = get_number(c, m, "mesh", "vertex_count", true, 1, 1e8, &n))) return rc;
    if (n != floor(n)) return fpr_bad(c, "mesh.vertex_count", "not an integer");
    r->n = (size_t)n;
    char crc[16] = "";
    if ((rc = get_string(c, m, "mesh", "positions_crc32", true, crc, sizeof crc))) return rc;
    /* exactly 8 hex digits: strtoul alone took "0x123456", " 1234567", "+1234567" and
     * "-0000001" (that one as ffffffff) */
    if (strlen(crc) != 8 || strspn(crc, "0123456789abcdefABCDEF") != 8)
        return fpr_bad(c, "mesh.positions_crc32", "expected 8 hexadecimal digits, got \"%s\"", crc);
    r->crc = (uint32_t)strtoul(crc, NULL, 16);
    return 0;
}

static int parse_axes(const fpr_ctx *c, fp_rig *r, const cJSON *root)
{
    char p[512];
    const cJSON *a;
    int rc = get_object(c, root, "", "axes", true, &a, p, sizeof p);
    if (rc) return rc;
    static const char *const f[] = {"up", "forward", "left", NULL};
    if ((rc = check_fields(c, a, "axes", f))) return rc;
    if ((rc = get_vec3(c, a, "axes", "up", r->geom.up)) || (rc = get_vec3(c, a, "axes", "forward", r->geom.fwd)) ||
        (rc = get_vec3(c, a, "axes", "left", r->geom.left)))
        return rc;
    double *ax[3] = {r->geom.up, r->geom.fwd, r->geom.left};
    const char *nm[3] = {"axes.up", "axes.forward", "axes.left"};
    for (int i = 0; i < 3; i++) {
        double l = sqrt(fp_dot3(ax[i], ax[i]));
        if (fabs(l - 1) > 1e-3) return fpr_bad(c, nm[i], "not a unit vector (length %g)", l);
        normalize(ax[i]);
    }
    if (fabs(fp_dot3(r->geom.up, r->geom.fwd)) > 1e-3 || fabs(fp_dot3(r->geom.up, r->geom.left)) > 1e-3 ||
        fabs(fp_dot3(r->geom.fwd, r->geom.left)) > 1e-3)
        return fpr_bad(c, "axes", "up, forward and left are not orthogonal");
    double x[3];
    fp_cross3(r->geom.up, r->geom.fwd, x);
    if (fp_dot3(x, r->geom.left) < 0.999) return fpr_bad(c, "axes.left", "must equal up x forward (a right-handed frame)");
    return 0;
}

static int parse_regions(const fpr_ctx *c, fp_rig *r, const cJSON *root)
{
    char p[512];
    const cJSON *rs;
    int rc = get_array(c, root, "", "regions", &rs, p, sizeof p);
    if (rc) return rc;
    int nr = cJSON_GetArraySize(rs);
    if (nr > FP_RIG_MAX_REGIONS) return fpr_bad(c, "regions", "more than %d regions", FP_RIG_MAX_REGIONS);
    r->kind = calloc(r->n, 1);
    uint8_t *owner = r->owner = calloc(r->n, 1); /* region index + 1 that claimed the vertex */
    if (!r->kind || !owner)
        return fp_errorf(c->err, c->errlen, -ENOMEM, "%s: out of memory", c->file);
    int i = 0;
    rc = 0;
    /* the vertices the spans list, repeats included: at most FP_RIG_LISTED_MAX x n, so that a
     * hostile file's thousands of whole-mesh spans are refused as counted, not walked */
    size_t listed = 0;
    for (const cJSON *g = rs->child; g && !rc; g = g->next, i++) {
        char gp[64];
        snprintf(gp, sizeof gp, "regions[%d]", i);
        if (!cJSON_IsObject(g)) { rc = fpr_bad(c, gp, "expected an object, got %s", type_name(g)); break; }
        static const char *const f[] = {"name", "kind", "vertices", NULL};
        if ((rc = check_fields(c, g, gp, f))) break;
        region *reg = &r->regions[i];
        if ((rc = get_string(c, g, gp, "name", true, reg->name, sizeof reg->name))) break;
        if (!valid_name(reg->name)) { rc = fpr_bad(c, gp, "name \"%s\": use a-z 0-9 _ . -", reg->name); break; }
        for (int k = 0; k < i; k++)
            if (!strcmp(r->regions[k].name, reg->name)) rc = fpr_bad(c, gp, "region \"%s\" given twice", reg->name);
        if (rc) break;
        char kind[16];
        if ((rc = get_string(c, g, gp, "kind", true, kind, sizeof kind))) break;
        if (!strcmp(kind, "soft")) reg->kind = FP_RIG_SOFT;
        else if (!strcmp(kind, "skull")) reg->kind = FP_RIG_SKULL;
        else if (!strcmp(kind, "jaw")) reg->kind = FP_RIG_JAW;
        else { char q[80]; snprintf(q, sizeof q, "%s.kind", gp); rc = fpr_bad(c, q, "\"%s\" is not soft, skull or jaw", kind); break; }
        const cJSON *vs;
        char vp[96];
        if ((rc = get_array(c, g, gp, "vertices", &vs, vp, sizeof vp))) break;
        int k = 0;
        for (const cJSON *e = vs->child; e && !rc; e = e->next, k++) {
            char ep[128];
            snprintf(ep, sizeof ep, "%s[%d]", vp, k);
            uint32_t a, b;
            if ((rc = vertex_span(c, e, ep, r->n, &a, &b))) break;
            if ((size_t)(b - a) + 1 > FP_RIG_LISTED_MAX * r->n - listed) {
                rc = fpr_bad(c, ep, "the regions list more than %d x %zu vertices (the mesh's count), "
                             "repeats included", FP_RIG_LISTED_MAX, r->n);
                break;
            }
            listed += (size_t)(b - a) + 1;
            for (uint32_t v = a; v <= b; v++) {
                if (owner[v] == (uint8_t)(i + 1)) continue; /* repeated in the same region */
                if (owner[v]) {
                    const region *o = &r->regions[owner[v] - 1];
                    rc = fpr_bad(c, ep, "vertex %u is already in regions[%d] \"%s\" (%s): regions may not overlap",
                             v, owner[v] - 1, o->name,
                             o->kind == FP_RIG_SKULL ? "skull" : o->kind == FP_RIG_JAW ? "jaw" : "soft");
                    break;
                }
                owner[v] = (uint8_t)(i + 1);
                r->kind[v] = (uint8_t)reg->kind;
                reg->count++;
            }
        }
        if (!rc && !reg->count) /* (a region of nothing: a mistake, never a choice) */
            rc = fpr_bad(c, vp, "empty: region \"%s\" lists no vertex", reg->name);
    }
    if (rc) return rc;
    r->region_count = (size_t)nr;
    size_t skull = 0, jaw = 0;
    for (size_t v = 0; v < r->n; v++) skull += r->kind[v] == FP_RIG_SKULL, jaw += r->kind[v] == FP_RIG_JAW;
    if (!skull) return fpr_bad(c, "regions", "no skull vertices: a rig needs a skull region");
    if (!jaw) return fpr_bad(c, "regions", "no jaw vertices: a rig needs a jaw region");
    return 0;
}

static int parse_landmarks(const fpr_ctx *c, fp_rig *r, const cJSON *root)
{
    char p[512];
    const cJSON *ls;
    int rc = get_object(c, root, "", "landmarks", true, &ls, p, sizeof p);
    if (rc) return rc;
    for (const cJSON *e = ls->child; e; e = e->next) {
        char q[600];
        join(q, sizeof q, "landmarks", e->string ? e->string : "?");
        if (!e->string || !valid_name(e->string)) return fpr_bad(c, q, "bad landmark name: use a-z 0-9 _ . -");
        if (r->landmark_count >= FP_RIG_MAX_LANDMARKS) return fpr_bad(c, q, "more than %d landmarks", FP_RIG_MAX_LANDMARKS);
        if (fpr_landmark_at(r, e->string) < r->landmark_count) return fpr_bad(c, q, "landmark given twice");
        landmark *l = &r->landmarks[r->landmark_count];
        if ((rc = vertex_index(c, e, q, r->n, &l->vertex))) return rc;
        strcpy(l->name, e->string);
        r->landmark_count++;
    }
    static const char *const need[] = {"chin", "nose_tip", "upper_lip", "lower_lip",
                                       "mouth_corner_left", "mouth_corner_right", "brow_left",
                                       "brow_right", "eye_outer_left", "eye_inner_left",
                                       "eye_outer_right", "eye_inner_right", NULL};
    for (size_t i = 0; need[i]; i++) {
        bool found = false;
        for (size_t k = 0; k < r->landmark_count; k++) found |= !strcmp(r->landmarks[k].name, need[i]);
        if (!found) {
            char q[80];
            snprintf(q, sizeof q, "landmarks.%s", need[i]);
            return fpr_bad(c, q, "missing (every rig names it)");
        }
    }
    return 0;
}

/* mesh.landmark_positions (optional): every landmark's position on the rig's own mesh, which
 * places the rig on a moved copy of it (fp_rig_place.c) */
static int parse_reference(const fpr_ctx *c, fp_rig *r, const cJSON *root)
{
    char p[512];
    const cJSON *lp;
    int rc = get_object(c, cJSON_GetObjectItemCaseSensitive(root, "mesh"), "mesh", "landmark_positions", false,
                        &lp, p, sizeof p);
    if (rc || !lp) return rc;
    size_t given = 0;
    for (const cJSON *e = lp->child; e; e = e->next) {
        char q[600];
        join(q, sizeof q, "mesh.landmark_positions", e->string ? e->string : "?");
        size_t k = e->string ? fpr_landmark_at(r, e->string) : r->landmark_count;
        if (k == r->landmark_count) return fpr_bad(c, q, "no landmark of that name");
        if (cJSON_GetObjectItemCaseSensitive(lp, e->string) != e) return fpr_bad(c, q, "given twice");
        if ((rc = vec3_of(c, e, q, r->landmarks[k].ref))) return rc;
        given++;
    }
    if (given != r->landmark_count)
        return fpr_bad(c, "mesh.landmark_positions", "%zu of the %zu landmarks: give every one", given,
                   r->landmark_count);
    r->has_ref = true;
    return 0;
}

static int parse_channels(const fpr_ctx *c, fp_rig *r, const cJSON *root)
{
    char p[512];
    const cJSON *cs;
    int rc = get_array(c, root, "", "channels", &cs, p, sizeof p);
    if (rc) return rc;
    int i = 0;
    r->jaw_open = -1;
    for (const cJSON *e = cs->child; e; e = e->next, i++) {
        char q[64];
        snprintf(q, sizeof q, "channels[%d]", i);
        if (!cJSON_IsObject(e)) return fpr_bad(c, q, "expected an object, got %s", type_name(e));
        if (i >= FP_RIG_MAX_CHANNELS) return fpr_bad(c, q, "more than %d channels", FP_RIG_MAX_CHANNELS);
        static const char *const f[] = {"name", "min", "max", "neutral", NULL};
        if ((rc = check_fields(c, e, q, f))) return rc;
        channel *ch = &r->channels[i];
        if ((rc = get_string(c, e, q, "name", true, ch->name, sizeof ch->name))) return rc;
        if (!valid_name(ch->name)) return fpr_bad(c, q, "name \"%s\": use a-z 0-9 _ . -", ch->name);
        for (int k = 0; k < i; k++)
            if (!strcmp(r->channels[k].name, ch->name)) return fpr_bad(c, q, "channel \"%s\" given twice", ch->name);
        double lo, hi, neutral = 0;
        if ((rc = get_number(c, e, q, "min", true, -1e6, 1e6, &lo)) ||
            (rc = get_number(c, e, q, "max", true, -1e6, 1e6, &hi)))
            return rc;
        if (!(hi > lo)) return fpr_bad(c, q, "max (%g) must exceed min (%g)", hi, lo);
        neutral = lo;
        if ((rc = get_number(c, e, q, "neutral", false, lo, hi, &neutral))) return rc;
        ch->min = (float)lo, ch->max = (float)hi, ch->neutral = (float)neutral;
        if (!strcmp(ch->name, "jaw.open")) {
            if (lo != 0 || hi != 1) return fpr_bad(c, q, "jaw.open must range over [0, 1]");
            r->jaw_open = i;
        }
    }
    r->channel_count = (size_t)i;
    if (r->jaw_open < 0) return fpr_bad(c, "channels", "no \"jaw.open\" channel");
    return 0;
}

typedef struct weight_pair {
    uint32_t v;
    float w;
    int at; /* element of jaw.weights.vertices it came from */
} weight_pair;

static int by_vertex(const void *a, const void *b)
{
    uint32_t x = ((const weight_pair *)a)->v, y = ((const weight_pair *)b)->v;
    return x < y ? -1 : x > y;
}

/* jaw.weights: {"vertices": [index or [first, last], ...], "values": [w, ...]}: one weight in
 * [0, 1] per listed vertex, in the listed order; only soft vertices; none twice. Memory is
 * bounded by the number of values in the file (a range may not list more vertices). */
static int parse_weights(const fpr_ctx *c, fp_rig *r, const cJSON *wj)
{
    const char *path = "jaw.weights";
    static const char *const fw[] = {"vertices", "values", NULL};
    int rc = check_fields(c, wj, path, fw);
    if (rc) return rc;
    char p[512];
    const cJSON *vs, *vals;
    if ((rc = get_member(c, wj, path, "values", true, &vals, p, sizeof p))) return rc;
    if (!cJSON_IsArray(vals)) return fpr_bad(c, p, "expected an array of numbers in [0, 1], got %s", type_name(vals));
    if ((rc = get_member(c, wj, path, "vertices", true, &vs, p, sizeof p))) return rc;
    if (!cJSON_IsArray(vs)) return fpr_bad(c, p, "expected an array of vertex indices and [first, last] ranges, got %s",
                                       type_name(vs));
    size_t nv = (size_t)cJSON_GetArraySize(vals);
    weight_pair *pairs = nv ? malloc(nv * sizeof *pairs) : NULL;
    if (nv && !pairs) return fp_errorf(c->err, c->errlen, -ENOMEM, "%s: out of memory", c->file);
    int i = 0;
    for (const cJSON *e = vals->child; e && !rc; e = e->next, i++) {
        char ep[64];
        snprintf(ep, sizeof ep, "jaw.weights.values[%d]", i);
        if (!cJSON_IsNumber(e)) rc = fpr_bad(c, ep, "expected a number, got %s", type_name(e));
        else if (!(e->valuedouble >= 0 && e->valuedouble <= 1)) rc = fpr_bad(c, ep, "%g is outside [0, 1]", e->valuedouble);
        else pairs[i].w = (float)e->valuedouble;
    }
    size_t k = 0;
    i = 0;
    for (const cJSON *e = vs->child; e && !rc; e = e->next, i++) {
        char ep[64];
        snprintf(ep, sizeof ep, "jaw.weights.vertices[%d]", i);
        uint32_t a, b;
        if ((rc = vertex_span(c, e, ep, r->n, &a, &b))) break;
        if ((size_t)(b - a) + 1 > nv - k) {
            rc = fpr_bad(c, ep, "more vertices listed than jaw.weights.values has numbers (%zu)", nv);
            break;
        }
        for (uint32_t v = a;; v++) {
            if (r->kind[v] != FP_RIG_SOFT) {
                rc = fpr_bad(c, ep, "vertex %u is %s: only soft vertices take a weight (skull 0, jaw 1)", v,
                         r->kind[v] == FP_RIG_SKULL ? "in a skull region" : "in a jaw region");
                break;
            }
            pairs[k].v = v, pairs[k].at = i, k++; /* pairs[k].w: the k-th value */
            if (v == b) break;
        }
    }
    if (!rc && k != nv)
        rc = fpr_bad(c, "jaw.weights", "%zu vertices listed but %zu values: one value per vertex", k, nv);
    if (!rc && nv) {
        qsort(pairs, nv, sizeof *pairs, by_vertex);
        for (size_t j = 1; j < nv && !rc; j++)
            if (pairs[j].v == pairs[j - 1].v) {
                char ep[64];
                snprintf(ep, sizeof ep, "jaw.weights.vertices[%d]", pairs[j].at > pairs[j - 1].at ? pairs[j].at : pairs[j - 1].at);
                rc = fpr_bad(c, ep, "vertex %u is listed twice", pairs[j].v);
            }
    }
    if (!rc && nv) {
        r->weight_v = malloc(nv * sizeof *r->weight_v);
        r->weight_w = malloc(nv * sizeof *r->weight_w);
        if (!r->weight_v || !r->weight_w) rc = fp_errorf(c->err, c->errlen, -ENOMEM, "%s: out of memory", c->file);
        for (size_t j = 0; j < nv && !rc; j++) r->weight_v[j] = pairs[j].v, r->weight_w[j] = pairs[j].w;
        if (!rc) r->weight_count = nv;
    }
    free(pairs);
    return rc;
}

/* The jaw's outline in the sagittal (forward, up) plane: the back border hinge -> gonion and the
 * lower border gonion -> menton must be lines (a gonion on the menton or on the hinge left
 * that border no direction: its fade was silently off, the whole neck turned with the jaw). */
static int check_outline(const fpr_ctx *c, const rig_geom *g)
{
    double zy[3][2]; /* hinge centre, gonion, menton */
    const double *pt[3] = {NULL, g->gonion, g->menton};
    for (int k = 0; k < 3; k++) {
        double d[3];
        for (int i = 0; i < 3; i++)
            d[i] = (k ? pt[k][i] : 0.5 * (g->hinge_r[i] + g->hinge_l[i])) - 0.5 * (g->hinge_r[i] + g->hinge_l[i]);
        zy[k][0] = fp_dot3(d, g->fwd), zy[k][1] = fp_dot3(d, g->up);
    }
    if (!(hypot(zy[1][0] - zy[2][0], zy[1][1] - zy[2][1]) > 0))
        return fpr_bad(c, "jaw.falloff.gonion", "lies on the menton in the (forward, up) plane: the jaw's lower border "
                       "gonion -> menton has no direction");
    if (!(hypot(zy[1][0], zy[1][1]) > 0))
        return fpr_bad(c, "jaw.falloff.gonion", "lies on the hinge in the (forward, up) plane: the jaw's back border "
                       "hinge -> gonion has no direction");
    return 0;
}

static int parse_jaw(const fpr_ctx *c, fp_rig *r, const cJSON *root)
{
    char p[512];
    const cJSON *jaw, *h, *fo;
    int rc = get_object(c, root, "", "jaw", true, &jaw, p, sizeof p);
    if (rc) return rc;
    static const char *const fj[] = {"hinge", "open_degrees", "glide", "glide_start", "falloff", "weights", NULL};
    if ((rc = check_fields(c, jaw, "jaw", fj))) return rc;
    if ((rc = get_object(c, jaw, "jaw", "hinge", true, &h, p, sizeof p))) return rc;
    static const char *const fh[] = {"right", "left", NULL};
    if ((rc = check_fields(c, h, "jaw.hinge", fh)) || (rc = get_vec3(c, h, "jaw.hinge", "right", r->geom.hinge_r)) ||
        (rc = get_vec3(c, h, "jaw.hinge", "left", r->geom.hinge_l)))
        return rc;
    double ax[3] = {r->geom.hinge_l[0] - r->geom.hinge_r[0], r->geom.hinge_l[1] - r->geom.hinge_r[1], r->geom.hinge_l[2] - r->geom.hinge_r[2]};
    double len = sqrt(fp_dot3(ax, ax));
    if (!(len > 0)) return fpr_bad(c, "jaw.hinge", "the two joints coincide");
    normalize(ax);
    if (fp_dot3(ax, r->geom.left) < cos(30 * M_PI / 180))
        return fpr_bad(c, "jaw.hinge", "the axis from right to left joint is %.0f degrees off the face's left axis (at most 30)",
                   acos(fmax(-1, fmin(1, fp_dot3(ax, r->geom.left)))) * 180 / M_PI);
    memcpy(r->geom.axis, ax, sizeof ax);
    if ((rc = get_number(c, jaw, "jaw", "open_degrees", true, 1, 60, &r->open_deg))) return rc;
    const cJSON *g;
    if ((rc = get_member(c, jaw, "jaw", "glide", false, &g, p, sizeof p))) return rc;
    if (g) {
        if (!cJSON_IsArray(g) || cJSON_GetArraySize(g) != 2)
            return fpr_bad(c, p, "expected [forward, down], got %s", type_name(g));
        int k = 0;
        for (const cJSON *e = g->child; e; e = e->next, k++) {
            char q[64];
            snprintf(q, sizeof q, "jaw.glide[%d]", k);
            if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble)) return fpr_bad(c, q, "expected a number, got %s", type_name(e));
            /* a jaw slides a few mm; half the joints' distance apart is already absurd (1e308
             * made every jaw vertex infinite at the first pose) */
            const double span = sqrt((r->geom.hinge_l[0] - r->geom.hinge_r[0]) * (r->geom.hinge_l[0] - r->geom.hinge_r[0]) +
                                     (r->geom.hinge_l[1] - r->geom.hinge_r[1]) * (r->geom.hinge_l[1] - r->geom.hinge_r[1]) +
                                     (r->geom.hinge_l[2] - r->geom.hinge_r[2]) * (r->geom.hinge_l[2] - r->geom.hinge_r[2]));
            if (fabs(e->valuedouble) > 0.5 * span)
                return fpr_bad(c, q, "%g mesh units is more than half the joints' distance apart (%g)",
                           e->valuedouble, span);
            r->geom.glide[k] = e->valuedouble;
        }
    }
    /* where the condyle starts to slide (rigs/README.md "Jaw and falloff"); absent: 0 (the
     * glide linear in jaw.open from the start) */
    const cJSON *gs;
    if ((rc = get_member(c, jaw, "jaw", "glide_start", false, &gs, p, sizeof p))) return rc;
    r->glide_start = 0;
    if (gs && (rc = get_number(c, jaw, "jaw", "glide_start", true, 0, 0.95, &r->glide_start))) return rc;
    if ((rc = get_object(c, jaw, "jaw", "falloff", true, &fo, p, sizeof p))) return rc;
    static const char *const ff[] = {"mouth_line", "lip_band", "cheek_band", "cheek_distance",
                                     "corner_inset", "inner_depth",
                                     "menton", "gonion", "neck_band", "back_band", NULL};
    if ((rc = check_fields(c, fo, "jaw.falloff", ff))) return rc;
    const cJSON *ml;
    if ((rc = get_member(c, fo, "jaw.falloff", "mouth_line", true, &ml, p, sizeof p))) return rc;
    if (!cJSON_IsArray(ml) || cJSON_GetArraySize(ml) < 2 || cJSON_GetArraySize(ml) > MAX_MOUTH_POINTS)
        return fpr_bad(c, p, "expected an array of 2 to %d points (right corner to left corner)", MAX_MOUTH_POINTS);
    int k = 0;
    for (const cJSON *e = ml->child; e; e = e->next, k++) {
        char q[64];
        snprintf(q, sizeof q, "jaw.falloff.mouth_line[%d]", k);
        if ((rc = vec3_of(c, e, q, r->geom.mouth[k]))) return rc;
        if (k > 0) {
            double d[3] = {r->geom.mouth[k][0] - r->geom.mouth[k - 1][0], r->geom.mouth[k][1] - r->geom.mouth[k - 1][1],
                           r->geom.mouth[k][2] - r->geom.mouth[k - 1][2]};
            if (fp_dot3(d, r->geom.left) <= 0) return fpr_bad(c, q, "the mouth line must run from the right corner to the left (along axes.left)");
        }
    }
    r->mouth_count = (size_t)k;
    double big = 1e9;
    if ((rc = get_number(c, fo, "jaw.falloff", "lip_band", true, 0, big, &r->geom.lip_band)) ||
        (rc = get_number(c, fo, "jaw.falloff", "cheek_band", true, 0, big, &r->geom.cheek_band)) ||
        (rc = get_number(c, fo, "jaw.falloff", "cheek_distance", true, 0, big, &r->geom.cheek_distance)) ||
        (rc = get_number(c, fo, "jaw.falloff", "corner_inset", false, 0, big, &r->geom.corner_inset)) ||
        (rc = get_number(c, fo, "jaw.falloff", "inner_depth", false, 0, big, &r->geom.inner_depth)) ||
        (rc = get_number(c, fo, "jaw.falloff", "neck_band", true, 0, big, &r->geom.neck_band)) ||
        (rc = get_number(c, fo, "jaw.falloff", "back_band", true, 0, big, &r->geom.back_band)) ||
        (rc = get_vec3(c, fo, "jaw.falloff", "menton", r->geom.menton)) ||
        (rc = get_vec3(c, fo, "jaw.falloff", "gonion", r->geom.gonion)))
        return rc;
    if (!(r->geom.lip_band > 0) || !(r->geom.cheek_band > 0) || !(r->geom.neck_band > 0) || !(r->geom.back_band > 0) ||
        !(r->geom.cheek_distance > 0))
        return fpr_bad(c, "jaw.falloff", "the bands and cheek_distance must be > 0");
    if ((rc = check_outline(c, &r->geom))) return rc;
    const cJSON *wj;
    if ((rc = get_object(c, jaw, "jaw", "weights", false, &wj, p, sizeof p))) return rc;
    return wj ? parse_weights(c, r, wj) : 0;
}

int fp_rig_parse(const char *json, size_t len, const char *name, fp_rig **out, char *err, size_t errlen)
{
    if (out) *out = NULL;
    if (!json || !out) return fp_errorf(err, errlen, -EINVAL, "fp_rig_parse: NULL argument");
    fpr_ctx c = {name ? name : "(rig)", err, errlen};
    /* a \u0000 in a string: cJSON ends the string there, so "ict\u0000x" was read as "ict"
     * (a name, a landmark's key) without a word. Escapes are two characters ("\\" too). */
    for (const char *q = json; q < json + len && (q = memchr(q, '\\', (size_t)(json + len - q))); q += 2)
        if ((size_t)(json + len - q) >= 6 && !memcmp(q, "\\u0000", 6)) {
            long line;
            fp_text_line_col(json, q, &line, NULL);
            return fp_errorf(err, errlen, -EBADMSG, "%s:%ld: \\u0000 (a NUL character) in a string (byte %zu)",
                             c.file, line, (size_t)(q - json));
        }
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(json, len, &end, false);
    const char *rest = root ? fp_text_after_space(end, json + len) : NULL;
    if (rest && *rest) { /* one JSON value and only white space after it */
        long line;
        fp_text_line_col(json, rest, &line, NULL);
        cJSON_Delete(root);
        return fp_errorf(err, errlen, -EBADMSG, "%s:%ld: text after the rig's JSON object (byte %zu)",
                         c.file, line, (size_t)(rest - json));
    }
    if (!root) {
        const char *at = cJSON_GetErrorPtr();
        if (!(at && at >= json && at <= json + len)) at = json;
        long line;
        fp_text_line_col(json, at, &line, NULL);
        return fp_errorf(err, errlen, -EBADMSG, "%s:%ld: not valid JSON (near byte %zu)", c.file, line,
                         (size_t)(at - json));
    }
    fp_rig *r = calloc(1, sizeof *r);
    if (!r) {
        cJSON_Delete(root);
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", c.file);
    }
    snprintf(r->source, sizeof r->source, "%s", c.file);
    int rc = 0;
    if (!cJSON_IsObject(root)) {
        rc = fpr_bad(&c, "", "expected an object, got %s", type_name(root));
        goto done;
    }
    static const char *const top[] = {"format", "version", "name", "description", "mesh",
                                      "mm_per_unit", "axes", "regions", "landmarks", "jaw",
                                      "mobility", "channels", NULL};
    if ((rc = check_fields(&c, root, "", top))) goto done;
    char fmt[32] = "";
    if ((rc = get_string(&c, root, "", "format", true, fmt, sizeof fmt))) goto done;
    if (strcmp(fmt, "facepuppet-rig")) {
        rc = fpr_bad(&c, "format", "expected \"facepuppet-rig\", got \"%s\"", fmt);
        goto done;
    }
    double ver = 0;
    if ((rc = get_number(&c, root, "", "version", true, 0, 1e6, &ver))) goto done;
    if (ver != FP_RIG_FORMAT_VERSION) {
        rc = fpr_bad(&c, "version", "this facepuppet reads version %d, the file is %.15g", FP_RIG_FORMAT_VERSION, ver);
        goto done;
    }
    char desc[2048];
    if ((rc = get_string(&c, root, "", "name", true, r->name, sizeof r->name)) ||
        (rc = get_string(&c, root, "", "description", false, desc, sizeof desc)) ||
        (rc = parse_mesh(&c, r, root)) ||
        (rc = get_number(&c, root, "", "mm_per_unit", true, 1e-6, 1e6, &r->geom.mm_per_unit)) ||
        (rc = parse_axes(&c, r, root)) || (rc = parse_regions(&c, r, root)) ||
        (rc = parse_landmarks(&c, r, root)) || (rc = parse_reference(&c, r, root)) ||
        (rc = parse_channels(&c, r, root)) ||
        (rc = parse_jaw(&c, r, root)))
        goto done;
    char p[64];
    const cJSON *mob;
    if ((rc = get_object(&c, root, "", "mobility", true, &mob, p, sizeof p))) goto done;
    static const char *const fm[] = {"ramp", NULL};
    if ((rc = check_fields(&c, mob, "mobility", fm)) ||
        (rc = get_number(&c, mob, "mobility", "ramp", true, 1e-9, 1e9, &r->geom.ramp)))
        goto done;
    r->parsed = r->geom; /* (what each bind places anew) */
done:
    cJSON_Delete(root);
    if (rc) {
        fp_rig_free(&r);
        return rc;
    }
    *out = r;
    return 0;
}

int fp_rig_load(const char *path, fp_rig **out, char *err, size_t errlen)
{
    if (out) *out = NULL;
    if (!path || !out) return fp_errorf(err, errlen, -EINVAL, "fp_rig_load: NULL argument");
    char *buf;
    size_t len;
    /* (a folder, FIFO or device: refused). At most FP_RIG_FILE_MAX: cJSON keeps some 80 bytes
     * a value, 40 times a file of "0,0,..." (1 GiB allowed was 40 GB: the OOM killer) */
    int code = fp_file_read_all(path, FP_RIG_FILE_MAX, &buf, &len);
    if (code == -EFBIG)
        return fp_errorf(err, errlen, -EBADMSG, "%s: larger than %d MiB (a rig file is kilobytes)", path,
                         (int)(FP_RIG_FILE_MAX >> 20));
    if (code == -ENOMEM) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", path);
    if (code == -EIO) return fp_errorf(err, errlen, -EIO, "%s: read error", path);
    if (code) return fp_errorf(err, errlen, code, "%s: %s", path, fp_file_error_text(code));
    int rc = fp_rig_parse(buf, len, path, out, err, errlen);
    free(buf);
    return rc;
}
