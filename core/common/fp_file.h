/*
 * fp_file.h: the pieces every "write a temporary file beside the target, then rename it over"
 * of the project shares (mesh saves, exports, bench's --plot and --trace): the temporary
 * file's name and creation, and the mode a new file gets. The callers keep their own writes,
 * fsync and rename (and their error messages). Link: the static library `fp_common` (PIC).
 */
#ifndef FP_FILE_H
#define FP_FILE_H

#include <stddef.h>

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

/** The mode a new file gets: 0666 & ~umask, the umask read from /proc/self/status without
 *  changing it (umask() is process-wide: setting it to read it races other threads); 022 when
 *  it cannot be read. Thread-safe. */
unsigned fp_file_new_mode(void);

#ifdef __cplusplus
}
#endif
#endif
