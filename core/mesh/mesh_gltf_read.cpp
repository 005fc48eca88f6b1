// glTF 2.0 and GLB in, through tinygltf (Debian's shared libtinygltf): the triangle
// primitives of the default scene's nodes with their transforms applied (GltfReader), file
// access restricted to the file's folder (GltfFs), and the JSON checked again for what
// tinygltf takes without a word (GltfJsonCheck). The document is kept in the mesh's source
// for a save that writes it back (mesh_gltf_write.cpp).
#include "mesh_io_internal.hpp"

#include <nlohmann/json.hpp> // tinygltf's JSON library (it includes it too)

#include <limits.h>
#include <stdlib.h>
#include <unistd.h>

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

struct Mat4 { double m[16]; }; // column-major, as glTF

Mat4 mat_identity()
{
    Mat4 r{};
    r.m[0] = r.m[5] = r.m[10] = r.m[15] = 1;
    return r;
}

Mat4 mat_mul(const Mat4 &a, const Mat4 &b)
{
    Mat4 r{};
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            double s = 0;
            for (int k = 0; k < 4; k++)
                s += a.m[k * 4 + row] * b.m[c * 4 + k];
            r.m[c * 4 + row] = s;
        }
    return r;
}

// The node's local transform: its matrix, or T * R * S.
Mat4 node_local(const tinygltf::Node &nd)
{
    Mat4 r = mat_identity();
    if (nd.matrix.size() == 16) {
        for (int i = 0; i < 16; i++)
            r.m[i] = nd.matrix[size_t(i)];
        return r;
    }
    double sx = 1, sy = 1, sz = 1, qx = 0, qy = 0, qz = 0, qw = 1;
    if (nd.scale.size() == 3) { sx = nd.scale[0]; sy = nd.scale[1]; sz = nd.scale[2]; }
    if (nd.rotation.size() == 4) {
        qx = nd.rotation[0]; qy = nd.rotation[1]; qz = nd.rotation[2]; qw = nd.rotation[3];
    }
    const double R[9] = {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy + qz * qw), 2 * (qx * qz - qy * qw),
                         2 * (qx * qy - qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz + qx * qw),
                         2 * (qx * qz + qy * qw), 2 * (qy * qz - qx * qw), 1 - 2 * (qx * qx + qy * qy)};
    const double S[3] = {sx, sy, sz};
    for (int c = 0; c < 3; c++)
        for (int row = 0; row < 3; row++)
            r.m[c * 4 + row] = R[c * 3 + row] * S[c]; // column c of R, times scale c
    if (nd.translation.size() == 3)
        for (int k = 0; k < 3; k++)
            r.m[12 + k] = nd.translation[size_t(k)];
    return r;
}

struct GltfReader {
    const tinygltf::Model &model;
    Soup &soup;
    std::string error;
    int code = FP_MESH_OK;
    size_t prims_seen = 0, prims_used = 0;
    bool all_normals = true, any_uv = false;
    std::vector<fp_mesh_source::Instance> instances;

    bool bad(int c, const std::string &msg)
    {
        if (code == FP_MESH_OK) { code = c; error = msg; }
        return false;
    }

    static std::string component_name(int t)
    {
        switch (t) {
        case TINYGLTF_COMPONENT_TYPE_BYTE: return "5120 (BYTE)";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "5121 (UNSIGNED_BYTE)";
        case TINYGLTF_COMPONENT_TYPE_SHORT: return "5122 (SHORT)";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "5123 (UNSIGNED_SHORT)";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "5125 (UNSIGNED_INT)";
        case TINYGLTF_COMPONENT_TYPE_FLOAT: return "5126 (FLOAT)";
        default: return std::to_string(t);
        }
    }

    bool uses_extension(const char *name) const
    {
        for (const auto *list : {&model.extensionsUsed, &model.extensionsRequired})
            if (std::find(list->begin(), list->end(), name) != list->end())
                return true;
        return false;
    }

    // The component types glTF 2.0 allows for the attributes read (section 3.7.2.1):
    // POSITION and NORMAL FLOAT, TEXCOORD_0 FLOAT or normalised UNSIGNED_BYTE/SHORT. Other
    // integer types are KHR_mesh_quantization's (not supported: its positions need the
    // node's dequantising transform) or invalid: a BYTE POSITION used to load its raw
    // values, garbage coordinates, without a word.
    bool component_ok(const tinygltf::Accessor &a, const char *what, const std::string &name)
    {
        const int t = a.componentType;
        if (t == TINYGLTF_COMPONENT_TYPE_FLOAT)
            return true;
        const bool uv = std::strcmp(what, "TEXCOORD_0") == 0;
        if (uv && a.normalized && (t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                   t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT))
            return true;
        const std::string allowed = uv ? "5126 (FLOAT), or 5121 (UNSIGNED_BYTE) or 5123 "
                                         "(UNSIGNED_SHORT) normalized"
                                       : "5126 (FLOAT)";
        const std::string what_is = name + " has component type " + component_name(t) +
                                    (a.normalized ? " normalized" : "");
        if (uses_extension("KHR_mesh_quantization"))
            return bad(FP_MESH_ERR_UNSUPPORTED, what_is + ": KHR_mesh_quantization is not "
                                                          "supported (" + allowed + ")");
        return bad(FP_MESH_ERR_FORMAT, what_is + "; glTF 2.0 requires " + allowed);
    }

    // Read accessor `ai` of attribute `what` of `where` as `want` components per element
    // into out (as float; normalised integers as glTF defines them).
    bool read_floats(int ai, int want, const char *what, const std::string &where,
                     std::vector<float> &out)
    {
        const std::string name = where + " " + what + " accessor " + std::to_string(ai);
        if (ai < 0 || size_t(ai) >= model.accessors.size())
            return bad(FP_MESH_ERR_FORMAT, name + " does not exist");
        const tinygltf::Accessor &a = model.accessors[size_t(ai)];
        const int ncomp = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        if (ncomp != want)
            return bad(FP_MESH_ERR_FORMAT, name + " has " + std::to_string(ncomp) +
                                                " components, expected " + std::to_string(want));
        if (!component_ok(a, what, name))
            return false;
        const uint8_t *base;
        size_t stride;
        if (!locate(a, name, &base, &stride))
            return false;
        out.resize(a.count * size_t(want));
        const int csize = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        for (size_t i = 0; i < a.count; i++)
            for (int k = 0; k < want; k++) {
                const uint8_t *p = base + i * stride + size_t(k * csize);
                float v;
                switch (a.componentType) {
                // the types component_ok lets through (the integers normalised)
                case TINYGLTF_COMPONENT_TYPE_FLOAT: std::memcpy(&v, p, 4); break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = float(*p) / 255.0f; break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                    uint16_t u; std::memcpy(&u, p, 2); v = float(u) / 65535.0f;
                    break;
                }
                default:
                    return bad(FP_MESH_ERR_FORMAT, name + " has component type " +
                                                        std::to_string(a.componentType) +
                                                        ", not a vertex attribute type");
                }
                if (!std::isfinite(v))
                    return bad(FP_MESH_ERR_FORMAT, name + " element " + std::to_string(i) +
                                                        " is not finite");
                out[i * size_t(want) + size_t(k)] = v;
            }
        return true;
    }

    bool read_indices(int ai, const std::string &where, std::vector<uint32_t> &out)
    {
        const std::string name = where + " indices: accessor " + std::to_string(ai);
        if (ai < 0 || size_t(ai) >= model.accessors.size())
            return bad(FP_MESH_ERR_FORMAT, name + " does not exist (the file has " +
                                               std::to_string(model.accessors.size()) + ")");
        const tinygltf::Accessor &a = model.accessors[size_t(ai)];
        if (a.type != TINYGLTF_TYPE_SCALAR)
            return bad(FP_MESH_ERR_FORMAT, name + " is not SCALAR");
        const uint8_t *base;
        size_t stride;
        if (!locate(a, name, &base, &stride))
            return false;
        out.resize(a.count);
        for (size_t i = 0; i < a.count; i++) {
            const uint8_t *p = base + i * stride;
            switch (a.componentType) {
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: out[i] = *p; break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                uint16_t u; std::memcpy(&u, p, 2); out[i] = u; break;
            }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: std::memcpy(&out[i], p, 4); break;
            default:
                return bad(FP_MESH_ERR_FORMAT, name + " has component type " +
                                                    std::to_string(a.componentType) +
                                                    " (indices must be unsigned integers)");
            }
        }
        return true;
    }

    // Find an accessor's first element and stride, checking every bound.
    bool locate(const tinygltf::Accessor &a, const std::string &name, const uint8_t **base,
                size_t *stride)
    {
        if (a.sparse.isSparse)
            return bad(FP_MESH_ERR_UNSUPPORTED, name + " is sparse (not supported)");
        if (a.bufferView < 0 || size_t(a.bufferView) >= model.bufferViews.size())
            return bad(FP_MESH_ERR_FORMAT, name + " has no valid bufferView");
        const tinygltf::BufferView &bv = model.bufferViews[size_t(a.bufferView)];
        if (bv.buffer < 0 || size_t(bv.buffer) >= model.buffers.size())
            return bad(FP_MESH_ERR_FORMAT, name + ": bufferView " + std::to_string(a.bufferView) +
                                                " has no valid buffer");
        const tinygltf::Buffer &buf = model.buffers[size_t(bv.buffer)];
        const int csize = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        const int ncomp = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        const int s = a.ByteStride(bv);
        if (csize <= 0 || ncomp <= 0 || s <= 0)
            return bad(FP_MESH_ERR_FORMAT, name + " has an invalid type, component type or stride");
        const size_t elem = size_t(csize) * size_t(ncomp);
        // glTF 2.0, bufferView.byteStride: 4..252, a multiple of 4, and at least one element
        // (a smaller stride would overlap the elements)
        if (bv.byteStride != 0 && (bv.byteStride < 4 || bv.byteStride > 252 || bv.byteStride % 4 ||
                                   bv.byteStride < elem))
            return bad(FP_MESH_ERR_FORMAT, name + ": bufferView " + std::to_string(a.bufferView) +
                                                " has byteStride " + std::to_string(bv.byteStride) +
                                                " (glTF: 4..252, a multiple of 4, at least the " +
                                                std::to_string(elem) + "-byte element)");
        if (bv.byteOffset > buf.data.size() || bv.byteLength > buf.data.size() - bv.byteOffset)
            return bad(FP_MESH_ERR_FORMAT, name + ": bufferView " + std::to_string(a.bufferView) +
                                                " lies outside its buffer (" +
                                                std::to_string(buf.data.size()) + " bytes)");
        if (a.count > 0) {
            const size_t limit = bv.byteLength;
            const bool fits = a.byteOffset <= limit && elem <= limit - a.byteOffset &&
                              (a.count - 1) <= (limit - a.byteOffset - elem) / size_t(s);
            if (!fits)
                return bad(FP_MESH_ERR_FORMAT, name + " (" + std::to_string(a.count) +
                                                    " elements) overruns bufferView " +
                                                    std::to_string(a.bufferView));
        }
        *base = buf.data.data() + bv.byteOffset + a.byteOffset;
        *stride = size_t(s);
        return true;
    }

    // A strip's or a fan's triangles as a list (glTF 2.0, 3.7.2.1 "Topology types": strip
    // triangle i is {v_i, v_(i+1+i%2), v_(i+2-i%2)}, fan triangle i {v_(i+1), v_(i+2), v_0}),
    // the degenerate ones a strip's restarts make (a repeated index) left out; fewer than 3
    // indices make none.
    static std::vector<uint32_t> strip_or_fan_triangles(const std::vector<uint32_t> &v, bool strip)
    {
        std::vector<uint32_t> out;
        for (size_t i = 0; i + 2 < v.size(); i++) {
            const uint32_t a = strip ? v[i] : v[i + 1], b = strip ? v[i + 1 + i % 2] : v[i + 2],
                           c = strip ? v[i + 2 - i % 2] : v[0];
            if (a == b || b == c || a == c)
                continue;
            out.insert(out.end(), {a, b, c});
        }
        return out;
    }

    bool add_mesh(int mi, const Mat4 &xf, int node)
    {
        if (mi < 0 || size_t(mi) >= model.meshes.size())
            return bad(FP_MESH_ERR_FORMAT, "mesh " + std::to_string(mi) + " does not exist");
        const tinygltf::Mesh &mesh = model.meshes[size_t(mi)];
        // normal matrix: cofactor of the upper 3x3 (= det * inverse transpose)
        const double *M = xf.m;
        auto a = [&](int r, int c) { return M[c * 4 + r]; };
        double C[3][3];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) {
                const int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
                C[r][c] = a(r1, c1) * a(r2, c2) - a(r1, c2) * a(r2, c1);
            }
        const double det = a(0, 0) * C[0][0] + a(0, 1) * C[0][1] + a(0, 2) * C[0][2];
        const bool flip = det < 0;
        for (size_t pi = 0; pi < mesh.primitives.size(); pi++) {
            const tinygltf::Primitive &prim = mesh.primitives[pi];
            prims_seen++;
            const bool strip = prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP,
                       fan = prim.mode == TINYGLTF_MODE_TRIANGLE_FAN;
            if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES && !strip && !fan)
                continue; // points and lines: no surface to deform
            const std::string where = "mesh " + std::to_string(mi) + " primitive " +
                                      std::to_string(pi);
            auto pos_it = prim.attributes.find("POSITION");
            if (pos_it == prim.attributes.end())
                return bad(FP_MESH_ERR_FORMAT, where + " has no POSITION");
            std::vector<float> pos, nrm, uv;
            if (!read_floats(pos_it->second, 3, "POSITION", where, pos))
                return false;
            const size_t count = pos.size() / 3;
            auto n_it = prim.attributes.find("NORMAL");
            auto t_it = prim.attributes.find("TEXCOORD_0");
            if (n_it != prim.attributes.end()) {
                if (!read_floats(n_it->second, 3, "NORMAL", where, nrm))
                    return false;
                if (nrm.size() != pos.size())
                    return bad(FP_MESH_ERR_FORMAT, where + ": NORMAL count differs from POSITION");
            } else {
                all_normals = false;
            }
            if (t_it != prim.attributes.end()) {
                if (!read_floats(t_it->second, 2, "TEXCOORD_0", where, uv))
                    return false;
                if (uv.size() / 2 != count)
                    return bad(FP_MESH_ERR_FORMAT, where + ": TEXCOORD_0 count differs from POSITION");
                any_uv = true;
            }
            std::vector<uint32_t> idx;
            if (prim.indices >= 0) { // a negative one in the file: refused (GltfJsonCheck)
                if (!read_indices(prim.indices, where, idx))
                    return false;
            } else {
                idx.resize(count);
                for (size_t i = 0; i < count; i++)
                    idx[i] = uint32_t(i);
            }
            if (!strip && !fan && idx.size() % 3 != 0) // (without indices: its vertices in threes)
                return bad(FP_MESH_ERR_FORMAT, where + " has " + std::to_string(idx.size()) +
                                                   (prim.indices >= 0 ? " indices" : " vertices and no indices") +
                                                   ", not a multiple of 3");
            for (size_t i = 0; i < idx.size(); i++) // (the file's indices, before a strip's expansion)
                if (idx[i] >= count)
                    return bad(FP_MESH_ERR_FORMAT, where + ": index " + std::to_string(i) + " = " +
                                                       std::to_string(idx[i]) + " is out of range (" +
                                                       std::to_string(count) + " vertices)");
            if (strip || fan) // glTF 2.0 3.7.2.1: as a list of triangles, the winding kept
                idx = strip_or_fan_triangles(idx, strip);
            const size_t base = soup.n();
            {
                fp_mesh_source::Instance in{mi, int(pi), base, count, {}, pos_it->second,
                                            n_it != prim.attributes.end() ? n_it->second : -1, node};
                std::copy(xf.m, xf.m + 16, in.xf.begin());
                instances.push_back(in);
            }
            if (base + count > UINT32_MAX)
                return bad(FP_MESH_ERR_UNSUPPORTED, "more vertices than 32-bit indices hold");
            for (size_t i = 0; i < count; i++) {
                const float *p = &pos[3 * i];
                double q[3];
                for (int r = 0; r < 3; r++)
                    q[r] = a(r, 0) * p[0] + a(r, 1) * p[1] + a(r, 2) * p[2] + a(r, 3);
                const size_t v = soup.add_vertex(float(q[0]), float(q[1]), float(q[2]));
                if (!nrm.empty()) {
                    const float *nn = &nrm[3 * i];
                    double w[3], len = 0;
                    for (int r = 0; r < 3; r++) {
                        w[r] = (C[r][0] * nn[0] + C[r][1] * nn[1] + C[r][2] * nn[2]) * (flip ? -1 : 1);
                        len += w[r] * w[r];
                    }
                    len = std::sqrt(len);
                    for (int r = 0; r < 3; r++)
                        soup.nrm[3 * v + size_t(r)] = len > 0 ? float(w[r] / len) : 0.0f;
                    soup.has_nrm[v] = 1;
                }
                if (!uv.empty()) {
                    soup.uv[2 * v] = uv[2 * i];
                    soup.uv[2 * v + 1] = uv[2 * i + 1];
                    soup.has_uv[v] = 1;
                }
            }
            if (!soup.error.empty())
                return bad(FP_MESH_ERR_FORMAT, where + ": " + soup.error);
            for (size_t i = 0; i + 2 < idx.size(); i += 3) {
                soup.corners.push_back(uint32_t(base + idx[i]));
                soup.corners.push_back(uint32_t(base + idx[i + (flip ? 2 : 1)]));
                soup.corners.push_back(uint32_t(base + idx[i + (flip ? 1 : 2)]));
                soup.face_start.push_back(uint32_t(soup.corners.size()));
            }
            prims_used++;
        }
        return true;
    }

    bool add_node(int ni, const Mat4 &parent, std::vector<char> &visited, int depth)
    {
        if (ni < 0 || size_t(ni) >= model.nodes.size())
            return bad(FP_MESH_ERR_FORMAT, "node " + std::to_string(ni) + " does not exist");
        if (visited[size_t(ni)])
            return bad(FP_MESH_ERR_FORMAT, "node " + std::to_string(ni) +
                                               " appears twice in the hierarchy (cycle?)");
        if (depth > 1000)
            return bad(FP_MESH_ERR_UNSUPPORTED, "node " + std::to_string(ni) +
                                                    " is more than 1000 levels deep in the hierarchy");
        visited[size_t(ni)] = 1;
        const tinygltf::Node &nd = model.nodes[size_t(ni)];
        const Mat4 xf = mat_mul(parent, node_local(nd));
        if (nd.mesh >= 0 && !add_mesh(nd.mesh, xf, ni))
            return false;
        for (int c : nd.children)
            if (!add_node(c, xf, visited, depth + 1))
                return false;
        return true;
    }
};

// Images are not needed: accept any without decoding.
bool skip_image(tinygltf::Image *, const int, std::string *, std::string *, int, int,
                const unsigned char *, int, void *)
{
    return true;
}

// tinygltf's messages on one line, a data URI's payload shortened to its first characters
// and length (a byteLength mismatch quoted the whole base64 text: kilobytes of it), the
// whole cut to 400 characters.
std::string one_line(std::string s)
{
    for (char &c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    for (size_t at = s.find(";base64,"); at != std::string::npos; at = s.find(";base64,", at + 1)) {
        const size_t from = at + 8;
        size_t end = from;
        while (end < s.size() && (isalnum((unsigned char)s[end]) || s[end] == '+' || s[end] == '/' ||
                                  s[end] == '='))
            end++;
        if (end - from > 24)
            s.replace(from + 16, end - from - 16,
                      "... (" + std::to_string(end - from) + " base64 characters)");
    }
    if (s.size() > 400)
        s = s.substr(0, 400) + "...";
    while (!s.empty() && s.back() == ' ')
        s.pop_back();
    return s;
}

// tinygltf's file access, restricted: a buffer or image URI (data URIs never come here) must
// be a relative path that stays inside the glTF file's folder after normalisation, whose
// real path (symlinks resolved) is inside that folder too, and that names a regular file
// (opened O_NONBLOCK, so a FIFO or device cannot block). Every refusal is remembered, and the
// load fails naming the URI, even where tinygltf would only warn (images): with the code of a
// file not there or not readable (FP_MESH_ERR_NOENT, _ACCESS: an input file missing, as the
// glTF's own) where the URI is a fair name that names no file, else FORMAT (a URI the glTF
// may not use).
struct GltfFs {
    std::string base;      // the folder given to tinygltf
    std::string refused;   // the first refusal: "URI 'x': reason"
    int code = FP_MESH_OK; // ... and its code
};

bool gltf_fs_exists(const std::string &, void *) { return true; } // fs_read decides
std::string gltf_fs_expand(const std::string &p, void *) { return p; } // no ~ or $VAR
bool gltf_fs_write(std::string *, const std::string &, const std::vector<unsigned char> &, void *)
{
    return false;
}

bool gltf_fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path,
                  void *user)
{
    GltfFs &fs = *static_cast<GltfFs *>(user);
    const std::string prefix = fs.base.empty() || fs.base.back() == '/' ? fs.base : fs.base + "/";
    std::string rel = path.compare(0, prefix.size(), prefix) == 0 ? path.substr(prefix.size())
                                                                  : path;
    auto refuse_as = [&](int code, const std::string &msg) {
        if (fs.refused.empty()) {
            fs.refused = msg;
            fs.code = code;
        }
        if (err)
            *err = msg;
        return false;
    };
    auto refuse = [&](const std::string &why) {
        return refuse_as(FP_MESH_ERR_FORMAT, "URI '" + rel + "' refused: " + why);
    };
    // a file the URI fairly names that is not there (or may not be read): named by its path
    auto missing = [&](int code, const std::string &why) {
        return refuse_as(code, "URI '" + rel + "': " + path + ": " + why);
    };
    if (path.compare(0, prefix.size(), prefix) != 0)
        return refuse("not inside the glTF file's folder");
    if (rel.empty())
        return refuse("empty path");
    if (rel[0] == '/')
        return refuse("absolute path (only paths relative to the glTF file are read)");
    int depth = 0;
    size_t b = 0;
    while (b <= rel.size()) {
        size_t e = rel.find('/', b);
        if (e == std::string::npos)
            e = rel.size();
        const std::string seg = rel.substr(b, e - b);
        if (seg == "..") {
            if (--depth < 0)
                return refuse("leaves the glTF file's folder");
        } else if (!seg.empty() && seg != ".") {
            depth++;
        }
        b = e + 1;
    }
    char *real_base = realpath(fs.base.empty() ? "." : fs.base.c_str(), nullptr);
    char *real = realpath(path.c_str(), nullptr);
    const int e = errno;
    std::string rb = real_base ? real_base : "", rp = real ? real : "";
    free(real_base);
    free(real);
    if (!rb.empty() && rp.empty() && (e == ENOENT || e == ENOTDIR || e == EACCES))
        return missing(e == EACCES ? FP_MESH_ERR_ACCESS : FP_MESH_ERR_NOENT,
                       e == EACCES ? "cannot open: " + std::string(std::strerror(e))
                                   : std::string("no such file (the glTF's buffer or image)"));
    if (rb.empty() || rp.empty())
        return refuse(std::string("cannot resolve: ") + std::strerror(e));
    if (rb.back() != '/')
        rb += '/';
    if (rp + '/' == rb)
        return refuse("names the glTF file's folder, not a file");
    if (rp.compare(0, rb.size(), rb) != 0)
        return refuse("a symbolic link leads outside the glTF file's folder");
    off_t size = 0;
    int code = FP_MESH_OK;
    std::string why;
    int fd = open_regular(rp.c_str(), max_file_bytes, &size, &code, &why);
    if (fd < 0) // (a FIFO or a device: NOENT, as the glTF itself would be)
        return refuse_as(code == FP_MESH_ERR_NOENT || code == FP_MESH_ERR_ACCESS ? code
                                                                                 : FP_MESH_ERR_FORMAT,
                         "URI '" + rel + "' refused: " + why);
    std::string data;
    const bool ok = read_fd(fd, size, data, &code, &why);
    ::close(fd);
    if (!ok)
        return refuse(why);
    out->assign(data.begin(), data.end());
    return true;
}

// What tinygltf does not check in the JSON it parsed, walked once more as SAX events (no
// document built). It reads an index that is not an integer from 0 to INT_MAX as absent
// (-1, or a wrapped int): "indices": -1 (or 0.5, or 4294967295) loaded a primitive as
// non-indexed, "mesh": -1 dropped a node's mesh, without a word. It takes a node's matrix,
// translation, rotation and scale at any length (node_local uses them at 16, 3, 4 and 3
// numbers only: others were ignored) and ignores TRS beside a matrix. Checked here: every
// index property of glTF 2.0's schema (index_key; attribute and morph target values; scene
// nodes, children, joints) and each node's transform arrays. extras and extensions hold
// free-form JSON: not looked into.
class GltfJsonCheck : public nlohmann::json_sax<nlohmann::json> {
public:
    std::string error; // "PATH is ...": the first problem found, or ""

    bool null() override { return scalar("null", false); }
    bool boolean(bool) override { return scalar("a boolean", false); }
    bool number_integer(number_integer_t v) override
    {
        return v >= 0 && v <= INT_MAX ? scalar(nullptr, true)
                                      : scalar(std::to_string(v).c_str(), true);
    }
    bool number_unsigned(number_unsigned_t v) override
    {
        return v <= number_unsigned_t(INT_MAX) ? scalar(nullptr, true)
                                               : scalar(std::to_string(v).c_str(), true);
    }
    bool number_float(number_float_t, const string_t &text) override
    {
        return scalar(text.c_str(), true);
    }
    bool string(string_t &) override { return scalar("a string", false); }
    bool binary(binary_t &) override { return scalar("binary data", false); }
    bool key(string_t &k) override
    {
        Frame &f = st_.back();
        f.key = k;
        if (f.node && (k == "matrix" || k == "translation" || k == "rotation" || k == "scale"))
            (k == "matrix" ? f.has_matrix : f.has_trs) = true;
        return true;
    }
    bool start_object(std::size_t) override { return open(false); }
    bool start_array(std::size_t) override { return open(true); }
    bool end_object() override { return close(); }
    bool end_array() override { return close(); }
    bool parse_error(std::size_t at, const std::string &,
                     const nlohmann::detail::exception &x) override
    {
        return fail("JSON error at byte " + std::to_string(at) + ": " + x.what());
    }

private:
    enum Slot { ANY, INDEX, TRANSFORM, TRANSFORM_NUMBER };
    struct Frame {
        bool array = false;
        std::string key;           // object: the current member's name
        size_t index = 0;          // array: the current element
        bool free = false;         // inside extras or extensions
        bool index_array = false;  // scenes[].nodes, children, joints
        bool index_object = false; // a primitive's attributes, a morph target
        bool node = false;         // an element of the top-level nodes array
        bool has_matrix = false, has_trs = false;
        size_t want = 0;           // a node's transform array: the length it must have
    };
    std::vector<Frame> st_;

    static bool index_key(const std::string &k)
    {
        static const char *const keys[] = {"bufferView", "buffer", "indices", "material",
                                           "mesh", "camera", "skin", "skeleton", "scene",
                                           "source", "sampler", "index", "input", "output",
                                           "node", "inverseBindMatrices"};
        for (const char *x : keys)
            if (k == x)
                return true;
        return false;
    }

    static bool transform_key(const std::string &k)
    {
        return k == "matrix" || k == "translation" || k == "rotation" || k == "scale";
    }

    // The key of the object below the top frame (the top frame's own name), or "".
    const std::string &outer_key() const
    {
        static const std::string none;
        return st_.size() >= 2 && !st_[st_.size() - 2].array ? st_[st_.size() - 2].key : none;
    }

    // What the next value (the top frame's current member or element) must be.
    Slot slot() const
    {
        if (st_.empty() || st_.back().free)
            return ANY;
        const Frame &p = st_.back();
        if (p.want)
            return TRANSFORM_NUMBER;
        if (p.array)
            return p.index_array ? INDEX : ANY;
        if (p.index_object || index_key(p.key))
            return INDEX;
        return p.node && transform_key(p.key) ? TRANSFORM : ANY;
    }

    // Where the next value is: "meshes[0].primitives[1].indices".
    std::string path() const
    {
        std::string s;
        for (const Frame &f : st_)
            s += f.array ? "[" + std::to_string(f.index) + "]" : (s.empty() ? "" : ".") + f.key;
        return s;
    }

    bool fail(const std::string &msg)
    {
        if (error.empty())
            error = msg;
        return false; // stops the parse
    }

    void next()
    {
        if (!st_.empty() && st_.back().array)
            st_.back().index++;
    }

    // A scalar value: what is nullptr for an integer from 0 to INT_MAX, else what it is.
    bool scalar(const char *what, bool number)
    {
        const Slot s = slot();
        if (s == INDEX && what)
            return fail(path() + " is " + what + ", not an index (an integer from 0 to " +
                        std::to_string(INT_MAX) + ")");
        if (s == TRANSFORM)
            return fail(path() + " is not an array of numbers");
        if (s == TRANSFORM_NUMBER && !number)
            return fail(path() + " is " + what + ", not a number");
        next();
        return true;
    }

    bool open(bool array)
    {
        const Slot s = slot();
        Frame f;
        f.array = array;
        if (!st_.empty()) {
            const Frame &p = st_.back();
            const std::string k = p.array ? std::string() : p.key;
            f.free = p.free || k == "extras" || k == "extensions";
            // an accessor's sparse.indices is an object (its bufferView and type)
            const bool sparse_indices = k == "indices" && !array && outer_key() == "sparse";
            if (!f.free && s == INDEX && !sparse_indices)
                return fail(path() + " is " + (array ? "an array" : "an object") +
                            ", not an index");
            if (!f.free && s == TRANSFORM_NUMBER)
                return fail(path() + " is " + (array ? "an array" : "an object") +
                            ", not a number");
            if (!f.free && s == TRANSFORM && !array)
                return fail(path() + " is not an array of numbers");
            if (!f.free && s == TRANSFORM)
                f.want = k == "matrix" ? 16 : k == "rotation" ? 4 : 3;
            // the top-level nodes array holds nodes; elsewhere nodes, children and joints
            // list node indices
            f.index_array = !f.free && array &&
                            (k == "children" || k == "joints" || (k == "nodes" && st_.size() > 1));
            f.index_object = !f.free && !array &&
                             (k == "attributes" || (p.array && outer_key() == "targets"));
            f.node = !f.free && !array && p.array && st_.size() == 2 && st_[0].key == "nodes";
        }
        st_.push_back(f);
        return true;
    }

    bool close()
    {
        const Frame f = st_.back();
        st_.pop_back(); // path() now names the value just closed
        if (f.want && f.index != f.want)
            return fail(path() + " has " + std::to_string(f.index) + " numbers, not " +
                        std::to_string(f.want));
        if (f.node && f.has_matrix && f.has_trs)
            return fail(path() + " has both a matrix and translation, rotation or scale "
                        "(one or the other)");
        next();
        return true;
    }
};

} // namespace

int load_gltf(const char *path, const std::string &ext, const std::string &data,
              fp_mesh **out, char *err, size_t errlen)
{
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
    tinygltf::Model model;
    std::string gerr, gwarn;
    std::string dir = path;
    size_t slash = dir.find_last_of('/');
    dir = slash == std::string::npos ? std::string(".") : slash == 0 ? std::string("/")
                                                                       : dir.substr(0, slash);
    GltfFs fs{dir, {}};
    loader.SetFsCallbacks({gltf_fs_exists, gltf_fs_expand, gltf_fs_read, gltf_fs_write, &fs});
    if (data.size() > UINT_MAX)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path, "file too large");
    // GLB header: magic, version, length (glTF 2.0 section 4.4.2). tinygltf never reads the
    // version: a version 1 file (glTF 1.0's KHR_binary_glTF, another layout) or any other
    // number went on as if it were 2.
    if (ext == "glb" && data.size() >= 12 && data.compare(0, 4, "glTF") == 0) {
        const unsigned char *h = reinterpret_cast<const unsigned char *>(data.data()) + 4;
        const uint32_t version = uint32_t(h[0]) | uint32_t(h[1]) << 8 | uint32_t(h[2]) << 16 |
                                 uint32_t(h[3]) << 24;
        if (version == 1)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                                  "glTF: GLB header version 1 (glTF 1.0) is not supported "
                                  "(glTF 2.0 only)");
        if (version != 2)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "glTF: GLB header version %u (a glTF 2.0 GLB has version 2)",
                                  version);
    }
    bool ok;
    if (ext == "glb")
        ok = loader.LoadBinaryFromMemory(&model, &gerr, &gwarn,
                                         reinterpret_cast<const unsigned char *>(data.data()),
                                         unsigned(data.size()), dir);
    else
        ok = loader.LoadASCIIFromString(&model, &gerr, &gwarn, data.data(),
                                        unsigned(data.size()), dir);
    if (!fs.refused.empty())
        return fail(err, errlen, fs.code, path, "glTF: " + fs.refused);
    if (!ok)
        return fail(err, errlen, FP_MESH_ERR_FORMAT, path,
                    "glTF: " + one_line(gerr.empty() ? std::string("cannot parse") : gerr));
    // asset.version is "2.0" (or a later 2.x): a glTF 1.0 document differs throughout
    if (model.asset.version.compare(0, 2, "2.") != 0)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                              "glTF: asset.version '%.20s' is not supported (glTF 2.0 only)",
                              model.asset.version.c_str());
    {
        // the JSON again, for what tinygltf took without a word (GltfJsonCheck); parsed
        // already, so the GLB's JSON chunk is where its header says
        const char *json = data.data();
        size_t json_len = data.size();
        if (ext == "glb") {
            uint32_t chunk0;
            std::memcpy(&chunk0, data.data() + 12, 4); // little-endian hosts, as tinygltf
            json = data.data() + 20;
            json_len = chunk0;
        }
        GltfJsonCheck check;
        if (!nlohmann::json::sax_parse(json, json + json_len, &check) || !check.error.empty())
            return fail(err, errlen, FP_MESH_ERR_FORMAT, path,
                        "glTF: " + (check.error.empty() ? std::string("JSON error") : check.error));
    }
    // an extension the file requires is one this reader does not implement (none is): said
    // by name up front, not as a FORMAT error about an accessor it compressed (Draco, meshopt)
    if (!model.extensionsRequired.empty()) {
        std::string names;
        for (const std::string &x : model.extensionsRequired)
            names += (names.empty() ? "" : ", ") + x;
        return fail(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                    "glTF: requires the extension" +
                        std::string(model.extensionsRequired.size() > 1 ? "s " : " ") + one_line(names) +
                        ", not supported (export without it)");
    }
    Soup soup;
    GltfReader r{model, soup, {}, FP_MESH_OK, 0, 0, true, false, {}};
    std::vector<char> visited(model.nodes.size(), 0);
    int scene = model.defaultScene >= 0 ? model.defaultScene : (model.scenes.empty() ? -1 : 0);
    if (scene >= 0 && size_t(scene) >= model.scenes.size())
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "glTF: default scene %d does not exist", scene);
    if (scene >= 0) {
        for (int ni : model.scenes[size_t(scene)].nodes)
            if (!r.add_node(ni, mat_identity(), visited, 0))
                break;
    } else {
        for (size_t mi = 0; mi < model.meshes.size(); mi++)
            if (!r.add_mesh(int(mi), mat_identity(), -1))
                break;
    }
    if (r.code != FP_MESH_OK)
        return fail(err, errlen, r.code, path, "glTF: " + r.error);
    if (r.prims_seen > 0 && r.prims_used == 0)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                              "glTF: no triangle primitives (only points or lines)");
    if (!r.all_normals)
        std::fill(soup.has_nrm.begin(), soup.has_nrm.end(), 0);
    soup.any_vertex_uv = r.any_uv;
    auto src = std::make_unique<fp_mesh_source>();
    src->format = ext;
    src->instances = std::move(r.instances);
    src->model = std::make_unique<tinygltf::Model>(std::move(model));
    return soup_to_mesh(soup, path, out, err, errlen, src.release());
}

} // namespace fp_mesh_io
