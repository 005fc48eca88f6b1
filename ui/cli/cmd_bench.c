/* facepuppet bench: CSRBF engine benchmarks (bench/bench.c). */
#include "command.h"
#include "fp_bench.h"

const fp_command fp_command_bench = {
    "bench", "time the CSRBF engine against the paper's Table 1, brute force and peers",
    fp_bench_main};
