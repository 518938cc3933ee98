// Extraction: 16- and 32-bit outputs, capacity limits, resolution queries, chain statistics.

#include <algorithm>
#include <array>
#include <set>

#include <catch2/catch.hpp>

#include "support.h"
#include "tom/builder/builder.h"
#include "tom/extract.h"
#include "tom/builder/writer.h"
#include "tom/format.h"
#include "tom/builder/generate.h"

namespace {

struct Built {
    test::NamedMesh input;
    tom::TomMesh tom;
    std::vector<uint8_t> bytes;  // serialized: 16-bit indices where they fit
};

Built bunny() {
    Built b;
    for (test::NamedMesh& nm : test::real_meshes())
        if (nm.name.find("bunny00") != std::string::npos) b.input = std::move(nm);
    REQUIRE(b.input.mesh.vertex_count() > 30000);
    b.tom = tom::build(b.input.mesh);
    b.bytes = tom::serialize({b.tom});
    return b;
}

} // namespace

TEST_CASE("16-bit and 32-bit storage and outputs agree with brute force at every sampled resolution", "[extract]") {
    const Built b = bunny();
    const tom::File file = tom::File::from_bytes(b.bytes.data(), b.bytes.size(), "bunny.tom");
    const tom::MeshView& m16 = file.mesh(0);
    REQUIRE(m16.index_size == 2);
    const tom::MeshView m32 = b.tom.view();
    std::vector<uint32_t> a(size_t(m32.triangle_count) * 3), c(a.size());
    std::vector<uint16_t> d(a.size());
    std::vector<uint32_t> resolutions;
    for (uint32_t n = m32.min_vertex_count; n < m32.vertex_count; n += 997) resolutions.push_back(n);
    resolutions.push_back(m32.vertex_count);  // full resolution: a copy (16-bit corners widened)
    for (const uint32_t n : resolutions) {
        INFO("resolution " << n);
        const std::vector<uint32_t> expect = test::brute_force_active(m32, n);
        const tom::Extracted r1 = tom::extract(m32, n, a.data(), a.size());
        const tom::Extracted r2 = tom::extract(m16, n, c.data(), c.size());
        const tom::Extracted r3 = tom::extract(m16, n, d.data(), d.size());
        REQUIRE(r1.triangle_count * 3 == expect.size());
        REQUIRE(r2.triangle_count == r1.triangle_count);
        REQUIRE(r3.triangle_count == r1.triangle_count);
        for (size_t i = 0; i < expect.size(); ++i) {
            REQUIRE(a[i] == expect[i]);
            REQUIRE(c[i] == expect[i]);
            REQUIRE(d[i] == expect[i]);
        }
    }
}

TEST_CASE("a mesh whose substitute array is not cache-resident (gathers to the end) agrees with brute force", "[extract]") {
    // bunny00's array (75-150 KB) takes the straggler path; this one (> 256 KB, 32-bit) does not
    tom::Mesh sphere = tom::make_sphere(260, 260, 1.0f, 0.05f);
    tom::clean_mesh(sphere);
    const tom::TomMesh t = tom::build(sphere);
    const tom::MeshView m = t.view();
    REQUIRE(size_t(m.vertex_count) * 4 > 256 * 1024);
    std::vector<uint32_t> out(size_t(m.triangle_count) * 3);
    for (uint32_t n = m.min_vertex_count; n <= m.vertex_count; n += 4999) {
        INFO("resolution " << n);
        const std::vector<uint32_t> expect = test::brute_force_active(m, n);
        const tom::Extracted r = tom::extract(m, n, out.data(), out.size());
        REQUIRE(r.triangle_count * 3 == expect.size());
        REQUIRE(std::equal(expect.begin(), expect.end(), out.begin()));
    }
}

TEST_CASE("coarse corners (COAR): extraction through them equals brute force at every resolution up to theirs", "[extract][coarse]") {
    const Built b = bunny();
    tom::WriteOptions wide;
    wide.index_size = tom::IndexSize::bits32;
    const std::vector<uint8_t> bytes32 = tom::serialize({b.tom}, wide);
    const tom::File f16 = tom::File::from_bytes(b.bytes.data(), b.bytes.size(), "bunny16.tom");
    const tom::File f32 = tom::File::from_bytes(bytes32.data(), bytes32.size(), "bunny32.tom");
    const tom::MeshView plain = b.tom.view();  // in memory: no coarse corners
    REQUIRE(plain.coarse_corners == nullptr);
    for (const tom::MeshView* m : {&f16.mesh(0), &f32.mesh(0)}) {
        // 1/64 of the vertices, 16-bit: about 0.4% of the file
        REQUIRE(m->coarse_corners != nullptr);
        CHECK(m->coarse_resolution == m->vertex_count / 64);
        CHECK(m->coarse_index_size == 2);
        CHECK(m->coarse_triangle_count == test::brute_force_active(plain, m->coarse_resolution).size() / 3);
        std::vector<uint32_t> got(size_t(plain.triangle_count) * 3);
        std::vector<uint16_t> got16(got.size());
        for (uint32_t n = plain.min_vertex_count; n <= m->coarse_resolution + 2; ++n) {
            INFO("resolution " << n << ", " << m->index_size << "-byte storage");
            const std::vector<uint32_t> expect = test::brute_force_active(plain, n);
            REQUIRE(tom::active_triangle_count(*m, n) * 3 == expect.size());
            const tom::Extracted r = tom::extract(*m, n, got.data(), got.size());
            const tom::Extracted r16 = tom::extract(*m, n, got16.data(), got16.size());
            REQUIRE(r.triangle_count * 3 == expect.size());
            REQUIRE(r16.triangle_count == r.triangle_count);
            REQUIRE(std::equal(expect.begin(), expect.end(), got.begin()));
            REQUIRE(std::equal(expect.begin(), expect.end(), got16.begin()));
            // a short buffer takes the first whole triangles
            const tom::Extracted part = tom::extract(*m, n, got.data(), 3 * (r.triangle_count / 2) + 2);
            REQUIRE(part.triangle_count == r.triangle_count / 2);
        }
    }
}

TEST_CASE("extraction never writes past the capacity it is given", "[extract]") {
    const Built b = bunny();
    const tom::File file = tom::File::from_bytes(b.bytes.data(), b.bytes.size(), "bunny.tom");
    for (const tom::MeshView& m : {b.tom.view(), file.mesh(0)})  // 32- and 16-bit corners
        for (const uint32_t n : {m.vertex_count / 3, m.vertex_count}) {
            INFO("index size " << m.index_size << ", resolution " << n);
            const uint32_t active = tom::active_triangle_count(m, n);
            std::vector<uint32_t> buf(size_t(active) * 3 + 64, 0xFFFFFFFFu);
            for (size_t cap : {size_t(0), size_t(2), size_t(3), size_t(100), size_t(active) * 3 - 1, size_t(active) * 3}) {
                std::fill(buf.begin(), buf.end(), 0xFFFFFFFFu);
                const tom::Extracted r = tom::extract(m, n, buf.data(), cap);
                CHECK(r.triangle_count == std::min<size_t>(active, cap / 3));
                for (size_t i = size_t(r.triangle_count) * 3; i < buf.size(); ++i) REQUIRE(buf[i] == 0xFFFFFFFFu);
            }
        }
}

TEST_CASE("resolution queries: clamping, smallest n for a triangle count, fractions", "[extract]") {
    const Built b = bunny();
    const tom::MeshView m = b.tom.view();
    CHECK(tom::active_triangle_count(m, 0) == tom::active_triangle_count(m, m.min_vertex_count));
    CHECK(tom::active_triangle_count(m, m.vertex_count + 10) == m.triangle_count);
    for (uint32_t target : {1u, 4u, 100u, 1000u, 7541u, 37704u, 75000u, m.triangle_count}) {
        const uint32_t n = tom::vertex_count_for_triangles(m, target);
        INFO("target " << target << " -> n " << n);
        CHECK(tom::active_triangle_count(m, n) >= std::min(target, m.triangle_count));
        if (n > m.min_vertex_count) CHECK(tom::active_triangle_count(m, n - 1) < target);
    }
    for (double f : {0.5, 0.25, 0.1, 0.01, 0.005}) {
        const uint32_t n = tom::vertex_count_for_fraction(m, f);
        const double got = double(tom::active_triangle_count(m, n)) / m.triangle_count;
        INFO("fraction " << f << " gives " << got);
        CHECK(got >= f - 0.5 / m.triangle_count);
        CHECK(got <= f + 3.0 / m.triangle_count);  // a substitution removes at most a few triangles
    }
    CHECK(tom::vertex_count_for_fraction(m, 1.0) == m.vertex_count);
    CHECK(tom::vertex_count_for_fraction(m, 0.0) == m.min_vertex_count);
}

TEST_CASE("chain statistics: empty at full resolution, short and growing as resolution falls", "[extract][chains]") {
    const Built b = bunny();
    const tom::MeshView m = b.tom.view();
    const tom::ChainStats full = tom::chain_stats(m, m.vertex_count);
    CHECK(full.steps == 0);
    CHECK(full.max_steps == 0);
    CHECK(full.corners == uint64_t(m.triangle_count) * 3);
    double previous = 0;
    for (double f : {0.5, 0.25, 0.1, 0.01}) {
        const uint32_t n = tom::vertex_count_for_fraction(m, f);
        const tom::ChainStats s = tom::chain_stats(m, n);
        uint64_t hist_total = 0, hist_steps = 0;
        for (int k = 0; k < tom::ChainStats::histogram_bins; ++k) hist_total += s.histogram[k], hist_steps += uint64_t(k) * s.histogram[k];
        CHECK(hist_total == s.corners);
        if (s.max_steps < uint32_t(tom::ChainStats::histogram_bins)) CHECK(hist_steps == s.steps);
        const double mean = double(s.steps) / double(s.corners);
        INFO("fraction " << f << " mean steps " << mean << " max " << s.max_steps);
        CHECK(mean >= previous);
        CHECK(mean < 8.0);  // the paper: chains stay short
        previous = mean;
    }
}

TEST_CASE("geomorph: a = 0 is the surface of resolution n, a = 1 that of n + 1", "[extract][geomorph]") {
    const Built b = bunny();
    const tom::MeshView m = b.tom.view();
    std::vector<uint32_t> next(size_t(m.triangle_count) * 3);
    for (uint32_t n : {m.min_vertex_count, m.vertex_count / 100, m.vertex_count / 7, m.vertex_count / 2, m.vertex_count - 1}) {
        INFO("n " << n);
        const tom::MorphedVertex v0 = tom::geomorph(m, n, 0.0f), v1 = tom::geomorph(m, n, 1.0f), vh = tom::geomorph(m, n, 0.5f);
        REQUIRE(v0.index == n);
        const uint32_t s = b.tom.substitute[n];
        for (int k = 0; k < 3; ++k) {
            CHECK(v0.position[k] == b.tom.positions[3 * s + k]);
            CHECK(v1.position[k] == b.tom.positions[3 * n + k]);
            CHECK(vh.position[k] == Approx(0.5f * (b.tom.positions[3 * s + k] + b.tom.positions[3 * n + k])));
        }
        CHECK(std::abs(v1.normal[0] * v1.normal[0] + v1.normal[1] * v1.normal[1] + v1.normal[2] * v1.normal[2] - 1.0f) < 1e-5f);
        // level n + 1 with vertex n moved onto its substitute draws exactly level n: every
        // triangle either collapses (two corners at one point) or equals one of level n's
        const tom::Extracted e = tom::extract(m, n + 1, next.data(), next.size());
        const std::vector<uint32_t> level_n = test::brute_force_active(m, n);
        std::multiset<std::array<uint32_t, 3>> expect, got;
        auto rotated = [](uint32_t a, uint32_t c, uint32_t d) {
            if (a <= c && a <= d) return std::array<uint32_t, 3>{a, c, d};
            if (c <= a && c <= d) return std::array<uint32_t, 3>{c, d, a};
            return std::array<uint32_t, 3>{d, a, c};
        };
        for (size_t i = 0; i < level_n.size(); i += 3) expect.insert(rotated(level_n[i], level_n[i + 1], level_n[i + 2]));
        for (size_t i = 0; i < size_t(e.triangle_count) * 3; i += 3) {
            uint32_t c[3];
            for (int k = 0; k < 3; ++k) c[k] = next[i + k] == n ? s : next[i + k];  // vertex n at a = 0 is its substitute
            if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
            got.insert(rotated(c[0], c[1], c[2]));
        }
        CHECK(got == expect);
    }
}
