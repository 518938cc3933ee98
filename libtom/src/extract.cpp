// Index-buffer extraction at any resolution (Gobbetti & Bouvier, TOM, section 3.2).
//
// The active triangles at resolution n are a prefix of the sorted triangle array; each corner v
// is mapped by `while (v >= n) v = substitute[v]`. At high resolutions almost every corner is
// already < n, so the loop copies blocks and only walks the few corners that need it.

#include "tom/extract.h"

#include <algorithm>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace tom {

namespace {

template <class I>
inline uint32_t walk(const I* substitute, uint32_t v, uint32_t n) noexcept {
    while (v >= n) v = substitute[v];
    return v;
}

template <class I>
inline bool alive(const I* substitute, const I* tri, uint32_t n) noexcept {
    const uint32_t a = walk(substitute, tri[0], n), b = walk(substitute, tri[1], n), c = walk(substitute, tri[2], n);
    return a != b && b != c && a != c;
}

inline uint32_t clamp_resolution(const MeshView& m, uint32_t n) noexcept {
    return std::min(std::max(n, m.min_vertex_count), m.vertex_count);
}

template <class I>
uint32_t count_active(const MeshView& m, uint32_t n) noexcept {
    if (n >= m.vertex_count) return m.triangle_count;
    const I* sub = static_cast<const I*>(m.substitute);
    const I* tri = static_cast<const I*>(m.triangles);
    // alive(t, n) is true on a prefix of the triangles: binary search its end
    uint32_t lo = 0, hi = m.triangle_count;
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (alive(sub, tri + 3 * size_t(mid), n))
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

// out[i] = walk(in[i]) for i < count
template <class I, class O>
void map_corners(const I* sub, const I* in, O* out, size_t count, uint32_t n) noexcept {
    size_t i = 0;
#if defined(__SSE2__)
    if (sizeof(I) == 4 && sizeof(O) == 4) {
        // compare 4 indices at a time against n (signed compare on biased values)
        const __m128i bias = _mm_set1_epi32(int(0x80000000u));
        const __m128i limit = _mm_set1_epi32(int(n ^ 0x80000000u));
        for (; i + 4 <= count; i += 4) {
            const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i));
            _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), v);
            const __m128i ge = _mm_cmpgt_epi32(_mm_xor_si128(v, bias), _mm_sub_epi32(limit, _mm_set1_epi32(1)));
            if (_mm_movemask_epi8(ge)) {
                for (size_t k = i; k < i + 4; ++k) out[k] = O(walk(sub, uint32_t(in[k]), n));
            }
        }
    } else if (sizeof(I) == 2 && sizeof(O) == 2) {
        // 16-bit: unsigned compare by bias as well, 8 at a time
        const __m128i bias = _mm_set1_epi16(int16_t(0x8000));
        const __m128i limit = _mm_set1_epi16(int16_t(uint16_t(std::min<uint32_t>(n, 65535u) - 1) ^ 0x8000));
        const bool all_fit = n > 65535u;  // every 16-bit index is < n
        for (; i + 8 <= count; i += 8) {
            const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i));
            _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), v);
            if (all_fit) continue;
            const __m128i ge = _mm_cmpgt_epi16(_mm_xor_si128(v, bias), limit);
            if (_mm_movemask_epi8(ge)) {
                for (size_t k = i; k < i + 8; ++k) out[k] = O(walk(sub, uint32_t(in[k]), n));
            }
        }
    }
#endif
    for (; i < count; ++i) out[i] = O(walk(sub, uint32_t(in[i]), n));
}

template <class I, class O>
Extracted extract_impl(const MeshView& m, uint32_t vertex_count, O* dst, size_t capacity) noexcept {
    Extracted r;
    r.vertex_count = clamp_resolution(m, vertex_count);
    uint32_t tris = count_active<I>(m, r.vertex_count);
    tris = uint32_t(std::min<size_t>(tris, capacity / 3));
    r.triangle_count = tris;
    const I* sub = static_cast<const I*>(m.substitute);
    const I* in = static_cast<const I*>(m.triangles);
    const size_t count = size_t(tris) * 3;
    if (r.vertex_count == m.vertex_count && sizeof(I) == sizeof(O)) {
        std::memcpy(dst, in, count * sizeof(O));  // full resolution: every chain is empty
        return r;
    }
    map_corners(sub, in, dst, count, r.vertex_count);
    return r;
}

} // namespace

uint32_t active_triangle_count(const MeshView& m, uint32_t vertex_count) noexcept {
    const uint32_t n = clamp_resolution(m, vertex_count);
    return m.index_size == 2 ? count_active<uint16_t>(m, n) : count_active<uint32_t>(m, n);
}

uint32_t vertex_count_for_triangles(const MeshView& m, uint32_t triangle_count) noexcept {
    if (triangle_count >= m.triangle_count) return m.vertex_count;
    uint32_t lo = m.min_vertex_count, hi = m.vertex_count;  // smallest n with active(n) >= triangle_count
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (active_triangle_count(m, mid) >= triangle_count)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

uint32_t vertex_count_for_fraction(const MeshView& m, double fraction) noexcept {
    if (!(fraction > 0.0)) return m.min_vertex_count;
    if (fraction >= 1.0) return m.vertex_count;
    const double t = fraction * double(m.triangle_count) + 0.5;
    return vertex_count_for_triangles(m, uint32_t(t));
}

Extracted extract(const MeshView& m, uint32_t vertex_count, uint32_t* dst, size_t capacity) noexcept {
    return m.index_size == 2 ? extract_impl<uint16_t>(m, vertex_count, dst, capacity)
                             : extract_impl<uint32_t>(m, vertex_count, dst, capacity);
}

Extracted extract(const MeshView& m, uint32_t vertex_count, uint16_t* dst, size_t capacity) noexcept {
    if (m.index_size == 2) return extract_impl<uint16_t>(m, vertex_count, dst, capacity);
    // 32-bit storage into a 16-bit buffer: only valid for resolutions <= 65536 (contract)
    return extract_impl<uint32_t>(m, std::min<uint32_t>(vertex_count, 65536u), dst, capacity);
}

ChainStats chain_stats(const MeshView& m, uint32_t vertex_count) noexcept {
    ChainStats s;
    const uint32_t n = clamp_resolution(m, vertex_count);
    const uint32_t tris = active_triangle_count(m, n);
    for (uint32_t c = 0; c < tris * 3; ++c) {
        uint32_t v = m.corner(c), steps = 0;
        while (v >= n) v = m.substitute_at(v), ++steps;
        s.steps += steps;
        s.max_steps = std::max(s.max_steps, steps);
        ++s.histogram[std::min<uint32_t>(steps, ChainStats::histogram_bins - 1)];
    }
    s.corners = uint64_t(tris) * 3;
    return s;
}

} // namespace tom
