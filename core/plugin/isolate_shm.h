/*
 * isolate_shm.h: what the host and an isolated mapping's helper process share (internal to
 * core/plugin: isolate.c is the host side, isolate_helper.c the helper's).
 *
 * One memfd, mapped by both: this header, then a variable part (the mesh's base, the rig's
 * regions, landmarks, channels and their names) whose size follows the mesh; the host grows
 * the memfd (ftruncate) and sets `size`, and the helper maps it again when `size` grew.
 * Everything is copied by value; pointers never cross (each side rebuilds its own).
 *
 * Wake-ups: two eventfds. The host writes a request (op, req_seq + 1) and writes `go`; the
 * helper answers (reply, reply_seq = req_seq) and writes `done`. During process() the helper
 * may ask for the host's surface service: it writes the points, reply FP_ISO_REPLY_SURFACE
 * and `done`, then waits on `go` for the host's FP_ISO_OP_SURFACE answer. A SOCK_SEQPACKET
 * socket carries the helper's log lines and its create result (fp_iso_msg), and its hang-up
 * tells either side that the other is gone.
 *
 * An isolated input (isolate_input.c, isolate_input_helper.c) uses the same memfd, eventfds
 * and socket: the host asks START and QUIT through the memory; the helper sends its READY,
 * log lines and every event its plugin pushes (FP_ISO_MSG_EVENT) on the socket, in order.
 *
 * Thread rules: the host side is one thread at a time (the session's; an isolated input's
 * reader thread once started); the mapping's helper is one thread.
 */
#ifndef FP_ISOLATE_SHM_H
#define FP_ISOLATE_SHM_H

#include <facepuppet/plugin.h>

#include <stdatomic.h>
#include <stdint.h>

#define FP_ISO_MAGIC 0x4f534946u        /* "FISO" */
#define FP_ISO_VERSION 4u              /* 2: the further performers' hands; 3: stage; 4: inputs */
#define FP_ISO_SURFACE_MAX 256          /* surface queries per round trip (more: several) */
#define FP_ISO_GUARD 8                  /* canary entries after each control-set array */
#define FP_ISO_CANARY 0xA5

enum { FP_ISO_OP_PROCESS = 1, FP_ISO_OP_RESET = 2, FP_ISO_OP_SURFACE = 3, FP_ISO_OP_QUIT = 4, FP_ISO_OP_START = 5 };
enum { FP_ISO_REPLY_DONE = 1, FP_ISO_REPLY_SURFACE = 2 };
/* EVENT: an isolated input's pushed event, its bytes in text (at most sizeof(fp_event)) */
enum { FP_ISO_MSG_READY = 1, FP_ISO_MSG_LOG = 2, FP_ISO_MSG_EVENT = 3 };
/* A LOG whose rc is FP_ISO_LOG_UNSENT: the mapping helper's count (decimal text) of log lines
 * it could not send since its last such count (the socket full: a plugin that floods its log),
 * sent before its reply, so the host counts them as dropped */
#define FP_ISO_LOG_UNSENT (-1000)
/* How far the helper got before its READY (fp_iso_shm.stage): for the message of a helper
 * that died or hung before it, "while loading" or "in create". */
enum { FP_ISO_STAGE_START = 0, FP_ISO_STAGE_LOAD = 1, FP_ISO_STAGE_CREATE = 2, FP_ISO_STAGE_READY = 3 };

/** A message on the socket: the create result (READY: rc, text the error) or a log line. */
typedef struct fp_iso_msg {
    uint32_t type;
    int32_t rc;       /* READY: create's code; LOG: the fp_log_level */
    char text[1000];
} fp_iso_msg;

/** A landmark or channel in the shared part: names as offsets into the string area. */
typedef struct fp_iso_landmark {
    uint32_t name;
    uint32_t vertex;
    float position[3];
} fp_iso_landmark;
typedef struct fp_iso_channel {
    uint32_t name;
    float min, max, neutral, value;
} fp_iso_channel;

typedef struct fp_iso_shm {
    uint32_t magic, version;
    _Atomic uint64_t size;            /* bytes of the memfd (header + variable part) */
    _Atomic uint64_t req_seq;         /* the host's request number */
    _Atomic uint64_t reply_seq;       /* the request the helper answered */
    uint32_t op;                      /* FP_ISO_OP_* of req_seq */
    uint32_t reply;                   /* FP_ISO_REPLY_* of reply_seq */
    int32_t rc;                       /* process()'s code */
    uint32_t offers;                  /* bit 0: surface, bit 1: rig (the host's extensions) */
    _Atomic uint32_t stage;           /* FP_ISO_STAGE_*, written by the helper */

    /* the frame: in's pointers are rebuilt by the helper */
    fp_frame_input in;
    fp_event events[FP_FRAME_EVENT_CAPACITY];
    /* in.extra_hands and in.extra_tip_distance (ABI 1.3), in.extra_performers x FP_HANDS rows */
    fp_hand_pose extra_hands[(FP_PERFORMER_CAPACITY - 1) * FP_HANDS];
    float extra_tips[(FP_PERFORMER_CAPACITY - 1) * FP_HANDS][FP_FINGERS];
    uint32_t has_mesh, has_rig;
    fp_mesh_view mesh;                /* base: at off_base */
    fp_rig_view rig;                  /* region, landmarks, channels, name: at their offsets */
    uint64_t off_base, off_region, off_landmarks, off_channels, off_strings;
    uint32_t rig_name;                /* offset of the rig's name in the strings */

    /* the control set, both ways, with canaries after each array */
    fp_control_set cs;                /* scalars; pointers rebuilt */
    float start[FP_CONTROL_CAPACITY + FP_ISO_GUARD][3];
    float end[FP_CONTROL_CAPACITY + FP_ISO_GUARD][3];
    fp_channel channels[FP_CHANNEL_CAPACITY + FP_ISO_GUARD];

    /* the surface service, one round trip */
    uint32_t surf_count;
    float surf_max;
    int32_t surf_rc;
    float surf_points[FP_ISO_SURFACE_MAX][3];
    fp_surface_hit surf_hits[FP_ISO_SURFACE_MAX];

    /* an isolated input's (isolate_input.c): its SPEC's ARG, written by the host before the
     * spawn; what its extensions answered after create, written by the helper before READY;
     * start's message */
    uint32_t in_has_arg;
    char in_arg[4096];
    uint32_t in_ext;                  /* FP_ISO_EXT_* bits */
    float in_ws_min[3], in_ws_max[3];
    fp_recording_info in_info;
    uint64_t in_joints, off_joints;   /* samples at off_joints: fp_iso_joints each; the helper
                                         grows the memfd (and `size`) to hold them */
    char in_err[512];
} fp_iso_shm;

/* in_ext: which extensions the instance offers, and what each answered */
enum {
    FP_ISO_EXT_WORKSPACE = 1, FP_ISO_EXT_WORKSPACE_OK = 2, FP_ISO_EXT_CLOCK = 4, FP_ISO_EXT_CLOCK_ON = 8,
    FP_ISO_EXT_INFO = 16, FP_ISO_EXT_INFO_OK = 32, FP_ISO_EXT_JOINTS = 64
};

/** One sample of an input's FP_EXT_RECORDING_JOINTS, as shared. */
typedef struct fp_iso_joints {
    int32_t hand;
    float mm[FP_HAND_JOINTS][3];
} fp_iso_joints;

#endif
