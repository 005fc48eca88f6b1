/* fp_rig: rig files, validation, binding to a mesh, lookups and the description (fp_rig.h);
 * the pose, the mobility blend and the finger limit are in fp_rig_pose.c. */
#define _GNU_SOURCE
#include "fp_rig_internal.h"

#include "fp_error.h"
#include "fp_text.h"
#include "fp_file.h"
#include "fp_vec.h"

#include <cjson/cJSON.h>
#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

/* ---------------------------------------------------------------------------------- */
/* Parsing helpers: every error names the file and the JSON path.                      */

typedef struct ctx {
    const char *file;
    char *err;
    size_t errlen;
} ctx;

static int bad(const ctx *c, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int bad(const ctx *c, const char *path, const char *fmt, ...)
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
static int check_fields(const ctx *c, const cJSON *obj, const char *path, const char *const *allowed)
{
    for (const cJSON *it = obj->child; it; it = it->next) {
        char p[512];
        join(p, sizeof p, path, it->string ? it->string : "?");
        bool ok = false;
        for (size_t i = 0; allowed[i]; i++)
            if (it->string && !strcmp(it->string, allowed[i])) ok = true;
        if (!ok) return bad(c, p, "unknown field");
        for (const cJSON *jt = it->next; jt; jt = jt->next)
            if (jt->string && !strcmp(jt->string, it->string)) return bad(c, p, "field given twice");
    }
    return 0;
}

static int get_member(const ctx *c, const cJSON *obj, const char *path, const char *key,
                      bool required, const cJSON **out, char *p, size_t plen)
{
    join(p, plen, path, key);
    *out = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!*out && required) return bad(c, p, "missing");
    return 0;
}

static int get_number(const ctx *c, const cJSON *obj, const char *path, const char *key,
                      bool required, double lo, double hi, double *out)
{
    char p[512];
    const cJSON *j;
    int rc = get_member(c, obj, path, key, required, &j, p, sizeof p);
    if (rc || !j) return rc;
    if (!cJSON_IsNumber(j)) return bad(c, p, "expected a number, got %s", type_name(j));
    if (!isfinite(j->valuedouble) || j->valuedouble < lo || j->valuedouble > hi)
        return bad(c, p, "%g is outside [%g, %g]", j->valuedouble, lo, hi);
    *out = j->valuedouble;
    return 0;
}

static int get_string(const ctx *c, const cJSON *obj, const char *path, const char *key,
                      bool required, char *out, size_t len)
{
    char p[512];
    const cJSON *j;
    int rc = get_member(c, obj, path, key, required, &j, p, sizeof p);
    if (rc || !j) return rc;
    if (!cJSON_IsString(j)) return bad(c, p, "expected a string, got %s", type_name(j));
    if (strlen(j->valuestring) >= len) return bad(c, p, "longer than %zu bytes", len - 1);
    if (!fp_text_ok(j->valuestring, false)) /* (an ESC in a name recoloured info's terminal) */
        return bad(c, p, "not UTF-8 text without control characters");
    strcpy(out, j->valuestring);
    return 0;
}

static int vec3_of(const ctx *c, const cJSON *j, const char *p, double out[3])
{
    if (!cJSON_IsArray(j) || cJSON_GetArraySize(j) != 3)
        return bad(c, p, "expected an array of 3 numbers, got %s", type_name(j));
    int i = 0;
    for (const cJSON *e = j->child; e; e = e->next, i++) {
        char q[560];
        snprintf(q, sizeof q, "%s[%d]", p, i);
        if (!cJSON_IsNumber(e)) return bad(c, q, "expected a number, got %s", type_name(e));
        if (!isfinite(e->valuedouble) || fabs(e->valuedouble) > 1e12)
            return bad(c, q, "not a finite coordinate");
        out[i] = e->valuedouble;
    }
    return 0;
}

static int get_vec3(const ctx *c, const cJSON *obj, const char *path, const char *key, double out[3])
{
    char p[512];
    const cJSON *j;
    int rc = get_member(c, obj, path, key, true, &j, p, sizeof p);
    return rc ? rc : vec3_of(c, j, p, out);
}

static int get_object(const ctx *c, const cJSON *obj, const char *path, const char *key,
                      bool required, const cJSON **out, char *p, size_t plen)
{
    int rc = get_member(c, obj, path, key, required, out, p, plen);
    if (rc || !*out) return rc;
    if (!cJSON_IsObject(*out)) return bad(c, p, "expected an object, got %s", type_name(*out));
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

static int vertex_index(const ctx *c, const cJSON *e, const char *p, size_t n, uint32_t *out)
{
    if (!cJSON_IsNumber(e)) return bad(c, p, "expected a vertex index, got %s", type_name(e));
    double v = e->valuedouble;
    if (!isfinite(v) || v != floor(v) || v < 0) return bad(c, p, "%g is not a vertex index", v);
    if (v >= (double)n) /* (%g: %.0f wrote 1e308 as 309 digits) */
        return bad(c, p, "vertex %.15g is out of range (the mesh has %zu)", v, n);
    *out = (uint32_t)v;
    return 0;
}

/* One entry of a vertex list: an index, or a range [first, last] (inclusive) at path p;
 * *a..*b the vertices. */
static int vertex_span(const ctx *c, const cJSON *e, const char *p, size_t n, uint32_t *a, uint32_t *b)
{
    int rc;
    if (!cJSON_IsArray(e)) {
        if ((rc = vertex_index(c, e, p, n, a))) return rc;
        *b = *a;
        return 0;
    }
    if (cJSON_GetArraySize(e) != 2) return bad(c, p, "a range is [first, last]");
    char q[160];
    snprintf(q, sizeof q, "%s[0]", p);
    if ((rc = vertex_index(c, e->child, q, n, a))) return rc;
    snprintf(q, sizeof q, "%s[1]", p);
    if ((rc = vertex_index(c, e->child->next, q, n, b))) return rc;
    if (*b < *a) return bad(c, p, "range [%u, %u] runs backwards", *a, *b);
    return 0;
}

static void normalize(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0) v[0] /= l, v[1] /= l, v[2] /= l;
}

/* ---------------------------------------------------------------------------------- */

static int parse_mesh(const ctx *c, fp_rig *r, const cJSON *root)
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
    if (n != floor(n)) return bad(c, "mesh.vertex_count", "not an integer");
    r->n = (size_t)n;
    char crc[16] = "";
    if ((rc = get_string(c, m, "mesh", "positions_crc32", true, crc, sizeof crc))) return rc;
    char *end = NULL;
    unsigned long v = strtoul(crc, &end, 16);
    if (strlen(crc) != 8 || !end || *end)
        return bad(c, "mesh.positions_crc32", "expected 8 hexadecimal digits, got \"%s\"", crc);
    r->crc = (uint32_t)v;
    return 0;
}

static int parse_axes(const ctx *c, fp_rig *r, const cJSON *root)
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
        if (fabs(l - 1) > 1e-3) return bad(c, nm[i], "not a unit vector (length %g)", l);
        normalize(ax[i]);
    }
    if (fabs(fp_dot3(r->geom.up, r->geom.fwd)) > 1e-3 || fabs(fp_dot3(r->geom.up, r->geom.left)) > 1e-3 ||
        fabs(fp_dot3(r->geom.fwd, r->geom.left)) > 1e-3)
        return bad(c, "axes", "up, forward and left are not orthogonal");
    double x[3];
    fp_cross3(r->geom.up, r->geom.fwd, x);
    if (fp_dot3(x, r->geom.left) < 0.999) return bad(c, "axes.left", "must equal up x forward (a right-handed frame)");
    return 0;
}

static int parse_regions(const ctx *c, fp_rig *r, const cJSON *root)
{
    char p[512];
    const cJSON *rs;
    int rc = get_member(c, root, "", "regions", true, &rs, p, sizeof p);
    if (rc) return rc;
    if (!cJSON_IsArray(rs)) return bad(c, "regions", "expected an array, got %s", type_name(rs));
    int nr = cJSON_GetArraySize(rs);
    if (nr > FP_RIG_MAX_REGIONS) return bad(c, "regions", "more than %d regions", FP_RIG_MAX_REGIONS);
    r->kind = calloc(r->n, 1);
    uint8_t *owner = r->owner = calloc(r->n, 1); /* region index + 1 that claimed the vertex */
    if (!r->kind || !owner)
        return fp_errorf(c->err, c->errlen, -ENOMEM, "%s: out of memory", c->file);
    int i = 0;
    rc = 0;
    for (const cJSON *g = rs->child; g && !rc; g = g->next, i++) {
        char gp[64];
        snprintf(gp, sizeof gp, "regions[%d]", i);
        if (!cJSON_IsObject(g)) { rc = bad(c, gp, "expected an object, got %s", type_name(g)); break; }
        static const char *const f[] = {"name", "kind", "vertices", NULL};
        if ((rc = check_fields(c, g, gp, f))) break;
        region *reg = &r->regions[i];
        if ((rc = get_string(c, g, gp, "name", true, reg->name, sizeof reg->name))) break;
        if (!valid_name(reg->name)) { rc = bad(c, gp, "name \"%s\": use a-z 0-9 _ . -", reg->name); break; }
        for (int k = 0; k < i; k++)
            if (!strcmp(r->regions[k].name, reg->name)) rc = bad(c, gp, "region \"%s\" given twice", reg->name);
        if (rc) break;
        char kind[16];
        if ((rc = get_string(c, g, gp, "kind", true, kind, sizeof kind))) break;
        if (!strcmp(kind, "soft")) reg->kind = FP_RIG_SOFT;
        else if (!strcmp(kind, "skull")) reg->kind = FP_RIG_SKULL;
        else if (!strcmp(kind, "jaw")) reg->kind = FP_RIG_JAW;
        else { char q[80]; snprintf(q, sizeof q, "%s.kind", gp); rc = bad(c, q, "\"%s\" is not soft, skull or jaw", kind); break; }
        const cJSON *vs;
        char vp[96];
        if ((rc = get_member(c, g, gp, "vertices", true, &vs, vp, sizeof vp))) break;
        if (!cJSON_IsArray(vs)) { rc = bad(c, vp, "expected an array, got %s", type_name(vs)); break; }
        int k = 0;
        for (const cJSON *e = vs->child; e && !rc; e = e->next, k++) {
            char ep[128];
            snprintf(ep, sizeof ep, "%s[%d]", vp, k);
            uint32_t a, b;
            if ((rc = vertex_span(c, e, ep, r->n, &a, &b))) break;
            for (uint32_t v = a; v <= b; v++) {
                if (owner[v] == (uint8_t)(i + 1)) continue; /* repeated in the same region */
                if (owner[v]) {
                    const region *o = &r->regions[owner[v] - 1];
                    rc = bad(c, ep, "vertex %u is already in regions[%d] \"%s\" (%s): regions may not overlap",
                             v, owner[v] - 1, o->name,
                             o->kind == FP_RIG_SKULL ? "skull" : o->kind == FP_RIG_JAW ? "jaw" : "soft");
                    break;
                }
                owner[v] = (uint8_t)(i + 1);
                r->kind[v] = (uint8_t)reg->kind;
                reg->count++;
            }
        }
    }
    if (rc) return rc;
    r->region_count = (size_t)nr;
    size_t skull = 0, jaw = 0;
    for (size_t v = 0; v < r->n; v++) skull += r->kind[v] == FP_RIG_SKULL, jaw += r->kind[v] == FP_RIG_JAW;
    if (!skull) return bad(c, "regions", "no skull vertices: a rig needs a skull region");
    if (!jaw) return bad(c, "regions", "no jaw vertices: a rig needs a jaw region");
    return 0;
}

static int parse_landmarks(const ctx *c, fp_rig *r, const cJSON *root)
{
    char p[512];
    const cJSON *ls;
    int rc = get_object(c, root, "", "landmarks", true, &ls, p, sizeof p);
    if (rc) return rc;
    for (const cJSON *e = ls->child; e; e = e->next) {
        char q[600];
        join(q, sizeof q, "landmarks", e->string ? e->string : "?");
        if (!e->string || !valid_name(e->string)) return bad(c, q, "bad landmark name: use a-z 0-9 _ . -");
        if (r->landmark_count >= FP_RIG_MAX_LANDMARKS) return bad(c, q, "more than %d landmarks", FP_RIG_MAX_LANDMARKS);
        for (size_t k = 0; k < r->landmark_count; k++)
            if (!strcmp(r->landmarks[k].name, e->string)) return bad(c, q, "landmark given twice");
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
            return bad(c, q, "missing (every rig names it)");
        }
    }
    return 0;
}

/* mesh.landmark_positions (optional): every landmark's position on the rig's own mesh, which
 * places the rig on a moved copy of it (fp_rig_place.c) */
static int parse_reference(const ctx *c, fp_rig *r, const cJSON *root)
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
        size_t k = 0;
        while (e->string && k < r->landmark_count && strcmp(r->landmarks[k].name, e->string)) k++;
        if (!e->string || k == r->landmark_count) return bad(c, q, "no landmark of that name");
        if (cJSON_GetObjectItemCaseSensitive(lp, e->string) != e) return bad(c, q, "given twice");
        if ((rc = vec3_of(c, e, q, r->landmarks[k].ref))) return rc;
        given++;
    }
    if (given != r->landmark_count)
        return bad(c, "mesh.landmark_positions", "%zu of the %zu landmarks: give every one", given,
                   r->landmark_count);
    r->has_ref = true;
    return 0;
}

static int parse_channels(const ctx *c, fp_rig *r, const cJSON *root)
{
    char p[512];
    const cJSON *cs;
    int rc = get_member(c, root, "", "channels", true, &cs, p, sizeof p);
    if (rc) return rc;
    if (!cJSON_IsArray(cs)) return bad(c, "channels", "expected an array, got %s", type_name(cs));
    int i = 0;
    r->jaw_open = -1;
    for (const cJSON *e = cs->child; e; e = e->next, i++) {
        char q[64];
        snprintf(q, sizeof q, "channels[%d]", i);
        if (!cJSON_IsObject(e)) return bad(c, q, "expected an object, got %s", type_name(e));
        if (i >= FP_RIG_MAX_CHANNELS) return bad(c, q, "more than %d channels", FP_RIG_MAX_CHANNELS);
        static const char *const f[] = {"name", "min", "max", "neutral", NULL};
        if ((rc = check_fields(c, e, q, f))) return rc;
        channel *ch = &r->channels[i];
        if ((rc = get_string(c, e, q, "name", true, ch->name, sizeof ch->name))) return rc;
        if (!valid_name(ch->name)) return bad(c, q, "name \"%s\": use a-z 0-9 _ . -", ch->name);
        for (int k = 0; k < i; k++)
            if (!strcmp(r->channels[k].name, ch->name)) return bad(c, q, "channel \"%s\" given twice", ch->name);
        double lo, hi, neutral = 0;
        if ((rc = get_number(c, e, q, "min", true, -1e6, 1e6, &lo)) ||
            (rc = get_number(c, e, q, "max", true, -1e6, 1e6, &hi)))
            return rc;
        if (!(hi > lo)) return bad(c, q, "max (%g) must exceed min (%g)", hi, lo);
        neutral = lo;
        if ((rc = get_number(c, e, q, "neutral", false, lo, hi, &neutral))) return rc;
        ch->min = (float)lo, ch->max = (float)hi, ch->neutral = (float)neutral;
        if (!strcmp(ch->name, "jaw.open")) {
            if (lo != 0 || hi != 1) return bad(c, q, "jaw.open must range over [0, 1]");
            r->jaw_open = i;
        }
    }
    r->channel_count = (size_t)i;
    if (r->jaw_open < 0) return bad(c, "channels", "no \"jaw.open\" channel");
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
static int parse_weights(const ctx *c, fp_rig *r, const cJSON *wj)
{
    const char *path = "jaw.weights";
    static const char *const fw[] = {"vertices", "values", NULL};
    int rc = check_fields(c, wj, path, fw);
    if (rc) return rc;
    char p[512];
    const cJSON *vs, *vals;
    if ((rc = get_member(c, wj, path, "values", true, &vals, p, sizeof p))) return rc;
    if (!cJSON_IsArray(vals)) return bad(c, p, "expected an array of numbers in [0, 1], got %s", type_name(vals));
    if ((rc = get_member(c, wj, path, "vertices", true, &vs, p, sizeof p))) return rc;
    if (!cJSON_IsArray(vs)) return bad(c, p, "expected an array of vertex indices and [first, last] ranges, got %s",
                                       type_name(vs));
    size_t nv = (size_t)cJSON_GetArraySize(vals);
    weight_pair *pairs = nv ? malloc(nv * sizeof *pairs) : NULL;
    if (nv && !pairs) return fp_errorf(c->err, c->errlen, -ENOMEM, "%s: out of memory", c->file);
    int i = 0;
    for (const cJSON *e = vals->child; e && !rc; e = e->next, i++) {
        char ep[64];
        snprintf(ep, sizeof ep, "jaw.weights.values[%d]", i);
        if (!cJSON_IsNumber(e)) rc = bad(c, ep, "expected a number, got %s", type_name(e));
        else if (!(e->valuedouble >= 0 && e->valuedouble <= 1)) rc = bad(c, ep, "%g is outside [0, 1]", e->valuedouble);
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
            rc = bad(c, ep, "more vertices listed than jaw.weights.values has numbers (%zu)", nv);
            break;
        }
        for (uint32_t v = a;; v++) {
            if (r->kind[v] != FP_RIG_SOFT) {
                rc = bad(c, ep, "vertex %u is %s: only soft vertices take a weight (skull 0, jaw 1)", v,
                         r->kind[v] == FP_RIG_SKULL ? "in a skull region" : "in a jaw region");
                break;
            }
            pairs[k].v = v, pairs[k].at = i, k++; /* pairs[k].w: the k-th value */
            if (v == b) break;
        }
    }
    if (!rc && k != nv)
        rc = bad(c, "jaw.weights", "%zu vertices listed but %zu values: one value per vertex", k, nv);
    if (!rc && nv) {
        qsort(pairs, nv, sizeof *pairs, by_vertex);
        for (size_t j = 1; j < nv && !rc; j++)
            if (pairs[j].v == pairs[j - 1].v) {
                char ep[64];
                snprintf(ep, sizeof ep, "jaw.weights.vertices[%d]", pairs[j].at > pairs[j - 1].at ? pairs[j].at : pairs[j - 1].at);
                rc = bad(c, ep, "vertex %u is listed twice", pairs[j].v);
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

static int parse_jaw(const ctx *c, fp_rig *r, const cJSON *root)
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
    if (!(len > 0)) return bad(c, "jaw.hinge", "the two joints coincide");
    normalize(ax);
    if (fp_dot3(ax, r->geom.left) < cos(30 * M_PI / 180))
        return bad(c, "jaw.hinge", "the axis from right to left joint is %.0f degrees off the face's left axis (at most 30)",
                   acos(fmax(-1, fmin(1, fp_dot3(ax, r->geom.left)))) * 180 / M_PI);
    memcpy(r->geom.axis, ax, sizeof ax);
    if ((rc = get_number(c, jaw, "jaw", "open_degrees", true, 1, 60, &r->open_deg))) return rc;
    const cJSON *g;
    if ((rc = get_member(c, jaw, "jaw", "glide", false, &g, p, sizeof p))) return rc;
    if (g) {
        if (!cJSON_IsArray(g) || cJSON_GetArraySize(g) != 2)
            return bad(c, p, "expected [forward, down], got %s", type_name(g));
        int k = 0;
        for (const cJSON *e = g->child; e; e = e->next, k++) {
            char q[64];
            snprintf(q, sizeof q, "jaw.glide[%d]", k);
            if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble)) return bad(c, q, "expected a number, got %s", type_name(e));
            /* a jaw slides a few mm; half the joints' distance apart is already absurd (1e308
             * made every jaw vertex infinite at the first pose) */
            const double span = sqrt((r->geom.hinge_l[0] - r->geom.hinge_r[0]) * (r->geom.hinge_l[0] - r->geom.hinge_r[0]) +
                                     (r->geom.hinge_l[1] - r->geom.hinge_r[1]) * (r->geom.hinge_l[1] - r->geom.hinge_r[1]) +
                                     (r->geom.hinge_l[2] - r->geom.hinge_r[2]) * (r->geom.hinge_l[2] - r->geom.hinge_r[2]));
            if (fabs(e->valuedouble) > 0.5 * span)
                return bad(c, q, "%g mesh units is more than half the joints' distance apart (%g)",
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
        return bad(c, p, "expected an array of 2 to %d points (right corner to left corner)", MAX_MOUTH_POINTS);
    int k = 0;
    for (const cJSON *e = ml->child; e; e = e->next, k++) {
        char q[64];
        snprintf(q, sizeof q, "jaw.falloff.mouth_line[%d]", k);
        if ((rc = vec3_of(c, e, q, r->geom.mouth[k]))) return rc;
        if (k > 0) {
            double d[3] = {r->geom.mouth[k][0] - r->geom.mouth[k - 1][0], r->geom.mouth[k][1] - r->geom.mouth[k - 1][1],
                           r->geom.mouth[k][2] - r->geom.mouth[k - 1][2]};
            if (fp_dot3(d, r->geom.left) <= 0) return bad(c, q, "the mouth line must run from the right corner to the left (along axes.left)");
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
        return bad(c, "jaw.falloff", "the bands and cheek_distance must be > 0");
    const cJSON *wj;
    if ((rc = get_object(c, jaw, "jaw", "weights", false, &wj, p, sizeof p))) return rc;
    return wj ? parse_weights(c, r, wj) : 0;
}

int fp_rig_parse(const char *json, size_t len, const char *name, fp_rig **out, char *err, size_t errlen)
{
    if (out) *out = NULL;
    if (!json || !out) return fp_errorf(err, errlen, -EINVAL, "fp_rig_parse: NULL argument");
    ctx c = {name ? name : "(rig)", err, errlen};
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
        rc = bad(&c, "", "expected an object, got %s", type_name(root));
        goto done;
    }
    static const char *const top[] = {"format", "version", "name", "description", "mesh",
                                      "mm_per_unit", "axes", "regions", "landmarks", "jaw",
                                      "mobility", "channels", NULL};
    if ((rc = check_fields(&c, root, "", top))) goto done;
    char fmt[32] = "";
    if ((rc = get_string(&c, root, "", "format", true, fmt, sizeof fmt))) goto done;
    if (strcmp(fmt, "facepuppet-rig")) {
        rc = bad(&c, "format", "expected \"facepuppet-rig\", got \"%s\"", fmt);
        goto done;
    }
    double ver = 0;
    if ((rc = get_number(&c, root, "", "version", true, 0, 1e6, &ver))) goto done;
    if (ver != FP_RIG_FORMAT_VERSION) {
        rc = bad(&c, "version", "this facepuppet reads version %d, the file is %g", FP_RIG_FORMAT_VERSION, ver);
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
    int code;
    FILE *f = fp_file_fopen_regular(path, &code); /* (a folder, FIFO or device: refused) */
    if (!f) return fp_errorf(err, errlen, code, "%s: %s", path, fp_file_error_text(code));
    char *buf = NULL;
    size_t len = 0, cap = 0;
    for (;;) {
        if (len + 65536 > cap) {
            cap = cap ? cap * 2 : 1 << 20;
            if (cap > (size_t)1 << 30) {
                free(buf);
                fclose(f);
                return fp_errorf(err, errlen, -EBADMSG, "%s: larger than 1 GiB", path);
            }
            char *nb = realloc(buf, cap);
            if (!nb) {
                free(buf);
                fclose(f);
                return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", path);
            }
            buf = nb;
        }
        size_t got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0) break;
    }
    int ioerr = ferror(f);
    fclose(f);
    if (ioerr) {
        free(buf);
        return fp_errorf(err, errlen, -EIO, "%s: read error", path);
    }
    int rc = fp_rig_parse(buf, len, path, out, err, errlen);
    free(buf);
    return rc;
}

/* ---------------------------------------------------------------------------------- */
/* Binding: the falloff and the mobility.                                              */

static double smoothstep(double a, double b, double x)
{
    if (x <= a) return 0;
    if (x >= b) return 1;
    double t = (x - a) / (b - a);
    return t * t * (3 - 2 * t);
}

/* Face coordinates of p relative to the hinge centre: x left, y up, z forward. */
static void face_coords(const fp_rig *r, const double p[3], double *x, double *y, double *z)
{
    double d[3];
    for (int i = 0; i < 3; i++) d[i] = p[i] - 0.5 * (r->geom.hinge_r[i] + r->geom.hinge_l[i]);
    *x = fp_dot3(d, r->geom.left);
    *y = fp_dot3(d, r->geom.up);
    *z = fp_dot3(d, r->geom.fwd);
}

/* Signed distance of (z, y) from the line a -> b in the sagittal plane, positive on the side
 * away from the point o. */
static double side_distance(const double a[2], const double b[2], const double o[2], double z, double y)
{
    double dz = b[0] - a[0], dy = b[1] - a[1];
    double l = sqrt(dz * dz + dy * dy);
    if (!(l > 0)) return -INFINITY;
    double nz = dy / l, ny = -dz / l; /* a normal */
    double so = (o[0] - a[0]) * nz + (o[1] - a[1]) * ny;
    if (so > 0) nz = -nz, ny = -ny;
    return (z - a[0]) * nz + (y - a[1]) * ny;
}

/* The jaw weight of a soft-tissue point (rigs/README.md "Falloff"). */
static double falloff(const fp_rig *r, const double p[3], const double mouth[][3], const double C[2],
                      const double G[2], const double M[2])
{
    double x, y, z;
    face_coords(r, p, &x, &y, &z);
    /* the mouth line's height at x, and the distance beyond the corners */
    size_t k = r->mouth_count;
    double ym, zm, e;
    if (x <= mouth[0][0]) {
        ym = mouth[0][1], zm = mouth[0][2];
        e = mouth[0][0] - x;
    } else if (x >= mouth[k - 1][0]) {
        ym = mouth[k - 1][1], zm = mouth[k - 1][2];
        e = x - mouth[k - 1][0];
    } else {
        size_t i = 1;
        while (i < k - 1 && x > mouth[i][0]) i++;
        double t = (x - mouth[i - 1][0]) / (mouth[i][0] - mouth[i - 1][0]);
        ym = mouth[i - 1][1] + t * (mouth[i][1] - mouth[i - 1][1]);
        zm = mouth[i - 1][2] + t * (mouth[i][2] - mouth[i - 1][2]);
        e = -fmin(x - mouth[0][0], mouth[k - 1][0] - x); /* inside the corners: negative */
    }
    /* the split between the lips widens toward the corners (from corner_inset inside them to
     * cheek_distance beyond) and with the depth behind the lips (the mouth's lining) */
    double s = smoothstep(-r->geom.corner_inset, r->geom.cheek_distance, e);
    if (r->geom.inner_depth > 0) s = fmax(s, smoothstep(r->geom.inner_depth, 2 * r->geom.inner_depth, zm - z));
    double b = r->geom.lip_band + (r->geom.cheek_band - r->geom.lip_band) * s;
    double w_mouth = 1 - smoothstep(-b, b, y - ym);
    if (w_mouth == 0) return 0;
    double d_back = side_distance(C, G, M, z, y);  /* behind the ramus */
    double d_below = side_distance(G, M, C, z, y); /* below the mandible's lower border */
    double w_back = 1 - smoothstep(0, r->geom.back_band, d_back);
    double w_neck = 1 - smoothstep(0, r->geom.neck_band, d_below);
    return w_mouth * w_back * w_neck;
}

int fp_rig_bind(fp_rig *r, size_t n, const float *pos, char *err, size_t errlen)
{
    if (!r || !pos) return fp_errorf(err, errlen, -EINVAL, "fp_rig_bind: NULL argument");
    ctx c = {r->source, err, errlen};
    if (n != r->n) return bad(&c, "mesh.vertex_count", "the rig fits %zu vertices, the mesh has %zu", r->n, n);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < n; v++)
        for (int i = 0; i < 3; i++) {
            double q = pos[3 * v + i];
            if (!isfinite(q)) return fp_errorf(err, errlen, -EINVAL, "fp_rig_bind: vertex %zu is not finite", v);
            lo[i] = fmin(lo[i], q), hi[i] = fmax(hi[i], q);
        }
    fpr_place(r, pos); /* a moved copy of the rig's mesh: its coordinates carried there */
    const double *hp[2] = {r->geom.hinge_r, r->geom.hinge_l};
    const char *hn[2] = {"jaw.hinge.right", "jaw.hinge.left"};
    double reach = 60.0 / r->geom.mm_per_unit;
    for (int s = 0; s < 2; s++) {
        for (int i = 0; i < 3; i++)
            if (hp[s][i] < lo[i] || hp[s][i] > hi[i])
                return bad(&c, hn[s], "(%g, %g, %g) lies outside the mesh's bounds: the hinge must be inside the head",
                           hp[s][0], hp[s][1], hp[s][2]);
        double best = INFINITY;
        for (size_t v = 0; v < n; v++) {
            double d0 = pos[3 * v] - hp[s][0], d1 = pos[3 * v + 1] - hp[s][1], d2 = pos[3 * v + 2] - hp[s][2];
            best = fmin(best, d0 * d0 + d1 * d1 + d2 * d2);
        }
        if (sqrt(best) > reach)
            return bad(&c, hn[s], "no vertex within 60 mm (nearest %.4g mm): not near the head",
                       sqrt(best) * r->geom.mm_per_unit);
    }
    float *w = malloc(n * sizeof *w), *m = malloc(n * sizeof *m), *g = calloc(n, sizeof *g);
    uint32_t *slope_v = malloc(n * sizeof *slope_v);
    float *slope_dir = malloc(3 * n * sizeof *slope_dir);
    size_t slope_count = 0;
    if (!w || !m || !g || !slope_v || !slope_dir) {
        free(w), free(m), free(g), free(slope_v), free(slope_dir);
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", r->source);
    }
    /* sagittal-plane points of the jaw outline and the mouth line in face coordinates */
    double mouth[MAX_MOUTH_POINTS][3], C[2] = {0, 0}, G[2], M[2], x, y, z;
    for (size_t k = 0; k < r->mouth_count; k++) {
        face_coords(r, r->geom.mouth[k], &x, &y, &z);
        mouth[k][0] = x, mouth[k][1] = y, mouth[k][2] = z;
    }
    face_coords(r, r->geom.gonion, &x, &y, &z);
    G[0] = z, G[1] = y;
    face_coords(r, r->geom.menton, &x, &y, &z);
    M[0] = z, M[1] = y;
    for (size_t v = 0; v < n; v++) {
        if (r->kind[v] == FP_RIG_SKULL) w[v] = 0;
        else if (r->kind[v] == FP_RIG_JAW) w[v] = 1;
        else {
            double p[3] = {pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]};
            w[v] = (float)falloff(r, p, mouth, C, G, M);
        }
    }
    for (size_t k = 0; k < r->weight_count; k++) w[r->weight_v[k]] = r->weight_w[k]; /* jaw.weights */
    /* mobility: smoothstep of the distance to the nearest rigid vertex, through a grid */
    double cell = r->geom.ramp;
    long dims[3];
    for (int i = 0; i < 3; i++) {
        double d = floor((hi[i] - lo[i]) / cell) + 1;
        dims[i] = d > 256 ? 256 : (long)d;
    }
    double csz[3];
    for (int i = 0; i < 3; i++) csz[i] = fmax((hi[i] - lo[i]) / (double)dims[i], cell);
    for (int i = 0; i < 3; i++) dims[i] = (long)floor((hi[i] - lo[i]) / csz[i]) + 1;
    size_t ncell = (size_t)(dims[0] * dims[1] * dims[2]);
    size_t *start = calloc(ncell + 1, sizeof *start), *items = malloc(n * sizeof *items);
    if (!start || !items) {
        free(w), free(m), free(g), free(slope_v), free(slope_dir), free(start), free(items);
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", r->source);
    }
#define CELL(v, i) ((long)fmin((double)(dims[i] - 1), floor((pos[3 * (v) + (i)] - lo[i]) / csz[i])))
    for (size_t v = 0; v < n; v++)
        if (r->kind[v] != FP_RIG_SOFT) start[(CELL(v, 0) * dims[1] + CELL(v, 1)) * dims[2] + CELL(v, 2) + 1]++;
    for (size_t i = 0; i < ncell; i++) start[i + 1] += start[i];
    size_t *fill = calloc(ncell, sizeof *fill);
    if (!fill) {
        free(w), free(m), free(g), free(slope_v), free(slope_dir), free(start), free(items);
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", r->source);
    }
    for (size_t v = 0; v < n; v++)
        if (r->kind[v] != FP_RIG_SOFT) {
            size_t ci = (size_t)((CELL(v, 0) * dims[1] + CELL(v, 1)) * dims[2] + CELL(v, 2));
            items[start[ci] + fill[ci]++] = v;
        }
    for (size_t v = 0; v < n; v++) {
        if (r->kind[v] != FP_RIG_SOFT) {
            m[v] = 0;
            continue;
        }
        long cc[3] = {CELL(v, 0), CELL(v, 1), CELL(v, 2)};
        double best = INFINITY;
        size_t bu = v;
        for (long a = cc[0] - 1; a <= cc[0] + 1; a++)
            for (long b = cc[1] - 1; b <= cc[1] + 1; b++)
                for (long d = cc[2] - 1; d <= cc[2] + 1; d++) {
                    if (a < 0 || b < 0 || d < 0 || a >= dims[0] || b >= dims[1] || d >= dims[2]) continue;
                    size_t ci = (size_t)((a * dims[1] + b) * dims[2] + d);
                    for (size_t k = start[ci]; k < start[ci + 1]; k++) {
                        size_t u = items[k];
                        double d0 = pos[3 * u] - pos[3 * v], d1 = pos[3 * u + 1] - pos[3 * v + 1],
                               d2 = pos[3 * u + 2] - pos[3 * v + 2];
                        if (d0 * d0 + d1 * d1 + d2 * d2 < best) best = d0 * d0 + d1 * d1 + d2 * d2, bu = u;
                    }
                }
        m[v] = (float)smoothstep(0, r->geom.ramp, sqrt(best));
        /* |grad m| = smoothstep'(d) |grad d| = 6 t (1 - t) / ramp (t = d / ramp; |grad d| = 1) */
        double t = sqrt(best) / r->geom.ramp;
        g[v] = t > 0 && t < 1 ? (float)(6 * t * (1 - t) / r->geom.ramp) : 0.0f;
        if (g[v] > 0) { /* grad m points away from the nearest rigid vertex */
            double e = sqrt(best);
            for (int i = 0; i < 3; i++) slope_dir[3 * slope_count + i] = (float)((pos[3 * v + i] - pos[3 * bu + i]) / e);
            slope_v[slope_count++] = (uint32_t)v;
        }
    }
#undef CELL
    free(start), free(items), free(fill);
    free(r->w), free(r->m), free(r->g), free(r->slope_v), free(r->slope_dir);
    r->w = w, r->m = m, r->g = g, r->slope_v = slope_v, r->slope_dir = slope_dir, r->slope_count = slope_count;
    return 0;
}

int fp_rig_load_for_mesh(const char *path, size_t n, const float *pos, fp_rig **out, char *err, size_t errlen)
{
    int rc = fp_rig_load(path, out, err, errlen);
    if (rc) return rc;
    rc = fp_rig_bind(*out, n, pos, err, errlen);
    if (rc) fp_rig_free(out);
    return rc;
}

void fp_rig_free(fp_rig **rig)
{
    if (!rig || !*rig) return;
    free((*rig)->kind);
    free((*rig)->owner);
    free((*rig)->w);
    free((*rig)->m);
    free((*rig)->g);
    free((*rig)->slope_dir);
    free((*rig)->slope_v);
    free((*rig)->weight_v);
    free((*rig)->weight_w);
    free(*rig);
    *rig = NULL;
}

uint32_t fp_rig_positions_crc32(size_t n, const float *pos)
{
    uLong crc = crc32(0L, Z_NULL, 0);
    unsigned char buf[4096];
    size_t k = 0;
    for (size_t i = 0; i < 3 * n; i++) {
        uint32_t u;
        memcpy(&u, &pos[i], 4);
        buf[k++] = (unsigned char)u, buf[k++] = (unsigned char)(u >> 8);
        buf[k++] = (unsigned char)(u >> 16), buf[k++] = (unsigned char)(u >> 24);
        if (k == sizeof buf) crc = crc32(crc, buf, (uInt)k), k = 0;
    }
    if (k) crc = crc32(crc, buf, (uInt)k);
    return (uint32_t)crc;
}

int fp_rig_checksum_matches(const fp_rig *rig, size_t n, const float *pos)
{
    return rig && pos && n == rig->n && fp_rig_positions_crc32(n, pos) == rig->crc;
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

int fp_rig_find(const char *dir, size_t n, const float *pos, char *path_out, size_t path_len, char *err,
                size_t errlen)
{
    if (!dir || !pos || !path_out || !path_len) return fp_errorf(err, errlen, -EINVAL, "fp_rig_find: NULL argument");
    DIR *d = opendir(dir);
    if (!d) return fp_errorf(err, errlen, -ENOENT, "%s: %s", dir, strerror(errno));
    char *names[512];
    size_t count = 0;
    struct dirent *e;
    while ((e = readdir(d)) && count < 512) {
        size_t l = strlen(e->d_name);
        if (l > 5 && !strcmp(e->d_name + l - 5, ".json")) names[count++] = strdup(e->d_name);
    }
    closedir(d);
    qsort(names, count, sizeof *names, by_name);
    uint32_t crc = fp_rig_positions_crc32(n, pos);
    char by_count[4096] = "";
    int count_matches = 0;
    int rc = -ENOENT;
    for (size_t i = 0; i < count; i++) {
        if (!names[i]) continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        fp_rig *r = NULL;
        char e2[256];
        if (fp_rig_load(path, &r, e2, sizeof e2) == 0) {
            if (r->n == n && r->crc == crc && rc != 0) {
                rc = strlen(path) < path_len ? 0 : -ENAMETOOLONG;
                if (!rc) strcpy(path_out, path);
            } else if (r->n == n) {
                count_matches++;
                snprintf(by_count, sizeof by_count, "%s", path);
            }
            fp_rig_free(&r);
        }
    }
    for (size_t i = 0; i < count; i++) free(names[i]);
    if (rc == 0) return 0;
    if (rc == -ENAMETOOLONG) return fp_errorf(err, errlen, rc, "%s: path too long", dir);
    if (count_matches == 1) {
        if (strlen(by_count) >= path_len) return fp_errorf(err, errlen, -ENAMETOOLONG, "%s: path too long", by_count);
        strcpy(path_out, by_count);
        return 0;
    }
    if (count_matches > 1)
        return fp_errorf(err, errlen, -ENOENT, "%s: %d rigs fit %zu vertices and none has the mesh's checksum %08x: name one with --rig",
                         dir, count_matches, n, crc);
    return fp_errorf(err, errlen, -ENOENT, "%s: no rig fits this mesh (%zu vertices, checksum %08x)", dir, n, crc);
}

/* ---------------------------------------------------------------------------------- */

const char *fp_rig_name(const fp_rig *r) { return r ? r->name : ""; }
const char *fp_rig_source(const fp_rig *r) { return r ? r->source : ""; }
size_t fp_rig_vertex_count(const fp_rig *r) { return r ? r->n : 0; }
const char *fp_rig_mesh_name(const fp_rig *r) { return r ? r->mesh_name : ""; }
uint32_t fp_rig_mesh_crc32(const fp_rig *r) { return r ? r->crc : 0; }
double fp_rig_mm_per_unit(const fp_rig *r) { return r ? r->geom.mm_per_unit : 0; }

void fp_rig_axes(const fp_rig *r, float up[3], float forward[3], float left[3])
{
    for (int i = 0; i < 3; i++) {
        if (up) up[i] = (float)r->geom.up[i];
        if (forward) forward[i] = (float)r->geom.fwd[i];
        if (left) left[i] = (float)r->geom.left[i];
    }
}

const uint8_t *fp_rig_vertex_kinds(const fp_rig *r) { return r ? r->kind : NULL; }
const uint8_t *fp_rig_vertex_regions(const fp_rig *r) { return r ? r->owner : NULL; }
size_t fp_rig_region_count(const fp_rig *r) { return r ? r->region_count : 0; }

int fp_rig_region_get(const fp_rig *r, size_t i, fp_rig_region_desc *out)
{
    if (!r || !out || i >= r->region_count) return -EINVAL;
    out->name = r->regions[i].name;
    out->kind = r->regions[i].kind;
    out->count = r->regions[i].count;
    return 0;
}

size_t fp_rig_landmark_count(const fp_rig *r) { return r ? r->landmark_count : 0; }

int fp_rig_landmark_get(const fp_rig *r, size_t i, const char **name, uint32_t *vertex)
{
    if (!r || i >= r->landmark_count) return -EINVAL;
    if (name) *name = r->landmarks[i].name;
    if (vertex) *vertex = r->landmarks[i].vertex;
    return 0;
}

long fp_rig_landmark_index(const fp_rig *r, const char *name)
{
    for (size_t i = 0; r && name && i < r->landmark_count; i++)
        if (!strcmp(r->landmarks[i].name, name)) return (long)r->landmarks[i].vertex;
    return -ENOENT;
}

size_t fp_rig_channel_count(const fp_rig *r) { return r ? r->channel_count : 0; }

int fp_rig_channel_get(const fp_rig *r, size_t i, fp_rig_channel_desc *out)
{
    if (!r || !out || i >= r->channel_count) return -EINVAL;
    out->name = r->channels[i].name;
    out->min = r->channels[i].min;
    out->max = r->channels[i].max;
    out->neutral = r->channels[i].neutral;
    return 0;
}

long fp_rig_channel_index(const fp_rig *r, const char *name)
{
    for (size_t i = 0; r && name && i < r->channel_count; i++)
        if (!strcmp(r->channels[i].name, name)) return (long)i;
    return -ENOENT;
}

int fp_rig_channel_check(const fp_rig *r, const char *name, double value, char *err, size_t errlen)
{
    long i = fp_rig_channel_index(r, name);
    if (i < 0) return fp_errorf(err, errlen, -ENOENT, "%s: no channel \"%s\"", r ? r->source : "(rig)", name ? name : "");
    const channel *c = &r->channels[i];
    if (!(value >= c->min && value <= c->max))
        return fp_errorf(err, errlen, -ERANGE, "%s: channel %s = %g is outside [%g, %g]", r->source, name, value,
                         c->min, c->max);
    return 0;
}

int fp_rig_channel_values(const fp_rig *r, const char *const *names, const float *vals, size_t n, float *values)
{
    if (!r || !values) return -EINVAL;
    for (size_t i = 0; i < r->channel_count; i++) values[i] = r->channels[i].neutral;
    int unknown = 0;
    for (size_t k = 0; k < n; k++) {
        long i = names && names[k] ? fp_rig_channel_index(r, names[k]) : -1;
        if (i < 0) unknown++;
        else values[i] = vals[k];
    }
    return unknown;
}

void fp_rig_hinge(const fp_rig *r, float right[3], float left[3], double *open_degrees, double glide[2])
{
    for (int i = 0; i < 3; i++) {
        if (right) right[i] = (float)r->geom.hinge_r[i];
        if (left) left[i] = (float)r->geom.hinge_l[i];
    }
    if (open_degrees) *open_degrees = r->open_deg;
    if (glide) glide[0] = r->geom.glide[0], glide[1] = r->geom.glide[1];
}

const float *fp_rig_jaw_weights(const fp_rig *r) { return r ? r->w : NULL; }
const float *fp_rig_mobility(const fp_rig *r) { return r ? r->m : NULL; }

size_t fp_rig_describe(const fp_rig *r, size_t n, const float *pos, char *buf, size_t len)
{
    size_t used = 0;
#define OUT(...)                                                                                   \
    do {                                                                                           \
        int k_ = snprintf(buf && used < len ? buf + used : NULL, buf && used < len ? len - used : 0, \
                          __VA_ARGS__);                                                            \
        if (k_ > 0) used += (size_t)k_;                                                            \
    } while (0)
    if (buf && len) buf[0] = '\0';
    OUT("%s\n  rig        %s (format version %d)\n  mesh       %s, %zu vertices, positions crc32 %08x\n",
        r->source, r->name, FP_RIG_FORMAT_VERSION, r->mesh_name[0] ? r->mesh_name : "(unnamed)", r->n, r->crc);
    OUT("  unit       %g mm per mesh unit\n  axes       up (%g, %g, %g)  forward (%g, %g, %g)  left (%g, %g, %g)\n",
        r->geom.mm_per_unit, r->geom.up[0], r->geom.up[1], r->geom.up[2], r->geom.fwd[0], r->geom.fwd[1], r->geom.fwd[2], r->geom.left[0], r->geom.left[1],
        r->geom.left[2]);
    size_t tot[3] = {0, 0, 0};
    for (size_t v = 0; v < r->n; v++) tot[r->kind[v]]++;
    OUT("  regions    %zu (skull %zu, jaw %zu, soft %zu vertices)\n", r->region_count, tot[1], tot[2], tot[0]);
    for (size_t i = 0; i < r->region_count; i++)
        OUT("    %-22s %-5s %zu\n", r->regions[i].name,
            r->regions[i].kind == FP_RIG_SKULL ? "skull" : r->regions[i].kind == FP_RIG_JAW ? "jaw" : "soft",
            r->regions[i].count);
    OUT("  landmarks  %zu\n", r->landmark_count);
    for (size_t i = 0; i < r->landmark_count; i++) OUT("    %-22s %u\n", r->landmarks[i].name, r->landmarks[i].vertex);
    OUT("  hinge      right (%g, %g, %g)  left (%g, %g, %g), opens %g degrees at jaw.open = 1, glide %g forward %g down\n",
        r->geom.hinge_r[0], r->geom.hinge_r[1], r->geom.hinge_r[2], r->geom.hinge_l[0], r->geom.hinge_l[1], r->geom.hinge_l[2], r->open_deg,
        r->geom.glide[0], r->geom.glide[1]);
    if (r->glide_start > 0)
        OUT("  glide      starts at jaw.open = %g (a pure rotation before), then linear to jaw.open = 1\n",
            r->glide_start);
    OUT("  falloff    lip band %g, cheek band %g from %g inside the corners to %g beyond, inner depth %g, neck band %g,"
        " back band %g; mobility ramp %g\n", r->geom.lip_band, r->geom.cheek_band, r->geom.corner_inset, r->geom.cheek_distance,
        r->geom.inner_depth, r->geom.neck_band, r->geom.back_band, r->geom.ramp);
    if (r->weight_count) OUT("  weights    %zu soft vertices take their jaw weight from the file (jaw.weights), the rest the falloff\n",
                             r->weight_count);
    OUT("  channels   %zu\n", r->channel_count);
    for (size_t i = 0; i < r->channel_count; i++)
        OUT("    %-22s [%g, %g], neutral %g\n", r->channels[i].name, r->channels[i].min, r->channels[i].max,
            r->channels[i].neutral);
    if (pos) {
        if (n != r->n) OUT("  check      DOES NOT FIT: the mesh has %zu vertices\n", n);
        else OUT("  check      fits %zu vertices; checksum %s\n", n,
                 fp_rig_positions_crc32(n, pos) == r->crc ? "matches" : "differs (same topology, another shape)");
    }
#undef OUT
    return used;
}

#ifndef FP_RIG_SOURCE_DIR
#define FP_RIG_SOURCE_DIR "rigs"
#endif

const char *fp_rig_default_dir(const char *exe_dir, char *buf, size_t len)
{
    const char *env = getenv("FACEPUPPET_RIGS");
    if (env && *env) {
        snprintf(buf, len, "%s", env);
        return buf;
    }
    if (exe_dir) {
        snprintf(buf, len, "%s/../share/facepuppet/rigs", exe_dir);
        DIR *d = opendir(buf);
        if (d) {
            closedir(d);
            return buf;
        }
    }
    snprintf(buf, len, "%s", FP_RIG_SOURCE_DIR);
    return buf;
}
