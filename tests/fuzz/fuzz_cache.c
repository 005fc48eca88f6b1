/* fuzz_cache.c: libFuzzer target for the point-cache reader `facepuppet info` uses
 * (core/export/cache_info.c: PC2 by signature, else MDD; the header, MDD's first, second and
 * last times). The input is written to a file and read. A read must give a header that agrees
 * with itself (points > 0, frames >= 0, the size the header gives, whole frames held within
 * the frames given, times only where an MDD holds them); a refusal -EBADMSG with its reason.
 * Seeds: tests/fuzz/corpus/fuzz_cache (a PC2 and an MDD of 2 points and 3 frames, a cut PC2). */
#include "fuzz_file.h"
#include "fp_cache_info.h"

#include <errno.h>
#include <math.h>

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_file_init("mdd");
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file_write(data, size);
    fp_cache_info c;
    char err[256];
    int rc = fp_cache_info_read(path, &c, err, sizeof err);
    if (rc) {
        if (rc != -EBADMSG || !strstr(err, "point cache")) abort();
        return 0;
    }
    if (!(c.points >= 1) || !(c.frames >= 0) || c.bytes != (double)size) abort();
    if (!(c.want >= (c.mdd ? 8 : 32)) || !(c.held >= 0) || c.held > c.frames) abort();
    if ((c.bytes >= c.want) != (c.held == c.frames)) abort();
    if (!c.mdd && (size < 32 || memcmp(data, "POINTCACHE2", 12))) abort();
    if (c.mdd && (!isnan(c.t_first) && (c.frames < 1 || size < 12))) abort();
    if (c.mdd && !isnan(c.t_last) && (c.frames < 2 || size < 8 + 4 * c.frames)) abort();
    if (!c.mdd && (!isnan(c.t_first) || !isnan(c.t_last))) abort();
    return 0;
}
