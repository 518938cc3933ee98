#pragma once
// The input mesh of the builder: an indexed triangle list as flat arrays.

#include <cstdint>
#include <string>
#include <vector>

namespace tom {

/// An indexed triangle mesh, one std::vector per attribute (struct of arrays).
/// Optional streams are either empty or hold exactly one element per vertex.
struct Mesh {
    std::string name;                ///< e.g. "bunny00" or "Engine/primitive 3"
    std::vector<float> positions;    ///< xyz per vertex, object units
    std::vector<float> normals;      ///< xyz per vertex (unit length), or empty
    std::vector<float> texcoords;    ///< uv per vertex (TEXCOORD_0), or empty
    std::vector<float> colors;       ///< rgba per vertex in [0,1] (COLOR_0), or empty
    std::vector<float> texcoords1;   ///< uv per vertex (TEXCOORD_1), or empty
    std::vector<float> tangents;     ///< xyzw per vertex (glTF TANGENT: unit xyz, w = +-1 handedness), or empty
    std::vector<uint32_t> indices;   ///< 3 per triangle, counter-clockwise front faces
    int32_t material = -1;           ///< material index of the source file, -1 if none

    uint32_t vertex_count() const noexcept { return uint32_t(positions.size() / 3); }
    uint32_t triangle_count() const noexcept { return uint32_t(indices.size() / 3); }
};

/// Calls f(stream, components, name) for every optional vertex stream of a Mesh or TomMesh,
/// in the order of the file's sections (normals, TEXCOORD_0, COLOR_0, TEXCOORD_1, tangents).
template <class M, class F>
void for_each_attribute_stream(M& mesh, F&& f) {
    f(mesh.normals, 3, "normal");
    f(mesh.texcoords, 2, "texcoord0");
    f(mesh.colors, 4, "color");
    f(mesh.texcoords1, 2, "texcoord1");
    f(mesh.tangents, 4, "tangent");
}

/// What clean_mesh() changed.
struct CleanStats {
    uint32_t degenerate_triangles = 0;   ///< triangles with a repeated index, removed
    uint32_t unreferenced_vertices = 0;  ///< vertices used by no triangle, removed
};

/// Checks a mesh and brings it to the form the builder expects.
/// \throw ImportError naming `mesh.name` when an index is >= vertex_count, a
///        position is not finite, a stream has the wrong size, or the mesh has
///        more than 2^32-2 vertices.
/// \post every triangle has three distinct indices; every vertex is referenced;
///       normals are present (area-weighted from the triangles when absent).
CleanStats clean_mesh(Mesh& mesh);

/// Area-weighted vertex normals from the triangles (zero-area neighbourhoods get +z).
void compute_normals(Mesh& mesh);

} // namespace tom
