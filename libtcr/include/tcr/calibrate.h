#pragma once
// Calibration: fits the cost model (tcr/model.h) to the engine's own renderer by timing frames
// it draws (Funkhouser & Sequin's and Gobbetti & Bouvier's procedure: time sample objects at
// several sizes and resolutions, fit the per-draw, per-triangle, per-vertex and per-pixel
// costs by least squares). The engine supplies the drawing and the clock, a
// CalibrationRenderer; calibrate() chooses the frames, reads the times and fits.
//
//   struct MyTimer : tcr::CalibrationRenderer { ...time_frame: draw, glFinish, return ms... };
//   MyTimer timer(...);                            // the engine's meshes uploaded in this order
//   tcr::CalibrationParams p;  p.path = "my.calibration";
//   const tcr::Calibration c = tcr::calibrate(timer, {&mesh_a, &mesh_b}, p);
//   tcr::Runtime rt(c.model, tcr::SelectorKind::exact);
//
// What is timed: an empty frame (t_init + t_final, the safety allowance from its spread); 5
// levels x 3 distances x 8 copies plus two frames of 64 small copies of each of up to 4 meshes,
// each frame repeated toward 100,000 triangles (the geometry terms); one heavy frame 61 times
// (the frame-to-frame noise); the same draws flat-shaded and texture-mapped, when the renderer
// draws those ways; and, when it has imposters, refreshes into textures, imposter quads of five
// sizes and depth-mesh draws of two grids.

#include <cstdint>
#include <string>
#include <vector>

#include "tcr/model.h"
#include "tcr/runtime.h"
#include "tcr/view.h"
#include "tom/view.h"

namespace tcr {

/// One draw of a calibration frame: a level of one of calibrate()'s meshes, placed.
struct CalibrationDraw {
    uint32_t mesh = 0;                  ///< index into calibrate()'s meshes
    const uint32_t* indices = nullptr;  ///< the level's triangles, indices into that mesh's vertices
    uint32_t index_count = 0;
    float model[16] = {};               ///< object to world, column-major
};

/// A render of a draw into an imposter's texture slot, before the frame.
struct CalibrationCapture {
    uint32_t slot = 0;                  ///< the texture slot, 0 to 47
    uint32_t side = 64;                 ///< texels a side: 64 or 256
    float view[16] = {}, projection[16] = {};
    uint32_t grid = 0;                  ///< > 0: a meshed imposter's capture: its depth read back into grid x grid cells
    CalibrationDraw draw;
};

/// An imposter drawn in the frame: a simple one's textured quad at `corners`, or a meshed one's
/// depth mesh where its slot was captured.
struct CalibrationImposter {
    uint32_t slot = 0;
    bool meshed = false;
    float corners[12] = {};             ///< simple: world corners of texture (0,0), (1,0), (1,1), (0,1)
};

/// The engine's side of calibration: its renderer, with the meshes given to calibrate()
/// uploaded, and its clock. Every call draws one cleared frame, waits until it is finished (as
/// a frame is finished in the engine: glFinish, a fence) and returns the milliseconds from the
/// call's start; a time < 0 says the renderer does not draw that way, and the model's
/// coefficients for it stay 0 (the runtime then never offers it).
class CalibrationRenderer {
public:
    virtual ~CalibrationRenderer() = default;
    virtual uint32_t width() const = 0;   ///< the viewport the engine renders, pixels
    virtual uint32_t height() const = 0;
    /// `draws` in order, each set up on its own, shaded `way`: Representation::smooth (Gouraud,
    /// required), flat, or textured (any texture bound: a fetch costs the same whatever the
    /// picture). An empty `draws` is the empty frame.
    virtual double time_frame(const Camera& camera, const std::vector<CalibrationDraw>& draws, Representation way) = 0;
    /// Renders `captures` into their slots (smooth-shaded), then draws `imposters` into the frame.
    virtual double time_imposters(const Camera& camera, const std::vector<CalibrationCapture>& captures,
                                  const std::vector<CalibrationImposter>& imposters) {
        (void)camera, (void)captures, (void)imposters;
        return -1;
    }
};

struct CalibrationParams {
    uint32_t max_meshes = 4;               ///< meshes timed for the geometry fit (the ways use the first two)
    double triangles_per_frame = 100000;   ///< a sample frame repeats its draws toward this many triangles
    std::string path;                      ///< when not empty, the model is written there (write_cost_model)
    std::string comment;                   ///< the file's first comment line (what was calibrated)
};

struct Calibration {
    CostModel model;
    CalibrationResult fit;          ///< the smooth-shaded geometry fit
    size_t samples = 0;             ///< smooth-shaded sample frames fitted
    double empty_ms = 0;            ///< the empty frame, median
    double noise_overall = 0;       ///< the heavy frame's relative standard deviation (model.noise_rel: frame to frame)
    std::string summary;            ///< what was measured and fitted, for a log (lines ending in '\n')
};

/// Times `renderer` on `meshes` (their levels, scaled to diagonal 1, in a 60-degree view down
/// -z from the origin) and fits the cost model; writes it to params.path when given.
/// \throw tom::ArgumentError when `meshes` is empty or holds a null, or the renderer does not
/// draw smooth-shaded; tom::IoError when params.path cannot be written.
Calibration calibrate(CalibrationRenderer& renderer, const std::vector<const tom::MeshView*>& meshes, const CalibrationParams& params = {});

} // namespace tcr
