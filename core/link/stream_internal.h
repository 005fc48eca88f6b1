/* stream_internal.h: the stream's state, shared by stream_send.c (the frame thread's side:
 * options, the hand-over), stream_snap.c (the frame thread's copy of the touched blocks),
 * stream_collect.c (the sender thread's quantising) and stream_tx.c (the sender thread:
 * packets, liblo, sendmmsg). Not installed. */
#ifndef FP_STREAM_INTERNAL_H
#define FP_STREAM_INTERNAL_H

#include "fp_stream.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <sys/socket.h>

#define STREAM_TIMES 4096        /* per-frame times kept for the percentiles */
#define STREAM_JOBS 64           /* frames handed over and not yet sent, at most (about 1 s at 60 fps) */

/* A frame's records (vertex index, offset in steps) and header, as the sender thread sends
 * them (stream_tx.c). */
typedef struct stream_job {
    uint64_t frame;
    bool key;                    /* sent as a keyframe: the sender's whole state */
    double t;
    char tc[16];
    float channels[FP_STREAM_MAX_CHANNELS];
    size_t m, cap;
    uint32_t *idx;
    int16_t *q;                  /* 3 a record */
} stream_job;

/* One frame handed to the sender thread: its header, and a snapshot of the positions in its
 * touched blocks (stream_snap.c), which the sender quantises (stream_collect.c). */
typedef struct stream_hand {
    stream_job head;             /* the header (frame, key, t, tc, channels; no records) */
    int snap;                    /* the snapshot (index into fp_stream.snaps) */
    uint32_t *ranges;            /* its blocks: (first, count) pairs, multiples of BLOCK (the
                                    last may end at n), increasing and disjoint */
    size_t nranges, cap_ranges;
} stream_hand;

#define STREAM_BLOCK 64          /* vertices quantised and compared at once */
#define STREAM_SNAPS_MAX 8       /* snapshots at most (fewer on a large mesh: 64 MB in all) */

struct fp_stream {
    fp_stream_options o;
    char host[256], port[8];
    double step_mm;              /* quantisation step */
    unsigned key_period;         /* frames between keyframes */
    unsigned mtu;                /* bytes of a datagram at most */
    size_t max_records;          /* records per packet */
    int sock;
    /* the snapshots: each n x 3 floats, made and touched at the opening; one is the frame
       thread's from its copy until the sender has quantised it */
    float *snaps[STREAM_SNAPS_MAX];
    int nsnaps;
    _Atomic bool snap_busy[STREAM_SNAPS_MAX];
    /* the frame thread's */
    struct fp_worker *helper;    /* copies half of a large frame (NULL: a small mesh) */
    size_t split_min;            /* touched vertices from which it does */
    const float *help_pos;       /* its part: pos into snap over the hand's ranges from */
    float *help_snap;            /* vertex help_from on */
    const stream_hand *help_hand;
    size_t help_from;
    _Atomic uint32_t help_done;  /* the last wake it served */
    uint64_t frame;              /* frames made */
    bool key_requested, full_scan;
    int64_t t0_ns;
    uint64_t frames, keyframes, busy;
    double times[STREAM_TIMES];  /* the frame thread's microseconds a frame */
    /* the hand-over: a single-producer single-consumer ring */
    stream_hand jobs[STREAM_JOBS];
    _Atomic size_t head, tail;
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t cond;         /* a job handed over (the sender waits on it) */
    pthread_cond_t space;        /* a job sent (a frame thread that waits for room: o.wait) */
    bool thread_ok, stop;        /* (stop: under mu) */
    /* the sender thread's */
    int16_t *tx_state;           /* n x 3: the offsets sent so far, in steps (a keyframe sends
                                    them; a frame sends those that changed) */
    stream_job tx_rec;           /* the frame's records */
    stream_job tx_key;           /* a keyframe's records, from tx_state */
    bool tx_key_owed;            /* a frame's records were lost: the next is a keyframe */
    unsigned char *slots;        /* the frame's packets, serialised, nslots x slot_size */
    size_t nslots, slot_size;
    struct mmsghdr *msgs;
    struct iovec *iov;
    size_t *starts, nstarts;     /* the record each packet of the frame starts at */
    unsigned char *blob;         /* one packet's records */
    uint32_t seq;                /* packets made */
    double drop_p;               /* the test knob FP_STREAM_DROP */
    uint64_t drop_frames;        /* 0: every frame */
    uint64_t rng;
    _Atomic uint64_t packets, bytes, records, dropped, send_errors, sent_frames, clipped;
    double tx_times[STREAM_TIMES];   /* the sender thread's microseconds a frame */
};

/** The sender thread's: the hand's records into s->tx_rec (the changed offsets of its
 *  blocks), tx_state updated; the snapshot is then free. Returns 0, or -ENOMEM: tx_state is
 *  up to date, the records are not (send a keyframe). stream_collect.c. */
int fp__stream_collect(fp_stream *s, const stream_hand *h);
/** Room for m records in j. Returns 0 or -ENOMEM. */
int fp__stream_reserve(stream_job *j, size_t m);

/** The frame thread's (stream_snap.c): the snapshots (a count that fits the mesh) and the
 *  copying helper of a large mesh (none below 131,072 vertices, or FP_STREAM_SPLIT's count).
 *  Returns 0 or a negative errno; fp__stream_snap_free undoes it (the sender stopped). */
int fp__stream_snap_open(fp_stream *s);
void fp__stream_snap_free(fp_stream *s);
/** A free snapshot's index, or -1 (all are the sender's). */
int fp__stream_snap_take(fp_stream *s);
/** h's ranges: the blocks of the touched ranges (all: every block). Returns 0 or -ENOMEM. */
int fp__stream_snap_ranges(stream_hand *h, const uint32_t *ranges, size_t nranges, bool all, size_t n);
/** pos (n x 3) into h's snapshot over h's ranges (with the helper, on a large frame). */
void fp__stream_snap_copy(fp_stream *s, const stream_hand *h, const float *pos);

/** The calling thread to SCHED_BATCH (the sender's and the copying helper's): woken by the
 *  frame thread it does not preempt it on its CPU (wakeup preemption: the sender's hand-over
 *  signal took 61 us, the helper's wake up to 3.6 ms on the 1.7M face); it runs when a CPU
 *  is free. Best effort: the default policy where refused. stream_tx.c. */
void fp__stream_batch(void);

/** The sender thread's body (stream_tx.c). */
void *fp__stream_tx(void *arg);
/** Room in the sender's buffers for a frame of up to n records. Returns 0 or -ENOMEM. */
int fp__stream_tx_init(fp_stream *s);
void fp__stream_tx_free(fp_stream *s);

#endif
