// Re-fitted vertices for one level (refit.h): the quadric of the full mesh's triangles that each
// live point stands for, minimised near the point's own position; then the attributes of the
// source where each moved vertex now stands.

#include "tom/builder/refit.h"

#include "geometry.h"
#include "substitution.h"
#include "tom/extract.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

namespace tom {
namespace {

using build_detail::add;
using build_detail::add_plane;
using build_detail::Quadric;
using detail::V3;
using detail::cross;
using detail::dot;
using detail::length;
using detail::sub;

constexpr uint32_t kNone = ~0u;

// Points: vertices at the same position (equal floats) and the groups of copies the builder
// removes together are one point each; `point[v]` numbers them in the order of their first
// vertex.
struct Points {
    std::vector<uint32_t> point;  // per vertex
    uint32_t count = 0;
};

Points weld_by_position(const MeshView& m) {
    const uint32_t V = m.vertex_count;
    std::vector<uint32_t> order(V);
    for (uint32_t v = 0; v < V; ++v) order[v] = v;
    auto key = [&](uint32_t v) {
        std::array<uint32_t, 3> k;
        for (int a = 0; a < 3; ++a) {
            const float x = m.positions[3 * size_t(v) + a] + 0.0f;  // -0 as 0
            std::memcpy(&k[size_t(a)], &x, 4);
        }
        return k;
    };
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
    Points p;
    p.point.assign(V, kNone);
    std::vector<uint32_t> first(V, kNone);  // per run of equal positions: its lowest vertex
    for (size_t i = 0; i < V;) {
        size_t j = i;
        uint32_t lowest = order[i];
        while (j < V && key(order[j]) == key(order[i])) lowest = std::min(lowest, order[j++]);
        for (size_t k = i; k < j; ++k) first[order[k]] = lowest;
        i = j;
    }
    // a group of copies the builder removes together (near-coincident ones too) is one point
    auto root = [&](uint32_t v) {
        while (first[v] != v) v = first[v] = first[first[v]];
        return v;
    };
    for (uint32_t v = 0; v + 1 < V; ++v)
        if (m.splits_pair(v + 1)) {
            const uint32_t a = root(v), b = root(v + 1);
            if (a != b) first[std::max(a, b)] = std::min(a, b);
        }
    std::vector<uint32_t> number(V, kNone);
    for (uint32_t v = 0; v < V; ++v) {
        const uint32_t r = root(v);
        if (number[r] == kNone) number[r] = p.count++;
        p.point[v] = number[r];
    }
    return p;
}

// The triangles of `m` at resolution `n`.
std::vector<uint32_t> level_triangles(const MeshView& m, uint32_t n) {
    std::vector<uint32_t> idx(size_t(active_triangle_count(m, n)) * 3);
    extract(m, n, idx.data(), idx.size());
    return idx;
}

// Points on an edge that is not shared by exactly two triangles of the full mesh (welded by
// position): open edges and the chains where parts meet.
std::vector<uint8_t> fixed_points(const std::vector<uint32_t>& full, const Points& p) {
    std::vector<uint64_t> edges;
    edges.reserve(full.size());
    for (size_t t = 0; t + 2 < full.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            const uint64_t a = p.point[full[t + k]], b = p.point[full[t + (k + 1) % 3]];
            if (a != b) edges.push_back(a < b ? a << 32 | b : b << 32 | a);
        }
    std::sort(edges.begin(), edges.end());
    std::vector<uint8_t> fixed(p.count, 0);
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i != 2) fixed[edges[i] >> 32] = fixed[edges[i] & 0xffffffffu] = 1;
        i = j;
    }
    return fixed;
}

// The vertex < n each vertex stands in for at resolution n (>= min_vertex_count): itself when
// live, else the end of its substitution chain (substitute[v] < v past the survivors, so in
// order of v the substitute's is known).
std::vector<uint32_t> representatives(const MeshView& m, uint32_t n) {
    std::vector<uint32_t> rep(m.vertex_count);
    for (uint32_t v = 0; v < m.vertex_count; ++v) rep[v] = v < n ? v : rep[m.substitute_at(v)];
    return rep;
}

// Per point: the planes of the full mesh's triangles around every vertex it stands for, each
// weighted as the builder weighs it (the square root of the triangle's area).
std::vector<Quadric> point_quadrics(const MeshView& m, const std::vector<uint32_t>& full, const Points& p, const std::vector<uint32_t>& rep) {
    std::vector<Quadric> q(p.count, Quadric{});
    const float* x = m.positions;
    for (size_t t = 0; t + 2 < full.size(); t += 3) {
        const uint32_t c[3] = {full[t], full[t + 1], full[t + 2]};
        const V3 p0{x[3 * c[0]], x[3 * c[0] + 1], x[3 * c[0] + 2]};
        const V3 p1{x[3 * c[1]], x[3 * c[1] + 1], x[3 * c[1] + 2]};
        const V3 p2{x[3 * c[2]], x[3 * c[2] + 1], x[3 * c[2] + 2]};
        const V3 nrm = cross(sub(p1, p0), sub(p2, p0));
        const double len = length(nrm);
        if (!(len > 0)) continue;
        const double nx = nrm.x / len, ny = nrm.y / len, nz = nrm.z / len;
        Quadric plane{};
        add_plane(plane, nx, ny, nz, -(nx * p0.x + ny * p0.y + nz * p0.z), detail::quadric_weight(0.5 * len));
        for (const uint32_t v : c) add(q[p.point[rep[v]]], plane);
    }
    return q;
}

// argmin Q(x) + lambda |x - x0|^2, lambda a thousandth of the quadric's trace: directions the
// quadric leaves free (along a flat region, along a crease) keep x0. False when singular.
bool solve_near(const Quadric& q, const double x0[3], double out[3]) {
    const double lambda = 1e-3 * (q.a00 + q.a11 + q.a22);
    if (!(lambda > 0)) return false;
    const double a[3][3] = {{q.a00 + lambda, q.a01, q.a02}, {q.a01, q.a11 + lambda, q.a12}, {q.a02, q.a12, q.a22 + lambda}};
    const double r[3] = {lambda * x0[0] - q.b0, lambda * x0[1] - q.b1, lambda * x0[2] - q.b2};
    const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                       a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if (!(std::abs(det) > 0)) return false;
    for (int k = 0; k < 3; ++k) {
        double c[3][3];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) c[i][j] = j == k ? r[i] : a[i][j];
        out[k] = (c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[2][1]) - c[0][1] * (c[1][0] * c[2][2] - c[1][2] * c[2][0]) +
                  c[0][2] * (c[1][0] * c[2][1] - c[1][1] * c[2][0])) /
                 det;
    }
    return std::isfinite(out[0]) && std::isfinite(out[1]) && std::isfinite(out[2]);
}

V3 at(const std::vector<float>& x, uint32_t v) { return {x[3 * size_t(v)], x[3 * size_t(v) + 1], x[3 * size_t(v) + 2]}; }

// Whether a triangle turned by more than acos(0.2) (78 degrees) or collapsed.
bool turned(const std::vector<float>& before, const std::vector<float>& after, const uint32_t* t) {
    const V3 n0 = cross(sub(at(before, t[1]), at(before, t[0])), sub(at(before, t[2]), at(before, t[0])));
    const V3 n1 = cross(sub(at(after, t[1]), at(after, t[0])), sub(at(after, t[2]), at(after, t[0])));
    const double l0 = length(n0), l1 = length(n1);
    return l0 > 0 && !(dot(n0, n1) > 0.2 * l0 * l1);
}

// Each live point at its quadric's minimum near where it is (its copies with it), unless fixed.
std::vector<uint8_t> move_points(const MeshView& m, uint32_t n, const Points& p, const std::vector<uint8_t>& fixed, const std::vector<Quadric>& q,
                                 std::vector<float>& out, RefitStats& s) {
    std::vector<uint8_t> moved(p.count, 0), seen(p.count, 0);
    std::vector<double> target(3 * size_t(p.count), 0.0);
    for (uint32_t v = 0; v < n; ++v) {
        const uint32_t k = p.point[v];
        if (!seen[k]) {  // the point's first live vertex
            seen[k] = 1;
            const double x0[3] = {m.positions[3 * size_t(v)], m.positions[3 * size_t(v) + 1], m.positions[3 * size_t(v) + 2]};
            if (fixed[k]) ++s.fixed;
            else if (solve_near(q[k], x0, &target[3 * size_t(k)])) moved[k] = 1, ++s.moved;
        }
        if (moved[k])
            for (int a = 0; a < 3; ++a) out[3 * size_t(v) + a] = float(target[3 * size_t(k) + a]);
    }
    return moved;
}

// Puts back the points of triangles that turned over, until none does (each round puts back at
// least one point, and a level with every point back is the level itself).
void put_back_turned(const std::vector<uint32_t>& level, uint32_t n, const Points& p, const std::vector<float>& before, std::vector<uint8_t>& moved,
                     std::vector<float>& out, RefitStats& s) {
    for (bool again = true; again;) {
        again = false;
        for (size_t t = 0; t + 2 < level.size(); t += 3) {
            if (!turned(before, out, &level[t])) continue;
            for (int c = 0; c < 3; ++c) {
                const uint32_t k = p.point[level[t + c]];
                if (moved[k]) moved[k] = 0, --s.moved, ++s.reverted, again = true;
            }
        }
        if (again)
            for (uint32_t v = 0; v < n; ++v)
                if (!moved[p.point[v]]) std::copy(before.begin() + 3 * ptrdiff_t(v), before.begin() + 3 * ptrdiff_t(v) + 3, out.begin() + 3 * ptrdiff_t(v));
    }
}

// Per live vertex, the full mesh's triangles around the vertices it stands for (CSR).
struct Around {
    std::vector<uint32_t> start, triangles;
};

Around triangles_around(uint32_t n, const std::vector<uint32_t>& full, const std::vector<uint32_t>& rep) {
    Around a;
    a.start.assign(size_t(n) + 1, 0);
    for (const uint32_t v : full) ++a.start[rep[v] + 1];
    for (uint32_t v = 0; v < n; ++v) a.start[v + 1] += a.start[v];
    a.triangles.resize(full.size());
    std::vector<uint32_t> next(a.start.begin(), a.start.end() - 1);
    for (size_t c = 0; c < full.size(); ++c) a.triangles[next[rep[full[c]]]++] = uint32_t(c / 3);
    return a;
}

// `width` values per vertex of `src` at barycentric `w` of the corners `c`, into `dst`.
void interpolate(const float* src, size_t width, const uint32_t* c, const double w[3], float* dst) {
    for (size_t a = 0; a < width; ++a)
        dst[a] = float(w[0] * src[width * c[0] + a] + w[1] * src[width * c[1] + a] + w[2] * src[width * c[2] + a]);
}

void normalize(float* x, size_t count) {
    double l = 0;
    for (size_t a = 0; a < count; ++a) l += double(x[a]) * x[a];
    l = std::sqrt(l);
    if (l > 0)
        for (size_t a = 0; a < count; ++a) x[a] = float(x[a] / l);
}

// Each moved vertex's attributes resampled from the source where it now stands: at the point
// closest to its new position among the triangles around the vertices it stands for (its own
// side of a seam or a hard edge: copies stand for their own sides), interpolated there; normals
// made unit, tangents made unit and orthogonal to the normal, their handedness kept.
void resample_attributes(const MeshView& m, uint32_t n, const std::vector<uint32_t>& full, const std::vector<float>& before,
                         const std::vector<uint32_t>& rep, const Points& p, const std::vector<uint8_t>& moved, RefitLevel& r) {
    const Around around = triangles_around(n, full, rep);
    for (uint32_t v = 0; v < n; ++v) {
        if (!moved[p.point[v]]) continue;
        const V3 x = at(r.positions, v);
        double best = std::numeric_limits<double>::infinity();
        const uint32_t* c = nullptr;
        detail::Flat nearest{};
        for (uint32_t i = around.start[v]; i < around.start[v + 1]; ++i) {
            const uint32_t* t = &full[3 * size_t(around.triangles[i])];
            const detail::Flat f = detail::make_flat(at(before, t[0]), at(before, t[1]), at(before, t[2]));
            const double d = detail::distance2(f, x);
            if (d < best) best = d, c = t, nearest = f;
        }
        if (!c) continue;
        double at_best[3];
        detail::nearest_point(nearest, x, at_best);
        if (m.normals) interpolate(m.normals, 3, c, at_best, &r.normals[3 * size_t(v)]), normalize(&r.normals[3 * size_t(v)], 3);
        if (m.texcoords) interpolate(m.texcoords, 2, c, at_best, &r.texcoords[2 * size_t(v)]);
        if (m.texcoords1) interpolate(m.texcoords1, 2, c, at_best, &r.texcoords1[2 * size_t(v)]);
        if (m.colors) interpolate(m.colors, 4, c, at_best, &r.colors[4 * size_t(v)]);
        if (m.tangents && m.normals) {
            float* t = &r.tangents[4 * size_t(v)];
            const float handedness = t[3];
            interpolate(m.tangents, 4, c, at_best, t);
            const float* nv = &r.normals[3 * size_t(v)];
            const float along = t[0] * nv[0] + t[1] * nv[1] + t[2] * nv[2];
            for (int a = 0; a < 3; ++a) t[a] -= along * nv[a];
            normalize(t, 3);
            t[3] = handedness;
        }
    }
}

// A stream of `width` floats per vertex copied, or empty when the mesh has none.
std::vector<float> copy_stream(const float* values, uint32_t count, size_t width) {
    return values ? std::vector<float>(values, values + width * count) : std::vector<float>();
}

} // namespace

RefitLevel refit_level(const MeshView& m, uint32_t n) {
    RefitLevel r;
    r.resolution = n = m.whole_groups_below(std::min(std::max(n, m.min_vertex_count), m.vertex_count));  // as extract() takes it
    const std::vector<float> before(m.positions, m.positions + 3 * size_t(m.vertex_count));
    r.positions = before;
    const Points p = weld_by_position(m);
    const std::vector<uint32_t> full = level_triangles(m, m.vertex_count), level = level_triangles(m, n);
    const std::vector<uint32_t> rep = representatives(m, n);
    std::vector<uint8_t> moved = move_points(m, n, p, fixed_points(full, p), point_quadrics(m, full, p, rep), r.positions, r.stats);
    put_back_turned(level, n, p, before, moved, r.positions, r.stats);
    r.normals = copy_stream(m.normals, m.vertex_count, 3);
    r.texcoords = copy_stream(m.texcoords, m.vertex_count, 2);
    r.texcoords1 = copy_stream(m.texcoords1, m.vertex_count, 2);
    r.colors = copy_stream(m.colors, m.vertex_count, 4);
    r.tangents = copy_stream(m.tangents, m.vertex_count, 4);
    resample_attributes(m, n, full, before, rep, p, moved, r);
    return r;
}

MeshView refit_view(const MeshView& m, const RefitLevel& r) {
    MeshView v = m;
    auto own = [](const std::vector<float>& values, const float* kept) { return values.empty() ? kept : values.data(); };
    v.positions = own(r.positions, m.positions);
    v.normals = own(r.normals, m.normals);
    v.texcoords = own(r.texcoords, m.texcoords);
    v.texcoords1 = own(r.texcoords1, m.texcoords1);
    v.colors = own(r.colors, m.colors);
    v.tangents = own(r.tangents, m.tangents);
    return v;
}

} // namespace tom
