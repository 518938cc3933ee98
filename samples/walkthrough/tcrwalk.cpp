// tcrwalk: the reference integration of libtom and libtcr. Renders a scene of TOM objects
// headless (Mesa's llvmpipe through OSMesa) along a path with Funkhouser's hard viewpoints,
// under each selector, and measures whether the frame budget holds.
//
// Frame = plan (cull, measure, optimise: libtcr) + extract (libtom index buffers) + render (one
// indexed draw per object, glFinish). Following Gobbetti & Bouvier, the non-rendering part is
// measured and the renderer gets the rest of the budget.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include <nlohmann/json.hpp>

#include "calibration_timer.h"
#include "cli.h"
#include "renderer.h"
#include "results.h"
#include "world.h"
#include "tcr/governor.h"
#include "tcr/runtime.h"
#include "tom/format.h"

namespace fs = std::filesystem;

namespace {

using namespace walk;  // the world, its frames and the results

// A selector's name in --selector: a libtcr selector, "none", or either with "-levels" (the
// TOM levels alone, for comparing the menu with them in one run).
bool ends_with_levels(const std::string& s) { return s.size() > 7 && s.compare(s.size() - 7, 7, "-levels") == 0; }
std::string base_selector(const std::string& s) { return ends_with_levels(s) ? s.substr(0, s.size() - 7) : s; }

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

    // "none" draws full detail: a budget no frame reaches, and a planning reserve of what its
    // planning takes (a share of that budget would be the simulated frame's time). A simulated
    // renderer's noise is the calibration's: the allowance stays the calibrated one.
    static tcr::GovernorParams governor_params(const Options& o, bool none, bool rendered) {
        tcr::GovernorParams g;
        g.budget_ms = none ? 1e12 : o.budget_ms;
        if (none) g.min_planning_share = 0.0;
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
            const auto frame_start = Clock::now();
            const tcr::FrameReport& r = governor.plan_frame(frame_params(cam));
            ensure(indices, size_t(r.triangles) * 3);  // outside the timing
            size_t index_count = 0;
            tcr::FrameTimes times = draw(cam, r, kGrey, frame_start, index_count);
            times.frame_ms = -1;  // the reserve, the extraction and the rendering
            governor.frame_done(times);
        }
    }

    // The planned frame extracted and drawn (or simulated), timed from `frame_start`.
    tcr::FrameTimes draw(const tcr::Camera& cam, const tcr::FrameReport& r, const float color[3], Clock::time_point frame_start, size_t& index_count) {
        const auto extract_start = Clock::now();
        index_count = extract_frame(w, rt, mesh_handles, color, indices, draws, captures, slots);
        const double extract_ms = ms_since(extract_start);
        if (!renderer) return {extract_ms, simulated.frame_ms(r, governor.model()), -1.0};
        const auto render_start = Clock::now();
        renderer->render(cam.view, cam.projection, draws, indices, index_count, captures);
        return {extract_ms, ms_since(render_start), ms_since(frame_start)};
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
        tcr::FrameTimes times = draw(cam, r, kSand, frame_start, index_count);
        row.extract_ms = times.extract_ms;
        // simulated: extraction is in the simulated time, and the frame is the planning time
        // reserved plus it (the real cull and optimise times, which a busy machine can stretch,
        // stay in the compute columns)
        if (!renderer) times.extract_ms = 0.0;
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
// fast spells alike (run one after another, a spell can move one selector's triangles more than
// the selectors differ); `--sequential` runs them one after another.
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

// What the command line asks: a run's options, or making a scene, calibrating, the noise test.
struct Command {
    Options o;
    std::string make_scene, calibrate_out;
    std::vector<std::string> mesh_files;
    uint32_t instances = 300, far_instances = 0, noise_renders = 0;
};

// Parses the command line into `c`; an exit code when done (help, version, usage error), else -1.
int parse_command(Command& c, int argc, char** argv) {
    CLI::App app{"tcrwalk: render a scene of TOM objects headless along a path, under libtcr's selectors, and measure the frame budget"};
    app.set_version_flag("--version", "tcrwalk 0.1.0");
    app.add_option("--scene", c.o.scene, "Scene file (see samples/walkthrough/scene.h)");
    app.add_option("--make-scene", c.make_scene, "Write a scene file from --meshes (deterministic from --seed) and exit");
    app.add_option("--meshes", c.mesh_files, "For --make-scene: .tom files (paths stored relative to the scene file)");
    app.add_option("--instances", c.instances, "For --make-scene: number of instances (default 300)");
    app.add_option("--far-instances", c.far_instances, "For --make-scene: this many more in a ring 50 to 150 units out, where imposters pay (default 0)");
    app.add_option("--calibrate", c.calibrate_out, "Render sample objects, fit the cost model, write this calibration file (docs/CALIBRATION.md)");
    app.add_option("--calibration", c.o.calibration, "Calibration file to run with (required unless --calibrate)");
    app.add_option("--selector", c.o.selectors, "none, static, stress, greedy, barrier, exact, or all (default all); SELECTOR-levels: that selector on the TOM levels alone")->delimiter(',');
    app.add_option("--budget-ms", c.o.budget_ms, "Frame budget in ms (default 40)")->check(CLI::PositiveNumber);
    app.add_option("--frames", c.o.frames, "Frames along the path (default 300)")->check(CLI::Range(10u, 100000u));
    app.add_flag("--simulate", c.o.simulate, "No OpenGL: frame times from the calibrated model plus noise");
    app.add_flag("--sequential", c.o.sequential,
                 "Run each selector's whole path in turn (default: frame by frame, every selector at frame f before frame f + 1, so all meet the "
                 "machine's slow and fast spells alike)");
    app.add_option("--out", c.o.out, "Folder for CSV, summary and screenshots");
    app.add_flag("--json", c.o.json, "Print one JSON summary per selector");
    app.add_option("--width", c.o.width, "Viewport width (default 640)");
    app.add_option("--height", c.o.height, "Viewport height (default 480)");
    app.add_option("--hysteresis", c.o.hysteresis, "Relative dead band against the previous frame (default 0.05)");
    app.add_option("--safety-sigma", c.o.safety_sigma, "Safety allowance in multiples of the frame-to-frame noise (the calibration's noise_rel, from the 11th rendered frame the run's own) times the budget (default 0.75)");
    app.add_option("--seed", c.o.seed, "Seed for --make-scene and simulated noise (default 1)");
    app.add_option("--quality-every", c.o.quality_every,
                   "Compare every K-th recorded frame with the same view at full detail (SSIM, PSNR by scikit-image; needs --out, not --simulate)")
        ->check(CLI::Range(1u, 100000u));
    app.add_option("--representations", c.o.representations,
                   "levels: TOM levels smooth-shaded only; all (default): also flat shading, simple and meshed imposters, where calibrated (exact and greedy choose "
                   "among them); simple: all but meshed imposters")
        ->check(CLI::IsMember({"levels", "simple", "all"}));
    app.add_option("--meshed-grid", c.o.meshed_grid, "A meshed imposter's depth mesh: cells a side, two triangles each (default 8)")->check(CLI::Range(1u, 64u));
    app.add_option("--flat-error-factor", c.o.flat_error_factor, "Flat shading's projected error as a multiple of smooth shading's (default 2)")->check(CLI::PositiveNumber);
    app.add_option("--imposter-max-px", c.o.imposter_max_px, "Reuse an imposter while its distortion stays within this many pixels (default 1)")->check(CLI::PositiveNumber);
    app.add_option("--imposter-error-factor", c.o.imposter_error_factor, "An imposter's projected error in the benefit as a multiple of its geometric error (default 1)")->check(CLI::PositiveNumber);
    app.add_option("--refresh-share", c.o.refresh_share, "Renew imposters in a frame for at most this share of the budget (default 0.25)")->check(CLI::Range(0.0, 1.0));
    app.add_option("--noise-test", c.noise_renders, "Draw viewpoint A's frame (the exact selector's plan at --budget-ms) this many times in a row and print how much identical frames vary")
        ->check(CLI::Range(20u, 100000u));
    app.footer("Exit codes: 0 ok, 1 failure (unreadable scene or mesh, no OpenGL), 2 usage error.\n"
               "The whole walkthrough: bash scripts/walkthrough.sh");
    return walk::parse_command_line(app, argc, argv);
}

int usage_error(const char* message) {
    std::fprintf(stderr, "error: %s\n", message);
    return 2;
}

// --make-scene: the scene file from --meshes, its heaviest mesh the one instanced close by.
int make_scene_file(const Command& c) {
    if (c.mesh_files.empty()) return usage_error("--make-scene needs --meshes");
    std::vector<std::string> relative;
    uint32_t heaviest = 0;
    uint64_t most = 0;
    for (size_t k = 0; k < c.mesh_files.size(); ++k) {
        relative.push_back(fs::relative(fs::absolute(c.mesh_files[k]), fs::absolute(c.make_scene).parent_path()).string());
        const tom::File f = tom::File::open(c.mesh_files[k]);
        if (f.mesh_count() && f.mesh(0).triangle_count > most) most = f.mesh(0).triangle_count, heaviest = uint32_t(k);
    }
    walk::write_scene(c.make_scene, walk::make_scene(relative, c.instances, c.o.seed, heaviest, c.far_instances));
    const World w = load_world(c.make_scene);
    std::printf("%s: %zu instances of %zu meshes, %llu triangles at full detail\n", c.make_scene.c_str(), w.scene.instances.size(), w.meshes.size(),
                static_cast<unsigned long long>(w.full_triangles));
    return 0;
}

// The scene loaded, and the renderer with its meshes and images when frames are drawn.
struct Viewer {
    World w;
    std::unique_ptr<walk::Renderer> renderer;
    std::vector<uint32_t> handles;  // the meshes' in the renderer (all 0 without one)
};

Viewer open_viewer(const Options& o, bool rendered) {
    Viewer v{load_world(o.scene), nullptr, {}};
    if (rendered) {
        v.renderer = std::make_unique<walk::Renderer>(o.width, o.height);
        for (const tom::MeshView* m : v.w.meshes) v.handles.push_back(v.renderer->add_mesh(*m));
    } else {
        v.handles.resize(v.w.meshes.size());
    }
    load_images(v.w, v.renderer.get());
    return v;
}

// --calibrate: the library's calibration on this renderer, written to `path`.
int calibrate_renderer(Viewer& v, const std::string& path) {
    CalibrationTimer timer(*v.renderer, v.handles);
    tcr::CalibrationParams p;
    p.path = path;
    p.comment = "tcrwalk --calibrate on " + v.renderer->description();
    std::printf("%swrote %s\n", tcr::calibrate(timer, v.w.meshes, p).summary.c_str(), path.c_str());
    return 0;
}

// --noise-test: viewpoint A's frame drawn again and again.
int run_noise_test(Viewer& v, const Options& o, const tcr::CostModel& model, uint32_t renders) {
    if (!v.renderer || o.simulate) return usage_error("--noise-test draws real frames: drop --simulate");
    const walk::PathSpec path{o.frames, o.width, o.height, o.budget_ms};
    const nlohmann::ordered_json j = walk::noise_test(v.w, path, model, *v.renderer, v.handles, renders);
    if (o.json) std::printf("%s\n", j.dump().c_str());
    else walk::print_noise(j, path, v.renderer->description());
    return 0;
}

// The selectors known and the options consistent; an exit code when not, else -1.
int check_run(Options& o) {
    if (o.selectors.empty() || (o.selectors.size() == 1 && o.selectors[0] == "all")) o.selectors = {"none", "static", "stress", "greedy", "barrier", "exact", "exact-levels"};
    for (const std::string& s : o.selectors) {
        tcr::SelectorKind k;
        if (s != "none" && !tcr::parse_selector(base_selector(s), k)) {
            std::fprintf(stderr, "error: unknown selector '%s'\n", s.c_str());
            return 2;
        }
    }
    if (o.quality_every && (o.out.empty() || o.simulate)) return usage_error("--quality-every compares rendered frames: give --out and drop --simulate");
    return -1;
}

// Every selector along the path; the frames' CSV, the image scores, the summaries printed and
// in OUT/summary.json.
int run_and_report(Viewer& v, const Options& o, const tcr::CostModel& model) {
    if (!o.out.empty()) fs::create_directories(o.out);
    std::unique_ptr<walk::Reference> reference;
    if (o.quality_every) reference = std::make_unique<walk::Reference>(v.w, v.handles, o.out);
    if (!o.json)
        std::printf("%s, %zu objects, %llu triangles at full detail, %u frames, budget %.1f ms%s\n", o.scene.c_str(), v.w.scene.instances.size(),
                    static_cast<unsigned long long>(v.w.full_triangles), o.frames, o.budget_ms,
                    o.simulate ? " (simulated)" : (", " + v.renderer->description()).c_str());
    std::vector<std::vector<walk::Row>> runs;
    std::vector<walk::Summary> summaries = run_paths(v.w, o, model, o.simulate ? nullptr : v.renderer.get(), v.handles, runs, reference.get());
    if (!o.out.empty())
        for (size_t k = 0; k < o.selectors.size(); ++k) walk::write_frames_csv((fs::path(o.out) / ("frames-" + o.selectors[k] + ".csv")).string(), runs[k]);
    if (reference) {
        // the references after every selector's path: a full-detail render between timed
        // frames would leave the next frame's caches cold
        for (uint32_t f = 0; f < o.frames; f += o.quality_every) reference->save_reference(*v.renderer, camera_for(f, o.frames, o.width, o.height), f);
        walk::score_quality(*reference, o.out, summaries);
    }
    nlohmann::ordered_json all = nlohmann::ordered_json::array();
    for (const walk::Summary& s : summaries)
        all.push_back(walk::summary_json(s, ends_with_levels(s.selector) ? std::string("levels") : o.representations, o.simulate, o.frames));
    if (o.json)
        for (const auto& j : all) std::printf("%s\n", j.dump().c_str());
    else
        walk::print_table(summaries, reference != nullptr);
    if (!o.out.empty()) std::ofstream(fs::path(o.out) / "summary.json") << all.dump(2) << "\n";
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    Command c;
    if (const int code = parse_command(c, argc, argv); code >= 0) return code;
    try {
        if (!c.make_scene.empty()) return make_scene_file(c);
        if (c.o.scene.empty()) return usage_error("give --scene (or --make-scene)");
        Viewer v = open_viewer(c.o, !c.o.simulate || !c.calibrate_out.empty());
        if (!c.calibrate_out.empty()) return calibrate_renderer(v, c.calibrate_out);
        if (c.o.calibration.empty()) return usage_error("give --calibration FILE (make one with --calibrate FILE)");
        const tcr::CostModel model = tcr::read_cost_model(c.o.calibration);
        if (c.noise_renders) return run_noise_test(v, c.o, model, c.noise_renders);
        if (const int code = check_run(c.o); code >= 0) return code;
        return run_and_report(v, c.o, model);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
