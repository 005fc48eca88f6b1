/*
 * fp_file.h: the pieces every "write a temporary file beside the target, then rename it over"
 * of the project shares (mesh saves, exports, calibration files, PNGs, bench's --plot and
 * --trace): which file a save replaces (fp_file_target), the temporary file's name and
 * creation, and the mode a new file gets; and the one way readers open an input file
 * (fp_file_open_regular: a FIFO or a device never blocks or passes for a file). The callers keep their own writes,
 * fsync and rename (and their error messages). Link: the static library `fp_common` (PIC).
 */
#ifndef FP_FILE_H
#define FP_FILE_H

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Create the temporary file ".NAME<tag>.XXXXXX" in path's folder (NAME: path's last
 *  component; no folder: the working one), so that a rename over path is atomic. path: the
 *  target (need not exist); tag: "" or a suffix that tells a caller's several temporaries
 *  apart (NULL as ""); tmp: n bytes for the temporary's name, "" after a failure. Returns the
 *  descriptor (O_CLOEXEC, mode 0600 as mkostemp makes it; the caller owns it and the file),
 *  or a negative errno: -EINVAL (NULL argument), -ENAMETOOLONG (the name does not fit n),
 *  mkostemp's (-ENOENT no folder, -EACCES, ...). Thread-safe. */
int fp_file_temp_beside(const char *path, const char *tag, char *tmp, size_t n);

/** Open `path` for reading if it is a regular file (a symbolic link to one included), without
 *  blocking on what is not: opened O_NONBLOCK (a FIFO with no writer, a tty, a device cannot
 *  hold the open), checked by fstat, then made blocking again. Returns the descriptor
 *  (O_CLOEXEC; the caller owns it: close or fdopen it), or a negative errno: open's (-ENOENT,
 *  -EACCES, ...), -EISDIR (a folder), -ENXIO (a FIFO, device or socket: not a file to read);
 *  fp_file_error_text(code) says which in words. Thread-safe. */
int fp_file_open_regular(const char *path);

/** fp_file_open_regular as a stdio stream ("rb"): the FILE, or NULL with *code (the same
 *  negative errno; -ENOMEM from fdopen). Thread-safe. */
FILE *fp_file_fopen_regular(const char *path, int *code);

/** The file an atomic save of `path` replaces: `path` itself when it is a regular file or does
 *  not exist, or, for a symbolic link, the file at the end of its chain (the link is written
 *  through, as a shell's > does, not replaced by a file). Into real (n bytes). Returns 0, or a
 *  negative errno: -EISDIR (a folder), -ENXIO (a FIFO, device or socket: never replaced by a
 *  file; as root such a rename would delete /dev/null), -ELOOP (over 16 links), -ENAMETOOLONG
 *  (real too small), -EINVAL (NULL), lstat's others (-EACCES ...). Callers make their
 *  temporary file beside `real` and rename it over `real`. Thread-safe. */
int fp_file_target(const char *path, char *real, size_t n);

/** Words for fp_file_open_regular's and fp_file_target's codes: -EISDIR "is a folder, not a
 *  file", -ENXIO "is not a regular file (a FIFO, device or socket)", -ELOOP "too many
 *  symbolic links", others strerror's. Static text. */
const char *fp_file_error_text(int code);

/** The code an output file's failure is reported with, from the errno of the call that
 *  failed (e > 0): -ENOENT (no such folder: ENOENT, ENOTDIR), -EACCES (EACCES, EPERM, EROFS),
 *  -ENOSPC (ENOSPC, EDQUOT), -ENOMEM, else -EIO. The exports and PNG writers share it, so a
 *  full disk or a read-only folder reads the same from each. Thread-safe. */
int fp_file_output_code(int e);

/** The mode a new file gets: 0666 & ~umask, the umask read from /proc/self/status without
 *  changing it (umask() is process-wide: setting it to read it races other threads); 022 when
 *  it cannot be read. Thread-safe. */
unsigned fp_file_new_mode(void);

#ifdef __cplusplus
}
#endif
#endif
