#pragma once
// Shared by the tests: named meshes by category (generated and real) and the invariants every
// built TOM must satisfy, checked by brute force against the definitions.

#include <cstdint>
#include <string>
#include <vector>

#include "tom/builder/builder.h"
#include "tom/builder/mesh.h"
#include "tom/view.h"

namespace test {

struct NamedMesh {
    std::string name;
    tom::Mesh mesh;               ///< cleaned (clean_mesh applied)
    bool closed_manifold = false; ///< every edge in exactly two consistently oriented triangles
    int euler = 0;                ///< V - E + F, meaningful when closed_manifold
};

/// Path of a sample under data/ (scripts/fetch-samples.sh); fails the test with the
/// fetch instruction when it is missing.
std::string sample(const std::string& relative);

/// Small meshes made here: sphere, torus, bumpy sphere, grid with a border, two components,
/// coincident duplicated vertices, a non-manifold fan, degenerate and zero-area triangles.
std::vector<NamedMesh> generated_meshes();
/// Real meshes from the samples: bunny00, fandisk, cow, elephant (OFF), WusonOBJ and spider
/// (OBJ), Spider_binary (STL), cube_binary (PLY), the largest 2CylinderEngine primitive (GLB).
std::vector<NamedMesh> real_meshes();

/// Triangles alive at resolution n, found by walking every triangle's chains (no shortcut);
/// also checks that they form a prefix of the triangle array. Returns the mapped triples.
std::vector<uint32_t> brute_force_active(const tom::MeshView& m, uint32_t n);
/// The triangles [begin, end) alive at resolution n, mapped, appended to `out`; REQUIREs that they
/// are a prefix of the range (a part's range, or the whole mesh's).
void brute_force_part(const tom::MeshView& m, uint32_t n, uint32_t begin, uint32_t end, std::vector<uint32_t>& out);

/// Checks every invariant of a built hierarchy against its input (Catch2 assertions):
/// counts, substitute[i] < i, the vertex permutation, full resolution = input triangles,
/// prefix property and extraction at sampled resolutions, monotone triangle counts, no
/// substitution flips a triangle (replayed one by one), no new border edges after welding by
/// position (no cracks), and for closed manifolds: still closed and, at every level built with
/// `topology_kept` (BuildParams::keep_topology) or else at the levels with a tenth of the
/// triangles or more (joins only where the manifold moves left cost far more), manifold with the
/// same Euler number.
void check_invariants(const NamedMesh& input, const tom::TomMesh& built, bool topology_kept = false);

/// Euler characteristic and border edges of a triangle list (vertices welded by position).
struct Topology {
    int vertices = 0, edges = 0, faces = 0;
    int border_edges = 0;       ///< edges used once
    int nonmanifold_edges = 0;  ///< edges used more than twice
    int euler() const { return vertices - edges + faces; }
};
/// Welding by position joins vertices within 1e-6 of the bounding box's diagonal (the builder's
/// BuildParams::copy_tolerance: exporters' copies differ in the last bits).
Topology topology(const float* positions, const uint32_t* indices, size_t triangle_count, bool weld_by_position);

/// The positions with every vertex moved onto its point: vertices within 1e-6 of the diagonal of
/// each other (and chains of such) take the lexicographically smallest position among them, so
/// that the same points get the same position whatever the vertex order.
std::vector<float> snap_copies(const float* positions, size_t vertex_count);

} // namespace test
