// One triangle budget shared among a scene's meshes (tcr::share_budget, tomextract
// --scene-budget): on a small scene of built meshes with measured error curves, the share is the
// brute-force optimum of the same objective up to its certified gap, never draws more than the
// budget, and its certificate bounds every share brute force finds.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <catch2/catch.hpp>

#include "tcr/scene_budget.h"
#include "tom/builder/builder.h"
#include "tom/builder/generate.h"
#include "tom/extract.h"
#include "tom/metrics/report.h"

namespace {

struct Built {
    tom::Mesh mesh;
    tom::TomMesh tom;
    tom::MeshView view;
};

// Three meshes of different detail and difficulty, each built and measured like tombuild's.
std::vector<Built> scene() {
    std::vector<Built> out;
    for (tom::Mesh m : {tom::make_sphere(14, 20, 1.0f, 0.15f), tom::make_torus(18, 10, 1.0f, 0.35f), tom::make_grid(14, 12, 0.3f)}) {
        tom::clean_mesh(m);
        Built b{m, tom::build(m), {}};
        out.push_back(std::move(b));
    }
    for (Built& b : out) b.view = b.tom.view();
    return out;
}

// Every (n_0, n_1, n_2) of resolutions whose drawn triangles fit the budget, by brute force over
// the first two meshes' resolutions (the third then takes its largest that fits): the least
// summed error of share_budget's objective (the model of budget_problem, evaluated per way).
double brute_force(const tcr::Problem& p, const std::vector<std::vector<uint32_t>>& triangles_at, double budget) {
    auto error_of = [&](size_t i, double t) {  // the model's least error over the ways that reach t
        double best = std::numeric_limits<double>::infinity();
        for (uint32_t j = 0; j < p.way_count(i); ++j) {
            const tcr::Way w = p.way(i, j);
            if (t >= w.lo - 1e-9 && t <= w.hi + 1e-9) best = std::min(best, p.importance[i] - p.benefit(i, j, t));
        }
        return best;
    };
    double best = std::numeric_limits<double>::infinity();
    for (const uint32_t t0 : triangles_at[0])
        for (const uint32_t t1 : triangles_at[1]) {
            const double left = budget - p.per_tri_ms[0] * t0 - p.per_tri_ms[1] * t1;
            uint32_t t2 = 0;
            for (const uint32_t t : triangles_at[2])
                if (p.per_tri_ms[2] * t <= left) t2 = std::max(t2, t);
            if (t2 == 0) continue;
            best = std::min(best, error_of(0, t0) + error_of(1, t1) + error_of(2, t2));
        }
    return best;
}

} // namespace

TEST_CASE("a scene's triangle budget goes where it lowers the summed error most: brute force agrees", "[tcr][scene_budget]") {
    const std::vector<Built> built = scene();
    std::vector<tcr::BudgetMesh> meshes;
    std::vector<std::vector<uint32_t>> triangles_at;  // each mesh's distinct triangle counts over its resolutions
    double total = 0;
    const double instances[3] = {1, 3, 2}, size[3] = {1.0, 0.5, 2.0};
    for (size_t i = 0; i < built.size(); ++i) {
        tcr::BudgetMesh b;
        b.mesh = &built[i].view;
        b.curve = tom::measure_error_curve(built[i].mesh, built[i].tom);
        b.instances = instances[i];
        b.weight = instances[i] * size[i] * b.curve.diagonal;
        meshes.push_back(b);
        std::vector<uint32_t> counts;
        for (uint32_t n = built[i].view.min_vertex_count; n <= built[i].view.vertex_count; ++n) counts.push_back(tom::active_triangle_count(built[i].view, n));
        counts.erase(std::unique(counts.begin(), counts.end()), counts.end());
        triangles_at.push_back(counts);
        total += instances[i] * built[i].view.triangle_count;
    }
    for (const double share : {0.08, 0.2, 0.45, 0.8}) {
        const double budget = std::floor(share * total);
        const tcr::BudgetShare s = tcr::share_budget(meshes, budget);
        const tcr::Problem p = tcr::budget_problem(meshes, budget);
        const double optimum = brute_force(p, triangles_at, budget);
        INFO("budget " << budget << " of " << total << ", drawn " << s.drawn << ": share's error " << s.error << ", brute force's " << optimum << ", certified bound "
                       << s.lower_bound << ", gap " << s.gap);
        REQUIRE(s.feasible);
        CHECK(s.drawn <= budget);
        double drawn = 0;
        for (size_t i = 0; i < meshes.size(); ++i) {
            CHECK(s.triangles[i] == tom::active_triangle_count(built[i].view, s.vertex_counts[i]));
            drawn += instances[i] * s.triangles[i];
        }
        CHECK(drawn == s.drawn);
        // the certificate bounds every share, brute force's best included
        CHECK(s.lower_bound <= optimum * (1 + 1e-9));
        // the share is within its certified gap of the optimum, and that gap is small: what a
        // mesh's rounding down to a resolution and the menu's duality gap leave
        CHECK(s.error >= optimum * (1 - 1e-9));
        CHECK(s.error <= optimum * 1.005);
        CHECK(s.gap < 0.05);
    }
    // a budget below every mesh's coarsest level: all at their coarsest, and said so
    const tcr::BudgetShare tight = tcr::share_budget(meshes, 3);
    CHECK_FALSE(tight.feasible);
    for (size_t i = 0; i < meshes.size(); ++i) CHECK(tight.vertex_counts[i] == built[i].view.min_vertex_count);
}

TEST_CASE("the share of a scene's budget weighs a mesh's instances and size", "[tcr][scene_budget]") {
    const std::vector<Built> built = scene();
    std::vector<tcr::BudgetMesh> meshes;
    for (size_t i = 0; i < 2; ++i) {
        tcr::BudgetMesh b;
        b.mesh = &built[0].view;  // the same mesh twice: only the weight differs
        b.curve = tom::measure_error_curve(built[0].mesh, built[0].tom);
        b.weight = i == 0 ? 1.0 : 8.0;
        meshes.push_back(b);
    }
    const tcr::BudgetShare s = tcr::share_budget(meshes, built[0].view.triangle_count);
    // with e ~ k / n the optimum gives n proportional to sqrt(weight): the heavier copy gets more
    CHECK(s.triangles[1] > s.triangles[0]);
    CHECK(s.triangles[1] > 2 * s.triangles[0] * 0.8);
}
