#pragma once
// A mesh's measured error curve, stored in its .tom metadata (key "error_curve") so a runtime
// can estimate the geometric error of any resolution without the original mesh.
//
// Errors are relative: a fraction of `diagonal` (the Metro denominator: the bounding-box
// diagonal of the original and the level, each side moved out by 2% of it). `mean` is the
// larger of the two one-sided Metro mean distances, `max` the Hausdorff distance. The error
// model is Pasman & Jansen's D = k / N, N the triangle count.

#include <cstdint>
#include <optional>
#include <vector>

#include "tom/extract.h"
#include "tom/view.h"

namespace tom {

struct ErrorCurvePoint {
    uint32_t vertices = 0;
    uint32_t triangles = 0;
    float mean = 0;  ///< fraction of the diagonal
    float max = 0;   ///< fraction of the diagonal
};

struct ErrorCurve {
    float diagonal = 0;  ///< object units
    float k_mean = 0;    ///< D_mean ~ k_mean / triangles
    float k_max = 0;     ///< D_max ~ k_max / triangles
    std::vector<ErrorCurvePoint> points;  ///< increasing vertex count, 2..64 points
};

constexpr const char* error_curve_key = "error_curve";

/// The metadata value for `curve` (layout in docs/FORMAT.md, key error_curve).
std::vector<uint8_t> encode_error_curve(const ErrorCurve& curve);

/// The curve stored with `mesh`, if any. A malformed value reads as absent (nullopt).
std::optional<ErrorCurve> read_error_curve(const MeshView& mesh);

/// Estimated relative error (fraction of the diagonal) at `triangles`: log-log interpolation
/// between the stored points, k / N beyond them. `use_max` selects the max curve.
double estimate_error(const ErrorCurve& curve, double triangles, bool use_max = false) noexcept;

/// The coarsest resolution of `mesh` whose error is known to be at most `max_error` (a fraction
/// of the diagonal; the Hausdorff distance with `use_max`, else the mean): the fewest vertices of
/// a stored point from which on every stored point, measured, is within the bound; the full
/// resolution (error 0) when none is. Measured points only, never the interpolation, so what
/// tomerr measures at that level is within the bound (up to its sampling).
/// Never below the usable floor unless `floor` is Floor::coarsest.
uint32_t vertex_count_for_error(const MeshView& mesh, const ErrorCurve& curve, double max_error, bool use_max = true,
                                Floor floor = Floor::usable) noexcept;

/// The usable floor (metadata key "usable_floor", layout in docs/FORMAT.md): the coarsest
/// resolution a selection picks unless asked to go lower (tom::Floor), where the stored curve
/// says the mean error stays within `mean_bound` (a fraction of the diagonal) from there on.
/// tombuild stores it beside the curve (--floor-error); below it the chain may fold and tear.
struct UsableFloor {
    uint32_t vertices = 0;
    float mean_bound = 0;
};

constexpr const char* usable_floor_key = "usable_floor";

/// The metadata value for `floor`.
std::vector<uint8_t> encode_usable_floor(const UsableFloor& floor);

/// The usable floor stored with `mesh`, if any. A malformed value (or a count outside
/// [min_vertex_count, vertex_count]) reads as absent.
std::optional<UsableFloor> read_usable_floor(const MeshView& mesh) noexcept;

/// Whether a measured point may be part of a usable floor at `mean_bound`: its level has
/// triangles (an empty level measures 0 but is no floor) and its mean error is within the bound.
inline bool within_floor_bound(const ErrorCurvePoint& p, double mean_bound) noexcept { return p.triangles > 0 && double(p.mean) <= mean_bound; }

/// The usable floor for `curve` at `mean_bound`: the coarsest measured point from which on every
/// point's mean error is within the bound and whose level has triangles (the full resolution
/// when the finest measured point is already beyond it).
UsableFloor usable_floor_of(const MeshView& mesh, const ErrorCurve& curve, double mean_bound) noexcept;

/// Least-squares fit of D = k / N through (N, D) pairs, in log space: k is the geometric mean of
/// D * N. Also the free slope b of log D = a + b log N (b = -1 is Pasman's law) and the RMS of
/// the log10 residuals of the k / N model. Pairs with D <= 0 or N == 0 are ignored.
struct KFit {
    double k = 0;
    double slope = 0;
    double rms_log10 = 0;
    size_t used = 0;
};
KFit fit_k_over_n(const std::vector<double>& triangles, const std::vector<double>& errors);

} // namespace tom
