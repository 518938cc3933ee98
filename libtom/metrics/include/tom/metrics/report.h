#pragma once
// The per-mesh report of tombuild --report: Metro-style error, substitution chains and
// extraction time per level, memory like the TOM paper's Table 4, the D = k / N fit, and the
// error curve stored in the .tom. Part of tom::metrics.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "tom/builder/builder.h"
#include "tom/error_curve.h"
#include "tom/extract.h"
#include "tom/builder/mesh.h"
#include "tom/metrics/distance.h"

namespace tom {

struct ReportParams {
    std::vector<double> levels = {0.5, 0.25, 0.1, 0.05, 0.02, 0.01, 0.005};  ///< fractions of the triangles
    DistanceParams distance;                 ///< Metro's defaults: 10 samples per face, seed 1
    bool error_curve = true;                 ///< make_report also measures the error curve (MeshReport::curve)
    uint32_t curve_points = 16;              ///< error-curve points, log-spaced in vertex count (2..64)
    /// The usable floor's bound (tom::UsableFloor, a fraction of the diagonal; 0: none): the
    /// curve gains up to 6 points bisecting the bracket where its mean error crosses it
    double floor_error = 0.01;
    /// Error-curve sampling, per direction and curve point: area-uniform face samples,
    /// curve_samples_per_triangle x the mesh's triangles within [curve_min_samples,
    /// curve_samples], and at most curve_samples_per_level_face x the faces of the level sampled
    double curve_samples_per_triangle = 0.5;
    uint64_t curve_min_samples = 1024;
    uint64_t curve_samples = 4096;
    double curve_samples_per_level_face = 64;
    /// Called after each error-curve point (from the measuring threads, one call at a time) with
    /// the share of the points measured: for a progress display. Never changes the figures.
    std::function<void(double)> progress;
};

/// One part of a multi-part mesh at one level: its live triangles and its attributes against
/// the original part's (the geometric error is the whole mesh's, LevelReport::error).
struct PartLevelReport {
    int32_t material = -1;
    uint32_t triangles = 0;
    AttributeDeviation attributes;
};

struct LevelReport {
    double fraction = 0;
    uint32_t vertices = 0, triangles = 0;
    double extract_seconds = 0;  ///< median of repeated extractions of the serialized mesh into a preallocated 32-bit buffer
    Distance error;              ///< object units; error.percent() for Metro's relative figures
    AttributeDeviation attributes;  ///< normal angle and texture-coordinate displacement against the original
    ChainStats chain;
    double mean_steps = 0;       ///< substitution steps per corner emitted
    double overhead = 0;         ///< extra distinct vertices walked over vertices sent (n): the paper's Fig. 6
    std::vector<PartLevelReport> parts;  ///< per part, for a mesh of several; empty otherwise
};

struct MemoryReport {
    // all with positions and normals as f32 and 32-bit indices, as the paper's Table 4
    uint64_t face_vertex_bytes = 0;  ///< 24 V + 12 T
    uint64_t tom_bytes = 0;          ///< the .tom image of the mesh in that form (headers included)
    uint64_t lod_bytes = 0;          ///< six discrete levels 100/50/25/12/6/3% as face-vertex meshes
    uint64_t pm_bytes = 0;           ///< progressive mesh, coarsest mesh resident (estimate, see report schema)
    uint64_t pm_max_bytes = 0;       ///< progressive mesh, fully refined mesh resident (estimate)
};

struct FitReport {
    KFit mean;  ///< D_mean = k / N (relative to the diagonal)
    KFit max;   ///< D_max = k / N
};

struct MeshReport {
    std::string name;
    uint32_t vertices = 0, triangles = 0;
    double bbox_diagonal = 0;  ///< denominator of every percentage (enlarged union box, see metrics.h)
    MemoryReport memory;
    FitReport fit;
    std::vector<LevelReport> levels;
    ErrorCurve curve;  ///< empty (no points) when ReportParams::error_curve is false
};

/// Measures `built` against `original` (the cleaned input it was built from).
/// \throw tom::ArgumentError when the meshes do not correspond (counts differ).
MeshReport make_report(const Mesh& original, const TomMesh& built, const ReportParams& params = {});

/// Measures only the error curve (cheaper density) and the k fits, for the .tom metadata.
ErrorCurve measure_error_curve(const Mesh& original, const TomMesh& built, const ReportParams& params = {});

} // namespace tom
