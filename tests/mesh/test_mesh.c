/* Tests of fp_mesh: loading the real faces, round trips through every format, normals, and
 * every error path. Inputs are written to a mkdtemp() folder, never into the repository. */
#define _DEFAULT_SOURCE /* mount(2), usleep */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>

#include "fp_mesh.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char tmpdir[64];
static char err[1024];

static const char *data_dir(void)
{
    const char *d = getenv("FP_SHARED_DATA");
    return d && *d ? d : "../shared/data";
}

static const char *face_path(const char *rel)
{
    static char buf[4][512];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/faces/%s", data_dir(), rel);
    return buf[k];
}

static const char *tmp_path(const char *name)
{
    static char buf[4][512];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", tmpdir, name);
    return buf[k];
}

static const char *write_tmp(const char *name, const char *text)
{
    const char *p = tmp_path(name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    return p;
}

static int setup(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/fp_mesh_test_XXXXXX");
    return mkdtemp(tmpdir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

/* ---- an independent OBJ reading, for reference: v lines and polygon sizes -------------- */

typedef struct obj_ref {
    size_t nv, nfaces, ntris, quads, tris;
    float *v;        /* nv x 3, strtof of the v lines */
    long first_face[4];
    int first_face_n;
} obj_ref;

static void obj_ref_read(const char *path, obj_ref *r)
{
    memset(r, 0, sizeof *r);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    size_t cap = 1024;
    r->v = malloc(cap * 3 * sizeof(float));
    char line[4096];
    while (fgets(line, sizeof line, f)) {
        if (line[0] == 'v' && line[1] == ' ') {
            if (r->nv == cap) {
                cap *= 2;
                r->v = realloc(r->v, cap * 3 * sizeof(float));
            }
            char *p = line + 2;
            for (int k = 0; k < 3; k++)
                r->v[3 * r->nv + k] = strtof(p, &p);
            r->nv++;
        } else if (line[0] == 'f' && line[1] == ' ') {
            int n = 0;
            char *save = NULL;
            for (char *tok = strtok_r(line + 2, " \t\r\n", &save); tok;
                 tok = strtok_r(NULL, " \t\r\n", &save)) {
                if (r->nfaces == 0 && n < 4)
                    r->first_face[n] = strtol(tok, NULL, 10);
                n++;
            }
            if (r->nfaces == 0)
                r->first_face_n = n;
            r->nfaces++;
            r->ntris += (size_t)(n - 2);
            r->quads += n == 4;
            r->tris += n == 3;
        }
    }
    fclose(f);
}

static void check_against_obj(const fp_mesh *m, const obj_ref *r)
{
    assert_int_equal(m->vertex_count, r->nv);
    assert_int_equal(m->triangle_count, r->ntris);
    for (size_t i = 0; i < 3 * r->nv; i++)
        assert_true(m->positions[i] == r->v[i]); /* same decimal, same float */
    /* the first face, fan-triangulated, is the first triangle(s) */
    assert_int_equal(m->triangles[0], r->first_face[0] - 1);
    assert_int_equal(m->triangles[1], r->first_face[1] - 1);
    assert_int_equal(m->triangles[2], r->first_face[2] - 1);
    if (r->first_face_n == 4) {
        assert_int_equal(m->triangles[3], r->first_face[0] - 1);
        assert_int_equal(m->triangles[4], r->first_face[2] - 1);
        assert_int_equal(m->triangles[5], r->first_face[3] - 1);
    }
    for (size_t i = 0; i < 3 * m->triangle_count; i++)
        assert_true(m->triangles[i] < m->vertex_count);
    for (size_t i = 0; i < m->vertex_count; i++) {
        const float *n = m->normals + 3 * i;
        float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        assert_true(isfinite(len));
        assert_true(fabsf(len - 1.0f) < 1e-4f || len == 0.0f);
    }
}

/* ---- the real faces ------------------------------------------------------------------ */

static void test_load_ict_keeps_vertex_order(void **state)
{
    (void)state;
    const char *path = face_path("ict-facekit/generic_neutral_mesh.obj");
    obj_ref r;
    obj_ref_read(path, &r);
    /* the counts the ICT README gives */
    assert_int_equal(r.nv, 26719);
    assert_int_equal(r.nfaces, 26384);
    assert_int_equal(r.quads, 25836);
    assert_int_equal(r.tris, 548);
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(path, &m, err, sizeof err), FP_MESH_OK);
    assert_int_equal(m->vertex_count, 26719);
    assert_int_equal(m->triangle_count, 52220);
    check_against_obj(m, &r);
    assert_non_null(m->uvs);
    assert_string_equal(m->source_path, path);
    /* every vertex of the ICT face is used, so every normal is a unit vector */
    for (size_t i = 0; i < m->vertex_count; i++) {
        const float *n = m->normals + 3 * i;
        assert_true(fabsf(sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0f) < 1e-4f);
    }
    fp_mesh_free(&m);
    assert_null(m);
    free(r.v);
}

static void test_load_lee_perry_smith(void **state)
{
    (void)state;
    const char *path = face_path("lee-perry-smith/LeePerrySmith.obj");
    obj_ref r;
    obj_ref_read(path, &r);
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(path, &m, err, sizeof err), FP_MESH_OK);
    check_against_obj(m, &r);
    assert_non_null(m->uvs);
    fp_mesh_free(&m);
    free(r.v);
}

static void test_load_mediapipe_canonical(void **state)
{
    (void)state;
    const char *path = face_path("mediapipe-canonical/canonical_face_model.obj");
    obj_ref r;
    obj_ref_read(path, &r);
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(path, &m, err, sizeof err), FP_MESH_OK);
    assert_int_equal(m->vertex_count, 468);
    assert_int_equal(m->triangle_count, 898);
    check_against_obj(m, &r);
    assert_non_null(m->uvs);
    fp_mesh_free(&m);
    free(r.v);
}

/* OpenMesh warns about the missing .mtl of the ICT face: the library must not print. */
static void test_load_prints_nothing(void **state)
{
    (void)state;
    const char *log = tmp_path("stderr.txt");
    fflush(stderr);
    fflush(stdout);
    int saved_err = dup(2), saved_out = dup(1);
    int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    assert_true(fd >= 0);
    dup2(fd, 2);
    dup2(fd, 1);
    fp_mesh *m = NULL, *m2 = NULL;
    int rc = fp_mesh_load(face_path("mediapipe-canonical/canonical_face_model.obj"), &m, err,
                          sizeof err);
    int rc2 = fp_mesh_load(write_tmp("quiet.ply", "ply\nformat ascii 1.0\nelement vertex 1\n"
                                                  "property float x\nend_header\nzzz\n"),
                           &m2, err, sizeof err);
    fflush(stderr);
    fflush(stdout);
    dup2(saved_err, 2);
    dup2(saved_out, 1);
    close(saved_err);
    close(saved_out);
    close(fd);
    assert_int_equal(rc, FP_MESH_OK);
    assert_int_equal(rc2, FP_MESH_ERR_FORMAT);
    struct stat st;
    assert_int_equal(stat(log, &st), 0);
    assert_int_equal(st.st_size, 0);
    fp_mesh_free(&m);
}

/* ---- round trips --------------------------------------------------------------------- */

static void assert_close(float a, float b, float tol)
{
    if (!(fabsf(a - b) <= tol * (1.0f + fabsf(b))))
        fail_msg("%.9g differs from %.9g", (double)a, (double)b);
}

static void round_trip(const char *ext, int keeps_uvs)
{
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(face_path("mediapipe-canonical/canonical_face_model.obj"), &m,
                                  err, sizeof err),
                     FP_MESH_OK);
    char name[32];
    snprintf(name, sizeof name, "round.%s", ext);
    const char *path = tmp_path(name);
    assert_int_equal(fp_mesh_save(m, path, err, sizeof err), FP_MESH_OK);
    fp_mesh *r = NULL;
    int rc = fp_mesh_load(path, &r, err, sizeof err);
    if (rc != FP_MESH_OK)
        fail_msg("%s", err);
    assert_int_equal(r->vertex_count, m->vertex_count);
    assert_int_equal(r->triangle_count, m->triangle_count);
    for (size_t i = 0; i < 3 * m->vertex_count; i++) {
        assert_close(r->positions[i], m->positions[i], 1e-6f);
        assert_close(r->normals[i], m->normals[i], 1e-5f);
    }
    assert_memory_equal(r->triangles, m->triangles, 3 * m->triangle_count * sizeof(uint32_t));
    if (keeps_uvs) {
        /* an OBJ's v-up texture coordinates are written to glTF v-down (v' = 1 - v), and
         * glTF's are read as stored */
        const int flipped = strstr(ext, "gl") != NULL;
        assert_non_null(r->uvs);
        for (size_t i = 0; i < 2 * m->vertex_count; i++)
            assert_close(r->uvs[i], flipped && i % 2 ? 1.0f - m->uvs[i] : m->uvs[i], 1e-6f);
    }
    /* a copy of what was read is equal to it and independent of it */
    fp_mesh *c = fp_mesh_copy(r);
    assert_non_null(c);
    assert_memory_equal(c->positions, r->positions, 3 * r->vertex_count * sizeof(float));
    assert_ptr_not_equal(c->positions, r->positions);
    assert_string_equal(c->source_path, path);
    fp_mesh_free(&c);
    fp_mesh_free(&r);
    fp_mesh_free(&m);
}

static void test_round_trip_obj(void **state) { (void)state; round_trip("obj", 1); }
static void test_round_trip_ply(void **state) { (void)state; round_trip("ply", 1); }
static void test_round_trip_off(void **state) { (void)state; round_trip("off", 1); }
static void test_round_trip_gltf(void **state) { (void)state; round_trip("gltf", 1); }
static void test_round_trip_glb(void **state) { (void)state; round_trip("glb", 1); }
static void test_round_trip_upper_case_extension(void **state) { (void)state; round_trip("PLY", 1); }

/* STL stores triangles as three corner positions each: a round trip keeps every triangle's
 * corner positions in order, but vertex sharing is rebuilt from equal positions (vertices
 * with equal positions merge, unused ones vanish), and normals are recomputed, UVs lost. */
static void test_round_trip_stl(void **state)
{
    (void)state;
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(face_path("lee-perry-smith/LeePerrySmith.obj"), &m, err,
                                  sizeof err),
                     FP_MESH_OK);
    const char *path = tmp_path("round.stl");
    assert_int_equal(fp_mesh_save(m, path, err, sizeof err), FP_MESH_OK);
    /* binary STL: 80 + 4 + 50 bytes per triangle */
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal((size_t)st.st_size, 84 + 50 * m->triangle_count);
    fp_mesh *r = NULL;
    assert_int_equal(fp_mesh_load(path, &r, err, sizeof err), FP_MESH_OK);
    assert_int_equal(r->triangle_count, m->triangle_count);
    assert_true(r->vertex_count <= m->vertex_count);
    assert_null(r->uvs);
    for (size_t t = 0; t < m->triangle_count; t++)
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 3; d++)
                assert_true(r->positions[3 * r->triangles[3 * t + k] + d] ==
                            m->positions[3 * m->triangles[3 * t + k] + d]);
    fp_mesh_free(&r);
    fp_mesh_free(&m);
}

/* A polygon file: an OBJ quad and pentagon are fan-triangulated, and an OFF/PLY too. */
static void test_polygons_are_fan_triangulated(void **state)
{
    (void)state;
    const char *obj = write_tmp("poly.obj", "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\n"
                                            "v 5 5 5\n"
                                            "f 1 2 3 4 5\nf 1/1 2/1 4/1\nvt 0.5 0.25\n");
    fp_mesh *m = NULL;
    int rc = fp_mesh_load(obj, &m, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    assert_int_equal(m->vertex_count, 6);
    assert_int_equal(m->triangle_count, 4);
    const uint32_t want[] = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 1, 3};
    assert_memory_equal(m->triangles, want, sizeof want);
    /* UVs: vertices 0, 1, 3 got (0.5, 0.25) from the second face; the others (0, 0) */
    assert_non_null(m->uvs);
    assert_true(m->uvs[0] == 0.5f && m->uvs[1] == 0.25f);
    assert_true(m->uvs[2 * 2] == 0.0f && m->uvs[2 * 3] == 0.5f);
    /* vertex 5 is in no face: zero normal; the others point along +z */
    assert_true(m->normals[15] == 0.0f && m->normals[16] == 0.0f && m->normals[17] == 0.0f);
    assert_true(fabsf(m->normals[2] - 1.0f) < 1e-6f);
    fp_mesh_free(&m);

    const char *off = write_tmp("poly.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
    assert_int_equal(fp_mesh_load(off, &m, err, sizeof err), FP_MESH_OK);
    assert_int_equal(m->triangle_count, 2);
    const uint32_t want2[] = {0, 1, 2, 0, 2, 3};
    assert_memory_equal(m->triangles, want2, sizeof want2);
    assert_null(m->uvs);
    fp_mesh_free(&m);
}

/* An OBJ saved with a byte order mark (a Windows editor's) loads as the same file without
 * it (before: "line 1: unknown OBJ statement" naming the mark) */
static void test_obj_byte_order_mark(void **state)
{
    (void)state;
    const char *text = "# a triangle\r\nv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n";
    char marked[128];
    snprintf(marked, sizeof marked, "\xEF\xBB\xBF%s", text);
    fp_mesh *a = NULL, *b = NULL;
    int rc = fp_mesh_load(write_tmp("plain.obj", text), &a, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    rc = fp_mesh_load(write_tmp("marked.obj", marked), &b, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    assert_int_equal(a->vertex_count, 3);
    assert_int_equal(b->vertex_count, 3);
    assert_memory_equal(a->positions, b->positions, 9 * sizeof(float));
    assert_memory_equal(a->triangles, b->triangles, 3 * sizeof(uint32_t));
    fp_mesh_free(&a);
    fp_mesh_free(&b);
}

/* Relative (negative) OBJ indices refer back from the last vertex read. */
static void test_obj_negative_indices(void **state)
{
    (void)state;
    const char *p = write_tmp("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n");
    fp_mesh *m = NULL;
    int rc = fp_mesh_load(p, &m, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    const uint32_t want[] = {0, 1, 2};
    assert_memory_equal(m->triangles, want, sizeof want);
    fp_mesh_free(&m);
}

/* OpenMesh's OBJ reader removes a repeated vertex from a face and drops a face left with
 * fewer than 3 distinct vertices; the load agrees with that and still succeeds. */
static void test_obj_degenerate_faces(void **state)
{
    (void)state;
    const char *p = write_tmp("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                                                "f 1 1 2\nf 1 2 3 2\nf 2 4 3\n");
    fp_mesh *m = NULL;
    int rc = fp_mesh_load(p, &m, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    assert_int_equal(m->vertex_count, 4);
    const uint32_t want[] = {0, 1, 2, 1, 3, 2};
    assert_int_equal(m->triangle_count, 2);
    assert_memory_equal(m->triangles, want, sizeof want);
    fp_mesh_free(&m);
}

/* ---- normals ------------------------------------------------------------------------- */

/* The regular icosahedron, counter-clockwise from outside. */
static fp_mesh *icosahedron(void)
{
    const float t = (1.0f + sqrtf(5.0f)) / 2.0f;
    const float v[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                            {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                            {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    const uint32_t f[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                               {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                               {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                               {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    fp_mesh *m = fp_mesh_create(12, 20, 0);
    assert_non_null(m);
    memcpy(m->positions, v, sizeof v);
    memcpy(m->triangles, f, sizeof f);
    return m;
}

/* Reference: sum over incident triangles of area * unit face normal, in double. */
static void reference_normal(const fp_mesh *m, uint32_t v, double out[3])
{
    out[0] = out[1] = out[2] = 0;
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        if (tri[0] != v && tri[1] != v && tri[2] != v)
            continue;
        double p[3][3];
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 3; d++)
                p[k][d] = m->positions[3 * tri[k] + d];
        double a[3], b[3], c[3];
        for (int d = 0; d < 3; d++) {
            a[d] = p[1][d] - p[0][d];
            b[d] = p[2][d] - p[0][d];
        }
        c[0] = a[1] * b[2] - a[2] * b[1];
        c[1] = a[2] * b[0] - a[0] * b[2];
        c[2] = a[0] * b[1] - a[1] * b[0];
        double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        double area = 0.5 * len;
        for (int d = 0; d < 3; d++)
            out[d] += area * c[d] / len;
    }
    double len = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
    for (int d = 0; d < 3; d++)
        out[d] /= len;
}

static void test_normals_outward_on_icosahedron(void **state)
{
    (void)state;
    fp_mesh *m = icosahedron();
    assert_int_equal(fp_mesh_compute_normals(m), FP_MESH_OK);
    for (uint32_t i = 0; i < 12; i++) {
        const float *p = m->positions + 3 * i, *n = m->normals + 3 * i;
        float pl = sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        float nl = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        assert_true(fabsf(nl - 1.0f) < 1e-6f);
        /* by symmetry the normal is the radial direction, and it points outward */
        assert_true((p[0] * n[0] + p[1] * n[1] + p[2] * n[2]) / pl > 0.99999f);
    }
    fp_mesh_free(&m);
}

static void test_normals_follow_moved_vertices(void **state)
{
    (void)state;
    fp_mesh *m = icosahedron();
    assert_int_equal(fp_mesh_compute_normals(m), FP_MESH_OK);
    float before[3];
    memcpy(before, m->normals, sizeof before);
    /* pull vertex 0 outward and push vertex 5 sideways, as a deformation would */
    m->positions[0] *= 2.0f;
    m->positions[1] *= 2.0f;
    m->positions[3 * 5 + 0] += 0.7f;
    assert_int_equal(fp_mesh_compute_normals(m), FP_MESH_OK);
    assert_true(fabsf(m->normals[0] - before[0]) + fabsf(m->normals[1] - before[1]) > 1e-3f);
    for (uint32_t i = 0; i < 12; i++) {
        double ref[3];
        reference_normal(m, i, ref);
        for (int d = 0; d < 3; d++)
            assert_true(fabs(m->normals[3 * i + d] - ref[d]) < 1e-5);
    }
    /* the external-array form gives the same on a separate positions array */
    float pos[36], nrm[36];
    memcpy(pos, m->positions, sizeof pos);
    assert_int_equal(fp_mesh_normals(m->triangles, 20, pos, 12, nrm), FP_MESH_OK);
    assert_memory_equal(nrm, m->normals, sizeof nrm);
    fp_mesh_free(&m);
}

static void test_normals_bad_index(void **state)
{
    (void)state;
    const uint32_t tris[] = {0, 1, 7};
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    float nrm[9];
    memset(nrm, 0x7f, sizeof nrm);
    assert_int_equal(fp_mesh_normals(tris, 1, pos, 3, nrm), FP_MESH_ERR_INVALID);
    for (int i = 0; i < 9; i++)
        assert_true(nrm[i] == 0.0f);
    assert_int_equal(fp_mesh_normals(tris, 1, NULL, 3, nrm), FP_MESH_ERR_INVALID);
    assert_int_equal(fp_mesh_compute_normals(NULL), FP_MESH_ERR_INVALID);
}

/* fp_mesh_subdivide: two triangles sharing an edge give 4 + 5 vertices (the shared edge's
 * midpoint once), 8 triangles of the documented corners and orientation; the icosahedron's
 * 30 edges give 42 vertices and 80 outward triangles; NULL gives NULL. */
static void test_subdivide(void **state)
{
    (void)state;
    fp_mesh *q = fp_mesh_create(4, 2, 0);
    assert_non_null(q);
    const float pos[12] = {0, 0, 0, 2, 0, 0, 2, 2, 0, 0, 2, 0};
    const uint32_t tri[6] = {0, 1, 2, 0, 2, 3};
    memcpy(q->positions, pos, sizeof pos);
    memcpy(q->triangles, tri, sizeof tri);
    fp_mesh *s = fp_mesh_subdivide(q);
    assert_non_null(s);
    assert_int_equal(s->vertex_count, 4 + 5);
    assert_int_equal(s->triangle_count, 8);
    assert_null(s->uvs);
    assert_memory_equal(s->positions, pos, sizeof pos);
    /* edges in (smaller, larger) order: 01 02 03 12 23, their midpoints vertices 4..8 */
    const float mid[15] = {1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 1, 0, 1, 2, 0};
    assert_memory_equal(s->positions + 12, mid, sizeof mid);
    /* triangle 0 (0 1 2): m01 = 4, m12 = 7, m20 = 5 */
    const uint32_t t0[12] = {0, 4, 5, 1, 7, 4, 2, 5, 7, 4, 7, 5};
    assert_memory_equal(s->triangles, t0, sizeof t0);
    for (size_t v = 0; v < s->vertex_count; v++) /* flat, counter-clockwise: +z */
        assert_true(fabsf(s->normals[3 * v + 2] - 1.0f) < 1e-6f);
    fp_mesh_free(&s);
    fp_mesh_free(&q);

    fp_mesh *m = icosahedron();
    s = fp_mesh_subdivide(m);
    assert_non_null(s);
    assert_int_equal(s->vertex_count, 12 + 30);
    assert_int_equal(s->triangle_count, 80);
    for (size_t v = 0; v < s->vertex_count; v++) {
        const float *p = s->positions + 3 * v, *n = s->normals + 3 * v;
        assert_true(p[0] * n[0] + p[1] * n[1] + p[2] * n[2] > 0.0f);
    }
    fp_mesh *again = fp_mesh_subdivide(m); /* deterministic */
    assert_memory_equal(again->positions, s->positions, 3 * s->vertex_count * sizeof(float));
    assert_memory_equal(again->triangles, s->triangles, 3 * s->triangle_count * sizeof(uint32_t));
    fp_mesh_free(&again);
    fp_mesh_free(&s);
    fp_mesh_free(&m);
    assert_null(fp_mesh_subdivide(NULL));
}

static void test_bounds(void **state)
{
    (void)state;
    fp_mesh *m = icosahedron();
    float lo[3], hi[3];
    fp_mesh_bounds(m, lo, hi);
    const float t = (1.0f + sqrtf(5.0f)) / 2.0f;
    for (int k = 0; k < 3; k++) {
        assert_true(lo[k] == -t);
        assert_true(hi[k] == t);
    }
    fp_mesh_bounds(NULL, lo, hi);
    assert_true(lo[0] == 0.0f && hi[2] == 0.0f);
    fp_mesh_free(&m);
}

/* glTF: node transforms are applied; the default scene is read. The node JSON replaces the
 * plain node of a saved one-triangle file (0,0,0) (1,0,0) (0,1,0). */
static const char *transformed_triangle_file(const char *name, const char *node_json)
{
    fp_mesh *tri = fp_mesh_create(3, 1, 0);
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    memcpy(tri->positions, p, sizeof p);
    const uint32_t t[3] = {0, 1, 2};
    memcpy(tri->triangles, t, sizeof t);
    assert_int_equal(fp_mesh_compute_normals(tri), FP_MESH_OK);
    const char *plain = tmp_path("tri.gltf");
    assert_int_equal(fp_mesh_save(tri, plain, err, sizeof err), FP_MESH_OK);
    fp_mesh_free(&tri);
    FILE *f = fopen(plain, "rb");
    char json[8192];
    size_t len = fread(json, 1, sizeof json - 1, f);
    fclose(f);
    json[len] = '\0';
    const char *plain_node = "\"nodes\":[{\"mesh\":0}]";
    char *node = strstr(json, plain_node);
    assert_non_null(node);
    char out[8400];
    snprintf(out, sizeof out, "%.*s\"nodes\":[%s]%s", (int)(node - json), json, node_json,
             node + strlen(plain_node));
    return write_tmp(name, out);
}

static fp_mesh *load_transformed_triangle(const char *node_json)
{
    fp_mesh *m = NULL;
    int rc = fp_mesh_load(transformed_triangle_file("moved.gltf", node_json), &m, err,
                          sizeof err);
    if (rc)
        fail_msg("%s", err);
    return m;
}

static void expect_triangle(const fp_mesh *m, const float want[9], const float normal[3])
{
    assert_int_equal(m->vertex_count, 3);
    for (int i = 0; i < 9; i++)
        if (fabsf(m->positions[i] - want[i]) > 1e-6f)
            fail_msg("position %d: %g, want %g", i, (double)m->positions[i], (double)want[i]);
    for (int v = 0; v < 3; v++)
        for (int d = 0; d < 3; d++)
            assert_true(fabsf(m->normals[3 * v + d] - normal[d]) < 1e-6f);
    /* the stored normals agree with the winding of the (possibly flipped) triangle */
    float check[9];
    assert_int_equal(fp_mesh_normals(m->triangles, 1, m->positions, 3, check), FP_MESH_OK);
    for (int d = 0; d < 3; d++)
        assert_true(fabsf(check[d] - normal[d]) < 1e-6f);
}

static void test_gltf_node_transform_applied(void **state)
{
    (void)state;
    /* translation (10, 0, 0) after scale 2 */
    fp_mesh *m = load_transformed_triangle(
        "{\"mesh\":0,\"translation\":[10,0,0],\"scale\":[2,2,2]}");
    const float want1[9] = {10, 0, 0, 12, 0, 0, 10, 2, 0}, up[3] = {0, 0, 1};
    expect_triangle(m, want1, up);
    fp_mesh_free(&m);
    /* rotation of 90 degrees about x: (x, y, z) -> (x, -z, y); the normal +z becomes -y */
    const double h = sqrt(0.5);
    char node[256];
    snprintf(node, sizeof node, "{\"mesh\":0,\"rotation\":[%.17g,0,0,%.17g]}", h, h);
    m = load_transformed_triangle(node);
    const float want2[9] = {0, 0, 0, 1, 0, 0, 0, 0, 1}, minus_y[3] = {0, -1, 0};
    expect_triangle(m, want2, minus_y);
    fp_mesh_free(&m);
    /* a parent matrix mirroring z, a child translating by (0, 0, 1): the triangle lands at
       z = -1, and its winding is flipped so the normal stays consistent (now -z) */
    m = load_transformed_triangle(
        "{\"children\":[1],\"matrix\":[1,0,0,0, 0,1,0,0, 0,0,-1,0, 0,0,0,1]},"
        "{\"mesh\":0,\"translation\":[0,0,1]}");
    const float want3[9] = {0, 0, -1, 1, 0, -1, 0, 1, -1}, down[3] = {0, 0, -1};
    expect_triangle(m, want3, down);
    fp_mesh_free(&m);
}

/* One mesh placed by two nodes loads as two copies, each deformed where its node put it;
 * written back, the file held one set of positions for both, the first copy's: the second's
 * deformation was lost (a face instanced beside itself kept one face's shape twice). Each
 * node whose copy differs now gets a mesh of its own; both come back as they were saved. */
static void test_gltf_instances_saved_apart(void **state)
{
    (void)state;
    fp_mesh *m = load_transformed_triangle(
        "{\"mesh\":0,\"children\":[1]},{\"mesh\":0,\"translation\":[10,0,0]}");
    assert_int_equal(m->vertex_count, 6);
    const float want[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 10, 0, 0, 11, 0, 0, 10, 1, 0};
    for (int i = 0; i < 18; i++) assert_true(fabsf(m->positions[i] - want[i]) < 1e-6f);
    m->positions[3 * 1 + 1] += 0.25f; /* the first copy's second vertex up */
    m->positions[3 * 5 + 2] += 0.5f;  /* the second copy's third vertex out */
    const char *path = tmp_path("instances-out.gltf");
    assert_int_equal(fp_mesh_save(m, path, err, sizeof err), FP_MESH_OK);
    fp_mesh *back = NULL;
    if (fp_mesh_load(path, &back, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(back->vertex_count, 6);
    for (int i = 0; i < 18; i++)
        if (fabsf(back->positions[i] - m->positions[i]) > 1e-6f)
            fail_msg("coordinate %d: %g written back, %g saved", i, (double)back->positions[i],
                     (double)m->positions[i]);
    fp_mesh_free(&back);
    /* copies that agree stay one mesh for both nodes */
    fp_mesh_free(&m);
    m = load_transformed_triangle("{\"mesh\":0,\"children\":[1]},{\"mesh\":0,\"translation\":[10,0,0]}");
    m->positions[3 * 1 + 1] += 0.25f;
    m->positions[3 * 4 + 1] += 0.25f;
    assert_int_equal(fp_mesh_save(m, path, err, sizeof err), FP_MESH_OK);
    FILE *f = fopen(path, "rb");
    char json[16384];
    size_t len = fread(json, 1, sizeof json - 1, f);
    fclose(f);
    json[len] = '\0';
    size_t k = 0; /* without white space, as the writer may indent */
    for (size_t i = 0; i < len; i++)
        if (!strchr(" \t\r\n", json[i])) json[k++] = json[i];
    json[k] = '\0';
    assert_non_null(strstr(json, "\"mesh\":0"));
    assert_null(strstr(json, "\"mesh\":1"));
    fp_mesh_free(&m);
}

/* A node that flattens its mesh (scale 0 along z: singular) loads; its deformed copy had no
 * local frame to go back into, and the save failed ("singular node transform") after the
 * whole performance. It goes, as deformed, onto a new root node; a reload gives it back. */
static void test_gltf_singular_node_saved(void **state)
{
    (void)state;
    fp_mesh *m = load_transformed_triangle("{\"mesh\":0,\"scale\":[2,1,0]}");
    const float want[9] = {0, 0, 0, 2, 0, 0, 0, 1, 0};
    for (int i = 0; i < 9; i++) assert_true(fabsf(m->positions[i] - want[i]) < 1e-6f);
    m->positions[3 * 2 + 2] = 0.5f; /* the third vertex off the flattened plane */
    const char *path = tmp_path("flat-out.gltf");
    if (fp_mesh_save(m, path, err, sizeof err)) fail_msg("%s", err);
    fp_mesh *back = NULL;
    if (fp_mesh_load(path, &back, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(back->vertex_count, 3);
    for (int i = 0; i < 9; i++)
        if (fabsf(back->positions[i] - m->positions[i]) > 1e-6f)
            fail_msg("coordinate %d: %g written back, %g saved", i, (double)back->positions[i],
                     (double)m->positions[i]);
    fp_mesh_free(&back);
    fp_mesh_free(&m);
}

/* ---- errors: each names the file and the reason ---------------------------------------- */

static void expect_load_error(const char *path, int code, const char *needle)
{
    fp_mesh *m = (fp_mesh *)(uintptr_t)1;
    err[0] = '\0';
    int rc = fp_mesh_load(path, &m, err, sizeof err);
    if (rc != code)
        fail_msg("%s: got %d (%s), want %d", path, rc, err, code);
    assert_null(m);
    if (!strstr(err, path))
        fail_msg("message does not name the file: %s", err);
    if (needle && !strstr(err, needle))
        fail_msg("message lacks '%s': %s", needle, err);
    assert_true(strlen(fp_mesh_strerror(rc)) > 0);
}

static void test_error_missing_file(void **state)
{
    (void)state;
    expect_load_error(tmp_path("nonexistent.obj"), FP_MESH_ERR_NOENT, "No such file");
    expect_load_error(tmp_path("nonexistent.glb"), FP_MESH_ERR_NOENT, "No such file");
}

static void test_error_empty_file(void **state)
{
    (void)state;
    expect_load_error(write_tmp("empty.obj", ""), FP_MESH_ERR_FORMAT, "empty");
    expect_load_error(write_tmp("empty.ply", ""), FP_MESH_ERR_FORMAT, "empty");
    expect_load_error(write_tmp("empty.gltf", ""), FP_MESH_ERR_FORMAT, "empty");
    /* only comments: no vertices */
    expect_load_error(write_tmp("comments.obj", "# nothing\n\n"), FP_MESH_ERR_FORMAT,
                      "no vertices");
    expect_load_error(write_tmp("nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
                      FP_MESH_ERR_FORMAT, "no faces");
}

static void test_error_malformed_text(void **state)
{
    (void)state;
    expect_load_error(write_tmp("garbage.obj", "v 0 0 0\nhello world, this is not a mesh\n"),
                      FP_MESH_ERR_FORMAT, "line 2: unknown OBJ statement 'hello'");
    expect_load_error(write_tmp("badnum.obj", "v 0 0 0\nv 1 x 0\n"), FP_MESH_ERR_FORMAT,
                      "line 2: malformed number 'x'");
    expect_load_error(write_tmp("short.obj", "v 0 0\n"), FP_MESH_ERR_FORMAT, "line 1");
    expect_load_error(write_tmp("badcorner.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3a\n"),
                      FP_MESH_ERR_FORMAT, "line 4: malformed face corner '3a'");
    expect_load_error(write_tmp("twocorners.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n"),
                      FP_MESH_ERR_FORMAT, "line 3");
    expect_load_error(write_tmp("garbage.ply", "this is not a ply file\n"), FP_MESH_ERR_FORMAT,
                      NULL);
    expect_load_error(write_tmp("garbage.off", "this is not an off file\n"), FP_MESH_ERR_FORMAT,
                      NULL);
    expect_load_error(write_tmp("garbage.stl", "this is not an stl file\n"), FP_MESH_ERR_FORMAT,
                      "not an STL file");
    expect_load_error(write_tmp("garbage.gltf", "{ not json"), FP_MESH_ERR_FORMAT, "glTF");
    expect_load_error(write_tmp("garbage.glb", "glTF but not really a binary glTF"),
                      FP_MESH_ERR_FORMAT, "glTF");
}

static void test_error_index_out_of_range(void **state)
{
    (void)state;
    expect_load_error(write_tmp("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n"),
                      FP_MESH_ERR_FORMAT, "line 5: face vertex index 9 out of range");
    expect_load_error(write_tmp("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
                      FP_MESH_ERR_FORMAT, "line 4");
    expect_load_error(write_tmp("negrange.obj", "v 0 0 0\nv 1 0 0\nf -3 -2 -1\nv 0 1 0\n"),
                      FP_MESH_ERR_FORMAT, "line 3");
    expect_load_error(write_tmp("vtrange.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n"
                                               "f 1/1 2/2 3/1\n"),
                      FP_MESH_ERR_FORMAT, "line 5: face texture coordinate index 2");
    expect_load_error(write_tmp("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n"),
                      FP_MESH_ERR_FORMAT, "line 6: face 0 references vertex 5");
    expect_load_error(write_tmp("range.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
                                             "property float x\nproperty float y\n"
                                             "property float z\nelement face 1\n"
                                             "property list uchar int vertex_indices\n"
                                             "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                      FP_MESH_ERR_FORMAT, "references vertex 3");
}

static void test_error_nan_coordinate(void **state)
{
    (void)state;
    expect_load_error(write_tmp("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"),
                      FP_MESH_ERR_FORMAT, "line 2: non-finite value 'nan'");
    expect_load_error(write_tmp("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n"),
                      FP_MESH_ERR_FORMAT, "line 4: non-finite value 'nan' in vertex 1");
    expect_load_error(write_tmp("nan.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
                                           "property float x\nproperty float y\n"
                                           "property float z\nelement face 1\n"
                                           "property list uchar int vertex_indices\n"
                                           "end_header\n0 0 0\n1 NaN 0\n0 1 0\n3 0 1 2\n"),
                      FP_MESH_ERR_FORMAT, "line 11: non-finite value 'NaN'");
    expect_load_error(write_tmp("nan.stl", "solid t\nfacet normal 0 0 1\nouter loop\n"
                                           "vertex 0 0 0\nvertex 1 nan 0\nvertex 0 1 0\n"
                                           "endloop\nendfacet\nendsolid t\n"),
                      FP_MESH_ERR_FORMAT, "line 5: non-finite value 'nan'");
    expect_load_error(write_tmp("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n"),
                      FP_MESH_ERR_FORMAT, "file ends after 2 of 3 vertices");
}

static void test_error_inf_coordinate(void **state)
{
    (void)state;
    expect_load_error(write_tmp("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n"),
                      FP_MESH_ERR_FORMAT, "line 3: non-finite value '-inf'");
    expect_load_error(write_tmp("big.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n"),
                      FP_MESH_ERR_FORMAT, "line 2");
}

/* Coordinates are decimals (facepuppet/decimal.h, as every number facepuppet reads): strtod's
 * hexadecimal floats are malformed in each text format, inf and nan non-finite (above); every
 * decimal form in the wild loads ("1e-05", "-0", "+.5E+1", "1.", ".5"). */
static void test_decimal_coordinates(void **state)
{
    (void)state;
    static const char ply_head[] = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                   "property float y\nproperty float z\nelement face 1\n"
                                   "property list uchar int vertex_indices\nend_header\n";
    char text[1024];
    expect_load_error(write_tmp("hex.obj", "v 0 0 0\nv 1 0x1p3 0\nv 0 1 0\nf 1 2 3\n"),
                      FP_MESH_ERR_FORMAT, "line 2: malformed number '0x1p3' in 'v' statement");
    expect_load_error(write_tmp("hex.off", "OFF\n3 1 0\n0 0 0\n1 -0X10 0\n0 1 0\n3 0 1 2\n"),
                      FP_MESH_ERR_FORMAT, "line 4: malformed number '-0X10' in vertex 1");
    snprintf(text, sizeof text, "%s0 0 0\n1 0x1p3 0\n0 1 0\n3 0 1 2\n", ply_head);
    expect_load_error(write_tmp("hex.ply", text), FP_MESH_ERR_FORMAT,
                      "line 11: malformed number '0x1p3'");
    expect_load_error(write_tmp("hex.stl", "solid t\nfacet normal 0 0 1\nouter loop\n"
                                           "vertex 0 0 0\nvertex 1 0x1p3 0\nvertex 0 1 0\n"
                                           "endloop\nendfacet\nendsolid t\n"),
                      FP_MESH_ERR_FORMAT, "line 5: malformed value '0x1p3'");
    static const float want[9] = {1e-05f, -0.0f, 5.0f, 1.0f, 0.5f, -2.0f, 0.0f, 1.0f, 0.0f};
    const char *obj = write_tmp("forms.obj", "v 1e-05 -0 +.5E+1\nv 1. .5 -2e0\nv 0 1 0\nf 1 2 3\n");
    const char *off = write_tmp("forms.off", "OFF\n3 1 0\n1e-05 -0 +.5E+1\n1. .5 -2e0\n0 1 0\n3 0 1 2\n");
    snprintf(text, sizeof text, "%s1e-05 -0 +.5E+1\n1. .5 -2e0\n0 1 0\n3 0 1 2\n", ply_head);
    const char *ply = write_tmp("forms.ply", text);
    const char *paths[] = {obj, off, ply};
    for (int k = 0; k < 3; k++) {
        fp_mesh *m = NULL;
        int rc = fp_mesh_load(paths[k], &m, err, sizeof err);
        if (rc) fail_msg("%s: %s", paths[k], err);
        assert_int_equal(m->vertex_count, 3);
        for (int i = 0; i < 9; i++) assert_true(m->positions[i] == want[i]);
        assert_true(signbit(m->positions[1]));
        fp_mesh_free(&m);
    }
    fp_mesh *m = NULL;
    const char *stl = write_tmp("forms.stl", "solid t\nfacet normal 0 0 +1E0\nouter loop\n"
                                             "vertex 1e-05 -0 +.5E+1\nvertex 1. .5 -2e0\n"
                                             "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n");
    if (fp_mesh_load(stl, &m, err, sizeof err)) fail_msg("%s: %s", stl, err);
    assert_int_equal(m->triangle_count, 1);
    fp_mesh_free(&m);
}

static const char tri_gltf_fmt[] =
    "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
    "\"nodes\":[{\"mesh\":0}],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\"}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
    "\"buffers\":[{\"byteLength\":36,\"uri\":\"%s\"}]}";

static void test_error_gltf_missing_buffer(void **state)
{
    (void)state;
    char json[1024];
    snprintf(json, sizeof json, tri_gltf_fmt, 3, "missing.bin");
    /* an input file missing (exit 66), named by its path: before, FORMAT (65) */
    expect_load_error(write_tmp("nobuffer.gltf", json), FP_MESH_ERR_NOENT,
                      tmp_path("missing.bin"));
    /* one that may not be read: ACCESS (66), named (not as root: root reads it anyway) */
    if (geteuid() != 0) {
        FILE *f = fopen(tmp_path("locked.bin"), "wb");
        assert_non_null(f);
        fclose(f);
        assert_int_equal(chmod(tmp_path("locked.bin"), 0), 0);
        snprintf(json, sizeof json, tri_gltf_fmt, 3, "locked.bin");
        expect_load_error(write_tmp("locked.gltf", json), FP_MESH_ERR_ACCESS, "locked.bin");
    }
}

static void test_error_gltf_bad_accessor(void **state)
{
    (void)state;
    /* a real 36-byte buffer, but an accessor claiming 4 vertices (48 bytes) */
    static const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    FILE *f = fopen(tmp_path("tri.bin"), "wb");
    fwrite(p, sizeof p, 1, f);
    fclose(f);
    char json[1024];
    snprintf(json, sizeof json, tri_gltf_fmt, 3, "tri.bin");
    fp_mesh *m = NULL;
    const char *good = write_tmp("good.gltf", json);
    int rc = fp_mesh_load(good, &m, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    assert_int_equal(m->triangle_count, 1); /* non-indexed: 3 vertices, one triangle */
    fp_mesh_free(&m);
    snprintf(json, sizeof json, tri_gltf_fmt, 4, "tri.bin");
    expect_load_error(write_tmp("overrun.gltf", json), FP_MESH_ERR_FORMAT, "overruns");
}

static void test_error_unknown_extension(void **state)
{
    (void)state;
    expect_load_error(write_tmp("mesh.fbx", "whatever"), FP_MESH_ERR_UNSUPPORTED, "fbx");
    expect_load_error(write_tmp("noext", "v 0 0 0\n"), FP_MESH_ERR_UNSUPPORTED, NULL);
    /* what is missing, or a folder, is said as such whatever its name (before: "unsupported
     * extension ''" for a folder, exit 65 where 66 belongs) */
    expect_load_error(tmpdir, FP_MESH_ERR_NOENT, "is a folder");
    expect_load_error(tmp_path("missing.fbx"), FP_MESH_ERR_NOENT, NULL);
    fp_mesh *m = icosahedron();
    assert_int_equal(fp_mesh_save(m, tmp_path("out.3ds"), err, sizeof err),
                     FP_MESH_ERR_UNSUPPORTED);
    fp_mesh_free(&m);
}

static void test_error_save(void **state)
{
    (void)state;
    fp_mesh *m = icosahedron();
    assert_int_equal(fp_mesh_save(m, tmp_path("no/such/dir/out.obj"), err, sizeof err),
                     FP_MESH_ERR_NOENT);
    assert_non_null(strstr(err, "no/such/dir/out.obj"));
    assert_int_equal(fp_mesh_save(m, tmp_path("no/such/dir/out.glb"), err, sizeof err),
                     FP_MESH_ERR_NOENT);
    m->triangles[5] = 12; /* out of range */
    assert_int_equal(fp_mesh_save(m, tmp_path("bad.obj"), err, sizeof err), FP_MESH_ERR_INVALID);
    assert_non_null(strstr(err, "triangle 1"));
    m->triangles[5] = 1;
    m->positions[4] = NAN;
    assert_int_equal(fp_mesh_save(m, tmp_path("bad.ply"), err, sizeof err), FP_MESH_ERR_INVALID);
    assert_int_equal(fp_mesh_save(NULL, tmp_path("x.obj"), err, sizeof err), FP_MESH_ERR_INVALID);
    fp_mesh *other = m;
    assert_int_equal(fp_mesh_load(NULL, &other, err, sizeof err), FP_MESH_ERR_INVALID);
    assert_null(other); /* *out is NULL after any failed load */
    fp_mesh_free(&m);
    fp_mesh_free(&m); /* a second free of the NULLed pointer is a no-op */
}

/* ---- hostile input (issue 16) --------------------------------------------------------- */

#if defined(__SANITIZE_ADDRESS__)
#define FP_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define FP_UNDER_ASAN 1
#endif
#endif

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* What a loaded mesh promises: indices in range, finite positions and UVs, unit or zero
 * normals (the fuzz targets check the same). */
static int mesh_consistent(const fp_mesh *m)
{
    if (!m || !m->vertex_count || !m->triangle_count || !m->normals)
        return 0;
    for (size_t i = 0; i < 3 * m->triangle_count; i++)
        if (m->triangles[i] >= m->vertex_count)
            return 0;
    for (size_t v = 0; v < m->vertex_count; v++) {
        const float *p = m->positions + 3 * v, *n = m->normals + 3 * v;
        double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]) ||
            !(len == 0 || fabs(len - 1) < 1e-3) ||
            (m->uvs && (!isfinite(m->uvs[2 * v]) || !isfinite(m->uvs[2 * v + 1]))))
            return 0;
    }
    return 1;
}

/* Load `path` in a child under 1 GiB of address space (not under ASan, which reserves
 * terabytes) and a 10 s alarm; the load must fail with a negative code, no mesh and a
 * message naming the file (and holding `needle` when given). Returns the seconds taken. */
static double expect_refused_bounded(const char *path, const char *needle)
{
    fflush(NULL);
    double t0 = now_s();
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
#ifndef FP_UNDER_ASAN
        struct rlimit rl = {1u << 30, 1u << 30};
        setrlimit(RLIMIT_AS, &rl);
#endif
        alarm(10);
        fp_mesh *m = NULL;
        char e[1024] = "";
        int rc = fp_mesh_load(path, &m, e, sizeof e);
        const char *base = strrchr(path, '/');
        if (!strncmp(base ? base + 1 : path, "loads-", 6)) /* found by fuzzing, loads */
            _exit(rc == 0 && mesh_consistent(m) ? 0 : 2);
        if (rc >= 0 || m || !strstr(e, path) || (needle && !strstr(e, needle))) {
            fprintf(stderr, "%s: rc %d, message '%s' (want '%s')\n", path, rc, e,
                    needle ? needle : "");
            _exit(1);
        }
        _exit(0);
    }
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    double dt = now_s() - t0;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        fail_msg("%s: child %s %d after %.2f s", path,
                 WIFSIGNALED(status) ? "killed by signal" : "exited with",
                 WIFSIGNALED(status) ? WTERMSIG(status) : WEXITSTATUS(status), dt);
    return dt;
}

/* Every file in tests/mesh/hostile/ (crashes, hangs and escapes found by review and fuzzing)
 * is refused, fast, in bounded memory, except loads-*: inputs that crashed a fuzz target's
 * checks and must load into a consistent mesh. Some messages are checked word for word. */
static void test_hostile_files_refused(void **state)
{
    (void)state;
    static const struct { const char *file, *needle; } expected[] = {
        {"ply_property_before_element.ply", "line 3: 'property' before any 'element'"},
        {"ply_count_not_a_number.ply", "line 3: element count 'three'"},
        {"ply_unknown_keyword.ply", "line 7: unknown PLY header keyword 'bogus'"},
        {"ply_no_end_header.ply", "no 'end_header'"},
        {"ply_binary_huge_faces.ply", "need at least 4000000036 bytes"},
        {"ply_ascii_float_overflow.ply", "line 11: non-finite value '1e39'"},
        {"off_binary_huge_faces.off", "4294967280 faces need at least"},
        {"off_ascii_huge_counts.off", "line 2: 4000000000 vertices"},
        {"stl_ascii_no_endloop.stl", "line 7: expected 'endloop', found 'endfacet'"},
        {"gltf_parent_uri.gltf", "URI '../../secret' refused: leaves the glTF file's folder"},
        {"gltf_percent_parent_uri.gltf", "URI '../../secret' refused"},
        {"gltf_absolute_uri.gltf", "URI '/etc/passwd' refused: absolute path"},
        {"gltf_image_parent_uri.gltf", "URI '../../secret.png' refused"},
        {"ply_binary_no_x.ply", "line 3: the vertex element has no property 'x'"},
        {"gltf_indices_negative.gltf", "meshes[0].primitives[0].indices is -1"},
        {"gltf_position_byte.gltf", "POSITION accessor 0 has component type 5120 (BYTE)"},
        {"gltf_matrix_15.gltf", "nodes[0].matrix has 15 numbers, not 16"},
        {"glb_version_1.glb", "GLB header version 1"},
        /* a data URI's payload is not quoted whole (it was: kilobytes of base64) */
        {"gltf_data_uri_bytelength.gltf", "base64,AAECAwQFBgcICQoL... (200 base64 characters)"},
        {"gltf_uri_dot.gltf", "URI '.' refused: names the glTF file's folder, not a file"},
        {"gltf_nodes_too_deep.gltf", "node 1001 is more than 1000 levels deep"},
        {"gltf_requires_draco.gltf", "requires the extension KHR_draco_mesh_compression, not supported"},
    };
    const char *dir = "tests/mesh/hostile";
    DIR *d = opendir(dir);
    assert_non_null(d);
    struct dirent *de;
    int n = 0;
    double worst = 0;
    while ((de = readdir(d))) {
        if (de->d_name[0] == '.')
            continue;
        char path[512];
        snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
        const char *needle = NULL;
        for (size_t i = 0; i < sizeof expected / sizeof expected[0]; i++)
            if (!strcmp(expected[i].file, de->d_name))
                needle = expected[i].needle;
        double dt = expect_refused_bounded(path, needle);
        worst = dt > worst ? dt : worst;
        n++;
    }
    closedir(d);
    assert_true(n >= 25);
    if (worst > 2.0)
        fail_msg("a hostile file took %.2f s to refuse", worst);
}

/* glTF buffers: a FIFO is refused at once (it used to block forever), a symbolic link that
 * leads outside the folder is refused, a plain relative file in a sub-folder is read. */
static void test_gltf_uri_fifo_symlink(void **state)
{
    (void)state;
    static const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    char sub[600], json[1024];
    snprintf(sub, sizeof sub, "%s/uri", tmpdir);
    assert_int_equal(mkdir(sub, 0700), 0);
    snprintf(sub, sizeof sub, "%s/uri/sub", tmpdir);
    assert_int_equal(mkdir(sub, 0700), 0);
    FILE *f = fopen(tmp_path("uri/sub/tri.bin"), "wb");
    assert_non_null(f);
    fwrite(p, sizeof p, 1, f);
    fclose(f);
    f = fopen(tmp_path("outside.bin"), "wb"); /* beside the glTF's folder, not in it */
    fwrite(p, sizeof p, 1, f);
    fclose(f);
    snprintf(json, sizeof json, tri_gltf_fmt, 3, "sub/./tri.bin");
    fp_mesh *m = NULL;
    int rc = fp_mesh_load(write_tmp("uri/ok.gltf", json), &m, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    fp_mesh_free(&m);

    assert_int_equal(mkfifo(tmp_path("uri/pipe.bin"), 0600), 0);
    snprintf(json, sizeof json, tri_gltf_fmt, 3, "pipe.bin");
    double dt = expect_refused_bounded(write_tmp("uri/fifo.gltf", json), "URI 'pipe.bin' refused");
    assert_true(dt < 1.0);
    assert_int_equal(symlink("../outside.bin", tmp_path("uri/link.bin")), 0);
    snprintf(json, sizeof json, tri_gltf_fmt, 3, "link.bin");
    expect_refused_bounded(write_tmp("uri/link.gltf", json),
                           "URI 'link.bin' refused: a symbolic link leads outside");
    snprintf(json, sizeof json, tri_gltf_fmt, 3, "sub/../../outside.bin");
    expect_refused_bounded(write_tmp("uri/up.gltf", json), "leaves the glTF file's folder");
    /* a mesh path that names a FIFO is refused too, without blocking */
    assert_int_equal(mkfifo(tmp_path("uri/fifo.obj"), 0600), 0);
    expect_refused_bounded(tmp_path("uri/fifo.obj"), "not a regular file");
}

/* OBJ `mtllib` names are never opened (OpenMesh used to open them wherever they pointed and
 * blocked for ever on a FIFO): the mesh loads, in a child with a 10 s alarm. */
static void test_obj_mtllib_not_opened(void **state)
{
    (void)state;
    assert_int_equal(mkfifo(tmp_path("pipe.mtl"), 0600), 0);
    const char *p = write_tmp("mtl.obj", "mtllib pipe.mtl\n  mtllib ../../../../etc/passwd\n"
                                         "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl skin\nf 1 2 3\n");
    fflush(NULL);
    double t0 = now_s();
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        alarm(10);
        fp_mesh *m = NULL;
        int rc = fp_mesh_load(p, &m, NULL, 0);
        _exit(rc == FP_MESH_OK && m && m->vertex_count == 3 && m->triangle_count == 1 ? 0 : 1);
    }
    int status;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    assert_true(now_s() - t0 < 2.0);
}

/* The OBJ scan's fast paths keep what the slow ones did: a corner index read as strtol reads
 * it ([+-]digits; beyond LONG_MAX malformed), and groups known without the materials pass when
 * the file has no usemtl (a save that cannot keep them says so). */
static void test_obj_scan_fast_paths(void **state)
{
    (void)state;
    fp_mesh *m = NULL;
    const char *tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    char text[256];
    snprintf(text, sizeof text, "%sf +1 +2 -1\n", tri);
    assert_int_equal(fp_mesh_load(write_tmp("plus.obj", text), &m, NULL, 0), FP_MESH_OK);
    assert_int_equal(m->triangle_count, 1);
    assert_int_equal(m->triangles[0] + m->triangles[1] + m->triangles[2], 0 + 1 + 2);
    fp_mesh_free(&m);
    snprintf(text, sizeof text, "%sf 1 2 9223372036854775807\n", tri); /* LONG_MAX: a number */
    expect_load_error(write_tmp("longmax.obj", text), FP_MESH_ERR_FORMAT,
                      "line 4: face vertex index 9223372036854775807 out of range");
    snprintf(text, sizeof text, "%sf 1 2 9223372036854775808\n", tri); /* one more: not */
    expect_load_error(write_tmp("longmax1.obj", text), FP_MESH_ERR_FORMAT,
                      "line 4: malformed face corner '9223372036854775808'");
    snprintf(text, sizeof text, "%sf 1 2 +\n", tri);
    expect_load_error(write_tmp("sign.obj", text), FP_MESH_ERR_FORMAT, "line 4: malformed face corner '+'");
    snprintf(text, sizeof text, "%sf 1 2 -/1\n", tri);
    expect_load_error(write_tmp("signslash.obj", text), FP_MESH_ERR_FORMAT, "line 4: malformed face corner");
    /* groups without materials, materials without groups, neither */
    const char *cases[][2] = {{"g head\n", "groups"}, {"o face\n", "groups"},
                              {"usemtl skin\n", "materials"}, {"", ""}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        snprintf(text, sizeof text, "%s%sf 1 2 3\n", tri, cases[i][0]);
        char name[32];
        snprintf(name, sizeof name, "grp%zu.obj", i);
        assert_int_equal(fp_mesh_load(write_tmp(name, text), &m, NULL, 0), FP_MESH_OK);
        unsigned dropped = 0;
        assert_int_equal(fp_mesh_save_ex(m, tmp_path("grp.ply"), &dropped, NULL, 0), FP_MESH_OK);
        int groups = (dropped & FP_MESH_DROPPED_GROUPS) != 0, mats = (dropped & FP_MESH_DROPPED_MATERIALS) != 0;
        assert_int_equal(groups, !strcmp(cases[i][1], "groups"));
        assert_int_equal(mats, !strcmp(cases[i][1], "materials"));
        fp_mesh_free(&m);
    }
}

/* A PLY's vertex colours and a face's flags (and an OFF's colours) are read past and never
 * written: saved back (the same format too) they were lost with no word. The save says it
 * dropped them; a plain PLY drops nothing. */
static void test_ply_other_properties_dropped(void **state)
{
    (void)state;
    static const char head[] = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                               "property float y\nproperty float z\n%selement face 1\n"
                               "property list uchar int vertex_indices\n%send_header\n";
    static const struct { const char *v, *f, *vals, *fval; int other; } cases[] = {
        {"property uchar red\nproperty uchar green\nproperty uchar blue\n", "", " 9 8 7", "", 1},
        {"", "property uchar flags\n", "", " 5", 1},
        {"property float nx\nproperty float ny\nproperty float nz\n", "", " 0 0 1", "", 0},
        {"", "", "", "", 0},
    };
    char text[1024], hdr[512], name[32];
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        snprintf(hdr, sizeof hdr, head, cases[i].v, cases[i].f);
        snprintf(text, sizeof text, "%s0 0 0%s\n1 0 0%s\n0 1 0%s\n3 0 1 2%s\n", hdr, cases[i].vals,
                 cases[i].vals, cases[i].vals, cases[i].fval);
        snprintf(name, sizeof name, "props%zu.ply", i);
        fp_mesh *m = NULL;
        if (fp_mesh_load(write_tmp(name, text), &m, err, sizeof err)) fail_msg("%s", err);
        for (int fmt = 0; fmt < 2; fmt++) {
            unsigned dropped = 0;
            assert_int_equal(fp_mesh_save_ex(m, tmp_path(fmt ? "props-out.obj" : "props-out.ply"), &dropped,
                                             err, sizeof err), FP_MESH_OK);
            if (((dropped & FP_MESH_DROPPED_PROPERTIES) != 0) != cases[i].other)
                fail_msg("case %zu to %s: dropped %#x", i, fmt ? "obj" : "ply", dropped);
        }
        fp_mesh_free(&m);
    }
    fp_mesh *m = NULL;
    if (fp_mesh_load(write_tmp("colours.off", "COFF\n3 1 0\n0 0 0 1 0 0 1\n1 0 0 1 0 0 1\n"
                                              "0 1 0 1 0 0 1\n3 0 1 2\n"), &m, err, sizeof err))
        fail_msg("%s", err);
    unsigned dropped = 0;
    assert_int_equal(fp_mesh_save_ex(m, tmp_path("colours-out.off"), &dropped, err, sizeof err), FP_MESH_OK);
    assert_true(dropped & FP_MESH_DROPPED_PROPERTIES);
    fp_mesh_free(&m);
    /* an OBJ's vertex colours: kept written back as OBJ (its text), dropped in a PLY */
    if (fp_mesh_load(write_tmp("colours.obj", "v 0 0 0 1 0 0\nv 1 0 0 1 0 0\nv 0 1 0 1 0 0\nf 1 2 3\n"),
                     &m, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(fp_mesh_save_ex(m, tmp_path("colours-out.obj"), &dropped, err, sizeof err), FP_MESH_OK);
    assert_false(dropped & FP_MESH_DROPPED_PROPERTIES);
    assert_int_equal(fp_mesh_save_ex(m, tmp_path("colours-out.ply"), &dropped, err, sizeof err), FP_MESH_OK);
    assert_true(dropped & FP_MESH_DROPPED_PROPERTIES);
    fp_mesh_free(&m);
    char what[256];
    assert_non_null(strstr(fp_mesh_dropped_text(FP_MESH_DROPPED_PROPERTIES, what, sizeof what),
                           "vertex and face properties"));
}

/* The codes are the project's negative errno values; a missing and an unreadable file. */
static void test_error_codes(void **state)
{
    (void)state;
    expect_load_error(tmp_path("missing.ply"), FP_MESH_ERR_NOENT, "No such file");
    const char *p = write_tmp("unreadable.obj", "v 0 0 0\n");
    assert_int_equal(chmod(p, 0), 0);
    if (geteuid() != 0) /* root reads anything */
        expect_load_error(p, FP_MESH_ERR_ACCESS, "Permission denied");
    assert_int_equal(FP_MESH_ERR_FORMAT, -EBADMSG);
    assert_int_equal(FP_MESH_ERR_IO, -EIO);
    assert_int_equal(FP_MESH_ERR_UNSUPPORTED, -ENOTSUP);
    assert_int_equal(FP_MESH_ERR_NOMEM, -ENOMEM);
    assert_int_equal(FP_MESH_ERR_INVALID, -EINVAL);
    assert_string_equal(fp_mesh_strerror(FP_MESH_ERR_NOENT), strerror(ENOENT));
}

/* ---- saves are never half-written ----------------------------------------------------- */

static fp_mesh *grid_mesh(size_t side, float z)
{
    fp_mesh *m = fp_mesh_create(side * side, 2 * (side - 1) * (side - 1), 1);
    assert_non_null(m);
    for (size_t j = 0; j < side; j++)
        for (size_t i = 0; i < side; i++) {
            float *q = m->positions + 3 * (j * side + i);
            q[0] = (float)i;
            q[1] = (float)j;
            q[2] = z + 0.001f * (float)((i * 7 + j * 13) % 17);
            m->uvs[2 * (j * side + i)] = (float)i / (float)side;
            m->uvs[2 * (j * side + i) + 1] = (float)j / (float)side;
        }
    size_t k = 0;
    for (size_t j = 0; j + 1 < side; j++)
        for (size_t i = 0; i + 1 < side; i++) {
            uint32_t a = (uint32_t)(j * side + i), b = a + 1, c = a + (uint32_t)side, d = c + 1;
            uint32_t t[6] = {a, b, d, a, d, c};
            memcpy(m->triangles + 6 * k++, t, sizeof t);
        }
    assert_int_equal(fp_mesh_compute_normals(m), FP_MESH_OK);
    return m;
}

/* fp_mesh_outlier_mask: a grid has none (used stays NULL); one vertex pulled 20 units out of
 * a 0.016-unit relief is cleared, alone, and a mask given keeps its zeros; a grid of one depth
 * (every z equal: the selection over equal values) clears the pulled vertex too. */
static void test_outlier_mask(void **state)
{
    (void)state;
    fp_mesh *m = grid_mesh(30, 0);
    uint8_t *used = NULL;
    size_t far = 99;
    assert_int_equal(fp_mesh_outlier_mask(m, &used, &far), 0);
    assert_null(used);
    assert_int_equal(far, 0);
    m->positions[3 * 17 + 2] = 20;
    assert_int_equal(fp_mesh_outlier_mask(m, &used, &far), 0);
    assert_non_null(used);
    assert_int_equal(far, 1);
    for (size_t v = 0; v < m->vertex_count; v++) assert_int_equal(used[v], v != 17);
    memset(used, 1, m->vertex_count);
    used[5] = 0;
    assert_int_equal(fp_mesh_outlier_mask(m, &used, &far), 0);
    assert_int_equal(far, 1);
    for (size_t v = 0; v < m->vertex_count; v++) assert_int_equal(used[v], v != 17 && v != 5);
    free(used);
    used = NULL;
    for (size_t v = 0; v < m->vertex_count; v++) m->positions[3 * v + 2] = v == 17 ? 20.0f : 1.0f;
    assert_int_equal(fp_mesh_outlier_mask(m, &used, &far), 0);
    assert_int_equal(far, 1);
    assert_non_null(used);
    assert_int_equal(used[17], 0);
    free(used);
    fp_mesh_free(&m);
}

/* fp_mesh_face_mask: a vertex in no triangle (0, its two triangles moved off it) and one far
 * off (17, pulled 20 units out) are both cleared and counted apart; fp_mesh_median_edge: the
 * grid's edges are 1 (two of three) and sqrt 2, median 1, with or without the mask. */
static void test_face_mask_and_median_edge(void **state)
{
    (void)state;
    fp_mesh *m = grid_mesh(30, 0);
    double edge = 0;
    assert_int_equal(fp_mesh_median_edge(m, NULL, &edge), 0);
    assert_float_equal(edge, 1.0, 1e-3);
    uint8_t *used = NULL;
    size_t unused = 99, far = 99;
    assert_int_equal(fp_mesh_face_mask(m, &used, &unused, &far), 0);
    assert_null(used);
    assert_int_equal(unused + far, 0);
    for (size_t i = 0; i < 6; i++)
        if (m->triangles[i] == 0) m->triangles[i] = 1;
    m->positions[3 * 17 + 2] = 20;
    assert_int_equal(fp_mesh_face_mask(m, &used, &unused, &far), 0);
    assert_non_null(used);
    assert_int_equal(unused, 1);
    assert_int_equal(far, 1);
    for (size_t v = 0; v < m->vertex_count; v++) assert_int_equal(used[v], v != 0 && v != 17);
    assert_int_equal(fp_mesh_median_edge(m, used, &edge), 0);
    assert_float_equal(edge, 1.0, 1e-3);
    free(used);
    fp_mesh_free(&m);
}

static int same_positions(const fp_mesh *a, const fp_mesh *b)
{
    return a->vertex_count == b->vertex_count && a->triangle_count == b->triangle_count &&
           !memcmp(a->positions, b->positions, a->vertex_count * 3 * sizeof(float)) &&
           !memcmp(a->triangles, b->triangles, a->triangle_count * 3 * sizeof(uint32_t));
}

static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)n + 1);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *len = (size_t)n;
    return b;
}

static size_t count_temp_files(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    size_t n = 0;
    struct dirent *de;
    while ((de = readdir(d)))
        n += de->d_name[0] == '.' && strcmp(de->d_name, ".") && strcmp(de->d_name, "..");
    closedir(d);
    return n;
}

/* A save whose writes fail leaves the old file byte for byte and no temporary file. The write
 * failure comes from RLIMIT_FSIZE (EFBIG, -EIO) in a child, and, where the test may mount
 * one (root), from a full 64 KiB tmpfs (ENOSPC, -ENOSPC). */
static void test_save_failure_keeps_old_file(void **state)
{
    (void)state;
    char dir[600];
    snprintf(dir, sizeof dir, "%s/full", tmpdir);
    assert_int_equal(mkdir(dir, 0700), 0);
    fp_mesh *small = icosahedron(), *big = grid_mesh(120, 1.0f);
    const char *exts[] = {"ply", "obj", "glb"};
    for (int e = 0; e < 3; e++) {
        char path[700];
        snprintf(path, sizeof path, "%s/out.%s", dir, exts[e]);
        assert_int_equal(fp_mesh_save(small, path, err, sizeof err), FP_MESH_OK);
        size_t len0;
        char *before = slurp(path, &len0);
        fflush(NULL);
        pid_t pid = fork();
        assert_true(pid >= 0);
        if (pid == 0) {
            signal(SIGXFSZ, SIG_IGN);
            struct rlimit rl = {4096, 4096};
            setrlimit(RLIMIT_FSIZE, &rl);
            char e2[1024] = "";
            int rc = fp_mesh_save(big, path, e2, sizeof e2);
            _exit(rc == FP_MESH_ERR_IO && strstr(e2, path) && strstr(e2, "unchanged") ? 0 : 1);
        }
        int status;
        assert_int_equal(waitpid(pid, &status, 0), pid);
        assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
        size_t len1;
        char *after = slurp(path, &len1);
        assert_int_equal(len0, len1);
        assert_memory_equal(before, after, len0);
        free(before);
        free(after);
        assert_int_equal(count_temp_files(dir), 0);
    }
    /* a real full disk */
    char mnt[700];
    snprintf(mnt, sizeof mnt, "%s/tmpfs", tmpdir);
    assert_int_equal(mkdir(mnt, 0700), 0);
    if (geteuid() == 0 && mount("fp_mesh_test", mnt, "tmpfs", 0, "size=64k") == 0) {
        char path[800];
        snprintf(path, sizeof path, "%s/out.ply", mnt);
        assert_int_equal(fp_mesh_save(small, path, err, sizeof err), FP_MESH_OK);
        size_t len0;
        char *before = slurp(path, &len0);
        int rc = fp_mesh_save(big, path, err, sizeof err);
        size_t len1;
        char *after = slurp(path, &len1);
        size_t temps = count_temp_files(mnt);
        umount(mnt);
        assert_int_equal(rc, FP_MESH_ERR_NOSPACE);
        assert_non_null(strstr(err, path));
        assert_non_null(strstr(err, "No space left"));
        assert_int_equal(len0, len1);
        assert_memory_equal(before, after, len0);
        assert_int_equal(temps, 0);
        free(before);
        free(after);
    } else {
        print_message("(no tmpfs could be mounted here: the ENOSPC case is not run)\n");
    }
    fp_mesh_free(&small);
    fp_mesh_free(&big);
}

/* SIGKILL a child that saves two different big meshes over the same file again and again:
 * whenever it dies, the file is one of the two meshes, complete. */
static void test_save_survives_sigkill(void **state)
{
    (void)state;
    fp_mesh *a = grid_mesh(300, 0.0f), *b = grid_mesh(300, 5.0f);
    const char *path = tmp_path("kill.ply");
    assert_int_equal(fp_mesh_save(a, path, err, sizeof err), FP_MESH_OK);
    srand(16);
    int saw_a = 0, saw_b = 0;
    for (int round = 0; round < 12; round++) {
        fflush(NULL);
        pid_t pid = fork();
        assert_true(pid >= 0);
        if (pid == 0) {
            for (int k = 0;; k++)
                fp_mesh_save(k % 2 ? a : b, path, NULL, 0);
        }
        usleep((useconds_t)(20000 + rand() % 150000));
        kill(pid, SIGKILL);
        int status;
        assert_int_equal(waitpid(pid, &status, 0), pid);
        fp_mesh *m = NULL;
        int rc = fp_mesh_load(path, &m, err, sizeof err);
        if (rc)
            fail_msg("round %d: the file is broken after SIGKILL: %s", round, err);
        int is_a = same_positions(m, a), is_b = same_positions(m, b);
        assert_true(is_a || is_b);
        saw_a += is_a;
        saw_b += is_b;
        fp_mesh_free(&m);
    }
    /* temporary files left by kills show that kills landed inside saves */
    print_message("after 12 kills: %d times the first mesh, %d times the second, %zu "
                  "temporary files left by killed saves\n", saw_a, saw_b,
                  count_temp_files(tmpdir));
    fp_mesh_free(&a);
    fp_mesh_free(&b);
}

/* ---- threads ------------------------------------------------------------------------- */

static void *load_many(void *arg)
{
    const char *path = arg;
    for (int i = 0; i < 4; i++) {
        fp_mesh *m = NULL;
        char e[256];
        if (fp_mesh_load(path, &m, e, sizeof e) != FP_MESH_OK || m->vertex_count != 468)
            return (void *)1;
        fp_mesh_free(&m);
    }
    return NULL;
}

static void test_concurrent_loads(void **state)
{
    (void)state;
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(face_path("mediapipe-canonical/canonical_face_model.obj"), &m,
                                  err, sizeof err),
                     FP_MESH_OK);
    char *paths[4] = {strdup(tmp_path("c.ply")), strdup(tmp_path("c.off")),
                      strdup(tmp_path("c.glb")), strdup(tmp_path("c.obj"))};
    for (int i = 0; i < 4; i++)
        assert_int_equal(fp_mesh_save(m, paths[i], err, sizeof err), FP_MESH_OK);
    pthread_t th[4];
    for (int i = 0; i < 4; i++)
        assert_int_equal(pthread_create(&th[i], NULL, load_many, paths[i]), 0);
    for (int i = 0; i < 4; i++) {
        void *ret;
        pthread_join(th[i], &ret);
        assert_null(ret);
        free(paths[i]);
    }
    fp_mesh_free(&m);
}


/* ---- strictness (a second hostile-input sweep): wrong files that loaded without a word -- */

static const char *write_bytes(const char *name, const void *data, size_t len)
{
    const char *p = tmp_path(name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, len, f), len);
    fclose(f);
    return p;
}

/* buf (len bytes, room for `room`) with the first `from` replaced by `to`; the new length. */
static size_t replace_once(char *buf, size_t len, size_t room, const char *from, const char *to)
{
    char *at = NULL;
    for (size_t i = 0; i + strlen(from) <= len && !at; i++)
        if (!memcmp(buf + i, from, strlen(from)))
            at = buf + i;
    if (!at)
        fail_msg("'%s' not found", from);
    const size_t fl = strlen(from), tl = strlen(to);
    assert_true(len - fl + tl <= room);
    memmove(at + tl, at + fl, len - (size_t)(at - buf) - fl);
    memcpy(at, to, tl);
    return len - fl + tl;
}

/* The canonical face (a real mesh) saved as a binary PLY: its bytes (malloc'ed) and the mesh. */
static char *canonical_ply(size_t *len, fp_mesh **mesh)
{
    assert_int_equal(fp_mesh_load(face_path("mediapipe-canonical/canonical_face_model.obj"),
                                  mesh, err, sizeof err),
                     FP_MESH_OK);
    assert_int_equal(fp_mesh_save(*mesh, tmp_path("canon.ply"), err, sizeof err), FP_MESH_OK);
    char *b = slurp(tmp_path("canon.ply"), len);
    char *room = realloc(b, *len + 512);
    assert_non_null(room);
    return room;
}

/* 1. A PLY vertex element without x, y or z: OpenMesh read the missing coordinate as 0 (a
 * binary file loaded flattened). Refused naming the property; a repeated one too. */
static void test_ply_vertex_needs_xyz(void **state)
{
    (void)state;
    size_t len;
    fp_mesh *ref = NULL;
    char *ply = canonical_ply(&len, &ref);
    const char *axes[] = {"x", "y", "z"};
    for (int k = 0; k < 3; k++) {
        char *b = malloc(len + 512);
        memcpy(b, ply, len);
        char from[32], to[32], want[64], name[32];
        snprintf(from, sizeof from, "property float %s\n", axes[k]);
        snprintf(to, sizeof to, "property float q\n");
        size_t n = replace_once(b, len, len + 512, from, to);
        snprintf(name, sizeof name, "no_%s.ply", axes[k]);
        snprintf(want, sizeof want, "line 3: the vertex element has no property '%s'", axes[k]);
        expect_load_error(write_bytes(name, b, n), FP_MESH_ERR_FORMAT, want);
        free(b);
    }
    /* the same in ASCII, and a repeated property */
    expect_load_error(write_tmp("no_z.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
                                            "property float x\nproperty float y\n"
                                            "property float w\nelement face 1\n"
                                            "property list uchar int vertex_indices\n"
                                            "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                      FP_MESH_ERR_FORMAT, "no property 'z'");
    expect_load_error(write_tmp("two_x.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
                                             "property float x\nproperty float y\n"
                                             "property float z\nproperty float x\n"
                                             "element face 1\n"
                                             "property list uchar int vertex_indices\n"
                                             "end_header\n0 0 0 0\n1 0 0 1\n0 1 0 0\n3 0 1 2\n"),
                      FP_MESH_ERR_FORMAT, "line 7: vertex property 'x' again (first on line 4)");
    /* the file as saved loads, with the face's coordinates */
    fp_mesh *m = NULL;
    assert_int_equal(fp_mesh_load(tmp_path("canon.ply"), &m, err, sizeof err), FP_MESH_OK);
    assert_true(same_positions(m, ref));
    fp_mesh_free(&m);
    fp_mesh_free(&ref);
    free(ply);
}

/* 6. PLY allows comment and obj_info lines anywhere in the header; before end_header of a
 * binary file they were refused, obj_info anywhere. They load, to the same mesh. */
static void test_ply_comments_anywhere(void **state)
{
    (void)state;
    size_t len;
    fp_mesh *ref = NULL;
    char *b = canonical_ply(&len, &ref);
    const size_t room = len + 512;
    len = replace_once(b, len, room, "ply\n", "ply\ncomment before the format\n");
    len = replace_once(b, len, room, "1.0\n",
                       "1.0\nobj_info element vertex 99 end_header property\n");
    len = replace_once(b, len, room, "property float y\n",
                       "property float y\ncomment between properties\n");
    len = replace_once(b, len, room, "end_header\n",
                       "comment right before end_header\nobj_info scanned\nend_header\n");
    fp_mesh *m = NULL;
    int rc = fp_mesh_load(write_bytes("notes.ply", b, len), &m, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    assert_true(same_positions(m, ref));
    assert_memory_equal(m->uvs, ref->uvs, 2 * ref->vertex_count * sizeof(float));
    fp_mesh_free(&m);
    /* ASCII, a CRLF comment line before end_header */
    rc = fp_mesh_load(write_tmp("notes_ascii.ply",
                                "ply\nformat ascii 1.0\nobj_info by hand\nelement vertex 3\n"
                                "property float x\nproperty float y\nproperty float z\n"
                                "element face 1\nproperty list uchar int vertex_indices\n"
                                "comment the end\r\nend_header\n0 0 0\n1 0 0\n0 2 0\n3 0 1 2\n"),
                      &m, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    assert_int_equal(m->vertex_count, 3);
    assert_true(m->positions[3] == 1.0f && m->positions[7] == 2.0f);
    fp_mesh_free(&m);
    fp_mesh_free(&ref);
    free(b);
}

/* 7. Binary PLY face errors name the byte where the bad value is (they cited the header's
 * last line); ASCII ones keep their line. */
static void test_ply_binary_errors_cite_bytes(void **state)
{
    (void)state;
    static const char hdr[] = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                              "property float x\nproperty float y\nproperty float z\n"
                              "element face 2\nproperty list uchar int vertex_indices\n"
                              "end_header\n";
    const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    unsigned char buf[256];
    const size_t h = strlen(hdr);
    memcpy(buf, hdr, h);
    memcpy(buf + h, v, sizeof v);
    size_t n = h + sizeof v;
    const size_t face0 = n;
    const int32_t good[3] = {0, 1, 2}, bad[3] = {0, 1, 7};
    buf[n++] = 3;
    memcpy(buf + n, good, sizeof good);
    n += sizeof good;
    const size_t face1 = n;
    buf[n++] = 3;
    memcpy(buf + n, bad, sizeof bad);
    n += sizeof bad;
    char want[128];
    snprintf(want, sizeof want, "byte %zu: face 1 references vertex 7, but the file has 3",
             face1 + 1 + 2 * sizeof(int32_t));
    expect_load_error(write_bytes("badref.ply", buf, n), FP_MESH_ERR_FORMAT, want);
    assert_null(strstr(err, "line"));
    buf[face1] = 2; /* two corners: the last index becomes a trailing byte count problem */
    snprintf(want, sizeof want, "byte %zu: face 1 has 2 corners", face1);
    expect_load_error(write_bytes("twocorners.ply", buf, n), FP_MESH_ERR_FORMAT, want);
    buf[face1] = 3;
    memcpy(buf + face0 + 1, bad, sizeof bad); /* face 0 bad too: the first is named */
    snprintf(want, sizeof want, "byte %zu: face 0 references vertex 7",
             face0 + 1 + 2 * sizeof(int32_t));
    expect_load_error(write_bytes("badref0.ply", buf, n), FP_MESH_ERR_FORMAT, want);
    expect_load_error(write_tmp("badref.ply.txt.ply",
                                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                "property float y\nproperty float z\nelement face 1\n"
                                "property list uchar int vertex_indices\nend_header\n"
                                "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
                      FP_MESH_ERR_FORMAT, "line 13: face 0 references vertex 7");
}

/* A one-triangle glTF with indices, UVs and a node translation, its buffer in strict.bin;
 * strict_gltf writes it with `from`/`to` replacements (NULL-terminated pairs). */
static const char strict_json[] =
    "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
    "\"nodes\":[{\"mesh\":0,\"translation\":[1,2,3]}],"
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":2},"
    "\"indices\":1}]}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
    "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"},"
    "{\"bufferView\":2,\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},"
    "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6},"
    "{\"buffer\":0,\"byteOffset\":44,\"byteLength\":24}],"
    "\"buffers\":[{\"byteLength\":68,\"uri\":\"strict.bin\"}]}";

static const char *strict_gltf(const char *name, ...)
{
    unsigned char bin[68] = {0};
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, uv[6] = {0.25f, 0.5f, 1, 0, 0, 1};
    const uint16_t idx[3] = {0, 1, 2};
    memcpy(bin, pos, sizeof pos);
    memcpy(bin + 36, idx, sizeof idx);
    memcpy(bin + 44, uv, sizeof uv);
    write_bytes("strict.bin", bin, sizeof bin);
    char json[4096];
    size_t len = strlen(strict_json);
    memcpy(json, strict_json, len);
    va_list ap;
    va_start(ap, name);
    for (const char *from; (from = va_arg(ap, const char *));) {
        const char *to = va_arg(ap, const char *);
        len = replace_once(json, len, sizeof json - 1, from, to);
    }
    va_end(ap);
    return write_bytes(name, json, len);
}

static void test_strict_gltf_loads(void **state)
{
    (void)state;
    fp_mesh *m = NULL;
    int rc = fp_mesh_load(strict_gltf("strict.gltf", NULL), &m, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    const float want[9] = {1, 2, 3, 2, 2, 3, 1, 3, 3}; /* translated by (1, 2, 3) */
    assert_int_equal(m->triangle_count, 1);
    assert_memory_equal(m->positions, want, sizeof want);
    assert_true(m->uvs[0] == 0.25f && m->uvs[1] == 0.5f);
    fp_mesh_free(&m);
    /* extras are free-form: an "indices": -1 there is no index */
    rc = fp_mesh_load(strict_gltf("extras.gltf", "\"scene\":0",
                                  "\"extras\":{\"indices\":-1,\"mesh\":\"x\"},\"scene\":0", NULL),
                      &m, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    fp_mesh_free(&m);
    /* normalised unsigned byte UVs are glTF's: read as value / 255 */
    static const char uv[] = "\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"";
    rc = fp_mesh_load(strict_gltf("uv8.gltf", uv,
                                  "\"componentType\":5121,\"normalized\":true,\"count\":3,"
                                  "\"type\":\"VEC2\"", NULL),
                      &m, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    const float u = 0.25f;
    unsigned char first; /* the first byte of the UV view: the float 0.25's lowest */
    memcpy(&first, &u, 1);
    assert_true(m->uvs[0] == (float)first / 255.0f);
    fp_mesh_free(&m);
}

/* 2. Vertex attributes of component types glTF 2.0 does not allow: a BYTE POSITION loaded
 * its raw bytes as coordinates. FORMAT, or UNSUPPORTED where the file declares
 * KHR_mesh_quantization (legal, not handled). */
static void test_gltf_attribute_component_types(void **state)
{
    (void)state;
    static const char pos[] = "\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"";
    expect_load_error(strict_gltf("pos_byte.gltf", pos,
                                  "\"componentType\":5120,\"count\":3,\"type\":\"VEC3\"", NULL),
                      FP_MESH_ERR_FORMAT,
                      "mesh 0 primitive 0 POSITION accessor 0 has component type 5120 (BYTE); "
                      "glTF 2.0 requires 5126 (FLOAT)");
    expect_load_error(strict_gltf("pos_short.gltf", pos,
                                  "\"componentType\":5122,\"normalized\":true,\"count\":3,"
                                  "\"type\":\"VEC3\"", NULL),
                      FP_MESH_ERR_FORMAT, "component type 5122 (SHORT) normalized");
    expect_load_error(strict_gltf("pos_quant.gltf", pos,
                                  "\"componentType\":5120,\"count\":3,\"type\":\"VEC3\"",
                                  "\"asset\":{", "\"extensionsUsed\":[\"KHR_mesh_quantization\"],"
                                  "\"asset\":{", NULL),
                      FP_MESH_ERR_UNSUPPORTED, "KHR_mesh_quantization is not supported");
    /* UVs: unsigned byte/short only normalised */
    static const char uv[] = "\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"";
    expect_load_error(strict_gltf("uv_raw.gltf", uv,
                                  "\"componentType\":5121,\"count\":3,\"type\":\"VEC2\"", NULL),
                      FP_MESH_ERR_FORMAT, "TEXCOORD_0 accessor 2 has component type 5121");
}

/* 3. An index that is no index: tinygltf read "indices": -1 (or -7, 0.5, 4294967295) as
 * absent, and the primitive loaded non-indexed; "mesh": -1 dropped the node's mesh. */
static void test_gltf_bad_index_fields(void **state)
{
    (void)state;
    static const struct { const char *to, *want; } cases[] = {
        {"\"indices\":-1", "meshes[0].primitives[0].indices is -1, not an index"},
        {"\"indices\":-7", "meshes[0].primitives[0].indices is -7"},
        {"\"indices\":0.5", "meshes[0].primitives[0].indices is 0.5"},
        {"\"indices\":4294967295", "meshes[0].primitives[0].indices is 4294967295"},
        {"\"indices\":\"1\"", "meshes[0].primitives[0].indices is a string"},
        {"\"indices\":7", "indices accessor out of bounds"}, /* tinygltf's own check */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char name[32];
        snprintf(name, sizeof name, "idx%zu.gltf", i);
        expect_load_error(strict_gltf(name, "\"indices\":1", cases[i].to, NULL),
                          FP_MESH_ERR_FORMAT, cases[i].want);
    }
    /* no indices: the vertices in threes; two are no triangle, and the message said "2
     * indices" of a primitive that has none */
    expect_load_error(strict_gltf("noidx.gltf", ",\"indices\":1", "", "\"POSITION\":0,\"TEXCOORD_0\":2",
                                  "\"POSITION\":0", "\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"",
                                  "\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"", NULL),
                      FP_MESH_ERR_FORMAT, "mesh 0 primitive 0 has 2 vertices and no indices, not a multiple of 3");
    expect_load_error(strict_gltf("mesh_neg.gltf", "\"mesh\":0", "\"mesh\":-1", NULL),
                      FP_MESH_ERR_FORMAT, "nodes[0].mesh is -1");
    expect_load_error(strict_gltf("attr_neg.gltf", "\"POSITION\":0", "\"POSITION\":-1", NULL),
                      FP_MESH_ERR_FORMAT, "meshes[0].primitives[0].attributes.POSITION is -1");
    expect_load_error(strict_gltf("scene_neg.gltf", "\"nodes\":[0]", "\"nodes\":[-1]", NULL),
                      FP_MESH_ERR_FORMAT, "scenes[0].nodes[0] is -1");
    expect_load_error(strict_gltf("mat_neg.gltf", "\"indices\":1", "\"indices\":1,\"material\":-1",
                                  NULL),
                      FP_MESH_ERR_FORMAT, "meshes[0].primitives[0].material is -1");
    expect_load_error(strict_gltf("uv1_neg.gltf", "\"TEXCOORD_0\":2",
                                  "\"TEXCOORD_0\":2,\"TEXCOORD_1\":-3", NULL),
                      FP_MESH_ERR_FORMAT, "meshes[0].primitives[0].attributes.TEXCOORD_1 is -3");
}

/* A glTF vertex in no triangle has no normal after the deformation (fp_mesh_compute_normals
 * gives it 0): written back as a zero NORMAL, which glTF forbids (the Khronos validator's
 * ACCESSOR_VECTOR3_NON_UNIT, one error a stray vertex). It keeps the file's unit normal. */
static void test_gltf_unused_vertex_normal(void **state)
{
    (void)state;
    unsigned char bin[104] = {0};
    const float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5}, nrm[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 1, 0, 0};
    const uint16_t idx[3] = {0, 1, 2}; /* vertex 3 in no triangle, its normal +x in the file */
    memcpy(bin, pos, sizeof pos);
    memcpy(bin + 48, nrm, sizeof nrm);
    memcpy(bin + 96, idx, sizeof idx);
    write_bytes("stray.bin", bin, sizeof bin);
    static const char json[] =
        "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1},\"indices\":2}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
        "{\"bufferView\":2,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":48},"
        "{\"buffer\":0,\"byteOffset\":96,\"byteLength\":6}],\"buffers\":[{\"byteLength\":104,\"uri\":\"stray.bin\"}]}";
    const char *first = write_tmp("stray-n.gltf", json), *again = tmp_path("stray-n-out.gltf");
    fp_mesh *m = NULL;
    if (fp_mesh_load(first, &m, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(m->vertex_count, 4);
    assert_int_equal(fp_mesh_compute_normals(m), FP_MESH_OK); /* as the session does each frame */
    m->positions[1] = -0.25f;
    if (fp_mesh_save(m, again, err, sizeof err)) fail_msg("%s", err);
    fp_mesh *back = NULL;
    if (fp_mesh_load(again, &back, err, sizeof err)) fail_msg("%s", err);
    for (int v = 0; v < 4; v++) {
        const float *n = back->normals + 3 * v;
        const float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (fabsf(len - 1) > 1e-5f) fail_msg("vertex %d: normal of length %g written", v, (double)len);
    }
    assert_true(back->normals[9] == 1 && back->normals[10] == 0 && back->normals[11] == 0);
    fp_mesh_free(&back);
    fp_mesh_free(&m);
}

/* 4. GLB header version other than 2: tinygltf never looked. */
static void test_glb_version(void **state)
{
    (void)state;
    fp_mesh *m = icosahedron();
    assert_int_equal(fp_mesh_save(m, tmp_path("v.glb"), err, sizeof err), FP_MESH_OK);
    fp_mesh_free(&m);
    size_t len;
    unsigned char *b = (unsigned char *)slurp(tmp_path("v.glb"), &len);
    assert_memory_equal(b, "glTF\2\0\0\0", 8);
    assert_int_equal(fp_mesh_load(write_bytes("v2.glb", b, len), &m, err, sizeof err),
                     FP_MESH_OK);
    assert_int_equal(m->vertex_count, 12);
    fp_mesh_free(&m);
    b[4] = 1;
    expect_load_error(write_bytes("v1.glb", b, len), FP_MESH_ERR_UNSUPPORTED,
                      "GLB header version 1 (glTF 1.0) is not supported");
    b[4] = 3;
    expect_load_error(write_bytes("v3.glb", b, len), FP_MESH_ERR_FORMAT, "GLB header version 3");
    b[4] = 2;
    b[7] = 1; /* 2 + 2^24 */
    expect_load_error(write_bytes("vbig.glb", b, len), FP_MESH_ERR_FORMAT,
                      "GLB header version 16777218");
    free(b);
    /* a .gltf says its version in asset.version */
    expect_load_error(strict_gltf("v1.gltf", "\"version\":\"2.0\"", "\"version\":\"1.0\"", NULL),
                      FP_MESH_ERR_UNSUPPORTED, "asset.version '1.0' is not supported");
}

/* 5. Node transforms of the wrong length were ignored (the node untransformed), TRS beside a
 * matrix too. Refused naming the node. */
static void test_gltf_node_transform_lengths(void **state)
{
    (void)state;
    static const struct { const char *node, *want; } cases[] = {
        {"{\"mesh\":0,\"matrix\":[1,0,0,0, 0,1,0,0, 0,0,1,0, 5,0,0]}",
         "nodes[0].matrix has 15 numbers, not 16"},
        {"{\"mesh\":0,\"matrix\":[]}", "nodes[0].matrix has 0 numbers, not 16"},
        {"{\"mesh\":0,\"translation\":[5,0]}", "nodes[0].translation has 2 numbers, not 3"},
        {"{\"mesh\":0,\"rotation\":[0,0,0]}", "nodes[0].rotation has 3 numbers, not 4"},
        {"{\"mesh\":0,\"scale\":[2,2,2,2]}", "nodes[0].scale has 4 numbers, not 3"},
        {"{\"mesh\":0,\"scale\":2}", "nodes[0].scale is not an array of numbers"},
        {"{\"mesh\":0,\"translation\":[5,\"0\",0]}", "nodes[0].translation[1] is a string"},
        {"{\"children\":[1]},{\"mesh\":0,\"translation\":[1,2,3],"
         "\"matrix\":[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}",
         "nodes[1] has both a matrix and translation, rotation or scale"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char name[32];
        snprintf(name, sizeof name, "node%zu.gltf", i);
        expect_load_error(transformed_triangle_file(name, cases[i].node), FP_MESH_ERR_FORMAT,
                          cases[i].want);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_load_ict_keeps_vertex_order),
        cmocka_unit_test(test_load_lee_perry_smith),
        cmocka_unit_test(test_load_mediapipe_canonical),
        cmocka_unit_test(test_load_prints_nothing),
        cmocka_unit_test(test_round_trip_obj),
        cmocka_unit_test(test_round_trip_ply),
        cmocka_unit_test(test_round_trip_off),
        cmocka_unit_test(test_round_trip_stl),
        cmocka_unit_test(test_round_trip_gltf),
        cmocka_unit_test(test_round_trip_glb),
        cmocka_unit_test(test_round_trip_upper_case_extension),
        cmocka_unit_test(test_polygons_are_fan_triangulated),
        cmocka_unit_test(test_obj_byte_order_mark),
        cmocka_unit_test(test_obj_negative_indices),
        cmocka_unit_test(test_obj_degenerate_faces),
        cmocka_unit_test(test_normals_outward_on_icosahedron),
        cmocka_unit_test(test_normals_follow_moved_vertices),
        cmocka_unit_test(test_normals_bad_index),
        cmocka_unit_test(test_bounds),
        cmocka_unit_test(test_subdivide),
        cmocka_unit_test(test_gltf_node_transform_applied),
        cmocka_unit_test(test_gltf_instances_saved_apart),
        cmocka_unit_test(test_gltf_unused_vertex_normal),
        cmocka_unit_test(test_gltf_singular_node_saved),
        cmocka_unit_test(test_ply_other_properties_dropped),
        cmocka_unit_test(test_error_missing_file),
        cmocka_unit_test(test_error_empty_file),
        cmocka_unit_test(test_error_malformed_text),
        cmocka_unit_test(test_error_index_out_of_range),
        cmocka_unit_test(test_error_nan_coordinate),
        cmocka_unit_test(test_error_inf_coordinate),
        cmocka_unit_test(test_decimal_coordinates),
        cmocka_unit_test(test_error_gltf_missing_buffer),
        cmocka_unit_test(test_error_gltf_bad_accessor),
        cmocka_unit_test(test_error_unknown_extension),
        cmocka_unit_test(test_error_save),
        cmocka_unit_test(test_concurrent_loads),
        cmocka_unit_test(test_hostile_files_refused),
        cmocka_unit_test(test_gltf_uri_fifo_symlink),
        cmocka_unit_test(test_error_codes),
        cmocka_unit_test(test_obj_mtllib_not_opened),
        cmocka_unit_test(test_obj_scan_fast_paths),
        cmocka_unit_test(test_save_failure_keeps_old_file),
        cmocka_unit_test(test_save_survives_sigkill),
        cmocka_unit_test(test_ply_vertex_needs_xyz),
        cmocka_unit_test(test_ply_comments_anywhere),
        cmocka_unit_test(test_ply_binary_errors_cite_bytes),
        cmocka_unit_test(test_strict_gltf_loads),
        cmocka_unit_test(test_gltf_attribute_component_types),
        cmocka_unit_test(test_gltf_bad_index_fields),
        cmocka_unit_test(test_glb_version),
        cmocka_unit_test(test_gltf_node_transform_lengths),
        cmocka_unit_test(test_outlier_mask),
        cmocka_unit_test(test_face_mask_and_median_edge),
    };
    return cmocka_run_group_tests_name("mesh", tests, setup, teardown);
}
