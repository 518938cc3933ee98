// Report of one built mesh: levels with Metro-style error, chains, extraction time; memory as
// the TOM paper's Table 4; Pasman & Jansen's D = k / N fit; the error curve for the .tom.

#include "tom/errors.h"
#include "tom/metrics/report.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <mutex>
#include <stdexcept>

#include "tom/builder/writer.h"
#include "tom/format.h"
#include "parallel.h"

namespace tom {

namespace {

struct Level {
    uint32_t n = 0;
    std::vector<uint32_t> indices;
    Extracted e;
};

Level extract_level(const TomMesh& t, uint32_t n) {
    Level l;
    l.n = n;
    l.indices.resize(size_t(active_triangle_count(t.view(), n)) * 3);  // the level's size, not the mesh's: reports hold several levels at once
    l.e = extract(t.view(), n, l.indices.data(), l.indices.size());
    return l;
}

Surface surface_of(const Mesh& m) { return {m.positions.data(), m.vertex_count(), m.indices.data(), m.triangle_count()}; }

// FaceHints between a level and the original the mesh was built from (`sorted_of`: original face
// -> sorted face; `around`: a level face of each level vertex): a level's face i is sorted face i
// with its corners substituted, so it lies over the original's face built.original_triangle[i]
// (the hints back). Forward: an original face alive at the level is that face, and one that died
// is near the faces around the vertex its first corner became.
FaceHints level_hints(const TomMesh& built, const Level& l, const std::vector<uint32_t>& sorted_of, std::vector<uint32_t>& around) {
    const uint32_t faces = l.e.triangle_count;
    around.assign(l.n, FaceHints::kNone);
    for (uint32_t c = faces * 3; c-- > 0;) around[l.indices[c]] = c / 3;
    FaceHints h;
    h.original_to_simplified = [&built, &sorted_of, &around, faces, n = l.n](uint32_t f) {
        const uint32_t t = sorted_of[f];
        if (t < faces) return t;
        uint32_t x = built.triangles[3 * size_t(t)];
        while (x >= n) x = built.substitute[x];
        return around[x];
    };
    h.simplified_to_original = [&built](uint32_t i) { return built.original_triangle[i]; };
    return h;
}

// Median of 5 timed batches of about 0.2 ms each: short enough that timing a file of many small
// meshes stays a small part of its report.
double median_extract_seconds(const MeshView& v, uint32_t n, std::vector<uint32_t>& buffer) {
    using Clock = std::chrono::steady_clock;
    constexpr double kBatchSeconds = 2e-4;
    constexpr int kBatches = 5;
    std::vector<double> times;
    int inner = 1;
    for (;;) {  // enough repeats for a batch of kBatchSeconds
        const auto t0 = Clock::now();
        for (int k = 0; k < inner; ++k) extract(v, n, buffer.data(), buffer.size());
        if (std::chrono::duration<double>(Clock::now() - t0).count() > kBatchSeconds || inner >= (1 << 16)) break;
        inner *= 2;
    }
    for (int r = 0; r < kBatches; ++r) {
        const auto t0 = Clock::now();
        for (int k = 0; k < inner; ++k) extract(v, n, buffer.data(), buffer.size());
        times.push_back(std::chrono::duration<double>(Clock::now() - t0).count() / inner);
    }
    std::sort(times.begin(), times.end());
    return times[times.size() / 2];
}

double overhead_distinct(const MeshView& v, uint32_t n) {
    // distinct vertices >= n walked through, over the n vertices sent
    std::vector<uint8_t> seen(v.vertex_count, 0);
    uint64_t extra = 0;
    const uint32_t tris = active_triangle_count(v, n);
    for (uint32_t c = 0; c < tris * 3; ++c) {
        uint32_t x = v.corner(c);
        while (x >= n) {
            if (!seen[x]) seen[x] = 1, ++extra;
            x = v.substitute_at(x);
        }
    }
    return n ? double(extra) / double(n) : 0.0;
}

uint64_t face_vertex(uint64_t v, uint64_t t) { return v * 24 + t * 12; }

MemoryReport memory_of(const TomMesh& built) {
    MemoryReport m;
    const MeshView v = built.view();
    m.face_vertex_bytes = face_vertex(v.vertex_count, v.triangle_count);
    TomMesh stripped = built;  // the paper's form: positions and normals, 32-bit indices
    stripped.texcoords.clear();
    stripped.colors.clear();
    stripped.metadata.clear();
    for (Part& part : stripped.parts) part.attributes &= ~(2u | 4u);  // the streams cleared above
    if (stripped.normals.empty()) stripped.normals.assign(stripped.positions.size(), 0.0f);
    WriteOptions o;
    o.index_size = IndexSize::bits32;
    m.tom_bytes = serialize({stripped}, o).size();
    for (double f : {1.0, 0.5, 0.25, 0.12, 0.06, 0.03}) {
        const uint32_t n = vertex_count_for_fraction(v, f);
        m.lod_bytes += face_vertex(n, active_triangle_count(v, n));
    }
    // progressive mesh (Hoppe 1996/1998), memory-resident: per vertex split a record of the new
    // vertex (position + normal, 24 B) and its connectivity (split vertex, two neighbours, 12 B);
    // plus the resident mesh with face adjacency (per face 3 vertex and 3 neighbour indices,
    // 24 B; per vertex 24 B): coarsest mesh resident (min) or full resolution (max)
    const uint64_t splits = v.vertex_count - v.min_vertex_count;
    const uint64_t records = splits * 36;
    const uint32_t base_tris = active_triangle_count(v, v.min_vertex_count);
    m.pm_bytes = records + uint64_t(v.min_vertex_count) * 24 + uint64_t(base_tris) * 24;
    m.pm_max_bytes = records + uint64_t(v.vertex_count) * 24 + uint64_t(v.triangle_count) * 24;
    return m;
}

void check(const Mesh& original, const TomMesh& built) {
    if (original.vertex_count() != built.vertex_count() || original.triangle_count() != built.triangle_count())
        throw ArgumentError("report: the built mesh does not come from this original (counts differ)");
    if (original.triangle_count() == 0) throw ArgumentError("report: the mesh has no triangle");
}

// The log-spaced points bracket the usable floor (tom::usable_floor_of at `bound`) within a
// factor of (vertices / lowest)^(1/15); this bisects the bracket, adding each point measured, so
// that the floor lies within 1/64 of it. measure(n, point, diagonal) measures resolution n.
template <class Measure>
void refine_floor(ErrorCurve& c, double bound, Measure&& measure) {
    auto within = [&](const ErrorCurvePoint& p) { return within_floor_bound(p, bound); };
    size_t i = c.points.size();  // the first point from which on every point is within the bound
    while (i > 0 && within(c.points[i - 1])) --i;
    if (i == 0 || i == c.points.size()) return;  // within from the coarsest point on, or never
    uint32_t lo = c.points[i - 1].vertices, hi = c.points[i].vertices;
    for (int step = 0; step < 6 && hi - lo > 1; ++step) {
        ErrorCurvePoint p;
        float diagonal = 0;
        measure(lo + (hi - lo) / 2, p, diagonal);
        c.points.insert(std::upper_bound(c.points.begin(), c.points.end(), p.vertices,
                                         [](uint32_t n, const ErrorCurvePoint& q) { return n < q.vertices; }),
                        p);
        (within(p) ? hi : lo) = p.vertices;
    }
}

// `workers`: threads for the points, 0 for one per core
ErrorCurve curve_with(const TomMesh& built, const ReportParams& params, const MetroReference& reference, unsigned workers) {
    ErrorCurve c;
    const MeshView v = built.view();
    const uint32_t lo = std::max<uint32_t>(v.min_vertex_count, std::min<uint32_t>(4, v.vertex_count));
    const uint32_t hi = v.vertex_count;
    const uint32_t count = std::max<uint32_t>(2, std::min<uint32_t>(64, params.curve_points));
    std::vector<uint32_t> ns;
    // and the coarsest level below them: a small mesh's (a floor's quad, a decal) would otherwise
    // have none measured, which every selection reads as free
    if (v.min_vertex_count > 0 && v.min_vertex_count < lo) ns.push_back(v.min_vertex_count);
    for (uint32_t i = 0; i < count; ++i) {
        const double t = count == 1 ? 1.0 : double(i) / double(count - 1);
        const uint32_t n = uint32_t(std::lround(std::exp(std::log(double(lo)) + t * (std::log(double(hi)) - std::log(double(lo))))));
        if (ns.empty() || n > ns.back()) ns.push_back(std::min(n, hi));
    }
    // each level's faces are the built mesh's first ones with corners substituted, which is where
    // they lie on the original: the searches start there (FaceHints; faster, the same figures)
    const bool hinted = built.original_triangle.size() == v.triangle_count;
    std::vector<uint32_t> sorted_of;  // original face -> its sorted face
    if (hinted) {
        sorted_of.resize(v.triangle_count);
        for (uint32_t t = 0; t < v.triangle_count; ++t) sorted_of[built.original_triangle[t]] = t;
    }
    // the points on `workers` threads, each measured on one (their costs differ widely: coarse
    // levels lie far from the original, fine ones make large trees), taken in turn
    std::vector<ErrorCurvePoint> points(ns.size());
    std::vector<float> diagonals(ns.size(), 0.0f);
    std::mutex progress_lock;
    size_t measured = 0;
    auto point_done = [&] {
        if (!params.progress) return;
        std::lock_guard<std::mutex> hold(progress_lock);
        params.progress(double(++measured) / double(ns.size()));
    };
    auto measure = [&](uint32_t n, ErrorCurvePoint& p, float& diagonal) {
        const Level l = extract_level(built, n);
        p.vertices = n;
        p.triangles = l.e.triangle_count;
        if (n == hi || l.e.triangle_count == 0) return;  // full resolution is the original itself: error 0
        const Surface level{built.positions.data(), n, l.indices.data(), l.e.triangle_count};
        std::vector<uint32_t> around;
        const Distance d = hinted ? reference.compare(level, level_hints(built, l, sorted_of, around)) : reference.compare(level);
        p.mean = float(std::max(d.forward.mean, d.backward.mean) / d.diagonal);
        p.max = float(d.hausdorff / d.diagonal);
        diagonal = float(d.diagonal);
    };
    detail::parallel_blocks(ns.size(), 1, workers, [&](unsigned, size_t i, size_t) {
        struct Done {
            const decltype(point_done)& done;
            ~Done() { done(); }
        } done{point_done};
        measure(ns[i], points[i], diagonals[i]);
    });
    std::vector<double> tris, means, maxes;
    for (size_t i = 0; i < ns.size(); ++i) {
        const ErrorCurvePoint& p = points[i];
        if (ns[i] != hi && p.triangles > 0) {
            c.diagonal = diagonals[i];
            tris.push_back(p.triangles);
            means.push_back(p.mean);
            maxes.push_back(p.max);
        }
        c.points.push_back(p);
    }
    c.k_mean = float(fit_k_over_n(tris, means).k);
    c.k_max = float(fit_k_over_n(tris, maxes).k);
    if (params.floor_error > 0) refine_floor(c, params.floor_error, measure);
    return c;
}

} // namespace

// Each part's attributes against the original part's, at every measured level: the part's live
// triangles (extract_parts) compared with its own triangles of the original (a reference each).
static void measure_parts(const Mesh& original, const TomMesh& built, const ReportParams& params, const SurfaceAttributes& original_attributes,
                          const SurfaceAttributes& level_attributes, std::vector<LevelReport>& levels, const std::vector<size_t>& first_of) {
    if (original.parts.empty() || original.parts.size() != built.parts.size()) return;
    const MeshView v = built.view();
    // each measured level extracted once, with where each part's triangles went
    struct PartsLevel {
        Extracted e;
        std::vector<uint32_t> indices;
        std::vector<PartDraw> draws;
    };
    std::vector<PartsLevel> extracted(levels.size());
    for (size_t i = 0; i < levels.size(); ++i) {
        if (first_of[i] != i) continue;
        PartsLevel& l = extracted[i];
        l.indices.resize(size_t(active_triangle_count(v, levels[i].vertices)) * 3);
        l.draws.resize(original.parts.size());
        l.e = extract_parts(v, levels[i].vertices, l.indices.data(), l.indices.size(), l.draws.data());
        levels[i].parts.resize(original.parts.size());
    }
    for (size_t p = 0; p < original.parts.size(); ++p) {
        const Part& part = original.parts[p];
        const MetroReference reference({original.positions.data(), original.vertex_count(), original.indices.data() + 3 * size_t(part.first_triangle), part.triangle_count},
                                       params.distance, original_attributes);
        for (size_t i = 0; i < levels.size(); ++i) {
            if (first_of[i] != i) continue;
            const PartsLevel& l = extracted[i];
            PartLevelReport& pr = levels[i].parts[p];
            pr.material = part.material;
            pr.triangles = l.draws[p].index_count / 3;
            if (pr.triangles > 0)
                reference.compare({built.positions.data(), l.e.vertex_count, l.indices.data() + l.draws[p].first_index, pr.triangles}, level_attributes, pr.attributes);
        }
    }
    for (size_t i = 0; i < levels.size(); ++i)  // a level at an earlier one's resolution repeats its figures
        if (first_of[i] != i) levels[i].parts = levels[first_of[i]].parts;
}

// The curve is a runtime estimate (the runtime reads its means): area-uniform face samples, a
// budget that grows with the mesh up to a cap, and fewer on a level of a few faces: its means stay
// within a few percent of a dense sampling's at half its cost, and a file of many small meshes
// does not pay a dense sampling per mesh.
static DistanceParams curve_distance_params(const ReportParams& params, size_t triangles) {
    DistanceParams dp = params.distance;
    dp.threads = 1;  // the points run in parallel instead (curve_with's workers)
    dp.vertex_samples = false;
    dp.edge_samples = false;
    dp.samples_per_face = 1e9;
    const double wanted = params.curve_samples_per_triangle * double(triangles);
    const uint64_t floor = std::min(params.curve_min_samples, params.curve_samples);
    dp.max_samples = std::max<uint64_t>(1, std::min<uint64_t>(params.curve_samples, std::max<uint64_t>(floor, uint64_t(std::llround(wanted)))));
    dp.max_samples_per_sampled_face = params.curve_samples_per_level_face;
    dp.compact_search_triangles = uint64_t(1) << 18;  // (a few thousand samples against up to the whole mesh)
    return dp;
}

ErrorCurve measure_error_curve(const Mesh& original, const TomMesh& built, const ReportParams& params) {
    check(original, built);
    const MetroReference reference(surface_of(original), curve_distance_params(params, original.triangle_count()));
    return curve_with(built, params, reference, params.distance.threads);
}

MeshReport make_report(const Mesh& original, const TomMesh& built, const ReportParams& params) {
    check(original, built);
    MeshReport r;
    r.name = built.name;
    r.vertices = built.vertex_count();
    r.triangles = built.triangle_count();
    r.memory = memory_of(built);
    const MeshView v = built.view();
    // a level at the vertex count of an earlier one is the same mesh, and repeats its figures:
    // the first level at its count (itself, for a new one). Meshes that stop simplifying above a
    // level's count (locked seams, a floor of min_vertex_count) repeat their last level: 152 of
    // the 238 levels of 2CylinderEngine's 34 parts
    std::vector<size_t> first_of;
    // extraction is timed on the form an engine maps: the file (16-bit indices where they fit,
    // coarse corners), extracted into 32-bit buffers, as tombench does; first, on a quiet machine
    {
        const std::vector<uint8_t> image = serialize({built});
        const File file = File::from_bytes(image.data(), image.size(), built.name, OpenOptions{false});
        std::vector<uint32_t> buffer(size_t(v.triangle_count) * 3);
        for (double f : params.levels) {
            LevelReport lr;
            lr.fraction = f;
            lr.vertices = vertex_count_for_fraction(v, f);
            size_t first = 0;
            while (first < r.levels.size() && r.levels[first].vertices != lr.vertices) ++first;
            first_of.push_back(first);
            if (first < r.levels.size()) {
                lr = r.levels[first];
                lr.fraction = f;
            } else {
                lr.extract_seconds = median_extract_seconds(file.mesh(0), lr.vertices, buffer);
                lr.chain = chain_stats(v, lr.vertices);
                lr.mean_steps = lr.chain.corners ? double(lr.chain.steps) / double(lr.chain.corners) : 0.0;
                lr.overhead = overhead_distinct(v, lr.vertices);
            }
            r.levels.push_back(lr);
        }
    }
    const SurfaceAttributes original_attributes{original.normals.empty() ? nullptr : original.normals.data(),
                                                original.texcoords.empty() ? nullptr : original.texcoords.data()};
    const SurfaceAttributes level_attributes{built.normals.empty() ? nullptr : built.normals.data(),
                                             built.texcoords.empty() ? nullptr : built.texcoords.data()};
    const MetroReference reference(surface_of(original), params.distance, original_attributes);
    // the stored curve does not depend on the levels (its own samples and seed; the same search
    // structure of the original): it is measured alongside them, on the cores their serial parts
    // leave idle
    const MetroReference curve_reference = reference.with_params(curve_distance_params(params, original.triangle_count()));
    std::future<ErrorCurve> curve;
    if (params.error_curve)
        curve = std::async(std::launch::async, [&] { return curve_with(built, params, curve_reference, params.distance.threads); });
    // the levels two at a time, each on every core: one's sequential parts (its tree, its
    // samples' sort) overlap the other's searches; each level in flight holds its samples (about
    // 80 bytes a sample, 10 samples a triangle), so a mesh of more than kPairedTriangles takes
    // them in turn
    constexpr uint32_t kPairedTriangles = 1u << 20;
    std::vector<size_t> measured;  // the levels not repeating an earlier one
    for (size_t i = 0; i < r.levels.size(); ++i)
        if (first_of[i] == i) measured.push_back(i);
    const unsigned streams = r.triangles <= kPairedTriangles ? 2 : 1;
    detail::parallel_blocks(measured.size(), 1, streams, [&](unsigned, size_t k, size_t) {
        LevelReport& lr = r.levels[measured[k]];
        const Level l = extract_level(built, lr.vertices);
        lr.triangles = l.e.triangle_count;
        if (l.e.triangle_count > 0)
            lr.error = reference.compare({built.positions.data(), lr.vertices, l.indices.data(), l.e.triangle_count}, level_attributes, lr.attributes);
    });
    measure_parts(original, built, params, original_attributes, level_attributes, r.levels, first_of);
    std::vector<double> tris, means, maxes;
    for (size_t i = 0; i < r.levels.size(); ++i) {
        LevelReport& lr = r.levels[i];
        if (first_of[i] != i) {
            const LevelReport& same = r.levels[first_of[i]];
            lr.triangles = same.triangles, lr.error = same.error, lr.attributes = same.attributes;
        }
        if (lr.triangles > 0) {
            r.bbox_diagonal = std::max(r.bbox_diagonal, lr.error.diagonal);
            tris.push_back(lr.triangles);
            means.push_back(std::max(lr.error.forward.mean, lr.error.backward.mean) / lr.error.diagonal);
            maxes.push_back(lr.error.hausdorff / lr.error.diagonal);
        }
    }
    r.fit.mean = fit_k_over_n(tris, means);
    r.fit.max = fit_k_over_n(tris, maxes);
    if (curve.valid()) r.curve = curve.get();
    return r;
}

} // namespace tom
