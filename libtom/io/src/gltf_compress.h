#pragma once
// Compressed glTF output (tomextract -c): vertex streams quantized as KHR_mesh_quantization
// allows, and vertex and index buffer views encoded with EXT_meshopt_compression by
// meshoptimizer's encoders, as gltfpack -c writes them.
//
// Quantization, per mesh (gltfpack's defaults): positions on a 14-bit grid over the mesh's
// bounding cube as unsigned shorts, the grid's offset and scale moved into the node that draws
// the mesh (the dequantization matrix); normals and tangents as normalized bytes (through the
// octahedral filter, as gltfpack -cc writes them); texture
// coordinates in [0, 1] as normalized unsigned shorts (others stay float); colours as
// normalized unsigned bytes. Carried streams keep their types.
// Vertex order: the levels' vertices are permuted into the order the finest level first uses
// them, its triangles into vertex-cache order (meshopt_optimizeVertexCache): both only reorder,
// and both make the delta coding of the encoders several times as effective as on the TOM order.

#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

namespace tom::detail {

constexpr int kPositionBits = 14;

/// The vertex order of a compressed mesh: new vertex i is old vertex order[i]; remap is its inverse.
struct VertexOrder {
    std::vector<uint32_t> order, remap;
};

/// The order in which `indices` (triangles over vertices [0, vertex_count)) first use their
/// vertices after their triangles are put in vertex-cache order; vertices they never use follow,
/// in their own order.
VertexOrder fetch_order(const std::vector<uint32_t>& indices, uint32_t vertex_count);

/// `indices` remapped by `order` and their triangles put in vertex-cache order (the same triangles).
std::vector<uint32_t> optimized_indices(const uint32_t* indices, size_t count, const VertexOrder& order, uint32_t vertex_count);

/// A buffer view's EXT_meshopt_compression encoding: ATTRIBUTES of `count` elements of `stride`
/// bytes (a multiple of 4, at most 256; filtered data as the filter's encoder left it), or
/// TRIANGLES of `count` indices of `stride` 2 or 4.
std::vector<uint8_t> encode_attributes(const void* data, size_t count, size_t stride);
std::vector<uint8_t> encode_triangles(const void* indices, size_t count, size_t stride);

/// Positions quantized to the 14-bit grid: xyz as unsigned shorts and a pad, 8 bytes a vertex,
/// and the grid (position = offset + scale * q) as a column-major dequantization matrix.
struct QuantizedPositions {
    std::vector<uint16_t> values;  // 4 per vertex
    uint16_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    nlohmann::json dequantize;  // the matrix, 16 numbers
};
QuantizedPositions quantize_positions(const float* positions, const VertexOrder& order);

/// Unit vectors (`width` 3: normals, 4: tangents with w = +-1) in the encoding of
/// EXT_meshopt_compression's OCTAHEDRAL filter, 4 bytes a vertex: 8-bit octahedral x and y that
/// decode into normalized bytes (xyz and the w kept), a third of the bytes after compression.
std::vector<int8_t> octahedral_unit_vectors(const float* vectors, size_t width, const VertexOrder& order);

/// Texture coordinates as normalized unsigned shorts, or empty when one is outside [0, 1].
std::vector<uint16_t> quantize_texcoords(const float* uv, const VertexOrder& order);

/// Colours clamped to [0, 1] as normalized unsigned bytes, rgba.
std::vector<uint8_t> quantize_colors(const float* rgba, const VertexOrder& order);

/// The elements of a stream of `bytes` bytes each, in `order`, padded to `stride` bytes.
std::vector<uint8_t> gather(const uint8_t* data, size_t bytes, size_t stride, const VertexOrder& order);

} // namespace tom::detail
