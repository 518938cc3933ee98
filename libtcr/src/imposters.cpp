// Pasman & Jansen's model of polygons against imposters (include/tcr/imposters.h).

#include "tcr/imposters.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tcr::imposters {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Table 1's ceiling, forgiving the rounding of a count that is whole in exact arithmetic.
double whole(double x) { return std::ceil(x - 1e-9); }

bool is_image(Method m) { return m == Method::simple_imposter || m == Method::image_with_depth || m == Method::layered_depth_image; }

// 5.4: bytes per texture pixel: RGB for textured polygons, RGBA for imposters, RGBA+depth for an
// image with depth, 1.24 layers of it plus a layer count for an LDI.
double bytes_per_pixel(Method m) {
    switch (m) {
    case Method::meshed_imposter:
    case Method::simple_imposter: return 4.0;
    case Method::image_with_depth: return 5.0;
    case Method::layered_depth_image: return 1.24 * 5.0 + 1.0;
    default: return 3.0;
    }
}

// 5.5: a polygon model needs a refresh only when the viewer comes nearer (1 of 6 directions),
// every other representation also when it moves around the object (5 of 6).
double refresh_chance(Method m) { return m == Method::polygons || m == Method::incremental_polygons ? 1.0 / 6.0 : 5.0 / 6.0; }

} // namespace

const char* to_string(Method m) {
    switch (m) {
    case Method::polygons: return "polygons";
    case Method::incremental_polygons: return "incremental_polygons";
    case Method::viewpoint_dependent: return "viewpoint_dependent";
    case Method::meshed_imposter: return "meshed_imposter";
    case Method::simple_imposter: return "simple_imposter";
    case Method::image_with_depth: return "image_with_depth";
    case Method::layered_depth_image: return "layered_depth_image";
    }
    return "?";
}

double polygon_distortion(double k, double r, double d, double n) { return 2.0 * k * std::atan(r / d) / n; }

double viewpoint_dependent_distortion(double k, double r, double d, double n, double theta) {
    return (21.0 - 19.0 * std::cos(2.0 * theta)) * k * std::atan(r / d) / (2.0 * n);
}

double parallax(double e, double imposter_distance, double theta, bool behind) {
    if (e <= 0.0) return 0.0;
    const double sign = behind ? 1.0 : -1.0;  // the angle at the imposter point is pi - theta behind it
    const double de = std::sqrt(std::max(0.0, imposter_distance * imposter_distance + e * e + sign * 2.0 * imposter_distance * e * std::cos(theta)));
    if (de <= 0.0) return 0.0;
    return std::asin(std::min(1.0, e * std::sin(theta) / de));
}

double gamma_min(double d, double r, double theta) {
    if (theta == 0.0) return 0.0;
    const double c = std::cos(theta);
    const double S = std::sqrt((d + r) * (d + r) - 4.0 * r * r * c + 4.0 * r * r * c * c);
    const double numerator = std::cos(theta / 2.0) * (r - d + S - 2.0 * r * c);
    const double inside = d * d + d * r + r * (r + S) - (d * (r + S) + 2.0 * r * (2.0 * r + S)) * c + 2.0 * r * (d + 2.0 * r) * c * c;
    const double denominator = std::sqrt(2.0) * std::sqrt(std::max(0.0, inside));
    if (denominator <= 0.0) return 0.0;
    return std::fabs(std::asin(std::max(-1.0, std::min(1.0, numerator / denominator))));
}

double simple_imposter_distortion(double d, double r, double theta) {
    const double c2 = std::cos(2.0 * theta);
    return (1.0 - c2) / 2.0 * 2.0 * std::atan(r / d) + (1.0 + c2) / 2.0 * gamma_min(d, r, theta);
}

double meshed_imposter_distortion(double k, double r, double d, double n, double theta) {
    const double c2 = std::cos(2.0 * theta);
    return ((1.0 - c2) + (1.0 + c2) * k / (2.0 * n) * std::sin(theta)) * 2.0 * std::atan(r / d);
}

double image_with_depth_distortion(double r, double d, double theta) { return (1.0 - std::cos(2.0 * theta)) * std::atan(r / d); }

double reachable_angle(double d, double r, double walk, double min_distance) {
    double theta;
    if (d <= min_distance) {
        theta = walk / (r + min_distance);
    } else {
        const double side = std::sqrt((d - min_distance) * (d + min_distance + 2.0 * r));
        theta = walk > side ? std::asin(std::min(1.0, side / (d + r))) + (walk - side) / (r + min_distance) : std::asin(std::min(1.0, walk / (d + r)));
    }
    return std::min(theta, kPi / 2.0);  // the formulas hold for |theta| <= 90 degrees
}

Setting paper_example() { return Setting{}; }

double nearest_distance(const Setting& s, double d) { return std::max(s.min_distance, d - s.speed * s.lifetime); }

double polygons_needed(const Setting& s, Method m, double d) {
    if (is_image(m)) return 1.0;
    const double near = nearest_distance(s, d), a = std::atan(s.radius / near), D = s.distortion;
    const double theta = reachable_angle(d, s.radius, s.speed * s.lifetime, s.min_distance);
    switch (m) {
    case Method::viewpoint_dependent: return std::max(4.0, whole((21.0 - 19.0 * std::cos(2.0 * theta)) * s.k * a / (2.0 * D)));
    case Method::meshed_imposter: {
        const double room = D + 2.0 * a * (-1.0 + std::cos(2.0 * theta));  // the bound less the missing back face
        if (room <= 0.0) return kInfinity;
        return std::max(4.0, whole((std::sin(theta) + std::sin(3.0 * theta)) * s.k * a / (2.0 * room)));
    }
    default: return std::max(4.0, whole(2.0 * s.k * a / D));
    }
}

double far_texture_pixels(const Setting& s, double d) {
    const double side = 2.0 * std::atan(s.radius / d) / s.distortion;
    return side * side;
}

double scan_extension(const Setting& s) {
    const double m = s.min_distance, r = s.radius, D = s.distortion;
    const double q = m * std::atan(r / m) * std::tan(D) / (r * D);
    return (r + m) * std::acos(std::max(-1.0, 1.0 - 2.0 / kPi * q * q));
}

double texture_pixels(const Setting& s, double d) {
    const double walk = s.speed * s.lifetime;
    if (walk <= d - s.min_distance) return far_texture_pixels(s, d - walk);
    // the viewer reaches MinDist and scans the surface from there: the area it can see, at most
    // the whole sphere, over a pixel's area at MinDist
    const double near = walk - (d - s.min_distance) + scan_extension(s);
    const double angle = std::min(kPi, near / (s.radius + s.min_distance));
    const double area = 2.0 * kPi * s.radius * s.radius * (1.0 - std::cos(angle));
    const double pixel = s.min_distance * std::tan(s.distortion);
    return area / (pixel * pixel);
}

std::vector<Choice> evaluate(const Setting& s, double d) {
    std::vector<Choice> out;
    const double near = nearest_distance(s, d);
    const double theta = reachable_angle(d, s.radius, s.speed * s.lifetime, s.min_distance);
    const double pixel = s.display_pixel > 0 ? s.display_pixel : s.distortion;
    const double covered = kPi * std::pow(std::atan(s.radius / d) / pixel, 2.0);
    const double texture = texture_pixels(s, d);
    for (int i = 0; i < method_count; ++i) {
        Choice c;
        c.method = Method(i);
        c.polygons = polygons_needed(s, c.method, d);
        switch (c.method) {
        case Method::viewpoint_dependent: c.distortion = viewpoint_dependent_distortion(s.k, s.radius, near, c.polygons, theta); break;
        case Method::meshed_imposter:
            c.distortion = std::isfinite(c.polygons) ? meshed_imposter_distortion(s.k, s.radius, near, c.polygons, theta) : kInfinity;
            break;
        case Method::simple_imposter: c.distortion = simple_imposter_distortion(near, s.radius, theta); break;
        case Method::image_with_depth:
        case Method::layered_depth_image: c.distortion = image_with_depth_distortion(s.radius, near, theta); break;
        default: c.distortion = polygon_distortion(s.k, s.radius, near, c.polygons); break;
        }
        const bool within_polygons = s.max_polygons <= 0 || c.polygons <= s.max_polygons;
        c.feasible = std::isfinite(c.polygons) && within_polygons && c.distortion <= s.distortion * (1.0 + 1e-9);
        // geometry: the polygons (a quad for a simple imposter, none for the depth images);
        // incremental transport sends what the nearest distance needs beyond the current one
        const double drawn = c.method == Method::simple_imposter ? 2.0 : (c.method == Method::image_with_depth || c.method == Method::layered_depth_image) ? 0.0 : c.polygons;
        double sent = drawn;
        if (c.method == Method::incremental_polygons) sent = std::max(0.0, c.polygons - std::max(4.0, whole(2.0 * s.k * std::atan(s.radius / d) / s.distortion)));
        c.geometry_bytes = std::isfinite(sent) ? s.bits_per_polygon * sent / 8.0 : kInfinity;
        const double ratio = c.method == Method::simple_imposter || c.method == Method::meshed_imposter ? s.mpeg_ratio : s.jpeg_ratio;
        c.texture_bytes = texture * bytes_per_pixel(c.method) / ratio;
        c.link_bytes_per_s = (c.geometry_bytes + c.texture_bytes) / s.lifetime * refresh_chance(c.method);
        c.refreshes_per_s = refresh_chance(c.method) / s.lifetime;
        c.screen_pixels = covered;
        out.push_back(c);
    }
    return out;
}

Choice cheapest(const Setting& s, double d) {
    const std::vector<Choice> all = evaluate(s, d);
    const Choice* best = nullptr;
    for (const Choice& c : all)
        if (c.feasible && (!best || c.link_bytes_per_s < best->link_bytes_per_s)) best = &c;
    return best ? *best : all.front();
}

Switching switching_distances(const Setting& s, double max_distance) {
    // log-spaced distances from MinDist out; a threshold "from here on" is the first distance
    // after which the method stays feasible to the end of the scan
    constexpr int steps = 4000;
    std::vector<double> ds(steps + 1);
    const double lo = std::log(s.min_distance), hi = std::log(std::max(max_distance, 2.0 * s.min_distance));
    for (int i = 0; i <= steps; ++i) ds[size_t(i)] = std::exp(lo + (hi - lo) * double(i) / steps);
    auto from_here_on = [&](Method m) {
        double at = kInfinity;
        for (int i = steps; i >= 0; --i) {
            const Choice c = evaluate(s, ds[size_t(i)])[size_t(m)];
            if (!c.feasible) break;
            at = ds[size_t(i)];
        }
        return at;
    };
    Switching out;
    out.meshed_imposters_above = from_here_on(Method::meshed_imposter);
    out.simple_imposters_above = from_here_on(Method::simple_imposter);
    out.polygons_below = std::min(out.meshed_imposters_above, out.simple_imposters_above);
    // the full model: polygons needed at least max_polygons, or (unbounded) the most any
    // distance needs, which the viewer needs wherever it can reach MinDist within the lifetime
    const double most = polygons_needed(s, Method::polygons, s.min_distance);
    const double full = s.max_polygons > 0 ? std::min(s.max_polygons, most) : most;
    for (double d : ds)
        if (polygons_needed(s, Method::polygons, d) >= full) out.full_resolution_below = d;
    return out;
}

double view_angle(const Capture& c, const double eye[3]) {
    double a[3], b[3], aa = 0, bb = 0, ab = 0;
    for (int k = 0; k < 3; ++k) {
        a[k] = c.eye[k] - c.centre[k];
        b[k] = eye[k] - c.centre[k];
        aa += a[k] * a[k];
        bb += b[k] * b[k];
        ab += a[k] * b[k];
    }
    if (aa <= 0.0 || bb <= 0.0) return 0.0;
    return std::acos(std::max(-1.0, std::min(1.0, ab / std::sqrt(aa * bb))));
}

double surface_distance(const Capture& c, const double eye[3]) {
    double dd = 0;
    for (int k = 0; k < 3; ++k) dd += (eye[k] - c.centre[k]) * (eye[k] - c.centre[k]);
    return std::max(1e-9, std::sqrt(dd) - c.radius);
}

namespace {

// The capture's distortion at surface distance d and angle theta from its viewpoint.
double distortion_at(const Capture& c, double d, double theta) {
    if (theta >= kPi / 2.0) return 2.0 * std::atan(c.radius / d);  // its back: the whole object is wrong
    if (c.method == Method::meshed_imposter) return meshed_imposter_distortion(c.k, c.radius, d, c.polygons, theta);
    return simple_imposter_distortion(d, c.radius, theta);
}

} // namespace

double distortion_from(const Capture& c, const double eye[3]) { return distortion_at(c, surface_distance(c, eye), view_angle(c, eye)); }

double lifetime(const Capture& c, double d, double bound, double speed, double min_distance) {
    // the worst viewpoint after walking w: nearer by w (down to min_distance) and around by the
    // reachable angle, both growing with w, and the distortion with both
    auto worst = [&](double w) { return distortion_at(c, std::max(min_distance, d - w), reachable_angle(d, c.radius, w, min_distance)); };
    if (worst(0.0) > bound) return 0.0;
    // far enough to reach 90 degrees at min_distance: beyond it nothing changes
    const double far = (d - min_distance) + (c.radius + min_distance) * kPi;
    if (worst(far) <= bound) return kInfinity;
    double lo = 0.0, hi = far;
    for (int it = 0; it < 200 && hi - lo > 1e-5 * hi; ++it) {  // lo always within the bound
        const double mid = 0.5 * (lo + hi);
        (worst(mid) <= bound ? lo : hi) = mid;
    }
    return lo / speed;
}

} // namespace tcr::imposters
