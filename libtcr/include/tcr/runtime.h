#pragma once
// The engine-facing runtime: a scene of TOM meshes with transforms and weights; per frame the
// camera, the budget and the measured time of the previous frame; back, per object, the chosen
// resolution and its index buffer, plus the frame's prediction and certificate.
//
//   tcr::Runtime rt(tcr::read_cost_model("calibration.txt"), tcr::SelectorKind::exact);
//   uint32_t id = rt.add_object(file.mesh(0), transform, 1.0f);
//   ...each frame:
//   tcr::FrameParams f; f.camera = ...; f.budget_ms = 16.0; f.previous_frame_ms = measured;
//   const tcr::FrameReport& r = rt.plan_frame(f);
//   for each object: if (rt.object(id).drawn) { auto e = rt.indices(id, buffer, capacity); draw(...); }
//
// Benefit (Funkhouser & Sequin; Gobbetti & Bouvier): importance = coverage (pixels) x focus x
// weight (x motion); accuracy(n) = 1 - e(n), e(n) = c n^-m x size_px the projected error in
// pixels, c fitted to the mesh's stored error curve for the exponent m (the relative error
// D(n) = c n^-m), or `fixed_c` when the file has none. Cost: the calibrated CostModel, its
// objects' part scaled by a correction that follows the measured time of previous frames
// (an exponential average of measured / predicted, within [0.5, 2]), so slow drifts of the
// renderer (fill growing as objects come close, a busier machine) do not break the budget.

#include <cstdint>
#include <vector>

#include "tcr/model.h"
#include "tcr/select.h"
#include "tcr/view.h"
#include "tom/extract.h"
#include "tom/view.h"

namespace tcr {

/// How an object is drawn (Funkhouser & Sequin's rendering algorithms: Gouraud-shaded, flat-shaded,
/// texture-mapped; Pasman & Jansen's simple imposter: the object rendered into a texture from one
/// viewpoint, drawn as one quad facing it; their meshed imposter: the same image over a coarse
/// mesh of the capture's depth buffer).
enum class Representation : uint8_t { smooth, flat, simple_imposter, meshed_imposter, textured };
inline bool is_imposter(Representation r) noexcept { return r == Representation::simple_imposter || r == Representation::meshed_imposter; }
const char* representation_name(Representation r) noexcept;

/// The menu a frame offers beside the TOM levels drawn smooth-shaded (way 0). A way is offered
/// only where the cost model has its coefficients (CostModel::has_flat, has_imposters), and
/// only the exact and greedy selectors choose among ways; the others keep way 0.
struct Menu {
    bool flat = false;                ///< flat shading, every level
    bool textured = false;            ///< texture mapping, every level, for objects that have a texture (Runtime::set_textured)
    bool imposters = false;           ///< simple imposters, for objects whose sphere the eye is well outside
    bool meshed = false;              ///< meshed imposters too, where the cost model has them (CostModel::has_meshed)
    /// A meshed imposter's depth mesh: a grid of this many cells a side over the capture, two
    /// triangles a cell (8: 128 triangles, as Pasman & Jansen's Table 1 asks of a 1 m object at
    /// 15 m for a 1 mrad bound and a 1 s lifetime).
    uint32_t meshed_grid = 8;
    double meshed_k = 5.0;            ///< the depth mesh's k of D = k / N (4.4; the paper's k: a grid fits no better than a simplification)
    /// Flat shading's projected error as a multiple of smooth shading's at the same level: its
    /// facets show the level's approximation (Funkhouser's flat m = 1 in polygons against
    /// Gouraud's m = 2 in vertices); fitted to the measured image by tcrwalk (docs/CALIBRATION.md).
    double flat_error_factor = 2.0;
    /// Texture mapping's projected error as a multiple of smooth shading's at the same level: the
    /// texture shows the surface detail that the level's geometry and its plain colour do not
    /// (Funkhouser's textured benefit above Gouraud's); below 1.
    double textured_error_factor = 0.5;
    double imposter_max_px = 1.0;     ///< a capture is reused while its distortion (Pasman & Jansen 4.3) stays within this
    /// An imposter's projected error (captured level + distortion + magnification) as it weighs
    /// in the benefit: a billboard also loses the object's parallax and lighting between
    /// captures, which the geometric error does not see (fitted to the measured image, TCR.md).
    double imposter_error_factor = 1.0;
    double refresh_share = 0.25;      ///< a frame renews at most what this share of the budget pays for, beyond the spread cost
    double capture_error_px = 0.1;    ///< a refresh renders the object at the level of this projected error (low: its cost is spread over the lifetime)
    uint32_t texture_max = 256;       ///< the largest texture side (power of two), texels
    uint32_t texture_min = 16;
    double min_distance_radii = 8.0;  ///< no imposter nearer than this many radii from the object's centre
    double max_lifetime_frames = 60;  ///< a refresh's cost is spread over at most this many frames of its lifetime
    double viewer_speed = -1;         ///< m/s for the lifetimes; < 0: from the camera's motion between frames
    double frame_interval_s = 0;      ///< seconds between frames for the lifetimes (0: the budget)
};

struct FrameParams {
    Camera camera;
    double budget_ms = 16.0;         ///< the whole frame
    double previous_frame_ms = 0;    ///< measured time of the last frame (stress selector, model correction); 0 if unknown
    bool correct_model = true;       ///< scale the objects' modelled cost by the recent measured / modelled factor
    double deadline_ms = 0;          ///< optimiser deadline (barrier, exact); 0 for none
    double m = 1.0;                  ///< accuracy exponent: 0.5, 1 or 2
    double hysteresis = 0.0;         ///< relative dead band against the previous frame's choice
    double max_error_px = 0;         ///< cap: no object gets more triangles than it needs for this error (0: no cap)
    bool error_bounded = false;      ///< ignore the budget: each object gets the smallest resolution within max_error_px
    bool use_motion = false;         ///< scale importance by Funkhouser's motion factor
    float focus_weight = 0.5f;       ///< focus factor weight (0: no focus)
    double fixed_c = 1.0;            ///< relative error constant for meshes without a stored curve (Pasman's k ~ 1)
    double triangles_per_pixel = 0.5;  ///< static and stress selectors
    OverBudgetPolicy policy = OverBudgetPolicy::drop_least_valuable;
    Menu menu;                       ///< the other ways to draw (default: none, levels only)
};

/// An object's imposter: the viewpoint and the sphere it was captured for, its texture side and
/// the level rendered into it. The renderer keeps the texture; the runtime decides when it is
/// renewed (ObjectResult::refresh) and fills this in for it.
struct ImposterState {
    bool valid = false;
    float eye[3] = {0, 0, 0}, centre[3] = {0, 0, 0};
    float radius = 0;
    uint32_t texture_px = 0;   ///< side of the square texture
    uint32_t grid = 0;         ///< a meshed imposter's depth mesh, cells a side; 0: a simple imposter
    uint32_t vertices = 0;     ///< the level rendered into it
    uint32_t triangles = 0;    ///< that level's triangles
    uint64_t frame = 0;        ///< the frame it was captured in
};
/// The camera of a capture: from its eye toward its centre, a square frustum just holding the
/// sphere (near and far planes at its front and back). Column-major, as tcr::look_at.
void imposter_camera(const ImposterState& s, float view[16], float projection[16]) noexcept;
/// The quad of a simple imposter: the capture's frustum cut at the centre's plane, facing the
/// capture's eye (Pasman & Jansen's two-axis billboard), corners in world space (4 x xyz;
/// texture corners (0,0), (1,0), (1,1), (0,1) in that order).
void imposter_quad(const ImposterState& s, float corners[12]) noexcept;
/// A meshed imposter's depth mesh: (grid + 1)^2 vertices, row by row from the bottom left, in
/// world space (xyz each), vertex (i, j) on the capture's ray through texture point (i, j) / grid
/// at the depth of the object texel nearest that point in the image (`depth`: side x side window
/// depths in [0, 1], 1 for none, rows from the bottom, as glReadPixels gives them) within one
/// cell: inside the object its own depth, at its outline the outline's, never the far plane (the
/// paper's stretched edges, section 6.2; the nearest depth instead would pull the outline forward
/// and exaggerate its parallax). Where no texel within a cell holds the object, at the depth of
/// the capture's centre, as a simple imposter's quad. `view` and `projection` are the capture's
/// (imposter_camera). Texture coordinates are (i, j) / grid. A grid of 0 gives one vertex, the
/// capture's centre (a mesh with no triangles).
void depth_mesh(const float view[16], const float projection[16], const float* depth, uint32_t side, uint32_t grid, float* positions) noexcept;

struct ObjectResult {
    bool visible = false;
    bool drawn = false;
    uint32_t vertices = 0;      ///< the resolution to draw: vertices [0, vertices)
    uint32_t triangles = 0;     ///< its active triangles
    float coverage_px = 0, size_px = 0, focus = 1;
    float distance = 0;         ///< eye-space distance to the box centre
    float inside_share = 1;     ///< share of the box inside the view frustum (its geometry cost scales with it)
    double importance = 0;
    double error_px = 0;        ///< projected error at the chosen resolution, as max_error_px bounds it: the stored curve (or Pasman's 2 k arctan(r/d) / N) in pixels
    double predicted_ms = 0;
    Representation representation = Representation::smooth;
    /// An imposter renewed this frame: render the level `vertices` into its texture from
    /// Runtime::imposter(id) (indices() gives that level), and for a meshed one make its depth
    /// mesh (depth_mesh), before drawing it. An imposter not renewed draws its quad or depth
    /// mesh alone (indices() gives nothing).
    bool refresh = false;
};

struct FrameReport {
    double predicted_ms = 0;    ///< t_init + t_final + safety + the drawn objects at their chosen resolutions
    double benefit = 0;         ///< of the continuous plan
    double upper_bound = 0;     ///< certified bound on the benefit of any plan of the same objects (NaN: none)
    double gap = 0;             ///< relative distance to the optimum, certified (NaN: the selector gives none)
    double max_error_px = 0;    ///< largest projected error among drawn objects
    uint32_t visible = 0, drawn = 0;
    uint64_t triangles = 0, visible_triangles = 0;  ///< drawn at the chosen resolutions; the visible ones at full
    double cull_ms = 0, optimize_ms = 0;
    double stress = 1.0;        ///< the stress selector's factor after this frame's update
    double correction = 1.0;    ///< the model correction applied to the objects' cost this frame
    bool feasible = true;
    bool deadline_hit = false;
    uint32_t iterations = 0;
    uint32_t flat = 0, imposters = 0, refreshes = 0;  ///< drawn flat-shaded; drawn as imposters (simple or meshed); of those, renewed
    uint32_t textured = 0;      ///< drawn texture-mapped
    uint32_t meshed = 0;        ///< of the imposters, meshed ones
};

class Runtime {
public:
    Runtime(const CostModel& model, SelectorKind selector);

    /// Adds an object. `mesh` (and the File it comes from) must outlive the runtime. Its levels
    /// go down to the mesh's usable floor, or with Floor::coarsest to its chain's last level.
    /// \return its id, 0, 1, 2, ... in order of addition.
    uint32_t add_object(const tom::MeshView& mesh, const float transform[16], float weight = 1.0f, tom::Floor floor = tom::Floor::usable);
    /// \pre id < object_count() (asserted), as for every call taking an object's id.
    void set_transform(uint32_t id, const float transform[16]) noexcept;
    void set_weight(uint32_t id, float weight) noexcept;
    /// Whether object `id` has a texture to be drawn with (its mesh's texture coordinates and a
    /// material's image, which the renderer holds): only such objects are offered texture mapping,
    /// and their imposters' captures, drawn texture-mapped, are costed so (CostModel::refresh_ms).
    void set_textured(uint32_t id, bool textured) noexcept { objects_[id].textured = textured; }
    void set_selector(SelectorKind selector) noexcept { selector_ = selector; }
    SelectorKind selector() const noexcept { return selector_; }
    void set_cost_model(const CostModel& model) noexcept { model_ = model; }
    const CostModel& cost_model() const noexcept { return model_; }
    size_t object_count() const noexcept { return objects_.size(); }

    /// Culls, measures, selects. Allocates nothing once the scene has been planned once.
    const FrameReport& plan_frame(const FrameParams& params);
    const ObjectResult& object(uint32_t id) const noexcept { return results_[id]; }
    const ImposterState& imposter(uint32_t id) const noexcept { return objects_[id].imposter; }
    /// Forgets every capture (the renderer lost its textures, the scene was reloaded).
    void clear_imposters() noexcept;
    const FrameReport& last_frame() const noexcept { return report_; }

    /// The chosen level's index buffer (nothing written for an object not drawn).
    tom::Extracted indices(uint32_t id, uint32_t* destination, size_t capacity) const noexcept;
    tom::Extracted indices(uint32_t id, uint16_t* destination, size_t capacity) const noexcept;
    /// The same, with where each part's triangles went: `draws` holds tom::part_count(mesh)
    /// entries (one draw per part, each with its material; empty ones for an object not drawn).
    tom::Extracted indices(uint32_t id, uint32_t* destination, size_t capacity, tom::PartDraw* draws) const noexcept;

    /// Projected error in pixels of object `id` at `triangles`, for its last projection.
    double error_px(uint32_t id, double triangles, double m) const noexcept;
    /// The smallest resolution whose projected error is at most `max_error_px` (error-bounded
    /// mode): from the stored error curve, or Pasman's 2 k arctan(r/d) / N with k = fixed_c.
    double triangles_for_error(uint32_t id, double max_error_px) const noexcept;

private:
    struct Object {
        const tom::MeshView* mesh;
        float transform[16];
        float weight;
        bool textured = false;
        Box box;
        uint32_t min_vertices;  // its floor (tom::floor_vertex_count)
        double triangles, min_triangles, vertices_per_triangle;
        bool has_curve;
        std::vector<double> curve_tris, curve_error;  // the stored curve (relative error), for error-bounded mode
        double c_by_m[3];                              // relative error constant fitted for m = 0.5, 1, 2
        double diagonal;                               // object-space bounding-box diagonal
        float last_x = -1, last_y = -1;                // previous frame's screen position (motion)
        ImposterState imposter;                        // the last capture
        // how far the viewer walks before a capture from here breaks its bound (simple, meshed),
        // the distance and the depth mesh's grid it was computed for
        double lifetime_distance = -1, lifetime_m[2] = {0, 0};
        uint32_t lifetime_grid = 0;
        // the level a capture renders, for the projected size and capture error it was found at
        double capture_size_px = -1, capture_error_px = -1;
        uint32_t capture_vertices = 0, capture_triangles = 0;
    };
    // One entry of a frame's menu beyond way 0: what it draws.
    struct WayKind {
        Representation representation;
        bool refresh;
        double error_px;       // imposters: the projected error
        uint32_t texture_px;   // imposters: the texture's side
        uint32_t vertices;     // imposters: the level in the texture
        uint32_t grid = 0;     // meshed imposters: the depth mesh's cells a side
        double full_ms = 0;    // refreshes: the whole cost, paid this frame
    };
    void add_ways(uint32_t id, size_t k, const FrameParams& params, double radians_per_px);
    double choose(uint32_t id, size_t k, double triangles, uint32_t way);
    void reserve_refreshes(const SelectParams& sp, double share);
    bool dominated_by_smooth(const Way& w, size_t k) const noexcept;
    uint32_t kept_capture_way(size_t k) const noexcept;
    double keep_cheapest_refreshes(double cap);
    struct Renewal { double extra; size_t k; uint32_t j; };
    std::vector<Renewal> renewals_;  // reserve_refreshes' scratch
    void repair_refreshes(double budget_ms, double& predicted);
    void note_viewer(const FrameParams& params);
    // plan_frame's steps, in order
    void cull(const FrameParams& params);
    void correct_model(const FrameParams& params);
    void build_problem(const FrameParams& params);
    void select_plan(const FrameParams& params);
    double round_to_levels(const FrameParams& params);
    void step_down(const FrameParams& params, double& predicted);
    void tally(const FrameParams& params, double predicted);
    void commit_capture(uint32_t id, uint32_t way, size_t k);
    static bool has_geometry(const ObjectResult& r) noexcept { return r.drawn && (!is_imposter(r.representation) || r.refresh); }
    double c_for(const Object& o, double m, double fixed_c) const noexcept;
    double pasman_k_px(const Object& o, const ObjectResult& r) const noexcept;
    double projected_error_px(const Object& o, const ObjectResult& r, double triangles) const noexcept;
    uint32_t resolution_for(const Object& o, double triangles) const noexcept;

    CostModel model_;
    SelectorKind selector_;
    std::vector<Object> objects_;
    std::vector<ObjectResult> results_;
    std::vector<uint32_t> visible_ids_;
    std::vector<double> coverage_;
    Problem problem_;
    Plan plan_;
    FrameReport report_;
    double stress_ = 1.0;
    double correction_ = 1.0;   // EMA of the factor (measured / model) for the objects' part of the frame
    double last_predicted_ms_ = 0;
    double last_fixed_c_ = 1.0;
    Camera last_camera_{};
    std::vector<WayKind> way_kinds_;  // parallel to problem_.ways
    uint64_t frame_ = 0;
    double eye_[3] = {0, 0, 0}, last_eye_[3] = {0, 0, 0};
    double speed_ = 0;                // the viewer's speed, m/s (estimated or given)
    bool have_eye_ = false;
};

} // namespace tcr
