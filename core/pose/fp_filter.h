/*
 * fp_filter.h: the input filter of step 2 (docs/architecture.md): the One Euro filter of
 * Casiez, Roussel and Vogel, "1 Euro Filter: A Simple Speed-based Low-pass Filter for Noisy
 * Input in Interactive Systems", CHI 2012, pp. 2527-2530 (doi 10.1145/2207676.2208639), run
 * per joint and per input on the hand events (core/pose/fp_pose.h), and the host keys that
 * set it on an input SPEC (`filter=oneeuro,mincutoff=HZ,beta=B,dcutoff=HZ`, stripped by
 * core/plugin before the plugin sees its keys).
 *
 * The filter, at each sample X_i taken at time t_i (T_e = t_i - t_{i-1}, seconds):
 *
 *   alpha(f_c)  = 1 / (1 + tau / T_e),  tau = 1 / (2 pi f_c)     (a first-order low pass)
 *   dX_i        = (X_i - Xhat_{i-1}) / T_e                       (the paper's Algorithm 1)
 *   dXhat_i     = alpha(d_cutoff) dX_i + (1 - alpha(d_cutoff)) dXhat_{i-1}
 *   f_c         = mincutoff + beta |dXhat_i|
 *   Xhat_i      = alpha(f_c) X_i + (1 - alpha(f_c)) Xhat_{i-1}
 *
 * with Xhat_0 = X_0, dXhat_0 = 0. A joint is filtered as one vector (its 3 coordinates share
 * the cutoff, |dXhat| being the length of the filtered velocity: the shape of a motion is kept,
 * whatever its direction); a joint angle (a glove's sensor) as a scalar. Speeds are in mm/s so
 * that one `beta` serves every kind of input: an angle's rate counts as the speed of a point
 * FP_FILTER_ARM_MM from the joint (radians x 100 mm: a fingertip about a knuckle), a wrist
 * rotation's likewise (the quaternion's rate is half the angular speed).
 *
 * Its lag: on a steady ramp of speed v (mm/s) sampled every T_e, the output trails the input
 * by exactly lambda = tau(f_c) seconds, where f_c = mincutoff + beta (v + v lambda / T_e)
 * (the derivative sees the lag too); fp_oneeuro_lag solves it. lambda <= 1 / (2 pi
 * (mincutoff + beta v)) at any rate, the bound `run` reports.
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
    FP_FILTER_ONEEURO = 1   /* the One Euro filter, per joint */
} fp_filter_kind;

/** An input's filter settings (the SPEC keys filter=, mincutoff=, beta=, dcutoff=). */
typedef struct fp_filter_config {
    fp_filter_kind kind;
    double mincutoff;   /* Hz, > 0: the cutoff when the joint is still (the jitter left) */
    double beta;        /* Hz per mm/s, >= 0: how fast the cutoff rises with speed (the lag) */
    double dcutoff;     /* Hz, > 0: the cutoff of the speed estimate (the paper: 1 Hz) */
} fp_filter_config;

/** The defaults of filter=oneeuro (a camera tracker: MediaPipe, Leap Motion over OSC), chosen
 *  on the real Leap recordings (HandSplay, grab, Waiting; 108 Hz and resampled to 57 Hz) with
 *  1 mm of Gaussian noise added on every joint, read at 60 frames a second: still holds 5.6x
 *  to 6.7x steadier at 108 Hz (5x to 6x at 57 Hz) and the motion 0.5 to 0.65 frames behind
 *  (0.65 to 0.85 at 57 Hz); tests/pose/test_steady_session.c checks HandSplay. The face
 *  through onehand follows the hand (HandSplay 6.3x, grab 5.6x at 108 Hz) but on Waiting
 *  4.7x against its hand's 5.7x, whatever the settings tried (mincutoff 0.3-0.7, beta
 *  0.015-0.035, dcutoff 4-12). Its jaw alone gives the same 4.7x (targets=-/-/-/-), and
 *  the jaw is shut in about a third of its frames, where the noise does not move it (not
 *  established as the cause); FP_TEST_STEADY_CLIP=Waiting-110fps FP_TEST_FILTER_KEYS=
 *  ",mincutoff=..." build/tests/test_steady_session prints the figures. The
 *  derivative's cutoff is well above the paper's 1 Hz: at 1 Hz the speed estimate takes
 *  160 ms to see a hand start moving, and the motion lags 1.2 frames for the same jitter. */
#define FP_FILTER_MINCUTOFF 0.5
#define FP_FILTER_BETA 0.025
#define FP_FILTER_DCUTOFF 8.0
/** A glove's defaults (cyberglove): light, its bend sensors' noise being small (a step of the
 *  converter): a higher cutoff when still, so less lag. */
#define FP_FILTER_GLOVE_MINCUTOFF 3.0
/** An angle's rate in rad/s counts as this many mm/s (a point 100 mm from the joint). */
#define FP_FILTER_ARM_MM 100.0

/** The filter an input of this plugin NAME gets when its SPEC says nothing: "osc" the One
 *  Euro filter at the defaults above (camera trackers jitter), "cyberglove" at the glove's
 *  (mincutoff FP_FILTER_GLOVE_MINCUTOFF), every other input ("replay", "take", "pedal", a
 *  third party's) off: a recording replayed for analysis is seen as recorded. name may be
 *  NULL (off). */
void fp_filter_default(const char *name, fp_filter_config *out);

/** The filter of an input named `name` from its host keys (each NULL where not given):
 *  filter=oneeuro|off, mincutoff=HZ (decimal in (0, 1000]), beta=B (in [0, 100]),
 *  dcutoff=HZ (in (0, 1000]). Starts from fp_filter_default(name); mincutoff, beta or dcutoff
 *  change the One Euro filter's settings, so they need it on (the input's default or
 *  filter=oneeuro). Returns 0 and *out, or -EINVAL (*out untouched) with a message naming the
 *  key into err (errlen bytes, may be 0). */
int fp_filter_parse(const char *name, const char *filter, const char *mincutoff,
                    const char *beta, const char *dcutoff, fp_filter_config *out, char *err,
                    size_t errlen);

/** One line for a person: "hands filtered in the session (oneeuro mincutoff=0.5 beta=0.025
 *  dcutoff=8): a steady motion lags 16 ms at 200 mm/s, 36 ms at 50 mm/s (samples at 60 Hz; at
 *  most 29 and 91 ms at any rate)" (fp_oneeuro_lag at FP_FILTER_DESCRIBE_HZ, and its bound),
 *  or "filter off". Returns the length snprintf would write. */
#define FP_FILTER_DESCRIBE_HZ 60.0
int fp_filter_describe(const fp_filter_config *c, char *buf, size_t len);

/** The state of one One Euro filter over a vector of up to FP_ONEEURO_MAX_DIM values. */
#define FP_ONEEURO_MAX_DIM 4
typedef struct fp_oneeuro {
    double x[FP_ONEEURO_MAX_DIM];   /* Xhat_{i-1} */
    double dx[FP_ONEEURO_MAX_DIM];  /* dXhat_{i-1}, units per second */
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

/** The One Euro filter's lag on a steady ramp of speed_mm_s sampled at rate_hz, seconds:
 *  lambda = tau(mincutoff + beta (v + v lambda T_e^-1)) solved exactly (a quadratic in
 *  lambda). rate_hz <= 0 or not finite: the bound at any rate, 1 / (2 pi (mincutoff +
 *  beta v)). c->kind is not read. */
double fp_oneeuro_lag(const fp_filter_config *c, double speed_mm_s, double rate_hz);

#ifdef __cplusplus
}
#endif
#endif
