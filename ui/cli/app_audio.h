/* app_audio.h: the soundtrack and timecode options of `run` and `play` (--audio,
 * --audio-out, --audio-offset, --timecode): parsed, checked before any work (a missing or
 * unreadable sound file: 66; an unknown device: 64; an output file that exists: 73), then
 * the soundtrack delivered in step with the frames (fp_audio_player) and the stage's
 * timecode handed to the take. */
#ifndef FP_CLI_APP_AUDIO_H
#define FP_CLI_APP_AUDIO_H

#include "fp_audio.h"
#include "fp_session_take.h"

#include <getopt.h>
#include <stdbool.h>
#include <stdio.h>

/** The options' getopt values (long-only; above the commands' own). */
enum { FP_APP_AUDIO_OPT = 0x300, FP_APP_AUDIO_OPT_OUT, FP_APP_AUDIO_OPT_OFFSET, FP_APP_AUDIO_OPT_TIMECODE,
       FP_APP_AUDIO_OPT_IN };
#define FP_APP_AUDIO_OPTS_COUNT 5

typedef struct fp_app_audio {
    const char *path;          /* --audio FILE (argv's) */
    const char *out_spec;      /* --audio-out SPEC; NULL: "default" where a soundtrack plays */
    double offset_s;           /* --audio-offset S: the soundtrack's time at the first frame */
    bool offset_given;
    const char *timecode;      /* --timecode system|ltc:FILE.wav|ltc:DEVICE; NULL: system */
    fp_soundtrack track;       /* loaded by fp_app_audio_prepare */
    fp_audio_out *out;
    fp_audio_player player;
    bool playing;              /* a soundtrack and its output are open */
    bool have_ltc;
    fp_ltc_info ltc;           /* --timecode ltc: what was decoded */
    char ltc_source[4200];     /* "ltc:FILE" for the take's header */
    const char *in_spec;       /* --audio-in DEVICE|file:X.wav (argv's) */
    fp_audio_in *in;           /* opened by fp_app_audio_prepare */
    char in_path[4400];        /* the WAV a take records ("" none) */
} fp_app_audio;

/** Write the options' getopt_long entries to out (FP_APP_AUDIO_OPTS_COUNT of them; with_timecode
 *  false, for play: the first three only, without --timecode and --audio-in). Returns how
 *  many were written. */
size_t fp_app_audio_longopts(struct option *out, bool with_timecode);

/** Parse one option (c as getopt_long returned it). Returns 1 when taken, 0 when c is not
 *  one of these, or FP_EXIT_USAGE (said on stderr, `cmd` naming the command). */
int fp_app_audio_parse(fp_app_audio *a, int c, const char *arg, const char *cmd);

/** The options' --help lines. */
void fp_app_audio_help(FILE *f, bool with_timecode);

/** Before the performance: load the soundtrack (--audio, or `fallback` when NULL: a take's
 *  recorded one), check and open its output (--audio-out; a soundtrack needs one, default
 *  "default"), decode --timecode ltc, open --audio-in (capturing from here on). Errors said
 *  on stderr with `cmd`. Returns 0 or the exit status: 66 a sound or LTC file missing or
 *  unreadable (file:X.wav of --audio-in too), 65 no LTC in it, or no sound file, or a sample
 *  not finite, 64 an unknown device (output
 *  or input) or a bad spec, 73 an output that exists without force or cannot be made. */
int fp_app_audio_prepare(fp_app_audio *a, const char *cmd, const char *fallback, bool force);

/** Fill a take's options from what prepare found: the soundtrack's path, crc32 and offset,
 *  and the LTC's timecode at t0_ns (a file's first sample is the performance's start; a
 *  device's timecode runs on from when it was heard) and its rate; both hold at t0_ns
 *  (o->stage_at_ns), so a take started later (run --control) gets them at its own first
 *  frame. Call before fp_session_take_start (on the take's own copy, fp_session_take.opt). */
void fp_app_audio_take_options(const fp_app_audio *a, int64_t t0_ns, fp_session_take_options *o);

/** Play the soundtrack from its start (--audio-offset) again: live, at each take's start. */
void fp_app_audio_restart(fp_app_audio *a);

/** A take started at host time origin_ns (after fp_session_take_start): --audio-in records
 *  the microphone into SLATE_TNNN.mic.wav beside it from origin_ns on (the name the take's
 *  header gives). Returns 0 or the exit status (73: the WAV cannot be made; said). */
int fp_app_audio_take_started(fp_app_audio *a, const fp_session_take *take, int64_t origin_ns,
                              const char *cmd);

/** The take ended at host time end_ns (its last frame's end): the microphone's WAV closed
 *  there; says its length unless quiet. Returns 0 or the exit status of a failed write. */
int fp_app_audio_take_stopped(fp_app_audio *a, int64_t end_ns, const char *cmd, bool quiet);

/** Whether a file's first n bytes h (12 suffice) are a sound file's signature (RIFF/RF64
 *  WAVE, FLAC, Ogg, AIFF, Sun .snd, CAF): what `info` reads with fp_app_sound_info rather
 *  than as a recording. Pure; any thread. */
bool fp_app_is_sound(const unsigned char *h, size_t n);

/** `facepuppet info` of a sound file (a soundtrack, the audio input's, an LTC recording):
 *  rate, channels, duration, peak level, crc32 (what a take records of a soundtrack), its LTC
 *  where it holds some (fp_ltc_read_file: rate and the timecode at its first sample), and the
 *  options that take it. Prints on stdout; errors on stderr. Returns the exit status (0; 65
 *  for a file libsndfile cannot read, 66 for one that cannot be opened). Loads the whole file
 *  (at most FP_SOUNDTRACK_MAX_SECONDS). Main thread (it prints). */
int fp_app_sound_info(const char *path);

/** The performance reached t_s seconds (the end of the frame shown): deliver the soundtrack
 *  up to there. Returns 0 or the exit status of a failed write (said on stderr). */
int fp_app_audio_advance(fp_app_audio *a, double t_s, const char *cmd);

/** As fp_app_audio_advance for a live performance: where the output is a device and more
 *  than 0.25 s is due at once (the frames stalled, or were paused), the gap is skipped (its
 *  sound lost, the soundtrack still at its place) rather than queued behind the device's
 *  blocking write. A file or null output gets every sample. */
int fp_app_audio_advance_live(fp_app_audio *a, double t_s, const char *cmd);

/** Close the output (a file renamed into place) and free everything; says what was written
 *  unless quiet. Returns 0 or the exit status of a failed close. */
int fp_app_audio_finish(fp_app_audio *a, const char *cmd, bool quiet);

/** export, before any frame is played: where the soundtrack of the take (header h: a take's
 *  or a stack's base layer's) goes, `anim_out` with its extension replaced by .wav (a folder
 *  output: beside it, FOLDER.wav), into wav (n bytes; "" when the take has none). A file there
 *  without force is refused, and the soundtrack itself (out.glb beside the take's out.wav)
 *  with force too. Returns 0 or 73 (said with cmd). */
int fp_app_audio_export_check(const fp_take_header *h, const char *anim_out, bool force, char *wav,
                              size_t n, const char *cmd);

/** export, after the frames: the soundtrack's samples under the exported frames, from the
 *  first one's time first_ns for duration_s seconds (the animation's length: its last
 *  frame's time + one frame period), into wav (32-bit float, the soundtrack's rate and
 *  channels): the animation's time 0 is the WAV's sample 0. A soundtrack that cannot be
 *  read is a warning (no WAV). Says what it wrote on `say` unless quiet. Returns 0 or 73 (a
 *  write failed; said). */
int fp_app_audio_export_write(const fp_take_header *h, const char *wav, int64_t first_ns,
                              double duration_s, bool force, bool quiet, FILE *say,
                              const char *cmd);

#endif
