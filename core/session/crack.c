/* crack.c: cracked seams kept closed (crack.h). */
#include "crack.h"
#include "weld.h"

#include "fp_contact.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

/* ---- building ---------------------------------------------------------------------------- */

static int by_crack(const void *a, const void *b)
{
    const uint32_t *p = a, *q = b; /* (lower weld, higher weld) */
    if (p[0] != q[0]) return (p[0] > q[0]) - (p[0] < q[0]);
    return (p[1] > q[1]) - (p[1] < q[1]);
}

static int by_u32(const void *a, const void *b)
{
    uint32_t p = *(const uint32_t *)a, q = *(const uint32_t *)b;
    return (p > q) - (p < q);
}

/* (a, b) onto the growing list *l of *len pairs */
static int push_pair(uint32_t **l, size_t *len, size_t *cap, uint32_t a, uint32_t b)
{
    if (*len == *cap) {
        size_t c = 2 * *cap + 64;
        uint32_t *g = realloc(*l, 2 * c * sizeof *g);
        if (!g) return -ENOMEM;
        *l = g, *cap = c;
    }
    (*l)[2 * *len] = a, (*l)[2 * *len + 1] = b;
    ++*len;
    return 0;
}

/* the welds (weld.h) and the cracks between them:
 * (lower weld, higher weld) pairs into *cr (2 x *ncr). 0 or -ENOMEM */
static int find_cracks(const float *pos, size_t n, uint32_t *weld, uint32_t **cr, size_t *ncr)
{
    fp_at_pos *ix = NULL;
    if (fp_weld_by_position(pos, n, weld, &ix)) return -ENOMEM;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < n; v++)
        for (int k = 0; k < 3; k++) lo[k] = fminf(lo[k], pos[3 * v + k]), hi[k] = fmaxf(hi[k], pos[3 * v + k]);
    double diag = 0;
    for (int k = 0; k < 3; k++) diag += ((double)hi[k] - lo[k]) * ((double)hi[k] - lo[k]);
    const double tol = FP_CRACK_TOL * sqrt(diag);
    size_t len = 0, cap = 0;
    uint32_t *out = NULL;
    /* ix is sorted by x first: the vertices within tol in x of ix[i] follow it */
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n && (double)ix[j].p[0] - ix[i].p[0] <= tol; j++) {
            uint32_t a = weld[ix[i].v], b = weld[ix[j].v];
            if (a == b) continue;
            double d2 = 0;
            for (int k = 0; k < 3; k++) {
                double e = (double)ix[i].p[k] - ix[j].p[k];
                d2 += e * e;
            }
            if (!(d2 <= tol * tol)) continue;
            if (push_pair(&out, &len, &cap, a < b ? a : b, a < b ? b : a)) return free(ix), free(out), -ENOMEM;
        }
    free(ix);
    /* once each (a weld of several vertices met the other side as often) */
    if (len) qsort(out, len, 2 * sizeof *out, by_crack);
    size_t m = 0;
    for (size_t i = 0; i < len; i++)
        if (!m || by_crack(out + 2 * i, out + 2 * (m - 1)))
            out[2 * m] = out[2 * i], out[2 * m + 1] = out[2 * i + 1], m++;
    *cr = out;
    *ncr = m;
    return 0;
}

/* the triangles around each weld: CSR start (n + 1), list; 0 or -ENOMEM */
static int fans(const uint32_t *weld, size_t n, const uint32_t *tris, size_t t, uint32_t **start, uint32_t **list)
{
    uint32_t *s = calloc(n + 1, sizeof *s), *l = malloc((t ? 3 * t : 1) * sizeof *l);
    if (!s || !l) return free(s), free(l), -ENOMEM;
    for (size_t f = 0; f < 3 * t; f++) s[weld[tris[f]] + 1]++;
    for (size_t v = 0; v < n; v++) s[v + 1] += s[v];
    for (size_t f = 0; f < 3 * t; f++) l[s[weld[tris[f]]]++] = (uint32_t)(f / 3);
    for (size_t v = n; v > 0; v--) s[v] = s[v - 1];
    s[0] = 0;
    *start = s, *list = l;
    return 0;
}

static bool share_weld(const uint32_t *weld, const uint32_t *a, const uint32_t *b)
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (weld[a[i]] == weld[b[j]]) return true;
    return false;
}

/* the groups: every vertex at a crack's position, one group per weld on either side of a
 * crack (key: the weld's first vertex, sorted); *key owned by the caller. 0 or -ENOMEM */
static int groups(fp_crack *k, const uint32_t *weld, size_t n, const uint32_t *cr, size_t ncr, uint32_t **keyp)
{
    uint32_t *key = malloc(2 * ncr * sizeof *key);
    if (!key) return -ENOMEM;
    memcpy(key, cr, 2 * ncr * sizeof *key);
    qsort(key, 2 * ncr, sizeof *key, by_u32);
    size_t u = 0;
    for (size_t i = 0; i < 2 * ncr; i++)
        if (!u || key[i] != key[u - 1]) key[u++] = key[i];
    *keyp = key;
    k->ngroups = u;
    if (!(k->group_start = calloc(u + 1, sizeof *k->group_start))) return -ENOMEM;
    size_t total = 0;
    for (size_t v = 0; v < n; v++) {
        uint32_t *g = bsearch(&weld[v], key, u, sizeof *key, by_u32);
        if (g) k->group_start[g - key + 1]++, total++;
    }
    for (size_t i = 0; i < u; i++) k->group_start[i + 1] += k->group_start[i];
    uint32_t *fill = calloc(u, sizeof *fill);
    if (!fill || !(k->group = malloc(total * sizeof *k->group))) return free(fill), -ENOMEM;
    for (size_t v = 0; v < n; v++) {
        uint32_t *g = bsearch(&weld[v], key, u, sizeof *key, by_u32);
        if (g) k->group[k->group_start[g - key] + fill[g - key]++] = (uint32_t)v;
    }
    free(fill);
    return 0;
}

int fp_crack_build(const float *pos, size_t n, const uint32_t *tris, size_t t, fp_crack *k)
{
    memset(k, 0, sizeof *k);
    if (!n || !t) return 0;
    uint32_t *weld = malloc(n * sizeof *weld), *cr = NULL, *fs = NULL, *fl = NULL, *key = NULL;
    size_t ncr = 0, cap = 0;
    int rc = -ENOMEM;
    if (!weld || find_cracks(pos, n, weld, &cr, &ncr)) goto out;
    if (!ncr) { rc = 0; goto out; }
    if (fans(weld, n, tris, t, &fs, &fl) || groups(k, weld, n, cr, ncr, &key)) goto out;
    if (!(k->side = malloc(ncr * sizeof *k->side)) || !(k->first = malloc((ncr + 1) * sizeof *k->first)))
        goto out;
    /* per crack, every pair of triangles, one around each side, that share no position */
    k->ncracks = ncr;
    for (size_t c = 0; c < ncr; c++) {
        uint32_t a = cr[2 * c], b = cr[2 * c + 1];
        k->side[c][0] = (uint32_t)((const uint32_t *)bsearch(&a, key, k->ngroups, sizeof *key, by_u32) - key);
        k->side[c][1] = (uint32_t)((const uint32_t *)bsearch(&b, key, k->ngroups, sizeof *key, by_u32) - key);
        k->first[c] = (uint32_t)k->npairs;
        for (uint32_t i = fs[a]; i < fs[a + 1]; i++)
            for (uint32_t j = fs[b]; j < fs[b + 1]; j++) {
                uint32_t t1 = fl[i], t2 = fl[j];
                if (t1 == t2 || share_weld(weld, tris + 3 * (size_t)t1, tris + 3 * (size_t)t2)) continue;
                if (k->npairs == cap) {
                    size_t c2 = 2 * cap + 64;
                    void *p2 = realloc(k->pair, c2 * sizeof *k->pair), *c3 = p2 ? realloc(k->corner, c2 * sizeof *k->corner) : NULL;
                    if (p2) k->pair = p2;
                    if (!c3) goto out;
                    k->corner = c3, cap = c2;
                }
                k->pair[k->npairs][0] = t1, k->pair[k->npairs][1] = t2;
                for (int q = 0; q < 6; q++) {
                    uint32_t w = weld[tris[3 * (size_t)(q < 3 ? t1 : t2) + q % 3]];
                    const uint32_t *g = bsearch(&w, key, k->ngroups, sizeof *key, by_u32);
                    k->corner[k->npairs][q] = g ? (uint32_t)(g - key) : FP_CRACK_NONE;
                }
                k->npairs++;
            }
    }
    k->first[ncr] = (uint32_t)k->npairs;
    rc = 0;
out:
    if (rc) fp_crack_free(k);
    free(weld), free(cr), free(fs), free(fl), free(key);
    return rc;
}

void fp_crack_free(fp_crack *k)
{
    free(k->side), free(k->first), free(k->pair), free(k->corner), free(k->group_start), free(k->group);
    memset(k, 0, sizeof *k);
}

/* ---- applying ------------------------------------------------------------------------------ */

static void tri_load(const float *x, const uint32_t *f, double t[3][3])
{
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) t[i][k] = x[3 * (size_t)f[i] + k];
}

/* the unit normal of triangle f in x (0 for a degenerate one) */
static void unit_normal(const float *x, const uint32_t *f, double n[3])
{
    double t[3][3], u[3], w[3];
    tri_load(x, f, t);
    for (int k = 0; k < 3; k++) u[k] = t[1][k] - t[0][k], w[k] = t[2][k] - t[0][k];
    n[0] = u[1] * w[2] - u[2] * w[1], n[1] = u[2] * w[0] - u[0] * w[2], n[2] = u[0] * w[1] - u[1] * w[0];
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; k++) n[k] = l > 0 ? n[k] / l : 0;
}

static bool cross_in(const float *x, const uint32_t *f1, const uint32_t *f2)
{
    double a[3][3], b[3][3];
    tri_load(x, f1, a);
    tri_load(x, f2, b);
    return fp_contact_tri_tri(a, b) != 0;
}

#define FP_CRACK_GROUP_MAX 16 /* vertices at one position moved, at most */

/* Moves group gi (the vertices at one crack corner's position, c its first) back across
 * triangle p's plane, to c's side of it in ref, until the pair (f1, f2) no longer crosses in
 * x; false, x as it was, when no try parts it */
static bool nudge(const fp_crack *k, const uint32_t *tris, const float *ref, float *x, uint32_t p, uint32_t gi,
                  const uint32_t *f1, const uint32_t *f2)
{
    const uint32_t *fp = tris + 3 * (size_t)p, *g = k->group + k->group_start[gi];
    const size_t ng = k->group_start[gi + 1] - k->group_start[gi];
    assert(ng > 0);
    if (ng > FP_CRACK_GROUP_MAX) return false;
    double nr[3], n[3], side = 0;
    unit_normal(ref, fp, nr);
    unit_normal(x, fp, n);
    for (int i = 0; i < 3; i++) side += ((double)ref[3 * (size_t)g[0] + i] - ref[3 * (size_t)fp[0] + i]) * nr[i];
    if (side == 0 || (n[0] == 0 && n[1] == 0 && n[2] == 0)) return false;
    float was[FP_CRACK_GROUP_MAX][3];
    float big = 0;
    for (size_t i = 0; i < ng; i++)
        for (int j = 0; j < 3; j++) {
            was[i][j] = x[3 * (size_t)g[i] + j];
            big = fmaxf(big, fabsf(was[i][j]));
        }
    const double ulp = (double)nextafterf(big, INFINITY) - big, s = side > 0 ? 1 : -1;
    double step = ulp;
    for (int tr = 0; tr < FP_CRACK_STEPS; tr++, step *= 2) {
        for (size_t i = 0; i < ng; i++)
            for (int j = 0; j < 3; j++) x[3 * (size_t)g[i] + j] = (float)(was[i][j] + s * step * n[j]);
        if (!cross_in(x, f1, f2)) return true;
    }
    for (size_t i = 0; i < ng; i++) memcpy(x + 3 * (size_t)g[i], was[i], sizeof was[i]);
    return false;
}

/* the first vertex of group gi moved from ref in x */
static bool group_moved(const fp_crack *k, const float *ref, const float *x, uint32_t gi)
{
    size_t v = k->group[k->group_start[gi]];
    return memcmp(x + 3 * v, ref + 3 * v, 3 * sizeof *x) != 0;
}

size_t fp_crack_apply(const fp_crack *k, const uint32_t *tris, const float *ref, float *x)
{
    size_t parted = 0;
    for (size_t c = 0; c < k->ncracks; c++) {
        if (!group_moved(k, ref, x, k->side[c][0]) && !group_moved(k, ref, x, k->side[c][1])) continue;
        for (size_t i = k->first[c]; i < k->first[c + 1]; i++) {
            const uint32_t *f1 = tris + 3 * (size_t)k->pair[i][0], *f2 = tris + 3 * (size_t)k->pair[i][1];
            if (!cross_in(x, f1, f2) || cross_in(ref, f1, f2)) continue;
            /* a corner of the second off the first's plane, else one of the first off the
             * second's; a corner that moved from ref only, so x changes only where the frame
             * moved it already (the engine's ranges, which the guard, the commit and the
             * stream read) */
            bool done = false;
            for (int j = 3; j < 6 && !done; j++)
                done = k->corner[i][j] != FP_CRACK_NONE && group_moved(k, ref, x, k->corner[i][j]) &&
                       nudge(k, tris, ref, x, k->pair[i][0], k->corner[i][j], f1, f2);
            for (int j = 0; j < 3 && !done; j++)
                done = k->corner[i][j] != FP_CRACK_NONE && group_moved(k, ref, x, k->corner[i][j]) &&
                       nudge(k, tris, ref, x, k->pair[i][1], k->corner[i][j], f1, f2);
            parted += done;
        }
    }
    return parted;
}
