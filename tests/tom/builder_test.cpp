// Builder invariants over generated and real meshes, for every strategy and predicate.

#include <map>

#include <catch2/catch.hpp>

#include "support.h"
#include "tom/builder/builder.h"
#include "tom/io/import.h"
#include "tom/errors.h"
#include "tom/scene.h"
#include "tom/extract.h"
#include "tom/builder/writer.h"
#include "tom/format.h"
#include "tom/builder/generate.h"

namespace {

std::vector<tom::BuildParams> all_params() {
    std::vector<tom::BuildParams> out;
    for (tom::Strategy s : {tom::Strategy::passes, tom::Strategy::heap})
        for (tom::Predicate p : {tom::Predicate::quadric, tom::Predicate::memoryless})
            for (bool keep_topology : {false, true}) {
                tom::BuildParams bp;
                bp.strategy = s;
                bp.predicate = p;
                bp.keep_topology = keep_topology;
                out.push_back(bp);
            }
    return out;
}

} // namespace

TEST_CASE("every invariant holds on generated meshes, all strategies and predicates", "[builder]") {
    for (const test::NamedMesh& nm : test::generated_meshes())
        for (const tom::BuildParams& bp : all_params()) {
            INFO("strategy " << tom::to_string(bp.strategy) << ", predicate " << tom::to_string(bp.predicate) << ", keep_topology "
                              << bp.keep_topology);
            const tom::TomMesh built = tom::build(nm.mesh, bp);
            test::check_invariants(nm, built, bp.keep_topology);
        }
}

TEST_CASE("every invariant holds on the real sample meshes (default parameters)", "[builder][samples]") {
    for (const test::NamedMesh& nm : test::real_meshes()) test::check_invariants(nm, tom::build(nm.mesh));
}

TEST_CASE("every invariant holds on the real sample meshes (heap, memoryless)", "[builder][samples]") {
    tom::BuildParams bp;
    bp.strategy = tom::Strategy::heap;
    bp.predicate = tom::Predicate::memoryless;
    for (const test::NamedMesh& nm : test::real_meshes()) test::check_invariants(nm, tom::build(nm.mesh, bp));
}

TEST_CASE("keeping its topology, a closed genus-0 surface ends as a tetrahedron, a torus keeps its hole", "[builder]") {
    for (const tom::BuildParams& bp : all_params()) {
        if (!bp.keep_topology) continue;
        INFO("strategy " << tom::to_string(bp.strategy) << ", predicate " << tom::to_string(bp.predicate));
        for (const test::NamedMesh& nm : test::generated_meshes()) {
            if (nm.name.rfind("sphere 12", 0) == 0) {
                const tom::TomMesh t = tom::build(nm.mesh, bp);
                CHECK(t.min_vertex_count == 4);
                CHECK(tom::active_triangle_count(t.view(), 4) == 4);
            }
            if (nm.name.rfind("torus", 0) == 0) {
                const tom::TomMesh t = tom::build(nm.mesh, bp);
                // the smallest torus triangulation has 7 vertices and 14 triangles
                CHECK(t.min_vertex_count >= 7);
                CHECK(tom::active_triangle_count(t.view(), t.min_vertex_count) == 2 * t.min_vertex_count);
            }
        }
    }
}

TEST_CASE("borders stay in place: a grid keeps its outline down to 5% of its triangles", "[builder]") {
    test::NamedMesh grid;
    for (test::NamedMesh& nm : test::generated_meshes())
        if (nm.name.rfind("grid 20x20", 0) == 0) grid = std::move(nm);
    REQUIRE(grid.mesh.vertex_count() > 0);
    for (tom::Predicate p : {tom::Predicate::quadric, tom::Predicate::memoryless}) {
        tom::BuildParams bp;
        bp.predicate = p;
        const tom::TomMesh t = tom::build(grid.mesh, bp);
        INFO("predicate " << tom::to_string(p));
        // the vertices used at 5% still span the unit square: the corners are still there
        const uint32_t n = tom::vertex_count_for_fraction(t.view(), 0.05);
        std::vector<uint32_t> idx(t.triangle_count() * 3);
        const tom::Extracted r = tom::extract(t.view(), n, idx.data(), idx.size());
        float lo[2] = {1e9f, 1e9f}, hi[2] = {-1e9f, -1e9f};
        for (size_t i = 0; i < size_t(r.triangle_count) * 3; ++i)
            for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], t.positions[3 * idx[i] + k]), hi[k] = std::max(hi[k], t.positions[3 * idx[i] + k]);
        CHECK(lo[0] == 0.0f);
        CHECK(lo[1] == 0.0f);
        CHECK(hi[0] == 1.0f);
        CHECK(hi[1] == 1.0f);
        // and its outline is the square's: every open edge of the level lies on one side of it,
        // and together they measure its perimeter (a border vertex moved inward would cut a
        // corner off or open an edge inside)
        std::map<std::pair<uint32_t, uint32_t>, int> edges;
        for (size_t f = 0; f < r.triangle_count; ++f)
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = idx[3 * f + k], b = idx[3 * f + (k + 1) % 3];
                ++edges[{std::min(a, b), std::max(a, b)}];
            }
        double outline = 0;
        for (const auto& [edge, uses] : edges) {
            if (uses != 1) continue;
            const float* a = &t.positions[3 * edge.first];
            const float* b = &t.positions[3 * edge.second];
            const bool on_side = (a[0] == b[0] && (a[0] == 0.0f || a[0] == 1.0f)) || (a[1] == b[1] && (a[1] == 0.0f || a[1] == 1.0f));
            CHECK(on_side);
            outline += std::hypot(double(a[0]) - b[0], double(a[1]) - b[1]);
        }
        CHECK(outline == Approx(4.0).epsilon(1e-6));
        // and the coarsest level is far coarser than the input
        CHECK(t.min_vertex_count < grid.mesh.vertex_count() / 20);
    }
}

TEST_CASE("the pair threshold joins separate parts that edges alone cannot", "[builder]") {
    // two grids side by side with a gap of 0.01: with edges only, each keeps at least its own
    // corners; with a threshold above the gap, vertices of one substitute into the other
    tom::Mesh a = tom::make_grid(8, 8, 0.0f), b = tom::make_grid(8, 8, 0.0f);
    const uint32_t base = a.vertex_count();
    for (size_t i = 0; i < b.positions.size(); i += 3) a.positions.insert(a.positions.end(), {b.positions[i] + 1.01f, b.positions[i + 1], b.positions[i + 2]});
    for (uint32_t i : b.indices) a.indices.push_back(i + base);
    tom::clean_mesh(a);
    tom::BuildParams edges_only, pairs;
    pairs.pair_threshold = 0.02f;
    tom::BuildStats se, sp;
    const tom::TomMesh te = tom::build(a, edges_only, &se), tp = tom::build(a, pairs, &sp);
    CHECK(se.pair_candidates == 0);
    CHECK(sp.pair_candidates > 0);
    test::NamedMesh nm{"two grids 0.01 apart", a, false, 0};
    test::check_invariants(nm, tp);
    // some substitution crosses the gap: a vertex of one grid has its substitute in the other
    bool crossed = false;
    for (uint32_t i = tp.min_vertex_count; i < tp.vertex_count(); ++i) {
        const bool left = tp.positions[3 * i] < 1.005f, target_left = tp.positions[3 * tp.substitute[i]] < 1.005f;
        crossed |= left != target_left;
    }
    CHECK(crossed);
}

TEST_CASE("the same input gives byte-identical files", "[builder][determinism]") {
    for (const tom::BuildParams& bp : all_params()) {
        const tom::Mesh m = test::generated_meshes()[1].mesh;
        CHECK(tom::serialize({tom::build(m, bp)}) == tom::serialize({tom::build(m, bp)}));
    }
}

TEST_CASE("texture coordinates no texture samples are carried but not weighed: the order of the mesh without them", "[builder][attributes][samples]") {
    int textured = 0, changed = 0;
    for (const test::NamedMesh& nm : test::real_meshes()) {
        if (nm.mesh.texcoords.empty()) continue;
        INFO(nm.name);
        ++textured;
        tom::BuildParams unweighed;
        unweighed.weigh_texcoords = false;
        const tom::TomMesh a = tom::build(nm.mesh, unweighed), weighed = tom::build(nm.mesh);
        tom::Mesh bare = nm.mesh;
        bare.texcoords.clear();
        const tom::TomMesh b = tom::build(bare);
        CHECK(a.original_index == b.original_index);
        CHECK(a.substitute == b.substitute);
        CHECK(a.triangles == b.triangles);
        CHECK(a.texcoords.size() == nm.mesh.texcoords.size());  // carried, sorted as the vertices
        changed += a.original_index != weighed.original_index;
    }
    CHECK(textured >= 2);
    CHECK(changed >= 1);  // weighed, they change the order (not where every coordinate is 0)
}

TEST_CASE("the thread count does not change the result: real meshes, 1, 2 and 3 threads", "[builder][determinism][samples]") {
    for (const test::NamedMesh& nm : test::real_meshes()) {
        if (nm.mesh.vertex_count() < 2000) continue;  // a pass needs two blocks of 512 vertices to share
        INFO(nm.name);
        for (tom::Predicate p : {tom::Predicate::quadric, tom::Predicate::memoryless}) {
            tom::BuildParams bp;
            bp.predicate = p;
            bp.threads = 1;
            const std::vector<uint8_t> one = tom::serialize({tom::build(nm.mesh, bp)});
            for (unsigned threads : {2u, 3u}) {
                bp.threads = threads;
                CHECK(tom::serialize({tom::build(nm.mesh, bp)}) == one);
            }
        }
    }
}

TEST_CASE("the foresight is only a speed-up: real meshes build the same bytes with it and without it", "[builder][determinism][samples]") {
    int foreseen_meshes = 0;
    for (const test::NamedMesh& nm : test::real_meshes()) {
        if (nm.mesh.vertex_count() < 4096) continue;  // the foresight starts at 2048 live vertices
        INFO(nm.name);
        for (tom::Predicate p : {tom::Predicate::quadric, tom::Predicate::memoryless}) {
            tom::BuildParams bp;
            bp.predicate = p;
            bp.threads = 2;
            tom::BuildStats with, without;
            const std::vector<uint8_t> ahead = tom::serialize({tom::build(nm.mesh, bp, &with)});
            bp.foresight = false;
            const std::vector<uint8_t> plain = tom::serialize({tom::build(nm.mesh, bp, &without)});
            CHECK(with.foreseen_chunks > 0);  // the layer ran
            CHECK(without.foreseen_chunks == 0);
            CHECK(ahead == plain);
            foreseen_meshes += with.foreseen_chunks > 0;
        }
    }
    CHECK(foreseen_meshes >= 4);
}

TEST_CASE("two coincident copies that are each other's border neighbours build a file the reader accepts", "[builder][edge][hostile]") {
    // the fuzzing run's 48-byte OBJ (tests/data/hostile/E-coincident-neighbours.obj): copies 1/2
    // and 0/3 coincide, and each pair closes a zero-length border edge; they were classed as a
    // seam and each substituted onto the other (substitute[2] == 3, FORMAT.md rule 13)
    tom::Mesh m;
    m.positions = {0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0};
    m.indices = {3, 2, 1, 3, 1, 0};
    tom::clean_mesh(m);
    tom::BuildStats stats;
    const tom::TomMesh t = tom::build(m, {}, &stats);
    for (uint32_t i = t.min_vertex_count; i < t.vertex_count(); ++i) CHECK(t.substitute[i] < i);
    CHECK(stats.seam_vertices == 0);
    const std::vector<uint8_t> bytes = tom::serialize({t});
    const tom::File f = tom::File::from_bytes(bytes.data(), bytes.size(), "coincident.tom");
    CHECK(tom::active_triangle_count(f.mesh(0), f.mesh(0).min_vertex_count) <= 2);
}

TEST_CASE("pairs are found at coordinates far past the pair threshold's grid", "[builder][edge][hostile]") {
    // the builder fuzzer's finding: a cell coordinate of 1e30 / 0.1 overflowed its conversion to
    // a 64-bit integer (UBSan). Two grids, one on each side of x = 0, scaled far out or given a
    // tiny threshold, whose facing borders are `gap` apart: those borders still pair up.
    struct Case {
        float scale, gap, threshold;
    };
    for (const Case c : {Case{1e30f, 0.05f, 0.1f}, Case{3e38f, 1e-3f, 1e-2f}, Case{1.0f, 1e-31f, 1e-30f}}) {
        INFO(c.scale << " " << c.threshold);
        tom::Mesh a = tom::make_grid(8, 8, 0.0f);
        const tom::Mesh b = tom::make_grid(8, 8, 0.0f);
        const uint32_t base = a.vertex_count();
        for (size_t i = 0; i < a.positions.size(); i += 3) a.positions[i] = (a.positions[i] - 1.0f) * c.scale;
        for (size_t i = 0; i < b.positions.size(); i += 3) a.positions.insert(a.positions.end(), {b.positions[i] * c.scale + c.gap, b.positions[i + 1], b.positions[i + 2]});
        for (uint32_t i : b.indices) a.indices.push_back(i + base);
        tom::clean_mesh(a);
        tom::BuildParams params;
        params.pair_threshold = c.threshold;
        tom::BuildStats stats;
        const tom::TomMesh t = tom::build(a, params, &stats);
        CHECK(stats.pair_candidates >= 2 * 8);  // each border vertex and its neighbour across, both ways
        const std::vector<uint8_t> bytes = tom::serialize({t});
        CHECK_NOTHROW(tom::File::from_bytes(bytes.data(), bytes.size(), "far.tom"));
    }
}

TEST_CASE("coincident copies joined by an interior edge are locked, not a seam", "[builder][edge][hostile]") {
    // the builder fuzzer's 10^6-run finding (tests/data/hostile/O-coincident-edge-neighbours.off):
    // two triangles share the zero-length edge between two coincident copies; both copies'
    // border neighbours coincide, so they were classed as a seam pair and each substituted onto
    // the other (a cycle: tombuild looped forever measuring the error curve)
    tom::Mesh m = tom::import_file(std::string(TOM_HOSTILE_DIR) + "/O-coincident-edge-neighbours.off").meshes.at(0);
    tom::clean_mesh(m);
    for (const tom::Predicate predicate : {tom::Predicate::quadric, tom::Predicate::memoryless})
        for (const tom::Strategy strategy : {tom::Strategy::passes, tom::Strategy::heap}) {
            INFO(tom::to_string(predicate) << " " << tom::to_string(strategy));
            tom::BuildParams params;
            params.predicate = predicate;
            params.strategy = strategy;
            tom::BuildStats stats;
            const tom::TomMesh t = tom::build(m, params, &stats);
            for (uint32_t i = t.min_vertex_count; i < t.vertex_count(); ++i) CHECK(t.substitute[i] < i);
            CHECK(stats.seam_vertices == 0);
            const std::vector<uint8_t> bytes = tom::serialize({t});
            const tom::File f = tom::File::from_bytes(bytes.data(), bytes.size(), "coincident-edge.tom");
            CHECK(tom::active_triangle_count(f.mesh(0), f.mesh(0).min_vertex_count) <= t.triangle_count());
        }
}

TEST_CASE("the writer never produces a file the reader rejects", "[builder][format][hostile]") {
    tom::Mesh m = test::generated_meshes()[0].mesh;
    tom::TomMesh t = tom::build(m);
    tom::Scene scene;
    scene.materials.resize(1);
    t.material = 4;  // past the scene's one material: FORMAT.md rule 17
    try {
        tom::serialize({t}, scene);
        FAIL("serialized a mesh whose material is not stored");
    } catch (const tom::ArgumentError& e) {
        CHECK(std::string(e.what()).find("rule 17") != std::string::npos);
    }
    t.material = 0;
    t.substitute.back() = t.vertex_count() - 1;  // a removed vertex that substitutes itself: rule 13
    CHECK_THROWS_AS(tom::serialize({t}, scene), tom::ArgumentError);
}

TEST_CASE("a single triangle and a lone quad build and extract", "[builder][edge]") {
    tom::Mesh tri;
    tri.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    tri.indices = {0, 1, 2};
    tom::clean_mesh(tri);
    const tom::TomMesh t = tom::build(tri);
    CHECK(t.min_vertex_count == 3);
    CHECK(tom::active_triangle_count(t.view(), 0) == 1);  // clamped to the coarsest level
    tom::Mesh quad;
    quad.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    quad.indices = {0, 1, 2, 0, 2, 3};
    tom::clean_mesh(quad);
    const tom::TomMesh q = tom::build(quad);
    test::check_invariants({"quad", quad, false, 0}, q);
}

TEST_CASE("a mesh moved into the builder builds the same bytes, and original_mesh gives it back exactly", "[builder][determinism][samples]") {
    int with_parts = 0, with_texcoords = 0;
    for (const test::NamedMesh& nm : test::real_meshes()) {
        INFO(nm.name);
        tom::Mesh input = nm.mesh;
        REQUIRE_NOTHROW(tom::clean_mesh(input));
        with_parts += !input.parts.empty();
        with_texcoords += !input.texcoords.empty();
        for (const tom::BuildParams& bp : {all_params().front(), all_params().back()}) {  // passes with quadrics, the heap with the memoryless predicate
            const tom::TomMesh kept = tom::build(input, bp);
            tom::Mesh moved = input;
            const tom::TomMesh taken = tom::build(std::move(moved), bp);
            CHECK(moved.positions.empty());
            CHECK(moved.indices.empty());
            CHECK(tom::serialize({taken}) == tom::serialize({kept}));
            const tom::Mesh back = tom::original_mesh(taken);
            CHECK(back.name == input.name);
            CHECK(back.material == input.material);
            CHECK(back.positions == input.positions);
            CHECK(back.normals == input.normals);
            CHECK(back.texcoords == input.texcoords);
            CHECK(back.colors == input.colors);
            CHECK(back.texcoords1 == input.texcoords1);
            CHECK(back.tangents == input.tangents);
            CHECK(back.indices == input.indices);
            REQUIRE(back.parts.size() == input.parts.size());
            for (size_t p = 0; p < back.parts.size(); ++p) {
                CHECK(back.parts[p].first_triangle == input.parts[p].first_triangle);
                CHECK(back.parts[p].triangle_count == input.parts[p].triangle_count);
                CHECK(back.parts[p].material == input.parts[p].material);
            }
        }
    }
    CHECK(with_parts >= 1);  // the cases original_mesh must get right beyond positions
    CHECK(with_texcoords >= 1);
}

TEST_CASE("original_mesh refuses a TomMesh without its map to the input", "[builder][edge]") {
    tom::TomMesh built = tom::build(test::generated_meshes()[1].mesh);
    built.original_triangle.clear();  // as a TomMesh made other than by build()
    CHECK_THROWS_WITH(tom::original_mesh(built), Catch::Contains("has no map to its input"));
    built = tom::build(test::generated_meshes()[1].mesh);
    built.original_index[0] = built.vertex_count();
    CHECK_THROWS_WITH(tom::original_mesh(built), Catch::Contains("not a permutation"));
}
