// Lower bounds of point-to-candidate distances, eight candidates per AVX2 instruction; the
// distances of a run's points to one triangle, four per AVX instruction.

#include "candidates.h"

#include <cmath>
#include <cstring>
#include <limits>

#include "../simd.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace tom::detail {

namespace {

// The lowering: bound * kKeep - slack. Rounding to float moves a coordinate by 2^-24 of the
// largest one at most (`scale`: of the boxes relative to the origin, and of the points), and an
// operation its result by 2^-24 of it: a distance along an axis errs by under 2^-22 scale, one
// from the plane (three products, the offset, three sums) by under 2^-19.4 scale; e = 2^-18
// scale bounds both. An error e in a distance d moves d^2 by 2 d e + e^2 <= 2^-10 d^2 + (2^10 + 1)
// e^2, so kKeep = 1 - 2^-9 (with the squares' and sums' own rounding) and slack = 3 (axes) 2049
// e^2 cover it twice over; the bound loses a fifth of a percent, which prunes as well. Outside
// [kSmallestScale, kLargestScale] float squares could overflow or vanish: then every candidate
// is kept (bound 0).
constexpr float kKeep = 1.0f - 1.0f / 512.0f;
constexpr double kSmallestScale = 1e-12, kLargestScale = 1e12;

#if defined(__x86_64__) || defined(__i386__)
// lane indices of the set bits of each 8-bit mask, in order, for a branch-free compaction (made
// at compile time)
struct Lanes {
    alignas(32) uint32_t of[256][8];
    constexpr Lanes() : of{} {
        for (unsigned mask = 0; mask < 256; ++mask) {
            unsigned n = 0;
            for (unsigned lane = 0; lane < 8; ++lane)
                if (mask >> lane & 1) of[mask][n++] = lane;
        }
    }
};
constexpr Lanes kLanes;

__attribute__((target("avx2"))) size_t below_avx(float* column, size_t padded, const float* floor, float beyond, const float q[3], float limit, float slack,
                                                      uint32_t* hits) {
    const float *lx = column, *ly = lx + padded, *lz = ly + padded, *hx = lz + padded, *hy = hx + padded, *hz = hy + padded, *nx = hz + padded,
                *ny = nx + padded, *nz = ny + padded, *off = nz + padded;
    float* low = column + 10 * padded;
    const __m256 x = _mm256_set1_ps(q[0]), y = _mm256_set1_ps(q[1]), z = _mm256_set1_ps(q[2]), zero = _mm256_setzero_ps(), below = _mm256_set1_ps(limit),
                 keep = _mm256_set1_ps(kKeep), lower = _mm256_set1_ps(slack);
    size_t count = 0;
    for (size_t k = 0; k < padded && floor[k / 8] < beyond; k += 8) {
        const __m256 dx = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(_mm256_loadu_ps(lx + k), x), _mm256_sub_ps(x, _mm256_loadu_ps(hx + k))), zero);
        const __m256 dy = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(_mm256_loadu_ps(ly + k), y), _mm256_sub_ps(y, _mm256_loadu_ps(hy + k))), zero);
        const __m256 dz = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(_mm256_loadu_ps(lz + k), z), _mm256_sub_ps(z, _mm256_loadu_ps(hz + k))), zero);
        const __m256 above = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(nx + k), x), _mm256_mul_ps(_mm256_loadu_ps(ny + k), y)),
                                           _mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(nz + k), z), _mm256_loadu_ps(off + k)));
        const __m256 box = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
        const __m256 bound = _mm256_sub_ps(_mm256_mul_ps(_mm256_max_ps(box, _mm256_mul_ps(above, above)), keep), lower);
        _mm256_storeu_ps(low + k, bound);
        const unsigned mask = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(bound, below, _CMP_LT_OQ)));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(hits + count),
                            _mm256_add_epi32(_mm256_load_si256(reinterpret_cast<const __m256i*>(kLanes.of[mask])), _mm256_set1_epi32(int(k))));
        count += unsigned(__builtin_popcount(mask));
    }
    return count;
}
// distance2() of four points (x, y, z: their coordinates) to f, operation for operation
__attribute__((target("avx"))) inline __m256d dot_avx(__m256d ax, __m256d ay, __m256d az, __m256d bx, __m256d by, __m256d bz) {
    return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(ax, bx), _mm256_mul_pd(ay, by)), _mm256_mul_pd(az, bz));
}
// segment_d2(w, e, we, ie): w - clamp01(we ie) e, squared; clamp01 as min(1, max(0, t))
__attribute__((target("avx"))) inline __m256d segment_avx(__m256d wx, __m256d wy, __m256d wz, __m256d ex, __m256d ey, __m256d ez, __m256d we, double ie) {
    const __m256d t = _mm256_min_pd(_mm256_max_pd(_mm256_mul_pd(we, _mm256_set1_pd(ie)), _mm256_setzero_pd()), _mm256_set1_pd(1.0));
    const __m256d dx = _mm256_sub_pd(wx, _mm256_mul_pd(t, ex)), dy = _mm256_sub_pd(wy, _mm256_mul_pd(t, ey)), dz = _mm256_sub_pd(wz, _mm256_mul_pd(t, ez));
    return dot_avx(dx, dy, dz, dx, dy, dz);
}
__attribute__((target("avx"))) inline __m256d distance2_avx(const Flat& f, __m256d x, __m256d y, __m256d z) {
    const __m256d e0x = _mm256_set1_pd(f.e0.x), e0y = _mm256_set1_pd(f.e0.y), e0z = _mm256_set1_pd(f.e0.z);
    const __m256d e1x = _mm256_set1_pd(f.e1.x), e1y = _mm256_set1_pd(f.e1.y), e1z = _mm256_set1_pd(f.e1.z);
    const __m256d wx = _mm256_sub_pd(x, _mm256_set1_pd(f.a.x)), wy = _mm256_sub_pd(y, _mm256_set1_pd(f.a.y)), wz = _mm256_sub_pd(z, _mm256_set1_pd(f.a.z));
    const __m256d w0 = dot_avx(e0x, e0y, e0z, wx, wy, wz), w1 = dot_avx(e1x, e1y, e1z, wx, wy, wz);
    const __m256d d00 = _mm256_set1_pd(f.d00), d01 = _mm256_set1_pd(f.d01), d11 = _mm256_set1_pd(f.d11), inverse = _mm256_set1_pd(f.inverse);
    const __m256d u = _mm256_mul_pd(_mm256_sub_pd(_mm256_mul_pd(d11, w0), _mm256_mul_pd(d01, w1)), inverse);
    const __m256d v = _mm256_mul_pd(_mm256_sub_pd(_mm256_mul_pd(d00, w1), _mm256_mul_pd(d01, w0)), inverse);
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
    const __m256d inside = _mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(u, zero, _CMP_GE_OQ), _mm256_cmp_pd(v, zero, _CMP_GE_OQ)),
                                         _mm256_cmp_pd(_mm256_add_pd(u, v), one, _CMP_LE_OQ));
    const __m256d above =
        _mm256_add_pd(dot_avx(_mm256_set1_pd(f.normal.x), _mm256_set1_pd(f.normal.y), _mm256_set1_pd(f.normal.z), x, y, z), _mm256_set1_pd(f.offset));
    const __m256d wbx = _mm256_sub_pd(wx, e0x), wby = _mm256_sub_pd(wy, e0y), wbz = _mm256_sub_pd(wz, e0z);
    const __m256d e2x = _mm256_sub_pd(e1x, e0x), e2y = _mm256_sub_pd(e1y, e0y), e2z = _mm256_sub_pd(e1z, e0z);
    const __m256d s0 = segment_avx(wx, wy, wz, e0x, e0y, e0z, w0, f.i00), s1 = segment_avx(wx, wy, wz, e1x, e1y, e1z, w1, f.i11),
                  s2 = segment_avx(wbx, wby, wbz, e2x, e2y, e2z, dot_avx(e2x, e2y, e2z, wbx, wby, wbz), f.i22);
    return _mm256_blendv_pd(_mm256_min_pd(s0, _mm256_min_pd(s1, s2)), _mm256_mul_pd(above, above), inside);
}
__attribute__((target("avx"))) void distances2_avx(const Flat& f, const V3* p, size_t n, double* d2) {
    size_t i = 0;
    for (; i + 4 <= n; i += 4) {
        const __m256d x = _mm256_set_pd(p[i + 3].x, p[i + 2].x, p[i + 1].x, p[i].x), y = _mm256_set_pd(p[i + 3].y, p[i + 2].y, p[i + 1].y, p[i].y),
                      z = _mm256_set_pd(p[i + 3].z, p[i + 2].z, p[i + 1].z, p[i].z);
        _mm256_storeu_pd(d2 + i, distance2_avx(f, x, y, z));
    }
    for (; i < n; ++i) d2[i] = distance2(f, p[i]);
}
bool cpu_has_avx() {
    static const bool has = __builtin_cpu_supports("avx") && simd_enabled();
    return has;
}
bool cpu_has_avx2() {
    static const bool has = __builtin_cpu_supports("avx2") && simd_enabled();
    return has;
}
#endif

} // namespace

void CandidateBounds::fill(const std::vector<Flat>& flat, const std::vector<uint32_t>& list, V3 o, double spread, const uint64_t* sorted) {
    const size_t m = list.size();
    padded = (m + 7) & ~size_t(7);
    data.resize(11 * padded);
    hits.resize(padded + 8);  // (the compaction stores eight at a time)
    origin = o;
    const float inf = std::numeric_limits<float>::infinity();
    double scale = spread;
    for (size_t k = 0; k < padded; ++k) {
        if (k >= m) {
            column(0)[k] = column(1)[k] = column(2)[k] = inf, column(3)[k] = column(4)[k] = column(5)[k] = -inf;
            column(6)[k] = column(7)[k] = column(8)[k] = column(9)[k] = 0;
            continue;
        }
        const Flat& f = flat[list[k]];
        const V3 lo = f.lo - o, hi = f.hi - o;
        column(0)[k] = float(lo.x), column(1)[k] = float(lo.y), column(2)[k] = float(lo.z);
        column(3)[k] = float(hi.x), column(4)[k] = float(hi.y), column(5)[k] = float(hi.z);
        column(6)[k] = float(f.normal.x), column(7)[k] = float(f.normal.y), column(8)[k] = float(f.normal.z);
        column(9)[k] = float(f.offset + dot(f.normal, o));  // the plane through the triangle, which lies in the box
        scale = std::max({scale, std::fabs(lo.x), std::fabs(lo.y), std::fabs(lo.z), std::fabs(hi.x), std::fabs(hi.y), std::fabs(hi.z)});
    }
    floor.assign(padded / 8, -std::numeric_limits<float>::infinity());  // (unsorted: every block scanned)
    if (sorted)
        for (size_t j = 0; j < floor.size(); ++j) {
            const uint32_t bits = uint32_t(sorted[8 * j] >> 32);
            std::memcpy(&floor[j], &bits, sizeof bits);
        }
    everything = !(scale >= kSmallestScale && scale <= kLargestScale);
    const double e = std::ldexp(scale, -18);
    slack = everything ? 0.0f : float(3.0 * 2049.0 * e * e);
    if (everything) std::fill(column(10), column(10) + padded, 0.0f);
    listed = m;
}

void distances2(const Flat& f, const V3* p, size_t n, double* d2) {
#if defined(__x86_64__) || defined(__i386__)
    if (cpu_has_avx()) return distances2_avx(f, p, n, d2);
#endif
    for (size_t i = 0; i < n; ++i) d2[i] = distance2(f, p[i]);
}

size_t CandidateBounds::below(V3 p, double best) {
    const V3 r = p - origin;
    const float q[3] = {float(r.x), float(r.y), float(r.z)};
    const float limit = float(best);
    // the blocks that may hold a candidate under `best`: the floors are non-decreasing, and a
    // block whose floor is at best or above (the floats' rounding allowed for) holds none
    const float beyond = float(best * (1.0 + 1e-6));
    if (everything) {
        for (size_t k = 0; k < listed; ++k) hits[k] = uint32_t(k);
        return listed;
    }
#if defined(__x86_64__) || defined(__i386__)
    if (cpu_has_avx2()) return below_avx(data.data(), padded, floor.data(), beyond, q, limit, slack, hits.data());
#endif
    const float *lx = column(0), *ly = column(1), *lz = column(2), *hx = column(3), *hy = column(4), *hz = column(5), *nx = column(6),
                *ny = column(7), *nz = column(8), *off = column(9);
    float* low = column(10);
    size_t count = 0;
    for (size_t k = 0; k < padded && floor[k / 8] < beyond; ++k) {
        const float dx = std::max(std::max(lx[k] - q[0], q[0] - hx[k]), 0.0f), dy = std::max(std::max(ly[k] - q[1], q[1] - hy[k]), 0.0f),
                    dz = std::max(std::max(lz[k] - q[2], q[2] - hz[k]), 0.0f);
        const float above = (nx[k] * q[0] + ny[k] * q[1]) + (nz[k] * q[2] + off[k]);
        low[k] = std::max(dx * dx + dy * dy + dz * dz, above * above) * kKeep - slack;
        if (low[k] < limit) hits[count++] = uint32_t(k);
    }
    return count;
}

} // namespace tom::detail
