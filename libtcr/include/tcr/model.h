#pragma once
// Frame cost model of time-critical rendering (Funkhouser & Sequin 1993; Gobbetti & Bouvier 1999):
//   frame = t_init + t_final + sum_i (draws_i t_setup + max((t_tri * tris_i + t_vert * verts_i) * inside_i, t_pix * pixels_i)) + safety
// (inside_i: the share of object i inside the view frustum, 1 for calibration's whole objects;
// draws_i: its parts, one draw set-up each, as a multi-material mesh is drawn)
// All times in milliseconds.

#include <cstddef>
#include <string>
#include <vector>

namespace tcr {

struct CostModel {
    double t_init_ms = 0.0;   ///< per frame, before the objects
    double t_final_ms = 0.0;  ///< per frame, after the objects (swap, read-back)
    double t_setup_ms = 0.0;  ///< per draw (one per drawn object, or per part of a multi-part one)
    double t_tri_ms = 0.0;    ///< per triangle
    double t_vert_ms = 0.0;   ///< per vertex
    double t_pix_ms = 0.0;    ///< per covered pixel
    double safety_ms = 0.0;   ///< allowance for the system's own noise
    double noise_rel = 0.0;   ///< measured relative variation of identical frames, frame to frame (informational; 0 unknown)
    // The other ways to draw an object (Funkhouser & Sequin's rendering algorithms, Pasman &
    // Jansen's imposters), each calibrated on its own; 0 where not calibrated, and a runtime
    // offers no way whose coefficients are all 0.
    double flat_t_tri_ms = 0.0;     ///< flat shading: per triangle (its set-up is t_setup)
    double flat_t_vert_ms = 0.0;    ///< flat shading: per vertex
    double flat_t_pix_ms = 0.0;     ///< flat shading: per covered pixel
    double textured_t_tri_ms = 0.0;   ///< texture mapping (Gouraud-lit, modulated by the texture): per triangle
    double textured_t_vert_ms = 0.0;  ///< texture mapping: per vertex
    double textured_t_pix_ms = 0.0;   ///< texture mapping: per covered pixel
    double imposter_t_setup_ms = 0.0;  ///< a simple imposter: its textured quad's draw
    double imposter_t_pix_ms = 0.0;    ///< a simple imposter: per covered pixel (texture fetch, alpha test)
    double refresh_t_setup_ms = 0.0;   ///< an imposter's refresh: binding its texture as the target, clearing it, the draw
    double meshed_t_tri_ms = 0.0;      ///< a meshed imposter: per triangle of its depth mesh, beyond the quad's draw and fill
    double meshed_refresh_t_setup_ms = 0.0;  ///< a meshed imposter's refresh beyond a simple one's: the depth read back, the mesh made

    /// Time of one object: t_setup + max(geometry, fill). `inside_share`: the share of the object
    /// inside the view frustum (Projection::inside_share); the rest is clipped before set-up and
    /// rasterisation, so the geometry term counts only that share. `draws`: the object's parts,
    /// one set-up each.
    double object_ms(double triangles, double vertices, double pixels, double inside_share = 1.0, double draws = 1.0) const noexcept {
        const double geometry = (t_tri_ms * triangles + t_vert_ms * vertices) * inside_share;
        const double fill = t_pix_ms * pixels;
        return t_setup_ms * draws + (geometry > fill ? geometry : fill);
    }
    /// Time of one object drawn flat-shaded (as object_ms, with the flat coefficients).
    double flat_ms(double triangles, double vertices, double pixels, double inside_share = 1.0, double draws = 1.0) const noexcept {
        const double geometry = (flat_t_tri_ms * triangles + flat_t_vert_ms * vertices) * inside_share;
        const double fill = flat_t_pix_ms * pixels;
        return t_setup_ms * draws + (geometry > fill ? geometry : fill);
    }
    /// Time of one object drawn texture-mapped (as object_ms, with the texture-mapping coefficients).
    double textured_ms(double triangles, double vertices, double pixels, double inside_share = 1.0, double draws = 1.0) const noexcept {
        const double geometry = (textured_t_tri_ms * triangles + textured_t_vert_ms * vertices) * inside_share;
        const double fill = textured_t_pix_ms * pixels;
        return t_setup_ms * draws + (geometry > fill ? geometry : fill);
    }
    /// Time of one simple imposter's quad covering `pixels`.
    double imposter_ms(double pixels) const noexcept { return imposter_t_setup_ms + imposter_t_pix_ms * pixels; }
    /// Time of one meshed imposter covering `pixels` over a depth mesh of `triangles`.
    double meshed_ms(double pixels, double triangles) const noexcept { return imposter_ms(pixels) + meshed_t_tri_ms * triangles; }
    /// Time of one refresh: the object at (triangles, vertices), whole, into a texture of `texels`;
    /// texture-mapped when `textured` and texture mapping is calibrated, else smooth-shaded.
    double refresh_ms(double triangles, double vertices, double texels, double draws = 1.0, bool textured = false) const noexcept {
        const bool mapped = textured && has_textured();
        return refresh_t_setup_ms + (mapped ? textured_ms(triangles, vertices, texels, 1.0, draws) : object_ms(triangles, vertices, texels, 1.0, draws));
    }
    bool has_flat() const noexcept { return flat_t_tri_ms > 0 || flat_t_vert_ms > 0 || flat_t_pix_ms > 0; }
    bool has_textured() const noexcept { return textured_t_tri_ms > 0 || textured_t_vert_ms > 0 || textured_t_pix_ms > 0; }
    bool has_imposters() const noexcept { return imposter_t_setup_ms > 0 || imposter_t_pix_ms > 0; }
    bool has_meshed() const noexcept { return has_imposters() && (meshed_t_tri_ms > 0 || meshed_refresh_t_setup_ms > 0); }
    /// Fixed part of a frame: t_init + t_final + safety.
    double frame_fixed_ms() const noexcept { return t_init_ms + t_final_ms + safety_ms; }
    /// Fewer triangles than this save no time: the object is fill bound (r_min of the sources).
    double min_useful_triangles(double pixels, double vertices_per_triangle = 0.5) const noexcept {
        const double per_tri = t_tri_ms + t_vert_ms * vertices_per_triangle;
        return per_tri > 0 ? t_pix_ms * pixels / per_tri : 0.0;
    }
};

/// One timed draw of one object (or a frame of one object) used for calibration.
struct CostSample {
    double triangles = 0, vertices = 0, pixels = 0;
    double time_ms = 0;  ///< measured time of the draw, including per-object setup
};

struct CalibrationResult {
    CostModel model;
    double rms_error_ms = 0;        ///< root mean square residual over the samples
    double mean_relative_error = 0; ///< mean |predicted - measured| / measured
    size_t geometry_bound = 0;      ///< samples the fit classed geometry bound
    size_t fill_bound = 0;
};

/// Fits t_setup, t_tri, t_vert and t_pix to samples by least squares on relative errors (each
/// sample weighted by 1 / its time) on the model
/// t = t_setup + max(t_tri*T + t_vert*V, t_pix*P): alternates between classifying each sample
/// as geometry or fill bound and solving the linear least-squares problem of that split
/// (all coefficients clamped to >= 0), until the split stops changing.
/// \pre at least 4 samples with varied triangle and pixel counts.
CalibrationResult fit_cost_model(const std::vector<CostSample>& samples);

/// Reads and writes the calibration file (format documented in docs/CALIBRATION.md):
/// text lines "key value" with keys t_init_ms, t_final_ms, t_setup_ms, t_tri_ms, t_vert_ms,
/// t_pix_ms, safety_ms, noise_rel; '#' starts a comment. \throw tom::ParseError naming file and line, tom::IoError when unreadable.
CostModel read_cost_model(const std::string& path);
void write_cost_model(const std::string& path, const CostModel& model, const std::string& comment = "");

} // namespace tcr
