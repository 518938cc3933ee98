// Lower bounds of point-to-candidate distances, eight points per AVX2 instruction; the
// distances of a run's points to one triangle, four per AVX instruction.

#include "candidates.h"

#include <cmath>
#include <limits>

#include "simd.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace tom::detail {

namespace {

// The lowering: bound * kKeep - slack. Rounding to float moves a coordinate by 2^-24 of the
// largest one at most (`scale`: of the boxes relative to the origin, and of the points), and an
// operation its result by 2^-24 of it: a distance along an axis errs by under 2^-22 scale, one
// from the plane or an edge line (three products, the offset, three sums) by under 2^-19.4
// scale; e = 2^-18 scale bounds both. An error e in a distance d moves d^2 by 2 d e + e^2 <=
// 2^-10 d^2 + (2^10 + 1) e^2, so for the box's sum of three squares and the prism's of two,
// kKeep = 1 - 2^-9 (with the squares' and sums' own rounding) and slack = 3 2049 e^2 cover it
// twice over; the bound loses a fifth of a percent, which prunes as well. Outside
// [kSmallestScale, kLargestScale] float squares could overflow or vanish: then every point is
// kept (bound -inf).
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

// (a x + b y) + (c z + d): a signed distance to a plane or a line
__attribute__((target("avx2"))) inline __m256 plane(__m256 a, __m256 b, __m256 c, __m256 d, __m256 x, __m256 y, __m256 z) {
    return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a, x), _mm256_mul_ps(b, y)), _mm256_add_ps(_mm256_mul_ps(c, z), d));
}

// bound() of one candidate (its fields c) at eight points at a time, the same operations in the
// same order; the lanes under their limit compacted into hits. Eight points whose box-and-plane
// bound keeps none skip the edge lines (the full bound is at least that one: same hits).
__attribute__((target("avx2"))) size_t points_below_avx(const float c[kBoundFields], const float* px, const float* py, const float* pz,
                                                          const float* limits, size_t n, float slack, uint32_t* hits) {
    const __m256 lx = _mm256_set1_ps(c[0]), ly = _mm256_set1_ps(c[1]), lz = _mm256_set1_ps(c[2]), hx = _mm256_set1_ps(c[3]), hy = _mm256_set1_ps(c[4]),
                 hz = _mm256_set1_ps(c[5]), nx = _mm256_set1_ps(c[6]), ny = _mm256_set1_ps(c[7]), nz = _mm256_set1_ps(c[8]), off = _mm256_set1_ps(c[9]);
    __m256 m[3][4];
    for (int e = 0; e < 3; ++e)
        for (int k = 0; k < 4; ++k) m[e][k] = _mm256_set1_ps(c[10 + 4 * e + k]);
    const __m256 zero = _mm256_setzero_ps(), keep = _mm256_set1_ps(kKeep), lower = _mm256_set1_ps(slack);
    size_t count = 0;
    for (size_t i = 0; i < n; i += 8) {
        const __m256 x = _mm256_loadu_ps(px + i), y = _mm256_loadu_ps(py + i), z = _mm256_loadu_ps(pz + i);
        const __m256 dx = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(lx, x), _mm256_sub_ps(x, hx)), zero);
        const __m256 dy = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(ly, y), _mm256_sub_ps(y, hy)), zero);
        const __m256 dz = _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(lz, z), _mm256_sub_ps(z, hz)), zero);
        const __m256 above = plane(nx, ny, nz, off, x, y, z);
        const __m256 box = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
        const __m256 limit = _mm256_loadu_ps(limits + i);
        const __m256 coarse = _mm256_sub_ps(_mm256_mul_ps(_mm256_max_ps(box, _mm256_mul_ps(above, above)), keep), lower);
        if (!_mm256_movemask_ps(_mm256_cmp_ps(coarse, limit, _CMP_LT_OQ))) continue;
        const __m256 beyond = _mm256_max_ps(_mm256_max_ps(plane(m[0][0], m[0][1], m[0][2], m[0][3], x, y, z), plane(m[1][0], m[1][1], m[1][2], m[1][3], x, y, z)),
                                            _mm256_max_ps(plane(m[2][0], m[2][1], m[2][2], m[2][3], x, y, z), zero));
        const __m256 prism = _mm256_add_ps(_mm256_mul_ps(above, above), _mm256_mul_ps(beyond, beyond));
        const __m256 bound = _mm256_sub_ps(_mm256_mul_ps(_mm256_max_ps(box, prism), keep), lower);
        const unsigned mask = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(bound, limit, _CMP_LT_OQ)));
        if (!mask) continue;
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(hits + count),
                            _mm256_add_epi32(_mm256_load_si256(reinterpret_cast<const __m256i*>(kLanes.of[mask])), _mm256_set1_epi32(int(i))));
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
// d2[i] = distance2(f, point(i)) for i < n, four at a time
template <class Point>
__attribute__((target("avx"))) void distances2_avx(const Flat& f, size_t n, double* d2, Point&& point) {
    size_t i = 0;
    for (; i + 4 <= n; i += 4) {
        const V3 &p0 = point(i), &p1 = point(i + 1), &p2 = point(i + 2), &p3 = point(i + 3);
        const __m256d x = _mm256_set_pd(p3.x, p2.x, p1.x, p0.x), y = _mm256_set_pd(p3.y, p2.y, p1.y, p0.y), z = _mm256_set_pd(p3.z, p2.z, p1.z, p0.z);
        _mm256_storeu_pd(d2 + i, distance2_avx(f, x, y, z));
    }
    for (; i < n; ++i) d2[i] = distance2(f, point(i));
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

EdgeLines edge_lines(const Flat& f) {
    EdgeLines lines{};
    // only where the plane's normal is reliable: a sliver's cross product loses its direction to
    // cancellation (then no edge term: the normals stay zero)
    if (!(dot(f.normal, f.normal) > 0) || !(gram(f) >= 1e-8 * f.d00 * f.d11)) return lines;
    const V3 corner[3] = {f.a, f.a + f.e0, f.a + f.e1};
    for (int k = 0; k < 3; ++k) {
        const V3 from = corner[k], to = corner[(k + 1) % 3], opposite = corner[(k + 2) % 3];
        V3 out = cross(to - from, f.normal);
        const double len = length(out);
        if (!(len > 0)) continue;
        out = (1.0 / len) * out;
        if (dot(out, opposite - from) > 0) out = -1.0 * out;
        lines.normals[k][0] = float(out.x), lines.normals[k][1] = float(out.y), lines.normals[k][2] = float(out.z);
        lines.offset[k] = -dot(lines.normal(k), from);
    }
    return lines;
}

CandidateBound candidate_bound(const Flat& f, const EdgeLines& lines, V3 o, double spread) {
    CandidateBound b;
    V3 box_lo, box_hi;
    flat_box(f, box_lo, box_hi);
    const V3 lo = box_lo - o, hi = box_hi - o;
    float* c = b.c;
    c[0] = float(lo.x), c[1] = float(lo.y), c[2] = float(lo.z);
    c[3] = float(hi.x), c[4] = float(hi.y), c[5] = float(hi.z);
    c[6] = float(f.normal.x), c[7] = float(f.normal.y), c[8] = float(f.normal.z);
    c[9] = float(f.offset + dot(f.normal, o));  // the plane through the triangle, which lies in the box
    for (int k = 0; k < 3; ++k) {
        float* m = c + 10 + 4 * k;
        const V3 out = lines.normal(k);
        m[0] = float(out.x), m[1] = float(out.y), m[2] = float(out.z), m[3] = float(lines.offset[k] + dot(out, o));
    }
    const double scale = std::max({spread, std::fabs(lo.x), std::fabs(lo.y), std::fabs(lo.z), std::fabs(hi.x), std::fabs(hi.y), std::fabs(hi.z)});
    b.everything = !(scale >= kSmallestScale && scale <= kLargestScale);
    const double e = scale * 0x1p-18;  // (exact: a power of two)
    b.slack = b.everything ? 0.0f : float(3.0 * 2049.0 * e * e);
    return b;
}

float bound(const CandidateBound& b, float x, float y, float z) {
    if (b.everything) return -std::numeric_limits<float>::infinity();
    const float* c = b.c;
    const float dx = std::max(std::max(c[0] - x, x - c[3]), 0.0f), dy = std::max(std::max(c[1] - y, y - c[4]), 0.0f),
                dz = std::max(std::max(c[2] - z, z - c[5]), 0.0f);
    auto plane = [&](const float* m) { return (m[0] * x + m[1] * y) + (m[2] * z + m[3]); };
    const float above = plane(c + 6);
    const float beyond = std::max(std::max(plane(c + 10), plane(c + 14)), std::max(plane(c + 18), 0.0f));
    const float box = (dx * dx + dy * dy) + dz * dz;
    const float prism = above * above + beyond * beyond;
    return std::max(box, prism) * kKeep - b.slack;
}

size_t points_below(const CandidateBound& b, const float* x, const float* y, const float* z, const float* limit, size_t n, uint32_t* hits) {
#if defined(__x86_64__) || defined(__i386__)
    if (!b.everything && cpu_has_avx2()) return points_below_avx(b.c, x, y, z, limit, n, b.slack, hits);
#endif
    size_t count = 0;
    for (size_t i = 0; i < n; ++i)
        if (bound(b, x[i], y[i], z[i]) < limit[i]) hits[count++] = uint32_t(i);
    return count;
}

void distances2(const Flat& f, const V3* p, size_t n, double* d2) {
    auto point = [p](size_t i) -> const V3& { return p[i]; };
#if defined(__x86_64__) || defined(__i386__)
    if (cpu_has_avx()) return distances2_avx(f, n, d2, point);
#endif
    for (size_t i = 0; i < n; ++i) d2[i] = distance2(f, point(i));
}

void distances2_at(const Flat& f, const V3* p, const uint32_t* which, size_t n, double* d2) {
    auto point = [p, which](size_t h) -> const V3& { return p[which[h]]; };
#if defined(__x86_64__) || defined(__i386__)
    if (cpu_has_avx()) return distances2_avx(f, n, d2, point);
#endif
    for (size_t h = 0; h < n; ++h) d2[h] = distance2(f, point(h));
}

} // namespace tom::detail
