/* The live viewer: window, frame loop, camera, keys, HUD (see fp_viewer.h; its measurements: measure.h). */
#define _GNU_SOURCE
#include "fp_viewer.h"

#include "fp_gpuwarp.h"
#include "fp_mesh.h"
#include "fp_rig.h"
#include "fp_error.h"
#include "hud.h"
#include "hud_hands.h"
#include "measure.h"
#include "overlay.h"
#include "png_file.h"
#include "render.h"
#include "script.h"
#include "takes.h"
#include "overdub.h"
#include "wave.h"
#include "vmath.h"
#include "vnormals.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <epoxy/gl.h>

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- state ------------------------------------------------------------------------------ */

typedef struct camera {
    float target[3];
    float yaw, pitch, dist;
    float fovy;
    float scene_size;   /* bounding-box diagonal of the mesh */
    float front[2], depth, aspect; /* framed box (mesh units), window w / h it was fitted to */
    face_axes axes;     /* yaw and pitch turn about the face's up and left (fp_session_face_axes) */
} camera;

typedef struct viewer {
    const fp_viewer_options *opt;
    fp_session_options so;
    bool r_ready;             /* the renderer is up (opening_progress may draw) */
    char *mesh_path;          /* owned copy of the current mesh path */
    char mapping[64];         /* the current mapping spec's name, for the HUD */
    fp_session *s;
    GLFWwindow *win;
    fp_render r;
    fp_gpuwarp *gw;
    fp_script script;
    camera cam;

    /* the face's geometry, CPU side */
    size_t n, t;
    float *pos, *nrm;         /* last uploaded shown shape and its normals */
    float *base, *base_nrm;   /* last uploaded base and its normals */
    bool have_pos, have_base;
    float *check;             /* GPU warp read-back */
    /* partial uploads (upload()): normals and buffers only where the session says the shape
     * changed; FACEPUPPET_VIEWER_UPLOAD=full: the whole mesh on any change (compared whole),
     * =check: partial, then compared with the whole every frame */
    fp_vnormals vn;
    enum { UPLOAD_PARTIAL, UPLOAD_FULL, UPLOAD_CHECK } upload_mode;
    enum { SRC_SESSION, SRC_REVIEW, SRC_SURFACE } shown_src; /* what the shown buffers hold:
                                 the session's shape, a take's frame, the GPU warp's surface */
    /* --gpu-warp: this frame's plan (gpu_plan): drawn by the shader from the surface? */
    bool gpu_now;
    fp_warp_coeffs warp;      /* the engine's coefficients this frame (identity: none) */
    const float *warp_surface;/* the surface they apply to (fp_session_warp_parts) */
    bool warp_solved;         /* a deformation is drawn (not the identity) */
    uint64_t warp_frames;     /* frames the shader drew a deformation (checked: 1 in 30) */
    unsigned gpu_said;        /* fallback reasons already said (one line each, bits) */
    unsigned long upload_checked, upload_mismatches;

    /* interaction */
    bool paused, wireframe, hands_on, hud_on, help_on;
    bool rig_on;              /* G: the rig's regions, landmarks and hinge axis */
    bool quit;
    int shot_counter;
    char *shot_path;          /* screenshot wanted for this frame */
    char *drop_path;          /* mesh dropped, loaded at the next frame */
    double mx, my;
    int drag;                 /* 0 none, 1 orbit, 2 pan */
    fp_hud_msgs msgs;         /* the HUD's message stack (hud.h) */
    fp_hud_hands hands;       /* the HUD's hands line: who is there, who is gone (hud_hands.h) */
    fp_tip_cues cues;         /* the fingertips' nearest skin points this frame (overlay.h) */

    /* measurements */
    uint64_t frames;
    fp_vmeasure m;            /* frame time, latency, engine and upload times (measure.h) */
    double last_update_ms;
    fp_frame_stats last_active;   /* the last deforming frame's stats (the HUD's guard line) */
    size_t events_window;
    int64_t window_start;
    double input_rate;
    bool committed_shown;     /* last frame committed (HUD) */
    fp_viewer_report rep;
    fp_vtakes takes;          /* T: takes, REC, the review strip (takes.h) */
    fp_vwave wave;            /* the soundtrack's waveform on the timeline (wave.h) */
    fp_voverdub over;         /* --over: a pass over a stack (overdub.h) */
    int error;                /* a failure that ends the run (screenshot not written) */
    char *err;
    size_t errlen;

    /* hot reload of the mapping's .so (checked at most every 250 ms, between frames) */
    struct {
        char file[4096];      /* the file watched (the mapping's, as found by name) */
        struct stat seen;     /* its state when loaded or last reloaded */
        struct stat pending;  /* a change seen, reloaded once it holds still for a check */
        bool have_pending;
        int64_t next_check;
        unsigned long attempts, reloads;
    } hot;
} viewer;

/* A message of `kind` (hud.h: FP_HUD_TAKE and FP_HUD_SETTING stay until their kind
 * replaces them, FP_HUD_INFO fades) to the HUD's stack, and to stderr unless quiet (or
 * always, with always_print: errors). */
static void say_kind(viewer *v, int kind, bool always_print, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void say_kind(viewer *v, int kind, bool always_print, const char *fmt, ...)
{
    char text[FP_HUD_MSG_LEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    fp_hud_say(&v->msgs, kind, fp_now_ns(), text);
    if (!v->opt->quiet || always_print) fprintf(stderr, "facepuppet live: %s\n", text);
}
#define say(v, ...) say_kind(v, FP_HUD_INFO, false, __VA_ARGS__)

/* The session's log lines (input status, mapping and engine errors, recordings): the
 * latest in the HUD's status line, every one to stderr (debug lines only with
 * FACEPUPPET_DEBUG; with quiet, not the engine's and contact guard's notes: fp_slog_is_note). Called from fp_session_step, on this thread or on the session's frame
 * thread while this one waits in it (fp_session.h): never beside the drawing. */
static void on_session_log(void *user, int level, const char *source, const char *message)
{
    viewer *v = user;
    if (level > FP_LOG_INFO && !getenv("FACEPUPPET_DEBUG")) return;
    char text[FP_HUD_MSG_LEN];
    snprintf(text, sizeof text, "%s: %s", source, message);
    fp_hud_say(&v->msgs, level <= FP_LOG_WARNING ? FP_HUD_WARN : FP_HUD_NOTE, fp_now_ns(), text);
    fp_hud_hands_log(&v->hands, v->so.inputs, v->so.input_count, level, source, message);
    if (!(v->opt->quiet && fp_slog_is_note(level, source)))
        fprintf(stderr, "facepuppet live: %s: %s\n", source, message);
}

/* ---- camera ----------------------------------------------------------------------------- */

static void frame_mesh(viewer *v)
{
    const fp_mesh *m = fp_session_mesh(v->s);
    float up[3], fwd[3], d[3];
    fp_session_face_axes(v->s, up, fwd); /* a face turned in its mesh: seen from its front */
    face_axes_set(&v->cam.axes, up, fwd);
    face_axes_frame(&v->cam.axes, m->positions, m->vertex_count, v->cam.target, d);
    float diag = v3_len(d);
    v->cam.yaw = 0;
    v->cam.pitch = 0;
    v->cam.fovy = 35.f * (float)M_PI / 180.f;
    /* The box's front (width x height) fills the view with a margin; the depth adds half. */
    int w, h;
    glfwGetFramebufferSize(v->win, &w, &h);
    float aspect = h > 0 ? (float)w / (float)h : 1.f;
    float half = 0.5f * fmaxf(d[1], d[0] / aspect) * 1.15f;
    v->cam.dist = half / tanf(v->cam.fovy / 2) + 0.5f * d[2];
    v->cam.scene_size = diag > 0 ? diag : 1.f;
    v->cam.front[0] = d[0], v->cam.front[1] = d[1], v->cam.depth = d[2];
    v->cam.aspect = aspect;
}


static void camera_matrices(const viewer *v, int w, int h, float view[16], float proj[16])
{
    const camera *c = &v->cam;
    float eye[3];
    face_axes_eye(&c->axes, c->target, c->dist, c->yaw, c->pitch, eye);
    m4_look_at(view, eye, c->target, c->axes.y);
    float zn = fmaxf(c->dist - 2 * c->scene_size, c->dist * 0.02f);
    m4_perspective(proj, c->fovy, h > 0 ? (float)w / (float)h : 1.f, zn, c->dist + 2 * c->scene_size);
}

/* ---- session ---------------------------------------------------------------------------- */

static int geometry_alloc(viewer *v)
{
    const fp_mesh *m = fp_session_mesh(v->s);
    v->n = m->vertex_count;
    v->t = m->triangle_count;
    size_t bytes = v->n * 3 * sizeof(float);
    float *p[5];
    for (int i = 0; i < 5; i++) p[i] = malloc(bytes);
    free(v->pos); free(v->nrm); free(v->base); free(v->base_nrm); free(v->check);
    v->pos = p[0]; v->nrm = p[1]; v->base = p[2]; v->base_nrm = p[3]; v->check = p[4];
    v->have_pos = v->have_base = false;
    if (!v->pos || !v->nrm || !v->base || !v->base_nrm || !v->check) return -ENOMEM;
    fp_vnormals_free(&v->vn);
    int rc = fp_vnormals_init(&v->vn, m->triangles, v->t, v->n);
    return rc ? rc : fp_render_set_topology(&v->r, v->n, m->triangles, v->t);
}

static void mapping_name(viewer *v, const char *spec)
{
    snprintf(v->mapping, sizeof v->mapping, "%s", spec ? spec : "anchored");
    char *comma = strchr(v->mapping, ',');
    if (comma) *comma = '\0';
}

/* fp_session_options.progress while a session opens (a large face: tens of seconds of
 * loading, indexing and building the contact guard): the caller's callback (opt->session's,
 * `live`'s status line on a terminal), then the step's line drawn alone in the window, where
 * the renderer is up. No events are handled meanwhile (a key's handler would find no
 * session). [the viewer's thread: the one that owns the GL context] */
static void opening_progress(void *user, const char *stage)
{
    viewer *v = user;
    const fp_session_options *caller = &v->opt->session;
    if (caller->progress) caller->progress(caller->progress_user, stage);
    if (!stage || !v->win || !v->r_ready) return;
    int w, h;
    glfwGetFramebufferSize(v->win, &w, &h);
    glViewport(0, 0, w, h);
    glClearColor(0.11f, 0.12f, 0.15f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    char text[600];
    snprintf(text, sizeof text, "opening: %s ...", stage);
    const float white[4] = {0.95f, 0.95f, 0.92f, 1.f};
    fp_render_text(&v->r, w, h, 8, 8, h >= 600 ? 2.f : 1.f, text, white);
    glfwSwapBuffers(v->win);
}

/* Create and start a session on the current options; on success replace the old one. */
static int open_session(viewer *v, char *err, size_t errlen)
{
    fp_session *s = NULL;
    int rc = fp_session_create(&v->so, &s, err, errlen);
    /* no page faults in the frames (fp_session_realtime_memory); where the C library is
     * not glibc the session runs without */
    if (!rc && (rc = fp_session_realtime_memory(s, 0, err, errlen)) == -ENOTSUP) rc = 0;
    if (!rc) rc = fp_session_start(s, err, errlen);
    if (rc) {
        fp_session_destroy(&s);
        return rc;
    }
    fp_session_destroy(&v->s);
    v->s = s;
    fp_vmeasure_new_session(&v->m);
    memset(&v->hands, 0, sizeof v->hands); /* (a new session: its inputs open afresh) */
    if ((rc = geometry_alloc(v))) {
        snprintf(err, errlen, "viewer: out of memory for %zu vertices", v->n);
        return rc;
    }
    const fp_rig *rig = fp_session_rig(v->s); /* the GPU warp's blend weights */
    if (v->gw && fp_render_set_mobility(&v->r, rig ? fp_rig_mobility(rig) : NULL)) {
        snprintf(err, errlen, "viewer: out of GPU memory for %zu vertices", v->n);
        return -ENOMEM;
    }
    v->shown_src = SRC_SESSION;
    frame_mesh(v);
    if (v->opt->opened) v->opt->opened(v->opt->user, v->s, &v->takes.take);
    return 0;
}

static void load_dropped(viewer *v)
{
    char *path = v->drop_path;
    v->drop_path = NULL;
    char err[1024];
    const char *old = v->so.mesh_path;
    v->so.mesh_path = path;
    int rc = open_session(v, err, sizeof err);
    if (rc) {
        v->so.mesh_path = old;
        say_kind(v, FP_HUD_INFO, true, "cannot load %s: %s", path, err);
        free(path);
        if (!v->n) v->error = rc;
        return;
    }
    free(v->mesh_path);
    v->mesh_path = path;
    v->committed_shown = false;
    say_kind(v, FP_HUD_SETTING, false, "loaded %s (%zu vertices)", path, v->n);
}

/* The HUD's state word: the session's, so that undo, reset and a new mesh show at once. */
static const char *hud_state(const viewer *v)
{
    const fp_control_set *cs = fp_session_control_set(v->s);
    return v->paused ? "PAUSED" : cs->active ? "ENGAGED" : v->committed_shown ? "committed" : "idle";
}

/* The HUD's badge (hud.h): recording first, then the review, pause, the gesture (LIMITED
 * while the fold-over guard stops its last frame short, HELD while the contact guard scales
 * it back: fp_hud_gesture_badge), a commit shown, idle. */
static fp_hud_badge hud_badge(const viewer *v)
{
    if (fp_session_take_recording(&v->takes.take)) return FP_HUD_REC;
    if (fp_vtakes_reviewing(&v->takes)) return v->takes.playing ? FP_HUD_PLAYING : FP_HUD_REVIEW;
    if (v->paused) return FP_HUD_PAUSED;
    if (fp_session_control_set(v->s)->active)
        return fp_hud_gesture_badge(v->last_active.guard_reached, v->last_active.collide_t);
    return v->committed_shown ? FP_HUD_COMMITTED : FP_HUD_IDLE;
}

/* ---- keys ------------------------------------------------------------------------------- */

static void set_mapping(viewer *v, const char *spec)
{
    char err[1024];
    if (fp_session_set_mapping(v->s, v->so.plugin_path, spec, err, sizeof err)) {
        say_kind(v, FP_HUD_INFO, true, "%s", err);
        return;
    }
    mapping_name(v, spec);
    say_kind(v, FP_HUD_SETTING, false, "mapping %s", spec);
}

/* T or the pedal's middle button: start or stop a take. */
static void take_toggle(viewer *v)
{
    char msg[1200];
    fp_vtakes_toggle(&v->takes, v->s, fp_now_ns(), msg, sizeof msg);
    if (msg[0]) say_kind(v, FP_HUD_TAKE, false, "%s", msg);
}

/* I, or the pedal's middle button during an overdub's take: punch in or out (overdub.h);
 * the pedal otherwise starts and stops takes. */
static void punch(viewer *v, bool pedal)
{
    char msg[300];
    if (fp_voverdub_punch(&v->over, fp_now_ns(), msg, sizeof msg)) say_kind(v, FP_HUD_TAKE, false, "%s", msg);
    else if (pedal) take_toggle(v);
    else say(v, "I punches in and out while a take records over a stack (--over)");
}

/* L, M, O: select, mute, solo a layer of the stack under an overdub (overdub.h). */
static void layer_key(viewer *v, int key)
{
    char msg[300];
    if (fp_voverdub_layer_key(&v->over, (char)('A' + (key - GLFW_KEY_A)), msg, sizeof msg)) say_kind(v, FP_HUD_TAKE, false, "%s", msg);
    else say(v, "L, M, O select, mute and solo a layer of the stack under an overdub (--over)");
}

static void act(viewer *v, int key)
{
    switch (key) {
    case GLFW_KEY_SPACE: v->paused = !v->paused; break;
    case GLFW_KEY_E: /* the next engage leaves a take's review: the live face again */
        fp_vtakes_leave(&v->takes);
        fp_session_request(v->s, FP_INTENT_ENGAGE);
        break;
    case GLFW_KEY_C: fp_session_request(v->s, FP_INTENT_COMMIT); break;
    case GLFW_KEY_X: fp_session_request(v->s, FP_INTENT_CANCEL); break;
    case GLFW_KEY_Z:
        if (!fp_session_undo(v->s)) say(v, "nothing to undo");
        v->committed_shown = false;
        break;
    case GLFW_KEY_R:
        fp_session_reset(v->s);
        v->committed_shown = false;
        break;
    case GLFW_KEY_J: /* fall through: the jaw, 0.1 per press (the session clamps to [0, 1]) */
    case GLFW_KEY_K: {
        double j = fp_session_channel(v->s, "jaw.open");
        if (isnan(j) || fp_session_set_channel(v->s, "jaw.open", j + (key == GLFW_KEY_J ? 0.1 : -0.1)))
            say(v, "no rig with a jaw.open channel");
        else
            say_kind(v, FP_HUD_SETTING, false, "jaw.open %.1f", fmin(1, fmax(0, j + (key == GLFW_KEY_J ? 0.1 : -0.1))));
        break;
    }
    case GLFW_KEY_G:
        if (!fp_session_rig(v->s) && !v->rig_on) say(v, "no rig to show");
        else v->rig_on = !v->rig_on;
        break;
    case GLFW_KEY_1: set_mapping(v, "anchored"); break;
    case GLFW_KEY_2: set_mapping(v, "unanchored"); break;
    case GLFW_KEY_LEFT_BRACKET: (void)fp_session_set_radius(v->s, fp_session_radius(v->s) / 1.1); break; /* (at a bound: stays) */
    case GLFW_KEY_RIGHT_BRACKET: (void)fp_session_set_radius(v->s, fp_session_radius(v->s) * 1.1); break;
    case GLFW_KEY_W: v->wireframe = !v->wireframe; break;
    case GLFW_KEY_S: /* the next name no file has: an earlier session's shots are kept */
        while (!v->shot_path && v->shot_counter < 9999) {
            if (asprintf(&v->shot_path, "facepuppet-shot-%03d.png", ++v->shot_counter) < 0) {
                v->shot_path = NULL;
            } else if (access(v->shot_path, F_OK) == 0) {
                free(v->shot_path);
                v->shot_path = NULL;
            }
        }
        break;
    case GLFW_KEY_F: frame_mesh(v); break;
    case GLFW_KEY_H: v->hands_on = !v->hands_on; break;
    case GLFW_KEY_TAB: v->hud_on = !v->hud_on; break;
    case GLFW_KEY_SLASH: v->help_on = !v->help_on; break;
    case GLFW_KEY_ESCAPE: /* out of a take's review first; else quit */
        if (fp_vtakes_reviewing(&v->takes)) fp_vtakes_leave(&v->takes);
        else glfwSetWindowShouldClose(v->win, GLFW_TRUE);
        break;
    case GLFW_KEY_V:
        if (fp_vtakes_review(&v->takes)) say(v, "no take to review%s", v->takes.enabled ? "" : " (--take-dir DIR records takes)");
        break;
    case GLFW_KEY_T: take_toggle(v); break;
    case GLFW_KEY_I: punch(v, false); break;
    case GLFW_KEY_L: case GLFW_KEY_M: case GLFW_KEY_O: layer_key(v, key); break;
    case GLFW_KEY_P: fp_vtakes_play_pause(&v->takes, fp_now_ns()); break;
    case GLFW_KEY_COMMA: fp_vtakes_step(&v->takes, -1); break;
    case GLFW_KEY_PERIOD: fp_vtakes_step(&v->takes, 1); break;
    default: break;
    }
}

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    (void)scancode; (void)mods;
    viewer *v = glfwGetWindowUserPointer(w);
    if (action == GLFW_PRESS || (action == GLFW_REPEAT && (key == GLFW_KEY_LEFT_BRACKET ||
                                                           key == GLFW_KEY_RIGHT_BRACKET)))
        act(v, key);
}

static void on_button(GLFWwindow *w, int button, int action, int mods)
{
    (void)mods;
    viewer *v = glfwGetWindowUserPointer(w);
    if (action == GLFW_RELEASE) {
        v->drag = 0;
        return;
    }
    glfwGetCursorPos(w, &v->mx, &v->my);
    v->drag = button == GLFW_MOUSE_BUTTON_LEFT ? 1 : 2;
    /* the left button on the take strip scrubs (drag 3) */
    int ww, wh, fw, fh;
    glfwGetWindowSize(w, &ww, &wh);
    glfwGetFramebufferSize(w, &fw, &fh);
    float sx, sy, sw, sh, px = (float)(v->mx * fw / (ww > 0 ? ww : 1)), py = (float)(v->my * fh / (wh > 0 ? wh : 1));
    fp_vtakes_strip_rect(fw, fh, &sx, &sy, &sw, &sh);
    if (button == GLFW_MOUSE_BUTTON_LEFT && v->takes.frames && px >= sx && px <= sx + sw &&
        py >= sy && py <= sy + sh) {
        v->drag = 3;
        fp_vtakes_scrub(&v->takes, (px - sx) / sw);
    }
}

static void on_cursor(GLFWwindow *w, double x, double y)
{
    viewer *v = glfwGetWindowUserPointer(w);
    double dx = x - v->mx, dy = y - v->my;
    v->mx = x;
    v->my = y;
    if (v->drag == 3) {
        int ww, wh;
        glfwGetWindowSize(w, &ww, &wh);
        fp_vtakes_scrub(&v->takes, (x - 8) / fmax(1, ww - 16));
    } else if (v->drag == 1) {
        v->cam.yaw -= (float)dx * 0.01f;
        v->cam.pitch += (float)dy * 0.01f;
        v->cam.pitch = fmaxf(-1.5f, fminf(1.5f, v->cam.pitch));
    } else if (v->drag == 2) {
        int ww, wh;
        glfwGetWindowSize(w, &ww, &wh);
        float k = 2.f * v->cam.dist * tanf(v->cam.fovy / 2) / (float)(wh > 0 ? wh : 1);
        float cy = cosf(v->cam.yaw), sy = sinf(v->cam.yaw), cp = cosf(v->cam.pitch), sp = sinf(v->cam.pitch);
        const float rl[3] = {cy, 0, -sy}, ul[3] = {-sp * sy, cp, -sp * cy}; /* (the face's axes) */
        float right[3], up[3];
        face_axes_to_mesh(&v->cam.axes, rl, right);
        face_axes_to_mesh(&v->cam.axes, ul, up);
        for (int i = 0; i < 3; i++) v->cam.target[i] += (float)(-dx * right[i] + dy * up[i]) * k;
    }
}

static void on_scroll(GLFWwindow *w, double dx, double dy)
{
    (void)dx;
    viewer *v = glfwGetWindowUserPointer(w);
    v->cam.dist *= powf(0.9f, (float)dy);
    v->cam.dist = fmaxf(v->cam.dist, 1e-3f * v->cam.scene_size);
}

static void on_drop(GLFWwindow *w, int count, const char **paths)
{
    viewer *v = glfwGetWindowUserPointer(w);
    if (count < 1) return;
    free(v->drop_path);
    v->drop_path = strdup(paths[0]);
}

/* ---- hot reload ------------------------------------------------------------------------- */

static bool same_file_state(const struct stat *a, const struct stat *b)
{
    return a->st_dev == b->st_dev && a->st_ino == b->st_ino && a->st_size == b->st_size &&
           a->st_mtim.tv_sec == b->st_mtim.tv_sec && a->st_mtim.tv_nsec == b->st_mtim.tv_nsec;
}

/* Copy src to a fresh private temporary file (dlopen caches by path: a copy has a new one). */
static int copy_to_temp(const char *src, char *tmp, size_t len)
{
    const char *dir = getenv("TMPDIR");
    snprintf(tmp, len, "%s/facepuppet-reload-XXXXXX", dir && *dir ? dir : "/tmp");
    int out = mkstemp(tmp);
    if (out < 0) return -errno;
    int in = open(src, O_RDONLY | O_CLOEXEC), rc = 0;
    if (in < 0) rc = -errno;
    char buf[65536];
    for (ssize_t n; !rc && (n = read(in, buf, sizeof buf)) != 0;) {
        if (n < 0 || write(out, buf, (size_t)n) != n) rc = -EIO;
    }
    if (in >= 0) close(in);
    if (close(out) && !rc) rc = -EIO;
    if (rc) unlink(tmp);
    return rc;
}

/* Between frames: when the mapping's file changed (inode, size or mtime) and then held still
 * for one check, load a copy, create it with the same keys, swap it in; a failure keeps the
 * old mapping and says why (HUD and stderr). */
static void watch_mapping(viewer *v)
{
    int64_t now = fp_now_ns();
    if (now < v->hot.next_check) return;
    v->hot.next_check = now + 250000000LL;
    const char *file = fp_session_mapping_file(v->s);
    struct stat st;
    if (!file || !*file) return;
    if (strcmp(file, v->hot.file)) { /* a new mapping (keys 1, 2, a dropped mesh): watch it */
        snprintf(v->hot.file, sizeof v->hot.file, "%s", file);
        v->hot.have_pending = false;
        if (stat(file, &v->hot.seen)) memset(&v->hot.seen, 0, sizeof v->hot.seen);
        return;
    }
    if (stat(file, &st) || same_file_state(&st, &v->hot.seen)) {
        v->hot.have_pending = false;
        return; /* absent for a moment (being replaced), or unchanged */
    }
    if (!v->hot.have_pending || !same_file_state(&st, &v->hot.pending)) {
        v->hot.pending = st; /* changed: reload at the next check if it holds still */
        v->hot.have_pending = true;
        return;
    }
    v->hot.have_pending = false;
    v->hot.seen = st;
    v->hot.attempts++;
    char tmp[4200], err[2048];
    const char *name = fp_session_mapping_name(v->s);
    int rc = copy_to_temp(file, tmp, sizeof tmp);
    if (rc) {
        say_kind(v, FP_HUD_INFO, true, "mapping '%s': reload of %s failed: cannot copy it (%s); keeping the old one", name, file, strerror(-rc));
        return;
    }
    rc = fp_session_reload_mapping(v->s, tmp, err, sizeof err);
    unlink(tmp); /* loaded (or not): the copy is no longer needed by name */
    if (rc) { /* said with -q too (an error), without the isolated load's own prefix */
        char prefix[128];
        size_t n = (size_t)snprintf(prefix, sizeof prefix, "mapping '%s': ", name);
        const char *why = strncmp(err, prefix, n) ? err : err + n;
        say_kind(v, FP_HUD_INFO, true, "mapping '%s': reload of %s failed: %s; keeping the old one", name, file, why);
        return;
    }
    v->hot.reloads++;
    const fp_plugin *p = fp_session_mapping_plugin(v->s);
    say_kind(v, FP_HUD_SETTING, true, "mapping '%s' reloaded from %s (%s %s)", name, file, p->entry && p->entry->id ? p->entry->id : "?",
        p->entry && p->entry->version ? p->entry->version : "?");
}

/* ---- script ----------------------------------------------------------------------------- */

static bool any_hand(const viewer *v) /* (any performer's) */
{
    for (size_t p = 0; p < fp_session_performer_count(v->s); p++)
        if (fp_session_performer_hand(v->s, p, FP_HAND_LEFT) || fp_session_performer_hand(v->s, p, FP_HAND_RIGHT))
            return true;
    return false;
}

static void run_script(viewer *v)
{
    fp_script *sc = &v->script;
    while (sc->next < sc->count) {
        fp_script_cmd *c = &sc->cmds[sc->next];
        if (c->op == FP_SCRIPT_WAIT_HANDS || c->op == FP_SCRIPT_WAIT_END ||
            c->op == FP_SCRIPT_WAIT_FRAMES || c->op == FP_SCRIPT_WAIT_RELOAD || c->op == FP_SCRIPT_WAIT_SECONDS) {
            if (!sc->waiting) {
                sc->waiting = 1;
                sc->wait_start = v->frames;
                sc->wait_start_s = glfwGetTime();
                sc->reload_mark = v->hot.attempts;
            }
            bool done = c->op == FP_SCRIPT_WAIT_HANDS  ? any_hand(v)
                      : c->op == FP_SCRIPT_WAIT_END    ? fp_session_finished(v->s)
                      : c->op == FP_SCRIPT_WAIT_RELOAD ? v->hot.attempts > sc->reload_mark
                      : c->op == FP_SCRIPT_WAIT_SECONDS ? glfwGetTime() - sc->wait_start_s >= c->number
                                                       : v->frames - sc->wait_start >= (uint64_t)c->number;
            if (!done) return;
            sc->waiting = 0;
            sc->next++;
            continue;
        }
        sc->next++;
        switch (c->op) {
        case FP_SCRIPT_KEY: act(v, c->key); break;
        case FP_SCRIPT_RADIUS: (void)fp_session_set_radius(v->s, c->number); break;
        case FP_SCRIPT_SCRUB: fp_vtakes_scrub(&v->takes, c->number); break;
        case FP_SCRIPT_CAMERA: /* the framed view (F), turned and zoomed */
            frame_mesh(v);
            v->cam.yaw = (float)(c->number * M_PI / 180);
            v->cam.pitch = (float)(c->pitch * M_PI / 180);
            v->cam.dist /= (float)c->zoom;
            break;
        case FP_SCRIPT_SIZE: glfwSetWindowSize(v->win, (int)c->pitch, (int)c->zoom); break;
        case FP_SCRIPT_CLOSE: glfwSetWindowShouldClose(v->win, GLFW_TRUE); return;
        case FP_SCRIPT_PRINT_MAPPING: {
            const fp_plugin *p = fp_session_mapping_plugin(v->s);
            const fp_control_set *cs = fp_session_control_set(v->s);
            printf("mapping %s id %s version %s frame %llu active %d count %zu reloads %lu\n",
                   fp_session_mapping_name(v->s), p->entry && p->entry->id ? p->entry->id : "?",
                   p->entry && p->entry->version ? p->entry->version : "?", (unsigned long long)v->frames,
                   cs->active, cs->count, v->hot.reloads);
            fflush(stdout);
            break;
        }
        case FP_SCRIPT_PRINT_HUD: {
            char hands[FP_HUD_MSG_LEN + 600], lag[64];
            fp_hud_hands_line(&v->hands, v->s, hands, sizeof hands);
            printf("hud frame %llu state %s commits %lu scale %.4g mm per mesh unit (%s) badge %s "
                   "touching %zu of %zu nearest %.2f mm messages %zu drawn %s lag %s hands '%s'\n",
                   (unsigned long long)v->frames, hud_state(v), fp_session_commits(v->s),
                   fp_session_head(v->s)->mm_per_unit, fp_session_head(v->s)->how,
                   fp_hud_badge_name(hud_badge(v)), v->cues.touch_count, v->cues.count,
                   v->cues.nearest * fp_session_head(v->s)->mm_per_unit,
                   fp_hud_live(&v->msgs, fp_now_ns(), (const fp_hud_msg *[FP_HUD_MSGS]){0}, NULL),
                   v->gpu_now ? (v->warp_solved ? "gpu-warp" : "gpu-surface") : "cpu",
                   fp_vmeasure_lag_text(&v->m, fp_now_ns(), lag, sizeof lag), hands[0] ? hands + 1 : "");
            fflush(stdout);
            break;
        }
        case FP_SCRIPT_PRINT_MESSAGES: {
            static const char *const kinds[FP_HUD_KINDS] = {"take", "setting", "note", "info", "warning"};
            const fp_hud_msg *live[FP_HUD_MSGS];
            float alpha[FP_HUD_MSGS];
            size_t n = fp_hud_live(&v->msgs, fp_now_ns(), live, alpha);
            for (size_t i = 0; i < n; i++)
                printf("message frame %llu %s %s alpha %.2f: %s\n", (unsigned long long)v->frames,
                       kinds[live[i]->kind], live[i]->until == INT64_MAX ? "kept" : "fading", alpha[i],
                       live[i]->text);
            printf("messages frame %llu: %zu\n", (unsigned long long)v->frames, n);
            fflush(stdout);
            break;
        }
        case FP_SCRIPT_DROP:
            free(v->drop_path);
            v->drop_path = strdup(c->text);
            return;
        case FP_SCRIPT_SHOT:
            free(v->shot_path);
            v->shot_path = strdup(c->text);
            return;
        default: break;
        }
    }
}

/* ---- drawing ---------------------------------------------------------------------------- */

static const char help_text[] =
    "keys\n"
    " space  pause / run\n"
    " E      engage      C  commit\n"
    " X      cancel      Z  undo commit\n"
    " R      back to the loaded shape\n"
    " J / K  open / close the jaw (rig)\n"
    " G      rig: regions, landmarks, hinge axis\n"
    " 1 / 2  anchored / unanchored\n"
    " [ / ]  radius down / up\n"
    " W wireframe  S screenshot  F frame\n"
    " H hands  Tab HUD  ? this list\n"
    " T      record a take (start / stop)\n"
    " V      review the last take / back to live\n"
    " P      play / pause the last take\n"
    " , / .  a frame back / on; mouse on the strip scrubs\n"
    " Esc    leave the review; else quit\n"
    " I punch in/out; L layer, M mute, O solo (--over)\n"
    "mouse: left orbit, right pan, wheel zoom\n"
    "drop a mesh file on the window to load it\n"
    "spheres: green where a fingertip's support reaches the skin;\n"
    "lines: each fingertip to its nearest skin point";

static void draw_hud(viewer *v, int w, int h, const fp_frame_stats *st)
{
    double recent = fp_vmeasure_recent_ms(&v->m);
    const fp_head *head = fp_session_head(v->s);
    /* the last deforming frame's reach (skin_reach.h): the least share of a touching
     * fingertip's motion that the skin under it followed, and the longest drag, in mm */
    char reach[160] = "", tips[160] = "", contact[160];
    const fp_frame_stats *la = &v->last_active;
    fp_hud_reach_line(la->reach, la->reach_vectors, la->reach_allowed, la->reach_allowed_vectors,
                      la->reach_held, la->reach_asked_max * head->mm_per_unit, reach, sizeof reach);
    fp_hud_contact_line(la->collide_t, la->collide_kept, la->collide_pairs, contact, sizeof contact);
    if (v->cues.count && isfinite(v->cues.nearest))
        snprintf(tips, sizeof tips, "\nfingertips: %zu of %zu touching, nearest %.1f mm from the skin",
                 v->cues.touch_count, v->cues.count, v->cues.nearest * head->mm_per_unit);
    char hands[FP_HUD_MSG_LEN + 600];
    fp_hud_hands_line(&v->hands, v->s, hands, sizeof hands);
    char text[4096], wrapped[8192], scale_line[300], lag[64];
    snprintf(text, sizeof text,
             "%s  %zu vertices  mapping %s\n"
             "%s\n"
             "commits %lu   radius %.4g (%.1f mm)\n"
             "%.1f fps (%.2f ms)   lag %s   engine %.3f ms   input %.0f ev/s%s\n"
             "fold-over guard: bound %.2f  reach %.0f%%  sub-steps %d%s%s%s%s",
             v->mesh_path ? (strrchr(v->mesh_path, '/') ? strrchr(v->mesh_path, '/') + 1 : v->mesh_path) : "", v->n, v->mapping,
             fp_hud_scale_line(head->mm_per_unit, head->how, scale_line, sizeof scale_line), fp_session_commits(v->s),
             fp_session_radius(v->s), fp_session_radius(v->s) * head->mm_per_unit,
             recent > 0 ? 1000.0 / recent : 0.0, recent, fp_vmeasure_lag_text(&v->m, fp_now_ns(), lag, sizeof lag),
             st->active ? st->update_ms : v->last_update_ms, v->input_rate,
             v->opt->gpu_warp ? (v->gpu_now ? "   gpu-warp" : "   gpu-warp (CPU now)") : "",
             v->last_active.guard_bound, 100.0 * v->last_active.guard_reached, v->last_active.guard_substeps,
             reach, contact, tips, hands);
    const float white[4] = {0.95f, 0.95f, 0.92f, 1.f}, dim[4] = {0.8f, 0.85f, 0.9f, 1.f};
    float scale = h >= 600 ? 2.f : 1.f, margin = 8, max_px = (float)w - 2 * margin;
    char tc[40] = "";
    fp_hud_badge b = hud_badge(v);
    if (b == FP_HUD_REC) {
        fp_timecode t;
        if (!fp_session_take_timecode(&v->takes.take, fp_now_ns(), &t)) fp_timecode_format(&t, tc, sizeof tc);
    }
    float y = margin + fp_hud_draw_badge(&v->r, w, h, margin, margin, scale, b, tc) + 4 * scale;
    fp_hud_wrap(text, max_px, scale, wrapped, sizeof wrapped);
    y += fp_render_text(&v->r, w, h, margin, y, scale, wrapped, white) + 6 * scale;
    float bottom = fp_voverdub_bottom_top(&v->over, &v->takes, &v->wave, w, h), room = bottom - y; /* to the strip */
    if (v->rig_on && fp_session_rig(v->s)) room -= fp_overlay_rig_legend_height(scale) + 4 * scale;
    y += fp_hud_draw_msgs(&v->msgs, &v->r, w, h, margin, y, max_px, scale, room, dim, fp_now_ns()) + 4 * scale;
    if (v->rig_on && fp_session_rig(v->s)) fp_overlay_rig_legend(&v->r, v->s, w, h, y, scale, bottom - y);
    fp_vtakes_draw(&v->takes, &v->r, w, h, fp_now_ns(), margin + fp_hud_badge_width(b, tc, scale) + 8 * scale);
    if (!fp_voverdub_draw(&v->over, &v->r, w, h, &v->wave)) /* else the waveform alone */
        fp_vwave_draw_lane(&v->wave, &v->r, w, h, fp_session_take_recording(&v->takes.take)
                                                      ? (double)(fp_now_ns() - v->takes.origin_ns) * 1e-9 : NAN);
    if (v->help_on) fp_hud_draw_help(&v->r, w, h, scale, help_text, white);
    else fp_render_text(&v->r, w, h, margin, (float)h - 14 * scale, scale, "? keys", dim);
}

/* Bring one of the face's GPU copies (base: the ghost and the GPU warp's input; else the
 * shown shape) and its CPU mirror up to src: whole on the first upload or when anything may
 * have changed (nr SIZE_MAX), else only the nr ranges the session reports, with the normals
 * that depend on them (vnormals.h). Returns whether it uploaded. */
static bool upload_shape(viewer *v, bool base, const float *src, const uint32_t *ranges, size_t nr)
{
    const fp_mesh *m = fp_session_mesh(v->s);
    float *pos = base ? v->base : v->pos, *nrm = base ? v->base_nrm : v->nrm;
    bool *have = base ? &v->have_base : &v->have_pos;
    size_t bytes = v->n * 3 * sizeof(float);
    if (v->upload_mode == UPLOAD_FULL) /* as before partial uploads: compared whole */
        nr = !*have || memcmp(src, pos, bytes) ? SIZE_MAX : 0;
    if (!nr && *have) return false;
    if (!*have || nr == SIZE_MAX) {
        memcpy(pos, src, bytes);
        fp_mesh_normals(m->triangles, v->t, pos, v->n, nrm);
        fp_render_upload(&v->r, base, pos, nrm);
        *have = true;
        return true;
    }
    for (size_t k = 0; k < nr; k++)
        memcpy(pos + 3 * (size_t)ranges[2 * k], src + 3 * (size_t)ranges[2 * k],
               ranges[2 * k + 1] * 3 * sizeof(float));
    const uint32_t *up;
    size_t nu = fp_vnormals_update(&v->vn, pos, ranges, nr, nrm, &up);
    fp_render_upload_ranges(&v->r, base, pos, nrm, up, nu);
    if (v->upload_mode == UPLOAD_CHECK) { /* the mirror against the whole computation */
        float *full = malloc(bytes);
        v->upload_checked++;
        if (!full || memcmp(src, pos, bytes) ||
            (fp_mesh_normals(m->triangles, v->t, pos, v->n, full), memcmp(full, nrm, bytes)))
            v->upload_mismatches++;
        free(full);
    }
    return true;
}

/* Upload the base and the shape to show where they changed (fp_session_base_touched,
 * fp_session_touched). The shown buffers hold the session's shape, a take's frame under
 * review, or (the GPU warp drawing this frame) the surface the warp applies to; the last two,
 * and the first after either, are compared whole. */
static void upload(viewer *v)
{
    int64_t t0 = fp_now_ns();
    const uint32_t *ranges;
    size_t nr = fp_session_base_touched(v->s, &ranges);
    bool did = upload_shape(v, true, fp_session_base(v->s), ranges, nr);
    nr = fp_session_touched(v->s, &ranges); /* taken every frame, so the record stays short */
    const float *review = fp_voverdub_shown(&v->over) ? fp_voverdub_shown(&v->over) : fp_vtakes_shown(&v->takes);
    int src = review ? SRC_REVIEW : v->gpu_now ? SRC_SURFACE : SRC_SESSION;
    if (src != SRC_SESSION || v->shown_src != SRC_SESSION) {
        const float *p = src == SRC_REVIEW ? review : src == SRC_SURFACE ? v->warp_surface : fp_session_positions(v->s);
        if (!v->have_pos || memcmp(p, v->pos, v->n * 3 * sizeof(float))) {
            v->have_pos = false;
            did |= upload_shape(v, false, p, NULL, SIZE_MAX);
        }
    } else {
        did |= upload_shape(v, false, fp_session_positions(v->s), ranges, nr);
    }
    v->shown_src = src;
    double ms = (double)(fp_now_ns() - t0) / 1e6;
    fp_vsamples_add(&v->m.upload_all_ms, ms);
    if (did) fp_vsamples_add(&v->m.upload_ms, ms);
}

/* --gpu-warp, each frame before the upload: whether the shader draws the shape this frame
 * (the rig's pose and blend weights on the CPU side, the warp on the GPU), with which
 * coefficients on which surface; where it cannot, the CPU's shape is drawn and the reason is
 * said once (a line on stderr, a HUD note). */
static void gpu_plan(viewer *v)
{
    static const char *const why[] = {
        "the contact guard scaled a frame back (its shape is not the warp's)",
        "more centres than the shader takes",
        "the engine's warp has a polynomial part, which the shader lacks",
        "the engine's coefficients could not be read",
        "the fold-over guard composed several maps (the shader draws one)"};
    v->gpu_now = false;
    if (!v->opt->gpu_warp || !v->gw || fp_vtakes_reviewing(&v->takes) || fp_voverdub_shown(&v->over)) return;
    const struct csrbf_solver *solver;
    int reason = -1;
    int parts = fp_session_warp_parts(v->s, &v->warp_surface, &solver);
    if (parts) {
        reason = parts == -ERANGE ? 4 : 0;
    } else {
        int rc = fp_warp_from_solver(solver, solver ? fp_session_control_set(v->s)->radius : 1.0, &v->warp);
        if (rc) reason = rc == -E2BIG ? 1 : rc == -ENOTSUP ? 2 : 3;
    }
    if (reason >= 0) {
        v->rep.warp_cpu_frames++;
        if (!(v->gpu_said & (1u << reason))) {
            v->gpu_said |= 1u << reason;
            say_kind(v, FP_HUD_NOTE, true, "gpu-warp: %s; drawing those frames from the CPU", why[reason]);
        }
        return;
    }
    v->warp_solved = solver != NULL;
    v->gpu_now = true;
}

/* Compare the GPU warp (transform feedback, then the rig's blend as the session does it)
 * with the CPU engine's shape this frame. */
static void check_warp(viewer *v)
{
    if (!v->gw || fp_gpuwarp_eval(v->gw, &v->warp, v->n, v->warp_surface, v->check)) return;
    const float *cpu = fp_session_positions(v->s), *x = v->warp_surface;
    const fp_rig *rig = fp_session_rig(v->s);
    const float *m = rig ? fp_rig_mobility(rig) : NULL;
    double err = 0, disp = 0;
    for (size_t i = 0; i < 3 * v->n; i += 3) {
        double e = 0, d = 0;
        float mob = m ? m[i / 3] : 1.f;
        for (int k = 0; k < 3; k++) {
            float g = !m ? v->check[i + k] : mob == 0 ? x[i + k] : x[i + k] + mob * (v->check[i + k] - x[i + k]);
            double a = (double)g - cpu[i + k], b = (double)cpu[i + k] - x[i + k];
            e += a * a;
            d += b * b;
        }
        err = fmax(err, sqrt(e));
        disp = fmax(disp, sqrt(d));
    }
    v->rep.warp_checks++;
    v->rep.warp_max_error = fmax(v->rep.warp_max_error, err);
    v->rep.warp_max_displacement = fmax(v->rep.warp_max_displacement, disp);
}

/* The back buffer as the PNG `path` (whole or not at all, png_file.h). A failure's message
 * goes to err: the run's error for --screenshot, the status line for the S key's. */
static int screenshot(viewer *v, const char *path, int w, int h, char *err, size_t errlen)
{
    unsigned char *px = malloc((size_t)w * h * 3);
    if (!px) return fp_errorf(err, errlen, -ENOMEM, "%s: no memory for the screenshot", path);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, px);
    int rc = fp_png_write(path, w, h, px, 1, err, errlen); /* (GL's rows go bottom-up) */
    free(px);
    if (rc < 0) return rc;
    if (!v->opt->quiet) fprintf(stderr, "facepuppet live: wrote %s (%dx%d)\n", path, w, h);
    return 0;
}

static void draw(viewer *v, const fp_frame_stats *st, int w, int h)
{
    glViewport(0, 0, w, h);
    glClearColor(0.11f, 0.12f, 0.15f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    float view[16], proj[16], pv[16];
    camera_matrices(v, w, h, view, proj);
    m4_mul(proj, view, pv);
    bool rig_on = v->rig_on && fp_session_rig(v->s);
    if (rig_on != v->r.shape_colors) {
        if (rig_on) fp_overlay_rig_colors(&v->r, v->s, v->n);
        else fp_render_set_colors(&v->r, NULL);
    }
    static const float skin[4] = {0.86f, 0.7f, 0.6f, 1.f}, ghost[4] = {0.6f, 0.8f, 1.f, 0.22f};
    bool reviewing = fp_vtakes_shown(&v->takes) || fp_voverdub_shown(&v->over);
    bool deformed = !reviewing && fp_session_positions(v->s) != fp_session_base(v->s);
    /* with a rig the shape is the posed base blended by mobility: drawn from the CPU */
    if (reviewing) {
        fp_render_mesh(&v->r, pv, view, false, NULL, skin, v->wireframe);
    } else if (v->gpu_now) {
        /* the engine step's own coefficients (no second solve) on the surface they apply
         * to, blended by the rig's mobility in the shader (fp_render_set_mobility) */
        fp_render_mesh(&v->r, pv, view, false, &v->warp, skin, v->wireframe);
        if (v->warp_solved && (v->warp_frames++ % 30 == 0 || v->shot_path || v->frames + 1 == v->opt->frames))
            check_warp(v); /* (and every frame shot: the tests compare those) */
    } else {
        fp_render_mesh(&v->r, pv, view, false, NULL, skin, v->wireframe);
    }
    if (deformed && (st->active || !fp_session_rig(v->s))) fp_render_mesh(&v->r, pv, view, true, NULL, ghost, false);
    if (rig_on) fp_overlay_rig(&v->r, v->s, v->have_pos ? v->pos : NULL, v->n, pv, w, h);
    if (v->hands_on && !reviewing) fp_overlay_hands(&v->r, v->s, &v->cues, pv, view);
    if (v->hud_on) draw_hud(v, w, h, st);
}

/* ---- the loop --------------------------------------------------------------------------- */

static void on_glfw_error(int code, const char *text)
{
    (void)code;
    fprintf(stderr, "facepuppet live: GLFW: %s\n", text);
}

static void frame(viewer *v)
{
    glfwPollEvents();
    if (v->drop_path) load_dropped(v);
    watch_mapping(v);
    run_script(v);
    if (v->drop_path) load_dropped(v);
    fp_frame_stats st;
    memset(&st, 0, sizeof st);
    int64_t now = fp_now_ns();
    char take_msg[1200];
    int take_rc = fp_vtakes_tick(&v->takes, v->s, now, take_msg, sizeof take_msg); /* (a failed */
    if (take_msg[0]) say_kind(v, FP_HUD_TAKE, take_rc != 0, "%s", take_msg); /* one: with -q too) */
    if (v->paused && v->opt->frame_paused) v->opt->frame_paused(v->opt->user, now); /* (--control) */
    if (!v->paused) {
        if (v->opt->frame_begin) v->opt->frame_begin(v->opt->user, now); /* (--control) */
        if (v->opt->step_begin) v->opt->step_begin(); /* (a stuck frame: app_stop.h) */
        fp_session_step(v->s, now, &st);
        if (v->opt->step_end) v->opt->step_end();
        if (v->opt->sound.frame_done) v->opt->sound.frame_done(v->opt->sound.user, now);
        if (v->opt->frame_end) v->opt->frame_end(v->opt->user, now); /* (--stream) */
        for (unsigned k = fp_session_record_toggles(v->s); k > 0; k--) punch(v, true);
        if (st.committed) v->committed_shown = true;
        if (st.engaged || st.cancelled) v->committed_shown = false;
        if (st.engaged) fp_vtakes_leave(&v->takes); /* (an engage by a pedal or a gesture) */
        if (st.active) {
            fp_vsamples_add(&v->m.engine_ms, st.update_ms);
            v->last_update_ms = st.update_ms;
            v->last_active = st;
        }
        v->events_window += st.events;
        fp_vmeasure_hands(&v->m, v->s);
    }
    if (now - v->window_start >= 1000000000LL) {
        v->input_rate = (double)v->events_window * 1e9 / (double)(now - v->window_start);
        v->events_window = 0;
        v->window_start = now;
    }
    fp_voverdub_frame(&v->over, &v->takes, v->s, v->so.plugin_path, now, take_msg, sizeof take_msg);
    if (take_msg[0]) say_kind(v, FP_HUD_TAKE, false, "%s", take_msg);
    fp_overlay_tip_cues(v->s, &v->cues);
    gpu_plan(v);
    upload(v);
    int w, h;
    glfwGetFramebufferSize(v->win, &w, &h);
    if (w > 0 && h > 0) /* a resized window keeps the framing */
        v->cam.dist = frame_keep_dist(v->cam.dist, v->cam.front, v->cam.depth, &v->cam.aspect, (float)w / (float)h);
    draw(v, &st, w, h);
    bool last = v->opt->frames && v->frames + 1 >= v->opt->frames;
    if (last && v->opt->screenshot && !v->shot_path) v->shot_path = strdup(v->opt->screenshot);
    if (v->shot_path) {
        char msg[1200];
        int rc = screenshot(v, v->shot_path, w, h, msg, sizeof msg);
        free(v->shot_path);
        v->shot_path = NULL;
        if (rc && v->opt->screenshot) { /* --screenshot's: the run fails with it, -EIO as
                                          * any output's (fp_viewer_run) */
            v->error = rc == -ENOMEM ? rc : -EIO;
            snprintf(v->err, v->errlen, "%s", msg);
        } else if (rc) {
            say(v, "%s", msg); /* the S key's: said, the performance goes on */
        }
    }
    glfwSwapBuffers(v->win);
    glFinish(); /* never queue frames: the next frame starts when this one is shown */
    fp_vmeasure_swap(&v->m, fp_now_ns());
    v->frames++;
}

int fp_viewer_run(const fp_viewer_options *opt, fp_viewer_report *report, char *err,
                  size_t errlen)
{
    viewer *v = calloc(1, sizeof *v);
    if (!v) return -ENOMEM;
    v->opt = opt;
    v->so = opt->session;
    v->so.log = on_session_log;
    v->so.log_user = v;
    v->so.progress = opening_progress; /* the window shows the opening; the caller's still runs */
    v->so.progress_user = v;
    fp_vtakes_init(&v->takes, opt->take_dir, opt->slate, opt->countdown_s, &v->so);
    v->takes.sound = &opt->sound;
    (void)fp_vwave_init(&v->wave, opt->sound.soundtrack, opt->sound.soundtrack_offset_s); /* (-ENOMEM: none drawn) */
    if (fp_voverdub_init(&v->over, opt->over, opt->layer, err, errlen)) {
        fp_vtakes_free(&v->takes);
        fp_vwave_free(&v->wave);
        free(v);
        return -EINVAL;
    }
    v->err = err;
    v->errlen = errlen;
    v->hands_on = v->hud_on = true;
    v->last_active.guard_reached = 1.0;
    v->last_active.guard_substeps = 1;
    v->last_active.collide_t = v->last_active.collide_kept = 1.0;
    const char *um = getenv("FACEPUPPET_VIEWER_UPLOAD");
    v->upload_mode = um && !strcmp(um, "full") ? UPLOAD_FULL : um && !strcmp(um, "check") ? UPLOAD_CHECK
                                                                                      : UPLOAD_PARTIAL;
    int rc = 0;
    bool glfw = false;
    if (opt->script && (rc = fp_script_parse(opt->script, &v->script, err, errlen))) goto out;
    if (!opt->session.mesh_path || !(v->mesh_path = strdup(opt->session.mesh_path))) {
        snprintf(err, errlen, "viewer: a mesh is required");
        rc = -EINVAL;
        goto out;
    }
    v->so.mesh_path = v->mesh_path;
    mapping_name(v, opt->session.mapping);

    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) {
        snprintf(err, errlen, "no display: GLFW cannot initialise (is DISPLAY set? try xvfb-run)");
        rc = -ENODEV;
        goto out;
    }
    glfw = true;
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    v->win = glfwCreateWindow(opt->width > 0 ? opt->width : 1280, opt->height > 0 ? opt->height : 720,
                              "facepuppet live", NULL, NULL);
    if (!v->win) {
        snprintf(err, errlen, "cannot open a window with an OpenGL 3.3 core context");
        rc = -ENODEV;
        goto out;
    }
    glfwMakeContextCurrent(v->win);
    glfwSwapInterval(opt->vsync ? 1 : 0);
    glfwSetWindowUserPointer(v->win, v);
    glfwSetKeyCallback(v->win, on_key);
    glfwSetMouseButtonCallback(v->win, on_button);
    glfwSetCursorPosCallback(v->win, on_cursor);
    glfwSetScrollCallback(v->win, on_scroll);
    glfwSetDropCallback(v->win, on_drop);
    if ((rc = fp_render_init(&v->r, err, errlen))) goto out;
    v->r_ready = true;
    if (opt->gpu_warp && fp_gpuwarp_create(&v->gw, err, errlen)) { /* said once; the CPU draws */
        fprintf(stderr, "facepuppet live: gpu-warp: %s; drawing from the CPU\n", err);
        err[0] = '\0';
    }
    if ((rc = open_session(v, err, errlen))) goto out;
    if (!opt->quiet) {
        const char *renderer = (const char *)glGetString(GL_RENDERER);
        fprintf(stderr, "facepuppet live: %s, %zu vertices, rig %s, mapping %s, radius %.4g; OpenGL %s on %s\n",
                v->mesh_path, v->n, fp_session_rig_how(v->s), v->mapping, fp_session_radius(v->s),
                (const char *)glGetString(GL_VERSION), renderer ? renderer : "?");
    }
    int64_t t0 = v->window_start = fp_now_ns();
    while (!glfwWindowShouldClose(v->win) && !v->error &&
           !(opt->stop_requested && opt->stop_requested())) {
        frame(v);
        if (opt->frames && v->frames >= opt->frames) break;
        if (opt->duration_s > 0 && fp_now_ns() - t0 >= (int64_t)(opt->duration_s * 1e9)) break;
    }
    if (!v->error && opt->out && fp_session_save(v->s, opt->out, err, errlen)) v->error = -EIO;
    {   /* a take still recording ends with the run; a failed one (then or before) fails it */
        char msg[1200], over_msg[1200];
        int trc = fp_vtakes_stop(&v->takes, v->s, msg, sizeof msg);
        if (msg[0] && (trc || !opt->quiet)) fprintf(stderr, "facepuppet live: %s\n", msg);
        fp_voverdub_frame(&v->over, &v->takes, v->s, v->so.plugin_path, fp_now_ns(), over_msg, sizeof over_msg);
        if (over_msg[0]) fprintf(stderr, "facepuppet live: %s\n", over_msg);
        if (!v->error && (trc = fp_vtakes_failed(&v->takes, err, errlen))) v->error = trc;
    }
    char stop_err[1024]; /* record=FILE: a failed write fails the run */
    int stop_rc = fp_session_stop(v->s, stop_err, sizeof stop_err);
    if (!v->error && stop_rc) {
        v->error = stop_rc;
        snprintf(err, errlen, "%s", stop_err);
    }
    if (v->error) {
        rc = v->error;
        if (!err[0]) snprintf(err, errlen, "viewer: the run failed");
    }
out:
    if (v->s) v->rep.dropped = fp_session_dropped(v->s);
    v->rep.frames = v->frames;
    fp_vmeasure_report(&v->m, &v->rep);
    v->rep.upload_checked = v->upload_checked;
    v->rep.upload_mismatches = v->upload_mismatches;
    if (report) *report = v->rep;
    fp_vtakes_free(&v->takes);
    fp_voverdub_free(&v->over);
    fp_vwave_free(&v->wave);
    fp_session_destroy(&v->s);
    if (v->win) {
        fp_gpuwarp_destroy(&v->gw);
        fp_render_free(&v->r);
        glfwDestroyWindow(v->win);
    }
    if (glfw) glfwTerminate();
    fp_script_free(&v->script);
    fp_vmeasure_free(&v->m);
    fp_vnormals_free(&v->vn);
    free(v->pos); free(v->nrm); free(v->base); free(v->base_nrm); free(v->check);
    free(v->shot_path);
    free(v->drop_path);
    free(v->mesh_path);
    free(v);
    return rc;
}
