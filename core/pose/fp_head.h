/*
 * fp_head.h: the head in a face mesh and the mesh's physical unit, for the life-size
 * calibration of core/pose (hands and head at the same physical scale).
 *
 * Convention: the mesh's +y is up (chin to crown) and +z points out of the face (toward the
 * viewer), as the rest of the project assumes (plugin.h: the device's +x right, +y up, +z
 * toward the performer map to the mesh's axes).
 *
 * Detection (fp_head_detect), on the vertex positions alone:
 *  1. The width profile: 64 slices along y over the mesh's height; each slice's width is the
 *     x extent and its depth the z extent of the vertices in it and its two neighbours.
 *  2. Walking down from the top: the widest slice so far is the head's widest part; the neck
 *     is the narrowest slice after the width fell below 85% of that, confirmed when the width
 *     below grows again past 120% of the narrowest (shoulders, the neck's base) or the mesh
 *     ends there.
 *  3. Mask or head: where the depth of the widest head slice is under 0.8 of its width, the
 *     mesh is a face mask without crown or back (MediaPipe's canonical face): its unit comes
 *     from the face's width, FP_HEAD_FACE_WIDTH_MM (145 mm, the face's breadth at the
 *     cheeks and temples) over the mask's x extent. Otherwise it is a head: FP_HEAD_HEIGHT_MM
 *     (230 mm, chin to crown) over the height from the neck slice to the top (the neck's
 *     narrowest slice lies at the jaw's lower edge, the chin's level).
 *  4. No neck found (a head cut off above the shoulders with no narrowing): the head's
 *     height is the mesh's height.
 * The head's box: x, y, z extents of the vertices from the neck (or the mesh's bottom) up.
 *
 * Threads: pure and reentrant; allocates a small profile internally (no I/O, never prints).
 */
#ifndef FP_HEAD_H
#define FP_HEAD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_HEAD_HEIGHT_MM 230.0      /* chin to crown of an adult head */
#define FP_HEAD_FACE_WIDTH_MM 145.0  /* the breadth a face mask spans */

typedef enum fp_head_method {
    FP_HEAD_GIVEN = 0,     /* mm_per_unit given (option, rig, calibration file) */
    FP_HEAD_NECK,          /* head height from the neck to the crown */
    FP_HEAD_NO_NECK,       /* a head without neck: the mesh's height */
    FP_HEAD_FACE_WIDTH,    /* a face mask: its width */
} fp_head_method;

typedef struct fp_head {
    double mm_per_unit;    /* millimetres per mesh unit */
    float min[3], max[3];  /* the head's box, mesh units */
    float neck_y;          /* the neck (chin level) or the mesh's bottom, mesh units */
    fp_head_method method;
    char how[160];         /* e.g. "detected from the head: 22.8 units neck to crown = 230 mm" */
} fp_head;

/** Find the head in n vertices (pos: n x 3 floats, mesh units) and the mesh's unit, as the
 *  top of this file says. Returns 0, or -EINVAL (NULL, n < 4, a non-finite coordinate, a
 *  flat mesh or one with no height above the neck found), -ENOMEM; on 0 mm_per_unit is finite
 *  and > 0. */
int fp_head_detect(const float *pos, size_t n, fp_head *out);

/** fp_head_detect over the vertices v with used[v] != 0 only (used: n bytes, or NULL for all;
 *  fp_mesh_face_mask: the surface's, without points in no triangle or far off the rest, which
 *  a stray one would turn into the head's box and the mesh's unit). -EINVAL also when fewer
 *  than 4 are used. */
int fp_head_detect_used(const float *pos, size_t n, const uint8_t *used, fp_head *out);

/** A face that looks elsewhere than +z (fp_calibration.face): its n positions turned back into
 *  the face's own frame into `turned` (n x 3, the caller's), by the inverse of the unit
 *  quaternion face (w, x, y, z: the face's frame -> the mesh's), and the head found there
 *  (fp_head_detect_used with used, NULL for all; its box in the face's frame). Returns as
 *  fp_head_detect. */
int fp_head_detect_turned(const float *pos, size_t n, const uint8_t *used, const double face[4], float *turned,
                          fp_head *out);

/** Where a head's nose points, from its shape alone (a face that looks another way than the
 *  session takes: the warning of a rigless face without --up/--facing). For each end of each
 *  axis, the cap: the vertices (used[v] != 0; used NULL: all) within FP_HEAD_CAP_DEPTH of the
 *  mesh's extent along that axis from that end; its size is the product of its box's spans
 *  along the two other axes, each over the mesh's extent there. A nose's cap is small (a
 *  nose tip), the back of the head behind it large, where a head's sides are alike (ears,
 *  cheeks) and its crown is round: the front is the end whose cap is the smallest among those
 *  whose opposite end's cap is FP_HEAD_NOSE_CONTRAST times larger or more. Measured on
 *  ../shared/data's faces, all along +z: ICT 0.051 against 0.47 behind (its sides 0.070
 *  each), Lee Perry-Smith 0.056 against 0.22 (his crown 0.21 against his shoulders' 0.69),
 *  MediaPipe's mask 0.019 against 0.40; a smooth head with a nose 2.4 units out of 9.5,
 *  0.040 against 0.39. up_axis: of the two other axes the one the mesh is longer along (a
 *  head is taller than wide); its sign is not decided. Returns 0 with *out, -ENOENT where no
 *  end stands out, -EINVAL (NULL, no vertex, a flat or non-finite mesh). Pure; any thread. */
#define FP_HEAD_CAP_DEPTH 0.1
#define FP_HEAD_NOSE_CONTRAST 3.0
typedef struct fp_head_front {
    int axis;       /* 0, 1, 2: x, y, z */
    int sign;       /* +1 or -1 */
    int up_axis;    /* the longer of the two others */
    double cap, opposite; /* the nose's cap and the opposite end's, as above */
} fp_head_front;
int fp_head_nose(const float *pos, size_t n, const uint8_t *used, fp_head_front *out);

/** Whether a face with no rig and no --up/--facing (taken to look along +z with +y up)
 *  probably looks elsewhere: where the mean vertex lies off the box's middle most along another
 *  axis than +z (a face's detailed front: on the shared faces 0.16-0.23 of the depth in front,
 *  under 0.11 off along x and y), or, for evenly spread vertices, where its nose
 *  (fp_head_nose) points elsewhere. True with the hint in msg (len bytes; no prefix: it names
 *  the axis and the --up/--facing to give), false where it looks along +z or cannot be told.
 *  `used` as fp_head_detect_used. What `run` and `calibrate` warn with. Pure; any thread. */
bool fp_head_facing_hint(const float *pos, size_t n, const uint8_t *used, char *msg, size_t len);

/** The face's size across, in millimetres, for a given scale: diagonal (the mesh's
 *  bounding-box diagonal, mesh units) x mm_per_unit, into *across_mm (may be NULL). Returns
 *  true when it is a face a hand can reach, 1 mm to 1 km (FP_HEAD_ACROSS_MIN_MM ..
 *  FP_HEAD_ACROSS_MAX_MM); false for a slip of units (mm per unit for units per mm, a power
 *  of ten too many), NaN included. The session checks a given scale with it, and calibrate
 *  its --mm-per-unit. Thread-safe. */
#define FP_HEAD_ACROSS_MIN_MM 1.0
#define FP_HEAD_ACROSS_MAX_MM 1e6
bool fp_head_scale_plausible(double diagonal, double mm_per_unit, double *across_mm);

/** The frontmost surface at (x, y): the largest z of the vertices within r (in the x-y
 *  plane) of (x, y) whose y lies in [y_lo, y_hi]. Returns 1 with *z, or 0 where no vertex is
 *  that close. */
int fp_head_surface_z(const float *pos, size_t n, float x, float y, float r, float y_lo,
                      float y_hi, float *z);

#ifdef __cplusplus
}
#endif
#endif
