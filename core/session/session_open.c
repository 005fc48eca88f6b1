/* Opening a session: fp_session_create (the mesh, the rig, the head and the radius, the
 * steps' state, the contact guard, the mapping and the inputs, the calibration) and
 * fp_session_start (fp_session.h). */
#define _GNU_SOURCE
#include "session_internal.h"

#include "fp_vec.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h> /* stat: the mesh file's size for progress */

/* A rig of dir whose own mesh (under root) holds every vertex of this one, split at seams:
 * loaded, carried over (fp_rig_find_split, fp_rig_remap), bound, s->rig_how said. 0 and *rig,
 * 1 none (nothing said), or -ENOMEM. */
static int attach_split_rig(fp_session *s, const char *dir, const char *root, fp_rig **rig,
                            char *err, size_t errlen)
{
    char path[1024], msg[300];
    uint32_t *map = NULL;
    int rc = fp_rig_find_split(dir, root, s->n, s->loaded, path, sizeof path, &map, msg, sizeof msg);
    if (rc) return rc == -ENOMEM ? fp_errorf(err, errlen, rc, "session: %s", msg) : 1;
    size_t rig_n = 0;
    rc = fp_rig_load(path, rig, msg, sizeof msg);
    if (!rc) {
        rig_n = fp_rig_vertex_count(*rig);
        rc = fp_rig_remap(*rig, s->n, map, s->loaded, msg, sizeof msg);
    }
    if (!rc) rc = fp_rig_bind(*rig, s->n, s->loaded, msg, sizeof msg);
    free(map);
    if (rc) { /* (it fit when found: only memory, or a file changed since, stops it) */
        fp_rig_free(rig);
        if (rc == -ENOMEM) return fp_errorf(err, errlen, rc, "session: %s", msg);
        fp_slog_printf(&s->log, FP_LOG_WARNING, "rig", "%s; running without a rig", msg);
        return 1;
    }
    snprintf(s->rig_how, sizeof s->rig_how, "%s (found by position: this mesh is its %s with the "
             "vertices split at seams, %zu vertices at its %zu)", path, fp_rig_mesh_name(*rig), s->n, rig_n);
    return 0;
}

/* The rig: given, "none", or the one of this mesh in the rig folder (fp_rig_find). */
static int attach_rig(fp_session *s, const fp_session_options *opt, char *err, size_t errlen)
{
    fp_rig *rig = NULL;
    int rc;
    if (opt->rig_path && !strcmp(opt->rig_path, "none")) {
        snprintf(s->rig_how, sizeof s->rig_how, "none (--rig none)");
    } else if (opt->rig_path) {
        if ((rc = fp_rig_load_for_mesh(opt->rig_path, s->n, s->loaded, &rig, err, errlen))) return rc;
        snprintf(s->rig_how, sizeof s->rig_how, "%s (given; mesh checksum %s%s)", opt->rig_path,
                 fp_rig_checksum_matches(rig, s->n, s->loaded) ? "matches" : "differs, same vertex count",
                 fp_rig_get_placement(rig).mirrored ? "; warning: this face is its mesh mirrored, left "
                 "for right, so its skull and jaw lie elsewhere: mirror the face back in a modeller"
                 : fp_rig_get_placement(rig).misfit ? "; warning: its landmarks do not sit on this face, "
                 "so its skull and jaw may lie elsewhere" : "");
    } else {
        char dir[1024], path[1024], msg[1200] = "";
        const char *d = opt->rig_dir ? opt->rig_dir : fp_rig_default_dir(NULL, dir, sizeof dir);
        rc = fp_rig_find(d, s->n, s->loaded, path, sizeof path, msg, sizeof msg);
        if (rc == -EEXIST) /* (two rigs of this mesh: a choice not ours; said also under -q) */
            fp_slog_printf(&s->log, FP_LOG_WARNING, "rig", "%s; running without a rig", msg);
        if (rc == -ENOENT && opt->rig_mesh_root) { /* its own mesh, split at seams? */
            int src = attach_split_rig(s, d, opt->rig_mesh_root, &rig, err, errlen);
            if (src < 0) return src;
            rc = src ? rc : 0;
        }
        if (rig) {
            /* (found by position: attach_split_rig said how) */
        } else if (rc) {
            snprintf(s->rig_how, sizeof s->rig_how, "none (%s)", msg);
        } else {
            if ((rc = fp_rig_load(path, &rig, err, errlen))) return rc;
            rc = fp_rig_bind(rig, s->n, s->loaded, err, errlen);
            fp_rig_placement pl = fp_rig_get_placement(rig);
            /* a rig found by the count whose landmarks do not sit on this face is left below,
             * not failed for its hinge off this mesh (a mirrored copy in metres exited 65) */
            if (rc && (rc == -ENOMEM || !pl.misfit || fp_rig_checksum_matches(rig, s->n, s->loaded))) {
                fp_rig_free(&rig);
                return rc;
            }
            if (pl.misfit && !fp_rig_checksum_matches(rig, s->n, s->loaded)) {
                /* the vertex count alone is no proof: its landmarks must sit on this face */
                if (pl.mirrored) /* (a mirror image: no similarity places the rig on it) */
                    snprintf(s->rig_how, sizeof s->rig_how, "none (%s fits %zu vertices, but this face "
                             "is its mesh mirrored, left for right, which no turn, scale or move of the "
                             "rig gives: mirror the face back in a modeller to use the rig)", path, s->n);
                else
                    snprintf(s->rig_how, sizeof s->rig_how, "none (%s fits %zu vertices, but not this "
                             "face: its landmarks lie %.3g mesh units from their vertices after the best "
                             "fit, against a spread of %.3g: another face, or its own with the vertices "
                             "in another order; --rig %s uses it anyway)", path, s->n, pl.rms, pl.spread, path);
                fp_rig_free(&rig);
            } else if (fp_rig_checksum_matches(rig, s->n, s->loaded))
                snprintf(s->rig_how, sizeof s->rig_how, "%s (found by the mesh's checksum %08x)", path,
                         fp_rig_mesh_crc32(rig));
            else
                snprintf(s->rig_how, sizeof s->rig_how, "%s (found by the vertex count %zu)", path, s->n);
        }
    }
    if (rig && fp_rig_get_placement(rig).placed) { /* a moved copy of the rig's mesh */
        fp_rig_placement pl = fp_rig_get_placement(rig);
        size_t k = strlen(s->rig_how);
        if (k && s->rig_how[k - 1] == ')') k--;
        snprintf(s->rig_how + k, sizeof s->rig_how - k,
                 "; placed on this mesh by its landmarks: turned %.1f degrees, scaled %.4g, moved "
                 "(%.4g, %.4g, %.4g))", pl.degrees, pl.scale, pl.shift[0], pl.shift[1], pl.shift[2]);
    }
    /* jaw weights that turn no triangle over (fp_rig_unfold_jaw) */
    if (rig && (rc = fp_rig_unfold_jaw(rig, s->loaded, s->mesh->triangles, s->mesh->triangle_count, NULL))) {
        fp_rig_free(&rig);
        snprintf(err, errlen, "session: out of memory for the rig's jaw weights");
        return rc;
    }
    if ((rc = fp_rig_step_init(&s->rig, rig, s->n, s->base))) {
        snprintf(err, errlen, "session: out of memory for the rig");
        return rc;
    }
    return 0;
}

/* The face's frame (session_internal.h): the options' axes (face_up, face_facing), else a rig
 * whose face axes are turned (placed on a turned copy of its mesh, fp_rig_placement); turned
 * from +x, +y, +z by more than FP_FACE_TURNED_DEG, they give the rotation, the loaded shape turned
 * back into it and the head found there (its unit too, unless one is given), where the hands
 * are fitted as for a face that looks along +z (fp_calibration.face). 0, -EINVAL (one axis
 * given, or two not at a right angle: err says) or -ENOMEM. */
/* With no rig and no --up/--facing the face is taken to look along +z, +y up. A face's front
 * holds most of its vertices (eyes, nose, lips against the smooth back of a head or the rim of
 * a mask: on the three faces of ../shared/data the mean vertex lies 0.16-0.23 of the depth in
 * front of the box's middle, under 0.11 of the extent off it along x and y); where the mean
 * lies off the middle most along another axis, or behind it, the face probably looks that way
 * (Blender's Z-up: along -y), and the log says so, with the options that turn it. */
static void facing_hint(fp_session *s)
{
    char msg[768];
    if (fp_head_facing_hint(s->loaded, s->n, s->used, msg, sizeof msg))
        fp_slog_printf(&s->log, FP_LOG_WARNING, "session", "%s", msg);
}

static int face_frame(fp_session *s, const fp_session_options *opt, char *err, size_t errlen)
{
    double q[4];
    memset(s->face, 0, sizeof s->face);
    const float *u = opt->face_up, *f = opt->face_facing;
    bool given_u = u[0] != 0 || u[1] != 0 || u[2] != 0, given_f = f[0] != 0 || f[1] != 0 || f[2] != 0;
    if (given_u || given_f) { /* the options' */
        if (fp_face_from_axes(u, f, q)) {
            snprintf(err, errlen, "the face's axes: give both --up and --facing, two unit axes at a right "
                     "angle (e.g. --up +z --facing -y)");
            return -EINVAL;
        }
    } else if (s->rig.rig) {
        fp_rig_face_rotation(s->rig.rig, q);
    } else {
        facing_hint(s);
        return 0;
    }
    if (!fp_face_turned(q)) return 0;
    if (!(s->canon = malloc(s->n * 3 * sizeof *s->canon))) {
        snprintf(err, errlen, "session: out of memory for the face's frame");
        return -ENOMEM;
    }
    if (fp_head_detect_turned(s->loaded, s->n, s->used, q, s->canon, &s->face_head)) { /* (as on the shape) */
        free(s->canon);
        s->canon = NULL;
        return 0;
    }
    memcpy(s->face, q, sizeof q);
    s->head.mm_per_unit = s->face_head.mm_per_unit; /* the unit detected as for a face that looks */
    s->head.method = s->face_head.method;           /* along +z (a given one still wins below) */
    memcpy(s->head.how, s->face_head.how, sizeof s->head.how);
    double z[3] = {0, 0, 1}, y[3] = {0, 1, 0}, fwd[3], up[3];
    fp_qrot(q, z, fwd);
    fp_qrot(q, y, up);
    fp_slog_printf(&s->log, FP_LOG_INFO, "session",
                   "the face looks along (%.2f, %.2f, %.2f) with up (%.2f, %.2f, %.2f) (%s): "
                   "the hands are placed in front of it, as for a face that looks along +z",
                   fwd[0], fwd[1], fwd[2], up[0], up[1], up[2], given_u ? "--up, --facing" : "its rig's axes");
    return 0;
}

/* fp_session_options.progress: one line, printf-style */
static void progress(const fp_session_options *opt, const char *fmt, ...)
{
    if (!opt->progress) return;
    char line[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    opt->progress(opt->progress_user, line);
}

/* The last component of a path. */
static const char *file_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash && slash[1] ? slash + 1 : path;
}

/* The options checked before anything is made: 0 or -EINVAL (the message in err). */
/* What messages call the radius, and a refused one's code: the option's (-EINVAL, 64), or a
 * file's value (opt->radius_name, e.g. a take's header: -ERANGE, 65). */
static const char *radius_name(const fp_session_options *opt)
{
    return opt->radius_name ? opt->radius_name : "--radius";
}

static int radius_code(const fp_session_options *opt)
{
    return opt->radius_name ? -ERANGE : -EINVAL;
}

static int check_options(const fp_session_options *opt, char *err, size_t errlen)
{
    if (!opt || (!opt->mesh_path && !opt->mesh) || !opt->plugin_path) {
        snprintf(err, errlen, "session: a mesh and a plugin path are required");
        return -EINVAL;
    }
    if (opt->input_count > FP_SESSION_MAX_INPUTS) {
        snprintf(err, errlen, "session: at most %d inputs", FP_SESSION_MAX_INPUTS);
        return -EINVAL;
    }
    if (opt->mm_per_unit < 0 || isnan(opt->mm_per_unit)) {
        snprintf(err, errlen, "--mm-per-unit must be > 0, got %g", opt->mm_per_unit);
        return -EINVAL;
    }
    if (opt->radius < 0 || isnan(opt->radius)) {
        snprintf(err, errlen, "%s must be > 0 (mesh units), got %g", radius_name(opt), opt->radius);
        return radius_code(opt);
    }
    return 0;
}

/* fp_sheet_bind_build and fp_crack_build on the session's loaded face, for a thread */
typedef struct bind_job {
    fp_session *s;
    int rc;
} bind_job;

static void *bind_run(void *u)
{
    bind_job *j = u;
    j->rc = fp_sheet_bind_build(j->s->loaded, j->s->n, j->s->mesh->triangles, j->s->mesh->triangle_count,
                                &j->s->bind);
    if (!j->rc)
        j->rc = fp_crack_build(j->s->loaded, j->s->n, j->s->mesh->triangles, j->s->mesh->triangle_count,
                               &j->s->crack);
    return NULL;
}

/* The mesh (given or loaded) and the session's shapes: loaded, base and deformed its copies,
 * the view's bounds; *diag the square of the bounding box's diagonal. 0 or the code. */
static int open_mesh(fp_session *s, const fp_session_options *opt, double *diag, char *err, size_t errlen)
{
    int rc = 0;
    if (opt->mesh) {
        if (!(s->mesh = fp_mesh_copy(opt->mesh))) {
            rc = -ENOMEM;
            snprintf(err, errlen, "session: out of memory for the mesh");
            return rc;
        }
    } else {
        struct stat fst;
        if (opt->progress && !stat(opt->mesh_path, &fst))
            progress(opt, "loading %s (%.0f MiB)", file_name(opt->mesh_path),
                     ceil((double)fst.st_size / 1048576.0));
        if ((rc = fp_mesh_load(opt->mesh_path, &s->mesh, err, errlen))) return rc; /* its code */
    }
    s->n = s->mesh->vertex_count;
    size_t bytes = s->n * 3 * sizeof(float);
    s->loaded = malloc(bytes);
    s->base = malloc(bytes);
    s->deformed = malloc(bytes);
    if (!s->loaded || !s->base || !s->deformed) {
        rc = -ENOMEM;
        snprintf(err, errlen, "session: out of memory for %zu vertices", s->n);
        return rc;
    }
    memcpy(s->loaded, s->mesh->positions, bytes);
    memcpy(s->base, s->loaded, bytes);
    memcpy(s->deformed, s->loaded, bytes);
    s->shown = s->base;
    /* the surface's bounds: a vertex in no triangle (a stray point an exporter left, drawn
     * nowhere) is left out of the mesh's size, hence of the radius, the head and the hands'
     * placement (one at 1e6 units beside a 25-unit mask made a radius of 6e4 units and moved
     * only itself); the engine still carries it */
    const char *name = opt->mesh_path ? opt->mesh_path : "the mesh";
    /* and a stray spike's tip (fp_mesh_face_mask's outliers) decided the face's front: the
     * hands, placed at its tip, grabbed the spike alone */
    size_t unused, spiked;
    if (fp_mesh_face_mask(s->mesh, &s->used, &unused, &spiked)) {
        snprintf(err, errlen, "session: out of memory for %zu vertices", s->n);
        return -ENOMEM;
    }
    if (unused)
        fp_slog_printf(&s->log, FP_LOG_WARNING, "session",
                       "%s: %zu of %zu vertices are in no triangle: left out of the face's size, "
                       "its head and the hands' placement", name, unused, s->n);
    if (spiked)
        fp_slog_printf(&s->log, FP_LOG_WARNING, "session",
                       "%s: %zu of %zu vertices lie far off the rest (beyond %g of its 0.5th-99.5th "
                       "percentile extent on an axis: a stray spike's tip): left out of the face's "
                       "size, its head and the hands' placement", name, spiked, s->n, FP_MESH_OUTLIER_SPAN);
    fp_mesh_bounds_used(s->mesh, s->used, s->view.bounds_min, s->view.bounds_max);
    s->view.vertex_count = s->n;
    s->view.base = s->base;
    *diag = 0;
    double reach = 0; /* the largest |coordinate| */
    for (int i = 0; i < 3; i++) {
        double d = s->view.bounds_max[i] - s->view.bounds_min[i];
        *diag += d * d;
    }
    s->diagonal = sqrt(*diag);
    float lo_all[3], hi_all[3];
    /* the engine's range (FP_SESSION_MIN_DIAGONAL): such a mesh was indexed nowhere ("cannot
     * index", exit 70) or moved nothing, the engine refusing its radius every frame */
    fp_mesh_bounds(s->mesh, lo_all, hi_all); /* (every vertex's, the engine holds them all) */
    for (int k = 0; k < 3; k++) reach = fmax(reach, fmax(fabs(lo_all[k]), fabs(hi_all[k])));
    if (reach > CSRBF_MAX_COORD) {
        snprintf(err, errlen, "%s: coordinates reach %.3g mesh units, beyond the engine's range (%g): "
                 "scale the mesh down (export it in larger units)", name, reach, CSRBF_MAX_COORD);
        return -EBADMSG;
    }
    /* a surface of no size, or too small for the engine, before the float step where it lies:
     * triangles all collapsed onto one point 1 unit off the origin were told to move near the
     * origin, which gives them no size */
    if (*diag == 0) {
        snprintf(err, errlen, "%s: its triangles have no size: every corner of every one lies at "
                 "(%.6g, %.6g, %.6g), nothing a hand can shape (a degenerate export)", name,
                 s->view.bounds_min[0], s->view.bounds_min[1], s->view.bounds_min[2]);
        return -EBADMSG;
    }
    if (sqrt(*diag) < FP_SESSION_MIN_DIAGONAL) {
        snprintf(err, errlen, "%s: the mesh spans %.3g mesh units (its bounding box's diagonal), under "
                 "%g, too small for the engine's support radii: scale it up (export it in smaller "
                 "units)", name, sqrt(*diag), FP_SESSION_MIN_DIAGONAL);
        return -EBADMSG;
    }
    /* the float step where the surface lies (FP_SESSION_MAX_STEP_DIAGONALS): a face in metres
     * moved 1e6 units off the origin loaded as a few steps of 0.0625, its unit detected as inf
     * mm and its summary NaN, exit 0 */
    double far = 0;
    for (int k = 0; k < 3; k++)
        far = fmax(far, fmax(fabs(s->view.bounds_min[k]), fabs(s->view.bounds_max[k])));
    const double step = far > 0 ? (double)nextafterf((float)far, INFINITY) - (double)(float)far : 0;
    if (step > FP_SESSION_MAX_STEP_DIAGONALS * s->diagonal) {
        snprintf(err, errlen, "%s: the surface lies %.3g mesh units from the origin, where the mesh's "
                 "floats keep steps of %.3g units, coarse for a mesh %.3g units across (its shape is "
                 "lost): move it near the origin in a modeller", name, far, step, s->diagonal);
        return -EBADMSG;
    }
    return 0;
}

/* A given --radius under the face's median edge (fp_mesh_median_edge over the face's
 * vertices, where the fingers act) holds one vertex or none: a fingertip pulls spikes. Said
 * once, with a radius of three edges (or the default, if larger); the radius is kept. */
static void warn_small_radius(fp_session *s, const fp_session_options *opt)
{
    double edge;
    if (!(opt->radius > 0) || fp_mesh_median_edge(s->mesh, s->used, &edge) || !(opt->radius < edge))
        return;
    const double mm = s->head.mm_per_unit > 0 && isfinite(s->head.mm_per_unit) ? s->head.mm_per_unit : NAN;
    const double hint = fmax(3 * edge, s->touch_radius);
    fp_slog_printf(&s->log, FP_LOG_WARNING, "session",
                   "--radius %.4g mesh units (%.3g mm) is under the face's typical edge length, "
                   "%.4g mesh units (%.3g mm, the median): a fingertip moves single vertices or "
                   "none (spikes); try --radius %.4g (%.3g mm)",
                   opt->radius, opt->radius * mm, edge, edge * mm, hint, hint * mm);
}

/* A calibration made for another mesh: its unit against the mesh's own (the rig's, else the
 * head's as detected, *head), FP_SESSION_CALIBRATION_UNIT_RATIO. */
void fp__session_warn_calibration_unit(fp_session *s, const char *source, double scale,
                                       const char *mesh_path, const fp_head *head)
{
    const double cal = 1.0 / scale;
    double own = head->mm_per_unit;
    char how[300];
    if (s->rig.rig) {
        own = fp_rig_mm_per_unit(s->rig.rig);
        snprintf(how, sizeof how, "the rig %s", fp_rig_source(s->rig.rig));
    } else {
        snprintf(how, sizeof how, "%s", head->how[0] ? head->how : "detected from the head");
    }
    if (!(scale > 0) || !(own > 0) || !isfinite(own) || (cal <= own * FP_SESSION_CALIBRATION_UNIT_RATIO &&
                                                          cal * FP_SESSION_CALIBRATION_UNIT_RATIO >= own))
        return;
    fp_slog_printf(&s->log, FP_LOG_WARNING, "session",
                   "%s: %.4g mm per mesh unit, but %s is %.4g mm per unit (%s): %.2g times %s; "
                   "a calibration made for another mesh? The hands are placed by it (make one "
                   "for this mesh: facepuppet calibrate --mesh %s ...)",
                   source ? source : "the calibration", cal, mesh_path ? mesh_path : "the mesh", own, how,
                   cal > own ? cal / own : own / cal, cal > own ? "larger" : "smaller",
                   mesh_path ? mesh_path : "FACE");
}

/* The head, the rig (the shape shown: the posed base), the mesh's unit and the radius. 0 or
 * the code. */
static int open_scale(fp_session *s, const fp_session_options *opt, double diag, char *err, size_t errlen)
{
    int rc = 0;
    if (fp_head_detect_used(s->loaded, s->n, s->used, &s->head)) {
        snprintf(err, errlen, "%s: cannot find a head in %zu vertices (flat or non-finite mesh)",
                 opt->mesh_path, s->n);
        rc = -EBADMSG; /* the mesh's fault: bad input data (65), as calibrate says */
        return rc;
    }
    if ((rc = attach_rig(s, opt, err, errlen))) return rc;
    if ((rc = face_frame(s, opt, err, errlen))) return rc;
    s->shown = s->view.base = fp_rig_step_posed(&s->rig, s->base);
    const fp_head detected = s->head; /* (for a calibration's unit: fp__session_warn_calibration_unit) */
    if (opt->mm_per_unit > 0) {
        s->head.mm_per_unit = opt->mm_per_unit;
        s->head.method = FP_HEAD_GIVEN;
        snprintf(s->head.how, sizeof s->head.how, "from %s",
                 opt->mm_per_unit_source ? opt->mm_per_unit_source : "the options");
    } else if (opt->calibration && opt->calibration->scale > 0) {
        s->head.mm_per_unit = 1.0 / opt->calibration->scale;
    } else if (s->rig.rig) { /* a rig wins over detection, the option over a rig */
        s->head.mm_per_unit = fp_rig_mm_per_unit(s->rig.rig);
        s->head.method = FP_HEAD_GIVEN;
        snprintf(s->head.how, sizeof s->head.how, "from the rig %s", fp_rig_source(s->rig.rig));
    }
    if (opt->radius > 0 && opt->radius < FP_SESSION_RADIUS_MIN_DIAGONALS * sqrt(diag)) {
        rc = radius_code(opt);
        snprintf(err, errlen, "%s %g is below a millionth of the mesh's bounding-box "
                 "diagonal (%.4g mesh units): no vertex would move; give a radius in mesh units",
                 radius_name(opt), opt->radius, sqrt(diag));
        return rc;
    }
    {   /* a given scale that makes the face under a millimetre or over a kilometre across is
         * a slip (mm per unit for units per mm, a unit's power of ten): no hand would reach it */
        double across_mm;
        if ((opt->mm_per_unit > 0 || (opt->calibration && opt->calibration->scale > 0)) &&
            !fp_head_scale_plausible(sqrt(diag), s->head.mm_per_unit, &across_mm)) {
            rc = opt->mm_per_unit > 0 ? -EINVAL : -ERANGE; /* an option's, or a file's (65) */
            snprintf(err, errlen, "%s: %g mm per mesh unit makes the face %.3g mm across "
                     "(its diagonal %.4g mesh units); give millimetres per mesh unit",
                     opt->mm_per_unit > 0 ? "--mm-per-unit"
                     : opt->calibration_source ? opt->calibration_source : "the calibration's scale",
                     s->head.mm_per_unit, across_mm, sqrt(diag));
            return rc;
        }
    }
    if (!(opt->mm_per_unit > 0) && opt->calibration && opt->calibration->scale > 0)
        fp__session_warn_calibration_unit(s, opt->calibration_source, opt->calibration->scale, opt->mesh_path,
                                          &detected);
    if (opt->radius > FP_SESSION_RADIUS_MAX_DIAGONALS * sqrt(diag)) {
        rc = radius_code(opt);
        snprintf(err, errlen, "%s %g is beyond 10x the mesh's bounding-box diagonal (%.4g "
                 "mesh units): every vertex would move as one; give a radius in mesh units",
                 radius_name(opt), opt->radius, sqrt(diag));
        return rc;
    }
    if (s->canon) { /* the face's frame's head: the same unit */
        s->face_head.mm_per_unit = s->head.mm_per_unit;
        s->face_head.method = s->head.method;
        memcpy(s->face_head.how, s->head.how, sizeof s->face_head.how);
    }
    /* Default radius: 6% of the bounding-box diagonal, at least a fingertip's reach
     * (FP_SESSION_MIN_RADIUS_MM): on a sparse mask (MediaPipe's 468 vertices) a smaller one
     * holds hardly a vertex. */
    s->touch_radius = fmax(0.06 * sqrt(diag), FP_SESSION_MIN_RADIUS_MM / s->head.mm_per_unit);
    s->radius = opt->radius > 0 ? opt->radius : s->touch_radius;
    warn_small_radius(s, opt);
    return 0;
}

/* The steps' state: intents, poses, history, recorder, the engine on the posed base, the
 * contact guard. 0 or the code. */
static int open_steps(fp_session *s, const fp_session_options *opt, double diag, char *err, size_t errlen)
{
    int rc = 0;
    /* One engine thread by default, at any size: a frame's evaluation writes only the blocks
     * in a support (a 1% frame on 1.7M vertices is about 0.1 ms on one core), and a second
     * OpenMP thread that the input and display threads (or the machine's other work) keep
     * off its core can cost a whole scheduler time slice, its spin-wait after a region the
     * main thread's core: measured on 2 cores with `bench --case frame --no-contact-guard`,
     * ICT subdivided to 1.7M vertices, deforming frames 4.06 ms median with all cores
     * against 0.33 ms on one (the ICT face: 13.7 ms against 0.11 ms with the other core
     * busy). Whole-mesh writes (a base change) are slower on one thread; -1 asks for all. */
    int threads = opt->engine_threads ? opt->engine_threads : 1;
    fp_intents_init(&s->intents);
    fp_pose_init(&s->pose[0], opt->hand_size, NULL); /* (the first performer's; the others' at
                                                        fp__session_performers_open) */
    if ((rc = fp_history_init(&s->history, s->n, s->base))) {
        snprintf(err, errlen, "session: out of memory for the undo history");
        return rc;
    }
    fp_record_step_init(&s->record, opt->record, opt->record_user);
    progress(opt, "indexing %zu vertices", s->n);
    if ((rc = fp_engine_step_init(&s->engine, s->n, s->shown, threads))) {
        snprintf(err, errlen, "session: cannot index %zu vertices", s->n);
        return rc;
    }
    /* the output buffer starts as the surface the engine indexes (the posed base), so the
     * first run writes only the blocks in a support, not the whole mesh */
    memcpy(s->deformed, s->shown, s->n * 3 * sizeof(float));
    fp_engine_step_output_is_base(&s->engine);
    s->mapping_budget_ms = opt->mapping_budget_ms;
    s->isolate = opt->isolate;
    snprintf(s->isolate_helper, sizeof s->isolate_helper, "%s", opt->isolate_helper ? opt->isolate_helper : "");
    s->isolate_opt.helper = opt->isolate_helper ? s->isolate_helper : NULL;
    s->isolate_opt.deadline_ms = opt->isolate_deadline_ms;
    s->isolate_opt.never_wait = !opt->input_clock; /* live: a frame never waits for a restart */
    s->whole_rig_commit = opt->whole_rig_commit;
    s->frame_thread_opt = opt->frame_thread;
    /* the hold's eps from the loaded face's diagonal (diag: its square, above) */
    s->cg.hold = opt->exact_frames || !isfinite(diag) ? 0.0f : (float)(FP_CONTACT_HOLD * sqrt(diag));
    s->engine.jacobian = opt->measure_jacobian;
    if ((rc = fp_engine_step_set_topology(&s->engine, s->mesh->triangles, s->mesh->triangle_count))) {
        snprintf(err, errlen, "session: out of memory for %zu triangles", s->mesh->triangle_count);
        return rc;
    }
    /* the loaded face's close sheets (sheet_bind.h), found on a second thread while the
     * contact guard builds its hierarchy: both read the loaded shape only */
    bind_job job = {.s = s};
    pthread_t th;
    bool threaded = pthread_create(&th, NULL, bind_run, &job) == 0;
    if (!threaded) bind_run(&job);
    if (!opt->no_contact_guard) {
        progress(opt, "building the contact guard over %zu triangles", s->mesh->triangle_count);
        rc = fp_cg_open(&s->cg, s->mesh->triangles, s->mesh->triangle_count, s->n, s->loaded, &s->rig,
                        s->base, s->shown);
    }
    if (threaded) pthread_join(th, NULL);
    if (rc) {
        snprintf(err, errlen, "session: out of memory for the contact guard");
        return rc;
    }
    if (job.rc) {
        snprintf(err, errlen, "session: out of memory finding the close sheets of %zu triangles",
                 s->mesh->triangle_count);
        return job.rc;
    }
    return 0;
}

/* The mapping and the inputs, the calibration, the inputs' clock, the mapping step. 0 or the
 * code. */
static int open_inputs(fp_session *s, const fp_session_options *opt, char *err, size_t errlen)
{
    int rc = 0;
    fp__session_mapping_services(s);
    progress(opt, "loading the mapping and %zu input%s", opt->input_count, opt->input_count == 1 ? "" : "s");
    if ((rc = fp__session_load_mapping(s, opt->mapping, opt->plugin_path, NULL, err, errlen))) return rc;
    for (size_t i = 0; i < opt->input_count; i++) {
        rc = fp_input_instance_open_isolated(&s->inputs[i], opt->plugin_path, opt->inputs[i], (uint32_t)i,
                                             s->isolate, &s->isolate_opt, err, errlen);
        if (rc) return rc;
        s->input_count = i + 1;
        /* its log lines (relayed from any thread) straight to the session's callback, on the
         * thread that drains them: the session's (as the mapping host's) */
        fp_input_instance_set_log(&s->inputs[i], s->log.fn, s->log.user);
        fp_input_instance_drain_log(&s->inputs[i]); /* what its create said */
    }
    if ((rc = fp__session_performers_open(s, opt, err, errlen))) return rc; /* and calibrate */
    s->intents.clocked = opt->input_clock;
    for (size_t i = 0; i < s->input_count && opt->input_clock; i++) {
        const fp_input *in = s->inputs[i].input;
        const fp_input_recording *ri = in && in->get_extension
                                           ? in->get_extension(in, FP_EXT_RECORDING_INFO) : NULL;
        const fp_input_clock *ck = in && in->get_extension ? in->get_extension(in, FP_EXT_INPUT_CLOCK) : NULL;
        fp_recording_info info;
        s->intents.waited[i] = (ri && ri->get && ri->get(in, &info)) ||
                               (ck && ck->on_recording_clock && ck->on_recording_clock(in));
    }
    fp_mapping_step_init(&s->mapping_step, &s->cs, s->mapping_budget_ms);
    return 0;
}

int fp_session_create(const fp_session_options *opt, fp_session **out, char *err, size_t errlen)
{
    *out = NULL;
    int rc = check_options(opt, err, errlen);
    if (rc) return rc;
    fp_session *s = calloc(1, sizeof *s);
    if (!s) return -ENOMEM;
    s->guard_dp_n = SIZE_MAX; /* (nothing kept: anything) */
    s->log = (fp_slog){opt->log, opt->log_user};
    if (fp_log_relay_init(&s->mapping_relay)) {
        free(s);
        return -ENOMEM;
    }
    double diag = 0;
    if ((rc = open_mesh(s, opt, &diag, err, errlen)) || (rc = open_scale(s, opt, diag, err, errlen)) ||
        (rc = open_steps(s, opt, diag, err, errlen)) || (rc = open_inputs(s, opt, err, errlen)))
        goto fail;
    if (opt->progress) opt->progress(opt->progress_user, NULL);
    *out = s;
    return 0;
fail:
    if (opt->progress) opt->progress(opt->progress_user, NULL);
    fp_session_destroy(&s);
    return rc ? rc : -EINVAL;
}

int fp_session_start(fp_session *s, char *err, size_t errlen)
{
    for (size_t i = 0; i < s->input_count; i++) {
        int rc = fp_input_instance_start(&s->inputs[i], err, errlen);
        fp_input_instance_drain_log(&s->inputs[i]); /* what its start said */
        if (rc) return rc;
    }
    /* the frame thread (fp_session_options.frame_thread): a frame whose data fit in a core's
     * caches runs on a core that stayed awake. Larger meshes do not fit; their contact guard
     * shares its check between the caller and its own worker, which a third busy thread
     * would slow down (the 1.7M face's frame, one trial run: 4.9 ms median with one, 2.6
     * without). None
     * could be made: the frames run on the caller's. */
    bool want = s->frame_thread_opt > 0 ||
                (s->frame_thread_opt == 0 && sysconf(_SC_NPROCESSORS_ONLN) >= 2 &&
                 s->mesh->triangle_count <= FP_CONTACT_PREWARM);
    if (want && !s->ft && fp_frame_thread_create(&s->ft))
        fp_slog_printf(&s->log, FP_LOG_DEBUG, "session", "no frame thread: frames run on the caller's");
    return 0;
}
