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
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* The frames decoded so far. */
typedef struct ltc_seen {
    struct seen { fp_timecode tc; int64_t start, end; } *f;
    size_t n, cap;
    unsigned max_frame;     /* the largest frame field: base - 1 after a second */
    bool drop;              /* a frame had the drop-frame flag */
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
        if (fx.ltc.dfbit) s->drop = true;
    }
    return 0;
}

/* The rate from the frames (max frame field, drop flag, spacing), each frame's number, the
 * jumps. Returns 0 or -EBADMSG with err. */
static int settle(ltc_seen *s, int sample_rate, const char *what, fp_ltc_info *info, uint64_t *numbers,
                  char *err, size_t errlen)
{
    if (s->n < 2 || s->max_frame < 20)
        return fp_errorf(err, errlen, -EBADMSG, "%s: %s (less than a second of LTC decoded)", what,
                         s->n ? "too little LTC" : "no LTC");
    unsigned base = s->max_frame + 1;
    fp_take_rate rate;
    if (base == 24) rate = (fp_take_rate){24, 1};
    else if (base == 25) rate = (fp_take_rate){25, 1};
    else if (base == 30 && s->drop) rate = (fp_take_rate){30000, 1001};
    else if (base == 30) { /* 29.97 non-drop or 30: by the frames' spacing */
        double period = (double)(s->f[s->n - 1].start - s->f[0].start) / (double)(s->n - 1);
        double p30 = sample_rate / 30.0, p2997 = sample_rate * 1001.0 / 30000.0;
        rate = fabs(period - p2997) < fabs(period - p30) ? (fp_take_rate){30000, 1001} : (fp_take_rate){30, 1};
    } else {
        return fp_errorf(err, errlen, -EBADMSG, "%s: LTC frames count to %u a second (24, 25 or 30 expected)",
                         what, base);
    }
    info->rate = rate;
    info->frames = s->n;
    info->jumps = 0;
    info->sample_rate = sample_rate;
    for (size_t i = 0; i < s->n; i++) {
        fp_timecode tc = s->f[i].tc;
        tc.drop = s->drop;
        if (fp_timecode_to_frames(&tc, rate, &numbers[i]))
            return fp_errorf(err, errlen, -EBADMSG, "%s: LTC frame %zu holds no valid timecode", what, i);
        if (i && numbers[i] != numbers[i - 1] + 1) info->jumps++;
    }
    return 0;
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
    LTCDecoder *d = ltc_decoder_create(si.samplerate / 25, 64);
    float *block = malloc(1024 * (size_t)si.channels * sizeof *block), mono[1024];
    ltc_seen s = {0};
    int rc = d && block ? 0 : fp_errorf(err, errlen, -ENOMEM, "out of memory");
    ltc_off_t pos = 0;
    sf_count_t got;
    while (!rc && (got = sf_readf_float(sf, block, 1024)) > 0) {
        for (sf_count_t k = 0; k < got; k++) mono[k] = block[k * si.channels];
        ltc_decoder_write_float(d, mono, (size_t)got, pos);
        pos += got;
        if (collect(d, &s)) rc = fp_errorf(err, errlen, -ENOMEM, "out of memory");
    }
    sf_close(sf);
    free(block);
    if (d) ltc_decoder_free(d);
    uint64_t *numbers = rc ? NULL : malloc((s.n ? s.n : 1) * sizeof *numbers);
    if (!rc && !numbers) rc = fp_errorf(err, errlen, -ENOMEM, "out of memory");
    if (!rc) rc = settle(&s, si.samplerate, path, info, numbers, err, errlen);
    if (!rc) { /* back from the first frame to sample 0, a whole number of frame periods */
        double period = (double)si.samplerate * info->rate.den / info->rate.num;
        uint64_t back = (uint64_t)llround((double)s.f[0].start / period);
        uint64_t day = 0;
        fp_timecode_to_frames(&(fp_timecode){23, 59, 59, (uint32_t)(fp_timecode_base(info->rate) - 1), s.drop},
                              info->rate, &day);
        day += 1;
        uint64_t n0 = (numbers[0] + day - back % day) % day;
        fp_timecode_from_frames(n0, info->rate, s.drop, &info->first);
    }
    free(numbers);
    free(s.f);
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
    if (!rc) rc = settle(&s, sr, device, info, numbers, err, errlen);
    if (!rc) { /* the next frame begins where the last decoded one ended */
        const struct seen *last = &s.f[s.n - 1];
        fp_timecode_from_frames(numbers[s.n - 1] + 1, info->rate, s.drop, &info->first);
        info->at_ns = read_end - (int64_t)((double)(pos - last->end) * 1e9 / sr);
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
