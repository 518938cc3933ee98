// The per-frame pipeline of time-critical rendering (Gobbetti & Bouvier 1999, section 3): cull
// and measure every object, build the frame's optimisation problem from the cost model and the
// benefit heuristics, select, round to the TOM resolutions, predict.
//
// References: T. Funkhouser, C. Sequin (1993) for the benefit factors (size, focus, motion,
// hysteresis) and the cost model; W. Pasman, F. Jansen (2003) for D = k / N and the angular
// error 2 k arctan(r / d) / N used when a mesh has no stored curve.

#include "tcr/runtime.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <limits>

#include "tcr/imposters.h"
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

// The eye of a world -> eye transform: -R^T t.
void eye_of(const float view[16], double eye[3]) {
    for (int k = 0; k < 3; ++k) eye[k] = -(double(view[k * 4]) * view[12] + double(view[k * 4 + 1]) * view[13] + double(view[k * 4 + 2]) * view[14]);
}

// The object's bounding sphere in world space: the box centre transformed, half the diagonal scaled.
void world_sphere(const float t[16], const Box& box, double diagonal, double centre[3], double& radius) {
    double c[3];
    for (int k = 0; k < 3; ++k) c[k] = 0.5 * (double(box.min[k]) + box.max[k]);
    for (int k = 0; k < 3; ++k) centre[k] = t[k] * c[0] + t[4 + k] * c[1] + t[8 + k] * c[2] + t[12 + k];
    radius = 0.5 * diagonal * scale_of(t);
}

double distance3(const double a[3], const double b[3]) { return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2])); }

// Seconds between frames for the viewer's speed and the captures' lifetimes: given, or the budget.
double frame_interval_s(const FrameParams& params) { return params.menu.frame_interval_s > 0 ? params.menu.frame_interval_s : 1e-3 * params.budget_ms; }

uint32_t power_of_two_at_least(double x, uint32_t lo, uint32_t hi) {
    uint32_t side = lo;
    while (side < hi && double(side) < x) side *= 2;
    return side;
}

} // namespace

const char* representation_name(Representation r) noexcept {
    switch (r) {
    case Representation::smooth: return "smooth";
    case Representation::flat: return "flat";
    case Representation::simple_imposter: return "imposter";
    case Representation::meshed_imposter: return "meshed";
    case Representation::textured: return "textured";
    }
    return "?";
}

void imposter_camera(const ImposterState& s, float view[16], float projection[16]) noexcept {
    double dir[3], d = 0;
    for (int k = 0; k < 3; ++k) dir[k] = double(s.centre[k]) - s.eye[k], d += dir[k] * dir[k];
    d = std::sqrt(std::max(d, 1e-30));
    const float up_y[3] = {0, 1, 0}, up_x[3] = {1, 0, 0};
    look_at(s.eye, s.centre, std::abs(dir[1]) > 0.99 * d ? up_x : up_y, view);  // an up not along the view
    const double half = std::asin(std::min(0.999, double(s.radius) / d));
    perspective(float(2.0 * half), 1.0f, float(std::max(d - s.radius, 1e-3 * d)), float(d + s.radius), projection);
}

void imposter_quad(const ImposterState& s, float corners[12]) noexcept {
    float view[16], projection[16];
    imposter_camera(s, view, projection);
    // the frustum's half side at the centre's distance: d tan(half angle) = 1 / P[5] x d
    double d = 0;
    for (int k = 0; k < 3; ++k) d += (double(s.centre[k]) - s.eye[k]) * (double(s.centre[k]) - s.eye[k]);
    const double h = std::sqrt(d) / double(projection[5]);
    const double right[3] = {view[0], view[4], view[8]}, up[3] = {view[1], view[5], view[9]};
    const double su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
    for (int c = 0; c < 4; ++c)
        for (int k = 0; k < 3; ++k) corners[3 * c + k] = float(s.centre[k] + h * (su[c] * right[k] + sv[c] * up[k]));
}

void depth_mesh(const float view[16], const float projection[16], const float* depth, uint32_t side, uint32_t grid, float* positions) noexcept {
    // eye-space depth from window depth: z_ndc = 2 depth - 1, z_eye = -P[14] / (z_ndc + P[10]);
    // the capture's centre lies on its axis halfway between the near and far planes' distances
    const double near = double(projection[14]) / (double(projection[10]) - 1.0), far = double(projection[14]) / (double(projection[10]) + 1.0);
    const double centre = 0.5 * (near + far);
    const double right[3] = {view[0], view[4], view[8]}, up[3] = {view[1], view[5], view[9]}, back[3] = {view[2], view[6], view[10]};
    double eye[3];
    eye_of(view, eye);
    if (grid == 0) {  // one vertex: the capture's centre
        for (int k = 0; k < 3; ++k) positions[k] = float(eye[k] - centre * back[k]);
        return;
    }
    const double cell = double(side) / grid;
    for (uint32_t j = 0; j <= grid; ++j)
        for (uint32_t i = 0; i <= grid; ++i) {
            // the object texel nearest the vertex in the image, within one cell (the nearer depth on a tie)
            const auto lo = [&](uint32_t v) { return uint32_t(std::max(0.0, std::floor((double(v) - 1.0) * cell))); };
            const auto hi = [&](uint32_t v) { return uint32_t(std::min(double(side), std::ceil((double(v) + 1.0) * cell))); };
            float nearest = 1.0f;
            double best = INFINITY;
            for (uint32_t y = lo(j); y < hi(j); ++y)
                for (uint32_t x = lo(i); x < hi(i); ++x) {
                    const float z = depth[size_t(y) * side + x];
                    if (z >= 1.0f) continue;
                    const double dx = x + 0.5 - i * cell, dy = y + 0.5 - j * cell, d2 = dx * dx + dy * dy;
                    if (d2 < best || (d2 == best && z < nearest)) best = d2, nearest = z;
                }
            double distance = centre;  // no object texel near: the simple imposter's plane
            if (nearest < 1.0f) distance = double(projection[14]) / (2.0 * nearest - 1.0 + double(projection[10]));
            const double x_ndc = 2.0 * i / grid - 1.0, y_ndc = 2.0 * j / grid - 1.0;
            const double xe = x_ndc * distance / projection[0], ye = y_ndc * distance / projection[5];
            float* out = positions + 3 * (size_t(j) * (grid + 1) + i);
            for (int k = 0; k < 3; ++k) out[k] = float(eye[k] + xe * right[k] + ye * up[k] - distance * back[k]);
        }
}

Runtime::Runtime(const CostModel& model, SelectorKind selector) : model_(model), selector_(selector) {}

uint32_t Runtime::add_object(const tom::MeshView& mesh, const float transform[16], float weight, tom::Floor floor) {
    Object o;
    o.mesh = &mesh;
    o.min_vertices = tom::floor_vertex_count(mesh, floor);
    std::copy(transform, transform + 16, o.transform);
    o.weight = weight;
    for (int k = 0; k < 3; ++k) o.box.min[k] = mesh.bounds_min[k], o.box.max[k] = mesh.bounds_max[k];
    o.triangles = mesh.triangle_count;
    o.min_triangles = std::max<uint32_t>(1, tom::active_triangle_count(mesh, o.min_vertices));
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

void Runtime::set_transform(uint32_t id, const float transform[16]) noexcept {
    assert(id < objects_.size() && "Runtime::set_transform: \\pre id < object_count()");
    Object& o = objects_[id];
    if (!std::equal(transform, transform + 16, o.transform)) o.imposter.valid = false;  // a capture of where it was
    std::copy(transform, transform + 16, o.transform);
}
void Runtime::set_weight(uint32_t id, float weight) noexcept {
    assert(id < objects_.size() && "Runtime::set_weight: \\pre id < object_count()");
    objects_[id].weight = weight;
}

void Runtime::clear_imposters() noexcept {
    for (Object& o : objects_) o.imposter = ImposterState();
}

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
    // bisection in log n over the interpolated curve, to a triangle or 0.05% (hi always meets the bound)
    double lo = o.min_triangles, hi = o.triangles;
    if (projected_error_px(o, r, lo) <= max_error_px) return lo;
    for (int it = 0; it < 40 && hi - lo > 0.5 && hi > lo * 1.0005; ++it) {
        const double mid = std::sqrt(lo * hi);
        (projected_error_px(o, r, mid) <= max_error_px ? hi : lo) = mid;
    }
    return std::min(o.triangles, std::ceil(hi));
}

uint32_t Runtime::resolution_for(const Object& o, double triangles) const noexcept {
    // the finest resolution with at most `triangles` active triangles (never below the floor)
    const tom::MeshView& m = *o.mesh;
    const uint32_t target = uint32_t(std::max(0.0, std::floor(triangles + 1e-9)));
    uint32_t v = std::max(o.min_vertices, tom::vertex_count_for_triangles(m, target, tom::Floor::coarsest));
    if (v > o.min_vertices && tom::active_triangle_count(m, v) > target) --v;
    return v;
}

// Object k's ways beyond way 0 (the levels, smooth-shaded, already in problem_): the levels
// flat-shaded; its imposter as captured, while the capture's distortion from here is within the
// bound; a new capture from here. An imposter's benefit is that of its projected error: the
// captured level's, the distortion (Pasman & Jansen 4.3) and the texture's magnification; a
// refresh costs its render into the texture spread over the capture's expected lifetime
// (section 5.2 at the viewer's speed), and the whole of it in the frame's prediction.
void Runtime::add_ways(uint32_t id, size_t k, const FrameParams& params, double radians_per_px) {
    const Object& o = objects_[id];
    const ObjectResult& r = results_[id];
    const Menu& menu = params.menu;
    const double I = problem_.importance[k];
    const uint32_t parts = tom::part_count(*o.mesh);
    const Representation previous = r.representation;
    uint32_t previous_way = 0;
    auto push = [&](const Way& w, WayKind kind) {
        problem_.ways.push_back(w);
        way_kinds_.push_back(kind);
        const uint32_t j = uint32_t(problem_.ways.size() - problem_.way_begin[k]);
        if (previous == kind.representation && (previous_way == 0 || !kind.refresh)) previous_way = j;
    };
    // the levels under another rendering algorithm: its coefficients, its error factor
    auto level_way = [&](double t_tri, double t_vert, double t_pix, double error_factor) {
        Way w;
        w.m = problem_.m;
        w.per_tri_ms = std::max(1e-12, (t_tri + t_vert * o.vertices_per_triangle) * r.inside_share);
        const double fill = t_pix * r.coverage_px;
        w.hi = problem_.hi[k];
        w.lo = std::min(w.hi, std::max(o.min_triangles, fill / w.per_tri_ms));
        w.setup_ms = model_.t_setup_ms * parts + std::max(0.0, fill - w.per_tri_ms * w.lo);
        w.error = problem_.error[k] * error_factor;
        return w;
    };
    if (menu.flat && model_.has_flat()) {
        const Way w = level_way(model_.flat_t_tri_ms, model_.flat_t_vert_ms, model_.flat_t_pix_ms, menu.flat_error_factor);
        if (!dominated_by_smooth(w, k)) push(w, {Representation::flat, false, 0, 0, 0});
    }
    if (menu.textured && o.textured && model_.has_textured())
        push(level_way(model_.textured_t_tri_ms, model_.textured_t_vert_ms, model_.textured_t_pix_ms, menu.textured_error_factor), {Representation::textured, false, 0, 0, 0});
    double centre[3], radius;
    world_sphere(o.transform, o.box, o.diagonal, centre, radius);
    const double from_centre = distance3(eye_, centre);
    if (menu.imposters && model_.has_imposters() && radius > 0 && from_centre > menu.min_distance_radii * radius && r.size_px >= 2) {
        const bool meshed = menu.meshed && menu.meshed_grid > 0 && model_.has_meshed();
        // an imposter draws n triangles (its quad, 2, or its depth mesh): A n^-m at that n is I e
        auto imposter_way = [&](double n, double cost_ms, double error_px) {
            Way w;
            w.m = problem_.m;
            w.lo = w.hi = n;
            w.per_tri_ms = 1e-12;
            w.setup_ms = std::max(0.0, cost_ms - 1e-12 * n);
            w.error = I * menu.imposter_error_factor * error_px * std::pow(n, problem_.m);
            return w;
        };
        auto mesh_triangles = [](uint32_t grid) { return grid ? 2.0 * grid * grid : 2.0; };
        auto draw_ms = [&](uint32_t grid) { return grid ? model_.meshed_ms(r.coverage_px, mesh_triangles(grid)) : model_.imposter_ms(r.coverage_px); };
        const double needed_px = 2.0 * std::asin(std::min(1.0, radius / from_centre)) / radians_per_px;  // the sphere's angular diameter
        imposters::Capture capture;
        capture.radius = radius;
        capture.k = menu.meshed_k;
        for (int c = 0; c < 3; ++c) capture.eye[c] = eye_[c], capture.centre[c] = centre[c];
        auto as_method = [&](imposters::Capture c, uint32_t grid) {
            c.method = grid ? imposters::Method::meshed_imposter : imposters::Method::simple_imposter;
            c.polygons = mesh_triangles(grid);
            return c;
        };
        const double bound_rad = menu.imposter_max_px * radians_per_px;
        // a capture is renewed once it breaks the bound (its distortion, or its level's error and
        // its texels' magnification as the object comes nearer), not sooner: the refresh's cost
        // is spread over a lifetime that a renewal within the bound would cut short, again and
        // again (Schaufler, Pasman)
        bool renew = true;
        const ImposterState& kept = o.imposter;
        if (kept.valid && (kept.grid == 0 || meshed)) {
            imposters::Capture old = as_method(capture, kept.grid);
            for (int c = 0; c < 3; ++c) old.eye[c] = kept.eye[c];
            const double distortion_px = imposters::distortion_from(old, eye_) / radians_per_px;
            if (distortion_px <= menu.imposter_max_px) {
                const double level_px = projected_error_px(o, r, kept.triangles);
                const double magnified_px = 0.5 * std::max(0.0, needed_px / kept.texture_px - 1.0);
                const double e = level_px + distortion_px + magnified_px;
                const Representation rep = kept.grid ? Representation::meshed_imposter : Representation::simple_imposter;
                push(imposter_way(mesh_triangles(kept.grid), draw_ms(kept.grid), e), {rep, false, e, kept.texture_px, kept.vertices, kept.grid});
                renew = level_px + magnified_px > menu.imposter_max_px;  // the object came nearer
            }
        }
        if (renew) {
            // a new capture from here: the level of capture_error_px (found again when the projected
            // size has changed by 10%: its error by as much), a texture holding the sphere
            Object& mo = objects_[id];
            if (mo.capture_error_px != menu.capture_error_px || std::abs(r.size_px - mo.capture_size_px) > 0.1 * mo.capture_size_px) {
                mo.capture_error_px = menu.capture_error_px;
                mo.capture_size_px = r.size_px;
                mo.capture_vertices = resolution_for(o, triangles_for_error(id, menu.capture_error_px));
                mo.capture_triangles = tom::active_triangle_count(*o.mesh, mo.capture_vertices);
            }
            const uint32_t vertices = mo.capture_vertices, triangles = mo.capture_triangles;
            const uint32_t side = power_of_two_at_least(needed_px, menu.texture_min, menu.texture_max);
            const double refresh_ms = model_.refresh_ms(triangles, vertices, double(side) * side, parts, o.textured);  // a textured object is captured texture-mapped
            const double d = from_centre - radius;
            const uint32_t grid = meshed ? menu.meshed_grid : 0;
            if (mo.lifetime_distance < 0 || std::abs(d - mo.lifetime_distance) > 0.1 * d || mo.lifetime_grid != grid) {  // Pasman's lifetime changes slowly with distance
                mo.lifetime_distance = d;
                mo.lifetime_grid = grid;
                for (int method = 0; method < (meshed ? 2 : 1); ++method)  // at 1 m/s: the walk
                    mo.lifetime_m[method] = imposters::lifetime(as_method(capture, method ? grid : 0), d, bound_rad, 1.0, (menu.min_distance_radii - 1.0) * radius);
            }
            const double e = projected_error_px(o, r, triangles) + 0.5 * std::max(0.0, needed_px / side - 1.0);
            for (int method = 0; method < (meshed ? 2 : 1); ++method) {
                const uint32_t g = method ? grid : 0;
                const double lifetime_s = speed_ > 0 ? mo.lifetime_m[method] / speed_ : INFINITY;
                const double frames = std::max(1.0, std::min(menu.max_lifetime_frames, lifetime_s / frame_interval_s(params)));
                const double full_ms = refresh_ms + (g ? model_.meshed_refresh_t_setup_ms : 0.0);
                const Representation rep = g ? Representation::meshed_imposter : Representation::simple_imposter;
                push(imposter_way(mesh_triangles(g), draw_ms(g) + full_ms / frames, e), {rep, true, e, side, vertices, g});
                way_kinds_.back().full_ms = draw_ms(g) + full_ms;
            }
        }
    }
    problem_.previous_way[k] = previous_way;
}

// Whether way 0 (the levels smooth) does better than the level way `w` of object k for every
// choice of it: for each n of w, the smooth resolution of the same error, n / (A_w / A)^(1/m),
// (or the smooth lo, when that is below it) costs no more. Costs are linear in n on the ranges,
// so the ends decide. A dominated way is never in an optimal plan; leaving it out makes the
// frame's problem smaller (a software rasterizer's flat shading, barely cheaper a triangle at
// twice the error, is such a way).
bool Runtime::dominated_by_smooth(const Way& w, size_t k) const noexcept {
    const double A = problem_.error[k], a = problem_.per_tri_ms[k], s = problem_.setup_ms[k], lo = problem_.lo[k];
    if (!(A > 0) || w.error < A || w.m != problem_.m) return false;
    const double stretch = std::pow(w.error / A, 1.0 / w.m);  // n of w has the error of n / stretch smooth
    auto worse = [&](double n) { return w.setup_ms + w.per_tri_ms * n >= s + a * std::max(lo, n / stretch); };
    return w.setup_ms + w.per_tri_ms * w.lo >= s + a * lo && worse(std::max(w.lo, lo * stretch)) && worse(w.hi);
}

// The resolution and prediction of object `id` (k-th visible) drawn its way `way` with about
// `triangles`; \return its predicted time.
double Runtime::choose(uint32_t id, size_t k, double triangles, uint32_t way) {
    const Object& o = objects_[id];
    ObjectResult& r = results_[id];
    const WayKind kind = way == 0 ? WayKind{Representation::smooth, false, 0, 0, 0, 0} : way_kinds_[problem_.way_begin[k] + way - 1];
    const double parts = double(tom::part_count(*o.mesh));
    r.representation = kind.representation;
    r.refresh = kind.refresh;
    if (is_imposter(kind.representation)) {
        r.vertices = kind.vertices;
        r.triangles = kind.refresh ? tom::active_triangle_count(*o.mesh, kind.vertices) : 0;
        r.error_px = kind.error_px;
        const double draw_ms = kind.grid ? model_.meshed_ms(r.coverage_px, 2.0 * kind.grid * kind.grid) : model_.imposter_ms(r.coverage_px);
        r.predicted_ms = correction_ * (kind.refresh ? kind.full_ms : draw_ms);
        return r.predicted_ms;
    }
    r.vertices = resolution_for(o, triangles);
    r.triangles = tom::active_triangle_count(*o.mesh, r.vertices);
    if (kind.representation == Representation::flat) r.predicted_ms = model_.flat_ms(r.triangles, r.vertices, r.coverage_px, r.inside_share, parts);
    else if (kind.representation == Representation::textured) r.predicted_ms = model_.textured_ms(r.triangles, r.vertices, r.coverage_px, r.inside_share, parts);
    else r.predicted_ms = model_.object_ms(r.triangles, r.vertices, r.coverage_px, r.inside_share, parts);
    r.predicted_ms *= correction_;
    r.error_px = projected_error_px(o, r, r.triangles);
    return r.predicted_ms;
}

// The way of the k-th visible object's kept capture, when its menu offers one; else 0 (its levels).
uint32_t Runtime::kept_capture_way(size_t k) const noexcept {
    for (uint32_t j = 1; j < problem_.way_count(k); ++j) {
        const WayKind& kind = way_kinds_[problem_.way_begin[k] + j - 1];
        if (is_imposter(kind.representation) && !kind.refresh) return j;
    }
    return 0;
}

// A plan spreads refreshes over their lifetimes; the frame pays each whole. While that tips it
// over the budget, the refresh that costs the most becomes its kept capture (when one is within
// the bound) or the captured level drawn smooth.
void Runtime::repair_refreshes(double budget_ms, double& predicted) {
    for (;;) {
        if (predicted <= budget_ms) return;
        size_t worst = SIZE_MAX;
        for (size_t k = 0; k < visible_ids_.size(); ++k) {
            const ObjectResult& r = results_[visible_ids_[k]];
            if (r.drawn && r.refresh && (worst == SIZE_MAX || r.predicted_ms > results_[visible_ids_[worst]].predicted_ms)) worst = k;
        }
        if (worst == SIZE_MAX) return;
        const uint32_t id = visible_ids_[worst];
        const uint32_t kept = kept_capture_way(worst);
        // else the level the refresh would have rendered, smooth: its error, without the
        // render into the texture (the step-down after this trims it if the frame is still over)
        const WayKind& refresh = way_kinds_[problem_.way_begin[worst] + plan_.way[worst] - 1];
        const double triangles = kept ? problem_.way(worst, kept).lo : std::max(problem_.lo[worst], double(tom::active_triangle_count(*objects_[id].mesh, refresh.vertices)));
        predicted -= results_[id].predicted_ms;
        plan_.way[worst] = kept;
        predicted += choose(id, worst, triangles, kept);
        plan_.triangles[worst] = triangles;
    }
}

// The plan counts each refresh at its cost spread over the capture's lifetime; the frame pays
// it whole. So a frame renews at most what a share of the budget pays for beyond the spread
// cost, the cheapest first (the others wait for a later frame, drawn by their kept capture or
// their levels), and the plan is solved again with that time set aside, so that every object,
// not the refreshes alone, gives it up. exact keeps its ways and solves the resolutions again
// (one sort); greedy chooses again, and when that drops some of the renewals it was given time
// for, once more among those it kept, with only their time set aside, so no reserve goes unspent.
void Runtime::reserve_refreshes(const SelectParams& sp, double share) {
    if (!problem_.has_menu()) return;
    const double budget = problem_.budget_ms;
    double cap = share * budget, reserved = -1;
    for (int round = 0; round < 3; ++round) {
        const double kept = keep_cheapest_refreshes(cap);
        if (reserved < 0 && renewals_.empty()) return;                  // the plan renews nothing
        if (reserved >= 0 && kept >= reserved - 0.01 * budget) return;  // little left unspent: this plan stands
        problem_.budget_ms = budget - kept;
        if (selector_ == SelectorKind::exact) spend_on_ways(problem_, plan_);
        else select(selector_, problem_, sp, plan_);
        problem_.budget_ms = budget;
        if (selector_ == SelectorKind::exact) return;  // its ways, and so its renewals, stand
        reserved = cap = kept;
    }
}

// The plan's refreshes (renewals_): keeps the cheapest whose extra cost (paid whole, beyond the
// spread cost) fits within `cap`, takes every other refresh way off this frame's menu (its
// setup past the budget) and moves the objects that had one to their kept capture, when it is
// offered, else to their levels. \return the extra cost of those kept.
double Runtime::keep_cheapest_refreshes(double cap) {
    renewals_.clear();
    for (size_t k = 0; k < visible_ids_.size(); ++k) {
        const uint32_t j = plan_.way[k];
        if (!plan_.drawn[k] || j == 0) continue;
        const WayKind& kind = way_kinds_[problem_.way_begin[k] + j - 1];
        if (kind.refresh) renewals_.push_back({std::max(0.0, kind.full_ms - problem_.cost(k, j, 2.0)), k, j});
    }
    std::sort(renewals_.begin(), renewals_.end(), [](const Renewal& a, const Renewal& b) { return a.extra < b.extra || (a.extra == b.extra && a.k < b.k); });
    const double off = 2.0 * problem_.budget_ms;
    for (size_t k = 0; k < visible_ids_.size(); ++k)  // the refreshes the plan did not choose
        for (uint32_t j = 1; j < problem_.way_count(k); ++j)
            if (way_kinds_[problem_.way_begin[k] + j - 1].refresh && !(plan_.drawn[k] && plan_.way[k] == j)) problem_.ways[problem_.way_begin[k] + j - 1].setup_ms = off;
    double kept = 0;
    for (const Renewal& r : renewals_) {
        if (kept + r.extra <= cap) {
            kept += r.extra;
            continue;
        }
        problem_.ways[problem_.way_begin[r.k] + r.j - 1].setup_ms = off;  // not this frame
        plan_.way[r.k] = kept_capture_way(r.k);
    }
    return kept;
}

// The eye of this frame, and the viewer's speed: given, or the eye's motion since the last
// frame over the frame interval, smoothed.
void Runtime::note_viewer(const FrameParams& params) {
    eye_of(params.camera.view, eye_);
    const double interval_s = frame_interval_s(params);
    if (params.menu.viewer_speed >= 0) speed_ = params.menu.viewer_speed;
    else if (have_eye_ && interval_s > 0 && std::isfinite(interval_s)) speed_ = 0.5 * speed_ + 0.5 * distance3(eye_, last_eye_) / interval_s;
    std::copy(eye_, eye_ + 3, last_eye_);
    have_eye_ = true;
}

// A refresh chosen: the object's imposter is now the capture from this frame's eye.
void Runtime::commit_capture(uint32_t id, uint32_t way, size_t k) {
    Object& o = objects_[id];
    const WayKind& kind = way_kinds_[problem_.way_begin[k] + way - 1];
    double centre[3], radius;
    world_sphere(o.transform, o.box, o.diagonal, centre, radius);
    ImposterState& s = o.imposter;
    s.valid = true;
    for (int c = 0; c < 3; ++c) s.eye[c] = float(eye_[c]), s.centre[c] = float(centre[c]);
    s.radius = float(radius);
    s.texture_px = kind.texture_px;
    s.grid = kind.grid;
    s.vertices = kind.vertices;
    s.triangles = tom::active_triangle_count(*o.mesh, kind.vertices);
    s.frame = frame_;
    o.lifetime_distance = -1;  // measured again from the new capture
}

// Step 1: each object's box against the frustum; the visible ones' projection and importance.
void Runtime::cull(const FrameParams& params) {
    visible_ids_.clear();
    for (uint32_t id = 0; id < objects_.size(); ++id) {
        Object& o = objects_[id];
        ObjectResult& r = results_[id];
        const double previous = r.drawn ? r.triangles : 0.0;
        const Representation previous_representation = r.drawn ? r.representation : Representation::smooth;
        const Projection p = project_box(params.camera, o.transform, o.box, params.focus_weight);
        r = ObjectResult();
        r.triangles = uint32_t(previous);  // kept for the problem's "previous" until replaced below
        r.representation = previous_representation;
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
}

// Step 2: the model correction from the last frame's measurement (objects' part only): the last
// prediction already carried the correction, so measured / predicted is the residual and
// correction x residual the factor the calibrated model should have had.
void Runtime::correct_model(const FrameParams& params) {
    if (params.correct_model && params.previous_frame_ms > 0 && last_predicted_ms_ > model_.frame_fixed_ms()) {
        const double residual = (params.previous_frame_ms - model_.frame_fixed_ms() + model_.safety_ms) / (last_predicted_ms_ - model_.frame_fixed_ms());
        if (std::isfinite(residual) && residual > 0)
            correction_ = std::min(2.0, std::max(0.5, 0.7 * correction_ + 0.3 * correction_ * residual));
    }
    if (!params.correct_model) correction_ = 1.0;
    report_.correction = correction_;
}

// Step 3: the menu problem of the visible objects: each one's benefit, cost, triangle range
// and, with a menu, its other ways.
void Runtime::build_problem(const FrameParams& params) {
    const size_t n = visible_ids_.size();
    problem_.resize(n);
    coverage_.resize(n);
    problem_.m = params.m;
    problem_.budget_ms = (params.budget_ms - model_.frame_fixed_ms()) / correction_;
    const bool menu = (params.menu.flat && model_.has_flat()) || (params.menu.imposters && model_.has_imposters()) || (params.menu.textured && model_.has_textured());
    problem_.ways.clear();
    way_kinds_.clear();
    problem_.way_begin.assign(menu ? n + 1 : 0, 0);
    problem_.previous_way.assign(menu ? n : 0, 0);
    const float* P = params.camera.projection;
    const double radians_per_px = (P[5] != 0 ? 2.0 * std::atan(1.0 / P[5]) : 1.0) / std::max<uint32_t>(1, params.camera.viewport_height);
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
        if (menu) {
            problem_.way_begin[k] = uint32_t(problem_.ways.size());
            add_ways(id, k, params, radians_per_px);
        }
    }
    if (menu) problem_.way_begin[n] = uint32_t(problem_.ways.size());
}

// Step 4: the selector's plan (or, error-bounded, every object at its bound's level).
void Runtime::select_plan(const FrameParams& params) {
    const size_t n = visible_ids_.size();
    stress_ = update_stress(stress_, params.previous_frame_ms, params.budget_ms);
    report_.stress = stress_;
    if (params.error_bounded) {
        plan_.triangles.resize(n);
        plan_.drawn.assign(n, 1);
        plan_.way.assign(n, 0);  // the levels alone: an error bound is a level's
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
        reserve_refreshes(sp, params.menu.refresh_share);
    }
}

// Step 5: the plan rounded down to the TOM resolutions and predicted with the real vertex
// counts; returns the frame's prediction.
double Runtime::round_to_levels(const FrameParams& params) {
    const size_t n = visible_ids_.size();
    double predicted = model_.frame_fixed_ms();
    for (size_t k = 0; k < n; ++k) {
        const uint32_t id = visible_ids_[k];
        ObjectResult& r = results_[id];
        r.drawn = plan_.drawn[k] != 0;
        r.triangles = 0;
        r.representation = Representation::smooth;
        if (r.drawn) predicted += choose(id, k, plan_.triangles[k], plan_.way[k]);
    }
    if (!params.error_bounded) repair_refreshes(params.budget_ms, predicted);
    return predicted;
}

// Step 6: vertex counts are exact here and were estimated in the problem: step down if that
// tipped a feasible plan over the budget (imposters have no levels to step down).
void Runtime::step_down(const FrameParams& params, double& predicted) {
    const size_t n = visible_ids_.size();
    for (int round = 0; round < 8 && plan_.feasible && predicted > params.budget_ms && !params.error_bounded; ++round) {
        const double factor = std::max(0.5, 1.0 - (predicted - params.budget_ms) / std::max(predicted - model_.frame_fixed_ms(), 1e-12) - 0.01);
        predicted = model_.frame_fixed_ms();
        for (size_t k = 0; k < n; ++k) {
            ObjectResult& r = results_[visible_ids_[k]];
            if (!r.drawn) continue;
            if (is_imposter(r.representation)) predicted += r.predicted_ms;
            else predicted += choose(visible_ids_[k], k, std::max(problem_.way(k, plan_.way[k]).lo, r.triangles * factor), plan_.way[k]);
        }
    }
}

// Step 7: the frame's report: what is drawn, how, and the plan's certificate.
void Runtime::tally(const FrameParams& params, double predicted) {
    const size_t n = visible_ids_.size();
    for (size_t k = 0; k < n; ++k) {
        const uint32_t id = visible_ids_[k];
        const ObjectResult& r = results_[id];
        if (!r.drawn) continue;
        ++report_.drawn;
        report_.triangles += r.triangles;
        report_.max_error_px = std::max(report_.max_error_px, r.error_px);
        report_.flat += r.representation == Representation::flat;
        report_.textured += r.representation == Representation::textured;
        if (is_imposter(r.representation)) {
            ++report_.imposters;
            if (r.refresh) {
                ++report_.refreshes;
                commit_capture(id, plan_.way[k], k);
            }
            const uint32_t grid = objects_[id].imposter.grid;
            report_.meshed += grid > 0;
            report_.triangles += grid ? 2u * grid * grid : 2u;  // its depth mesh or its quad
        }
    }
    ++frame_;
    report_.visible = uint32_t(n);
    report_.predicted_ms = predicted;
    last_predicted_ms_ = predicted;
    report_.benefit = plan_.benefit;
    report_.upper_bound = plan_.upper_bound;
    report_.gap = plan_.gap;
    report_.feasible = plan_.feasible && predicted <= params.budget_ms * (1 + 1e-9);
    report_.deadline_hit = plan_.deadline_hit;
    report_.iterations = plan_.iterations;
}

// Cull, correct, build the problem, select, round, step down, tally.
const FrameReport& Runtime::plan_frame(const FrameParams& params) {
    const auto start = std::chrono::steady_clock::now();
    last_camera_ = params.camera;
    last_fixed_c_ = params.fixed_c;
    report_ = FrameReport();
    note_viewer(params);
    cull(params);
    report_.cull_ms = 1e3 * seconds_since(start);
    const auto optimize_start = std::chrono::steady_clock::now();
    correct_model(params);
    build_problem(params);
    select_plan(params);
    double predicted = round_to_levels(params);
    step_down(params, predicted);
    tally(params, predicted);
    report_.optimize_ms = 1e3 * seconds_since(optimize_start);
    return report_;
}

tom::Extracted Runtime::indices(uint32_t id, uint32_t* destination, size_t capacity) const noexcept {
    const ObjectResult& r = results_[id];
    if (!has_geometry(r)) return {};
    return tom::extract(*objects_[id].mesh, r.vertices, destination, capacity);
}

tom::Extracted Runtime::indices(uint32_t id, uint32_t* destination, size_t capacity, tom::PartDraw* draws) const noexcept {
    const ObjectResult& r = results_[id];
    const uint32_t parts = tom::part_count(*objects_[id].mesh);
    if (!has_geometry(r)) {
        for (uint32_t p = 0; p < parts; ++p) draws[p] = {0, 0, tom::part_at(*objects_[id].mesh, p).material};
        return {};
    }
    return tom::extract_parts(*objects_[id].mesh, r.vertices, destination, capacity, draws);
}

tom::Extracted Runtime::indices(uint32_t id, uint16_t* destination, size_t capacity) const noexcept {
    const ObjectResult& r = results_[id];
    if (!has_geometry(r)) return {};
    return tom::extract(*objects_[id].mesh, r.vertices, destination, capacity);
}

} // namespace tcr
