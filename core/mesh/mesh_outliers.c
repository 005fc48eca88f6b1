/* The face's vertices (fp_mesh.h): the surface's far-off ones, a stray spike's tip
 * (fp_mesh_outlier_mask), the face's mask (fp_mesh_face_mask: in a triangle and not far off)
 * and the face's typical edge length (fp_mesh_median_edge). */
#include "fp_mesh.h"

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* The value of 0-based rank r among a[0 .. m-1] (reorders a): Hoare's partition with the
 * middle element as pivot (its j lies in [lo, hi - 1]), kept to the side that holds r. */
static float select_rank(float *a, size_t m, size_t r)
{
    ptrdiff_t lo = 0, hi = (ptrdiff_t)m - 1, k = (ptrdiff_t)r;
    while (lo < hi) {
        const float pivot = a[lo + (hi - lo) / 2];
        ptrdiff_t i = lo - 1, j = hi + 1;
        for (;;) {
            do i++; while (a[i] < pivot);
            do j--; while (a[j] > pivot);
            if (i >= j) break;
            float t = a[i];
            a[i] = a[j], a[j] = t;
        }
        if (k <= j) hi = j;
        else lo = j + 1;
    }
    return a[k];
}

int fp_mesh_outlier_mask(const fp_mesh *mesh, uint8_t **used, size_t *outliers)
{
    *outliers = 0;
    size_t n = mesh->vertex_count, m = 0;
    for (size_t v = 0; v < n; v++) m += !*used || (*used)[v];
    if (m < 4) return 0;
    float *a = malloc(m * sizeof *a), lo[3], hi[3];
    if (!a) return -ENOMEM;
    const size_t r_lo = (size_t)(0.005 * (double)(m - 1) + 0.5), r_hi = (size_t)(0.995 * (double)(m - 1) + 0.5);
    for (int k = 0; k < 3; k++) {
        size_t i = 0;
        for (size_t v = 0; v < n; v++)
            if (!*used || (*used)[v]) a[i++] = mesh->positions[3 * v + k];
        float p_lo = select_rank(a, m, r_lo), p_hi = select_rank(a, m, r_hi);
        double e = (double)p_hi - p_lo;
        lo[k] = (float)(p_lo - FP_MESH_OUTLIER_SPAN * e);
        hi[k] = (float)(p_hi + FP_MESH_OUTLIER_SPAN * e);
    }
    free(a);
    size_t far = 0;
    for (size_t v = 0; v < n; v++) {
        if (*used && !(*used)[v]) continue;
        const float *p = mesh->positions + 3 * v;
        for (int k = 0; k < 3; k++)
            if (p[k] < lo[k] || p[k] > hi[k]) {
                far++;
                break;
            }
    }
    if (!far) return 0;
    if (!*used) {
        if (!(*used = malloc(n))) return -ENOMEM;
        memset(*used, 1, n);
    }
    for (size_t v = 0; v < n; v++) {
        const float *p = mesh->positions + 3 * v;
        for (int k = 0; k < 3 && (*used)[v]; k++)
            if (p[k] < lo[k] || p[k] > hi[k]) (*used)[v] = 0;
    }
    *outliers = far;
    return 0;
}

int fp_mesh_face_mask(const fp_mesh *mesh, uint8_t **used, size_t *unused, size_t *outliers)
{
    *outliers = 0;
    if (fp_mesh_surface_mask(mesh, used, unused)) return -ENOMEM;
    if (fp_mesh_outlier_mask(mesh, used, outliers)) {
        free(*used);
        *used = NULL;
        *unused = 0;
        return -ENOMEM;
    }
    return 0;
}

/* at most this many triangles' edges are measured, at an even stride */
#define MEDIAN_EDGE_TRIANGLES 65536

int fp_mesh_median_edge(const fp_mesh *mesh, const uint8_t *used, double *median)
{
    *median = 0;
    const size_t t = mesh->triangle_count;
    const size_t stride = t > MEDIAN_EDGE_TRIANGLES ? (t + MEDIAN_EDGE_TRIANGLES - 1) / MEDIAN_EDGE_TRIANGLES : 1;
    float *len = malloc(3 * (t / stride + 1) * sizeof *len);
    if (!len) return -ENOMEM;
    size_t m = 0;
    for (size_t i = 0; i < t; i += stride) {
        const uint32_t *c = mesh->triangles + 3 * i;
        if (used && (!used[c[0]] || !used[c[1]] || !used[c[2]])) continue;
        for (int k = 0; k < 3; k++) {
            const float *a = mesh->positions + 3 * c[k], *b = mesh->positions + 3 * c[(k + 1) % 3];
            const double dx = (double)a[0] - b[0], dy = (double)a[1] - b[1], dz = (double)a[2] - b[2];
            len[m++] = (float)sqrt(dx * dx + dy * dy + dz * dz);
        }
    }
    if (m) *median = select_rank(len, m, m / 2);
    free(len);
    return 0;
}
