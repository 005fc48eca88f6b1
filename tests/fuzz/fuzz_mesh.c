/* libFuzzer target for one mesh format (FP_FUZZ_EXT, set by tests/fuzz/CMakeLists.txt).
 * Each input is written to a file of that extension in a private mkdtemp() folder and
 * loaded with fp_mesh_load(), the path every user file takes (OpenMesh reads by file name).
 * A successful load must give a consistent mesh: indices in range, finite positions, unit or
 * zero normals, finite UVs; anything else aborts, as does any sanitizer report. */
#define _POSIX_C_SOURCE 200809L
#include "fp_mesh.h"

#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char dir[64];
static char path[128];

static void cleanup(void)
{
    unlink(path);
    rmdir(dir);
}

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/fp_fuzz_XXXXXX", tmp && strlen(tmp) < 40 ? tmp : "/tmp");
    if (!mkdtemp(dir))
        abort();
    snprintf(path, sizeof path, "%s/input.%s", dir, FP_FUZZ_EXT);
    atexit(cleanup);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd < 0)
        abort();
    for (size_t off = 0; off < size;) {
        ssize_t put = write(fd, data + off, size - off);
        if (put <= 0)
            abort();
        off += (size_t)put;
    }
    close(fd);
    fp_mesh *m = NULL;
    char err[512];
    int rc = fp_mesh_load(path, &m, err, sizeof err);
    if (rc == FP_MESH_OK) {
        if (!m || m->vertex_count == 0 || m->triangle_count == 0 || !m->normals)
            abort();
        for (size_t i = 0; i < 3 * m->triangle_count; i++)
            if (m->triangles[i] >= m->vertex_count)
                abort();
        for (size_t v = 0; v < m->vertex_count; v++) {
            const float *p = m->positions + 3 * v, *n = m->normals + 3 * v;
            if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
                abort();
            double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
            if (!(len == 0 || fabs(len - 1) < 1e-3))
                abort();
            if (m->uvs && (!isfinite(m->uvs[2 * v]) || !isfinite(m->uvs[2 * v + 1])))
                abort();
        }
        /* `info`'s summary of a glTF document: any index it follows may be hostile */
        fp_mesh_gltf_info g;
        int gs = fp_mesh_gltf_summary(m, &g);
        const int gltf = !strcmp(FP_FUZZ_EXT, "gltf") || !strcmp(FP_FUZZ_EXT, "glb");
        if (gltf ? gs != FP_MESH_OK : gs != FP_MESH_ERR_INVALID)
            abort();
    } else {
        /* a refusal: a negative errno code, no mesh, a message naming the file */
        if (rc >= 0 || m || !strstr(err, path))
            abort();
    }
    fp_mesh_free(&m);
    return 0;
}
