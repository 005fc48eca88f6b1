/* fp_mesh: the C part: allocation, copies, normals, bounds, subdivision, error text. The
 * strict scans of the text formats are mesh_scan_obj.c, mesh_scan_offstl.c and
 * mesh_scan_ply.c; the files themselves go through the C++ of mesh_io.cpp and its
 * neighbours. */
#include "mesh_internal.h"
#include "fp_error.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <assert.h>
#include <string.h>

const char *fp_mesh_strerror(int result) { return fp_strerror(result); }

int fp__mesh_error(char *err, size_t errlen, int code, const char *path, const char *fmt, ...)
{
    if (!err || errlen == 0)
        return code;
    int k = snprintf(err, errlen, "%s: ", path ? path : "(mesh)");
    if (k < 0)
        k = 0;
    if ((size_t)k < errlen) { /* (fp_verrorf: what the message quotes of the file, shown safe) */
        va_list ap;
        va_start(ap, fmt);
        fp_verrorf(err + k, errlen - (size_t)k, code, fmt, ap);
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

int fp_mesh_surface_mask(const fp_mesh *mesh, uint8_t **used, size_t *unused)
{
    *used = NULL;
    *unused = 0;
    size_t n = mesh->vertex_count, none = n;
    if (!mesh->triangle_count) return 0;
    uint8_t *u = calloc(n ? n : 1, 1);
    if (!u) return -ENOMEM;
    for (size_t i = 0; i < 3 * mesh->triangle_count; i++) {
        uint32_t v = mesh->triangles[i];
        assert(v < n);
        none -= !u[v];
        u[v] = 1;
    }
    if (!none) {
        free(u);
        return 0;
    }
    *used = u;
    *unused = none;
    return 0;
}

void fp_mesh_bounds_used(const fp_mesh *mesh, const uint8_t *used, float min[3], float max[3])
{
    if (!used) {
        fp_mesh_bounds(mesh, min, max);
        return;
    }
    bool any = false;
    for (size_t i = 0; i < mesh->vertex_count; i++) {
        if (!used[i]) continue;
        const float *p = mesh->positions + 3 * i;
        for (int k = 0; k < 3; k++) {
            if (!any || p[k] < min[k]) min[k] = p[k];
            if (!any || p[k] > max[k]) max[k] = p[k];
        }
        any = true;
    }
    if (!any)
        for (int k = 0; k < 3; k++) min[k] = max[k] = 0.0f;
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

/* ---- subdivision --------------------------------------------------------------------- */

static int edge_cmp(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

fp_mesh *fp_mesh_subdivide(const fp_mesh *m)
{
    if (!m || (m->vertex_count && !m->positions) || (m->triangle_count && !m->triangles) ||
        m->triangle_count > SIZE_MAX / (3 * sizeof(uint64_t)) / 4)
        return NULL;
    size_t nv = m->vertex_count, nt = m->triangle_count;
    /* each triangle's three edges as keys (smaller vertex << 32 | larger), then the distinct
     * ones sorted: edge i's midpoint is vertex nv + i */
    uint64_t *e = malloc(3 * nt * sizeof *e + 1);
    uint64_t *keys = malloc(3 * nt * sizeof *keys + 1);
    if (!e || !keys) {
        free(e);
        free(keys);
        return NULL;
    }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint64_t a = m->triangles[3 * t + k], b = m->triangles[3 * t + (k + 1) % 3];
            keys[3 * t + k] = a < b ? a << 32 | b : b << 32 | a;
        }
    memcpy(e, keys, 3 * nt * sizeof *e);
    qsort(e, 3 * nt, sizeof *e, edge_cmp);
    size_t ne = 0;
    for (size_t i = 0; i < 3 * nt; i++)
        if (!ne || e[ne - 1] != e[i]) e[ne++] = e[i];
    fp_mesh *o = nv + ne <= UINT32_MAX ? fp_mesh_create(nv + ne, 4 * nt, 0) : NULL;
    if (!o) {
        free(e);
        free(keys);
        return NULL;
    }
    memcpy(o->positions, m->positions, nv * 3 * sizeof(float));
    for (size_t i = 0; i < ne; i++) {
        uint32_t a = (uint32_t)(e[i] >> 32), b = (uint32_t)e[i];
        for (int k = 0; k < 3; k++)
            o->positions[3 * (nv + i) + k] = 0.5f * (m->positions[3 * a + k] + m->positions[3 * b + k]);
    }
    for (size_t t = 0; t < nt; t++) {
        uint32_t v[3], mid[3];
        for (int k = 0; k < 3; k++) {
            v[k] = m->triangles[3 * t + k];
            uint64_t *f = bsearch(&keys[3 * t + k], e, ne, sizeof *e, edge_cmp);
            mid[k] = (uint32_t)(nv + (size_t)(f - e)); /* mid[k]: edge v[k] -> v[k+1] */
        }
        uint32_t tri[4][3] = {{v[0], mid[0], mid[2]}, {v[1], mid[1], mid[0]},
                              {v[2], mid[2], mid[1]}, {mid[0], mid[1], mid[2]}};
        memcpy(o->triangles + 12 * t, tri, sizeof tri);
    }
    free(e);
    free(keys);
    fp_mesh_compute_normals(o);
    return o;
}
