/* fuzz_glove_cal.c: libFuzzer target for CyberGlove calibration files
 * (plugins/input-cyberglove/glove_cal.c: asr two-point and SENSOR GAIN OFFSET formats). The
 * input is written to a file and loaded. A load must give finite gains and offsets, a `used`
 * mask within the 22 sensors, angles that are never NaN and an inverse within the raw range;
 * a refusal a negative code and a message naming the file.
 * Seeds: tests/fuzz/corpus/fuzz_glove_cal and ../shared/data/cyberglove. */
#include "fuzz_file.h"
#include "glove_cal.h"

#include <math.h>

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_file_init("cal");
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file_write(data, size);
    fpg_cal cal;
    char err[512];
    int rc = fpg_cal_load(path, &cal, err, sizeof err);
    if (rc) {
        if (rc > 0 || !strstr(err, path)) abort();
        return 0;
    }
    if (cal.used >> FPG_SENSORS) abort();
    for (int i = 0; i < FPG_SENSORS; i++) {
        if (!isfinite(cal.gain[i]) || !isfinite(cal.offset[i])) abort();
        /* fpg_cal_angle may overflow to infinity for a huge gain (the decoder drops those);
         * it must never be NaN from finite parameters */
        for (int raw = 1; raw <= 255; raw += 127)
            if (isnan(fpg_cal_angle(&cal, i, raw))) abort();
        int clamped = 0;
        int v = fpg_cal_inverse(&cal, i, 0.5, 1, 1, 254, &clamped);
        if (v < 1 || v > 254) abort();
    }
    return 0;
}
