/* run/play/export: the exporter and its summary line (app_export.h). */
#include "app_export.h"
#include "app_util.h"
#include "command.h"
#include "fp_mesh.h"

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

int fp_app_export_open(const char *cmd, const char *file, const struct fp_mesh *mesh,
                       double mm_per_unit, const char *name, double frames, fp_exporter **x)
{
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
