/* ltc.c: SMPTE linear timecode decoded with libltc, from a sound file or a PortAudio input
 * device (fp_audio.h). */
#define _GNU_SOURCE
#include "fp_audio.h"

#include "fp_clock.h"
#include "fp_error.h"
#include "fp_file.h"

#include <errno.h>
#include <ltc.h>
#include <math.h>
#include <portaudio.h>
#include <sndfile.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* How far (in frame periods) a decoded frame's start may stray from where it lies: libltc's
 * off_start is within a few samples (-7 to +5 at 48 kHz in the encoder's own files). */
#define LTC_START_SLACK 0.05

/* The frames decoded so far. */
typedef struct ltc_seen {
    struct seen { fp_timecode tc; int64_t start, end; } *f;
    size_t n, cap;
    unsigned max_frame;     /* the largest frame field: base - 1 after a second */
    size_t drop_flags;      /* frames with the drop-frame flag set */
} ltc_seen;

/* Read every frame the decoder holds into s. Returns 0 or -ENOMEM. */
static int collect(LTCDecoder *d, ltc_seen *s)
{
    LTCFrameExt fx;
    while (ltc_decoder_read(d, &fx)) {
        if (s->n == s->cap) {
            size_t cap = s->cap ? 2 * s->cap : 256;
            struct seen *g = realloc(s->f, cap * sizeof *g);
            if (!g) return -ENOMEM;
            s->f = g;
            s->cap = cap;
        }
        SMPTETimecode t;
        ltc_frame_to_time(&t, &fx.ltc, 0);
        struct seen *e = &s->f[s->n++];
        e->tc = (fp_timecode){t.hours, t.mins, t.secs, t.frame, fx.ltc.dfbit != 0};
        e->start = fx.off_start;
        e->end = fx.off_end;
        if (t.frame > s->max_frame) s->max_frame = t.frame;
        if (fx.ltc.dfbit) s->drop_flags++;
    }
    return 0;
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* The LTC frame period in samples: the median spacing of consecutive frames (a frame lost
 * or misread moves single spacings, not the median). 0 when there is none. */
static double median_period(const ltc_seen *s)
{
    int64_t *d = malloc((s->n - 1) * sizeof *d);
    if (!d) return 0;
    for (size_t i = 0; i + 1 < s->n; i++) d[i] = s->f[i + 1].start - s->f[i].start;
    qsort(d, s->n - 1, sizeof *d, cmp_i64);
    double p = (double)d[(s->n - 1) / 2];
    free(d);
    return p;
}

/* The rate from the frames' spacing (the nearest of 24, 25 and 30 a second; at 30, 29.97
 * where most frames have the drop-frame flag, else 29.97 or 30 by the mean spacing), each
 * frame's number (UINT64_MAX where its fields are no timecode at that rate: misread), the
 * jumps, and in *n_ref the frame number at sample `ref`: the first frame (from_end: the last)
 * that three frames in a row confirm, carried back to the frame in progress at `ref`. A misread frame, the
 * first one included, moves neither the rate nor the timecode. Returns 0 or -EBADMSG with err. */
static int settle(ltc_seen *s, int sample_rate, const char *what, int64_t ref, bool from_end,
                  fp_ltc_info *info, uint64_t *numbers, uint64_t *n_ref, char *err, size_t errlen)
{
    if (s->n < 2 || s->max_frame < 20)
        return fp_errorf(err, errlen, -EBADMSG, "%s: %s (less than a second of LTC decoded)", what,
                         s->n ? "too little LTC" : "no LTC");
    double period = median_period(s);
    if (!(period > 0)) return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    const double per_s = sample_rate / period;
    const bool flagged = 2 * s->drop_flags > s->n;
    fp_take_rate rate;
    if (fabs(per_s - 24) < 0.5) rate = (fp_take_rate){24, 1};
    else if (fabs(per_s - 25) < 0.5) rate = (fp_take_rate){25, 1};
    else if (fabs(per_s - 30) < 0.5 && flagged) rate = (fp_take_rate){30000, 1001};
    else if (fabs(per_s - 30) < 0.5) { /* 29.97 non-drop or 30: by the frames' mean spacing */
        double span = (double)(s->f[s->n - 1].start - s->f[0].start);
        double mean = span / fmax(1.0, round(span / period));
        double p30 = sample_rate / 30.0, p2997 = sample_rate * 1001.0 / 30000.0;
        rate = fabs(mean - p2997) < fabs(mean - p30) ? (fp_take_rate){30000, 1001} : (fp_take_rate){30, 1};
    } else {
        return fp_errorf(err, errlen, -EBADMSG, "%s: LTC frames come %.2f a second (24, 25 or 30 expected)",
                         what, per_s);
    }
    info->rate = rate;
    info->frames = s->n;
    info->jumps = 0;
    info->sample_rate = sample_rate;
    const bool drop = flagged && fp_timecode_drop_allowed(rate);
    uint64_t day = 0;
    fp_timecode_to_frames(&(fp_timecode){23, 59, 59, fp_timecode_base(rate) - 1, drop}, rate, &day);
    day += 1;
    const double exact = (double)sample_rate * rate.den / rate.num;
    for (size_t i = 0; i < s->n; i++) {
        fp_timecode tc = s->f[i].tc;
        tc.drop = drop;
        if (fp_timecode_to_frames(&tc, rate, &numbers[i])) numbers[i] = UINT64_MAX;
        if (i && (numbers[i] == UINT64_MAX || numbers[i] != (numbers[i - 1] + 1) % day)) info->jumps++;
    }
    /* the anchor: the first (from_end: the last) frame that starts three in a row, so that a
     * misread frame is passed over and, after a jump, the run at `ref` counts; none: the
     * first (last) valid frame */
    size_t anchor = SIZE_MAX, any = SIZE_MAX;
    for (size_t k = 0; k < s->n && anchor == SIZE_MAX; k++) {
        const size_t i = from_end ? s->n - 1 - k : k;
        if (numbers[i] == UINT64_MAX) continue;
        if (any == SIZE_MAX) any = i;
        const size_t lo = from_end ? (i >= 2 ? i - 2 : SIZE_MAX) : i;
        if (lo != SIZE_MAX && lo + 2 < s->n && numbers[lo] != UINT64_MAX &&
            numbers[lo + 1] == (numbers[lo] + 1) % day && numbers[lo + 2] == (numbers[lo] + 2) % day)
            anchor = i;
    }
    if (anchor == SIZE_MAX) anchor = any;
    if (anchor == SIZE_MAX)
        return fp_errorf(err, errlen, -EBADMSG, "%s: no LTC frame holds a valid timecode at %u/%u fps",
                         what, rate.num, rate.den);
    /* the frame in progress at `ref`: the anchor's number less the frame starts between ref
     * and the anchor's start, a start up to LTC_START_SLACK of a period after ref counting as
     * at ref (libltc places a frame's start within a few samples). Before, the nearest whole
     * period: a file whose first whole LTC frame began under half a frame in was said to start
     * at that frame, one ahead of the frame its first sample is in. */
    const double periods = (double)(s->f[anchor].start - ref) / exact;
    const int64_t back = (int64_t)ceil(periods - LTC_START_SLACK);
    *n_ref = (uint64_t)((((int64_t)numbers[anchor] - back) % (int64_t)day + (int64_t)day) % (int64_t)day);
    return 0;
}

/* Decode every channel of sf (one libltc decoder each) into seen[0..channels). Returns 0 or
 * -ENOMEM with err. */
static int decode_channels(SNDFILE *sf, const SF_INFO *si, ltc_seen *seen, char *err, size_t errlen)
{
    const size_t ch = (size_t)si->channels;
    LTCDecoder **d = calloc(ch, sizeof *d);
    float *block = malloc(1024 * ch * sizeof *block), mono[1024];
    int rc = d && block ? 0 : -ENOMEM;
    for (size_t c = 0; !rc && c < ch; c++)
        if (!(d[c] = ltc_decoder_create(si->samplerate / 25, 64))) rc = -ENOMEM;
    ltc_off_t pos = 0;
    sf_count_t got;
    while (!rc && (got = sf_readf_float(sf, block, 1024)) > 0) {
        for (size_t c = 0; !rc && c < ch; c++) {
            for (sf_count_t k = 0; k < got; k++) mono[k] = block[(size_t)k * ch + c];
            ltc_decoder_write_float(d[c], mono, (size_t)got, pos);
            rc = collect(d[c], &seen[c]);
        }
        pos += got;
    }
    for (size_t c = 0; d && c < ch; c++)
        if (d[c]) ltc_decoder_free(d[c]);
    free(d);
    free(block);
    return rc ? fp_errorf(err, errlen, -ENOMEM, "out of memory") : 0;
}

int fp_ltc_read_file(const char *path, fp_ltc_info *info, char *err, size_t errlen)
{
    memset(info, 0, sizeof *info);
    int fd = fp_file_open_regular(path);
    if (fd < 0) return fp_errorf(err, errlen, fd, "%s: %s", path, fp_file_error_text(fd));
    SF_INFO si;
    memset(&si, 0, sizeof si);
    SNDFILE *sf = sf_open_fd(fd, SFM_READ, &si, 1);
    if (!sf) return fp_errorf(err, errlen, -EBADMSG, "%s: not a sound file libsndfile reads", path);
    if (si.channels <= 0 || si.samplerate < 8000) {
        sf_close(sf);
        return fp_errorf(err, errlen, -EBADMSG, "%s: no samples, or under 8 kHz", path);
    }
    ltc_seen *seen = calloc((size_t)si.channels, sizeof *seen);
    int rc = seen ? decode_channels(sf, &si, seen, err, errlen) : fp_errorf(err, errlen, -ENOMEM, "out of memory");
    sf_close(sf);
    size_t best = 0; /* the channel with the most frames: LTC on any track of a recording */
    for (size_t c = 1; seen && c < (size_t)si.channels; c++)
        if (seen[c].n > seen[best].n) best = c;
    ltc_seen *s = seen ? &seen[best] : NULL;
    uint64_t *numbers = rc ? NULL : malloc((s->n ? s->n : 1) * sizeof *numbers);
    if (!rc && !numbers) rc = fp_errorf(err, errlen, -ENOMEM, "out of memory");
    uint64_t n0 = 0;
    if (!rc) rc = settle(s, si.samplerate, path, 0, false, info, numbers, &n0, err, errlen);
    if (!rc) {
        fp_timecode_from_frames(n0, info->rate, fp_timecode_drop_allowed(info->rate) && 2 * s->drop_flags > s->n,
                                &info->first);
        info->channel = (int)best + 1;
    }
    free(numbers);
    for (size_t c = 0; seen && c < (size_t)si.channels; c++) free(seen[c].f);
    free(seen);
    return rc;
}

int fp_ltc_listen(const char *device, double seconds, fp_ltc_info *info, char *err, size_t errlen)
{
    memset(info, 0, sizeof *info);
    if (fp_audio_pa_init())
        return fp_errorf(err, errlen, -ENODEV, "LTC device '%s': no sound system (PortAudio)", device);
    PaDeviceIndex dev = paNoDevice;
    if (!strcmp(device, "default")) {
        dev = Pa_GetDefaultInputDevice();
    } else {
        char *end;
        long idx = strtol(device, &end, 10);
        for (int i = 0; i < Pa_GetDeviceCount() && dev == paNoDevice; i++) {
            const PaDeviceInfo *di = Pa_GetDeviceInfo(i);
            if (di && di->maxInputChannels > 0 &&
                ((*device && !*end && idx == i) || (di->name && strcasestr(di->name, device))))
                dev = i;
        }
    }
    if (dev == paNoDevice) {
        Pa_Terminate();
        return fp_errorf(err, errlen, -ENODEV, "no audio input device '%s' for LTC", device);
    }
    const int sr = 48000;
    PaStreamParameters p = {.device = dev, .channelCount = 1, .sampleFormat = paFloat32,
                            .suggestedLatency = Pa_GetDeviceInfo(dev)->defaultLowInputLatency};
    PaStream *stream = NULL;
    PaError e = Pa_OpenStream(&stream, &p, NULL, sr, 1024, paClipOff, NULL, NULL);
    if (e == paNoError) e = Pa_StartStream(stream);
    int rc = e == paNoError ? 0 : fp_errorf(err, errlen, -EIO, "LTC device '%s': %s", device, Pa_GetErrorText(e));
    LTCDecoder *d = rc ? NULL : ltc_decoder_create(sr / 25, 64);
    ltc_seen s = {0};
    float buf[1024];
    ltc_off_t pos = 0;
    int64_t until = fp_now_ns() + (int64_t)(seconds * 1e9), read_end = 0;
    while (!rc && d && fp_now_ns() < until && s.n < 45) {
        e = Pa_ReadStream(stream, buf, 1024);
        read_end = fp_now_ns();
        if (e != paNoError && e != paInputOverflowed) {
            rc = fp_errorf(err, errlen, -EIO, "LTC device '%s': %s", device, Pa_GetErrorText(e));
            break;
        }
        ltc_decoder_write_float(d, buf, 1024, pos);
        pos += 1024;
        if (collect(d, &s)) rc = fp_errorf(err, errlen, -ENOMEM, "out of memory");
    }
    if (stream) {
        Pa_AbortStream(stream);
        Pa_CloseStream(stream);
    }
    Pa_Terminate();
    if (d) ltc_decoder_free(d);
    if (!rc && s.n < 45)
        rc = fp_errorf(err, errlen, -ETIMEDOUT, "LTC device '%s': no LTC heard in %.0f s", device, seconds);
    uint64_t *numbers = rc ? NULL : malloc(s.n * sizeof *numbers);
    if (!rc && !numbers) rc = fp_errorf(err, errlen, -ENOMEM, "out of memory");
    uint64_t n_last = 0;
    const struct seen *last = s.n ? &s.f[s.n - 1] : NULL;
    if (!rc) rc = settle(&s, sr, device, last->start, true, info, numbers, &n_last, err, errlen);
    if (!rc) { /* the next frame begins where the last decoded one ended */
        fp_timecode_from_frames(n_last + 1, info->rate, fp_timecode_drop_allowed(info->rate) && 2 * s.drop_flags > s.n,
                                &info->first);
        info->at_ns = read_end - (int64_t)((double)(pos - last->end) * 1e9 / sr);
        info->channel = 1;
    }
    free(numbers);
    free(s.f);
    return rc;
}

int fp_ltc_timecode_at(const fp_ltc_info *info, int64_t t_ns, fp_timecode *tc)
{
    uint64_t n0;
    int rc = fp_timecode_to_frames(&info->first, info->rate, &n0);
    if (rc) return rc;
    int64_t dt = t_ns - info->at_ns;
    uint64_t step = fp_take_frames_in(dt < 0 ? 0 : dt, info->rate);
    return fp_timecode_from_frames(n0 + step, info->rate, info->first.drop, tc);
}
