// Compressed glTF output: quantization and meshoptimizer's encoders (see gltf_compress.h).

#include "gltf_compress.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <meshoptimizer.h>

namespace tom::detail {

VertexOrder fetch_order(const std::vector<uint32_t>& indices, uint32_t vertex_count) {
    std::vector<uint32_t> cached(indices.size());
    meshopt_optimizeVertexCache(cached.data(), indices.data(), indices.size(), vertex_count);
    VertexOrder out;
    out.remap.resize(vertex_count);
    const size_t used = meshopt_optimizeVertexFetchRemap(out.remap.data(), cached.data(), cached.size(), vertex_count);
    uint32_t next = uint32_t(used);
    for (uint32_t& r : out.remap)
        if (r == ~0u) r = next++;  // vertices the finest level does not use, after the rest
    out.order.resize(vertex_count);
    for (uint32_t v = 0; v < vertex_count; ++v) out.order[out.remap[v]] = v;
    return out;
}

std::vector<uint32_t> optimized_indices(const uint32_t* indices, size_t count, const VertexOrder& order, uint32_t vertex_count) {
    std::vector<uint32_t> remapped(count), out(count);
    for (size_t i = 0; i < count; ++i) remapped[i] = order.remap[indices[i]];
    meshopt_optimizeVertexCache(out.data(), remapped.data(), count, vertex_count);
    return out;
}

std::vector<uint8_t> encode_attributes(const void* data, size_t count, size_t stride) {
    std::vector<uint8_t> out(meshopt_encodeVertexBufferBound(count, stride));
    out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), data, count, stride));
    return out;
}

std::vector<uint8_t> encode_triangles(const void* indices, size_t count, size_t stride) {
    std::vector<uint32_t> wide(count);
    for (size_t i = 0; i < count; ++i) {
        if (stride == 2) {
            uint16_t v;
            std::memcpy(&v, static_cast<const uint8_t*>(indices) + 2 * i, 2);
            wide[i] = v;
        } else {
            std::memcpy(&wide[i], static_cast<const uint8_t*>(indices) + 4 * i, 4);
        }
    }
    uint32_t vertices = 0;
    for (const uint32_t v : wide) vertices = std::max(vertices, v + 1);
    meshopt_encodeIndexVersion(1);  // what EXT_meshopt_compression decoders read since meshoptimizer 0.14
    std::vector<uint8_t> out(meshopt_encodeIndexBufferBound(count, vertices));
    out.resize(meshopt_encodeIndexBuffer(out.data(), out.size(), wide.data(), count));
    return out;
}

QuantizedPositions quantize_positions(const float* positions, const VertexOrder& order) {
    QuantizedPositions q;
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (size_t i = 0; i < order.order.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const float x = positions[3 * size_t(order.order[i]) + size_t(k)];
            lo[k] = i ? std::min(lo[k], x) : x;
            hi[k] = i ? std::max(hi[k], x) : x;
        }
    // one scale for all axes: the grid is a cube, so the dequantization keeps normals as they are
    const double extent = std::max({double(hi[0]) - lo[0], double(hi[1]) - lo[1], double(hi[2]) - lo[2]});
    const double steps = (1 << kPositionBits) - 1, scale = extent > 0 ? extent / steps : 1.0;
    q.values.resize(order.order.size() * 4, 0);
    for (int k = 0; k < 3; ++k) q.lo[k] = 0xFFFF, q.hi[k] = 0;
    for (size_t i = 0; i < order.order.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const double x = (double(positions[3 * size_t(order.order[i]) + size_t(k)]) - lo[k]) / scale;
            const uint16_t v = uint16_t(std::min(steps, std::max(0.0, std::round(x))));
            q.values[4 * i + size_t(k)] = v;
            q.lo[k] = std::min(q.lo[k], v), q.hi[k] = std::max(q.hi[k], v);
        }
    if (order.order.empty()) std::fill(q.lo, q.lo + 3, uint16_t(0));
    q.dequantize = {scale, 0, 0, 0, 0, scale, 0, 0, 0, 0, scale, 0, lo[0], lo[1], lo[2], 1};
    return q;
}

std::vector<int8_t> octahedral_unit_vectors(const float* vectors, size_t width, const VertexOrder& order) {
    std::vector<float> unit(order.order.size() * 4);
    for (size_t i = 0; i < order.order.size(); ++i) {
        const float* v = vectors + width * size_t(order.order[i]);
        const double len = std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]);
        float* u = &unit[4 * i];
        if (len > 0)
            for (int k = 0; k < 3; ++k) u[k] = float(v[k] / len);
        else if (width == 3)  // a zero vector becomes +z (a normal) or +x (a tangent), as the float output writes it
            u[0] = 0, u[1] = 0, u[2] = 1;
        else
            u[0] = 1, u[1] = 0, u[2] = 0;
        u[3] = width == 4 ? (v[3] < 0 ? -1.0f : 1.0f) : 0.0f;
    }
    std::vector<int8_t> out(unit.size());
    meshopt_encodeFilterOct(out.data(), order.order.size(), 4, 8, unit.data());
    return out;
}

std::vector<uint16_t> quantize_texcoords(const float* uv, const VertexOrder& order) {
    std::vector<uint16_t> out(order.order.size() * 2);
    for (size_t i = 0; i < order.order.size(); ++i)
        for (int k = 0; k < 2; ++k) {
            const float x = uv[2 * size_t(order.order[i]) + size_t(k)];
            if (!(x >= 0.0f && x <= 1.0f)) return {};
            out[2 * i + size_t(k)] = uint16_t(std::lround(double(x) * 65535));
        }
    return out;
}

std::vector<uint8_t> quantize_colors(const float* rgba, const VertexOrder& order) {
    std::vector<uint8_t> out(order.order.size() * 4);
    for (size_t i = 0; i < order.order.size(); ++i)
        for (int k = 0; k < 4; ++k) {
            const float x = rgba[4 * size_t(order.order[i]) + size_t(k)];
            out[4 * i + size_t(k)] = uint8_t(std::lround(std::max(0.0f, std::min(1.0f, x)) * 255));
        }
    return out;
}

std::vector<uint8_t> gather(const uint8_t* data, size_t bytes, size_t stride, const VertexOrder& order) {
    std::vector<uint8_t> out(order.order.size() * stride, 0);
    for (size_t i = 0; i < order.order.size(); ++i) std::memcpy(&out[i * stride], data + size_t(order.order[i]) * bytes, bytes);
    return out;
}

} // namespace tom::detail
