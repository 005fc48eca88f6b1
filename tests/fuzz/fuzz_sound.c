/* fuzz_sound.c: libFuzzer target for sound files, as --audio, --timecode ltc:FILE, the audio
 * input and `info` read them (core/audio: fp_soundtrack_load over libsndfile, then
 * fp_ltc_read_file over libltc). The input is written to input.wav and read by both.
 * A soundtrack loaded must have frames, channels and a rate, finite samples, and the crc32
 * of the file's bytes; an LTC read a rate of 24, 25, 29.97 or 30, a channel of the file and
 * some frames decoded. A refusal: a negative code and a message naming the file.
 * Seeds: tests/fuzz/corpus/fuzz_sound (small WAVs: 16-bit, float, 8-bit, and 1.2 s of LTC). */
#include "fuzz_file.h"
#include "fp_audio.h"

#include <math.h>
#include <zlib.h>

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_file_init("wav");
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file_write(data, size);
    char err[1024];
    fp_soundtrack st;
    int rc = fp_soundtrack_load(path, &st, err, sizeof err);
    if (rc) {
        if (rc > 0 || !strstr(err, path) || st.samples) abort();
    } else {
        if (!st.samples || st.frames == 0 || st.channels < 1 || st.rate <= 0) abort();
        for (uint64_t i = 0; i < st.frames * (uint64_t)st.channels; i++)
            if (!isfinite(st.samples[i])) abort();
        if (st.crc32 != (uint32_t)crc32(crc32(0L, Z_NULL, 0), data, (uInt)size)) abort();
        fp_soundtrack_free(&st);
    }
    fp_ltc_info info;
    rc = fp_ltc_read_file(path, &info, err, sizeof err);
    if (rc) {
        if (rc > 0 || !strstr(err, path)) abort();
        return 0;
    }
    const int64_t num = info.rate.num, den = info.rate.den;
    if (!((num == 24 && den == 1) || (num == 25 && den == 1) || (num == 30 && den == 1) ||
          (num == 30000 && den == 1001)))
        abort();
    if (info.channel < 1 || info.frames == 0 || info.sample_rate <= 0) abort();
    return 0;
}
