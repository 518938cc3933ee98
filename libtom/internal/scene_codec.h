#pragma once
// The file-level scene sections MATL and INST (docs/FORMAT.md, rules 17 and 18).

#include <cstdint>
#include <string>
#include <vector>

#include "tom/scene.h"

namespace tom::detail {

std::vector<uint8_t> encode_materials(const std::vector<Material>& materials);
std::vector<uint8_t> encode_instances(const std::vector<Instance>& instances);

/// Validate and decode a section of `bytes` bytes at file offset `offset`.
/// \throw FormatError naming `path`, the byte offset, the field and the rule.
std::vector<Material> decode_materials(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path);
std::vector<Instance> decode_instances(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path, uint32_t mesh_count);

} // namespace tom::detail
