#pragma once
// Writing one resolution of a TOM mesh as OBJ or PLY, so a level can be opened in MeshLab or Blender.
// Part of tom::io.

#include <cstdint>
#include <string>
#include <vector>

#include "tom/view.h"

namespace tom {

/// One mesh at one resolution: vertices [0, vertex_count) of `mesh` and triangles whose
/// indices are all < vertex_count.
struct ExportPart {
    const MeshView* mesh = nullptr;
    uint32_t vertex_count = 0;
    std::vector<uint32_t> indices;
};

/// Writes the parts into one file, one after another (indices offset accordingly), with every
/// attribute stream that all parts have. The format follows the extension: .obj (text; v, vt,
/// vn, colours as "v x y z r g b") or .ply (binary little-endian, colours as uchar rgba).
/// The file is written to a temporary name and renamed into place.
/// \throw IoError when the extension is unknown or the file cannot be written.
void export_meshes(const std::string& path, const std::vector<ExportPart>& parts);

} // namespace tom
