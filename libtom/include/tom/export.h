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

/// One mesh of a .tom file at one or more resolutions, for export_glb().
struct GlbMesh {
    const MeshView* mesh = nullptr;
    std::vector<uint32_t> vertex_counts;  ///< resolutions, finest first
};

/// Writes a binary glTF 2.0 (.glb): per resolution a glTF mesh with one primitive per input mesh,
/// all levels of an input mesh sharing its vertex streams (POSITION, NORMAL, TEXCOORD_0, COLOR_0:
/// the levels are prefixes of one vertex array) with their own indices (16-bit when they fit).
/// With one resolution: one node. With several: the first is the scene's node and the others are
/// its levels of detail through the MSFT_lod extension (coarser in order). Materials referenced by
/// index get placeholder materials named "material N" (material tables are not stored in .tom yet).
/// Written to a temporary name and renamed. \throw IoError when it cannot be written.
void export_glb(const std::string& path, const std::vector<GlbMesh>& meshes);

} // namespace tom
