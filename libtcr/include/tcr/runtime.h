#pragma once
// The engine-facing runtime: a scene of TOM meshes with transforms and weights; per frame the
// camera, the budget and the measured time of the previous frame; back, per object, the chosen
// resolution and its index buffer, plus the frame's prediction and certificate.
//
//   tcr::Runtime rt(tcr::read_cost_model("calibration.txt"), tcr::SelectorKind::exact);
//   uint32_t id = rt.add_object(file.mesh(0), transform, 1.0f);
//   ...each frame:
//   tcr::FrameParams f; f.camera = ...; f.budget_ms = 16.0; f.previous_frame_ms = measured;
//   const tcr::FrameReport& r = rt.plan_frame(f);
//   for each object: if (rt.object(id).drawn) { auto e = rt.indices(id, buffer, capacity); draw(...); }
//
// Benefit (Funkhouser & Sequin; Gobbetti & Bouvier): importance = coverage (pixels) x focus x
// weight (x motion); accuracy(n) = 1 - e(n), e(n) = c n^-m x size_px the projected error in
// pixels, c fitted to the mesh's stored error curve for the exponent m (the relative error
// D(n) = c n^-m), or `fixed_c` when the file has none. Cost: the calibrated CostModel, its
// objects' part scaled by a correction that follows the measured time of previous frames
// (an exponential average of measured / predicted, within [0.5, 2]), so slow drifts of the
// renderer (fill growing as objects come close, a busier machine) do not break the budget.

#include <cstdint>
#include <vector>

#include "tcr/model.h"
#include "tcr/select.h"
#include "tcr/view.h"
#include "tom/extract.h"
#include "tom/view.h"

namespace tcr {

struct FrameParams {
    Camera camera;
    double budget_ms = 16.0;         ///< the whole frame
    double previous_frame_ms = 0;    ///< measured time of the last frame (stress selector, model correction); 0 if unknown
    bool correct_model = true;       ///< scale the objects' modelled cost by the recent measured / modelled factor
    double deadline_ms = 0;          ///< optimiser deadline (barrier, exact); 0 for none
    double m = 1.0;                  ///< accuracy exponent: 0.5, 1 or 2
    double hysteresis = 0.0;         ///< relative dead band against the previous frame's choice
    double max_error_px = 0;         ///< cap: no object gets more triangles than it needs for this error (0: no cap)
    bool error_bounded = false;      ///< ignore the budget: each object gets the smallest resolution within max_error_px
    bool use_motion = false;         ///< scale importance by Funkhouser's motion factor
    float focus_weight = 0.5f;       ///< focus factor weight (0: no focus)
    double fixed_c = 1.0;            ///< relative error constant for meshes without a stored curve (Pasman's k ~ 1)
    double triangles_per_pixel = 0.5;  ///< static and stress selectors
    OverBudgetPolicy policy = OverBudgetPolicy::drop_least_valuable;
};

struct ObjectResult {
    bool visible = false;
    bool drawn = false;
    uint32_t vertices = 0;      ///< the resolution to draw: vertices [0, vertices)
    uint32_t triangles = 0;     ///< its active triangles
    float coverage_px = 0, size_px = 0, focus = 1;
    float distance = 0;         ///< eye-space distance to the box centre
    float inside_share = 1;     ///< share of the box inside the view frustum (its geometry cost scales with it)
    double importance = 0;
    double error_px = 0;        ///< projected error at the chosen resolution, as max_error_px bounds it: the stored curve (or Pasman's 2 k arctan(r/d) / N) in pixels
    double predicted_ms = 0;
};

struct FrameReport {
    double predicted_ms = 0;    ///< t_init + t_final + safety + the drawn objects at their chosen resolutions
    double benefit = 0;         ///< of the continuous plan
    double upper_bound = 0;     ///< certified bound on the benefit of any plan of the same objects (NaN: none)
    double gap = 0;             ///< relative distance to the optimum, certified (NaN: the selector gives none)
    double max_error_px = 0;    ///< largest projected error among drawn objects
    uint32_t visible = 0, drawn = 0;
    uint64_t triangles = 0, visible_triangles = 0;  ///< drawn at the chosen resolutions; the visible ones at full
    double cull_ms = 0, optimize_ms = 0;
    double stress = 1.0;        ///< the stress selector's factor after this frame's update
    double correction = 1.0;    ///< the model correction applied to the objects' cost this frame
    bool feasible = true;
    bool deadline_hit = false;
    uint32_t iterations = 0;
};

class Runtime {
public:
    Runtime(const CostModel& model, SelectorKind selector);

    /// Adds an object. `mesh` (and the File it comes from) must outlive the runtime.
    /// \return its id, 0, 1, 2, ... in order of addition.
    uint32_t add_object(const tom::MeshView& mesh, const float transform[16], float weight = 1.0f);
    void set_transform(uint32_t id, const float transform[16]) noexcept;
    void set_weight(uint32_t id, float weight) noexcept;
    void set_selector(SelectorKind selector) noexcept { selector_ = selector; }
    SelectorKind selector() const noexcept { return selector_; }
    void set_cost_model(const CostModel& model) noexcept { model_ = model; }
    const CostModel& cost_model() const noexcept { return model_; }
    size_t object_count() const noexcept { return objects_.size(); }

    /// Culls, measures, selects. Allocates nothing once the scene has been planned once.
    const FrameReport& plan_frame(const FrameParams& params);
    const ObjectResult& object(uint32_t id) const noexcept { return results_[id]; }
    const FrameReport& last_frame() const noexcept { return report_; }

    /// The chosen level's index buffer (nothing written for an object not drawn).
    tom::Extracted indices(uint32_t id, uint32_t* destination, size_t capacity) const noexcept;
    tom::Extracted indices(uint32_t id, uint16_t* destination, size_t capacity) const noexcept;
    /// The same, with where each part's triangles went: `draws` holds tom::part_count(mesh)
    /// entries (one draw per part, each with its material; empty ones for an object not drawn).
    tom::Extracted indices(uint32_t id, uint32_t* destination, size_t capacity, tom::PartDraw* draws) const noexcept;

    /// Projected error in pixels of object `id` at `triangles`, for its last projection.
    double error_px(uint32_t id, double triangles, double m) const noexcept;
    /// The smallest resolution whose projected error is at most `max_error_px` (error-bounded
    /// mode): from the stored error curve, or Pasman's 2 k arctan(r/d) / N with k = fixed_c.
    double triangles_for_error(uint32_t id, double max_error_px) const noexcept;

private:
    struct Object {
        const tom::MeshView* mesh;
        float transform[16];
        float weight;
        Box box;
        double triangles, min_triangles, vertices_per_triangle;
        bool has_curve;
        std::vector<double> curve_tris, curve_error;  // the stored curve (relative error), for error-bounded mode
        double c_by_m[3];                              // relative error constant fitted for m = 0.5, 1, 2
        double diagonal;                               // object-space bounding-box diagonal
        float last_x = -1, last_y = -1;                // previous frame's screen position (motion)
    };
    double c_for(const Object& o, double m, double fixed_c) const noexcept;
    double pasman_k_px(const Object& o, const ObjectResult& r) const noexcept;
    double projected_error_px(const Object& o, const ObjectResult& r, double triangles) const noexcept;
    uint32_t resolution_for(const Object& o, double triangles) const noexcept;

    CostModel model_;
    SelectorKind selector_;
    std::vector<Object> objects_;
    std::vector<ObjectResult> results_;
    std::vector<uint32_t> visible_ids_;
    std::vector<double> coverage_;
    Problem problem_;
    Plan plan_;
    FrameReport report_;
    double stress_ = 1.0;
    double correction_ = 1.0;   // EMA of the factor (measured / model) for the objects' part of the frame
    double last_predicted_ms_ = 0;
    double last_fixed_c_ = 1.0;
    Camera last_camera_{};
};

} // namespace tcr
