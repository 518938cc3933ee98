#pragma once
// Lower bounds of the squared distance from the points of a run to each of its candidates: the
// larger of the squared distances to the candidate's box and plane, computed branch-free for
// one candidate and eight points per instruction with AVX2 (checked at run time; a scalar loop
// otherwise). points_below() keeps the points whose bound is under their best so far: the
// search then measures only those exactly.
//
// In floats, relative to an origin near the run (its centre), so that they keep the precision of
// the run's own size, and made conservative: each bound lowered by more than every rounding of
// the floats can add (candidates.cpp): a bound is never above the exact one, so a candidate the
// exact bound keeps is never dropped (a few more are kept, and their exact distance decides).
// The hits are compacted without branches (a table of lane indices per mask). History, on
// bunny00's 7-level report: bounds in doubles four candidates at a time with a branch per hit,
// then floats eight candidates at a time for one point (the backward searches 15% faster), then
// candidates nearest box first with a scan stopped at the first eight too far (7% fewer
// instructions in all), now one candidate against eight points at a time, candidates nearest
// box first until the farthest point's best (5.5% fewer again, the levels 7.7% faster: 0.82 ->
// 0.76 s, medians of 6 interleaved runs). The same figures throughout. Internal to tom::metrics.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "geometry.h"

namespace tom::detail {

struct CandidateBounds {
    static constexpr size_t kFields = 10;  // lx, ly, lz, hx, hy, hz, nx, ny, nz, off
    std::vector<float> data;  // kFields a candidate, side by side (one candidate is read at a time)
    float slack = 0;          // the absolute part of the lowering (squared distance)
    bool everything = false;  // coordinates out of float's comfortable range: every point kept
    // the candidates `list` of `flat`, relative to `origin`; `spread`: how far the points to
    // bound lie from it at most (along any axis)
    void fill(const std::vector<Flat>& flat, const std::vector<uint32_t>& list, V3 origin, double spread);
    // the bound of candidate k at the point (x, y, z) relative to the origin (-inf: everything)
    float bound(size_t k, float x, float y, float z) const;
    // of `n` points (coordinates relative to the origin, in floats; n a multiple of eight, a
    // padding lane's limit -inf), those whose bound to candidate k is under their limit (a float
    // of their best), in hits[0, returned count) (room for n + 8), in order
    size_t points_below(size_t k, const float* x, const float* y, const float* z, const float* limit, size_t n, uint32_t* hits) const;
};

// d2[i] = distance2(f, p[i]) for i < n, bit for bit: four points at a time with AVX (the same
// operations in the same order, both branches computed and the right one kept), one by one
// otherwise. (A run's distances to its centre's nearest triangle, once for each of its points.)
void distances2(const Flat& f, const V3* p, size_t n, double* d2);

} // namespace tom::detail
