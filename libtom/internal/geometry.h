#pragma once
// Point-triangle and point-box distances on plain doubles, for the Metro-style nearest-point
// search (metrics/distance_cgal.cpp) and the builder's re-fitting (builder/refit.cpp): a
// triangle is kept as a Flat record with what a distance needs precomputed.

#include <algorithm>
#include <cmath>
#include <limits>

#include "vec3.h"

namespace tom::detail {

// Vector arithmetic on plain doubles (the hot loops do not go through CGAL's kernel).
using V3 = Vec3T<double>;
inline V3 operator-(V3 a, V3 b) { return sub(a, b); }
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }

// A target triangle as the search reads it: plane first (the cheapest lower bound), then corner
// a, the edges from a, their Gram matrix with its inverse determinant and the inverse squared
// lengths of the three edges (what distance2() needs); its box is flat_box()'s.
struct Flat {
    V3 normal;  // unit normal (zero for a degenerate triangle)
    double offset;
    V3 a, e0, e1;              // a, b - a, c - a
    double d00, d01, d11;      // e0.e0, e0.e1, e1.e1
    double inverse;            // 1 / (d00 d11 - d01^2); NaN for a degenerate triangle (never inside)
    double i00, i11, i22;      // 1 / |e|^2 of each edge, e2 = c - b (0 for a zero-length one)
};

// The Gram determinant of the edges from a: (2 area)^2.
inline double gram(const Flat& f) { return f.d00 * f.d11 - f.d01 * f.d01; }

// The box of the corners a, a + e0, a + e1: the triangle's own box where the edges are exact
// differences (of floats: a mesh's corners, unless their exponents lie some 29 apart), within a
// rounding of it otherwise (which the bounds that read it are lowered by far more than). Made
// when needed: 48 bytes a record less (a report holds millions).
inline void flat_box(const Flat& f, V3& lo, V3& hi) {
    const V3 b = f.a + f.e0, c = f.a + f.e1;
    lo = {std::min({f.a.x, b.x, c.x}), std::min({f.a.y, b.y, c.y}), std::min({f.a.z, b.z, c.z})};
    hi = {std::max({f.a.x, b.x, c.x}), std::max({f.a.y, b.y, c.y}), std::max({f.a.z, b.z, c.z})};
}

inline Flat make_flat(V3 a, V3 b, V3 c) {
    Flat f;
    f.a = a;
    f.e0 = b - a, f.e1 = c - a;
    const V3 n = cross(f.e0, f.e1);
    const double len = length(n);
    f.normal = len > 0 ? (1.0 / len) * n : V3{0, 0, 0};
    f.offset = -dot(f.normal, a);
    f.d00 = dot(f.e0, f.e0), f.d01 = dot(f.e0, f.e1), f.d11 = dot(f.e1, f.e1);
    const double det = gram(f);
    f.inverse = len > 0 && det > 0 ? 1.0 / det : std::numeric_limits<double>::quiet_NaN();
    const double l22 = dot(c - b, c - b);
    f.i00 = f.d00 > 0 ? 1.0 / f.d00 : 0.0, f.i11 = f.d11 > 0 ? 1.0 / f.d11 : 0.0, f.i22 = l22 > 0 ? 1.0 / l22 : 0.0;
    return f;
}

inline double clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

// Squared distance from p to segment o + t e, t in [0, 1], given w = p - o, we = w.e, ie = 1/|e|^2.
inline double segment_d2(V3 w, V3 e, double we, double ie) {
    const V3 d = w - clamp01(we * ie) * e;
    return dot(d, d);
}

// Where p projects in the triangle's plane: weights (u, v) of e0 and e1; inside when u, v >= 0
// and u + v <= 1 (never for a degenerate triangle: NaN).
inline void project(const Flat& f, double w0, double w1, double& u, double& v) {
    u = (f.d11 * w0 - f.d01 * w1) * f.inverse, v = (f.d00 * w1 - f.d01 * w0) * f.inverse;
}

// Squared distance from p (w = p - a, w0 = e0.w, w1 = e1.w) to the nearest of the triangle's
// three edges.
inline double edges_d2(const Flat& f, V3 w, double w0, double w1) {
    const V3 wb = w - f.e0, e2 = f.e1 - f.e0;
    return std::min({segment_d2(w, f.e0, w0, f.i00), segment_d2(w, f.e1, w1, f.i11), segment_d2(wb, e2, dot(e2, wb), f.i22)});
}

// Squared distance from p to the triangle: when p projects inside it, its plane distance;
// otherwise the nearest of its three edges. Few branches, no division.
inline double distance2(const Flat& f, V3 p) {
    const V3 w = p - f.a;
    const double w0 = dot(f.e0, w), w1 = dot(f.e1, w);
    double u, v;
    project(f, w0, w1, u, v);
    if (u >= 0 && v >= 0 && u + v <= 1) {
        const double above = dot(f.normal, p) + f.offset;
        return above * above;
    }
    return edges_d2(f, w, w0, w1);
}

// distance2(f, p) where it is under `best`, and otherwise perhaps only a lower bound of it (at
// least `best`): where p projects outside the triangle, the plane's distance and the in-plane
// distance to the line of each edge p's projection lies beyond (weight w of the opposite corner
// below 0: |w| times that corner's height over the edge, squared w^2 |e|^-2 (2 area)^2, with
// (2 area)^2 = d00 d11 - d01^2) bound it from below; the three edges' distances are computed only
// when that bound is under the best, widened against rounding (relatively, and by 2^-30 of the
// triangle's size, so that points on the surface get distance2()'s very figure): a candidate
// the search tests that is not nearer can stop there.
inline double distance2_below(const Flat& f, V3 p, double best) {
    const V3 w = p - f.a;
    const double w0 = dot(f.e0, w), w1 = dot(f.e1, w);
    double u, v;
    project(f, w0, w1, u, v);
    const double above = dot(f.normal, p) + f.offset;
    if (u >= 0 && v >= 0 && u + v <= 1) return above * above;
    const double t = 1 - u - v;
    const double beyond = std::max({u < 0 ? u * u * f.i11 : 0.0, v < 0 ? v * v * f.i00 : 0.0, t < 0 ? t * t * f.i22 : 0.0}) * gram(f);
    const double low = above * above + beyond;  // (NaN for a degenerate triangle: never skipped)
    if (low * (1.0 - 1e-9) - (f.d00 + f.d11) * 0x1p-60 >= best) return low;
    return edges_d2(f, w, w0, w1);
}

// The point of the triangle nearest to p (distance2()'s argument), and its barycentric weights.
inline V3 nearest_point(const Flat& f, V3 p, double weights[3] = nullptr) {
    const V3 w = p - f.a;
    const double w0 = dot(f.e0, w), w1 = dot(f.e1, w);
    double u, v;
    project(f, w0, w1, u, v);
    if (!(u >= 0 && v >= 0 && u + v <= 1)) {
        const V3 wb = w - f.e0, e2 = f.e1 - f.e0;
        const double t0 = clamp01(w0 * f.i00), t1 = clamp01(w1 * f.i11), t2 = clamp01(dot(e2, wb) * f.i22);
        const V3 q0 = t0 * f.e0, q1 = t1 * f.e1, q2 = f.e0 + t2 * e2;  // relative to a
        const double s0 = dot(w - q0, w - q0), s1 = dot(w - q1, w - q1), s2 = dot(w - q2, w - q2);
        if (s0 <= s1 && s0 <= s2)
            u = t0, v = 0;
        else if (s1 <= s2)
            u = 0, v = t1;
        else
            u = 1 - t2, v = t2;
    }
    if (weights) weights[0] = 1 - u - v, weights[1] = u, weights[2] = v;
    return f.a + u * f.e0 + v * f.e1;
}

// Squared distance between the axis-aligned boxes [alo, ahi] and [blo, bhi] (0 when they
// overlap), and from point p to the box [lo, hi]; branch-free.
inline double gap(double a, double b) { return std::max(std::max(a, b), 0.0); }
inline double boxes_d2(V3 alo, V3 ahi, V3 blo, V3 bhi) {
    const double dx = gap(blo.x - ahi.x, alo.x - bhi.x), dy = gap(blo.y - ahi.y, alo.y - bhi.y), dz = gap(blo.z - ahi.z, alo.z - bhi.z);
    return dx * dx + dy * dy + dz * dz;
}
inline double point_box_d2(V3 p, V3 lo, V3 hi) { return boxes_d2(p, p, lo, hi); }

} // namespace tom::detail
