#pragma once
// A file's scene: the materials its meshes refer to and the instances that place the meshes in
// the world (a glTF node tree flattened into world transforms). Stored in the file-level
// sections MATL, INST and IMAG (docs/FORMAT.md); textures are referenced, and images stored or
// referenced, never decoded.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace tom {

/// What a texture of a material is for (glTF's metallic-roughness material model).
enum class TextureRole : uint32_t { base_color = 0, metallic_roughness = 1, normal = 2, occlusion = 3, emissive = 4 };
constexpr uint32_t texture_role_count = 5;
const char* to_string(TextureRole role) noexcept;

struct TextureRef {
    TextureRole role = TextureRole::base_color;
    uint32_t texcoord = 0;   ///< which TEXCOORD_n it samples with
    std::string uri;         ///< as written in the source (relative to it), or empty for an image embedded in the source
    std::string mime_type;   ///< e.g. "image/png" when the source says, or empty
    int32_t image = -1;      ///< the image stored in the file (Scene::images) for an image embedded in the source, else -1
};

/// An image embedded in the source asset (a GLB's buffer view, a data: URI), stored in the file
/// byte for byte (section IMAG, since 1.6): PNG, JPEG, WebP, KTX2, ... never decoded.
struct Image {
    std::string name;        ///< the source's name for it, or empty
    std::string mime_type;   ///< "image/png", "image/jpeg", "image/webp", "image/ktx2", ...; never empty
    const uint8_t* data = nullptr;  ///< `bytes` bytes: into the File's mapping (valid while it lives), or held by `owner`
    uint64_t bytes = 0;
    std::shared_ptr<const void> owner;  ///< keeps `data` alive where no File holds it (an import's images); null for a File's
};

enum class AlphaMode : uint32_t { opaque = 0, mask = 1, blend = 2 };

struct Material {
    std::string name;
    float base_color[4] = {1, 1, 1, 1};  ///< linear RGBA factor
    float metallic = 1.0f, roughness = 1.0f;
    float emissive[3] = {0, 0, 0};
    AlphaMode alpha_mode = AlphaMode::opaque;
    float alpha_cutoff = 0.5f;
    bool double_sided = false;
    std::vector<TextureRef> textures;
};

/// One placement of one mesh of the file.
struct Instance {
    uint32_t mesh = 0;          ///< index of the mesh in the file
    uint32_t node = 0;          ///< the source node it came from (several meshes of one node share it)
    std::string name;           ///< the node's name, or empty
    float transform[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  ///< object to world, column-major
};

/// What a glTF source holds beyond meshes and materials, kept as it is for the glTF exporter
/// (section GLTF, since 1.6): its node tree, scenes, skins, animations, cameras and root
/// extensions (lights) as a glTF JSON fragment whose nodes' `mesh` index this file's meshes and
/// whose accessors read `data` as buffer 0. Never interpreted by the runtime (Instance is the
/// runtime's view of the nodes); empty for other sources.
struct SourceGltf {
    std::string json;               ///< a JSON object: "nodes", "scenes", "scene", "skins", "animations", "cameras", "accessors", "bufferViews", ...
    const uint8_t* data = nullptr;  ///< `bytes` bytes: into the File's mapping, or held by `owner`
    uint64_t bytes = 0;
    std::shared_ptr<const void> owner;
    bool empty() const noexcept { return json.empty(); }
};

struct Scene {
    std::vector<Material> materials;  ///< a mesh's `material` indexes this list
    std::vector<Instance> instances;  ///< empty: draw every mesh once, untransformed
    std::vector<Image> images;        ///< the images embedded in the source; a TextureRef's `image` indexes this list
    SourceGltf gltf;                  ///< a glTF source's nodes, skins, animations, ... (see SourceGltf)
};

/// An image of `bytes` bytes held by the Image itself (copied once), e.g. for tom::serialize.
Image make_image(std::string name, std::string mime_type, std::vector<uint8_t> bytes);

/// The MIME type that an image's first bytes announce ("image/png", "image/jpeg", "image/webp",
/// "image/ktx2", "image/gif", "image/bmp"), or "" when they announce none of these.
const char* sniff_image_type(const uint8_t* data, uint64_t bytes) noexcept;

/// What to draw for a whole file: the scene's instances, or, when it has none, every mesh once
/// with the identity transform (node = mesh index).
std::vector<Instance> draw_list(const Scene& scene, uint32_t mesh_count);

/// Product of two column-major 4x4 matrices: out = a * b (out may alias neither).
void multiply_4x4(const float a[16], const float b[16], float out[16]) noexcept;

} // namespace tom
