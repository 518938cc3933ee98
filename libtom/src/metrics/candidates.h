#pragma once
// Lower bounds of the squared distance from a point to each candidate of a run: the larger of
// its squared distances to the candidate's box and plane, computed branch-free over separate
// arrays padded to a multiple of four (padding: an empty box at infinite distance), four
// candidates per instruction with AVX (checked at run time; a scalar loop otherwise). below()
// keeps the candidates whose bound is under a given best: usually one or two of dozens.
// Internal to tom::metrics.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "geometry.h"

namespace tom::detail {

struct CandidateBounds {
    size_t padded = 0;  // the candidates, rounded up to a multiple of 4
    std::vector<double> data;  // lx, ly, lz, hx, hy, hz, nx, ny, nz, off, low: `padded` each
    std::vector<uint32_t> hits;
    double* column(int c) { return data.data() + size_t(c) * padded; }
    void fill(const std::vector<Flat>& flat, const std::vector<uint32_t>& list) {
        const size_t m = list.size();
        padded = (m + 3) & ~size_t(3);
        data.resize(11 * padded);
        hits.resize(padded);
        const double inf = std::numeric_limits<double>::infinity();
        for (size_t k = 0; k < padded; ++k) {
            const Flat* f = k < m ? &flat[list[k]] : nullptr;
            column(0)[k] = f ? f->lo.x : inf, column(1)[k] = f ? f->lo.y : inf, column(2)[k] = f ? f->lo.z : inf;
            column(3)[k] = f ? f->hi.x : -inf, column(4)[k] = f ? f->hi.y : -inf, column(5)[k] = f ? f->hi.z : -inf;
            column(6)[k] = f ? f->normal.x : 0, column(7)[k] = f ? f->normal.y : 0, column(8)[k] = f ? f->normal.z : 0, column(9)[k] = f ? f->offset : 0;
        }
    }
    const double* low() { return column(10); }
    // the candidates whose lower bound for p is under `best`, in hits[0, returned count)
    size_t below(V3 p, double best);
};

} // namespace tom::detail
