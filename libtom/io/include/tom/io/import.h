#pragma once
// Reading mesh files: OBJ, PLY (ASCII and binary), OFF, STL through OpenMesh; glTF 2.0
// (.gltf with .bin, embedded, .glb, KHR_draco_mesh_compression) through tinygltf and Draco.
// Part of the tom::io library (target tom::io), which carries those dependencies.

#include <string>
#include <vector>

#include "tom/builder/mesh.h"
#include "tom/scene.h"

namespace tom {

/// Everything read from one file.
struct ImportResult {
    std::string format;                 ///< "obj", "ply", "off", "stl", "gltf", "glb"
    std::vector<Mesh> meshes;           ///< one per triangle primitive (glTF) or one for the file
    std::vector<std::string> skipped;   ///< primitives not imported and why (points, lines, ...)
    std::vector<std::string> warnings;  ///< problems the reader worked around (one line each)
    /// What the file holds that the .tom does not keep, one phrase each ("skins (1)", "animations
    /// (2)", "extension KHR_lights_punctual", ...): empty when nothing is lost. glTF only.
    std::vector<std::string> dropped;
    Scene scene;                        ///< glTF: materials, and the default scene's nodes as instances of `meshes`
    /// The other files the input names and the import reads (a glTF's external buffers, an
    /// OBJ's `mtllib` libraries, read or found missing), relative to the input's folder as the
    /// input names them, in the input's order: with the input, everything the result depends on.
    std::vector<std::string> sources;
};

/// True when `path` has an extension import_file() reads (case-insensitive).
bool is_importable(const std::string& path);

/// Reads every triangle mesh of a file. Polygons and glTF strips and fans become triangles;
/// normals are kept when present (computed later by clean_mesh() otherwise); TEXCOORD_0 and
/// COLOR_0 are kept when present. Meshes are returned as read, before clean_mesh().
/// \throw MeshError with a one-line message naming the file and, for glTF, the mesh,
///        primitive and accessor at fault (a primitive whose data cannot be decoded is an
///        error, never an empty mesh); IoError when the file cannot be read.
ImportResult import_file(const std::string& path);

} // namespace tom
