/* fp_bench: the benchmark bodies behind `facepuppet bench` (ui/cli/cmd_bench.c parses the
 * command line and calls fp_bench_run). */
#ifndef FP_BENCH_H
#define FP_BENCH_H

#include <stdbool.h>

/** What to run. Zeroed: every case, full repetitions, a text table. */
typedef struct fp_bench_options {
    bool quick;        /* fewer repetitions (2 rounds instead of 3, about a fifth of the updates) */
    bool json;         /* one JSON object per line instead of the table */
    const char *only;  /* run this case only (one of fp_bench_cases), or NULL for all */
    const struct fp_plugin_path *plugin_path; /* where the replay and mapping plugins are
                                                 (case frame; NULL: that case is skipped) */
} fp_bench_options;

/** The case names, in the order they run; NULL-terminated. */
extern const char *const fp_bench_cases[];

/** Run the cases. Prints the table (or JSON lines) on stdout and progress on stderr.
 *  Returns 0, -EINVAL (o->only names no case), -ENOMEM (a set-up allocation failed) or
 *  FP_ENUMERIC (an engine call failed; its message is on stderr). Not thread-safe. */
int fp_bench_run(const fp_bench_options *o);

#endif
