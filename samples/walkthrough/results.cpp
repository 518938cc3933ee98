// The walkthrough's results (results.h).

#include "results.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "tcr/governor.h"
#include "tom/extract.h"

namespace fs = std::filesystem;

namespace walk {
Summary summarize(const std::string& selector, double budget, const std::vector<Row>& rows) {
    Summary s;
    s.selector = selector;
    s.frames = uint32_t(rows.size());
    s.budget_ms = budget;
    double gap_sum = 0;
    int gaps = 0, predicted = 0;
    for (const Row& r : rows) {
        s.mean += r.measured_ms / rows.size();
        s.max = std::max(s.max, r.measured_ms);
        const double compute = r.cull_ms + r.optimize_ms;
        s.compute_mean += compute / rows.size();
        s.compute_max = std::max(s.compute_max, compute);
        s.over += (r.measured_ms > 1.1 * budget) ? 1.0 / rows.size() : 0.0;
        s.drawn += double(r.drawn_triangles) / rows.size();
        s.visible += double(r.visible_triangles) / rows.size();
        s.flat_mean += double(r.flat_objects) / rows.size();
        s.imposters_mean += double(r.imposters) / rows.size();
        s.refreshes_mean += double(r.refreshes) / rows.size();
        s.meshed_mean += double(r.meshed) / rows.size();
        s.textured_mean += double(r.textured) / rows.size();
        if (r.predicted_ms > 0) {
            s.prediction_error += std::abs(r.predicted_ms - r.measured_ms) / r.measured_ms;
            ++predicted;
        }
        if (!std::isnan(r.gap)) gap_sum += r.gap, ++gaps;
    }
    for (const Row& r : rows) s.std += (r.measured_ms - s.mean) * (r.measured_ms - s.mean) / rows.size();
    s.std = std::sqrt(s.std);
    s.prediction_error = predicted ? s.prediction_error / predicted : NAN;
    if (gaps) s.gap = gap_sum / gaps;
    return s;
}

namespace {

std::string frame_name(uint32_t frame) {
    char n[16];
    std::snprintf(n, sizeof n, "%05u", frame);
    return n;
}

} // namespace

Reference::Reference(const World& w, const std::vector<uint32_t>& handles, const std::string& out) : folder((fs::path(out) / "quality").string()) {
    // each mesh's full triangles once, with its part ranges; every instance draws them
    std::vector<std::vector<tom::PartDraw>> parts(w.meshes.size());
    std::vector<size_t> first(w.meshes.size());
    for (size_t m = 0; m < w.meshes.size(); ++m) {
        const tom::MeshView& mesh = *w.meshes[m];
        first[m] = indices.size();
        indices.resize(indices.size() + size_t(mesh.triangle_count) * 3);
        parts[m].resize(tom::part_count(mesh));
        tom::extract_parts(mesh, mesh.vertex_count, indices.data() + first[m], size_t(mesh.triangle_count) * 3, parts[m].data());
    }
    for (size_t id = 0; id < w.scene.instances.size(); ++id) {  // one draw a part, textured where it has an image
        const uint32_t m = w.scene.instances[id].mesh;
        for (uint32_t p = 0; p < parts[m].size(); ++p) {
            const tom::PartDraw& part = parts[m][p];
            if (part.index_count == 0) continue;
            walk::Renderer::Draw d{handles[m], w.transforms[id].data(), first[m] + part.first_index, part.index_count, {kSand[0], kSand[1], kSand[2]}};
            if (w.textured[m] && w.image_handles[m][p] >= 0) d.shading = walk::Renderer::Shading::textured, d.image = uint32_t(w.image_handles[m][p]);
            draws.push_back(d);
        }
    }
    fs::remove_all(folder);
    fs::create_directories(folder);
}
void Reference::save(Renderer& renderer, const std::string& selector, uint32_t frame) const {
    if (!renderer.save_png((fs::path(folder) / (selector + "-" + frame_name(frame) + ".png")).string())) throw std::runtime_error("cannot write into " + folder);
}
void Reference::save_reference(Renderer& renderer, const tcr::Camera& cam, uint32_t frame) const {
    const fs::path path = fs::path(folder) / ("reference-" + frame_name(frame) + ".png");
    if (fs::exists(path)) return;
    renderer.render(cam.view, cam.projection, draws, indices, indices.size());
    if (!renderer.save_png(path.string())) throw std::runtime_error("cannot write " + path.string());
}

void score_quality(const Reference& ref, const std::string& out, std::vector<Summary>& summaries) {
    const std::string command = "/usr/bin/python3 '" TOM_IMAGE_QUALITY_SCRIPT "' '" + ref.folder + "'";
    std::FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) throw std::runtime_error("cannot run " + command);
    std::string text;
    char buffer[4096];
    for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) text.append(buffer, n);
    if (::pclose(pipe) != 0) throw std::runtime_error("image scoring failed (" + command + "); python3-skimage comes with scripts/install-deps.sh");
    std::map<std::string, std::vector<std::pair<double, double>>> scores;  // selector -> (ssim, psnr) per frame
    std::ofstream csv(fs::path(out) / "quality.csv");
    csv << "selector,frame,ssim,psnr\n";
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
        if (line.empty()) continue;
        const nlohmann::json j = nlohmann::json::parse(line);
        scores[j.at("selector").get<std::string>()].push_back({j.at("ssim").get<double>(), j.at("psnr").get<double>()});
        csv << j.at("selector").get<std::string>() << ',' << j.at("frame").get<uint32_t>() << ',' << j.at("ssim").get<double>() << ',' << j.at("psnr").get<double>() << '\n';
    }
    for (Summary& s : summaries) {
        const auto it = scores.find(s.selector);
        if (it == scores.end() || it->second.empty()) continue;
        double ssim = 0, psnr = 0, least = 1;
        for (const auto& [a, b] : it->second) ssim += a, psnr += b, least = std::min(least, a);
        s.quality_frames = uint32_t(it->second.size());
        s.ssim_mean = ssim / double(it->second.size());
        s.ssim_min = least;
        s.psnr_mean = psnr / double(it->second.size());
    }
}

nlohmann::ordered_json noise_test(const World& w, const PathSpec& path, const tcr::CostModel& model, Renderer& renderer, const std::vector<uint32_t>& handles,
                                  uint32_t count) {
    uint32_t shots[3];
    walk::viewpoints(path.frames, shots);
    tcr::Runtime rt(model, tcr::SelectorKind::exact);
    add_objects(rt, w);
    const tcr::Camera cam = camera_for(shots[0], path.frames, path.width, path.height);
    tcr::FrameParams fp;
    fp.camera = cam;
    fp.budget_ms = path.budget_ms;
    std::vector<uint32_t> indices;
    std::vector<walk::Renderer::Draw> draws;
    std::vector<walk::Renderer::Capture> captures;  // (the levels alone: none)
    size_t at = 0;
    for (int settle = 0; settle < 10; ++settle) {
        rt.plan_frame(fp);
        at = extract_frame(w, rt, handles, kSand, indices, draws, captures);
        const auto t0 = Clock::now();
        renderer.render(cam.view, cam.projection, draws, indices, at);
        fp.previous_frame_ms = ms_since(t0);
    }
    const tcr::FrameReport& r = rt.last_frame();
    std::vector<double> times;
    for (uint32_t k = 0; k < count; ++k) {
        const auto t0 = Clock::now();
        renderer.render(cam.view, cam.projection, draws, indices, at);
        times.push_back(ms_since(t0));
    }
    std::vector<double> sorted = times;
    std::sort(sorted.begin(), sorted.end());
    auto quantile = [&](double q) { return sorted[size_t(q * double(sorted.size() - 1) + 0.5)]; };
    const double median = quantile(0.5);
    double mean = 0, var = 0, lag1 = 0;
    for (double t : times) mean += t / double(count);
    for (double t : times) var += (t - mean) * (t - mean) / double(count);
    for (size_t k = 1; k < times.size(); ++k) lag1 += (times[k] - mean) * (times[k - 1] - mean) / double(count - 1);
    // means of 10 frames in a row: a slow variation moves them, a fast one averages out
    double block_lo = INFINITY, block_hi = 0;
    for (size_t k = 0; k + 10 <= times.size(); k += 10) {
        const double b = std::accumulate(times.begin() + ptrdiff_t(k), times.begin() + ptrdiff_t(k + 10), 0.0) / 10.0;
        block_lo = std::min(block_lo, b), block_hi = std::max(block_hi, b);
    }
    nlohmann::ordered_json j;
    j["frame"] = shots[0];
    j["renders"] = count;
    j["triangles"] = r.triangles;
    j["objects"] = r.drawn;
    j["median_ms"] = median;
    j["std_percent"] = 100.0 * std::sqrt(var) / median;
    j["p5_percent"] = 100.0 * quantile(0.05) / median;
    j["p95_percent"] = 100.0 * quantile(0.95) / median;
    j["lag1_autocorrelation"] = var > 0 ? lag1 / var : 0.0;
    j["frame_to_frame_percent"] = 100.0 * tcr::frame_to_frame(times);  // what calibration stores as noise_rel
    j["block10_percent"] = {100.0 * block_lo / median, 100.0 * block_hi / median};
    return j;
}

void print_noise(const nlohmann::ordered_json& j, const PathSpec& path, const std::string& renderer) {
    std::printf("viewpoint A (frame %u of %u), %llu triangles in %u objects, drawn %u times in a row on %s:\n"
                "  median %.2f ms; standard deviation %.1f%% of it; 5th / 95th percentile %.0f%% / %.0f%%\n"
                "  lag-1 autocorrelation %.2f; means of 10 frames in a row from %.0f%% to %.0f%%; frame to frame %.1f%%\n",
                j["frame"].get<uint32_t>(), path.frames, static_cast<unsigned long long>(j["triangles"].get<uint64_t>()), j["objects"].get<uint32_t>(),
                j["renders"].get<uint32_t>(), renderer.c_str(), j["median_ms"].get<double>(), j["std_percent"].get<double>(), j["p5_percent"].get<double>(),
                j["p95_percent"].get<double>(), j["lag1_autocorrelation"].get<double>(), j["block10_percent"][0].get<double>(),
                j["block10_percent"][1].get<double>(), j["frame_to_frame_percent"].get<double>());
}

void write_frames_csv(const std::string& path, const std::vector<Row>& rows) {
    std::ofstream csv(path);
    csv << "frame,visible_objects,drawn_objects,visible_triangles,drawn_triangles,predicted_ms,measured_ms,render_ms,cull_ms,optimize_ms,extract_ms,benefit,gap,"
           "flat_objects,imposters,imposter_refreshes,meshed_imposters,textured_objects\n";
    for (const Row& r : rows)
        csv << r.frame << ',' << r.visible_objects << ',' << r.drawn_objects << ',' << r.visible_triangles << ',' << r.drawn_triangles << ',' << r.predicted_ms
            << ',' << r.measured_ms << ',' << r.render_ms << ',' << r.cull_ms << ',' << r.optimize_ms << ',' << r.extract_ms << ',' << r.benefit << ','
            << (std::isnan(r.gap) ? std::string("") : std::to_string(r.gap)) << ',' << r.flat_objects << ',' << r.imposters << ',' << r.refreshes << ','
            << r.meshed << ',' << r.textured << '\n';
    if (!csv) throw std::runtime_error("cannot write " + path);
}

nlohmann::ordered_json summary_json(const Summary& s, const std::string& representations, bool simulated, uint32_t frames) {
    auto or_null = [](double x) { return std::isnan(x) ? nlohmann::json(nullptr) : nlohmann::json(x); };
    uint32_t shots[3];
    viewpoints(frames, shots);
    nlohmann::ordered_json j;
    j["selector"] = s.selector;
    j["frames"] = s.frames;
    j["budget_ms"] = s.budget_ms;
    j["frame_ms"] = {{"mean", s.mean}, {"max", s.max}, {"std", s.std}};
    j["compute_ms"] = {{"mean", s.compute_mean}, {"max", s.compute_max}};
    j["over_budget_fraction"] = s.over;
    j["prediction_error"] = or_null(s.prediction_error);
    j["drawn_triangles_mean"] = s.drawn;
    j["visible_triangles_mean"] = s.visible;
    j["gap_mean"] = or_null(s.gap);
    j["quality_frames"] = s.quality_frames;
    j["ssim_mean"] = or_null(s.ssim_mean);
    j["ssim_min"] = or_null(s.ssim_min);
    j["psnr_mean"] = or_null(s.psnr_mean);
    j["representations"] = representations;
    j["flat_objects_mean"] = s.flat_mean;
    j["textured_objects_mean"] = s.textured_mean;
    j["imposters_drawn_mean"] = s.imposters_mean;
    j["imposter_refreshes_mean"] = s.refreshes_mean;
    j["meshed_imposters_mean"] = s.meshed_mean;
    j["simulated"] = simulated;
    j["viewpoint_frames"] = {{"A", shots[0]}, {"B", shots[1]}, {"C", shots[2]}};  // the screenshots' frames
    return j;
}

void print_table(const std::vector<Summary>& summaries, bool quality) {
    std::printf("\n%-8s | %23s | %17s | %7s | %7s | %12s %12s | %34s%s\n", "", "frame time ms", "compute ms", ">1.1 B", "pred.", "drawn", "visible",
                "objects a frame", quality ? " | image vs full detail" : "");
    std::printf("%-8s | %7s %7s %7s | %8s %8s | %7s | %7s | %12s %12s | %6s %6s %6s %6s %6s%s\n", "selector", "mean", "max", "std", "mean", "max", "frames",
                "error", "tris mean", "tris mean", "flat", "textur", "impost", "meshed", "renew", quality ? " | SSIM mean    min  PSNR dB" : "");
    for (const Summary& s : summaries) {
        std::printf("%-8s | %7.2f %7.2f %7.2f | %8.3f %8.3f | %6.1f%% | %6.1f%% | %12.0f %12.0f | %6.1f %6.1f %6.1f %6.1f %6.2f", s.selector.c_str(), s.mean,
                    s.max, s.std, s.compute_mean, s.compute_max, 100 * s.over, std::isnan(s.prediction_error) ? 0.0 : 100 * s.prediction_error, s.drawn,
                    s.visible, s.flat_mean, s.textured_mean, s.imposters_mean, s.meshed_mean, s.refreshes_mean);
        if (quality) std::printf(" |    %.4f %.4f %8.2f", s.ssim_mean, s.ssim_min, s.psnr_mean);
        std::printf("\n");
    }
    if (quality)
        std::printf("image: %u frames of each selector against the same view at full detail (scikit-image; identical frames count as 99 dB)\n",
                    summaries.empty() ? 0 : summaries.front().quality_frames);
}

} // namespace walk
