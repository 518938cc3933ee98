#pragma once
// Lower bounds of the squared distance from the points of a run to each of its candidates: the
// larger of the squared distance to the candidate's box and that to its prism (the plane's
// distance squared, plus the square of how far the point's projection lies beyond the farthest
// of the three edge lines; the second only for the groups of eight the first keeps), computed for
// one candidate and eight points per instruction with AVX2 (checked at run time; a scalar loop
// otherwise). points_below() keeps the points whose bound is under their best so far: the
// search then measures only those exactly.
//
// In floats, relative to an origin near the run (its centre), so that they keep the precision of
// the run's own size, and made conservative: each bound lowered by more than every rounding of
// the floats can add (candidates.cpp): a bound is never above the exact one, so a candidate the
// exact bound keeps is never dropped (a few more are kept, and their exact distance decides).
// The hits are compacted without branches (a table of lane indices per mask). One candidate is
// tested against eight points at a time, candidates nearest box first until the farthest
// point's best; each candidate's fields are made when it is reached, with a lowering of its own,
// so the run's candidates beyond the stop are never converted. Internal to tom::metrics.

#include <cstddef>
#include <cstdint>

#include "geometry.h"

namespace tom::detail {

// One candidate's bound, relative to the run's origin: its box, plane and edge lines in floats,
// and the lowering that covers their rounding and the points' (`everything`: coordinates out of
// float's comfortable range, every point kept).
constexpr int kBoundFields = 22;
struct CandidateBound {
    float c[kBoundFields];  // lx, ly, lz, hx, hy, hz; nx, ny, nz, off (plane); per edge mx, my, mz, off (its line)
    float slack;  // the absolute part of the lowering (squared distance)
    bool everything;
};

// The lines of a triangle's edges in its plane: unit normals in the plane pointing away from the
// triangle, and offsets (the signed distance of p's projection beyond edge k is
// normal(k).p + offset[k]; edge k runs from corner k to corner k + 1 of a, a + e0, a + e1).
// All zero for a degenerate or sliver triangle, whose plane is not reliable. The normals are
// floats (the bounds read them so) and each offset puts its float line through the edge's first
// corner: 64 bytes a record, against doubles' 96.
struct EdgeLines {
    float normals[3][3];
    double offset[3];
    V3 normal(int k) const { return {normals[k][0], normals[k][1], normals[k][2]}; }
};
EdgeLines edge_lines(const Flat& f);

// Triangle f (its edge lines `lines`) as a candidate of points within `spread` of `origin` along
// every axis.
CandidateBound candidate_bound(const Flat& f, const EdgeLines& lines, V3 origin, double spread);
// The bound at the point (x, y, z) relative to the origin (-inf: everything).
float bound(const CandidateBound& b, float x, float y, float z);
// Of `n` points (coordinates relative to the origin, in floats; n a multiple of eight, a padding
// lane's limit -inf), those whose bound is under their limit (a float of their best), in
// hits[0, returned count) (room for n + 8), in order.
size_t points_below(const CandidateBound& b, const float* x, const float* y, const float* z, const float* limit, size_t n, uint32_t* hits);

// d2[i] = distance2(f, p[i]) for i < n, bit for bit: four points at a time with AVX (the same
// operations in the same order, both branches computed and the right one kept), one by one
// otherwise. (A run's distances to its centre's nearest triangle, once for each of its points.)
void distances2(const Flat& f, const V3* p, size_t n, double* d2);
// d2[h] = distance2(f, p[which[h]]) for h < n, bit for bit, as distances2(): the points a
// candidate's bound kept (four of them at a time where distance2_below() took one, and branched
// on where each projects)
void distances2_at(const Flat& f, const V3* p, const uint32_t* which, size_t n, double* d2);

} // namespace tom::detail
