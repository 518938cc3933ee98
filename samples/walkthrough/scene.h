#pragma once
// The walkthrough's scene and camera path.
//
// Scene file (text, '#' comments; paths relative to the file):
//   mesh PATH.tom                          one line per mesh; each file's first mesh is used
//   instance MESH X Y Z SIZE YAW WEIGHT    MESH: index of a mesh line; SIZE: world bounding-box
//                                          diagonal; YAW: degrees about +y; WEIGHT: semantic weight
//
// The path (Funkhouser & Sequin's hard viewpoints): A, walking through the dense crowd at the
// origin with many large objects close up; B, far out looking away from it at a few small
// objects; C, a sudden spin that turns the crowd into view at once; then a slow approach.

#include <cstdint>
#include <string>
#include <vector>

namespace walk {

struct Instance {
    uint32_t mesh;
    float x, y, z, size, yaw_deg, weight;
};

struct Scene {
    std::vector<std::string> meshes;  ///< .tom paths as written in the file
    std::vector<Instance> instances;
};

/// \throw tom::ParseError naming the file and line; tom::IoError when unreadable.
Scene read_scene(const std::string& path);
void write_scene(const std::string& path, const Scene& scene);
/// A crowd of about 60% of the instances within radius 6 of the origin (any mesh), the rest
/// sparse in a ring from radius 14 to 40 (mesh `heaviest`, the most detailed); sizes 0.6 to 2.4;
/// deterministic from the seed. `far_instances` more go in a ring from radius 50 to 150 (every
/// mesh, sizes 2 to 6), drawn from a stream of their own so the rest is the same without them.
Scene make_scene(const std::vector<std::string>& meshes, uint32_t instances, uint64_t seed, uint32_t heaviest, uint32_t far_instances = 0);

struct CameraPose {
    float eye[3], target[3];
};
/// The pose at frame `f` of `frames`.
CameraPose path_pose(uint32_t f, uint32_t frames);
/// The frames of viewpoints A, B and C.
void viewpoints(uint32_t frames, uint32_t out[3]);

} // namespace walk
