/* The surface's far-off vertices: a stray spike's tip (fp_mesh.h, fp_mesh_outlier_mask). */
#include "fp_mesh.h"

#include <errno.h>
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
