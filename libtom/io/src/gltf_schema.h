#pragma once
// Type check of a glTF 2.0 document (the .gltf JSON or a .glb's JSON chunk) against the core schema.

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tom::detail {

/// \throw MeshError naming `file` and the JSON path of the first property of the wrong type,
///        a missing required property, or malformed GLB headers.
/// Returns the parsed document.
nlohmann::json check_gltf_schema(const std::vector<uint8_t>& bytes, bool binary, const std::string& file);

/// "mesh M 'name' primitive P (ROLE)" for every primitive that uses accessor `accessor`
/// (as an attribute or its indices), "; "-separated; empty if none does.
std::string primitives_using_accessor(const nlohmann::json& doc, int accessor);

} // namespace tom::detail
