// fp_mesh file I/O, the C API: the format by extension, whole files in and out, and the
// save's dispatch to the writers (mesh_io_internal.hpp lists the files). OBJ, PLY, OFF and
// STL go through OpenMesh's readers and writers, driven by our own importer/exporter over
// flat arrays (so OpenMesh's half-edge kernel never sees the mesh: no vertex is split or
// merged, no face dropped, and vertex order stays the file's). glTF 2.0 goes through tinygltf
// (Debian's shared build). Nothing here throws past the C API: every entry point catches.
#include "mesh_io_internal.hpp"
#include "fp_file.h"

#include <fcntl.h>
#include <limits.h>
#include <stdlib.h>
#include <sys/stat.h>
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

} // namespace fp_mesh_io

using namespace fp_mesh_io;

namespace {

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

// What writing a mesh with this source to `ext` drops, and the writer to use.
int save_dispatch(const fp_mesh *mesh, const char *path, const std::string &ext,
                  unsigned *dropped, char *err, size_t errlen)
{
    const fp_mesh_source *src = source_of(mesh);
    const bool src_gltf = src && (src->format == "gltf" || src->format == "glb");
    // (whatever the format: no writer keeps them, but an OBJ written back as it came in)
    if (src && src->other && !(ext == "obj" && src->format == "obj" && !src->obj_text.empty()))
        *dropped |= FP_MESH_DROPPED_PROPERTIES;
    if (is_gltf_ext(ext)) {
        if (src_gltf)
            return save_gltf_source(mesh, *src, path, ext, err, errlen);
        return save_gltf(mesh, nullptr, path, ext, err, errlen, dropped);
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
        if (!is_openmesh_ext(ext) && !is_gltf_ext(ext)) {
            // what is not there (or is a folder) is said as such, whatever its name
            const int fd = fp_file_open_regular(path);
            if (fd < 0)
                return fp__mesh_error(err, errlen, fd == -EISDIR || fd == -ENXIO ? FP_MESH_ERR_NOENT : errno_code(-fd),
                                      path, "%s", fp_file_error_text(fd));
            ::close(fd);
            return fp__mesh_error(err, errlen, FP_MESH_ERR_UNSUPPORTED, path,
                                  "unsupported extension '%s' (obj, ply, off, stl, gltf, glb)",
                                  e);
        }
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

extern "C" int fp_mesh_save(const fp_mesh *mesh, const char *path, char *err, size_t errlen)
{
    return fp_mesh_save_ex(mesh, path, nullptr, err, errlen);
}

extern "C" const char *fp_mesh_dropped_text(unsigned dropped, char *buf, size_t n)
{
    static const char *const names[] = {"polygons (written as triangles)", "UV seams",
                                        "texture coordinates", "normals", "groups",
                                        "materials", "glTF nodes",
                                        "other vertex and face properties (colours, flags and the like)"};
    if (!buf || n == 0)
        return buf;
    buf[0] = '\0';
    size_t k = 0;
    for (int i = 0; i < 8; i++)
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
        if (!(anim->unit_scale >= 0 && std::isfinite(anim->unit_scale)) ||
            !(anim->frame_rate >= 0 && std::isfinite(anim->frame_rate)))
            return fp__mesh_error(err, errlen, FP_MESH_ERR_INVALID, path,
                                  "unit scale and frame rate must be finite and >= 0");
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
        rc = save_gltf(mesh, anim, path, e, err, errlen, &lost);
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
