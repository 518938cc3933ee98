// EXT_meshopt_compression decoding (see gltf_meshopt.h) with meshoptimizer's Debian package.

#include "gltf_meshopt.h"

#include <cstring>

#include "glb.h"

#include <meshoptimizer.h>

#include "tom/errors.h"

namespace tom::detail {

namespace {

using nlohmann::json;

constexpr const char* kExt = "EXT_meshopt_compression";

// base64 of `n` zero bytes: 'A' is a zero sextet
std::string zero_data_uri(uint64_t n) {
    std::string s = "data:application/octet-stream;base64,";
    s.append(size_t((n / 3) * 4), 'A');
    if (n % 3 == 1) s += "AA==";
    if (n % 3 == 2) s += "AAA=";
    return s;
}

} // namespace

bool prepare_meshopt(json& doc, std::vector<uint8_t>& bytes, bool binary, const std::string& path) {
    bool used = false;
    if (doc.contains("extensionsUsed") && doc["extensionsUsed"].is_array())
        for (const json& e : doc["extensionsUsed"])
            if (e == kExt) used = true;
    if (!used || !doc.contains("buffers")) return used;
    for (size_t i = 0; i < doc["buffers"].size(); ++i) {
        json& b = doc["buffers"][i];
        if (b.contains("uri") || !b.contains("extensions") || !b["extensions"].contains(kExt)) continue;
        // the GLB's own chunk is buffer 0 without a URI: it holds data, leave it
        if (binary && i == 0) continue;
        const uint64_t n = b.value("byteLength", uint64_t(0));
        if (n > (uint64_t(1) << 30))
            throw MeshError(path + ": EXT_meshopt_compression fallback buffer " + std::to_string(i) + " declares " + std::to_string(n) +
                              " bytes, more than this reader accepts (1 GiB)");
        b["uri"] = zero_data_uri(n);
    }
    const std::string text = doc.dump();
    if (!binary) {
        bytes.assign(text.begin(), text.end());
        return true;
    }
    // a new GLB: the changed JSON chunk, the original BIN chunk (if any) unchanged
    const GlbChunk chunk = glb_second_chunk(bytes);
    std::vector<uint8_t> bin;
    if (chunk.found) bin.assign(bytes.begin() + ptrdiff_t(chunk.offset), bytes.begin() + ptrdiff_t(chunk.offset + chunk.length));
    bytes = glb_bytes(text, chunk.found ? &bin : nullptr);
    return true;
}

void decode_meshopt(tinygltf::Model& model, const json& doc, const std::string& path) {
    if (!doc.contains("bufferViews")) return;
    const json& views = doc["bufferViews"];
    for (size_t vi = 0; vi < views.size() && vi < model.bufferViews.size(); ++vi) {
        if (!views[vi].contains("extensions") || !views[vi]["extensions"].contains(kExt)) continue;
        const json& ext = views[vi]["extensions"][kExt];
        const std::string where = path + ": buffer view " + std::to_string(vi) + " (EXT_meshopt_compression)";
        auto number = [&](const char* key) -> uint64_t {
            if (!ext.contains(key) || !ext[key].is_number_unsigned()) throw MeshError(where + ": '" + key + "' is missing or not a non-negative integer");
            return ext[key].get<uint64_t>();
        };
        const uint64_t source = number("buffer"), offset = ext.value("byteOffset", uint64_t(0)), length = number("byteLength");
        const uint64_t stride = number("byteStride"), count = number("count");
        const std::string mode = ext.value("mode", std::string());
        const std::string filter = ext.value("filter", std::string("NONE"));
        if (source >= model.buffers.size()) throw MeshError(where + ": source buffer " + std::to_string(source) + " does not exist");
        const std::vector<unsigned char>& src = model.buffers[size_t(source)].data;
        if (offset > src.size() || length > src.size() - offset)
            throw MeshError(where + ": " + std::to_string(length) + " compressed bytes at " + std::to_string(offset) + " lie outside buffer " +
                              std::to_string(source) + " (" + std::to_string(src.size()) + " bytes)");
        tinygltf::BufferView& view = model.bufferViews[vi];
        if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size()) throw MeshError(where + ": its buffer does not exist");
        std::vector<unsigned char>& dst = model.buffers[size_t(view.buffer)].data;
        if (stride == 0 || count > (uint64_t(1) << 32) || stride * count > view.byteLength || view.byteOffset > dst.size() ||
            view.byteLength > dst.size() - view.byteOffset)
            throw MeshError(where + ": " + std::to_string(count) + " elements of " + std::to_string(stride) + " bytes do not fit the view (" +
                              std::to_string(view.byteLength) + " bytes at " + std::to_string(view.byteOffset) + " of a " + std::to_string(dst.size()) +
                              "-byte buffer)");
        // decoded apart and copied, so a view whose fallback is its own source buffer decodes too
        std::vector<unsigned char> decoded(size_t(stride * count));
        unsigned char* out = decoded.data();
        const unsigned char* in = src.data() + offset;
        int rc;
        if (mode == "ATTRIBUTES") {
            if (stride % 4 != 0 || stride > 256) throw MeshError(where + ": ATTRIBUTES need a byte stride that is a multiple of 4 up to 256, not " + std::to_string(stride));
            rc = meshopt_decodeVertexBuffer(out, size_t(count), size_t(stride), in, size_t(length));
        } else if (mode == "TRIANGLES" || mode == "INDICES") {
            if (stride != 2 && stride != 4) throw MeshError(where + ": " + mode + " need a byte stride of 2 or 4, not " + std::to_string(stride));
            if (mode == "TRIANGLES" && count % 3 != 0) throw MeshError(where + ": TRIANGLES need a multiple of 3 indices, not " + std::to_string(count));
            rc = mode == "TRIANGLES" ? meshopt_decodeIndexBuffer(out, size_t(count), size_t(stride), in, size_t(length))
                                     : meshopt_decodeIndexSequence(out, size_t(count), size_t(stride), in, size_t(length));
        } else {
            throw MeshError(where + ": unknown mode '" + mode + "'");
        }
        if (rc != 0) throw MeshError(where + ": the " + mode + " data does not decode (meshoptimizer error " + std::to_string(rc) + ")");
        if (filter == "OCTAHEDRAL") {
            if (mode != "ATTRIBUTES" || (stride != 4 && stride != 8)) throw MeshError(where + ": the OCTAHEDRAL filter needs ATTRIBUTES of stride 4 or 8");
            meshopt_decodeFilterOct(out, size_t(count), size_t(stride));
        } else if (filter == "QUATERNION") {
            if (mode != "ATTRIBUTES" || stride != 8) throw MeshError(where + ": the QUATERNION filter needs ATTRIBUTES of stride 8");
            meshopt_decodeFilterQuat(out, size_t(count), size_t(stride));
        } else if (filter == "EXPONENTIAL") {
            if (mode != "ATTRIBUTES" || stride % 4 != 0) throw MeshError(where + ": the EXPONENTIAL filter needs ATTRIBUTES of a stride that is a multiple of 4");
            meshopt_decodeFilterExp(out, size_t(count), size_t(stride));
        } else if (filter != "NONE") {
            throw MeshError(where + ": unknown filter '" + filter + "'");
        }
        if (!decoded.empty()) std::memcpy(dst.data() + view.byteOffset, decoded.data(), decoded.size());
    }
}

} // namespace tom::detail
