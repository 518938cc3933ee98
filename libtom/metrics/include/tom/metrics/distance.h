#pragma once
// Metro-style geometric distance between two triangle surfaces (Cignoni, Rocchini, Scopigno,
// "Metro: measuring error on simplified surfaces", 1998), computed with CGAL AABB trees.
// Part of the tom::metrics library (target tom::metrics), which carries CGAL.
//
// Conventions, as Metro's: in each direction the samples are every vertex, then points along
// every edge, then area-uniform random points on the faces, about `samples_per_face` times the
// face count of the larger mesh in total; max, mean and RMS are over all samples of a
// direction; Hausdorff is the larger of the two maxima. Relative figures divide by the
// diagonal of the union bounding box of both meshes, each side moved out by 2% of its diagonal.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>

namespace tom {

/// A triangle surface as flat arrays (nothing is copied or owned).
struct Surface {
    const float* positions = nullptr;  ///< xyz per vertex
    uint32_t vertex_count = 0;
    const uint32_t* indices = nullptr; ///< 3 per triangle, each < vertex_count
    size_t triangle_count = 0;
};

/// Per-vertex attributes of a Surface, for the attribute deviation; null streams are absent.
struct SurfaceAttributes {
    const float* normals = nullptr;    ///< xyz per vertex
    const float* texcoords = nullptr;  ///< uv per vertex
};

/// How far the simplified surface's attributes are from the original's: at area-uniform random
/// points of the original's faces, the attributes interpolated there against those interpolated
/// at the closest point of the simplified surface (only where both surfaces have the stream).
struct AttributeDeviation {
    uint64_t samples = 0;
    bool normals = false, texcoords = false;            ///< which streams were compared
    double normal_mean_degrees = 0, normal_max_degrees = 0;
    double uv_mean = 0, uv_max = 0;                     ///< texture-coordinate units
};

struct DistanceParams {
    double samples_per_face = 10.0;  ///< total samples per direction = this x faces of the larger mesh
    uint64_t max_samples = 0;        ///< cap on that total per direction (0: none)
    /// Cap per direction of this x the faces of the surface sampled in it (0: none; not Metro's
    /// convention, which gives both directions the same total). The error curve's: a level of a
    /// few large faces far from the original needs few samples, and each costs a long search.
    double max_samples_per_sampled_face = 0;
    uint64_t seed = 1;               ///< fixed seed: repeated runs give identical figures
    bool vertex_samples = true;
    bool edge_samples = true;
    bool face_samples = true;
    unsigned threads = 0;            ///< 0: every core
    /// attribute deviation: about this x faces of the original samples, every k-th of the
    /// forward direction's face samples (their nearest points serve both); where those are fewer
    /// than half that (vertices and long edges took the budget), face samples of its own
    double attribute_samples_per_face = 2.0;
    /// A surface searched that has at least this many triangles (0: none) is searched sample by
    /// sample in a compact tree over its own arrays (about 16 bytes a triangle) instead of the
    /// run search's structure (about 270 bytes a triangle, made in a CGAL tree): for a few
    /// thousand samples against large surfaces, as the error curve's (from 2^18 triangles), where
    /// making that structure costs far more time and memory than the searches; below, the run
    /// search is the faster (CAD parts' long thin triangles). The same figures (the same exact
    /// distances); not with the attribute deviation (compare() with attributes takes the run
    /// search).
    uint64_t compact_search_triangles = 0;
    /// A direction of more than 4 x this many samples is sampled and searched in batches of
    /// about this many, each a compact part of the surface, so that the samples in flight (some
    /// 80 bytes each) bound the memory; the same samples, so the same figures up to the order of
    /// their sums. 0: never in batches.
    uint64_t batch_samples = uint64_t(1) << 20;
};

/// One direction: from the samples of one surface to the closest points of the other.
struct OneSidedDistance {
    double max = 0, mean = 0, rms = 0;  ///< object units
    uint64_t samples = 0, vertex_samples = 0, edge_samples = 0, face_samples = 0;
    double sampled_area = 0;            ///< area of the sampled surface
};

struct Distance {
    OneSidedDistance forward;   ///< first surface (the original) -> second (the simplified)
    OneSidedDistance backward;  ///< second -> first
    double hausdorff = 0;       ///< max(forward.max, backward.max)
    double diagonal = 0;        ///< the denominator of relative figures (see above)
    double percent(double object_units) const noexcept { return diagonal > 0 ? 100.0 * object_units / diagonal : 0.0; }
};

/// Where the faces of two related surfaces lie on each other (a level of a Totally Ordered Mesh
/// and the mesh it was built from: a level's face is one of the original's with some corners
/// substituted), for MetroReference::compare: each closest-point search that runs on its own
/// starts from the hinted face of the sample's face too, near its answer, and a sample's
/// distance to it narrows the candidates of the sample's grid cell. Only the speed depends on
/// them: the searches are exact, so the figures are those without (up to 2^-40 of the surface's
/// size, where a search stops). The error curve uses them.
/// Each is asked only about the faces that carry samples (once for each run of neighbouring
/// samples on a face), so a hint costs nothing for the faces never sampled (most of a large
/// mesh's, with the curve's 4096 samples).
struct FaceHints {
    static constexpr uint32_t kNone = 0xffffffffu;  ///< no hint for this face
    std::function<uint32_t(uint32_t)> original_to_simplified;  ///< face of the original -> a face of the simplified near it, or kNone
    std::function<uint32_t(uint32_t)> simplified_to_original;  ///< face of the simplified -> a face of the original near it, or kNone
};

/// Distance between two surfaces in both directions.
/// \throw tom::ArgumentError when a surface has no triangle or an index out of range.
Distance metro_distance(const Surface& original, const Surface& simplified, const DistanceParams& params = {});

/// The exact squared distance from each of `count` points (xyz in `points`) to the nearest point
/// of `target`, written to `squared_distances[i]` (the same search the distances above use:
/// points grouped by grid cell, one candidate list per cell; both cores by default).
/// \throw tom::ArgumentError when the target has no triangle or an index out of range.
void nearest_squared_distances(const Surface& target, const double* points, size_t count, double* squared_distances, unsigned threads = 0);

/// The original side of many comparisons, prepared once: its AABB tree and its own samples,
/// then compare() against any number of simplified versions (the levels of a report).
class MetroReference {
public:
    /// `original` (and its attribute streams) must outlive this object.
    /// \throw tom::ArgumentError as metro_distance.
    MetroReference(const Surface& original, const DistanceParams& params = {}, const SurfaceAttributes& attributes = {});
    ~MetroReference();
    MetroReference(MetroReference&&) noexcept;
    MetroReference& operator=(MetroReference&&) noexcept;

    /// The same figures metro_distance(original, simplified, params) gives. Safe to call from
    /// several threads at once (the figures do not depend on it).
    Distance compare(const Surface& simplified) const;
    /// The same, and the attribute deviation of `simplified` (whose attributes are given).
    Distance compare(const Surface& simplified, const SurfaceAttributes& attributes, AttributeDeviation& deviation) const;
    /// The same figures as compare(simplified), faster where `hints` are good (see FaceHints).
    /// \throw tom::ArgumentError as compare(), or when a hint is not a face of its surface.
    Distance compare(const Surface& simplified, const FaceHints& hints) const;

    /// A reference to the same original with other parameters and attributes, sharing this
    /// one's search structure of the original (a report's levels and its error curve: made once).
    MetroReference with_params(const DistanceParams& params, const SurfaceAttributes& attributes = {}) const;

private:
    MetroReference() = default;
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace tom
