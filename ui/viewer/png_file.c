/* png_file: a PNG written whole or not at all (png_file.h). */
#define _GNU_SOURCE
#include "png_file.h"
#include "fp_error.h"
#include "fp_file.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stb_image_write.h>

typedef struct {
    FILE *f;
    int err; /* the first write's errno, 0 while all went */
} png_sink;

static void sink_write(void *ctx, void *data, int size)
{
    png_sink *s = ctx;
    if (s->err || size <= 0) return;
    if (fwrite(data, 1, (size_t)size, s->f) != (size_t)size) s->err = errno ? errno : EIO;
}

int fp_png_write(const char *path, int w, int h, const unsigned char *rgb, int bottom_up,
                 char *err, size_t errlen)
{
    if (!path || !rgb || w < 1 || h < 1)
        return fp_errorf(err, errlen, -EINVAL, "%s: cannot write the PNG: no image (%d x %d)",
                         path ? path : "(no path)", w, h);
    fp_file_output o;
    int rc = fp_file_open_output(path, "", "wb", 0, &o); /* a link's end; no folder or device */
    if (rc < 0 && o.failed == FP_FILE_STEP_TARGET)
        return fp_errorf(err, errlen, rc == -EISDIR || rc == -ENXIO ? -EEXIST : fp_file_output_code(-rc),
                         "%s: cannot write the PNG: %s", path, fp_file_error_text(rc));
    if (rc < 0) /* the temporary beside the file: named by the file */
        return fp_errorf(err, errlen, fp_file_output_code(-rc), "%s: cannot write the PNG: %s", o.path,
                         strerror(-rc));
    png_sink s = {o.f, 0};
    const size_t stride = (size_t)w * 3;
    /* bottom-up rows: start at the last row, a negative stride */
    const unsigned char *first = bottom_up ? rgb + (size_t)(h - 1) * stride : rgb;
    int ok = stbi_write_png_to_func(sink_write, &s, w, h, 3, first,
                                    bottom_up ? -(int)stride : (int)stride);
    int e = !ok ? ENOMEM : s.err; /* (the encoder fails only for its memory) */
    if (e) fp_file_output_abort(&o);
    else e = -fp_file_output_commit(&o);
    if (e)
        return fp_errorf(err, errlen, fp_file_output_code(e), "%s: cannot write the PNG: %s", o.path,
                         strerror(e));
    return 0;
}
