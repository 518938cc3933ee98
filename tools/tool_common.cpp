#include "tool_common.h"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <filesystem>
#include <map>

#include <unistd.h>

#include "tom/io/import.h"

namespace fs = std::filesystem;

namespace tools {

void BuildOptions::add_to(CLI::App& app, const std::string& group) {
    app.add_option("--predicate", predicate, "Fairness predicate: quadric (default) or memoryless (the TOM paper's penalty)")
        ->check(CLI::IsMember({"quadric", "memoryless"}))
        ->group(group);
    app.add_option("--strategy", strategy, "Greedy order: passes (default, independent substitutions per pass) or heap")
        ->check(CLI::IsMember({"passes", "heap"}))
        ->group(group);
    app.add_option("-t,--pair-threshold", numbers.pair_threshold,
                   "Also substitute non-edge vertex pairs closer than this, in object units (default 0: edges only)")
        ->check(CLI::NonNegativeNumber)
        ->group(group);
    app.add_option("--pass-fraction", numbers.pass_fraction, "passes: share of live vertices one pass may remove, (0,1] (default 0.1)")
        ->check(CLI::Range(0.0001f, 1.0f))
        ->group(group);
    app.add_option("--attribute-weight", numbers.attribute_weight,
                   "Weight of the attribute term (normals, TEXCOORD_0, COLOR_0) in the predicates; 0 = geometry only, as meshopt_simplify "
                   "(default " + std::to_string(tom::BuildParams{}.attribute_weight).substr(0, 4) + ")")
        ->check(CLI::NonNegativeNumber)
        ->group(group);
    app.add_option("--animation-weight", numbers.animation_weight,
                   "Weight of the skinning and morph-target terms: a skinned mesh's joint centroid and each target's position "
                   "deltas count like attributes, so levels stay close in every pose and target; 0 = rest pose only (default " +
                       std::to_string(tom::BuildParams{}.animation_weight).substr(0, 4) + ")")
        ->check(CLI::NonNegativeNumber)
        ->group(group);
    app.add_option("--max-rotation", numbers.max_rotation_degrees,
                   "Largest rotation, in degrees, a substitution may give a surviving triangle's normal (90: flips only; default 60)")
        ->check(CLI::Range(1.0f, 90.0f))
        ->group(group);
    app.add_option("--copy-tolerance", numbers.copy_tolerance,
                   "Vertices closer than this share of the bounding box's diagonal are copies of one point (seams, hard edges, pole "
                   "fans); copies of a point move together, so the mesh never cracks (default 1e-6; 0: exact copies only)")
        ->check(CLI::Range(0.0f, 0.01f))
        ->group(group);
    app.add_flag("--lock-borders", numbers.lock_borders,
                 "Never move vertices on open borders (of the mesh welded by position), so tiles and modular pieces keep meeting their "
                 "neighbours at every resolution (meshoptimizer's LockBorder, gltfpack -slb)")
        ->group(group);
    app.add_flag("--keep-topology", numbers.keep_topology,
                 "Never join two sheets (a thin wall's faces, a handle closing): closed manifolds keep their genus and stop at a "
                 "tetrahedron; by default such a join is taken where it costs far less than what the topology leaves, as meshoptimizer does")
        ->group(group);
    app.add_flag("--no-weld", no_weld,
                 "Keep the file's vertices as they are; by default identical vertices (same position and the same value in every "
                 "stream, joints, weights and morph deltas included) are merged first, so unindexed files simplify")
        ->group(group);
    app.add_option("--build-threads", numbers.threads,
                   "Threads that evaluate each mesh's substitutions (default 0: one per core, shared among -j jobs); "
                   "the output is the same for any count")
        ->check(CLI::Range(0u, 256u))
        ->group(group);
}

tom::BuildParams BuildOptions::params() const {
    tom::BuildParams p = numbers;
    p.predicate = predicate == "memoryless" ? tom::Predicate::memoryless : tom::Predicate::quadric;
    p.strategy = strategy == "heap" ? tom::Strategy::heap : tom::Strategy::passes;
    return p;
}

nlohmann::ordered_json build_params_json(const tom::BuildParams& params) {
    return {{"predicate", tom::to_string(params.predicate)},
            {"strategy", tom::to_string(params.strategy)},
            {"pair_threshold", params.pair_threshold},
            {"pass_fraction", params.pass_fraction},
            {"attribute_weight", params.attribute_weight},
            {"animation_weight", params.animation_weight},
            {"max_rotation_degrees", params.max_rotation_degrees},
            {"lock_borders", params.lock_borders},
            {"keep_topology", params.keep_topology},
            {"copy_tolerance", params.copy_tolerance}};
}

int parse(CLI::App& app, int argc, char** argv) {
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return exit_usage;
    }
    return -1;
}

std::vector<Job> plan_jobs(const std::vector<std::string>& inputs, const std::string& outdir, const std::string& suffix,
                           std::vector<std::string>& errors) {
    struct Found {
        fs::path file, relative_dir;
    };
    std::vector<Found> found;
    for (const std::string& in : inputs) {
        std::error_code ec;
        const fs::path p(in);
        if (fs::is_directory(p, ec)) {
            std::vector<fs::path> files;
            for (auto it = fs::recursive_directory_iterator(p, fs::directory_options::skip_permission_denied, ec);
                 !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
                if (it->is_regular_file(ec) && tom::is_importable(it->path().string())) files.push_back(it->path());
            if (ec) errors.push_back(in + ": cannot list folder: " + ec.message());
            std::sort(files.begin(), files.end());
            for (const fs::path& f : files) found.push_back({f, f.parent_path().lexically_relative(p)});
        } else if (fs::exists(p, ec)) {
            found.push_back({p, fs::path()});
        } else {
            errors.push_back(in + ": no such file or folder");
        }
    }
    // drop repeated inputs, keep the first
    std::vector<Found> unique;
    std::map<std::string, bool> seen;
    for (const Found& f : found) {
        std::error_code ec;
        const std::string key = fs::weakly_canonical(f.file, ec).string();
        if (!seen[key]) {
            seen[key] = true;
            unique.push_back(f);
        }
    }
    auto out_name = [&](const Found& f, bool keep_ext) {
        std::string name = keep_ext ? f.file.filename().string() : f.file.stem().string();
        return (fs::path(outdir) / f.relative_dir / (name + suffix)).lexically_normal().string();
    };
    std::map<std::string, int> uses;
    for (const Found& f : unique) ++uses[out_name(f, false)];
    std::vector<Job> jobs;
    for (const Found& f : unique) jobs.push_back({f.file.string(), out_name(f, uses[out_name(f, false)] > 1)});
    return jobs;
}

double parse_fraction(const std::string& text, const std::string& option) {
    const bool percent = !text.empty() && text.back() == '%';
    const std::string number = percent ? text.substr(0, text.size() - 1) : text;
    char* end = nullptr;
    const double value = number.empty() ? -1.0 : std::strtod(number.c_str(), &end);
    const double fraction = percent ? value / 100.0 : value;
    if (number.empty() || *end != '\0' || !(fraction >= 0.0 && fraction <= 1.0))
        throw std::invalid_argument(option + " '" + text + "' is not a fraction in [0, 1] or a percentage (such as 0.5%)");
    return fraction;
}

std::string human_bytes(uint64_t bytes) {
    char buf[64];
    if (bytes < 10 * 1024)
        std::snprintf(buf, sizeof buf, "%llu B", static_cast<unsigned long long>(bytes));
    else if (bytes < 10ull * 1024 * 1024)
        std::snprintf(buf, sizeof buf, "%.1f KiB", double(bytes) / 1024.0);
    else
        std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / (1024.0 * 1024.0));
    return buf;
}

bool is_terminal(int fd) { return ::isatty(fd) != 0; }

} // namespace tools
