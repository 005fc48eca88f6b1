// Internal to core/mesh: what its C++ files share. The C++ of fp_mesh's file I/O is these
// files and nothing outside core/mesh:
//   mesh_io.cpp          the C API (fp_mesh_load, fp_mesh_save(_ex), fp_mesh_save_animation):
//                        the format by extension, whole files in and out (read_whole_file,
//                        write_atomically), the save's dispatch;
//   mesh_openmesh.cpp    the OpenMesh bridge: OBJ, PLY, OFF and STL through OpenMesh's
//                        readers and writers, over our own importer and exporter;
//   mesh_gltf_read.cpp   glTF 2.0 and GLB in, through tinygltf;
//   mesh_gltf_write.cpp  glTF and GLB out: a fresh document (with morph targets and an
//                        animation when asked) or the loaded one rewritten;
//   mesh_source.cpp      fp_mesh_source (what a file held beyond the arrays), a mesh from
//                        a Soup, and an OBJ written back as it came in.
// Nothing here throws past the C API: every entry point catches.
#ifndef FP_MESH_IO_INTERNAL_HPP
#define FP_MESH_IO_INTERNAL_HPP

#include "mesh_internal.h"

#include <tiny_gltf.h>

#include <sys/types.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

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
    int encoding = -1;                   // PLY, STL as read, kept when saved to PLY or STL:
                                         // 0 ASCII, 1 binary little-endian, 2 big-endian
    bool groups = false;                 // OBJ g / o statements
    bool other = false;                  // PLY properties or elements read past (colours,
                                         // flags, edges), OFF colours: never written
    std::string obj_text;                // OBJ: the file
    // OBJ: its v and vn lines of 4 or more tokens, for the write-back (obj_plan, made at the
    // first save: loading stays as fast; once, whichever thread saves first): the line is
    // obj_text[begin, end), what follows x y z starts at tail (== end: nothing), and it takes
    // the position (v) or normal (vn) of `vertex` (-1: a vn no face uses)
    struct ObjRewrite {
        size_t begin, tail, end;
        long vertex;
        bool vn;
    };
    mutable std::once_flag obj_planned;
    mutable std::vector<ObjRewrite> obj_rewrites;
    // glTF: the document and where each triangle primitive's vertices went
    struct Instance {
        int mesh, prim;
        size_t first, count;             // mesh vertices [first, first + count)
        std::array<double, 16> xf;       // node transform applied at load (column-major)
        int pos, nrm;                    // accessors (nrm -1: none)
        int node;                        // the node that placed it (-1: a mesh in no scene)
    };
    std::unique_ptr<tinygltf::Model> model;
    std::vector<Instance> instances;
};

namespace fp_mesh_io {

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

// ---- mesh_io.cpp: files

// fp__mesh_error with a std::string message.
int fail(char *err, size_t errlen, int code, const char *path, const std::string &msg);
// The project's code for a failed open/read/write (fp_error.h's table).
int errno_code(int e);
// Open a file for reading only if it is a regular file of at most max_bytes; the fd, or -1
// with *code and *why set.
int open_regular(const char *path, size_t max_bytes, off_t *size, int *code, std::string *why);
// Read all of fd (a regular file of about `size` bytes) into data.
bool read_fd(int fd, off_t size, std::string &data, int *code, std::string *why);
// Mesh files larger than this are refused (2 GiB: far above any face mesh).
constexpr size_t max_file_bytes = size_t(1) << 31;
// The whole file at path into data (not empty), or an error.
int read_whole_file(const char *path, std::string &data, char *err, size_t errlen);
// `bytes` to `path`, never half-written (see mesh_io.cpp).
int write_atomically(const char *given, const std::string &bytes, char *err, size_t errlen);

// ---- mesh_source.cpp

// Build the fp_mesh from a Soup: fan triangulation, per-vertex UVs, normals; src (taken,
// may be null) becomes the mesh's source with the Soup's polygons.
int soup_to_mesh(Soup &s, const char *path, fp_mesh **out, char *err, size_t errlen,
                 fp_mesh_source *src = nullptr);
// The source applies while the mesh has the counts it was loaded with (else null).
const fp_mesh_source *source_of(const fp_mesh *m);
// One line of OBJ text split into whitespace tokens (the text passed fp__obj_scan).
struct ObjLine {
    size_t begin, end;                 // the line without its '\n' (and '\r')
    bool cr;                           // the line ended in "\r\n"
    std::vector<std::pair<size_t, size_t>> tok; // token offsets and lengths
};

// The next line of OBJ text from p (false at the end).
bool obj_next_line(const std::string &text, size_t &p, ObjLine &l);
// The line's statement is kw.
bool obj_is(const std::string &text, const ObjLine &l, const char *kw);
// Corner k of an f line: 0-based v, vt, vn indices (-1 where absent), relative resolved.
void obj_corner(const std::string &text, std::pair<size_t, size_t> tok, size_t nv, size_t nvt,
                size_t nvn, long out[3]);
// The write-back's plan of src.obj_text into src.obj_rewrites (save_obj_source makes it at
// the first save, through src.obj_planned): each save then copies the text between the lines
// it rewrites.
void obj_plan(const fp_mesh_source &src);
// OBJ back as it came in: the text with v (and vn) lines rewritten.
int save_obj_source(const fp_mesh *m, const fp_mesh_source &src, const char *path, char *err,
                    size_t errlen);

// ---- mesh_openmesh.cpp

// OBJ, PLY, OFF, STL in (data: the file's bytes, taken: an OBJ's text is moved into the
// mesh's source), after the strict scans.
int load_openmesh(const char *path, const std::string &ext, std::string &data,
                  fp_mesh **out, char *err, size_t errlen);
// OBJ, PLY, OFF, STL out; poly: the source's polygons to write instead of the triangles.
int save_openmesh(const fp_mesh *m, const char *path, const std::string &ext, char *err,
                  size_t errlen, const fp_mesh_source *poly = nullptr);

// ---- mesh_gltf_read.cpp

// glTF or GLB in (data: the file's bytes).
int load_gltf(const char *path, const std::string &ext, const std::string &data,
              fp_mesh **out, char *err, size_t errlen);

// ---- mesh_gltf_write.cpp

// glTF back as it came in: the document with POSITION and NORMAL rewritten.
int save_gltf_source(const fp_mesh *m, const fp_mesh_source &src, const char *path,
                     const std::string &ext, char *err, size_t errlen);
// A fresh glTF document of the mesh (its source's polygons, UV seams, OBJ materials), with
// morph targets and an animation when anim is given; what it could not keep into *dropped.
int save_gltf(const fp_mesh *m, const fp_mesh_morph_animation *anim, const char *path,
              const std::string &ext, char *err, size_t errlen, unsigned *dropped);

} // namespace fp_mesh_io

#endif
