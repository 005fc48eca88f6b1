/*
 * fp_test_support.h: what the tests share (library fp_test_support, tests/support/): the
 * shared-data and build folders, a clock, loading one plugin by dlopen, a fake fp_host that
 * keeps what a plugin pushes, and a session on the ICT face started from input SPECs.
 *
 * Test code only: helpers fail the running cmocka test (assert_*) where noted rather than
 * returning errors. The fake host is thread-safe (plugins push from their threads); the
 * other helpers are for the test's main thread.
 */
#ifndef FP_TEST_SUPPORT_H
#define FP_TEST_SUPPORT_H

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "facepuppet/plugin.h"

/* ---- folders and time ----------------------------------------------------------------- */

/** $FP_SHARED_DATA, or "../shared/data" (ctest runs tests from the source root). */
const char *fp_test_data_dir(void);
/** $FP_BUILD_DIR, or "build". */
const char *fp_test_build_dir(void);
/** "<build>/lib/facepuppet": where the plugins are built. */
const char *fp_test_plugin_dir(void);
/** "<data>/faces/ict-facekit/generic_neutral_mesh.obj". */
const char *fp_test_face_path(void);

/* ---- the hand recordings a test runs on ------------------------------------------------ */

#define FP_TEST_RECORDINGS_MAX 32

/** Leap recordings (*_joints_mm.csv, or the playback originals *.json.lz and *.json): their
 *  paths and names (the file name less that ending), read through `replay:`. */
typedef struct fp_test_recordings {
    size_t n;
    char path[FP_TEST_RECORDINGS_MAX][4200];
    char name[FP_TEST_RECORDINGS_MAX][256];
} fp_test_recordings;

/** The recordings a test runs on, chosen by the environment variable `env` (so that the checks
 *  run on hands they were not tuned on, e.g. FP_REACH_HANDS): unset or empty, the four of
 *  <data>/hands/leap-motion (HandSplay-110fps, Waiting-110fps, grab, three-claps); a folder,
 *  every recording in it (*_joints_mm.csv, *.json.lz, *.json), sorted by name (at most
 *  FP_TEST_RECORDINGS_MAX); such a file, that one. Fails the test, saying why, when `env`
 *  names neither or a folder without one. out: the caller's (large: keep it static or on the heap). */
void fp_test_recordings_from(const char *env, fp_test_recordings *out);

/** Write text to path (created or truncated). Fails the test when it cannot. */
void fp_test_write_file(const char *path, const char *text);

/** Triangles (t x 3 indices into both shapes, n x 3 floats each) whose normal in b points
 *  against its normal in a (dot < 0, computed in double): turned over, a fold, whether or not
 *  it crosses another triangle. A degenerate triangle in either shape does not count. */
size_t fp_test_reversed(const float *a, const float *b, const uint32_t *tris, size_t t);

/** CLOCK_MONOTONIC in ns. */
int64_t fp_test_mono_ns(void);
/** Sleep ms milliseconds. */
void fp_test_nap_ms(int ms);
/** FP_TEST_TIME_SCALE (cmake/FpHelpers.cmake: 3 in sanitizer builds, where the code runs
 *  several times slower), at least 1; 1 when unset or not a number. */
int fp_test_time_scale(void);

/* ---- one plugin, loaded by dlopen ----------------------------------------------------- */

/** dlopen "<plugin dir>/FILE" (e.g. "input-replay.so"), check its ABI, init it and return
 *  its factory `factory_id` (FP_INPUT_FACTORY_ID, ...), or NULL after printing why to stderr.
 *  *handle receives what fp_test_plugin_close takes. */
const void *fp_test_plugin_open(const char *file, const char *factory_id, void **handle);
/** deinit and dlclose what fp_test_plugin_open opened (a NULL handle is ignored). */
void fp_test_plugin_close(void **handle);

/* ---- a fake host that keeps the events pushed to it ------------------------------------ */

typedef struct fp_test_host {
    fp_host host;               /* first member; host.host_data points to this too */
    pthread_mutex_t lock;       /* guards everything below; tests read fields after the
                                   plugin stopped, or through the functions below */
    pthread_cond_t cond;
    fp_event *events;           /* kept events in push order (copies, zero-padded) */
    size_t count;               /* events kept */
    size_t cap;                 /* the most events kept; 0: as many as come (grows) */
    bool refuse_when_full;      /* past cap, push returns false (a full queue); else the
                                   event is dropped and push still returns true */
    unsigned refuse_every;      /* refuse every Nth push (a full queue), 0: never */
    bool count_only;            /* count joint-angle events, keep only the others */
    unsigned long calls;        /* push calls */
    size_t refused;             /* pushes answered false */
    size_t oversize;            /* events larger than fp_event (refused) */
    uint64_t angles;            /* joint-angle events pushed and accepted */
    int eos;                    /* FP_STATUS_END_OF_STREAM statuses kept */
    size_t read;                /* fp_test_host_next's cursor */
    char log[4096];             /* every log line as "LEVEL message\n", truncated */
    char last_log[1024];        /* the last log message */
    size_t alloc_;              /* private: events allocated */
    fp_log_level echo_level;    /* messages at or below it go to stderr too (FP_LOG_ERROR by
                                   default; every message with $FP_TEST_VERBOSE set) */
} fp_test_host;

/** A host keeping at most cap events (0: unbounded). Fails the test when out of memory. */
fp_test_host *fp_test_host_new(size_t cap);
void fp_test_host_free(fp_test_host *h);
/** The same on a caller's struct (embedded in a fixture); clear with fp_test_host_clear. */
void fp_test_host_init(fp_test_host *h, size_t cap);
void fp_test_host_clear(fp_test_host *h);

/** Events kept so far, and a copy of event i (< count). */
size_t fp_test_host_count(fp_test_host *h);
fp_event fp_test_host_get(fp_test_host *h, size_t i);
/** Wait until at least min_count events are kept (min_count 0: until an end of stream).
 *  Returns 0, or -1 after limit_ns. */
int fp_test_host_wait(fp_test_host *h, size_t min_count, int64_t limit_ns);
/** Wait for a status event at index >= from with this code (and text_part in its text,
 *  unless NULL). Returns its index, or -1 after ms milliseconds. */
long fp_test_host_wait_status(fp_test_host *h, size_t from, uint32_t code,
                              const char *text_part, int ms);
/** Wait until count joint-angle events follow index from; returns the index just past the
 *  count-th, or -1 after ms milliseconds. */
long fp_test_host_wait_angles(fp_test_host *h, size_t from, size_t count, int ms);
/** The next event after the read cursor, waiting at most timeout_ms; false on time out. */
bool fp_test_host_next(fp_test_host *h, fp_event *out, int timeout_ms);
/** Events kept but not yet read by fp_test_host_next. */
size_t fp_test_host_unread(fp_test_host *h);

/* ---- a session on the ICT face --------------------------------------------------------- */

struct fp_session;
struct fp_plugin_path;

/** The plugin search path of the build's plugins (one for the whole test program). */
const struct fp_plugin_path *fp_test_plugin_path(void);

struct fp_session_options;
/** *so := the options of a session on the ICT face (fp_test_face_path) with the mapping SPEC
 *  mapping and the build's plugins (fp_test_plugin_path), rigs looked for in rig_dir (NULL:
 *  none given); every other field zero. */
void fp_test_face_options(struct fp_session_options *so, const char *mapping, const char *rig_dir);

/** Create and start a session with the options so (not kept). Fails the test (printing the
 *  error) when create or start fails; the session is the caller's (fp_session_destroy). */
struct fp_session *fp_test_session_open(const struct fp_session_options *so);

/** Create and start a session on the ICT face with n input SPECs and a mapping SPEC, plugins
 *  from the build (fp_test_session_open). */
struct fp_session *fp_test_session_start(const char *mapping, const char *const *inputs, int n);

/** The input clock's start of s (options.input_clock, fp_session_input_start): waits for it
 *  (1 ms naps) at most 120 s x fp_test_time_scale(); fails the test when no input is a
 *  recording or the wait runs out. Returns t0, ns on the recordings' clock. */
int64_t fp_test_session_t0(struct fp_session *s);

/** Frame k of a replay stepped at fps frames a second on the input clock from t0: its time,
 *  t0 + round(k x 1e9 / fps) ns, once s's inputs are ready at it (fp_session_inputs_ready:
 *  every event up to it delivered), waiting with 1 ms naps at most 120 s x
 *  fp_test_time_scale() (then fails the test). Pass it to fp_session_step. */
int64_t fp_test_frame_time(struct fp_session *s, int64_t t0, uint64_t k, double fps);

#endif
