/* fp_bench: the benchmark bodies behind `facepuppet bench` (ui/cli/cmd_bench.c parses the
 * command line and calls fp_bench_run). */
#ifndef FP_BENCH_H
#define FP_BENCH_H

#include <stdbool.h>
#include <stdio.h>

/** What to run. Zeroed: every case, full repetitions, a text table. */
typedef struct fp_bench_options {
    bool quick;        /* fewer repetitions (2 rounds instead of 3, about a fifth of the updates) */
    bool json;         /* one JSON object per line instead of the table */
    const char *only;  /* run this case only (one of fp_bench_cases), or NULL for all */
    bool no_contact_guard; /* case frame: sessions with fp_session_options.no_contact_guard
                              (`bench --no-contact-guard`: the frame without the guard's
                              collide time) */
    bool exact_frames;     /* case frame: sessions with fp_session_options.exact_frames
                              (`bench --exact-frames`: no contact hold, every shown frame the
                              engine's shape bit for bit) */
    bool no_rig;           /* case frame: sessions with rig_path "none" (`bench --no-rig`):
                              the ICT face without its rig, as its subdivisions always are */
    bool every_frame;      /* case frame: the replay on its own clock (`bench --every-frame`):
                              every 60 fps frame stepped, none skipped, each timed; a slow
                              frame delays the next instead of skipping periods, so its
                              hands are never merged with later ones' */
    unsigned subdivide;    /* case frame: bit L set (1 <= L <= FP_BENCH_MAX_LEVEL) runs ICT
                              subdivided L times (`bench --subdivide L[,L...]`); 0: level 3 */
    const char *mapping;   /* case frame: the sessions' mapping (`bench --mapping NAME`);
                              NULL: anchored */
    const struct fp_plugin_path *plugin_path; /* where the replay and mapping plugins are
                                                 (case frame; NULL: that case is skipped) */
    FILE *trace;             /* case frame: one CSV row per frame of each mesh written here
                                (`bench --trace FILE.csv`; FP_BENCH_TRACE_HEADER first), or
                                NULL; borrowed, left open */
} fp_bench_options;

/** The most midpoint subdivisions of the ICT face the frame case makes (level 3: about 1.7M
 *  vertices; each level 4x the triangles). */
#define FP_BENCH_MAX_LEVEL 3

/** The trace's header line (fp_bench_options.trace): the columns, in order. Times in ms;
 *  cpu_wait_ms empty where /proc/thread-self/schedstat is missing; contact_node_pairs ..
 *  contact_certified: the contact guard's walks, summed over the frame's checks
 *  (fp_frame_stats.collide_*); skipped_after: the 60 fps periods that passed while the frame
 *  ran (frames the paced loop skipped after it). */
#define FP_BENCH_TRACE_HEADER                                                                  \
    "mesh,frame,frame_ms,events_ms,hands_ms,distances_ms,mapping_ms,solve_ms,evaluate_ms,"     \
    "shape_ms,commit_ms,contact_ms,contact_worker_wait_ms,cpu_wait_ms,cpu,active,engaged,"      \
    "committed,refactored,control_vectors,pairs,guard_substeps,contact_t,contact_pairs,"       \
    "contact_held,contact_checks,contact_moved,contact_node_pairs,contact_leaf_pairs,"          \
    "contact_tested,contact_certified,skipped_after\n"

/** The case names, in the order they run; NULL-terminated. */
extern const char *const fp_bench_cases[];

/** Run the cases. Prints the table (or JSON lines) on stdout and progress on stderr.
 *  Returns 0, -EINVAL (o->only names no case), -ENOMEM (a set-up allocation failed) or
 *  FP_ENUMERIC (an engine call failed; its message is on stderr). Not thread-safe. */
int fp_bench_run(const fp_bench_options *o);

/** `--case take` (bench/bench_take.c): the take recorder's cost on the session thread
 *  (median, p99 and max of fp_take_recorder_push per frame, 10 control vectors and 4
 *  events, while the recorder thread writes to a folder under /tmp) and a take's size per
 *  minute at 60 fps. One line of text, or one JSON object with json != 0, to `out`.
 *  quick: 4000 frames instead of 20000 (docs/performance.md: how long). Returns 0, or 1 when the
 *  take could not be written (the reason on stderr). */
int fp_bench_take(FILE *out, int quick, int json);

struct fp_mesh;
/** The frame case's isolated mapping (bench_isolate.c, issue 56): the same paced replay of
 *  three-claps (data_dir's) on `mesh` with the mapping in process, then in a helper process;
 *  prints the mapping stage's medians, their difference (the overhead a frame, us) and ratio,
 *  the whole frame's medians and the helper's resident memory (a table, or one JSON line
 *  labelled `label`). Returns 0 or the session's code (its message on stderr). */
int fp_bench_isolate(FILE *out, const fp_bench_options *bo, const struct fp_mesh *mesh, const char *label,
                     const char *data_dir, bool json);
/** The same on the MediaPipe face (468 vertices): the overhead without the large base's copy. */
int fp_bench_isolate_small(FILE *out, const fp_bench_options *bo, const char *data_dir, bool json);

/** The ICT face's rig carried through the frame case's subdivisions (bench_rig.c; the rule is
 *  there): open a rig file (a JSON document held whole), carry it from `coarse` to `fine`
 *  (fp_mesh_subdivide(coarse); the rig must be coarse's), write it to a new temporary file
 *  (path: its name, n bytes; the caller unlinks it), free it. Each returns 0 or a negative
 *  code with err set. One thread. */
typedef struct fp_bench_rig fp_bench_rig;
int fp_bench_rig_open(const char *path, fp_bench_rig **out, char *err, size_t errlen);
int fp_bench_rig_subdivide(fp_bench_rig *r, const struct fp_mesh *coarse, const struct fp_mesh *fine,
                           char *err, size_t errlen);
int fp_bench_rig_write(const fp_bench_rig *r, char *path, size_t n, char *err, size_t errlen);
void fp_bench_rig_free(fp_bench_rig **r);

#endif
