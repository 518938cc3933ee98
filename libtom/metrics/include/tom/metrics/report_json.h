#pragma once
// A mesh's report as its users read it: the JSON contract (docs/REPORT.md; report.schema.json
// beside this library states it as a JSON Schema), the readable table, and the rows of the batch
// summary CSV. The JSON is nlohmann::json's (Debian's nlohmann-json3-dev, header-only).

#include <string>

#include <nlohmann/json.hpp>

#include "tom/metrics/report.h"

namespace tom {

struct ReportContext {
    std::string file;            ///< the input file
    double import_seconds = 0;   ///< reading and cleaning the file (all its meshes)
    double build_seconds = 0;    ///< tom::build for this mesh
    double report_seconds = 0;   ///< make_report for this mesh
    uint32_t welded_vertices = 0; ///< identical vertices clean_mesh merged (tom::CleanStats)
    ReportParams params;
};

/// One mesh's report as the documented JSON object.
nlohmann::ordered_json report_json(const tom::MeshReport& r, const ReportContext& ctx);
/// The conventions every report states (sampling, denominators, units).
nlohmann::ordered_json conventions_json(const tom::ReportParams& params);
/// A readable table: levels, memory, fit.
std::string report_table(const tom::MeshReport& r, const ReportContext& ctx);
/// The header and one row of the batch summary CSV.
std::string summary_csv_header(const tom::ReportParams& params);
/// A mesh's row from its report_json() object, so that a rerun that skips an up-to-date input
/// rebuilds the same row from the report on disk.
std::string summary_csv_row(const nlohmann::ordered_json& mesh, const std::string& file);

} // namespace tom
