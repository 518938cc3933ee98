// tomextract: writes a .tom file's meshes at one resolution as OBJ (with a .mtl and a usemtl
// group per part) or PLY, or at one or more resolutions as binary glTF with the file's materials
// and instances (a primitive per part).

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>

#include "tcr/scene_budget.h"
#include "tom/builder/refit.h"
#include "tom/error_curve.h"
#include "tom/errors.h"
#include "tom/io/export.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/stream/stream_file.h"
#include "tool_common.h"

namespace {

// The mesh's full-detail surface area, in its own units.
double surface_area(const tom::MeshView& m) {
    double area = 0;
    for (uint32_t t = 0; t < m.triangle_count; ++t) {
        const float* a = &m.positions[3 * size_t(m.corner(3 * t))];
        const float* b = &m.positions[3 * size_t(m.corner(3 * t + 1))];
        const float* c = &m.positions[3 * size_t(m.corner(3 * t + 2))];
        const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
        const double v[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
        const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        area += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return area;
}

// The meshes of `file` (or mesh `only`) as a scene budget shares among them, each costing its
// instance count in triangles drawn. The weights make the summed error the scene's Metro mean
// (what tomerr measures, what the screen shows): a point's distance averaged over the whole
// surface, so each instance counts with its area. An instance scaled by s (the cube root of its
// transform's determinant) has s^2 times the mesh's area A and s times its distances, which the
// curve gives relative to the diagonal D: its weight is A D s^3 over the scene's area.
std::vector<tcr::BudgetMesh> budget_meshes(const tom::File& file, std::optional<uint32_t> only, tom::Floor floor, const std::string& path) {
    const std::vector<tom::Instance> draws = tom::draw_list(file.scene(), file.mesh_count());
    std::vector<tcr::BudgetMesh> out;
    double scene_area = 0;
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        if (only && *only != i) continue;
        tcr::BudgetMesh b;
        b.mesh = &file.mesh(i);
        b.floor = floor;
        std::optional<tom::ErrorCurve> curve = tom::read_error_curve(*b.mesh);
        if (!curve) throw tom::ArgumentError(path + ": mesh '" + std::string(b.mesh->name) + "' has no stored error curve (it was built with --no-error-curve)");
        b.curve = std::move(*curve);
        double instances = 0, areas = 0, cubes = 0;  // the sums of s^2 and s^3 over the instances
        for (const tom::Instance& inst : draws) {
            if (inst.mesh != i) continue;
            const float* t = inst.transform;
            const double det = double(t[0]) * (double(t[5]) * t[10] - double(t[6]) * t[9]) - double(t[4]) * (double(t[1]) * t[10] - double(t[2]) * t[9]) +
                               double(t[8]) * (double(t[1]) * t[6] - double(t[2]) * t[5]);
            const double s = std::cbrt(std::fabs(det));
            instances += 1, areas += s * s, cubes += s * s * s;
        }
        if (instances == 0 || !(cubes > 0)) instances = 1, areas = 1, cubes = 1;  // drawn by no instance: once, as stored
        const double area = std::max(1e-30, surface_area(*b.mesh));
        b.instances = instances;
        b.weight = area * std::max(1e-30, double(b.curve.diagonal)) * cubes;
        scene_area += area * areas;
        out.push_back(std::move(b));
    }
    for (tcr::BudgetMesh& b : out) b.weight /= scene_area;
    return out;
}

// The folder the stored texture URIs are relative to when --texture-dir is not given: the
// source's, as the manifest tombuild wrote beside `tom_path` records it (its paths are relative
// to the folder tombuild ran in, found as the part of `tom_path`'s absolute path before the
// recorded output). Empty when there is no such record, or no texture that is a file.
std::string source_folder(const std::string& tom_path, const tom::Scene& scene) {
    bool files = false;
    for (const tom::Material& m : scene.materials)
        for (const tom::TextureRef& t : m.textures) files = files || (t.image < 0 && !t.uri.empty());
    if (!files) return "";
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path tom = fs::weakly_canonical(tom_path, ec);
    std::ifstream manifest(tom.parent_path() / "manifest.jsonl");
    for (std::string line; std::getline(manifest, line);) {
        const nlohmann::json r = nlohmann::json::parse(line, nullptr, false);
        if (!r.is_object() || !r.contains("input") || !r.contains("output") || !r["input"].is_string() || !r["output"].is_string()) continue;
        const fs::path input = r["input"].get<std::string>(), output = fs::path(r["output"].get<std::string>()).lexically_normal();
        if (output.is_absolute()) {
            if (fs::weakly_canonical(output, ec) == tom) return input.parent_path().string();
            continue;
        }
        // the folder tombuild ran in: tom's path without the recorded output's components
        const std::string whole = tom.generic_string(), tail = "/" + output.generic_string();
        if (whole.size() <= tail.size() || whole.compare(whole.size() - tail.size(), tail.size(), tail) != 0) continue;
        const fs::path ran_in = whole.substr(0, whole.size() - tail.size());
        return (input.is_absolute() ? input : ran_in / input).parent_path().string();
    }
    return "";
}

// The meshes' resolutions (file order; --mesh's alone) for `triangles` in total, shared in
// proportion to their triangle counts: the largest common fraction whose levels, each the
// largest resolution within its share (a mesh at its floor keeps that), sum to at most
// `triangles`. A mesh that cannot go lower takes more than its share, and the others give it up,
// so the total exceeds `triangles` only when every mesh's floor does.
std::vector<uint32_t> proportional_levels(const tom::File& file, std::optional<uint32_t> only, tom::Floor floor, uint64_t triangles) {
    std::vector<const tom::MeshView*> meshes;
    for (uint32_t i = 0; i < file.mesh_count(); ++i)
        if (!only || *only == i) meshes.push_back(&file.mesh(i));
    auto at = [&](double fraction, std::vector<uint32_t>& out) {  // the levels at `fraction` and their triangles
        uint64_t total = 0;
        out.clear();
        for (const tom::MeshView* m : meshes) {
            const uint32_t share = uint32_t(std::floor(fraction * m->triangle_count));
            const uint32_t n = tom::vertex_count_within_triangles(*m, share, floor);
            out.push_back(n);
            total += tom::active_triangle_count(*m, n);
        }
        return total;
    };
    std::vector<uint32_t> levels, trial;
    if (at(1.0, levels) <= triangles) return levels;
    double lo = 0, hi = 1;
    at(0.0, levels);  // every mesh at its floor: the answer when nothing fits
    for (int step = 0; step < 48; ++step) {
        const double mid = 0.5 * (lo + hi);
        if (at(mid, trial) <= triangles) {
            lo = mid;
            levels = trial;
        } else {
            hi = mid;
        }
    }
    return levels;
}

struct Options {
    std::string path, output, texture_dir;
    std::optional<double> fraction;
    std::optional<uint64_t> bytes;  // --bytes: the prefix of a streamed file to decode
    std::optional<uint64_t> triangles, vertices;
    std::optional<uint32_t> mesh_index;
    std::vector<double> lods, scene_budgets;
    std::string max_error_text, metric = "max";
    std::vector<std::string> lods_error_text;
    std::optional<double> max_error_px, distance, fov_deg;
    std::optional<uint32_t> height;
    bool below_floor = false, embed_images = false, compress = false, refit = false;
    std::vector<double> error_bounds;  // --max-error, --lods-error: fractions of each mesh's diagonal

    bool by_error() const { return !error_bounds.empty() || max_error_px.has_value(); }
    tom::Floor floor() const { return below_floor ? tom::Floor::coarsest : tom::Floor::usable; }
    bool glb() const { return output.size() > 4 && (output.substr(output.size() - 4) == ".glb" || output.substr(output.size() - 4) == ".GLB"); }
    bool wanted(uint32_t mesh) const { return !mesh_index || *mesh_index == mesh; }
};

// Parses the command line into `o`; an exit code when done (help, version, usage error), else -1.
int parse_options(Options& o, int argc, char** argv) {
    CLI::App app{"tomextract: write the meshes of a .tom file at one resolution as OBJ or PLY"};
    app.set_version_flag("--version", "tomextract 0.1.0");
    app.add_option("file", o.path, "A .tom file")->required();
    auto* f = app.add_option("-f,--fraction", o.fraction, "Fraction of each mesh's triangles, in [0,1]")->check(CLI::Range(0.0, 1.0));
    auto* t = app.add_option("-t,--triangles", o.triangles,
                             "Triangle count (for several meshes: in total, shared in proportion; a mesh at its floor keeps it and "
                             "the others give up what it takes beyond its share)");
    auto* v = app.add_option("-n,--vertices", o.vertices, "Vertex count (per mesh, clamped to its range)");
    app.add_option("--bytes", o.bytes,
                   "For a streamed file (tombuild --stream): decode only its first B bytes (the last whole chunk at or before B), what a viewer "
                   "shows after B bytes; alone, writes that mesh whole");
    f->excludes(t)->excludes(v);
    t->excludes(v);
    auto* l = app.add_option("--lods", o.lods, "Levels in % of the triangles, finest first, into one .glb with MSFT_lod (e.g. 100,50,25,10)")
                  ->delimiter(',')
                  ->check(CLI::Range(0.0, 100.0));
    l->excludes(f)->excludes(t)->excludes(v);
    auto* by_max_error = app.add_option("--max-error", o.max_error_text,
                             "Each mesh at its coarsest level whose measured error (the stored error curve) is at most E: a fraction of the "
                             "mesh's diagonal, or a percentage (0.5%)");
    auto* le = app.add_option("--lods-error", o.lods_error_text, "Levels by error, finest first, into one .glb with MSFT_lod (e.g. 0.1%,0.5%,2%)")->delimiter(',');
    auto* px = app.add_option("--max-error-px", o.max_error_px, "The error bound in pixels on screen, with --distance, --fov and --height")->check(CLI::PositiveNumber);
    app.add_option("--distance", o.distance, "With --max-error-px: the distance from the eye, in the mesh's units")->check(CLI::PositiveNumber);
    app.add_option("--fov", o.fov_deg, "With --max-error-px: the vertical field of view in degrees")->check(CLI::Range(0.01, 179.0));
    app.add_option("--height", o.height, "With --max-error-px: the viewport's height in pixels")->check(CLI::Range(1u, 1000000u));
    app.add_option("--error-metric", o.metric, "What --max-error bounds: max (the Hausdorff distance, default) or mean (Metro's mean)")
        ->check(CLI::IsMember({"max", "mean"}));
    auto* sb = app.add_option("--scene-budget", o.scene_budgets,
                              "The whole scene in N triangles drawn (each mesh's count times its instances), shared among its meshes so that "
                              "the scene's mean error (Metro's, each instance weighted by its area) is least; several, finest first, "
                              "write a .glb chain "
                              "(e.g. 200000,50000,10000)")
                   ->delimiter(',')
                   ->check(CLI::PositiveNumber);
    for (auto* bound : {by_max_error, le, px, sb}) bound->excludes(f)->excludes(t)->excludes(v)->excludes(l);
    sb->excludes(by_max_error)->excludes(le)->excludes(px);
    by_max_error->excludes(le)->excludes(px);
    le->excludes(px);
    app.add_flag("--below-floor", o.below_floor,
                 "Let --fraction, --triangles, --lods, the error bounds and --scene-budget go below each mesh's usable floor (tombuild --floor-error) "
                 "to the coarsest level of its chain; --vertices always may");
    app.add_option("-m,--mesh", o.mesh_index, "Only this mesh (index as tominfo lists it); default: all meshes in one file");
    app.add_option("-o,--output", o.output, "Output .obj, .ply or .glb (binary glTF, with the file's materials and instances)")->required();
    app.add_option("--texture-dir", o.texture_dir,
                   "For .glb and .obj: the folder the stored texture URIs are relative to (default: the source asset's, from the manifest "
                   "tombuild wrote beside the .tom); they are rewritten relative to the output");
    app.add_flag("--embed-images", o.embed_images,
                 "For .glb: also embed the images that are files (read from --texture-dir); images stored in the .tom are always embedded");
    app.add_flag("--refit", o.refit,
                 "Move each level's vertices to where they best stand for the full mesh's surface (the quadric of the triangles they "
                 "replaced, then fitted to the surface, each kept where the error around it is smallest; as gltfpack -sv), their normals, texture coordinates, colours and tangents the source's there: each level "
                 "written with vertex streams of its own, no longer a prefix of the .tom's vertex array (in a .glb chain, joints, weights "
                 "and targets stay shared); open edges, edges where parts meet and coincident copies stay joined");
    app.add_flag("-c,--compress", o.compress,
                 "For .glb: quantize the vertex streams (KHR_mesh_quantization) and compress vertex and index data "
                 "(EXT_meshopt_compression), as gltfpack -c does; both extensions are then required");
    app.footer("Exit codes: 0 ok, 1 unreadable input or unwritable output, 2 usage error.\n"
               "Examples: tomextract out/bunny00.tom --fraction 0.1 -o bunny10.obj\n"
               "          tomextract out/bunny00.tom --max-error 0.5% -o bunny-half-percent.obj\n"
               "          tomextract out/bunny00.tom --lods 100,50,25,10 -o bunny-lods.glb\n"
               "          tomextract out/scene.tom --scene-budget 20000 -o scene-20k.glb\n"
               "          tomextract out/bunny00.tom --bytes 50000 -o bunny-50kB.glb   (a file of tombuild --stream)");
    return tools::parse(app, argc, argv);
}

int usage_error(const std::string& message) {
    std::fprintf(stderr, "error: %s\n", message.c_str());
    return tools::exit_usage;
}

// The options that CLI11 cannot check alone, the error bounds parsed; an exit code when they do
// not hold, else -1.
int check_options(Options& o) {
    try {
        if (!o.max_error_text.empty()) o.error_bounds.push_back(tools::parse_fraction(o.max_error_text, "--max-error"));
        for (const std::string& text : o.lods_error_text) o.error_bounds.push_back(tools::parse_fraction(text, "--lods-error"));
    } catch (const std::invalid_argument& bad) {
        return usage_error(bad.what());
    }
    if (o.max_error_px && (!o.distance || !o.fov_deg || !o.height)) return usage_error("--max-error-px needs --distance, --fov and --height");
    const bool level_chosen = o.fraction || o.triangles || o.vertices || !o.lods.empty() || o.by_error() || !o.scene_budgets.empty();
    if (o.bytes && !level_chosen) o.fraction = 1.0;  // the decoded prefix, whole
    else if (!level_chosen)
        return usage_error("give one of --fraction, --triangles, --vertices, --lods, --max-error, --max-error-px, --lods-error or --scene-budget");
    const std::string not_glb = "'" + o.output + "' is not one";
    if (o.compress && !o.glb()) return usage_error("-c compresses a .glb; " + not_glb);
    if (o.embed_images && !o.glb()) return usage_error("--embed-images writes images into a .glb; " + not_glb);
    if (!o.lods_error_text.empty() && !o.glb()) return usage_error("--lods-error writes a .glb (MSFT_lod); " + not_glb);
    if (o.scene_budgets.size() > 1 && !o.glb()) return usage_error("several --scene-budget values write a .glb (MSFT_lod); " + not_glb);
    if (!o.lods.empty() && !o.glb()) return usage_error("--lods writes a .glb (MSFT_lod); " + not_glb);
    return -1;
}

// Mesh m's resolution for bound k of the error bounds (or the pixel bound), from its stored curve.
uint32_t level_for_error(const Options& o, const tom::MeshView& m, size_t k) {
    const std::optional<tom::ErrorCurve> curve = tom::read_error_curve(m);
    if (!curve) throw tom::ArgumentError(o.path + ": mesh '" + std::string(m.name) + "' has no stored error curve (it was built with --no-error-curve)");
    double bound = 0;
    if (o.max_error_px) {
        const double pixel = 2.0 * *o.distance * std::tan(*o.fov_deg * 3.14159265358979323846 / 360.0) / double(*o.height);  // object units a pixel spans
        bound = curve->diagonal > 0 ? *o.max_error_px * pixel / double(curve->diagonal) : 0.0;
    } else {
        bound = o.error_bounds[k];
    }
    return tom::vertex_count_for_error(m, *curve, bound, o.metric == "max", o.floor());
}

// --scene-budget: each budget's share, a resolution per wanted mesh (file order).
std::vector<std::vector<uint32_t>> share_scene_budgets(const tom::File& file, const Options& o) {
    std::vector<std::vector<uint32_t>> levels;
    if (o.scene_budgets.empty()) return levels;
    const std::vector<tcr::BudgetMesh> meshes = budget_meshes(file, o.mesh_index, o.floor(), o.path);  // once for every budget
    for (const double budget : o.scene_budgets) {
        const tcr::BudgetShare share = tcr::share_budget(meshes, budget);
        if (share.feasible)
            std::printf("%s: scene budget %.0f triangles: %.0f drawn, estimated mean error %.6g (world units, from the stored curves), "
                        "certified within %.2f%% of the optimum\n",
                        o.path.c_str(), budget, share.drawn, share.error, 100.0 * share.gap);
        else
            std::fprintf(stderr, "warning: %s: the meshes' floors draw %.0f triangles, more than the budget of %.0f; each is at its floor\n",
                         o.path.c_str(), share.drawn, budget);
        levels.push_back(share.vertex_counts);
    }
    return levels;
}

// --triangles: the proportional share, a resolution per wanted mesh (file order); warns when the
// floors hold more.
std::vector<uint32_t> share_triangles(const tom::File& file, const Options& o) {
    const std::vector<uint32_t> shared = proportional_levels(file, o.mesh_index, o.floor(), *o.triangles);
    uint64_t total = 0;
    for (size_t k = 0, i = 0; i < file.mesh_count(); ++i)
        if (o.wanted(uint32_t(i))) total += tom::active_triangle_count(file.mesh(uint32_t(i)), shared[k++]);
    if (total > *o.triangles)
        std::fprintf(stderr, "warning: %s: the meshes' floors hold %llu triangles, more than the %llu asked for; each is at its floor\n",
                     o.path.c_str(), static_cast<unsigned long long>(total), static_cast<unsigned long long>(*o.triangles));
    return shared;
}

// Each wanted mesh's resolutions, finest first (one unless a chain of levels was asked), by
// whichever option chose them.
std::vector<std::vector<uint32_t>> choose_levels(const tom::File& file, const Options& o) {
    const std::vector<std::vector<uint32_t>> budget_levels = share_scene_budgets(file, o);
    const std::vector<uint32_t> shared = o.triangles ? share_triangles(file, o) : std::vector<uint32_t>();
    std::vector<std::vector<uint32_t>> levels;
    for (uint32_t i = 0, k = 0; i < file.mesh_count(); ++i) {
        if (!o.wanted(i)) continue;
        const tom::MeshView& m = file.mesh(i);
        std::vector<uint32_t> n;
        if (!o.lods.empty()) {
            for (double pct : o.lods) n.push_back(tom::vertex_count_for_fraction(m, pct / 100.0, o.floor()));
        } else if (o.by_error()) {
            for (size_t b = 0; b < std::max<size_t>(1, o.error_bounds.size()); ++b) n.push_back(level_for_error(o, m, b));
        } else if (!budget_levels.empty()) {
            for (const std::vector<uint32_t>& budget : budget_levels) n.push_back(budget[k]);
        } else if (o.fraction) {
            n.push_back(tom::vertex_count_for_fraction(m, *o.fraction, o.floor()));
        } else if (o.triangles) {
            n.push_back(shared[k]);
        } else {
            n.push_back(uint32_t(std::min<uint64_t>(*o.vertices, m.vertex_count)));
        }
        levels.push_back(std::move(n));
        ++k;
    }
    return levels;
}

// With --refit, each wanted mesh's levels with their re-fitted vertex streams (views of the
// file's meshes); without, nothing: the file's meshes are written as they are.
struct Refits {
    std::vector<std::vector<tom::RefitLevel>> levels;     // per mesh, per level (empty for the others)
    std::vector<std::vector<tom::MeshView>> views;        // views of those
    // mesh i as written at its first level (OBJ, PLY)
    const tom::MeshView& first(const tom::File& file, uint32_t i) const { return views[i].empty() ? file.mesh(i) : views[i].front(); }
};

Refits refit_meshes(const tom::File& file, const Options& o, const std::vector<std::vector<uint32_t>>& levels) {
    Refits out;
    out.levels.resize(file.mesh_count());
    out.views.resize(file.mesh_count());
    if (!o.refit) return out;
    tom::RefitStats total;
    for (uint32_t i = 0, k = 0; i < file.mesh_count(); ++i) {
        if (!o.wanted(i)) continue;
        for (const uint32_t n : levels[k++]) {
            out.levels[i].push_back(tom::refit_level(file.mesh(i), n));
            const tom::RefitStats& s = out.levels[i].back().stats;
            total.moved += s.moved, total.fixed += s.fixed, total.reverted += s.reverted, total.kept += s.kept;
        }
        for (const tom::RefitLevel& r : out.levels[i]) out.views[i].push_back(tom::refit_view(file.mesh(i), r));
    }
    std::printf("re-fitted: %u points moved, %u on open edges or where parts meet left in place, %u where no move lowered the error, %u put back (a "
                "triangle would turn over)\n",
                total.moved, total.fixed, total.kept, total.reverted);
    return out;
}

// A .glb of the wanted meshes at their levels (MSFT_lod for a chain), with the scene.
void write_glb(const tom::File& file, const Refits& refits, const Options& o, const std::vector<std::vector<uint32_t>>& levels) {
    std::vector<tom::GlbMesh> glb;
    uint64_t written = 0;
    tom::Scene scene = file.scene();  // with --mesh: that mesh's instances, renumbered
    if (o.mesh_index) {
        scene.gltf = tom::SourceGltf{};  // the source's node tree names every mesh: one mesh gets its instances' nodes
        std::vector<tom::Instance> kept;
        for (tom::Instance inst : scene.instances)
            if (inst.mesh == *o.mesh_index) inst.mesh = 0, kept.push_back(inst);
        scene.instances.swap(kept);
    }
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        if (!o.wanted(i)) continue;
        tom::GlbMesh g;
        g.mesh = &file.mesh(i);
        g.vertex_counts = levels[glb.size()];
        for (const tom::MeshView& level : refits.views[i]) g.level_views.push_back(&level);  // --refit: each level's own streams
        written += tom::active_triangle_count(*g.mesh, g.vertex_counts.front());
        glb.push_back(g);
    }
    tom::export_glb(o.output, glb, scene, o.texture_dir, o.embed_images, o.compress);
    const size_t level_count = glb.empty() ? 0 : glb.front().vertex_counts.size();
    const size_t instances = tom::draw_list(scene, uint32_t(glb.size())).size();
    std::printf("%s: %zu mesh%s, %zu level%s, %llu triangles at the finest, %zu material%s, %zu instance%s -> %s\n", o.path.c_str(), glb.size(),
                glb.size() == 1 ? "" : "es", level_count, level_count == 1 ? "" : "s", static_cast<unsigned long long>(written),
                scene.materials.size(), scene.materials.size() == 1 ? "" : "s", instances, instances == 1 ? "" : "s", o.output.c_str());
}

// An OBJ or PLY of the wanted meshes, each at its (first) level.
void write_meshes(const tom::File& file, const Refits& refits, const Options& o, const std::vector<std::vector<uint32_t>>& levels) {
    std::vector<tom::ExportPart> parts;
    uint64_t out_tris = 0, out_verts = 0, total_tris = 0;
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        if (!o.wanted(i)) continue;
        const tom::MeshView& m = refits.first(file, i);
        const uint32_t n = levels[parts.size()].front();
        total_tris += m.triangle_count;
        tom::ExportPart part;
        part.mesh = &m;
        part.indices.resize(size_t(tom::active_triangle_count(m, n)) * 3);
        part.draws.resize(tom::part_count(m));
        const tom::Extracted r = tom::extract_parts(m, n, part.indices.data(), part.indices.size(), part.draws.data());
        part.vertex_count = r.vertex_count;
        part.indices.resize(size_t(r.triangle_count) * 3);
        out_tris += r.triangle_count;
        out_verts += r.vertex_count;
        parts.push_back(std::move(part));
    }
    tom::export_meshes(o.output, parts, file.scene(), o.texture_dir);
    std::printf("%s: %zu mesh%s, %llu vertices, %llu triangles (%.2f%% of %llu) -> %s\n", o.path.c_str(), parts.size(), parts.size() == 1 ? "" : "es",
                static_cast<unsigned long long>(out_verts), static_cast<unsigned long long>(out_tris),
                total_tris ? 100.0 * double(out_tris) / double(total_tris) : 0.0, static_cast<unsigned long long>(total_tris), o.output.c_str());
}

/// --bytes: what the first B bytes of a streamed file decode to; a warning when they end before
/// its deferred block and it holds what the output would carry (embedded images, the source glTF
/// scene: the provenance alone is not written out).
tom::File open_prefix(const std::string& path, uint64_t bytes) {
    if (!tom::is_stream_file(path)) return tom::open_any(path, bytes);  // (its error)
    const tom::StreamDecoder d = tom::read_stream(path, bytes);
    const tom::StreamDeferred& deferred = d.deferred();
    std::string missing;
    for (const std::string& s : deferred.sections)
        if (s == "IMAG" || s == "GLTF")
            missing += std::string(missing.empty() ? "" : " and ") + (s == "IMAG" ? "its embedded images" : "its source glTF scene");
    if (!d.deferred_received() && d.has_directory() && !missing.empty())
        std::fprintf(stderr, "warning: %s: the first %llu bytes end before the deferred sections (bytes %llu to %llu): the output lacks %s\n", path.c_str(),
                     static_cast<unsigned long long>(bytes), static_cast<unsigned long long>(deferred.begin_byte),
                     static_cast<unsigned long long>(deferred.end_byte), missing.c_str());
    return d.file();
}

} // namespace

int main(int argc, char** argv) {
    Options o;
    if (const int code = parse_options(o, argc, argv); code >= 0) return code;
    if (const int code = check_options(o); code >= 0) return code;
    try {
        const tom::File file = o.bytes ? open_prefix(o.path, *o.bytes) : tom::open_any(o.path);
        if (o.mesh_index && *o.mesh_index >= file.mesh_count())
            return usage_error(o.path + " has " + std::to_string(file.mesh_count()) + " meshes; --mesh " + std::to_string(*o.mesh_index) + " does not exist");
        if (o.texture_dir.empty()) o.texture_dir = source_folder(o.path, file.scene());
        if (const std::filesystem::path parent = std::filesystem::path(o.output).parent_path(); !parent.empty()) {
            std::error_code ec;
            std::filesystem::create_directories(parent, ec);  // a failure shows when the file is written
        }
        const std::vector<std::vector<uint32_t>> levels = choose_levels(file, o);
        const Refits refits = refit_meshes(file, o, levels);
        if (o.glb())
            write_glb(file, refits, o, levels);
        else
            write_meshes(file, refits, o, levels);
        return tools::exit_ok;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}
