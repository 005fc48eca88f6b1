/* Test helper: a glTF 2.0 morph-target animation read back with tinygltf (gltf_anim.cpp),
 * independently of core/mesh's writer, for the export tests. */
#ifndef FP_TEST_GLTF_ANIM_H
#define FP_TEST_GLTF_ANIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct fp_test_gltf_anim {
    size_t vertices;         /* N glTF vertices (shared by every primitive) */
    size_t targets;          /* K */
    size_t keys;             /* F animation keys */
    float *base;             /* N x 3 POSITION */
    float *target;           /* K x N x 3 */
    float *times;            /* F */
    float *weights;          /* F x K */
    int step;                /* STEP sampler */
    uint32_t *source_vertex; /* N: the mesh vertex of each glTF vertex (seamCopyOf) */
    size_t primitives, materials, nodes, target_names, triangles;
    double unit_scale;       /* the scale from the mesh's node to the scene (the product of
                                the uniform scales of it and its ancestors; 1: none), or -1
                                when a node on that path has a non-uniform scale, a
                                translation or a matrix, or more than one rotation */
    double rotation[4];      /* the one node rotation on that path (x, y, z, w; the export's
                                root turns the face's up to +y and front to +z), else 0 0 0 1 */
    double frame_rate;       /* asset.extras.frameRate; 0 where it is not there */
    char material_names[1024]; /* "a,b,c" */
} fp_test_gltf_anim;

/** Load path (.gltf/.glb). Returns 0, or -1 with a message in err. */
int fp_test_gltf_anim_load(const char *path, size_t mesh_vertices, fp_test_gltf_anim *a,
                           char *err, size_t errlen);
/** The weights at time t (seconds) by the sampler's interpolation (glTF 2.0 3.11). */
void fp_test_gltf_anim_weights(const fp_test_gltf_anim *a, double t, float *w);
void fp_test_gltf_anim_free(fp_test_gltf_anim *a);

#ifdef __cplusplus
}
#endif
#endif
