// Meshes of several parts (glTF primitives, OBJ usemtl groups): one vertex order, each part's
// triangles a prefix of its range at every resolution, and the parts' common border closed at
// every sampled resolution, through the builder, the .tom file, glTF and OBJ + MTL.

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "support.h"
#include "tom/builder/builder.h"
#include "tom/builder/generate.h"
#include "tom/builder/writer.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/io/export.h"
#include "tom/io/import.h"
#include "tom/metrics/report.h"

namespace fs = std::filesystem;

namespace {

// The triangles of `m` for which `side` holds, as a mesh of their own (own vertex copies).
tom::Mesh piece(const tom::Mesh& m, bool (*side)(const float centroid[3]), int32_t material) {
    tom::Mesh out;
    out.material = material;
    std::map<uint32_t, uint32_t> local;
    for (uint32_t t = 0; t < m.triangle_count(); ++t) {
        float c[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 3; ++j) c[j] += m.positions[3 * size_t(m.indices[3 * t + k]) + size_t(j)] / 3.0f;
        if (!side(c)) continue;
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = m.indices[3 * t + k];
            auto [it, fresh] = local.emplace(v, out.vertex_count());
            if (fresh) {
                out.positions.insert(out.positions.end(), &m.positions[3 * size_t(v)], &m.positions[3 * size_t(v)] + 3);
                if (!m.texcoords.empty()) out.texcoords.insert(out.texcoords.end(), &m.texcoords[2 * size_t(v)], &m.texcoords[2 * size_t(v)] + 2);
            }
            out.indices.push_back(it->second);
        }
    }
    return out;
}

// Two primitives meeting along a ring, as a glTF mesh holds them: each has its own copies of the
// border's positions.
tom::Mesh two_material_sphere() {
    const tom::Mesh sphere = tom::make_sphere(24, 32, 1.0f, 0.05f);
    tom::Mesh joined = tom::join_parts({piece(sphere, [](const float c[3]) { return c[2] >= 0; }, 0),
                                        piece(sphere, [](const float c[3]) { return c[2] < 0; }, 1)},
                                       "two-material sphere");
    tom::clean_mesh(joined);
    return joined;
}

tom::Mesh two_material_grid() {
    const tom::Mesh grid = tom::make_grid(40, 40, 0.1f);
    tom::Mesh joined = tom::join_parts({piece(grid, [](const float c[3]) { return c[0] < 0.5f; }, 0),
                                        piece(grid, [](const float c[3]) { return c[0] >= 0.5f; }, 1)},
                                       "two-material grid");
    tom::clean_mesh(joined);
    return joined;
}

// Open edges of triangles welded by exact position (of snapped copies), as position pairs.
std::set<std::pair<std::array<float, 3>, std::array<float, 3>>> open_edges(const float* positions, const uint32_t* indices, size_t triangles) {
    std::map<std::pair<std::array<float, 3>, std::array<float, 3>>, int> count;
    auto at = [&](uint32_t v) { return std::array<float, 3>{positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]}; };
    for (size_t t = 0; t < triangles; ++t)
        for (int k = 0; k < 3; ++k) {
            std::array<float, 3> a = at(indices[3 * t + k]), b = at(indices[3 * t + (k + 1) % 3]);
            if (b < a) std::swap(a, b);
            ++count[{a, b}];
        }
    std::set<std::pair<std::array<float, 3>, std::array<float, 3>>> out;
    for (const auto& [edge, c] : count)
        if (c == 1) out.insert(edge);
    return out;
}

struct LevelReport {
    int levels = 0;
    size_t input_open = 0, worst_open = 0;
};

// At every sampled resolution: extract_parts agrees with extract and with each part's count, each
// draw carries its part's material, and the level welded by position has no more open edges
// than the welded input (none for a closed input).
LevelReport check_parts(const tom::Mesh& input, const tom::TomMesh& built) {
    test::check_invariants({input.name, input, false, 0}, built);
    const tom::MeshView v = built.view();
    REQUIRE(tom::part_count(v) == std::max<size_t>(1, input.parts.size()));
    LevelReport report;
    // welded by position within the builder's copy tolerance (the same points in both orders)
    const std::vector<float> input_points = test::snap_copies(input.positions.data(), input.vertex_count());
    const std::vector<float> level_points = test::snap_copies(v.positions, v.vertex_count);
    const auto input_edges = open_edges(input_points.data(), input.indices.data(), input.triangle_count());
    report.input_open = input_edges.size();
    std::set<std::array<float, 3>> boundary;  // the welded input's open boundary: where a level may have open edges
    for (const auto& [a, b] : input_edges) boundary.insert(a), boundary.insert(b);
    std::vector<uint32_t> whole(size_t(v.triangle_count) * 3), by_part(whole.size());
    std::vector<tom::PartDraw> draws(tom::part_count(v));
    for (double f : {1.0, 0.5, 0.25, 0.1, 0.05, 0.02, 0.01, 0.0}) {
        const uint32_t n = tom::vertex_count_for_fraction(v, f);
        INFO("fraction " << f << ", resolution " << n);
        const tom::Extracted a = tom::extract(v, n, whole.data(), whole.size());
        const tom::Extracted b = tom::extract_parts(v, n, by_part.data(), by_part.size(), draws.data());
        REQUIRE(a.triangle_count == b.triangle_count);
        REQUIRE(a.triangle_count == tom::active_triangle_count(v, n));
        REQUIRE(std::equal(whole.begin(), whole.begin() + 3 * ptrdiff_t(a.triangle_count), by_part.begin()));
        uint32_t next = 0;
        for (uint32_t p = 0; p < draws.size(); ++p) {
            CHECK(draws[p].first_index == next);
            CHECK(draws[p].index_count == 3 * tom::active_part_triangle_count(v, p, n));
            CHECK(draws[p].material == tom::part_at(v, p).material);
            next += draws[p].index_count;
        }
        const auto level_edges = open_edges(level_points.data(), whole.data(), a.triangle_count);
        const size_t open = level_edges.size();
        CHECK(open <= report.input_open);
        // no crack: every open edge of the level runs between points of the input's own boundary
        // (a border between parts that came apart would have open edges inside the welded surface)
        size_t inside = 0;
        for (const auto& [p, q] : level_edges) inside += !boundary.count(p) || !boundary.count(q);
        CHECK(inside == 0);
        report.worst_open = std::max(report.worst_open, open);
        ++report.levels;
    }
    return report;
}

tom::Scene two_materials() {
    tom::Scene scene;
    tom::Material red, blue;
    red.name = "red";
    red.base_color[1] = red.base_color[2] = 0.1f;
    blue.name = "blue";
    blue.base_color[0] = blue.base_color[1] = 0.2f;
    blue.textures.push_back({tom::TextureRole::base_color, 0, "textures/blue.png", ""});
    scene.materials = {red, blue};
    return scene;
}

// the JSON chunk of a .glb
nlohmann::json glb_json(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    REQUIRE(b.size() > 20);
    uint32_t length;
    std::memcpy(&length, &b[12], 4);
    return nlohmann::json::parse(b.begin() + 20, b.begin() + 20 + length);
}

} // namespace

TEST_CASE("parts: a two-material sphere and grid keep their common border closed at every level", "[parts]") {
    for (const tom::Mesh& mesh : {two_material_sphere(), two_material_grid()}) {
        INFO(mesh.name);
        REQUIRE(mesh.parts.size() == 2);
        const tom::TomMesh built = tom::build(mesh);
        const LevelReport r = check_parts(mesh, built);
        if (mesh.name == "two-material sphere") CHECK(r.worst_open == 0);  // closed: no level has a crack
        // the border really is tied: a level at 5% has triangles in both parts
        const tom::MeshView v = built.view();
        const uint32_t n = tom::vertex_count_for_fraction(v, 0.05);
        CHECK(tom::active_part_triangle_count(v, 0, n) > 0);
        CHECK(tom::active_part_triangle_count(v, 1, n) > 0);
    }
}

TEST_CASE("parts: built one at a time (the old behaviour) the same sphere cracks along the border", "[parts]") {
    // what the parts fix: each primitive simplified alone moves its own copy of the border
    const tom::Mesh sphere = tom::make_sphere(24, 32, 1.0f, 0.05f);
    tom::Mesh top = piece(sphere, [](const float c[3]) { return c[2] >= 0; }, 0), bottom = piece(sphere, [](const float c[3]) { return c[2] < 0; }, 1);
    tom::clean_mesh(top);
    tom::clean_mesh(bottom);
    const tom::TomMesh a = tom::build(top), b = tom::build(bottom);
    size_t worst = 0;
    for (double f : {0.25, 0.1, 0.05, 0.02, 0.0}) {
        std::vector<float> positions;
        std::vector<uint32_t> indices;
        for (const tom::TomMesh* t : {&a, &b}) {
            const tom::MeshView v = t->view();
            std::vector<uint32_t> level(size_t(v.triangle_count) * 3);
            const tom::Extracted e = tom::extract(v, tom::vertex_count_for_fraction(v, f), level.data(), level.size());
            const uint32_t base = uint32_t(positions.size() / 3);
            positions.insert(positions.end(), v.positions, v.positions + 3 * size_t(e.vertex_count));
            for (uint32_t i = 0; i < 3 * e.triangle_count; ++i) indices.push_back(base + level[i]);
        }
        worst = std::max(worst, open_edges(positions.data(), indices.data(), indices.size() / 3).size());
    }
    CHECK(worst > 0);  // any open edge is a crack (10 of the border's 32 edges at worst, built today)
}

TEST_CASE("parts: through the .tom file, glTF (a primitive per part) and OBJ + MTL (a usemtl group per part)", "[parts][gltf][obj]") {
    const fs::path dir = fs::temp_directory_path() / "tom_parts_test";
    fs::remove_all(dir);
    fs::create_directories(dir / "textures");
    const tom::Mesh mesh = two_material_grid();
    const tom::TomMesh built = tom::build(mesh);
    const tom::Scene scene = two_materials();
    const std::vector<uint8_t> bytes = tom::serialize({built}, scene);
    const tom::File file = tom::File::from_bytes(bytes.data(), bytes.size(), "parts.tom");
    const tom::MeshView& v = file.mesh(0);
    REQUIRE(tom::part_count(v) == 2);
    for (uint32_t p = 0; p < 2; ++p) {
        CHECK(tom::part_at(v, p).material == int32_t(p));
        CHECK(tom::part_at(v, p).triangle_count == built.parts[p].triangle_count);
    }

    SECTION("glTF: every level has a primitive per part with its material, and converts back to two parts") {
        const std::string glb = (dir / "grid.glb").string();
        tom::GlbMesh g;
        g.mesh = &v;
        for (double f : {1.0, 0.25, 0.05}) g.vertex_counts.push_back(tom::vertex_count_for_fraction(v, f));
        tom::export_glb(glb, {g}, file.scene());
        const nlohmann::json doc = glb_json(glb);
        REQUIRE(doc["meshes"].size() == 3);
        for (const auto& m : doc["meshes"]) {
            REQUIRE(m["primitives"].size() == 2);
            CHECK(m["primitives"][0]["material"] == 0);
            CHECK(m["primitives"][1]["material"] == 1);
        }
        tom::ImportResult back = tom::import_file(glb);
        REQUIRE(back.meshes.size() == 3);  // one per level
        tom::Mesh finest = back.meshes[0];
        tom::clean_mesh(finest);
        REQUIRE(finest.parts.size() == 2);
        CHECK(finest.parts[0].material == 0);
        CHECK(finest.parts[1].material == 1);
        CHECK(back.scene.materials.size() == 2);
        check_parts(finest, tom::build(finest));
    }

    SECTION("OBJ: a usemtl group per part and a .mtl with the materials, read back as parts") {
        const std::string obj = (dir / "grid.obj").string();
        tom::ExportPart part;
        part.mesh = &v;
        const uint32_t n = tom::vertex_count_for_fraction(v, 0.25);
        part.indices.resize(size_t(v.triangle_count) * 3);
        part.draws.resize(2);
        const tom::Extracted e = tom::extract_parts(v, n, part.indices.data(), part.indices.size(), part.draws.data());
        part.vertex_count = e.vertex_count;
        part.indices.resize(size_t(e.triangle_count) * 3);
        tom::export_meshes(obj, {part}, file.scene());
        REQUIRE(fs::exists(dir / "grid.mtl"));
        tom::ImportResult back = tom::import_file(obj);
        CHECK(back.warnings.empty());
        REQUIRE(back.meshes.size() == 1);
        REQUIRE(back.meshes[0].parts.size() == 2);
        REQUIRE(back.scene.materials.size() == 2);
        CHECK(back.scene.materials[0].name == "red");
        CHECK(back.scene.materials[0].base_color[1] == Approx(0.1f));
        CHECK(back.scene.materials[1].name == "blue");
        REQUIRE(back.scene.materials[1].textures.size() == 1);
        CHECK(back.scene.materials[1].textures[0].uri == "textures/blue.png");
        CHECK(back.meshes[0].parts[0].triangle_count == part.draws[0].index_count / 3);
        tom::Mesh m = back.meshes[0];
        tom::clean_mesh(m);
        check_parts(m, tom::build(m));
    }

    SECTION("OBJ: a group without a material gets a default entry of the .mtl, not a name it lacks") {
        tom::TomMesh unassigned = built;
        unassigned.parts[0].material = -1;
        const std::vector<uint8_t> b = tom::serialize({unassigned}, scene);
        const tom::File f = tom::File::from_bytes(b.data(), b.size(), "unassigned.tom");
        const tom::MeshView& w = f.mesh(0);
        tom::ExportPart part;
        part.mesh = &w;
        part.indices.resize(size_t(w.triangle_count) * 3);
        part.draws.resize(2);
        const tom::Extracted e = tom::extract_parts(w, w.vertex_count, part.indices.data(), part.indices.size(), part.draws.data());
        part.vertex_count = e.vertex_count;
        part.indices.resize(size_t(e.triangle_count) * 3);
        const std::string obj = (dir / "unassigned.obj").string();
        tom::export_meshes(obj, {part}, f.scene());
        std::ifstream obj_in(obj), mtl_in(dir / "unassigned.mtl");
        const std::string obj_text((std::istreambuf_iterator<char>(obj_in)), std::istreambuf_iterator<char>());
        const std::string mtl_text((std::istreambuf_iterator<char>(mtl_in)), std::istreambuf_iterator<char>());
        CHECK(obj_text.find("usemtl default\n") != std::string::npos);
        CHECK(obj_text.find("(null)") == std::string::npos);
        CHECK(mtl_text.find("newmtl default\n") != std::string::npos);
        tom::ImportResult back = tom::import_file(obj);
        CHECK(back.warnings.empty());  // every usemtl is defined
        REQUIRE(back.meshes.size() == 1);
        CHECK(back.meshes[0].parts.size() == 2);
        REQUIRE(back.scene.materials.size() == 2);
        CHECK((back.scene.materials[0].name == "default" || back.scene.materials[1].name == "default"));
    }

    SECTION("OBJ: a missing .mtl is a warning naming it, and the groups are still parts") {
        const std::string obj = (dir / "lonely.obj").string();
        std::ofstream(obj) << "mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 3 4\n";
        tom::ImportResult r = tom::import_file(obj);
        REQUIRE(r.meshes.size() == 1);
        CHECK(r.meshes[0].parts.size() == 2);
        REQUIRE(r.scene.materials.size() == 2);
        CHECK(r.scene.materials[1].name == "b");
        bool named = false;
        for (const std::string& w : r.warnings) named |= w.find("nowhere.mtl") != std::string::npos;
        CHECK(named);
    }
}

TEST_CASE("parts: 2CylinderEngine's multi-primitive meshes keep their borders closed", "[parts][gltf][samples]") {
    tom::ImportResult r = tom::import_file(test::sample("assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"));
    int multi = 0;
    for (tom::Mesh m : r.meshes) {
        if (m.parts.empty()) continue;
        tom::clean_mesh(m);
        if (m.parts.empty()) continue;
        ++multi;
        INFO(m.name);
        check_parts(m, tom::build(m));
    }
    CHECK(multi == 4);
}

TEST_CASE("lock borders: the open border of a grid never moves, the interior still simplifies", "[parts][borders]") {
    tom::Mesh grid = tom::make_grid(30, 30, 0.1f);
    tom::clean_mesh(grid);
    tom::BuildParams params;
    params.lock_borders = true;
    const tom::TomMesh built = tom::build(grid, params);
    test::check_invariants({"locked grid", grid, false, 0}, built);
    const tom::MeshView v = built.view();
    const auto border = open_edges(grid.positions.data(), grid.indices.data(), grid.triangle_count());
    // every border vertex survives to the coarsest level
    std::set<std::array<float, 3>> border_points;
    for (const auto& [a, b] : border) border_points.insert(a), border_points.insert(b);
    for (uint32_t i = v.min_vertex_count; i < v.vertex_count; ++i)
        CHECK(border_points.count({v.positions[3 * i], v.positions[3 * i + 1], v.positions[3 * i + 2]}) == 0);
    std::vector<uint32_t> level(size_t(v.triangle_count) * 3);
    const tom::Extracted e = tom::extract(v, v.min_vertex_count, level.data(), level.size());
    CHECK(e.triangle_count < grid.triangle_count() / 4);
    CHECK(open_edges(v.positions, level.data(), e.triangle_count) == border);  // the same outline, edge for edge
    // without the lock the outline coarsens
    const tom::TomMesh free = tom::build(grid);
    const tom::MeshView f = free.view();
    const tom::Extracted fe = tom::extract(f, f.min_vertex_count, level.data(), level.size());
    CHECK(open_edges(f.positions, level.data(), fe.triangle_count).size() < border.size() / 2);
}

TEST_CASE("mirrored texture coordinates: copies with opposite tangent handedness keep their seam", "[parts][seams]") {
    // a grid mirrored at x = 0.5: u = |x - 0.5|, the same on both sides of the mirror line, and
    // the tangent's handedness flips there; the line's vertices are two copies each
    tom::Mesh left = tom::make_grid(20, 20, 0.05f);
    tom::Mesh mesh = tom::join_parts({piece(left, [](const float c[3]) { return c[0] < 0.5f; }, -1),
                                      piece(left, [](const float c[3]) { return c[0] >= 0.5f; }, -1)},
                                     "mirrored");
    const uint32_t first_right = uint32_t(piece(left, [](const float c[3]) { return c[0] < 0.5f; }, -1).vertex_count());
    mesh.parts.clear();  // one part: the seam is inside it
    for (uint32_t i = 0; i < mesh.vertex_count(); ++i) {
        const float x = mesh.positions[3 * size_t(i)], y = mesh.positions[3 * size_t(i) + 1];
        mesh.texcoords.insert(mesh.texcoords.end(), {std::fabs(x - 0.5f), y});
        mesh.tangents.insert(mesh.tangents.end(), {x < 0.5f || (x == 0.5f && i < first_right) ? -1.0f : 1.0f, 0.0f, 0.0f,
                                                   i < first_right ? -1.0f : 1.0f});
    }
    tom::clean_mesh(mesh);
    const tom::TomMesh built = tom::build(mesh);
    test::check_invariants({"mirrored", mesh, false, 0}, built);
    const tom::MeshView v = built.view();
    std::vector<uint32_t> level(size_t(v.triangle_count) * 3);
    for (double f : {0.5, 0.2, 0.05, 0.0}) {
        INFO("fraction " << f);
        const tom::Extracted e = tom::extract(v, tom::vertex_count_for_fraction(v, f), level.data(), level.size());
        REQUIRE(e.triangle_count > 0);
        // every triangle's corners share one handedness: no corner crossed the mirror's seam
        for (uint32_t t = 0; t < e.triangle_count; ++t) {
            const float w = v.tangents[4 * size_t(level[3 * t]) + 3];
            CHECK(v.tangents[4 * size_t(level[3 * t + 1]) + 3] == w);
            CHECK(v.tangents[4 * size_t(level[3 * t + 2]) + 3] == w);
        }
    }
}

TEST_CASE("parts: the OBJ samples with usemtl convert with their groups as parts and their .mtl materials", "[parts][obj][samples]") {
    const fs::path root = test::sample("assimp/OBJ");
    int with_parts = 0;
    for (const char* name : {"spider.obj", "cube_usemtl.obj", "regr01.obj", "box.obj"}) {
        INFO(name);
        tom::ImportResult r = tom::import_file((root / name).string());
        REQUIRE(r.meshes.size() == 1);
        tom::Mesh m = r.meshes[0];
        tom::clean_mesh(m);
        CHECK(!r.scene.materials.empty());
        for (const tom::Part& p : m.parts) CHECK((p.material >= 0 && size_t(p.material) < r.scene.materials.size()));
        if (m.parts.empty()) continue;
        ++with_parts;
        check_parts(m, tom::build(m));
    }
    CHECK(with_parts == 3);  // box.obj has one material: one part
    // spider: four materials, each with its texture, relative to the OBJ
    tom::ImportResult spider = tom::import_file((root / "spider.obj").string());
    REQUIRE(spider.scene.materials.size() == 4);
    CHECK(spider.meshes[0].parts.size() == 4);
    REQUIRE(spider.scene.materials[0].textures.size() == 1);
    CHECK(spider.scene.materials[0].textures[0].uri == "SpiderTex.jpg");
    CHECK(fs::exists(root / spider.scene.materials[0].textures[0].uri));
}

TEST_CASE("parts: the report gives each part's attributes per level, the whole mesh's error once", "[parts][report]") {
    tom::Mesh mesh = two_material_grid();
    // texture coordinates from the position: both parts carry them
    for (uint32_t v = 0; v < mesh.vertex_count(); ++v) mesh.texcoords.insert(mesh.texcoords.end(), {mesh.positions[3 * v], mesh.positions[3 * v + 1]});
    for (tom::Part& p : mesh.parts) p.attributes |= 2u;
    const tom::TomMesh built = tom::build(mesh);
    tom::ReportParams params;
    params.levels = {0.5, 0.1};
    params.error_curve = false;
    const tom::MeshReport r = tom::make_report(mesh, built, params);
    for (const tom::LevelReport& l : r.levels) {
        INFO("level " << l.fraction);
        REQUIRE(l.parts.size() == 2);
        CHECK(l.parts[0].triangles + l.parts[1].triangles == l.triangles);
        for (uint32_t p = 0; p < 2; ++p) {
            CHECK(l.parts[p].material == int32_t(p));
            CHECK(l.parts[p].attributes.samples > 0);
            CHECK(l.parts[p].attributes.texcoords);
            // a part's displacement is of the order of the whole mesh's (the same surface, split)
            CHECK(l.parts[p].attributes.uv_mean <= 4 * l.attributes.uv_mean + 1e-6);
        }
    }
}

TEST_CASE("parts with different attribute sets: the mesh holds the union, each part says which are its own", "[parts][gltf]") {
    // the top half textured, the bottom not: as two glTF primitives of one mesh would be
    tom::Mesh sphere = tom::make_sphere(24, 32, 1.0f, 0.05f);
    for (uint32_t v = 0; v < sphere.vertex_count(); ++v)
        sphere.texcoords.insert(sphere.texcoords.end(), {sphere.positions[3 * v], sphere.positions[3 * v + 1]});
    tom::Mesh top = piece(sphere, [](const float c[3]) { return c[2] >= 0; }, 0);
    tom::Mesh bottom = piece(sphere, [](const float c[3]) { return c[2] < 0; }, 1);
    bottom.texcoords.clear();
    tom::Mesh mesh = tom::join_parts({top, bottom}, "half textured");
    tom::clean_mesh(mesh);
    REQUIRE(mesh.texcoords.size() == 2 * size_t(mesh.vertex_count()));
    REQUIRE(mesh.parts.size() == 2);
    CHECK((mesh.parts[0].attributes & 2u) != 0);
    CHECK((mesh.parts[1].attributes & 2u) == 0);
    // the bottom's vertices hold the neutral (0, 0)
    for (uint32_t v = top.vertex_count(); v < mesh.vertex_count(); ++v) CHECK((mesh.texcoords[2 * v] == 0 && mesh.texcoords[2 * v + 1] == 0));
    const tom::TomMesh built = tom::build(mesh);
    const LevelReport r = check_parts(mesh, built);
    CHECK(r.worst_open == 0);
    // glTF: the textured part's primitive has TEXCOORD_0, the other's not
    const fs::path dir = fs::temp_directory_path() / "tom_parts_test";
    fs::create_directories(dir);
    const std::string glb = (dir / "half.glb").string();
    const tom::MeshView v = built.view();
    tom::GlbMesh g;
    g.mesh = &v;
    g.vertex_counts = {v.vertex_count, tom::vertex_count_for_fraction(v, 0.1)};
    CHECK_THROWS_WITH(tom::export_glb(glb, {g}), Catch::Contains("a mesh refers to material 1, but 0 are stored"));
    tom::Scene two;
    two.materials.resize(2);
    tom::export_glb(glb, {g}, two);
    const nlohmann::json doc = glb_json(glb);
    for (const auto& m : doc["meshes"]) {
        REQUIRE(m["primitives"].size() == 2);
        CHECK(m["primitives"][0]["attributes"].contains("TEXCOORD_0"));
        CHECK(!m["primitives"][1]["attributes"].contains("TEXCOORD_0"));
    }
}
