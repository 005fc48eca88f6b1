/* fuzz_calib.c: libFuzzer target for the calibration file (core/pose/fp_calib_file.c, JSON,
 * docs/calibration.md). The input is written to a file and loaded. A load must give a finite
 * scale > 0, a unit rotation quaternion and finite offsets, and must survive a round trip:
 * fp_calibration_save, then fp_calibration_load again gives the same values (to 1e-12
 * relative). A refusal: a negative code and a message naming the file.
 * Seeds: tests/fuzz/corpus/fuzz_calib. */
#include "fuzz_file.h"
#include "fp_calib_file.h"

#include <math.h>

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_file_init("json");
    return 0;
}

static int close_to(double a, double b)
{
    return fabs(a - b) <= 1e-12 * fmax(1.0, fmax(fabs(a), fabs(b)));
}

static void check(const fp_calibration *c)
{
    if (!isfinite(c->scale) || !(c->scale > 0)) abort();
    double n = 0;
    for (int i = 0; i < 4; i++) {
        if (!isfinite(c->rotation[i])) abort();
        n += c->rotation[i] * c->rotation[i];
    }
    if (fabs(n - 1) > 1e-9) abort();
    for (int i = 0; i < 3; i++)
        if (!isfinite(c->offset[i]) || !isfinite(c->hand_offset[0][i]) ||
            !isfinite(c->hand_offset[1][i]))
            abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file_write(data, size);
    fp_calibration c, d;
    char err[512];
    int rc = fp_calibration_load(path, &c, err, sizeof err);
    if (rc) {
        if (rc > 0 || !strstr(err, path)) abort();
        return 0;
    }
    check(&c);
    if (fp_calibration_save(fuzz_file_path2, &c, "fuzz", err, sizeof err)) abort();
    if (fp_calibration_load(fuzz_file_path2, &d, err, sizeof err)) abort();
    check(&d);
    if (!close_to(c.scale, d.scale)) abort();
    for (int i = 0; i < 4; i++)
        if (!close_to(c.rotation[i], d.rotation[i])) abort();
    for (int i = 0; i < 3; i++)
        if (!close_to(c.offset[i], d.offset[i]) || !close_to(c.hand_offset[0][i], d.hand_offset[0][i]) ||
            !close_to(c.hand_offset[1][i], d.hand_offset[1][i]))
            abort();
    return 0;
}
