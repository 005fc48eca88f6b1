/* audio_in.c: a microphone recorded beside a take on the performance's clock (fp_audio.h,
 * "inputs"): a PortAudio input device, or "file:X.wav", a sound file heard in real time (an
 * emulated microphone for machines without one and for tests). A thread captures blocks
 * into a ring of the last seconds, each sample at a known host time; a recording writes the
 * samples from its start time to its end time into a WAV (32-bit float), written in place with
 * its header kept up to date after every write, as a take is: a run killed mid-take leaves a
 * WAV that reads up to its last write. */
#define _GNU_SOURCE
#include "fp_audio.h"
#include "audio_internal.h"

#include "fp_clock.h"
#include "fp_error.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <portaudio.h>
#include <pthread.h>
#include <sndfile.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

#define RING_SECONDS 10      /* samples kept for a recording that starts in the past */
#define BLOCKS_PER_SECOND 100

struct fp_audio_in {
    pthread_t thread;
    bool thread_up;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool stop;                /* asks the thread to end */
    int rate, channels;
    int64_t start_ns;         /* host time (CLOCK_MONOTONIC) of sample 0 */
    uint64_t captured;        /* sample frames captured so far */
    float *ring;              /* the last ring_frames frames: frame i at (i % ring_frames) */
    uint64_t ring_frames;
    bool device_error;        /* the device stopped delivering (capture goes on as silence) */
    /* the recording */
    bool rec;
    SNDFILE *sf;
    char rec_path[4096];      /* the WAV being written */
    uint64_t rec_next;        /* the next frame to write */
    uint64_t rec_end;         /* frames from here are not written (UINT64_MAX: open) */
    uint64_t rec_written;
    int64_t rec_first;        /* the frame at the recording's start (may be negative) */
    int rec_error;
    char rec_err[600];
    /* the source */
    fp_soundtrack track;      /* file: (an emulated microphone) */
    PaStream *stream;         /* a device */
    bool pa_up;
};

static bool is_file(const char *spec) { return !strncmp(spec, "file:", 5); }

int fp_audio_in_check(const char *spec, char *err, size_t errlen)
{
    if (!spec || !*spec)
        return fp_errorf(err, errlen, -EINVAL, "empty audio input (file:IN.wav or a device)");
    if (is_file(spec)) {
        fp_soundtrack t;
        int rc = fp_soundtrack_load(spec + 5, &t, err, errlen);
        fp_soundtrack_free(&t);
        return rc;
    }
    if (fp_audio_pa_init())
        return fp_errorf(err, errlen, -ENODEV, "audio input '%s': no sound system (PortAudio)", spec);
    PaDeviceIndex d = fp_audio_find_device(spec, true);
    Pa_Terminate();
    if (d == paNoDevice)
        return fp_errorf(err, errlen, -ENODEV, "no audio input device '%s' (file:IN.wav needs none)",
                         spec);
    return 0;
}

static void rec_fail(fp_audio_in *in);

/* Append n frames (the mutex held): into the ring, and into the recording where it wants
 * them. */
static void append(fp_audio_in *in, const float *frames, size_t n)
{
    const size_t ch = (size_t)in->channels;
    for (size_t k = 0; k < n; k++)
        memcpy(in->ring + (size_t)((in->captured + k) % in->ring_frames) * ch, frames + k * ch,
               ch * sizeof(float));
    uint64_t a = in->captured, b = in->captured + n;
    in->captured = b;
    if (in->rec && !in->rec_error) {
        uint64_t from = in->rec_next > a ? in->rec_next : a, to = in->rec_end < b ? in->rec_end : b;
        if (to > from) {
            sf_count_t w = sf_writef_float(in->sf, frames + (size_t)(from - a) * ch, (sf_count_t)(to - from));
            if (w != (sf_count_t)(to - from)) {
                rec_fail(in);
            }
            in->rec_next = to;
            in->rec_written += to - from;
        }
    }
    pthread_cond_broadcast(&in->cv);
}

/* A write to the recording failed (the mutex held). */
static void rec_fail(fp_audio_in *in)
{
    in->rec_error = -EIO;
    snprintf(in->rec_err, sizeof in->rec_err, "%.400s: %.150s", in->rec_path, sf_strerror(in->sf));
}

static void sleep_until(int64_t t_ns)
{
    struct timespec ts = {(time_t)(t_ns / 1000000000LL), (long)(t_ns % 1000000000LL)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
}

/* The capture thread: a block at a time, each when its last sample has been heard (a file)
 * or as the device delivers it. */
static void *capture(void *arg)
{
    fp_audio_in *in = arg;
    const size_t block = (size_t)(in->rate / BLOCKS_PER_SECOND > 0 ? in->rate / BLOCKS_PER_SECOND : 1);
    const size_t ch = (size_t)in->channels;
    float *buf = calloc(block * ch, sizeof *buf);
    for (bool first = true; buf;) {
        pthread_mutex_lock(&in->mu);
        bool stop = in->stop;
        uint64_t at = in->captured;
        pthread_mutex_unlock(&in->mu);
        if (stop) break;
        if (in->stream && !in->device_error) {
            PaError e = Pa_ReadStream(in->stream, buf, (unsigned long)block);
            if (e != paNoError && e != paInputOverflowed) {
                pthread_mutex_lock(&in->mu);
                in->device_error = true; /* silence from here, on the host clock */
                pthread_mutex_unlock(&in->mu);
                continue;
            }
            if (first) { /* sample 0 was heard a block and the input latency ago */
                const PaStreamInfo *si = Pa_GetStreamInfo(in->stream);
                pthread_mutex_lock(&in->mu);
                in->start_ns = fp_now_ns() - (int64_t)(1e9 * ((double)block / in->rate + (si ? si->inputLatency : 0)));
                pthread_mutex_unlock(&in->mu);
                first = false;
            }
        } else {
            sleep_until(in->start_ns + (int64_t)llround((double)(at + block) * 1e9 / in->rate));
            for (size_t k = 0; k < block; k++) {
                uint64_t src = at + k;
                if (src < in->track.frames) memcpy(buf + k * ch, in->track.samples + src * ch, ch * sizeof(float));
                else memset(buf + k * ch, 0, ch * sizeof(float));
            }
        }
        pthread_mutex_lock(&in->mu);
        append(in, buf, block);
        pthread_mutex_unlock(&in->mu);
    }
    free(buf);
    return NULL;
}

static int open_device(fp_audio_in *in, const char *spec, char *err, size_t errlen)
{
    if (fp_audio_pa_init())
        return fp_errorf(err, errlen, -ENODEV, "audio input '%s': no sound system (PortAudio)", spec);
    in->pa_up = true;
    PaDeviceIndex d = fp_audio_find_device(spec, true);
    if (d == paNoDevice) return fp_errorf(err, errlen, -ENODEV, "no audio input device '%s'", spec);
    const PaDeviceInfo *di = Pa_GetDeviceInfo(d);
    in->channels = 1;
    in->rate = di->defaultSampleRate > 0 ? (int)lround(di->defaultSampleRate) : 48000;
    PaStreamParameters p = {.device = d, .channelCount = 1, .sampleFormat = paFloat32,
                            .suggestedLatency = di->defaultLowInputLatency};
    PaError e = Pa_OpenStream(&in->stream, &p, NULL, in->rate, paFramesPerBufferUnspecified, paClipOff,
                              NULL, NULL);
    if (e == paNoError) e = Pa_StartStream(in->stream);
    if (e != paNoError) return fp_errorf(err, errlen, -EIO, "audio input '%s': %s", spec, Pa_GetErrorText(e));
    return 0;
}

int fp_audio_in_open(const char *spec, fp_audio_in **out, char *err, size_t errlen)
{
    *out = NULL;
    int rc = fp_audio_in_check(spec, err, errlen);
    if (rc) return rc;
    fp_audio_in *in = calloc(1, sizeof *in);
    if (!in) return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    pthread_mutex_init(&in->mu, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&in->cv, &ca);
    pthread_condattr_destroy(&ca);
    if (is_file(spec)) {
        rc = fp_soundtrack_load(spec + 5, &in->track, err, errlen);
        in->rate = in->track.rate;
        in->channels = in->track.channels;
    } else {
        rc = open_device(in, spec, err, errlen);
    }
    if (!rc) {
        in->ring_frames = (uint64_t)in->rate * RING_SECONDS;
        if (!(in->ring = calloc((size_t)in->ring_frames * (size_t)in->channels, sizeof(float))))
            rc = fp_errorf(err, errlen, -ENOMEM, "out of memory");
    }
    in->start_ns = fp_now_ns();
    if (!rc && pthread_create(&in->thread, NULL, capture, in))
        rc = fp_errorf(err, errlen, -EAGAIN, "audio input '%s': no thread", spec);
    in->thread_up = !rc;
    if (rc) {
        fp_audio_in_close(&in);
        return rc;
    }
    *out = in;
    return 0;
}

int fp_audio_in_rate(const fp_audio_in *in) { return in ? in->rate : 0; }

int fp_audio_in_channels(const fp_audio_in *in) { return in ? in->channels : 0; }

/* The frame index at host time t (may be negative: before the capture began). */
static int64_t frame_at(const fp_audio_in *in, int64_t t_ns)
{
    return (int64_t)llround((double)(t_ns - in->start_ns) * in->rate / 1e9);
}

/* n frames of silence into the recording (the mutex held). */
static int write_silence(fp_audio_in *in, uint64_t n)
{
    float zero[256 * 8] = {0};
    const uint64_t per = sizeof zero / sizeof zero[0] / (uint64_t)in->channels;
    while (n && !in->rec_error) {
        uint64_t k = n < per ? n : per;
        if (sf_writef_float(in->sf, zero, (sf_count_t)k) != (sf_count_t)k) {
            rec_fail(in);
        }
        in->rec_written += k;
        n -= k;
    }
    return in->rec_error;
}

int fp_audio_in_record(fp_audio_in *in, const char *path, int64_t t0_ns, char *err, size_t errlen)
{
    if (!in || !path) return fp_errorf(err, errlen, -EINVAL, "no audio input");
    pthread_mutex_lock(&in->mu);
    int rc = 0;
    if (in->rec) {
        rc = fp_errorf(err, errlen, -EBUSY, "the audio input is recording already");
        goto out;
    }
    /* in place, not through a temporary renamed at the end: a killed run keeps what it heard */
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) {
        rc = fp_errorf(err, errlen, -errno, "%s: %s", path, strerror(errno));
        goto out;
    }
    snprintf(in->rec_path, sizeof in->rec_path, "%s", path);
    SF_INFO info = {.samplerate = in->rate, .channels = in->channels, .format = SF_FORMAT_WAV | SF_FORMAT_FLOAT};
    if (!(in->sf = sf_open_fd(fd, SFM_WRITE, &info, 1))) { /* (closes fd, also on failure) */
        rc = fp_errorf(err, errlen, -EIO, "%s: %s", path, sf_strerror(NULL));
        unlink(path);
        goto out;
    }
    sf_command(in->sf, SFC_SET_UPDATE_HEADER_AUTO, NULL, SF_TRUE); /* the header after every write */
    in->rec = true;
    in->rec_error = 0;
    in->rec_written = 0;
    in->rec_end = UINT64_MAX;
    int64_t first = frame_at(in, t0_ns);
    in->rec_first = first;
    uint64_t oldest = in->captured > in->ring_frames ? in->captured - in->ring_frames : 0;
    /* silence before the capture began (or past the ring: never, RING_SECONDS back) */
    if (first < (int64_t)oldest) write_silence(in, (uint64_t)((int64_t)oldest - first));
    in->rec_next = first < (int64_t)oldest ? oldest : (uint64_t)first;
    const size_t ch = (size_t)in->channels;
    while (in->rec_next < in->captured && !in->rec_error) { /* what the ring holds already */
        size_t at = (size_t)(in->rec_next % in->ring_frames);
        uint64_t n = in->captured - in->rec_next;
        if (n > in->ring_frames - at) n = in->ring_frames - at;
        if (sf_writef_float(in->sf, in->ring + at * ch, (sf_count_t)n) != (sf_count_t)n) {
            rec_fail(in);
        }
        in->rec_next += n;
        in->rec_written += n;
    }
out:
    pthread_mutex_unlock(&in->mu);
    return rc;
}

int fp_audio_in_record_stop(fp_audio_in *in, int64_t end_ns, uint64_t *frames, char *err,
                            size_t errlen)
{
    if (frames) *frames = 0;
    if (!in) return 0;
    pthread_mutex_lock(&in->mu);
    if (!in->rec) {
        pthread_mutex_unlock(&in->mu);
        return 0;
    }
    int64_t end = frame_at(in, end_ns);
    const uint64_t want = end > in->rec_first ? (uint64_t)(end - in->rec_first) : 0; /* the file's */
    if (in->rec_written > want && !in->rec_error) { /* the thread wrote past the end already */
        sf_count_t keep = (sf_count_t)want;
        if (sf_command(in->sf, SFC_FILE_TRUNCATE, &keep, sizeof keep)) rec_fail(in);
        else in->rec_written = want;
    }
    in->rec_end = end > (int64_t)in->rec_next ? (uint64_t)end : in->rec_next;
    /* wait for the device to deliver up to the end (a block and its latency; 2 s at most) */
    struct timespec until;
    clock_gettime(CLOCK_MONOTONIC, &until);
    until.tv_sec += 2;
    while (in->captured < in->rec_end && !in->device_error &&
           pthread_cond_timedwait(&in->cv, &in->mu, &until) != ETIMEDOUT) {
    }
    if (in->rec_next < in->rec_end) write_silence(in, in->rec_end - in->rec_next); /* (a device lost) */
    in->rec_next = in->rec_end;
    int rc = in->rec_error;
    if (rc) fp_errorf(err, errlen, rc, "%s", in->rec_err);
    sf_write_sync(in->sf);
    if (sf_close(in->sf) && !rc) rc = fp_errorf(err, errlen, -EIO, "%s: closing the WAV failed", in->rec_path);
    in->sf = NULL;
    if (rc) unlink(in->rec_path); /* (a write failed: no half file beside the take) */
    if (frames && !rc) *frames = in->rec_written;
    in->rec = false;
    pthread_mutex_unlock(&in->mu);
    return rc;
}

void fp_audio_in_close(fp_audio_in **inp)
{
    fp_audio_in *in = inp ? *inp : NULL;
    if (!in) return;
    if (in->thread_up) {
        pthread_mutex_lock(&in->mu);
        in->stop = true;
        pthread_mutex_unlock(&in->mu);
        pthread_join(in->thread, NULL);
    }
    if (in->sf) sf_close(in->sf); /* a recording in progress ends where it got (its header up to date) */
    if (in->stream) {
        Pa_AbortStream(in->stream);
        Pa_CloseStream(in->stream);
    }
    if (in->pa_up) Pa_Terminate();
    fp_soundtrack_free(&in->track);
    free(in->ring);
    pthread_cond_destroy(&in->cv);
    pthread_mutex_destroy(&in->mu);
    free(in);
    *inp = NULL;
}
