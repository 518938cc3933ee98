// tomerr: Metro-style distance between two mesh files (OBJ, PLY, OFF, STL, glTF, GLB or .tom at a
// chosen level), so other tools' outputs can be measured with the same yardstick; with the
// attribute deviation (normals, texture coordinates) where both files have them.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include <nlohmann/json.hpp>

#include "tom/stream/stream_file.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/io/import.h"
#include "tom/scene.h"
#include "tom/metrics/distance.h"
#include "tool_common.h"

namespace {

// every triangle mesh of a file merged into one surface, in world space: each placed by every
// instance of the file's scene (node transforms applied), or as stored when the scene has none
struct Loaded {
    std::vector<float> positions, normals, texcoords;  // normals / texcoords: empty unless every mesh has them
    std::vector<uint32_t> indices;
    size_t meshes = 0;
    bool all_normals = true, all_texcoords = true;
    tom::Surface surface() const { return {positions.data(), uint32_t(positions.size() / 3), indices.data(), indices.size() / 3}; }
    tom::SurfaceAttributes attributes() const {
        return {all_normals && !normals.empty() ? normals.data() : nullptr, all_texcoords && !texcoords.empty() ? texcoords.data() : nullptr};
    }
};

bool ends_with(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// One mesh placed by a column-major object-to-world transform: positions by it, normals by its
// cofactor matrix (the inverse transpose up to scale, then normalised), and the winding reversed
// where it mirrors.
struct Placement {
    const float* m;
    void point(const float* p, float* out) const {
        for (int r = 0; r < 3; ++r) out[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
    }
    double det() const {
        return double(m[0]) * (double(m[5]) * m[10] - double(m[9]) * m[6]) - double(m[4]) * (double(m[1]) * m[10] - double(m[9]) * m[2]) +
               double(m[8]) * (double(m[1]) * m[6] - double(m[5]) * m[2]);
    }
    void normal(const float* n, float* out) const {
        auto a = [&](int r, int c) { return double(m[4 * c + r]); };  // the 3x3 part, row r, column c
        double cof[3][3];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c)
                cof[r][c] = a((r + 1) % 3, (c + 1) % 3) * a((r + 2) % 3, (c + 2) % 3) - a((r + 1) % 3, (c + 2) % 3) * a((r + 2) % 3, (c + 1) % 3);
        const double sign = det() < 0 ? -1.0 : 1.0;
        double v[3], len = 0;
        for (int r = 0; r < 3; ++r) v[r] = sign * (cof[r][0] * n[0] + cof[r][1] * n[1] + cof[r][2] * n[2]), len += v[r] * v[r];
        len = std::sqrt(len);
        for (int r = 0; r < 3; ++r) out[r] = len > 0 ? float(v[r] / len) : 0.0f;
    }
};

Loaded load(const std::string& path, std::optional<double> fraction) {
    Loaded out;
    auto append = [&](const float* pos, const float* nrm, const float* uv, uint32_t n, const uint32_t* idx, size_t tris, const float* transform) {
        const uint32_t base = uint32_t(out.positions.size() / 3);
        const Placement place{transform};
        for (uint32_t v = 0; v < n; ++v) {
            float p[3];
            if (transform) place.point(pos + 3 * size_t(v), p);
            else std::copy_n(pos + 3 * size_t(v), 3, p);
            out.positions.insert(out.positions.end(), p, p + 3);
            if (!nrm) continue;
            if (transform) place.normal(nrm + 3 * size_t(v), p);
            else std::copy_n(nrm + 3 * size_t(v), 3, p);
            out.normals.insert(out.normals.end(), p, p + 3);
        }
        out.all_normals &= nrm != nullptr;
        out.all_texcoords &= uv != nullptr;
        if (uv) out.texcoords.insert(out.texcoords.end(), uv, uv + size_t(n) * 2);
        const bool mirrored = transform && place.det() < 0;
        for (size_t t = 0; t < tris; ++t)
            for (const size_t k : {size_t(0), mirrored ? size_t(2) : size_t(1), mirrored ? size_t(1) : size_t(2)}) out.indices.push_back(idx[3 * t + k] + base);
        ++out.meshes;
    };
    // f(mesh, transform or null) for each placement of the file's meshes
    auto each_placement = [](const tom::Scene& scene, size_t mesh_count, auto&& f) {
        if (scene.instances.empty()) {
            for (size_t i = 0; i < mesh_count; ++i) f(i, nullptr);
            return;
        }
        for (const tom::Instance& in : scene.instances)
            if (in.mesh < mesh_count) f(in.mesh, in.transform);
    };
    if (ends_with(path, ".tom")) {
        const tom::File f = tom::open_any(path);
        each_placement(f.scene(), f.mesh_count(), [&](size_t i, const float* transform) {
            const tom::MeshView& m = f.mesh(uint32_t(i));
            const uint32_t n = fraction ? tom::vertex_count_for_fraction(m, *fraction) : m.vertex_count;
            std::vector<uint32_t> idx(size_t(m.triangle_count) * 3);
            const tom::Extracted e = tom::extract(m, n, idx.data(), idx.size());
            append(m.positions, m.normals, m.texcoords, e.vertex_count, idx.data(), e.triangle_count, transform);
        });
        if (out.indices.empty()) throw tom::MeshError(path + ": no triangles");
        return out;
    }
    tom::ImportResult r = tom::import_file(path);
    for (tom::Mesh& m : r.meshes) tom::clean_mesh(m);
    each_placement(r.scene, r.meshes.size(), [&](size_t i, const float* transform) {
        const tom::Mesh& m = r.meshes[i];
        append(m.positions.data(), m.normals.empty() ? nullptr : m.normals.data(), m.texcoords.empty() ? nullptr : m.texcoords.data(),
               m.vertex_count(), m.indices.data(), m.triangle_count(), transform);
    });
    if (out.indices.empty()) throw tom::MeshError(path + ": no triangles");
    return out;
}

} // namespace

int main(int argc, char** argv) {
    std::string a_path, b_path;
    std::optional<double> fraction;
    double samples_per_face = 10.0;
    uint64_t seed = 1;
    bool json = false, no_vertex = false, no_edge = false, no_face = false;
    CLI::App app{"tomerr: Metro-style distance between two meshes, in both directions"};
    app.set_version_flag("--version", "tomerr 0.1.0");
    app.add_option("original", a_path, "The reference mesh (any supported file, or .tom at full resolution)")->required();
    app.add_option("simplified", b_path, "The mesh to measure (any supported file, or .tom at --fraction)")->required();
    app.add_option("-f,--fraction", fraction, "Level of a .tom input, as a fraction of its triangles")->check(CLI::Range(0.0, 1.0));
    app.add_option("--samples-per-face", samples_per_face, "Samples per face of the larger mesh per direction (default 10, Metro's)")
        ->check(CLI::Range(0.01, 1000.0));
    app.add_option("--seed", seed, "Sampling seed (default 1)");
    app.add_flag("--no-vertex-samples", no_vertex, "Do not sample vertices");
    app.add_flag("--no-edge-samples", no_edge, "Do not sample edges");
    app.add_flag("--no-face-samples", no_face, "Do not sample faces");
    app.add_flag("--json", json, "Print one JSON object");
    app.footer("Conventions (Metro's): samples per direction are every vertex, then points along the edges, then area-uniform points on the\n"
               "faces, samples-per-face x faces of the larger mesh in all; percentages are of the diagonal of the union bounding box of\n"
               "both meshes, each side moved out by 2% of it. forward = original -> simplified.\n"
               "Exit codes: 0 ok, 1 an input cannot be read, 2 usage error.\n"
               "Example: tomerr data/meshes/bunny00.off out/bunny-meshopt-1.obj");
    if (const int code = tools::parse(app, argc, argv); code >= 0) return code;
    try {
        const Loaded a = load(a_path, std::nullopt), b = load(b_path, fraction);
        tom::DistanceParams p;
        p.samples_per_face = samples_per_face;
        p.seed = seed;
        p.vertex_samples = !no_vertex;
        p.edge_samples = !no_edge;
        p.face_samples = !no_face;
        const tom::MetroReference reference(a.surface(), p, a.attributes());
        tom::AttributeDeviation attributes;
        const tom::Distance d = reference.compare(b.surface(), b.attributes(), attributes);
        auto side = [&](const tom::OneSidedDistance& s) {
            return nlohmann::ordered_json{{"max", d.percent(s.max)},       {"mean", d.percent(s.mean)},       {"rms", d.percent(s.rms)},
                                          {"max_abs", s.max},              {"mean_abs", s.mean},              {"rms_abs", s.rms},
                                          {"samples", s.samples},          {"vertex_samples", s.vertex_samples}, {"edge_samples", s.edge_samples},
                                          {"face_samples", s.face_samples}, {"area", s.sampled_area}};
        };
        if (json) {
            nlohmann::ordered_json j;
            j["original"] = a_path;
            j["simplified"] = b_path;
            j["original_triangles"] = a.indices.size() / 3;
            j["simplified_triangles"] = b.indices.size() / 3;
            j["bbox_diagonal"] = d.diagonal;
            j["forward"] = side(d.forward);
            j["backward"] = side(d.backward);
            j["hausdorff"] = d.percent(d.hausdorff);
            j["hausdorff_abs"] = d.hausdorff;
            j["mean"] = d.percent(std::max(d.forward.mean, d.backward.mean));
            j["attributes"] = {{"samples", attributes.samples},
                               {"normal_mean_degrees", attributes.normals ? nlohmann::json(attributes.normal_mean_degrees) : nlohmann::json()},
                               {"normal_max_degrees", attributes.normals ? nlohmann::json(attributes.normal_max_degrees) : nlohmann::json()},
                               {"uv_mean", attributes.texcoords ? nlohmann::json(attributes.uv_mean) : nlohmann::json()},
                               {"uv_max", attributes.texcoords ? nlohmann::json(attributes.uv_max) : nlohmann::json()}};
            std::printf("%s\n", j.dump(2).c_str());
            return tools::exit_ok;
        }
        std::printf("original   %s: %zu triangles, area %.6g\nsimplified %s: %zu triangles, area %.6g\n", a_path.c_str(), a.indices.size() / 3,
                    d.forward.sampled_area, b_path.c_str(), b.indices.size() / 3, d.backward.sampled_area);
        std::printf("bbox diagonal (union, enlarged 2%%): %.6g; %.3g samples/face of the larger mesh per direction, seed %llu\n", d.diagonal,
                    samples_per_face, static_cast<unsigned long long>(seed));
        for (auto [name, s] : {std::pair{"forward  (original -> simplified)", &d.forward}, std::pair{"backward (simplified -> original)", &d.backward}})
            std::printf("%s: max %.6g (%.4f%%)  mean %.6g (%.5f%%)  rms %.6g (%.5f%%)  [%llu samples: %llu vertex, %llu edge, %llu face]\n", name,
                        s->max, d.percent(s->max), s->mean, d.percent(s->mean), s->rms, d.percent(s->rms), static_cast<unsigned long long>(s->samples),
                        static_cast<unsigned long long>(s->vertex_samples), static_cast<unsigned long long>(s->edge_samples),
                        static_cast<unsigned long long>(s->face_samples));
        std::printf("Hausdorff distance: %.6g (%.4f%% of the diagonal)\n", d.hausdorff, d.percent(d.hausdorff));
        if (attributes.normals)
            std::printf("normals: mean deviation %.3f degrees, max %.2f [%llu samples of the original's faces]\n", attributes.normal_mean_degrees,
                        attributes.normal_max_degrees, static_cast<unsigned long long>(attributes.samples));
        if (attributes.texcoords)
            std::printf("texture coordinates: mean displacement %.5f, max %.4f\n", attributes.uv_mean, attributes.uv_max);
        return tools::exit_ok;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}
