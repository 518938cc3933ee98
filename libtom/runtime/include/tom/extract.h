#pragma once
// Extraction of an index buffer at any resolution (TOM paper, section 3.2):
// vertices [0, n) are sent as they are; each corner v of the active triangles is
// mapped by `while (v >= n) v = substitute[v]`.

#include <cstddef>
#include <cstdint>

#include "tom/view.h"

namespace tom {

/// The resolution actually extracted.
struct Extracted {
    uint32_t vertex_count = 0;    ///< n: the caller draws vertices [0, n)
    uint32_t triangle_count = 0;  ///< triangles written (3 indices each)
};

/// How low a selection by count, fraction or error may go: to the usable floor tombuild stored
/// with the mesh (error_curve.h, UsableFloor; below it the error of the chain's last steps grows
/// out of proportion), or, when asked, to the chain's coarsest level, min_vertex_count.
enum class Floor : uint8_t { usable, coarsest };

/// The lowest resolution a selection with `floor` picks: the stored usable floor (raised to keep
/// groups of copies whole) or min_vertex_count when none is stored or with Floor::coarsest.
uint32_t floor_vertex_count(const MeshView& mesh, Floor floor = Floor::usable) noexcept;

/// Number of triangles alive at resolution `vertex_count` (clamped to
/// [min_vertex_count, vertex_count], and lowered to keep every group of copies whole: see
/// MeshView::whole_groups_below), over all parts. O(P log T) chain walks; allocates nothing.
uint32_t active_triangle_count(const MeshView& mesh, uint32_t vertex_count) noexcept;

/// Smallest resolution n, at or above floor_vertex_count(mesh, floor), whose active triangle
/// count is >= `triangle_count` (the full vertex count if `triangle_count` exceeds the mesh's).
uint32_t vertex_count_for_triangles(const MeshView& mesh, uint32_t triangle_count, Floor floor = Floor::usable) noexcept;

/// Largest resolution n whose active triangle count is <= `triangle_count` (the floor when even
/// that has more): for budgets that must not be exceeded.
uint32_t vertex_count_within_triangles(const MeshView& mesh, uint32_t triangle_count, Floor floor = Floor::usable) noexcept;

/// Resolution for a fraction in [0, 1] of the mesh's triangles (see vertex_count_for_triangles);
/// 0 gives the floor.
uint32_t vertex_count_for_fraction(const MeshView& mesh, double triangle_fraction, Floor floor = Floor::usable) noexcept;

/// Writes the index buffer at resolution `vertex_count` (clamped as above) into `destination`.
/// At or below a file's coarse resolution (MeshView::coarse_resolution, FORMAT.md section COAR)
/// the corners are read from the coarse corners, already mapped that far; the result is the same.
/// At most `destination_capacity` indices (rounded down to whole triangles) are written: a
/// buffer of 3 * mesh.triangle_count indices always suffices, and so does one of
/// 3 * active_triangle_count(mesh, vertex_count). The walk stops at the first inactive
/// triangle, so no count has to be computed first. A mesh with parts gives its parts' live
/// triangles one after the other (extract_parts says where each part's are).
/// Every written index is < the returned vertex_count; no triangle is degenerate.
/// The uint16_t form requires vertex_count <= 65536. Allocates nothing.
Extracted extract(const MeshView& mesh, uint32_t vertex_count, uint32_t* destination, size_t destination_capacity) noexcept;
Extracted extract(const MeshView& mesh, uint32_t vertex_count, uint16_t* destination, size_t destination_capacity) noexcept;

/// One part's draw in a buffer written by extract_parts: indices
/// [first_index, first_index + index_count) of the buffer, drawn with `material` over the
/// shared vertex prefix [0, n) (a sub-mesh in Unity, a surface in Godot).
struct PartDraw {
    uint32_t first_index = 0;
    uint32_t index_count = 0;   ///< 3 per live triangle of the part
    int32_t material = -1;
};

/// extract() for a mesh of several parts, saying where each part's triangles went: the parts'
/// live triangles are written one after the other, in part order, and draws[p] receives part p's
/// range (part_count(mesh) entries). extract() writes the same buffer; on a mesh without parts
/// this is extract() with one draw. A buffer too small ends the writing at a whole triangle; the
/// parts it did not reach get empty draws. Allocates nothing.
Extracted extract_parts(const MeshView& mesh, uint32_t vertex_count, uint32_t* destination, size_t destination_capacity, PartDraw* draws) noexcept;
Extracted extract_parts(const MeshView& mesh, uint32_t vertex_count, uint16_t* destination, size_t destination_capacity, PartDraw* draws) noexcept;

/// Live triangles of part p at resolution `vertex_count` (clamped as in active_triangle_count).
uint32_t active_part_triangle_count(const MeshView& mesh, uint32_t p, uint32_t vertex_count) noexcept;

/// The one vertex that moves in a geomorph between resolutions n and n + 1 (TOM paper: only
/// vertex n changes between them). Streams the mesh lacks are left zero.
struct MorphedVertex {
    uint32_t index = 0;        ///< n: overwrite this vertex of the n + 1 prefix with the values below
    float position[3] = {0, 0, 0};
    float normal[3] = {0, 0, 0};   ///< interpolated, then normalised
    float texcoord[2] = {0, 0};
    float color[4] = {0, 0, 0, 0};
    float texcoord1[2] = {0, 0};
    float tangent[4] = {0, 0, 0, 0}; ///< xyz interpolated and normalised; w the sign (+-1) of the interpolated w
};

/// Attributes of vertex n at the fractional resolution n + a, a in [0, 1]: interpolated from its
/// substitute's (a = 0: the surface of resolution n) to its own (a = 1: resolution n + 1). Draw
/// vertices [0, n + 1) with this vertex replaced and the index buffer of resolution n + 1. When
/// n is the first copy of a group (mesh.splits_pair(n + 1): a seam's pair, a pole's fan), morph
/// every copy of the group with the same a and draw the index buffer of the resolution above it
/// (mesh.whole_groups_above(n + 1)).
/// \pre min_vertex_count <= n < vertex_count. Allocates nothing.
MorphedVertex geomorph(const MeshView& mesh, uint32_t n, float a) noexcept;

/// Substitution-chain statistics of one resolution (the paper's Fig. 6).
struct ChainStats {
    uint64_t corners = 0;        ///< corners of the active triangles
    uint64_t steps = 0;          ///< substitution steps walked over all corners
    uint32_t max_steps = 0;
    /// histogram[k] = corners whose chain has k steps; the last bin counts >= its index.
    static constexpr int histogram_bins = 16;
    uint64_t histogram[histogram_bins] = {};
};

/// Walks the active triangles at resolution `vertex_count` and counts chain lengths.
ChainStats chain_stats(const MeshView& mesh, uint32_t vertex_count) noexcept;

} // namespace tom
