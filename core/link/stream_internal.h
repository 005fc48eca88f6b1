/* stream_internal.h: the stream's state, shared by stream_send.c (the frame thread's side:
 * options, quantising, the hand-over) and stream_tx.c (the sender thread: packets, liblo,
 * sendmmsg). Not installed. */
#ifndef FP_STREAM_INTERNAL_H
#define FP_STREAM_INTERNAL_H

#include "fp_stream.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <sys/socket.h>

#define STREAM_TIMES 4096        /* per-frame times kept for the percentiles */
#define STREAM_JOBS 64           /* frames handed over and not yet sent, at most (about 1 s at 60 fps) */

/* One frame for the sender thread: its records (vertex index, offset in steps) and header. */
typedef struct stream_job {
    uint64_t frame;
    bool key;                    /* sent as a keyframe: the sender's whole state (stream_tx.c) */
    bool full;                   /* the records are every non-zero offset (after a lost hand-over) */
    double t;
    char tc[16];
    float channels[FP_STREAM_MAX_CHANNELS];
    size_t m, cap;
    uint32_t *idx;
    int16_t *q;                  /* 3 a record */
} stream_job;

struct fp_stream {
    fp_stream_options o;
    char host[256], port[8];
    double step_mm;              /* quantisation step */
    unsigned key_period;         /* frames between keyframes */
    unsigned mtu;                /* bytes of a datagram at most */
    size_t max_records;          /* records per packet */
    int sock;
    /* the frame thread's */
    int16_t *sent;               /* n x 3: the quantised offsets last handed over */
    float *last;                 /* n x 3: the positions last quantised */
    uint32_t *idx;               /* the frame's records, before the copy into a job */
    int16_t *q;
    uint64_t frame;              /* frames made */
    bool key_requested, full_scan;
    bool resync;                 /* a frame's records were lost: the next job carries them all */
    int64_t t0_ns;
    uint64_t frames, keyframes, clipped, busy;
    double times[STREAM_TIMES];  /* the frame thread's microseconds a frame */
    /* the hand-over: a single-producer single-consumer ring of jobs */
    stream_job jobs[STREAM_JOBS];
    _Atomic size_t head, tail;
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t cond;         /* a job handed over (the sender waits on it) */
    pthread_cond_t space;        /* a job sent (a frame thread that waits for room: o.wait) */
    bool thread_ok, stop;        /* (stop: under mu) */
    /* the sender thread's */
    int16_t *tx_state;           /* n x 3: the offsets handed over so far (a keyframe sends them) */
    stream_job tx_key;           /* a keyframe's records, from tx_state */
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
    _Atomic uint64_t packets, bytes, records, dropped, send_errors, sent_frames;
    double tx_times[STREAM_TIMES];   /* the sender thread's microseconds a frame */
};

/** The sender thread's body (stream_tx.c). */
void *fp__stream_tx(void *arg);
/** Room in the sender's buffers for a frame of up to n records. Returns 0 or -ENOMEM. */
int fp__stream_tx_init(fp_stream *s);
void fp__stream_tx_free(fp_stream *s);

#endif
