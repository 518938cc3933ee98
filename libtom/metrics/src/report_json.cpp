// A mesh's report as JSON, a table and CSV rows (report_json.h).

#include "tom/metrics/report_json.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace tom {

namespace {

std::string format(const char* fmt, double a) {
    char buf[64];
    std::snprintf(buf, sizeof buf, fmt, a);
    return buf;
}

nlohmann::ordered_json one_sided(const tom::OneSidedDistance& d, double diagonal) {
    auto pct = [&](double x) { return diagonal > 0 ? 100.0 * x / diagonal : 0.0; };
    return {{"max", pct(d.max)}, {"mean", pct(d.mean)}, {"rms", pct(d.rms)}, {"samples", d.samples},
            {"vertex_samples", d.vertex_samples}, {"edge_samples", d.edge_samples}, {"face_samples", d.face_samples}};
}

double pct(double x, double d) { return d > 0 ? 100.0 * x / d : 0.0; }

} // namespace

nlohmann::ordered_json conventions_json(const tom::ReportParams& p) {
    return {{"errors", "percent of bbox_diagonal"},
            {"bbox_diagonal", "diagonal of the union bounding box of the original and the level, each side moved out by 2% of it (Metro)"},
            {"samples_per_face", p.distance.samples_per_face},
            {"samples", "per direction: every vertex, then points along every edge, then area-uniform random points on the faces "
                        "(similar-triangles stratified), samples_per_face x faces of the larger mesh in all (Metro's order and budget)"},
            {"seed", p.distance.seed},
            {"forward", "original -> level: from samples on the original to the closest point of the level"},
            {"backward", "level -> original"},
            {"mean_error", "the larger of forward.mean and backward.mean"},
            {"max_error", "hausdorff = the larger of forward.max and backward.max"},
            {"fit", "D = k / N, D relative error (fraction of bbox_diagonal), N triangles; k from a least-squares fit in log space"}};
}

nlohmann::ordered_json attributes_json(const tom::AttributeDeviation& a) {
    nlohmann::ordered_json j;
    j["samples"] = a.samples;
    j["normal_mean_degrees"] = a.normals ? nlohmann::json(a.normal_mean_degrees) : nlohmann::json();
    j["normal_max_degrees"] = a.normals ? nlohmann::json(a.normal_max_degrees) : nlohmann::json();
    j["uv_mean"] = a.texcoords ? nlohmann::json(a.uv_mean) : nlohmann::json();
    j["uv_max"] = a.texcoords ? nlohmann::json(a.uv_max) : nlohmann::json();
    return j;
}

nlohmann::ordered_json report_json(const tom::MeshReport& r, const ReportContext& ctx) {
    nlohmann::ordered_json j;
    j["name"] = r.name;
    j["vertices"] = r.vertices;
    j["triangles"] = r.triangles;
    j["bbox_diagonal"] = r.bbox_diagonal;
    j["build_seconds"] = ctx.build_seconds;
    j["import_seconds"] = ctx.import_seconds;
    j["report_seconds"] = ctx.report_seconds;
    j["welded_vertices"] = ctx.welded_vertices;
    const double fv = double(r.memory.face_vertex_bytes);
    j["memory"] = {{"face_vertex_bytes", r.memory.face_vertex_bytes},
                   {"tom_bytes", r.memory.tom_bytes},
                   {"lod_bytes", r.memory.lod_bytes},
                   {"pm_bytes", r.memory.pm_bytes},
                   {"pm_max_bytes", r.memory.pm_max_bytes},
                   {"tom_percent", 100.0 * double(r.memory.tom_bytes) / fv},
                   {"lod_percent", 100.0 * double(r.memory.lod_bytes) / fv},
                   {"pm_percent", 100.0 * double(r.memory.pm_bytes) / fv},
                   {"pm_max_percent", 100.0 * double(r.memory.pm_max_bytes) / fv}};
    j["fit"] = {{"k_mean", r.fit.mean.k},
                {"k_max", r.fit.max.k},
                {"slope_mean", r.fit.mean.slope},
                {"slope_max", r.fit.max.slope},
                {"rms_log10_mean", r.fit.mean.rms_log10},
                {"rms_log10_max", r.fit.max.rms_log10},
                {"levels_used", r.fit.mean.used}};
    j["levels"] = nlohmann::json::array();
    for (const tom::LevelReport& l : r.levels) {
        const double d = l.error.diagonal;
        nlohmann::ordered_json hist = nlohmann::json::array();
        for (int k = 0; k < tom::ChainStats::histogram_bins; ++k) hist.push_back(l.chain.histogram[k]);
        j["levels"].push_back({{"fraction", l.fraction},
                               {"vertices", l.vertices},
                               {"triangles", l.triangles},
                               {"extract_seconds", l.extract_seconds},
                               {"error",
                                {{"forward", one_sided(l.error.forward, d)},
                                 {"backward", one_sided(l.error.backward, d)},
                                 {"hausdorff", pct(l.error.hausdorff, d)},
                                 {"mean", pct(std::max(l.error.forward.mean, l.error.backward.mean), d)},
                                 {"diagonal", d}}},
                               {"chain", {{"mean_steps", l.mean_steps}, {"max_steps", l.chain.max_steps}, {"overhead", l.overhead}, {"histogram", hist}}},
                               {"attributes", attributes_json(l.attributes)}});
        if (!l.parts.empty()) {  // a multi-part mesh: each part's attributes against the original part's
            nlohmann::ordered_json parts = nlohmann::json::array();
            for (const tom::PartLevelReport& p : l.parts)
                parts.push_back({{"material", p.material}, {"triangles", p.triangles}, {"attributes", attributes_json(p.attributes)}});
            j["levels"].back()["parts"] = parts;
        }
    }
    if (!ctx.params.error_curve) {
        j["error_curve"] = nullptr;  // --no-error-curve: not measured
        return j;
    }
    j["error_curve"] = {{"diagonal", r.curve.diagonal}, {"k_mean", r.curve.k_mean}, {"k_max", r.curve.k_max}, {"points", nlohmann::json::array()}};
    for (const tom::ErrorCurvePoint& p : r.curve.points)
        j["error_curve"]["points"].push_back({{"vertices", p.vertices}, {"triangles", p.triangles}, {"mean", 100.0 * p.mean}, {"max", 100.0 * p.max}});
    return j;
}

std::string report_table(const tom::MeshReport& r, const ReportContext& ctx) {
    std::ostringstream o;
    char line[512];
    std::snprintf(line, sizeof line, "%s / %s: %u vertices, %u triangles; built in %.3f s, measured in %.2f s\n", ctx.file.c_str(), r.name.c_str(),
                  r.vertices, r.triangles, ctx.build_seconds, ctx.report_seconds);
    o << line;
    std::snprintf(line, sizeof line,
                  "  Metro-style error in %% of the bbox diagonal (%.6g, union box enlarged 2%%); %.3g samples/face of the larger mesh per "
                  "direction (vertices, edges, faces), seed %llu\n",
                  r.bbox_diagonal, ctx.params.distance.samples_per_face, static_cast<unsigned long long>(ctx.params.distance.seed));
    o << line;
    o << "   level  vertices triangles |  fwd max fwd mean  fwd rms |  bwd max bwd mean  bwd rms | hausdorff |  chain mean max overhead | extract us"
         " | normal deg    uv\n";
    for (const tom::LevelReport& l : r.levels) {
        const double d = l.error.diagonal;
        const std::string normal = l.attributes.normals ? format("%10.2f", l.attributes.normal_mean_degrees) : std::string(10, ' ') + "-";
        const std::string uv = l.attributes.texcoords ? format("%6.4f", l.attributes.uv_mean) : "     -";
        std::snprintf(line, sizeof line, "  %5.1f%% %9u %9u | %8.4f %8.5f %8.5f | %8.4f %8.5f %8.5f | %9.4f | %10.2f %3u %8.3f | %10.1f | %s %s\n",
                      100 * l.fraction, l.vertices, l.triangles, pct(l.error.forward.max, d), pct(l.error.forward.mean, d), pct(l.error.forward.rms, d),
                      pct(l.error.backward.max, d), pct(l.error.backward.mean, d), pct(l.error.backward.rms, d), pct(l.error.hausdorff, d), l.mean_steps,
                      l.chain.max_steps, l.overhead, 1e6 * l.extract_seconds, normal.c_str(), uv.c_str());
        o << line;
    }
    // levels at the vertex count of an earlier one (a mesh that stops simplifying above them)
    // repeat its mesh: said once, under the first of them, in any order of --levels
    for (size_t i = 0; i < r.levels.size(); ++i) {
        const uint32_t n = r.levels[i].vertices;
        if (std::any_of(r.levels.begin(), r.levels.begin() + std::ptrdiff_t(i), [n](const tom::LevelReport& l) { return l.vertices == n; })) continue;
        std::string which;
        for (size_t k = i + 1; k < r.levels.size(); ++k)
            if (r.levels[k].vertices == n) which += format(which.empty() ? "%.1f%%" : ", %.1f%%", 100 * r.levels[k].fraction);
        if (which.empty()) continue;
        std::snprintf(line, sizeof line, "  %s: the %.1f%% level's mesh again (%u vertices, %u triangles)\n", which.c_str(), 100 * r.levels[i].fraction, n,
                      r.levels[i].triangles);
        o << line;
    }
    o << "  normal deg, uv: mean angle between interpolated normals and mean texture-coordinate displacement at the closest point,\n"
         "  over " << (r.levels.empty() ? 0 : r.levels[0].attributes.samples) << " area-uniform samples of the original's faces\n";
    const double fv = double(r.memory.face_vertex_bytes);
    std::snprintf(line, sizeof line,
                  "  memory (positions+normals, 32-bit): face-vertex %llu B (100%%), TOM %llu B (%.1f%%), 6 LODs %llu B (%.1f%%), progressive mesh "
                  "%.1f%%..%.1f%% (estimate)\n",
                  static_cast<unsigned long long>(r.memory.face_vertex_bytes), static_cast<unsigned long long>(r.memory.tom_bytes),
                  100 * r.memory.tom_bytes / fv, static_cast<unsigned long long>(r.memory.lod_bytes), 100 * r.memory.lod_bytes / fv,
                  100 * r.memory.pm_bytes / fv, 100 * r.memory.pm_max_bytes / fv);
    o << line;
    std::snprintf(line, sizeof line,
                  "  fit D = k/N (D relative, N triangles): k_mean %.4g (free slope %.2f, rms %.3f dex), k_max %.4g (free slope %.2f, rms %.3f dex)\n",
                  r.fit.mean.k, r.fit.mean.slope, r.fit.mean.rms_log10, r.fit.max.k, r.fit.max.slope, r.fit.max.rms_log10);
    o << line;
    return o.str();
}

std::string summary_csv_header(const tom::ReportParams& params) {
    std::string h = "file,mesh,vertices,triangles,build_seconds,report_seconds,tom_percent,k_mean,k_max";
    for (double f : params.levels) {
        const std::string p = format("%g", 100 * f);
        h += ",triangles_" + p + ",hausdorff_" + p + ",mean_" + p;
    }
    return h + "\n";
}

std::string summary_csv_row(const nlohmann::ordered_json& mesh, const std::string& file) {
    auto quote = [](const std::string& s) {
        std::string q = "\"";
        for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
        return q + "\"";
    };
    std::ostringstream o;
    o.precision(6);
    o << quote(file) << ',' << quote(mesh.at("name").get<std::string>()) << ',' << mesh.at("vertices").get<uint64_t>() << ','
      << mesh.at("triangles").get<uint64_t>() << ',' << mesh.at("build_seconds").get<double>() << ',' << mesh.at("report_seconds").get<double>()
      << ',' << mesh.at("memory").at("tom_percent").get<double>() << ',' << mesh.at("fit").at("k_mean").get<double>() << ','
      << mesh.at("fit").at("k_max").get<double>();
    for (const auto& l : mesh.at("levels"))
        o << ',' << l.at("triangles").get<uint64_t>() << ',' << l.at("error").at("hausdorff").get<double>() << ','
          << l.at("error").at("mean").get<double>();
    o << '\n';
    return o.str();
}

} // namespace tom
