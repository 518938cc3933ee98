// Nothing lost without a word: images embedded in a glTF (a GLB's buffer view, a data: URI) are
// stored in the .tom byte for byte and written again by the exporters; WebP and KTX2 textures are
// carried, not refused; what a glTF holds that the .tom does not keep (skins, animations, morph
// targets, cameras, extensions, ...) is named; an OBJ's texture coordinates reach glTF the right
// way up and come back unchanged; a material index that names no stored material is never
// followed.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "glb.h"
#include "support.h"
#include "tom/builder/builder.h"
#include "tom/builder/writer.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/io/export.h"
#include "tom/io/import.h"
#include "tom/metrics/distance.h"

namespace {

namespace fs = std::filesystem;
using test::file_bytes;
using test::Glb;

fs::path work_dir(const char* name) {
    const fs::path dir = fs::temp_directory_path() / "tom_fidelity_test" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

// Imports `source`, builds and stores it, and opens the stored bytes.
struct Stored {
    tom::ImportResult imported;
    std::vector<uint8_t> bytes;
    tom::File file;
};
Stored store(const std::string& source) {
    tom::ImportResult r = tom::import_file(source);
    std::vector<tom::TomMesh> built;
    for (tom::Mesh& m : r.meshes) {
        tom::clean_mesh(m);
        built.push_back(tom::build(m));
    }
    std::vector<uint8_t> bytes = tom::serialize(built, r.scene);
    tom::File file = tom::File::from_bytes(bytes.data(), bytes.size(), source);
    return {std::move(r), std::move(bytes), std::move(file)};
}

// Every mesh of `file` at full resolution, as export_glb takes them.
std::vector<tom::GlbMesh> full_detail(const tom::File& file) {
    std::vector<tom::GlbMesh> out;
    for (uint32_t i = 0; i < file.mesh_count(); ++i) out.push_back({&file.mesh(i), {file.mesh(i).vertex_count}});
    return out;
}

bool has(const std::vector<std::string>& list, const std::string& item) { return std::find(list.begin(), list.end(), item) != list.end(); }

} // namespace

TEST_CASE("images embedded in a GLB or a data: URI are stored byte for byte and embedded again", "[fidelity][images]") {
    const std::vector<uint8_t> png = file_bytes(test::sample("assimp/glTF2/BoxTextured-glTF/CesiumLogoFlat.png"));
    REQUIRE(png.size() > 1000);
    // the same image in a GLB's binary chunk and in a data: URI
    for (const char* source : {"assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", "assimp/glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf"}) {
        INFO(source);
        const Stored s = store(test::sample(source));
        REQUIRE(s.file.scene().images.size() == 1);
        const tom::Image& image = s.file.scene().images[0];
        CHECK(image.mime_type == "image/png");
        REQUIRE(image.bytes == png.size());
        CHECK(std::memcmp(image.data, png.data(), png.size()) == 0);
        // in place: a borrowed file's image lies inside the caller's bytes
        const tom::File mapped = tom::File::borrow(s.bytes.data(), s.bytes.size());
        CHECK((mapped.scene().images[0].data > s.bytes.data() && mapped.scene().images[0].data + png.size() <= s.bytes.data() + s.bytes.size()));
        REQUIRE(s.file.scene().materials.size() == 1);
        CHECK(s.file.scene().materials[0].textures.at(0).image == 0);
        CHECK(s.file.scene().materials[0].textures.at(0).uri.empty());
        // glTF out: the image in the binary chunk again, the validator's way (bufferView + mimeType)
        const fs::path dir = work_dir("images");
        tom::export_glb((dir / "box.glb").string(), full_detail(s.file), s.file.scene());
        const Glb out(file_bytes(dir / "box.glb"));
        REQUIRE(out.doc["images"].size() == 1);
        CHECK(out.doc["images"][0]["mimeType"] == "image/png");
        CHECK(out.image(out.base_color_image(0)) == png);
        // OBJ out: the image as a file beside it, named by the .mtl
        tom::ExportPart part;
        part.mesh = &s.file.mesh(0);
        part.vertex_count = part.mesh->vertex_count;
        part.indices.resize(size_t(part.mesh->triangle_count) * 3);
        tom::extract(*part.mesh, part.vertex_count, part.indices.data(), part.indices.size());
        tom::export_meshes((dir / "box.obj").string(), {part}, s.file.scene());
        CHECK(file_bytes(dir / "box.image-0.png") == png);
        std::ifstream mtl(dir / "box.mtl");
        const std::string text((std::istreambuf_iterator<char>(mtl)), std::istreambuf_iterator<char>());
        CHECK(text.find("map_Kd box.image-0.png") != std::string::npos);
    }
}

TEST_CASE("a JPEG in a GLB and a punctual light come back as they were", "[fidelity][images]") {
    // the box with the spider's JPEG in its binary chunk in place of its PNG, and a point light on
    // a node of its own beside the box's
    Glb variant(file_bytes(test::sample("assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb")));
    const std::vector<uint8_t> jpeg = file_bytes(test::sample("assimp/OBJ/SpiderTex.jpg"));
    REQUIRE(jpeg.size() > 1000);
    while (variant.bin.size() % 4) variant.bin.push_back(0);
    variant.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", variant.bin.size()}, {"byteLength", jpeg.size()}});
    variant.bin.insert(variant.bin.end(), jpeg.begin(), jpeg.end());
    while (variant.bin.size() % 4) variant.bin.push_back(0);  // GLB chunks end on 4 bytes
    variant.doc["buffers"][0]["byteLength"] = variant.bin.size();
    variant.doc["images"][0] = {{"bufferView", variant.doc["bufferViews"].size() - 1}, {"mimeType", "image/jpeg"}};
    const nlohmann::json light = {{"type", "point"}, {"color", {1.0, 0.5, 0.25}}, {"intensity", 20.0}, {"name", "lamp"}};
    variant.doc["extensions"]["KHR_lights_punctual"]["lights"] = {light};
    variant.doc["nodes"].push_back({{"name", "lamp node"}, {"translation", {1.0, 2.0, 3.0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    variant.doc["scenes"][0]["nodes"].push_back(variant.doc["nodes"].size() - 1);
    variant.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    const fs::path dir = work_dir("jpeg-light");
    const std::vector<uint8_t> bytes = variant.bytes();
    std::ofstream(dir / "box.glb", std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));

    const Stored s = store((dir / "box.glb").string());
    CHECK(s.imported.dropped.empty());
    REQUIRE(s.file.scene().images.size() == 1);
    CHECK(s.file.scene().images[0].mime_type == "image/jpeg");
    CHECK(std::vector<uint8_t>(s.file.scene().images[0].data, s.file.scene().images[0].data + s.file.scene().images[0].bytes) == jpeg);
    tom::export_glb((dir / "out.glb").string(), full_detail(s.file), s.file.scene());
    const Glb out(file_bytes(dir / "out.glb"));
    CHECK(out.doc["images"][0]["mimeType"] == "image/jpeg");
    CHECK(out.image(out.base_color_image(0)) == jpeg);
    CHECK(out.doc["extensions"]["KHR_lights_punctual"]["lights"] == nlohmann::json::array({light}));
    CHECK(out.doc["extensionsUsed"] == nlohmann::json::array({"KHR_lights_punctual"}));
    const nlohmann::json& lamp = out.doc["nodes"][variant.doc["nodes"].size() - 1];
    CHECK(lamp["name"] == "lamp node");
    CHECK(lamp["extensions"]["KHR_lights_punctual"]["light"] == 0);
    CHECK(lamp["translation"] == nlohmann::json::array({1.0, 2.0, 3.0}));
}

TEST_CASE("an image that is a file stays a URI, or is embedded on request", "[fidelity][images]") {
    const std::string source = test::sample("assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf");
    const Stored s = store(source);
    CHECK(s.file.scene().images.empty());
    REQUIRE(s.file.scene().materials.at(0).textures.size() == 1);
    CHECK(s.file.scene().materials[0].textures[0].image == -1);
    CHECK(s.file.scene().materials[0].textures[0].uri == "CesiumLogoFlat.png");
    const fs::path dir = work_dir("external");
    const std::string texture_dir = fs::path(source).parent_path().string();
    tom::export_glb((dir / "uri.glb").string(), full_detail(s.file), s.file.scene(), texture_dir);
    const Glb by_uri(file_bytes(dir / "uri.glb"));
    CHECK(by_uri.doc["images"][0]["uri"] == fs::relative(fs::path(texture_dir) / "CesiumLogoFlat.png", dir).generic_string());
    tom::export_glb((dir / "embedded.glb").string(), full_detail(s.file), s.file.scene(), texture_dir, true);
    const Glb embedded(file_bytes(dir / "embedded.glb"));
    CHECK(!embedded.doc["images"][0].contains("uri"));
    CHECK(embedded.image(0) == file_bytes(fs::path(texture_dir) / "CesiumLogoFlat.png"));
    // an image to embed that is not there is an error naming it, and no output is left
    CHECK_THROWS_WITH(tom::export_glb((dir / "missing.glb").string(), full_detail(s.file), s.file.scene(), dir.string(), true),
                      Catch::Contains("cannot read image") && Catch::Contains("CesiumLogoFlat.png"));
    CHECK(!fs::exists(dir / "missing.glb"));
}

TEST_CASE("WebP and KTX2 textures are carried with their extension, not refused", "[fidelity][images]") {
    const Glb box(file_bytes(test::sample("assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb")));
    const std::vector<uint8_t> image = box.image(0);
    const std::pair<const char*, const char*> codecs[] = {{"EXT_texture_webp", "image/webp"}, {"KHR_texture_basisu", "image/ktx2"}};
    for (const auto& [extension, mime] : codecs) {
        INFO(extension);
        // the box with its texture in that codec alone (the bytes stay the PNG's: nothing decodes them)
        Glb variant = box;
        variant.doc["images"][0]["mimeType"] = mime;
        variant.doc["textures"][0] = {{"extensions", {{extension, {{"source", 0}}}}}};
        variant.doc["extensionsUsed"] = {extension};
        variant.doc["extensionsRequired"] = {extension};
        const fs::path dir = work_dir("codecs");
        const fs::path path = dir / "variant.glb";
        const std::vector<uint8_t> bytes = variant.bytes();
        std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
        const Stored s = store(path.string());
        REQUIRE(s.file.scene().images.size() == 1);
        CHECK(s.file.scene().images[0].mime_type == mime);
        CHECK(!has(s.imported.dropped, std::string("extension ") + extension));
        tom::export_glb((dir / "out.glb").string(), full_detail(s.file), s.file.scene());
        const Glb out(file_bytes(dir / "out.glb"));
        CHECK(out.doc["extensionsRequired"] == nlohmann::json::array({extension}));
        CHECK(out.doc["textures"][0]["extensions"][extension]["source"] == 0);
        CHECK(out.doc["images"][0]["mimeType"] == mime);
        CHECK(out.image(out.base_color_image(0)) == image);
    }
    // an extension that changes how geometry is placed is still refused, by name
    Glb instanced = box;
    instanced.doc["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
    instanced.doc["extensionsRequired"] = {"EXT_mesh_gpu_instancing"};
    const fs::path path = work_dir("instanced") / "instanced.glb";
    const std::vector<uint8_t> bytes = instanced.bytes();
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
    CHECK_THROWS_WITH(tom::import_file(path.string()), Catch::Contains("requires extension EXT_mesh_gpu_instancing"));
}

TEST_CASE("what a glTF holds and the .tom does not keep is named, never dropped silently", "[fidelity][dropped]") {
    // what is carried is not named: skins, animations, cameras, node trees, samplers, morph targets
    const std::vector<std::pair<const char*, std::vector<std::string>>> cases = {
        {"assimp/glTF2/simple_skin/simple_skin.gltf", {}},
        {"assimp/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf", {}},
        {"assimp/glTF2/cameras/Cameras.gltf", {}},
        {"assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", {}},
        {"assimp/glTF2/ClearCoat-glTF/ClearCoatTest.gltf", {}},
        {"assimp/glTF2/BoxTextured-glTF-pbrSpecularGlossiness/BoxTextured.gltf",
         {"extension KHR_materials_pbrSpecularGlossiness (its specular and glossiness; the diffuse is kept as the base colour)"}},
    };
    for (const auto& [source, expected] : cases) {
        INFO(source);
        const tom::ImportResult r = tom::import_file(test::sample(source));
        CHECK(r.dropped == expected);
        CHECK(!r.scene.gltf.empty());
    }
    {
        // assimp's exporter declares extensions no object uses: nothing is lost, nothing named;
        // the one a primitive uses is
        Glb declared(file_bytes(test::sample("assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb")));
        declared.doc["extensionsUsed"] = {"KHR_materials_volume", "FB_ngon_encoding"};
        const fs::path path = work_dir("declared") / "declared.glb";
        std::vector<uint8_t> bytes = declared.bytes();
        std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
        CHECK(tom::import_file(path.string()).dropped.empty());
        declared.doc["meshes"][0]["primitives"][0]["extensions"] = {{"FB_ngon_encoding", nlohmann::json::object()}};
        bytes = declared.bytes();
        std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
        CHECK(tom::import_file(path.string()).dropped == std::vector<std::string>{"extension FB_ngon_encoding"});
    }
    // a mesh's default morph weights and its extras are kept and come back on every level
    const std::string cube = test::sample("assimp/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf");
    std::ifstream cube_in(cube);
    nlohmann::json weighted = nlohmann::json::parse(cube_in);
    weighted["meshes"][0]["weights"] = {0.5, 0.0};
    weighted["meshes"][0]["extras"] = {{"tag", "cube"}};
    const fs::path weighted_dir = work_dir("weighted");
    for (const auto& e : fs::directory_iterator(fs::path(cube).parent_path()))
        if (e.path().extension() != ".gltf") fs::copy_file(e.path(), weighted_dir / e.path().filename());
    std::ofstream(weighted_dir / "weighted.gltf") << weighted.dump();
    {
        const Stored w = store((weighted_dir / "weighted.gltf").string());
        CHECK(w.imported.dropped.empty());
        const tom::MeshView& m = w.file.mesh(0);
        tom::export_glb((weighted_dir / "out.glb").string(), {{&m, {m.vertex_count, m.min_vertex_count}}}, w.file.scene());
        const Glb out(file_bytes(weighted_dir / "out.glb"));
        REQUIRE(out.doc["meshes"].size() == 2);
        for (const auto& level : out.doc["meshes"]) {
            CHECK(level["weights"] == nlohmann::json({0.5, 0.0}));
            CHECK(level["extras"] == nlohmann::json({{"tag", "cube"}}));
        }
    }
    // a material extension in extensionsRequired is read (it changes no geometry) and carried
    const std::string clearcoat = test::sample("assimp/glTF2/ClearCoat-glTF/ClearCoatTest.gltf");
    std::ifstream in(clearcoat);
    nlohmann::json doc = nlohmann::json::parse(in);
    doc["extensionsRequired"] = {"KHR_materials_clearcoat"};
    const fs::path dir = work_dir("required");
    for (const auto& e : fs::directory_iterator(fs::path(clearcoat).parent_path()))
        if (e.path().extension() != ".gltf") fs::copy_file(e.path(), dir / e.path().filename());
    std::ofstream(dir / "required.gltf") << doc.dump();
    const tom::ImportResult r = tom::import_file((dir / "required.gltf").string());
    CHECK(!r.meshes.empty());
    CHECK(r.dropped.empty());
    CHECK(r.scene.gltf.json.find("KHR_materials_clearcoat") != std::string::npos);
}

// The carried stream `name` of `s`'s mesh 0 as read from the file, and as imported (by input vertex).
static const tom::VertexStreamView& stored_stream(const tom::MeshView& m, const std::string& name) {
    for (uint32_t k = 0; k < m.extra_stream_count; ++k)
        if (m.extra_streams[k].name == name) return m.extra_streams[k];
    FAIL("no carried stream " << name);
    return m.extra_streams[0];
}

TEST_CASE("3-component texture coordinates, as assimp writes them, are read as (u, v)", "[fidelity][dropped]") {
    // assimp's glTF exporter writes the UVW channels of Collada and FBX files as VEC3 accessors
    // (glTF allows VEC2): u and v are the texture coordinates, and a third component is named
    // only when it holds something
    const std::string path = test::sample("assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
    const tom::ImportResult original = tom::import_file(path);
    REQUIRE(original.meshes.size() == 1);
    const std::vector<float>& uv = original.meshes[0].texcoords;
    const size_t n = uv.size() / 2;
    REQUIRE(n == original.meshes[0].vertex_count());
    for (const float w : {0.0f, 0.5f}) {
        INFO("w = " << w);
        Glb box(file_bytes(path));
        std::vector<float> uvw;
        for (size_t v = 0; v < n; ++v) uvw.insert(uvw.end(), {uv[2 * v], uv[2 * v + 1], w});
        box.doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = box.add(uvw, "VEC3", 5126, n);
        const fs::path out = work_dir("uvw") / "uvw.glb";
        const std::vector<uint8_t> bytes = box.bytes();
        std::ofstream(out, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
        const tom::ImportResult r = tom::import_file(out.string());
        REQUIRE(r.meshes.size() == 1);
        CHECK(r.meshes[0].texcoords == uv);
        const std::vector<std::string> named =
            w == 0.0f ? std::vector<std::string>{} : std::vector<std::string>{"the third component of TEXCOORD_0 (3-component texture coordinates)"};
        CHECK(r.dropped == named);
    }
    // four components are still an error naming the accessor
    Glb box(file_bytes(path));
    box.doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = box.add(std::vector<float>(4 * n, 0.25f), "VEC4", 5126, n);
    const fs::path out = work_dir("uvwq") / "uvwq.glb";
    const std::vector<uint8_t> bytes = box.bytes();
    std::ofstream(out, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
    CHECK_THROWS_WITH(tom::import_file(out.string()), Catch::Contains("TEXCOORD_0 accessor") && Catch::Contains("has 4 components"));
}

TEST_CASE("material extensions and materials' extras pass through, the textures they refer to renumbered", "[fidelity][dropped]") {
    const std::string box = test::sample("assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf");
    std::ifstream in(box);
    nlohmann::json doc = nlohmann::json::parse(in);
    const nlohmann::json kept = {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4.0}}}, {"KHR_materials_ior", {{"ior", 1.4}}}, {"KHR_materials_unlit", nlohmann::json::object()}};
    doc["materials"][0]["extensions"] = kept;
    doc["materials"][0]["extensions"]["KHR_materials_clearcoat"] = {{"clearcoatFactor", 1.0}, {"clearcoatTexture", {{"index", 0}}}};
    doc["materials"][0]["extras"] = {{"author", "someone"}};
    doc["extensionsUsed"] = {"KHR_materials_emissive_strength", "KHR_materials_ior", "KHR_materials_unlit", "KHR_materials_clearcoat"};
    const fs::path dir = work_dir("material-extensions");
    for (const auto& e : fs::directory_iterator(fs::path(box).parent_path()))
        if (e.path().extension() != ".gltf") fs::copy_file(e.path(), dir / e.path().filename());
    std::ofstream(dir / "box.gltf") << doc.dump();
    const Stored s = store((dir / "box.gltf").string());
    CHECK(s.imported.dropped.empty());
    tom::export_glb((dir / "out.glb").string(), full_detail(s.file), s.file.scene(), dir.string());
    const Glb out(file_bytes(dir / "out.glb"));
    nlohmann::json extensions = out.doc["materials"][0]["extensions"];
    // the clearcoat texture is the source's texture 0, the base colour's: the same image and sampler
    const nlohmann::json clearcoat = extensions["KHR_materials_clearcoat"];
    CHECK(clearcoat["clearcoatFactor"] == 1.0);
    CHECK(clearcoat["clearcoatTexture"]["index"] == out.doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"]);
    extensions.erase("KHR_materials_clearcoat");
    CHECK(extensions == kept);
    CHECK(out.doc["materials"][0]["extras"] == doc["materials"][0]["extras"]);
    CHECK(out.doc["extensionsUsed"] == nlohmann::json({"KHR_materials_clearcoat", "KHR_materials_emissive_strength", "KHR_materials_ior", "KHR_materials_unlit"}));
    CHECK(!out.doc.contains("extensionsRequired"));
    // a texture index that names no texture of the source is left out, the rest kept
    doc["materials"][0]["extensions"]["KHR_materials_clearcoat"]["clearcoatRoughnessTexture"] = {{"index", 7}};
    std::ofstream(dir / "box.gltf") << doc.dump();
    const Stored bad = store((dir / "box.gltf").string());
    tom::export_glb((dir / "out2.glb").string(), full_detail(bad.file), bad.file.scene(), dir.string());
    const Glb out2(file_bytes(dir / "out2.glb"));
    CHECK(out2.doc["materials"][0]["extensions"]["KHR_materials_clearcoat"].contains("clearcoatTexture"));
    CHECK(!out2.doc["materials"][0]["extensions"]["KHR_materials_clearcoat"].contains("clearcoatRoughnessTexture"));
}

TEST_CASE("joints, weights and morph deltas are carried exactly: every level's vertices hold the source's values", "[fidelity][carried]") {
    const std::vector<std::pair<const char*, std::vector<std::string>>> cases = {
        {"assimp/glTF2/simple_skin/simple_skin.gltf", {"JOINTS_0", "WEIGHTS_0"}},
        {"assimp/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf",
         {"TARGET0/NORMAL", "TARGET0/POSITION", "TARGET0/TANGENT", "TARGET1/NORMAL", "TARGET1/POSITION", "TARGET1/TANGENT"}},
    };
    for (const auto& [source, names] : cases) {
        INFO(source);
        tom::ImportResult r = tom::import_file(test::sample(source));
        REQUIRE(r.meshes.size() == 1);
        tom::clean_mesh(r.meshes[0]);
        const tom::Mesh input = r.meshes[0];
        const tom::TomMesh built = tom::build(input);
        const std::vector<uint8_t> bytes = tom::serialize({built}, r.scene);
        const tom::File f = tom::File::from_bytes(bytes.data(), bytes.size(), source);
        const tom::MeshView& m = f.mesh(0);
        REQUIRE(m.extra_stream_count == names.size());
        for (const std::string& name : names) {
            INFO(name);
            const tom::VertexStreamView& x = stored_stream(m, name);
            const auto in = std::find_if(input.extra_streams.begin(), input.extra_streams.end(), [&](const tom::VertexStream& s) { return s.name == name; });
            REQUIRE(in != input.extra_streams.end());
            CHECK((x.component_type == in->component_type && x.components == in->components && x.normalized == in->normalized));
            // sorted vertex i is input vertex original_index[i]: its element, byte for byte (no
            // interpolation: each level's vertices are a prefix of these)
            const size_t elem = in->element_bytes();
            for (uint32_t i = 0; i < m.vertex_count; ++i) REQUIRE(std::memcmp(x.data + i * elem, &in->data[size_t(built.original_index[i]) * elem], elem) == 0);
        }
        // back to glTF at two levels: the attributes and targets with their accessors' types
        const fs::path dir = work_dir("carried");
        tom::export_glb((dir / "out.glb").string(), {{&m, {m.vertex_count, m.min_vertex_count}}}, f.scene());
        const Glb out(file_bytes(dir / "out.glb"));
        for (const auto& mesh : out.doc["meshes"]) {
            const nlohmann::json& prim = mesh["primitives"][0];
            for (const std::string& name : names) {
                const size_t slash = name.find('/');
                const nlohmann::json& at = slash == std::string::npos ? prim["attributes"] : prim["targets"][std::stoul(name.substr(6))];
                const std::string attribute = slash == std::string::npos ? name : name.substr(slash + 1);
                INFO(name);
                REQUIRE(at.contains(attribute));
                CHECK(out.doc["accessors"][at[attribute].get<size_t>()]["componentType"] == stored_stream(m, name).component_type);
            }
        }
    }
}

namespace {

// A scene's triangles in world space: each instance's mesh (draw_list) through its transform.
struct WorldSurface {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    tom::Surface surface() const { return {positions.data(), uint32_t(positions.size() / 3), indices.data(), indices.size() / 3}; }
};
WorldSurface world_surface(const tom::ImportResult& r) {
    WorldSurface out;
    for (const tom::Instance& inst : tom::draw_list(r.scene, uint32_t(r.meshes.size()))) {
        const tom::Mesh& m = r.meshes[inst.mesh];
        const uint32_t base = uint32_t(out.positions.size() / 3);
        const float* t = inst.transform;
        for (size_t v = 0; v < m.vertex_count(); ++v) {
            const float* p = &m.positions[3 * v];
            for (int k = 0; k < 3; ++k) out.positions.push_back(t[k] * p[0] + t[4 + k] * p[1] + t[8 + k] * p[2] + t[12 + k]);
        }
        for (const uint32_t i : m.indices) out.indices.push_back(base + i);
    }
    return out;
}

// Each carried stream's elements as a sorted multiset of byte strings, per mesh and stream name.
std::map<std::string, std::multiset<std::string>> carried_elements(const tom::ImportResult& r) {
    std::map<std::string, std::multiset<std::string>> out;
    for (size_t i = 0; i < r.meshes.size(); ++i)
        for (const tom::VertexStream& x : r.meshes[i].extra_streams)
            for (size_t v = 0; v < r.meshes[i].vertex_count(); ++v)
                out[std::to_string(i) + ":" + x.name].insert(std::string(reinterpret_cast<const char*>(&x.data[v * x.element_bytes()]), x.element_bytes()));
    return out;
}

} // namespace

TEST_CASE("compressed glTF output: the same triangles within the 14-bit grid, carried data exact, read back", "[fidelity][compressed]") {
    for (const char* sample : {"assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", "assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb",
                               "assimp/glTF2/simple_skin/simple_skin.gltf", "assimp/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf"}) {
        INFO(sample);
        const Stored s = store(test::sample(sample));
        const fs::path dir = work_dir("compressed");
        tom::export_glb((dir / "plain.glb").string(), full_detail(s.file), s.file.scene());
        tom::export_glb((dir / "packed.glb").string(), full_detail(s.file), s.file.scene(), "", false, true);
        const Glb packed(file_bytes(dir / "packed.glb"));
        const size_t plain_bytes = file_bytes(dir / "plain.glb").size(), packed_bytes = file_bytes(dir / "packed.glb").size();
        if (plain_bytes > 100000) CHECK(packed_bytes * 3 < plain_bytes);  // the engine: 3.3 MB to 0.6 MB
        const std::set<std::string> required(packed.doc["extensionsRequired"].begin(), packed.doc["extensionsRequired"].end());
        CHECK(required.count("KHR_mesh_quantization"));
        CHECK(required.count("EXT_meshopt_compression"));
        for (const auto& view : packed.doc["bufferViews"])
            if (view.value("target", 0) == 34962 || view.value("target", 0) == 34963) CHECK(view["extensions"].contains("EXT_meshopt_compression"));
        // a skinned or morphed mesh keeps float positions (skinning ignores its node's transform)
        const bool animated = packed.doc.contains("skins") || packed.doc["meshes"][0]["primitives"][0].contains("targets");
        const size_t position = packed.doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<size_t>();
        CHECK(packed.doc["accessors"][position]["componentType"].get<int>() == (animated ? 5126 : 5123));
        // read back: the same triangles in world space, each corner within the grid's half step
        const tom::ImportResult plain = tom::import_file((dir / "plain.glb").string()), back = tom::import_file((dir / "packed.glb").string());
        const WorldSurface a = world_surface(plain), b = world_surface(back);
        REQUIRE(a.indices.size() == b.indices.size());
        const tom::Distance d = tom::metro_distance(a.surface(), b.surface());
        CHECK(d.hausdorff <= 1.0 / (1 << 14) * d.diagonal);
        CHECK(carried_elements(plain) == carried_elements(back));
        CHECK(back.dropped == plain.dropped);
    }
}

TEST_CASE("a sparse accessor is made dense: a sparse morph target carries the same deltas", "[fidelity][carried]") {
    // the morph cube as a GLB, its first target's POSITION rewritten as a sparse accessor: the
    // elements that move are spoiled in its base and given again by its sparse values
    const fs::path source = test::sample("assimp/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf");
    Glb glb;
    std::ifstream in(source);
    glb.doc = nlohmann::json::parse(in);
    glb.bin = file_bytes(source.parent_path() / "AnimatedMorphCube.bin");
    glb.doc["buffers"][0].erase("uri");
    const size_t target = glb.doc["meshes"][0]["primitives"][0]["targets"][0]["POSITION"].get<size_t>();
    nlohmann::json& accessor = glb.doc["accessors"][target];
    const size_t at = glb.doc["bufferViews"][accessor["bufferView"].get<size_t>()]["byteOffset"].get<size_t>() + accessor.value("byteOffset", size_t(0));
    std::vector<uint16_t> indices;
    std::vector<float> values;
    for (uint16_t v = 0; v < accessor["count"].get<uint16_t>(); ++v) {
        float d[3];
        std::memcpy(d, &glb.bin[at + 12 * size_t(v)], 12);
        if (d[1] == 0) continue;
        indices.push_back(v);
        values.insert(values.end(), d, d + 3);
        const float spoiled[3] = {7, 7, 7};
        std::memcpy(&glb.bin[at + 12 * size_t(v)], spoiled, 12);
    }
    REQUIRE((!indices.empty() && indices.size() < accessor["count"].get<size_t>()));
    const size_t index_view = glb.doc["accessors"][glb.add(indices, "SCALAR", 5123, indices.size())]["bufferView"].get<size_t>();
    const size_t value_view = glb.doc["accessors"][glb.add(values, "VEC3", 5126, indices.size())]["bufferView"].get<size_t>();
    nlohmann::json& sparse_accessor = glb.doc["accessors"][target];
    sparse_accessor["sparse"] = {{"count", indices.size()}, {"indices", {{"bufferView", index_view}, {"componentType", 5123}}}, {"values", {{"bufferView", value_view}}}};
    const fs::path dir = work_dir("sparse");
    const std::vector<uint8_t> bytes = glb.bytes();
    std::ofstream(dir / "sparse.glb", std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
    const tom::ImportResult dense = tom::import_file(source.string()), sparse = tom::import_file((dir / "sparse.glb").string());
    CHECK(sparse.dropped.empty());
    CHECK(carried_elements(sparse) == carried_elements(dense));
    REQUIRE(sparse.meshes.size() == 1);
    for (const tom::VertexStream& x : sparse.meshes[0].extra_streams)
        if (x.name == "TARGET0/POSITION")
            for (const tom::VertexStream& y : dense.meshes[0].extra_streams)
                if (y.name == x.name) CHECK(x.data == y.data);  // in vertex order too
    // an index past the accessor's elements is refused, named
    std::memcpy(&glb.bin[glb.doc["bufferViews"][index_view]["byteOffset"].get<size_t>()], "\xff\x00", 2);
    const std::vector<uint8_t> bad = glb.bytes();
    std::ofstream(dir / "bad.glb", std::ios::binary).write(reinterpret_cast<const char*>(bad.data()), long(bad.size()));
    CHECK_THROWS_WITH(tom::import_file((dir / "bad.glb").string()), Catch::Contains("bad.glb") && Catch::Contains("sparse index 0 is 255, past its 24 elements"));
}

TEST_CASE("an OBJ's texture coordinates reach glTF the right way up and come back unchanged", "[fidelity][texcoords]") {
    const std::string spider = test::sample("assimp/OBJ/spider.obj");
    // the file's vt values, as (u, v) pairs
    auto vt_of = [](const fs::path& path) {
        std::multiset<std::pair<float, float>> out;
        std::ifstream in(path);
        for (std::string line; std::getline(in, line);)
            if (line.rfind("vt ", 0) == 0) {
                std::istringstream ls(line.substr(3));
                float u = 0, v = 0;
                ls >> u >> v;
                out.insert({u, v});
            }
        return out;
    };
    const Stored s = store(spider);
    const tom::MeshView& m = s.file.mesh(0);
    REQUIRE(m.texcoords);
    // in glTF's convention: the .tom's v is 1 - the file's v, for the corners the file names
    std::multiset<std::pair<float, float>> flipped;
    for (uint32_t i = 0; i < m.vertex_count; ++i) flipped.insert({m.texcoords[2 * i], float(1.0 - double(m.texcoords[2 * i + 1]))});
    const std::multiset<std::pair<float, float>> source = vt_of(spider);
    size_t found = 0;
    for (const auto& uv : flipped) {
        const auto near = std::find_if(source.begin(), source.end(), [&](const std::pair<float, float>& t) {
            return std::fabs(t.first - uv.first) <= 1e-6f && std::fabs(t.second - uv.second) <= 1e-6f;
        });
        found += near != source.end();
    }
    CHECK(found == flipped.size());
    // and back: the exported OBJ's vt are the stored ones flipped back, within float rounding
    const fs::path dir = work_dir("obj");
    tom::ExportPart part;
    part.mesh = &m;
    part.vertex_count = m.vertex_count;
    part.indices.resize(size_t(m.triangle_count) * 3);
    tom::extract(m, m.vertex_count, part.indices.data(), part.indices.size());
    tom::export_meshes((dir / "spider.obj").string(), {part}, s.file.scene());
    const std::multiset<std::pair<float, float>> written = vt_of(dir / "spider.obj");
    REQUIRE(written.size() == flipped.size());
    auto a = written.begin();
    for (auto b = flipped.begin(); b != flipped.end(); ++a, ++b) CHECK((std::fabs(a->first - b->first) <= 1e-6f && std::fabs(a->second - b->second) <= 1e-6f));
}

TEST_CASE("the exporters refuse a material index that names no stored material instead of looping to it", "[fidelity][hostile]") {
    tom::Mesh tri;
    tri.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    tri.indices = {0, 1, 2};
    tom::clean_mesh(tri);
    const tom::TomMesh built = tom::build(tri);
    tom::MeshView view = built.view();
    view.material = 1196310868;  // the fuzzing run's index, in a file that stored no material
    const fs::path dir = work_dir("hostile");
    tom::ExportPart part;
    part.mesh = &view;
    part.vertex_count = view.vertex_count;
    part.indices = {0, 1, 2};
    for (const char* name : {"out.obj", "out.ply"}) {
        INFO(name);
        if (std::string(name) == "out.ply") {
            CHECK_NOTHROW(tom::export_meshes((dir / name).string(), {part}));  // PLY writes the index per face, names nothing
            continue;
        }
        CHECK_THROWS_WITH(tom::export_meshes((dir / name).string(), {part}), Catch::Contains("refers to material 1196310868, but 0 are stored"));
        CHECK(!fs::exists(dir / name));
    }
    CHECK_THROWS_WITH(tom::export_glb((dir / "out.glb").string(), {{&view, {view.vertex_count}}}), Catch::Contains("refers to material 1196310868, but 0 are stored"));
    CHECK(!fs::exists(dir / "out.glb"));
}
