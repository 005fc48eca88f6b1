/*
 * bench_rig.c: the frame case's subdivided faces with the ICT face's rig carried through each
 * midpoint subdivision (fp_bench.h, fp_bench_rig_*), so that the 105k to 1.7M vertex faces
 * are performed as the ICT face is: skull, teeth and eyeballs still, the jaw on its hinge.
 *
 * The rule, per level (fp_mesh_subdivide's layout: the input's vertices first, then one
 * midpoint per edge): a midpoint belongs to a region when both ends of its edge do (else to
 * none: soft); it takes a jaw weight from jaw.weights when both ends have one (their mean;
 * else the rig's falloff gives it one at bind); the landmarks, hinge and falloff keep their
 * vertices and coordinates (the input's vertices keep their positions); mesh.vertex_count and
 * mesh.positions_crc32 are the subdivided mesh's. The rig is rewritten as JSON (cJSON) and
 * written to a temporary file the session loads like any rig file. Bench-only: no product
 * path loads a rig this way.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "fp_bench.h"

#include "fp_error.h"
#include "fp_file.h"
#include "fp_mesh.h"
#include "fp_rig.h"

#include <cJSON.h>

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct fp_bench_rig {
    cJSON *root;
    size_t n; /* the vertex count it is for */
};

int fp_bench_rig_open(const char *path, fp_bench_rig **out, char *err, size_t errlen)
{
    *out = NULL;
    char *text;
    size_t len;
    int rc = fp_file_read_all(path, (size_t)1 << 30, &text, &len);
    if (rc) return fp_errorf(err, errlen, rc, "%s: %s", path, fp_file_error_text(rc));
    cJSON *root = cJSON_ParseWithLength(text, len);
    free(text);
    const cJSON *vc = root ? cJSON_GetObjectItem(cJSON_GetObjectItem(root, "mesh"), "vertex_count") : NULL;
    if (!cJSON_IsNumber(vc)) {
        cJSON_Delete(root);
        return fp_errorf(err, errlen, -EBADMSG, "%s: not a rig with mesh.vertex_count", path);
    }
    fp_bench_rig *r = malloc(sizeof *r);
    if (!r) {
        cJSON_Delete(root);
        return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    }
    r->root = root;
    r->n = (size_t)vc->valuedouble;
    *out = r;
    return 0;
}

void fp_bench_rig_free(fp_bench_rig **r)
{
    if (!r || !*r) return;
    cJSON_Delete((*r)->root);
    free(*r);
    *r = NULL;
}

/* a vertex list (indices and [first, last] ranges, ascending) into mark[v] = val; -1 when
 * it is not one */
static int list_mark(const cJSON *list, size_t n, uint8_t *mark, uint8_t val)
{
    double last = -1;
    for (const cJSON *e = list ? list->child : NULL; e; e = e->next) {
        double a, b;
        if (cJSON_IsNumber(e)) a = b = e->valuedouble;
        else if (cJSON_IsArray(e) && cJSON_GetArraySize(e) == 2)
            a = cJSON_GetArrayItem(e, 0)->valuedouble, b = cJSON_GetArrayItem(e, 1)->valuedouble;
        else return -1;
        if (!(a > last && a <= b && b < (double)n)) return -1;
        last = b;
        for (size_t v = (size_t)a; v <= (size_t)b; v++) mark[v] = val;
    }
    return 0;
}

/* the vertices v with mark[v] == val as a list of indices and [first, last] ranges */
static cJSON *list_of(const uint8_t *mark, size_t n, uint8_t val)
{
    cJSON *a = cJSON_CreateArray();
    for (size_t v = 0; a && v < n;) {
        if (mark[v] != val) {
            v++;
            continue;
        }
        size_t w = v;
        while (w + 1 < n && mark[w + 1] == val) w++;
        cJSON *e = v == w ? cJSON_CreateNumber((double)v) : cJSON_CreateArray();
        if (e && v != w) {
            cJSON_AddItemToArray(e, cJSON_CreateNumber((double)v));
            cJSON_AddItemToArray(e, cJSON_CreateNumber((double)w));
        }
        if (!e) {
            cJSON_Delete(a);
            return NULL;
        }
        cJSON_AddItemToArray(a, e);
        v = w + 1;
    }
    return a;
}

/* fine's midpoints' edge ends (ends[2 (m - n0)], from its triangles 4t and 4t + 1, the
 * layout fp_mesh_subdivide documents) */
static int midpoint_ends(const fp_mesh *coarse, const fp_mesh *fine, uint32_t *ends)
{
    size_t n0 = coarse->vertex_count;
    for (size_t t = 0; t < coarse->triangle_count; t++) {
        const uint32_t *v = coarse->triangles + 3 * t, *f0 = fine->triangles + 12 * t, *f1 = f0 + 3;
        if (f0[0] != v[0] || f1[0] != v[1]) return -1;
        const uint32_t mid[3] = {f0[1], f1[1], f0[2]}; /* edges v0v1, v1v2, v2v0 */
        for (int k = 0; k < 3; k++) {
            if (mid[k] < n0 || mid[k] >= fine->vertex_count) return -1;
            ends[2 * (mid[k] - n0)] = v[k];
            ends[2 * (mid[k] - n0) + 1] = v[(k + 1) % 3];
        }
    }
    return 0;
}

int fp_bench_rig_subdivide(fp_bench_rig *r, const fp_mesh *coarse, const fp_mesh *fine, char *err,
                           size_t errlen)
{
    size_t n0 = coarse->vertex_count, n1 = fine->vertex_count;
    if (r->n != n0 || n1 < n0 || fine->triangle_count != 4 * coarse->triangle_count)
        return fp_errorf(err, errlen, -EINVAL, "the rig (%zu vertices) is not for this mesh (%zu)", r->n, n0);
    uint32_t *ends = malloc((n1 - n0) * 2 * sizeof *ends + 1);
    uint8_t *owner = calloc(n1, 1), *listed = calloc(n1, 1);
    float *w = malloc(n1 * sizeof *w + 1);
    int rc = ends && owner && listed && w ? 0 : -ENOMEM;
    if (!rc && midpoint_ends(coarse, fine, ends)) rc = -EINVAL;
    /* regions: owner[v] = region index + 1 */
    cJSON *regions = cJSON_GetObjectItem(r->root, "regions");
    int k = 0;
    for (cJSON *g = regions ? regions->child : NULL; g && !rc; g = g->next, k++)
        if (k > 250 || list_mark(cJSON_GetObjectItem(g, "vertices"), n0, owner, (uint8_t)(k + 1))) rc = -EBADMSG;
    /* jaw weights, in the order listed */
    cJSON *jw = cJSON_GetObjectItem(cJSON_GetObjectItem(r->root, "jaw"), "weights");
    cJSON *vals = jw ? cJSON_GetObjectItem(jw, "values") : NULL;
    if (!rc && jw) {
        if (list_mark(cJSON_GetObjectItem(jw, "vertices"), n0, listed, 1)) rc = -EBADMSG;
        const cJSON *x = vals ? vals->child : NULL;
        for (size_t v = 0; v < n0 && !rc; v++)
            if (listed[v]) { /* (the listed vertices ascending: the values in that order) */
                if (!cJSON_IsNumber(x)) rc = -EBADMSG;
                else w[v] = (float)x->valuedouble, x = x->next;
            }
    }
    if (rc) {
        free(ends), free(owner), free(listed), free(w);
        return fp_errorf(err, errlen, rc, "the rig's regions or jaw weights could not be carried (%s)",
                         rc == -ENOMEM ? "out of memory" : "malformed, or not this mesh's subdivision");
    }
    for (size_t m = n0; m < n1; m++) {
        uint32_t a = ends[2 * (m - n0)], b = ends[2 * (m - n0) + 1];
        owner[m] = owner[a] == owner[b] ? owner[a] : 0;
        listed[m] = listed[a] && listed[b];
        if (listed[m]) w[m] = 0.5f * (w[a] + w[b]);
    }
    k = 0;
    for (cJSON *g = regions ? regions->child : NULL; g && !rc; g = g->next, k++) {
        cJSON *list = list_of(owner, n1, (uint8_t)(k + 1));
        if (!list || !cJSON_ReplaceItemInObject(g, "vertices", list)) rc = -ENOMEM;
    }
    if (!rc && jw) {
        cJSON *list = list_of(listed, n1, 1), *nv = cJSON_CreateArray();
        for (size_t v = 0; nv && v < n1; v++)
            if (listed[v]) cJSON_AddItemToArray(nv, cJSON_CreateNumber(w[v]));
        if (!list || !nv || !cJSON_ReplaceItemInObject(jw, "vertices", list) ||
            !cJSON_ReplaceItemInObject(jw, "values", nv))
            rc = -ENOMEM;
    }
    cJSON *mesh = cJSON_GetObjectItem(r->root, "mesh");
    char crc[16];
    snprintf(crc, sizeof crc, "%08x", fp_rig_positions_crc32(n1, fine->positions));
    if (!rc && (!cJSON_ReplaceItemInObject(mesh, "vertex_count", cJSON_CreateNumber((double)n1)) ||
                !cJSON_ReplaceItemInObject(mesh, "positions_crc32", cJSON_CreateString(crc))))
        rc = -ENOMEM;
    free(ends), free(owner), free(listed), free(w);
    if (rc) return fp_errorf(err, errlen, rc, "out of memory carrying the rig");
    r->n = n1;
    return 0;
}

int fp_bench_rig_write(const fp_bench_rig *r, char *path, size_t n, char *err, size_t errlen)
{
    snprintf(path, n, "%s/facepuppet-bench-rig-XXXXXX.json", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    int fd = mkstemps(path, 5);
    if (fd < 0) return fp_errorf(err, errlen, -errno, "%s: cannot create", path);
    char *text = cJSON_PrintUnformatted(r->root);
    size_t len = text ? strlen(text) : 0, done = 0;
    while (text && done < len) {
        ssize_t k = write(fd, text + done, len - done);
        if (k <= 0) break;
        done += (size_t)k;
    }
    free(text);
    if (close(fd) || !len || done < len) {
        unlink(path);
        return fp_errorf(err, errlen, -EIO, "%s: cannot write the subdivided rig", path);
    }
    return 0;
}
