/*
 * facepuppet/plugin.h: the plugin ABI of facepuppet, the one header a plugin author needs.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * A plugin is a shared object (input-NAME.so or map-NAME.so) that exports one constant
 * symbol, `facepuppet_plugin_entry`, of type fp_plugin_entry. The host never looks up any
 * other symbol. Everything else is reached through factories asked for by string id
 * (get_factory), and optional features through get_extension with versioned string ids, so
 * the ABI grows without breaking (the pattern of CLAP's clap_entry).
 *
 * Versioning: the host loads a plugin whose abi.major equals FP_PLUGIN_ABI_MAJOR and whose
 * abi.minor is at most the host's FP_PLUGIN_ABI_MINOR; anything else is refused with an error
 * naming both versions. Structs that may grow start with a `size` field set by whoever fills
 * them (sizeof of the struct as that side compiled it); the reader reads no field past it:
 * FP_HAS_FIELD(ptr, type, field) is that test. Fill these structs with designated
 * initialisers (`.size = sizeof(fp_input), .start = my_start, ...`), as the templates do, so
 * that fields an ABI minor adds stay zero.
 *
 * Threads, as CLAP writes them:
 *   [main-thread]    the thread that loaded the plugin (the host's control thread);
 *   [input-thread]   a thread the input plugin creates and owns;
 *   [session-thread] the host's frame loop; a call marked so must not allocate, block, do
 *                    I/O or take locks, and must return within a small part of a frame.
 *                    Calls come one at a time and in order, but not always from the same
 *                    OS thread (a frame runs on the host's frame thread or its caller's):
 *                    keep no thread-local state between them;
 *   [any-thread]     any thread, concurrently.
 *
 * Units: hands in millimetres in the device frame before calibration; the mapping sees them
 * in mesh units (after the host's workspace calibration). Angles in radians. Times in
 * nanoseconds of CLOCK_MONOTONIC (fp_host.now_ns).
 *
 * The device frame, in which every input delivers positions and wrist poses: right-handed,
 * millimetres, the performer facing the device (and the face):
 *   +x to the performer's right, +y up, +z toward the performer (out of the device),
 * the frame of a Leap Motion controller. An input whose device measures in other axes or
 * units turns its data into this frame before pushing it. The host's workspace calibration
 * then places it at the face (identity rotation: device +x, +y, +z onto the mesh's +x, +y,
 * +z, a mesh whose face looks along +z).
 *
 * Errors: functions return 0 or a negative code: a negative errno (-EINVAL a bad key or
 * value, -ENOENT/-ENODEV a file or device not there, -EBADMSG malformed data, -EIO, -ENOMEM,
 * ...; docs/plugin-guide.md, installed with the SDK, gives the exit status each one leads
 * to) or one of facepuppet's own codes (FP_EPLUGIN_*, FP_ENUMERIC, all below -1000;
 * facepuppet/errors.h, included here), which a plugin may meet in what the host reports and
 * never needs to return.
 */
#ifndef FACEPUPPET_PLUGIN_H
#define FACEPUPPET_PLUGIN_H

#include <facepuppet/errors.h> /* FP_EPLUGIN_*, FP_ENUMERIC: facepuppet's own error codes */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_PLUGIN_ABI_MAJOR 1
#define FP_PLUGIN_ABI_MINOR 3   /* 1.1: capacities, face frame, rig and surface services,
                                   typed parameters; 1.2: channel events (FP_EVENT_CHANNEL);
                                   1.3: further performers' hands (fp_frame_input.extra_*),
                                   the touch radius (fp_frame_input.touch_radius);
                                   1.0 to 1.2 plugins still load */

/** True when the struct at `ptr` (of ABI type `type`, starting with `uint32_t size`) is large
 *  enough to hold `field`: its size covers the field's last byte. A reader tests it before
 *  reading a field that a later ABI minor added, e.g.
 *  `if (FP_HAS_FIELD(in, fp_frame_input, mm_per_unit) && in->mm_per_unit > 0) ...`
 *  (a 1.0 host's fp_frame_input ends before mm_per_unit). `ptr` is evaluated once. */
#define FP_HAS_FIELD(ptr, type, field) \
    ((size_t)(ptr)->size >= offsetof(type, field) + sizeof(((type *)0)->field))

/** How far fp_frame_input.tip_distance is exact, in support radii: beyond it the host reports
 *  +INFINITY. A fingertip farther than the support radius from every vertex moves none
 *  (the Wendland function is 0 there), and the host's search stops there, so its cost follows
 *  the fingers' reach, not the mesh (ABI 1.1; a 1.0 host reported every distance). */
#define FP_TIP_DISTANCE_REACH 1.0

/** Capacities the host guarantees (ABI 1.1). A mapping may rely on at least this many
 *  control vectors and channels in every fp_control_set (fp_control_set.capacity and
 *  channel_capacity say the exact figure, never less than these). */
#define FP_CONTROL_CAPACITY 64
#define FP_CHANNEL_CAPACITY 16
/** At most this many events (buttons, status) reach a mapping in one frame. */
#define FP_FRAME_EVENT_CAPACITY 64
/** At most this many performers share a session (ABI 1.3): the first one's hands are
 *  fp_frame_input.hands, the others' fp_frame_input.extra_hands (at most
 *  FP_PERFORMER_CAPACITY - 1 pairs). An input joins a performer with the host's SPEC key
 *  `performer=NAME`; inputs without it are the first performer's. */
#define FP_PERFORMER_CAPACITY 4

/** Name of the one exported symbol, of type `const fp_plugin_entry`. */
#define FP_PLUGIN_ENTRY_SYMBOL "facepuppet_plugin_entry"

/** Factory ids for fp_plugin_entry.get_factory. */
#define FP_INPUT_FACTORY_ID   "facepuppet.input-factory/1"
#define FP_MAPPING_FACTORY_ID "facepuppet.mapping-factory/1"

#if defined(_WIN32)
#define FP_PLUGIN_EXPORT __declspec(dllexport)
#else
#define FP_PLUGIN_EXPORT __attribute__((visibility("default")))
#endif

typedef struct fp_version {
    uint32_t major;
    uint32_t minor;
} fp_version;

/** True when a plugin built for `plugin` can be loaded by a host of `host`. */
static inline bool fp_version_is_compatible(fp_version host, fp_version plugin)
{
    return plugin.major == host.major && plugin.minor <= host.minor;
}

/* ------------------------------------------------------------------------------------- */
/* Hands                                                                                 */

/** Sensors of a 22-sensor CyberGlove, in the order the glove sends them in a record (as the
 *  open readers name them: asr_cyberglove_lib, Shadow Robot's and TAMS' drivers): thumb
 *  rotation, thumb MPJ, IJ and abduction; index MPJ, PIJ, DIJ; middle MPJ, PIJ, DIJ and
 *  middle-index abduction; ring likewise with ring-middle abduction; pinkie likewise with
 *  pinkie-ring abduction; palm arch; wrist pitch and yaw. The 18-sensor glove is the same
 *  list without the four DIJ sensors. */
enum fp_glove_sensor {
    FP_SENSOR_THUMB_ROTATE = 0, FP_SENSOR_THUMB_MPJ, FP_SENSOR_THUMB_IJ, FP_SENSOR_THUMB_AB,
    FP_SENSOR_INDEX_MPJ, FP_SENSOR_INDEX_PIJ, FP_SENSOR_INDEX_DIJ,
    FP_SENSOR_MIDDLE_MPJ, FP_SENSOR_MIDDLE_PIJ, FP_SENSOR_MIDDLE_DIJ, FP_SENSOR_MIDDLE_INDEX_AB,
    FP_SENSOR_RING_MPJ, FP_SENSOR_RING_PIJ, FP_SENSOR_RING_DIJ, FP_SENSOR_RING_MIDDLE_AB,
    FP_SENSOR_PINKIE_MPJ, FP_SENSOR_PINKIE_PIJ, FP_SENSOR_PINKIE_DIJ, FP_SENSOR_PINKIE_RING_AB,
    FP_SENSOR_PALM_ARCH, FP_SENSOR_WRIST_PITCH, FP_SENSOR_WRIST_YAW,
    FP_GLOVE_SENSORS = 22
};

/** Joints of one hand as positions: the palm centre, then for each finger (thumb, index,
 *  middle, ring, pinky) four points from the hand outward: MCP, PIP, DIP, tip (for the
 *  thumb CMC, MCP, IP, tip): Leap Motion's skeleton, finger by finger, bone ends in order. */
enum fp_hand_joint {
    FP_JOINT_PALM = 0,
    FP_JOINT_FINGER0 = 1,       /* first joint of the thumb; finger f, segment k: 1 + 4f + k */
    FP_HAND_JOINTS = 21
};
#define FP_FINGERS 5
#define FP_JOINT(finger, k) (1 + 4 * (finger) + (k))   /* k: 0 MCP, 1 PIP, 2 DIP, 3 tip */
#define FP_JOINT_TIP(finger) FP_JOINT(finger, 3)

typedef enum fp_hand_side { FP_HAND_LEFT = 0, FP_HAND_RIGHT = 1, FP_HANDS = 2 } fp_hand_side;

/* ------------------------------------------------------------------------------------- */
/* Events: flat, memcpy-able structs behind a common header                              */

/** The farthest a joint or wrist position may be from the device's origin, on any axis, in
 *  mm (10 m): beyond it a position is broken or hostile, and the host refuses the event. */
#define FP_EVENT_MAX_MM 10000.0f

typedef enum fp_event_type {
    FP_EVENT_JOINT_ANGLES = 1,    /* fp_event_joint_angles */
    FP_EVENT_JOINT_POSITIONS = 2, /* fp_event_joint_positions */
    FP_EVENT_WRIST_POSE = 3,      /* fp_event_wrist_pose */
    FP_EVENT_BUTTON = 4,          /* fp_event_button */
    FP_EVENT_STATUS = 5,          /* fp_event_status */
    FP_EVENT_CHANNEL = 6          /* fp_event_channel (ABI 1.2) */
} fp_event_type;

typedef struct fp_event_header {
    uint32_t size;     /* sizeof the whole event struct */
    uint16_t type;     /* fp_event_type */
    uint16_t flags;    /* FP_EVENT_FLAG_* below, 0 where none applies */
    int64_t time_ns;   /* when the device measured it (host clock, fp_host.now_ns) */
    uint32_t source;   /* set by the host: which input instance pushed it */
    int32_t hand;      /* fp_hand_side, or -1 where no hand applies */
} fp_event_header;

/** header.flags: the tracker gives each sample as it measured it, with no smoothing of its
 *  own (a camera landmark model such as MediaPipe's, whose joints jitter by millimetres from
 *  frame to frame). A host's input filter `filter=auto` (the osc input's default) smooths the
 *  hands of these events and passes the others as sent (a Leap service's joints, which it
 *  smooths itself: the Leap recordings in shared/data move under 0.05 mm off a straight line
 *  from sample to sample). Plugins built before the flag send 0; hosts before it ignore it. */
#define FP_EVENT_FLAG_UNSMOOTHED 0x1u

/** Joint angles in radians, CyberGlove sensor order. Bit i of `valid` is set where sensor i
 *  was measured; the others are 0 and must be ignored (the host uses its default pose). */
typedef struct fp_event_joint_angles {
    fp_event_header header;
    uint32_t valid;
    float radians[FP_GLOVE_SENSORS];
} fp_event_joint_angles;

/** Joint positions in millimetres in the device frame (+x the performer's right, +y up, +z
 *  toward the performer; above), fp_hand_joint layout. */
typedef struct fp_event_joint_positions {
    fp_event_header header;
    float mm[FP_HAND_JOINTS][3];
} fp_event_joint_positions;

/** Wrist pose in the device frame: position in mm, orientation as a unit quaternion
 *  (w, x, y, z) turning the hand's own frame into the device frame. The hand's frame is
 *  right-handed: +y out of the back of the hand, -z toward the fingers, x = y cross z (toward
 *  the pinky of a right hand, the thumb of a left hand: Leap Motion's convention). */
typedef struct fp_event_wrist_pose {
    fp_event_header header;
    float position_mm[3];
    float rotation[4];
} fp_event_wrist_pose;

enum fp_button {
    FP_BUTTON_LEFT = 1u << 0,
    FP_BUTTON_MIDDLE = 1u << 1,
    FP_BUTTON_RIGHT = 1u << 2,
    /** Not a physical button: a request for the intents in `mask` (fp_intent bits), as the
     *  performer's keys make them (down = 1; no release follows). The take input pushes it
     *  to perform a take's key requests again; the host binds it like a key (ABI 1.1). */
    FP_BUTTON_REQUEST = 1u << 8
};

/** A button went down or up. `mask` is every button held after this change (chords). */
typedef struct fp_event_button {
    fp_event_header header;
    uint32_t button;   /* one fp_button bit */
    uint32_t down;     /* 1 pressed, 0 released */
    uint32_t mask;
} fp_event_button;

typedef enum fp_status_code {
    FP_STATUS_CONNECTED = 1,     /* device found and streaming */
    FP_STATUS_DISCONNECTED = 2,  /* device gone (unplugged, cable pulled, EOF) */
    FP_STATUS_RECONNECTING = 3,  /* trying again; text says when */
    FP_STATUS_WARNING = 4,       /* something odd but recoverable (line noise, resync) */
    FP_STATUS_ERROR = 5,         /* the input cannot go on without the performer */
    FP_STATUS_END_OF_STREAM = 6  /* a recording ended (not looping) */
} fp_status_code;

typedef struct fp_event_status {
    fp_event_header header;
    uint32_t code;      /* fp_status_code */
    char text[116];     /* NUL-terminated, human readable */
} fp_event_status;

/** A rig channel's value from an input (ABI 1.2), e.g. input-audio's loudness on
 *  "jaw.open": the host sets the channel (clamped to its range, as the viewer's keys) when it
 *  drains the event, before the frame's mapping runs; a channel the mapping also returns
 *  that frame takes the mapping's value. A name the rig lacks (or a session without a rig)
 *  is reported once and otherwise ignored. hand: -1. Not passed to the mapping. */
typedef struct fp_event_channel {
    fp_event_header header;
    char name[32];      /* NUL-terminated, at most 31 bytes */
    float value;        /* finite */
} fp_event_channel;

/** Any event; the host's queues hold these. */
typedef union fp_event {
    fp_event_header header;
    fp_event_joint_angles angles;
    fp_event_joint_positions positions;
    fp_event_wrist_pose wrist;
    fp_event_button button;
    fp_event_status status;
    fp_event_channel channel;   /* ABI 1.2 */
} fp_event;

/* ------------------------------------------------------------------------------------- */
/* Host services                                                                         */

typedef enum fp_log_level { FP_LOG_ERROR = 0, FP_LOG_WARNING, FP_LOG_INFO, FP_LOG_DEBUG } fp_log_level;

/** What the host offers a plugin instance. Each instance gets its own fp_host, valid until
 *  the instance is destroyed. */
typedef struct fp_host {
    uint32_t size;
    fp_version abi;
    void *host_data;   /* the host's; do not touch */

    /** [any-thread, lock-free, wait-free] Copy one event into this instance's queue. The host
     *  sets header.source. Returns false when the queue is full: the event is dropped and
     *  counted by the host (the session thread always has the latest pose anyway), unless
     *  the plugin pushes the same event again and it is taken (a recording's replay that
     *  waits for room): then its refusals are not counted as drops; false
     *  too, and not counted, when header.size is below sizeof(fp_event_header) or above
     *  sizeof(fp_event). A malformed event (another type's size, a NaN, a position beyond
     *  FP_EVENT_MAX_MM, a rotation that is not a unit quaternion, a pose without a hand: the
     *  rule `facepuppet plugins check` applies) is refused: true is returned, the event is
     *  dropped, and the host warns once per kind and counts them. The event is copied: it
     *  may live on the caller's stack. */
    bool (*push_event)(const struct fp_host *host, const fp_event_header *event);

    /** [any-thread] The host clock: CLOCK_MONOTONIC in nanoseconds. */
    int64_t (*now_ns)(const struct fp_host *host);

    /** [any-thread] Report a message; the host prefixes the instance's name. The line is
     *  kept (up to 32 at a time; more are counted and reported as dropped) and handed to the
     *  session's log on the session's thread at its next frame (the host prints nothing
     *  itself: `run` prints the line, `live` shows it in its status line). Not for
     *  [session-thread] calls, which must not do I/O. */
    void (*log)(const struct fp_host *host, fp_log_level level, const char *message);

    /** [main-thread] Optional host features by versioned id; NULL where not offered. The
     *  struct returned stays valid while the instance lives: ask in create and keep it, then
     *  call its functions on the threads each documents (e.g. [session-thread]). */
    const void *(*get_extension)(const struct fp_host *host, const char *id);
} fp_host;

/** One `key=value` of a SPEC (`NAME[:ARG][,key=value...]`). Strings owned by the host, valid
 *  during the call they are passed to. */
typedef struct fp_param {
    const char *key;
    const char *value;
} fp_param;

/** Typed description of one key a factory accepts (ABI 1.1), for `facepuppet plugins`,
 *  `plugins check` and the viewer. A list ends with an entry whose name is NULL. */
typedef enum fp_param_type {
    FP_PARAM_BOOL = 1,         /* 0 or 1 */
    FP_PARAM_INT = 2,          /* integer in [min, max] */
    FP_PARAM_FLOAT = 3,        /* real in [min, max] */
    FP_PARAM_ENUM = 4,         /* one of `choices` ("a|b|c") */
    FP_PARAM_STRING = 5,       /* free text */
    FP_PARAM_PATH = 6          /* a file or device path */
} fp_param_type;
typedef struct fp_param_info {
    const char *name;          /* the key */
    fp_param_type type;
    double min, max;           /* INT and FLOAT; ignored otherwise */
    const char *default_value; /* as text; NULL where the key is required */
    const char *choices;       /* ENUM: "a|b|c"; NULL otherwise */
    const char *unit;          /* e.g. "mm", "s", "mesh units"; NULL where none */
    const char *description;   /* one line */
} fp_param_info;

/* ------------------------------------------------------------------------------------- */
/* Input plugins                                                                         */

/** An input instance. The plugin fills and owns it; the host calls through it. */
typedef struct fp_input {
    uint32_t size;
    void *plugin_data;

    /** [main-thread] Start producing events, on the plugin's own thread(s). Returns 0, or a
     *  negative errno-style code after writing a message to `err` (errlen bytes). */
    int (*start)(struct fp_input *self, char *err, size_t errlen);

    /** [main-thread] Stop: join the plugin's threads. No push_event after it returns. May be
     *  called without a successful start. The host calls it on a thread of its own while the
     *  main thread waits (no other call into the instance meanwhile), at most 5 s: a stop that
     *  has not returned by then is abandoned (destroy is never called; the plugin stays
     *  loaded), so make a blocking read wake up for it. */
    void (*stop)(struct fp_input *self);

    /** [main-thread] Free the instance (after stop). */
    void (*destroy)(struct fp_input *self);

    /** [main-thread] Optional features by versioned id; may be NULL. */
    const void *(*get_extension)(const struct fp_input *self, const char *id);
} fp_input;

/** Optional input extension FP_EXT_WORKSPACE: the box the hands move in, millimetres,
 *  device frame. A recording knows it in advance; a live device may give its tracking
 *  volume. The host's default workspace calibration fits this box to the face; where no
 *  input gives one, the host estimates it from the joint positions as the hands arrive and
 *  refines it as they move (docs/calibration.md, "Live inputs").
 *  [main-thread], after create. Returns false where unknown. */
#define FP_EXT_WORKSPACE "facepuppet.workspace/1"
typedef struct fp_input_workspace {
    bool (*get)(const fp_input *self, float min_mm[3], float max_mm[3]);
} fp_input_workspace;

/** Optional input extension FP_EXT_INPUT_CLOCK: an input without a recording of its own whose
 *  event times nevertheless follow a recording's clock (the OSC input with clock=recording,
 *  fed by another session's forward=): a host that steps on the recordings' clock (`run`)
 *  waits for it as for a recording: a frame at time t is made once the input has delivered an
 *  event later than t or ended (FP_STATUS_END_OF_STREAM). Such an input must keep its event
 *  times, statuses included, non-decreasing, and end its stream when its source stops.
 *  [main-thread], after create. Returns false where the times are measured as they come. */
#define FP_EXT_INPUT_CLOCK "facepuppet.input-clock/1"
typedef struct fp_input_clock {
    bool (*on_recording_clock)(const fp_input *self);
} fp_input_clock;

/** Optional input extension FP_EXT_RECORDING_INFO: what a recording holds, for
 *  `facepuppet info`. [main-thread], after create. Returns false where not a recording. */
#define FP_EXT_RECORDING_INFO "facepuppet.recording-info/1"
typedef struct fp_recording_info {
    uint64_t frames;          /* distinct sample times */
    uint32_t hands;           /* bit per fp_hand_side seen */
    double rate_hz;           /* median sample rate */
    double duration_s;        /* first to last sample */
    char format[32];          /* e.g. "joints-csv", "angles-csv", "eventlog", "leap-playback" */
} fp_recording_info;
typedef struct fp_input_recording {
    bool (*get)(const fp_input *self, fp_recording_info *info);
} fp_input_recording;

/** Optional input extension FP_EXT_RECORDING_JOINTS: a recording's joint positions in
 *  advance, for the host's placement (docs/calibration.md, "Hands that never come near"):
 *  each calls fn once per FP_EVENT_JOINT_POSITIONS event it will push, in order, with the
 *  event's hand (fp_hand_side) and its FP_HAND_JOINTS positions (mm, device frame; the
 *  pointer valid during the call). Only an input that also states its workspace
 *  (FP_EXT_WORKSPACE) is asked. [main-thread], after create, before start. Returns the
 *  number of samples given (0: none). */
#define FP_EXT_RECORDING_JOINTS "facepuppet.recording-joints/1"
typedef struct fp_input_recording_joints {
    size_t (*each)(const fp_input *self, void (*fn)(void *ctx, int hand, const float (*mm)[3]), void *ctx);
} fp_input_recording_joints;

typedef struct fp_input_factory {
    uint32_t size;
    const char *name;        /* the SPEC name, e.g. "replay" */
    const char *description; /* one line */
    const char *usage;       /* SPEC grammar and keys, several lines */

    /** [main-thread] Create an instance from a SPEC's ARG (NULL where none) and keys.
     *  Returns 0 and *out, or a negative errno-style code after writing a message naming
     *  the offending key or file to `err` (errlen bytes). Unknown keys are an error. */
    int (*create)(const fp_host *host, const char *arg, const fp_param *params, size_t nparams,
                  fp_input **out, char *err, size_t errlen);

    /* ABI 1.1 (read where size covers it): the keys, ended by a NULL name; may be NULL. */
    const fp_param_info *params;
} fp_input_factory;

/* ------------------------------------------------------------------------------------- */
/* Mapping plugins                                                                       */

/** The pose of one hand at the frame's time, in mesh units after the workspace calibration:
 *  the host filters each input's samples (One Euro, per the input's SPEC) and interpolates
 *  between them, or predicts at most one sample ahead, to the frame's time. */
typedef struct fp_hand_pose {
    bool present;              /* false: never seen, or the input reported it gone */
    int64_t time_ns;           /* when the newest sample it is made from was measured */
    float joints[FP_HAND_JOINTS][3];
} fp_hand_pose;

/** Read-only view of the mesh the session deforms. */
typedef struct fp_mesh_view {
    size_t vertex_count;
    const float *base;         /* vertex_count x 3: the committed shape (the "base") */
    float bounds_min[3], bounds_max[3];
} fp_mesh_view;

enum fp_intent {
    FP_INTENT_ENGAGE = 1u << 0,   /* begin a deformation (anchored: start points are set now) */
    FP_INTENT_COMMIT = 1u << 1,   /* fold the current deformation into the base */
    FP_INTENT_CANCEL = 1u << 2    /* drop the current deformation, back to the base */
};

/** What the host gives a mapping each frame. It and everything it points to (events, mesh,
 *  mesh->base, rig) are the host's, valid during the process call only: copy what is kept. */
typedef struct fp_frame_input {
    uint32_t size;
    int64_t time_ns;               /* the frame's time */
    uint64_t frame;                /* frame number since the session began */
    fp_hand_pose hands[FP_HANDS];  /* the hands at time_ns, left and right */
    const fp_event *events;        /* button and status events since the last frame */
    size_t event_count;
    const fp_mesh_view *mesh;
    double radius;                 /* the session's support radius, mesh units */
    uint32_t requested;            /* fp_intent bits asked for by the performer (keys, pedal) */
    /** Distance from each fingertip (FP_JOINT_TIP) of each present hand to the nearest
     *  vertex of the base, mesh units, exact up to FP_TIP_DISTANCE_REACH x the larger of
     *  radius and touch_radius; +INFINITY
     *  beyond it ("far") and for an absent hand. The paper's rule "a hand is active while its
     *  fingertips are within the support radius of the surface" reads it. A mapping that
     *  needs distances farther out asks FP_HOST_EXT_SURFACE with its own max_distance. */
    float tip_distance[FP_HANDS][FP_FINGERS];

    /* ---- ABI 1.1 (read only where size covers them; a 1.0 host does not fill them) --- */
    /** The mesh's unit in millimetres (from the rig, the calibration or the head's size);
     *  0 where unknown. A gain "in mm" becomes mesh units by dividing by it. */
    double mm_per_unit;
    /** The face's frame in mesh coordinates, unit vectors: up (chin to crown), forward
     *  (out of the face, toward the viewer) and the face's own left. Where the face is turned
     *  (a rig placed on a turned copy of its mesh, or --up/--facing), the hands are placed in
     *  front of this frame and turned with it: the performer's right, up and toward the
     *  performer are face_left, face_up and face_forward in `hands`, so a mapping reads a
     *  hand's motion along them (not +x, +y, +z). Else the rig's axes, or +x, +y, +z. */
    float face_up[3], face_forward[3], face_left[3];
    /** The rig of this mesh (fp_rig_view below), or NULL where the session has none. Valid
     *  during this call. */
    const struct fp_rig_view *rig;

    /* ---- ABI 1.3 (read only where size covers them; a 1.2 host does not fill them) --- */
    /** The radius touch is measured in, mesh units: the face's default support radius, which
     *  --radius and the live keys ([ ]) leave as it is, so that a fingertip touches the skin
     *  at the same distance whatever the brush's size (a wider brush then never engages
     *  farther off the skin nor lets go later). fp_touch_radius (mapping_util.h) reads it,
     *  or radius where a host does not fill it. */
    double touch_radius;
    /** Further performers (inputs with `performer=NAME`, two right hands from two people):
     *  extra_performers of them, 0 to FP_PERFORMER_CAPACITY - 1, in the order their names
     *  first appear among the inputs. Their hands are pairs, left then right:
     *  extra_hands[FP_HANDS * p + side] is performer p + 2's hand of fp_hand_side `side`
     *  (p from 0), as `hands` (mesh units, at time_ns, each performer placed by its own
     *  calibration); extra_tip_distance[FP_HANDS * p + side][finger] is its fingertips'
     *  distances, as `tip_distance`. `hands` and `tip_distance` stay the first performer's.
     *  Both arrays have FP_HANDS x extra_performers rows; NULL where extra_performers is 0.
     *  The host's, valid during this call only (copy what is kept); [session-thread]. A
     *  mapping that ignores them drives the face from the first performer alone;
     *  mapping_util.h's fp_frame_hand_count and fp_frame_hand read both as one list. */
    uint32_t extra_performers;
    const fp_hand_pose *extra_hands;
    const float (*extra_tip_distance)[FP_FINGERS];
} fp_frame_input;

/* ------------------------------------------------------------------------------------- */
/* Rigs (ABI 1.1): what a mapping may know of the face's skull, jaw and landmarks          */

/** Region of a vertex in a rig (rigs/README.md). */
typedef enum fp_rig_region {
    FP_REGION_SOFT = 0,        /* soft tissue: free to deform */
    FP_REGION_SKULL = 1,       /* rigid with the skull (cranium, upper teeth, eyes): never moves */
    FP_REGION_JAW = 2          /* rigid with the jaw (lower teeth, chin bone): turns about the hinge */
} fp_rig_region;

typedef struct fp_rig_landmark {
    const char *name;          /* e.g. "chin", "nose_tip", "mouth_corner_left" */
    uint32_t vertex;           /* vertex index in the mesh */
    float position[3];         /* that vertex of the base, mesh units */
} fp_rig_landmark;

typedef struct fp_rig_channel_info {
    const char *name;          /* e.g. "jaw.open" */
    float min, max;            /* the range the host clamps to */
    float neutral;             /* the value at rest */
    float value;               /* the value the host applied last frame */
} fp_rig_channel_info;

/** A rig as a mapping sees it. Owned by the host; valid during the call it is passed to (or,
 *  from FP_HOST_EXT_RIG, until the mapping is reset or destroyed). */
typedef struct fp_rig_view {
    uint32_t size;
    const char *name;                    /* the rig file's name */
    double mm_per_unit;                  /* the mesh's unit in millimetres */
    float up[3], forward[3], left[3];    /* face axes, mesh coordinates */
    size_t vertex_count;
    const uint8_t *region;               /* vertex_count fp_rig_region values */
    size_t landmark_count;
    const fp_rig_landmark *landmarks;
    size_t channel_count;
    const fp_rig_channel_info *channels;
    float hinge[2][3];                   /* the jaw hinge: two points on its axis, mesh units */
} fp_rig_view;

/** Host extension FP_HOST_EXT_RIG (ABI 1.1): the session's rig, for a mapping that wants it
 *  at create (to look up landmarks once). get returns NULL where the session has no rig.
 *  [main-thread] and [session-thread]; no allocation. */
#define FP_HOST_EXT_RIG "facepuppet.rig/1"
typedef struct fp_host_rig {
    const fp_rig_view *(*get)(const fp_host *host);
} fp_host_rig;

/** Host extension FP_HOST_EXT_SURFACE (ABI 1.1): nearest points of the base surface.
 *  For each of `count` query points (mesh units) the nearest base vertex within
 *  `max_distance` (mesh units; +INFINITY for no limit): out[i].vertex (UINT32_MAX where none
 *  is within reach), its position, its distance and its unit normal. out: count entries of
 *  the caller's, written during the call. Returns 0, -EINVAL (points or out NULL with count >
 *  0), -ENODATA (the session has no surface index yet: no triangles), or the engine's negative
 *  code (a negative errno, or FP_ENUMERIC). [session-thread]: no allocation, no lock; cost
 *  follows the queries, not the mesh. */
#define FP_HOST_EXT_SURFACE "facepuppet.surface/1"
typedef struct fp_surface_hit {
    uint32_t vertex;
    float distance;
    float position[3];
    float normal[3];
} fp_surface_hit;
typedef struct fp_host_surface {
    int (*nearest)(const fp_host *host, const float (*points)[3], size_t count,
                   float max_distance, fp_surface_hit *out);
} fp_host_surface;

/** A named scalar a mapping drives (e.g. "jaw.open" in [0, 1]); for rigs. */
typedef struct fp_channel {
    char name[32];
    float value;
} fp_channel;

/** The control set a host takes (the engine's own limits, csrbf.h): every start and end
 *  coordinate finite with |x| <= FP_CONTROL_COORD_MAX and, when active, a radius within
 *  [FP_CONTROL_RADIUS_MIN, FP_CONTROL_RADIUS_MAX] mesh units (an inactive set's radius is
 *  replaced by the session's). Any other set is the mapping's error: reported naming it, the
 *  base shown that frame, nothing recorded. `facepuppet plugins check` holds a plugin to the
 *  same rule (the host's fp_control_check.h). */
#define FP_CONTROL_RADIUS_MIN 1e-15
#define FP_CONTROL_RADIUS_MAX 1e15
#define FP_CONTROL_COORD_MAX 1e15

/** What a mapping returns each frame. The host owns the arrays and sets the capacities; the
 *  mapping fills at most that many.
 *
 *  Meaning, as the host executes it:
 *   - active == false: nothing is being deformed; the host shows the base.
 *   - active == true: the engine maps the base with control vectors start[i] -> end[i],
 *     i < count, support radius `radius`. While start[] stays bit-for-bit the same the host
 *     reuses its factorization (the anchored mode); when it changes it factors anew.
 *   - intents & FP_INTENT_COMMIT: after this frame's evaluation the deformed shape becomes
 *     the base (anchored commit; the unanchored mode commits every step).
 *   - intents & FP_INTENT_CANCEL: the deformation is dropped; the base stays.
 *   - intents & FP_INTENT_ENGAGE: informs the host (HUD, take markers) that one began. */
typedef struct fp_control_set {
    uint32_t size;
    bool active;
    uint32_t intents;             /* fp_intent bits */
    double radius;                /* support radius, mesh units, in [FP_CONTROL_RADIUS_MIN,
                                     FP_CONTROL_RADIUS_MAX] when active */
    size_t capacity;              /* set by the host, >= FP_CONTROL_CAPACITY (ABI 1.1) */
    size_t count;                 /* filled by the mapping, <= capacity */
    float (*start)[3];            /* start points s_i, mesh units */
    float (*end)[3];              /* end points d_i, mesh units */
    size_t channel_capacity;      /* set by the host */
    size_t channel_count;
    /** Rig channels the mapping drives this frame, by name (e.g. "jaw.open"); the host's rig
     *  step clamps each to its range and poses the face before the control vectors apply.
     *  Channels not set keep their last value; a name the rig lacks is reported once. */
    fp_channel *channels;
} fp_control_set;

typedef struct fp_mapping {
    uint32_t size;
    void *plugin_data;

    /** [session-thread] Turn this frame's input into a control set. No allocation, I/O or
     *  locks. Returns 0, or a negative code: the host shows the base for this frame (a
     *  gesture in progress ends) and logs the code once, then counts it. A control set
     *  written past out's capacities stops the mapping for good (FP_EPLUGIN_FAULT). */
    int (*process)(struct fp_mapping *self, const fp_frame_input *in, fp_control_set *out);

    /** [session-thread] Forget any gesture in progress (the host reset the mesh). */
    void (*reset)(struct fp_mapping *self);

    /** [main-thread] Free the instance. */
    void (*destroy)(struct fp_mapping *self);

    /** [main-thread] Optional features by versioned id; may be NULL. */
    const void *(*get_extension)(const struct fp_mapping *self, const char *id);
} fp_mapping;

typedef struct fp_mapping_factory {
    uint32_t size;
    const char *name;        /* the --mapping name, e.g. "anchored" */
    const char *description;
    const char *usage;

    /** [main-thread] As fp_input_factory.create. */
    int (*create)(const fp_host *host, const fp_param *params, size_t nparams,
                  fp_mapping **out, char *err, size_t errlen);

    /* ABI 1.1 (read where size covers it): the keys, ended by a NULL name; may be NULL. */
    const fp_param_info *params;
} fp_mapping_factory;

/* ------------------------------------------------------------------------------------- */
/* The entry                                                                             */

typedef struct fp_plugin_entry {
    fp_version abi;          /* FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR as built */
    const char *id;          /* reverse-DNS, e.g. "org.facepuppet.input-replay" */
    const char *version;     /* the plugin's own version, free form */

    /** [main-thread] Called once after loading, with the shared object's path (the host's
     *  string, valid during the call: copy it to keep it). false refuses the load: the host
     *  unloads the plugin and reports FP_EPLUGIN_INIT (exit 78), naming it. May be NULL (the
     *  host then loads the plugin as if init returned true): leave it out where there is
     *  nothing to set up. */
    bool (*init)(const char *plugin_path);
    /** [main-thread] Called once before unloading. May be NULL (nothing to release). */
    void (*deinit)(void);
    /** [main-thread] A factory by id (FP_INPUT_FACTORY_ID, FP_MAPPING_FACTORY_ID), or NULL.
     *  The factory must stay valid until deinit or unloading (a static const struct, as the
     *  templates). Required. */
    const void *(*get_factory)(const char *factory_id);
} fp_plugin_entry;

/** Declare the entry in a plugin, with designated initialisers (init and deinit may be left
 *  out):
 *    FP_PLUGIN_DECLARE_ENTRY = {
 *        .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
 *        .id = "org.example.map-grab", .version = "1.0", .get_factory = get_factory,
 *    };
 *  In C++ too (it gives the entry C linkage; designated initialisers need C++20, in the
 *  fields' order). */
#ifdef __cplusplus /* (C linkage: a const object at namespace scope is otherwise internal) */
#define FP_PLUGIN_DECLARE_ENTRY extern "C" FP_PLUGIN_EXPORT const fp_plugin_entry facepuppet_plugin_entry
#else
#define FP_PLUGIN_DECLARE_ENTRY FP_PLUGIN_EXPORT const fp_plugin_entry facepuppet_plugin_entry
#endif

#ifdef __cplusplus
}
#endif
#endif /* FACEPUPPET_PLUGIN_H */
