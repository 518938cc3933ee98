// Lower bounds of point-to-candidate distances, four candidates per AVX instruction.

#include "candidates.h"

#include "../simd.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace tom::detail {

namespace {

#if defined(__x86_64__) || defined(__i386__)
__attribute__((target("avx"))) size_t below_avx(double* column, size_t padded, V3 p, double best, uint32_t* hits) {
    const double *lx = column, *ly = lx + padded, *lz = ly + padded, *hx = lz + padded, *hy = hx + padded, *hz = hy + padded, *nx = hz + padded,
                 *ny = nx + padded, *nz = ny + padded, *off = nz + padded;
    double* low = column + 10 * padded;
    const __m256d x = _mm256_set1_pd(p.x), y = _mm256_set1_pd(p.y), z = _mm256_set1_pd(p.z), zero = _mm256_setzero_pd(), limit = _mm256_set1_pd(best);
    size_t count = 0;
    for (size_t k = 0; k < padded; k += 4) {
        const __m256d dx = _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(_mm256_loadu_pd(lx + k), x), _mm256_sub_pd(x, _mm256_loadu_pd(hx + k))), zero);
        const __m256d dy = _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(_mm256_loadu_pd(ly + k), y), _mm256_sub_pd(y, _mm256_loadu_pd(hy + k))), zero);
        const __m256d dz = _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(_mm256_loadu_pd(lz + k), z), _mm256_sub_pd(z, _mm256_loadu_pd(hz + k))), zero);
        const __m256d above = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(nx + k), x), _mm256_mul_pd(_mm256_loadu_pd(ny + k), y)),
                                            _mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(nz + k), z), _mm256_loadu_pd(off + k)));
        const __m256d box = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
        const __m256d bound = _mm256_max_pd(box, _mm256_mul_pd(above, above));
        _mm256_storeu_pd(low + k, bound);
        for (int mask = _mm256_movemask_pd(_mm256_cmp_pd(bound, limit, _CMP_LT_OQ)); mask; mask &= mask - 1) hits[count++] = uint32_t(k) + uint32_t(__builtin_ctz(unsigned(mask)));
    }
    return count;
}
bool cpu_has_avx() {
    static const bool has = __builtin_cpu_supports("avx") && simd_enabled();
    return has;
}
#endif

} // namespace

size_t CandidateBounds::below(V3 p, double best) {
#if defined(__x86_64__) || defined(__i386__)
    if (cpu_has_avx()) return below_avx(data.data(), padded, p, best, hits.data());
#endif
    const double *lx = column(0), *ly = column(1), *lz = column(2), *hx = column(3), *hy = column(4), *hz = column(5), *nx = column(6),
                 *ny = column(7), *nz = column(8), *off = column(9);
    double* low = column(10);
    size_t count = 0;
    for (size_t k = 0; k < padded; ++k) {
        const double above = (nx[k] * p.x + ny[k] * p.y) + (nz[k] * p.z + off[k]);  // summed as the AVX path sums it
        low[k] = std::max(point_box_d2(p, {lx[k], ly[k], lz[k]}, {hx[k], hy[k], hz[k]}), above * above);
        if (low[k] < best) hits[count++] = uint32_t(k);
    }
    return count;
}

} // namespace tom::detail
