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

// --- menus: a way per object besides its level (Funkhouser's rendering algorithms, imposters) ---

namespace {

// random_problem's objects drawn smooth-shaded (way 0, m as given), each with up to three other
// ways: flat shading (Funkhouser's m = 1 on polygons: twice the error, 0.7 of the cost), a
// texture (half the error, 1.4 of the cost, more set-up) and an imposter (two triangles, a fixed
// error worth `imposter_share` of the object's range of accuracy, the set-up of a refresh)
tcr::Problem random_menu_problem(std::mt19937& rng, size_t n, double m, double budget_share) {
    std::uniform_real_distribution<double> u(0, 1);
    tcr::Problem p = random_problem(rng, n, m, 1.0);
    p.way_begin.assign(1, 0);
    double lo_cost = 0, hi_cost = 0;
    for (size_t i = 0; i < n; ++i) {
        const tcr::Way base = p.way(i, 0);
        if (u(rng) < 0.8) p.ways.push_back({1.0, 2.0 * base.error / std::pow(base.lo, m - 1.0), 0.7 * base.per_tri_ms, base.setup_ms, base.lo, base.hi});
        if (u(rng) < 0.6) p.ways.push_back({m, 0.5 * base.error, 1.4 * base.per_tri_ms, base.setup_ms + 0.02, base.lo, base.hi});
        if (u(rng) < 0.5) {
            const double imposter_error = (0.05 + 0.5 * u(rng)) * base.error * std::pow(base.lo, -m) * 4.0;  // benefit I - this at n = 2
            p.ways.push_back({1.0, imposter_error * 2.0, base.per_tri_ms, 0.05 + 0.1 * u(rng), 2, 2});
        }
        p.way_begin.push_back(uint32_t(p.ways.size()));
        double cheapest = INFINITY, dearest = 0;
        for (uint32_t j = 0; j < p.way_count(i); ++j) {
            const tcr::Way w = p.way(i, j);
            cheapest = std::min(cheapest, p.cost(i, j, w.lo));
            dearest = std::max(dearest, p.cost(i, j, w.hi));
        }
        lo_cost += cheapest;
        hi_cost += dearest;
    }
    p.budget_ms = lo_cost + budget_share * (hi_cost - lo_cost);
    return p;
}

// The best benefit over every way of every object on a dense geometric grid of resolutions.
double brute_force_menu(const tcr::Problem& p, int steps) {
    const size_t n = p.size();
    double best = -INFINITY;
    std::function<void(size_t, double, double)> rec = [&](size_t i, double c, double b) {
        if (c > p.budget_ms) return;
        if (i == n) {
            best = std::max(best, b);
            return;
        }
        for (uint32_t j = 0; j < p.way_count(i); ++j) {
            const tcr::Way w = p.way(i, j);
            const int count = w.hi > w.lo ? steps : 0;
            for (int s = 0; s <= count; ++s) {
                const double x = w.lo * std::pow(w.hi / w.lo, count ? double(s) / count : 0.0);
                rec(i + 1, c + p.cost(i, j, x), b + p.benefit(i, j, x));
            }
        }
    };
    rec(0, 0, 0);
    return best;
}

double plan_benefit(const tcr::Problem& p, const tcr::Plan& plan) {
    double b = 0;
    for (size_t i = 0; i < p.size(); ++i)
        if (plan.drawn[i]) b += p.benefit(i, plan.way[i], plan.triangles[i]);
    return b;
}

} // namespace

TEST_CASE("menus: exact's certificate bounds the brute-force optimum over every way, and its plan comes within a small gap", "[tcr][select][menu]") {
    std::mt19937 rng(37);
    int at_optimum = 0, trials = 0, switched = 0;
    for (double m : {1.0, 2.0})
        for (int trial = 0; trial < 16; ++trial) {
            const tcr::Problem p = random_menu_problem(rng, 3, m, 0.03 + 0.5 * (trial % 4) / 3.0);
            const double brute = brute_force_menu(p, 60);
            std::vector<double> coverage;
            const tcr::SelectParams sp = params_for(p, coverage);
            tcr::Plan plan;
            tcr::select(tcr::SelectorKind::exact, p, sp, plan);
            INFO("m " << m << " trial " << trial << ": benefit " << plan.benefit << " brute " << brute << " bound " << plan.upper_bound << " gap " << plan.gap);
            REQUIRE(plan.feasible);
            CHECK(plan.cost_ms <= p.budget_ms * (1 + 1e-9));
            CHECK(plan.benefit == Approx(plan_benefit(p, plan)).epsilon(1e-12));
            CHECK(plan.upper_bound >= brute - 1e-9 * std::abs(brute));  // the relaxation's bound holds over every way
            const double range = std::abs(plan.upper_bound);
            CHECK(plan.benefit >= brute - 0.02 * range);  // within 2% of the bound's size of the optimum
            at_optimum += plan.benefit >= brute - 1e-6 * range;
            for (size_t i = 0; i < p.size(); ++i) switched += plan.way[i] != 0;
            ++trials;
        }
    CHECK(at_optimum >= trials * 3 / 4);  // the duality gap is usually closed by the fixed-way solve
    CHECK(switched > 0);                  // the menu was used
}

TEST_CASE("menus: exact never does worse than without the menu, and picks a way that dominates", "[tcr][select][menu]") {
    std::mt19937 rng(41);
    int better = 0;
    for (int trial = 0; trial < 20; ++trial) {
        const tcr::Problem p = random_menu_problem(rng, 20, 1.0, 0.02 + 0.4 * (trial % 5) / 4.0);
        tcr::Problem plain = p;
        plain.way_begin.clear();
        plain.ways.clear();
        std::vector<double> coverage;
        const tcr::SelectParams sp = params_for(p, coverage);
        tcr::Plan with, without;
        tcr::select(tcr::SelectorKind::exact, p, sp, with);
        tcr::select(tcr::SelectorKind::exact, plain, sp, without);
        INFO("trial " << trial << " with " << with.benefit << " without " << without.benefit << " gap " << with.gap);
        CHECK(with.feasible);
        CHECK(with.benefit >= without.benefit - 1e-3 * std::abs(without.benefit) - with.gap * std::abs(with.upper_bound));
        better += with.benefit > without.benefit * (1 + 1e-9);
    }
    CHECK(better >= 10);
    // a copy of way 0 at half the cost: every object must take it
    std::mt19937 rng2(43);
    tcr::Problem p = random_problem(rng2, 10, 1.0, 0.3);
    p.way_begin.assign(1, 0);
    for (size_t i = 0; i < p.size(); ++i) {
        tcr::Way w = p.way(i, 0);
        w.per_tri_ms *= 0.5;
        w.setup_ms *= 0.5;
        p.ways.push_back(w);
        p.way_begin.push_back(uint32_t(p.ways.size()));
    }
    std::vector<double> coverage;
    const tcr::SelectParams sp = params_for(p, coverage);
    for (tcr::SelectorKind k : {tcr::SelectorKind::exact, tcr::SelectorKind::greedy}) {
        tcr::Plan plan;
        tcr::select(k, p, sp, plan);
        INFO(tcr::selector_name(k));
        for (size_t i = 0; i < p.size(); ++i) CHECK(plan.way[i] == 1);
    }
}

TEST_CASE("greedy reaches at least half the optimum, over levels and over levels and ways", "[tcr][select][menu]") {
    std::mt19937 rng(47);
    int switched = 0;
    for (const bool menu : {false, true})
        for (int trial = 0; trial < 30; ++trial) {
            const double share = 0.02 + 0.5 * (trial % 5) / 4.0;
            const tcr::Problem p = menu ? random_menu_problem(rng, 12, 1.0, share) : random_problem(rng, 12, 1.0, share);
            std::vector<double> coverage;
            const tcr::SelectParams sp = params_for(p, coverage);
            tcr::Plan greedy, exact;
            tcr::select(tcr::SelectorKind::greedy, p, sp, greedy);
            tcr::select(tcr::SelectorKind::exact, p, sp, exact);
            // benefit above every object at its cheapest way's minimum, so "half" is meaningful
            // for negative accuracies
            double base = 0;
            for (size_t i = 0; i < p.size(); ++i) {
                uint32_t cheapest = 0;
                for (uint32_t j = 1; j < p.way_count(i); ++j)
                    if (p.cost(i, j, p.way(i, j).lo) < p.cost(i, cheapest, p.way(i, cheapest).lo)) cheapest = j;
                base += p.benefit(i, cheapest, p.way(i, cheapest).lo);
            }
            INFO((menu ? "menu" : "levels") << " trial " << trial << " greedy " << greedy.benefit - base << " exact " << exact.benefit - base);
            CHECK(greedy.feasible);
            CHECK(greedy.benefit == Approx(plan_benefit(p, greedy)).epsilon(1e-12));
            CHECK(greedy.benefit - base >= 0.5 * (exact.benefit - base));
            CHECK(greedy.benefit <= exact.upper_bound + 1e-9 * std::abs(exact.upper_bound));
            for (size_t i = 0; i < p.size(); ++i) {
                const tcr::Way w = p.way(i, greedy.way[i]);
                CHECK(greedy.triangles[i] >= w.lo * (1 - 1e-12));
                CHECK(greedy.triangles[i] <= w.hi * (1 + 1e-12));
                switched += greedy.way[i] != 0;
            }
        }
    CHECK(switched > 0);  // the menu was used
}

TEST_CASE("menus: static, stress and barrier keep way 0 and plan as without the menu", "[tcr][select][menu]") {
    std::mt19937 rng(53);
    const tcr::Problem p = random_menu_problem(rng, 15, 1.0, 0.3);
    tcr::Problem plain = p;
    plain.way_begin.clear();
    plain.ways.clear();
    std::vector<double> coverage;
    const tcr::SelectParams sp = params_for(p, coverage);
    for (tcr::SelectorKind k : {tcr::SelectorKind::static_size, tcr::SelectorKind::stress, tcr::SelectorKind::barrier}) {
        tcr::Plan with, without;
        tcr::select(k, p, sp, with);
        tcr::select(k, plain, sp, without);
        INFO(tcr::selector_name(k));
        CHECK(with.feasible == without.feasible);
        for (size_t i = 0; i < p.size(); ++i) {
            CHECK(with.way[i] == 0);
            CHECK(with.triangles[i] == without.triangles[i]);
        }
    }
}

TEST_CASE("menus: a malformed menu is refused with what is wrong", "[tcr][select][menu]") {
    std::mt19937 rng(59);
    tcr::Problem p = random_menu_problem(rng, 4, 1.0, 0.3);
    std::vector<double> coverage;
    const tcr::SelectParams sp = params_for(p, coverage);
    tcr::Plan plan;
    tcr::Problem short_index = p;
    short_index.way_begin.pop_back();
    CHECK_THROWS_WITH(tcr::select(tcr::SelectorKind::exact, short_index, sp, plan), Catch::Contains("size() + 1 entries"));
    tcr::Problem bad_way = p;
    bad_way.ways.push_back({1.0, 1.0, 0.0, 0.0, 1, 2});
    bad_way.way_begin.back() = uint32_t(bad_way.ways.size());
    CHECK_THROWS_WITH(tcr::select(tcr::SelectorKind::exact, bad_way, sp, plan), Catch::Contains("per_tri_ms > 0"));
}

TEST_CASE("menus: exact spends the budget that a change of way leaves", "[tcr][select][menu]") {
    // two objects; for each, a set-up heavy way of a tenth of the error: at the multiplier where
    // the first changes its way, the cost jumps past the budget, and the feasible side leaves
    // a share of it unspent unless the resolutions are solved again for the ways kept
    tcr::Problem p;
    p.m = 1.0;
    p.resize(2);
    for (size_t i = 0; i < 2; ++i) {
        p.importance[i] = 1000;
        p.error[i] = 1e5 * double(i + 1);
        p.per_tri_ms[i] = 1e-3;
        p.setup_ms[i] = 0;
        p.lo[i] = 10;
        p.hi[i] = 1e5;
    }
    p.way_begin = {0, 1, 2};
    p.ways = {{1.0, 1e4, 1e-3, 4.0, 10, 1e5}, {1.0, 2e4, 1e-3, 4.0, 10, 1e5}};
    for (double budget : {3.0, 5.0, 7.0, 9.0, 12.0}) {
        p.budget_ms = budget;
        const double brute = brute_force_menu(p, 4000);
        std::vector<double> coverage;
        const tcr::SelectParams sp = params_for(p, coverage);
        tcr::Plan plan;
        tcr::select(tcr::SelectorKind::exact, p, sp, plan);
        INFO("budget " << budget << ": benefit " << plan.benefit << " brute " << brute << " cost " << plan.cost_ms << " ways " << plan.way[0] << plan.way[1]);
        CHECK(plan.cost_ms == Approx(budget).epsilon(1e-6));  // nothing left unspent (no object is at hi)
        CHECK(plan.benefit >= brute - 1e-6 * std::abs(brute));
        CHECK(plan.upper_bound >= brute - 1e-9 * std::abs(brute));
    }
}

TEST_CASE("menus: spend_on_ways keeps the ways and finds the fixed-way optimum for a new budget", "[tcr][select][menu]") {
    // the reference: each object's kept way as the way 0 of a problem without a menu, solved by
    // exact (bisection and a linear solve on the bracket's segment)
    std::mt19937 rng(21);
    for (int trial = 0; trial < 40; ++trial) {
        tcr::Problem p = random_menu_problem(rng, 25, 1.0, 0.3);
        std::vector<double> coverage;
        const tcr::SelectParams sp = params_for(p, coverage);
        tcr::Plan plan;
        tcr::select(tcr::SelectorKind::exact, p, sp, plan);
        const std::vector<uint32_t> ways = plan.way;
        if (std::count(plan.drawn.begin(), plan.drawn.end(), 0)) continue;  // compare whole plans
        p.budget_ms *= trial % 2 ? 0.9 : 1.1;  // less time, or more
        tcr::spend_on_ways(p, plan);
        CHECK(plan.way == ways);
        tcr::Problem fixed;
        fixed.m = p.m;
        fixed.resize(p.size());
        fixed.budget_ms = p.budget_ms;
        double minima = 0;
        for (size_t i = 0; i < p.size(); ++i) {
            if (!plan.drawn[i]) continue;
            const tcr::Way w = p.way(i, ways[i]);
            fixed.importance[i] = p.importance[i], fixed.error[i] = w.error, fixed.per_tri_ms[i] = w.per_tri_ms;
            fixed.setup_ms[i] = w.setup_ms, fixed.lo[i] = w.lo, fixed.hi[i] = w.hi;
            minima += w.setup_ms + w.per_tri_ms * w.lo;
        }
        if (minima > p.budget_ms) continue;  // the kept ways no longer fit: nothing to compare
        tcr::Plan reference;
        std::vector<double> fixed_coverage;
        tcr::select(tcr::SelectorKind::exact, fixed, params_for(fixed, fixed_coverage), reference);
        double benefit = 0, cost = 0;
        for (size_t i = 0; i < p.size(); ++i)
            if (plan.drawn[i]) benefit += p.benefit(i, ways[i], plan.triangles[i]), cost += p.cost(i, ways[i], plan.triangles[i]);
        INFO("trial " << trial << ": benefit " << benefit << " reference " << reference.benefit << " cost " << cost << " budget " << p.budget_ms);
        CHECK(cost <= p.budget_ms * (1 + 1e-12));
        CHECK(benefit >= reference.benefit - 1e-7 * std::abs(reference.benefit));
        CHECK(plan.benefit == Approx(benefit).epsilon(1e-12));
        CHECK(plan.upper_bound >= plan.benefit - 1e-9 * std::abs(plan.benefit));  // a certificate over every way
    }
}
