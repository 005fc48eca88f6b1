/* The GPU warp (ui/viewer/gpuwarp.c) against the CPU engine (core/csrbf) on the ICT face: the
 * vertex shader's T(x), read back by transform feedback, agrees with csrbf_evaluate to 1e-4
 * of the largest displacement; the identity leaves the base bit for bit; coincident start
 * points merge as the engine merges them; bad input is refused. Also the viewer's script
 * parser and percentiles. Needs a display (ctest runs it under xvfb-run, Mesa llvmpipe). */
#define _GNU_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "csrbf.h"
#include "fp_gpuwarp.h"
#include "fp_mesh.h"
#include "fp_viewer.h"
#include "script.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <epoxy/gl.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static GLFWwindow *win;
static fp_mesh *face;
static fp_gpuwarp *gw;

/* CPU (engine) and GPU results for n control vectors; returns max |GPU - CPU| and sets *disp
 * to the largest CPU displacement. */
static double compare(size_t n, const float *start, const float *end, double radius, double *disp)
{
    size_t nv = face->vertex_count;
    float *cpu = malloc(nv * 3 * sizeof *cpu), *gpu = malloc(nv * 3 * sizeof *gpu);
    assert_non_null(cpu);
    assert_non_null(gpu);
    csrbf_options o = {0};
    o.radius = radius;
    csrbf_solver *s = NULL;
    csrbf_points *p = NULL;
    assert_true(csrbf_solver_create(&o, &s) >= 0);
    assert_true(csrbf_points_create(nv, face->positions, &p) >= 0);
    assert_true(csrbf_solver_solve(s, n, start, end) >= 0);
    assert_true(csrbf_evaluate(s, p, cpu, 0, NULL) >= 0);
    fp_warp_coeffs c;
    assert_int_equal(fp_warp_from_solver(s, radius, &c), 0);
    assert_int_equal(c.count, csrbf_solver_centres(s));
    assert_int_equal(fp_gpuwarp_eval(gw, &c, nv, face->positions, gpu), 0);
    double err = 0;
    *disp = 0;
    for (size_t i = 0; i < nv; i++) {
        double e = 0, d = 0;
        for (int k = 0; k < 3; k++) {
            double a = (double)gpu[3 * i + k] - cpu[3 * i + k];
            double b = (double)cpu[3 * i + k] - face->positions[3 * i + k];
            e += a * a;
            d += b * b;
        }
        err = fmax(err, sqrt(e));
        *disp = fmax(*disp, sqrt(d));
    }
    csrbf_solver_destroy(&s);
    csrbf_points_destroy(&p);
    free(cpu);
    free(gpu);
    return err;
}

/* n start points on face vertices spread over the mesh, ends moved by `len` x R in varied
 * directions. */
static void controls(size_t n, double radius, double len, float *start, float *end)
{
    size_t nv = face->vertex_count;
    for (size_t i = 0; i < n; i++) {
        size_t v = (i * 7919 + 13) % nv;
        double th = 2.399963 * (double)i, z = 1 - 2 * ((double)i + 0.5) / (double)n;
        double dir[3] = {sqrt(1 - z * z) * cos(th), sqrt(1 - z * z) * sin(th), z};
        for (int k = 0; k < 3; k++) {
            start[3 * i + k] = face->positions[3 * v + k];
            end[3 * i + k] = (float)(start[3 * i + k] + len * radius * dir[k]);
        }
    }
}

static void test_gpu_matches_engine(void **state)
{
    (void)state;
    const double radius = 2.85; /* the session's default for the ICT face */
    for (size_t n = 1; n <= 64; n *= 4) {
        float start[64 * 3], end[64 * 3];
        controls(n, radius, 0.3, start, end);
        double disp, err = compare(n, start, end, radius, &disp);
        print_message("%2zu centres: max |GPU - CPU| %.3g, max displacement %.4g, ratio %.3g\n", n, err,
                      disp, err / disp);
        assert_true(disp > 0.1 * radius);
        assert_true(err <= 1e-4 * disp);
    }
}

static void test_merged_start_points(void **state)
{
    (void)state;
    /* Points 0 and 1 coincide: one centre whose displacement is their mean. */
    float start[3 * 3], end[3 * 3];
    controls(3, 2.85, 0.25, start, end);
    memcpy(start + 3, start, 3 * sizeof *start);
    double disp, err = compare(3, start, end, 2.85, &disp);
    assert_true(disp > 0);
    assert_true(err <= 1e-4 * disp);
}

static void test_identity_is_exact(void **state)
{
    (void)state;
    fp_warp_coeffs c;
    assert_int_equal(fp_warp_from_solver(NULL, 1.0, &c), 0);
    assert_int_equal(c.count, 0);
    size_t nv = face->vertex_count;
    float *gpu = malloc(nv * 3 * sizeof *gpu);
    assert_non_null(gpu);
    assert_int_equal(fp_gpuwarp_eval(gw, &c, nv, face->positions, gpu), 0);
    assert_memory_equal(gpu, face->positions, nv * 3 * sizeof *gpu);
    free(gpu);
}

static void test_solve_refuses_bad_input(void **state)
{
    (void)state;
    float st[65 * 3], en[65 * 3];
    for (int i = 0; i < 65; i++)
        for (int k = 0; k < 3; k++) st[3 * i + k] = en[3 * i + k] = (float)(i * (k + 1)) * 0.1f;
    fp_warp_coeffs c;
    csrbf_options o = {0};
    o.radius = 1.0;
    csrbf_solver *s = NULL;
    assert_true(csrbf_solver_create(&o, &s) >= 0);
    /* no start points yet; bad radii */
    assert_int_equal(fp_warp_from_solver(s, 1.0, &c), -EINVAL);
    assert_true(csrbf_solver_solve(s, 1, st, en) >= 0);
    assert_int_equal(fp_warp_from_solver(s, 0.0, &c), -EINVAL);
    assert_int_equal(fp_warp_from_solver(s, INFINITY, &c), -EINVAL);
    assert_int_equal(fp_warp_from_solver(s, 1.0, &c), 0);
    assert_int_equal(c.count, 1);
    /* 65 distinct centres: more than the shader's uniforms hold */
    assert_true(csrbf_solver_solve(s, 65, st, en) >= 0);
    assert_int_equal(csrbf_solver_centres(s), 65);
    assert_int_equal(fp_warp_from_solver(s, 1.0, &c), -E2BIG);
    assert_int_equal(c.count, 0);
    csrbf_solver_destroy(&s);
    /* a polynomial part, which the shader lacks */
    o.poly = CSRBF_POLY_LINEAR;
    assert_true(csrbf_solver_create(&o, &s) >= 0);
    for (int i = 0; i < 3 * 6; i++) en[i] += 0.05f;
    assert_true(csrbf_solver_solve(s, 6, st, en) >= 0);
    assert_int_equal(fp_warp_from_solver(s, 1.0, &c), -ENOTSUP);
    assert_int_equal(c.count, 0);
    csrbf_solver_destroy(&s);
}

static void test_script_parse(void **state)
{
    (void)state;
    fp_script s;
    char err[256];
    assert_int_equal(fp_script_parse("wait hands; key E\nwait frames 3; shot /tmp/a b.png ;radius 2.5;"
                                     " drop x.obj; key Esc; key [; key ?; close", &s, err, sizeof err), 0);
    assert_int_equal(s.count, 10);
    assert_int_equal(s.cmds[0].op, FP_SCRIPT_WAIT_HANDS);
    assert_int_equal(s.cmds[1].key, GLFW_KEY_E);
    assert_int_equal(s.cmds[2].op, FP_SCRIPT_WAIT_FRAMES);
    assert_true(s.cmds[2].number == 3);
    assert_string_equal(s.cmds[3].text, "/tmp/a b.png");
    assert_true(s.cmds[4].number == 2.5);
    assert_int_equal(s.cmds[6].key, GLFW_KEY_ESCAPE);
    assert_int_equal(s.cmds[7].key, GLFW_KEY_LEFT_BRACKET);
    assert_int_equal(s.cmds[8].key, GLFW_KEY_SLASH);
    assert_int_equal(s.cmds[9].op, FP_SCRIPT_CLOSE);
    fp_script_free(&s);
    /* the rig's keys and the camera (yaw, pitch in degrees, zoom 1 unless given) */
    assert_int_equal(fp_script_parse("key J; key k; key G; camera -35 10; camera 20 -5 1.5", &s, err,
                                     sizeof err), 0);
    assert_int_equal(s.count, 5);
    assert_int_equal(s.cmds[0].key, GLFW_KEY_J);
    assert_int_equal(s.cmds[1].key, GLFW_KEY_K);
    assert_int_equal(s.cmds[2].key, GLFW_KEY_G);
    assert_int_equal(s.cmds[3].op, FP_SCRIPT_CAMERA);
    assert_true(s.cmds[3].number == -35 && s.cmds[3].pitch == 10 && s.cmds[3].zoom == 1);
    assert_true(s.cmds[4].number == 20 && s.cmds[4].pitch == -5 && s.cmds[4].zoom == 1.5);
    fp_script_free(&s);
    /* numbers are decimals in every form (no hex, inf or nan: below), blanks between them */
    assert_int_equal(fp_script_parse("radius .5; scrub 1.; camera  -3e1\t+5  2E-1 ; wait frames 4", &s,
                                     err, sizeof err), 0);
    assert_int_equal(s.count, 4);
    assert_true(s.cmds[0].number == 0.5 && s.cmds[1].number == 1);
    assert_true(s.cmds[2].number == -30 && s.cmds[2].pitch == 5 && s.cmds[2].zoom == 0.2);
    assert_true(s.cmds[3].op == FP_SCRIPT_WAIT_FRAMES && s.cmds[3].number == 4);
    fp_script_free(&s);
    /* seconds on the wall clock, fractions kept (frames are whole) */
    assert_int_equal(fp_script_parse("wait seconds 1.25; wait seconds 0", &s, err, sizeof err), 0);
    assert_true(s.cmds[0].op == FP_SCRIPT_WAIT_SECONDS && s.cmds[0].number == 1.25);
    assert_true(s.cmds[1].op == FP_SCRIPT_WAIT_SECONDS && s.cmds[1].number == 0);
    fp_script_free(&s);
    /* the window resized: W x H pixels, 16..16384 each, as --size */
    assert_int_equal(fp_script_parse("size 240x480; size +16x16384", &s, err, sizeof err), 0);
    assert_true(s.cmds[0].op == FP_SCRIPT_SIZE && s.cmds[0].pitch == 240 && s.cmds[0].zoom == 480);
    assert_true(s.cmds[1].op == FP_SCRIPT_SIZE && s.cmds[1].pitch == 16 && s.cmds[1].zoom == 16384);
    fp_script_free(&s);
    const char *bad[] = {"size", "size 240", "size 15x480", "size 240x16385", "size 240x", "size x480",
                         "size 240x480x2", "size -240x480", "jump 3", "key Q", "wait forever", "radius -1", "shot", "close now",
                         "wait frames x", "camera", "camera 10", "camera 10 95", "camera 1 2 0",
                         "camera 1 2 3 4", "camera nan 0", "radius 0x10", "radius inf",
                         "scrub 0x1p-1", "wait frames 0x3", "camera 0x10 5", "camera 10 5 0x1",
                         "wait frames 3 x", "wait seconds", "wait seconds -1", "wait seconds inf",
                         "wait seconds 2 3"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err[0] = '\0';
        assert_int_equal(fp_script_parse(bad[i], &s, err, sizeof err), -EINVAL);
        assert_non_null(strstr(err, "--script"));
        assert_int_equal(s.count, 0);
    }
    /* a key it has no name for: the key said, and the keys it knows (before: "'key Q' is not
     * one of: ... key NAME ...", which read as if the command were wrong) */
    err[0] = '\0';
    assert_int_equal(fp_script_parse("wait frames 2; key Q", &s, err, sizeof err), -EINVAL);
    assert_non_null(strstr(err, "command 2 'key Q': no such key; keys: E C X"));
    assert_null(strstr(err, "is not one of"));
}

static void test_percentiles(void **state)
{
    (void)state;
    double v[100], med, p99;
    for (int i = 0; i < 100; i++) v[i] = 100 - i; /* 100 .. 1, unsorted */
    fp_viewer_percentiles(v, 100, &med, &p99);
    assert_true(med == 50.5);
    assert_true(p99 == 99);
    double one = 7;
    fp_viewer_percentiles(&one, 1, &med, &p99);
    assert_true(med == 7 && p99 == 7);
    fp_viewer_percentiles(NULL, 0, &med, &p99);
    assert_true(med == 0 && p99 == 0);
}

static int setup(void **state)
{
    (void)state;
    const char *data = getenv("FP_SHARED_DATA");
    char path[4096], err[512];
    snprintf(path, sizeof path, "%s/faces/ict-facekit/generic_neutral_mesh.obj",
             data ? data : "../shared/data");
    if (fp_mesh_load(path, &face, err, sizeof err) != FP_MESH_OK) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    if (!glfwInit()) {
        fprintf(stderr, "no display (run under xvfb-run)\n");
        return -1;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
    win = glfwCreateWindow(64, 64, "test_gpuwarp", NULL, NULL);
    if (!win) return -1;
    glfwMakeContextCurrent(win);
    if (fp_gpuwarp_create(&gw, err, sizeof err)) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    fp_gpuwarp_destroy(&gw);
    if (win) glfwDestroyWindow(win);
    glfwTerminate();
    fp_mesh_free(&face);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gpu_matches_engine),
        cmocka_unit_test(test_merged_start_points),
        cmocka_unit_test(test_identity_is_exact),
        cmocka_unit_test(test_solve_refuses_bad_input),
        cmocka_unit_test(test_script_parse),
        cmocka_unit_test(test_percentiles),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
