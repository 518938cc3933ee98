#pragma once
// What of a glTF document the toolkit carries into a .tom and back out, and what it does not: the
// importer's answer to "was anything lost?" (ImportResult::dropped).

#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tom::detail {

/// Whether an asset that lists `extension` in extensionsRequired can be read: the extensions the
/// importer decodes or carries, and those that change no geometry (materials, lights, image
/// codecs); an extension that places or shapes geometry otherwise (EXT_mesh_gpu_instancing,
/// KHR_technique_webgl, an unknown one) cannot.
bool can_read_required(const std::string& extension);

/// Whether a material's extension `name` is kept (with the scene, tom::SourceGltf's
/// "materialExtensions"): every one (KHR_materials_unlit, clearcoat, transmission, sheen, ...)
/// but the specular-glossiness model, which becomes the metallic-roughness one, and
/// KHR_texture_transform, which is baked into the texture coordinates. The textures an extension
/// refers to are described in "extensionTextures" and renumbered by the exporter.
bool carries_material_extension(const std::string& name);

/// The texture indices a material extension's value refers to (its textureInfo objects' "index").
void texture_indices(const nlohmann::json& j, std::set<int>& out);

/// Whether the importer reads attribute `name` into a stream of its own (POSITION, NORMAL,
/// TANGENT, TEXCOORD_0, TEXCOORD_1, COLOR_0); every other attribute is carried unread.
bool is_interpreted_attribute(const std::string& name);

/// The features of `doc` that the .tom does not keep, one phrase each, in a fixed order:
/// "skins (1)", "animations (2)", "morph target weights (1 mesh)", "cameras (1)", "node tree
/// (flattened into instances: 2 nodes without a mesh)", "extension KHR_materials_clearcoat",
/// "texture samplers (2)", "extras (4)", ..., then `also` (what the importer itself could not
/// carry). With `scene_kept` (the node tree, scenes, skins, animations, cameras, lights and
/// texture samplers are kept as tom::SourceGltf) those are not named. Empty when nothing is lost.
std::vector<std::string> gltf_dropped(const nlohmann::json& doc, bool scene_kept, std::vector<std::string> also);

} // namespace tom::detail
