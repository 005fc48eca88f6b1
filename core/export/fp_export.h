/*
 * fp_export.h: a take's frames out as files an animator's tools read (docs/export.md).
 *
 * An exporter is fed the frames of a take (or of a run) one at a time, each as the mesh's
 * positions at a time, and writes one of:
 *   - gltf / glb: glTF 2.0 with the base mesh (UVs, OBJ materials), K morph targets and one
 *     animation whose `weights` channel has a key at every frame. The frames' displacements
 *     from the base are compressed into their K leading principal components (eigenvectors
 *     of the frames x frames Gram matrix D D^T of the (frames x 3n) displacement matrix D,
 *     or from the 3n x 3n D^T D where that is the smaller,
 *     LAPACK dsyevr; K the smallest whose largest per-vertex error, measured with the float32
 *     targets and weights written, is within max_error_mm); the weights then moved into
 *     [0, 1] (Blender 3.4 clamps shape keys there) by rescaled targets and, where needed, one
 *     more target "offset" keyed 1 at every frame. Written by
 *     fp_mesh_save_animation (core/mesh). In metres, as glTF wants: the vertices stay in
 *     mesh units under a root node scaled by mm_per_unit / 1000 ("NAME_metres"); the frame
 *     rate is named in asset.extras.frameRate and the animation's extras.frameRate.
 *   - pc2: Point Cache 2 (little-endian; header "POINTCACHE2\0", version 1, points, start
 *     frame 0, sampling 1, samples; then samples x points x 3 float32). PC2 has no place for
 *     a rate: start and sampling count frames of the reader's scene (one sample a frame),
 *     so the scene must run at the take's rate (docs/export.md, the Blender recipe).
 *   - mdd: LightWave MDD (big-endian; frames, points, frames float32 times in seconds, then
 *     frames x points x 3 float32): the times carry the rate.
 *   - obj-seq: one mesh file per frame in a folder (PATH/STEM_NNNNNN.obj), each written back
 *     as the input came in (fp_mesh_save_ex).
 * Point caches hold every frame's positions exactly (the float32 given), in the mesh's vertex
 * order. Files appear whole or not at all: pc2/mdd/gltf are written to a temporary file in
 * the target's folder and renamed at fp_export_finish; an aborted export leaves nothing
 * (obj-seq files already written stay, each whole).
 *
 * Errors: 0 or a negative errno-style code (core/common/fp_error.h) with a message in err:
 * -EINVAL bad options or frames (non-finite, times not increasing), -EDOM (glTF) times that
 * increase by less than float32 seconds resolve (times far from the first frame's: the
 * frames' data, not the call), -ENOENT/-EACCES/-ENOSPC/-EIO for the output, -ENOMEM, -EINVAL
 * an unknown format or bad options, FP_ENUMERIC the eigensolver failed. Nothing is printed. Threads: one exporter belongs to one thread.
 */
#ifndef FP_EXPORT_H
#define FP_EXPORT_H

#include "fp_mesh.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum fp_export_format {
    FP_EXPORT_GLTF = 0,
    FP_EXPORT_GLB,
    FP_EXPORT_PC2,
    FP_EXPORT_MDD,
    FP_EXPORT_OBJ_SEQ
} fp_export_format;

/** "gltf", "glb", "pc2", "mdd", "obj-seq" -> *f. Returns 0 or -EINVAL. */
int fp_export_format_parse(const char *name, fp_export_format *f);
/** The format of a file name's extension (.gltf .glb .pc2 .mdd). Returns 0 or -EINVAL. */
int fp_export_format_from_path(const char *path, fp_export_format *f);
/** The format's name ("gltf" ...) and its file extension without the dot ("" for obj-seq). */
const char *fp_export_format_name(fp_export_format f);
const char *fp_export_format_extension(fp_export_format f);

typedef struct fp_export_options {
    fp_export_format format;
    const char *path;        /* the file (gltf, glb, pc2, mdd) or folder (obj-seq) */
    double max_error_mm;     /* glTF: the largest per-vertex error allowed; 0: 0.1 mm */
    double mm_per_unit;      /* millimetres per mesh unit (> 0); 0: 1 */
    int max_targets;         /* glTF: at most this many targets; 0: no limit but frames */
    int step;                /* glTF: STEP sampler instead of LINEAR */
    const char *name;        /* the animation's name (glTF); NULL: "take" */
    const char *stem;        /* obj-seq file names' stem; NULL: "frame" */
    const char *seq_ext;     /* obj-seq mesh format by extension; NULL: the base mesh's own,
                                else "obj" */
    double frame_rate;       /* the frames' rate, frames per second (a take's nominal rate,
                                or the resampling rate), named in the glTF and in the result;
                                0: measured from the frames' times at finish */
    double up[3], facing[3]; /* glTF: the face's up and front in the mesh (unit; all zeros:
                                +y, +z), turned to glTF's +y and +z by the root node */
    uint64_t frames_expected; /* glTF: the frames that will be added, when known (0: not);
                                 more than FP_EXPORT_GLTF_MAX_FRAMES is refused at begin */
    double memory_budget;    /* glTF: bytes the finish may take (0: no check); an add whose
                                frames show that the finish would need more
                                (fp_export_gltf_peak_bytes of frames_expected and the vertices
                                moved so far, plus the 16 bytes a moved vertex a frame held)
                                fails with -ENOMEM at once, not after the last frame */
} fp_export_options;

/** The most frames a glTF export compresses (its F x F Gram matrix indexed in size_t). */
#define FP_EXPORT_GLTF_MAX_FRAMES 46340

/** Bytes the finish of a glTF export of `frames` frames that move `moved` vertices writes at
 *  once, at least: the dense displacements and their copy (8 x frames x 3 moved) and their
 *  Gram matrix (8 x min(frames, 3 moved)^2); the components found come on top (a lower
 *  bound: an export refused by it could not have been written). Thread-safe, pure. */
double fp_export_gltf_peak_bytes(uint64_t frames, size_t moved);

typedef struct fp_export_result {
    uint64_t frames;         /* frames written */
    size_t targets;          /* glTF: K (with the "offset" target, if any) */
    uint64_t bytes;          /* size of the file written (obj-seq: all files) */
    double max_error_mm;     /* glTF: the largest per-vertex distance, mm, between a frame
                                as the glTF's float32 values give it and the frame given;
                                0 for point caches (exact) */
    double max_error_units;  /* the same in mesh units */
    unsigned dropped;        /* FP_MESH_DROPPED_* bits: what the format could not keep */
    double frame_rate;       /* frames per second: the options' rate, else (frames - 1) over
                                the span from the first frame's time to the last's; 0 for a
                                single frame with no rate given */
    double unit_scale;       /* metres per mesh unit (mm_per_unit / 1000): glTF writes it as
                                its root node's scale; the other formats hold mesh units,
                                and a reader scales the mesh by it (Blender's importer) */
} fp_export_result;

typedef struct fp_exporter fp_exporter;

/** Start an export of frames of `base` (its vertex count, triangles, UVs and source are
 *  used; the mesh must outlive the exporter, and so must opt's name, stem and seq_ext, kept
 *  by pointer; opt->path is copied). Checks the output before any frame (the file it would
 *  replace, fp_file_target: a folder, FIFO or device is refused with -EEXIST; pc2/mdd/glTF:
 *  creates the temporary file; obj-seq: creates the folder). Returns 0 and *out, which
 *  fp_export_finish or fp_export_abort frees; or -EINVAL (NULL, an empty path, an unknown
 *  format, bad limits), -E2BIG (glTF: frames_expected over FP_EXPORT_GLTF_MAX_FRAMES), -EEXIST, -ENOENT/-EACCES/-ENOSPC/-EIO for the output, -ENOMEM, with
 *  err. [main-thread]. */
int fp_export_begin(const fp_mesh *base, const fp_export_options *opt, fp_exporter **out,
                    char *err, size_t errlen);

/** Add one frame: positions (vertex_count x 3 float32, mesh units) at time_s seconds from
 *  the export's start (strictly increasing; the first frame's time is taken as 0 in files
 *  that store times relative to the start: glTF keys and MDD times are time_s - first).
 *  Returns 0 or a negative code (the export is then only to be aborted). */
int fp_export_add(fp_exporter *x, const float *positions, double time_s, char *err,
                  size_t errlen);

/** Frames added so far. */
uint64_t fp_export_frames(const fp_exporter *x);

/** Write what is left (glTF: the compression and the file; pc2/mdd: the header, times) and
 *  rename it into place; *res (may be NULL) says what was written. Frees *x. An export with
 *  no frame fails with -EINVAL and leaves nothing. Returns 0 or a negative code. */
int fp_export_finish(fp_exporter **x, fp_export_result *res, char *err, size_t errlen);

/** Give up: remove the temporary file, free *x. NULL or *x == NULL is a no-op. */
void fp_export_abort(fp_exporter **x);

/** The morph-target compression alone (what the glTF export uses), for tests and tools:
 *  D is F x m (row-major, double: frame f's displacement over m = 3 x vertices), tol the
 *  largest per-vertex Euclidean error allowed (same units as D), kmax the most components
 *  (0: F). On success *k_out components, targets (K x m, float32, malloc()ed, caller frees)
 *  and weights (F x K, float32, malloc()ed), *max_err the largest per-vertex error of
 *  weights x targets against D measured in double from the float32 values. Returns 0,
 *  -EINVAL, -ENOMEM or FP_ENUMERIC. */
int fp_export_compress(const double *D, size_t F, size_t m, double tol, size_t kmax,
                       size_t *k_out, float **targets, float **weights, double *max_err,
                       char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
