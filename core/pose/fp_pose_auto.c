/* Hands that arrive: a live input's workspace estimated as it runs (fp_pose_auto.h). */
#include "fp_pose_auto.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NBINS ((int)(2.0 * FP_POSE_AUTO_SPAN_MM / FP_POSE_AUTO_BIN_MM))
/* the ring: a window of both hands at the highest sample rate */
#define CAPACITY ((size_t)(FP_POSE_AUTO_WINDOW_S * FP_POSE_AUTO_RATE_HZ) * FP_HANDS)
#define PERIOD_NS ((int64_t)(1e9 / FP_POSE_AUTO_RATE_HZ))
#define BASES (1 + FP_FINGERS) /* a hand's base: its palm centre and each finger's first joint */

/* (NBINS <= 65536: a bin index fits in uint16_t; asserted at create, as clang does not
 * take a floating-point expression in _Static_assert) */

typedef struct sample {
    int64_t t_ns;
    uint16_t bin[FP_HAND_JOINTS][3];
    uint8_t hand;                  /* FP_HAND_LEFT or FP_HAND_RIGHT */
} sample;

struct fp_pose_auto {
    sample *ring;                  /* CAPACITY samples, oldest at head */
    size_t head, count;
    uint32_t *hist;                /* 3 x NBINS counts of joint coordinates */
    uint32_t *hand_hist;           /* FP_HANDS x 3 x NBINS: the same per hand */
    size_t hand_count[FP_HANDS];   /* samples kept per hand */
    int64_t last_kept[FP_HANDS];   /* each hand's last sample time */
    bool have_kept[FP_HANDS];
    bool dirty;                    /* samples came (or went) since the last refit */
    bool fitted;
    int64_t fit_t;                 /* the newest sample's time at the last refit */
    unsigned long refits;
    float first[FP_HANDS][FP_FINGERS][3]; /* each hand's fingertips in its first sample, mm */
    bool have_first[FP_HANDS];
    int beyond[FP_HANDS];          /* samples in a row with a fingertip FP_POSE_STILL_MM off */
    bool moved;                    /* a hand moved (FP_POSE_STILL_MM): not still any more */
    float base[FP_HANDS][BASES][3]; /* each hand's palm and finger bases in its first sample, mm */
    int base_beyond[FP_HANDS];     /* samples in a row with one of them FP_POSE_STILL_MM off */
    bool shifted;                  /* a hand's base moved (FP_POSE_STILL_MM): not held in place */
    int64_t first_t, newest_t;     /* the first sample's time and the newest's (any hand) */
    bool have_any;
    bool hovered;                  /* the last refit placed them hovering */
};

int fp_pose_auto_create(fp_pose_auto **out)
{
    *out = NULL;
    assert(NBINS <= 65536); /* bins fit in uint16_t */
    fp_pose_auto *a = calloc(1, sizeof *a);
    if (!a) return -ENOMEM;
    a->ring = malloc(CAPACITY * sizeof *a->ring);
    a->hist = calloc(3 * (size_t)NBINS, sizeof *a->hist);
    a->hand_hist = calloc(FP_HANDS * 3 * (size_t)NBINS, sizeof *a->hand_hist);
    if (!a->ring || !a->hist || !a->hand_hist) {
        fp_pose_auto_destroy(&a);
        return -ENOMEM;
    }
    *out = a;
    return 0;
}

void fp_pose_auto_destroy(fp_pose_auto **a)
{
    if (!a || !*a) return;
    free((*a)->ring);
    free((*a)->hist);
    free((*a)->hand_hist);
    free(*a);
    *a = NULL;
}

static uint16_t bin_of(float mm)
{
    double b = floor(((double)mm + FP_POSE_AUTO_SPAN_MM) / FP_POSE_AUTO_BIN_MM);
    return (uint16_t)(b < 0 ? 0 : b > NBINS - 1 ? NBINS - 1 : b);
}

static void count_sample(fp_pose_auto *a, const sample *s, uint32_t sign)
{
    uint32_t *hh = a->hand_hist + (size_t)s->hand * 3 * NBINS;
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++) {
            a->hist[(size_t)k * NBINS + s->bin[j][k]] += sign; /* -1u: wraps back */
            hh[(size_t)k * NBINS + s->bin[j][k]] += sign;
        }
    a->hand_count[s->hand] += sign == 1 ? 1 : (size_t)-1;
}

static void drop_oldest(fp_pose_auto *a)
{
    count_sample(a, &a->ring[a->head], (uint32_t)-1);
    a->head = (a->head + 1) % CAPACITY;
    a->count--;
    a->dirty = true;
}

/* joint b of a hand's base (BASES): the palm centre, then each finger's first joint */
static int base_joint(int b) { return b ? FP_JOINT(b - 1, 0) : FP_JOINT_PALM; }

/* Whether some of the n points p lies FP_POSE_STILL_MM or more (on an axis) from ref. */
static bool off_by(const float (*ref)[3], const float (*mm)[3], const int *joint, int n)
{
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            if (fabs((double)mm[joint[i]][k] - ref[i][k]) >= FP_POSE_STILL_MM) return true;
    return false;
}

/* Stillness (FP_POSE_STILL_MM): hand h's fingertips in a kept sample against its first; and
 * its base (palm and finger bases) against its first, whatever the fingertips do. */
static void note_motion(fp_pose_auto *a, int h, const float (*mm)[3])
{
    int tips[FP_FINGERS], bases[BASES];
    for (int f = 0; f < FP_FINGERS; f++) tips[f] = FP_JOINT_TIP(f);
    for (int b = 0; b < BASES; b++) bases[b] = base_joint(b);
    if (!a->have_first[h]) {
        for (int f = 0; f < FP_FINGERS; f++) memcpy(a->first[h][f], mm[tips[f]], sizeof a->first[h][f]);
        for (int b = 0; b < BASES; b++) memcpy(a->base[h][b], mm[bases[b]], sizeof a->base[h][b]);
        a->have_first[h] = true;
        return;
    }
    if (!a->shifted) {
        a->base_beyond[h] = off_by((const float(*)[3])a->base[h], mm, bases, BASES) ? a->base_beyond[h] + 1 : 0;
        if (a->base_beyond[h] >= 2) a->shifted = true;
    }
    if (a->moved) return;
    a->beyond[h] = off_by((const float(*)[3])a->first[h], mm, tips, FP_FINGERS) ? a->beyond[h] + 1 : 0;
    if (a->beyond[h] >= 2) {
        a->moved = true;
        a->dirty = true; /* (the next refit drops the hover) */
    }
}

bool fp_pose_auto_still(const fp_pose_auto *a) { return !a->moved; }

bool fp_pose_auto_held(const fp_pose_auto *a)
{
    return a->moved && !a->shifted && a->have_any && a->newest_t - a->first_t >= (int64_t)(FP_POSE_HELD_S * 1e9);
}

void fp_pose_auto_take(fp_pose_auto *a, const fp_event *ev)
{
    int h = ev->header.hand;
    if (ev->header.type != FP_EVENT_JOINT_POSITIONS || (h != FP_HAND_LEFT && h != FP_HAND_RIGHT)) return;
    int64_t t = ev->header.time_ns;
    if (a->have_kept[h] && t >= a->last_kept[h] && t - a->last_kept[h] < PERIOD_NS) return;
    sample s;
    s.t_ns = t;
    s.hand = (uint8_t)h;
    for (int j = 0; j < FP_HAND_JOINTS; j++)
        for (int k = 0; k < 3; k++) {
            float v = ev->positions.mm[j][k];
            if (!isfinite(v)) return;
            s.bin[j][k] = bin_of(v);
        }
    a->last_kept[h] = t;
    a->have_kept[h] = true;
    if (!a->have_any) a->first_t = t;
    a->newest_t = t;
    a->have_any = true;
    note_motion(a, h, ev->positions.mm);
    /* the window, by the newest sample's time (a clock gone backwards drops nothing: the
     * ring's capacity still bounds it) */
    while (a->count && a->ring[a->head].t_ns < t - (int64_t)(FP_POSE_AUTO_WINDOW_S * 1e9)) drop_oldest(a);
    if (a->count == CAPACITY) drop_oldest(a);
    a->ring[(a->head + a->count) % CAPACITY] = s;
    a->count++;
    count_sample(a, &s, 1);
    a->dirty = true;
}

size_t fp_pose_auto_samples(const fp_pose_auto *a) { return a->count; }

/* the middle of bin b, mm */
static float bin_mm(uint16_t b) { return (float)(-FP_POSE_AUTO_SPAN_MM + (b + 0.5) * FP_POSE_AUTO_BIN_MM); }

void fp_pose_auto_each(const fp_pose_auto *a, void (*fn)(void *ctx, int hand, const float (*mm)[3]), void *ctx)
{
    float mm[FP_HAND_JOINTS][3];
    for (size_t i = 0; i < a->count; i++) {
        const sample *s = &a->ring[(a->head + i) % CAPACITY];
        for (int j = 0; j < FP_HAND_JOINTS; j++)
            for (int k = 0; k < 3; k++) mm[j][k] = bin_mm(s->bin[j][k]);
        fn(ctx, s->hand, (const float(*)[3])mm);
    }
}
unsigned long fp_pose_auto_refits(const fp_pose_auto *a) { return a->refits; }

/* The coordinate of 0-based rank r in axis k's histogram: the middle of its bin. */
static float rank_in(const uint32_t *hist, int k, size_t r)
{
    const uint32_t *hk = hist + (size_t)k * NBINS;
    size_t cum = 0;
    int b = 0;
    for (; b < NBINS - 1; b++) {
        cum += hk[b];
        if (cum > r) break;
    }
    return bin_mm((uint16_t)b);
}

/* The 2nd and 98th percentiles on axis k of a histogram of `samples` samples' joints (mm), by
 * the replay's ranks (input-replay's workspace: v[(size_t)(0.02 (m - 1) + 0.5)]) */
static void percentiles(const uint32_t *hist, size_t samples, int k, float *lo_mm, float *hi_mm)
{
    size_t m = samples * FP_HAND_JOINTS;
    *lo_mm = rank_in(hist, k, (size_t)(0.02 * (double)(m - 1) + 0.5));
    *hi_mm = rank_in(hist, k, (size_t)(0.98 * (double)(m - 1) + 0.5));
}

/* hand h's 2nd-98th percentile centre on axis k (mm) */
static double hand_centre(const fp_pose_auto *a, int h, int k)
{
    float lo, hi;
    percentiles(a->hand_hist + (size_t)h * 3 * NBINS, a->hand_count[h], k, &lo, &hi);
    return 0.5 * ((double)lo + hi);
}

bool fp_pose_auto_box(const fp_pose_auto *a, float ws_min[3], float ws_max[3])
{
    if (!a->count) return false;
    for (int k = 0; k < 3; k++) percentiles(a->hist, a->count, k, &ws_min[k], &ws_max[k]);
    return true;
}

bool fp_pose_auto_refit(fp_pose_auto *a, fp_pose_state *p, bool engaged, double mm_per_unit,
                        const float head_min[3], const float head_max[3], double hover)
{
    assert(hover >= 0);
    if (!a->count || !a->dirty || engaged) return false;
    int64_t newest = a->ring[(a->head + a->count - 1) % CAPACITY].t_ns;
    int64_t oldest = a->ring[a->head].t_ns;
    bool settling = newest - oldest < (int64_t)(FP_POSE_AUTO_SETTLE_S * 1e9);
    if (a->fitted && !settling && !(a->hovered && a->moved) && newest >= a->fit_t &&
        newest - a->fit_t < (int64_t)(FP_POSE_AUTO_REFIT_S * 1e9))
        return false; /* (hands that hovered and moved are placed at once) */
    float wmin[3], wmax[3];
    fp_pose_auto_box(a, wmin, wmax);
    /* two hands: centred between their own centres (sideways and up), not on the box of both
     * (fp_pose_auto.h) */
    if (a->hand_count[FP_HAND_LEFT] && a->hand_count[FP_HAND_RIGHT])
        for (int k = 0; k < 2; k++) {
            double c = 0.5 * (hand_centre(a, FP_HAND_LEFT, k) + hand_centre(a, FP_HAND_RIGHT, k));
            double sh = c - 0.5 * ((double)wmin[k] + wmax[k]);
            wmin[k] += (float)sh;
            wmax[k] += (float)sh;
        }
    fp_calibration old = p->calib, c;
    fp_pose_fit_workspace(&c, mm_per_unit, wmin, wmax, head_min, head_max);
    memcpy(c.face, old.face, sizeof c.face); /* (the fit is in the face's frame) */
    a->hovered = !a->moved && hover > 0;
    if (a->hovered) c.offset[2] += hover; /* still hands hover (FP_POSE_STILL_MM) */
    fp_pose_recalibrate(p, &c); /* (gloves without a wrist pose keep their place) */
    a->fitted = true;
    a->dirty = false;
    a->fit_t = newest;
    a->refits++;
    return true;
}
