/*
 * fp_cache_info.h: what a point cache (PC2 or MDD, as core/export writes them and Blender's
 * Mesh Cache modifier reads them) says of itself: its header, MDD's first, second and last
 * frame times, and whether the file holds all the header gives. `facepuppet info` prints it
 * (ui/cli/app_export.c); fuzz_cache (tests/fuzz) feeds it any bytes. Reads the header and
 * three times, never the frames. Link: the static library `fp_export`.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FP_CACHE_INFO_H
#define FP_CACHE_INFO_H

#include <stdbool.h>
#include <stddef.h>

typedef struct fp_cache_info {
    bool mdd;                  /* MDD (big-endian, no signature); else PC2 ("POINTCACHE2\0") */
    double points, frames;     /* as the header gives them (PC2: points, samples) */
    float start, sampling;     /* PC2: the first sample's frame, frames between samples */
    double t_first, t_second, t_last; /* MDD: frame times, s, as stored (NaN where the file
                                          holds none: no frame, a second or last missing) */
    double bytes;              /* the file's size */
    double want;               /* the size its header gives */
    double held;               /* whole frames the file holds (= frames when whole) */
} fp_cache_info;

/** Read the point cache at `path` (a regular file, fp_file_fopen_regular): PC2 by its
 *  signature, else MDD. *out is filled on 0 (the file whole when out->bytes == out->want:
 *  a cut or padded file is still described). Returns 0; -EBADMSG with "not a PC2 point cache
 *  (...)" (a signature but a header that is not 32 bytes, version 1, points > 0, samples >=
 *  0) or "not an MDD point cache (...)" (frames >= 0 and points > 0, big-endian) in err;
 *  -errno (fp_file_open_regular's) when it cannot be opened, err "cannot open: REASON".
 *  Thread-safe (no shared state). */
int fp_cache_info_read(const char *path, fp_cache_info *out, char *err, size_t errlen);

#endif
