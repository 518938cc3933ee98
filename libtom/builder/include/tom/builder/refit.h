// Re-fitted vertices for one level exported on its own.
//
// A TOM's levels share one vertex array: a vertex that survives to a coarse level keeps the
// position and normal it has at full detail, which is what lets any prefix be a level. A level
// written out alone (tomextract to OBJ, PLY or a one-level .glb) needs no such sharing, and can
// move its vertices to where they best stand for the surface they replaced, as gltfpack's -sv
// and meshoptimizer's simplifyWithUpdate do.
#pragma once

#include "tom/view.h"

#include <cstdint>
#include <vector>

namespace tom {

struct RefitStats {
    uint32_t moved = 0;     ///< points (coincident copies count once) given a new position
    uint32_t fixed = 0;     ///< live points left in place: on an open edge or where parts meet
    uint32_t reverted = 0;  ///< points put back because a triangle of theirs would turn over
    uint32_t kept = 0;      ///< points left in place because no move lowered their local error
};

/// A level's own vertex streams (each value-per-vertex * vertex_count, empty when the mesh has
/// none of that stream).
struct RefitLevel {
    std::vector<float> positions;  ///< xyz
    std::vector<float> normals;    ///< xyz
    std::vector<float> texcoords;  ///< uv
    std::vector<float> texcoords1; ///< uv
    std::vector<float> colors;     ///< rgba
    std::vector<float> tangents;   ///< xyzw
    uint32_t resolution = 0;       ///< the level's vertex count, n as extract() takes it
    RefitStats stats;
};

/// The level of `m` at resolution `n` (taken as extract() takes it: into [min_vertex_count,
/// vertex_count], never among a group's copies; its triangles are extract(m, n)'s) with each
/// live point moved to the minimum of the quadric of the full mesh's triangles around every
/// vertex it stands for (itself and the vertices whose substitution chains end at it), held
/// near its own position along the directions the quadric leaves free, then fitted to the
/// full mesh's surface (Hoppe et al. 1993's fit: area-weighted samples of the full mesh, their
/// squared distances to the level minimised); each point then takes, of its full-detail
/// position, its quadric's minimum and its fitted position, the one where the two-sided error
/// of the triangles around it is the smallest. A moved vertex's normal,
/// texture coordinates, colour and tangent are first the source's where it now stands (at the
/// closest point of the triangles around the vertices it stands for, on its side of a seam or
/// hard edge: its texture does not slide); then every live vertex's normal, texture coordinates
/// and colour are fitted to the source's the same way (at three inner points of every source
/// triangle, the level's values interpolated at the nearest point of the level triangles on its
/// side against the source's: their squared differences minimised, normals as directions), and
/// tangents made orthogonal to the normals again. A point is a
/// vertex with its coincident copies and the group of copies the builder removes together
/// (seams, hard edges, poles): they move as one. Points on open edges or on edges where more
/// than two triangles meet stay, so that borders and the chains where parts meet do not open;
/// a point whose move would turn one of the level's triangles by more than 78 degrees stays.
/// Vertices >= n keep their values, the vertices that stay their positions; the carried streams
/// (joints, weights, morph deltas) are not re-fitted. Deterministic.
RefitLevel refit_level(const MeshView& m, uint32_t n);

/// `m` with the vertex streams `r` has in place of its own (for the exporters).
MeshView refit_view(const MeshView& m, const RefitLevel& r);

} // namespace tom
