#pragma once
// Helpers shared by the command-line tools: CLI11 exit handling, input discovery, formatting.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "tom/builder/builder.h"

namespace tools {

/// Exit codes of every tool (also in each --help footer and the README).
enum Exit : int { exit_ok = 0, exit_failed = 1, exit_usage = 2 };

/// CLI11 parse with the project's exit codes: --help/--version print and give 0, any other
/// parse error prints CLI11's message and gives exit_usage. Returns -1 when parsing succeeded.
int parse(CLI::App& app, int argc, char** argv);

/// The builder's command-line options, shared by tombuild and tombench: --predicate, --strategy,
/// -t/--pair-threshold, --pass-fraction, --attribute-weight and --max-rotation (defaults those of
/// tom::BuildParams).
struct BuildOptions {
    std::string predicate = "quadric", strategy = "passes";
    tom::BuildParams numbers;  // the numeric settings, bound to their options directly
    bool no_weld = false;      // --no-weld: the file's vertices as they are (tom::CleanOptions)

    void add_to(CLI::App& app, const std::string& group);
    tom::BuildParams params() const;
    tom::CleanOptions clean() const { return {!no_weld}; }
};

/// The builder settings as JSON (reports and benchmark output): predicate, strategy,
/// pair_threshold, pass_fraction, attribute_weight, animation_weight, max_rotation_degrees.
nlohmann::ordered_json build_params_json(const tom::BuildParams& params);

/// One input file and the output path it maps to.
struct Job {
    std::string input;
    std::string output;
};

/// Expands files and folders (recursively, by importable extension, sorted) into jobs whose
/// outputs lie in `outdir`, with `suffix` as extension. Files under a folder keep their relative
/// sub-folders; two inputs that would share an output name keep their source extension
/// (a.obj -> a.obj.tom). Unreadable inputs are returned in `errors`.
std::vector<Job> plan_jobs(const std::vector<std::string>& inputs, const std::string& outdir, const std::string& suffix,
                           std::vector<std::string>& errors);

std::string human_bytes(uint64_t bytes);
bool is_terminal(int fd);

/// A fraction written as a number ("0.005") or a percentage ("0.5%"), in [0, 1].
/// \throw std::invalid_argument naming `option` and the text.
double parse_fraction(const std::string& text, const std::string& option);

/// The median of benchmark samples (the mean of the middle two for an even count; 0 for none).
inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

/// Bytes of a mesh in face-vertex form with positions and normals (floats) and 32-bit indices:
/// the reference of the paper's Table 4.
inline uint64_t face_vertex_bytes(uint64_t vertices, uint64_t triangles) { return vertices * 24 + triangles * 12; }

} // namespace tools
