// libtcr cost model: calibration recovers known coefficients from noisy samples; file round trip.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include <catch2/catch.hpp>

#include "tom/errors.h"
#include "tcr/model.h"

TEST_CASE("calibration recovers known coefficients from synthetic noisy samples", "[tcr][calibration]") {
    tcr::CostModel truth;
    truth.t_setup_ms = 0.02;
    truth.t_tri_ms = 2e-5;
    truth.t_vert_ms = 1e-5;
    truth.t_pix_ms = 1e-6;
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 0.01);
    std::uniform_real_distribution<double> tris(100, 200000), pix(100, 2e6);
    std::vector<tcr::CostSample> samples;
    for (int i = 0; i < 400; ++i) {
        tcr::CostSample s;
        s.triangles = tris(rng);
        s.vertices = s.triangles * (0.45 + 0.1 * (i % 3));
        s.pixels = pix(rng);
        s.time_ms = truth.object_ms(s.triangles, s.vertices, s.pixels) * (1.0 + noise(rng));
        samples.push_back(s);
    }
    const tcr::CalibrationResult r = tcr::fit_cost_model(samples);
    INFO("setup " << r.model.t_setup_ms << " tri " << r.model.t_tri_ms << " vert " << r.model.t_vert_ms << " pix " << r.model.t_pix_ms);
    CHECK(r.model.t_pix_ms == Approx(truth.t_pix_ms).epsilon(0.05));
    // tri and vert are collinear-ish (vertices ~ half the triangles): check their combination
    const double per_tri_truth = truth.t_tri_ms + 0.55 * truth.t_vert_ms, per_tri = r.model.t_tri_ms + 0.55 * r.model.t_vert_ms;
    CHECK(per_tri == Approx(per_tri_truth).epsilon(0.05));
    CHECK(r.mean_relative_error < 0.03);
    CHECK(r.geometry_bound > 50);
    CHECK(r.fill_bound > 50);
}

TEST_CASE("the calibration file round-trips and rejects bad lines with file and line", "[tcr][calibration]") {
    namespace fs = std::filesystem;
    const std::string path = (fs::temp_directory_path() / "tcr_calibration_test.txt").string();
    tcr::CostModel m;
    m.t_init_ms = 0.5;
    m.t_final_ms = 0.25;
    m.t_setup_ms = 0.01;
    m.t_tri_ms = 3e-5;
    m.t_vert_ms = 1e-5;
    m.t_pix_ms = 2e-6;
    m.safety_ms = 1.0;
    tcr::write_cost_model(path, m, "test");
    const tcr::CostModel r = tcr::read_cost_model(path);
    CHECK(r.t_init_ms == Approx(m.t_init_ms));
    CHECK(r.t_tri_ms == Approx(m.t_tri_ms));
    CHECK(r.safety_ms == Approx(m.safety_ms));
    std::ofstream(path) << "t_tri_ms 1e-5\nt_pix_ms banana\n";
    try {
        tcr::read_cost_model(path);
        FAIL("accepted a bad line");
    } catch (const tom::ParseError& e) {
        CHECK(std::string(e.what()).find(path + ":2") != std::string::npos);
    }
    fs::remove(path);
}

TEST_CASE("object cost is geometry or fill bound, and r_min is where they meet", "[tcr]") {
    tcr::CostModel m;
    m.t_setup_ms = 0.1;
    m.t_tri_ms = 1e-4;
    m.t_pix_ms = 1e-5;
    CHECK(m.object_ms(1000, 0, 100) == Approx(0.1 + 0.1));     // geometry bound
    CHECK(m.object_ms(10, 0, 100000) == Approx(0.1 + 1.0));    // fill bound
    CHECK(m.min_useful_triangles(100000, 0) == Approx(10000));  // below it, fewer triangles save nothing
    CHECK(m.object_ms(m.min_useful_triangles(100000, 0), 0, 100000) == Approx(m.object_ms(1, 0, 100000)));
    // half the object outside the frustum: half its geometry time; fill (the clipped rectangle) as is
    CHECK(m.object_ms(1000, 0, 100, 0.5) == Approx(0.1 + 0.05));
    CHECK(m.object_ms(10, 0, 100000, 0.5) == Approx(0.1 + 1.0));
}
