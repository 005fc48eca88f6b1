/* The soundtrack and timecode options of run and play (app_audio.h). */
#define _GNU_SOURCE
#include "app_audio.h"
#include "app_util.h"

#include "command.h"
#include "fp_text.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

size_t fp_app_audio_longopts(struct option *out, bool with_timecode)
{
    out[0] = (struct option){"audio", required_argument, NULL, FP_APP_AUDIO_OPT};
    out[1] = (struct option){"audio-out", required_argument, NULL, FP_APP_AUDIO_OPT_OUT};
    out[2] = (struct option){"audio-offset", required_argument, NULL, FP_APP_AUDIO_OPT_OFFSET};
    if (!with_timecode) return 3;
    out[3] = (struct option){"timecode", required_argument, NULL, FP_APP_AUDIO_OPT_TIMECODE};
    out[4] = (struct option){"audio-in", required_argument, NULL, FP_APP_AUDIO_OPT_IN};
    return 5;
}

int fp_app_audio_parse(fp_app_audio *a, int c, const char *arg, const char *cmd)
{
    switch (c) {
    case FP_APP_AUDIO_OPT: a->path = arg; return 1;
    case FP_APP_AUDIO_OPT_OUT: a->out_spec = arg; return 1;
    case FP_APP_AUDIO_OPT_OFFSET:
        if (!fp_parse_decimal(arg, &a->offset_s) || fabs(a->offset_s) > FP_SOUNDTRACK_MAX_SECONDS) {
            fprintf(stderr, "facepuppet %s: --audio-offset must be seconds within +-%.0f, got '%s'\n",
                    cmd, FP_SOUNDTRACK_MAX_SECONDS, arg);
            return FP_EXIT_USAGE;
        }
        a->offset_given = true;
        return 1;
    case FP_APP_AUDIO_OPT_TIMECODE:
        if (strcmp(arg, "system") && (strncmp(arg, "ltc:", 4) || !arg[4])) {
            fprintf(stderr, "facepuppet %s: --timecode: give system, ltc:FILE.wav or ltc:DEVICE, "
                    "got '%s'\n", cmd, arg);
            return FP_EXIT_USAGE;
        }
        a->timecode = arg;
        return 1;
    case FP_APP_AUDIO_OPT_IN:
        if (!*arg || !strcmp(arg, "file:")) {
            fprintf(stderr, "facepuppet %s: --audio-in: give a device or file:IN.wav, got '%s'\n", cmd, arg);
            return FP_EXIT_USAGE;
        }
        a->in_spec = arg;
        return 1;
    default: return 0;
    }
}

void fp_app_audio_help(FILE *f, bool with_timecode)
{
    fprintf(f,
        "      --audio FILE       a soundtrack (WAV, FLAC, OGG) played in step with the frames;\n"
        "                         a take records its path, crc32 and offset\n"
        "      --audio-out SPEC   where it plays: default (the system's output, PortAudio), a\n"
        "                         device's index or part of its name, null (nowhere), or\n"
        "                         file:OUT.wav (exactly the samples played, 32-bit float)\n"
        "      --audio-offset S   the soundtrack's time at the first frame (default %s)\n",
        with_timecode ? "0; with --over, the base take's" : "the take's, or 0");
    if (with_timecode)
        fprintf(f,
        "      --timecode SRC     the take's timecode: system (the time of day, default),\n"
        "                         ltc:FILE.wav (LTC decoded from a recording whose first sample\n"
        "                         is the first frame) or ltc:DEVICE (LTC heard on an input\n"
        "                         device before the run); the take's rate is the LTC's\n"
        "      --audio-in DEV     record a microphone beside each take (SLATE_TNNN.mic.wav, its\n"
        "                         sample 0 at the take's first frame; the take's header names\n"
        "                         it): default, a device's index or part of its name, or\n"
        "                         file:IN.wav (a sound file heard in real time: an emulated\n"
        "                         microphone); it runs on the wall clock\n");
}

/* Exit status for a soundtrack's load error: missing or unreadable (not a sound file) is an
 * input that cannot be opened (66), as the issue asks. */
static int file_status(int rc)
{
    switch (rc) {
    case -ENOMEM: return FP_EXIT_SOFTWARE;
    case -EBADMSG: return FP_EXIT_DATAERR; /* a file there, but no sound file, or bad samples */
    default: return FP_EXIT_NOINPUT;
    }
}

static int out_status(int rc)
{
    switch (rc) {
    case -ENODEV: case -EINVAL: return FP_EXIT_USAGE;
    case -ENOMEM: return FP_EXIT_SOFTWARE;
    default: return FP_EXIT_CANTCREAT;
    }
}

static int prepare_timecode(fp_app_audio *a, const char *cmd)
{
    if (!a->timecode || !strcmp(a->timecode, "system")) return 0;
    const char *src = a->timecode + 4;
    char err[1024];
    struct stat st;
    bool file = stat(src, &st) == 0 || strchr(src, '/') || strchr(src, '.');
    int rc = file ? fp_ltc_read_file(src, &a->ltc, err, sizeof err)
                  : fp_ltc_listen(src, 5.0, &a->ltc, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet %s: --timecode: %s\n", cmd, err);
        if (!file) return rc == -ENODEV ? FP_EXIT_USAGE : FP_EXIT_NOINPUT;
        return rc == -EBADMSG && stat(src, &st) == 0 ? FP_EXIT_DATAERR : FP_EXIT_NOINPUT;
    }
    a->have_ltc = true;
    snprintf(a->ltc_source, sizeof a->ltc_source, "%s", a->timecode);
    return 0;
}

int fp_app_audio_prepare(fp_app_audio *a, const char *cmd, const char *fallback, bool force)
{
    char err[2048];
    const char *path = a->path ? a->path : fallback;
    int rc = 0;
    if (a->out_spec && !path) {
        fprintf(stderr, "facepuppet %s: --audio-out needs a soundtrack (--audio FILE)\n", cmd);
        return FP_EXIT_USAGE;
    }
    if (path) {
        /* the output first: an unknown device is a usage error whatever the file */
        const char *spec = a->out_spec ? a->out_spec : "default";
        if ((rc = fp_audio_out_check(spec, force, err, sizeof err))) {
            fprintf(stderr, "facepuppet %s: --audio-out: %s\n", cmd, err);
            return out_status(rc);
        }
        if ((rc = fp_soundtrack_load(path, &a->track, err, sizeof err))) {
            fprintf(stderr, "facepuppet %s: --audio: %s\n", cmd, err);
            return file_status(rc);
        }
        a->path = path;
        if ((rc = fp_audio_out_open(spec, a->track.rate, a->track.channels, force, &a->out, err, sizeof err))) {
            fprintf(stderr, "facepuppet %s: --audio-out: %s\n", cmd, err);
            fp_soundtrack_free(&a->track);
            return out_status(rc);
        }
        fp_audio_player_init(&a->player, &a->track, a->out, a->offset_s);
        a->playing = true;
    }
    rc = prepare_timecode(a, cmd);
    if (!rc && a->in_spec && (rc = fp_audio_in_open(a->in_spec, &a->in, err, sizeof err))) {
        fprintf(stderr, "facepuppet %s: --audio-in: %s\n", cmd, err);
        rc = rc == -ENODEV || rc == -EINVAL ? FP_EXIT_USAGE : file_status(rc);
    }
    if (rc) {
        fp_audio_out_abort(&a->out); /* (a file output's temporary removed: nothing written) */
        fp_app_audio_finish(a, cmd, true);
        return rc;
    }
    return 0;
}

void fp_app_audio_take_options(const fp_app_audio *a, int64_t t0_ns, fp_session_take_options *o)
{
    if (a->playing) {
        o->soundtrack_path = a->path;
        o->soundtrack_crc32 = a->track.crc32;
        o->soundtrack_offset_s = a->offset_s;
    }
    if (a->in) o->audio_in_device = a->in_spec;
    o->stage_at_given = true; /* (a take started later carries both on: fp_session_take.h) */
    o->stage_at_ns = t0_ns;
    if (a->have_ltc) {
        o->rate = a->ltc.rate;
        o->have_timecode = true;
        o->timecode_source = a->ltc_source;
        if (a->ltc.at_ns) fp_ltc_timecode_at(&a->ltc, t0_ns, &o->timecode_in);
        else o->timecode_in = a->ltc.first;
    }
}

void fp_app_audio_restart(fp_app_audio *a)
{
    if (!a->playing) return;
    fp_audio_player_free(&a->player);
    fp_audio_player_init(&a->player, &a->track, a->out, a->offset_s);
}

int fp_app_audio_take_started(fp_app_audio *a, const fp_session_take *take, int64_t origin_ns,
                              const char *cmd)
{
    a->in_path[0] = '\0';
    if (!a->in || !take->header.audio_in_device) return 0;
    const char *tp = fp_take_recorder_path(take->rec), *slash = strrchr(tp, '/');
    char name[FP_TAKE_SLATE_MAX + 32], err[2048];
    if (fp_take_audio_in_name(take->header.slate, take->header.take, name, sizeof name)) return 0;
    snprintf(a->in_path, sizeof a->in_path, "%.*s%s", slash ? (int)(slash - tp + 1) : 0, tp, name);
    if (fp_audio_in_record(a->in, a->in_path, origin_ns, err, sizeof err)) {
        fprintf(stderr, "facepuppet %s: --audio-in: %s\n", cmd, err);
        a->in_path[0] = '\0';
        return FP_EXIT_CANTCREAT;
    }
    return 0;
}

int fp_app_audio_take_stopped(fp_app_audio *a, int64_t end_ns, const char *cmd, bool quiet)
{
    if (!a->in || !a->in_path[0]) return 0;
    char err[2048];
    uint64_t n = 0;
    int rc = fp_audio_in_record_stop(a->in, end_ns, &n, err, sizeof err);
    if (rc) fprintf(stderr, "facepuppet %s: --audio-in: %s\n", cmd, err);
    else if (!quiet)
        fprintf(stderr, "facepuppet %s: microphone %s: %.3f s from %s\n", cmd, a->in_path,
                (double)n / fp_audio_in_rate(a->in), a->in_spec);
    a->in_path[0] = '\0';
    return rc ? FP_EXIT_CANTCREAT : 0;
}

int fp_app_audio_advance(fp_app_audio *a, double t_s, const char *cmd)
{
    if (!a->playing) return 0;
    char err[1024];
    if (fp_audio_player_advance(&a->player, t_s, err, sizeof err)) {
        fprintf(stderr, "facepuppet %s: --audio-out: %s\n", cmd, err);
        return FP_EXIT_CANTCREAT;
    }
    return 0;
}

int fp_app_audio_advance_live(fp_app_audio *a, double t_s, const char *cmd)
{
    if (!a->playing) return 0;
    const char *spec = a->out_spec ? a->out_spec : "default";
    const double due = t_s - (double)a->player.delivered / a->track.rate;
    if (strcmp(spec, "null") && strncmp(spec, "file:", 5) && due > 0.25)
        fp_audio_player_skip(&a->player, t_s - 0.05);
    return fp_app_audio_advance(a, t_s, cmd);
}

int fp_app_audio_finish(fp_app_audio *a, const char *cmd, bool quiet)
{
    int status = 0;
    if (a->out) {
        char err[1024];
        uint64_t n = fp_audio_out_frames(a->out);
        if (fp_audio_out_close(&a->out, err, sizeof err)) {
            fprintf(stderr, "facepuppet %s: --audio-out: %s\n", cmd, err);
            status = FP_EXIT_CANTCREAT;
        } else if (!quiet && a->track.rate) {
            fprintf(stderr, "facepuppet %s: soundtrack %s: %.3f s played from %.3f s to %s\n", cmd,
                    a->path, (double)n / a->track.rate, a->offset_s,
                    a->out_spec ? a->out_spec : "default");
        }
    }
    fp_audio_player_free(&a->player);
    fp_soundtrack_free(&a->track);
    fp_audio_in_close(&a->in); /* (a recording not stopped is dropped) */
    a->playing = false;
    return status;
}

int fp_app_audio_export_check(const fp_take_header *h, const char *anim_out, bool force, char *wav,
                              size_t n, const char *cmd)
{
    wav[0] = '\0';
    if (!h->soundtrack_path) return 0;
    const char *dot = strrchr(anim_out, '.'), *slash = strrchr(anim_out, '/');
    struct stat st;
    bool folder = stat(anim_out, &st) == 0 ? S_ISDIR(st.st_mode) : !dot || (slash && dot < slash);
    size_t len = strlen(anim_out);
    while (folder && len > 1 && anim_out[len - 1] == '/') len--;
    int stem = folder ? (int)len : (int)(dot - anim_out);
    snprintf(wav, n, "%.*s.wav", stem, anim_out);
    char err[2048], spec[4300];
    snprintf(err, sizeof err, "facepuppet %s", cmd);
    int rc = fp_app_check_not_input(err, "the soundtrack's WAV", wav, h->soundtrack_path,
                                    "the take's soundtrack");
    if (rc) {   /* (the WAV beside the output would be written over its own source) */
        wav[0] = '\0';
        return rc;
    }
    snprintf(spec, sizeof spec, "file:%s", wav);
    if ((rc = fp_audio_out_check(spec, force, err, sizeof err))) {
        fprintf(stderr, "facepuppet %s: the soundtrack's WAV: %s\n", cmd, err);
        wav[0] = '\0';
        return rc == -ENOMEM ? FP_EXIT_SOFTWARE : FP_EXIT_CANTCREAT;
    }
    return 0;
}

int fp_app_audio_export_write(const fp_take_header *h, const char *wav, int64_t first_ns,
                              double duration_s, bool force, bool quiet, FILE *say,
                              const char *cmd)
{
    if (!wav[0] || !h->soundtrack_path) return 0;
    char err[2048], spec[4300];
    fp_soundtrack track;
    if (fp_soundtrack_load(h->soundtrack_path, &track, err, sizeof err)) {
        fprintf(stderr, "facepuppet %s: warning: the take's soundtrack: %s: %s not written\n", cmd, err, wav);
        return 0;
    }
    if (!quiet && track.crc32 != h->soundtrack_crc32)
        fprintf(stderr, "facepuppet %s: warning: %s has crc32 %08x, the take's soundtrack had %08x: "
                "another file?\n", cmd, h->soundtrack_path, (unsigned)track.crc32, (unsigned)h->soundtrack_crc32);
    /* the soundtrack's time at the first exported frame */
    const double start_s = h->soundtrack_offset_s + (double)(first_ns - h->time_origin_ns) * 1e-9;
    snprintf(spec, sizeof spec, "file:%s", wav);
    fp_audio_out *out = NULL;
    fp_audio_player p;
    int rc = fp_audio_out_open(spec, track.rate, track.channels, force, &out, err, sizeof err);
    if (!rc) {
        fp_audio_player_init(&p, &track, out, start_s);
        rc = fp_audio_player_advance(&p, duration_s, err, sizeof err);
        fp_audio_player_free(&p);
    }
    uint64_t frames = fp_audio_out_frames(out);
    if (!rc) rc = fp_audio_out_close(&out, err, sizeof err);
    fp_audio_out_abort(&out);
    if (rc) fprintf(stderr, "facepuppet %s: the soundtrack's WAV: %s\n", cmd, err);
    else if (!quiet)
        fprintf(say, "facepuppet %s: wrote %s: the soundtrack %s from %.6f s for %.6f s (%llu samples at "
                "%d Hz), its sample 0 at the animation's first frame\n", cmd, wav, h->soundtrack_path,
                start_s, (double)frames / track.rate, (unsigned long long)frames, track.rate);
    fp_soundtrack_free(&track);
    return rc ? FP_EXIT_CANTCREAT : 0;
}

bool fp_app_is_sound(const unsigned char *h, size_t n)
{
    if (n < 4) return false;
    return ((!memcmp(h, "RIFF", 4) || !memcmp(h, "RF64", 4)) && n >= 12 && !memcmp(h + 8, "WAVE", 4)) ||
           !memcmp(h, "fLaC", 4) || !memcmp(h, "OggS", 4) || !memcmp(h, ".snd", 4) || !memcmp(h, "caff", 4) ||
           (!memcmp(h, "FORM", 4) && n >= 12 && (!memcmp(h + 8, "AIFF", 4) || !memcmp(h + 8, "AIFC", 4)));
}

int fp_app_sound_info(const char *path)
{
    fp_soundtrack st;
    char err[1024];
    int rc = fp_soundtrack_load(path, &st, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet info: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    float peak = 0;
    for (uint64_t i = 0; i < st.frames * (uint64_t)st.channels; i++)
        if (fabsf(st.samples[i]) > peak) peak = fabsf(st.samples[i]);
    printf("%s\n  format    sound, %d Hz, %d channel%s\n  duration  %.3f s (%llu frames)\n", path, st.rate,
           st.channels, st.channels == 1 ? "" : "s", (double)st.frames / st.rate, (unsigned long long)st.frames);
    if (peak > 0) printf("  peak      %.1f dBFS\n", 20.0 * log10(peak));
    else printf("  peak      silence\n");
    printf("  crc32     %08x (a take records it with --audio)\n", (unsigned)st.crc32);
    const int st_channels = st.channels;
    fp_soundtrack_free(&st);
    fp_ltc_info ltc;
    char tc[32] = "";
    if (!fp_ltc_read_file(path, &ltc, err, sizeof err) && !fp_timecode_format(&ltc.first, tc, sizeof tc)) {
        char on[32] = ""; /* which track holds it, where there are several */
        if (st_channels > 1) snprintf(on, sizeof on, " on channel %d", ltc.channel);
        printf("  timecode  LTC at %.5g fps, %s at the first sample (%llu frames decoded%s%s)\n",
               (double)ltc.rate.num / ltc.rate.den, tc, (unsigned long long)ltc.frames, on,
               ltc.jumps ? ", with jumps" : "");
    } else {
        printf("  timecode  none (no LTC on any channel)\n");
    }
    printf("  use       --audio %s (a soundtrack), --input audio:%s (the jaw flap)%s%s\n", path, path,
           tc[0] ? ", --timecode ltc:" : "", tc[0] ? path : "");
    return FP_EXIT_OK;
}
