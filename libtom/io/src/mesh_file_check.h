#pragma once
// Structural checks of OFF, PLY, OBJ and STL files before OpenMesh reads them, and the canonical
// text it reads instead (see the .cpp).

#include <cstdint>
#include <string>
#include <vector>

namespace tom::detail {

/// An OBJ file's material groups, as check_obj_groups finds them beside the canonical text.
struct ObjGroups {
    std::vector<std::string> libraries;   ///< `mtllib` file names, as written (relative to the OBJ)
    std::vector<std::string> materials;   ///< `usemtl` names, in order of first use
    /// per face line of the canonical text: its material (index into `materials`), or -1 before any usemtl
    std::vector<int32_t> face_material;
    /// per face line: its vertices (0-based), face k's in [face_first[k], face_first[k + 1])
    std::vector<uint32_t> face_first, face_vertices;
};

/// Throws MeshError naming the file, the line and the problem when an OFF, PLY, OBJ or STL file
/// announces more than it holds or refers to vertices it does not define. Returns what OpenMesh
/// is to read in the file's place: the checked content in canonical form (empty for a binary OFF
/// or STL file, which is read as it is, and for other extensions).
/// For OBJ, `groups` (when given) receives the material groups of the face lines.
std::string check_mesh_file(const std::string& path, const std::string& extension, ObjGroups* groups = nullptr);

} // namespace tom::detail
