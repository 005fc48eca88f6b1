#define _GNU_SOURCE
#include "app_util.h"
#include "fp_text.h"

#include "command.h"
#include "fp_error.h"
#include "fp_stats.h"
#include "fp_file.h"
#include "fp_mesh.h"
#include "fp_session_take.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>
#include <dirent.h>
#include <sys/stat.h>
#include <sys/statvfs.h>

#ifndef FP_PLUGIN_RELDIR
#define FP_PLUGIN_RELDIR "../lib/facepuppet"
#endif
#ifndef FP_SHARED_DATA
#define FP_SHARED_DATA "../shared/data"
#endif

const char *fp_app_builtin_plugin_dir(char *buf, size_t len)
{
    snprintf(buf, len, "%s/%s", fp_app_exe_dir(), FP_PLUGIN_RELDIR);
    return buf;
}

void fp_app_plugin_path(fp_plugin_path *path, const char *const *dirs, size_t ndirs)
{
    char builtin[4200];
    fp_app_builtin_plugin_dir(builtin, sizeof builtin);
    fp_plugin_path_init(path, dirs, ndirs, builtin);
    /* a --plugin-dir that is no folder is said (it was searched in silence, and a plugin
     * "not found" in it read as the plugin's fault) */
    for (size_t i = 0; i < ndirs; i++) {
        struct stat st;
        const bool there = dirs[i] && !stat(dirs[i], &st);
        if (dirs[i] && (!there || !S_ISDIR(st.st_mode)))
            fprintf(stderr, "facepuppet: warning: --plugin-dir %s: %s\n", dirs[i],
                    there ? "not a folder" : "no such folder");
    }
    /* Folders skipped for safety are said once, each on its own line. */
    for (const char *w = path->warnings; *w;) {
        const char *nl = strchr(w, '\n');
        int n = nl ? (int)(nl - w) : (int)strlen(w);
        fprintf(stderr, "facepuppet: warning: %.*s\n", n, w);
        w += n + (nl ? 1 : 0);
    }
}

#ifdef FP_BUILD_BIN_DIR
/* Whether folders a and b are the same one (device and inode). */
static bool same_dir(const char *a, const char *b)
{
    struct stat sa, sb;
    return !stat(a, &sa) && !stat(b, &sb) && S_ISDIR(sa.st_mode) && sa.st_dev == sb.st_dev &&
           sa.st_ino == sb.st_ino;
}
#endif

const char *fp_app_data_root(char *buf, size_t len)
{
    const char *env = getenv("FP_SHARED_DATA");
    if (env && *env) {
        snprintf(buf, len, "%s", env);
        return buf;
    }
    struct stat st;
    snprintf(buf, len, "%s/../share/facepuppet/data", fp_app_exe_dir());
    if (!stat(buf, &st) && S_ISDIR(st.st_mode)) return buf;
#ifdef FP_BUILD_BIN_DIR
    /* the build tree's binary: the folder the build was configured with */
    if (same_dir(fp_app_exe_dir(), FP_BUILD_BIN_DIR)) {
        snprintf(buf, len, "%s", FP_SHARED_DATA);
        return buf;
    }
#endif
    return NULL;
}

const char *fp_app_data_path(const char *cmd, const char *rel, char *buf, size_t len)
{
    char root[4096];
    if (!fp_app_data_root(root, sizeof root)) {
        fprintf(stderr, "%s: no shared data folder for %s: set FP_SHARED_DATA to the folder that "
                "holds faces/ and hands/ (or put it at %s/../share/facepuppet/data), or give the "
                "file yourself\n", cmd, rel, fp_app_exe_dir());
        return NULL;
    }
    int n = snprintf(buf, len, "%s/%s", root, rel);
    if (n < 0 || (size_t)n >= len) {
        fprintf(stderr, "%s: the shared data folder's path is too long: %s\n", cmd, root);
        return NULL;
    }
    return buf;
}

int fp_app_exit_code(int code, fp_app_io io)
{
    if (fp_error_is_plugin(code)) return FP_EXIT_PLUGIN;
    switch (-code) {
    case 0: return FP_EXIT_OK;
    case EINVAL: return FP_EXIT_USAGE;
    case EBADMSG: case ERANGE: case EDOM: case EPROTO: case ENOTSUP: case EILSEQ:
        return FP_EXIT_DATAERR;
    case ENOENT: case EACCES: case EPERM: case ENODEV: case ENXIO: case EBUSY: case ENOTDIR:
    case EISDIR: case ENAMETOOLONG: case ELOOP:
        return io == FP_APP_OUTPUT ? FP_EXIT_CANTCREAT : FP_EXIT_NOINPUT;
    case EIO: case ENOSPC: case EROFS: case EDQUOT: case EFBIG: case EEXIST: return FP_EXIT_CANTCREAT;
    case ENOMEM: return FP_EXIT_SOFTWARE;
    default: return FP_EXIT_FAILURE;
    }
}

/* The take a `take:FILE` SPEC performs, opened, and the SPEC parsed into *spec (fp_spec_clear
 * it in any case); NULL for another input, a SPEC that does not parse or a take that does not
 * open (the plugin says why when the session opens it). */
static fp_take_reader *open_take(const char *text, fp_spec *spec)
{
    char err[512];
    fp_take_reader *r = NULL;
    memset(spec, 0, sizeof *spec);
    if (strncmp(text, "take:", 5) || fp_spec_parse(text, spec, err, sizeof err) || !spec->arg ||
        fp_take_reader_open(spec->arg, &r, err, sizeof err))
        return NULL;
    return r;
}

static bool spec_has(const fp_spec *spec, const char *key)
{
    for (size_t i = 0; i < spec->nparams; i++)
        if (spec->params[i].key && !strcmp(spec->params[i].key, key)) return true;
    return false;
}

/* A recorded SPEC's performer= (into name) and calibration= (into cal, when not NULL): "" where
 * it has none or does not parse. */
static void recorded_keys(const char *text, char *name, size_t nlen, char *cal, size_t clen)
{
    fp_spec spec;
    char err[256];
    name[0] = '\0';
    if (cal) cal[0] = '\0';
    if (!text || fp_spec_parse(text, &spec, err, sizeof err)) return;
    const char *p = fp_spec_take(&spec, "performer"), *c = fp_spec_take(&spec, "calibration");
    if (p) snprintf(name, nlen, "%s", p);
    if (c && cal) snprintf(cal, clen, "%s", c);
    fp_spec_clear(&spec);
}

/* How many performers a take's inputs were: the first input's is the first, inputs without
 * performer= join it, and each name met for the first time opens the next (as
 * fp_performers_assign gives them). */
static size_t take_performers(const fp_take_header *h)
{
    char names[FP_TAKE_MAX_INPUTS][FP_PERFORMER_NAME_MAX + 2];
    size_t count = 0;
    for (size_t i = 0; i < h->input_count && i < FP_TAKE_MAX_INPUTS; i++) {
        char name[sizeof names[0]];
        recorded_keys(h->inputs[i], name, sizeof name, NULL, 0);
        if (i && !name[0]) continue; /* the first performer's */
        size_t k = 0;
        while (k < count && strcmp(names[k], name)) k++;
        if (k == count) memcpy(names[count++], name, sizeof name);
    }
    return count;
}

/* The recorded placement of a take: from format 1.3 each performer's (the first's as
 * so->calibration, the others' by name as so->performer_calibrations), before it the first
 * performer's scale and offset (the right hand's where both). */
static void take_calibration(const fp_take_header *h, fp_session_options *so, fp_app_inputs *buf)
{
    /* 1.3: each performer's placement whole, the first's for every performer as before, the
     * others' by name (a take of several performers comes back split: each keeps theirs) */
    for (size_t k = 0; k < h->performer_count && k < FP_PERFORMER_CAPACITY; k++) {
        const fp_take_performer *p = &h->performers[k];
        fp_calibration c = {.scale = p->scale};
        memcpy(c.rotation, p->rotation, sizeof c.rotation);
        memcpy(c.offset, p->offset, sizeof c.offset);
        memcpy(c.hand_offset, p->hand_offset, sizeof c.hand_offset);
        if (!k) {
            buf->take_calibration = c;
            so->calibration = &buf->take_calibration;
            continue;
        }
        fp_session_performer_placement *pp = &buf->performers[so->performer_calibration_count++];
        snprintf(buf->performer_names[k], sizeof buf->performer_names[k], "%s", p->name);
        pp->name = buf->performer_names[k];
        pp->calibration = c;
        so->performer_calibrations = buf->performers;
    }
    for (int hand = FP_HANDS - 1; hand >= 0 && !so->calibration; hand--) { /* (before 1.3) */
        const fp_take_calibration *c = &h->calibration[hand];
        if (!c->present || !(c->scale > 0)) continue;
        buf->take_calibration.scale = c->scale;
        memcpy(buf->take_calibration.offset, c->offset, sizeof c->offset);
        so->calibration = &buf->take_calibration;
    }
}

/* The take inputs of take h's inputs, one each, into ins (at *n, *made of buf->takes used):
 * the user's SPEC text, ",source=K", and the recorded SPEC's performer= and calibration= (a
 * calibration file that cannot be read is left out: that performer is then placed as the
 * others). Returns 0, or 64 with the line printed: more than FP_SESSION_MAX_INPUTS (rest: the
 * --input after this one), or a SPEC too long. */
static int split_take(const char *cmd, const char *text, const fp_take_header *h, size_t rest,
                      const char **ins, size_t *n, fp_app_inputs *buf, size_t *made)
{
    if (*n + h->input_count + rest > FP_SESSION_MAX_INPUTS) {
        const size_t np = take_performers(h);
        fprintf(stderr, "%s: --input %s: the take has %zu inputs (%zu performer%s), one take input "
                "each (source=N): %zu --input in all, at most %d\n", cmd, text, h->input_count, np,
                np == 1 ? "" : "s", *n + h->input_count + rest, FP_SESSION_MAX_INPUTS);
        return FP_EXIT_USAGE;
    }
    for (size_t k = 0; k < h->input_count; k++) {
        char name[FP_PERFORMER_NAME_MAX + 2], cal[1100];
        recorded_keys(h->inputs[k], name, sizeof name, cal, sizeof cal);
        if (cal[0] && access(cal, R_OK)) cal[0] = '\0';
        char *out = buf->takes[(*made)++];
        int len = snprintf(out, sizeof buf->takes[0], "%s,source=%zu%s%s%s%s", text, k + 1,
                           name[0] ? ",performer=" : "", name, cal[0] ? ",calibration=" : "", cal);
        if (len < 0 || (size_t)len >= sizeof buf->takes[0]) {
            fprintf(stderr, "%s: --input %s: too long to perform the take's input %zu\n", cmd, text,
                    k + 1);
            return FP_EXIT_USAGE;
        }
        ins[(*n)++] = out;
    }
    return 0;
}

int fp_app_session_defaults(const char *cmd, fp_session_options *so, double speed, fp_app_inputs *buf,
                            bool *demo_out)
{
    bool demo = !so->mesh_path && !so->input_count;
    if (demo_out) *demo_out = demo;
    if (!so->mesh_path &&
        !(so->mesh_path = fp_app_data_path(cmd, "faces/ict-facekit/generic_neutral_mesh.obj",
                                           buf->demo_mesh, sizeof buf->demo_mesh)))
        return FP_EXIT_NOINPUT;
    if (demo) {
        char rec[4000];
        if (!fp_app_data_path(cmd, "hands/leap-motion/three-claps_joints_mm.csv", rec, sizeof rec))
            return FP_EXIT_NOINPUT;
        snprintf(buf->demo_input, sizeof buf->demo_input, "replay:%s", rec);
        so->inputs[so->input_count++] = buf->demo_input;
    }
    if (!so->mapping) so->mapping = "anchored";
    /* where the rigs' meshes lie: a glTF copy of a rig's mesh, split at seams, finds its rig */
    if (!so->rig_mesh_root) so->rig_mesh_root = fp_app_data_root(buf->data_root, sizeof buf->data_root);
    for (size_t i = 0; i < so->input_count; i++) {
        const char *in = so->inputs[i];
        bool paced = (!strncmp(in, "replay", 6) && (in[6] == ':' || in[6] == ',' || !in[6])) ||
                     (!strncmp(in, "take", 4) && (in[4] == ':' || in[4] == ','));
        if (speed != 1 && paced && !strstr(in, ",speed=")) {
            snprintf(buf->specs[i], sizeof buf->specs[i], "%s,speed=%g", in, speed);
            so->inputs[i] = buf->specs[i];
        }
    }
    /* A take performed again: its hands where the take had them (the recorded calibration);
     * a take of two or more inputs, unless the SPEC picks a source= or a performer=: one take
     * input for each of its inputs, each with its performer as recorded, so that their hands
     * stay theirs (issue 55) and each input's state (its filter, its clock) is its own again,
     * as in the run that recorded it (one input for all of them did not give that run's
     * shapes, even with one performer). */
    const char *ins[FP_SESSION_MAX_INPUTS];
    size_t n = 0, made = 0;
    int rc = 0;
    for (size_t i = 0; i < so->input_count && !rc; i++) {
        fp_spec spec;
        fp_take_reader *r = open_take(so->inputs[i], &spec);
        const fp_take_header *h = r ? fp_take_reader_header(r) : NULL;
        if (h && !so->calibration) take_calibration(h, so, buf);
        if (h && !spec_has(&spec, "source") && !spec_has(&spec, "performer") && h->input_count > 1)
            rc = split_take(cmd, so->inputs[i], h, so->input_count - i - 1, ins, &n, buf, &made);
        else
            ins[n++] = so->inputs[i];
        fp_take_reader_close(&r);
        fp_spec_clear(&spec);
    }
    if (rc) return rc;
    memcpy(so->inputs, ins, n * sizeof ins[0]);
    so->input_count = n;
    return 0;
}

fp_take_rate fp_app_take_rate(double fps)
{
    if (fps == floor(fps)) return (fp_take_rate){(uint32_t)fps, 1};
    /* the NTSC rates as written (23.976, 29.97, 59.94) and as computed (30000/1001.0): the
     * nearest N*1000/1001 within 0.005 (was: fps * 1001 a whole number, which 29.97 is not) */
    if (fabs(fps - round(fps) * 1000 / 1001) < 0.005)
        return (fp_take_rate){(uint32_t)round(fps) * 1000, 1001};
    return (fp_take_rate){(uint32_t)llround(fps * 1000), 1000};
}

void fp_app_print_take(FILE *f, const char *prefix, const fp_session_take_result *r)
{
    char in[32], out[32];
    fp_timecode_format(&r->timecode_in, in, sizeof in);
    fp_timecode_format(&r->timecode_out, out, sizeof out);
    fprintf(f, "%s: take %s: %llu frames, %llu dropped, timecode %s - %s%s\n", prefix, r->path,
            (unsigned long long)r->frames, (unsigned long long)r->dropped, in, out,
            r->error ? " (stopped by an error)" : "");
}

void fp_app_open_progress_init(fp_app_open_progress *p, const char *cmd, bool quiet)
{
    *p = (fp_app_open_progress){cmd, !quiet && isatty(STDERR_FILENO), false, 0, "opening", "opened"};
}

/* The status line on the screen, if any (fp_app_log_line erases it before a line of its own
 * and draws it again after: a warning while a face opens ran into it). */
static char status_line[1024];
static bool status_shown;

void fp_app_open_progress_fn(void *user, const char *stage)
{
    fp_app_open_progress *p = user;
    if (!p->on) return;
    if (stage) {
        if (!p->shown) p->t0 = fp_now_ns();
        snprintf(status_line, sizeof status_line, "%s: %s: %s ...", p->cmd, p->phase, stage);
        /* \r and "erase to the end of the line" (ECMA-48 EL): the last step's text goes */
        fprintf(stderr, "\r\033[K%s", status_line);
        fflush(stderr);
        p->shown = status_shown = true;
        return;
    }
    status_shown = false;
    if (!p->shown) return;
    double s = (double)(fp_now_ns() - p->t0) / 1e9;
    fprintf(stderr, "\r\033[K");
    if (s >= 1.0) fprintf(stderr, "%s: %s in %.1f s\n", p->cmd, p->done, s);
    fflush(stderr);
    p->shown = false;
}

int fp_app_load_mesh(const char *cmd, bool quiet, const char *path, fp_mesh **out, char *err,
                     size_t errlen)
{
    fp_app_open_progress p;
    fp_app_open_progress_init(&p, cmd, quiet);
    struct stat st;
    if (p.on && !stat(path, &st)) {
        const char *slash = strrchr(path, '/');
        char line[600];
        snprintf(line, sizeof line, "loading %s (%.0f MiB)", slash && slash[1] ? slash + 1 : path,
                 ceil((double)st.st_size / 1048576.0));
        fp_app_open_progress_fn(&p, line);
    }
    int rc = fp_mesh_load(path, out, err, errlen);
    fp_app_open_progress_fn(&p, NULL);
    return rc;
}

void fp_app_log_line(void *user, int level, const char *source, const char *message)
{
    (void)user;
    if (level > FP_LOG_INFO && !getenv("FACEPUPPET_DEBUG")) return;
    /* one line a terminal may show: a plugin's or a sender's text may carry control bytes */
    char src[128], msg[2048];
    const bool status = status_shown; /* (erased first, drawn again after) */
    fprintf(stderr, "%sfacepuppet: %s: %s\n%s", status ? "\r\033[K" : "", fp_text_clean(source, src, sizeof src),
            fp_text_clean(message, msg, sizeof msg), status ? status_line : "");
    if (status) fflush(stderr);
}

void fp_app_log_line_quiet(void *user, int level, const char *source, const char *message)
{
    if (!fp_slog_is_note(level, source)) fp_app_log_line(user, level, source, message);
}

void fp_app_log_line_warnings(void *user, int level, const char *source, const char *message)
{
    if (level <= FP_LOG_WARNING) fp_app_log_line_quiet(user, level, source, message);
}

int fp_app_check_output(const char *cmd, const char *option, const char *path)
{
    char real[4096];
    int rc = fp_file_target(path, real, sizeof real);
    if (rc < 0) {
        fprintf(stderr, "%s: %s %s: cannot replace it: %s\n", cmd, option, path, fp_file_error_text(rc));
        return FP_EXIT_CANTCREAT;
    }
    const char *slash = strrchr(real, '/');
    char dir[4096];
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - real) + 1 : 1, slash ? real : ".");
    struct stat st;
    errno = 0;
    if (stat(dir, &st) || !S_ISDIR(st.st_mode) || access(dir, W_OK | X_OK)) {
        fprintf(stderr, "%s: %s %s: cannot write in %s: %s\n", cmd, option, path, dir,
                errno ? strerror(errno) : "not a folder");
        return FP_EXIT_CANTCREAT;
    }
    return 0;
}

int fp_app_check_new_output(const char *cmd, const char *option, const char *path, bool force)
{
    int rc = fp_app_check_output(cmd, option, path);
    if (rc || force) return rc;
    struct stat st;
    if (!stat(path, &st)) { /* (a link's end: what the save would replace) */
        fprintf(stderr, "%s: %s %s: exists (--force to overwrite)\n", cmd, option, path);
        return FP_EXIT_CANTCREAT;
    }
    return 0;
}

int fp_app_check_not_input(const char *cmd, const char *option, const char *out, const char *input,
                           const char *what)
{
    struct stat so, si;
    if (!out || !input || !*input || stat(out, &so) || stat(input, &si)) return 0;
    if (so.st_dev != si.st_dev || so.st_ino != si.st_ino) return 0;
    fprintf(stderr, "%s: %s %s: is %s being read (%s): refused (it would be written over)\n",
            cmd, option, out, what, input);
    return FP_EXIT_CANTCREAT;
}

bool fp_app_free_name(const char *path, char *buf, size_t len)
{
    struct stat st;
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path, *dot = strrchr(base, '.');
    if (dot == base) dot = NULL; /* ".hidden": no extension */
    int stem = dot ? (int)(dot - path) : (int)strlen(path);
    for (unsigned n = 0; n <= 999; n++) {
        int k = n ? snprintf(buf, len, "%.*s-%u%s", stem, path, n, dot ? dot : "")
                  : snprintf(buf, len, "%s", path);
        if (k < 0 || (size_t)k >= len) break;
        if (lstat(buf, &st) && errno == ENOENT) return true;
    }
    snprintf(buf, len, "%s", path);
    return false;
}

/* The files of dir named PREFIX...SUFFIX: how many, and the first by name into first. */
static size_t count_named(const char *dir, const char *prefix, const char *suffix, char *first,
                          size_t len)
{
    DIR *d = opendir(dir);
    size_t n = 0, pl = strlen(prefix), sl = strlen(suffix);
    first[0] = '\0';
    for (struct dirent *e; d && (e = readdir(d));) {
        size_t el = strlen(e->d_name);
        if (e->d_name[0] == '.' || el < pl + sl || strncmp(e->d_name, prefix, pl) ||
            strcmp(e->d_name + el - sl, suffix))
            continue;
        if (!n++ || strcmp(e->d_name, first) < 0) snprintf(first, len, "%s", e->d_name);
    }
    if (d) closedir(d);
    return n;
}

/* One file of fp_app_check_input_files: 0, or its exit code with the line printed. */
static int check_input_file(const char *cmd, const char *spec, const char *path)
{
    int fd = fp_file_open_regular(path);
    if (fd >= 0) {
        close(fd);
        return 0;
    }
    if (spec) fprintf(stderr, "%s: input '%s': %s: cannot open: %s\n", cmd, spec, path, fp_file_error_text(fd));
    else fprintf(stderr, "%s: %s: cannot open: %s\n", cmd, path, fp_file_error_text(fd));
    return fp_app_exit_code(fd, FP_APP_INPUT);
}

int fp_app_check_input_files(const char *cmd, const fp_session_options *so)
{
    int rc = 0;
    if (so->mesh_path && !so->mesh) rc = check_input_file(cmd, NULL, so->mesh_path);
    if (!rc && so->rig_path && strcmp(so->rig_path, "none")) rc = check_input_file(cmd, NULL, so->rig_path);
    for (size_t i = 0; !rc && i < so->input_count; i++) {
        fp_spec spec;
        char err[256];
        if (fp_spec_parse(so->inputs[i], &spec, err, sizeof err)) continue; /* said when opened */
        if (spec.arg && (!strcmp(spec.name, "replay") || !strcmp(spec.name, "take")))
            rc = check_input_file(cmd, so->inputs[i], spec.arg);
        fp_spec_clear(&spec);
    }
    return rc;
}

int fp_app_check_take_dir(const char *cmd, const char *dir)
{
    char p[4096];
    size_t n = strlen(dir);
    if (n >= sizeof p) {
        fprintf(stderr, "%s: --take-dir %s: %s\n", cmd, dir, strerror(ENAMETOOLONG));
        return FP_EXIT_CANTCREAT;
    }
    memcpy(p, dir, n + 1);
    for (;;) { /* the folder, else the nearest one above it that is there */
        while (n > 1 && p[n - 1] == '/') p[--n] = '\0';
        struct stat st;
        const char *why = NULL;
        if (stat(p, &st) == 0) {
            if (!S_ISDIR(st.st_mode)) why = "not a folder (a file is in its place)";
            else if (access(p, W_OK | X_OK)) why = strerror(errno);
            else return 0;
        } else if (errno == ENOTDIR) {
            why = "not a folder (a file is in its path)";
        } else if (errno != ENOENT) {
            why = strerror(errno);
        }
        if (why) {
            fprintf(stderr, "%s: --take-dir %s: %s%s%s\n", cmd, dir, why, strcmp(p, dir) ? ": " : "",
                    strcmp(p, dir) ? p : "");
            return FP_EXIT_CANTCREAT;
        }
        char *slash = strrchr(p, '/'); /* missing: made by the take writer, as mkdir -p */
        if (!slash) snprintf(p, sizeof p, ".");
        else if (slash == p) p[1] = '\0';
        else *slash = '\0';
        n = strlen(p);
    }
}

int fp_app_check_output_dir(const char *cmd, const char *option, const char *dir, const char *prefix,
                            const char *suffix, bool make, bool force, bool *made)
{
    struct stat st;
    const bool mk = make && mkdir(dir, 0777) == 0;
    if (made) *made = mk;
    if (make && !mk && errno != EEXIST) {
        fprintf(stderr, "%s: %s %s: %s\n", cmd, option, dir, strerror(errno));
        return FP_EXIT_CANTCREAT;
    }
    if (stat(dir, &st)) {
        if (!make && errno == ENOENT) return 0;
        fprintf(stderr, "%s: %s %s: %s\n", cmd, option, dir, strerror(errno));
        return FP_EXIT_CANTCREAT;
    }
    if (!S_ISDIR(st.st_mode)) {
        fprintf(stderr, "%s: %s %s: not a folder\n", cmd, option, dir);
        return FP_EXIT_CANTCREAT;
    }
    if (access(dir, W_OK | X_OK)) {
        fprintf(stderr, "%s: %s %s: %s\n", cmd, option, dir, strerror(errno));
        return FP_EXIT_CANTCREAT;
    }
    char first[512];
    size_t n = force ? 0 : count_named(dir, prefix ? prefix : "", suffix ? suffix : "", first,
                                       sizeof first);
    if (n) {
        fprintf(stderr, "%s: %s %s: holds %zu file%s of an earlier run (%s%s) (--force to "
                "overwrite)\n", cmd, option, dir, n, n == 1 ? "" : "s", first, n > 1 ? " ..." : "");
        return FP_EXIT_CANTCREAT;
    }
    return 0;
}

/* name = prefix + digits (six or more) + suffix (NULL: "." and an extension without a dot;
 * "_t*REST": "_t", a time of digits, '.' and '-', then REST): true with the number in *num */
static bool frame_named(const char *name, const char *prefix, const char *suffix,
                        unsigned long long *num)
{
    const size_t pl = strlen(prefix);
    if (strncmp(name, prefix, pl)) return false;
    const char *d = name + pl, *e = d;
    unsigned long long v = 0;
    for (; *e >= '0' && *e <= '9'; e++) {
        if (v > (ULLONG_MAX - 9) / 10) return false;
        v = 10 * v + (unsigned long long)(*e - '0');
    }
    if (e - d < 6) return false;
    if (suffix && !strncmp(suffix, "_t*", 3)) { /* --frames-out's frame_NNNNNN_tS.SSSs.obj */
        if (strncmp(e, "_t", 2)) return false;
        const char *t = e + 2;
        while ((*t >= '0' && *t <= '9') || *t == '.' || *t == '-') t++;
        if (t == e + 2 || strcmp(t, suffix + 3)) return false;
    } else if (suffix ? strcmp(e, suffix) != 0 : (e[0] != '.' || !e[1] || strchr(e + 1, '.'))) {
        return false;
    }
    *num = v;
    return true;
}

long fp_app_remove_stale_frames(const char *dir, const char *prefix, const char *suffix,
                                unsigned long long from, char *first, size_t len)
{
    first[0] = '\0';
    DIR *d = opendir(dir);
    if (!d) {
        snprintf(first, len, "%s", dir);
        return -errno;
    }
    long n = 0;
    for (struct dirent *e; (e = readdir(d));) {
        unsigned long long num;
        if (e->d_name[0] == '.' || !frame_named(e->d_name, prefix, suffix, &num) || num < from)
            continue;
        char path[4600];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (unlink(path)) {
            const int code = -errno;
            snprintf(first, len, "%s", e->d_name);
            closedir(d);
            return code;
        }
        if (!n++ || strcmp(e->d_name, first) < 0) snprintf(first, len, "%s", e->d_name);
    }
    closedir(d);
    return n;
}

int fp_app_frames_out_clear(const char *cmd, const char *dir, bool quiet)
{
    char first[512];
    const long n = fp_app_remove_stale_frames(dir, "frame_", "_t*s.obj", 0, first, sizeof first);
    if (n < 0) {
        fprintf(stderr, "%s: --frames-out %s: %s: an earlier run's frame could not be removed: %s\n",
                cmd, dir, first, strerror((int)-n));
        return FP_EXIT_CANTCREAT;
    }
    if (n > 0 && !quiet)
        fprintf(stderr, "%s: --frames-out %s: removed %ld frame%s of an earlier run (%s%s) (--force)\n",
                cmd, dir, n, n == 1 ? "" : "s", first, n > 1 ? " ..." : "");
    return 0;
}

void fp_app_size_text(double bytes, char *buf, size_t len)
{
    if (bytes >= 1e9) snprintf(buf, len, "%.1f GB", bytes / 1e9);
    else if (bytes >= 1e6) snprintf(buf, len, "%.0f MB", bytes / 1e6);
    else snprintf(buf, len, "%.0f kB", ceil(bytes / 1e3));
}

double fp_app_obj_frame_bytes(const fp_mesh *mesh)
{
    /* (36 bytes a vertex and 17 a triangle undercounted a frame of a face not from an OBJ by
     * half: its frames carry vn lines and normal indices) */
    return fp_mesh_obj_bytes(mesh);
}

int fp_app_free_room(const char *path, double *bytes)
{
    char dir[4200];
    snprintf(dir, sizeof dir, "%s", path && path[0] ? path : ".");
    struct statvfs fs;
    for (;;) {
        if (statvfs(dir, &fs) == 0) break;
        char *slash = strrchr(dir, '/');
        if (!slash) {
            if (statvfs(".", &fs) != 0) return -1;
            break;
        }
        if (slash == dir) { /* the root keeps its '/' */
            if (!slash[1] || statvfs("/", &fs) != 0) return -1;
            break;
        }
        *slash = 0;
    }
    *bytes = (double)fs.f_bavail * (double)fs.f_frsize;
    return 0;
}

int fp_app_output_fits(const char *cmd, const char *what, const char *path, double bytes,
                       double frames, size_t vertices, const char *hint)
{
    double room;
    if (!(bytes > 0)) return FP_EXIT_OK;
    char need[32], free_text[32], frame[32];
    fp_app_size_text(bytes, need, sizeof need);
    if (fp_app_free_room(path, &room) || bytes <= room) {
        if (bytes > FP_APP_FRAMES_WARN_BYTES) {
            fp_app_size_text(frames > 0 ? bytes / frames : bytes, frame, sizeof frame);
            fprintf(stderr, "%s: warning: %s: about %s (%.0f frames x %zu vertices, ~%s a frame), "
                    "over 1 GiB\n", cmd, what, need, frames, vertices, frame);
        }
        return FP_EXIT_OK;
    }
    fp_app_size_text(room, free_text, sizeof free_text);
    fprintf(stderr, "%s: %s: about %s (%.0f frames x %zu vertices), more than the %s free there; "
            "nothing written%s%s%s\n", cmd, what, need, frames, vertices, free_text,
            hint ? " (" : "", hint ? hint : "", hint ? ")" : "");
    return FP_EXIT_CANTCREAT;
}

int fp_app_frames_estimate(const char *cmd, const char *option, const char *dir, double frames,
                           double fps, const fp_mesh *mesh, bool quiet, const char *hint)
{
    const size_t vertices = mesh->vertex_count;
    const double frame = fp_app_obj_frame_bytes(mesh);
    char a[32], b[32], what[4300];
    const char *c = "1 GiB"; /* (FP_APP_FRAMES_WARN_BYTES) */
    fp_app_size_text(frame, b, sizeof b);
    if (frames > 0) {
        const double total = frames * frame;
        snprintf(what, sizeof what, "%s %s", option, dir);
        int rc = fp_app_output_fits(cmd, what, dir, total, frames, vertices, hint);
        if (rc) return rc;
        fp_app_size_text(total, a, sizeof a);
        if (total <= FP_APP_FRAMES_WARN_BYTES && !quiet) /* (above it: said as a warning) */
            fprintf(stderr, "%s: %s %s: about %s (%.0f frames x %zu vertices, ~%s a frame)\n",
                    cmd, option, dir, a, frames, vertices, b);
        return FP_EXIT_OK;
    }
    if (quiet || !(fps > 0)) return FP_EXIT_OK;
    fp_app_size_text(frame * fps, a, sizeof a);
    fprintf(stderr, "%s: %s %s: about %s a second (%g frames a second x %zu vertices, ~%s a "
            "frame): %s after %.0f s (--duration bounds it)\n", cmd, option, dir, a, fps, vertices,
            b, c, ceil(FP_APP_FRAMES_WARN_BYTES / (frame * fps)));
    return FP_EXIT_OK;
}

bool fp_app_spec_looks_like_file(const char *cmd, const char *option, const char *spec)
{
    const size_t name = strcspn(spec, ":,");
    if (!memchr(spec, '/', name) && !memchr(spec, '.', name)) return false;
    if (memchr(spec, '/', name) && name > 3 && !strncmp(spec + name - 3, ".so", 3))
        return false; /* a plugin's file, named by its path (docs/plugin-guide.md) */
    const size_t el = strlen(FP_TAKE_EXTENSION);
    const bool take = name > el && !strncasecmp(spec + name - el, FP_TAKE_EXTENSION, el);
    fprintf(stderr, "%s: %s %s: not a SPEC (NAME[:ARG][,key=value...]); it looks like a file: did "
            "you mean %s %s:%s?\n", cmd, option, spec, option, take ? "take" : "replay", spec);
    return true;
}

bool fp_app_parse_size(const char *v, int lo, int hi, int *w, int *h)
{
    const char *x = v ? strchr(v, 'x') : NULL;
    char first[32];
    unsigned long long a, b;
    if (!x || (size_t)(x - v) >= sizeof first || lo < 0 || hi < lo) return false;
    snprintf(first, sizeof first, "%.*s", (int)(x - v), v);
    if (!fp_parse_whole(first, (unsigned long long)hi, &a) ||
        !fp_parse_whole(x + 1, (unsigned long long)hi, &b) || a < (unsigned long long)lo ||
        b < (unsigned long long)lo)
        return false;
    *w = (int)a;
    *h = (int)b;
    return true;
}

int fp_app_check_mesh_name(const char *cmd, const char *option, const char *path)
{
    static const char *exts[] = {".obj", ".ply", ".off", ".stl", ".gltf", ".glb"};
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    bool known = false;
    for (size_t i = 0; dot && (!slash || dot > slash) && i < sizeof exts / sizeof exts[0]; i++)
        known |= !strcasecmp(dot, exts[i]);
    if (known) return 0;
    fprintf(stderr, "%s: %s %s: unknown mesh format (give .obj, .ply, .off, .stl, .gltf or .glb)\n",
            cmd, option, path);
    return FP_EXIT_USAGE;
}

int fp_app_take_intact(const char *cmd, const char *verb, const char *path,
                       const struct fp_take_reader *r)
{
    const char *cut = fp_take_reader_warning(r);
    if (!fp_take_reader_frames(r)) {
        fprintf(stderr, "%s: %s: no intact frame to %s%s%s%s\n", cmd, path, verb, cut[0] ? " (" : "",
                cut, cut[0] ? ")" : "");
        return FP_EXIT_DATAERR;
    }
    if (cut[0])
        fprintf(stderr, "%s: warning: %s; %sing the %zu intact frames\n", cmd, cut, verb,
                fp_take_reader_frames(r));
    else if (!fp_take_reader_summary(r)->complete) /* (exported mid-take: said nothing) */
        fprintf(stderr, "%s: warning: %s: no end chunk: it may still be recording, or its "
                "recording stopped without closing it (killed, a full disk); %sing the %zu "
                "frames it holds now\n", cmd, path, verb, fp_take_reader_frames(r));
    return FP_EXIT_OK;
}

/* Append x to the array *v of *n (capacity *cap); false where it could not grow. */
static bool reach_push(double **v, size_t *n, size_t *cap, double x)
{
    if (*n == *cap) {
        size_t nc = *cap ? 2 * *cap : 1024;
        double *g = realloc(*v, nc * sizeof *g);
        if (!g) return false;
        *v = g;
        *cap = nc;
    }
    (*v)[(*n)++] = x;
    return true;
}

void fp_app_reach_add(fp_app_reach *r, const fp_frame_stats *st)
{
    for (size_t i = 0; i < st->reach_vectors; i++)
        if (!reach_push(&r->v, &r->n, &r->cap, st->reach[i])) return;
    for (size_t i = 0; i < st->reach_allowed_vectors; i++)
        if (!reach_push(&r->va, &r->na, &r->capa, st->reach_allowed[i])) return;
    r->held += st->reach_held;
    if (st->reach_asked_max > r->asked_max) r->asked_max = st->reach_asked_max;
}

void fp_app_reach_rig_clause(fp_app_reach *r, double median, double p10, char *rig, size_t len)
{
    if (!len) return;
    rig[0] = '\0';
    if (!r->na) return;
    double ma = fp_median(r->va, r->na), pa = fp_percentile(r->va, r->na, 0.10);
    if (fabs(ma - median) >= 0.005 || fabs(pa - p10) >= 0.005)
        snprintf(rig, len, "; %.0f%% of what the rig allowed, 10th percentile %.0f%%: it holds back a push "
                 "toward the skull or the jaw", 100.0 * ma, 100.0 * pa);
}

void fp_app_reach_text(fp_app_reach *r, double mm_per_unit, bool played_rig, char *text, size_t len)
{
    if (!len) return;
    text[0] = 0;
    if (played_rig) { /* the vectors are a take's, the rig's cut: only what it allowed is known */
        if (!r->na) return;
        double ma = fp_median(r->va, r->na), pa = fp_percentile(r->va, r->na, 0.10);
        char h[96] = "";
        if (r->held) snprintf(h, sizeof h, "; %zu more on the skull or the jaw, which the rig keeps still", r->held);
        snprintf(text, len, "; the skin followed %.0f%% of what the rig allowed (median over %zu touching vectors, "
                 "10th percentile %.0f%%, longest drag %.1f mm; a take holds the rig's vectors, not how far "
                 "the fingertips asked%s)", 100.0 * ma, r->na, 100.0 * pa, r->asked_max * mm_per_unit, h);
        return;
    }
    if (!r->n) return;
    double med = fp_median(r->v, r->n), p10 = fp_percentile(r->v, r->n, 0.10);
    char rig[256];
    fp_app_reach_rig_clause(r, med, p10, rig, sizeof rig);
    int w = snprintf(text, len, "; ");
    if (w > 0 && (size_t)w < len)
        fp_app_reach_sentence(text + w, len - (size_t)w, med, r->n, p10, r->asked_max * mm_per_unit, rig,
                              r->held);
}

void fp_app_reach_sentence(char *text, size_t len, double median, size_t vectors, double p10,
                           double longest_mm, const char *rig, size_t held)
{
    if (!len) return;
    char h[96] = "";
    if (held) snprintf(h, sizeof h, "; %zu of them on the skull or the jaw, which the rig keeps still", held);
    snprintf(text, len,
             "the skin followed the fingertips %.0f%% (median over %zu touching vectors, 10th "
             "percentile %.0f%%, longest drag %.1f mm%s%s)", 100.0 * median, vectors, 100.0 * p10,
             longest_mm, rig ? rig : "", h);
}

void fp_app_reach_free(fp_app_reach *r)
{
    free(r->v);
    free(r->va);
    memset(r, 0, sizeof *r);
}
