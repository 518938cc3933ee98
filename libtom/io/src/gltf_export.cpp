// Binary glTF 2.0 output of TOM levels, with MSFT_lod for several (glTF 2.0 specification;
// MSFT_lod extension specification).

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>

#include <nlohmann/json.hpp>

#include "glb.h"
#include "tom/errors.h"
#include "tom/io/export.h"
#include "tom/extract.h"
#include "tom/builder/writer.h"
#include "tom/format.h"

namespace tom {

namespace {

using nlohmann::json;

constexpr int kFloat = 5126, kUint16 = 5123, kUint32 = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

struct Writer {
    std::vector<uint8_t> bin;
    json views = json::array(), accessors = json::array();

    int view(const void* data, size_t bytes, int target) {
        while (bin.size() % 4) bin.push_back(0);
        const size_t offset = bin.size();
        bin.insert(bin.end(), static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + bytes);
        views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}, {"target", target}});
        return int(views.size() - 1);
    }
    int accessor(int view_index, int component, size_t count, const char* type, json extra = json::object()) {
        json a = {{"bufferView", view_index}, {"componentType", component}, {"count", count}, {"type", type}};
        a.update(extra);
        accessors.push_back(a);
        return int(accessors.size() - 1);
    }
};

// glTF requires unit normals and tangents, and a tangent's w of exactly +-1: copies of the first
// `count` vectors of `width` 3 (normals) or 4 (tangents), normalised (a zero vector becomes +z / +x).
std::vector<float> unit_vectors(const float* src, uint32_t count, size_t width) {
    std::vector<float> out(src, src + size_t(count) * width);
    for (size_t v = 0; v < out.size(); v += width) {
        float* q = &out[v];
        const float len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        if (len > 0) q[0] /= len, q[1] /= len, q[2] /= len;
        else if (width == 3) q[0] = 0, q[1] = 0, q[2] = 1;
        else q[0] = 1, q[1] = 0, q[2] = 0;
        if (width == 4) q[3] = q[3] < 0 ? -1.0f : 1.0f;
    }
    return out;
}

// The scene's materials (factors, and textures whose images are files: `texture_dir` is the folder
// their stored URIs are relative to, rewritten relative to the output; empty keeps them as
// stored); placeholders when the file stores no materials but meshes refer to some.
void write_materials(json& doc, const Scene& scene, int max_material, const std::string& texture_dir, const std::string& path) {
    if (scene.materials.empty()) {
        if (max_material < 0) return;
        doc["materials"] = json::array();
        for (int k = 0; k <= max_material; ++k) doc["materials"].push_back({{"name", "material " + std::to_string(k)}});
        return;
    }
    if (size_t(max_material + 1) > scene.materials.size())
        throw IoError("cannot write '" + path + "': a mesh refers to material " + std::to_string(max_material) + " of " + std::to_string(scene.materials.size()));
    namespace fs = std::filesystem;
    const fs::path out_dir = fs::absolute(fs::path(path)).parent_path();
    json images = json::array(), textures = json::array();
    std::map<std::string, int> texture_of;  // one glTF texture per distinct URI
    doc["materials"] = json::array();
    for (const Material& m : scene.materials) {
        json pbr = {{"baseColorFactor", m.base_color}, {"metallicFactor", m.metallic}, {"roughnessFactor", m.roughness}};
        json mat = {{"name", m.name}, {"pbrMetallicRoughness", json::object()}};
        if (m.emissive[0] != 0 || m.emissive[1] != 0 || m.emissive[2] != 0) mat["emissiveFactor"] = m.emissive;
        if (m.alpha_mode != AlphaMode::opaque) mat["alphaMode"] = m.alpha_mode == AlphaMode::mask ? "MASK" : "BLEND";
        if (m.alpha_mode == AlphaMode::mask) mat["alphaCutoff"] = m.alpha_cutoff;
        if (m.double_sided) mat["doubleSided"] = true;
        for (const TextureRef& t : m.textures) {
            if (t.uri.empty()) continue;  // embedded in the source: not kept
            std::string uri = t.uri;
            if (!texture_dir.empty() && uri.find("://") == std::string::npos)
                uri = fs::relative(fs::absolute(fs::path(texture_dir) / uri), out_dir).generic_string();
            auto [it, fresh] = texture_of.emplace(uri, int(textures.size()));
            if (fresh) {
                json image = {{"uri", uri}};
                images.push_back(image);
                textures.push_back({{"source", images.size() - 1}});
            }
            const json info = {{"index", it->second}, {"texCoord", t.texcoord}};
            switch (t.role) {
            case TextureRole::base_color: pbr["baseColorTexture"] = info; break;
            case TextureRole::metallic_roughness: pbr["metallicRoughnessTexture"] = info; break;
            case TextureRole::normal: mat["normalTexture"] = info; break;
            case TextureRole::occlusion: mat["occlusionTexture"] = info; break;
            case TextureRole::emissive: mat["emissiveTexture"] = info; break;
            }
        }
        mat["pbrMetallicRoughness"] = pbr;
        doc["materials"].push_back(mat);
    }
    if (!images.empty()) {
        doc["images"] = images;
        doc["textures"] = textures;
    }
}

} // namespace

void export_glb(const std::string& path, const std::vector<GlbMesh>& meshes, const Scene& scene, const std::string& texture_dir) {
    Writer w;
    size_t levels = 0;
    for (const GlbMesh& m : meshes) levels = std::max(levels, m.vertex_counts.size());
    if (levels == 0) throw IoError("cannot write '" + path + "': no resolution requested");
    for (const Instance& inst : scene.instances)
        if (inst.mesh >= meshes.size()) throw IoError("cannot write '" + path + "': an instance names mesh " + std::to_string(inst.mesh) + " of " + std::to_string(meshes.size()));
    // glTF mesh of (input mesh, level), -1 where that level has no triangles
    std::vector<std::vector<int>> level_mesh(meshes.size(), std::vector<int>(levels, -1));
    json gltf_meshes = json::array();
    int max_material = -1;
    for (size_t mi = 0; mi < meshes.size(); ++mi) {
        const GlbMesh& gm = meshes[mi];
        const MeshView& m = *gm.mesh;
        uint32_t n_max = 0;
        for (uint32_t n : gm.vertex_counts) n_max = std::max(n_max, std::min(n, m.vertex_count));
        if (n_max == 0) continue;
        // vertex streams, shared by every level of this mesh
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint32_t v = 0; v < n_max; ++v)
            for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], m.positions[3 * size_t(v) + k]), hi[k] = std::max(hi[k], m.positions[3 * size_t(v) + k]);
        json attributes;
        attributes["POSITION"] = w.accessor(w.view(m.positions, size_t(n_max) * 12, kArrayBuffer), kFloat, n_max, "VEC3",
                                            {{"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}});
        if (m.normals) {
            const std::vector<float> normals = unit_vectors(m.normals, n_max, 3);
            attributes["NORMAL"] = w.accessor(w.view(normals.data(), normals.size() * 4, kArrayBuffer), kFloat, n_max, "VEC3");
        }
        if (m.texcoords) attributes["TEXCOORD_0"] = w.accessor(w.view(m.texcoords, size_t(n_max) * 8, kArrayBuffer), kFloat, n_max, "VEC2");
        if (m.colors) attributes["COLOR_0"] = w.accessor(w.view(m.colors, size_t(n_max) * 16, kArrayBuffer), kFloat, n_max, "VEC4");
        if (m.texcoords1) attributes["TEXCOORD_1"] = w.accessor(w.view(m.texcoords1, size_t(n_max) * 8, kArrayBuffer), kFloat, n_max, "VEC2");
        if (m.tangents && m.normals) {
            const std::vector<float> tangents = unit_vectors(m.tangents, n_max, 4);
            attributes["TANGENT"] = w.accessor(w.view(tangents.data(), tangents.size() * 4, kArrayBuffer), kFloat, n_max, "VEC4");
        }
        std::vector<uint32_t> indices(size_t(m.triangle_count) * 3);
        std::vector<PartDraw> draws(part_count(m));
        for (size_t level = 0; level < gm.vertex_counts.size(); ++level) {
            const Extracted e = extract_parts(m, std::min(gm.vertex_counts[level], m.vertex_count), indices.data(), indices.size(), draws.data());
            if (e.triangle_count == 0) continue;
            // one primitive per part that has triangles at this level, with the streams its source had
            json primitives = json::array();
            for (uint32_t p = 0; p < draws.size(); ++p) {
                const PartDraw& d = draws[p];
                if (d.index_count == 0) continue;
                const uint32_t* part_indices = indices.data() + d.first_index;
                int view_index;
                int component;
                if (e.vertex_count <= 65535) {  // 16-bit, 65535 itself being reserved by glTF for restart
                    std::vector<uint16_t> small(part_indices, part_indices + d.index_count);
                    view_index = w.view(small.data(), size_t(d.index_count) * 2, kElementArrayBuffer);
                    component = kUint16;
                } else {
                    view_index = w.view(part_indices, size_t(d.index_count) * 4, kElementArrayBuffer);
                    component = kUint32;
                }
                json own = attributes;
                if (m.parts) {
                    const uint32_t streams = part_at(m, p).attributes;
                    const std::pair<const char*, uint32_t> optional[] = {{"TEXCOORD_0", 2}, {"COLOR_0", 4}, {"TEXCOORD_1", 8}, {"TANGENT", 16}};
                    for (const auto& [key, bit] : optional)
                        if (!(streams & bit)) own.erase(key);
                }
                json primitive = {{"attributes", own}, {"indices", w.accessor(view_index, component, d.index_count, "SCALAR")}, {"mode", 4}};
                if (d.material >= 0) {
                    primitive["material"] = d.material;
                    max_material = std::max(max_material, d.material);
                }
                primitives.push_back(primitive);
            }
            level_mesh[mi][level] = int(gltf_meshes.size());
            const std::string name(m.name);
            gltf_meshes.push_back({{"name", levels > 1 ? name + " level " + std::to_string(level) : name}, {"primitives", primitives}});
        }
    }
    json doc;
    doc["asset"] = {{"version", "2.0"}, {"generator", "libtom (tomextract)"}};
    doc["meshes"] = gltf_meshes;
    // one node per instance (each mesh once, untransformed, without a scene); with several levels,
    // its coarser levels follow it as nodes of their own listed by its MSFT_lod extension
    doc["nodes"] = json::array();
    json roots = json::array();
    const Instance untransformed;  // its transform is the identity
    for (const Instance& inst : draw_list(scene, uint32_t(meshes.size()))) {
        const std::vector<int>& lm = level_mesh[inst.mesh];
        if (lm[0] < 0) continue;
        auto node_of = [&](int mesh, const std::string& name) {
            json node = {{"mesh", mesh}};
            if (!name.empty()) node["name"] = name;
            if (!std::equal(inst.transform, inst.transform + 16, untransformed.transform)) node["matrix"] = inst.transform;
            return node;
        };
        const size_t index = doc["nodes"].size();
        roots.push_back(index);
        doc["nodes"].push_back(node_of(lm[0], inst.name));
        json ids = json::array();
        for (size_t level = 1; level < levels; ++level) {
            if (lm[level] < 0) continue;
            ids.push_back(doc["nodes"].size());
            doc["nodes"].push_back(node_of(lm[level], inst.name.empty() ? std::string() : inst.name + " lod " + std::to_string(level)));
        }
        if (!ids.empty()) {
            doc["nodes"][index]["extensions"] = {{"MSFT_lod", {{"ids", ids}}}};
            doc["extensionsUsed"] = {"MSFT_lod"};
        }
    }
    if (roots.empty()) throw IoError("cannot write '" + path + "': no mesh has a triangle at the finest level requested");
    doc["scenes"] = {{{"nodes", roots}}};
    doc["scene"] = 0;
    write_materials(doc, scene, max_material, texture_dir, path);
    while (w.bin.size() % 4) w.bin.push_back(0);
    doc["buffers"] = {{{"byteLength", w.bin.size()}}};
    doc["bufferViews"] = w.views;
    doc["accessors"] = w.accessors;
    const std::vector<uint8_t> out = detail::glb_bytes(doc.dump(), &w.bin);
    write_bytes_atomically(path, out.data(), out.size());
}

} // namespace tom
