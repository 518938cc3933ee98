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
#include "tom/stream/stream_file.h"
#include "tool_common.h"

namespace fs = std::filesystem;

namespace {

struct Options {
    std::vector<std::string> inputs;
    std::string outdir;
    unsigned jobs = 1;
    tools::BuildOptions build;
    std::string index_size = "auto";
    bool stream = false;            // write the streamed layout (docs/FORMAT.md, "Streamed files")
    tom::StreamOptions stream_options;
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

// Raised whenever the same input and options give other bytes (the builder's order, the stream
// encoder's layout): it is part of the version a .tom's provenance records, so a rerun after an
// upgrade converts again instead of keeping outputs the new code would not write.
// 2: integrated quadric costs, texture coordinates weighed only when sampled.
// 3: chains where parts meet move along them; joins of two sheets ranked behind manifold moves.
// 4: streams place provenance, images and the source glTF after the first chunks (stream 1.1);
//    a join taken only at the cost the oracle ranked it.
// 5: the stored error curve reaches the coarsest level (was: none below 4 vertices); texture
//    seams keep their shape (edge planes).
constexpr int kOutputRevision = 5;
const std::string tool_version = "tombuild 0.1.0 (format " + std::to_string(tom::format_version_major) + "." + std::to_string(tom::format_version_minor) +
                                 ", output revision " + std::to_string(kOutputRevision) + ")";

// Every option that changes a .tom's bytes (its provenance records them): not the thread or
// job count, and the error curve's sampling only when the curve is stored.
nlohmann::ordered_json output_options(const Options& opt, const tom::BuildParams& params) {
    nlohmann::ordered_json j;
    j["build"] = tools::build_params_json(params);
    j["weld"] = !opt.build.no_weld;
    j["index_size"] = opt.index_size;
    if (opt.stream) {
        const tom::StreamOptions& s = opt.stream_options;
        j["stream"] = {{"position_bits", s.position_bits}, {"normal_bits", s.normal_bits}, {"texcoord_bits", s.texcoord_bits},
                       {"first_chunk", s.first_share},     {"chunk_growth", s.growth},     {"keep_order", s.keep_order}};
    }
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
    bool stream = false;
    tom::StreamOptions stream_options;
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

// One input's conversion as it goes: the settings, the file as imported and cleaned, the
// meshes built, and what the run prints and writes.
struct Conversion {
    const tools::Job& job;
    const Options& opt;
    const Settings& settings;
    const std::string& report_path;  // the JSON report's, or empty
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    StageLine stage;
    std::string stage_name;
    tom::BuildParams params;
    tom::ReportParams rparams;
    tom::ImportResult imported;
    tools::Provenance provenance;
    std::vector<tom::CleanStats> cleans;
    double import_seconds = 0, build_seconds = 0, measure_seconds = 0, write_seconds = 0;
    std::vector<tom::TomMesh> built;
    uint64_t vertices = 0, triangles = 0, fv_bytes = 0, bytes = 0;
    std::string details, tables;  // -v's lines per mesh, --report's tables
    nlohmann::ordered_json json_meshes = nlohmann::json::array();
    std::string tom_provenance;   // as written into the .tom

    Conversion(const tools::Job& j, const Options& o, const Settings& s, const std::string& report)
        : job(j), opt(o), settings(s), report_path(report), params(s.params), rparams(s.report) {
        stage.on = opt.mesh_progress;
        stage.input = job.input;
        if (stage.on) {
            params.progress = [this](double f) { stage.show(stage_name, f); };
            rparams.progress = [this](double f) { stage.show(stage_name, f); };
        }
    }
    Conversion(const Conversion&) = delete;
    bool reported() const { return opt.report || !report_path.empty(); }
    std::string of_meshes(size_t mi) const {
        return imported.meshes.size() > 1 ? " " + std::to_string(mi + 1) + "/" + std::to_string(imported.meshes.size()) : "";
    }
};

// The file read, its provenance described, every mesh cleaned (welded unless --no-weld).
void import_input(Conversion& c, Outcome& out) {
    c.stage.show("import");
    c.imported = tom::import_file(c.job.input);
    c.provenance = tools::describe(c.job.input, c.imported.sources, tool_version, c.settings.output_options);
    c.provenance.dropped = out.dropped = c.imported.dropped;
    out.digest = c.provenance.input_digest;
    if (c.imported.meshes.empty())
        throw tom::MeshError(c.job.input + ": no triangle primitives (" + std::to_string(c.imported.skipped.size()) + " skipped)");
    for (tom::Mesh& mesh : c.imported.meshes) {
        c.cleans.push_back(tom::clean_mesh(mesh, c.settings.clean));
        if (mesh.indices.empty()) throw tom::MeshError(c.job.input + ": mesh '" + mesh.name + "' has no non-degenerate triangle");
    }
    c.import_seconds = seconds_since(c.start);
}

// Whether a texture of one of the mesh's materials (its own, its parts') is mapped through
// TEXCOORD_0: only then do the coordinates weigh in the build (BuildParams::weigh_texcoords).
bool samples_texcoord0(const tom::Mesh& mesh, const tom::Scene& scene) {
    auto samples = [&](int32_t material) {
        if (material < 0 || size_t(material) >= scene.materials.size()) return false;
        for (const tom::TextureRef& texture : scene.materials[size_t(material)].textures)
            if (texture.texcoord == 0) return true;
        return false;
    };
    if (samples(mesh.material)) return true;
    for (const tom::Part& part : mesh.parts)
        if (samples(part.material)) return true;
    return false;
}

// -v's line for a built mesh.
std::string mesh_details(const tom::TomMesh& t, const tom::BuildStats& stats, const tom::CleanStats& clean, uint32_t floor, bool texcoords_weighed) {
    auto count = [](uint64_t n, const char* what) { return n ? ", " + std::to_string(n) + what : std::string(); };
    const std::string parts = t.parts.empty() ? "" : " (" + std::to_string(t.parts.size()) + " parts)";
    const std::string usable = floor ? ", usable floor " + std::to_string(floor) + " vertices / " +
                                           std::to_string(tom::active_triangle_count(t.view(), floor)) + " triangles"
                                     : "";
    char line[512];
    std::snprintf(line, sizeof line,
                  "  mesh '%s'%s: %u vertices, %u triangles, coarsest %u vertices / %u triangles; %u substitutions, %u locked, "
                  "%u border vertices, %u seam vertices, %u passes%s%s%s%s%s%s\n",
                  t.name.c_str(), parts.c_str(), t.vertex_count(), t.triangle_count(), t.min_vertex_count,
                  tom::active_triangle_count(t.view(), t.min_vertex_count), stats.substitutions, stats.locked_vertices, stats.border_vertices,
                  stats.seam_vertices, stats.passes, usable.c_str(), count(stats.pruned_pieces, " small pieces pruned").c_str(),
                  count(clean.welded_vertices, " identical vertices welded").c_str(), count(clean.degenerate_triangles, " degenerate triangles dropped").c_str(),
                  count(clean.unreferenced_vertices, " unused vertices dropped").c_str(),
                  texcoords_weighed ? "" : "; texture coordinates carried, not weighed: no texture samples them");
    return line;
}

// Mesh `mi` built into a TOM, then measured against the input: its error curve and usable floor
// stored, its report made when asked; its counts and -v's line added up.
void build_mesh(Conversion& c, size_t mi, Outcome& out) {
    tom::BuildStats stats;
    const auto build_start = std::chrono::steady_clock::now();
    c.stage_name = "build" + (c.imported.meshes.size() > 1 ? " mesh" + c.of_meshes(mi) : std::string());
    c.stage.show(c.stage_name, 0);
    tom::BuildParams params = c.params;
    params.weigh_texcoords = samples_texcoord0(c.imported.meshes[mi], c.imported.scene);
    const bool unweighed_texcoords = !params.weigh_texcoords && !c.imported.meshes[mi].texcoords.empty();
    c.built.push_back(tom::build(std::move(c.imported.meshes[mi]), params, &stats));  // frees the input as it goes: a lower peak
    const double build_seconds = seconds_since(build_start);
    c.build_seconds += build_seconds;

    const auto measure_start = std::chrono::steady_clock::now();
    c.stage_name = (c.reported() ? "report" : "error curve") + c.of_meshes(mi);
    if (!c.opt.no_error_curve || c.reported()) c.stage.show(c.stage_name, 0);
    tom::TomMesh& t = c.built.back();
    const tom::Mesh mesh = c.reported() || !c.opt.no_error_curve ? tom::original_mesh(t) : tom::Mesh();  // the input again, exactly
    uint32_t floor = 0;  // the usable floor stored (0: none)
    if (c.reported()) {
        tom::ReportContext ctx;
        ctx.file = c.job.input;
        ctx.import_seconds = c.import_seconds;
        ctx.build_seconds = build_seconds;
        ctx.welded_vertices = c.cleans[mi].welded_vertices;
        ctx.params = c.rparams;
        const auto report_start = std::chrono::steady_clock::now();
        const tom::MeshReport r = tom::make_report(mesh, t, c.rparams);
        ctx.report_seconds = seconds_since(report_start);
        if (!c.opt.no_error_curve) floor = store_curve(t, r.curve, c.rparams.floor_error);
        if (c.opt.report) c.tables += tom::report_table(r, ctx);
        c.json_meshes.push_back(tom::report_json(r, ctx));
        out.summary_csv += tom::summary_csv_row(c.json_meshes.back(), c.job.input);
    } else if (!c.opt.no_error_curve) {
        floor = store_curve(t, tom::measure_error_curve(mesh, t, c.rparams), c.rparams.floor_error);
    }
    c.measure_seconds += seconds_since(measure_start);

    c.vertices += t.vertex_count();
    c.triangles += t.triangle_count();
    c.fv_bytes += tools::face_vertex_bytes(t.vertex_count(), t.triangle_count());
    if (c.opt.verbose > 0) c.details += mesh_details(t, stats, c.cleans[mi], floor, !unweighed_texcoords);
}

// The meshes and the file's scene serialized and written atomically.
void write_tom(Conversion& c, Outcome& out) {
    std::error_code ec;
    fs::create_directories(fs::path(c.job.output).parent_path(), ec);
    c.stage.show("write");
    const auto write_start = std::chrono::steady_clock::now();
    tom::WriteOptions wopt = c.settings.write;
    wopt.provenance = c.tom_provenance = c.provenance.text();
    std::vector<uint8_t> bytes = tom::serialize(c.built, c.imported.scene, wopt);
    if (c.settings.stream) bytes = tom::encode_stream(bytes.data(), bytes.size(), c.settings.stream_options, c.job.output);
    tom::write_bytes_atomically(c.job.output, bytes.data(), bytes.size());
    c.bytes = bytes.size();
    out.triangles = c.triangles;
    c.write_seconds = seconds_since(write_start);
}

// The JSON report (docs/REPORT.md) of every mesh, with what made it.
void write_report(const Conversion& c) {
    nlohmann::ordered_json doc;
    doc["file"] = c.job.input;
    doc["output"] = c.job.output;
    doc["format"] = c.imported.format;
    doc.update(tools::build_params_json(c.params));
    doc["conventions"] = tom::conventions_json(c.rparams);
    doc["skipped"] = c.imported.skipped;
    doc["dropped"] = c.imported.dropped;
    doc["meshes"] = c.json_meshes;
    // what made the report: its .tom's provenance and the report's own options (a rerun keeps
    // the report when both are unchanged)
    doc["provenance"] = {{"tom", nlohmann::ordered_json::parse(c.tom_provenance)}, {"report", c.settings.report_options}};
    std::error_code ec;
    fs::create_directories(fs::path(c.report_path).parent_path(), ec);
    const std::string text = doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
    tom::write_bytes_atomically(c.report_path, text.data(), text.size());
}

// What the run prints for the input: its line, -v's details and times, the tables, what was skipped.
std::string conversion_text(const Conversion& c) {
    char line[1024];
    std::snprintf(line, sizeof line, "%s: %zu mesh%s, %llu vertices, %llu triangles -> %s (%s, %.1f%% of face-vertex) in %.2f s\n", c.job.input.c_str(),
                  c.built.size(), c.built.size() == 1 ? "" : "es", static_cast<unsigned long long>(c.vertices), static_cast<unsigned long long>(c.triangles),
                  c.job.output.c_str(), tools::human_bytes(c.bytes).c_str(), c.fv_bytes ? 100.0 * double(c.bytes) / double(c.fv_bytes) : 0.0,
                  seconds_since(c.start));
    std::string text = line + c.details;
    if (c.opt.verbose > 0) {
        std::snprintf(line, sizeof line, "  seconds: import %.3f, build %.3f, error curve and report %.3f, write %.3f\n", c.import_seconds, c.build_seconds,
                      c.measure_seconds, c.write_seconds);
        text += line;
    }
    text += c.tables;
    for (const std::string& s : c.imported.skipped) text += "  skipped " + s + "\n";
    if (c.opt.verbose > 0)
        for (const std::string& w : c.imported.warnings) text += "  warning: " + w + "\n";
    return text;
}

Outcome convert(const tools::Job& job, const Options& opt, const Settings& settings, const std::string& report_path) {
    Outcome out;
    try {
        Conversion c(job, opt, settings, report_path);
        import_input(c, out);
        for (size_t mi = 0; mi < c.imported.meshes.size(); ++mi) build_mesh(c, mi, out);
        write_tom(c, out);
        if (!report_path.empty()) write_report(c);
        out.text = conversion_text(c);
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
            const tom::File f = tom::open_any(path);
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

// Parses the command line into `opt`; an exit code when done (help, version, usage error), else -1.
int parse_options(Options& opt, int argc, char** argv) {
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
    CLI::Option* stream = app.add_flag("--stream", opt.stream,
                                       "Write the streamed layout: quantized, compressed chunks in resolution order, every prefix a coarser mesh (docs/FORMAT.md, "
                                       "\"Streamed files\"); every tool reads it")
                              ->group("Output");
    tom::StreamOptions& so = opt.stream_options;
    app.add_option("--position-bits", so.position_bits, "With --stream: bits of the grid positions are rounded to over the mesh's box (default 14, gltfpack's)")
        ->check(CLI::Range(1u, 16u))
        ->needs(stream)
        ->group("Output");
    app.add_option("--normal-bits", so.normal_bits, "With --stream: bits per octahedral component of normals and tangents (default 8)")
        ->check(CLI::Range(2u, 16u))
        ->needs(stream)
        ->group("Output");
    app.add_option("--texcoord-bits", so.texcoord_bits, "With --stream: bits per texture coordinate over its range (default 12)")
        ->check(CLI::Range(1u, 16u))
        ->needs(stream)
        ->group("Output");
    app.add_option("--first-chunk", so.first_share,
                   "With --stream: the share of a mesh's vertices and triangles its first chunk holds at least (default 0.01; at least its coarsest level)")
        ->check(CLI::Range(1e-6, 1.0))
        ->needs(stream)
        ->group("Output");
    app.add_option("--chunk-growth", so.growth,
                   "With --stream: each next chunk ends at this many times the last one's resolution (default 1.25; smaller: more, smaller chunks, a smoother "
                   "error against bytes, a little more overhead)")
        ->check(CLI::Range(1.01, 16.0))
        ->needs(stream)
        ->group("Output");
    app.add_flag("--keep-order", so.keep_order,
                 "With --stream: keep the builder's vertex order inside each chunk (by default a chunk's splits are ordered by their substitutes, "
                 "which code smaller: the same levels at chunk boundaries, a different order between them)")
        ->needs(stream)
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
    return tools::parse(app, argc, argv);
}

// The conversion's settings from the options; `per_job`: each job's build and report threads.
Settings make_settings(const Options& opt, unsigned per_job) {
    Settings settings;
    settings.params = opt.build.params();
    settings.clean = opt.build.clean();
    settings.write.index_size = opt.index_size == "32" ? tom::IndexSize::bits32 : opt.index_size == "16" ? tom::IndexSize::bits16 : tom::IndexSize::automatic;
    settings.stream = opt.stream;
    settings.stream_options = opt.stream_options;
    settings.output_options = output_options(opt, settings.params);
    settings.report_options = report_options(opt);
    settings.report = report_params(opt, per_job);
    if (settings.params.threads == 0) settings.params.threads = per_job;
    return settings;
}

// A run over the inputs: the jobs of the whole batch, this shard's share, and what each gave.
struct Batch {
    tools::Shard shard;
    std::vector<std::string> errors;       // inputs that could not be planned
    std::vector<tools::Job> all_jobs;      // the whole batch, every shard's
    std::vector<size_t> selected;          // this run's share: indices into all_jobs
    std::vector<std::string> summary_rows; // per selected job, its rows of summary.csv
    std::vector<tools::ManifestRecord> records;
    size_t done = 0, failed = 0, fresh = 0;
    bool show_progress = false;

    std::string report_path_of(const Options& opt, const tools::Job& job) const {
        if (opt.report_json_dir.empty()) return "";
        fs::path rel = fs::path(job.output).lexically_relative(opt.outdir);
        rel.replace_extension(".json");
        return (fs::path(opt.report_json_dir) / rel).string();
    }
};

// The inputs expanded into jobs, the output folder made, this shard's share chosen (balanced by
// size). false (after printing why) when the output folder cannot be made.
bool plan_batch(const Options& opt, Batch& b) {
    b.all_jobs = tools::plan_jobs(opt.inputs, opt.outdir, ".tom", b.errors);
    for (const std::string& e : b.errors) std::fprintf(stderr, "error: %s\n", e.c_str());
    std::error_code ec;
    fs::create_directories(opt.outdir, ec);
    if (ec) {
        std::fprintf(stderr, "error: cannot create output folder '%s': %s\n", opt.outdir.c_str(), ec.message().c_str());
        return false;
    }
    std::vector<uint64_t> sizes;
    for (const tools::Job& j : b.all_jobs) {
        const uintmax_t size = fs::file_size(j.input, ec);
        sizes.push_back(ec ? 0 : uint64_t(size));
    }
    const std::vector<uint32_t> of = tools::assign_shards(b.all_jobs, sizes, b.shard.count);
    for (size_t i = 0; i < b.all_jobs.size(); ++i)
        if (of[i] == b.shard.index) b.selected.push_back(i);
    b.summary_rows.resize(b.selected.size());
    b.records.resize(b.selected.size());
    b.failed = b.errors.size();
    return true;
}

// One job: up to date (its output's provenance, and its report's) or converted.
Outcome process(const tools::Job& job, const Options& opt, const Settings& settings, const std::string& report_path, bool& up_to_date) {
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
    up_to_date = f.up_to_date;
    if (f.up_to_date) {
        r.ok = true;
        r.digest = f.digest;
        r.triangles = f.triangles;
        r.dropped = f.dropped;
        r.text = job.input + ": up to date (" + job.output + ")\n";
        return r;
    }
    r = opt.isolate ? convert_isolated(job, opt, settings, report_path) : convert(job, opt, settings, report_path);
    if (r.digest.empty()) {
        try {
            r.digest = tools::file_digest(job.input);
        } catch (const std::exception&) {
        }
    }
    return r;
}

// The manifest's record of a job's outcome.
tools::ManifestRecord record_of(size_t index, const tools::Job& job, const std::string& report_path, const Outcome& r, bool up_to_date, double seconds) {
    tools::ManifestRecord rec;
    rec.index = index;
    rec.input = job.input;
    rec.output = job.output;
    rec.report = report_path;
    rec.digest = r.digest == "missing" ? "" : r.digest;
    rec.status = !r.ok ? "failed" : up_to_date ? "up to date" : "converted";
    rec.triangles = r.ok ? r.triangles : 0;
    rec.dropped = r.ok ? r.dropped : std::vector<std::string>();
    rec.seconds = seconds;
    if (!r.ok) {
        std::string message = r.text;
        if (message.rfind("error: ", 0) == 0) message.erase(0, 7);
        while (!message.empty() && message.back() == '\n') message.pop_back();
        rec.message = message;
    }
    return rec;
}

// This shard's jobs on -j threads, each outcome recorded and printed as it comes (a progress
// bar on a terminal); stops early on SIGTERM or SIGINT.
void run_batch(const Options& opt, const Settings& settings, Batch& b) {
    std::atomic<size_t> next{0};
    std::mutex print_mutex;
    auto worker = [&] {
        for (size_t s; (s = next++) < b.selected.size() && stop_signal == 0;) {
            const tools::Job& job = b.all_jobs[b.selected[s]];
            const std::string report_path = b.report_path_of(opt, job);
            const auto start = std::chrono::steady_clock::now();
            bool up_to_date = false;
            const Outcome r = process(job, opt, settings, report_path, up_to_date);
            b.records[s] = record_of(b.selected[s], job, report_path, r, up_to_date, seconds_since(start));
            std::lock_guard<std::mutex> lock(print_mutex);
            b.summary_rows[s] = r.summary_csv;
            ++b.done;
            if (!r.ok) ++b.failed;
            if (up_to_date) ++b.fresh;
            if (b.show_progress) std::fprintf(stderr, "\r%*s\r", 60, "");
            if (!r.ok)
                std::fputs(r.text.c_str(), stderr);
            else if (!opt.quiet && (!up_to_date || opt.verbose > 0))
                std::fputs(r.text.c_str(), stdout);
            if (r.ok && !up_to_date && !r.dropped.empty()) std::fputs(dropped_warning(job.input, r.dropped).c_str(), stderr);
            std::fflush(stdout);
            if (b.show_progress) draw_progress(b.done, b.selected.size(), b.failed);
        }
    };
    std::signal(SIGTERM, on_stop_signal);
    std::signal(SIGINT, on_stop_signal);
    std::vector<std::thread> pool;
    const unsigned threads = std::min<unsigned>(opt.jobs, unsigned(std::max<size_t>(1, b.selected.size())));
    for (unsigned k = 1; k < threads; ++k) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    if (b.show_progress) std::fprintf(stderr, "\n");
}

// Outputs whose input is gone: named by every run over the whole batch, removed with --prune
// (by shard 0 only, so that shards do not race).
void handle_orphans(const Options& opt, const Batch& b) {
    if (b.shard.index != 0) return;
    std::error_code ec;
    for (const std::string& orphan : find_orphans(opt.outdir, b.all_jobs)) {
        if (opt.prune) {
            fs::remove(orphan, ec);
            if (const std::string report = b.report_path_of(opt, {"", orphan}); !report.empty()) fs::remove(report, ec);
            if (!opt.quiet) std::printf("%s: removed (no input maps to it)\n", orphan.c_str());
        } else if (!opt.quiet) {
            std::printf("%s: no input of this run maps to it (its input is gone?); --prune removes it\n", orphan.c_str());
        }
    }
}

// The shard's manifest and, unsharded, the reports' summary.csv (shards: tombuild --merge
// writes it); returns the manifest's path.
std::string write_manifest(const Options& opt, const Settings& settings, const Batch& b) {
    tools::ManifestHeader header;
    header.shard = b.shard;
    header.inputs = b.all_jobs.size();
    header.report_json = opt.report_json_dir;
    header.summary_header = tom::summary_csv_header(settings.report);
    const std::string manifest = tools::manifest_path(opt.outdir, b.shard);
    tools::write_manifest(manifest, header, b.records);
    if (!opt.report_json_dir.empty() && b.shard.count == 1) {
        std::string csv = header.summary_header;
        for (const std::string& rows : b.summary_rows) csv += rows;  // input order, whatever -j
        std::error_code ec;
        fs::create_directories(opt.report_json_dir, ec);
        const std::string path = (fs::path(opt.report_json_dir) / "summary.csv").string();
        tom::write_bytes_atomically(path, csv.data(), csv.size());
        if (!opt.quiet) std::printf("reports: %s (one JSON per input), %s\n", opt.report_json_dir.c_str(), path.c_str());
    }
    return manifest;
}

// The closing line and the exit code.
int finish(const Options& opt, const Batch& b, const std::string& manifest) {
    const size_t total = b.selected.size() + b.errors.size();
    if (!opt.quiet || b.failed)
        std::fprintf(b.failed ? stderr : stdout, "%zu of %zu inputs converted%s%s%s; manifest %s\n", total - b.failed - b.fresh, total,
                     b.fresh ? (", " + std::to_string(b.fresh) + " up to date").c_str() : "",
                     b.failed ? (", " + std::to_string(b.failed) + " failed").c_str() : "",
                     b.shard.count > 1 ? (" (shard " + b.shard.name() + " of " + std::to_string(b.all_jobs.size()) + " inputs)").c_str() : "",
                     manifest.c_str());
    if (b.all_jobs.empty() && b.errors.empty()) {
        std::fprintf(stderr, "error: no mesh files found in the inputs\n");
        return tools::exit_failed;
    }
    return b.failed ? tools::exit_failed : tools::exit_ok;
}

int usage_error(const std::string& message) {
    std::fprintf(stderr, "error: %s\n", message.c_str());
    return tools::exit_usage;
}

} // namespace

int main(int argc, char** argv) {
    Options opt;
    if (const int code = parse_options(opt, argc, argv); code >= 0) return code;
    try {
        if (!opt.merge_dir.empty()) {
            if (!opt.inputs.empty() || !opt.outdir.empty()) return usage_error("--merge OUTDIR takes no inputs and no -o");
            return tools::merge_shards(opt.merge_dir, opt.quiet);
        }
        if (opt.inputs.empty() || opt.outdir.empty())
            return usage_error(std::string(opt.inputs.empty() ? "inputs is required" : "--output is required") + "\nRun with --help for more information.");
        Batch batch;
        try {
            batch.shard = tools::parse_shard(opt.shard);
        } catch (const std::invalid_argument& e) {
            return usage_error(e.what());
        }
        // the cores shared among the -j jobs: each job's build and report threads
        const unsigned per_job = std::max(1u, std::max(1u, std::thread::hardware_concurrency()) / std::max(1u, opt.jobs));
        const Settings settings = make_settings(opt, per_job);
        if (opt.max_memory_mb == 0) {
            const double total_mb = double(::sysconf(_SC_PHYS_PAGES)) * double(::sysconf(_SC_PAGE_SIZE)) / (1024.0 * 1024.0);
            opt.max_memory_mb = std::max(1024.0, 0.75 * total_mb / double(std::max(1u, opt.jobs)));
        }
        if (!plan_batch(opt, batch)) return tools::exit_failed;
        batch.show_progress = (opt.progress || tools::is_terminal(2)) && !opt.quiet && batch.selected.size() > 1;
        opt.mesh_progress = (opt.progress || tools::is_terminal(2)) && !opt.quiet && opt.jobs == 1;

        run_batch(opt, settings, batch);
        if (stop_signal != 0) {
            std::fprintf(stderr, "error: stopped by signal %d (%s) after %zu of %zu inputs; no manifest written, a rerun converts the rest\n", int(stop_signal),
                         strsignal(stop_signal), batch.done, batch.selected.size());
            return 128 + stop_signal;
        }
        handle_orphans(opt, batch);
        return finish(opt, batch, write_manifest(opt, settings, batch));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}
