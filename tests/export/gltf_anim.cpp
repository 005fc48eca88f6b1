// Test helper: read a glTF morph-target animation back with tinygltf (gltf_anim.h). It only
// trusts the file: accessors through their buffer views, strides and offsets as the spec
// says, the sampler evaluated here (not by core/mesh).
#include "gltf_anim.h"

#include <tiny_gltf.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {
bool read_floats(const tinygltf::Model &m, int ai, int comps, std::vector<float> &out,
                 std::string &why)
{
    if (ai < 0 || size_t(ai) >= m.accessors.size()) { why = "no accessor"; return false; }
    const tinygltf::Accessor &a = m.accessors[size_t(ai)];
    if (a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT ||
        tinygltf::GetNumComponentsInType(uint32_t(a.type)) != comps || a.sparse.isSparse) {
        why = "accessor " + std::to_string(ai) + " is not float x " + std::to_string(comps);
        return false;
    }
    const tinygltf::BufferView &bv = m.bufferViews[size_t(a.bufferView)];
    const tinygltf::Buffer &b = m.buffers[size_t(bv.buffer)];
    const size_t stride = bv.byteStride ? bv.byteStride : size_t(4 * comps);
    if (bv.byteOffset + a.byteOffset + (a.count ? (a.count - 1) * stride + 4 * size_t(comps) : 0) >
        b.data.size()) { why = "accessor out of its buffer"; return false; }
    out.resize(a.count * size_t(comps));
    for (size_t i = 0; i < a.count; i++)
        std::memcpy(&out[i * size_t(comps)], b.data.data() + bv.byteOffset + a.byteOffset + i * stride,
                    4 * size_t(comps));
    return true;
}
} // namespace

extern "C" int fp_test_gltf_anim_load(const char *path, size_t mesh_vertices,
                                      fp_test_gltf_anim *a, char *err, size_t errlen)
{
    std::memset(a, 0, sizeof *a);
    tinygltf::TinyGLTF loader;
    tinygltf::Model m;
    std::string e, w, why;
    const std::string p = path;
    const bool glb = p.size() > 4 && p.compare(p.size() - 4, 4, ".glb") == 0;
    bool ok = glb ? loader.LoadBinaryFromFile(&m, &e, &w, p) : loader.LoadASCIIFromFile(&m, &e, &w, p);
    auto fail = [&](const std::string &msg) {
        std::snprintf(err, errlen, "%s: %s", path, msg.c_str());
        fp_test_gltf_anim_free(a);
        return -1;
    };
    if (!ok) return fail("tinygltf: " + e);
    if (m.meshes.size() != 1 || m.animations.size() != 1) return fail("want one mesh, one animation");
    const tinygltf::Mesh &mesh = m.meshes[0];
    a->primitives = mesh.primitives.size();
    a->materials = m.materials.size();
    a->nodes = m.nodes.size();
    for (size_t i = 0; i < m.materials.size(); i++) {
        size_t k = std::strlen(a->material_names);
        std::snprintf(a->material_names + k, sizeof a->material_names - k, "%s%s", i ? "," : "",
                      m.materials[i].name.c_str());
    }
    if (mesh.extras.Has("targetNames")) a->target_names = mesh.extras.Get("targetNames").ArrayLen();
    // every primitive's vertices appended, as a reader builds one mesh from them
    std::vector<float> base, tg;
    a->targets = mesh.primitives.at(0).targets.size();
    std::vector<std::vector<float>> per_target(a->targets);
    for (const auto &pr : mesh.primitives) {
        std::vector<float> b;
        if (!read_floats(m, pr.attributes.at("POSITION"), 3, b, why)) return fail(why);
        base.insert(base.end(), b.begin(), b.end());
        if (pr.targets.size() != a->targets) return fail("primitives differ in targets");
        for (size_t k = 0; k < a->targets; k++) {
            std::vector<float> t;
            if (!read_floats(m, pr.targets[k].at("POSITION"), 3, t, why)) return fail(why);
            if (t.size() != b.size()) return fail("target size differs");
            per_target[k].insert(per_target[k].end(), t.begin(), t.end());
        }
        const tinygltf::Accessor &ia = m.accessors[size_t(pr.indices)];
        a->triangles += ia.count / 3;
    }
    a->vertices = base.size() / 3;
    for (size_t k = 0; k < a->targets; k++) tg.insert(tg.end(), per_target[k].begin(), per_target[k].end());
    const tinygltf::Animation &an = m.animations[0];
    if (an.channels.size() != 1 || an.channels[0].target_path != "weights" ||
        an.channels[0].target_node < 0 || m.nodes[size_t(an.channels[0].target_node)].mesh != 0)
        return fail("want one weights channel on the mesh's node");
    const tinygltf::AnimationSampler &s = an.samplers[size_t(an.channels[0].sampler)];
    std::vector<float> times, weights;
    if (!read_floats(m, s.input, 1, times, why) || !read_floats(m, s.output, 1, weights, why))
        return fail(why);
    a->keys = times.size();
    if (weights.size() != a->keys * a->targets) return fail("weights count is not keys x targets");
    a->step = s.interpolation == "STEP";
    a->base = (float *)std::malloc(base.size() * 4);
    a->target = (float *)std::malloc(tg.size() * 4 + 4);
    a->times = (float *)std::malloc(times.size() * 4);
    a->weights = (float *)std::malloc(weights.size() * 4 + 4);
    a->source_vertex = (uint32_t *)std::malloc(a->vertices * 4);
    a->frame_rate = m.asset.extras.Has("frameRate") && m.asset.extras.Get("frameRate").IsNumber()
                        ? m.asset.extras.Get("frameRate").GetNumberAsDouble() : 0;
    // the path from the mesh's node up to a scene root: each uniform scale multiplied in
    a->unit_scale = 1;
    a->rotation[0] = a->rotation[1] = a->rotation[2] = 0, a->rotation[3] = 1;
    bool turned = false;
    for (int ni = an.channels[0].target_node, hops = 0; ni >= 0 && hops <= int(m.nodes.size()); hops++) {
        const tinygltf::Node &nd = m.nodes[size_t(ni)];
        if (!nd.matrix.empty() || !nd.translation.empty() ||
            (!nd.rotation.empty() && (nd.rotation.size() != 4 || turned)) ||
            (!nd.scale.empty() && (nd.scale.size() != 3 || nd.scale[0] != nd.scale[1] ||
                                   nd.scale[1] != nd.scale[2]))) {
            a->unit_scale = -1;
            break;
        }
        if (!nd.scale.empty()) a->unit_scale *= nd.scale[0];
        if (!nd.rotation.empty()) {
            for (int i = 0; i < 4; i++) a->rotation[i] = nd.rotation[size_t(i)];
            turned = true;
        }
        int parent = -1;
        for (size_t q = 0; q < m.nodes.size() && parent < 0; q++)
            for (int c : m.nodes[q].children)
                if (c == ni) parent = int(q);
        ni = parent;
    }
    if (!a->base || !a->target || !a->times || !a->weights || !a->source_vertex) return fail("out of memory");
    std::memcpy(a->base, base.data(), base.size() * 4);
    std::memcpy(a->target, tg.data(), tg.size() * 4);
    std::memcpy(a->times, times.data(), times.size() * 4);
    std::memcpy(a->weights, weights.data(), weights.size() * 4);
    // the mesh vertex of each glTF vertex: mesh.extras.sourceVertex, else the identity
    if (mesh.extras.Has("sourceVertex")) {
        const tinygltf::Value &map = mesh.extras.Get("sourceVertex");
        if (map.ArrayLen() != a->vertices) return fail("sourceVertex has the wrong length");
        for (size_t i = 0; i < a->vertices; i++) {
            const int v = map.Get(int(i)).GetNumberAsInt();
            if (v < 0 || size_t(v) >= mesh_vertices) return fail("sourceVertex out of range");
            a->source_vertex[i] = uint32_t(v);
        }
    } else {
        if (a->vertices != mesh_vertices) return fail("vertex count differs and no sourceVertex");
        for (size_t i = 0; i < a->vertices; i++) a->source_vertex[i] = uint32_t(i);
    }
    return 0;
}

extern "C" void fp_test_gltf_anim_weights(const fp_test_gltf_anim *a, double t, float *w)
{
    const size_t K = a->targets, F = a->keys;
    if (t <= a->times[0] || F == 1) { std::memcpy(w, a->weights, K * 4); return; }
    if (t >= a->times[F - 1]) { std::memcpy(w, a->weights + (F - 1) * K, K * 4); return; }
    size_t i = 0;
    while (i + 1 < F && !(a->times[i + 1] > t)) i++;
    const float *w0 = a->weights + i * K, *w1 = a->weights + (i + 1) * K;
    const double u = (t - a->times[i]) / (double(a->times[i + 1]) - a->times[i]);
    for (size_t k = 0; k < K; k++)
        w[k] = a->step ? w0[k] : float(w0[k] + u * (double(w1[k]) - w0[k]));
}

extern "C" void fp_test_gltf_anim_free(fp_test_gltf_anim *a)
{
    std::free(a->base); std::free(a->target); std::free(a->times); std::free(a->weights);
    std::free(a->source_vertex);
    std::memset(a, 0, sizeof *a);
}
