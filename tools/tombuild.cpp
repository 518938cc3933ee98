// tombuild: converts mesh files (OBJ, PLY, OFF, STL, glTF, GLB) or folders of them into .tom files.

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <thread>

#include "tom/builder.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/import.h"
#include "tool_common.h"

namespace fs = std::filesystem;

namespace {

struct Options {
    std::vector<std::string> inputs;
    std::string outdir;
    unsigned jobs = 1;
    std::string predicate = "quadric";
    std::string strategy = "passes";
    float pair_threshold = 0.0f;
    float pass_fraction = 0.2f;
    std::string index_size = "auto";
    bool progress = false;
    bool quiet = false;
    int verbose = 0;
};

struct Outcome {
    bool ok = false;
    std::string text;  // what to print for this input (stdout if ok, stderr otherwise)
};

Outcome convert(const tools::Job& job, const Options& opt, const tom::BuildParams& params, const tom::WriteOptions& wopt) {
    Outcome out;
    const auto start = std::chrono::steady_clock::now();
    try {
        tom::ImportResult imported = tom::import_file(job.input);
        if (imported.meshes.empty())
            throw tom::ImportError(job.input + ": no triangle primitives (" + std::to_string(imported.skipped.size()) + " skipped)");
        std::vector<tom::TomMesh> built;
        uint64_t vertices = 0, triangles = 0, fv_bytes = 0;
        std::string details;
        for (tom::Mesh& mesh : imported.meshes) {
            const tom::CleanStats clean = tom::clean_mesh(mesh);
            if (mesh.indices.empty()) throw tom::ImportError(job.input + ": mesh '" + mesh.name + "' has no non-degenerate triangle");
            tom::BuildStats stats;
            built.push_back(tom::build(mesh, params, &stats));
            const tom::TomMesh& t = built.back();
            vertices += t.vertex_count();
            triangles += t.triangle_count();
            fv_bytes += tools::face_vertex_bytes(t.vertex_count(), t.triangle_count());
            if (opt.verbose > 0) {
                char line[512];
                std::snprintf(line, sizeof line,
                              "  mesh '%s': %u vertices, %u triangles, coarsest %u vertices / %u triangles; %u substitutions, %u locked, "
                              "%u border vertices, %u passes%s%s\n",
                              t.name.c_str(), t.vertex_count(), t.triangle_count(), t.min_vertex_count,
                              tom::active_triangle_count(t.view(), t.min_vertex_count), stats.substitutions, stats.locked_vertices,
                              stats.border_vertices, stats.passes, clean.degenerate_triangles ? (", " + std::to_string(clean.degenerate_triangles) + " degenerate triangles dropped").c_str() : "",
                              clean.unreferenced_vertices ? (", " + std::to_string(clean.unreferenced_vertices) + " unused vertices dropped").c_str() : "");
                details += line;
            }
        }
        std::error_code ec;
        fs::create_directories(fs::path(job.output).parent_path(), ec);
        const std::vector<uint8_t> bytes = tom::serialize(built, wopt);
        tom::write_bytes_atomically(job.output, bytes.data(), bytes.size());
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        char line[1024];
        std::snprintf(line, sizeof line, "%s: %zu mesh%s, %llu vertices, %llu triangles -> %s (%s, %.1f%% of face-vertex) in %.2f s\n",
                      job.input.c_str(), built.size(), built.size() == 1 ? "" : "es", static_cast<unsigned long long>(vertices),
                      static_cast<unsigned long long>(triangles), job.output.c_str(), tools::human_bytes(bytes.size()).c_str(),
                      fv_bytes ? 100.0 * double(bytes.size()) / double(fv_bytes) : 0.0, seconds);
        out.text = line + details;
        for (const std::string& s : imported.skipped) out.text += "  skipped " + s + "\n";
        if (opt.verbose > 0)
            for (const std::string& w : imported.warnings) out.text += "  warning: " + w + "\n";
        out.ok = true;
    } catch (const std::exception& e) {
        out.text = std::string("error: ") + e.what() + "\n";
    }
    return out;
}

void draw_progress(size_t done, size_t total, size_t failed) {
    const int width = 30;
    const int filled = total ? int(double(done) / double(total) * width) : width;
    std::fprintf(stderr, "\r[%.*s%*s] %zu/%zu files%s", filled, "==============================", width - filled, "", done, total,
                 failed ? (", " + std::to_string(failed) + " failed").c_str() : "");
    std::fflush(stderr);
}

} // namespace

int main(int argc, char** argv) {
    Options opt;
    CLI::App app{"tombuild: simplify meshes by greedy vertex substitution into Totally Ordered Meshes (.tom)"};
    app.set_version_flag("--version", "tombuild 0.1.0 (format " + std::to_string(tom::format_version_major) + "." +
                                          std::to_string(tom::format_version_minor) + ")");
    app.add_option("inputs", opt.inputs, "Mesh files (obj, ply, off, stl, gltf, glb) or folders, searched recursively")
        ->required()
        ->group("Basics");
    app.add_option("-o,--output", opt.outdir, "Output folder; one .tom per input, sub-folders mirrored")->required()->group("Basics");
    app.add_option("-j,--jobs", opt.jobs, "Files converted in parallel (default 1)")->check(CLI::Range(1u, 256u))->group("Basics");
    app.add_flag("--progress", opt.progress, "Show a progress bar on stderr even when it is not a terminal")->group("Basics");
    app.add_flag("-q,--quiet", opt.quiet, "Print only errors")->group("Basics");
    app.add_flag("-v,--verbose", opt.verbose, "Per-mesh statistics, reader warnings")->group("Basics");
    app.add_option("--predicate", opt.predicate, "Fairness predicate: quadric (default) or memoryless (the TOM paper's penalty)")
        ->check(CLI::IsMember({"quadric", "memoryless"}))
        ->group("Simplification");
    app.add_option("--strategy", opt.strategy, "Greedy order: passes (default, independent substitutions per pass) or heap")
        ->check(CLI::IsMember({"passes", "heap"}))
        ->group("Simplification");
    app.add_option("-t,--pair-threshold", opt.pair_threshold,
                   "Also substitute non-edge vertex pairs closer than this, in object units (default 0: edges only)")
        ->check(CLI::NonNegativeNumber)
        ->group("Simplification");
    app.add_option("--pass-fraction", opt.pass_fraction, "passes: share of live vertices one pass may remove, (0,1] (default 0.2)")
        ->check(CLI::Range(0.0001f, 1.0f))
        ->group("Simplification");
    app.add_option("--index-size", opt.index_size, "Stored index width: auto (16-bit when a mesh allows; default), 16 or 32")
        ->check(CLI::IsMember({"auto", "16", "32"}))
        ->group("Output");
    app.footer("Exit codes: 0 every input converted, 1 some inputs failed (the others are still written), 2 usage error.\n"
               "Example: tombuild data/meshes/bunny00.off assets/ -o out/ -j 2");
    if (const int code = tools::parse(app, argc, argv); code >= 0) return code;

    try {
        tom::BuildParams params;
        params.predicate = opt.predicate == "memoryless" ? tom::Predicate::memoryless : tom::Predicate::quadric;
        params.strategy = opt.strategy == "heap" ? tom::Strategy::heap : tom::Strategy::passes;
        params.pair_threshold = opt.pair_threshold;
        params.pass_fraction = opt.pass_fraction;
        tom::WriteOptions wopt;
        wopt.index_size = opt.index_size == "32" ? tom::IndexSize::bits32 : opt.index_size == "16" ? tom::IndexSize::bits16 : tom::IndexSize::automatic;

        std::vector<std::string> errors;
        const std::vector<tools::Job> jobs = tools::plan_jobs(opt.inputs, opt.outdir, ".tom", errors);
        for (const std::string& e : errors) std::fprintf(stderr, "error: %s\n", e.c_str());
        std::error_code ec;
        fs::create_directories(opt.outdir, ec);
        if (ec) {
            std::fprintf(stderr, "error: cannot create output folder '%s': %s\n", opt.outdir.c_str(), ec.message().c_str());
            return tools::exit_failed;
        }
        const bool show_progress = (opt.progress || tools::is_terminal(2)) && !opt.quiet && jobs.size() > 1;
        std::atomic<size_t> next{0};
        size_t done = 0, failed = errors.size();
        std::mutex print_mutex;
        auto worker = [&] {
            for (size_t i; (i = next++) < jobs.size();) {
                const Outcome r = convert(jobs[i], opt, params, wopt);
                std::lock_guard<std::mutex> lock(print_mutex);
                ++done;
                if (!r.ok) ++failed;
                if (show_progress) std::fprintf(stderr, "\r%*s\r", 60, "");
                if (!r.ok)
                    std::fputs(r.text.c_str(), stderr);
                else if (!opt.quiet)
                    std::fputs(r.text.c_str(), stdout);
                std::fflush(stdout);
                if (show_progress) draw_progress(done, jobs.size(), failed);
            }
        };
        std::vector<std::thread> pool;
        const unsigned threads = std::min<unsigned>(opt.jobs, unsigned(std::max<size_t>(1, jobs.size())));
        for (unsigned k = 1; k < threads; ++k) pool.emplace_back(worker);
        worker();
        for (std::thread& t : pool) t.join();
        if (show_progress) std::fprintf(stderr, "\n");
        if (!opt.quiet || failed)
            std::fprintf(failed ? stderr : stdout, "%zu of %zu inputs converted%s\n", jobs.size() + errors.size() - failed,
                         jobs.size() + errors.size(), failed ? (", " + std::to_string(failed) + " failed").c_str() : "");
        if (jobs.empty() && errors.empty()) {
            std::fprintf(stderr, "error: no mesh files found in the inputs\n");
            return tools::exit_failed;
        }
        return failed ? tools::exit_failed : tools::exit_ok;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}
