/* The session: the frame loop of shared/docs/design.md ("One frame", steps 1-5). */
#define _GNU_SOURCE
#include "fp_session.h"

#include "csrbf.h"
#include "fp_hand.h"
#include "fp_mesh.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FP_MAX_CONTROL 64
#define FP_MAX_FRAME_EVENTS 64
#define FP_UNDO_LEVELS 32

typedef struct hand_state {
    bool have_positions;          /* a tracker gave joint positions */
    bool have_angles;
    bool have_wrist;
    fp_event_joint_angles angles;
    float wrist_pos[3], wrist_rot[4];
    float joints_mm[FP_HAND_JOINTS][3];
    int64_t time_ns;
    bool present;
} hand_state;

struct fp_session {
    fp_mesh *mesh;
    size_t n;
    float *loaded, *base, *deformed;
    const float *shown;
    float *undo[FP_UNDO_LEVELS];
    size_t undo_count, undo_next;
    bool gesture_open;

    fp_input_instance inputs[FP_SESSION_MAX_INPUTS];
    size_t input_count;
    bool ended[FP_SESSION_MAX_INPUTS];

    fp_plugin mapping_plugin;
    fp_mapping *mapping;
    fp_host mapping_host;
    fp_mesh_view view;

    hand_state hands[FP_HANDS];
    fp_hand_model hand_model;
    fp_calibration calib;
    double radius;
    int engine_threads;           /* csrbf_options.threads */
    uint32_t requested;
    bool engaged;                 /* the mapping's deformation is active */
    unsigned input_errors;        /* FP_STATUS_ERROR events seen */
    char last_error[128];
    uint64_t frame;

    csrbf_solver *solver;
    double solver_radius;
    csrbf_points *points;
    size_t factored_count;
    float factored_start[FP_MAX_CONTROL][3];
    bool factored;

    fp_control_set cs;
    float cs_start[FP_MAX_CONTROL][3], cs_end[FP_MAX_CONTROL][3];
    fp_channel channels[16];
    fp_event frame_events[FP_MAX_FRAME_EVENTS];
    size_t frame_event_count;
    fp_hand_pose poses[FP_HANDS];
};

/* ---- calibration ----------------------------------------------------------------------- */

/* Default workspace: where a desktop tracker sees hands (Leap Motion interaction box,
 * mm): used when no input tells its workspace. */
static const float default_ws_min[3] = {-150.f, 80.f, -120.f};
static const float default_ws_max[3] = {150.f, 330.f, 120.f};

/* Fit the hands' workspace to the face: the workspace's width spans the face's width, its
 * centre in x and y lands on the face's centre, and its deepest point (farthest from the
 * performer, -z) reaches 15% of the face's depth behind the face's front, so that the
 * performer's forward reach touches the face. */
static void fit_workspace(fp_calibration *c, const float ws_min[3], const float ws_max[3],
                          const float face_min[3], const float face_max[3])
{
    double ws_w = fmax(ws_max[0] - ws_min[0], 1.0);
    double ws_h = fmax(ws_max[1] - ws_min[1], 1.0);
    double sx = (face_max[0] - face_min[0]) / ws_w, sy = (face_max[1] - face_min[1]) / ws_h;
    c->scale = fmin(sx, sy);
    for (int i = 0; i < 2; i++)
        c->offset[i] = 0.5 * (face_min[i] + face_max[i]) - c->scale * 0.5 * (ws_min[i] + ws_max[i]);
    double depth = face_max[2] - face_min[2];
    c->offset[2] = (face_max[2] - 0.15 * depth) - c->scale * ws_min[2];
}

static void to_mesh(const fp_calibration *c, const float mm[3], float out[3])
{
    for (int i = 0; i < 3; i++) out[i] = (float)(c->scale * mm[i] + c->offset[i]);
}

/* ---- creation -------------------------------------------------------------------------- */

static int load_mapping(fp_session *s, const fp_session_options *opt, char *err, size_t errlen)
{
    fp_spec spec;
    int rc = fp_spec_parse(opt->mapping ? opt->mapping : "anchored", &spec, err, errlen);
    if (rc) return rc;
    if (spec.arg) {
        snprintf(err, errlen, "mapping '%s': a mapping takes no ':ARG', only keys", opt->mapping);
        fp_spec_clear(&spec);
        return -EINVAL;
    }
    rc = fp_plugin_load(opt->plugin_path, FP_PLUGIN_MAPPING, spec.name, &s->mapping_plugin, err,
                        errlen);
    if (!rc) {
        fp_host_init_for_mapping(&s->mapping_host, spec.name);
        const fp_mapping_factory *f = s->mapping_plugin.factory;
        char perr[512] = "";
        rc = f->create(&s->mapping_host, spec.params, spec.nparams, &s->mapping, perr, sizeof perr);
        if (rc || !s->mapping) {
            snprintf(err, errlen, "mapping '%s': %s", opt->mapping, perr[0] ? perr : "create failed");
            s->mapping = NULL;
            rc = rc ? rc : -EINVAL;
        }
    }
    fp_spec_clear(&spec);
    return rc;
}

int fp_session_create(const fp_session_options *opt, fp_session **out, char *err, size_t errlen)
{
    *out = NULL;
    if (!opt || !opt->mesh_path || !opt->plugin_path) {
        snprintf(err, errlen, "session: a mesh and a plugin path are required");
        return -EINVAL;
    }
    if (opt->input_count > FP_SESSION_MAX_INPUTS) {
        snprintf(err, errlen, "session: at most %d inputs", FP_SESSION_MAX_INPUTS);
        return -EINVAL;
    }
    if (opt->radius < 0 || isnan(opt->radius)) {
        snprintf(err, errlen, "--radius must be > 0 (mesh units), got %g", opt->radius);
        return -EINVAL;
    }
    fp_session *s = calloc(1, sizeof *s);
    if (!s) return -ENOMEM;
    int rc = 0;
    char merr[512];
    if (fp_mesh_load(opt->mesh_path, &s->mesh, merr, sizeof merr) != FP_MESH_OK) {
        snprintf(err, errlen, "%s", merr);
        rc = -EBADMSG;
        goto fail;
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
    s->radius = opt->radius > 0 ? opt->radius : 0.06 * sqrt(diag);
    /* One engine thread for face-sized meshes: the ICT face (27k vertices) takes about
     * 0.1 ms on one core, and a second OpenMP thread that the input and display threads
     * keep off its core can cost a whole scheduler time slice (measured: 13.7 ms median
     * update with the other core busy, against 0.11 ms on one thread). */
    s->engine_threads = opt->engine_threads ? opt->engine_threads : (s->n < 200000 ? 1 : 0);
    fp_hand_model_init(&s->hand_model);
    if (opt->hand_size > 0) s->hand_model.size = (float)opt->hand_size;

    if (csrbf_points_create(s->n, s->base, &s->points) != CSRBF_OK) {
        rc = -ENOMEM;
        snprintf(err, errlen, "session: cannot index %zu vertices", s->n);
        goto fail;
    }
    if ((rc = load_mapping(s, opt, err, errlen))) goto fail;
    for (size_t i = 0; i < opt->input_count; i++) {
        rc = fp_input_instance_open(&s->inputs[i], opt->plugin_path, opt->inputs[i], (uint32_t)i,
                                    err, errlen);
        if (rc) goto fail;
        s->input_count = i + 1;
    }
    /* Workspace calibration: given, or the inputs' workspaces fitted to the face. */
    if (opt->calibration) {
        s->calib = *opt->calibration;
    } else {
        float wmin[3] = {INFINITY, INFINITY, INFINITY}, wmax[3] = {-INFINITY, -INFINITY, -INFINITY};
        bool known = false;
        for (size_t i = 0; i < s->input_count; i++) {
            fp_input *in = s->inputs[i].input;
            const fp_input_workspace *ws =
                in->get_extension ? in->get_extension(in, FP_EXT_WORKSPACE) : NULL;
            float a[3], b[3];
            if (ws && ws->get && ws->get(in, a, b)) {
                known = true;
                for (int k = 0; k < 3; k++) {
                    wmin[k] = fminf(wmin[k], a[k]);
                    wmax[k] = fmaxf(wmax[k], b[k]);
                }
            }
        }
        fit_workspace(&s->calib, known ? wmin : default_ws_min, known ? wmax : default_ws_max,
                      s->view.bounds_min, s->view.bounds_max);
    }
    s->cs.size = sizeof s->cs;
    s->cs.capacity = FP_MAX_CONTROL;
    s->cs.start = s->cs_start;
    s->cs.end = s->cs_end;
    s->cs.channels = s->channels;
    s->cs.channel_capacity = sizeof s->channels / sizeof s->channels[0];
    *out = s;
    return 0;
fail:
    fp_session_destroy(&s);
    return rc ? rc : -EINVAL;
}

int fp_session_start(fp_session *s, char *err, size_t errlen)
{
    for (size_t i = 0; i < s->input_count; i++) {
        int rc = fp_input_instance_start(&s->inputs[i], err, errlen);
        if (rc) return rc;
    }
    return 0;
}

/* ---- one frame ------------------------------------------------------------------------- */

static void keep_frame_event(fp_session *s, const fp_event *ev)
{
    if (s->frame_event_count < FP_MAX_FRAME_EVENTS) s->frame_events[s->frame_event_count++] = *ev;
}

/* Pedal binding (defaults of the pedal issue): left engages, or commits an engaged
 * deformation; right cancels; middle is for takes (not yet). */
static void bind_button(fp_session *s, const fp_event_button *b)
{
    if (!b->down) return;
    if (b->button == FP_BUTTON_LEFT) s->requested |= s->engaged ? FP_INTENT_COMMIT : FP_INTENT_ENGAGE;
    else if (b->button == FP_BUTTON_RIGHT) s->requested |= FP_INTENT_CANCEL;
}

static void take_event(fp_session *s, size_t src, const fp_event *ev)
{
    int h = ev->header.hand;
    bool has_hand = h == FP_HAND_LEFT || h == FP_HAND_RIGHT;
    switch (ev->header.type) {
    case FP_EVENT_JOINT_POSITIONS:
        if (!has_hand) break;
        memcpy(s->hands[h].joints_mm, ev->positions.mm, sizeof ev->positions.mm);
        s->hands[h].have_positions = s->hands[h].present = true;
        s->hands[h].time_ns = ev->header.time_ns;
        break;
    case FP_EVENT_JOINT_ANGLES:
        if (!has_hand) break;
        s->hands[h].angles = ev->angles;
        s->hands[h].have_angles = s->hands[h].present = true;
        s->hands[h].have_positions = false;
        s->hands[h].time_ns = ev->header.time_ns;
        break;
    case FP_EVENT_WRIST_POSE:
        if (!has_hand) break;
        memcpy(s->hands[h].wrist_pos, ev->wrist.position_mm, sizeof s->hands[h].wrist_pos);
        memcpy(s->hands[h].wrist_rot, ev->wrist.rotation, sizeof s->hands[h].wrist_rot);
        s->hands[h].have_wrist = true;
        break;
    case FP_EVENT_BUTTON:
        bind_button(s, &ev->button);
        keep_frame_event(s, ev);
        break;
    case FP_EVENT_STATUS:
        if (ev->status.code == FP_STATUS_END_OF_STREAM) s->ended[src] = true;
        if (ev->status.code == FP_STATUS_ERROR) {
            s->input_errors++;
            snprintf(s->last_error, sizeof s->last_error, "%.*s", 100, ev->status.text);
        }
        if (ev->status.code == FP_STATUS_ERROR || ev->status.code == FP_STATUS_WARNING ||
            ev->status.code == FP_STATUS_DISCONNECTED)
            fprintf(stderr, "facepuppet: input %s: %s\n", s->inputs[src].name, ev->status.text);
        if (ev->status.code == FP_STATUS_DISCONNECTED && has_hand) s->hands[h].present = false;
        keep_frame_event(s, ev);
        break;
    default:
        break;
    }
}

/* Default wrist placement for a glove that reports no wrist pose: the two hands side by
 * side 80 mm from the middle, 200 mm above the device, fingers pointing away (-z). */
static void default_wrist(int h, float pos[3], float rot[4])
{
    pos[0] = h == FP_HAND_LEFT ? -80.f : 80.f;
    pos[1] = 200.f;
    pos[2] = 60.f;
    rot[0] = 1.f;
    rot[1] = rot[2] = rot[3] = 0.f;
}

static void build_poses(fp_session *s)
{
    for (int h = 0; h < FP_HANDS; h++) {
        hand_state *hs = &s->hands[h];
        fp_hand_pose *p = &s->poses[h];
        p->present = hs->present;
        if (!hs->present) continue;
        p->time_ns = hs->time_ns;
        if (!hs->have_positions && hs->have_angles) {
            float pos[3], rot[4];
            if (hs->have_wrist) {
                memcpy(pos, hs->wrist_pos, sizeof pos);
                memcpy(rot, hs->wrist_rot, sizeof rot);
            } else {
                default_wrist(h, pos, rot);
            }
            fp_hand_fk(&s->hand_model, (fp_hand_side)h, hs->angles.radians, hs->angles.valid, pos,
                       rot, hs->joints_mm);
        }
        for (int j = 0; j < FP_HAND_JOINTS; j++) to_mesh(&s->calib, hs->joints_mm[j], p->joints[j]);
    }
}

/* Distance from each fingertip to the nearest base vertex (brute force over the base,
 * vectorised: 10 tips x 27k vertices is about 0.1 ms). */
static void tip_distances(const fp_session *s, float d[FP_HANDS][FP_FINGERS])
{
    float tips[FP_HANDS * FP_FINGERS][3];
    float best[FP_HANDS * FP_FINGERS];
    int nt = 0;
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++) {
            d[h][f] = INFINITY;
            if (!s->poses[h].present) continue;
            memcpy(tips[nt], s->poses[h].joints[FP_JOINT_TIP(f)], sizeof tips[nt]);
            best[nt++] = INFINITY;
        }
    if (!nt) return;
    const float *b = s->base;
    for (int t = 0; t < nt; t++) {
        float m = INFINITY, tx = tips[t][0], ty = tips[t][1], tz = tips[t][2];
        for (size_t v = 0; v < s->n; v++) {
            float dx = b[3 * v] - tx, dy = b[3 * v + 1] - ty, dz = b[3 * v + 2] - tz;
            float q = dx * dx + dy * dy + dz * dz;
            m = q < m ? q : m;
        }
        best[t] = sqrtf(m);
    }
    nt = 0;
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++)
            if (s->poses[h].present) d[h][f] = best[nt++];
}

static void push_undo(fp_session *s)
{
    size_t bytes = s->n * 3 * sizeof(float);
    float **slot = &s->undo[s->undo_next];
    if (!*slot) *slot = malloc(bytes);
    if (!*slot) return;
    memcpy(*slot, s->base, bytes);
    s->undo_next = (s->undo_next + 1) % FP_UNDO_LEVELS;
    if (s->undo_count < FP_UNDO_LEVELS) s->undo_count++;
}

static int engine_update(fp_session *s, fp_frame_stats *st)
{
    const fp_control_set *cs = &s->cs;
    int rc;
    if (!s->solver || s->solver_radius != cs->radius) {
        csrbf_solver_destroy(&s->solver);
        csrbf_options o = {0};
        o.radius = cs->radius;
        o.threads = s->engine_threads;
        if ((rc = csrbf_solver_create(&o, &s->solver)) < 0) return rc;
        s->solver_radius = cs->radius;
        s->factored = false;
    }
    if (!s->factored || s->factored_count != cs->count ||
        memcmp(s->factored_start, cs->start, cs->count * sizeof cs->start[0])) {
        if ((rc = csrbf_solver_set_start_points(s->solver, cs->count, &cs->start[0][0])) < 0) {
            s->factored = false;
            return rc;
        }
        memcpy(s->factored_start, cs->start, cs->count * sizeof cs->start[0]);
        s->factored_count = cs->count;
        s->factored = true;
        st->refactored = true;
    }
    if ((rc = csrbf_solver_set_end_points(s->solver, &cs->end[0][0])) < 0) return rc;
    csrbf_eval_stats es = {0};
    if ((rc = csrbf_evaluate(s->solver, s->points, s->deformed, 0, &es)) < 0) return rc;
    st->pairs = es.pairs;
    return 0;
}

void fp_session_step(fp_session *s, int64_t now_ns, fp_frame_stats *st)
{
    fp_frame_stats local;
    if (!st) st = &local;
    memset(st, 0, sizeof *st);
    st->frame = s->frame;
    s->frame_event_count = 0;
    /* 1-2: drain the inputs' queues; keep the latest pose of each hand. */
    for (size_t i = 0; i < s->input_count; i++) {
        fp_event ev;
        while (fp_input_instance_poll(&s->inputs[i], &ev)) {
            take_event(s, i, &ev);
            st->events++;
        }
    }
    build_poses(s);
    /* 3: the mapping. */
    fp_frame_input in;
    memset(&in, 0, sizeof in);
    in.size = sizeof in;
    in.time_ns = now_ns;
    in.frame = s->frame;
    memcpy(in.hands, s->poses, sizeof in.hands);
    in.events = s->frame_events;
    in.event_count = s->frame_event_count;
    in.mesh = &s->view;
    in.radius = s->radius;
    in.requested = s->requested;
    s->requested = 0;
    tip_distances(s, in.tip_distance);
    int rc = s->mapping->process(s->mapping, &in, &s->cs);
    if (rc < 0 || s->cs.count > s->cs.capacity || !(s->cs.radius > 0)) {
        fprintf(stderr, "facepuppet: mapping error %d on frame %llu; keeping the last shape\n", rc,
                (unsigned long long)s->frame);
        s->cs.active = false;
        s->cs.intents = 0;
    }
    st->engaged = s->cs.intents & FP_INTENT_ENGAGE;
    /* 5: the engine. */
    s->shown = s->base;
    if (s->cs.intents & FP_INTENT_CANCEL) {
        st->cancelled = true;
        s->cs.active = false;
    }
    if (s->cs.active && s->cs.count > 0) {
        int64_t t0 = fp_now_ns();
        rc = engine_update(s, st);
        st->update_ms = (double)(fp_now_ns() - t0) / 1e6;
        st->control_vectors = s->cs.count;
        if (rc < 0) {
            fprintf(stderr, "facepuppet: engine: %s%s%s; keeping the last shape\n", csrbf_strerror(rc),
                    s->solver ? ": " : "", s->solver ? csrbf_solver_message(s->solver) : "");
        } else {
            st->active = true;
            s->shown = s->deformed;
            if (s->cs.intents & FP_INTENT_COMMIT) {
                if (!s->gesture_open) push_undo(s);
                s->gesture_open = true;
                memcpy(s->base, s->deformed, s->n * 3 * sizeof(float));
                csrbf_points_update(s->points, s->base);
                s->factored = false; /* the anchored gesture ended; unanchored restarts anyway */
                s->shown = s->base;
                st->committed = true;
            }
        }
    } else {
        s->gesture_open = false;
    }
    s->engaged = s->cs.active && !(s->cs.intents & (FP_INTENT_COMMIT | FP_INTENT_CANCEL));
    s->frame++;
}

/* ---- queries and edits ------------------------------------------------------------------ */

bool fp_session_finished(const fp_session *s)
{
    if (!s->input_count) return false;
    for (size_t i = 0; i < s->input_count; i++)
        if (!s->ended[i]) return false;
    return true;
}

void fp_session_request(fp_session *s, uint32_t intents) { s->requested |= intents; }
const float *fp_session_positions(const fp_session *s) { return s->shown; }
const float *fp_session_base(const fp_session *s) { return s->base; }
const float *fp_session_loaded(const fp_session *s) { return s->loaded; }
size_t fp_session_vertex_count(const fp_session *s) { return s->n; }
const struct fp_mesh *fp_session_mesh(const fp_session *s) { return s->mesh; }
double fp_session_radius(const fp_session *s) { return s->radius; }
const fp_calibration *fp_session_calibration(const fp_session *s) { return &s->calib; }
const fp_control_set *fp_session_control_set(const fp_session *s) { return &s->cs; }

void fp_session_set_radius(fp_session *s, double radius)
{
    if (radius > 0 && isfinite(radius)) s->radius = radius;
}

const fp_hand_pose *fp_session_hand(const fp_session *s, int hand)
{
    return hand >= 0 && hand < FP_HANDS && s->poses[hand].present ? &s->poses[hand] : NULL;
}

static void set_base(fp_session *s, const float *src)
{
    memcpy(s->base, src, s->n * 3 * sizeof(float));
    csrbf_points_update(s->points, s->base);
    s->shown = s->base;
    s->factored = false;
    s->gesture_open = false;
    if (s->mapping->reset) s->mapping->reset(s->mapping);
}

bool fp_session_undo(fp_session *s)
{
    if (!s->undo_count) return false;
    s->undo_next = (s->undo_next + FP_UNDO_LEVELS - 1) % FP_UNDO_LEVELS;
    s->undo_count--;
    set_base(s, s->undo[s->undo_next]);
    return true;
}

void fp_session_reset(fp_session *s)
{
    if (memcmp(s->base, s->loaded, s->n * 3 * sizeof(float))) push_undo(s);
    set_base(s, s->loaded);
}

int fp_session_set_mapping(fp_session *s, const fp_plugin_path *path, const char *spec,
                           char *err, size_t errlen)
{
    if (!s || !path || !spec) {
        snprintf(err, errlen, "session: a mapping spec and a plugin path are required");
        return -EINVAL;
    }
    fp_plugin old_plugin = s->mapping_plugin;
    fp_mapping *old = s->mapping;
    fp_session_options o = {0};
    o.mapping = spec;
    o.plugin_path = path;
    memset(&s->mapping_plugin, 0, sizeof s->mapping_plugin);
    s->mapping = NULL;
    int rc = load_mapping(s, &o, err, errlen);
    if (rc) {
        fp_plugin_unload(&s->mapping_plugin);
        s->mapping_plugin = old_plugin;
        s->mapping = old;
        return rc;
    }
    if (old && old->destroy) old->destroy(old);
    fp_plugin_unload(&old_plugin);
    s->shown = s->base;
    s->engaged = false;
    s->gesture_open = false;
    s->factored = false;
    s->cs.active = false;
    s->cs.intents = 0;
    s->cs.count = 0;
    return 0;
}

unsigned fp_session_input_errors(const fp_session *s, const char **last)
{
    if (last) *last = s->last_error;
    return s->input_errors;
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
    fp_mesh out = *s->mesh;
    size_t bytes = s->n * 3 * sizeof(float);
    out.positions = (float *)s->shown;
    out.normals = malloc(bytes);
    if (!out.normals) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -ENOMEM;
    }
    fp_mesh_compute_normals(&out);
    int rc = fp_mesh_save(&out, path, err, errlen);
    free(out.normals);
    return rc == FP_MESH_OK ? 0 : -EIO;
}

void fp_session_destroy(fp_session **sp)
{
    fp_session *s = *sp;
    if (!s) return;
    for (size_t i = 0; i < s->input_count; i++) fp_input_instance_close(&s->inputs[i]);
    if (s->mapping && s->mapping->destroy) s->mapping->destroy(s->mapping);
    fp_plugin_unload(&s->mapping_plugin);
    csrbf_solver_destroy(&s->solver);
    csrbf_points_destroy(&s->points);
    for (size_t i = 0; i < FP_UNDO_LEVELS; i++) free(s->undo[i]);
    free(s->loaded);
    free(s->base);
    free(s->deformed);
    fp_mesh_free(&s->mesh);
    free(s);
    *sp = NULL;
}
