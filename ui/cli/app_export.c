/* run/play/export: the exporter and its summary line (app_export.h). */
#include "app_export.h"
#include "app_util.h"
#include "command.h"
#include "fp_cache_info.h"
#include "fp_file.h"
#include "fp_mesh.h"
#include "fp_session.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/stat.h>

double fp_app_export_frame_bytes(fp_export_format format, const struct fp_mesh *mesh)
{
    const double n = (double)mesh->vertex_count;
    switch (format) {
    case FP_EXPORT_PC2: return 12 * n;
    case FP_EXPORT_MDD: return 12 * n + 4;
    case FP_EXPORT_OBJ_SEQ: return fp_app_obj_frame_bytes(mesh);
    default: return 0;
    }
}

void fp_app_export_name(const char *path, bool stack, const char *slate, unsigned take, char *buf,
                        size_t n)
{
    if (!stack) {
        snprintf(buf, n, "%s_T%03u", slate, take);
        return;
    }
    const char *slash = strrchr(path, '/'), *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    snprintf(buf, n, "%.*s", dot && dot > base ? (int)(dot - base) : (int)strlen(base), base);
}

/* A /proc file's "KEY: N kB" line, in bytes; -1 where absent. */
static double proc_kb(const char *file, const char *key)
{
    FILE *f = fopen(file, "re");
    if (!f) return -1;
    char line[256];
    double v = -1;
    const size_t n = strlen(key);
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, key, n) && line[n] == ':') {
            v = strtod(line + n + 1, NULL) * 1024.0;
            break;
        }
    fclose(f);
    return v;
}

double fp_app_memory_budget(void)
{
    const double avail = proc_kb("/proc/meminfo", "MemAvailable"), swap = proc_kb("/proc/meminfo", "SwapFree");
    double budget = avail > 0 ? avail + (swap > 0 ? swap : 0) : 0;
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
        const double size = proc_kb("/proc/self/status", "VmSize");
        const double left = (double)rl.rlim_cur - (size > 0 ? size : 0);
        if (budget == 0 || left < budget) budget = left > 1 ? left : 1;
    }
    return budget;
}

int fp_app_export_gltf_plan(const char *cmd, const char *what, const char *hint, double frames,
                            const struct fp_mesh *mesh, bool quiet,
                            fp_export_options *eo)
{
    if (eo->format != FP_EXPORT_GLTF && eo->format != FP_EXPORT_GLB) return FP_EXIT_OK;
    if (frames > FP_EXPORT_GLTF_MAX_FRAMES) {
        fprintf(stderr, "%s: %s: %.0f frames: a glTF export holds at most %d (%s); nothing "
                "written\n", cmd, what, frames, FP_EXPORT_GLTF_MAX_FRAMES, hint);
        return FP_EXIT_USAGE;
    }
    eo->frames_expected = frames > 0 ? (uint64_t)frames : 0;
    eo->memory_budget = fp_app_memory_budget();
    const double most = fp_export_gltf_peak_bytes(eo->frames_expected, mesh->vertex_count);
    if (!quiet && frames > 0 && eo->memory_budget > 0 && most > eo->memory_budget)
        fprintf(stderr, "%s: %s: %.0f frames of %zu vertices: the morph targets may need "
                "%.1f GB or more at the end, more than the %.1f GB there is room for; the export stops "
                "as soon as the frames show it cannot fit (%s)\n", cmd, what, frames,
                mesh->vertex_count, most / 1e9, eo->memory_budget / 1e9, hint);
    return FP_EXIT_OK;
}

int fp_app_export_open(const char *cmd, const char *file, const struct fp_session *s,
                       double mm_per_unit, const char *name, double frames, fp_exporter **x)
{
    const struct fp_mesh *mesh = fp_session_mesh(s);
    fp_export_format fmt;
    if (fp_export_format_from_path(file, &fmt)) {
        fprintf(stderr, "%s: --export %s: give a file ending in .gltf, .glb, .pc2 or .mdd\n",
                cmd, file);
        return FP_EXIT_USAGE;
    }
    char what[4200];
    snprintf(what, sizeof what, "--export %s", file);
    int status = fp_app_output_fits(cmd, what, file, frames * fp_app_export_frame_bytes(fmt, mesh),
                                    frames, mesh->vertex_count, NULL);
    if (status) return status;
    fp_export_options eo = {.format = fmt, .path = file, .mm_per_unit = mm_per_unit,
                            .name = name};
    if ((status = fp_app_export_gltf_plan(cmd, what, "a shorter --duration", frames, mesh, false,
                                          &eo)))
        return status;
    float up[3], facing[3];
    fp_session_face_axes(s, up, facing);
    for (int i = 0; i < 3; i++) eo.up[i] = up[i], eo.facing[i] = facing[i];
    char err[1024];
    int rc = fp_export_begin(mesh, &eo, x, err, sizeof err);
    if (rc) {
        fprintf(stderr, "%s: --export: %s\n", cmd, err);
        return fp_app_exit_code(rc, FP_APP_OUTPUT);
    }
    return FP_EXIT_OK;
}

int fp_app_export_close(const char *cmd, const char *option, fp_exporter **x,
                        fp_export_format format, const char *file, double limit_mm, bool quiet,
                        FILE *f)
{
    fp_export_result res;
    char err[1024];
    int rc = fp_export_finish(x, &res, err, sizeof err);
    if (rc) {
        fprintf(stderr, "%s: %s%s%s\n", cmd, option ? option : "", option ? ": " : "", err);
        return fp_app_exit_code(rc, FP_APP_OUTPUT);
    }
    if (!quiet) {
        fprintf(f, "%s: exported %llu frame%s to %s (%s): ", cmd, (unsigned long long)res.frames,
                res.frames == 1 ? "" : "s", file, fp_export_format_name(format));
        if (format == FP_EXPORT_GLTF || format == FP_EXPORT_GLB)
            fprintf(f, "K = %zu morph targets, %.2f MB, largest error %.4g mm (limit %.4g mm); "
                    "in metres: root node scale %.6g (%.6g mm per mesh unit)",
                    res.targets, (double)res.bytes / 1e6, res.max_error_mm, limit_mm,
                    res.unit_scale, res.unit_scale * 1000);
        else
            fprintf(f, "%.2f MB, every frame exact; mesh units of %.6g mm (scale %.6g for "
                    "metres)", (double)res.bytes / 1e6, res.unit_scale * 1000, res.unit_scale);
        if (res.frame_rate > 0)
            fprintf(f, "; %.6g fps\n", res.frame_rate);
        else
            fprintf(f, "; one frame, no rate\n");
        if (res.dropped) {
            char what[256];
            fprintf(f, "%s: note: %s cannot hold the input's %s\n", cmd,
                    fp_export_format_name(format),
                    fp_mesh_dropped_text(res.dropped, what, sizeof what));
        }
    }
    return FP_EXIT_OK;
}

void fp_app_print_dropped(const char *cmd, const char *file, unsigned dropped, bool quiet)
{
    if (!dropped || quiet)
        return;
    char what[256];
    fprintf(stderr, "%s: note: %s cannot hold the input's %s\n", cmd, file,
            fp_mesh_dropped_text(dropped, what, sizeof what));
}

bool fp_app_is_point_cache(const char *path, const unsigned char *h, size_t n)
{
    const char *dot = strrchr(path, '.');
    return (dot && !strcasecmp(dot, ".mdd")) || (n >= 12 && !memcmp(h, "POINTCACHE2\0", 12));
}

int fp_app_cache_info(const char *path)
{
    fp_cache_info c;
    char err[256];
    int rc = fp_cache_info_read(path, &c, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet info: %s: %s\n", path, err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    char note[96] = ""; /* the file's size against what its header says it holds */
    if (c.bytes > c.want) snprintf(note, sizeof note, " (and %.0f bytes more than they take)", c.bytes - c.want);
    else if (c.bytes < c.want) snprintf(note, sizeof note, " (cut: the file holds %.0f of them)", c.held);
    if (!c.mdd) {
        printf("%s\n  format    PC2 point cache (little-endian)\n  points    %.0f\n  frames    %.0f%s\n"
               "  start     frame %g, a sample every %g frames (PC2 has no rate: the scene's)\n",
               path, c.points, c.frames, note, c.start, c.sampling);
    } else {
        printf("%s\n  format    MDD point cache (big-endian)\n  points    %.0f\n  frames    %.0f%s\n", path,
               c.points, c.frames, note);
        if (isfinite(c.t_first) && isfinite(c.t_last) && c.frames >= 2 && c.t_last > c.t_first)
            printf("  times     %.4g .. %.4g s, %.4g fps (first step %.4g s)\n", c.t_first, c.t_last,
                   (c.frames - 1) / (c.t_last - c.t_first), c.t_second - c.t_first);
        else if (isfinite(c.t_first))
            printf("  times     %.4g s\n", c.t_first);
    }
    if (note[0]) {
        fprintf(stderr, "facepuppet info: %s: not the size its header gives%s\n", path, note);
        return FP_EXIT_DATAERR;
    }
    return FP_EXIT_OK;
}
