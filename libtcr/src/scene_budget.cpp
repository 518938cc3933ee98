// One triangle budget shared among a scene's meshes by the exact selector (see scene_budget.h).

#include "tcr/scene_budget.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "tom/errors.h"
#include "tom/extract.h"

namespace tcr {

namespace {

// One piece of a mesh's error model: e(n) = a n^-m on [lo, hi].
struct Segment {
    double m = 1, a = 0, lo = 1, hi = 1;
};

// The curve's measured points with triangles and a positive error, in increasing triangle
// count, made non-increasing in error (a finer level measured worse than a coarser one, by the
// sampling's noise, reads as the coarser one's error: every segment's exponent stays > 0).
std::vector<std::pair<double, double>> monotone_points(const tom::ErrorCurve& curve, bool use_max) {
    std::vector<std::pair<double, double>> out;  // (triangles, error)
    for (const tom::ErrorCurvePoint& q : curve.points) {
        const double t = q.triangles, e = use_max ? q.max : q.mean;
        if (!(t > 0) || !(e > 0) || (!out.empty() && t <= out.back().first)) continue;
        out.emplace_back(t, out.empty() ? e : std::min(e, out.back().second * (1 - 1e-9)));
    }
    return out;
}

// The mesh's error model on [lo, hi], as tom::estimate_error reads the curve: k / N below the
// first point, a power law between each two, k / N past the last; empty segments left out.
std::vector<Segment> segments(const tom::ErrorCurve& curve, bool use_max, double lo, double hi) {
    const std::vector<std::pair<double, double>> q = monotone_points(curve, use_max);
    std::vector<Segment> all;
    if (q.empty()) {
        all.push_back({1.0, use_max ? curve.k_max : curve.k_mean, 1, INFINITY});
    } else {
        all.push_back({1.0, q.front().second * q.front().first, 1, q.front().first});
        for (size_t j = 1; j < q.size(); ++j) {
            const double m = std::log(q[j - 1].second / q[j].second) / std::log(q[j].first / q[j - 1].first);
            all.push_back({m, q[j - 1].second * std::pow(q[j - 1].first, m), q[j - 1].first, q[j].first});
        }
        all.push_back({1.0, q.back().second * q.back().first, q.back().first, INFINITY});
    }
    std::vector<Segment> out;
    for (Segment s : all) {
        s.lo = std::max(s.lo, lo);
        s.hi = std::min(s.hi, hi);
        if (s.lo <= s.hi && (out.empty() || s.hi > out.back().hi)) out.push_back(s);
    }
    return out;
}

double error_at(const std::vector<Segment>& model, double n) {
    for (const Segment& s : model)
        if (n <= s.hi) return s.a * std::pow(std::max(n, s.lo), -s.m);
    return model.back().a * std::pow(model.back().hi, -model.back().m);
}

// The triangle range of a mesh: its floor's triangles (at least 1) to all of them.
std::pair<double, double> triangle_range(const BudgetMesh& b) {
    const tom::MeshView& m = *b.mesh;
    const double lo = std::max<uint32_t>(1, tom::active_triangle_count(m, tom::floor_vertex_count(m, b.floor)));
    return {lo, std::max<double>(lo, m.triangle_count)};
}

void check(const std::vector<BudgetMesh>& meshes) {
    for (size_t i = 0; i < meshes.size(); ++i) {
        const BudgetMesh& b = meshes[i];
        if (!b.mesh || b.mesh->triangle_count == 0 || !(b.weight > 0) || !(b.instances >= 1))
            throw tom::ArgumentError("tcr::share_budget: mesh " + std::to_string(i) + " needs a view with triangles, weight > 0 and instances >= 1");
    }
}

// The largest resolution of the mesh with at most `triangles` triangles (its floor at least).
uint32_t resolution_within(const BudgetMesh& b, double triangles) {
    const tom::MeshView& m = *b.mesh;
    return tom::vertex_count_within_triangles(m, uint32_t(std::min<double>(m.triangle_count, std::floor(triangles + 1e-9))), b.floor);
}

// The share's state while it is polished: per mesh its resolution, triangles and model.
struct Polish {
    const std::vector<BudgetMesh>& meshes;
    std::vector<std::vector<Segment>> models;
    std::vector<double> lo;
    std::vector<uint32_t> n, t;

    double error(size_t i, uint32_t triangles) const { return meshes[i].weight * error_at(models[i], std::max<double>(triangles, lo[i])); }
    // mesh i's next finer resolution with more triangles, or 0 at its finest
    uint32_t next(size_t i) const {
        const tom::MeshView& m = *meshes[i].mesh;
        for (uint32_t k = n[i] + 1; k <= m.vertex_count; ++k)
            if (tom::active_triangle_count(m, k) > t[i]) return k;
        return 0;
    }
    // mesh i's next coarser resolution with fewer triangles (not below its floor), or 0 at its floor
    uint32_t previous(size_t i) const {
        const tom::MeshView& m = *meshes[i].mesh;
        const uint32_t floor = tom::floor_vertex_count(m, meshes[i].floor);
        for (uint32_t k = n[i]; k-- > floor;)
            if (tom::active_triangle_count(m, k) < t[i]) return k;
        return 0;
    }
    double total_error() const {
        double e = 0;
        for (size_t i = 0; i < meshes.size(); ++i) e += error(i, t[i]);
        return e;
    }
    // Spends what rounding down and the menu's clamps left: the step to a finer resolution with
    // the most error saved per triangle drawn that still fits, until none does. Returns what is
    // left.
    double spend(double left) {
        for (;;) {
            size_t best = meshes.size();
            uint32_t best_n = 0, best_t = 0;
            double best_ratio = 0;
            for (size_t i = 0; i < meshes.size(); ++i) {
                const uint32_t k = next(i);
                if (k == 0) continue;
                const uint32_t tk = tom::active_triangle_count(*meshes[i].mesh, k);
                const double cost = meshes[i].instances * (tk - t[i]);
                const double ratio = (error(i, t[i]) - error(i, tk)) / cost;
                if (cost <= left && ratio > best_ratio) best = i, best_n = k, best_t = tk, best_ratio = ratio;
            }
            if (best == meshes.size()) return left;
            left -= meshes[best].instances * (best_t - t[best]);
            n[best] = best_n, t[best] = best_t;
        }
    }
    // Trades what spend() alone cannot: one mesh up to kSteps resolutions coarser and the
    // triangles it frees spent again, kept when the summed error falls, until no such trade
    // lowers it. (The curves are not convex between their measured points, so the greedy step
    // can miss a better share by a few steps.)
    void exchange(double left) {
        constexpr int kSteps = 32;
        for (bool improved = true; improved;) {
            improved = false;
            const double before = total_error();
            const std::vector<uint32_t> kept_n = n, kept_t = t;
            for (size_t i = 0; i < meshes.size() && !improved; ++i) {
                double freed = left;
                for (int step = 0; step < kSteps && !improved; ++step) {
                    const uint32_t k = previous(i);
                    if (k == 0) break;
                    const uint32_t tk = tom::active_triangle_count(*meshes[i].mesh, k);
                    freed += meshes[i].instances * (t[i] - tk);
                    n[i] = k, t[i] = tk;
                    const std::vector<uint32_t> coarse_n = n, coarse_t = t;
                    const double rest = spend(freed);
                    if (total_error() < before * (1 - 1e-12)) {
                        left = rest;
                        improved = true;
                    } else {
                        n = coarse_n, t = coarse_t;
                    }
                }
                if (!improved) n = kept_n, t = kept_t;
            }
        }
    }
};

} // namespace

Problem budget_problem(const std::vector<BudgetMesh>& meshes, double budget, bool use_max) {
    check(meshes);
    Problem p;
    p.m = 1.0;
    p.budget_ms = budget;
    p.resize(meshes.size());
    p.way_begin.assign(1, 0);
    for (size_t i = 0; i < meshes.size(); ++i) {
        const BudgetMesh& b = meshes[i];
        const auto [lo, hi] = triangle_range(b);
        const std::vector<Segment> model = segments(b.curve, use_max, lo, hi);
        // way 0: the floor's level alone (the exponent p.m = 1 is then immaterial)
        const double at_lo = b.weight * error_at(model, lo);
        p.importance[i] = at_lo;
        p.error[i] = at_lo * lo;
        p.per_tri_ms[i] = b.instances;
        p.setup_ms[i] = 0;
        p.lo[i] = p.hi[i] = lo;
        p.previous[i] = 0;
        for (const Segment& s : model) p.ways.push_back({s.m, b.weight * s.a, b.instances, 0.0, s.lo, s.hi});
        p.way_begin.push_back(uint32_t(p.ways.size()));
    }
    p.check_menu();
    return p;
}

BudgetShare share_budget(const std::vector<BudgetMesh>& meshes, double budget, bool use_max) {
    const Problem p = budget_problem(meshes, budget, use_max);
    SelectParams params;
    params.policy = OverBudgetPolicy::keep_minimum;  // a mesh is never left out of the scene
    params.tolerance = 1e-9;
    Plan plan;
    select(SelectorKind::exact, p, params, plan);
    // each mesh at the resolution below its planned triangles, then what that left spent
    Polish polish{meshes, {}, {}, {}, {}};
    double drawn = 0;
    for (size_t i = 0; i < meshes.size(); ++i) {
        const BudgetMesh& b = meshes[i];
        const auto [lo, hi] = triangle_range(b);
        polish.models.push_back(segments(b.curve, use_max, lo, hi));
        polish.lo.push_back(lo);
        polish.n.push_back(resolution_within(b, plan.triangles[i]));
        polish.t.push_back(tom::active_triangle_count(*b.mesh, polish.n.back()));
        drawn += b.instances * polish.t.back();
    }
    if (plan.feasible) polish.exchange(polish.spend(budget - drawn));
    BudgetShare share;
    share.feasible = plan.feasible;
    share.vertex_counts = polish.n;
    share.triangles = polish.t;
    double importance = 0;
    for (size_t i = 0; i < meshes.size(); ++i) {
        share.drawn += meshes[i].instances * polish.t[i];
        importance += p.importance[i];
    }
    share.error = polish.total_error();
    share.lower_bound = std::isfinite(plan.upper_bound) ? std::max(0.0, importance - plan.upper_bound) : 0.0;
    share.gap = share.error > 0 ? std::max(0.0, (share.error - share.lower_bound) / share.error) : 0.0;
    return share;
}

} // namespace tcr
