/* The viewer's OpenGL drawing: shaders, buffers, text. */
#define _GNU_SOURCE
#include "render.h"

#include "vmath.h"

#define STB_EASY_FONT_IMPLEMENTATION
#include <stb_easy_font.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- shaders --------------------------------------------------------------------------- */

static const char mesh_vs[] =
    "layout(location = 0) in vec3 a_pos;\n"
    "layout(location = 1) in vec3 a_nrm;\n"
    "layout(location = 2) in vec3 a_col;\n"
    "layout(location = 3) in float a_mob;\n"
    "uniform mat4 u_mvp;\n"
    "uniform mat4 u_view;\n"
    "uniform int u_warp_on;\n"
    "uniform int u_mob_on;\n"
    "out vec3 v_nrm;\n"
    "out vec3 v_posv;\n"
    "out vec3 v_col;\n"
    "void main() {\n"
    "    v_col = a_col;\n"
    "    vec3 p = a_pos, n = a_nrm;\n"
    "    if (u_warp_on != 0) {\n"
    "        mat3 j;\n"
    "        p = fp_warp(a_pos, j);\n"
    "        if (u_mob_on != 0) {\n" /* a rig's blend: posed + m (T(posed) - posed) */
    "            p = a_pos + a_mob * (p - a_pos);\n"
    "            j = mat3(1.0) + a_mob * (j - mat3(1.0));\n"
    "        }\n"
    "        n = transpose(inverse(j)) * a_nrm;\n"
    "    }\n"
    "    gl_Position = u_mvp * vec4(p, 1.0);\n"
    "    v_nrm = mat3(u_view) * n;\n"
    "    v_posv = (u_view * vec4(p, 1.0)).xyz;\n"
    "}\n";

/* Two-sided Blinn-Phong with a key light above-left of the camera and a fill. */
static const char mesh_fs[] =
    "in vec3 v_nrm;\n"
    "in vec3 v_posv;\n"
    "in vec3 v_col;\n"
    "uniform vec4 u_color;\n"
    "uniform int u_flat;\n"
    "uniform int u_vcolor;\n"
    "out vec4 o_color;\n"
    "void main() {\n"
    "    if (u_flat != 0) { o_color = u_color; return; }\n"
    "    vec3 n = normalize(v_nrm);\n"
    "    vec3 v = normalize(-v_posv);\n"
    "    if (dot(n, v) < 0.0) n = -n;\n"
    "    vec3 l = normalize(vec3(-0.45, 0.6, 0.75));\n"
    "    float diff = max(dot(n, l), 0.0);\n"
    "    float fill = 0.35 * max(dot(n, v), 0.0);\n"
    "    float spec = pow(max(dot(n, normalize(l + v)), 0.0), 40.0) * 0.18;\n"
    "    vec3 c = u_vcolor != 0 ? v_col : u_color.rgb;\n"
    "    o_color = vec4(c * (0.16 + 0.62 * diff + fill) + vec3(spec), u_color.a);\n"
    "}\n";

static const char lines_vs[] =
    "layout(location = 0) in vec3 a_pos;\n"
    "layout(location = 1) in vec4 a_color;\n"
    "uniform mat4 u_mvp;\n"
    "uniform float u_point_size;\n"
    "out vec4 v_color;\n"
    "void main() { gl_Position = u_mvp * vec4(a_pos, 1.0); gl_PointSize = u_point_size;"
    " v_color = a_color; }\n";
static const char lines_fs[] =
    "in vec4 v_color;\n"
    "out vec4 o_color;\n"
    "void main() { o_color = v_color; }\n";

static const char text_vs[] =
    "layout(location = 0) in vec2 a_pos;\n"
    "uniform mat4 u_proj;\n"
    "void main() { gl_Position = u_proj * vec4(a_pos, 0.0, 1.0); }\n";
static const char text_fs[] =
    "uniform vec4 u_color;\n"
    "out vec4 o_color;\n"
    "void main() { o_color = u_color; }\n";

static GLuint compile(GLenum type, const char *const *parts, int nparts, char *err, size_t errlen)
{
    const char *src[4] = {"#version 330 core\n"};
    for (int i = 0; i < nparts && i < 3; i++) src[i + 1] = parts[i];
    GLuint sh = glCreateShader(type);
    glShaderSource(sh, nparts + 1, src, NULL);
    glCompileShader(sh);
    GLint ok = 0;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = "";
        glGetShaderInfoLog(sh, sizeof log, NULL, log);
        snprintf(err, errlen, "viewer: shader does not compile: %s", log);
        glDeleteShader(sh);
        return 0;
    }
    return sh;
}

static GLuint program(const char *const *vs, int nvs, const char *fs, char *err, size_t errlen)
{
    GLuint v = compile(GL_VERTEX_SHADER, vs, nvs, err, errlen);
    if (!v) return 0;
    GLuint f = compile(GL_FRAGMENT_SHADER, &fs, 1, err, errlen);
    if (!f) {
        glDeleteShader(v);
        return 0;
    }
    GLuint p = glCreateProgram();
    glAttachShader(p, v);
    glAttachShader(p, f);
    glLinkProgram(p);
    glDeleteShader(v);
    glDeleteShader(f);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024] = "";
        glGetProgramInfoLog(p, sizeof log, NULL, log);
        snprintf(err, errlen, "viewer: program does not link: %s", log);
        glDeleteProgram(p);
        return 0;
    }
    return p;
}

/* ---- setup ------------------------------------------------------------------------------ */

static void make_sphere(fp_render *r)
{
    enum { SLICES = 20, STACKS = 12 };
    float v[(SLICES + 1) * (STACKS + 1) * 3];
    GLushort idx[SLICES * STACKS * 6];
    size_t nv = 0, ni = 0;
    for (int i = 0; i <= STACKS; i++) {
        double th = M_PI * i / STACKS;
        for (int j = 0; j <= SLICES; j++) {
            double ph = 2 * M_PI * j / SLICES;
            v[nv++] = (float)(sin(th) * cos(ph));
            v[nv++] = (float)cos(th);
            v[nv++] = (float)(sin(th) * sin(ph));
        }
    }
    for (int i = 0; i < STACKS; i++)
        for (int j = 0; j < SLICES; j++) {
            GLushort a = (GLushort)(i * (SLICES + 1) + j), b = (GLushort)(a + SLICES + 1);
            idx[ni++] = a; idx[ni++] = b; idx[ni++] = (GLushort)(a + 1);
            idx[ni++] = (GLushort)(a + 1); idx[ni++] = b; idx[ni++] = (GLushort)(b + 1);
        }
    glGenVertexArrays(1, &r->vao_sphere);
    glBindVertexArray(r->vao_sphere);
    glGenBuffers(1, &r->vbo_sphere);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_sphere);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)sizeof v, v, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glEnableVertexAttribArray(1); /* a unit sphere's normal is its position */
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glGenBuffers(1, &r->ebo_sphere);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, r->ebo_sphere);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)sizeof idx, idx, GL_STATIC_DRAW);
    r->sphere_indices = (GLsizei)ni;
    glBindVertexArray(0);
}

int fp_render_init(fp_render *r, char *err, size_t errlen)
{
    memset(r, 0, sizeof *r);
    const char *mvs[] = {fp_warp_glsl, mesh_vs};
    const char *lvs[] = {lines_vs}, *tvs[] = {text_vs};
    r->prog_mesh = program(mvs, 2, mesh_fs, err, errlen);
    if (r->prog_mesh) r->prog_lines = program(lvs, 1, lines_fs, err, errlen);
    if (r->prog_lines) r->prog_text = program(tvs, 1, text_fs, err, errlen);
    if (!r->prog_text) {
        fp_render_free(r);
        return -ENODEV;
    }
    make_sphere(r);
    glGenVertexArrays(1, &r->vao_lines);
    glBindVertexArray(r->vao_lines);
    glGenBuffers(1, &r->vbo_lines);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_lines);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 7 * sizeof(float), NULL);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, 7 * sizeof(float), (void *)(3 * sizeof(float)));
    glGenVertexArrays(1, &r->vao_text);
    glBindVertexArray(r->vao_text);
    glGenBuffers(1, &r->vbo_text);
    glGenBuffers(1, &r->ebo_text);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_text);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 16, NULL); /* stb_easy_font: x y z rgba */
    glBindVertexArray(0);
    glEnable(GL_PROGRAM_POINT_SIZE);
    return 0;
}

void fp_render_free(fp_render *r)
{
    glDeleteProgram(r->prog_mesh);
    glDeleteProgram(r->prog_lines);
    glDeleteProgram(r->prog_text);
    GLuint bufs[] = {r->vbo_shape_pos, r->vbo_shape_nrm, r->vbo_base_pos, r->vbo_base_nrm,
                     r->ebo_tris, r->vbo_sphere, r->ebo_sphere, r->vbo_lines, r->vbo_text,
                     r->ebo_text, r->vbo_shape_col, r->vbo_shape_mob};
    glDeleteBuffers(sizeof bufs / sizeof bufs[0], bufs);
    GLuint vaos[] = {r->vao_shape, r->vao_base, r->vao_sphere, r->vao_lines, r->vao_text};
    glDeleteVertexArrays(sizeof vaos / sizeof vaos[0], vaos);
    memset(r, 0, sizeof *r);
}

static void face_vao(GLuint *vao, GLuint *pos, GLuint *nrm, GLuint ebo, size_t n)
{
    if (!*vao) {
        glGenVertexArrays(1, vao);
        glGenBuffers(1, pos);
        glGenBuffers(1, nrm);
    }
    glBindVertexArray(*vao);
    glBindBuffer(GL_ARRAY_BUFFER, *pos);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(n * 3 * sizeof(float)), NULL, GL_DYNAMIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glBindBuffer(GL_ARRAY_BUFFER, *nrm);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(n * 3 * sizeof(float)), NULL, GL_DYNAMIC_DRAW);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
    glBindVertexArray(0);
}

int fp_render_set_topology(fp_render *r, size_t n, const uint32_t *tris, size_t t)
{
    if (!r->ebo_tris) glGenBuffers(1, &r->ebo_tris);
    glBindVertexArray(0);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, r->ebo_tris);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(t * 3 * sizeof(uint32_t)), tris, GL_STATIC_DRAW);
    face_vao(&r->vao_shape, &r->vbo_shape_pos, &r->vbo_shape_nrm, r->ebo_tris, n);
    face_vao(&r->vao_base, &r->vbo_base_pos, &r->vbo_base_nrm, r->ebo_tris, n);
    r->vertex_count = n;
    r->index_count = t * 3;
    r->shape_colors = false; /* colours were for the old vertices */
    r->shape_mobility = false;
    return glGetError() == GL_OUT_OF_MEMORY ? -ENOMEM : 0;
}

void fp_render_upload(fp_render *r, bool base, const float *pos, const float *nrm)
{
    GLsizeiptr bytes = (GLsizeiptr)(r->vertex_count * 3 * sizeof(float));
    glBindBuffer(GL_ARRAY_BUFFER, base ? r->vbo_base_pos : r->vbo_shape_pos);
    glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, pos);
    glBindBuffer(GL_ARRAY_BUFFER, base ? r->vbo_base_nrm : r->vbo_shape_nrm);
    glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, nrm);
}

int fp_render_set_colors(fp_render *r, const float *rgb)
{
    r->shape_colors = false;
    if (!rgb || !r->vao_shape) return 0;
    if (!r->vbo_shape_col) glGenBuffers(1, &r->vbo_shape_col);
    glBindVertexArray(r->vao_shape);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_shape_col);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(r->vertex_count * 3 * sizeof(float)), rgb, GL_STATIC_DRAW);
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glBindVertexArray(0);
    if (glGetError() == GL_OUT_OF_MEMORY) return -ENOMEM;
    r->shape_colors = true;
    return 0;
}

int fp_render_set_mobility(fp_render *r, const float *m)
{
    r->shape_mobility = false;
    if (!m || !r->vao_shape) return 0;
    if (!r->vbo_shape_mob) glGenBuffers(1, &r->vbo_shape_mob);
    glBindVertexArray(r->vao_shape);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_shape_mob);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(r->vertex_count * sizeof(float)), m, GL_STATIC_DRAW);
    glEnableVertexAttribArray(3);
    glVertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, 0, NULL);
    glBindVertexArray(0);
    if (glGetError() == GL_OUT_OF_MEMORY) return -ENOMEM;
    r->shape_mobility = true;
    return 0;
}

void fp_render_upload_ranges(fp_render *r, bool base, const float *pos, const float *nrm,
                             const uint32_t *ranges, size_t count)
{
    const float *src[2] = {pos, nrm};
    GLuint buf[2] = {base ? r->vbo_base_pos : r->vbo_shape_pos, base ? r->vbo_base_nrm : r->vbo_shape_nrm};
    for (int b = 0; b < 2; b++) {
        glBindBuffer(GL_ARRAY_BUFFER, buf[b]);
        for (size_t k = 0; k < count; k++) {
            size_t first = ranges[2 * k], n = ranges[2 * k + 1];
            if (first >= r->vertex_count) break;
            if (n > r->vertex_count - first) n = r->vertex_count - first;
            glBufferSubData(GL_ARRAY_BUFFER, (GLintptr)(first * 3 * sizeof(float)),
                            (GLsizeiptr)(n * 3 * sizeof(float)), src[b] + 3 * first);
        }
    }
}

/* ---- drawing ---------------------------------------------------------------------------- */

static void begin_blend(bool translucent)
{
    if (translucent) {
        glEnable(GL_BLEND);
        glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
        glDepthMask(GL_FALSE);
    } else {
        glDisable(GL_BLEND);
        glDepthMask(GL_TRUE);
    }
}

void fp_render_mesh(fp_render *r, const float mvp[16], const float view[16], bool base,
                    const fp_warp_coeffs *warp, const float color[4], bool wireframe)
{
    if (!r->index_count) return;
    glUseProgram(r->prog_mesh);
    glUniformMatrix4fv(glGetUniformLocation(r->prog_mesh, "u_mvp"), 1, GL_FALSE, mvp);
    glUniformMatrix4fv(glGetUniformLocation(r->prog_mesh, "u_view"), 1, GL_FALSE, view);
    glUniform1i(glGetUniformLocation(r->prog_mesh, "u_warp_on"), warp != NULL);
    glUniform1i(glGetUniformLocation(r->prog_mesh, "u_mob_on"), warp && !base && r->shape_mobility);
    if (warp) fp_warp_set_uniforms(r->prog_mesh, warp);
    glUniform4fv(glGetUniformLocation(r->prog_mesh, "u_color"), 1, color);
    glUniform1i(glGetUniformLocation(r->prog_mesh, "u_flat"), 0);
    glUniform1i(glGetUniformLocation(r->prog_mesh, "u_vcolor"), !base && r->shape_colors);
    glBindVertexArray(base ? r->vao_base : r->vao_shape);
    bool translucent = color[3] < 1.f;
    begin_blend(translucent);
    glEnable(GL_DEPTH_TEST);
    if (wireframe || translucent) {
        /* behind the lines; a ghost behind the face where they coincide (no z-fighting) */
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset(translucent ? 2.f : 1.f, translucent ? 8.f : 1.f);
    }
    glDrawElements(GL_TRIANGLES, (GLsizei)r->index_count, GL_UNSIGNED_INT, NULL);
    glDisable(GL_POLYGON_OFFSET_FILL);
    if (wireframe && !translucent) {
        const float line[4] = {0.15f, 0.12f, 0.1f, 1.f};
        glUniform4fv(glGetUniformLocation(r->prog_mesh, "u_color"), 1, line);
        glUniform1i(glGetUniformLocation(r->prog_mesh, "u_flat"), 1);
        glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
        glDrawElements(GL_TRIANGLES, (GLsizei)r->index_count, GL_UNSIGNED_INT, NULL);
        glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    }
    begin_blend(false);
    glBindVertexArray(0);
}

void fp_render_spheres(fp_render *r, const float proj_view[16], const float view[16],
                       const float *centres, size_t n, float radius, const float color[4])
{
    if (!n) return;
    glUseProgram(r->prog_mesh);
    glUniform1i(glGetUniformLocation(r->prog_mesh, "u_warp_on"), 0);
    glUniform1i(glGetUniformLocation(r->prog_mesh, "u_flat"), 0);
    glUniform1i(glGetUniformLocation(r->prog_mesh, "u_vcolor"), 0);
    glUniform4fv(glGetUniformLocation(r->prog_mesh, "u_color"), 1, color);
    GLint lmvp = glGetUniformLocation(r->prog_mesh, "u_mvp");
    GLint lview = glGetUniformLocation(r->prog_mesh, "u_view");
    glBindVertexArray(r->vao_sphere);
    begin_blend(true);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_CULL_FACE); /* front faces only: each sphere blends once */
    for (size_t i = 0; i < n; i++) {
        float model[16], mv[16], mvp[16];
        m4_identity(model);
        model[0] = model[5] = model[10] = radius;
        model[12] = centres[3 * i];
        model[13] = centres[3 * i + 1];
        model[14] = centres[3 * i + 2];
        m4_mul(view, model, mv);
        m4_mul(proj_view, model, mvp);
        glUniformMatrix4fv(lmvp, 1, GL_FALSE, mvp);
        glUniformMatrix4fv(lview, 1, GL_FALSE, mv);
        glDrawElements(GL_TRIANGLES, r->sphere_indices, GL_UNSIGNED_SHORT, NULL);
    }
    glDisable(GL_CULL_FACE);
    begin_blend(false);
    glBindVertexArray(0);
}

void fp_render_lines(fp_render *r, const float mvp[16], const float *verts, size_t n,
                     GLenum mode, float point_size, bool depth)
{
    if (!n) return;
    glUseProgram(r->prog_lines);
    glUniformMatrix4fv(glGetUniformLocation(r->prog_lines, "u_mvp"), 1, GL_FALSE, mvp);
    glUniform1f(glGetUniformLocation(r->prog_lines, "u_point_size"), point_size);
    glBindVertexArray(r->vao_lines);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_lines);
    size_t bytes = n * 7 * sizeof(float);
    if (bytes > r->lines_cap) {
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)bytes, NULL, GL_STREAM_DRAW);
        r->lines_cap = bytes;
    }
    glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)bytes, verts);
    if (depth) glEnable(GL_DEPTH_TEST);
    else glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDrawArrays(mode, 0, (GLsizei)n);
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
    glBindVertexArray(0);
}
/* The text program's state for a 2D overlay in pixels (origin top left) of a fbw x fbh
 * framebuffer, drawn in color over the scene with alpha blending; overlay_end restores the
 * scene's (depth test on, no blending, no vertex array bound). [the GL thread] */
static void overlay_begin(fp_render *r, int fbw, int fbh, const float color[4])
{
    float proj[16];
    m4_ortho(proj, 0, (float)fbw, (float)fbh, 0);
    glUseProgram(r->prog_text);
    glUniformMatrix4fv(glGetUniformLocation(r->prog_text, "u_proj"), 1, GL_FALSE, proj);
    glUniform4fv(glGetUniformLocation(r->prog_text, "u_color"), 1, color);
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
}

static void overlay_end(void)
{
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
    glBindVertexArray(0);
}


float fp_render_text(fp_render *r, int fbw, int fbh, float x, float y, float scale,
                     const char *text, const float color[4])
{
    /* stb_easy_font: about 270 bytes per character of quads at most; 4 vertices per quad. */
    size_t len = strlen(text);
    size_t cap = len * 270 + 64;
    char *buf = malloc(cap);
    if (!buf) return 0;
    int quads = stb_easy_font_print(0, 0, (char *)text, NULL, buf, (int)cap);
    float *v = (float *)buf;
    for (int i = 0; i < quads * 4; i++) {
        v[i * 4] = x + v[i * 4] * scale;
        v[i * 4 + 1] = y + v[i * 4 + 1] * scale;
    }
    glBindVertexArray(r->vao_text);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_text);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)((size_t)quads * 4 * 16), buf, GL_STREAM_DRAW);
    if ((size_t)quads > r->text_quads_cap) {
        GLuint *idx = malloc((size_t)quads * 6 * sizeof *idx);
        if (idx) {
            for (GLuint q = 0; q < (GLuint)quads; q++) {
                GLuint b = 4 * q, *o = idx + 6 * q;
                o[0] = b; o[1] = b + 1; o[2] = b + 2; o[3] = b; o[4] = b + 2; o[5] = b + 3;
            }
            glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, r->ebo_text);
            glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)((size_t)quads * 6 * sizeof *idx), idx,
                         GL_STATIC_DRAW);
            r->text_quads_cap = (size_t)quads;
            free(idx);
        }
    } else {
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, r->ebo_text);
    }
    overlay_begin(r, fbw, fbh, color);
    if ((size_t)quads <= r->text_quads_cap)
        glDrawElements(GL_TRIANGLES, quads * 6, GL_UNSIGNED_INT, NULL);
    overlay_end();
    free(buf);
    return (float)stb_easy_font_height((char *)text) * scale;
}

float fp_render_text_width(const char *text, float scale)
{
    return (float)stb_easy_font_width((char *)text) * scale;
}

float fp_render_text_height(const char *text, float scale)
{
    return (float)stb_easy_font_height((char *)text) * scale;
}

void fp_render_rect(fp_render *r, int fbw, int fbh, float x, float y, float w, float h,
                    const float color[4])
{
    /* The text program's layout (x y z + 4 colour bytes, 16 bytes a vertex), one fan. */
    float v[16] = {x, y, 0, 0, x + w, y, 0, 0, x + w, y + h, 0, 0, x, y + h, 0, 0};
    glBindVertexArray(r->vao_text);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_text);
    glBufferData(GL_ARRAY_BUFFER, sizeof v, v, GL_STREAM_DRAW);
    overlay_begin(r, fbw, fbh, color);
    glDrawArrays(GL_TRIANGLE_FAN, 0, 4);
    overlay_end();
}

int fp_render_rects(fp_render *r, int fbw, int fbh, const float *xywh, size_t n,
                    const float color[4])
{
    if (!n) return 0;
    /* two triangles a rectangle, the text program's layout (x y z + 4 colour bytes) */
    float *v = malloc(n * 6 * 4 * sizeof *v);
    if (!v) return -ENOMEM;
    for (size_t i = 0; i < n; i++) {
        const float x = xywh[4 * i], y = xywh[4 * i + 1], w = xywh[4 * i + 2], h = xywh[4 * i + 3];
        const float c[6][2] = {{x, y}, {x + w, y}, {x + w, y + h}, {x, y}, {x + w, y + h}, {x, y + h}};
        for (int k = 0; k < 6; k++) {
            float *o = v + (i * 6 + (size_t)k) * 4;
            o[0] = c[k][0], o[1] = c[k][1], o[2] = 0, o[3] = 0;
        }
    }
    glBindVertexArray(r->vao_text);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_text);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(n * 6 * 4 * sizeof *v), v, GL_STREAM_DRAW);
    free(v);
    overlay_begin(r, fbw, fbh, color);
    glDrawArrays(GL_TRIANGLES, 0, (GLsizei)(n * 6));
    overlay_end();
    return 0;
}
