/*
 * fp_session_take.h: recording a session as a take (core/take, docs/take-format.md), and
 * playing a take's stored control sets back through a session.
 *
 * Recording: an fp_session_take is the record sink of fp_session_options (step 7): give
 * fp_session_take_sink and the object as `record` / `record_user` before fp_session_create.
 * While no take is recording the sink does nothing; fp_session_take_start writes the take's
 * header (mesh path and crc32 of its loaded positions, rig, mapping and its keys, input
 * SPECs by source, calibration, radius, frame rate, timecode in from the time of day) and
 * starts the recorder thread; from the next frame on every frame record goes into the
 * recorder's lock-free ring (fp_take_recorder_push: no I/O, no lock, no allocation on the
 * session thread); fp_session_take_stop writes the rest and the end chunk, joins the thread
 * and says what was recorded. Start and stop may be called any number of times (`live`'s T
 * key): each start makes the next take of the slate (numbers per slate, never overwritten).
 *
 * Playing: fp_session_play_frame applies one stored frame through the same engine, guard,
 * history and recorder steps the session ran (fp_session_apply_controls): the frame's control
 * set as the engine was given it, its commits, the host actions (undo, reset) recorded with
 * it. fp_session_take_check_mesh compares a session's loaded mesh with a take's checksum.
 *
 * Errors: 0 or a negative errno-style code (core/common/fp_error.h) with a message in err:
 * -EINVAL (no folder or a bad slate), the recorder's codes (-EACCES, -ENOSPC, -EIO...),
 * -EBADMSG (a take's mesh checksum differs: the message names both). Nothing is printed.
 *
 * Threads: one session thread; start and stop on it too (they may block on the disk:
 * header, join), the sink on it between them. One exception: another thread may end the
 * take while the session thread is stuck (a plugin that never returns): it seals the take
 * first (fp_session_take_seal), then stops it; the sink records nothing from then on.
 */
#ifndef FP_SESSION_TAKE_H
#define FP_SESSION_TAKE_H

#include "fp_session.h"
#include "fp_take.h"

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** What a take is recorded as; strings are the caller's and must outlive the object. */
typedef struct fp_session_take_options {
    const char *dir;               /* take folder (created if missing); required */
    const char *slate;             /* slate name; NULL: "take" */
    const char *description;       /* NULL: none */
    const char *rig_path;          /* the rig the session uses; NULL: the session's own
                                      (fp_session_rig_how) */
    fp_take_rate rate;             /* nominal frame rate; {0,0}: 60/1 */
    fp_take_recorder_options recorder;  /* zero: the recorder's defaults */
    /* Stage timecode and soundtrack (take format 1.2; zero: none) */
    bool have_timecode;            /* timecode_in below instead of the time of day */
    fp_timecode timecode_in;       /* the timecode at the take's origin (e.g. decoded LTC);
                                      drop-frame as its `drop` says (rate must allow it) */
    const char *timecode_source;   /* recorded as the header's timecode_source ("ltc:FILE") */
    const char *soundtrack_path;   /* the soundtrack performed to; NULL: none */
    uint32_t soundtrack_crc32;     /* zlib crc32 of its bytes */
    double soundtrack_offset_s;    /* the soundtrack's time at the take's origin */
    const char *audio_in_device;   /* a microphone recorded beside the take (its WAV's name in
                                      the header: fp_take_audio_in_name); NULL: none */
    bool stage_at_given;           /* stage_at_ns below is given; false: both hold at the
                                      take's origin */
    int64_t stage_at_ns;           /* the session time (ns, the clock of the take's origin) at
                                      which timecode_in and soundtrack_offset_s hold. A take
                                      whose origin is later (run --control: a take started
                                      mid-run) has both carried on to it: the timecode by the
                                      frames of `rate` between (fp_take_frames_at), the offset
                                      by the seconds */
} fp_session_take_options;

/** What a finished take holds (fp_session_take_stop). */
typedef struct fp_session_take_result {
    char path[4096];
    uint32_t take;
    uint64_t frames;               /* written */
    uint64_t dropped;              /* refused by the recorder (ring full, after an error) */
    fp_timecode timecode_in, timecode_out;
    int error;                     /* 0, or the code that stopped the recording */
} fp_session_take_result;

/** The take's reach histogram: steps of 1/200 from 0 to 2 (200%), the last bin holding more. */
#define FP_SESSION_TAKE_REACH_STEPS 200
#define FP_SESSION_TAKE_REACH_BINS (2 * FP_SESSION_TAKE_REACH_STEPS + 1)

typedef struct fp_session_take {
    fp_session_take_options opt;   /* copied at init */
    const fp_session_options *so;  /* the session's options (mapping, inputs) */
    fp_take_recorder *rec;         /* non-NULL while recording */
    fp_take_header header;         /* of the take recording */
    uint64_t first_frame;          /* session frame number of the take's first frame */
    int64_t origin_ns;             /* host time of timecode in */
    bool have_first;
    uint64_t frames;               /* frames offered to the recorder */
    char rig_buf[1024];            /* the session's rig path, for the header */
    /* the take's reach (fp_take_reach, into its end chunk): a histogram of the touching
     * vectors' reach in steps of 1/FP_SESSION_TAKE_REACH_STEPS (the last bin: that and
     * more), filled on the session thread without allocation */
    uint32_t reach_bins[FP_SESSION_TAKE_REACH_BINS];
    uint64_t reach_vectors;
    uint64_t reach_held;           /* of them, on the skull or the jaw (fp_take_reach.held) */
    double reach_asked_max;        /* mesh units */
    double mm_per_unit;            /* the session's, at start (0: unknown) */
    _Atomic int gate;              /* 0 open, 1 a sink call in progress, 2 sealed */
} fp_session_take;

/** Keep the options (copied; their strings are the caller's) and the session options the
 *  session is made from (mapping and input SPECs for the header; must outlive *t). */
void fp_session_take_init(fp_session_take *t, const fp_session_take_options *opt,
                          const fp_session_options *so);

/** The record sink (fp_frame_record_fn) to put into fp_session_options.record with *t as
 *  record_user: pushes each frame into the recorder while a take is recording. */
void fp_session_take_sink(void *t, const fp_frame_record *record);

/** Start a take of session s (its loaded mesh, calibration and radius) whose timecode in is
 *  the time of day now and whose time origin is the host time origin_ns (the next frame's
 *  time): the header is on disk when this returns. Returns 0, -EBUSY when already recording,
 *  or the recorder's code with err. */
int fp_session_take_start(fp_session_take *t, const fp_session *s, int64_t origin_ns,
                          char *err, size_t errlen);

/** True while a take is recording. */
bool fp_session_take_recording(const fp_session_take *t);

/** Whether the take recording has stopped writing (a full disk, an I/O error, its file
 *  deleted: the recorder's thread stopped on the write, docs/take-format.md) while it still
 *  counts as recording until fp_session_take_stop: 0 while it writes (or nothing records),
 *  else the code (-ENOSPC, -EIO, -ENOENT...) with the recorder's message, naming the file and
 *  the byte, in err. No I/O, no lock (two atomic loads): a host asks it every frame to say a
 *  failure at once rather than at the take's end. [session thread] */
int fp_session_take_failed(const fp_session_take *t, char *err, size_t errlen);

/** The running timecode of a frame at host time now_ns of the take recording (timecode in
 *  plus the frames of the rate since the origin). Returns 0, or -EINVAL when not recording. */
int fp_session_take_timecode(const fp_session_take *t, int64_t now_ns, fp_timecode *tc);

/** Stop the take recording: everything queued is written with the end chunk, the thread is
 *  joined; *res (may be NULL) says what was recorded. Returns 0, or the error that stopped
 *  the recording (-ENOSPC, -EIO...) with err; 0 when nothing was recording. */
int fp_session_take_stop(fp_session_take *t, fp_session_take_result *res, char *err,
                         size_t errlen);

/** Seal the take from a thread other than the session's: from now on the sink records
 *  nothing (a call in progress is waited for: it does no I/O and calls no plugin, so this
 *  takes microseconds), so that this thread may then stop the take (fp_session_take_stop)
 *  while the session thread is stuck elsewhere (in a plugin's process, say). For ending a
 *  process: the session thread must not start or stop the take after this (a start opens
 *  the gate again). [any thread] */
void fp_session_take_seal(fp_session_take *t);

/** Compare session s's loaded positions with the take's mesh checksum (crc of "positions").
 *  Returns 0, or -EBADMSG with a message naming both meshes and both checksums. */
int fp_session_take_check_mesh(const fp_session *s, const char *mesh_path,
                               const fp_take_header *h, char *err, size_t errlen);
/** The same for n vertex positions (n x 3 floats) loaded from mesh_path. */
int fp_take_check_positions(const float *pos, size_t n, const char *mesh_path,
                            const fp_take_header *h, char *err, size_t errlen);

/** Apply one stored frame of a take to s at the frame's time: the host actions of
 *  frame->requested (FP_SESSION_ACTION_UNDO, _RESET) first, then the control set through
 *  fp_session_apply_controls (engine with its guard, history, recorder). */
void fp_session_play_frame(fp_session *s, const fp_take_frame *frame, fp_frame_stats *st);

#ifdef __cplusplus
}
#endif
#endif
