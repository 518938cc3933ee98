// Exact selection through the separable structure (the follow-up of Gobbetti & Bouvier 2000:
// Lagrange multiplier estimates in linear time).
//
// For a multiplier l each object's best resolution is n_i = clamp(C_i mu), mu = l^(-1/(m+1)),
// C_i = (m A_i / a_i)^(1/(m+1)) computed once per frame. The cost sum_i a_i clamp(C_i mu) is
// piecewise linear and non-decreasing in mu: bisection brackets the mu that meets the budget,
// then one linear solve on the bracket's segment lands on it. The plan is the KKT point of the
// continuous problem; its certificate is the dual bound g(l) at the same l (gap ~ 0).

#include <algorithm>
#include <cmath>

#include "solver.h"

namespace tcr::detail {

void solve_exact(const Problem& p, const SelectParams& params, Plan& plan) {
    const size_t n = p.size();
    const Deadline deadline(params.deadline_ms);
    const double budget = variable_budget(p, plan.drawn);
    std::vector<double>& C = plan.work_b;
    double at_hi = 0, mu_max = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!plan.drawn[i]) continue;
        at_hi += p.per_tri_ms[i] * p.hi[i];
        C[i] = p.error[i] > 0 ? closed_form_coefficient(p, i) : 0.0;
        if (C[i] > 0) mu_max = std::max(mu_max, p.hi[i] / C[i]);
    }
    if (at_hi <= budget) {  // the budget does not bind: full resolution is optimal
        for (size_t i = 0; i < n; ++i)
            if (plan.drawn[i]) plan.triangles[i] = p.hi[i];
        evaluate(p, plan);
        certify(p, plan, 0.0);
        return;
    }
    auto cost_at = [&](double mu) {
        double c = 0;
        for (size_t i = 0; i < n; ++i)
            if (plan.drawn[i]) c += p.per_tri_ms[i] * clamp(C[i] * mu, p.lo[i], p.hi[i]);
        return c;
    };
    // cost(0), the minima's, is within the budget (the over-budget policy saw to it) < at_hi = cost(mu_max)
    double a = 0, b = mu_max;
    const double tolerance = std::max(1e-15, params.tolerance * 1e-3);
    for (int it = 0; it < 100; ++it) {
        const double mid = 0.5 * (a + b);
        if (cost_at(mid) <= budget)
            a = mid;
        else
            b = mid;
        ++plan.iterations;
        if (b - a <= tolerance * b) break;
        if ((it & 7) == 7 && deadline.expired()) {
            plan.deadline_hit = true;
            break;
        }
    }
    // on [a, b] the objects clamped at both ends agree with a linear model: solve it exactly
    double fixed = 0, slope = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!plan.drawn[i]) continue;
        const double lo_mu = C[i] > 0 ? p.lo[i] / C[i] : INFINITY, hi_mu = C[i] > 0 ? p.hi[i] / C[i] : INFINITY;
        if (hi_mu <= a)
            fixed += p.per_tri_ms[i] * p.hi[i];
        else if (lo_mu >= b)
            fixed += p.per_tri_ms[i] * p.lo[i];
        else if (lo_mu <= a && hi_mu >= b)
            slope += p.per_tri_ms[i] * C[i];
        else
            slope = -1;  // a breakpoint inside the bracket: keep the bisection's feasible end
        if (slope < 0) break;
    }
    double mu = a;
    if (slope > 0) {
        const double exact = (budget - fixed) / slope;
        if (exact >= a && exact <= b && cost_at(exact) <= budget) mu = exact;
    }
    for (size_t i = 0; i < n; ++i)
        if (plan.drawn[i]) plan.triangles[i] = clamp(C[i] * mu, p.lo[i], p.hi[i]);
    evaluate(p, plan);
    // certificate: g(l) at the plan's multiplier (any l >= 0 bounds the optimum)
    const double lambda = mu > 0 ? std::pow(mu, -(p.m + 1.0)) : 0.0;
    certify(p, plan, lambda);
    if (mu > 0 && b > a) {  // the other end of the bracket may certify tighter
        const double ub = dual_bound(p, plan.drawn, std::pow(b, -(p.m + 1.0)));
        if (ub < plan.upper_bound) {
            plan.upper_bound = ub;
            plan.gap = std::max(0.0, (ub - plan.benefit) / std::max(std::abs(ub), 1e-300));
        }
    }
}

} // namespace tcr::detail
