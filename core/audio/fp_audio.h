/*
 * fp_audio.h: soundtracks, audio outputs and LTC timecode for performances (issue 54).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Parts:
 *   - fp_soundtrack: a sound file (WAV, FLAC, OGG: whatever libsndfile reads) loaded whole
 *     into memory as interleaved f32 samples, with the zlib crc32 of the file's bytes (what a
 *     take records, docs/take-format.md "soundtrack").
 *   - fp_audio_out: where the soundtrack goes: "null" (nothing, for machines without sound),
 *     "file:PATH.wav" (a 32-bit float WAV of exactly the samples played, for tests) or a
 *     PortAudio output device ("default", a device's index or a part of its name).
 *   - fp_audio_player: a soundtrack delivered in step with a performance's clock: each call
 *     says how far the performance got, the player writes the soundtrack's samples up to
 *     that time (plus the offset) to its output. The output's sample k is therefore the
 *     soundtrack's sample round(offset * rate) + k, whatever the session's speed or load:
 *     a file output is in sync to the sample; a device output follows the frames the session
 *     delivers (paced by the device's blocking write when the session runs ahead).
 *   - fp_audio_in: a microphone (a PortAudio input device, or "file:X.wav": a sound file
 *     heard in real time, an emulated microphone) captured on its own thread, each sample at
 *     a host time; a recording writes the samples from a start time to an end time (host
 *     clock, CLOCK_MONOTONIC: the performance's) into a WAV beside a take.
 *   - fp_ltc: SMPTE LTC decoded with libltc from a WAV (or a PortAudio input device): the
 *     frame rate (24, 25, 29.97 drop-frame or not, 30), the timecode at the file's first
 *     sample, and the count of frames decoded and of discontinuities.
 *
 * Errors: 0 or a negative errno-style code (core/common/fp_error.h) with a message in a
 * caller-owned `err` buffer naming the file or device: -ENOENT (missing), -EACCES,
 * -EBADMSG (not a sound file libsndfile reads, no LTC in it), -ENODEV (no such device),
 * -EEXIST (an output file exists and force is false), -EINVAL (a bad spec), -ENOMEM, -EIO.
 * Nothing is printed (PortAudio's ALSA back end may print its own lines on stderr when a
 * device spec is opened; null and file: never touch PortAudio).
 *
 * Threads: every object belongs to one thread at a time.
 */
#ifndef FP_AUDIO_H
#define FP_AUDIO_H

#include "fp_take.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- soundtracks ------------------------------------------------------------------------ */

#define FP_SOUNDTRACK_MAX_SECONDS 7200.0   /* longer files are refused (-EFBIG) */

typedef struct fp_soundtrack {
    float *samples;       /* frames x channels, interleaved, [-1, 1]; malloc()ed, owned */
    uint64_t frames;      /* sample frames */
    int channels;         /* >= 1 */
    int rate;             /* sample frames per second */
    uint32_t crc32;       /* zlib crc32 of the file's bytes */
} fp_soundtrack;

/** Load the sound file at `path` whole (libsndfile: WAV, FLAC, OGG...). A FIFO or device is
 *  refused (-ENXIO), as is a file over FP_SOUNDTRACK_MAX_SECONDS (-EFBIG) or without samples
 *  (-EBADMSG). Returns 0 and *out (free with fp_soundtrack_free), or a negative code with err
 *  ("PATH: reason"). */
int fp_soundtrack_load(const char *path, fp_soundtrack *out, char *err, size_t errlen);

/** Release the samples; *st zeroed. NULL or an empty soundtrack: nothing. */
void fp_soundtrack_free(fp_soundtrack *st);

/* ---- outputs ------------------------------------------------------------------------------ */

typedef struct fp_audio_out fp_audio_out;

/** Check an output spec before any work: "null"; "file:PATH" (PATH ends in .wav, its folder
 *  exists and is writable, and PATH does not exist unless force); a device ("default", an
 *  index, or a case-insensitive part of a PortAudio output device's name: PortAudio is
 *  initialised to look). Returns 0, -EINVAL (an empty or malformed spec), -EEXIST, -ENOENT
 *  (no folder), -EACCES, -ENODEV (no such device, or no sound system). */
int fp_audio_out_check(const char *spec, bool force, char *err, size_t errlen);

/** Initialise PortAudio (Pa_Initialize) with ALSA's error lines kept off stderr. Returns 0
 *  or -ENODEV; pair with Pa_Terminate. [main-thread] */
int fp_audio_pa_init(void);

/** Open the output for `channels` channels at `rate` Hz (fp_audio_out_check's rules; a file
 *  is written as a WAV of 32-bit floats, through a temporary name renamed at close). Returns
 *  0 and *out, or a negative code with err. */
int fp_audio_out_open(const char *spec, int rate, int channels, bool force, fp_audio_out **out,
                      char *err, size_t errlen);

/** Write n interleaved sample frames (a device: blocks while its buffer is full). Returns 0
 *  or -EIO with err. */
int fp_audio_out_write(fp_audio_out *o, const float *frames, size_t n, char *err, size_t errlen);

/** Sample frames written so far. */
uint64_t fp_audio_out_frames(const fp_audio_out *o);

/** Finish (a device: drain its buffer; a file: close and rename into place) and free *o
 *  (set to NULL). Returns 0 or the first error with err. NULL: 0. */
int fp_audio_out_close(fp_audio_out **o, char *err, size_t errlen);

/** Drop the output without finishing it (a file's temporary is removed). NULL: nothing. */
void fp_audio_out_abort(fp_audio_out **o);

/* ---- the player ----------------------------------------------------------------------------- */

typedef struct fp_audio_player {
    const fp_soundtrack *track;   /* the caller's, outlives the player */
    fp_audio_out *out;            /* the caller's */
    double offset_s;              /* the soundtrack's time at performance time 0 */
    uint64_t delivered;           /* sample frames written to out */
    float *chunk;                 /* scratch, malloc()ed */
    size_t chunk_cap;             /* in frames */
} fp_audio_player;

/** Set up *p for track and out (both the caller's), the soundtrack's time `offset_s` at the
 *  performance's time 0 (negative: silence first). */
void fp_audio_player_init(fp_audio_player *p, const fp_soundtrack *track, fp_audio_out *out,
                          double offset_s);

/** The performance reached time t_s (seconds since its start, the end of the frame just
 *  shown): write the soundtrack's samples from where the last call stopped up to soundtrack
 *  time offset_s + t_s (silence before its start and after its end). An earlier t_s writes
 *  nothing. Returns 0 or the output's error with err. */
int fp_audio_player_advance(fp_audio_player *p, double t_s, char *err, size_t errlen);

/** Skip to performance time t_s without writing (a live performance that stalled or paused:
 *  a device's blocking write would otherwise queue the whole gap and lag by it): the next
 *  advance writes from there. An earlier t_s does nothing. */
void fp_audio_player_skip(fp_audio_player *p, double t_s);

/** Free the scratch (not the track or the output). */
void fp_audio_player_free(fp_audio_player *p);

/* ---- inputs (a microphone) -------------------------------------------------------------------- */

typedef struct fp_audio_in fp_audio_in;

/** Check an input spec before any work: "file:PATH" (an emulated microphone: PATH must be a
 *  sound file libsndfile reads: fp_soundtrack_load's codes, -ENOENT, -EACCES, -EBADMSG) or a
 *  PortAudio input device ("default", an index or a case-insensitive part of its name:
 *  -ENODEV when there is none, or no sound system). -EINVAL: an empty spec. */
int fp_audio_in_check(const char *spec, char *err, size_t errlen);

/** Open the input and start capturing on its own thread: a device at its default rate, one
 *  channel; a file at its rate and channels, its sample k heard at the open's host time +
 *  k / rate (silence after its end). The last 10 s are kept, for a recording that starts
 *  in the past. Device samples are placed on the host clock at the first block (the input
 *  latency PortAudio reports subtracted); the device's own clock is not followed after that.
 *  Returns 0 and *out, or fp_audio_in_check's codes, -EIO (the device would not start),
 *  -ENOMEM, -EAGAIN (no thread), with err. [main-thread] */
int fp_audio_in_open(const char *spec, fp_audio_in **out, char *err, size_t errlen);

/** The input's sample rate (Hz) and channels; 0 for NULL. */
int fp_audio_in_rate(const fp_audio_in *in);
int fp_audio_in_channels(const fp_audio_in *in);

/** Record into a WAV at `path` (32-bit float, the input's rate and channels; written in place,
 *  a file there replaced, its header updated after every write: a process killed mid-take
 *  leaves a WAV of what was written): its sample 0 is the input's sample at host time t0_ns
 *  (silence for any time before the capture began). Returns 0, -EBUSY (recording already),
 *  or the file's code (open(2)'s -errno, -EIO) with err.
 *  Thread-safe against the capture thread; one caller at a time. */
int fp_audio_in_record(fp_audio_in *in, const char *path, int64_t t0_ns, char *err, size_t errlen);

/** End the recording at host time end_ns: waits until the input has captured up to there (2 s
 *  at most; a device that stopped: silence), writes the samples before end_ns, syncs and
 *  closes the WAV. *frames (may be NULL): the sample frames in the file, 0 on an error.
 *  Returns 0 (also when nothing records) or the first write's error (-EIO; the WAV removed)
 *  with err. */
int fp_audio_in_record_stop(fp_audio_in *in, int64_t end_ns, uint64_t *frames, char *err,
                            size_t errlen);

/** Stop the capture thread, end a recording in progress where it got (the WAV kept, its header
 *  up to date) and free *in (set to NULL). NULL: nothing. */
void fp_audio_in_close(fp_audio_in **in);

/* ---- LTC ---------------------------------------------------------------------------------- */

typedef struct fp_ltc_info {
    fp_take_rate rate;            /* 24/1, 25/1, 30000/1001 or 30/1 */
    fp_timecode first;            /* the timecode at the source's first sample (file) or at
                                     `at_ns` (device); drop as the LTC's drop-frame flag */
    int64_t at_ns;                /* device: the host time (CLOCK_MONOTONIC) of `first`;
                                     file: 0 */
    uint64_t frames;              /* LTC frames decoded */
    uint64_t jumps;               /* frames that did not follow the one before (a cut, a
                                     restart of the generator) */
    int sample_rate;
    int channel;                  /* the channel it was decoded from, 1-based (a device: 1) */
} fp_ltc_info;

/** Decode the LTC of a sound file (every channel, each with its own libltc decoder; the
 *  channel with the most frames decoded is the LTC's: info->channel): the rate from the
 *  frames' median spacing (the nearest of 24, 25, 30; at 30, 29.97 drop-frame where most
 *  frames have the drop-frame flag, else 29.97 or 30 by the mean spacing); the timecode at
 *  sample 0 from the first frame that starts three consecutive ones, carried back to the
 *  frame in progress at sample 0 (SMPTE: a frame's timecode holds from its start; a start
 *  within 5% of a period after sample 0 counts as at it) (a misread frame, the first one included, is passed over and counted as a
 *  jump; after a jump the first run counts). Needs at least 1 s of LTC. Returns 0 and
 *  *info, or -ENOENT/-EACCES/-EBADMSG (not a sound file, no LTC on any channel, less than a
 *  second of it, a rate none of those) with err. */
int fp_ltc_read_file(const char *path, fp_ltc_info *info, char *err, size_t errlen);

/** Listen to a PortAudio input device ("default", an index or part of a name) for up to
 *  `seconds` until 1.5 s of LTC decoded; info->first is the timecode at host time
 *  info->at_ns (fp_ltc_read_file's rules, the timecode from the last three consecutive
 *  frames). Returns 0, -ENODEV (no such input device), -ETIMEDOUT (no LTC heard) or
 *  -EIO with err. */
int fp_ltc_listen(const char *device, double seconds, fp_ltc_info *info, char *err,
                  size_t errlen);

/** The timecode at host time t_ns of a device's LTC (info from fp_ltc_listen): first plus
 *  the frames since at_ns. Returns 0 or -EINVAL. */
int fp_ltc_timecode_at(const fp_ltc_info *info, int64_t t_ns, fp_timecode *tc);

#ifdef __cplusplus
}
#endif
#endif
