/*
 * fp_viewer.h: the live viewer (`facepuppet live`): one GLFW 3.3 window with an OpenGL 3.3
 * core context (libepoxy) showing a puppeteering session as it is performed: the face
 * (smooth shaded, normals recomputed every frame, optional wireframe), the base shape as a
 * translucent ghost while a deformation is engaged, both hands' skeletons, each fingertip's
 * support sphere (radius R), the control vectors as arrows, and a HUD (stb_easy_font).
 *
 * Frame loop: poll window events, run due script commands, step the session once with the
 * current time (inputs run on their own threads, so the frame always shows the latest pose
 * and never queues: swap interval 0 unless vsync is asked, glFinish after each swap), upload,
 * draw, swap. The upload follows the supports: positions and normals are recomputed and
 * uploaded only inside the vertex ranges the session reports (fp_session_touched,
 * fp_session_base_touched; normals of the vertices of triangles with a changed vertex, bit for
 * bit the whole computation's), the base only when it changed. FACEPUPPET_VIEWER_UPLOAD=full
 * uploads whole meshes on any change (for comparisons), =check compares every partial upload
 * with the whole computation (fp_viewer_report.upload_mismatches). Timing is measured inside: frame time (swap to swap) and the latency from a
 * hand event's time (fp_session_hand_since: fp_hand_pose.time_ns on the host clock, or, for a
 * replay or take, whose times are the recording's, when it was pushed) to the swap of the
 * first frame showing it (measure.h); the HUD shows the lag beside the frame time: the
 * median latency of the last second, in ms and over that second's median frame time, in
 * frames (fp_viewer_report.latency_frames_median is the same over the run), "-" where no
 * hand sample was shown in it.
 *
 * Keys: space pause, E engage, C commit, X cancel, Z undo, R reset to the loaded shape,
 * 1 anchored, 2 unanchored, [ ] radius down / up (x 1/1.1, 1.1), W wireframe, S screenshot
 * (facepuppet-shot-NNN.png, the next NNN no file has), F frame the mesh, H hands and supports on/off, Tab HUD on/off,
 * J / K open / close the jaw by 0.1 (a rig's jaw.open), G the rig on/off (regions coloured:
 * skull blue, jaw red, soft tissue green blending to red by its jaw weight; landmarks as
 * white points, the hinge axis as a cyan line through the two joints; a legend in the HUD),
 * I punch in/out and L, M, O select, mute, solo a layer of the stack under an overdub
 * (--over; overdub.h), T take start/stop (the live face and hands stay shown), V review the last take (again:
 * back to live; so do Esc and the next engage), P play/pause it, , . a frame back/on,
 * ? (or /) the key list (on a backdrop), Esc quit (in a review: back to live). The HUD
 * (hud.h): a state badge by colour, a message stack that wraps and fades; fingertip cues
 * (overlay.h). --gpu-warp with a rig: the rig's pose and mobility from the CPU, the warp and
 * the blend in the shader; frames it cannot draw come from the CPU (said once). Mouse: left drag orbit, right or middle drag pan, wheel
 * zoom. A mesh file dropped on the window is loaded (the session is created anew on it).
 *
 * Script (deterministic runs and tests): commands separated by ';' or new lines, run in
 * order at the start of frames; a `wait` holds the rest until it holds, a `shot` ends the
 * frame's commands (the shot shows this frame):
 *   wait hands | wait end | wait frames N    a hand is present / every input ended / N frames
 *                                            passed since the wait began
 *   key NAME     as the key: E C X Z R 1 2 [ ] W S F H J K G T P V I L M O , . Tab ? space Esc
 *   shot FILE    write this frame as PNG
 *   radius R     set the support radius (mesh units)
 *   camera YAW PITCH [ZOOM]   the framed view (F) turned by yaw (degrees, about +y, positive
 *                to the face's left) and pitch (degrees, from above), the distance / ZOOM
 *   drop FILE    as a file dropped on the window
 *   size WxH     resize the window to W x H pixels (16..16384), as the performer dragging
 *                its edge: the framing is kept (the face keeps its place and share)
 *   print mapping | print hud   one stdout line: the mapping (name, id, version, active,
 *                control vectors, reloads) / the HUD (state ENGAGED|committed|idle|PAUSED,
 *                commits in the base, mm per mesh unit and how it was found, the badge,
 *                fingertips touching and the nearest's mm, messages, drawn cpu|gpu-warp,
 *                lag "X frames (Y ms)" or "-", the hands line)
 *   print messages   the HUD's message stack, a line each (kind, kept|fading, alpha, text)
 *   close        as the window's close button (glfwSetWindowShouldClose)
 *
 * Thread rules: call from the process's main thread (GLFW's rule); one viewer at a time.
 */
#ifndef FP_VIEWER_H
#define FP_VIEWER_H

#include "fp_session.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

struct fp_session_take; /* (fp_session_take.h) */
struct fp_session_take_options;
struct fp_soundtrack;   /* (fp_audio.h) */

/* The performance's sound and timecode (ui/cli: live's --audio, --audio-in, --timecode), each
 * NULL for none; called on the viewer's thread with `user`:
 *   take_starting(user, origin_ns, o)  a take is about to start at host time origin_ns: fill
 *                                      o's soundtrack and timecode fields (o: the take's own)
 *   take_started(user, take, origin_ns) it started (its path, header: take->rec, header)
 *   take_stopped(user)                 it stopped (after its last frame)
 *   frame_done(user, now_ns)           a frame was stepped at now_ns (not while paused)
 * soundtrack: drawn as a waveform on the take strip, from soundtrack_offset_s at a take's
 * start (the caller's; outlives fp_viewer_run). */
typedef struct fp_viewer_sound {
    void (*take_starting)(void *user, int64_t origin_ns, struct fp_session_take_options *o);
    void (*take_started)(void *user, const struct fp_session_take *take, int64_t origin_ns);
    void (*take_stopped)(void *user);
    void (*frame_done)(void *user, int64_t now_ns);
    void *user;
    const struct fp_soundtrack *soundtrack;
    double soundtrack_offset_s;
} fp_viewer_sound;

typedef struct fp_viewer_options {
    fp_session_options session;  /* as for fp_session_create (mesh, inputs, mapping, ...) */
    int width, height;           /* window size in screen coordinates; 0: 1280 x 720 */
    uint64_t frames;             /* stop after this many frames; 0: until the window closes */
    double duration_s;           /* stop after this many seconds; 0: no limit */
    const char *out;             /* write the final shape here (format by extension), or NULL */
    const char *screenshot;      /* write the last frame here (PNG) before exiting, or NULL */
    const char *script;          /* script text (see above), or NULL */
    bool gpu_warp;               /* evaluate the warp in the vertex shader (and check it
                                    against the CPU engine by transform feedback) */
    bool vsync;                  /* swap interval 1 (default 0: never wait for the display) */
    bool quiet;                  /* no status lines on stderr, nor the engine's and contact
                                    guard's notes (fp_slog_is_note); errors and the inputs',
                                    recordings', mapping's and rig's lines still print */
    const char *take_dir;        /* T records takes here (ui/viewer/takes.h); NULL: no takes */
    const char *slate;           /* the takes' slate; NULL: "take" */
    double countdown_s;          /* seconds counted down before a take starts; 0: none */
    const char *over;            /* --over STACK_OR_TAKE: takes are passes over it (overdub.h) */
    const char *layer;           /* --layer REGION[:MODE] of those passes; NULL: mouth */
    /* An end asked from outside (SIGINT, SIGTERM: ui/cli/app_stop.h), NULL each for none:
     * stop_requested, read before each frame, ends the loop as the window's closing does
     * (the take closed, --out written); step_begin and step_end bracket the session's step;
     * opened(user, s, take) gives the caller the session (again after a dropped mesh) and
     * the take recorder, for a take-over from another thread while a frame is stuck in a
     * plugin (valid until fp_viewer_run returns; called on this thread between frames). */
    bool (*stop_requested)(void);
    void (*step_begin)(void);
    void (*step_end)(void);
    void (*opened)(void *user, fp_session *s, struct fp_session_take *take);
    /* frame_begin and frame_end (NULL: none) bracket each frame's session step (not while
     * paused), on this thread: the control surface's commands applied before it, the frame
     * streamed after it (ui/cli/app_link.h); now_ns is the frame's time. */
    void (*frame_begin)(void *user, int64_t now_ns);
    void (*frame_end)(void *user, int64_t now_ns);
    /* frame_paused (NULL: none) instead of them on each frame drawn while paused (space): the
     * control surface's commands applied and answered, the status pushed when due, nothing
     * streamed (the session does not step). */
    void (*frame_paused)(void *user, int64_t now_ns);
    void *user;
    fp_viewer_sound sound;       /* soundtrack, microphone, timecode hooks (above) */
} fp_viewer_options;

/** What a run measured. Times in milliseconds. */
typedef struct fp_viewer_report {
    uint64_t frames;
    double frame_ms_median, frame_ms_p99;      /* swap to swap, over all frames but the first */
    size_t latency_samples;                    /* hand events shown */
    double latency_ms_median, latency_ms_p99;  /* event (fp_session_hand_since) to the swap
                                                  showing it */
    double latency_frames_median;              /* the lag in frames: latency_ms_median over
                                                  frame_ms_median (0 where that is 0); the
                                                  HUD's lag is the same over the last second */
    double engine_ms_median;                   /* fp_frame_stats.update_ms of active frames */
    size_t warp_checks;                        /* GPU-warp read-backs compared */
    double warp_max_error;                     /* max |GPU - CPU| over vertices, mesh units */
    double warp_max_displacement;              /* max |CPU - surface| in those frames (the
                                                  surface: the base posed by the rig) */
    size_t warp_cpu_frames;                    /* --gpu-warp frames drawn from the CPU (the
                                                  reason said once on stderr) */
    unsigned long dropped;                     /* input events dropped (queues full) */
    size_t uploads;                            /* frames that uploaded a shape (changed) */
    double upload_ms_median, upload_ms_p99;    /* their normals + GL upload, CPU side */
    double upload_all_ms_median, upload_all_ms_p99; /* the same over every frame */
    unsigned long upload_checked;              /* FACEPUPPET_VIEWER_UPLOAD=check: partial */
    unsigned long upload_mismatches;           /* uploads compared whole, and those that
                                                  differed from the whole computation */
} fp_viewer_report;

/** Open the window, create and start the session from opt->session, run until the window
 *  closes (Esc, close button, script), opt->frames frames pass, or an error. report may be
 *  NULL. Returns 0, or a negative code with a message in err: the session's codes (see
 *  fp_session_create: -EINVAL, -EBADMSG, -ENOENT, FP_EPLUGIN_*), -ENODEV (no display, no
 *  OpenGL 3.3 core context, a shader that does not build), -EIO (a screenshot or the final
 *  mesh could not be written), -EINVAL also for a malformed script (naming the command). */
int fp_viewer_run(const fp_viewer_options *opt, fp_viewer_report *report, char *err,
                  size_t errlen);

/** The median and the 99th percentile (nearest rank) of n values; sorts v in place.
 *  Both 0 for n == 0. */
void fp_viewer_percentiles(double *v, size_t n, double *median, double *p99);

#ifdef __cplusplus
}
#endif
#endif
