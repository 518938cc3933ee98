// tombench: build and extraction throughput, measured against references in the same run:
// meshopt_simplify to 1% for the build, memcpy of the same output bytes for extraction.
// Wall times on a shared machine are noisy: every figure is the median of interleaved repeats,
// and the ratios (not the absolute times) are what to compare.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <thread>

#include <meshoptimizer.h>
#include <nlohmann/json.hpp>

#include "tom/builder/builder.h"
#include "tom/extract.h"
#include "tom/builder/writer.h"
#include "tom/format.h"
#include "tom/builder/generate.h"
#include "tom/io/import.h"
#include "tool_common.h"

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct ExtractRow {
    double fraction;
    uint32_t vertices, triangles;
    double extract_s, memcpy_s;
};

struct Row {
    std::string mesh;
    uint32_t vertices, triangles;
    double build_s, meshopt_s;
    uint32_t meshopt_triangles;
    uint32_t index_bytes = 4;
    std::vector<ExtractRow> extract;
};

Row bench(const tom::Mesh& mesh, const tom::BuildParams& params, int repeats) {
    Row row;
    row.mesh = mesh.name;
    row.vertices = mesh.vertex_count();
    row.triangles = mesh.triangle_count();
    std::vector<double> build_times, meshopt_times;
    tom::TomMesh tm;
    std::vector<uint32_t> simplified(mesh.indices.size());
    const size_t target = std::max<size_t>(3, mesh.indices.size() / 100 / 3 * 3);
    for (int r = 0; r < repeats; ++r) {  // interleaved so both see the same machine state
        auto t0 = Clock::now();
        tm = tom::build(mesh, params);
        build_times.push_back(seconds_since(t0));
        t0 = Clock::now();
        const size_t count = meshopt_simplify(simplified.data(), mesh.indices.data(), mesh.indices.size(), mesh.positions.data(),
                                              mesh.vertex_count(), 12, target, 1.0f, 0, nullptr);
        meshopt_times.push_back(seconds_since(t0));
        row.meshopt_triangles = uint32_t(count / 3);
    }
    row.build_s = tools::median(build_times);
    row.meshopt_s = tools::median(meshopt_times);

    // measure the form an engine maps: the serialized file (16-bit indices stored where they fit),
    // extracted into 32-bit index buffers, the same output for every mesh
    const std::vector<uint8_t> bytes_image = tom::serialize({tm});
    const tom::File file = tom::File::from_bytes(bytes_image.data(), bytes_image.size(), row.mesh);
    const tom::MeshView& view = file.mesh(0);
    row.index_bytes = view.index_size;
    std::vector<uint32_t> out(size_t(tm.triangle_count()) * 3), src(out.size()), dst(out.size());
    for (size_t i = 0; i < src.size(); ++i) src[i] = uint32_t(i * 2654435761u);
    for (double fraction : {1.0, 0.5, 0.1, 0.01}) {
        ExtractRow e;
        e.fraction = fraction;
        e.vertices = tom::vertex_count_for_fraction(view, fraction);
        e.triangles = tom::active_triangle_count(view, e.vertices);
        const size_t bytes = size_t(e.triangles) * 12;
        // enough inner iterations for ~2 ms per sample
        int inner = 1;
        for (;;) {
            const auto t0 = Clock::now();
            for (int k = 0; k < inner; ++k) tom::extract(view, e.vertices, out.data(), out.size());
            if (seconds_since(t0) > 2e-3 || inner > (1 << 20)) break;
            inner *= 2;
        }
        std::vector<double> ext, cpy;
        for (int r = 0; r < std::max(repeats, 5) * 3; ++r) {
            auto t0 = Clock::now();
            for (int k = 0; k < inner; ++k) {
                tom::extract(view, e.vertices, out.data(), out.size());
                asm volatile("" : : "r"(out.data()) : "memory");
            }
            ext.push_back(seconds_since(t0) / inner);
            t0 = Clock::now();
            for (int k = 0; k < inner; ++k) {
                std::memcpy(dst.data(), src.data(), bytes);
                asm volatile("" : : "r"(dst.data()) : "memory");
            }
            cpy.push_back(seconds_since(t0) / inner);
        }
        e.extract_s = tools::median(ext);
        e.memcpy_s = tools::median(cpy);
        row.extract.push_back(e);
    }
    return row;
}

} // namespace

int run(const std::vector<std::string>& inputs, uint32_t generated, bool json, int repeats, const tom::BuildParams& params,
        const tom::CleanOptions& clean, const std::string& meshopt_out, const std::vector<double>& meshopt_levels);

// The generated bumpy sphere of about `triangles` triangles (2 s (s - 1) for s rings and segments).
tom::Mesh generated_sphere(uint32_t triangles) {
    uint32_t s = 3;
    while (2.0 * s * (s - 1) < triangles) ++s;
    tom::Mesh m = tom::make_sphere(s, s, 1.0f, 0.05f);
    m.name = "generated-sphere-" + std::to_string(m.triangle_count());
    tom::clean_mesh(m);
    return m;
}

// Writes a mesh's positions and triangles as binary little-endian PLY (tombuild's large input).
void write_binary_ply(const std::string& path, const tom::Mesh& m) {
    std::string head = "ply\nformat binary_little_endian 1.0\ncomment tombench --write-generated\nelement vertex " + std::to_string(m.vertex_count()) +
                       "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(m.triangle_count()) +
                       "\nproperty list uchar int vertex_indices\nend_header\n";
    std::vector<uint8_t> bytes(head.begin(), head.end());
    const size_t at = bytes.size();
    bytes.resize(at + m.positions.size() * 4 + size_t(m.triangle_count()) * 13);
    std::memcpy(&bytes[at], m.positions.data(), m.positions.size() * 4);
    uint8_t* f = &bytes[at + m.positions.size() * 4];
    for (size_t t = 0; t < m.triangle_count(); ++t, f += 13) {
        f[0] = 3;
        std::memcpy(f + 1, &m.indices[3 * t], 12);
    }
    tom::write_bytes_atomically(path, bytes.data(), bytes.size());
}

int main(int argc, char** argv) {
    std::vector<std::string> inputs;
    uint32_t generated = 0;
    bool json = false;
    int repeats = 5;
    tools::BuildOptions build;
    CLI::App app{"tombench: TOM build and extraction throughput against meshopt_simplify and memcpy, measured in the same run"};
    app.set_version_flag("--version", "tombench 0.1.0");
    app.add_option("meshes", inputs, "Mesh files to measure");
    app.add_option("--generated", generated, "Also measure a generated bumpy sphere of about this many triangles (e.g. 2000000)");
    app.add_option("-r,--repeats", repeats, "Repeats per figure; medians are reported (default 5)")->check(CLI::Range(1, 1000));
    build.add_to(app, "Builder");
    app.add_flag("--json", json, "One JSON object per mesh (one per line) instead of the table");
    std::string meshopt_out;
    std::vector<double> meshopt_levels = {10, 5, 2, 1};
    app.add_option("--meshopt-out", meshopt_out, "Also write meshopt_simplify's result at --meshopt-levels as MESH-meshopt-P.obj here, for tomerr");
    app.add_option("--meshopt-levels", meshopt_levels, "Levels in % of the triangles for --meshopt-out (default 10,5,2,1)")->delimiter(',');
    std::string write_generated;
    app.add_option("--write-generated", write_generated, "Write the --generated sphere as binary PLY to this file and exit (a large input for tombuild)");
    app.footer("Exit codes: 0 ok, 1 a mesh could not be read, 2 usage error.\nExample: tombench data/meshes/bunny00.off --generated 2000000");
    if (const int code = tools::parse(app, argc, argv); code >= 0) return code;
    if (!write_generated.empty()) {
        if (generated == 0) {
            std::fprintf(stderr, "error: --write-generated needs --generated N\n");
            return tools::exit_usage;
        }
        try {
            write_binary_ply(write_generated, generated_sphere(generated));
            return tools::exit_ok;
        } catch (const std::exception& e) {
            std::fprintf(stderr, "error: %s\n", e.what());
            return tools::exit_failed;
        }
    }
    if (inputs.empty() && generated == 0) {
        std::fprintf(stderr, "error: give mesh files or --generated N\n");
        return tools::exit_usage;
    }
    try {
        tom::BuildParams params = build.params();
        if (params.threads == 0) params.threads = std::max(1u, std::thread::hardware_concurrency());
        return run(inputs, generated, json, repeats, params, build.clean(), meshopt_out, meshopt_levels);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}

int run(const std::vector<std::string>& inputs, uint32_t generated, bool json, int repeats, const tom::BuildParams& params,
        const tom::CleanOptions& clean, const std::string& meshopt_out, const std::vector<double>& meshopt_levels) {
    std::vector<tom::Mesh> meshes;
    int status = tools::exit_ok;
    for (const std::string& in : inputs) {
        try {
            tom::ImportResult r = tom::import_file(in);
            for (tom::Mesh& m : r.meshes) {
                tom::clean_mesh(m, clean);
                if (!m.indices.empty()) meshes.push_back(std::move(m));
            }
        } catch (const std::exception& e) {
            std::fprintf(stderr, "error: %s\n", e.what());
            status = tools::exit_failed;
        }
    }
    if (generated) meshes.push_back(generated_sphere(generated));
    if (!json) {
        std::printf("build: %s/%s, attribute weight %g, %u thread%s; meshopt = meshopt_simplify to 1%% of the triangles (reference, 1 thread); "
                    "medians of %d\n",
                    tom::to_string(params.predicate), tom::to_string(params.strategy), double(params.attribute_weight), params.threads,
                    params.threads == 1 ? "" : "s", repeats);
        std::printf("%-28s %10s %10s %10s %12s %8s | %s\n", "mesh", "triangles", "build ms", "meshopt ms", "build tri/s", "x meshopt",
                    "extract: fraction triangles Mtri/s memcpy-ratio");
    }
    if (!meshopt_out.empty()) {
        std::filesystem::create_directories(meshopt_out);
        for (const tom::Mesh& m : meshes)
            for (double pct : meshopt_levels) {
                std::vector<uint32_t> out(m.indices.size());
                const size_t target = std::max<size_t>(3, size_t(double(m.indices.size() / 3) * pct / 100.0 + 0.5) * 3);
                float result_error = 0;
                out.resize(meshopt_simplify(out.data(), m.indices.data(), m.indices.size(), m.positions.data(), m.vertex_count(), 12, target, 1.0f, 0,
                                            &result_error));
                std::string safe = m.name;
                for (char& c : safe)
                    if (c == '/' || c == ' ') c = '_';
                char name[64];
                std::snprintf(name, sizeof name, "-meshopt-%g.obj", pct);
                const std::string path = (std::filesystem::path(meshopt_out) / (safe + name)).string();
                std::FILE* f = std::fopen(path.c_str(), "w");
                if (!f) {
                    std::fprintf(stderr, "error: cannot write %s\n", path.c_str());
                    return tools::exit_failed;
                }
                std::fprintf(f, "# meshopt_simplify of %s to %g%% of %u triangles: %zu triangles\n", m.name.c_str(), pct, m.triangle_count(), out.size() / 3);
                for (uint32_t v = 0; v < m.vertex_count(); ++v)
                    std::fprintf(f, "v %.9g %.9g %.9g\n", m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
                for (size_t t = 0; t < out.size(); t += 3) std::fprintf(f, "f %u %u %u\n", out[t] + 1, out[t + 1] + 1, out[t + 2] + 1);
                std::fclose(f);
                if (!json) std::printf("wrote %s (%zu triangles)\n", path.c_str(), out.size() / 3);
            }
    }
    for (const tom::Mesh& m : meshes) {
        const Row row = bench(m, params, repeats);
        if (json) {
            nlohmann::ordered_json j;
            j["mesh"] = row.mesh;
            j["vertices"] = row.vertices;
            j["triangles"] = row.triangles;
            j.update(tools::build_params_json(params));
            j["build_threads"] = params.threads;
            j["build_ms"] = row.build_s * 1e3;
            j["meshopt_ms"] = row.meshopt_s * 1e3;
            j["meshopt_triangles"] = row.meshopt_triangles;
            j["build_tris_per_s"] = row.triangles / row.build_s;
            j["build_over_meshopt"] = row.build_s / row.meshopt_s;
            j["stored_index_bytes"] = row.index_bytes;
            j["output_index_bytes"] = 4;
            j["extract"] = nlohmann::json::array();
            for (const ExtractRow& e : row.extract)
                j["extract"].push_back({{"fraction", e.fraction},
                                        {"vertices", e.vertices},
                                        {"triangles", e.triangles},
                                        {"tris_per_s", e.triangles / e.extract_s},
                                        {"memcpy_ratio", e.memcpy_s / e.extract_s}});
            std::printf("%s\n", j.dump().c_str());
        } else {
            std::printf("%-28.28s %10u %10.2f %10.2f %12.3g %8.2f |", row.mesh.c_str(), row.triangles, row.build_s * 1e3, row.meshopt_s * 1e3,
                        row.triangles / row.build_s, row.build_s / row.meshopt_s);
            for (const ExtractRow& e : row.extract)
                std::printf("  %g%%: %u %.0f %.2f", e.fraction * 100, e.triangles, e.triangles / e.extract_s / 1e6, e.memcpy_s / e.extract_s);
            std::printf("\n");
        }
        std::fflush(stdout);
    }
    return status;
}
