// View-frustum culling and projected size of bounding boxes (Funkhouser & Sequin 1993: screen
// size and focus as benefit factors; Gobbetti & Bouvier 1999: coverage in pixels for the cost).

#include "tcr/view.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace tcr {

void identity(float out[16]) noexcept {
    for (int i = 0; i < 16; ++i) out[i] = (i % 5 == 0) ? 1.0f : 0.0f;
}

void multiply(const float a[16], const float b[16], float out[16]) noexcept {
    float r[16];
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) {
            float s = 0;
            for (int k = 0; k < 4; ++k) s += a[k * 4 + row] * b[c * 4 + k];
            r[c * 4 + row] = s;
        }
    for (int i = 0; i < 16; ++i) out[i] = r[i];
}

void translation_scale(float tx, float ty, float tz, float scale, float out[16]) noexcept {
    identity(out);
    out[0] = out[5] = out[10] = scale;
    out[12] = tx, out[13] = ty, out[14] = tz;
}

void perspective(float fov_y, float aspect, float z_near, float z_far, float out[16]) noexcept {
    const float f = 1.0f / std::tan(fov_y / 2);
    for (int i = 0; i < 16; ++i) out[i] = 0;
    out[0] = f / aspect;
    out[5] = f;
    out[10] = (z_far + z_near) / (z_near - z_far);
    out[11] = -1;
    out[14] = 2 * z_far * z_near / (z_near - z_far);
}

void look_at(const float eye[3], const float target[3], const float up[3], float out[16]) noexcept {
    float f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
    const float fl = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (float& x : f) x /= fl;
    float s[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]};
    const float sl = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    for (float& x : s) x /= sl;
    const float u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]};
    identity(out);
    for (int k = 0; k < 3; ++k) {
        out[k * 4 + 0] = s[k];
        out[k * 4 + 1] = u[k];
        out[k * 4 + 2] = -f[k];
    }
    out[12] = -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]);
    out[13] = -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]);
    out[14] = f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2];
}

namespace {

// The clip planes a point in clip space lies outside of: bit 2 axis below (x < -w), bit
// 2 axis + 1 above (x > w), for the axes x, y, z.
uint8_t outcode(const float v[4]) noexcept {
    uint8_t bits = 0;
    for (int axis = 0; axis < 3; ++axis) {
        if (v[axis] < -v[3]) bits |= uint8_t(1u << (2 * axis));
        if (v[axis] > v[3]) bits |= uint8_t(1u << (2 * axis + 1));
    }
    return bits;
}

// The share of `box`'s 4 x 4 x 4 sub-boxes that are not entirely outside one clip plane, at
// least one sub-box's share (the caller has found the box as a whole visible).
float inside_share(const float mvp[16], const Box& box) noexcept {
    constexpr int K = 4, L = K + 1;
    // the outcodes of the lattice of sub-box corners, each corner transformed once
    uint8_t outside[L * L * L];
    for (int i = 0; i < L; ++i)
        for (int j = 0; j < L; ++j)
            for (int k = 0; k < L; ++k) {
                const float x = box.min[0] + (box.max[0] - box.min[0]) * float(i) / K;
                const float y = box.min[1] + (box.max[1] - box.min[1]) * float(j) / K;
                const float z = box.min[2] + (box.max[2] - box.min[2]) * float(k) / K;
                float v[4];
                for (int r = 0; r < 4; ++r) v[r] = mvp[r] * x + mvp[4 + r] * y + mvp[8 + r] * z + mvp[12 + r];
                outside[(i * L + j) * L + k] = outcode(v);
            }
    int visible = 0;
    for (int i = 0; i < K; ++i)
        for (int j = 0; j < K; ++j)
            for (int k = 0; k < K; ++k) {
                uint8_t all = 0x3F;  // the planes every corner of the sub-box lies outside of
                for (int c = 0; c < 8; ++c) all &= outside[((i + (c & 1)) * L + (j + ((c >> 1) & 1))) * L + (k + ((c >> 2) & 1))];
                visible += all == 0;
            }
    return float(std::max(visible, 1)) / float(K * K * K);
}

} // namespace

Projection project_box(const Camera& camera, const float model[16], const Box& box, float focus_weight) noexcept {
    Projection p;
    float view_model[16], mvp[16];
    multiply(camera.view, model, view_model);
    multiply(camera.projection, view_model, mvp);
    // the eight corners in clip space, and the clip planes (-w <= x, y, z <= w) all of them lie
    // outside of (culled when there is one) and any of them does (none: wholly inside)
    float clip[8][4];
    uint8_t outside_all = 0x3F, outside_any = 0;
    for (int c = 0; c < 8; ++c) {
        const float x = (c & 1) ? box.max[0] : box.min[0], y = (c & 2) ? box.max[1] : box.min[1], z = (c & 4) ? box.max[2] : box.min[2];
        for (int r = 0; r < 4; ++r) clip[c][r] = mvp[r] * x + mvp[4 + r] * y + mvp[8 + r] * z + mvp[12 + r];
        const uint8_t code = outcode(clip[c]);
        outside_all &= code;
        outside_any |= code;
    }
    if (outside_all) return p;
    p.visible = true;
    p.inside_share = outside_any ? inside_share(mvp, box) : 1.0f;
    const float w = float(camera.viewport_width), h = float(camera.viewport_height);
    // eye-space distance to the box centre
    const float cx = 0.5f * (box.min[0] + box.max[0]), cy = 0.5f * (box.min[1] + box.max[1]), cz = 0.5f * (box.min[2] + box.max[2]);
    float eye[3];
    for (int r = 0; r < 3; ++r) eye[r] = view_model[r] * cx + view_model[4 + r] * cy + view_model[8 + r] * cz + view_model[12 + r];
    p.distance = std::sqrt(eye[0] * eye[0] + eye[1] * eye[1] + eye[2] * eye[2]);
    float x0 = w, y0 = h, x1 = 0, y1 = 0;
    bool crosses_eye_plane = false;
    for (int c = 0; c < 8; ++c) {
        if (clip[c][3] <= 1e-6f) {
            crosses_eye_plane = true;
            break;
        }
        const float sx = (clip[c][0] / clip[c][3] * 0.5f + 0.5f) * w;
        const float sy = (0.5f - clip[c][1] / clip[c][3] * 0.5f) * h;
        x0 = std::min(x0, sx), x1 = std::max(x1, sx), y0 = std::min(y0, sy), y1 = std::max(y1, sy);
    }
    if (crosses_eye_plane) {
        x0 = 0, y0 = 0, x1 = w, y1 = h;  // the box reaches the eye: it may fill the screen
    } else {
        x0 = std::max(x0, 0.0f), y0 = std::max(y0, 0.0f), x1 = std::min(x1, w), y1 = std::min(y1, h);
    }
    const float rw = std::max(0.0f, x1 - x0), rh = std::max(0.0f, y1 - y0);
    p.coverage_px = rw * rh;
    p.size_px = std::sqrt(rw * rw + rh * rh);
    p.center_x = 0.5f * (x0 + x1);
    p.center_y = 0.5f * (y0 + y1);
    const float dx = p.center_x - 0.5f * w, dy = p.center_y - 0.5f * h;
    const float off = std::sqrt(dx * dx + dy * dy) / (0.5f * std::sqrt(w * w + h * h));
    p.focus = 1.0f - std::min(1.0f, std::max(0.0f, focus_weight)) * std::min(1.0f, off);
    return p;
}

} // namespace tcr
