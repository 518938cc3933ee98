// tcr::calibrate against a renderer whose costs are known: frames timed by a true cost model
// (every way with its own coefficients) plus 1% noise, on the bunny and a sphere. The
// calibration must recover the coefficients, the noise and the empty frame, write the file, and
// leave every way the renderer does not draw uncalibrated.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>

#include <catch2/catch.hpp>

#include "support.h"
#include "tcr/calibrate.h"
#include "tom/builder/builder.h"
#include "tom/builder/generate.h"
#include "tom/builder/writer.h"
#include "tom/errors.h"
#include "tom/format.h"

namespace {

tcr::CostModel truth() {
    tcr::CostModel m;
    m.t_init_ms = m.t_final_ms = 0.2;
    m.t_setup_ms = 0.004;
    m.t_tri_ms = 6e-5;
    m.t_vert_ms = 3e-5;
    m.t_pix_ms = 2e-6;
    m.flat_t_tri_ms = 4e-5, m.flat_t_vert_ms = 2e-5, m.flat_t_pix_ms = 1.5e-6;
    m.textured_t_tri_ms = 8e-5, m.textured_t_vert_ms = 4e-5, m.textured_t_pix_ms = 3e-6;
    m.imposter_t_setup_ms = 0.003, m.imposter_t_pix_ms = 4e-7;
    m.refresh_t_setup_ms = 0.05;
    m.meshed_t_tri_ms = 2e-4, m.meshed_refresh_t_setup_ms = 0.3;
    return m;
}

// Times every frame by `model` (whole objects, as calibration assumes), times 1 + `noise`
// Gaussian; draws only the ways asked.
class ModelRenderer final : public tcr::CalibrationRenderer {
public:
    ModelRenderer(const std::vector<const tom::MeshView*>& meshes, const tcr::CostModel& model, double noise, bool all_ways)
        : meshes_(meshes), m_(model), noise_(noise), all_ways_(all_ways) {}
    uint32_t width() const override { return 640; }
    uint32_t height() const override { return 480; }
    size_t frames = 0;

    double time_frame(const tcr::Camera& cam, const std::vector<tcr::CalibrationDraw>& draws, tcr::Representation way) override {
        if (way != tcr::Representation::smooth && !all_ways_) return -1;
        double t = m_.t_init_ms + m_.t_final_ms;
        for (const tcr::CalibrationDraw& d : draws) {
            const double tris = d.index_count / 3, verts = vertices(d), pixels = pixels_of(cam, d);
            t += way == tcr::Representation::flat       ? m_.flat_ms(tris, verts, pixels)
                 : way == tcr::Representation::textured ? m_.textured_ms(tris, verts, pixels)
                                                        : m_.object_ms(tris, verts, pixels);
        }
        return noisy(t);
    }

    double time_imposters(const tcr::Camera& cam, const std::vector<tcr::CalibrationCapture>& captures,
                          const std::vector<tcr::CalibrationImposter>& imposters) override {
        if (!all_ways_) return -1;
        double t = m_.t_init_ms + m_.t_final_ms;
        for (const tcr::CalibrationCapture& c : captures) {
            // the object covers half the texture; an empty capture, none of it
            t += m_.refresh_ms(c.draw.index_count / 3, vertices(c.draw), c.draw.index_count ? 0.5 * double(c.side) * c.side : 0.0);
            if (c.grid) t += m_.meshed_refresh_t_setup_ms, grid_[c.slot] = c.grid;
        }
        for (const tcr::CalibrationImposter& q : imposters) {
            if (q.meshed) {
                t += m_.meshed_ms(0, 2.0 * grid_[q.slot] * grid_[q.slot]);
                continue;
            }
            // the quad's projected area; the object covers 0.8 of it (what calibration assumes)
            const double side = std::abs(q.corners[3] - q.corners[0]) / -q.corners[2] * 0.5 * height() / std::tan(3.14159265 / 6);
            t += m_.imposter_ms(0.8 * side * side);
        }
        (void)cam;
        return noisy(t);
    }

private:
    double vertices(const tcr::CalibrationDraw& d) {
        const auto key = std::make_pair(d.indices, d.index_count);
        const auto known = distinct_.find(key);
        if (known != distinct_.end()) return known->second;
        std::vector<uint8_t> used(meshes_[d.mesh]->vertex_count, 0);
        double n = 0;
        for (uint32_t k = 0; k < d.index_count; ++k) n += used[d.indices[k]] ? 0 : (used[d.indices[k]] = 1);
        return distinct_[key] = n;
    }
    double pixels_of(const tcr::Camera& cam, const tcr::CalibrationDraw& d) const {
        const tom::MeshView& m = *meshes_[d.mesh];
        const tcr::Box box{{m.bounds_min[0], m.bounds_min[1], m.bounds_min[2]}, {m.bounds_max[0], m.bounds_max[1], m.bounds_max[2]}};
        return tcr::project_box(cam, d.model, box).coverage_px;
    }
    double noisy(double t) {
        ++frames;
        return t * (1.0 + noise_ * std::max(-2.0, std::min(2.0, gauss_(rng_))));
    }

    const std::vector<const tom::MeshView*>& meshes_;
    tcr::CostModel m_;
    double noise_;
    bool all_ways_;
    std::map<std::pair<const uint32_t*, uint32_t>, double> distinct_;
    std::map<uint32_t, uint32_t> grid_;
    std::mt19937 rng_{11};
    std::normal_distribution<double> gauss_{0.0, 1.0};
};

struct Meshes {
    std::vector<uint8_t> bytes;
    tom::File file;
    std::vector<const tom::MeshView*> views;
    static std::vector<uint8_t> make() {
        tom::Mesh sphere = tom::make_sphere(40, 80, 1.0f, 0.1f);
        tom::clean_mesh(sphere);
        return tom::serialize({tom::build(test::real_meshes()[0].mesh), tom::build(sphere)});
    }
    Meshes() : bytes(make()), file(tom::File::from_bytes(bytes.data(), bytes.size())), views{&file.mesh(0), &file.mesh(1)} {}
};

// the cost of a triangle at the calibration's own ratio of vertices to triangles
double per_triangle(double t_tri, double t_vert) { return t_tri + 0.5 * t_vert; }

} // namespace

TEST_CASE("calibration recovers a renderer's true costs, noise and empty frame", "[tcr][calibration]") {
    const Meshes meshes;
    const tcr::CostModel t = truth();
    ModelRenderer renderer(meshes.views, t, 0.01, true);
    const std::string path = (std::filesystem::temp_directory_path() / "tcr_calibrate_test.txt").string();
    tcr::CalibrationParams params;
    params.path = path;
    params.comment = "calibrate_test";
    const tcr::Calibration c = tcr::calibrate(renderer, meshes.views, params);
    const tcr::CostModel& m = c.model;
    INFO(c.summary);
    CHECK(c.samples == 2 * 17);
    CHECK(c.empty_ms == Approx(t.t_init_ms + t.t_final_ms).epsilon(0.03));
    CHECK(m.t_init_ms + m.t_final_ms == Approx(c.empty_ms));
    // 1% Gaussian noise: 1% frame to frame (the median step scaled to a deviation)
    CHECK(m.noise_rel > 0.006);
    CHECK(m.noise_rel < 0.015);
    CHECK(m.safety_ms >= 0.25);
    CHECK(c.fit.mean_relative_error < 0.03);
    CHECK(per_triangle(m.t_tri_ms, m.t_vert_ms) == Approx(per_triangle(t.t_tri_ms, t.t_vert_ms)).epsilon(0.1));
    CHECK(m.t_pix_ms == Approx(t.t_pix_ms).epsilon(0.1));
    CHECK(m.t_setup_ms == Approx(t.t_setup_ms).epsilon(0.25));
    CHECK(per_triangle(m.flat_t_tri_ms, m.flat_t_vert_ms) == Approx(per_triangle(t.flat_t_tri_ms, t.flat_t_vert_ms)).epsilon(0.1));
    CHECK(m.flat_t_pix_ms == Approx(t.flat_t_pix_ms).epsilon(0.1));
    CHECK(per_triangle(m.textured_t_tri_ms, m.textured_t_vert_ms) == Approx(per_triangle(t.textured_t_tri_ms, t.textured_t_vert_ms)).epsilon(0.1));
    CHECK(m.textured_t_pix_ms == Approx(t.textured_t_pix_ms).epsilon(0.1));
    CHECK(m.refresh_t_setup_ms == Approx(t.refresh_t_setup_ms).epsilon(0.2));
    CHECK(m.meshed_refresh_t_setup_ms == Approx(t.meshed_refresh_t_setup_ms).epsilon(0.1));
    CHECK(m.meshed_t_tri_ms == Approx(t.meshed_t_tri_ms).epsilon(0.1));
    CHECK(m.imposter_t_setup_ms == Approx(t.imposter_t_setup_ms).epsilon(0.1));
    CHECK(m.imposter_t_pix_ms == Approx(t.imposter_t_pix_ms).epsilon(0.1));

    // the file holds the model
    const tcr::CostModel read = tcr::read_cost_model(path);
    CHECK(read.t_tri_ms == Approx(m.t_tri_ms));
    CHECK(read.meshed_t_tri_ms == Approx(m.meshed_t_tri_ms));
    CHECK(read.noise_rel == Approx(m.noise_rel));
    std::remove(path.c_str());
}

TEST_CASE("calibration leaves uncalibrated the ways a renderer does not draw, and rejects bad arguments", "[tcr][calibration]") {
    const Meshes meshes;
    ModelRenderer renderer(meshes.views, truth(), 0.0, false);
    const tcr::Calibration c = tcr::calibrate(renderer, {meshes.views[0]});
    CHECK(c.samples == 17);
    CHECK(c.model.t_tri_ms + c.model.t_vert_ms > 0);
    CHECK_FALSE(c.model.has_flat());
    CHECK_FALSE(c.model.has_textured());
    CHECK_FALSE(c.model.has_imposters());
    CHECK_FALSE(c.model.has_meshed());

    CHECK_THROWS_AS(tcr::calibrate(renderer, {}), tom::ArgumentError);
    CHECK_THROWS_AS(tcr::calibrate(renderer, {nullptr}), tom::ArgumentError);
    tcr::CalibrationParams unwritable;
    unwritable.path = "/nonexistent-dir/calibration.txt";
    const size_t frames = renderer.frames;
    CHECK_THROWS_AS(tcr::calibrate(renderer, {meshes.views[0]}, unwritable), tom::IoError);
    CHECK(renderer.frames == frames);  // refused before timing
}
