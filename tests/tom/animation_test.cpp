// The builder's animation terms (BuildParams::animation_weight): the levels of a skinned and of
// a morphed asset stay close to the original in its poses and targets, not only at rest. The
// assets are GLB files made here (a capped tube with two bones and a bend; the same tube with
// two morph targets), read by the importer as any user's would be; the distance is Metro's
// (tom::metro_distance) between a level and the original, both posed on the CPU by the same
// joint matrices or morph weights.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <unistd.h>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "glb.h"
#include "tom/builder/builder.h"
#include "tom/builder/writer.h"
#include "tom/format.h"
#include "tom/io/export.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/io/import.h"
#include "tom/metrics/distance.h"

namespace {

namespace fs = std::filesystem;
constexpr double kPi = 3.14159265358979323846;

// A capped tube along +y, 8 long, its radius rippled so that every level has some rest-pose
// error; a pole at each end.
struct Tube {
    static constexpr int rings = 97, segments = 48;
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    std::vector<float> heights, angles;  // per vertex, for the streams

    Tube() {
        for (int i = 0; i < rings; ++i)
            for (int j = 0; j < segments; ++j) {
                const double y = 8.0 * i / (rings - 1), a = 2 * kPi * j / segments;
                const double r = 1 + 0.1 * std::sin(2.2 * y) + 0.06 * std::cos(3 * a + y);
                add(r * std::cos(a), y, r * std::sin(a), a);
            }
        const uint32_t bottom = uint32_t(heights.size());
        add(0, -0.4, 0, 0);
        add(0, 8.4, 0, 0);
        auto at = [](int i, int j) { return uint32_t(i * segments + (j % segments)); };
        for (int i = 0; i + 1 < rings; ++i)
            for (int j = 0; j < segments; ++j) indices.insert(indices.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        for (int j = 0; j < segments; ++j) {
            indices.insert(indices.end(), {bottom, at(0, j), at(0, j + 1)});
            indices.insert(indices.end(), {bottom + 1, at(rings - 1, j + 1), at(rings - 1, j)});
        }
    }
    uint32_t vertex_count() const { return uint32_t(heights.size()); }

private:
    void add(double x, double y, double z, double a) {
        positions.insert(positions.end(), {float(x), float(y), float(z)});
        heights.push_back(float(y));
        angles.push_back(float(a));
    }
};

// The tube as a GLB's one mesh, drawn by node 0; returns the document to add to.
test::Glb tube_glb(const Tube& tube) {
    test::Glb glb;
    glb.doc = {{"asset", {{"version", "2.0"}}}, {"scene", 0}};
    glb.doc["scenes"] = nlohmann::json::array({{{"nodes", {0}}}});
    const size_t position = glb.add(tube.positions, "VEC3", 5126, tube.vertex_count());
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (size_t i = 0; i < tube.positions.size(); ++i) lo[i % 3] = std::min(lo[i % 3], tube.positions[i]), hi[i % 3] = std::max(hi[i % 3], tube.positions[i]);
    glb.doc["accessors"][position]["min"] = {lo[0], lo[1], lo[2]};
    glb.doc["accessors"][position]["max"] = {hi[0], hi[1], hi[2]};
    const size_t indices = glb.add(tube.indices, "SCALAR", 5125, tube.indices.size());
    nlohmann::json primitive = {{"attributes", {{"POSITION", position}}}, {"indices", indices}};
    glb.doc["meshes"] = nlohmann::json::array({{{"name", "tube"}, {"primitives", nlohmann::json::array({primitive})}}});
    glb.doc["nodes"] = nlohmann::json::array({{{"name", "body"}, {"mesh", 0}}});
    return glb;
}

fs::path write(const test::Glb& glb, const char* name) {
    // a folder per process: ctest runs this file's test cases side by side
    const fs::path dir = fs::temp_directory_path() / ("tom_animation_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const fs::path path = dir / name;
    const std::vector<uint8_t> bytes = glb.bytes();
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
    return path;
}

// The skinned tube: joint 0 (the root) at the origin, joint 1 (the elbow) at y = 4, the weights
// blending from one to the other between y = 3.4 and 4.6.
fs::path skinned_tube() {
    const Tube tube;
    test::Glb glb = tube_glb(tube);
    std::vector<uint8_t> joints;
    std::vector<float> weights;
    for (const float y : tube.heights) {
        const double t = std::min(1.0, std::max(0.0, (y - 3.4) / 1.2)), w1 = t * t * (3 - 2 * t);
        joints.insert(joints.end(), {0, 1, 0, 0});
        weights.insert(weights.end(), {float(1 - w1), float(w1), 0.0f, 0.0f});
    }
    auto& attributes = glb.doc["meshes"][0]["primitives"][0]["attributes"];
    attributes["JOINTS_0"] = glb.add(joints, "VEC4", 5121, tube.vertex_count());
    attributes["WEIGHTS_0"] = glb.add(weights, "VEC4", 5126, tube.vertex_count());
    const std::vector<float> inverse_bind = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1,    // the root's: identity
                                             1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -4, 0, 1};  // the elbow's: y - 4
    glb.doc["skins"] = nlohmann::json::array({{{"joints", {1, 2}}, {"inverseBindMatrices", glb.add(inverse_bind, "MAT4", 5126, 2)}}});
    glb.doc["nodes"][0]["skin"] = 0;
    glb.doc["nodes"].push_back({{"name", "root"}, {"children", {2}}});
    glb.doc["nodes"].push_back({{"name", "elbow"}, {"translation", {0, 4, 0}}});
    glb.doc["scenes"][0]["nodes"].push_back(1);
    return write(glb, "skinned.glb");
}

// The morphed tube: target 0 raises a bump on the +x side at y = 2, target 1 presses a dent
// into the -x side at y = 6.
fs::path morphed_tube() {
    const Tube tube;
    test::Glb glb = tube_glb(tube);
    std::array<std::vector<float>, 2> deltas;
    for (uint32_t v = 0; v < tube.vertex_count(); ++v) {
        const double y = tube.heights[v], a = tube.angles[v], pole = v >= Tube::rings * Tube::segments;
        const double bump = pole ? 0 : 0.6 * std::exp(-(std::pow(y - 2, 2) + std::pow(std::remainder(a, 2 * kPi), 2)) / 0.35);
        const double dent = pole ? 0 : -0.4 * std::exp(-(std::pow(y - 6, 2) + std::pow(std::remainder(a - kPi, 2 * kPi), 2)) / 0.35);
        deltas[0].insert(deltas[0].end(), {float(bump * std::cos(a)), 0.0f, float(bump * std::sin(a))});
        deltas[1].insert(deltas[1].end(), {float(dent * std::cos(a)), 0.0f, float(dent * std::sin(a))});
    }
    auto& primitive = glb.doc["meshes"][0]["primitives"][0];
    for (const auto& d : deltas) primitive["targets"].push_back({{"POSITION", glb.add(d, "VEC3", 5126, tube.vertex_count())}});
    glb.doc["meshes"][0]["weights"] = {0, 0};
    return write(glb, "morphed.glb");
}

const tom::VertexStream& stream(const tom::Mesh& mesh, const std::string& name) {
    for (const tom::VertexStream& x : mesh.extra_streams)
        if (x.name == name) return x;
    FAIL("mesh has no stream " << name);
    throw;
}
double value(const tom::VertexStream& x, size_t v, uint32_t k) {
    return tom::component_value(x.component_type, x.normalized, &x.data[v * x.element_bytes() + k * tom::component_bytes(x.component_type)]);
}

// A pose of the skinned tube: the root turned about x by `root`, the elbow bent about z by
// `bend` (radians); vertices skinned by glTF's rule, sum_j w_j M_j p, M_j = world_j * IBM_j.
std::vector<float> skin(const tom::Mesh& mesh, double root, double bend) {
    REQUIRE(mesh.joint_positions.size() == 6);
    const double c1[3] = {mesh.joint_positions[3], mesh.joint_positions[4], mesh.joint_positions[5]};
    auto turn_root = [&](const double p[3], double out[3]) {
        out[0] = p[0], out[1] = std::cos(root) * p[1] - std::sin(root) * p[2], out[2] = std::sin(root) * p[1] + std::cos(root) * p[2];
    };
    auto bend_elbow = [&](const double p[3], double out[3]) {  // about z through c1
        const double x = p[0] - c1[0], y = p[1] - c1[1];
        out[0] = c1[0] + std::cos(bend) * x - std::sin(bend) * y, out[1] = c1[1] + std::sin(bend) * x + std::cos(bend) * y, out[2] = p[2];
    };
    const tom::VertexStream &joints = stream(mesh, "JOINTS_0"), &weights = stream(mesh, "WEIGHTS_0");
    std::vector<float> out(mesh.positions.size());
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
        const double p[3] = {mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
        double moved[2][3], bent[3];
        turn_root(p, moved[0]);
        bend_elbow(p, bent);
        turn_root(bent, moved[1]);
        double q[3] = {0, 0, 0};
        for (uint32_t k = 0; k < 4; ++k) {
            const double w = value(weights, v, k);
            const size_t j = size_t(value(joints, v, k));
            REQUIRE(j < 2);
            for (int a = 0; a < 3; ++a) q[a] += w * moved[j][a];
        }
        for (int a = 0; a < 3; ++a) out[3 * v + size_t(a)] = float(q[a]);
    }
    return out;
}

// The morphed tube at target weights (w0, w1): p + sum_k w_k d_k.
std::vector<float> morph(const tom::Mesh& mesh, double w0, double w1) {
    const tom::VertexStream &d0 = stream(mesh, "TARGET0/POSITION"), &d1 = stream(mesh, "TARGET1/POSITION");
    std::vector<float> out(mesh.positions.size());
    for (size_t v = 0; v < mesh.vertex_count(); ++v)
        for (uint32_t a = 0; a < 3; ++a) out[3 * v + a] = float(mesh.positions[3 * v + a] + w0 * value(d0, v, a) + w1 * value(d1, v, a));
    return out;
}

// The level of `built` at `fraction` of its triangles, in the input's vertex numbering.
std::vector<uint32_t> level(const tom::TomMesh& built, double fraction) {
    const tom::MeshView view = built.view();
    std::vector<uint32_t> indices(3 * size_t(view.triangle_count));
    const tom::Extracted e = tom::extract(view, tom::vertex_count_for_fraction(view, fraction), indices.data(), indices.size());
    indices.resize(3 * size_t(e.triangle_count));
    for (uint32_t& i : indices) i = built.original_index[i];
    return indices;
}

// Two-sided mean distance (the larger direction's) between the original and a level, both with
// vertices at `positions`, relative to the diagonal.
double distance(const std::vector<float>& positions, const std::vector<uint32_t>& original, const std::vector<uint32_t>& level) {
    const uint32_t n = uint32_t(positions.size() / 3);
    const tom::Surface a{positions.data(), n, original.data(), original.size() / 3}, b{positions.data(), n, level.data(), level.size() / 3};
    const tom::Distance d = tom::metro_distance(a, b);
    return d.percent(std::max(d.forward.mean, d.backward.mean));
}

struct AnimatedError {
    double rest = 0, posed = 0;  // posed: the worst pose's
};

// Rest-pose and worst posed error of `mesh`'s level at `fraction`, built with the animation
// terms at `weight`; `poses` gives the posed positions.
template <class Poses>
AnimatedError animated_error(const tom::Mesh& mesh, float weight, double fraction, const Poses& poses) {
    tom::BuildParams params;
    params.animation_weight = weight;
    const tom::TomMesh built = tom::build(mesh, params);
    const std::vector<uint32_t> coarse = level(built, fraction);
    AnimatedError e;
    e.rest = distance(mesh.positions, mesh.indices, coarse);
    for (const std::vector<float>& posed : poses) e.posed = std::max(e.posed, distance(posed, mesh.indices, coarse));
    return e;
}

tom::Mesh imported(const fs::path& path) {
    tom::ImportResult r = tom::import_file(path.string());
    REQUIRE(r.meshes.size() == 1);
    tom::clean_mesh(r.meshes[0]);
    return std::move(r.meshes[0]);
}

// The table a reader of the test's output (and the note) wants, and the two checks:
// posed within 1.5x of rest with the terms, and lower than without them.
template <class Poses>
void check_animated(const char* what, const tom::Mesh& mesh, const Poses& poses) {
    std::printf("%s: level, rest / worst posed mean error (%% of diagonal), with the animation terms and without\n", what);
    for (const double fraction : {0.5, 0.25, 0.1}) {
        const AnimatedError with = animated_error(mesh, 1.0f, fraction, poses), without = animated_error(mesh, 0.0f, fraction, poses);
        std::printf("  %3.0f%%  with %.4f / %.4f (%.2fx)   without %.4f / %.4f (%.2fx)\n", 100 * fraction, with.rest, with.posed,
                    with.posed / with.rest, without.rest, without.posed, without.posed / without.rest);
        INFO(what << " at " << fraction << ": rest " << with.rest << ", posed " << with.posed << "; without the terms posed " << without.posed);
        CHECK(with.posed <= 1.5 * with.rest);
        CHECK(with.posed < without.posed);
    }
}

} // namespace

TEST_CASE("a skinned mesh's levels stay close to it in its poses", "[animation][skin]") {
    const tom::Mesh mesh = imported(skinned_tube());
    // the importer placed the joints from the inverse bind matrices
    REQUIRE(mesh.joint_positions == std::vector<float>({0, 0, 0, 0, 4, 0}));
    std::vector<std::vector<float>> poses;
    for (const auto& [root, bend] : {std::pair{0.0, 45.0}, {0.0, 90.0}, {30.0, -60.0}}) poses.push_back(skin(mesh, root * kPi / 180, bend * kPi / 180));
    check_animated("skinned tube", mesh, poses);
}

TEST_CASE("a morphed mesh's levels stay close to it in every target", "[animation][morph]") {
    const tom::Mesh mesh = imported(morphed_tube());
    std::vector<std::vector<float>> poses;
    for (const auto& [w0, w1] : {std::pair{1.0, 0.0}, {0.0, 1.0}, {1.0, 1.0}, {0.5, 0.5}}) poses.push_back(morph(mesh, w0, w1));
    check_animated("morphed tube", mesh, poses);
}

TEST_CASE("a skin whose joints or weights break glTF's rules is refused with the place named", "[animation][skin]") {
    const tom::Mesh good = imported(skinned_tube());
    SECTION("a joint index past the skin's joints") {
        tom::Mesh mesh = good;
        tom::VertexStream& joints = mesh.extra_streams[0].name == "JOINTS_0" ? mesh.extra_streams[0] : mesh.extra_streams[1];
        joints.data[4 * 7 + 1] = 2;
        CHECK_THROWS_WITH(tom::clean_mesh(mesh), Catch::Contains("JOINTS_0 of vertex 7 is 2, past the skin's 2 joints"));
    }
    SECTION("a negative or non-finite weight") {
        for (const float bad : {-0.25f, std::nanf("")}) {
            tom::Mesh mesh = good;
            tom::VertexStream& weights = mesh.extra_streams[0].name == "WEIGHTS_0" ? mesh.extra_streams[0] : mesh.extra_streams[1];
            std::memcpy(&weights.data[16 * 3], &bad, 4);
            CHECK_THROWS_WITH(tom::clean_mesh(mesh), Catch::Contains("WEIGHTS_0 of vertex 3 is") && Catch::Contains("finite and non-negative"));
        }
    }
    SECTION("a singular inverse bind matrix, named with its file and skin") {
        test::Glb glb(test::file_bytes(skinned_tube()));
        const size_t view = glb.doc["accessors"][glb.doc["skins"][0]["inverseBindMatrices"].get<size_t>()]["bufferView"].get<size_t>();
        const size_t at = glb.doc["bufferViews"][view]["byteOffset"].get<size_t>();
        std::fill(glb.bin.begin() + long(at + 64), glb.bin.begin() + long(at + 64 + 48), uint8_t(0));  // the elbow's 3x3 part
        const fs::path path = write(glb, "singular.glb");
        CHECK_THROWS_WITH(tom::import_file(path.string()), Catch::Contains("singular.glb") && Catch::Contains("skin 0 inverseBindMatrices: matrix 1 is singular"));
    }
}

namespace {

// The elements of accessor `a` of `glb` (tightly packed or strided), as a multiset of byte strings.
std::multiset<std::string> elements(const test::Glb& glb, size_t a) {
    const nlohmann::json& accessor = glb.doc["accessors"][a];
    const nlohmann::json& view = glb.doc["bufferViews"][accessor["bufferView"].get<size_t>()];
    const size_t components = std::map<std::string, size_t>{{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}, {"MAT4", 16}}.at(accessor["type"]);
    const size_t bytes = components * tom::component_bytes(accessor["componentType"].get<uint32_t>());
    const size_t stride = view.value("byteStride", bytes), at = view.value("byteOffset", size_t(0)) + accessor.value("byteOffset", size_t(0));
    std::multiset<std::string> out;
    for (size_t i = 0; i < accessor["count"].get<size_t>(); ++i) out.insert(std::string(reinterpret_cast<const char*>(&glb.bin[at + i * stride]), bytes));
    return out;
}

// The asset at `source` through tombuild's steps and tomextract at 100% and 25%: the output GLB.
fs::path round_trip(const fs::path& source) {
    tom::ImportResult r = tom::import_file(source.string());
    std::vector<tom::TomMesh> built;
    for (tom::Mesh& m : r.meshes) {
        tom::clean_mesh(m);
        built.push_back(tom::build(m));
    }
    const std::vector<uint8_t> bytes = tom::serialize(built, r.scene);
    const tom::File file = tom::File::from_bytes(bytes.data(), bytes.size(), source.string());
    const tom::MeshView& m = file.mesh(0);
    const fs::path out = source.parent_path() / (source.stem().string() + "-levels.glb");
    tom::export_glb(out.string(), {{&m, {m.vertex_count, tom::vertex_count_for_fraction(m, 0.25)}}}, file.scene());
    return out;
}

// Khronos' validator on `path` (installed by scripts/install-deps.sh): its exit code.
int validate(const fs::path& path) {
    const fs::path script = fs::path(TOM_DATA_DIR).parent_path() / "scripts/validate-gltf.mjs";
    REQUIRE(fs::exists(fs::path(TOM_DATA_DIR).parent_path() / ".tools/node_modules/gltf-validator"));
    return std::system(("node '" + script.string() + "' '" + path.string() + "' > /dev/null").c_str());
}

} // namespace

TEST_CASE("the skinned and the morphed tube come back out of tomextract whole, and valid", "[animation][round_trip]") {
    SECTION("skinned: the skin, its joints' nodes and matrices, every level's joints and weights") {
        const fs::path source = skinned_tube();
        const test::Glb in(test::file_bytes(source)), out(test::file_bytes(round_trip(source)));
        CHECK(out.doc["skins"][0]["joints"] == in.doc["skins"][0]["joints"]);
        CHECK(elements(out, out.doc["skins"][0]["inverseBindMatrices"].get<size_t>()) ==
              elements(in, in.doc["skins"][0]["inverseBindMatrices"].get<size_t>()));
        for (size_t k = 0; k < 3; ++k) CHECK(out.doc["nodes"][k]["name"] == in.doc["nodes"][k]["name"]);
        CHECK(out.doc["nodes"][2]["translation"] == in.doc["nodes"][2]["translation"]);
        const nlohmann::json& body = out.doc["nodes"][0];
        CHECK(body["skin"] == 0);
        const size_t lod = body["extensions"]["MSFT_lod"]["ids"][0].get<size_t>();
        CHECK(out.doc["nodes"][lod]["skin"] == 0);
        const nlohmann::json& source_attributes = in.doc["meshes"][0]["primitives"][0]["attributes"];
        for (const char* name : {"JOINTS_0", "WEIGHTS_0"}) {
            INFO(name);
            // the finest level holds the source's elements (in the levels' order); the coarser shares them
            const size_t finest = out.doc["meshes"][0]["primitives"][0]["attributes"][name].get<size_t>();
            CHECK(elements(out, finest) == elements(in, source_attributes[name].get<size_t>()));
            CHECK(out.doc["meshes"][1]["primitives"][0]["attributes"][name] == finest);
        }
        CHECK(validate(round_trip(source)) == 0);
    }
    SECTION("morphed: both targets' deltas on every level, the default weights") {
        const fs::path source = morphed_tube();
        const test::Glb in(test::file_bytes(source)), out(test::file_bytes(round_trip(source)));
        REQUIRE(out.doc["meshes"].size() == 2);
        for (const auto& level : out.doc["meshes"]) {
            CHECK(level["weights"] == in.doc["meshes"][0]["weights"]);
            REQUIRE(level["primitives"][0]["targets"].size() == 2);
            for (size_t k = 0; k < 2; ++k)
                CHECK(elements(out, level["primitives"][0]["targets"][k]["POSITION"].get<size_t>()) ==
                      elements(in, in.doc["meshes"][0]["primitives"][0]["targets"][k]["POSITION"].get<size_t>()));
        }
        CHECK(validate(round_trip(source)) == 0);
    }
}
