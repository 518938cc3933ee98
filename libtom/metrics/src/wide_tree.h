#pragma once
// A compact four-way copy of a binary bounding-volume hierarchy, for the Metro-style distance's
// two searches (metrics/distance_cgal.cpp, where the hierarchy is CGAL's AABB tree): every node
// holds its (up to) four children's boxes in single precision, side by side, so one node read
// (two cache lines) and four box tests replace two levels of the binary tree (its nodes hold one
// box each, in double: 64 bytes a node, four nodes read per two levels). Leaves are the
// triangles' Flat records, in the binary tree's leaf order.
//
// Single precision is a filter, never an answer: boxes are stored relative to the tree's centre
// and a box counts as within a squared distance r2 up to a margin that covers the rounding
// (Query::limit), so a search enters every node the binary tree's exact tests would enter (and
// perhaps a few more); what it finds is decided in double at the leaves. Internal to
// tom::metrics.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "geometry.h"

namespace tom::detail {

struct WideNode {
    alignas(16) float lo[3][4];  // child boxes by axis, relative to the tree's centre; unused: empty (+inf, -inf)
    alignas(16) float hi[3][4];
    int32_t child[4];  // >= 0: a node; kUnused; otherwise < 0: the leaf ~child (a record of the Flat array)
    static constexpr int32_t kUnused = INT32_MIN;  // (its box is empty, so only an infinite limit reaches it)
};

class WideTree {
public:
    // The binary hierarchy `Split` describes: split(sub, left, right) gives a subtree's two
    // children, box(sub, lo, hi) its box; a subtree has a `count` of leaves and the record
    // `first` of its first, and a subtree of one leaf is that record.
    template <class Sub, class Split, class Box>
    void build(const Sub& root, Split&& split, Box&& box) {
        nodes_.clear();
        V3 lo, hi;
        box(root, lo, hi);
        centre_ = 0.5 * (lo + hi);
        extent_ = std::max({hi.x - centre_.x, hi.y - centre_.y, hi.z - centre_.z, 0.0});
        add(root, split, box);
    }

    // Per query: the point (or box) relative to the centre in single precision, and the margin
    // that covers the rounding of it and of the boxes: each distance is off by at most delta =
    // 64 units of the last place of the largest coordinate involved, so a box whose exact
    // squared distance d2 is below r2 computes below (sqrt(r2) + delta)^2 <= 1.001 r2 + 1001
    // delta^2 (2ab <= a^2 e + b^2 / e with e = 1e-3), up to the squares' own rounding (relative,
    // inside the 1.001)
    //
    // `enough`: a squared distance so small that nearest() stops there, (2^-40 of the tree's
    // size)^2. Without it a point on the surface (squared distance 1e-30 from rounding, not 0)
    // made the search open every box around it, in case a triangle were nearer still, which on
    // CAD meshes, whose long thin triangles' boxes overlap, is most of the search.
    // What it can cost a distance, 2^-40 of the size, is far below the input's own precision.
    struct Query {
        float x0, y0, z0, x1, y1, z1;  // the box queried (a point: both corners the same)
        double slack, enough;
        float limit(double r2) const { return float(r2 * 1.001 + slack); }
    };
    Query query(V3 lo, V3 hi) const {
        const V3 a = lo - centre_, b = hi - centre_;
        const double m = std::max({extent_, std::fabs(a.x), std::fabs(a.y), std::fabs(a.z), std::fabs(b.x), std::fabs(b.y), std::fabs(b.z)});
        const double delta = 64.0 * m * std::ldexp(1.0, -24), close = std::ldexp(extent_, -40);
        return {float(a.x), float(a.y), float(a.z), float(b.x), float(b.y), float(b.z), m < 1e15 ? 1001.0 * delta * delta : INFINITY, close * close};
    }

    // Squared distances (single precision) from the query's box to node n's four child boxes.
    void distances(const Query& q, int32_t n, float d2[4]) const {
        const WideNode& w = nodes_[size_t(n)];
#if defined(__SSE2__)
        const __m128 zero = _mm_setzero_ps();
        auto axis = [&](int a, float q0, float q1) {
            const __m128 lo = _mm_load_ps(w.lo[a]), hi = _mm_load_ps(w.hi[a]);
            const __m128 d = _mm_max_ps(_mm_max_ps(_mm_sub_ps(lo, _mm_set1_ps(q1)), _mm_sub_ps(_mm_set1_ps(q0), hi)), zero);
            return _mm_mul_ps(d, d);
        };
        _mm_storeu_ps(d2, _mm_add_ps(_mm_add_ps(axis(0, q.x0, q.x1), axis(1, q.y0, q.y1)), axis(2, q.z0, q.z1)));
#else
        for (int k = 0; k < 4; ++k) {
            const float dx = std::max(std::max(w.lo[0][k] - q.x1, q.x0 - w.hi[0][k]), 0.0f);
            const float dy = std::max(std::max(w.lo[1][k] - q.y1, q.y0 - w.hi[1][k]), 0.0f);
            const float dz = std::max(std::max(w.lo[2][k] - q.z1, q.z0 - w.hi[2][k]), 0.0f);
            d2[k] = (dx * dx + dy * dy) + dz * dz;
        }
#endif
    }

    // Calls leaf(record, d2) for every leaf in a node whose box lies within the query's squared
    // distance r2 (a filter: the caller tests the leaf exactly), left to right; d2, the leaf box's
    // squared distance to the query in single precision (floor(d2) is at most the exact one).
    template <class Leaf>
    void within(const Query& q, double r2, Leaf&& leaf, int32_t n = 0) const {
        float d2[4];
        distances(q, n, d2);
        const float limit = q.limit(r2);
        const WideNode& w = nodes_[size_t(n)];
        for (int k = 0; k < 4; ++k) {
            if (!(d2[k] <= limit) || w.child[k] == WideNode::kUnused) continue;
            if (w.child[k] >= 0)
                within(q, r2, leaf, w.child[k]);
            else
                leaf(uint32_t(~w.child[k]), d2[k]);
        }
    }

    // A lower bound of the exact squared distance whose single-precision figure a search
    // computed as d2 (the inverse of Query::limit: the rounding it allows for taken off).
    static double floor(const Query& q, float d2) { return std::max(0.0, (double(d2) - q.slack) / 1.001); }

    // Nearest-first search: leaf(record) for the leaves of the nodes whose box may be nearer
    // than the current best, bound() (a squared distance, read again after each leaf), nearer
    // children first; it stops once the best is within the query's `enough`.
    template <class Leaf, class Bound>
    void nearest(const Query& q, Leaf&& leaf, Bound&& bound, int32_t n = 0) const {
        float d2[4];
        distances(q, n, d2);
        int order[4] = {0, 1, 2, 3};
        for (int i = 1; i < 4; ++i)  // insertion sort of four
            for (int j = i; j > 0 && d2[order[j]] < d2[order[j - 1]]; --j) std::swap(order[j], order[j - 1]);
        const WideNode& w = nodes_[size_t(n)];
        for (int i = 0; i < 4; ++i) {
            const int k = order[i];
            const double best = bound();
            if (best <= q.enough || !(d2[k] < q.limit(best)) || w.child[k] == WideNode::kUnused) return;  // sorted: the rest are farther
            if (w.child[k] >= 0)
                nearest(q, leaf, bound, w.child[k]);
            else
                leaf(uint32_t(~w.child[k]));
        }
    }

private:
    template <class Sub, class Split, class Box>
    int32_t add(const Sub& sub, Split& split, Box& box) {
        // up to four parts: the largest part of more than one leaf is split until there are four
        std::vector<Sub> parts{sub};
        while (parts.size() < 4) {
            size_t widest = parts.size();
            for (size_t i = 0; i < parts.size(); ++i)
                if (parts[i].count > 1 && (widest == parts.size() || parts[i].count > parts[widest].count)) widest = i;
            if (widest == parts.size()) break;  // all leaves
            Sub l, r;
            split(parts[widest], l, r);
            parts[widest] = l;
            parts.insert(parts.begin() + std::ptrdiff_t(widest) + 1, r);  // left to right kept
        }
        const int32_t index = int32_t(nodes_.size());
        nodes_.emplace_back();
        const float inf = std::numeric_limits<float>::infinity();
        for (int k = 0; k < 4; ++k) {
            WideNode& w = nodes_[size_t(index)];
            if (size_t(k) >= parts.size()) {
                for (int a = 0; a < 3; ++a) w.lo[a][k] = inf, w.hi[a][k] = -inf;
                w.child[k] = WideNode::kUnused;
                continue;
            }
            V3 lo, hi;
            box(parts[size_t(k)], lo, hi);
            const V3 a = lo - centre_, b = hi - centre_;
            w.lo[0][k] = float(a.x), w.lo[1][k] = float(a.y), w.lo[2][k] = float(a.z);
            w.hi[0][k] = float(b.x), w.hi[1][k] = float(b.y), w.hi[2][k] = float(b.z);
            const int32_t c = parts[size_t(k)].count == 1 ? ~int32_t(parts[size_t(k)].first) : add(parts[size_t(k)], split, box);
            nodes_[size_t(index)].child[k] = c;  // (add() may have moved the nodes)
        }
        return index;
    }

    std::vector<WideNode> nodes_;
    V3 centre_{0, 0, 0};
    double extent_ = 0;
};

} // namespace tom::detail
