// The selectors against dense brute force on random small problems, and their contracts:
// certificates never lie, plans fit the budget whenever one can, greedy reaches half the
// optimum, hysteresis reduces changes, deadlines return a feasible plan.

#include <cmath>
#include <functional>
#include <random>

#include <catch2/catch.hpp>

#include "tcr/select.h"

namespace {

const tcr::SelectorKind kAll[] = {tcr::SelectorKind::static_size, tcr::SelectorKind::stress, tcr::SelectorKind::greedy,
                                  tcr::SelectorKind::barrier, tcr::SelectorKind::exact};

// A random but plausible frame: importance from coverage, error from k/N, cost per triangle
// from a calibrated model, ranges from a few hundred to tens of thousands of triangles.
tcr::Problem random_problem(std::mt19937& rng, size_t n, double m, double budget_share) {
    std::uniform_real_distribution<double> u(0, 1);
    tcr::Problem p;
    p.m = m;
    p.resize(n);
    double lo_cost = 0, hi_cost = 0;
    for (size_t i = 0; i < n; ++i) {
        const double coverage = 100 + 20000 * u(rng) * u(rng);
        p.importance[i] = coverage * (0.5 + 0.5 * u(rng));
        const double size_px = std::sqrt(coverage) * 1.4;
        p.error[i] = p.importance[i] * (0.5 + 2 * u(rng)) * size_px * std::pow(1.0, m);
        p.per_tri_ms[i] = 2e-5 * (0.8 + 0.4 * u(rng));
        p.setup_ms[i] = 0.01 + 0.02 * u(rng);
        p.lo[i] = 50 + 200 * u(rng);
        p.hi[i] = p.lo[i] + 1000 + 40000 * u(rng);
        p.previous[i] = u(rng) < 0.5 ? p.lo[i] + (p.hi[i] - p.lo[i]) * u(rng) : 0;
        lo_cost += p.cost(i, p.lo[i]);
        hi_cost += p.cost(i, p.hi[i]);
    }
    p.budget_ms = lo_cost + budget_share * (hi_cost - lo_cost);
    return p;
}

// Best benefit over a dense grid of resolutions (every combination), all objects drawn.
double brute_force(const tcr::Problem& p, int steps) {
    const size_t n = p.size();
    std::vector<double> cost(n), best_level(n);
    double best = -INFINITY;
    std::vector<int> k(n, 0);
    std::function<void(size_t, double, double)> rec = [&](size_t i, double c, double b) {
        if (c > p.budget_ms) return;
        if (i == n) {
            best = std::max(best, b);
            return;
        }
        for (int s = 0; s <= steps; ++s) {
            // geometric grid: dense where benefit changes fastest
            const double x = p.lo[i] * std::pow(p.hi[i] / p.lo[i], double(s) / steps);
            rec(i + 1, c + p.cost(i, x), b + p.benefit(i, x));
        }
    };
    rec(0, 0, 0);
    return best;
}

tcr::SelectParams params_for(const tcr::Problem& p, std::vector<double>& coverage) {
    tcr::SelectParams sp;
    coverage.resize(p.size());
    for (size_t i = 0; i < p.size(); ++i) coverage[i] = p.importance[i];
    sp.coverage_px = coverage.data();
    return sp;
}

} // namespace

TEST_CASE("barrier and exact reach the brute-force optimum within their certified gap", "[tcr][select]") {
    std::mt19937 rng(11);
    for (double m : {0.5, 1.0, 2.0})
        for (int trial = 0; trial < 12; ++trial) {
            const tcr::Problem p = random_problem(rng, 3, m, 0.05 + 0.4 * (trial % 4) / 3.0);
            const double brute = brute_force(p, 160);
            std::vector<double> coverage;
            const tcr::SelectParams sp = params_for(p, coverage);
            for (tcr::SelectorKind k : {tcr::SelectorKind::barrier, tcr::SelectorKind::exact}) {
                tcr::Plan plan;
                tcr::select(k, p, sp, plan);
                INFO("m " << m << " trial " << trial << " " << tcr::selector_name(k) << ": benefit " << plan.benefit << " brute " << brute
                          << " bound " << plan.upper_bound << " gap " << plan.gap);
                REQUIRE(plan.feasible);
                REQUIRE(plan.cost_ms <= p.budget_ms * (1 + 1e-9));
                REQUIRE(!std::isnan(plan.upper_bound));
                CHECK(plan.upper_bound >= brute - 1e-9 * std::abs(brute));                      // the certificate never lies
                CHECK(plan.benefit >= brute - (plan.upper_bound - plan.benefit) - 1e-9 * std::abs(brute));  // within its gap
                CHECK(plan.gap <= 1e-3);
            }
        }
}

TEST_CASE("certificates never lie: no random feasible plan beats the upper bound", "[tcr][select]") {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0, 1);
    for (int trial = 0; trial < 20; ++trial) {
        const tcr::Problem p = random_problem(rng, 8, trial % 2 ? 1.0 : 2.0, 0.2);
        std::vector<double> coverage;
        const tcr::SelectParams sp = params_for(p, coverage);
        for (tcr::SelectorKind k : {tcr::SelectorKind::barrier, tcr::SelectorKind::exact}) {
            tcr::Plan plan;
            tcr::select(k, p, sp, plan);
            for (int s = 0; s < 2000; ++s) {
                tcr::Plan other;
                other.triangles.resize(p.size());
                other.drawn.assign(p.size(), 1);
                for (size_t i = 0; i < p.size(); ++i) other.triangles[i] = p.lo[i] + (p.hi[i] - p.lo[i]) * std::pow(u(rng), 3);
                tcr::fit_to_budget(p, other);
                double benefit = 0;
                for (size_t i = 0; i < p.size(); ++i) benefit += p.benefit(i, other.triangles[i]);
                REQUIRE(benefit <= plan.upper_bound + 1e-9 * std::abs(plan.upper_bound));
            }
            // and any multiplier gives a bound: the certificate's formula itself
            for (double lambda : {0.0, 1e-3, 1.0, 1e3, 1e6}) CHECK(tcr::dual_bound(p, plan.drawn, lambda) >= plan.benefit - 1e-9 * std::abs(plan.benefit));
        }
    }
}

TEST_CASE("greedy reaches at least half the optimum", "[tcr][select]") {
    std::mt19937 rng(17);
    for (int trial = 0; trial < 30; ++trial) {
        const tcr::Problem p = random_problem(rng, 12, 1.0, 0.02 + 0.5 * (trial % 5) / 4.0);
        std::vector<double> coverage;
        const tcr::SelectParams sp = params_for(p, coverage);
        tcr::Plan greedy, exact;
        tcr::select(tcr::SelectorKind::greedy, p, sp, greedy);
        tcr::select(tcr::SelectorKind::exact, p, sp, exact);
        // benefit above the all-minimum plan, so "half" is meaningful for negative accuracies
        double base = 0;
        for (size_t i = 0; i < p.size(); ++i) base += p.benefit(i, p.lo[i]);
        INFO("trial " << trial << " greedy " << greedy.benefit - base << " optimum " << exact.benefit - base);
        CHECK(greedy.feasible);
        CHECK(greedy.benefit - base >= 0.5 * (exact.benefit - base));
        CHECK(greedy.benefit <= exact.upper_bound + 1e-9 * std::abs(exact.upper_bound));
    }
}

TEST_CASE("every selector keeps every feasible instance within budget", "[tcr][select]") {
    std::mt19937 rng(23);
    for (int trial = 0; trial < 40; ++trial) {
        const tcr::Problem p = random_problem(rng, 1 + trial % 30, trial % 3 == 0 ? 0.5 : 1.0, 0.01 + 0.9 * (trial % 7) / 6.0);
        std::vector<double> coverage;
        tcr::SelectParams sp = params_for(p, coverage);
        sp.triangles_per_pixel = 10;  // static/stress alone would go far over
        sp.stress = 0.3;
        for (tcr::SelectorKind k : kAll) {
            tcr::Plan plan;
            tcr::select(k, p, sp, plan);
            INFO(tcr::selector_name(k) << " trial " << trial);
            CHECK(plan.feasible);
            CHECK(plan.cost_ms <= p.budget_ms * (1 + 1e-9));
            for (size_t i = 0; i < p.size(); ++i) {
                CHECK(plan.triangles[i] >= p.lo[i] * (1 - 1e-12));
                CHECK(plan.triangles[i] <= p.hi[i] * (1 + 1e-12));
            }
        }
    }
}

TEST_CASE("over budget even at minimum: the policies", "[tcr][select]") {
    std::mt19937 rng(29);
    tcr::Problem p = random_problem(rng, 20, 1.0, 0.0);
    double lo_cost = 0;
    for (size_t i = 0; i < p.size(); ++i) lo_cost += p.cost(i, p.lo[i]);
    p.budget_ms = 0.6 * lo_cost;
    std::vector<double> coverage;
    tcr::SelectParams sp = params_for(p, coverage);
    for (tcr::SelectorKind k : kAll) {
        tcr::Plan plan;
        tcr::select(k, p, sp, plan);
        INFO(tcr::selector_name(k));
        CHECK(plan.feasible);  // the least valuable objects were left out
        size_t dropped = 0;
        for (uint8_t d : plan.drawn) dropped += d == 0;
        CHECK(dropped > 0);
        CHECK(dropped < p.size());
        // what was dropped is worth less per ms than everything kept
        double worst_kept = INFINITY, best_dropped = 0;
        for (size_t i = 0; i < p.size(); ++i) {
            const double v = p.importance[i] / p.cost(i, p.lo[i]);
            (plan.drawn[i] ? worst_kept : best_dropped) = plan.drawn[i] ? std::min(worst_kept, v) : std::max(best_dropped, v);
        }
        CHECK(best_dropped <= worst_kept);
    }
    sp.policy = tcr::OverBudgetPolicy::keep_minimum;
    tcr::Plan plan;
    tcr::select(tcr::SelectorKind::exact, p, sp, plan);
    CHECK(!plan.feasible);
    CHECK(plan.cost_ms == Approx(lo_cost));
}

TEST_CASE("hysteresis reduces resolution changes between frames", "[tcr][select]") {
    std::mt19937 rng(31);
    tcr::Problem p = random_problem(rng, 40, 1.0, 0.3);
    std::normal_distribution<double> drift(0.0, 0.02);
    auto run = [&](double band) {
        tcr::Problem q = p;
        std::mt19937 r(99);
        std::vector<double> coverage;
        tcr::SelectParams sp = params_for(q, coverage);
        sp.hysteresis = band;
        size_t changes = 0;
        std::fill(q.previous.begin(), q.previous.end(), 0.0);
        for (int frame = 0; frame < 60; ++frame) {
            for (size_t i = 0; i < q.size(); ++i) q.error[i] *= std::exp(drift(r));  // a slowly moving camera
            tcr::Plan plan;
            tcr::select(tcr::SelectorKind::exact, q, sp, plan);
            REQUIRE(plan.feasible);
            for (size_t i = 0; i < q.size(); ++i) {
                if (q.previous[i] > 0 && std::abs(plan.triangles[i] - q.previous[i]) > 1e-9 * q.previous[i]) ++changes;
                q.previous[i] = plan.triangles[i];
            }
        }
        return changes;
    };
    const size_t without = run(0.0), with = run(0.1);
    INFO("changes without " << without << ", with 10% hysteresis " << with);
    CHECK(with < without / 2);
}

TEST_CASE("a deadline returns a feasible plan with the gap the method reached", "[tcr][select][deadline]") {
    std::mt19937 rng(37);
    const tcr::Problem p = random_problem(rng, 20000, 1.0, 0.2);
    std::vector<double> coverage;
    tcr::SelectParams sp = params_for(p, coverage);
    sp.deadline_ms = 0.05;
    sp.tolerance = 1e-12;
    tcr::SelectParams unhurried = sp;
    unhurried.deadline_ms = 0;
    unhurried.tolerance = 1e-9;
    for (tcr::SelectorKind k : {tcr::SelectorKind::barrier, tcr::SelectorKind::exact}) {
        tcr::Plan plan, full;
        tcr::select(k, p, sp, plan);
        tcr::select(k, p, unhurried, full);
        INFO(tcr::selector_name(k) << " gap " << plan.gap << " iterations " << plan.iterations << " (without the deadline: gap "
                                   << full.gap << ", " << full.iterations << " iterations)");
        CHECK(plan.deadline_hit);  // 20000 objects cannot reach a 1e-12 gap in 0.05 ms
        CHECK(!full.deadline_hit);
        CHECK(plan.iterations < full.iterations);
        // feasible as computed here, not only as flagged
        double cost = 0;
        for (size_t i = 0; i < p.size(); ++i)
            if (plan.drawn[i]) cost += p.cost(i, plan.triangles[i]);
        CHECK(cost <= p.budget_ms * (1 + 1e-9));
        CHECK(plan.feasible);
        // the gap it reached is a true certificate: its bound is above the unhurried optimum,
        // and the unhurried plan is at least as good
        CHECK(!std::isnan(plan.gap));
        CHECK(plan.gap >= 0);
        CHECK(plan.upper_bound >= plan.benefit);
        CHECK(plan.upper_bound >= full.benefit * (1 - 1e-9));
        CHECK(full.benefit >= plan.benefit * (1 - 1e-9));
    }
}

TEST_CASE("the stress factor follows the TOM paper's load band", "[tcr][stress]") {
    CHECK(tcr::update_stress(1.0, 40, 100) == Approx(0.6));   // load 0.4 < 0.5: relax
    CHECK(tcr::update_stress(1.0, 130, 100) == Approx(1.4));  // load 1.3 > 1.0: stress
    CHECK(tcr::update_stress(1.0, 80, 100) == Approx(1.0));   // inside the band
    CHECK(tcr::update_stress(2.0, 0, 100) == Approx(2.0));    // no measurement yet
}
