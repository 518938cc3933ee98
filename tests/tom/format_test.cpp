// The .tom format: round trips, and every validation rule of docs/FORMAT.md rejecting a bad
// file with its own message. The byte offsets used to corrupt files are the ones FORMAT.md
// documents, written out here independently of the library's own constants.

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <random>

#include <catch2/catch.hpp>

#include "support.h"
#include "tom/builder/builder.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/builder/writer.h"
#include "tom/format.h"
#include "tom/scene.h"
#include "tom/builder/generate.h"

namespace {

// FORMAT.md, "Header" and "Section table"
constexpr size_t kHeaderBytes = 64, kEntryBytes = 32;
constexpr size_t kVersionMajor = 8, kMeshCount = 24, kSectionCount = 28, kTableOffset = 32, kTableCrc = 40, kHeaderCrc = 44;
constexpr size_t kEntryType = 0, kEntryOffset = 8, kEntryBytesField = 16, kEntryCrc = 24;

uint32_t get32(const std::vector<uint8_t>& b, size_t at) {
    uint32_t v;
    std::memcpy(&v, &b[at], 4);
    return v;
}
uint64_t get64(const std::vector<uint8_t>& b, size_t at) {
    uint64_t v;
    std::memcpy(&v, &b[at], 8);
    return v;
}
void put32(std::vector<uint8_t>& b, size_t at, uint32_t v) { std::memcpy(&b[at], &v, 4); }

constexpr int kLastRule = 23;  // the last numbered validation rule of docs/FORMAT.md

struct Section {
    std::string type;
    size_t entry;
    uint64_t offset, bytes;
};

// the entries that lie inside the buffer and point inside it (a corrupted table may not)
std::vector<Section> sections_of(const std::vector<uint8_t>& b) {
    std::vector<Section> out;
    if (b.size() < kHeaderBytes) return out;
    const uint64_t table = get64(b, kTableOffset);
    for (uint64_t i = 0; i < get32(b, kSectionCount); ++i) {
        const uint64_t e = table + i * kEntryBytes;
        if (table > b.size() || e + kEntryBytes > b.size()) break;
        const uint64_t offset = get64(b, e + kEntryOffset), bytes = get64(b, e + kEntryBytesField);
        if (offset > b.size() || bytes > b.size() - offset) continue;
        out.push_back({std::string(reinterpret_cast<const char*>(&b[e + kEntryType]), 4), size_t(e), offset, bytes});
    }
    return out;
}

const Section& find(const std::vector<Section>& s, const std::string& type) {
    for (const Section& x : s)
        if (x.type == type) return x;
    FAIL("no section " << type);
    return s.front();
}

// recomputes every checksum, so a corruption reaches the structural rules behind them
void fix_checksums(std::vector<uint8_t>& b) {
    const uint64_t table = get64(b, kTableOffset);
    const uint64_t count = get32(b, kSectionCount);
    for (const Section& s : sections_of(b)) put32(b, s.entry + kEntryCrc, tom::crc32(&b[s.offset], s.bytes));
    if (table <= b.size() && count * kEntryBytes <= b.size() - table) put32(b, kTableCrc, tom::crc32(&b[table], count * kEntryBytes));
    put32(b, kHeaderCrc, tom::crc32(b.data(), kHeaderCrc));
}

int rule_of(const std::vector<uint8_t>& b) {
    try {
        tom::File::from_bytes(b.data(), b.size(), "corrupt.tom");
    } catch (const tom::FormatError& e) {
        CHECK(std::string(e.what()).find("corrupt.tom") == 0);  // the message names the file
        return e.rule();
    }
    return 0;
}

std::string message_of(const std::vector<uint8_t>& b) {
    try {
        tom::File::from_bytes(b.data(), b.size(), "corrupt.tom");
    } catch (const tom::FormatError& e) {
        return e.what();
    }
    return "";
}

tom::TomMesh small_mesh() {
    tom::Mesh m = tom::make_sphere(6, 8);
    m.name = "small sphere";
    m.texcoords.assign(size_t(m.vertex_count()) * 2, 0.5f);
    m.colors.assign(size_t(m.vertex_count()) * 4, 1.0f);
    // TEXCOORD_1 and tangents derived from the position, so the test can tell they moved with it
    for (uint32_t v = 0; v < m.vertex_count(); ++v) {
        const float* p = &m.positions[3 * size_t(v)];
        m.texcoords1.insert(m.texcoords1.end(), {p[0], p[1]});
        m.tangents.insert(m.tangents.end(), {-p[1], p[0], 0.0f, p[2] < 0 ? -1.0f : 1.0f});
    }
    tom::clean_mesh(m);
    tom::TomMesh t = tom::build(m);
    t.metadata.push_back({"note", {1, 2, 3, 4, 5}});
    t.metadata.push_back({"empty", {}});
    return t;
}

// a mesh large enough (>= 4096 vertices) for the writer to store coarse corners (COAR)
tom::TomMesh coarse_sphere() {
    tom::Mesh sphere = tom::make_sphere(64, 96, 1.0f, 0.05f);
    tom::clean_mesh(sphere);
    return tom::build(sphere);
}

// two materials (one with textures), three instances of meshes 0 and 1 (or only mesh 0)
tom::Scene small_scene(uint32_t meshes = 2) {
    tom::Scene scene;
    tom::Material plain;
    plain.name = "plain";
    plain.base_color[0] = 0.25f;
    plain.alpha_mode = tom::AlphaMode::mask;
    plain.alpha_cutoff = 0.3f;
    tom::Material textured;
    textured.name = "textured";
    textured.metallic = 0.0f;
    textured.roughness = 0.5f;
    textured.emissive[2] = 1.0f;
    textured.double_sided = true;
    textured.textures.push_back({tom::TextureRole::base_color, 0, "images/albedo.png", "image/png"});
    textured.textures.push_back({tom::TextureRole::normal, 1, "", "image/jpeg"});
    scene.materials = {plain, textured};
    for (uint32_t i = 0; i < 3; ++i) {
        tom::Instance inst;
        inst.mesh = i % meshes;
        inst.node = 10 + i;
        inst.name = i == 1 ? "" : "node " + std::to_string(i);
        inst.transform[12] = float(i);
        inst.transform[0] = 2.0f;
        scene.instances.push_back(inst);
    }
    return scene;
}

} // namespace

TEST_CASE("round trip: every stream, count, bound and metadata entry survives", "[format]") {
    const tom::TomMesh a = small_mesh();
    tom::Mesh big = tom::make_sphere(200, 200);  // > 65536 vertices: 32-bit indices
    tom::clean_mesh(big);
    const tom::TomMesh b = tom::build(big);
    const std::vector<tom::TomMesh> meshes = {a, b};
    const std::vector<uint8_t> bytes = tom::serialize(meshes);
    const tom::File file = tom::File::from_bytes(bytes.data(), bytes.size());
    REQUIRE(file.mesh_count() == 2);
    for (uint32_t i = 0; i < 2; ++i) {
        const tom::TomMesh& t = meshes[i];
        const tom::MeshView& v = file.mesh(i);
        INFO("mesh " << i);
        CHECK(v.name == t.name);
        CHECK(v.index_size == (t.vertex_count() <= 65536 ? 2u : 4u));
        CHECK(v.vertex_count == t.vertex_count());
        CHECK(v.triangle_count == t.triangle_count());
        CHECK(v.min_vertex_count == t.min_vertex_count);
        CHECK(std::memcmp(v.positions, t.positions.data(), t.positions.size() * 4) == 0);
        const float* view_streams[] = {v.normals, v.texcoords, v.colors, v.texcoords1, v.tangents};
        int stream = 0;
        tom::for_each_attribute_stream(t, [&](const std::vector<float>& values, size_t, const char* what) {
            const float* got = view_streams[stream++];
            INFO(what);
            REQUIRE((got != nullptr) == !values.empty());
            if (got) CHECK(std::memcmp(got, values.data(), values.size() * 4) == 0);
        });
        if (i == 0) {  // every stream was sorted with the positions
            REQUIRE(v.texcoords1);
            REQUIRE(v.tangents);
            for (uint32_t k = 0; k < v.vertex_count; ++k) {
                const float* p = v.positions + 3 * size_t(k);
                REQUIRE(v.texcoords1[2 * k] == p[0]);
                REQUIRE(v.texcoords1[2 * k + 1] == p[1]);
                REQUIRE(v.tangents[4 * k] == -p[1]);
                REQUIRE(v.tangents[4 * k + 3] == (p[2] < 0 ? -1.0f : 1.0f));
            }
            // geomorph carries them too: a = 0 is the substitute's, a = 1 the vertex's own
            const uint32_t n = v.vertex_count - 1, sub = v.substitute_at(n);
            const tom::MorphedVertex m0 = tom::geomorph(v, n, 0.0f), m1 = tom::geomorph(v, n, 1.0f);
            CHECK(m0.texcoord1[0] == v.texcoords1[2 * sub]);
            CHECK(m1.texcoord1[1] == v.texcoords1[2 * n + 1]);
            CHECK(m0.tangent[3] == v.tangents[4 * sub + 3]);
            CHECK(m1.tangent[3] == v.tangents[4 * n + 3]);
            CHECK(std::abs(m1.tangent[0] * m1.tangent[0] + m1.tangent[1] * m1.tangent[1] + m1.tangent[2] * m1.tangent[2] - 1.0f) < 1e-5f);
        }
        for (uint32_t k = 0; k < v.vertex_count; ++k) REQUIRE(v.substitute_at(k) == t.substitute[k]);
        for (uint32_t k = 0; k < v.triangle_count * 3; ++k) REQUIRE(v.corner(k) == t.triangles[k]);
        for (int k = 0; k < 3; ++k) CHECK(v.bounds_min[k] == t.bounds_min[k]);
    }
    const tom::MetadataValue note = tom::find_metadata(file.mesh(0), "note");
    REQUIRE(note.found());
    CHECK(std::vector<uint8_t>(note.data, note.data + note.bytes) == std::vector<uint8_t>{1, 2, 3, 4, 5});
    CHECK(tom::find_metadata(file.mesh(0), "empty").found());
    CHECK(!tom::find_metadata(file.mesh(0), "absent").found());
    CHECK(!tom::find_metadata(file.mesh(1), "note").found());

    // through the file system, mapped: the same bytes, and a second serialization is identical
    const std::string path = (std::filesystem::temp_directory_path() / "tom_format_test.tom").string();
    tom::write_file(path, meshes);
    const tom::File mapped = tom::File::open(path);
    CHECK(mapped.file_bytes() == bytes.size());
    CHECK(tom::serialize(meshes) == bytes);
    std::FILE* f = std::fopen(path.c_str(), "rb");
    std::vector<uint8_t> disk(bytes.size());
    REQUIRE(std::fread(disk.data(), 1, disk.size(), f) == disk.size());
    std::fclose(f);
    CHECK(disk == bytes);
    std::filesystem::remove(path);
}

TEST_CASE("an adopted image is validated and used where it lies, a bad one refused", "[format]") {
    std::vector<uint8_t> bytes = tom::serialize({small_mesh()});
    const std::vector<uint8_t> copy = bytes;
    const uint8_t *first = bytes.data(), *last = bytes.data() + bytes.size();
    const tom::File file = tom::File::adopt(std::move(bytes), "adopted.tom");
    const auto* positions = reinterpret_cast<const uint8_t*>(file.mesh(0).positions);
    CHECK(positions >= first);  // a view into the moved bytes: no copy was made
    CHECK(positions < last);
    CHECK(std::memcmp(file.mesh(0).positions, tom::File::from_bytes(copy.data(), copy.size()).mesh(0).positions, 12 * file.mesh(0).vertex_count) == 0);
    std::vector<uint8_t> bad = copy;
    bad[0] ^= 1;
    CHECK_THROWS_WITH(tom::File::adopt(std::move(bad), "bad.tom"), Catch::Contains("bad.tom") && Catch::Contains("magic"));
}

TEST_CASE("with positions, normals and 32-bit indices a mesh takes at most 109% of face-vertex", "[format][memory]") {
    for (const test::NamedMesh& nm : test::real_meshes()) {
        // the paper's case: about two triangles per vertex (the overhead is 4 bytes per vertex,
        // 8.3% at T = 2V, up to 11% where every vertex is split by attributes, V = T)
        if (nm.mesh.triangle_count() < 2000 || nm.mesh.triangle_count() < 1.8 * nm.mesh.vertex_count()) continue;
        tom::TomMesh t = tom::build(nm.mesh);
        t.texcoords.clear();
        t.colors.clear();
        tom::WriteOptions o;
        o.index_size = tom::IndexSize::bits32;
        const size_t bytes = tom::serialize({t}, o).size();
        const size_t face_vertex = size_t(t.vertex_count()) * 24 + size_t(t.triangle_count()) * 12;
        INFO(nm.name << ": " << bytes << " bytes, face-vertex " << face_vertex << " (" << 100.0 * bytes / face_vertex << "%)");
        CHECK(bytes <= face_vertex * 109 / 100);
    }
}

TEST_CASE("CRC-32 is zlib's: the check value, and any split of the bytes gives the same", "[format]") {
    const std::string check = "123456789";
    CHECK(tom::crc32(check.data(), check.size()) == 0xCBF43926u);  // the polynomial's published check value
    std::mt19937 rng(7);
    std::vector<uint8_t> bytes(1000);
    for (uint8_t& b : bytes) b = uint8_t(rng());
    const uint32_t whole = tom::crc32(bytes.data(), bytes.size());
    for (size_t split : {size_t(0), size_t(1), size_t(7), size_t(8), size_t(9), size_t(501), size_t(999)})  // around the 8-byte steps
        CHECK(tom::crc32(bytes.data() + split, bytes.size() - split, tom::crc32(bytes.data(), split)) == whole);
    // one byte changed anywhere changes the value
    for (size_t at : {size_t(0), size_t(3), size_t(8), size_t(999)}) {
        std::vector<uint8_t> changed = bytes;
        changed[at] ^= 0x10;
        CHECK(tom::crc32(changed.data(), changed.size()) != whole);
    }
}

TEST_CASE("rule 1: shorter than the header", "[format][corrupt]") {
    const std::vector<uint8_t> good = tom::serialize({small_mesh()});
    for (size_t n = 0; n < kHeaderBytes; ++n) CHECK(rule_of(std::vector<uint8_t>(good.begin(), good.begin() + n)) == 1);
}

TEST_CASE("rules 2 to 4: bad magic, unsupported version, header checksum", "[format][corrupt]") {
    const std::vector<uint8_t> good = tom::serialize({small_mesh()});
    std::vector<uint8_t> b = good;
    b[1] = 'X';
    CHECK(rule_of(b) == 2);
    CHECK(message_of(b).find("bad magic") != std::string::npos);
    b = good;
    put32(b, kVersionMajor, 2);
    CHECK(rule_of(b) == 3);
    CHECK(message_of(b).find("unsupported version 2.") != std::string::npos);
    b = good;
    put32(b, kMeshCount, 7);  // without fixing the header checksum
    CHECK(rule_of(b) == 4);
}

TEST_CASE("rule 5: truncation at every offset is detected", "[format][corrupt]") {
    const std::vector<uint8_t> good = tom::serialize({small_mesh()});
    for (size_t n = kHeaderBytes; n < good.size(); ++n) {
        const std::vector<uint8_t> cut(good.begin(), good.begin() + n);
        INFO("truncated to " << n << " bytes");
        REQUIRE(rule_of(cut) == 5);
    }
    std::vector<uint8_t> longer = good;
    longer.push_back(0);
    CHECK(rule_of(longer) == 5);
    CHECK(rule_of(good) == 0);
}

TEST_CASE("rules 6 to 8: section table and section placement, content checksums", "[format][corrupt]") {
    const std::vector<uint8_t> good = tom::serialize({small_mesh()});
    std::vector<uint8_t> b = good;
    put32(b, kSectionCount, 100000);
    fix_checksums(b);
    CHECK(rule_of(b) == 6);
    b = good;
    b[get64(b, kTableOffset) + 3] ^= 1;  // table byte, checksum not fixed
    CHECK(rule_of(b) == 6);
    b = good;
    const std::vector<Section> secs = sections_of(good);
    put32(b, secs[1].entry + kEntryOffset, uint32_t(secs[1].offset + 4));  // misaligned
    fix_checksums(b);
    CHECK(rule_of(b) == 7);
    b = good;
    put32(b, secs[1].entry + kEntryBytesField, uint32_t(good.size()));  // past the end
    put32(b, kTableCrc, tom::crc32(&b[get64(b, kTableOffset)], secs.size() * kEntryBytes));
    put32(b, kHeaderCrc, tom::crc32(b.data(), kHeaderCrc));
    CHECK(rule_of(b) == 7);
    for (const Section& s : secs) {
        if (s.bytes == 0) continue;
        b = good;
        b[s.offset + s.bytes / 2] ^= 0x40;
        INFO("section " << s.type);
        CHECK(rule_of(b) == 8);
        CHECK(message_of(b).find("(" + s.type + ")") != std::string::npos);
    }
}

TEST_CASE("rules 9 to 15: structure behind valid checksums", "[format][corrupt]") {
    const std::vector<uint8_t> good = tom::serialize({small_mesh()});
    const std::vector<Section> secs = sections_of(good);
    std::vector<uint8_t> b = good;
    put32(b, find(secs, "SUBS").entry + 4, 9);  // SUBS belongs to mesh 9
    fix_checksums(b);
    CHECK(rule_of(b) == 9);
    b = good;
    std::memcpy(&b[find(secs, "TRIS").entry], "XXXX", 4);  // TRIS renamed: unknown, so TRIS is missing
    fix_checksums(b);
    CHECK(rule_of(b) == 9);
    CHECK(message_of(b).find("required section TRIS is missing") != std::string::npos);
    b = good;
    put32(b, find(secs, "MESH").offset + 12, 3);  // index size 3
    fix_checksums(b);
    CHECK(rule_of(b) == 10);
    b = good;
    put32(b, find(secs, "MESH").offset + 0, get32(good, find(secs, "MESH").offset) + 1);  // one more vertex than streams hold
    fix_checksums(b);
    CHECK(rule_of(b) == 11);
    b = good;
    put32(b, find(secs, "MESH").offset + 8, 1000000);  // min_vertex_count > vertex_count
    fix_checksums(b);
    CHECK(rule_of(b) == 12);
    const uint32_t nv = get32(good, find(secs, "MESH").offset);
    b = good;
    const Section& subs = find(secs, "SUBS");
    uint16_t self = uint16_t(nv - 1);
    std::memcpy(&b[subs.offset + 2 * (nv - 1)], &self, 2);  // substitute[i] == i for a removed vertex
    fix_checksums(b);
    CHECK(rule_of(b) == 13);
    b = good;
    const Section& tris = find(secs, "TRIS");
    uint16_t out_of_range = uint16_t(nv);
    std::memcpy(&b[tris.offset + 2], &out_of_range, 2);
    fix_checksums(b);
    CHECK(rule_of(b) == 14);
    CHECK(message_of(b).find("index out of range") != std::string::npos);
    b = good;
    std::memcpy(&b[tris.offset + 2], &b[tris.offset], 2);  // repeated corner
    fix_checksums(b);
    CHECK(rule_of(b) == 14);
    b = good;
    put32(b, find(secs, "META").offset, 50);  // 50 entries announced
    fix_checksums(b);
    CHECK(rule_of(b) == 15);
}

TEST_CASE("rule 16: groups of copies join removed vertices, a run of bits one group", "[format][corrupt][seams]") {
    // a UV sphere cut along a meridian: its seam copies collapse in pairs, its poles' in fans
    const tom::Mesh seam_sphere = test::generated_meshes()[2].mesh;
    REQUIRE(test::generated_meshes()[2].name.find("seam") != std::string::npos);
    tom::BuildStats stats;
    const tom::TomMesh t = tom::build(seam_sphere, {}, &stats);
    CHECK(stats.seam_vertices > 0);
    REQUIRE(!t.pair_bits.empty());
    const std::vector<uint8_t> good = tom::serialize({t});
    const tom::File f = tom::File::from_bytes(good.data(), good.size());
    REQUIRE(f.mesh(0).pair_bits != nullptr);
    const Section pairs = find(sections_of(good), "PAIR");  // a copy: the list is a temporary
    std::vector<uint8_t> b = good;
    for (size_t k = 0; k < pairs.bytes; ++k) b[pairs.offset + k] = 0xFF;  // every bit: survivors among them
    fix_checksums(b);
    CHECK(rule_of(b) == 16);
    CHECK(message_of(b).find("a group must join removed vertices") != std::string::npos);
    // the removed vertices as one run of bits: one group, valid (extraction then keeps it whole)
    b = good;
    const tom::MeshView& m = f.mesh(0);
    for (uint32_t i = m.min_vertex_count; i + 1 < m.vertex_count; ++i) b[pairs.offset + i / 8] |= uint8_t(1u << (i % 8));
    fix_checksums(b);
    const tom::File one_group = tom::File::from_bytes(b.data(), b.size());
    CHECK(one_group.mesh(0).whole_groups_below(m.vertex_count - 1) == m.min_vertex_count);
    CHECK(one_group.mesh(0).whole_groups_above(m.min_vertex_count + 1) == m.vertex_count);
    b = good;
    b[pairs.offset] |= 1;  // vertex 0 is a survivor
    fix_checksums(b);
    CHECK(rule_of(b) == 16);
}

TEST_CASE("rule 19: coarse corners are the active triangles' corners mapped to their resolution", "[format][corrupt][coarse]") {
    // FORMAT.md, section COAR: u32 resolution, u32 triangle_count, u32 index_size, u32 reserved, corners
    const tom::TomMesh t = coarse_sphere();
    REQUIRE(t.vertex_count() >= 4096);
    const std::vector<uint8_t> good = tom::serialize({t});
    const Section coarse = find(sections_of(good), "COAR");
    const uint32_t resolution = get32(good, coarse.offset), triangles = get32(good, coarse.offset + 4);
    CHECK(resolution == t.vertex_count() / 64);
    CHECK(get32(good, coarse.offset + 8) == 2);
    CHECK(coarse.bytes == 16 + 6 * uint64_t(triangles));
    const tom::File f = tom::File::from_bytes(good.data(), good.size());
    CHECK(f.mesh(0).coarse_triangle_count == triangles);
    CHECK(triangles == tom::active_triangle_count(t.view(), resolution));
    // a file without the section (as a 1.2 writer made it) reads, and extracts the same
    tom::TomMesh tiny = small_mesh();
    CHECK(tiny.vertex_count() < 4096);
    for (const Section& s : sections_of(tom::serialize({tiny}))) CHECK(s.type != "COAR");

    std::vector<uint8_t> b = good;
    const size_t first = coarse.offset + 16;
    uint16_t corner;
    std::memcpy(&corner, &b[first], 2);
    corner = uint16_t((corner + 1) % resolution);  // still in range, but not the mapped corner
    std::memcpy(&b[first], &corner, 2);
    fix_checksums(b);
    CHECK(rule_of(b) == 19);
    CHECK(message_of(b).find("mapped to resolution") != std::string::npos);
    b = good;
    put32(b, coarse.offset, t.vertex_count() + 1);  // resolution past the vertex count
    fix_checksums(b);
    CHECK(rule_of(b) == 19);
    b = good;
    put32(b, coarse.offset + 8, 4);  // 32-bit corners for a 16-bit resolution
    fix_checksums(b);
    CHECK(rule_of(b) == 19);
    b = good;
    put32(b, coarse.offset + 4, triangles + 1);  // more corners than the section holds
    fix_checksums(b);
    CHECK(rule_of(b) == 19);
    CHECK(message_of(b).find("bytes where the counts require") != std::string::npos);
    b = good;
    put32(b, coarse.offset, resolution + 1);  // corners mapped to another resolution
    fix_checksums(b);
    CHECK(rule_of(b) == 19);
}

// two parts over one sphere's triangles (materials 0 and 1 of small_scene()), big enough for COAR
tom::TomMesh two_part_mesh() {
    tom::Mesh sphere = tom::make_sphere(64, 96, 1.0f, 0.05f);
    tom::clean_mesh(sphere);
    const uint32_t half = sphere.triangle_count() / 2;
    sphere.parts = {{0, half, 0, 1}, {half, sphere.triangle_count() - half, 1, 1}};
    return tom::build(sphere);
}

TEST_CASE("rule 20: parts tile the triangles, name streams the mesh has, and set attribute bit 5", "[format][corrupt][parts]") {
    const tom::TomMesh mesh = two_part_mesh();
    REQUIRE(mesh.parts.size() == 2);
    const std::vector<uint8_t> good = tom::serialize({mesh}, small_scene(1));
    const std::vector<Section> secs = sections_of(good);
    const tom::File f = tom::File::from_bytes(good.data(), good.size());
    CHECK(tom::part_count(f.mesh(0)) == 2);
    CHECK(f.mesh(0).coarse_corners == nullptr);  // COAR holds one prefix: never with parts
    const size_t part = find(secs, "PART").offset, mesh_header = find(secs, "MESH").offset;
    CHECK((get32(good, mesh_header + 20) & 32u) != 0);  // attribute bit 5: a 1.3 reader rejects the mesh (rule 10) rather than misread it
    auto corrupt = [&](size_t at, uint32_t value) {
        std::vector<uint8_t> b = good;
        put32(b, at, value);
        fix_checksums(b);
        return b;
    };
    // records at part + 16: first_triangle, triangle_count, material, attributes
    const uint32_t first_count = get32(good, part + 16 + 4);
    CHECK(rule_of(corrupt(part, 1)) == 20);                      // one part is no PART
    CHECK(rule_of(corrupt(part + 16 + 16, first_count + 1)) == 20);  // part 1 does not start where part 0 ends
    CHECK(message_of(corrupt(part + 16 + 16, first_count + 1)).find("not where the previous part ends") != std::string::npos);
    CHECK(rule_of(corrupt(part + 16 + 4, 0)) == 20);             // an empty part
    CHECK(rule_of(corrupt(part + 16 + 16 + 4, get32(good, part + 16 + 16 + 4) - 1)) == 20);  // the parts cover too little
    CHECK(rule_of(corrupt(part + 16 + 16 + 4, get32(good, part + 16 + 16 + 4) + 1)) == 20);  // and too much
    CHECK(rule_of(corrupt(part + 16 + 12, 2)) == 20);            // TEX0, which the mesh has not
    CHECK(rule_of(corrupt(part + 16 + 8, 7)) == 17);             // material 7 of 2
    CHECK(rule_of(corrupt(mesh_header + 20, get32(good, mesh_header + 20) & ~32u)) == 10);  // PART without bit 5
    // and the parts extract as written
    std::vector<uint32_t> buffer(size_t(f.mesh(0).triangle_count) * 3);
    std::vector<tom::PartDraw> draws(2);
    const tom::Extracted e = tom::extract_parts(f.mesh(0), tom::vertex_count_for_fraction(f.mesh(0), 0.1), buffer.data(), buffer.size(), draws.data());
    CHECK(draws[0].index_count + draws[1].index_count == 3 * e.triangle_count);
    CHECK(draws[1].material == 1);
}

TEST_CASE("version 1.3 files: read by this reader as meshes of one part", "[format][parts]") {
    // a file without parts differs from a 1.3 file only in its minor version
    std::vector<uint8_t> b = tom::serialize({coarse_sphere()});
    put32(b, 12, 3);
    fix_checksums(b);
    const tom::File f = tom::File::from_bytes(b.data(), b.size(), "old.tom");
    CHECK(f.version_minor() == 3);
    const tom::MeshView& m = f.mesh(0);
    REQUIRE(tom::part_count(m) == 1);
    CHECK(tom::part_at(m, 0).triangle_count == m.triangle_count);
    CHECK(tom::part_at(m, 0).material == m.material);
    std::vector<uint32_t> a(size_t(m.triangle_count) * 3), c(a.size());
    tom::PartDraw draw;
    const uint32_t n = tom::vertex_count_for_fraction(m, 0.05);
    const tom::Extracted x = tom::extract(m, n, a.data(), a.size());
    const tom::Extracted y = tom::extract_parts(m, n, c.data(), c.size(), &draw);
    CHECK(x.triangle_count == y.triangle_count);
    CHECK(draw.first_index == 0);
    CHECK(draw.index_count == 3 * x.triangle_count);
    CHECK(a == c);
}

TEST_CASE("provenance (PROV, since 1.5): stored as given, file-level, once (rule 9), skipped by 1.4 readers", "[format][provenance]") {
    tom::WriteOptions with;
    with.provenance = R"({"tool":"test","input":{"bytes":3,"digest":"xxh3-128:00"}})";
    const std::vector<uint8_t> plain = tom::serialize({coarse_sphere()});
    const std::vector<uint8_t> b = tom::serialize({coarse_sphere()}, with);
    const tom::File f = tom::File::from_bytes(b.data(), b.size(), "prov.tom");
    CHECK(f.provenance() == with.provenance);
    CHECK(f.version_minor() == tom::format_version_minor);
    CHECK(tom::File::from_bytes(plain.data(), plain.size(), "plain.tom").provenance().empty());
    // the same provenance gives the same bytes; the meshes' sections are those of a file without it
    CHECK(tom::serialize({coarse_sphere()}, with) == b);
    const tom::File g = tom::File::from_bytes(plain.data(), plain.size(), "plain.tom");
    REQUIRE(f.mesh(0).triangle_count == g.mesh(0).triangle_count);
    CHECK(std::memcmp(f.mesh(0).triangles, g.mesh(0).triangles, size_t(g.mesh(0).triangle_count) * 3 * g.mesh(0).index_size) == 0);
    const std::vector<Section> secs = sections_of(b);
    const Section& prov = find(secs, "PROV");
    CHECK(get32(b, prov.entry + 4) == 0xFFFFFFFFu);
    std::vector<uint8_t> c = b;
    put32(c, prov.entry + 4, 0);  // claimed by mesh 0
    fix_checksums(c);
    CHECK(rule_of(c) == 9);
    // a reader that does not know PROV (1.4) skips it: renamed to an unknown type, the file reads
    c = b;
    std::memcpy(&c[prov.entry], "ZZZZ", 4);
    fix_checksums(c);
    const tom::File old = tom::File::from_bytes(c.data(), c.size(), "renamed.tom");
    CHECK(old.provenance().empty());
    CHECK(old.mesh(0).triangle_count == f.mesh(0).triangle_count);
    // twice: the second MESH-less copy of PROV is a rule 9 error
    c = tom::serialize({small_mesh()}, with);  // (a mesh with metadata)
    const size_t meta = find(sections_of(c), "META").entry;
    std::memcpy(&c[meta], "PROV", 4);
    put32(c, meta + 4, 0xFFFFFFFFu);
    fix_checksums(c);
    CHECK(rule_of(c) == 9);
    CHECK(message_of(c).find("twice") != std::string::npos);
}

TEST_CASE("scenes: materials with texture references and instances survive the round trip (rules 17 and 18)", "[format][scene]") {
    tom::TomMesh a = small_mesh(), b = small_mesh();
    a.material = 1;
    b.material = -1;
    const tom::Scene scene = small_scene();
    const std::vector<uint8_t> good = tom::serialize({a, b}, scene);
    CHECK(tom::serialize({a, b}, scene) == good);  // deterministic
    const tom::File f = tom::File::from_bytes(good.data(), good.size());
    const tom::Scene& got = f.scene();
    REQUIRE(got.materials.size() == 2);
    for (size_t i = 0; i < 2; ++i) {
        const tom::Material &x = scene.materials[i], &y = got.materials[i];
        CHECK(y.name == x.name);
        CHECK(std::equal(x.base_color, x.base_color + 4, y.base_color));
        CHECK(y.metallic == x.metallic);
        CHECK(y.roughness == x.roughness);
        CHECK(std::equal(x.emissive, x.emissive + 3, y.emissive));
        CHECK(y.alpha_mode == x.alpha_mode);
        CHECK(y.alpha_cutoff == x.alpha_cutoff);
        CHECK(y.double_sided == x.double_sided);
        REQUIRE(y.textures.size() == x.textures.size());
        for (size_t t = 0; t < x.textures.size(); ++t) {
            CHECK(y.textures[t].role == x.textures[t].role);
            CHECK(y.textures[t].texcoord == x.textures[t].texcoord);
            CHECK(y.textures[t].uri == x.textures[t].uri);
            CHECK(y.textures[t].mime_type == x.textures[t].mime_type);
        }
    }
    REQUIRE(got.instances.size() == 3);
    for (size_t i = 0; i < 3; ++i) {
        CHECK(got.instances[i].mesh == scene.instances[i].mesh);
        CHECK(got.instances[i].node == scene.instances[i].node);
        CHECK(got.instances[i].name == scene.instances[i].name);
        CHECK(std::equal(scene.instances[i].transform, scene.instances[i].transform + 16, got.instances[i].transform));
    }
    CHECK(f.mesh(0).material == 1);
    // without a scene: no instance, so the draw list is every mesh once; the materials the
    // meshes name are stored as defaults (rule 17: every index names a stored material)
    const std::vector<uint8_t> bare = tom::serialize({a, b});
    const tom::File g = tom::File::from_bytes(bare.data(), bare.size());
    REQUIRE(g.scene().materials.size() == 2);
    CHECK((g.scene().materials[1].name == "material 1" && g.scene().materials[1].base_color[0] == 1.0f && g.scene().materials[1].textures.empty()));
    tom::TomMesh far = a;
    far.material = 65536;
    CHECK_THROWS_WITH(tom::serialize({far}), Catch::Contains("names material 65536 but the scene stores none"));
    const std::vector<tom::Instance> all = tom::draw_list(g.scene(), g.mesh_count());
    REQUIRE(all.size() == 2);
    CHECK((all[0].mesh == 0 && all[1].mesh == 1 && all[1].transform[0] == 1.0f && all[1].transform[12] == 0.0f));
    // an instance of a mesh the file does not have cannot be written
    tom::Scene bad = scene;
    bad.instances[0].mesh = 2;
    CHECK_THROWS_AS(tom::serialize({a, b}, bad), tom::ArgumentError);

    const std::vector<Section> secs = sections_of(good);
    const Section &matl = find(secs, "MATL"), &inst = find(secs, "INST");
    std::vector<uint8_t> c = good;
    put32(c, matl.entry + 4, 0);  // a file-level section claimed by mesh 0
    fix_checksums(c);
    CHECK(rule_of(c) == 9);
    c = good;
    put32(c, matl.offset, 1000);  // 1000 materials announced
    fix_checksums(c);
    CHECK(rule_of(c) == 17);
    CHECK(message_of(c).find("runs past the end of the section") != std::string::npos);
    c = good;
    put32(c, matl.offset + 16 + 36, 7);  // alpha mode 7
    fix_checksums(c);
    CHECK(rule_of(c) == 17);
    c = good;
    put32(c, matl.offset + 16 + 48, uint32_t(matl.bytes) + 8);  // name outside the section
    fix_checksums(c);
    CHECK(rule_of(c) == 17);
    CHECK(message_of(c).find("material 0 name") != std::string::npos);
    c = good;
    put32(c, matl.offset, 1);  // one material left, but mesh 0 uses material 1
    put32(c, matl.offset + 4, uint32_t(scene.materials[0].textures.size()));
    fix_checksums(c);
    CHECK(rule_of(c) == 17);
    CHECK(message_of(c).find("material 1 is not among the 1 stored") != std::string::npos);
    c = good;
    put32(c, inst.offset + 16, 5);  // instance 0 of mesh 5
    fix_checksums(c);
    CHECK(rule_of(c) == 18);
    CHECK(message_of(c).find("instance 0 mesh") != std::string::npos);
    c = good;
    put32(c, inst.offset + 16 + 16, 0x7F800000u);  // an infinite transform entry
    fix_checksums(c);
    CHECK(rule_of(c) == 18);
}

TEST_CASE("rule 17 without MATL: a material index must name a stored material, as the fuzzing run's file did not", "[format][corrupt][scene]") {
    tom::TomMesh m = small_mesh();
    const std::vector<uint8_t> good = tom::serialize({m});  // material -1, no MATL
    REQUIRE(rule_of(good) == 0);
    std::vector<uint8_t> c = good;
    put32(c, find(sections_of(c), "MESH").offset + 16, 1196310868u);
    fix_checksums(c);
    CHECK(rule_of(c) == 17);
    CHECK(message_of(c).find("mesh 0 material: material 1196310868 is not among the 0 stored") != std::string::npos);
    put32(c, find(sections_of(c), "MESH").offset + 16, uint32_t(-7));
    fix_checksums(c);
    CHECK(rule_of(c) == 17);
    CHECK(message_of(c).find("material -7 is neither -1 (none) nor a stored material") != std::string::npos);
}

TEST_CASE("images (IMAG, since 1.6): stored byte for byte, viewed in place, and rule 21", "[format][corrupt][scene]") {
    tom::TomMesh a = small_mesh();
    a.material = 1;
    tom::Scene scene = small_scene(1);
    // two images: the textured material's normal texture shows the second; its base colour stays a file
    scene.images.push_back(tom::make_image("first", "image/png", {0x89, 'P', 'N', 'G', 1, 2, 3}));
    scene.images.push_back(tom::make_image("", "image/jpeg", std::vector<uint8_t>(1000, 0xAB)));
    scene.materials[1].textures[1].image = 1;
    const std::vector<uint8_t> good = tom::serialize({a}, scene);
    const tom::File f = tom::File::borrow(good.data(), good.size(), "images.tom");
    REQUIRE(f.scene().images.size() == 2);
    for (size_t i = 0; i < 2; ++i) {
        const tom::Image &got = f.scene().images[i], &want = scene.images[i];
        CHECK(got.name == want.name);
        CHECK(got.mime_type == want.mime_type);
        REQUIRE(got.bytes == want.bytes);
        CHECK(std::memcmp(got.data, want.data, want.bytes) == 0);
        CHECK((got.data >= good.data() && got.data + got.bytes <= good.data() + good.size()));  // in place
        CHECK((got.data - good.data()) % 16 == 0);  // each image at a multiple of 16
        CHECK(got.owner == nullptr);
    }
    CHECK(f.scene().materials[1].textures[0].image == -1);
    CHECK(f.scene().materials[1].textures[0].uri == "images/albedo.png");
    CHECK(f.scene().materials[1].textures[1].image == 1);
    CHECK(tom::serialize({a}, scene) == good);  // deterministic
    // a texture showing an image the scene does not hold cannot be written
    tom::Scene bad = scene;
    bad.materials[1].textures[1].image = 2;
    CHECK_THROWS_WITH(tom::serialize({a}, bad), Catch::Contains("shows image 2 of 2"));

    const std::vector<Section> secs = sections_of(good);
    const Section& imag = find(secs, "IMAG");
    const size_t records = imag.offset + 16 + 4 * 2;  // two texture records
    std::vector<uint8_t> c = good;
    put32(c, imag.offset + 4, 3);  // three textures announced, MATL stores two
    fix_checksums(c);
    CHECK(rule_of(c) == 21);
    CHECK(message_of(c).find("IMAG texture_count: 3 where MATL stores 2 textures") != std::string::npos);
    c = good;
    put32(c, imag.offset, 1000000);  // a million images announced
    fix_checksums(c);
    CHECK(rule_of(c) == 21);
    CHECK(message_of(c).find("runs past the end of the section") != std::string::npos);
    c = good;
    put32(c, imag.offset + 16 + 4, 2);  // texture 1 shows image 2 of 2
    fix_checksums(c);
    CHECK(rule_of(c) == 21);
    CHECK(message_of(c).find("image 2 is not among the 2 stored") != std::string::npos);
    c = good;
    put32(c, records + 32 + 8, uint32_t(imag.bytes));  // image 1's bytes run past the section
    fix_checksums(c);
    CHECK(rule_of(c) == 21);
    CHECK(message_of(c).find("image 1 data") != std::string::npos);
    c = good;
    put32(c, records, 8);  // image 0's bytes inside the records
    fix_checksums(c);
    CHECK(rule_of(c) == 21);
    c = good;
    put32(c, records + 16 + 4, 0);  // an empty MIME type
    fix_checksums(c);
    CHECK(rule_of(c) == 21);
    CHECK(message_of(c).find("image 0 mime_type: is empty") != std::string::npos);
    c = good;
    put32(c, imag.entry + 4, 0);  // a file-level section claimed by mesh 0
    fix_checksums(c);
    CHECK(rule_of(c) == 9);
}

TEST_CASE("carried streams (XATT, since 1.6): each vertex's element in resolution order, and rule 22", "[format][corrupt]") {
    tom::Mesh m = tom::make_sphere(6, 8);
    tom::VertexStream joints{"JOINTS_0", 5123, 4, false, {}}, weights{"WEIGHTS_0", 5126, 4, false, {}}, ids{"_ID", 5121, 1, false, {}};
    for (uint32_t v = 0; v < m.vertex_count(); ++v) {
        const uint16_t j[4] = {uint16_t(v % 3), uint16_t(v % 5), 0, 0};
        const float w[4] = {0.75f, 0.25f, 0, 0};
        joints.data.insert(joints.data.end(), reinterpret_cast<const uint8_t*>(j), reinterpret_cast<const uint8_t*>(j) + 8);
        weights.data.insert(weights.data.end(), reinterpret_cast<const uint8_t*>(w), reinterpret_cast<const uint8_t*>(w) + 16);
        ids.data.push_back(uint8_t(v));
    }
    m.extra_streams = {joints, weights, ids};
    tom::clean_mesh(m);
    const tom::TomMesh t = tom::build(m);
    const std::vector<uint8_t> good = tom::serialize({t});
    const tom::File f = tom::File::from_bytes(good.data(), good.size(), "xatt.tom");
    const tom::MeshView& v = f.mesh(0);
    REQUIRE(v.extra_stream_count == 3);
    CHECK(v.extra_streams[2].name == "_ID");
    for (uint32_t i = 0; i < v.vertex_count; ++i) CHECK(v.extra_streams[2].data[i] == uint8_t(t.original_index[i]));  // the vertex's own id
    // original_mesh gives the input's streams back exactly
    CHECK(tom::original_mesh(t).extra_streams[1].data == m.extra_streams[1].data);

    const std::vector<Section> secs = sections_of(good);
    const Section& x = find(secs, "XATT");
    std::vector<uint8_t> c = good;
    put32(c, x.offset + 16 + 8, 5124);  // not a glTF component type
    fix_checksums(c);
    CHECK(rule_of(c) == 22);
    CHECK(message_of(c).find("stream 0 component_type: 5124 is not a glTF component type") != std::string::npos);
    c = good;
    put32(c, x.offset + 16 + 12, 5);  // five components
    fix_checksums(c);
    CHECK(rule_of(c) == 22);
    c = good;
    put32(c, x.offset + 16 + 32, 8);  // 8 bytes for every vertex's joints
    fix_checksums(c);
    CHECK(rule_of(c) == 22);
    CHECK(message_of(c).find("8 where") != std::string::npos);
    c = good;
    put32(c, x.offset + 16 + 40 + 24, uint32_t(x.bytes) - 4);  // the weights run past the section
    fix_checksums(c);
    CHECK(rule_of(c) == 22);
    c = good;
    const uint64_t weights_at = get64(c, x.offset + 16 + 40 + 24);
    put32(c, x.offset + weights_at, 0x7FC00000u);  // a NaN weight
    fix_checksums(c);
    CHECK(rule_of(c) == 22);
    CHECK(message_of(c).find("is not finite") != std::string::npos);
    c = good;
    put32(c, x.offset + weights_at + 4, 0xBE800000u);  // a weight of -0.25
    fix_checksums(c);
    CHECK(rule_of(c) == 22);
    CHECK(message_of(c).find("stream 1 value 1: is a negative skin weight") != std::string::npos);
    c = good;
    std::memcpy(&c[x.offset + 16 + 80], &c[x.offset + 16], 8);  // stream 2 named as stream 0
    fix_checksums(c);
    CHECK(rule_of(c) == 22);
    CHECK(message_of(c).find("stream 2 name: 'JOINTS_0' is also stream 0") != std::string::npos);
    // a stream of the wrong size cannot be written
    tom::TomMesh bad = t;
    bad.extra_streams[0].data.pop_back();
    CHECK_THROWS_WITH(tom::serialize({bad}), Catch::Contains("carried stream 'JOINTS_0' has"));
}

TEST_CASE("a glTF source's scene (GLTF, since 1.6): kept as given, its data in place, and rule 23", "[format][corrupt][scene]") {
    tom::Scene scene;
    const std::string json = R"({"nodes":[{"mesh":0,"skin":0}],"skins":[{"joints":[0],"inverseBindMatrices":0}],"accessors":[],"bufferViews":[]})";
    scene.gltf.json = json;
    const std::vector<uint8_t> blob(64, 0x3F);
    scene.gltf.data = blob.data();
    scene.gltf.bytes = blob.size();
    const std::vector<uint8_t> good = tom::serialize({small_mesh()}, scene);
    const tom::File f = tom::File::borrow(good.data(), good.size(), "gltf.tom");
    CHECK(f.scene().gltf.json == json);
    REQUIRE(f.scene().gltf.bytes == blob.size());
    CHECK(std::memcmp(f.scene().gltf.data, blob.data(), blob.size()) == 0);
    CHECK((f.scene().gltf.data >= good.data() && f.scene().gltf.data + blob.size() <= good.data() + good.size()));
    const std::vector<Section> secs = sections_of(good);
    const Section& g = find(secs, "GLTF");
    std::vector<uint8_t> c = good;
    put32(c, g.offset + 8, 65);  // one byte of data more than the section holds
    fix_checksums(c);
    CHECK(rule_of(c) == 23);
    CHECK(message_of(c).find("GLTF data_bytes") != std::string::npos);
    c = good;
    put32(c, g.offset, 0);  // no JSON
    fix_checksums(c);
    CHECK(rule_of(c) == 23);
    c = good;
    put32(c, g.offset, 0xFFFFFFF0u);  // JSON past the section
    fix_checksums(c);
    CHECK(rule_of(c) == 23);
    c = good;
    put32(c, g.entry + 4, 0);  // a file-level section claimed by mesh 0
    fix_checksums(c);
    CHECK(rule_of(c) == 9);
}

TEST_CASE("random corruption never crashes and never yields an out-of-range index", "[format][fuzz]") {
    tom::TomMesh with_material = small_mesh();
    with_material.material = 0;
    const std::vector<uint8_t> good = tom::serialize({with_material}, small_scene(1));
    std::mt19937 rng(1234);
    int rejected = 0, accepted = 0;
    std::map<int, int> rules;  // rejections by rule
    for (int trial = 0; trial < 4000; ++trial) {
        std::vector<uint8_t> b = good;
        const int flips = 1 + int(rng() % 4);
        for (int k = 0; k < flips; ++k) b[rng() % b.size()] ^= uint8_t(1u << (rng() % 8));
        if (trial % 2) fix_checksums(b);  // half reach the structural rules
        try {
            const tom::File f = tom::File::from_bytes(b.data(), b.size(), "fuzz.tom");
            ++accepted;
            for (uint32_t i = 0; i < f.mesh_count(); ++i) {
                const tom::MeshView& m = f.mesh(i);
                std::vector<uint32_t> out(size_t(m.triangle_count) * 3);
                for (uint32_t n : {0u, m.vertex_count / 2, m.vertex_count}) {
                    const tom::Extracted r = tom::extract(m, n, out.data(), out.size());
                    for (size_t c = 0; c < size_t(r.triangle_count) * 3; ++c) REQUIRE(out[c] < r.vertex_count);
                }
            }
        } catch (const tom::FormatError& e) {
            ++rejected;
            // every rejection names the file, a numbered rule of FORMAT.md and a place inside the file
            REQUIRE(std::string(e.what()).find("fuzz.tom") != std::string::npos);
            REQUIRE(e.rule() >= 1);
            REQUIRE(e.rule() <= kLastRule);
            REQUIRE(e.offset() <= b.size());
            ++rules[e.rule()];
        }
    }
    CHECK(rejected > 0);
    CHECK(accepted > 0);  // flips in the streams' values leave valid files, whose levels were extracted above
    CHECK(rules[4] + rules[6] + rules[8] > 0);  // the checksums caught the flips left unfixed
    size_t structural = 0;
    for (const auto& [rule, count] : rules) structural += rule != 4 && rule != 6 && rule != 8 && count > 0;
    CHECK(structural >= 4);  // the fixed checksums let the flips reach the structural rules
}

TEST_CASE("random corruption of the coarse corners and the order never yields an out-of-range index", "[format][fuzz][coarse]") {
    const std::vector<uint8_t> good = tom::serialize({coarse_sphere()});
    const std::vector<Section> sections = sections_of(good);
    const Section coarse = find(sections, "COAR"), subs = find(sections, "SUBS"), tris = find(sections, "TRIS");
    std::mt19937 rng(4321);
    int rejected = 0, accepted = 0;
    for (int trial = 0; trial < 600; ++trial) {
        std::vector<uint8_t> b = good;
        // bits of COAR (header and corners) mostly, sometimes of SUBS or TRIS, behind valid checksums
        const Section& target = trial % 4 == 0 ? subs : trial % 4 == 1 ? tris : coarse;
        for (int k = 0, flips = 1 + int(rng() % 3); k < flips; ++k) b[target.offset + rng() % target.bytes] ^= uint8_t(1u << (rng() % 8));
        fix_checksums(b);
        try {
            const tom::File f = tom::File::from_bytes(b.data(), b.size(), "fuzz.tom");
            ++accepted;
            const tom::MeshView& m = f.mesh(0);
            std::vector<uint32_t> out(size_t(m.triangle_count) * 3);
            for (uint32_t n : {m.min_vertex_count, m.coarse_resolution / 2, m.coarse_resolution, m.coarse_resolution + 1}) {
                const tom::Extracted r = tom::extract(m, n, out.data(), out.size());
                for (size_t c = 0; c < size_t(r.triangle_count) * 3; ++c) REQUIRE(out[c] < r.vertex_count);
            }
        } catch (const tom::FormatError& e) {
            ++rejected;
            REQUIRE((e.rule() == 13 || e.rule() == 14 || e.rule() == 19));  // the order's and the coarse corners' rules
        }
    }
    CHECK(rejected > 300);  // a flipped corner or count is caught by rule 19 (or 13, 14)
    CHECK(accepted > 0);    // flips that keep the order valid (a survivor's corner to another survivor) pass, and extract
}

TEST_CASE("a missing file is an I/O error naming it", "[format]") {
    try {
        tom::File::open("/nonexistent/dir/x.tom");
        FAIL("no error");
    } catch (const tom::IoError& e) {
        CHECK(std::string(e.what()).find("/nonexistent/dir/x.tom") != std::string::npos);
    }
}
