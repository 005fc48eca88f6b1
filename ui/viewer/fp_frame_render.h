/*
 * fp_frame_render.h: a mesh's frames rendered headless to PNG files, as the live viewer
 * draws the face (ui/viewer/render.c: smooth-shaded skin, the viewer's background), for
 * `facepuppet export --format png-seq`. A hidden GLFW window gives the OpenGL 3.3 core
 * context; frames are drawn into an offscreen framebuffer of the asked size and read back,
 * so the window's size and visibility do not matter (under Xvfb in tests: xvfb-run).
 *
 * Camera: framed on the mesh's bounds as the viewer's F key does (35 degree field of view,
 * the front of the box with a margin), then turned by yaw (about +y, degrees, positive to the
 * face's left) and pitch (degrees, positive from above), the distance divided by zoom.
 *
 * Errors: 0 or a negative code with err: -ENODEV (no display, no GL 3.3 context),
 * -EINVAL (bad size), -ENOMEM, a PNG's write errors (fp_frame_renderer_png). Thread rules:
 * the process's main thread (GLFW's rule); one renderer at a time.
 */
#ifndef FP_FRAME_RENDER_H
#define FP_FRAME_RENDER_H

#include "fp_mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct fp_frame_render_options {
    int width, height;        /* pixels; 0: 1280 x 720 */
    double yaw_deg, pitch_deg;/* about the face's up and left */
    double zoom;              /* 0: 1 */
    float up[3], forward[3];  /* the face's axes (fp_session_face_axes), unit and orthogonal;
                                 all zeros: +y up, looking along +z */
} fp_frame_render_options;

typedef struct fp_frame_renderer fp_frame_renderer;

/** Open the renderer for `mesh` (its triangles; the camera framed on its positions; the
 *  mesh must outlive the renderer). Returns 0 and *out. */
int fp_frame_renderer_open(const fp_mesh *mesh, const fp_frame_render_options *opt,
                           fp_frame_renderer **out, char *err, size_t errlen);

/** Draw the mesh at `positions` (vertex_count x 3, normals recomputed) and write PNG `path`
 *  (png_file.h: a temporary file beside it, renamed over it: whole or not at all; an
 *  existing PNG is left as it was on failure). Returns 0 or fp_png_write's negative errno:
 *  -ENOENT (no such folder), -EACCES, -ENOSPC, -ENOMEM, -EIO. */
int fp_frame_renderer_png(fp_frame_renderer *r, const float *positions, const char *path,
                          char *err, size_t errlen);

void fp_frame_renderer_close(fp_frame_renderer **r);

#ifdef __cplusplus
}
#endif
#endif
