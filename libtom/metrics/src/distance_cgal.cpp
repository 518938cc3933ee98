// Metro-style two-sided surface distance, with CGAL AABB trees for the closest-point queries.
// The only translation unit of the project that includes CGAL.
//
// References: P. Cignoni, C. Rocchini, R. Scopigno. Metro: measuring error on simplified
// surfaces. Computer Graphics Forum 17(2), 1998 (sampling: vertices, edges, faces; distances
// relative to the bounding-box diagonal). P. Alliez, S. Tayeb, C. Wormser. 3D Fast
// Intersection and Distance Computation, CGAL manual (AABB tree, closest point with a hint).
//
// Speed: the samples of each side are sorted in Morton order once, and grouped by the cells of
// an octree level chosen for the target (about kCellSamples samples a cell, cells at most
// kCellTriangles target triangles wide). Per cell, one descent of CGAL's tree finds the triangle
// c nearest to the cell's centre; every sample's distance to c bounds its distance to the
// surface, so a second descent collects every triangle that can be the nearest of one of the
// cell's samples; candidate by candidate, nearest box first, lower bounds (box, plane and edge
// lines) of its distance to the cell's samples are computed eight samples at a time (AVX2, in
// floats made conservative: candidates.h), and the exact distance only for the samples whose
// bound is under their best so far, until the boxes lie beyond every sample's best. Exact: the
// figures are those of a full nearest search per sample (to 2^-40 of the target's size, where a
// search stops: wide_tree.h). Samples are processed in fixed chunks combined in order, so the
// figures do not depend on the number of threads. Two descents a cell cost far less than one a
// sample. The descents read CGAL's hierarchy from a compact four-way copy (wide_tree.h), and the
// collecting one takes children left to right (ordering them by distance, as the nearest search
// must, would cost two box distances a node for nothing).
// With FaceHints (the error curve's: a level's faces over the original's), each point also
// starts from its face's hint: a descent of its own starts near its answer, and in a cell the
// nearer of the centre's triangle and the hint bounds the reach.

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "candidates.h"
#include "compact_tree.h"
#include "geometry.h"
#include "samples.h"
#include "wide_tree.h"
#include "tom/errors.h"
#include "tom/metrics/distance.h"

namespace tom {

namespace {

using namespace detail;

using K = CGAL::Simple_cartesian<double>;
using Point = K::Point_3;
using Triangle = K::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

// The bits of float(x) (x >= 0): ordered as the values; and back.
inline uint32_t float_bits(double x) {
    const float f = float(x);
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    return bits;
}
inline float bits_float(uint32_t bits) {
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

inline Point point(const Surface& s, uint32_t v) {
    const V3 p = vertex(s, v);
    return Point(p.x, p.y, p.z);
}

void validate(const Surface& s, const char* which) {
    if (s.triangle_count == 0 || s.positions == nullptr || s.indices == nullptr)
        throw ArgumentError(std::string(which) + " surface has no triangle");
    for (size_t i = 0; i < s.triangle_count * 3; ++i)
        if (s.indices[i] >= s.vertex_count)
            throw ArgumentError(std::string(which) + " surface: index " + std::to_string(s.indices[i]) + " out of range");
}

using Node = CGAL::AABB_node<CGAL::AABB_traits<K, Primitive>>;

// A part of CGAL's tree: a node of `count` leaves, or one leaf (count 1); `first`, the place of
// its first leaf in left-to-right order.
struct Part {
    const Node* node;
    const Primitive* leaf;
    size_t count;
    uint32_t first;
};

// A part's two halves, as CGAL lays a node out: two leaves under a node of 2, a leaf and a node
// of 2 under a node of 3, otherwise nodes of count / 2 and the rest.
void split(const Part& part, Part& l, Part& r) {
    if (part.count == 2) {
        l = {nullptr, &part.node->left_data(), 1, part.first}, r = {nullptr, &part.node->right_data(), 1, part.first + 1};
    } else if (part.count == 3) {
        l = {nullptr, &part.node->left_data(), 1, part.first}, r = {&part.node->right_child(), nullptr, 2, part.first + 1};
    } else {
        const size_t nl = part.count / 2;
        l = {&part.node->left_child(), nullptr, nl, part.first}, r = {&part.node->right_child(), nullptr, part.count - nl, part.first + uint32_t(nl)};
    }
}

// Every leaf of a part, left to right: leaf(primitive).
template <class Leaf>
void each_leaf(const Part& part, Leaf&& leaf) {
    if (part.count == 1) return leaf(*part.leaf);
    Part l, r;
    split(part, l, r);
    each_leaf(l, leaf);
    each_leaf(r, leaf);
}

// The corners of a CGAL box.
inline V3 low(const CGAL::Bbox_3& b) { return {b.xmin(), b.ymin(), b.zmin()}; }
inline V3 high(const CGAL::Bbox_3& b) { return {b.xmax(), b.ymax(), b.zmax()}; }

// A target mesh: its triangles as Flat records in the order of the leaves of CGAL's tree (a
// descent reads neighbouring records, not scattered ones), and that tree's hierarchy as a
// compact four-way copy. CGAL's tree and its triangles are needed only to build these, and go
// (they hold several times the records' memory).
struct Mesh3 {
    std::vector<Flat> flat;              // in leaf order
    std::vector<EdgeLines> lines;        // of each record, for the candidate bounds
    std::vector<uint32_t> triangle_of;   // record -> its triangle
    std::vector<uint32_t> slot;          // triangle -> its record
    explicit Mesh3(const Surface& s) {
        build_hierarchy(s);
        make_records(s);
    }
    // the leaf order and the four-way copy of CGAL's tree, which goes with its triangles before
    // the records are made (they held some 150 bytes a triangle more at the peak)
    void build_hierarchy(const Surface& s) {
        std::vector<Triangle> triangles;
        triangles.reserve(s.triangle_count);
        for (size_t t = 0; t < s.triangle_count; ++t)
            triangles.emplace_back(point(s, s.indices[3 * t]), point(s, s.indices[3 * t + 1]), point(s, s.indices[3 * t + 2]));
        Tree tree(triangles.begin(), triangles.end());
        tree.build();
        const Part root{triangles.size() >= 2 ? tree.root_node() : nullptr, nullptr, triangles.size(), 0};  // (a tree of one triangle has no node)
        triangle_of.reserve(triangles.size());
        if (triangles.size() == 1)
            triangle_of.push_back(0);
        else
            each_leaf(root, [&](const Primitive& p) { triangle_of.push_back(uint32_t(p.id() - triangles.begin())); });
        slot.resize(triangles.size());
        for (uint32_t i = 0; i < triangle_of.size(); ++i) slot[triangle_of[i]] = i;
        auto box = [&](const Part& part, V3& lo, V3& hi) {
            if (part.count == 1) {  // a leaf: its corners' box (as make_flat's)
                const size_t t = triangle_of[part.first];
                const V3 a = corner(s, t, 0), b = corner(s, t, 1), c = corner(s, t, 2);
                lo = {std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})};
                hi = {std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})};
            } else {
                lo = low(part.node->bbox()), hi = high(part.node->bbox());
            }
        };
        wide.build(root, split, box);
    }
    // the Flat records and edge lines, in leaf order
    void make_records(const Surface& s) {
        flat.reserve(triangle_of.size());
        lines.reserve(triangle_of.size());
        scale = std::sqrt(surface_area(s) / double(triangle_of.size()));
        for (const uint32_t t : triangle_of) {
            flat.push_back(make_flat(corner(s, t, 0), corner(s, t, 1), corner(s, t, 2)));
            lines.push_back(edge_lines(flat.back()));
        }
    }
    double scale = 0;  // the side of a square of a triangle's mean area
    WideTree wide;
    // whether record r at squared distance d is nearer than record `best` at `best_d2`: among
    // triangles at the same distance (a point nearest to an edge or a corner they share), the
    // one first in the mesh, so that which one a search meets first does not matter (the
    // attribute deviation interpolates the nearest triangle's normals: split at a crease); save
    // on the surface itself, where a descent stops at the first within WideTree's `enough`
    bool nearer(double d, uint32_t r, double best_d2, uint32_t best) const {
        return d < best_d2 || (d == best_d2 && triangle_of[r] < triangle_of[best]);
    }
};


struct Partial {
    double max = 0, sum = 0, sum_squares = 0;
};

constexpr uint32_t kNoRecord = FaceHints::kNone;

// The record of the triangle of `target` nearest to p, and its squared distance `d2`; `hint` (a
// triangle near p) and `other` (another, or kNoRecord), the nearer of them, bound the search from
// the start. Nearer nodes first, and a farther one only if its box is still nearer than the best
// triangle found.
uint32_t nearest(const Mesh3& target, V3 p, uint32_t hint, double& d2, uint32_t other = kNoRecord) {
    double best_d2 = distance2(target.flat[hint], p);
    uint32_t best = hint;
    if (other != kNoRecord && other != hint) {
        const double d = distance2(target.flat[other], p);
        if (target.nearer(d, other, best_d2, best)) best_d2 = d, best = other;
    }
    const WideTree::Query q = target.wide.query(p, p);
    if (target.flat.size() >= 2 && best_d2 > q.enough) {
        auto leaf = [&](uint32_t t) {
            const Flat& f = target.flat[t];
            // the distance to the triangle's plane bounds the distance to the triangle from below
            const double above = dot(f.normal, p) + f.offset;
            if (above * above > best_d2) return;
            const double d = distance2_below(f, p, best_d2);
            if (target.nearer(d, t, best_d2, best)) best_d2 = d, best = t;
        };
        target.wide.nearest(q, leaf, [&] { return best_d2; });
    }
    d2 = best_d2;
    return best;
}

// Nearest triangles for runs of Morton-sorted points that share a grid cell, exactly. Two
// descents per run (the centre's nearest triangle c, then every triangle whose box is within
// reach) find every triangle that can be the nearest of one of its points; then candidate by
// candidate, each point's lower bound of its distance to it (box, plane and edge lines, eight
// points at a time: candidates.h), and the exact distance only where the bound is below the
// point's best so far (from c at first).
struct RunSearch {
    const Mesh3& target;
    const V3* points;
    const uint32_t* starts = nullptr;  // per point: a record near it (FaceHints), or kNoRecord; or none
    uint32_t hint = 0;  // the record of the last nearest triangle: a first bound for the next run
    std::vector<uint64_t> keyed;  // (box distance, record) of each candidate, in that order
    std::vector<float> qx, qy, qz, limit;  // the run's points relative to its centre, their bests
    std::vector<uint32_t> record, which;  // each point's nearest so far; the points a candidate may be nearer to
    std::vector<double> upper;  // each point's squared distance to its nearest so far
    std::vector<double> kept;  // the squared distances of the points a candidate's bound keeps
    RunSearch(const Mesh3& t, const V3* p) : target(t), points(p) {}

    // one descent of the tree for each point of [b, e)
    template <class Emit>
    void each(size_t b, size_t e, Emit& emit) {
        for (size_t i = b; i < e; ++i) {
            double d2;
            hint = nearest(target, points[i], hint, d2, starts ? starts[i] : kNoRecord);
            emit(i, d2, hint);
        }
    }

    // run() on each range of [begin, end) whose keys agree above bit `shift` (one grid cell)
    template <class Emit>
    void runs(const uint64_t* keys, size_t begin, size_t end, int shift, Emit& emit) {
        for (size_t i = begin; i < end;) {
            size_t j = i + 1;
            while (j < end && (keys[j] >> shift) == (keys[i] >> shift)) ++j;
            run(i, j, emit);
            i = j;
        }
    }

    template <class Emit>
    void run(size_t b, size_t e, Emit& emit) {
        // a few points (sparse samples): a descent each costs less than gathering candidates
        if (e - b < 8 || target.flat.size() < 8) return each(b, e, emit);
        V3 lo = points[b], hi = lo;
        for (size_t i = b + 1; i < e; ++i) {
            const V3 p = points[i];
            lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
            hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
        }
        const V3 centre = 0.5 * (lo + hi);
        // the centre's nearest triangle c bounds every point's distance: d(p) <= d(p, c), so each
        // point's nearest triangle has its box within U = max_p d(p, c) of the run's box. U is at
        // most d(centre) + the run's spread (the bound of the single descent that collected while
        // finding c, used before) and much less where the points lie far from the surface (about
        // sqrt(d^2 + spread^2) against d + spread), which shrinks the candidates of far runs.
        double centre_d2;
        const uint32_t c = nearest(target, centre, hint, centre_d2, starts ? starts[b + (e - b) / 2] : kNoRecord);
        const size_t n = e - b;
        upper.resize(n);
        record.assign(n, c);
        distances2(target.flat[c], points + b, n, upper.data());
        double widest = 0;  // (a local: reach2 is captured below, which kept it in memory through this loop)
        for (size_t i = 0; i < n; ++i) {
            const uint32_t start = starts ? starts[b + i] : kNoRecord;
            if (start != kNoRecord && start != c) {  // a point's own start, when nearer, shrinks the reach
                const double d2 = distance2(target.flat[start], points[b + i]);
                if (d2 < upper[i]) upper[i] = d2, record[i] = start;
            }
            widest = std::max(widest, upper[i]);
        }
        const double reach2 = widest * (1.0 + 1e-9);  // widened against rounding
        // the candidates in order of their boxes' distance to the run's box, which no point of the
        // run is nearer to them than: the scan below stops at the first that lies beyond every
        // point's best. Keys: that distance as float bits (ordered as the floats: non-negative),
        // the record below
        keyed.clear();
        const WideTree::Query around = target.wide.query(lo, hi);
        target.wide.within(around, reach2, [&](uint32_t t, float d2) {
            // (the tree's own single-precision box distance, made a floor: the triangle's record
            // is not read here)
            keyed.push_back(uint64_t(float_bits(WideTree::floor(around, d2))) << 32 | t);
        });
        const size_t m = keyed.size();
        // with many candidates, every point is far from a fine surface and its own descent is
        // cheaper than the scan
        if (m > 1024) return each(b, e, emit);
        std::sort(keyed.begin(), keyed.end());
        const double spread = 0.5 * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
        // candidate by candidate, nearest box first, each against every point of the run (eight
        // at a time) while its box is nearer than the farthest point's best (c, every point's
        // first, is not one again); a point's limit is a float of its best, which a candidate
        // nearer than the best is always under (its bound is lowered by 2^-9 of it, the float's
        // rounding is 2^-24)
        const size_t padded = (n + 7) & ~size_t(7);
        qx.resize(padded), qy.resize(padded), qz.resize(padded), limit.resize(padded), which.resize(padded + 8), kept.resize(padded);
        for (size_t i = 0; i < padded; ++i) {
            if (i >= n) {
                qx[i] = qy[i] = qz[i] = 0.0f, limit[i] = -std::numeric_limits<float>::infinity();
                continue;
            }
            const V3 r = points[b + i] - centre;
            qx[i] = float(r.x), qy[i] = float(r.y), qz[i] = float(r.z);
            limit[i] = float(upper[i]);
        }
        double farthest = widest;
        for (size_t k = 0; k < m; ++k) {
            if (k % 8 == 0 && k) {  // (the bests only fall: a stale farthest is still an upper bound)
                farthest = 0;
                for (size_t i = 0; i < n; ++i) farthest = std::max(farthest, upper[i]);
            }
            const float floor = bits_float(uint32_t(keyed[k] >> 32));
            if (floor > float(farthest * (1.0 + 1e-6))) break;  // sorted: every later box is as far
            const uint32_t t = uint32_t(keyed[k]);
            if (t == c) continue;  // (every best is at most its distance already)
            const Flat& f = target.flat[t];
            const size_t count = points_below(candidate_bound(f, target.lines[t], centre, spread), qx.data(), qy.data(), qz.data(), limit.data(), padded, which.data());
            // their exact distances (distance2_below() would stop at a bound for the points the
            // candidate is not nearer to, for the same outcome: the bound is above the best)
            distances2_at(f, points + b, which.data(), count, kept.data());
            for (size_t h = 0; h < count; ++h) {
                const size_t i = which[h];
                const double d2 = kept[h];
                if (target.nearer(d2, t, upper[i], record[i])) upper[i] = d2, record[i] = t, limit[i] = float(d2);
            }
        }
        for (size_t i = 0; i < n; ++i) emit(b + i, upper[i], record[i]);
        hint = record[n - 1];
    }
};

// The grid whose cells group samples into runs (RunSearch::runs takes keys >> this shift): a
// level of the samples' Morton octree, cells of about kCellSamples samples but not wider than
// kCellTriangles target triangles (where samples are sparse, a cell's candidates would be many).
constexpr double kCellSamples = 128.0, kCellTriangles = 2.5;

int cell_shift(const Samples& samples, const Mesh3& target) {
    if (samples.points.empty() || !(samples.extent > 0)) return 63;
    const double want = std::min(std::sqrt(kCellSamples * samples.area / double(samples.points.size())), kCellTriangles * target.scale);
    const double level = std::round(std::log2(want * double(1u << kMortonBits) / samples.extent));
    return 3 * int(std::max(0.0, std::min(double(kMortonBits), level)));
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

// The original's attributes at its picked face samples, interpolated once for every level
// compared (the same values add() interpolated each time before): per pick, the normal and its
// length (four), the texture coordinates (two).
struct PickedAttributes {
    std::vector<double> normal, uv;
    void make(const Surface& original, const SurfaceAttributes& oa, const PickedFaceSamples& picks, unsigned threads) {
        const size_t n = picks.picked.size();
        normal.resize(oa.normals ? 4 * n : 0);
        uv.resize(oa.texcoords ? 2 * n : 0);
        parallel_chunks(n, threads, [&](size_t, size_t begin, size_t end) {
            for (size_t k = begin; k < end; ++k) {
                const FaceSample& fs = picks.picked[k];
                const double wo[3] = {1.0 - fs.u - fs.v, fs.u, fs.v};
                if (oa.normals) {
                    double* n0 = &normal[4 * k];
                    interpolate(original, oa.normals, 3, fs.face, wo, n0);
                    n0[3] = std::sqrt(n0[0] * n0[0] + n0[1] * n0[1] + n0[2] * n0[2]);
                }
                if (oa.texcoords) interpolate(original, oa.texcoords, 2, fs.face, wo, &uv[2 * k]);
            }
        });
    }
};

// The attribute deviation at the picked face samples of the original, from the nearest points
// the forward direction finds for them (measure() calls add() for those).
struct AttributeProbe {
    const PickedFaceSamples& picks;
    const PickedAttributes& at_picks;
    const Surface& simplified;
    const SurfaceAttributes& sa;
    const Mesh3& target;
    bool normals, texcoords;

    // at pick k, point p, whose nearest triangle (record `slot`) is at squared distance d2
    void add(AttributePartial& r, uint32_t k, V3 p, double d2, uint32_t slot) const {
        constexpr double degrees = 180.0 / 3.14159265358979323846;
        const Flat& nearest = target.flat[slot];
        const size_t t = target.triangle_of[slot];
        double ws[3];
        nearest_point(nearest, p, ws);
        if (normals) {
            double n1[3];
            const double* n0 = &at_picks.normal[4 * size_t(k)];
            interpolate(simplified, sa.normals, 3, t, ws, n1);
            const double l0 = n0[3], l1 = std::sqrt(n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]);
            if (l0 > 0 && l1 > 0) {
                const double cosine = std::max(-1.0, std::min(1.0, (n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2]) / (l0 * l1)));
                const double angle = std::acos(cosine) * degrees;
                r.normal_sum += angle;
                r.normal_max = std::max(r.normal_max, angle);
                ++r.normal_n;
            }
        }
        if (texcoords) {
            // at the nearest point; but a displacement of more than a quarter of the texture
            // there is a jump across a seam line that moved (the two charts meet along it), so
            // then the nearest point within one triangle's reach (the nearest triangle's
            // longest edge) with a displacement under that bound counts, if there is one
            constexpr double jump = 0.25;
            double t1[2];
            const double* t0 = &at_picks.uv[2 * size_t(k)];
            interpolate(simplified, sa.texcoords, 2, t, ws, t1);
            double d = std::hypot(t0[0] - t1[0], t0[1] - t1[1]);
            if (d > jump) {
                const V3 e2 = nearest.e1 - nearest.e0;
                const double reach2 = std::max({nearest.d00, nearest.d11, dot(e2, e2)});
                const double radius = std::sqrt(d2) + std::sqrt(reach2);
                double best_d2 = INFINITY;
                auto consider = [&](uint32_t record) {
                    double w[3], tc[2];
                    const V3 at = nearest_point(target.flat[record], p, w);
                    interpolate(simplified, sa.texcoords, 2, target.triangle_of[record], w, tc);
                    const double du = std::hypot(t0[0] - tc[0], t0[1] - tc[1]);
                    const V3 off = at - p;
                    if (du <= jump && dot(off, off) < best_d2) best_d2 = dot(off, off), d = du;
                };
                const double radius2 = radius * radius;
                target.wide.within(target.wide.query(p, p), radius2, [&](uint32_t record, float) {
                    if (distance2(target.flat[record], p) <= radius2) consider(record);
                });
            }
            r.uv_sum += d;
            r.uv_max = std::max(r.uv_max, d);
            ++r.uv_n;
        }
    }
};

// Of each sample, in order, the face `hint` gives for its own face (face of the sampled surface
// -> a face of the target near it, or kNoRecord; asked once for each run of samples on one
// face), checked against the target's `faces` (`which` names the hint in errors); empty
// without a hint.
std::vector<uint32_t> hinted_faces(const Samples& samples, const std::function<uint32_t(uint32_t)>* hint, size_t faces, const char* which) {
    std::vector<uint32_t> out;
    if (!hint || !*hint) return out;
    const size_t n = samples.points.size();
    out.resize(n);
    uint32_t face = kNoRecord, start = kNoRecord;  // the last face asked about (neighbouring points share faces)
    for (size_t i = 0; i < n; ++i) {
        if (samples.faces[i] != face) {
            face = samples.faces[i];
            start = (*hint)(face);
            if (start != kNoRecord && start >= faces)
                throw ArgumentError(std::string("FaceHints::") + which + ": face " + std::to_string(face) + " hints face " +
                                    std::to_string(start) + ", the other surface has " + std::to_string(faces));
        }
        out[i] = start;
    }
    return out;
}

// A direction's sums over some of its samples: chunks, and the batches of a large surface,
// added in order (the same figures whatever the thread count).
struct Sums {
    Partial d;
    AttributePartial a;
    void add(const Partial& p) {
        d.max = std::max(d.max, p.max);
        d.sum += p.sum;
        d.sum_squares += p.sum_squares;
    }
    void add(const AttributePartial& p) {
        a.normal_sum += p.normal_sum, a.uv_sum += p.uv_sum, a.normal_n += p.normal_n, a.uv_n += p.uv_n;
        a.normal_max = std::max(a.normal_max, p.normal_max);
        a.uv_max = std::max(a.uv_max, p.uv_max);
    }
    void add(const Sums& o) {
        add(o.d);
        add(o.a);
    }
};

// The sample counts of a direction, of one Samples or of all the batches of a SampleBatches.
struct Counts {
    uint64_t samples = 0, vertex = 0, edge = 0, face = 0;
    double area = 0;
    static Counts of(const Samples& s) { return {s.points.size(), s.vertex, s.edge, s.face, s.area}; }
    static Counts of(const SampleBatches& b) { return {b.vertex + b.edge + b.face, b.vertex, b.edge, b.face, b.area}; }
};

OneSidedDistance one_sided(const Sums& sums, const Counts& c) {
    OneSidedDistance out;
    out.max = sums.d.max;
    out.samples = c.samples;
    out.vertex_samples = c.vertex;
    out.edge_samples = c.edge;
    out.face_samples = c.face;
    out.sampled_area = c.area;
    out.mean = c.samples ? sums.d.sum / double(c.samples) : 0.0;
    out.rms = c.samples ? std::sqrt(sums.d.sum_squares / double(c.samples)) : 0.0;
    return out;
}

// The attribute deviation from the sums at `picks` picked samples, of the streams compared.
AttributeDeviation deviation_of(const Sums& sums, uint64_t picks, bool normals, bool texcoords) {
    AttributeDeviation a;
    a.normals = normals && picks > 0;  // (no face samples: nothing compared)
    a.texcoords = texcoords && picks > 0;
    a.samples = picks;
    a.normal_max_degrees = sums.a.normal_max;
    a.uv_max = sums.a.uv_max;
    a.normal_mean_degrees = sums.a.normal_n ? sums.a.normal_sum / double(sums.a.normal_n) : 0.0;
    a.uv_mean = sums.a.uv_n ? sums.a.uv_sum / double(sums.a.uv_n) : 0.0;
    return a;
}

// One direction's sums: the samples' distances to `target`; with `probe`, the attribute
// deviation's at its picked samples; with `hint` (face of the sampled surface -> a triangle of
// `target` near it, or kNoRecord; `which` names it in errors), each search starts there too.
Sums measure_sums(const Samples& samples, const Mesh3& target, unsigned threads, const AttributeProbe* probe = nullptr,
                  const std::function<uint32_t(uint32_t)>* hint = nullptr, const char* which = "") {
    const size_t n = samples.points.size();
    std::vector<Partial> partial((n + kChunk - 1) / kChunk);
    std::vector<AttributePartial> attribute_partial(probe ? partial.size() : 0);
    const int shift = cell_shift(samples, target);
    std::vector<uint32_t> starts = hinted_faces(samples, hint, target.slot.size(), which);  // per point: the record of its face's hint
    for (uint32_t& t : starts)
        if (t != kNoRecord) t = target.slot[t];
    parallel_chunks(n, threads, [&](size_t c, size_t begin, size_t end) {
        Partial& r = partial[c];
        RunSearch search(target, samples.points.data());
        if (!starts.empty()) search.starts = starts.data();
        auto emit = [&](size_t i, double d2, uint32_t slot) {
            const double d = std::sqrt(d2);
            r.max = std::max(r.max, d);
            r.sum += d;
            r.sum_squares += d2;
            if (probe) {
                const uint32_t k = probe->picks.of_point[i];
                if (k != PickedFaceSamples::kNotPicked) probe->add(attribute_partial[c], k, samples.points[i], d2, slot);
            }
        };
        search.runs(samples.keys.data(), begin, end, shift, emit);
    });
    Sums sums;
    for (const Partial& p : partial) sums.add(p);
    for (const AttributePartial& p : attribute_partial) sums.add(p);
    return sums;
}

// One direction (measure_sums), with `probe` its attribute deviation into `deviation`.
OneSidedDistance measure(const Samples& samples, const Mesh3& target, unsigned threads, const AttributeProbe* probe = nullptr,
                         AttributeDeviation* deviation = nullptr, const std::function<uint32_t(uint32_t)>* hint = nullptr,
                         const char* which = "") {
    const Sums sums = measure_sums(samples, target, threads, probe, hint, which);
    if (probe && deviation) *deviation = deviation_of(sums, probe->picks.picked.size(), probe->normals, probe->texcoords);
    return one_sided(sums, Counts::of(samples));
}

// One direction searched in a CompactTree, a descent for each sample from its hinted face and
// the previous sample's nearest (DistanceParams::compact_search_triangles).
OneSidedDistance measure_compact(const Samples& samples, const CompactTree& target, unsigned threads,
                                 const std::function<uint32_t(uint32_t)>* hint, const char* which) {
    const size_t n = samples.points.size();
    std::vector<Partial> partial((n + kChunk - 1) / kChunk);
    const std::vector<uint32_t> starts = hinted_faces(samples, hint, target.triangle_count(), which);
    parallel_chunks(n, threads, [&](size_t c, size_t begin, size_t end) {
        Partial& r = partial[c];
        uint32_t last = kNoRecord;
        for (size_t i = begin; i < end; ++i) {
            double d2;
            last = target.nearest(samples.points[i], starts.empty() ? kNoRecord : starts[i], last, d2);
            const double d = std::sqrt(d2);
            r.max = std::max(r.max, d);
            r.sum += d;
            r.sum_squares += d2;
        }
    });
    Sums sums;
    for (const Partial& p : partial) sums.add(p);
    return one_sided(sums, Counts::of(samples));
}

void bounds(const Surface& s, double lo[3], double hi[3]) {
    for (size_t i = 0; i < s.triangle_count * 3; ++i)
        for (int k = 0; k < 3; ++k) {
            const double x = s.positions[3 * size_t(s.indices[i]) + k];
            lo[k] = std::min(lo[k], x);
            hi[k] = std::max(hi[k], x);
        }
}

// The box of a surface's corners.
struct Box {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
};
Box box_of(const Surface& s) {
    Box b;
    bounds(s, b.lo, b.hi);
    return b;
}

// `a`: the box of the first surface (the original's, made once)
double enlarged_union_diagonal(const Box& a, const Surface& b) {
    double lo[3] = {a.lo[0], a.lo[1], a.lo[2]}, hi[3] = {a.hi[0], a.hi[1], a.hi[2]};
    bounds(b, lo, hi);
    const double diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    const double grow = 2.0 * 0.02 * diag;  // each side moves out by 2% of the diagonal
    return std::sqrt((hi[0] - lo[0] + grow) * (hi[0] - lo[0] + grow) + (hi[1] - lo[1] + grow) * (hi[1] - lo[1] + grow) +
                     (hi[2] - lo[2] + grow) * (hi[2] - lo[2] + grow));
}

// The samples of one direction, on `sampled`, between `sampled` and `other`.
uint64_t sample_target(const Surface& sampled, const Surface& other, const DistanceParams& p) {
    uint64_t n = uint64_t(std::llround(p.samples_per_face * double(std::max(sampled.triangle_count, other.triangle_count))));
    if (p.max_samples) n = std::min(n, p.max_samples);
    if (p.max_samples_per_sampled_face > 0)
        n = std::min(n, std::max<uint64_t>(1, uint64_t(std::llround(p.max_samples_per_sampled_face * double(sampled.triangle_count)))));
    return n;
}


} // namespace

// compare() may run on several threads at once: what it makes on first use is made under the
// lock (and never moves: a deque), and each call borrows its own buffers
struct MetroReference::Impl {
    struct Workspace {
        Samples backward;  // the simplified side's, buffers reused between calls
        MortonScratch scratch;
        Samples batch;  // a batch of the original's (SampleBatches), its picks and their attributes
        PickedFaceSamples picks;
        PickedAttributes at_picks;
    };
    // whether a direction of `samples` is made in batches (DistanceParams::batch_samples)
    bool batched(uint64_t samples) const { return params.batch_samples > 0 && samples > 4 * params.batch_samples; }
    Surface original;
    DistanceParams params;
    SurfaceAttributes attributes;
    // the original's search structure, made on a thread of its own from the start (a first
    // compare() samples the original and searches its level meanwhile), shared by the references
    // made with with_params()
    std::shared_future<std::shared_ptr<const Mesh3>> mesh;
    std::shared_future<std::shared_ptr<const CompactTree>> compact;  // (DistanceParams::compact_search_triangles; made when first needed)
    Box box;  // of the original's corners
    mutable std::mutex lock;
    struct Forward {  // the original's samples for one target count, and the attribute samples picked from them
        uint64_t target = 0;
        Samples samples;
        PickedFaceSamples picks;
        // where the face samples were too few to pick from (long edges took the budget: the parts
        // of CAD models; 32 of 2CylinderEngine's 34 had fewer than one a face, many none), the
        // attribute deviation's own face samples, all picked, searched apart
        bool separate = false;
        Samples attribute_samples;
        PickedFaceSamples attribute_picks;
        PickedAttributes at_picks;  // of the picks in use (attribute_picks where separate)
        // or, made in batches (batched()), the plans of those samples, made batch by batch
        std::unique_ptr<SampleBatches> batches, attribute_batches;
    };
    mutable std::deque<Forward> forward;  // by target count
    mutable std::vector<std::unique_ptr<Workspace>> idle;
    // (a small original's is made when first needed: a thread would cost more)
    static constexpr size_t kOwnThreadTriangles = 4096, kAwaitOriginalTriangles = size_t(1) << 19;
    Impl(const Surface& s, const DistanceParams& p, const SurfaceAttributes& a)
        : original(s), params(p), attributes(a), mesh(make_mesh(s, !compact_for(p, s))), compact(make_compact(s)), box(box_of(s)) {}
    // whether `s`, searched, takes the compact tree (DistanceParams::compact_search_triangles)
    static bool compact_for(const DistanceParams& p, const Surface& s) {
        return p.compact_search_triangles > 0 && s.triangle_count >= p.compact_search_triangles;
    }
    // `early`: on a thread of its own from the start (else when first needed: a compact search's
    // reference may never need it)
    static std::shared_future<std::shared_ptr<const Mesh3>> make_mesh(const Surface& s, bool early) {
        auto make = [s] { return std::shared_ptr<const Mesh3>(std::make_shared<Mesh3>(s)); };
        if (early && s.triangle_count >= kOwnThreadTriangles) {
            try {
                return std::async(std::launch::async, make).share();
            } catch (const std::system_error&) {  // no thread to be had: made when first needed
            }
        }
        return std::async(std::launch::deferred, make).share();
    }
    static std::shared_future<std::shared_ptr<const CompactTree>> make_compact(const Surface& s) {
        return std::async(std::launch::deferred, [s] { return std::shared_ptr<const CompactTree>(std::make_shared<CompactTree>(s)); }).share();
    }
    Impl(const Impl& shared, const DistanceParams& p, const SurfaceAttributes& a)
        : original(shared.original), params(p), attributes(a), mesh(shared.mesh), compact(shared.compact), box(shared.box) {}
    const Forward& forward_for(uint64_t target) const {
        std::lock_guard<std::mutex> hold(lock);
        for (const Forward& f : forward)
            if (f.target == target) return f;
        Forward& f = forward.emplace_back();
        f.target = target;
        MortonScratch scratch;
        const bool pick = attributes.normals || attributes.texcoords;
        const uint64_t picks = uint64_t(std::llround(std::max(0.0, params.attribute_samples_per_face) * double(original.triangle_count)));
        DistanceParams faces_only = params;
        faces_only.vertex_samples = faces_only.edge_samples = false;
        faces_only.face_samples = true;
        if (batched(target)) {
            f.batches = std::make_unique<SampleBatches>(original, target, params, params.batch_samples, pick ? picks : 0);
            if (pick && f.batches->picked < picks / 2) {
                f.attribute_batches = std::make_unique<SampleBatches>(original, picks, faces_only, params.batch_samples, picks);
                f.separate = true;
            }
            return f;
        }
        sample_surface(original, target, params, f.samples, scratch, pick ? &f.picks : nullptr, picks);
        if (pick && f.picks.picked.size() < picks / 2) {
            sample_surface(original, picks, faces_only, f.attribute_samples, scratch, &f.attribute_picks, picks);
            f.separate = true;
        }
        if (pick) f.at_picks.make(original, attributes, f.separate ? f.attribute_picks : f.picks, params.threads);
        return f;
    }
    std::unique_ptr<Workspace> borrow() const {
        std::lock_guard<std::mutex> hold(lock);
        if (idle.empty()) return std::make_unique<Workspace>();
        std::unique_ptr<Workspace> w = std::move(idle.back());
        idle.pop_back();
        return w;
    }
    void give_back(std::unique_ptr<Workspace> w) const {
        std::lock_guard<std::mutex> hold(lock);
        idle.push_back(std::move(w));
    }

    Distance compare(const Surface& simplified, const SurfaceAttributes& simplified_attributes, AttributeDeviation* deviation,
                     const FaceHints* hints) const {
        validate(simplified, "simplified");
        if (params.compact_search_triangles > 0 && !deviation) return compare_compact(simplified, hints);
        const uint64_t target = sample_target(original, simplified, params);
        const uint64_t backward_target = sample_target(simplified, original, params);
        // a large level's structure is made once the original's is done: the two made at once
        // would hold both their CGAL trees, the report's peak
        if (simplified.triangle_count >= kAwaitOriginalTriangles) mesh.wait();
        const Mesh3 other(simplified);
        const Forward& f = forward_for(target);
        const bool normals = deviation && simplified_attributes.normals && attributes.normals,
                   texcoords = deviation && simplified_attributes.texcoords && attributes.texcoords;
        const AttributeProbe probe{f.separate ? f.attribute_picks : f.picks, f.at_picks, simplified, simplified_attributes, other, normals, texcoords};
        if (deviation) *deviation = AttributeDeviation{};
        const bool probing = normals || texcoords;
        std::unique_ptr<Workspace> work = borrow();
        Distance d;
        if (f.batches) {
            d.forward = forward_batched(f, other, simplified, simplified_attributes, normals, texcoords, deviation, hints, *work);
        } else {
            d.forward = measure(f.samples, other, params.threads, probing && !f.separate ? &probe : nullptr, deviation,
                                hints ? &hints->original_to_simplified : nullptr, "original_to_simplified");
            if (probing && f.separate) measure(f.attribute_samples, other, params.threads, &probe, deviation);  // (only its deviation)
        }
        const std::shared_future<std::shared_ptr<const Mesh3>> original_mesh = mesh;  // (each caller its own copy)
        const std::function<uint32_t(uint32_t)>* back_hint = hints ? &hints->simplified_to_original : nullptr;
        if (batched(backward_target)) {
            const SampleBatches plan(simplified, backward_target, params, params.batch_samples);
            Sums sums;
            for (size_t k = 0; k < plan.size(); ++k) {
                plan.make(k, work->backward, work->scratch, nullptr, back_hint != nullptr);
                sums.add(measure_sums(work->backward, *original_mesh.get(), params.threads, nullptr, back_hint, "simplified_to_original"));
            }
            d.backward = one_sided(sums, Counts::of(plan));
        } else {
            sample_surface(simplified, backward_target, params, work->backward, work->scratch, nullptr, 0, hints != nullptr);
            d.backward = measure(work->backward, *original_mesh.get(), params.threads, nullptr, nullptr, back_hint, "simplified_to_original");
        }
        give_back(std::move(work));
        d.hausdorff = std::max(d.forward.max, d.backward.max);
        d.diagonal = enlarged_union_diagonal(box, simplified);
        return d;
    }

    // The forward direction of compare() batch by batch (Forward::batches): each batch's picks
    // and the original's attributes there made with it; the attribute deviation into `deviation`
    // when normals or texcoords are compared.
    OneSidedDistance forward_batched(const Forward& f, const Mesh3& other, const Surface& simplified, const SurfaceAttributes& simplified_attributes,
                                     bool normals, bool texcoords, AttributeDeviation* deviation, const FaceHints* hints, Workspace& work) const {
        const std::function<uint32_t(uint32_t)>* hint = hints ? &hints->original_to_simplified : nullptr;
        auto run = [&](const SampleBatches& plan, bool probing) {
            Sums sums;
            for (size_t k = 0; k < plan.size(); ++k) {
                plan.make(k, work.batch, work.scratch, probing ? &work.picks : nullptr, hint != nullptr);
                if (probing) work.at_picks.make(original, attributes, work.picks, params.threads);
                const AttributeProbe probe{work.picks, work.at_picks, simplified, simplified_attributes, other, normals, texcoords};
                sums.add(measure_sums(work.batch, other, params.threads, probing ? &probe : nullptr, hint, "original_to_simplified"));
            }
            return sums;
        };
        const bool probing = normals || texcoords;
        const Sums sums = run(*f.batches, probing && !f.separate);
        if (probing) {
            const SampleBatches& picked = f.separate ? *f.attribute_batches : *f.batches;
            *deviation = deviation_of(f.separate ? run(picked, true) : sums, picked.picked, normals, texcoords);
        }
        return one_sided(sums, Counts::of(*f.batches));
    }

    // compare() with DistanceParams::compact_search_triangles, without the attribute deviation:
    // the same samples, each surface searched in the structure its size calls for
    Distance compare_compact(const Surface& simplified, const FaceHints* hints) const {
        const uint64_t target = sample_target(original, simplified, params);
        const uint64_t backward_target = sample_target(simplified, original, params);
        const Forward& f = forward_for(target);
        const std::function<uint32_t(uint32_t)>* forward_hint = hints ? &hints->original_to_simplified : nullptr;
        const std::function<uint32_t(uint32_t)>* backward_hint = hints ? &hints->simplified_to_original : nullptr;
        Distance d;
        if (compact_for(params, simplified))
            d.forward = measure_compact(f.samples, CompactTree(simplified), params.threads, forward_hint, "original_to_simplified");
        else
            d.forward = measure(f.samples, Mesh3(simplified), params.threads, nullptr, nullptr, forward_hint, "original_to_simplified");
        std::unique_ptr<Workspace> work = borrow();
        sample_surface(simplified, backward_target, params, work->backward, work->scratch, nullptr, 0, hints != nullptr);
        if (compact_for(params, original)) {
            const std::shared_future<std::shared_ptr<const CompactTree>> original_tree = compact;  // (each caller its own copy)
            d.backward = measure_compact(work->backward, *original_tree.get(), params.threads, backward_hint, "simplified_to_original");
        } else {
            const std::shared_future<std::shared_ptr<const Mesh3>> original_mesh = mesh;
            d.backward = measure(work->backward, *original_mesh.get(), params.threads, nullptr, nullptr, backward_hint, "simplified_to_original");
        }
        give_back(std::move(work));
        d.hausdorff = std::max(d.forward.max, d.backward.max);
        d.diagonal = enlarged_union_diagonal(box, simplified);
        return d;
    }
};

MetroReference::MetroReference(const Surface& original, const DistanceParams& params, const SurfaceAttributes& attributes) {
    validate(original, "original");
    impl_ = std::make_unique<Impl>(original, params, attributes);
}
MetroReference MetroReference::with_params(const DistanceParams& params, const SurfaceAttributes& attributes) const {
    MetroReference r;
    r.impl_ = std::make_unique<Impl>(*impl_, params, attributes);
    return r;
}
MetroReference::~MetroReference() = default;
MetroReference::MetroReference(MetroReference&&) noexcept = default;
MetroReference& MetroReference::operator=(MetroReference&&) noexcept = default;

Distance MetroReference::compare(const Surface& simplified) const {
    return impl_->compare(simplified, SurfaceAttributes{}, nullptr, nullptr);
}

Distance MetroReference::compare(const Surface& simplified, const SurfaceAttributes& attributes, AttributeDeviation& deviation) const {
    return impl_->compare(simplified, attributes, &deviation, nullptr);
}

Distance MetroReference::compare(const Surface& simplified, const FaceHints& hints) const {
    return impl_->compare(simplified, SurfaceAttributes{}, nullptr, &hints);
}

void nearest_squared_distances(const Surface& target, const double* points, size_t count, double* squared_distances, unsigned threads) {
    validate(target, "target");
    const Mesh3 mesh(target);
    Samples s;
    s.points.reserve(count);
    for (size_t i = 0; i < count; ++i) s.points.push_back({points[3 * i], points[3 * i + 1], points[3 * i + 2]});
    s.area = surface_area(target);  // the density of points on (or near) the target decides the cells
    MortonScratch scratch;
    std::vector<uint32_t> order;
    order_morton(s.points, s.keys, s.extent, scratch, threads, &order);
    const int shift = cell_shift(s, mesh);
    parallel_chunks(count, threads, [&](size_t, size_t begin, size_t end) {
        RunSearch search(mesh, s.points.data());
        auto emit = [&](size_t i, double d2, uint32_t) { squared_distances[order[i]] = d2; };
        search.runs(s.keys.data(), begin, end, shift, emit);
    });
}

Distance metro_distance(const Surface& original, const Surface& simplified, const DistanceParams& params) {
    return MetroReference(original, params).compare(simplified);
}

} // namespace tom
