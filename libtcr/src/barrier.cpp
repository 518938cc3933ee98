// Interior-point selection (Gobbetti & Bouvier, Time-critical multiresolution scene rendering,
// IEEE Visualization 1999): logarithmic barrier, sequential unconstrained minimisation with
// Newton steps, started from a strictly feasible point (the previous frame's resolutions,
// pulled inside where needed), stopped by a deadline with the best feasible point so far.
//
// Minimise  t sum A_i n_i^-m - log(B - sum a_i n_i) - sum log(n_i - lo_i) - sum log(hi_i - n_i).
// The Hessian is diagonal plus the rank-one term a a^T / slack^2, so each Newton step costs
// O(N) through Sherman-Morrison. The certificate is the dual bound g(l) at the barrier's
// multiplier estimate l = 1 / (t slack), valid for any l >= 0.

#include <algorithm>
#include <cmath>
#include <limits>

#include "solver.h"

namespace tcr::detail {

void solve_barrier(const Problem& p, const SelectParams& params, Plan& plan) {
    const size_t N = p.size();
    const Deadline deadline(params.deadline_ms);
    std::vector<double>& x = plan.triangles;
    std::vector<double>& dx = plan.work_a;
    std::vector<double>& dinv = plan.work_b;
    std::vector<double>& trial = plan.work_c;
    const double m = p.m;
    // objects with a range to choose from; the others sit at lo = hi
    double budget = variable_budget(p, plan.drawn);
    double lo_cost = 0, hi_cost = 0, free_count = 0;
    for (size_t i = 0; i < N; ++i) {
        if (!plan.drawn[i]) continue;
        if (p.hi[i] - p.lo[i] <= 1e-9 * std::max(1.0, p.hi[i])) {
            x[i] = p.lo[i];
            budget -= p.per_tri_ms[i] * p.lo[i];
            dx[i] = NAN;  // marks a fixed object
            continue;
        }
        dx[i] = 0;
        lo_cost += p.per_tri_ms[i] * p.lo[i];
        hi_cost += p.per_tri_ms[i] * p.hi[i];
        free_count += 1;
    }
    auto is_free = [&](size_t i) { return plan.drawn[i] && !std::isnan(dx[i]); };
    if (hi_cost <= budget) {  // the budget does not bind
        for (size_t i = 0; i < N; ++i)
            if (is_free(i)) x[i] = p.hi[i];
        evaluate(p, plan);
        certify(p, plan, 0.0);
        return;
    }
    if (!(budget - lo_cost > 1e-12 * std::max(1.0, std::abs(budget)))) {  // no interior: the minima exactly fill the budget
        for (size_t i = 0; i < N; ++i)
            if (is_free(i)) x[i] = p.lo[i];
        evaluate(p, plan);
        return;
    }
    // strictly feasible start: the previous frame's choice pulled into the box, then toward lo
    // until 2% of the budget slack is free (the previous optimum sits on the budget)
    double cost = 0, extra = 0;
    for (size_t i = 0; i < N; ++i) {
        if (!is_free(i)) continue;
        const double margin = 0.01 * (p.hi[i] - p.lo[i]);
        const double start = p.previous[i] > 0 ? p.previous[i] : 0.5 * (p.lo[i] + p.hi[i]);
        x[i] = clamp(start, p.lo[i] + margin, p.hi[i] - margin);
        cost += p.per_tri_ms[i] * x[i];
        extra += p.per_tri_ms[i] * (x[i] - p.lo[i]);
    }
    const double target = lo_cost + 0.98 * (budget - lo_cost);
    if (cost > target) {
        const double theta = (target - lo_cost) / extra;
        for (size_t i = 0; i < N; ++i)
            if (is_free(i)) x[i] = p.lo[i] + theta * (x[i] - p.lo[i]);
    }
    auto slack_of = [&](const std::vector<double>& v) {
        double c = 0;
        for (size_t i = 0; i < N; ++i)
            if (is_free(i)) c += p.per_tri_ms[i] * v[i];
        return budget - c;
    };
    // initial t from the start's own duality gap: the barrier's suboptimality bound (2N+1)/t is
    // matched to g(l) - f(x0), with l the median marginal benefit per ms of the free objects (at
    // the optimum they are all equal). A warm start near the optimum begins near the path's end.
    double t;
    {
        evaluate(p, plan);
        std::vector<double>& ratio = trial;
        size_t count = 0;
        for (size_t i = 0; i < N; ++i)
            if (is_free(i)) ratio[count++] = m * p.error[i] * pow_neg(x[i], m) / x[i] / p.per_tri_ms[i];
        std::nth_element(ratio.begin(), ratio.begin() + ptrdiff_t(count / 2), ratio.begin() + ptrdiff_t(count));
        const double lambda0 = count ? ratio[count / 2] : 0.0;
        const double gap0 = dual_bound(p, plan.drawn, lambda0, false) - plan.benefit;
        double error_sum = 0;
        for (size_t i = 0; i < N; ++i)
            if (is_free(i)) error_sum += p.error[i] * pow_neg(x[i], m);
        const double scale = gap0 > 0 ? gap0 : std::max(error_sum, 1e-300);
        t = (2.0 * free_count + 1.0) / std::max(scale, 1e-300 * error_sum + 1e-300);
    }
    const double growth = 20.0;
    double best_lambda = 0;
    for (int outer = 0; outer < 60; ++outer) {
        // centring: Newton's method on phi_t
        for (int inner = 0; inner < 50; ++inner) {
            const double slack = slack_of(x);
            const double us = 1.0 / slack;
            double ud = 0, gd = 0;  // u^T D^-1 u, u^T D^-1 g
            for (size_t i = 0; i < N; ++i) {
                if (!is_free(i)) continue;
                const double nm = pow_neg(x[i], m);
                const double l = x[i] - p.lo[i], h = p.hi[i] - x[i];
                const double g = -t * m * p.error[i] * nm / x[i] + p.per_tri_ms[i] * us - 1.0 / l + 1.0 / h;
                const double d = t * m * (m + 1.0) * p.error[i] * nm / (x[i] * x[i]) + 1.0 / (l * l) + 1.0 / (h * h);
                dinv[i] = 1.0 / d;
                const double u = p.per_tri_ms[i] * us;
                ud += u * u * dinv[i];
                gd += u * g * dinv[i];
                dx[i] = g;  // keep g for now
            }
            // Sherman-Morrison: (D + u u^T)^-1 g = D^-1 g - D^-1 u (u^T D^-1 g) / (1 + u^T D^-1 u)
            const double coef = gd / (1.0 + ud);
            double decrement = 0, step_max = 1.0 / 0.99, cost_change = 0;
            for (size_t i = 0; i < N; ++i) {
                if (!is_free(i)) continue;
                const double u = p.per_tri_ms[i] * us;
                const double step = -(dinv[i] * dx[i] - dinv[i] * u * coef);
                decrement -= dx[i] * step;
                dx[i] = step;
                if (step < 0) step_max = std::min(step_max, (p.lo[i] - x[i]) / step);
                if (step > 0) step_max = std::min(step_max, (p.hi[i] - x[i]) / step);
                cost_change += p.per_tri_ms[i] * step;
            }
            if (cost_change > 0) step_max = std::min(step_max, slack / cost_change);
            ++plan.iterations;
            if (decrement / 2 <= 1e-9) break;
            // line search on the directional derivative: phi is convex along the Newton
            // direction, so a step whose derivative is still <= 0 has decreased it; past the
            // minimum, a secant on the derivative steps back. Divisions only, no logarithms.
            auto derivative = [&](double alpha) {
                double c = 0;
                for (size_t i = 0; i < N; ++i)
                    if (is_free(i)) c += p.per_tri_ms[i] * (x[i] + alpha * dx[i]);
                const double s_new = budget - c;
                if (!(s_new > 0)) return std::numeric_limits<double>::infinity();
                double d = 0;
                for (size_t i = 0; i < N; ++i) {
                    if (!is_free(i)) continue;
                    const double v = x[i] + alpha * dx[i];
                    const double l = v - p.lo[i], h = p.hi[i] - v;
                    if (!(l > 0 && h > 0)) return std::numeric_limits<double>::infinity();
                    const double g = -t * m * p.error[i] * pow_neg(v, m) / v + p.per_tri_ms[i] / s_new - 1.0 / l + 1.0 / h;
                    d += g * dx[i];
                }
                return d;
            };
            const double d0 = -decrement;  // derivative at alpha = 0
            double alpha = std::min(1.0, 0.99 * step_max);
            for (int ls = 0; ls < 30; ++ls) {
                const double d = derivative(alpha);
                if (d <= 0.5 * std::abs(d0) || ls == 29) break;  // at or before the line's minimum (or just past it)
                if (std::isinf(d))
                    alpha *= 0.5;
                else
                    alpha *= std::max(0.1, std::min(0.9, -d0 / (d - d0)));  // secant toward the derivative's zero
            }
            for (size_t i = 0; i < N; ++i)
                if (is_free(i)) x[i] += alpha * dx[i];
            if (deadline.expired()) break;
        }
        // the multiplier estimate of the budget constraint: l = 1 / (t slack)
        best_lambda = 1.0 / (t * slack_of(x));
        evaluate(p, plan);
        certify(p, plan, best_lambda);
        if (plan.gap <= params.tolerance) break;
        if (deadline.expired()) {
            plan.deadline_hit = true;
            break;
        }
        t *= growth;
    }
    // fixed objects were marked in dx; x holds every drawn object's value
    evaluate(p, plan);
    certify(p, plan, best_lambda);
}

} // namespace tcr::detail
