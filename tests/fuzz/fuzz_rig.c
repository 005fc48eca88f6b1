/* libFuzzer target: the rig parser on arbitrary bytes (must refuse, never crash or leak).
 * Build: clang -fsanitize=fuzzer,address tests/fuzz/fuzz_rig.c core/rig/fp_rig.c
 *        core/common/fp_error.c -Icore/rig -Icore/common -lcjson -lz -lm
 * Seeds: tests/fuzz/corpus/rig/. */
#include "fp_rig.h"

#include <stddef.h>
#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fp_rig *r = NULL;
    char err[512];
    if (fp_rig_parse((const char *)data, size, "fuzz.json", &r, err, sizeof err) == 0) {
        /* bind to a small synthetic mesh when the rig asks for a small one */
        if (fp_rig_vertex_count(r) <= 4096) {
            static float pos[4096 * 3];
            for (size_t v = 0; v < 4096; v++)
                pos[3 * v] = (float)(v % 16), pos[3 * v + 1] = (float)(v / 16 % 16), pos[3 * v + 2] = (float)(v / 256);
            if (fp_rig_bind(r, fp_rig_vertex_count(r), pos, err, sizeof err) == 0) {
                static float out[4096 * 3];
                fp_rig_pose(r, pos, NULL, out);
            }
        }
        fp_rig_free(&r);
    }
    return 0;
}
