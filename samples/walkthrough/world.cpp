// The walkthrough's world (world.h).

#include "world.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "tom/errors.h"
#include "tom/extract.h"

namespace fs = std::filesystem;

namespace walk {
namespace {

// The base-colour image of each part of mesh `m`; a mesh with texture coordinates and at least
// one such image is textured.
void find_images(World& w, size_t m, const fs::path& tom_path) {
    std::vector<walk::PartImage> images = walk::find_part_images(w.files[m], 0, tom_path);
    const bool any = std::any_of(images.begin(), images.end(), [](const walk::PartImage& i) { return !i.key.empty(); });
    w.textured.push_back(w.meshes[m]->texcoords && any);
    w.part_images.push_back(std::move(images));
}

} // namespace

World load_world(const std::string& scene_path) {
    World w;
    w.scene = walk::read_scene(scene_path);
    const fs::path dir = fs::path(scene_path).parent_path();
    for (const std::string& m : w.scene.meshes) {
        const fs::path p = fs::path(m).is_absolute() ? fs::path(m) : dir / m;
        w.files.push_back(tom::File::open(p.string()));
        if (w.files.back().mesh_count() == 0) throw tom::Error(p.string() + ": no mesh");
    }
    for (const tom::File& f : w.files) w.meshes.push_back(&f.mesh(0));
    for (size_t m = 0; m < w.meshes.size(); ++m)
        find_images(w, m, fs::path(w.scene.meshes[m]).is_absolute() ? fs::path(w.scene.meshes[m]) : dir / w.scene.meshes[m]);
    for (const walk::Instance& i : w.scene.instances) {
        const tom::MeshView& m = *w.meshes[i.mesh];
        double d2 = 0;
        float c[3];
        for (int k = 0; k < 3; ++k) {
            d2 += double(m.bounds_max[k] - m.bounds_min[k]) * (m.bounds_max[k] - m.bounds_min[k]);
            c[k] = 0.5f * (m.bounds_min[k] + m.bounds_max[k]);
        }
        const float s = float(i.size / std::max(1e-9, std::sqrt(d2)));
        const float a = i.yaw_deg * 3.14159265f / 180.0f, ca = std::cos(a), sa = std::sin(a);
        // T(x,y,z) R_y(yaw) S(s) T(-centre), column-major
        std::array<float, 16> t{};
        t[0] = s * ca, t[2] = -s * sa, t[5] = s, t[8] = s * sa, t[10] = s * ca, t[15] = 1;
        t[12] = i.x - (t[0] * c[0] + t[4] * c[1] + t[8] * c[2]);
        t[13] = i.y - (t[1] * c[0] + t[5] * c[1] + t[9] * c[2]);
        t[14] = i.z - (t[2] * c[0] + t[6] * c[1] + t[10] * c[2]);
        w.transforms.push_back(t);
        w.full_triangles += m.triangle_count;
    }
    return w;
}

void load_images(World& w, walk::Renderer* renderer) {
    std::map<std::string, int32_t> loaded;
    w.image_handles.clear();
    for (const std::vector<walk::PartImage>& parts : w.part_images) {
        std::vector<int32_t> handles(parts.size(), -1);
        if (renderer)
            for (size_t p = 0; p < parts.size(); ++p) handles[p] = walk::load_image(parts[p], *renderer, loaded);
        w.image_handles.push_back(std::move(handles));
    }
}

tcr::Camera camera_for(uint32_t f, uint32_t frames, uint32_t width, uint32_t height) {
    const walk::CameraPose pose = walk::path_pose(f, frames);
    tcr::Camera c;
    const float up[3] = {0, 1, 0};
    tcr::look_at(pose.eye, pose.target, up, c.view);
    tcr::perspective(60.0f * 3.14159265f / 180.0f, float(width) / float(height), 0.05f, 200.0f, c.projection);
    c.viewport_width = width;
    c.viewport_height = height;
    return c;
}

void add_objects(tcr::Runtime& rt, const World& w) {
    for (size_t i = 0; i < w.scene.instances.size(); ++i) {
        const uint32_t id = rt.add_object(*w.meshes[w.scene.instances[i].mesh], w.transforms[i].data(), w.scene.instances[i].weight);
        rt.set_textured(id, w.textured[w.scene.instances[i].mesh] != 0);
    }
}

const float* representation_color(tcr::Representation r) {
    switch (r) {
    case tcr::Representation::flat: return kFlatColor;
    case tcr::Representation::simple_imposter: return kImposterColor;
    case tcr::Representation::meshed_imposter: return kMeshedColor;
    case tcr::Representation::textured: return kTexturedColor;
    default: return kSmoothColor;
    }
}

void lod_color(double fraction, float out[3]) {
    const double t = std::min(1.0, std::max(0.0, std::log10(std::max(fraction, 1e-3)) / 3.0 + 1.0));  // 0.1% .. 100%
    out[0] = float(std::max(0.0, 1.0 - 2.0 * t));
    out[1] = float(1.0 - std::abs(2.0 * t - 1.0));
    out[2] = float(std::max(0.0, 2.0 * t - 1.0));
}

void ensure(std::vector<uint32_t>& v, size_t n) {
    if (v.size() >= n) return;
    v.resize(std::max(n, v.size() * 2), 0u);
}

size_t extract_frame(const World& w, const tcr::Runtime& rt, const std::vector<uint32_t>& mesh_handles, const float color[3],
                     std::vector<uint32_t>& indices, std::vector<walk::Renderer::Draw>& draws, std::vector<walk::Renderer::Capture>& captures,
                     uint32_t slots) {
    using Shading = walk::Renderer::Shading;
    ensure(indices, size_t(rt.last_frame().triangles) * 3);
    draws.clear();
    captures.clear();
    size_t at = 0;
    tom::PartDraw parts[64];
    for (uint32_t id = 0; id < rt.object_count(); ++id) {
        const tcr::ObjectResult& obj = rt.object(id);
        if (!obj.drawn) continue;
        const uint32_t mesh = w.scene.instances[id].mesh;
        walk::Renderer::Draw d{mesh_handles[mesh], w.transforms[id].data(), at, 0, {color[0], color[1], color[2]}};
        d.tag = id;
        d.shading = obj.representation == tcr::Representation::flat ? Shading::flat : Shading::smooth;
        // texture-mapped where the plan says, and in a capture of a textured object (an
        // imposter keeps the best picture)
        const bool textured = obj.representation == tcr::Representation::textured || (tcr::is_imposter(obj.representation) && w.textured[mesh]);
        if (tcr::is_imposter(obj.representation)) {
            const tcr::ImposterState& im = rt.imposter(id);
            walk::Renderer::Draw quad = d;
            quad.shading = im.grid ? Shading::meshed : Shading::imposter;
            quad.texture = slots + id;
            if (!im.grid) tcr::imposter_quad(im, quad.corners);
            draws.push_back(quad);
            if (!obj.refresh) continue;
            walk::Renderer::Capture c{slots + id, im.texture_px, {}, {}, im.grid};
            tcr::imposter_camera(im, c.view, c.projection);
            d.capture = int32_t(captures.size());
            captures.push_back(c);
        }
        if (tom::part_count(*w.meshes[mesh]) > 64) {  // more than a draw list here holds: one draw
            const tom::Extracted e = rt.indices(id, indices.data() + at, indices.size() - at);
            d.index_count = e.triangle_count * 3;
            draws.push_back(d);
            at += size_t(e.triangle_count) * 3;
            continue;
        }
        const tom::Extracted e = rt.indices(id, indices.data() + at, indices.size() - at, parts);
        for (uint32_t p = 0; p < tom::part_count(*w.meshes[mesh]); ++p)
            if (parts[p].index_count > 0) {
                d.first = at + parts[p].first_index;
                d.index_count = parts[p].index_count;
                if (textured && w.image_handles[mesh][p] >= 0) {
                    walk::Renderer::Draw t = d;
                    t.shading = Shading::textured;
                    t.image = uint32_t(w.image_handles[mesh][p]);
                    draws.push_back(t);
                    continue;
                }
                draws.push_back(d);
            }
        at += size_t(e.triangle_count) * 3;
    }
    return at;
}

} // namespace walk
