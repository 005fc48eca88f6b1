/* fp_rig: rig files (rigs/README.md) and the frame's step 4: a skull that stays, a jaw that
 * turns about its hinge, landmarks and channels that mappings can aim at.
 *
 * A rig file (JSON) names, for one mesh: its unit (mm_per_unit) and face axes; regions of
 * vertices (skull: never moves; jaw: turns rigidly about the hinge; soft: everything else);
 * the jaw hinge (the axis through the two temporomandibular joints), its opening angle and
 * the soft-tissue falloff; landmarks by vertex index; channels (named scalars with ranges).
 *
 * Typical use (the session's rig step, once per frame):
 *
 *     fp_rig *rig;
 *     fp_rig_load_for_mesh(path, n, rest_positions, &rig, err, sizeof err);  // load + bind
 *     float vals[FP_RIG_MAX_CHANNELS];
 *     fp_rig_channel_values(rig, names, values_in, control_set.channel_count, vals);
 *     fp_rig_pose(rig, base, vals, posed);          // the jaw about its hinge
 *     // the engine: csrbf_points on `posed`, fingers' control vectors start -> end,
 *     csrbf_evaluate(solver, posed_points, warped, 0, NULL);
 *     fp_rig_apply_mobility(rig, posed, warped, out);  // skull and jaw exactly as posed
 *
 * Keeping the skull still under the fingers: the mobility weight (chosen approach).
 * Each vertex has a mobility m in [0, 1]: 0 on every skull and jaw vertex, rising smoothly
 * (smoothstep) with the distance d to the nearest skull or jaw vertex to 1 at d >= ramp
 * (rig field "mobility.ramp", mesh units). The fingers' map T (any engine result) is blended
 * per vertex: out = posed + m * (T(posed) - posed), and vertices with m == 0 are copied bit
 * for bit. Why this and not extra CSRBF constraint centres (zero displacement on the skull,
 * the hinge motion on the jaw) solved with the fingers:
 *  - exactness: an interpolating CSRBF only pins its centres; every skull vertex between
 *    centres would still move a little, so a mask is needed anyway to make it exactly 0;
 *  - cost: the factorization of the fingers alone is untouched (10 centres, not 1000-5000),
 *    and the blend is one multiply-add per vertex;
 *  - injectivity: centres of zero displacement next to a finger force steep coefficients
 *    (the fold-over guard trips); the blend's Jacobian is I + m J_T + (T - x) grad(m)^T,
 *    whose extra term is bounded by |T - x| |grad m|. T - x vanishes outside the fingers'
 *    supports (radius R about each start point), so the bound is local: a finger whose
 *    support reaches vertices of slope at most G = max |grad m| keeps the extra term below
 *    FP_RIG_FINGER_MARGIN (1/2) when its control vector is at most 1/2 / G
 *    (fp_rig_finger_limit; no limit where m is flat, i.e. soft tissue farther than the ramp
 *    from bone, where only the engine's own 0.45 R guard applies). The worst case anywhere
 *    is ramp / 3 (smoothstep's steepest slope 1.5 / ramp): fp_rig_max_finger_displacement().
 *    Sharper, by direction (fp_rig_finger_limit_toward, what the session clamps by): the
 *    extra term is rank one, so I + (T - x) grad(m)^T has the eigenvalues 1, 1 and
 *    1 + grad(m) . (T - x): only a motion toward the bone (against grad m) squeezes the ramp,
 *    and a pull away from it or along it stretches or shears the skin without folding it. The
 *    clamp then bounds |control vector| * psi(rho / R) * |grad m| * max(0, -cos) <= 1/2 over
 *    the vertices of the ramp within R of the vector's whole segment (the capsule the
 *    engine's composed sub-steps sweep; rho a vertex's distance to it, psi Wendland's
 *    psi_{3,1}: T - x at rho from a centre that moves by the vector, one finger alone), with
 *    no limit for a pull away from every bone it reaches. The session keeps a vector within
 *    that bound by cutting its push alone (fp_rig_finger_clamp_indexed: the vector
 *    projected onto the pushes' constraints, the nearest one meeting them), not by
 *    shortening the whole vector, so a drag along the cheek with a little push toward the
 *    cheekbone keeps its drag (what that changed: docs/performance.md, "The rig cuts the
 *    push only"). A fold the bound misses (fingers' fields adding up) is a flipped triangle
 *    the session's contact guard sees and holds back.
 * The rig's pose itself (the jaw about its hinge, rotated by a smooth fraction of the angle)
 * is applied before the fingers, so a finger's start point is taken on the posed base.
 *
 * Units: positions in mesh units (the mesh file's own), angles in degrees in the file and
 * the API unless named _rad. Thread rules: a bound rig is immutable; every const function
 * may run concurrently from any thread ([any-thread]). Load, bind and free: one thread.
 * Errors: 0 or a negative errno (fp_error.h); a message naming the file and the field as a
 * JSON path ("rigs/x.json: jaw.hinge.left[2]: expected a number") goes into err.
 * The library never prints. Link: static library fp_rig (cJSON, zlib, libm).
 */
#ifndef FP_RIG_H
#define FP_RIG_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The rig format version this library reads (the file's "version"). */
#define FP_RIG_FORMAT_VERSION 1
/** At most this many channels, regions and landmarks in one rig. */
#define FP_RIG_MAX_CHANNELS 32
#define FP_RIG_MAX_REGIONS 64
#define FP_RIG_MAX_LANDMARKS 256
/** The regions' spans list at most this many times mesh.vertex_count vertices in all, repeats
 *  within a region included (a vertex in two regions is refused anyway). */
#define FP_RIG_LISTED_MAX 4
/** Longest name (region, landmark, channel), bytes, without the NUL. */
#define FP_RIG_NAME_MAX 31

/** Kind of a region / a vertex. Same numbers as fp_rig_region of plugin.h (ABI 1.1). */
enum {
    FP_RIG_SOFT = 0,   /* soft tissue: posed by the falloff, free for the fingers */
    FP_RIG_SKULL = 1,  /* rigid with the skull: never moves (bit-identical) */
    FP_RIG_JAW = 2     /* rigid with the jaw: turns about the hinge, fingers cannot move it */
};

typedef struct fp_rig fp_rig;

/** One region of the file: name, kind, number of vertices. */
typedef struct fp_rig_region_desc {
    const char *name;
    int kind;          /* FP_RIG_SOFT / SKULL / JAW */
    size_t count;      /* vertices listed (after removing repeats) */
} fp_rig_region_desc;

/** One channel: name, range, neutral value (the value at rest). */
typedef struct fp_rig_channel_desc {
    const char *name;
    float min, max, neutral;
} fp_rig_channel_desc;

/** Parse a rig from `len` bytes of JSON (need not be NUL-terminated). `name` (e.g. the file
 *  path) starts every message. Checks the structure, every type, unknown fields, ranges,
 *  index ranges against the file's own mesh.vertex_count, overlapping regions, landmark and
 *  channel names, axes (unit, orthogonal, right-handed: left = up x forward), that the
 *  hinge axis runs along the left axis (within 30 degrees), and jaw.weights (soft vertices
 *  only, none twice, one value in [0, 1] each; memory bounded by the values in the file). The rig is not yet bound to a
 *  mesh: fp_rig_bind() must follow before posing.
 *  Returns 0 and *out (free with fp_rig_free), or -EBADMSG (malformed or invalid; message
 *  "NAME: json.path: reason"), -ENOMEM, -EINVAL (NULL arguments). Never crashes on any bytes
 *  (fuzzed: tests/fuzz/fuzz_rig.c). */
int fp_rig_parse(const char *json, size_t len, const char *name, fp_rig **out, char *err,
                 size_t errlen);

/** The largest rig file fp_rig_load reads: 32 MiB (ICT's is 64 kB; a weight for every vertex of
 *  a million-vertex mesh about 10 MB), so that parsing needs at most about 1.3 GB. */
#define FP_RIG_FILE_MAX ((size_t)32 << 20)

/** Read and parse a rig file. Errors as fp_rig_parse (a file over FP_RIG_FILE_MAX: -EBADMSG), plus
 *  the file's own codes (-ENOENT, -EACCES, -EISDIR, -ENXIO: a folder, FIFO or device;
 *  fp_file_read_all), -ENOMEM, -EIO. */
int fp_rig_load(const char *path, fp_rig **out, char *err, size_t errlen);

/** Bind a parsed rig to its mesh's rest positions (n x 3 floats, mesh units): checks that
 *  n equals the rig's mesh.vertex_count and that each hinge point lies inside the mesh's
 *  bounding box and within 60 mm of a vertex (a hinge "inside nothing" is refused), then
 *  computes the per-vertex jaw weights (the falloff, or the file's jaw.weights for the soft
 *  vertices it lists) and mobility weights. The checksum
 *  (mesh.positions_crc32) need not match: a rig fits any shape of its topology (an identity
 *  morph, a committed base); fp_rig_checksum_matches() tells. O(n) plus a grid search.
 *  Returns 0, -EBADMSG (does not fit; message names the field), -ENOMEM, -EINVAL. */
int fp_rig_bind(fp_rig *rig, size_t n, const float *positions, char *err, size_t errlen);

/** Jaw weights that turn no triangle over: after fp_rig_bind, with the mesh's triangles (t x 3
 *  indices < n) and the same rest positions. At jaw.open = max / 8, 2 max / 8, ... max, each
 *  triangle the pose turns over (its normal within 0.0006 of a degree of 90 degrees from its
 *  rest normal, or past it) gives its soft vertices the mean jaw weight of its three, round
 *  after round (at most 200), until none is turned over; skull and jaw vertices keep theirs,
 *  and so does every vertex of no such triangle. Why: a weight that changes faster than a
 *  triangle is wide shears it; on the ICT face 4 gum triangles turned over at jaw.open 0.6
 *  and 20 triangles at 1.0 (the lower lip's corners, where the falloff's lip band is
 *  narrower than they are); after it, none at 0.3, 0.6, 0.8 or 1.0, with 56 vertices
 *  changed (the face's by 0.025 mm RMS at 1.0). This project's rule, no paper's. The
 *  session and `facepuppet pose` call it once after loading a rig. *changed (may be NULL):
 *  the soft vertices whose weight changed. A turned triangle with no soft vertex stays.
 *  Returns 0, -EINVAL (NULL, an index >= n, an unbound rig) or -ENOMEM. One thread; the rig
 *  must not be in use meanwhile. O(t) a round, the rounds after the first only over the
 *  triangles of vertices the last one changed. */
int fp_rig_unfold_jaw(fp_rig *rig, const float *positions, const uint32_t *tris, size_t t,
                      size_t *changed);

/** Where fp_rig_bind put the rig on the mesh it bound. A rig file may give its landmarks'
 *  positions on its own mesh (mesh.landmark_positions). Binding a mesh whose landmark
 *  vertices lie elsewhere (a copy moved, turned or scaled: Blender's Z-up, metres instead of
 *  centimetres) first carries the rig's coordinates (axes, hinge, mouth line, menton, gonion)
 *  by the similarity x -> scale R x + shift that fits the landmarks best (least squares:
 *  Horn's unit quaternion, Umeyama's scale; fp_similarity_fit, as calibrate's touch fit),
 *  scales its lengths (bands, glide, mobility.ramp) and divides mm_per_unit by the scale.
 *  Not placed (the file's coordinates kept, bit for bit) when the fit moves no landmark by
 *  more than FP_RIG_PLACE_SAME of their spread (the rig's own mesh, or another shape of its
 *  topology in the same frame), when it leaves more than FP_RIG_PLACE_MISFIT of it as
 *  residual (no copy of the face: the landmarks' layout differs), or without positions. */
typedef struct fp_rig_placement {
    int placed;        /* 1: the rig was carried as below; 0: the file's coordinates */
    double degrees;    /* rotation angle of R */
    double scale;      /* mesh units of the bound mesh per unit of the rig's (1 unplaced) */
    double shift[3];   /* translation, bound mesh units */
    double rms;        /* the landmarks' residual after the fit, bound mesh units */
    double spread;     /* their RMS distance from their centroid on the bound mesh */
    int misfit;        /* 1: rms > FP_RIG_PLACE_MISFIT x spread: the landmarks' vertices lie
                          nowhere like the rig's (another face of its vertex count, or its
                          own with the vertices in another order): its regions would lie
                          elsewhere on this mesh */
    int mirrored;      /* 1 (with misfit): the landmarks fit the rig's own mirrored (within
                          FP_RIG_PLACE_MIRROR x spread): a mirror image of its mesh, which no
                          turn, scale or move gives (the rig is not placed on it) */
} fp_rig_placement;
#define FP_RIG_PLACE_SAME 0.01
#define FP_RIG_PLACE_MISFIT 0.25
#define FP_RIG_PLACE_MIRROR 0.01

/** The last fp_rig_bind's placement (zeros before a bind). [any-thread] */
fp_rig_placement fp_rig_get_placement(const fp_rig *rig);

/** The rotation that turns +x, +y, +z into the face's left, up and forward axes (fp_rig_axes,
 *  as bound): a unit quaternion w, x, y, z into q; the identity for the shipped rigs on their
 *  own meshes. What fp_calibration's face frame takes (fp_pose.h). [any-thread] */
void fp_rig_face_rotation(const fp_rig *rig, double q[4]);

/** fp_rig_load then fp_rig_bind. */
int fp_rig_load_for_mesh(const char *path, size_t n, const float *positions, fp_rig **out,
                         char *err, size_t errlen);

/** Free a rig; sets *rig to NULL. NULL and *NULL are no-ops. */
void fp_rig_free(fp_rig **rig);

/** zlib crc32 of the positions as n*3 little-endian IEEE-754 floats: the mesh checksum a
 *  rig file records (mesh.positions_crc32). */
uint32_t fp_rig_positions_crc32(size_t n, const float *positions);

/** Whether positions (n x 3) have the checksum the rig records: 1 yes, 0 no. */
int fp_rig_checksum_matches(const fp_rig *rig, size_t n, const float *positions);

/** Find the rig of a mesh among the *.json files of `dir` (all of them, however many): the
 *  file whose mesh checksum matches; else the only one whose vertex count matches. Files that
 *  do not parse are skipped (when none fits, the message counts them and gives the first
 *  one's error: file and JSON path). Writes its path into path_out. Returns 0, -ENOENT (none,
 *  or several with that vertex count and none by checksum; message says which), -EEXIST (two
 *  files with the mesh's checksum: the message names both, the first two by name),
 *  -ENAMETOOLONG, -ENOMEM, -EINVAL. Reads the folder and its files; any thread. */
int fp_rig_find(const char *dir, size_t n, const float *positions, char *path_out,
                size_t path_len, char *err, size_t errlen);

/** Each of the n vertices of pos (n x 3) found at a vertex of rig_pos (rig_n x 3) by its
 *  position, the three floats bit for bit (-0 as +0): to_rig[i] (n entries, the caller's) the
 *  lowest such vertex, UINT32_MAX where none. What finds a rig's own mesh whose vertices were
 *  split at UV or material seams (a glTF, GLB or PLY copy: the ICT face's 26719 vertices as
 *  28716): each copy of a split vertex lies where the vertex does. Returns the number of
 *  vertices not found (0: all), -EINVAL (no vertex), -ENOMEM. O((rig_n + n) log rig_n); any
 *  thread. */
int fp_rig_match_positions(size_t rig_n, const float *rig_pos, size_t n, const float *pos,
                           uint32_t *to_rig);

/** Carry a loaded rig (fp_rig_load; not yet bound) over to a mesh of n vertices whose vertex i
 *  is the rig's vertex to_rig[i] (fp_rig_match_positions; pos, n x 3, that mesh's positions):
 *  every vertex takes its rig vertex's region, kind and file jaw weight; a landmark goes to the
 *  first vertex of its own; the rig's vertex count and checksum become the mesh's (pos). Then
 *  fp_rig_bind(rig, n, pos). Returns 0; -EBADMSG (a landmark's vertex is in no vertex of the
 *  mesh: the message names it), -EINVAL (a to_rig entry out of range, a bound rig), -ENOMEM;
 *  on any error the rig is unchanged. */
int fp_rig_remap(fp_rig *rig, size_t n, const uint32_t *to_rig, const float *pos, char *err,
                 size_t errlen);

/** Where fp_rig_find finds none: the rig of `dir` whose own mesh (its mesh.name under
 *  data_root, the shared data folder; loaded, and with the rig's vertex count and checksum)
 *  has fewer vertices than this one (n, pos) and holds every one of its positions
 *  (fp_rig_match_positions): the rig's path into path_out and the map into *to_rig (n entries,
 *  malloc()ed: the caller frees it) for fp_rig_remap. The first such rig by file name. Returns
 *  0, -ENOENT (none: err says so), -ENOMEM, -EINVAL. Reads the folder, the rigs and their
 *  meshes; any thread. */
int fp_rig_find_split(const char *dir, const char *data_root, size_t n, const float *pos,
                      char *path_out, size_t path_len, uint32_t **to_rig, char *err, size_t errlen);

/** The rig's name (file "name"), its file's name (as given to parse/load), the vertex
 *  count it fits, the mesh name it records (may be ""). Strings owned by the rig. */
const char *fp_rig_name(const fp_rig *rig);
const char *fp_rig_source(const fp_rig *rig);
size_t fp_rig_vertex_count(const fp_rig *rig);
const char *fp_rig_mesh_name(const fp_rig *rig);
uint32_t fp_rig_mesh_crc32(const fp_rig *rig);

/** The mesh's unit in millimetres (e.g. 10 for a mesh in centimetres). */
double fp_rig_mm_per_unit(const fp_rig *rig);

/** Face axes, unit vectors in mesh coordinates: up (chin to crown), forward (out of the
 *  face), left (the face's own left). Any pointer may be NULL. */
void fp_rig_axes(const fp_rig *rig, float up[3], float forward[3], float left[3]);

/** Region kind of every vertex: n bytes of FP_RIG_* values, owned by the rig. */
const uint8_t *fp_rig_vertex_kinds(const fp_rig *rig);
/** Region of every vertex: n bytes, the region's index (fp_rig_region_get) + 1, or 0 for a
 *  vertex in no region; owned by the rig, valid while it lives. [any-thread] */
const uint8_t *fp_rig_vertex_regions(const fp_rig *rig);

/** Number of regions and the i-th (0 <= i < count). Returns 0 or -EINVAL (i out of range). */
size_t fp_rig_region_count(const fp_rig *rig);
int fp_rig_region_get(const fp_rig *rig, size_t i, fp_rig_region_desc *out);

/** Landmarks: count, the i-th name and vertex (*name the rig's, valid while it lives; -EINVAL
 *  for i out of range or NULLs), and lookup by name (vertex index, or -ENOENT). */
size_t fp_rig_landmark_count(const fp_rig *rig);
int fp_rig_landmark_get(const fp_rig *rig, size_t i, const char **name, uint32_t *vertex);
long fp_rig_landmark_index(const fp_rig *rig, const char *name);

/** Channels: count, the i-th (-EINVAL for i out of range or NULLs; its strings the rig's),
 *  lookup by name (index, or -ENOENT). */
size_t fp_rig_channel_count(const fp_rig *rig);
int fp_rig_channel_get(const fp_rig *rig, size_t i, fp_rig_channel_desc *out);
long fp_rig_channel_index(const fp_rig *rig, const char *name);

/** Check one value for a channel: 0 when name exists and min <= value <= max; -ENOENT
 *  (unknown channel) or -ERANGE (outside, or NaN), with a message; value is compared as a
 *  float, as the channel keeps its range (the file's 0.7 admits 0.7). For the command line,
 *  which refuses out-of-range values; fp_rig_pose clamps instead. */
int fp_rig_channel_check(const fp_rig *rig, const char *name, double value, char *err,
                         size_t errlen);

/** Fill values[fp_rig_channel_count] from named pairs (the control set's channels, plugin.h
 *  fp_channel is {char name[32]; float value;}: pass them as parallel arrays here to keep
 *  this library free of the plugin ABI): channels not named keep their neutral value; names
 *  the rig does not have are ignored and counted. Returns that count (>= 0), or -EINVAL (rig or
 *  values NULL). No allocation. [any-thread]. */
int fp_rig_channel_values(const fp_rig *rig, const char *const *names, const float *vals,
                          size_t n, float *values);

/** The jaw: hinge points (right and left temporomandibular joints, mesh units), the opening
 *  angle at jaw.open = 1 (degrees; jaw.open = x turns by x times it), and the glide (the
 *  jaw's translation at jaw.open = 1, mesh units, forward and down). Any pointer may be NULL. */
void fp_rig_hinge(const fp_rig *rig, float right[3], float left[3], double *open_degrees,
                  double glide[2]);

/** The fraction of the glide (jaw.glide, the condyle's slide along the articular eminence)
 *  the jaw has made at a jaw.open value: with the file's jaw.glide_start a (in [0, 0.95],
 *  default 0) it is 0 up to a (the opening is a pure rotation about the condyles) and
 *  (open - a) / (1 - a) after, reaching 1 at jaw.open = 1 (0 for open <= 0 or NaN, 1 for
 *  open >= 1); a = 0 is the version-1 glide, linear from the start. Source: Posselt's
 *  envelope of motion (the posterior border path: rotation for the first 20-25 mm of incisal
 *  opening, then the condyles translate, a corner in the incisal point's path), rigs/README.md
 *  "ICT: how the hinge, the angle and the weights were chosen". 0 for a NULL rig.
 *  [any-thread], no allocation. */
double fp_rig_glide_fraction(const fp_rig *rig, double open);

/** Per-vertex weights after fp_rig_bind (NULL before): the jaw weight w (fraction of the
 *  jaw's motion a vertex takes: 1 on the jaw, 0 on the skull, in soft tissue the file's
 *  jaw.weights where it lists the vertex, else the falloff; rigs/README.md)
 *  and the mobility m (see the top of this file). n floats each, owned by the rig. */
const float *fp_rig_jaw_weights(const fp_rig *rig);
const float *fp_rig_mobility(const fp_rig *rig);

/** Pose the base by the channels: out[v] = H + R(w_v * theta) (base[v] - H)
 *  + w_v * s(jaw.open) * (glide[0] * forward - glide[1] * up) (s = fp_rig_glide_fraction), where H is the right hinge point,
 *  R(a) the rotation by a about the hinge axis (right to left TMJ; positive opens the mouth:
 *  the chin goes down and back), theta = jaw.open * open_degrees, w_v the vertex's jaw weight
 *  and forward, up the rig's axes. Skull vertices, every vertex with w_v == 0 and every
 *  vertex while theta == 0 (the glide too: a closed jaw does not slide) are copied bit for bit; jaw vertices (w = 1) move rigidly. Computed in double.
 *  base, out: n x 3 floats (n = fp_rig_vertex_count), may be the same array. values: the
 *  channel values in the rig's channel order (fp_rig_channel_values), NULL = neutral; values
 *  outside a channel's range are clamped to it (a mapping's noise must not fail a frame),
 *  NaN counts as neutral. Returns 0, -EINVAL (NULL, rig not bound). [any-thread], no
 *  allocation. Source: rigs/README.md "Jaw" (rotation about a fixed axis, Rodrigues). */
int fp_rig_pose(const fp_rig *rig, const float *base, const float *values, float *out);

/** fp_rig_pose on vertices v0 .. v0 + count - 1 only (the same arithmetic, bit for bit): the
 *  arrays are whole n x 3 arrays, the rest of out untouched. For a caller whose base changed
 *  only there (a ranged commit: the posed base refreshed where the fingers moved). Returns 0
 *  or -EINVAL (also for a range beyond n). [any-thread], no allocation. */
int fp_rig_pose_range(const fp_rig *rig, const float *base, const float *values, float *out,
                      size_t v0, size_t count);

/** The inverse of fp_rig_pose for a committed shape: each vertex v of `shown` (the posed
 *  base plus the fingers' work) is taken back by the inverse of its own pose,
 *  out[v] = J_r + R(w_v theta)^T (shown[v] - J_r - w_v s(jaw.open) glide), so that posing `out`
 *  with the same values gives `shown` again (to float rounding) and a commit keeps only the
 *  fingers' part (the jaw does not turn twice). Vertices with mobility 0 (skull, jaw: the
 *  fingers cannot move them) are copied from `base` bit for bit. Arrays n x 3 floats; out
 *  may alias neither base nor shown. values as fp_rig_pose. Returns 0 or -EINVAL.
 *  [any-thread], no allocation. */
int fp_rig_unpose(const fp_rig *rig, const float *base, const float *values, const float *shown,
                  float *out);
/** fp_rig_unpose on vertices v0 .. v0 + count - 1 only (the same arithmetic), the rest of out
 *  untouched; with `posed` (the posed base `shown` was made on, n x 3; NULL: as
 *  fp_rig_unpose) a vertex whose shown position equals its posed one (==, per coordinate:
 *  the fingers did not move it) is copied from `base` bit for bit, so a commit changes no
 *  vertex the fingers left (the pose's float round trip would otherwise move them by a
 *  rounding when the jaw is open). Returns 0 or -EINVAL (also for a range beyond n).
 *  [any-thread], no allocation. */
int fp_rig_unpose_range(const fp_rig *rig, const float *base, const float *posed, const float *values,
                        const float *shown, float *out, size_t v0, size_t count);

/** Blend the fingers' result into the posed shape: out[v] = posed[v] + m_v (warped[v] -
 *  posed[v]); vertices with m_v == 0 (skull, jaw) are copied from posed bit for bit. Arrays
 *  n x 3 floats; out may alias posed or warped. Returns 0 or -EINVAL. [any-thread]. */
int fp_rig_apply_mobility(const fp_rig *rig, const float *posed, const float *warped,
                          float *out);
/** fp_rig_apply_mobility on vertices v0 .. v0 + count - 1 only (the same arithmetic, bit for
 *  bit); the arrays are still whole n x 3 arrays, the rest untouched. For a caller that knows
 *  where warped moved (the engine's touched ranges). Returns 0 or -EINVAL (also for a range
 *  beyond n). [any-thread]. */
int fp_rig_apply_mobility_range(const fp_rig *rig, const float *posed, const float *warped,
                                float *out, size_t v0, size_t count);

/** The largest finger displacement (mesh units) for which the blended map stays injective
 *  anywhere on the mesh by the bound above: mobility.ramp / 3 (the worst case of
 *  fp_rig_finger_limit; the session clamps each finger by fp_rig_finger_limit instead). */
double fp_rig_max_finger_displacement(const fp_rig *rig);

/** The margin of the local finger clamp: |control vector| * max |grad m| <= this. */
#define FP_RIG_FINGER_MARGIN 0.5

/** The slope of the mobility, |grad m| per mesh unit, per vertex after fp_rig_bind (NULL
 *  before): 6 t (1 - t) / ramp with t = d / ramp (d: distance to the nearest skull or jaw
 *  vertex) for soft vertices within the ramp, 0 elsewhere (rigid, or m == 1). n floats,
 *  owned by the rig. */
const float *fp_rig_mobility_slope(const fp_rig *rig);

/** The local finger clamp: the largest control vector (mesh units) for a finger starting at
 *  `start` with support radius `radius` (mesh units) that keeps the mobility blend injective
 *  by the bound at the top of this file: FP_RIG_FINGER_MARGIN / G, G the largest
 *  fp_rig_mobility_slope over the vertices of `posed` (n x 3, the posed base the finger
 *  starts on) within `radius` of `start`; INFINITY when every such vertex has slope 0 (the
 *  support reaches no bone's ramp: only the engine's 0.45 R applies). Returns ramp / 3
 *  (the global bound) for NULL posed/start or radius <= 0, 0 for an unbound rig.
 *  O(vertices with slope > 0). [any-thread], no allocation. */
double fp_rig_finger_limit(const fp_rig *rig, const float *posed, const float start[3],
                           double radius);

/** The finger limit by blocks (the same result as fp_rig_finger_limit, bit for bit, for a
 *  fraction of its cost): the slope vertices in blocks of 32 (consecutive in the Morton
 *  order of their positions in the first posed base given, the order then kept; before
 *  that in vertex order), each with its largest slope and its directions' box (fixed by the
 *  rig) and its box in the posed base, stored steepest block first with a copy of its
 *  vertices' posed positions and slopes. A query visits the blocks steepest first, skips those whose box is at least
 *  `radius` away (a lower bound in the same float arithmetic as the full scan, so nothing
 *  within reach is skipped) and stops at the first block no steeper than the slope found.
 *  The index refers to the rig (which must outlive it):
 *    - fp_rig_slope_index_set(ix, posed): positions and boxes from a whole posed base (n x
 *      3; O(slope vertices)), required before the first query and after the posed base
 *      changed unknown where;
 *    - fp_rig_slope_index_update_ranges(ix, posed, ranges, n): the posed base changed only
 *      on these vertex ranges ((first, count) pairs): their slope vertices take their new
 *      positions, their blocks' boxes are made again from their vertices (O(log + the
 *      touched blocks' vertices)); a box always holds its vertices, which keeps every skip
 *      exact, and shrinks when skin that moved away comes back;
 *    - fp_rig_finger_limit_indexed(ix, start, radius): fp_rig_finger_limit(rig, posed,
 *      start, radius) for the posed base given last.
 *  create: 0, -EINVAL (NULL, rig not bound), -ENOMEM (16 bytes per slope vertex). Queries
 *  [any-thread] on an index not being updated; no allocation after create. */
typedef struct fp_rig_slope_index fp_rig_slope_index;
int fp_rig_slope_index_create(const fp_rig *rig, fp_rig_slope_index **out);
void fp_rig_slope_index_destroy(fp_rig_slope_index **ix);
void fp_rig_slope_index_set(fp_rig_slope_index *ix, const float *posed);
void fp_rig_slope_index_update_ranges(fp_rig_slope_index *ix, const float *posed,
                                      const uint32_t *ranges, size_t nranges);
double fp_rig_finger_limit_indexed(const fp_rig_slope_index *ix, const float start[3], double radius);

/** The directional finger clamp (the bound at the top of this file, by direction): the
 *  largest length (mesh units) of a control vector from `start` toward `end` (3 floats each,
 *  mesh units, on the posed base `posed`, n x 3) that keeps |vector| * c_v <=
 *  FP_RIG_FINGER_MARGIN for every slope vertex v within `radius` of the segment start -> end,
 *  c_v = psi(rho_v / radius) |grad m|_v max(0, -dir_v . u), rho_v v's distance to the
 *  segment, psi Wendland's psi_{3,1}, dir_v grad m's unit direction at v (in the bound
 *  shape; the pose turns the jaw's by a few degrees at most), u the vector's unit direction;
 *  INFINITY when no such vertex is pushed toward its bone. Returns ramp / 3 for NULL
 *  arguments or radius <= 0, 0 for an unbound rig. O(slope vertices). [any-thread]. */
double fp_rig_finger_limit_toward(const fp_rig *rig, const float *posed, const float start[3], const float end[3],
                                  double radius);
/** fp_rig_finger_limit_toward through the index (the blocks within `radius` of the
 *  segment's box found through a tree of the blocks' boxes, 8 to a node, then visited
 *  steepest first, skipped when their slope times the most of u their directions' box can
 *  push against times psi at that box gap is no more than the push found, stopped at the
 *  first block no steeper than the push found): the same value as the brute force, for the
 *  posed base given last. On the ICT face's anchored frames (one finger, widened supports)
 *  the rig's clamp took 30-80 us a frame with blocks in vertex order, about a third of that
 *  in Morton order; on ICT subdivided three times (530,102 slope vertices, 16,566 blocks)
 *  the scan of every block's box was 1.1 ms of a frame, the tree's search under 0.1
 *  (docs/performance.md).
 *  [any-thread] on an index not being updated; no allocation. */
double fp_rig_finger_limit_toward_indexed(const fp_rig_slope_index *ix, const float start[3], const float end[3],
                                          double radius);

/** The directional clamp of one control vector (what the session applies; the bound at the
 *  top of this file): writes into out_end (3 floats, mesh units) the end point of a vector
 *  from `start` that keeps every push c_v within FP_RIG_FINGER_MARGIN and lands as near
 *  `end` as it finds. Only a push toward bone folds the ramp, so the vector loses only that:
 *  each vertex of the asked vector's capsule gives a constraint (its push, the component
 *  along -dir_v weighed there, at most the margin), and the result is the vector asked
 *  projected onto those constraints (the nearest vector meeting them: up to 16 rounds each
 *  add the worst one met and project again, an exact projection onto at most 3 active
 *  constraints), then scaled to its limit on its own capsule where that reaches a vertex
 *  harder (within the bound: a scaled vector's capsule lies in the one searched). A
 *  sideways drag with a little push toward the cheekbone so keeps its sideways part, and
 *  the result moves continuously with `end` (the weights follow `end`, and the projection
 *  onto a convex set is continuous; test_rig: a step of `end` moves it at most 10x as far,
 *  where the earlier clamp, weighing each cut on its own capsule, jumped 18.8 mm in a step
 *  of 0.05). Returns 0 (out_end = end: within the bound, the same test as
 *  fp_rig_finger_limit_toward_indexed's), 1 (the push cut), 2 (scaled). radius <= 0: scaled
 *  to the global bound ramp / 3 (as the limit says); NULL ix or an unbound rig: 0. Source: the bound above (this project's);
 *  the projection onto half-spaces is the KKT point of min |v - v0|^2 subject to
 *  a_j . v <= b_j. [any-thread] on an index not being updated; no allocation; asserts its
 *  pointers. */
int fp_rig_finger_clamp_indexed(const fp_rig_slope_index *ix, const float start[3], const float end[3],
                                double radius, float out_end[3]);

/** The folder of the rig files: $FACEPUPPET_RIGS when set; else <exe_dir>/../share/
 *  facepuppet/rigs when it exists (installed); else the source tree's rigs/ (compiled in as
 *  FP_RIG_SOURCE_DIR). Writes it into buf (truncated to len) and returns buf. */
const char *fp_rig_default_dir(const char *exe_dir, char *buf, size_t len);

/** Print-free description for `facepuppet info RIG`: writes lines (regions with counts,
 *  landmarks, hinge, channels, and, when positions are given, whether the rig fits them) into
 *  buf (truncated, NUL-terminated). Returns the length it needed (like snprintf). */
size_t fp_rig_describe(const fp_rig *rig, size_t n, const float *positions, char *buf,
                       size_t len);

#ifdef __cplusplus
}
#endif
#endif
