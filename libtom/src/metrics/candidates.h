#pragma once
// Lower bounds of the squared distance from a point to each candidate of a run: the larger of
// its squared distances to the candidate's box and plane, computed branch-free over separate
// arrays padded to a multiple of eight (padding: an empty box at infinite distance), eight
// candidates per instruction with AVX2 (checked at run time; a scalar loop otherwise). below()
// keeps the candidates whose bound is under a given best: usually one or two of dozens.
//
// In floats, relative to an origin near the run (its centre), so that they keep the precision of
// the run's own size, and made conservative: each bound lowered by more than every rounding of
// the floats can add (candidates.cpp): a bound is never above the exact one, so a candidate the
// exact bound keeps is never dropped (a few more are kept, and their exact distance decides).
// The hits are compacted without branches (a table of lane indices per mask). Against the same
// bounds in doubles four at a time with a branch per hit: the backward searches of bunny00's
// report 15% faster, the same figures. The search lists a run's candidates nearest box first,
// with each block's least box distance (a floor for every point of the run): a point's scan
// stops at the first block whose floor is at its best. On bunny00's 7 levels (callgrind) the
// scans took 2.0G instructions instead of 3.4G, everything 7% fewer. Internal to tom::metrics.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "geometry.h"

namespace tom::detail {

struct CandidateBounds {
    size_t padded = 0;  // the candidates, rounded up to a multiple of 8
    std::vector<float> data;  // lx, ly, lz, hx, hy, hz, nx, ny, nz, off, low: `padded` each
    std::vector<uint32_t> hits;
    std::vector<float> floor;  // per block of eight: a lower bound of every point's squared distance to its boxes
    V3 origin{0, 0, 0};
    float slack = 0;  // the absolute part of the lowering (squared distance)
    size_t listed = 0;
    bool everything = false;  // coordinates out of float's comfortable range: every candidate kept
    float* column(int c) { return data.data() + size_t(c) * padded; }
    // the candidates `list` of `flat`, relative to `origin`; `spread`: how far the points to
    // bound lie from it at most (along any axis); `sorted`, per candidate, the float bits of a
    // lower bound of every point's squared distance to its box in the high half (non-decreasing
    // along the list; the run's box's distance), or null: below() then skips the blocks beyond
    // a point's best
    void fill(const std::vector<Flat>& flat, const std::vector<uint32_t>& list, V3 origin, double spread, const uint64_t* sorted = nullptr);
    const float* low() { return column(10); }
    // the candidates whose lower bound for p is under `best`, in hits[0, returned count); low()
    // then holds the bound for p of every candidate of the blocks scanned (those of the hits)
    size_t below(V3 p, double best);
};

// d2[i] = distance2(f, p[i]) for i < n, bit for bit: four points at a time with AVX (the same
// operations in the same order, both branches computed and the right one kept), one by one
// otherwise. (A run's distances to its centre's nearest triangle, once for each of its points.)
void distances2(const Flat& f, const V3* p, size_t n, double* d2);

} // namespace tom::detail
