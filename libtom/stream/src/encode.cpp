// Writing streamed .tom files (docs/FORMAT.md, "Streamed files"): an ordinary .tom's meshes cut
// into chunks of resolution, quantized, predicted and compressed with meshoptimizer's codecs.

#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "format_layout.h"
#include "points.h"
#include "scene_codec.h"
#include "stream_layout.h"
#include "stream_order.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/stream/stream_file.h"

namespace tom {

namespace {

using namespace stream_layout;
using layout::store_f32;
using layout::store_u32;
using layout::store_u64;

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
}

/// A mesh's values on the stream's grids, one array per stream (as the decoder rebuilds them).
struct Quantized {
    StreamQuantization q;
    std::vector<uint16_t> positions;  // 3 per vertex
    std::vector<int16_t> normals;     // 2 per vertex
    std::vector<uint16_t> texcoords[2];
    std::vector<uint8_t> colors;      // 4 per vertex
    std::vector<int16_t> tangents;    // 3 per vertex: octahedral pair, w
};

using Planes = std::array<double, 6>;  // a sum of n n^T: xx, xy, xz, yy, yz, zz

/// Adds the plane of triangle (a, b, c) of `m`, weighted by its area, to `q`.
void add_plane(Planes& q, const MeshView& m, uint32_t a, uint32_t b, uint32_t c) {
    const float *p0 = m.positions + 3 * size_t(a), *p1 = m.positions + 3 * size_t(b), *p2 = m.positions + 3 * size_t(c);
    const double e1[3] = {double(p1[0]) - p0[0], double(p1[1]) - p0[1], double(p1[2]) - p0[2]};
    const double e2[3] = {double(p2[0]) - p0[0], double(p2[1]) - p0[1], double(p2[2]) - p0[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double twice_area = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(twice_area > 0)) return;
    const double w = 0.5 / twice_area;  // area * unit n n^T = (n n^T) / (2 |n|)
    const Planes add{n[0] * n[0] * w, n[0] * n[1] * w, n[0] * n[2] * w, n[1] * n[1] * w, n[1] * n[2] * w, n[2] * n[2] * w};
    for (int j = 0; j < 6; ++j) q[j] += add[j];
}

/// `q` scaled to trace 1 (left 0 when 0).
Planes unit_trace(Planes q) {
    const double trace = q[0] + q[3] + q[5];
    if (trace > 0)
        for (double& x : q) x /= trace;
    return q;
}

/// The resolutions chunks end at: the first holding `first_share` of the vertices and of the
/// triangles at least (and the survivors), each next `growth` times the last, none inside a group
/// of copies, the last V.
std::vector<uint32_t> chunk_ends(const MeshView& m, const StreamOptions& o) {
    std::vector<uint32_t> ends;
    const uint32_t V = m.vertex_count;
    if (V == 0) return ends;
    double target = std::max<double>({double(m.min_vertex_count), std::ceil(o.first_share * V),
                                      double(vertex_count_for_triangles(m, uint32_t(std::ceil(o.first_share * m.triangle_count)), Floor::coarsest)), 1.0});
    while (true) {
        uint32_t b = m.whole_groups_above(uint32_t(std::min<double>(target, V)));
        if (!ends.empty() && b <= ends.back()) b = m.whole_groups_above(ends.back() + 1);
        ends.push_back(b);
        if (b >= V) break;
        target = std::max(double(b) * o.growth, double(b) + 16);
    }
    return ends;
}

/// The residuals of vertices [a, b) against their predictions (stream_layout::prediction), each
/// element `lanes` values of T padded to `element` bytes, zigzag-coded or in byte form with the
/// lanes summed (stream_layout::residual_to_bytes): what the decoder adds back.
template <class T>
std::vector<uint8_t> residuals(const std::vector<T>& values, const MeshView& m, const std::vector<std::vector<uint32_t>>* rings, uint32_t a, uint32_t b,
                               int lanes, uint32_t element, bool byte_form) {
    std::vector<uint8_t> out(size_t(b - a) * element, 0);
    for (uint32_t v = a; v < b; ++v) {
        const std::vector<uint32_t>* ring = rings && v >= m.min_vertex_count ? &(*rings)[v - m.min_vertex_count] : nullptr;
        T base[4];
        prediction(values.data(), lanes, v, m.substitute_at(v), ring ? ring->data() : nullptr, ring ? ring->size() : 0, base);
        for (int k = 0; k < lanes; ++k) {
            const T r = T(values[size_t(v) * lanes + k] - base[k]);
            uint8_t* at = &out[size_t(v - a) * element + k * sizeof(T)];
            if (byte_form) {
                residual_to_bytes(r, at);
            } else {
                const T z = zigzag(r);
                std::memcpy(at, &z, sizeof(T));
            }
        }
    }
    if (byte_form) sum_lanes(out.data(), b - a, element, element);
    return out;
}

void put_vertex_block(std::vector<uint8_t>& out, const std::vector<uint8_t>& elements, size_t count, size_t size) {
    std::vector<uint8_t> encoded(meshopt_encodeVertexBufferBound(count, size));
    encoded.resize(meshopt_encodeVertexBuffer(encoded.data(), encoded.size(), elements.data(), count, size));
    put_u32(out, uint32_t(encoded.size()));
    out.insert(out.end(), encoded.begin(), encoded.end());
}

/// The index codec may rotate a triangle's corners (it keeps the winding); a rotation block
/// after it says, per triangle, by how much to turn the decoded corners back (0 to 2, four
/// triangles to a 4-byte element), or is empty when none turned.
void put_index_block(std::vector<uint8_t>& out, const uint32_t* corners, size_t count, uint32_t vertex_count) {
    std::vector<uint8_t> encoded(meshopt_encodeIndexBufferBound(count, vertex_count));
    encoded.resize(meshopt_encodeIndexBuffer(encoded.data(), encoded.size(), corners, count));
    put_u32(out, uint32_t(encoded.size()));
    out.insert(out.end(), encoded.begin(), encoded.end());
    std::vector<uint32_t> decoded(count);
    if (meshopt_decodeIndexBuffer(decoded.data(), count, sizeof(uint32_t), encoded.data(), encoded.size()) != 0)
        throw InternalError("encode_stream: meshoptimizer does not decode the index block it encoded");
    std::vector<uint8_t> turns((count / 3 + 3) / 4 * 4, 0);
    bool any = false;
    for (size_t t = 0; t < count / 3; ++t) {
        const uint32_t* d = &decoded[3 * t];
        const uint32_t* o = corners + 3 * t;
        uint8_t r = 0;
        while (r < 3 && !(d[r] == o[0] && d[(r + 1) % 3] == o[1] && d[(r + 2) % 3] == o[2])) ++r;
        if (r == 3) throw InternalError("encode_stream: meshoptimizer's index codec changed a triangle beyond a rotation");
        turns[t] = r;
        any = any || r != 0;
    }
    if (any) {
        put_vertex_block(out, turns, turns.size() / rotation_element, rotation_element);
    } else {
        put_u32(out, 0);
    }
}

/// Bits, least significant first, as the decoder's reader takes them.
struct BitWriter {
    std::vector<uint8_t> bytes;
    uint64_t bits = 0;
    void put(uint32_t value, uint32_t n) {
        for (uint32_t i = 0; i < n; ++i, ++bits) {
            if (bits % 8 == 0) bytes.push_back(0);
            if (value >> i & 1u) bytes.back() |= uint8_t(1u << (bits % 8));
        }
    }
    /// Elias gamma code of n >= 1: as many zeros as n has bits after its leading one, a one,
    /// then those bits.
    void gamma(uint32_t n) {
        uint32_t width = 0;
        while (width < 31 && (n >> (width + 1))) ++width;
        put(0, width);
        put(1, 1);
        put(n, width);
    }
};

/// What the decoder reads for the split of vertex v (docs/FORMAT.md, "Streamed files").
struct Split {
    uint32_t p = 0;
    std::vector<bool> moves;            // over p's live corners in order before the split: 1 = becomes v
    std::vector<uint32_t> born_count;   // per part
    struct Born {
        uint8_t order;
        uint8_t predicted;  // the orientation the live triangles predict (predicted_orientation)
        uint32_t index;     // among the candidates; their count: an escape, then x
        uint32_t x;
        bool escape;
    };
    std::vector<Born> born;             // part by part, in file order
    uint32_t common = 0;                // candidates that share a triangle with both p and v
};

/// A mesh's connectivity as the stream codes it: the triangles live at the coarsest resolution
/// S (per part, corners mapped to S) and every vertex's split, found by removing the vertices
/// from the finest down, as the order defines.
struct Connectivity {
    std::vector<std::vector<uint32_t>> base;  // per part
    std::vector<Split> splits;                // vertex S + i
    std::vector<std::vector<uint32_t>> rings;  // vertex S + i: its neighbours just after its split, ascending
};

/// The mesh's Connectivity, and in `born_planes` every vertex's triangles' planes at the
/// coarsest level it is in (what quantize_mesh needs; the chunks do not).
Connectivity connectivity(const MeshView& m, std::vector<Planes>& born_planes) {
    const uint32_t V = m.vertex_count, S = m.min_vertex_count, T = m.triangle_count, P = part_count(m);
    std::vector<uint32_t> cur(3 * size_t(T)), part_of(T), alive_count(P);
    for (size_t c = 0; c < cur.size(); ++c) cur[c] = m.corner(uint32_t(c));
    for (uint32_t q = 0; q < P; ++q) {
        const Part part = part_at(m, q);
        for (uint32_t t = 0; t < part.triangle_count; ++t) part_of[part.first_triangle + t] = q;
        alive_count[q] = part.triangle_count;
    }
    std::vector<std::vector<uint32_t>> incident(V);
    for (size_t g = 0; g < cur.size(); ++g) incident[cur[g]].push_back(uint32_t(g));
    std::vector<uint8_t> alive(T, 1);
    const auto triangle = [&](uint32_t g) { return &cur[3 * size_t(g / 3)]; };
    auto prune = [&](std::vector<uint32_t>& list) { list.erase(std::remove_if(list.begin(), list.end(), [&](uint32_t g) { return !alive[g / 3]; }), list.end()); };
    Connectivity out;
    Seen seen;
    seen.cover(V);
    out.splits.resize(V - S);
    out.rings.resize(V - S);
    born_planes.assign(V, Planes{0, 0, 0, 0, 0, 0});
    for (uint32_t v = V; v-- > S;) {
        Split& s = out.splits[v - S];
        const uint32_t p = m.substitute_at(v);
        s.p = p;
        // born at v + 1: the live triangles holding both v and p, each part's last ones
        prune(incident[v]);
        gather_neighbours(incident[v], triangle, v, v, seen, out.rings[v - S]);
        for (uint32_t g : incident[v]) {
            const uint32_t* c = triangle(g);
            add_plane(born_planes[v], m, c[0], c[1], c[2]);
        }
        std::vector<uint32_t> born;
        for (uint32_t g : incident[v]) {
            const uint32_t* c = &cur[3 * size_t(g / 3)];
            if (c[0] == p || c[1] == p || c[2] == p) born.push_back(g / 3);
        }
        std::sort(born.begin(), born.end());
        s.born_count.assign(P, 0);
        for (uint32_t t : born) ++s.born_count[part_of[t]];
        for (uint32_t q = 0, k = 0; q < P; ++q)
            for (uint32_t i = 0; i < s.born_count[q]; ++i, ++k)
                if (born[k] != part_at(m, q).first_triangle + alive_count[q] - s.born_count[q] + i)
                    throw ArgumentError("encode_stream: mesh '" + std::string(m.name) + "' triangle " + std::to_string(born[k]) + " is born out of order (not a TOM order)");
        for (uint32_t q = 0; q < P; ++q) alive_count[q] -= s.born_count[q];
        for (uint32_t t : born) alive[t] = 0;
        prune(incident[v]);
        prune(incident[p]);
        // the candidates for x: the other corners of the triangles around p and v once v is split
        std::vector<uint32_t> candidates;
        if (!born.empty()) {
            std::vector<uint32_t> around[2];
            gather_neighbours(incident[p], triangle, p, v, seen, around[0]);
            gather_neighbours(incident[v], triangle, p, v, seen, around[1]);
            s.common = uint32_t(order_candidates(around[0], around[1], candidates));
        }
        // p's live corners as the decoder holds them at each born triangle: p's side, then the
        // split's born triangles before it
        std::vector<uint32_t> p_corners = incident[p];
        for (uint32_t t : born) {
            const uint32_t* c = &cur[3 * size_t(t)];
            uint8_t role[3];
            uint32_t x = 0;
            for (int k = 0; k < 3; ++k) {
                role[k] = c[k] == v ? 0 : c[k] == p ? 1 : 2;
                if (role[k] == 2) x = c[k];
            }
            uint8_t order = 0;
            while (!(born_orders[order][0] == role[0] && born_orders[order][1] == role[1] && born_orders[order][2] == role[2])) ++order;
            const uint32_t index = uint32_t(std::find(candidates.begin(), candidates.end(), x) - candidates.begin());
            const uint32_t predicted = predicted_orientation(p_corners.data(), p_corners.data() + p_corners.size(), triangle, p, x);
            s.born.push_back({order, uint8_t(predicted), index, x, index == candidates.size()});
            p_corners.push_back(3 * t + uint32_t(std::find(c, c + 3, p) - c));
        }
        // v's other corners were p's before the split: p's list in order, marked
        std::vector<uint32_t> merged = incident[p];
        merged.insert(merged.end(), incident[v].begin(), incident[v].end());
        std::sort(merged.begin(), merged.end());
        for (uint32_t g : merged) s.moves.push_back(cur[g] == v);
        for (uint32_t g : incident[v]) cur[g] = p;
        incident[p] = std::move(merged);
        std::vector<uint32_t>().swap(incident[v]);
    }
    for (uint32_t q = 0; q < P; ++q) {
        const Part part = part_at(m, q);
        out.base.emplace_back(cur.begin() + 3 * size_t(part.first_triangle), cur.begin() + 3 * (size_t(part.first_triangle) + alive_count[q]));
        for (size_t t = 0; t < out.base.back().size(); t += 3)  // the survivors' coarsest level
            for (int k = 0; k < 3; ++k) add_plane(born_planes[out.base.back()[t + k]], m, out.base.back()[t], out.base.back()[t + 1], out.base.back()[t + 2]);
    }
    return out;
}

/// What a vertex's quantization should keep it near, per point (coincident vertices count once,
/// so that a seam's copies land on one grid point): the planes of the full mesh's triangles around
/// it, and those of the triangles around it at the coarsest level it is in (where it is born, or
/// the survivors' level), each scaled to trace 1: a vertex serves every level from its birth on,
/// and at the coarse ones its triangles are the coarse ones.
struct PointPlanes {
    std::vector<uint32_t> point;  // per vertex
    std::vector<Planes> q;        // per point
};

PointPlanes point_planes(const MeshView& m, const std::vector<Planes>& born_planes) {
    PointPlanes pp;
    const uint32_t n = m.vertex_count;
    detail::PositionPoints at = detail::points_by_position(m.positions, n);
    pp.point = std::move(at.point);
    const size_t points = at.count;
    std::vector<Planes> fine(points, Planes{0, 0, 0, 0, 0, 0}), born(points, Planes{0, 0, 0, 0, 0, 0});
    for (uint32_t t = 0; t < m.triangle_count; ++t) {
        Planes q{0, 0, 0, 0, 0, 0};
        add_plane(q, m, m.corner(3 * t), m.corner(3 * t + 1), m.corner(3 * t + 2));
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 6; ++j) fine[pp.point[m.corner(3 * t + k)]][j] += q[j];
    }
    for (uint32_t v = 0; v < n; ++v)
        for (int j = 0; j < 6; ++j) born[pp.point[v]][j] += born_planes[v][j];
    pp.q.resize(points);
    for (size_t i = 0; i < points; ++i) {
        const Planes a = unit_trace(fine[i]), b = unit_trace(born[i]);
        for (int j = 0; j < 6; ++j) pp.q[i][j] = a[j] + b[j];
    }
    return pp;
}

/// A position's grid values: of the grid points of the cell around it (at most one step away on
/// each axis), the one that moves it least off the planes of its triangles (PointPlanes), with a
/// small weight on the move itself: the quantized surface stays nearer the source than rounding each
/// coordinate does (at a crease or corner, near every plane there).
std::array<uint32_t, 3> quantize_on_surface(const float x[3], const Planes& planes, const StreamQuantization& q) {
    constexpr double move_weight = 0.1;  // of the squared move; the planes' terms weigh 1
    const uint32_t top = (1u << q.position_bits) - 1;
    uint32_t lo[3];
    for (int k = 0; k < 3; ++k) {
        const double f = std::floor((double(x[k]) - double(q.position_min[k])) / double(q.position_step));
        lo[k] = uint32_t(std::clamp(f, 0.0, double(top)));
    }
    std::array<uint32_t, 3> best{};
    double best_cost = INFINITY;
    for (int corner = 0; corner < 8; ++corner) {
        std::array<uint32_t, 3> g;
        double d[3];
        for (int k = 0; k < 3; ++k) {
            g[k] = std::min(top, lo[k] + (corner >> k & 1));
            d[k] = double(dequantize(g[k], q.position_min[k], q.position_step)) - double(x[k]);
        }
        const double planes_cost = planes[0] * d[0] * d[0] + planes[3] * d[1] * d[1] + planes[5] * d[2] * d[2] +
                                   2 * (planes[1] * d[0] * d[1] + planes[2] * d[0] * d[2] + planes[4] * d[1] * d[2]);
        const double cost = planes_cost + move_weight * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (cost < best_cost) best_cost = cost, best = g;
    }
    return best;
}

Quantized quantize_mesh(const MeshView& m, const std::vector<Planes>& born_planes, const StreamOptions& o) {
    Quantized out;
    StreamQuantization& q = out.q;
    q.position_bits = o.position_bits, q.normal_bits = o.normal_bits, q.texcoord_bits = o.texcoord_bits;
    const size_t n = m.vertex_count;
    float extent = 0;
    for (int k = 0; k < 3; ++k) {
        q.position_min[k] = m.bounds_min[k];
        extent = std::max(extent, m.bounds_max[k] - m.bounds_min[k]);
    }
    q.position_step = grid_step(extent, o.position_bits);
    const PointPlanes planes = point_planes(m, born_planes);
    for (size_t v = 0; v < n; ++v) {
        const std::array<uint32_t, 3> g = quantize_on_surface(m.positions + 3 * v, planes.q[planes.point[v]], q);
        out.positions.insert(out.positions.end(), {uint16_t(g[0]), uint16_t(g[1]), uint16_t(g[2])});
    }
    if (m.normals)
        for (size_t v = 0; v < n; ++v) {
            int16_t e[2];
            octahedral_encode(m.normals + 3 * v, o.normal_bits, e);
            out.normals.insert(out.normals.end(), e, e + 2);
        }
    const float* uvs[2] = {m.texcoords, m.texcoords1};
    for (int t = 0; t < 2; ++t) {
        if (!uvs[t]) continue;
        for (int k = 0; k < 2; ++k) {
            float lo = n ? uvs[t][k] : 0, hi = lo;
            for (size_t v = 0; v < n; ++v) lo = std::min(lo, uvs[t][2 * v + k]), hi = std::max(hi, uvs[t][2 * v + k]);
            q.texcoord_min[t][k] = lo;
            q.texcoord_step[t][k] = grid_step(hi - lo, o.texcoord_bits);
        }
        for (size_t i = 0; i < 2 * n; ++i)
            out.texcoords[t].push_back(uint16_t(quantize(uvs[t][i], q.texcoord_min[t][i % 2], q.texcoord_step[t][i % 2], o.texcoord_bits)));
    }
    for (int t = 0; t < 2; ++t)
        for (int k = 0; k < 2; ++k)
            if (!uvs[t]) q.texcoord_step[t][k] = 1;
    if (m.colors)
        for (size_t i = 0; i < 4 * n; ++i) out.colors.push_back(uint8_t(std::nearbyint(std::clamp(m.colors[i], 0.0f, 1.0f) * 255.0f)));
    if (m.tangents)
        for (size_t v = 0; v < n; ++v) {
            int16_t e[2];
            octahedral_encode(m.tangents + 4 * v, o.normal_bits, e);
            out.tangents.insert(out.tangents.end(), {e[0], e[1], int16_t(m.tangents[4 * v + 3] < 0 ? -1 : 1)});
        }
    return out;
}

/// A vertex's born triangles per part: for a mesh of one part, a 1 bit for the usual two (an
/// interior split) or a 0 and gamma(count + 1); for several parts gamma(count + 1) each.
void put_born_counts(BitWriter& w, const std::vector<uint32_t>& counts) {
    if (counts.size() == 1 && counts[0] == 2) return w.put(1, 1);
    if (counts.size() == 1) w.put(0, 1);
    for (uint32_t count : counts) w.gamma(count + 1);
}

/// Since 1.2 a split with two born triangles and two candidates near both p and v codes the pair
/// bit: whether it is a manifold split, the triangles' third corners those two (split_pair). Then
/// one more bit says which the first takes, and the triangles name no candidate.
bool has_pair_bit(const Split& s) { return s.born.size() == 2 && s.common == 2; }
bool split_pair(const Split& s) { return has_pair_bit(s) && s.born[0].index < 2 && s.born[1].index < 2 && s.born[0].index != s.born[1].index; }

/// Since 1.3 the splits block opens with a bit saying how the substitutes are coded: clear, each
/// in index_bits(v) bits; set, each as gamma(zigzag(p - previous p) + 1), the previous of the
/// chunk's first 0 (small when the chunk's splits are ordered by substitute, stream_order.h).
/// The encoder takes whichever is smaller.
bool differences_smaller(const Connectivity& conn, uint32_t S, uint32_t a, uint32_t b) {
    uint64_t plain = 0, differences = 0;
    uint32_t previous = 0;
    for (uint32_t v = std::max(a, S); v < b; ++v) {
        const uint32_t p = conn.splits[v - S].p;
        const uint64_t z = zigzag_difference(p, previous);
        if (z >= UINT32_MAX) return false;  // gamma codes below 2^32
        plain += index_bits(v);
        differences += gamma_bits(z + 1);
        previous = p;
    }
    return differences < plain;
}

void put_splits(std::vector<uint8_t>& out, const Connectivity& conn, uint32_t S, uint32_t a, uint32_t b) {
    BitWriter w;
    const bool differences = differences_smaller(conn, S, a, b);
    w.put(differences ? 1 : 0, 1);
    uint32_t previous = 0;
    for (uint32_t v = std::max(a, S); v < b; ++v) {
        const Split& s = conn.splits[v - S];
        if (differences) {
            w.gamma(uint32_t(zigzag_difference(s.p, previous) + 1));
        } else {
            w.put(s.p, index_bits(v));
        }
        previous = s.p;
        for (const bool move : s.moves) w.put(move ? 1 : 0, 1);
        put_born_counts(w, s.born_count);
        const bool pair = split_pair(s);
        if (has_pair_bit(s)) {
            w.put(pair ? 1 : 0, 1);
            if (pair) w.put(s.born[0].index, 1);
        }
        for (const Split::Born& t : s.born) {
            if (!pair) w.gamma(t.index + 1);
            if (t.escape) w.put(t.x, index_bits(v));
            if (t.order / 3 != t.predicted) w.put(other_orientation, turn_bits);
            w.put(t.order % 3, turn_bits);
        }
    }
    put_u32(out, uint32_t(w.bytes.size()));
    out.insert(out.end(), w.bytes.begin(), w.bytes.end());
}

/// One attribute's residuals in the form that codes them smaller (stream_layout::predict_neighbours,
/// predict_byte_form). Smooth surfaces favour the neighbours' mean; hard edges, seams and flat CAD
/// faces the substitute; the byte form wins where consecutive residuals are independent, the
/// zigzag form where they are alike (the codec then codes their difference). Each is tried in a
/// block of its own: the vertex codec codes each byte lane on its own, so the choice holds in the
/// chunk's block of every attribute.
struct AttributeResiduals {
    uint32_t prediction = 0, element = 0;
    std::vector<uint8_t> elements;
};

template <class T>
AttributeResiduals smallest_residuals(const std::vector<T>& values, const MeshView& m, const Connectivity& conn, uint32_t a, uint32_t b, int lanes,
                                      uint32_t element) {
    AttributeResiduals best;
    size_t best_bytes = 0;
    for (uint32_t p = 0; p < prediction_count; ++p) {
        const auto* rings = p & predict_neighbours ? &conn.rings : nullptr;
        std::vector<uint8_t> elements = residuals(values, m, rings, a, b, lanes, element, p & predict_byte_form);
        std::vector<uint8_t> block;
        put_vertex_block(block, elements, b - a, element);
        if (p == 0 || block.size() < best_bytes) best = {p, element, std::move(elements)}, best_bytes = block.size();
    }
    return best;
}

/// The attributes of a chunk's vertices (since stream 1.2): each one's prediction, then one block
/// of their elements side by side, so that a chunk pays the vertex codec's fixed cost (its header
/// and a tail of 32 bytes) once rather than per attribute.
void put_attributes(std::vector<uint8_t>& out, const std::vector<AttributeResiduals>& attributes, uint32_t count) {
    uint32_t stride = 0;
    for (const AttributeResiduals& r : attributes) put_u32(out, r.prediction), stride += r.element;
    std::vector<uint8_t> elements(size_t(count) * stride);
    uint32_t offset = 0;
    for (const AttributeResiduals& r : attributes) {
        for (uint32_t i = 0; i < count; ++i) std::memcpy(&elements[size_t(i) * stride + offset], &r.elements[size_t(i) * r.element], r.element);
        offset += r.element;
    }
    put_vertex_block(out, elements, count, stride);
}

/// One chunk of a mesh before it is placed in the file.
struct Chunk {
    uint32_t mesh = 0, vertex_end = 0, triangles = 0;
    double start = 0;  // the share of its mesh's triangles live before it (-1 for a mesh's first chunk)
    std::vector<uint8_t> bytes;
};

/// The payload of the chunk that adds vertices [a, b) to mesh `m`; `live` holds each part's live
/// triangles at a and is moved on to b.
std::vector<uint8_t> chunk_payload(const MeshView& m, const Quantized& q, const Connectivity& conn, uint32_t a, uint32_t b, std::vector<uint32_t>& live) {
    const uint32_t count = b - a, parts = part_count(m), S = m.min_vertex_count;
    std::vector<uint8_t> out;
    for (uint32_t p = 0; p < parts; ++p) {
        const uint32_t base = a == 0 ? uint32_t(conn.base[p].size() / 3) : 0;
        uint32_t born = 0;
        for (uint32_t v = std::max(a, S); v < b; ++v) born += conn.splits[v - S].born_count[p];
        put_u32(out, base);
        put_u32(out, born);
        live[p] += base + born;
    }
    if (a == 0)
        for (uint32_t p = 0; p < parts; ++p)
            if (!conn.base[p].empty()) put_index_block(out, conn.base[p].data(), conn.base[p].size(), S);
    put_splits(out, conn, S, a, b);
    std::vector<AttributeResiduals> attributes{smallest_residuals(q.positions, m, conn, a, b, 3, position_element)};
    if (m.normals) attributes.push_back(smallest_residuals(q.normals, m, conn, a, b, 2, normal_element));
    if (m.texcoords) attributes.push_back(smallest_residuals(q.texcoords[0], m, conn, a, b, 2, texcoord_element));
    if (m.colors) attributes.push_back(smallest_residuals(q.colors, m, conn, a, b, 4, color_element));
    if (m.texcoords1) attributes.push_back(smallest_residuals(q.texcoords[1], m, conn, a, b, 2, texcoord_element));
    if (m.tangents) attributes.push_back(smallest_residuals(q.tangents, m, conn, a, b, 3, tangent_element));
    put_attributes(out, attributes, count);
    for (uint32_t s = 0; s < m.extra_stream_count; ++s) {
        const VertexStreamView& x = m.extra_streams[s];
        const uint32_t element = x.components * component_bytes(x.component_type), size = padded_element(element);
        std::vector<uint8_t> raw(size_t(count) * size, 0);
        for (uint32_t v = a; v < b; ++v) std::memcpy(&raw[size_t(v - a) * size], x.data + size_t(v) * element, element);
        put_vertex_block(out, raw, count, size);
    }
    return out;
}

/// Every chunk of mesh `index`.
std::vector<Chunk> mesh_chunks(const MeshView& m, uint32_t index, const Connectivity& conn, const Quantized& q, const std::vector<uint32_t>& ends) {
    std::vector<uint32_t> live(part_count(m), 0);
    std::vector<Chunk> out;
    uint32_t a = 0;
    for (const uint32_t b : ends) {
        Chunk c;
        c.mesh = index, c.vertex_end = b;
        c.start = out.empty() ? -1.0 : double(out.back().triangles) / double(std::max(1u, m.triangle_count));
        c.bytes = chunk_payload(m, q, conn, a, b, live);
        for (uint32_t t : live) c.triangles += t;
        out.push_back(std::move(c));
        a = b;
    }
    return out;
}

std::vector<uint8_t> quantization_record(const StreamQuantization& q) {
    std::vector<uint8_t> r(quantization_bytes, 0);
    store_u32(&r[q_position_bits], q.position_bits);
    store_u32(&r[q_normal_bits], q.normal_bits);
    store_u32(&r[q_texcoord_bits], q.texcoord_bits);
    for (int k = 0; k < 3; ++k) store_f32(&r[q_position_min + 4 * k], q.position_min[k]);
    store_f32(&r[q_position_step], q.position_step);
    for (int k = 0; k < 2; ++k) {
        store_f32(&r[q_texcoord0_min + 4 * k], q.texcoord_min[0][k]);
        store_f32(&r[q_texcoord0_step + 4 * k], q.texcoord_step[0][k]);
        store_f32(&r[q_texcoord1_min + 4 * k], q.texcoord_min[1][k]);
        store_f32(&r[q_texcoord1_step + 4 * k], q.texcoord_step[1][k]);
    }
    return r;
}

/// The sections the directory keeps whole: the file's own as stored, and per mesh its header,
/// metadata, groups and parts as stored and its carried streams' records (without elements).
std::vector<layout::PendingSection> kept_sections(const File& file, const uint8_t* bytes) {
    using namespace layout;
    std::vector<PendingSection> kept;
    for (const SectionInfo& s : file.sections()) {
        const uint32_t type = fourcc(s.type);
        const bool whole = s.mesh == file_level || type == sec_mesh || type == sec_metadata || type == sec_pairs || type == sec_parts;
        if (whole) kept.push_back({type, s.mesh, std::vector<uint8_t>(bytes + s.offset, bytes + s.offset + s.bytes)});
    }
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        const MeshView& m = file.mesh(i);
        if (!m.extra_stream_count) continue;
        const std::vector<VertexStreamView> records(m.extra_streams, m.extra_streams + m.extra_stream_count);
        kept.push_back({sec_extra_streams, i, detail::encode_extra_streams(records, 0)});
    }
    return kept;
}

void check_options(const StreamOptions& o) {
    if (o.position_bits < 1 || o.position_bits > 16) throw ArgumentError("encode_stream: position_bits " + std::to_string(o.position_bits) + " is not in [1, 16]");
    if (o.normal_bits < 2 || o.normal_bits > 16) throw ArgumentError("encode_stream: normal_bits " + std::to_string(o.normal_bits) + " is not in [2, 16]");
    if (o.texcoord_bits < 1 || o.texcoord_bits > 16) throw ArgumentError("encode_stream: texcoord_bits " + std::to_string(o.texcoord_bits) + " is not in [1, 16]");
    if (!(o.first_share > 0 && o.first_share <= 1)) throw ArgumentError("encode_stream: first_share is not in (0, 1]");
    if (!(o.growth > 1 && o.growth <= 16)) throw ArgumentError("encode_stream: growth is not in (1, 16]");
}

/// Every mesh's chunk ends.
std::vector<std::vector<uint32_t>> all_chunk_ends(const File& file, const StreamOptions& options) {
    std::vector<std::vector<uint32_t>> ends;
    for (uint32_t i = 0; i < file.mesh_count(); ++i) ends.push_back(chunk_ends(file.mesh(i), options));
    return ends;
}

/// The streamed image of `file` (whose bytes are `bytes`), its meshes' chunks ending at `ends`.
std::vector<uint8_t> encode_file(const File& file, const uint8_t* bytes, const std::vector<std::vector<uint32_t>>& ends, const StreamOptions& options) {
    // the directory: kept sections (those a frame needs, then the deferred ones), quantization per
    // mesh, then (below) the chunk table
    std::vector<layout::PendingSection> kept = kept_sections(file, bytes);
    const size_t front = size_t(
        std::stable_partition(kept.begin(), kept.end(), [](const layout::PendingSection& s) { return s.mesh != layout::file_level || !deferrable(s.type); }) -
        kept.begin());
    std::vector<uint8_t> deferred;
    for (size_t k = front; k < kept.size(); ++k) deferred.insert(deferred.end(), kept[k].bytes.begin(), kept[k].bytes.end());
    std::vector<uint8_t> directory(directory_header_bytes, 0);
    store_u32(&directory[d_kept_count], uint32_t(kept.size()));
    for (const layout::PendingSection& s : kept) {
        put_u32(directory, s.type);
        put_u32(directory, s.mesh);
        directory.resize(directory.size() + 8);
        store_u64(&directory[directory.size() - 8], s.bytes.size());
    }
    // chunks: every mesh's first, then the others by the share of their mesh's triangles live
    // before them, so that the prefix a share of every mesh needs holds little else
    std::vector<Chunk> chunks;
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        const MeshView& m = file.mesh(i);
        std::vector<Planes> born_planes;
        const Connectivity conn = connectivity(m, born_planes);
        const Quantized q = quantize_mesh(m, born_planes, options);
        std::vector<Planes>().swap(born_planes);
        const std::vector<uint8_t> record = quantization_record(q.q);
        directory.insert(directory.end(), record.begin(), record.end());
        for (Chunk& c : mesh_chunks(m, i, conn, q, ends[i])) chunks.push_back(std::move(c));
    }
    std::stable_sort(chunks.begin(), chunks.end(), [](const Chunk& x, const Chunk& y) { return x.start < y.start; });
    // the deferred block right after the meshes' first chunks
    const size_t after = kept.size() > front ? std::min<size_t>(file.mesh_count(), chunks.size()) : 0;
    if (kept.size() > front) {
        store_u32(&directory[d_deferred_count], uint32_t(kept.size() - front));
        store_u32(&directory[d_deferred_after], uint32_t(after));
        store_u32(&directory[d_deferred_checksum], crc32(deferred.data(), deferred.size()));
    }
    std::vector<ChunkRecord> records;
    for (const Chunk& c : chunks) records.push_back({c.mesh, c.vertex_end, c.triangles, uint32_t(c.bytes.size()), crc32(c.bytes.data(), c.bytes.size())});
    put_chunk_table(directory, records, file.mesh_count());
    for (size_t k = 0; k < front; ++k) directory.insert(directory.end(), kept[k].bytes.begin(), kept[k].bytes.end());
    // header, directory, chunks with the deferred block among them
    std::vector<uint8_t> out(header_bytes, 0);
    std::memcpy(out.data(), magic, 8);
    store_u32(&out[h_version_major], version_major);
    store_u32(&out[h_version_minor], version_minor);
    store_u32(&out[h_mesh_count], file.mesh_count());
    store_u32(&out[h_chunk_count], uint32_t(chunks.size()));
    store_u64(&out[h_directory_bytes], directory.size());
    store_u32(&out[h_directory_checksum], crc32(directory.data(), directory.size()));
    out.insert(out.end(), directory.begin(), directory.end());
    for (size_t k = 0; k <= chunks.size(); ++k) {
        if (k == after) out.insert(out.end(), deferred.begin(), deferred.end());
        if (k < chunks.size()) out.insert(out.end(), chunks[k].bytes.begin(), chunks[k].bytes.end());
    }
    store_u64(&out[h_file_bytes], out.size());
    store_u32(&out[h_header_checksum], crc32(out.data(), h_header_checksum));
    return out;
}

}  // namespace

std::vector<uint8_t> stream_order(const void* bytes, size_t size, const StreamOptions& options, const std::string& name) {
    check_options(options);
    const File file = File::borrow(bytes, size, name);
    if (options.keep_order) return std::vector<uint8_t>(static_cast<const uint8_t*>(bytes), static_cast<const uint8_t*>(bytes) + size);
    return stream_ordered_image(file, static_cast<const uint8_t*>(bytes), all_chunk_ends(file, options));
}

std::vector<uint8_t> encode_stream(const void* source, size_t source_size, const StreamOptions& options, const std::string& name) {
    check_options(options);
    // the chunks end where the source's do (the renumbered groups would move some ends)
    const File original = File::borrow(source, source_size, name);
    const std::vector<std::vector<uint32_t>> ends = all_chunk_ends(original, options);
    if (options.keep_order) return encode_file(original, static_cast<const uint8_t*>(source), ends, options);
    const std::vector<uint8_t> ordered = stream_ordered_image(original, static_cast<const uint8_t*>(source), ends);
    return encode_file(File::borrow(ordered.data(), ordered.size(), name), ordered.data(), ends, options);
}

} // namespace tom
