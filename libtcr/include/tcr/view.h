#pragma once
// Visibility and screen size of an object's bounding box (Funkhouser & Sequin 1993; Gobbetti &
// Bouvier 1999): view-frustum culling, projected coverage in pixels, focus (distance of the
// projection from the screen centre) and an optional motion factor.

#include <cstdint>

namespace tcr {

/// Matrices are 4x4, column-major (OpenGL convention): element (row r, column c) is m[c * 4 + r].
struct Camera {
    float view[16];          ///< world -> eye
    float projection[16];    ///< eye -> clip (perspective or orthographic)
    uint32_t viewport_width = 1;
    uint32_t viewport_height = 1;
};

/// A bounding box in object space and the object's transform (object -> world).
struct Box {
    float min[3];
    float max[3];
};

/// What the camera sees of one box.
struct Projection {
    bool visible = false;     ///< false: entirely outside one frustum plane
    float coverage_px = 0;    ///< area of the projected box's screen rectangle, clipped to the viewport
    float size_px = 0;        ///< diagonal of that rectangle: the object's projected size
    float center_x = 0, center_y = 0;  ///< rectangle centre, pixels from the top-left corner
    float focus = 1;          ///< 1 at the screen centre, 1 - focus_weight at a corner
    float distance = 0;       ///< eye-space distance to the box centre (object units x scale)
    /// Share of the box inside the view frustum: of its 4 x 4 x 4 equal sub-boxes, those not
    /// entirely outside one frustum plane (1 when the whole box is inside, at least 1/64 when it
    /// is visible, 0 when culled). What lies outside is clipped before set-up and rasterisation,
    /// so it costs little (tcr::CostModel::object_ms).
    float inside_share = 0;
};

/// Projects `box` transformed by `model` (object -> world). A box crossing the eye plane counts
/// as covering the whole viewport. `focus_weight` in [0, 1] (Funkhouser's focus factor).
Projection project_box(const Camera& camera, const float model[16], const Box& box, float focus_weight = 0.5f) noexcept;

/// Funkhouser's motion-blur factor: 1 for a still object, falling as its projection moves
/// `moved_px` pixels since the previous frame: 1 / (1 + moved_px / scale_px).
inline float motion_factor(float moved_px, float scale_px = 32.0f) noexcept { return 1.0f / (1.0f + moved_px / scale_px); }

/// Matrix helpers (column-major): a perspective projection (vertical field of view in radians)
/// and a look-at view matrix, as gluPerspective and gluLookAt.
void perspective(float fov_y, float aspect, float z_near, float z_far, float out[16]) noexcept;
void look_at(const float eye[3], const float target[3], const float up[3], float out[16]) noexcept;
void multiply(const float a[16], const float b[16], float out[16]) noexcept;  ///< out = a * b
void identity(float out[16]) noexcept;
void translation_scale(float tx, float ty, float tz, float scale, float out[16]) noexcept;

} // namespace tcr
