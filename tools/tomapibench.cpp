// tomapibench: the cost of one extraction through the C++ API and through the C API, measured in
// the same run on the same mapped file, rounds alternating between the two so that drift falls
// on both. scripts/bench-bindings.py adds the Python call to the same table.
//
// For each fraction of the first mesh's triangles, each round times a batch of calls (as many as
// take about 2 ms) into a preallocated buffer and keeps the time per call; the figure is the
// median over the rounds.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/tom.h"

namespace {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

// Seconds per call of `call`, run `batch` times in a row.
template <class Call>
double per_call(Call&& call, int batch) {
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < batch; ++i) call();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / batch;
}

struct Row {
    double fraction = 0;
    uint32_t vertices = 0, triangles = 0;
    double cpp_ns = 0, c_ns = 0;
};

Row measure(const tom::MeshView& view, const tom_mesh_view& c_view, double fraction, int rounds) {
    Row row;
    row.fraction = fraction;
    row.vertices = tom::vertex_count_for_fraction(view, fraction);
    std::vector<uint32_t> out(size_t(view.triangle_count) * 3);
    volatile uint32_t sink = 0;
    auto cpp = [&] { sink = sink + tom::extract(view, row.vertices, out.data(), out.size()).triangle_count; };
    auto c = [&] {
        tom_extracted e;
        tom_extract_u32(&c_view, row.vertices, out.data(), out.size(), &e);
        sink = sink + e.triangle_count;
    };
    row.triangles = tom::active_triangle_count(view, row.vertices);
    // a batch of about 2 ms, from one warm call
    cpp();
    const double one = std::max(per_call(cpp, 1), 1e-9);
    const int batch = std::max(1, int(2e-3 / one));
    std::vector<double> cpp_times, c_times;
    for (int r = 0; r < rounds; ++r) {
        cpp_times.push_back(per_call(cpp, batch));
        c_times.push_back(per_call(c, batch));
    }
    row.cpp_ns = median(cpp_times) * 1e9;
    row.c_ns = median(c_times) * 1e9;
    return row;
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"tomapibench: one extraction through the C++ and the C API, same run, median per call"};
    std::string path;
    std::vector<double> fractions = {1.0, 0.1, 0.01};
    int rounds = 31;
    bool json = false;
    app.add_option("file", path, "A .tom file (its first mesh is measured)")->required();
    app.add_option("--fractions", fractions, "Fractions of the triangles (default 1 0.1 0.01)");
    app.add_option("-r,--rounds", rounds, "Rounds per fraction (default 31)")->check(CLI::PositiveNumber);
    app.add_flag("--json", json, "One JSON object per fraction (one per line) instead of the table");
    CLI11_PARSE(app, argc, argv);
    try {
        const tom::File file = tom::File::open(path);
        tom_file* c_file = nullptr;
        if (tom_file_open(path.c_str(), &c_file) != TOM_OK) throw tom::Error(tom_last_error());
        tom_mesh_view c_view;
        tom_file_mesh(c_file, 0, &c_view);
        const tom::MeshView& view = file.mesh(0);
        if (!json) std::printf("%-9s %9s %9s %12s %12s %8s\n", "fraction", "vertices", "triangles", "C++ ns", "C ns", "C/C++");
        for (double f : fractions) {
            const Row r = measure(view, c_view, f, rounds);
            if (json) {
                nlohmann::ordered_json j;
                j["mesh"] = std::string(view.name);
                j["fraction"] = r.fraction;
                j["vertices"] = r.vertices;
                j["triangles"] = r.triangles;
                j["cpp_ns"] = r.cpp_ns;
                j["c_ns"] = r.c_ns;
                j["c_over_cpp"] = r.c_ns / r.cpp_ns;
                std::printf("%s\n", j.dump().c_str());
            } else {
                std::printf("%-9g %9u %9u %12.0f %12.0f %8.3f\n", r.fraction, r.vertices, r.triangles, r.cpp_ns, r.c_ns, r.c_ns / r.cpp_ns);
            }
        }
        tom_file_close(c_file);
        return 0;
    } catch (const tom::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
