/*
 * fp_stream.h: the live output stream (`--stream osc:HOST:PORT` of run, live and play;
 * docs/osc.md, "Stream"). Every frame the deformation goes out as OSC messages over UDP: each
 * vertex's offset from the neutral (the loaded mesh) in millimetres, quantised to `step`
 * (default 0.05 mm: each coordinate within step/2, a vertex within step x sqrt(3)/2 = 0.043
 * mm), only the vertices whose quantised offset changed since the last frame, and every
 * `key` frames (default 30, and on request) a keyframe with every non-zero offset. A frame's
 * packets cover the vertex indices [0, n) in consecutive ranges [lo, hi), each within `mtu`
 * bytes, each carrying the sequence number, the frame number, its time and timecode, and the
 * rig channels: a receiver that misses a packet knows which range is stale (the gap between
 * the ranges it got, or the whole frame), and a keyframe packet makes its range exact again
 * (unlisted vertices there are at the neutral). Before each keyframe /fp/stream/info says
 * the vertex count, the unit, the step and the channels' names. The frame thread hands the
 * sender thread only the changed offsets; the sender keeps every offset handed so far and
 * makes a keyframe from them, so a keyframe costs the frame thread no more than any frame.
 *
 * Test knob: FP_STREAM_DROP=P[:FRAMES] drops each packet with probability P (in the first
 * FRAMES frames only, when given), seeded by FP_STREAM_SEED (default 1); the drops are
 * counted in the summary.
 *
 * Errors: 0 or a negative errno code with err: -EINVAL a bad SPEC, -ENOENT a host that does
 * not resolve, the socket's codes, -ENOMEM. A failed send is counted, never fatal.
 * Threads: one caller thread (the frame loop's) for a stream, and the stream's own sender
 * thread (started by open, joined by finish or close); the hand-over is a lock-free ring of
 * frames (64), the sender woken by a condition variable.
 */
#ifndef FP_STREAM_H
#define FP_STREAM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_STREAM_MAX_CHANNELS 32

typedef struct fp_stream_options {
    const char *spec;               /* osc:HOST:PORT[,step=MM][,key=FRAMES][,mtu=BYTES] */
    const float *neutral;           /* n x 3 floats, mesh units: the loaded mesh; kept (caller's) */
    size_t n;
    double mm_per_unit;             /* > 0 */
    const char *mesh_path;          /* for /fp/stream/info; may be NULL */
    uint32_t mesh_crc32;            /* fp_take_crc32_positions of neutral */
    const char *const *channels;    /* names (caller's, kept), up to FP_STREAM_MAX_CHANNELS */
    size_t nchannels;
    double fps;                     /* the frame rate, for info (0: unknown) */
    bool wait;                      /* when the sender is behind, the frame waits for room
                                       (run, play: no frame lost) instead of being skipped
                                       (live: the performance keeps its pace) */
} fp_stream_options;

typedef struct fp_stream fp_stream;

/** Check SPEC's syntax (no socket). Returns 0 or -EINVAL with err. */
int fp_stream_spec_check(const char *spec, char *err, size_t errlen);

/** Resolve the host, open a UDP socket to it, allocate the state (3 x int16 a vertex) and the
 *  snapshots (2 to 8 copies of the positions, 64 MB in all where the mesh allows; touched
 *  here, so that no frame faults them in), start the sender thread and, on a mesh of 131,072
 *  vertices or more, a helper that shares large copies. Returns 0 and *out, or a negative
 *  code with err. */
int fp_stream_open(const fp_stream_options *o, fp_stream **out, char *err, size_t errlen);

/** The time origin of the frames' times (seconds since it). */
void fp_stream_origin(fp_stream *st, int64_t t0_ns);

/** Send one frame: pos (n x 3 floats, mesh units), the channels' values (nchannels floats;
 *  NULL: zeros) at host time now_ns, with timecode (may be "" or NULL). A keyframe when due
 *  or requested. On the calling thread only a copy: the positions of the blocks that may have
 *  moved go into a free snapshot, handed to the stream's sender thread, which quantises them,
 *  makes and sends the packets (liblo, sendmmsg). Returns 0; -EAGAIN when the sender holds
 *  every snapshot or is 64 frames behind (STREAM_JOBS) and o.wait is not set: the frame is not
 *  sent (a receiver sees it lost) and the next is a keyframe (with o.wait the call waits for
 *  room); -ENOMEM the same when the frame's list of blocks could not grow. */
int fp_stream_frame(fp_stream *st, const float *pos, const float *channels, int64_t now_ns,
                    const char *timecode);

/** fp_stream_frame where only the vertex ranges given can differ from the last frame's pos:
 *  ranges[2k] first vertex, ranges[2k+1] count, increasing and disjoint (fp_session_touched's;
 *  nranges SIZE_MAX or ranges NULL: any may, as fp_stream_frame). Outside them the positions
 *  must be bit for bit those of the last call. */
int fp_stream_frame_ranges(fp_stream *st, const float *pos, const uint32_t *ranges, size_t nranges,
                           const float *channels, int64_t now_ns, const char *timecode);

/** Make the next frame a keyframe. */
void fp_stream_request_key(fp_stream *st);

/** Totals so far (the sender thread's counts may trail while it runs: fp_stream_finish). */
typedef struct fp_stream_stats {
    uint64_t frames, keyframes, packets, bytes, records, dropped, send_errors, clipped;
    uint64_t busy;                                     /* frames not handed over: sender behind */
    double send_us_median, send_us_p99, send_us_max;   /* the frame thread's part a frame (the
                                                          quantising and the hand-over), the
                                                          last 4096 frames */
    double tx_us_median, tx_us_p99;                    /* the sender thread's a frame */
} fp_stream_stats;
void fp_stream_stats_get(const fp_stream *st, fp_stream_stats *out);

/** Send what was handed over and stop the sender thread (summary and close do it). */
void fp_stream_finish(fp_stream *st);

/** "to 127.0.0.1:9100, step 0.05 mm, keyframe every 30 frames, packets of at most 1400 bytes" */
void fp_stream_describe(const fp_stream *st, char *buf, size_t n);
/** fp_stream_finish, then "N frames (K keyframes), P packets, B bytes, ...; the frame thread's
 *  part median U us, ...; dropped D, ..." */
void fp_stream_summary(fp_stream *st, char *buf, size_t n);

void fp_stream_close(fp_stream **st);

#ifdef __cplusplus
}
#endif
#endif
