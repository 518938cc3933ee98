#pragma once
// The file-level scene sections MATL, INST and IMAG and a mesh's carried streams XATT
// (docs/FORMAT.md, rules 17, 18, 21 and 22): sections of records, strings and data blocks.

#include <cstdint>
#include <string>
#include <vector>

#include "tom/scene.h"
#include "tom/view.h"

namespace tom::detail {

std::vector<uint8_t> encode_materials(const std::vector<Material>& materials);
std::vector<uint8_t> encode_instances(const std::vector<Instance>& instances);
/// IMAG: the scene's images and, per texture record of MATL (materials in order, each one's
/// textures in order), the image it shows. Empty when the scene has no image.
std::vector<uint8_t> encode_images(const Scene& scene);

/// GLTF: u64 json_bytes, u64 data_bytes, the JSON, zero padding to a multiple of 16, the data.
std::vector<uint8_t> encode_source_gltf(const SourceGltf& gltf);
/// Decodes GLTF: the JSON copied, the data a view into `data`. Its content is not checked here
/// (the runtime never reads it): the exporter that parses it does.
SourceGltf decode_source_gltf(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path);

/// XATT: one record per stream (name, type, components, normalized) and its `vertex_count`
/// elements. `streams` views the builder's data (VertexStreamView over VertexStream::data).
std::vector<uint8_t> encode_extra_streams(const std::vector<VertexStreamView>& streams, uint32_t vertex_count);
/// Decodes XATT of a mesh of `vertex_count` vertices: views into `data`, no copy.
std::vector<VertexStreamView> decode_extra_streams(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path, const std::string& mesh_field,
                                                   uint32_t vertex_count);

/// Validate and decode a section of `bytes` bytes at file offset `offset`.
/// \throw FormatError naming `path`, the byte offset, the field and the rule.
std::vector<Material> decode_materials(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path);
std::vector<Instance> decode_instances(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path, uint32_t mesh_count);
/// Decodes IMAG into `scene.images` (views into `data`, no copy) and sets the `image` of each of
/// `scene.materials`' textures; `scene.materials` must already be decoded (MATL).
void decode_images(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path, Scene& scene);

} // namespace tom::detail
