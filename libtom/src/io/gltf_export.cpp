// Binary glTF 2.0 output of TOM levels, with MSFT_lod for several (glTF 2.0 specification;
// MSFT_lod extension specification).

#include <algorithm>
#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>

#include "tom/errors.h"
#include "tom/export.h"
#include "tom/extract.h"
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

} // namespace

void export_glb(const std::string& path, const std::vector<GlbMesh>& meshes) {
    Writer w;
    size_t levels = 0;
    for (const GlbMesh& m : meshes) levels = std::max(levels, m.vertex_counts.size());
    if (levels == 0) throw IoError("cannot write '" + path + "': no resolution requested");
    std::vector<json> level_primitives(levels, json::array());
    int max_material = -1;
    for (const GlbMesh& gm : meshes) {
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
        for (size_t level = 0; level < gm.vertex_counts.size(); ++level) {
            const Extracted e = extract(m, std::min(gm.vertex_counts[level], m.vertex_count), indices.data(), indices.size());
            if (e.triangle_count == 0) continue;
            const size_t count = size_t(e.triangle_count) * 3;
            int view_index;
            int component;
            if (e.vertex_count <= 65535) {  // 16-bit, 65535 itself being reserved by glTF for restart
                std::vector<uint16_t> small(indices.begin(), indices.begin() + ptrdiff_t(count));
                view_index = w.view(small.data(), count * 2, kElementArrayBuffer);
                component = kUint16;
            } else {
                view_index = w.view(indices.data(), count * 4, kElementArrayBuffer);
                component = kUint32;
            }
            json primitive = {{"attributes", attributes}, {"indices", w.accessor(view_index, component, count, "SCALAR")}, {"mode", 4}};
            if (m.material >= 0) {
                primitive["material"] = m.material;
                max_material = std::max(max_material, m.material);
            }
            level_primitives[level].push_back(primitive);
        }
    }
    json doc;
    doc["asset"] = {{"version", "2.0"}, {"generator", "libtom (tomextract)"}};
    doc["meshes"] = json::array();
    doc["nodes"] = json::array();
    for (size_t level = 0; level < levels; ++level) {
        if (level_primitives[level].empty()) throw IoError("cannot write '" + path + "': level " + std::to_string(level) + " has no triangles");
        doc["meshes"].push_back({{"name", "level " + std::to_string(level)}, {"primitives", level_primitives[level]}});
        doc["nodes"].push_back({{"name", level == 0 ? std::string("tom") : "tom lod " + std::to_string(level)}, {"mesh", level}});
    }
    if (levels > 1) {
        json ids = json::array();
        for (size_t level = 1; level < levels; ++level) ids.push_back(level);
        doc["nodes"][0]["extensions"] = {{"MSFT_lod", {{"ids", ids}}}};
        doc["extensionsUsed"] = {"MSFT_lod"};
    }
    doc["scenes"] = {{{"nodes", {0}}}};
    doc["scene"] = 0;
    if (max_material >= 0) {
        doc["materials"] = json::array();
        for (int k = 0; k <= max_material; ++k) doc["materials"].push_back({{"name", "material " + std::to_string(k)}});
    }
    while (w.bin.size() % 4) w.bin.push_back(0);
    doc["buffers"] = {{{"byteLength", w.bin.size()}}};
    doc["bufferViews"] = w.views;
    doc["accessors"] = w.accessors;
    std::string text = doc.dump();
    while (text.size() % 4) text.push_back(' ');
    // GLB: header, JSON chunk, BIN chunk
    std::vector<uint8_t> out;
    auto put32 = [&](uint32_t v) {
        for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
    };
    const uint32_t total = uint32_t(12 + 8 + text.size() + 8 + w.bin.size());
    out.insert(out.end(), {'g', 'l', 'T', 'F'});
    put32(2);
    put32(total);
    put32(uint32_t(text.size()));
    put32(0x4E4F534A);  // JSON
    out.insert(out.end(), text.begin(), text.end());
    put32(uint32_t(w.bin.size()));
    put32(0x004E4942);  // BIN
    out.insert(out.end(), w.bin.begin(), w.bin.end());
    write_bytes_atomically(path, out.data(), out.size());
}

} // namespace tom
