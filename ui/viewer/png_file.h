/*
 * png_file.h: a PNG written whole or not at all, for the viewer's screenshots (viewer.c) and
 * the headless frames of `export --format png-seq` (frame_render.c): stb_image_write's
 * encoder into a temporary file beside the target with the mode a new file gets, fsync'ed and
 * renamed over the target (fp_file_open_output, fp_file_output_commit). No GL needed.
 */
#ifndef FP_PNG_FILE_H
#define FP_PNG_FILE_H

#include <stddef.h>

/** Write `rgb` (h rows of w RGB pixels, 3 bytes each, rows packed; bottom_up: the first row
 *  is the image's bottom, as glReadPixels returns it) as the PNG `path`. Whole or not at all:
 *  on failure the temporary file is removed and an existing `path` is left as it was.
 *  Returns 0, or a negative errno with err ("PATH: cannot write the PNG: REASON"): -EINVAL
 *  (w or h < 1, NULL arguments), -ENOENT (no such folder), -EACCES (not writable, read-only
 *  file system), -ENOSPC, -ENOMEM (the encoder), -EIO. The caller keeps `rgb`. Thread-safe
 *  (no shared state; stb's encoder is reentrant). */
int fp_png_write(const char *path, int w, int h, const unsigned char *rgb, int bottom_up,
                 char *err, size_t errlen);

#endif
