// fp_mesh_source: what a file held beyond fp_mesh's arrays (its polygons, per-corner UVs,
// OBJ materials and text, the glTF document), shared by reference count between copies; a
// mesh and its source from what a reader delivered (a Soup); and an OBJ written back as it
// came in (its text, v and vn lines rewritten).
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
#include <functional>
#include <map>
#include <memory>
#include <new>
#include <sstream>
#include <string>
#include <vector>

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

namespace fp_mesh_io {

namespace {

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

} // namespace

int soup_to_mesh(Soup &s, const char *path, fp_mesh **out, char *err, size_t errlen,
                 fp_mesh_source *src)
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

// The source applies while the mesh has the counts it was loaded with.
const fp_mesh_source *source_of(const fp_mesh *m)
{
    const fp_mesh_source *src = m->source;
    if (src && src->n == m->vertex_count && src->t == m->triangle_count)
        return src;
    return nullptr;
}

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

void obj_plan(const fp_mesh_source &src)
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
    src.obj_rewrites.clear();
    size_t p = 0, iv = 0, ivn = 0;
    ObjLine l;
    while (obj_next_line(text, p, l)) {
        const bool v = obj_is(text, l, "v"), vn = obj_is(text, l, "vn");
        if ((v || vn) && l.tok.size() >= 4) // (a tail: w or colours, kept as written)
            src.obj_rewrites.push_back({l.begin, l.tok.size() > 4 ? l.tok[4].first - 1 : l.end, l.end,
                                        v ? long(iv) : vn_vertex[ivn], vn});
        iv += v;
        ivn += vn;
    }
}

// OBJ back as it came in: the text with v (and vn) lines rewritten (obj_plan's lines, those
// whose vertex the mesh has; a vn line only when the mesh has normals), the rest copied.
int save_obj_source(const fp_mesh *m, const fp_mesh_source &src, const char *path, char *err,
                    size_t errlen)
{
    std::call_once(src.obj_planned, obj_plan, std::cref(src));
    const std::string &text = src.obj_text;
    std::string out;
    out.reserve(text.size() + text.size() / 4);
    size_t copied = 0; // text[0, copied) is in out
    for (const fp_mesh_source::ObjRewrite &r : src.obj_rewrites) {
        if (r.vertex < 0 || size_t(r.vertex) >= m->vertex_count || (r.vn && !m->normals))
            continue; // copied as it is
        const float *q = (r.vn ? m->normals : m->positions) + 3 * size_t(r.vertex);
        char buf[96];
        std::snprintf(buf, sizeof buf, "%s %.9g %.9g %.9g", r.vn ? "vn" : "v", double(q[0]),
                      double(q[1]), double(q[2]));
        out.append(text, copied, r.begin - copied);
        out += buf;
        out.append(text, r.tail, r.end - r.tail);
        copied = r.end;
    }
    out.append(text, copied, std::string::npos);
    return write_atomically(path, out, err, errlen);
}

} // namespace fp_mesh_io

// The size of an OBJ save (fp_mesh.h): the source's text with its v and vn lines rewritten,
// or OpenMesh's writer's lines (save_openmesh: v, vn, vt, f with normal and UV indices).
extern "C" double fp_mesh_obj_bytes(const fp_mesh *m)
{
    if (!m)
        return 0;
    const double line = 38; // "v " and three "%.9g" of a face's sizes ("-11.2345678"), "\n"
    const fp_mesh_source *src = m->source;
    try {
        if (src && src->format == "obj" && !src->obj_text.empty()) {
            const std::string &text = src->obj_text;
            double bytes = double(text.size());
            size_t p = 0;
            fp_mesh_io::ObjLine l;
            while (fp_mesh_io::obj_next_line(text, p, l))
                if (l.tok.size() >= 4 && (fp_mesh_io::obj_is(text, l, "v") || fp_mesh_io::obj_is(text, l, "vn")))
                    bytes += line + (l.tok[0].second - 1) - double(l.tok[3].first + l.tok[3].second - l.begin);
            return bytes;
        }
    } catch (...) {
        // (out of memory for a line's tokens: the estimate below)
    }
    const double n = double(m->vertex_count), digits = n >= 1 ? std::floor(std::log10(n)) + 1 : 1;
    const bool poly = src && src->polygons && src->face_start.size() > 1;
    const double faces = poly ? double(src->face_start.size() - 1) : double(m->triangle_count);
    const double corners = poly ? double(src->corners.size()) : 3.0 * double(m->triangle_count);
    const double corner = 1 + digits + (m->uvs ? 1 + digits : 0) + (m->normals ? (m->uvs ? 1 : 2) + digits : 0);
    return 64 + n * (line + (m->normals ? line + 1 : 0) + (m->uvs ? 28 : 0)) + faces * 2 + corners * corner;
}
