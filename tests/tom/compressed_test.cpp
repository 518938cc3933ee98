// Compressed glTF in: what gltfpack writes (KHR_mesh_quantization, EXT_meshopt_compression with
// its filters) decodes to the same scene as the uncompressed asset. gltfpack 0.18 (the version of
// Debian's meshoptimizer decoders) comes from the npm registry through scripts/install-deps.sh.

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include <catch2/catch.hpp>

#include "support.h"
#include "tom/errors.h"
#include "tom/io/import.h"
#include "tom/scene.h"

namespace {

namespace fs = std::filesystem;

// Runs gltfpack on a sample; returns the output path.
fs::path gltfpack(const std::string& sample, const std::string& out_name, const std::string& options) {
    const fs::path cli = fs::path(TOM_DATA_DIR).parent_path() / ".tools/node_modules/gltfpack/cli.js";
    INFO("gltfpack is installed by scripts/install-deps.sh into .tools/");
    REQUIRE(fs::exists(cli));
    // a folder per output: ctest runs the test cases of this file in parallel
    const fs::path dir = fs::temp_directory_path() / ("tom_compressed_" + fs::path(out_name).stem().string() + "_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const fs::path out = dir / out_name;
    const std::string cmd = "node '" + cli.string() + "' -i '" + test::sample(sample) + "' -o '" + out.string() + "' " + options + " > /dev/null 2>&1";
    REQUIRE(std::system(cmd.c_str()) == 0);
    return out;
}

// Surface area and bounds of the whole scene in world space (every instance transformed).
struct WorldShape {
    double area = 0;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    size_t instances = 0;
    double diagonal() const { return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2])); }
};

WorldShape world_shape(const tom::ImportResult& r) {
    WorldShape s;
    const std::vector<tom::Instance> list = tom::draw_list(r.scene, uint32_t(r.meshes.size()));
    s.instances = list.size();
    for (const tom::Instance& inst : list) {
        const tom::Mesh& m = r.meshes[inst.mesh];
        const float* t = inst.transform;
        std::vector<std::array<double, 3>> w(m.vertex_count());
        for (uint32_t v = 0; v < m.vertex_count(); ++v) {
            const float* p = &m.positions[3 * size_t(v)];
            for (int k = 0; k < 3; ++k) {
                w[v][size_t(k)] = double(t[k]) * p[0] + double(t[4 + k]) * p[1] + double(t[8 + k]) * p[2] + t[12 + k];
                s.lo[k] = std::min(s.lo[k], w[v][size_t(k)]), s.hi[k] = std::max(s.hi[k], w[v][size_t(k)]);
            }
        }
        for (size_t i = 0; i < m.indices.size(); i += 3) {
            const auto &a = w[m.indices[i]], &b = w[m.indices[i + 1]], &c = w[m.indices[i + 2]];
            const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            const double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2], z = e1[0] * e2[1] - e1[1] * e2[0];
            s.area += 0.5 * std::sqrt(x * x + y * y + z * z);
        }
    }
    return s;
}

void check_same_shape(const tom::ImportResult& original, const tom::ImportResult& packed) {
    const WorldShape a = world_shape(original), b = world_shape(packed);
    INFO("area " << a.area << " vs " << b.area << ", diagonal " << a.diagonal() << " vs " << b.diagonal());
    CHECK(std::fabs(a.area - b.area) < 0.01 * a.area);
    for (int k = 0; k < 3; ++k) {
        CHECK(std::fabs(a.lo[k] - b.lo[k]) < 1e-3 * a.diagonal());
        CHECK(std::fabs(a.hi[k] - b.hi[k]) < 1e-3 * a.diagonal());
    }
}

} // namespace

TEST_CASE("glTF: KHR_mesh_quantization and EXT_meshopt_compression (gltfpack) decode to the same scene", "[import][gltf][compressed]") {
    const std::string engine = "assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
    const tom::ImportResult original = tom::import_file(test::sample(engine));
    struct Variant {
        const char* name;
        const char* options;
        const char* extension;
    };
    // -noq: plain floats; default: quantized integer attributes; -c: meshopt-compressed views;
    // -cc: with the octahedral and exponential filters; .gltf with a separate .bin too
    for (const Variant v : {Variant{"engine-noq.glb", "-noq", nullptr}, Variant{"engine-q.glb", "", "KHR_mesh_quantization"},
                            Variant{"engine-c.glb", "-c", "EXT_meshopt_compression"}, Variant{"engine-cc.gltf", "-cc", "EXT_meshopt_compression"},
                            Variant{"engine-cf.glb", "-cf", "EXT_meshopt_compression"}}) {
        INFO(v.name);
        const fs::path packed_path = gltfpack(engine, v.name, v.options);
        if (v.extension) {
            std::ifstream in(packed_path, std::ios::binary);
            const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
            REQUIRE(bytes.find(v.extension) != std::string::npos);  // the variant really uses it
        }
        tom::ImportResult packed;
        try {
            packed = tom::import_file(packed_path.string());
        } catch (const tom::Error& e) {
            FAIL(e.what());
        }
        CHECK(packed.scene.instances.size() > 0);
        for (tom::Mesh& m : packed.meshes) {
            tom::clean_mesh(m);
            for (size_t i = 0; i < m.normals.size(); i += 3)
                REQUIRE(std::fabs(m.normals[i] * m.normals[i] + m.normals[i + 1] * m.normals[i + 1] + m.normals[i + 2] * m.normals[i + 2] - 1) < 1e-4);
        }
        check_same_shape(original, packed);
        fs::remove_all(packed_path.parent_path());
    }
}

TEST_CASE("glTF: quantized texture coordinates decode to the original ones", "[import][gltf][compressed]") {
    const tom::ImportResult original = tom::import_file(test::sample("assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf"));
    const fs::path packed_path = gltfpack("assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf", "box-c.glb", "-c");
    const tom::ImportResult packed = tom::import_file(packed_path.string());
    REQUIRE(original.meshes.size() == 1);
    REQUIRE(packed.meshes.size() == 1);
    check_same_shape(original, packed);
    REQUIRE(packed.meshes[0].texcoords.size() == original.meshes[0].texcoords.size());
    // gltfpack reorders vertices: every original uv has a decoded one within the 12-bit step
    const std::vector<float>& a = original.meshes[0].texcoords;
    const std::vector<float>& b = packed.meshes[0].texcoords;
    for (size_t i = 0; i < a.size(); i += 2) {
        double best = INFINITY;
        for (size_t j = 0; j < b.size(); j += 2) best = std::min(best, std::hypot(double(a[i] - b[j]), double(a[i + 1] - b[j + 1])));
        CHECK(best < 1e-3);
    }
    REQUIRE(packed.scene.materials.size() == 1);
    CHECK(packed.scene.materials[0].textures.size() == 1);
    fs::remove_all(fs::path(packed_path).parent_path());
}

TEST_CASE("glTF: a meshopt stream that does not decode is an error naming the buffer view", "[import][gltf][compressed]") {
    const fs::path packed = gltfpack("assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb", "engine-broken.glb", "-c");
    std::vector<char> bytes;
    {
        std::ifstream in(packed, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    uint32_t json_len;
    std::memcpy(&json_len, &bytes[12], 4);
    const size_t bin = 20 + json_len + 8;
    for (size_t i = bin; i < bytes.size(); ++i) bytes[i] = char(0xFF);  // every compressed byte
    const fs::path broken = packed.parent_path() / "engine-garbage.glb";
    std::ofstream(broken, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    try {
        tom::import_file(broken.string());
        FAIL("no error");
    } catch (const tom::MeshError& e) {
        const std::string what = e.what();
        INFO(what);
        CHECK(what.find(broken.string()) == 0);
        CHECK(what.find("buffer view") != std::string::npos);
        CHECK(what.find("EXT_meshopt_compression") != std::string::npos);
    }
    fs::remove_all(packed.parent_path());
}
