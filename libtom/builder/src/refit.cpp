// Re-fitted vertices for one level (refit.h): the quadric of the full mesh's triangles that each
// live point stands for, minimised near the point's own position, the points fitted to the
// source's surface and each kept where it helps most; then the attributes of the source where
// each moved vertex now stands, and every live vertex's attributes fitted to the source's.

#include "tom/builder/refit.h"

#include "geometry.h"
#include "parallel.h"
#include "points.h"
#include "substitution.h"
#include "tom/extract.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace tom {
namespace {

using build_detail::add;
using build_detail::add_plane;
using build_detail::Quadric;
using detail::cross;
using detail::dot;
using detail::length;
using detail::sub;
using detail::V3;

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
    const detail::PositionPoints at = detail::points_by_position(m.positions, V);
    Points p;
    p.point.assign(V, kNone);
    std::vector<uint32_t> lowest(at.count, kNone), first(V);  // first: per vertex, the lowest at its position
    for (uint32_t v = 0; v < V; ++v) {
        if (lowest[at.point[v]] == kNone) lowest[at.point[v]] = v;
        first[v] = lowest[at.point[v]];
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

// The points renumbered along a Morton curve through the mesh's box (by the position of each
// point's first vertex): what the fit reads per point (its triangles, its samples, its place)
// then lies together in memory for neighbouring points, where the file's order is that of
// resolution, spread over the whole surface.
void number_in_space(const MeshView& m, Points& p) {
    std::vector<uint32_t> first(p.count, kNone);
    for (uint32_t v = m.vertex_count; v-- > 0;) first[p.point[v]] = v;
    auto spread = [](uint64_t x) {  // 21 bits to every third of 63
        x &= 0x1fffff;
        x = (x | x << 32) & 0x1f00000000ffffull;
        x = (x | x << 16) & 0x1f0000ff0000ffull;
        x = (x | x << 8) & 0x100f00f00f00f00full;
        x = (x | x << 4) & 0x10c30c30c30c30c3ull;
        return (x | x << 2) & 0x1249249249249249ull;
    };
    std::vector<std::pair<uint64_t, uint32_t>> order(p.count);
    for (uint32_t k = 0; k < p.count; ++k) {
        uint64_t code = 0;
        for (int a = 0; a < 3; ++a) {
            const double lo = m.bounds_min[a], extent = double(m.bounds_max[a]) - lo;
            const double t = extent > 0 ? (double(m.positions[3 * size_t(first[k]) + size_t(a)]) - lo) / extent : 0.0;
            code |= spread(uint64_t(t > 0 ? std::min(t, 1.0) * 2097151.0 : 0.0)) << a;  // (NaN: 0)
        }
        order[k] = {code, k};
    }
    std::sort(order.begin(), order.end());
    std::vector<uint32_t> number(p.count);
    for (uint32_t i = 0; i < p.count; ++i) number[order[i].second] = i;
    for (uint32_t& k : p.point) k = number[k];
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

// `triangles` in the order of their lowest corner's point, `point_of` a corner's (points are
// numbered in space).
template <class PointOf>
std::vector<uint32_t> in_point_order(const std::vector<uint32_t>& triangles, PointOf point_of) {
    std::vector<std::pair<uint32_t, uint32_t>> order;
    for (size_t t = 0; t + 2 < triangles.size(); t += 3)
        order.emplace_back(std::min({point_of(triangles[t]), point_of(triangles[t + 1]), point_of(triangles[t + 2])}), uint32_t(t));
    std::sort(order.begin(), order.end());
    std::vector<uint32_t> out;
    out.reserve(triangles.size());
    for (const auto& [key, t] : order) out.insert(out.end(), triangles.begin() + t, triangles.begin() + t + 3);
    return out;
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
            if (fixed[k])
                ++s.fixed;
            else if (solve_near(q[k], x0, &target[3 * size_t(k)]))
                moved[k] = 1, ++s.moved;
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

// Per live vertex or point: a list of triangles (CSR).
struct Around {
    std::vector<uint32_t> start, triangles;
};

// Samples of the full mesh for the fit and its checks: every triangle's centroid, every edge's
// midpoint and every vertex, each weighing a seventh of the area of the triangles it belongs to
// (seven samples a triangle, shared; Metro's mean, which the benchmark reads, samples the edges
// and vertices first). With each, the points the corners of the full triangles it belongs to
// stand for at the level: it may lie nearest their triangles, and its distance is theirs to
// answer for, each point by the weight of those of the sample's triangles it is a corner of.
struct Samples {
    std::vector<V3> x;
    std::vector<double> weight;
    std::vector<uint32_t> start{0}, near;  // CSR: per sample, its points
    std::vector<float> share;              // per entry of `near`: the weight of the sample's triangles around that point
};

// The seven sample points of triangle abc, Samples' own (for the level's triangles).
std::array<V3, 7> seven_points(V3 a, V3 b, V3 c) { return {(1.0 / 3.0) * (a + b + c), 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a), a, b, c}; }

// `s` with its samples in the order of their lowest point (points are numbered in space).
Samples in_point_order(const Samples& s) {
    std::vector<std::pair<uint32_t, uint32_t>> order;
    for (uint32_t i = 0; i + 1 < s.start.size(); ++i) order.emplace_back(s.start[i] < s.start[i + 1] ? s.near[s.start[i]] : kNone, i);
    std::sort(order.begin(), order.end());
    Samples out;
    for (const auto& [key, i] : order) {
        out.x.push_back(s.x[i]), out.weight.push_back(s.weight[i]);
        out.near.insert(out.near.end(), s.near.begin() + s.start[i], s.near.begin() + s.start[i + 1]);
        out.share.insert(out.share.end(), s.share.begin() + s.start[i], s.share.begin() + s.start[i + 1]);
        out.start.push_back(uint32_t(out.near.size()));
    }
    return out;
}

Samples surface_samples(const std::vector<uint32_t>& full, const std::vector<float>& before, const std::vector<uint32_t>& rep, const Points& p) {
    Samples s;
    std::vector<double> weight(full.size() / 3, 0.0);
    std::vector<std::pair<uint32_t, double>> candidates;  // (point, share) of the sample being made
    auto corners_of = [&](size_t t) {
        for (int k = 0; k < 3; ++k) candidates.emplace_back(p.point[rep[full[3 * t + size_t(k)]]], weight[t]);
    };
    auto add = [&](V3 x, double w) {
        s.x.push_back(x), s.weight.push_back(w);
        std::sort(candidates.begin(), candidates.end());
        for (size_t i = 0; i < candidates.size();) {
            const uint32_t k = candidates[i].first;
            double share = 0;
            for (; i < candidates.size() && candidates[i].first == k; ++i) share += candidates[i].second;
            s.near.push_back(k), s.share.push_back(float(share));
        }
        s.start.push_back(uint32_t(s.near.size()));
        candidates.clear();
    };
    std::vector<std::pair<uint64_t, uint32_t>> edges;    // (lower << 32 | upper vertex, triangle)
    std::vector<std::pair<uint32_t, uint32_t>> corners;  // (vertex, triangle)
    for (size_t t = 0; 3 * t + 2 < full.size(); ++t) {
        const uint32_t* c = &full[3 * t];
        const V3 a = at(before, c[0]), b = at(before, c[1]), d = at(before, c[2]);
        weight[t] = 0.5 * length(cross(b - a, d - a)) / 7.0;
        if (!(weight[t] > 0)) continue;
        corners_of(t);
        add((1.0 / 3.0) * (a + b + d), weight[t]);
        for (int k = 0; k < 3; ++k) {
            const uint64_t u = c[k], v = c[(k + 1) % 3];
            edges.emplace_back(std::min(u, v) << 32 | std::max(u, v), uint32_t(t));
            corners.emplace_back(c[k], uint32_t(t));
        }
    }
    std::sort(edges.begin(), edges.end());
    for (size_t i = 0; i < edges.size();) {
        const uint64_t e = edges[i].first;
        double w = 0;
        for (; i < edges.size() && edges[i].first == e; ++i) w += weight[edges[i].second], corners_of(edges[i].second);
        const uint32_t u = uint32_t(e >> 32), v = uint32_t(e & 0xffffffffu);
        add(0.5 * (at(before, u) + at(before, v)), w);
    }
    std::sort(corners.begin(), corners.end());
    for (size_t i = 0; i < corners.size();) {
        const uint32_t v = corners[i].first;
        double w = 0;
        for (; i < corners.size() && corners[i].first == v; ++i) w += weight[corners[i].second], corners_of(corners[i].second);
        add(at(before, v), w);
    }
    return in_point_order(s);
}

// Per point, the triangles of `triangles` (3 corners each) with a corner whose point is `of`
// that corner's (CSR, each once per point).
template <class PointOf>
Around around_points(const std::vector<uint32_t>& triangles, uint32_t points, PointOf of) {
    std::vector<std::pair<uint32_t, uint32_t>> pairs;
    for (size_t c = 0; c < triangles.size(); ++c) pairs.emplace_back(of(triangles[c]), uint32_t(c / 3));
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    Around a;
    a.start.assign(size_t(points) + 1, 0);
    for (const auto& [k, t] : pairs) ++a.start[k + 1], a.triangles.push_back(t);
    for (uint32_t k = 0; k < points; ++k) a.start[k + 1] += a.start[k];
    return a;
}

// Per key below `keys`, the corners (3 item + corner, for items below `items`) whose
// `key_of(item, corner)` it is, in item order (CSR; kNone: the corner has none).
template <class KeyOf>
Around corners_by_key(size_t items, uint32_t keys, KeyOf key_of) {
    Around a;
    a.start.assign(size_t(keys) + 1, 0);
    for (size_t i = 0; i < items; ++i)
        for (int c = 0; c < 3; ++c)
            if (const uint32_t k = key_of(i, c); k != kNone) ++a.start[k + 1];
    for (uint32_t k = 0; k < keys; ++k) a.start[k + 1] += a.start[k];
    a.triangles.resize(a.start[keys]);
    std::vector<uint32_t> next(a.start.begin(), a.start.end() - 1);
    for (size_t i = 0; i < items; ++i)
        for (int c = 0; c < 3; ++c)
            if (const uint32_t k = key_of(i, c); k != kNone) a.triangles[next[k]++] = uint32_t(3 * i + size_t(c));
    return a;
}

// Per item of a CSR list of points, the union of those points' lists in `of` (CSR, each
// triangle once, in the order first met). `triangles` bounds the triangle numbers.
Around unions(const std::vector<uint32_t>& start, const std::vector<uint32_t>& points, const Around& of, size_t triangles) {
    Around a;
    a.start.assign(start.size(), 0);
    std::vector<uint32_t> mark(triangles, kNone);
    for (size_t i = 0; i + 1 < start.size(); ++i) {
        for (uint32_t c = start[i]; c < start[i + 1]; ++c)
            for (uint32_t j = of.start[points[c]]; j < of.start[points[c] + 1]; ++j)
                if (mark[of.triangles[j]] != uint32_t(i)) mark[of.triangles[j]] = uint32_t(i), a.triangles.push_back(of.triangles[j]);
        a.start[i + 1] = uint32_t(a.triangles.size());
    }
    return a;
}

// What the fit and its checks read, made once per level: the source's samples with, per
// sample, the level triangles around its points (where a sample of the surface a point stands
// for lies nearest, unless the level folds there), and per level triangle the source triangles
// its corners stand for, with their flats.
struct FitContext {
    std::vector<uint32_t> level;  // the level's triangles, in point order
    const std::vector<float>& before;
    const Points& p;
    uint32_t n;
    Samples samples;
    std::vector<detail::Flat> source_flats;  // per full triangle, in point order
    Around sample_near;                      // per sample: the level triangles around its points, each once
    Around level_sources;                    // per level triangle: the full triangles its corners stand for, each once

    FitContext(const std::vector<uint32_t>& full_, const std::vector<uint32_t>& level_, const std::vector<float>& before_, const std::vector<uint32_t>& rep,
               const Points& p_, uint32_t n_)
        : level(in_point_order(level_, [&](uint32_t v) { return p_.point[v]; })), before(before_), p(p_), n(n_) {
        const auto source_point = [&](uint32_t v) { return p.point[rep[v]]; };
        const std::vector<uint32_t> full = in_point_order(full_, source_point);
        samples = surface_samples(full, before, rep, p);
        source_flats.resize(full.size() / 3);
        for (size_t t = 0; t < source_flats.size(); ++t)
            source_flats[t] = detail::make_flat(at(before, full[3 * t]), at(before, full[3 * t + 1]), at(before, full[3 * t + 2]));
        const Around near = around_points(level, p.count, [&](uint32_t v) { return p.point[v]; });  // per point
        sample_near = unions(samples.start, samples.near, near, level.size() / 3);
        std::vector<uint32_t> start(level.size() / 3 + 1), corners(level.size());
        for (size_t c = 0; c < level.size(); ++c) corners[c] = p.point[level[c]], start[c / 3 + 1] = uint32_t(c + 1);
        level_sources = unions(start, corners, around_points(full, p.count, source_point), full.size() / 3);
    }
};

// The flat of each of `triangles` (3 corners each) with its vertices at `x`.
std::vector<detail::Flat> flats_of(const std::vector<uint32_t>& triangles, const std::vector<float>& x) {
    std::vector<detail::Flat> flats(triangles.size() / 3);
    for (size_t t = 0; t < flats.size(); ++t) flats[t] = detail::make_flat(at(x, triangles[3 * t]), at(x, triangles[3 * t + 1]), at(x, triangles[3 * t + 2]));
    return flats;
}

// Where each sample lies nearest on the level with its vertices at `x`: the nearest point's
// triangle's points, its barycentric weights and the squared distance, among the level
// triangles around the points the sample stands for (kNone where there are none).
struct Projection {
    std::vector<std::array<uint32_t, 3>> points;
    std::vector<std::array<double, 3>> weights;
    std::vector<double> d2;
};

Projection project_samples(const FitContext& f, const std::vector<float>& x) {
    const std::vector<uint32_t>& level = f.level;
    const std::vector<detail::Flat> flats = flats_of(level, x);
    const size_t count = f.samples.x.size();
    Projection out;
    out.points.assign(count, {kNone, kNone, kNone});
    out.weights.assign(count, {0, 0, 0});
    out.d2.assign(count, 0.0);
    detail::parallel_blocks(count, 4096, 0, [&](unsigned, size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
            const V3 s = f.samples.x[i];
            double best = std::numeric_limits<double>::infinity();
            uint32_t nearest = kNone;
            for (uint32_t j = f.sample_near.start[i]; j < f.sample_near.start[i + 1]; ++j) {
                const double d = detail::distance2_below(flats[f.sample_near.triangles[j]], s, best);
                if (d < best) best = d, nearest = f.sample_near.triangles[j];
            }
            if (nearest == kNone) continue;
            detail::nearest_point(flats[nearest], s, out.weights[i].data());
            out.d2[i] = best;
            for (int c = 0; c < 3; ++c) out.points[i][size_t(c)] = f.p.point[level[3 * size_t(nearest) + size_t(c)]];
        }
    });
    return out;
}

// Per point, the (sample, corner) terms where it is a corner of the sample's nearest triangle
// (CSR; a term t is 3 sample + corner).
Around terms_of(const Projection& pr, uint32_t points) {
    return corners_by_key(pr.points.size(), points, [&](size_t i, int c) { return pr.points[i][size_t(c)]; });
}

// The fit of Hoppe et al.'s mesh optimization (1993) with the projections held: the moved points
// minimising the weighted squared distances from the samples to their nearest points,
// sum_i w_i |sum_c b_ic X_c - s_i|^2, plus a pull toward each point's start of a twentieth of a
// mean point's weight (a point the samples barely see, at the far corner of long triangles,
// would otherwise go far to mend a little). Block Gauss-Seidel: each point in turn at its
// minimum with the others held, a weighted average as a point enters each term through a scalar.
// Samples far from the level (of a part the level dropped) weigh less past three times the RMS
// distance, and no point leaves its start by more than `reach`.
void fit_points(const FitContext& f, const Projection& pr, const std::vector<uint8_t>& moved, const std::vector<V3>& anchor, const std::vector<double>& reach,
                std::vector<V3>& x) {
    const Samples& s = f.samples;
    const Around terms = terms_of(pr, f.p.count);
    double sum_d2 = 0, sum_w = 0;
    for (size_t i = 0; i < pr.d2.size(); ++i)
        if (pr.points[i][0] != kNone) sum_d2 += s.weight[i] * pr.d2[i], sum_w += s.weight[i];
    const double tau2 = sum_w > 0 ? 9.0 * sum_d2 / sum_w : 0.0;
    std::vector<double> w(s.weight.size());
    for (size_t i = 0; i < w.size(); ++i) w[i] = tau2 > 0 ? s.weight[i] / (1.0 + pr.d2[i] / tau2) : s.weight[i];
    double total = 0;
    uint32_t seen = 0;
    for (const uint32_t t : terms.triangles) total += w[t / 3] * pr.weights[t / 3][t % 3] * pr.weights[t / 3][t % 3];
    for (uint32_t k = 0; k < f.p.count; ++k) seen += terms.start[k] != terms.start[k + 1];
    const double hold = seen ? 0.05 * total / seen : 0.0;
    for (int sweep = 0; sweep < 8; ++sweep)
        for (uint32_t k = 0; k < f.p.count; ++k) {
            if (!moved[k] || terms.start[k] == terms.start[k + 1]) continue;
            V3 sum{0, 0, 0};
            double norm = 0;
            for (uint32_t j = terms.start[k]; j < terms.start[k + 1]; ++j) {
                const size_t i = terms.triangles[j] / 3, c = terms.triangles[j] % 3;
                const double b = pr.weights[i][c];
                V3 rest = s.x[i];  // the sample less the other corners' share
                for (size_t o = 0; o < 3; ++o)
                    if (o != c) rest = rest - pr.weights[i][o] * x[pr.points[i][o]];
                sum = sum + (w[i] * b) * rest;
                norm += w[i] * b * b;
            }
            if (!(norm + hold > 0)) continue;
            const V3 step = (1.0 / (norm + hold)) * (sum + hold * anchor[k]) - anchor[k];
            const double far = length(step);
            x[k] = anchor[k] + (far > reach[k] ? reach[k] / far : 1.0) * step;
        }
}

// The moved points of the level at `start` fitted to the source: three rounds of projecting the
// samples on the level as it stands and fitting the points to them (eight sweeps each). A point reaches at most
// twice the RMS distance of the samples it is a corner for at the start (what it is there to mend).
std::vector<float> fitted(const FitContext& f, const std::vector<float>& start, const std::vector<uint8_t>& moved) {
    std::vector<float> out = start;
    std::vector<V3> x(f.p.count, V3{0, 0, 0});
    for (uint32_t v = f.n; v-- > 0;) x[f.p.point[v]] = at(out, v);  // the point's first live vertex's
    const std::vector<V3> anchor = x;
    std::vector<double> reach(f.p.count, 0.0), weight(f.p.count, 0.0);
    for (int round = 0; round < 3; ++round) {
        const Projection pr = project_samples(f, out);
        if (round == 0) {
            for (size_t i = 0; i < pr.d2.size(); ++i)
                for (int c = 0; c < 3; ++c) {
                    const uint32_t k = pr.points[i][size_t(c)];
                    if (k == kNone) continue;
                    const double w = f.samples.weight[i] * pr.weights[i][size_t(c)];
                    reach[k] += w * pr.d2[i], weight[k] += w;
                }
            for (uint32_t k = 0; k < f.p.count; ++k) reach[k] = weight[k] > 0 ? 2.0 * std::sqrt(reach[k] / weight[k]) : 0.0;
        }
        fit_points(f, pr, moved, anchor, reach, x);
        for (uint32_t v = 0; v < f.n; ++v)
            if (moved[f.p.point[v]]) {
                const V3 y = x[f.p.point[v]];
                out[3 * size_t(v)] = float(y.x), out[3 * size_t(v) + 1] = float(y.y), out[3 * size_t(v) + 2] = float(y.z);
            }
    }
    return out;
}

// Adds `term` to each distinct point of `k`.
void add_once(std::vector<double>& e, const std::array<uint32_t, 3>& k, double term) {
    e[k[0]] += term;
    if (k[1] != k[0]) e[k[1]] += term;
    if (k[2] != k[0] && k[2] != k[1]) e[k[2]] += term;
}

// Per point, the local two-sided error of the level with its vertices at `x`: the area-weighted
// squared distances from the source's samples of the triangles it stands for to the level, and
// from the seven points of each level triangle around it to the source triangles its corners
// stand for. The second weighs three quarters: the mean the benchmark reads is the larger of
// the two directions', the first on nearly every level, and a point pushed out to bring a
// chord nearer its arc (a sphere's) pays in the second what it gains in the first.
std::vector<double> local_errors(const FitContext& f, const std::vector<float>& x) {
    std::vector<double> e(f.p.count, 0.0);
    const Projection pr = project_samples(f, x);
    for (size_t i = 0; i < f.samples.x.size(); ++i)
        for (uint32_t c = f.samples.start[i]; c < f.samples.start[i + 1]; ++c) e[f.samples.near[c]] += f.samples.share[c] * pr.d2[i];
    const std::vector<uint32_t>& level = f.level;
    std::vector<double> away(level.size() / 3, 0.0);  // per level triangle: its seven points' weighted squared distances
    detail::parallel_blocks(away.size(), 1024, 0, [&](unsigned, size_t begin, size_t end) {
        for (size_t t = begin; t < end; ++t) {
            const uint32_t* c = &level[3 * t];
            const double area = 0.5 * length(cross(at(f.before, c[1]) - at(f.before, c[0]), at(f.before, c[2]) - at(f.before, c[0])));
            double sum = 0;
            for (const V3& q : seven_points(at(x, c[0]), at(x, c[1]), at(x, c[2]))) {
                double best = std::numeric_limits<double>::infinity();
                for (uint32_t j = f.level_sources.start[t]; j < f.level_sources.start[t + 1]; ++j)
                    best = std::min(best, detail::distance2_below(f.source_flats[f.level_sources.triangles[j]], q, best));
                if (std::isfinite(best)) sum += best;
            }
            away[t] = 0.75 * area / 7.0 * sum;
        }
    });
    for (size_t t = 0; t < away.size(); ++t) add_once(e, {f.p.point[level[3 * t]], f.p.point[level[3 * t + 1]], f.p.point[level[3 * t + 2]]}, away[t]);
    return e;
}

// Each point placed where, among the candidate placements of all points (`configs`), its local
// error is the smallest: a move that helps only on average, or only elsewhere, is not taken.
// Returns each point's choice.
std::vector<uint8_t> choose_placements(const FitContext& f, const std::vector<const std::vector<float>*>& configs, std::vector<float>& out) {
    std::vector<double> best(f.p.count, std::numeric_limits<double>::infinity());
    std::vector<uint8_t> choice(f.p.count, 0);
    for (size_t c = 0; c < configs.size(); ++c) {
        const std::vector<double> e = local_errors(f, *configs[c]);
        for (uint32_t k = 0; k < f.p.count; ++k)
            if (e[k] < best[k]) best[k] = e[k], choice[k] = uint8_t(c);
    }
    for (uint32_t v = 0; v < f.n; ++v) std::copy_n(configs[choice[f.p.point[v]]]->begin() + 3 * ptrdiff_t(v), 3, out.begin() + 3 * ptrdiff_t(v));
    return choice;
}

// The level's moved points fitted to the source's surface (fitted()), then each point where its
// local error is the smallest: at full detail, at its quadric's minimum or fitted. A point
// chosen at full detail is no longer moved.
void fit_to_source(const FitContext& f, std::vector<uint8_t>& moved, std::vector<float>& out, RefitStats& s) {
    const std::vector<float> quadric = out, fit = fitted(f, quadric, moved);
    const std::vector<uint8_t> choice = choose_placements(f, {&f.before, &quadric, &fit}, out);
    for (uint32_t k = 0; k < f.p.count; ++k)
        if (choice[k] == 0 && moved[k]) moved[k] = 0, --s.moved, ++s.kept;
}

// `width` values per vertex of `src` at barycentric `w` of the corners `c`, into `dst`.
void interpolate(const float* src, size_t width, const uint32_t* c, const double w[3], float* dst) {
    for (size_t a = 0; a < width; ++a) dst[a] = float(w[0] * src[width * c[0] + a] + w[1] * src[width * c[1] + a] + w[2] * src[width * c[2] + a]);
}

void normalize(float* x, size_t count) {
    double l = 0;
    for (size_t a = 0; a < count; ++a) l += double(x[a]) * x[a];
    l = std::sqrt(l);
    if (l > 0)
        for (size_t a = 0; a < count; ++a) x[a] = float(x[a] / l);
}

// A tangent's xyz made unit and orthogonal to the unit normal `n`.
void orthogonalize(float* t, const float* n) {
    const float along = t[0] * n[0] + t[1] * n[1] + t[2] * n[2];
    for (int a = 0; a < 3; ++a) t[a] -= along * n[a];
    normalize(t, 3);
}

// Each moved vertex's attributes resampled from the source where it now stands: at the point
// closest to its new position among the triangles around the vertices it stands for (its own
// side of a seam or a hard edge: copies stand for their own sides), interpolated there; normals
// made unit, tangents made unit and orthogonal to the normal, their handedness kept.
void resample_attributes(const MeshView& m, uint32_t n, const std::vector<uint32_t>& full, const std::vector<float>& before, const std::vector<uint32_t>& rep,
                         const Points& p, const std::vector<uint8_t>& moved, RefitLevel& r) {
    const Around around = around_points(full, n, [&](uint32_t v) { return rep[v]; });  // per live vertex
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
            orthogonalize(t, &r.normals[3 * size_t(v)]);
            t[3] = handedness;
        }
    }
}

// Where the source's attributes are compared with the level's: at three inner points of every
// source triangle (barycentric 2/3, 1/6, 1/6 and its turns, a third of its area each: exact for
// the squared difference of two linear fields over it, and off its edges, where the copies of a
// seam or a pole's fan meet), the nearest point among the level triangles around the vertices
// its corners stand for (their own sides of a seam or a hard edge; of level triangles as near,
// the one with more of those vertices), in the level as re-fitted.
struct AttributeTerms {
    struct Term {
        uint32_t source[3], level[3];     // the source triangle's corners, the level triangle's
        float at_source[3], at_level[3];  // barycentric weights in each
        float weight = 0;
    };
    std::vector<Term> terms;
    Around of_vertex;  // per live vertex, the terms (3 term + slot) where it is a level corner
};

AttributeTerms attribute_terms(const std::vector<uint32_t>& full, const std::vector<uint32_t>& level, uint32_t n, const std::vector<float>& before,
                               const std::vector<float>& after, const std::vector<uint32_t>& rep) {
    const Around around = around_points(level, n, [](uint32_t v) { return v; });
    const std::vector<detail::Flat> flats = flats_of(level, after);
    const size_t triangles = full.size() / 3;
    AttributeTerms out;
    out.terms.resize(3 * triangles, AttributeTerms::Term{});  // three per source triangle; weight 0 where no level triangle is near
    detail::parallel_blocks(triangles, 1024, 0, [&](unsigned, size_t begin, size_t end) {
        for (size_t t = begin; t < end; ++t) {
            const uint32_t* w = &full[3 * t];
            const double third = length(cross(at(before, w[1]) - at(before, w[0]), at(before, w[2]) - at(before, w[0]))) / 6;
            const uint32_t own[3] = {rep[w[0]], rep[w[1]], rep[w[2]]};
            for (int e = 0; e < 3; ++e) {
                float weights[3];
                for (int a = 0; a < 3; ++a) weights[a] = a == e ? 2.0f / 3.0f : 1.0f / 6.0f;
                const V3 x = double(weights[0]) * at(before, w[0]) + double(weights[1]) * at(before, w[1]) + double(weights[2]) * at(before, w[2]);
                double best = std::numeric_limits<double>::infinity();
                int best_shared = -1;
                AttributeTerms::Term& term = out.terms[3 * t + size_t(e)];
                for (int k = 0; k < 3; ++k)
                    for (uint32_t i = around.start[own[k]]; i < around.start[own[k] + 1]; ++i) {
                        const uint32_t* c = &level[3 * size_t(around.triangles[i])];
                        const detail::Flat& f = flats[around.triangles[i]];
                        const double d = detail::distance2(f, x);
                        const int shared = int(std::count_if(c, c + 3, [&](uint32_t u) { return u == own[0] || u == own[1] || u == own[2]; }));
                        if (!(d < best || (d == best && shared > best_shared))) continue;
                        best = d, best_shared = shared;
                        double b[3];
                        detail::nearest_point(f, x, b);
                        for (int a = 0; a < 3; ++a) term.level[a] = c[a], term.at_level[a] = float(b[a]);
                    }
                if (!(best < std::numeric_limits<double>::infinity()) || !(third > 0)) continue;
                for (int a = 0; a < 3; ++a) term.source[a] = w[a], term.at_source[a] = weights[a];
                term.weight = float(third);
            }
        }
    });
    out.of_vertex = corners_by_key(out.terms.size(), n, [&](size_t i, int c) { return out.terms[i].weight > 0 ? out.terms[i].level[c] : kNone; });
    return out;
}

// Each term's source values of a stream (`width` per vertex of `source`): interpolated at the
// term's point of the source triangle.
std::vector<double> source_targets(const AttributeTerms& a, const float* source, size_t width) {
    std::vector<double> out(a.terms.size() * width, 0.0);
    for (size_t i = 0; i < a.terms.size(); ++i)
        if (a.terms[i].weight > 0)
            for (size_t c = 0; c < width; ++c)
                for (int k = 0; k < 3; ++k) out[width * i + c] += double(a.terms[i].at_source[k]) * source[width * a.terms[i].source[k] + c];
    return out;
}

// One stream's values at the live vertices (`width` per vertex of `values`) fitted to the terms'
// `targets`: each vertex's values minimise the weighted squared differences of the level's
// interpolated values from the targets, with the others held, plus a pull toward its values
// before of a twentieth of a mean vertex's weight (a vertex the terms barely see keeps them);
// four Gauss-Seidel sweeps. A term weighs `weights[term]` when given, else its own weight.
void fit_stream(const AttributeTerms& a, uint32_t n, const std::vector<double>& targets, size_t width, float* values,
                const std::vector<double>* weights = nullptr) {
    const auto weight_of = [&](uint32_t term) { return weights ? (*weights)[term] : double(a.terms[term].weight); };
    std::vector<double> diagonal(n, 0.0);
    double total = 0;
    uint32_t seen = 0;
    for (uint32_t v = 0; v < n; ++v) {
        for (uint32_t i = a.of_vertex.start[v]; i < a.of_vertex.start[v + 1]; ++i) {
            const AttributeTerms::Term& t = a.terms[a.of_vertex.triangles[i] / 3];
            const double b = t.at_level[a.of_vertex.triangles[i] % 3];
            diagonal[v] += weight_of(a.of_vertex.triangles[i] / 3) * b * b;
        }
        if (diagonal[v] > 0) total += diagonal[v], ++seen;
    }
    if (!seen) return;
    const double hold = 0.05 * total / seen;
    const std::vector<float> start(values, values + width * n);
    std::vector<double> sum(width);
    for (int sweep = 0; sweep < 4; ++sweep)
        for (uint32_t v = 0; v < n; ++v) {
            if (!(diagonal[v] > 0)) continue;
            for (size_t c = 0; c < width; ++c) sum[c] = hold * start[width * v + c];
            for (uint32_t i = a.of_vertex.start[v]; i < a.of_vertex.start[v + 1]; ++i) {
                const uint32_t term = a.of_vertex.triangles[i] / 3, slot = a.of_vertex.triangles[i] % 3;
                const AttributeTerms::Term& t = a.terms[term];
                for (size_t c = 0; c < width; ++c) {
                    double r = targets[width * term + c];  // less the other corners' share
                    for (uint32_t k = 0; k < 3; ++k)
                        if (k != slot) r -= double(t.at_level[k]) * values[width * t.level[k] + c];
                    sum[c] += weight_of(term) * t.at_level[slot] * r;
                }
            }
            for (size_t c = 0; c < width; ++c) values[width * v + c] = float(sum[c] / (diagonal[v] + hold));
        }
}

// The live vertices' normals fitted to the source's directions: a normal drawn is the unit
// vector of the interpolated one, which between differing unit normals is shorter than one, so
// each term's target is the source's unit normal at the length the level's interpolation has
// there (a level whose normals already point as the source's is left as it is). What is judged
// is the mean angle off the source's normals, not its square: after a first round of least
// squares each term weighs its own weight over its angle from the last round (iteratively
// reweighted least squares toward the least mean angle; angles below a tenth of a degree count
// as that, so that a term already met does not take over), four rounds of fitting and making the
// normals unit.
void fit_normals(const AttributeTerms& a, uint32_t n, const float* source, float* normals) {
    constexpr int rounds = 4;
    constexpr double least_angle = 0.002;  // radians
    const std::vector<double> directions = source_targets(a, source, 3);
    std::vector<double> targets(directions.size()), weights(a.terms.size());
    for (int round = 0; round < rounds; ++round) {
        for (size_t i = 0; i < a.terms.size(); ++i) {
            const AttributeTerms::Term& t = a.terms[i];
            weights[i] = t.weight;
            if (!(t.weight > 0)) continue;
            double level[3] = {0, 0, 0};
            for (int k = 0; k < 3; ++k)
                for (int c = 0; c < 3; ++c) level[c] += double(t.at_level[k]) * normals[3 * size_t(t.level[k]) + c];
            const double* d = &directions[3 * i];
            const double length = std::sqrt(level[0] * level[0] + level[1] * level[1] + level[2] * level[2]),
                         unit = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int c = 0; c < 3; ++c) targets[3 * i + c] = unit > 0 ? d[c] * length / unit : level[c];
            if (round > 0 && length > 0 && unit > 0) {
                const double cosine = std::clamp((level[0] * d[0] + level[1] * d[1] + level[2] * d[2]) / (length * unit), -1.0, 1.0);
                weights[i] = t.weight / std::max(std::acos(cosine), least_angle);
            }
        }
        fit_stream(a, n, targets, 3, normals, &weights);
        for (uint32_t v = 0; v < n; ++v) normalize(&normals[3 * size_t(v)], 3);
    }
}

// The live vertices' attributes fitted to the source's (fit_stream, fit_normals), colours kept
// in [0, 1], tangents made unit and orthogonal to the normal again.
void fit_attributes(const MeshView& m, uint32_t n, const std::vector<uint32_t>& full, const std::vector<uint32_t>& level, const std::vector<float>& before,
                    const std::vector<uint32_t>& rep, RefitLevel& r) {
    if (!m.normals && !m.texcoords && !m.texcoords1 && !m.colors) return;
    const AttributeTerms a = attribute_terms(full, level, n, before, r.positions, rep);
    if (m.normals) fit_normals(a, n, m.normals, r.normals.data());
    if (m.texcoords) fit_stream(a, n, source_targets(a, m.texcoords, 2), 2, r.texcoords.data());
    if (m.texcoords1) fit_stream(a, n, source_targets(a, m.texcoords1, 2), 2, r.texcoords1.data());
    if (m.colors) {
        fit_stream(a, n, source_targets(a, m.colors, 4), 4, r.colors.data());
        for (size_t i = 0; i < 4 * size_t(n); ++i) r.colors[i] = std::clamp(r.colors[i], 0.0f, 1.0f);
    }
    if (m.tangents && m.normals)
        for (uint32_t v = 0; v < n; ++v) orthogonalize(&r.tangents[4 * size_t(v)], &r.normals[3 * size_t(v)]);
}

// A stream of `width` floats per vertex copied, or empty when the mesh has none.
std::vector<float> copy_stream(const float* values, uint32_t count, size_t width) {
    return values ? std::vector<float>(values, values + width * count) : std::vector<float>();
}

}  // namespace

RefitLevel refit_level(const MeshView& m, uint32_t n) {
    RefitLevel r;
    r.resolution = n = m.whole_groups_below(std::min(std::max(n, m.min_vertex_count), m.vertex_count));  // as extract() takes it
    const std::vector<float> before(m.positions, m.positions + 3 * size_t(m.vertex_count));
    r.positions = before;
    Points p = weld_by_position(m);
    number_in_space(m, p);
    const std::vector<uint32_t> full = level_triangles(m, m.vertex_count), level = level_triangles(m, n);
    const std::vector<uint32_t> rep = representatives(m, n);
    std::vector<uint8_t> moved = move_points(m, n, p, fixed_points(full, p), point_quadrics(m, full, p, rep), r.positions, r.stats);
    fit_to_source(FitContext(full, level, before, rep, p, n), moved, r.positions, r.stats);
    put_back_turned(level, n, p, before, moved, r.positions, r.stats);
    r.normals = copy_stream(m.normals, m.vertex_count, 3);
    r.texcoords = copy_stream(m.texcoords, m.vertex_count, 2);
    r.texcoords1 = copy_stream(m.texcoords1, m.vertex_count, 2);
    r.colors = copy_stream(m.colors, m.vertex_count, 4);
    r.tangents = copy_stream(m.tangents, m.vertex_count, 4);
    resample_attributes(m, n, full, before, rep, p, moved, r);
    fit_attributes(m, n, full, level, before, rep, r);
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

}  // namespace tom
