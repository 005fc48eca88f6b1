/*
 * fp_take.h: takes, facepuppet's recordings of performances (docs/take-format.md).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * A take is one file, SLATE_TNNN.fptake: a header (slate, take number, timecode in, frame
 * rate, date, mesh and its checksum, rig, mapping and its keys, calibration, radius,
 * description, rating) and then, per session frame, the raw input events drained that frame,
 * the performer's requested intents, and the control set the engine used (with the intents
 * the mapping returned). The stored control sets reproduce every frame exactly (play); the
 * raw events and requested intents perform the take again through another mapping or rig.
 *
 * The file is binary, little-endian, append-only, in chunks that each carry a zlib crc32, so
 * a crash loses at most the chunk being written and a reader plays everything before a cut.
 *
 * Parts:
 *   - timecode: SMPTE HH:MM:SS:FF at a rational frame rate, non-drop, and drop-frame for
 *     30000/1001 and 60000/1001 (fp_timecode_*).
 *   - naming: fp_take_next_number, fp_take_filename (never overwrite: O_CREAT|O_EXCL).
 *   - fp_take_writer: synchronous writer (header, frames batched into chunks, close).
 *   - fp_take_recorder: the writer on its own thread, fed by the session thread through a
 *     bounded lock-free single-producer single-consumer ring (fp_take_recorder_push: no
 *     allocation, no I/O, no lock, bounded time; a full ring drops and counts the frame).
 *   - fp_take_reader: open (index of every intact frame built on open), header, iteration,
 *     random access by frame index; cut or corrupt files report the byte offset.
 *   - fp_take_list: the takes of a folder, for `facepuppet takes`.
 *
 * Errors: the project's convention (core/common/fp_error.h): 0 or a negative errno-style
 * code (-EINVAL bad argument, -ENOENT, -EEXIST, -EACCES, -EIO, -ENOSPC, -ENOMEM, -EBADMSG a
 * malformed file, -ENOTSUP a newer major version), details in a caller-owned `err` buffer
 * naming the file and, for malformed files, the byte offset. Nothing is printed.
 *
 * Threads: every object belongs to one thread at a time, except the recorder, whose
 * functions name their thread ([main-thread], [session-thread], [any-thread]).
 */
#ifndef FP_TAKE_H
#define FP_TAKE_H

#include <facepuppet/plugin.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Format version written (docs/take-format.md). A reader accepts files of the same major
 *  and any minor (unknown chunk types, event types and trailing fields are skipped). */
#define FP_TAKE_VERSION_MAJOR 1
#define FP_TAKE_VERSION_MINOR 4   /* 1.1: a frame's channels are every rig channel as posed;
                                     1.2: header keys soundtrack and timecode_source, channel
                                     events (type 6); 1.3: header key performers; 1.4: header
                                     key face */
#define FP_TAKE_EXTENSION ".fptake"
#define FP_TAKE_SLATE_MAX 64      /* bytes of a slate name, NUL included */
#define FP_TAKE_DEFAULT_SLATE "scene1" /* a slate none was given: "scene1 take 2", scene1_T002.fptake */

/* ------------------------------------------------------------------------------------- */
/* Frame rate and SMPTE timecode                                                           */

/** A frame rate num/den frames per second (60/1, 30000/1001). Both > 0. */
typedef struct fp_take_rate {
    uint32_t num;
    uint32_t den;
} fp_take_rate;

/** A SMPTE timecode HH:MM:SS:FF. `drop` marks drop-frame counting (written with ';' before
 *  the frames). Hours wrap at 24. */
typedef struct fp_timecode {
    uint32_t hours, minutes, seconds, frames;
    bool drop;
} fp_timecode;

/** Frames per timecode second: the rate rounded to the nearest integer (30 for 29.97). */
uint32_t fp_timecode_base(fp_take_rate rate);

/** True where drop-frame counting is defined: 30000/1001 (drops 2 frame numbers a minute)
 *  and 60000/1001 (drops 4), except every tenth minute (SMPTE ST 12-1). */
bool fp_timecode_drop_allowed(fp_take_rate rate);

/** Frame count -> timecode (frames from 00:00:00:00, wrapping at 24 h). drop=true needs
 *  fp_timecode_drop_allowed(rate). Returns 0 or -EINVAL (bad rate, drop not allowed). */
int fp_timecode_from_frames(uint64_t frames, fp_take_rate rate, bool drop, fp_timecode *tc);

/** Timecode -> frame count since 00:00:00:00. Returns 0, or -EINVAL for a field out of range
 *  (minutes, seconds >= 60, frames >= base, hours >= 24, a frame number drop-frame skips). */
int fp_timecode_to_frames(const fp_timecode *tc, fp_take_rate rate, uint64_t *frames);

/** "HH:MM:SS:FF" (or "HH:MM:SS;FF" for drop-frame) into buf (>= 12 bytes; more for frame
 *  numbers of three digits). Returns 0 or -EINVAL (buffer too small). */
int fp_timecode_format(const fp_timecode *tc, char *buf, size_t n);

/** Parse "HH:MM:SS:FF" or "HH:MM:SS;FF" (';' or '.' marks drop-frame) and check it against
 *  rate. Returns 0 or -EINVAL with a message naming the field. */
int fp_timecode_parse(const char *text, fp_take_rate rate, fp_timecode *tc, char *err,
                      size_t errlen);

/** Frames of the take's rate in `ns` nanoseconds, rounded down (exact integer arithmetic);
 *  negative ns gives 0. */
uint64_t fp_take_frames_in(int64_t ns, fp_take_rate rate);

/** The frame count of the take's rate at a frame's time, `ns` after the time origin: the
 *  frames in ns + 1 (fp_take_frames_in), since frame times are whole nanoseconds rounded to
 *  the nearest: frame 2 at 60 fps lies at 33333333 ns, short of 2/60 s, and counts 2, not 1.
 *  What docs/take-format.md's frame timecode uses. Negative ns gives 0. */
uint64_t fp_take_frames_at(int64_t ns, fp_take_rate rate);

/** The timecode of the local time of day given as seconds + nanoseconds since the epoch
 *  (CLOCK_REALTIME), at `rate`: the "system clock" timecode source of Live Link. The local
 *  time is the process's time zone (TZ, localtime_r). Returns 0, or -EINVAL (a time
 *  localtime_r cannot convert, a bad rate, drop frame where the rate allows none). */
int fp_timecode_time_of_day(int64_t realtime_s, int64_t realtime_ns, fp_take_rate rate,
                            bool drop, fp_timecode *tc);

/* ------------------------------------------------------------------------------------- */
/* Header                                                                                  */

/** Workspace calibration of one hand: p_mesh = scale * R(rotation) p_mm + offset. */
typedef struct fp_take_calibration {
    bool present;
    double scale;          /* mesh units per millimetre */
    double rotation[4];    /* unit quaternion w, x, y, z (identity 1 0 0 0) */
    double offset[3];      /* mesh units */
} fp_take_calibration;

#define FP_TAKE_MAX_INPUTS 16
#define FP_TAKE_MAX_KEYS 32

/** 1.3: one performer's placement at the take's start (p_mesh = scale * R(rotation) p_mm +
 *  offset + hand_offset[hand]), as the session placed their hands (fp_pose.h's
 *  fp_calibration, whole: `calibration` above keeps scale and offset only). */
typedef struct fp_take_performer {
    const char *name;               /* performer=NAME; "" for a first performer whose inputs
                                       name none (writing: the caller's; reading: the reader's) */
    double scale;                   /* mesh units per millimetre, > 0 */
    double rotation[4];             /* unit quaternion w, x, y, z */
    double offset[3];               /* mesh units */
    double hand_offset[FP_HANDS][3];/* mesh units, left, right */
} fp_take_performer;

/** What a take is of. Strings are caller-owned when writing (NULL = absent) and
 *  reader-owned (valid until fp_take_reader_close) when read. */
typedef struct fp_take_header {
    char slate[FP_TAKE_SLATE_MAX];  /* [A-Za-z0-9._-], not starting with '.' */
    uint32_t take;                  /* 1..; the recorder fills it from the folder */
    fp_take_rate rate;              /* nominal frame rate of the take */
    fp_timecode timecode_in;        /* timecode at time_origin_ns */
    int64_t time_origin_ns;         /* host clock (CLOCK_MONOTONIC ns) at timecode_in */
    char date[32];                  /* ISO 8601 UTC "2025-01-31T12:34:56Z"; empty: now */
    const char *mesh_path;
    uint32_t mesh_crc32;            /* zlib crc32 (fp_take_crc32_positions or _file) */
    const char *mesh_crc_of;        /* "positions" or "file" */
    uint64_t mesh_vertices;
    const char *rig_path;
    const char *mapping;            /* mapping name, e.g. "anchored" */
    fp_param mapping_keys[FP_TAKE_MAX_KEYS];   /* its key=value settings */
    size_t mapping_key_count;
    const char *inputs[FP_TAKE_MAX_INPUTS];    /* input SPECs, index = fp_event source */
    size_t input_count;
    fp_take_calibration calibration[FP_HANDS]; /* left, right */
    double radius;                  /* support radius at the start, mesh units */
    const char *description;
    int rating;                     /* 0 (none) .. 5 */
    /* 1.2 (absent from earlier takes: NULL / 0) */
    const char *soundtrack_path;    /* the soundtrack performed to (--audio); NULL: none */
    uint32_t soundtrack_crc32;      /* zlib crc32 of the soundtrack file's bytes */
    double soundtrack_offset_s;     /* the soundtrack's time, seconds, at time_origin_ns */
    const char *timecode_source;    /* where timecode_in came from: "system" (NULL) or
                                       "ltc:FILE" (decoded LTC) */
    const char *audio_in_device;    /* the microphone recorded beside the take (--audio-in
                                       DEVICE); NULL: none. Writing: the writer names the
                                       file (fp_take_audio_in_name) */
    const char *audio_in_path;      /* its WAV's name, in the take's folder; its sample 0 is
                                       at time_origin_ns (ignored when writing) */
    /* 1.3 (absent from earlier takes: 0) */
    fp_take_performer performers[FP_PERFORMER_CAPACITY]; /* each performer's placement, in the
                                       session's order (the first first); written where count
                                       > 0 */
    size_t performer_count;
    /* 1.4 (absent from earlier takes, and where the face looks along +z with +y up: zeros) */
    double face_up[3], face_facing[3]; /* the face's axes in the mesh (fp_session_face_axes,
                                       from a placed rig or --up, --facing): a player's session
                                       takes them, so its camera sees the face's front */
} fp_take_header;

/** zlib crc32 of vertex positions (n x 3 floats) as little-endian bytes. */
uint32_t fp_take_crc32_positions(const float *positions, size_t n);
/** zlib crc32 of a whole file's bytes. Returns 0 or a negative errno with err. */
int fp_take_crc32_file(const char *path, uint32_t *crc, char *err, size_t errlen);

/* ------------------------------------------------------------------------------------- */
/* Frames                                                                                  */

/** One session frame as recorded. Writing: pointers are the caller's, read during the call
 *  only. Reading: the reader's, valid until the next read from it. */
typedef struct fp_take_frame {
    uint64_t frame;                 /* session frame number */
    int64_t time_ns;                /* the frame's host time */
    const fp_event *events;         /* raw events drained this frame (header.source = input) */
    size_t event_count;
    uint32_t requested;             /* fp_intent bits the performer asked for (keys, pedal) */
    /** The control set the engine used (its `intents` are those the mapping returned; with a
     *  rig, its channels are every channel of the rig with the value posed that frame, from
     *  keys, the host's API or the mapping: format 1.1; a channel whose value is NaN or
     *  infinite, which only a mapping without a rig returns, is not recorded: the rig ignores
     *  a NaN and a reader refuses the record); NULL where the frame had none (mapping failed):
     *  recorded as inactive, no vectors. */
    const fp_control_set *control;
} fp_take_frame;

/** Encoded size of a frame record in bytes (docs/take-format.md), or 0 when it cannot be
 *  recorded (count fields beyond 2^24; an event of unknown type, and a channel whose value
 *  is not finite, are skipped and not counted). */
size_t fp_take_frame_size(const fp_take_frame *frame);

/* ------------------------------------------------------------------------------------- */
/* Naming                                                                                  */

/** True where `slate` is a valid slate name. */
bool fp_take_slate_valid(const char *slate);

/** "SLATE_T003.fptake" (three digits at least) into buf. Returns 0 or -EINVAL. */
int fp_take_filename(const char *slate, uint32_t take, char *buf, size_t n);

/** The name of the microphone's WAV beside take `take` of `slate` (--audio-in):
 *  "SLATE_TNNN.mic.wav". Returns 0, or -EINVAL (a bad slate, take 0, buf too small). */
int fp_take_audio_in_name(const char *slate, uint32_t take, char *buf, size_t n);

/** The next free take number for `slate` in folder `dir`: one more than the largest NNN of
 *  the files SLATE_TNNN.fptake there, or 1. Numbers increase per slate and start at 1 for a
 *  slate with no take. A missing folder gives 1. Returns 0 and *take, or a negative errno. */
int fp_take_next_number(const char *dir, const char *slate, uint32_t *take, char *err,
                        size_t errlen);

/* ------------------------------------------------------------------------------------- */
/* Writer (synchronous; the recorder runs one on its thread)                              */

typedef struct fp_take_writer fp_take_writer;

typedef struct fp_take_writer_options {
    uint32_t chunk_frames;     /* frames per chunk at most; 0: 30 */
    size_t chunk_bytes;        /* flush a chunk once its payload reaches this; 0: 1 MiB */
    bool no_sync;              /* skip fdatasync after each chunk (tests); default: sync */
    bool sync_later;           /* FRMS chunks are written without fdatasync: the caller syncs
                                  (fp_take_writer_sync; the recorder: every flush_seconds);
                                  HEAD and TAIL are synced still (unless no_sync) */
    uint32_t take;             /* 0: the next free number; else exactly this one (a stage's
                                  control surface names it: --control), -EEXIST if taken */
} fp_take_writer_options;

/** Create the next take of header->slate in `dir` (made with its parents if missing, as
 *  mkdir -p: fp_file_mkdirs; -ENOTDIR where a file is in the way): choose the number
 *  (fp_take_next_number, retried on EEXIST; or opt->take exactly), open with
 *  O_CREAT|O_EXCL, write the file signature and the header chunk. header->take is ignored;
 *  header->date empty means now. Returns 0 and *out, or a negative errno with err (-EINVAL
 *  bad header, -EEXIST opt->take's file exists: never overwritten, -EACCES, -ENOSPC, -EIO).
 *  On failure no file is left behind. */
int fp_take_writer_create(const char *dir, const fp_take_header *header,
                          const fp_take_writer_options *opt, fp_take_writer **out,
                          char *err, size_t errlen);

/** The file's path (the writer's, valid until fp_take_writer_close) and take number. */
const char *fp_take_writer_path(const fp_take_writer *w);
uint32_t fp_take_writer_take(const fp_take_writer *w);

/** Append one frame; the chunk goes to disk when full. Returns 0, -EINVAL (frame cannot be
 *  recorded), or the write error (-ENOSPC, -EIO, ...) after which the writer only closes. */
int fp_take_writer_add(fp_take_writer *w, const fp_take_frame *frame, char *err, size_t errlen);
/** Append an already encoded frame record (fp_take_frame_encode's bytes, `size` of them).
 *  Returns 0, -EINVAL (a record that fails take_frame_check), or the write error as
 *  fp_take_writer_add. */
int fp_take_writer_add_encoded(fp_take_writer *w, const void *record, size_t size, char *err,
                               size_t errlen);
/** How far the skin followed the fingertips over a take (issue 51; core/session/skin_reach.h):
 *  the control vectors of its frames that started on the skin and asked to move, each one's
 *  reach (how far the skin vertex nearest its start moved over how far it was asked to), as
 *  their median and 10th percentile (fractions, 1 = all the way), and the longest ask in mm
 *  (0 where the scale is unknown); held: of those vectors, the ones whose grabbed vertex a rig
 *  keeps still (the skull or the jaw: fp_frame_stats.reach_held). vectors = 0: none (a take
 *  without touching fingertips, or one written before the reach was stored). Stored in the
 *  TAIL chunk as "reach":{"vectors":N,"median":M,"p10":P,"longest_drag_mm":L}, with
 *  "held":H where H > 0 (a reader of a take without it reads 0). */
typedef struct fp_take_reach {
    uint64_t vectors;
    double median, p10;
    double longest_drag_mm;
    uint64_t held;
} fp_take_reach;

/** The reach the end chunk will store (copied; vectors = 0 stores none; NULL w or reach:
 *  nothing). Call before fp_take_writer_close, on the thread that owns the writer. */
void fp_take_writer_set_reach(fp_take_writer *w, const fp_take_reach *reach);

/** Write the frames buffered so far as one chunk (nothing if none). Returns 0 or the write
 *  error (-ENOSPC, -EIO, ...; -ENOENT where the file was deleted while recording, its folder
 *  removed: writes to it would succeed and the take vanish at close), after which the writer
 *  only closes. */
int fp_take_writer_flush(fp_take_writer *w, char *err, size_t errlen);
/** fdatasync what was written since the last sync (nothing with no_sync, or when all is
 *  synced). Returns 0 or the error (-EIO, ...), after which the writer only closes (the file
 *  keeps its whole chunks). */
int fp_take_writer_sync(fp_take_writer *w, char *err, size_t errlen);
/** Frames buffered and not yet written. */
size_t fp_take_writer_pending(const fp_take_writer *w);

/** Flush, append the end chunk (frames, dropped frames, timecode out, end status) and close.
 *  `status` (0 or the negative code that ended the take) and `dropped` go into the end chunk.
 *  After a write error the file is cut back to its last whole chunk and no end chunk is
 *  written. Returns 0 or the first error of the take. Frees *w and sets it to NULL. */
int fp_take_writer_close(fp_take_writer **w, uint64_t dropped, int status, char *err,
                         size_t errlen);

/** Encode a frame record into buf (n bytes, at least fp_take_frame_size). Returns the size
 *  written, or 0 when it does not fit or cannot be recorded. No allocation: session-safe. */
size_t fp_take_frame_encode(const fp_take_frame *frame, void *buf, size_t n);

/* ------------------------------------------------------------------------------------- */
/* Recorder: the writer on its own thread                                                 */

typedef struct fp_take_recorder fp_take_recorder;

typedef struct fp_take_recorder_options {
    fp_take_writer_options writer;
    size_t ring_bytes;         /* ring capacity, rounded up to a power of two; 0: 8 MiB */
    double flush_seconds;      /* the file is synced to disk (fdatasync) at least this often;
                                  0: 0.25. Frames go to the file (a write(2), one chunk of what
                                  the ring held) as the thread takes them, every 2 ms at most:
                                  a kill -9 loses only the frames not yet taken */
} fp_take_recorder_options;

typedef struct fp_take_recorder_status {
    uint64_t pushed;           /* frames accepted by fp_take_recorder_push */
    uint64_t dropped;          /* frames refused: ring full, too large, or after an error;
                                  after close also those lost in the ring or the failed
                                  chunk, so that written + dropped = frames offered */
    uint64_t written;          /* frames on disk (in written chunks) */
    uint64_t bytes;            /* file size written so far */
    int error;                 /* 0, or the code that stopped the recording (-ENOSPC...) */
    bool stopped;              /* the recorder thread stopped writing (error or close) */
} fp_take_recorder_status;

/** [main-thread] Create the take (fp_take_writer_create: the header is on disk when this
 *  returns) and start the recorder thread. Returns 0 and *out or a negative code with err. */
int fp_take_recorder_start(const char *dir, const fp_take_header *header,
                           const fp_take_recorder_options *opt, fp_take_recorder **out,
                           char *err, size_t errlen);

/** [session-thread] Hand one frame to the recorder: encodes it into the ring (no allocation,
 *  no I/O, no lock, time bounded by the frame's size). Returns true when queued; false when
 *  the frame was dropped (ring full, larger than a quarter of the ring, or the recorder
 *  stopped after an error): it is counted and reported in the status and at close. */
bool fp_take_recorder_push(fp_take_recorder *rec, const fp_take_frame *frame);

/** [any-thread] Counters and the error that stopped the recording, if any (its message with
 *  fp_take_recorder_error). */
void fp_take_recorder_status_get(const fp_take_recorder *rec, fp_take_recorder_status *st);
/** [any-thread] The message of status.error ("" while none). Valid until close. */
const char *fp_take_recorder_error(const fp_take_recorder *rec);

/** [any-thread] The take's path (the recorder's, valid until its close) and number. */
const char *fp_take_recorder_path(const fp_take_recorder *rec);
uint32_t fp_take_recorder_take(const fp_take_recorder *rec);

/** [main-thread] The reach the take's end chunk will store (fp_take_writer_set_reach), set
 *  before fp_take_recorder_close; the recorder thread does not read it. Copied; NULL rec or
 *  reach: nothing. */
void fp_take_recorder_set_reach(fp_take_recorder *rec, const fp_take_reach *reach);

/** [main-thread] Stop: the thread writes every frame queued before the call, the end chunk
 *  (with the dropped count), closes the file and is joined; *st gets the final counters
 *  (may be NULL). Returns 0, or the error that stopped the recording (-ENOSPC, -EIO...)
 *  with err; a take that dropped frames returns 0 (st->dropped says how many). Frees *rec. */
int fp_take_recorder_close(fp_take_recorder **rec, fp_take_recorder_status *st, char *err,
                           size_t errlen);

/* ------------------------------------------------------------------------------------- */
/* Reader                                                                                  */

typedef struct fp_take_reader fp_take_reader;

/** What a reader found at the end of a take. */
typedef struct fp_take_summary {
    uint64_t frames;           /* intact frames */
    uint64_t first_frame, last_frame;   /* session frame numbers (0 if no frames) */
    int64_t first_time_ns, last_time_ns;
    fp_timecode timecode_out;  /* timecode_in + frames of the take's rate to the last frame */
    double duration_s;         /* first to last frame time */
    bool complete;             /* the end chunk is present (closed normally) */
    uint64_t dropped;          /* from the end chunk: frames the recorder dropped */
    int end_status;            /* from the end chunk: 0 or the code that ended the take */
    bool cut;                  /* the file is damaged or truncated after the intact part */
    uint64_t cut_offset;       /* byte offset of the first damaged or missing byte */
    uint64_t file_size;
    unsigned version_major, version_minor;   /* the file's format version (signature) */
    fp_take_reach reach;       /* from the end chunk (vectors = 0: none stored) */
    /* What a cut leaves unplayed, from a scan past the damage for whole chunks (their magic,
     * length and crc32 intact; the frames in them are not indexed): */
    uint64_t after_bytes;      /* bytes from cut_offset to the end of the file */
    uint64_t after_frames;     /* frames in whole FRMS chunks after the damaged one */
    uint64_t after_total;      /* the end chunk's "frames" where a whole one lies after it
                                  (the take's frames in all), else 0 */
} fp_take_summary;

/** Open a take: check the signature and header chunk, then scan every chunk (magic, type,
 *  length, crc32, each frame record's structure) and index every frame of the intact part.
 *  A damaged tail is not an error: open succeeds, summary.cut is set and
 *  fp_take_reader_warning says "FILE: cut at byte N: reason", and what is not played after
 *  it ("; the 151261 bytes from there are not read: 105 frames in whole chunks past the
 *  damage, of the 225 the end chunk counts": summary.after_*). A damaged signature or header
 *  fails with -EBADMSG ("FILE: byte N: reason"); -ENOTSUP for another major version;
 *  -ENOENT/-EACCES/-EIO for the file, -EISDIR (a folder), -ENXIO (a FIFO or device: refused
 *  at once, never read from; fp_file_open_regular). */
int fp_take_reader_open(const char *path, fp_take_reader **out, char *err, size_t errlen);

/** The same from memory (`data`, n bytes, copied); `name` names it in messages. */
int fp_take_reader_open_memory(const void *data, size_t n, const char *name,
                               fp_take_reader **out, char *err, size_t errlen);

/** The take's header and summary: the reader's, valid until fp_take_reader_close. */
const fp_take_header *fp_take_reader_header(const fp_take_reader *r);
const fp_take_summary *fp_take_reader_summary(const fp_take_reader *r);
/** "" or the damaged-tail warning ("FILE: cut at byte N: reason"). */
const char *fp_take_reader_warning(const fp_take_reader *r);
/** Number of intact frames (= summary.frames). */
size_t fp_take_reader_frames(const fp_take_reader *r);
/** The stored time (ns) of intact frame `index`, from the index made at open (no read, the
 *  iteration of fp_take_reader_next untouched); INT64_MIN past the end. */
int64_t fp_take_reader_time(const fp_take_reader *r, size_t index);

/** Read frame number `index` (0-based over the intact frames, not the session frame
 *  number) into *frame; its arrays are the reader's until the next read. Returns 0,
 *  -ERANGE past the end, or -EIO/-EBADMSG (the file changed under the reader) with err. */
int fp_take_reader_read(fp_take_reader *r, size_t index, fp_take_frame *frame, char *err,
                        size_t errlen);

/** Iterate: the next frame after the last read (the first after open). Returns 1 and
 *  *frame, 0 at the end, or a negative code with err. */
int fp_take_reader_next(fp_take_reader *r, fp_take_frame *frame, char *err, size_t errlen);

void fp_take_reader_close(fp_take_reader **r);

/* ------------------------------------------------------------------------------------- */
/* Editing a take's rating and description                                                 */

/** What fp_take_edit_header changes. */
typedef struct fp_take_edit {
    bool set_rating;           /* set the rating to `rating` (0 none .. 5) */
    int rating;
    const char *description;   /* the new description ("" clears it); NULL keeps it */
    bool open_ok;              /* rewrite a take with no end chunk too (see below) */
} fp_take_edit;

/** Rewrite the header of the take at `path` with e's rating and description (`facepuppet
 *  takes rate` and `describe`). Only the header chunk's "rating" and "description" members
 *  change (a member missing is added); every other byte of the file (the signature, the
 *  header's other members as written, every frame chunk, the end chunk) is copied as it was.
 *  Atomic: a temporary file beside the take (fp_file_open_output: a symbolic link written
 *  through, the file's mode kept), fsync, renamed over it, the folder synced: a crash leaves
 *  the old take or the new one. The take is read whole first (fp_take_reader_open); one with
 *  no end chunk may still be recording (its recorder would write on into the replaced file;
 *  a take read while its last chunk is half written looks cut) and is refused with -EBUSY
 *  unless e->open_ok, whether cut or not. Returns 0, or -EINVAL (NULL,
 *  a rating outside 0..5, a description that is not UTF-8 text: fp_text_ok with lines),
 *  the reader's codes (-ENOENT, -EBADMSG a damaged header, -ENOTSUP, ...), -EBUSY, or the
 *  write's (-EACCES, -ENOSPC, -EIO; the take then as it was), with err naming the file.
 *  Nothing printed. Any thread; not against another writer of the same file. */
int fp_take_edit_header(const char *path, const fp_take_edit *e, char *err, size_t errlen);

/* ------------------------------------------------------------------------------------- */
/* Listing a folder                                                                        */

typedef struct fp_take_info {
    char path[4096];
    char slate[FP_TAKE_SLATE_MAX];
    uint32_t take;
    fp_take_rate rate;
    fp_timecode timecode_in, timecode_out;
    double duration_s;
    uint64_t frames;
    char mesh[256];            /* mesh path as recorded (truncated) */
    char mapping[64];
    int rating;
    char date[32];
    char description[512];     /* the header's description (truncated), "" when none */
    bool complete;             /* closed normally */
    fp_take_reach reach;       /* from the end chunk (vectors = 0: none stored) */
    int error;                 /* 0, or the code why this file could not be read */
    char message[256];         /* the error or the cut warning, "" when none */
} fp_take_info;

/** Every *.fptake of `dir`, sorted by slate then take number; unreadable files are listed
 *  with .error and .message set. *out is malloc()ed (free() it), *count its length.
 *  Returns 0 or a negative errno (the folder cannot be read) with err. */
int fp_take_list(const char *dir, fp_take_info **out, size_t *count, char *err,
                 size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
