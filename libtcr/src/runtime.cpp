// The per-frame pipeline of time-critical rendering (Gobbetti & Bouvier 1999, section 3): cull
// and measure every object, build the frame's optimisation problem from the cost model and the
// benefit heuristics, select, round to the TOM resolutions, predict.
//
// References: T. Funkhouser, C. Sequin (1993) for the benefit factors (size, focus, motion,
// hysteresis) and the cost model; W. Pasman, F. Jansen (2003) for D = k / N and the angular
// error 2 k arctan(r / d) / N used when a mesh has no stored curve.

#include "tcr/runtime.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "tom/error_curve.h"

namespace tcr {

namespace {

int m_index(double m) { return m == 0.5 ? 0 : (m == 2.0 ? 2 : 1); }

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double scale_of(const float t[16]) {
    // the largest column length of the upper 3x3: the transform's scale on the diagonal
    double s = 0;
    for (int c = 0; c < 3; ++c) s = std::max(s, std::sqrt(double(t[c * 4]) * t[c * 4] + double(t[c * 4 + 1]) * t[c * 4 + 1] + double(t[c * 4 + 2]) * t[c * 4 + 2]));
    return s;
}

} // namespace

Runtime::Runtime(const CostModel& model, SelectorKind selector) : model_(model), selector_(selector) {}

uint32_t Runtime::add_object(const tom::MeshView& mesh, const float transform[16], float weight) {
    Object o;
    o.mesh = &mesh;
    std::copy(transform, transform + 16, o.transform);
    o.weight = weight;
    for (int k = 0; k < 3; ++k) o.box.min[k] = mesh.bounds_min[k], o.box.max[k] = mesh.bounds_max[k];
    o.triangles = mesh.triangle_count;
    o.min_triangles = std::max<uint32_t>(1, tom::active_triangle_count(mesh, mesh.min_vertex_count));
    o.vertices_per_triangle = mesh.triangle_count ? double(mesh.vertex_count) / double(mesh.triangle_count) : 0.5;
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += double(o.box.max[k] - o.box.min[k]) * (o.box.max[k] - o.box.min[k]);
    o.diagonal = std::sqrt(d2);
    o.has_curve = false;
    for (double& c : o.c_by_m) c = 0;
    if (const std::optional<tom::ErrorCurve> curve = tom::read_error_curve(mesh)) {
        // the relative error constant c of D = c n^-m for each exponent, least squares in log space
        const double ms[3] = {0.5, 1.0, 2.0};
        for (int j = 0; j < 3; ++j) {
            double sum = 0;
            int count = 0;
            for (const tom::ErrorCurvePoint& p : curve->points)
                if (p.mean > 0 && p.triangles > 0 && p.triangles < mesh.triangle_count) {
                    sum += std::log(double(p.mean)) + ms[j] * std::log(double(p.triangles));
                    ++count;
                }
            o.c_by_m[j] = count ? std::exp(sum / count) : 0.0;
        }
        for (const tom::ErrorCurvePoint& p : curve->points) {
            o.curve_tris.push_back(p.triangles);
            o.curve_error.push_back(p.mean);
        }
        o.has_curve = o.c_by_m[1] > 0;
    }
    objects_.push_back(std::move(o));
    results_.emplace_back();
    return uint32_t(objects_.size() - 1);
}

void Runtime::set_transform(uint32_t id, const float transform[16]) noexcept { std::copy(transform, transform + 16, objects_[id].transform); }
void Runtime::set_weight(uint32_t id, float weight) noexcept { objects_[id].weight = weight; }

double Runtime::c_for(const Object& o, double m, double fixed_c) const noexcept { return o.has_curve ? o.c_by_m[m_index(m)] : fixed_c; }

double Runtime::error_px(uint32_t id, double triangles, double m) const noexcept {
    const Object& o = objects_[id];
    return c_for(o, m, last_fixed_c_) * std::pow(std::max(1.0, triangles), -m) * results_[id].size_px;
}

// Pasman & Jansen's angular error 2 k arctan(r / d) / N, in pixels, is k_px / N with this k_px.
double Runtime::pasman_k_px(const Object& o, const ObjectResult& r) const noexcept {
    const float* P = last_camera_.projection;
    const double fov = P[5] != 0 ? 2.0 * std::atan(1.0 / P[5]) : 1.0;
    const double radians_per_px = fov / std::max<uint32_t>(1, last_camera_.viewport_height);
    const double radius = 0.5 * o.diagonal * scale_of(o.transform);
    const double d = std::max(r.distance, 1e-6f);
    return 2.0 * last_fixed_c_ * std::atan(radius / d) / radians_per_px;
}

double Runtime::projected_error_px(const Object& o, const ObjectResult& r, double n) const noexcept {
    n = std::max(n, 1.0);
    if (!o.has_curve) return pasman_k_px(o, r) / n;
    // the stored curve, interpolated log-log, k / N beyond its points, scaled to the projected size
    const std::vector<double>& t = o.curve_tris;
    const std::vector<double>& e = o.curve_error;
    size_t hi = 0;
    while (hi < t.size() && t[hi] < n) ++hi;
    double rel;
    if (hi == 0)
        rel = e.empty() ? 0.0 : e[0] * t[0] / n;
    else if (hi == t.size())
        rel = e.back() * t.back() / n;
    else if (e[hi - 1] > 0 && e[hi] > 0 && t[hi] > t[hi - 1])
        rel = std::exp(std::log(e[hi - 1]) + (std::log(n) - std::log(t[hi - 1])) / (std::log(t[hi]) - std::log(t[hi - 1])) * (std::log(e[hi]) - std::log(e[hi - 1])));
    else
        rel = e[hi];
    return rel * r.size_px;
}

double Runtime::triangles_for_error(uint32_t id, double max_error_px) const noexcept {
    const Object& o = objects_[id];
    const ObjectResult& r = results_[id];
    if (!(max_error_px > 0)) return o.triangles;
    if (!o.has_curve) return std::min(o.triangles, std::max(o.min_triangles, std::ceil(pasman_k_px(o, r) / max_error_px)));
    // bisection in log n over the interpolated curve
    double lo = o.min_triangles, hi = o.triangles;
    if (projected_error_px(o, r, lo) <= max_error_px) return lo;
    for (int it = 0; it < 40; ++it) {
        const double mid = std::sqrt(lo * hi);
        (projected_error_px(o, r, mid) <= max_error_px ? hi : lo) = mid;
    }
    return std::min(o.triangles, std::ceil(hi));
}

uint32_t Runtime::resolution_for(const Object& o, double triangles) const noexcept {
    // the finest resolution with at most `triangles` active triangles (never below the coarsest)
    const tom::MeshView& m = *o.mesh;
    const uint32_t target = uint32_t(std::max(0.0, std::floor(triangles + 1e-9)));
    uint32_t v = tom::vertex_count_for_triangles(m, target);
    if (v > m.min_vertex_count && tom::active_triangle_count(m, v) > target) --v;
    return v;
}

const FrameReport& Runtime::plan_frame(const FrameParams& params) {
    const auto start = std::chrono::steady_clock::now();
    last_camera_ = params.camera;
    last_fixed_c_ = params.fixed_c;
    report_ = FrameReport();
    visible_ids_.clear();
    for (uint32_t id = 0; id < objects_.size(); ++id) {
        Object& o = objects_[id];
        ObjectResult& r = results_[id];
        const double previous = r.drawn ? r.triangles : 0.0;
        const Projection p = project_box(params.camera, o.transform, o.box, params.focus_weight);
        r = ObjectResult();
        r.triangles = uint32_t(previous);  // kept for the problem's "previous" until replaced below
        r.visible = p.visible;
        if (!p.visible) {
            o.last_x = o.last_y = -1;
            continue;
        }
        r.coverage_px = p.coverage_px;
        r.inside_share = p.inside_share;
        r.size_px = p.size_px;
        r.focus = p.focus;
        r.distance = p.distance;
        double motion = 1.0;
        if (params.use_motion && o.last_x >= 0) motion = motion_factor(std::hypot(p.center_x - o.last_x, p.center_y - o.last_y));
        o.last_x = p.center_x, o.last_y = p.center_y;
        r.importance = double(p.coverage_px) * p.focus * o.weight * motion;
        visible_ids_.push_back(id);
        report_.visible_triangles += uint64_t(o.triangles);
    }
    report_.cull_ms = 1e3 * seconds_since(start);
    const auto optimize_start = std::chrono::steady_clock::now();
    const size_t n = visible_ids_.size();
    problem_.resize(n);
    coverage_.resize(n);
    problem_.m = params.m;
    // model correction from the last frame's measurement (objects' part only): the last
    // prediction already carried the correction, so measured / predicted is the residual and
    // correction x residual the factor the calibrated model should have had
    if (params.correct_model && params.previous_frame_ms > 0 && last_predicted_ms_ > model_.frame_fixed_ms()) {
        const double residual = (params.previous_frame_ms - model_.frame_fixed_ms() + model_.safety_ms) / (last_predicted_ms_ - model_.frame_fixed_ms());
        if (std::isfinite(residual) && residual > 0)
            correction_ = std::min(2.0, std::max(0.5, 0.7 * correction_ + 0.3 * correction_ * residual));
    }
    if (!params.correct_model) correction_ = 1.0;
    report_.correction = correction_;
    problem_.budget_ms = (params.budget_ms - model_.frame_fixed_ms()) / correction_;
    for (size_t k = 0; k < n; ++k) {
        const uint32_t id = visible_ids_[k];
        const Object& o = objects_[id];
        const ObjectResult& r = results_[id];
        // per triangle, of the share inside the frustum (CostModel::object_ms)
        const double a = (model_.t_tri_ms + model_.t_vert_ms * o.vertices_per_triangle) * r.inside_share;
        const double fill_ms = model_.t_pix_ms * r.coverage_px;
        double hi = o.triangles;
        if (params.max_error_px > 0) hi = std::max(o.min_triangles, std::min(hi, triangles_for_error(id, params.max_error_px)));
        const double r_min = a > 0 ? fill_ms / a : 0.0;  // fewer triangles than this save no time
        double lo = std::min(hi, std::max(o.min_triangles, r_min));
        problem_.importance[k] = r.importance;
        problem_.error[k] = r.importance * c_for(o, params.m, params.fixed_c) * r.size_px;
        problem_.per_tri_ms[k] = std::max(a, 1e-12);
        // cost s + max(a n, fill): on [lo, hi] it is s + a n, unless the object is fill bound
        // even at full resolution (lo = hi), where the fill time is folded into the setup
        problem_.setup_ms[k] = model_.t_setup_ms * double(tom::part_count(*o.mesh)) + std::max(0.0, fill_ms - a * lo);
        problem_.lo[k] = lo;
        problem_.hi[k] = hi;
        problem_.previous[k] = r.triangles > 0 ? std::min(hi, std::max(lo, double(r.triangles))) : 0.0;
        coverage_[k] = r.coverage_px;
    }
    stress_ = update_stress(stress_, params.previous_frame_ms, params.budget_ms);
    report_.stress = stress_;
    if (params.error_bounded) {
        plan_.triangles.resize(n);
        plan_.drawn.assign(n, 1);
        for (size_t k = 0; k < n; ++k) plan_.triangles[k] = problem_.hi[k];  // hi is the error bound's resolution
        plan_.cost_ms = plan_.benefit = 0;
        for (size_t k = 0; k < n; ++k) {
            plan_.cost_ms += problem_.cost(k, plan_.triangles[k]);
            plan_.benefit += problem_.benefit(k, plan_.triangles[k]);
        }
        plan_.feasible = plan_.cost_ms <= problem_.budget_ms;
        plan_.upper_bound = plan_.gap = std::numeric_limits<double>::quiet_NaN();
        plan_.iterations = 0;
        plan_.deadline_hit = false;
    } else {
        SelectParams sp;
        sp.policy = params.policy;
        sp.deadline_ms = params.deadline_ms;
        sp.hysteresis = params.hysteresis;
        sp.triangles_per_pixel = params.triangles_per_pixel;
        sp.coverage_px = coverage_.data();
        sp.stress = stress_;
        select(selector_, problem_, sp, plan_);
    }
    // round down to the TOM resolutions and predict with the real vertex counts
    // (the finest resolution with at most `triangles`; returns its predicted time)
    auto choose = [&](const Object& o, ObjectResult& r, double triangles) {
        r.vertices = resolution_for(o, triangles);
        r.triangles = tom::active_triangle_count(*o.mesh, r.vertices);
        r.predicted_ms = correction_ * model_.object_ms(r.triangles, r.vertices, r.coverage_px, r.inside_share, double(tom::part_count(*o.mesh)));
        r.error_px = projected_error_px(o, r, r.triangles);
        return r.predicted_ms;
    };
    double predicted = model_.frame_fixed_ms();
    for (size_t k = 0; k < n; ++k) {
        const uint32_t id = visible_ids_[k];
        ObjectResult& r = results_[id];
        r.drawn = plan_.drawn[k] != 0;
        r.triangles = 0;
        if (r.drawn) predicted += choose(objects_[id], r, plan_.triangles[k]);
    }
    // vertex counts are exact here and were estimated in the problem: step down if that tipped
    // a feasible plan over the budget
    for (int round = 0; round < 8 && plan_.feasible && predicted > params.budget_ms && !params.error_bounded; ++round) {
        const double factor = std::max(0.5, 1.0 - (predicted - params.budget_ms) / std::max(predicted - model_.frame_fixed_ms(), 1e-12) - 0.01);
        predicted = model_.frame_fixed_ms();
        for (size_t k = 0; k < n; ++k) {
            ObjectResult& r = results_[visible_ids_[k]];
            if (r.drawn) predicted += choose(objects_[visible_ids_[k]], r, std::max(problem_.lo[k], r.triangles * factor));
        }
    }
    for (size_t k = 0; k < n; ++k) {
        const ObjectResult& r = results_[visible_ids_[k]];
        if (!r.drawn) continue;
        ++report_.drawn;
        report_.triangles += r.triangles;
        report_.max_error_px = std::max(report_.max_error_px, r.error_px);
    }
    report_.visible = uint32_t(n);
    report_.predicted_ms = predicted;
    last_predicted_ms_ = predicted;
    report_.benefit = plan_.benefit;
    report_.upper_bound = plan_.upper_bound;
    report_.gap = plan_.gap;
    report_.feasible = plan_.feasible && predicted <= params.budget_ms * (1 + 1e-9);
    report_.deadline_hit = plan_.deadline_hit;
    report_.iterations = plan_.iterations;
    report_.optimize_ms = 1e3 * seconds_since(optimize_start);
    return report_;
}

tom::Extracted Runtime::indices(uint32_t id, uint32_t* destination, size_t capacity) const noexcept {
    const ObjectResult& r = results_[id];
    if (!r.drawn) return {};
    return tom::extract(*objects_[id].mesh, r.vertices, destination, capacity);
}

tom::Extracted Runtime::indices(uint32_t id, uint32_t* destination, size_t capacity, tom::PartDraw* draws) const noexcept {
    const ObjectResult& r = results_[id];
    const uint32_t parts = tom::part_count(*objects_[id].mesh);
    if (!r.drawn) {
        for (uint32_t p = 0; p < parts; ++p) draws[p] = {0, 0, tom::part_at(*objects_[id].mesh, p).material};
        return {};
    }
    return tom::extract_parts(*objects_[id].mesh, r.vertices, destination, capacity, draws);
}

tom::Extracted Runtime::indices(uint32_t id, uint16_t* destination, size_t capacity) const noexcept {
    const ObjectResult& r = results_[id];
    if (!r.drawn) return {};
    return tom::extract(*objects_[id].mesh, r.vertices, destination, capacity);
}

} // namespace tcr
