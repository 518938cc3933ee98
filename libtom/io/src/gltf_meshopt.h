#pragma once
// EXT_meshopt_compression (what gltfpack -c writes), decoded with meshoptimizer's decoders.
//
// A compressed buffer view points into a "fallback" buffer that usually has no data at all; the
// real bytes are in the extension's source buffer. tinygltf knows neither, so the document is
// prepared before loading (a fallback buffer without a URI gets zero bytes of its declared
// length) and every compressed view is decoded into its place after loading, before any
// accessor is read.

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gltf_model.h"

namespace tom::detail {

/// True when the document uses EXT_meshopt_compression; then its fallback buffers without a
/// URI get a data URI of zeros of their byteLength, and `bytes` (the .gltf text or the whole
/// .glb) is rewritten with the changed JSON. \throw MeshError naming `path` for a fallback
/// buffer larger than 1 GiB.
bool prepare_meshopt(nlohmann::json& doc, std::vector<uint8_t>& bytes, bool binary, const std::string& path);

/// Decodes every compressed buffer view of `doc` into `model`'s buffers (filters applied).
/// \throw MeshError naming `path` and the buffer view when a range is outside its buffer, the
/// mode, stride or filter is invalid, or the data does not decode.
void decode_meshopt(tinygltf::Model& model, const nlohmann::json& doc, const std::string& path);

} // namespace tom::detail
