// What a glTF import keeps and what it names as dropped (see the header). The lists follow what
// the importer, the .tom format and the glTF exporter carry: geometry with the streams POSITION,
// NORMAL, TANGENT, TEXCOORD_0/1 and COLOR_0, every other attribute and the morph targets'
// deltas carried unread (sparse ones made dense);
// metallic-roughness materials and their textures;
// images (embedded ones stored, external ones by URI); the default scene's mesh nodes as
// instances with their names and world transforms.

#include "gltf_carried.h"

#include <algorithm>
#include <iterator>
#include <set>

namespace tom::detail {

namespace {

// decoded on import (compression, quantization, texture transforms baked into TEXCOORD) or
// carried through to the exported glTF (image codecs)
const std::set<std::string> carried_extensions = {
    "KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_mesh_quantization", "KHR_texture_transform",
    "EXT_texture_webp",           "KHR_texture_basisu",      "EXT_texture_avif",
};

const std::set<std::string> interpreted_attributes = {"POSITION", "NORMAL", "TANGENT", "TEXCOORD_0", "TEXCOORD_1", "COLOR_0"};

size_t size_of(const nlohmann::json& doc, const char* key) {
    const auto it = doc.find(key);
    return it != doc.end() && it->is_array() ? it->size() : 0;
}

// the top-level keys kept whole with the scene (tom::SourceGltf): their extras go along
const std::set<std::string> scene_keys = {"nodes", "scenes", "skins", "animations", "cameras", "samplers"};

// objects anywhere in the document with a non-empty "extras" (past the top level's `skip` keys;
// without `own`, not counting the object's own)
size_t count_extras(const nlohmann::json& j, const std::set<std::string>& skip = {}, bool own = true) {
    size_t n = 0;
    if (j.is_object()) {
        const auto it = j.find("extras");
        if (own && it != j.end() && !it->is_null() && !(it->is_object() && it->empty())) ++n;
        for (const auto& [key, value] : j.items())
            if (key != "extras" && !skip.count(key)) n += count_extras(value);
    } else if (j.is_array()) {
        for (const auto& value : j) n += count_extras(value);
    }
    return n;
}

std::string counted(const std::string& what, size_t n) { return what + " (" + std::to_string(n) + ")"; }

// meshes whose default morph weights are not all zero (the .tom keeps the deltas, not the weights)
size_t weighted_meshes(const nlohmann::json& doc) {
    size_t n = 0;
    const auto meshes = doc.find("meshes");
    if (meshes == doc.end() || !meshes->is_array()) return 0;
    for (const auto& mesh : *meshes) {
        const auto weights = mesh.find("weights");
        if (weights != mesh.end() && weights->is_array() &&
            std::any_of(weights->begin(), weights->end(), [](const nlohmann::json& w) { return !w.is_number() || w.get<double>() != 0.0; }))
            ++n;
    }
    return n;
}

// nodes of the default scene's tree that carry no mesh: the tree is flattened into instances
size_t nodes_without_mesh(const nlohmann::json& doc) {
    size_t n = 0;
    const auto nodes = doc.find("nodes");
    if (nodes == doc.end() || !nodes->is_array()) return 0;
    for (const auto& node : *nodes)
        if (node.is_object() && !node.contains("mesh")) ++n;
    return n;
}

// the names of the extensions some object of the document uses (keys of any "extensions" object):
// a name only declared in extensionsUsed loses nothing (exporters declare some they never use)
void extensions_in_use(const nlohmann::json& j, std::set<std::string>& out) {
    if (j.is_object()) {
        const auto it = j.find("extensions");
        if (it != j.end() && it->is_object())
            for (const auto& [name, value] : it->items()) out.insert(name);
        for (const auto& [key, value] : j.items()) extensions_in_use(value, out);
    } else if (j.is_array()) {
        for (const auto& value : j) extensions_in_use(value, out);
    }
}

// what a dropped extension costs, where part of it is kept
std::string dropped_extension(const std::string& name) {
    if (name == "KHR_materials_pbrSpecularGlossiness") return "extension " + name + " (its specular and glossiness; the diffuse is kept as the base colour)";
    return "extension " + name;
}

// texture-info properties the materials do not keep
void scan_materials(const nlohmann::json& doc, std::vector<std::string>& out) {
    const auto materials = doc.find("materials");
    if (materials == doc.end() || !materials->is_array()) return;
    size_t scaled = 0, strength = 0;
    for (const auto& m : *materials) {
        if (!m.is_object()) continue;
        const auto normal = m.find("normalTexture");
        if (normal != m.end() && normal->is_object() && normal->value("scale", 1.0) != 1.0) ++scaled;
        const auto occlusion = m.find("occlusionTexture");
        if (occlusion != m.end() && occlusion->is_object() && occlusion->value("strength", 1.0) != 1.0) ++strength;
    }
    if (scaled) out.push_back(counted("normalTexture scale", scaled));
    if (strength) out.push_back(counted("occlusionTexture strength", strength));
}

} // namespace

void texture_indices(const nlohmann::json& j, std::set<int>& out) {
    if (j.is_object()) {
        const auto index = j.find("index");
        if (index != j.end() && index->is_number_integer()) out.insert(index->get<int>());
        for (const auto& [key, value] : j.items()) texture_indices(value, out);
    } else if (j.is_array()) {
        for (const auto& value : j) texture_indices(value, out);
    }
}

bool carries_material_extension(const std::string& name) {
    // the specular-glossiness model is converted into the metallic-roughness one, and texture
    // transforms are baked into the texture coordinates: neither is kept
    return name != "KHR_materials_pbrSpecularGlossiness" && name != "KHR_texture_transform";
}

bool is_interpreted_attribute(const std::string& name) { return interpreted_attributes.count(name) != 0; }

bool can_read_required(const std::string& extension) {
    if (carried_extensions.count(extension)) return true;
    static const std::set<std::string> no_geometry = {"KHR_materials_pbrSpecularGlossiness", "KHR_materials_unlit", "KHR_lights_punctual",
                                                      "KHR_materials_variants", "KHR_xmp_json_ld", "EXT_lights_image_based"};
    return no_geometry.count(extension) || extension.rfind("KHR_materials_", 0) == 0;
}

std::vector<std::string> gltf_dropped(const nlohmann::json& doc, bool scene_kept, std::vector<std::string> also) {
    std::vector<std::string> out;
    if (!scene_kept) {
        if (const size_t n = size_of(doc, "skins")) out.push_back(counted("skins", n));
        if (const size_t n = size_of(doc, "animations")) out.push_back(counted("animations", n));
    }
    if (const size_t n = weighted_meshes(doc); n && !scene_kept) out.push_back("morph target weights (" + std::to_string(n) + (n == 1 ? " mesh)" : " meshes)"));
    if (!scene_kept) {
        if (const size_t n = size_of(doc, "cameras")) out.push_back(counted("cameras", n));
        if (const size_t n = size_of(doc, "scenes"); n > 1) out.push_back(counted("scenes other than the default", n - 1));
        if (const size_t n = nodes_without_mesh(doc))
            out.push_back("node tree (flattened into instances: " + std::to_string(n) + " node" + (n == 1 ? "" : "s") + " without a mesh)");
    }
    // with the scene kept, so are the lights and every material extension that refers to no texture
    std::set<std::string> kept;
    if (scene_kept) {
        kept.insert("KHR_lights_punctual");
        std::set<std::string> lost;
        const auto materials = doc.find("materials");
        if (materials != doc.end() && materials->is_array())
            for (const auto& m : *materials)
                if (m.is_object() && m.contains("extensions") && m["extensions"].is_object())
                    for (const auto& [name, value] : m["extensions"].items()) (carries_material_extension(name) ? kept : lost).insert(name);
        for (const std::string& name : lost) kept.erase(name);
    }
    std::set<std::string> in_use;
    extensions_in_use(doc, in_use);
    const auto used = doc.find("extensionsUsed");
    if (used != doc.end() && used->is_array())
        for (const auto& e : *used)
            if (e.is_string() && in_use.count(e.get<std::string>()) && !carried_extensions.count(e.get<std::string>()) && !kept.count(e.get<std::string>()))
                out.push_back(dropped_extension(e.get<std::string>()));
    scan_materials(doc, out);
    if (const size_t n = size_of(doc, "samplers"); n && !scene_kept) out.push_back(counted("texture samplers", n));
    // with the scene kept, so are its objects' extras and the materials' and meshes' own
    size_t extras = count_extras(doc, scene_kept ? scene_keys : std::set<std::string>{});
    for (const char* key : {"materials", "meshes"})
        if (scene_kept && doc.contains(key) && doc[key].is_array())
            for (const auto& m : doc[key]) extras -= count_extras(m) - count_extras(m, {}, false);
    if (extras) out.push_back(counted("extras", extras));
    const auto asset = doc.find("asset");
    if (!scene_kept && asset != doc.end() && asset->is_object() && asset->contains("copyright")) out.push_back("asset copyright");
    out.insert(out.end(), std::make_move_iterator(also.begin()), std::make_move_iterator(also.end()));
    return out;
}

} // namespace tom::detail
