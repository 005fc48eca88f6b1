/*
 * replay_load.h: input-replay's loader. Reads a whole recording (Leap joint-positions CSV,
 * Leap joint-angles CSV, both read by core/hand/leapcsv.h; a Leap playback original, JSON or
 * LZ-string base64, read by core/hand/leapjson.h into the joints CSV's rows; or a facepuppet
 * event log) into a list of timed events.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef REPLAY_LOAD_H
#define REPLAY_LOAD_H

#include <facepuppet/plugin.h>
#include <facepuppet/plugin_util.h>

#include <stddef.h>
#include <stdint.h>

/** Which hands to keep (bit per fp_hand_side). Events with hand -1 are always kept. */
enum { REPLAY_HAND_LEFT = FP_HANDMASK_LEFT, REPLAY_HAND_RIGHT = FP_HANDMASK_RIGHT,
       REPLAY_HAND_BOTH = FP_HANDMASK_BOTH };

typedef enum replay_format {
    REPLAY_FORMAT_JOINTS_CSV = 1,  /* *_joints_mm.csv */
    REPLAY_FORMAT_ANGLES_CSV = 2,  /* *_cyberglove_like_angles_deg.csv */
    REPLAY_FORMAT_EVENTLOG = 3,    /* docs/eventlog.md */
    REPLAY_FORMAT_LEAP_JSON = 4    /* *.json.lz, *.json: Leap playback originals (leapjson.h) */
} replay_format;

/** One event and when it happened, in ns after the recording's first kept event. */
typedef struct replay_item {
    int64_t t_ns;
    fp_event event;   /* header.time_ns is rewritten at replay; source is set by the host */
} replay_item;

typedef struct replay_recording {
    replay_format format;
    replay_item *items;      /* count items, t_ns non-decreasing, first 0 */
    size_t count;
    size_t frames;           /* CSV rows kept (one hand, one moment), or events for a log */
    int64_t duration_ns;     /* last t_ns */
    int64_t loop_period_ns;  /* duration plus the mean step between distinct times */
    long truncated_line;     /* 0, or the unterminated last line that was dropped */
    size_t repeated;         /* CSV/JSON rows at their hand's previous row's time (a sample
                                sent twice: both kept, the later shown) */
    long first_repeat;       /* the first of them: its line (CSV), or its frame id (JSON) */
} replay_recording;

/** Read `path` in full. hands: REPLAY_HAND_* bits.
 *  Returns 0, or a negative errno code (-EBADMSG for malformed content, -ENOENT ...) after
 *  writing to err "PATH: reason" or
 *  "PATH:LINE:COLUMN: reason" (bad number, wrong column count, unknown hand_type, time going
 *  backwards, every row at one time, unknown format, no events for the hands asked for). */
int replay_load(const char *path, int hands, replay_recording *out, char *err, size_t errlen);

/** Free what replay_load allocated; leaves *rec zeroed. */
void replay_recording_free(replay_recording *rec);

/** Wrist rotation from a Leap palm normal and hand direction (device frame, need not be unit
 *  or orthogonal): the right-handed frame with +y the back of the hand (-normal) and -z toward
 *  the fingers (direction), as a unit quaternion (w, x, y, z), w >= 0. x = y cross z, so +x
 *  points toward the pinky of a right hand and the thumb of a left hand (plugin.h's "+x toward
 *  the thumb side for a right hand" would need a reflection; see docs/arch/replay.md).
 *  Returns 0, or -1 when a vector is zero, or they are parallel. */
int replay_wrist_rotation(const double normal[3], const double direction[3], float q[4]);

#endif
