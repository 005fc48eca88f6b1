/* fp_export: a take's frames as glTF morph-target animation, PC2 and MDD point caches, or a
 * sequence of meshes (fp_export.h, docs/export.md). */
#define _GNU_SOURCE
#include "fp_export.h"
#include "fp_error.h"
#include "fp_file.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* LAPACK (Debian liblapack-dev): symmetric eigen-decomposition, Fortran calling convention */
extern void dsyevr_(const char *jobz, const char *range, const char *uplo, const int *n, double *a,
                    const int *lda, const double *vl, const double *vu, const int *il,
                    const int *iu, const double *abstol, int *m, double *w, double *z,
                    const int *ldz, int *isuppz, double *work, const int *lwork, int *iwork,
                    const int *liwork, int *info);

struct fp_exporter {
    fp_export_options opt;
    const fp_mesh *base;
    size_t n;
    uint64_t frames;
    double first_time, last_time;
    char path[4096];          /* the target (pc2/mdd/glTF: the file replaced, a link's end) */
    fp_file_output out;       /* pc2/mdd: the file being written (out.tmp "" when none) */
    fp_file_output data;      /* mdd: the frames before the header is known (never committed) */
    FILE *f;                  /* what put() writes: out's or data's stream */
    float *scratch;           /* n x 3 */
    /* mdd: times; glTF: times and sparse displacements per frame */
    double *times;
    size_t times_cap;
    uint32_t *idx;            /* glTF: moved vertex indices, all frames back to back */
    float *disp;              /* glTF: their displacements (x 3) */
    size_t used, cap;         /* entries in idx (disp has 3x) */
    size_t *frame_start;      /* frames + 1 offsets into idx */
    size_t fs_cap;
    unsigned char *seen;      /* glTF with a memory budget: n flags, the vertices moved so far */
    size_t moved;             /* ... how many */
    uint64_t seq_bytes;
    unsigned dropped;
};

static const char *const names[] = {"gltf", "glb", "pc2", "mdd", "obj-seq"};
static const char *const exts[] = {"gltf", "glb", "pc2", "mdd", ""};

int fp_export_format_parse(const char *name, fp_export_format *f)
{
    for (int i = 0; name && i < 5; i++)
        if (strcmp(name, names[i]) == 0) {
            *f = (fp_export_format)i;
            return 0;
        }
    return -EINVAL;
}

int fp_export_format_from_path(const char *path, fp_export_format *f)
{
    const char *dot = path ? strrchr(path, '.') : NULL;
    const char *slash = path ? strrchr(path, '/') : NULL;
    if (!dot || (slash && dot < slash))
        return -EINVAL;
    for (int i = 0; i < 4; i++)
        if (strcasecmp(dot + 1, exts[i]) == 0) {
            *f = (fp_export_format)i;
            return 0;
        }
    return -EINVAL;
}

const char *fp_export_format_name(fp_export_format f)
{
    return (unsigned)f < 5 ? names[f] : "?";
}

const char *fp_export_format_extension(fp_export_format f)
{
    return (unsigned)f < 5 ? exts[f] : "";
}

/* ---- files ----------------------------------------------------------------------------- */

/* Start the output o of `path` (fp_file_open_output: the file it replaces, a temporary file
 * ".NAME<tag>.XXXXXX" beside that file, open "w+b"); x->path becomes the file replaced.
 * Returns 0 or the code, with err as every export words it. */
static int open_output(fp_exporter *x, const char *path, const char *tag, fp_file_output *o,
                       char *err, size_t errlen)
{
    int rc = fp_file_open_output(path, tag, "w+b", 0, o);
    if (rc < 0 && o->failed == FP_FILE_STEP_TARGET)
        return fp_errorf(err, errlen, rc == -EISDIR || rc == -ENXIO ? -EEXIST : fp_file_output_code(-rc),
                         "%s: cannot replace it: %s", path, fp_file_error_text(rc));
    snprintf(x->path, sizeof x->path, "%s", o->path);
    if (rc < 0 && o->failed == FP_FILE_STEP_TEMP)
        return fp_errorf(err, errlen, fp_file_output_code(-rc), "%s: cannot create a file in its folder: %s",
                         x->path, strerror(-rc));
    if (rc < 0)
        return fp_errorf(err, errlen, fp_file_output_code(-rc), "%s: %s", x->path, strerror(-rc));
    return 0;
}

static int put(fp_exporter *x, const void *p, size_t n, char *err, size_t errlen)
{
    if (fwrite(p, 1, n, x->f) != n) {
        int e = errno ? errno : EIO;
        return fp_errorf(err, errlen, fp_file_output_code(e), "%s: write failed: %s", x->path,
                         strerror(e));
    }
    return 0;
}

static void be32(void *dst, const void *src)
{
    const unsigned char *s = src;
    unsigned char *d = dst;
    d[0] = s[3]; d[1] = s[2]; d[2] = s[1]; d[3] = s[0];
}

static void le32(void *dst, const void *src)
{
    uint32_t v;
    memcpy(&v, src, 4);
    unsigned char *d = dst;
    d[0] = (unsigned char)v; d[1] = (unsigned char)(v >> 8);
    d[2] = (unsigned char)(v >> 16); d[3] = (unsigned char)(v >> 24);
}

/* fsync, close, rename o's temporary file over the target (fp_file_output_commit). */
static int commit_file(fp_exporter *x, fp_file_output *o, char *err, size_t errlen)
{
    int rc = fp_file_output_commit(o);
    x->f = NULL;
    if (rc < 0) {
        rc = fp_file_output_code(-rc);
        return fp_errorf(err, errlen, rc, "%s: cannot write: %s (nothing written)", x->path,
                         fp_strerror(rc));
    }
    return 0;
}

/* ---- begin / add ----------------------------------------------------------------------- */

int fp_export_begin(const fp_mesh *base, const fp_export_options *opt, fp_exporter **out,
                    char *err, size_t errlen)
{
    if (out)
        *out = NULL;
    if (!base || !opt || !out || !opt->path || !opt->path[0] || base->vertex_count == 0 ||
        !base->positions)
        return fp_errorf(err, errlen, -EINVAL, "export: no mesh, options or output path");
    if ((unsigned)opt->format > FP_EXPORT_OBJ_SEQ)
        return fp_errorf(err, errlen, -EINVAL, "export: unknown format %d", (int)opt->format);
    if (opt->max_error_mm < 0 || !isfinite(opt->max_error_mm) || opt->mm_per_unit < 0 ||
        !isfinite(opt->mm_per_unit) || opt->frame_rate < 0 || !isfinite(opt->frame_rate))
        return fp_errorf(err, errlen, -EINVAL,
                         "export: max error, mm per unit and frame rate must be >= 0");
    if (strlen(opt->path) >= 4000)
        return fp_errorf(err, errlen, -EINVAL, "output path too long (%zu bytes, at most 3999)",
                         strlen(opt->path));
    fp_exporter *x = calloc(1, sizeof *x);
    if (!x)
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", opt->path);
    x->opt = *opt;
    if (x->opt.max_error_mm == 0)
        x->opt.max_error_mm = 0.1;
    if (x->opt.mm_per_unit == 0)
        x->opt.mm_per_unit = 1;
    x->base = base;
    x->n = base->vertex_count;
    snprintf(x->path, sizeof x->path, "%s", opt->path); /* (pc2/mdd/glTF: open_output's) */
    x->scratch = malloc(x->n * 3 * sizeof(float));
    if (!x->scratch) {
        free(x);
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", opt->path);
    }
    int rc = 0;
    switch (opt->format) {
    case FP_EXPORT_PC2: {
        rc = open_output(x, opt->path, "", &x->out, err, errlen);
        if (rc)
            break;
        x->f = x->out.f;
        unsigned char h[32] = "POINTCACHE2";
        const int32_t version = 1, points = (int32_t)x->n, samples = 0;
        const float start = 0.0f, sampling = 1.0f;
        le32(h + 12, &version);
        le32(h + 16, &points);
        le32(h + 20, &start);
        le32(h + 24, &sampling);
        le32(h + 28, &samples);
        rc = put(x, h, sizeof h, err, errlen);
        break;
    }
    case FP_EXPORT_MDD:
        rc = open_output(x, opt->path, "frames", &x->data, err, errlen);
        x->f = x->data.f;
        break;
    case FP_EXPORT_GLTF:
    case FP_EXPORT_GLB: {
        if (opt->frames_expected > FP_EXPORT_GLTF_MAX_FRAMES) {
            rc = fp_errorf(err, errlen, -E2BIG, "%s: %llu frames: a glTF export holds at most %d",
                           x->path, (unsigned long long)opt->frames_expected,
                           FP_EXPORT_GLTF_MAX_FRAMES);
            break;
        }
        if (opt->memory_budget > 0 && !(x->seen = calloc(x->n ? x->n : 1, 1))) {
            rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", x->path);
            break;
        }
        /* the folder must take a file now, not after the whole take was played */
        fp_file_output probe;
        rc = open_output(x, opt->path, "probe", &probe, err, errlen);
        fp_file_output_abort(&probe);
        break;
    }
    case FP_EXPORT_OBJ_SEQ:
        if (mkdir(x->path, 0777) != 0 && errno != EEXIST)
            rc = fp_errorf(err, errlen, fp_file_output_code(errno), "%s: cannot create the folder: %s",
                           x->path, strerror(errno));
        else {
            struct stat st;
            if (stat(x->path, &st) != 0 || !S_ISDIR(st.st_mode))
                rc = fp_errorf(err, errlen, -ENOTDIR, "%s: not a folder", x->path);
        }
        break;
    }
    if (rc) {
        fp_export_abort(&x);
        return rc;
    }
    *out = x;
    return 0;
}

double fp_export_gltf_peak_bytes(uint64_t frames, size_t moved)
{
    /* what the finish writes whole, at once: finish_gltf's dense D (F x m floats, m = 3 x
     * moved), compress_f's copy R (F x m) and its Gram matrix G (N x N doubles, N the smaller
     * of F and m); its components (T, W, Z: calloc'ed, written in part) come on top */
    const double F = (double)frames, m = 3.0 * (double)moved, N = F < m ? F : m;
    return 8.0 * F * m + 8.0 * N * N;
}

static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return 0;
    size_t c = *cap ? *cap : 1024;
    while (c < need)
        c *= 2;
    void *q = realloc(*p, c * elem);
    if (!q)
        return -ENOMEM;
    *p = q;
    *cap = c;
    return 0;
}

static int keep_time(fp_exporter *x, double t)
{
    if (grow((void **)&x->times, &x->times_cap, x->frames + 1, sizeof(double)))
        return -ENOMEM;
    x->times[x->frames] = t;
    return 0;
}

int fp_export_add(fp_exporter *x, const float *positions, double time_s, char *err,
                  size_t errlen)
{
    if (!x || !positions)
        return fp_errorf(err, errlen, -EINVAL, "export: NULL exporter or positions");
    if (!isfinite(time_s) || (x->frames > 0 && !(time_s > x->last_time)))
        return fp_errorf(err, errlen, -EINVAL,
                         "%s: frame %llu: time %.9g s is not after the previous frame's",
                         x->path, (unsigned long long)x->frames, time_s);
    const size_t n = x->n;
    for (size_t i = 0; i < 3 * n; i++)
        if (!isfinite(positions[i]))
            return fp_errorf(err, errlen, -EINVAL, "%s: frame %llu: vertex %zu is not finite",
                             x->path, (unsigned long long)x->frames, i / 3);
    if (x->frames == 0)
        x->first_time = time_s;
    int rc = 0;
    switch (x->opt.format) {
    case FP_EXPORT_PC2:
        for (size_t i = 0; i < 3 * n; i++)
            le32(x->scratch + i, positions + i);
        rc = put(x, x->scratch, 12 * n, err, errlen);
        break;
    case FP_EXPORT_MDD:
        for (size_t i = 0; i < 3 * n; i++)
            be32(x->scratch + i, positions + i);
        rc = put(x, x->scratch, 12 * n, err, errlen);
        if (!rc && keep_time(x, time_s - x->first_time))
            rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", x->path);
        break;
    case FP_EXPORT_GLTF:
    case FP_EXPORT_GLB: {
        if (keep_time(x, time_s - x->first_time) ||
            grow((void **)&x->frame_start, &x->fs_cap, x->frames + 2, sizeof(size_t))) {
            rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", x->path);
            break;
        }
        if (x->frames == 0)
            x->frame_start[0] = 0;
        const float *b = x->base->positions;
        for (size_t v = 0; v < n; v++) {
            const float *p = positions + 3 * v, *q = b + 3 * v;
            if (memcmp(p, q, 3 * sizeof(float)) == 0)
                continue;
            if (x->used + 1 > x->cap) {
                size_t cap = x->cap;
                if (grow((void **)&x->idx, &cap, x->used + 1, sizeof(uint32_t))) {
                    rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", x->path);
                    break;
                }
                float *d = realloc(x->disp, cap * 3 * sizeof(float));
                if (!d) {
                    rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", x->path);
                    break;
                }
                x->disp = d;
                x->cap = cap;
            }
            if (x->seen && !x->seen[v]) {
                x->seen[v] = 1;
                x->moved++;
            }
            x->idx[x->used] = (uint32_t)v;
            for (int k = 0; k < 3; k++)
                x->disp[3 * x->used + (size_t)k] = (float)((double)p[k] - (double)q[k]);
            x->used++;
        }
        x->frame_start[x->frames + 1] = x->used;
        if (!rc && x->seen) { /* the finish's memory, at least: refused now, not at the end */
            const uint64_t F = x->opt.frames_expected > x->frames + 1 ? x->opt.frames_expected
                                                                      : x->frames + 1;
            const double need = fp_export_gltf_peak_bytes(F, x->moved) +
                                16.0 * (double)x->used;
            if (need > x->opt.memory_budget)
                rc = fp_errorf(err, errlen, -ENOMEM, "%s: the morph targets of %llu frames need "
                               "%.1f GB or more at the end (%zu vertices moved by frame %llu), more "
                               "than the %.1f GB there is room for: stopped before it; nothing "
                               "written", x->path, (unsigned long long)F, need / 1e9, x->moved,
                               (unsigned long long)x->frames + 1, x->opt.memory_budget / 1e9);
        }
        break;
    }
    case FP_EXPORT_OBJ_SEQ: {
        char file[4400];
        const char *ext = x->opt.seq_ext ? x->opt.seq_ext : "obj";
        if (!x->opt.seq_ext && x->base->source_path) {
            const char *dot = strrchr(x->base->source_path, '.');
            if (dot && !strchr(dot, '/'))
                ext = dot + 1;
        }
        snprintf(file, sizeof file, "%s/%s_%06llu.%s", x->path,
                 x->opt.stem ? x->opt.stem : "frame", (unsigned long long)x->frames, ext);
        fp_mesh m = *x->base;  /* the base's triangles, UVs and source; these positions */
        m.positions = (float *)positions;
        m.normals = x->scratch;
        fp_mesh_normals(m.triangles, m.triangle_count, m.positions, m.vertex_count, m.normals);
        unsigned dropped = 0;
        rc = fp_mesh_save_ex(&m, file, &dropped, err, errlen);
        x->dropped |= dropped;
        struct stat st;
        if (!rc && stat(file, &st) == 0)
            x->seq_bytes += (uint64_t)st.st_size;
        break;
    }
    }
    if (rc)
        return rc;
    x->last_time = time_s;
    x->frames++;
    return 0;
}

uint64_t fp_export_frames(const fp_exporter *x)
{
    return x ? x->frames : 0;
}

/* ---- compression ------------------------------------------------------------------------ */

/* Largest per-vertex error of weights x targets (float32 values, double sums) against D. */
static double recon_error(const float *D, size_t F, size_t m, const float *T, const float *W,
                          size_t K)
{
    double worst = 0;
    for (size_t f = 0; f < F; f++)
        for (size_t j = 0; j + 2 < m; j += 3) {
            double e2 = 0;
            for (int c = 0; c < 3; c++) {
                double r = D[f * m + j + (size_t)c];
                for (size_t k = 0; k < K; k++)
                    r -= (double)W[f * K + k] * (double)T[k * m + j + (size_t)c];
                e2 += r * r;
            }
            if (e2 > worst)
                worst = e2;
        }
    return sqrt(worst);
}

/* Two doubles, one SSE2 (or NEON) register: GCC's and Clang's vector extension. */
typedef double v2d __attribute__((vector_size(16)));

/* Rows i0 .. i0+3 of D (F x m) against rows j0 .. j0+3 (j0 <= i0), the pairs j <= i into G
 * (both triangles): 16 sums that share each value loaded, in 8 two-lane registers, each
 * lane one pair's sum over c in order (the very sums one pair at a time gave: the same G to
 * the bit). Rows past F (the last tiles) are summed one pair at a time. */
static void gram_tile(const float *D, size_t F, size_t m, size_t i0, size_t j0, double *G)
{
    double s[4][4] = {{0}};
    const size_t ni = F - i0 < 4 ? F - i0 : 4, nj = F - j0 < 4 ? F - j0 : 4;
    if (ni == 4 && nj == 4) {
        const float *a0 = D + i0 * m, *a1 = a0 + m, *a2 = a1 + m, *a3 = a2 + m;
        const float *b0 = D + j0 * m, *b1 = b0 + m, *b2 = b1 + m, *b3 = b2 + m;
        v2d lo[4] = {{0, 0}, {0, 0}, {0, 0}, {0, 0}}, hi[4] = {{0, 0}, {0, 0}, {0, 0}, {0, 0}};
        for (size_t c = 0; c < m; c++) {
            const v2d bl = {b0[c], b1[c]}, bh = {b2[c], b3[c]};
            const v2d x0 = {a0[c], a0[c]}, x1 = {a1[c], a1[c]}, x2 = {a2[c], a2[c]}, x3 = {a3[c], a3[c]};
            lo[0] += x0 * bl, hi[0] += x0 * bh;
            lo[1] += x1 * bl, hi[1] += x1 * bh;
            lo[2] += x2 * bl, hi[2] += x2 * bh;
            lo[3] += x3 * bl, hi[3] += x3 * bh;
        }
        for (int x = 0; x < 4; x++)
            s[x][0] = lo[x][0], s[x][1] = lo[x][1], s[x][2] = hi[x][0], s[x][3] = hi[x][1];
    } else {
        for (size_t x = 0; x < ni; x++)
            for (size_t y = 0; y < nj; y++)
                for (size_t c = 0; c < m; c++)
                    s[x][y] += (double)D[(i0 + x) * m + c] * (double)D[(j0 + y) * m + c];
    }
    for (size_t x = 0; x < ni; x++)
        for (size_t y = 0; y < nj && j0 + y <= i0 + x; y++)
            G[(i0 + x) * F + j0 + y] = G[(j0 + y) * F + i0 + x] = s[x][y];
}

/* The Gram matrix of D (F x m): D D^T (F x F) or, by_values, D^T D (m x m), both triangles
 * filled, into G (zeroed). D D^T by 4 x 4 tiles of frames (gram_tile): 3.5 times faster than
 * pair by pair (1,201 frames x 14,037 values: 3.05 s against 10.65 s of CPU), the same G. */
static void gram(const float *D, size_t F, size_t m, bool by_values, double *G)
{
    if (!by_values) {
        for (size_t i0 = 0; i0 < F; i0 += 4)
            for (size_t j0 = 0; j0 <= i0; j0 += 4)
                gram_tile(D, F, m, i0, j0, G);
        return;
    }
    for (size_t f = 0; f < F; f++) {
        const float *a = D + f * m;
        for (size_t i = 0; i < m; i++) {
            const double ai = a[i];
            if (ai == 0)
                continue;
            double *g = G + i * m;
            for (size_t j = 0; j <= i; j++)
                g[j] += ai * (double)a[j];
        }
    }
    for (size_t i = 0; i < m; i++)
        for (size_t j = 0; j < i; j++)
            G[j * m + i] = G[i * m + j];
}

/* The `want` largest eigenpairs of the symmetric N x N G (both triangles filled), through
 * LAPACK dsyevr (RANGE 'I': the reduction to tridiagonal form, then only the eigenvectors
 * asked for, where dsyev made all N: 2.5 times its CPU on a minute of the ICT face). ev (N)
 * gets them ascending in ev[0 .. want-1], Z (N x want, column-major) their unit
 * eigenvectors, column j for ev[j]. dsyevr overwrites G's upper triangle with the diagonal:
 * they are put back from the lower triangle and diag (N, G's diagonal), so G can be asked
 * again. *Z is realloc'ed to N x want. 0, -ENOMEM or FP_ENUMERIC (LAPACK's info). */
static int top_eigen_range(double *G, const double *diag, size_t N, size_t want, double *ev,
                           double **Z)
{
    double *z = realloc(*Z, N * want * sizeof(double));
    if (!z) return -ENOMEM;
    *Z = z;
    const int n = (int)N, il = (int)(N - want + 1), iu = (int)N;
    const double none = 0;
    int got = 0, info = 0, lwork = -1, liwork = -1, iq = 0;
    double q = 0;
    int *isuppz = malloc(2 * want * sizeof(int));
    if (!isuppz) return -ENOMEM;
    dsyevr_("V", "I", "U", &n, G, &n, &none, &none, &il, &iu, &none, &got, ev, z, &n, isuppz,
            &q, &lwork, &iq, &liwork, &info);
    lwork = info == 0 ? (int)q : 26 * n;
    liwork = info == 0 ? iq : 10 * n;
    double *work = malloc((size_t)lwork * sizeof(double));
    int *iwork = malloc((size_t)liwork * sizeof(int));
    int rc = -ENOMEM;
    if (work && iwork) {
        dsyevr_("V", "I", "U", &n, G, &n, &none, &none, &il, &iu, &none, &got, ev, z, &n,
                isuppz, work, &lwork, iwork, &liwork, &info);
        rc = info != 0 || (size_t)got != want ? FP_ENUMERIC : 0;
    }
    free(isuppz);
    free(work);
    free(iwork);
    for (size_t c = 0; c < N; c++) {   /* column c's upper part (Fortran's view) back */
        for (size_t r = 0; r < c; r++)
            G[r + c * N] = G[c + r * N];
        G[c + c * N] = diag[c];
    }
    return rc;
}

/* The largest norm of the n / 3 vectors of three floats in R (the residual's largest vertex
 * norm: a close estimate of the float residual's) */
static double largest_norm(const float *R, size_t n)
{
    double worst = 0;
    for (size_t i = 0; i + 2 < n; i += 3) {
        const double e2 = (double)R[i] * R[i] + (double)R[i + 1] * R[i + 1] + (double)R[i + 2] * R[i + 2];
        if (e2 > worst)
            worst = e2;
    }
    return sqrt(worst);
}

/* top_eigen_range, and where LAPACK fails on a part of the spectrum (dsyevr's inverse
 * iteration, DSTEIN, not converging), the whole of it (the MRRR path dsyevr takes for every
 * eigenpair); the largest `want` then lie at ev[N - want ..] and Z's last columns, moved to
 * the front so that the caller's view is the same. */
static int top_eigen(double *G, const double *diag, size_t N, size_t want, double *ev,
                     double **Z)
{
    int rc = top_eigen_range(G, diag, N, want, ev, Z);
    if (rc != FP_ENUMERIC || want == N)
        return rc;
    if ((rc = top_eigen_range(G, diag, N, N, ev, Z)))
        return rc;
    memmove(ev, ev + (N - want), want * sizeof(double));
    memmove(*Z, *Z + (N - want) * N, want * N * sizeof(double));
    return 0;
}

/* The F x m float matrix version (what the exporter holds). */
static int compress_f(const char *who, const float *D, size_t F, size_t m, double tol,
                      size_t kmax, size_t *k_out, float **targets, float **weights,
                      double *max_err, char *err, size_t errlen)
{
    *targets = NULL;
    *weights = NULL;
    if (F == 0 || m == 0 || F > 46340)
        return fp_errorf(err, errlen, -EINVAL, "%s: %zu frames of %zu values", who, F, m);
    /* The principal directions from the smaller of D D^T (F x F) and D^T D (m x m): the same
     * nonzero eigenvalues, u = D v / sigma. A minute at 60 fps of a face moving 320 vertices
     * (F 3,601, m 960) took minutes through the 3,601 x 3,601 one. */
    const bool by_values = m < F;
    const size_t N = by_values ? m : F;
    if (kmax == 0 || kmax > N)
        kmax = N;
    /* eigenpairs are asked for `want` at a time, the largest first (top_eigen): a take needs
     * a few dozen components, not N */
    size_t want = kmax < 64 ? kmax : 64, got = 0;
    double *G = calloc(N * N, sizeof(double)), *ev = calloc(N, sizeof(double));
    double *diag = malloc(N * sizeof(double)), *Z = NULL;
    double *ub = malloc(F * sizeof(double));
    float *R = malloc(F * m * sizeof(float));
    float *T = calloc(kmax * m, sizeof(float)), *W = calloc(F * kmax, sizeof(float));
    double *v = malloc(m * sizeof(double));
    int rc = 0;
    if (!G || !ev || !diag || !ub || !R || !T || !W || !v) {
        rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory (%zu frames x %zu values)",
                       who, F, m);
        goto out;
    }
    gram(D, F, m, by_values, G);
    for (size_t i = 0; i < N; i++)
        diag[i] = G[i * N + i];
    if ((rc = top_eigen(G, diag, N, want, ev, &Z))) {
        rc = fp_errorf(err, errlen, rc, "%s: %s", who, rc == -ENOMEM ? "out of memory" : "LAPACK dsyevr failed");
        goto out;
    }
    got = want;
    memcpy(R, D, F * m * sizeof(float));
    const double res0 = recon_error(D, F, m, T, W, 0);
    double res = res0;
    size_t K = 0;
    const double top = ev[got - 1] > 0 ? ev[got - 1] : 0;
    while (K < kmax) {
        if (res <= tol && K > 0)
            break;
        if (res <= tol && K == 0 && top == 0)
            break;
        if (K == got) {   /* more eigenpairs: four times as many, the largest again */
            want = 4 * got < kmax ? 4 * got : kmax;
            if ((rc = top_eigen(G, diag, N, want, ev, &Z))) {
                rc = fp_errorf(err, errlen, rc, "%s: %s", who, rc == -ENOMEM ? "out of memory" : "LAPACK dsyevr failed");
                goto out;
            }
            got = want;
            /* and the components again from the first: where eigenvalues tie across the
             * first call's last one, the new call may span that eigenspace with another basis,
             * and a new column would repeat a direction already taken and miss another */
            K = 0;
            memcpy(R, D, F * m * sizeof(float));
            res = res0;
            continue;
        }
        /* component K: the (K+1)-th largest eigenpair; column got-1-K of Z */
        const double lambda = ev[got - 1 - K];
        const double *u = Z + (got - 1 - K) * N;
        if (!(lambda > top * 1e-14) || lambda <= 0)
            break;   /* what is left is rounding: no more directions */
        const double sigma = sqrt(lambda);
        if (by_values) {   /* u = D v / sigma, v the eigenvector of D^T D */
            for (size_t f = 0; f < F; f++) {
                double s = 0;
                for (size_t c = 0; c < m; c++)
                    s += (double)D[f * m + c] * u[c];
                ub[f] = s / sigma;
            }
            u = ub;
        }
        for (size_t c = 0; c < m; c++)
            v[c] = 0;
        for (size_t f = 0; f < F; f++) {
            const double uf = u[f];
            if (uf == 0)
                continue;
            const float *a = D + f * m;
            for (size_t c = 0; c < m; c++)
                v[c] += uf * a[c];
        }
        double wmax = 0;
        for (size_t f = 0; f < F; f++)
            if (fabs(sigma * u[f]) > wmax)
                wmax = fabs(sigma * u[f]);
        if (!(wmax > 0))
            break;
        /* weights in [-1, 1]: target = D^T u / sigma * wmax, weight = sigma u / wmax */
        for (size_t c = 0; c < m; c++)
            T[K * m + c] = (float)(v[c] / sigma * wmax);
        /* weights from the float32 target by least squares against the residual: the
         * stored values then fit what a reader computes as well as they can */
        double tt = 0;
        for (size_t c = 0; c < m; c++)
            tt += (double)T[K * m + c] * (double)T[K * m + c];
        for (size_t f = 0; f < F; f++) {
            double s = 0;
            const float *r = R + f * m, *t = T + K * m;
            for (size_t c = 0; c < m; c++)
                s += (double)r[c] * (double)t[c];
            const float w = (float)(tt > 0 ? s / tt : 0);
            /* weights are set for every earlier component already; fold this one in */
            W[f * kmax + K] = w;
            float *rr = R + f * m;
            for (size_t c = 0; c < m; c++)
                rr[c] = (float)((double)rr[c] - (double)w * (double)t[c]);
        }
        K++;
        res = largest_norm(R, F * m);
    }
    if (K == 0) {   /* nothing moved: one zero target keeps the file well-formed */
        K = 1;
    }
    /* pack W (F x kmax) into F x K and measure exactly from the float32 values */
    float *Wk = malloc(F * K * sizeof(float)), *Tk = malloc(K * m * sizeof(float));
    if (!Wk || !Tk) {
        free(Wk);
        free(Tk);
        rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", who);
        goto out;
    }
    for (size_t f = 0; f < F; f++)
        for (size_t k = 0; k < K; k++)
            Wk[f * K + k] = W[f * kmax + k];
    memcpy(Tk, T, K * m * sizeof(float));
    *max_err = recon_error(D, F, m, Tk, Wk, K);
    *k_out = K;
    *targets = Tk;
    *weights = Wk;
out:
    free(G);
    free(ev);
    free(diag);
    free(Z);
    free(ub);
    free(R);
    free(T);
    free(W);
    free(v);
    return rc;
}

int fp_export_compress(const double *D, size_t F, size_t m, double tol, size_t kmax,
                       size_t *k_out, float **targets, float **weights, double *max_err,
                       char *err, size_t errlen)
{
    if (!D || !k_out || !targets || !weights || !max_err || !(tol >= 0))
        return fp_errorf(err, errlen, -EINVAL, "export: bad arguments");
    float *Df = malloc(F * m * sizeof(float));
    if (!Df)
        return fp_errorf(err, errlen, -ENOMEM, "export: out of memory");
    for (size_t i = 0; i < F * m; i++)
        Df[i] = (float)D[i];
    int rc = compress_f("export", Df, F, m, tol, kmax, k_out, targets, weights, max_err, err, errlen);
    free(Df);
    if (rc == 0) {   /* the error against D as given (double), not its float32 copy */
        const size_t K = *k_out;
        double worst = 0;
        for (size_t f = 0; f < F; f++)
            for (size_t j = 0; j + 2 < m; j += 3) {
                double e2 = 0;
                for (int c = 0; c < 3; c++) {
                    double r = D[f * m + j + (size_t)c];
                    for (size_t k = 0; k < K; k++)
                        r -= (double)(*weights)[f * K + k] * (double)(*targets)[k * m + j + (size_t)c];
                    e2 += r * r;
                }
                if (e2 > worst) worst = e2;
            }
        *max_err = sqrt(worst);
    }
    return rc;
}

/* ---- finish ------------------------------------------------------------------------------ */

static uint64_t file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (uint64_t)st.st_size : 0;
}

/* The frames' rate: the options', else (frames - 1) over the span of their times; 0 for one
 * frame with none given. */
static double frame_rate(const fp_exporter *x)
{
    if (x->opt.frame_rate > 0)
        return x->opt.frame_rate;
    if (x->frames < 2 || !(x->last_time > x->first_time))
        return 0;
    return (double)(x->frames - 1) / (x->last_time - x->first_time);
}

/* The weights into [0, 1]. Blender 3.4's glTF importer (Debian 12's) keys each shape key's
 * value within its slider range, [0, 1], widened only by the first key's weight
 * (io_scene_gltf2 gltf2_blender_animation_weight.py: min(coords[1:2])): a weight below 0 or
 * above 1 later in a take played as 0 or 1, the face up to 27 mm off in Blender while the
 * file was right. Per target k, weights in [lo, hi]: weight' = (w - a) / s, target' =
 * s x target, with s = max(hi, 1), a = 0 where lo >= 0 (a scale where hi > 1); s = lo, a = 0
 * where hi <= 0 (the sign turned); else s = hi - lo, a = lo, and a x target goes into one
 * more target (the last, "offset") whose weight is 1 at every key (0 in mesh.weights: the
 * rest shape stays the loaded face). *T (K x m) and *W (F x K, malloc()ed) are replaced where anything changes;
 * *K is one more with an offset. Returns 1 (changed), 0 (the weights were in [0, 1]) or
 * -ENOMEM (nothing changed). */
static int unit_weights(float **T, float **W, size_t F, size_t m, size_t *K)
{
    const size_t k0 = *K;
    double *a = calloc(k0, sizeof(double)), *sc = calloc(k0, sizeof(double));
    float *T2 = calloc((k0 + 1) * m, sizeof(float)), *W2 = calloc(F * (k0 + 1), sizeof(float));
    double *off = calloc(m, sizeof(double));
    if (!a || !sc || !T2 || !W2 || !off) {
        free(a); free(sc); free(T2); free(W2); free(off);
        return -ENOMEM;
    }
    bool change = false, offset = false;
    for (size_t k = 0; k < k0; k++) {
        double lo = 0, hi = 0;
        for (size_t f = 0; f < F; f++) {
            const double w = (*W)[f * k0 + k];
            lo = w < lo ? w : lo;
            hi = w > hi ? w : hi;
        }
        sc[k] = lo >= 0 ? (hi > 1 ? hi : 1) : hi <= 0 ? lo : hi - lo;
        a[k] = lo < 0 && hi > 0 ? lo : 0;
        change |= sc[k] != 1;
        offset |= a[k] != 0;
    }
    const size_t k1 = k0 + (offset ? 1 : 0);
    if (change) {
        for (size_t k = 0; k < k0; k++) {
            for (size_t c = 0; c < m; c++) {
                T2[k * m + c] = (float)(sc[k] * (*T)[k * m + c]);
                off[c] += a[k] * (double)(*T)[k * m + c];
            }
            for (size_t f = 0; f < F; f++) {
                const double w = ((double)(*W)[f * k0 + k] - a[k]) / sc[k];
                W2[f * k1 + k] = (float)(w < 0 ? 0 : w > 1 ? 1 : w);
            }
        }
        for (size_t c = 0; offset && c < m; c++)
            T2[k0 * m + c] = (float)off[c];
        for (size_t f = 0; offset && f < F; f++)
            W2[f * k1 + k0] = 1;
        free(*T);
        free(*W);
        *T = T2;
        *W = W2;
        *K = k1;
    } else {
        free(T2);
        free(W2);
    }
    free(a);
    free(sc);
    free(off);
    return change ? 1 : 0;
}

/* The compression (compress_f) of D (F x m) and its weights into [0, 1] (unit_weights):
 * *K targets, the first *k_pc principal components, then "offset" where one is needed; *T,
 * *W malloc()ed; *max_err measured on the values written. --max-targets counts the offset:
 * where it would be one too many the components are one fewer (but one component whose
 * weights change sign still takes two targets). Returns 0 or a negative code (said). */
static int compress_unit(const fp_exporter *x, const float *D, size_t F, size_t m, size_t *K,
                         size_t *k_pc, float **T, float **W, double *max_err, char *err,
                         size_t errlen)
{
    const double tol = x->opt.max_error_mm / x->opt.mm_per_unit;
    const size_t cap = x->opt.max_targets > 0 ? (size_t)x->opt.max_targets : 0;
    for (size_t kmax = cap;; kmax--) {
        int rc = compress_f(x->path, D, F, m, tol, kmax, K, T, W, max_err, err, errlen);
        if (rc)
            return rc;
        *k_pc = *K;
        const int changed = unit_weights(T, W, F, m, K);
        if (changed < 0)
            return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", x->path);
        if (changed)   /* (the error of the values written: targets rescaled in float32) */
            *max_err = recon_error(D, F, m, *T, *W, *K);
        if (!cap || *K <= cap || kmax <= 1)
            return 0;
        free(*T);
        free(*W);
        *T = *W = NULL;
    }
}

static int finish_gltf(fp_exporter *x, fp_export_result *res, char *err, size_t errlen)
{
    const size_t F = (size_t)x->frames, n = x->n;
    /* the vertices any frame moved, and the dense F x 3M displacement matrix over them */
    uint32_t *col = malloc(n * sizeof(uint32_t));
    if (!col)
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", x->path);
    for (size_t v = 0; v < n; v++)
        col[v] = UINT32_MAX;
    size_t M = 0;
    for (size_t e = 0; e < x->used; e++)
        if (col[x->idx[e]] == UINT32_MAX)
            col[x->idx[e]] = 1;
    uint32_t *moved = malloc((n ? n : 1) * sizeof(uint32_t));
    if (!moved) {
        free(col);
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", x->path);
    }
    for (size_t v = 0; v < n; v++)
        if (col[v] != UINT32_MAX) {
            col[v] = (uint32_t)M;
            moved[M++] = (uint32_t)v;
        }
    const size_t m = 3 * (M ? M : 1);
    float *D = calloc(F * m, sizeof(float));
    int rc = 0;
    float *T = NULL, *W = NULL, *targets = NULL;
    char **tnames = NULL;
    if (!D) {
        rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory (%zu frames x %zu moved "
                       "vertices)", x->path, F, M);
        goto out;
    }
    for (size_t f = 0; f < F; f++)
        for (size_t e = x->frame_start[f]; e < x->frame_start[f + 1]; e++)
            for (int c = 0; c < 3; c++)
                D[f * m + 3 * col[x->idx[e]] + (size_t)c] = x->disp[3 * e + (size_t)c];
    size_t K = 0, k_pc = 0;   /* targets written; of them, principal components */
    double max_err = 0;
    if ((rc = compress_unit(x, D, F, m, &K, &k_pc, &T, &W, &max_err, err, errlen)))
        goto out;
    targets = calloc(K * n * 3, sizeof(float));
    tnames = calloc(K, sizeof(char *));
    float *times = malloc(F * sizeof(float));
    if (!targets || !tnames || !times) {
        free(times);
        rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", x->path);
        goto out;
    }
    for (size_t k = 0; k < K; k++)
        for (size_t j = 0; j < M; j++)
            for (int c = 0; c < 3; c++)
                targets[k * n * 3 + 3 * moved[j] + (size_t)c] = T[k * m + 3 * j + (size_t)c];
    for (size_t k = 0; k < K; k++) {
        tnames[k] = malloc(32);
        if (tnames[k] && k < k_pc)
            snprintf(tnames[k], 32, "pc%02zu", k + 1);
        else if (tnames[k])
            snprintf(tnames[k], 32, "offset");
    }
    for (size_t f = 0; f < F; f++)
        times[f] = (float)x->times[f];
    /* float32 times must stay increasing */
    for (size_t f = 1; f < F; f++)
        if (!(times[f] > times[f - 1])) {
            free(times);
            rc = fp_errorf(err, errlen, -EDOM, "%s: frames %zu and %zu are closer in time "
                           "than float32 seconds resolve", x->path, f - 1, f);
            goto out;
        }
    fp_mesh_morph_animation anim = {.target_count = K, .targets = targets,
                                    .target_names = (const char *const *)tnames,
                                    .frame_count = F, .times = times, .weights = W,
                                    .step = x->opt.step, .name = x->opt.name,
                                    .unit_scale = x->opt.mm_per_unit / 1000,
                                    .frame_rate = frame_rate(x)};
    memcpy(anim.up, x->opt.up, sizeof anim.up);
    memcpy(anim.facing, x->opt.facing, sizeof anim.facing);
    unsigned dropped = 0;
    rc = fp_mesh_save_animation(x->base, &anim, x->path, &dropped, err, errlen);
    free(times);
    if (rc)
        goto out;
    if (res) {
        res->targets = K;
        res->max_error_units = max_err;
        res->max_error_mm = max_err * x->opt.mm_per_unit;
        res->dropped = dropped;
        res->bytes = file_size(x->path);
    }
out:
    if (tnames)
        for (size_t k = 0; k < K; k++)
            free(tnames[k]);
    free(tnames);
    free(targets);
    free(T);
    free(W);
    free(D);
    free(col);
    free(moved);
    return rc;
}

static int finish_mdd(fp_exporter *x, char *err, size_t errlen)
{
    int rc = open_output(x, x->path, "", &x->out, err, errlen);
    if (rc)
        return rc;
    FILE *data = x->data.f;
    x->f = x->out.f;
    unsigned char h[8];
    const int32_t frames = (int32_t)x->frames, points = (int32_t)x->n;
    be32(h, &frames);
    be32(h + 4, &points);
    rc = put(x, h, 8, err, errlen);
    for (uint64_t f = 0; !rc && f < x->frames; f++) {
        float t = (float)x->times[f];
        unsigned char b[4];
        be32(b, &t);
        rc = put(x, b, 4, err, errlen);
    }
    if (!rc && (fflush(data) != 0 || fseek(data, 0, SEEK_SET) != 0))
        rc = fp_errorf(err, errlen, fp_file_output_code(errno), "%s: %s", x->data.tmp, strerror(errno));
    char buf[1 << 16];
    size_t got;
    while (!rc && (got = fread(buf, 1, sizeof buf, data)) > 0)
        rc = put(x, buf, got, err, errlen);
    if (!rc && ferror(data))
        rc = fp_errorf(err, errlen, -EIO, "%s: read failed", x->data.tmp);
    fp_file_output_abort(&x->data); /* (only a scratch: never the target) */
    if (rc)
        return rc;
    return commit_file(x, &x->out, err, errlen);
}

int fp_export_finish(fp_exporter **xp, fp_export_result *res, char *err, size_t errlen)
{
    if (res)
        memset(res, 0, sizeof *res);
    if (!xp || !*xp)
        return fp_errorf(err, errlen, -EINVAL, "export: NULL exporter");
    fp_exporter *x = *xp;
    int rc = 0;
    if (x->frames == 0) {
        rc = fp_errorf(err, errlen, -EINVAL, "%s: no frames to export (nothing written)",
                       x->path);
        fp_export_abort(xp);
        return rc;
    }
    if (x->frames > INT32_MAX / 2) {
        rc = fp_errorf(err, errlen, -EINVAL, "%s: too many frames", x->path);
        fp_export_abort(xp);
        return rc;
    }
    switch (x->opt.format) {
    case FP_EXPORT_PC2: {
        unsigned char b[4];
        const int32_t samples = (int32_t)x->frames;
        le32(b, &samples);
        if (fflush(x->f) != 0 || pwrite(fileno(x->f), b, 4, 28) != 4)
            rc = fp_errorf(err, errlen, fp_file_output_code(errno), "%s: write failed: %s", x->path,
                           strerror(errno));
        if (!rc)
            rc = commit_file(x, &x->out, err, errlen);
        break;
    }
    case FP_EXPORT_MDD:
        rc = finish_mdd(x, err, errlen);
        break;
    case FP_EXPORT_GLTF:
    case FP_EXPORT_GLB:
        rc = finish_gltf(x, res, err, errlen);
        break;
    case FP_EXPORT_OBJ_SEQ:
        break;
    }
    if (res && !rc) {
        res->frames = x->frames;
        res->frame_rate = frame_rate(x);
        res->unit_scale = x->opt.mm_per_unit / 1000;
        if (x->opt.format == FP_EXPORT_OBJ_SEQ) {
            res->bytes = x->seq_bytes;
            res->dropped = x->dropped;
        } else if (x->opt.format == FP_EXPORT_PC2 || x->opt.format == FP_EXPORT_MDD) {
            res->bytes = file_size(x->path);
        }
    }
    fp_export_abort(xp);
    return rc;
}

void fp_export_abort(fp_exporter **xp)
{
    if (!xp || !*xp)
        return;
    fp_exporter *x = *xp;
    fp_file_output_abort(&x->out); /* (x->f is one of their streams) */
    fp_file_output_abort(&x->data);
    free(x->scratch);
    free(x->times);
    free(x->idx);
    free(x->disp);
    free(x->frame_start);
    free(x->seen);
    free(x);
    *xp = NULL;
}
