// Calibration (calibrate.h): the procedure tcrwalk measured on a real renderer, in the library
// so that an engine calibrates its own renderer through a draw-and-time callback.

#include "tcr/calibrate.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <string>

#include "tcr/governor.h"
#include "tom/errors.h"
#include "tom/extract.h"

namespace tcr {
namespace {

constexpr float kPi = 3.14159265f;

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

// The distinct vertices `indices` reference (all below n): what the renderer shades, since a
// level's prefix may hold unused survivors. `used` is scratch.
uint32_t referenced_vertices(const std::vector<uint32_t>& indices, uint32_t n, std::vector<uint8_t>& used) {
    used.assign(n, 0);
    uint32_t count = 0;
    for (const uint32_t v : indices) count += used[v] ? 0 : (used[v] = 1);
    return count;
}

struct MeshFrame {
    double centre[3];
    double diagonal;
};

MeshFrame frame_of(const tom::MeshView& mesh) {
    MeshFrame f{};
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
        const double e = double(mesh.bounds_max[k]) - mesh.bounds_min[k];
        d2 += e * e;
        f.centre[k] = 0.5 * (double(mesh.bounds_min[k]) + mesh.bounds_max[k]);
    }
    f.diagonal = std::sqrt(d2);
    return f;
}

Box box_of(const tom::MeshView& mesh) {
    return Box{{mesh.bounds_min[0], mesh.bounds_min[1], mesh.bounds_min[2]}, {mesh.bounds_max[0], mesh.bounds_max[1], mesh.bounds_max[2]}};
}

// One configuration of a sample frame: a level of a mesh (scaled to diagonal 1) at a distance,
// in `copies` copies side by side (8, or 64 small ones for the per-draw cost).
struct Config {
    double fraction;
    float distance;
    int copies;
};

std::vector<Config> configs() {
    std::vector<Config> out;
    for (double fraction : {1.0, 0.4, 0.15, 0.05, 0.015})
        for (float distance : {1.6f, 4.0f, 10.0f}) out.push_back({fraction, distance, 8});
    out.push_back({0.015, 10.0f, 64});
    out.push_back({0.05, 10.0f, 64});
    return out;
}

// The state of one calibration: the renderer, its view, the empty frame's time and the buffers
// every sample reuses.
struct Session {
    Session(CalibrationRenderer& r, const std::vector<const tom::MeshView*>& m, const CalibrationParams& p) : renderer(r), meshes(m), params(p) {}
    CalibrationRenderer& renderer;
    const std::vector<const tom::MeshView*>& meshes;
    const CalibrationParams& params;
    Camera camera{};
    double empty_ms = 0;
    std::vector<uint32_t> indices;
    std::vector<CalibrationDraw> draws;
    std::vector<CalibrationCapture> captures;
    std::vector<CalibrationImposter> imposters;
    std::vector<uint8_t> used;

    // `count` renders of the frame in `draws`, each timed; empty when the renderer does not draw `way`
    std::vector<double> time_frames(Representation way, int count) {
        return repeat(count, [&] { return renderer.time_frame(camera, draws, way); });
    }
    // the same with the frame's captures and imposters
    std::vector<double> time_imposter_frames(int count) {
        return repeat(count, [&] { return renderer.time_imposters(camera, captures, imposters); });
    }
    template <class Render>
    static std::vector<double> repeat(int count, Render&& render) {
        std::vector<double> times;
        for (int r = 0; r < count; ++r) {
            const double t = render();
            if (t < 0) return {};
            times.push_back(t);
        }
        return times;
    }
    // the level of `mesh` at `fraction` into `indices`; its vertex count
    uint32_t extract_level(const tom::MeshView& mesh, double fraction) {
        const uint32_t n = tom::vertex_count_for_fraction(mesh, fraction, tom::Floor::coarsest);
        indices.resize(size_t(tom::active_triangle_count(mesh, n)) * 3);
        tom::extract(mesh, n, indices.data(), indices.size());
        return n;
    }
};

// The calibration's view: from the origin down -z, 60 degrees, the renderer's viewport.
Camera calibration_camera(const CalibrationRenderer& renderer) {
    Camera cam;
    const float eye[3] = {0, 0, 0}, target[3] = {0, 0, -1}, up[3] = {0, 1, 0};
    look_at(eye, target, up, cam.view);
    perspective(60.0f * kPi / 180.0f, float(renderer.width()) / float(renderer.height()), 0.05f, 200.0f, cam.projection);
    cam.viewport_width = renderer.width();
    cam.viewport_height = renderer.height();
    return cam;
}

// The time per object of one configuration, above the empty frame's: the copies drawn
// `repeats` times in the frame (up to 64), toward triangles_per_frame, so that even a small
// level's time stands well above the empty frame's jitter; the median of 7 frames. time_ms < 0
// when the renderer does not draw `way`.
CostSample sample(Session& s, uint32_t mi, const Config& cfg, Representation way) {
    const tom::MeshView& mesh = *s.meshes[mi];
    const MeshFrame mf = frame_of(mesh);
    const uint32_t n = s.extract_level(mesh, cfg.fraction);
    const uint32_t tris = uint32_t(s.indices.size() / 3);
    const float scale = float(1.0 / std::max(1e-30, mf.diagonal));
    const int copies = cfg.copies, columns = copies == 8 ? 4 : 8;
    const float spacing = copies == 8 ? cfg.distance * 0.42f : cfg.distance * 0.13f;
    const Box box = box_of(mesh);
    double pixels = 0;
    s.draws.clear();
    for (int k = 0; k < copies; ++k) {
        CalibrationDraw d;
        d.mesh = mi;
        d.indices = s.indices.data();
        d.index_count = tris * 3;
        const float x = (float(k % columns) - 0.5f * float(columns - 1)) * spacing;
        const float y = (float(k / columns) - 0.5f * float(copies / columns - 1)) * spacing;
        translation_scale(x - scale * float(mf.centre[0]), y - scale * float(mf.centre[1]), -cfg.distance - scale * float(mf.centre[2]), scale, d.model);
        pixels += project_box(s.camera, d.model, box).coverage_px;
        s.draws.push_back(d);
    }
    const int repeats = std::max(1, std::min(64, int(std::ceil(s.params.triangles_per_frame / (std::max(1.0, double(tris)) * copies)))));
    for (int rep = 1; rep < repeats; ++rep)
        for (int k = 0; k < copies; ++k) s.draws.push_back(s.draws[size_t(k)]);
    const std::vector<double> times = s.time_frames(way, 7);
    CostSample out;
    out.triangles = tris;
    out.vertices = referenced_vertices(s.indices, n, s.used);
    out.pixels = pixels / copies;
    out.time_ms = times.empty() ? -1.0 : std::max(0.0, median(times) - s.empty_ms) / (copies * repeats);
    return out;
}

// The samples of every configuration of the first `mesh_count` meshes drawn `way`; empty when
// the renderer does not draw it.
std::vector<CostSample> samples_of(Session& s, size_t mesh_count, Representation way) {
    std::vector<CostSample> out;
    for (uint32_t mi = 0; mi < mesh_count; ++mi)
        for (const Config& cfg : configs()) {
            const CostSample c = sample(s, mi, cfg, way);
            if (c.time_ms < 0) return {};
            out.push_back(c);
        }
    return out;
}

// The renderer's noise: one heavy frame (the draws of the last configuration, at the first
// mesh's full detail) drawn 61 times; its relative variation frame to frame, and in `overall`
// its relative standard deviation.
double frame_noise(Session& s, double& overall) {
    const tom::MeshView& mesh = *s.meshes[0];
    s.extract_level(mesh, 1.0);
    for (CalibrationDraw& d : s.draws) d.mesh = 0, d.indices = s.indices.data(), d.index_count = uint32_t(s.indices.size());
    const std::vector<double> times = s.time_frames(Representation::smooth, 61);
    double mean = 0, var = 0;
    for (double t : times) mean += t / double(times.size());
    for (double t : times) var += (t - mean) * (t - mean) / double(times.size());
    overall = mean > 0 ? std::sqrt(var) / mean : 0.0;
    return frame_to_frame(times);
}

// Simple imposters' quads: 64 quads a frame (repeated toward 2,000 quads), each showing the
// next of `textures` slots from `slot` on (a frame's imposters each bind their own), each
// covering about `side_px` square pixels; the time per quad above the empty frame's, as a
// sample of no triangles (the fit's fill term: t_setup + t_pix pixels); time_ms < 0 without
// imposters.
CostSample quad_sample(Session& s, uint32_t slot, uint32_t textures, float side_px) {
    const float distance = 10.0f;
    const float half = 0.5f * side_px * 2.0f * distance * std::tan(30.0f * kPi / 180.0f) / float(s.renderer.height());  // pixels -> metres at 10 m
    s.captures.clear();
    s.imposters.clear();
    for (int k = 0; k < 64; ++k) {
        CalibrationImposter q;
        q.slot = slot + uint32_t(k) % textures;
        const float x = (float(k % 8) - 3.5f) * 1.1f * 2 * half, y = (float(k / 8) - 3.5f) * 1.1f * 2 * half;
        const float su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
        for (int c = 0; c < 4; ++c) q.corners[3 * c] = x + half * su[c], q.corners[3 * c + 1] = y + half * sv[c], q.corners[3 * c + 2] = -distance;
        s.imposters.push_back(q);
    }
    const int repeats = 2000 / 64;
    for (int rep = 1; rep < repeats; ++rep)
        for (size_t k = 0; k < 64; ++k) s.imposters.push_back(s.imposters[k]);
    const std::vector<double> times = s.time_imposter_frames(7);
    CostSample out;
    out.pixels = double(side_px) * side_px * 0.8;  // the object's share of its quad (the alpha test discards the rest after the fetch)
    out.time_ms = times.empty() ? -1.0 : std::max(0.0, median(times) - s.empty_ms) / (64.0 * repeats);
    return out;
}

// Captures: 16 of the `index_count` indices in `s.indices` (0: an empty capture) into the slots
// 0 to 15 of `side` texels a side (with depth meshes of `grid` cells a side when `grid`), in one
// frame, the first mesh seen from 4 radii; the time per capture above the empty frame's, the
// median of 7 frames. < 0 without imposters.
double capture_ms(Session& s, uint32_t index_count, uint32_t side, uint32_t grid) {
    const MeshFrame mf = frame_of(*s.meshes[0]);
    ImposterState state;
    state.valid = true;
    for (int k = 0; k < 3; ++k) state.centre[k] = float(mf.centre[k]);
    state.radius = float(0.5 * mf.diagonal);
    state.eye[0] = state.centre[0], state.eye[1] = state.centre[1], state.eye[2] = state.centre[2] + 4 * state.radius;
    state.texture_px = side;
    const uint32_t count = 16;
    s.captures.clear();
    s.imposters.clear();
    for (uint32_t c = 0; c < count; ++c) {
        CalibrationCapture cap;
        cap.slot = c;
        cap.side = side;
        cap.grid = grid;
        imposter_camera(state, cap.view, cap.projection);
        cap.draw.indices = s.indices.data();
        cap.draw.index_count = index_count;
        translation_scale(0, 0, 0, 1, cap.draw.model);  // the object where it is
        s.captures.push_back(cap);
    }
    const std::vector<double> times = s.time_imposter_frames(7);
    return times.empty() ? -1.0 : std::max(0.0, median(times) - s.empty_ms) / count;
}

// A refresh's fixed part (CostModel::refresh_t_setup_ms), measured directly: empty captures,
// the render target's switch, its clear and the wait for the captures, above the model's draw
// set-up. Not the difference between whole captures and the model's time of their draws: that
// difference is within the fit's error, and a fit that overestimates the draws makes it 0.
// < 0 without imposters.
double refresh_setup(Session& s, uint32_t side, const CostModel& model) {
    const double per_capture = capture_ms(s, 0, side, 0);
    return per_capture < 0 ? -1.0 : std::max(0.0, per_capture - model.object_ms(0, 0, 0));
}

// A meshed refresh beyond a simple one (CostModel::meshed_refresh_t_setup_ms): captures of the
// first mesh's level `fraction` with depth meshes of 8 x 8 cells, above the model's refresh of
// that level (its depth read back, its mesh made).
double meshed_refresh_overhead(Session& s, double fraction, uint32_t side, const CostModel& model) {
    const uint32_t n = s.extract_level(*s.meshes[0], fraction);
    const uint32_t tris = uint32_t(s.indices.size() / 3);
    const double per_capture = capture_ms(s, tris * 3, side, 8);
    return per_capture - model.refresh_ms(tris, referenced_vertices(s.indices, n, s.used), 0.5 * double(side) * side);
}

// Meshed imposters' draws: 16 captures of the first mesh's level 0.1, placed 10 m ahead at
// about `side_px` pixels across, with depth meshes of `grid` cells a side, into the slots from
// `slot` (one frame, untimed); then 64 draws a frame of those depth meshes (repeated toward
// 2,000); the time per draw above the empty frame's.
double meshed_draw_ms(Session& s, uint32_t slot, uint32_t grid, float side_px) {
    const tom::MeshView& mesh = *s.meshes[0];
    s.extract_level(mesh, 0.1);
    const MeshFrame mf = frame_of(mesh);
    const double distance = 10.0, radius = 0.5 * side_px * distance * std::tan(30.0 * kPi / 180.0) / s.renderer.height() * 2.0;
    const double scale = radius / std::max(1e-9, 0.5 * mf.diagonal);
    float model[16];
    translation_scale(float(-scale * mf.centre[0]), float(-scale * mf.centre[1]), float(-distance - scale * mf.centre[2]), float(scale), model);
    ImposterState state;
    state.valid = true;
    state.centre[2] = float(-distance);
    state.radius = float(radius);
    s.captures.clear();
    s.imposters.clear();
    for (uint32_t c = 0; c < 16; ++c) {
        CalibrationCapture cap;
        cap.slot = slot + c;
        cap.side = 64;
        cap.grid = grid;
        imposter_camera(state, cap.view, cap.projection);
        cap.draw.indices = s.indices.data();
        cap.draw.index_count = uint32_t(s.indices.size());
        std::copy(model, model + 16, cap.draw.model);
        s.captures.push_back(cap);
    }
    if (s.time_imposter_frames(1).empty()) return -1.0;
    s.captures.clear();
    for (uint32_t k = 0; k < 2048; ++k) {
        CalibrationImposter q;
        q.slot = slot + k % 16;
        q.meshed = true;
        s.imposters.push_back(q);
    }
    const std::vector<double> times = s.time_imposter_frames(7);
    return times.empty() ? -1.0 : std::max(0.0, median(times) - s.empty_ms) / double(s.imposters.size());
}

// The geometry fit's coefficients for `way`, from the first two meshes' draws; false when the
// renderer does not draw that way.
bool fit_way(Session& s, Representation way, double& t_tri, double& t_vert, double& t_pix, CalibrationResult& fit) {
    const std::vector<CostSample> samples = samples_of(s, std::min<size_t>(s.meshes.size(), 2), way);
    if (samples.empty()) return false;
    fit = fit_cost_model(samples);
    t_tri = fit.model.t_tri_ms, t_vert = fit.model.t_vert_ms, t_pix = fit.model.t_pix_ms;
    return true;
}

// The imposters' coefficients: a refresh's fixed part (empty captures into two texture sides),
// a meshed refresh's beyond it (the median over two levels and two sides), a depth mesh's
// triangle (from draws of 16 x 16 and 4 x 4 grids of the same captures), and the quad's draw and
// fill by least squares on relative errors over five quad sizes. Leaves `m` without imposters
// when the renderer has none.
void fit_imposters(Session& s, CostModel& m) {
    std::vector<double> setups, meshed_overheads, per_triangle;
    for (uint32_t side : {64u, 256u}) {
        const double setup = refresh_setup(s, side, m);
        if (setup < 0) return;
        setups.push_back(setup);
    }
    m.refresh_t_setup_ms = median(setups);
    for (double fraction : {0.4, 0.05})
        for (uint32_t side : {64u, 256u}) meshed_overheads.push_back(meshed_refresh_overhead(s, fraction, side, m));
    for (float side_px : {32.0f, 96.0f}) {
        const double coarse = meshed_draw_ms(s, 16, 4, side_px);
        const double fine = meshed_draw_ms(s, 32, 16, side_px);
        per_triangle.push_back((fine - coarse) / (2.0 * 16 * 16 - 2.0 * 4 * 4));
    }
    // at least 1e-9 ms and 1e-6 ms: a measured 0 would read as not calibrated
    m.meshed_refresh_t_setup_ms = std::max(1e-6, median(meshed_overheads));
    m.meshed_t_tri_ms = std::max(1e-9, median(per_triangle));
    // t = a + b P by weighted least squares, weights 1 / t^2 (relative residuals); the quads show
    // the refreshes' 16 textures
    double s00 = 0, s01 = 0, s11 = 0, r0 = 0, r1 = 0;
    for (float side : {8.0f, 16.0f, 32.0f, 64.0f, 128.0f}) {
        const CostSample q = quad_sample(s, 0, 16, side);
        if (q.time_ms <= 0) continue;
        const double wt = 1.0 / (q.time_ms * q.time_ms);
        s00 += wt, s01 += wt * q.pixels, s11 += wt * q.pixels * q.pixels, r0 += wt * q.time_ms, r1 += wt * q.time_ms * q.pixels;
    }
    const double det = s00 * s11 - s01 * s01;
    if (det > 0) {
        m.imposter_t_pix_ms = std::max(0.0, (s00 * r1 - s01 * r0) / det);
        m.imposter_t_setup_ms = std::max(1e-6, (r0 - s01 * m.imposter_t_pix_ms) / s00);
    }
}

// printf into a string (the summary's lines are short)
std::string format(const char* fmt, ...) {
    char buffer[1024];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(buffer, sizeof buffer, fmt, args);
    va_end(args);
    return buffer;
}

void check_arguments(const CalibrationRenderer& renderer, const std::vector<const tom::MeshView*>& meshes, const CalibrationParams& params) {
    if (meshes.empty()) throw tom::ArgumentError("tcr::calibrate: no meshes to draw");
    for (const tom::MeshView* m : meshes)
        if (!m || m->vertex_count == 0) throw tom::ArgumentError("tcr::calibrate: a null or empty mesh");
    if (renderer.width() == 0 || renderer.height() == 0) throw tom::ArgumentError("tcr::calibrate: the renderer's viewport is empty");
    // the file's folder before the minute of timing, not after
    if (!params.path.empty()) {
        const std::filesystem::path folder = std::filesystem::absolute(params.path).parent_path();
        std::error_code ec;
        if (!std::filesystem::is_directory(folder, ec))
            throw tom::IoError("cannot write calibration file '" + params.path + "': no folder '" + folder.string() + "'");
    }
}

} // namespace

Calibration calibrate(CalibrationRenderer& renderer, const std::vector<const tom::MeshView*>& meshes, const CalibrationParams& params) {
    check_arguments(renderer, meshes, params);
    Session s(renderer, meshes, params);
    s.camera = calibration_camera(renderer);
    Calibration out;

    // the empty frame: t_init + t_final, and the safety allowance from its spread
    if (s.time_frames(Representation::smooth, 10).empty())  // warm-up
        throw tom::ArgumentError("tcr::calibrate: the renderer does not draw smooth-shaded frames");
    const std::vector<double> empty = s.time_frames(Representation::smooth, 25);
    s.empty_ms = out.empty_ms = median(empty);
    double spread = 0;
    for (double e : empty) spread += (e - s.empty_ms) * (e - s.empty_ms) / double(empty.size());

    // the geometry fit, then the noise
    const std::vector<CostSample> samples = samples_of(s, std::min<size_t>(meshes.size(), params.max_meshes), Representation::smooth);
    out.samples = samples.size();
    out.fit = fit_cost_model(samples);
    CostModel& m = out.model = out.fit.model;
    m.t_init_ms = m.t_final_ms = 0.5 * s.empty_ms;
    m.safety_ms = std::max(0.25, 2.0 * std::sqrt(spread));
    m.noise_rel = frame_noise(s, out.noise_overall);

    // the other ways, each where the renderer draws it
    CalibrationResult flat, textured;
    const bool has_flat = fit_way(s, Representation::flat, m.flat_t_tri_ms, m.flat_t_vert_ms, m.flat_t_pix_ms, flat);
    const bool has_textured = fit_way(s, Representation::textured, m.textured_t_tri_ms, m.textured_t_vert_ms, m.textured_t_pix_ms, textured);
    fit_imposters(s, m);

    out.summary = format("calibration: %zu samples (%zu meshes x (5 levels x 3 distances x 8 copies + 2 x 64 small copies), each frame repeated up "
                         "to 64x toward %.0f triangles, median of 7), empty frame %.3f ms\n"
                         "  t_setup %.4g ms, t_tri %.4g ms, t_vert %.4g ms, t_pix %.4g ms; fit: rms %.4f ms, mean relative error %.1f%% "
                         "(%zu geometry bound, %zu fill bound); identical frames vary by %.1f%% frame to frame (%.1f%% standard deviation)\n",
                         out.samples, out.samples / configs().size(), params.triangles_per_frame, s.empty_ms, m.t_setup_ms, m.t_tri_ms, m.t_vert_ms,
                         m.t_pix_ms, out.fit.rms_error_ms, 100 * out.fit.mean_relative_error, out.fit.geometry_bound, out.fit.fill_bound,
                         100 * m.noise_rel, 100 * out.noise_overall);
    if (has_flat) out.summary += format("  flat: t_tri %.4g ms, t_vert %.4g ms, t_pix %.4g ms (fit %.1f%%)\n", m.flat_t_tri_ms, m.flat_t_vert_ms,
                                        m.flat_t_pix_ms, 100 * flat.mean_relative_error);
    if (has_textured) out.summary += format("  textured: t_tri %.4g ms, t_vert %.4g ms, t_pix %.4g ms (fit %.1f%%)\n", m.textured_t_tri_ms,
                                            m.textured_t_vert_ms, m.textured_t_pix_ms, 100 * textured.mean_relative_error);
    if (m.has_imposters())
        out.summary += format("  imposters: refresh overhead %.4g ms; quad %.4g ms + %.4g ms a pixel; meshed + %.4g ms a depth-mesh triangle, "
                              "its refresh + %.4g ms\n",
                              m.refresh_t_setup_ms, m.imposter_t_setup_ms, m.imposter_t_pix_ms, m.meshed_t_tri_ms, m.meshed_refresh_t_setup_ms);
    if (!params.path.empty()) write_cost_model(params.path, m, params.comment);
    return out;
}

} // namespace tcr
