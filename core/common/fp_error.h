/*
 * fp_error.h: the one error convention of facepuppet (docs/architecture.md, "Errors").
 *
 * Every fallible function of the project returns 0 (or a count) on success and a negative
 * code on failure: a negative errno value (-EINVAL, -ENOENT, -EBADMSG, -EIO, -ENOMEM,
 * -ENOSPC, -ENOTSUP, ...) or one of the project's own codes below (FP_E*, all below -1000).
 * The human-readable detail goes into a caller-owned message buffer `char *err, size_t
 * errlen` (always NUL-terminated when errlen > 0), naming the file and line, the field, the
 * SPEC or the plugin at fault. Libraries never print; the programs in ui/ print, and choose
 * their exit codes from the code alone (never from the text).
 *
 * Which errno means what, project-wide:
 *   -EINVAL   a bad argument or option (usage)          -ENOENT   a file that is not there
 *   -EBADMSG  a file or stream whose content is malformed -EIO      a read or write failed
 *   -EACCES   a file that cannot be read or written     -ENOSPC   the disk is full
 *   -ENOMEM   out of memory                              -ENOTSUP  a format or feature we lack
 *   -ERANGE   a value outside its documented range       -EEXIST   an output that must not
 *                                                                    be overwritten
 *   -EDOM     degenerate geometry (a zero vector or quaternion, coincident points)
 * Thread rules: every function here is reentrant and [any-thread].
 * Link: the static library `fp_common` (PIC), which plugins may link too.
 */
#ifndef FP_ERROR_H
#define FP_ERROR_H

#include <facepuppet/errors.h>

#include <stdarg.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The project's own codes, for failures errno has no word for (FP_EPLUGIN_NOT_FOUND ...
 * FP_EPLUGIN_FAULT, FP_ENUMERIC), are part of the plugin ABI: defined once in the installed
 * facepuppet/errors.h, which plugins see too. */

/** A static, never-NULL description of `code` (0, a negative errno or an FP_E* code). */
const char *fp_strerror(int code);

/** True when `code` is one of the FP_EPLUGIN_* codes. */
int fp_error_is_plugin(int code);

/** Write printf-style text into err (errlen bytes, truncated, NUL-terminated; nothing when
 *  err is NULL or errlen is 0) and return `code`, so that a failure reads
 *  `return fp_errorf(err, errlen, -EBADMSG, "%s:%d: bad number", path, line);`. The message
 *  is one line a terminal may show: what it quotes of a file or a sender (a token, a field)
 *  keeps its well-formed UTF-8, and a control character (an escape sequence that would
 *  recolour the terminal, a line break) or ill-formed byte becomes U+FFFD (fp_text_clean);
 *  so do fp_error_prefix and fp_error_at. */
int fp_errorf(char *err, size_t errlen, int code, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
int fp_verrorf(char *err, size_t errlen, int code, const char *fmt, va_list ap);

/** Put `fmt...` in front of the message already in err ("PREFIX: old message"), for a
 *  caller that adds context (a file name, a SPEC) to a callee's message. Returns `code`. */
int fp_error_prefix(char *err, size_t errlen, int code, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/** The project's message for a place in a file: "PATH:LINE:COL: text" (line > 0, col > 0),
 *  "PATH:LINE: text" (col <= 0) or "PATH: text" (line <= 0), written like fp_errorf.
 *  Returns `code`. */
int fp_error_at(char *err, size_t errlen, int code, const char *path, long line, long col,
                const char *fmt, ...) __attribute__((format(printf, 7, 8)));

#ifdef __cplusplus
}
#endif
#endif
