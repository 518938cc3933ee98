// glTF materials and node tree -> tom::Scene (materials with texture references, instances
// with world transforms).

#include <array>
#include <cmath>
#include <map>

#include "gltf_model.h"

#include <nlohmann/json.hpp>

#include "gltf_carried.h"
#include "tom/errors.h"

namespace tom::detail {

namespace {

constexpr size_t max_instances = 1000000;

// The image extensions whose `source` stands in for (or beside) a texture's own.
constexpr const char* image_extensions[] = {"EXT_texture_webp", "KHR_texture_basisu", "EXT_texture_avif"};

// The image a texture shows: its own `source`, else an image extension's (a texture in WebP or
// KTX2 alone has no `source`); -1 for none.
int texture_source(const tinygltf::Texture& texture) {
    if (texture.source >= 0) return texture.source;
    for (const char* ext : image_extensions) {
        const auto it = texture.extensions.find(ext);
        if (it != texture.extensions.end() && it->second.IsObject() && it->second.Get("source").IsNumber()) return it->second.Get("source").GetNumberAsInt();
    }
    return -1;
}

// Materials with their texture references; the images embedded in the source are stored in the
// scene once each, the others referenced by URI.
struct MaterialReader {
    const tinygltf::Model& model;
    const EmbeddedImages& embedded;
    Scene& scene;
    std::map<int, int32_t> stored{};  // source image -> Scene::images index
    std::vector<int> samplers{};      // per texture reference made, in order: its texture's sampler (-1: none)

    int32_t store_image(int source) {
        const auto bytes = embedded.find(source);
        if (bytes == embedded.end()) return -1;
        const auto [it, fresh] = stored.emplace(source, int32_t(scene.images.size()));
        if (fresh) {
            const tinygltf::Image& image = model.images[size_t(source)];
            std::string mime = image.mimeType;
            if (mime.empty()) mime = sniff_image_type(bytes->second.data(), bytes->second.size());
            if (mime.empty()) mime = "application/octet-stream";
            scene.images.push_back(make_image(image.name, mime, bytes->second));
        }
        return it->second;
    }

    // the image texture `texture` shows: stored, or its URI (and type); texture must exist
    TextureRef image_of(int texture) {
        const int source = texture_source(model.textures[size_t(texture)]);
        TextureRef ref;
        if (source >= 0 && size_t(source) < model.images.size()) {
            const tinygltf::Image& image = model.images[size_t(source)];
            ref.image = store_image(source);
            ref.mime_type = ref.image >= 0 ? scene.images[size_t(ref.image)].mime_type : image.mimeType;
            if (ref.image < 0 && image.uri.rfind("data:", 0) != 0) ref.uri = image.uri;
        }
        return ref;
    }

    void texture_ref(int texture, int texcoord, TextureRole role, Material& out) {
        if (texture < 0 || size_t(texture) >= model.textures.size()) return;
        TextureRef ref = image_of(texture);
        ref.role = role;
        ref.texcoord = texcoord > 0 ? uint32_t(texcoord) : 0u;
        out.textures.push_back(std::move(ref));
        samplers.push_back(model.textures[size_t(texture)].sampler);
    }

    // texture `texture` as the stored scene describes one a material extension refers to, or null
    // when it does not exist or shows no image
    nlohmann::json describe(int texture) {
        if (texture < 0 || size_t(texture) >= model.textures.size()) return nullptr;
        const TextureRef ref = image_of(texture);
        nlohmann::json out = nlohmann::json::object();
        if (ref.image >= 0) out["image"] = ref.image;
        else if (!ref.uri.empty()) out["uri"] = ref.uri;
        else return nullptr;
        if (!ref.mime_type.empty()) out["mimeType"] = ref.mime_type;
        if (const int s = model.textures[size_t(texture)].sampler; s >= 0) out["sampler"] = s;
        return out;
    }

    Material material(const tinygltf::Material& m);
};

// A material's five texture slots of the metallic-roughness model: texture index, TEXCOORD set,
// the slot's extensions (KHR_texture_transform) and the role it plays.
struct TextureSlot {
    int index, texcoord;
    const tinygltf::ExtensionMap* extensions;
    TextureRole role;
};

std::array<TextureSlot, texture_role_count> texture_slots(const tinygltf::Material& m) {
    const tinygltf::PbrMetallicRoughness& pbr = m.pbrMetallicRoughness;
    return {{{pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord, &pbr.baseColorTexture.extensions, TextureRole::base_color},
             {pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord, &pbr.metallicRoughnessTexture.extensions,
              TextureRole::metallic_roughness},
             {m.normalTexture.index, m.normalTexture.texCoord, &m.normalTexture.extensions, TextureRole::normal},
             {m.occlusionTexture.index, m.occlusionTexture.texCoord, &m.occlusionTexture.extensions, TextureRole::occlusion},
             {m.emissiveTexture.index, m.emissiveTexture.texCoord, &m.emissiveTexture.extensions, TextureRole::emissive}}};
}

Material MaterialReader::material(const tinygltf::Material& m) {
    Material out;
    out.name = m.name;
    const tinygltf::PbrMetallicRoughness& pbr = m.pbrMetallicRoughness;
    for (size_t k = 0; k < 4 && k < pbr.baseColorFactor.size(); ++k) out.base_color[k] = float(pbr.baseColorFactor[k]);
    out.metallic = float(pbr.metallicFactor);
    out.roughness = float(pbr.roughnessFactor);
    for (size_t k = 0; k < 3 && k < m.emissiveFactor.size(); ++k) out.emissive[k] = float(m.emissiveFactor[k]);
    out.alpha_mode = m.alphaMode == "MASK" ? AlphaMode::mask : m.alphaMode == "BLEND" ? AlphaMode::blend : AlphaMode::opaque;
    out.alpha_cutoff = float(m.alphaCutoff);
    out.double_sided = m.doubleSided;
    for (const TextureSlot& slot : texture_slots(m)) texture_ref(slot.index, slot.texcoord, slot.role, out);
    // the specular-glossiness extension's diffuse colour and texture stand for the base colour
    const auto sg = m.extensions.find("KHR_materials_pbrSpecularGlossiness");
    if (sg != m.extensions.end() && sg->second.IsObject()) {
        const tinygltf::Value& diffuse = sg->second.Get("diffuseFactor");
        if (diffuse.IsArray() && diffuse.ArrayLen() == 4)
            for (int k = 0; k < 4; ++k) out.base_color[k] = float(diffuse.Get(k).GetNumberAsDouble());
        const tinygltf::Value& tex = sg->second.Get("diffuseTexture");
        if (tex.IsObject() && tex.Get("index").IsNumber() && pbr.baseColorTexture.index < 0)
            texture_ref(tex.Get("index").GetNumberAsInt(), tex.Get("texCoord").IsNumber() ? tex.Get("texCoord").GetNumberAsInt() : 0,
                        TextureRole::base_color, out);
    }
    return out;
}

// The node's local transform, column-major: its matrix, or T * R * S.
void local_transform(const tinygltf::Node& node, float out[16]) {
    if (node.matrix.size() == 16) {
        for (int k = 0; k < 16; ++k) out[k] = float(node.matrix[size_t(k)]);
        return;
    }
    double q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1}, t[3] = {0, 0, 0};
    if (node.rotation.size() == 4)
        for (int k = 0; k < 4; ++k) q[k] = node.rotation[size_t(k)];
    if (node.scale.size() == 3)
        for (int k = 0; k < 3; ++k) s[k] = node.scale[size_t(k)];
    if (node.translation.size() == 3)
        for (int k = 0; k < 3; ++k) t[k] = node.translation[size_t(k)];
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),   // column 0
                         2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),   // column 1
                         2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; ++c) {
        for (int k = 0; k < 3; ++k) out[4 * c + k] = float(r[3 * c + k] * s[c]);
        out[4 * c + 3] = 0;
    }
    for (int k = 0; k < 3; ++k) out[12 + k] = float(t[k]);
    out[15] = 1;
}

struct Flattener {
    const tinygltf::Model& model;
    const std::vector<std::vector<uint32_t>>& mesh_parts;
    const std::string& path;
    Scene& scene;
    std::vector<uint8_t> on_path;  // nodes between the root and the current one: a repeat is a cycle

    void visit(int index, const float parent[16]) {
        if (index < 0 || size_t(index) >= model.nodes.size())
            throw MeshError(path + ": the node tree refers to node " + std::to_string(index) + ", which does not exist");
        if (on_path[size_t(index)]) throw MeshError(path + ": node " + std::to_string(index) + " is its own ancestor (the node tree has a cycle)");
        on_path[size_t(index)] = 1;
        const tinygltf::Node& node = model.nodes[size_t(index)];
        float local[16], world[16];
        local_transform(node, local);
        multiply_4x4(parent, local, world);
        if (node.mesh >= 0 && size_t(node.mesh) < mesh_parts.size()) {
            for (const uint32_t part : mesh_parts[size_t(node.mesh)]) {
                if (scene.instances.size() >= max_instances)
                    throw MeshError(path + ": the node tree gives more than " + std::to_string(max_instances) + " instances");
                Instance inst;
                inst.mesh = part;
                inst.node = uint32_t(index);
                inst.name = node.name;
                for (int k = 0; k < 16; ++k) inst.transform[k] = world[k];
                scene.instances.push_back(std::move(inst));
            }
        }
        for (const int child : node.children) visit(child, world);
        on_path[size_t(index)] = 0;
    }
};

} // namespace

bool has_texture_transform(const tinygltf::Model& model, int material) {
    if (material < 0 || size_t(material) >= model.materials.size()) return false;
    for (const TextureSlot& slot : texture_slots(model.materials[size_t(material)])) {
        const auto it = slot.extensions->find("KHR_texture_transform");
        if (it != slot.extensions->end() && it->second.IsObject()) return true;
    }
    return false;
}

std::string bake_texture_transform(const tinygltf::Model& model, int material, Mesh& mesh) {
    if (material < 0 || size_t(material) >= model.materials.size()) return "";
    const tinygltf::Value* chosen = nullptr;
    int set = 0;
    bool disagree = false;
    for (const TextureSlot& slot : texture_slots(model.materials[size_t(material)])) {
        const auto it = slot.extensions->find("KHR_texture_transform");
        if (it == slot.extensions->end() || !it->second.IsObject()) continue;
        if (!chosen) {
            chosen = &it->second;
            set = it->second.Get("texCoord").IsNumber() ? it->second.Get("texCoord").GetNumberAsInt() : slot.texcoord;
        } else if (!(it->second == *chosen)) {
            disagree = true;
        }
    }
    if (!chosen || set > 1) return "";
    std::vector<float>& uv = set == 1 ? mesh.texcoords1 : mesh.texcoords;
    if (uv.empty()) return "";
    auto pair = [&](const char* key, double a, double b, double out[2]) {
        out[0] = a, out[1] = b;
        const tinygltf::Value& v = chosen->Get(key);
        if (v.IsArray() && v.ArrayLen() == 2)
            for (int k = 0; k < 2; ++k) out[k] = v.Get(k).GetNumberAsDouble();
    };
    double offset[2], scale[2];
    pair("offset", 0, 0, offset);
    pair("scale", 1, 1, scale);
    const double r = chosen->Get("rotation").IsNumber() ? chosen->Get("rotation").GetNumberAsDouble() : 0.0;
    const double c = std::cos(r), s = std::sin(r);
    // uv' = T R S uv with R = [c s; -s c] (the extension's definition)
    for (size_t i = 0; i + 1 < uv.size(); i += 2) {
        const double x = scale[0] * uv[i], y = scale[1] * uv[i + 1];
        uv[i] = float(c * x + s * y + offset[0]);
        uv[i + 1] = float(-s * x + c * y + offset[1]);
    }
    return disagree ? "material " + std::to_string(material) + ": its textures carry different KHR_texture_transforms; the first was baked into TEXCOORD_" +
                          std::to_string(set)
                    : "";
}

Scene gltf_scene(const tinygltf::Model& model, const nlohmann::json& doc, const std::vector<std::vector<uint32_t>>& mesh_parts,
                 const EmbeddedImages& embedded, const std::string& path, TextureSources& textures) {
    Scene scene;
    MaterialReader reader{model, embedded, scene};
    for (const tinygltf::Material& m : model.materials) scene.materials.push_back(reader.material(m));
    textures.samplers = std::move(reader.samplers);
    // the textures of the material extensions kept, their images stored after the materials' own
    std::set<int> referred;
    if (doc.contains("materials") && doc["materials"].is_array())
        for (const nlohmann::json& m : doc["materials"])
            if (m.is_object() && m.contains("extensions") && m["extensions"].is_object())
                for (const auto& [name, value] : m["extensions"].items())
                    if (carries_material_extension(name)) texture_indices(value, referred);
    for (const int t : referred)
        if (const nlohmann::json d = reader.describe(t); !d.is_null()) textures.extension[t] = d.dump();
    const int which = model.defaultScene >= 0 ? model.defaultScene : 0;
    if (size_t(which) < model.scenes.size()) {
        Flattener f{model, mesh_parts, path, scene, std::vector<uint8_t>(model.nodes.size(), 0)};
        const Instance untransformed;  // its transform is the identity
        for (const int root : model.scenes[size_t(which)].nodes) f.visit(root, untransformed.transform);
        for (const Instance& inst : scene.instances)
            for (const float x : inst.transform)
                if (!std::isfinite(x)) throw MeshError(path + ": node " + std::to_string(inst.node) + " has a transform that is not finite");
    }
    return scene;
}

} // namespace tom::detail
