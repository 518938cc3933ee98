#include "scene.h"

#include "tom/errors.h"

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

namespace walk {

namespace {
constexpr float kPi = 3.14159265358979f;
}

Scene read_scene(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw tom::IoError("cannot open scene file '" + path + "'");
    Scene s;
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
        ++number;
        const size_t hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        std::istringstream ls(line);
        std::string word;
        if (!(ls >> word)) continue;
        const std::string where = path + ":" + std::to_string(number) + ": ";
        if (word == "mesh") {
            std::string p;
            if (!(ls >> p)) throw tom::ParseError(where + "expected 'mesh PATH'");
            s.meshes.push_back(p);
        } else if (word == "instance") {
            Instance i;
            if (!(ls >> i.mesh >> i.x >> i.y >> i.z >> i.size >> i.yaw_deg >> i.weight))
                throw tom::ParseError(where + "expected 'instance MESH X Y Z SIZE YAW WEIGHT'");
            if (i.mesh >= s.meshes.size()) throw tom::ParseError(where + "mesh " + std::to_string(i.mesh) + " is not declared above");
            if (!(i.size > 0) || !(i.weight >= 0)) throw tom::ParseError(where + "size must be > 0 and weight >= 0");
            s.instances.push_back(i);
        } else {
            throw tom::ParseError(where + "unknown keyword '" + word + "'");
        }
    }
    if (s.instances.empty()) throw tom::ParseError(path + ": no instances");
    return s;
}

void write_scene(const std::string& path, const Scene& s) {
    std::ofstream out(path);
    if (!out) throw tom::ParseError("cannot write scene file '" + path + "'");
    out << "# tcrwalk scene: mesh PATH; instance MESH X Y Z SIZE YAW WEIGHT\n";
    for (const std::string& m : s.meshes) out << "mesh " << m << "\n";
    out.precision(6);
    for (const Instance& i : s.instances)
        out << "instance " << i.mesh << ' ' << i.x << ' ' << i.y << ' ' << i.z << ' ' << i.size << ' ' << i.yaw_deg << ' ' << i.weight << "\n";
}

namespace {

// The far ring: objects of every mesh 50 to 150 units out, two to six units tall, where the
// levels are down to their coarsest and an imposter of the detailed object costs a quad (Pasman
// & Jansen's simple imposters pay beyond about fifty radii). Its own stream of the seed, so the
// near scene is the same with or without it.
void add_far_ring(Scene& s, uint32_t count, uint64_t seed) {
    std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ull);
    std::uniform_real_distribution<float> u(0, 1);
    for (uint32_t k = 0; k < count; ++k) {
        Instance i;
        i.mesh = uint32_t(rng() % s.meshes.size());
        const float r = 50.0f + 100.0f * u(rng), a = 2 * kPi * u(rng);
        i.x = r * std::cos(a);
        i.z = r * std::sin(a);
        i.size = 2.0f + 4.0f * u(rng);
        i.y = 0.5f * i.size;
        i.yaw_deg = 360.0f * u(rng);
        i.weight = 1.0f;
        s.instances.push_back(i);
    }
}

} // namespace

Scene make_scene(const std::vector<std::string>& meshes, uint32_t instances, uint64_t seed, uint32_t heaviest, uint32_t far_instances) {
    Scene s;
    s.meshes = meshes;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> u(0, 1);
    for (uint32_t k = 0; k < instances; ++k) {
        Instance i;
        i.mesh = uint32_t(rng() % meshes.size());
        const bool crowd = u(rng) < 0.6f;
        if (!crowd) i.mesh = heaviest;  // the few far objects are detailed: the budget binds there too
        const float r = crowd ? 6.0f * std::sqrt(u(rng)) : 14.0f + 26.0f * u(rng);
        const float a = 2 * kPi * u(rng);
        i.x = r * std::cos(a);
        i.z = r * std::sin(a);
        i.size = 0.6f + 1.8f * u(rng);
        i.y = 0.5f * i.size;
        i.yaw_deg = 360.0f * u(rng);
        i.weight = u(rng) < 0.05f ? 3.0f : 1.0f;
        s.instances.push_back(i);
    }
    add_far_ring(s, far_instances, seed);
    return s;
}

CameraPose path_pose(uint32_t f, uint32_t frames) {
    const float t = frames > 1 ? float(f) / float(frames - 1) : 0.0f;
    CameraPose p;
    auto set = [&](float ex, float ey, float ez, float tx, float ty, float tz) {
        p.eye[0] = ex, p.eye[1] = ey, p.eye[2] = ez, p.target[0] = tx, p.target[1] = ty, p.target[2] = tz;
    };
    if (t < 0.35f) {  // A: through the crowd, many large objects close up
        const float s = t / 0.35f;
        const float z = 7.0f - 12.0f * s;
        set(0.6f * std::sin(6 * s), 1.1f, z, 0.0f, 0.8f, z - 5.0f);
    } else if (t < 0.62f) {  // out to the east, looking away from the crowd: few small objects
        const float s = (t - 0.35f) / 0.27f;
        const float x = 2.0f + 14.0f * s;
        set(x, 1.4f, -5.0f + 5.0f * s, x + 10.0f, 1.0f, 0.0f);
    } else if (t < 0.66f) {  // C: a sudden spin back toward the crowd
        const float s = (t - 0.62f) / 0.04f;
        const float yaw = kPi * s;  // from +x to -x
        set(16.0f, 1.4f, 0.0f, 16.0f + 10.0f * std::cos(yaw), 1.0f, 10.0f * std::sin(yaw));
    } else {  // a slow approach, the crowd filling the view
        const float s = (t - 0.66f) / 0.34f;
        const float x = 16.0f - 8.0f * s;
        set(x, 1.4f + 0.6f * s, 0.0f, x - 10.0f, 0.8f, 0.0f);
    }
    return p;
}

void viewpoints(uint32_t frames, uint32_t out[3]) {
    out[0] = uint32_t(0.15 * (frames - 1));   // A
    out[1] = uint32_t(0.55 * (frames - 1));   // B
    out[2] = uint32_t(0.665 * (frames - 1));  // C: just after the spin
}

} // namespace walk
