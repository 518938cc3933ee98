// tombuild: converts mesh files (OBJ, PLY, OFF, STL, glTF, GLB) or folders of them into .tom files.

#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <new>
#include <thread>
#include <utility>

#include <poll.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "tom/builder/builder.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/builder/writer.h"
#include "tom/format.h"
#include "tom/io/import.h"
#include "tom/metrics/report.h"
#include "batch.h"
#include "tom/metrics/report_json.h"
#include "tool_common.h"

namespace fs = std::filesystem;

namespace {

struct Options {
    std::vector<std::string> inputs;
    std::string outdir;
    unsigned jobs = 1;
    tools::BuildOptions build;
    std::string index_size = "auto";
    bool progress = false;
    bool mesh_progress = false;     // a line per input's stages (set by main: a terminal, one job at a time)
    bool quiet = false;
    int verbose = 0;
    bool report = false;
    std::string report_json_dir;
    std::vector<double> levels_percent = {50, 25, 10, 5, 2, 1, 0.5};
    double samples_per_face = 10.0;
    uint64_t seed = 1;
    bool no_error_curve = false;
    uint32_t curve_points = 16;
    double floor_error_percent = 1.0;  // the usable floor's bound on the mean error; 0: none
    double timeout_seconds = 3600;  // per input
    double max_memory_mb = 0;       // per input; 0: three quarters of the machine's memory over the jobs
    bool isolate = true;            // each input in a worker process of its own
    bool force = false;             // convert even the inputs whose output is up to date
    bool prune = false;             // remove outputs whose input is gone
    std::string shard = "0/1";      // --shard K/N | auto | auto/N
    std::string merge_dir;          // --merge OUTDIR
};

const std::string tool_version = "tombuild 0.1.0 (format " + std::to_string(tom::format_version_major) + "." + std::to_string(tom::format_version_minor) + ")";

// Every option that changes a .tom's bytes (its provenance records them): not the thread or
// job count, and the error curve's sampling only when the curve is stored.
nlohmann::ordered_json output_options(const Options& opt, const tom::BuildParams& params) {
    nlohmann::ordered_json j;
    j["build"] = tools::build_params_json(params);
    j["weld"] = !opt.build.no_weld;
    j["index_size"] = opt.index_size;
    j["error_curve"] = !opt.no_error_curve;
    if (!opt.no_error_curve) {
        j["curve_points"] = opt.curve_points;
        j["floor_error"] = opt.floor_error_percent;
        j["samples_per_face"] = opt.samples_per_face;
        j["seed"] = opt.seed;
    }
    return j;
}

// The options that change a JSON report besides its .tom's.
nlohmann::ordered_json report_options(const Options& opt) {
    return {{"levels", opt.levels_percent}, {"samples_per_face", opt.samples_per_face}, {"seed", opt.seed}};
}

struct Outcome {
    bool ok = false;
    std::string text;         // what to print for this input (stdout if ok, stderr otherwise)
    std::string summary_csv;  // rows of the batch summary, one per mesh (with --report-json)
    std::string digest;       // of the input as converted
    uint64_t triangles = 0;
    std::vector<std::string> dropped;  // what the input holds that the output does not
};

// What a conversion needs besides the job: the settings, and what the provenance records.
struct Settings {
    tom::BuildParams params;
    tom::CleanOptions clean;
    tom::WriteOptions write;
    tom::ReportParams report;
    nlohmann::ordered_json output_options, report_options;
};

tom::ReportParams report_params(const Options& opt, unsigned threads) {
    tom::ReportParams rp;
    rp.levels.clear();
    for (double p : opt.levels_percent) rp.levels.push_back(p / 100.0);
    rp.distance.samples_per_face = opt.samples_per_face;
    rp.distance.seed = opt.seed;
    rp.distance.threads = threads;
    rp.curve_points = opt.curve_points;
    rp.floor_error = opt.floor_error_percent / 100.0;
    rp.error_curve = !opt.no_error_curve;
    return rp;
}

// The mesh's error curve and, with a bound, its usable floor, into its metadata; the floor's
// vertex count (0: none stored).
uint32_t store_curve(tom::TomMesh& t, const tom::ErrorCurve& curve, double floor_error) {
    t.metadata.push_back({tom::error_curve_key, tom::encode_error_curve(curve)});
    if (!(floor_error > 0)) return 0;
    const tom::UsableFloor floor = tom::usable_floor_of(t.view(), curve, floor_error);
    t.metadata.push_back({tom::usable_floor_key, tom::encode_usable_floor(floor)});
    return floor.vertices;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One input's stages on one line of stderr ("bunny.off: build 45%"), for a long single mesh;
// redrawn at most every quarter second, erased when the input is done.
struct StageLine {
    bool on = false;
    std::string input, shown;  // shown: the stage on the line
    std::chrono::steady_clock::time_point last{};
    void show(const std::string& stage, double fraction = -1) {
        if (!on) return;
        const auto now = std::chrono::steady_clock::now();
        if (stage == shown && fraction < 1 && now - last < std::chrono::milliseconds(250)) return;
        last = now;
        shown = stage;
        char line[160];
        if (fraction >= 0)
            std::snprintf(line, sizeof line, "%.90s: %s %3.0f%%", input.c_str(), stage.c_str(), 100.0 * fraction);
        else
            std::snprintf(line, sizeof line, "%.90s: %s", input.c_str(), stage.c_str());
        std::fprintf(stderr, "\r%-120s", line);
        std::fflush(stderr);
    }
    ~StageLine() {
        if (on) std::fprintf(stderr, "\r%-120s\r", "");
    }
};

// The warning for what a conversion did not carry: one line naming the input and every feature.
std::string dropped_warning(const std::string& input, const std::vector<std::string>& dropped) {
    std::string line = "warning: " + input + ": not carried into the .tom: ";
    for (size_t k = 0; k < dropped.size(); ++k) line += (k ? "; " : "") + dropped[k];
    return line + "\n";
}

Outcome convert(const tools::Job& job, const Options& opt, const Settings& settings, const std::string& report_path) {
    Outcome out;
    const auto start = std::chrono::steady_clock::now();
    StageLine stage;
    stage.on = opt.mesh_progress;
    stage.input = job.input;
    tom::BuildParams params = settings.params;
    tom::ReportParams rparams = settings.report;
    std::string stage_name;
    if (stage.on) {
        params.progress = [&](double f) { stage.show(stage_name, f); };
        rparams.progress = [&](double f) { stage.show(stage_name, f); };
    }
    try {
        stage.show("import");
        tom::ImportResult imported = tom::import_file(job.input);
        tools::Provenance provenance = tools::describe(job.input, imported.sources, tool_version, settings.output_options);
        provenance.dropped = out.dropped = imported.dropped;
        out.digest = provenance.input_digest;
        if (imported.meshes.empty())
            throw tom::MeshError(job.input + ": no triangle primitives (" + std::to_string(imported.skipped.size()) + " skipped)");
        std::vector<tom::CleanStats> cleans;
        for (tom::Mesh& mesh : imported.meshes) {
            cleans.push_back(tom::clean_mesh(mesh, settings.clean));
            if (mesh.indices.empty()) throw tom::MeshError(job.input + ": mesh '" + mesh.name + "' has no non-degenerate triangle");
        }
        const double import_seconds = seconds_since(start);
        struct {
            double build = 0, measure = 0;
        } times;
        std::vector<tom::TomMesh> built;
        uint64_t vertices = 0, triangles = 0, fv_bytes = 0;
        std::string details, tables;
        nlohmann::ordered_json json_meshes = nlohmann::json::array();
        for (size_t mi = 0; mi < imported.meshes.size(); ++mi) {
            const tom::CleanStats& clean = cleans[mi];
            tom::BuildStats stats;
            const auto build_start = std::chrono::steady_clock::now();
            stage_name = imported.meshes.size() > 1 ? "build mesh " + std::to_string(mi + 1) + "/" + std::to_string(imported.meshes.size()) : "build";
            stage.show(stage_name, 0);
            built.push_back(tom::build(std::move(imported.meshes[mi]), params, &stats));  // frees the input as it goes: a lower peak
            stage_name = opt.report || !report_path.empty() ? "report" : "error curve";
            if (imported.meshes.size() > 1) stage_name += " " + std::to_string(mi + 1) + "/" + std::to_string(imported.meshes.size());
            if (!opt.no_error_curve || opt.report || !report_path.empty()) stage.show(stage_name, 0);
            const double build_seconds = seconds_since(build_start);
            times.build += build_seconds;
            const auto measure_start = std::chrono::steady_clock::now();
            tom::TomMesh& t = built.back();
            const bool measured = opt.report || !report_path.empty() || !opt.no_error_curve;
            const tom::Mesh mesh = measured ? tom::original_mesh(t) : tom::Mesh();  // the input again, exactly
            uint32_t floor = 0;  // the usable floor stored (0: none)
            if (opt.report || !report_path.empty()) {
                tom::ReportContext ctx;
                ctx.file = job.input;
                ctx.import_seconds = import_seconds;
                ctx.build_seconds = build_seconds;
                ctx.welded_vertices = clean.welded_vertices;
                ctx.params = rparams;
                const auto report_start = std::chrono::steady_clock::now();
                const tom::MeshReport r = tom::make_report(mesh, t, rparams);
                ctx.report_seconds = seconds_since(report_start);
                if (!opt.no_error_curve) floor = store_curve(t, r.curve, rparams.floor_error);
                if (opt.report) tables += tom::report_table(r, ctx);
                json_meshes.push_back(tom::report_json(r, ctx));
                out.summary_csv += tom::summary_csv_row(json_meshes.back(), job.input);
            } else if (!opt.no_error_curve) {
                floor = store_curve(t, tom::measure_error_curve(mesh, t, rparams), rparams.floor_error);
            }
            times.measure += seconds_since(measure_start);
            vertices += t.vertex_count();
            triangles += t.triangle_count();
            fv_bytes += tools::face_vertex_bytes(t.vertex_count(), t.triangle_count());
            if (opt.verbose > 0) {
                char line[512];
                std::snprintf(line, sizeof line,
                              "  mesh '%s'%s: %u vertices, %u triangles, coarsest %u vertices / %u triangles; %u substitutions, %u locked, "
                              "%u border vertices, %u seam vertices, %u passes%s%s%s%s%s\n",
                              t.name.c_str(), t.parts.empty() ? "" : (" (" + std::to_string(t.parts.size()) + " parts)").c_str(), t.vertex_count(), t.triangle_count(), t.min_vertex_count,
                              tom::active_triangle_count(t.view(), t.min_vertex_count), stats.substitutions, stats.locked_vertices,
                              stats.border_vertices, stats.seam_vertices, stats.passes,
                              floor ? (", usable floor " + std::to_string(floor) + " vertices / " + std::to_string(tom::active_triangle_count(t.view(), floor)) +
                                       " triangles").c_str() : "",
                              stats.pruned_pieces ? (", " + std::to_string(stats.pruned_pieces) + " small pieces pruned").c_str() : "",
                              clean.welded_vertices ? (", " + std::to_string(clean.welded_vertices) + " identical vertices welded").c_str() : "",
                              clean.degenerate_triangles ? (", " + std::to_string(clean.degenerate_triangles) + " degenerate triangles dropped").c_str() : "",
                              clean.unreferenced_vertices ? (", " + std::to_string(clean.unreferenced_vertices) + " unused vertices dropped").c_str() : "");
                details += line;
            }
        }
        std::error_code ec;
        fs::create_directories(fs::path(job.output).parent_path(), ec);
        stage.show("write");
        const auto write_start = std::chrono::steady_clock::now();
        tom::WriteOptions wopt = settings.write;
        wopt.provenance = provenance.text();
        const std::vector<uint8_t> bytes = tom::serialize(built, imported.scene, wopt);
        out.triangles = triangles;
        tom::write_bytes_atomically(job.output, bytes.data(), bytes.size());
        const double write_seconds = seconds_since(write_start);
        if (opt.verbose > 0) {
            char line[256];
            std::snprintf(line, sizeof line, "  seconds: import %.3f, build %.3f, error curve and report %.3f, write %.3f\n", import_seconds, times.build,
                          times.measure, write_seconds);
            details += line;
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        char line[1024];
        std::snprintf(line, sizeof line, "%s: %zu mesh%s, %llu vertices, %llu triangles -> %s (%s, %.1f%% of face-vertex) in %.2f s\n",
                      job.input.c_str(), built.size(), built.size() == 1 ? "" : "es", static_cast<unsigned long long>(vertices),
                      static_cast<unsigned long long>(triangles), job.output.c_str(), tools::human_bytes(bytes.size()).c_str(),
                      fv_bytes ? 100.0 * double(bytes.size()) / double(fv_bytes) : 0.0, seconds);
        out.text = line + details + tables;
        for (const std::string& s : imported.skipped) out.text += "  skipped " + s + "\n";
        if (!report_path.empty()) {
            nlohmann::ordered_json doc;
            doc["file"] = job.input;
            doc["output"] = job.output;
            doc["format"] = imported.format;
            doc.update(tools::build_params_json(params));
            doc["conventions"] = tom::conventions_json(rparams);
            doc["skipped"] = imported.skipped;
            doc["dropped"] = imported.dropped;
            doc["meshes"] = json_meshes;
            // what made the report: its .tom's provenance and the report's own options (a rerun
            // keeps the report when both are unchanged)
            doc["provenance"] = {{"tom", nlohmann::ordered_json::parse(wopt.provenance)}, {"report", settings.report_options}};
            fs::create_directories(fs::path(report_path).parent_path(), ec);
            const std::string text = doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
            tom::write_bytes_atomically(report_path, text.data(), text.size());
        }
        if (opt.verbose > 0)
            for (const std::string& w : imported.warnings) out.text += "  warning: " + w + "\n";
        out.ok = true;
    } catch (const std::bad_alloc&) {
        out.text = "error: " + job.input + ": needs more memory than this process may take" +
                   (opt.isolate ? " (--max-memory " + std::to_string(int64_t(opt.max_memory_mb)) + " MB)" : std::string()) + "\n";
    } catch (const std::exception& e) {
        out.text = std::string("error: ") + e.what() + "\n";
    }
    return out;
}

// The signal (SIGTERM, SIGINT) that asked the batch to stop, 0 while it runs: workers kill their
// conversion, remove its temporary files and start no other; no manifest is written.
volatile std::sig_atomic_t stop_signal = 0;
extern "C" void on_stop_signal(int signal) { stop_signal = signal; }

// --- worker processes ---------------------------------------------------------------------
// Each input is converted in a child process with an address-space limit, watched for a time
// limit: a crash, a hang or a memory-hungry reader fails that input alone, with a message naming
// it and the cause, while the batch goes on. The child sends its Outcome back through a pipe.

void put_string(std::string& wire, const std::string& s) {
    const uint64_t n = s.size();
    wire.append(reinterpret_cast<const char*>(&n), sizeof n);
    wire += s;
}
bool get_string(const std::string& wire, size_t& at, std::string& s) {
    uint64_t n = 0;
    if (at + sizeof n > wire.size()) return false;
    std::memcpy(&n, wire.data() + at, sizeof n);
    at += sizeof n;
    if (n > wire.size() - at) return false;
    s.assign(wire, at, size_t(n));
    at += size_t(n);
    return true;
}

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;  // its shadow memory needs the whole address space
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

// The temporary files a killed child may have left beside `output` (write_bytes_atomically's).
void remove_temporaries(const std::string& output, pid_t child) {
    std::error_code ec;
    const fs::path out(output);
    const std::string prefix = out.filename().string() + ".tmp." + std::to_string(child) + ".";
    for (const fs::directory_entry& e : fs::directory_iterator(out.parent_path().empty() ? "." : out.parent_path(), ec))
        if (e.path().filename().string().rfind(prefix, 0) == 0) fs::remove(e.path(), ec);
}

Outcome convert_isolated(const tools::Job& job, const Options& opt, const Settings& settings, const std::string& report_path) {
    Outcome out;
    int fds[2];
    if (::pipe(fds) != 0) return convert(job, opt, settings, report_path);
    std::fflush(stdout);
    std::fflush(stderr);
    const pid_t child = ::fork();
    if (child < 0) {
        ::close(fds[0]);
        ::close(fds[1]);
        return convert(job, opt, settings, report_path);
    }
    if (child == 0) {
        ::close(fds[0]);
        std::signal(SIGTERM, SIG_DFL);  // a stopped batch ends its workers at once
        std::signal(SIGINT, SIG_DFL);
        if (!kAddressSanitizer && opt.max_memory_mb > 0) {
            const rlim_t bytes = rlim_t(opt.max_memory_mb * 1024.0 * 1024.0);
            const struct rlimit limit = {bytes, bytes};
            ::setrlimit(RLIMIT_AS, &limit);
        }
        const Outcome r = convert(job, opt, settings, report_path);
        std::string wire(1, r.ok ? '1' : '0');
        put_string(wire, r.text);
        put_string(wire, r.summary_csv);
        put_string(wire, r.digest);
        put_string(wire, std::to_string(r.triangles));
        for (const std::string& d : r.dropped) put_string(wire, d);
        for (size_t at = 0; at < wire.size();) {
            const ssize_t n = ::write(fds[1], wire.data() + at, wire.size() - at);
            if (n <= 0) break;
            at += size_t(n);
        }
        ::close(fds[1]);
        ::_exit(0);
    }
    ::close(fds[1]);
    // read what the child sends until it closes the pipe, or the time limit passes
    std::string wire;
    const auto start = std::chrono::steady_clock::now();
    bool timed_out = false, stopped = false;
    for (char buffer[65536];;) {
        const double left = opt.timeout_seconds - seconds_since(start);
        if (left <= 0) {
            timed_out = true;
            break;
        }
        if (stop_signal != 0) {
            stopped = true;
            break;
        }
        struct pollfd pfd = {fds[0], POLLIN, 0};
        const int ready = ::poll(&pfd, 1, int(std::min(left * 1000.0, 1000.0)) + 1);
        if (ready < 0 && errno == EINTR) continue;
        if (ready <= 0) continue;
        const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        wire.append(buffer, size_t(n));
    }
    ::close(fds[0]);
    if (timed_out || stopped) ::kill(child, SIGKILL);
    int status = 0;
    while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
    }
    size_t at = 1;
    std::string triangles;
    if (!timed_out && !stopped && WIFEXITED(status) && WEXITSTATUS(status) == 0 && !wire.empty() && get_string(wire, at, out.text) &&
        get_string(wire, at, out.summary_csv) && get_string(wire, at, out.digest) && get_string(wire, at, triangles)) {
        out.ok = wire[0] == '1';
        out.triangles = std::strtoull(triangles.c_str(), nullptr, 10);
        for (std::string d; get_string(wire, at, d);) out.dropped.push_back(d);
        return out;
    }
    remove_temporaries(job.output, child);
    if (!report_path.empty()) remove_temporaries(report_path, child);
    char reason[256];
    if (stopped)
        std::snprintf(reason, sizeof reason, "stopped by signal %d (%s) before it finished", int(stop_signal), strsignal(stop_signal));
    else if (timed_out)
        std::snprintf(reason, sizeof reason, "took longer than --timeout %g s and was stopped", opt.timeout_seconds);
    else if (WIFSIGNALED(status))
        std::snprintf(reason, sizeof reason, "the conversion crashed (signal %d, %s)%s", WTERMSIG(status), strsignal(WTERMSIG(status)),
                      WTERMSIG(status) == SIGABRT || WTERMSIG(status) == SIGSEGV ? "; at the memory limit a failed allocation can end this way" : "");
    else
        std::snprintf(reason, sizeof reason, "the conversion ended without a result (exit status %d)", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    out.text = "error: " + job.input + ": " + reason + "\n";
    return out;
}

void draw_progress(size_t done, size_t total, size_t failed) {
    const int width = 30;
    const int filled = total ? int(double(done) / double(total) * width) : width;
    std::fprintf(stderr, "\r[%.*s%*s] %zu/%zu files%s", filled, "==============================", width - filled, "", done, total,
                 failed ? (", " + std::to_string(failed) + " failed").c_str() : "");
    std::fflush(stderr);
}

// The .tom files under `outdir` that tombuild made (they have a provenance) and that no input of
// this run maps to: their input is gone, or was not given this time.
std::vector<std::string> find_orphans(const std::string& outdir, const std::vector<tools::Job>& jobs) {
    std::set<std::string> planned;
    for (const tools::Job& j : jobs) planned.insert(fs::path(j.output).lexically_normal().string());
    std::vector<std::string> orphans;
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(outdir, fs::directory_options::skip_permission_denied, ec);
         !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
        if (!it->is_regular_file(ec) || it->path().extension() != ".tom") continue;
        const std::string path = it->path().lexically_normal().string();
        if (planned.count(path)) continue;
        try {
            const tom::File f = tom::File::open(path);
            if (f.provenance().rfind("{\"tool\":\"tombuild", 0) == 0) orphans.push_back(path);
        } catch (const std::exception&) {
        }  // not a .tom of ours: never touched
    }
    std::sort(orphans.begin(), orphans.end());
    return orphans;
}

// Whether the JSON report at `path` belongs to the up-to-date output (its provenance) and the
// report options; if so its summary rows go to `rows`.
bool report_is_current(const std::string& path, const std::string& input, const std::string& provenance, const nlohmann::ordered_json& options,
                       std::string& rows) {
    try {
        std::ifstream in(path);
        if (!in) return false;
        const nlohmann::ordered_json doc = nlohmann::ordered_json::parse(in);
        const nlohmann::ordered_json expected = {{"tom", nlohmann::ordered_json::parse(provenance)}, {"report", options}};
        if (!doc.contains("provenance") || doc["provenance"] != expected) return false;
        for (const auto& mesh : doc.at("meshes")) rows += tom::summary_csv_row(mesh, input);
        return true;
    } catch (const std::exception&) {
        return false;
    }
}

} // namespace

int main(int argc, char** argv) {
    Options opt;
    CLI::App app{"tombuild: simplify meshes by greedy vertex substitution into Totally Ordered Meshes (.tom)"};
    app.set_version_flag("--version", tool_version);
    app.add_option("inputs", opt.inputs, "Mesh files (obj, ply, off, stl, gltf, glb) or folders, searched recursively")->group("Basics");
    app.add_option("-o,--output", opt.outdir, "Output folder; one .tom per input, sub-folders mirrored")->group("Basics");
    app.add_option("-j,--jobs", opt.jobs, "Files converted in parallel (default 1)")->check(CLI::Range(1u, 256u))->group("Basics");
    app.add_flag("--progress", opt.progress, "Show progress on stderr even when it is not a terminal: a bar over the files and, with -j 1, each input's stage (import, build %, error curve %, write)")->group("Basics");
    app.add_flag("-q,--quiet", opt.quiet, "Print only errors")->group("Basics");
    app.add_flag("-v,--verbose", opt.verbose, "Per-mesh statistics, reader warnings")->group("Basics");
    opt.build.add_to(app, "Simplification");
    app.add_option("--index-size", opt.index_size, "Stored index width: auto (16-bit when a mesh allows; default), 16 or 32")
        ->check(CLI::IsMember({"auto", "16", "32"}))
        ->group("Output");
    app.add_flag("--no-error-curve", opt.no_error_curve, "Do not measure and store each mesh's error curve (faster builds and reports; the JSON report's error_curve is null)")->group("Output");
    app.add_option("--curve-points", opt.curve_points, "Error-curve points per mesh, log-spaced in vertex count (default 16)")
        ->check(CLI::Range(2u, 64u))
        ->group("Output");
    app.add_option("--floor-error", opt.floor_error_percent,
                   "Store each mesh's usable floor: the coarsest level from which on the measured mean error stays within PERCENT of the diagonal "
                   "(default 1; 0: none). tomextract, the runtime's vertex_count_for_* and libtcr pick no coarser level unless asked")
        ->check(CLI::Range(0.0, 100.0))
        ->group("Output");
    app.add_flag("--report", opt.report, "Print a report per mesh: Metro-style error, chains and extraction time per level, memory, k/N fit")
        ->group("Reports");
    app.add_option("--report-json", opt.report_json_dir, "Write one JSON report per input (docs/REPORT.md) and summary.csv into this folder")
        ->group("Reports");
    app.add_option("--levels", opt.levels_percent, "Report levels in % of the triangles (default 50,25,10,5,2,1,0.5)")
        ->delimiter(',')
        ->check(CLI::Range(0.0001, 100.0))
        ->group("Reports");
    app.add_option("--samples-per-face", opt.samples_per_face, "Metro sampling density: samples per face of the larger mesh per direction (default 10)")
        ->check(CLI::Range(0.01, 1000.0))
        ->group("Reports");
    app.add_option("--seed", opt.seed, "Sampling seed; the same seed gives the same figures (default 1)")->group("Reports");
    app.add_option("--timeout", opt.timeout_seconds, "Seconds an input may take before it is stopped and reported (default 3600)")
        ->check(CLI::PositiveNumber)
        ->group("Batch");
    app.add_option("--max-memory", opt.max_memory_mb, "MB of address space an input's conversion may take (default: 3/4 of the memory over the jobs)")
        ->check(CLI::PositiveNumber)
        ->group("Batch");
    app.add_flag("!--no-isolate", opt.isolate, "Convert in this process instead of one worker process per input (no --timeout or --max-memory)")
        ->group("Batch");
    app.add_flag("--force", opt.force, "Convert every input, also those whose output is up to date")->group("Batch");
    app.add_flag("--prune", opt.prune, "Remove the outputs (and reports) of tombuild in the output folder that no input maps to any more")->group("Batch");
    app.add_option("--shard", opt.shard,
                   "Convert only shard K of N of the inputs (0 <= K < N, balanced by size, the same split on every machine); auto: K and N "
                   "of a Slurm job array; auto/N: K from Kubernetes' JOB_COMPLETION_INDEX")
        ->group("Batch");
    app.add_option("--merge", opt.merge_dir, "Join the shards' manifests in this output folder into manifest.jsonl and summary.csv; names missing or failed shards")
        ->group("Batch");
    app.footer("Exit codes: 0 every input converted or up to date, 1 some inputs failed (the others are still written), 2 usage error.\n"
               "Example: tombuild data/meshes/bunny00.off assets/ -o out/ -j 2");
    if (const int code = tools::parse(app, argc, argv); code >= 0) return code;

    try {
        if (!opt.merge_dir.empty()) {
            if (!opt.inputs.empty() || !opt.outdir.empty()) {
                std::fprintf(stderr, "error: --merge OUTDIR takes no inputs and no -o\n");
                return tools::exit_usage;
            }
            return tools::merge_shards(opt.merge_dir, opt.quiet);
        }
        if (opt.inputs.empty() || opt.outdir.empty()) {
            std::fprintf(stderr, "error: %s\nRun with --help for more information.\n", opt.inputs.empty() ? "inputs is required" : "--output is required");
            return tools::exit_usage;
        }
        tools::Shard shard;
        try {
            shard = tools::parse_shard(opt.shard);
        } catch (const std::invalid_argument& e) {
            std::fprintf(stderr, "error: %s\n", e.what());
            return tools::exit_usage;
        }
        Settings settings;
        settings.params = opt.build.params();
        settings.clean = opt.build.clean();
        settings.write.index_size = opt.index_size == "32" ? tom::IndexSize::bits32 : opt.index_size == "16" ? tom::IndexSize::bits16 : tom::IndexSize::automatic;
        settings.output_options = output_options(opt, settings.params);
        settings.report_options = report_options(opt);

        std::vector<std::string> errors;
        const std::vector<tools::Job> all_jobs = tools::plan_jobs(opt.inputs, opt.outdir, ".tom", errors);
        for (const std::string& e : errors) std::fprintf(stderr, "error: %s\n", e.c_str());
        std::error_code ec;
        fs::create_directories(opt.outdir, ec);
        if (ec) {
            std::fprintf(stderr, "error: cannot create output folder '%s': %s\n", opt.outdir.c_str(), ec.message().c_str());
            return tools::exit_failed;
        }
        // this run's share of the inputs (all of them without --shard)
        std::vector<size_t> selected;
        {
            std::vector<uint64_t> sizes;
            for (const tools::Job& j : all_jobs) {
                const uintmax_t size = fs::file_size(j.input, ec);
                sizes.push_back(ec ? 0 : uint64_t(size));
            }
            const std::vector<uint32_t> of = tools::assign_shards(all_jobs, sizes, shard.count);
            for (size_t i = 0; i < all_jobs.size(); ++i)
                if (of[i] == shard.index) selected.push_back(i);
        }
        const bool show_progress = (opt.progress || tools::is_terminal(2)) && !opt.quiet && selected.size() > 1;
        opt.mesh_progress = (opt.progress || tools::is_terminal(2)) && !opt.quiet && opt.jobs == 1;
        // the cores shared among the -j jobs: each job's build and report threads
        const unsigned per_job = std::max(1u, std::max(1u, std::thread::hardware_concurrency()) / std::max(1u, opt.jobs));
        settings.report = report_params(opt, per_job);
        if (settings.params.threads == 0) settings.params.threads = per_job;
        if (opt.max_memory_mb == 0) {
            const double total_mb = double(::sysconf(_SC_PHYS_PAGES)) * double(::sysconf(_SC_PAGE_SIZE)) / (1024.0 * 1024.0);
            opt.max_memory_mb = std::max(1024.0, 0.75 * total_mb / double(std::max(1u, opt.jobs)));
        }
        auto report_path_of = [&](const tools::Job& job) -> std::string {
            if (opt.report_json_dir.empty()) return "";
            fs::path rel = fs::path(job.output).lexically_relative(opt.outdir);
            rel.replace_extension(".json");
            return (fs::path(opt.report_json_dir) / rel).string();
        };
        std::signal(SIGTERM, on_stop_signal);
        std::signal(SIGINT, on_stop_signal);

        std::vector<std::string> summary_rows(selected.size());
        std::vector<tools::ManifestRecord> records(selected.size());
        std::atomic<size_t> next{0};
        size_t done = 0, failed = errors.size(), fresh = 0;
        std::mutex print_mutex;
        auto worker = [&] {
            for (size_t s; (s = next++) < selected.size() && stop_signal == 0;) {
                const tools::Job& job = all_jobs[selected[s]];
                const std::string report_path = report_path_of(job);
                const auto start = std::chrono::steady_clock::now();
                tools::ManifestRecord& rec = records[s];
                rec.index = selected[s];
                rec.input = job.input;
                rec.output = job.output;
                rec.report = report_path;
                Outcome r;
                tools::Freshness f;
                if (!opt.force) {
                    try {
                        f = tools::check_output(job.input, job.output, tool_version, settings.output_options);
                    } catch (const std::exception&) {
                        f = tools::Freshness{};  // an unreadable input: the conversion reports it
                    }
                    if (f.up_to_date && !report_path.empty() && !opt.report &&
                        !report_is_current(report_path, job.input, f.provenance, settings.report_options, r.summary_csv))
                        f.up_to_date = false;
                    if (opt.report) f.up_to_date = false;  // the printed report is made by converting
                }
                if (f.up_to_date) {
                    r.ok = true;
                    r.digest = f.digest;
                    r.triangles = f.triangles;
                    r.dropped = f.dropped;
                    r.text = job.input + ": up to date (" + job.output + ")\n";
                } else {
                    r = opt.isolate ? convert_isolated(job, opt, settings, report_path) : convert(job, opt, settings, report_path);
                    if (r.digest.empty()) {
                        try {
                            r.digest = tools::file_digest(job.input);
                        } catch (const std::exception&) {
                        }
                    }
                }
                rec.digest = r.digest == "missing" ? "" : r.digest;
                rec.status = !r.ok ? "failed" : f.up_to_date ? "up to date" : "converted";
                rec.triangles = r.ok ? r.triangles : 0;
                rec.dropped = r.ok ? r.dropped : std::vector<std::string>();
                rec.seconds = seconds_since(start);
                if (!r.ok) {
                    std::string message = r.text;
                    if (message.rfind("error: ", 0) == 0) message.erase(0, 7);
                    while (!message.empty() && message.back() == '\n') message.pop_back();
                    rec.message = message;
                }
                std::lock_guard<std::mutex> lock(print_mutex);
                summary_rows[s] = r.summary_csv;
                ++done;
                if (!r.ok) ++failed;
                if (f.up_to_date) ++fresh;
                if (show_progress) std::fprintf(stderr, "\r%*s\r", 60, "");
                if (!r.ok)
                    std::fputs(r.text.c_str(), stderr);
                else if (!opt.quiet && (!f.up_to_date || opt.verbose > 0))
                    std::fputs(r.text.c_str(), stdout);
                if (r.ok && !f.up_to_date && !r.dropped.empty()) std::fputs(dropped_warning(job.input, r.dropped).c_str(), stderr);
                std::fflush(stdout);
                if (show_progress) draw_progress(done, selected.size(), failed);
            }
        };
        std::vector<std::thread> pool;
        const unsigned threads = std::min<unsigned>(opt.jobs, unsigned(std::max<size_t>(1, selected.size())));
        for (unsigned k = 1; k < threads; ++k) pool.emplace_back(worker);
        worker();
        for (std::thread& t : pool) t.join();
        if (show_progress) std::fprintf(stderr, "\n");
        if (stop_signal != 0) {
            std::fprintf(stderr, "error: stopped by signal %d (%s) after %zu of %zu inputs; no manifest written, a rerun converts the rest\n", int(stop_signal),
                         strsignal(stop_signal), done, selected.size());
            return 128 + stop_signal;
        }
        // outputs whose input is gone: named by every run over the whole batch, removed with
        // --prune (by shard 0 only, so that shards do not race)
        if (shard.index == 0) {
            for (const std::string& orphan : find_orphans(opt.outdir, all_jobs)) {
                if (opt.prune) {
                    fs::remove(orphan, ec);
                    if (const std::string report = report_path_of({"", orphan}); !report.empty()) fs::remove(report, ec);
                    if (!opt.quiet) std::printf("%s: removed (no input maps to it)\n", orphan.c_str());
                } else if (!opt.quiet) {
                    std::printf("%s: no input of this run maps to it (its input is gone?); --prune removes it\n", orphan.c_str());
                }
            }
        }
        tools::ManifestHeader header;
        header.shard = shard;
        header.inputs = all_jobs.size();
        header.report_json = opt.report_json_dir;
        header.summary_header = tom::summary_csv_header(settings.report);
        const std::string manifest = tools::manifest_path(opt.outdir, shard);
        tools::write_manifest(manifest, header, records);
        if (!opt.report_json_dir.empty() && shard.count == 1) {  // shards: tombuild --merge writes it
            std::string csv = header.summary_header;
            for (const std::string& rows : summary_rows) csv += rows;  // input order, whatever -j
            fs::create_directories(opt.report_json_dir, ec);
            const std::string path = (fs::path(opt.report_json_dir) / "summary.csv").string();
            tom::write_bytes_atomically(path, csv.data(), csv.size());
            if (!opt.quiet) std::printf("reports: %s (one JSON per input), %s\n", opt.report_json_dir.c_str(), path.c_str());
        }
        const size_t total = selected.size() + errors.size();
        if (!opt.quiet || failed)
            std::fprintf(failed ? stderr : stdout, "%zu of %zu inputs converted%s%s%s; manifest %s\n", total - failed - fresh, total,
                         fresh ? (", " + std::to_string(fresh) + " up to date").c_str() : "",
                         failed ? (", " + std::to_string(failed) + " failed").c_str() : "",
                         shard.count > 1 ? (" (shard " + shard.name() + " of " + std::to_string(all_jobs.size()) + " inputs)").c_str() : "",
                         manifest.c_str());
        if (all_jobs.empty() && errors.empty()) {
            std::fprintf(stderr, "error: no mesh files found in the inputs\n");
            return tools::exit_failed;
        }
        return failed ? tools::exit_failed : tools::exit_ok;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}
