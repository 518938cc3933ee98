// Sample points of the Metro-style distance: vertices, edges, stratified faces, Morton order.

#include "samples.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

#include "morton.h"
#include "radix_sort.h"

namespace tom::detail {

namespace {

// splitmix64: a small, portable generator, so samples are the same on every platform
struct Random {
    uint64_t state;
    uint64_t next() {
        uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
        return z ^ (z >> 31);
    }
    double uniform() { return double(next() >> 11) * (1.0 / 9007199254740992.0); }
    // area-uniform weights (u, v) of the edges from a triangle's first corner
    void in_triangle(double& u, double& v) {
        u = uniform(), v = uniform();
        if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    }
};

} // namespace

double face_area(const Surface& s, size_t t) {
    const V3 a = corner(s, t, 0);
    return 0.5 * length(cross(corner(s, t, 1) - a, corner(s, t, 2) - a));
}

double surface_area(const Surface& s) {
    double area = 0;
    for (size_t t = 0; t < s.triangle_count; ++t) area += face_area(s, t);
    return area;
}

namespace {

// each face's area into `areas`; returns their sum (summed in face order, as surface_area())
double face_areas(const Surface& s, std::vector<double>& areas) {
    areas.resize(s.triangle_count);
    double total = 0;
    for (size_t t = 0; t < s.triangle_count; ++t) total += areas[t] = face_area(s, t);
    return total;
}

// Sorts distinct words whose key bits [low, low + key_bits) sit above an index ascending in
// `items`' order: the same order as radix_sort() by key (equal keys by index), in fewer passes
// over memory. One scatter by the key's top kTopBits (an octree level of 4096 cells, of which a
// surface fills a fifth or so), then each bucket, in cache, by the rest of the key, least
// significant digit first (stable: the index order kept) or, for a few words, by insertion.
void sort_words(std::vector<uint64_t>& items, std::vector<uint64_t>& other, int key_bits, int low, Team* team) {
    constexpr int kTopBits = 12, kDigitBits = 10;
    constexpr size_t kTop = size_t(1) << kTopBits, kDigit = size_t(1) << kDigitBits, kInsertion = 48;
    const size_t n = items.size();
    auto key = [low](uint64_t item) { return item >> low; };
    // the top digit into other; a small sort, or one whose words all share the top digit (points
    // all at one place), by one radix sort
    std::vector<size_t> place;
    if (key_bits <= kTopBits + kDigitBits || n < kParallelSortItems || !radix_pass(items, other, key_bits - kTopBits, kTopBits, key, team, place)) {
        radix_sort(items, other, key_bits, key, team);
        return;
    }
    std::vector<size_t> first(kTop + 1, 0);  // each bucket's first place (where the one before ends)
    for (size_t b = 0; b < kTop; ++b) first[b + 1] = place[place.size() - kTop + b];
    // the buckets, in blocks of about equal words, back into items
    const int rest = key_bits - kTopBits, digits = (rest + kDigitBits - 1) / kDigitBits;
    auto sort_buckets = [&](size_t b0, size_t b1) {
        std::vector<uint32_t> count(size_t(digits) * kDigit);
        for (size_t b = b0; b < b1; ++b) {
            const size_t begin = first[b], m = first[b + 1] - begin;
            uint64_t* from = other.data() + begin;
            uint64_t* to = items.data() + begin;
            if (m <= kInsertion) {
                for (size_t i = 0; i < m; ++i) {
                    const uint64_t x = from[i];
                    size_t j = i;
                    for (; j > 0 && to[j - 1] > x; --j) to[j] = to[j - 1];
                    to[j] = x;
                }
                continue;
            }
            std::fill(count.begin(), count.end(), 0u);
            for (size_t i = 0; i < m; ++i)
                for (int d = 0; d < digits; ++d) ++count[size_t(d) * kDigit + (from[i] >> (low + d * kDigitBits) & (kDigit - 1))];
            for (int d = 0; d < digits; ++d) {
                uint32_t* c = &count[size_t(d) * kDigit];
                uint32_t at = 0;
                for (size_t k = 0; k < kDigit; ++k) at += std::exchange(c[k], at);
                const int shift = low + d * kDigitBits;
                for (size_t i = 0; i < m; ++i) to[c[from[i] >> shift & (kDigit - 1)]++] = from[i];
                std::swap(from, to);
            }
            if (from != items.data() + begin) std::copy(from, from + m, items.data() + begin);  // (an odd count of digits)
        }
    };
    if (!team) return sort_buckets(0, kTop);
    // blocks of buckets cut at about n / 16 words each, taken in turn
    std::vector<size_t> cut{0};
    for (size_t b = 0; b < kTop; ++b)
        if (first[b + 1] - first[cut.back()] >= n / 16 || b + 1 == kTop) cut.push_back(b + 1);
    team->blocks(cut.size() - 1, 1, [&](unsigned, size_t k, size_t) { sort_buckets(cut[k], cut[k + 1]); });
}

} // namespace

void order_morton(std::vector<V3>& points, std::vector<uint64_t>& keys, double& extent, MortonScratch& scratch, unsigned threads,
                  std::vector<uint32_t>* permutation) {
    const size_t n = points.size();
    if (n == 0) {  // nothing to order (and no first point to take bounds from)
        keys.clear();
        extent = 0;
        if (permutation) permutation->clear();
        return;
    }
    // one team for the whole ordering, where the points are many enough to share
    std::unique_ptr<Team> team;
    if (n >= kParallelSortItems && thread_count(threads) > 1) team = std::make_unique<Team>(thread_count(threads), false);
    auto each = [&](auto&& f) {  // f(begin, end) over [0, n) in chunks of kChunk, on the team if any
        if (!team) return f(size_t(0), n);
        team->blocks(n, kChunk, [&](unsigned, size_t begin, size_t end) { f(begin, end); });
    };
    struct Bounds {
        V3 lo = {1e300, 1e300, 1e300}, hi = {-1e300, -1e300, -1e300};
    };
    std::vector<Bounds> bounds((n + kChunk - 1) / kChunk);
    each([&](size_t begin, size_t end) {
        Bounds& b = bounds[begin / kChunk];
        for (size_t i = begin; i < end; ++i) {
            const V3 p = points[i];
            b.lo = {std::min(b.lo.x, p.x), std::min(b.lo.y, p.y), std::min(b.lo.z, p.z)};
            b.hi = {std::max(b.hi.x, p.x), std::max(b.hi.y, p.y), std::max(b.hi.z, p.z)};
        }
    });
    V3 lo = {1e300, 1e300, 1e300}, hi = {-1e300, -1e300, -1e300};
    for (const Bounds& b : bounds) {
        lo = {std::min(lo.x, b.lo.x), std::min(lo.y, b.lo.y), std::min(lo.z, b.lo.z)};
        hi = {std::max(hi.x, b.hi.x), std::max(hi.y, b.hi.y), std::max(hi.z, b.hi.z)};
    }
    extent = n ? std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) : 0.0;
    const double scale = extent > 0 ? double((1u << kMortonBits) - 1) / extent : 0.0;
    // each point's code and index in one 64-bit word, the index below: half the bytes a sort pass
    // moves of (code, index) pairs. Where the index needs more than 16 bits, the code keeps fewer
    // (14 bits an axis up to 4M points): those points still come in the order of the full code,
    // but where it only differs below (within 2^-14 of the extent, far below the spacing of so
    // many samples), in the order made
    int index_bits = 1;
    while (index_bits < 32 && (uint64_t(1) << index_bits) < n) ++index_bits;
    const int axis_bits = std::min(kMortonBits, (64 - index_bits) / 3), drop = kMortonBits - axis_bits;
    std::vector<uint64_t>& packed = scratch.packed;
    packed.resize(n);
    each([&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
            const V3 q = scale * (points[i] - lo);  // (in [0, 65535]: a signed conversion is exact and quicker)
            const uint32_t x = uint32_t(int32_t(q.x)) >> drop, y = uint32_t(int32_t(q.y)) >> drop, z = uint32_t(int32_t(q.z)) >> drop;
            packed[i] = (spread16(x) << 2 | spread16(y) << 1 | spread16(z)) << index_bits | i;
        }
    });
    sort_words(packed, scratch.packed_other, 3 * axis_bits, index_bits, team.get());
    std::vector<V3>& sorted = scratch.sorted;
    sorted.resize(n);
    keys.resize(n);
    if (permutation) permutation->resize(n);
    const uint64_t index_mask = (uint64_t(1) << index_bits) - 1;
    each([&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
            const uint32_t from = uint32_t(packed[i] & index_mask);
            sorted[i] = points[from];
            keys[i] = (packed[i] >> index_bits) << (3 * drop);  // the full code's place (zeros below)
            if (permutation) (*permutation)[i] = from;
        }
    });
    points.swap(sorted);
}

// Vertices first, then points along the edges, then area-uniform random points on the faces,
// about `target` in all (Metro's order and budget).
namespace {

// Where sample_surface() puts its points, with the face each came from when asked.
struct SampleSink {
    Samples& out;
    std::vector<uint32_t>& faces;
    bool with_faces;
    void add(const V3& point, uint32_t face) {
        out.points.push_back(point);
        if (with_faces) faces.push_back(face);
    }
};

// Every vertex that a face uses, once.
void sample_vertices(const Surface& s, SampleSink& sink) {
    constexpr uint32_t kUnused = 0xffffffffu;
    std::vector<uint32_t> face_of(s.vertex_count, kUnused);  // a vertex's first face
    for (size_t i = s.triangle_count * 3; i-- > 0;) face_of[s.indices[i]] = uint32_t(i / 3);
    for (uint32_t v = 0; v < s.vertex_count; ++v)
        if (face_of[v] != kUnused) sink.add(vertex(s, v), face_of[v]);
}

// The points spaced along the edge from pa to pb (pa the lower vertex's): `per_length` a unit of
// length, rounded down, none at the ends; emit(point) for each. Returns their count.
template <class Emit>
uint64_t edge_points(V3 pa, V3 pb, double per_length, Emit&& emit) {
    const int n = int(std::sqrt(dot(pb - pa, pb - pa)) * per_length);
    for (int i = 1; i <= n; ++i) emit(pa + (double(i) / double(n + 1)) * (pb - pa));
    return uint64_t(std::max(n, 0));
}

// Points spaced along every edge once, in the order of (lower vertex, higher vertex): the square
// root of the area density along a length. A radix sort of the two vertices packed into one key
// finds the edges, with the first face that has each.
void sample_edges(const Surface& s, double per_area, const DistanceParams& p, MortonScratch& scratch, SampleSink& sink) {
    int bits = 1;
    while (bits < 32 && (uint64_t(1) << bits) < s.vertex_count) ++bits;
    std::vector<std::pair<uint64_t, uint32_t>>& edges = scratch.keyed;
    edges.clear();
    edges.reserve(s.triangle_count * 3);
    for (size_t t = 0; t < s.triangle_count; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = s.indices[3 * t + k], b = s.indices[3 * t + (k + 1) % 3];
            edges.push_back({uint64_t(std::min(a, b)) << bits | std::max(a, b), uint32_t(t)});
        }
    radix_sort(edges, scratch.other, 2 * bits, [](const std::pair<uint64_t, uint32_t>& edge) { return edge.first; }, p.threads);
    edges.erase(std::unique(edges.begin(), edges.end(), [](const auto& x, const auto& y) { return x.first == y.first; }), edges.end());
    const double per_length = std::sqrt(per_area);
    const uint64_t low = (uint64_t(1) << bits) - 1;
    for (const auto& edge : edges) {
        const uint32_t a = uint32_t(edge.first >> bits), b = uint32_t(edge.first & low);
        edge_points(vertex(s, a), vertex(s, b), per_length, [&](const V3& q) { sink.add(q, edge.second); });
    }
}

// Face t's samples, numbers [first, first + n) among the face samples, into points[0, n), stratified as Metro's
// similar-triangles sampling: the face is cut into m x m similar triangles, one random point in
// each, visited row by row in serpentine order so consecutive samples are neighbours; the n - m^2
// left over fall anywhere on the face. A point is made from its weights (u, v) of the face's
// edges from its first corner. Every `every`-th sample (0: none) is also recorded in `picked`.
// `points` and `picked` hold the samples from index `first` and the picks from `first_pick` on
// (the whole surface's from 0, a batch's from its own first).
void sample_face(const Surface& s, size_t t, uint64_t first, uint64_t n, uint64_t seed, V3* points, uint64_t every,
                 std::vector<FaceSample>* picked, uint64_t first_pick = 0) {
    Random rng{(seed * 0x2545F4914F6CDD1DULL) ^ (uint64_t(t) * 0x9E3779B97F4A7C15ULL)};
    uint64_t index = first;  // of the face sample made next
    const V3 a = corner(s, t, 0), b = corner(s, t, 1), c = corner(s, t, 2);
    const uint64_t m = uint64_t(std::sqrt(double(n)));
    struct Weights {
        double u, v;
    };
    auto random_in = [&](Weights w0, Weights w1, Weights w2) {
        double s1, s2;
        rng.in_triangle(s1, s2);
        const double u = w0.u + s1 * (w1.u - w0.u) + s2 * (w2.u - w0.u), v = w0.v + s1 * (w1.v - w0.v) + s2 * (w2.v - w0.v);
        points[index - first] = a + u * (b - a) + v * (c - a);
        if (every && index % every == 0) (*picked)[index / every - first_pick] = {uint32_t(t), u, v};
        ++index;
    };
    auto grid = [&](uint64_t i, uint64_t j) { return Weights{double(i) / double(m), double(j) / double(m)}; };
    for (uint64_t i = 0; i < m; ++i) {
        const uint64_t cells = 2 * (m - i) - 1;  // up and down triangles of row i
        for (uint64_t k = 0; k < cells; ++k) {
            const uint64_t cell = (i % 2 == 0) ? k : cells - 1 - k;
            const uint64_t j = cell / 2;
            if (cell % 2 == 0)
                random_in(grid(i, j), grid(i + 1, j), grid(i, j + 1));
            else
                random_in(grid(i + 1, j), grid(i + 1, j + 1), grid(i, j + 1));
        }
    }
    for (uint64_t i = m * m; i < n; ++i) random_in({0, 0}, {1, 0}, {0, 1});
}

// Each face's first face sample in first[t] (their count in first[T]): its expected share of
// `remaining` by its area (area(t), of `total_area` in all), the fraction rounded at random.
template <class Area>
void face_sample_starts(const Surface& s, double remaining, double total_area, const DistanceParams& p, Area&& area, std::vector<uint64_t>& first) {
    Random rounding{p.seed * 0x2545F4914F6CDD1DULL + s.triangle_count};
    first.assign(s.triangle_count + 1, 0);
    for (size_t t = 0; t < s.triangle_count; ++t) {
        const double expected = remaining * area(t) / total_area;
        first[t + 1] = first[t] + uint64_t(expected + rounding.uniform());
    }
}

// About `remaining` area-uniform points: each face gets its expected share, the fraction rounded
// at random, then its points on the team (each face with its own generator: the same points
// whatever the threads). Returns `every`, the picking stride among the face samples (0: none).
uint64_t sample_faces(const Surface& s, double remaining, const std::vector<double>& areas, const DistanceParams& p, SampleSink& sink,
                      PickedFaceSamples* pick, uint64_t pick_count) {
    Samples& out = sink.out;
    const size_t base = out.points.size();
    std::vector<uint64_t> first;  // each face's first sample
    face_sample_starts(s, remaining, out.area, p, [&](size_t t) { return areas[t]; }, first);
    out.points.resize(base + first.back());
    if (sink.with_faces) {
        sink.faces.resize(base + first.back());
        for (size_t t = 0; t < s.triangle_count; ++t)
            std::fill(sink.faces.begin() + std::ptrdiff_t(base + first[t]), sink.faces.begin() + std::ptrdiff_t(base + first[t + 1]), uint32_t(t));
    }
    uint64_t every = 0;
    if (pick && pick_count > 0 && first.back() > 0) {
        every = std::max<uint64_t>(1, uint64_t(std::llround(double(first.back()) / double(pick_count))));
        pick->picked.resize((first.back() + every - 1) / every);
    }
    V3* points = out.points.data() + base;
    parallel_chunks(first.back(), p.threads, [&](size_t, size_t begin, size_t end) {
        // the faces whose first sample falls in [begin, end)
        const size_t t0 = size_t(std::lower_bound(first.begin(), first.end() - 1, begin) - first.begin());
        const size_t t1 = size_t(std::lower_bound(first.begin(), first.end() - 1, end) - first.begin());
        for (size_t t = t0; t < t1; ++t)
            if (first[t + 1] > first[t])
                sample_face(s, t, first[t], first[t + 1] - first[t], p.seed, points + first[t], every, pick ? &pick->picked : nullptr);
    });
    return every;
}

} // namespace

// out's points in Morton order (scratch.order: the permutation, when `with_faces`), each one's
// face (scratch.faces, in the order made) carried along into out.faces when `with_faces`;
// returns with_faces.
static bool order_samples(Samples& out, MortonScratch& scratch, unsigned threads, bool with_faces) {
    std::vector<uint32_t>& order = scratch.order;
    order_morton(out.points, out.keys, out.extent, scratch, threads, with_faces ? &order : nullptr);
    if (!with_faces) {
        out.faces.clear();
        return false;
    }
    out.faces.resize(order.size());
    parallel_chunks(order.size(), threads, [&](size_t, size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) out.faces[i] = scratch.faces[order[i]];
    });
    return true;
}

void sample_surface(const Surface& s, uint64_t target, const DistanceParams& p, Samples& out, MortonScratch& scratch, PickedFaceSamples* pick,
                    uint64_t pick_count, bool with_faces) {
    with_faces = with_faces || pick;
    out.points.clear();
    scratch.faces.clear();  // of each point, in the order made
    out.vertex = out.edge = out.face = 0;
    std::vector<double> areas;
    out.area = face_areas(s, areas);
    out.points.reserve(target + target / 8 + 16);  // face samples round up at random: a little over the target
    const double per_area = out.area > 0 ? double(target) / out.area : 0.0;
    SampleSink sink{out, scratch.faces, with_faces};

    if (p.vertex_samples) sample_vertices(s, sink);
    out.vertex = out.points.size();
    if (p.edge_samples && per_area > 0) sample_edges(s, per_area, p, scratch, sink);
    out.edge = out.points.size() - out.vertex;
    const double remaining = double(target) - double(out.points.size());
    const size_t base = out.points.size();  // the first face sample's
    if (pick) pick->picked.clear();
    uint64_t every = 0;  // picking every this-th face sample (0: none)
    if (p.face_samples && remaining > 0 && out.area > 0) every = sample_faces(s, remaining, areas, p, sink, pick, pick_count);
    out.face = out.points.size() - out.vertex - out.edge;

    // Morton order, and each point's face (and pick) carried along
    if (!order_samples(out, scratch, p.threads, with_faces) || !pick) return;
    const std::vector<uint32_t>& order = scratch.order;
    pick->of_point.resize(order.size());
    for (size_t i = 0; i < order.size(); ++i) {
        const bool picked = every && order[i] >= base && (order[i] - base) % every == 0;  // (index among the face samples)
        pick->of_point[i] = picked ? uint32_t((order[i] - base) / every) : PickedFaceSamples::kNotPicked;
    }
}

std::vector<uint32_t> faces_in_morton_order(const Surface& s, unsigned threads) {
    const size_t faces = s.triangle_count;
    V3 lo = {1e300, 1e300, 1e300}, hi = {-1e300, -1e300, -1e300};
    for (size_t c = 0; c < 3 * faces; ++c) {
        const V3 x = vertex(s, s.indices[c]);
        lo = {std::min(lo.x, x.x), std::min(lo.y, x.y), std::min(lo.z, x.z)};
        hi = {std::max(hi.x, x.x), std::max(hi.y, x.y), std::max(hi.z, x.z)};
    }
    int index_bits = 1;
    while (index_bits < 32 && (uint64_t(1) << index_bits) < faces) ++index_bits;
    const int axis_bits = std::min(kMortonBits, (64 - index_bits) / 3);
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    const double scale = extent > 0 ? double((1u << axis_bits) - 1) / extent : 0.0;
    std::vector<uint64_t> words(faces), other;
    for (size_t t = 0; t < faces; ++t) {
        const V3 q = scale * ((1.0 / 3.0) * (corner(s, t, 0) + corner(s, t, 1) + corner(s, t, 2)) - lo);
        words[t] = (spread16(uint32_t(q.x)) << 2 | spread16(uint32_t(q.y)) << 1 | spread16(uint32_t(q.z))) << index_bits | t;
    }
    radix_sort(words, other, 3 * axis_bits, [index_bits](uint64_t w) { return w >> index_bits; }, threads);
    std::vector<uint32_t> order(faces);
    const uint64_t mask = (uint64_t(1) << index_bits) - 1;
    for (size_t i = 0; i < faces; ++i) order[i] = uint32_t(words[i] & mask);
    return order;
}

// The plan: which corner samples each vertex and which edge each edge (the first face and corner
// that has it, as sample_vertices() and sample_edges() take them), each face's first face
// sample, the faces in Morton order of their centroids, and the cuts between batches.
SampleBatches::SampleBatches(const Surface& s, uint64_t target, const DistanceParams& p, uint64_t batch_samples, uint64_t pick_count)
    : s_(s), p_(p) {
    const size_t faces = s.triangle_count;
    owns_.assign(faces, 0);
    area = surface_area(s);
    const double per_area = area > 0 ? double(target) / area : 0.0;
    per_length_ = std::sqrt(per_area);
    // the faces around each vertex, in face order (corner lists: 4 bytes a corner)
    std::vector<uint32_t> start(size_t(s.vertex_count) + 1, 0), around(3 * faces);
    for (size_t c = 0; c < 3 * faces; ++c) ++start[s.indices[c] + 1];
    for (uint32_t v = 0; v < s.vertex_count; ++v) start[v + 1] += start[v];
    {
        std::vector<uint32_t> at(start.begin(), start.end() - 1);
        for (size_t c = 0; c < 3 * faces; ++c) around[at[s.indices[c]]++] = uint32_t(c);
    }
    for (uint32_t v = 0; v < s.vertex_count; ++v)  // a used vertex: its first corner samples it
        if (p.vertex_samples && start[v + 1] > start[v]) owns_[around[start[v]] / 3] |= uint8_t(1u << (around[start[v]] % 3)), ++vertex;
    if (p.edge_samples && per_area > 0)
        for (size_t t = 0; t < faces; ++t)
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = s.indices[3 * t + size_t(k)], b = s.indices[3 * t + size_t(k + 1) % 3];
                if (a == b) continue;  // (a point, no edge: no points along it)
                // taken by an earlier corner of this face, or by an earlier face with both ends?
                bool earlier = false;
                for (int j = 0; j < k && !earlier; ++j) {
                    const uint32_t x = s.indices[3 * t + size_t(j)], y = s.indices[3 * t + size_t(j + 1) % 3];
                    earlier = (x == a && y == b) || (x == b && y == a);
                }
                for (uint32_t i = start[a]; i < start[a + 1] && !earlier; ++i) {
                    const uint32_t f = around[i] / 3;
                    if (f >= t) break;
                    earlier = s.indices[3 * size_t(f)] == b || s.indices[3 * size_t(f) + 1] == b || s.indices[3 * size_t(f) + 2] == b;
                }
                if (earlier) continue;
                owns_[t] |= uint8_t(8u << k);
                edge += edge_points(detail::vertex(s, std::min(a, b)), detail::vertex(s, std::max(a, b)), per_length_, [](const V3&) {});
            }
    const double remaining = double(target) - double(vertex + edge);
    if (p.face_samples && remaining > 0 && area > 0)
        face_sample_starts(s, remaining, area, p, [&](size_t t) { return face_area(s, t); }, first_);
    else
        first_.assign(faces + 1, 0);
    face = first_.back();
    if (pick_count > 0 && face > 0) {
        every_ = std::max<uint64_t>(1, uint64_t(std::llround(double(face) / double(pick_count))));
        picked = (face + every_ - 1) / every_;
    }
    order_ = faces_in_morton_order(s, p.threads);
    // the cuts: runs of faces in that order of about batch_samples samples each
    cuts_.push_back(0);
    uint64_t in_batch = 0;
    for (size_t i = 0; i < faces; ++i) {
        in_batch += samples_of(order_[i]);
        if (in_batch >= batch_samples || i + 1 == faces) cuts_.push_back(i + 1), in_batch = 0;
    }
}

uint64_t SampleBatches::samples_of(uint32_t t) const {
    uint64_t n = first_[t + 1] - first_[t];
    for (int k = 0; k < 3; ++k) {
        if (owns_[t] >> k & 1u) ++n;
        if (owns_[t] >> (3 + k) & 1u) {
            const uint32_t a = s_.indices[3 * size_t(t) + size_t(k)], b = s_.indices[3 * size_t(t) + size_t(k + 1) % 3];
            n += edge_points(detail::vertex(s_, std::min(a, b)), detail::vertex(s_, std::max(a, b)), per_length_, [](const V3&) {});
        }
    }
    return n;
}

void SampleBatches::make(size_t k, Samples& out, MortonScratch& scratch, PickedFaceSamples* pick, bool with_faces) const {
    with_faces = with_faces || pick;
    out.points.clear();
    scratch.faces.clear();
    out.vertex = out.edge = out.face = 0;
    out.area = 0;
    std::vector<FaceSample> local_picks, face_picks;  // the batch's picks; one face's
    std::vector<uint32_t> pick_of;  // of each point made, its pick in local_picks or kNotPicked
    for (size_t i = cuts_[k]; i < cuts_[k + 1]; ++i) {
        const uint32_t t = order_[i];
        out.area += face_area(s_, t);
        auto add = [&](const V3& q) {
            out.points.push_back(q);
            if (with_faces) scratch.faces.push_back(t);
            if (pick) pick_of.push_back(PickedFaceSamples::kNotPicked);
        };
        for (int c = 0; c < 3; ++c)
            if (owns_[t] >> c & 1u) add(detail::vertex(s_, s_.indices[3 * size_t(t) + size_t(c)])), ++out.vertex;
        for (int c = 0; c < 3; ++c)
            if (owns_[t] >> (3 + c) & 1u) {
                const uint32_t a = s_.indices[3 * size_t(t) + size_t(c)], b = s_.indices[3 * size_t(t) + size_t(c + 1) % 3];
                out.edge += edge_points(detail::vertex(s_, std::min(a, b)), detail::vertex(s_, std::max(a, b)), per_length_, add);
            }
        const uint64_t n = first_[t + 1] - first_[t];
        if (n == 0) continue;
        const size_t base = out.points.size();
        out.points.resize(base + n);
        if (with_faces) scratch.faces.resize(base + n, t);
        // this face's picks: the face samples numbered a multiple of every_
        const uint64_t first_pick = every_ ? (first_[t] + every_ - 1) / every_ : 0, end_pick = every_ ? (first_[t + 1] + every_ - 1) / every_ : 0;
        face_picks.resize(size_t(end_pick - first_pick));
        sample_face(s_, t, first_[t], n, p_.seed, out.points.data() + base, pick ? every_ : 0, &face_picks, first_pick);
        out.face += n;
        if (!pick) continue;
        pick_of.resize(base + n, PickedFaceSamples::kNotPicked);
        for (uint64_t j = first_pick; j < end_pick; ++j) {
            pick_of[base + (j * every_ - first_[t])] = uint32_t(local_picks.size());
            local_picks.push_back(face_picks[size_t(j - first_pick)]);
        }
    }
    if (!order_samples(out, scratch, p_.threads, with_faces) || !pick) return;
    const std::vector<uint32_t>& order = scratch.order;
    pick->picked.swap(local_picks);
    pick->of_point.resize(order.size());
    for (size_t i = 0; i < order.size(); ++i) pick->of_point[i] = pick_of[order[i]];
}

} // namespace tom::detail
