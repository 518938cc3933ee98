#pragma once
// Morton (Z-order) codes: interleaving the bits of three coordinates so that points close in
// space get close codes. Used to order the builder's vertices (spread_bits) and the Metro-style
// samples (spread16, the same figure by table: many more of them).

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

/// spread_bits(x) for a 16-bit x by table, a byte at a time: fewer operations than the shifts for
/// the many codes of a report's samples (metrics/samples.cpp).
struct SpreadTable {
    uint32_t of[256];
    constexpr SpreadTable() : of{} {
        for (unsigned x = 0; x < 256; ++x)
            for (unsigned b = 0; b < 8; ++b)
                if (x >> b & 1) of[x] |= 1u << (3 * b);
    }
};
inline constexpr SpreadTable kSpread;
inline uint64_t spread16(uint32_t x) noexcept { return uint64_t(kSpread.of[x & 255]) | uint64_t(kSpread.of[x >> 8 & 255]) << 24; }

} // namespace tom::detail
