// Metro-style two-sided surface distance, with CGAL AABB trees for the closest-point queries.
// The only translation unit of the project that includes CGAL.
//
// References: P. Cignoni, C. Rocchini, R. Scopigno. Metro: measuring error on simplified
// surfaces. Computer Graphics Forum 17(2), 1998 (sampling: vertices, edges, faces; distances
// relative to the bounding-box diagonal). P. Alliez, S. Tayeb, C. Wormser. 3D Fast
// Intersection and Distance Computation, CGAL manual (AABB tree, closest point with a hint).
//
// Speed: samples are generated face by face, so consecutive samples are close; each query
// starts from its predecessor's triangle (which bounds the search from the start) and goes down
// CGAL's tree nearer child first. Samples are processed in fixed chunks combined in order, so the
// figures do not depend on the number of threads. (Sorting the samples in Morton order was
// measured: it cost more instructions than it saved.)

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <thread>
#include <vector>

#include "tom/metrics.h"

namespace tom {

namespace {

using K = CGAL::Simple_cartesian<double>;
using Point = K::Point_3;
using Triangle = K::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

constexpr size_t kChunk = 4096;

void validate(const Surface& s, const char* which) {
    if (s.triangle_count == 0 || s.positions == nullptr || s.indices == nullptr)
        throw std::invalid_argument(std::string(which) + " surface has no triangle");
    for (size_t i = 0; i < s.triangle_count * 3; ++i)
        if (s.indices[i] >= s.vertex_count)
            throw std::invalid_argument(std::string(which) + " surface: index " + std::to_string(s.indices[i]) + " out of range");
}

Point point(const Surface& s, uint32_t v) { return Point(s.positions[3 * size_t(v)], s.positions[3 * size_t(v) + 1], s.positions[3 * size_t(v) + 2]); }

double triangle_area(const Point& a, const Point& b, const Point& c) {
    const K::Vector_3 n = CGAL::cross_product(b - a, c - a);
    return 0.5 * std::sqrt(n.squared_length());
}

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
};

struct Samples {
    std::vector<Point> points;
    uint64_t vertex = 0, edge = 0, face = 0;
    double area = 0;
};

double surface_area(const Surface& s) {
    double area = 0;
    for (size_t t = 0; t < s.triangle_count; ++t)
        area += triangle_area(point(s, s.indices[3 * t]), point(s, s.indices[3 * t + 1]), point(s, s.indices[3 * t + 2]));
    return area;
}

// Vertices first, then points along the edges, then area-uniform random points on the faces,
// about `target` in all (Metro's order and budget).
Samples sample_surface(const Surface& s, uint64_t target, const DistanceParams& p) {
    Samples out;
    out.area = surface_area(s);
    const double per_area = out.area > 0 ? double(target) / out.area : 0.0;
    if (p.vertex_samples) {
        std::vector<uint8_t> used(s.vertex_count, 0);
        for (size_t i = 0; i < s.triangle_count * 3; ++i) used[s.indices[i]] = 1;
        for (uint32_t v = 0; v < s.vertex_count; ++v)
            if (used[v]) out.points.push_back(point(s, v));
        out.vertex = out.points.size();
    }
    if (p.edge_samples && per_area > 0) {
        std::vector<std::pair<uint32_t, uint32_t>> edges;
        edges.reserve(s.triangle_count * 3);
        for (size_t t = 0; t < s.triangle_count; ++t)
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = s.indices[3 * t + k], b = s.indices[3 * t + (k + 1) % 3];
                edges.push_back({std::min(a, b), std::max(a, b)});
            }
        std::sort(edges.begin(), edges.end());
        edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
        const double per_length = std::sqrt(per_area);
        for (const auto& [a, b] : edges) {
            const Point pa = point(s, a), pb = point(s, b);
            const int n = int(std::sqrt(CGAL::squared_distance(pa, pb)) * per_length);
            for (int i = 1; i <= n; ++i) {
                const double t = double(i) / double(n + 1);
                out.points.push_back(pa + t * (pb - pa));
            }
        }
        out.edge = out.points.size() - out.vertex;
    }
    const double remaining = double(target) - double(out.points.size());
    if (p.face_samples && remaining > 0 && out.area > 0) {
        Random rng{p.seed * 0x2545F4914F6CDD1DULL + s.triangle_count};
        for (size_t t = 0; t < s.triangle_count; ++t) {
            const Point a = point(s, s.indices[3 * t]), b = point(s, s.indices[3 * t + 1]), c = point(s, s.indices[3 * t + 2]);
            // each face gets its expected share, the fraction rounded at random: area-uniform overall
            const double expected = remaining * triangle_area(a, b, c) / out.area;
            const uint64_t n = uint64_t(expected + rng.uniform());
            // stratified as Metro's similar-triangles sampling: the face is cut into m x m similar
            // triangles, one random point in each, visited row by row in serpentine order so
            // consecutive samples are neighbours; the n - m^2 left over fall anywhere on the face
            const uint64_t m = uint64_t(std::sqrt(double(n)));
            auto random_in = [&](const Point& p0, const Point& p1, const Point& p2) {
                double u = rng.uniform(), v = rng.uniform();
                if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
                out.points.push_back(p0 + u * (p1 - p0) + v * (p2 - p0));
            };
            auto grid = [&](uint64_t i, uint64_t j) { return a + (double(i) / double(m)) * (b - a) + (double(j) / double(m)) * (c - a); };
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
            for (uint64_t i = m * m; i < n; ++i) random_in(a, b, c);
        }
        out.face = out.points.size() - out.vertex - out.edge;
    }
    return out;
}

struct Mesh3 {
    std::vector<Triangle> triangles;
    std::vector<double> planes;  // per triangle: unit normal and offset (zero for a degenerate one)
    Tree tree;
    explicit Mesh3(const Surface& s) {
        triangles.reserve(s.triangle_count);
        planes.reserve(4 * s.triangle_count);
        for (size_t t = 0; t < s.triangle_count; ++t) {
            const Point a = point(s, s.indices[3 * t]), b = point(s, s.indices[3 * t + 1]), c = point(s, s.indices[3 * t + 2]);
            triangles.emplace_back(a, b, c);
            const K::Vector_3 n = CGAL::cross_product(b - a, c - a);
            const double len = std::sqrt(n.squared_length());
            if (len > 0)
                planes.insert(planes.end(), {n.x() / len, n.y() / len, n.z() / len, -(n.x() * a.x() + n.y() * a.y() + n.z() * a.z()) / len});
            else
                planes.insert(planes.end(), {0.0, 0.0, 0.0, 0.0});
        }
        tree.insert(triangles.begin(), triangles.end());
        tree.build();
    }
};

// Closest point of triangle (a, b, c) to p, by the Voronoi regions of its vertices, edges and
// face (Ericson, Real-Time Collision Detection, 5.1.5): a handful of dot products, no branches
// into generic kernel code. Returns the squared distance.
struct V3 {
    double x, y, z;
};
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 v3(const Point& p) { return {p.x(), p.y(), p.z()}; }

inline double closest_on_triangle(V3 p, V3 a, V3 b, V3 c, V3& out) {
    auto at = [&](V3 q) {  // the answer: q, and its squared distance to p
        out = q;
        const V3 d = p - q;
        return dot(d, d);
    };
    const V3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return at(a);  // vertex region a
    const V3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return at(b);  // vertex region b
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return at(a + (d1 / (d1 - d3)) * ab);  // edge ab
    const V3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return at(c);  // vertex region c
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return at(a + (d2 / (d2 - d6)) * ac);  // edge ac
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return at(b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b));  // edge bc
    const double denom = va + vb + vc;
    if (denom != 0) return at(a + (vb / denom) * ab + (vc / denom) * ac);  // the face
    // zero-area triangle: its longest edge decides
    V3 best = a;
    double best_d = dot(p - a, p - a);
    const V3 ends[3][2] = {{a, b}, {b, c}, {c, a}};
    for (const auto& e : ends) {
        const V3 d = e[1] - e[0];
        const double len2 = dot(d, d);
        const double t = len2 > 0 ? std::min(1.0, std::max(0.0, dot(p - e[0], d) / len2)) : 0.0;
        const V3 q = e[0] + t * d;
        if (dot(p - q, p - q) < best_d) best = q, best_d = dot(p - q, p - q);
    }
    return at(best);
}

using Node = CGAL::AABB_node<CGAL::AABB_traits<K, Primitive>>;

// Squared distance from p to an axis-aligned box (0 inside).
inline double axis_gap(double lo, double hi, double x) { return x < lo ? lo - x : (x > hi ? x - hi : 0.0); }
inline double box_d2(const CGAL::Bbox_3& b, V3 p) {
    const double dx = axis_gap(b.xmin(), b.xmax(), p.x), dy = axis_gap(b.ymin(), b.ymax(), p.y), dz = axis_gap(b.zmin(), b.zmax(), p.z);
    return dx * dx + dy * dy + dz * dz;
}

struct Partial {
    double max = 0, sum = 0, sum_squares = 0;
};

// Visits every triangle within sqrt(radius2) of query: visit(triangle iterator, closest point).
template <class Visit>
struct WithinTraits {
    V3 query;
    double radius2;
    Visit& visit;
    bool go_further() const { return true; }
    bool do_intersect(const Point&, const Node& node) const { return box_d2(node.bbox(), query) <= radius2; }
    void intersection(const Point&, const Primitive& primitive) {
        const Triangle& t = *primitive.id();
        V3 q;
        if (closest_on_triangle(query, v3(t[0]), v3(t[1]), v3(t[2]), q) <= radius2) visit(primitive.id(), q);
    }
};

// Runs work(chunk, begin, end) over [0, n) in chunks of kChunk on up to `threads` threads (0: every
// core); results kept per chunk and combined in chunk order give the same figures for any count.
template <class Work>
size_t parallel_chunks(size_t n, unsigned threads, Work&& work) {
    const size_t chunks = (n + kChunk - 1) / kChunk;
    std::atomic<size_t> next{0};
    auto run = [&] {
        for (size_t c; (c = next++) < chunks;) work(c, c * kChunk, std::min(n, c * kChunk + kChunk));
    };
    if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
    threads = unsigned(std::min<size_t>(threads, std::max<size_t>(1, chunks)));
    std::vector<std::thread> pool;
    for (unsigned k = 1; k < threads; ++k) pool.emplace_back(run);
    run();
    for (std::thread& t : pool) t.join();
    return chunks;
}

// Nearest-triangle search down CGAL's AABB tree (its nodes, boxes and primitives), nearer child
// first, and the farther one only if its box is still nearer than the best triangle found in the
// nearer one (CGAL's traversal_with_priority decides both children before descending).
struct Nearest {
    V3 query;
    double best_d2;
    TriangleIterator best;
    V3 best_point;
    TriangleIterator first;  // the target's triangles, for the index of a primitive
    const double* planes;

    void leaf(const Primitive& primitive) {
        // the distance to the triangle's plane bounds the distance to the triangle from below
        const double* plane = planes + 4 * size_t(primitive.id() - first);
        const double above = plane[0] * query.x + plane[1] * query.y + plane[2] * query.z + plane[3];
        if (above * above >= best_d2) return;
        const Triangle& t = *primitive.id();
        V3 q;
        const double d2 = closest_on_triangle(query, v3(t[0]), v3(t[1]), v3(t[2]), q);
        if (d2 < best_d2) best_d2 = d2, best = primitive.id(), best_point = q;
    }
    void visit(const Node& node, size_t primitives) {
        if (primitives == 2) {
            leaf(node.left_data());
            leaf(node.right_data());
            return;
        }
        if (primitives == 3) {
            leaf(node.left_data());
            if (box_d2(node.right_child().bbox(), query) < best_d2) visit(node.right_child(), 2);
            return;
        }
        const size_t left = primitives / 2, right = primitives - left;
        const double dl = box_d2(node.left_child().bbox(), query), dr = box_d2(node.right_child().bbox(), query);
        if (dl <= dr) {
            if (dl < best_d2) visit(node.left_child(), left);
            if (dr < best_d2) visit(node.right_child(), right);
        } else {
            if (dr < best_d2) visit(node.right_child(), right);
            if (dl < best_d2) visit(node.left_child(), left);
        }
    }
};

// The closest triangle of `target` to p, its squared distance `d2` and (when asked) the closest
// point on it; `previous` (the previous sample's triangle, near in sample order) bounds the
// search from the start.
TriangleIterator closest(const Mesh3& target, const Point& p, TriangleIterator previous, double& d2, V3* point = nullptr) {
    Nearest search;
    search.query = v3(p);
    search.first = target.triangles.begin();
    search.planes = target.planes.data();
    search.best_d2 = closest_on_triangle(search.query, v3((*previous)[0]), v3((*previous)[1]), v3((*previous)[2]), search.best_point);
    search.best = previous;
    if (target.triangles.size() >= 2 && search.best_d2 > 0) search.visit(*target.tree.root_node(), target.triangles.size());
    d2 = search.best_d2;
    if (point) *point = search.best_point;
    return search.best;
}

OneSidedDistance measure(const Samples& samples, const Mesh3& target, unsigned threads) {
    const size_t n = samples.points.size();
    std::vector<Partial> partial((n + kChunk - 1) / kChunk);
    parallel_chunks(n, threads, [&](size_t c, size_t begin, size_t end) {
        Partial& r = partial[c];
        TriangleIterator previous = target.triangles.begin();
        for (size_t i = begin; i < end; ++i) {
            double d2;
            previous = closest(target, samples.points[i], previous, d2);
            const double d = std::sqrt(d2);
            r.max = std::max(r.max, d);
            r.sum += d;
            r.sum_squares += d2;
        }
    });
    OneSidedDistance out;
    double sum = 0, sum_squares = 0;
    for (const Partial& p : partial) {  // in order: the same figures whatever the thread count
        out.max = std::max(out.max, p.max);
        sum += p.sum;
        sum_squares += p.sum_squares;
    }
    out.samples = n;
    out.vertex_samples = samples.vertex;
    out.edge_samples = samples.edge;
    out.face_samples = samples.face;
    out.sampled_area = samples.area;
    out.mean = n ? sum / double(n) : 0.0;
    out.rms = n ? std::sqrt(sum_squares / double(n)) : 0.0;
    return out;
}

void bounds(const Surface& s, double lo[3], double hi[3]) {
    for (size_t i = 0; i < s.triangle_count * 3; ++i)
        for (int k = 0; k < 3; ++k) {
            const double x = s.positions[3 * size_t(s.indices[i]) + k];
            lo[k] = std::min(lo[k], x);
            hi[k] = std::max(hi[k], x);
        }
}

double enlarged_union_diagonal(const Surface& a, const Surface& b) {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    bounds(a, lo, hi);
    bounds(b, lo, hi);
    const double diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    const double grow = 2.0 * 0.02 * diag;  // each side moves out by 2% of the diagonal
    return std::sqrt((hi[0] - lo[0] + grow) * (hi[0] - lo[0] + grow) + (hi[1] - lo[1] + grow) * (hi[1] - lo[1] + grow) +
                     (hi[2] - lo[2] + grow) * (hi[2] - lo[2] + grow));
}

uint64_t sample_target(const Surface& a, const Surface& b, const DistanceParams& p) {
    const uint64_t n = uint64_t(std::llround(p.samples_per_face * double(std::max(a.triangle_count, b.triangle_count))));
    return p.max_samples ? std::min(n, p.max_samples) : n;
}

// Attribute samples: area-uniform random points of the faces, kept as (face, barycentrics) so
// the original's attributes can be interpolated there.
struct FaceSample {
    uint32_t face;
    double u, v;  // weights of corners 1 and 2
};

std::vector<FaceSample> face_samples(const Surface& s, uint64_t target, uint64_t seed) {
    std::vector<FaceSample> out;
    const double area = surface_area(s);
    if (!(area > 0)) return out;
    Random rng{seed * 0x9E3779B97F4A7C15ULL + s.triangle_count};
    for (size_t t = 0; t < s.triangle_count; ++t) {
        const double expected = double(target) * triangle_area(point(s, s.indices[3 * t]), point(s, s.indices[3 * t + 1]), point(s, s.indices[3 * t + 2])) / area;
        for (uint64_t k = 0, n = uint64_t(expected + rng.uniform()); k < n; ++k) {
            double u = rng.uniform(), v = rng.uniform();
            if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
            out.push_back({uint32_t(t), u, v});
        }
    }
    return out;
}

// Barycentric weights of q (in the triangle's plane) in triangle (a, b, c).
void barycentric(V3 q, V3 a, V3 b, V3 c, double w[3]) {
    const V3 e0 = b - a, e1 = c - a, e2 = q - a;
    const double d00 = dot(e0, e0), d01 = dot(e0, e1), d11 = dot(e1, e1), d20 = dot(e2, e0), d21 = dot(e2, e1);
    const double den = d00 * d11 - d01 * d01;
    if (!(std::fabs(den) > 0)) {
        w[0] = 1, w[1] = w[2] = 0;
        return;
    }
    w[1] = (d11 * d20 - d01 * d21) / den;
    w[2] = (d00 * d21 - d01 * d20) / den;
    w[0] = 1.0 - w[1] - w[2];
}

// An attribute of `width` floats interpolated in face t of s with weights w.
void interpolate(const Surface& s, const float* attribute, int width, size_t t, const double w[3], double* out) {
    for (int k = 0; k < width; ++k) {
        out[k] = 0;
        for (int c = 0; c < 3; ++c) out[k] += w[c] * attribute[size_t(width) * s.indices[3 * t + size_t(c)] + size_t(k)];
    }
}

struct AttributePartial {
    double normal_sum = 0, normal_max = 0, uv_sum = 0, uv_max = 0;
    uint64_t normal_n = 0, uv_n = 0;
};

AttributeDeviation measure_attributes(const Surface& original, const SurfaceAttributes& oa, const std::vector<FaceSample>& samples,
                                      const Surface& simplified, const SurfaceAttributes& sa, const Mesh3& target, unsigned threads) {
    AttributeDeviation out;
    out.normals = oa.normals && sa.normals;
    out.texcoords = oa.texcoords && sa.texcoords;
    if (!out.normals && !out.texcoords) return out;
    std::vector<AttributePartial> partial((samples.size() + kChunk - 1) / kChunk);
    constexpr double degrees = 180.0 / 3.14159265358979323846;
    parallel_chunks(samples.size(), threads, [&](size_t c, size_t begin, size_t end) {
        AttributePartial& r = partial[c];
        TriangleIterator previous = target.triangles.begin();
        for (size_t i = begin; i < end; ++i) {
            const FaceSample& fs = samples[i];
            const double wo[3] = {1.0 - fs.u - fs.v, fs.u, fs.v};
            const Point a = point(original, original.indices[3 * size_t(fs.face)]), b = point(original, original.indices[3 * size_t(fs.face) + 1]),
                        cc = point(original, original.indices[3 * size_t(fs.face) + 2]);
            const Point p = a + fs.u * (b - a) + fs.v * (cc - a);
            double d2;
            V3 q;
            previous = closest(target, p, previous, d2, &q);
            const size_t t = size_t(previous - target.triangles.begin());
            double ws[3];
            barycentric(q, v3((*previous)[0]), v3((*previous)[1]), v3((*previous)[2]), ws);
            if (out.normals) {
                double n0[3], n1[3];
                interpolate(original, oa.normals, 3, fs.face, wo, n0);
                interpolate(simplified, sa.normals, 3, t, ws, n1);
                const double l0 = std::sqrt(n0[0] * n0[0] + n0[1] * n0[1] + n0[2] * n0[2]), l1 = std::sqrt(n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]);
                if (l0 > 0 && l1 > 0) {
                    const double cosine = std::max(-1.0, std::min(1.0, (n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2]) / (l0 * l1)));
                    const double angle = std::acos(cosine) * degrees;
                    r.normal_sum += angle;
                    r.normal_max = std::max(r.normal_max, angle);
                    ++r.normal_n;
                }
            }
            if (out.texcoords) {
                // at the nearest point; but a displacement of more than a quarter of the texture
                // there is a jump across a seam line that moved (the two charts meet along it), so
                // then the nearest point within one triangle's reach (the nearest triangle's
                // longest edge) with a displacement under that bound counts, if there is one
                constexpr double jump = 0.25;
                double t0[2], t1[2];
                interpolate(original, oa.texcoords, 2, fs.face, wo, t0);
                interpolate(simplified, sa.texcoords, 2, t, ws, t1);
                double d = std::hypot(t0[0] - t1[0], t0[1] - t1[1]);
                if (d > jump) {
                    const Triangle& nearest = *previous;
                    double reach2 = 0;
                    for (int k = 0; k < 3; ++k) reach2 = std::max(reach2, CGAL::squared_distance(nearest[k], nearest[(k + 1) % 3]));
                    const double radius = std::sqrt(d2) + std::sqrt(reach2);
                    double best_d2 = INFINITY;
                    auto consider = [&](TriangleIterator it, V3 at) {
                        double w[3], tc[2];
                        barycentric(at, v3((*it)[0]), v3((*it)[1]), v3((*it)[2]), w);
                        interpolate(simplified, sa.texcoords, 2, size_t(it - target.triangles.begin()), w, tc);
                        const double du = std::hypot(t0[0] - tc[0], t0[1] - tc[1]);
                        const V3 off = at - v3(p);
                        if (du <= jump && dot(off, off) < best_d2) best_d2 = dot(off, off), d = du;
                    };
                    WithinTraits<decltype(consider)> within{v3(p), radius * radius, consider};
                    target.tree.traversal(p, within);
                }
                r.uv_sum += d;
                r.uv_max = std::max(r.uv_max, d);
                ++r.uv_n;
            }
        }
    });
    double normal_sum = 0, uv_sum = 0;
    uint64_t normal_n = 0, uv_n = 0;
    for (const AttributePartial& p : partial) {
        normal_sum += p.normal_sum, uv_sum += p.uv_sum, normal_n += p.normal_n, uv_n += p.uv_n;
        out.normal_max_degrees = std::max(out.normal_max_degrees, p.normal_max);
        out.uv_max = std::max(out.uv_max, p.uv_max);
    }
    out.samples = samples.size();
    out.normal_mean_degrees = normal_n ? normal_sum / double(normal_n) : 0.0;
    out.uv_mean = uv_n ? uv_sum / double(uv_n) : 0.0;
    return out;
}

} // namespace

struct MetroReference::Impl {
    Surface original;
    DistanceParams params;
    SurfaceAttributes attributes;
    Mesh3 mesh;
    mutable std::vector<std::pair<uint64_t, Samples>> samples;  // by target count
    mutable std::vector<FaceSample> attribute_samples;          // made on first use
    Impl(const Surface& s, const DistanceParams& p, const SurfaceAttributes& a) : original(s), params(p), attributes(a), mesh(s) {}
    const Samples& samples_for(uint64_t target) const {
        for (const auto& [t, smp] : samples)
            if (t == target) return smp;
        samples.emplace_back(target, sample_surface(original, target, params));
        return samples.back().second;
    }
};

MetroReference::MetroReference(const Surface& original, const DistanceParams& params, const SurfaceAttributes& attributes) {
    validate(original, "original");
    impl_ = std::make_unique<Impl>(original, params, attributes);
}
MetroReference::~MetroReference() = default;
MetroReference::MetroReference(MetroReference&&) noexcept = default;
MetroReference& MetroReference::operator=(MetroReference&&) noexcept = default;

Distance MetroReference::compare(const Surface& simplified) const {
    AttributeDeviation unused;
    return compare(simplified, SurfaceAttributes{}, unused);
}

Distance MetroReference::compare(const Surface& simplified, const SurfaceAttributes& attributes, AttributeDeviation& deviation) const {
    validate(simplified, "simplified");
    const uint64_t target = sample_target(impl_->original, simplified, impl_->params);
    const Mesh3 other(simplified);
    if ((attributes.normals && impl_->attributes.normals) || (attributes.texcoords && impl_->attributes.texcoords)) {
        if (impl_->attribute_samples.empty())
            impl_->attribute_samples = face_samples(impl_->original, uint64_t(std::llround(impl_->params.attribute_samples_per_face * double(impl_->original.triangle_count))),
                                                    impl_->params.seed);
        deviation = measure_attributes(impl_->original, impl_->attributes, impl_->attribute_samples, simplified, attributes, other, impl_->params.threads);
    } else {
        deviation = AttributeDeviation{};
    }
    Distance d;
    d.forward = measure(impl_->samples_for(target), other, impl_->params.threads);
    d.backward = measure(sample_surface(simplified, target, impl_->params), impl_->mesh, impl_->params.threads);
    d.hausdorff = std::max(d.forward.max, d.backward.max);
    d.diagonal = enlarged_union_diagonal(impl_->original, simplified);
    return d;
}

Distance metro_distance(const Surface& original, const Surface& simplified, const DistanceParams& params) {
    return MetroReference(original, params).compare(simplified);
}

} // namespace tom
