#pragma once
// Shared by the selectors (private to libtcr).

#include <chrono>
#include <cmath>

#include "tcr/select.h"

namespace tcr::detail {

/// n^-m for the exponents in use, without pow() where it can be avoided.
inline double pow_neg(double n, double m) noexcept {
    if (m == 1.0) return 1.0 / n;
    if (m == 2.0) return 1.0 / (n * n);
    if (m == 0.5) return 1.0 / std::sqrt(n);
    return std::pow(n, -m);
}

/// x^(1/(m+1)) for the exponents in use.
inline double root_m1(double x, double m) noexcept {
    if (m == 1.0) return std::sqrt(x);
    if (m == 2.0) return std::cbrt(x);
    if (m == 0.5) return std::cbrt(x * x);  // x^(2/3)
    return std::pow(x, 1.0 / (m + 1.0));
}

inline double clamp(double x, double lo, double hi) noexcept { return x < lo ? lo : (x > hi ? hi : x); }

/// The unconstrained maximiser coefficient: n_i(l) = C_i l^(-1/(m+1)), C_i = (m A_i / a_i)^(1/(m+1)).
inline double closed_form_coefficient(const Problem& p, size_t i) noexcept { return root_m1(p.m * p.error[i] / p.per_tri_ms[i], p.m); }

/// The best resolution of way w at multiplier l: argmax over [lo, hi] of -A n^-m - l a n.
inline double best_resolution(const Way& w, double lambda) noexcept {
    if (w.error <= 0) return lambda > 0 ? w.lo : w.hi;
    if (lambda <= 0) return w.hi;
    return clamp(root_m1(w.m * w.error / (lambda * w.per_tri_ms), w.m), w.lo, w.hi);
}

/// Object i's best way and resolution at multiplier l: argmax over its ways j and n of
/// b_ij(n) - l c_ij(n), `value` that maximum (ties: the cheaper way, then the lower j).
struct WayChoice {
    uint32_t way = 0;
    double n = 0, value = -INFINITY, cost = 0;
};
inline WayChoice best_way_at(const Problem& p, size_t i, double lambda) noexcept {
    WayChoice best;
    for (uint32_t j = 0; j < p.way_count(i); ++j) {
        const double x = best_resolution(p.way(i, j), lambda), c = p.cost(i, j, x);
        const double value = p.benefit(i, j, x) - lambda * c;
        if (value > best.value || (value == best.value && c < best.cost)) best = {j, x, value, c};
    }
    return best;
}

/// Object i's way of least cost at its lo (the lowest such j).
inline uint32_t cheapest_way(const Problem& p, size_t i) noexcept {
    uint32_t best = 0;
    for (uint32_t j = 1; j < p.way_count(i); ++j)
        if (p.cost(i, j, p.way(i, j).lo) < p.cost(i, best, p.way(i, best).lo)) best = j;
    return best;
}

struct Deadline {
    std::chrono::steady_clock::time_point end;
    bool active = false;
    explicit Deadline(double ms) {
        if (ms > 0) {
            active = true;
            end = std::chrono::steady_clock::now() + std::chrono::nanoseconds(int64_t(ms * 1e6));
        }
    }
    bool expired() const noexcept { return active && std::chrono::steady_clock::now() >= end; }
};

/// Geometric bisection of a multiplier bracket [lo, hi] (infeasible at lo, feasible at hi) down
/// to hi <= lo (1 + tolerance), 200 steps at most, stopping at the deadline (checked every 8);
/// counts plan.iterations and sets plan.deadline_hit. \return the feasible end.
template <class Feasible>
double bisect_multiplier(double lo, double hi, double tolerance, Feasible&& feasible, const Deadline& deadline, Plan& plan) {
    for (int it = 0; it < 200 && hi > lo * (1 + tolerance); ++it) {
        const double mid = std::sqrt(lo * hi);
        (feasible(mid) ? hi : lo) = mid;
        ++plan.iterations;
        if ((it & 7) == 7 && deadline.expired()) {
            plan.deadline_hit = true;
            break;
        }
    }
    return hi;
}

/// Budget left for the drawn objects' per-triangle costs: budget minus their setup costs.
double variable_budget(const Problem& p, const std::vector<uint8_t>& drawn) noexcept;
/// Recomputes plan.cost_ms, plan.benefit and plan.feasible from plan.triangles.
void evaluate(const Problem& p, Plan& plan) noexcept;
/// Sets plan.upper_bound and plan.gap from the dual bound at `lambda`: over every way of a menu
/// with `ways` (exact on a menu), over way 0 alone otherwise (the problem the others solve).
void certify(const Problem& p, Plan& plan, double lambda, bool ways = false) noexcept;
/// dual_bound() over every way of a menu (`ways`) or over way 0 alone.
double dual_bound(const Problem& p, const std::vector<uint8_t>& drawn, double lambda, bool ways) noexcept;

void solve_exact(const Problem& p, const SelectParams& params, Plan& plan);
void solve_barrier(const Problem& p, const SelectParams& params, Plan& plan);
void solve_greedy(const Problem& p, const SelectParams& params, Plan& plan);
void solve_exact_menu(const Problem& p, const SelectParams& params, Plan& plan);
void spend_on_ways(const Problem& p, Plan& plan);
void solve_greedy_menu(const Problem& p, const SelectParams& params, Plan& plan);
void solve_size_heuristic(const Problem& p, const SelectParams& params, double stress, Plan& plan);

} // namespace tcr::detail
