#pragma once
// Batch conversion at scale (tombuild): digests of what made an output, the up-to-date check of
// incremental runs, the run's manifest, shards of a batch, and the merge of the shards' manifests.
// docs/TOOLS.md ("Incremental conversion", "Shards") describes what users see.

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tool_common.h"

namespace tools {

/// "xxh3-128:" and the 32 hex digits of the XXH3-128 digest of the file's bytes, or "missing"
/// when the file does not exist. `bytes` receives its size (0 when missing).
/// \throw tom::IoError when the file exists but cannot be read.
std::string file_digest(const std::string& path, uint64_t* bytes = nullptr);

/// What made an output: the input's size and digest, the digests of the other files the import
/// read (named relative to the input's folder), the tool and the options that change the bytes.
/// Stored as the .tom's PROV section (docs/FORMAT.md), compared on the next run.
struct Provenance {
    std::string tool;
    uint64_t input_bytes = 0;
    std::string input_digest;
    std::vector<std::pair<std::string, std::string>> sources;  // (name, digest)
    nlohmann::ordered_json options;
    std::vector<std::string> dropped;  ///< what the import did not carry into the file (ImportResult::dropped)

    std::string text() const;  ///< the PROV section's JSON, compact, keys in a fixed order
    /// \throw nlohmann::json::exception when `text` is not what text() writes
    static Provenance parse(const std::string& text);
};

/// The digests of `input` and of `sources` (names relative to the input's folder).
Provenance describe(const std::string& input, const std::vector<std::string>& sources, const std::string& tool, const nlohmann::ordered_json& options);

/// Whether `output` is an up-to-date conversion of `input`: it is a valid .tom whose provenance
/// names the same tool and options, and whose input and sources still have the recorded digests.
struct Freshness {
    bool up_to_date = false;
    std::string reason;        ///< why not ("no output", "the input changed", ...)
    std::string digest;        ///< the input's digest now
    uint64_t triangles = 0;    ///< the output's triangles, summed over its meshes (when up to date)
    std::string provenance;    ///< the output's PROV text (when up to date)
    std::vector<std::string> dropped;  ///< what its conversion did not carry (when up to date)
};
Freshness check_output(const std::string& input, const std::string& output, const std::string& tool, const nlohmann::ordered_json& options);

/// One line of manifest.jsonl: what became of one input.
struct ManifestRecord {
    size_t index = 0;        ///< the input's place in the run's sorted input list (the manifest's order)
    std::string input, output;
    std::string digest;      ///< of the input, "" when it could not be read
    std::string status;      ///< "converted", "up to date" or "failed"
    std::string message;     ///< failed: the error
    std::string report;      ///< the JSON report's path, when reports were asked for
    std::vector<std::string> dropped;  ///< what the input holds that the output does not (ImportResult::dropped)
    uint64_t triangles = 0;
    double seconds = 0;

    nlohmann::ordered_json json() const;
    static ManifestRecord from_json(const nlohmann::json& j);
};

/// Which share of a batch a run converts: shard `index` of `count` (0-based; count 1: all).
struct Shard {
    uint32_t index = 0, count = 1;
    std::string name() const;  ///< "2/4"
};
/// Reads "K/N" (0 <= K < N), "auto" (K and N from Slurm's SLURM_ARRAY_TASK_ID -
/// SLURM_ARRAY_TASK_MIN and SLURM_ARRAY_TASK_COUNT) or "auto/N" (K from a Kubernetes indexed
/// job's JOB_COMPLETION_INDEX, or from Slurm's variables, which must then agree with N).
/// \throw std::invalid_argument with a message saying what is wrong or missing
Shard parse_shard(const std::string& text);

/// The shard of each job: the jobs, largest input first (ties by output path), each go to the
/// shard with the fewest bytes so far (the lowest index among equals). Depends only on the jobs'
/// outputs and input sizes, so every machine computes the same split.
std::vector<uint32_t> assign_shards(const std::vector<Job>& jobs, const std::vector<uint64_t>& sizes, uint32_t count);

/// The manifest file of a run: OUTDIR/manifest.jsonl, or OUTDIR/manifest.shard-K-of-N.jsonl for
/// one shard of several.
std::string manifest_path(const std::string& outdir, const Shard& shard);

/// What a shard's manifest part says about the whole run, in its first line.
struct ManifestHeader {
    Shard shard;
    size_t inputs = 0;            ///< inputs of the whole run, over all shards
    std::string report_json;      ///< the reports' folder, "" without reports
    std::string summary_header;   ///< summary.csv's first line (with reports)
};

/// Writes the manifest atomically: for a shard of several, the header line first; then the
/// records in index order.
void write_manifest(const std::string& path, const ManifestHeader& header, const std::vector<ManifestRecord>& records);

/// tombuild --merge: joins OUTDIR's shard manifests into OUTDIR/manifest.jsonl (and the
/// reports' summary.csv) and names each shard that is missing or had failures on stderr.
/// Returns the exit code: exit_ok when every shard is there and nothing failed.
int merge_shards(const std::string& outdir, bool quiet);

} // namespace tools
