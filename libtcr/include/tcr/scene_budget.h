#pragma once
// One triangle budget shared among the meshes of a scene so that the scene's summed error is
// least (tomextract --scene-budget): the offline form of a frame's selection, with each mesh's
// stored error curve as its benefit and its drawn triangles as its cost.
//
// Mesh i at n triangles has the error its stored curve estimates, e_i(n) (tom::estimate_error:
// a power law between each two measured points, k / N beyond them), weighted by w_i (its
// instances times their world-space size: what a unit of relative error costs on screen), and
// costs c_i n triangles (c_i: its instances). Each segment of the curve is one way of the mesh
// in a menu problem (tcr::Problem), so the exact selector minimises sum w_i e_i(n_i) subject to
// sum c_i n_i <= budget over the curves as they are, and its dual bound certifies the result.

#include <cstdint>
#include <vector>

#include "tcr/select.h"
#include "tom/error_curve.h"
#include "tom/extract.h"
#include "tom/view.h"

namespace tcr {

/// A mesh to share the budget with.
struct BudgetMesh {
    const tom::MeshView* mesh = nullptr;
    tom::ErrorCurve curve;   ///< its stored error curve (tom::read_error_curve)
    double weight = 1;       ///< w_i > 0: instances x world-space diagonal, say
    double instances = 1;    ///< c_i >= 1: a level of n triangles draws instances x n
    tom::Floor floor = tom::Floor::usable;  ///< how low it may go (tom::floor_vertex_count)
};

/// The share: each mesh's resolution and what the scene draws at it.
struct BudgetShare {
    std::vector<uint32_t> vertex_counts;  ///< per mesh: its resolution
    std::vector<uint32_t> triangles;      ///< per mesh: its triangles at that resolution
    double drawn = 0;       ///< sum of instances x triangles: <= the budget when `feasible`
    double error = 0;       ///< sum of weight x estimated error (the objective; relative error x weight)
    /// Certified: no share of the budget has a summed error below this (the dual bound of the
    /// continuous problem, which every share's resolutions lie in).
    double lower_bound = 0;
    double gap = 0;         ///< (error - lower_bound) / error: 0 proves the share optimal
    bool feasible = true;   ///< false when every mesh at its floor already exceeds the budget: then all are there
};

/// The menu problem of `meshes` under `budget` triangles (see above): object i's ways are the
/// segments of its curve, benefit I_i - w_i e_i(n) with I_i = w_i e_i(lo_i). Exposed for checks.
/// `use_max`: the curves' Hausdorff errors instead of their means.
/// \throw tom::ArgumentError for a mesh without a view, triangles, or a positive weight.
Problem budget_problem(const std::vector<BudgetMesh>& meshes, double budget, bool use_max = false);

/// Shares `budget` triangles among `meshes` (exact selector on budget_problem), each mesh's
/// triangle count rounded down to a resolution of it, so the share never draws more than the
/// budget when every mesh's floor fits. Deterministic.
BudgetShare share_budget(const std::vector<BudgetMesh>& meshes, double budget, bool use_max = false);

} // namespace tcr
