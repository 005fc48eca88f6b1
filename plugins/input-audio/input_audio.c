/*
 * input_audio.c: the input-audio plugin, `--input audio:FILE` or `--input audio:mic`: the
 * loudness of a soundtrack or of a microphone drives a rig channel (jaw.open by default), the
 * "jaw flap" of animatronics, which a performer layers under a hand pass.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * How it drives the channel: it pushes FP_EVENT_CHANNEL events (plugin ABI 1.2), which the
 * host applies to the rig when it drains them, whatever the mapping (a mapping that returns
 * the same channel that frame wins). No mapping key is needed.
 *
 * The envelope, every hop (5 ms): the RMS of the last `window` seconds of the mono mix, as a
 * fraction of the reference level (a file: its loudest window, so that the loudest syllable
 * opens the jaw fully; the mic: ref=DBFS), times gain, clamped to [0, 1]; 0 where the RMS is
 * under gate=DBFS; smoothed by one-pole attack and release times. The value sent is
 * min + envelope x (max - min) (keys min, max: the channel's values for silence and for the
 * loudest sound).
 *
 * A file is a recording: its events are stamped host_t0 + t for the envelope at soundtrack
 * time t (host_t0: when the plugin started), paced by the clock at speed=X (fast=1: as fast
 * as the queue takes them), never dropped; the input reports FP_EXT_RECORDING_INFO, so a
 * headless run steps on its clock as on a replay's and the jaw follows the soundtrack's time
 * exactly. It ends with an end-of-stream status. The mic runs live (PortAudio's callback
 * computes the envelope and pushes at the host's time; a full queue drops, as a live device).
 *
 * Threads: create, start, stop, destroy [main-thread]; the file's pacing thread (fp_pacer)
 * or PortAudio's callback thread push.
 */
#define _GNU_SOURCE
#include <facepuppet/plugin.h>
#include <facepuppet/plugin_util.h>
#include "fp_audio.h"
#include "fp_pacer.h"

#include <alsa/asoundlib.h>
#include <errno.h>
#include <math.h>
#include <portaudio.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define HOP_S 0.005

typedef struct env_params {
    double attack_s, release_s, gate_db, gain, ref_db, window_s, min, max;
    char channel[32];
} env_params;

/* The envelope's running state. */
typedef struct env_state {
    double level;          /* smoothed, 0..1 */
    double *ring;          /* squares of the window's samples */
    size_t ring_n, ring_at;
    double sum;            /* of ring */
} env_state;

typedef struct audio_input {
    fp_input input;
    const fp_host *host;
    env_params p;
    bool mic;
    char *path;
    /* file */
    float *values;         /* the channel's value at every hop */
    size_t count;
    double speed;
    bool fast;
    fp_pacer pacer;
    /* mic */
    char device[128];
    PaStream *stream;
    bool pa_up;
    env_state live;
    double ref_rms;
    size_t hop_frames, hop_at;
    double hop_sum;
} audio_input;

static const char usage_text[] =
    "audio:FILE[,key=value...]  or  audio:mic[,device=NAME][,key=value...]\n"
    "  The loudness of a sound file (WAV, FLAC, OGG) or of a microphone drives a rig channel\n"
    "  (jaw.open): the jaw flap. A file is paced as a recording (speed=X, fast=1) and ends\n"
    "  with it; the mic runs live. Keys: channel=NAME (jaw.open), attack=S (0.005),\n"
    "  release=S (0.06), gate=DBFS (-40: quieter is silence), gain=G (4), ref=DBFS (the\n"
    "  file's loudest window; the mic: -12), window=S (0.01), min=V (0), max=V (1),\n"
    "  device=NAME (mic: 'default', an index or part of a name).\n";

/* ---- the envelope ----------------------------------------------------------------------- */

static int env_init(env_state *e, const env_params *p, int rate)
{
    memset(e, 0, sizeof *e);
    e->ring_n = (size_t)fmax(1.0, round(p->window_s * rate));
    e->ring = calloc(e->ring_n, sizeof *e->ring);
    return e->ring ? 0 : -ENOMEM;
}

static void env_add(env_state *e, double x)
{
    double sq = isfinite(x) ? x * x : 0.0; /* (a live device's NaN, as silence: files are refused) */
    e->sum += sq - e->ring[e->ring_at];
    e->ring[e->ring_at] = sq;
    e->ring_at = (e->ring_at + 1) % e->ring_n;
}

static double env_rms(const env_state *e) { return sqrt(fmax(0.0, e->sum) / (double)e->ring_n); }

/* One hop: the smoothed level from the window's RMS against ref_rms; returns the value. */
static double env_step(env_state *e, const env_params *p, double ref_rms)
{
    double rms = env_rms(e);
    double db = 20.0 * log10(rms + 1e-12);
    double target = db < p->gate_db || ref_rms <= 0 ? 0.0 : fmin(1.0, p->gain * rms / ref_rms);
    double tau = target > e->level ? p->attack_s : p->release_s;
    double k = tau > 0 ? 1.0 - exp(-HOP_S / tau) : 1.0;
    e->level += k * (target - e->level);
    return p->min + e->level * (p->max - p->min);
}

/* The file whole: mono mix, the loudest window (the reference unless ref= was given), then
 * the value at every hop. */
static int load_file(audio_input *a, bool ref_given, char *err, size_t errlen)
{
    /* core's reader (fp_audio.h): a regular file only, every sample finite, at most 2 h */
    fp_soundtrack t;
    char msg[512];
    int rc = fp_soundtrack_load(a->path, &t, msg, sizeof msg);
    if (rc) {
        snprintf(err, errlen, "audio: %s", msg);
        return rc;
    }
    float *buf = t.samples; /* (owned here from now on) */
    size_t n = (size_t)t.frames, ch = (size_t)t.channels;
    const int rate = t.rate;
    for (size_t i = 0; i < n; i++) { /* mono, in place */
        double m = 0;
        for (size_t c = 0; c < ch; c++) m += buf[i * ch + c];
        buf[i] = (float)(m / (double)ch);
    }
    size_t hop = (size_t)llround(HOP_S * rate);
    env_state e;
    if (env_init(&e, &a->p, rate)) {
        free(buf);
        return -ENOMEM;
    }
    double ref = ref_given ? pow(10.0, a->p.ref_db / 20.0) : 0.0;
    if (!ref_given) /* the loudest window */
        for (size_t i = 0; i < n; i++) {
            env_add(&e, buf[i]);
            if ((i + 1) % hop == 0) ref = fmax(ref, env_rms(&e));
        }
    free(e.ring);
    a->count = n / hop + 1;
    a->values = malloc(a->count * sizeof *a->values);
    rc = a->values ? env_init(&e, &a->p, rate) : -ENOMEM;
    if (!rc) {
        a->values[0] = (float)a->p.min;
        for (size_t i = 0, k = 1; i < n; i++) {
            env_add(&e, buf[i]);
            if ((i + 1) % hop == 0 && k < a->count) a->values[k++] = (float)env_step(&e, &a->p, ref);
        }
        free(e.ring);
    } else {
        snprintf(err, errlen, "audio: out of memory");
    }
    free(buf);
    return rc;
}

/* ---- file: the pacing thread ------------------------------------------------------------ */

static bool push_value(fp_pacer *pc, const audio_input *a, int64_t t_ns, float v)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.channel.header = (fp_event_header){.size = sizeof ev.channel, .type = FP_EVENT_CHANNEL,
                                          .time_ns = t_ns, .hand = -1};
    memcpy(ev.channel.name, a->p.channel, sizeof ev.channel.name);
    ev.channel.value = v;
    return pc ? fp_pacer_push(pc, &ev) : a->host->push_event(a->host, &ev.header);
}

static void *file_thread(void *arg)
{
    audio_input *a = arg;
    const int64_t host_t0 = a->host->now_ns(a->host), mono_t0 = fp_pacer_now_ns();
    const char *base = strrchr(a->path, '/') ? strrchr(a->path, '/') + 1 : a->path;
    if (!fp_pacer_push_status(&a->pacer, host_t0, FP_STATUS_CONNECTED, "loudness of %s: %.3f s",
                              base, (double)(a->count - 1) * HOP_S))
        return NULL;
    int64_t t = host_t0;
    for (size_t k = 0; k < a->count; k++) {
        int64_t off = llround((double)k * HOP_S * 1e9);
        if (a->fast) {
            if (fp_pacer_stopped(&a->pacer)) return NULL;
        } else if (!fp_pacer_wait_until(&a->pacer, mono_t0 + llround((double)off / a->speed))) {
            return NULL;
        }
        t = host_t0 + off;
        if (!push_value(&a->pacer, a, t, a->values[k])) return NULL;
    }
    fp_pacer_push_status(&a->pacer, t, FP_STATUS_END_OF_STREAM, "end of %s", base);
    return NULL;
}

/* ---- mic: PortAudio's callback ----------------------------------------------------------- */

static int mic_callback(const void *in, void *out, unsigned long frames,
                        const PaStreamCallbackTimeInfo *ti, PaStreamCallbackFlags flags, void *user)
{
    (void)out, (void)ti, (void)flags;
    audio_input *a = user;
    const float *x = in;
    for (unsigned long i = 0; x && i < frames; i++) {
        env_add(&a->live, x[i]);
        if (++a->hop_at == a->hop_frames) {
            a->hop_at = 0;
            float v = (float)env_step(&a->live, &a->p, a->ref_rms);
            push_value(NULL, a, a->host->now_ns(a->host), v); /* (a full queue drops it) */
        }
    }
    return paContinue;
}

static void alsa_quiet(const char *file, int line, const char *fn, int err, const char *fmt, ...)
{
    (void)file, (void)line, (void)fn, (void)err, (void)fmt;
}

static int mic_start(audio_input *a, char *err, size_t errlen)
{
    snd_lib_error_set_handler(alsa_quiet);
    if (Pa_Initialize() != paNoError) {
        snprintf(err, errlen, "audio: no sound system (PortAudio)");
        return -ENODEV;
    }
    a->pa_up = true;
    PaDeviceIndex dev = paNoDevice;
    if (!strcmp(a->device, "default")) {
        dev = Pa_GetDefaultInputDevice();
    } else {
        char *end;
        long idx = strtol(a->device, &end, 10);
        for (int i = 0; i < Pa_GetDeviceCount() && dev == paNoDevice; i++) {
            const PaDeviceInfo *d = Pa_GetDeviceInfo(i);
            if (d && d->maxInputChannels > 0 &&
                ((*a->device && !*end && idx == i) || (d->name && strcasestr(d->name, a->device))))
                dev = i;
        }
    }
    if (dev == paNoDevice) {
        snprintf(err, errlen, "audio: no input device '%s'", a->device);
        return -ENODEV;
    }
    const int rate = 48000;
    a->hop_frames = (size_t)llround(HOP_S * rate);
    a->hop_at = 0;
    if (env_init(&a->live, &a->p, rate)) return -ENOMEM;
    a->ref_rms = pow(10.0, a->p.ref_db / 20.0);
    PaStreamParameters ip = {.device = dev, .channelCount = 1, .sampleFormat = paFloat32,
                             .suggestedLatency = Pa_GetDeviceInfo(dev)->defaultLowInputLatency};
    PaError e = Pa_OpenStream(&a->stream, &ip, NULL, rate, a->hop_frames, paClipOff, mic_callback, a);
    if (e == paNoError) e = Pa_StartStream(a->stream);
    if (e != paNoError) {
        snprintf(err, errlen, "audio: input device '%s': %s", a->device, Pa_GetErrorText(e));
        return -EIO;
    }
    return 0;
}

static void mic_stop(audio_input *a)
{
    if (a->stream) {
        Pa_StopStream(a->stream);
        Pa_CloseStream(a->stream);
        a->stream = NULL;
    }
    if (a->pa_up) Pa_Terminate();
    a->pa_up = false;
    free(a->live.ring);
    a->live.ring = NULL;
}

/* ---- fp_input ------------------------------------------------------------------------------ */

static int audio_start(fp_input *self, char *err, size_t errlen)
{
    audio_input *a = self->plugin_data;
    if (!a->mic) return fp_pacer_start(&a->pacer, file_thread, a, "audio", err, errlen);
    int rc = mic_start(a, err, errlen);
    if (rc) mic_stop(a);
    return rc;
}

static void audio_stop(fp_input *self)
{
    audio_input *a = self->plugin_data;
    if (a->mic) mic_stop(a);
    else fp_pacer_stop(&a->pacer);
}

static void audio_destroy(fp_input *self)
{
    if (!self) return;
    audio_input *a = self->plugin_data;
    if (a->mic) mic_stop(a);
    else fp_pacer_destroy(&a->pacer);
    free(a->values);
    free(a->path);
    free(a);
}

static bool audio_recording_info(const fp_input *self, fp_recording_info *info)
{
    const audio_input *a = self->plugin_data;
    if (a->mic) return false;
    memset(info, 0, sizeof *info);
    info->frames = a->count;
    info->rate_hz = 1.0 / HOP_S;
    info->duration_s = (double)(a->count - 1) * HOP_S;
    snprintf(info->format, sizeof info->format, "audio-envelope");
    return true;
}

static const fp_input_recording recording_ext = {.get = audio_recording_info};

static const void *audio_get_extension(const fp_input *self, const char *id)
{
    const audio_input *a = self->plugin_data;
    if (!a->mic && id && !strcmp(id, FP_EXT_RECORDING_INFO)) return &recording_ext;
    return NULL;
}

/* ---- factory ------------------------------------------------------------------------------ */

/* A number key into *out within [lo, hi]; -EINVAL with err otherwise. */
static int number(const fp_param *p, double lo, double hi, double *out, char *err, size_t errlen)
{
    double v;
    if (!fp_parse_decimal(p->value, &v) || v < lo || v > hi) {
        snprintf(err, errlen, "audio: %s=%s: expected a number from %g to %g", p->key, p->value, lo, hi);
        return -EINVAL;
    }
    *out = v;
    return 0;
}

static int parse_keys(audio_input *a, const fp_param *params, size_t n, bool *ref_given, char *err,
                      size_t errlen)
{
    for (size_t i = 0; i < n; i++) {
        const fp_param *p = &params[i];
        const char *k = p->key ? p->key : "", *v = p->value ? p->value : "";
        int rc = 0;
        if (!strcmp(k, "attack")) rc = number(p, 0, 10, &a->p.attack_s, err, errlen);
        else if (!strcmp(k, "release")) rc = number(p, 0, 10, &a->p.release_s, err, errlen);
        else if (!strcmp(k, "gate")) rc = number(p, -200, 0, &a->p.gate_db, err, errlen);
        else if (!strcmp(k, "gain")) rc = number(p, 0, 1000, &a->p.gain, err, errlen);
        else if (!strcmp(k, "window")) rc = number(p, 0.001, 1, &a->p.window_s, err, errlen);
        else if (!strcmp(k, "min")) rc = number(p, -1e6, 1e6, &a->p.min, err, errlen);
        else if (!strcmp(k, "max")) rc = number(p, -1e6, 1e6, &a->p.max, err, errlen);
        else if (!strcmp(k, "ref")) {
            rc = number(p, -200, 0, &a->p.ref_db, err, errlen);
            *ref_given = true;
        } else if (!strcmp(k, "speed")) {
            if (!fp_pacer_parse_speed(v, &a->speed)) {
                snprintf(err, errlen, "audio: speed=%s: expected a number from 0.001 to 1e6", v);
                rc = -EINVAL;
            }
        } else if (!strcmp(k, "fast")) {
            int b = fp_parse_bool(v);
            if (b < 0) {
                snprintf(err, errlen, "audio: fast=%s: expected 0 or 1", v);
                rc = -EINVAL;
            }
            a->fast = b == 1;
        } else if (!strcmp(k, "channel")) {
            bool printable = true; /* as event logs write it (record=): no space, ASCII */
            for (const char *q = v; *q; q++) printable &= *q > ' ' && *q <= '~';
            if (!*v || strlen(v) >= sizeof a->p.channel || !printable) {
                snprintf(err, errlen, "audio: channel=%s: give a name of 1 to 31 printable ASCII characters, no spaces", v);
                rc = -EINVAL;
            }
            snprintf(a->p.channel, sizeof a->p.channel, "%s", v);
        } else if (!strcmp(k, "device")) {
            snprintf(a->device, sizeof a->device, "%s", v);
        } else {
            snprintf(err, errlen, "audio: unknown key \"%s\" (known: channel, attack, release, gate, "
                     "gain, ref, window, min, max, speed, fast, device)", k);
            rc = -EINVAL;
        }
        if (rc) return rc;
    }
    return 0;
}

static int audio_create(const fp_host *host, const char *arg, const fp_param *params, size_t nparams,
                        fp_input **out, char *err, size_t errlen)
{
    *out = NULL;
    if (!host || !host->push_event || !host->now_ns) {
        snprintf(err, errlen, "audio: the host lacks push_event or now_ns");
        return -EINVAL;
    }
    if (!arg || !*arg) {
        snprintf(err, errlen, "audio: give a sound FILE or mic (audio:FILE[,key=value...])");
        return -EINVAL;
    }
    audio_input *a = calloc(1, sizeof *a);
    if (!a || !(a->path = strdup(arg))) {
        free(a);
        snprintf(err, errlen, "audio: out of memory");
        return -ENOMEM;
    }
    a->host = host;
    a->p = (env_params){.attack_s = 0.005, .release_s = 0.06, .gate_db = -40, .gain = 4, .ref_db = -12,
                        .window_s = 0.01, .min = 0, .max = 1};
    snprintf(a->p.channel, sizeof a->p.channel, "jaw.open");
    snprintf(a->device, sizeof a->device, "default");
    a->speed = 1.0;
    a->mic = !strcmp(arg, "mic");
    bool ref_given = false;
    int rc = parse_keys(a, params, nparams, &ref_given, err, errlen);
    if (!rc && !a->mic) rc = load_file(a, ref_given, err, errlen);
    if (!rc && !a->mic && (rc = fp_pacer_init(&a->pacer, host)))
        snprintf(err, errlen, "audio: cannot set up its thread's clock: %s", strerror(-rc));
    if (rc) {
        free(a->values);
        free(a->path);
        free(a);
        return rc;
    }
    a->input = (fp_input){.size = sizeof(fp_input), .plugin_data = a, .start = audio_start,
                          .stop = audio_stop, .destroy = audio_destroy,
                          .get_extension = audio_get_extension};
    *out = &a->input;
    return 0;
}

static const fp_param_info audio_keys[] = {
    {.name = "channel", .type = FP_PARAM_STRING, .default_value = "jaw.open",
     .description = "the rig channel the loudness drives"},
    {.name = "attack", .type = FP_PARAM_FLOAT, .min = 0, .max = 10, .default_value = "0.005", .unit = "s",
     .description = "time constant of the rise"},
    {.name = "release", .type = FP_PARAM_FLOAT, .min = 0, .max = 10, .default_value = "0.06", .unit = "s",
     .description = "time constant of the fall"},
    {.name = "gate", .type = FP_PARAM_FLOAT, .min = -200, .max = 0, .default_value = "-40", .unit = "dBFS",
     .description = "quieter than this is silence"},
    {.name = "gain", .type = FP_PARAM_FLOAT, .min = 0, .max = 1000, .default_value = "4",
     .description = "the envelope's gain over the reference level"},
    {.name = "ref", .type = FP_PARAM_FLOAT, .min = -200, .max = 0, .default_value = "-12", .unit = "dBFS",
     .description = "reference level (a file: its loudest window unless given)"},
    {.name = "window", .type = FP_PARAM_FLOAT, .min = 0.001, .max = 1, .default_value = "0.01", .unit = "s",
     .description = "RMS window"},
    {.name = "min", .type = FP_PARAM_FLOAT, .min = -1e6, .max = 1e6, .default_value = "0",
     .description = "the channel's value in silence"},
    {.name = "max", .type = FP_PARAM_FLOAT, .min = -1e6, .max = 1e6, .default_value = "1",
     .description = "the channel's value at full loudness"},
    {.name = "speed", .type = FP_PARAM_FLOAT, .min = 1e-3, .max = 1e6, .default_value = "1", .unit = "x",
     .description = "a file: play this many times as fast"},
    {.name = "fast", .type = FP_PARAM_BOOL, .min = 0, .max = 1, .default_value = "0",
     .description = "a file: as fast as possible"},
    {.name = "device", .type = FP_PARAM_STRING, .default_value = "default",
     .description = "mic: the input device (index or part of its name)"},
    {.name = NULL},
};

static const fp_input_factory audio_factory = {
    .size = sizeof(fp_input_factory),
    .name = "audio",
    .description = "loudness of a sound file or the mic drives a rig channel (jaw flap)",
    .usage = usage_text,
    .create = audio_create,
    .params = audio_keys,
};

static const void *audio_get_factory(const char *factory_id)
{
    if (factory_id && !strcmp(factory_id, FP_INPUT_FACTORY_ID)) return &audio_factory;
    return NULL;
}

FP_PLUGIN_DECLARE_ENTRY = {
    .abi = {.major = FP_PLUGIN_ABI_MAJOR, .minor = FP_PLUGIN_ABI_MINOR},
    .id = "org.facepuppet.input-audio",
    .version = "1.0.0",
    .get_factory = audio_get_factory,
};
