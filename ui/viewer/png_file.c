/* png_file: a PNG written whole or not at all (png_file.h). */
#define _GNU_SOURCE
#include "png_file.h"
#include "fp_error.h"
#include "fp_file.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
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
    char tmp[4200], real[4096];
    int tr = fp_file_target(path, real, sizeof real); /* a link's end; no folder or device */
    if (tr < 0)
        return fp_errorf(err, errlen, tr == -EISDIR || tr == -ENXIO ? -EEXIST : fp_file_output_code(-tr),
                         "%s: cannot write the PNG: %s", path, fp_file_error_text(tr));
    path = real;
    int fd = fp_file_temp_beside(path, "", tmp, sizeof tmp);
    if (fd < 0)
        return fp_errorf(err, errlen, fp_file_output_code(-fd), "%s: cannot write the PNG: %s", path,
                         strerror(-fd));
    (void)fchmod(fd, (mode_t)fp_file_new_mode()); /* the mode a new file would get */
    png_sink s = {fdopen(fd, "wb"), 0};
    if (!s.f) {
        int e = errno;
        close(fd);
        unlink(tmp);
        return fp_errorf(err, errlen, fp_file_output_code(e), "%s: cannot write the PNG: %s", path,
                         strerror(e));
    }
    const size_t stride = (size_t)w * 3;
    /* bottom-up rows: start at the last row, a negative stride */
    const unsigned char *first = bottom_up ? rgb + (size_t)(h - 1) * stride : rgb;
    int ok = stbi_write_png_to_func(sink_write, &s, w, h, 3, first,
                                    bottom_up ? -(int)stride : (int)stride);
    int e = !ok ? ENOMEM : s.err; /* (the encoder fails only for its memory) */
    if (!e && (fflush(s.f) != 0 || fsync(fileno(s.f)) != 0)) e = errno;
    if (fclose(s.f) != 0 && !e) e = errno;
    if (!e && rename(tmp, path) != 0) e = errno;
    if (e) {
        unlink(tmp);
        return fp_errorf(err, errlen, fp_file_output_code(e), "%s: cannot write the PNG: %s", path,
                         strerror(e));
    }
    return 0;
}
