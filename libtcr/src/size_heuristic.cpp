// Resolution from screen size: the static thresholds of Funkhouser & Sequin's first selector
// (a fixed number of triangles per covered pixel) and the TOM paper's demo selector, the same
// linear map scaled by 1 / stress, the stress fed back from the measured frame time (see
// update_stress). Either is then fitted to the budget so no plan is predicted over it.

#include <algorithm>

#include "solver.h"

namespace tcr::detail {

void solve_size_heuristic(const Problem& p, const SelectParams& params, double stress, Plan& plan) {
    const double scale = params.triangles_per_pixel / std::max(stress, 1e-12);
    for (size_t i = 0; i < p.size(); ++i) {
        if (!plan.drawn[i]) continue;
        const double pixels = params.coverage_px ? params.coverage_px[i] : 0.0;
        plan.triangles[i] = clamp(pixels * scale, p.lo[i], p.hi[i]);
    }
    fit_to_budget(p, plan);
}

} // namespace tcr::detail
