// tcrbench: the selectors of libtcr on seeded, random but realistic frames.
//
// A frame is what libtcr's runtime builds after culling: per visible object its importance
// (coverage x focus x weight, coverage log-normal from a few hundred pixels to a large part of
// the screen), its error constant (Pasman's k from 0.5 to 3 times its projected size), its cost
// per triangle from a typical calibration, and its triangle range (meshes of 1k to 200k
// triangles, never below the fill-bound count). The budget is set so that full detail would take
// about four times it. Between frames the camera drifts: coverages change by a few percent and
// the previous frame's choice is handed back, as an engine would.
//
// Wall times are medians over frames; instruction counts (stable on a shared machine) come from
// scripts/tcrbench-instructions.sh, which runs this tool under valgrind --tool=callgrind.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include <nlohmann/json.hpp>

#include "tcr/select.h"
#include "tool_common.h"

namespace {

struct Scene {
    std::vector<double> coverage, focus, weight, k, size_px, tris, min_tris;
};

Scene make_scene(size_t n, std::mt19937_64& rng) {
    Scene s;
    std::lognormal_distribution<double> coverage(std::log(2000.0), 1.2);
    std::uniform_real_distribution<double> u(0, 1);
    for (size_t i = 0; i < n; ++i) {
        const double c = std::min(5e5, 50 + coverage(rng));
        s.coverage.push_back(c);
        s.focus.push_back(0.5 + 0.5 * u(rng));
        s.weight.push_back(u(rng) < 0.05 ? 4.0 : 1.0);  // a few objects matter more (the one manipulated...)
        s.k.push_back(0.5 + 2.5 * u(rng));
        s.size_px.push_back(std::sqrt(c) * 1.4);
        s.tris.push_back(std::round(std::exp(std::log(1000.0) + u(rng) * std::log(200.0))));
        s.min_tris.push_back(4 + std::round(20 * u(rng)));
    }
    return s;
}

// the problem libtcr's runtime would build for this frame (cost model of a software rasterizer)
void build_problem(const Scene& s, double m, tcr::Problem& p) {
    const double t_tri = 2e-5, t_vert = 1e-5, t_pix = 2e-6, t_setup = 0.01;
    const size_t n = s.coverage.size();
    p.resize(n);
    p.m = m;
    double full = 0;
    for (size_t i = 0; i < n; ++i) {
        const double a = t_tri + 0.5 * t_vert;
        const double fill = t_pix * s.coverage[i];
        const double hi = s.tris[i];
        const double lo = std::min(hi, std::max(s.min_tris[i], fill / a));
        p.importance[i] = s.coverage[i] * s.focus[i] * s.weight[i];
        p.error[i] = p.importance[i] * s.k[i] * s.size_px[i];
        p.per_tri_ms[i] = a;
        p.setup_ms[i] = t_setup + std::max(0.0, fill - a * lo);
        p.lo[i] = lo;
        p.hi[i] = hi;
        full += p.setup_ms[i] + a * hi;
    }
    p.budget_ms = full / 4.0;
}

struct Result {
    std::string selector;
    size_t objects = 0;
    int frames = 0;
    double budget_ms = 0, predicted_ms = 0, benefit = 0, gap = NAN, ns_per_object = 0, max_gap = NAN;
    uint32_t iterations = 0;
    size_t deadline_hits = 0, over_budget = 0;
};

Result run(tcr::SelectorKind kind, size_t objects, int frames, double deadline_ms, double m, uint64_t seed) {
    std::mt19937_64 rng(seed);
    Scene scene = make_scene(objects, rng);
    tcr::Problem p;
    tcr::Plan plan;
    tcr::SelectParams sp;
    sp.deadline_ms = deadline_ms;
    sp.tolerance = 1e-4;
    std::vector<double> times;
    Result r;
    r.selector = tcr::selector_name(kind);
    r.objects = objects;
    r.frames = frames;
    double stress = 1.0, gap_sum = 0, max_gap = 0;
    int gaps = 0;
    std::lognormal_distribution<double> drift(0.0, 0.03);
    for (int f = 0; f < frames; ++f) {
        if (f > 0)
            for (double& c : scene.coverage) c = std::min(5e5, c * drift(rng));  // the camera moves
        for (size_t i = 0; i < objects; ++i) scene.size_px[i] = std::sqrt(scene.coverage[i]) * 1.4;
        build_problem(scene, m, p);
        if (f > 0)
            for (size_t i = 0; i < objects; ++i) p.previous[i] = plan.drawn[i] ? std::min(p.hi[i], std::max(p.lo[i], plan.triangles[i])) : 0.0;
        sp.coverage_px = scene.coverage.data();
        sp.stress = stress;
        const auto t0 = std::chrono::steady_clock::now();
        tcr::select(kind, p, sp, plan);
        times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        stress = tcr::update_stress(stress, plan.cost_ms * 1.05, p.budget_ms);  // as if measured 5% above prediction
        r.budget_ms += p.budget_ms / frames;
        r.predicted_ms += plan.cost_ms / frames;
        r.benefit += plan.benefit / frames;
        r.iterations += plan.iterations;
        r.deadline_hits += plan.deadline_hit;
        r.over_budget += !plan.feasible;
        if (!std::isnan(plan.gap)) {
            gap_sum += plan.gap;
            max_gap = std::max(max_gap, plan.gap);
            ++gaps;
        }
    }
    std::sort(times.begin(), times.end());
    r.ns_per_object = times[times.size() / 2] * 1e9 / double(objects);
    if (gaps) {
        r.gap = gap_sum / gaps;
        r.max_gap = max_gap;
    }
    return r;
}

} // namespace

int main(int argc, char** argv) {
    std::string selector;
    std::vector<size_t> sizes;
    int frames = 20;
    double deadline_ms = 0, m = 1.0;
    uint64_t seed = 1;
    bool json = false;
    CLI::App app{"tcrbench: libtcr's selectors on seeded random frames: predicted time, benefit, certified gap, time per object"};
    app.set_version_flag("--version", "tcrbench 0.1.0");
    app.add_option("--selector", selector, "static, stress, greedy, barrier or exact (default: all)")
        ->check(CLI::IsMember({"static", "stress", "greedy", "barrier", "exact"}));
    app.add_option("--objects", sizes, "Visible objects per frame (default: 100,1000,10000,100000)")->delimiter(',');
    app.add_option("--frames", frames, "Frames per run (default 20)")->check(CLI::Range(1, 100000));
    app.add_option("--deadline-ms", deadline_ms, "Optimiser deadline for barrier and exact (default none)")->check(CLI::NonNegativeNumber);
    app.add_option("-m", m, "Accuracy exponent: 0.5, 1 or 2 (default 1)")->check(CLI::IsMember({0.5, 1.0, 2.0}));
    app.add_option("--seed", seed, "Scene seed (default 1)");
    app.add_flag("--json", json, "One JSON object per selector and size, one per line");
    app.footer("Exit codes: 0 ok, 2 usage error.\nInstruction counts: scripts/tcrbench-instructions.sh exact 10000");
    if (const int code = tools::parse(app, argc, argv); code >= 0) return code;
    try {
        if (sizes.empty()) sizes = {100, 1000, 10000, 100000};
        std::vector<tcr::SelectorKind> kinds;
        if (selector.empty()) {
            kinds = {tcr::SelectorKind::static_size, tcr::SelectorKind::stress, tcr::SelectorKind::greedy, tcr::SelectorKind::barrier, tcr::SelectorKind::exact};
        } else {
            tcr::SelectorKind k;
            tcr::parse_selector(selector, k);
            kinds = {k};
        }
        if (!json)
            std::printf("%-8s %8s %6s %11s %13s %12s %12s %12s %10s %6s\n", "selector", "objects", "frames", "budget ms", "predicted ms", "benefit",
                        "gap (mean)", "gap (max)", "ns/object", "late");
        for (size_t n : sizes)
            for (tcr::SelectorKind k : kinds) {
                const Result r = run(k, n, frames, deadline_ms, m, seed);
                if (json) {
                    nlohmann::ordered_json j;
                    j["selector"] = r.selector;
                    j["objects"] = r.objects;
                    j["frames"] = r.frames;
                    j["budget_ms"] = r.budget_ms;
                    j["predicted_ms"] = r.predicted_ms;
                    j["benefit"] = r.benefit;
                    j["gap"] = std::isnan(r.gap) ? nlohmann::json(nullptr) : nlohmann::json(r.gap);
                    j["max_gap"] = std::isnan(r.max_gap) ? nlohmann::json(nullptr) : nlohmann::json(r.max_gap);
                    j["ns_per_object"] = r.ns_per_object;
                    j["deadline_ms"] = deadline_ms;
                    j["deadline_hits"] = r.deadline_hits;
                    j["over_budget_frames"] = r.over_budget;
                    j["iterations"] = r.iterations;
                    std::printf("%s\n", j.dump().c_str());
                } else {
                    char g[32] = "-", gm[32] = "-";
                    if (!std::isnan(r.gap)) {
                        std::snprintf(g, sizeof g, "%.2e", r.gap);
                        std::snprintf(gm, sizeof gm, "%.2e", r.max_gap);
                    }
                    std::printf("%-8s %8zu %6d %11.3f %13.3f %12.6g %12s %12s %10.1f %6zu\n", r.selector.c_str(), r.objects, r.frames, r.budget_ms,
                                r.predicted_ms, r.benefit, g, gm, r.ns_per_object, r.deadline_hits);
                }
                std::fflush(stdout);
            }
        return tools::exit_ok;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}
