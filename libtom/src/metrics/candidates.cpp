// Lower bounds of point-to-candidate distances, eight candidates per AVX instruction.

#include "candidates.h"

#include <cmath>
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
// [kSmallestScale, kLargestScale] float squares could overflow or vanish: then every candidate is kept (bound 0).
constexpr float kKeep = 1.0f - 1.0f / 512.0f;
constexpr double kSmallestScale = 1e-12, kLargestScale = 1e12;

// lane indices of the set bits of each 8-bit mask, in order, for a branch-free compaction
struct Lanes {
    alignas(32) uint32_t of[256][8];
    Lanes() {
        for (unsigned mask = 0; mask < 256; ++mask) {
            unsigned n = 0;
            for (unsigned lane = 0; lane < 8; ++lane)
                if (mask >> lane & 1) of[mask][n++] = lane;
            while (n < 8) of[mask][n++] = 0;
        }
    }
};
const Lanes kLanes;

#if defined(__x86_64__) || defined(__i386__)
__attribute__((target("avx2"))) size_t below_avx(float* column, size_t padded, const float q[3], float limit, float slack, uint32_t* hits) {
    const float *lx = column, *ly = lx + padded, *lz = ly + padded, *hx = lz + padded, *hy = hx + padded, *hz = hy + padded, *nx = hz + padded,
                *ny = nx + padded, *nz = ny + padded, *off = nz + padded;
    float* low = column + 10 * padded;
    const __m256 x = _mm256_set1_ps(q[0]), y = _mm256_set1_ps(q[1]), z = _mm256_set1_ps(q[2]), zero = _mm256_setzero_ps(), below = _mm256_set1_ps(limit),
                 keep = _mm256_set1_ps(kKeep), lower = _mm256_set1_ps(slack);
    size_t count = 0;
    for (size_t k = 0; k < padded; k += 8) {
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
bool cpu_has_avx() {
    static const bool has = __builtin_cpu_supports("avx2") && simd_enabled();
    return has;
}
#endif

} // namespace

void CandidateBounds::fill(const std::vector<Flat>& flat, const std::vector<uint32_t>& list, V3 o, double spread) {
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
    everything = !(scale >= kSmallestScale && scale <= kLargestScale);
    const double e = std::ldexp(scale, -18);
    slack = everything ? 0.0f : float(3.0 * 2049.0 * e * e);
    if (everything) std::fill(column(10), column(10) + padded, 0.0f);
    listed = m;
}

size_t CandidateBounds::below(V3 p, double best) {
    const V3 r = p - origin;
    const float q[3] = {float(r.x), float(r.y), float(r.z)};
    const float limit = float(best);
    if (everything) {
        for (size_t k = 0; k < listed; ++k) hits[k] = uint32_t(k);
        return listed;
    }
#if defined(__x86_64__) || defined(__i386__)
    if (cpu_has_avx()) return below_avx(data.data(), padded, q, limit, slack, hits.data());
#endif
    const float *lx = column(0), *ly = column(1), *lz = column(2), *hx = column(3), *hy = column(4), *hz = column(5), *nx = column(6),
                *ny = column(7), *nz = column(8), *off = column(9);
    float* low = column(10);
    size_t count = 0;
    for (size_t k = 0; k < padded; ++k) {
        const float dx = std::max(std::max(lx[k] - q[0], q[0] - hx[k]), 0.0f), dy = std::max(std::max(ly[k] - q[1], q[1] - hy[k]), 0.0f),
                    dz = std::max(std::max(lz[k] - q[2], q[2] - hz[k]), 0.0f);
        const float above = (nx[k] * q[0] + ny[k] * q[1]) + (nz[k] * q[2] + off[k]);
        low[k] = std::max(dx * dx + dy * dy + dz * dz, above * above) * kKeep - slack;
        if (low[k] < limit) hits[count++] = uint32_t(k);
    }
    return count;
}

} // namespace tom::detail
