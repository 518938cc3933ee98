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

// The ladder over [lo, hi]: the resolution of step k (0 = lo), capped at hi; the top step; the
// step at or just below n. (Bounds, not a Way: the plain greedy's hot loop reads its arrays.)
namespace greedy_ladder {
double level(double lo, double hi, int k) { return std::min(hi, lo * std::pow(kStep, k)); }
int top(double lo, double hi) { return hi > lo ? int(std::ceil(std::log(hi / lo) / std::log(kStep) - 1e-12)) : 0; }
int nearest_below(double lo, double hi, double n) {
    if (n <= lo) return 0;
    return std::min(top(lo, hi), int(std::floor(std::log(n / lo) / std::log(kStep) + 1e-9)));
}
double level(const Way& w, int k) { return level(w.lo, w.hi, k); }
int top(const Way& w) { return top(w.lo, w.hi); }
int nearest_below(const Way& w, double n) { return nearest_below(w.lo, w.hi, n); }
} // namespace greedy_ladder

// Object i's ladder in its one way.
struct Ladder {
    const Problem& p;
    double level(size_t i, int k) const { return greedy_ladder::level(p.lo[i], p.hi[i], k); }
    int top(size_t i) const { return greedy_ladder::top(p.lo[i], p.hi[i]); }
    int nearest_below(size_t i, double n) const { return greedy_ladder::nearest_below(p.lo[i], p.hi[i], n); }
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

// --- with a menu: Funkhouser's tuples (object, level, algorithm) ------------------------------
//
// Each way has its ladder (the same steps); an object's state is a way and a step. A move is a
// step up or down its ladder, or a change of way to the step of the other ladder nearest its
// cost from above (up) or below (down); an object's best move goes on the heap, valued as
// above (benefit per ms), a change that costs nothing more and gains first. From the previous
// frame's ways and resolutions, down while over budget, then up while the moves fit.

namespace {

using namespace greedy_ladder;

struct State {
    uint32_t way = 0;
    int step = 0;
};

struct Move {
    double value = -INFINITY;  // gain (up) or -loss (down) per ms; -inf: none
    State to;
    double extra = 0;          // the move's cost: > 0 up, < 0 down
};

struct MenuLadder {
    const Problem& p;
    Way way(size_t i, uint32_t j) const { return p.way(i, j); }
    double cost(size_t i, State s) const { return p.cost(i, s.way, level(way(i, s.way), s.step)); }
    double benefit(size_t i, State s) const { return p.benefit(i, s.way, level(way(i, s.way), s.step)); }

    // the best move up (gain > 0) or down (saving > 0) of object i from s
    Move best_move(size_t i, State s, bool up) const {
        const double c0 = cost(i, s), b0 = benefit(i, s);
        Move best;
        auto consider = [&](State to) {
            const double extra = cost(i, to) - c0, gain = benefit(i, to) - b0;
            double value;
            if (up) {
                if (!(gain > 0)) return;
                value = extra > 0 ? gain / extra : INFINITY;  // costs nothing more: first
            } else {
                if (!(extra < 0)) return;
                value = gain / -extra;  // -loss per ms saved (a gain: the best)
            }
            if (value > best.value) best = {value, to, extra};
        };
        const Way w = way(i, s.way);
        if (up && s.step < top(w)) consider({s.way, s.step + 1});
        if (!up && s.step > 0) consider({s.way, s.step - 1});
        for (uint32_t j = 0; j < p.way_count(i); ++j) {
            if (j == s.way) continue;
            const Way other = way(i, j);
            // the other ladder's step nearest c0: the first above it (up) or the last below (down)
            auto cost_of = [&](int k) { return p.cost(i, j, level(other, k)); };
            int k = 0;
            while (k < top(other) && cost_of(k) <= c0) ++k;
            const bool above = cost_of(k) > c0;   // k: the first step dearer than now, or the top
            const int at_most = above ? k - 1 : k;  // the last step as cheap as now or cheaper (-1: none)
            if (up) {
                if (above) consider({j, k});
                if (at_most >= 0) consider({j, at_most});  // a gain that costs nothing more
            } else {
                int below = at_most;
                while (below >= 0 && cost_of(below) >= c0) --below;
                if (below >= 0) consider({j, below});
            }
        }
        return best;
    }
};

} // namespace

void solve_greedy_menu(const Problem& p, const SelectParams&, Plan& plan) {
    const size_t n = p.size();
    const MenuLadder ladder{p};
    std::vector<State> state(n);
    double cost = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!plan.drawn[i]) continue;
        const uint32_t j = p.previous_way.size() == n && p.previous_way[i] < p.way_count(i) ? p.previous_way[i] : 0;
        state[i] = {j, greedy_ladder::nearest_below(p.way(i, j), p.previous[i])};
        cost += ladder.cost(i, state[i]);
    }
    auto less = [](const Entry& x, const Entry& y) { return x.first < y.first || (x.first == y.first && x.second > y.second); };
    std::vector<Entry>& heap = plan.work_heap;
    std::vector<Move> moves(n);
    // phase: down while over budget (up = false), then up while the moves fit
    for (const bool up : {false, true}) {
        heap.clear();
        for (size_t i = 0; i < n; ++i) {
            if (!plan.drawn[i]) continue;
            moves[i] = ladder.best_move(i, state[i], up);
            if (moves[i].value > -INFINITY) heap.push_back({moves[i].value, uint32_t(i)});
        }
        std::make_heap(heap.begin(), heap.end(), less);
        while (!heap.empty() && (up || cost > p.budget_ms)) {
            std::pop_heap(heap.begin(), heap.end(), less);
            const uint32_t i = heap.back().second;
            heap.pop_back();
            const Move mv = moves[i];
            if (up && cost + mv.extra > p.budget_ms) continue;  // does not fit: this object stays
            state[i] = mv.to;
            cost += mv.extra;
            ++plan.iterations;
            moves[i] = ladder.best_move(i, state[i], up);
            if (moves[i].value > -INFINITY) {
                heap.push_back({moves[i].value, i});
                std::push_heap(heap.begin(), heap.end(), less);
            }
        }
    }
    for (size_t i = 0; i < n; ++i)
        if (plan.drawn[i]) {
            plan.way[i] = state[i].way;
            plan.triangles[i] = greedy_ladder::level(p.way(i, state[i].way), state[i].step);
        }
    fit_to_budget(p, plan);  // the minima fit (the policy saw to it): this only guards rounding
}

} // namespace tcr::detail
