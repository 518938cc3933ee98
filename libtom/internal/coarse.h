#pragma once
// The coarse-corner shortcut of a .tom mesh (FORMAT.md, section COAR): what the writer stores and
// the reader checks. Implemented with extraction, in extract.cpp.

#include <cstdint>

#include "tom/view.h"

namespace tom::detail {

/// The resolution whose mapped corners a writer stores for `mesh` (1/64 of its vertices, at
/// most 65536 so they fit 16 bits), or 0 when the mesh is too small to gain from it.
uint32_t coarse_resolution(const MeshView& mesh) noexcept;

/// Bytes per stored coarse corner: 2 when the resolution allows (values < resolution), else 4.
inline uint32_t coarse_index_size(uint32_t resolution) noexcept { return resolution <= 65536 ? 2 : 4; }

/// Stored corner c of TRIS mapped to resolution n (n >= min_vertex_count).
uint32_t map_corner(const MeshView& mesh, uint32_t c, uint32_t n) noexcept;

/// Whether TRIS triangle t is active at exactly resolution n (no seam-pair adjustment).
bool triangle_active(const MeshView& mesh, uint32_t t, uint32_t n) noexcept;

/// The active triangle count at exactly resolution n, from TRIS (no seam-pair adjustment).
uint32_t active_prefix(const MeshView& mesh, uint32_t n) noexcept;

} // namespace tom::detail
