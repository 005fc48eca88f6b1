/*
 * fp_rig_split.c: a rig's own mesh with its vertices split at seams (fp_rig.h,
 * fp_rig_find_split and fp_rig_remap): each vertex of the mesh given found at a vertex of the
 * rig's mesh by its position, bit for bit, and the rig's per-vertex data carried over.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "fp_rig_internal.h"

#include "fp_error.h"
#include "fp_mesh.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

/* A position's key: its three floats' bits (-0 as +0), and the vertex. */
typedef struct pkey {
    uint32_t b[3];
    uint32_t v;
} pkey;

static void key_of(const float *p, uint32_t v, pkey *k)
{
    for (int c = 0; c < 3; c++) {
        float f = p[c] == 0.0f ? 0.0f : p[c];
        memcpy(&k->b[c], &f, 4);
    }
    k->v = v;
}

static int by_bits(const void *a, const void *b)
{
    const pkey *x = a, *y = b;
    for (int c = 0; c < 3; c++)
        if (x->b[c] != y->b[c]) return x->b[c] < y->b[c] ? -1 : 1;
    return x->v < y->v ? -1 : x->v > y->v; /* coincident vertices: the lowest first */
}

int fp_rig_match_positions(size_t rig_n, const float *rig_pos, size_t n, const float *pos,
                           uint32_t *to_rig)
{
    if (!rig_n || !n || rig_n > UINT32_MAX) return -EINVAL;
    pkey *keys = malloc(rig_n * sizeof *keys);
    if (!keys) return -ENOMEM;
    for (size_t i = 0; i < rig_n; i++) key_of(rig_pos + 3 * i, (uint32_t)i, &keys[i]);
    qsort(keys, rig_n, sizeof *keys, by_bits);
    size_t unmatched = 0;
    for (size_t i = 0; i < n; i++) {
        pkey k;
        key_of(pos + 3 * i, 0, &k); /* v 0: the first of coincident rig vertices */
        size_t lo = 0, hi = rig_n;
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if (by_bits(&keys[mid], &k) < 0) lo = mid + 1;
            else hi = mid;
        }
        if (lo < rig_n && !memcmp(keys[lo].b, k.b, sizeof k.b)) to_rig[i] = keys[lo].v;
        else to_rig[i] = UINT32_MAX, unmatched++;
    }
    free(keys);
    return unmatched > (size_t)INT32_MAX ? INT32_MAX : (int)unmatched;
}

int fp_rig_remap(fp_rig *r, size_t n, const uint32_t *to_rig, const float *pos, char *err, size_t errlen)
{ /* (the rig is changed only once nothing can fail) */
    if (!r || !to_rig || !pos || !n || n > UINT32_MAX) return fp_errorf(err, errlen, -EINVAL, "fp_rig_remap: bad argument");
    if (r->w) return fp_errorf(err, errlen, -EINVAL, "%s: fp_rig_remap: the rig is bound already", r->source);
    for (size_t i = 0; i < n; i++)
        if (to_rig[i] >= r->n)
            return fp_errorf(err, errlen, -EINVAL, "%s: vertex %zu has no vertex of the rig's mesh", r->source, i);
    uint8_t *kind = malloc(n), *owner = malloc(n);
    uint32_t *first = malloc(r->n * sizeof *first), *wat = malloc(r->n * sizeof *wat);
    uint32_t *wv = malloc(n * sizeof *wv);
    float *ww = malloc(n * sizeof *ww);
    int rc = 0;
    if (!kind || !owner || !first || !wat || !wv || !ww) {
        rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", r->source);
        goto out;
    }
    for (size_t u = 0; u < r->n; u++) first[u] = wat[u] = UINT32_MAX;
    for (size_t j = 0; j < r->weight_count; j++) wat[r->weight_v[j]] = (uint32_t)j;
    size_t wc = 0, counts[FP_RIG_MAX_REGIONS] = {0};
    for (size_t i = 0; i < n; i++) {
        const uint32_t u = to_rig[i];
        kind[i] = r->kind[u];
        owner[i] = r->owner[u];
        if (owner[i]) counts[owner[i] - 1]++;
        if (first[u] == UINT32_MAX) first[u] = (uint32_t)i;
        if (wat[u] != UINT32_MAX) wv[wc] = (uint32_t)i, ww[wc++] = r->weight_w[wat[u]]; /* ascending in i */
    }
    for (size_t k = 0; k < r->landmark_count; k++) {
        if (first[r->landmarks[k].vertex] == UINT32_MAX) {
            rc = fp_errorf(err, errlen, -EBADMSG, "%s: landmark %s (vertex %u of the rig's mesh) is not "
                           "in this mesh", r->source, r->landmarks[k].name, r->landmarks[k].vertex);
            goto out;
        }
    }
    uint32_t *weld = malloc(n * sizeof *weld);
    if (!weld) {
        rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", r->source);
        goto out;
    }
    for (size_t i = 0; i < n; i++) weld[i] = first[to_rig[i]];
    for (size_t k = 0; k < r->region_count; k++) r->regions[k].count = counts[k];
    free(r->weld);
    r->weld = weld;
    for (size_t k = 0; k < r->landmark_count; k++) r->landmarks[k].vertex = first[r->landmarks[k].vertex];
    free(r->kind), free(r->owner), free(r->weight_v), free(r->weight_w);
    r->kind = kind, r->owner = owner, r->weight_v = wv, r->weight_w = ww;
    kind = owner = NULL, wv = NULL, ww = NULL;
    r->weight_count = wc;
    r->n = n;
    r->crc = fp_rig_positions_crc32(n, pos);
out:
    free(kind), free(owner), free(first), free(wat), free(wv), free(ww);
    return rc;
}

int fp_rig_find_split(const char *dir, const char *data_root, size_t n, const float *pos,
                      char *path_out, size_t path_len, uint32_t **to_rig, char *err, size_t errlen)
{
    *to_rig = NULL;
    if (!dir || !data_root || !pos || !n) return fp_errorf(err, errlen, -EINVAL, "fp_rig_find_split: bad argument");
    char **names;
    long count = fpr_json_names(dir, &names);
    if (count < 0) return fp_errorf(err, errlen, count == -ENOMEM ? -ENOMEM : -ENOENT, "%s: %s", dir, strerror((int)-count));
    uint32_t *map = malloc(n * sizeof *map);
    int rc = map ? -ENOENT : -ENOMEM;
    for (long i = 0; map && rc == -ENOENT && i < count; i++) {
        char path[4096], mesh_path[4096], e2[256];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        fp_rig *r = NULL;
        if (fp_rig_load(path, &r, e2, sizeof e2)) continue; /* (fp_rig_find says why) */
        fp_mesh *m = NULL;
        /* fewer vertices than this mesh: a split copy has more (a rig's mesh with the same
         * count is fp_rig_find's) */
        if (r->mesh_name[0] && r->n < n &&
            snprintf(mesh_path, sizeof mesh_path, "%s/%s", data_root, r->mesh_name) < (int)sizeof mesh_path &&
            fp_mesh_load(mesh_path, &m, NULL, 0) == FP_MESH_OK && m->vertex_count == r->n &&
            fp_rig_checksum_matches(r, m->vertex_count, m->positions)) {
            int left = fp_rig_match_positions(m->vertex_count, m->positions, n, pos, map);
            if (left < 0) rc = left;
            else if (left == 0 && strlen(path) < path_len) strcpy(path_out, path), rc = 0;
        }
        fp_mesh_free(&m);
        fp_rig_free(&r);
    }
    for (long i = 0; i < count; i++) free(names[i]);
    free(names);
    if (rc) {
        free(map);
        return rc == -ENOMEM ? fp_errorf(err, errlen, -ENOMEM, "out of memory")
                             : fp_errorf(err, errlen, -ENOENT, "no rig's mesh holds every vertex of this one");
    }
    *to_rig = map;
    return 0;
}
