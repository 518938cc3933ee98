// tomparts: what simplifying a multi-part mesh as one surface buys over simplifying each part
// alone (the behaviour before parts): for every mesh of several parts in the inputs, at a few
// triangle fractions, the whole mesh's two-sided Metro mean error and its open edges (welded by
// position) for both, at the same total triangle count: each part alone at the level's fraction
// of its triangles, the joint mesh at the smallest resolution with at least their sum. Prints a
// table (open: the input's open edges; j, a: the levels'; crack: a level's open edges with an end
// off the input's open boundary, which a crack between parts makes), or JSON with --json.

#include <cstdio>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "tom/builder/builder.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/io/import.h"
#include "tom/metrics/distance.h"
#include "tool_common.h"

namespace {

// The triangles of part p as a mesh of its own, with only the vertices they use.
tom::Mesh part_alone(const tom::Mesh& m, const tom::Part& p) {
    tom::Mesh out;
    out.name = m.name;
    std::map<uint32_t, uint32_t> local;
    for (uint32_t t = p.first_triangle; t < p.first_triangle + p.triangle_count; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = m.indices[3 * size_t(t) + size_t(k)];
            const auto [it, fresh] = local.emplace(v, out.vertex_count());
            if (fresh) {
                out.positions.insert(out.positions.end(), &m.positions[3 * size_t(v)], &m.positions[3 * size_t(v)] + 3);
                out.normals.insert(out.normals.end(), &m.normals[3 * size_t(v)], &m.normals[3 * size_t(v)] + 3);
            }
            out.indices.push_back(it->second);
        }
    return out;
}

// A level as a surface: positions and indices appended from any number of extracted meshes.
struct Level {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    void add(const tom::MeshView& v, uint32_t n) {
        std::vector<uint32_t> buffer(size_t(v.triangle_count) * 3);
        const tom::Extracted e = tom::extract(v, n, buffer.data(), buffer.size());
        const uint32_t base = uint32_t(positions.size() / 3);
        positions.insert(positions.end(), v.positions, v.positions + 3 * size_t(e.vertex_count));
        for (size_t i = 0; i < 3 * size_t(e.triangle_count); ++i) indices.push_back(base + buffer[i]);
    }
    tom::Surface surface() const { return {positions.data(), uint32_t(positions.size() / 3), indices.data(), indices.size() / 3}; }
    using Point = std::array<float, 3>;
    // open edges welded by position, as position pairs
    std::set<std::pair<Point, Point>> open_edges() const {
        std::map<std::pair<Point, Point>, int> count;
        auto at = [&](uint32_t v) { return std::array<float, 3>{positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]}; };
        for (size_t t = 0; t < indices.size() / 3; ++t)
            for (int k = 0; k < 3; ++k) {
                std::array<float, 3> a = at(indices[3 * t + size_t(k)]), b = at(indices[3 * t + size_t((k + 1) % 3)]);
                if (b < a) std::swap(a, b);
                ++count[{a, b}];
            }
        std::set<std::pair<Point, Point>> open;
        for (const auto& [edge, c] : count)
            if (c == 1) open.insert(edge);
        return open;
    }
    // open edges with an end off `boundary` (the input's open boundary): cracks the level opened
    size_t cracks(const std::set<Point>& boundary) const {
        size_t n = 0;
        for (const auto& [a, b] : open_edges()) n += !boundary.count(a) || !boundary.count(b);
        return n;
    }
};

} // namespace

int main(int argc, char** argv) {
    std::vector<std::string> inputs;
    std::vector<double> percents = {10, 5, 2, 1};
    bool json = false;
    CLI::App app{"tomparts: a multi-part mesh simplified as one surface against each part alone (Metro mean error, open edges)"};
    app.set_version_flag("--version", "tomparts 0.1.0");
    app.add_option("inputs", inputs, "Mesh files (glTF with multi-primitive meshes, OBJ with usemtl groups)")->required();
    app.add_option("--levels", percents, "Levels in % of the triangles (default 10,5,2,1)")->delimiter(',')->check(CLI::Range(0.0, 100.0));
    app.add_flag("--json", json, "Print JSON instead of a table");
    app.footer("Exit codes: 0 ok, 1 unreadable input, 2 usage error.\nExample: tomparts data/assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
    if (const int code = tools::parse(app, argc, argv); code >= 0) return code;
    try {
        nlohmann::ordered_json rows = nlohmann::json::array();
        if (!json)
            std::printf("%-40s %5s %6s %11s %12s %12s %7s %6s %6s %6s %7s %7s\n", "mesh", "parts", "level", "tris j/a", "mean joint %", "mean alone %",
                        "a / j", "open", "open j", "open a", "crack j", "crack a");
        for (const std::string& path : inputs) {
            tom::ImportResult r = tom::import_file(path);
            for (tom::Mesh& mesh : r.meshes) {
                tom::clean_mesh(mesh);
                if (mesh.parts.empty()) continue;
                const tom::TomMesh joint = tom::build(mesh);
                std::vector<tom::TomMesh> alone;
                for (const tom::Part& p : mesh.parts) {
                    tom::Mesh piece = part_alone(mesh, p);
                    tom::clean_mesh(piece);
                    alone.push_back(tom::build(piece));
                }
                const tom::Surface original{mesh.positions.data(), mesh.vertex_count(), mesh.indices.data(), mesh.triangle_count()};
                Level full;
                full.add(joint.view(), joint.vertex_count());
                const auto input_edges = full.open_edges();
                const size_t input_open = input_edges.size();
                std::set<Level::Point> boundary;
                for (const auto& [a, b] : input_edges) boundary.insert(a), boundary.insert(b);
                for (const double pct : percents) {
                    // each part alone at the level's share of its triangles, as before parts; then the
                    // joint mesh at (at least) the same total, so both spend the same triangles
                    Level together, apart;
                    for (const tom::TomMesh& a : alone) apart.add(a.view(), tom::vertex_count_for_fraction(a.view(), pct / 100.0));
                    const tom::MeshView jv = joint.view();
                    together.add(jv, tom::vertex_count_for_triangles(jv, uint32_t(apart.indices.size() / 3)));
                    if (together.indices.empty() || apart.indices.empty()) continue;
                    const tom::Distance dj = tom::metro_distance(original, together.surface());
                    const tom::Distance da = tom::metro_distance(original, apart.surface());
                    const double mj = dj.percent(0.5 * (dj.forward.mean + dj.backward.mean)), ma = da.percent(0.5 * (da.forward.mean + da.backward.mean));
                    nlohmann::ordered_json row = {{"file", path},
                                                  {"mesh", mesh.name},
                                                  {"parts", mesh.parts.size()},
                                                  {"percent", pct},
                                                  {"triangles_joint", together.indices.size() / 3},
                                                  {"triangles_alone", apart.indices.size() / 3},
                                                  {"mean_percent_joint", mj},
                                                  {"mean_percent_alone", ma},
                                                  {"open_edges_input", input_open},
                                                  {"open_edges_joint", together.open_edges().size()},
                                                  {"open_edges_alone", apart.open_edges().size()},
                                                  {"crack_edges_joint", together.cracks(boundary)},
                                                  {"crack_edges_alone", apart.cracks(boundary)}};
                    if (!json)
                        std::printf("%-40.40s %5zu %5.0f%% %5zu/%-5zu %12.4f %12.4f %7.2f %6zu %6zu %6zu %7zu %7zu\n", mesh.name.c_str(), mesh.parts.size(), pct,
                                    together.indices.size() / 3, apart.indices.size() / 3, mj, ma, mj > 0 ? ma / mj : 0.0, input_open,
                                    row["open_edges_joint"].get<size_t>(), row["open_edges_alone"].get<size_t>(), row["crack_edges_joint"].get<size_t>(),
                                    row["crack_edges_alone"].get<size_t>());
                    rows.push_back(row);
                }
            }
        }
        if (json) std::printf("%s\n", rows.dump(2).c_str());
        return tools::exit_ok;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}
