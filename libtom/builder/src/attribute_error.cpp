// The attribute term of the fairness predicates (see attribute_error.h).

#include "attribute_error.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

#include "vec3.h"

namespace tom::detail {

namespace {

using D3 = Vec3T<double>;
inline D3 at(const float* p, uint32_t i) { return {p[3 * size_t(i)], p[3 * size_t(i) + 1], p[3 * size_t(i) + 2]}; }

// The linear field g.p + d over triangle (p0, p1, p2) taking values a0, a1, a2 at its corners,
// with g in the triangle's plane: g = (da1 (e2 x n) + da2 (n x e1)) / |n|^2.
struct Frame {
    D3 p0, r1, r2;  // r1 = (e2 x n) / |n|^2, r2 = (n x e1) / |n|^2
    double area;
    bool valid;
};

Frame frame(D3 p0, D3 p1, D3 p2) {
    Frame f;
    const D3 e1 = sub(p1, p0), e2 = sub(p2, p0), n = cross(e1, e2);
    const double nn = dot(n, n);
    f.p0 = p0;
    f.valid = nn > 0;
    f.area = 0.5 * std::sqrt(nn);
    if (!f.valid) return f;
    const D3 a = cross(e2, n), b = cross(n, e1);
    f.r1 = {a.x / nn, a.y / nn, a.z / nn};
    f.r2 = {b.x / nn, b.y / nn, b.z / nn};
    return f;
}

const VertexStream* find_stream(const Mesh& mesh, const std::string& name) {
    for (const VertexStream& x : mesh.extra_streams)
        if (x.name == name) return &x;
    return nullptr;
}

double value(const VertexStream& x, size_t vertex, uint32_t component) {
    return component_value(x.component_type, x.normalized, &x.data[vertex * x.element_bytes() + component * component_bytes(x.component_type)]);
}

// A skinned mesh's influence streams: JOINTS_k with WEIGHTS_k, k = 0, 1, ... while both exist
// with as many components
std::vector<std::pair<const VertexStream*, const VertexStream*>> influence_streams(const Mesh& mesh) {
    std::vector<std::pair<const VertexStream*, const VertexStream*>> out;
    for (int k = 0;; ++k) {
        const VertexStream* joints = find_stream(mesh, "JOINTS_" + std::to_string(k));
        const VertexStream* weights = find_stream(mesh, "WEIGHTS_" + std::to_string(k));
        if (!joints || !weights || joints->components != weights->components) return out;
        out.emplace_back(joints, weights);
    }
}

// The morph targets' POSITION deltas, the kMaxTargets with the largest summed length, in target order
std::vector<const VertexStream*> weighed_targets(const Mesh& mesh, size_t vertex_count) {
    std::vector<std::pair<double, const VertexStream*>> targets;
    for (int k = 0;; ++k) {
        const VertexStream* x = find_stream(mesh, "TARGET" + std::to_string(k) + "/POSITION");
        if (!x) break;
        if (x->components != 3) continue;
        double size = 0;
        for (size_t v = 0; v < vertex_count; ++v) {
            const double d[3] = {value(*x, v, 0), value(*x, v, 1), value(*x, v, 2)};
            size += std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        }
        targets.emplace_back(size, x);
    }
    std::stable_sort(targets.begin(), targets.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    if (targets.size() > size_t(AnimationChannels::kMaxTargets)) targets.resize(size_t(AnimationChannels::kMaxTargets));
    std::vector<const VertexStream*> out;
    for (const auto& t : targets) out.push_back(t.second);
    std::sort(out.begin(), out.end());  // in the streams' order (all point into mesh.extra_streams)
    return out;
}

} // namespace

AnimationChannels AnimationChannels::of(const Mesh& mesh, float weight, const std::vector<uint32_t>& order) {
    AnimationChannels out;
    if (!(weight > 0)) return out;
    const auto influences = influence_streams(mesh);
    const size_t joints = mesh.joint_positions.size() / 3;
    const bool skinned = !influences.empty() && joints > 0;
    const std::vector<const VertexStream*> targets = weighed_targets(mesh, order.size());
    out.count = (skinned ? 3 : 0) + 3 * int(targets.size());
    if (out.count == 0) return out;
    // a typical joint rotation: |I - R| = 2 sin(angle / 2) is 0.7 for about 40 degrees (see the header)
    constexpr double skin_angle = 0.7;
    out.values.resize(order.size() * size_t(out.count));
    for (size_t i = 0; i < order.size(); ++i) {
        const uint32_t v = order[i];
        float* dst = &out.values[i * size_t(out.count)];
        if (skinned) {
            double c[3] = {0, 0, 0}, sum = 0;
            for (const auto& [joint_stream, weight_stream] : influences)
                for (uint32_t k = 0; k < joint_stream->components; ++k) {
                    const double w = value(*weight_stream, v, k), j = value(*joint_stream, v, k);
                    if (!(w > 0) || !(j >= 0) || j >= double(joints)) continue;
                    for (int a = 0; a < 3; ++a) c[a] += w * mesh.joint_positions[3 * size_t(j) + size_t(a)];
                    sum += w;
                }
            for (int a = 0; a < 3; ++a) *dst++ = float(sum > 0 ? weight * skin_angle * c[a] / sum : 0.0);
        }
        for (const VertexStream* x : targets)
            for (uint32_t a = 0; a < 3; ++a) *dst++ = float(weight * value(*x, v, a));
    }
    return out;
}

void AttributeError::init(const Mesh& mesh, float weight, bool texcoords, const AnimationChannels& animation, bool accumulate, Team& team) {
    channels_ = 0;
    values_.clear();
    normals_ = nullptr;
    quadric_.clear();
    const uint32_t n = mesh.vertex_count(), m = mesh.triangle_count();
    if (n == 0 || m == 0) return;
    const bool attributes = weight > 0;
    const bool normals = attributes && mesh.normals.size() == size_t(n) * 3, uv = attributes && texcoords && mesh.texcoords.size() == size_t(n) * 2,
               colors = attributes && mesh.colors.size() == size_t(n) * 4;
    const int animated = animation.values.size() == size_t(n) * size_t(animation.count) ? animation.count : 0;
    channels_ = (normals ? 3 : 0) + (uv ? 2 : 0) + (colors ? 4 : 0) + animated;
    if (channels_ == 0) return;
    // scales: mean edge length; surface area over UV area
    // each triangle's terms on the team, a tile at a time, then summed in triangle order (the
    // same sums whatever the thread count)
    const float* p = mesh.positions.data();
    constexpr size_t kTile = 8192;  // a buffer that stays in cache
    std::vector<double> terms(std::min<size_t>(m, kTile) * 5);  // a triangle's three edge lengths, area, UV area
    double edges = 0, area = 0, uv_area = 0;
    for (size_t first = 0; first < m; first += kTile) {
        const size_t count = std::min<size_t>(kTile, m - first);
        team.blocks(count, 4096, [&](unsigned, size_t begin, size_t end) {
            for (size_t i = begin; i < end; ++i) {
                const uint32_t* c = &mesh.indices[3 * (first + i)];
                double* out = &terms[5 * i];
                for (int k = 0; k < 3; ++k) {
                    const D3 e = sub(at(p, c[(k + 1) % 3]), at(p, c[k]));
                    out[k] = std::sqrt(dot(e, e));
                }
                const D3 nrm = cross(sub(at(p, c[1]), at(p, c[0])), sub(at(p, c[2]), at(p, c[0])));
                out[3] = 0.5 * std::sqrt(dot(nrm, nrm));
                out[4] = 0;
                if (uv) {
                    const float* t0 = &mesh.texcoords[2 * size_t(c[0])];
                    const float* t1 = &mesh.texcoords[2 * size_t(c[1])];
                    const float* t2 = &mesh.texcoords[2 * size_t(c[2])];
                    out[4] = 0.5 * std::fabs(double(t1[0] - t0[0]) * (t2[1] - t0[1]) - double(t1[1] - t0[1]) * (t2[0] - t0[0]));
                }
            }
        });
        for (size_t i = 0; i < count; ++i) {
            const double* in = &terms[5 * i];
            edges += in[0];
            edges += in[1];
            edges += in[2];
            area += in[3];
            uv_area += in[4];
        }
    }
    const double h = edges / (3.0 * m);
    const double uv_scale = uv_area > 0 ? std::sqrt(area / uv_area) : 0.0;
    // Relative weights of the channels at weight 1, chosen with scripts/attribute-weights.sh (Metro
    // mean error, mean normal deviation and UV displacement on the sample meshes): the largest
    // normal weight that keeps the geometric error of a hard-edged CAD mesh below
    // meshopt_simplify's, and the UV weight past which the texture displacement stops falling.
    constexpr double normal_scale = 0.015, uv_weight = 0.3, color_scale = 0.1;
    if (channels_ == 3 && normals) {
        normals_ = mesh.normals.data();
        normal_factor_ = weight * normal_scale * h;  // (weight * normal_scale * h) * normal below: the same value
    } else {
        values_.resize(size_t(n) * size_t(channels_));
    }
    for (uint32_t v = 0; v < n && !normals_; ++v) {
        float* out = &values_[size_t(v) * size_t(channels_)];
        int k = 0;
        if (normals)
            for (int j = 0; j < 3; ++j) out[k++] = float(weight * normal_scale * h * mesh.normals[3 * size_t(v) + size_t(j)]);
        if (uv)
            for (int j = 0; j < 2; ++j) out[k++] = float(weight * uv_weight * uv_scale * mesh.texcoords[2 * size_t(v) + size_t(j)]);
        if (colors)
            for (int j = 0; j < 4; ++j) out[k++] = float(weight * color_scale * h * mesh.colors[4 * size_t(v) + size_t(j)]);
        for (int j = 0; j < animated; ++j) out[k++] = animation.values[size_t(v) * size_t(animated) + size_t(j)];
    }
    if (!accumulate) return;
    stride_ = 11 + 4 * size_t(channels_);
    zero_on_team(team, quadric_, size_t(n) * stride_);
    double* quadric = quadric_.data();
    auto scatter = [&](auto channel_count) {  // the channel count a constant where it is common: unrolled sums, the same in the same order
        constexpr int kC = decltype(channel_count)::value;
        const int channels = kC ? kC : channels_;
        const size_t stride = kC ? 11 + 4 * size_t(kC) : stride_;
        detail::scatter_by_vertex_range(team, n, mesh.indices.data(), m, [&](uint32_t t, uint32_t lo, uint32_t hi) {
            const uint32_t* c = &mesh.indices[3 * size_t(t)];
            const Frame f = frame(at(p, c[0]), at(p, c[1]), at(p, c[2]));
            if (!f.valid) return;
            double q[kMaxStride] = {};
            const double w = quadric_weight(f.area);
            q[0] = w;
            float scaled[3][kMaxChannels];
            const float* a[3] = {values(c[0], scaled[0]), values(c[1], scaled[1]), values(c[2], scaled[2])};
            for (int j = 0; j < channels; ++j) {
                const double a0 = a[0][j];
                const double d1 = a[1][j] - a0;
                const double d2 = a[2][j] - a0;
                const D3 g = {d1 * f.r1.x + d2 * f.r2.x, d1 * f.r1.y + d2 * f.r2.y, d1 * f.r1.z + d2 * f.r2.z};
                const double d = a0 - dot(g, f.p0);
                // sum over channels of w (g.p + d)^2 = p^T (w g g^T) p + 2 (w d g).p + w d^2
                q[1] += w * g.x * g.x, q[2] += w * g.x * g.y, q[3] += w * g.x * g.z, q[4] += w * g.y * g.y, q[5] += w * g.y * g.z, q[6] += w * g.z * g.z;
                q[7] += w * d * g.x, q[8] += w * d * g.y, q[9] += w * d * g.z;
                q[10] += w * d * d;
                double* ch = &q[11 + 4 * size_t(j)];
                ch[0] = w * g.x, ch[1] = w * g.y, ch[2] = w * g.z, ch[3] = w * d;
            }
            for (int k = 0; k < 3; ++k) {
                if (c[k] < lo || c[k] >= hi) continue;
                double* dst = quadric + size_t(c[k]) * stride;
                for (size_t i = 0; i < stride; ++i) dst[i] += q[i];
            }
        });
    };
    switch (channels_) {
    case 3: scatter(std::integral_constant<int, 3>()); break;  // normals
    case 5: scatter(std::integral_constant<int, 5>()); break;  // normals, TEXCOORD_0
    default: scatter(std::integral_constant<int, 0>()); break;
    }
}

void AttributeError::merge(uint32_t u, uint32_t v) noexcept {
    if (quadric_.empty()) return;
    double* dst = &quadric_[size_t(u) * stride_];
    const double* src = &quadric_[size_t(v) * stride_];
    for (size_t i = 0; i < stride_; ++i) dst[i] += src[i];
}

double AttributeError::triangle_error(const float* positions, uint32_t i0, uint32_t i1, uint32_t i2, uint32_t u) const noexcept {
    if (channels_ == 0) return 0.0;
    const Frame f = frame(at(positions, i0), at(positions, i1), at(positions, i2));
    if (!f.valid) return 0.0;
    const D3 pu = at(positions, u);
    const D3 rel = sub(pu, f.p0);
    const double l1 = dot(rel, f.r1), l2 = dot(rel, f.r2);  // the field's barycentric weights of corners 1 and 2 at p_u
    float scaled[4][kMaxChannels];
    const float *a0 = values(i0, scaled[0]), *a1 = values(i1, scaled[1]), *a2 = values(i2, scaled[2]), *au = values(u, scaled[3]);
    double e = 0;
    for (int j = 0; j < channels_; ++j) {
        const double field = a0[j] + l1 * (double(a1[j]) - a0[j]) + l2 * (double(a2[j]) - a0[j]);
        const double r = field - au[j];
        e += r * r;
    }
    return e;
}

} // namespace tom::detail
