#pragma once
// A glTF's scene beyond meshes and materials, kept for the glTF exporter (tom::SourceGltf).

#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

#include "gltf_model.h"
#include "tom/scene.h"

namespace tom::detail {

/// The node tree, scenes, skins, animations, cameras and KHR_lights_punctual lights of `doc`
/// (as `model` decoded it), nodes' meshes renumbered through `mesh_parts` (glTF mesh -> imported
/// meshes), the accessors of skins and animations copied into the blob, and the texture samplers
/// with, per texture reference of the materials in order, its sampler as "textureSamplers", the
/// materials' extensions, and the textures those refer to as "extensionTextures" (both from
/// `textures`, as gltf_scene gives it). Empty when the document
/// has no nodes, or when one of those accessors cannot be copied (sparse): then nothing of it is
/// kept and the importer names what is lost.
SourceGltf source_gltf(const tinygltf::Model& model, const nlohmann::json& doc, const std::vector<std::vector<uint32_t>>& mesh_parts,
                       const TextureSources& textures);

} // namespace tom::detail
