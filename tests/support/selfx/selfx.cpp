/* fp_selfx: exact triangle-triangle self-intersection counts with CGAL (see selfx.h). */
#include "selfx.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <cerrno>
#include <new>
#include <numeric>
#include <utility>
#include <vector>

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Triangle = K::Triangle_3;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, uint32_t>;
using Pair = std::pair<uint32_t, uint32_t>;

/* canon[v] = the smallest vertex index at v's exact position. */
std::vector<uint32_t> weld(const float *pos, size_t n)
{
    std::vector<uint32_t> order(n), canon(n);
    std::iota(order.begin(), order.end(), 0u);
    auto key = [pos](uint32_t a, uint32_t b) {
        for (int k = 0; k < 3; k++)
            if (pos[3 * a + k] != pos[3 * b + k]) return pos[3 * a + k] < pos[3 * b + k];
        return a < b;
    };
    std::sort(order.begin(), order.end(), key);
    for (size_t i = 0; i < n; i++) {
        uint32_t v = order[i];
        if (i > 0) {
            uint32_t u = order[i - 1];
            if (pos[3 * u] == pos[3 * v] && pos[3 * u + 1] == pos[3 * v + 1] &&
                pos[3 * u + 2] == pos[3 * v + 2]) {
                canon[v] = canon[u];
                continue;
            }
        }
        canon[v] = v;
    }
    return canon;
}

/* Sorted crossing pairs of the mesh at positions pos, adjacency from canon. */
std::vector<Pair> crossings(const float *pos, const uint32_t *tris, size_t nt,
                            const std::vector<uint32_t> &canon)
{
    std::vector<Triangle> tri;
    std::vector<Box> boxes;
    std::vector<uint32_t> id;
    tri.reserve(nt);
    boxes.reserve(nt);
    for (size_t t = 0; t < nt; t++) {
        Point p[3];
        for (int k = 0; k < 3; k++) {
            const float *v = pos + 3 * (size_t)tris[3 * t + k];
            p[k] = Point(v[0], v[1], v[2]);
        }
        Triangle T(p[0], p[1], p[2]);
        tri.push_back(T);
        if (T.is_degenerate()) continue;
        boxes.emplace_back(T.bbox(), (uint32_t)t);
    }
    std::vector<Pair> out;
    auto cb = [&](const Box &a, const Box &b) {
        uint32_t i = a.info(), j = b.info();
        for (int x = 0; x < 3; x++)
            for (int y = 0; y < 3; y++)
                if (canon[tris[3 * (size_t)i + x]] == canon[tris[3 * (size_t)j + y]]) return;
        if (CGAL::do_intersect(tri[i], tri[j])) out.emplace_back(std::min(i, j), std::max(i, j));
    };
    CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), cb);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

bool valid(const float *pos, size_t nv, const uint32_t *tris, size_t nt)
{
    if (!pos || (!tris && nt) || nv >= UINT32_MAX || nt >= UINT32_MAX) return false;
    for (size_t i = 0; i < 3 * nt; i++)
        if (tris[i] >= nv) return false;
    return true;
}

} // namespace

extern "C" long fp_selfx_count(const float *pos, size_t nv, const uint32_t *tris, size_t nt)
{
    if (!valid(pos, nv, tris, nt)) return -EINVAL;
    try {
        return (long)crossings(pos, tris, nt, weld(pos, nv)).size();
    } catch (const std::bad_alloc &) {
        return -ENOMEM;
    }
}

extern "C" long fp_selfx_count_new(const float *before, const float *after, size_t nv,
                                   const uint32_t *tris, size_t nt, uint32_t *pairs,
                                   size_t max_pairs, long *own_before)
{
    if (!valid(before, nv, tris, nt) || !after) return -EINVAL;
    try {
        std::vector<uint32_t> canon = weld(before, nv);
        std::vector<Pair> b = crossings(before, tris, nt, canon);
        std::vector<Pair> a = crossings(after, tris, nt, canon);
        std::vector<Pair> fresh;
        std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(fresh));
        if (own_before) *own_before = (long)b.size();
        if (pairs)
            for (size_t k = 0; k < fresh.size() && k < max_pairs; k++) {
                pairs[2 * k] = fresh[k].first;
                pairs[2 * k + 1] = fresh[k].second;
            }
        return (long)fresh.size();
    } catch (const std::bad_alloc &) {
        return -ENOMEM;
    }
}

extern "C" long fp_selfx_count_new_away(const float *before, const float *after, size_t nv,
                                        const uint32_t *tris, size_t nt, int rings,
                                        uint32_t *pairs, size_t max_pairs, long *own_before,
                                        long *near_own)
{
    if (!valid(before, nv, tris, nt) || !after || rings < 0) return -EINVAL;
    try {
        std::vector<uint32_t> canon = weld(before, nv);
        std::vector<Pair> b = crossings(before, tris, nt, canon);
        std::vector<Pair> a = crossings(after, tris, nt, canon);
        std::vector<Pair> fresh;
        std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(fresh));
        if (own_before) *own_before = (long)b.size();
        /* the welded vertices of the input's own crossing triangles, grown by `rings` rings */
        std::vector<char> mark(nv, 0);
        for (const Pair &p : b)
            for (uint32_t t : {p.first, p.second})
                for (int k = 0; k < 3; k++) mark[canon[tris[3 * (size_t)t + k]]] = 1;
        for (int r = 0; r < rings; r++) {
            std::vector<char> next = mark;
            for (size_t t = 0; t < nt; t++) {
                const uint32_t *v = tris + 3 * t;
                if (mark[canon[v[0]]] || mark[canon[v[1]]] || mark[canon[v[2]]])
                    for (int k = 0; k < 3; k++) next[canon[v[k]]] = 1;
            }
            mark.swap(next);
        }
        auto near = [&](uint32_t t) {
            const uint32_t *v = tris + 3 * (size_t)t;
            return mark[canon[v[0]]] || mark[canon[v[1]]] || mark[canon[v[2]]];
        };
        long nnear = 0;
        std::vector<Pair> away;
        for (const Pair &p : fresh) {
            if (near(p.first) || near(p.second)) nnear++;
            else away.push_back(p);
        }
        if (near_own) *near_own = nnear;
        if (pairs)
            for (size_t k = 0; k < away.size() && k < max_pairs; k++) {
                pairs[2 * k] = away[k].first;
                pairs[2 * k + 1] = away[k].second;
            }
        return (long)away.size();
    } catch (const std::bad_alloc &) {
        return -ENOMEM;
    }
}
