/* measure.h: the live viewer's measurements (internal to ui/viewer): the frame time (swap to
 * swap), the latency from a hand event to the swap of the first frame that shows it (from
 * fp_session_hand_since: a tracker's own time, a replay's or a take's arrival), the engine's
 * update time and the upload's; their median and p99 for the exit report
 * (fp_viewer_report), and the lag over the last second for the HUD, both by fp_vmeasure_lag.
 *
 * Memory: the sample arrays grow by doubling (a failed growth drops the sample, never the
 * frame); fp_vmeasure_free releases them. A zeroed struct is ready. Threads: the viewer's. */
#ifndef FP_UI_MEASURE_H
#define FP_UI_MEASURE_H

#include "fp_session.h"
#include "fp_viewer.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/** A growable array of n doubles (cap allocated). */
typedef struct fp_vsamples {
    double *v;
    size_t n, cap;
} fp_vsamples;

/** Append x (dropped where the array cannot grow). */
void fp_vsamples_add(fp_vsamples *s, double x);

#define FP_VMEASURE_RECENT 64 /* frame times in the HUD's fps (their mean) */
#define FP_VMEASURE_LAG_NS 1000000000LL /* the HUD's lag: the last second's samples, */
#define FP_VMEASURE_RING 512            /* the newest 512 of each at most */

/** A sample and the swap (ns) it was taken at. */
typedef struct fp_vtimed {
    int64_t at;
    double ms;
} fp_vtimed;

typedef struct fp_vmeasure {
    uint64_t swaps;                        /* frames swapped so far */
    fp_vsamples frame_ms, latency_ms, engine_ms;
    fp_vsamples upload_ms, upload_all_ms;  /* upload() of frames that uploaded something, of all */
    int64_t last_swap;                     /* ns, fp_now_ns's clock */
    int64_t seen_time[FP_HANDS];           /* each hand's newest sample seen (time_ns) */
    int64_t pending_time[FP_HANDS];        /* ... its fp_session_hand_since, until shown; 0 none */
    double recent_frame_ms[FP_VMEASURE_RECENT];
    int recent_n;
    fp_vtimed ring_frame[FP_VMEASURE_RING], ring_latency[FP_VMEASURE_RING]; /* the newest */
    uint64_t ring_frames, ring_latencies; /* pushed so far (slot: count % FP_VMEASURE_RING) */
} fp_vmeasure;

/** A new session: no hand sample seen or waiting to be shown. */
void fp_vmeasure_new_session(fp_vmeasure *m);
/** After a step of s: each hand of its first performer with a newer sample than seen waits to
 *  be shown, late from fp_session_hand_since. */
void fp_vmeasure_hands(fp_vmeasure *m, const fp_session *s);
/** The frame was swapped (and finished) at swap (ns): its frame time (from the second swap
 *  on) and the latency of each hand sample it shows. */
void fp_vmeasure_swap(fp_vmeasure *m, int64_t swap);
/** The mean of the last FP_VMEASURE_RECENT frame times, ms (0 before two swaps). */
double fp_vmeasure_recent_ms(const fp_vmeasure *m);
/** The lag the performer sees, from n latencies and nf frame times (ms; both sorted in
 *  place): *ms the latencies' median, *frames that over the frame times' median (0 where
 *  nf is 0 or that median is not above 0). Returns n > 0: whether there is a lag to give.
 *  The exit report's latency and the HUD's lag are both this; [any-thread] on distinct
 *  arrays. */
bool fp_vmeasure_lag(double *latency_ms, size_t n, double *frame_ms, size_t nf, double *ms,
                     double *frames);
/** fp_vmeasure_lag over the samples swapped within FP_VMEASURE_LAG_NS before now (ns): the
 *  HUD's lag. False (*ms, *frames 0) where no hand sample was shown in that second. */
bool fp_vmeasure_lag_recent(const fp_vmeasure *m, int64_t now, double *ms, double *frames);
/** The HUD's lag readout into buf (len bytes, always terminated), returned: "1.3 frames
 *  (9.9 ms)", or "-" where fp_vmeasure_lag_recent has none. */
const char *fp_vmeasure_lag_text(const fp_vmeasure *m, int64_t now, char *buf, size_t len);
/** The report's timings (frame time, latency and lag in frames, engine, upload): medians and
 *  p99s, in ms. The
 *  sample arrays are sorted in place: call it once, at the end. */
void fp_vmeasure_report(fp_vmeasure *m, fp_viewer_report *rep);
void fp_vmeasure_free(fp_vmeasure *m);

#endif
