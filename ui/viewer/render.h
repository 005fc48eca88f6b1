/* render.h: the viewer's OpenGL 3.3 core drawing (internal to ui/): the face (smooth shaded,
 * optional wireframe, optional GPU warp), its translucent ghost, spheres, lines and points,
 * and stb_easy_font text. Every function needs the context current. */
#ifndef FP_UI_RENDER_H
#define FP_UI_RENDER_H

#include "fp_gpuwarp.h"

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct fp_render {
    GLuint prog_mesh, prog_lines, prog_text;
    /* the face: shown shape (updated per frame) and base shape (ghost, GPU warp) */
    GLuint vao_shape, vbo_shape_pos, vbo_shape_nrm;
    GLuint vao_base, vbo_base_pos, vbo_base_nrm;
    GLuint ebo_tris;
    size_t vertex_count, index_count;
    /* per-vertex colours of the shown shape (the rig's regions), attribute 2 of vao_shape */
    GLuint vbo_shape_col;
    bool shape_colors;
    /* per-vertex mobility of a rig (attribute 3 of vao_shape) for a warp drawn on it */
    GLuint vbo_shape_mob;
    bool shape_mobility;
    /* a unit sphere */
    GLuint vao_sphere, vbo_sphere, ebo_sphere;
    GLsizei sphere_indices;
    /* lines and points: x y z r g b a per vertex */
    GLuint vao_lines, vbo_lines;
    size_t lines_cap;
    /* text: stb_easy_font quads */
    GLuint vao_text, vbo_text, ebo_text;
    size_t text_quads_cap;
} fp_render;

/** Compile the programs, make the sphere. Returns 0 or -ENODEV with the GL log in err. */
int fp_render_init(fp_render *r, char *err, size_t errlen);
void fp_render_free(fp_render *r);

/** (Re)allocate the face's buffers for n vertices and t triangles (t x 3 indices). */
int fp_render_set_topology(fp_render *r, size_t n, const uint32_t *tris, size_t t);
/** Upload the shown shape, or the base shape (base = true): positions and normals, n x 3. */
void fp_render_upload(fp_render *r, bool base, const float *pos, const float *nrm);
/** The same for some vertices only: `count` (first, count) vertex ranges, increasing, of the
 *  full n x 3 arrays pos and nrm (glBufferSubData per range and buffer). */
void fp_render_upload_ranges(fp_render *r, bool base, const float *pos, const float *nrm,
                             const uint32_t *ranges, size_t count);

/** Colour the shown shape per vertex: rgb, vertex_count x 3 floats in [0, 1], replaces the
 *  flat colour of fp_render_mesh (base = false; its alpha stays) until called with NULL or
 *  the topology changes. Shaded as the face. Returns 0 or -ENOMEM. */
int fp_render_set_colors(fp_render *r, const float *rgb);

/** A rig's mobility per vertex for a warp drawn from the shown buffers: m, vertex_count
 *  floats in [0, 1] (fp_rig_mobility); then fp_render_mesh(base = false, warp) draws
 *  x + m (T(x) - x), the session's blend (fp_rig_apply_mobility), with the normals by the
 *  blend's Jacobian I + m (J_T - I) (the term of grad m left out: shading only). NULL: the
 *  warp alone. Kept until called again or the topology changes. Returns 0 or -ENOMEM. */
int fp_render_set_mobility(fp_render *r, const float *m);

/** Draw the face from the shown (base = false) or base buffers. warp: NULL, or coefficients
 *  applied in the vertex shader to the buffer's positions (blended by the mobility of
 *  fp_render_set_mobility when drawn from the shown buffers). color: RGBA (A < 1:
 *  translucent, no depth writes). mvp and view: column-major 4x4. */
void fp_render_mesh(fp_render *r, const float mvp[16], const float view[16], bool base,
                    const fp_warp_coeffs *warp, const float color[4], bool wireframe);

/** Translucent spheres of radius `radius` at n centres (n x 3). */
void fp_render_spheres(fp_render *r, const float proj_view[16], const float view[16],
                       const float *centres, size_t n, float radius, const float color[4]);

/** Lines (mode GL_LINES) or points (GL_POINTS, size in pixels) from n vertices of
 *  x y z r g b a floats. depth: test against the face. */
void fp_render_lines(fp_render *r, const float mvp[16], const float *verts, size_t n,
                     GLenum mode, float point_size, bool depth);

/** Text at pixel (x, y) from the top-left of a fbw x fbh framebuffer, stb_easy_font glyphs
 *  scaled by `scale`, in color. Returns the height drawn in pixels. */
float fp_render_text(fp_render *r, int fbw, int fbh, float x, float y, float scale,
                     const char *text, const float color[4]);

/** The width and the height in pixels that fp_render_text draws text at scale (the widest
 *  line; every line). No GL: any thread. */
float fp_render_text_width(const char *text, float scale);
float fp_render_text_height(const char *text, float scale);

/** A filled rectangle at pixel (x, y) from the top left, w x h pixels, in color (A < 1
 *  blends): the HUD's boxes (the take timeline). */
void fp_render_rect(fp_render *r, int fbw, int fbh, float x, float y, float w, float h,
                    const float color[4]);

/** n filled rectangles (xywh: n x 4 floats, pixels from the top left) in one colour, one
 *  draw call (a waveform's columns). Returns 0 or -ENOMEM (nothing drawn). */
int fp_render_rects(fp_render *r, int fbw, int fbh, const float *xywh, size_t n,
                    const float color[4]);

#endif
