/*
 * fp_plugin_host.h: the host side of the plugin ABI (facepuppet/plugin.h): SPEC strings,
 * finding and loading plugins, the event queues input plugins push into, and input
 * instances. Used by the session and the facepuppet command; not part of the plugin ABI.
 *
 * Thread rules: everything here is [main-thread] except fp_event_queue_push (any thread)
 * and fp_event_queue_pop (one consumer thread at a time: the session thread).
 */
#ifndef FP_PLUGIN_HOST_H
#define FP_PLUGIN_HOST_H

#include "fp_clock.h" /* fp_now_ns, the host clock of the ABI */
#include "fp_error.h"
#include "fp_event_check.h"
#include "fp_filter.h"
#include "log_relay.h"

#include <facepuppet/plugin.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- SPEC strings: NAME[:ARG][,key=value...] ---------------------------------------- */

#define FP_SPEC_MAX_PARAMS 16

/** A parsed SPEC. Owns one buffer; the strings point into it. */
typedef struct fp_spec {
    char *buffer;
    const char *name;                      /* never NULL after a successful parse */
    const char *arg;                       /* NULL where the SPEC has no ':ARG' */
    fp_param params[FP_SPEC_MAX_PARAMS];
    size_t nparams;
} fp_spec;

/** Parse `text` (e.g. "replay:take.csv,speed=2") into *spec. The NAME is [A-Za-z0-9_-]+,
 *  or a plugin file's path where it holds a '/' (fp_plugin_find loads that file; any text
 *  but control characters, ending at the first ':' or ','). The ARG ends at the first
 *  comma; keys are [A-Za-z0-9_-]+ and must be unique; a value may be empty, and runs to the
 *  next `,key=` (`keys=a,b,c` gives keys the value "a,b,c"; an item without '=' before any
 *  key is refused).
 *  Returns 0, or -EINVAL with a message in err naming the offending part.
 *  Free with fp_spec_clear. */
int fp_spec_parse(const char *text, fp_spec *spec, char *err, size_t errlen);

/** Remove the key `key` from the spec and return its value (pointer into the spec's
 *  buffer, valid until fp_spec_clear), or NULL where absent. */
const char *fp_spec_take(fp_spec *spec, const char *key);

/** Free the SPEC's buffer (its strings become invalid) and zero it; safe on a zeroed one. */
void fp_spec_clear(fp_spec *spec);

/* ---- finding and loading plugins ------------------------------------------------------ */

typedef enum fp_plugin_kind { FP_PLUGIN_INPUT = 0, FP_PLUGIN_MAPPING = 1 } fp_plugin_kind;

#define FP_PLUGIN_MAX_DIRS 16

/** Where plugins are looked for, in order: the built-in folder <directory of the
 *  executable>/FP_PLUGIN_RELDIR first (so a built-in plugin's name always resolves to the
 *  built-in plugin), then the --plugin-dir folders, then each folder of
 *  FACEPUPPET_PLUGIN_PATH (colon-separated).
 *
 *  Safety (plugins run with the caller's rights): a folder other than the built-in one is
 *  skipped when it is writable by group or others, or owned by a user other than the caller
 *  and root; a relative FACEPUPPET_PLUGIN_PATH entry is ignored (--plugin-dir folders are
 *  made absolute); a plugin file in a searched folder is skipped on the same rules. Each
 *  skip is explained in `warnings` (one line each) or in fp_plugin.warning. */
typedef struct fp_plugin_path {
    char *dirs[FP_PLUGIN_MAX_DIRS];
    size_t count;
    size_t builtin;                      /* index of the built-in folder, or SIZE_MAX */
    char warnings[1024];                 /* folders skipped and why, "\n"-separated */
} fp_plugin_path;

/** Fill *path: builtin_dir (may be NULL), extra_dirs (may be NULL, n_extra entries), then the
 *  environment, applying the safety rules above. Copies the strings. Never prints: the
 *  caller shows path->warnings. Free with fp_plugin_path_clear. */
void fp_plugin_path_init(fp_plugin_path *path, const char *const *extra_dirs, size_t n_extra,
                         const char *builtin_dir);
/** Why `file_or_dir` may not be trusted (writable by group or others; owned by another user
 *  than the caller or root), into why (whylen bytes); false where it is safe. Follows
 *  symbolic links. [any-thread] */
bool fp_plugin_path_unsafe(const char *file_or_dir, char *why, size_t whylen);
/** Free the search path's folders and zero it; safe on a zeroed one. */
void fp_plugin_path_clear(fp_plugin_path *path);

/** A loaded shared object. */
typedef struct fp_plugin {
    void *handle;                    /* dlopen handle */
    char *path;                      /* the file it was loaded from */
    const fp_plugin_entry *entry;
    fp_plugin_kind kind;
    const void *factory;             /* fp_input_factory or fp_mapping_factory */
    char warning[512];               /* set when an unsafe candidate file was skipped */
} fp_plugin;

/** Find `<input|map>-<name>.so` on `path` (or load `name` itself where it contains a '/'),
 *  dlopen it, check its entry's ABI (fp_version_is_compatible), call init and get the
 *  factory of `kind`. Returns 0, or one of the FP_EPLUGIN_* codes of fp_error.h
 *  (NOT_FOUND, DLOPEN, NO_ENTRY, ABI, INIT, NO_FACTORY; -ENOMEM) with a message naming the
 *  file (or the folders searched and the plugins found there) in err. */
int fp_plugin_load(const fp_plugin_path *path, fp_plugin_kind kind, const char *name,
                   fp_plugin *out, char *err, size_t errlen);

/** Whether `name` (a SPEC's NAME, e.g. "anchored"; NULL: false) of `kind` is one of the
 *  plugins facepuppet ships (plugins/). Pure, [any-thread]; no errors. */
bool fp_plugin_shipped(fp_plugin_kind kind, const char *name);

/** Where fp_plugin_load would find `name` (as it searches: a name with a '/' is the file
 *  itself), into file (filelen bytes), without loading it; *builtin (may be NULL) true when
 *  it is in the path's built-in folder and is one of facepuppet's own (fp_plugin_shipped): a
 *  third party's plugin installed there (the SDK's install step puts it there) is not. Unsafe candidates skipped are described in warning
 *  (may be NULL). Returns whether a file was found. */
bool fp_plugin_find(const fp_plugin_path *path, fp_plugin_kind kind, const char *name, char *file,
                    size_t filelen, bool *builtin, char *warning, size_t warnlen);
/** fp_plugin_load's message for a plugin not found (the folders searched and the plugins
 *  there, and `warning` where not empty) into err. */
void fp_plugin_not_found(const fp_plugin_path *path, fp_plugin_kind kind, const char *name,
                         const char *warning, char *err, size_t errlen);

/** deinit and dlclose. Safe on a zeroed fp_plugin. */
void fp_plugin_unload(fp_plugin *plugin);

/** Names of the plugins of `kind` on `path`, comma-separated into buf (for messages). */
void fp_plugin_list(const fp_plugin_path *path, fp_plugin_kind kind, char *buf, size_t len);

/** What a loaded plugin's factory says of itself (plugin.h), read only where the factory's
 *  `size` covers a field: name, description, usage (NULL where absent) and, for an ABI 1.1
 *  factory, the typed key list `params` (NULL-name terminated; NULL for a 1.0 factory or
 *  one that declares none). Pointers into the plugin: valid until it is unloaded. */
typedef struct fp_plugin_about {
    const char *name, *description, *usage;
    const fp_param_info *params;
} fp_plugin_about;
void fp_plugin_describe(const fp_plugin *plugin, fp_plugin_about *out);

/** One candidate file that fp_plugin_scan found. */
typedef struct fp_plugin_scan_item {
    fp_plugin_kind kind;
    const char *dir;           /* the folder it was found in */
    const char *file;          /* full path */
    const char *name;          /* the NAME of input-NAME.so / map-NAME.so */
    bool shadowed;             /* a folder searched earlier has a plugin of that kind and name:
                                  this one is never loaded by name (it is still inspected) */
    int code;                  /* 0 loaded; an FP_EPLUGIN_* code (why it is broken); -EACCES
                                  skipped for safety (not loaded) */
    const char *error;         /* the reason where code != 0 */
    const fp_plugin *plugin;   /* loaded where code == 0: entry and factory readable during
                                  the callback only (the scan unloads it afterwards) */
} fp_plugin_scan_item;

/** Every `input-*.so` and `map-*.so` in every folder of `path`, in search order, each
 *  file's names sorted: loaded (fp_plugin_load, which runs the plugin's init), passed to fn,
 *  then unloaded. A file outside the built-in folder that fp_plugin_path_unsafe rejects is
 *  passed with code -EACCES and not loaded. Returns how many files were passed.
 *  [main-thread]: loading runs plugins' init functions. */
size_t fp_plugin_scan(const fp_plugin_path *path,
                      void (*fn)(void *user, const fp_plugin_scan_item *item), void *user);

/* ---- the event queue: bounded, multi-producer single-consumer, lock-free ------------- */

/** Bounded MPSC queue of fp_event (D. Vyukov's bounded queue, sequence number per cell).
 *  push: [any-thread], lock-free, never blocks; pop: one consumer at a time. */
typedef struct fp_event_queue {
    struct fp_event_cell *cells;
    size_t mask;
    _Alignas(64) atomic_size_t head;     /* producers claim here */
    _Alignas(64) atomic_size_t tail;     /* consumer reads here */
    _Alignas(64) atomic_ulong dropped;   /* events refused because the queue was full (each
                                            once, however often pushed again), less those
                                            pushed again and taken (refused) */
    atomic_uint_least64_t refused;       /* the last refused event: a key of its bytes (never
                                            0); 0: none since the last push taken */
    int64_t popped_since_ns;             /* the consumer's: the since_ns of the event popped
                                            last (fp_event_queue_push_at) */
} fp_event_queue;

/** capacity is rounded up to a power of two (at least 2). Returns 0 or -ENOMEM. */
int fp_event_queue_init(fp_event_queue *q, size_t capacity);
/** Free the cells; no producer may push any more (the input stopped, its threads joined).
 *  Safe on a zeroed queue. */
void fp_event_queue_destroy(fp_event_queue *q);
/** The share of a queue's capacity kept from poses: 1/8 (a capacity under 8: none). */
#define FP_EVENT_QUEUE_RESERVE 8
/** Copy ev (ev->size bytes, at most sizeof(fp_event)) in. False when full or too large; a
 *  pose (joint angles, joint positions, wrist pose) finds it full with 1/FP_EVENT_QUEUE_RESERVE
 *  of the capacity still free, which only the other events (statuses, buttons, channels)
 *  take: an input that floods poses cannot push out its end of stream or a button.
 *  An event refused as full counts once in dropped, however often it is pushed again; when
 *  it is taken before another is refused, that count is taken back: a producer that waits
 *  for room loses nothing, and the count says so. */
bool fp_event_queue_push(fp_event_queue *q, const fp_event_header *ev);
/** fp_event_queue_push, with since_ns (ns, host clock) kept beside the event: the time its
 *  delay is counted from (fp_event_queue_push gives the event's own time_ns; an input on a
 *  recording's clock, whose times are not the host's, the time it was pushed). The pop that
 *  takes the event sets q->popped_since_ns to it. */
bool fp_event_queue_push_at(fp_event_queue *q, const fp_event_header *ev, int64_t since_ns);
/** The events dropped so far: dropped, less the last refused event, which its producer may
 *  still be waiting to push again (a replay stopped while it waited for room lost nothing
 *  the run had reached; an event not pushed again counts once another is refused). About,
 *  while producers push. Any thread. */
unsigned long fp_event_queue_dropped(const fp_event_queue *q);
/** Copy the oldest event out. False when empty. */
bool fp_event_queue_pop(fp_event_queue *q, fp_event *out);

/* ---- input instances ------------------------------------------------------------------ */

struct fp_event_recorder;
struct fp_event_forwarder;

/** A log callback with the signature of the session's (fp_session_log_fn): level is an
 *  fp_log_level, source names who speaks. */
typedef void (*fp_host_log_fn)(void *user, int level, const char *source, const char *message);

/** The longest performer name (`performer=NAME`, FP_PERFORMER_CAPACITY performers at most in
 *  a session): letters, digits, '-' and '_'. */
#define FP_PERFORMER_NAME_MAX 31

struct fp_input_instance;
/** The fp_host an input plugin is given, apart from its instance (host_data is this link):
 *  a plugin's thread that outlives an abandoned stop() may still push or log through it after
 *  the owner freed the instance, so an abandoned input's link is never freed (leaked on
 *  purpose, a few dozen bytes) and its calls find inst gone and do nothing. Otherwise freed by
 *  fp_input_instance_close once the plugin's threads are gone. */
typedef struct fp_input_link {
    fp_host host;                        /* what the plugin holds (create's host) */
    struct fp_input_instance *inst;      /* where push_event and log go, until abandoned */
    atomic_bool abandoned;               /* set by the owner: calls do nothing from then on */
    atomic_int busy;                     /* push_event and log calls in progress (the owner
                                            waits for 0 after setting abandoned) */
    atomic_uint_least64_t dropped;       /* events pushed after abandoned: dropped, counted */
} fp_input_link;

/** One running input: its plugin, the fp_host given to it (its link), its queue. */
typedef struct fp_input_instance {
    fp_plugin plugin;
    fp_input_link *link;                 /* link->host is the plugin's fp_host (heap) */
    fp_input *input;
    fp_event_queue queue;
    char name[64];                       /* the SPEC's name, for messages */
    uint32_t source;                     /* index in the session; stamped into events */
    struct fp_event_recorder *record;    /* record=FILE: every polled event is queued for
                                            its writer thread (fp_record.h) */
    struct fp_event_forwarder *forward;  /* forward=osc:HOST:PORT: every event the queue
                                            takes is sent again over OSC (fp_forward.h) */
    bool started;
    bool stopped;                        /* stop() was called (it is called once) */
    bool abandoned;                      /* stop() did not return within
                                            FP_INPUT_STOP_DEADLINE_MS: left running */
    fp_input_link *orphan;               /* once abandoned: its link (kept for good), which
                                            counts what the plugin pushes from then on */
    uint64_t unread;                     /* once abandoned and closed: the events left in
                                            its queue, never read (a recording's kept) */
    fp_log_relay log;                    /* the plugin's log lines, from any thread, until
                                            drained on the owner's (log_relay.h) */
    fp_host_log_fn log_fn;               /* where they are drained to (fp_input_instance_set_log) */
    void *log_user;
    fp_filter_config filter;             /* the filter of its hand events (fp_filter.h): the
                                            SPEC's filter keys, else the default of its NAME */
    char performer[FP_PERFORMER_NAME_MAX + 1]; /* performer=NAME: whose hands its events
                                            are (the session keys hands by performer and
                                            side); "" without the key: the first performer */
    char calibration[1024];              /* calibration=FILE: its performer's calibration
                                            (docs/calibration.md; read by the session); "" */
    atomic_uint_least64_t refused;       /* malformed events push_event refused
                                            (fp_event_check.h), from the plugin's threads */
    _Atomic(const char *) refused_why[FP_EVENT_FAULTS]; /* per fp_event_fault: the first
                                            one's reason (a static phrase), set by push_event */
    unsigned refused_said;               /* owner's: bit f, the warning for fault f was said */
    atomic_uint_least64_t oversize;      /* the first event refused for its size (over
                                            sizeof(fp_event), or under its header): its
                                            size << 32 | its type; 0: none */
    bool oversize_said;                  /* owner's: its warning was said */
    bool isolated;                       /* in a helper process (fp_input_instance_open_isolated) */
    bool own_clock;                      /* fp_input_own_clock, read before start: its events'
                                            times are not held to the host's clock */
} fp_input_instance;

/** Load the plugin for `spec` and create the instance (not yet started). The host strips
 *  its own keys before the plugin sees the keys: `record=FILE` (record this input's events in
 *  the event-log format; `force=1` beside it), `forward=osc:HOST:PORT` (send them again in
 *  the OSC input's format, fp_forward.h; -ENOTSUP without liblo) and the filter keys `filter=oneeuro|auto|off`,
 *  `mincutoff=HZ`, `beta=B`, `dcutoff=HZ`, `trend=HZ` (fp_filter_parse: into inst->filter, starting from
 *  fp_filter_default of the SPEC's NAME; a bad value is -EINVAL naming the SPEC and key), and
 *  `performer=NAME` (into inst->performer: 1 to FP_PERFORMER_NAME_MAX letters, digits, '-'
 *  or '_', else -EINVAL naming the SPEC; the session gives each performer its own hands) and
 *  `calibration=FILE` (into inst->calibration, not read here: the session places that
 *  input's performer by it; an empty or too long path is -EINVAL). A
 *  filter that is on is described (fp_filter_describe, with its lag) in an info line of the
 *  input's log. Returns 0, -EINVAL, an FP_EPLUGIN_* code (fp_error.h), or the plugin's own
 *  negative errno; err names the SPEC and reason. */
int fp_input_instance_open(fp_input_instance *inst, const fp_plugin_path *path,
                           const char *spec_text, uint32_t source, char *err, size_t errlen);
struct fp_isolate_options;
/** fp_input_instance_open where `isolate` (fp_isolate.h's fp_isolate_mode; 0: none) may put
 *  the plugin in a helper process (fp_isolate_input_create, with `opt`, may be NULL): under
 *  fp_isolate_wanted (a plugin found outside facepuppet's own, or every one under ALL).
 *  inst->isolated says which. The host keys, the queue, the checks of every event, record=
 *  and forward= stay here, as in process. [main-thread] */
int fp_input_instance_open_isolated(fp_input_instance *inst, const fp_plugin_path *path, const char *spec_text,
                                    uint32_t source, int isolate, const struct fp_isolate_options *opt,
                                    char *err, size_t errlen);
/** Call the plugin's start(): its threads or device run from here. Returns 0 or the plugin's
 *  negative errno (err "input 'NAME': REASON"). [main-thread], once, after a successful open. */
int fp_input_instance_start(fp_input_instance *inst, char *err, size_t errlen);
/** Where the plugin's log lines go (its fp_host.log, from any thread, is kept in inst->log):
 *  fn(user, level, NAME, message) on the thread that calls fp_input_instance_drain_log or
 *  fp_input_instance_close. fn NULL (the default): drained lines are discarded. Lines the
 *  plugin logs before this (in create) wait for the first drain. [owner's thread]. */
void fp_input_instance_set_log(fp_input_instance *inst, fp_host_log_fn fn, void *user);
/** Hand the lines the plugin logged since the last drain to the set_log callback, oldest
 *  first, with a line counting any dropped (over 32 kept at a time). Returns the lines handed.
 *  [owner's thread]: the session drains its inputs every frame; monitor and calibrate in
 *  their loops. Safe on a zeroed instance. */
size_t fp_input_instance_drain_log(fp_input_instance *inst);
/** How long the host waits for an input's stop() (ms): its call runs on a thread of the
 *  host's while the owner waits; one that has not returned by then is abandoned. */
#define FP_INPUT_STOP_DEADLINE_MS 5000

/** Stop (if started), destroy, close the recording, unload; the lines logged until then are
 *  drained to the set_log callback last. Safe on a zeroed instance. A stop() that has not
 *  returned within FP_INPUT_STOP_DEADLINE_MS (a plugin's thread blocked for good) is
 *  abandoned so that the command can end: an error line in the input's log names it
 *  ("stop has not returned within 5 s ..."), inst->abandoned is set, and nothing more of the
 *  plugin is called or freed (destroy, its code stay: its threads may still run). Its link
 *  is detached (inst->link NULL, the link kept for good as inst->orphan): what its threads
 *  push or log from then on is dropped there (the pushes counted: fp_input_instance_dropped),
 *  so the owner may free the instance's memory. A line says how many of its events were so
 *  dropped by then, those it had queued and not delivered among them.
 *  The same holds for fp_input_instance_close_record. */
void fp_input_instance_close(fp_input_instance *inst);
/** The events of this input that were lost: refused by its full queue
 *  (fp_event_queue_dropped) and, once abandoned, those it had queued that will never be read
 *  and those it pushed after (its link counts them, for good: the figure may grow while its
 *  threads run). Any thread for the queue's part; the rest is the owner's. */
uint64_t fp_input_instance_dropped(const fp_input_instance *inst);
/** Pop one event; queues it for the recording if any (no I/O on the caller's thread).
 *  [session-thread]. */
bool fp_input_instance_poll(fp_input_instance *inst, fp_event *out);
/** The recording's first error so far (a failed write, events dropped), 0 when none or no
 *  recording; the message into err. Any thread. */
int fp_input_instance_record_error(fp_input_instance *inst, char *err, size_t errlen);
/** Stop the input, record what is still queued, close the recording (join its writer) and
 *  return 0 or its first error (fp_record.h's codes; message into err). No-op without a
 *  recording. fp_input_instance_close does this too but drops the error. */
int fp_input_instance_close_record(fp_input_instance *inst, char *err, size_t errlen);

/** Make the standard host services for a mapping instance (no queue); its log lines go to
 *  stderr as "facepuppet: NAME: LEVEL: MESSAGE". `name` must outlive the host. Prefer
 *  fp_mapping_host_init, which routes them through a log callback. */
void fp_host_init_for_mapping(fp_host *host, const char *name);

/** Services a session offers its mapping through get_extension (plugin.h, ABI 1.1). */
typedef struct fp_mapping_services {
    fp_host_surface surface;   /* FP_HOST_EXT_SURFACE; not offered while nearest is NULL */
    uint64_t (*base_version)(void *user); /* FP_HOST_EXT_BASE_VERSION; NULL: not offered */
    void *user;                /* the provider's data, for the service's implementation */
} fp_mapping_services;


/** The fp_host of a mapping instance, with its log target: plugin log lines go to `log`
 *  (NULL: stderr, "facepuppet: mapping 'NAME': LEVEL: MESSAGE") with the source
 *  "mapping 'NAME'"; FP_LOG_DEBUG lines only when FACEPUPPET_DEBUG is set in the
 *  environment. With `relay` set (the session's), a line is kept there from whatever thread
 *  the mapping logs on and handed to `log` by fp_mapping_host_drain_log on the owner's
 *  thread; without, `log` is called at once on the plugin's thread. Pass &mh->host to the
 *  factory; mh must stay in place while the instance lives. */
typedef struct fp_mapping_host {
    fp_host host;
    char source[96];
    fp_host_log_fn log;
    void *log_user;
    const struct fp_rig_view *rig;   /* FP_HOST_EXT_RIG's answer (ABI 1.1); NULL: no rig. The
                                        session sets it after fp_mapping_host_init */
    const fp_mapping_services *services; /* FP_HOST_EXT_SURFACE (ABI 1.1); NULL: not offered.
                                        Kept by pointer: it must outlive the host */
    fp_log_relay *relay;             /* NULL: none; else the owner's, set after init, which
                                        must outlive the instance */
    void (*fault)(void *user, const char *text); /* FP_HOST_EXT_FAULT_NOTICE; NULL: not offered */
    void *fault_user;
} fp_mapping_host;

/** Host extension of the host's own (not in plugin.h, not for plugins): an isolated mapping's
 *  proxy (fp_isolate.h) tells the host of each fault (a helper dead or past its deadline) with
 *  one line of text, e.g. for the take. [session-thread], during process(). */
/** Host extension of the host's own (not for plugins): a number that changes whenever the
 *  content of fp_frame_input.mesh->base may have changed since the last frame (a commit, an
 *  undo, a rig pose), so that an isolated mapping's proxy copies the base to its helper only
 *  then. [session-thread] */
#define FP_HOST_EXT_BASE_VERSION "facepuppet.host.base-version/1"
typedef struct fp_host_base_version {
    uint64_t (*get)(const fp_host *host);
} fp_host_base_version;

#define FP_HOST_EXT_FAULT_NOTICE "facepuppet.host.fault-notice/1"
typedef struct fp_host_fault_notice {
    void (*notice)(const fp_host *host, const char *text);
} fp_host_fault_notice;
void fp_mapping_host_init(fp_mapping_host *mh, const char *name, fp_host_log_fn log, void *log_user);
/** Hand the lines kept in mh->relay to mh->log with mh's source, oldest first (a line counts
 *  any dropped). Returns their number; 0 without a relay. [owner's thread]. */
size_t fp_mapping_host_drain_log(fp_mapping_host *mh);

#ifdef __cplusplus
}
#endif
#endif
