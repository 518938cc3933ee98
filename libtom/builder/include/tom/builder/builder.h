#pragma once
// Greedy vertex substitution into a Totally Ordered Mesh (Gobbetti & Bouvier 1999).

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "tom/builder/mesh.h"
#include "tom/view.h"

namespace tom {

/// The fairness predicate: the priority of a substitution v1 -> v2 (lower is better).
enum class Predicate {
    quadric,     ///< Garland-Heckbert quadric of v1 evaluated at v2: the squared distances to the planes merged into v1, weighted by sqrt(area), summed (error accumulates through merges)
    memoryless,  ///< the TOM paper's penalty: dVolume + |v1-v2| dArea + inversion + normal-angle term
};

/// How the greedy order is produced.
enum class Strategy {
    passes,  ///< passes of independent substitutions sorted by priority (meshoptimizer-style)
    heap,    ///< a priority heap with local re-evaluation after each substitution (the paper)
};

struct BuildParams {
    Predicate predicate = Predicate::quadric;
    Strategy strategy = Strategy::passes;
    /// Binary oracle: besides edges, vertex pairs closer than this (object units) may be
    /// substituted, joining separate parts. 0 = edges only.
    float pair_threshold = 0.0f;
    /// passes only: the share of the live vertices a pass may remove, in (0, 1].
    /// Smaller follows the greedy order more closely and takes more passes.
    float pass_fraction = 0.1f;
    /// Weight of the attribute term in both predicates (normals, TEXCOORD_0, COLOR_0 against the
    /// attribute fields of the surface a vertex leaves; see libtom/builder/src/attribute_error.h). 0 = geometry only.
    float attribute_weight = 1.0f;
    /// TEXCOORD_0 weighs in the attribute term: a texture mapped through it would slide. A caller
    /// that knows no material samples it clears this (tombuild does, from the file's materials):
    /// the coordinates are still carried, but hold the geometry back no more than any other
    /// unread stream (gltfpack drops them). On a UV sphere without a texture they kept the pole
    /// fans dense and cost 37% of the mean error at 50% of the triangles.
    bool weigh_texcoords = true;
    /// Weight of the animation terms in both predicates: a skinned mesh's joint centroid (its
    /// joints' bind-pose positions averaged by its weights, Mesh::joint_positions) and each morph
    /// target's position deltas count like attributes, so that a vertex is not substituted onto
    /// one that moves otherwise in a pose or a target (see attribute_error.h). 0 = off.
    float animation_weight = 1.0f;
    /// Binary oracle: no substitution may turn a surviving triangle's normal by more than this
    /// (degrees, 1..90; 90 forbids flips only, the TOM paper's rule). 60 keeps spikes out of the
    /// coarse levels, whose Hausdorff error would otherwise be about twice as large.
    float max_rotation_degrees = 60.0f;
    /// Threads that share the build (0 = one per core): the quadrics' set-up and, with passes,
    /// each pass's candidate evaluation. Between a pass's parallel loops the helpers spin for up
    /// to 2 ms before they sleep, so a build keeps its cores busy while it runs; they end with
    /// build(). The result is the same for any count.
    unsigned threads = 0;
    /// passes with threads: the team foresees the sequential loop's oracle verdicts and costs
    /// (a speed-up only; the result is byte-identical with it off).
    bool foresight = true;
    /// Vertices on open borders (of the mesh welded by position: not the borders between parts
    /// or along attribute seams) are never removed, so a mesh meant to tile with its neighbours
    /// (terrain tiles, modular kits) keeps its outline at every resolution (meshoptimizer's
    /// LockBorder, gltfpack's -slb).
    bool lock_borders = false;
    /// Every level keeps the input's topology: a substitution that would join two sheets (the
    /// link condition fails: a thin wall's faces, a box's sides, a torus's hole closing) is
    /// refused, so closed manifolds stay closed manifolds of the same genus and a closed piece
    /// stops at a tetrahedron. Off by default: such a join is taken, as meshoptimizer takes it,
    /// when even at 8 times its cost it is cheaper than what the topology leaves (a building's
    /// walls flatten into double-sided sheets before its roof folds); the scanned meshes' levels
    /// are the same either way down to 10% of their triangles (bunny00's and fandisk's all the
    /// way down); below, the cow and the elephant lose less, a 4-triangle cross more.
    bool keep_topology = false;
    /// Vertices closer than this share of the bounding box's diagonal are copies of one point
    /// (split by a seam, a hard edge or a pole's fan, or never indexed): with Strategy::passes the
    /// copies of a point inside the surface move together, each onto a copy of the same
    /// neighbouring point, so the mesh welded by position never cracks; copies of a point on an
    /// open border stay in place. Exporters' copies often differ in the last bits (a generated
    /// sphere's seam at sin(2 pi) = -2.4e-16); 0 joins exact copies only.
    float copy_tolerance = 1e-6f;
    /// Called on the calling thread after each pass (Strategy::passes) with the share of the
    /// vertices removed so far, which follows the work done (a pass's work is its live
    /// vertices): for a progress display on long builds. Never changes the result.
    std::function<void(double)> progress;
};

/// What the builder did, for reports.
struct BuildStats {
    uint32_t substitutions = 0;      ///< vertices removed = vertex_count - min_vertex_count
    uint32_t locked_vertices = 0;    ///< never substituted: non-manifold, coincident copies, border corners
    uint32_t border_vertices = 0;
    uint32_t seam_vertices = 0;      ///< copies of interior points (seams, hard edges, pole fans), which move as groups
    uint32_t passes = 0;             ///< passes (Strategy::passes) or 0
    uint32_t pair_candidates = 0;    ///< non-edge pairs offered by the oracle
    uint32_t foreseen_chunks = 0;    ///< chunks of candidates the foresight evaluated ahead (0 without it)
    uint32_t pruned_pieces = 0;      ///< disconnected pieces removed whole (all but the largest may go, cheapest first)
};

/// A named binary value stored with a mesh (FORMAT.md, section META).
using MetadataEntry = std::pair<std::string, std::vector<uint8_t>>;

/// A built TOM mesh in memory: every stream sorted so that resolution n uses
/// vertices [0, n) and a prefix of the triangles.
struct TomMesh {
    std::string name;
    int32_t material = -1;
    uint32_t min_vertex_count = 0;
    std::vector<float> positions, normals, texcoords, colors, texcoords1, tangents;  ///< sorted, as in Mesh
    std::vector<uint32_t> substitute;     ///< per vertex: substitute[i] < i, or i for survivors
    std::vector<uint32_t> triangles;      ///< 3 per triangle, original corners, sorted by death
    std::vector<uint32_t> original_index; ///< sorted vertex -> index in the cleaned input (not stored in files)
    std::vector<uint32_t> original_triangle; ///< sorted triangle -> index in the cleaned input (not stored in files)
    std::vector<uint8_t> pair_bits;       ///< bit i (LSB first): vertices i and i + 1 are a seam pair, removed together; empty if none
    /// The input's parts, in its order, each a range of `triangles` sorted by death on its own
    /// (FORMAT.md, section PART); empty for a mesh of one part.
    std::vector<Part> parts;
    std::vector<MetadataEntry> metadata;
    std::vector<VertexStream> extra_streams;  ///< the input's carried streams, sorted as the vertices (not in view())
    float bounds_min[3] = {0, 0, 0};
    float bounds_max[3] = {0, 0, 0};

    uint32_t vertex_count() const noexcept { return uint32_t(positions.size() / 3); }
    uint32_t triangle_count() const noexcept { return uint32_t(triangles.size() / 3); }
    /// A view for extraction; valid while this TomMesh lives and is not modified.
    MeshView view() const noexcept;
};

/// Builds the total order of a mesh.
/// \pre `mesh` went through clean_mesh() (distinct corners, all vertices referenced, normals present).
/// Works on any input: borders, non-manifold edges, several components, zero-area triangles and
/// coincident vertices are handled (such vertices are locked so no crack can open). The parts'
/// common borders are coincident copies too: they collapse together or not at all.
/// No substitution flips a triangle. Runs until no legal substitution is left.
TomMesh build(const Mesh& mesh, const BuildParams& params = {}, BuildStats* stats = nullptr);

/// The same build of a mesh the caller gives up: its vertex streams are freed as soon as the
/// builder has its own copy, which lowers the build's peak by about 12 bytes a triangle (a mesh
/// with normals alone). The result is byte-identical; `mesh` is left empty. To go on using
/// the input (a report, an error curve), take it back with original_mesh().
TomMesh build(Mesh&& mesh, const BuildParams& params = {}, BuildStats* stats = nullptr);

/// The mesh `tom` was built from, exactly (after clean_mesh()): every stream in the input's
/// vertex order, the triangles in its order with their corners and winding, its parts and
/// material. Only the parts' `attributes` can differ: they keep just the streams the input had.
/// \throw tom::ArgumentError when `tom` has no map to its input (a TomMesh not made by
///        build(), such as one read from a file).
Mesh original_mesh(const TomMesh& tom);

const char* to_string(Predicate p) noexcept;
const char* to_string(Strategy s) noexcept;

} // namespace tom
