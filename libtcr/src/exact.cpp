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
        const double ub = dual_bound(p, plan.drawn, std::pow(b, -(p.m + 1.0)), false);
        if (ub < plan.upper_bound) {
            plan.upper_bound = ub;
            plan.gap = std::max(0.0, (ub - plan.benefit) / std::max(std::abs(ub), 1e-300));
        }
    }
}

// --- with a menu: the multiple-choice problem ---------------------------------------------------
//
// At a multiplier l each object takes its best way and resolution, argmax_j,n b_ij(n) - l c_ij(n)
// (the Lagrangian relaxation of the multiple-choice problem); the cost of that choice does not
// grow with l, but jumps where an object changes its way. Bisection on log l brackets the
// budget: the plan is the choice at the bracket's feasible end, whose ways are then kept while
// the resolutions are solved exactly for the whole budget (the fixed-way problem is the concave
// one above, so this only adds benefit). Its certificate is min g(l) over the bracket's ends: the
// gap left is the relaxation's duality gap, at most about one object's change of way.

namespace {

// Each drawn object's best way and resolution at l; returns their cost.
double choose_at(const Problem& p, const Plan& plan, double lambda, std::vector<uint32_t>& way, std::vector<double>& n) {
    double cost = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        if (!plan.drawn[i]) continue;
        const WayChoice best = best_way_at(p, i, lambda);
        way[i] = best.way;
        n[i] = best.n;
        cost += best.cost;
    }
    return cost;
}

// The resolutions for fixed ways that meet the budget: the fixed-way problem is the concave one
// solve_exact solves, so its optimum spends the budget at one multiplier (returned). In mu = l^(-1/(m+1))
// each resolution is clamp(C_j mu, lo, hi), so the cost is piecewise linear in mu with a
// breakpoint at each end of each clamp: one sort and one sweep find the mu that meets the budget
// exactly. With ways of different exponents it bisects on l from the feasible `feasible` instead.
double spend_budget(const Problem& p, Plan& plan, double feasible, const Deadline& deadline) {
    const size_t n = p.size();
    double m = -1;
    bool one_m = true;
    for (size_t i = 0; i < n && one_m; ++i)
        if (plan.drawn[i]) {
            const double wm = p.way(i, plan.way[i]).m;
            one_m = m < 0 || wm == m;
            m = wm;
        }
    if (m < 0) return 0.0;
    if (!one_m) {
        auto fits = [&](double lambda) {
            double c = 0;
            for (size_t i = 0; i < n; ++i)
                if (plan.drawn[i]) c += p.cost(i, plan.way[i], best_resolution(p.way(i, plan.way[i]), lambda));
            return c <= p.budget_ms;
        };
        double hi = 0;
        if (!fits(0)) {
            double lo = feasible > 0 ? feasible : 1.0;
            for (int k = 0; k < 200 && !fits(lo); ++k) lo *= 2;  // a multiplier that fits
            const double start = lo;
            for (int k = 0; k < 200 && fits(lo); ++k) lo *= 0.5;
            hi = bisect_multiplier(lo, std::min(start, 2.0 * lo), 1e-7, fits, deadline, plan);
        }
        for (size_t i = 0; i < n; ++i)
            if (plan.drawn[i]) plan.triangles[i] = best_resolution(p.way(i, plan.way[i]), hi);
        return hi;
    }
    // cost(mu) = fixed + sum a_j clamp(C_j mu, lo_j, hi_j): at mu = 0 every clamp is at lo
    std::vector<double>& C = plan.work_b;
    std::vector<std::pair<double, uint32_t>>& breaks = plan.work_heap;
    breaks.clear();
    double cost = 0, at_hi = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!plan.drawn[i]) continue;
        const Way w = p.way(i, plan.way[i]);
        C[i] = w.error > 0 && w.hi > w.lo ? root_m1(w.m * w.error / w.per_tri_ms, w.m) : 0.0;
        cost += w.setup_ms + w.per_tri_ms * w.lo;
        at_hi += w.setup_ms + w.per_tri_ms * w.hi;
        if (C[i] > 0) {
            breaks.push_back({w.lo / C[i], uint32_t(2 * i)});      // from here it grows
            breaks.push_back({w.hi / C[i], uint32_t(2 * i + 1)});  // from here it is at hi
        }
    }
    if (at_hi <= p.budget_ms) {  // the budget does not bind (l = 0): every way at its hi
        for (size_t i = 0; i < n; ++i)
            if (plan.drawn[i]) plan.triangles[i] = p.way(i, plan.way[i]).hi;
        return 0.0;
    }
    double mu = 0;
    {
        std::sort(breaks.begin(), breaks.end());
        double slope = 0, at = 0;
        for (const auto& [b, tag] : breaks) {
            const double next = cost + slope * (b - at);
            if (next > p.budget_ms) break;
            cost = next, at = b;
            const size_t i = tag / 2;
            slope += (tag % 2 ? -1.0 : 1.0) * p.way(i, plan.way[i]).per_tri_ms * C[i];
        }
        mu = slope > 0 ? at + (p.budget_ms - cost) / slope : at;
        mu *= 1.0 - 1e-12;  // on the feasible side of the rounding
        ++plan.iterations;
    }
    for (size_t i = 0; i < n; ++i) {
        if (!plan.drawn[i]) continue;
        const Way w = p.way(i, plan.way[i]);
        plan.triangles[i] = C[i] > 0 ? clamp(C[i] * mu, w.lo, w.hi) : w.lo;
    }
    return mu > 0 ? std::pow(mu, -(m + 1.0)) : INFINITY;
}

} // namespace

void spend_on_ways(const Problem& p, Plan& plan) {
    const double lambda = spend_budget(p, plan, plan.multiplier, Deadline(0));
    evaluate(p, plan);
    if (std::isfinite(lambda)) certify(p, plan, lambda, true);
}

void solve_exact_menu(const Problem& p, const SelectParams& params, Plan& plan) {
    const Deadline deadline(params.deadline_ms);
    std::vector<uint32_t> way(p.size(), 0);
    std::vector<double> n(p.size(), 0);
    auto take = [&]() {
        for (size_t i = 0; i < p.size(); ++i)
            if (plan.drawn[i]) plan.way[i] = way[i], plan.triangles[i] = n[i];
    };
    if (choose_at(p, plan, 0.0, way, n) <= p.budget_ms) {  // the budget does not bind: the best ways at full resolution
        take();
        plan.multiplier = 0;
        evaluate(p, plan);
        certify(p, plan, 0.0, true);
        return;
    }
    // bracket: cost(lo) > budget >= cost(hi); the minima fit (the over-budget policy saw to it).
    // The search starts from the multiplier of the plan given (a warm plan: the last frame's,
    // or the same frame's first solve), steps of 4 at a time, then halves the last step.
    const double start = plan.multiplier > 0 && std::isfinite(plan.multiplier) ? plan.multiplier : 1.0;
    double lo = start, hi = start;
    if (choose_at(p, plan, hi, way, n) <= p.budget_ms) {
        for (int k = 0; k < 200 && choose_at(p, plan, lo, way, n) <= p.budget_ms; ++k) hi = lo, lo *= 0.25;
    } else {
        for (int k = 0; k < 200 && choose_at(p, plan, hi, way, n) > p.budget_ms; ++k) lo = hi, hi *= 4;
    }
    // the ways change only where l crosses an object's switch point, and the fixed-way solve
    // after this spends what the bracket leaves: the way bisection needs no more than the
    // certificate's tolerance
    const double tolerance = std::max(1e-12, params.tolerance);
    hi = bisect_multiplier(lo, hi, tolerance, [&](double lambda) { return choose_at(p, plan, lambda, way, n) <= p.budget_ms; }, deadline, plan);
    choose_at(p, plan, hi, way, n);
    take();
    spend_budget(p, plan, hi, deadline);
    evaluate(p, plan);
    certify(p, plan, hi, true);
    plan.multiplier = hi;
    const double ub = dual_bound(p, plan.drawn, lo, true);
    if (ub < plan.upper_bound) {
        plan.upper_bound = ub;
        plan.gap = std::max(0.0, (ub - plan.benefit) / std::max(std::abs(ub), 1e-300));
    }
}

} // namespace tcr::detail
