#pragma once
// Range checks of a glTF document's references before tinygltf follows them (see the .cpp).

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tom::detail {

/// Checks every index tinygltf or the importer follows (buffer views' buffers and extents,
/// accessors' views, primitives' accessors and materials, nodes, scenes, textures) and decodes
/// each KHR_draco_mesh_compression primitive to check its view and attribute ids. `bytes` is
/// the .gltf text or the whole .glb; `base_dir` holds its external buffers.
/// \throw MeshError naming `file`, the JSON path and the problem.
void check_gltf_references(const nlohmann::json& doc, const std::vector<uint8_t>& bytes, bool binary, const std::string& base_dir,
                           const std::string& file);

} // namespace tom::detail
