#pragma once
// A mesh's vertices as points: vertices at the same position (equal floats, -0 as 0) share a
// point. The builder's re-fitting (builder/src/refit.cpp) and the stream's quantization
// (stream/src/encode.cpp) treat such copies as one point, so that they stay together.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

namespace tom::detail {

struct PositionPoints {
    std::vector<uint32_t> point;  // per vertex
    uint32_t count = 0;
};

/// The points of `vertex_count` vertices (3 floats each at `positions`), numbered in the order of
/// their lowest vertex. Positions compare by their bits, so a NaN is a point of its own bits.
inline PositionPoints points_by_position(const float* positions, uint32_t vertex_count) {
    auto key = [&](uint32_t v) {
        std::array<uint32_t, 3> k;
        for (int a = 0; a < 3; ++a) {
            const float x = positions[3 * size_t(v) + size_t(a)] + 0.0f;  // -0 as 0
            std::memcpy(&k[size_t(a)], &x, 4);
        }
        return k;
    };
    std::vector<uint32_t> order(vertex_count);
    for (uint32_t v = 0; v < vertex_count; ++v) order[v] = v;
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
    std::vector<uint32_t> lowest(vertex_count);  // per vertex: the lowest vertex at its position
    for (size_t i = 0; i < vertex_count;) {
        size_t j = i;
        const std::array<uint32_t, 3> k = key(order[i]);
        while (j < vertex_count && key(order[j]) == k) ++j;
        for (size_t x = i; x < j; ++x) lowest[order[x]] = order[i];  // stable: order[i] is the lowest
        i = j;
    }
    PositionPoints p;
    p.point.resize(vertex_count);
    for (uint32_t v = 0; v < vertex_count; ++v) p.point[v] = lowest[v] == v ? p.count++ : p.point[lowest[v]];  // lowest[v] <= v: numbered
    return p;
}

}  // namespace tom::detail
