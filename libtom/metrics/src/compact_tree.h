#pragma once
// A compact bounding-volume hierarchy over a surface's own arrays, for the nearest triangles of a
// few thousand points (the error curve's 4096 samples a direction against levels of up to
// millions of triangles): triangles in Morton order of their centroids, split at the median
// into nodes of one box each, leaves of up to kLeafTriangles. About 16 bytes a triangle where
// the run search's Mesh3 holds some 270 (its Flat records, edge lines and four-way tree, made
// through a CGAL tree), and made in a radix sort and one pass: for so few points against a
// large surface the structure, not the search, is the cost (DistanceParams::
// compact_search_triangles says from what size). Internal to tom::metrics.
//
// Exact as the run search: the leaves' triangles are made into the same Flat records from the
// same corners (make_flat), so a distance is the same double; among triangles at the same
// distance, the one first in the surface wins; boxes are the corners' own floats (exact), and
// a node is left only when its box is farther than the best so far.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "geometry.h"
#include "samples.h"
#include "tom/metrics/distance.h"

namespace tom::detail {

class CompactTree {
public:
    static constexpr uint32_t kNone = 0xffffffffu;
    static constexpr uint32_t kLeafTriangles = 8;

    /// `s` must outlive the tree and have at least one triangle with indices in range.
    explicit CompactTree(const Surface& s) : s_(s) {
        order_ = faces_in_morton_order(s, 1);
        nodes_.reserve(2 * (s.triangle_count / kLeafTriangles + 1));
        add(0, uint32_t(s.triangle_count));
    }

    uint32_t triangle_count() const { return uint32_t(s_.triangle_count); }

    /// The triangle nearest to p and its squared distance `d2`; `hint` and `other` (triangles
    /// near p, or kNone) bound the search from the start.
    uint32_t nearest(V3 p, uint32_t hint, uint32_t other, double& d2) const {
        double best_d2 = INFINITY;
        uint32_t best = kNone;
        auto consider = [&](uint32_t t) {
            const double d = distance2_below(flat(t), p, best_d2);
            if (d < best_d2 || (d == best_d2 && t < best)) best_d2 = d, best = t;
        };
        if (hint != kNone) consider(hint);
        if (other != kNone && other != hint) consider(other);
        struct Entry {
            uint32_t node;
            double d2;
        };
        Entry stack[96];  // (depth at most log2 of 2^32 / kLeafTriangles, two entries a level)
        size_t top = 0;
        stack[top++] = {0, box_d2(nodes_[0], p)};
        while (top > 0) {
            const Entry e = stack[--top];
            if (e.d2 > best_d2) continue;
            const Node& n = nodes_[e.node];
            if (n.count > 0) {
                for (uint32_t i = n.first; i < n.first + n.count; ++i) consider(order_[i]);
                continue;
            }
            // children: the nearer last, so taken first
            const uint32_t l = e.node + 1, r = n.first;
            const double dl = box_d2(nodes_[l], p), dr = box_d2(nodes_[r], p);
            if (dl <= dr) {
                if (dr <= best_d2) stack[top++] = {r, dr};
                if (dl <= best_d2) stack[top++] = {l, dl};
            } else {
                if (dl <= best_d2) stack[top++] = {l, dl};
                if (dr <= best_d2) stack[top++] = {r, dr};
            }
        }
        d2 = best_d2;
        return best;
    }

    Flat flat(uint32_t t) const { return make_flat(corner(t, 0), corner(t, 1), corner(t, 2)); }

private:
    // A node's box; a leaf (count > 0) holds order_[first, first + count), an inner node's left
    // child follows it and `first` is its right child.
    struct Node {
        float lo[3], hi[3];
        uint32_t first, count;
    };

    V3 corner(uint32_t t, int k) const {
        const float* x = s_.positions + 3 * size_t(s_.indices[3 * size_t(t) + size_t(k)]);
        return {x[0], x[1], x[2]};
    }

    // Squared distance to a node's box, lowered by 2^-40 of itself against the rounding of the
    // three differences and squares (the box's floats are exact)
    static double box_d2(const Node& n, V3 p) {
        const double d = point_box_d2(p, {n.lo[0], n.lo[1], n.lo[2]}, {n.hi[0], n.hi[1], n.hi[2]});
        return d * (1.0 - 0x1p-40);
    }

    // The subtree over order_[b, e), depth first; returns its node.
    uint32_t add(uint32_t b, uint32_t e) {
        const uint32_t at = uint32_t(nodes_.size());
        nodes_.push_back({});
        if (e - b <= kLeafTriangles) {
            Node& n = nodes_[at];
            n.first = b, n.count = e - b;
            for (int a = 0; a < 3; ++a) n.lo[a] = INFINITY, n.hi[a] = -INFINITY;
            for (uint32_t i = b; i < e; ++i)
                for (int k = 0; k < 3; ++k) {
                    const float* x = s_.positions + 3 * size_t(s_.indices[3 * size_t(order_[i]) + size_t(k)]);
                    for (int a = 0; a < 3; ++a) n.lo[a] = std::fmin(n.lo[a], x[a]), n.hi[a] = std::fmax(n.hi[a], x[a]);
                }
            return at;
        }
        const uint32_t mid = b + (e - b) / 2;
        const uint32_t l = add(b, mid), r = add(mid, e);
        Node& n = nodes_[at];
        n.first = r, n.count = 0;
        for (int a = 0; a < 3; ++a) n.lo[a] = std::fmin(nodes_[l].lo[a], nodes_[r].lo[a]), n.hi[a] = std::fmax(nodes_[l].hi[a], nodes_[r].hi[a]);
        return at;
    }

    Surface s_;
    std::vector<uint32_t> order_;  // triangles in leaf order
    std::vector<Node> nodes_;
};

} // namespace tom::detail
