// glTF 2.0 and GLB out, through tinygltf's writer: a fresh document of a mesh (build_gltf:
// UV seams split, one primitive per OBJ material, morph targets and a weights animation when
// asked), or the document the mesh was loaded from with its POSITION and NORMAL rewritten in
// each node's frame (save_gltf_source).
#include "mesh_io_internal.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <new>
#include <sstream>
#include <string>
#include <vector>

namespace fp_mesh_io {

namespace {

// The tinygltf writer with image files left alone (URIs kept as written).
int write_gltf_model(tinygltf::Model &model, const char *path, const std::string &ext,
                     char *err, size_t errlen)
{
    std::ostringstream os(std::ios::out | std::ios::binary);
    tinygltf::TinyGLTF writer;
    writer.SetImageWriter(nullptr, nullptr);
    const bool ok = writer.WriteGltfSceneToStream(&model, os, false, ext == "glb");
    if (!ok || !os)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_IO, path, "the glTF writer failed");
    return write_atomically(path, os.str(), err, errlen);
}

struct GltfOut {
    tinygltf::Model model;
    tinygltf::Buffer buffer;
    int add_view(const void *src, size_t bytes, int target)
    {
        while (buffer.data.size() % 4)
            buffer.data.push_back(0);
        tinygltf::BufferView bv;
        bv.buffer = 0;
        bv.byteOffset = buffer.data.size();
        bv.byteLength = bytes;
        bv.target = target;
        const unsigned char *p = static_cast<const unsigned char *>(src);
        buffer.data.insert(buffer.data.end(), p, p + bytes);
        model.bufferViews.push_back(bv);
        return int(model.bufferViews.size() - 1);
    }
    int add_accessor(int view, int ctype, int type, size_t count)
    {
        tinygltf::Accessor a;
        a.bufferView = view;
        a.componentType = ctype;
        a.type = type;
        a.count = count;
        model.accessors.push_back(a);
        return int(model.accessors.size() - 1);
    }
    // float accessor of `comps` components with min/max
    int add_floats(const std::vector<float> &v, int comps, int target, bool minmax)
    {
        const size_t count = v.size() / size_t(comps);
        const int type = comps == 1 ? TINYGLTF_TYPE_SCALAR : comps == 2 ? TINYGLTF_TYPE_VEC2
                                                                       : TINYGLTF_TYPE_VEC3;
        int a = add_accessor(add_view(v.data(), v.size() * 4, target),
                             TINYGLTF_COMPONENT_TYPE_FLOAT, type, count);
        if (minmax) {
            std::vector<double> lo(size_t(comps), 0), hi(size_t(comps), 0);
            for (size_t i = 0; i < count; i++)
                for (int k = 0; k < comps; k++) {
                    const double x = v[i * size_t(comps) + size_t(k)];
                    if (i == 0 || x < lo[size_t(k)]) lo[size_t(k)] = x;
                    if (i == 0 || x > hi[size_t(k)]) hi[size_t(k)] = x;
                }
            model.accessors[size_t(a)].minValues = lo;
            model.accessors[size_t(a)].maxValues = hi;
        }
        return a;
    }
};

std::string file_stem(const char *path)
{
    std::string s = path ? path : "mesh";
    size_t slash = s.find_last_of('/');
    if (slash != std::string::npos)
        s = s.substr(slash + 1);
    size_t dot = s.find_last_of('.');
    if (dot != std::string::npos && dot > 0)
        s = s.substr(0, dot);
    return s;
}

void minmax3(const std::vector<float> &v, tinygltf::Accessor &a)
{
    std::vector<double> lo(3, 0), hi(3, 0);
    for (size_t i = 0; i < v.size() / 3; i++)
        for (size_t k = 0; k < 3; k++) {
            if (i == 0 || v[3 * i + k] < lo[k]) lo[k] = v[3 * i + k];
            if (i == 0 || v[3 * i + k] > hi[k]) hi[k] = v[3 * i + k];
        }
    a.minValues = lo;
    a.maxValues = hi;
}

// The glTF vertices and primitives of a mesh for build_gltf: mesh vertex i is glTF vertex i,
// UV seams' copies follow (split_seams); the triangles per material (material_triangles);
// each primitive's own block of the vertices its triangles use (primitive_blocks).
struct GltfLayout {
    const fp_mesh *m;
    const fp_mesh_source *src;           // polygons, corner UVs, materials (null: triangles)
    size_t n;                            // mesh vertices
    std::vector<uint32_t> copy_of;       // source vertex of glTF vertex n + j
    std::vector<float> uv;               // glTF vertices x 2
    std::vector<uint32_t> corner_vertex; // per source corner: glTF vertex
    bool split = false;                  // the source's corner UVs split seams
    size_t nmat = 0;                     // the source's materials
    std::vector<std::vector<uint32_t>> tris; // per material, last: none (block-local after
                                             // primitive_blocks)
    std::vector<uint32_t> out_src;       // output vertex -> split vertex
    std::vector<size_t> prim_first, prim_count, prim_mat; // per non-empty material: its block

    GltfLayout(const fp_mesh *mesh, const fp_mesh_source *source)
        : m(mesh), src(source), n(mesh->vertex_count) {}

    size_t src_vertex(size_t j) const { return j < n ? j : size_t(copy_of[j - n]); }

    // A vertex used with two different corner UVs gets a copy per further UV.
    void split_seams()
    {
        std::vector<unsigned char> first(n, 0);
        std::map<std::array<uint32_t, 3>, uint32_t> copies;
        corner_vertex.resize(src->corners.size());
        for (size_t c = 0; c < src->corners.size(); c++) {
            const uint32_t v = src->corners[c];
            corner_vertex[c] = v;
            if (!src->has_corner_uv[c])
                continue;
            const float u0 = src->corner_uv[2 * c], u1 = src->corner_uv[2 * c + 1];
            if (!first[v]) {
                first[v] = 1;
                uv[2 * v] = u0;
                uv[2 * v + 1] = u1;
                continue;
            }
            if (uv[2 * v] == u0 && uv[2 * v + 1] == u1)
                continue;
            uint32_t b0, b1;
            std::memcpy(&b0, &u0, 4);
            std::memcpy(&b1, &u1, 4);
            auto it = copies.find({v, b0, b1});
            if (it != copies.end()) {
                corner_vertex[c] = it->second;
                continue;
            }
            const uint32_t nv = uint32_t(n + copy_of.size());
            copy_of.push_back(v);
            uv.push_back(u0);
            uv.push_back(u1);
            copies[{v, b0, b1}] = nv;
            corner_vertex[c] = nv;
        }
    }

    // triangles per material, in split vertices
    void material_triangles(unsigned *dropped)
    {
        nmat = src ? src->materials.size() : 0;
        tris.assign(nmat + 1, std::vector<uint32_t>()); // last: no material
        if (src) {
            const bool mats = src->face_material.size() == src->face_start.size() - 1;
            for (size_t f = 0; f + 1 < src->face_start.size(); f++) {
                const uint32_t b = src->face_start[f], e = src->face_start[f + 1];
                const int mi = mats ? src->face_material[f] : -1;
                std::vector<uint32_t> &t = tris[mi < 0 ? nmat : size_t(mi)];
                for (uint32_t c = b + 1; c + 1 < e; c++) {
                    t.push_back(split ? corner_vertex[b] : src->corners[b]);
                    t.push_back(split ? corner_vertex[c] : src->corners[c]);
                    t.push_back(split ? corner_vertex[c + 1] : src->corners[c + 1]);
                }
            }
            if (src->polygons)
                *dropped |= FP_MESH_DROPPED_POLYGONS;
            if (src->groups)
                *dropped |= FP_MESH_DROPPED_GROUPS;
        } else {
            tris[0].assign(m->triangles, m->triangles + 3 * m->triangle_count);
        }
    }

    // Each primitive gets its own block of vertices (those its triangles use, in first-use
    // order; a vertex on a material border appears in both blocks), so that every reader
    // (ours appends each primitive's vertices) sees each vertex once per primitive.
    void primitive_blocks()
    {
        const size_t N = n + copy_of.size();
        std::vector<int64_t> local(N, -1);
        for (size_t mi = 0; mi <= nmat; mi++) {
            if (tris[mi].empty())
                continue;
            const size_t first = out_src.size();
            for (uint32_t v : tris[mi])
                if (local[v] < 0) {
                    local[v] = 0;
                    out_src.push_back(v);
                }
            // in vertex order (mesh vertices, then seam copies): one material using every
            // vertex without seams keeps the mesh's own order
            std::sort(out_src.begin() + long(first), out_src.end());
            for (size_t j = first; j < out_src.size(); j++)
                local[out_src[j]] = int64_t(j - first);
            for (uint32_t &v : tris[mi])
                v = uint32_t(local[v]);
            for (size_t j = first; j < out_src.size(); j++)
                local[out_src[j]] = -1;
            prim_first.push_back(first);
            prim_count.push_back(out_src.size() - first);
            prim_mat.push_back(mi);
        }
    }
};

// The output vertices' positions, unit normals and UVs (tuv empty when the mesh has none).
void vertex_attributes(const GltfLayout &L, std::vector<float> &pos, std::vector<float> &nrm,
                       std::vector<float> &tuv)
{
    const fp_mesh *m = L.m;
    const size_t NO = L.out_src.size();
    pos.assign(3 * NO, 0.0f);
    nrm.assign(3 * NO, 0.0f);
    tuv.assign(L.uv.empty() ? 0 : 2 * NO, 0.0f);
    for (size_t j = 0; j < NO; j++) {
        const size_t v = L.src_vertex(L.out_src[j]);
        float q[3] = {0, 0, 1};
        if (m->normals) {
            const float *a = m->normals + 3 * v;
            const double len = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] +
                                         double(a[2]) * a[2]);
            if (len > 0 && std::isfinite(len))
                for (int k = 0; k < 3; k++)
                    q[k] = float(a[k] / len);
        }
        for (int k = 0; k < 3; k++) {
            pos[3 * j + size_t(k)] = m->positions[3 * v + size_t(k)];
            nrm[3 * j + size_t(k)] = q[k];
        }
        if (!tuv.empty()) {
            tuv[2 * j] = L.uv[2 * size_t(L.out_src[j])];
            tuv[2 * j + 1] = L.uv[2 * size_t(L.out_src[j]) + 1];
        }
    }
}

// One buffer view of an attribute (comps floats a vertex) and one accessor per primitive
// over its block (with min/max when asked); the accessors returned.
std::vector<int> sub_accessors(GltfOut &g, const GltfLayout &L, const std::vector<float> &v,
                               int comps, bool minmax)
{
    const int view = g.add_view(v.data(), v.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER);
    g.model.bufferViews[size_t(view)].byteStride = size_t(comps) * 4; // shared by accessors
    std::vector<int> acc;
    for (size_t p = 0; p < L.prim_first.size(); p++) {
        const int type = comps == 2 ? TINYGLTF_TYPE_VEC2 : TINYGLTF_TYPE_VEC3;
        const int a = g.add_accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, type, L.prim_count[p]);
        g.model.accessors[size_t(a)].byteOffset = L.prim_first[p] * size_t(comps) * 4;
        if (minmax) {
            std::vector<float> part(v.begin() + long(L.prim_first[p] * size_t(comps)),
                                    v.begin() + long((L.prim_first[p] + L.prim_count[p]) * size_t(comps)));
            minmax3(part, g.model.accessors[size_t(a)]);
        }
        acc.push_back(a);
    }
    return acc;
}

// The mesh's primitives (attributes pa, na, ta; morph targets target_acc[target][primitive];
// indices; one material per OBJ material) and extras (targetNames, sourceVertex).
tinygltf::Mesh gltf_mesh(GltfOut &g, GltfLayout &L, const fp_mesh_morph_animation *anim,
                         const std::vector<int> &pa, const std::vector<int> &na,
                         const std::vector<int> &ta,
                         const std::vector<std::vector<int>> &target_acc)
{
    const fp_mesh *m = L.m;
    tinygltf::Mesh mesh;
    if (m->source_path)
        mesh.name = file_stem(m->source_path);
    for (size_t p = 0; p < L.prim_first.size(); p++) {
        const size_t mi = L.prim_mat[p];
        std::vector<uint32_t> &tris = L.tris[mi];
        tinygltf::Primitive prim;
        prim.mode = TINYGLTF_MODE_TRIANGLES;
        prim.attributes["POSITION"] = pa[p];
        prim.attributes["NORMAL"] = na[p];
        if (!ta.empty())
            prim.attributes["TEXCOORD_0"] = ta[p];
        prim.indices = g.add_accessor(g.add_view(tris.data(), tris.size() * 4,
                                                 TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                                      TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                                      TINYGLTF_TYPE_SCALAR, tris.size());
        if (mi < L.nmat) {
            tinygltf::Material mat;
            mat.name = L.src->materials[mi];
            mat.pbrMetallicRoughness.metallicFactor = 0.0;
            g.model.materials.push_back(mat);
            prim.material = int(g.model.materials.size() - 1);
        }
        for (const auto &t : target_acc) {
            std::map<std::string, int> tm;
            tm["POSITION"] = t[p];
            prim.targets.push_back(tm);
        }
        mesh.primitives.push_back(prim);
    }
    tinygltf::Value::Object extras;
    if (anim) {
        tinygltf::Value::Array names;
        for (size_t k = 0; k < anim->target_count; k++)
            names.push_back(tinygltf::Value(anim->target_names && anim->target_names[k]
                                                ? std::string(anim->target_names[k])
                                                : "t" + std::to_string(k)));
        extras["targetNames"] = tinygltf::Value(names);
        mesh.weights.assign(anim->target_count, 0.0);
    }
    const size_t NO = L.out_src.size();
    bool identity = NO == L.n;
    for (size_t j = 0; j < NO && identity; j++)
        identity = L.src_vertex(L.out_src[j]) == j;
    if (!identity) { // the mesh vertex of each glTF vertex, primitives' blocks in order
        tinygltf::Value::Array map;
        for (size_t j = 0; j < NO; j++)
            map.push_back(tinygltf::Value(int(L.src_vertex(L.out_src[j]))));
        extras["sourceVertex"] = tinygltf::Value(map);
    }
    if (!extras.empty())
        mesh.extras = tinygltf::Value(extras);
    return mesh;
}

// The animation: one sampler of the weights at the key times, one channel on node 0.
void add_animation(GltfOut &g, const fp_mesh_morph_animation *anim)
{
    std::vector<float> times(anim->times, anim->times + anim->frame_count);
    std::vector<float> w(anim->weights, anim->weights + anim->frame_count * anim->target_count);
    tinygltf::AnimationSampler sm;
    sm.input = g.add_floats(times, 1, 0, true);
    sm.output = g.add_floats(w, 1, 0, false);
    sm.interpolation = anim->step ? "STEP" : "LINEAR";
    tinygltf::Animation an;
    an.name = anim->name ? anim->name : "take";
    an.samplers.push_back(sm);
    if (anim->frame_rate > 0) {
        tinygltf::Value::Object ex;
        ex["frameRate"] = tinygltf::Value(anim->frame_rate);
        an.extras = tinygltf::Value(ex);
    }
    tinygltf::AnimationChannel ch;
    ch.sampler = 0;
    ch.target_node = 0;
    ch.target_path = "weights";
    an.channels.push_back(ch);
    g.model.animations.push_back(an);
}

// The root's rotation (x, y, z, w) that turns the mesh's up to +y and its front to +z, the
// axes glTF's readers expect (a Z-up face imported into Blender on its back without it).
// Each axis is taken as the mesh axis nearest it (a quarter or half turn, as an importer's
// Up and Forward settings turn a file; a face a few degrees off stays as its OBJ shows it).
// false where none is needed (+y and +z, or all zeros) or the axes are not two directions.
static bool root_rotation(const double up[3], const double facing[3], double q[4])
{
    double u[3] = {0, 0, 0}, f[3] = {0, 0, 0};
    int iu = 0, jf = -1;
    for (int i = 1; i < 3; i++)
        if (std::fabs(up[i]) > std::fabs(up[iu])) iu = i;
    if (!(std::fabs(up[iu]) > 0) || !std::isfinite(up[iu])) return false;
    for (int i = 0; i < 3; i++)
        if (i != iu && (jf < 0 || std::fabs(facing[i]) > std::fabs(facing[jf]))) jf = i;
    if (!(std::fabs(facing[jf]) > 0) || !std::isfinite(facing[jf])) return false;
    u[iu] = up[iu] > 0 ? 1 : -1;
    f[jf] = facing[jf] > 0 ? 1 : -1;
    const double r[3] = {u[1] * f[2] - u[2] * f[1], u[2] * f[0] - u[0] * f[2],
                         u[0] * f[1] - u[1] * f[0]}; // right = up x front: x = y x z
    // R's rows are right, up, front (R up = +y, R front = +z); its quaternion
    const double R[3][3] = {{r[0], r[1], r[2]}, {u[0], u[1], u[2]}, {f[0], f[1], f[2]}};
    if (R[0][0] > 1 - 1e-12 && R[1][1] > 1 - 1e-12 && R[2][2] > 1 - 1e-12) return false;
    const double tr = R[0][0] + R[1][1] + R[2][2];
    if (tr > 0) {
        const double s = 2 * std::sqrt(tr + 1);
        q[3] = s / 4, q[0] = (R[2][1] - R[1][2]) / s, q[1] = (R[0][2] - R[2][0]) / s,
        q[2] = (R[1][0] - R[0][1]) / s;
    } else if (R[0][0] > R[1][1] && R[0][0] > R[2][2]) {
        const double s = 2 * std::sqrt(1 + R[0][0] - R[1][1] - R[2][2]);
        q[3] = (R[2][1] - R[1][2]) / s, q[0] = s / 4, q[1] = (R[0][1] + R[1][0]) / s,
        q[2] = (R[0][2] + R[2][0]) / s;
    } else if (R[1][1] > R[2][2]) {
        const double s = 2 * std::sqrt(1 + R[1][1] - R[0][0] - R[2][2]);
        q[3] = (R[0][2] - R[2][0]) / s, q[0] = (R[0][1] + R[1][0]) / s, q[1] = s / 4,
        q[2] = (R[1][2] + R[2][1]) / s;
    } else {
        const double s = 2 * std::sqrt(1 + R[2][2] - R[0][0] - R[1][1]);
        q[3] = (R[1][0] - R[0][1]) / s, q[0] = (R[0][2] + R[2][0]) / s,
        q[1] = (R[1][2] + R[2][1]) / s, q[2] = s / 4;
    }
    return true;
}

// A fresh glTF document of the mesh (and its source's polygons, UV seams, OBJ materials),
// with morph targets and an animation when anim is given.
void build_gltf(const fp_mesh *m, const fp_mesh_morph_animation *anim, GltfOut &g,
                unsigned *dropped)
{
    const fp_mesh_source *src = source_of(m);
    const bool from_gltf = src && (src->format == "gltf" || src->format == "glb");
    if (from_gltf) {
        *dropped |= FP_MESH_DROPPED_NODES;
        if (!src->model->materials.empty())
            *dropped |= FP_MESH_DROPPED_MATERIALS;
        src = nullptr;
    }
    const size_t n = m->vertex_count;
    GltfLayout L(m, src);
    L.split = src && src->any_corner_uv;
    const bool flip_v = src != nullptr; // OBJ/PLY/OFF: v up; glTF: v down
    if (m->uvs)
        L.uv.assign(m->uvs, m->uvs + 2 * n);
    if (L.split)
        L.split_seams();
    if (flip_v)
        for (size_t j = 0; j < L.uv.size() / 2; j++)
            L.uv[2 * j + 1] = 1.0f - L.uv[2 * j + 1];
    L.material_triangles(dropped);
    L.primitive_blocks();
    std::vector<float> pos, nrm, tuv;
    vertex_attributes(L, pos, nrm, tuv);
    g.model.asset.version = "2.0";
    g.model.asset.generator = "facepuppet fp_mesh";
    // one buffer view per attribute; one accessor per primitive over its block
    const std::vector<int> pa = sub_accessors(g, L, pos, 3, true);
    const std::vector<int> na = sub_accessors(g, L, nrm, 3, false);
    const std::vector<int> ta = tuv.empty() ? std::vector<int>() : sub_accessors(g, L, tuv, 2, false);
    std::vector<std::vector<int>> target_acc; // [target][primitive]
    if (anim) {
        const size_t NO = L.out_src.size();
        std::vector<float> d(3 * NO);
        for (size_t k = 0; k < anim->target_count; k++) {
            const float *t = anim->targets + k * 3 * n;
            for (size_t j = 0; j < NO; j++)
                for (int c = 0; c < 3; c++)
                    d[3 * j + size_t(c)] = t[3 * L.src_vertex(L.out_src[j]) + size_t(c)];
            target_acc.push_back(sub_accessors(g, L, d, 3, true));
        }
    }
    const tinygltf::Mesh mesh = gltf_mesh(g, L, anim, pa, na, ta, target_acc);
    g.model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.mesh = 0;
    node.name = mesh.name;
    g.model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes.push_back(0);
    if (anim && anim->unit_scale > 0) { // mesh units to metres above the mesh's node
        tinygltf::Node root;
        root.name = std::string(anim->name ? anim->name : "take") + "_metres";
        root.scale.assign(3, anim->unit_scale);
        double q[4];
        if (root_rotation(anim->up, anim->facing, q))
            root.rotation.assign(q, q + 4);
        root.children.push_back(0);
        g.model.nodes.push_back(root);
        scene.nodes[0] = int(g.model.nodes.size() - 1);
    }
    g.model.scenes.push_back(scene);
    g.model.defaultScene = 0;
    if (anim && (anim->frame_rate > 0 || anim->unit_scale > 0)) {
        tinygltf::Value::Object ex;
        if (anim->frame_rate > 0)
            ex["frameRate"] = tinygltf::Value(anim->frame_rate);
        if (anim->unit_scale > 0)
            ex["metresPerUnit"] = tinygltf::Value(anim->unit_scale);
        g.model.asset.extras = tinygltf::Value(ex);
    }
    if (anim)
        add_animation(g, anim);
    g.model.buffers.push_back(std::move(g.buffer));
}

// Affine inverse of a column-major 4x4 (upper 3x4 used); false when singular.
bool affine_inverse(const std::array<double, 16> &M, std::array<double, 16> &R)
{
    auto a = [&](int r, int c) { return M[size_t(c * 4 + r)]; };
    double C[3][3];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            const int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            C[r][c] = a(r1, c1) * a(r2, c2) - a(r1, c2) * a(r2, c1);
        }
    const double det = a(0, 0) * C[0][0] + a(0, 1) * C[0][1] + a(0, 2) * C[0][2];
    if (!(std::fabs(det) > 0))
        return false;
    R.fill(0);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            R[size_t(c * 4 + r)] = C[c][r] / det; // inverse = adjugate / det
    for (int r = 0; r < 3; r++)
        R[size_t(12 + r)] = -(R[size_t(r)] * a(0, 3) + R[size_t(4 + r)] * a(1, 3) +
                              R[size_t(8 + r)] * a(2, 3));
    R[15] = 1;
    return true;
}

// Vertex i's NORMAL in the file (a float VEC3, glTF 2.0's only NORMAL without quantization,
// which the load refuses) into out, made unit; +z where it has none or is no unit vector.
void file_normal(const tinygltf::Model &model, int ai, size_t i, float out[3])
{
    out[0] = out[1] = 0, out[2] = 1;
    if (ai < 0 || size_t(ai) >= model.accessors.size())
        return;
    const tinygltf::Accessor &a = model.accessors[size_t(ai)];
    if (a.bufferView < 0 || size_t(a.bufferView) >= model.bufferViews.size() || a.sparse.isSparse ||
        a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || a.type != TINYGLTF_TYPE_VEC3 || i >= a.count)
        return;
    const tinygltf::BufferView &bv = model.bufferViews[size_t(a.bufferView)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= model.buffers.size())
        return;
    const size_t stride = bv.byteStride ? bv.byteStride : 12, at = bv.byteOffset + a.byteOffset + i * stride;
    const std::vector<unsigned char> &data = model.buffers[size_t(bv.buffer)].data;
    if (at + 12 > data.size())
        return;
    float n[3];
    std::memcpy(n, data.data() + at, 12);
    const double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    if (len > 0 && std::isfinite(len))
        for (int r = 0; r < 3; r++) out[r] = float(n[r] / len);
}

// Whether two copies of an accessor's positions differ by more than float round-off: a
// node's transform there and back moves a vertex by a few ulps of its size.
bool differs(const std::vector<float> &a, const std::vector<float> &b)
{
    if (a.size() != b.size())
        return true;
    double extent = 0;
    for (size_t i = 0; i < a.size(); i++)
        extent = std::max(extent, double(std::fabs(a[i])));
    const double tol = 1e-5 * std::max(extent, 1e-30);
    for (size_t i = 0; i < a.size(); i++)
        if (std::fabs(double(a[i]) - b[i]) > tol)
            return true;
    return false;
}

} // namespace

// glTF back as it came in: the document with POSITION and NORMAL rewritten.
int save_gltf_source(const fp_mesh *m, const fp_mesh_source &src, const char *path,
                     const std::string &ext, char *err, size_t errlen)
{
    tinygltf::Model model = *src.model;
    // one buffer: the document's buffers back to back (4-byte aligned)
    tinygltf::Buffer all;
    std::vector<size_t> at(model.buffers.size());
    for (size_t b = 0; b < model.buffers.size(); b++) {
        while (all.data.size() % 4)
            all.data.push_back(0);
        at[b] = all.data.size();
        all.data.insert(all.data.end(), model.buffers[b].data.begin(), model.buffers[b].data.end());
    }
    for (auto &bv : model.bufferViews) {
        bv.byteOffset += at[size_t(bv.buffer)];
        bv.buffer = 0;
    }
    model.buffers.clear();
    model.buffers.push_back(all);
    GltfOut extra; // new accessors where the old cannot be overwritten in place
    std::vector<char> done(model.accessors.size(), 0);
    // fresh: a new accessor whatever the old one (the primitive of a mesh copied for its node)
    auto rewrite = [&](int ai, const std::vector<float> &v, bool minmax, int mesh, int prim,
                       const char *attr, bool fresh) {
        if (ai < 0 || size_t(ai) >= done.size() || (done[size_t(ai)] && !fresh))
            return;
        done[size_t(ai)] = 1;
        tinygltf::Accessor &a = model.accessors[size_t(ai)];
        const tinygltf::BufferView *bv = a.bufferView >= 0 ? &model.bufferViews[size_t(a.bufferView)] : nullptr;
        const bool in_place = !fresh && bv && !a.sparse.isSparse && a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT &&
                              a.type == TINYGLTF_TYPE_VEC3 && (bv->byteStride == 0 || bv->byteStride == 12) &&
                              a.count * 3 == v.size();
        if (in_place) {
            std::memcpy(model.buffers[0].data.data() + bv->byteOffset + a.byteOffset, v.data(),
                        v.size() * 4);
            if (minmax)
                minmax3(v, a);
            return;
        }
        // a new float accessor at the end of the buffer
        while (model.buffers[0].data.size() % 4)
            model.buffers[0].data.push_back(0);
        tinygltf::BufferView nb;
        nb.buffer = 0;
        nb.byteOffset = model.buffers[0].data.size();
        nb.byteLength = v.size() * 4;
        nb.target = TINYGLTF_TARGET_ARRAY_BUFFER;
        const unsigned char *p = reinterpret_cast<const unsigned char *>(v.data());
        model.buffers[0].data.insert(model.buffers[0].data.end(), p, p + v.size() * 4);
        model.bufferViews.push_back(nb);
        tinygltf::Accessor na;
        na.bufferView = int(model.bufferViews.size() - 1);
        na.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        na.type = TINYGLTF_TYPE_VEC3;
        na.count = v.size() / 3;
        model.accessors.push_back(na);
        const int nai = int(model.accessors.size() - 1);
        done.push_back(1);
        model.meshes[size_t(mesh)].primitives[size_t(prim)].attributes[attr] = nai;
        if (minmax)
            minmax3(v, model.accessors[size_t(nai)]);
    };
    // A mesh that several nodes place (instances) is one set of accessors in the file but as
    // many copies in fp_mesh, each deformed where its node put it: the first copy's shape went
    // into the accessors and the others' was lost. A node whose copy differs from what its
    // accessor got gets a copy of the mesh of its own (own_mesh) with accessors of its own.
    std::map<int, std::vector<float>> written;  // POSITION accessor -> local positions written
    std::map<std::pair<int, int>, int> own_mesh; // (node, mesh) -> its own copy of the mesh
    for (const auto &in : src.instances) {
        // A node that flattens its mesh (a scale of 0: singular) has no local frame to write
        // the deformation back into; the refusal came after the whole performance. Its copy
        // goes, as deformed, into a mesh of its own on a new root node of the scene (the
        // node keeps its transform and children, not the mesh).
        std::array<double, 16> inv, xf = in.xf;
        const bool flat = !affine_inverse(in.xf, inv);
        const int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
        if (flat && (in.node < 0 || size_t(scene) >= model.scenes.size()))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                                  "glTF: mesh %d has a singular node transform", in.mesh);
        if (flat) {
            inv.fill(0);
            inv[0] = inv[5] = inv[10] = inv[15] = 1;
            xf = inv;
        }
        std::vector<float> p(3 * in.count), q;
        for (size_t i = 0; i < in.count; i++) {
            const float *x = m->positions + 3 * (in.first + i);
            for (int r = 0; r < 3; r++)
                p[3 * i + size_t(r)] = float(inv[size_t(r)] * x[0] + inv[size_t(4 + r)] * x[1] +
                                             inv[size_t(8 + r)] * x[2] + inv[size_t(12 + r)]);
        }
        int mesh = in.mesh;
        auto own = own_mesh.find({in.node, in.mesh});
        bool fresh = own != own_mesh.end();
        if (fresh) {
            mesh = own->second;
        } else if (in.node >= 0 && (flat || (written.count(in.pos) && differs(written[in.pos], p)))) {
            model.meshes.push_back(model.meshes[size_t(in.mesh)]);
            mesh = int(model.meshes.size() - 1);
            model.meshes.back().name += model.meshes.back().name.empty() ? "" : "_";
            model.meshes.back().name += "node" + std::to_string(in.node);
            if (flat) {
                tinygltf::Node root;
                root.name = model.nodes[size_t(in.node)].name + "_deformed";
                root.mesh = mesh;
                model.nodes[size_t(in.node)].mesh = -1;
                model.nodes.push_back(root);
                model.scenes[size_t(scene)].nodes.push_back(int(model.nodes.size() - 1));
            } else {
                model.nodes[size_t(in.node)].mesh = mesh;
            }
            own_mesh[{in.node, in.mesh}] = mesh;
            fresh = true;
        }
        if (!written.count(in.pos) && !flat)
            written[in.pos] = p;
        rewrite(in.pos, p, true, mesh, in.prim, "POSITION", fresh);
        if (in.nrm >= 0 && m->normals) {
            q.resize(3 * in.count);
            for (size_t i = 0; i < in.count; i++) {
                const float *x = m->normals + 3 * (in.first + i);
                double w[3], len = 0;
                for (int r = 0; r < 3; r++) { // local normal ~ M^T n
                    w[r] = xf[size_t(r * 4)] * x[0] + xf[size_t(r * 4 + 1)] * x[1] +
                           xf[size_t(r * 4 + 2)] * x[2];
                    len += w[r] * w[r];
                }
                len = std::sqrt(len);
                if (!(len > 0)) { // no normal (a vertex in no triangle): the file's, unit as glTF wants
                    file_normal(*src.model, in.nrm, i, &q[3 * i]);
                    continue;
                }
                for (int r = 0; r < 3; r++)
                    q[3 * i + size_t(r)] = float(w[r] / len);
            }
            rewrite(in.nrm, q, false, mesh, in.prim, "NORMAL", fresh);
        }
    }
    return write_gltf_model(model, path, ext, err, errlen);
}

int save_gltf(const fp_mesh *m, const fp_mesh_morph_animation *anim, const char *path,
              const std::string &ext, char *err, size_t errlen, unsigned *dropped)
{
    GltfOut g;
    build_gltf(m, anim, g, dropped);
    return write_gltf_model(g.model, path, ext, err, errlen);
}

} // namespace fp_mesh_io
