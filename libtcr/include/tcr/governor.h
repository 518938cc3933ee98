#pragma once
// The frame governor: what every engine needs around tcr::Runtime to hold a frame budget on a
// real, noisy machine (Gobbetti & Bouvier: the non-rendering part is measured and the renderer
// gets the rest). Per frame it
//   - reserves the planning time (culling and optimisation) the recent frames took,
//   - asks the runtime for the rest of the budget, with the optimiser's deadline,
//   - feeds back the measured time of the previous frame (the runtime's model correction),
//   - keeps the cost model's safety allowance at a multiple of the renderer's frame-to-frame
//     noise as measured over the last frames, and
//   - over its first frames (the warm-up) measures extraction per triangle and folds it into the
//     model's per-triangle cost, which is the CPU's share of a triangle.
//
//   tcr::Runtime rt(model, tcr::SelectorKind::exact);   ...rt.add_object(...) for each object
//   tcr::FrameGovernor governor(rt, model, {/*budget_ms*/ 16.0});
//   each frame:
//     const tcr::FrameReport& r = governor.plan_frame(request);   // camera, menu: yours
//     ...extract (rt.indices) and time it; render and time it...
//     governor.frame_done({extract_ms, render_ms, frame_ms});

#include <cstdint>
#include <vector>

#include "tcr/model.h"
#include "tcr/runtime.h"

namespace tcr {

struct GovernorParams {
    double budget_ms = 16.0;          ///< the whole frame: planning, extraction and rendering
    /// The safety allowance: this many frame-to-frame variations of measured over predicted time,
    /// times the budget (less lets more frames over 1.1x the budget, more leaves it underused);
    /// never below the calibrated model's safety_ms.
    double safety_sigma = 0.75;
    bool follow_noise = true;         ///< false: the calibration's allowance throughout (simulated renderers)
    double optimize_share = 0.1;      ///< the optimiser's deadline, a share of the budget
    /// The planning reserve: twice the second longest of the last 8 frames' culling and
    /// optimisation (one stall is not the norm), within [min_planning_share, max_planning_share]
    /// of the budget.
    double min_planning_share = 0.02;
    double max_planning_share = 0.9;
    uint32_t warm_up_frames = 4;      ///< frames planned at warm_up_budget_factor x the budget, timing extraction
    double warm_up_budget_factor = 4;
    double extraction_margin = 1.25;  ///< extraction per triangle joins t_tri times this
};

/// What the engine measured of the frame it last planned.
struct FrameTimes {
    double extract_ms = 0;  ///< writing the index buffers (Runtime::indices)
    double render_ms = 0;   ///< submitting the draws until the frame is finished
    /// The whole frame as measured (planning, extraction, rendering, the engine's own work);
    /// < 0: the planning time reserved plus extract_ms and render_ms.
    double frame_ms = -1;
};

/// The relative variation of times from one to the next: the median of the successive
/// differences' sizes, scaled to a standard deviation (1.048 = 1 / (0.6745 sqrt 2) for normal
/// noise), over the mean. Unlike the standard deviation, a slow spell of the machine (which the
/// runtime's correction follows) barely adds to it, and the median keeps a burst of a few noisy
/// frames out. 0 for fewer than 2 times.
double frame_to_frame(const std::vector<double>& times);
/// The same, its scratch given (allocates nothing once `scratch` holds times.size() values).
double frame_to_frame(const std::vector<double>& times, std::vector<double>& scratch);

/// A renderer simulated from the cost model, for tests and samples without a GPU: a frame takes
/// the time the model gives the runtime's plan (without the runtime's correction, which, fed its
/// own output, would drift), times `slowdown` (a renderer slower or faster than calibrated), plus
/// Gaussian noise of `noise_rel` of it, clamped to two deviations and, `within_allowance`, to the
/// model's safety allowance (as tcrwalk --simulate draws its frames).
class SimulatedRenderer {
public:
    SimulatedRenderer(double noise_rel, double slowdown = 1.0, uint64_t seed = 1, bool within_allowance = true);
    /// The frame `report` plans with `model` (the runtime's, as FrameGovernor::model()): its
    /// extraction and rendering.
    double frame_ms(const FrameReport& report, const CostModel& model);

private:
    double noise_rel_, slowdown_;
    uint64_t state_;
    bool within_allowance_;
    double gaussian();
};

class FrameGovernor {
public:
    /// `runtime` (which must outlive the governor) gets `calibrated`, its safety allowance raised
    /// to safety_sigma x its noise_rel x the budget.
    FrameGovernor(Runtime& runtime, const CostModel& calibrated, const GovernorParams& params = {});

    /// Plans the next frame with `request`'s camera, menu and policy; its budget_ms,
    /// previous_frame_ms and deadline_ms are the governor's (the budget less the planning
    /// reserve; during the warm-up, warm_up_budget_factor x that).
    const FrameReport& plan_frame(FrameParams request);
    /// What the frame planned last took (call once per plan_frame): updates the feedback, the
    /// planning reserve, the noise allowance and, during the warm-up, the extraction cost.
    void frame_done(const FrameTimes& times);

    /// The whole frame the runtime's last plan predicts, comparable with FrameTimes::frame_ms:
    /// its extraction and rendering without the safety allowance, plus its culling and
    /// optimisation.
    double predicted_ms() const noexcept { return predicted_ms_; }
    double planning_reserve_ms() const noexcept;
    bool warming_up() const noexcept { return frames_ < params_.warm_up_frames; }
    const CostModel& model() const noexcept { return model_; }
    const GovernorParams& params() const noexcept { return params_; }
    /// A new budget from the next frame on (the allowance follows it).
    void set_budget(double budget_ms);

private:
    void note_planning();
    void fold_extraction();
    void follow_noise(double measured_over_predicted);

    static constexpr size_t kPlanningFrames = 8, kNoiseFrames = 31, kMinNoiseFrames = 11;
    Runtime& rt_;
    GovernorParams params_;
    CostModel model_;
    double calibrated_safety_ms_;
    uint32_t frames_ = 0;
    double predicted_ms_ = 0, reserve_ms_ = 0, planning_ms_ = 0;
    double previous_frame_ms_ = 0;   // extraction and rendering of the last frame, fed back
    double last_triangles_ = 0;
    double extract_per_triangle_ = 0;
    double recent_planning_[kPlanningFrames] = {};
    std::vector<double> recent_ratios_;  // measured / predicted, the last kNoiseFrames frames
    std::vector<double> scratch_;        // frame_to_frame's
};

} // namespace tcr
