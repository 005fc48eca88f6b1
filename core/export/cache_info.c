/* cache_info.c: a point cache's header (fp_cache_info.h).
 * SPDX-License-Identifier: GPL-3.0-or-later */
#define _POSIX_C_SOURCE 200809L /* fseeko, fileno */
#include "fp_cache_info.h"

#include "fp_error.h"
#include "fp_file.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

static uint32_t u32_of(const unsigned char *b, bool big)
{
    return big ? (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3]
               : (uint32_t)b[3] << 24 | (uint32_t)b[2] << 16 | (uint32_t)b[1] << 8 | b[0];
}

static float f32_of(const unsigned char *b, bool big)
{
    uint32_t u = u32_of(b, big);
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

/* MDD's time of frame i (4 bytes at 8 + 4 i), NaN where the file does not hold it. */
static double mdd_time(FILE *f, double i)
{
    unsigned char t[4];
    if (fseeko(f, (off_t)(8 + 4 * i), SEEK_SET) || fread(t, 1, 4, f) != 4) return NAN;
    return f32_of(t, true);
}

int fp_cache_info_read(const char *path, fp_cache_info *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    out->t_first = out->t_second = out->t_last = NAN;
    int code;
    FILE *f = fp_file_fopen_regular(path, &code);
    struct stat st;
    if (!f || fstat(fileno(f), &st)) {
        if (f) code = -errno, fclose(f); /* (fstat's errno, before fclose may change it) */
        return fp_errorf(err, errlen, code, "cannot open: %s", fp_file_error_text(code));
    }
    unsigned char h[32] = {0};
    const size_t got = fread(h, 1, sizeof h, f);
    out->bytes = (double)st.st_size;
    int rc = 0;
    double header = 0, frame = 0;
    if (got >= 12 && !memcmp(h, "POINTCACHE2\0", 12)) {
        if (got < 32 || u32_of(h + 12, false) != 1 || (int32_t)u32_of(h + 16, false) <= 0 ||
            (int32_t)u32_of(h + 28, false) < 0) {
            rc = fp_errorf(err, errlen, -EBADMSG, "not a PC2 point cache (a header of 32 bytes, "
                           "version 1, points > 0, samples >= 0)");
        } else {
            out->points = u32_of(h + 16, false);
            out->frames = u32_of(h + 28, false);
            out->start = f32_of(h + 20, false);
            out->sampling = f32_of(h + 24, false);
            header = 32;
        }
    } else if (got >= 8 && (int32_t)u32_of(h, true) >= 0 && (int32_t)u32_of(h + 4, true) > 0) {
        out->mdd = true;
        out->frames = u32_of(h, true);
        out->points = u32_of(h + 4, true);
        header = 8 + 4 * out->frames;
        if (out->frames >= 1) out->t_first = mdd_time(f, 0);
        if (out->frames >= 2) out->t_second = mdd_time(f, 1);
        if (out->frames >= 2) out->t_last = mdd_time(f, out->frames - 1);
    } else {
        rc = fp_errorf(err, errlen, -EBADMSG, "not an MDD point cache (frames >= 0 and points > 0, "
                       "big-endian)");
    }
    fclose(f);
    if (rc) return rc;
    frame = out->points * 12;
    out->want = header + out->frames * frame;
    out->held = out->bytes >= out->want ? out->frames
                : out->bytes > header ? floor((out->bytes - header) / frame) : 0;
    return 0;
}
