// Mapping and validation of .tom files. Every rule below is numbered as in docs/FORMAT.md;
// nothing is dereferenced before the rule that makes it safe has passed.

#include <algorithm>
#include <cassert>
#include <cstring>
#include <string>
#include <tuple>

#include "coarse.h"
#include "format_layout.h"
#include "platform.h"
#include "scene_codec.h"
#include "tom/errors.h"
#include "tom/format.h"
#include "tom/stream.h"

namespace tom {

using namespace layout;

FormatError::FormatError(std::string path, uint64_t offset, std::string field, int rule, const std::string& detail)
    : Error(path + ": byte " + std::to_string(offset) + ", " + field + ": " + detail + " (FORMAT.md rule " + std::to_string(rule) + ")"),
      path_(std::move(path)),
      offset_(offset),
      field_(std::move(field)),
      rule_(rule) {}

namespace {

struct MeshSections {
    const SectionInfo* mesh = nullptr;
    const SectionInfo* positions = nullptr;
    const SectionInfo* streams[attribute_stream_count] = {};  // as layout::attribute_streams
    const SectionInfo* substitute = nullptr;
    const SectionInfo* triangles = nullptr;
    const SectionInfo* metadata = nullptr;
    const SectionInfo* pairs = nullptr;
    const SectionInfo* coarse = nullptr;
    const SectionInfo* parts = nullptr;
    const SectionInfo* extra = nullptr;
};

// The section table as rules 6 to 9 read it: where the table is, and each section by its role.
struct SectionMap {
    uint32_t mesh_count = 0;
    uint64_t table_offset = 0, table_bytes = 0;
    std::vector<MeshSections> per_mesh;
    const SectionInfo* materials = nullptr;
    const SectionInfo* instances = nullptr;
    const SectionInfo* provenance = nullptr;
    const SectionInfo* images = nullptr;
    const SectionInfo* gltf = nullptr;
};

} // namespace

struct File::Impl {
    std::string path;
    // a mapping, an owned copy, or the caller's bytes (borrow)
    detail::MappedFile mapping;
    std::vector<uint8_t> owned;
    const uint8_t* data = nullptr;
    uint64_t size = 0;
    uint32_t version_major = 0, version_minor = 0;
    std::vector<MeshView> meshes;
    std::vector<SectionInfo> sections;
    Scene scene;
    std::string_view provenance;  // into data
    std::vector<std::vector<VertexStreamView>> extra_streams;  // per mesh (section XATT): MeshView::extra_streams points here

    [[noreturn]] void fail(uint64_t offset, const std::string& field, int rule, const std::string& detail) const {
        throw FormatError(path, offset, field, rule, detail);
    }

    // validate() as its steps, each the rules it names (docs/FORMAT.md)
    void validate(const OpenOptions& options);
    SectionMap validate_header();                                        // rules 1 to 6
    void read_sections(SectionMap& map, const OpenOptions& options);     // rules 7 to 9
    void validate_mesh(uint32_t mi, const MeshSections& ms, uint64_t table_offset);  // rules 9 to 16, 20, 22
    void validate_scene(const SectionMap& map);                          // rules 17, 18, 21, 23
    void validate_coarse(uint32_t mi, const SectionInfo& sec);           // rule 19
    // rule 17: -1 (none) or one of the `stored` materials
    void check_material(int32_t material, uint64_t offset, const std::string& field, size_t stored) const {
        if (material == -1 || (material >= 0 && size_t(material) < stored)) return;
        fail(offset, field, 17,
             material < 0 ? "material " + std::to_string(material) + " is neither -1 (none) nor a stored material"
                          : "material " + std::to_string(material) + " is not among the " + std::to_string(stored) + " stored");
    }
    void validate_parts(const SectionInfo& sec, uint32_t attributes, MeshView& v, const std::string& mesh_field) const;
};

// rule 20: the parts tile the triangles in order (since 1.8 a part may be empty: a stream's prefix
// holds none of its triangles yet); two or more of them;
// each part's streams are some of the mesh's
void File::Impl::validate_parts(const SectionInfo& sec, uint32_t attributes, MeshView& v, const std::string& mesh_field) const {
    const std::string field = mesh_field + " PART";
    const uint8_t* p = data + sec.offset;
    if (sec.bytes < parts_header_bytes) fail(sec.offset, field, 20, "shorter than its 16-byte header");
    const uint32_t count = load_u32(p);
    if (count < 2) fail(sec.offset, field + " part_count", 20, std::to_string(count) + " parts: a mesh of one part has no PART section");
    if (sec.bytes != parts_header_bytes + uint64_t(count) * part_record_bytes)
        fail(sec.offset, field, 20, std::to_string(sec.bytes) + " bytes where " + std::to_string(count) + " parts require " + std::to_string(parts_header_bytes + uint64_t(count) * part_record_bytes));
    uint64_t next = 0;
    for (uint32_t k = 0; k < count; ++k) {
        const uint8_t* r = p + parts_header_bytes + uint64_t(k) * part_record_bytes;
        const uint64_t at = sec.offset + parts_header_bytes + uint64_t(k) * part_record_bytes;
        const std::string part = field + " part " + std::to_string(k);
        const uint32_t first = load_u32(r), triangles = load_u32(r + 4), part_attributes = load_u32(r + 12);
        if (first != next) fail(at, part + " first_triangle", 20, "starts at triangle " + std::to_string(first) + ", not where the previous part ends (" + std::to_string(next) + ")");
        next += triangles;
        if (next > v.triangle_count) fail(at + 4, part + " triangle_count", 20, "ends at triangle " + std::to_string(next) + ", past the mesh's " + std::to_string(v.triangle_count));
        if (part_attributes & ~(attributes & stream_attributes)) fail(at + 12, part + " attributes", 20, "names a stream the mesh does not have");
    }
    if (next != v.triangle_count) fail(sec.offset, field, 20, "the parts cover " + std::to_string(next) + " of the mesh's " + std::to_string(v.triangle_count) + " triangles");
    v.parts = reinterpret_cast<const Part*>(p + parts_header_bytes);
    v.part_count = count;
}


void File::Impl::validate(const OpenOptions& options) {
    SectionMap map = validate_header();
    read_sections(map, options);
    meshes.resize(map.mesh_count);
    extra_streams.resize(map.mesh_count);
    for (uint32_t mi = 0; mi < map.mesh_count; ++mi) validate_mesh(mi, map.per_mesh[mi], map.table_offset);
    validate_scene(map);
    for (uint32_t mi = 0; mi < map.mesh_count; ++mi)
        if (map.per_mesh[mi].coarse) validate_coarse(mi, *map.per_mesh[mi].coarse);
}

SectionMap File::Impl::validate_header() {
    // rule 1: the header fits
    if (size < header_bytes) fail(0, "header", 1, "file is " + std::to_string(size) + " bytes, shorter than the 64-byte header");
    // rule 2: magic
    if (std::memcmp(data, magic, 8) != 0)
        fail(0, "magic", 2,
             is_stream(data, size)
                 ? "a streamed .tom (tombuild --stream): decode it with tom::open_any or tom::StreamDecoder (C: tom_stream_create; Python: tom.open)"
                 : "not a .tom file (bad magic)");
    // rule 3: version
    version_major = load_u32(data + h_version_major);
    version_minor = load_u32(data + h_version_minor);
    if (version_major != format_version_major)
        fail(h_version_major, "version_major", 3,
             "unsupported version " + std::to_string(version_major) + "." + std::to_string(version_minor) + " (this reader reads " +
                 std::to_string(format_version_major) + ".x)");
    // rule 4: header checksum
    const uint32_t header_crc = load_u32(data + h_header_checksum);
    if (crc32(data, h_header_checksum) != header_crc) fail(h_header_checksum, "header_checksum", 4, "header checksum mismatch");
    // rule 5: declared size
    const uint64_t declared = load_u64(data + h_file_bytes);
    if (declared != size)
        fail(h_file_bytes, "file_bytes", 5,
             declared > size ? "file is truncated: " + std::to_string(size) + " bytes of " + std::to_string(declared)
                             : "file has " + std::to_string(size - declared) + " bytes past its declared end");
    // rule 6: section table
    SectionMap map;
    const uint32_t mesh_count = map.mesh_count = load_u32(data + h_mesh_count);
    const uint32_t section_count = load_u32(data + h_section_count);
    const uint64_t table_offset = map.table_offset = load_u64(data + h_table_offset);
    const uint64_t table_bytes = map.table_bytes = uint64_t(section_count) * section_entry_bytes;
    if (table_offset < header_bytes || table_offset > size || table_bytes > size - table_offset)
        fail(h_table_offset, "section_table", 6, std::to_string(section_count) + " sections at offset " + std::to_string(table_offset) + " do not fit in the file");
    if (crc32(data + table_offset, table_bytes) != load_u32(data + h_table_checksum))
        fail(h_table_checksum, "table_checksum", 6, "section table checksum mismatch");
    if (mesh_count > section_count) fail(h_mesh_count, "mesh_count", 9, std::to_string(mesh_count) + " meshes but only " + std::to_string(section_count) + " sections");
    return map;
}

void File::Impl::read_sections(SectionMap& map, const OpenOptions& options) {
    const uint32_t section_count = uint32_t(map.table_bytes / section_entry_bytes), mesh_count = map.mesh_count;
    const uint64_t table_offset = map.table_offset, table_bytes = map.table_bytes;
    map.per_mesh.resize(mesh_count);
    sections.resize(section_count);
    for (uint32_t i = 0; i < section_count; ++i) {
        const uint64_t e = table_offset + uint64_t(i) * section_entry_bytes;
        SectionInfo& s = sections[i];
        const uint32_t type = load_u32(data + e + s_type);
        for (int k = 0; k < 4; ++k) s.type[k] = layout::fourcc_name(type)[k];
        s.mesh = load_u32(data + e + s_mesh);
        s.offset = load_u64(data + e + s_offset);
        s.bytes = load_u64(data + e + s_bytes);
        s.checksum = load_u32(data + e + s_checksum);
        const std::string field = "section " + std::to_string(i) + " (" + layout::fourcc_name(type) + ")";
        // rule 7: placement
        if (s.offset % section_alignment != 0) fail(e + s_offset, field, 7, "offset " + std::to_string(s.offset) + " is not a multiple of 16");
        if (s.offset < table_offset + table_bytes || s.offset > size || s.bytes > size - s.offset)
            fail(e + s_offset, field, 7, std::to_string(s.bytes) + " bytes at offset " + std::to_string(s.offset) + " lie outside the file's data area");
        // rule 8: content checksum
        if (options.verify_checksums && crc32(data + s.offset, s.bytes) != s.checksum)
            fail(s.offset, field, 8, "checksum mismatch: the section is corrupt");
        // rule 9: known sections belong to an existing mesh, once each; file-level ones to none
        if (type == sec_materials || type == sec_instances || type == sec_provenance || type == sec_images || type == sec_source_gltf) {
            if (s.mesh != file_level) fail(e + s_mesh, field, 9, "a file-level section must have mesh 0xFFFFFFFF");
            const SectionInfo*& file_slot = type == sec_materials     ? map.materials
                                          : type == sec_instances   ? map.instances
                                          : type == sec_images      ? map.images
                                          : type == sec_source_gltf ? map.gltf
                                                                    : map.provenance;
            if (file_slot) fail(e, field, 9, "the file has this section twice");
            file_slot = &s;
            continue;
        }
        const SectionInfo** slot = nullptr;
        int stream = -1;
        for (int k = 0; k < attribute_stream_count; ++k)
            if (type == attribute_streams[k].section) stream = k;
        if (type == sec_mesh || type == sec_positions || stream >= 0 || type == sec_substitute || type == sec_triangles ||
            type == sec_metadata || type == sec_pairs || type == sec_coarse || type == sec_parts || type == sec_extra_streams) {
            if (s.mesh >= mesh_count)
                fail(e + s_mesh, field, 9, "belongs to mesh " + std::to_string(s.mesh) + " but the file has " + std::to_string(mesh_count));
            MeshSections& ms = map.per_mesh[s.mesh];
            slot = type == sec_mesh ? &ms.mesh
                 : type == sec_positions ? &ms.positions
                 : stream >= 0 ? &ms.streams[stream]
                 : type == sec_substitute ? &ms.substitute
                 : type == sec_triangles ? &ms.triangles
                 : type == sec_pairs     ? &ms.pairs
                 : type == sec_coarse    ? &ms.coarse
                 : type == sec_parts     ? &ms.parts
                 : type == sec_extra_streams ? &ms.extra
                                         : &ms.metadata;
            if (*slot) fail(e, field, 9, "mesh " + std::to_string(s.mesh) + " has this section twice");
            *slot = &s;
        }  // unknown types are skipped (forward compatibility)
    }
}

void File::Impl::validate_mesh(uint32_t mi, const MeshSections& ms, uint64_t table_offset) {
    const std::string mesh_field = "mesh " + std::to_string(mi);
    for (auto [sec, name] : {std::pair{ms.mesh, "MESH"}, std::pair{ms.positions, "POSI"}, std::pair{ms.substitute, "SUBS"},
                             std::pair{ms.triangles, "TRIS"}})
        if (!sec) fail(table_offset, mesh_field, 9, std::string("required section ") + name + " is missing");
    // rule 10: mesh header
    const uint8_t* h = data + ms.mesh->offset;
    if (ms.mesh->bytes < mesh_header_bytes) fail(ms.mesh->offset, mesh_field + " MESH", 10, "mesh header shorter than 64 bytes");
    MeshView& v = meshes[mi];
    v.vertex_count = load_u32(h + m_vertex_count);
    v.triangle_count = load_u32(h + m_triangle_count);
    v.min_vertex_count = load_u32(h + m_min_vertex_count);
    v.index_size = load_u32(h + m_index_size);
    v.material = int32_t(load_u32(h + m_material));
    const uint32_t attributes = load_u32(h + m_attributes);
    for (int k = 0; k < 3; ++k) {
        v.bounds_min[k] = load_f32(h + m_bounds_min + 4 * k);
        v.bounds_max[k] = load_f32(h + m_bounds_max + 4 * k);
    }
    const uint32_t name_bytes = load_u32(h + m_name_bytes);
    if (uint64_t(name_bytes) + mesh_header_bytes != ms.mesh->bytes)
        fail(ms.mesh->offset + m_name_bytes, mesh_field + " name_bytes", 10, "name of " + std::to_string(name_bytes) + " bytes does not match the section size");
    v.name = std::string_view(reinterpret_cast<const char*>(h + mesh_header_bytes), name_bytes);
    if (v.index_size != 2 && v.index_size != 4)
        fail(ms.mesh->offset + m_index_size, mesh_field + " index_size", 10, "index size " + std::to_string(v.index_size) + " is not 2 or 4");
    if (v.index_size == 2 && v.vertex_count > 65536)
        fail(ms.mesh->offset + m_index_size, mesh_field + " index_size", 10, "16-bit indices for " + std::to_string(v.vertex_count) + " vertices");
    if (attributes & ~known_attributes) fail(ms.mesh->offset + m_attributes, mesh_field + " attributes", 10, "unknown attribute flags");
    for (int k = 0; k < attribute_stream_count; ++k)
        if (bool(attributes & attribute_streams[k].flag) != (ms.streams[k] != nullptr))
            fail(ms.mesh->offset + m_attributes, mesh_field + " attributes", 10,
                 std::string("attribute flags and section ") + attribute_streams[k].name + " disagree");
    if (bool(attributes & attr_parts) != (ms.parts != nullptr))
        fail(ms.mesh->offset + m_attributes, mesh_field + " attributes", 10, "attribute flags and section PART disagree");
    // rule 11: stream sizes
    auto check_size = [&](const SectionInfo* sec, uint64_t expected, const char* name) {
        if (sec && sec->bytes != expected)
            fail(sec->offset, mesh_field + " " + name, 11,
                 std::to_string(sec->bytes) + " bytes where the counts require " + std::to_string(expected));
    };
    const uint64_t nv = v.vertex_count, nt = v.triangle_count;
    check_size(ms.positions, nv * 12, "POSI");
    for (int k = 0; k < attribute_stream_count; ++k)
        check_size(ms.streams[k], nv * 4 * attribute_streams[k].components, attribute_streams[k].name);
    check_size(ms.substitute, nv * v.index_size, "SUBS");
    check_size(ms.triangles, nt * 3 * v.index_size, "TRIS");
    v.positions = reinterpret_cast<const float*>(data + ms.positions->offset);
    for (int k = 0; k < attribute_stream_count; ++k)
        v.*attribute_streams[k].view = ms.streams[k] ? reinterpret_cast<const float*>(data + ms.streams[k]->offset) : nullptr;
    v.substitute = data + ms.substitute->offset;
    v.triangles = data + ms.triangles->offset;
    // rule 12: resolution range
    if (v.min_vertex_count > v.vertex_count || (v.vertex_count > 0 && v.min_vertex_count == 0))
        fail(ms.mesh->offset + m_min_vertex_count, mesh_field + " min_vertex_count", 12,
             std::to_string(v.min_vertex_count) + " is not in [1, vertex_count = " + std::to_string(v.vertex_count) + "]");
    if (v.vertex_count == 0 && v.triangle_count > 0) fail(ms.mesh->offset, mesh_field + " vertex_count", 12, "triangles without vertices");
    // rule 13: substitutes point strictly down (so every chain ends), survivors to themselves
    for (uint32_t i = 0; i < v.vertex_count; ++i) {
        const uint32_t s = v.substitute_at(i);
        if (i < v.min_vertex_count ? s != i : s >= i)
            fail(ms.substitute->offset + uint64_t(i) * v.index_size, mesh_field + " substitute[" + std::to_string(i) + "]", 13,
                 "value " + std::to_string(s) + (i < v.min_vertex_count ? " must equal its own index (survivor)" : " must be smaller than its index"));
    }
    // rule 14: triangle corners in range and distinct
    for (uint32_t t = 0; t < v.triangle_count; ++t) {
        const uint32_t a = v.corner(3 * t), b = v.corner(3 * t + 1), c = v.corner(3 * t + 2);
        const uint64_t at = ms.triangles->offset + uint64_t(t) * 3 * v.index_size;
        if (a >= v.vertex_count || b >= v.vertex_count || c >= v.vertex_count)
            fail(at, mesh_field + " triangle " + std::to_string(t), 14,
                 "index out of range (" + std::to_string(std::max(a, std::max(b, c))) + " >= vertex_count " + std::to_string(v.vertex_count) + ")");
        if (a == b || b == c || a == c) fail(at, mesh_field + " triangle " + std::to_string(t), 14, "degenerate triangle (repeated corner)");
    }
    // rule 15: metadata entries
    if (ms.metadata) {
        const uint8_t* p = data + ms.metadata->offset;
        const uint64_t bytes = ms.metadata->bytes;
        if (bytes < 4) fail(ms.metadata->offset, mesh_field + " META", 15, "shorter than its entry count");
        const uint32_t count = load_u32(p);
        uint64_t at = 4;
        for (uint32_t k = 0; k < count; ++k) {
            if (bytes - at < 8) fail(ms.metadata->offset + at, mesh_field + " META entry " + std::to_string(k), 15, "entry header past the section end");
            const uint64_t key_bytes = load_u32(p + at), value_bytes = load_u32(p + at + 4);
            const uint64_t need = 8 + (key_bytes + 3) / 4 * 4 + (value_bytes + 3) / 4 * 4;
            if (need > bytes - at) fail(ms.metadata->offset + at, mesh_field + " META entry " + std::to_string(k), 15, "entry runs past the section end");
            at += need;
        }
        if (at != bytes) fail(ms.metadata->offset + at, mesh_field + " META", 15, "bytes after the last entry");
        v.metadata = p;
        v.metadata_bytes = bytes;
    }
    // rule 16: groups: (V + 7) / 8 bytes, each set bit joining two removed vertices (a run of
    // set bits one group, since 1.7)
    if (ms.pairs) {
        if (ms.pairs->bytes != (nv + 7) / 8)
            fail(ms.pairs->offset, mesh_field + " PAIR", 16, std::to_string(ms.pairs->bytes) + " bytes where the vertex count requires " + std::to_string((nv + 7) / 8));
        const uint8_t* bits = data + ms.pairs->offset;
        for (uint32_t i = 0; i < v.vertex_count; ++i) {
            const bool set = (bits[i / 8] >> (i % 8)) & 1u;
            if (set && (i < v.min_vertex_count || i + 1 >= v.vertex_count))
                fail(ms.pairs->offset + i / 8, mesh_field + " PAIR bit " + std::to_string(i), 16, "a group must join removed vertices");
        }
        v.pair_bits = bits;
    }
    if (ms.parts) validate_parts(*ms.parts, attributes, v, mesh_field);
    // rule 22: carried streams, one element per vertex each
    if (ms.extra) {
        extra_streams[mi] = detail::decode_extra_streams(data + ms.extra->offset, ms.extra->bytes, ms.extra->offset, path, mesh_field, v.vertex_count);
        v.extra_streams = extra_streams[mi].empty() ? nullptr : extra_streams[mi].data();
        v.extra_stream_count = uint32_t(extra_streams[mi].size());
    }
}

void File::Impl::validate_scene(const SectionMap& map) {
    // rules 17 and 18: the scene; a material index names a stored material or none (-1), also
    // when the file stores no materials, so that no reader or exporter follows an index the
    // file merely declares
    if (map.materials)
        scene.materials = detail::decode_materials(data + map.materials->offset, map.materials->bytes, map.materials->offset, path);
    // rule 21: the images embedded in the source, and which texture shows which
    if (map.images) detail::decode_images(data + map.images->offset, map.images->bytes, map.images->offset, path, scene);
    // rule 23: a glTF source's scene beyond meshes, kept for the exporter
    if (map.gltf) scene.gltf = detail::decode_source_gltf(data + map.gltf->offset, map.gltf->bytes, map.gltf->offset, path);
    for (uint32_t mi = 0; mi < map.mesh_count; ++mi) {
        const MeshView& v = meshes[mi];
        const std::string field = "mesh " + std::to_string(mi);
        check_material(v.material, map.per_mesh[mi].mesh->offset + m_material, field + " material", scene.materials.size());
        for (uint32_t p = 0; p < v.part_count && v.parts; ++p)
            check_material(v.parts[p].material, map.per_mesh[mi].parts->offset + parts_header_bytes + uint64_t(p) * part_record_bytes + 8,
                           field + " part " + std::to_string(p) + " material", scene.materials.size());
    }
    if (map.provenance) provenance = std::string_view(reinterpret_cast<const char*>(data + map.provenance->offset), map.provenance->bytes);
    if (map.instances)
        scene.instances = detail::decode_instances(data + map.instances->offset, map.instances->bytes, map.instances->offset, path, map.mesh_count);
}

// rule 19: coarse corners are exactly the active triangles' corners mapped to their resolution
void File::Impl::validate_coarse(uint32_t mi, const SectionInfo& section) {
    const SectionInfo* sec = &section;
    MeshView& v = meshes[mi];
    const std::string field = "mesh " + std::to_string(mi) + " COAR";
    const uint8_t* p = data + sec->offset;
    if (v.parts) fail(sec->offset, field, 19, "a mesh with parts has no coarse corners (they hold one prefix of TRIS)");
    if (sec->bytes < coarse_header_bytes) fail(sec->offset, field, 19, "shorter than its 16-byte header");
    const uint32_t resolution = load_u32(p + c_resolution), triangles = load_u32(p + c_triangle_count), index_size = load_u32(p + c_index_size);
    if (resolution < v.min_vertex_count || resolution > v.vertex_count || resolution == 0)
        fail(sec->offset + c_resolution, field + " resolution", 19,
             std::to_string(resolution) + " is not in [min_vertex_count, vertex_count] = [" + std::to_string(v.min_vertex_count) + ", " +
                 std::to_string(v.vertex_count) + "]");
    if (index_size != detail::coarse_index_size(resolution))
        fail(sec->offset + c_index_size, field + " index_size", 19,
             "index size " + std::to_string(index_size) + " where resolution " + std::to_string(resolution) + " requires " + std::to_string(detail::coarse_index_size(resolution)));
    if (triangles > v.triangle_count)
        fail(sec->offset + c_triangle_count, field + " triangle_count", 19, std::to_string(triangles) + " is more than the mesh's " + std::to_string(v.triangle_count));
    if (sec->bytes != coarse_header_bytes + uint64_t(triangles) * 3 * index_size)
        fail(sec->offset, field, 19, std::to_string(sec->bytes) + " bytes where the counts require " + std::to_string(coarse_header_bytes + uint64_t(triangles) * 3 * index_size));
    const uint8_t* corners = p + coarse_header_bytes;
    for (uint32_t c = 0; c < triangles * 3; ++c) {
        const uint32_t stored = index_size == 2 ? uint32_t(reinterpret_cast<const uint16_t*>(corners)[c]) : reinterpret_cast<const uint32_t*>(corners)[c];
        const uint32_t expected = detail::map_corner(v, c, resolution);
        if (stored != expected)
            fail(sec->offset + coarse_header_bytes + uint64_t(c) * index_size, field + " corner " + std::to_string(c), 19,
                 "value " + std::to_string(stored) + " is not corner " + std::to_string(c) + " mapped to resolution " + std::to_string(resolution) + " (" + std::to_string(expected) + ")");
    }
    if ((triangles > 0 && !detail::triangle_active(v, triangles - 1, resolution)) ||
        (triangles < v.triangle_count && detail::triangle_active(v, triangles, resolution)))
        fail(sec->offset + c_triangle_count, field + " triangle_count", 19,
             std::to_string(triangles) + " is not the number of triangles active at resolution " + std::to_string(resolution));
    v.coarse_corners = corners;
    v.coarse_resolution = resolution;
    v.coarse_triangle_count = triangles;
    v.coarse_index_size = index_size;
}

File::File(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
File::File(File&&) noexcept = default;
File& File::operator=(File&&) noexcept = default;
File::~File() = default;

File File::open(const std::string& path, const OpenOptions& options) {
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->mapping = detail::MappedFile::open(path);
    impl->data = impl->mapping.data();
    impl->size = impl->mapping.size();
    impl->validate(options);
    return File(std::move(impl));
}

File File::from_bytes(const void* bytes, size_t size, const std::string& name, const OpenOptions& options) {
    auto impl = std::make_unique<Impl>();
    impl->path = name;
    impl->owned.assign(static_cast<const uint8_t*>(bytes), static_cast<const uint8_t*>(bytes) + size);
    impl->owned.reserve(size + 1);  // non-null data pointer even for size 0
    impl->data = impl->owned.data();
    impl->size = size;
    impl->validate(options);
    return File(std::move(impl));
}

File File::adopt(std::vector<uint8_t>&& bytes, const std::string& name, const OpenOptions& options) {
    auto impl = std::make_unique<Impl>();
    impl->path = name;
    impl->owned = std::move(bytes);
    impl->size = impl->owned.size();
    if (impl->owned.empty()) impl->owned.reserve(1);  // a non-null data pointer (no copy of the bytes)
    impl->data = impl->owned.data();
    impl->validate(options);
    return File(std::move(impl));
}

File File::borrow(const void* bytes, size_t size, const std::string& name, const OpenOptions& options) {
    auto impl = std::make_unique<Impl>();
    impl->path = name;
    impl->data = size > 0 ? static_cast<const uint8_t*>(bytes) : reinterpret_cast<const uint8_t*>("");
    impl->size = size;
    impl->validate(options);
    return File(std::move(impl));
}

void validate_bytes(const void* bytes, size_t size, const std::string& name, const OpenOptions& options) {
    File::Impl impl;
    impl.path = name;
    impl.data = size > 0 ? static_cast<const uint8_t*>(bytes) : reinterpret_cast<const uint8_t*>("");
    impl.size = size;
    impl.validate(options);
}

const std::string& File::path() const noexcept { return impl_->path; }
uint32_t File::version_major() const noexcept { return impl_->version_major; }
uint32_t File::version_minor() const noexcept { return impl_->version_minor; }
uint64_t File::file_bytes() const noexcept { return impl_->size; }
uint32_t File::mesh_count() const noexcept { return uint32_t(impl_->meshes.size()); }
const MeshView& File::mesh(uint32_t index) const noexcept {
    assert(index < impl_->meshes.size() && "File::mesh: \\pre index < mesh_count()");
    return impl_->meshes[index];
}
const std::vector<SectionInfo>& File::sections() const noexcept { return impl_->sections; }
const Scene& File::scene() const noexcept { return impl_->scene; }
std::string_view File::provenance() const noexcept { return impl_->provenance; }

MetadataValue find_metadata(const MeshView& view, std::string_view key) noexcept {
    MetadataValue r;
    if (!view.metadata || view.metadata_bytes < 4) return r;
    const uint8_t* p = view.metadata;
    const uint32_t count = load_u32(p);
    size_t at = 4;
    for (uint32_t k = 0; k < count && at + 8 <= view.metadata_bytes; ++k) {
        const uint32_t key_bytes = load_u32(p + at), value_bytes = load_u32(p + at + 4);
        const uint8_t* key_ptr = p + at + 8;
        const uint8_t* value_ptr = key_ptr + (size_t(key_bytes) + 3) / 4 * 4;
        if (std::string_view(reinterpret_cast<const char*>(key_ptr), key_bytes) == key) {
            r.data = value_ptr;
            r.bytes = value_bytes;
            return r;
        }
        at += 8 + (size_t(key_bytes) + 3) / 4 * 4 + (size_t(value_bytes) + 3) / 4 * 4;
    }
    return r;
}

} // namespace tom
