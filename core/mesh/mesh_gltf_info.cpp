// What a loaded glTF held beyond the triangles (fp_mesh_gltf_summary, fp_mesh.h): counts of
// nodes, meshes and materials, the morph targets, the animations' channels and keys, and the
// rate and unit the project's exports name in asset.extras, read from the document the
// loader keeps in the mesh's source (tinygltf's model).
#include "mesh_io_internal.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace {

double extras_number(const tinygltf::Value &extras, const char *key)
{
    if (!extras.IsObject() || !extras.Has(key)) return 0;
    const tinygltf::Value &v = extras.Get(key);
    return v.IsNumber() ? v.GetNumberAsDouble() : 0;
}

// The uniform scale of the default scene's one root node (1 where it has none; 0 where the
// scene has several roots or the root's scale is not uniform or it has a matrix).
double root_scale(const tinygltf::Model &m)
{
    int scene = m.defaultScene >= 0 ? m.defaultScene : (m.scenes.empty() ? -1 : 0);
    if (scene < 0 || size_t(scene) >= m.scenes.size() || m.scenes[size_t(scene)].nodes.size() != 1) return 0;
    int ni = m.scenes[size_t(scene)].nodes[0];
    if (ni < 0 || size_t(ni) >= m.nodes.size()) return 0;
    const tinygltf::Node &n = m.nodes[size_t(ni)];
    if (!n.matrix.empty()) return 0;
    if (n.scale.empty()) return 1;
    if (n.scale.size() != 3 || n.scale[0] != n.scale[1] || n.scale[1] != n.scale[2]) return 0;
    return n.scale[0];
}

} // namespace

extern "C" int fp_mesh_gltf_summary(const fp_mesh *mesh, fp_mesh_gltf_info *out)
{
    if (!mesh || !out) return FP_MESH_ERR_INVALID;
    std::memset(out, 0, sizeof *out);
    const fp_mesh_source *src = mesh->source;
    if (!src || !src->model) return FP_MESH_ERR_INVALID;
    const tinygltf::Model &m = *src->model;
    out->nodes = m.nodes.size();
    out->meshes = m.meshes.size();
    out->materials = m.materials.size();
    for (const tinygltf::Mesh &me : m.meshes)
        for (const tinygltf::Primitive &p : me.primitives)
            out->morph_targets = std::max(out->morph_targets, p.targets.size());
    out->animations = m.animations.size();
    for (const tinygltf::Animation &a : m.animations) {
        out->channels += a.channels.size();
        for (const tinygltf::AnimationChannel &c : a.channels) {
            if (c.target_path == "weights") out->weights_channels++;
            if (c.sampler < 0 || size_t(c.sampler) >= a.samplers.size()) continue;
            int in = a.samplers[size_t(c.sampler)].input;
            if (in < 0 || size_t(in) >= m.accessors.size()) continue;
            const tinygltf::Accessor &acc = m.accessors[size_t(in)];
            out->keys = std::max(out->keys, size_t(acc.count));
            if (!acc.maxValues.empty()) out->duration_s = std::max(out->duration_s, acc.maxValues[0]);
        }
    }
    if (!m.animations.empty())
        std::snprintf(out->animation, sizeof out->animation, "%s", m.animations[0].name.c_str());
    std::snprintf(out->generator, sizeof out->generator, "%s", m.asset.generator.c_str());
    out->frame_rate = extras_number(m.asset.extras, "frameRate");
    out->metres_per_unit = extras_number(m.asset.extras, "metresPerUnit");
    out->root_scale = root_scale(m);
    return FP_MESH_OK;
}
