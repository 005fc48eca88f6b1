/* fp_bench: the benchmarks behind `facepuppet bench`. */
#ifndef FP_BENCH_H
#define FP_BENCH_H

/** `facepuppet bench [--quick] [--json] [--case NAME] [--help]`. argv[0] is "bench".
 *  Prints a table on stdout (with --json one JSON object per line instead), progress on
 *  stderr. Returns 0, 64 (bad command line) or 1 (an engine call failed). Not thread-safe. */
int fp_bench_main(int argc, char **argv);

#endif
