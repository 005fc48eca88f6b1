/* fp_rig: binding a rig to a mesh, finding a mesh's rig, lookups and the description
 * (fp_rig.h); reading the files is fp_rig_parse.c, the placement on a moved copy
 * fp_rig_place.c, the pose, the mobility blend and the finger limit fp_rig_pose.c. */
#define _GNU_SOURCE
#include "fp_rig_internal.h"

#include "fp_error.h"
#include "fp_vec.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

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

/* fpr_nearest_rigid with the grid's keys: each rigid vertex's cell (of ramp-sized cells over
 * the mesh's box lo, sides csz, dims cells a side) and its index */
static int fpr_nearest_rigid_keyed(const fp_rig *r, size_t n, const float *pos, const double *lo,
                                   const double *csz, const long *dims, uint64_t *key, uint32_t *near,
                                   double *best2)
{
#define CELL(v, i) ((long)fmin((double)(dims[i] - 1), floor((pos[3 * (v) + (i)] - lo[i]) / csz[i])))
    for (size_t v = 0; v < n; v++)
        key[v] = r->kind[v] == FP_RIG_SOFT ? UINT64_MAX
                 : (uint64_t)((CELL(v, 0) * dims[1] + CELL(v, 1)) * dims[2] + CELL(v, 2)) << 32 | v;
#undef CELL
    return fpr_nearest_rigid(r->kind, n, pos, key, r->geom.ramp * r->geom.ramp, near, best2);
}

int fp_rig_bind(fp_rig *r, size_t n, const float *pos, char *err, size_t errlen)
{
    if (!r || !pos) return fp_errorf(err, errlen, -EINVAL, "fp_rig_bind: NULL argument");
    fpr_ctx c = {r->source, err, errlen};
    if (n != r->n) return fpr_bad(&c, "mesh.vertex_count", "the rig fits %zu vertices, the mesh has %zu", r->n, n);
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
                return fpr_bad(&c, hn[s], "(%g, %g, %g) lies outside the mesh's bounds: the hinge must be inside the head",
                           hp[s][0], hp[s][1], hp[s][2]);
        double best = INFINITY;
        for (size_t v = 0; v < n; v++) {
            double d0 = pos[3 * v] - hp[s][0], d1 = pos[3 * v + 1] - hp[s][1], d2 = pos[3 * v + 2] - hp[s][2];
            best = fmin(best, d0 * d0 + d1 * d1 + d2 * d2);
        }
        if (sqrt(best) > reach)
            return fpr_bad(&c, hn[s], "no vertex within 60 mm (nearest %.4g mm): not near the head",
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
    /* mobility: smoothstep of the distance to the nearest rigid vertex (within the ramp: beyond
     * it m is 1). Ties go to the vertex first in the order of the grid of ramp-sized cells this
     * search once scanned (its cell's index, then its own): the key, so that the result is the
     * same as that grid's, bit for bit (fp_rig_near.c) */
    double cell = r->geom.ramp;
    long dims[3];
    for (int i = 0; i < 3; i++) {
        double d = floor((hi[i] - lo[i]) / cell) + 1;
        dims[i] = d > 256 ? 256 : (long)d;
    }
    double csz[3];
    for (int i = 0; i < 3; i++) csz[i] = fmax((hi[i] - lo[i]) / (double)dims[i], cell);
    for (int i = 0; i < 3; i++) dims[i] = (long)floor((hi[i] - lo[i]) / csz[i]) + 1;
    uint64_t *key = malloc(n * sizeof *key);
    uint32_t *near = malloc(n * sizeof *near);
    double *best2 = malloc(n * sizeof *best2);
    if (!key || !near || !best2 || fpr_nearest_rigid_keyed(r, n, pos, lo, csz, dims, key, near, best2)) {
        free(w), free(m), free(g), free(slope_v), free(slope_dir), free(key), free(near), free(best2);
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", r->source);
    }
    for (size_t v = 0; v < n; v++) {
        if (r->kind[v] != FP_RIG_SOFT) {
            m[v] = 0;
            continue;
        }
        double best = best2[v];
        size_t bu = near[v];
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
    free(key), free(near), free(best2);
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
    free((*rig)->weld);
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

long fpr_json_names(const char *dir, char ***names)
{
    *names = NULL;
    DIR *d = opendir(dir);
    if (!d) return -errno;
    size_t count = 0, cap = 0;
    long rc = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        size_t l = strlen(e->d_name);
        if (l <= 5 || strcmp(e->d_name + l - 5, ".json")) continue;
        if (count == cap) {
            size_t nc = cap ? 2 * cap : 64;
            char **g = realloc(*names, nc * sizeof *g);
            if (!g) { rc = -ENOMEM; break; }
            *names = g, cap = nc;
        }
        if (!((*names)[count] = strdup(e->d_name))) { rc = -ENOMEM; break; }
        count++;
    }
    closedir(d);
    if (rc) {
        for (size_t i = 0; i < count; i++) free((*names)[i]);
        free(*names);
        *names = NULL;
        return rc;
    }
    if (count) qsort(*names, count, sizeof **names, by_name);
    return (long)count;
}

int fp_rig_find(const char *dir, size_t n, const float *pos, char *path_out, size_t path_len, char *err,
                size_t errlen)
{
    if (!dir || !pos || !path_out || !path_len) return fp_errorf(err, errlen, -EINVAL, "fp_rig_find: NULL argument");
    char **names;
    long count = fpr_json_names(dir, &names);
    if (count == -ENOMEM) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", dir);
    if (count < 0) return fp_errorf(err, errlen, -ENOENT, "%s: %s", dir, strerror((int)-count));
    uint32_t crc = fp_rig_positions_crc32(n, pos);
    char by_count[4096] = "", by_crc[4096] = "", twin[4096] = "";
    int count_matches = 0, unread = 0;
    char first_unread[300] = ""; /* the first file that did not parse: why (said when none fits) */
    for (long i = 0; i < count; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        fp_rig *r = NULL;
        char e2[256];
        if (fp_rig_load(path, &r, e2, sizeof e2) == 0) {
            if (r->n == n && r->crc == crc) { /* the first by name; a second one is said */
                if (!by_crc[0]) snprintf(by_crc, sizeof by_crc, "%s", path);
                else if (!twin[0]) snprintf(twin, sizeof twin, "%s", path);
            } else if (r->n == n) {
                count_matches++;
                snprintf(by_count, sizeof by_count, "%s", path);
            }
            fp_rig_free(&r);
        } else if (!unread++) {
            snprintf(first_unread, sizeof first_unread, "%s", e2);
        }
    }
    for (long i = 0; i < count; i++) free(names[i]);
    free(names);
    if (twin[0]) /* (which one a run took hung on the files' names) */
        return fp_errorf(err, errlen, -EEXIST, "%s and %s both fit this mesh (%zu vertices, checksum %08x): "
                         "name one with --rig, or remove the other", by_crc, twin, n, crc);
    const char *found = by_crc[0] ? by_crc : count_matches == 1 ? by_count : NULL;
    if (found) {
        if (strlen(found) >= path_len) return fp_errorf(err, errlen, -ENAMETOOLONG, "%s: path too long", found);
        strcpy(path_out, found);
        return 0;
    }
    char why[400] = ""; /* (an artist's own rig with an error was skipped without a word) */
    if (unread)
        snprintf(why, sizeof why, "; %d file%s not read as a rig, the first: %s", unread, unread > 1 ? "s" : "",
                 first_unread);
    if (count_matches > 1)
        return fp_errorf(err, errlen, -ENOENT, "%s: %d rigs fit %zu vertices and none has the mesh's checksum %08x: name one with --rig%s",
                         dir, count_matches, n, crc, why);
    return fp_errorf(err, errlen, -ENOENT, "%s: no rig fits this mesh (%zu vertices, checksum %08x)%s", dir, n, crc, why);
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
    size_t k = r && name ? fpr_landmark_at(r, name) : 0;
    return r && name && k < r->landmark_count ? (long)r->landmarks[k].vertex : -ENOENT;
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
    /* compared as the float the channel keeps: the file's max 0.7 is 0.69999999f, and the
     * value 0.7 a user types (a double) was refused as outside [-0.3, 0.7] */
    float v = (float)value;
    if (!(v >= c->min && v <= c->max))
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
