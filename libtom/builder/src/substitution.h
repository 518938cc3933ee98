#pragma once
// The state of one build and the operations both strategies share: the binary oracle (legal()),
// the fairness predicate (cost()), the choice of a vertex's best substitution and the
// substitution itself. Internal to tom::builder; builder.cpp sets it up, passes.cpp and
// builder.cpp's heap strategy drive it.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "attribute_error.h"
#include "parallel.h"
#include "tom/builder/builder.h"
#include "vec3.h"
#include "platform.h"

namespace tom::build_detail {

using Vec3 = detail::Vec3T<float>;
using detail::cross;
using detail::dot;
using detail::length;
using detail::sub;

// Q(p) = p^T A p + 2 b.p + c, A symmetric (a00 a01 a02 a11 a12 a22): the squared distances of p
// to the planes of the triangles merged into a vertex, each weighted by the square root of its
// triangle's area (meshoptimizer's weight: the error grows linearly with a triangle's size).
// The sum is the cost, not divided by the accumulated weight as meshoptimizer divides it: a move
// is charged for all the surface it displaces, so a large or long part (a roof, a ridge cap, the
// outline of a thin slab) is not given up at the price of a speck. Divided, the two ranked alike,
// and a building's roof lost half its area before 50% of its triangles (assimp's regr01.obj).
struct Quadric {
    double a00, a01, a02, a11, a12, a22, b0, b1, b2, c;
};

inline void add_plane(Quadric& q, double nx, double ny, double nz, double d, double w) {
    q.a00 += w * nx * nx, q.a01 += w * nx * ny, q.a02 += w * nx * nz;
    q.a11 += w * ny * ny, q.a12 += w * ny * nz, q.a22 += w * nz * nz;
    q.b0 += w * nx * d, q.b1 += w * ny * d, q.b2 += w * nz * d;
    q.c += w * d * d;
}

inline void add(Quadric& q, const Quadric& r) {
    q.a00 += r.a00, q.a01 += r.a01, q.a02 += r.a02, q.a11 += r.a11, q.a12 += r.a12, q.a22 += r.a22;
    q.b0 += r.b0, q.b1 += r.b1, q.b2 += r.b2, q.c += r.c;
}

inline double evaluate(const Quadric& q, Vec3 p) {
    const double x = p.x, y = p.y, z = p.z;
    const double r = q.a00 * x * x + q.a11 * y * y + q.a22 * z * z + 2 * (q.a01 * x * y + q.a02 * x * z + q.a12 * y * z) +
                     2 * (q.b0 * x + q.b1 * y + q.b2 * z) + q.c;
    return r > 0 ? r : 0;
}

// A vertex's kind, from classify(): what its neighbourhood lets it do. Kinds are those of the
// mesh welded by position (coincident copies one point): a vertex next to a seam is interior.
enum Kind : uint8_t { kInterior = 0, kBorder = 1, kLocked = 2, kGroup = 3, kCopy = 4, kBorderGroup = 5, kKindCount = 6 };

// The collapse rules of the vertex kinds, read in one place (as meshoptimizer's kCanCollapse).
// Any vertex may be a target; what differs is where a vertex may go.
struct CollapseRule {
    bool moves;         // may be substituted at all (a group: with its copies)
    bool along_border;  // only onto a neighbour on its border loop (or onto a pair partner)
    bool as_group;      // all copies of its point move at once, onto copies of one neighbouring point
};
constexpr CollapseRule kCollapseRules[kKindCount] = {
    {true, false, false},  // interior: onto any edge neighbour
    {true, true, false},   // border: along its loop, so the border keeps its shape
    {false, false, false}, // locked (non-manifold, border corners, copies of a border point): never moves
    {true, false, true},   // group: the first of the coincident copies of an interior point (split by
                           // seams, hard edges, pole fans, or an unindexed file); the copies move
                           // together onto one neighbouring point, so the surface welded by position
                           // stays closed at every resolution
    {false, false, false}, // copy: a group's other copies, moved by it
    {true, true, true},    // border group: the same for a point on an open border, along its loop
};

constexpr uint32_t kNone = UINT32_MAX;
constexpr float kBoundaryWeight = 4.0f;  // border edge planes (x edge length) vs. face planes (x sqrt(area))
// Texture seam edge planes (x edge length), where a sampled TEXCOORD_0 differs across an edge of
// the welded mesh: a seam's copies move together along it, and its planes keep it from cutting
// corners, so the texture on both sides does not slide. Light: hard edges get none (a
// flat-shaded mesh is all hard edges, which must stay free to move).
constexpr float kTextureSeamWeight = 0.25f;
// A substitution that joins two sheets (it fails the link condition: a thin wall's two faces, a
// box's sides, a handle) is legal unless BuildParams::keep_topology, and ranks as if it cost this
// many times more: it is taken where the manifold moves left cost far more (a building's walls
// flatten before its roof folds onto its gables), not instead of a manifold move of about the
// same cost (the scanned meshes keep their levels). A power of two: the penalized cost is exact,
// so the pass can tell a candidate the oracle ranked (passes.cpp, refused()).
constexpr float kJoinPenalty = 8.0f;

struct Candidate {
    float cost;
    uint32_t v, u;
};

// One group substitution: the copies of a point, each onto a copy of the target point.
struct GroupMove {
    static constexpr uint32_t kMaxCopies = 256;  // a point with more copies stays locked
    uint32_t count = 0;
    uint32_t from[kMaxCopies], to[kMaxCopies];
    float cost = 0;
};

// What one thread needs to evaluate substitutions: visit stamps per vertex (deduplication in
// O(1)) and the candidate targets of one vertex.
struct Scratch {
    std::vector<uint32_t> stamp;  // per vertex: the visit that last saw it
    uint32_t visit = 0;
    std::vector<Candidate> targets;
    std::vector<GroupMove> moves;  // best_group_target's, one per target
    std::vector<uint32_t> order;   // best_group_target's targets, cheapest first
    uint32_t next_visit() {
        if (++visit == 0) {  // wrapped: clear and start again
            std::fill(stamp.begin(), stamp.end(), 0u);
            visit = 1;
        }
        return visit;
    }
};

// The current triangles and, per vertex, the singly linked list of its corners, which
// substitutions splice together (nothing is rebuilt between passes).
struct Topology {
    std::vector<uint32_t> idx;         // current corners, rewritten by substitutions
    std::vector<uint8_t> dead;         // per triangle
    std::vector<uint32_t> death_step;  // per triangle: the substitution that killed it, or kNone
    std::vector<uint32_t> first, last, next;  // first and last corner of a vertex; next corner of the same vertex

    void build(uint32_t vertex_count, std::vector<uint32_t> indices) {
        idx = std::move(indices);
        const size_t triangle_count = idx.size() / 3;
        dead.assign(triangle_count, 0);
        death_step.assign(triangle_count, kNone);
        first.assign(vertex_count, kNone);
        last.assign(vertex_count, kNone);
        next.assign(idx.size(), kNone);
        for (uint32_t c = uint32_t(next.size()); c-- > 0;) {
            const uint32_t v = idx[c];
            next[c] = first[v];
            if (first[v] == kNone) last[v] = c;
            first[v] = c;
        }
    }
    // f(t) for each live triangle t around v
    template <class F>
    void each(uint32_t v, F&& f) const {
        for (uint32_t c = first[v]; c != kNone; c = next[c])
            if (!dead[c / 3]) f(c / 3);
    }
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
    void prefetch(uint32_t v) const { tom::detail::prefetch(&first[v]); }
    // what splice(v, u) reads
    void prefetch_splice(uint32_t v, uint32_t u) const {
        tom::detail::prefetch(&last[v]);
        tom::detail::prefetch_write(&first[u]);
        tom::detail::prefetch_write(&last[u]);
    }
    // the second step, once first[v] is in: v's first corner's triangle and link
    void prefetch_fan(uint32_t v) const {
        const uint32_t c = first[v];
        if (c == kNone) return;
        tom::detail::prefetch(&idx[c - c % 3]);
        tom::detail::prefetch(&next[c]);
    }
    // drops the corners of dead triangles from v's list
    void compact(uint32_t v) {
        uint32_t* link = &first[v];
        uint32_t tail = kNone;
        while (*link != kNone) {
            if (dead[*link / 3]) {
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

// Each vertex's kind and the links classify() gives it.
struct VertexClasses {
    std::vector<uint8_t> kind;
    // a border point's loop neighbours, in the welded mesh: position classes (their first
    // copies), held at the class's first copy
    // (on a border, next follows the open edge out; on a chain where parts meet, no direction)
    std::vector<uint32_t> border_next, border_prev;
    std::vector<uint32_t> wedge;       // the position class of a vertex: its first coincident copy
    std::vector<uint32_t> next_copy;   // circular list of a class's copies (a singleton points to itself)

    // point v's loop neighbour other than w
    uint32_t other_link(uint32_t v, uint32_t w) const { return border_next[v] == w ? border_prev[v] : border_next[v]; }
    // points a and e are each other's loop neighbours: their edge is open or a chain
    bool linked(uint32_t a, uint32_t e) const {
        return (border_next[a] == e || border_prev[a] == e) && (border_next[e] == a || border_prev[e] == a);
    }
    // point p's link to `from` now goes to `to`
    void relink(uint32_t p, uint32_t from, uint32_t to) {
        if (border_next[p] == from) border_next[p] = to;
        else if (border_prev[p] == from) border_prev[p] = to;
    }
};

// The mesh's connected pieces (of the surface welded by position) that may vanish whole: each
// small piece's vertices, and the cost of removing it, as the quadric predicate counts (the
// squared half-diagonal of its box: the distance the surface it leaves is from what remains).
struct Pieces {
    std::vector<uint32_t> first;    // per prunable piece: its members in [first[k], first[k + 1])
    std::vector<uint32_t> members;  // vertices, by piece, each piece's lowest first
    std::vector<float> cost;
    std::vector<uint8_t> gone;
    size_t count() const { return cost.size(); }
};

// The best legal target of one vertex, its candidates offered cheapest first: the first one that
// keeps the topology, unless a join (Builder::illegal) costs less even times kJoinPenalty.
struct JoinRanking {
    Candidate best{0.0f, kNone, kNone};  // the winner, or the cheapest join with its cost times the penalty
    // a join's rank from its own cost (exact: the penalty is a power of two), and whether a
    // candidate's cost is that rank (the pass takes a join only from this ranking)
    static float penalized(float cost) { return cost * kJoinPenalty; }
    static bool ranked(float candidate_cost, float own_cost) { return candidate_cost >= penalized(own_cost); }
    // no later (costlier) candidate can win
    bool settled(float cost) const { return best.v != kNone && cost >= best.cost; }
    // a legal candidate; true when it wins (it keeps the topology)
    bool offer(const Candidate& c, bool joins) {
        if (!joins) {
            best = c;
            return true;
        }
        if (best.v == kNone) best = {penalized(c.cost), c.v, c.u};
        return false;
    }
    bool result(Candidate& out) const {
        if (best.v == kNone) return false;
        out = best;
        return true;
    }
};

// Shared state of one build: the mesh, the current triangles, the vertex classes, the costs'
// quadrics and the record of substitutions.
struct Builder {
    uint32_t n = 0, m = 0;
    const Vec3* pos = nullptr;
    const Vec3* vnormal = nullptr;
    Predicate predicate = Predicate::quadric;
    detail::AttributeError attributes;  // the predicates' attribute term (inactive without attributes)
    bool keep_topology = false;  // joins are never legal (BuildParams::keep_topology)
    float min_cos2 = 0.0f;  // cos^2 of the largest rotation a surviving triangle's normal may take (0: flips only)
    Topology topo;
    VertexClasses classes;
    detail::TeamVector<Quadric> quadric;
    // non-edge pairs closer than the threshold, symmetric; a substitution v -> u moves v's pairs
    // to u (Garland-Heckbert), so parts stay joinable after their first vertices are gone
    std::vector<std::vector<uint32_t>> pairs;
    // the record: which vertices went, in order, and where
    std::vector<uint8_t> removed;
    std::vector<uint32_t> removed_order, removed_target;
    // group substitutions: (first step, copies); their steps are one move
    std::vector<std::pair<uint32_t, uint32_t>> group_steps;
    Pieces pieces;  // with Strategy::passes and the quadric predicate; empty otherwise
    // per vertex: its tangent's handedness is negative (a mirrored UV chart); empty without
    // tangents. A seam copy never moves onto a copy of the other handedness: a triangle with both
    // would turn its normal map inside out.
    std::vector<uint8_t> mirrored;
    Scratch scratch;  // the calling thread's; workers bring their own

    // A border loop of three edges cannot lose a vertex (it would fold onto itself).
    // A border vertex moves along its loop, or onto a pair partner (joining two parts).
    bool border_move_allowed(uint32_t v, uint32_t u) const {
        if (!kCollapseRules[classes.kind[v]].along_border) return true;
        const uint32_t wu = classes.wedge[u];
        if (wu != classes.border_next[v] && wu != classes.border_prev[v])
            return !pairs.empty() && std::find(pairs[v].begin(), pairs[v].end(), u) != pairs[v].end();
        return classes.other_link(classes.border_next[v], v) != classes.border_prev[v];
    }

    // The group substitution of v's point onto the point `target` (a class): each copy p goes to
    // the copy of the target it shares a triangle with, or, sharing none, to the copy its cost
    // prefers (a pole's fan onto a seam point: each copy to the side of its texture coordinates).
    // False when a copy shares triangles with two copies of the target (the one left would keep
    // a zero-area triangle), when the target has no copy of its tangent's handedness, or, with
    // check_legal, when the oracle refuses a copy's move.
    bool group_move(uint32_t v, uint32_t target, bool check_legal, GroupMove& move, Scratch& sc, bool* joins = nullptr) const {
        move.count = 0;
        move.cost = 0;
        uint32_t p = v;
        do {
            if (move.count == GroupMove::kMaxCopies) return false;
            uint32_t adjacent = kNone;
            bool twice = false;
            topo.each(p, [&](uint32_t t) {
                for (int k = 0; k < 3; ++k) {
                    const uint32_t w = topo.idx[3 * t + k];
                    if (classes.wedge[w] != target) continue;
                    if (adjacent != kNone && adjacent != w) twice = true;
                    adjacent = w;
                }
            });
            if (twice) return false;
            uint32_t to = adjacent;
            float c = 0;
            if (to != kNone) {
                c = cost(p, to);
            } else {  // the cheapest copy of the target of p's handedness, the first on ties
                uint32_t q = target;
                do {
                    if (mirrored.empty() || mirrored[q] == mirrored[p]) {
                        const float cq = cost(p, q);
                        if (to == kNone || cq < c) to = q, c = cq;
                    }
                    q = classes.next_copy[q];
                } while (q != target);
                if (to == kNone) return false;  // the target has no copy on p's side of a mirror seam
            }
            move.from[move.count] = p;
            move.to[move.count++] = to;
            move.cost += c;
            p = classes.next_copy[p];
        } while (p != v);
        return !check_legal || group_legal(move, sc, joins);
    }
    // The oracle on each copy's move; the link condition, a property of the two points, once.
    bool group_legal(const GroupMove& move, Scratch& sc, bool* joins = nullptr) const {
        for (uint32_t i = 0; i < move.count; ++i)
            if (illegal(move.from[i], move.to[i], sc, i == 0, joins)) return false;
        return true;
    }

    // The binary oracle's geometric and topological tests for v -> u:
    // - no surviving triangle of v flips (or becomes zero-area), nor turns its normal by more
    //   than the maximum rotation (BuildParams::max_rotation_degrees);
    // - u keeps a live triangle: a piece never vanishes through substitutions (a double-sided
    //   triangle is as far as a closed piece goes; pruning removes small pieces whole);
    // - the link condition: every vertex w adjacent to both v and u forms a triangle (v, u, w),
    //   otherwise edges v-w and u-w merge into a non-manifold edge (two sheets join: a thin
    //   wall's faces, a handle's sides); and no rewritten triangle duplicates one of u's (a
    //   closed surface stops at a tetrahedron). A move that fails only these joins sheets: legal
    //   when the caller passes `joins` (set true) and keep_topology is off (kJoinPenalty).
    // All but the first concern the points (position classes) of v and u, the same for every
    // copy: with `points` false only v's own fan is checked (a group's other copies).
    bool illegal(uint32_t v, uint32_t u, Scratch& sc, bool points = true, bool* joins = nullptr) const {
        std::vector<uint32_t>& stamp = sc.stamp;
        const Vec3 pv = pos[v], pu = pos[u];
        uint32_t opposite[8];
        size_t co = 0;
        bool bad = false, join = false, kept = false;  // kept: a triangle of v's or u's point survives
        const uint32_t wv = classes.wedge[v], wu = classes.wedge[u];
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
            const uint32_t wa = classes.wedge[a], wc = classes.wedge[c];
            kept |= wa != wu && wc != wu;
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
        topo.each(v, [&](uint32_t t) {
            if (bad) return;
            uint32_t a, c;
            topo.others(t, v, a, c);
            if (a != u && c != u) {
                // another copy of u's point would stay in a triangle with u: zero area, and a crack
                if (classes.wedge[a] == wu || classes.wedge[c] == wu) {
                    bad = true;
                    return;
                }
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
        for (uint32_t x = classes.next_copy[v]; points && x != v && !bad; x = classes.next_copy[x])
            topo.each(x, [&](uint32_t t) {
                uint32_t a, c;
                topo.others(t, x, a, c);
                link(a, c);
            });
        if (bad || !points) return bad;
        uint32_t y = u;
        do {
            topo.each(y, [&](uint32_t t) {
                if (bad) return;
                uint32_t a, c;
                topo.others(t, y, a, c);
                const uint32_t wa = classes.wedge[a], wc = classes.wedge[c];
                kept |= wa != wv && wc != wv;
                if (join) return;
                if (wa != wv && stamp[wa] == mark && !is_opposite(wa)) join = true;
                if (wc != wv && stamp[wc] == mark && !is_opposite(wc)) join = true;
                // a tetrahedron folds flat: u's point's triangle (u, a, c) with both a and c
                // opposite would be duplicated by v's (v, a, c) rewritten to u (points: a copy of
                // v's point may hold it)
                if (!join && wa != wv && wc != wv && is_opposite(wa) && is_opposite(wc)) {
                    auto holds = [&](uint32_t s2, uint32_t w) {
                        const uint32_t* corner = &topo.idx[3 * s2];
                        return classes.wedge[corner[0]] == w || classes.wedge[corner[1]] == w || classes.wedge[corner[2]] == w;
                    };
                    uint32_t x = v;
                    do {
                        topo.each(x, [&](uint32_t s2) {
                            if (!join && !holds(s2, wu) && holds(s2, wa) && holds(s2, wc)) join = true;
                        });
                        x = classes.next_copy[x];
                    } while (x != v && !join);
                }
            });
            y = classes.next_copy[y];
        } while (y != u && (!join || !kept));
        if (join && (!joins || keep_topology)) return true;
        if (join) *joins = true;
        return !kept;
    }

    // f(w) for every corner w of x's live triangles (x among them; a neighbour once per
    // triangle it shares with x)
    template <class F>
    void each_corner(uint32_t x, F&& f) const {
        topo.each(x, [&](uint32_t t) {
            for (int k = 0; k < 3; ++k) f(topo.idx[3 * t + k]);
        });
    }
    // the same, each distinct corner once (in the order first met; sc's stamps mark them);
    // with g, g(t) for each of x's live triangles t before its corners
    template <class F, class G = void (*)(uint32_t)>
    void each_distinct_corner(uint32_t x, Scratch& sc, F&& f, G&& g = [](uint32_t) {}) const {
        const uint32_t seen = sc.next_visit();
        topo.each(x, [&](uint32_t t) {
            g(t);
            for (int k = 0; k < 3; ++k) {
                const uint32_t w = topo.idx[3 * t + k];
                if (sc.stamp[w] == seen) continue;
                sc.stamp[w] = seen;
                f(w);
            }
        });
    }

    // starts loading what evaluating v's substitutions reads first
    void prefetch(uint32_t v) const {
        if (!quadric.empty()) tom::detail::prefetch(&quadric[v]);
        attributes.prefetch(v);
        topo.prefetch(v);
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

    float cost(uint32_t v, uint32_t u) const {
        if (predicate == Predicate::quadric) return quadric_cost(v, u);
        // memoryless penalty (TOM paper section 4.1): volume swept by v's triangles, distance x area
        // change, rotation of the surviving triangles (inversion penalty), angle between vertex normals
        const Vec3 pv = pos[v], pu = pos[u];
        const Vec3 d = sub(pu, pv);
        const float dist = length(d);
        float volume = 0, area0 = 0, area1 = 0, rotation = 0;
        double attribute = 0;  // area-weighted squared attribute error of u against v's fields
        topo.each(v, [&](uint32_t t) {
            uint32_t a, b;
            topo.others(t, v, a, b);
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
        return volume + dist * std::fabs(area1 - area0) + dist * rotation + dist * area0 * 0.5f * normal_term + attribute_term +
               border_sweep(v, u, dist);
    }

    // A border vertex's move in the memoryless penalty (Lindstrom & Turk's boundary term): its
    // other border edge (w, v) becomes (w, u), sweeping the triangle (w, v, u), 0 along a straight
    // border; that area x the distance, weighted as the quadric's border planes. Without it, a
    // corner of a flat sheet costs little more than the free moves around it and the outline is
    // cut.
    float border_sweep(uint32_t v, uint32_t u, float dist) const {
        if (!kCollapseRules[classes.kind[v]].along_border) return 0.0f;
        const uint32_t wv = classes.wedge[v], wu = classes.wedge[u];
        const uint32_t w = wu == classes.border_next[wv] ? classes.border_prev[wv] : wu == classes.border_prev[wv] ? classes.border_next[wv] : kNone;
        if (w == kNone || w == wu) return 0.0f;
        const Vec3 pw = pos[w];
        return kBoundaryWeight * 0.5f * length(cross(sub(pos[v], pw), sub(pos[u], pw))) * dist;
    }

    // Best substitution of v, or false when v has none. With check_legal the best *legal* one
    // (cheapest first through the oracle); without, the cheapest by cost alone, to be checked
    // by the caller when it is about to be applied.
    bool best_target(uint32_t v, Candidate& best, bool check_legal, Scratch& sc) const {
        const CollapseRule& rule = kCollapseRules[classes.kind[v]];
        if (!rule.moves || removed[v]) return false;
        if (rule.as_group) return best_group_target(v, best, check_legal, sc);
        if (!check_legal && predicate == Predicate::quadric && classes.kind[v] == kInterior && pairs.empty()) {
            // the common case, in one sweep: each edge neighbour costed as it is met, the cheapest kept
            // an interior vertex's fan is closed and consistently oriented (every edge has one
            // triangle on each side), so each neighbour follows v in exactly one triangle
            bool any = false;
            topo.each(v, [&](uint32_t t) {
                uint32_t u, unused;
                topo.others(t, v, u, unused);
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
        if (rule.along_border) {
            // the copies of its loop neighbours (points of the welded mesh) that v's triangles hold
            topo.each(v, [&](uint32_t t) {
                uint32_t a, b;
                topo.others(t, v, a, b);
                for (const uint32_t w : {a, b})
                    if (classes.wedge[w] == classes.border_next[v] || classes.wedge[w] == classes.border_prev[v]) offer(w);
            });
        } else {
            topo.each(v, [&](uint32_t t) {
                uint32_t a, b;
                topo.others(t, v, a, b);
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
        for (Candidate& c : targets) c.cost = cost(v, c.u);
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
        JoinRanking ranking;
        for (const Candidate& c : targets) {
            if (ranking.settled(c.cost)) break;
            bool joins = false;
            if (!illegal(v, c.u, sc, true, &joins) && ranking.offer(c, joins)) break;
        }
        return ranking.result(best);
    }

    // best_target() for a group's first copy v: the neighbouring points (the classes of its copies'
    // triangles' corners), each costed as the sum of its copies' moves (group_move); the target
    // is the point's first copy.
    bool best_group_target(uint32_t v, Candidate& best, bool check_legal, Scratch& sc) const {
        std::vector<Candidate>& targets = sc.targets;
        targets.clear();
        const uint32_t seen = sc.next_visit();
        sc.stamp[v] = seen;
        const bool along_border = kCollapseRules[classes.kind[v]].along_border;
        uint32_t p = v;
        do {
            topo.each(p, [&](uint32_t t) {
                for (int k = 0; k < 3; ++k) {
                    const uint32_t w = classes.wedge[topo.idx[3 * t + k]];
                    if (sc.stamp[w] == seen) continue;
                    sc.stamp[w] = seen;
                    if (!along_border || ((w == classes.border_next[v] || w == classes.border_prev[v]) && border_move_allowed(v, w)))
                        targets.push_back({0.0f, v, w});
                }
            });
            p = classes.next_copy[p];
        } while (p != v);
        // each target's move, costed once; then cheapest first through the oracle
        if (sc.moves.size() < targets.size()) sc.moves.resize(targets.size());
        size_t kept = 0;
        for (const Candidate& c : targets)
            if (group_move(v, c.u, false, sc.moves[kept], sc)) targets[kept] = {sc.moves[kept].cost, v, c.u}, ++kept;
        targets.resize(kept);
        if (targets.empty()) return false;
        sc.order.resize(kept);
        for (uint32_t i = 0; i < kept; ++i) sc.order[i] = i;
        std::sort(sc.order.begin(), sc.order.end(), [&](uint32_t i, uint32_t j) {
            const Candidate &a = targets[i], &b = targets[j];
            return a.cost < b.cost || (a.cost == b.cost && a.u < b.u);
        });
        JoinRanking ranking;
        for (const uint32_t i : sc.order) {
            if (ranking.settled(targets[i].cost)) break;
            bool joins = false;
            if ((!check_legal || group_legal(sc.moves[i], sc, &joins)) && ranking.offer(targets[i], joins)) break;
        }
        return ranking.result(best);
    }

    // v's geometric and attribute quadrics into u's (v -> u); nothing without quadrics
    void merge_quadrics(uint32_t u, uint32_t v) {
        if (predicate != Predicate::quadric) return;
        add(quadric[u], quadric[v]);
        attributes.merge(u, v);
    }
    // merge i of a list (target, removed), the rows of merge i + 4 loaded meanwhile
    void merge_quadrics(const std::vector<std::pair<uint32_t, uint32_t>>& merges, size_t i) {
        if (i + 4 < merges.size())
            for (const uint32_t x : {merges[i + 4].first, merges[i + 4].second}) {
                tom::detail::prefetch(&quadric[x]);
                attributes.prefetch(x);
            }
        merge_quadrics(merges[i].first, merges[i].second);
    }

    // Substitutes v -> u in v's live triangles (those with u die), records it, moves v's pairs and
    // border links to u. The caller merges v's quadrics into u's (merge_quadrics) before u's
    // cost is next read, and splices v's corner list into u's.
    void substitute(uint32_t v, uint32_t u) {
        substitute_over(v, u, [&](auto&& on) { topo.each(v, on); });
    }
    // the same, v's live triangles given (in adjacency order: the foresight's list, while v's fan
    // is as it saw it), so that their reads need not wait for each other along v's corner list
    void substitute_listed(uint32_t v, uint32_t u, const uint32_t* triangles, uint32_t count) {
        substitute_over(v, u, [&](auto&& on) {
            for (uint32_t i = 0; i < count; ++i) on(triangles[i]);
        });
    }
    template <class Fan>
    void substitute_over(uint32_t v, uint32_t u, Fan&& fan) {
        const uint32_t step = uint32_t(removed_order.size());
        fan([&](uint32_t t) {
            if (topo.contains(t, u)) {
                topo.dead[t] = 1;
                topo.death_step[t] = step;
            } else {
                uint32_t* c = &topo.idx[3 * t];
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
        if (kCollapseRules[classes.kind[v]].along_border) {  // (links are points: u's class)
            const uint32_t p = classes.border_prev[v], q = classes.border_next[v], wu = classes.wedge[u];
            if (wu == q || wu == p) {
                const uint32_t far = wu == q ? p : q;
                classes.relink(wu, v, far);
                classes.relink(far, v, wu);
            } else {  // a pair contraction joined this border to another part
                classes.relink(p, v, wu);
                classes.relink(q, v, wu);
                if (classes.kind[u] != kLocked) classes.kind[u] = kLocked;
            }
        }
    }
};
} // namespace tom::build_detail
