// Metro-style distance against cases with known answers, the k/N fit, the stored error curve,
// and the report over a real mesh.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <future>
#include <random>

#include <thread>

#include <catch2/catch.hpp>

#include "support.h"
#include "tom/error_curve.h"
#include "tom/errors.h"
#include "tom/builder/writer.h"
#include "tom/format.h"
#include "tom/extract.h"
#include "tom/builder/generate.h"
#include "tom/io/import.h"
#include "tom/metrics/distance.h"
#include "tom/metrics/report.h"
#include "candidates.h"  // internal: the search's bounds and batched distances
#include "samples.h"     // internal: the samples' Morton order
#include "morton.h"

namespace {

tom::Surface surface(const tom::Mesh& m) { return {m.positions.data(), m.vertex_count(), m.indices.data(), m.triangle_count()}; }

// The surface of built mesh t at a fraction of its vertices; `idx` holds its indices.
tom::Surface level_surface(const tom::TomMesh& t, double fraction, std::vector<uint32_t>& idx) {
    idx.assign(size_t(t.triangle_count()) * 3, 0);
    const uint32_t n = tom::vertex_count_for_fraction(t.view(), fraction);
    const tom::Extracted e = tom::extract(t.view(), n, idx.data(), idx.size());
    return {t.positions.data(), n, idx.data(), e.triangle_count};
}

// An icosahedron with vertices on the sphere of radius r, and the same with each face cut into
// f x f triangles whose vertices are pushed out onto the sphere (a geodesic sphere).
tom::Mesh icosphere(int f, double r) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    const double base[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    const int faces[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                              {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    tom::Mesh m;
    for (const auto& face : faces) {
        const uint32_t first = m.vertex_count();
        // grid points a + i/f (b - a) + j/f (c - a), projected to the sphere (f = 1: the icosahedron)
        for (int i = 0; i <= f; ++i)
            for (int j = 0; i + j <= f; ++j) {
                double p[3];
                for (int k = 0; k < 3; ++k)
                    p[k] = base[face[0]][k] + (base[face[1]][k] - base[face[0]][k]) * i / f + (base[face[2]][k] - base[face[0]][k]) * j / f;
                const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
                for (int k = 0; k < 3; ++k) m.positions.push_back(float(p[k] / len * r));
            }
        auto id = [&](int i, int j) { return first + uint32_t(i * (f + 1) - i * (i - 1) / 2 + j); };
        for (int i = 0; i < f; ++i)
            for (int j = 0; i + j < f; ++j) {
                m.indices.insert(m.indices.end(), {id(i, j), id(i + 1, j), id(i, j + 1)});
                if (i + j + 1 < f) m.indices.insert(m.indices.end(), {id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
            }
    }
    return m;
}

} // namespace

TEST_CASE("a mesh against itself is at distance 0 in both directions", "[metrics]") {
    for (const test::NamedMesh& nm : test::real_meshes()) {
        INFO(nm.name);
        const tom::Distance d = tom::metro_distance(surface(nm.mesh), surface(nm.mesh));
        CHECK(d.hausdorff <= 1e-6 * d.diagonal);
        CHECK(d.forward.mean <= 1e-7 * d.diagonal);
        CHECK(d.backward.mean <= 1e-7 * d.diagonal);
        CHECK(d.forward.samples >= uint64_t(9.5 * nm.mesh.triangle_count()));  // Metro's budget: 10 per face
    }
}

TEST_CASE("a translated copy is at the translation, in both directions", "[metrics]") {
    // a flat grid moved along its normal by h: every sample is exactly h away
    tom::Mesh a = tom::make_grid(30, 30, 0.0f);
    tom::Mesh b = a;
    const float h = 0.0125f;
    for (size_t i = 2; i < b.positions.size(); i += 3) b.positions[i] += h;
    const tom::Distance d = tom::metro_distance(surface(a), surface(b));
    CHECK(d.forward.max == Approx(h).epsilon(1e-4));
    CHECK(d.forward.mean == Approx(h).epsilon(1e-4));
    CHECK(d.backward.rms == Approx(h).epsilon(1e-4));
    CHECK(d.hausdorff == Approx(h).epsilon(1e-4));
    // a closed surface moved sideways: distances are at most the shift, the max reaches it
    // (within sampling tolerance) where the surface faces the motion
    tom::Mesh s = test::generated_meshes()[0].mesh, s2 = s;
    const float dx = 0.01f;
    for (size_t i = 0; i < s2.positions.size(); i += 3) s2.positions[i] += dx;
    const tom::Distance e = tom::metro_distance(surface(s), surface(s2));
    CHECK(e.forward.max <= dx * 1.0001);
    CHECK(e.forward.max >= dx * 0.9);
    CHECK(e.backward.max <= dx * 1.0001);
    CHECK(e.backward.max >= dx * 0.9);
    CHECK(e.forward.mean < e.forward.max);
}

TEST_CASE("a sphere against its inscribed icosahedron: the known maximum distance", "[metrics]") {
    // the sphere's farthest points from the icosahedron lie above the face centres, at
    // R - inradius = R (1 - sqrt((5 + 2 sqrt 5) / 15)); a geodesic sphere of frequency 3 has a
    // vertex exactly there, so vertex sampling finds it
    const double R = 2.0;
    const double expected = R * (1.0 - std::sqrt((5.0 + 2.0 * std::sqrt(5.0)) / 15.0));
    const tom::Mesh sphere = icosphere(12, R), ico = icosphere(1, R);
    const tom::Distance d = tom::metro_distance(surface(sphere), surface(ico));
    INFO("expected " << expected << ", forward max " << d.forward.max << ", backward max " << d.backward.max);
    CHECK(d.forward.max == Approx(expected).epsilon(1e-5));
    CHECK(d.hausdorff == Approx(expected).epsilon(1e-5));
    CHECK(d.backward.max <= expected * 1.0001);  // the icosahedron lies inside the sphere's polyhedron
    CHECK(d.forward.mean < d.forward.max);
    // percentages: of the enlarged union box (both meshes span [-R, R]^3 up to 1e-6)
    CHECK(d.diagonal == Approx(std::sqrt(3.0) * (2 * R + 2 * 0.02 * 2 * R * std::sqrt(3.0))).epsilon(1e-5));
}

TEST_CASE("figures are repeatable: same seed and any thread count give identical results", "[metrics]") {
    const test::NamedMesh bunny = test::real_meshes()[0];
    const tom::TomMesh t = tom::build(bunny.mesh);
    std::vector<uint32_t> idx;
    const tom::Surface level = level_surface(t, 0.05, idx);
    tom::DistanceParams one, two, other_seed;
    one.threads = 1;
    two.threads = 2;
    other_seed.seed = 7;
    const tom::Distance a = tom::metro_distance(surface(bunny.mesh), level, one), b = tom::metro_distance(surface(bunny.mesh), level, two);
    CHECK(a.forward.mean == b.forward.mean);
    CHECK(a.backward.rms == b.backward.rms);
    CHECK(a.hausdorff == b.hausdorff);
    const tom::Distance c = tom::metro_distance(surface(bunny.mesh), level, other_seed);
    CHECK(c.forward.mean != a.forward.mean);                            // other samples...
    CHECK(c.forward.mean == Approx(a.forward.mean).epsilon(0.02));      // ...the same figure within sampling noise
}

TEST_CASE("a per-face cap on one direction's samples: a coarse level gets fewer, the figures stay within sampling noise", "[metrics][curve]") {
    // the error curve's setting: face samples only, a fixed total, at most 4 per face of the level
    const test::NamedMesh bunny = test::real_meshes()[0];
    const tom::TomMesh t = tom::build(bunny.mesh);
    std::vector<uint32_t> idx;
    const tom::Surface level = level_surface(t, 0.005, idx);
    tom::DistanceParams all;
    all.vertex_samples = all.edge_samples = false;
    all.samples_per_face = 1e9;
    all.max_samples = 16384;
    tom::DistanceParams capped = all;
    capped.max_samples_per_sampled_face = 4;
    const tom::Distance a = tom::metro_distance(surface(bunny.mesh), level, all), b = tom::metro_distance(surface(bunny.mesh), level, capped);
    INFO("level triangles " << level.triangle_count << ", backward samples " << a.backward.samples << " -> " << b.backward.samples);
    CHECK(a.forward.samples == b.forward.samples);  // the original has far more faces than the total
    CHECK(a.backward.samples >= 16000);
    CHECK(b.backward.samples >= uint64_t(3.5 * double(level.triangle_count)));  // each face's share rounded at random
    CHECK(b.backward.samples <= uint64_t(4.5 * double(level.triangle_count)));
    CHECK(a.forward.mean == b.forward.mean);
    CHECK(b.backward.mean == Approx(a.backward.mean).epsilon(0.05));
    CHECK(b.backward.max <= a.backward.max * 1.0001);  // a tenth of the samples: a lower max (with this seed)...
    CHECK(b.backward.max >= a.backward.max * 0.7);     // ...and not far below
}

TEST_CASE("one reference compared from several threads at once, and the curve on any thread count, give identical figures", "[metrics][curve]") {
    // four levels of a built mesh (40, 10, 2.5 and 0.6% of its triangles; idx holds their indices)
    auto four_levels = [](const tom::TomMesh& built, std::vector<std::vector<uint32_t>>& idx) {
        idx.assign(4, {});
        std::vector<tom::Surface> levels;
        for (size_t k = 0; k < idx.size(); ++k) levels.push_back(level_surface(built, 0.4 / double(1 << (2 * k)), idx[k]));
        return levels;
    };
    // each level compared on a thread of its own, all at once
    auto at_once = [](const tom::MetroReference& reference, const std::vector<tom::Surface>& levels) {
        std::vector<tom::Distance> out(levels.size());
        std::vector<std::thread> pool;
        for (size_t k = 0; k < levels.size(); ++k) pool.emplace_back([&, k] { out[k] = reference.compare(levels[k]); });
        for (std::thread& th : pool) th.join();
        return out;
    };
    const test::NamedMesh fandisk = test::real_meshes()[1];
    const tom::TomMesh t = tom::build(fandisk.mesh);
    std::vector<std::vector<uint32_t>> idx;
    const std::vector<tom::Surface> levels = four_levels(t, idx);
    const tom::MetroReference reference(surface(fandisk.mesh));
    std::vector<tom::Distance> alone;
    for (const tom::Surface& l : levels) alone.push_back(reference.compare(l));
    std::vector<tom::Distance> together = at_once(reference, levels);
    for (size_t k = 0; k < levels.size(); ++k) {
        INFO("level " << k);
        CHECK(together[k].forward.mean == alone[k].forward.mean);
        CHECK(together[k].backward.mean == alone[k].backward.mean);
        CHECK(together[k].hausdorff == alone[k].hausdorff);
        CHECK(alone[k].hausdorff > 0);
    }
    tom::ReportParams one, three;
    one.distance.threads = 1;
    three.distance.threads = 3;
    const std::vector<uint8_t> curve = tom::encode_error_curve(tom::measure_error_curve(fandisk.mesh, t, one));
    CHECK(curve == tom::encode_error_curve(tom::measure_error_curve(fandisk.mesh, t, three)));
    // a report's curve (its reference's search structure shared with the levels') is the one a
    // build without a report stores
    const tom::MeshReport with_curve = tom::make_report(fandisk.mesh, t);
    CHECK(tom::encode_error_curve(with_curve.curve) == curve);
    // without it (tombuild --no-error-curve), the same levels, and no curve
    tom::ReportParams no_curve;
    no_curve.error_curve = false;
    const tom::MeshReport without = tom::make_report(fandisk.mesh, t, no_curve);
    CHECK(without.curve.points.empty());
    REQUIRE(without.levels.size() == with_curve.levels.size());
    for (size_t k = 0; k < without.levels.size(); ++k) {
        CHECK(without.levels[k].error.forward.mean == with_curve.levels[k].error.forward.mean);
        CHECK(without.levels[k].error.backward.max == with_curve.levels[k].error.backward.max);
    }
    // a reference made from another with other parameters gives a fresh one's figures, while the
    // first is in use on other threads
    tom::DistanceParams sparse;
    sparse.samples_per_face = 2.5;
    sparse.seed = 7;
    const tom::MetroReference fresh(surface(fandisk.mesh), sparse);
    std::vector<tom::Distance> shared(levels.size());
    std::future<std::vector<tom::Distance>> in_use = std::async(std::launch::async, [&] { return at_once(reference, levels); });
    {
        const tom::MetroReference derived = reference.with_params(sparse);
        for (size_t k = 0; k < levels.size(); ++k) shared[k] = derived.compare(levels[k]);
    }
    together = in_use.get();
    for (size_t k = 0; k < levels.size(); ++k) {
        INFO("level " << k);
        const tom::Distance own = fresh.compare(levels[k]);
        CHECK(shared[k].forward.samples == own.forward.samples);
        CHECK(shared[k].forward.samples < alone[k].forward.samples);  // (the other parameters are in use)
        CHECK(shared[k].forward.mean == own.forward.mean);
        CHECK(shared[k].backward.mean == own.backward.mean);
        CHECK(shared[k].hausdorff == own.hausdorff);
        CHECK(together[k].hausdorff == alone[k].hausdorff);
    }
    // a small original (its search structure made by the first compare that needs it, not on a
    // thread of its own), first used by several threads at once
    const test::NamedMesh spider = test::real_meshes()[5];
    REQUIRE(spider.mesh.triangle_count() < 4096);
    const tom::TomMesh st = tom::build(spider.mesh);
    std::vector<std::vector<uint32_t>> small_idx;
    const std::vector<tom::Surface> small_levels = four_levels(st, small_idx);
    const tom::MetroReference small_reference(surface(spider.mesh));
    const std::vector<tom::Distance> first = at_once(small_reference, small_levels);
    const tom::MetroReference small_fresh(surface(spider.mesh));
    for (size_t k = 0; k < small_levels.size(); ++k) {
        INFO("spider level " << k);
        const tom::Distance again = small_fresh.compare(small_levels[k]);
        CHECK(first[k].backward.mean == again.backward.mean);
        CHECK(first[k].hausdorff == again.hausdorff);
        CHECK(first[k].hausdorff > 0);
    }
}

TEST_CASE("face hints change only the speed: the same figures with good but partial, poor or no hints (and a hint out of range is an error)", "[metrics][hints]") {
    // the engine's largest part (long thin CAD triangles, where the curve's searches were slowest)
    // and fandisk; dense (Metro's 10 per face) and sparse (the curve's 4096) samples
    const std::vector<test::NamedMesh> meshes = test::real_meshes();
    for (const test::NamedMesh* named : {&meshes[8], &meshes[1]}) {
        const tom::Mesh& mesh = named->mesh;
        const tom::TomMesh t = tom::build(mesh);
        REQUIRE(t.original_triangle.size() == t.triangle_count());
        tom::DistanceParams sparse;
        sparse.vertex_samples = sparse.edge_samples = false;
        sparse.samples_per_face = 1e9;
        sparse.max_samples = 4096;
        for (const tom::DistanceParams& params : {tom::DistanceParams{}, sparse}) {
            const tom::MetroReference reference(surface(mesh), params);
            for (double fraction : {0.3, 0.05, 0.005}) {
                INFO(named->name << " at " << fraction << ", " << (params.max_samples ? "sparse" : "dense"));
                std::vector<uint32_t> idx;
                const tom::Surface level = level_surface(t, fraction, idx);
                // good but partial hints: level face i lies over the original face it was sorted
                // from; an original face alive at the level is that level face, a dead one has none
                // (the curve's own hints, which also place dead faces, are checked at the end)
                std::vector<uint32_t> to_level(t.triangle_count(), tom::FaceHints::kNone);
                for (uint32_t i = 0; i < level.triangle_count; ++i) to_level[t.original_triangle[i]] = i;
                tom::FaceHints good_hints, poor_hints;
                good_hints.original_to_simplified = [&](uint32_t f) { return to_level[f]; };
                good_hints.simplified_to_original = [&](uint32_t i) { return t.original_triangle[i]; };
                // poor hints: every face points at one far corner of the other surface
                const uint32_t last = uint32_t(level.triangle_count - 1);
                poor_hints.original_to_simplified = [last](uint32_t) { return last; };
                poor_hints.simplified_to_original = [](uint32_t) { return 0u; };
                const tom::Distance plain = reference.compare(level);
                const tom::Distance good = reference.compare(level, good_hints);
                const tom::Distance poor = reference.compare(level, poor_hints);
                // exact searches, which stop within 2^-40 of the size: equal to far below any printed digit
                const double tolerance = 1e-11 * plain.diagonal;
                for (const tom::Distance* d : {&good, &poor}) {
                    CHECK(std::fabs(d->forward.mean - plain.forward.mean) <= tolerance);
                    CHECK(std::fabs(d->backward.mean - plain.backward.mean) <= tolerance);
                    CHECK(std::fabs(d->forward.rms - plain.forward.rms) <= tolerance);
                    CHECK(std::fabs(d->backward.rms - plain.backward.rms) <= tolerance);
                    CHECK(std::fabs(d->hausdorff - plain.hausdorff) <= tolerance);
                    CHECK(d->forward.samples == plain.forward.samples);
                    CHECK(d->backward.samples == plain.backward.samples);
                }
                CHECK(plain.forward.mean > 0);
                tom::FaceHints bad;  // every other face hinting past the end of the other surface
                bad.simplified_to_original = [&](uint32_t i) { return i % 2 ? uint32_t(t.triangle_count()) : t.original_triangle[i]; };
                CHECK_THROWS_AS(reference.compare(level, bad), tom::ArgumentError);
            }
        }
    }
    // the curve uses the built mesh's hints when it has them; without, the same curve
    const test::NamedMesh& engine_part = meshes[8];
    tom::TomMesh t = tom::build(engine_part.mesh);
    const std::vector<uint8_t> hinted = tom::encode_error_curve(tom::measure_error_curve(engine_part.mesh, t));
    t.original_triangle.clear();
    CHECK(tom::encode_error_curve(tom::measure_error_curve(engine_part.mesh, t)) == hinted);
}

TEST_CASE("the compact search gives the run search's figures, with and without hints, dense and sparse", "[metrics][compact]") {
    // fandisk (smooth, well shaped) and the engine's largest part (long thin CAD triangles), the
    // levels of each against the original in both directions
    const std::vector<test::NamedMesh> meshes = test::real_meshes();
    for (const test::NamedMesh* named : {&meshes[1], &meshes[8]}) {
        const tom::Mesh& mesh = named->mesh;
        const tom::TomMesh t = tom::build(mesh);
        tom::DistanceParams sparse;
        sparse.vertex_samples = sparse.edge_samples = false;
        sparse.samples_per_face = 1e9;
        sparse.max_samples = 4096;
        for (const tom::DistanceParams& params : {tom::DistanceParams{}, sparse}) {
            tom::DistanceParams compact_params = params;
            compact_params.compact_search_triangles = 1;  // (every surface: these are small)
            const tom::MetroReference run(surface(mesh), params);
            const tom::MetroReference compact(surface(mesh), compact_params);
            for (double fraction : {1.0, 0.3, 0.05, 0.005}) {
                INFO(named->name << " at " << fraction << ", " << (params.max_samples ? "sparse" : "dense"));
                std::vector<uint32_t> idx;
                const tom::Surface level = level_surface(t, fraction, idx);
                tom::FaceHints hints;
                hints.simplified_to_original = [&](uint32_t i) { return t.original_triangle[i]; };
                hints.original_to_simplified = [](uint32_t) { return 0u; };  // (a poor one: the search must still find the nearest)
                const tom::Distance expected = run.compare(level);
                for (const tom::Distance& d : {compact.compare(level), compact.compare(level, hints)}) {
                    const double tolerance = 1e-11 * expected.diagonal;  // (both stop within 2^-40 of the size on the surface)
                    CHECK(std::fabs(d.forward.mean - expected.forward.mean) <= tolerance);
                    CHECK(std::fabs(d.backward.mean - expected.backward.mean) <= tolerance);
                    CHECK(std::fabs(d.forward.rms - expected.forward.rms) <= tolerance);
                    CHECK(std::fabs(d.backward.rms - expected.backward.rms) <= tolerance);
                    CHECK(std::fabs(d.hausdorff - expected.hausdorff) <= tolerance);
                    CHECK(d.forward.samples == expected.forward.samples);
                    CHECK(d.backward.samples == expected.backward.samples);
                    CHECK(d.diagonal == expected.diagonal);
                }
                if (fraction < 1.0) CHECK(expected.hausdorff > 0);
            }
        }
    }
}

TEST_CASE("samples in batches give the figures of the whole, attribute deviation included", "[metrics][batches]") {
    // fandisk (its picks among Metro's face samples) and the engine's largest part (long edges
    // take the budget: the attribute deviation's own samples, batched too), with normals; batches
    // of 2,000 samples (dozens a direction) against none
    const std::vector<test::NamedMesh> meshes = test::real_meshes();
    for (const test::NamedMesh* named : {&meshes[1], &meshes[8]}) {
        tom::Mesh mesh = named->mesh;
        if (mesh.normals.empty()) tom::compute_normals(mesh);
        const tom::TomMesh t = tom::build(mesh);
        tom::DistanceParams whole, batched;
        whole.batch_samples = 0;
        batched.batch_samples = 2000;
        const tom::SurfaceAttributes oa{mesh.normals.data(), nullptr}, la{t.normals.data(), nullptr};
        const tom::MetroReference a(surface(mesh), whole, oa), b(surface(mesh), batched, oa);
        for (double fraction : {1.0, 0.2, 0.01}) {
            INFO(named->name << " at " << fraction);
            std::vector<uint32_t> idx;
            const tom::Surface level = level_surface(t, fraction, idx);
            tom::AttributeDeviation da, db;
            const tom::Distance x = a.compare(level, la, da), y = b.compare(level, la, db);
            REQUIRE(x.forward.samples > 4 * batched.batch_samples);  // (both directions in batches)
            REQUIRE(x.backward.samples > 4 * batched.batch_samples);
            const double tolerance = 1e-12 * x.diagonal;  // (the sums in another order)
            for (const auto& [p, q] : {std::pair{x.forward, y.forward}, std::pair{x.backward, y.backward}}) {
                CHECK(p.samples == q.samples);
                CHECK(p.vertex_samples == q.vertex_samples);
                CHECK(p.edge_samples == q.edge_samples);
                CHECK(p.face_samples == q.face_samples);
                INFO("max " << p.max << " and " << q.max);
                CHECK(std::fabs(p.max - q.max) <= tolerance);  // (at full detail, rounding noise: which of two coincident triangles is met first)
                CHECK(std::fabs(p.mean - q.mean) <= tolerance);
                CHECK(std::fabs(p.rms - q.rms) <= tolerance);
                CHECK(std::fabs(p.sampled_area - q.sampled_area) <= 1e-9 * p.sampled_area);
            }
            CHECK(std::fabs(x.hausdorff - y.hausdorff) <= tolerance);
            CHECK(da.samples == db.samples);
            CHECK(da.normals == db.normals);
            CHECK(da.normal_max_degrees == db.normal_max_degrees);
            CHECK(std::fabs(da.normal_mean_degrees - db.normal_mean_degrees) <= 1e-9);
            if (fraction < 1.0) CHECK(da.normal_mean_degrees > 0);
        }
    }
}

namespace {

// Squared distance from p to triangle (a, b, c) by the Voronoi regions of its vertices, edges and
// face (Ericson, Real-Time Collision Detection, 5.1.5): the reference for the search below.
double reference_d2(const double p[3], const double a[3], const double b[3], const double c[3]) {
    auto sub = [](const double* u, const double* v, double* out) { for (int k = 0; k < 3; ++k) out[k] = u[k] - v[k]; };
    auto dot = [](const double* u, const double* v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
    double ab[3], ac[3], ap[3], bp[3], cp[3], q[3];
    sub(b, a, ab), sub(c, a, ac), sub(p, a, ap), sub(p, b, bp), sub(p, c, cp);
    auto at = [&](double s, double t) {  // q = a + s ab + t ac
        for (int k = 0; k < 3; ++k) q[k] = a[k] + s * ab[k] + t * ac[k];
        double d[3];
        sub(p, q, d);
        return dot(d, d);
    };
    const double d1 = dot(ab, ap), d2 = dot(ac, ap), d3 = dot(ab, bp), d4 = dot(ac, bp), d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d1 <= 0 && d2 <= 0) return at(0, 0);
    if (d3 >= 0 && d4 <= d3) return at(1, 0);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return at(d1 / (d1 - d3), 0);
    if (d6 >= 0 && d5 <= d6) return at(0, 1);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return at(0, d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return at(1 - w, w);
    }
    const double denom = va + vb + vc;
    return at(vb / denom, vc / denom);
}

// nearest_squared_distances() against a brute-force search over every triangle of m, for points
// on, near and far from its surface and anywhere around it
void check_nearest_against_brute_force(const tom::Mesh& m) {
    const tom::Surface s = surface(m);
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (size_t i = 0; i < m.positions.size(); ++i) lo[i % 3] = std::min(lo[i % 3], double(m.positions[i])), hi[i % 3] = std::max(hi[i % 3], double(m.positions[i]));
    const double diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<double> points;
    auto corner = [&](uint32_t t, int k, int axis) { return double(m.positions[3 * size_t(m.indices[3 * t + k]) + axis]); };
    // points on random faces, then pushed off along the face normal by growing offsets: on the
    // surface, near it (runs share candidate lists) and far (lists would be long)
    for (double offset : {0.0, 1e-4, 1e-3, 1e-2, 0.1, 0.5}) {
        for (int i = 0; i < 400; ++i) {
            const uint32_t t = uint32_t(unit(rng) * double(m.triangle_count())) % m.triangle_count();
            double u = unit(rng), v = unit(rng);
            if (u + v > 1) u = 1 - u, v = 1 - v;
            double e1[3], e2[3], n[3];
            for (int k = 0; k < 3; ++k) e1[k] = corner(t, 1, k) - corner(t, 0, k), e2[k] = corner(t, 2, k) - corner(t, 0, k);
            n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            const double side = (i % 2 ? 1.0 : -1.0) * offset * diag / (len > 0 ? len : 1.0);
            for (int k = 0; k < 3; ++k) points.push_back(corner(t, 0, k) + u * e1[k] + v * e2[k] + side * n[k]);
        }
    }
    for (int i = 0; i < 400; ++i)  // anywhere in the box, enlarged by half its diagonal
        for (int k = 0; k < 3; ++k) points.push_back(lo[k] - 0.5 * diag + unit(rng) * (hi[k] - lo[k] + diag));
    const size_t count = points.size() / 3;
    std::vector<double> fast(count), two(count);
    tom::nearest_squared_distances(s, points.data(), count, fast.data(), 1);
    tom::nearest_squared_distances(s, points.data(), count, two.data(), 2);
    CHECK(fast == two);
    size_t wrong = 0;
    double worst = 0;
    for (size_t i = 0; i < count; ++i) {
        double best = INFINITY;
        for (uint32_t t = 0; t < m.triangle_count(); ++t) {
            double a[3], b[3], c[3];
            for (int k = 0; k < 3; ++k) a[k] = corner(t, 0, k), b[k] = corner(t, 1, k), c[k] = corner(t, 2, k);
            best = std::min(best, reference_d2(&points[3 * i], a, b, c));
        }
        const double error = std::fabs(std::sqrt(fast[i]) - std::sqrt(best));
        worst = std::max(worst, error);
        if (error > 1e-9 * diag) ++wrong;
    }
    INFO("worst difference " << worst << " of a diagonal of " << diag);
    CHECK(wrong == 0);
}

} // namespace

TEST_CASE("nearest distances equal a brute-force search, on, near and far from real surfaces", "[metrics][nearest]") {
    const std::vector<test::NamedMesh> meshes = test::real_meshes();
    for (const test::NamedMesh& nm : meshes) {
        if (nm.mesh.triangle_count() > 20000) continue;  // brute force over every triangle: keep it quick
        INFO(nm.name);
        check_nearest_against_brute_force(nm.mesh);
    }
}

TEST_CASE("nearest distances stay exact far from the origin and at huge scale (the searches' single-precision boxes)", "[metrics][nearest]") {
    // fandisk (about 1 wide, edges about 0.02) moved 5000 to 6000 away from the origin, where a
    // float's unit in the last place is 0.0005 to 0.001: box tests in single precision that
    // rounded carelessly would drop candidates there
    tom::ImportResult fandisk = tom::import_file(test::sample("meshes/fandisk.off"));
    REQUIRE(fandisk.meshes.size() == 1);
    tom::Mesh& m = fandisk.meshes[0];
    tom::clean_mesh(m);
    tom::Mesh huge = m;
    for (size_t i = 0; i < m.positions.size(); ++i) m.positions[i] += i % 3 == 1 ? -6000.0f : 5000.0f;
    check_nearest_against_brute_force(m);
    // and scaled to 1e17 (squares near single precision's limit: every box counts as near)
    for (float& x : huge.positions) x *= 1e17f;
    check_nearest_against_brute_force(huge);
}

// The search's float bounds (metrics/candidates.h) against doubles, on the triangles of real meshes
// (also moved 5000 away from the origin) and a degenerate one, for runs of points on, near and
// far from them: every bound is at most the exact distance (a candidate it drops cannot be the
// nearest) and within a fifth of a percent and the slack of the exact box-or-plane bound (it
// still prunes); points_below() keeps exactly the points whose bound is under their best, as
// bound() computes it; distances2() and distances2_at() equal distance2() bit for bit, and
// distance2_below() does under the best.
TEST_CASE("the search's float bounds never exceed the exact distance, and its batched distances equal distance2", "[metrics][nearest]") {
    using tom::detail::V3;
    std::vector<tom::Mesh> meshes;
    for (const test::NamedMesh& nm : test::real_meshes())
        if (nm.mesh.triangle_count() <= 20000) meshes.push_back(nm.mesh);
    REQUIRE(meshes.size() >= 3);
    tom::Mesh far = meshes.back();
    for (size_t i = 0; i < far.positions.size(); ++i) far.positions[i] += i % 3 == 1 ? -6000.0f : 5000.0f;
    meshes.push_back(far);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    size_t compared = 0, pruned = 0, kept = 0, lines_checked = 0;
    for (const tom::Mesh& m : meshes) {
        std::vector<tom::detail::Flat> flat;
        auto at = [&](uint32_t v) { return V3{m.positions[3 * size_t(v)], m.positions[3 * size_t(v) + 1], m.positions[3 * size_t(v) + 2]}; };
        for (size_t t = 0; t < m.triangle_count(); ++t) flat.push_back(tom::detail::make_flat(at(m.indices[3 * t]), at(m.indices[3 * t + 1]), at(m.indices[3 * t + 2])));
        flat.push_back(tom::detail::make_flat(at(0), at(1), at(0) + 1e-7 * (at(1) - at(0)) + 1e-9 * (at(2) - at(0))));  // a sliver
        flat.push_back(tom::detail::make_flat(at(0), at(0), at(1)));  // degenerate: two corners at one place
        for (int run = 0; run < 40; ++run) {
            // a run: 37 points around a random face, spread by up to `reach` (face sizes to
            // object sizes), and 64 candidates drawn from everywhere, the degenerate one among them
            const uint32_t home_index = uint32_t(size_t(unit(rng) * double(m.triangle_count())) % m.triangle_count());
            const tom::detail::Flat& home = flat[home_index];
            const double reach = std::sqrt(home.d00) * std::pow(10.0, 3.0 * unit(rng));
            std::vector<V3> points;
            for (int i = 0; i < 37; ++i) {
                double u = unit(rng), v = unit(rng);
                if (u + v > 1) u = 1 - u, v = 1 - v;
                const double off = i % 3 == 0 ? 0.0 : reach * (unit(rng) - 0.5);
                const V3 jitter{reach * (unit(rng) - 0.5) * (i % 4 == 3), 0.0, 0.0};
                points.push_back(home.a + u * home.e0 + v * home.e1 + off * home.normal + jitter);
            }
            V3 lo = points[0], hi = points[0];
            for (const V3& p : points)
                lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)}, hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
            std::vector<uint32_t> list;
            for (int k = 0; k < 61; ++k) list.push_back(uint32_t(unit(rng) * double(flat.size())) % uint32_t(flat.size()));
            list.push_back(home_index);  // (its points lie over it and beyond its edges: the edge lines' term)
            list.push_back(uint32_t(flat.size() - 2));
            list.push_back(uint32_t(flat.size() - 1));
            const V3 origin = 0.5 * (lo + hi);
            const double spread = 0.5 * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
            // the points relative to the origin in floats, each with the best of a random
            // candidate, padded to 40 with lanes no bound is under
            const size_t padded = (points.size() + 7) & ~size_t(7);
            std::vector<float> qx(padded, 0.0f), qy(padded, 0.0f), qz(padded, 0.0f), limit(padded, -INFINITY);
            std::vector<double> best(points.size());
            for (size_t i = 0; i < points.size(); ++i) {
                const V3 r = points[i] - origin;
                qx[i] = float(r.x), qy[i] = float(r.y), qz[i] = float(r.z);
                best[i] = tom::detail::distance2(flat[list[size_t(unit(rng) * 64.0) % 64]], points[i]);
                limit[i] = float(best[i]);
            }
            std::vector<uint32_t> hits(padded + 8);
            for (size_t k = 0; k < list.size(); ++k) {
                const tom::detail::Flat& f = flat[list[k]];
                const tom::detail::EdgeLines lines = tom::detail::edge_lines(f);
                const tom::detail::CandidateBound candidate = tom::detail::candidate_bound(f, lines, origin, spread);
                const size_t count = tom::detail::points_below(candidate, qx.data(), qy.data(), qz.data(), limit.data(), padded, hits.data());
                std::vector<uint32_t> expected;
                for (size_t i = 0; i < points.size(); ++i) {
                    const V3 p = points[i];
                    const float low = tom::detail::bound(candidate, qx[i], qy[i], qz[i]);
                    const double above = tom::detail::dot(f.normal, p) + f.offset;
                    // the exact bound: the box, or the plane's distance with the in-plane distance
                    // beyond the farthest edge line p's projection lies outside of
                    double beyond = 0;
                    for (int e = 0; e < 3; ++e) beyond = std::max(beyond, tom::detail::dot(lines.normal(e), p) + lines.offset[e]);
                    V3 box_lo, box_hi;
                    tom::detail::flat_box(f, box_lo, box_hi);
                    const double exact = std::max(tom::detail::point_box_d2(p, box_lo, box_hi), above * above + beyond * beyond);
                    const double d2 = tom::detail::distance2(f, p);
                    CHECK(double(low) <= d2);
                    if (!candidate.everything) CHECK(double(low) >= exact * 0.997 - double(candidate.slack) * 1.001);  // kKeep and the absolute slack
                    if (d2 < best[i]) CHECK(low < limit[i]);  // a candidate nearer than the best is always kept
                    if (low < limit[i]) expected.push_back(uint32_t(i));
                    // distance2_below(): distance2() itself under the best, at least the best otherwise
                    const double below = tom::detail::distance2_below(f, p, best[i]);
                    if (d2 < best[i])
                        CHECK(std::memcmp(&d2, &below, sizeof d2) == 0);
                    else
                        CHECK(below >= best[i]);
                    pruned += below != d2;
                    kept += low < limit[i];
                    ++compared;
                }
                CHECK(std::vector<uint32_t>(hits.begin(), hits.begin() + std::ptrdiff_t(count)) == expected);
            }
            // and of some of the points, in the order listed (as points_below() lists them)
            std::vector<uint32_t> some;
            for (uint32_t i = 0; i < points.size(); ++i)
                if (unit(rng) < 0.6) some.push_back(i);
            std::shuffle(some.begin(), some.end(), rng);
            for (uint32_t t : list) {
                std::vector<double> batched(points.size()), picked(some.size());
                tom::detail::distances2(flat[t], points.data(), points.size(), batched.data());
                tom::detail::distances2_at(flat[t], points.data(), some.data(), some.size(), picked.data());
                for (size_t i = 0; i < points.size(); ++i) {
                    const double one = tom::detail::distance2(flat[t], points[i]);
                    CHECK(std::memcmp(&one, &batched[i], sizeof one) == 0);
                }
                for (size_t h = 0; h < some.size(); ++h) CHECK(std::memcmp(&batched[some[h]], &picked[h], sizeof(double)) == 0);
            }
        }
    }
    CHECK(compared > 100000);
    CHECK(pruned > compared / 10);
    CHECK(kept < compared * 3 / 4);  // the bounds prune (against bests of random candidates: half are kept)
    // the edge lines of the real triangles: unit normals in the plane, each edge on its line, the
    // opposite corner inside; and the bound they make is tight where the box and the plane are
    // not: beyond an edge's midpoint by s in the plane and h above it, the distance is exactly
    // (s^2 + h^2), and so is the bound, up to its lowering
    for (const tom::Mesh& m : meshes)
        for (size_t t = 0; t < m.triangle_count(); t += 7) {
            auto at = [&](size_t c) { const float* q = &m.positions[3 * size_t(m.indices[3 * t + c])]; return V3{q[0], q[1], q[2]}; };
            const tom::detail::Flat f = tom::detail::make_flat(at(0), at(1), at(2));
            const tom::detail::EdgeLines lines = tom::detail::edge_lines(f);
            const double size = std::sqrt(std::max({f.d00, f.d11, tom::detail::dot(f.e1 - f.e0, f.e1 - f.e0)}));
            for (int e = 0; e < 3; ++e) {
                // (float normals: unit and in the plane to a float's rounding; the line through
                // the edge's first corner, its second within that rounding of the edge's length)
                const V3 n = lines.normal(e);
                if (tom::detail::dot(n, n) == 0) continue;  // (a sliver's: no term)
                CHECK(std::fabs(tom::detail::dot(n, n) - 1) < 1e-6);
                CHECK(std::fabs(tom::detail::dot(n, f.normal)) < 1e-6);
                CHECK(std::fabs(tom::detail::dot(n, at(size_t(e))) + lines.offset[e]) <= 1e-9 * (size + 1e-3 * std::sqrt(tom::detail::dot(at(0), at(0)))));
                CHECK(std::fabs(tom::detail::dot(n, at(size_t(e + 1) % 3)) + lines.offset[e]) <= 1e-6 * size + 1e-12 * std::sqrt(tom::detail::dot(at(0), at(0))));
                CHECK(tom::detail::dot(n, at(size_t(e + 2) % 3)) + lines.offset[e] <= 1e-6 * size);
                const double out = 0.5 * size, up = 0.25 * size;
                const V3 q = 0.5 * (at(size_t(e)) + at(size_t(e + 1) % 3)) + out * n + up * f.normal;
                const double d2 = tom::detail::distance2(f, q);
                CHECK(std::fabs(d2 - (out * out + up * up)) <= 1e-6 * d2);
                const tom::detail::CandidateBound b = tom::detail::candidate_bound(f, lines, q, 0.0);
                const float low = tom::detail::bound(b, 0.0f, 0.0f, 0.0f);
                CHECK(double(low) <= d2);
                CHECK(double(low) >= 0.99 * d2);
                ++lines_checked;
            }
        }
    CHECK(lines_checked > 1000);
}

// The searches group samples by octree cell, which needs them in Morton order. order_morton()
// sorts by a table of spread_bits() (spread16) and, for many samples, by one scatter on the top
// bits and then each bucket in cache: on real samples, fed in another order, each key must be
// the code spread_bits() gives its point's cell (on the grid the header describes: 16 bits an
// axis, fewer where the index needs more than 16 bits), keys ascending, equal keys in the order
// given, points moved with their keys, the same on one thread and two. bunny00's 754K samples and
// fandisk's 129K take the bucket sort (on the team with two threads), a few thousand the plain
// radix sort.
TEST_CASE("samples come in Morton order: each key its point's code, ascending, ties in the order given, on any thread count", "[metrics][samples]") {
    using tom::detail::V3;
    const std::vector<test::NamedMesh> meshes = test::real_meshes();
    for (size_t mi : {size_t(0), size_t(1)}) {
        INFO(meshes[mi].name);
        tom::detail::Samples made;
        tom::detail::MortonScratch scratch;
        tom::detail::sample_surface(surface(meshes[mi].mesh), 10 * meshes[mi].mesh.triangle_count(), tom::DistanceParams{}, made, scratch);
        for (const size_t count : {made.points.size(), size_t(5000)}) {
            // the input: the sorted samples taken backwards (equal keys then come in reverse)
            const std::vector<V3> input(made.points.rend() - std::ptrdiff_t(count), made.points.rend());
            std::vector<std::vector<uint64_t>> keys_of;
            for (unsigned threads : {1u, 2u}) {
                std::vector<V3> points = input;
                std::vector<uint64_t> keys;
                std::vector<uint32_t> from;
                double extent = 0;
                tom::detail::order_morton(points, keys, extent, scratch, threads, &from);
                REQUIRE(points.size() == count);
                REQUIRE(keys.size() == count);
                REQUIRE(from.size() == count);
                V3 lo = input[0], hi = input[0];
                for (const V3& p : input) {
                    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
                    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
                }
                CHECK(extent == std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}));
                int index_bits = 1;
                while ((uint64_t(1) << index_bits) < count) ++index_bits;
                const int drop = tom::detail::kMortonBits - std::min(tom::detail::kMortonBits, (64 - index_bits) / 3);
                const double scale = double((1u << tom::detail::kMortonBits) - 1) / extent;
                std::vector<uint8_t> used(count, 0);
                size_t wrong_code = 0, out_of_order = 0, moved_wrong = 0;
                for (size_t i = 0; i < count; ++i) {
                    REQUIRE(from[i] < count);
                    used[from[i]] = 1;
                    const V3 p = input[from[i]];
                    moved_wrong += !(points[i].x == p.x && points[i].y == p.y && points[i].z == p.z);
                    auto axis = [&](double x, double low) { return tom::detail::spread_bits(uint64_t(scale * (x - low)) >> drop); };
                    const uint64_t code = (axis(p.x, lo.x) << 2 | axis(p.y, lo.y) << 1 | axis(p.z, lo.z)) << (3 * drop);
                    wrong_code += keys[i] != code;
                    if (i > 0) out_of_order += keys[i] < keys[i - 1] || (keys[i] == keys[i - 1] && from[i] < from[i - 1]);
                }
                CHECK(wrong_code == 0);
                CHECK(out_of_order == 0);
                CHECK(moved_wrong == 0);
                CHECK(std::count(used.begin(), used.end(), 1) == std::ptrdiff_t(count));
                keys_of.push_back(keys);
            }
            CHECK(keys_of[0] == keys_of[1]);
        }
    }
    // the table is spread_bits() for every 16-bit coordinate
    size_t differ = 0;
    for (uint32_t x = 0; x < 65536; ++x) differ += tom::detail::spread16(x) != tom::detail::spread_bits(x);
    CHECK(differ == 0);
}

TEST_CASE("nearest distances: known answers for one triangle, a degenerate one, no points", "[metrics][nearest]") {
    // the triangle (0,0,0) (1,0,0) (0,1,0), and a collinear one along x from 2 to 4
    const float positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0, 3, 0, 0, 4, 0, 0};
    const uint32_t one[] = {0, 1, 2}, flat[] = {3, 4, 5};
    const double points[] = {0.25, 0.25, 2.0,    // above the face: its height
                             -1.0, -1.0, 0.0,    // beyond corner a: to (0,0,0)
                             0.5, -3.0, 4.0,     // beside edge ab: to (0.5,0,0)
                             2.0, 2.0, 0.0};     // beyond edge bc: to (0.5,0.5,0)
    double d2[4];
    tom::nearest_squared_distances({positions, 6, one, 1}, points, 4, d2);
    CHECK(d2[0] == Approx(4.0));
    CHECK(d2[1] == Approx(2.0));
    CHECK(d2[2] == Approx(25.0));
    CHECK(d2[3] == Approx(4.5));
    tom::nearest_squared_distances({positions, 6, flat, 1}, points, 4, d2);  // a segment from (2,0,0) to (4,0,0)
    CHECK(d2[0] == Approx(1.75 * 1.75 + 0.25 * 0.25 + 4.0));
    CHECK(d2[3] == Approx(4.0));
    tom::nearest_squared_distances({positions, 6, one, 1}, points, 0, d2);  // nothing to do, nothing written
    CHECK_THROWS_AS(tom::nearest_squared_distances({positions, 6, one, 0}, points, 4, d2), tom::ArgumentError);
}

TEST_CASE("the k/N fit recovers k from synthetic k/N data", "[metrics][fit]") {
    std::mt19937 rng(3);
    std::normal_distribution<double> noise(0.0, 0.05);
    for (double k : {0.3, 1.0, 12.5}) {
        std::vector<double> n, d;
        for (double tris : {100.0, 300.0, 1000.0, 3000.0, 10000.0, 30000.0}) {
            n.push_back(tris);
            d.push_back(k / tris * std::exp(noise(rng)));
        }
        const tom::KFit f = tom::fit_k_over_n(n, d);
        INFO("k " << k << " fitted " << f.k << " slope " << f.slope);
        CHECK(f.k == Approx(k).epsilon(0.05));
        CHECK(f.slope == Approx(-1.0).epsilon(0.1));
        CHECK(f.rms_log10 < 0.05);
        CHECK(f.used == 6);
    }
    CHECK(tom::fit_k_over_n({10, 0}, {0.0, 1.0}).used == 0);  // zero errors and counts are ignored
}

TEST_CASE("the stored error curve survives the file round trip and answers estimates", "[metrics][curve]") {
    const test::NamedMesh fandisk = test::real_meshes()[1];
    tom::TomMesh t = tom::build(fandisk.mesh);
    const tom::ErrorCurve curve = tom::measure_error_curve(fandisk.mesh, t);
    REQUIRE(curve.points.size() >= 8);
    CHECK(curve.points.back().vertices == t.vertex_count());
    CHECK(curve.points.back().mean == 0.0f);  // full resolution
    for (size_t i = 1; i < curve.points.size(); ++i) CHECK(curve.points[i].vertices > curve.points[i - 1].vertices);
    CHECK(curve.points.front().mean > curve.points[curve.points.size() / 2].mean);  // coarser is worse
    CHECK(curve.k_mean > 0);
    CHECK(curve.k_max > curve.k_mean);
    t.metadata.push_back({tom::error_curve_key, tom::encode_error_curve(curve)});
    const std::vector<uint8_t> bytes = tom::serialize({t});
    const tom::File file = tom::File::from_bytes(bytes.data(), bytes.size());
    const std::optional<tom::ErrorCurve> back = tom::read_error_curve(file.mesh(0));
    REQUIRE(back.has_value());
    CHECK(back->diagonal == curve.diagonal);
    CHECK(back->k_mean == curve.k_mean);
    CHECK(back->k_max == curve.k_max);
    REQUIRE(back->points.size() == curve.points.size());
    for (size_t i = 0; i < curve.points.size(); ++i) {
        CHECK(back->points[i].vertices == curve.points[i].vertices);
        CHECK(back->points[i].triangles == curve.points[i].triangles);
        CHECK(back->points[i].mean == curve.points[i].mean);
        CHECK(back->points[i].max == curve.points[i].max);
    }
    // estimates: exact at stored points, between neighbours inside, k/N-like outside
    const tom::ErrorCurvePoint& mid = curve.points[curve.points.size() / 2];
    CHECK(tom::estimate_error(*back, mid.triangles) == Approx(mid.mean));
    const tom::ErrorCurvePoint& p0 = curve.points[3];
    const tom::ErrorCurvePoint& p1 = curve.points[4];
    const double between = tom::estimate_error(*back, std::sqrt(double(p0.triangles) * p1.triangles));
    CHECK(between <= std::max(p0.mean, p1.mean) * 1.0001);
    CHECK(between >= std::min(p0.mean, p1.mean) * 0.9999);
    CHECK(tom::estimate_error(*back, 1.0) >= curve.points.front().mean);
    // a mesh without a curve, and a malformed value, read as absent
    const std::vector<uint8_t> plain = tom::serialize({tom::build(fandisk.mesh)});
    CHECK(!tom::read_error_curve(tom::File::from_bytes(plain.data(), plain.size()).mesh(0)).has_value());
    tom::TomMesh bad = tom::build(fandisk.mesh);
    bad.metadata.push_back({tom::error_curve_key, {1, 0, 0, 0, 200, 0, 0, 0}});
    const std::vector<uint8_t> bad_bytes = tom::serialize({bad});
    CHECK(!tom::read_error_curve(tom::File::from_bytes(bad_bytes.data(), bad_bytes.size()).mesh(0)).has_value());
}

TEST_CASE("a report on a real mesh: levels, error growth, memory like Table 4, errors near Pasman's k / N", "[metrics][report]") {
    const test::NamedMesh fandisk = test::real_meshes()[1];
    const tom::TomMesh t = tom::build(fandisk.mesh);
    const tom::MeshReport r = tom::make_report(fandisk.mesh, t);
    REQUIRE(r.levels.size() == 7);
    double previous_mean = 0;
    for (const tom::LevelReport& l : r.levels) {
        INFO("level " << l.fraction);
        CHECK(std::abs(double(l.triangles) - l.fraction * t.triangle_count()) <= 3.0);
        const double mean = std::max(l.error.forward.mean, l.error.backward.mean);
        CHECK(mean > previous_mean);  // coarser levels are farther from the original
        previous_mean = mean;
        CHECK(l.error.hausdorff >= mean);
        CHECK(l.error.forward.samples >= uint64_t(9.5 * t.triangle_count()));
        CHECK(l.chain.corners == uint64_t(l.triangles) * 3);
        CHECK(l.extract_seconds > 0);
    }
    CHECK(r.levels.back().mean_steps > r.levels.front().mean_steps);
    const double fv = double(r.memory.face_vertex_bytes);
    CHECK(r.memory.tom_bytes / fv < 1.09);  // the paper: 108%
    CHECK(r.memory.tom_bytes / fv > 1.0);
    CHECK(r.memory.lod_bytes / fv > 1.9);   // 100+50+25+12+6+3 = 196%
    CHECK(r.memory.lod_bytes / fv < 2.0);
    CHECK(r.memory.pm_max_bytes > r.memory.pm_bytes);
    // Pasman & Jansen: D = k / N, with k about ten times larger for the maximum than for the mean
    // error. The levels' errors fall as a power of N near -1 (the free slope), the k / N model
    // predicts each within a factor of 5 (RMS of the log10 residuals), and k_max / k_mean is near 10.
    for (const tom::KFit* fit : {&r.fit.mean, &r.fit.max}) {
        INFO("k " << fit->k << " slope " << fit->slope << " rms_log10 " << fit->rms_log10);
        CHECK(fit->used == r.levels.size());
        CHECK(fit->k > 0);
        CHECK(fit->slope < -0.7);
        CHECK(fit->slope > -2.0);
        CHECK(fit->rms_log10 < 0.7);
    }
    CHECK(r.fit.max.k / r.fit.mean.k > 3);
    CHECK(r.fit.max.k / r.fit.mean.k < 30);
    CHECK(r.bbox_diagonal > 0);
    // the figures do not depend on the number of threads
    tom::ReportParams serial;
    serial.distance.threads = 1;
    const tom::MeshReport s = tom::make_report(fandisk.mesh, t, serial);
    REQUIRE(s.levels.size() == r.levels.size());
    for (size_t i = 0; i < r.levels.size(); ++i) {
        INFO("level " << r.levels[i].fraction);
        CHECK(s.levels[i].error.forward.mean == r.levels[i].error.forward.mean);
        CHECK(s.levels[i].error.forward.rms == r.levels[i].error.forward.rms);
        CHECK(s.levels[i].error.backward.mean == r.levels[i].error.backward.mean);
        CHECK(s.levels[i].error.hausdorff == r.levels[i].error.hausdorff);
        CHECK(s.levels[i].attributes.normal_mean_degrees == r.levels[i].attributes.normal_mean_degrees);
    }
    CHECK(s.fit.mean.k == r.fit.mean.k);
}

TEST_CASE("attribute deviation: among triangles at the same distance, the one first in the mesh is the nearest", "[metrics][attributes]") {
    // a grid with normals +z, against a surface made of the grid twice over, one copy with
    // normals tilted by 10 degrees: every sample lies at the same distance from both copies
    // (the same corners, the same operations), and the copy listed first decides, whichever the
    // searches meet first
    tom::Mesh a = tom::make_grid(20, 20);
    a.normals.clear();
    for (uint32_t v = 0; v < a.vertex_count(); ++v) a.normals.insert(a.normals.end(), {0.0f, 0.0f, 1.0f});
    const double angle = 10.0 * 3.14159265358979 / 180.0;
    std::vector<float> tilted;
    for (uint32_t v = 0; v < a.vertex_count(); ++v) tilted.insert(tilted.end(), {0.0f, float(std::sin(angle)), float(std::cos(angle))});
    auto twice = [&](const std::vector<float>& first, const std::vector<float>& second) {
        tom::Mesh d = a;
        d.positions.insert(d.positions.end(), a.positions.begin(), a.positions.end());
        d.normals = first;
        d.normals.insert(d.normals.end(), second.begin(), second.end());
        for (uint32_t i : a.indices) d.indices.push_back(i + a.vertex_count());
        return d;
    };
    for (int tilted_first = 0; tilted_first < 2; ++tilted_first) {
        const tom::Mesh d = tilted_first ? twice(tilted, a.normals) : twice(a.normals, tilted);
        for (unsigned threads : {1u, 2u}) {
            tom::DistanceParams p;
            p.threads = threads;
            const tom::MetroReference by(surface(a), p, {a.normals.data(), nullptr});
            tom::AttributeDeviation dev;
            const tom::Distance dist = by.compare(surface(d), {d.normals.data(), nullptr}, dev);
            INFO("tilted copy first: " << tilted_first << ", threads " << threads);
            CHECK(dist.hausdorff < 1e-12);
            CHECK(dev.normal_mean_degrees == Approx(tilted_first ? 10.0 : 0.0).margin(1e-4));
            CHECK(dev.normal_max_degrees == Approx(tilted_first ? 10.0 : 0.0).margin(1e-4));
        }
    }
}

TEST_CASE("attribute deviation: 0 against itself, the known angle and shift against altered copies", "[metrics][attributes]") {
    // a grid with one UV chart (uv = xy) and normals +z, against copies whose normals are tilted
    // by 10 degrees about x and whose UVs are shifted by (0.1, 0)
    tom::Mesh a = tom::make_grid(20, 20);
    a.normals.clear();
    for (uint32_t v = 0; v < a.vertex_count(); ++v) {
        a.normals.insert(a.normals.end(), {0.0f, 0.0f, 1.0f});
        a.texcoords.insert(a.texcoords.end(), {a.positions[3 * v], a.positions[3 * v + 1]});
    }
    const tom::SurfaceAttributes aa{a.normals.data(), a.texcoords.data()};
    const tom::MetroReference reference(surface(a), {}, aa);
    tom::AttributeDeviation same;
    reference.compare(surface(a), aa, same);
    CHECK(same.normals);
    CHECK(same.texcoords);
    CHECK(same.samples >= 2 * a.triangle_count() - 20);
    CHECK(same.normal_mean_degrees < 1e-3);
    CHECK(same.uv_mean < 1e-6);
    tom::Mesh b = a;
    const double angle = 10.0 * 3.14159265358979 / 180.0;
    for (size_t i = 0; i < b.normals.size(); i += 3) b.normals[i + 1] = float(std::sin(angle)), b.normals[i + 2] = float(std::cos(angle));
    for (size_t i = 0; i < b.texcoords.size(); i += 2) b.texcoords[i] += 0.1f;
    tom::AttributeDeviation moved;
    reference.compare(surface(b), {b.normals.data(), b.texcoords.data()}, moved);
    CHECK(moved.normal_mean_degrees == Approx(10.0).epsilon(1e-4));
    CHECK(moved.normal_max_degrees == Approx(10.0).epsilon(1e-4));
    CHECK(moved.uv_mean == Approx(0.1).epsilon(1e-4));
    // without texture coordinates on one side, only normals are compared
    tom::AttributeDeviation normals_only;
    reference.compare(surface(b), {b.normals.data(), nullptr}, normals_only);
    CHECK(normals_only.normals);
    CHECK(!normals_only.texcoords);
}

TEST_CASE("attribute deviation where long edges take Metro's budget: face samples of its own", "[metrics][attributes]") {
    // a grid stretched 300 times along x: the points along its edges take the whole budget (the
    // forward direction has fewer face samples than one per face), as on CAD parts
    tom::Mesh a = tom::make_grid(20, 20);
    a.normals.clear();
    for (uint32_t v = 0; v < a.vertex_count(); ++v) {
        a.positions[3 * v] *= 300.0f;
        a.normals.insert(a.normals.end(), {0.0f, 0.0f, 1.0f});
    }
    const tom::SurfaceAttributes aa{a.normals.data(), nullptr};
    const tom::MetroReference reference(surface(a), {}, aa);
    tom::AttributeDeviation same;
    const tom::Distance d = reference.compare(surface(a), aa, same);
    CHECK(d.forward.face_samples < a.triangle_count());
    CHECK(same.normals);
    CHECK(!same.texcoords);
    CHECK(same.samples >= 2 * a.triangle_count() - 20);
    CHECK(same.normal_mean_degrees < 1e-3);
    tom::Mesh b = a;
    const double angle = 10.0 * 3.14159265358979 / 180.0;
    for (size_t i = 0; i < b.normals.size(); i += 3) b.normals[i + 1] = float(std::sin(angle)), b.normals[i + 2] = float(std::cos(angle));
    tom::AttributeDeviation moved;
    const tom::Distance e = reference.compare(surface(b), {b.normals.data(), nullptr}, moved);
    CHECK(moved.normal_mean_degrees == Approx(10.0).epsilon(1e-4));
    CHECK(moved.normal_max_degrees == Approx(10.0).epsilon(1e-4));
    // the distances are those of Metro's samples alone
    CHECK(e.forward.samples == d.forward.samples);
    CHECK(e.forward.max < 1e-9);
}

namespace {

// Metro mean error (relative), mean normal deviation and UV displacement of a level
struct LevelError {
    double geometry, normal_degrees, uv;
};

LevelError level_error(const tom::Mesh& original, const tom::TomMesh& t, double fraction) {
    std::vector<uint32_t> idx;
    const tom::Surface level = level_surface(t, fraction, idx);
    const tom::MetroReference reference(surface(original), {}, {original.normals.data(), original.texcoords.empty() ? nullptr : original.texcoords.data()});
    tom::AttributeDeviation a;
    const tom::Distance d = reference.compare(level, {t.normals.data(), t.texcoords.empty() ? nullptr : t.texcoords.data()}, a);
    return {std::max(d.forward.mean, d.backward.mean) / d.diagonal, a.normal_mean_degrees, a.uv_mean};
}

} // namespace

TEST_CASE("the attribute term keeps shading and texture layout at little geometric cost", "[metrics][attributes][builder]") {
    // fandisk: a CAD part whose creases carry the (computed) normals; ClearCoatTest: textured spheres
    const tom::Mesh fandisk = test::real_meshes()[1].mesh;
    REQUIRE(test::real_meshes()[1].name.find("fandisk") != std::string::npos);
    for (const tom::Predicate predicate : {tom::Predicate::quadric, tom::Predicate::memoryless}) {
        INFO(tom::to_string(predicate));
        tom::BuildParams with, without;
        with.predicate = without.predicate = predicate;
        without.attribute_weight = 0.0f;
        const LevelError a = level_error(fandisk, tom::build(fandisk, with), 0.25), g = level_error(fandisk, tom::build(fandisk, without), 0.25);
        INFO("normal deviation " << a.normal_degrees << " vs " << g.normal_degrees << " degrees; geometry " << a.geometry << " vs " << g.geometry);
        CHECK(a.normal_degrees < 0.1 * g.normal_degrees);
        CHECK(a.geometry < 2.0 * g.geometry);
    }
    tom::ImportResult r = tom::import_file(test::sample("assimp/glTF2/ClearCoat-glTF/ClearCoatTest.gltf"));
    double uv_with = 0, uv_without = 0, geo_with = 0, geo_without = 0;
    for (tom::Mesh& m : r.meshes) {
        tom::clean_mesh(m);
        if (m.texcoords.empty() || m.triangle_count() < 1000) continue;
        tom::BuildParams without;
        without.attribute_weight = 0.0f;
        const LevelError a = level_error(m, tom::build(m), 0.05), g = level_error(m, tom::build(m, without), 0.05);
        uv_with += a.uv, uv_without += g.uv, geo_with += a.geometry, geo_without += g.geometry;
    }
    INFO("UV displacement at 5% " << uv_with << " vs " << uv_without << "; geometry " << geo_with << " vs " << geo_without);
    REQUIRE(uv_without > 0);
    CHECK(uv_with < 0.95 * uv_without);  // measured 0.69
    // seams move now (as groups), and only the build without the attribute term moves them off
    // their texture charts freely: measured 1.10
    CHECK(geo_with < 1.2 * geo_without);
}

TEST_CASE("vertex_count_for_error takes the coarsest level from which every measured point is within the bound", "[metrics][curve]") {
    tom::MeshView mesh;
    mesh.vertex_count = 50;
    mesh.min_vertex_count = 5;
    tom::ErrorCurve curve;
    curve.diagonal = 1.0f;
    // measured errors need not fall monotonically: 30 vertices is worse than 20
    curve.points = {{10, 16, 0.01f, 0.05f}, {20, 36, 0.002f, 0.01f}, {30, 56, 0.004f, 0.02f}, {40, 76, 0.0002f, 0.001f}};
    CHECK(tom::vertex_count_for_error(mesh, curve, 0.015) == 40);  // 30's 2% stops the walk down
    CHECK(tom::vertex_count_for_error(mesh, curve, 0.03) == 20);
    CHECK(tom::vertex_count_for_error(mesh, curve, 0.051) == 10);
    CHECK(tom::vertex_count_for_error(mesh, curve, 0.0001) == 50);  // none within: full detail, error 0
    CHECK(tom::vertex_count_for_error(mesh, curve, 0.005, false) == 20);  // the mean curve
    CHECK(tom::vertex_count_for_error(mesh, curve, 0.003, false) == 40);
    mesh.min_vertex_count = 25;  // points below the coarsest resolution are not levels of this mesh
    CHECK(tom::vertex_count_for_error(mesh, curve, 1.0) == 30);
}

TEST_CASE("the usable floor: where a real asset's measured mean error leaves the bound, bracketed narrowly, respected unless asked", "[metrics][curve][floor]") {
    // Wuson's last steps before its chain's floor take the mean error from about 1% to 11% of the
    // diagonal (between 108 and 77 triangles): the chain goes on where the asset stops being usable
    const test::NamedMesh wuson = test::real_meshes()[4];
    REQUIRE(wuson.name.find("Wuson") != std::string::npos);
    tom::TomMesh t = tom::build(wuson.mesh);
    tom::ReportParams params;
    params.floor_error = 0.01;
    const tom::ErrorCurve curve = tom::measure_error_curve(wuson.mesh, t, params);
    const tom::UsableFloor floor = tom::usable_floor_of(t.view(), curve, params.floor_error);
    INFO("floor " << floor.vertices << " of " << t.vertex_count() << " vertices, chain's floor " << t.min_vertex_count);
    REQUIRE(floor.vertices > t.min_vertex_count);
    REQUIRE(floor.vertices < t.vertex_count() / 4);
    // every measured point from the floor on is within the bound; the one below it is not, and
    // lies within 2% of the floor (the bisection; the log-spaced points alone are 22% apart)
    size_t at = 0;
    while (curve.points[at].vertices < floor.vertices) ++at;
    REQUIRE(at > 0);
    for (size_t i = at; i < curve.points.size(); ++i) CHECK(curve.points[i].mean <= params.floor_error);
    const tom::ErrorCurvePoint& below = curve.points[at - 1];
    CHECK(below.mean > params.floor_error);
    CHECK(double(floor.vertices) <= 1.02 * double(below.vertices) + 2);
    // Metro's dense figures agree: the floor's level within the bound (up to sampling), the chain's
    // coarsest level far beyond it
    tom::ReportParams dense;
    dense.levels = {double(tom::active_triangle_count(t.view(), floor.vertices)) / t.triangle_count(), 0.0};
    dense.error_curve = false;
    const tom::MeshReport report = tom::make_report(wuson.mesh, t, dense);
    REQUIRE(report.levels[0].vertices == floor.vertices);
    const auto relative_mean = [](const tom::LevelReport& l) { return std::max(l.error.forward.mean, l.error.backward.mean) / l.error.diagonal; };
    CHECK(relative_mean(report.levels[0]) <= 1.25 * params.floor_error);
    CHECK(relative_mean(report.levels[1]) > 4 * params.floor_error);

    // stored, every selection by count, fraction or error stops there unless asked
    t.metadata.push_back({tom::error_curve_key, tom::encode_error_curve(curve)});
    t.metadata.push_back({tom::usable_floor_key, tom::encode_usable_floor(floor)});
    const std::vector<uint8_t> bytes = tom::serialize({t});
    const tom::File file = tom::File::from_bytes(bytes.data(), bytes.size());
    const tom::MeshView& m = file.mesh(0);
    REQUIRE(tom::read_usable_floor(m).has_value());
    CHECK(tom::read_usable_floor(m)->mean_bound == float(params.floor_error));
    const uint32_t n = tom::floor_vertex_count(m);
    CHECK(n == m.whole_groups_above(floor.vertices));
    CHECK(tom::floor_vertex_count(m, tom::Floor::coarsest) == m.min_vertex_count);
    CHECK(tom::vertex_count_for_fraction(m, 0.0) == n);
    CHECK(tom::vertex_count_for_fraction(m, 0.001) == n);
    CHECK(tom::vertex_count_for_fraction(m, 0.0, tom::Floor::coarsest) == m.min_vertex_count);
    CHECK(tom::vertex_count_for_triangles(m, 1) == n);
    CHECK(tom::vertex_count_within_triangles(m, 1) == n);
    CHECK(tom::vertex_count_within_triangles(m, 1, tom::Floor::coarsest) == m.min_vertex_count);
    CHECK(tom::vertex_count_for_error(m, curve, 1.0, false) == n);
    CHECK(tom::vertex_count_for_error(m, curve, 1.0, false, tom::Floor::coarsest) < n);
    // above the floor nothing changes
    const uint32_t half = tom::vertex_count_for_fraction(m, 0.5);
    CHECK(half == tom::vertex_count_for_fraction(m, 0.5, tom::Floor::coarsest));
    CHECK(half > n);

    // a malformed value, or a floor outside the mesh's range, reads as absent
    for (const std::vector<uint8_t>& value : {std::vector<uint8_t>{1, 0, 0, 0, 5, 0, 0, 0}, tom::encode_usable_floor({t.vertex_count() + 1, 0.01f}),
                                              tom::encode_usable_floor({t.min_vertex_count - 1, 0.01f}), tom::encode_usable_floor({floor.vertices, -1.0f})}) {
        tom::TomMesh bad = t;
        bad.metadata.back().second = value;
        const std::vector<uint8_t> bad_bytes = tom::serialize({bad});
        const tom::File bad_file = tom::File::from_bytes(bad_bytes.data(), bad_bytes.size());
        CHECK(!tom::read_usable_floor(bad_file.mesh(0)).has_value());
        CHECK(tom::vertex_count_for_fraction(bad_file.mesh(0), 0.0) == bad_file.mesh(0).min_vertex_count);
    }
}

TEST_CASE("the error curve reaches the coarsest level: a floor's quad is not free to halve", "[metrics][curve][floor]") {
    // a quad of two triangles (a floor, a wall, a decal) has one coarser level, a triangle covering
    // half of it; a curve starting above it made every selection read that level as free
    const tom::Mesh quad = tom::make_grid(1, 1, 0.0f);
    REQUIRE(quad.vertex_count() == 4);
    const tom::TomMesh t = tom::build(quad);
    REQUIRE(t.min_vertex_count == 3);
    tom::ReportParams params;
    params.floor_error = 0.01;
    const tom::ErrorCurve curve = tom::measure_error_curve(quad, t, params);
    REQUIRE(curve.points.size() == 2);
    CHECK(curve.points[0].vertices == 3);
    CHECK(curve.points[0].triangles == 1);
    CHECK(curve.points[0].mean > 0.02);  // a quarter of the square's area, a third of its width away
    CHECK(curve.k_mean > 0);
    CHECK(tom::usable_floor_of(t.view(), curve, params.floor_error).vertices == 4);
    // a real mesh's curve starts at its chain's coarsest level too
    const test::NamedMesh wuson = test::real_meshes()[4];
    const tom::TomMesh w = tom::build(wuson.mesh);
    CHECK(tom::measure_error_curve(wuson.mesh, w, params).points.front().vertices == w.min_vertex_count);
}
