// Procedural meshes for tests and benchmarks.

#include "tom/builder/generate.h"

#include <cmath>

namespace tom {

namespace {
constexpr float kPi = 3.14159265358979323846f;
}

Mesh make_sphere(uint32_t rings, uint32_t segments, float radius, float bump) {
    Mesh m;
    m.name = "sphere";
    rings = rings < 2 ? 2 : rings;
    segments = segments < 3 ? 3 : segments;
    auto add = [&](float theta, float phi) {
        const float r = radius * (1.0f + bump * std::sin(7.0f * theta) * std::sin(9.0f * phi));
        const float nx = std::sin(theta) * std::cos(phi), ny = std::sin(theta) * std::sin(phi), nz = std::cos(theta);
        m.positions.insert(m.positions.end(), {r * nx, r * ny, r * nz});
    };
    add(0.0f, 0.0f);  // north pole = vertex 0
    for (uint32_t i = 1; i < rings; ++i)
        for (uint32_t j = 0; j < segments; ++j) add(kPi * float(i) / float(rings), 2.0f * kPi * float(j) / float(segments));
    add(kPi, 0.0f);  // south pole
    const uint32_t south = 1 + (rings - 1) * segments;
    auto ring_vertex = [&](uint32_t i, uint32_t j) { return 1 + (i - 1) * segments + (j % segments); };
    for (uint32_t j = 0; j < segments; ++j) m.indices.insert(m.indices.end(), {0, ring_vertex(1, j), ring_vertex(1, j + 1)});
    for (uint32_t i = 1; i + 1 < rings; ++i)
        for (uint32_t j = 0; j < segments; ++j) {
            const uint32_t a = ring_vertex(i, j), b = ring_vertex(i, j + 1), c = ring_vertex(i + 1, j), d = ring_vertex(i + 1, j + 1);
            m.indices.insert(m.indices.end(), {a, c, d, a, d, b});
        }
    for (uint32_t j = 0; j < segments; ++j) m.indices.insert(m.indices.end(), {south, ring_vertex(rings - 1, j + 1), ring_vertex(rings - 1, j)});
    return m;
}

Mesh make_grid(uint32_t nx, uint32_t ny, float amplitude) {
    Mesh m;
    m.name = "grid";
    nx = nx < 1 ? 1 : nx;
    ny = ny < 1 ? 1 : ny;
    for (uint32_t j = 0; j <= ny; ++j)
        for (uint32_t i = 0; i <= nx; ++i) {
            const float x = float(i) / float(nx), y = float(j) / float(ny);
            m.positions.insert(m.positions.end(), {x, y, amplitude * std::sin(2 * kPi * x * 3) * std::cos(2 * kPi * y * 2)});
        }
    for (uint32_t j = 0; j < ny; ++j)
        for (uint32_t i = 0; i < nx; ++i) {
            const uint32_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
            m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
        }
    return m;
}

Mesh make_torus(uint32_t rings, uint32_t segments, float major_radius, float minor_radius) {
    Mesh m;
    m.name = "torus";
    rings = rings < 3 ? 3 : rings;
    segments = segments < 3 ? 3 : segments;
    for (uint32_t i = 0; i < rings; ++i)
        for (uint32_t j = 0; j < segments; ++j) {
            const float u = 2 * kPi * float(i) / float(rings), v = 2 * kPi * float(j) / float(segments);
            const float r = major_radius + minor_radius * std::cos(v);
            m.positions.insert(m.positions.end(), {r * std::cos(u), r * std::sin(u), minor_radius * std::sin(v)});
        }
    for (uint32_t i = 0; i < rings; ++i)
        for (uint32_t j = 0; j < segments; ++j) {
            const uint32_t a = i * segments + j, b = i * segments + (j + 1) % segments;
            const uint32_t c = ((i + 1) % rings) * segments + j, d = ((i + 1) % rings) * segments + (j + 1) % segments;
            m.indices.insert(m.indices.end(), {a, c, d, a, d, b});
        }
    return m;
}

} // namespace tom
