/* fp_mesh: the triangle mesh facepuppet deforms, and its file I/O.
 *
 * A mesh is a flat set of arrays (positions, normals, optional UVs, triangles) that C code
 * reads and writes directly; the deformation engine works on `positions` in place and calls
 * fp_mesh_compute_normals() after each frame. Files are read and written through OpenMesh
 * (OBJ, PLY, OFF, STL) and tinygltf (glTF 2.0 .gltf and .glb) behind this C API; the C++ stays
 * inside core/mesh (mesh_io.cpp and its neighbours, mesh_io_internal.hpp).
 *
 * Units: positions are in the file's units (facepuppet calls them "mesh units"); nothing is
 * rescaled. Normals are unit vectors. UVs are as in the file (OBJ/PLY convention, v up; glTF
 * TEXCOORD_0 is stored as in the glTF file, v down, and not flipped).
 *
 * Thread rules: every function is reentrant; different meshes may be used from different
 * threads at once, one mesh from one thread at a time. Load and save may run concurrently:
 * OpenMesh's readers and writers are process-wide singletons with mutable state and its log
 * streams (omerr/omlog/omout) are global, so the OpenMesh part of a load or save is serialised
 * by one internal mutex, during which OpenMesh's log output is captured (used in error
 * messages) instead of printed. glTF I/O runs fully in parallel.
 *
 * Errors: functions return an fp_mesh_result (0 = success, negative = error) and, where they
 * take `err`/`errlen`, write a one-line, NUL-terminated message naming the file and the reason
 * ("path: line N: reason" for OBJ text errors; "path: byte N: reason" in a binary PLY's
 * body). err may be NULL or errlen 0. The library never prints.
 */
#ifndef FP_MESH_H
#define FP_MESH_H

#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Results of the mesh functions: 0 or a negative errno value, as everywhere in the project
 *  (core/common/fp_error.h; fp_strerror() gives the text of any of them). */
typedef enum fp_mesh_result {
    FP_MESH_OK = 0,
    FP_MESH_ERR_NOENT = -ENOENT,        /* the file is not there (or what is there is no
                                           regular file: a folder, FIFO, device) */
    FP_MESH_ERR_ACCESS = -EACCES,       /* the file (or its folder) may not be read/written */
    FP_MESH_ERR_IO = -EIO,              /* a read or write failed (or a save's target is no
                                           regular file: never replaced) */
    FP_MESH_ERR_NOSPACE = -ENOSPC,      /* a save ran out of disk space (old file kept) */
    FP_MESH_ERR_FORMAT = -EBADMSG,      /* malformed content: syntax, NaN/inf, index out of
                                           range, counts that do not fit the file's size, no
                                           vertices or no faces, bad glTF accessor or buffer,
                                           a glTF URI that leaves the file's folder */
    FP_MESH_ERR_UNSUPPORTED = -ENOTSUP, /* unknown file extension, or a feature not handled
                                           (sparse glTF accessors, a glTF with no triangles,
                                           glTF 1.0, KHR_mesh_quantization) */
    FP_MESH_ERR_NOMEM = -ENOMEM,        /* out of memory */
    FP_MESH_ERR_INVALID = -EINVAL       /* bad argument: NULL pointer, inconsistent mesh */
} fp_mesh_result;

/** A triangle mesh. All arrays are owned by the mesh, allocated with malloc() and released
 *  by fp_mesh_free(); a caller may replace an array by its own malloc()ed one of the same
 *  shape (the mesh then owns it). Vertex i has position positions[3i..3i+2]. */
typedef struct fp_mesh {
    size_t vertex_count;     /* n */
    float *positions;        /* n x 3, mesh units */
    float *normals;          /* n x 3, unit length; always present after fp_mesh_load() */
    float *uvs;              /* n x 2, or NULL when the file has no texture coordinates */
    size_t triangle_count;   /* t */
    uint32_t *triangles;     /* t x 3 vertex indices, counter-clockwise seen from outside;
                                polygons of the file are fan-triangulated (0,i,i+1) */
    char *source_path;       /* the path the mesh was loaded from (a copy), or NULL */
    /** What the file held beyond these arrays, kept by fp_mesh_load() so that a save writes
     *  the mesh back as it came in (fp_mesh_save): the polygons with their per-corner UVs,
     *  OBJ materials per face and the OBJ text itself (groups, materials, comments), or the
     *  glTF document (materials, nodes, images). Opaque, immutable, reference-counted:
     *  fp_mesh_copy() shares it, fp_mesh_free() releases it; a shallow struct copy may use it
     *  while the mesh lives. It applies while vertex_count and triangle_count are those
     *  loaded (the engine only moves vertices); NULL for meshes built in memory. */
    struct fp_mesh_source *source;
} fp_mesh;

/** What a save could not keep of the input (fp_mesh_save_ex's *dropped, bit flags). */
enum {
    FP_MESH_DROPPED_POLYGONS = 1u << 0,  /* polygons written as triangles */
    FP_MESH_DROPPED_UV_SEAMS = 1u << 1,  /* per-corner UVs merged per vertex (first use) */
    FP_MESH_DROPPED_UVS = 1u << 2,       /* texture coordinates not written */
    FP_MESH_DROPPED_NORMALS = 1u << 3,   /* vertex normals not written */
    FP_MESH_DROPPED_GROUPS = 1u << 4,    /* OBJ g, o, s statements and comments */
    FP_MESH_DROPPED_MATERIALS = 1u << 5, /* OBJ mtllib/usemtl, glTF materials and images */
    FP_MESH_DROPPED_NODES = 1u << 6,     /* glTF node hierarchy and names, other primitives */
    FP_MESH_DROPPED_PROPERTIES = 1u << 7 /* a PLY's vertex and face properties other than
                                            positions, normals and UVs (colours, flags), its
                                            other elements, an OFF's colours, an OBJ's vertex
                                            colours: read past, never written (but in an OBJ
                                            written back as it came in) */
};

/** The message for a result code: fp_strerror(result) (a static string, never NULL), kept
 *  for older callers. Thread-safe. */
const char *fp_mesh_strerror(int result);

/** Allocate a mesh of n vertices and t triangles with zeroed positions, normals, triangles,
 *  and zeroed uvs when with_uvs is non-zero (else uvs = NULL); source_path = NULL.
 *  Returns NULL when out of memory (or when n or t overflows the allocation size).
 *  The caller frees it with fp_mesh_free(). */
fp_mesh *fp_mesh_create(size_t vertex_count, size_t triangle_count, int with_uvs);

/** Release a mesh and all its arrays and set *mesh to NULL. NULL or *mesh == NULL is a no-op. */
void fp_mesh_free(fp_mesh **mesh);

/** A deep copy of `mesh` (all arrays and source_path), or NULL when out of memory or mesh is
 *  NULL. The caller frees it with fp_mesh_free(). */
fp_mesh *fp_mesh_copy(const fp_mesh *mesh);

/** Read a mesh from `path`, choosing the format by the (case-insensitive) extension:
 *  .obj .ply .off .stl (OpenMesh) and .gltf .glb (tinygltf).
 *
 *  Vertices: OBJ and OFF keep the file's vertex order and count exactly (vertex i is the
 *  i-th `v` line of an OBJ, so index ranges published for a model stay valid); PLY keeps its
 *  vertex element order. STL has no shared vertices: OpenMesh merges corners with equal
 *  positions, in first-use order. glTF: the triangle primitives (mode 4) of the meshes of
 *  the default scene's nodes (scene 0 when none is set; every mesh when the file has no
 *  scene), in node traversal order, each primitive's vertices appended; the node transforms
 *  (matrix or TRS, down the hierarchy) are APPLIED to positions and normals. Other modes
 *  (points, lines, strips, fans) are skipped.
 *
 *  Faces: polygons are fan-triangulated in file order, each giving (corners - 2) consecutive
 *  triangles (0,1,2), (0,2,3), ... OBJ faces that repeat a vertex lose the repeats, and one
 *  left with fewer than 3 distinct vertices is dropped (OpenMesh's OBJ reader does this). An OBJ
 *  line that ends in a backslash (blanks after it allowed) continues on the next, as the
 *  format says (comments too); errors name the line a statement starts on. Normals: the file's vertex normals when every vertex has a finite,
 *  non-zero one (normalised); otherwise computed with fp_mesh_compute_normals(). UVs: per
 *  vertex; OBJ gives a UV per face corner, and a vertex used with several UVs (a texture seam)
 *  takes the UV of its first use in face order. glTF TEXCOORD_0 (float or normalised
 *  unsigned byte/short); where only some primitives have UVs the others get (0, 0).
 *
 *  Hostile files are refused before any third-party parser sees them, in time and memory
 *  bounded by the file's size: PLY headers are checked strictly (element before property,
 *  known types, numeric counts, vertex x, y and z once each, a real end_header; comment and
 *  obj_info lines anywhere after the first) and every value walked; OFF (ASCII and
 *  binary) and STL counts must fit the file's size; every number must be finite as a float;
 *  glTF buffers and images are read only from data URIs or relative paths that stay inside
 *  the file's folder (after normalisation and symlinks) and name regular files (one that is
 *  not there, or not a regular file, is NOENT and one not readable ACCESS, as the glTF file
 *  itself, the message naming the URI and the path; one that leaves the folder FORMAT); glTF 2.0
 *  only (GLB header version 2, asset.version 2.x); every index in the JSON an integer from
 *  0 (a negative "indices" is refused, not read as absent); POSITION and NORMAL FLOAT,
 *  TEXCOORD_0 FLOAT or normalised unsigned byte/short; node matrix 16 numbers, translation
 *  3, rotation 4, scale 3, a matrix or TRS, not both. The path
 *  itself must name a regular file (a FIFO or device is refused, never opened blocking).
 *
 *  On success *out is a new mesh (free with fp_mesh_free()) with source_path set and
 *  FP_MESH_OK is returned. On error *out is NULL and a negative errno code is returned, with
 *  a message "path: [line N: ]reason": NOENT (missing), ACCESS (unreadable), IO (read error,
 *  not a regular file), FORMAT (empty file, syntax, NaN/inf values, counts beyond the file's
 *  size, face index out of range, no vertices, no faces, glTF buffer missing, refused or
 *  accessor out of bounds, an index or component type glTF 2.0 does not allow, a node
 *  transform of the wrong length, a PLY vertex without x, y or z), UNSUPPORTED (extension,
 *  sparse accessors, binary COFF, > 2 GiB, glTF 1.0, KHR_mesh_quantization),
 *  NOMEM, INVALID (NULL path or out).
 *  Thread rules: see the top of this file. */
int fp_mesh_load(const char *path, fp_mesh **out, char *err, size_t errlen);

/** Write `mesh` to `path` in the format of its extension (as fp_mesh_load()), overwriting.
 *  Written data: positions and triangles always; normals and UVs when present:
 *  OBJ: v, vt (when uvs), vn (when normals), f v/vt/vn, 9 significant digits (float exact).
 *  PLY: x y z nx ny nz u v properties, faces as uchar/int lists; binary little-endian, or
 *  as the PLY or STL the mesh was loaded from was (while its source applies, see fp_mesh):
 *  ASCII (9 digits) from ASCII, big-endian from a big-endian PLY.
 *  OFF: ASCII, 9 digits; header "NOFF", "STOFF" or "STNOFF" as normals/uvs are written.
 *  STL: triangles with their face normals only (no vertex normals, no UVs); binary, or ASCII
 *  where the mesh was loaded from an ASCII PLY or STL (as PLY above).
 *  glTF: one mesh, one triangle primitive with POSITION (with min/max), NORMAL, TEXCOORD_0
 *  and uint32 indices, one node, one scene; .gltf embeds the buffer as a base64 data URI,
 *  .glb puts it in the binary chunk.
 *  Never half-written: the file is written to a temporary file in the same folder
 *  (".NAME.XXXXXX"), every write checked, fsync()ed, then renamed over `path`; on any failure
 *  the temporary file is removed and an existing file at `path` is left unchanged. A
 *  replaced file keeps its mode; a new one gets 0666 & ~umask. (A process killed during the
 *  write may leave its temporary file behind, never a broken `path`.)
 *  Returns FP_MESH_OK, or INVALID (NULL arguments, index out of range, non-finite position),
 *  NOENT (no such folder), ACCESS (folder not writable), NOSPACE (disk full), IO (another
 *  write failure, e.g. EFBIG), UNSUPPORTED (extension), NOMEM, with a message naming path. */
int fp_mesh_save(const fp_mesh *mesh, const char *path, char *err, size_t errlen);

/** fp_mesh_save(), and in *dropped (may be NULL) what the file at `path` could not keep of
 *  what the mesh came in with (FP_MESH_DROPPED_* bits; 0 when nothing was lost).
 *
 *  Written back as it came in: where mesh->source applies (see fp_mesh), a mesh saved in the
 *  format it was loaded from keeps everything but positions and normals:
 *  OBJ: the file's text line for line (a line continued with a backslash comes back joined,
 *  an empty line after it; comments, mtllib, usemtl, g, o, s, vt and f lines
 *  unchanged; the .mtl is never opened), with each `v` line's x y z replaced (any further
 *  numbers on the line kept) and each `vn` line replaced by the normal of the first vertex
 *  that uses it (when the file had vn lines): quads stay quads, UV seams stay seams.
 *  glTF/GLB: the document (nodes, materials, images, other attributes, morph targets) with
 *  POSITION (min/max updated) and NORMAL of each triangle primitive rewritten in the node's
 *  local frame (the inverse of the transform fp_mesh_load() applied); a mesh that several
 *  nodes place (one copy per node in fp_mesh) keeps one mesh while the copies agree, and a
 *  node whose copy differs from the first gets a copy of the mesh (named NAME_nodeN) with
 *  its own POSITION and NORMAL, so every copy comes back as saved; a node whose transform
 *  is singular (a scale of 0 flattens its mesh) keeps its transform and children but not the
 *  mesh, whose copy goes as it is (mesh units) onto a new root node NAME_deformed of the
 *  scene; the buffers become one
 *  (embedded in .gltf as base64, the BIN chunk of .glb); image URIs are kept as written.
 *  Another format keeps what it can hold: PLY and OFF write the file's polygons (per-vertex
 *  UVs: seams dropped); glTF from an OBJ splits vertices at UV seams (one glTF vertex per
 *  (vertex, UV) pair; OBJ's v-up UVs flipped to glTF's v-down), one primitive per OBJ
 *  material (named, default PBR values) with its own block of the vertices its triangles
 *  use, triangles; where glTF vertex j is not mesh vertex j, mesh.extras.sourceVertex lists
 *  the mesh vertex of every glTF vertex (the primitives' blocks in order). Returns as fp_mesh_save(). */
int fp_mesh_save_ex(const fp_mesh *mesh, const char *path, unsigned *dropped, char *err,
                    size_t errlen);

/** "polygons, UV seams, ..." naming the FP_MESH_DROPPED_* bits of `dropped` into buf (n
 *  bytes); "" for 0. Returns buf. */
const char *fp_mesh_dropped_text(unsigned dropped, char *buf, size_t n);

/** About how many bytes fp_mesh_save() of `mesh` to a .obj writes (a frame of --frames-out or
 *  of an obj-seq export, for the room it needs): an OBJ written back as it came in, its text
 *  with each v and vn line's numbers at the typical length of three "%.9g" coordinates; any
 *  other, the v, vn and vt lines and the faces' corners with their UV and normal indices
 *  (each index counted at the vertex count's digits). 0 for NULL. Thread-safe (reads mesh). */
double fp_mesh_obj_bytes(const fp_mesh *mesh);

/** A morph-target animation for fp_mesh_save_animation(). */
typedef struct fp_mesh_morph_animation {
    size_t target_count;           /* K >= 1 */
    const float *targets;          /* K x n x 3 position displacements, mesh units */
    const char *const *target_names; /* K names (mesh.extras.targetNames), or NULL: "t0".. */
    size_t frame_count;            /* F >= 1 */
    const float *times;            /* F key times, seconds, strictly increasing */
    const float *weights;          /* F x K: weights of the targets at each key */
    int step;                      /* 0: LINEAR sampler, 1: STEP */
    const char *name;              /* the animation's name, or NULL */
    double unit_scale;             /* > 0: metres per mesh unit, written as the uniform scale
                                      of a root node (named "NAME_metres", "take_metres")
                                      whose one child is the mesh's node, so that readers
                                      place the mesh in metres (glTF 2.0 3.4: units are
                                      metres); the vertices stay in mesh units. 0: no root
                                      node (the mesh's node is the scene's) */
    double frame_rate;             /* > 0: the frames' rate, frames per second, named in
                                      asset.extras.frameRate and the animation's
                                      extras.frameRate (glTF has no field of its own for it;
                                      the keys' times are in seconds). 0: not named */
    double up[3], facing[3];       /* the mesh's up and the axis its front looks along (the
                                      face's: fp_session_face_axes); with unit_scale > 0 the
                                      root node also turns them to glTF's +y up and +z front
                                      (glTF 2.0 3.4), a rotation quaternion: each taken as the
                                      mesh axis nearest it (quarter and half turns only). All
                                      zeros, or nearest +y and +z: no turn */
} fp_mesh_morph_animation;

/** Write `mesh` as glTF 2.0 (.gltf, buffer embedded as base64, or .glb) with morph targets
 *  and one animation whose `weights` channel plays `anim` (glTF 2.0 sections 3.7.2.2 morph
 *  targets, 3.11 animations). The base mesh is written as fp_mesh_save_ex() writes a glTF
 *  from a non-glTF input (UV seams split, one primitive per OBJ material, names of targets
 *  in mesh.extras.targetNames, mesh.extras.sourceVertex); each
 *  primitive gets K POSITION targets (accessors with min/max) sharing the vertex set. From a
 *  glTF input the document's nodes and materials are not kept (*dropped says so).
 *  Buffer views carry their target (34962/34963) except the animation's. anim->unit_scale
 *  adds the root node of that scale, turned by anim->up and ->facing (the animation's channel
 *  stays on node 0, the mesh's);
 *  anim->frame_rate names the rate in extras. Atomic as
 *  fp_mesh_save(). Returns FP_MESH_OK, INVALID (bad arguments, non-finite values, times not
 *  increasing), UNSUPPORTED (extension other than gltf/glb), and the save's codes. */
int fp_mesh_save_animation(const fp_mesh *mesh, const fp_mesh_morph_animation *anim,
                           const char *path, unsigned *dropped, char *err, size_t errlen);

/** What a glTF file held beyond the triangles fp_mesh_load() takes from it. */
typedef struct fp_mesh_gltf_info {
    size_t nodes, meshes, materials;
    size_t morph_targets;    /* the most POSITION targets of one primitive (glTF 2.0 3.7.2.2) */
    size_t animations;
    size_t channels;         /* over every animation */
    size_t weights_channels; /* of them, those that drive morph target weights */
    size_t keys;             /* the most keyframes of one channel's sampler (its input count) */
    double duration_s;       /* the latest key time (the input accessors' max), seconds */
    double frame_rate;       /* asset.extras.frameRate (the project's exports name it), or 0 */
    double metres_per_unit;  /* asset.extras.metresPerUnit (the same), or 0 */
    double root_scale;       /* the uniform scale of the default scene's one root node: 1
                                without a scale; 0 where there are several roots, a matrix
                                or a non-uniform scale */
    char animation[64];      /* the first animation's name ("" none) */
    char generator[64];      /* asset.generator */
} fp_mesh_gltf_info;

/** The glTF document a mesh was loaded from (fp_mesh_load of a .gltf or .glb: its source),
 *  summarised into *out (zeroed first). Returns FP_MESH_OK, or FP_MESH_ERR_INVALID when mesh
 *  or out is NULL or the mesh did not come from a glTF file. Reads only; thread-safe on a
 *  const mesh. */
int fp_mesh_gltf_summary(const fp_mesh *mesh, fp_mesh_gltf_info *out);

/** Area-weighted vertex normals (each triangle adds its unnormalised cross product
 *  (p1-p0) x (p2-p0), whose length is twice its area, to its three vertices; then each sum is
 *  normalised). Shapes: tris t x 3, pos n x 3, normals_out n x 3 (may not alias pos).
 *  A vertex in no triangle of non-zero area gets (0, 0, 0). Counter-clockwise triangles give
 *  outward normals. No allocation, O(n + t); cheap enough for every frame.
 *  Returns FP_MESH_OK, or FP_MESH_ERR_INVALID when a pointer is NULL (with n or t > 0) or an
 *  index is >= n (normals_out is then all zero). Reentrant. */
int fp_mesh_normals(const uint32_t *tris, size_t t, const float *pos, size_t n,
                    float *normals_out);

/** Vertex -> triangle adjacency (compressed rows) for fp_mesh_normals_at: vertex v's
 *  triangles are (*vt)[(*vt_start)[v] .. (*vt_start)[v + 1]), in increasing triangle order (a
 *  triangle naming v twice is listed twice). Shapes: tris t x 3, *vt_start n + 1, *vt 3t
 *  uint32; both malloc()ed, the caller frees them. Returns FP_MESH_OK, FP_MESH_ERR_INVALID
 *  (NULL, an index >= n, n or 3t beyond uint32) or FP_MESH_ERR_NOMEM (*vt_start and *vt are
 *  then NULL). O(n + t). Reentrant. */
int fp_mesh_vertex_triangles(const uint32_t *tris, size_t t, size_t n, uint32_t **vt_start,
                             uint32_t **vt);

/** The normals of the `count` vertices verts[i] only, bit for bit what fp_mesh_normals
 *  writes for them (each vertex's cross products summed in triangle order, normalised in
 *  double), from fp_mesh_vertex_triangles' adjacency of the same triangles. A vertex's
 *  normal depends on its triangles only: after positions changed at a set of vertices, the
 *  normals to recompute are those of every vertex of a triangle that has a changed vertex
 *  (ui/viewer's partial uploads). normals_out is n x 3; other entries are left alone.
 *  O(sum of the vertices' triangle counts); no allocation; no checks (indices come from
 *  the adjacency). Reentrant. */
void fp_mesh_normals_at(const uint32_t *tris, const uint32_t *vt_start, const uint32_t *vt,
                        const float *pos, const uint32_t *verts, size_t count,
                        float *normals_out);

/** fp_mesh_normals() on the mesh's own arrays, allocating mesh->normals if it is NULL.
 *  Returns as fp_mesh_normals(), or FP_MESH_ERR_NOMEM. */
int fp_mesh_compute_normals(fp_mesh *mesh);

/** Axis-aligned bounds of the positions: min[k] and max[k] for k = x, y, z (mesh units).
 *  A mesh without vertices (or NULL) gives all zeros. */
void fp_mesh_bounds(const fp_mesh *mesh, float min[3], float max[3]);

/** The surface's vertices: *unused := how many vertices are a corner of no triangle (a
 *  stray point an exporter left: drawn nowhere, no part of the surface); *used := a mask of
 *  vertex_count bytes, used[v] = 1 where v is in a triangle, else 0 (malloc'ed, the caller
 *  frees it), or NULL where every vertex is in one or the mesh has no triangles (then
 *  *unused = 0), so that NULL means "all" to fp_mesh_bounds_used and fp_head_detect_used.
 *  The mesh's indices are < vertex_count (as every loader checks). Returns 0, or -ENOMEM
 *  (*used NULL, *unused 0). */
int fp_mesh_surface_mask(const fp_mesh *mesh, uint8_t **used, size_t *unused);

/** The surface's far-off vertices, a stray spike's tip (one long thin triangle an exporter or
 *  a slip in a modeller left): per axis, the 0.5th and 99.5th percentiles p_lo, p_hi of the
 *  coordinates of the vertices in *used (NULL: all); a vertex beyond p_hi + s (p_hi - p_lo)
 *  or below p_lo - s (p_hi - p_lo) on any axis, s = FP_MESH_OUTLIER_SPAN, is far off and
 *  used[v] is cleared (a spike 30 mm out of a 21 mm deep head lies 1.35 of the depth out;
 *  the real faces' farthest, the ICT face's shoulders along x, 0.23). *used, n bytes as
 *  fp_mesh_surface_mask gives it, is malloc'ed here (all 1, then cleared) when NULL and one
 *  is found; the caller frees it. *outliers: how many were cleared. Fewer than 4 used
 *  vertices: none. The session and calibrate leave them out of the face's size, head and
 *  the hands' placement, as points in no triangle. Returns 0, or -ENOMEM (*used unchanged,
 *  *outliers 0). Pure but for *used; any thread. */
#define FP_MESH_OUTLIER_SPAN 0.5
int fp_mesh_outlier_mask(const fp_mesh *mesh, uint8_t **used, size_t *outliers);

/** The face's vertices, as the session and calibrate count them: fp_mesh_surface_mask (in a
 *  triangle) then fp_mesh_outlier_mask (not far off the rest). *used: vertex_count bytes,
 *  1 for a face vertex, malloc'ed (the caller frees it), or NULL where every vertex is one;
 *  *unused: the vertices in no triangle, *outliers: the far-off ones cleared after them.
 *  Returns 0, or -ENOMEM (*used NULL, both counts 0). Pure but for its outputs; any thread. */
int fp_mesh_face_mask(const fp_mesh *mesh, uint8_t **used, size_t *unused, size_t *outliers);

/** The typical edge length (mesh units) where the mesh is the face: the median of the edge
 *  lengths of the triangles whose three corners are in used (NULL: every triangle), measured
 *  on at most 65,536 triangles taken at an even stride (a 1.7M-vertex face costs what a small
 *  one does). *median := 0 when no triangle counts. Scratch: 12 bytes a triangle measured.
 *  Indices must be < vertex_count (not checked). Returns 0, or -ENOMEM (*median 0).
 *  Pure; any thread. */
int fp_mesh_median_edge(const fp_mesh *mesh, const uint8_t *used, double *median);

/** fp_mesh_bounds over the vertices v with used[v] != 0 (used NULL: every vertex; none used:
 *  all zeros): the surface's bounds, without points in no triangle. */
void fp_mesh_bounds_used(const fp_mesh *mesh, const uint8_t *used, float min[3], float max[3]);

/** Midpoint subdivision: a new mesh with every triangle of `mesh` cut into four at the
 *  midpoints of its edges, each edge's midpoint one vertex shared by the triangles on it.
 *  Shapes: the result has n + e vertices and 4t triangles (n, t: the input's; e: its
 *  distinct edges, an edge being an unordered vertex pair). Vertices 0 .. n-1 are the
 *  input's positions; vertex n + i is the midpoint 0.5 (p_a + p_b) (float, mesh units) of the
 *  i-th edge (a, b), a < b, in increasing (a, b) order. Triangle k's four, 4k .. 4k+3, are
 *  (v0, m01, m20), (v1, m12, m01), (v2, m20, m12) and (m01, m12, m20), mij the midpoint of
 *  edge (vi, vj): the input's orientation is kept. Normals computed as
 *  fp_mesh_compute_normals(); no UVs, no source, no source_path. Deterministic: the same mesh
 *  gives the same result bit for bit. Three levels make the ICT face (26,719 vertices) about
 *  1.7M vertices: `facepuppet bench --case frame`'s large face, the viewer's tests.
 *  mesh must be consistent: every index < vertex_count (not checked).
 *  Errors: NULL for a NULL mesh (or NULL arrays under non-zero counts), n + e beyond 32-bit
 *  indices (UINT32_MAX), or out of memory. Cost: O(t log t) time (a sort of the 3t edges),
 *  48 bytes of scratch a triangle besides the result.
 *  Ownership: the result is the caller's (fp_mesh_free()); mesh is only read.
 *  Thread rules: reentrant; other threads may read mesh meanwhile. */
fp_mesh *fp_mesh_subdivide(const fp_mesh *mesh);

#ifdef __cplusplus
}
#endif

#endif
