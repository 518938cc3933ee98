#pragma once
// The readers behind import_file(); private to tom::io.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tom/io/import.h"

namespace tom::detail {

ImportResult import_openmesh(const std::string& path, const std::string& extension);
ImportResult import_gltf(const std::string& path, bool binary);
/// A binary little-endian PLY of the simple layout of scans (vertex: float x y z, optional float
/// nx ny nz and uchar red green blue [alpha]; face: only an int or uint vertex_indices list) read
/// directly; std::nullopt for any other layout (import_openmesh reads those).
/// \throw MeshError naming the file and the face or count at fault
std::optional<ImportResult> read_simple_binary_ply(const std::string& path, const std::vector<uint8_t>& bytes);
std::string file_stem(const std::string& path);
/// A texture coordinate v between OBJ's and PLY's convention (v = 0 at the image's bottom row)
/// and glTF's, which .tom files use (v = 0 at its top row); its own inverse. The exporters use it too.
inline float flip_v(float v) { return float(1.0 - double(v)); }
/// The whole file; IoError when it cannot be read.
std::vector<uint8_t> read_whole_file(const std::string& path);
/// The materials named by an OBJ's `usemtl` lines (`names`, in that order) from its `mtllib`
/// files (relative to the OBJ). A missing or unreadable library, or a name none defines, is a
/// warning naming it; such materials get default values. Texture URIs are relative to the OBJ.
std::vector<Material> read_obj_materials(const std::string& obj_path, const std::vector<std::string>& libraries,
                                         const std::vector<std::string>& names, std::vector<std::string>& warnings);

} // namespace tom::detail
