// The OpenMesh bridge: OBJ, PLY, OFF and STL through OpenMesh's readers and writers, driven
// by our own importer (Collector: vertices and polygons as they come, into a Soup) and
// exporter (ArrayExporter: the mesh's arrays) so that OpenMesh's half-edge kernel never sees
// the mesh: no vertex split or merged, no face dropped, the file's vertex order kept. The
// strict scans (mesh_scan_*.c) check every file first; OpenMesh's calls are serialised and
// its log captured (its readers and writers are singletons, its log streams global).
#include "mesh_io_internal.hpp"
#include "fp_text.h"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/exporter/BaseExporter.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/Mesh/BaseKernel.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <iostream>
#include <mutex>
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

// Whether a PLY header (the scan accepted it) names what fp_mesh does not keep: a vertex
// property other than a position, normal or UV, a face property other than its corner list,
// another element (edges, materials); or an OFF header has colours (COFF, [ST][C][N]OFF).
bool holds_other(const std::string &data, const std::string &ext)
{
    static const char *const kept_v[] = {"x", "y", "z", "nx", "ny", "nz", "u", "v", "s", "t",
                                         "texture_u", "texture_v", "texture_s", "texture_t"};
    static const char *const kept_f[] = {"vertex_indices", "vertex_index", "texcoord"};
    std::string element;
    for (size_t p = 0; p < data.size();) {
        size_t eol = data.find('\n', p);
        if (eol == std::string::npos)
            eol = data.size();
        std::istringstream line(data.substr(p, eol - p));
        p = eol + 1;
        std::string w, a, b, name;
        line >> w;
        if (ext == "off") {
            const size_t at = w.find("OFF");
            return at != std::string::npos && w.substr(0, at).find('C') != std::string::npos;
        }
        if (w == "end_header")
            return false;
        if (w == "element") {
            line >> element;
            if (element != "vertex" && element != "face")
                return true;
        } else if (w == "property") {
            line >> a >> b; // TYPE NAME, or list COUNT_TYPE TYPE NAME
            name = b;
            if (a == "list")
                line >> name >> name;
            bool known = false;
            if (element == "vertex")
                for (const char *k : kept_v) known = known || name == k;
            else
                for (const char *k : kept_f) known = known || name == k;
            if (!known)
                return true;
        }
    }
    return false;
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

} // namespace

// data: the file's bytes, taken (an OBJ's text is moved into the mesh's source).
int load_openmesh(const char *path, const std::string &ext, std::string &data,
                  fp_mesh **out, char *err, size_t errlen)
{
    fp__obj_info obj{};
    size_t want_v = 0, want_f = 0; // the header's counts (PLY, OFF)
    int encoding = -1;             // PLY, STL: 0 ASCII, 1 binary little-, 2 big-endian
    if (ext == "obj") {
        // a byte order mark (a Windows editor's) first: not OBJ, and read from `data` below
        data.erase(0, fp_text_bom(data.data(), data.size()));
        // lines continued with '\' joined (in place: the line numbers stay the file's)
        fp__obj_join_continuations(&data[0], data.size());
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
        encoding = binary ? 1 : 0;
        int rc = binary ? fp__stl_binary_scan(path, data.data(), data.size(), err, errlen)
                        : fp__stl_ascii_scan(path, data.c_str(), data.size(), err, errlen);
        if (rc != FP_MESH_OK)
            return rc;
    }
    if (ext == "ply") {
        int rc = fp__ply_scan(path, data.c_str(), data.size(), &want_v, &want_f, &encoding, err,
                              errlen);
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
    src->encoding = encoding;
    src->other = ext == "obj" ? obj.colours > 0 : (ext == "ply" || ext == "off") && holds_other(data, ext);
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
                  size_t errlen, const fp_mesh_source *poly)
{
    IO::Options opt;
    if (m->normals && ext != "stl")
        opt += IO::Options::VertexNormal;
    if (m->uvs && ext != "stl")
        opt += IO::Options::VertexTexCoord;
    // PLY and STL: binary little-endian, or the encoding a PLY or STL source was read in
    // (an ASCII file is saved as ASCII, a big-endian PLY as big-endian; STL has no such)
    const int encoding = poly && poly->encoding >= 0 ? poly->encoding : 1;
    if ((ext == "stl" || ext == "ply") && encoding > 0) {
        opt += IO::Options::Binary;
        opt += encoding == 2 && ext == "ply" ? IO::Options::MSB : IO::Options::LSB;
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

} // namespace fp_mesh_io
