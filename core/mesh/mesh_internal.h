/* Internal to core/mesh: helpers shared by the C part (mesh.c) and the C++ I/O shim. */
#ifndef FP_MESH_INTERNAL_H
#define FP_MESH_INTERNAL_H

#include "fp_mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Format a message into err (if err && errlen): "path: message". Returns `code`. */
int fp__mesh_error(char *err, size_t errlen, int code, const char *path, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/** What a strict scan of OBJ text found. */
typedef struct fp__obj_info {
    size_t v, vt, vn;  /* counts of v, vt, vn lines */
    size_t faces;      /* f lines */
    size_t triangles;  /* sum over f lines of (corners - 2) */
    size_t degenerate; /* f lines with fewer than 3 distinct vertices (OpenMesh drops them) */
} fp__obj_info;

/** Check OBJ text (NUL-terminated, len bytes) line by line: known statements only; v, vt, vn
 *  with the right count of numbers, all finite; f with at least 3 corners v[/vt][/vn] whose
 *  indices (1-based, or negative = relative) are in range. Errors read "path: line N: reason".
 *  Returns FP_MESH_OK or FP_MESH_ERR_FORMAT. */
int fp__obj_scan(const char *path, const char *text, size_t len, fp__obj_info *info,
                 char *err, size_t errlen);

/** Check ASCII OFF text the way OpenMesh's reader consumes it (header line, a line of three
 *  counts, one vertex per line with finite numbers, one face per line "k i1 .. ik" with
 *  indices < vertex count); binary OFF passes unchecked. "path: line N: reason" errors.
 *  Returns FP_MESH_OK or FP_MESH_ERR_FORMAT. */
int fp__off_scan(const char *path, const char *text, size_t len, char *err, size_t errlen);

/** ASCII PLY: every token after end_header is a finite number (binary PLY passes).
 *  ASCII STL: known keywords only; facet normals and vertices with 3 finite numbers.
 *  "path: line N: reason" errors. Return FP_MESH_OK or FP_MESH_ERR_FORMAT. */
int fp__ply_scan(const char *path, const char *text, size_t len, char *err, size_t errlen);
int fp__stl_ascii_scan(const char *path, const char *text, size_t len, char *err,
                       size_t errlen);

/** The extension of path after its last dot, lower-cased into ext (size extlen; "" when none). */
void fp__mesh_extension(const char *path, char *ext, size_t extlen);

#ifdef __cplusplus
}
#endif

#endif
