/* The CSRBF warp on the GPU: coefficients (from the engine), GLSL, transform-feedback read-back. */
#include "fp_gpuwarp.h"

#include "csrbf.h"

#include <epoxy/gl.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int fp_warp_from_solver(const csrbf_solver *solver, double radius, fp_warp_coeffs *out)
{
    memset(out, 0, sizeof *out);
    if (!(radius > 0) || !isfinite(radius)) return -EINVAL;
    out->radius = (float)radius;
    if (!solver) return 0;
    size_t m = csrbf_solver_centres(solver);
    if (m > FP_WARP_MAX_CENTRES) return -E2BIG;
    double c[FP_WARP_MAX_CENTRES * 3], a[FP_WARP_MAX_CENTRES * 3], poly[12];
    if (csrbf_solver_get_coefficients(solver, c, a, poly) < 0) return -EINVAL;
    for (int i = 0; i < 12; i++)
        if (poly[i] != 0) return -ENOTSUP;
    for (size_t i = 0; i < m; i++)
        for (int k = 0; k < 3; k++) {
            out->centre[i][k] = (float)c[3 * i + k];
            out->alpha[i][k] = (float)a[3 * i + k];
        }
    out->count = m;
    return 0;
}

/* psi31(r) = (1-r)^4 (4r+1); its gradient in x is -20 (1-r)^3 (x - c) / R^2. */
const char fp_warp_glsl[] =
    "uniform int u_warp_count;\n"
    "uniform float u_warp_inv_r;\n"
    "uniform vec3 u_warp_centre[64];\n"
    "uniform vec3 u_warp_alpha[64];\n"
    "vec3 fp_warp(vec3 x, out mat3 jac) {\n"
    "    vec3 y = x;\n"
    "    jac = mat3(1.0);\n"
    "    for (int i = 0; i < u_warp_count; i++) {\n"
    "        vec3 d = (x - u_warp_centre[i]) * u_warp_inv_r;\n"
    "        float r = length(d);\n"
    "        if (r < 1.0) {\n"
    "            float t = 1.0 - r;\n"
    "            float t3 = t * t * t;\n"
    "            y += u_warp_alpha[i] * (t3 * t * (4.0 * r + 1.0));\n"
    "            jac += outerProduct(u_warp_alpha[i], d * (-20.0 * t3 * u_warp_inv_r));\n"
    "        }\n"
    "    }\n"
    "    return y;\n"
    "}\n";

void fp_warp_set_uniforms(unsigned program, const fp_warp_coeffs *c)
{
    GLint n = glGetUniformLocation(program, "u_warp_count");
    glUniform1i(n, (GLint)c->count);
    glUniform1f(glGetUniformLocation(program, "u_warp_inv_r"), c->radius > 0 ? 1.f / c->radius : 0.f);
    if (c->count) {
        glUniform3fv(glGetUniformLocation(program, "u_warp_centre"), (GLsizei)c->count, &c->centre[0][0]);
        glUniform3fv(glGetUniformLocation(program, "u_warp_alpha"), (GLsizei)c->count, &c->alpha[0][0]);
    }
}

struct fp_gpuwarp {
    GLuint program, vao, vbo_in, vbo_out;
    size_t cap;
};

static const char feedback_vs_body[] =
    "layout(location = 0) in vec3 a_pos;\n"
    "out vec3 v_out;\n"
    "void main() { mat3 j; v_out = fp_warp(a_pos, j); }\n";

int fp_gpuwarp_create(fp_gpuwarp **out, char *err, size_t errlen)
{
    *out = NULL;
    fp_gpuwarp *w = calloc(1, sizeof *w);
    if (!w) return -ENOMEM;
    const char *src[3] = {"#version 330 core\n", fp_warp_glsl, feedback_vs_body};
    GLuint vs = glCreateShader(GL_VERTEX_SHADER);
    glShaderSource(vs, 3, src, NULL);
    glCompileShader(vs);
    GLint ok = 0;
    glGetShaderiv(vs, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = "";
        glGetShaderInfoLog(vs, sizeof log, NULL, log);
        snprintf(err, errlen, "gpu-warp: feedback shader: %s", log);
        glDeleteShader(vs);
        free(w);
        return -ENODEV;
    }
    w->program = glCreateProgram();
    glAttachShader(w->program, vs);
    const char *varyings[] = {"v_out"};
    glTransformFeedbackVaryings(w->program, 1, varyings, GL_INTERLEAVED_ATTRIBS);
    glLinkProgram(w->program);
    glDeleteShader(vs);
    glGetProgramiv(w->program, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024] = "";
        glGetProgramInfoLog(w->program, sizeof log, NULL, log);
        snprintf(err, errlen, "gpu-warp: feedback program: %s", log);
        glDeleteProgram(w->program);
        free(w);
        return -ENODEV;
    }
    glGenVertexArrays(1, &w->vao);
    glGenBuffers(1, &w->vbo_in);
    glGenBuffers(1, &w->vbo_out);
    *out = w;
    return 0;
}

int fp_gpuwarp_eval(fp_gpuwarp *w, const fp_warp_coeffs *c, size_t n, const float *base,
                    float *out)
{
    while (glGetError() != GL_NO_ERROR) {}
    size_t bytes = n * 3 * sizeof(float);
    glBindVertexArray(w->vao);
    glBindBuffer(GL_ARRAY_BUFFER, w->vbo_in);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)bytes, base, GL_STREAM_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, w->vbo_out);
    if (w->cap < bytes) {
        glBufferData(GL_TRANSFORM_FEEDBACK_BUFFER, (GLsizeiptr)bytes, NULL, GL_STREAM_READ);
        w->cap = bytes;
    }
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, w->vbo_out);
    glUseProgram(w->program);
    fp_warp_set_uniforms(w->program, c);
    glEnable(GL_RASTERIZER_DISCARD);
    glBeginTransformFeedback(GL_POINTS);
    glDrawArrays(GL_POINTS, 0, (GLsizei)n);
    glEndTransformFeedback();
    glDisable(GL_RASTERIZER_DISCARD);
    glGetBufferSubData(GL_TRANSFORM_FEEDBACK_BUFFER, 0, (GLsizeiptr)bytes, out);
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0);
    glBindVertexArray(0);
    glUseProgram(0);
    return glGetError() == GL_NO_ERROR ? 0 : -EIO;
}

void fp_gpuwarp_destroy(fp_gpuwarp **wp)
{
    fp_gpuwarp *w = *wp;
    if (!w) return;
    glDeleteProgram(w->program);
    glDeleteBuffers(1, &w->vbo_in);
    glDeleteBuffers(1, &w->vbo_out);
    glDeleteVertexArrays(1, &w->vao);
    free(w);
    *wp = NULL;
}
