/* The viewer's partial normal update (vnormals.h). */
#include "vnormals.h"

#include "fp_mesh.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

int fp_vnormals_init(fp_vnormals *vn, const uint32_t *tris, size_t t, size_t n)
{
    memset(vn, 0, sizeof *vn);
    int rc = fp_mesh_vertex_triangles(tris, t, n, &vn->vt_start, &vn->vt);
    if (rc) return rc == FP_MESH_ERR_NOMEM ? -ENOMEM : -EINVAL;
    vn->tris = tris;
    vn->n = n;
    vn->t = t;
    vn->bits = calloc((n + 63) / 64 + 1, sizeof *vn->bits);
    vn->verts = malloc((n ? n : 1) * sizeof *vn->verts);
    /* ranges start at least FP_VNORMALS_GAP vertices past the last one's end */
    vn->ranges = malloc((n / FP_VNORMALS_GAP + 2) * 2 * sizeof *vn->ranges);
    if (!vn->bits || !vn->verts || !vn->ranges) {
        fp_vnormals_free(vn);
        return -ENOMEM;
    }
    return 0;
}

void fp_vnormals_free(fp_vnormals *vn)
{
    free(vn->vt_start);
    free(vn->vt);
    free(vn->bits);
    free(vn->verts);
    free(vn->ranges);
    memset(vn, 0, sizeof *vn);
}

size_t fp_vnormals_update(fp_vnormals *vn, const float *pos, const uint32_t *ranges, size_t count,
                          float *nrm, const uint32_t **upload)
{
    *upload = vn->ranges;
    if (!count || !vn->n) return 0;
    /* 1: mark the changed vertices and every vertex of their triangles */
    uint64_t *bits = vn->bits;
    size_t lo = SIZE_MAX, hi = 0;
    for (size_t r = 0; r < count; r++) {
        size_t first = ranges[2 * r], end = first + ranges[2 * r + 1];
        if (end > vn->n) end = vn->n;
        for (size_t v = first; v < end; v++) {
            bits[v >> 6] |= 1ull << (v & 63);
            for (uint32_t k = vn->vt_start[v]; k < vn->vt_start[v + 1]; k++) {
                const uint32_t *tri = vn->tris + 3 * (size_t)vn->vt[k];
                for (int c = 0; c < 3; c++) {
                    size_t w = tri[c] >> 6;
                    bits[w] |= 1ull << (tri[c] & 63);
                    if (w < lo) lo = w;
                    if (w > hi) hi = w;
                }
            }
            if ((v >> 6) < lo) lo = v >> 6;
            if ((v >> 6) > hi) hi = v >> 6;
        }
    }
    if (lo == SIZE_MAX) return 0;
    /* 2: those vertices in order (the bits cleared again), and the ranges to upload */
    size_t nv = 0, nr = 0;
    for (size_t w = lo; w <= hi; w++) {
        uint64_t b = bits[w];
        bits[w] = 0;
        while (b) {
            uint32_t v = (uint32_t)(w * 64 + (size_t)__builtin_ctzll(b));
            b &= b - 1;
            vn->verts[nv++] = v;
            if (nr && v - (vn->ranges[2 * nr - 2] + vn->ranges[2 * nr - 1]) < FP_VNORMALS_GAP) {
                vn->ranges[2 * nr - 1] = v + 1 - vn->ranges[2 * nr - 2];
            } else {
                vn->ranges[2 * nr] = v;
                vn->ranges[2 * nr + 1] = 1;
                nr++;
            }
        }
    }
    /* 3: their normals */
    fp_mesh_normals_at(vn->tris, vn->vt_start, vn->vt, pos, vn->verts, nv, nrm);
    return nr;
}
