#pragma once
// The input mesh of the builder: an indexed triangle list as flat arrays.

#include <cstdint>
#include <string>
#include <vector>

#include "tom/view.h"

namespace tom {

/// A vertex stream the builder carries without reading it (see tom::VertexStreamView): its
/// elements move with their vertices and are never interpolated, so every level holds the
/// source's values exactly.
struct VertexStream {
    std::string name;                ///< glTF attribute ("JOINTS_0", "TEXCOORD_2", "_ID") or "TARGET<k>/<ATTRIBUTE>"
    uint32_t component_type = 5126;  ///< glTF component type (tom::component_bytes)
    uint32_t components = 1;         ///< 1 to 4
    bool normalized = false;
    std::vector<uint8_t> data;       ///< vertex_count elements, tightly packed

    uint32_t element_bytes() const noexcept { return components * component_bytes(component_type); }
};

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
    /// The parts (a glTF mesh's primitives, an OBJ's `usemtl` groups): ranges of `indices`' triangles
    /// that tile them in order, each with its material and the streams its source had. Empty for
    /// a mesh of one part drawn with `material`. Parts share the vertex arrays; where two meet they
    /// share vertices (an OBJ's groups) or each has its own coincident copy (glTF primitives),
    /// which the builder ties like a seam.
    std::vector<Part> parts;
    /// Streams carried through the build unread (joints, weights, morph deltas, further texture
    /// coordinates or colours), each one element per vertex, names distinct.
    std::vector<VertexStream> extra_streams;
    /// A skinned mesh's joints in its bind pose: xyz per joint that its JOINTS_n streams index
    /// (the origin of each inverse bind matrix's joint space, in the mesh's space), or empty.
    /// Read by the builder's skinning term only (BuildParams::animation_weight); not stored.
    std::vector<float> joint_positions;

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

/// The optional streams a mesh has, as the bits of MESH `attributes` and Part::attributes
/// (bit k for the k-th stream of for_each_attribute_stream).
uint32_t attribute_bits(const Mesh& mesh) noexcept;

/// What clean_mesh() changed.
struct CleanStats {
    uint32_t welded_vertices = 0;        ///< identical copies merged into an earlier vertex (CleanOptions::weld)
    uint32_t degenerate_triangles = 0;   ///< triangles with a repeated index, removed
    uint32_t unreferenced_vertices = 0;  ///< vertices used by no triangle, removed
};

/// How clean_mesh() treats vertices.
struct CleanOptions {
    /// Identical vertices (the same position and the same value in every stream, carried ones
    /// included: joints, weights, morph deltas) become one, the first; triangles that then repeat
    /// a corner are dropped. An unindexed file (every triangle its own three vertices) becomes an
    /// indexed mesh that can simplify, and its computed normals are smooth; a file's deliberate
    /// splits (hard edges, seams) differ in some stream and stay. Off: the file's vertices as they
    /// are (tombuild --no-weld).
    bool weld = true;
};

/// Checks a mesh and brings it to the form the builder expects: identical vertices welded (by
/// default, see CleanOptions), degenerate triangles and unreferenced vertices dropped, normals
/// computed where absent.
/// \throw MeshError naming `mesh.name` when an index is >= vertex_count, a
///        position is not finite, a stream has the wrong size (a carried stream also when its
///        type is unknown, its components not 1 to 4 or its name repeated), or the mesh has
///        more than 2^32-2 vertices.
/// \post every triangle has three distinct indices; every vertex is referenced; with weld, no
///       two vertices are identical;
///       normals are present (area-weighted from the triangles when absent); the parts still
///       tile the triangles (a part left without triangles is dropped; one part left means none).
/// \throw MeshError also when the parts do not tile the triangles.
CleanStats clean_mesh(Mesh& mesh, const CleanOptions& options = {});

/// One mesh made of several: vertices and triangles appended in order, one part per input (an
/// input with parts keeps them). The streams are the union of the inputs'; where an input lacks
/// one, its vertices get neutral values (normals zero, so clean_mesh computes them; texture
/// coordinates 0; colours opaque white; tangents +x with w = +1) and its part's `attributes` say
/// which streams are its own. Carried streams are joined by name; an input without one gets
/// zero bytes there. The result has parts unless there is a single input without them.
Mesh join_parts(const std::vector<Mesh>& inputs, std::string name);

/// Area-weighted vertex normals from the triangles (zero-area neighbourhoods get +z).
void compute_normals(Mesh& mesh);

} // namespace tom
