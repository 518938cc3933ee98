// libtcr's C API (tom/tcr.h) over tcr::Runtime and tcr::FrameGovernor: conversions between the C
// structs and the C++ ones, every entry point guarded (capi_common.h).

#include "tom/tcr.h"

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "capi_common.h"
#include "tcr/calibrate.h"
#include "tcr/governor.h"
#include "tcr/model.h"
#include "tcr/runtime.h"

struct tcr_runtime {
    explicit tcr_runtime(const tcr::CostModel& model, tcr::SelectorKind selector) : runtime(model, selector) {}
    tcr::Runtime runtime;
};

// The engine's C callbacks as tcr::calibrate's renderer; each call's draws converted to C.
class CCalibrationRenderer final : public tcr::CalibrationRenderer {
public:
    explicit CCalibrationRenderer(const tcr_calibration_renderer& r) : r_(r) {}
    uint32_t width() const override { return r_.width; }
    uint32_t height() const override { return r_.height; }
    double time_frame(const tcr::Camera& camera, const std::vector<tcr::CalibrationDraw>& draws, tcr::Representation way) override {
        const tcr_camera cam = to_c(camera);
        draws_.clear();
        for (const tcr::CalibrationDraw& d : draws) draws_.push_back(to_c(d));
        return r_.time_frame(r_.user, &cam, draws_.data(), draws_.size(), tcr_way(way));
    }
    double time_imposters(const tcr::Camera& camera, const std::vector<tcr::CalibrationCapture>& captures,
                          const std::vector<tcr::CalibrationImposter>& imposters) override {
        if (!r_.time_imposters) return -1;
        const tcr_camera cam = to_c(camera);
        captures_.clear();
        for (const tcr::CalibrationCapture& c : captures) {
            tcr_calibration_capture cc{};
            cc.slot = c.slot, cc.side = c.side, cc.grid = c.grid, cc.draw = to_c(c.draw);
            std::copy(c.view, c.view + 16, cc.view);
            std::copy(c.projection, c.projection + 16, cc.projection);
            captures_.push_back(cc);
        }
        imposters_.clear();
        for (const tcr::CalibrationImposter& q : imposters) {
            tcr_calibration_imposter cq{};
            cq.slot = q.slot, cq.meshed = q.meshed ? 1 : 0;
            std::copy(q.corners, q.corners + 12, cq.corners);
            imposters_.push_back(cq);
        }
        return r_.time_imposters(r_.user, &cam, captures_.data(), captures_.size(), imposters_.data(), imposters_.size());
    }

private:
    static tcr_camera to_c(const tcr::Camera& c) {
        tcr_camera out{};
        std::copy(c.view, c.view + 16, out.view);
        std::copy(c.projection, c.projection + 16, out.projection);
        out.viewport_width = c.viewport_width, out.viewport_height = c.viewport_height;
        return out;
    }
    static tcr_calibration_draw to_c(const tcr::CalibrationDraw& d) {
        tcr_calibration_draw out{};
        out.mesh = d.mesh, out.indices = d.indices, out.index_count = d.index_count;
        std::copy(d.model, d.model + 16, out.model);
        return out;
    }
    const tcr_calibration_renderer& r_;
    std::vector<tcr_calibration_draw> draws_;
    std::vector<tcr_calibration_capture> captures_;
    std::vector<tcr_calibration_imposter> imposters_;
};

struct tcr_governor {
    tcr_governor(tcr::Runtime& runtime, const tcr::CostModel& model, const tcr::GovernorParams& params) : governor(runtime, model, params) {}
    tcr::FrameGovernor governor;
};

namespace {

using namespace tom::capi;

// The fields both forms share, in one list: C to C++ and back
template <class A, class B, class F>
void each_coefficient(A& a, B& b, F&& f) {
    f(a.t_init_ms, b.t_init_ms), f(a.t_final_ms, b.t_final_ms), f(a.t_setup_ms, b.t_setup_ms), f(a.t_tri_ms, b.t_tri_ms);
    f(a.t_vert_ms, b.t_vert_ms), f(a.t_pix_ms, b.t_pix_ms), f(a.safety_ms, b.safety_ms), f(a.noise_rel, b.noise_rel);
    f(a.flat_t_tri_ms, b.flat_t_tri_ms), f(a.flat_t_vert_ms, b.flat_t_vert_ms), f(a.flat_t_pix_ms, b.flat_t_pix_ms);
    f(a.textured_t_tri_ms, b.textured_t_tri_ms), f(a.textured_t_vert_ms, b.textured_t_vert_ms), f(a.textured_t_pix_ms, b.textured_t_pix_ms);
    f(a.imposter_t_setup_ms, b.imposter_t_setup_ms), f(a.imposter_t_pix_ms, b.imposter_t_pix_ms), f(a.refresh_t_setup_ms, b.refresh_t_setup_ms);
    f(a.meshed_t_tri_ms, b.meshed_t_tri_ms), f(a.meshed_refresh_t_setup_ms, b.meshed_refresh_t_setup_ms);
}

tcr::CostModel to_cpp(const tcr_cost_model& c) {
    tcr::CostModel m;
    each_coefficient(m, c, [](double& to, double from) { to = from; });
    return m;
}

tcr_cost_model to_c(const tcr::CostModel& m) {
    tcr_cost_model c{};
    each_coefficient(c, m, [](double& to, double from) { to = from; });
    return c;
}

tcr::FrameParams to_cpp(const tcr_frame_params& p) {
    tcr::FrameParams f;
    std::copy(p.camera.view, p.camera.view + 16, f.camera.view);
    std::copy(p.camera.projection, p.camera.projection + 16, f.camera.projection);
    f.camera.viewport_width = p.camera.viewport_width;
    f.camera.viewport_height = p.camera.viewport_height;
    f.budget_ms = p.budget_ms;
    f.previous_frame_ms = p.previous_frame_ms;
    f.deadline_ms = p.deadline_ms;
    f.max_error_px = p.max_error_px;
    f.error_bounded = p.error_bounded != 0;
    f.hysteresis = p.hysteresis;
    return f;
}

tcr_frame_report to_c(const tcr::FrameReport& r) {
    tcr_frame_report c{};
    c.predicted_ms = r.predicted_ms;
    c.benefit = r.benefit;
    c.gap = r.gap;
    c.max_error_px = r.max_error_px;
    c.visible = r.visible;
    c.drawn = r.drawn;
    c.triangles = r.triangles;
    c.cull_ms = r.cull_ms;
    c.optimize_ms = r.optimize_ms;
    c.feasible = r.feasible ? 1 : 0;
    return c;
}

// A frame planned by the runtime or the governor (both have plan_frame(FrameParams)), its
// report converted; `function` and `what` name the call and its first argument in errors.
template <class Planner>
tom_status plan_frame(const char* function, const char* what, Planner* planner, const tcr_frame_params* params, tcr_frame_report* report) {
    if (!planner) return null_argument(function, what);
    if (!params) return null_argument(function, "params");
    return guarded([&] {
        const tcr::FrameReport& r = planner->plan_frame(to_cpp(*params));
        if (report) *report = to_c(r);
        return TOM_OK;
    });
}

bool valid_selector(tcr_selector s) { return s >= TCR_SELECTOR_STATIC && s <= TCR_SELECTOR_EXACT; }

tom_status object_out_of_range(const char* function, const tcr_runtime* rt, uint32_t id) {
    return fail(TOM_ERROR_ARGUMENT, std::string(function) + ": object " + std::to_string(id) + " of a runtime with " + std::to_string(rt->runtime.object_count()));
}

} // namespace

extern "C" {

tom_status tcr_read_cost_model(const char* path, tcr_cost_model* out) {
    if (!path) return null_argument("tcr_read_cost_model", "path");
    if (!out) return null_argument("tcr_read_cost_model", "out");
    return guarded([&] {
        *out = to_c(tcr::read_cost_model(path));
        return TOM_OK;
    });
}

void tcr_frame_params_default(tcr_frame_params* params) {
    if (!params) return;
    *params = tcr_frame_params{};
    for (int k = 0; k < 16; k += 5) params->camera.view[k] = params->camera.projection[k] = 1.0f;
    params->camera.viewport_width = params->camera.viewport_height = 1;
    params->budget_ms = tcr::FrameParams().budget_ms;
}

tom_status tcr_runtime_create(const tcr_cost_model* model, tcr_selector selector, tcr_runtime** out) {
    if (!model) return null_argument("tcr_runtime_create", "model");
    if (!out) return null_argument("tcr_runtime_create", "out");
    if (!valid_selector(selector)) return fail(TOM_ERROR_ARGUMENT, "tcr_runtime_create: selector " + std::to_string(int(selector)) + " is not one of TCR_SELECTOR_*");
    return guarded([&] {
        *out = new tcr_runtime(to_cpp(*model), tcr::SelectorKind(int(selector)));
        return TOM_OK;
    });
}

void tcr_runtime_destroy(tcr_runtime* runtime) { delete runtime; }

tom_status tcr_runtime_add_object(tcr_runtime* runtime, const tom_mesh_view* mesh, const float transform[16], float weight, uint32_t* id) {
    if (!runtime) return null_argument("tcr_runtime_add_object", "runtime");
    const tom::MeshView* v = view_of(mesh);
    if (!v) return null_argument("tcr_runtime_add_object", "mesh");
    if (!transform) return null_argument("tcr_runtime_add_object", "transform");
    if (!(weight > 0)) return fail(TOM_ERROR_ARGUMENT, "tcr_runtime_add_object: weight " + std::to_string(weight) + " is not positive");
    return guarded([&] {
        const uint32_t added = runtime->runtime.add_object(*v, transform, weight);
        if (id) *id = added;
        return TOM_OK;
    });
}

tom_status tcr_runtime_set_transform(tcr_runtime* runtime, uint32_t id, const float transform[16]) {
    if (!runtime) return null_argument("tcr_runtime_set_transform", "runtime");
    if (!transform) return null_argument("tcr_runtime_set_transform", "transform");
    if (id >= runtime->runtime.object_count()) return object_out_of_range("tcr_runtime_set_transform", runtime, id);
    runtime->runtime.set_transform(id, transform);
    return TOM_OK;
}

uint32_t tcr_runtime_object_count(const tcr_runtime* runtime) { return runtime ? uint32_t(runtime->runtime.object_count()) : 0; }

tom_status tcr_runtime_plan_frame(tcr_runtime* runtime, const tcr_frame_params* params, tcr_frame_report* report) {
    return plan_frame("tcr_runtime_plan_frame", "runtime", runtime ? &runtime->runtime : nullptr, params, report);
}

tom_status tcr_runtime_object(const tcr_runtime* runtime, uint32_t id, tcr_object_result* out) {
    if (!runtime) return null_argument("tcr_runtime_object", "runtime");
    if (!out) return null_argument("tcr_runtime_object", "out");
    if (id >= runtime->runtime.object_count()) return object_out_of_range("tcr_runtime_object", runtime, id);
    const tcr::ObjectResult& o = runtime->runtime.object(id);
    *out = tcr_object_result{o.visible ? 1 : 0, o.drawn ? 1 : 0, o.vertices, o.triangles, o.coverage_px, o.error_px, o.predicted_ms};
    return TOM_OK;
}

tom_status tcr_runtime_indices_u32(const tcr_runtime* runtime, uint32_t id, uint32_t* out, size_t capacity, tom_extracted* result) {
    if (!runtime) return null_argument("tcr_runtime_indices_u32", "runtime");
    if (!out && capacity > 0) return null_argument("tcr_runtime_indices_u32", "out");
    if (!result) return null_argument("tcr_runtime_indices_u32", "result");
    if (id >= runtime->runtime.object_count()) return object_out_of_range("tcr_runtime_indices_u32", runtime, id);
    const tcr::ObjectResult& o = runtime->runtime.object(id);
    if (o.drawn && capacity / 3 < o.triangles)
        return fail(TOM_ERROR_CAPACITY, "tcr_runtime_indices_u32: object " + std::to_string(id) + " draws " + std::to_string(o.triangles) +
                                            " triangles, the buffer holds " + std::to_string(capacity) + " indices");
    const tom::Extracted e = runtime->runtime.indices(id, out, capacity);
    *result = tom_extracted{e.vertex_count, e.triangle_count};
    return TOM_OK;
}

void tcr_governor_params_default(tcr_governor_params* params) {
    if (!params) return;
    const tcr::GovernorParams g;
    *params = tcr_governor_params{g.budget_ms, g.safety_sigma, g.follow_noise ? 1 : 0, g.optimize_share, g.warm_up_frames};
}

tom_status tcr_governor_create(tcr_runtime* runtime, const tcr_cost_model* calibrated, const tcr_governor_params* params, tcr_governor** out) {
    if (!runtime) return null_argument("tcr_governor_create", "runtime");
    if (!calibrated) return null_argument("tcr_governor_create", "calibrated");
    if (!params) return null_argument("tcr_governor_create", "params");
    if (!out) return null_argument("tcr_governor_create", "out");
    if (!(params->budget_ms > 0)) return fail(TOM_ERROR_ARGUMENT, "tcr_governor_create: budget_ms " + std::to_string(params->budget_ms) + " is not positive");
    return guarded([&] {
        tcr::GovernorParams g;
        g.budget_ms = params->budget_ms;
        g.safety_sigma = params->safety_sigma;
        g.follow_noise = params->follow_noise != 0;
        g.optimize_share = params->optimize_share;
        g.warm_up_frames = params->warm_up_frames;
        *out = new tcr_governor(runtime->runtime, to_cpp(*calibrated), g);
        return TOM_OK;
    });
}

void tcr_governor_destroy(tcr_governor* governor) { delete governor; }

tom_status tcr_governor_plan_frame(tcr_governor* governor, const tcr_frame_params* params, tcr_frame_report* report) {
    return plan_frame("tcr_governor_plan_frame", "governor", governor ? &governor->governor : nullptr, params, report);
}

tom_status tcr_governor_frame_done(tcr_governor* governor, double extract_ms, double render_ms, double frame_ms) {
    if (!governor) return null_argument("tcr_governor_frame_done", "governor");
    if (!(extract_ms >= 0) || !(render_ms >= 0))
        return fail(TOM_ERROR_ARGUMENT, "tcr_governor_frame_done: times must be >= 0 (extract " + std::to_string(extract_ms) + ", render " + std::to_string(render_ms) + ")");
    governor->governor.frame_done({extract_ms, render_ms, frame_ms});
    return TOM_OK;
}

int tcr_governor_warming_up(const tcr_governor* governor) { return governor && governor->governor.warming_up() ? 1 : 0; }

double tcr_governor_planning_reserve_ms(const tcr_governor* governor) { return governor ? governor->governor.planning_reserve_ms() : 0.0; }

tom_status tcr_governor_model(const tcr_governor* governor, tcr_cost_model* out) {
    if (!governor) return null_argument("tcr_governor_model", "governor");
    if (!out) return null_argument("tcr_governor_model", "out");
    *out = to_c(governor->governor.model());
    return TOM_OK;
}

} // extern "C"

tom_status tcr_calibrate(const tcr_calibration_renderer* renderer, const tom_mesh_view* const* meshes, size_t mesh_count, const char* path,
                         tcr_cost_model* out) {
    if (!renderer || !renderer->time_frame) return null_argument("tcr_calibrate", "renderer");
    if (!meshes && mesh_count) return null_argument("tcr_calibrate", "meshes");
    if (!out) return null_argument("tcr_calibrate", "out");
    return guarded([&] {
        std::vector<const tom::MeshView*> views;
        for (size_t k = 0; k < mesh_count; ++k) views.push_back(view_of(meshes[k]));
        CCalibrationRenderer timer(*renderer);
        tcr::CalibrationParams params;
        if (path) params.path = path, params.comment = "tcr_calibrate";
        *out = to_c(tcr::calibrate(timer, views, params).model);
        return TOM_OK;
    });
}
