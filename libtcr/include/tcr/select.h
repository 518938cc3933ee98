#pragma once
// Resolution selection for one frame: maximise the total benefit of the visible objects under
// one frame-time budget (Gobbetti & Bouvier 1999; Funkhouser & Sequin 1993).
//
// Object i gets n_i triangles in [lo_i, hi_i] (lo_i is at least the count below which the
// object is fill bound and fewer triangles save no time). Its benefit is concave:
//     b_i(n) = I_i - A_i n^-m         (I_i: importance; A_i n^-m: importance x error, m > 0)
// and its cost is linear on that range: c_i(n) = s_i + a_i n (ms). The problem
//     maximise sum b_i(n_i)  subject to  sum c_i(n_i) <= budget,  lo_i <= n_i <= hi_i
// is a separable concave maximisation under one linear constraint. For a multiplier l >= 0 the
// Lagrangian's maximiser is closed form per object, n_i(l) = clamp((m A_i / (l a_i))^(1/(m+1))),
// and g(l) = sum max_n [b_i(n) - l c_i(n)] + l budget >= optimum for every l >= 0: every
// certificate (upper bound, gap) reported here comes from such a g(l), so it never lies.
//
// With a menu (Funkhouser & Sequin, section 4: the tuple object, level, rendering algorithm),
// each object also has other ways to be drawn, each with its own accuracy exponent, error
// coefficient, costs and range: b_ij(n) = I_i - A_ij n^-m_ij, c_ij(n) = s_ij + a_ij n. One way
// per object is chosen, a multiple-choice problem: g(l) takes the best way per object and stays
// an upper bound, but no longer meets the optimum, and exact reports the remaining duality gap.

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace tcr {

/// The five selectors, named as command lines take them.
enum class SelectorKind {
    static_size,  ///< "static": resolution from screen size alone (triangles per pixel), then fitted to the budget
    stress,       ///< "stress": the TOM paper's load feedback on a global stress factor, then fitted to the budget
    greedy,       ///< "greedy": Funkhouser's incremental greedy on benefit/cost from the previous frame's choice
    barrier,      ///< "barrier": Gobbetti-Bouvier interior point (log barrier, Newton), deadline, duality-gap certificate
    exact,        ///< "exact": Lagrange multiplier by bisection on the closed-form per-object optimum
};
const char* selector_name(SelectorKind k) noexcept;
/// Parses "static", "stress", "greedy", "barrier", "exact". \return false for anything else.
bool parse_selector(const std::string& name, SelectorKind& out) noexcept;

/// What to do when even every visible object at its minimum exceeds the budget.
enum class OverBudgetPolicy {
    drop_least_valuable,  ///< leave out the objects of least importance per ms at minimum until the rest fits (default)
    keep_minimum,         ///< draw everything at its minimum; the plan is then over budget and says so
};

/// One way to draw an object besides its first (Problem's own fields): a rendering algorithm,
/// an imposter. The importance is the object's; everything else is the way's own.
struct Way {
    double m = 1.0;          ///< accuracy exponent
    double error = 0;        ///< A_ij >= 0
    double per_tri_ms = 0;   ///< a_ij > 0
    double setup_ms = 0;     ///< s_ij >= 0
    double lo = 1, hi = 1;   ///< triangle range, 1 <= lo <= hi (an imposter: its quad or depth mesh)
};

/// One frame's problem, struct of arrays over the visible objects.
struct Problem {
    double m = 1.0;                  ///< accuracy exponent: 1/2, 1 or 2
    double budget_ms = 0;            ///< for the objects: frame budget minus t_init, t_final and safety
    std::vector<double> importance;  ///< I_i >= 0
    std::vector<double> error;       ///< A_i >= 0 (importance x error coefficient)
    std::vector<double> per_tri_ms;  ///< a_i > 0
    std::vector<double> setup_ms;    ///< s_i >= 0
    std::vector<double> lo, hi;      ///< triangle range, 1 <= lo_i <= hi_i
    std::vector<double> previous;    ///< previous frame's triangles, 0 when none
    /// The menu (optional). Object i's ways are 0, the fields above with exponent m, and
    /// j = 1 .. way_begin[i + 1] - way_begin[i], ways[way_begin[i] + j - 1]. Empty way_begin:
    /// no menu (way 0 only); otherwise size() + 1 non-decreasing entries ending at ways.size().
    std::vector<uint32_t> way_begin;
    std::vector<Way> ways;
    std::vector<uint32_t> previous_way;  ///< the ways of `previous` (greedy's start; empty: 0)

    size_t size() const noexcept { return importance.size(); }
    void resize(size_t n);
    double benefit(size_t i, double n) const noexcept;  ///< b_i(n)
    double cost(size_t i, double n) const noexcept { return setup_ms[i] + per_tri_ms[i] * n; }

    bool has_menu() const noexcept { return !way_begin.empty(); }
    uint32_t way_count(size_t i) const noexcept { return has_menu() ? 1 + way_begin[i + 1] - way_begin[i] : 1; }
    Way way(size_t i, uint32_t j) const noexcept;                     ///< way j of object i (0: its own fields)
    double benefit(size_t i, uint32_t j, double n) const noexcept;    ///< b_ij(n)
    double cost(size_t i, uint32_t j, double n) const noexcept;       ///< c_ij(n)
    /// \throw tom::ArgumentError when the menu's arrays do not fit together
    void check_menu() const;
};

struct SelectParams {
    OverBudgetPolicy policy = OverBudgetPolicy::drop_least_valuable;
    double deadline_ms = 0;        ///< barrier and exact: stop with the best feasible plan when it expires (0: none)
    double tolerance = 1e-4;       ///< barrier and exact: stop at this relative certified gap
    double hysteresis = 0;         ///< relative dead band: keep the previous resolution when the change is smaller
    double triangles_per_pixel = 0.5;  ///< static and stress: resolution = coverage x this / stress
    const double* coverage_px = nullptr; ///< static and stress: each object's coverage (size() entries)
    double stress = 1.0;           ///< stress: the current stress factor (the caller keeps it across frames)
};

/// A frame's plan. `triangles` and `drawn` have size() entries.
struct Plan {
    std::vector<double> triangles;   ///< chosen n_i (continuous; the runtime rounds down to a resolution)
    std::vector<uint8_t> drawn;      ///< 0 for objects left out by the over-budget policy
    std::vector<uint32_t> way;       ///< the way chosen for each object (0 without a menu)
    double cost_ms = 0;              ///< sum of c_i over drawn objects
    double benefit = 0;              ///< sum of b_i over drawn objects
    double upper_bound = 0;          ///< certified: no feasible plan (same drawn set) has more benefit; NaN if none
    double gap = 0;                  ///< (upper_bound - benefit) / |upper_bound|, NaN when the selector gives none
    bool feasible = true;            ///< cost_ms <= budget
    uint32_t iterations = 0;         ///< solver iterations (Newton steps, bisection steps)
    bool deadline_hit = false;
    /// exact on a menu: the plan's Lagrange multiplier (0 where the budget does not bind). A
    /// plan given back to exact starts its search there: the runtime's plan is last frame's.
    double multiplier = 0;

    // reused between frames so that a warm plan allocates nothing (not part of the result)
    std::vector<double> work_a, work_b, work_c;
    std::vector<uint32_t> work_index;
    std::vector<std::pair<double, uint32_t>> work_heap;
};

/// Computes a plan for `p` with the chosen selector. Allocates only when `plan` must grow.
/// Every selector returns a plan with cost_ms <= budget_ms whenever one exists (a plan of only
/// minimum resolutions fits); otherwise the policy decides.
/// With a menu: exact and greedy choose the way and the resolution of every object (the minima
/// that must fit are then each object's cheapest way at its lo); static, stress and barrier keep
/// every object's way 0, as without a menu.
void select(SelectorKind kind, const Problem& p, const SelectParams& params, Plan& plan);

/// Keeps the plan's drawn set and ways and solves its resolutions again for p's budget: the
/// optimum of that fixed-way problem (concave), by one sort of its clamp breakpoints. For a
/// caller that changes a few objects' ways after select(): the runtime defers imposter refreshes
/// this way. Certifies the plan over every way at the multiplier found.
void spend_on_ways(const Problem& p, Plan& plan);

/// The dual bound g(l) for the drawn objects of `plan` (see above), and the l that the plan's
/// marginal costs suggest; used by tests and by selectors for their certificates. With a menu,
/// each object's best way at l: a bound on every plan, whatever its ways.
double dual_bound(const Problem& p, const std::vector<uint8_t>& drawn, double lambda) noexcept;

/// Scales every drawn n_i toward lo_i by one factor so the plan fits the budget (closed form),
/// each in its way (plan.way; none: way 0). \return false when even the minima do not fit.
bool fit_to_budget(const Problem& p, Plan& plan) noexcept;

/// The TOM paper's stress feedback: load = measured / target; stress x (1 - a) below the band,
/// x (1 + a) above it. Defaults: a = 0.4, band [0.5, 1.0].
double update_stress(double stress, double measured_ms, double target_ms, double a = 0.4, double load_min = 0.5, double load_max = 1.0) noexcept;

} // namespace tcr
