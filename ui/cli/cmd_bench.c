/* facepuppet bench: the command line of the CSRBF engine benchmarks (bodies in bench/). */
#include "app_util.h"
#include "command.h"
#include "fp_bench.h"

#include <stdio.h>
#include <string.h>

static void usage(FILE *f)
{
    fprintf(f,
            "usage: facepuppet bench [--quick] [--json] [--case NAME] [--help]\n\n"
            "Times the CSRBF engine (medians over repeated updates; the lowest median of 3\n"
            "rounds, 2 with --quick, as the machine may be shared) beside references measured\n"
            "in the same run. Cases:\n"
            "  table1   the paper's Table 1: planar grids of 1089, 4225, 16641, 33025 vertices\n"
            "           over 64 x 64, 10 control vectors, R = 10..80, anchored (end points move:\n"
            "           set_end_points + evaluate) and unanchored (start and end points move:\n"
            "           set_start_points + set_end_points + evaluate)\n"
            "  scale    a 1,000,000-vertex grid, 10 control vectors, every vertex in support\n"
            "  centres  1000 and 5000 random centres: factor, fresh factor-and-solve, and an\n"
            "           update that reuses the factor\n"
            "  guard    the fold-over guard's cost on the ICT face (10 and 42 fingertips, R =\n"
            "           0.06 x diagonal): update without and with it, medians, same frames\n"
            "  support  csrbf_evaluate vs csrbf_evaluate_touched (persistent output): 33,025\n"
            "           grid at R = 10 and 80, 1M and 1.8M grids with about 1%% in support\n"
            "  take     the take recorder's cost on the session thread per frame (median, p99)\n"
            "           and a take's size per minute at 60 fps\n"
            "  frame    the session's whole frame through the session API: the ICT face and\n"
            "           ICT subdivided in memory (3 midpoint levels, about 1.7M vertices), the\n"
            "           three-claps recording at its own pace, 60 frames a second, anchored;\n"
            "           medians and p99 of each stage (events, hands, distances, mapping,\n"
            "           solve, evaluate, commit), of the frame, and of the brute-force\n"
            "           fingertip distances on the same frame's hands (about 15 s)\n"
            "Columns: pairs = (vertex, centre) pairs inside the support (paper: its count);\n"
            "ms_ref = the brute-force loop (all pairs, scalar double, one thread) for the same\n"
            "update, or for 'reused' the fresh factor-and-solve; ratio = ms_ref / ms_median;\n"
            "ms_touch (table1) = the same update through csrbf_evaluate_touched with statistics\n"
            "(persistent output: only blocks in a support now or last update are written, the\n"
            "session's evaluation), checked bit for bit against csrbf_evaluate.\n"
            "  --quick  fewer repetitions (under 40 s)\n"
            "  --json   one JSON object per line: case, mode, vertices, centres, radius, pairs,\n"
            "           paper_pairs, ms_median, ms_bruteforce, ms_fresh, ms_touched, paper_fps\n"
            "           (null: none)\n"
            "  --case NAME  run one case only\n\n"
            "Exit status: 0 done, 64 usage, 70 out of memory, 1 an engine call failed.\n");
}

static int bench_main(int argc, char **argv)
{
    fp_bench_options o = {0};
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick")) {
            o.quick = true;
        } else if (!strcmp(argv[i], "--json")) {
            o.json = true;
        } else if (!strcmp(argv[i], "--case") && i + 1 < argc) {
            o.only = argv[++i];
        } else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return FP_EXIT_OK;
        } else {
            fprintf(stderr, "facepuppet bench: unknown option '%s'\n", argv[i]);
            usage(stderr);
            return FP_EXIT_USAGE;
        }
    }
    if (o.only) {
        size_t c = 0;
        while (fp_bench_cases[c] && strcmp(fp_bench_cases[c], o.only)) c++;
        if (!fp_bench_cases[c]) {
            fprintf(stderr, "facepuppet bench: unknown case '%s' (cases:", o.only);
            for (size_t k = 0; fp_bench_cases[k]; k++) fprintf(stderr, " %s", fp_bench_cases[k]);
            fprintf(stderr, ")\n");
            return FP_EXIT_USAGE;
        }
    }
    fp_plugin_path path;
    fp_app_plugin_path(&path, NULL, 0); /* the replay and anchored plugins, for 'frame' */
    o.plugin_path = &path;
    int rc = fp_bench_run(&o);
    fp_plugin_path_clear(&path);
    return fp_app_exit_code(rc, FP_APP_INPUT);
}

const fp_command fp_command_bench = {
    "bench", "time the CSRBF engine against the paper's Table 1, brute force and peers", bench_main};
