// Index-buffer extraction at any resolution (Gobbetti & Bouvier, TOM, section 3.2).
//
// The active triangles at resolution n are a prefix of the sorted triangle array; each corner v
// is mapped by `while (v >= n) v = substitute[v]`. At high resolutions almost every corner is
// already < n, so the loop copies blocks and only walks the few corners that need it.

#include "tom/extract.h"
#include "tom/error_curve.h"

#include "coarse.h"
#include "format_layout.h"
#include "platform.h"
#include "simd.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>

#if TOM_X86_SIMD
#include <immintrin.h>
#endif


namespace tom {

namespace {

template <class I>
inline uint32_t walk(const I* substitute, uint32_t v, uint32_t n) noexcept {
    while (v >= n) v = substitute[v];
    return v;
}

// The corners extraction reads: the stored full-resolution ones (TRIS), or, at resolutions up to
// the COAR section's, the coarse corners stored already mapped to that resolution. A corner
// mapped to R walks on from there to any n <= R: its chain passes through the stored value.
struct Corners {
    const void* data;
    uint32_t index_size;  // bytes per corner
    uint32_t triangles;   // how many are stored
    uint32_t resolution;  // the resolution they are mapped to
};

inline Corners corners_for(const MeshView& m, uint32_t n) noexcept {
    if (m.coarse_corners && n <= m.coarse_resolution)
        return {m.coarse_corners, m.coarse_index_size, m.coarse_triangle_count, m.coarse_resolution};
    return {m.triangles, m.index_size, m.triangle_count, m.vertex_count};
}

template <class I, class C>
inline bool alive(const I* substitute, const C* tri, uint32_t n) noexcept {
    const uint32_t a = walk(substitute, tri[0], n), b = walk(substitute, tri[1], n), c = walk(substitute, tri[2], n);
    return a != b && b != c && a != c;
}

// Into [min_vertex_count, vertex_count], and never among the copies of a group (resolution n
// takes vertices [0, n): some copies of a point without the others would open a crack): the
// highest resolution below that keeps every group whole.
inline uint32_t clamp_resolution(const MeshView& m, uint32_t n) noexcept {
    n = std::min(std::max(n, m.min_vertex_count), m.vertex_count);
    return m.whole_groups_below(n);
}

// The active prefix at resolution n <= src.resolution, from the corners of `src`.
template <class I, class C>
uint32_t count_active(const I* sub, const Corners& src, uint32_t n) noexcept {
    const C* tri = static_cast<const C*>(src.data);
    // alive(t, n) is true on a prefix of the triangles. Its end is close to n * T / R (about two
    // triangles per vertex), so gallop from that guess, then binary search the bracket.
    const uint32_t T = src.triangles;
    if (T == 0) return 0;
    if (n >= src.resolution) {
        // the stored corners are the active ones of their resolution (all of TRIS at full
        // resolution; COAR holds exactly the active ones)
        return T;
    }
    auto is_alive = [&](uint32_t t) { return alive(sub, tri + 3 * size_t(t), n); };
    uint32_t guess = uint32_t(uint64_t(n) * T / src.resolution);
    guess = std::min(std::max(guess, 1u), T);
    uint32_t lo, hi;  // invariant: every t < lo is alive, every t >= hi is not
    if (is_alive(guess - 1)) {
        lo = guess;
        uint32_t stride = 1;
        for (;;) {
            if (lo >= T) return T;
            const uint32_t probe = uint32_t(std::min<uint64_t>(uint64_t(lo) + stride, T)) - 1;
            if (!is_alive(probe)) {
                hi = probe;
                break;
            }
            lo = probe + 1;
            stride *= 2;
        }
    } else {
        hi = guess - 1;
        uint32_t stride = 1;
        for (;;) {
            if (hi == 0) return 0;
            const uint32_t probe = hi > stride ? hi - stride : 0;
            if (is_alive(probe)) {
                lo = probe + 1;
                break;
            }
            hi = probe;
            stride *= 2;
        }
    }
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (is_alive(mid))
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

template <class I, class C, class O>
void map_corners_scalar(const I* sub, const C* in, O* out, size_t count, uint32_t n) noexcept {
    for (size_t i = 0; i < count; ++i) out[i] = O(walk(sub, uint32_t(in[i]), n));
}

#if TOM_X86_SIMD
#define TOM_HAVE_AVX2_PATH 1
// AVX2: 8 corners at a time; each round gathers substitute[v] for the lanes still >= n, until
// no lane is. One unpredictable branch per 8 corners instead of one per corner, and the
// gathers of independent lanes overlap their cache misses.
template <class I>
TOM_TARGET_AVX2 inline __m256i load8(const I* in) noexcept {
    if (sizeof(I) == 4) return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(in));
    return _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(in)));
}

template <class O>
TOM_TARGET_AVX2 inline void store8(O* out, __m256i v) noexcept {
    if (sizeof(O) == 4) {
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), v);
    } else {
        const __m128i lo = _mm256_castsi256_si128(v), hi = _mm256_extracti128_si256(v, 1);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_packus_epi32(lo, hi));
    }
}

template <class I>
TOM_TARGET_AVX2 inline __m256i gather_substitutes(const I* sub, __m256i v, __m256i mask) noexcept {
    if (sizeof(I) == 4) return _mm256_mask_i32gather_epi32(v, reinterpret_cast<const int*>(sub), v, mask, 4);
    // 16-bit: read the 32-bit word ending at substitute[v] (its high half) so nothing past the
    // array is touched; masked lanes have v >= n >= 1, so 2v - 2 >= 0
    const __m256i offsets = _mm256_sub_epi32(_mm256_add_epi32(v, v), _mm256_set1_epi32(2));
    const __m256i words = _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(sub), offsets, mask, 1);
    return _mm256_blendv_epi8(v, _mm256_srli_epi32(words, 16), mask);
}

// Stragglers: when at most this many of a round's 32 lanes still walk, they finish one by one
// (scalar) instead of the whole round gathering again for them: chains are short and their
// lengths skewed, so most rounds would otherwise gather again for one or two lanes. Only while
// the substitute array is cache-resident: a scalar walk then hits the cache, while out of it
// each step waits for its miss where a gather overlaps eight.
constexpr int kStragglers = 12;
constexpr size_t kCacheResidentBytes = 256 * 1024;

template <class I, class C, class O>
TOM_TARGET_AVX2 void map_corners_avx2(const I* sub, size_t vertices, const C* in, O* out, size_t count, uint32_t n) noexcept {
    const __m256i limit = _mm256_set1_epi32(int(n));
    const int alone = vertices * sizeof(I) <= kCacheResidentBytes ? kStragglers : -1;  // -1: never
    size_t i = 0;
    // 32 corners per round trip: four independent gathers in flight, one exit branch
    for (; i + 32 <= count; i += 32) {
        __m256i v0 = load8(in + i), v1 = load8(in + i + 8), v2 = load8(in + i + 16), v3 = load8(in + i + 24);
        for (;;) {
            const __m256i g0 = _mm256_cmpeq_epi32(_mm256_max_epu32(v0, limit), v0);  // v >= n, unsigned
            const __m256i g1 = _mm256_cmpeq_epi32(_mm256_max_epu32(v1, limit), v1);
            const __m256i g2 = _mm256_cmpeq_epi32(_mm256_max_epu32(v2, limit), v2);
            const __m256i g3 = _mm256_cmpeq_epi32(_mm256_max_epu32(v3, limit), v3);
            const __m256i any = _mm256_or_si256(_mm256_or_si256(g0, g1), _mm256_or_si256(g2, g3));
            if (_mm256_testz_si256(any, any)) break;
            const uint32_t left = uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(g0))) | uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(g1))) << 8 |
                                  uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(g2))) << 16 | uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(g3))) << 24;
            if (detail::popcount32(left) <= alone) {
                alignas(32) uint32_t lanes[32];
                _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), v0);
                _mm256_store_si256(reinterpret_cast<__m256i*>(lanes + 8), v1);
                _mm256_store_si256(reinterpret_cast<__m256i*>(lanes + 16), v2);
                _mm256_store_si256(reinterpret_cast<__m256i*>(lanes + 24), v3);
                for (uint32_t m = left; m; m &= m - 1) {
                    const int k = detail::trailing_zeros32(m);
                    lanes[k] = walk(sub, lanes[k], n);
                }
                v0 = _mm256_load_si256(reinterpret_cast<const __m256i*>(lanes));
                v1 = _mm256_load_si256(reinterpret_cast<const __m256i*>(lanes + 8));
                v2 = _mm256_load_si256(reinterpret_cast<const __m256i*>(lanes + 16));
                v3 = _mm256_load_si256(reinterpret_cast<const __m256i*>(lanes + 24));
                break;
            }
            v0 = gather_substitutes(sub, v0, g0);
            v1 = gather_substitutes(sub, v1, g1);
            v2 = gather_substitutes(sub, v2, g2);
            v3 = gather_substitutes(sub, v3, g3);
        }
        store8(out + i, v0);
        store8(out + i + 8, v1);
        store8(out + i + 16, v2);
        store8(out + i + 24, v3);
    }
    for (; i + 8 <= count; i += 8) {
        __m256i v = load8(in + i);
        for (;;) {
            const __m256i ge = _mm256_cmpeq_epi32(_mm256_max_epu32(v, limit), v);
            if (_mm256_testz_si256(ge, ge)) break;
            v = gather_substitutes(sub, v, ge);
        }
        store8(out + i, v);
    }
    map_corners_scalar(sub, in + i, out + i, count - i, n);
}

// Full resolution from 16-bit corners into a 32-bit buffer: 16 corners widened per step (the
// plain loop widens 8 with SSE2)
TOM_TARGET_AVX2 void widen_avx2(const uint16_t* in, uint32_t* out, size_t count) noexcept {
    size_t i = 0;
    for (; i + 16 <= count; i += 16) {
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + i), load8(in + i));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + i + 8), load8(in + i + 8));
    }
    for (; i < count; ++i) out[i] = in[i];
}

bool cpu_has_avx2() noexcept {
    static const bool has = detail::cpu_has_avx2() && detail::simd_enabled();
    return has;
}
#endif

// AVX2 gathers at every resolution where the CPU has them. The scalar walk's branches are fast
// only when the same level is extracted over and over (the predictor learns its chains, as in a
// benchmark loop); in a renderer, where levels change and other work runs between extractions,
// the gathers are the faster (docs/PERFORMANCE.md).
template <class I, class C, class O>
void map_corners(const I* sub, size_t vertices, const C* in, O* dst, size_t corners, uint32_t n) noexcept {
    (void)vertices;  // only the AVX2 path uses it
#ifdef TOM_HAVE_AVX2_PATH
    if (cpu_has_avx2()) {
        map_corners_avx2(sub, vertices, in, dst, corners, n);
        return;
    }
#endif
    map_corners_scalar(sub, in, dst, corners, n);
}

template <class I>
uint32_t active_count(const MeshView& m, uint32_t n) noexcept {
    const Corners src = corners_for(m, n);
    const I* sub = static_cast<const I*>(m.substitute);
    return src.index_size == 2 ? count_active<I, uint16_t>(sub, src, n) : count_active<I, uint32_t>(sub, src, n);
}

template <class I, class O>
Extracted extract_impl(const MeshView& m, uint32_t vertex_count, O* dst, size_t capacity) noexcept {
    Extracted r;
    r.vertex_count = clamp_resolution(m, vertex_count);
    const uint32_t n = r.vertex_count;
    // the count costs O(log T) short walks: far less than checking every triangle for the end
    r.triangle_count = uint32_t(std::min<size_t>(active_count<I>(m, n), capacity / 3));
    const size_t corners = size_t(r.triangle_count) * 3;
    if (n == m.vertex_count) {  // full resolution: every chain is empty
        const I* in = static_cast<const I*>(m.triangles);
        if (sizeof(I) == sizeof(O)) {
            if (corners) std::memcpy(dst, in, corners * sizeof(O));  // an empty mesh may have no buffers at all
            return r;
        }
#ifdef TOM_HAVE_AVX2_PATH
        if (sizeof(I) == 2 && sizeof(O) == 4 && cpu_has_avx2()) {
            widen_avx2(reinterpret_cast<const uint16_t*>(in), reinterpret_cast<uint32_t*>(dst), corners);
            return r;
        }
#endif
        for (size_t i = 0; i < corners; ++i) dst[i] = O(in[i]);
        return r;
    }
    const I* sub = static_cast<const I*>(m.substitute);
    const Corners src = corners_for(m, n);
    if (src.index_size == 2)
        map_corners(sub, m.vertex_count, static_cast<const uint16_t*>(src.data), dst, corners, n);
    else
        map_corners(sub, m.vertex_count, static_cast<const uint32_t*>(src.data), dst, corners, n);
    return r;
}

uint32_t active_count_at(const MeshView& m, uint32_t n) noexcept {
    return m.index_size == 2 ? active_count<uint16_t>(m, n) : active_count<uint32_t>(m, n);
}

// Part p as a mesh of its own: the same vertices, the part's range of triangles, no coarse
// corners (COAR is only for meshes without parts). The single-part code runs on it unchanged.
MeshView part_mesh(const MeshView& m, uint32_t p) noexcept {
    if (!m.parts) return m;
    const Part& part = m.parts[p];
    MeshView v = m;
    v.triangles = static_cast<const uint8_t*>(m.triangles) + size_t(part.first_triangle) * 3 * m.index_size;
    v.triangle_count = part.triangle_count;
    v.material = part.material;
    v.coarse_corners = nullptr;
    v.parts = nullptr;
    v.part_count = 0;
    return v;
}

template <class O>
Extracted extract_any(const MeshView& m, uint32_t vertex_count, O* dst, size_t capacity) noexcept {
    if (sizeof(O) == 2 && m.index_size == 4) vertex_count = std::min<uint32_t>(vertex_count, 65536u);  // the contract
    return m.index_size == 2 ? extract_impl<uint16_t>(m, vertex_count, dst, capacity) : extract_impl<uint32_t>(m, vertex_count, dst, capacity);
}

// Each part's live triangles after the previous part's, until the buffer is full.
template <class O>
Extracted extract_all_parts(const MeshView& m, uint32_t vertex_count, O* dst, size_t capacity, PartDraw* draws) noexcept {
    Extracted total;
    total.vertex_count = clamp_resolution(m, vertex_count);
    const uint32_t parts = part_count(m);
    size_t written = 0;
    for (uint32_t p = 0; p < parts; ++p) {
        const MeshView part = part_mesh(m, p);
        const Extracted e = extract_any(part, vertex_count, dst + written, capacity - written);
        total.vertex_count = e.vertex_count;
        total.triangle_count += e.triangle_count;
        if (draws) draws[p] = {uint32_t(written), e.triangle_count * 3, part.material};
        written += size_t(e.triangle_count) * 3;
    }
    return total;
}

} // namespace

Part part_at(const MeshView& m, uint32_t p) noexcept {
    assert(p < part_count(m) && "part_at: \\pre p < part_count(mesh)");
    if (m.parts) return m.parts[p];
    Part whole;
    whole.triangle_count = m.triangle_count;
    whole.material = m.material;
    for (const layout::AttributeStream& stream : layout::attribute_streams)
        if (m.*stream.view) whole.attributes |= stream.flag;
    return whole;
}

uint32_t active_part_triangle_count(const MeshView& m, uint32_t p, uint32_t vertex_count) noexcept {
    return active_count_at(part_mesh(m, p), clamp_resolution(m, vertex_count));
}

uint32_t active_triangle_count(const MeshView& m, uint32_t vertex_count) noexcept {
    const uint32_t n = clamp_resolution(m, vertex_count);
    uint32_t total = 0;
    for (uint32_t p = 0; p < part_count(m); ++p) total += active_count_at(part_mesh(m, p), n);
    return total;
}

uint32_t floor_vertex_count(const MeshView& m, Floor floor) noexcept {
    if (floor == Floor::coarsest) return m.min_vertex_count;
    const std::optional<UsableFloor> f = read_usable_floor(m);
    return f ? m.whole_groups_above(f->vertices) : m.min_vertex_count;
}

uint32_t vertex_count_for_triangles(const MeshView& m, uint32_t triangle_count, Floor floor) noexcept {
    if (triangle_count >= m.triangle_count) return m.vertex_count;
    uint32_t lo = floor_vertex_count(m, floor), hi = m.vertex_count;  // smallest n with active(n) >= triangle_count
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (active_triangle_count(m, mid) >= triangle_count)
            hi = mid;
        else
            lo = mid + 1;
    }
    return m.whole_groups_above(lo);  // a resolution that keeps every group of copies whole
}

uint32_t vertex_count_within_triangles(const MeshView& m, uint32_t triangle_count, Floor floor) noexcept {
    const uint32_t lowest = floor_vertex_count(m, floor);
    uint32_t n = vertex_count_for_triangles(m, triangle_count, floor);
    while (n > lowest && active_triangle_count(m, n) > triangle_count) --n;
    return n;
}

uint32_t vertex_count_for_fraction(const MeshView& m, double fraction, Floor floor) noexcept {
    if (!(fraction > 0.0)) return floor_vertex_count(m, floor);
    if (fraction >= 1.0) return m.vertex_count;
    const double t = fraction * double(m.triangle_count) + 0.5;
    return vertex_count_for_triangles(m, uint32_t(t), floor);
}

Extracted extract(const MeshView& m, uint32_t vertex_count, uint32_t* dst, size_t capacity) noexcept {
    return m.parts ? extract_all_parts(m, vertex_count, dst, capacity, nullptr) : extract_any(m, vertex_count, dst, capacity);
}

Extracted extract(const MeshView& m, uint32_t vertex_count, uint16_t* dst, size_t capacity) noexcept {
    assert(std::min(vertex_count, m.vertex_count) <= 65536 && "extract: the uint16_t form needs a resolution of at most 65536 vertices");
    return m.parts ? extract_all_parts(m, vertex_count, dst, capacity, nullptr) : extract_any(m, vertex_count, dst, capacity);
}

Extracted extract_parts(const MeshView& m, uint32_t vertex_count, uint32_t* dst, size_t capacity, PartDraw* draws) noexcept {
    return extract_all_parts(m, vertex_count, dst, capacity, draws);
}

Extracted extract_parts(const MeshView& m, uint32_t vertex_count, uint16_t* dst, size_t capacity, PartDraw* draws) noexcept {
    return extract_all_parts(m, vertex_count, dst, capacity, draws);
}

MorphedVertex geomorph(const MeshView& m, uint32_t n, float a) noexcept {
    MorphedVertex r;
    r.index = n;
    if (n >= m.vertex_count) return r;
    a = std::min(1.0f, std::max(0.0f, a));
    const uint32_t s = m.substitute_at(n);  // < n: alive at resolution n, where vertex n sits on it
    auto lerp = [&](const float* stream, int width, float* out) {
        if (!stream) return;
        // (1 - a) x + a y: exactly the substitute at a = 0 and the vertex itself at a = 1
        for (int k = 0; k < width; ++k) out[k] = (1.0f - a) * stream[size_t(s) * width + k] + a * stream[size_t(n) * width + k];
    };
    lerp(m.positions, 3, r.position);
    lerp(m.normals, 3, r.normal);
    lerp(m.texcoords, 2, r.texcoord);
    lerp(m.colors, 4, r.color);
    lerp(m.texcoords1, 2, r.texcoord1);
    lerp(m.tangents, 4, r.tangent);
    for (float* q : {r.normal, r.tangent}) {
        const float len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        if (len > 0) q[0] /= len, q[1] /= len, q[2] /= len;
    }
    if (m.tangents) r.tangent[3] = r.tangent[3] < 0.0f ? -1.0f : 1.0f;
    return r;
}

ChainStats chain_stats(const MeshView& m, uint32_t vertex_count) noexcept {
    ChainStats s;
    const uint32_t n = clamp_resolution(m, vertex_count);
    for (uint32_t p = 0; p < part_count(m); ++p) {
        const MeshView part = part_mesh(m, p);
        const uint32_t tris = active_count_at(part, n);
        for (uint32_t c = 0; c < tris * 3; ++c) {
            uint32_t v = part.corner(c), steps = 0;
            while (v >= n) v = part.substitute_at(v), ++steps;
            s.steps += steps;
            s.max_steps = std::max(s.max_steps, steps);
            ++s.histogram[std::min<uint32_t>(steps, ChainStats::histogram_bins - 1)];
        }
        s.corners += uint64_t(tris) * 3;
    }
    return s;
}

namespace detail {

uint32_t coarse_resolution(const MeshView& m) noexcept {
    if (m.vertex_count < 4096) return 0;
    const uint32_t r = std::min<uint32_t>(m.vertex_count / 64, 65536);
    return r > m.min_vertex_count ? r : 0;
}

uint32_t map_corner(const MeshView& m, uint32_t c, uint32_t n) noexcept {
    uint32_t v = m.corner(c);
    while (v >= n) v = m.substitute_at(v);
    return v;
}

bool triangle_active(const MeshView& m, uint32_t t, uint32_t n) noexcept {
    const uint32_t a = map_corner(m, 3 * t, n), b = map_corner(m, 3 * t + 1, n), c = map_corner(m, 3 * t + 2, n);
    return a != b && b != c && a != c;
}

uint32_t active_prefix(const MeshView& m, uint32_t n) noexcept {
    MeshView plain = m;  // from TRIS only
    plain.coarse_corners = nullptr;
    return active_count_at(plain, n);
}

} // namespace detail

} // namespace tom
