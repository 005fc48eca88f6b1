/* facepuppet bench: the command line of the CSRBF engine benchmarks (bodies in bench/), and
 * --plot: the paper's Figure 3 remade from the table1 case by bench/plot_fig3.py. */
#define _GNU_SOURCE
#include "app_getopt.h"
#include "app_util.h"
#include "command.h"
#include "fp_bench.h"
#include "fp_file.h"

#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#ifndef FP_BENCH_SOURCE_DIR
#define FP_BENCH_SOURCE_DIR "bench"
#endif

static void usage(FILE *f)
{
    fprintf(f,
            "usage: facepuppet bench [--quick] [--json] [--case NAME] [--no-contact-guard]\n"
            "                        [--exact-frames] [--every-frame] [--no-rig] [--subdivide L[,L...]]\n"
            "                        [--mapping SPEC] [--trace FILE.csv] [--plot FILE.png] [--force]\n"
            "                        [--help]\n\n"
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
            "           ICT subdivided in memory (3 midpoint levels, about 1.7M vertices;\n"
            "           --subdivide for others), the three-claps recording at its own pace,\n"
            "           60 frames a second, anchored, sessions with real-time memory and\n"
            "           started as live opens them (no page fault in a frame;\n"
            "           fp_session_realtime_memory, a process-wide malloc setting, so this\n"
            "           case runs last; the ICT frames on the session's frame thread, a\n"
            "           count says how many); medians and p99 of each stage (events, hands,\n"
            "           distances, mapping, solve, evaluate, shape: the sheets, the rig's\n"
            "           blend and the reach; commit; contact), of the frame, and of the\n"
            "           brute-force fingertip distances on the same frame's hands\n"
            "           (about 30 s), and the frame's median on each CPU the stepping loop\n"
            "           was on; the contact guard's walk a check (node pairs, leaf pairs,\n"
            "           exact triangle tests, certified patches: medians). Its figures\n"
            "           follow the machine: run it idle (on the 2-core VM a run started\n"
            "           right after another had up to twice its ICT p99; the machine\n"
            "           line's chases, ns a load on each CPU at the start, show how much\n"
            "           of the caches other guests held then)\n"
            "Columns: pairs = (vertex, centre) pairs inside the support (paper: its count);\n"
            "ms_ref = the brute-force loop (all pairs, scalar double, one thread) for the same\n"
            "update, or for 'reused' the fresh factor-and-solve; ratio = ms_ref / ms_median;\n"
            "ms_touch (table1) = the same update through csrbf_evaluate_touched with statistics\n"
            "(persistent output: only blocks in a support now or last update are written, the\n"
            "session's evaluation), checked bit for bit against csrbf_evaluate. table1 ends\n"
            "with the 33,025-vertex R=80 / R=10 time ratios and the anchored update's least\n"
            "memory traffic (bytes ratio: the most the time ratio can reach at one bandwidth).\n"
            "  --quick  fewer repetitions (under 40 s)\n"
            "  --json   one JSON object per line: case, mode, vertices, centres, radius, pairs,\n"
            "           paper_pairs, ms_median, ms_bruteforce, ms_fresh, ms_touched, paper_fps\n"
            "           (null: none)\n"
            "  --case NAME  run one case only\n"
            "  --no-contact-guard  case frame: sessions without the contact guard (its\n"
            "           collide time leaves the frame; the rest of the frame alone)\n"
            "  --exact-frames  case frame: sessions without the contact guard's hold (every\n"
            "           shown frame the engine's shape bit for bit; by default a vertex that\n"
            "           moved under 1e-5 of the face's diagonal since the last frame keeps its\n"
            "           place, and its triangles go unchecked)\n"
            "  --every-frame  case frame: every frame of the recording stepped and timed, on\n"
            "           its own clock (as run steps), none skipped: a frame slower than the\n"
            "           60 fps period delays the next instead of making the loop skip periods\n"
            "           (whose hands would then come merged into one frame)\n"
            "  --no-rig  case frame: sessions without a rig (the ICT face's, found by its\n"
            "           checksum, holds the skull and the teeth still under the fingers; the\n"
            "           subdivided faces carry it, subdivided with them: a midpoint in a region\n"
            "           when both ends of its edge are, jaw weights averaged)\n"
            "  --subdivide L[,L...]  case frame: after the ICT face, ICT subdivided L times\n"
            "           (1: 105,569 vertices, 2: 419,929, 3: 1,675,289; default 3)\n"
            "  --mapping SPEC  case frame: the sessions' mapping (default anchored; e.g.\n"
            "           unanchored: a one-shot step committed every frame, composed by the\n"
            "           fold-over guard where one map would fold)\n"
            "  --trace FILE.csv  case frame: one row per frame of each mesh (stage times,\n"
            "           contact guard, commits, the 60 fps periods a slow frame made the loop\n"
            "           skip; the columns on the first line), to find what makes the p99;\n"
            "           written whole or not at all\n"
            "  --plot FILE.png  the paper's Figure 3 remade: run table1 (--quick respected; with\n"
            "           --json its rows on stdout too) and draw updates per second (log) against\n"
            "           R for the four meshes, anchored and unanchored, ours beside the paper's,\n"
            "           with plot_fig3.py (share/facepuppet/ when installed, else the source\n"
            "           tree's bench/) and matplotlib; python3 is $FACEPUPPET_PYTHON, else\n"
            "           /usr/bin/python3, else the PATH's. FILE.png is written whole or not at all\n"
            "  --force  overwrite FILE.csv or FILE.png when it exists; without it, an existing\n"
            "           one is refused before any work (73)\n\n"
            "Exit status: 0 done, 64 usage, 69 --plot without python3, matplotlib or the script,\n"
            "70 out of memory, 73 FILE.png or FILE.csv not writable or existing without --force,\n"
            "78 a plugin missing or failing\n"
            "(case frame: --mapping names no mapping plugin), 1 an engine call failed.\n");
}

/* ---- --plot: Figure 3 ------------------------------------------------------------------- */

extern char **environ;

/* The plot script: <exe dir>/../share/facepuppet/plot_fig3.py when installed, else the
 * source tree's bench/plot_fig3.py (as the rig files are found). NULL when neither exists;
 * `tried` names both. */
static const char *plot_script(char *buf, size_t len, char *tried, size_t tried_len)
{
    snprintf(buf, len, "%s/../share/facepuppet/plot_fig3.py", fp_app_exe_dir());
    snprintf(tried, tried_len, "%s", buf);
    if (access(buf, R_OK) == 0) return buf;
    snprintf(buf, len, "%s/plot_fig3.py", FP_BENCH_SOURCE_DIR);
    snprintf(tried + strlen(tried), tried_len - strlen(tried), ", %s", buf);
    return access(buf, R_OK) == 0 ? buf : NULL;
}

/* The interpreter: $FACEPUPPET_PYTHON, else Debian's /usr/bin/python3 (where
 * python3-matplotlib installs), else python3 on the PATH. */
static const char *plot_python(void)
{
    const char *env = getenv("FACEPUPPET_PYTHON");
    if (env && *env) return env;
    return access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
}

/* Run argv (argv[0] through the PATH when it has no slash) with stdin from in_fd (-1: as
 * ours) and stdout to /dev/null when quiet. Returns its exit status (128 + signal when
 * killed), or a negative errno when it could not be started (-ENOENT: no such program). */
static int spawn_wait(char *const argv[], int in_fd, bool quiet)
{
    posix_spawn_file_actions_t fa;
    if (posix_spawn_file_actions_init(&fa)) return -ENOMEM;
    if (in_fd >= 0) posix_spawn_file_actions_adddup2(&fa, in_fd, STDIN_FILENO);
    if (quiet) posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    pid_t pid;
    int rc = posix_spawnp(&pid, argv[0], &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc) return -rc;
    int st;
    while (waitpid(pid, &st, 0) < 0)
        if (errno != EINTR) return -errno;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
}

/* Start the output `path` (fp_file_open_output: the file it replaces, a link's end, never a
 * folder, FIFO or device; a temporary file beside it, so that the rename is atomic, with the
 * mode a new file gets; a stream on it with stdio_mode, NULL: none). Returns 0, or an exit
 * status with a message printed: 73 for the file (fp_app_exit_code maps -EISDIR and -ENXIO
 * on an output to it), 70 when no stream could be made. */
static int open_output(const char *path, const char *stdio_mode, fp_file_output *o)
{
    int rc = fp_file_open_output(path, "", stdio_mode, 0, o);
    switch (rc < 0 ? o->failed : FP_FILE_STEP_NONE) {
    case FP_FILE_STEP_NONE: return FP_EXIT_OK;
    case FP_FILE_STEP_TARGET:
        fprintf(stderr, "facepuppet bench: %s: cannot replace it: %s\n", path, fp_file_error_text(rc));
        break;
    case FP_FILE_STEP_TEMP:
        fprintf(stderr, "facepuppet bench: %s: cannot create a file beside it: %s\n", o->path, strerror(-rc));
        break;
    case FP_FILE_STEP_STREAM:
        fprintf(stderr, "facepuppet bench: %s: %s\n", o->path, strerror(-rc));
        return FP_EXIT_SOFTWARE;
    default:
        fprintf(stderr, "facepuppet bench: %s: cannot write it: %s\n", o->path, strerror(-rc));
        break;
    }
    return fp_app_exit_code(rc, FP_APP_OUTPUT);
}

/* An output that exists is refused before any work, as every command does (README: no
 * command overwrites a file without being asked), unless --force. Returns 0, or 73 with a
 * message naming the option and the file. */
static int refuse_existing(const char *option, const char *path, bool force)
{
    struct stat st;
    if (force || stat(path, &st)) return FP_EXIT_OK; /* (a link's end: what would be replaced) */
    fprintf(stderr, "facepuppet bench: %s %s: exists (--force to overwrite)\n", option, path);
    return FP_EXIT_CANTCREAT;
}

/* o's temporary made o->path (fsync, rename: fp_file_output_commit). Returns 0 or a negative
 * errno (a message printed). */
static int commit_output(fp_file_output *o)
{
    int rc = fp_file_output_commit(o);
    if (rc < 0) fprintf(stderr, "facepuppet bench: %s: cannot write it: %s\n", o->path, strerror(-rc));
    return rc;
}

/* `bench --plot FILE.png`: check python3, matplotlib and the output's folder first, run the
 * table1 case into an unlinked temporary file (JSON lines; echoed to stdout with --json),
 * give it to plot_fig3.py as its stdin, which writes .FILE.png.XXXXXX beside FILE.png; fsync,
 * rename. Never a half-written FILE.png. Returns an exit status. */
static int bench_plot(fp_bench_options *o, const char *png)
{
    char script[4200], tried[8500];
    if (!plot_script(script, sizeof script, tried, sizeof tried)) {
        fprintf(stderr, "facepuppet bench: the plot script plot_fig3.py is missing (looked for %s)\n",
                tried);
        return FP_EXIT_UNAVAILABLE;
    }
    const char *py = plot_python();
    char *check[] = {(char *)py, script, "--check", NULL};
    int rc = spawn_wait(check, -1, true);
    if (rc < 0 || rc == 127) {
        fprintf(stderr, "facepuppet bench: --plot needs python3 with matplotlib: cannot run '%s'%s%s "
                        "(on Debian: apt-get install python3-matplotlib; or set FACEPUPPET_PYTHON)\n",
                py, rc < 0 ? ": " : "", rc < 0 ? strerror(-rc) : "");
        return FP_EXIT_UNAVAILABLE;
    }
    if (rc == 3) { /* the script said which: matplotlib */
        fprintf(stderr, "facepuppet bench: --plot needs matplotlib for '%s' (on Debian: apt-get "
                        "install python3-matplotlib)\n", py);
        return FP_EXIT_UNAVAILABLE;
    }
    if (rc) {
        fprintf(stderr, "facepuppet bench: '%s %s --check' failed (exit %d)\n", py, script, rc);
        return FP_EXIT_FAILURE;
    }
    /* the temporary PNG beside the target (so the rename is atomic), made before the bench
     * runs so that an unwritable folder fails at once */
    fp_file_output out;
    if ((rc = open_output(png, NULL, &out))) return rc;
    png = out.path;
    const char *tmpdir = getenv("TMPDIR");
    char json_path[4200];
    snprintf(json_path, sizeof json_path, "%s/facepuppet-fig3-XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
    int json_fd = mkostemp(json_path, O_CLOEXEC);
    if (json_fd >= 0) unlink(json_path);
    int saved = -1, exit_code = FP_EXIT_OK;
    if (json_fd < 0 || fflush(stdout) || (saved = dup(STDOUT_FILENO)) < 0 ||
        dup2(json_fd, STDOUT_FILENO) < 0) {
        fprintf(stderr, "facepuppet bench: cannot make a temporary file for the JSON: %s\n", strerror(errno));
        exit_code = FP_EXIT_CANTCREAT;
        goto done;
    }
    bool echo = o->json;
    o->json = true;
    o->only = "table1";
    rc = fp_bench_run(o);
    fflush(stdout);
    dup2(saved, STDOUT_FILENO);
    if (rc) {
        exit_code = fp_app_exit_code(rc, FP_APP_INPUT);
        goto done;
    }
    if (echo) { /* --json: the rows on stdout too */
        char buf[65536];
        ssize_t got;
        lseek(json_fd, 0, SEEK_SET);
        while ((got = read(json_fd, buf, sizeof buf)) > 0) fwrite(buf, 1, (size_t)got, stdout);
        fflush(stdout);
    }
    lseek(json_fd, 0, SEEK_SET);
    char *plot[] = {(char *)py, script, "--out", out.tmp, NULL};
    rc = spawn_wait(plot, json_fd, false);
    if (rc) {
        fprintf(stderr, "facepuppet bench: %s failed (exit %d); %s not written\n", script, rc, png);
        exit_code = rc < 0 ? fp_app_exit_code(rc, FP_APP_INPUT) : rc == 3 ? FP_EXIT_UNAVAILABLE
                    : rc == 73 ? FP_EXIT_CANTCREAT : FP_EXIT_FAILURE;
        goto done;
    }
    struct stat st;
    int fs = fstat(out.fd, &st);
    if (fs || st.st_size == 0) {
        fprintf(stderr, "facepuppet bench: %s: cannot write it: %s\n", png,
                fs ? strerror(errno) : "the script wrote nothing");
        exit_code = FP_EXIT_CANTCREAT;
        goto done;
    }
    if ((rc = commit_output(&out))) {
        exit_code = fp_app_exit_code(rc, FP_APP_OUTPUT);
        goto done;
    }
    fprintf(stderr, "facepuppet bench: wrote %s (Figure 3: table1%s)\n", png, o->quick ? ", --quick" : "");
done:
    if (saved >= 0) close(saved);
    if (json_fd >= 0) close(json_fd);
    fp_file_output_abort(&out); /* (nothing left after a commit) */
    return exit_code;
}

static int bench_main(int argc, char **argv)
{
    enum { O_QUICK = 256, O_FORCE, O_JSON, O_NOGUARD, O_EXACT, O_NORIG, O_EVERY, O_SUBDIV, O_MAPPING,
           O_CASE, O_PLOT, O_TRACE };
    static const struct option opts[] = {
        {"quick", no_argument, 0, O_QUICK},           {"force", no_argument, 0, O_FORCE},
        {"json", no_argument, 0, O_JSON},             {"no-contact-guard", no_argument, 0, O_NOGUARD},
        {"exact-frames", no_argument, 0, O_EXACT},    {"no-rig", no_argument, 0, O_NORIG},
        {"every-frame", no_argument, 0, O_EVERY},     {"subdivide", required_argument, 0, O_SUBDIV},
        {"mapping", required_argument, 0, O_MAPPING}, {"case", required_argument, 0, O_CASE},
        {"plot", required_argument, 0, O_PLOT},       {"trace", required_argument, 0, O_TRACE},
        {"help", no_argument, 0, 'h'},                {0, 0, 0, 0}};
    fp_bench_options o = {0};
    const char *plot = NULL, *trace = NULL;
    bool force = false;
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, "h", opts)) != -1;) {
        switch (c) {
        case O_QUICK: o.quick = true; break;
        case O_FORCE: force = true; break;
        case O_JSON: o.json = true; break;
        case O_NOGUARD: o.no_contact_guard = true; break;
        case O_EXACT: o.exact_frames = true; break;
        case O_NORIG: o.no_rig = true; break;
        case O_EVERY: o.every_frame = true; break;
        case O_MAPPING: o.mapping = optarg; break;
        case O_CASE: o.only = optarg; break;
        case O_PLOT: plot = optarg; break;
        case O_TRACE: trace = optarg; break;
        case O_SUBDIV: {
            const char *v = optarg;
            o.subdivide = 0;
            for (;;) { /* digits only: no sign, space or hex */
                long l = 0;
                const char *d = v;
                while (*v >= '0' && *v <= '9' && l <= FP_BENCH_MAX_LEVEL) l = 10 * l + (*v++ - '0');
                if (v == d || l < 1 || l > FP_BENCH_MAX_LEVEL || (*v && *v != ',') || (*v == ',' && !v[1])) {
                    fprintf(stderr, "facepuppet bench: --subdivide '%s': levels 1 to %d, comma-separated\n",
                            optarg, FP_BENCH_MAX_LEVEL);
                    return FP_EXIT_USAGE;
                }
                o.subdivide |= 1u << l;
                if (!*v++) break;
            }
            break;
        }
        case 'h': usage(stdout); return FP_EXIT_OK;
        default: usage(stderr); return FP_EXIT_USAGE;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "facepuppet bench: unexpected argument '%s'\n", argv[optind]);
        usage(stderr);
        return FP_EXIT_USAGE;
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
    if (plot) {
        if (trace) {
            fprintf(stderr, "facepuppet bench: --plot draws the table1 case; --trace records the frame case\n");
            return FP_EXIT_USAGE;
        }
        if (o.only && strcmp(o.only, "table1")) {
            fprintf(stderr, "facepuppet bench: --plot draws the table1 case, not '%s'\n", o.only);
            return FP_EXIT_USAGE;
        }
        int ec = refuse_existing("--plot", plot, force);
        return ec ? ec : bench_plot(&o, plot);
    }
    if (o.subdivide && o.only && strcmp(o.only, "frame")) {
        fprintf(stderr, "facepuppet bench: --subdivide chooses the frame case's meshes (--case is '%s')\n", o.only);
        return FP_EXIT_USAGE;
    }
    if (trace && o.only && strcmp(o.only, "frame")) {
        fprintf(stderr, "facepuppet bench: --trace records the frame case, not '%s'\n", o.only);
        return FP_EXIT_USAGE;
    }
    /* the trace's temporary file first, so that an unwritable folder fails before the work */
    fp_file_output out = {.fd = -1};
    if (trace) {
        int ec = refuse_existing("--trace", trace, force);
        if (!ec) ec = open_output(trace, "w", &out);
        if (ec) return ec;
        trace = out.path;
        o.trace = out.f;
    }
    fp_plugin_path path;
    fp_app_plugin_path(&path, NULL, 0); /* the replay and anchored plugins, for 'frame' */
    o.plugin_path = &path;
    int rc = fp_bench_run(&o);
    fp_plugin_path_clear(&path);
    int exit_code = fp_app_exit_code(rc, FP_APP_INPUT);
    if (o.trace) {
        int wrc = 0;
        if (!rc && (fflush(o.trace) || ferror(o.trace))) {
            wrc = -(errno ? errno : EIO);
            fprintf(stderr, "facepuppet bench: %s: cannot write it: %s\n", trace, strerror(-wrc));
        }
        if (!rc && !wrc) wrc = commit_output(&out);
        if (!rc && !wrc)
            fprintf(stderr, "facepuppet bench: wrote %s (the frame case, a row per frame)\n", trace);
        if (wrc) exit_code = fp_app_exit_code(wrc, FP_APP_OUTPUT);
        fp_file_output_abort(&out); /* (after a commit: nothing) */
    }
    return exit_code;
}

const fp_command fp_command_bench = {
    "bench", "time the CSRBF engine against the paper's Table 1, brute force and peers", bench_main};
