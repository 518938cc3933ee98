// tcrwalk: the reference integration of libtom and libtcr. Renders a scene of TOM objects
// headless (Mesa's llvmpipe through OSMesa) along a path with Funkhouser's hard viewpoints,
// under each selector, and measures whether the frame budget holds.
//
// Frame = plan (cull, measure, optimise: libtcr) + extract (libtom index buffers) + render (one
// indexed draw per object, glFinish). Following Gobbetti & Bouvier, the non-rendering part is
// measured and the renderer gets the rest of the budget.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "images.h"
#include "renderer.h"
#include "scene.h"
#include "tcr/governor.h"
#include "tcr/model.h"
#include "tcr/runtime.h"
#include "tcr/view.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tool_common.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

using tcr::frame_to_frame;

// The scene with its meshes mapped and each instance's transform.
struct World {
    walk::Scene scene;
    std::vector<tom::File> files;
    std::vector<const tom::MeshView*> meshes;
    std::vector<std::array<float, 16>> transforms;
    uint64_t full_triangles = 0;
    // per mesh, per part: its material's base-colour image (stored in the .tom, or a file found
    // beside it), or none; a mesh with texture coordinates and at least one such image is textured
    std::vector<std::vector<walk::PartImage>> part_images;
    std::vector<uint8_t> textured;
    // the renderer's handles of those images (-1: none), once it has them (load_images)
    std::vector<std::vector<int32_t>> image_handles;
};

// The base-colour image of each part of mesh `m`; a mesh with texture coordinates and at least
// one such image is textured.
void find_images(World& w, size_t m, const fs::path& tom_path) {
    std::vector<walk::PartImage> images = walk::find_part_images(w.files[m], 0, tom_path);
    const bool any = std::any_of(images.begin(), images.end(), [](const walk::PartImage& i) { return !i.key.empty(); });
    w.textured.push_back(w.meshes[m]->texcoords && any);
    w.part_images.push_back(std::move(images));
}

World load_world(const std::string& scene_path) {
    World w;
    w.scene = walk::read_scene(scene_path);
    const fs::path dir = fs::path(scene_path).parent_path();
    for (const std::string& m : w.scene.meshes) {
        const fs::path p = fs::path(m).is_absolute() ? fs::path(m) : dir / m;
        w.files.push_back(tom::File::open(p.string()));
        if (w.files.back().mesh_count() == 0) throw tom::Error(p.string() + ": no mesh");
    }
    for (const tom::File& f : w.files) w.meshes.push_back(&f.mesh(0));
    for (size_t m = 0; m < w.meshes.size(); ++m)
        find_images(w, m, fs::path(w.scene.meshes[m]).is_absolute() ? fs::path(w.scene.meshes[m]) : dir / w.scene.meshes[m]);
    for (const walk::Instance& i : w.scene.instances) {
        const tom::MeshView& m = *w.meshes[i.mesh];
        double d2 = 0;
        float c[3];
        for (int k = 0; k < 3; ++k) {
            d2 += double(m.bounds_max[k] - m.bounds_min[k]) * (m.bounds_max[k] - m.bounds_min[k]);
            c[k] = 0.5f * (m.bounds_min[k] + m.bounds_max[k]);
        }
        const float s = float(i.size / std::max(1e-9, std::sqrt(d2)));
        const float a = i.yaw_deg * 3.14159265f / 180.0f, ca = std::cos(a), sa = std::sin(a);
        // T(x,y,z) R_y(yaw) S(s) T(-centre), column-major
        std::array<float, 16> t{};
        t[0] = s * ca, t[2] = -s * sa, t[5] = s, t[8] = s * sa, t[10] = s * ca, t[15] = 1;
        t[12] = i.x - (t[0] * c[0] + t[4] * c[1] + t[8] * c[2]);
        t[13] = i.y - (t[1] * c[0] + t[5] * c[1] + t[9] * c[2]);
        t[14] = i.z - (t[2] * c[0] + t[6] * c[1] + t[10] * c[2]);
        w.transforms.push_back(t);
        w.full_triangles += m.triangle_count;
    }
    return w;
}

// The parts' images into the renderer (each once); none without a renderer (--simulate).
void load_images(World& w, walk::Renderer* renderer) {
    std::map<std::string, int32_t> loaded;
    w.image_handles.clear();
    for (const std::vector<walk::PartImage>& parts : w.part_images) {
        std::vector<int32_t> handles(parts.size(), -1);
        if (renderer)
            for (size_t p = 0; p < parts.size(); ++p) handles[p] = walk::load_image(parts[p], *renderer, loaded);
        w.image_handles.push_back(std::move(handles));
    }
}

tcr::Camera camera_for(uint32_t f, uint32_t frames, uint32_t width, uint32_t height) {
    const walk::CameraPose pose = walk::path_pose(f, frames);
    tcr::Camera c;
    const float up[3] = {0, 1, 0};
    tcr::look_at(pose.eye, pose.target, up, c.view);
    tcr::perspective(60.0f * 3.14159265f / 180.0f, float(width) / float(height), 0.05f, 200.0f, c.projection);
    c.viewport_width = width;
    c.viewport_height = height;
    return c;
}

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

// A selector's name in --selector: a libtcr selector, "none", or either with "-levels" (the
// TOM levels alone, for comparing the menu with them in one run).
bool ends_with_levels(const std::string& s) { return s.size() > 7 && s.compare(s.size() - 7, 7, "-levels") == 0; }
std::string base_selector(const std::string& s) { return ends_with_levels(s) ? s.substr(0, s.size() - 7) : s; }

// Every instance of the scene into the runtime, in scene order (its object ids are the instances').
void add_objects(tcr::Runtime& rt, const World& w) {
    for (size_t i = 0; i < w.scene.instances.size(); ++i) {
        const uint32_t id = rt.add_object(*w.meshes[w.scene.instances[i].mesh], w.transforms[i].data(), w.scene.instances[i].weight);
        rt.set_textured(id, w.textured[w.scene.instances[i].mesh] != 0);
    }
}

// Object colours of the shaded view, and of the warm-up frames (never shown).
constexpr float kSand[3] = {0.85f, 0.78f, 0.62f}, kGrey[3] = {0.8f, 0.8f, 0.8f};
// The representation view's colours: smooth-shaded levels, flat-shaded levels, simple and meshed imposters.
constexpr float kSmoothColor[3] = {0.3f, 0.5f, 0.9f}, kFlatColor[3] = {0.95f, 0.6f, 0.15f}, kImposterColor[3] = {0.85f, 0.2f, 0.75f},
                kMeshedColor[3] = {0.2f, 0.75f, 0.35f}, kTexturedColor[3] = {0.95f, 0.85f, 0.2f};
const float* representation_color(tcr::Representation r) {
    switch (r) {
    case tcr::Representation::flat: return kFlatColor;
    case tcr::Representation::simple_imposter: return kImposterColor;
    case tcr::Representation::meshed_imposter: return kMeshedColor;
    case tcr::Representation::textured: return kTexturedColor;
    default: return kSmoothColor;
    }
}

// Hue from red (coarse) through green to blue (full resolution), for the LOD view.
void lod_color(double fraction, float out[3]) {
    const double t = std::min(1.0, std::max(0.0, std::log10(std::max(fraction, 1e-3)) / 3.0 + 1.0));  // 0.1% .. 100%
    out[0] = float(std::max(0.0, 1.0 - 2.0 * t));
    out[1] = float(1.0 - std::abs(2.0 * t - 1.0));
    out[2] = float(std::max(0.0, 2.0 * t - 1.0));
}

struct Options {
    std::string scene, calibration, out;
    std::vector<std::string> selectors;
    double budget_ms = 40;
    uint32_t frames = 300;
    bool simulate = false, json = false;
    bool sequential = false;      // each selector's whole path in turn instead of frame by frame (run_paths)
    uint32_t width = 640, height = 480;
    double optimize_share = 0.1;  // the optimiser's deadline, as a share of the budget
    double hysteresis = 0.05;
    double noise = 1.0;           // simulated: noise in standard deviations of the calibrated noise (clamped to +-2)
    double safety_sigma = 0.75;   // safety allowance in the renderer's frame-to-frame noise (noise_rel, then the run's own: PathRun::follow_noise): less lets more frames over 1.1x the budget, more leaves the budget underused
    uint64_t seed = 1;
    uint32_t quality_every = 0;   // every this-th recorded frame is compared with full detail (0: none)
    std::string representations = "all";  // "levels": TOM levels smooth-shaded only; "all": flat shading, texture mapping and imposters too; "simple": all but meshed imposters
    uint32_t meshed_grid = 8;             // a meshed imposter's depth mesh, cells a side (tcr::Menu)
    double flat_error_factor = 2.0;       // flat shading's projected error over smooth's (tcr::Menu)
    double imposter_max_px = 1.0;         // an imposter is reused while its distortion stays within this
    double imposter_error_factor = 1.0;   // an imposter's error in the benefit over its geometric error (tcr::Menu)
    double refresh_share = 0.25;          // a frame renews at most what this share of the budget pays for
};

// Grows `v` to hold at least `n` elements, by doubling, and touches the new memory once, so no
// frame pays page faults for its index array.
void ensure(std::vector<uint32_t>& v, size_t n) {
    if (v.size() >= n) return;
    v.resize(std::max(n, v.size() * 2), 0u);
}

// The frame the runtime planned, extracted: each drawn object's level into `indices` (grown as
// needed), one draw per object, or per part of a multi-part object (as the cost model counts
// them), in `color` and the shading the runtime chose; an imposter as its quad or depth mesh,
// after, when the runtime renews it, its level drawn into its texture (a capture, which for a
// meshed imposter also remakes its depth mesh). Object id's texture is the renderer's slot
// `slots + id`, so runs that share a renderer keep their captures apart. Returns the frame's
// index count.
size_t extract_frame(const World& w, const tcr::Runtime& rt, const std::vector<uint32_t>& mesh_handles, const float color[3],
                     std::vector<uint32_t>& indices, std::vector<walk::Renderer::Draw>& draws, std::vector<walk::Renderer::Capture>& captures,
                     uint32_t slots = 0) {
    using Shading = walk::Renderer::Shading;
    ensure(indices, size_t(rt.last_frame().triangles) * 3);
    draws.clear();
    captures.clear();
    size_t at = 0;
    tom::PartDraw parts[64];
    for (uint32_t id = 0; id < rt.object_count(); ++id) {
        const tcr::ObjectResult& obj = rt.object(id);
        if (!obj.drawn) continue;
        const uint32_t mesh = w.scene.instances[id].mesh;
        walk::Renderer::Draw d{mesh_handles[mesh], w.transforms[id].data(), at, 0, {color[0], color[1], color[2]}};
        d.tag = id;
        d.shading = obj.representation == tcr::Representation::flat ? Shading::flat : Shading::smooth;
        // texture-mapped where the plan says, and in a capture of a textured object (an
        // imposter keeps the best picture)
        const bool textured = obj.representation == tcr::Representation::textured || (tcr::is_imposter(obj.representation) && w.textured[mesh]);
        if (tcr::is_imposter(obj.representation)) {
            const tcr::ImposterState& im = rt.imposter(id);
            walk::Renderer::Draw quad = d;
            quad.shading = im.grid ? Shading::meshed : Shading::imposter;
            quad.texture = slots + id;
            if (!im.grid) tcr::imposter_quad(im, quad.corners);
            draws.push_back(quad);
            if (!obj.refresh) continue;
            walk::Renderer::Capture c{slots + id, im.texture_px, {}, {}, im.grid};
            tcr::imposter_camera(im, c.view, c.projection);
            d.capture = int32_t(captures.size());
            captures.push_back(c);
        }
        if (tom::part_count(*w.meshes[mesh]) > 64) {  // more than a draw list here holds: one draw
            const tom::Extracted e = rt.indices(id, indices.data() + at, indices.size() - at);
            d.index_count = e.triangle_count * 3;
            draws.push_back(d);
            at += size_t(e.triangle_count) * 3;
            continue;
        }
        const tom::Extracted e = rt.indices(id, indices.data() + at, indices.size() - at, parts);
        for (uint32_t p = 0; p < tom::part_count(*w.meshes[mesh]); ++p)
            if (parts[p].index_count > 0) {
                d.first = at + parts[p].first_index;
                d.index_count = parts[p].index_count;
                if (textured && w.image_handles[mesh][p] >= 0) {
                    walk::Renderer::Draw t = d;
                    t.shading = Shading::textured;
                    t.image = uint32_t(w.image_handles[mesh][p]);
                    draws.push_back(t);
                    continue;
                }
                draws.push_back(d);
            }
        at += size_t(e.triangle_count) * 3;
    }
    return at;
}

// The full-detail frame a measured frame is compared with (--quality-every): every instance at
// its mesh's full resolution, no budget, in the colour the recorded frames use; drawn once per
// measured frame for all selectors, after their paths.
struct Reference {
    std::vector<uint32_t> indices;  // each mesh's full triangles, one mesh after another
    std::vector<walk::Renderer::Draw> draws;
    std::string folder;             // OUT/quality: SELECTOR-FRAME.png beside reference-FRAME.png

    Reference(const World& w, const std::vector<uint32_t>& handles, const std::string& out) : folder((fs::path(out) / "quality").string()) {
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
    static std::string name(uint32_t frame) {
        char n[16];
        std::snprintf(n, sizeof n, "%05u", frame);
        return n;
    }
    // the frame on the renderer now, as SELECTOR-FRAME.png; the reference's, when not there yet
    void save(walk::Renderer& renderer, const std::string& selector, uint32_t frame) const {
        if (!renderer.save_png((fs::path(folder) / (selector + "-" + name(frame) + ".png")).string())) throw std::runtime_error("cannot write into " + folder);
    }
    void save_reference(walk::Renderer& renderer, const tcr::Camera& cam, uint32_t frame) const {
        const fs::path path = fs::path(folder) / ("reference-" + name(frame) + ".png");
        if (fs::exists(path)) return;
        renderer.render(cam.view, cam.projection, draws, indices, indices.size());
        if (!renderer.save_png(path.string())) throw std::runtime_error("cannot write " + path.string());
    }
};

// SSIM and PSNR of every measured frame against its reference, by scikit-image
// (scripts/image-quality.py), into the summaries and OUT/quality.csv.
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

// One selector's run along the path: the runtime and what it carries from frame to frame.
struct PathRun {
    const World& w;
    const Options& o;
    walk::Renderer* renderer;  // null: simulated
    const std::vector<uint32_t>& mesh_handles;
    const bool none;           // full detail, no budget
    const bool levels_only;    // "SELECTOR-levels": TOM levels smooth-shaded, whatever --representations says
    const uint32_t slots;      // its imposters' first texture slot in the shared renderer
    tcr::Runtime rt;
    tcr::FrameGovernor governor;  // the planning reserve, the feedback, the noise allowance, extraction in t_tri
    std::vector<uint32_t> indices;
    std::vector<walk::Renderer::Draw> draws;
    std::vector<walk::Renderer::Capture> captures;
    tcr::SimulatedRenderer simulated;  // without a renderer (--simulate): the calibrated noise, --noise times

    PathRun(const World& world, const std::string& selector, const Options& options, const tcr::CostModel& calibrated, walk::Renderer* r,
            const std::vector<uint32_t>& handles, uint32_t first_slot)
        : w(world), o(options), renderer(r), mesh_handles(handles), none(selector == "none"), levels_only(ends_with_levels(selector)), slots(first_slot),
          rt(calibrated, kind_of(selector)), governor(rt, calibrated, governor_params(options, none, r != nullptr)),
          simulated(options.noise * std::max(calibrated.noise_rel, 0.01), 1.0, options.seed) {
        add_objects(rt, w);
    }

    // "none" draws full detail: a budget no frame reaches. A simulated renderer's noise is the
    // calibration's: the allowance stays the calibrated one.
    static tcr::GovernorParams governor_params(const Options& o, bool none, bool rendered) {
        tcr::GovernorParams g;
        g.budget_ms = none ? 1e12 : o.budget_ms;
        g.safety_sigma = o.safety_sigma;
        g.follow_noise = rendered && !none;
        g.optimize_share = o.optimize_share;
        return g;
    }
    static tcr::SelectorKind kind_of(const std::string& selector) {
        tcr::SelectorKind kind = tcr::SelectorKind::exact;
        if (selector != "none") tcr::parse_selector(base_selector(selector), kind);
        return kind;
    }

    // The governor's warm-up frames at the path's start, not counted: the planning time, and the
    // extraction cost per triangle, which joins the model's per-triangle cost.
    void warm_up() {
        const tcr::Camera cam = camera_for(0, o.frames, o.width, o.height);
        while (governor.warming_up()) {
            const tcr::FrameReport& r = governor.plan_frame(frame_params(cam));
            ensure(indices, size_t(r.triangles) * 3);  // outside the timing
            const auto extract_start = Clock::now();
            const size_t at = extract_frame(w, rt, mesh_handles, kGrey, indices, draws, captures, slots);
            const double extract_ms = ms_since(extract_start);
            double render_ms = 0;
            if (renderer) {
                const auto render_start = Clock::now();
                renderer->render(cam.view, cam.projection, draws, indices, at, captures);
                render_ms = ms_since(render_start);
            } else {
                render_ms = simulated.frame_ms(r, governor.model());
            }
            governor.frame_done({extract_ms, render_ms});
        }
    }

    // The frame's request to the runtime (the governor sets its budget, feedback and deadline;
    // for "none": every visible object at full detail, its best way).
    tcr::FrameParams frame_params(const tcr::Camera& cam) const {
        tcr::FrameParams fp;
        fp.camera = cam;
        fp.hysteresis = o.hysteresis;
        fp.menu.flat = fp.menu.imposters = (o.representations == "all" || o.representations == "simple") && !levels_only;
        fp.menu.meshed = o.representations == "all" && !levels_only;
        fp.menu.textured = fp.menu.flat;
        fp.menu.meshed_grid = o.meshed_grid;
        fp.menu.flat_error_factor = o.flat_error_factor;
        fp.menu.imposter_max_px = o.imposter_max_px;
        fp.menu.imposter_error_factor = o.imposter_error_factor;
        fp.menu.refresh_share = o.refresh_share;
        if (none) {
            fp.menu = tcr::Menu();
            fp.menu.textured = true;
            fp.max_error_px = 0;
        }
        return fp;
    }

    // One frame: plan, extract, render (or simulate), and what the runtime is fed back.
    Row frame(uint32_t f, size_t& index_count) {
        const tcr::Camera cam = camera_for(f, o.frames, o.width, o.height);
        const auto frame_start = Clock::now();
        Row row{};
        row.frame = f;
        const double planning_reserve_ms = governor.planning_reserve_ms();
        const tcr::FrameReport& r = governor.plan_frame(frame_params(cam));
        row.cull_ms = r.cull_ms;
        row.optimize_ms = r.optimize_ms;
        row.visible_objects = r.visible;
        row.drawn_objects = r.drawn;
        row.flat_objects = r.flat;
        row.imposters = r.imposters;
        row.refreshes = r.refreshes;
        row.meshed = r.meshed;
        row.textured = r.textured;
        row.visible_triangles = r.visible_triangles;
        row.drawn_triangles = r.triangles;
        row.benefit = r.benefit;
        row.gap = r.gap;
        const auto extract_start = Clock::now();
        index_count = extract_frame(w, rt, mesh_handles, kSand, indices, draws, captures, slots);
        row.extract_ms = ms_since(extract_start);
        tcr::FrameTimes times;
        if (renderer) {
            const auto render_start = Clock::now();
            renderer->render(cam.view, cam.projection, draws, indices, index_count, captures);
            times = {row.extract_ms, ms_since(render_start), ms_since(frame_start)};
        } else {
            // simulated: extraction is in the simulated time, and the frame is the planning time
            // reserved plus it (the real cull and optimise times, which a busy machine can
            // stretch, stay in the compute columns)
            times = {0.0, simulated.frame_ms(r, governor.model()), -1.0};
        }
        row.render_ms = times.render_ms;
        row.measured_ms = times.frame_ms >= 0 ? times.frame_ms : planning_reserve_ms + times.render_ms;
        row.predicted_ms = governor.predicted_ms();
        governor.frame_done(times);
        return row;
    }

    // The frame as drawn, then each object coloured by its level (an imposter by the level in
    // its texture) and by its representation, as shots/SELECTOR-NAME{,-lod,-rep}.png; the
    // re-renders draw no captures (the textures are the frame's).
    void save_shots(const std::string& selector, char name, uint32_t f, size_t index_count) {
        const tcr::Camera cam = camera_for(f, o.frames, o.width, o.height);
        const std::string base = (fs::path(o.out) / "shots" / (selector + "-" + name)).string();
        fs::create_directories(fs::path(base).parent_path());
        renderer->save_png(base + ".png");
        std::vector<walk::Renderer::Draw> coloured = draws;
        for (walk::Renderer::Draw& d : coloured) {
            if (d.shading == walk::Renderer::Shading::textured) d.shading = walk::Renderer::Shading::smooth;  // the colour alone
            const tcr::ObjectResult& obj = rt.object(d.tag);
            const tom::MeshView& mesh = *w.meshes[w.scene.instances[d.tag].mesh];
            const uint32_t level = tcr::is_imposter(obj.representation) ? tom::active_triangle_count(mesh, rt.imposter(d.tag).vertices) : obj.triangles;
            lod_color(double(level) / mesh.triangle_count, d.color);
            d.tint = 1;
        }
        renderer->render(cam.view, cam.projection, coloured, indices, index_count);
        renderer->save_png(base + "-lod.png");
        for (walk::Renderer::Draw& d : coloured) {
            const float* c = representation_color(rt.object(d.tag).representation);
            std::copy(c, c + 3, d.color);
            d.tint = 0.7f;  // an imposter's picture shows through its colour
        }
        renderer->render(cam.view, cam.projection, coloured, indices, index_count);
        renderer->save_png(base + "-rep.png");
    }
};

// The selectors' runs along the path, interleaved: each selector's warm-up, then 8 frames at the
// path's first position, planned, drawn and fed back as every frame is but not recorded (the
// runtime's model correction starts from this scene's measured frames instead of the
// calibration's isolated objects, which would put the first frames over the budget while the
// correction caught up), then the recorded path, frame f of every selector in turn before frame
// f + 1, with screenshots at A, B and C. Interleaved, every selector meets the machine's slow and
// fast spells alike (run one after another, exact-levels drew 313k to 460k triangles a frame over
// one stretch of the path in three runs, more than the selectors differ); `--sequential` runs
// them one after another.
// Each run's imposters have their own texture slots in the shared renderer.
std::vector<Summary> run_paths(const World& w, const Options& o, const tcr::CostModel& calibrated, walk::Renderer* renderer,
                               const std::vector<uint32_t>& mesh_handles, std::vector<std::vector<Row>>& rows, const Reference* reference) {
    const uint32_t objects = uint32_t(w.scene.instances.size());
    std::vector<std::unique_ptr<PathRun>> paths;
    for (size_t k = 0; k < o.selectors.size(); ++k)
        paths.push_back(std::make_unique<PathRun>(w, o.selectors[k], o, calibrated, renderer, mesh_handles, uint32_t(k) * objects));
    uint32_t shots[3];
    walk::viewpoints(o.frames, shots);
    rows.assign(paths.size(), {});
    const int64_t settle = 8;
    // one selector's step (full detail has no budget to settle on: it starts at the path)
    auto step_of = [&](size_t k, int64_t step) {
        PathRun& path = *paths[k];
        if (path.none && step < 0) return;
        const uint32_t f = uint32_t(std::max<int64_t>(step, 0));
        size_t index_count = 0;
        const Row row = path.frame(f, index_count);
        if (step < 0) return;
        rows[k].push_back(row);
        const std::string& selector = o.selectors[k];
        const bool measured = reference && renderer && f % o.quality_every == 0;
        if (measured) reference->save(*renderer, selector, f);  // (off the clock: the frame was timed)
        if (renderer && !o.out.empty() && (f == shots[0] || f == shots[1] || f == shots[2]))
            path.save_shots(selector, f == shots[0] ? 'A' : (f == shots[1] ? 'B' : 'C'), f, index_count);
    };
    if (o.sequential) {
        for (size_t k = 0; k < paths.size(); ++k) {
            paths[k]->warm_up();
            for (int64_t step = -settle; step < int64_t(o.frames); ++step) step_of(k, step);
        }
    } else {
        for (const std::unique_ptr<PathRun>& path : paths) path->warm_up();
        for (int64_t step = -settle; step < int64_t(o.frames); ++step)
            for (size_t k = 0; k < paths.size(); ++k) step_of(k, step);
    }
    std::vector<Summary> summaries;
    for (size_t k = 0; k < paths.size(); ++k) summaries.push_back(summarize(o.selectors[k], o.budget_ms, rows[k]));
    return summaries;
}

// The renderer's own variation, which no selector can remove: viewpoint A's frame, as the exact
// selector plans it at the budget once its model correction has settled on 10 frames there,
// drawn `count` times in a row. The spread of identical frames and how it comes in runs.
nlohmann::ordered_json noise_test(const World& w, const Options& o, const tcr::CostModel& model, walk::Renderer& renderer,
                                  const std::vector<uint32_t>& handles, uint32_t count) {
    uint32_t shots[3];
    walk::viewpoints(o.frames, shots);
    tcr::Runtime rt(model, tcr::SelectorKind::exact);
    add_objects(rt, w);
    const tcr::Camera cam = camera_for(shots[0], o.frames, o.width, o.height);
    tcr::FrameParams fp;
    fp.camera = cam;
    fp.budget_ms = o.budget_ms;
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
    j["frame_to_frame_percent"] = 100.0 * frame_to_frame(times);  // what calibration stores as noise_rel
    j["block10_percent"] = {100.0 * block_lo / median, 100.0 * block_hi / median};
    return j;
}

constexpr double kCalibrationTriangles = 100000;

// The distinct vertices `indices` reference (all below n); `used` is scratch.
uint32_t referenced_vertices(const std::vector<uint32_t>& indices, uint32_t n, std::vector<uint8_t>& used) {
    used.assign(n, 0);
    uint32_t count = 0;
    for (const uint32_t v : indices) count += used[v] ? 0 : (used[v] = 1);
    return count;
}

// Renders sample objects at several resolutions and sizes, fits the cost model by least squares.
namespace calib {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

// The calibration's view: from the origin down -z, 60 degrees, the renderer's viewport.
tcr::Camera camera(const walk::Renderer& renderer) {
    tcr::Camera cam;
    const float eye[3] = {0, 0, 0}, target[3] = {0, 0, -1}, up[3] = {0, 1, 0};
    tcr::look_at(eye, target, up, cam.view);
    tcr::perspective(60.0f * 3.14159265f / 180.0f, float(renderer.width()) / float(renderer.height()), 0.05f, 200.0f, cam.projection);
    cam.viewport_width = renderer.width();
    cam.viewport_height = renderer.height();
    return cam;
}

// `count` renders of the same frame, each timed
std::vector<double> time_frames(walk::Renderer& renderer, const tcr::Camera& cam, const std::vector<walk::Renderer::Draw>& draws,
                                const std::vector<uint32_t>& indices, size_t index_count, int count) {
    std::vector<double> times;
    for (int r = 0; r < count; ++r) {
        const auto t0 = Clock::now();
        renderer.render(cam.view, cam.projection, draws, indices, index_count);
        times.push_back(ms_since(t0));
    }
    return times;
}

// One configuration of a calibration draw: a level of a mesh (scaled to diagonal 1) at a
// distance, in `copies` copies side by side (8, or 64 small ones for the per-draw cost).
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

// What the sampling draws reuse.
struct Frame {
    std::vector<uint32_t> indices;
    std::vector<walk::Renderer::Draw> draws;
    std::vector<std::array<float, 16>> models = std::vector<std::array<float, 16>>(64);
    std::vector<uint8_t> used;
};

// The time per object of one configuration, above the empty frame's: the copies drawn
// `repeats` times in the frame (up to 64), toward kCalibrationTriangles a frame, so that even a
// small level's time stands well above the empty frame's jitter; the median of 7 frames.
tcr::CostSample sample(const tom::MeshView& mesh, uint32_t handle, const Config& cfg, const tcr::Camera& cam, double empty_ms,
                       walk::Renderer& renderer, Frame& f, walk::Renderer::Shading shading = walk::Renderer::Shading::smooth, uint32_t image = 0) {
    double d2 = 0;
    float c[3];
    for (int k = 0; k < 3; ++k) {
        d2 += double(mesh.bounds_max[k] - mesh.bounds_min[k]) * (mesh.bounds_max[k] - mesh.bounds_min[k]);
        c[k] = 0.5f * (mesh.bounds_min[k] + mesh.bounds_max[k]);
    }
    const uint32_t n = tom::vertex_count_for_fraction(mesh, cfg.fraction);
    const uint32_t tris = tom::active_triangle_count(mesh, n);
    f.indices.resize(size_t(tris) * 3);
    tom::extract(mesh, n, f.indices.data(), f.indices.size());
    f.draws.clear();
    double pixels = 0;
    const float s = float(1.0 / std::sqrt(d2));
    const int copies = cfg.copies, columns = copies == 8 ? 4 : 8;
    const float spacing = copies == 8 ? cfg.distance * 0.42f : cfg.distance * 0.13f;
    const tcr::Box box{{mesh.bounds_min[0], mesh.bounds_min[1], mesh.bounds_min[2]}, {mesh.bounds_max[0], mesh.bounds_max[1], mesh.bounds_max[2]}};
    for (int k = 0; k < copies; ++k) {
        std::array<float, 16>& t = f.models[k];
        const float x = (float(k % columns) - 0.5f * (columns - 1)) * spacing, y = (float(k / columns) - 0.5f * (copies / columns - 1)) * spacing;
        t = {s, 0, 0, 0, 0, s, 0, 0, 0, 0, s, 0, x - s * c[0], y - s * c[1], -cfg.distance - s * c[2], 1};
        f.draws.push_back({handle, t.data(), 0, tris * 3, {kGrey[0], kGrey[1], kGrey[2]}});
        f.draws.back().shading = shading;
        f.draws.back().image = image;
        pixels += tcr::project_box(cam, t.data(), box).coverage_px;
    }
    const int repeats = std::max(1, std::min(64, int(std::ceil(kCalibrationTriangles / (double(tris) * copies)))));
    for (int rep = 1; rep < repeats; ++rep)
        for (int k = 0; k < copies; ++k) f.draws.push_back(f.draws[size_t(k)]);
    const double frame_ms = median(time_frames(renderer, cam, f.draws, f.indices, f.indices.size(), 7));
    tcr::CostSample out;
    out.triangles = tris;
    out.vertices = referenced_vertices(f.indices, n, f.used);  // what the renderer shades: a level's prefix may hold unused survivors
    out.pixels = pixels / copies;
    out.time_ms = std::max(0.0, frame_ms - empty_ms) / (copies * repeats);
    if (std::getenv("TCRWALK_DEBUG"))
        std::fprintf(stderr, "  sample level %.3f distance %.1f x%d: tris %u verts %u pixels %.0f time/object %.4f ms (frame %.3f)\n", cfg.fraction,
                     cfg.distance, copies, tris, n, out.pixels, out.time_ms, frame_ms);
    return out;
}

// The renderer's noise: one heavy frame (the draws of the last configuration, at the first
// mesh's full detail) drawn again and again; its relative variation frame to frame, and in
// `overall` its relative standard deviation.
double frame_noise(const tom::MeshView& mesh, uint32_t handle, const tcr::Camera& cam, walk::Renderer& renderer, Frame& f, double& overall) {
    f.indices.resize(size_t(mesh.triangle_count) * 3);
    tom::extract(mesh, mesh.vertex_count, f.indices.data(), f.indices.size());
    for (walk::Renderer::Draw& d : f.draws) d.index_count = mesh.triangle_count * 3, d.mesh = handle;
    const std::vector<double> times = time_frames(renderer, cam, f.draws, f.indices, f.indices.size(), 61);
    double mean = 0, var = 0;
    for (double t : times) mean += t / times.size();
    for (double t : times) var += (t - mean) * (t - mean) / times.size();
    overall = mean > 0 ? std::sqrt(var) / mean : 0.0;
    return frame_to_frame(times);
}

// Simple imposters' quads: 64 quads a frame (repeated toward 2,000 quads), each showing the
// next of `textures` textures from `texture` on (a frame's imposters each bind their own), each
// covering about `side_px` square pixels; the time per quad above the empty frame's, as a
// sample of no triangles (the fit's fill term: t_setup + t_pix pixels).
tcr::CostSample quad_sample(uint32_t texture, uint32_t textures, float side_px, const tcr::Camera& cam, double empty_ms, walk::Renderer& renderer, Frame& f) {
    f.draws.clear();
    const float distance = 10.0f;
    const float half = 0.5f * side_px * 2.0f * distance * std::tan(30.0f * 3.14159265f / 180.0f) / float(renderer.height());  // pixels -> metres at 10 m
    const int columns = 8;
    for (int k = 0; k < 64; ++k) {
        walk::Renderer::Draw d{0, nullptr, 0, 0, {kGrey[0], kGrey[1], kGrey[2]}};
        d.shading = walk::Renderer::Shading::imposter;
        d.texture = texture + uint32_t(k) % textures;
        const float x = (float(k % columns) - 3.5f) * 1.1f * 2 * half, y = (float(k / columns) - 3.5f) * 1.1f * 2 * half;
        const float su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
        for (int c = 0; c < 4; ++c) d.corners[3 * c] = x + half * su[c], d.corners[3 * c + 1] = y + half * sv[c], d.corners[3 * c + 2] = -distance;
        f.draws.push_back(d);
    }
    const int repeats = std::max(1, int(2000 / 64));
    for (int rep = 1; rep < repeats; ++rep)
        for (int k = 0; k < 64; ++k) f.draws.push_back(f.draws[size_t(k)]);
    const double frame_ms = median(time_frames(renderer, cam, f.draws, f.indices, 0, 7));
    tcr::CostSample out;
    out.pixels = double(side_px) * side_px * 0.8;  // the object's share of its quad (the alpha test discards the rest after the fetch)
    out.time_ms = std::max(0.0, frame_ms - empty_ms) / (64.0 * repeats);
    return out;
}

// Refreshes: `count` captures of the mesh's level `fraction` into textures of `side`, in one
// frame; the time per capture above the model's time of drawing that level into that many
// pixels: the render target's switch and clear (CostModel::refresh_t_setup_ms), and with a
// `grid`, a meshed imposter's depth read back and its mesh made too.
double refresh_overhead(const tom::MeshView& mesh, uint32_t handle, double fraction, uint32_t side, const tcr::CostModel& model, const tcr::Camera& cam,
                        double empty_ms, walk::Renderer& renderer, Frame& f, uint32_t grid = 0) {
    const uint32_t n = tom::vertex_count_for_fraction(mesh, fraction);
    const uint32_t tris = tom::active_triangle_count(mesh, n);
    f.indices.resize(size_t(tris) * 3);
    tom::extract(mesh, n, f.indices.data(), f.indices.size());
    tcr::ImposterState s;
    s.valid = true;
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
        d2 += double(mesh.bounds_max[k] - mesh.bounds_min[k]) * (mesh.bounds_max[k] - mesh.bounds_min[k]);
        s.centre[k] = 0.5f * (mesh.bounds_min[k] + mesh.bounds_max[k]);
    }
    s.radius = float(0.5 * std::sqrt(d2));
    s.eye[0] = s.centre[0], s.eye[1] = s.centre[1], s.eye[2] = s.centre[2] + 4 * s.radius;
    s.texture_px = side;
    const int count = 16;
    std::vector<walk::Renderer::Capture> captures;
    f.draws.clear();
    static const float kIdentity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    for (int c = 0; c < count; ++c) {
        walk::Renderer::Capture cap{uint32_t(1000 + c), side, {}, {}, grid};
        tcr::imposter_camera(s, cap.view, cap.projection);
        captures.push_back(cap);
        walk::Renderer::Draw d{handle, kIdentity, 0, tris * 3, {kGrey[0], kGrey[1], kGrey[2]}};
        d.capture = c;
        f.draws.push_back(d);
    }
    std::vector<double> times;
    for (int r = 0; r < 7; ++r) {
        const auto t0 = Clock::now();
        renderer.render(cam.view, cam.projection, f.draws, f.indices, f.indices.size(), captures);
        times.push_back(ms_since(t0));
    }
    const double per_capture = std::max(0.0, median(times) - empty_ms) / count;
    return std::max(0.0, per_capture - model.object_ms(tris, referenced_vertices(f.indices, n, f.used), 0.5 * double(side) * side));
}

// Meshed imposters' draws: 16 captures of the mesh's level `fraction`, placed 10 m ahead at
// about `side_px` pixels across, with depth meshes of `grid` cells a side, into the slots from
// `slot`; then 64 draws a frame of those depth meshes (repeated toward 2,000); the time per draw
// above the empty frame's.
double meshed_draw_ms(const tom::MeshView& mesh, uint32_t handle, uint32_t slot, uint32_t grid, float side_px, const tcr::Camera& cam, double empty_ms,
                      walk::Renderer& renderer, Frame& f) {
    const uint32_t n = tom::vertex_count_for_fraction(mesh, 0.1);
    const uint32_t tris = tom::active_triangle_count(mesh, n);
    f.indices.resize(size_t(tris) * 3);
    tom::extract(mesh, n, f.indices.data(), f.indices.size());
    double d2 = 0, centre[3];
    for (int k = 0; k < 3; ++k) {
        d2 += double(mesh.bounds_max[k] - mesh.bounds_min[k]) * (mesh.bounds_max[k] - mesh.bounds_min[k]);
        centre[k] = 0.5 * (double(mesh.bounds_min[k]) + mesh.bounds_max[k]);
    }
    const double distance = 10.0, radius = 0.5 * side_px * distance * std::tan(30.0 * 3.14159265 / 180.0) / renderer.height() * 2.0;
    const double scale = radius / std::max(1e-9, 0.5 * std::sqrt(d2));
    float model[16] = {float(scale), 0, 0, 0, 0, float(scale), 0, 0, 0, 0, float(scale), 0, float(-scale * centre[0]), float(-scale * centre[1]),
                       float(-distance - scale * centre[2]), 1};
    tcr::ImposterState s;
    s.valid = true;
    s.centre[2] = float(-distance);
    s.radius = float(radius);
    std::vector<walk::Renderer::Capture> captures;
    f.draws.clear();
    for (uint32_t c = 0; c < 16; ++c) {
        walk::Renderer::Capture cap{slot + c, 64, {}, {}, grid};
        tcr::imposter_camera(s, cap.view, cap.projection);
        captures.push_back(cap);
        walk::Renderer::Draw d{handle, model, 0, tris * 3, {kGrey[0], kGrey[1], kGrey[2]}};
        d.capture = int32_t(c);
        f.draws.push_back(d);
    }
    renderer.render(cam.view, cam.projection, f.draws, f.indices, f.indices.size(), captures);
    f.draws.clear();
    for (uint32_t k = 0; k < 2048; ++k) {
        walk::Renderer::Draw d{0, nullptr, 0, 0, {kGrey[0], kGrey[1], kGrey[2]}};
        d.shading = walk::Renderer::Shading::meshed;
        d.texture = slot + k % 16;
        f.draws.push_back(d);
    }
    return std::max(0.0, median(time_frames(renderer, cam, f.draws, f.indices, 0, 7)) - empty_ms) / double(f.draws.size());
}

} // namespace calib

// The other ways' coefficients: flat shading refitted on the first two meshes' draws; a refresh's
// overhead, the median over two levels and two texture sides; the imposter quad's draw and fill
// by least squares on relative errors over five quad sizes.
void calibrate_ways(const World& w, walk::Renderer& renderer, const std::vector<uint32_t>& handles, const tcr::Camera& cam, double empty_ms,
                    calib::Frame& frame, tcr::CostModel& m, std::FILE* log) {
    std::vector<tcr::CostSample> flat;
    for (size_t mi = 0; mi < std::min<size_t>(w.meshes.size(), 2); ++mi)
        for (const calib::Config& cfg : calib::configs())
            flat.push_back(calib::sample(*w.meshes[mi], handles[mi], cfg, cam, empty_ms, renderer, frame, walk::Renderer::Shading::flat));
    const tcr::CalibrationResult fit = tcr::fit_cost_model(flat);
    m.flat_t_tri_ms = fit.model.t_tri_ms;
    m.flat_t_vert_ms = fit.model.t_vert_ms;
    m.flat_t_pix_ms = fit.model.t_pix_ms;
    // texture mapping: the same draws through the textured program, a 256 x 256 checker bound
    // (what a texture fetch costs does not depend on the picture)
    std::vector<unsigned char> checker(256 * 256 * 4);
    for (size_t i = 0; i < 256 * 256; ++i) {
        const unsigned char v = ((i % 256) / 16 + (i / 256) / 16) % 2 ? 230 : 60;
        checker[4 * i] = checker[4 * i + 1] = checker[4 * i + 2] = v, checker[4 * i + 3] = 255;
    }
    const uint32_t image = renderer.add_image(256, 256, checker.data());
    std::vector<tcr::CostSample> textured;
    for (size_t mi = 0; mi < std::min<size_t>(w.meshes.size(), 2); ++mi)
        for (const calib::Config& cfg : calib::configs())
            textured.push_back(calib::sample(*w.meshes[mi], handles[mi], cfg, cam, empty_ms, renderer, frame, walk::Renderer::Shading::textured, image));
    const tcr::CalibrationResult textured_fit = tcr::fit_cost_model(textured);
    m.textured_t_tri_ms = textured_fit.model.t_tri_ms;
    m.textured_t_vert_ms = textured_fit.model.t_vert_ms;
    m.textured_t_pix_ms = textured_fit.model.t_pix_ms;
    std::vector<double> overheads;
    for (double fraction : {0.4, 0.05})
        for (uint32_t side : {64u, 256u}) overheads.push_back(calib::refresh_overhead(*w.meshes[0], handles[0], fraction, side, m, cam, empty_ms, renderer, frame));
    m.refresh_t_setup_ms = calib::median(overheads);
    // meshed imposters: the refresh's depth read-back and mesh beyond a simple refresh; a depth
    // mesh's triangle, from the draws of 16 x 16 and 4 x 4 grids of the same captures (at least
    // 1e-9 ms: a measured 0 would read as not calibrated)
    std::vector<double> meshed_overheads;
    for (double fraction : {0.4, 0.05})
        for (uint32_t side : {64u, 256u})
            meshed_overheads.push_back(calib::refresh_overhead(*w.meshes[0], handles[0], fraction, side, m, cam, empty_ms, renderer, frame, 8));
    m.meshed_refresh_t_setup_ms = std::max(1e-6, calib::median(meshed_overheads) - m.refresh_t_setup_ms);
    std::vector<double> per_triangle;
    for (float side_px : {32.0f, 96.0f}) {
        const double coarse = calib::meshed_draw_ms(*w.meshes[0], handles[0], 2000, 4, side_px, cam, empty_ms, renderer, frame);
        const double fine = calib::meshed_draw_ms(*w.meshes[0], handles[0], 2100, 16, side_px, cam, empty_ms, renderer, frame);
        per_triangle.push_back((fine - coarse) / (2.0 * 16 * 16 - 2.0 * 4 * 4));
    }
    m.meshed_t_tri_ms = std::max(1e-9, calib::median(per_triangle));
    // t = a + b P by weighted least squares, weights 1 / t^2 (relative residuals)
    double s00 = 0, s01 = 0, s11 = 0, r0 = 0, r1 = 0;
    for (float side : {8.0f, 16.0f, 32.0f, 64.0f, 128.0f}) {
        const tcr::CostSample q = calib::quad_sample(1000, 16, side, cam, empty_ms, renderer, frame);  // the refreshes' 16 textures
        if (q.time_ms <= 0) continue;
        const double wt = 1.0 / (q.time_ms * q.time_ms);
        s00 += wt, s01 += wt * q.pixels, s11 += wt * q.pixels * q.pixels, r0 += wt * q.time_ms, r1 += wt * q.time_ms * q.pixels;
    }
    const double det = s00 * s11 - s01 * s01;
    if (det > 0) {
        m.imposter_t_pix_ms = std::max(0.0, (s00 * r1 - s01 * r0) / det);
        m.imposter_t_setup_ms = std::max(1e-6, (r0 - s01 * m.imposter_t_pix_ms) / s00);
    }
    std::fprintf(log,
                 "ways: flat t_tri %.4g ms, t_vert %.4g ms, t_pix %.4g ms (fit %.1f%% mean relative error over %zu samples); "
                 "textured t_tri %.4g ms, t_vert %.4g ms, t_pix %.4g ms (fit %.1f%%); refresh overhead %.4g ms; "
                 "imposter quad %.4g ms + %.4g ms a pixel; meshed imposter + %.4g ms a depth-mesh triangle, its refresh + %.4g ms\n",
                 m.flat_t_tri_ms, m.flat_t_vert_ms, m.flat_t_pix_ms, 100 * fit.mean_relative_error, flat.size(), m.textured_t_tri_ms, m.textured_t_vert_ms,
                 m.textured_t_pix_ms, 100 * textured_fit.mean_relative_error, m.refresh_t_setup_ms, m.imposter_t_setup_ms,
                 m.imposter_t_pix_ms, m.meshed_t_tri_ms, m.meshed_refresh_t_setup_ms);
}

// Fits the cost model on this renderer: the empty frame gives t_init + t_final and the safety
// allowance, draws of up to four meshes at five levels, three distances and two copy counts give
// the per-draw, per-triangle, per-vertex and per-pixel costs, and a repeated heavy frame the noise.
tcr::CostModel calibrate(const World& w, walk::Renderer& renderer, const std::vector<uint32_t>& handles, std::FILE* log) {
    const tcr::Camera cam = calib::camera(renderer);
    calib::Frame frame;
    for (int r = 0; r < 10; ++r) renderer.render(cam.view, cam.projection, frame.draws, frame.indices, 0);  // warm up
    const std::vector<double> empty = calib::time_frames(renderer, cam, frame.draws, frame.indices, 0, 25);
    const double empty_ms = calib::median(empty);

    std::vector<tcr::CostSample> samples;
    const size_t mesh_count = std::min<size_t>(w.meshes.size(), 4);
    for (size_t mi = 0; mi < mesh_count; ++mi)
        for (const calib::Config& cfg : calib::configs()) samples.push_back(calib::sample(*w.meshes[mi], handles[mi], cfg, cam, empty_ms, renderer, frame));
    double noise_overall = 0;
    const double noise_rel = calib::frame_noise(*w.meshes[0], handles[0], cam, renderer, frame, noise_overall);

    const tcr::CalibrationResult fit = tcr::fit_cost_model(samples);
    tcr::CostModel m = fit.model;
    m.t_init_ms = 0.5 * empty_ms;
    m.t_final_ms = 0.5 * empty_ms;
    double spread = 0;
    for (double e : empty) spread += (e - empty_ms) * (e - empty_ms) / empty.size();
    m.safety_ms = std::max(0.25, 2.0 * std::sqrt(spread));
    m.noise_rel = noise_rel;
    calibrate_ways(w, renderer, handles, cam, empty_ms, frame, m, log);
    std::fprintf(log,
                 "calibration: %zu samples (4 meshes x (5 levels x 3 distances x 8 copies + 2 x 64 small copies), each frame repeated up to 64x toward %.0f triangles, median of 7), empty frame %.3f ms\n"
                 "  t_setup %.4g ms, t_tri %.4g ms, t_vert %.4g ms, t_pix %.4g ms; fit: rms %.4f ms, mean relative error %.1f%% "
                 "(%zu geometry bound, %zu fill bound); identical frames vary by %.1f%% frame to frame (%.1f%% standard deviation)\n",
                 samples.size(), kCalibrationTriangles, empty_ms, m.t_setup_ms, m.t_tri_ms, m.t_vert_ms, m.t_pix_ms, fit.rms_error_ms, 100 * fit.mean_relative_error,
                 fit.geometry_bound, fit.fill_bound, 100 * noise_rel, 100 * noise_overall);
    return m;
}

} // namespace

int main(int argc, char** argv) {
    Options o;
    std::string make_scene, calibrate_out;
    std::vector<std::string> mesh_files;
    uint32_t instances = 300, far_instances = 0, noise_renders = 0;
    CLI::App app{"tcrwalk: render a scene of TOM objects headless along a path, under libtcr's selectors, and measure the frame budget"};
    app.set_version_flag("--version", "tcrwalk 0.1.0");
    app.add_option("--scene", o.scene, "Scene file (see samples/walkthrough/scene.h)");
    app.add_option("--make-scene", make_scene, "Write a scene file from --meshes (deterministic from --seed) and exit");
    app.add_option("--meshes", mesh_files, "For --make-scene: .tom files (paths stored relative to the scene file)");
    app.add_option("--instances", instances, "For --make-scene: number of instances (default 300)");
    app.add_option("--far-instances", far_instances, "For --make-scene: this many more in a ring 50 to 150 units out, where imposters pay (default 0)");
    app.add_option("--calibrate", calibrate_out, "Render sample objects, fit the cost model, write this calibration file (docs/CALIBRATION.md)");
    app.add_option("--calibration", o.calibration, "Calibration file to run with (required unless --calibrate)");
    app.add_option("--selector", o.selectors, "none, static, stress, greedy, barrier, exact, or all (default all); SELECTOR-levels: that selector on the TOM levels alone")->delimiter(',');
    app.add_option("--budget-ms", o.budget_ms, "Frame budget in ms (default 40)")->check(CLI::PositiveNumber);
    app.add_option("--frames", o.frames, "Frames along the path (default 300)")->check(CLI::Range(10u, 100000u));
    app.add_flag("--simulate", o.simulate, "No OpenGL: frame times from the calibrated model plus noise");
    app.add_flag("--sequential", o.sequential,
                 "Run each selector's whole path in turn (default: frame by frame, every selector at frame f before frame f + 1, so all meet the "
                 "machine's slow and fast spells alike)");
    app.add_option("--out", o.out, "Folder for CSV, summary and screenshots");
    app.add_flag("--json", o.json, "Print one JSON summary per selector");
    app.add_option("--width", o.width, "Viewport width (default 640)");
    app.add_option("--height", o.height, "Viewport height (default 480)");
    app.add_option("--hysteresis", o.hysteresis, "Relative dead band against the previous frame (default 0.05)");
    app.add_option("--safety-sigma", o.safety_sigma, "Safety allowance in multiples of the frame-to-frame noise (the calibration's noise_rel, from the 11th rendered frame the run's own) times the budget (default 0.75)");
    app.add_option("--seed", o.seed, "Seed for --make-scene and simulated noise (default 1)");
    app.add_option("--quality-every", o.quality_every,
                   "Compare every K-th recorded frame with the same view at full detail (SSIM, PSNR by scikit-image; needs --out, not --simulate)")
        ->check(CLI::Range(1u, 100000u));
    app.add_option("--representations", o.representations,
                   "levels: TOM levels smooth-shaded only; all (default): also flat shading, simple and meshed imposters, where calibrated (exact and greedy choose "
                   "among them); simple: all but meshed imposters")
        ->check(CLI::IsMember({"levels", "simple", "all"}));
    app.add_option("--meshed-grid", o.meshed_grid, "A meshed imposter's depth mesh: cells a side, two triangles each (default 8)")->check(CLI::Range(1u, 64u));
    app.add_option("--flat-error-factor", o.flat_error_factor, "Flat shading's projected error as a multiple of smooth shading's (default 2)")->check(CLI::PositiveNumber);
    app.add_option("--imposter-max-px", o.imposter_max_px, "Reuse an imposter while its distortion stays within this many pixels (default 1)")->check(CLI::PositiveNumber);
    app.add_option("--imposter-error-factor", o.imposter_error_factor, "An imposter's projected error in the benefit as a multiple of its geometric error (default 1)")->check(CLI::PositiveNumber);
    app.add_option("--refresh-share", o.refresh_share, "Renew imposters in a frame for at most this share of the budget (default 0.25)")->check(CLI::Range(0.0, 1.0));
    app.add_option("--noise-test", noise_renders, "Draw viewpoint A's frame (the exact selector's plan at --budget-ms) this many times in a row and print how much identical frames vary")
        ->check(CLI::Range(20u, 100000u));
    app.footer("Exit codes: 0 ok, 1 failure (unreadable scene or mesh, no OpenGL), 2 usage error.\n"
               "The whole walkthrough: bash scripts/walkthrough.sh");
    if (const int code = tools::parse(app, argc, argv); code >= 0) return code;
    try {
        if (!make_scene.empty()) {
            if (mesh_files.empty()) {
                std::fprintf(stderr, "error: --make-scene needs --meshes\n");
                return 2;
            }
            std::vector<std::string> rel;
            uint32_t heaviest = 0;
            uint64_t most = 0;
            for (size_t k = 0; k < mesh_files.size(); ++k) {
                rel.push_back(fs::relative(fs::absolute(mesh_files[k]), fs::absolute(make_scene).parent_path()).string());
                const tom::File f = tom::File::open(mesh_files[k]);
                if (f.mesh_count() && f.mesh(0).triangle_count > most) most = f.mesh(0).triangle_count, heaviest = uint32_t(k);
            }
            walk::write_scene(make_scene, walk::make_scene(rel, instances, o.seed, heaviest, far_instances));
            const World w = load_world(make_scene);
            std::printf("%s: %zu instances of %zu meshes, %llu triangles at full detail\n", make_scene.c_str(), w.scene.instances.size(),
                        w.meshes.size(), static_cast<unsigned long long>(w.full_triangles));
            return 0;
        }
        if (o.scene.empty()) {
            std::fprintf(stderr, "error: give --scene (or --make-scene)\n");
            return 2;
        }
        World w = load_world(o.scene);
        std::unique_ptr<walk::Renderer> renderer;
        std::vector<uint32_t> handles;
        if (!o.simulate || !calibrate_out.empty()) {
            renderer = std::make_unique<walk::Renderer>(o.width, o.height);
            for (const tom::MeshView* m : w.meshes) handles.push_back(renderer->add_mesh(*m));
        } else {
            handles.resize(w.meshes.size());
        }
        load_images(w, renderer.get());
        if (!calibrate_out.empty()) {
            const tcr::CostModel m = calibrate(w, *renderer, handles, stdout);
            tcr::write_cost_model(calibrate_out, m, "tcrwalk --calibrate on " + renderer->description());
            std::printf("wrote %s\n", calibrate_out.c_str());
            return 0;
        }
        if (o.calibration.empty()) {
            std::fprintf(stderr, "error: give --calibration FILE (make one with --calibrate FILE)\n");
            return 2;
        }
        const tcr::CostModel model = tcr::read_cost_model(o.calibration);
        if (noise_renders) {
            if (!renderer) {
                std::fprintf(stderr, "error: --noise-test draws real frames: drop --simulate\n");
                return 2;
            }
            const nlohmann::ordered_json j = noise_test(w, o, model, *renderer, handles, noise_renders);
            if (o.json) {
                std::printf("%s\n", j.dump().c_str());
            } else {
                std::printf("viewpoint A (frame %u of %u), %llu triangles in %u objects, drawn %u times in a row on %s:\n"
                            "  median %.2f ms; standard deviation %.1f%% of it; 5th / 95th percentile %.0f%% / %.0f%%\n"
                            "  lag-1 autocorrelation %.2f; means of 10 frames in a row from %.0f%% to %.0f%%; frame to frame %.1f%%\n",
                            j["frame"].get<uint32_t>(), o.frames, static_cast<unsigned long long>(j["triangles"].get<uint64_t>()), j["objects"].get<uint32_t>(),
                            noise_renders, renderer->description().c_str(), j["median_ms"].get<double>(), j["std_percent"].get<double>(),
                            j["p5_percent"].get<double>(), j["p95_percent"].get<double>(), j["lag1_autocorrelation"].get<double>(),
                            j["block10_percent"][0].get<double>(), j["block10_percent"][1].get<double>(), j["frame_to_frame_percent"].get<double>());
            }
            return 0;
        }
        if (o.selectors.empty() || (o.selectors.size() == 1 && o.selectors[0] == "all")) o.selectors = {"none", "static", "stress", "greedy", "barrier", "exact", "exact-levels"};
        for (const std::string& s : o.selectors) {
            tcr::SelectorKind k;
            if (s != "none" && !tcr::parse_selector(base_selector(s), k)) {
                std::fprintf(stderr, "error: unknown selector '%s'\n", s.c_str());
                return 2;
            }
        }
        if (!o.out.empty()) fs::create_directories(o.out);
        if (o.quality_every && (o.out.empty() || !renderer || o.simulate)) {
            std::fprintf(stderr, "error: --quality-every compares rendered frames: give --out and drop --simulate\n");
            return 2;
        }
        std::unique_ptr<Reference> reference;
        if (o.quality_every) reference = std::make_unique<Reference>(w, handles, o.out);
        if (!o.json)
            std::printf("%s, %zu objects, %llu triangles at full detail, %u frames, budget %.1f ms%s\n", o.scene.c_str(), w.scene.instances.size(),
                        static_cast<unsigned long long>(w.full_triangles), o.frames, o.budget_ms,
                        o.simulate ? " (simulated)" : (", " + renderer->description()).c_str());
        std::vector<std::vector<Row>> runs;
        std::vector<Summary> summaries = run_paths(w, o, model, o.simulate ? nullptr : renderer.get(), handles, runs, reference.get());
        for (size_t k = 0; k < o.selectors.size(); ++k) {
            const std::vector<Row>& rows = runs[k];
            if (!o.out.empty()) {
                std::ofstream csv(fs::path(o.out) / ("frames-" + o.selectors[k] + ".csv"));
                csv << "frame,visible_objects,drawn_objects,visible_triangles,drawn_triangles,predicted_ms,measured_ms,render_ms,cull_ms,optimize_ms,extract_ms,benefit,gap,"
                       "flat_objects,imposters,imposter_refreshes,meshed_imposters,textured_objects\n";
                for (const Row& r : rows)
                    csv << r.frame << ',' << r.visible_objects << ',' << r.drawn_objects << ',' << r.visible_triangles << ',' << r.drawn_triangles << ','
                        << r.predicted_ms << ',' << r.measured_ms << ',' << r.render_ms << ',' << r.cull_ms << ',' << r.optimize_ms << ',' << r.extract_ms
                        << ',' << r.benefit << ',' << (std::isnan(r.gap) ? std::string("") : std::to_string(r.gap)) << ',' << r.flat_objects << ','
                        << r.imposters << ',' << r.refreshes << ',' << r.meshed << ',' << r.textured << '\n';
            }
        }
        if (reference) {
            // the references after every selector's path: a full-detail render between timed
            // frames would leave the next frame's caches cold
            for (uint32_t f = 0; f < o.frames; f += o.quality_every) reference->save_reference(*renderer, camera_for(f, o.frames, o.width, o.height), f);
            score_quality(*reference, o.out, summaries);
        }
        std::vector<nlohmann::ordered_json> out;
        uint32_t shots[3];
        walk::viewpoints(o.frames, shots);
        for (const Summary& s : summaries) {
            nlohmann::ordered_json j;
            j["selector"] = s.selector;
            j["frames"] = s.frames;
            j["budget_ms"] = s.budget_ms;
            j["frame_ms"] = {{"mean", s.mean}, {"max", s.max}, {"std", s.std}};
            j["compute_ms"] = {{"mean", s.compute_mean}, {"max", s.compute_max}};
            j["over_budget_fraction"] = s.over;
            j["prediction_error"] = std::isnan(s.prediction_error) ? nlohmann::json(nullptr) : nlohmann::json(s.prediction_error);
            j["drawn_triangles_mean"] = s.drawn;
            j["visible_triangles_mean"] = s.visible;
            j["gap_mean"] = std::isnan(s.gap) ? nlohmann::json(nullptr) : nlohmann::json(s.gap);
            auto or_null = [](double x) { return std::isnan(x) ? nlohmann::json(nullptr) : nlohmann::json(x); };
            j["quality_frames"] = s.quality_frames;
            j["ssim_mean"] = or_null(s.ssim_mean);
            j["ssim_min"] = or_null(s.ssim_min);
            j["psnr_mean"] = or_null(s.psnr_mean);
            j["representations"] = ends_with_levels(s.selector) ? std::string("levels") : o.representations;
            j["flat_objects_mean"] = s.flat_mean;
            j["textured_objects_mean"] = s.textured_mean;
            j["imposters_drawn_mean"] = s.imposters_mean;
            j["imposter_refreshes_mean"] = s.refreshes_mean;
            j["meshed_imposters_mean"] = s.meshed_mean;
            j["simulated"] = o.simulate;
            j["viewpoint_frames"] = {{"A", shots[0]}, {"B", shots[1]}, {"C", shots[2]}};  // the screenshots' frames
            out.push_back(j);
        }
        if (o.json) {
            for (const auto& j : out) std::printf("%s\n", j.dump().c_str());
        } else {
            const bool quality = reference != nullptr;
            std::printf("\n%-8s | %23s | %17s | %7s | %7s | %12s %12s | %34s%s\n", "", "frame time ms", "compute ms", ">1.1 B", "pred.", "drawn", "visible",
                        "objects a frame", quality ? " | image vs full detail" : "");
            std::printf("%-8s | %7s %7s %7s | %8s %8s | %7s | %7s | %12s %12s | %6s %6s %6s %6s %6s%s\n", "selector", "mean", "max", "std", "mean", "max", "frames", "error",
                        "tris mean", "tris mean", "flat", "textur", "impost", "meshed", "renew", quality ? " | SSIM mean    min  PSNR dB" : "");
            for (const Summary& s : summaries) {
                std::printf("%-8s | %7.2f %7.2f %7.2f | %8.3f %8.3f | %6.1f%% | %6.1f%% | %12.0f %12.0f | %6.1f %6.1f %6.1f %6.1f %6.2f", s.selector.c_str(), s.mean, s.max,
                            s.std, s.compute_mean, s.compute_max, 100 * s.over, std::isnan(s.prediction_error) ? 0.0 : 100 * s.prediction_error, s.drawn, s.visible,
                            s.flat_mean, s.textured_mean, s.imposters_mean, s.meshed_mean, s.refreshes_mean);
                if (quality) std::printf(" |    %.4f %.4f %8.2f", s.ssim_mean, s.ssim_min, s.psnr_mean);
                std::printf("\n");
            }
            if (quality)
                std::printf("image: %u frames of each selector against the same view at full detail (scikit-image; identical frames count as 99 dB)\n",
                            summaries.empty() ? 0 : summaries.front().quality_frames);
        }
        if (!o.out.empty()) {
            std::ofstream js(fs::path(o.out) / "summary.json");
            nlohmann::ordered_json arr = nlohmann::ordered_json::array();
            for (const auto& j : out) arr.push_back(j);
            js << arr.dump(2) << "\n";
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
