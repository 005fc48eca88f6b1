// fp_mesh file I/O: the project's only C++. OBJ, PLY, OFF and STL go through OpenMesh's
// readers and writers, driven by our own importer/exporter over flat arrays (so OpenMesh's
// half-edge kernel never sees the mesh: no vertex is split or merged, no face dropped, and
// vertex order stays the file's). glTF 2.0 goes through tinygltf (Debian's shared build).
// Nothing here throws past the C API: every entry point catches.
#include "mesh_internal.h"
#include "fp_file.h"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/exporter/BaseExporter.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/Mesh/BaseKernel.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <tiny_gltf.h>
#include <nlohmann/json.hpp> // tinygltf's JSON library (it includes it too)

#include <fcntl.h>
#include <limits.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <mutex>
#include <new>
#include <sstream>
#include <string>
#include <array>
#include <atomic>
#include <map>
#include <memory>
#include <vector>
#include <algorithm>

// What a file held beyond fp_mesh's arrays, to write it back as it came in (fp_mesh.h).
// Immutable once loaded; shared between copies by reference count.
struct fp_mesh_source {
    std::atomic<int> refs{1};
    std::string format;                  // extension it came from: obj, ply, off, stl, gltf, glb
    size_t n = 0, t = 0;                 // vertex and triangle counts it describes
    std::vector<uint32_t> face_start{0}; // polygons: faces + 1 offsets into corners
    std::vector<uint32_t> corners;
    std::vector<float> corner_uv;        // corners x 2 where has_corner_uv
    std::vector<unsigned char> has_corner_uv;
    bool any_corner_uv = false, seams = false, polygons = false, file_normals = false;
    std::vector<int> face_material;      // OBJ: material per face (index into materials), -1
    std::vector<std::string> materials;  // OBJ usemtl names in first-use order
    bool groups = false;                 // OBJ g / o statements
    std::string obj_text;                // OBJ: the file
    // glTF: the document and where each triangle primitive's vertices went
    struct Instance {
        int mesh, prim;
        size_t first, count;             // mesh vertices [first, first + count)
        std::array<double, 16> xf;       // node transform applied at load (column-major)
        int pos, nrm;                    // accessors (nrm -1: none)
    };
    std::unique_ptr<tinygltf::Model> model;
    std::vector<Instance> instances;
};

extern "C" struct fp_mesh_source *fp__mesh_source_ref(struct fp_mesh_source *src)
{
    if (src)
        src->refs.fetch_add(1, std::memory_order_relaxed);
    return src;
}

extern "C" void fp__mesh_source_unref(struct fp_mesh_source *src)
{
    if (src && src->refs.fetch_sub(1, std::memory_order_acq_rel) == 1)
        delete src;
}

namespace {

using OpenMesh::EdgeHandle;
using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;
using OpenMesh::Vec2f;
using OpenMesh::Vec3d;
using OpenMesh::Vec3f;
using OpenMesh::Vec3uc;
using OpenMesh::Vec3ui;
using OpenMesh::Vec4f;
using OpenMesh::Vec4uc;
using OpenMesh::Vec4ui;
namespace IO = OpenMesh::IO;

// A mesh as the readers deliver it: vertices, optional per-vertex normals and UVs, polygons
// as corner lists with optional per-corner UVs. fp_mesh is built from it.
struct Soup {
    std::vector<float> pos;              // n x 3
    std::vector<float> nrm;              // n x 3 where has_nrm
    std::vector<float> uv;               // n x 2 where has_uv
    std::vector<unsigned char> has_nrm, has_uv;
    std::vector<uint32_t> face_start{0}; // faces + 1 offsets into corners
    std::vector<uint32_t> corners;
    std::vector<float> corner_uv;        // corners x 2 where has_corner_uv
    std::vector<unsigned char> has_corner_uv;
    bool any_corner_uv = false, any_vertex_uv = false;
    std::string error;                   // first problem found while reading, or ""

    size_t n() const { return pos.size() / 3; }
    size_t faces() const { return face_start.size() - 1; }
    void fail(const std::string &msg) { if (error.empty()) error = msg; }

    size_t add_vertex(float x, float y, float z)
    {
        if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
            fail("vertex " + std::to_string(n()) + " has a non-finite coordinate");
        pos.push_back(x); pos.push_back(y); pos.push_back(z);
        nrm.resize(pos.size()); uv.resize(n() * 2);
        has_nrm.push_back(0); has_uv.push_back(0);
        return n() - 1;
    }
};

// OpenMesh importer that records what a reader delivers, with no connectivity checks.
class Collector : public IO::BaseImporter {
public:
    explicit Collector(Soup &s) : s_(s) {}

    VertexHandle add_vertex(const Vec3f &p) override
    {
        return VertexHandle(int(s_.add_vertex(p[0], p[1], p[2])));
    }
    VertexHandle add_vertex(const Vec3d &p) override
    {
        return VertexHandle(int(s_.add_vertex(float(p[0]), float(p[1]), float(p[2]))));
    }
    VertexHandle add_vertex() override { return VertexHandle(int(s_.add_vertex(0, 0, 0))); }
    HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }

    FaceHandle add_face(const VHandles &idx) override
    {
        const size_t face = s_.faces();
        for (const VertexHandle &vh : idx) {
            if (vh.idx() < 0 || size_t(vh.idx()) >= s_.n()) {
                s_.fail("face " + std::to_string(face) + " references vertex " +
                        std::to_string(vh.idx()) + ", but the file has " +
                        std::to_string(s_.n()) + " vertices");
                return FaceHandle();
            }
        }
        if (idx.size() < 3) {
            s_.fail("face " + std::to_string(face) + " has " + std::to_string(idx.size()) +
                    " corners (at least 3)");
            return FaceHandle();
        }
        for (const VertexHandle &vh : idx)
            s_.corners.push_back(uint32_t(vh.idx()));
        s_.face_start.push_back(uint32_t(s_.corners.size()));
        s_.corner_uv.resize(s_.corners.size() * 2);
        s_.has_corner_uv.resize(s_.corners.size());
        return FaceHandle(int(face));
    }
    FaceHandle add_face(HalfedgeHandle) override
    {
        s_.fail("the reader used half-edge input, which is not supported");
        return FaceHandle();
    }

    // Texture coordinates of a face's corners, starting at the corner of vertex _vh.
    void add_face_texcoords(FaceHandle fh, VertexHandle vh,
                            const std::vector<Vec2f> &tc) override
    {
        if (!fh.is_valid() || size_t(fh.idx()) >= s_.faces())
            return;
        const uint32_t b = s_.face_start[size_t(fh.idx())];
        const uint32_t e = s_.face_start[size_t(fh.idx()) + 1];
        uint32_t start = b;
        for (uint32_t c = b; c < e; c++)
            if (int(s_.corners[c]) == vh.idx()) { start = c; break; }
        for (size_t i = 0; i < tc.size() && i < size_t(e - b); i++) {
            const uint32_t c = b + uint32_t((start - b + i) % (e - b));
            if (!std::isfinite(tc[i][0]) || !std::isfinite(tc[i][1]))
                s_.fail("face " + std::to_string(fh.idx()) + " has a non-finite texture coordinate");
            s_.corner_uv[2 * c] = tc[i][0];
            s_.corner_uv[2 * c + 1] = tc[i][1];
            s_.has_corner_uv[c] = 1;
            s_.any_corner_uv = true;
        }
    }
    void add_face_texcoords(FaceHandle fh, VertexHandle vh,
                            const std::vector<OpenMesh::Vec3f> &tc) override
    {
        std::vector<Vec2f> t2;
        for (const auto &t : tc)
            t2.push_back(Vec2f(t[0], t[1]));
        add_face_texcoords(fh, vh, t2);
    }
    void set_face_texindex(FaceHandle, int) override {}

    void set_point(VertexHandle vh, const Vec3f &p) override
    {
        if (!valid(vh))
            return;
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
            s_.fail("vertex " + std::to_string(vh.idx()) + " has a non-finite coordinate");
        for (int k = 0; k < 3; k++)
            s_.pos[3 * size_t(vh.idx()) + k] = p[k];
    }
    void set_halfedge(VertexHandle, HalfedgeHandle) override {}
    void set_normal(VertexHandle vh, const Vec3f &nv) override
    {
        if (!valid(vh))
            return;
        if (!std::isfinite(nv[0]) || !std::isfinite(nv[1]) || !std::isfinite(nv[2]))
            s_.fail("vertex " + std::to_string(vh.idx()) + " has a non-finite normal");
        for (int k = 0; k < 3; k++)
            s_.nrm[3 * size_t(vh.idx()) + k] = nv[k];
        s_.has_nrm[size_t(vh.idx())] = 1;
    }
    void set_normal(VertexHandle vh, const Vec3d &nv) override { set_normal(vh, Vec3f(nv)); }
    void set_color(VertexHandle, const Vec3uc &) override {}
    void set_color(VertexHandle, const Vec4uc &) override {}
    void set_color(VertexHandle, const Vec3f &) override {}
    void set_color(VertexHandle, const Vec4f &) override {}
    void set_texcoord(VertexHandle vh, const Vec2f &t) override
    {
        if (!valid(vh))
            return;
        if (!std::isfinite(t[0]) || !std::isfinite(t[1]))
            s_.fail("vertex " + std::to_string(vh.idx()) + " has a non-finite texture coordinate");
        s_.uv[2 * size_t(vh.idx())] = t[0];
        s_.uv[2 * size_t(vh.idx()) + 1] = t[1];
        s_.has_uv[size_t(vh.idx())] = 1;
        s_.any_vertex_uv = true;
    }
    void set_texcoord(VertexHandle vh, const Vec3f &t) override { set_texcoord(vh, Vec2f(t[0], t[1])); }
    void set_status(VertexHandle, const OpenMesh::Attributes::StatusInfo &) override {}
    void set_next(HalfedgeHandle, HalfedgeHandle) override {}
    void set_face(HalfedgeHandle, FaceHandle) override {}
    void request_face_texcoords2D() override {}
    void set_texcoord(HalfedgeHandle, const Vec2f &) override {}
    void set_texcoord(HalfedgeHandle, const Vec3f &) override {}
    void set_status(HalfedgeHandle, const OpenMesh::Attributes::StatusInfo &) override {}
    void set_color(EdgeHandle, const Vec3uc &) override {}
    void set_color(EdgeHandle, const Vec4uc &) override {}
    void set_color(EdgeHandle, const Vec3f &) override {}
    void set_color(EdgeHandle, const Vec4f &) override {}
    void set_status(EdgeHandle, const OpenMesh::Attributes::StatusInfo &) override {}
    void set_normal(FaceHandle, const Vec3f &) override {}
    void set_normal(FaceHandle, const Vec3d &) override {}
    void set_color(FaceHandle, const Vec3uc &) override {}
    void set_color(FaceHandle, const Vec4uc &) override {}
    void set_color(FaceHandle, const Vec3f &) override {}
    void set_color(FaceHandle, const Vec4f &) override {}
    void set_status(FaceHandle, const OpenMesh::Attributes::StatusInfo &) override {}
    void add_texture_information(int, std::string) override {}
    void reserve(unsigned int nv, unsigned int, unsigned int nf) override
    {
        // counts come from file headers: cap them so a lying header cannot exhaust memory
        const unsigned int cap = 1u << 24;
        s_.pos.reserve(3 * size_t(nv < cap ? nv : cap));
        s_.face_start.reserve(size_t(nf < cap ? nf : cap) + 1);
    }
    size_t n_vertices() const override { return s_.n(); }
    size_t n_faces() const override { return s_.faces(); }
    size_t n_edges() const override { return 0; }

private:
    bool valid(VertexHandle vh) const { return vh.idx() >= 0 && size_t(vh.idx()) < s_.n(); }
    Soup &s_;
};

// OpenMesh exporter over an fp_mesh's arrays: faces are its triangles.
class ArrayExporter : public IO::BaseExporter {
public:
    // poly: write these polygons instead of the mesh's triangles (nullptr: triangles)
    explicit ArrayExporter(const fp_mesh &m, const fp_mesh_source *poly = nullptr)
        : m_(m), poly_(poly) {}

    Vec3f point(VertexHandle vh) const override
    {
        const float *p = m_.positions + 3 * size_t(vh.idx());
        return Vec3f(p[0], p[1], p[2]);
    }
    Vec3d pointd(VertexHandle vh) const override { return Vec3d(point(vh)); }
    bool is_point_double() const override { return false; }
    Vec3f normal(VertexHandle vh) const override
    {
        if (!m_.normals)
            return Vec3f(0, 0, 0);
        const float *p = m_.normals + 3 * size_t(vh.idx());
        return Vec3f(p[0], p[1], p[2]);
    }
    Vec3d normald(VertexHandle vh) const override { return Vec3d(normal(vh)); }
    bool is_normal_double() const override { return false; }
    Vec3uc color(VertexHandle) const override { return Vec3uc(0, 0, 0); }
    Vec4uc colorA(VertexHandle) const override { return Vec4uc(0, 0, 0, 0); }
    Vec3ui colori(VertexHandle) const override { return Vec3ui(0, 0, 0); }
    Vec4ui colorAi(VertexHandle) const override { return Vec4ui(0, 0, 0, 0); }
    Vec3f colorf(VertexHandle) const override { return Vec3f(0, 0, 0); }
    Vec4f colorAf(VertexHandle) const override { return Vec4f(0, 0, 0, 0); }
    Vec2f texcoord(VertexHandle vh) const override
    {
        if (!m_.uvs)
            return Vec2f(0, 0);
        const float *p = m_.uvs + 2 * size_t(vh.idx());
        return Vec2f(p[0], p[1]);
    }
    Vec2f texcoord(HalfedgeHandle) const override { return Vec2f(0, 0); }
    OpenMesh::Attributes::StatusInfo status(VertexHandle) const override { return {}; }
    unsigned int get_vhandles(FaceHandle fh, std::vector<VertexHandle> &vh) const override
    {
        vh.clear();
        if (poly_) {
            const size_t f = size_t(fh.idx());
            for (uint32_t c = poly_->face_start[f]; c < poly_->face_start[f + 1]; c++)
                vh.push_back(VertexHandle(int(poly_->corners[c])));
            return unsigned(vh.size());
        }
        const uint32_t *t = m_.triangles + 3 * size_t(fh.idx());
        for (int k = 0; k < 3; k++)
            vh.push_back(VertexHandle(int(t[k])));
        return 3;
    }
    HalfedgeHandle getHeh(FaceHandle, VertexHandle) const override { return HalfedgeHandle(); }
    unsigned int get_face_texcoords(std::vector<Vec2f> &) const override { return 0; }
    Vec3f normal(FaceHandle fh) const override
    {
        uint32_t t[3];
        if (poly_) {
            const uint32_t b0 = poly_->face_start[size_t(fh.idx())];
            t[0] = poly_->corners[b0]; t[1] = poly_->corners[b0 + 1]; t[2] = poly_->corners[b0 + 2];
        } else {
            std::memcpy(t, m_.triangles + 3 * size_t(fh.idx()), sizeof t);
        }
        Vec3f a = point(VertexHandle(int(t[0]))), b = point(VertexHandle(int(t[1]))),
              c = point(VertexHandle(int(t[2])));
        Vec3f n = OpenMesh::cross(b - a, c - a);
        float len = n.norm();
        return len > 0 ? n / len : Vec3f(0, 0, 0);
    }
    Vec3d normald(FaceHandle fh) const override { return Vec3d(normal(fh)); }
    Vec3uc color(FaceHandle) const override { return Vec3uc(0, 0, 0); }
    Vec4uc colorA(FaceHandle) const override { return Vec4uc(0, 0, 0, 0); }
    Vec3ui colori(FaceHandle) const override { return Vec3ui(0, 0, 0); }
    Vec4ui colorAi(FaceHandle) const override { return Vec4ui(0, 0, 0, 0); }
    Vec3f colorf(FaceHandle) const override { return Vec3f(0, 0, 0); }
    Vec4f colorAf(FaceHandle) const override { return Vec4f(0, 0, 0, 0); }
    OpenMesh::Attributes::StatusInfo status(FaceHandle) const override { return {}; }
    Vec3uc color(EdgeHandle) const override { return Vec3uc(0, 0, 0); }
    Vec4uc colorA(EdgeHandle) const override { return Vec4uc(0, 0, 0, 0); }
    Vec3ui colori(EdgeHandle) const override { return Vec3ui(0, 0, 0); }
    Vec4ui colorAi(EdgeHandle) const override { return Vec4ui(0, 0, 0, 0); }
    Vec3f colorf(EdgeHandle) const override { return Vec3f(0, 0, 0); }
    Vec4f colorAf(EdgeHandle) const override { return Vec4f(0, 0, 0, 0); }
    OpenMesh::Attributes::StatusInfo status(EdgeHandle) const override { return {}; }
    int get_halfedge_id(VertexHandle) override { return -1; }
    int get_halfedge_id(FaceHandle) override { return -1; }
    int get_next_halfedge_id(HalfedgeHandle) override { return -1; }
    int get_to_vertex_id(HalfedgeHandle) override { return -1; }
    int get_face_id(HalfedgeHandle) override { return -1; }
    OpenMesh::Attributes::StatusInfo status(HalfedgeHandle) const override { return {}; }
    size_t n_vertices() const override { return m_.vertex_count; }
    size_t n_faces() const override
    {
        return poly_ ? poly_->face_start.size() - 1 : m_.triangle_count;
    }
    size_t n_edges() const override { return 0; }
    bool is_triangle_mesh() const override { return !poly_ || !poly_->polygons; }
    bool has_vertex_normals() const override { return m_.normals != nullptr; }
    bool has_vertex_texcoords() const override { return m_.uvs != nullptr; }
    // The PLY writer looks for custom properties in a kernel: give it an empty one.
    const OpenMesh::BaseKernel *kernel() override { return &no_properties_; }

private:
    const fp_mesh &m_;
    const fp_mesh_source *poly_;
    OpenMesh::BaseKernel no_properties_;
};

// OpenMesh's reader/writer singletons keep per-call state and its log streams are global:
// one OpenMesh call at a time, with its log captured instead of printed.
std::mutex openmesh_lock;

// OpenMesh's log text, kept up to a cap: a reader that loops while it logs (it did, on a bad
// PLY header) must not grow memory without bound.
class CappedLog : public std::streambuf {
public:
    static constexpr size_t cap = 64 * 1024;
    std::string text;
    bool truncated = false;

protected:
    int_type overflow(int_type ch) override
    {
        if (ch != traits_type::eof()) {
            if (text.size() < cap)
                text.push_back(char(ch));
            else
                truncated = true;
        }
        return traits_type::not_eof(ch);
    }
    std::streamsize xsputn(const char *s, std::streamsize n) override
    {
        const size_t room = text.size() < cap ? cap - text.size() : 0;
        const size_t k = size_t(n) < room ? size_t(n) : room;
        text.append(s, k);
        if (k < size_t(n))
            truncated = true;
        return n;
    }
};

// OpenMesh's log streams are std::ostreams whose buffer multiplexes to std::cerr etc. While
// OpenMesh works we point them at our own capped buffer (mostream::disconnect would leak its
// target object on every call), then restore them.
class OmLogCapture {
public:
    OmLogCapture()
    {
        OpenMesh::mostream *s[3] = {&::omerr(), &::omlog(), &::omout()};
        for (int i = 0; i < 3; i++) {
            streams_[i] = s[i];
            s[i]->flush();
            saved_[i] = s[i]->rdbuf(&text_);
        }
    }
    ~OmLogCapture()
    {
        for (int i = 0; i < 3; i++) {
            streams_[i]->flush();
            streams_[i]->rdbuf(saved_[i]);
            streams_[i]->clear();
        }
    }
    // The first line of what OpenMesh logged, for an error message ("" if nothing).
    std::string first_line()
    {
        const std::string &t = text_.text;
        size_t b = t.find_first_not_of(" \t\r\n");
        if (b == std::string::npos)
            return "";
        size_t e = t.find_first_of("\r\n", b);
        std::string line = t.substr(b, e == std::string::npos ? std::string::npos : e - b);
        return line.size() > 200 ? line.substr(0, 200) + "..." : line;
    }
    size_t captured() const { return text_.text.size(); }
    bool truncated() const { return text_.truncated; }
    OmLogCapture(const OmLogCapture &) = delete;
    OmLogCapture &operator=(const OmLogCapture &) = delete;

private:
    CappedLog text_;
    OpenMesh::mostream *streams_[3];
    std::streambuf *saved_[3];
};

// ---- small helpers ------------------------------------------------------------------

int fail(char *err, size_t errlen, int code, const char *path, const std::string &msg)
{
    return fp__mesh_error(err, errlen, code, path, "%s", msg.c_str());
}

// The project's code for a failed open/read/write (fp_error.h's table).
int errno_code(int e)
{
    switch (e) {
    case ENOENT: case ENOTDIR: case ENAMETOOLONG: case ELOOP: return FP_MESH_ERR_NOENT;
    case EACCES: case EPERM: case EROFS: return FP_MESH_ERR_ACCESS;
    case ENOSPC: case EDQUOT: return FP_MESH_ERR_NOSPACE;
    case ENOMEM: return FP_MESH_ERR_NOMEM;
    default: return FP_MESH_ERR_IO;
    }
}

// Open a file for reading only if it is a regular file (fp_file_open_regular: a FIFO or a
// device cannot block the open; a folder, FIFO or device is "not there", NOENT, as an input
// that cannot be opened). Returns the fd, or -1 with *code and *why set.
int open_regular(const char *path, size_t max_bytes, off_t *size, int *code, std::string *why)
{
    int fd = fp_file_open_regular(path);
    if (fd < 0) {
        *code = fd == -EISDIR || fd == -ENXIO ? FP_MESH_ERR_NOENT : errno_code(-fd);
        *why = std::string(fd == -EISDIR || fd == -ENXIO ? "" : "cannot open: ") +
               fp_file_error_text(fd);
        return -1;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        const int e = errno;
        ::close(fd);
        *code = errno_code(e);
        *why = std::string("cannot read: ") + std::strerror(e);
        return -1;
    }
    if (uint64_t(st.st_size) > max_bytes) {
        ::close(fd);
        *code = FP_MESH_ERR_UNSUPPORTED;
        *why = "file too large (" + std::to_string(st.st_size) + " bytes)";
        return -1;
    }
    *size = st.st_size;
    return fd;
}

// Read all of fd (a regular file of about `size` bytes) into data.
bool read_fd(int fd, off_t size, std::string &data, int *code, std::string *why)
{
    data.clear();
    data.reserve(size_t(size));
    char buf[1 << 16];
    for (;;) {
        ssize_t got = ::read(fd, buf, sizeof buf);
        if (got < 0 && errno == EINTR)
            continue;
        if (got < 0) {
            *code = errno_code(errno);
            *why = std::string("cannot read: ") + std::strerror(errno);
            return false;
        }
        if (got == 0)
            return true;
        data.append(buf, size_t(got));
    }
}

// Mesh files larger than this are refused (2 GiB: far above any face mesh).
constexpr size_t max_file_bytes = size_t(1) << 31;

int read_whole_file(const char *path, std::string &data, char *err, size_t errlen)
{
    off_t size = 0;
    int code = FP_MESH_OK;
    std::string why;
    int fd = open_regular(path, max_file_bytes, &size, &code, &why);
    if (fd < 0)
        return fail(err, errlen, code, path, why);
    const bool ok = read_fd(fd, size, data, &code, &why);
    ::close(fd);
    if (!ok)
        return fail(err, errlen, code, path, why);
    if (data.empty())
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path, "file is empty");
    return FP_MESH_OK;
}

// Write `bytes` to `path` so that the file is never half-written: a temporary file in the
// same folder (fp_file_open_output), every write checked, fsync, then rename over the target
// (and an fsync of the folder). On any failure the temporary file is removed and the old file,
// if any, is left as it was. A new file gets mode 0666 & ~umask; a replaced one keeps its mode.
int write_atomically(const char *given, const std::string &bytes, char *err, size_t errlen)
{
    // the file replaced: a link's end (written through), never a folder, FIFO or device
    fp_file_output o;
    const int rc = fp_file_open_output(given, "", nullptr,
                                       FP_FILE_OUTPUT_KEEP_MODE | FP_FILE_OUTPUT_SYNC_FOLDER,
                                       &o);
    if (rc < 0 && o.failed == FP_FILE_STEP_TARGET)
        return fp__mesh_error(err, errlen, rc == -EISDIR || rc == -ENXIO ? FP_MESH_ERR_IO : errno_code(-rc),
                              given, "cannot replace it: %s", fp_file_error_text(rc));
    const char *path = o.path;
    if (rc < 0 && o.failed == FP_FILE_STEP_TEMP) {
        const char *slash = std::strrchr(path, '/');
        const std::string dir = !slash ? std::string(".") : slash == path ? std::string("/")
                                                          : std::string(path, size_t(slash - path));
        return fp__mesh_error(err, errlen, errno_code(-rc), path,
                              "cannot create a temporary file in %s: %s", dir.c_str(),
                              std::strerror(-rc));
    }
    auto give_up = [&](const char *what, int e) {
        fp_file_output_abort(&o);
        return fp__mesh_error(err, errlen, errno_code(e), path,
                              "%s: %s (the previous file, if any, is unchanged)", what,
                              std::strerror(e));
    };
    const char *p = bytes.data();
    size_t left = bytes.size();
    while (left > 0) {
        ssize_t put = ::write(o.fd, p, left);
        if (put < 0 && errno == EINTR)
            continue;
        if (put <= 0)
            return give_up("write failed", put < 0 ? errno : EIO);
        p += put;
        left -= size_t(put);
    }
    const int cr = fp_file_output_commit(&o);
    if (cr < 0)
        return give_up(o.failed == FP_FILE_STEP_SYNC    ? "fsync failed"
                       : o.failed == FP_FILE_STEP_CLOSE ? "close failed"
                                                        : "cannot replace the file",
                       -cr);
    return FP_MESH_OK;
}

// Build the fp_mesh from a Soup: fan triangulation, per-vertex UVs, normals.
// The polygons of a Soup into a source (which keeps them for writing back).
void keep_polygons(const Soup &s, fp_mesh_source &src)
{
    src.face_start = s.face_start;
    src.corners = s.corners;
    src.corner_uv = s.corner_uv;
    src.has_corner_uv = s.has_corner_uv;
    src.corner_uv.resize(2 * s.corners.size(), 0.0f);
    src.has_corner_uv.resize(s.corners.size(), 0);
    src.any_corner_uv = s.any_corner_uv;
    size_t t = 0;
    for (size_t f = 0; f + 1 < s.face_start.size(); f++) {
        const uint32_t k = s.face_start[f + 1] - s.face_start[f];
        t += k - 2;
        if (k > 3)
            src.polygons = true;
    }
    src.n = s.n();
    src.t = t;
    // a seam: one vertex with two different corner UVs
    std::vector<float> first(2 * s.n());
    std::vector<unsigned char> seen(s.n(), 0);
    for (size_t c = 0; c < s.corners.size() && !src.seams; c++) {
        if (!src.has_corner_uv[c])
            continue;
        const uint32_t v = s.corners[c];
        if (!seen[v]) {
            seen[v] = 1;
            first[2 * v] = src.corner_uv[2 * c];
            first[2 * v + 1] = src.corner_uv[2 * c + 1];
        } else if (first[2 * v] != src.corner_uv[2 * c] ||
                   first[2 * v + 1] != src.corner_uv[2 * c + 1]) {
            src.seams = true;
        }
    }
}

int soup_to_mesh(Soup &s, const char *path, fp_mesh **out, char *err, size_t errlen,
                 fp_mesh_source *src = nullptr)
{
    std::unique_ptr<fp_mesh_source> keep(src);
    const size_t n = s.n();
    if (n == 0)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path, "no vertices");
    if (n > UINT32_MAX)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                              "%zu vertices exceed 32-bit indices", n);
    size_t t = 0;
    for (size_t f = 0; f < s.faces(); f++)
        t += s.face_start[f + 1] - s.face_start[f] - 2;
    if (t == 0)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path, "no faces");
    const bool with_uvs = s.any_corner_uv || s.any_vertex_uv;
    s.has_corner_uv.resize(s.corners.size(), 0);
    s.corner_uv.resize(2 * s.corners.size(), 0.0f);
    fp_mesh *m = fp_mesh_create(n, t, with_uvs);
    if (!m)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_NOMEM, path, "out of memory");
    std::memcpy(m->positions, s.pos.data(), n * 3 * sizeof(float));
    size_t k = 0;
    for (size_t f = 0; f < s.faces(); f++) {
        const uint32_t b = s.face_start[f], e = s.face_start[f + 1];
        for (uint32_t c = b + 1; c + 1 < e; c++) {
            m->triangles[3 * k] = s.corners[b];
            m->triangles[3 * k + 1] = s.corners[c];
            m->triangles[3 * k + 2] = s.corners[c + 1];
            k++;
        }
    }
    if (with_uvs) {
        // a corner's UV wins over a vertex UV; among corners, the first use in face order
        std::vector<unsigned char> set(n, 0);
        for (size_t c = 0; c < s.corners.size(); c++) {
            const uint32_t v = s.corners[c];
            if (s.has_corner_uv[c] && !set[v]) {
                m->uvs[2 * v] = s.corner_uv[2 * c];
                m->uvs[2 * v + 1] = s.corner_uv[2 * c + 1];
                set[v] = 1;
            }
        }
        for (size_t v = 0; v < n; v++)
            if (!set[v] && s.has_uv[v]) {
                m->uvs[2 * v] = s.uv[2 * v];
                m->uvs[2 * v + 1] = s.uv[2 * v + 1];
            }
    }
    bool file_normals = true;
    for (size_t v = 0; v < n && file_normals; v++) {
        const float *q = &s.nrm[3 * v];
        const double len = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] +
                                     double(q[2]) * q[2]);
        if (!s.has_nrm[v] || !(len > 0.0) || !std::isfinite(len)) {
            file_normals = false;
            break;
        }
        for (int d = 0; d < 3; d++)
            m->normals[3 * v + d] = float(q[d] / len);
    }
    if (!file_normals)
        fp_mesh_normals(m->triangles, t, m->positions, n, m->normals);
    m->source_path = strdup(path);
    if (!m->source_path) {
        fp_mesh_free(&m);
        return fp__mesh_error(err, errlen, FP_MESH_ERR_NOMEM, path, "out of memory");
    }
    if (keep) {
        keep_polygons(s, *keep);
        keep->file_normals = file_normals;
        m->source = keep.release();
    }
    *out = m;
    return FP_MESH_OK;
}

// ---- OpenMesh formats ---------------------------------------------------------------

// OBJ text with every `mtllib` statement turned into a comment (same length and lines).
std::string obj_without_mtllib(const std::string &data)
{
    std::string out = data;
    size_t p = 0;
    while (p < out.size()) {
        size_t b = out.find_first_not_of(" \t", p);
        if (b != std::string::npos && out.compare(b, 6, "mtllib") == 0 &&
            (b + 6 == out.size() || std::isspace((unsigned char)out[b + 6])))
            out[b] = '#';
        size_t e = out.find('\n', p);
        if (e == std::string::npos)
            break;
        p = e + 1;
    }
    return out;
}

// A read-only stream over text already in memory (OpenMesh reads OBJ from a stream; an
// istringstream would copy the whole file again, 279 MiB for a 1.7M-vertex face). Seeks in
// the get area, as OpenMesh's OBJ reader rewinds for its second pass.
struct MemBuf : std::streambuf {
    MemBuf(const char *b, size_t n)
    {
        char *p = const_cast<char *>(b); // never written: no put area
        setg(p, p, p + n);
    }
    pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override
    {
        if (!(which & std::ios_base::in))
            return pos_type(off_type(-1));
        off_type base = dir == std::ios_base::beg ? 0 : dir == std::ios_base::cur ? gptr() - eback()
                                                                                  : egptr() - eback();
        off_type to = base + off;
        if (to < 0 || to > egptr() - eback())
            return pos_type(off_type(-1));
        setg(eback(), eback() + to, egptr());
        return pos_type(to);
    }
    pos_type seekpos(pos_type pos, std::ios_base::openmode which) override
    {
        return seekoff(off_type(pos), std::ios_base::beg, which);
    }
};

// PLY bytes with the header's comment and obj_info lines left out (the body unchanged), for
// OpenMesh's reader: it takes obj_info's words for keywords, and after a comment line it
// looks for a binary body one byte too far (it finds the body from where its last token
// read ended, and a comment is read with getline, to the next line). fp__ply_scan accepted
// the header with them, and checked it as OpenMesh will see it. Empty when there are none
// (the bytes are used as they are).
std::string ply_without_notes(const std::string &data)
{
    std::string out;
    size_t p = 0, kept = 0; // kept: data[0, kept) is in out or still to be copied as a block
    bool any = false;
    while (p < data.size()) {
        size_t eol = data.find('\n', p);
        if (eol == std::string::npos)
            break; // no end_header: the scan refused that
        size_t b = p;
        while (b < eol && std::strchr(" \t\r\v\f", data[b]))
            b++;
        size_t e = b;
        while (e < eol && !std::strchr(" \t\r\v\f", data[e]))
            e++;
        const std::string word = data.substr(b, e - b);
        if (p > 0 && (word == "comment" || word == "obj_info")) {
            if (!any)
                out.reserve(data.size());
            any = true;
            out.append(data, kept, p - kept);
            kept = eol + 1;
        }
        p = eol + 1;
        if (word == "end_header")
            break;
    }
    if (!any)
        return std::string();
    out.append(data, kept, std::string::npos);
    return out;
}

// One line of OBJ text split into whitespace tokens (the text passed fp__obj_scan).
struct ObjLine {
    size_t begin, end;                 // the line without its '\n' (and '\r')
    bool cr;                           // the line ended in "\r\n"
    std::vector<std::pair<size_t, size_t>> tok; // token offsets and lengths
};

bool obj_next_line(const std::string &text, size_t &p, ObjLine &l)
{
    if (p >= text.size())
        return false;
    size_t e = text.find('\n', p);
    if (e == std::string::npos)
        e = text.size();
    l.begin = p;
    l.end = e;
    l.cr = e > p && text[e - 1] == '\r';
    if (l.cr)
        l.end--;
    l.tok.clear();
    size_t q = l.begin;
    while (q < l.end) {
        while (q < l.end && (text[q] == ' ' || text[q] == '\t'))
            q++;
        if (q >= l.end)
            break;
        size_t b = q;
        while (q < l.end && text[q] != ' ' && text[q] != '\t')
            q++;
        l.tok.push_back({b, q - b});
    }
    p = e + 1;
    return true;
}

bool obj_is(const std::string &text, const ObjLine &l, const char *kw)
{
    return !l.tok.empty() && text.compare(l.tok[0].first, l.tok[0].second, kw) == 0 &&
           std::strlen(kw) == l.tok[0].second;
}

// Corner k of an f line: 0-based v, vt, vn indices (-1 where absent), relative resolved.
void obj_corner(const std::string &text, std::pair<size_t, size_t> tok, size_t nv, size_t nvt,
                size_t nvn, long out[3])
{
    out[0] = out[1] = out[2] = -1;
    const size_t count[3] = {nv, nvt, nvn};
    size_t q = tok.first, e = tok.first + tok.second;
    for (int k = 0; k < 3 && q <= e; k++) {
        size_t s = q;
        while (q < e && text[q] != '/')
            q++;
        if (q > s) {
            long x = std::strtol(text.c_str() + s, nullptr, 10);
            out[k] = x < 0 ? long(count[k]) + x : x - 1;
        }
        q++;
    }
}

// OBJ materials per face (faces OpenMesh keeps: >= 3 distinct vertices) and groups.
void obj_materials(const std::string &text, fp_mesh_source &src)
{
    size_t p = 0, nv = 0, nvt = 0, nvn = 0;
    int current = -1;
    ObjLine l;
    while (obj_next_line(text, p, l)) {
        if (l.tok.empty())
            continue;
        if (obj_is(text, l, "v")) nv++;
        else if (obj_is(text, l, "vt")) nvt++;
        else if (obj_is(text, l, "vn")) nvn++;
        else if (obj_is(text, l, "g") || obj_is(text, l, "o")) src.groups = true;
        else if (obj_is(text, l, "usemtl") && l.tok.size() >= 2) {
            const std::string name = text.substr(l.tok[1].first, l.tok.back().first +
                                                 l.tok.back().second - l.tok[1].first);
            current = -1;
            for (size_t i = 0; i < src.materials.size(); i++)
                if (src.materials[i] == name)
                    current = int(i);
            if (current < 0) {
                src.materials.push_back(name);
                current = int(src.materials.size() - 1);
            }
        } else if (obj_is(text, l, "f")) {
            std::vector<long> vs;
            for (size_t k = 1; k < l.tok.size(); k++) {
                long c[3];
                obj_corner(text, l.tok[k], nv, nvt, nvn, c);
                if (std::find(vs.begin(), vs.end(), c[0]) == vs.end())
                    vs.push_back(c[0]);
            }
            if (vs.size() >= 3)
                src.face_material.push_back(current);
        }
    }
}

// data: the file's bytes, taken (an OBJ's text is moved into the mesh's source).
int load_openmesh(const char *path, const std::string &ext, std::string &data,
                  fp_mesh **out, char *err, size_t errlen)
{
    fp__obj_info obj{};
    size_t want_v = 0, want_f = 0; // the header's counts (PLY, OFF)
    if (ext == "obj") {
        int rc = fp__obj_scan(path, data.c_str(), data.size(), &obj, err, errlen);
        if (rc != FP_MESH_OK)
            return rc;
    }
    if (ext == "off") {
        // OpenMesh's ASCII OFF reader does not check its stream: a bad number silently
        // becomes 0 and leaves later values undefined. Check the text first.
        int rc = fp__off_scan(path, data.c_str(), data.size(), &want_v, &want_f, err, errlen);
        if (rc != FP_MESH_OK)
            return rc;
    }
    IO::Options opt = IO::Options::VertexNormal;
    opt += IO::Options::VertexTexCoord;
    opt += IO::Options::FaceTexCoord;
    if (ext == "stl") {
        // binary STL: 80-byte header, uint32 count, 50 bytes per triangle; else ASCII "solid"
        bool binary = false;
        if (data.size() >= 84) {
            uint32_t count;
            std::memcpy(&count, data.data() + 80, 4);
            binary = data.size() == 84 + 50 * uint64_t(count);
        }
        size_t b = data.find_first_not_of(" \t\r\n");
        if (!binary && (b == std::string::npos || data.compare(b, 5, "solid") != 0))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                                  "not an STL file (no 'solid' and the size does not match a "
                                  "binary STL's triangle count)");
        if (!binary) {
            int rc = fp__stl_ascii_scan(path, data.c_str(), data.size(), err, errlen);
            if (rc != FP_MESH_OK)
                return rc;
        }
    }
    if (ext == "ply") {
        int rc = fp__ply_scan(path, data.c_str(), data.size(), &want_v, &want_f, err, errlen);
        if (rc != FP_MESH_OK)
            return rc;
    }
    Soup soup;
    bool ok;
    std::string log;
    {
        std::lock_guard<std::mutex> guard(openmesh_lock);
        OmLogCapture capture;
        // OFF/STL by file name, not from `data`: their stream readers skip the header probe
        // (can_u_read) and would use the flags of the previous file (OFF's ST/N/C, STL's
        // binary). The file was just read whole and checked.
        // PLY from memory (its stream reader parses the header itself): the bytes the scan
        // checked, less the header's comment and obj_info lines (ply_without_notes).
        // OBJ from memory, with its `mtllib` lines commented out: OpenMesh would open the
        // named material files itself, wherever they point (outside the folder, a FIFO
        // that blocks for ever), and materials are not used.
        Collector collector(soup);
        if (ext == "obj") {
            // the text as it is unless it names material files (a copy with them commented)
            const std::string masked = obj.mtllib ? obj_without_mtllib(data) : std::string();
            const std::string &text = obj.mtllib ? masked : data;
            MemBuf buf(text.data(), text.size());
            std::istream in(&buf);
            ok = IO::IOManager().read(in, ext, collector, opt);
        } else if (ext == "ply") {
            const std::string stripped = ply_without_notes(data);
            const std::string &text = stripped.empty() ? data : stripped;
            MemBuf buf(text.data(), text.size());
            std::istream in(&buf);
            ok = IO::IOManager().read(in, ext, collector, opt);
        } else {
            ok = IO::IOManager().read(path, collector, opt);
        }
        log = capture.first_line();
        if (capture.truncated())
            log += " [OpenMesh log truncated at " + std::to_string(capture.captured()) + " bytes]";
    }
    if (!soup.error.empty())
        return fail(err, errlen, FP_MESH_ERR_FORMAT, path, soup.error);
    if (!ok)
        return fail(err, errlen, FP_MESH_ERR_FORMAT, path,
                    "OpenMesh cannot read it as ." + ext +
                        (log.empty() ? std::string() : " (" + log + ")"));
    // OpenMesh's OBJ reader removes repeated vertices from a face and drops a face left with
    // fewer than 3; anything else is a disagreement between its parse and ours.
    if (ext == "obj" && (soup.n() != obj.v || soup.faces() != obj.faces - obj.degenerate))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "OpenMesh read %zu vertices and %zu faces; the file has %zu and "
                              "%zu (%zu degenerate)",
                              soup.n(), soup.faces(), obj.v, obj.faces, obj.degenerate);
    // PLY and OFF were checked value by value: OpenMesh must have read what the header says.
    if ((ext == "ply" || ext == "off") && (soup.n() != want_v || soup.faces() != want_f))
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path,
                              "OpenMesh read %zu vertices and %zu faces; the header says %zu "
                              "and %zu", soup.n(), soup.faces(), want_v, want_f);
    auto src = std::make_unique<fp_mesh_source>();
    src->format = ext;
    if (ext == "obj") {
        if (obj.usemtl) {
            obj_materials(data, *src);
        } else { // no material: every face kept has none, without another pass over the text
            src->groups = obj.groups > 0;
            src->face_material.assign(soup.faces(), -1);
        }
        src->obj_text = std::move(data); // the caller's last use: kept, not copied
        if (src->face_material.size() != soup.faces()) { // should not happen: same rule
            src->face_material.clear();
            src->materials.clear();
        }
    }
    return soup_to_mesh(soup, path, out, err, errlen, src.release());
}

int save_openmesh(const fp_mesh *m, const char *path, const std::string &ext, char *err,
                  size_t errlen, const fp_mesh_source *poly = nullptr)
{
    IO::Options opt;
    if (m->normals && ext != "stl")
        opt += IO::Options::VertexNormal;
    if (m->uvs && ext != "stl")
        opt += IO::Options::VertexTexCoord;
    if (ext == "stl" || ext == "ply") {
        opt += IO::Options::Binary;
        opt += IO::Options::LSB;
    }
    std::ostringstream os(std::ios::out | std::ios::binary);
    bool ok;
    std::string log;
    {
        std::lock_guard<std::mutex> guard(openmesh_lock);
        OmLogCapture capture;
        ArrayExporter exporter(*m, ext == "stl" ? nullptr : poly);
        ok = IO::IOManager().write(os, ext, exporter, opt, 9);
        log = capture.first_line();
    }
    if (!ok || !os)
        return fail(err, errlen, FP_MESH_ERR_IO, path,
                    "OpenMesh cannot write ." + ext +
                        (log.empty() ? std::string() : " (" + log + ")"));
    return write_atomically(path, os.str(), err, errlen);
}

// ---- glTF ---------------------------------------------------------------------------

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

    bool add_mesh(int mi, const Mat4 &xf)
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
            if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES)
                continue;
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
            if (idx.size() % 3 != 0)
                return bad(FP_MESH_ERR_FORMAT, where + " has " + std::to_string(idx.size()) +
                                                   " indices, not a multiple of 3");
            for (size_t i = 0; i < idx.size(); i++)
                if (idx[i] >= count)
                    return bad(FP_MESH_ERR_FORMAT, where + ": index " + std::to_string(i) + " = " +
                                                       std::to_string(idx[i]) + " is out of range (" +
                                                       std::to_string(count) + " vertices)");
            const size_t base = soup.n();
            {
                fp_mesh_source::Instance in{mi, int(pi), base, count, {}, pos_it->second,
                                            n_it != prim.attributes.end() ? n_it->second : -1};
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
        if (nd.mesh >= 0 && !add_mesh(nd.mesh, xf))
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
// load fails naming the URI, even where tinygltf would only warn (images).
struct GltfFs {
    std::string base;    // the folder given to tinygltf
    std::string refused; // the first refusal: "URI 'x': reason"
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
    auto refuse = [&](const std::string &why) {
        const std::string msg = "URI '" + rel + "' refused: " + why;
        if (fs.refused.empty())
            fs.refused = msg;
        if (err)
            *err = msg;
        return false;
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
    if (fd < 0)
        return refuse(why);
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
        return fail(err, errlen, FP_MESH_ERR_FORMAT, path, "glTF: " + fs.refused);
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
            if (!r.add_mesh(int(mi), mat_identity()))
                break;
    }
    if (r.code != FP_MESH_OK)
        return fail(err, errlen, r.code, path, "glTF: " + r.error);
    if (r.prims_seen > 0 && r.prims_used == 0)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                              "glTF: no triangle primitives (only points, lines, strips or fans)");
    if (!r.all_normals)
        std::fill(soup.has_nrm.begin(), soup.has_nrm.end(), 0);
    soup.any_vertex_uv = r.any_uv;
    auto src = std::make_unique<fp_mesh_source>();
    src->format = ext;
    src->instances = std::move(r.instances);
    src->model = std::make_unique<tinygltf::Model>(std::move(model));
    return soup_to_mesh(soup, path, out, err, errlen, src.release());
}

// ---- writing back as it came in ----------------------------------------------------

// The source applies while the mesh has the counts it was loaded with.
const fp_mesh_source *source_of(const fp_mesh *m)
{
    const fp_mesh_source *src = m->source;
    if (src && src->n == m->vertex_count && src->t == m->triangle_count)
        return src;
    return nullptr;
}

std::string fmt9(float x)
{
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", double(x));
    return buf;
}

// OBJ back as it came in: the text with v (and vn) lines rewritten.
int save_obj_source(const fp_mesh *m, const fp_mesh_source &src, const char *path, char *err,
                    size_t errlen)
{
    const std::string &text = src.obj_text;
    // vn index -> the first vertex that uses it
    std::vector<long> vn_vertex;
    {
        size_t p = 0, nv = 0, nvt = 0, nvn = 0;
        ObjLine l;
        while (obj_next_line(text, p, l)) {
            if (obj_is(text, l, "v")) nv++;
            else if (obj_is(text, l, "vt")) nvt++;
            else if (obj_is(text, l, "vn")) { nvn++; vn_vertex.push_back(-1); }
            else if (obj_is(text, l, "f"))
                for (size_t k = 1; k < l.tok.size(); k++) {
                    long c[3];
                    obj_corner(text, l.tok[k], nv, nvt, nvn, c);
                    if (c[2] >= 0 && size_t(c[2]) < vn_vertex.size() && vn_vertex[size_t(c[2])] < 0)
                        vn_vertex[size_t(c[2])] = c[0];
                }
        }
    }
    std::string out;
    out.reserve(text.size() + text.size() / 4);
    size_t p = 0, iv = 0, ivn = 0;
    ObjLine l;
    while (obj_next_line(text, p, l)) {
        const bool v = obj_is(text, l, "v"), vn = obj_is(text, l, "vn");
        if ((v && iv < m->vertex_count && l.tok.size() >= 4) ||
            (vn && m->normals && ivn < vn_vertex.size() && vn_vertex[ivn] >= 0 &&
             size_t(vn_vertex[ivn]) < m->vertex_count && l.tok.size() >= 4)) {
            const float *q = v ? m->positions + 3 * iv : m->normals + 3 * size_t(vn_vertex[ivn]);
            out += v ? "v " : "vn ";
            out += fmt9(q[0]) + " " + fmt9(q[1]) + " " + fmt9(q[2]);
            if (l.tok.size() > 4) // w or colours: kept as written
                out.append(text, l.tok[4].first - 1, l.end - (l.tok[4].first - 1));
        } else {
            out.append(text, l.begin, l.end - l.begin);
        }
        if (l.cr)
            out += '\r';
        if (l.end + (l.cr ? 1 : 0) < text.size())
            out += '\n';
        iv += v;
        ivn += vn;
    }
    return write_atomically(path, out, err, errlen);
}

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
    // glTF vertices: mesh vertex i is glTF vertex i; seam copies follow
    std::vector<uint32_t> copy_of;                 // source vertex of glTF vertex n + j
    std::vector<float> uv;                         // glTF vertices x 2
    std::vector<uint32_t> corner_vertex;           // per source corner: glTF vertex
    const bool split = src && src->any_corner_uv;
    const bool flip_v = src != nullptr;            // OBJ/PLY/OFF: v up; glTF: v down
    if (m->uvs)
        uv.assign(m->uvs, m->uvs + 2 * n);
    if (split) {
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
    const size_t N = n + copy_of.size();
    auto src_vertex = [&](size_t j) { return j < n ? j : size_t(copy_of[j - n]); };
    if (flip_v)
        for (size_t j = 0; j < uv.size() / 2; j++)
            uv[2 * j + 1] = 1.0f - uv[2 * j + 1];
    // triangles per material, in split vertices
    const size_t nmat = src ? src->materials.size() : 0;
    std::vector<std::vector<uint32_t>> tris(nmat + 1); // last: no material
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
    // Each primitive gets its own block of vertices (those its triangles use, in first-use
    // order; a vertex on a material border appears in both blocks), so that every reader
    // (ours appends each primitive's vertices) sees each vertex once per primitive.
    std::vector<uint32_t> out_src;              // output vertex -> split vertex
    std::vector<size_t> prim_first, prim_count; // per non-empty material: its block
    std::vector<size_t> prim_mat;
    {
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
    const size_t NO = out_src.size();
    std::vector<float> pos(3 * NO), nrm(3 * NO), tuv(uv.empty() ? 0 : 2 * NO);
    for (size_t j = 0; j < NO; j++) {
        const size_t v = src_vertex(out_src[j]);
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
            tuv[2 * j] = uv[2 * size_t(out_src[j])];
            tuv[2 * j + 1] = uv[2 * size_t(out_src[j]) + 1];
        }
    }
    g.model.asset.version = "2.0";
    g.model.asset.generator = "facepuppet fp_mesh";
    // one buffer view per attribute; one accessor per primitive over its block
    auto sub_accessors = [&](const std::vector<float> &v, int comps, bool minmax) {
        const int view = g.add_view(v.data(), v.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER);
        g.model.bufferViews[size_t(view)].byteStride = size_t(comps) * 4; // shared by accessors
        std::vector<int> acc;
        for (size_t p = 0; p < prim_first.size(); p++) {
            const int type = comps == 2 ? TINYGLTF_TYPE_VEC2 : TINYGLTF_TYPE_VEC3;
            const int a = g.add_accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, type, prim_count[p]);
            g.model.accessors[size_t(a)].byteOffset = prim_first[p] * size_t(comps) * 4;
            if (minmax) {
                std::vector<float> part(v.begin() + long(prim_first[p] * size_t(comps)),
                                        v.begin() + long((prim_first[p] + prim_count[p]) * size_t(comps)));
                minmax3(part, g.model.accessors[size_t(a)]);
            }
            acc.push_back(a);
        }
        return acc;
    };
    const std::vector<int> pa = sub_accessors(pos, 3, true);
    const std::vector<int> na = sub_accessors(nrm, 3, false);
    const std::vector<int> ta = tuv.empty() ? std::vector<int>() : sub_accessors(tuv, 2, false);
    std::vector<std::vector<int>> target_acc; // [target][primitive]
    if (anim) {
        std::vector<float> d(3 * NO);
        for (size_t k = 0; k < anim->target_count; k++) {
            const float *t = anim->targets + k * 3 * n;
            for (size_t j = 0; j < NO; j++)
                for (int c = 0; c < 3; c++)
                    d[3 * j + size_t(c)] = t[3 * src_vertex(out_src[j]) + size_t(c)];
            target_acc.push_back(sub_accessors(d, 3, true));
        }
    }
    tinygltf::Mesh mesh;
    if (m->source_path)
        mesh.name = file_stem(m->source_path);
    for (size_t p = 0; p < prim_first.size(); p++) {
        const size_t mi = prim_mat[p];
        tinygltf::Primitive prim;
        prim.mode = TINYGLTF_MODE_TRIANGLES;
        prim.attributes["POSITION"] = pa[p];
        prim.attributes["NORMAL"] = na[p];
        if (!ta.empty())
            prim.attributes["TEXCOORD_0"] = ta[p];
        prim.indices = g.add_accessor(g.add_view(tris[mi].data(), tris[mi].size() * 4,
                                                 TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                                      TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                                      TINYGLTF_TYPE_SCALAR, tris[mi].size());
        if (mi < nmat) {
            tinygltf::Material mat;
            mat.name = src->materials[mi];
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
    bool identity = NO == n;
    for (size_t j = 0; j < NO && identity; j++)
        identity = src_vertex(out_src[j]) == j;
    if (!identity) { // the mesh vertex of each glTF vertex, primitives' blocks in order
        tinygltf::Value::Array map;
        for (size_t j = 0; j < NO; j++)
            map.push_back(tinygltf::Value(int(src_vertex(out_src[j]))));
        extras["sourceVertex"] = tinygltf::Value(map);
    }
    if (!extras.empty())
        mesh.extras = tinygltf::Value(extras);
    g.model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.mesh = 0;
    node.name = mesh.name;
    g.model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes.push_back(0);
    g.model.scenes.push_back(scene);
    g.model.defaultScene = 0;
    if (anim) {
        std::vector<float> times(anim->times, anim->times + anim->frame_count);
        std::vector<float> w(anim->weights, anim->weights + anim->frame_count * anim->target_count);
        tinygltf::AnimationSampler sm;
        sm.input = g.add_floats(times, 1, 0, true);
        sm.output = g.add_floats(w, 1, 0, false);
        sm.interpolation = anim->step ? "STEP" : "LINEAR";
        tinygltf::Animation an;
        an.name = anim->name ? anim->name : "take";
        an.samplers.push_back(sm);
        tinygltf::AnimationChannel ch;
        ch.sampler = 0;
        ch.target_node = 0;
        ch.target_path = "weights";
        an.channels.push_back(ch);
        g.model.animations.push_back(an);
    }
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
    auto rewrite = [&](int ai, const std::vector<float> &v, bool minmax, int mesh, int prim,
                       const char *attr) {
        if (ai < 0 || size_t(ai) >= done.size() || done[size_t(ai)])
            return;
        done[size_t(ai)] = 1;
        tinygltf::Accessor &a = model.accessors[size_t(ai)];
        const tinygltf::BufferView *bv = a.bufferView >= 0 ? &model.bufferViews[size_t(a.bufferView)] : nullptr;
        const bool in_place = bv && !a.sparse.isSparse && a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT &&
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
    for (const auto &in : src.instances) {
        std::array<double, 16> inv;
        if (!affine_inverse(in.xf, inv))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                                  "glTF: mesh %d has a singular node transform", in.mesh);
        std::vector<float> p(3 * in.count), q;
        for (size_t i = 0; i < in.count; i++) {
            const float *x = m->positions + 3 * (in.first + i);
            for (int r = 0; r < 3; r++)
                p[3 * i + size_t(r)] = float(inv[size_t(r)] * x[0] + inv[size_t(4 + r)] * x[1] +
                                             inv[size_t(8 + r)] * x[2] + inv[size_t(12 + r)]);
        }
        rewrite(in.pos, p, true, in.mesh, in.prim, "POSITION");
        if (in.nrm >= 0 && m->normals) {
            q.resize(3 * in.count);
            for (size_t i = 0; i < in.count; i++) {
                const float *x = m->normals + 3 * (in.first + i);
                double w[3], len = 0;
                for (int r = 0; r < 3; r++) { // local normal ~ M^T n
                    w[r] = in.xf[size_t(r * 4)] * x[0] + in.xf[size_t(r * 4 + 1)] * x[1] +
                           in.xf[size_t(r * 4 + 2)] * x[2];
                    len += w[r] * w[r];
                }
                len = std::sqrt(len);
                for (int r = 0; r < 3; r++)
                    q[3 * i + size_t(r)] = len > 0 ? float(w[r] / len) : 0.0f;
            }
            rewrite(in.nrm, q, false, in.mesh, in.prim, "NORMAL");
        }
    }
    return write_gltf_model(model, path, ext, err, errlen);
}

int save_gltf(const fp_mesh *m, const char *path, const std::string &ext, char *err,
              size_t errlen, unsigned *dropped)
{
    GltfOut g;
    build_gltf(m, nullptr, g, dropped);
    return write_gltf_model(g.model, path, ext, err, errlen);
}

int check_mesh(const fp_mesh *m, const char *path, char *err, size_t errlen)
{
    if (m->vertex_count == 0 || m->triangle_count == 0 || !m->positions || !m->triangles)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                              "mesh has no vertices or no triangles");
    if (m->vertex_count > size_t(INT_MAX) || m->triangle_count > size_t(INT_MAX) / 3)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path, "mesh too large");
    for (size_t i = 0; i < 3 * m->triangle_count; i++)
        if (m->triangles[i] >= m->vertex_count)
            return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                                  "triangle %zu references vertex %u of %zu", i / 3,
                                  m->triangles[i], m->vertex_count);
    for (size_t i = 0; i < 3 * m->vertex_count; i++)
        if (!std::isfinite(m->positions[i]) || (m->normals && !std::isfinite(m->normals[i])))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                                  "vertex %zu has a non-finite position or normal", i / 3);
    if (m->uvs)
        for (size_t i = 0; i < 2 * m->vertex_count; i++)
            if (!std::isfinite(m->uvs[i]))
                return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                                      "vertex %zu has a non-finite UV", i / 2);
    return FP_MESH_OK;
}

bool is_openmesh_ext(const std::string &e) { return e == "obj" || e == "ply" || e == "off" || e == "stl"; }
bool is_gltf_ext(const std::string &e) { return e == "gltf" || e == "glb"; }

} // namespace

extern "C" int fp_mesh_load(const char *path, fp_mesh **out, char *err, size_t errlen)
{
    if (err && errlen)
        err[0] = '\0';
    if (out)
        *out = nullptr;
    if (!path || !out)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path, "NULL path or out");
    try {
        char e[16];
        fp__mesh_extension(path, e, sizeof e);
        const std::string ext = e;
        if (!is_openmesh_ext(ext) && !is_gltf_ext(ext))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                                  "unsupported extension '%s' (obj, ply, off, stl, gltf, glb)",
                                  e);
        std::string data;
        int rc = read_whole_file(path, data, err, errlen);
        if (rc != FP_MESH_OK)
            return rc;
        if (is_gltf_ext(ext))
            return load_gltf(path, ext, data, out, err, errlen);
        return load_openmesh(path, ext, data, out, err, errlen);
    } catch (const std::bad_alloc &) {
        return fp__mesh_error(err, errlen, FP_MESH_ERR_NOMEM, path, "out of memory");
    } catch (const std::exception &x) {
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path, "reader failed: %s",
                              x.what());
    } catch (...) {
        return fp__mesh_error(err, errlen, FP_MESH_ERR_FORMAT, path, "reader failed");
    }
}

// What writing a mesh with this source to `ext` drops, and the writer to use.
int save_dispatch(const fp_mesh *mesh, const char *path, const std::string &ext,
                  unsigned *dropped, char *err, size_t errlen)
{
    const fp_mesh_source *src = source_of(mesh);
    const bool src_gltf = src && (src->format == "gltf" || src->format == "glb");
    if (is_gltf_ext(ext)) {
        if (src_gltf)
            return save_gltf_source(mesh, *src, path, ext, err, errlen);
        return save_gltf(mesh, path, ext, err, errlen, dropped);
    }
    if (ext == "obj" && src && src->format == "obj" && !src->obj_text.empty())
        return save_obj_source(mesh, *src, path, err, errlen);
    if (src) {
        if (src->groups)
            *dropped |= FP_MESH_DROPPED_GROUPS;
        if (!src->materials.empty() || (src_gltf && !src->model->materials.empty()))
            *dropped |= FP_MESH_DROPPED_MATERIALS;
        if (src_gltf)
            *dropped |= FP_MESH_DROPPED_NODES;
        if (ext == "stl") {
            if (src->polygons)
                *dropped |= FP_MESH_DROPPED_POLYGONS;
        } else if (src->seams) {
            *dropped |= FP_MESH_DROPPED_UV_SEAMS;
        }
    }
    if (ext == "stl") {
        if (mesh->uvs)
            *dropped |= FP_MESH_DROPPED_UVS;
        if (src && src->file_normals)
            *dropped |= FP_MESH_DROPPED_NORMALS;
    }
    return save_openmesh(mesh, path, ext, err, errlen, src);
}

extern "C" int fp_mesh_save(const fp_mesh *mesh, const char *path, char *err, size_t errlen)
{
    return fp_mesh_save_ex(mesh, path, nullptr, err, errlen);
}

extern "C" const char *fp_mesh_dropped_text(unsigned dropped, char *buf, size_t n)
{
    static const char *const names[] = {"polygons (written as triangles)", "UV seams",
                                        "texture coordinates", "normals", "groups",
                                        "materials", "glTF nodes"};
    if (!buf || n == 0)
        return buf;
    buf[0] = '\0';
    size_t k = 0;
    for (int i = 0; i < 7; i++)
        if (dropped & (1u << i)) {
            int w = std::snprintf(buf + k, n - k, "%s%s", k ? ", " : "", names[i]);
            if (w < 0 || size_t(w) >= n - k)
                break;
            k += size_t(w);
        }
    return buf;
}

extern "C" int fp_mesh_save_animation(const fp_mesh *mesh, const fp_mesh_morph_animation *anim,
                                      const char *path, unsigned *dropped, char *err,
                                      size_t errlen)
{
    if (err && errlen)
        err[0] = '\0';
    unsigned lost = 0;
    if (dropped)
        *dropped = 0;
    if (!path || !mesh || !anim || anim->target_count == 0 || anim->frame_count == 0 ||
        !anim->targets || !anim->times || !anim->weights)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                              "NULL mesh, path or animation, or no targets or frames");
    try {
        char e[16];
        fp__mesh_extension(path, e, sizeof e);
        if (!is_gltf_ext(e))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                                  "an animation is written as .gltf or .glb, not '%s'", e);
        int rc = check_mesh(mesh, path, err, errlen);
        if (rc != FP_MESH_OK)
            return rc;
        const size_t K = anim->target_count, F = anim->frame_count;
        for (size_t i = 0; i < K * 3 * mesh->vertex_count; i++)
            if (!std::isfinite(anim->targets[i]))
                return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                                      "target %zu is not finite", i / (3 * mesh->vertex_count));
        for (size_t f = 0; f < F; f++) {
            if (!std::isfinite(anim->times[f]) || (f > 0 && !(anim->times[f] > anim->times[f - 1])))
                return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                                      "key %zu: times must be finite and increasing", f);
            for (size_t k = 0; k < K; k++)
                if (!std::isfinite(anim->weights[f * K + k]))
                    return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                                          "key %zu: weight %zu is not finite", f, k);
        }
        GltfOut g;
        build_gltf(mesh, anim, g, &lost);
        rc = write_gltf_model(g.model, path, e, err, errlen);
        if (rc == FP_MESH_OK && dropped)
            *dropped = lost;
        return rc;
    } catch (const std::bad_alloc &) {
        return fp__mesh_error(err, errlen, FP_MESH_ERR_NOMEM, path, "out of memory");
    } catch (const std::exception &x) {
        return fp__mesh_error(err, errlen, FP_MESH_ERR_IO, path, "writer failed: %s", x.what());
    } catch (...) {
        return fp__mesh_error(err, errlen, FP_MESH_ERR_IO, path, "writer failed");
    }
}

extern "C" int fp_mesh_save_ex(const fp_mesh *mesh, const char *path, unsigned *dropped,
                               char *err, size_t errlen)
{
    unsigned lost = 0;
    if (dropped)
        *dropped = 0;
    if (err && errlen)
        err[0] = '\0';
    if (!path || !mesh)
        return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path, "NULL mesh or path");
    try {
        char e[16];
        fp__mesh_extension(path, e, sizeof e);
        const std::string ext = e;
        if (!is_openmesh_ext(ext) && !is_gltf_ext(ext))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                                  "unsupported extension '%s' (obj, ply, off, stl, gltf, glb)",
                                  e);
        int rc = check_mesh(mesh, path, err, errlen);
        if (rc != FP_MESH_OK)
            return rc;
        rc = save_dispatch(mesh, path, ext, &lost, err, errlen);
        if (rc == FP_MESH_OK && dropped)
            *dropped = lost;
        return rc;
    } catch (const std::bad_alloc &) {
        return fp__mesh_error(err, errlen, FP_MESH_ERR_NOMEM, path, "out of memory");
    } catch (const std::exception &x) {
        return fp__mesh_error(err, errlen, FP_MESH_ERR_IO, path, "writer failed: %s", x.what());
    } catch (...) {
        return fp__mesh_error(err, errlen, FP_MESH_ERR_IO, path, "writer failed");
    }
}
