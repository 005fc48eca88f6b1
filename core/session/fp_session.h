/*
 * fp_session.h: one puppeteering session, the frame loop of shared/docs/design.md: drain
 * the inputs' events, turn hands into poses (forward kinematics for joint angles), place
 * them in mesh space (workspace calibration), ask the mapping for a control set, and let
 * the CSRBF engine solve and evaluate deformed = T(base).
 *
 * Thread rules: a session is used from one thread (the session thread: the frame loop of
 * `facepuppet run` or the viewer). Input plugins run on their own threads and reach it only
 * through the lock-free queues of core/plugin.
 */
#ifndef FP_SESSION_H
#define FP_SESSION_H

#include "fp_plugin_host.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_SESSION_MAX_INPUTS 8

/** Workspace calibration: p_mesh = scale * p_mm + offset (hands: mm, device frame; the
 *  device's +x right, +y up, +z toward the performer, as the mesh's +x, +y, +z). */
typedef struct fp_calibration {
    double scale;        /* mesh units per millimetre */
    double offset[3];    /* mesh units */
} fp_calibration;

typedef struct fp_session_options {
    const char *mesh_path;                          /* required */
    const char *inputs[FP_SESSION_MAX_INPUTS];      /* SPECs */
    size_t input_count;
    const char *mapping;                            /* NAME[,key=value...]; "anchored" */
    double radius;                                  /* support radius, mesh units; 0: 6% of
                                                       the mesh's bounding-box diagonal */
    double hand_size;                               /* 0 or 1: mean adult hand */
    const fp_calibration *calibration;              /* NULL: fit the workspace to the face */
    const fp_plugin_path *plugin_path;              /* required */
    int engine_threads;                             /* 0: 1 below 200k vertices, else all
                                                       cores; -1: all cores; N: N threads */
} fp_session_options;

/** Statistics of one fp_session_step. */
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
    double update_ms;         /* engine solve + evaluate, milliseconds */
} fp_frame_stats;

typedef struct fp_session fp_session;

/** Load the mesh, load the mapping plugin and every input (not started). Returns 0, or a
 *  negative code with a message in err naming the file, SPEC or plugin at fault:
 *  -EINVAL bad options, FP_EPLUGIN_* for plugins (see fp_plugin_host.h), -ENOENT and
 *  -EBADMSG for the mesh (unreadable, malformed). */
int fp_session_create(const fp_session_options *opt, fp_session **out, char *err, size_t errlen);

/** Start the inputs' threads. */
int fp_session_start(fp_session *s, char *err, size_t errlen);

/** One frame at host time now_ns (fp_now_ns()). Never fails the session: an engine or
 *  mapping error keeps the last shape and is counted in the frame's stats and logged. */
void fp_session_step(fp_session *s, int64_t now_ns, fp_frame_stats *stats);

/** True once every input has reported FP_STATUS_END_OF_STREAM (recordings ended). */
bool fp_session_finished(const fp_session *s);

/** Ask for intents (fp_intent bits) on the next frame: keys, pedal bindings. */
void fp_session_request(fp_session *s, uint32_t intents);

/** The shape to show: vertex_count x 3 floats, mesh units; valid until the next step. */
const float *fp_session_positions(const fp_session *s);
/** The committed shape (the base). */
const float *fp_session_base(const fp_session *s);
/** The shape as loaded. */
const float *fp_session_loaded(const fp_session *s);
size_t fp_session_vertex_count(const fp_session *s);
/** The loaded mesh (topology, UVs); its positions are the loaded shape. */
const struct fp_mesh *fp_session_mesh(const fp_session *s);
double fp_session_radius(const fp_session *s);
void fp_session_set_radius(fp_session *s, double radius);
const fp_calibration *fp_session_calibration(const fp_session *s);
/** The latest pose of a hand in mesh units (NULL if never seen). */
const fp_hand_pose *fp_session_hand(const fp_session *s, int hand);
/** The last control set (start/end points) the engine used. */
const fp_control_set *fp_session_control_set(const fp_session *s);
/** Replace the mapping by a new one from spec (NAME[,key=value...], as the mapping option),
 *  loaded from path: keeps the mesh, the base, the undo history, the inputs and the radius;
 *  drops a deformation in progress (the base is shown). On error the old mapping stays and
 *  err names the spec or plugin at fault (codes as fp_session_create: -EINVAL, FP_EPLUGIN_*).
 *  Session thread only (the viewer's keys 1 and 2). */
int fp_session_set_mapping(fp_session *s, const fp_plugin_path *path, const char *spec,
                           char *err, size_t errlen);
/** Undo the last commit (one level of the commit history, up to 64), or back to loaded. */
bool fp_session_undo(fp_session *s);
void fp_session_reset(fp_session *s);
/** Events dropped because a queue was full, over all inputs. */
unsigned long fp_session_dropped(const fp_session *s);

/** How many FP_STATUS_ERROR events the inputs reported (a damaged recording, a device that
 *  needs the performer); *last gets the latest one's text. */
unsigned fp_session_input_errors(const fp_session *s, const char **last);

/** Write the shape to show (normals recomputed) to path; format by extension. */
int fp_session_save(const fp_session *s, const char *path, char *err, size_t errlen);

/** Stop inputs, unload plugins, free everything; sets *s to NULL. */
void fp_session_destroy(fp_session **s);

#ifdef __cplusplus
}
#endif
#endif
