#pragma once
// A read-only view of one sorted TOM mesh: the form extraction works on,
// whether the data lives in a mapped .tom file or in a TomMesh in memory.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

namespace tom {

/// One part of a mesh: a range of its triangles drawn with one material (a glTF primitive, an
/// OBJ `usemtl` group). The 16-byte record of section PART (FORMAT.md), used in place.
/// All parts share the mesh's vertex order; at any resolution the live triangles of a part are
/// a prefix of its range.
struct Part {
    uint32_t first_triangle = 0;
    uint32_t triangle_count = 0;
    int32_t material = -1;     ///< index into the file's materials, -1 if none
    uint32_t attributes = 0;   ///< the streams the part's source had (MESH attribute bits 0-4); the others hold neutral values
};

/// A vertex stream carried beside the ones above, never read by the toolkit (section XATT, since
/// 1.6): a glTF attribute such as TEXCOORD_2, COLOR_1, JOINTS_0, WEIGHTS_0 or a custom "_NAME",
/// or a morph target's deltas, named "TARGET<k>/<ATTRIBUTE>" ("TARGET0/POSITION"). One element
/// per vertex in resolution order, each the source's value exactly.
struct VertexStreamView {
    std::string_view name;
    uint32_t component_type = 5126;  ///< glTF's: 5120 BYTE, 5121 UNSIGNED_BYTE, 5122 SHORT, 5123 UNSIGNED_SHORT, 5125 UNSIGNED_INT, 5126 FLOAT
    uint32_t components = 1;         ///< 1 to 4
    bool normalized = false;         ///< integers that stand for [0, 1] or [-1, 1] (glTF's `normalized`)
    const uint8_t* data = nullptr;   ///< vertex_count elements of components values, tightly packed, little-endian
};

/// The bytes of one value of a glTF component type, 0 for an unknown type.
inline uint32_t component_bytes(uint32_t component_type) noexcept {
    switch (component_type) {
    case 5120: case 5121: return 1;
    case 5122: case 5123: return 2;
    case 5125: case 5126: return 4;
    default: return 0;
    }
}

/// One value of a glTF component type at `at` (little-endian), as a number: integers as they
/// are, or with `normalized` mapped to [0, 1] (unsigned) or [-1, 1] (signed) as glTF maps them;
/// 0 for an unknown type. For reading carried streams (joints, weights, morph deltas).
inline double component_value(uint32_t component_type, bool normalized, const uint8_t* at) noexcept {
    auto load = [at](auto v) {
        std::memcpy(&v, at, sizeof v);
        return v;
    };
    switch (component_type) {
    case 5120: { const double c = load(int8_t()); return normalized ? (c / 127.0 < -1.0 ? -1.0 : c / 127.0) : c; }
    case 5121: { const double c = load(uint8_t()); return normalized ? c / 255.0 : c; }
    case 5122: { const double c = load(int16_t()); return normalized ? (c / 32767.0 < -1.0 ? -1.0 : c / 32767.0) : c; }
    case 5123: { const double c = load(uint16_t()); return normalized ? c / 65535.0 : c; }
    case 5125: return double(load(uint32_t()));
    case 5126: return double(load(float()));
    default: return 0.0;
    }
}

/// Pointers into sorted streams; nothing is owned. Optional streams are null.
/// Invariants (checked by the reader for files, by construction for builds):
///   min_vertex_count <= vertex_count; for i >= min_vertex_count substitute[i] < i,
///   for i < min_vertex_count substitute[i] == i; every triangle index < vertex_count;
///   triangles alive at resolution n are a prefix of the triangle array.
struct MeshView {
    std::string_view name;
    uint32_t vertex_count = 0;
    uint32_t triangle_count = 0;
    uint32_t min_vertex_count = 0;   ///< survivors: the coarsest resolution
    uint32_t index_size = 4;         ///< bytes per stored index: 2 or 4
    int32_t material = -1;
    const float* positions = nullptr;  ///< xyz * vertex_count
    const float* normals = nullptr;    ///< xyz * vertex_count, or null
    const float* texcoords = nullptr;  ///< uv * vertex_count, or null
    const float* colors = nullptr;     ///< rgba * vertex_count, or null
    const float* texcoords1 = nullptr; ///< uv * vertex_count (TEXCOORD_1), or null
    const float* tangents = nullptr;   ///< xyzw * vertex_count (w = +-1 handedness), or null
    const void* substitute = nullptr;  ///< index_size bytes * vertex_count
    const void* triangles = nullptr;   ///< index_size bytes * 3 * triangle_count
    float bounds_min[3] = {0, 0, 0};
    float bounds_max[3] = {0, 0, 0};
    const uint8_t* metadata = nullptr; ///< metadata entries (FORMAT.md, section META)
    /// bit i: vertices i and i + 1 are copies of one point, removed together (section PAIR; a run
    /// of set bits is one group of copies), or null
    const uint8_t* pair_bits = nullptr;
    size_t metadata_bytes = 0;
    /// Optional extraction shortcut (section COAR): the corners of the triangles active at
    /// resolution coarse_resolution, already mapped to it, so coarser resolutions walk on from
    /// there instead of from the full-resolution corners. Null when absent.
    const void* coarse_corners = nullptr;        ///< coarse_index_size bytes * 3 * coarse_triangle_count
    uint32_t coarse_resolution = 0;
    uint32_t coarse_triangle_count = 0;
    uint32_t coarse_index_size = 2;
    /// Parts (section PART), or null with part_count 0 for a mesh of one part: then the whole
    /// triangle array is one prefix-sorted range, drawn with `material`.
    const Part* parts = nullptr;
    uint32_t part_count = 0;
    /// The carried streams (section XATT) of a mesh read from a file; null with a count of 0
    /// when it has none, and always for TomMesh::view() (see TomMesh::extra_streams).
    const VertexStreamView* extra_streams = nullptr;
    uint32_t extra_stream_count = 0;

    uint32_t substitute_at(uint32_t i) const noexcept {
        return index_size == 2 ? static_cast<const uint16_t*>(substitute)[i] : static_cast<const uint32_t*>(substitute)[i];
    }
    /// True when resolution n would take some copies of a group (a seam's pair, a pole's fan)
    /// without the others.
    bool splits_pair(uint32_t n) const noexcept {
        return pair_bits && n > 0 && n < vertex_count && (pair_bits[(n - 1) / 8] >> ((n - 1) % 8) & 1u);
    }
    /// The highest resolution <= n that splits no group (n itself when none is split).
    uint32_t whole_groups_below(uint32_t n) const noexcept {
        while (splits_pair(n)) --n;
        return n;
    }
    /// The lowest resolution >= n that splits no group.
    uint32_t whole_groups_above(uint32_t n) const noexcept {
        while (splits_pair(n)) ++n;
        return n;
    }
    uint32_t corner(uint32_t c) const noexcept {
        return index_size == 2 ? static_cast<const uint16_t*>(triangles)[c] : static_cast<const uint32_t*>(triangles)[c];
    }
};

/// The number of parts of a mesh: 1 for a mesh without section PART.
inline uint32_t part_count(const MeshView& mesh) noexcept { return mesh.parts ? mesh.part_count : 1u; }

/// Part p of a mesh (\pre p < part_count(mesh)); a mesh without parts is one part of all its
/// triangles with the mesh's material and attributes.
Part part_at(const MeshView& mesh, uint32_t p) noexcept;

/// A value stored in a mesh's metadata area, found by key; empty data if absent.
struct MetadataValue {
    const uint8_t* data = nullptr;
    size_t bytes = 0;
    bool found() const noexcept { return data != nullptr; }
};

/// Looks a key up in view.metadata (entries are validated when a file is opened).
MetadataValue find_metadata(const MeshView& view, std::string_view key) noexcept;

} // namespace tom
