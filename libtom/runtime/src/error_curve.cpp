// Error curve storage and Pasman & Jansen's D = k / N model (Pasman, Jansen: Comparing
// simplification and image-based techniques for 3D client-server rendering systems, 2003).

#include "tom/error_curve.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace tom {

namespace {

constexpr uint32_t kCurveFormat = 1;
constexpr size_t kHeaderBytes = 20, kPointBytes = 16;
constexpr uint32_t kFloorFormat = 1;
constexpr size_t kFloorBytes = 12;

void put32(std::vector<uint8_t>& out, uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
}
void putf(std::vector<uint8_t>& out, float f) {
    uint32_t v;
    std::memcpy(&v, &f, 4);
    put32(out, v);
}
uint32_t get32(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24; }
float getf(const uint8_t* p) {
    const uint32_t v = get32(p);
    float f;
    std::memcpy(&f, &v, 4);
    return f;
}

} // namespace

std::vector<uint8_t> encode_error_curve(const ErrorCurve& c) {
    std::vector<uint8_t> out;
    put32(out, kCurveFormat);
    put32(out, uint32_t(c.points.size()));
    putf(out, c.diagonal);
    putf(out, c.k_mean);
    putf(out, c.k_max);
    for (const ErrorCurvePoint& p : c.points) {
        put32(out, p.vertices);
        put32(out, p.triangles);
        putf(out, p.mean);
        putf(out, p.max);
    }
    return out;
}

std::optional<ErrorCurve> read_error_curve(const MeshView& mesh) {
    const MetadataValue v = find_metadata(mesh, error_curve_key);
    if (!v.found() || v.bytes < kHeaderBytes) return std::nullopt;
    if (get32(v.data) != kCurveFormat) return std::nullopt;
    const uint32_t count = get32(v.data + 4);
    if (count > 4096 || v.bytes != kHeaderBytes + size_t(count) * kPointBytes) return std::nullopt;
    ErrorCurve c;
    c.diagonal = getf(v.data + 8);
    c.k_mean = getf(v.data + 12);
    c.k_max = getf(v.data + 16);
    if (!std::isfinite(c.diagonal) || !std::isfinite(c.k_mean) || !std::isfinite(c.k_max) || c.k_mean < 0 || c.k_max < 0 || c.diagonal < 0)
        return std::nullopt;  // (a negative k would make estimate_error() negative)
    for (uint32_t i = 0; i < count; ++i) {
        const uint8_t* p = v.data + kHeaderBytes + size_t(i) * kPointBytes;
        ErrorCurvePoint q{get32(p), get32(p + 4), getf(p + 8), getf(p + 12)};
        if (!std::isfinite(q.mean) || !std::isfinite(q.max) || q.mean < 0 || q.max < 0) return std::nullopt;
        if (!c.points.empty() && q.vertices <= c.points.back().vertices) return std::nullopt;
        c.points.push_back(q);
    }
    return c;
}

double estimate_error(const ErrorCurve& c, double triangles, bool use_max) noexcept {
    const double k = use_max ? c.k_max : c.k_mean;
    triangles = std::max(triangles, 1.0);
    auto value = [&](const ErrorCurvePoint& p) { return double(use_max ? p.max : p.mean); };
    // points sorted by vertices, hence by triangles; find the bracket
    const ErrorCurvePoint* lo = nullptr;
    const ErrorCurvePoint* hi = nullptr;
    for (const ErrorCurvePoint& p : c.points) {
        if (p.triangles == 0) continue;
        if (double(p.triangles) <= triangles) lo = &p;
        if (double(p.triangles) >= triangles && !hi) hi = &p;
    }
    if (lo && hi && lo != hi && value(*lo) > 0 && value(*hi) > 0) {
        const double t = (std::log(triangles) - std::log(double(lo->triangles))) / (std::log(double(hi->triangles)) - std::log(double(lo->triangles)));
        return std::exp(std::log(value(*lo)) + t * (std::log(value(*hi)) - std::log(value(*lo))));
    }
    if (lo && hi && lo == hi) return value(*lo);
    // beyond the measured range: scale the nearest point by k / N, or k / N itself
    const ErrorCurvePoint* edge = lo ? lo : hi;
    if (edge && value(*edge) > 0) return value(*edge) * double(edge->triangles) / triangles;
    return k / triangles;
}

std::vector<uint8_t> encode_usable_floor(const UsableFloor& floor) {
    std::vector<uint8_t> out;
    put32(out, kFloorFormat);
    put32(out, floor.vertices);
    putf(out, floor.mean_bound);
    return out;
}

std::optional<UsableFloor> read_usable_floor(const MeshView& mesh) noexcept {
    const MetadataValue v = find_metadata(mesh, usable_floor_key);
    if (!v.found() || v.bytes != kFloorBytes || get32(v.data) != kFloorFormat) return std::nullopt;
    const UsableFloor f{get32(v.data + 4), getf(v.data + 8)};
    if (f.vertices < mesh.min_vertex_count || f.vertices > mesh.vertex_count || !std::isfinite(f.mean_bound) || f.mean_bound < 0) return std::nullopt;
    return f;
}

UsableFloor usable_floor_of(const MeshView& mesh, const ErrorCurve& curve, double mean_bound) noexcept {
    UsableFloor f{mesh.vertex_count, float(mean_bound)};
    // from the finest point down, while every point so far is within the bound
    for (auto p = curve.points.rbegin(); p != curve.points.rend(); ++p) {
        if (p->vertices > mesh.vertex_count || p->vertices < mesh.min_vertex_count) continue;
        if (!within_floor_bound(*p, mean_bound)) break;
        f.vertices = p->vertices;
    }
    return f;
}

uint32_t vertex_count_for_error(const MeshView& mesh, const ErrorCurve& curve, double max_error, bool use_max, Floor floor) noexcept {
    const uint32_t lowest = floor_vertex_count(mesh, floor);
    uint32_t n = mesh.vertex_count;
    // from the finest point down, while every point so far is within the bound
    for (auto p = curve.points.rbegin(); p != curve.points.rend(); ++p) {
        if (p->vertices > mesh.vertex_count || p->vertices < lowest) continue;
        if (double(use_max ? p->max : p->mean) > max_error) break;
        n = p->vertices;
    }
    return n;
}

KFit fit_k_over_n(const std::vector<double>& triangles, const std::vector<double>& errors) {
    KFit f;
    std::vector<double> x, y;
    for (size_t i = 0; i < std::min(triangles.size(), errors.size()); ++i)
        if (triangles[i] > 0 && errors[i] > 0) {
            x.push_back(std::log(triangles[i]));
            y.push_back(std::log(errors[i]));
        }
    f.used = x.size();
    if (x.empty()) return f;
    // slope fixed at -1: log k = mean(log D + log N)
    double log_k = 0;
    for (size_t i = 0; i < x.size(); ++i) log_k += y[i] + x[i];
    log_k /= double(x.size());
    f.k = std::exp(log_k);
    double sq = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        const double r = (y[i] - (log_k - x[i])) / std::log(10.0);
        sq += r * r;
    }
    f.rms_log10 = std::sqrt(sq / double(x.size()));
    // free slope, for how well Pasman's exponent holds
    if (x.size() >= 2) {
        double mx = 0, my = 0;
        for (size_t i = 0; i < x.size(); ++i) mx += x[i], my += y[i];
        mx /= double(x.size()), my /= double(x.size());
        double sxy = 0, sxx = 0;
        for (size_t i = 0; i < x.size(); ++i) sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
        f.slope = sxx > 0 ? sxy / sxx : 0.0;
    }
    return f;
}

} // namespace tom
