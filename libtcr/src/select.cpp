// Selection of one frame's resolutions: the common frame (over-budget policy, hysteresis,
// certificates) around the five selectors.
//
// References: T. Funkhouser, C. Sequin. Adaptive display algorithm for interactive frame rates
// during visualization of complex virtual environments. SIGGRAPH 1993. E. Gobbetti, E. Bouvier.
// Time-critical multiresolution scene rendering. IEEE Visualization 1999.

#include "tcr/select.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include "tom/errors.h"

#include "solver.h"

namespace tcr {

using namespace detail;

const char* selector_name(SelectorKind k) noexcept {
    switch (k) {
    case SelectorKind::static_size: return "static";
    case SelectorKind::stress: return "stress";
    case SelectorKind::greedy: return "greedy";
    case SelectorKind::barrier: return "barrier";
    case SelectorKind::exact: return "exact";
    }
    return "?";
}

bool parse_selector(const std::string& name, SelectorKind& out) noexcept {
    for (SelectorKind k : {SelectorKind::static_size, SelectorKind::stress, SelectorKind::greedy, SelectorKind::barrier, SelectorKind::exact})
        if (name == selector_name(k)) {
            out = k;
            return true;
        }
    return false;
}

void Problem::resize(size_t n) {
    for (std::vector<double>* v : {&importance, &error, &per_tri_ms, &setup_ms, &lo, &hi, &previous}) v->resize(n);
}

double Problem::benefit(size_t i, double n) const noexcept { return importance[i] - error[i] * pow_neg(n, m); }

Way Problem::way(size_t i, uint32_t j) const noexcept {
    if (j == 0) return {m, error[i], per_tri_ms[i], setup_ms[i], lo[i], hi[i]};
    return ways[way_begin[i] + j - 1];
}

double Problem::benefit(size_t i, uint32_t j, double n) const noexcept {
    if (j == 0) return benefit(i, n);
    const Way& w = ways[way_begin[i] + j - 1];
    return importance[i] - w.error * pow_neg(n, w.m);
}

double Problem::cost(size_t i, uint32_t j, double n) const noexcept {
    if (j == 0) return cost(i, n);
    const Way& w = ways[way_begin[i] + j - 1];
    return w.setup_ms + w.per_tri_ms * n;
}

void Problem::check_menu() const {
    if (!has_menu()) return;
    if (way_begin.size() != size() + 1 || way_begin.front() != 0 || way_begin.back() != ways.size())
        throw tom::ArgumentError("tcr::Problem: way_begin needs size() + 1 entries from 0 to ways.size()");
    for (size_t i = 0; i < size(); ++i)
        if (way_begin[i + 1] < way_begin[i]) throw tom::ArgumentError("tcr::Problem: way_begin decreases at object " + std::to_string(i));
    for (size_t k = 0; k < ways.size(); ++k) {
        const Way& w = ways[k];
        if (!(w.per_tri_ms > 0) || !(w.setup_ms >= 0) || !(w.error >= 0) || !(w.m > 0) || !(w.lo >= 1) || !(w.hi >= w.lo))
            throw tom::ArgumentError("tcr::Problem: way " + std::to_string(k) + " needs per_tri_ms > 0, setup_ms >= 0, error >= 0, m > 0, 1 <= lo <= hi");
    }
}

double update_stress(double stress, double measured_ms, double target_ms, double a, double load_min, double load_max) noexcept {
    if (!(target_ms > 0) || !(measured_ms > 0)) return stress;
    const double load = measured_ms / target_ms;
    if (load < load_min) return std::max(1e-6, stress * (1.0 - a));
    if (load > load_max) return std::min(1e6, stress * (1.0 + a));
    return stress;
}

namespace detail {

double variable_budget(const Problem& p, const std::vector<uint8_t>& drawn) noexcept {
    double b = p.budget_ms;
    for (size_t i = 0; i < p.size(); ++i)
        if (drawn[i]) b -= p.setup_ms[i];
    return b;
}

void evaluate(const Problem& p, Plan& plan) noexcept {
    plan.cost_ms = 0;
    plan.benefit = 0;
    const bool ways = p.has_menu() && plan.way.size() == p.size();
    for (size_t i = 0; i < p.size(); ++i)
        if (plan.drawn[i]) {
            const uint32_t j = ways ? plan.way[i] : 0;
            plan.cost_ms += p.cost(i, j, plan.triangles[i]);
            plan.benefit += p.benefit(i, j, plan.triangles[i]);
        }
    plan.feasible = plan.cost_ms <= p.budget_ms * (1 + 1e-12) + 1e-12;
}

void certify(const Problem& p, Plan& plan, double lambda, bool ways) noexcept {
    plan.upper_bound = dual_bound(p, plan.drawn, lambda, ways);
    const double denom = std::max(std::abs(plan.upper_bound), 1e-300);
    plan.gap = std::max(0.0, (plan.upper_bound - plan.benefit) / denom);
}

} // namespace detail

double dual_bound(const Problem& p, const std::vector<uint8_t>& drawn, double lambda) noexcept { return detail::dual_bound(p, drawn, lambda, p.has_menu()); }

void spend_on_ways(const Problem& p, Plan& plan) { detail::spend_on_ways(p, plan); }

double detail::dual_bound(const Problem& p, const std::vector<uint8_t>& drawn, double lambda, bool ways) noexcept {
    // g(l) = sum_i max_{lo<=n<=hi} [b_i(n) - l c_i(n)] + l budget: an upper bound for l >= 0
    lambda = std::max(0.0, lambda);
    double g = lambda * p.budget_ms;
    for (size_t i = 0; i < p.size(); ++i) {
        if (!drawn[i]) continue;
        if (ways && p.has_menu()) {  // the best way at l
            g += best_way_at(p, i, lambda).value;
            continue;
        }
        double n;
        if (p.error[i] <= 0)
            n = lambda > 0 ? p.lo[i] : p.hi[i];
        else if (lambda <= 0)
            n = p.hi[i];
        else
            n = clamp(closed_form_coefficient(p, i) * root_m1(1.0 / lambda, p.m), p.lo[i], p.hi[i]);
        g += p.benefit(i, n) - lambda * p.cost(i, n);
    }
    return g;
}

bool fit_to_budget(const Problem& p, Plan& plan) noexcept {
    const bool ways = p.has_menu() && plan.way.size() == p.size();
    auto way_of = [&](size_t i) { return p.way(i, ways ? plan.way[i] : 0); };
    double lo_cost = 0, extra = 0;
    for (size_t i = 0; i < p.size(); ++i)
        if (plan.drawn[i]) {
            const Way w = way_of(i);
            lo_cost += w.setup_ms + w.per_tri_ms * w.lo;
            extra += w.per_tri_ms * (plan.triangles[i] - w.lo);
        }
    if (lo_cost > p.budget_ms) return false;
    if (lo_cost + extra <= p.budget_ms) return true;
    const double theta = (p.budget_ms - lo_cost) / extra * (1.0 - 1e-12);
    for (size_t i = 0; i < p.size(); ++i)
        if (plan.drawn[i]) {
            const Way w = way_of(i);
            plan.triangles[i] = w.lo + theta * (plan.triangles[i] - w.lo);
        }
    return true;
}

namespace {

// The least object i can cost: at its lo, in its cheapest way (way 0 alone unless `menu`).
double min_cost(const Problem& p, size_t i, bool menu) noexcept {
    if (!menu) return p.cost(i, p.lo[i]);
    const uint32_t j = cheapest_way(p, i);
    return p.cost(i, j, p.way(i, j).lo);
}

// Leaves out the objects of least importance per ms at minimum until the minima fit.
void drop_least_valuable(const Problem& p, bool menu, Plan& plan) {
    std::vector<uint32_t>& order = plan.work_index;
    order.resize(p.size());
    double total = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        order[i] = uint32_t(i);
        total += min_cost(p, i, menu);
    }
    std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) {
        const double vx = p.importance[x] / std::max(1e-300, min_cost(p, x, menu)), vy = p.importance[y] / std::max(1e-300, min_cost(p, y, menu));
        return vx < vy || (vx == vy && x < y);
    });
    for (uint32_t i : order) {
        if (total <= p.budget_ms) break;
        plan.drawn[i] = 0;
        total -= min_cost(p, i, menu);
    }
}

// Keeps the previous resolution where the change would be smaller than the dead band; undoes
// the snaps that cost the most if the plan no longer fits. With a menu, only objects drawn the
// way they were drawn in the previous frame snap, within that way's range.
void apply_hysteresis(const Problem& p, double band, Plan& plan) {
    std::vector<uint32_t>& snapped = plan.work_index;
    snapped.clear();
    double cost = 0;
    const bool menu = p.has_menu() && p.previous_way.size() == p.size();
    for (size_t i = 0; i < p.size(); ++i) {
        if (!plan.drawn[i]) continue;
        const uint32_t j = plan.way[i];
        const Way w = p.way(i, j);
        const double prev = p.previous[i];
        const bool same_way = !menu || p.previous_way[i] == j;
        if (same_way && prev >= w.lo && prev <= w.hi && prev > 0 && std::abs(plan.triangles[i] - prev) < band * prev && plan.triangles[i] != prev) {
            plan.work_a[i] = plan.triangles[i];  // remember the solver's value
            plan.triangles[i] = prev;
            snapped.push_back(uint32_t(i));
        }
        cost += p.cost(i, j, plan.triangles[i]);
    }
    if (cost <= p.budget_ms) return;
    auto extra = [&](uint32_t i) { return p.way(i, plan.way[i]).per_tri_ms * (plan.triangles[i] - plan.work_a[i]); };
    std::sort(snapped.begin(), snapped.end(), [&](uint32_t x, uint32_t y) {
        const double dx = extra(x), dy = extra(y);
        return dx > dy || (dx == dy && x < y);
    });
    for (uint32_t i : snapped) {
        if (cost <= p.budget_ms) break;
        cost -= extra(i);
        plan.triangles[i] = plan.work_a[i];
    }
}

} // namespace

void select(SelectorKind kind, const Problem& p, const SelectParams& params, Plan& plan) {
    const size_t n = p.size();
    p.check_menu();
    const bool menu = p.has_menu() && (kind == SelectorKind::exact || kind == SelectorKind::greedy);
    plan.triangles.resize(n);
    plan.drawn.assign(n, 1);
    plan.way.assign(n, 0);
    plan.work_a.resize(n);
    plan.work_b.resize(n);
    plan.work_c.resize(n);
    plan.upper_bound = std::numeric_limits<double>::quiet_NaN();
    plan.gap = std::numeric_limits<double>::quiet_NaN();
    plan.iterations = 0;
    plan.deadline_hit = false;
    double lo_cost = 0;
    for (size_t i = 0; i < n; ++i) lo_cost += min_cost(p, i, menu);
    if (lo_cost > p.budget_ms) {
        if (params.policy == OverBudgetPolicy::keep_minimum) {
            for (size_t i = 0; i < n; ++i) {
                plan.way[i] = menu ? cheapest_way(p, i) : 0;
                plan.triangles[i] = p.way(i, plan.way[i]).lo;
            }
            evaluate(p, plan);
            return;
        }
        drop_least_valuable(p, menu, plan);
    }
    for (size_t i = 0; i < n; ++i) plan.triangles[i] = p.lo[i];
    switch (kind) {
    case SelectorKind::exact:
        if (menu) solve_exact_menu(p, params, plan);
        else solve_exact(p, params, plan);
        break;
    case SelectorKind::barrier: solve_barrier(p, params, plan); break;
    case SelectorKind::greedy:
        if (menu) solve_greedy_menu(p, params, plan);
        else solve_greedy(p, params, plan);
        break;
    case SelectorKind::static_size: solve_size_heuristic(p, params, 1.0, plan); break;
    case SelectorKind::stress: solve_size_heuristic(p, params, params.stress, plan); break;
    }
    if (params.hysteresis > 0 && !(menu && kind == SelectorKind::greedy)) apply_hysteresis(p, params.hysteresis, plan);  // (greedy on a menu starts from the previous frame)
    evaluate(p, plan);
    // the certificate holds for any plan with these drawn objects: recompute the gap for the final one
    if (!std::isnan(plan.upper_bound)) plan.gap = std::max(0.0, (plan.upper_bound - plan.benefit) / std::max(std::abs(plan.upper_bound), 1e-300));
}

} // namespace tcr
