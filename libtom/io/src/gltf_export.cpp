// Binary glTF 2.0 output of TOM levels, with MSFT_lod for several (glTF 2.0 specification;
// MSFT_lod extension specification).

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "glb.h"
#include "import_backends.h"
#include "tom/errors.h"
#include "tom/io/export.h"
#include "tom/extract.h"
#include "tom/builder/writer.h"
#include "tom/format.h"
#include "gltf_compress.h"

namespace tom {

namespace {

using nlohmann::json;
using detail::encode_attributes;
using detail::encode_triangles;

constexpr int kFloat = 5126, kInt8 = 5120, kUint8 = 5121, kUint16 = 5123, kUint32 = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

struct Writer {
    std::vector<uint8_t> bin;
    json views = json::array(), accessors = json::array();
    bool compress = false;  // vertex and index views through EXT_meshopt_compression
    size_t fallback = 0;    // then the bytes of the fallback buffer (1) their views lie in

    // A view of `count` vertex elements of `bytes` bytes each, `stride` apart (a multiple of 4):
    // the bytes themselves, or compressed their encoding, the view itself in the fallback buffer.
    // `filter`: the EXT_meshopt_compression filter whose encoding `data` holds (compressed only).
    int vertex_view(const void* data, size_t count, size_t bytes, size_t stride, const char* filter = nullptr) {
        if (!compress) {
            const int v = view(data, count * stride, kArrayBuffer);
            if (stride != bytes) views[size_t(v)]["byteStride"] = stride;
            return v;
        }
        const int v = compressed_view(encode_attributes(data, count, stride), count, stride, "ATTRIBUTES", kArrayBuffer);
        views[size_t(v)]["byteStride"] = stride;
        if (filter) views[size_t(v)]["extensions"]["EXT_meshopt_compression"]["filter"] = filter;
        return v;
    }
    // A view of `count` indices of `stride` bytes (a triangle list).
    int index_view(const void* data, size_t count, size_t stride) {
        if (!compress) return view(data, count * stride, kElementArrayBuffer);
        return compressed_view(encode_triangles(data, count, stride), count, stride, "TRIANGLES", kElementArrayBuffer);
    }

    int view(const void* data, size_t bytes, int target) {
        while (bin.size() % 4) bin.push_back(0);
        const size_t offset = bin.size();
        bin.insert(bin.end(), static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + bytes);
        views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}});
        if (target) views.back()["target"] = target;  // 0: an image's bytes, no vertex or index data
        return int(views.size() - 1);
    }
    int compressed_view(const std::vector<uint8_t>& encoded, size_t count, size_t stride, const char* mode, int target) {
        while (bin.size() % 4) bin.push_back(0);
        const size_t offset = bin.size();
        bin.insert(bin.end(), encoded.begin(), encoded.end());
        fallback = (fallback + 3) / 4 * 4;
        views.push_back({{"buffer", 1},
                         {"byteOffset", fallback},
                         {"byteLength", count * stride},
                         {"target", target},
                         {"extensions",
                          {{"EXT_meshopt_compression",
                            {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", encoded.size()}, {"byteStride", stride}, {"mode", mode}, {"count", count}}}}}});
        fallback += count * stride;
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

// The carried streams of `m` (its first `count` vertices): attributes by their names, and
// "TARGET<k>/<ATTRIBUTE>" as morph target k's attribute. Elements are padded to a multiple of 4
// bytes (glTF's vertex alignment); a target's POSITION has its bounds, as glTF requires.
void write_carried_streams(Writer& w, const MeshView& m, const detail::VertexOrder& order, json& attributes, json& targets) {
    static const char* const types[] = {"SCALAR", "VEC2", "VEC3", "VEC4"};
    const uint32_t count = uint32_t(order.order.size());
    for (uint32_t k = 0; k < m.extra_stream_count; ++k) {
        const VertexStreamView& x = m.extra_streams[k];
        const uint32_t elem = x.components * component_bytes(x.component_type), stride = (elem + 3) / 4 * 4;
        const std::vector<uint8_t> bytes = detail::gather(x.data, elem, stride, order);
        const int view = w.vertex_view(bytes.data(), count, elem, stride);
        json extra = json::object();
        if (x.normalized) extra["normalized"] = true;
        const std::string name(x.name);
        const size_t slash = name.find('/');
        const bool target = name.rfind("TARGET", 0) == 0 && slash != std::string::npos;
        const std::string attribute = target ? name.substr(slash + 1) : name;
        if (target && attribute == "POSITION" && x.component_type == uint32_t(kFloat) && x.components == 3 && count > 0) {
            float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            for (uint32_t v = 0; v < count; ++v)
                for (int c = 0; c < 3; ++c) {
                    float f;
                    std::memcpy(&f, x.data + size_t(v) * elem + 4 * size_t(c), 4);
                    lo[c] = std::min(lo[c], f), hi[c] = std::max(hi[c], f);
                }
            extra["min"] = {lo[0], lo[1], lo[2]};
            extra["max"] = {hi[0], hi[1], hi[2]};
        }
        const int accessor = w.accessor(view, int(x.component_type), count, types[x.components - 1], extra);
        if (!target) {
            attributes[attribute] = accessor;
            continue;
        }
        const size_t index = size_t(std::strtoul(name.c_str() + 6, nullptr, 10));
        while (targets.size() <= index) targets.push_back(json::object());
        targets[index][attribute] = accessor;
    }
}

// One mesh's vertex streams, written once and shared by its levels: their accessors, the order
// its vertices are in, and with quantized positions the dequantization its nodes take (null:
// positions as they are).
struct MeshStreams {
    json attributes = json::object(), targets = json::array();
    detail::VertexOrder order;
    json dequantize;
};

detail::VertexOrder identity_order(uint32_t n) {
    detail::VertexOrder o;
    o.order.resize(n);
    for (uint32_t v = 0; v < n; ++v) o.order[v] = v;
    o.remap = o.order;
    return o;
}

// The streams of `m`'s first `n` vertices as they are, floats (normals and tangents made unit).
void write_float_streams(Writer& w, const MeshView& m, uint32_t n, MeshStreams& s) {
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t v = 0; v < n; ++v)
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], m.positions[3 * size_t(v) + k]), hi[k] = std::max(hi[k], m.positions[3 * size_t(v) + k]);
    json& a = s.attributes;
    a["POSITION"] = w.accessor(w.view(m.positions, size_t(n) * 12, kArrayBuffer), kFloat, n, "VEC3", {{"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}});
    if (m.normals) {
        const std::vector<float> normals = unit_vectors(m.normals, n, 3);
        a["NORMAL"] = w.accessor(w.view(normals.data(), normals.size() * 4, kArrayBuffer), kFloat, n, "VEC3");
    }
    if (m.texcoords) a["TEXCOORD_0"] = w.accessor(w.view(m.texcoords, size_t(n) * 8, kArrayBuffer), kFloat, n, "VEC2");
    if (m.colors) a["COLOR_0"] = w.accessor(w.view(m.colors, size_t(n) * 16, kArrayBuffer), kFloat, n, "VEC4");
    if (m.texcoords1) a["TEXCOORD_1"] = w.accessor(w.view(m.texcoords1, size_t(n) * 8, kArrayBuffer), kFloat, n, "VEC2");
    if (m.tangents && m.normals) {
        const std::vector<float> tangents = unit_vectors(m.tangents, n, 4);
        a["TANGENT"] = w.accessor(w.view(tangents.data(), tangents.size() * 4, kArrayBuffer), kFloat, n, "VEC4");
    }
}

// The same streams quantized (gltf_compress.h) in `s.order`, through compressed views;
// positions on the grid when `grid`, else floats.
void write_quantized_streams(Writer& w, const MeshView& m, bool grid, MeshStreams& s) {
    const detail::VertexOrder& order = s.order;
    const size_t n = order.order.size();
    const json normalized = {{"normalized", true}};
    json& a = s.attributes;
    if (grid) {
        const detail::QuantizedPositions q = detail::quantize_positions(m.positions, order);
        a["POSITION"] = w.accessor(w.vertex_view(q.values.data(), n, 6, 8), kUint16, n, "VEC3",
                                   {{"min", {q.lo[0], q.lo[1], q.lo[2]}}, {"max", {q.hi[0], q.hi[1], q.hi[2]}}});
        s.dequantize = q.dequantize;
    } else {
        std::vector<float> p(n * 3);
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t i = 0; i < n; ++i)
            for (int k = 0; k < 3; ++k) {
                p[3 * i + size_t(k)] = m.positions[3 * size_t(order.order[i]) + size_t(k)];
                lo[k] = std::min(lo[k], p[3 * i + size_t(k)]), hi[k] = std::max(hi[k], p[3 * i + size_t(k)]);
            }
        a["POSITION"] = w.accessor(w.vertex_view(p.data(), n, 12, 12), kFloat, n, "VEC3", {{"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}});
    }
    if (m.normals) {
        const std::vector<int8_t> q = detail::octahedral_unit_vectors(m.normals, 3, order);
        a["NORMAL"] = w.accessor(w.vertex_view(q.data(), n, 3, 4, "OCTAHEDRAL"), kInt8, n, "VEC3", normalized);
    }
    auto texcoords = [&](const float* uv, const char* key) {
        const std::vector<uint16_t> q = detail::quantize_texcoords(uv, order);
        if (!q.empty()) {
            a[key] = w.accessor(w.vertex_view(q.data(), n, 4, 4), kUint16, n, "VEC2", normalized);
            return;
        }
        const std::vector<uint8_t> f = detail::gather(reinterpret_cast<const uint8_t*>(uv), 8, 8, order);  // outside [0, 1]: floats
        a[key] = w.accessor(w.vertex_view(f.data(), n, 8, 8), kFloat, n, "VEC2");
    };
    if (m.texcoords) texcoords(m.texcoords, "TEXCOORD_0");
    if (m.colors) {
        const std::vector<uint8_t> q = detail::quantize_colors(m.colors, order);
        a["COLOR_0"] = w.accessor(w.vertex_view(q.data(), n, 4, 4), kUint8, n, "VEC4", normalized);
    }
    if (m.texcoords1) texcoords(m.texcoords1, "TEXCOORD_1");
    if (m.tangents && m.normals) {
        const std::vector<int8_t> q = detail::octahedral_unit_vectors(m.tangents, 4, order);
        a["TANGENT"] = w.accessor(w.vertex_view(q.data(), n, 4, 4, "OCTAHEDRAL"), kInt8, n, "VEC4", normalized);
    }
}

// The vertex streams of `m`'s first `n` vertices. Compressed, in the order its finest level
// `finest` first uses them, quantized; positions on the grid unless `float_positions` (a skinned
// mesh, whose nodes' transforms skinning ignores, or a morphed one, whose deltas are floats).
MeshStreams write_streams(Writer& w, const MeshView& m, uint32_t n, const std::vector<uint32_t>& finest, bool float_positions) {
    MeshStreams s;
    if (w.compress) {
        s.order = detail::fetch_order(finest, n);
        write_quantized_streams(w, m, !float_positions, s);
    } else {
        s.order = identity_order(n);
        write_float_streams(w, m, n, s);
    }
    write_carried_streams(w, m, s.order, s.attributes, s.targets);
    return s;
}

// A level's own vertex streams (POSITION, NORMAL, TEXCOORD_0/1, COLOR_0, TANGENT: those of
// `level`, a view of the same mesh) in `shared`'s vertex order, written as write_streams writes
// the mesh's; `dequantize` gets their grid's.
json level_streams(Writer& w, const MeshView& level, const MeshStreams& shared, bool grid, json& dequantize) {
    MeshStreams s;
    s.order = shared.order;
    if (w.compress)
        write_quantized_streams(w, level, grid, s);
    else
        write_float_streams(w, level, uint32_t(s.order.order.size()), s);
    dequantize = s.dequantize;
    return s.attributes;
}

// KHR_mesh_quantization's positions lie on a grid whose offset and scale the node that draws
// the mesh applies. A node without children, animation or a translation/rotation/scale takes
// the dequantization into its matrix; any other hands its mesh to a new child that carries it
// alone (so neither its children nor its animation see it). `dequantize`: per glTF mesh.
void place_dequantization(json& doc, const std::vector<json>& dequantize) {
    std::set<size_t> animated;
    if (doc.contains("animations"))
        for (const json& animation : doc["animations"])
            for (const json& channel : animation.value("channels", json::array()))
                if (channel.is_object() && channel.contains("target") && channel["target"].is_object() && channel["target"].contains("node") &&
                    channel["target"]["node"].is_number_unsigned())
                    animated.insert(channel["target"]["node"].get<size_t>());
    json& nodes = doc["nodes"];
    const size_t count = nodes.size();
    for (size_t i = 0; i < count; ++i) {
        if (!nodes[i].contains("mesh")) continue;
        const json& d = dequantize.at(nodes[i]["mesh"].get<size_t>());
        if (d.is_null()) continue;
        const bool own = !nodes[i].contains("children") && !animated.count(i) && !nodes[i].contains("translation") && !nodes[i].contains("rotation") &&
                         !nodes[i].contains("scale");
        if (own) {
            float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}, q[16], out[16];
            if (nodes[i].contains("matrix"))
                for (int k = 0; k < 16; ++k) m[k] = nodes[i]["matrix"][size_t(k)].get<float>();
            for (int k = 0; k < 16; ++k) q[k] = d[size_t(k)].get<float>();
            multiply_4x4(m, q, out);
            nodes[i]["matrix"] = out;
            continue;
        }
        const json child = {{"mesh", nodes[i]["mesh"]}, {"matrix", d}};
        nodes[i].erase("mesh");
        nodes[i]["children"].push_back(nodes.size());
        nodes.push_back(child);
    }
}

// The glTF texture of an image of type `mime`: image codecs past PNG and JPEG are shown through
// their extension (which the output then uses and requires: it has no fallback image).
const char* image_extension(const std::string& mime) {
    if (mime == "image/webp") return "EXT_texture_webp";
    if (mime == "image/ktx2") return "KHR_texture_basisu";
    if (mime == "image/avif") return "EXT_texture_avif";
    return nullptr;
}

// The bytes of an image file to embed (the importers' reader), the error naming the output too.
std::vector<uint8_t> read_image_file(const std::filesystem::path& file, const std::string& path) {
    try {
        return detail::read_whole_file(file.string());
    } catch (const IoError& e) {
        throw IoError("cannot write '" + path + "': cannot read image '" + file.string() + "' to embed it (" + e.what() + ")");
    }
}

// The scene's materials with their factors and textures. Images stored in the file are embedded
// in the binary buffer; images that were files keep their URIs (`texture_dir`: the folder those
// are relative to, rewritten relative to the output; empty keeps them as stored), or are read and
// embedded too with `embed_external`. Every material a mesh refers to must be stored.
struct MaterialWriter {
    Writer& w;
    const Scene& scene;
    const std::string& texture_dir;
    bool embed_external;
    const std::string& path;
    const json* source = nullptr;             // the stored glTF scene: its samplers and each texture reference's
    json images = json::array(), textures = json::array();
    std::map<std::string, int> texture_of{};  // one glTF texture per image ("#k" for stored image k, else its URI) and sampler
    std::set<std::string> extensions{};       // used and required
    std::set<std::string> used{};             // used only
    size_t reference = 0;                     // the texture reference being written, counted over all materials

    // the sampler of the current texture reference (the source's), or -1
    int sampler_of_reference() const {
        if (!source || !source->contains("textureSamplers")) return -1;
        const json& list = (*source)["textureSamplers"];
        if (reference >= list.size() || !list[reference].is_number_unsigned()) return -1;
        const size_t s = list[reference].get<size_t>();
        return source->contains("samplers") && s < (*source)["samplers"].size() ? int(s) : -1;
    }

    // a glTF image (and its texture, with the source's `sampler` or none) for reference `t`; -1
    // when it has neither bytes nor a URI
    int texture_for(const TextureRef& t, int sampler) {
        namespace fs = std::filesystem;
        std::string key = t.image >= 0 ? "#" + std::to_string(t.image) : t.uri;
        if (key.empty()) return -1;
        fs::path file;
        if (t.image < 0) {
            std::string uri = t.uri;
            std::replace(uri.begin(), uri.end(), '\\', '/');
            const bool local = uri.find("://") == std::string::npos;
            if (local && !texture_dir.empty()) file = fs::absolute(fs::path(texture_dir) / uri);
            else if (local) file = fs::path(uri);
            if (local && !texture_dir.empty() && !embed_external)
                key = fs::relative(file, fs::absolute(fs::path(path)).parent_path()).generic_string();
        }
        const auto [it, fresh] = texture_of.emplace(key + "|" + std::to_string(sampler), int(textures.size()));
        if (!fresh) return it->second;
        json image;
        std::string mime = t.mime_type;
        if (t.image >= 0) {
            const Image& stored = scene.images[size_t(t.image)];
            image = {{"bufferView", w.view(stored.data, size_t(stored.bytes), 0)}, {"mimeType", stored.mime_type}};
            if (!stored.name.empty()) image["name"] = stored.name;
            mime = stored.mime_type;
        } else if (embed_external && !file.empty()) {
            const std::vector<uint8_t> bytes = read_image_file(file, path);
            if (mime.empty()) mime = sniff_image_type(bytes.data(), bytes.size());
            if (mime.empty()) throw IoError("cannot write '" + path + "': the type of image '" + file.string() + "' is unknown");
            image = {{"bufferView", w.view(bytes.data(), bytes.size(), 0)}, {"mimeType", mime}};
        } else {
            image = {{"uri", key}};
        }
        images.push_back(image);
        json texture = {{"source", images.size() - 1}};
        if (const char* ext = image_extension(mime)) {
            texture = {{"extensions", {{ext, {{"source", images.size() - 1}}}}}};
            extensions.insert(ext);
        }
        if (sampler >= 0) texture["sampler"] = sampler;
        textures.push_back(texture);
        return it->second;
    }

    // material k's extensions and extras as the source had them (those the stored scene keeps);
    // the extensions' names are used, not required
    void add_source_extensions(size_t k, json& mat) {
        if (!source || !source->contains("materialExtensions")) return;
        const json& list = (*source)["materialExtensions"];
        if (k >= list.size() || !list[k].is_object()) return;
        if (list[k].contains("extras")) mat["extras"] = list[k]["extras"];
        if (!list[k].contains("extensions") || !list[k]["extensions"].is_object()) return;
        for (const auto& [name, value] : list[k]["extensions"].items()) {
            json kept = value;
            renumber_textures(kept);
            mat["extensions"][name] = kept;
            used.insert(name);
        }
    }

    // The texture a kept material extension refers to by the source's index `t`, written as the
    // stored scene describes it ("extensionTextures"); -1 when it describes none (checked: a
    // hostile file's description names no image or sampler it does not store).
    int extension_texture(const json& t) {
        if (!t.is_number_unsigned() || !source->contains("extensionTextures")) return -1;
        const json& list = (*source)["extensionTextures"];
        if (t.get<size_t>() >= list.size() || !list[t.get<size_t>()].is_object()) return -1;
        const json& d = list[t.get<size_t>()];
        TextureRef ref;
        if (d.contains("image")) {
            if (!d["image"].is_number_unsigned() || d["image"].get<size_t>() >= scene.images.size()) return -1;
            ref.image = d["image"].get<int32_t>();
        } else if (d.contains("uri") && d["uri"].is_string()) {
            ref.uri = d["uri"].get<std::string>();
            if (d.contains("mimeType") && d["mimeType"].is_string()) ref.mime_type = d["mimeType"].get<std::string>();
        }
        int sampler = -1;
        if (d.contains("sampler") && d["sampler"].is_number_unsigned() && source->contains("samplers") && d["sampler"].get<size_t>() < (*source)["samplers"].size())
            sampler = d["sampler"].get<int>();
        return texture_for(ref, sampler);
    }

    // Every textureInfo (an object with an "index") in an extension's value gets the index of the
    // texture written for it, or goes when there is none.
    void renumber_textures(json& j) {
        if (j.is_array()) {
            for (json& value : j) renumber_textures(value);
            return;
        }
        if (!j.is_object()) return;
        std::vector<std::string> gone;
        for (auto it = j.begin(); it != j.end(); ++it) {
            json& value = it.value();
            if (!value.is_object() || !value.contains("index")) {
                renumber_textures(value);
                continue;
            }
            const int index = extension_texture(value["index"]);
            if (index < 0) gone.push_back(it.key());
            else value["index"] = index;
            if (index >= 0 && value.contains("extensions") && value["extensions"].is_object())  // KHR_texture_transform, say
                for (const auto& [name, unused] : value["extensions"].items()) used.insert(name);
        }
        for (const std::string& key : gone) j.erase(key);
    }

    json material(const Material& m) {
        json pbr = {{"baseColorFactor", m.base_color}, {"metallicFactor", m.metallic}, {"roughnessFactor", m.roughness}};
        json mat = {{"name", m.name}, {"pbrMetallicRoughness", json::object()}};
        if (m.emissive[0] != 0 || m.emissive[1] != 0 || m.emissive[2] != 0) mat["emissiveFactor"] = m.emissive;
        if (m.alpha_mode != AlphaMode::opaque) mat["alphaMode"] = m.alpha_mode == AlphaMode::mask ? "MASK" : "BLEND";
        if (m.alpha_mode == AlphaMode::mask) mat["alphaCutoff"] = m.alpha_cutoff;
        if (m.double_sided) mat["doubleSided"] = true;
        for (const TextureRef& t : m.textures) {
            const int index = texture_for(t, sampler_of_reference());
            ++reference;
            if (index < 0) continue;
            const json info = {{"index", index}, {"texCoord", t.texcoord}};
            switch (t.role) {
            case TextureRole::base_color: pbr["baseColorTexture"] = info; break;
            case TextureRole::metallic_roughness: pbr["metallicRoughnessTexture"] = info; break;
            case TextureRole::normal: mat["normalTexture"] = info; break;
            case TextureRole::occlusion: mat["occlusionTexture"] = info; break;
            case TextureRole::emissive: mat["emissiveTexture"] = info; break;
            }
        }
        mat["pbrMetallicRoughness"] = pbr;
        return mat;
    }
};

void write_materials(json& doc, Writer& w, const Scene& scene, const json* source, int max_material, const std::string& texture_dir,
                     bool embed_external, const std::string& path, std::set<std::string>& required, std::set<std::string>& used) {
    if (max_material >= 0 && size_t(max_material) >= scene.materials.size())
        throw IoError("cannot write '" + path + "': a mesh refers to material " + std::to_string(max_material) + ", but " +
                      std::to_string(scene.materials.size()) + " are stored");
    if (scene.materials.empty()) return;
    MaterialWriter mw{w, scene, texture_dir, embed_external, path, source};
    doc["materials"] = json::array();
    for (size_t k = 0; k < scene.materials.size(); ++k) {
        doc["materials"].push_back(mw.material(scene.materials[k]));
        mw.add_source_extensions(k, doc["materials"].back());
    }
    if (!mw.images.empty()) {
        doc["images"] = mw.images;
        doc["textures"] = mw.textures;
        if (source && source->contains("samplers") && source->contains("textureSamplers")) doc["samplers"] = (*source)["samplers"];
    }
    required.insert(mw.extensions.begin(), mw.extensions.end());
    used.insert(mw.used.begin(), mw.used.end());
}

// One node per instance (each mesh once, untransformed, without instances); with several
// levels, its coarser levels follow it as nodes of their own listed by its MSFT_lod extension.
void write_instance_nodes(json& doc, const Scene& scene, const std::vector<std::vector<int>>& level_mesh, const std::string& path, std::set<std::string>& used) {
    doc["nodes"] = json::array();
    json roots = json::array();
    const Instance untransformed;  // its transform is the identity
    for (const Instance& inst : draw_list(scene, uint32_t(level_mesh.size()))) {
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
        for (size_t level = 1; level < lm.size(); ++level) {
            if (lm[level] < 0) continue;
            ids.push_back(doc["nodes"].size());
            doc["nodes"].push_back(node_of(lm[level], inst.name.empty() ? std::string() : inst.name + " lod " + std::to_string(level)));
        }
        if (!ids.empty()) {
            doc["nodes"][index]["extensions"] = {{"MSFT_lod", {{"ids", ids}}}};
            used.insert("MSFT_lod");
        }
    }
    if (roots.empty()) throw IoError("cannot write '" + path + "': no mesh has a triangle at the finest level requested");
    doc["scenes"] = {{{"nodes", roots}}};
    doc["scene"] = 0;
}

// An index the stored scene gives, checked against the count of what it indexes.
size_t stored_index(const json& value, size_t count, const char* what) {
    const size_t i = value.get<size_t>();
    if (i >= count) throw std::out_of_range(std::string(what) + " " + std::to_string(i) + " of " + std::to_string(count));
    return i;
}

// The source's own node tree (SourceGltf) in place of one node per instance: the nodes keep their
// hierarchy, transforms, names, skins, cameras, lights, extensions and extras, and the scenes,
// skins, animations and cameras come along, their accessors appended with their data. A node's
// mesh becomes its finest level; its coarser levels are nodes of their own (with its skin)
// listed by its MSFT_lod extension. \throw IoError when the stored scene is not what the
// importer writes (a hostile file): every index followed here is checked.
void write_source_scene(json& doc, Writer& w, const json& src, const SourceGltf& gltf, const std::vector<std::vector<int>>& level_mesh,
                        const std::string& path, std::set<std::string>& used) {
    try {
        // the data of the stored accessors, their views and the accessors, renumbered
        while (w.bin.size() % 4) w.bin.push_back(0);
        const size_t data_base = w.bin.size(), view_base = w.views.size(), accessor_base = w.accessors.size();
        if (gltf.bytes) w.bin.insert(w.bin.end(), gltf.data, gltf.data + gltf.bytes);
        const json& views = src.at("bufferViews");
        for (json view : views) {
            const size_t offset = view.value("byteOffset", size_t(0)), length = view.at("byteLength").get<size_t>();
            if (offset > gltf.bytes || length > gltf.bytes - offset) throw std::out_of_range("a buffer view past the stored data");
            view["buffer"] = 0;
            view["byteOffset"] = data_base + offset;
            w.views.push_back(view);
        }
        const json& accessors = src.at("accessors");
        for (json accessor : accessors) {
            accessor["bufferView"] = view_base + stored_index(accessor.at("bufferView"), views.size(), "buffer view");
            w.accessors.push_back(accessor);
        }
        auto accessor_ref = [&](json& value) { value = accessor_base + stored_index(value, accessors.size(), "accessor"); };
        if (src.contains("skins")) {
            doc["skins"] = src["skins"];
            for (json& skin : doc["skins"])
                if (skin.contains("inverseBindMatrices")) accessor_ref(skin["inverseBindMatrices"]);
        }
        if (src.contains("animations")) {
            doc["animations"] = src["animations"];
            for (json& animation : doc["animations"])
                for (json& sampler : animation.at("samplers"))
                    for (const char* key : {"input", "output"}) accessor_ref(sampler.at(key));
        }
        for (const char* key : {"cameras", "scenes", "scene", "extensions"})
            if (src.contains(key)) doc[key] = src[key];
        if (src.contains("asset") && src["asset"].contains("copyright")) doc["asset"]["copyright"] = src["asset"]["copyright"];
        if (src.contains("extensions") && src["extensions"].contains("KHR_lights_punctual")) used.insert("KHR_lights_punctual");
        // the nodes, each mesh node at its finest level, coarser ones appended after them all
        json nodes = src.at("nodes"), lods = json::array();
        const size_t stored_nodes = nodes.size();
        bool any = false;
        for (size_t i = 0; i < stored_nodes; ++i) {
            json& node = nodes[i];
            if (!node.contains("mesh")) continue;
            const std::vector<int>& lm = level_mesh[stored_index(node["mesh"], level_mesh.size(), "mesh")];
            if (lm[0] < 0) {
                node.erase("mesh");
                continue;
            }
            any = true;
            node["mesh"] = lm[0];
            json ids = json::array();
            for (size_t level = 1; level < lm.size(); ++level) {
                if (lm[level] < 0) continue;
                json lod = {{"mesh", lm[level]}};
                if (node.contains("name")) lod["name"] = node["name"].get<std::string>() + " lod " + std::to_string(level);
                if (node.contains("skin")) lod["skin"] = node["skin"];
                ids.push_back(stored_nodes + lods.size());
                lods.push_back(lod);
            }
            if (!ids.empty()) {
                node["extensions"]["MSFT_lod"] = {{"ids", ids}};
                used.insert("MSFT_lod");
            }
        }
        if (!any) throw IoError("cannot write '" + path + "': no mesh has a triangle at the finest level requested");
        nodes.insert(nodes.end(), lods.begin(), lods.end());
        // each mesh's default morph weights (where its levels have as many targets) and extras, on every level
        if (src.contains("meshes"))
            for (size_t mi = 0; mi < level_mesh.size() && mi < src["meshes"].size(); ++mi)
                for (const int g : level_mesh[mi]) {
                    if (g < 0) continue;
                    const json& kept = src["meshes"][mi];
                    json& out = doc["meshes"][size_t(g)];
                    const size_t targets = out["primitives"][0].value("targets", json::array()).size();
                    if (kept.contains("weights") && kept["weights"].is_array() && kept["weights"].size() == targets && targets > 0) out["weights"] = kept["weights"];
                    if (kept.contains("extras")) out["extras"] = kept["extras"];
                }
        doc["nodes"] = nodes;
        if (!doc.contains("scenes")) {  // a source without scenes: its root nodes make one
            std::vector<uint8_t> child(stored_nodes, 0);
            for (const json& node : src["nodes"])
                if (node.contains("children"))
                    for (const json& c : node["children"]) child[stored_index(c, stored_nodes, "node")] = 1;
            json roots = json::array();
            for (size_t i = 0; i < stored_nodes; ++i)
                if (!child[i]) roots.push_back(i);
            doc["scenes"] = {{{"nodes", roots}}};
            doc["scene"] = 0;
        }
    } catch (const json::exception& e) {
        throw IoError("cannot write '" + path + "': the file's stored glTF scene is malformed (" + e.what() + ")");
    } catch (const std::out_of_range& e) {
        throw IoError("cannot write '" + path + "': the file's stored glTF scene is malformed (" + e.what() + ")");
    }
}

// The stored glTF scene, parsed (null when the file has none).
json parse_source(const Scene& scene, const std::string& path) {
    if (scene.gltf.empty()) return json();
    json source;
    try {
        source = json::parse(scene.gltf.json);
    } catch (const json::exception& e) {
        throw IoError("cannot write '" + path + "': the file's stored glTF scene is not JSON (" + e.what() + ")");
    }
    if (!source.is_object()) throw IoError("cannot write '" + path + "': the file's stored glTF scene is not a JSON object");
    return source;
}

// Whether each mesh's positions must stay floats when compressed: a node of the stored scene
// draws it with a skin, or it has morph targets.
std::vector<uint8_t> float_positions(const std::vector<GlbMesh>& meshes, const json& source) {
    std::vector<uint8_t> out(meshes.size(), 0);
    for (size_t mi = 0; mi < meshes.size(); ++mi) {
        const MeshView& m = *meshes[mi].mesh;
        for (uint32_t k = 0; k < m.extra_stream_count; ++k)
            if (m.extra_streams[k].name.rfind("TARGET", 0) == 0) out[mi] = 1;
    }
    if (source.is_object() && source.contains("nodes") && source["nodes"].is_array())
        for (const json& node : source["nodes"])
            if (node.is_object() && node.contains("skin") && node.contains("mesh") && node["mesh"].is_number_unsigned() && node["mesh"].get<size_t>() < out.size())
                out[node["mesh"].get<size_t>()] = 1;
    return out;
}

} // namespace

void export_glb(const std::string& path, const std::vector<GlbMesh>& meshes, const Scene& scene, const std::string& texture_dir, bool embed_images, bool compress) {
    Writer w;
    w.compress = compress;
    const json source = parse_source(scene, path);  // the stored glTF scene, parsed once
    const std::vector<uint8_t> keep_float = float_positions(meshes, source);
    std::vector<json> dequantize;  // per glTF mesh
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
        // vertex streams, shared by every level of this mesh (compressed: in the order its finest level uses them)
        std::vector<uint32_t> indices(size_t(m.triangle_count) * 3);
        std::vector<uint32_t> finest;
        if (compress) finest.assign(indices.begin(), indices.begin() + long(3 * size_t(extract(m, n_max, indices.data(), indices.size()).triangle_count)));
        const MeshStreams streams = write_streams(w, m, n_max, finest, keep_float[mi]);
        const json& attributes = streams.attributes;
        const json& targets = streams.targets;
        std::vector<PartDraw> draws(part_count(m));
        for (size_t level = 0; level < gm.vertex_counts.size(); ++level) {
            const Extracted e = extract_parts(m, std::min(gm.vertex_counts[level], m.vertex_count), indices.data(), indices.size(), draws.data());
            if (e.triangle_count == 0) continue;
            // a level with vertex streams of its own (re-fitted): those, and the carried ones shared
            json level_attributes = attributes, level_dequantize = streams.dequantize;
            if (level < gm.level_views.size() && gm.level_views[level]) {
                const json own = level_streams(w, *gm.level_views[level], streams, !keep_float[mi], level_dequantize);
                for (const auto& [key, accessor] : own.items()) level_attributes[key] = accessor;
            }
            // one primitive per part that has triangles at this level, with the streams its source had
            json primitives = json::array();
            for (uint32_t p = 0; p < draws.size(); ++p) {
                const PartDraw& d = draws[p];
                if (d.index_count == 0) continue;
                std::vector<uint32_t> reordered;  // compressed: in the streams' vertex order, in vertex-cache order
                if (compress) reordered = detail::optimized_indices(indices.data() + d.first_index, d.index_count, streams.order, n_max);
                const uint32_t* part_indices = compress ? reordered.data() : indices.data() + d.first_index;
                int view_index;
                int component;
                if ((compress ? n_max : e.vertex_count) <= 65535) {  // 16-bit, 65535 itself being reserved by glTF for restart
                    std::vector<uint16_t> small(part_indices, part_indices + d.index_count);
                    view_index = w.index_view(small.data(), d.index_count, 2);
                    component = kUint16;
                } else {
                    view_index = w.index_view(part_indices, d.index_count, 4);
                    component = kUint32;
                }
                json own = level_attributes;
                if (m.parts) {
                    const uint32_t part_streams = part_at(m, p).attributes;
                    const std::pair<const char*, uint32_t> optional[] = {{"TEXCOORD_0", 2}, {"COLOR_0", 4}, {"TEXCOORD_1", 8}, {"TANGENT", 16}};
                    for (const auto& [key, bit] : optional)
                        if (!(part_streams & bit)) own.erase(key);
                }
                json primitive = {{"attributes", own}, {"indices", w.accessor(view_index, component, d.index_count, "SCALAR")}, {"mode", 4}};
                if (!targets.empty()) primitive["targets"] = targets;
                if (d.material >= 0) {
                    primitive["material"] = d.material;
                    max_material = std::max(max_material, d.material);
                }
                primitives.push_back(primitive);
            }
            level_mesh[mi][level] = int(gltf_meshes.size());
            dequantize.push_back(level_dequantize);
            const std::string name(m.name);
            gltf_meshes.push_back({{"name", levels > 1 ? name + " level " + std::to_string(level) : name}, {"primitives", primitives}});
        }
    }
    json doc;
    doc["asset"] = {{"version", "2.0"}, {"generator", "libtom (tomextract)"}};
    doc["meshes"] = gltf_meshes;
    std::set<std::string> used;
    if (source.is_object())
        write_source_scene(doc, w, source, scene.gltf, level_mesh, path, used);
    else
        write_instance_nodes(doc, scene, level_mesh, path, used);
    std::set<std::string> required;  // image codecs without a fallback, and the compression's extensions
    if (compress) {
        place_dequantization(doc, dequantize);
        required.insert("KHR_mesh_quantization");
        required.insert("EXT_meshopt_compression");
    }
    write_materials(doc, w, scene, source.is_object() ? &source : nullptr, max_material, texture_dir, embed_images, path, required, used);
    used.insert(required.begin(), required.end());
    if (!used.empty()) doc["extensionsUsed"] = used;
    if (!required.empty()) doc["extensionsRequired"] = required;
    while (w.bin.size() % 4) w.bin.push_back(0);
    doc["buffers"] = {{{"byteLength", w.bin.size()}}};
    if (w.fallback)  // compressed views lie in a buffer of no data, decoded from buffer 0
        doc["buffers"].push_back({{"byteLength", (w.fallback + 3) / 4 * 4}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}});
    doc["bufferViews"] = w.views;
    doc["accessors"] = w.accessors;
    const std::vector<uint8_t> out = detail::glb_bytes(doc.dump(), &w.bin);
    write_bytes_atomically(path, out.data(), out.size());
}

} // namespace tom
