#pragma once
// The attribute term of the fairness predicates: how far a vertex's attributes (normal, TEXCOORD_0,
// COLOR_0, each scaled to a length) are from the attribute fields of the surface it leaves.
//
// After Hoppe, "New quadric metric for simplifying meshes with appearance attributes" (1999):
// over each triangle an attribute a is a linear field g.p + d (g in the triangle's plane); the
// error of giving a point p the attribute value s is sum_t w_t (g_t.p + d_t - s)^2, a quadric in
// (p, s) accumulated per vertex like the geometric one. Restricted to existing vertices it is
// evaluated at (p_u, a_u) for a substitution v -> u, so a collapse along a region where the
// attributes vary linearly (a smooth normal field, an undistorted UV chart) costs nothing, and
// one across a crease, a UV fold or a colour edge costs what it smears.

#include <cmath>
#include <cstdint>
#include <vector>

#include "parallel.h"
#include "tom/builder/mesh.h"
#include "platform.h"

namespace tom::detail {

/// The weight of a triangle's planes in the geometric and attribute quadrics (and of a pruned
/// piece's triangles): the square root of its area (see Quadric in substitution.h).
inline double quadric_weight(double area) noexcept { return std::sqrt(area); }

/// The animation channels of a mesh (BuildParams::animation_weight), already scaled, `count` per
/// vertex in the order the builder's vertices are numbered in.
///
/// Skinning: posed, a vertex goes to sum_j w_j M_j p. For joints turning by a common rotation
/// R about their bind-pose centres c_j, M_j p = R (p - c_j) + c_j, and with weights summing to
/// 1 the posed point is R p + (I - R) c, where c = sum_j w_j c_j is the vertex's joint centroid.
/// Substituting v by u therefore moves the posed surface by (I - R) (c_field(p_u) - c_u) beyond
/// its rest-pose error: a linear field's error like the attributes', times |I - R| (about the
/// angle). The centroid, scaled by a typical |I - R|, is three channels; vertices driven alike
/// have equal centroids and substitute among themselves for free.
/// Morph targets: at weight 1 a target moves each vertex by its delta d, so a substitution
/// departs from the morphed surface by d_field(p_u) - d_u: each target's POSITION deltas are
/// three channels at scale 1. The kMaxTargets targets with the largest deltas are weighed; the
/// others are carried but not weighed.
struct AnimationChannels {
    static constexpr int kMaxTargets = 8;
    int count = 0;
    std::vector<float> values;  // count per vertex

    /// The channels of `mesh` (its JOINTS_n/WEIGHTS_n streams with joint_positions, its
    /// TARGET<k>/POSITION streams) in the order `order` gives (vertex i is mesh's order[i]).
    /// None when weight <= 0 or the mesh is neither skinned nor morphed.
    static AnimationChannels of(const Mesh& mesh, float weight, const std::vector<uint32_t>& order);
};

class AttributeError {
public:
    /// Prepares the scaled attributes and, when `accumulate`, the per-vertex quadrics of the
    /// input triangles. Scales: TEXCOORD_0 by sqrt(surface area / UV area) (texture units to
    /// surface length), normals and colours by the mean edge length, each by a measured relative
    /// weight (see the .cpp); all by `weight`.
    /// Inactive (every cost 0) when weight <= 0 or the mesh has none of the streams.
    /// `team` shares the accumulation (bit-identical sums whatever its size). With normals alone
    /// the costs read `mesh.normals` (6 bytes a triangle less than a scaled copy), which must
    /// then stay as they are until release().
    /// The `animation` channels follow the attributes'. Without `texcoords`, TEXCOORD_0 is not
    /// weighed (BuildParams::weigh_texcoords).
    void init(const Mesh& mesh, float weight, bool texcoords, const AnimationChannels& animation, bool accumulate, Team& team);
    bool active() const noexcept { return channels_ > 0; }
    int channels() const noexcept { return channels_; }

    /// Accumulated error of v's quadric at u's position and attributes, weighted like the
    /// geometric quadric (sqrt of each triangle's area) and, like it, not divided by the weight.
    double accumulated(uint32_t v, const float* position_u, uint32_t u) const noexcept {
        if (quadric_.empty()) return 0.0;
        const double* q = &quadric_[size_t(v) * stride_];
        float scaled[kMaxChannels];
        const float* a = values(u, scaled);
        switch (channels_) {  // the common layouts unrolled (the same sums in the same order)
        case 3: return evaluate<3>(q, position_u, a);        // normals
        case 5: return evaluate<5>(q, position_u, a);        // normals, TEXCOORD_0
        default: return evaluate<0>(q, position_u, a);
        }
    }
    /// Starts loading v's quadric (a hint; no effect on results).
    void prefetch(uint32_t v) const noexcept {
        if (quadric_.empty()) return;
        const char* q = reinterpret_cast<const char*>(&quadric_[size_t(v) * stride_]);
        for (size_t byte = 0; byte < stride_ * sizeof(double); byte += 64) tom::detail::prefetch(q + byte);
    }
    /// Frees the quadrics and values (every later cost is 0: inactive).
    void release() noexcept {
        TeamVector<double>().swap(quadric_);
        std::vector<float>().swap(values_);
        normals_ = nullptr;
        channels_ = 0;
        stride_ = 0;
    }
    /// v's quadric merges into u's (v -> u).
    void merge(uint32_t u, uint32_t v) noexcept;

    /// Squared attribute error of triangle (i0, i1, i2)'s fields at u's position and attributes,
    /// summed over channels (for the memoryless predicate); 0 for a zero-area triangle.
    double triangle_error(const float* positions, uint32_t i0, uint32_t i1, uint32_t i2, uint32_t u) const noexcept;

private:
    // u's scaled attributes: its row of values_, or, with normals alone, made in `scratch` from
    // the mesh's normals with the same operations in the same order as values_ would hold them
    const float* values(uint32_t u, float* scratch) const noexcept {
        if (!normals_) return &values_[size_t(u) * size_t(channels_)];
        for (int j = 0; j < 3; ++j) scratch[j] = float(normal_factor_ * normals_[3 * size_t(u) + size_t(j)]);
        return scratch;
    }

    // v's quadric q at position p with attributes a; C channels (0: channels_)
    template <int C>
    double evaluate(const double* q, const float* p, const float* a) const noexcept {
        if (!(q[0] > 0)) return 0.0;
        const double x = p[0], y = p[1], z = p[2];
        double e = q[1] * x * x + q[4] * y * y + q[6] * z * z + 2 * (q[2] * x * y + q[3] * x * z + q[5] * y * z) + 2 * (q[7] * x + q[8] * y + q[9] * z) + q[10];
        const int channels = C ? C : channels_;
        for (int j = 0; j < channels; ++j) {
            const double* ch = &q[11 + 4 * j];
            const double s = a[j];
            e += q[0] * s * s - 2 * s * (ch[0] * x + ch[1] * y + ch[2] * z + ch[3]);
        }
        return e > 0 ? e : 0.0;
    }

    int channels_ = 0;
    std::vector<float> values_;    // channels_ per vertex, scaled; empty with normals alone:
    const float* normals_ = nullptr;  // then the mesh's normals (3 per vertex), which init()'s
    double normal_factor_ = 0;        // caller keeps while it evaluates, scaled by this factor
    TeamVector<double> quadric_;  // stride_ per vertex: w, A (6), b (3), c, then per channel G (3), D
    size_t stride_ = 0;
    // normals (3), TEXCOORD_0 (2), COLOR_0 (4), joint centroid (3), morph targets (3 each)
    static constexpr int kMaxChannels = 12 + 3 * AnimationChannels::kMaxTargets;
    static constexpr size_t kMaxStride = 11 + 4 * size_t(kMaxChannels);
};

} // namespace tom::detail
