// Greedy vertex substitution into a Totally Ordered Mesh.
//
// This work is based on:
// - E. Gobbetti, E. Bouvier. Time-critical multiresolution scene rendering / The Totally Ordered
//   Mesh. 1999: vertex substitution, binary oracle + fairness predicate, total order of vertices
//   and triangles, memoryless penalty dV + |v1-v2| dA + inversion + normal angle.
// - M. Garland, P. Heckbert. Surface Simplification Using Quadric Error Metrics. 1997.
// - P. Lindstrom, G. Turk. Fast and Memory Efficient Polygonal Simplification. 1998.
// - A. Kapoulkine. meshoptimizer, simplifier: the idea of passes of independent collapses sorted
//   by cost, and of classifying vertices (manifold, border, locked) to restrict their targets.
//
// Algorithm (both strategies):
//   classify vertices: interior (any edge neighbour), border (only along its border loop),
//   locked (non-manifold, border corners, coincident copies: never removed, may be a target)
//   repeat: pick the legal substitution v1 -> v2 of lowest penalty, rewrite v1's triangles to v2,
//           the ones containing v2 die; record (v1, v2)
//   until no legal substitution is left. Sort: survivors first, then removed vertices from the
//   last removed to the first; triangles by the resolution at which they die.

#include "tom/builder.h"

#include "attribute_error.h"
#include "format_layout.h"
#include "morton.h"
#include "parallel.h"
#include "radix_sort.h"
#include "vec3.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>

namespace tom {

namespace {

using Vec3 = detail::Vec3T<float>;
using detail::cross;
using detail::dot;
using detail::length;
using detail::sub;
using detail::thread_count;

// Q(p) = p^T A p + 2 b.p + c, A symmetric (a00 a01 a02 a11 a12 a22). The error is divided by
// the accumulated weight (area), as meshoptimizer does: a mean squared distance, which measured
// lower Metro error on both bunny and fandisk than the area-weighted sum.
struct Quadric {
    double a00, a01, a02, a11, a12, a22, b0, b1, b2, c;
    double w;  // accumulated weight (area): the error is reported per unit weight
};

inline void add_plane(Quadric& q, double nx, double ny, double nz, double d, double w) {
    q.a00 += w * nx * nx, q.a01 += w * nx * ny, q.a02 += w * nx * nz;
    q.a11 += w * ny * ny, q.a12 += w * ny * nz, q.a22 += w * nz * nz;
    q.b0 += w * nx * d, q.b1 += w * ny * d, q.b2 += w * nz * d;
    q.c += w * d * d;
    q.w += w;
}

inline void add(Quadric& q, const Quadric& r) {
    q.a00 += r.a00, q.a01 += r.a01, q.a02 += r.a02, q.a11 += r.a11, q.a12 += r.a12, q.a22 += r.a22;
    q.b0 += r.b0, q.b1 += r.b1, q.b2 += r.b2, q.c += r.c;
    q.w += r.w;
}

inline double evaluate(const Quadric& q, Vec3 p) {
    const double x = p.x, y = p.y, z = p.z;
    const double r = q.a00 * x * x + q.a11 * y * y + q.a22 * z * z + 2 * (q.a01 * x * y + q.a02 * x * z + q.a12 * y * z) +
                     2 * (q.b0 * x + q.b1 * y + q.b2 * z) + q.c;
    return r > 0 && q.w > 0 ? r / q.w : 0;
}

// kSeam: one of two coincident copies (an attribute seam), each on its own chart's border; the
// two collapse together along the seam (see seam_target) and stay coincident at every resolution
enum Kind : uint8_t { kInterior = 0, kBorder = 1, kLocked = 2, kSeam = 3 };

constexpr uint32_t kNone = UINT32_MAX;
constexpr float kBoundaryWeight = 4.0f;  // border edge planes vs. area-weighted face planes

struct Candidate {
    float cost;
    uint32_t v, u;
};

// What one thread needs to evaluate substitutions: visit stamps per vertex (deduplication in
// O(1)) and the candidate targets of one vertex.
struct Scratch {
    std::vector<uint32_t> stamp;  // per vertex: the visit that last saw it
    uint32_t visit = 0;
    std::vector<Candidate> targets;
    uint32_t next_visit() {
        if (++visit == 0) {  // wrapped: clear and start again
            std::fill(stamp.begin(), stamp.end(), 0u);
            visit = 1;
        }
        return visit;
    }
};

// Shared state of one build: current triangles, vertex classes, removal record.
struct Builder {
    uint32_t n = 0, m = 0;
    const Vec3* pos = nullptr;
    const Vec3* vnormal = nullptr;
    Predicate predicate = Predicate::quadric;
    detail::AttributeError attributes;  // the predicates' attribute term (inactive without attributes)
    float min_cos2 = 0.0f;  // cos^2 of the largest rotation a surviving triangle's normal may take (0: flips only)
    std::vector<uint32_t> idx;  // current corners, rewritten by substitutions
    std::vector<uint8_t> dead;  // per triangle
    std::vector<uint8_t> kind;
    std::vector<uint8_t> removed;
    std::vector<uint32_t> border_next, border_prev;
    std::vector<uint32_t> partner;     // a seam vertex's coincident copy, or kNone
    std::vector<uint32_t> wedge;       // the position class of a vertex: its first coincident copy
    std::vector<uint32_t> next_copy;   // circular list of a class's copies (a singleton points to itself)
    std::vector<uint32_t> pair_steps;  // substitution j and j + 1 are one seam collapse
    detail::TeamVector<Quadric> quadric;
    // non-edge pairs closer than the threshold, symmetric; a substitution v -> u moves v's pairs
    // to u (Garland-Heckbert), so parts stay joinable after their first vertices are gone
    std::vector<std::vector<uint32_t>> pairs;
    std::vector<uint32_t> removed_order, removed_target;
    std::vector<uint32_t> death_step;  // per triangle: the substitution that killed it, or kNone
    Scratch scratch;  // the calling thread's; workers bring their own
    // with a list, apply() leaves the quadric merges (target, removed) there for the caller to make
    // before the targets' quadrics are read (run_passes: on the team, with the next foresight)
    std::vector<std::pair<uint32_t, uint32_t>>* deferred_merges = nullptr;

    // (both without branches: which corner holds v is a coin toss the predictor always loses)
    bool contains(uint32_t t, uint32_t v) const {
        const uint32_t* c = &idx[3 * t];
        return (c[0] == v) | (c[1] == v) | (c[2] == v);
    }
    // the two other corners of t in winding order after v
    void others(uint32_t t, uint32_t v, uint32_t& a, uint32_t& b) const {
        static constexpr uint8_t after[3] = {1, 2, 0}, before[3] = {2, 0, 1};
        const uint32_t* c = &idx[3 * t];
        const uint32_t k = uint32_t(c[1] == v) + 2u * uint32_t(c[2] == v);  // v's corner
        a = c[after[k]], b = c[before[k]];
    }

    // A border loop of three edges cannot lose a vertex (it would fold onto itself).
    // A border vertex moves along its loop, or onto a pair partner (joining two parts).
    bool border_move_allowed(uint32_t v, uint32_t u) const {
        if (kind[v] != kBorder && kind[v] != kSeam) return true;
        if (u != border_next[v] && u != border_prev[v])
            return !pairs.empty() && std::find(pairs[v].begin(), pairs[v].end(), u) != pairs[v].end();
        return border_next[border_next[v]] != border_prev[v];
    }

    // For a seam vertex v moving to its border neighbour u: the copy's matching move v' -> u',
    // u' the copy's border neighbour at u's position; kNone when there is none.
    uint32_t seam_target(uint32_t v, uint32_t u) const {
        const uint32_t w = partner[v];
        if (w == kNone || removed[w]) return kNone;
        for (const uint32_t c : {border_next[w], border_prev[w]})
            if (c != kNone && !removed[c] && std::memcmp(&pos[c], &pos[u], sizeof(Vec3)) == 0) return c;
        return kNone;
    }

    // The binary oracle's geometric and topological tests for v -> u:
    // - no surviving triangle of v flips (or becomes zero-area), nor turns its normal by more
    //   than the maximum rotation (BuildParams::max_rotation_degrees);
    // - link condition: every vertex w adjacent to both v and u forms a triangle (v, u, w),
    //   otherwise edges v-w and u-w merge into a non-manifold edge;
    // - no rewritten triangle duplicates one of u's (closed surfaces stop at a tetrahedron).
    template <class Adj>
    bool illegal(const Adj& adj, uint32_t v, uint32_t u, Scratch& sc) const {
        std::vector<uint32_t>& stamp = sc.stamp;
        const Vec3 pv = pos[v], pu = pos[u];
        uint32_t opposite[8];
        size_t co = 0;
        bool bad = false;
        const uint32_t wv = wedge[v], wu = wedge[u];
        // link condition on the surface welded by position (seam copies are one point): every
        // class adjacent to both v's and u's must be opposite a triangle joining them, otherwise
        // two edges merge into a non-manifold one. First, the classes around v and its copies.
        const uint32_t mark = sc.next_visit();
        auto is_opposite = [&](uint32_t w) {
            for (size_t i = 0; i < co; ++i)
                if (opposite[i] == w) return true;
            return false;
        };
        auto link = [&](uint32_t a, uint32_t c) {
            const uint32_t wa = wedge[a], wc = wedge[c];
            stamp[wa] = mark;
            stamp[wc] = mark;
            if (wa == wu || wc == wu) {
                const uint32_t w = wa == wu ? wc : wa;
                if (!is_opposite(w)) {
                    if (co < 8) opposite[co++] = w;
                    else bad = true;
                }
            }
        };
        // v's own fan in one walk: flips (only v's triangles move; those with u die) and its link
        adj.each(v, [&](uint32_t t) {
            if (bad) return;
            uint32_t a, c;
            others(t, v, a, c);
            if (a != u && c != u) {
                const Vec3 pa = pos[a], pc = pos[c];
                const Vec3 n0 = cross(sub(pa, pv), sub(pc, pv));
                const Vec3 n1 = cross(sub(pa, pu), sub(pc, pu));
                const float d = dot(n0, n1), l0 = dot(n0, n0);
                if (l0 > 0.0f && (d <= 0.0f || d * d <= min_cos2 * l0 * dot(n1, n1))) {
                    bad = true;
                    return;
                }
            }
            link(a, c);
        });
        for (uint32_t x = next_copy[v]; x != v && !bad; x = next_copy[x])
            adj.each(x, [&](uint32_t t) {
                uint32_t a, c;
                others(t, x, a, c);
                link(a, c);
            });
        if (bad) return true;
        uint32_t y = u;
        do {
            adj.each(y, [&](uint32_t t) {
                if (bad) return;
                uint32_t a, c;
                others(t, y, a, c);
                const uint32_t wa = wedge[a], wc = wedge[c];
                if (wa != wv && stamp[wa] == mark && !is_opposite(wa)) bad = true;
                if (wc != wv && stamp[wc] == mark && !is_opposite(wc)) bad = true;
                // a tetrahedron folds flat: u's triangle (u, a, c) with both a and c opposite
                // would be duplicated by v's (v, a, c) rewritten to u
                if (!bad && y == u && co == 2 && wa != wv && wc != wv && is_opposite(wa) && is_opposite(wc)) {
                    adj.each(v, [&](uint32_t s2) {
                        if (!bad && !contains(s2, u) && contains(s2, a) && contains(s2, c)) bad = true;
                    });
                }
            });
            y = next_copy[y];
        } while (y != u && !bad);
        return bad;
    }

    // f(w) for every corner w of x's live triangles (x among them; a neighbour once per
    // triangle it shares with x)
    template <class Adj, class F>
    void each_corner(const Adj& adj, uint32_t x, F&& f) const {
        adj.each(x, [&](uint32_t t) {
            for (int k = 0; k < 3; ++k) f(idx[3 * t + k]);
        });
    }
    // the same, each distinct corner once (in the order first met; sc's stamps mark them);
    // with g, g(t) for each of x's live triangles t before its corners
    template <class Adj, class F, class G = void (*)(uint32_t)>
    void each_distinct_corner(const Adj& adj, uint32_t x, Scratch& sc, F&& f, G&& g = [](uint32_t) {}) const {
        const uint32_t seen = sc.next_visit();
        adj.each(x, [&](uint32_t t) {
            g(t);
            for (int k = 0; k < 3; ++k) {
                const uint32_t w = idx[3 * t + k];
                if (sc.stamp[w] == seen) continue;
                sc.stamp[w] = seen;
                f(w);
            }
        });
    }

    // starts loading what evaluating v's substitutions reads first
    template <class Adj>
    void prefetch(const Adj& adj, uint32_t v) const {
        if (!quadric.empty()) __builtin_prefetch(&quadric[v]);
        attributes.prefetch(v);
        adj.prefetch(v);
    }

    // the quadric predicate: geometric and attribute error accumulated in v, at u
    float quadric_cost(uint32_t v, uint32_t u) const {
        return float(evaluate(quadric[v], pos[u]) + attributes.accumulated(v, &pos[u].x, u));
    }
    // quadric_cost(v, u) into `cost` when it may beat (bound, bound_u) in the order (cost, u);
    // false when it cannot: both terms are >= 0 and rounding is monotone, so the geometric term
    // alone bounds the sum from below, and the attribute term is skipped (same results)
    bool quadric_cost_within(uint32_t v, uint32_t u, float bound, uint32_t bound_u, float& cost) const {
        const double geometric = evaluate(quadric[v], pos[u]);
        const float lower = float(geometric);
        if (lower > bound || (lower == bound && u > bound_u)) return false;
        cost = float(geometric + attributes.accumulated(v, &pos[u].x, u));
        return true;
    }

    template <class Adj>
    float cost(const Adj& adj, uint32_t v, uint32_t u) const {
        if (predicate == Predicate::quadric) return quadric_cost(v, u);
        // memoryless penalty (TOM paper section 4.1): volume swept by v's triangles, distance x area
        // change, rotation of the surviving triangles (inversion penalty), angle between vertex normals
        const Vec3 pv = pos[v], pu = pos[u];
        const Vec3 d = sub(pu, pv);
        const float dist = length(d);
        float volume = 0, area0 = 0, area1 = 0, rotation = 0;
        double attribute = 0;  // area-weighted squared attribute error of u against v's fields
        adj.each(v, [&](uint32_t t) {
            uint32_t a, b;
            others(t, v, a, b);
            const Vec3 pa = pos[a], pb = pos[b];
            const Vec3 n0 = cross(sub(pa, pv), sub(pb, pv));
            const float l0 = length(n0);
            area0 += 0.5f * l0;
            if (attributes.active()) attribute += 0.5 * l0 * attributes.triangle_error(&pos[0].x, v, a, b, u);
            if (a == u || b == u) return;  // dies
            const Vec3 n1 = cross(sub(pa, pu), sub(pb, pu));
            const float l1 = length(n1);
            area1 += 0.5f * l1;
            volume += std::fabs(dot(d, n0)) * (1.0f / 6.0f);
            if (l0 > 0 && l1 > 0) rotation += 0.5f * l0 * (1.0f - dot(n0, n1) / (l0 * l1));
        });
        const float normal_term = 1.0f - dot(vnormal[v], vnormal[u]);
        // the attribute term in the penalty's units (length^3): RMS attribute error x area
        const float attribute_term = area0 > 0 ? float(std::sqrt(attribute / area0)) * area0 : 0.0f;
        return volume + dist * std::fabs(area1 - area0) + dist * rotation + dist * area0 * 0.5f * normal_term + attribute_term;
    }

    // Best substitution of v, or false when v has none. With check_legal the best *legal* one
    // (cheapest first through the oracle); without, the cheapest by cost alone, to be checked
    // by the caller when it is about to be applied.
    template <class Adj>
    bool best_target(const Adj& adj, uint32_t v, Candidate& best, bool check_legal, Scratch& sc) const {
        if (kind[v] == kLocked || removed[v]) return false;
        if (!check_legal && predicate == Predicate::quadric && kind[v] == kInterior && pairs.empty()) {
            // the common case, in one sweep: each edge neighbour costed as it is met, the cheapest kept
            // an interior vertex's fan is closed and consistently oriented (every edge has one
            // triangle on each side), so each neighbour follows v in exactly one triangle
            bool any = false;
            adj.each(v, [&](uint32_t t) {
                uint32_t u, unused;
                others(t, v, u, unused);
                if (!any) {
                    best = {quadric_cost(v, u), v, u};
                    any = true;
                    return;
                }
                float c;
                if (quadric_cost_within(v, u, best.cost, best.u, c) && (c < best.cost || (c == best.cost && u < best.u))) best = {c, v, u};
            });
            return any;
        }
        std::vector<Candidate>& targets = sc.targets;
        std::vector<uint32_t>& stamp = sc.stamp;
        targets.clear();
        const uint32_t seen = sc.next_visit();
        stamp[v] = seen;
        auto offer = [&](uint32_t u) {
            if (stamp[u] == seen || removed[u]) return;
            stamp[u] = seen;
            if (!border_move_allowed(v, u)) return;
            targets.push_back({0.0f, v, u});
        };
        if (kind[v] == kSeam) {
            for (const uint32_t u : {border_next[v], border_prev[v]}) {
                if (stamp[u] == seen || removed[u]) continue;
                stamp[u] = seen;
                const uint32_t u2 = seam_target(v, u);
                if (u2 == kNone || !border_move_allowed(v, u) || !border_move_allowed(partner[v], u2)) continue;
                targets.push_back({0.0f, v, u});
            }
        } else if (kind[v] == kBorder) {
            offer(border_next[v]);
            offer(border_prev[v]);
        } else {
            adj.each(v, [&](uint32_t t) {
                uint32_t a, b;
                others(t, v, a, b);
                offer(a);
                offer(b);
            });
        }
        if (!pairs.empty())
            for (const uint32_t u : pairs[v])
                if (stamp[u] != seen && !removed[u]) {
                    stamp[u] = seen;
                    targets.push_back({0.0f, v, u});
                }
        if (targets.empty()) return false;
        for (Candidate& c : targets) {
            c.cost = cost(adj, v, c.u);
            if (kind[v] == kSeam) c.cost += cost(adj, partner[v], seam_target(v, c.u));  // both copies move
        }
        if (!check_legal) {
            best = targets[0];
            for (const Candidate& c : targets)
                if (c.cost < best.cost || (c.cost == best.cost && c.u < best.u)) best = c;
            return true;
        }
        // check legality cheapest first; neighbourhoods are small
        std::sort(targets.begin(), targets.end(), [](const Candidate& a, const Candidate& b) {
            return a.cost < b.cost || (a.cost == b.cost && a.u < b.u);
        });
        for (const Candidate& c : targets)
            if (!illegal(adj, v, c.u, sc) && (kind[v] != kSeam || !illegal(adj, partner[v], seam_target(v, c.u), sc))) {
                best = c;
                return true;
            }
        return false;
    }

    // v's geometric and attribute quadrics into u's (v -> u)
    void merge_quadrics(uint32_t u, uint32_t v) {
        add(quadric[u], quadric[v]);
        attributes.merge(u, v);
    }
    // merge i of a list (target, removed), the rows of merge i + 4 loaded meanwhile
    void merge_quadrics(const std::vector<std::pair<uint32_t, uint32_t>>& merges, size_t i) {
        if (i + 4 < merges.size())
            for (const uint32_t x : {merges[i + 4].first, merges[i + 4].second}) {
                __builtin_prefetch(&quadric[x]);
                attributes.prefetch(x);
            }
        merge_quadrics(merges[i].first, merges[i].second);
    }

    // Substitutes v -> u in v's live triangles.
    template <class Adj>
    void apply(const Adj& adj, uint32_t v, uint32_t u) {
        substitute(v, u, [&](auto&& on) { adj.each(v, on); });
    }
    // the same, v's live triangles given (in adjacency order: the foresight's list, while v's fan
    // is as it saw it), so that their reads need not wait for each other along v's corner list
    void apply(uint32_t v, uint32_t u, const uint32_t* triangles, uint32_t count) {
        substitute(v, u, [&](auto&& on) {
            for (uint32_t i = 0; i < count; ++i) on(triangles[i]);
        });
    }
    template <class Fan>
    void substitute(uint32_t v, uint32_t u, Fan&& fan) {
        const uint32_t step = uint32_t(removed_order.size());
        fan([&](uint32_t t) {
            if (contains(t, u)) {
                dead[t] = 1;
                death_step[t] = step;
            } else {
                uint32_t* c = &idx[3 * t];
                for (int k = 0; k < 3; ++k)
                    if (c[k] == v) c[k] = u;
            }
        });
        removed[v] = 1;
        if (!pairs.empty()) {
            for (const uint32_t w : pairs[v]) {
                std::vector<uint32_t>& back = pairs[w];
                back.erase(std::remove(back.begin(), back.end(), v), back.end());
                if (w == u || removed[w]) continue;
                if (std::find(back.begin(), back.end(), u) == back.end()) back.push_back(u);
                if (std::find(pairs[u].begin(), pairs[u].end(), w) == pairs[u].end()) pairs[u].push_back(w);
            }
            pairs[v].clear();
        }
        removed_order.push_back(v);
        removed_target.push_back(u);
        if (predicate == Predicate::quadric) {
            if (deferred_merges)
                deferred_merges->push_back({u, v});
            else
                merge_quadrics(u, v);
        }
        if (kind[v] == kBorder || kind[v] == kSeam) {
            const uint32_t p = border_prev[v], q = border_next[v];
            if (u == q) {
                border_prev[u] = p;
                border_next[p] = u;
            } else if (u == p) {
                border_next[u] = q;
                border_prev[q] = u;
            } else {  // a pair contraction joined this border to another part
                border_next[p] = u;
                border_prev[q] = u;
                if (kind[u] != kLocked) kind[u] = kLocked;
            }
        }
    }
};

// Triangles around each vertex as singly linked corner lists that substitutions splice together.
struct ListAdjacency {
    std::vector<uint32_t> first, last, next;  // first and last corner of a vertex; next corner of the same vertex
    Builder* b = nullptr;
    void build(Builder& builder) {
        b = &builder;
        first.assign(builder.n, kNone);
        last.assign(builder.n, kNone);
        next.assign(size_t(builder.m) * 3, kNone);
        for (uint32_t c = uint32_t(next.size()); c-- > 0;) {
            const uint32_t v = builder.idx[c];
            next[c] = first[v];
            if (first[v] == kNone) last[v] = c;
            first[v] = c;
        }
    }
    template <class F>
    void each(uint32_t v, F&& f) const {
        for (uint32_t c = first[v]; c != kNone; c = next[c])
            if (!b->dead[c / 3]) f(c / 3);
    }
    void prefetch(uint32_t v) const { __builtin_prefetch(&first[v]); }
    // what splice(v, u) reads
    void prefetch_splice(uint32_t v, uint32_t u) const {
        __builtin_prefetch(&last[v]);
        __builtin_prefetch(&first[u], 1);
        __builtin_prefetch(&last[u], 1);
    }
    // the second step, once first[v] is in: v's first corner's triangle and link
    void prefetch_fan(uint32_t v) const {
        const uint32_t c = first[v];
        if (c == kNone) return;
        __builtin_prefetch(&b->idx[c - c % 3]);
        __builtin_prefetch(&next[c]);
    }
    // drops the corners of dead triangles from v's list
    void compact(uint32_t v) {
        uint32_t* link = &first[v];
        uint32_t tail = kNone;
        while (*link != kNone) {
            if (b->dead[*link / 3]) {
                *link = next[*link];
            } else {
                tail = *link;
                link = &next[*link];
            }
        }
        last[v] = tail;
    }
    // moves v's corners to the front of u's list (after v's triangles were rewritten to u), O(1)
    void splice(uint32_t v, uint32_t u) {
        if (first[v] == kNone) return;
        next[last[v]] = first[u];
        if (first[u] == kNone) last[u] = last[v];
        first[u] = first[v];
        first[v] = last[v] = kNone;
    }
};

// A candidate's cost as its bits: non-negative floats order like them.
inline uint32_t cost_bits(const Candidate& c) {
    uint32_t bits;
    std::memcpy(&bits, &c.cost, 4);
    return bits;
}

// Candidates by cost, stable; the team shares a large sort (the same order).
void sort_candidates(std::vector<Candidate>& items, std::vector<Candidate>& tmp, detail::Team& team) {
    detail::radix_sort(items, tmp, 32, [](const Candidate& c) { return cost_bits(c); }, &team);  // (a lambda: inlined)
}

// Splits [0, count) in order: make(i) goes to `first` where which(i) is 1, to `second` where it
// is 2, nowhere where 0. The team counts and then places fixed blocks, so the order is the same
// whatever its size.
template <class T, class Which, class Make>
void split_in_order(detail::Team& team, size_t count, Which&& which, Make&& make, std::vector<T>& first, std::vector<T>& second) {
    constexpr size_t kBlock = 8192;
    std::vector<size_t> place(2 * ((count + kBlock - 1) / kBlock));  // per block: its first places in first and second
    team.blocks(count, kBlock, [&](unsigned, size_t begin, size_t end) {
        size_t ones = 0, twos = 0;
        for (size_t i = begin; i < end; ++i) {
            const int w = which(i);
            ones += w == 1;
            twos += w == 2;
        }
        place[2 * (begin / kBlock)] = ones;
        place[2 * (begin / kBlock) + 1] = twos;
    });
    size_t ones = 0, twos = 0;
    for (size_t k = 0; k < place.size(); k += 2) {
        ones += std::exchange(place[k], ones);
        twos += std::exchange(place[k + 1], twos);
    }
    first.resize(ones);
    second.resize(twos);
    team.blocks(count, kBlock, [&](unsigned, size_t begin, size_t end) {
        size_t one = place[2 * (begin / kBlock)], two = place[2 * (begin / kBlock) + 1];
        for (size_t i = begin; i < end; ++i) {
            const int w = which(i);
            if (w == 1) first[one++] = make(i);
            else if (w == 2) second[two++] = make(i);
        }
    });
}

void classify(Builder& b, const ListAdjacency& adj, BuildStats& stats, bool allow_seams, detail::Team& team) {
    const uint32_t n = b.n;
    b.kind.assign(n, kInterior);
    b.border_next.assign(n, kNone);
    b.border_prev.assign(n, kNone);
    // Per vertex v, from its triangles in order: outs = the vertices following v (its outgoing
    // edges v -> e), ins = those preceding it (incoming w -> v). The multiplicity of the directed
    // edge v -> e is e's count in outs, that of e -> v is e's count in ins: every edge is counted
    // from one vertex's own corners. An edge used twice in a direction (non-manifold, or
    // inconsistently oriented) locks both ends; an edge without its reverse is open.
    // each vertex writes only its own class and border links: blocks of vertices on the team.
    // The counts sit in the worker's array, zero between vertices: tally[2x] = x's count in outs,
    // tally[2x + 1] in ins, held at 2 (only 0, 1 and more than 1 matter)
    std::vector<std::vector<uint32_t>> lists(2 * size_t(team.size()));
    std::vector<std::vector<uint8_t>> tallies(team.size());
    team.blocks(n, 4096, [&](unsigned worker, size_t begin, size_t end) {
        std::vector<uint32_t>& outs = lists[2 * worker];  // of v, in corner order
        std::vector<uint32_t>& ins = lists[2 * worker + 1];
        std::vector<uint8_t>& tally = tallies[worker];
        if (tally.empty()) tally.assign(2 * size_t(n), 0);
        for (uint32_t v = uint32_t(begin); v < uint32_t(end); ++v) {
            outs.clear();
            ins.clear();
            adj.each(v, [&](uint32_t t) {
                uint32_t e, w;
                b.others(t, v, e, w);
                outs.push_back(e);
                ins.push_back(w);
                uint8_t& out_count = tally[2 * size_t(e)];
                uint8_t& in_count = tally[2 * size_t(w) + 1];
                out_count += out_count < 2;
                in_count += in_count < 2;
            });
            const uint32_t valence = uint32_t(outs.size());
            const uint32_t* out = outs.data();
            const uint32_t* in = ins.data();
            uint32_t open_out = 0, open_in = 0;
            bool locked = false;
            // the edge between v and x, x taken from outs (mine = 0) or ins (1): its multiplicity
            // in that direction is x's count there, the reverse's x's count in the other list
            auto edge = [&](uint32_t x, size_t mine, uint32_t& link, uint32_t& open) {
                const uint32_t fwd = tally[2 * size_t(x) + mine], rev = tally[2 * size_t(x) + (1 - mine)];
                if (fwd > 1 || rev > 1) {
                    locked = true;
                } else if (rev == 0) {
                    link = x;
                    ++open;
                }
            };
            for (uint32_t i = 0; i < valence; ++i) {
                edge(out[i], 0, b.border_next[v], open_out);
                edge(in[i], 1, b.border_prev[v], open_in);
            }
            if (locked || !((open_out == 0 && open_in == 0) || (open_out == 1 && open_in == 1)))
                b.kind[v] = kLocked;
            else if (open_out == 1)
                b.kind[v] = kBorder;
            for (uint32_t i = 0; i < valence; ++i) tally[2 * size_t(out[i])] = tally[2 * size_t(in[i]) + 1] = 0;
        }
    });
    // coincident vertices (split by attributes, or duplicated in the input) must not drift apart.
    // An open-addressing table of exact position bits groups them: a group of two border vertices
    // whose border neighbours are coincident too is a seam (the two collapse together); any other
    // group is locked.
    b.partner.assign(n, kNone);
    {
        size_t cap = 16;
        while (cap < size_t(n) * 2) cap *= 2;
        std::vector<uint32_t> table(cap, kNone), first(n, kNone), count(n, 0), second(n, kNone);
        auto same = [&](uint32_t a, uint32_t c) { return std::memcmp(&b.pos[a], &b.pos[c], sizeof(Vec3)) == 0; };
        for (uint32_t v = 0; v < n; ++v) {
            uint32_t bits[3];
            std::memcpy(bits, &b.pos[v], 12);
            uint64_t h = (uint64_t(bits[0]) * 73856093u) ^ (uint64_t(bits[1]) * 19349663u) ^ (uint64_t(bits[2]) * 83492791u);
            h ^= h >> 29;
            h *= 0xbf58476d1ce4e5b9ULL;
            h ^= h >> 32;
            for (size_t i = size_t(h) & (cap - 1);; i = (i + 1) & (cap - 1)) {
                if (table[i] == kNone) {
                    table[i] = v;
                    first[v] = v;
                    count[v] = 1;
                    break;
                }
                if (same(table[i], v)) {
                    first[v] = table[i];
                    if (++count[table[i]] == 2) second[table[i]] = v;
                    break;
                }
            }
        }
        // position classes: the first copy names the class; copies are linked in a circle
        b.wedge.assign(first.begin(), first.end());
        b.next_copy.resize(n);
        {
            std::vector<uint32_t> last(n, kNone);
            for (uint32_t v = 0; v < n; ++v) b.next_copy[v] = v;
            for (uint32_t v = 0; v < n; ++v) {
                const uint32_t r = first[v];
                if (v == r) {
                    last[r] = v;
                    continue;
                }
                b.next_copy[v] = r;          // v closes the circle
                b.next_copy[last[r]] = v;    // after the class's previous copy
                last[r] = v;
            }
        }
        auto pos_eq = [&](uint32_t a, uint32_t c) { return a != kNone && c != kNone && same(a, c); };
        for (uint32_t v = 0; v < n; ++v) {
            const uint32_t r = first[v];
            if (count[r] < 2) continue;
            const uint32_t a = r, c = second[r];
            const bool seam = count[r] == 2 && b.kind[a] == kBorder && b.kind[c] == kBorder &&
                              ((pos_eq(b.border_next[a], b.border_prev[c]) && pos_eq(b.border_prev[a], b.border_next[c])) ||
                               (pos_eq(b.border_next[a], b.border_next[c]) && pos_eq(b.border_prev[a], b.border_prev[c])));
            if (seam && allow_seams) {
                b.kind[v] = kSeam;
                b.partner[v] = v == a ? c : a;
            } else {
                b.kind[v] = kLocked;
            }
        }
    }
    // a border vertex whose loop neighbour is locked keeps its pointers; pointers of locked
    // vertices are never followed from a locked vertex itself
    for (uint32_t v = 0; v < n; ++v) {
        stats.locked_vertices += b.kind[v] == kLocked;
        stats.border_vertices += b.kind[v] == kBorder;
        stats.seam_vertices += b.kind[v] == kSeam;
    }
}

void init_quadrics(Builder& b, detail::Team& team) {
    detail::zero_on_team(team, b.quadric, b.n);
    detail::scatter_by_vertex_range(team, b.n, b.idx.data(), b.m, [&](uint32_t t, uint32_t lo, uint32_t hi) {
        auto mine = [&](uint32_t v) { return v >= lo && v < hi; };
        const uint32_t i0 = b.idx[3 * t], i1 = b.idx[3 * t + 1], i2 = b.idx[3 * t + 2];
        const Vec3 p0 = b.pos[i0], p1 = b.pos[i1], p2 = b.pos[i2];
        Vec3 nrm = cross(sub(p1, p0), sub(p2, p0));
        const float len = length(nrm);
        if (len == 0.0f) return;
        const float area = 0.5f * len;
        nrm = {nrm.x / len, nrm.y / len, nrm.z / len};
        const double d = -double(dot(nrm, p0));
        Quadric q{};
        add_plane(q, nrm.x, nrm.y, nrm.z, d, area);
        for (const uint32_t v : {i0, i1, i2})
            if (mine(v)) add(b.quadric[v], q);
        // open edges: a plane through the edge, perpendicular to the triangle, keeps borders in place
        const uint32_t c[3] = {i0, i1, i2};
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = c[k], e = c[(k + 1) % 3];
            if ((!mine(a) && !mine(e)) || b.border_next[a] != e || b.border_prev[e] != a) continue;
            const Vec3 pa = b.pos[a], pe = b.pos[e];
            const Vec3 edge = sub(pe, pa);
            Vec3 en = cross(edge, nrm);
            const float el = length(en);
            if (el == 0.0f) continue;
            en = {en.x / el, en.y / el, en.z / el};
            Quadric qe{};
            add_plane(qe, en.x, en.y, en.z, -double(dot(en, pa)), kBoundaryWeight * double(dot(edge, edge)));
            if (mine(a)) add(b.quadric[a], qe);
            if (mine(e)) add(b.quadric[e], qe);
        }
    });
}

// Non-edge pairs closer than t, found on a uniform grid of cell size t (at most 8 per vertex).
void find_pairs(Builder& b, float t, BuildStats& stats) {
    if (!(t > 0.0f)) return;
    struct Cell {
        int64_t key;
        uint32_t v;
    };
    std::vector<Cell> cells(b.n);
    auto cell_key = [&](int64_t x, int64_t y, int64_t z) { return (x * 73856093LL) ^ (y * 19349663LL) ^ (z * 83492791LL); };
    auto coord = [&](float x) { return int64_t(std::floor(x / t)); };
    for (uint32_t v = 0; v < b.n; ++v)
        cells[v] = {cell_key(coord(b.pos[v].x), coord(b.pos[v].y), coord(b.pos[v].z)), v};
    std::sort(cells.begin(), cells.end(), [](const Cell& a, const Cell& c) { return a.key < c.key || (a.key == c.key && a.v < c.v); });
    std::vector<std::vector<uint32_t>>& found = b.pairs;
    found.assign(b.n, {});
    const float t2 = t * t;
    for (uint32_t v = 0; v < b.n; ++v) {
        if (b.kind[v] == kLocked) continue;
        const Vec3 p = b.pos[v];
        const int64_t cx = coord(p.x), cy = coord(p.y), cz = coord(p.z);
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const int64_t key = cell_key(cx + dx, cy + dy, cz + dz);
                    auto it = std::lower_bound(cells.begin(), cells.end(), key, [](const Cell& c, int64_t k) { return c.key < k; });
                    for (; it != cells.end() && it->key == key && found[v].size() < 8; ++it) {
                        const uint32_t u = it->v;
                        const Vec3 d = sub(b.pos[u], p);
                        if (u != v && dot(d, d) <= t2) found[v].push_back(u);
                    }
                }
        std::sort(found[v].begin(), found[v].end());
        found[v].erase(std::unique(found[v].begin(), found[v].end()), found[v].end());
    }
    // symmetric: u is v's partner iff v is u's
    for (uint32_t v = 0; v < b.n; ++v)
        for (const uint32_t u : found[v])
            if (std::find(found[u].begin(), found[u].end(), v) == found[u].end()) found[u].push_back(v);
    for (uint32_t v = 0; v < b.n; ++v) {
        std::sort(found[v].begin(), found[v].end());
        stats.pair_candidates += uint32_t(found[v].size());
    }
}

// the top 11 bits below the sign: costs in coarse order
inline uint32_t cost_bucket(const Candidate& c) { return cost_bits(c) >> 21; }

// The candidates of a pass in the order the loop takes them: the cheapest `keep` (at least: whole
// buckets) sorted, then the others in their original order. Sorted in two steps, as the loop
// reaches them: sort_cheapest() sorts the cheapest `first` (at least) to the front of `items` and
// moves the others, in order, to `rest`, returning the last bucket of the cheapest `keep`;
// sort_next(), once the loop has passed the front, appends the rest up to that bucket, sorted,
// and then the others. The same order as one sort (buckets follow costs; equal costs share a
// bucket and keep their order) for the part the loop reaches: bunny00's passes stop after 1.3
// times their quota, while the cheapest 4 x quota are 4.7 times it. Stable, deterministic.
uint32_t sort_cheapest(std::vector<Candidate>& items, size_t first, size_t keep, std::vector<Candidate>& tmp, std::vector<Candidate>& rest,
                       detail::Team& team) {
    std::vector<uint32_t> hists(size_t(team.size()) * 2048, 0);  // per team thread (counts: their sum is the same)
    team.blocks(items.size(), 8192, [&](unsigned worker, size_t begin, size_t end) {
        uint32_t* hist = &hists[size_t(worker) * 2048];
        for (size_t i = begin; i < end; ++i) ++hist[cost_bucket(items[i])];
    });
    uint32_t limit_first = 2047, limit_keep = 2047;
    size_t sum = 0;
    for (uint32_t bucket = 0; bucket < 2048; ++bucket) {
        const size_t before = sum;
        for (unsigned worker = 0; worker < team.size(); ++worker) sum += hists[size_t(worker) * 2048 + bucket];
        if (before < first && sum >= first) limit_first = bucket;
        if (sum >= keep) {
            limit_keep = bucket;
            break;
        }
    }
    limit_first = std::min(limit_first, limit_keep);
    split_in_order(team, items.size(), [&](size_t i) { return cost_bucket(items[i]) <= limit_first ? 1 : 2; }, [&](size_t i) { return items[i]; }, tmp, rest);
    items.swap(tmp);
    sort_candidates(items, tmp, team);
    return limit_keep;
}
void sort_next(std::vector<Candidate>& items, std::vector<Candidate>& rest, uint32_t limit_keep, std::vector<Candidate>& tmp, detail::Team& team) {
    std::vector<Candidate> next, others;
    split_in_order(team, rest.size(), [&](size_t i) { return cost_bucket(rest[i]) <= limit_keep ? 1 : 2; }, [&](size_t i) { return rest[i]; }, next, others);
    sort_candidates(next, tmp, team);
    items.insert(items.end(), next.begin(), next.end());
    items.insert(items.end(), others.begin(), others.end());
    rest.clear();
}

// What the team found out ahead of the sequential loop about one candidate v -> u of a pass.
enum : uint8_t { kLegal, kIllegal, kUnknown };
constexpr uint32_t kRingMax = 15, kChunkMax = 256;
constexpr uint8_t kRingUnknown = 255;
struct Foresight {
    uint8_t verdict;  // the oracle's: kLegal, kIllegal, or kUnknown (not asked)
    uint8_t ring;     // v's neighbours below (when legal, quadric predicate), or kRingUnknown
    uint8_t fan;      // v's live triangles below (the same), or kRingUnknown
    uint32_t w[kRingMax];
    float cost[kRingMax];  // quadric_cost(w[i], u) for an interior w[i] other than u
    uint32_t triangle[kRingMax];
};

// Runs f(i, scratch) for i in [0, count) on the team's threads (the caller's with `own`, each
// helper with its own scratch), in blocks of 16 to 512: eight or more a thread, so that a short
// loop (a late pass, a small mesh) is shared too. f must only write state that belongs to i.
template <class F>
void parallel_for(detail::Team& team, size_t count, Scratch& own, std::vector<Scratch>& helpers, F&& f) {
    const size_t block = std::min<size_t>(512, std::max<size_t>(16, count / (8 * size_t(team.size()))));
    team.blocks(count, block, [&](unsigned worker, size_t begin, size_t end) {
        Scratch& sc = worker == 0 ? own : helpers[worker - 1];
        for (size_t i = begin; i < end; ++i) f(i, sc);
    });
}

// `adj`: the triangles around each vertex, which substitutions splice (nothing is rebuilt
// between passes)
void run_passes(Builder& b, ListAdjacency& adj, float fraction, detail::Team& team, BuildStats& stats) {
    std::vector<uint32_t> live_vertices;
    for (uint32_t v = 0; v < b.n; ++v)
        if (b.kind[v] != kLocked) live_vertices.push_back(v);
    // each vertex's best substitution is kept across passes and recomputed only when its
    // neighbourhood changed (dirty)
    std::vector<Candidate> best(b.n);
    // Costs alone pick a vertex's candidate; the oracle runs when it is applied. A vertex whose
    // cheapest target failed the oracle is evaluated with the oracle from then on (needs_oracle).
    std::vector<uint8_t> has(b.n, 0), dirty(b.n, 1), needs_oracle(b.n, 0);
    std::vector<Candidate> candidates, tmp, rest;
    std::vector<uint32_t> pass_mark(b.n, 0);
    // the vertices to evaluate in a pass are independent: each reads the shared state and writes
    // only its own best[], has[] and dirty[] (results do not depend on the thread count)
    std::vector<uint32_t> evaluate, unused;  // (unused: split_in_order's second list, always empty here)
    std::vector<Scratch> helpers(team.size() - 1);
    for (Scratch& h : helpers) h.stamp.assign(b.n, 0);
    uint32_t alive_count = b.n;
    bool full_rescan_done = false;
    // Foresight (with helpers): before the sequential loop reaches a chunk of candidates, the team
    // takes their oracle verdicts and their neighbours' costs of the target. A substitution applied
    // marks the position classes whose fans it changed (every corner of v's triangles, and u) with
    // the chunk's number: a verdict whose v and u are unmarked is what the oracle would say now. A
    // foreseen cost Q_w(p_u) is used only for a clean w, and a clean w has taken no merge since
    // (a target is dirty from its merge to the next pass). Same substitutions, same files, with
    // the oracle's and the costs' cold reads off the sequential path.
    std::vector<Foresight> foresight(kChunkMax);
    std::vector<std::pair<uint32_t, uint32_t>> merges;  // a chunk's, made with the next foresight
    std::vector<uint32_t> touched(b.n, 0);
    uint32_t chunk = 0;
    // a substitution of x changes its ring: each vertex is looked at again next pass, and the
    // fans of their classes are no longer what the foresight saw
    auto ring_changed = [&](uint32_t x) {
        b.each_corner(adj, x, [&](uint32_t w) {
            dirty[w] = 1;
            touched[b.wedge[w]] = chunk;
        });
    };
    for (uint32_t pass = 1;; ++pass) {
        split_in_order(team, live_vertices.size(), [&](size_t i) { return int(dirty[live_vertices[i]]); }, [&](size_t i) { return live_vertices[i]; }, evaluate, unused);
        // two phases: compaction rewrites v's list, which another vertex's oracle may be walking
        // (each corner is in one list, so compactions do not meet); evaluation only reads lists
        parallel_for(team, evaluate.size(), b.scratch, helpers, [&](size_t i, Scratch&) { adj.compact(evaluate[i]); });
        parallel_for(team, evaluate.size(), b.scratch, helpers, [&](size_t i, Scratch& sc) {
            const uint32_t v = evaluate[i];
            if (i + 8 < evaluate.size()) b.prefetch(adj, evaluate[i + 8]);
            if (i + 4 < evaluate.size()) adj.prefetch_fan(evaluate[i + 4]);
            has[v] = b.best_target(adj, v, best[v], needs_oracle[v] != 0, sc);
            dirty[v] = 0;
        });
        split_in_order(team, live_vertices.size(), [&](size_t i) { return int(has[live_vertices[i]]); }, [&](size_t i) { return best[live_vertices[i]]; }, candidates, rest);
        size_t quota = std::max<size_t>(1, size_t(std::ceil(double(fraction) * alive_count)));
        // independence rejects many candidates: the cheapest 4 x quota are enough to fill a pass
        // (sorted as far as the loop goes: the cheapest 2 x quota first)
        const uint32_t limit_keep = sort_cheapest(candidates, quota * 2, quota * 4, tmp, rest, team);
        size_t executed = 0;
        for (int attempt = 0; attempt < 2 && executed == 0 && !candidates.empty(); ++attempt) {
            if (attempt == 1) {  // nothing went through: try them all, in order
                candidates.insert(candidates.end(), rest.begin(), rest.end());
                rest.clear();
                sort_candidates(candidates, tmp, team);
                quota = candidates.size();
            }
            size_t chunk_begin = 0, chunk_end = 0;
            // a chunk's substitutions touch about 7 classes each: on a small mesh most of the next
            // verdicts would be stale, and their work lost (chunks of at most 1/64 of the mesh)
            const bool ahead = team.size() > 1 && alive_count >= 64 * 32;
            // with the foresight, a chunk's quadric merges are made by the team with the next
            // chunk's foresight (and at the end): a merge's target is dirty from then on, so until
            // the next pass evaluates it nothing reads its quadric (the loop and the foresight
            // read only clean vertices'), and each target takes one merge a pass (pass_mark):
            // the same sums, off the sequential path
            b.deferred_merges = ahead && b.predicate == Predicate::quadric ? &merges : nullptr;
            for (size_t ci = 0; executed < quota; ++ci) {
                if (ci == candidates.size()) {  // past the sorted front
                    if (rest.empty()) break;
                    sort_next(candidates, rest, limit_keep, tmp, team);
                }
                const Candidate& c = candidates[ci];
                if (ci == chunk_end && ahead) {
                    // the oracle's verdicts for the next candidates, on the team, from the state
                    // as it is now (a chunk of about what the quota still needs)
                    ++chunk;
                    chunk_begin = ci;
                    const size_t length = std::min({size_t(kChunkMax), size_t(alive_count / 64), std::max<size_t>(32, (quota - executed) * 5 / 4)});
                    chunk_end = std::min(candidates.size(), ci + length);
                    const size_t pending = merges.size();
                    parallel_for(team, pending + (chunk_end - chunk_begin), b.scratch, helpers, [&](size_t i, Scratch& sc) {
                        if (i < pending) {
                            b.merge_quadrics(merges, i);
                            return;
                        }
                        const size_t k = i - pending;
                        // the reads of the candidates a little ahead started now (the chunk's
                        // vertices lie anywhere in the mesh: its cost order, not its layout)
                        if (chunk_begin + k + 8 < chunk_end) b.prefetch(adj, candidates[chunk_begin + k + 8].v);
                        if (chunk_begin + k + 4 < chunk_end) adj.prefetch_fan(candidates[chunk_begin + k + 4].v);
                        const Candidate& e = candidates[chunk_begin + k];
                        Foresight& f = foresight[k];
                        f.verdict = kUnknown;
                        f.ring = f.fan = kRingUnknown;
                        if (pass_mark[e.v] == pass || pass_mark[e.u] == pass || b.kind[e.v] == kSeam || b.removed[e.u]) return;
                        f.verdict = b.illegal(adj, e.v, e.u, sc) ? kIllegal : kLegal;
                        if (f.verdict == kIllegal || b.predicate != Predicate::quadric) return;
                        // v's triangles, its neighbours (their corners but v) and, for the interior ones, Q_w(p_u)
                        uint32_t ring = 0, fan = 0;
                        b.each_distinct_corner(adj, e.v, sc, [&](uint32_t w) {
                            if (w == e.v) return;
                            if (ring < kRingMax) {
                                f.w[ring] = w;
                                f.cost[ring] = 0.0f;  // (the loop uses it only for an interior w other than u that has a best and is clean)
                                // what the loop compares with w's best; where even the geometric
                                // term cannot beat that best, +inf (the loop's test fails as with
                                // the full cost: a best only falls within a pass, dirty stays
                                // dirty), and w's attribute quadric is not read
                                if (w != e.u && b.kind[w] == kInterior && has[w] && !dirty[w] &&
                                    !b.quadric_cost_within(w, e.u, best[w].cost, best[w].u, f.cost[ring]))
                                    f.cost[ring] = std::numeric_limits<float>::infinity();
                            }
                            ++ring;
                        }, [&](uint32_t t) {
                            if (fan < kRingMax) f.triangle[fan] = t;
                            ++fan;
                        });
                        if (ring <= kRingMax) f.ring = uint8_t(ring);
                        if (fan <= kRingMax) f.fan = uint8_t(fan);
                    });
                    merges.clear();
                }
                if (ci + 4 < candidates.size()) {
                    b.prefetch(adj, candidates[ci + 4].v);
                    adj.prefetch_splice(candidates[ci + 4].v, candidates[ci + 4].u);
                }
                if (ci + 2 < candidates.size()) {
                    const Foresight* next = ahead && ci + 2 < chunk_end ? &foresight[ci + 2 - chunk_begin] : nullptr;
                    if (next && next->fan != kRingUnknown) {  // its triangles' corners at once, not down its list
                        for (uint32_t i = 0; i < next->fan; ++i) {
                            const size_t t = next->triangle[i];
                            __builtin_prefetch(&b.idx[3 * t], 1);
                            __builtin_prefetch(&b.dead[t], 1);
                            __builtin_prefetch(&b.death_step[t], 1);
                        }
                        if (next->ring != kRingUnknown)
                            for (uint32_t i = 0; i < next->ring; ++i) {
                                const uint32_t w = next->w[i];
                                __builtin_prefetch(&best[w], 1);
                                __builtin_prefetch(&dirty[w], 1);
                                __builtin_prefetch(&has[w]);
                                __builtin_prefetch(&b.kind[w]);
                                __builtin_prefetch(&b.wedge[w]);
                                __builtin_prefetch(&touched[w], 1);  // (its class's mark: w's own but for coincident copies)
                            }
                    } else {
                        adj.prefetch_fan(candidates[ci + 2].v);
                    }
                }
                if (pass_mark[c.v] == pass || pass_mark[c.u] == pass) continue;
                if (b.kind[c.v] == kSeam) {
                    // both copies move, each to the copy of the target on its side
                    const uint32_t v2 = b.partner[c.v], u2 = b.seam_target(c.v, c.u);
                    if (b.removed[c.v] || b.removed[c.u] || v2 == kNone || u2 == kNone || pass_mark[v2] == pass || pass_mark[u2] == pass ||
                        !b.border_move_allowed(c.v, c.u) || !b.border_move_allowed(v2, u2) || b.illegal(adj, c.v, c.u, b.scratch) || b.illegal(adj, v2, u2, b.scratch)) {
                        dirty[c.v] = 1;
                        needs_oracle[c.v] = 1;
                        continue;
                    }
                    for (const uint32_t x : {c.v, c.u, v2, u2}) ring_changed(x);
                    b.pair_steps.push_back(uint32_t(b.removed_order.size()));
                    b.apply(adj, c.v, c.u);
                    adj.splice(c.v, c.u);
                    b.apply(adj, v2, u2);
                    adj.splice(v2, u2);
                    b.partner[c.u] = u2;  // the targets are the seam's copies from now on
                    b.partner[u2] = c.u;
                    pass_mark[c.v] = pass_mark[c.u] = pass_mark[v2] = pass_mark[u2] = pass;
                    executed += 2;
                    continue;
                }
                // a verdict taken for this chunk holds while nothing applied since has touched
                // the fans the oracle reads: those of v's and u's position classes
                const uint8_t known = ahead && touched[b.wedge[c.v]] != chunk && touched[b.wedge[c.u]] != chunk ? foresight[ci - chunk_begin].verdict : uint8_t(kUnknown);
                if (b.removed[c.u] || !b.border_move_allowed(c.v, c.u) || (known == kUnknown ? b.illegal(adj, c.v, c.u, b.scratch) : known == kIllegal)) {
                    dirty[c.v] = 1;  // look again next pass, through the oracle
                    needs_oracle[c.v] = 1;
                    continue;
                }
                const Foresight* listed = nullptr;  // the foresight's list of v's triangles, when it holds
                // costs that change: u's (its quadric grows) and those of v's neighbours, whose
                // target v becomes u; legality elsewhere is re-checked when applied
                if (b.predicate == Predicate::quadric) {
                    // a neighbour w keeps its candidate unless that was v; it gains u as a target,
                    // whose cost Q_w(p_u) is one evaluation (the team's, while w's quadric is as it was)
                    auto neighbour = [&](uint32_t w, const float* foreseen) {
                        if (w == c.v || w == c.u || dirty[w] || b.kind[w] == kLocked) return;
                        if (!has[w] || best[w].u == c.v || b.kind[w] != kInterior) {  // borders, seams: look again
                            dirty[w] = 1;
                            return;
                        }
                        float cw;
                        if (foreseen) {
                            cw = *foreseen;
                        } else if (!b.quadric_cost_within(w, c.u, best[w].cost, best[w].u, cw)) {
                            return;
                        }
                        if (cw < best[w].cost || (cw == best[w].cost && c.u < best[w].u)) best[w] = {cw, w, c.u};
                    };
                    const Foresight* f = known == kLegal ? &foresight[ci - chunk_begin] : nullptr;
                    if (f && f->fan != kRingUnknown) listed = f;
                    if (f && f->ring != kRingUnknown) {
                        touched[b.wedge[c.v]] = chunk;
                        for (uint32_t i = 0; i < f->ring; ++i) {
                            touched[b.wedge[f->w[i]]] = chunk;
                            neighbour(f->w[i], &f->cost[i]);
                        }
                    } else {
                        b.each_distinct_corner(adj, c.v, b.scratch, [&](uint32_t w) {
                            touched[b.wedge[w]] = chunk;
                            neighbour(w, nullptr);
                        });
                    }
                    dirty[c.u] = 1;
                } else {
                    ring_changed(c.v);
                }
                touched[b.wedge[c.u]] = chunk;  // a pair target gains v's fan
                if (listed)
                    b.apply(c.v, c.u, listed->triangle, listed->fan);
                else
                    b.apply(adj, c.v, c.u);
                adj.splice(c.v, c.u);
                pass_mark[c.v] = pass_mark[c.u] = pass;
                ++executed;
            }
            parallel_for(team, merges.size(), b.scratch, helpers, [&](size_t i, Scratch&) { b.merge_quadrics(merges, i); });
            merges.clear();
            b.deferred_merges = nullptr;
        }
        if (executed == 0) {
            // cached verdicts can be stale two rings away: one full re-evaluation before stopping
            if (full_rescan_done) break;
            full_rescan_done = true;
            std::fill(dirty.begin(), dirty.end(), 1);
            std::fill(needs_oracle.begin(), needs_oracle.end(), 1);
            continue;
        }
        full_rescan_done = false;
        ++stats.passes;
        alive_count -= uint32_t(executed);
        split_in_order(team, live_vertices.size(), [&](size_t i) { return int(!b.removed[live_vertices[i]]); }, [&](size_t i) { return live_vertices[i]; }, evaluate, unused);
        live_vertices.swap(evaluate);
    }
}

void run_heap(Builder& b, ListAdjacency& adj) {
    struct Entry {
        float cost;
        uint32_t v, u, stamp;
        bool operator<(const Entry& o) const {  // std heap is a max-heap: invert
            return cost > o.cost || (cost == o.cost && v > o.v);
        }
    };
    std::vector<Entry> heap;
    std::vector<uint32_t> stamp(b.n, 0);
    heap.reserve(b.n * 2);
    auto evaluate_vertex = [&](uint32_t v) {
        ++stamp[v];
        Candidate c;
        if (b.best_target(adj, v, c, true, b.scratch)) {
            heap.push_back({c.cost, v, c.u, stamp[v]});
            std::push_heap(heap.begin(), heap.end());
        }
    };
    for (uint32_t v = 0; v < b.n; ++v)
        if (b.kind[v] != kLocked) {
            Candidate c;
            if (b.best_target(adj, v, c, true, b.scratch)) heap.push_back({c.cost, v, c.u, stamp[v]});
        }
    std::make_heap(heap.begin(), heap.end());
    std::vector<uint32_t> ring;
    while (!heap.empty()) {
        std::pop_heap(heap.begin(), heap.end());
        const Entry e = heap.back();
        heap.pop_back();
        if (b.removed[e.v] || e.stamp != stamp[e.v]) continue;
        if (b.removed[e.u]) {  // a pair target went away without touching v's triangles
            evaluate_vertex(e.v);
            continue;
        }
        b.apply(adj, e.v, e.u);
        adj.splice(e.v, e.u);
        adj.compact(e.u);
        ring.clear();
        ring.push_back(e.u);
        b.each_distinct_corner(adj, e.u, b.scratch, [&](uint32_t w) {
            if (w != e.u) ring.push_back(w);
        });
        for (uint32_t w : ring) {
            if (b.kind[w] == kLocked) continue;
            adj.compact(w);
            evaluate_vertex(w);
        }
    }
}

// the blocks in which the team shares the set-up's and the output's per-vertex and per-triangle loops
constexpr size_t kRowBlock = 16384;

// dst = src's vertex rows in the given order (row i = src row order[i]) for every stream of
// `from` into the same stream of `to`; positions included. Streams not one row per vertex are
// copied as they are (clean_mesh leaves none).
template <class From, class To>
void gather_vertex_streams(const From& from, To& to, const std::vector<uint32_t>& order, detail::Team& team) {
    auto gather = [&](const std::vector<float>& src, std::vector<float>& dst, size_t width) {
        if (src.size() != order.size() * width) {
            dst = src;
            return;
        }
        dst.resize(src.size());
        team.blocks(order.size(), kRowBlock, [&](unsigned, size_t begin, size_t end) {
            for (size_t i = begin; i < end; ++i) std::memcpy(&dst[i * width], &src[size_t(order[i]) * width], width * sizeof(float));
        });
    };
    gather(from.positions, to.positions, 3);
    std::vector<const std::vector<float>*> sources;
    for_each_attribute_stream(from, [&](const std::vector<float>& values, size_t, const char*) { sources.push_back(&values); });
    size_t stream = 0;
    for_each_attribute_stream(to, [&](std::vector<float>& dst, size_t width, const char*) { gather(*sources[stream++], dst, width); });
}

// The mesh the build runs on: the input with its vertices in Morton order of their positions
// and its triangles ordered by their first-numbered vertex (stable; corners and winding kept).
// Input vertex orders can be arbitrary (bunny00's triangles span 40% of its vertex range at the
// median), and the passes then miss the cache on almost every neighbour's quadric and corner
// list. vertex_old[i] / triangle_old[t]: the input vertex / triangle at position i / t; lo, hi:
// the positions' bounding box (zero for no vertex), which the codes are taken in.
Mesh reorder_for_locality(const Mesh& in, std::vector<uint32_t>& vertex_old, std::vector<uint32_t>& triangle_old, float lo[3], float hi[3],
                          detail::Team& team) {
    const uint32_t n = in.vertex_count(), m = in.triangle_count();
    std::fill(lo, lo + 3, 0.0f);
    std::fill(hi, hi + 3, 0.0f);
    for (uint32_t v = 0; v < n; ++v)
        for (int k = 0; k < 3; ++k) {
            const float x = in.positions[3 * size_t(v) + size_t(k)];
            lo[k] = v ? std::min(lo[k], x) : x;
            hi[k] = v ? std::max(hi[k], x) : x;
        }
    std::vector<uint32_t> code(n);
    vertex_old.resize(n);
    team.blocks(n, kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (uint32_t v = uint32_t(begin); v < uint32_t(end); ++v) {
            uint32_t c = 0;
            for (int k = 0; k < 3; ++k) {
                const float extent = hi[k] - lo[k];
                const float t = extent > 0 ? (in.positions[3 * size_t(v) + size_t(k)] - lo[k]) / extent : 0.0f;
                c |= uint32_t(detail::spread_bits(uint32_t(std::min(1023.0f, std::max(0.0f, t * 1023.0f))))) << k;  // 10 bits: 30 in all
            }
            code[v] = c;
            vertex_old[v] = v;
        }
    });
    // by the 30-bit codes, stable: equal codes keep input order
    {
        std::vector<uint32_t> tmp;
        detail::radix_sort(vertex_old, tmp, 30, [&](uint32_t v) { return code[v]; }, &team);
    }
    std::vector<uint32_t> vertex_new(n);
    team.blocks(n, kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (uint32_t i = uint32_t(begin); i < uint32_t(end); ++i) vertex_new[vertex_old[i]] = i;
    });

    Mesh out;
    out.name = in.name;
    out.material = in.material;
    gather_vertex_streams(in, out, vertex_old, team);
    // triangles by their lowest new vertex (counting sort, stable)
    std::vector<uint32_t> first_vertex(m), start(size_t(n) + 1, 0);
    team.blocks(m, kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (size_t t = begin; t < end; ++t) {
            const uint32_t* c = &in.indices[3 * t];
            first_vertex[t] = std::min(vertex_new[c[0]], std::min(vertex_new[c[1]], vertex_new[c[2]]));
        }
    });
    for (uint32_t t = 0; t < m; ++t) ++start[first_vertex[t] + 1];
    for (uint32_t i = 0; i < n; ++i) start[i + 1] += start[i];
    triangle_old.resize(m);
    for (uint32_t t = 0; t < m; ++t) triangle_old[start[first_vertex[t]]++] = t;
    out.indices.resize(in.indices.size());
    team.blocks(m, kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (size_t t = begin; t < end; ++t)
            for (size_t k = 0; k < 3; ++k) out.indices[3 * t + k] = vertex_new[in.indices[3 * size_t(triangle_old[t]) + k]];
    });
    return out;
}

} // namespace

MeshView TomMesh::view() const noexcept {
    MeshView v;
    v.name = name;
    v.vertex_count = vertex_count();
    v.triangle_count = triangle_count();
    v.min_vertex_count = min_vertex_count;
    v.index_size = 4;
    v.material = material;
    v.positions = positions.data();
    int stream = 0;
    for_each_attribute_stream(*this, [&](const std::vector<float>& values, size_t, const char*) {
        v.*layout::attribute_streams[stream++].view = values.empty() ? nullptr : values.data();
    });
    v.substitute = substitute.data();
    v.triangles = triangles.data();
    v.pair_bits = pair_bits.empty() ? nullptr : pair_bits.data();
    for (int k = 0; k < 3; ++k) v.bounds_min[k] = bounds_min[k], v.bounds_max[k] = bounds_max[k];
    return v;
}

const char* to_string(Predicate p) noexcept { return p == Predicate::quadric ? "quadric" : "memoryless"; }
const char* to_string(Strategy s) noexcept { return s == Strategy::passes ? "passes" : "heap"; }

TomMesh build(const Mesh& input, const BuildParams& params, BuildStats* stats_out) {
    BuildStats stats;
    detail::Team team(thread_count(params.threads));
    std::vector<uint32_t> vertex_old, triangle_old;
    float bounds_min[3], bounds_max[3];
    const Mesh mesh = reorder_for_locality(input, vertex_old, triangle_old, bounds_min, bounds_max, team);
    Builder b;
    b.n = mesh.vertex_count();
    b.m = mesh.triangle_count();
    static_assert(sizeof(Vec3) == 12, "Vec3 must alias xyz floats");
    b.pos = reinterpret_cast<const Vec3*>(mesh.positions.data());
    std::vector<float> normals_storage;
    if (mesh.normals.size() == mesh.positions.size()) {
        b.vnormal = reinterpret_cast<const Vec3*>(mesh.normals.data());
    } else {
        Mesh tmp;
        tmp.positions = mesh.positions;
        tmp.indices = mesh.indices;
        compute_normals(tmp);
        normals_storage.swap(tmp.normals);
        b.vnormal = reinterpret_cast<const Vec3*>(normals_storage.data());
    }
    b.predicate = params.predicate;
    {
        const double c = std::cos(std::min(90.0, std::max(1.0, double(params.max_rotation_degrees))) * 3.14159265358979323846 / 180.0);
        b.min_cos2 = float(c * c);
    }
    b.idx = mesh.indices;
    b.dead.assign(b.m, 0);
    b.removed.assign(b.n, 0);
    b.scratch.stamp.assign(b.n, 0);
    b.death_step.assign(b.m, kNone);
    b.removed_order.reserve(b.n);
    b.removed_target.reserve(b.n);
    // seams collapse in pairs in the passes strategy; the heap strategy and pair contraction
    // keep coincident copies locked
    ListAdjacency adj;  // the triangles around each vertex, from classification to the last substitution
    adj.build(b);
    classify(b, adj, stats, params.strategy == Strategy::passes && !(params.pair_threshold > 0.0f), team);
    if (b.predicate == Predicate::quadric) init_quadrics(b, team);
    b.attributes.init(mesh, params.attribute_weight, b.predicate == Predicate::quadric, team);
    find_pairs(b, params.pair_threshold, stats);

    if (params.strategy == Strategy::heap) {
        run_heap(b, adj);
    } else {
        run_passes(b, adj, std::min(1.0f, std::max(1e-4f, params.pass_fraction)), team, stats);
    }

    // back to the input's numbering
    const uint32_t n = b.n, m = b.m;
    {
        std::vector<uint8_t> removed(n);
        team.blocks(n, kRowBlock, [&](unsigned, size_t begin, size_t end) {
            for (size_t i = begin; i < end; ++i) removed[vertex_old[i]] = b.removed[i];
        });
        b.removed.swap(removed);
        for (uint32_t& v : b.removed_order) v = vertex_old[v];
        for (uint32_t& v : b.removed_target) v = vertex_old[v];
        std::vector<uint32_t> death(m);
        team.blocks(m, kRowBlock, [&](unsigned, size_t begin, size_t end) {
            for (size_t t = begin; t < end; ++t) death[triangle_old[t]] = b.death_step[t];
        });
        b.death_step.swap(death);
    }

    // total order: survivors first (in input order), then removed vertices, last removed first
    const uint32_t removed_count = uint32_t(b.removed_order.size());
    const uint32_t s = n - removed_count;
    std::vector<uint32_t> new_index(n, kNone);
    TomMesh out;
    out.name = input.name;
    out.material = input.material;
    out.min_vertex_count = s;
    out.original_index.resize(n);
    uint32_t next = 0;
    for (uint32_t v = 0; v < n; ++v)
        if (!b.removed[v]) new_index[v] = next++;
    assert(next == s);
    for (uint32_t j = 0; j < removed_count; ++j) new_index[b.removed_order[j]] = n - 1 - j;
    for (uint32_t v = 0; v < n; ++v) out.original_index[new_index[v]] = v;
    out.substitute.resize(n);
    for (uint32_t i = 0; i < s; ++i) out.substitute[i] = i;
    for (uint32_t j = 0; j < removed_count; ++j) out.substitute[n - 1 - j] = new_index[b.removed_target[j]];

    gather_vertex_streams(input, out, out.original_index, team);

    // triangle t is alive at resolution r >= key(t): key = n - step for a triangle killed by
    // substitution `step` (its removed vertex gets index n-1-step), s for the survivors.
    // Counting sort by key, stable in input order.
    std::vector<uint32_t> bucket(n + 2, 0);
    auto key_of = [&](uint32_t t) { return b.death_step[t] == kNone ? s : n - b.death_step[t]; };
    for (uint32_t t = 0; t < m; ++t) ++bucket[key_of(t) + 1];
    for (uint32_t k = 0; k <= n; ++k) bucket[k + 1] += bucket[k];
    out.triangles.resize(size_t(m) * 3);
    out.original_triangle.resize(m);
    for (uint32_t t = 0; t < m; ++t) out.original_triangle[bucket[key_of(t)]++] = t;
    team.blocks(m, kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (size_t slot = begin; slot < end; ++slot)
            for (size_t k = 0; k < 3; ++k) out.triangles[3 * slot + k] = new_index[input.indices[3 * size_t(out.original_triangle[slot]) + k]];
    });

    std::copy(bounds_min, bounds_min + 3, out.bounds_min);
    std::copy(bounds_max, bounds_max + 3, out.bounds_max);
    // a seam collapse removed two vertices at steps j, j + 1: they sit at n-2-j and n-1-j, and
    // no resolution may take one without the other
    if (!b.pair_steps.empty()) {
        out.pair_bits.assign((size_t(n) + 7) / 8, 0);
        for (const uint32_t j : b.pair_steps) {
            const uint32_t i = n - 2 - j;
            out.pair_bits[i / 8] |= uint8_t(1u << (i % 8));
        }
    }
    stats.substitutions = removed_count;
    if (stats_out) *stats_out = stats;
    return out;
}

} // namespace tom
