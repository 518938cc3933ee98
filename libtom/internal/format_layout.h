#pragma once
// Byte layout of .tom files, shared by the writer and the reader (docs/FORMAT.md is the spec).

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "tom/format.h"
#include "tom/view.h"

namespace tom::layout {

constexpr uint8_t magic[8] = {0x89, 'T', 'O', 'M', 0x0D, 0x0A, 0x1A, 0x0A};
constexpr uint32_t header_bytes = 64;
constexpr uint32_t section_entry_bytes = 32;
constexpr uint32_t section_alignment = 16;
constexpr uint32_t mesh_header_bytes = 64;

// header field offsets
constexpr uint32_t h_version_major = 8, h_version_minor = 12, h_file_bytes = 16, h_mesh_count = 24, h_section_count = 28,
                   h_table_offset = 32, h_table_checksum = 40, h_header_checksum = 44;
// section entry field offsets
constexpr uint32_t s_type = 0, s_mesh = 4, s_offset = 8, s_bytes = 16, s_checksum = 24;
// mesh header field offsets
constexpr uint32_t m_vertex_count = 0, m_triangle_count = 4, m_min_vertex_count = 8, m_index_size = 12, m_material = 16,
                   m_attributes = 20, m_bounds_min = 24, m_bounds_max = 36, m_name_bytes = 48;

// COAR header field offsets
constexpr uint32_t coarse_header_bytes = 16;
constexpr uint32_t c_resolution = 0, c_triangle_count = 4, c_index_size = 8;

// PART header (since 1.4): u32 part_count, u32[3] reserved, then part_count records of 16 bytes
constexpr uint32_t parts_header_bytes = 16, part_record_bytes = 16;

enum Attribute : uint32_t { attr_normals = 1, attr_texcoords = 2, attr_colors = 4, attr_texcoords1 = 8, attr_tangents = 16 };
constexpr uint32_t stream_attributes = attr_normals | attr_texcoords | attr_colors | attr_texcoords1 | attr_tangents;
/// Bit 5 of a mesh's `attributes`: the mesh has parts (section PART, since 1.4). Not a stream:
/// it is set so that readers before 1.4, which would draw only the first part's prefix, reject
/// the mesh (rule 10) instead of misreading it.
constexpr uint32_t attr_parts = 32;
constexpr uint32_t known_attributes = stream_attributes | attr_parts;

constexpr uint32_t fourcc(const char (&s)[5]) {
    return uint32_t(uint8_t(s[0])) | uint32_t(uint8_t(s[1])) << 8 | uint32_t(uint8_t(s[2])) << 16 | uint32_t(uint8_t(s[3])) << 24;
}
/// A section type as its four characters ('?' for one that is not printable ASCII).
inline std::string fourcc_name(uint32_t type) {
    std::string s;
    for (int k = 0; k < 4; ++k) {
        const char c = char((type >> (8 * k)) & 0xFF);
        s += (c >= 32 && c < 127) ? c : '?';
    }
    return s;
}
constexpr uint32_t sec_mesh = fourcc("MESH"), sec_positions = fourcc("POSI"), sec_normals = fourcc("NORM"),
                   sec_texcoords = fourcc("TEX0"), sec_colors = fourcc("COL0"), sec_substitute = fourcc("SUBS"),
                   sec_triangles = fourcc("TRIS"), sec_metadata = fourcc("META"), sec_pairs = fourcc("PAIR"),
                   sec_texcoords1 = fourcc("TEX1"), sec_tangents = fourcc("TANG"), sec_materials = fourcc("MATL"),
                   sec_instances = fourcc("INST"), sec_coarse = fourcc("COAR"), sec_parts = fourcc("PART"),
                   sec_provenance = fourcc("PROV"), sec_images = fourcc("IMAG"), sec_extra_streams = fourcc("XATT"),
                   sec_source_gltf = fourcc("GLTF");
/// The `mesh` field of file-level sections (MATL, INST, PROV).
constexpr uint32_t file_level = SectionInfo::file_level;

/// The optional f32 vertex streams, in the order of tom::for_each_attribute_stream: attribute
/// flag, section type and name, floats per vertex, and the MeshView member that points at it.
struct AttributeStream {
    uint32_t flag;
    uint32_t section;
    const char* name;
    uint32_t components;
    const float* MeshView::*view;
};
constexpr AttributeStream attribute_streams[] = {{attr_normals, sec_normals, "NORM", 3, &MeshView::normals},
                                                 {attr_texcoords, sec_texcoords, "TEX0", 2, &MeshView::texcoords},
                                                 {attr_colors, sec_colors, "COL0", 4, &MeshView::colors},
                                                 {attr_texcoords1, sec_texcoords1, "TEX1", 2, &MeshView::texcoords1},
                                                 {attr_tangents, sec_tangents, "TANG", 4, &MeshView::tangents}};
constexpr int attribute_stream_count = int(sizeof(attribute_streams) / sizeof(attribute_streams[0]));

// little-endian loads and stores (the format is little-endian; so is every supported host)
inline uint32_t load_u32(const uint8_t* p) {
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
inline uint64_t load_u64(const uint8_t* p) { return uint64_t(load_u32(p)) | uint64_t(load_u32(p + 4)) << 32; }
inline float load_f32(const uint8_t* p) {
    const uint32_t bits = load_u32(p);
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}
inline void store_u32(uint8_t* p, uint32_t v) {
    p[0] = uint8_t(v), p[1] = uint8_t(v >> 8), p[2] = uint8_t(v >> 16), p[3] = uint8_t(v >> 24);
}
inline void store_u64(uint8_t* p, uint64_t v) {
    store_u32(p, uint32_t(v));
    store_u32(p + 4, uint32_t(v >> 32));
}
inline void store_f32(uint8_t* p, float f) {
    uint32_t bits;
    std::memcpy(&bits, &f, 4);
    store_u32(p, bits);
}

/// A stream of f32 values as stored (POSI, NORM, ...).
inline std::vector<uint8_t> float_bytes(const std::vector<float>& values) {
    std::vector<uint8_t> out(values.size() * 4);
    for (size_t i = 0; i < values.size(); ++i) store_f32(&out[4 * i], values[i]);
    return out;
}

/// `count` indices as stored at `out`, `index_size` (2 or 4) bytes each (SUBS, TRIS, COAR).
inline void store_indices(uint8_t* out, const uint32_t* values, size_t count, uint32_t index_size) {
    for (size_t i = 0; i < count; ++i) {
        if (index_size == 2) {
            out[2 * i] = uint8_t(values[i]);
            out[2 * i + 1] = uint8_t(values[i] >> 8);
        } else {
            store_u32(&out[4 * i], values[i]);
        }
    }
}
inline std::vector<uint8_t> index_bytes(const std::vector<uint32_t>& values, uint32_t index_size) {
    std::vector<uint8_t> out(values.size() * index_size);
    store_indices(out.data(), values.data(), values.size(), index_size);
    return out;
}

/// One section of a file image being assembled: its type, its mesh (or file_level) and its data.
struct PendingSection {
    uint32_t type, mesh;
    std::vector<uint8_t> bytes;
};

/// A section's data where it already lies, for assemble_file: with its checksum when the caller
/// knows it (a section kept whole from a stream's directory), so that it is not computed again.
struct SectionView {
    uint32_t type, mesh;
    const uint8_t* data;
    size_t bytes;
    bool has_checksum = false;
    uint32_t checksum = 0;
};

/// The file image of `sections`, in their order: header, section table, then each section's data
/// at a multiple of 16 with its checksum. Shared by the writer and the stream decoder, which
/// validate what it returns. Each byte is written once (no fill before the copies).
inline std::vector<uint8_t> assemble_file(const std::vector<SectionView>& sections, uint32_t mesh_count) {
    const uint64_t table_offset = header_bytes;
    uint64_t offset = table_offset + uint64_t(sections.size()) * section_entry_bytes;
    std::vector<uint64_t> offsets;
    for (const SectionView& s : sections) {
        offset = (offset + section_alignment - 1) / section_alignment * section_alignment;
        offsets.push_back(offset);
        offset += s.bytes;
    }
    std::vector<uint8_t> file;
    file.reserve(offset);
    file.resize(table_offset + sections.size() * section_entry_bytes, 0);
    std::memcpy(file.data(), magic, 8);
    store_u32(&file[h_version_major], format_version_major);
    store_u32(&file[h_version_minor], format_version_minor);
    store_u64(&file[h_file_bytes], offset);
    store_u32(&file[h_mesh_count], mesh_count);
    store_u32(&file[h_section_count], uint32_t(sections.size()));
    store_u64(&file[h_table_offset], table_offset);
    for (size_t i = 0; i < sections.size(); ++i) {
        const SectionView& s = sections[i];
        uint8_t* e = &file[table_offset + i * section_entry_bytes];
        store_u32(e + s_type, s.type);
        store_u32(e + s_mesh, s.mesh);
        store_u64(e + s_offset, offsets[i]);
        store_u64(e + s_bytes, s.bytes);
        store_u32(e + s_checksum, s.has_checksum ? s.checksum : crc32(s.data, s.bytes));
    }
    store_u32(&file[h_table_checksum], crc32(&file[table_offset], sections.size() * section_entry_bytes));
    store_u32(&file[h_header_checksum], crc32(file.data(), h_header_checksum));
    for (size_t i = 0; i < sections.size(); ++i) {
        file.resize(offsets[i], 0);  // the padding before the section
        file.insert(file.end(), sections[i].data, sections[i].data + sections[i].bytes);
    }
    return file;
}
inline std::vector<uint8_t> assemble_file(const std::vector<PendingSection>& sections, uint32_t mesh_count) {
    std::vector<SectionView> views;
    for (const PendingSection& s : sections) views.push_back({s.type, s.mesh, s.bytes.data(), s.bytes.size()});
    return assemble_file(views, mesh_count);
}

} // namespace tom::layout
