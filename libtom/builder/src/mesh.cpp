// Mesh validation and normal computation.

#include "tom/builder/mesh.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "tom/errors.h"

namespace tom {

namespace {

void check_stream(const Mesh& mesh, const std::vector<float>& stream, size_t width, const char* what) {
    if (!stream.empty() && stream.size() != size_t(mesh.vertex_count()) * width)
        throw MeshError("mesh '" + mesh.name + "': " + what + " stream has " + std::to_string(stream.size() / width) +
                          " elements for " + std::to_string(mesh.vertex_count()) + " vertices");
}

// A carried stream: a known type, 1 to 4 components, one element per vertex, a name of its own.
void check_extra_streams(const Mesh& mesh) {
    for (size_t k = 0; k < mesh.extra_streams.size(); ++k) {
        const VertexStream& x = mesh.extra_streams[k];
        const std::string what = "mesh '" + mesh.name + "': carried stream '" + x.name + "'";
        if (x.element_bytes() == 0 || x.components > 4)
            throw MeshError(what + " has component type " + std::to_string(x.component_type) + " and " + std::to_string(x.components) + " components");
        if (x.data.size() != size_t(mesh.vertex_count()) * x.element_bytes())
            throw MeshError(what + " has " + std::to_string(x.data.size()) + " bytes for " + std::to_string(mesh.vertex_count()) + " vertices");
        for (size_t j = 0; j < k; ++j)
            if (mesh.extra_streams[j].name == x.name) throw MeshError(what + " appears twice");
    }
}

// A skinned mesh's data: joint positions finite, weights finite and non-negative, and with joint
// positions every JOINTS_k value one of those joints (glTF's rule for a skin's joint list).
void check_skin(const Mesh& mesh) {
    const std::string what = "mesh '" + mesh.name + "': ";
    if (mesh.joint_positions.size() % 3 != 0)
        throw MeshError(what + "joint position stream length " + std::to_string(mesh.joint_positions.size()) + " is not a multiple of 3");
    for (size_t i = 0; i < mesh.joint_positions.size(); ++i)
        if (!std::isfinite(mesh.joint_positions[i])) throw MeshError(what + "joint " + std::to_string(i / 3) + " has a non-finite position");
    const size_t joints = mesh.joint_positions.size() / 3;
    for (const VertexStream& x : mesh.extra_streams) {
        const bool weights = x.name.rfind("WEIGHTS_", 0) == 0, indices = x.name.rfind("JOINTS_", 0) == 0 && joints > 0;
        if (!weights && !indices) continue;
        const uint32_t size = component_bytes(x.component_type);
        for (size_t i = 0; i < x.data.size() / size; ++i) {
            const double value = component_value(x.component_type, x.normalized, &x.data[i * size]);
            const std::string at = what + x.name + " of vertex " + std::to_string(i / x.components) + " is ";
            if (weights && !(value >= 0 && std::isfinite(value))) throw MeshError(at + std::to_string(value) + ": a weight must be finite and non-negative");
            if (indices && !(value < double(joints)))
                throw MeshError(at + std::to_string(uint64_t(value)) + ", past the skin's " + std::to_string(joints) + " joints");
        }
    }
}

template <class T>
void compact_stream(std::vector<T>& stream, const std::vector<uint32_t>& remap, size_t width, uint32_t new_count) {
    if (stream.empty()) return;
    std::vector<T> out(size_t(new_count) * width);
    for (size_t v = 0; v < remap.size(); ++v)
        if (remap[v] != UINT32_MAX)
            for (size_t k = 0; k < width; ++k) out[remap[v] * width + k] = stream[v * width + k];
    stream.swap(out);
}

// Degenerate triangles removed: each part's range shrinks by those it lost; empty parts go.
void recount_parts(Mesh& mesh, const std::vector<uint32_t>& kept_before) {
    std::vector<Part> parts;
    for (Part p : mesh.parts) {
        const uint32_t first = kept_before[p.first_triangle], end = kept_before[p.first_triangle + p.triangle_count];
        p.first_triangle = first;
        p.triangle_count = end - first;
        if (p.triangle_count > 0) parts.push_back(p);
    }
    if (parts.size() == 1) {
        mesh.material = parts[0].material;
        parts.clear();
    }
    mesh.parts.swap(parts);
}

void check_parts(const Mesh& mesh) {
    uint64_t next = 0;
    for (size_t k = 0; k < mesh.parts.size(); ++k) {
        if (mesh.parts[k].first_triangle != next)
            throw MeshError("mesh '" + mesh.name + "': part " + std::to_string(k) + " starts at triangle " + std::to_string(mesh.parts[k].first_triangle) +
                              ", not where the previous part ends (" + std::to_string(next) + ")");
        next += mesh.parts[k].triangle_count;
    }
    if (!mesh.parts.empty() && next != mesh.triangle_count())
        throw MeshError("mesh '" + mesh.name + "': the parts cover " + std::to_string(next) + " of " + std::to_string(mesh.triangle_count()) + " triangles");
}

// Identical vertices (CleanOptions::weld) merged into the first of them: an open-addressing table
// of the vertices' hashes over the position and every stream, compared value by value (0 and -0
// alike; a NaN equals nothing). Returns vertex -> the vertex that stands for it.
std::vector<uint32_t> identical_vertices(const Mesh& mesh) {
    struct Stream {
        const float* values;
        size_t width;
    };
    std::vector<Stream> streams{{mesh.positions.data(), 3}};
    for_each_attribute_stream(mesh, [&](const std::vector<float>& s, size_t width, const char*) {
        if (!s.empty()) streams.push_back({s.data(), width});
    });
    const uint32_t n = mesh.vertex_count();
    auto hash_of = [&](uint32_t v) {
        uint64_t h = 0x9e3779b97f4a7c15ULL;
        auto mix = [&](uint64_t x) {
            h ^= x + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
            h *= 0xbf58476d1ce4e5b9ULL;
        };
        for (const Stream& s : streams)
            for (size_t k = 0; k < s.width; ++k) {
                const float x = s.values[v * s.width + k];
                uint32_t bits = 0;
                if (x != 0.0f) std::memcpy(&bits, &x, 4);
                mix(bits);
            }
        for (const VertexStream& x : mesh.extra_streams) {
            const size_t bytes = x.element_bytes();
            for (size_t k = 0; k < bytes; ++k) mix(x.data[v * bytes + k]);
        }
        return h ^ (h >> 31);
    };
    auto same = [&](uint32_t a, uint32_t b) {
        for (const Stream& s : streams)
            for (size_t k = 0; k < s.width; ++k)
                if (!(s.values[a * s.width + k] == s.values[b * s.width + k])) return false;
        for (const VertexStream& x : mesh.extra_streams) {
            const size_t bytes = x.element_bytes();
            if (std::memcmp(&x.data[a * bytes], &x.data[b * bytes], bytes) != 0) return false;
        }
        return true;
    };
    size_t cap = 16;
    while (cap < size_t(n) * 2) cap *= 2;
    std::vector<uint32_t> table(cap, UINT32_MAX), first(n);
    for (uint32_t v = 0; v < n; ++v)
        for (size_t i = size_t(hash_of(v)) & (cap - 1);; i = (i + 1) & (cap - 1)) {
            if (table[i] == UINT32_MAX) {
                table[i] = first[v] = v;
                break;
            }
            if (same(table[i], v)) {
                first[v] = table[i];
                break;
            }
        }
    return first;
}

// Welds identical vertices: each triangle's corners rewritten to the first of their copies (the
// others, now unreferenced, go with the unreferenced vertices). Returns the referenced vertices
// merged.
uint32_t weld_identical(Mesh& mesh) {
    const std::vector<uint32_t> first = identical_vertices(mesh);
    std::vector<uint8_t> counted(first.size(), 0);
    uint32_t welded = 0;
    for (uint32_t& i : mesh.indices) {
        if (first[i] != i && !counted[i]) {
            counted[i] = 1;
            ++welded;
        }
        i = first[i];
    }
    return welded;
}

} // namespace

uint32_t attribute_bits(const Mesh& mesh) noexcept {
    uint32_t bits = 0, k = 0;
    for_each_attribute_stream(mesh, [&](const std::vector<float>& stream, size_t, const char*) { bits |= (stream.empty() ? 0u : 1u) << k++; });
    return bits;
}

namespace {

// Appends `in`'s carried streams to `out`'s (n vertices): by name, the first input that has a
// stream giving its type; zero bytes where `in` lacks it.
void join_extra_streams(const std::vector<Mesh>& inputs, const Mesh& in, uint32_t n, Mesh& out) {
    for (const Mesh& any : inputs)
        for (const VertexStream& x : any.extra_streams) {
            auto it = std::find_if(out.extra_streams.begin(), out.extra_streams.end(), [&](const VertexStream& o) { return o.name == x.name; });
            if (it == out.extra_streams.end()) {
                out.extra_streams.push_back({x.name, x.component_type, x.components, x.normalized, std::vector<uint8_t>(size_t(out.vertex_count() - n) * x.element_bytes(), 0)});
                it = out.extra_streams.end() - 1;
            }
        }
    for (VertexStream& o : out.extra_streams) {
        const auto own = std::find_if(in.extra_streams.begin(), in.extra_streams.end(), [&](const VertexStream& x) { return x.name == o.name; });
        if (own != in.extra_streams.end() && own->component_type == o.component_type && own->components == o.components && own->data.size() == size_t(n) * o.element_bytes())
            o.data.insert(o.data.end(), own->data.begin(), own->data.end());
        else
            o.data.resize(o.data.size() + size_t(n) * o.element_bytes(), 0);
    }
}

} // namespace

Mesh join_parts(const std::vector<Mesh>& inputs, std::string name) {
    Mesh out;
    out.name = std::move(name);
    if (inputs.size() == 1 && inputs[0].parts.empty()) {
        out = inputs[0];
        return out;
    }
    uint32_t present = 0;  // the streams any input has: those the joined mesh has
    for (const Mesh& in : inputs) present |= attribute_bits(in);
    static const float neutral[5][4] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {1, 1, 1, 1}, {0, 0, 0, 0}, {1, 0, 0, 1}};
    for (const Mesh& in : inputs) {
        const uint32_t base = out.vertex_count(), first_triangle = out.triangle_count(), n = in.vertex_count();
        out.positions.insert(out.positions.end(), in.positions.begin(), in.positions.end());
        std::vector<const std::vector<float>*> sources;
        for_each_attribute_stream(in, [&](const std::vector<float>& s, size_t, const char*) { sources.push_back(&s); });
        const uint32_t own = attribute_bits(in);
        size_t k = 0;
        for_each_attribute_stream(out, [&](std::vector<float>& dst, size_t width, const char*) {
            const std::vector<float>& src = *sources[k];
            if (present & (1u << k)) {
                if (src.size() == size_t(n) * width)
                    dst.insert(dst.end(), src.begin(), src.end());
                else
                    for (uint32_t v = 0; v < n; ++v) dst.insert(dst.end(), neutral[k], neutral[k] + width);
            }
            ++k;
        });
        join_extra_streams(inputs, in, n, out);
        for (const uint32_t i : in.indices) out.indices.push_back(base + i);
        if (in.parts.empty()) {
            out.parts.push_back({first_triangle, in.triangle_count(), in.material, own});
        } else {
            for (Part p : in.parts) {
                p.first_triangle += first_triangle;
                out.parts.push_back(p);
            }
        }
    }
    out.material = out.parts.empty() ? -1 : out.parts[0].material;
    if (out.parts.size() == 1) out.parts.clear();
    return out;
}

void compute_normals(Mesh& mesh) {
    const uint32_t n = mesh.vertex_count();
    std::vector<float> acc(size_t(n) * 3, 0.0f);
    const float* p = mesh.positions.data();
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
        const float e1[3] = {p[3 * b] - p[3 * a], p[3 * b + 1] - p[3 * a + 1], p[3 * b + 2] - p[3 * a + 2]};
        const float e2[3] = {p[3 * c] - p[3 * a], p[3 * c + 1] - p[3 * a + 1], p[3 * c + 2] - p[3 * a + 2]};
        // the cross product's length is twice the area: area weighting for free
        const float nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2], nz = e1[0] * e2[1] - e1[1] * e2[0];
        for (uint32_t v : {a, b, c}) {
            acc[3 * v] += nx;
            acc[3 * v + 1] += ny;
            acc[3 * v + 2] += nz;
        }
    }
    for (uint32_t v = 0; v < n; ++v) {
        float* q = &acc[3 * size_t(v)];
        const float len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        if (len > 0.0f) {
            q[0] /= len, q[1] /= len, q[2] /= len;
        } else {
            q[0] = 0.0f, q[1] = 0.0f, q[2] = 1.0f;
        }
    }
    mesh.normals.swap(acc);
}

CleanStats clean_mesh(Mesh& mesh, const CleanOptions& options) {
    CleanStats stats;
    if (mesh.positions.size() % 3 != 0)
        throw MeshError("mesh '" + mesh.name + "': position stream length " + std::to_string(mesh.positions.size()) + " is not a multiple of 3");
    if (mesh.indices.size() % 3 != 0)
        throw MeshError("mesh '" + mesh.name + "': index count " + std::to_string(mesh.indices.size()) + " is not a multiple of 3");
    if (mesh.positions.size() / 3 > size_t(UINT32_MAX) - 1 || mesh.indices.size() / 3 > size_t(UINT32_MAX) - 1)
        throw MeshError("mesh '" + mesh.name + "': more than 2^32-2 vertices or triangles");
    for_each_attribute_stream(mesh, [&](std::vector<float>& stream, size_t width, const char* what) { check_stream(mesh, stream, width, what); });
    check_extra_streams(mesh);
    check_skin(mesh);
    const uint32_t n = mesh.vertex_count();
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        if (!std::isfinite(mesh.positions[i]))
            throw MeshError("mesh '" + mesh.name + "': vertex " + std::to_string(i / 3) + " has a non-finite position");
    for (size_t i = 0; i < mesh.indices.size(); ++i)
        if (mesh.indices[i] >= n)
            throw MeshError("mesh '" + mesh.name + "': triangle " + std::to_string(i / 3) + " uses vertex " +
                              std::to_string(mesh.indices[i]) + " but the mesh has " + std::to_string(n) + " vertices");
    check_parts(mesh);
    for (float& x : mesh.normals)
        if (!std::isfinite(x)) x = 0.0f;  // renormalised below
    if (options.weld) stats.welded_vertices = weld_identical(mesh);

    // drop triangles with a repeated corner: they cover no area and can never be drawn
    size_t out = 0;
    std::vector<uint32_t> kept_before(mesh.parts.empty() ? 0 : mesh.triangle_count() + size_t(1));  // triangles kept before t
    for (size_t t = 0; t < mesh.indices.size(); t += 3) {
        if (!kept_before.empty()) kept_before[t / 3] = uint32_t(out / 3);
        const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
        if (a == b || b == c || a == c) {
            ++stats.degenerate_triangles;
            continue;
        }
        mesh.indices[out++] = a, mesh.indices[out++] = b, mesh.indices[out++] = c;
    }
    if (!kept_before.empty()) kept_before.back() = uint32_t(out / 3);
    mesh.indices.resize(out);
    if (!mesh.parts.empty()) recount_parts(mesh, kept_before);

    // drop unreferenced vertices, keeping the order of the rest
    std::vector<uint32_t> remap(n, UINT32_MAX);
    for (uint32_t i : mesh.indices) remap[i] = 0;
    uint32_t next = 0;
    for (uint32_t v = 0; v < n; ++v)
        if (remap[v] == 0) remap[v] = next++;
    stats.unreferenced_vertices = n - next - stats.welded_vertices;
    if (next != n) {
        compact_stream(mesh.positions, remap, 3, next);
        for_each_attribute_stream(mesh, [&](std::vector<float>& stream, size_t width, const char*) { compact_stream(stream, remap, width, next); });
        for (VertexStream& x : mesh.extra_streams) compact_stream(x.data, remap, x.element_bytes(), next);
        for (uint32_t& i : mesh.indices) i = remap[i];
    }

    if (mesh.normals.empty()) {
        compute_normals(mesh);
    } else {
        // given normals are normalised; zero ones are replaced by computed ones
        bool missing = false;
        for (size_t v = 0; v < mesh.normals.size(); v += 3) {
            float* q = &mesh.normals[v];
            const float len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
            if (len > 0.0f)
                q[0] /= len, q[1] /= len, q[2] /= len;
            else
                missing = true;
        }
        if (missing) {
            std::vector<float> given;
            given.swap(mesh.normals);
            compute_normals(mesh);
            for (size_t v = 0; v < given.size(); v += 3)
                if (given[v] != 0.0f || given[v + 1] != 0.0f || given[v + 2] != 0.0f)
                    for (int k = 0; k < 3; ++k) mesh.normals[v + size_t(k)] = given[v + size_t(k)];
        }
    }
    return stats;
}

} // namespace tom
