/*
 * fp_filter.h: the input filter of step 2 (docs/architecture.md): the One Euro filter of
 * Casiez, Roussel and Vogel, "1 Euro Filter: A Simple Speed-based Low-pass Filter for Noisy
 * Input in Interactive Systems", CHI 2012, pp. 2527-2530 (doi 10.1145/2207676.2208639), run
 * per joint and per input on the hand events (a hand's joint positions sharing one cutoff,
 * fp_oneeuro_filter_joints) (core/pose/fp_pose.h), and the host keys that
 * set it on an input SPEC (`filter=oneeuro,mincutoff=HZ,beta=B,dcutoff=HZ,trend=HZ`, stripped
 * by core/plugin before the plugin sees its keys).
 *
 * The filter, at each sample X_i taken at time t_i (T_e = t_i - t_{i-1}, seconds):
 *
 *   alpha(f_c)  = 1 / (1 + tau / T_e),  tau = 1 / (2 pi f_c)     (a first-order low pass)
 *   dX_i        = (X_i - Xhat_{i-1}) / T_e                       (the paper's Algorithm 1)
 *   dXhat_i     = alpha(d_cutoff) dX_i + (1 - alpha(d_cutoff)) dXhat_{i-1}
 *   f_c         = mincutoff + beta |dXhat_i|
 *   Xhat_i      = alpha(f_c) X_i + (1 - alpha(f_c)) (Xhat_{i-1} + g_i T_e B_{i-1})
 *   B_i         = g_i alpha(trend) (Xhat_i - Xhat_{i-1}) / T_e + (1 - alpha(trend)) B_{i-1}
 *   s_i         = -(X_i - Xhat_{i-1}) . B_{i-1} / |B_{i-1}|       (mm behind along the trend)
 *   g_i         = 1 - clamp((s_i - SLACK) / (STOP - SLACK), 0, 1) (FP_FILTER_TREND_SLACK_MM,
 *                                                                 FP_FILTER_TREND_STOP_MM)
 *   (B_{i-1} taken as 0 where T_e > FP_FILTER_TREND_GAP_S; g_i = 1 where B_{i-1} = 0)
 *
 * with Xhat_0 = X_0, dXhat_0 = 0, B_0 = 0. B is Holt's trend (C. C. Holt, "Forecasting
 * seasonals and trends by exponentially weighted moving averages", 1957; Int. J. Forecasting
 * 20(1), 2004, pp. 5-10; "double exponential smoothing", which LaViola, EGVE 2003, used for
 * tracked hands): the low pass smooths about where the motion is heading, not where it was,
 * so a steady motion is followed without lag once B has settled (a time constant of
 * 1 / (2 pi trend) after it starts or turns), and the cutoff can stay low for the jitter.
 * As the sample falls behind the smoothed position along B (the motion stopping or turning)
 * the prediction fades, from all of it at FP_FILTER_TREND_SLACK_MM to none at
 * FP_FILTER_TREND_STOP_MM, and B dies away: Holt's trend alone carries a stopping hand on (at
 * a low cutoff the prediction outweighs the sample): 10.8 mm past a sudden stop from
 * 300 mm/s at 57 Hz, 4.3 mm with the fade (tests/pose/test_filter.c). The fade is a ramp,
 * not a switch, so the output is continuous in the sample: with a switch at one distance
 * the noise decided at each turn of a slow motion whether the prediction went on or stopped,
 * and the face jumped between frames there (docs/performance.md, "The filter's trend
 * fades"). trend = 0 leaves B at 0: the paper's filter, bit for bit.
 *
 * A joint is filtered as one vector (its 3 coordinates share the cutoff, |dXhat| being the
 * length of the filtered velocity: the shape of a motion is kept, whatever its direction); a
 * joint angle (a glove's sensor) as a scalar. Speeds are in mm/s so
 * that one `beta` serves every kind of input: an angle's rate counts as the speed of a point
 * FP_FILTER_ARM_MM from the joint (radians x 100 mm: a fingertip about a knuckle), a wrist
 * rotation's likewise (the quaternion's rate is half the angular speed).
 *
 * Its lag without the trend (trend = 0): on a steady ramp of speed v (mm/s) sampled every T_e,
 * the output trails the input by exactly lambda = tau(f_c) seconds, where f_c = mincutoff +
 * beta (v + v lambda / T_e) (the derivative sees the lag too); fp_oneeuro_lag solves it.
 * lambda <= 1 / (2 pi (mincutoff + beta v)) at any rate, the bound `run` reports.
 *
 * Units: times in nanoseconds of the event clock (plugin.h), cutoffs in Hz, beta in Hz per
 * mm/s. Errors: fp_filter_parse returns -EINVAL with a message; nothing else fails.
 * Threads: pure functions; an fp_oneeuro belongs to one thread (the session thread).
 * No allocation, no I/O.
 */
#ifndef FP_FILTER_H
#define FP_FILTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Which filter an input's hand events go through. */
typedef enum fp_filter_kind {
    FP_FILTER_OFF = 0,      /* the events as the input gave them */
    FP_FILTER_ONEEURO = 1,  /* the One Euro filter, per joint */
    FP_FILTER_AUTO = 2      /* the One Euro filter on the events the input flags
                               FP_EVENT_FLAG_UNSMOOTHED (plugin.h: a tracker that does not
                               smooth its own samples), the others as given */
} fp_filter_kind;

/** An input's filter settings (the SPEC keys filter=, mincutoff=, beta=, dcutoff=, trend=). */
typedef struct fp_filter_config {
    fp_filter_kind kind;
    double mincutoff;   /* Hz, > 0: the cutoff when the joint is still (the jitter left) */
    double beta;        /* Hz per mm/s, >= 0: how fast the cutoff rises with speed (the lag) */
    double dcutoff;     /* Hz, > 0: the cutoff of the speed estimate (the paper: 1 Hz) */
    double trend;       /* Hz, >= 0: the cutoff of Holt's trend B (0: none, the paper's) */
} fp_filter_config;

/** The defaults of filter=oneeuro (a camera tracker: MediaPipe, Leap Motion over OSC), chosen
 *  on the real Leap recordings with 1 mm of Gaussian noise added on every joint, through
 *  onehand at 60 frames a second, 108 Hz and resampled to 57 Hz (`FP_TEST_STEADY_CLIP=NAME
 *  FP_TEST_STEADY_HZ=57 build/tests/test_steady_session` prints each; its tests check every
 *  row below, the hand's jitter on HandSplay only; FP_TEST_FILTER_KEYS=",trend=0,mincutoff=0.5,
 *  beta=0.018" gives the old column).
 *  Jitter in still holds, hand / face, x less than unfiltered (5x asked); lag in frames (one
 *  asked; negative: ahead). The defaults' column through onehand's eased jaw (ease=0.3,
 *  plugins/map-onehand) and the trend's fade (FP_FILTER_TREND_SLACK_MM to _STOP_MM), the
 *  test's noise (seed 51) and, after "|", the worst face of seeds 1-3 (FP_TEST_STEADY_SEED);
 *  the no-trend column was measured with the jaw straight from neutral and seed 51 (before
 *  the ease; the defaults then gave Waiting's face 11.8x and 16.9x, whose unfiltered face the
 *  straight jaw's chatter made 2.5x as unsteady, and a still hand pinching 2.6x):
 *
 *    clip, rate        no trend (0.5, 0.018, 6)        trend 6 Hz (0.3, 0.01, 6): the defaults
 *    HandSplay 108     6.3 / 6.2, lag 0.60 / 0.70      8.4 / 8.9, lag 0.35 / 0.05  | 7.2
 *    HandSplay 57      5.4 / 5.3, lag 0.80 / 0.85      7.3 / 7.8, lag 0.60 / 0.05  | 5.6
 *    grab 108          6.1 / 5.6, lag 0.50 / 0.70      7.6 / 5.7, lag 0.35 / 0.10  | 6.3
 *    grab 57           5.4 / 5.2, lag 0.65 / 1.25      7.2 / 6.4, lag 0.55 / 0.75  | 5.7
 *    Waiting 108       5.6 / 5.6, lag 0.60 / 0.70      7.7 / 5.8, lag 0.45 / 0.05  | 5.6
 *    Waiting 57        4.9 / 2.5, lag 0.75 / 1.05      6.2 / 5.6, lag 0.75 / 0.50  | 5.1
 *    three-claps 108   4.0 / 4.4, lag 0.65 / 0.70      4.7 / 6.5, lag 0.40 / 0.50  | 5.4
 *    three-claps 57                                    4.4 / 6.1, lag 0.65 / 0.60  | 4.9 (seed 3)
 *    still pinch 108                                   10.6 / 9.6, lag 0.15 / 0.45 | 7.2 (seed 2)
 *    still pinch 57                                    11.0 / 10.9, lag 0.35 / 0.45 | 5.6 (seed 2)
 *
 *  Before the fade (a switch at 3 mm) the same seeds 1-3 gave the face 4.8x on Waiting at
 *  108 and 57 Hz, a face lag of 1.15 frames on Waiting at 57 Hz, 4.4x on three-claps, and
 *  3.9-4.4x on tools/hands-variants' still-pinching copies at 57 Hz (6.2-6.6x with the fade):
 *  docs/performance.md, "The filter's trend fades".
 *
 *  Without the trend a low pass smooths where the motion was, so the cutoff that leaves 5x
 *  less jitter lagged the slow motions (grab's jaw, closed by a slow thumb, over a frame at
 *  57 Hz), and in Waiting at 57 Hz the lag counted as jitter. With it the cutoff could go
 *  down (0.3 Hz, beta 0.01). Swept (trend 1-8 Hz, mincutoff 0.2-0.3, beta 0.007-0.012, the
 *  stop rule, then a switch, at 0, 2 and 3 mm): a trend of 1 Hz lingered into the holds
 *  (jitter 4.4-5.2x); with no slack, noise stopped the trend of slow motions (face lag
 *  1.1-1.3 frames at 57 Hz); with none of the stop rule, the face ran up to 0.85 frames
 *  ahead. Still short of 5x:
 *  three-claps' hand (11 hold frames, between claps, each right after a fast motion). At
 *  30 Hz (FP_TEST_STEADY_HZ=30; a webcam's MediaPipe) neither filter reaches 5x: showing a
 *  30 Hz hand at 60 fps interpolates every other frame, which halves the unfiltered jitter
 *  (1.1 mm instead of 2.3). HandSplay 3.4 / 2.3x, lag 0.80 / 0.50 (no trend: 3.8 / 2.6x,
 *  0.75 / 1.30); grab 3.7 / 3.8x, lag 0.60 / -1.30 (3.8 / 3.6x, 0.60 / 1.25). The
 *  derivative's cutoff is well above the paper's 1 Hz: at 1 Hz the speed estimate takes
 *  160 ms to see a hand start moving. */
#define FP_FILTER_MINCUTOFF 0.3
#define FP_FILTER_BETA 0.01
#define FP_FILTER_DCUTOFF 6.0
#define FP_FILTER_TREND 6.0
/** How far (mm) a sample may fall behind the smoothed position along the trend before the
 *  trend's prediction begins to fade (about the trackers' jitter, so that noise barely slows a
 *  slow motion's trend), and how far behind it is gone (the motion stopped or turned). */
#define FP_FILTER_TREND_SLACK_MM 1.0
#define FP_FILTER_TREND_STOP_MM 4.0
/** A sample more than this many seconds after the last (a tracker that lost the hand, or
 *  paused) starts the trend afresh (B = 0): no motion is guessed across a gap. */
#define FP_FILTER_TREND_GAP_S 0.1
/** A glove's defaults (cyberglove): light, its bend sensors' noise being small (a step of the
 *  converter): a higher cutoff when still, so less lag; its sensors each filtered alone, at
 *  the camera trackers' settings before the joints shared a cutoff; no trend (trend=0). */
#define FP_FILTER_GLOVE_MINCUTOFF 3.0
#define FP_FILTER_GLOVE_BETA 0.025
#define FP_FILTER_GLOVE_DCUTOFF 8.0
/** An angle's rate in rad/s counts as this many mm/s (a point 100 mm from the joint). */
#define FP_FILTER_ARM_MM 100.0

/** The filter an input of this plugin NAME gets when its SPEC says nothing: "osc" auto at
 *  the defaults above (FP_FILTER_AUTO: the hands of a MediaPipe sender, whose landmarks
 *  jitter, filtered; a Leap's or another facepuppet's, smooth already, as sent, so that they
 *  deform the face as their recordings replayed do), "cyberglove" the One Euro filter at the
 *  glove's settings (FP_FILTER_GLOVE_*), every other input ("replay", "take", "pedal", a
 *  third party's) off: a recording replayed for analysis is seen as recorded. name may be
 *  NULL (off). */
void fp_filter_default(const char *name, fp_filter_config *out);

/** The filter of an input named `name` from its host keys (each NULL where not given):
 *  filter=oneeuro|auto|off, mincutoff=HZ (decimal in (0, 1000]), beta=B (in [0, 100]),
 *  dcutoff=HZ (in (0, 1000]), trend=HZ (in [0, 1000]; 0 turns the trend off). Starts from
 *  fp_filter_default(name); mincutoff, beta, dcutoff or trend change the One Euro filter's
 *  settings, so they need it on or auto (the input's default, filter=oneeuro or filter=auto).
 *  Returns 0 and *out, or -EINVAL (*out untouched) with a message naming the key into err
 *  (errlen bytes, may be 0). */
int fp_filter_parse(const char *name, const char *filter, const char *mincutoff,
                    const char *beta, const char *dcutoff, const char *trend, fp_filter_config *out,
                    char *err, size_t errlen);

/** One line for a person: without a trend "hands filtered in the session (oneeuro
 *  mincutoff=0.5 beta=0.018 dcutoff=6): a steady motion lags 19 ms at 200 mm/s, 43 ms at 50
 *  mm/s (samples at 60 Hz; at most 39 and 114 ms at any rate)" (fp_oneeuro_lag at
 *  FP_FILTER_DESCRIBE_HZ, and its bound); with one "(oneeuro mincutoff=0.3 beta=0.01
 *  dcutoff=6 trend=6): a steady motion is followed without lag once its trend has settled
 *  (about 27 ms after it starts or turns)" (1 / (2 pi trend)); for auto "hands filtered in
 *  the session where the tracker does not smooth them (MediaPipe's landmarks; a Leap's
 *  joints as sent) (oneeuro ...", or "filter off". Returns the length snprintf would write. */
#define FP_FILTER_DESCRIBE_HZ 60.0
int fp_filter_describe(const fp_filter_config *c, char *buf, size_t len);

/** The state of one One Euro filter over a vector of up to FP_ONEEURO_MAX_DIM values. */
#define FP_ONEEURO_MAX_DIM 4
typedef struct fp_oneeuro {
    double x[FP_ONEEURO_MAX_DIM];   /* Xhat_{i-1} */
    double dx[FP_ONEEURO_MAX_DIM];  /* dXhat_{i-1}, units per second */
    double tr[FP_ONEEURO_MAX_DIM];  /* B_{i-1}, Holt's trend, units per second */
    double te;                      /* the last sampling period, seconds */
    int64_t t_ns;                   /* t_{i-1} */
    bool started;                   /* a sample was taken since the reset */
} fp_oneeuro;

/** Forget every sample: the next one is passed through unchanged (Xhat_0 = X_0). */
void fp_oneeuro_reset(fp_oneeuro *f);

/** alpha(f_c) = 1 / (1 + tau / T_e), tau = 1 / (2 pi cutoff_hz): the smoothing factor of a
 *  first-order low pass sampled every te_s seconds (both > 0). */
double fp_oneeuro_alpha(double cutoff_hz, double te_s);

/** Filter one sample x (dim values, 1..FP_ONEEURO_MAX_DIM; the same dim every call) taken at
 *  t_ns into out (may be x): the equations above with c's settings (c->kind is not read),
 *  |dXhat| the Euclidean length of the filtered derivative times mm_per_unit (1 for mm,
 *  FP_FILTER_ARM_MM for radians). T_e is t_ns minus the last sample's time; a sample at or
 *  before the last one's time (a repeated stamp) uses the last T_e (1/120 s before any).
 *  A non-finite value in x resets the filter and is passed through. */
void fp_oneeuro_filter(fp_oneeuro *f, const fp_filter_config *c, int dim, double mm_per_unit,
                       const double *x, int64_t t_ns, double *out);

/** A hand's joint positions, filtered as one hand: count filters f[0 .. count) (count <=
 *  FP_ONEEURO_MAX_JOINTS), one a joint, each over the 3-vector x[j] (mm) taken at t_ns,
 *  filtered in place. Each joint keeps its own dXhat and Xhat (its own noise averaged by its
 *  own low pass), but the joints share one cutoff, f_c = mincutoff + beta |dXhat| of the
 *  fastest joint this sample, as a joint's coordinates share theirs: the hand keeps its shape
 *  as it moves (joint-to-joint vectors, which a mapping reads, lag as the joints do), and the
 *  still palm of a hand whose fingers close follows them at once. A joint whose filter had
 *  not started, or whose sample is not finite, passes through as in fp_oneeuro_filter and
 *  does not count. Same units and rules as fp_oneeuro_filter; c->kind is not read. Nothing
 *  fails (count is asserted, and only the first FP_ONEEURO_MAX_JOINTS are filtered in a
 *  release build); no allocation; f belongs to one thread (the session thread). */
#define FP_ONEEURO_MAX_JOINTS 32
void fp_oneeuro_filter_joints(fp_oneeuro *f, size_t count, const fp_filter_config *c,
                              double (*x)[3], int64_t t_ns);

/** The One Euro filter's lag on a steady ramp of speed_mm_s sampled at rate_hz, seconds:
 *  lambda = tau(mincutoff + beta (v + v lambda T_e^-1)) solved exactly (a quadratic in
 *  lambda). rate_hz <= 0 or not finite: the bound at any rate, 1 / (2 pi (mincutoff +
 *  beta v)). With a trend (c->trend > 0) 0: once settled, the ramp is followed exactly.
 *  c->kind is not read. */
double fp_oneeuro_lag(const fp_filter_config *c, double speed_mm_s, double rate_hz);

#ifdef __cplusplus
}
#endif
#endif
