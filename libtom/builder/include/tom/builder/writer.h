#pragma once
// Writing .tom files (docs/FORMAT.md) from built meshes.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tom/builder/builder.h"
#include "tom/scene.h"

namespace tom {

enum class IndexSize {
    automatic,  ///< 16-bit when every mesh of the file has <= 65536 vertices, else 32-bit (per mesh)
    bits16,     ///< 16-bit (only for meshes of <= 65536 vertices; others use 32-bit)
    bits32,
};

struct WriteOptions {
    IndexSize index_size = IndexSize::automatic;
    /// Stored as the file-level PROV section when not empty (tom::File::provenance): what made
    /// the file. It is part of the bytes, so equal provenance keeps equal inputs byte-identical.
    std::string provenance;
};

/// The complete file image of `meshes`. Deterministic: equal inputs give equal bytes. The image
/// is validated as the reader would (\throw tom::ArgumentError when it breaks a rule, such as a
/// mesh's material index past the scene's materials): no writer call produces a file the reader
/// rejects.
std::vector<uint8_t> serialize(const std::vector<TomMesh>& meshes, const WriteOptions& options = {});
/// The same with a scene: its materials, instances and images are stored in the file-level
/// sections. Meshes that name materials of a scene that stores none get default materials
/// ("material K", up to the largest index named, at most 65536), so that every material index in
/// the file names a stored material.
/// \pre every instance names a mesh < meshes.size() (\throw tom::ArgumentError otherwise).
std::vector<uint8_t> serialize(const std::vector<TomMesh>& meshes, const Scene& scene, const WriteOptions& options = {});

/// Writes `meshes` to `path` through a temporary file in the same folder that is
/// renamed into place, so `path` never holds a truncated file.
/// \throw IoError naming the path when the file cannot be written or renamed.
void write_file(const std::string& path, const std::vector<TomMesh>& meshes, const WriteOptions& options = {});
void write_file(const std::string& path, const std::vector<TomMesh>& meshes, const Scene& scene, const WriteOptions& options = {});

/// Writes bytes to `path` atomically (temporary file + rename). \throw IoError.
void write_bytes_atomically(const std::string& path, const void* data, size_t bytes);

} // namespace tom
