// A glTF's scene beyond its meshes and materials, kept as it is (tom::SourceGltf, section GLTF):
// the node tree with its transforms, names, extensions and extras, the scenes, skins,
// animations, cameras, the lights of KHR_lights_punctual, the texture samplers, the materials'
// extensions (the textures they refer to described apart) and extras, the meshes' default morph weights and
// extras, and the asset's copyright. Nodes' `mesh` are renumbered to the
// imported meshes; the accessors that skins and animations read are copied, tightly packed, into
// one binary blob (buffer 0) with a buffer view each.

#include "gltf_source.h"

#include "gltf_carried.h"

#include <algorithm>
#include <cstring>

#include "tom/errors.h"

namespace tom::detail {

namespace {

using nlohmann::json;

// The accessors skins and animations read, in a fixed order, each with where in the fragment it
// is referenced (so the reference can be renumbered).
std::vector<json*> accessor_references(json& out) {
    std::vector<json*> refs;
    if (out.contains("skins"))
        for (json& skin : out["skins"])
            if (skin.is_object() && skin.contains("inverseBindMatrices")) refs.push_back(&skin["inverseBindMatrices"]);
    if (out.contains("animations"))
        for (json& animation : out["animations"])
            if (animation.is_object() && animation.contains("samplers"))
                for (json& sampler : animation["samplers"])
                    for (const char* key : {"input", "output"})
                        if (sampler.is_object() && sampler.contains(key)) refs.push_back(&sampler[key]);
    return refs;
}

int type_components(int type) {
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
    }
}

// Accessor `index` of the source, its elements appended to `blob` (4-byte aligned) with a
// buffer view of their own; false when it cannot be copied (sparse, or its data is missing).
bool copy_accessor(const tinygltf::Model& model, const json& doc, int index, std::vector<uint8_t>& blob, json& accessors, json& views) {
    if (index < 0 || size_t(index) >= model.accessors.size()) return false;
    const tinygltf::Accessor& a = model.accessors[size_t(index)];
    if (a.sparse.isSparse || a.bufferView < 0 || size_t(a.bufferView) >= model.bufferViews.size()) return false;
    const tinygltf::BufferView& view = model.bufferViews[size_t(a.bufferView)];
    if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size()) return false;
    const std::vector<unsigned char>& buffer = model.buffers[size_t(view.buffer)].data;
    const size_t elem = size_t(type_components(a.type)) * component_bytes(uint32_t(a.componentType));
    const size_t stride = view.byteStride ? view.byteStride : elem;
    if (elem == 0 || a.count == 0 || stride < elem) return false;
    const size_t start = view.byteOffset + a.byteOffset;
    if (view.byteOffset > buffer.size() || view.byteLength > buffer.size() - view.byteOffset || a.byteOffset > view.byteLength ||
        view.byteLength - a.byteOffset < elem || (a.count - 1) > (view.byteLength - a.byteOffset - elem) / stride)
        return false;
    while (blob.size() % 4) blob.push_back(0);
    const size_t offset = blob.size();
    for (size_t i = 0; i < a.count; ++i) blob.insert(blob.end(), buffer.begin() + long(start + i * stride), buffer.begin() + long(start + i * stride + elem));
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", a.count * elem}});
    json out = doc["accessors"][size_t(index)];
    out.erase("sparse");
    out.erase("byteOffset");
    out["bufferView"] = views.size() - 1;
    accessors.push_back(out);
    return true;
}

} // namespace

SourceGltf source_gltf(const tinygltf::Model& model, const json& doc, const std::vector<std::vector<uint32_t>>& mesh_parts,
                       const TextureSources& textures) {
    json out = json::object();
    const bool sampled = std::any_of(textures.samplers.begin(), textures.samplers.end(), [](int s) { return s >= 0; }) ||
                         std::any_of(textures.extension.begin(), textures.extension.end(), [](const auto& t) { return json::parse(t.second).contains("sampler"); });
    if (doc.contains("samplers") && sampled) {
        out["samplers"] = doc["samplers"];
        out["textureSamplers"] = json::array();
        for (const int s : textures.samplers) out["textureSamplers"].push_back(s >= 0 ? json(s) : json(nullptr));
    }
    if (!textures.extension.empty()) {
        out["extensionTextures"] = json::array();
        for (const auto& [t, description] : textures.extension) {
            while (out["extensionTextures"].size() < size_t(t)) out["extensionTextures"].push_back(nullptr);
            out["extensionTextures"].push_back(json::parse(description));
        }
    }
    for (const char* key : {"nodes", "scenes", "scene", "skins", "animations", "cameras"})
        if (doc.contains(key)) out[key] = doc[key];
    if (!out.contains("nodes") || !out["nodes"].is_array()) return {};
    if (doc.contains("asset") && doc["asset"].is_object() && doc["asset"].contains("copyright")) out["asset"] = {{"copyright", doc["asset"]["copyright"]}};
    // per material, the extensions that refer to no texture, and its extras
    if (doc.contains("materials") && doc["materials"].is_array()) {
        json kept = json::array();
        bool any = false;
        for (const json& m : doc["materials"]) {
            json one = json::object();
            if (m.is_object() && m.contains("extensions") && m["extensions"].is_object())
                for (const auto& [name, value] : m["extensions"].items())
                    if (carries_material_extension(name)) one["extensions"][name] = value;
            if (m.is_object() && m.contains("extras")) one["extras"] = m["extras"];
            any = any || !one.empty();
            kept.push_back(one);
        }
        if (any) out["materialExtensions"] = kept;
    }
    // per imported mesh, its glTF mesh's default morph weights and extras
    if (doc.contains("meshes") && doc["meshes"].is_array()) {
        json kept = json::array();
        bool any = false;
        for (size_t gm = 0; gm < mesh_parts.size() && gm < doc["meshes"].size(); ++gm) {
            const json& m = doc["meshes"][gm];
            for (size_t k = 0; k < mesh_parts[gm].size(); ++k) {
                json one = json::object();
                if (m.is_object() && m.contains("weights") && m["weights"].is_array()) one["weights"] = m["weights"];
                if (m.is_object() && m.contains("extras")) one["extras"] = m["extras"];
                any = any || !one.empty();
                kept.push_back(one);
            }
        }
        if (any) out["meshes"] = kept;
    }
    // the lights (KHR_lights_punctual's root list; the nodes keep their references)
    if (doc.contains("extensions") && doc["extensions"].is_object() && doc["extensions"].contains("KHR_lights_punctual"))
        out["extensions"] = {{"KHR_lights_punctual", doc["extensions"]["KHR_lights_punctual"]}};
    for (json& node : out["nodes"]) {
        if (!node.is_object() || !node.contains("mesh")) continue;
        const json& m = node["mesh"];
        if (m.is_number_unsigned() && m.get<size_t>() < mesh_parts.size() && !mesh_parts[m.get<size_t>()].empty())
            node["mesh"] = mesh_parts[m.get<size_t>()][0];
        else
            node.erase("mesh");  // a mesh without triangles (points, lines): not converted
    }
    std::vector<uint8_t> blob;
    json accessors = json::array(), views = json::array();
    for (json* ref : accessor_references(out)) {
        if (!ref->is_number_unsigned() || !copy_accessor(model, doc, ref->get<int>(), blob, accessors, views)) return {};
        *ref = accessors.size() - 1;
    }
    out["accessors"] = accessors;
    out["bufferViews"] = views;
    SourceGltf gltf;
    gltf.json = out.dump();
    auto held = std::make_shared<const std::vector<uint8_t>>(std::move(blob));
    gltf.data = held->data();
    gltf.bytes = held->size();
    gltf.owner = std::move(held);
    return gltf;
}

} // namespace tom::detail
