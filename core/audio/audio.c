/* audio.c: soundtracks (libsndfile), audio outputs (null, a WAV file, PortAudio devices) and
 * the player that delivers a soundtrack in step with a performance (fp_audio.h). */
#define _GNU_SOURCE
#include "fp_audio.h"
#include "audio_internal.h"

#include "fp_error.h"
#include "fp_file.h"

#include <errno.h>
#include <math.h>
#include <alsa/asoundlib.h>
#include <portaudio.h>
#include <sndfile.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- soundtracks ------------------------------------------------------------------------ */

int fp_soundtrack_load(const char *path, fp_soundtrack *out, char *err, size_t errlen)
{
    if (!path || !out) return fp_errorf(err, errlen, -EINVAL, "no soundtrack");
    memset(out, 0, sizeof *out);
    int fd = fp_file_open_regular(path);
    if (fd < 0) return fp_errorf(err, errlen, fd, "%s: %s", path, fp_file_error_text(fd));
    SF_INFO info;
    memset(&info, 0, sizeof info);
    SNDFILE *sf = sf_open_fd(fd, SFM_READ, &info, 1); /* (closes fd, also on failure) */
    if (!sf)
        return fp_errorf(err, errlen, -EBADMSG, "%s: not a sound file libsndfile reads (%s)", path,
                         sf_strerror(NULL));
    int rc = 0;
    if (info.frames <= 0 || info.channels <= 0 || info.samplerate <= 0)
        rc = fp_errorf(err, errlen, -EBADMSG, "%s: no samples", path);
    else if ((double)info.frames / info.samplerate > FP_SOUNDTRACK_MAX_SECONDS)
        rc = fp_errorf(err, errlen, -EFBIG, "%s: longer than %.0f s", path, FP_SOUNDTRACK_MAX_SECONDS);
    if (!rc) {
        size_t n = (size_t)info.frames * (size_t)info.channels;
        out->samples = malloc(n * sizeof *out->samples);
        if (!out->samples) rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", path);
    }
    if (!rc) {
        sf_count_t got = sf_readf_float(sf, out->samples, info.frames);
        if (got <= 0) rc = fp_errorf(err, errlen, -EBADMSG, "%s: unreadable samples (%s)", path, sf_strerror(sf));
        out->frames = got > 0 ? (uint64_t)got : 0;
        out->channels = info.channels;
        out->rate = info.samplerate;
        for (size_t i = 0; !rc && i < (size_t)out->frames * (size_t)info.channels; i++)
            if (!isfinite(out->samples[i])) /* (a float file's NaN or infinity: played, it is noise) */
                rc = fp_errorf(err, errlen, -EBADMSG, "%s: sample %zu of channel %zu (at %.3f s) is not a "
                               "finite number", path, i / (size_t)info.channels + 1,
                               i % (size_t)info.channels + 1,
                               (double)(i / (size_t)info.channels) / info.samplerate);
    }
    sf_close(sf);
    if (!rc) rc = fp_take_crc32_file(path, &out->crc32, err, errlen);
    if (rc) fp_soundtrack_free(out);
    return rc;
}

void fp_soundtrack_free(fp_soundtrack *st)
{
    if (!st) return;
    free(st->samples);
    memset(st, 0, sizeof *st);
}

/* ---- outputs ------------------------------------------------------------------------------ */

/* ALSA's own error lines (a machine without a card logs dozens while PortAudio probes):
 * kept off stderr, the project's libraries print nothing. */
static void alsa_quiet(const char *file, int line, const char *fn, int err, const char *fmt, ...)
{
    (void)file, (void)line, (void)fn, (void)err, (void)fmt;
}

int fp_audio_pa_init(void)
{
    snd_lib_error_set_handler(alsa_quiet);
    return Pa_Initialize() == paNoError ? 0 : -ENODEV;
}

typedef enum { OUT_NULL, OUT_FILE, OUT_DEVICE } out_kind;

struct fp_audio_out {
    out_kind kind;
    int channels, rate;
    uint64_t frames;
    fp_file_output file;   /* OUT_FILE: the temporary beside the target */
    SNDFILE *sf;
    PaStream *stream;      /* OUT_DEVICE */
    bool pa_up;            /* Pa_Initialize succeeded */
};

static bool ends_with(const char *s, const char *tail)
{
    size_t a = strlen(s), b = strlen(tail);
    return a >= b && !strcasecmp(s + a - b, tail);
}

int fp_audio_find_device(const char *spec, bool input)
{
    if (!strcmp(spec, "default")) return input ? Pa_GetDefaultInputDevice() : Pa_GetDefaultOutputDevice();
    int count = Pa_GetDeviceCount();
    char *end;
    long idx = strtol(spec, &end, 10);
    for (int i = 0; i < count; i++) {
        const PaDeviceInfo *d = Pa_GetDeviceInfo(i);
        if (!d || (input ? d->maxInputChannels : d->maxOutputChannels) <= 0) continue;
        if ((*spec && !*end && idx == i) || (d->name && strcasestr(d->name, spec))) return i;
    }
    return paNoDevice;
}

static int check_file(const char *path, bool force, char *err, size_t errlen)
{
    if (!*path) return fp_errorf(err, errlen, -EINVAL, "file: needs a path (file:OUT.wav)");
    if (!ends_with(path, ".wav")) return fp_errorf(err, errlen, -EINVAL, "%s: give a name ending in .wav", path);
    struct stat st;
    if (!force && lstat(path, &st) == 0)
        return fp_errorf(err, errlen, -EEXIST, "%s exists (--force overwrites)", path);
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash) *(slash == dir ? slash + 1 : slash) = '\0';
    else snprintf(dir, sizeof dir, ".");
    if (stat(dir, &st) || !S_ISDIR(st.st_mode))
        return fp_errorf(err, errlen, -ENOENT, "%s: no folder %s", path, dir);
    if (access(dir, W_OK | X_OK)) return fp_errorf(err, errlen, -EACCES, "%s: folder %s not writable", path, dir);
    return 0;
}

int fp_audio_out_check(const char *spec, bool force, char *err, size_t errlen)
{
    if (!spec || !*spec) return fp_errorf(err, errlen, -EINVAL, "empty audio output (null, file:OUT.wav or a device)");
    if (!strcmp(spec, "null")) return 0;
    if (!strncmp(spec, "file:", 5)) return check_file(spec + 5, force, err, errlen);
    if (fp_audio_pa_init())
        return fp_errorf(err, errlen, -ENODEV, "audio device '%s': no sound system (PortAudio)", spec);
    PaDeviceIndex d = fp_audio_find_device(spec, false);
    Pa_Terminate();
    if (d == paNoDevice)
        return fp_errorf(err, errlen, -ENODEV, "no audio output device '%s' (null and file:OUT.wav "
                         "need none)", spec);
    return 0;
}

static int open_device(fp_audio_out *o, const char *spec, char *err, size_t errlen)
{
    if (fp_audio_pa_init())
        return fp_errorf(err, errlen, -ENODEV, "audio device '%s': no sound system (PortAudio)", spec);
    o->pa_up = true;
    PaDeviceIndex d = fp_audio_find_device(spec, false);
    if (d == paNoDevice) return fp_errorf(err, errlen, -ENODEV, "no audio output device '%s'", spec);
    PaStreamParameters p = {.device = d, .channelCount = o->channels, .sampleFormat = paFloat32,
                            .suggestedLatency = Pa_GetDeviceInfo(d)->defaultLowOutputLatency};
    PaError e = Pa_OpenStream(&o->stream, NULL, &p, o->rate, paFramesPerBufferUnspecified, paClipOff,
                              NULL, NULL);
    if (e == paNoError) e = Pa_StartStream(o->stream);
    if (e != paNoError)
        return fp_errorf(err, errlen, -EIO, "audio device '%s': %s", spec, Pa_GetErrorText(e));
    return 0;
}

int fp_audio_out_open(const char *spec, int rate, int channels, bool force, fp_audio_out **out,
                      char *err, size_t errlen)
{
    int rc = fp_audio_out_check(spec, force, err, errlen);
    if (rc) return rc;
    if (rate <= 0 || channels <= 0) return fp_errorf(err, errlen, -EINVAL, "bad audio format");
    fp_audio_out *o = calloc(1, sizeof *o);
    if (!o) return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    o->channels = channels;
    o->rate = rate;
    o->file.fd = -1;
    if (!strcmp(spec, "null")) {
        o->kind = OUT_NULL;
    } else if (!strncmp(spec, "file:", 5)) {
        o->kind = OUT_FILE;
        const char *path = spec + 5;
        if ((rc = fp_file_open_output(path, "", NULL, 0, &o->file))) {
            free(o);
            return fp_errorf(err, errlen, rc, "%s: %s", path, fp_file_error_text(rc));
        }
        SF_INFO info = {.samplerate = rate, .channels = channels,
                        .format = SF_FORMAT_WAV | SF_FORMAT_FLOAT};
        o->sf = sf_open_fd(o->file.fd, SFM_WRITE, &info, 0);
        if (!o->sf) {
            fp_file_output_abort(&o->file);
            free(o);
            return fp_errorf(err, errlen, -EIO, "%s: %s", path, sf_strerror(NULL));
        }
    } else {
        o->kind = OUT_DEVICE;
        if ((rc = open_device(o, spec, err, errlen))) {
            fp_audio_out_abort(&o);
            return rc;
        }
    }
    *out = o;
    return 0;
}

int fp_audio_out_write(fp_audio_out *o, const float *frames, size_t n, char *err, size_t errlen)
{
    if (!o) return fp_errorf(err, errlen, -EINVAL, "no audio output");
    if (!n) return 0;
    if (o->kind == OUT_FILE && sf_writef_float(o->sf, frames, (sf_count_t)n) != (sf_count_t)n)
        return fp_errorf(err, errlen, -EIO, "%s: %s", o->file.path, sf_strerror(o->sf));
    if (o->kind == OUT_DEVICE) {
        PaError e = Pa_WriteStream(o->stream, frames, (unsigned long)n);
        if (e != paNoError && e != paOutputUnderflowed)
            return fp_errorf(err, errlen, -EIO, "audio device: %s", Pa_GetErrorText(e));
    }
    o->frames += n;
    return 0;
}

uint64_t fp_audio_out_frames(const fp_audio_out *o) { return o ? o->frames : 0; }

int fp_audio_out_close(fp_audio_out **op, char *err, size_t errlen)
{
    fp_audio_out *o = op ? *op : NULL;
    if (!o) return 0;
    int rc = 0;
    if (o->kind == OUT_FILE) {
        if (sf_close(o->sf)) rc = fp_errorf(err, errlen, -EIO, "%s: closing the WAV failed", o->file.path);
        o->sf = NULL;
        if (!rc && (rc = fp_file_output_commit(&o->file)))
            fp_errorf(err, errlen, rc, "%s: %s", o->file.path, strerror(-rc));
        if (rc) fp_file_output_abort(&o->file);
    } else if (o->kind == OUT_DEVICE) {
        if (o->stream) {
            Pa_StopStream(o->stream); /* (plays what is buffered) */
            Pa_CloseStream(o->stream);
        }
        if (o->pa_up) Pa_Terminate();
    }
    free(o);
    *op = NULL;
    return rc;
}

void fp_audio_out_abort(fp_audio_out **op)
{
    fp_audio_out *o = op ? *op : NULL;
    if (!o) return;
    if (o->sf) sf_close(o->sf);
    fp_file_output_abort(&o->file);
    if (o->stream) {
        Pa_AbortStream(o->stream);
        Pa_CloseStream(o->stream);
    }
    if (o->pa_up) Pa_Terminate();
    free(o);
    *op = NULL;
}

/* ---- the player ----------------------------------------------------------------------------- */

void fp_audio_player_init(fp_audio_player *p, const fp_soundtrack *track, fp_audio_out *out,
                          double offset_s)
{
    memset(p, 0, sizeof *p);
    p->track = track;
    p->out = out;
    p->offset_s = offset_s;
}

int fp_audio_player_advance(fp_audio_player *p, double t_s, char *err, size_t errlen)
{
    const fp_soundtrack *st = p->track;
    if (!st || !p->out || !isfinite(t_s)) return 0;
    const int64_t start = (int64_t)llround(p->offset_s * st->rate);   /* track frame at t = 0 */
    const int64_t want = (int64_t)llround(t_s * st->rate);            /* frames due in all */
    const size_t ch = (size_t)st->channels;
    while ((int64_t)p->delivered < want) {
        size_t n = (size_t)(want - (int64_t)p->delivered);
        if (n > 4096) n = 4096;
        if (n > p->chunk_cap) {
            float *c = realloc(p->chunk, n * ch * sizeof *c);
            if (!c) return fp_errorf(err, errlen, -ENOMEM, "out of memory");
            p->chunk = c;
            p->chunk_cap = n;
        }
        for (size_t k = 0; k < n; k++) { /* the track's frame, or silence outside it */
            int64_t src = start + (int64_t)p->delivered + (int64_t)k;
            if (src >= 0 && (uint64_t)src < st->frames) memcpy(p->chunk + k * ch, st->samples + (size_t)src * ch, ch * sizeof(float));
            else memset(p->chunk + k * ch, 0, ch * sizeof(float));
        }
        int rc = fp_audio_out_write(p->out, p->chunk, n, err, errlen);
        if (rc) return rc;
        p->delivered += n;
    }
    return 0;
}

void fp_audio_player_skip(fp_audio_player *p, double t_s)
{
    if (!p->track || !isfinite(t_s)) return;
    const int64_t want = (int64_t)llround(t_s * p->track->rate);
    if (want > (int64_t)p->delivered) p->delivered = (uint64_t)want;
}

void fp_audio_player_free(fp_audio_player *p)
{
    free(p->chunk);
    p->chunk = NULL;
    p->chunk_cap = 0;
}
