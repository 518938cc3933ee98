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

/// Budget left for the drawn objects' per-triangle costs: budget minus their setup costs.
double variable_budget(const Problem& p, const std::vector<uint8_t>& drawn) noexcept;
/// Recomputes plan.cost_ms, plan.benefit and plan.feasible from plan.triangles.
void evaluate(const Problem& p, Plan& plan) noexcept;
/// Sets plan.upper_bound and plan.gap from the dual bound at `lambda`.
void certify(const Problem& p, Plan& plan, double lambda) noexcept;

void solve_exact(const Problem& p, const SelectParams& params, Plan& plan);
void solve_barrier(const Problem& p, const SelectParams& params, Plan& plan);
void solve_greedy(const Problem& p, const SelectParams& params, Plan& plan);
void solve_size_heuristic(const Problem& p, const SelectParams& params, double stress, Plan& plan);

} // namespace tcr::detail
