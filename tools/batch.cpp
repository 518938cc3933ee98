#include "batch.h"

#include "tom/stream/stream_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <stdexcept>

#include <xxhash.h>

#include "tom/metrics/report_json.h"
#include "tom/builder/writer.h"
#include "tom/errors.h"
#include "tom/format.h"

namespace fs = std::filesystem;

namespace tools {

namespace {

// Compact JSON; bytes that are not UTF-8 (a Latin-1 file name, a reader's quote of the input)
// become U+FFFD instead of failing the run.
std::string compact(const nlohmann::ordered_json& j) { return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace); }

} // namespace

std::string file_digest(const std::string& path, uint64_t* bytes) {
    if (bytes) *bytes = 0;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return "missing";
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw tom::IoError("cannot open '" + path + "': " + std::strerror(errno));
    XXH3_state_t* state = XXH3_createState();
    XXH3_128bits_reset(state);
    std::vector<char> buffer(1 << 20);
    uint64_t total = 0;
    for (size_t n; (n = std::fread(buffer.data(), 1, buffer.size(), f)) > 0;) {
        XXH3_128bits_update(state, buffer.data(), n);
        total += n;
    }
    const bool failed = std::ferror(f) != 0;
    std::fclose(f);
    const XXH128_hash_t h = XXH3_128bits_digest(state);
    XXH3_freeState(state);
    if (failed) throw tom::IoError("cannot read '" + path + "'");
    if (bytes) *bytes = total;
    char hex[64];
    std::snprintf(hex, sizeof hex, "xxh3-128:%016llx%016llx", static_cast<unsigned long long>(h.high64), static_cast<unsigned long long>(h.low64));
    return hex;
}

// --- provenance ------------------------------------------------------------------------------

std::string Provenance::text() const {
    nlohmann::ordered_json j;
    j["tool"] = tool;
    j["input"] = {{"bytes", input_bytes}, {"digest", input_digest}};
    j["sources"] = nlohmann::json::array();
    for (const auto& [name, digest] : sources) j["sources"].push_back({{"file", name}, {"digest", digest}});
    j["options"] = options;
    if (!dropped.empty()) j["dropped"] = dropped;
    return compact(j);
}

Provenance Provenance::parse(const std::string& text) {
    const nlohmann::ordered_json j = nlohmann::ordered_json::parse(text);
    Provenance p;
    p.tool = j.at("tool").get<std::string>();
    p.input_bytes = j.at("input").at("bytes").get<uint64_t>();
    p.input_digest = j.at("input").at("digest").get<std::string>();
    for (const auto& s : j.at("sources")) p.sources.emplace_back(s.at("file").get<std::string>(), s.at("digest").get<std::string>());
    p.options = j.at("options");
    if (j.contains("dropped")) p.dropped = j.at("dropped").get<std::vector<std::string>>();
    return p;
}

namespace {

std::string source_path(const std::string& input, const std::string& name) { return (fs::path(input).parent_path() / name).string(); }

} // namespace

Provenance describe(const std::string& input, const std::vector<std::string>& sources, const std::string& tool, const nlohmann::ordered_json& options) {
    Provenance p;
    p.tool = tool;
    p.input_digest = file_digest(input, &p.input_bytes);
    for (const std::string& name : sources) p.sources.emplace_back(name, file_digest(source_path(input, name)));
    p.options = options;
    return p;
}

Freshness check_output(const std::string& input, const std::string& output, const std::string& tool, const nlohmann::ordered_json& options) {
    Freshness f;
    uint64_t bytes = 0;
    f.digest = file_digest(input, &bytes);
    std::error_code ec;
    if (!fs::is_regular_file(output, ec)) {
        f.reason = "no output yet";
        return f;
    }
    try {
        const tom::File file = tom::open_any(output);
        if (file.provenance().empty()) {
            f.reason = "the output does not say what made it";
            return f;
        }
        const std::string text(file.provenance());
        const Provenance p = Provenance::parse(text);
        if (p.tool != tool) {
            f.reason = "made by " + p.tool;
        } else if (p.options != options) {
            f.reason = "made with other options";
        } else if (p.input_digest != f.digest || p.input_bytes != bytes) {
            f.reason = "the input changed";
        } else {
            for (const auto& [name, digest] : p.sources)
                if (file_digest(source_path(input, name)) != digest) {
                    f.reason = name + " changed";
                    return f;
                }
            f.up_to_date = true;
            f.provenance = text;
            f.dropped = p.dropped;
            for (uint32_t m = 0; m < file.mesh_count(); ++m) f.triangles += file.mesh(m).triangle_count;
        }
    } catch (const tom::Error& e) {
        f.reason = std::string("the output is not readable (") + e.what() + ")";
    } catch (const nlohmann::json::exception&) {
        f.reason = "the output's provenance is not tombuild's";
    }
    return f;
}

// --- manifest --------------------------------------------------------------------------------

nlohmann::ordered_json ManifestRecord::json() const {
    nlohmann::ordered_json j;
    j["index"] = index;
    j["input"] = input;
    j["digest"] = digest.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(digest);
    j["output"] = output;
    j["status"] = status;
    if (!message.empty()) j["message"] = message;
    j["dropped"] = dropped;
    if (!report.empty()) j["report"] = report;
    j["triangles"] = triangles;
    j["seconds"] = seconds;
    return j;
}

ManifestRecord ManifestRecord::from_json(const nlohmann::json& j) {
    ManifestRecord r;
    r.index = j.at("index").get<size_t>();
    r.input = j.at("input").get<std::string>();
    r.digest = j.at("digest").is_null() ? "" : j.at("digest").get<std::string>();
    r.output = j.at("output").get<std::string>();
    r.status = j.at("status").get<std::string>();
    r.message = j.value("message", "");
    r.report = j.value("report", "");
    if (j.contains("dropped")) r.dropped = j.at("dropped").get<std::vector<std::string>>();
    r.triangles = j.at("triangles").get<uint64_t>();
    r.seconds = j.at("seconds").get<double>();
    return r;
}

std::string Shard::name() const { return std::to_string(index) + "/" + std::to_string(count); }

namespace {

// A non-negative integer in an environment variable, or -1 when unset.
long env_number(const char* name) {
    const char* v = std::getenv(name);
    if (!v || !*v) return -1;
    char* end = nullptr;
    errno = 0;
    const long n = std::strtol(v, &end, 10);
    if (*end != '\0' || n < 0 || errno != 0) throw std::invalid_argument(std::string(name) + "='" + v + "' is not a non-negative integer");
    return n;
}

uint32_t parse_count(const std::string& s, const std::string& what) {
    char* end = nullptr;
    const long n = std::strtol(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0' || n < 0 || n > 1000000) throw std::invalid_argument(what + " '" + s + "' is not a number in [0, 1000000]");
    return uint32_t(n);
}

} // namespace

Shard parse_shard(const std::string& text) {
    const size_t slash = text.find('/');
    const std::string first = text.substr(0, slash);
    const std::string second = slash == std::string::npos ? "" : text.substr(slash + 1);
    Shard s;
    if (first == "auto") {
        const long task = env_number("SLURM_ARRAY_TASK_ID"), count = env_number("SLURM_ARRAY_TASK_COUNT");
        const long min = std::max(0L, env_number("SLURM_ARRAY_TASK_MIN"));
        const long k8s = env_number("JOB_COMPLETION_INDEX");
        if (task >= 0) {
            if (count <= 0) throw std::invalid_argument("--shard auto: SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not");
            s.index = uint32_t(task - min);
            s.count = uint32_t(count);
            if (task < min) throw std::invalid_argument("--shard auto: SLURM_ARRAY_TASK_ID is below SLURM_ARRAY_TASK_MIN");
            if (!second.empty() && parse_count(second, "--shard auto/N: N") != s.count)
                throw std::invalid_argument("--shard " + text + ": the Slurm array has " + std::to_string(count) + " tasks");
        } else if (k8s >= 0) {
            if (second.empty()) throw std::invalid_argument("--shard auto: JOB_COMPLETION_INDEX is set; give the job's completions as --shard auto/N");
            s.index = uint32_t(k8s);
            s.count = parse_count(second, "--shard auto/N: N");
        } else {
            throw std::invalid_argument("--shard auto: neither Slurm's SLURM_ARRAY_TASK_ID nor Kubernetes' JOB_COMPLETION_INDEX is set");
        }
        if (s.index >= s.count)
            throw std::invalid_argument("--shard auto: task " + std::to_string(s.index) + " of " + std::to_string(s.count) +
                                        " (an array with a step, such as 0-7:2, is not a sequence of shards; use 0-(N-1))");
        return s;
    }
    if (second.empty()) throw std::invalid_argument("--shard '" + text + "': expected K/N (0 <= K < N), auto or auto/N");
    s.index = parse_count(first, "--shard K/N: K");
    s.count = parse_count(second, "--shard K/N: N");
    if (s.count == 0 || s.index >= s.count) throw std::invalid_argument("--shard " + text + ": K must be in [0, N) and N at least 1");
    return s;
}

std::vector<uint32_t> assign_shards(const std::vector<Job>& jobs, const std::vector<uint64_t>& sizes, uint32_t count) {
    std::vector<size_t> order(jobs.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        if (sizes[a] != sizes[b]) return sizes[a] > sizes[b];
        return jobs[a].output < jobs[b].output;
    });
    std::vector<uint64_t> load(count, 0);
    std::vector<uint32_t> shard(jobs.size(), 0);
    for (size_t j : order) {
        const uint32_t k = uint32_t(std::min_element(load.begin(), load.end()) - load.begin());
        shard[j] = k;
        load[k] += sizes[j] + 1;  // + 1: empty files still spread out
    }
    return shard;
}

std::string manifest_path(const std::string& outdir, const Shard& shard) {
    const std::string name = shard.count == 1 ? "manifest.jsonl"
                                              : "manifest.shard-" + std::to_string(shard.index) + "-of-" + std::to_string(shard.count) + ".jsonl";
    return (fs::path(outdir) / name).string();
}

void write_manifest(const std::string& path, const ManifestHeader& header, const std::vector<ManifestRecord>& records) {
    std::string text;
    if (header.shard.count > 1) {
        nlohmann::ordered_json h;
        h["shard"] = header.shard.index;
        h["shards"] = header.shard.count;
        h["inputs"] = header.inputs;
        h["report_json"] = header.report_json.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(header.report_json);
        h["summary_header"] = header.summary_header;
        text += compact(nlohmann::ordered_json{{"manifest_part", h}}) + "\n";
    }
    std::vector<const ManifestRecord*> sorted;
    for (const ManifestRecord& r : records) sorted.push_back(&r);
    std::stable_sort(sorted.begin(), sorted.end(), [](const ManifestRecord* a, const ManifestRecord* b) { return a->index < b->index; });
    for (const ManifestRecord* r : sorted) text += compact(r->json()) + "\n";
    tom::write_bytes_atomically(path, text.data(), text.size());
}

// --- merge -----------------------------------------------------------------------------------

namespace {

struct ManifestPart {
    std::string path;
    ManifestHeader header;
    std::vector<ManifestRecord> records;
};

// Reads one shard's manifest. \throw std::runtime_error naming the file and line
ManifestPart read_part(const std::string& path) {
    ManifestPart part;
    part.path = path;
    std::ifstream in(path);
    if (!in) throw std::runtime_error(path + ": cannot read");
    std::string line;
    for (size_t number = 1; std::getline(in, line); ++number) {
        try {
            const nlohmann::json j = nlohmann::json::parse(line);
            if (number == 1) {
                const nlohmann::json& h = j.at("manifest_part");
                part.header.shard.index = h.at("shard").get<uint32_t>();
                part.header.shard.count = h.at("shards").get<uint32_t>();
                part.header.inputs = h.at("inputs").get<size_t>();
                part.header.report_json = h.at("report_json").is_null() ? "" : h.at("report_json").get<std::string>();
                part.header.summary_header = h.at("summary_header").get<std::string>();
                continue;
            }
            part.records.push_back(ManifestRecord::from_json(j));
        } catch (const nlohmann::json::exception& e) {
            throw std::runtime_error(path + ": line " + std::to_string(number) + ": not a manifest record (" + e.what() + ")");
        }
    }
    return part;
}

// OUTDIR's manifest.shard-K-of-N.jsonl files, by name.
std::vector<std::string> part_files(const std::string& outdir) {
    std::vector<std::string> files;
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(outdir, ec)) {
        const std::string name = e.path().filename().string();
        if (name.rfind("manifest.shard-", 0) == 0 && name.size() > 6 && name.compare(name.size() - 6, 6, ".jsonl") == 0) files.push_back(e.path().string());
    }
    std::sort(files.begin(), files.end());
    return files;
}

// summary.csv from the reports of the merged records, in the manifest's order.
std::string merged_summary(const std::string& header, const std::vector<ManifestRecord>& records, std::vector<std::string>& problems) {
    std::string csv = header;
    for (const ManifestRecord& r : records) {
        if (r.status == "failed" || r.report.empty()) continue;
        try {
            std::ifstream in(r.report);
            if (!in) throw std::runtime_error("cannot read it");
            const nlohmann::ordered_json doc = nlohmann::ordered_json::parse(in);
            for (const auto& mesh : doc.at("meshes")) csv += tom::summary_csv_row(mesh, r.input);
        } catch (const std::exception& e) {
            problems.push_back(r.report + ": report of " + r.input + " unusable: " + e.what());
        }
    }
    return csv;
}

} // namespace

int merge_shards(const std::string& outdir, bool quiet) {
    const std::vector<std::string> files = part_files(outdir);
    if (files.empty()) {
        std::fprintf(stderr, "error: %s: no shard manifests (manifest.shard-K-of-N.jsonl) to merge\n", outdir.c_str());
        return exit_failed;
    }
    std::vector<ManifestPart> parts;
    std::vector<std::string> problems;
    for (const std::string& f : files) {
        try {
            parts.push_back(read_part(f));
        } catch (const std::exception& e) {
            problems.push_back(e.what());
        }
    }
    if (parts.empty()) {
        for (const std::string& p : problems) std::fprintf(stderr, "error: %s\n", p.c_str());
        return exit_failed;
    }
    // the run is the newest part's; parts of another shard count are stale
    const ManifestPart* newest = &parts.front();
    fs::file_time_type newest_time = fs::file_time_type::min();
    for (const ManifestPart& p : parts) {
        std::error_code ec;
        const fs::file_time_type t = fs::last_write_time(p.path, ec);
        if (!ec && t > newest_time) newest_time = t, newest = &p;
    }
    const ManifestHeader run = newest->header;
    std::vector<const ManifestPart*> by_shard(run.shard.count, nullptr);
    for (const ManifestPart& p : parts) {
        if (p.header.shard.count != run.shard.count || p.header.inputs != run.inputs) {
            problems.push_back(p.path + ": from another run (shard " + p.header.shard.name() + " of " + std::to_string(p.header.inputs) +
                               " inputs; the newest part is of " + std::to_string(run.shard.count) + " shards over " + std::to_string(run.inputs) + ")");
            continue;
        }
        by_shard[p.header.shard.index] = &p;
    }
    std::vector<ManifestRecord> records;
    size_t failed = 0, converted = 0, fresh = 0, missing = 0;
    for (uint32_t k = 0; k < run.shard.count; ++k) {
        const Shard shard{k, run.shard.count};
        if (!by_shard[k]) {
            problems.push_back("shard " + shard.name() + " is missing: no " + manifest_path(outdir, shard) + " (the task did not finish; rerun it)");
            ++missing;
            continue;
        }
        size_t shard_failed = 0;
        std::string first_failure;
        for (const ManifestRecord& r : by_shard[k]->records) {
            records.push_back(r);
            if (r.status == "failed") {
                if (!shard_failed++) first_failure = r.input + ": " + r.message;
            } else if (r.status == "converted") {
                ++converted;
            } else {
                ++fresh;
            }
        }
        failed += shard_failed;
        if (shard_failed)
            problems.push_back("shard " + shard.name() + ": " + std::to_string(shard_failed) + " of " + std::to_string(by_shard[k]->records.size()) +
                               " inputs failed, first " + first_failure);
    }
    std::sort(records.begin(), records.end(), [](const ManifestRecord& a, const ManifestRecord& b) { return a.index < b.index; });
    write_manifest(manifest_path(outdir, Shard{}), ManifestHeader{}, records);
    if (!run.report_json.empty()) {
        const std::string csv = merged_summary(run.summary_header, records, problems);
        const std::string path = (fs::path(run.report_json) / "summary.csv").string();
        tom::write_bytes_atomically(path, csv.data(), csv.size());
        if (!quiet) std::printf("reports: %s\n", path.c_str());
    }
    for (const std::string& p : problems) std::fprintf(stderr, "error: %s\n", p.c_str());
    if (!quiet || !problems.empty())
        std::fprintf(problems.empty() ? stdout : stderr, "merged %u of %u shards into %s: %zu of %zu inputs, %zu converted, %zu up to date, %zu failed\n",
                     run.shard.count - uint32_t(missing), run.shard.count, manifest_path(outdir, Shard{}).c_str(), records.size(), run.inputs, converted,
                     fresh, failed);
    return problems.empty() ? exit_ok : exit_failed;
}

} // namespace tools
