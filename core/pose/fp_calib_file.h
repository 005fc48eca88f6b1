/*
 * fp_calib_file.h: the calibration file (docs/calibration.md), a small JSON object:
 *   { "mm_per_unit": 10.0,            // or "scale": 0.1 (mesh units per mm); one is required
 *     "rotation": [1, 0, 0, 0],       // optional, device -> mesh, quaternion w x y z
 *     "offset": [0, 0, 0],            // optional, mesh units, both hands
 *     "left":  {"offset": [x, y, z]}, // optional, per hand, added
 *     "right": {"offset": [x, y, z]} }
 * Errors: -ENOENT / -EACCES (cannot read), -EBADMSG (not JSON, a field of the wrong type or
 * length), -ERANGE (a non-finite number, a scale <= 0, a rotation of norm ~0); err names
 * the file and the field. Writing is atomic (a temporary file in the same folder with the
 * mode a new file gets under the umask, fsync, then rename: fp_file_open_output; on failure
 * an existing file is left as it was): -EACCES, -ENOENT, -EIO, -ENOSPC with the path.
 * Pure library: no printing, no shared state (any thread).
 */
#ifndef FP_CALIB_FILE_H
#define FP_CALIB_FILE_H

#include "fp_pose.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Read the calibration file `path` (a JSON object, the format above) into *c (untouched on
 *  error). Returns 0, or with a message naming the file (and line:column or the field):
 *  -EBADMSG (not valid JSON, an unknown or repeated field, a bad value; a file over 1 MiB,
 *  which no calibration is), -ERANGE (a value not finite or beyond 1e9), the file's own
 *  codes (-ENOENT, -EACCES, -EISDIR, -ENXIO: a folder, FIFO or device; fp_file_read_all),
 *  -ENOMEM, -EIO. Reentrant. */
int fp_calibration_load(const char *path, fp_calibration *c, char *err, size_t errlen);

/** Write *c to path atomically (mm_per_unit = 1 / scale, rotation, offsets; a face frame folded
 *  into them, fp_calibration_flatten); `comment` (may be NULL) goes into a "comment" field. */
int fp_calibration_save(const char *path, const fp_calibration *c, const char *comment, char *err,
                        size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
