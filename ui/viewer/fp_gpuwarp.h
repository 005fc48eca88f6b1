/*
 * fp_gpuwarp.h: the CSRBF space warp T(x) = x + sum_i alpha_i psi31(|x - c_i| / R) evaluated in
 * a vertex shader (Sato, Savchenko, Ohbuchi, Cyberworlds 2004, eq. 1 without the polynomial;
 * shared/docs/csrbf.md), so that the viewer can draw a deformation from the base shape and a
 * few uniforms instead of uploading every vertex each frame (`facepuppet live --gpu-warp`).
 *
 * The coefficients are the engine's own: fp_warp_from_solver copies them out of the solver
 * that made the CPU shape (the session's engine step, fp_session_solver), with the
 * session's settings: kernel psi31, no polynomial, start points merged below 1e-4 R. No
 * second solve. The shader evaluates psi31 only; the result is checked against the CPU
 * engine's evaluation (fp_gpuwarp_eval, tests/viewer/test_gpuwarp.c).
 *
 * Thread rules: fp_warp_from_solver is reentrant on a const solver that no thread changes
 * meanwhile; the fp_gpuwarp functions need the GL 3.3 core context they were created in to
 * be current on the calling thread.
 */
#ifndef FP_GPUWARP_H
#define FP_GPUWARP_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Most centres the shader takes (as uniforms): the session's control-set capacity. */
#define FP_WARP_MAX_CENTRES 64

/** Solved warp: `count` merged centres (mesh units) and their coefficients alpha_i (mesh
 *  units), support radius R (mesh units). count == 0 is the identity. */
typedef struct fp_warp_coeffs {
    size_t count;
    float radius;
    float centre[FP_WARP_MAX_CENTRES][3];
    float alpha[FP_WARP_MAX_CENTRES][3];
} fp_warp_coeffs;

struct csrbf_solver;

/** Copy the solved warp out of an engine solver (core/csrbf: csrbf_solver_get_coefficients)
 *  whose support radius is R (mesh units) and whose kernel is psi31 (the engine's default;
 *  the solver cannot tell its kernel, the caller vouches). solver NULL gives the identity.
 *  Returns 0, or -EINVAL (R not finite and > 0; a solver with no start points),
 *  -E2BIG (more than FP_WARP_MAX_CENTRES centres after merging), -ENOTSUP (the solver has
 *  a polynomial part, which the shader lacks). out is the identity after an error. */
int fp_warp_from_solver(const struct csrbf_solver *solver, double radius, fp_warp_coeffs *out);

/** The GLSL (3.30) text declaring the warp's uniforms and
 *  `vec3 fp_warp(vec3 x, out mat3 jacobian)`; inserted into the viewer's mesh shader. */
extern const char fp_warp_glsl[];

/** Upload c into the warp uniforms of `program` (a linked program that contains
 *  fp_warp_glsl; it must be in use). */
void fp_warp_set_uniforms(unsigned program, const fp_warp_coeffs *c);

typedef struct fp_gpuwarp fp_gpuwarp;

/** Compile the transform-feedback program. Returns 0, or -ENODEV with the GL compiler's log
 *  in err when the context cannot build it. Free with fp_gpuwarp_destroy. */
int fp_gpuwarp_create(fp_gpuwarp **out, char *err, size_t errlen);

/** T at n points base (n x 3 floats, mesh units) computed by the shader, read back through
 *  transform feedback into out (n x 3 floats). Returns 0, -ENOMEM, or -EIO (a GL error). */
int fp_gpuwarp_eval(fp_gpuwarp *w, const fp_warp_coeffs *c, size_t n, const float *base,
                    float *out);

/** Free the program and buffers; sets *w to NULL. */
void fp_gpuwarp_destroy(fp_gpuwarp **w);

#ifdef __cplusplus
}
#endif
#endif
