/*
 * fp_session.h: one puppeteering session, the frame loop of shared/docs/design.md. One
 * fp_session_step runs the frame's steps, each a module of core/session (or core/pose):
 *   1 inputs and intents (intents.h): drain the inputs' queues, pedal and key bindings
 *   2 hand poses and calibration (core/pose/fp_pose.h): FK, workspace calibration
 *   3 the mapping call (step_mapping.h): the control set, checked
 *   4 the rig (step_rig.h): channels pose the base (the jaw), fingers blended by mobility
 *   5 the engine (step_engine.h): factor or reuse, solve, guard, evaluate; tip distances;
 *     the contact guard (step_contact.h, core/contact): no new self-crossings shown
 *   6 history (history.h): commit into the base (step_commit.h), undo ring, reset
 *   7 the recorder (step_record.h): the frame's record to the sink of the options
 *
 * Errors: functions return 0 or a negative code of core/common/fp_error.h: negative errno
 * (-EINVAL, -ENOMEM, ...), the mesh loader's code unchanged, the plugin host's codes
 * unchanged (FP_EPLUGIN_* / FP_EPLUGIN_*, or a plugin's own negative code), the event
 * log's code for a recording; a message naming the file, SPEC or plugin goes into err.
 * The session never prints: run-time messages (input status lines, mapping and engine
 * errors, recording errors) go to the log callback of the options; an error that repeats
 * every frame is sent once, then as "... (repeated N more times)" when it ends or changes.
 *
 * Thread rules: a session is used from one thread (the session thread: the frame loop of
 * `facepuppet run` or the viewer); every function here is [session-thread] unless noted.
 * fp_session_step may run the frame on the session's frame thread (frame_thread.h; options
 * .frame_thread) while the caller waits: then the frame's calls into the mapping plugin and
 * the log and record callbacks are made there, one frame at a time, ordered with the
 * caller's own calls as if on one thread (the session thread, taking turns). Input plugins
 * run on their own threads and reach it only through the lock-free queues of core/plugin;
 * record=FILE recordings are written by threads of their own.
 */
#ifndef FP_SESSION_H
#define FP_SESSION_H

#include "fp_plugin_host.h"
#include "fp_pose.h"
#include "session_log.h"
#include "step_record.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_SESSION_MAX_INPUTS 8
/** Commits that fp_session_undo can take back (the oldest is forgotten beyond). */
#define FP_SESSION_UNDO_LEVELS 32
/** The default support radius is at least this many millimetres (a fingertip's reach). */
#define FP_SESSION_MIN_RADIUS_MM 25.0
/** A mesh fits the engine (csrbf.h) when every |coordinate| is at most CSRBF_MAX_COORD (1e15)
 *  and its bounding box's diagonal at least this many mesh units (its default support radius,
 *  6% of that, then stays far above the engine's smallest, 1e-15); fp_session_create refuses
 *  another (-EBADMSG, naming the file and the figure) before any work. */
#define FP_SESSION_MIN_DIAGONAL 1e-12
/** A mesh's surface is kept in floats (24-bit mantissa): far from the origin their step grows
 *  (0.0625 units at 1e6), and a face 0.3 units across placed there is a handful of steps,
 *  its shape gone before any work. fp_session_create refuses (-EBADMSG, naming the file, the
 *  step and the size) a mesh whose float step at its surface's largest |coordinate| exceeds
 *  this fraction of its bounding box's diagonal (0.3 mm on a 30 cm head). */
#define FP_SESSION_MAX_STEP_DIAGONALS 1e-3
/** A support radius is at least this many and at most this many bounding-box diagonals
 *  (--radius at open, fp_session_set_radius after): below, no vertex would move; above, every
 *  vertex would move as one. */
#define FP_SESSION_RADIUS_MIN_DIAGONALS 1e-6
#define FP_SESSION_RADIUS_MAX_DIAGONALS 10.0
/** A calibration whose unit (mm per mesh unit) is more than this many times the mesh's own
 *  (its rig's, else detected from the head: within 7% of the rigs' on the shared faces), or
 *  less than its inverse, was made for another mesh (ICT's 10 mm/unit on Lee Perry-Smith's
 *  48.98: hands 4.9 times too large, the whole head moved): fp_session_create warns (source
 *  `session`), naming both units and where the mesh's came from, and goes on with it. */
#define FP_SESSION_CALIBRATION_UNIT_RATIO 1.5

/* fp_calibration (p_mesh = scale * p_mm + offset) is declared in fp_pose.h;
 * fp_session_log_fn in session_log.h; fp_frame_record and fp_frame_record_fn in
 * step_record.h. */

/** fp_session_options.progress: `stage` is a line without newline, e.g. "loading face.obj
 *  (279 MiB)", valid during the call only; NULL once, when fp_session_create returns
 *  (opened or failed; not when it refuses its options before any work), so that a status
 *  line can be cleared. */
typedef void (*fp_session_progress_fn)(void *user, const char *stage);

/** A performer's calibration by name (fp_session_options.performer_calibrations): name ""
 *  is a first performer whose inputs name none. */
typedef struct fp_session_performer_placement {
    const char *name;
    fp_calibration calibration;
} fp_session_performer_placement;

typedef struct fp_session_options {
    const char *mesh_path;                          /* required (unless mesh is given) */
    const struct fp_mesh *mesh;                     /* a mesh in memory instead of mesh_path
                                                       (copied; e.g. `bench --case frame`'s
                                                       subdivided face) */
    const char *inputs[FP_SESSION_MAX_INPUTS];      /* SPECs */
    size_t input_count;
    const char *mapping;                            /* NAME[,key=value...]; "anchored" */
    double radius;                                  /* support radius, mesh units; 0: 6% of
                                                       the mesh's bounding-box diagonal, at
                                                       least FP_SESSION_MIN_RADIUS_MM */
    const char *radius_name;                        /* what a refused radius is called: NULL
                                                       "--radius" (the option's: -EINVAL);
                                                       else a file's value ("T.fptake: the
                                                       take's radius": -ERANGE) */
    double hand_size;                               /* 0 or 1: mean adult hand */
    const fp_session_performer_placement *performer_calibrations; /* a performer's own
                                                       calibration by name (a take performed
                                                       again: its header's performers), after
                                                       its inputs' calibration=FILE, before
                                                       `calibration`; may be NULL */
    size_t performer_calibration_count;
    const fp_calibration *calibration;              /* NULL: the life-size calibration (the
                                                       inputs' workspace in front of the face
                                                       at scale 1 / mm_per_unit; where no
                                                       input states one, estimated from the
                                                       joints as the hands arrive and refined
                                                       as they run: step_arrive.h) */
    const char *calibration_source;                 /* what `calibration` is called in a
                                                       warning or an error (its file: "cal.json");
                                                       NULL: "the calibration". A calibration
                                                       whose unit is over 1.5 times off the
                                                       mesh's (its rig's, else the head's) is
                                                       warned about: one made for another mesh
                                                       (FP_SESSION_CALIBRATION_UNIT_RATIO) */
    double mm_per_unit;                             /* the mesh's unit in mm; 0: detect it
                                                       from the head (core/pose/fp_head.h).
                                                       The --mm-per-unit option sets it, and
                                                       the rig integration fills it from the
                                                       rig's mm_per_unit (a rig wins over
                                                       detection, the option over a rig) */
    const char *mm_per_unit_source;                 /* where a given mm_per_unit came from,
                                                       for the scale line ("--mm-per-unit",
                                                       "rig FILE"); NULL: "given" */
    float face_up[3], face_facing[3];               /* the face's up and the axis it looks
                                                       along, in the mesh (unit, orthogonal;
                                                       both or neither): the hands are placed
                                                       in front of it and the viewer looks at
                                                       it from there. Zeros: the rig's axes
                                                       (a rig placed on a turned copy of its
                                                       mesh), else +y up, looking along +z
                                                       (fp_calibration.face) */
    const fp_plugin_path *plugin_path;              /* required */
    int engine_threads;                             /* 0: 1 (a frame's work follows the
                                                       supports); -1: all cores; N: N threads */
    fp_session_log_fn log;                          /* NULL: silent. Called on the session
                                                       thread (and in create/destroy) with an
                                                       fp_log_level, a source (input SPEC
                                                       name, mapping name, "engine") and a
                                                       line without newline */
    void *log_user;                                 /* passed to log */
    fp_session_progress_fn progress;                /* NULL: none. Called by
                                                       fp_session_create on the calling
                                                       thread as each of its steps whose cost
                                                       grows with the mesh begins (loading the
                                                       file, indexing the vertices, building
                                                       the contact guard; then the mapping and
                                                       inputs), with a line naming it and its
                                                       size, then with NULL as it returns
                                                       (fp_session_progress_fn): a 1.7M-vertex
                                                       OBJ of 279 MiB
                                                       takes about 15 s to load and 9 s more
                                                       to open on the 2-core VM */
    void *progress_user;                            /* passed to progress */
    fp_frame_record_fn record;                      /* NULL: none. After each frame, on the
                                                       session thread; must not block, lock
                                                       or do I/O (a take recorder pushes into
                                                       its lock-free queue) */
    void *record_user;                              /* passed to record */
    double mapping_budget_ms;                       /* a process() call slower than this is
                                                       reported (once, then counted); 0: 2 ms */
    bool input_clock;                               /* step on the inputs' own clock (a
                                                       headless run): fp_session_step(t)
                                                       consumes only events stamped <= t from
                                                       recordings (inputs with the
                                                       recording-info extension); false (live):
                                                       every queued event, each frame */
    const char *rig_path;                           /* the rig file (rigs/README.md); NULL:
                                                       the rig of this mesh found in rig_dir
                                                       (fp_rig_find: checksum, else vertex
                                                       count; none found: no rig); "none":
                                                       no rig. A rig's mm_per_unit is the
                                                       mesh's unit unless mm_per_unit is given */
    const char *rig_dir;                            /* NULL: fp_rig_default_dir(NULL) */
    const char *rig_mesh_root;                      /* the shared data folder, where the rigs'
                                                       meshes (mesh.name) lie: a mesh no rig
                                                       fits by checksum or vertex count that
                                                       is a rig's own with its vertices split
                                                       at seams (a glTF copy) gets that rig,
                                                       carried over by position
                                                       (fp_rig_find_split); NULL: not looked
                                                       for */
    bool measure_jacobian;                          /* fill fp_frame_stats.min_det_j (the
                                                       engine's general path: slower, same
                                                       shape) */
    bool no_contact_guard;                          /* true: no contact guard (benchmarks);
                                                       default (false): every shown shape is
                                                       checked for new self-crossings
                                                       (fp_contact.h) and its motion scaled back */
    bool whole_rig_commit;                          /* true: a commit with a rig unposes,
                                                       commits, poses and re-indexes the whole
                                                       mesh, and one of the contact guard's
                                                       shape without a rig copies and
                                                       re-indexes the whole mesh (the
                                                       references that tests compare the
                                                       default with); default (false): only
                                                       the engine's touched ranges (and the
                                                       guard's D_P) */
    bool exact_frames;                              /* true: every shown frame is the
                                                       engine's shape bit for bit (where the
                                                       contact guard accepts it); default
                                                       (false): the guard's hold
                                                       (fp_contact_hold): a vertex that moved
                                                       less than 1e-5 of the face's diagonal
                                                       since the last frame keeps its place
                                                       until it moves more (commits exact) */
    int frame_thread;                               /* 0 (default): fp_session_start makes
                                                       a frame thread when the machine has
                                                       2 or more CPUs and the mesh at most
                                                       FP_CONTACT_PREWARM (262,144)
                                                       triangles; 1: whenever; 2: whenever,
                                                       and a frame waits up to 1 s for the
                                                       thread to take it (tests: on a busy
                                                       machine a 20 us grace may pass every
                                                       frame); -1: never. fp_session_step,
                                                       frame_thread.h */
    int isolate;                                    /* which plugins, the mapping and the
                                                       inputs, run in a helper process
                                                       (fp_isolate.h's fp_isolate_mode): 0
                                                       (FP_ISOLATE_NONE, the default of the
                                                       library) every one in process; 1 those
                                                       that are not facepuppet's own in the
                                                       path's built-in folder (the default of
                                                       `run` and `live`); 2 every one */
    double isolate_deadline_ms;                     /* an isolated process() that has not
                                                       answered by then is abandoned and its
                                                       helper restarted; 0: 50 ms */
    const char *isolate_helper;                     /* the executable run in helper mode;
                                                       NULL: /proc/self/exe (facepuppet) */
} fp_session_options;

/** The frame's stages, for fp_frame_stats.stage_ms (`bench --case frame`). */
enum fp_frame_stage {
    FP_STAGE_EVENTS = 0,      /* drain the inputs, intents */
    FP_STAGE_HANDS,           /* hand poses, calibration */
    FP_STAGE_DISTANCES,       /* fingertip-to-surface distances */
    FP_STAGE_MAPPING,         /* the mapping plugin and the rig */
    FP_STAGE_SOLVE,           /* factor or reuse, solve, the fold-over guard */
    FP_STAGE_EVALUATE,        /* T(base) (touched blocks) */
    FP_STAGE_SHAPE,           /* the shape shown around the contact guard: close sheets
                                 carried, the rig's mobility blend, the skin's reach */
    FP_STAGE_COMMIT,          /* history and re-index after a commit */
    FP_STAGE_COUNT
};

/** Statistics of one fp_session_step. */
#define FP_FRAME_REACH_MAX 64 /* the session's control-set capacity */
typedef struct fp_frame_stats {
    uint64_t frame;
    size_t events;            /* events drained this frame */
    bool active;              /* a deformation is being shown */
    bool engaged;             /* the mapping began one this frame */
    bool committed;           /* this frame's deformation went into the base */
    bool cancelled;
    bool refactored;          /* the engine factored anew (start points changed) */
    size_t control_vectors;
    uint64_t pairs;           /* vertex-centre pairs evaluated */
    double update_ms;         /* engine solve + guard + evaluate, milliseconds */
    /* the fold-over guard (step_engine.h): every map applied is injective */
    double guard_bound;       /* injectivity bound L of the map the mapping asked for (L < 1:
                                 injective; the guard applies maps with L <= 0.9) */
    size_t guard_clusters;    /* clusters of overlapping supports */
    size_t guard_limited;     /* clusters the guard scaled back (first map) */
    int guard_substeps;       /* maps composed (1: one; unanchored steps may compose) */
    double guard_reached;     /* smallest fraction of a control vector the map reached (1: all;
                                 below 1 the guard stopped short of an end point) */
    /* reach (skin_reach.h): how far the skin followed the fingertips this frame */
    size_t reach_vectors;     /* control vectors starting on the skin (within 0.5 R) that ask
                                 to move (at least 1e-4 R) */
    float reach[FP_FRAME_REACH_MAX]; /* each one's reach: how far the skin vertex nearest its
                                 start point moved over how far its end point asked (1: all) */
    double reach_asked_max;   /* the longest of them, mesh units */
    size_t reach_allowed_vectors; /* with a rig: the same vectors' reach against what the rig
                                 allowed (the vector its clamp left, the engine's, times the
                                 grabbed vertex's mobility: a push toward a bone held back, the
                                 blend near it); 0 without a rig */
    float reach_allowed[FP_FRAME_REACH_MAX];
    size_t reach_held;        /* with a rig: vectors whose grabbed vertex the rig keeps still
                                 (mobility 0: the skull or the jaw; skin_reach.h), left out of
                                 reach_allowed */
    double min_det_j;         /* min det dT/dx over the moved vertices (and composed maps) with
                                 fp_session_options.measure_jacobian, else NAN (and when not
                                 active) */
    /* the contact guard (fp_contact.h): the shown shape adds no self-crossing to the last one */
    double collide_t;         /* fraction of this frame's motion kept near where the skin would
                                 cross (fp_contact_result.t: 1 all; 0 none there) */
    double collide_kept;      /* share of the frame's motion kept over the moved skin
                                 (fp_contact_result.kept: 1 all; with a local scale-back the
                                 skin away from the crossing moved whole) */
    long collide_pairs;       /* new crossing pairs the full motion would have added */
    double flip_widen;        /* the support radius this frame, over the mapping's: 1, or more
                                 in a gesture the guard held back for flipped triangles alone
                                 (FP_FLIP_WIDEN, step_contact.h) */
    double collide_ms;        /* the guard's checks, milliseconds */
    double collide_wait_ms;   /* of those, the guard's waits for its worker thread to finish a
                                 task (fp_contact.h, fp_contact_result.worker_wait_ms), ms */
    size_t collide_held;      /* vertices the guard's hold kept in place (fp_contact_hold:
                                 they moved less than its eps since the last frame) */
    int collide_checks;       /* shapes the guard checked (fp_contact_result.checks: 1 when the
                                 motion passed whole; more when it scaled it back) */
    size_t collide_moved;     /* vertices the guard found moved (fp_contact_result.moved_verts) */
    /* the guard's walks this frame (fp_contact_result: node_pairs, leaf_pairs, tested,
       certified; summed over its checks; 0 without a guard): where its time goes */
    size_t collide_node_pairs, collide_leaf_pairs, collide_tested, collide_certified;
    double stage_ms[FP_STAGE_COUNT]; /* wall time of each stage (fp_frame_stage), ms */
    bool frame_thread;        /* the frame ran on the session's frame thread (fp_session_step) */
} fp_frame_stats;

typedef struct fp_session fp_session;

/** Load the mesh, load the mapping plugin and every input (not started), open the inputs'
 *  record=FILE recordings. Returns 0, or a negative code with a message in err naming the
 *  file, SPEC or plugin at fault: -EINVAL bad options (no mesh or plugin path, too many
 *  inputs, a negative or NaN radius, a radius beyond 10x the mesh's bounding-box diagonal
 *  or under a millionth of it: -ERANGE instead where radius_name is given,
 *  a negative or NaN mm_per_unit, a mapping SPEC with ':ARG'), -ENOMEM, the mesh
 *  loader's code unchanged (fp_mesh_load), the rig's code unchanged (options rig_path,
 *  rig_dir; fp_rig_load_for_mesh: -ENOENT a missing file, -EBADMSG a malformed rig or one that
 *  does not fit the mesh, naming the file and field), the plugin host's codes unchanged
 *  (fp_plugin_load, fp_input_instance_open: FP_EPLUGIN_*, a plugin's own code, a
 *  recording's code). [main-thread]. */
int fp_session_create(const fp_session_options *opt, fp_session **out, char *err, size_t errlen);

/** Start the inputs' threads. Returns 0 or the first failing input's code (unchanged),
 *  err naming it. [main-thread]. */
int fp_session_start(fp_session *s, char *err, size_t errlen);

/** Real-time memory for a live session (`facepuppet live`, `bench --case frame`): so that
 *  no frame waits for a page fault (about 10 us each on the 2-core VM; 1 to 9 in each of the
 *  ICT replay's committing and envelope-renewing frames, its slowest, before). Sets glibc's
 *  malloc, for the whole process and for good, to keep the memory it frees (M_TRIM_THRESHOLD
 *  INT_MAX), to serve large blocks from its heap (M_MMAP_MAX 0) and to use one arena
 *  (M_ARENA_MAX 1: threads started later share the heap); then writes a reserve of
 *  reserve_bytes (0: 32 MiB + 32 bytes a vertex of s) in 4 KiB blocks and frees it, touches
 *  512 KiB of the calling thread's stack and makes the code mappings present
 *  (MADV_POPULATE_READ, Linux 5.14; best effort). The frames' allocations (undo levels, the
 *  contact guard's lists, its worker's scratch) then reuse memory already mapped. The cost:
 *  memory freed stays with the process until it ends, and the call takes about 0.1 s for
 *  the ICT face's 33 MiB. Call after fp_session_create and before fp_session_start, on the
 *  thread that will step the session; calling it again (a new session) only adds a reserve.
 *  Returns 0; -EINVAL s NULL; -ENOTSUP not glibc's malloc, or a setting refused (a
 *  sanitizer's allocator: nothing more done, the session runs as without); -ENOMEM no
 *  reserve (the settings stay). err names the cause. [main-thread]. */
int fp_session_realtime_memory(fp_session *s, size_t reserve_bytes, char *err, size_t errlen);

/** One frame at host time now_ns (fp_now_ns()): the seven steps above. Never fails the
 *  session: an engine or mapping error keeps the base shown for this frame and is sent to
 *  the log (once, then counted). stats may be NULL. With a frame thread (made by
 *  fp_session_start, options .frame_thread) the frame runs there when that thread polls,
 *  which it does for 20 ms after each frame (a core kept busy through a performance), and
 *  on the caller's thread when it sleeps or has not taken the frame within 20 us; either
 *  way it is done when this returns (stats->frame_thread says where). Why: a thread that
 *  slept since the last frame finds its caches cold (the ICT frame's median 0.126 ms
 *  stepped on the bench's sleeping loop, 0.088 on the frame thread; frame_thread.h). */
void fp_session_step(fp_session *s, int64_t now_ns, fp_frame_stats *stats);

/** The engine step's solver (core/csrbf) whose coefficients made fp_session_positions, for
 *  a GPU warp (csrbf_solver_get_coefficients): non-NULL only while a deformation is shown
 *  (fp_session_positions != fp_session_base), made by one map (not composed by the fold-over
 *  guard), and the session has no rig (with a rig the shape
 *  is the posed base warped and blended by mobility, which the coefficients alone do not
 *  give). Valid until the next step, radius change or
 *  destroy; read it on the session thread between steps. */
const struct csrbf_solver *fp_session_solver(const fp_session *s);

/** What the shape shown this frame is made of, for a GPU warp that draws it from a surface
 *  and the engine's coefficients (the viewer's --gpu-warp, also with a rig): *surface, the
 *  surface the engine's map T runs on (the base posed by the rig's channels; the base itself
 *  without a rig; n x 3 floats, mesh units, the session's, valid until the next step, undo,
 *  reset or commit), and *solver, the engine solver whose coefficients are T, or NULL when
 *  the shape shown is the surface itself (nothing engaged). With a rig the shape shown is
 *  fp_rig_apply_mobility(rig, surface, T(surface)) (fp_rig_mobility's weights), without one
 *  T(surface). Returns 0, -EAGAIN when the shape shown this frame is neither (the contact
 *  guard's shape, an engine error), or -ERANGE when the fold-over guard composed several maps
 *  for it (the solver holds the last one only): draw fp_session_positions then. Session thread, between
 *  steps. */
int fp_session_warp_parts(const fp_session *s, const float **surface,
                          const struct csrbf_solver **solver);

/** The nearest vertex of the surface the fingers touch (fp_session_warp_parts' surface: the
 *  base posed by the rig) to each of `count` points (mesh units), within max_distance (mesh
 *  units; INFINITY: no bound): out[i] as plugin.h's fp_surface_hit (vertex UINT32_MAX and
 *  distance INFINITY where none is within reach; the vertex's position and unit normal).
 *  For the viewer's fingertip cues. Returns 0, -EINVAL (NULL, a non-finite point, a NaN or
 *  negative max_distance), -ENODATA (no triangles). Session thread, between steps; no
 *  allocation. */
int fp_session_surface_nearest(const fp_session *s, const float (*points)[3], size_t count,
                               float max_distance, fp_surface_hit *out);

/** Close the inputs' record=FILE recordings: each recorded input is stopped, what it had
 *  queued is written, its writer thread joined (inputs without a recording keep running). Returns 0, or the first recording's error (a failed write,
 *  events dropped because its writer fell behind; the event log's code or -ENOBUFS), also
 *  sent to the log, with the message in err. Call once, before
 *  destroy where a failed recording must change the exit status; destroy does it otherwise
 *  (and only logs). */
int fp_session_stop(fp_session *s, char *err, size_t errlen);

/** Input clock (options.input_clock): the earliest first event time of the recordings, once
 *  each has delivered one: 1 and *t0; 0 while waiting (poll again); -1 when no input is a
 *  recording (then step on the wall clock). */
int fp_session_input_start(fp_session *s, int64_t *t0);

/** Input clock: true when every recording has ended or delivered an event later than t, so
 *  that fp_session_step(s, t) sees every event up to t whatever the replay's pacing (poll it
 *  before each step; it consumes nothing). True without the input clock. */
bool fp_session_inputs_ready(fp_session *s, int64_t t);

/** Input clock: how many recordings have not yet delivered past t (after
 *  fp_session_inputs_ready said false), their names ('replay', 'osc', ...) in names (n bytes,
 *  cut short where it does not fit); the inputs' log lines waiting meanwhile go to the log
 *  (a wait for a forwarded recording says why). Session thread, between frames. */
size_t fp_session_inputs_waiting(fp_session *s, int64_t t, char *names, size_t n);

/** True once every input has reported FP_STATUS_END_OF_STREAM (recordings ended). */
bool fp_session_finished(const fp_session *s);

/** Ask for intents (fp_intent bits) on the next frame: keys, pedal bindings. */
void fp_session_request(fp_session *s, uint32_t intents);

/** Host actions between frames, recorded with the next frame's requested intents (bits
 *  above the fp_intent bits; docs/take-format.md): fp_session_undo and fp_session_reset. A
 *  take played back applies them before that frame (fp_session_take.h). */
#define FP_SESSION_ACTION_UNDO (1u << 16)
#define FP_SESSION_ACTION_RESET (1u << 17)

/** How many times the performer asked to start or stop a take (the pedal's middle button,
 *  pressed) since the last call; the count is cleared. The viewer reads it each frame. */
unsigned fp_session_record_toggles(fp_session *s);

/** Steps 5-7 of a frame on a given control set instead of the inputs and the mapping: a
 *  take's stored control set (the one the engine was given, after the rig) through the
 *  engine (factor or reuse, solve, guard, evaluate), history (its COMMIT) and the recorder
 *  (requested goes into the frame's record). The inputs are not drained. cs->count <=
 *  FP_ENGINE_MAX_CONTROL and cs->radius > 0 where cs->active (a take's frames are). */
void fp_session_apply_controls(fp_session *s, int64_t now_ns, const fp_control_set *cs,
                               uint32_t requested, fp_frame_stats *st);

/** The shape to show: vertex_count x 3 floats, mesh units; valid until the next step. */
const float *fp_session_positions(const fp_session *s);
/** The committed shape (the base): vertex_count x 3 floats, mesh units, the session's; valid
 *  until the next step, undo or reset (a commit rewrites it in place). */
const float *fp_session_base(const fp_session *s);

/** For a partial upload (the viewer): the vertex ranges, (*ranges)[2k] = first vertex,
 *  [2k+1] = count, increasing and disjoint, in which fp_session_positions may differ from
 *  what it was at this function's previous call; outside them it is bit for bit the same.
 *  Returns their number, 0 when nothing changed, or SIZE_MAX (*ranges NULL) when anything
 *  may have: the first call (which starts the record: a session nobody asks records
 *  nothing), undo, reset, a commit with a rig or the contact guard, a rig pose (channels),
 *  an engine error, a mapping swap. Otherwise the ranges are the union of the engine's per
 *  frame (fp_engine_step_touched: blocks of 16 vertices in a support now or at its last
 *  run), and where the contact guard's shape is shown, now or the frame before, of its D_P
 *  (the blocks where that shape may differ from the posed base: fp_cg_ranges). *ranges is
 *  the session's, valid until the next call. Session thread. */
size_t fp_session_touched(fp_session *s, const uint32_t **ranges);
/** The same for fp_session_base: a commit's ranges (the engine's), SIZE_MAX after undo,
 *  reset, a commit with a rig or through the contact guard. */
size_t fp_session_base_touched(fp_session *s, const uint32_t **ranges);
/** The shape as loaded: vertex_count x 3 floats, mesh units; the session's, unchanged while
 *  it lives. */
const float *fp_session_loaded(const fp_session *s);
size_t fp_session_vertex_count(const fp_session *s);
/** The loaded mesh (topology, UVs); its positions are the loaded shape. The session's, valid
 *  while it lives; do not free it. */
const struct fp_mesh *fp_session_mesh(const fp_session *s);
/** The support radius R of the Wendland functions the engine uses (Sato et al., section 3),
 *  mesh units. */
double fp_session_radius(const fp_session *s);
/** Set the support radius, mesh units, from the next frame on (the viewer's [ and ] keys,
 *  the control surface's /fp/radius). The bounds --radius has at open: at least a millionth
 *  and at most 10 times the mesh's bounding-box diagonal (fp_session_radius_range); outside
 *  them, or not finite, the radius stays and -ERANGE is returned (a radius of 1e-30 made the
 *  engine refuse every frame, the face still). Returns 0 or -ERANGE. [session-thread] or
 *  between frames. */
int fp_session_set_radius(fp_session *s, double radius);
/** The radii fp_session_set_radius takes, mesh units: *lo a millionth and *hi 10 times the
 *  mesh's bounding-box diagonal (of the vertices in a triangle). No errors. Any thread (it
 *  reads what fp_session_create fixed). */
void fp_session_radius_range(const fp_session *s, double *lo, double *hi);
const fp_calibration *fp_session_calibration(const fp_session *s);
/** The head found in the loaded mesh and the mesh's unit: head->mm_per_unit is the one the
 *  session uses (given, from the calibration's scale, or detected), head->how says where it
 *  came from ("detected from the head: ...", "from --mm-per-unit", "from the calibration"). */
const fp_head *fp_session_head(const fp_session *s);
/** A hand of the first performer (below) at the last frame's time in mesh units
 *  (fp_pose_build_at: its input's filter, interpolated or predicted from its samples; NULL if
 *  never seen, or its device is disconnected). Owned by the session; valid until the next
 *  fp_session_step. */
const fp_hand_pose *fp_session_hand(const fp_session *s, int hand);
/** For a viewer's event-to-frame latency: the host time (ns, fp_now_ns's clock) that the
 *  newest sample of the first performer's hand `hand` (fp_session_hand's time_ns) is late
 *  from. Its time_ns where its input measures on the host's clock (a tracker, a glove); the
 *  time it was pushed where the input keeps a recording's clock (a replay, a take: their
 *  times run on the recording's clock, which speed=X stretches away from the host's), so a
 *  replay at speed=0.5 or 2 is late by what the performer sees, not by the stretch. Under
 *  the input clock (options.input_clock) its time_ns. 0 before any sample. */
int64_t fp_session_hand_since(const fp_session *s, int hand);
/** Performers (the inputs' host key `performer=NAME`; core/session/performers.h): how many
 *  share the session (1 to FP_PERFORMER_CAPACITY; 1 where no input names one), performer i's
 *  name ("" for a first performer whose inputs name none; NULL beyond the count; the
 *  session's string) and its hand of fp_hand_side `hand` as fp_session_hand (performer 0's
 *  hands are fp_session_hand's; NULL beyond the count). Each performer's hands are placed by
 *  its own calibration; fp_session_calibration is the first performer's. [session-thread]
 *  or between frames. */
size_t fp_session_performer_count(const fp_session *s);
const char *fp_session_performer_name(const fp_session *s, size_t performer);
/** Performer i's calibration now (fp_pose.h: scale in mesh units per mm, offsets in mesh
 *  units, rotation device -> mesh): the one its hands are placed by, refined as they arrive
 *  where none was given. NULL beyond the count; owned by the session, valid until the next
 *  fp_session_step; performer 0's is fp_session_calibration's. No errors. [session-thread]
 *  or between frames. */
const fp_calibration *fp_session_performer_calibration(const fp_session *s, size_t performer);
const fp_hand_pose *fp_session_performer_hand(const fp_session *s, size_t performer, int hand);
/** The last control set (start/end points) the mapping made and the engine used, its radius
 *  the engine's (the mapping's, widened in a gesture the contact guard held back for flipped
 *  triangles alone: fp_frame_stats.flip_widen); the session's, rewritten by every step (copy
 *  what is kept). */
const fp_control_set *fp_session_control_set(const fp_session *s);
/** Replace the mapping by a new one from spec (NAME[,key=value...], as the mapping option),
 *  loaded from path: keeps the mesh, the base, the undo history, the inputs and the radius;
 *  drops a deformation in progress (the base is shown). On error the old mapping stays and
 *  err names the spec or plugin at fault (codes as fp_session_create: -EINVAL, FP_EPLUGIN_*).
 *  Session thread only (the viewer's keys 1 and 2). */
int fp_session_set_mapping(fp_session *s, const fp_plugin_path *path, const char *spec,
                           char *err, size_t errlen);
/** Hot reload: replace the mapping by the one in `file` (a path, e.g. a fresh copy of the
 *  mapping's rebuilt .so), created with the current mapping's SPEC keys, then reset; as
 *  fp_session_set_mapping otherwise (a deformation in progress is dropped; on error the old
 *  mapping stays and err says why: the loader's FP_EPLUGIN_* codes, the plugin's create
 *  code). Session thread only, between frames. */
int fp_session_reload_mapping(fp_session *s, const char *file, char *err, size_t errlen);
/** The file the mapping was found at by name (not a reload's copy), the loaded plugin (its
 *  entry's id and version), and the mapping's name. Valid until the mapping changes. An
 *  isolated mapping (fp_session_options.isolate) is loaded in its helper process: its
 *  fp_plugin has the path and an entry with the id and version its helper reported, and no
 *  handle, factory or entry functions. */
const char *fp_session_mapping_file(const fp_session *s);
const fp_plugin *fp_session_mapping_plugin(const fp_session *s);
const char *fp_session_mapping_name(const fp_session *s);
/** FP_EPLUGIN_FAULT when the mapping was stopped for a fault (it wrote past the capacity of
 *  the host's arrays; the base has been shown since), the message naming the mapping, the
 *  array and the frame in err; else 0. */
int fp_session_mapping_fault(const fp_session *s, char *err, size_t errlen);
/** The session's rig (core/rig), or NULL without one. */
const struct fp_rig *fp_session_rig(const fp_session *s);

/** The face's up and the axis it looks along, in mesh coordinates (unit): the options', the
 *  placed rig's, or +y and +z (fp_session_options.face_up). The viewer's and png-seq's camera
 *  turns about them. [any-thread] after fp_session_create. */
void fp_session_face_axes(const fp_session *s, float up[3], float facing[3]);
/** How the rig was chosen, for a command's first line: "rigs/ict-facekit.json (found by the
 *  mesh's checksum 577903df)", "... (given)", "none (--rig none)", "none (no rig fits ...)". */
const char *fp_session_rig_how(const fp_session *s);
/** Set a rig channel (e.g. "jaw.open"; the viewer's keys), clamped to its range; it applies
 *  from the next fp_session_step (a mapping that drives the channel overrides it). Returns 0,
 *  -ENOENT (no rig, or no such channel), -ERANGE (NaN). */
int fp_session_set_channel(fp_session *s, const char *name, double value);
/** A channel's current value; NaN without a rig or for an unknown name. */
double fp_session_channel(const fp_session *s, const char *name);

/** Committed gestures in the base since the loaded shape (one per undo level: an anchored
 *  commit, an unanchored drag): undo restores the count of the level it returns to, reset
 *  sets 0. [session-thread] or between frames, as every accessor here. */
unsigned long fp_session_commits(const fp_session *s);
/** Undo the last commit or reset (one level, up to FP_SESSION_UNDO_LEVELS): the base goes
 *  back, a deformation in progress is dropped, the mapping's gesture is reset. Returns false
 *  when there is nothing to undo. */
bool fp_session_undo(fp_session *s);
/** Back to the loaded shape (undoable when the base differed); rig channels to neutral. */
void fp_session_reset(fp_session *s);
/** Events dropped because an input's queue was full, over all inputs: an event the input
 *  pushed again until it was taken (a replay with fast=1) is not one
 *  (fp_event_queue_dropped); and those an input abandoned at its stop pushed after it was
 *  abandoned, as far as they are known when called (fp_input_instance_dropped: what it had
 *  queued and never had read is known only when the session is destroyed, and said then in
 *  that input's closing line). The session's owner's thread. */
unsigned long fp_session_dropped(const fp_session *s);

/** How many FP_STATUS_ERROR events the inputs reported (a damaged recording, a device that
 *  needs the performer); *last (may be NULL) gets the latest one's text, the session's, valid
 *  until the next step. */
unsigned fp_session_input_errors(const fp_session *s, const char **last);

/** Write the shape to show (normals recomputed) to path; format by extension. Returns 0,
 *  -ENOMEM, or the mesh writer's code unchanged (fp_mesh_save), err naming path. */
int fp_session_save(const fp_session *s, const char *path, char *err, size_t errlen);
/** fp_session_save, written back as the mesh came in (fp_mesh_save_ex): *dropped (may be
 *  NULL) gets what the file's format could not keep (FP_MESH_DROPPED_* bits). */
int fp_session_save_ex(const fp_session *s, const char *path, unsigned *dropped, char *err,
                       size_t errlen);

/** fp_session_stop if not done (its error only logged), then a pending repeated error's
 *  count is logged, plugins unloaded, everything freed; sets *s to NULL. NULL-safe. */
void fp_session_destroy(fp_session **s);

#ifdef __cplusplus
}
#endif
#endif
