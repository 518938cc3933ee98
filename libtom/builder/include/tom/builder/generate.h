#pragma once
// Procedural meshes with known geometry, for tests and benchmarks.

#include <cstdint>

#include "tom/builder/mesh.h"

namespace tom {

/// A closed, welded UV sphere: `rings` >= 2 latitude bands, `segments` >= 3 longitudes, one vertex
/// per pole, 2 * segments * (rings - 1) triangles, outward normals. With `bump` > 0 the radius is
/// modulated by bump * sin(7 theta) * sin(9 phi) so the surface has detail to simplify.
Mesh make_sphere(uint32_t rings, uint32_t segments, float radius = 1.0f, float bump = 0.0f);

/// An open height field over [0,1]^2 with nx * ny quads (2 triangles each) and a border;
/// z = amplitude * sin(2 pi x * 3) * cos(2 pi y * 2).
Mesh make_grid(uint32_t nx, uint32_t ny, float amplitude = 0.1f);

/// A closed torus (genus 1) with `rings` x `segments` quads.
Mesh make_torus(uint32_t rings, uint32_t segments, float major_radius = 1.0f, float minor_radius = 0.3f);

} // namespace tom
