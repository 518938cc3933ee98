#pragma once
// Structural checks of OFF, PLY, OBJ and STL files before OpenMesh reads them (see the .cpp).

#include <string>

namespace tom::detail {

/// Throws ImportError naming the file, the line and the problem when an OFF, PLY, OBJ or STL file
/// announces more than it holds or refers to vertices it does not define; does nothing for
/// other extensions.
void check_mesh_file(const std::string& path, const std::string& extension);

} // namespace tom::detail
