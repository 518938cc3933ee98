#pragma once
// The file-level scene sections MATL, INST and IMAG (docs/FORMAT.md, rules 17, 18 and 21).

#include <cstdint>
#include <string>
#include <vector>

#include "tom/scene.h"

namespace tom::detail {

std::vector<uint8_t> encode_materials(const std::vector<Material>& materials);
std::vector<uint8_t> encode_instances(const std::vector<Instance>& instances);
/// IMAG: the scene's images and, per texture record of MATL (materials in order, each one's
/// textures in order), the image it shows. Empty when the scene has no image.
std::vector<uint8_t> encode_images(const Scene& scene);

/// Validate and decode a section of `bytes` bytes at file offset `offset`.
/// \throw FormatError naming `path`, the byte offset, the field and the rule.
std::vector<Material> decode_materials(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path);
std::vector<Instance> decode_instances(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path, uint32_t mesh_count);
/// Decodes IMAG into `scene.images` (views into `data`, no copy) and sets the `image` of each of
/// `scene.materials`' textures; `scene.materials` must already be decoded (MATL).
void decode_images(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path, Scene& scene);

} // namespace tom::detail
