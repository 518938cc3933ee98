#pragma once
// Pasman & Jansen's comparison of simplified polygon objects with image-based imposters
// (../shared/papers/pasman-jansen-simplification-vs-imposters.txt, sections 4 and 5): each
// representation's visual distortion, the polygons it needs for a distortion bound, the angle
// the viewer can walk around an object within a lifetime, the texture it needs, its bytes, and
// the load on the link. Angles in radians, lengths in metres, times in seconds. `d` is always
// the distance from the viewer to the object's surface, `r` the object's radius.
// Part of tom::tcr.

#include <cstdint>
#include <string>
#include <vector>

namespace tcr::imposters {

/// The representations the paper compares.
enum class Method {
    polygons,              ///< a simplified polygon model, sent whole at each refresh
    incremental_polygons,  ///< the same, sent as the difference to the model already there
    viewpoint_dependent,   ///< polygons simplified for the current viewpoint (4.2)
    meshed_imposter,       ///< the object's image over a coarse depth mesh (4.4)
    simple_imposter,       ///< the object's image on one quad facing the viewer (4.3)
    image_with_depth,      ///< an image with a depth per pixel (4.5)
    layered_depth_image,   ///< several colour+depth pairs per pixel (4.6)
};
constexpr int method_count = 7;
const char* to_string(Method m);

// --- distortion (section 4) -------------------------------------------------------------------

/// Polygon simplification, D = k/N made visual: 2 k atan(r/d) / N.
double polygon_distortion(double k, double r, double d, double n);
/// Viewpoint-dependent simplification at angle `theta` from the optimal viewpoint:
/// (21 - 19 cos 2 theta) k atan(r/d) / (2 N). (Section 4.2 prints the numerator with 2k for k
/// and without the 1/4 of its derivation, a front-view factor of 0.5 growing to 10 at the side;
/// Table 1 inverts this form, which is the derivation's.)
double viewpoint_dependent_distortion(double k, double r, double d, double n, double theta);
/// The parallax of a point `e` in front of (`behind` false) or behind a flat imposter at
/// `imposter_distance` from a viewer `theta` off the optimal viewpoint (4.3): asin(e sin theta / d_e).
double parallax(double e, double imposter_distance, double theta, bool behind);
/// gamma_min of 4.3: the least over the imposter's placement of the larger parallax of the
/// object's front and back (closed form of gamma_f = gamma_b).
double gamma_min(double d, double r, double theta);
/// A simple imposter, weighing the missing back face (the object's whole angle) and the front's
/// parallax by their areas: (1 - cos 2 theta) atan(r/d) + (1 + cos 2 theta) gamma_min / 2.
double simple_imposter_distortion(double d, double r, double theta);
/// A meshed imposter of N polygons: ((1 - cos 2 theta) + (1 + cos 2 theta) k sin(theta) / (2N)) 2 atan(r/d).
double meshed_imposter_distortion(double k, double r, double d, double n, double theta);
/// Images with depth and layered depth images: (1 - cos 2 theta) atan(r/d).
double image_with_depth_distortion(double r, double d, double theta);

// --- lifetime (section 5.2) -------------------------------------------------------------------

/// The angle around the object that a viewer at distance `d` can walk in `walk` metres (v T),
/// going no nearer than `min_distance`.
double reachable_angle(double d, double r, double walk, double min_distance);

/// A viewing situation: an object, a viewer, the bound and the costs of section 5.
struct Setting {
    double radius = 1.0;           ///< r, metres
    double k = 5.0;                ///< the object's D_rel = k / N
    double distortion = 0.001;     ///< D, radians (1 mrad: about a pixel of 640 x 480 at 40 degrees)
    double speed = 1.0;            ///< v, metres per second
    double lifetime = 1.0;         ///< T, seconds a representation must last
    double min_distance = 0.2;     ///< MinDist, metres
    double max_polygons = 0;       ///< the full model's polygons (0: as many as needed)
    double bits_per_polygon = 25;  ///< 5.3: 4 bits of connectivity + 3 x 42 / 6 of vertices
    double jpeg_ratio = 20, mpeg_ratio = 75;  ///< texture compression (5.4): rare refreshes, frequent ones
    double display_pixel = 0;      ///< radians per pixel, for the covered pixels (0: the distortion)
};

/// The paper's Figure 11 setting: r = 1 m, D = 1 mrad, MinDist = 0.2 m, v = 1 m/s, k = 5, T = 1 s.
Setting paper_example();

// --- inversion, sizes and loads (section 5) ---------------------------------------------------

/// The nearest the viewer gets within the lifetime: max(MinDist, d - v T).
double nearest_distance(const Setting& s, double d);
/// Table 1: the polygons `m` needs to stay within the distortion bound at distance d (at least 4;
/// 1 for the image methods); infinity where no polygon count does (a meshed imposter whose
/// missing back face alone exceeds the bound).
double polygons_needed(const Setting& s, Method m, double d);
/// FarTextureSize: (2 atan(r/d) / D)^2 pixels.
double far_texture_pixels(const Setting& s, double d);
/// TextureSize(r, v, T) of 5.4, in pixels: FarTextureSize at the nearest distance, or, when the
/// viewer can reach MinDist, the pixels of the surface it can scan from there (vispixels).
double texture_pixels(const Setting& s, double d);
/// d_0 of 5.4: the extra scanning distance that joins vispixels to FarTextureSize at MinDist.
double scan_extension(const Setting& s);

/// One representation at one distance.
struct Choice {
    Method method;
    bool feasible = false;       ///< the bound can be met (and, with max_polygons, within them)
    double distortion = 0;       ///< with the polygons below, at the nearest distance in the lifetime
    double polygons = 0;         ///< Table 1 (the geometry drawn)
    double geometry_bytes = 0;   ///< bits_per_polygon x polygons / 8 (incremental: the difference)
    double texture_bytes = 0;    ///< texture pixels x bytes per pixel / compression
    double link_bytes_per_s = 0; ///< (geometry + texture) / T x the chance a refresh is needed (1/6 or 5/6)
    double refreshes_per_s = 0;  ///< renders of the object into its texture (imposters), or loads
    double screen_pixels = 0;    ///< the object's disc on screen (the render load, alike for all: 6.2)
};

/// Every method at distance d.
std::vector<Choice> evaluate(const Setting& s, double d);
/// The feasible choice of least link load at distance d (polygons when none is).
Choice cheapest(const Setting& s, double d);

/// Where the choice changes, scanning distance from MinDist outwards.
struct Switching {
    double full_resolution_below = 0;  ///< the full model (or the most polygons any distance needs) below this
    double polygons_below = 0;         ///< no imposter meets the bound nearer than this
    double meshed_imposters_above = 0; ///< a meshed imposter meets it from here on
    double simple_imposters_above = 0; ///< a simple imposter meets it from here on (infinity if never within max_distance)
};
Switching switching_distances(const Setting& s, double max_distance = 1000.0);

// --- reuse of a captured imposter (sections 4.3, 4.4 and 5.2 turned around) -----------------------

/// An imposter of an object (centre, radius) captured from a viewpoint: a simple imposter, or a
/// meshed one over a depth mesh of `polygons` polygons.
struct Capture {
    Method method = Method::simple_imposter;  ///< simple_imposter or meshed_imposter
    double eye[3] = {0, 0, 0};                ///< the viewpoint it was rendered from
    double centre[3] = {0, 0, 0};
    double radius = 1.0;
    double polygons = 2;                      ///< the depth mesh's polygons (meshed imposters)
    double k = 5.0;                           ///< the object's D_rel = k / N, for the depth mesh
};

/// theta of section 4: the angle at the object's centre between the capture's viewpoint and `eye`.
double view_angle(const Capture& c, const double eye[3]);
/// The distance from `eye` to the object's surface (its sphere), at least 1e-9.
double surface_distance(const Capture& c, const double eye[3]);
/// The capture seen from `eye`: its distortion (4.3 or 4.4) at theta = view_angle and the
/// current surface distance; beyond 90 degrees the imposter shows its back, the whole angle.
double distortion_from(const Capture& c, const double eye[3]);
/// How long the capture lasts for a viewer at surface distance d walking at `speed`: the least
/// time after which the worst viewpoint it can reach (section 5.2: nearer by the distance
/// walked, down to min_distance, and around by reachable_angle) sees more than `bound`. 0 when
/// even the capture's own viewpoint does; infinity when no walk ever does.
double lifetime(const Capture& c, double d, double bound, double speed, double min_distance);

} // namespace tcr::imposters
