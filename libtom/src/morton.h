#pragma once
// Morton (Z-order) codes: interleaving the bits of three coordinates so that points close in
// space get close codes. Used to order the builder's vertices and the Metro-style samples.

#include <cstdint>

namespace tom::detail {

/// The 16 low bits of x spread to every third bit (bit i to bit 3i): one axis of a Morton code.
inline uint64_t spread_bits(uint64_t x) noexcept {
    x &= 0xFFFF;
    x = (x | x << 16) & 0x0000FF0000FFULL;
    x = (x | x << 8) & 0x00F00F00F00FULL;
    x = (x | x << 4) & 0x0C30C30C30C3ULL;
    x = (x | x << 2) & 0x249249249249ULL;
    return x;
}

} // namespace tom::detail
