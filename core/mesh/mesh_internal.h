/* Internal to core/mesh: what its C files (mesh.c, the scans mesh_scan_*.c) and its C++
 * (mesh_io_internal.hpp) share. */
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
    size_t usemtl;     /* usemtl lines */
    size_t groups;     /* g and o lines */
    size_t mtllib;     /* mtllib lines */
    size_t colours;    /* v lines with a colour (6 or 7 numbers) */
} fp__obj_info;

/** Check OBJ text (NUL-terminated, len bytes) line by line: known statements only; v, vt, vn
 *  with the right count of numbers, all finite; f with at least 3 corners v[/vt][/vn] whose
 *  indices (1-based, or negative = relative) are in range. Errors read "path: line N: reason".
 *  Returns FP_MESH_OK or FP_MESH_ERR_FORMAT. */
int fp__obj_scan(const char *path, const char *text, size_t len, fp__obj_info *info,
                 char *err, size_t errlen);

/** OBJ's line continuation (Wavefront, appendix B1: a backslash at the end of a line
 *  continues it on the next), resolved in place before the scan and OpenMesh's reader (which
 *  reads the backslash as a token): each backslash that only blanks separate from the end of
 *  its line becomes a space with those blanks, and its newline moves to the end of the joined
 *  line (an empty line after it; a CR LF stays a CR LF), so the text keeps its length and every statement its line
 *  number (a joined statement's: its first line's). Comment lines continue too, as the
 *  format says. Returns the number of lines joined onto the one before. */
size_t fp__obj_join_continuations(char *text, size_t len);

/** Check OFF text the way OpenMesh's reader consumes it. ASCII: header line, a line of three
 *  counts (which must fit the file's size), one vertex per line with finite numbers, one
 *  face per line "k i1 .. ik" with indices < vertex count and nothing after them unless the
 *  header has colours (COFF: colours of 1 to 4 values as OpenMesh counts them). Binary ("[ST][N]OFF BINARY"):
 *  counts, finite floats, corner counts and indices walked exactly to the file's end.
 *  *nv and *nf get the header's counts. "path: line N: reason" errors.
 *  Returns FP_MESH_OK, FP_MESH_ERR_FORMAT or FP_MESH_ERR_UNSUPPORTED (binary COFF). */
int fp__off_scan(const char *path, const char *text, size_t len, size_t *nv, size_t *nf,
                 char *err, size_t errlen);

/** PLY, before OpenMesh sees it (its reader crashes or loops on bad headers): a strict
 *  header ("ply", one format line, 'element NAME COUNT' before its 'property TYPE NAME' or
 *  'property list CTYPE TYPE NAME' lines, known types, numeric counts, vertex x, y, z once
 *  each, a real end_header; comment and obj_info lines anywhere after line 1, which the
 *  loader leaves out of what OpenMesh reads), counts against the file's size, then every
 *  value walked: ASCII tokens of the right type and range (floats finite), binary sizes
 *  exact to the file's end, list counts, face indices < vertex count. *nv and *nf get the
 *  header's vertex and face counts, *format its encoding (0 ascii, 1 binary_little_endian,
 *  2 binary_big_endian; -1 on error). Errors in a binary body say "byte N" (the offset).
 *  ASCII STL: solid / facet normal / outer loop / 3 vertex / endloop / endfacet / endsolid in
 *  order, 3 finite numbers where numbers belong.
 *  "path: line N: reason" errors. Return FP_MESH_OK, FP_MESH_ERR_FORMAT or NOMEM. */
int fp__ply_scan(const char *path, const char *text, size_t len, size_t *nv, size_t *nf,
                 int *format, char *err, size_t errlen);
int fp__stl_ascii_scan(const char *path, const char *text, size_t len, char *err,
                       size_t errlen);
/** Binary STL (len == 84 + 50 x the count at byte 80, checked by the caller): every corner's
 *  3 floats finite (OpenMesh's reader merges corners by position, and a NaN corner would be
 *  welded to another vertex unseen); the facet normals are not read. "path: triangle N
 *  (byte B): reason" errors. Returns FP_MESH_OK or FP_MESH_ERR_FORMAT. */
int fp__stl_binary_scan(const char *path, const char *data, size_t len, char *err, size_t errlen);

/** Reference counting of fp_mesh_source (mesh_source.cpp): ref returns src. */
struct fp_mesh_source *fp__mesh_source_ref(struct fp_mesh_source *src);
void fp__mesh_source_unref(struct fp_mesh_source *src);

/** The extension of path after its last dot, lower-cased into ext (size extlen; "" when none). */
void fp__mesh_extension(const char *path, char *ext, size_t extlen);

#ifdef __cplusplus
}
#endif

#endif
