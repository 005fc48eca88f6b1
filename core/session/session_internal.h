/*
 * session_internal.h: the session's insides, shared by its files and by nothing else (the
 * API is fp_session.h): struct fp_session, and what one file gives another.
 *   session.c           the frame (fp_session_step: the seven steps), real-time memory,
 *                       the queries and edits, destruction
 *   session_open.c      fp_session_create, fp_session_start
 *   session_mapping.c   the mapping's load, swap and reload (fp_session_set_mapping, ...)
 *   session_performers.c  each performer's hands: the calibration, the frame's poses
 *   step_commit.c       the commit (step 6 with the rig and the contact guard; step_commit.h)
 *   step_contact.c      the contact guard's step (step_contact.h)
 */
#ifndef FP_SESSION_INTERNAL_H
#define FP_SESSION_INTERNAL_H

/* A grabbed point whose vertex's rig mobility (fp_rig_mobility) is under this lies on skin
 * the rig keeps still (the skull: mobility 0). A gesture made only of such points moves
 * nothing, and lets the live placement go on (session_performers.c). */
#define FP_SESSION_STILL_MOBILITY 0.05

#include "fp_session.h"

#include "changed.h"
#include "fp_isolate.h"
#include "fp_mesh.h"
#include "fp_pose.h"
#include "fp_rig.h"
#include "frame_thread.h"
#include "history.h"
#include "intents.h"
#include "performers.h"
#include "skin_reach.h"
#include "step_contact.h"
#include "sheet_bind.h"
#include "crack.h"
#include "step_engine.h"
#include "step_mapping.h"
#include "step_arrive.h"
#include "step_record.h"
#include "step_rig.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

struct fp_session {
    fp_mesh *mesh;
    size_t n;
    float *loaded, *base, *deformed;
    const float *shown;
    fp_slog log;

    fp_input_instance inputs[FP_SESSION_MAX_INPUTS];
    size_t input_count;
    bool stopped;                 /* fp_session_stop ran */

    fp_plugin mapping_plugin;
    fp_mapping *mapping;
    fp_mapping_host mapping_host;
    fp_log_relay mapping_relay; /* the mapping's log lines until the session thread hands them over */
    fp_mapping_services services;     /* the host extensions the mapping may ask for */
    char mapping_name[64];
    char mapping_spec[1024];      /* the SPEC it was made from (keys kept for a reload) */
    char mapping_file[4096];      /* the file it was found at (a reload loads a copy) */
    double mapping_budget_ms;
    int isolate;                  /* fp_isolate_mode of the options */
    fp_isolate_options isolate_opt;
    char isolate_helper[4096];
    fp_plugin_entry isolated_entry; /* an isolated mapping's id and version, for
                                       mapping_plugin.entry (no functions: the plugin is
                                       loaded in its helper) */
    char isolated_id[128], isolated_version[64];
    fp_mesh_view view;
    char rig_how[3072];           /* how the rig was chosen (fp_session_rig_how) */

    double radius;
    double diagonal;              /* the surface's bounding-box diagonal, mesh units */
    double touch_radius;          /* the default radius: touch is measured in it (plugin.h) */
    fp_head head;                 /* the head and the mesh's unit (life-size calibration) */
    double face[4];               /* the face's frame (fp_calibration.face): set where the rig
                                     says the face looks along another axis than +z, or up is
                                     not +y (a turned copy of its mesh); all zeros: none */
    uint8_t *used;                /* n: 1 where a vertex is in a triangle and not far off the
                                     rest; NULL when all are (fp_mesh_face_mask: the face's
                                     size and head) */
    float *canon;                 /* n x 3: the loaded shape turned into the face's frame (with
                                     face; the gloves' placement reads it) */
    fp_head face_head;            /* the head in the face's frame (with face) */
    bool engaged;                 /* the mapping's deformation is active */
    bool engaged_still;           /* ... and every point it grabbed lies on skin the rig keeps
                                     still (mobility under FP_SESSION_STILL_MOBILITY: the skull):
                                     the gesture moves nothing, so it does not hold a live
                                     placement (session_performers.c) */
    uint64_t frame;
    uint32_t actions;             /* FP_SESSION_ACTION_* since the last frame (recorded) */

    fp_intents intents;           /* step 1 */
    fp_pose_state pose[FP_PERFORMER_CAPACITY]; /* step 2: each performer's (performers.h);
                                     [0] the first's, the only one without performer= */
    fp_performers performers;     /* whose inputs are whose */
    fp_hand_pose extra_hands[(FP_PERFORMER_CAPACITY - 1) * FP_HANDS]; /* the frame's further
                                     performers' hands and their tip distances (plugin.h) */
    float extra_tips[(FP_PERFORMER_CAPACITY - 1) * FP_HANDS][FP_FINGERS];
    fp_mapping_step mapping_step; /* step 3 */
    fp_rig_step rig;
    bool channel_event_warned;   /* an input's channel event named no channel of the rig */              /* step 4 */
    fp_engine_step engine;        /* step 5 */
    fp_skin_reach_gesture gesture_reach; /* the gesture's reach so far (skin_reach.h) */
    fp_skin_reach_gesture gesture_reach_allowed; /* ... against what the rig allowed */
    fp_slog_repeat jump_report;          /* hands that jumped (fp_pose.h FP_POSE_JUMP_MM) */
    int64_t hand_since_ns[FP_HANDS];     /* fp_session_hand_since: the first performer's */
    fp_history history;           /* step 6 */
    fp_record_step record;        /* step 7 */
    fp_arrive_step arrive[FP_PERFORMER_CAPACITY]; /* each performer's placement as the hands
                                     run, and the hint (step_arrive.h) */

    fp_control_set cs;            /* its arrays are the mapping step's (with canaries) */

    fp_sheet_bind bind;           /* close sheets carried together (sheet_bind.h) */
    fp_crack crack;               /* cracked seams kept closed (crack.h) */
    double flip_widen;            /* this gesture's support widening (fp_cg_next_widen; 1: none) */
    double cs_asked_radius;       /* the mapping's radius where cs.radius was widened; 0: not */
    double flip_widened;          /* the most this gesture's support was widened (its log line) */
    fp_cg_step cg;                /* step 5, after the engine: the contact guard (step_contact.h);
                                     cg.contact NULL with no_contact_guard */

    /* what changed since the viewer last asked (fp_session_touched, changed.h) */
    fp_changed shown_changed, base_changed;
    uint32_t *guard_dp;           /* the guard's D_P when its shape was last shown (fp_cg_ranges'
                                     copy, guard_dp_n pairs; SIZE_MAX: not kept, anything): where
                                     that shape may differ from the reference (session.c) */
    size_t guard_dp_n, guard_dp_cap;
    int shown_substeps;           /* maps the engine composed for the shape shown (1: one,
                                     whose coefficients the solver holds; fp_session_warp_parts) */
    int shown_kind;               /* what s->shown held at the end of the last frame: */
    bool whole_rig_commit;        /* fp_session_options.whole_rig_commit */
    int frame_thread_opt;         /* fp_session_options.frame_thread */
    fp_frame_thread *ft;          /* the frame thread (frame_thread.h; fp_session_start),
                                     or NULL: frames run on the caller's */
};

enum {
    SHOWN_POSED,    /* the posed base */
    SHOWN_ENGINE,   /* the engine's output (through the rig's blend): differs from the posed
                       base only inside the engine's touched ranges */
    SHOWN_OTHER     /* the contact guard's shape */
};

/* session_mapping.c: the mapping of SPEC `mapping` loaded and created (from `file` where not
 * NULL: a copy being hot-reloaded); its reset and destruction (plugin calls, named for a
 * crash); the host's services it may ask for (FP_HOST_EXT_SURFACE) */
int fp__session_load_mapping(fp_session *s, const char *mapping, const fp_plugin_path *path,
                             const char *file, char *err, size_t errlen);
void fp__session_reset_mapping(fp_session *s);
void fp__session_destroy_mapping(fp_session *s, fp_mapping *m, const char *name);
void fp__session_mapping_services(fp_session *s);

/* session_open.c: a calibration whose unit (1 / scale mm per mesh unit) is far from the mesh's
 * own (the rig's, else the head's: as detected, or given) is warned of in the log, naming source
 * (the file, or the input and its calibration= file) and mesh_path; --calibration and an
 * input's calibration= alike. */
void fp__session_warn_calibration_unit(fp_session *s, const char *source, double scale,
                                       const char *mesh_path, const fp_head *head);

/* session_performers.c: the inputs' performers (performers.h) and each performer's pose state
 * and calibration (given, else its own inputs' workspaces, else placed as the hands arrive;
 * the glove placement), after the inputs opened; then, each frame, every performer's hands
 * placed and built at now_ns, the further performers' into in->extra_* with their fingertip
 * distances, and the hint per performer after the mapping. */
int fp__session_performers_open(fp_session *s, const fp_session_options *opt, char *err, size_t errlen);
void fp__session_performers_build(fp_session *s, int64_t now_ns);
void fp__session_performers_frame(fp_session *s, fp_frame_input *in, float reach);
void fp__session_performers_check(fp_session *s, int64_t now_ns, const fp_frame_input *in);

#endif
