#pragma once
// The walkthrough's world: the scene's meshes mapped, each instance's transform and images, the
// camera along the path, and the frame a runtime planned, extracted into the renderer's draws.

#include <array>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "images.h"
#include "renderer.h"
#include "scene.h"
#include "tcr/runtime.h"
#include "tcr/view.h"
#include "tom/format.h"

namespace walk {

/// The clock every timed step of the walkthrough reads, and milliseconds since `t0` on it.
using Clock = std::chrono::steady_clock;
inline double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// The scene with its meshes mapped and each instance's transform.
struct World {
    walk::Scene scene;
    std::vector<tom::File> files;
    std::vector<const tom::MeshView*> meshes;
    std::vector<std::array<float, 16>> transforms;
    uint64_t full_triangles = 0;
    // per mesh, per part: its material's base-colour image (stored in the .tom, or a file found
    // beside it), or none; a mesh with texture coordinates and at least one such image is textured
    std::vector<std::vector<walk::PartImage>> part_images;
    std::vector<uint8_t> textured;
    // the renderer's handles of those images (-1: none), once it has them (load_images)
    std::vector<std::vector<int32_t>> image_handles;
};

/// The scene file's meshes mapped, their images found, each instance's transform.
/// \throw tom::Error naming an unreadable mesh, std::runtime_error for a bad scene file.
World load_world(const std::string& scene_path);
/// The parts' images into the renderer (each once); none without a renderer (--simulate).
void load_images(World& w, Renderer* renderer);
/// The camera at frame `f` of the path's `frames`.
tcr::Camera camera_for(uint32_t f, uint32_t frames, uint32_t width, uint32_t height);
/// Every instance of the scene into the runtime, in scene order (its object ids are the instances').
void add_objects(tcr::Runtime& rt, const World& w);

// Object colours of the shaded view, and of the warm-up frames (never shown).
constexpr float kSand[3] = {0.85f, 0.78f, 0.62f}, kGrey[3] = {0.8f, 0.8f, 0.8f};
// The representation view's colours: smooth-shaded levels, flat-shaded levels, simple and meshed imposters.
constexpr float kSmoothColor[3] = {0.3f, 0.5f, 0.9f}, kFlatColor[3] = {0.95f, 0.6f, 0.15f}, kImposterColor[3] = {0.85f, 0.2f, 0.75f},
                kMeshedColor[3] = {0.2f, 0.75f, 0.35f}, kTexturedColor[3] = {0.95f, 0.85f, 0.2f};
const float* representation_color(tcr::Representation r);
/// Hue from red (coarse) through green to blue (full resolution), for the LOD view.
void lod_color(double fraction, float out[3]);

/// Grows `v` to hold at least `n` elements, by doubling, and touches the new memory once, so no
/// frame pays page faults for its index array.
void ensure(std::vector<uint32_t>& v, size_t n);
/// The frame the runtime planned, extracted: each drawn object's level into `indices` (grown as
/// needed), one draw per object, or per part of a multi-part object (as the cost model counts
/// them), in `color` and the shading the runtime chose; an imposter as its quad or depth mesh,
/// after, when the runtime renews it, its level drawn into its texture (a capture, which for a
/// meshed imposter also remakes its depth mesh). Object id's texture is the renderer's slot
/// `slots + id`, so runs that share a renderer keep their captures apart. Returns the frame's
/// index count.
size_t extract_frame(const World& w, const tcr::Runtime& rt, const std::vector<uint32_t>& mesh_handles, const float color[3],
                     std::vector<uint32_t>& indices, std::vector<Renderer::Draw>& draws, std::vector<Renderer::Capture>& captures,
                     uint32_t slots = 0);

} // namespace walk
