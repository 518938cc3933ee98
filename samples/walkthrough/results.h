#pragma once
// The walkthrough's results: a row per frame, a summary per selector (as a table, JSON and
// CSV), the images scored against full detail, and the renderer's own noise.

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "renderer.h"
#include "world.h"

namespace walk {

struct Row {
    uint32_t frame, visible_objects, drawn_objects, flat_objects, imposters, refreshes, meshed, textured;
    uint64_t visible_triangles, drawn_triangles;
    double predicted_ms, measured_ms, render_ms, cull_ms, optimize_ms, extract_ms, benefit, gap;
};

struct Summary {
    std::string selector;
    uint32_t frames = 0;
    double budget_ms = 0;
    double mean = 0, max = 0, std = 0, compute_mean = 0, compute_max = 0, over = 0, prediction_error = 0, drawn = 0, visible = 0, gap = NAN;
    double flat_mean = 0, imposters_mean = 0, refreshes_mean = 0;  // objects drawn flat-shaded, as imposters, imposters renewed, a frame
    double meshed_mean = 0;  // of the imposters, meshed ones, a frame
    double textured_mean = 0;  // objects drawn texture-mapped, a frame
    // the image against full detail (--quality-every): SSIM and PSNR over the measured frames
    uint32_t quality_frames = 0;
    double ssim_mean = NAN, ssim_min = NAN, psnr_mean = NAN;
};

Summary summarize(const std::string& selector, double budget, const std::vector<Row>& rows);

// The full-detail frame a measured frame is compared with (--quality-every): every instance at
// its mesh's full resolution, no budget, in the colour the recorded frames use; drawn once per
// measured frame for all selectors, after their paths.
struct Reference {
    std::vector<uint32_t> indices;  // each mesh's full triangles, one mesh after another
    std::vector<Renderer::Draw> draws;
    std::string folder;             // OUT/quality: SELECTOR-FRAME.png beside reference-FRAME.png

    /// Empties OUT/quality for this run's images.
    Reference(const World& w, const std::vector<uint32_t>& handles, const std::string& out);
    /// The frame on the renderer now, as SELECTOR-FRAME.png.
    void save(Renderer& renderer, const std::string& selector, uint32_t frame) const;
    /// The reference's frame as reference-FRAME.png, when not there yet.
    void save_reference(Renderer& renderer, const tcr::Camera& cam, uint32_t frame) const;
};

/// SSIM and PSNR of every measured frame against its reference, by scikit-image
/// (scripts/image-quality.py), into the summaries and OUT/quality.csv.
void score_quality(const Reference& ref, const std::string& out, std::vector<Summary>& summaries);

/// The path's frames and viewport, and the budget a run holds.
struct PathSpec {
    uint32_t frames, width, height;
    double budget_ms;
};

/// The renderer's own variation, which no selector can remove: viewpoint A's frame, as the exact
/// selector plans it at the budget once its model correction has settled on 10 frames there,
/// drawn `count` times in a row. The spread of identical frames and how it comes in runs.
nlohmann::ordered_json noise_test(const World& w, const PathSpec& path, const tcr::CostModel& model, Renderer& renderer, const std::vector<uint32_t>& handles,
                                  uint32_t count);
/// The noise test as text.
void print_noise(const nlohmann::ordered_json& j, const PathSpec& path, const std::string& renderer);

/// OUT/frames-SELECTOR.csv: one row a frame.
void write_frames_csv(const std::string& path, const std::vector<Row>& rows);
/// A summary as the JSON of --json and summary.json; `representations`: what the menu offered.
nlohmann::ordered_json summary_json(const Summary& s, const std::string& representations, bool simulated, uint32_t frames);
/// The summaries as the table tcrwalk prints.
void print_table(const std::vector<Summary>& summaries, bool quality);

} // namespace walk
