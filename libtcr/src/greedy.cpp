// Incremental greedy selection (Funkhouser & Sequin 1993, section 4.3): each object has a
// ladder of resolutions (factor 1.25 from lo to hi); starting from the previous frame's choice,
// the object whose step down loses the least benefit per ms saved steps down while the frame
// is over budget, then the object whose step up gains the most benefit per ms steps up while
// the step fits. Greedy on value = benefit/cost is within a factor of two of the optimum.

#include <algorithm>
#include <cmath>

#include "solver.h"

namespace tcr::detail {

namespace {

constexpr double kStep = 1.25;

struct Ladder {
    const Problem& p;
    double level(size_t i, int k) const {  // resolution of step k (0 = lo), capped at hi
        return std::min(p.hi[i], p.lo[i] * std::pow(kStep, k));
    }
    int top(size_t i) const { return p.hi[i] > p.lo[i] ? int(std::ceil(std::log(p.hi[i] / p.lo[i]) / std::log(kStep) - 1e-12)) : 0; }
    int nearest_below(size_t i, double n) const {
        if (n <= p.lo[i]) return 0;
        return std::min(top(i), int(std::floor(std::log(n / p.lo[i]) / std::log(kStep) + 1e-9)));
    }
};

using Entry = std::pair<double, uint32_t>;  // value, object

} // namespace

void solve_greedy(const Problem& p, const SelectParams&, Plan& plan) {
    const size_t n = p.size();
    const Ladder ladder{p};
    std::vector<double>& step = plan.work_b;  // current ladder step per object
    double cost = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!plan.drawn[i]) continue;
        step[i] = ladder.nearest_below(i, p.previous[i]);
        plan.triangles[i] = ladder.level(i, int(step[i]));
        cost += p.cost(i, plan.triangles[i]);
    }
    std::vector<Entry>& heap = plan.work_heap;
    heap.clear();
    heap.reserve(n);  // one entry per object at most (each pop is followed by at most one push)
    // over budget: step down the cheapest losses per ms
    if (cost > p.budget_ms) {
        auto loss = [&](size_t i) {
            const int k = int(step[i]);
            const double a = ladder.level(i, k), b = ladder.level(i, k - 1);
            return (p.benefit(i, a) - p.benefit(i, b)) / std::max(1e-300, p.per_tri_ms[i] * (a - b));
        };
        for (size_t i = 0; i < n; ++i)
            if (plan.drawn[i] && step[i] > 0) heap.push_back({-loss(i), uint32_t(i)});
        auto less = [](const Entry& x, const Entry& y) { return x.first < y.first || (x.first == y.first && x.second > y.second); };
        std::make_heap(heap.begin(), heap.end(), less);
        while (cost > p.budget_ms && !heap.empty()) {
            std::pop_heap(heap.begin(), heap.end(), less);
            const uint32_t i = heap.back().second;
            heap.pop_back();
            const double before = plan.triangles[i];
            step[i] -= 1;
            plan.triangles[i] = ladder.level(i, int(step[i]));
            cost -= p.per_tri_ms[i] * (before - plan.triangles[i]);
            ++plan.iterations;
            if (step[i] > 0) {
                heap.push_back({-loss(i), i});
                std::push_heap(heap.begin(), heap.end(), less);
            }
        }
    }
    // under budget: step up the best gains per ms that still fit
    auto gain = [&](size_t i) {
        const int k = int(step[i]);
        const double a = ladder.level(i, k), b = ladder.level(i, k + 1);
        return (p.benefit(i, b) - p.benefit(i, a)) / std::max(1e-300, p.per_tri_ms[i] * (b - a));
    };
    heap.clear();
    for (size_t i = 0; i < n; ++i)
        if (plan.drawn[i] && step[i] < ladder.top(i)) heap.push_back({gain(i), uint32_t(i)});
    auto less = [](const Entry& x, const Entry& y) { return x.first < y.first || (x.first == y.first && x.second > y.second); };
    std::make_heap(heap.begin(), heap.end(), less);
    while (!heap.empty()) {
        std::pop_heap(heap.begin(), heap.end(), less);
        const uint32_t i = heap.back().second;
        heap.pop_back();
        const double next = ladder.level(i, int(step[i]) + 1);
        const double extra = p.per_tri_ms[i] * (next - plan.triangles[i]);
        if (cost + extra > p.budget_ms) continue;  // does not fit: this object stays
        cost += extra;
        step[i] += 1;
        plan.triangles[i] = next;
        ++plan.iterations;
        if (step[i] < ladder.top(i)) {
            heap.push_back({gain(i), i});
            std::push_heap(heap.begin(), heap.end(), less);
        }
    }
    fit_to_budget(p, plan);  // the minima fit (the policy saw to it): this only guards rounding
}

} // namespace tcr::detail
