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
//   classify vertices: interior (any edge neighbour), border (only along its border loop, or
//   along the chain of edges where parts meet), locked (other non-manifold points, border
//   corners: never removed, may be a target); coincident copies move as groups
//   repeat: pick the legal substitution v1 -> v2 of lowest penalty, rewrite v1's triangles to v2,
//           the ones containing v2 die; record (v1, v2)
//   until no legal substitution is left. Sort: survivors first, then removed vertices from the
//   last removed to the first; triangles by the resolution at which they die.

#include "tom/builder/builder.h"
#include "tom/errors.h"

#include "format_layout.h"
#include "morton.h"
#include "parallel.h"
#include "passes.h"
#include "radix_sort.h"
#include "substitution.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>
#include <cstring>
#include <limits>

namespace tom {

namespace build_detail {
namespace {

using detail::thread_count;

// Each vertex's kind from the edges of its fan in `topo` (n vertices): interior, border (its
// loop neighbours the ends of its two special edges) or locked. An edge is special when it is
// open (no reverse) or non-manifold (used twice in a direction: more than two triangles, or
// sheets of opposite orientation). A vertex with one open edge out and one in is on a border; a
// vertex whose only special edges are two, one of them non-manifold, is on a chain where parts
// meet (a wall standing on a floor, parts of several materials welded by position): each part's
// fan at it runs from one chain edge to the other, so it moves along the chain as a border
// vertex along its loop, and every part keeps meeting the others there. Its links are the two
// chain neighbours, in no particular direction (VertexClasses::other_link). Any other vertex
// with a special edge is locked.
void classify_by_edges(const Topology& topo, uint32_t n, VertexClasses& cl, detail::Team& team) {
    cl.kind.assign(n, kInterior);
    cl.border_next.assign(n, kNone);
    cl.border_prev.assign(n, kNone);
    // Per vertex v, from its triangles in order: outs = the vertices following v (its outgoing
    // edges v -> e), ins = those preceding it (incoming w -> v). The multiplicity of the directed
    // edge v -> e is e's count in outs, that of e -> v is e's count in ins: every edge is counted
    // from one vertex's own corners.
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
            topo.each(v, [&](uint32_t t) {
                uint32_t e, w;
                topo.others(t, v, e, w);
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
            uint32_t open_out = 0, open_in = 0, open_out_to = kNone, open_in_from = kNone;
            uint32_t special[3], specials = 0;  // distinct ends of special edges, up to 3
            bool non_manifold = false;
            // the edge between v and x, x taken from outs (mine = 0) or ins (1): its multiplicity
            // in that direction is x's count there, the reverse's x's count in the other list
            auto edge = [&](uint32_t x, size_t mine) {
                const uint32_t fwd = tally[2 * size_t(x) + mine], rev = tally[2 * size_t(x) + (1 - mine)];
                if (fwd > 1 || rev > 1) {
                    non_manifold = true;
                } else if (rev == 0) {
                    (mine == 0 ? open_out_to : open_in_from) = x;
                    ++(mine == 0 ? open_out : open_in);
                } else {
                    return;
                }
                if (specials < 3 && std::find(special, special + specials, x) == special + specials) special[specials++] = x;
            };
            for (uint32_t i = 0; i < valence; ++i) {
                edge(out[i], 0);
                edge(in[i], 1);
            }
            // (a locked vertex keeps a link along an open edge: its planes in init_quadrics)
            cl.border_next[v] = open_out_to;
            cl.border_prev[v] = open_in_from;
            if (!non_manifold) {
                const bool loop = open_out == 1 && open_in == 1;
                cl.kind[v] = loop ? kBorder : open_out == 0 && open_in == 0 ? kInterior : kLocked;
            } else if (specials == 2) {
                cl.kind[v] = kBorder;
                cl.border_next[v] = special[0];
                cl.border_prev[v] = special[1];
            } else {
                cl.kind[v] = kLocked;
            }
            for (uint32_t i = 0; i < valence; ++i) tally[2 * size_t(out[i])] = tally[2 * size_t(in[i]) + 1] = 0;
        }
    });
}

// A uniform grid of cubes `size` wide, for near-neighbour queries. Cell coordinates are clamped
// to 2^40 so that a far-away vertex or a tiny cell cannot overflow the conversion to integer:
// clamped vertices share edge cells, which costs candidates, never correctness (callers check
// every candidate by distance).
struct Grid {
    double size;
    int64_t coord(float x) const {
        constexpr double kLimit = double(int64_t(1) << 40);
        const double c = std::floor(double(x) / size);
        return int64_t(c > -kLimit ? (c < kLimit ? c : kLimit) : -kLimit);
    }
    // a cell's hash (wrapping in unsigned arithmetic), mixed so that its low bits index a table
    static uint64_t hash(int64_t x, int64_t y, int64_t z) {
        uint64_t h = (uint64_t(x) * 73856093ULL) ^ (uint64_t(y) * 19349663ULL) ^ (uint64_t(z) * 83492791ULL);
        h ^= h >> 29;
        h *= 0xbf58476d1ce4e5b9ULL;
        return h ^ (h >> 32);
    }
};

// Union-find over vertices whose root is a set's lowest vertex: the first copy names a class.
struct FirstCopy {
    std::vector<uint32_t> parent;
    explicit FirstCopy(uint32_t n) : parent(n) {
        for (uint32_t v = 0; v < n; ++v) parent[v] = v;
    }
    uint32_t find(uint32_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    }
    void join(uint32_t a, uint32_t c) {
        a = find(a), c = find(c);
        if (a < c) parent[c] = a;
        else parent[a] = c;
    }
};

// Coincident vertices (split by attributes, duplicated or never indexed in the input) are
// copies of one point: vertices within `tolerance` of each other (object units; 0: the same
// position bits) join one position class. Candidates come from a hash of cells twice the
// tolerance wide: a vertex looks in its own cell and, along each axis, the neighbour on its
// nearer side (8 cells). Returns false when every class has one vertex.
bool find_position_classes(Builder& b, float tolerance) {
    const uint32_t n = b.n;
    VertexClasses& cl = b.classes;
    const Grid grid{tolerance > 0 ? 2.0 * double(tolerance) : 1.0};
    size_t cap = 16;
    while (cap < size_t(n) * 2) cap *= 2;
    struct Slot {
        int64_t x, y, z;
        uint32_t head;  // the cell's last vertex; earlier ones follow next_in_cell
    };
    std::vector<Slot> table(cap, Slot{0, 0, 0, kNone});
    std::vector<uint32_t> next_in_cell(n, kNone);
    auto slot_of = [&](int64_t x, int64_t y, int64_t z) -> Slot& {
        for (size_t i = size_t(Grid::hash(x, y, z)) & (cap - 1);; i = (i + 1) & (cap - 1))
            if (table[i].head == kNone || (table[i].x == x && table[i].y == y && table[i].z == z)) return table[i];
    };
    FirstCopy classes(n);
    const double t2 = double(tolerance) * double(tolerance);
    bool any = false;
    for (uint32_t v = 0; v < n; ++v) {
        const Vec3 p = b.pos[v];
        const int64_t c[3] = {grid.coord(p.x), grid.coord(p.y), grid.coord(p.z)};
        int64_t side[3];
        for (int k = 0; k < 3; ++k) {
            const double f = double((&p.x)[k]) / grid.size - double(c[k]);
            side[k] = f < 0.5 ? -1 : 1;
        }
        for (int corner = 0; corner < 8; ++corner) {
            const int64_t x = c[0] + (corner & 1 ? side[0] : 0), y = c[1] + (corner & 2 ? side[1] : 0), z = c[2] + (corner & 4 ? side[2] : 0);
            const Slot& slot = slot_of(x, y, z);
            for (uint32_t w = slot.head; w != kNone; w = next_in_cell[w]) {
                const Vec3 d = sub(b.pos[w], p);
                const double d2 = double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z;
                if (d2 <= t2) {
                    classes.join(v, w);
                    any = true;
                }
            }
        }
        Slot& own = slot_of(c[0], c[1], c[2]);
        own.x = c[0], own.y = c[1], own.z = c[2];
        next_in_cell[v] = own.head;
        own.head = v;
    }
    // position classes: the first copy names the class; copies are linked in a circle
    cl.wedge.resize(n);
    cl.next_copy.resize(n);
    std::vector<uint32_t> last(n, kNone);
    for (uint32_t v = 0; v < n; ++v) {
        const uint32_t r = cl.wedge[v] = classes.find(v);
        cl.next_copy[v] = r;  // v closes the circle
        if (v != r) cl.next_copy[last[r]] = v;  // after the class's previous copy
        last[r] = v;
    }
    return any;
}

// Kinds and border loops of the mesh welded by position: each class one point. A point with
// several copies is a group (a border group on an open border) when it is manifold there (its
// copies' fans make one disk or half-disk) and no triangle holds two of its copies; otherwise
// its copies are locked. With `allow_groups` false
// (the heap strategy, pair contraction) every point with copies is locked.
void classify_welded(Builder& b, bool allow_groups, detail::Team& team) {
    const uint32_t n = b.n;
    VertexClasses& cl = b.classes;
    std::vector<uint32_t> welded;
    welded.reserve(b.topo.idx.size());
    std::vector<uint8_t> folded(n, 0);  // a triangle holds two copies of the point
    for (size_t t = 0; t < b.topo.idx.size(); t += 3) {
        const uint32_t a = cl.wedge[b.topo.idx[t]], c = cl.wedge[b.topo.idx[t + 1]], d = cl.wedge[b.topo.idx[t + 2]];
        if (a == c || c == d || a == d) {
            folded[a] = folded[c] = folded[d] = 1;
            continue;
        }
        welded.insert(welded.end(), {a, c, d});
    }
    Topology points;
    points.build(n, std::move(welded));
    VertexClasses by_point;
    classify_by_edges(points, n, by_point, team);
    cl.border_next.swap(by_point.border_next);
    cl.border_prev.swap(by_point.border_prev);
    for (uint32_t v = 0; v < n; ++v) {
        const uint32_t r = cl.wedge[v];
        if (cl.next_copy[r] == r) {
            cl.kind[v] = folded[r] ? uint8_t(kLocked) : by_point.kind[r];
            continue;
        }
        uint32_t copies = 0;
        for (uint32_t x = r; copies <= GroupMove::kMaxCopies; x = cl.next_copy[x]) {
            ++copies;
            if (cl.next_copy[x] == r) break;
        }
        const uint8_t point = by_point.kind[r];
        const bool group = allow_groups && !folded[r] && (point == kInterior || point == kBorder) && copies <= GroupMove::kMaxCopies;
        cl.kind[v] = !group ? kLocked : v != r ? kCopy : point == kBorder ? kBorderGroup : kGroup;
    }
}

// The vertex classes: kinds by edges and, where some vertices are copies of one point, by the
// edges of the mesh welded by position. A border vertex whose loop neighbour is locked keeps its
// pointers; pointers of locked vertices are never followed from a locked vertex itself.
void classify(Builder& b, BuildStats& stats, float tolerance, bool allow_groups, bool lock_borders, detail::Team& team) {
    classify_by_edges(b.topo, b.n, b.classes, team);
    if (find_position_classes(b, tolerance)) classify_welded(b, allow_groups, team);
    if (lock_borders) {
        std::vector<uint8_t>& kind = b.classes.kind;
        for (uint32_t v = 0; v < b.n; ++v)  // (a copy after its group's first copy)
            if (kind[v] == kBorder || kind[v] == kBorderGroup || (kind[v] == kCopy && kind[b.classes.wedge[v]] == kLocked)) kind[v] = kLocked;
    }
    for (const uint8_t kind : b.classes.kind) {
        stats.locked_vertices += kind == kLocked;
        stats.border_vertices += kind == kBorder;
        stats.seam_vertices += kind == kGroup || kind == kCopy || kind == kBorderGroup;
    }
}

// The pieces that may be pruned: the connected parts of the mesh welded by position whose box's
// diagonal is at most half the mesh's (never the one with the most triangles: a mesh never
// vanishes), each removable whole at the cost of its squared diagonal (about as far as its
// surface can be from what is left) over its triangles' quadric weights, the sum a quadric
// charges (meshoptimizer's meshopt_simplifyPrune removes such pieces too). A piece goes when
// that is cheaper than what remains: specks early, a building's planks near the end, instead of
// folding each into a sheet. (A smaller cost lets a character's large pieces go too early; a
// smaller size bound keeps a building's floor high.)
void find_pieces(Builder& b, float mesh_diagonal) {
    const uint32_t n = b.n;
    FirstCopy piece(n);
    for (uint32_t v = 0; v < n; ++v) piece.join(v, b.classes.wedge[v]);
    for (size_t c = 0; c < b.topo.idx.size(); c += 3) {
        piece.join(b.topo.idx[c], b.topo.idx[c + 1]);
        piece.join(b.topo.idx[c], b.topo.idx[c + 2]);
    }
    std::vector<uint32_t> root(n), triangles(n, 0);
    uint32_t count = 0;
    for (uint32_t v = 0; v < n; ++v) count += (root[v] = piece.find(v)) == v;
    if (count < 2) return;
    std::vector<double> weight(n, 0.0);  // per piece (at its root): its triangles' quadric weights
    for (size_t c = 0; c < b.topo.idx.size(); c += 3) {
        const uint32_t r = root[b.topo.idx[c]];
        ++triangles[r];
        const Vec3 p0 = b.pos[b.topo.idx[c]];
        weight[r] += detail::quadric_weight(0.5 * double(length(cross(sub(b.pos[b.topo.idx[c + 1]], p0), sub(b.pos[b.topo.idx[c + 2]], p0)))));
    }
    uint32_t largest = 0;
    for (uint32_t v = 0; v < n; ++v)
        if (root[v] == v && triangles[v] > triangles[largest]) largest = v;
    // members by piece, pieces in the order of their first members
    std::vector<uint32_t> index(n, kNone);
    Pieces& p = b.pieces;
    std::vector<double> piece_weight;
    for (uint32_t v = 0; v < n; ++v)
        if (root[v] == v && v != root[largest]) index[v] = uint32_t(p.cost.size()), p.cost.push_back(0.0f), piece_weight.push_back(weight[v]);
    p.first.assign(p.count() + 1, 0);
    for (uint32_t v = 0; v < n; ++v)
        if (index[root[v]] != kNone) ++p.first[index[root[v]] + 1];
    for (size_t k = 0; k < p.count(); ++k) p.first[k + 1] += p.first[k];
    p.members.resize(p.first.back());
    std::vector<uint32_t> next(p.first.begin(), p.first.end() - 1);
    std::vector<float> lo(3 * p.count(), std::numeric_limits<float>::max()), hi(3 * p.count(), -std::numeric_limits<float>::max());
    for (uint32_t v = 0; v < n; ++v) {
        const uint32_t k = index[root[v]];
        if (k == kNone) continue;
        p.members[next[k]++] = v;
        for (int a = 0; a < 3; ++a) lo[3 * k + a] = std::min(lo[3 * k + a], (&b.pos[v].x)[a]), hi[3 * k + a] = std::max(hi[3 * k + a], (&b.pos[v].x)[a]);
    }
    p.gone.assign(p.count(), 0);
    for (size_t k = 0; k < p.count(); ++k) {
        double d2 = 0;
        for (int a = 0; a < 3; ++a) d2 += double(hi[3 * k + a] - lo[3 * k + a]) * double(hi[3 * k + a] - lo[3 * k + a]);
        p.cost[k] = float(d2 * piece_weight[k]);
        p.gone[k] = d2 > double(mesh_diagonal) * mesh_diagonal / 4;  // too large: never a candidate
    }
}

// Edge (a, e) of triangle t is a texture seam: the mesh welded by position has another triangle
// on it (it is no border), and there the copies of a or e have other texture coordinates.
bool texture_seam(const Builder& b, const float* uv, uint32_t t, uint32_t a, uint32_t e) {
    // without copies of a or e, the triangle across is on a and e themselves: no seam (most edges)
    if (b.classes.next_copy[a] == a && b.classes.next_copy[e] == e) return false;
    const uint32_t we = b.classes.wedge[e];
    auto differs = [&](uint32_t x, uint32_t y) { return uv[2 * size_t(x)] != uv[2 * size_t(y)] || uv[2 * size_t(x) + 1] != uv[2 * size_t(y) + 1]; };
    uint32_t a2 = a;
    do {
        for (uint32_t c = b.topo.first[a2]; c != kNone; c = b.topo.next[c]) {
            const uint32_t t2 = c / 3;
            if (t2 == t) continue;
            for (int k = 0; k < 3; ++k) {
                const uint32_t x = b.topo.idx[3 * size_t(t2) + size_t(k)];
                if (x != a2 && b.classes.wedge[x] == we && (differs(a, a2) || differs(e, x))) return true;
            }
        }
        a2 = b.classes.next_copy[a2];
    } while (a2 != a);
    return false;
}

void init_quadrics(Builder& b, const float* texcoords, detail::Team& team) {
    detail::zero_on_team(team, b.quadric, b.n);
    detail::scatter_by_vertex_range(team, b.n, b.topo.idx.data(), b.m, [&](uint32_t t, uint32_t lo, uint32_t hi) {
        auto mine = [&](uint32_t v) { return v >= lo && v < hi; };
        const uint32_t i0 = b.topo.idx[3 * t], i1 = b.topo.idx[3 * t + 1], i2 = b.topo.idx[3 * t + 2];
        const Vec3 p0 = b.pos[i0], p1 = b.pos[i1], p2 = b.pos[i2];
        Vec3 nrm = cross(sub(p1, p0), sub(p2, p0));
        const float len = length(nrm);
        if (len == 0.0f) return;
        const double weight = detail::quadric_weight(0.5 * double(len));
        nrm = {nrm.x / len, nrm.y / len, nrm.z / len};
        const double d = -double(dot(nrm, p0));
        Quadric q{};
        add_plane(q, nrm.x, nrm.y, nrm.z, d, weight);
        for (const uint32_t v : {i0, i1, i2})
            if (mine(v)) add(b.quadric[v], q);
        // open and chain edges, and texture seams: a plane through the edge, perpendicular to the
        // triangle, keeps borders, the chains where parts meet and (lighter) seams in place
        const uint32_t c[3] = {i0, i1, i2};
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = c[k], e = c[(k + 1) % 3];
            const uint32_t pa_ = b.classes.wedge[a], pe_ = b.classes.wedge[e];  // open in the welded mesh
            if (!mine(a) && !mine(e)) continue;
            double edge_weight = kBoundaryWeight;
            if (!b.classes.linked(pa_, pe_)) {
                if (!texcoords || !texture_seam(b, texcoords, t, a, e)) continue;
                edge_weight = kTextureSeamWeight;
            }
            const Vec3 pa = b.pos[a], pe = b.pos[e];
            const Vec3 edge = sub(pe, pa);
            Vec3 en = cross(edge, nrm);
            const float el = length(en);
            if (el == 0.0f) continue;
            en = {en.x / el, en.y / el, en.z / el};
            Quadric qe{};
            add_plane(qe, en.x, en.y, en.z, -double(dot(en, pa)), edge_weight * double(length(edge)));
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
    const Grid grid{double(t)};
    auto cell_key = [](int64_t x, int64_t y, int64_t z) { return int64_t(Grid::hash(x, y, z)); };
    auto coord = [&](float x) { return grid.coord(x); };
    for (uint32_t v = 0; v < b.n; ++v)
        cells[v] = {cell_key(coord(b.pos[v].x), coord(b.pos[v].y), coord(b.pos[v].z)), v};
    std::sort(cells.begin(), cells.end(), [](const Cell& a, const Cell& c) { return a.key < c.key || (a.key == c.key && a.v < c.v); });
    std::vector<std::vector<uint32_t>>& found = b.pairs;
    found.assign(b.n, {});
    const float t2 = t * t;
    for (uint32_t v = 0; v < b.n; ++v) {
        if (b.classes.kind[v] == kLocked) continue;
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

void run_heap(Builder& b) {
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
        if (b.best_target(v, c, true, b.scratch)) {
            heap.push_back({c.cost, v, c.u, stamp[v]});
            std::push_heap(heap.begin(), heap.end());
        }
    };
    for (uint32_t v = 0; v < b.n; ++v)
        if (kCollapseRules[b.classes.kind[v]].moves) {
            Candidate c;
            if (b.best_target(v, c, true, b.scratch)) heap.push_back({c.cost, v, c.u, stamp[v]});
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
        b.substitute(e.v, e.u);
        b.merge_quadrics(e.u, e.v);
        b.topo.splice(e.v, e.u);
        b.topo.compact(e.u);
        ring.clear();
        ring.push_back(e.u);
        b.each_distinct_corner(e.u, b.scratch, [&](uint32_t w) {
            if (w != e.u) ring.push_back(w);
        });
        for (uint32_t w : ring) {
            if (!kCollapseRules[b.classes.kind[w]].moves) continue;
            b.topo.compact(w);
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

// vertex_new: the inverse of the permutation vertex_old
std::vector<uint32_t> inverse_order(const std::vector<uint32_t>& vertex_old, detail::Team& team) {
    std::vector<uint32_t> vertex_new(vertex_old.size());
    team.blocks(vertex_old.size(), kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) vertex_new[vertex_old[i]] = uint32_t(i);
    });
    return vertex_new;
}

// The local order of the triangles `indices` (input numbering): by their lowest new vertex
// (vertex_new: input vertex -> local), a counting sort, stable. Returns local -> input triangle.
// Cheap to make again, so the build keeps it only while it needs it.
std::vector<uint32_t> local_triangle_order(const std::vector<uint32_t>& indices, const std::vector<uint32_t>& vertex_new, detail::Team& team) {
    const size_t m = indices.size() / 3, n = vertex_new.size();
    std::vector<uint32_t> first_vertex(m), start(n + 1, 0);
    team.blocks(m, kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (size_t t = begin; t < end; ++t) {
            const uint32_t* c = &indices[3 * t];
            first_vertex[t] = std::min(vertex_new[c[0]], std::min(vertex_new[c[1]], vertex_new[c[2]]));
        }
    });
    for (size_t t = 0; t < m; ++t) ++start[first_vertex[t] + 1];
    for (size_t i = 0; i < n; ++i) start[i + 1] += start[i];
    std::vector<uint32_t> triangle_old(m);
    for (uint32_t t = 0; t < uint32_t(m); ++t) triangle_old[start[first_vertex[t]]++] = t;
    return triangle_old;
}

// The mesh the build runs on: the input with its vertices in Morton order of their positions
// and its triangles ordered by their first-numbered vertex (local_triangle_order; corners and
// winding kept). Input vertex orders can be arbitrary (a triangle's corners far apart in the
// vertex range), and the passes would then miss the cache on almost every neighbour's quadric
// and corner list. vertex_old[i]: the input vertex at position i; lo, hi: the positions'
// bounding box (zero for no vertex), which the codes are taken in.
Mesh reorder_for_locality(const Mesh& in, std::vector<uint32_t>& vertex_old, float lo[3], float hi[3], detail::Team& team) {
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
    code = std::vector<uint32_t>();
    const std::vector<uint32_t> vertex_new = inverse_order(vertex_old, team);

    Mesh out;
    out.name = in.name;
    out.material = in.material;
    gather_vertex_streams(in, out, vertex_old, team);
    const std::vector<uint32_t> triangle_old = local_triangle_order(in.indices, vertex_new, team);
    out.indices.resize(in.indices.size());
    team.blocks(m, kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (size_t t = begin; t < end; ++t)
            for (size_t k = 0; k < 3; ++k) out.indices[3 * t + k] = vertex_new[in.indices[3 * size_t(triangle_old[t]) + k]];
    });
    return out;
}

// The input reordered for locality, with what maps it back.
struct LocalMesh {
    Mesh mesh;
    std::vector<uint32_t> vertex_old;  // local vertex -> input's (the triangles' map is made again at the end)
    bool sole_copy = false;            // the input's vertex streams are gone: the output takes these
    float bounds_min[3], bounds_max[3];
    std::vector<float> normals;  // vertex normals computed for the memoryless predicate, when the mesh has none
};

// The builder's state for `local`: positions, normals, the current triangles, the predicate's
// parameters and the record's storage.
void set_up(Builder& b, LocalMesh& local, const BuildParams& params) {
    const Mesh& mesh = local.mesh;
    b.n = mesh.vertex_count();
    b.m = mesh.triangle_count();
    static_assert(sizeof(Vec3) == 12, "Vec3 must alias xyz floats");
    b.pos = reinterpret_cast<const Vec3*>(mesh.positions.data());
    if (mesh.normals.size() == mesh.positions.size()) {
        b.vnormal = reinterpret_cast<const Vec3*>(mesh.normals.data());
    } else {
        Mesh tmp;
        tmp.positions = mesh.positions;
        tmp.indices = mesh.indices;
        compute_normals(tmp);
        local.normals.swap(tmp.normals);
        b.vnormal = reinterpret_cast<const Vec3*>(local.normals.data());
    }
    b.predicate = params.predicate;
    const double c = std::cos(std::min(90.0, std::max(1.0, double(params.max_rotation_degrees))) * 3.14159265358979323846 / 180.0);
    b.min_cos2 = float(c * c);
    b.keep_topology = params.keep_topology;
    if (mesh.tangents.size() == size_t(b.n) * 4) {
        b.mirrored.resize(b.n);
        for (uint32_t v = 0; v < b.n; ++v) b.mirrored[v] = mesh.tangents[4 * size_t(v) + 3] < 0.0f;
    }
    b.topo.build(b.n, mesh.indices);  // the triangles around each vertex, from classification to the last substitution
    b.removed.assign(b.n, 0);
    b.scratch.stamp.assign(b.n, 0);
    b.removed_order.reserve(b.n);  // reserved: grown by doubling, a large build's would end at up to twice this
    b.removed_target.reserve(b.n);
}

float diagonal_of(const LocalMesh& local) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += double(local.bounds_max[k] - local.bounds_min[k]) * double(local.bounds_max[k] - local.bounds_min[k]);
    return float(std::sqrt(d2));
}

// BuildParams::copy_tolerance in object units: a share of the bounding box's diagonal.
float copy_tolerance(const LocalMesh& local, const BuildParams& params) {
    return float(std::max(0.0, double(params.copy_tolerance)) * double(diagonal_of(local)));
}

// What the substitutions no longer read goes before they run: the local copy's triangles (the
// topology holds its own) and, unless they are the only copy, its vertex streams other than
// normals (the attribute term holds its scaled values); its positions and normals stay (the
// predicates read them). 12 bytes a triangle of the build's peak, and more with texture
// coordinates or colours.
void release_input_copy(LocalMesh& local) {
    std::vector<uint32_t>().swap(local.mesh.indices);
    if (local.sole_copy) return;
    for_each_attribute_stream(local.mesh, [](std::vector<float>& values, size_t, const char* name) {
        if (std::string_view(name) != "normal") std::vector<float>().swap(values);
    });
}

// A moved-in input's vertex streams go once the local copy holds them: 12 bytes a triangle of
// the peak with normals alone (the input keeps its triangles, which the output is ordered by).
void release_input_streams(Mesh& input, LocalMesh& local) {
    std::vector<float>().swap(input.positions);
    for_each_attribute_stream(input, [](std::vector<float>& values, size_t, const char*) { std::vector<float>().swap(values); });
    local.sole_copy = true;
}

// The quadrics (about 270 bytes a vertex with normals) go before the output is assembled.
void release_costs(Builder& b) {
    detail::TeamVector<Quadric>().swap(b.quadric);
    b.attributes.release();
}

// The record and the triangles' deaths back in the input's numbering (vertex_new: the inverse
// of local.vertex_old; triangles: the input's).
void to_input_numbering(Builder& b, const LocalMesh& local, const std::vector<uint32_t>& vertex_new, const std::vector<uint32_t>& triangles,
                        detail::Team& team) {
    std::vector<uint8_t> removed(b.n);
    team.blocks(b.n, kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) removed[local.vertex_old[i]] = b.removed[i];
    });
    b.removed.swap(removed);
    for (uint32_t& v : b.removed_order) v = local.vertex_old[v];
    for (uint32_t& v : b.removed_target) v = local.vertex_old[v];
    const std::vector<uint32_t> triangle_old = local_triangle_order(triangles, vertex_new, team);
    std::vector<uint32_t> death(b.m);
    team.blocks(b.m, kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (size_t t = begin; t < end; ++t) death[triangle_old[t]] = b.topo.death_step[t];
    });
    b.topo.death_step.swap(death);
}

// The total order of the vertices: survivors first (in input order), then the removed ones,
// last removed first; new_index maps the input's vertices into it.
void order_vertices(const Builder& b, TomMesh& out, std::vector<uint32_t>& new_index) {
    const uint32_t n = b.n, removed_count = uint32_t(b.removed_order.size()), s = n - removed_count;
    out.min_vertex_count = s;
    new_index.assign(n, kNone);
    uint32_t next = 0;
    for (uint32_t v = 0; v < n; ++v)
        if (!b.removed[v]) new_index[v] = next++;
    assert(next == s);
    for (uint32_t j = 0; j < removed_count; ++j) new_index[b.removed_order[j]] = n - 1 - j;
    out.original_index.resize(n);
    for (uint32_t v = 0; v < n; ++v) out.original_index[new_index[v]] = v;
    out.substitute.resize(n);
    for (uint32_t i = 0; i < s; ++i) out.substitute[i] = i;
    for (uint32_t j = 0; j < removed_count; ++j) out.substitute[n - 1 - j] = new_index[b.removed_target[j]];
}

// The output's vertex streams: the input's rows in the total order, from the local copy when
// it is the only one (vertex_new: input vertex -> local).
void gather_output_streams(const Mesh& input, const LocalMesh& local, const std::vector<uint32_t>& vertex_new, TomMesh& out, detail::Team& team) {
    if (!local.sole_copy) {
        gather_vertex_streams(input, out, out.original_index, team);
        return;
    }
    std::vector<uint32_t> order(out.original_index.size());
    team.blocks(order.size(), kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) order[i] = vertex_new[out.original_index[i]];
    });
    gather_vertex_streams(local.mesh, out, order, team);
}

// The triangles by the resolution at which they die: triangle t is alive at resolution
// r >= key(t), key = n - step for a triangle killed by substitution `step` (its removed vertex
// gets index n-1-step), s for the survivors. Counting sort by key, stable in input order; with
// parts, then by part (stable), so each part's range is sorted by death on its own.
// input_bits: the input's attribute_bits (its streams may be gone by now).
void order_triangles(const Builder& b, const Mesh& input, uint32_t input_bits, const std::vector<uint32_t>& new_index, TomMesh& out,
                     detail::Team& team) {
    const uint32_t n = b.n, m = b.m, s = out.min_vertex_count;
    const std::vector<uint32_t>& death = b.topo.death_step;
    std::vector<uint32_t> bucket(n + 2, 0);
    auto key_of = [&](uint32_t t) { return death[t] == kNone ? s : n - death[t]; };
    for (uint32_t t = 0; t < m; ++t) ++bucket[key_of(t) + 1];
    for (uint32_t k = 0; k <= n; ++k) bucket[k + 1] += bucket[k];
    out.triangles.resize(size_t(m) * 3);
    out.original_triangle.resize(m);
    for (uint32_t t = 0; t < m; ++t) out.original_triangle[bucket[key_of(t)]++] = t;
    if (!input.parts.empty()) {
        std::vector<uint32_t> part_of(m), start(input.parts.size() + 1, 0), by_part(m);
        for (uint32_t p = 0; p < input.parts.size(); ++p) {
            const Part& part = input.parts[p];
            for (uint32_t t = part.first_triangle; t < part.first_triangle + part.triangle_count; ++t) part_of[t] = p;
            start[p + 1] = start[p] + part.triangle_count;
        }
        for (const uint32_t t : out.original_triangle) by_part[start[part_of[t]]++] = t;
        out.original_triangle.swap(by_part);
        out.parts = input.parts;  // same ranges: each part keeps its triangle count
        for (Part& part : out.parts) part.attributes &= input_bits;  // a stream may have been dropped since import
    }
    team.blocks(m, kRowBlock, [&](unsigned, size_t begin, size_t end) {
        for (size_t slot = begin; slot < end; ++slot)
            for (size_t k = 0; k < 3; ++k) out.triangles[3 * slot + k] = new_index[input.indices[3 * size_t(out.original_triangle[slot]) + k]];
    });
}

// A group collapse removed k copies at steps j .. j + k - 1: they sit at n-j-k .. n-1-j, and no
// resolution may take some without the others (bits n-j-k .. n-j-2: each joins i and i + 1).
void mark_groups(const Builder& b, TomMesh& out) {
    if (b.group_steps.empty()) return;
    out.pair_bits.assign((size_t(b.n) + 7) / 8, 0);
    for (const auto& [j, k] : b.group_steps)
        for (uint32_t i = b.n - j - k; i + 1 < b.n - j; ++i) out.pair_bits[i / 8] |= uint8_t(1u << (i % 8));
}

} // namespace
} // namespace build_detail

using namespace build_detail;

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
    v.parts = parts.empty() ? nullptr : parts.data();
    v.part_count = uint32_t(parts.size());
    for (int k = 0; k < 3; ++k) v.bounds_min[k] = bounds_min[k], v.bounds_max[k] = bounds_max[k];
    return v;
}

const char* to_string(Predicate p) noexcept { return p == Predicate::quadric ? "quadric" : "memoryless"; }
const char* to_string(Strategy s) noexcept { return s == Strategy::passes ? "passes" : "heap"; }

// The total order's one rule every later step relies on (each walk `while (v >= n) v = s[v]`
// ends): a substitute comes before its vertex. Broken only by a defect here; a loop forever
// would be worse than this error.
static void check_order(const TomMesh& out) {
    for (uint32_t i = out.min_vertex_count; i < out.vertex_count(); ++i)
        if (out.substitute[i] >= i)
            throw InternalError("tom::build: mesh '" + out.name + "': vertex " + std::to_string(i) + " has substitute " + std::to_string(out.substitute[i]) +
                                   ", not an earlier vertex (a defect of the builder)");
}

// Carried streams in another vertex order: element i of `to` is element order[i] of `from`.
static std::vector<VertexStream> gather_extra_streams(const std::vector<VertexStream>& from, const std::vector<uint32_t>& order) {
    std::vector<VertexStream> to;
    for (const VertexStream& x : from) {
        VertexStream y{x.name, x.component_type, x.components, x.normalized, std::vector<uint8_t>(x.data.size())};
        const size_t bytes = x.element_bytes();
        for (size_t i = 0; i < order.size(); ++i) std::memcpy(&y.data[i * bytes], &x.data[size_t(order[i]) * bytes], bytes);
        to.push_back(std::move(y));
    }
    return to;
}

// The build of `input`; with `owned` (== &input, moved in by the caller) its vertex streams are
// freed once the local copy holds them, and the output comes from that copy: the same bytes.
static TomMesh build_from(const Mesh& input, Mesh* owned, const BuildParams& params, BuildStats* stats_out) {
    BuildStats stats;
    detail::Team team(thread_count(params.threads));
    const uint32_t input_bits = attribute_bits(input);
    LocalMesh local;
    local.mesh = reorder_for_locality(input, local.vertex_old, local.bounds_min, local.bounds_max, team);
    detail::AnimationChannels animation = detail::AnimationChannels::of(input, params.animation_weight, local.vertex_old);
    if (owned) release_input_streams(*owned, local);
    Builder b;
    set_up(b, local, params);

    // coincident copies move as groups in the passes strategy; the heap strategy and pair
    // contraction keep them locked (pair contraction takes only exact copies: it joins near ones)
    classify(b, stats, params.pair_threshold > 0.0f ? 0.0f : copy_tolerance(local, params), params.strategy == Strategy::passes && !(params.pair_threshold > 0.0f), params.lock_borders,
             team);
    const bool weigh_texcoords = params.weigh_texcoords && !local.mesh.texcoords.empty();
    if (b.predicate == Predicate::quadric) init_quadrics(b, weigh_texcoords ? local.mesh.texcoords.data() : nullptr, team);
    // (not with locked borders: a tile's pieces all meet its neighbours)
    if (b.predicate == Predicate::quadric && params.strategy == Strategy::passes && !(params.pair_threshold > 0.0f) && !params.lock_borders)
        find_pieces(b, diagonal_of(local));
    b.attributes.init(local.mesh, params.attribute_weight, params.weigh_texcoords, animation, b.predicate == Predicate::quadric, team);
    animation = {};
    find_pairs(b, params.pair_threshold, stats);
    release_input_copy(local);

    if (params.strategy == Strategy::heap)
        run_heap(b);
    else
        run_passes(b, std::min(1.0f, std::max(1e-4f, params.pass_fraction)), params.foresight, team, stats, params.progress);
    release_costs(b);

    const std::vector<uint32_t> vertex_new = inverse_order(local.vertex_old, team);
    to_input_numbering(b, local, vertex_new, input.indices, team);
    TomMesh out;
    out.name = input.name;
    out.material = input.material;
    std::vector<uint32_t> new_index;
    order_vertices(b, out, new_index);
    check_order(out);
    gather_output_streams(input, local, vertex_new, out, team);
    out.extra_streams = gather_extra_streams(input.extra_streams, out.original_index);
    order_triangles(b, input, input_bits, new_index, out, team);
    std::copy(local.bounds_min, local.bounds_min + 3, out.bounds_min);
    std::copy(local.bounds_max, local.bounds_max + 3, out.bounds_max);
    mark_groups(b, out);

    stats.substitutions = uint32_t(b.removed_order.size());
    if (stats_out) *stats_out = stats;
    return out;
}

TomMesh build(const Mesh& input, const BuildParams& params, BuildStats* stats_out) { return build_from(input, nullptr, params, stats_out); }

TomMesh build(Mesh&& input, const BuildParams& params, BuildStats* stats_out) {
    TomMesh out = build_from(input, &input, params, stats_out);
    input = Mesh();  // moved from: left empty, whatever the build freed
    return out;
}

Mesh original_mesh(const TomMesh& tom) {
    const uint32_t n = tom.vertex_count(), m = tom.triangle_count();
    if (tom.original_index.size() != n || tom.original_triangle.size() != m)
        throw ArgumentError("tom::original_mesh: mesh '" + tom.name + "' has no map to its input (only a TomMesh from build() has one)");
    for (const uint32_t v : tom.original_index)
        if (v >= n) throw ArgumentError("tom::original_mesh: mesh '" + tom.name + "': original_index is not a permutation");
    Mesh mesh;
    mesh.name = tom.name;
    mesh.material = tom.material;
    detail::Team team(1);
    const std::vector<uint32_t> new_index = inverse_order(tom.original_index, team);  // input vertex v is sorted vertex new_index[v]
    gather_vertex_streams(tom, mesh, new_index, team);
    mesh.extra_streams = gather_extra_streams(tom.extra_streams, new_index);
    mesh.indices.resize(size_t(m) * 3);
    for (uint32_t slot = 0; slot < m; ++slot) {
        const uint32_t t = tom.original_triangle[slot];
        if (t >= m) throw ArgumentError("tom::original_mesh: mesh '" + tom.name + "': original_triangle is not a permutation");
        for (size_t k = 0; k < 3; ++k) {
            const uint32_t c = tom.triangles[3 * size_t(slot) + k];
            if (c >= n) throw ArgumentError("tom::original_mesh: mesh '" + tom.name + "': a triangle's corner is past the vertices");
            mesh.indices[3 * size_t(t) + k] = tom.original_index[c];
        }
    }
    mesh.parts = tom.parts;  // the same ranges: each part's triangles keep their place and count
    return mesh;
}

} // namespace tom
