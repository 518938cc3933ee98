// The frame governor (governor.h): the policy around the runtime that tcrwalk measured on a real
// renderer, in the library so that every engine holds its budget the same way.

#include "tcr/governor.h"

#include <algorithm>
#include <cmath>

namespace tcr {

double frame_to_frame(const std::vector<double>& times, std::vector<double>& steps) {
    if (times.size() < 2) return 0.0;
    double mean = 0;
    for (double t : times) mean += t / double(times.size());
    steps.clear();
    for (size_t k = 1; k < times.size(); ++k) steps.push_back(std::abs(times[k] - times[k - 1]));
    std::nth_element(steps.begin(), steps.begin() + ptrdiff_t(steps.size() / 2), steps.end());
    return mean > 0 ? 1.048 * steps[steps.size() / 2] / mean : 0.0;
}

double frame_to_frame(const std::vector<double>& times) {
    std::vector<double> steps;
    return frame_to_frame(times, steps);
}

FrameGovernor::FrameGovernor(Runtime& runtime, const CostModel& calibrated, const GovernorParams& params)
    : rt_(runtime), params_(params), model_(calibrated), calibrated_safety_ms_(calibrated.safety_ms) {
    recent_ratios_.reserve(kNoiseFrames);
    scratch_.reserve(kNoiseFrames);
    set_budget(params.budget_ms);
}

void FrameGovernor::set_budget(double budget_ms) {
    params_.budget_ms = budget_ms;
    // the allowance for the renderer's noise at this budget, until the frames measure their own
    model_.safety_ms = std::max(calibrated_safety_ms_, params_.safety_sigma * model_.noise_rel * budget_ms);
    rt_.set_cost_model(model_);
    note_planning();
}

double FrameGovernor::planning_reserve_ms() const noexcept { return std::min(reserve_ms_, params_.max_planning_share * params_.budget_ms); }

const FrameReport& FrameGovernor::plan_frame(FrameParams request) {
    const double reserve = planning_reserve_ms();
    const double factor = warming_up() ? params_.warm_up_budget_factor : 1.0;
    request.budget_ms = factor * (params_.budget_ms - reserve);  // the renderer's share
    request.previous_frame_ms = previous_frame_ms_;
    request.deadline_ms = params_.optimize_share * params_.budget_ms;
    const FrameReport& r = rt_.plan_frame(request);
    // the runtime predicts extraction and rendering with the allowance; the frame adds planning
    planning_ms_ = r.cull_ms + r.optimize_ms;
    predicted_ms_ = r.predicted_ms - model_.safety_ms + planning_ms_;
    last_triangles_ = double(r.triangles);
    return r;
}

void FrameGovernor::frame_done(const FrameTimes& times) {
    const double frame_ms = times.frame_ms >= 0 ? times.frame_ms : planning_reserve_ms() + times.extract_ms + times.render_ms;
    if (warming_up()) {
        // the first frame pays for first touches (page faults, caches): not a sample
        if (frames_ > 0 && last_triangles_ > 0) extract_per_triangle_ = std::max(extract_per_triangle_, times.extract_ms / last_triangles_);
        if (frames_ + 1 == params_.warm_up_frames) fold_extraction();
    } else if (params_.follow_noise) {
        follow_noise(frame_ms / std::max(1e-9, predicted_ms_));
    }
    recent_planning_[frames_ % kPlanningFrames] = planning_ms_;
    note_planning();
    previous_frame_ms_ = times.extract_ms + times.render_ms;
    ++frames_;
}

// The next frame's culling and optimisation: twice the second longest of the last eight
// (planning times jitter; a single stall of the machine would otherwise take most of the budget
// for eight frames, the correction would learn those nearly empty frames, and the frame after
// them overshoot), and at least min_planning_share of the budget; extraction is in the model's
// t_tri.
void FrameGovernor::note_planning() {
    double longest = 0, second = 0;
    for (double t : recent_planning_) {
        if (t > longest) second = longest, longest = t;
        else second = std::max(second, t);
    }
    reserve_ms_ = std::max(params_.min_planning_share * params_.budget_ms, 2.0 * second);
}

void FrameGovernor::fold_extraction() {
    model_.t_tri_ms += params_.extraction_margin * extract_per_triangle_;
    rt_.set_cost_model(model_);
}

// The safety allowance follows the renderer's noise as the frames meet it: safety_sigma times
// the frame-to-frame variation of measured over predicted over the last 31 frames, times the
// budget (from 11 frames on). A calibration measures the noise once, for seconds, and a
// machine's varies by the minute.
void FrameGovernor::follow_noise(double ratio) {
    if (recent_ratios_.size() == kNoiseFrames) recent_ratios_.erase(recent_ratios_.begin());
    recent_ratios_.push_back(ratio);
    if (recent_ratios_.size() < kMinNoiseFrames) return;
    model_.safety_ms = std::max(calibrated_safety_ms_, params_.safety_sigma * frame_to_frame(recent_ratios_, scratch_) * params_.budget_ms);
    rt_.set_cost_model(model_);
}

SimulatedRenderer::SimulatedRenderer(double noise_rel, double slowdown, uint64_t seed, bool within_allowance)
    : noise_rel_(noise_rel), slowdown_(slowdown), state_(seed), within_allowance_(within_allowance) {}

// A standard normal deviate (Box-Muller on splitmix64): the same sequence on every platform.
double SimulatedRenderer::gaussian() {
    auto uniform = [&] {
        uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
        return (double((z ^ (z >> 31)) >> 11) + 0.5) * (1.0 / 9007199254740992.0);
    };
    const double u = uniform(), v = uniform();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(6.283185307179586 * v);
}

double SimulatedRenderer::frame_ms(const FrameReport& r, const CostModel& model) {
    const double fixed = model.t_init_ms + model.t_final_ms;
    const double expected = slowdown_ * (fixed + (r.predicted_ms - model.frame_fixed_ms()) / std::max(1e-9, r.correction));
    const double e = std::max(-2.0, std::min(2.0, gaussian())) * noise_rel_;
    const double bound = within_allowance_ ? model.safety_ms : expected;
    return std::max(0.0, expected + std::max(-bound, std::min(bound, expected * e)));
}

} // namespace tcr
