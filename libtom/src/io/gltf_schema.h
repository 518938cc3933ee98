#pragma once
// Type check of a glTF 2.0 document (the .gltf JSON or a .glb's JSON chunk) against the core schema.

#include <cstdint>
#include <string>
#include <vector>

namespace tom::detail {

/// \throw ImportError naming `file` and the JSON path of the first property of the wrong type,
///        a missing required property, or malformed GLB headers.
void check_gltf_schema(const std::vector<uint8_t>& bytes, bool binary, const std::string& file);

} // namespace tom::detail
