#pragma once
// tinygltf with the configuration every translation unit of tom::io uses (the implementation
// is compiled once, in gltf_import.cpp).

#define TINYGLTF_ENABLE_DRACO
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "tom/builder/mesh.h"
#include "tom/scene.h"

namespace tom::detail {

/// The bytes of the images embedded in a glTF (buffer views, data: URIs), by image index.
using EmbeddedImages = std::map<int, std::vector<uint8_t>>;

/// The materials of `model` and its default scene's node tree flattened into instances:
/// `mesh_parts[m]` lists the imported meshes (indices into ImportResult::meshes) made from the
/// triangle primitives of glTF mesh m; each node with a mesh gives one instance per part, with
/// the node's world transform. A texture whose image is in `embedded` shows that image, stored
/// in the scene (Scene::images, once per source image); others keep the image's URI.
/// What the stored glTF scene needs to know of the textures: per texture reference of the
/// materials in order, the sampler of the glTF texture it came from (-1 for none); and the
/// textures the kept material extensions refer to (by source texture index), each described as
/// the JSON text {"image": K} (stored, Scene::images) or {"uri": U, "mimeType": M}, with its
/// "sampler" (text: a json member would widen this struct's visibility past nlohmann's).
struct TextureSources {
    std::vector<int> samplers;
    std::map<int, std::string> extension;
};

/// `textures` receives the above for the materials of `doc` (the document `model` decoded).
/// \throw MeshError naming `path` and the node for a cycle or a node tree that would give
/// more than 1,000,000 instances.
Scene gltf_scene(const tinygltf::Model& model, const nlohmann::json& doc, const std::vector<std::vector<uint32_t>>& mesh_parts,
                 const EmbeddedImages& embedded, const std::string& path, TextureSources& textures);

/// Bakes the KHR_texture_transform of material `material` (its base colour texture's, else the
/// first of its textures that has one) into the TEXCOORD set it applies to: .tom keeps texture
/// references without transforms (and gltfpack's quantized UVs rely on one). Returns a warning
/// when textures of the material carry different transforms (only one can be baked), else "".
std::string bake_texture_transform(const tinygltf::Model& model, int material, Mesh& mesh);

/// True when a texture of material `material` carries KHR_texture_transform (so its primitive's
/// texture coordinates change on import and cannot share vertices with another material's).
bool has_texture_transform(const tinygltf::Model& model, int material);

} // namespace tom::detail
