// Import of every supported format from the real samples, and clear errors for broken files.

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <iterator>
#include <random>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <catch2/catch.hpp>

#include "support.h"
#include "tom/builder/builder.h"
#include "tom/builder/generate.h"
#include "tom/errors.h"
#include "tom/builder/writer.h"
#include "tom/format.h"
#include "tom/io/import.h"

namespace {

std::string import_error(const std::string& path) {
    try {
        tom::ImportResult r = tom::import_file(path);
        for (tom::Mesh& m : r.meshes) tom::clean_mesh(m);
    } catch (const tom::Error& e) {
        return e.what();
    }
    return "";
}

double area(const tom::Mesh& m) {
    double a = 0;
    for (size_t t = 0; t < m.indices.size(); t += 3) {
        const float* p0 = &m.positions[3 * m.indices[t]];
        const float* p1 = &m.positions[3 * m.indices[t + 1]];
        const float* p2 = &m.positions[3 * m.indices[t + 2]];
        const double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        const double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        a += 0.5 * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    }
    return a;
}

} // namespace

TEST_CASE("OFF, OBJ, PLY (ASCII and binary) and STL (ASCII and binary) read real meshes", "[import]") {
    const tom::ImportResult bunny = tom::import_file(test::sample("meshes/bunny00.off"));
    REQUIRE(bunny.meshes.size() == 1);
    CHECK(bunny.format == "off");
    CHECK(bunny.meshes[0].vertex_count() == 37706);
    CHECK(bunny.meshes[0].triangle_count() == 75408);

    // the same cube in ASCII and binary PLY
    tom::ImportResult a = tom::import_file(test::sample("assimp/PLY/cube.ply"));
    tom::ImportResult b = tom::import_file(test::sample("assimp/PLY/cube_binary.ply"));
    REQUIRE(a.meshes.size() == 1);
    REQUIRE(b.meshes.size() == 1);
    CHECK(a.meshes[0].positions == b.meshes[0].positions);
    CHECK(a.meshes[0].indices == b.meshes[0].indices);
    CHECK(a.meshes[0].triangle_count() == 12);  // six quads, triangulated

    // the same spider in ASCII and binary STL, welded into a shared-vertex mesh
    tom::ImportResult sa = tom::import_file(test::sample("assimp/STL/Spider_ascii.stl"));
    tom::ImportResult sb = tom::import_file(test::sample("assimp/STL/Spider_binary.stl"));
    CHECK(sa.meshes[0].triangle_count() == sb.meshes[0].triangle_count());
    CHECK(sa.meshes[0].vertex_count() < sa.meshes[0].triangle_count() * 3);
    CHECK(sa.meshes[0].texcoords.empty());  // STL has no texture coordinates
    CHECK(sa.meshes[0].colors.empty());
    CHECK(std::fabs(area(sa.meshes[0]) - area(sb.meshes[0])) < 1e-3 * area(sa.meshes[0]));

    // OBJ with texture coordinates and polygons
    tom::ImportResult w = tom::import_file(test::sample("assimp/OBJ/WusonOBJ.obj"));
    REQUIRE(w.meshes.size() == 1);
    CHECK(w.meshes[0].triangle_count() > 3000);
    tom::ImportResult poly = tom::import_file(test::sample("assimp/OBJ/concave_polygon.obj"));
    CHECK(poly.meshes[0].triangle_count() > 0);
    // OBJ with per-vertex colours
    tom::ImportResult col = tom::import_file(test::sample("assimp/OBJ/cube_with_vertexcolors.obj"));
    REQUIRE(col.meshes[0].colors.size() == size_t(col.meshes[0].vertex_count()) * 4);
}

TEST_CASE("normals are computed when absent: unit length, pointing out of a closed mesh", "[import]") {
    tom::Mesh m = tom::import_file(test::sample("meshes/fandisk.off")).meshes[0];
    REQUIRE(m.normals.empty());
    tom::clean_mesh(m);
    REQUIRE(m.normals.size() == m.positions.size());
    double centre[3] = {0, 0, 0};
    for (size_t i = 0; i < m.positions.size(); ++i) centre[i % 3] += m.positions[i] / m.vertex_count();
    size_t outward = 0;
    for (uint32_t v = 0; v < m.vertex_count(); ++v) {
        const float* n = &m.normals[3 * v];
        REQUIRE(std::fabs(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0) < 1e-4);
        double d = 0;
        for (int k = 0; k < 3; ++k) d += n[k] * (m.positions[3 * v + k] - centre[k]);
        outward += d > 0;
    }
    CHECK(outward > m.vertex_count() * 8 / 10);
}

TEST_CASE("glTF: .gltf with .bin, embedded and .glb give the same mesh with its attributes", "[import][gltf]") {
    const char* forms[] = {"assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf", "assimp/glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf",
                           "assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"};
    std::vector<tom::Mesh> meshes;
    for (const char* f : forms) {
        tom::ImportResult r = tom::import_file(test::sample(f));
        INFO(f);
        REQUIRE(r.meshes.size() == 1);
        CHECK(r.meshes[0].vertex_count() == 24);
        CHECK(r.meshes[0].triangle_count() == 12);
        CHECK(r.meshes[0].normals.size() == 24 * 3);
        CHECK(r.meshes[0].texcoords.size() == 24 * 2);
        CHECK(r.meshes[0].material == 0);
        meshes.push_back(r.meshes[0]);
    }
    CHECK(meshes[0].positions == meshes[1].positions);
    CHECK(meshes[0].positions == meshes[2].positions);
    CHECK(meshes[0].texcoords == meshes[2].texcoords);
    CHECK(meshes[0].indices == meshes[2].indices);
}

TEST_CASE("glTF: TEXCOORD_1 and TANGENT are read, built, stored and extracted with their vertices", "[import][gltf][attributes]") {
    struct Case {
        const char* file;
        bool texcoord1, tangent;
    };
    for (const Case c : {Case{"assimp/glTF2/BoxTexcoords-glTF/boxTexcoords.gltf", true, false},
                         Case{"assimp/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf", false, true}}) {
        INFO(c.file);
        tom::ImportResult r = tom::import_file(test::sample(c.file));
        REQUIRE(r.meshes.size() == 1);
        tom::Mesh m = r.meshes[0];
        const uint32_t n = m.vertex_count();
        CHECK(m.texcoords1.size() == (c.texcoord1 ? n * 2 : 0));
        CHECK(m.tangents.size() == (c.tangent ? n * 4 : 0));
        for (size_t v = 0; v < m.tangents.size(); v += 4) CHECK(std::abs(m.tangents[v + 3]) == 1.0f);  // handedness
        const tom::Mesh input = m;
        tom::clean_mesh(m);
        const tom::TomMesh t = tom::build(m);
        const std::vector<uint8_t> bytes = tom::serialize({t});
        const tom::File f = tom::File::from_bytes(bytes.data(), bytes.size());
        const tom::MeshView& v = f.mesh(0);
        REQUIRE((v.texcoords1 != nullptr) == c.texcoord1);
        REQUIRE((v.tangents != nullptr) == c.tangent);
        // each sorted vertex carries the attributes of the input vertex it came from
        for (uint32_t i = 0; i < v.vertex_count; ++i) {
            const uint32_t o = t.original_index[i];
            for (int k = 0; k < 3; ++k) REQUIRE(v.positions[3 * i + k] == input.positions[3 * o + k]);
            if (c.texcoord1)
                for (int k = 0; k < 2; ++k) REQUIRE(v.texcoords1[2 * i + k] == input.texcoords1[2 * o + k]);
            if (c.tangent)
                for (int k = 0; k < 4; ++k) REQUIRE(v.tangents[4 * i + k] == input.tangents[4 * o + k]);
        }
    }
}

namespace {

using CornerSet = std::set<std::pair<std::array<float, 3>, std::array<float, 2>>>;

// The (position, uv) pairs an OBJ file's faces use, read from its text, v flipped into glTF's
// convention (v = 0 at the image's top row); a corner without `vt` has (0, 0).
CornerSet obj_corners(const std::string& path) {
    std::ifstream in(path);
    std::vector<std::array<float, 3>> v;
    std::vector<std::array<float, 2>> vt;
    CornerSet expect;
    for (std::string line; std::getline(in, line);) {
        std::istringstream ls(line);
        std::string tag;
        ls >> tag;
        if (tag == "v") {
            std::array<float, 3> p{};
            ls >> p[0] >> p[1] >> p[2];
            v.push_back(p);
        } else if (tag == "vt") {
            std::array<float, 2> t{};
            ls >> t[0] >> t[1];
            t[1] = float(1.0 - double(t[1]));
            vt.push_back(t);
        } else if (tag == "f") {
            for (std::string corner; ls >> corner;) {
                const size_t slash = corner.find('/');
                const int a = std::stoi(corner);
                const bool textured = slash != std::string::npos && slash + 1 < corner.size() && corner[slash + 1] != '/';
                expect.insert({v[size_t(a - 1)], textured ? vt[size_t(std::stoi(corner.substr(slash + 1)) - 1)] : std::array<float, 2>{0, 0}});
            }
        }
    }
    return expect;
}

// The same pairs as the imported mesh has them at its triangles' corners.
CornerSet mesh_corners(const tom::Mesh& m) {
    CornerSet got;
    for (uint32_t i : m.indices)
        got.insert({{m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]}, {m.texcoords[2 * i], m.texcoords[2 * i + 1]}});
    return got;
}

void check_corners(const std::string& path) {
    INFO(path);
    const CornerSet expect = obj_corners(path);
    tom::ImportResult r = tom::import_file(path);
    REQUIRE(r.meshes.size() == 1);
    REQUIRE(r.meshes[0].texcoords.size() == r.meshes[0].positions.size() / 3 * 2);
    const CornerSet got = mesh_corners(r.meshes[0]);
    std::vector<CornerSet::value_type> extra, missing;
    std::set_difference(got.begin(), got.end(), expect.begin(), expect.end(), std::back_inserter(extra));
    std::set_difference(expect.begin(), expect.end(), got.begin(), got.end(), std::back_inserter(missing));
    for (const auto& e : extra) UNSCOPED_INFO("extra " << e.first[0] << " " << e.first[1] << " " << e.first[2] << " uv " << e.second[0] << " " << e.second[1]);
    for (const auto& e : missing) UNSCOPED_INFO("missing " << e.first[0] << " " << e.first[1] << " " << e.first[2] << " uv " << e.second[0] << " " << e.second[1]);
    CHECK(got == expect);
}

} // namespace

TEST_CASE("OBJ: texture coordinates per face corner split vertices at UV seams, never smeared", "[import][attributes]") {
    const std::string spider = test::sample("assimp/OBJ/spider.obj");
    REQUIRE(obj_corners(spider).size() > 762);  // UV seams: more (position, uv) pairs than the file's 762 positions
    check_corners(spider);
}

TEST_CASE("OBJ: faces without texture coordinates among faces with them get (0, 0), the same every run", "[import][attributes]") {
    // regr01 has 2042 faces without `vt` and 668 with: OpenMesh leaves the former's corners
    // uninitialised, which made the output differ from run to run
    const std::string regr01 = test::sample("assimp/OBJ/regr01.obj");
    check_corners(regr01);
    const tom::Mesh a = tom::import_file(regr01).meshes.at(0), b = tom::import_file(regr01).meshes.at(0);
    CHECK(a.positions == b.positions);
    CHECK(a.texcoords == b.texcoords);
    CHECK(a.normals == b.normals);
    CHECK(a.indices == b.indices);
}

TEST_CASE("OBJ: a polygon's texture coordinates stay at its corners when it is cut into triangles", "[import][attributes]") {
    // a quad, a pentagon, a triangle without `vt` and a face repeating an edge the wrong way
    // round (non-manifold: OpenMesh re-adds it with copies of its vertices), every corner with
    // its own coordinate
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "tom_import_polygons";
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "polygons.obj").string();
    {
        std::ofstream f(path);
        f << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 3 0.5 0\nv 2.5 1.5 0\nv 2 1 0\nv 0.5 2 0\n";
        for (int i = 1; i <= 12; ++i) f << "vt " << 0.05 * i << " " << 1.0 - 0.07 * i << "\n";
        f << "f 1/1 2/2 3/3 4/4\n"           // quad
             "f 2/5 5/6 6/7 7/8 8/9\n"       // pentagon sharing vertex 2
             "f 4 3 9\n"                     // no texture coordinates
             "f 1/10 2/11 4/12\n";           // edge 1-2 a second time in the same direction
    }
    check_corners(path);
    std::filesystem::remove_all(dir);
}

TEST_CASE("glTF: KHR_texture_transform is baked into the texture coordinates it applies to", "[import][gltf][attributes]") {
    // meshes 0-2 share accessor 2 and meshes 3-8 accessor 1; 6 has no transform
    const tom::ImportResult r = tom::import_file(test::sample("assimp/glTF2/textureTransform/TextureTransformTest.gltf"));
    REQUIRE(r.meshes.size() == 9);
    const std::vector<float>& plain = r.meshes[6].texcoords;  // accessor 1, untransformed
    REQUIRE(r.meshes[4].texcoords.size() == plain.size());
    for (size_t i = 0; i < plain.size(); ++i) CHECK(r.meshes[4].texcoords[i] == Approx(1.5f * plain[i]));  // "Scale"
    const double c = std::cos(0.39269908169872414), s = std::sin(0.39269908169872414);
    for (size_t i = 0; i < plain.size(); i += 2) {  // "Rotation": [c s; -s c]
        CHECK(r.meshes[3].texcoords[i] == Approx(c * plain[i] + s * plain[i + 1]).margin(1e-6));
        CHECK(r.meshes[3].texcoords[i + 1] == Approx(-s * plain[i] + c * plain[i + 1]).margin(1e-6));
    }
    // "Offset U" and "Offset UV" share an accessor: they differ by (0, 0.5)
    for (size_t i = 0; i < r.meshes[0].texcoords.size(); i += 2) {
        CHECK(r.meshes[2].texcoords[i] == Approx(r.meshes[0].texcoords[i]));
        CHECK(r.meshes[2].texcoords[i + 1] == Approx(r.meshes[0].texcoords[i + 1] + 0.5f));
    }
}

TEST_CASE("glTF: Draco-compressed primitives decode to the same meshes as the uncompressed file", "[import][gltf][draco]") {
    tom::ImportResult plain = tom::import_file(test::sample("assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"));
    tom::ImportResult draco = tom::import_file(test::sample("assimp/glTF2/draco/2CylinderEngine.gltf"));
    // the Draco copy was encoded without the plain file's degenerate triangles: compare clean meshes
    for (tom::Mesh& m : plain.meshes) tom::clean_mesh(m);
    for (tom::Mesh& m : draco.meshes) tom::clean_mesh(m);
    // 34 triangle primitives in 29 meshes: the primitives of a mesh are its parts
    REQUIRE(plain.meshes.size() == 29);
    REQUIRE(draco.meshes.size() == plain.meshes.size());
    size_t parts = 0;
    double area_plain = 0, area_draco = 0;
    for (size_t i = 0; i < plain.meshes.size(); ++i) {
        INFO("mesh " << i << " " << plain.meshes[i].name);
        CHECK(plain.meshes[i].name == draco.meshes[i].name);
        REQUIRE(plain.meshes[i].parts.size() == draco.meshes[i].parts.size());
        parts += std::max<size_t>(1, plain.meshes[i].parts.size());
        for (size_t p = 0; p < plain.meshes[i].parts.size(); ++p) CHECK(plain.meshes[i].parts[p].material == draco.meshes[i].parts[p].material);
        // Draco quantizes positions, which can collapse a sliver or two: counts within a few
        CHECK(std::abs(int(plain.meshes[i].triangle_count()) - int(draco.meshes[i].triangle_count())) <= 8);
        area_plain += area(plain.meshes[i]);
        area_draco += area(draco.meshes[i]);
    }
    CHECK(parts == 34);
    CHECK(std::fabs(area_plain - area_draco) < 0.01 * area_plain);
}

TEST_CASE("glTF: a Draco primitive that cannot be decoded is an error naming it, never an empty mesh", "[import][gltf][draco]") {
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / "tom_draco_broken";
    fs::create_directories(dir);
    fs::copy_file(test::sample("assimp/glTF2/draco/2CylinderEngine.gltf"), dir / "2CylinderEngine.gltf", fs::copy_options::overwrite_existing);
    // the same buffer with its Draco bitstreams overwritten
    std::ifstream in(test::sample("assimp/glTF2/draco/2CylinderEngine.bin"), std::ios::binary);
    std::vector<char> bin((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (size_t i = 0; i < bin.size(); ++i) bin[i] = char(i * 7);
    std::ofstream(dir / "2CylinderEngine.bin", std::ios::binary).write(bin.data(), std::streamsize(bin.size()));
    const std::string e = import_error((dir / "2CylinderEngine.gltf").string());
    INFO(e);
    CHECK(e.find("2CylinderEngine.gltf") != std::string::npos);
    CHECK(e.find("primitives[0]") != std::string::npos);
    CHECK(e.find("KHR_draco_mesh_compression data does not decode") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("glTF: strips and fans become triangles, points and lines are listed as skipped", "[import][gltf]") {
    // Mesh_PrimitiveMode_NN of the glTF-Asset-Generator: 00 points, 01-03 lines, 04 line strip?,
    // the README of the set lists which; check by mode as read from the file instead
    int triangles_files = 0, skipped_files = 0;
    for (int k = 0; k <= 15; ++k) {
        char name[128];
        std::snprintf(name, sizeof name, "assimp/glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_%02d.gltf", k);
        const std::string path = test::sample(name);
        tom::ImportResult r;
        try {
            r = tom::import_file(path);
        } catch (const tom::Error& e) {
            FAIL(path << ": " << e.what());
        }
        INFO(path);
        if (r.meshes.empty()) {
            REQUIRE(r.skipped.size() == 1);
            CHECK((r.skipped[0].find("POINTS") != std::string::npos || r.skipped[0].find("LINE") != std::string::npos));
            ++skipped_files;
        } else {
            REQUIRE(r.meshes.size() == 1);
            CHECK(r.skipped.empty());
            tom::Mesh m = r.meshes[0];
            tom::clean_mesh(m);
            // every variant draws the same square: two triangles, same area, facing +z
            CHECK(m.triangle_count() == 2);
            CHECK(std::fabs(area(m) - area(r.meshes[0])) < 1e-6);
            for (size_t t = 0; t < m.indices.size(); t += 3) {
                const float* a = &m.positions[3 * m.indices[t]];
                const float* b = &m.positions[3 * m.indices[t + 1]];
                const float* c = &m.positions[3 * m.indices[t + 2]];
                const float nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
                CHECK(nz > 0);
            }
            ++triangles_files;
        }
    }
    CHECK(triangles_files == 8);
    CHECK(skipped_files == 8);
}

TEST_CASE("broken glTF files give a clear error naming the file and the problem", "[import][gltf][broken]") {
    struct Case {
        const char* file;
        const char* expect;
    } cases[] = {
        {"assimp/glTF2/IndexOutOfRange/IndexOutOfRange.gltf", "out of range"},
        {"assimp/glTF2/IndexOutOfRange/AllIndicesOutOfRange.gltf", "out of range"},
        {"assimp/glTF2/wrongTypes/badArray.gltf", "$.meshes[0].primitives: expected an array"},
        {"assimp/glTF2/wrongTypes/badExtension.gltf", "KHR_texture_transform: expected an object"},
        {"assimp/glTF2/wrongTypes/badNumber.gltf", "$.materials[0].normalTexture"},
        {"assimp/glTF2/wrongTypes/badObject.gltf", "pbrMetallicRoughness: expected an object"},
        {"assimp/glTF2/wrongTypes/badString.gltf", "name: expected a string"},
        {"assimp/glTF2/wrongTypes/badUint.gltf", "expected a non-negative integer"},
        {"assimp/glTF2/SchemaFailures/sceneWrongType.gltf", "$.scene: expected a non-negative integer"},
        {"assimp/glTF2/IncorrectVertexArrays/Cube.gltf", "$.bufferViews[2]: bytes up to 936 of buffer 0, which has 514"},
        {"assimp/glTF2/MissingBin/BoxTextured.gltf", "BoxTextured0.bin"},
        {"assimp/glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb", "not finite"},
    };
    for (const Case& c : cases) {
        const std::string path = test::sample(c.file);
        const std::string e = import_error(path);
        INFO(path << " -> " << e);
        CHECK(e.find(path) == 0);
        CHECK(e.find(c.expect) != std::string::npos);
        CHECK(e.find('\n') == std::string::npos);  // one line
    }
}

TEST_CASE("unreadable, empty and unknown files are errors, not crashes", "[import]") {
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / "tom_import_bad";
    fs::create_directories(dir);
    std::ofstream(dir / "empty.obj").close();
    std::ofstream(dir / "garbage.ply") << "ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\nend_header\n\x01\x02";
    std::ofstream(dir / "garbage.glb") << "glTF\x02\x00\x00\x00";
    std::ofstream(dir / "notes.txt") << "hello";
    CHECK(import_error((dir / "missing.obj").string()).find("missing.obj") != std::string::npos);
    CHECK(import_error((dir / "empty.obj").string()).find("empty") != std::string::npos);
    CHECK(import_error((dir / "garbage.ply").string()).find("garbage.ply") != std::string::npos);
    CHECK(import_error((dir / "garbage.glb").string()).find("garbage.glb") != std::string::npos);
    CHECK(import_error((dir / "notes.txt").string()).find("unsupported file type") != std::string::npos);
    CHECK(import_error(test::sample("assimp/OBJ/point_cloud.obj")).find("no triangles") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("malformed OFF, PLY and OBJ files are errors naming the file and the line", "[import][broken]") {
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / "tom_import_malformed";
    fs::create_directories(dir);
    const std::string cube_v = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
    struct Case {
        const char* name;
        std::string text;
        const char* expect;  // in the message, after "file:line: "
    };
    const std::vector<Case> cases = {
        {"huge_face.off", "OFF\n4 1 0\n" + cube_v + "999999999 0 1 2\n", "dir/huge_face.off:7: face 0 announces '999999999' corners"},
        {"bad_index.off", "OFF\n4 1 0\n" + cube_v + "3 0 1 4\n", "dir/bad_index.off:7: face 0 refers to vertex '4', the file has 4"},
        {"short.off", "OFF\n4 2 0\n" + cube_v + "3 0 1 2\n", "dir/short.off:8: the file ends after 1 of 2 faces"},
        {"counts.off", "OFF\n4000000000 1 0\n" + cube_v, "dir/counts.off:2: 4000000000 vertices and 1 faces cannot fit"},
        {"nan.off", "OFF\n4 1 0\n0 0 0\nnan 0 0\n1 1 0\n0 1 0\n3 0 1 2\n", "dir/nan.off:4: vertex 1: 'nan' is not a number"},
        // out of float range (strtof's ERANGE: overflow, and underflow past the normal floats)
        {"overflow.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 3.5e38\n3 0 1 2\n", "dir/overflow.off:6: vertex 3: '3.5e38' is not a number"},
        {"underflow.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0.000000000000000000000000000000000000001 1 0\n0 0 1\n3 0 1 2\n",
         "dir/underflow.off:5: vertex 2: '0.00000000000000000000000000000000000000...' is not a number"},  // quoted up to 40 characters
        {"underflow_exponent.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n1e-41 0 1\n3 0 1 2\n", "dir/underflow_exponent.off:6: vertex 3: '1e-41' is not a number"},
        {"dimension.off", "nOFF\n4\n4 1 0\n", "only three-dimensional vertices"},
        {"bad_type.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty flaot x\nend_header\n", "dir/bad_type.ply:4: expected 'property TYPE NAME'"},
        {"no_end.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n", "the file ends before end_header"},
        {"list.ply",
         "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" +
             cube_v + "200 0 1 2\n",
         "dir/list.ply:14: face 0: the list vertex_indices announces '200' items, the line holds 3"},
        {"index.ply",
         "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" +
             cube_v + "3 0 1 7\n",
         "dir/index.ply:14: face 0: '7' is not a vertex of the 4"},
        {"binary.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\nproperty float z\nend_header\n" + std::string(24, '\0'),
         "dir/binary.ply:3: 1000 vertex elements of at least 12 bytes cannot fit in the 24 bytes left"},
        {"vertex.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 4\n", "dir/vertex.obj:4: a face refers to vertex '4', the file has 3"},
        {"texcoord.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nf 1/1 2/2 3/1\n", "dir/texcoord.obj:5: a face refers to texture coordinate '2', the file has 1"},
        {"relative.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -1 -2 -4\n", "dir/relative.obj:4: a face refers to vertex '-4', the file has 3"},
    };
    for (const Case& c : cases) {
        INFO(c.name);
        const std::string path = (dir / c.name).string();
        std::ofstream(path, std::ios::binary) << c.text;
        std::string expect = c.expect;
        if (expect.rfind("dir/", 0) == 0) expect = (dir / expect.substr(4)).string();
        const std::string message = import_error(path);
        CHECK(message.find(expect) != std::string::npos);
        CHECK(message.find(path) != std::string::npos);
    }
    fs::remove_all(dir);
}

// The files a first coverage-guided fuzzing run made crash, exhaust memory or loop (tests/data/
// hostile/, one per defect class), and two written by hand: each is an error naming the file and
// the place, before OpenMesh or tinygltf sees it.
TEST_CASE("hostile files from the first fuzzing run are errors naming the file and the place", "[import][broken][hostile]") {
    const std::string dir = TOM_HOSTILE_DIR;
    struct Case {
        const char* file;
        const char* expect;  // after the path
    };
    const std::vector<Case> cases = {
        {"A-vertex-not-a-number.obj", ":3: a vertex needs 3 numbers, found '%0'"},
        {"A2-vertex-number-suffix.obj", ":3: a vertex needs 3 numbers, found '1o'"},  // (the fuzzers' second run)
        {"B-extra-token.ply", ":12: vertex 2: 1 value past its 3 properties, from '-1'"},
        {"C-property-word.ply", ":3: a header line starting with 'l' has the keyword 'property' after it"},
        {"D-element-word.ply", ":3: a header line starting with 'x' has the keyword 'element' after it"},
        {"K-off-counts-on-keyword-line.off", ":1: '0' after 'NOFF': the vertex, face and edge counts must start the next line"},  // OpenMesh read -1 vertices
        {"L-off-comment-before-counts.off", ": no triangles or polygons in the file"},  // the counts after the comment are 0 0 0
        {"Q-ply-element-count-past-32-bits.ply", ":3: the element count 66666666666664 exceeds 4294967295"},  // OpenMesh's header loop grew without end
        {"P-off-binary-after-tabs.off", ":1: a binary OFF file must start with the line 'COFF BINARY'"},
        {"J-header-format-words.ply", ":2: a header line starting with 'fmat' has the keyword 'binary_little_endian' after it"},  // a hang
        {"F-draco-no-buffer-views.gltf", ": $.meshes[0].primitives[0].extensions.KHR_draco_mesh_compression.bufferView: names bufferView 0, the file has 0"},
        {"F-draco-no-buffers.gltf", ": $.bufferViews[0].buffer: names buffer 0, the file has 0"},
        {"F-draco-view-past-list.gltf", ": $.meshes[0].primitives[0].extensions.KHR_draco_mesh_compression.bufferView: names bufferView 7, the file has 1"},
        {"G-number-overflow.gltf", ": the glTF JSON does not parse: number overflow parsing '1e400'"},
        {"I-material-past-list.gltf", ": $.meshes[0].primitives[0].material: names material 3, the file has 1"},
    };
    for (const Case& c : cases) {
        INFO(c.file);
        const std::string path = dir + "/" + c.file;
        const std::string message = import_error(path);
        CHECK(message.find(path + c.expect) != std::string::npos);
    }
}

// Files of the fuzzers' later runs that OpenMesh read differently from the check (a '#' inside a
// face, a value after a face's corners): OpenMesh now reads the canonical text of what was
// checked, so they convert as the check read them (N has a face with a repeated corner: 3 of 4).
TEST_CASE("files OpenMesh once tokenized differently convert as checked", "[import][hostile]") {
    struct Case {
        const char* file;
        uint32_t triangles;
    };
    for (const Case& c : {Case{"M-obj-comment-inside-face.obj", 8}, Case{"N-off-value-after-corners.off", 3}}) {
        INFO(c.file);
        const tom::ImportResult r = tom::import_file(std::string(TOM_HOSTILE_DIR) + "/" + c.file);
        REQUIRE(r.meshes.size() == 1);
        CHECK(r.meshes[0].triangle_count() == c.triangles);
        for (uint32_t i : r.meshes[0].indices) CHECK(i < r.meshes[0].vertex_count());
    }
}

TEST_CASE("OFF BINARY reads as its ASCII form does and another header line is an error", "[import]") {
    // a tetrahedron; OpenMesh takes a file as binary only for " BINARY" after the keyword: the
    // tabs of the fuzzers' file P-off-binary-after-tabs.off made it read the body as text
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / "tom_off_binary";
    fs::create_directories(dir);
    const float p[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const uint32_t faces[4][4] = {{3, 0, 2, 1}, {3, 0, 1, 3}, {3, 1, 2, 3}, {3, 0, 3, 2}};
    std::string body;
    auto put = [&](const void* bytes, size_t n) { body.append(static_cast<const char*>(bytes), n); };
    const uint32_t counts[3] = {4, 4, 0};
    put(counts, sizeof counts);
    put(p, sizeof p);
    for (const auto& f : faces) put(f, sizeof f);  // as OpenMesh reads them: no colour count after the corners
    std::ofstream(dir / "ascii.off") << "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
    std::ofstream(dir / "binary.off", std::ios::binary) << "OFF BINARY\n" << body;
    std::ofstream(dir / "tabs.off", std::ios::binary) << "OFF\t\t BINARY # a comment\n" << body;
    const tom::Mesh ascii = tom::import_file((dir / "ascii.off").string()).meshes.at(0);
    const tom::Mesh m = tom::import_file((dir / "binary.off").string()).meshes.at(0);
    CHECK(m.positions == ascii.positions);
    CHECK(m.indices == ascii.indices);
    CHECK(import_error((dir / "tabs.off").string()) == (dir / "tabs.off").string() + ":1: a binary OFF file must start with the line 'OFF BINARY', found 'OFF\t\t BINARY # a comment'");
    fs::remove_all(dir);
}

TEST_CASE("glTF: a Draco attribute id the Draco data does not have is an error naming it", "[import][gltf][draco][hostile]") {
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / "tom_draco_attribute";
    fs::create_directories(dir);
    fs::copy_file(test::sample("assimp/glTF2/draco/2CylinderEngine.bin"), dir / "2CylinderEngine.bin", fs::copy_options::overwrite_existing);
    std::ifstream in(test::sample("assimp/glTF2/draco/2CylinderEngine.gltf"));
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string from = "\"NORMAL\": 0,\n                \"POSITION\": 1";  // the first primitive's ids
    REQUIRE(text.find(from) != std::string::npos);
    text.replace(text.find(from), from.size(), "\"NORMAL\": 0,\n                \"POSITION\": 9");
    std::ofstream(dir / "2CylinderEngine.gltf") << text;
    const std::string e = import_error((dir / "2CylinderEngine.gltf").string());
    CHECK(e.find((dir / "2CylinderEngine.gltf").string() + ": $.meshes[0].primitives[0].extensions.KHR_draco_mesh_compression.attributes.POSITION: "
                 "the Draco data has no attribute 9") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("numbers anywhere in the float range are read, written in any form", "[import]") {
    namespace fs = std::filesystem;
    const fs::path path = fs::temp_directory_path() / "tom_import_numbers.off";
    std::ofstream(path, std::ios::binary) << "OFF\n4 2 0\n1e30 0 0\n0 1E-30 +2.5\n-3.4e38 0.000000000000000000000000000001 0\n"
                                             "00012.5e+1 -0 .5\n3 0 1 2\n3 0 2 3\n";
    const tom::ImportResult r = tom::import_file(path.string());
    REQUIRE(r.meshes.size() == 1);
    const std::vector<float>& p = r.meshes[0].positions;
    REQUIRE(p.size() == 12);
    CHECK(p[0] == 1e30f);
    CHECK(p[4] == 1e-30f);
    CHECK(p[5] == 2.5f);
    CHECK(p[6] == -3.4e38f);
    CHECK(p[7] == 1e-30f);
    CHECK(p[9] == 125.0f);
    CHECK(p[11] == 0.5f);
    fs::remove(path);
}

TEST_CASE("mutated sample files (truncated, bytes flipped, extreme numbers) give a mesh or an error, never a crash", "[import][broken]") {
    // OpenMesh's readers, left to themselves, loop forever, crash or read uninitialised memory on
    // several of these (a PLY header with a mangled type, an OFF face announcing a billion
    // corners, an OBJ face naming a missing vertex, 'nan' in an ASCII PLY)
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / "tom_import_mutated";
    fs::create_directories(dir);
    std::mt19937 rng(20261122);
    const char* samples[] = {"assimp/PLY/cube.ply", "assimp/PLY/cube_binary.ply", "assimp/PLY/cube_uv.ply", "assimp/PLY/float-color.ply",
                             "assimp/OFF/Cube.off", "assimp/OBJ/box.obj", "assimp/OBJ/spider.obj", "assimp/STL/triangle.stl", "assimp/STL/Spider_binary.stl"};
    const char* extreme[] = {"999999999", "-1", "0", "4294967295", "2147483648", "1e308", "nan", "-999999", "1.5"};
    size_t meshes = 0, errors = 0;
    for (const char* sample : samples) {
        std::ifstream in(test::sample(sample), std::ios::binary);
        const std::string original((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        REQUIRE(original.size() > 8);
        const std::string ext = fs::path(sample).extension().string();
        for (int k = 0; k < 40; ++k) {
            std::string text = original;
            switch (k % 4) {
            case 0:  // truncated
                text.resize(1 + rng() % (text.size() - 1));
                break;
            case 1:  // bytes changed
                for (int n = 1 + int(rng() % 20); n > 0; --n) text[rng() % text.size()] = char(rng() % 256);
                break;
            case 2:  // a number replaced by an extreme one
                for (int n = 0; n < 5; ++n) {
                    size_t at = rng() % text.size();
                    while (at < text.size() && !std::isdigit(static_cast<unsigned char>(text[at]))) ++at;
                    size_t end = at;
                    while (end < text.size() && std::isdigit(static_cast<unsigned char>(text[end]))) ++end;
                    if (end > at) text.replace(at, end - at, extreme[rng() % 9]);
                }
                break;
            default: {  // a chunk repeated
                const size_t at = rng() % text.size(), len = std::min<size_t>(text.size() - at, 1 + rng() % 200);
                text.insert(at + len, text.substr(at, len));
            }
            }
            const std::string path = (dir / ("m" + std::to_string(k) + ext)).string();
            std::ofstream(path, std::ios::binary) << text;
            INFO(sample << " mutation " << k);
            try {
                tom::ImportResult r = tom::import_file(path);
                for (tom::Mesh& m : r.meshes) {
                    tom::clean_mesh(m);
                    for (uint32_t i : m.indices) REQUIRE(i < m.vertex_count());
                }
                ++meshes;
            } catch (const tom::Error& e) {
                CHECK(std::string(e.what()).find(path) != std::string::npos);
                ++errors;
            }
        }
    }
    CHECK(meshes > 0);
    CHECK(errors > 0);
    fs::remove_all(dir);
}

TEST_CASE("binary PLY of a scan's layout reads directly, as OpenMesh reads it, and bad counts are errors", "[import][ply]") {
    // the same sphere with normals and colours, as quads and triangles, written twice: in the
    // simple layout (read by read_simple_binary_ply) and with one more vertex property, which
    // sends it to OpenMesh; both must give the same mesh
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / "tom_ply_simple";
    fs::create_directories(dir);
    tom::Mesh sphere = tom::make_sphere(24, 32, 1.0f, 0.05f);
    tom::clean_mesh(sphere);
    auto write = [&](const fs::path& path, bool extra, const std::vector<std::vector<uint32_t>>& faces, const std::string& list = "uchar int") {
        std::ostringstream o(std::ios::binary);
        o << "ply\nformat binary_little_endian 1.0\ncomment a test\nelement vertex " << sphere.vertex_count()
          << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
             "property uchar red\nproperty uchar green\nproperty uchar blue\n"
          << (extra ? "property float quality\n" : "") << "element face " << faces.size() << "\nproperty list " << list << " vertex_indices\nend_header\n";
        for (uint32_t v = 0; v < sphere.vertex_count(); ++v) {
            o.write(reinterpret_cast<const char*>(&sphere.positions[3 * v]), 12);
            o.write(reinterpret_cast<const char*>(&sphere.normals[3 * v]), 12);
            const uint8_t rgb[3] = {uint8_t(v % 256), uint8_t(v * 7 % 256), 200};
            o.write(reinterpret_cast<const char*>(rgb), 3);
            const float q = 0.5f;
            if (extra) o.write(reinterpret_cast<const char*>(&q), 4);
        }
        for (const std::vector<uint32_t>& f : faces) {
            if (list.rfind("uchar", 0) == 0) {
                const uint8_t n = uint8_t(f.size());
                o.write(reinterpret_cast<const char*>(&n), 1);
            } else {
                const uint32_t n = uint32_t(f.size());
                o.write(reinterpret_cast<const char*>(&n), 4);
            }
            o.write(reinterpret_cast<const char*>(f.data()), std::streamsize(4 * f.size()));
        }
        std::ofstream(path, std::ios::binary) << o.str();
    };
    std::vector<std::vector<uint32_t>> faces;  // pairs of triangles as quads where they share an edge, the rest as triangles
    for (size_t t = 0; t < sphere.indices.size(); t += 3) {
        const uint32_t a = sphere.indices[t], b = sphere.indices[t + 1], c = sphere.indices[t + 2];
        if (t + 5 < sphere.indices.size() && t % 12 == 0 && sphere.indices[t + 3] == a && sphere.indices[t + 4] == c)
            faces.push_back({a, b, c, sphere.indices[t + 5]}), t += 3;
        else
            faces.push_back({a, b, c});
    }
    write(dir / "simple.ply", false, faces);
    write(dir / "openmesh.ply", true, faces);
    write(dir / "uint-counts.ply", false, faces, "uint uint");
    const tom::Mesh a = tom::import_file((dir / "simple.ply").string()).meshes.at(0);
    const tom::Mesh b = tom::import_file((dir / "openmesh.ply").string()).meshes.at(0);
    const tom::Mesh c = tom::import_file((dir / "uint-counts.ply").string()).meshes.at(0);
    REQUIRE(a.triangle_count() > faces.size());  // some quads were cut
    CHECK(a.positions == b.positions);
    CHECK(a.indices == b.indices);
    CHECK(a.normals == b.normals);
    REQUIRE(a.colors.size() == b.colors.size());
    for (size_t i = 0; i < a.colors.size(); ++i) CHECK(a.colors[i] == Approx(b.colors[i]).margin(1e-6));
    CHECK(c.indices == a.indices);
    // a corner past the vertices, a count past the data, and truncation are errors naming the file
    std::vector<std::vector<uint32_t>> bad = faces;
    bad[5][1] = sphere.vertex_count();
    write(dir / "bad-index.ply", false, bad);
    CHECK(import_error((dir / "bad-index.ply").string()).find(":14: face 5 refers to vertex " + std::to_string(sphere.vertex_count())) != std::string::npos);
    bad = faces;
    bad.back() = std::vector<uint32_t>(200, 0);
    write(dir / "long-face.ply", false, bad, "uint int");
    std::string bytes;
    {
        std::ifstream in(dir / "long-face.ply", std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    const uint32_t huge = 0x7fffffffu;
    std::memcpy(&bytes[bytes.size() - 4 * 200 - 4], &huge, 4);  // the last face announces 2^31 - 1 corners
    std::ofstream(dir / "huge-count.ply", std::ios::binary) << bytes;
    CHECK(import_error((dir / "huge-count.ply").string()).find(":14: face " + std::to_string(bad.size() - 1) + ": the list vertex_indices announces 2147483647 items, the file holds fewer") != std::string::npos);
    std::ofstream(dir / "truncated.ply", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    CHECK(import_error((dir / "truncated.ply").string()).find((dir / "truncated.ply").string()) == 0);
    fs::remove_all(dir);
}
