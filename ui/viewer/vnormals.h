/* vnormals.h: the viewer's partial normal update (internal to ui/). After the shown shape
 * changed inside some vertex ranges (fp_session_touched), only the vertices of triangles
 * with a changed vertex get new normals (fp_mesh_normals_at: bit for bit what
 * fp_mesh_normals gives), and the ranges to upload cover those vertices, gaps shorter than
 * FP_VNORMALS_GAP vertices bridged (one glBufferSubData per range). */
#ifndef FP_UI_VNORMALS_H
#define FP_UI_VNORMALS_H

#include <stddef.h>
#include <stdint.h>

/* Gaps of fewer vertices between two ranges to upload are uploaded too (12 bytes a vertex
 * per buffer: cheaper than another call). */
#define FP_VNORMALS_GAP 64

typedef struct fp_vnormals {
    const uint32_t *tris;          /* the mesh's triangles (not owned) */
    size_t n, t;
    uint32_t *vt_start, *vt;       /* vertex -> triangles (fp_mesh_vertex_triangles) */
    uint64_t *bits;                /* n bits: vertices whose normals are due (kept clear) */
    uint32_t *verts;               /* those vertices, increasing */
    uint32_t *ranges;              /* (first, count) pairs to upload */
} fp_vnormals;

/** Build the adjacency for t triangles over n vertices (once per mesh). Returns 0,
 *  -EINVAL (an index >= n) or -ENOMEM. */
int fp_vnormals_init(fp_vnormals *vn, const uint32_t *tris, size_t t, size_t n);
void fp_vnormals_free(fp_vnormals *vn);

/** pos (n x 3) changed inside `count` (first, count) vertex ranges since nrm (n x 3) was
 *  right for it: recompute the normals that depend on them. Returns the number of
 *  (first, count) ranges to upload (positions and normals; they cover the changed ranges
 *  and every normal written) in *upload, owned by vn until the next call. */
size_t fp_vnormals_update(fp_vnormals *vn, const float *pos, const uint32_t *ranges, size_t count,
                          float *nrm, const uint32_t **upload);

#endif
