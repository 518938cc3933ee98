// The references between a glTF document's objects, checked before tinygltf reads it.
//
// tinygltf follows indices without range checks in several places, among them its Draco
// extension (KHR_draco_mesh_compression): the extension's bufferView, that view's buffer, the
// primitive's accessors and the Draco attribute ids are all used as they come, so a file that
// names a missing object crashes the reader. Every index that tinygltf or this importer follows
// is checked here against the list it names, every buffer view against its buffer's declared
// length, and each Draco primitive is decoded once to check that its attribute ids exist.

#include "gltf_references.h"

#include <cstring>

#include <draco/compression/decode.h>

#include "glb.h"
#include "gltf_model.h"
#include "import_backends.h"
#include "tom/errors.h"

namespace tom::detail {

namespace {

using nlohmann::json;

size_t count_of(const json& doc, const char* list) {
    const auto it = doc.find(list);
    return it != doc.end() && it->is_array() ? it->size() : 0;
}

// `value` (an integer; the schema check ran) names an entry of doc[list]
void check_index(const json& doc, const json& value, const char* list, const std::string& where, const std::string& file) {
    const int64_t i = value.get<int64_t>();
    const size_t n = count_of(doc, list);
    if (i < 0 || uint64_t(i) >= n) {
        const std::string one = std::strcmp(list, "meshes") == 0 ? "mesh" : std::string(list, std::strlen(list) - 1);
        throw MeshError(file + ": " + where + ": names " + one + " " + std::to_string(i) + ", the file has " + std::to_string(n));
    }
}

// doc[list][*][key] -> doc[target] for each entry that has the key
void check_member(const json& doc, const char* list, const char* key, const char* target, const std::string& file) {
    const size_t n = count_of(doc, list);
    for (size_t i = 0; i < n; ++i) {
        const json& entry = doc[list][i];
        if (entry.is_object() && entry.contains(key))
            check_index(doc, entry[key], target, std::string("$.") + list + "[" + std::to_string(i) + "]." + key, file);
    }
}

// The bytes of buffer b as tinygltf will load them: the GLB's BIN chunk, a data URI (decoded by
// tinygltf's own decoder), or a file beside the glTF. Empty when they cannot be had (tinygltf
// then reports it).
std::vector<uint8_t> buffer_bytes(const json& doc, size_t b, const std::vector<uint8_t>& bytes, bool binary, const std::string& base_dir) {
    const json& buffer = doc["buffers"][b];
    if (!buffer.contains("uri")) {
        if (!binary || b != 0 || bytes.size() < 20) return {};
        const GlbChunk chunk = glb_second_chunk(bytes);
        if (!chunk.found || chunk.type != kGlbBin) return {};
        return std::vector<uint8_t>(bytes.begin() + std::ptrdiff_t(chunk.offset), bytes.begin() + std::ptrdiff_t(chunk.offset + chunk.length));
    }
    const std::string uri = buffer["uri"].get<std::string>();
    std::vector<uint8_t> out;
    if (tinygltf::IsDataURI(uri)) {
        std::string mime;
        if (!tinygltf::DecodeDataURI(&out, mime, uri, 0, false)) out.clear();
        return out;
    }
    try {
        out = read_whole_file(base_dir + "/" + uri);
    } catch (const Error&) {
        out.clear();
    }
    return out;
}

// A Draco primitive's extension: its view, the accessors it fills, and its attribute ids in the
// decoded mesh.
void check_draco(const json& doc, const json& prim, const json& ext, const std::string& where, const std::vector<std::vector<uint8_t>>& buffers,
                 const std::string& file) {
    if (!ext.contains("bufferView") || !ext["bufferView"].is_number_integer())
        throw MeshError(file + ": " + where + ": KHR_draco_mesh_compression has no bufferView");
    check_index(doc, ext["bufferView"], "bufferViews", where + ".extensions.KHR_draco_mesh_compression.bufferView", file);
    if (!ext.contains("attributes") || !ext["attributes"].is_object())
        throw MeshError(file + ": " + where + ": KHR_draco_mesh_compression has no attributes object");
    const json& view = doc["bufferViews"][ext["bufferView"].get<size_t>()];
    const size_t b = view.value("buffer", size_t(0));
    const uint64_t offset = view.value("byteOffset", uint64_t(0)), length = view.value("byteLength", uint64_t(0));
    if (b >= buffers.size() || buffers[b].size() < offset + length) return;  // tinygltf reports a buffer it cannot load
    draco::DecoderBuffer in;
    in.Init(reinterpret_cast<const char*>(buffers[b].data() + offset), size_t(length));
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&in);
    if (!decoded.ok())
        throw MeshError(file + ": " + where + ": its KHR_draco_mesh_compression data does not decode (" + decoded.status().error_msg_string() + ")");
    const draco::Mesh& mesh = *decoded.value();
    for (auto it = ext["attributes"].begin(); it != ext["attributes"].end(); ++it) {
        const std::string at = where + ".extensions.KHR_draco_mesh_compression.attributes." + it.key();
        if (!it.value().is_number_integer()) throw MeshError(file + ": " + at + ": expected an integer attribute id");
        if (!prim.contains("attributes") || !prim["attributes"].contains(it.key()))
            throw MeshError(file + ": " + at + ": the primitive has no " + it.key() + " accessor for it");
        const int64_t id = it.value().get<int64_t>();
        if (id < 0 || id > INT32_MAX || mesh.GetAttributeByUniqueId(uint32_t(id)) == nullptr)
            throw MeshError(file + ": " + at + ": the Draco data has no attribute " + std::to_string(id) + " (it has " + std::to_string(mesh.num_attributes()) + ")");
    }
}

} // namespace

void check_gltf_references(const json& doc, const std::vector<uint8_t>& bytes, bool binary, const std::string& base_dir, const std::string& file) {
    check_member(doc, "bufferViews", "buffer", "buffers", file);
    for (size_t i = 0; i < count_of(doc, "bufferViews"); ++i) {
        const json& view = doc["bufferViews"][i];
        const size_t b = view["buffer"].get<size_t>();
        const uint64_t end = view.value("byteOffset", uint64_t(0)) + view.value("byteLength", uint64_t(0));
        const uint64_t declared = doc["buffers"][b].value("byteLength", uint64_t(0));
        if (end > declared)
            throw MeshError(file + ": $.bufferViews[" + std::to_string(i) + "]: bytes up to " + std::to_string(end) + " of buffer " + std::to_string(b) + ", which has " +
                              std::to_string(declared));
    }
    check_member(doc, "accessors", "bufferView", "bufferViews", file);
    check_member(doc, "nodes", "mesh", "meshes", file);
    check_member(doc, "textures", "source", "images", file);
    check_member(doc, "textures", "sampler", "samplers", file);
    for (size_t n = 0; n < count_of(doc, "nodes"); ++n)
        if (doc["nodes"][n].contains("children"))
            for (const json& c : doc["nodes"][n]["children"]) check_index(doc, c, "nodes", "$.nodes[" + std::to_string(n) + "].children", file);
    for (size_t s = 0; s < count_of(doc, "scenes"); ++s)
        if (doc["scenes"][s].contains("nodes"))
            for (const json& c : doc["scenes"][s]["nodes"]) check_index(doc, c, "nodes", "$.scenes[" + std::to_string(s) + "].nodes", file);
    if (doc.contains("scene")) check_index(doc, doc["scene"], "scenes", "$.scene", file);

    std::vector<std::vector<uint8_t>> buffers;  // loaded when a Draco primitive needs them
    for (size_t m = 0; m < count_of(doc, "meshes"); ++m) {
        const json& prims = doc["meshes"][m]["primitives"];
        for (size_t p = 0; p < prims.size(); ++p) {
            const json& prim = prims[p];
            const std::string where = "$.meshes[" + std::to_string(m) + "].primitives[" + std::to_string(p) + "]";
            if (prim.contains("attributes"))
                for (auto it = prim["attributes"].begin(); it != prim["attributes"].end(); ++it) check_index(doc, it.value(), "accessors", where + ".attributes." + it.key(), file);
            if (prim.contains("indices")) check_index(doc, prim["indices"], "accessors", where + ".indices", file);
            if (prim.contains("material")) check_index(doc, prim["material"], "materials", where + ".material", file);
            if (!prim.contains("extensions") || !prim["extensions"].contains("KHR_draco_mesh_compression")) continue;
            if (buffers.empty())
                for (size_t b = 0; b < count_of(doc, "buffers"); ++b) buffers.push_back(buffer_bytes(doc, b, bytes, binary, base_dir));
            check_draco(doc, prim, prim["extensions"]["KHR_draco_mesh_compression"], where, buffers, file);
        }
    }
}

} // namespace tom::detail
