/*
 * leapjson.h: the reader of Leap Motion playback recordings, the originals beside the CSVs in
 * shared/data/hands/leap-motion (*.json.lz): leapjs-playback's JSON frames (formats 0.1 and 1,
 * and its packed format 2; Leap protocol 6), plain (*.json) or compressed with LZ-string's
 * compressToBase64 (*.json.lz).
 * Each hand of each frame is handed on as one row of the joints CSV (leapcsv.h), so that
 * `replay:` reads an original as it reads its conversion. Used by the replay input plugin
 * (static library `fp_leapjson`, PIC, hidden symbols).
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * What a recording must be: one JSON object with "frames", an array of frame objects, each
 * with "timestamp" (an integer of microseconds, never smaller than the frame before's,
 * within +-FP_LEAPCSV_TIME_MAX_US), "hands" (objects with "id", "type" "left" or "right",
 * "palmPosition", "palmNormal" and "direction", three numbers each) and "pointables"
 * (objects with "handId", "type" 0 thumb .. 4 pinky, and "mcpPosition", "pipPosition",
 * "dipPosition", "tipPosition"; tools, "tool": true, are passed over; without "type", Leap's
 * rule that a finger's "id" is 10 x its hand's id + its type gives it). Each hand has each of
 * the five fingers once. Every position within FP_EVENT_MAX_MM (10 m) of the tracker. Other
 * fields are ignored. Format 2 (metadata.formatVersion 2, as leapjs-playback 0.2 saves): frames[0]
 * is the packing structure (names, nested lists and {name: [...]}), each later frame an array of
 * values in its order, unfolded as recording.js's unPackArray does; rows count its frames from
 * frames[1] as frame 0, messages name the file's own index. The compressed text is LZ-string's base64 alphabet (A-Z a-z 0-9 + / =), white
 * space at its end allowed, at most FP_LEAPJSON_MAX_PACKED bytes, and decompresses to at most
 * FP_LEAPJSON_MAX_TEXT bytes (a stream that grows past it is refused: LZ's output can be
 * quadratic in its input).
 *
 * Rows (fp_leapcsv_row, format FP_LEAPCSV_JOINTS): frame = the frame's index in "frames",
 * timestamp_us, hand_id, side; value[] the palm, normal, direction and the fingers' mcp, pip,
 * dip and tip (the Leap thumb's "mcp" is its CMC joint, as in the CSV); valuef[] = (float)
 * value[] (the CSV's are strtof of its text: they agree to the CSV's 4 decimals); line 0 and
 * col[] 0 (a JSON file has no row lines: messages name the JSON path instead). The CSVs in
 * shared/data were made from these files by others: tests/hand/test_leapjson compares the two.
 *
 * Errors (core/common/fp_error.h), messages "FILE: reason" naming the JSON path where there is
 * one ("FILE: frames[12].hands[0].palmNormal: expected 3 numbers"): -EBADMSG for malformed
 * content (bad base64 at byte N, a cut stream, a bad code, bad JSON near line L of the
 * decompressed text, a missing or wrong field); -EFBIG for a text past the limit; the file's
 * own codes (fp_file_read_all: -ENOENT, -EISDIR, -ENXIO ...); -EIO; -ENOMEM. Never crashes on
 * any bytes (fuzzed through tests/fuzz/fuzz_replay). Threads: reentrant, [any-thread].
 */
#ifndef FP_LEAPJSON_H
#define FP_LEAPJSON_H

#include <stdbool.h>
#include <stddef.h>

#include "leapcsv.h"

/** The largest plain or decompressed JSON text read, and the largest compressed file, in
 *  bytes (the four originals in shared/data are 0.3-0.8 MB, 2-10 MB decompressed; the
 *  decoder's dictionary takes up to about 12 bytes a compressed bit's worth of codes). */
#define FP_LEAPJSON_MAX_TEXT ((size_t)256 << 20)
#define FP_LEAPJSON_MAX_PACKED ((size_t)16 << 20)

/** Decode LZ-string's compressToBase64 output (lz-string 1.x, pieroxy): `len` bytes of `in`
 *  (trailing white space ignored) into UTF-8 text (its UTF-16 code units joined, a pair of
 *  surrogates as one character, a lone one as U+FFFD), at most max_out bytes. On success
 *  *out (NUL-ended, free() it) holds *out_len bytes; "Q===" (the empty string) gives 0.
 *  Returns 0, -EBADMSG (why: "not base64 at byte N", "the stream ends before its end
 *  mark", "bad code C"), -EFBIG (past max_out), -ENOMEM; -EINVAL for NULL. why (whylen
 *  bytes, may be NULL) says what, with no file name. Reentrant. */
int fp_lzstring_decode_base64(const char *in, size_t len, size_t max_out, char **out,
                              size_t *out_len, char *why, size_t whylen);

/** Read the recording at `path` (plain JSON when its first non-blank byte is '{', else
 *  LZ-string base64) and call fn for each hand of each frame, in order. Returns 0, fn's
 *  non-zero code, or a negative code (above) with err "path: reason". */
int fp_leapjson_read(const char *path, fp_leapcsv_row_fn fn, void *user, char *err, size_t errlen);

/** Whether a file's first bytes (head: NUL-ended, up to 63 of them or the whole file) look like
 *  a Leap playback recording: '{' after blanks or a UTF-8 BOM, or only LZ-string's base64
 *  alphabet, 16 characters or more (a word is not a recording), to the end of the head or of
 *  a short file (then blanks). How `replay:` and fp-osc-send tell it from a CSV. */
bool fp_leapjson_looks_like(const char *head);

/** fp_leapjson_read into rows, as fp_leapcsv_read_joints reads a CSV: *rows (free() it)
 *  holds *n >= 1 rows; a recording without hands is -EBADMSG. */
int fp_leapjson_read_joints(const char *path, fp_leap_joints_row **rows, size_t *n, char *err,
                            size_t errlen);

#endif
