#pragma once
// Structural checks of OFF, PLY, OBJ and STL files before OpenMesh reads them, and the canonical
// text it reads instead (see the .cpp).

#include <string>

namespace tom::detail {

/// Throws ImportError naming the file, the line and the problem when an OFF, PLY, OBJ or STL file
/// announces more than it holds or refers to vertices it does not define. Returns what OpenMesh
/// is to read in the file's place: the checked content in canonical form (empty for a binary OFF
/// or STL file, which is read as it is, and for other extensions).
std::string check_mesh_file(const std::string& path, const std::string& extension);

} // namespace tom::detail
