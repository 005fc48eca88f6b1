/* fp_bench: the benchmarks behind `facepuppet bench`. */
#ifndef FP_BENCH_H
#define FP_BENCH_H

/** `facepuppet bench [--quick] [--json] [--case NAME] [--help]`. argv[0] is "bench".
 *  Prints a table on stdout (with --json one JSON object per line instead), progress on
 *  stderr. Returns 0, 64 (bad command line) or 1 (an engine call failed). Not thread-safe. */
int fp_bench_main(int argc, char **argv);

#include <stdio.h>

/** `--case take` (bench/bench_take.c): the take recorder's cost on the session thread
 *  (median, p99 and max of fp_take_recorder_push per frame, 10 control vectors and 4
 *  events, while the recorder thread writes to a folder under /tmp) and a take's size per
 *  minute at 60 fps. One line of text, or one JSON object with json != 0, to `out`.
 *  quick: 4000 frames instead of 20000 (about 1 s against 5 s). Returns 0, or 1 when the
 *  take could not be written (the reason on stderr). */
int fp_bench_take(FILE *out, int quick, int json);

#endif
