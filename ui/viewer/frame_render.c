/* fp_frame_render: headless PNG frames of a mesh (fp_frame_render.h). */
#define _GNU_SOURCE
#include "fp_frame_render.h"
#include "render.h"
#include "vmath.h"
#include "fp_error.h"
#include "png_file.h"

#include <GLFW/glfw3.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct fp_frame_renderer {
    const fp_mesh *mesh;
    GLFWwindow *win;
    fp_render r;
    bool render_ok;
    GLuint fbo, color, depth;
    int w, h;
    float view[16], proj[16];
    float *nrm;
    unsigned char *px;
};

int fp_frame_renderer_open(const fp_mesh *mesh, const fp_frame_render_options *opt,
                           fp_frame_renderer **out, char *err, size_t errlen)
{
    *out = NULL;
    if (!mesh || !opt || mesh->vertex_count == 0)
        return fp_errorf(err, errlen, -EINVAL, "png: no mesh");
    int w = opt->width > 0 ? opt->width : 1280, h = opt->height > 0 ? opt->height : 720;
    if (w > 8192 || h > 8192)
        return fp_errorf(err, errlen, -EINVAL, "png: size %dx%d beyond 8192x8192", w, h);
    fp_frame_renderer *f = calloc(1, sizeof *f);
    if (!f)
        return fp_errorf(err, errlen, -ENOMEM, "png: out of memory");
    f->mesh = mesh;
    f->w = w;
    f->h = h;
    f->nrm = malloc(mesh->vertex_count * 3 * sizeof(float));
    f->px = malloc((size_t)w * (size_t)h * 3);
    int rc = 0;
    if (!f->nrm || !f->px) {
        rc = fp_errorf(err, errlen, -ENOMEM, "png: out of memory");
        goto fail;
    }
    if (!glfwInit()) {
        rc = fp_errorf(err, errlen, -ENODEV,
                       "png: no display: GLFW cannot initialise (is DISPLAY set? try xvfb-run)");
        goto fail;
    }
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    f->win = glfwCreateWindow(64, 64, "facepuppet export", NULL, NULL);
    if (!f->win) {
        rc = fp_errorf(err, errlen, -ENODEV, "png: cannot open an OpenGL 3.3 core context");
        goto fail;
    }
    glfwMakeContextCurrent(f->win);
    if ((rc = fp_render_init(&f->r, err, errlen)))
        goto fail;
    f->render_ok = true;
    if ((rc = fp_render_set_topology(&f->r, mesh->vertex_count, mesh->triangles,
                                     mesh->triangle_count))) {
        fp_errorf(err, errlen, rc, "png: cannot upload the mesh");
        goto fail;
    }
    glGenFramebuffers(1, &f->fbo);
    glGenRenderbuffers(1, &f->color);
    glGenRenderbuffers(1, &f->depth);
    glBindRenderbuffer(GL_RENDERBUFFER, f->color);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glBindRenderbuffer(GL_RENDERBUFFER, f->depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, f->fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, f->color);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, f->depth);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        rc = fp_errorf(err, errlen, -ENODEV, "png: the offscreen framebuffer is incomplete");
        goto fail;
    }
    /* the camera: the viewer's framing of the loaded shape, turned and zoomed */
    float d[3], target[3];
    face_axes ax;
    bool given = v3_dot(opt->up, opt->up) > 0.5f && v3_dot(opt->forward, opt->forward) > 0.5f;
    face_axes_set(&ax, given ? opt->up : NULL, given ? opt->forward : NULL);
    face_axes_frame(&ax, mesh->positions, mesh->vertex_count, target, d);
    const float fovy = 35.f * (float)M_PI / 180.f, aspect = (float)w / (float)h;
    const float half = 0.5f * fmaxf(d[1], d[0] / aspect) * 1.15f;
    const float zoom = opt->zoom > 0 ? (float)opt->zoom : 1.f;
    const float dist = (half / tanf(fovy / 2) + 0.5f * d[2]) / zoom;
    const float size = v3_len(d) > 0 ? v3_len(d) : 1.f;
    const float yaw = (float)(opt->yaw_deg * M_PI / 180), pitch = (float)(opt->pitch_deg * M_PI / 180);
    float eye[3];
    face_axes_eye(&ax, target, dist, yaw, pitch, eye);
    m4_look_at(f->view, eye, target, ax.y);
    m4_perspective(f->proj, fovy, aspect, fmaxf(dist - 2 * size, dist * 0.02f), dist + 2 * size);
    *out = f;
    return 0;
fail:
    fp_frame_renderer_close(&f);
    return rc;
}

int fp_frame_renderer_png(fp_frame_renderer *f, const float *positions, const char *path,
                          char *err, size_t errlen)
{
    const fp_mesh *m = f->mesh;
    fp_mesh_normals(m->triangles, m->triangle_count, positions, m->vertex_count, f->nrm);
    glfwMakeContextCurrent(f->win);
    fp_render_upload(&f->r, false, positions, f->nrm);
    glBindFramebuffer(GL_FRAMEBUFFER, f->fbo);
    glViewport(0, 0, f->w, f->h);
    glClearColor(0.11f, 0.12f, 0.15f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    float pv[16];
    m4_mul(f->proj, f->view, pv);
    static const float skin[4] = {0.86f, 0.7f, 0.6f, 1.f};
    fp_render_mesh(&f->r, pv, f->view, false, NULL, skin, false);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, f->w, f->h, GL_RGB, GL_UNSIGNED_BYTE, f->px);
    /* GL's rows go bottom-up */
    int rc = fp_png_write(path, f->w, f->h, f->px, 1, err, errlen);
    if (rc < 0) return rc;
    return 0;
}

void fp_frame_renderer_close(fp_frame_renderer **fp)
{
    if (!fp || !*fp)
        return;
    fp_frame_renderer *f = *fp;
    if (f->win) {
        glfwMakeContextCurrent(f->win);
        if (f->fbo) glDeleteFramebuffers(1, &f->fbo);
        if (f->color) glDeleteRenderbuffers(1, &f->color);
        if (f->depth) glDeleteRenderbuffers(1, &f->depth);
        if (f->render_ok) fp_render_free(&f->r);
        glfwDestroyWindow(f->win);
    }
    glfwTerminate();
    free(f->nrm);
    free(f->px);
    free(f);
    *fp = NULL;
}
