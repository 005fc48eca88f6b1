/*
 * fp_text.h: text from outside (a take's description, names from a folder, header strings of
 * a file someone else wrote) checked or made safe before it is stored or shown: well-formed
 * UTF-8 (no overlong forms, no surrogates, nothing past U+10FFFF) and no control characters,
 * which a terminal would obey (ESC [31m recolours it) and JSON must not carry raw.
 * Link: the static library `fp_common`.
 */
#ifndef FP_TEXT_H
#define FP_TEXT_H

#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** True when s (NUL-terminated; NULL: true) is well-formed UTF-8 with no control character
 *  (U+0000..U+001F, U+007F..U+009F; tab and line feed allowed when lines is true: a note of
 *  several lines). Thread-safe. */
bool fp_text_ok(const char *s, bool lines);

/** s copied into out (n bytes, always NUL-terminated when n > 0) with every byte of an
 *  ill-formed sequence and every control character (tab and line feed too) replaced by U+FFFD, so that the result
 *  passes fp_text_ok. Returns out; a result that does not fit is cut at a whole character.
 *  s NULL: "". Thread-safe. */
char *fp_text_clean(const char *s, char *out, size_t n);

/** Where the text [p, stop) holds more than JSON's white space (space, tab, line feed,
 *  carriage return): the first other byte, or NULL when there is none (p NULL: NULL). For
 *  the readers that take one JSON value per file (rigs, calibration files). Thread-safe. */
const char *fp_text_after_space(const char *p, const char *stop);

/** The UTF-8 byte order mark (EF BB BF) that spreadsheet programs and Windows editors write at
 *  the start of a text file ("CSV UTF-8"): the length of the one at p ([p, p + len)), 3, or
 *  0 when there is none (p NULL: 0). The text readers skip it (recordings, meshes,
 *  calibration files). Thread-safe. */
size_t fp_text_bom(const char *p, size_t len);

/** The share (0..1) of something held back (a motion the contact guard scaled back) as a
 *  whole percentage for a person, into out (n bytes, NUL-terminated when n > 0): "37%", but
 *  "over 99%" from 0.995 on, where it would read "100%" beside "held back". Thread-safe. */
void fp_text_share_held(double share, char *out, size_t n);

/** The 1-based line and column of `at` in text (at within text, or at its end), for
 *  messages "FILE:LINE:COL". line or col may be NULL. Thread-safe. */
void fp_text_line_col(const char *text, const char *at, long *line, long *col);

#ifdef __cplusplus
}
#endif
#endif
