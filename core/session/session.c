/* The session: creation, destruction, accessors, and fp_session_step as the frame's seven
 * steps (shared/docs/design.md "One frame"; each step is a module of its own). */
#define _GNU_SOURCE
#include "fp_session.h"

#include "changed.h"
#include "contact.h"
#include "csrbf.h"
#include "fp_plugin_crash.h"
#include "fp_mesh.h"
#include "fp_pose.h"
#include "fp_rig.h"
#include "frame_thread.h"
#include "history.h"
#include "intents.h"
#include "step_engine.h"
#include "step_mapping.h"
#include "step_record.h"
#include "step_rig.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#if defined(__GLIBC__)
#include <malloc.h> /* mallopt: fp_session_realtime_memory */
#endif
#include <sys/mman.h> /* madvise: fp_session_realtime_memory */
#include <sys/stat.h> /* stat: the mesh file's size for progress */

_Static_assert(FP_INTENTS_MAX_INPUTS == FP_SESSION_MAX_INPUTS, "one input limit");
_Static_assert(FP_HISTORY_LEVELS == FP_SESSION_UNDO_LEVELS, "one undo depth");

struct fp_session {
    fp_mesh *mesh;
    size_t n;
    float *loaded, *base, *deformed;
    const float *shown;
    fp_slog log;

    fp_input_instance inputs[FP_SESSION_MAX_INPUTS];
    size_t input_count;
    bool stopped;                 /* fp_session_stop ran */

    fp_plugin mapping_plugin;
    fp_mapping *mapping;
    fp_mapping_host mapping_host;
    fp_log_relay mapping_relay; /* the mapping's log lines until the session thread hands them over */
    fp_mapping_services services;     /* the host extensions the mapping may ask for */
    char mapping_name[64];
    char mapping_spec[1024];      /* the SPEC it was made from (keys kept for a reload) */
    char mapping_file[4096];      /* the file it was found at (a reload loads a copy) */
    double mapping_budget_ms;
    fp_mesh_view view;
    char rig_how[1200];           /* how the rig was chosen (fp_session_rig_how) */

    double radius;
    fp_head head;                 /* the head and the mesh's unit (life-size calibration) */
    bool engaged;                 /* the mapping's deformation is active */
    uint64_t frame;
    uint32_t actions;             /* FP_SESSION_ACTION_* since the last frame (recorded) */

    fp_intents intents;           /* step 1 */
    fp_pose_state pose;           /* step 2 */
    fp_mapping_step mapping_step; /* step 3 */
    fp_rig_step rig;              /* step 4 */
    fp_engine_step engine;        /* step 5 */
    fp_history history;           /* step 6 */
    fp_record_step record;        /* step 7 */

    fp_control_set cs;            /* its arrays are the mapping step's (with canaries) */

    /* the contact guard (contact.h, its incremental form); NULL with no_contact_guard */
    fp_contact *contact;
    int cg_sync;                  /* FP_CG_*: what the guard's P must catch up with */
    float cg_pose[FP_RIG_MAX_CHANNELS]; /* the channel values its rest normals were posed by */
    bool cg_posed;                /* cg_pose is set (fp_contact_set_pose was called) */
    bool cg_lost;                 /* the guard ran out of memory: made anew, the base shown
                                     until then */
    unsigned long cg_frames, cg_limited; /* this gesture: frames checked, scaled back */
    double cg_t;                  /* this gesture: smallest fraction kept */
    float cg_hold;                /* fp_contact_hold's eps (mesh units): FP_CONTACT_HOLD of the
                                     loaded face's diagonal (view.bounds); 0: none
                                     (options.exact_frames) */

    /* what changed since the viewer last asked (fp_session_touched, changed.h) */
    fp_changed shown_changed, base_changed;
    fp_changed cg_ref;            /* where the reference changed since the guard last took it
                                     (FP_CG_REF_CHANGED: fp_contact_reference compares there) */
    uint8_t *gc_mark;             /* guard_ranges: a byte per block of 16 vertices (zero */
    uint32_t *gc_blk, *gc_ranges; /*   between calls), the blocks listed, their ranges */
    int shown_kind;               /* what s->shown held at the end of the last frame: */
    bool whole_rig_commit;        /* fp_session_options.whole_rig_commit */
    int frame_thread_opt;         /* fp_session_options.frame_thread */
    fp_frame_thread *ft;          /* the frame thread (frame_thread.h; fp_session_start),
                                     or NULL: frames run on the caller's */
};

enum {
    SHOWN_POSED,    /* the posed base */
    SHOWN_ENGINE,   /* the engine's output (through the rig's blend): differs from the posed
                       base only inside the engine's touched ranges */
    SHOWN_OTHER     /* the contact guard's shape */
};

#define FP_CONTACT_BISECTIONS 6
/* The guard's P (the shape it last accepted) and the frame's reference, the posed base: */
enum {
    FP_CG_SYNCED = 0,   /* P is the shape shown, on the current reference */
    FP_CG_SHOWN_REF,    /* the reference was shown since (a gesture ended): P := ref at D_P */
    FP_CG_REF_CHANGED   /* the reference changed (a pose, undo, reset: anywhere; a commit with a
                           rig: on its ranges): compare there (s->cg_ref) and at D_P */
};
/* pairs within this many vertex rings of the input's own crossings are not the guard's
 * business (fp_contact_dilate_own): the eyes' intersection curves move under any motion */
#define FP_CONTACT_OWN_RINGS 1
/* fp_contact_hold's eps, a fraction of the loaded face's bounding-box diagonal: a vertex
 * that moved less than this since the last frame keeps its place until it moves more or a
 * commit (4.75 um on the ICT face, 47.5 cm across: about 1/25 of a pixel where the face
 * fills a 4K screen) */
#define FP_CONTACT_HOLD 1e-5

_Static_assert(FP_ENGINE_MAX_CONTROL >= FP_CONTROL_CAPACITY, "the engine takes a full control set");

/* ---- creation -------------------------------------------------------------------------- */

/* The contact guard on the loaded mesh (its own crossings widened by FP_CONTACT_OWN_RINGS),
 * started on the shape shown. Returns 0 or -ENOMEM (s->contact NULL). */
static int contact_open(fp_session *s)
{
    int rc = fp_contact_create(s->mesh->triangles, s->mesh->triangle_count, s->n, s->loaded, &s->contact);
    if (!rc) rc = fp_contact_dilate_own(s->contact, FP_CONTACT_OWN_RINGS);
    /* a large mesh's checks on two threads where there are two cores (contact.h: the
     * caller never waits for a worker that has not started; small meshes stay on one) */
    if (!rc) fp_contact_set_threads(s->contact, sysconf(_SC_NPROCESSORS_ONLN) >= 2 ? 2 : 1, 0);
    /* flips judged from where the rig's pose put each triangle (O(t): here, once, not at the
     * first commit of a performance) */
    if (!rc && s->rig.rig) {
        rc = fp_contact_set_pose(s->contact, s->base, s->shown);
        memcpy(s->cg_pose, s->rig.posed_values, sizeof s->cg_pose);
        s->cg_posed = !rc;
    }
    if (!rc) rc = fp_contact_reference(s->contact, s->shown, NULL, SIZE_MAX);
    if (rc) fp_contact_destroy(&s->contact);
    const uint32_t *r;
    fp_changed_take(&s->cg_ref, &r); /* from here: where the reference changes */
    s->cg_sync = FP_CG_SYNCED;
    return rc;
}

/* Load the mapping of SPEC `mapping` (from `file` where not NULL: a copy being hot-reloaded)
 * and create it with the SPEC's keys. */
static int load_mapping(fp_session *s, const char *mapping, const fp_plugin_path *path,
                        const char *file, char *err, size_t errlen)
{
    fp_spec spec;
    int rc = fp_spec_parse(mapping ? mapping : "anchored", &spec, err, errlen);
    if (rc) return rc;
    if (spec.arg) {
        snprintf(err, errlen, "mapping '%s': a mapping takes no ':ARG', only keys", mapping);
        fp_spec_clear(&spec);
        return -EINVAL;
    }
    rc = fp_plugin_load(path, FP_PLUGIN_MAPPING, file ? file : spec.name, &s->mapping_plugin, err, errlen);
    if (!rc) {
        snprintf(s->mapping_name, sizeof s->mapping_name, "%s", spec.name);
        fp_mapping_host_init(&s->mapping_host, spec.name, s->log.fn, s->log.user);
        s->mapping_host.rig = fp_rig_step_view(&s->rig); /* FP_HOST_EXT_RIG */
        s->mapping_host.services = &s->services; /* FP_HOST_EXT_SURFACE */
        s->mapping_host.relay = &s->mapping_relay;
        const fp_mapping_factory *f = s->mapping_plugin.factory;
        char perr[512] = "";
        fp_plugin_call_enter(s->mapping_name, "create", s->frame);
        rc = f->create(&s->mapping_host.host, spec.params, spec.nparams, &s->mapping, perr, sizeof perr);
        fp_plugin_call_leave();
        fp_mapping_host_drain_log(&s->mapping_host); /* what its create said */
        if (rc || !s->mapping) {
            snprintf(err, errlen, "mapping '%s': %s", mapping,
                     perr[0] ? perr : rc ? "create failed" : "create returned 0 without an instance");
            s->mapping = NULL;
            rc = rc ? rc : FP_EPLUGIN_FAULT;
        } else {
            snprintf(s->mapping_spec, sizeof s->mapping_spec, "%s", mapping);
            if (!file) snprintf(s->mapping_file, sizeof s->mapping_file, "%s", s->mapping_plugin.path);
        }
    }
    fp_spec_clear(&spec);
    return rc;
}

/* FP_HOST_EXT_SURFACE: nearest vertices of the surface the fingers touch (the posed base),
 * from the engine's index of it. */
static int surface_nearest(const fp_host *host, const float (*points)[3], size_t count,
                           float max_distance, fp_surface_hit *out)
{
    const fp_session *s = ((const fp_mapping_host *)host->host_data)->services->user;
    return fp_engine_step_surface(&s->engine, fp_rig_step_posed(&s->rig, s->base), points, count,
                                  max_distance, out);
}

/* Workspace calibration (step 2's state): the mesh's unit (given, else detected from the
 * head), then the calibration (given, else the inputs' workspaces, or the default one,
 * fitted life-size in front of the face), then the glove placement. */
static int calibrate(fp_session *s, const fp_session_options *opt, char *err, size_t errlen)
{
    fp_calibration c;
    if (opt->calibration) {
        c = *opt->calibration;
        if (!(c.scale > 0) || !isfinite(c.scale)) {
            snprintf(err, errlen, "calibration: scale must be > 0, got %g", c.scale);
            return -EINVAL;
        }
        s->head.mm_per_unit = 1.0 / c.scale;
        s->head.method = FP_HEAD_GIVEN;
        snprintf(s->head.how, sizeof s->head.how, "from the calibration");
    } else {
        fp_input *ins[FP_SESSION_MAX_INPUTS];
        for (size_t i = 0; i < s->input_count; i++) ins[i] = s->inputs[i].input;
        float wmin[3], wmax[3];
        if (!fp_pose_inputs_workspace(ins, s->input_count, wmin, wmax)) fp_pose_default_workspace(wmin, wmax);
        fp_pose_fit_workspace(&c, s->head.mm_per_unit, wmin, wmax, s->head.min, s->head.max);
    }
    s->pose.calib = c;
    fp_pose_place_gloves(&s->pose, s->loaded, s->n, &s->head);
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
        snprintf(s->rig_how, sizeof s->rig_how, "%s (given; mesh checksum %s)", opt->rig_path,
                 fp_rig_checksum_matches(rig, s->n, s->loaded) ? "matches" : "differs, same vertex count");
    } else {
        char dir[1024], path[1024], msg[1200] = "";
        const char *d = opt->rig_dir ? opt->rig_dir : fp_rig_default_dir(NULL, dir, sizeof dir);
        rc = fp_rig_find(d, s->n, s->loaded, path, sizeof path, msg, sizeof msg);
        if (rc) {
            snprintf(s->rig_how, sizeof s->rig_how, "none (%s)", msg);
        } else {
            if ((rc = fp_rig_load_for_mesh(path, s->n, s->loaded, &rig, err, errlen))) return rc;
            if (fp_rig_checksum_matches(rig, s->n, s->loaded))
                snprintf(s->rig_how, sizeof s->rig_how, "%s (found by the mesh's checksum %08x)", path,
                         fp_rig_mesh_crc32(rig));
            else
                snprintf(s->rig_how, sizeof s->rig_how, "%s (found by the vertex count %zu)", path, s->n);
        }
    }
    if ((rc = fp_rig_step_init(&s->rig, rig, s->n, s->base))) {
        snprintf(err, errlen, "session: out of memory for the rig");
        return rc;
    }
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

int fp_session_create(const fp_session_options *opt, fp_session **out, char *err, size_t errlen)
{
    *out = NULL;
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
        snprintf(err, errlen, "--radius must be > 0 (mesh units), got %g", opt->radius);
        return -EINVAL;
    }
    fp_session *s = calloc(1, sizeof *s);
    if (!s) return -ENOMEM;
    s->log = (fp_slog){opt->log, opt->log_user};
    int rc = 0;
    if (fp_log_relay_init(&s->mapping_relay)) {
        free(s);
        return -ENOMEM;
    }
    if (opt->mesh) {
        if (!(s->mesh = fp_mesh_copy(opt->mesh))) {
            rc = -ENOMEM;
            snprintf(err, errlen, "session: out of memory for the mesh");
            goto fail;
        }
    } else {
        struct stat fst;
        if (opt->progress && !stat(opt->mesh_path, &fst))
            progress(opt, "loading %s (%.0f MiB)", file_name(opt->mesh_path),
                     ceil((double)fst.st_size / 1048576.0));
        if ((rc = fp_mesh_load(opt->mesh_path, &s->mesh, err, errlen))) goto fail; /* its code */
    }
    s->n = s->mesh->vertex_count;
    size_t bytes = s->n * 3 * sizeof(float);
    s->loaded = malloc(bytes);
    s->base = malloc(bytes);
    s->deformed = malloc(bytes);
    if (!s->loaded || !s->base || !s->deformed) {
        rc = -ENOMEM;
        snprintf(err, errlen, "session: out of memory for %zu vertices", s->n);
        goto fail;
    }
    memcpy(s->loaded, s->mesh->positions, bytes);
    memcpy(s->base, s->loaded, bytes);
    memcpy(s->deformed, s->loaded, bytes);
    s->shown = s->base;
    fp_mesh_bounds(s->mesh, s->view.bounds_min, s->view.bounds_max);
    s->view.vertex_count = s->n;
    s->view.base = s->base;
    double diag = 0;
    for (int i = 0; i < 3; i++) {
        double d = s->view.bounds_max[i] - s->view.bounds_min[i];
        diag += d * d;
    }
    if (fp_head_detect(s->loaded, s->n, &s->head)) {
        snprintf(err, errlen, "%s: cannot find a head in %zu vertices (flat or non-finite mesh)",
                 opt->mesh_path, s->n);
        rc = -EBADMSG; /* the mesh's fault: bad input data (65), as calibrate says */
        goto fail;
    }
    if ((rc = attach_rig(s, opt, err, errlen))) goto fail;
    s->shown = s->view.base = fp_rig_step_posed(&s->rig, s->base);
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
    if (opt->radius > 0 && opt->radius < 1e-6 * sqrt(diag)) {
        rc = -EINVAL;
        snprintf(err, errlen, "--radius %g is below a millionth of the mesh's bounding-box "
                 "diagonal (%.4g mesh units): no vertex would move; give a radius in mesh units",
                 opt->radius, sqrt(diag));
        goto fail;
    }
    {   /* a given scale that makes the face under a millimetre or over a kilometre across is
         * a slip (mm per unit for units per mm, a unit's power of ten): no hand would reach it */
        double across_mm;
        if ((opt->mm_per_unit > 0 || (opt->calibration && opt->calibration->scale > 0)) &&
            !fp_head_scale_plausible(sqrt(diag), s->head.mm_per_unit, &across_mm)) {
            rc = opt->mm_per_unit > 0 ? -EINVAL : -ERANGE; /* an option's, or a file's (65) */
            snprintf(err, errlen, "%s: %g mm per mesh unit makes the face %.3g mm across "
                     "(its diagonal %.4g mesh units); give millimetres per mesh unit",
                     opt->mm_per_unit > 0 ? "--mm-per-unit" : "the calibration's scale",
                     s->head.mm_per_unit, across_mm, sqrt(diag));
            goto fail;
        }
    }
    if (opt->radius > 10 * sqrt(diag)) {
        rc = -EINVAL;
        snprintf(err, errlen, "--radius %g is beyond 10x the mesh's bounding-box diagonal (%.4g "
                 "mesh units): every vertex would move as one; give a radius in mesh units",
                 opt->radius, sqrt(diag));
        goto fail;
    }
    /* Default radius: 6% of the bounding-box diagonal, at least a fingertip's reach
     * (FP_SESSION_MIN_RADIUS_MM): on a sparse mask (MediaPipe's 468 vertices) a smaller one
     * holds hardly a vertex. */
    s->radius = opt->radius > 0 ? opt->radius
                                : fmax(0.06 * sqrt(diag), FP_SESSION_MIN_RADIUS_MM / s->head.mm_per_unit);
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
    fp_pose_init(&s->pose, opt->hand_size, NULL);
    if ((rc = fp_history_init(&s->history, s->n, s->base))) {
        snprintf(err, errlen, "session: out of memory for the undo history");
        goto fail;
    }
    fp_record_step_init(&s->record, opt->record, opt->record_user);
    progress(opt, "indexing %zu vertices", s->n);
    if ((rc = fp_engine_step_init(&s->engine, s->n, s->shown, threads))) {
        snprintf(err, errlen, "session: cannot index %zu vertices", s->n);
        goto fail;
    }
    /* the output buffer starts as the surface the engine indexes (the posed base), so the
     * first run writes only the blocks in a support, not the whole mesh */
    memcpy(s->deformed, s->shown, bytes);
    fp_engine_step_output_is_base(&s->engine);
    s->mapping_budget_ms = opt->mapping_budget_ms;
    s->whole_rig_commit = opt->whole_rig_commit;
    s->frame_thread_opt = opt->frame_thread;
    /* the hold's eps from the loaded face's diagonal (diag: its square, above) */
    s->cg_hold = opt->exact_frames || !isfinite(diag) ? 0.0f : (float)(FP_CONTACT_HOLD * sqrt(diag));
    s->engine.jacobian = opt->measure_jacobian;
    if ((rc = fp_engine_step_set_topology(&s->engine, s->mesh->triangles, s->mesh->triangle_count))) {
        snprintf(err, errlen, "session: out of memory for %zu triangles", s->mesh->triangle_count);
        goto fail;
    }
    if (!opt->no_contact_guard) {
        progress(opt, "building the contact guard over %zu triangles", s->mesh->triangle_count);
        if ((rc = contact_open(s))) {
            rc = rc ? rc : -ENOMEM;
            snprintf(err, errlen, "session: out of memory for the contact guard");
            goto fail;
        }
    }
    s->services.surface.nearest = surface_nearest;
    s->services.user = s;
    progress(opt, "loading the mapping and %zu input%s", opt->input_count, opt->input_count == 1 ? "" : "s");
    if ((rc = load_mapping(s, opt->mapping, opt->plugin_path, NULL, err, errlen))) goto fail;
    for (size_t i = 0; i < opt->input_count; i++) {
        rc = fp_input_instance_open(&s->inputs[i], opt->plugin_path, opt->inputs[i], (uint32_t)i,
                                    err, errlen);
        if (rc) goto fail;
        s->input_count = i + 1;
        /* its log lines (relayed from any thread) straight to the session's callback, on the
         * thread that drains them: the session's (as the mapping host's) */
        fp_input_instance_set_log(&s->inputs[i], s->log.fn, s->log.user);
        fp_input_instance_drain_log(&s->inputs[i]); /* what its create said */
    }
    if ((rc = calibrate(s, opt, err, errlen))) goto fail;
    s->intents.clocked = opt->input_clock;
    for (size_t i = 0; i < s->input_count && opt->input_clock; i++) {
        const fp_input *in = s->inputs[i].input;
        const fp_input_recording *ri = in && in->get_extension
                                           ? in->get_extension(in, FP_EXT_RECORDING_INFO) : NULL;
        fp_recording_info info;
        s->intents.waited[i] = ri && ri->get && ri->get(in, &info);
    }
    fp_mapping_step_init(&s->mapping_step, &s->cs, s->mapping_budget_ms);
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

/* Real-time memory (fp_session.h). A page fault took about 10 us on the 2-core VM
 * (a first write to fresh anonymous pages, 64 at a time); before this the ICT replay's
 * renewing and committing frames took 1 to 9 each (the undo level's arrays growing, the
 * contact guard's renewed lists), and they were its slowest frames. glibc's malloc gives
 * freed memory back to the system (trim, munmap of large chunks) and maps new memory for
 * growth (brk, mmap, a thread's own arena); with these settings it keeps what it has, serves
 * large blocks from the heap and one arena, so the reserve touched here is what a frame's
 * allocations reuse. */
#define FP_RT_RESERVE_BASE (32u << 20)  /* bytes: the reserve, at least */
#define FP_RT_RESERVE_PER_VERTEX 32u    /* bytes a vertex more (an undo level of the whole
                                           mesh is 12 a vertex, with its pieces' list) */
#define FP_RT_BLOCK 4096u               /* bytes: the reserve's blocks */
#define FP_RT_STACK (512u << 10)        /* bytes of the calling thread's stack touched */

/* The process's code mapped in (MADV_POPULATE_READ, Linux 5.14, on every executable file
 * mapping: the program, the libraries, the plugins loaded): a code page first run in a frame
 * (a gesture's first contact check) faults otherwise. Best effort: without /proc or that
 * advice the first run of a page still faults. */
static void populate_code(void)
{
#if defined(MADV_POPULATE_READ)
    FILE *f = fopen("/proc/self/maps", "re");
    if (!f) return;
    char line[4352];
    while (fgets(line, sizeof line, f)) {
        unsigned long lo, hi;
        char perm[8];
        int path_at = 0;
        if (sscanf(line, "%lx-%lx %7s %*s %*s %*s %n", &lo, &hi, perm, &path_at) < 3 || !path_at) continue;
        if (strcmp(perm, "r-xp") || line[path_at] != '/' || hi <= lo) continue; /* a file's code */
        (void)madvise((void *)lo, hi - lo, MADV_POPULATE_READ);
    }
    fclose(f);
#endif
}

/* FP_RT_STACK bytes of this thread's stack below the caller's frame written (not inlined:
 * its array is the stack touched) */
static __attribute__((noinline)) void touch_stack(void)
{
    volatile unsigned char pad[FP_RT_STACK];
    for (size_t i = 0; i < sizeof pad; i += 1024) pad[i] = 0;
}

int fp_session_realtime_memory(fp_session *s, size_t reserve_bytes, char *err, size_t errlen)
{
    if (!s) {
        if (err && errlen) snprintf(err, errlen, "real-time memory: no session");
        return -EINVAL;
    }
#if defined(__GLIBC__)
    if (!reserve_bytes) reserve_bytes = FP_RT_RESERVE_BASE + FP_RT_RESERVE_PER_VERTEX * s->n;
    if (!mallopt(M_TRIM_THRESHOLD, INT_MAX) || !mallopt(M_MMAP_MAX, 0) || !mallopt(M_ARENA_MAX, 1)) {
        if (err && errlen) snprintf(err, errlen, "real-time memory: the C library refused a malloc setting (mallopt)");
        return -ENOTSUP;
    }
    /* in blocks, so that free memory inside the heap that nothing wrote yet (calloc's fresh
     * pages, blocks freed untouched: glibc serves a request from those before its top) is
     * written too, then the top */
    size_t nb = (reserve_bytes + FP_RT_BLOCK - 1) / FP_RT_BLOCK, got = 0;
    volatile unsigned char **b = malloc(nb * sizeof *b);
    while (b && got < nb && (b[got] = malloc(FP_RT_BLOCK))) {
        b[got][0] = 0; /* a block spans two pages at most */
        b[got++][FP_RT_BLOCK - 1] = 0;
    }
    bool whole = b && got == nb;
    while (got > 0) free((void *)b[--got]);
    free(b);
    if (!whole) {
        if (err && errlen) snprintf(err, errlen, "real-time memory: out of memory for a reserve of %zu MiB", reserve_bytes >> 20);
        return -ENOMEM;
    }
    touch_stack();
    populate_code();
    return 0;
#else
    (void)reserve_bytes;
    if (err && errlen) snprintf(err, errlen, "real-time memory: not supported by this C library (glibc only)");
    return -ENOTSUP;
#endif
}

/* ---- one frame ------------------------------------------------------------------------- */

/* Every drained event: to the pose step (through its input's filter) and, raw, to the
 * frame's record. */
static void on_event(void *user, size_t input, const fp_event *ev)
{
    fp_session *s = user;
    fp_pose_take_event_filtered(&s->pose, ev, input < s->input_count ? &s->inputs[input].filter : NULL);
    fp_record_step_event(&s->record, ev);
}

/* The contact guard's reference (the posed base) changed on ranges (count SIZE_MAX:
 * anywhere): its next call compares P there and at D_P (fp_contact_reference). */
static void reference_changed(fp_session *s, const uint32_t *ranges, size_t count)
{
    fp_changed_add(&s->cg_ref, ranges, count);
    s->cg_sync = FP_CG_REF_CHANGED;
}

/* The base changed (commit, undo, reset): the rig poses it, the engine re-indexes the posed
 * base, which is shown. */
static void base_changed(fp_session *s)
{
    fp_changed_all(&s->shown_changed);
    fp_changed_all(&s->base_changed);
    s->shown_kind = SHOWN_POSED;
    fp_rig_step_base_changed(&s->rig);
    fp_rig_step_update(&s->rig, NULL, s->base, &s->log);
    s->shown = fp_rig_step_posed(&s->rig, s->base);
    fp_engine_step_set_base(&s->engine, s->shown);
    reference_changed(s, NULL, SIZE_MAX);
}

/* The shape shown is the reference again (a frame without a deformation, an engine error):
 * the contact guard's P catches up before its next check. */
static void shown_ref(fp_session *s)
{
    if (s->cg_sync == FP_CG_SYNCED) s->cg_sync = FP_CG_SHOWN_REF;
}

/* The contact guard (contact.h, incremental): the frame's shape (s->shown) against the shape
 * shown last (the guard's P), on the reference ref (the posed base): when it adds
 * self-crossings or flipped triangles against ref, this frame's motion is scaled back
 * (fp_contact_step) and s->shown becomes the guard's shape. Without a rig, by induction
 * over commits, the shown surface never crosses itself where the loaded face did not; a
 * rig's own pose (its channels) is not checked. The guard looks only where the shape may
 * have changed: the engine's touched ranges (the rig's blend moves no vertex the fingers
 * did not). */
static void contact_guard(fp_session *s, const float *ref, bool commit, fp_frame_stats *st)
{
    if (s->cg_lost && s->shown != ref) { /* the guard is made anew on the shape shown: ref */
        const float *shown = s->shown;
        s->shown = ref;
        if (contact_open(s)) return; /* still no memory: the base stays */
        s->cg_lost = false;
        s->shown = shown; /* P is ref, shown last frame; the rig's pose set by contact_open */
    }
    if (!s->contact || s->shown == ref) return;
    int64_t t0 = fp_now_ns();
    fp_contact_set_local(s->contact, s->radius); /* a blocked finger stops alone */
    int rc = 0;
    /* flips are judged from where the rig's pose put each triangle (fp_contact_set_pose,
     * O(t): when the channels changed, not at every commit): the open jaw turns the ICT
     * mouth corners 89 degrees from the neutral face */
    if (s->cg_sync == FP_CG_REF_CHANGED && s->rig.rig &&
        (!s->cg_posed || memcmp(s->cg_pose, s->rig.posed_values, sizeof s->cg_pose))) {
        rc = fp_contact_set_pose(s->contact, s->base, ref);
        memcpy(s->cg_pose, s->rig.posed_values, sizeof s->cg_pose);
        s->cg_posed = true;
    }
    if (!rc && s->cg_sync != FP_CG_SYNCED) {
        /* P differs from the old reference at D_P only, the new one from the old where
         * cg_ref says (a rig's commit: its ranges, so not all n vertices compared: 0.08-0.12
         * ms on the ICT face, in the next gesture's first frame) */
        const uint32_t *rr = NULL;
        size_t nr = s->cg_sync == FP_CG_REF_CHANGED ? fp_changed_take(&s->cg_ref, &rr) : 0;
        rc = fp_contact_reference(s->contact, ref, rr, nr);
    }
    s->cg_sync = FP_CG_SYNCED;
    const uint32_t *ranges;
    size_t nranges = fp_engine_step_touched(&s->engine, &ranges);
    fp_contact_result r;
    /* the hold (fp_contact_hold): vertices that moved less than cg_hold keep their place;
     * never in a commit's frame, so the base gets the engine's shape. The candidate is the
     * engine's output or the rig's blend of it, each rewritten next frame wherever it
     * differs from the posed base now (the engine's touched ranges then hold this frame's
     * supports), so a held vertex is never left behind */
    float *cand = s->shown == s->deformed ? s->deformed
                  : s->rig.rig && s->shown == s->rig.shown ? s->rig.shown : NULL;
    if (!rc && !commit && s->cg_hold > 0 && cand)
        st->collide_held = fp_contact_hold(s->contact, ref, cand, ranges, nranges, s->cg_hold);
    if (!rc) rc = fp_contact_step(s->contact, ref, s->shown, ranges, nranges, FP_CONTACT_BISECTIONS, &r);
    st->collide_ms += (double)(fp_now_ns() - t0) / 1e6;
    if (rc) { /* out of memory: the guard is unusable; show the reference, a new guard next frame */
        s->shown = ref;
        fp_contact_destroy(&s->contact);
        s->cg_lost = true;
        fp_slog_printf(&s->log, FP_LOG_ERROR, FP_SLOG_CONTACT, "contact guard: out of memory; showing the base");
        return;
    }
    st->collide_pairs += r.pairs;
    st->collide_wait_ms += r.worker_wait_ms;
    st->collide_checks += r.checks;
    st->collide_moved += r.moved_verts;
    if (!s->cg_frames) s->cg_t = 1.0;
    s->cg_frames++;
    if (r.t < 1) {
        s->shown = fp_contact_shape(s->contact);
        s->cg_limited++;
        if (r.t < s->cg_t) s->cg_t = r.t;
        if (r.t < st->collide_t) st->collide_t = r.t;
    }
}

/* The gesture ended: one line when the contact guard scaled it back. */
static void contact_end_gesture(fp_session *s)
{
    if (s->cg_limited)
        fp_slog_printf(&s->log, FP_LOG_WARNING, FP_SLOG_CONTACT,
                       "contact guard stopped the surface from passing through itself: %lu of "
                       "%lu frames scaled back (least share of a frame's motion kept %.0f%%)",
                       s->cg_limited, s->cg_frames, 100.0 * s->cg_t);
    s->cg_frames = s->cg_limited = 0;
}

#define FP_GC_SHIFT 4 /* guard_ranges: blocks of 16 vertices */

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* Where the contact guard's shape (P) and the engine's output may differ from the base: the
 * blocks of 16 vertices holding the guard's D_P (fp_contact_differs) or a touched range (tr,
 * nt), as increasing, disjoint vertex ranges in s->gc_ranges; returns their number, SIZE_MAX
 * when unknown (nt == SIZE_MAX) or out of memory. O(D_P + touched), no pass over n. */
static size_t guard_ranges(fp_session *s, const uint32_t *tr, size_t nt, const uint32_t **out)
{
    size_t nb = (s->n >> FP_GC_SHIFT) + 1;
    if (nt == SIZE_MAX) return SIZE_MAX;
    if (!s->gc_mark) {
        s->gc_mark = calloc(nb, 1);
        s->gc_blk = malloc((nb + 1) * sizeof *s->gc_blk); /* (+1: the store before the test) */
        s->gc_ranges = malloc(2 * nb * sizeof *s->gc_ranges);
        if (!s->gc_mark || !s->gc_blk || !s->gc_ranges) {
            free(s->gc_mark), free(s->gc_blk), free(s->gc_ranges);
            s->gc_mark = NULL, s->gc_blk = s->gc_ranges = NULL;
            return SIZE_MAX;
        }
    }
    const uint32_t *dp;
    size_t ndp = fp_contact_differs(s->contact, &dp), k = 0;
    for (size_t i = 0; i < ndp; i++) {
        uint32_t b = dp[i] >> FP_GC_SHIFT;
        s->gc_blk[k] = b;
        k += !s->gc_mark[b];
        s->gc_mark[b] = 1;
    }
    for (size_t r = 0; r < nt; r++) {
        if (!tr[2 * r + 1]) continue;
        size_t b0 = tr[2 * r] >> FP_GC_SHIFT, b1 = (tr[2 * r] + tr[2 * r + 1] - 1) >> FP_GC_SHIFT;
        for (size_t b = b0; b <= b1; b++) {
            s->gc_blk[k] = (uint32_t)b;
            k += !s->gc_mark[b];
            s->gc_mark[b] = 1;
        }
    }
    qsort(s->gc_blk, k, sizeof *s->gc_blk, cmp_u32);
    size_t nr = 0;
    for (size_t i = 0; i < k;) {
        size_t b0 = s->gc_blk[i], b1 = b0 + 1;
        s->gc_mark[b0] = 0;
        for (i++; i < k && s->gc_blk[i] == b1; i++) s->gc_mark[b1++] = 0;
        size_t v0 = b0 << FP_GC_SHIFT, v1 = b1 << FP_GC_SHIFT;
        s->gc_ranges[2 * nr] = (uint32_t)v0;
        s->gc_ranges[2 * nr + 1] = (uint32_t)((v1 < s->n ? v1 : s->n) - v0);
        nr++;
    }
    *out = s->gc_ranges;
    return nr;
}

/* A commit of the engine's output buffer: into the base (and the gesture's undo level) on the
 * touched ranges, outside which it equals the base; the whole buffer where they are unknown. */
static void commit_touched(fp_session *s)
{
    const uint32_t *r;
    size_t nr = fp_engine_step_touched(&s->engine, &r);
    if (nr == SIZE_MAX)
        fp_history_commit(&s->history, s->deformed);
    else
        fp_history_commit_ranges(&s->history, s->deformed, r, nr);
}

/* Steps 5 and 6 on the control set the engine is given (after the rig's clamp), on the
 * posed base: evaluate, the rig's mobility blend, show, commit. Shared by fp_session_step
 * and fp_session_apply_controls (takes played back). */
static void engine_and_history(fp_session *s, const fp_control_set *cs, fp_frame_stats *st)
{
    int was = s->shown_kind;
    const uint32_t *ranges;
    s->shown = fp_rig_step_posed(&s->rig, s->base);
    s->shown_kind = SHOWN_POSED;
    if (cs->active && cs->count > 0) {
        fp_engine_result er;
        int rc = fp_engine_step_run(&s->engine, cs, s->deformed, &er, &s->log);
        st->refactored = er.refactored;
        st->pairs = er.pairs;
        st->update_ms = er.update_ms;
        st->stage_ms[FP_STAGE_SOLVE] = er.update_ms - er.eval_ms;
        st->stage_ms[FP_STAGE_EVALUATE] = er.eval_ms;
        st->control_vectors = cs->count;
        st->guard_bound = er.bound;
        st->guard_clusters = er.clusters;
        st->guard_limited = er.clusters_limited;
        st->guard_substeps = er.substeps;
        st->guard_reached = er.reached;
        st->min_det_j = er.min_det_j;
        if (rc) s->rig.shown_valid = false; /* the output buffer may have changed unseen */
        if (!rc) {
            st->active = true;
            const float *ref = s->shown; /* the posed base */
            const uint32_t *touched;
            size_t ntouched = fp_engine_step_touched(&s->engine, &touched);
            s->shown = fp_rig_step_finish(&s->rig, s->deformed, touched, ntouched);
            contact_guard(s, ref, (cs->intents & FP_INTENT_COMMIT) != 0, st);
            /* the output differs from the last only in the engine's ranges (blocks in a
             * support now or at its last run), unless the guard's shape is or was shown */
            s->shown_kind = s->contact && s->shown == fp_contact_shape(s->contact) ? SHOWN_OTHER : SHOWN_ENGINE;
            if (s->shown_kind == SHOWN_OTHER || was == SHOWN_OTHER)
                fp_changed_all(&s->shown_changed);
            else
                fp_changed_add(&s->shown_changed, ranges, fp_engine_step_touched(&s->engine, &ranges));
            if (cs->intents & FP_INTENT_COMMIT) {
                int64_t t0 = fp_now_ns();
                const uint32_t *tr;
                size_t nt = fp_engine_step_touched(&s->engine, &tr);
                /* the contact guard's shape may differ from the posed base outside this
                 * frame's touched ranges (earlier frames scaled back), within its D_P:
                 * committed on both (guard_ranges) */
                bool guard_shown = s->contact && s->shown == fp_contact_shape(s->contact);
                const uint32_t *gr = tr;
                size_t ng = nt;
                /* with a rig, the guard's shape is committed on its D_P and the touched ranges
                 * (guard_ranges) as the blend is on the touched ranges */
                bool rig_whole = s->rig.rig && (nt == SIZE_MAX || s->whole_rig_commit ||
                                                !fp_rig_step_posed_current(&s->rig));
                if (s->rig.rig && !rig_whole && guard_shown)
                    rig_whole = (ng = guard_ranges(s, tr, nt, &gr)) == SIZE_MAX;
                if (rig_whole) {
                    /* with a rig only the fingers' part goes into the base; here the whole
                     * mesh is unposed, committed, posed and re-indexed */
                    fp_history_commit(&s->history, fp_rig_step_commit_shape(&s->rig, s->base, s->shown));
                    base_changed(s); /* the anchored gesture ended; unanchored restarts anyway */
                } else if (!s->rig.rig && guard_shown && !s->whole_rig_commit &&
                           (ng = guard_ranges(s, tr, nt, &gr)) != SIZE_MAX) {
                    /* the guard scaled the motion back: its shape goes into the output
                     * buffer and the base where either may differ from the base (D_P and
                     * this frame's touched ranges; bit for bit the whole path below), and
                     * only those ranges are re-indexed. The guard's P is that shape. */
                    for (size_t r = 0; r < ng; r++)
                        memcpy(s->deformed + 3 * (size_t)gr[2 * r], s->shown + 3 * (size_t)gr[2 * r],
                               3 * (size_t)gr[2 * r + 1] * sizeof(float));
                    fp_history_commit_ranges(&s->history, s->deformed, gr, ng);
                    fp_engine_step_commit_ranges(&s->engine, s->base, gr, ng);
                    s->shown = s->base;
                    s->shown_kind = SHOWN_POSED;
                    fp_changed_add(&s->shown_changed, gr, ng);
                    fp_changed_add(&s->base_changed, gr, ng);
                    s->cg_sync = FP_CG_SHOWN_REF;
                } else if (!s->rig.rig && guard_shown) {
                    /* the guard scaled the motion back: its shape goes into the base and
                     * the output buffer (it may differ from the base outside this frame's
                     * touched ranges: earlier frames scaled back); the engine re-indexes the
                     * whole base. The guard's P is that shape: nothing to catch up. */
                    memcpy(s->deformed, s->shown, s->n * 3 * sizeof(float));
                    fp_history_commit(&s->history, s->deformed);
                    fp_engine_step_set_base(&s->engine, s->base);
                    s->shown = s->base;
                    s->shown_kind = SHOWN_POSED;
                    fp_changed_all(&s->shown_changed);
                    fp_changed_all(&s->base_changed);
                    s->cg_sync = FP_CG_SHOWN_REF;
                } else if (s->rig.rig) {
                    /* the same on the ranges gr only: the touched ranges, where the blend
                     * may differ from the posed base, and with the guard's shape shown its D_P
                     * too (guard_ranges), so the commit shape equals the base outside them
                     * (fp_rig_unpose_range keeps unmoved vertices), and the base, the posed
                     * base, the engine's output and index change there only. Bit for bit the
                     * whole path. */
                    const float *cshape = fp_rig_step_commit_ranges(&s->rig, s->base, s->shown, gr, ng);
                    fp_history_commit_ranges(&s->history, cshape, gr, ng);
                    fp_changed_add(&s->base_changed, gr, ng);
                    fp_changed_add(&s->shown_changed, gr, ng); /* the posed base is shown */
                    fp_rig_step_rebase_ranges(&s->rig, s->base, s->deformed, gr, ng);
                    fp_engine_step_commit_ranges(&s->engine, fp_rig_step_posed(&s->rig, s->base), gr, ng);
                    s->shown = fp_rig_step_posed(&s->rig, s->base);
                    s->shown_kind = SHOWN_POSED;
                    reference_changed(s, gr, ng);
                } else {
                    /* the output buffer becomes the base on the touched ranges only, and
                     * only those are re-indexed; the anchored gesture ended, unanchored
                     * restarts anyway. The base changed where the output did. */
                    commit_touched(s);
                    fp_changed_add(&s->base_changed, ranges, fp_engine_step_touched(&s->engine, &ranges));
                    fp_engine_step_commit(&s->engine, s->base);
                    s->shown = s->base;
                    s->shown_kind = SHOWN_POSED;
                    /* the guard's P is the shape committed, the new reference: only D_P
                     * to compare */
                    s->cg_sync = FP_CG_SHOWN_REF;
                }
                st->stage_ms[FP_STAGE_COMMIT] = (double)(fp_now_ns() - t0) / 1e6;
                st->committed = true;
            }
        } else {
            fp_changed_all(&s->shown_changed); /* the posed base again, after an error */
            shown_ref(s); /* the engine failed: the posed base is shown */
        }
    } else {
        /* the posed base: where the engine's last output differed from it, if shown */
        if (was == SHOWN_OTHER)
            fp_changed_all(&s->shown_changed);
        else if (was == SHOWN_ENGINE)
            fp_changed_add(&s->shown_changed, ranges, fp_engine_step_touched(&s->engine, &ranges));
        fp_history_end_gesture(&s->history);
        fp_engine_step_end_gesture(&s->engine, &s->log);
        contact_end_gesture(s);
        shown_ref(s);
    }
    s->engaged = cs->active && !(cs->intents & (FP_INTENT_COMMIT | FP_INTENT_CANCEL));
}

static void step_frame(fp_session *s, int64_t now_ns, fp_frame_stats *st);

/* fp_session_step's arguments, for the frame thread */
typedef struct frame_call {
    fp_session *s;
    int64_t now_ns;
    fp_frame_stats *st;
} frame_call;

static void frame_call_run(void *u)
{
    frame_call *f = u;
    step_frame(f->s, f->now_ns, f->st);
}

void fp_session_step(fp_session *s, int64_t now_ns, fp_frame_stats *st)
{
    fp_frame_stats local;
    if (!st) st = &local;
    frame_call f = {s, now_ns, st};
    bool there = fp_frame_thread_run(s->ft, frame_call_run, &f,
                                      s->frame_thread_opt == 2 ? 1000000000
                                                               : FP_FRAME_THREAD_GRACE_NS) == 1;
    st->frame_thread = there;
}

/* One frame (fp_session_step), on the frame thread or the caller's. */
static void step_frame(fp_session *s, int64_t now_ns, fp_frame_stats *st)
{
    memset(st, 0, sizeof *st);
    st->frame = s->frame;
    st->guard_reached = 1.0;
    st->min_det_j = NAN;
    st->collide_t = 1.0;

    int64_t tick = fp_now_ns(), tock;
#define FP_STAGE_END(stage)                                                                   \
    (tock = fp_now_ns(), st->stage_ms[stage] += (double)(tock - tick) / 1e6, tick = tock)
    /* 1: inputs and intents. */
    fp_record_step_begin(&s->record);
    st->events = s->intents.clocked
                     ? fp_intents_drain_until(&s->intents, s->inputs, s->input_count, now_ns,
                                              s->engaged, &s->log, on_event, s)
                     : fp_intents_drain(&s->intents, s->inputs, s->input_count, s->engaged,
                                        &s->log, on_event, s);
    for (size_t i = 0; i < s->input_count; i++) /* (one load each when none logged) */
        fp_input_instance_drain_log(&s->inputs[i]);
    FP_STAGE_END(FP_STAGE_EVENTS);
    /* 2: hand poses in mesh units, at the frame's time. */
    fp_pose_build_at(&s->pose, now_ns);
    FP_STAGE_END(FP_STAGE_HANDS);

    /* 3: the mapping. */
    fp_frame_input in;
    memset(&in, 0, sizeof in);
    in.size = sizeof in;
    in.time_ns = now_ns;
    in.frame = s->frame;
    memcpy(in.hands, s->pose.poses, sizeof in.hands);
    in.events = s->intents.frame_events;
    in.event_count = s->intents.frame_event_count;
    in.mesh = &s->view;
    in.radius = s->radius;
    in.requested = fp_intents_take_requested(&s->intents);
    in.mm_per_unit = s->head.mm_per_unit;
    if (s->rig.rig) {
        fp_rig_axes(s->rig.rig, in.face_up, in.face_forward, in.face_left);
    } else {
        in.face_up[1] = 1.f; /* the project's convention (fp_head.h) */
        in.face_forward[2] = 1.f;
        in.face_left[0] = 1.f;
    }
    in.rig = fp_rig_step_view(&s->rig);
    const float *surface = fp_rig_step_posed(&s->rig, s->base); /* what the fingers touch */
    s->view.base = surface;
    /* on its base (the posed surface), within the fingers' reach only (plugin.h); the index
     * first takes a commit of the last frame */
    fp_engine_step_sync(&s->engine);
    fp_engine_step_tip_distances(&s->engine, s->pose.poses, (float)(FP_TIP_DISTANCE_REACH * s->radius),
                                 in.tip_distance);
    FP_STAGE_END(FP_STAGE_DISTANCES);
    fp_mapping_step_run(&s->mapping_step, s->mapping, s->mapping_name, &in, &s->cs, &s->log);
    fp_mapping_host_drain_log(&s->mapping_host); /* (one load when it logged nothing) */
    st->engaged = s->cs.intents & FP_INTENT_ENGAGE;
    if (s->cs.intents & FP_INTENT_CANCEL) {
        st->cancelled = true;
        s->cs.active = false;
    }

    /* 4: the rig: channels pose the base; the engine works on the posed base. */
    if (fp_rig_step_update(&s->rig, &s->cs, s->base, &s->log)) {
        fp_engine_step_set_base(&s->engine, fp_rig_step_posed(&s->rig, s->base));
        fp_changed_all(&s->shown_changed);
        reference_changed(s, NULL, SIZE_MAX);
    }
    const fp_control_set *cs = fp_rig_step_run(&s->rig, &s->cs);
    FP_STAGE_END(FP_STAGE_MAPPING);

    /* 5: the engine. 6: history. */
    engine_and_history(s, cs, st);

#undef FP_STAGE_END
    /* 7: the recorder. */
    fp_record_step_end(&s->record, s->frame, now_ns, in.requested | s->actions, cs, s->inputs,
                       s->input_count, &s->log);
    s->actions = 0;
    s->frame++;
}

void fp_session_apply_controls(fp_session *s, int64_t now_ns, const fp_control_set *cs,
                               uint32_t requested, fp_frame_stats *st)
{
    fp_frame_stats local;
    if (!st) st = &local;
    memset(st, 0, sizeof *st);
    st->frame = s->frame;
    st->collide_t = 1.0;
    fp_record_step_begin(&s->record);
    st->engaged = cs->intents & FP_INTENT_ENGAGE;
    st->cancelled = cs->intents & FP_INTENT_CANCEL;
    /* 4: the rig poses the base from the stored channels; the stored set is already the
     * one the rig's clamp returned, so it goes to the engine as it is. */
    if (fp_rig_step_update(&s->rig, cs, s->base, &s->log)) {
        fp_engine_step_set_base(&s->engine, fp_rig_step_posed(&s->rig, s->base));
        fp_changed_all(&s->shown_changed);
        reference_changed(s, NULL, SIZE_MAX);
    }
    engine_and_history(s, cs, st);
    fp_record_step_end(&s->record, s->frame, now_ns, requested | s->actions, cs, s->inputs,
                       s->input_count, &s->log);
    s->actions = 0;
    s->frame++;
}

/* ---- queries and edits ------------------------------------------------------------------ */

int fp_session_input_start(fp_session *s, int64_t *t0)
{
    return fp_intents_first_time(&s->intents, s->inputs, s->input_count, t0);
}

bool fp_session_inputs_ready(fp_session *s, int64_t t)
{
    return !s->intents.clocked || fp_intents_ready(&s->intents, s->inputs, s->input_count, t);
}

bool fp_session_finished(const fp_session *s) { return fp_intents_all_ended(&s->intents, s->input_count); }

void fp_session_request(fp_session *s, uint32_t intents) { fp_intents_request(&s->intents, intents); }

unsigned fp_session_record_toggles(fp_session *s)
{
    unsigned n = s->intents.record_toggles;
    s->intents.record_toggles = 0;
    return n;
}
const float *fp_session_positions(const fp_session *s) { return s->shown; }
const float *fp_session_base(const fp_session *s) { return s->base; }

size_t fp_session_touched(fp_session *s, const uint32_t **ranges)
{
    return fp_changed_take(&s->shown_changed, ranges);
}

size_t fp_session_base_touched(fp_session *s, const uint32_t **ranges)
{
    return fp_changed_take(&s->base_changed, ranges);
}
const float *fp_session_loaded(const fp_session *s) { return s->loaded; }
size_t fp_session_vertex_count(const fp_session *s) { return s->n; }
const struct fp_mesh *fp_session_mesh(const fp_session *s) { return s->mesh; }
double fp_session_radius(const fp_session *s) { return s->radius; }
const fp_calibration *fp_session_calibration(const fp_session *s) { return &s->pose.calib; }
const fp_head *fp_session_head(const fp_session *s) { return &s->head; }
const fp_control_set *fp_session_control_set(const fp_session *s) { return &s->cs; }

const struct csrbf_solver *fp_session_solver(const fp_session *s)
{
    /* not when the contact guard scaled the shape back: the solver's map is not what is shown */
    return s->shown != s->base && (!s->contact || s->shown != fp_contact_shape(s->contact)) && !s->rig.rig
               ? fp_engine_step_solver(&s->engine) : NULL;
}

const struct fp_rig *fp_session_rig(const fp_session *s) { return s->rig.rig; }
const char *fp_session_rig_how(const fp_session *s) { return s->rig_how; }

int fp_session_set_channel(fp_session *s, const char *name, double value)
{
    return fp_rig_step_set_channel(&s->rig, name, (float)value);
}

double fp_session_channel(const fp_session *s, const char *name)
{
    return fp_rig_step_channel(&s->rig, name);
}

void fp_session_set_radius(fp_session *s, double radius)
{
    if (radius > 0 && isfinite(radius)) s->radius = radius;
}

const fp_hand_pose *fp_session_hand(const fp_session *s, int hand)
{
    return hand >= 0 && hand < FP_HANDS && s->pose.poses[hand].present ? &s->pose.poses[hand] : NULL;
}

static void reset_mapping(fp_session *s)
{
    if (!s->mapping->reset || s->mapping_step.stopped) return;
    fp_plugin_call_enter(s->mapping_name, "reset", s->frame);
    s->mapping->reset(s->mapping);
    fp_plugin_call_leave();
}

static void destroy_mapping(fp_session *s, fp_mapping *m, const char *name)
{
    if (!m || !m->destroy) return;
    fp_plugin_call_enter(name, "destroy", s->frame);
    m->destroy(m);
    fp_plugin_call_leave();
}

/* After undo or reset: the mapping forgets its gesture, and so does the control set that
 * fp_session_control_set shows (no deformation until the next frame makes one). */
static void after_set_base(fp_session *s)
{
    base_changed(s);
    reset_mapping(s);
    s->cs.active = false;
    s->cs.count = 0;
    s->cs.intents = 0;
    s->engaged = false;
}

unsigned long fp_session_commits(const fp_session *s) { return s->history.gestures; }

bool fp_session_undo(fp_session *s)
{
    if (!fp_history_undo(&s->history)) return false;
    after_set_base(s);
    s->actions |= FP_SESSION_ACTION_UNDO;
    return true;
}

void fp_session_reset(fp_session *s)
{
    fp_history_reset(&s->history, s->loaded);
    fp_rig_step_neutral(&s->rig);
    after_set_base(s);
    s->actions |= FP_SESSION_ACTION_RESET;
}

/* Replace the mapping by one made from spec (from file where not NULL); the old one stays on
 * error. */
static int swap_mapping(fp_session *s, const fp_plugin_path *path, const char *spec, const char *file,
                        char *err, size_t errlen)
{
    fp_plugin old_plugin = s->mapping_plugin;
    fp_mapping *old = s->mapping;
    fp_mapping_host old_host = s->mapping_host;
    char old_name[sizeof s->mapping_name], old_spec[sizeof s->mapping_spec];
    memcpy(old_name, s->mapping_name, sizeof old_name);
    memcpy(old_spec, s->mapping_spec, sizeof old_spec);
    memset(&s->mapping_plugin, 0, sizeof s->mapping_plugin);
    s->mapping = NULL;
    char spec_copy[sizeof s->mapping_spec];
    snprintf(spec_copy, sizeof spec_copy, "%s", spec); /* spec may be s->mapping_spec */
    int rc = load_mapping(s, spec_copy, path, file, err, errlen);
    if (rc) {
        fp_plugin_unload(&s->mapping_plugin);
        s->mapping_plugin = old_plugin;
        s->mapping = old;
        s->mapping_host = old_host;
        memcpy(s->mapping_name, old_name, sizeof old_name);
        memcpy(s->mapping_spec, old_spec, sizeof old_spec);
        return rc;
    }
    /* The old instance's host must stay valid until it is destroyed. */
    fp_mapping_host new_host = s->mapping_host;
    s->mapping_host = old_host;
    destroy_mapping(s, old, old_name);
    fp_mapping_host_drain_log(&s->mapping_host); /* the old one's last lines, under its name */
    s->mapping_host = new_host;
    fp_mapping_step_flush(&s->mapping_step, &s->log);
    fp_plugin_unload(&old_plugin);
    s->shown = fp_rig_step_posed(&s->rig, s->base);
    s->shown_kind = SHOWN_POSED;
    fp_changed_all(&s->shown_changed);
    shown_ref(s);
    s->engaged = false;
    fp_history_end_gesture(&s->history);
    fp_engine_step_end_gesture(&s->engine, &s->log);
    contact_end_gesture(s);
    fp_engine_step_invalidate(&s->engine);
    fp_mapping_step_init(&s->mapping_step, &s->cs, s->mapping_budget_ms);
    reset_mapping(s);
    return 0;
}

int fp_session_set_mapping(fp_session *s, const fp_plugin_path *path, const char *spec,
                           char *err, size_t errlen)
{
    if (!s || !path || !spec) {
        snprintf(err, errlen, "session: a mapping spec and a plugin path are required");
        return -EINVAL;
    }
    return swap_mapping(s, path, spec, NULL, err, errlen);
}

int fp_session_reload_mapping(fp_session *s, const char *file, char *err, size_t errlen)
{
    if (!s || !file) {
        snprintf(err, errlen, "session: a plugin file is required");
        return -EINVAL;
    }
    fp_plugin_path none;
    memset(&none, 0, sizeof none);
    none.builtin = SIZE_MAX;
    return swap_mapping(s, &none, s->mapping_spec, file, err, errlen);
}

const char *fp_session_mapping_file(const fp_session *s) { return s->mapping_file; }
const fp_plugin *fp_session_mapping_plugin(const fp_session *s) { return &s->mapping_plugin; }
const char *fp_session_mapping_name(const fp_session *s) { return s->mapping_name; }

int fp_session_mapping_fault(const fp_session *s, char *err, size_t errlen)
{
    if (!s->mapping_step.fault) return 0;
    snprintf(err, errlen, "mapping '%s': %s", s->mapping_name, s->mapping_step.fault_message);
    return s->mapping_step.fault;
}

unsigned fp_session_input_errors(const fp_session *s, const char **last)
{
    if (last) *last = s->intents.last_error;
    return s->intents.input_errors;
}

unsigned long fp_session_dropped(const fp_session *s)
{
    unsigned long n = 0;
    for (size_t i = 0; i < s->input_count; i++)
        n += atomic_load(&((fp_session *)s)->inputs[i].queue.dropped);
    return n;
}

int fp_session_save(const fp_session *s, const char *path, char *err, size_t errlen)
{
    return fp_session_save_ex(s, path, NULL, err, errlen);
}

int fp_session_save_ex(const fp_session *s, const char *path, unsigned *dropped, char *err,
                       size_t errlen)
{
    fp_mesh out = *s->mesh;
    size_t bytes = s->n * 3 * sizeof(float);
    out.positions = (float *)s->shown;
    out.normals = malloc(bytes);
    if (!out.normals) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -ENOMEM;
    }
    fp_mesh_compute_normals(&out);
    int rc = fp_mesh_save_ex(&out, path, dropped, err, errlen);  /* its code, unchanged */
    free(out.normals);
    return rc;
}

int fp_session_stop(fp_session *s, char *err, size_t errlen)
{
    int first = 0;
    if (s->stopped) return 0;
    s->stopped = true;
    for (size_t i = 0; i < s->input_count; i++) {
        char msg[512] = "";
        int rc = fp_input_instance_close_record(&s->inputs[i], msg, sizeof msg);
        fp_input_instance_drain_log(&s->inputs[i]);
        if (rc) {
            fp_slog_printf(&s->log, FP_LOG_ERROR, s->inputs[i].name, "record: %s", msg);
            if (!first) {
                first = rc;
                snprintf(err, errlen, "input '%s': record: %s", s->inputs[i].name, msg);
            }
        }
    }
    return first;
}

void fp_session_destroy(fp_session **sp)
{
    fp_session *s = *sp;
    if (!s) return;
    fp_frame_thread_destroy(&s->ft); /* (between frames: no call in progress) */
    char msg[8];
    fp_session_stop(s, msg, sizeof msg);
    fp_mapping_step_flush(&s->mapping_step, &s->log);
    fp_engine_step_flush(&s->engine, &s->log);
    contact_end_gesture(s);
    for (size_t i = 0; i < s->input_count; i++) fp_input_instance_close(&s->inputs[i]);
    destroy_mapping(s, s->mapping, s->mapping_name);
    fp_mapping_host_drain_log(&s->mapping_host);
    fp_log_relay_destroy(&s->mapping_relay);
    fp_plugin_unload(&s->mapping_plugin);
    fp_engine_step_free(&s->engine);
    fp_contact_destroy(&s->contact);
    fp_changed_free(&s->shown_changed);
    fp_changed_free(&s->cg_ref);
    fp_changed_free(&s->base_changed);
    free(s->gc_mark);
    free(s->gc_blk);
    free(s->gc_ranges);
    fp_rig_step_free(&s->rig);
    fp_history_free(&s->history);
    fp_intents_free(&s->intents);
    fp_record_step_free(&s->record);
    free(s->loaded);
    free(s->base);
    free(s->deformed);
    fp_mesh_free(&s->mesh);
    free(s);
    *sp = NULL;
}
