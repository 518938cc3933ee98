// The walkthrough's headless renderer (OSMesa, llvmpipe): a simple imposter seen from the
// viewpoint it was captured from covers the pixels its geometry covers, in the geometry's
// colours, whatever the side of its cell and wherever the cell sits among the other captures
// of the shared array textures (several sides in one layer, layers in two array textures); a
// meshed imposter does too, and seen from elsewhere keeps closer to its object than a simple one.

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <vector>

#include <catch2/catch.hpp>

#include "renderer.h"
#include "support.h"
#include "tcr/runtime.h"
#include "tcr/view.h"
#include "tom/builder/builder.h"
#include "tom/builder/mesh.h"
#include "tom/builder/writer.h"
#include "tom/format.h"

namespace {

constexpr uint32_t kWidth = 320, kHeight = 240;

struct Bunny {
    std::vector<uint8_t> bytes;
    tom::File file;
    static std::vector<uint8_t> make() { return tom::serialize({tom::build(test::real_meshes()[0].mesh)}); }
    Bunny() : bytes(make()), file(tom::File::from_bytes(bytes.data(), bytes.size())) {}
    const tom::MeshView& mesh() const { return file.mesh(0); }
};

// One object of the test scene: where it stands and how large, and its capture.
struct Placed {
    float model[16];
    tcr::ImposterState capture;
};

struct Scene {
    walk::Renderer renderer{kWidth, kHeight};
    Bunny bunny;
    uint32_t handle = renderer.add_mesh(bunny.mesh());
    std::vector<uint32_t> indices;
    float eye[3] = {0, 0.2f, 7}, view[16], projection[16];
    Scene() {
        indices.resize(size_t(bunny.mesh().triangle_count) * 3);
        tom::extract(bunny.mesh(), bunny.mesh().vertex_count, indices.data(), indices.size());
        look_from(eye);
        tcr::perspective(50.0f * 3.14159265f / 180.0f, float(kWidth) / float(kHeight), 0.1f, 100.0f, projection);
    }
    // the frame's viewpoint (captures placed after this are made from it)
    void look_from(const float from[3]) {
        std::copy(from, from + 3, eye);
        const float target[3] = {0, 0, 0}, up[3] = {0, 1, 0};
        tcr::look_at(eye, target, up, view);
    }
    // an object at (x, y, 0) whose bounding sphere has radius `radius`, turned `yaw` radians
    // about the vertical, captured from the eye
    Placed place(float x, float y, float radius, uint32_t side, float yaw = 0) const {
        const tom::MeshView& m = bunny.mesh();
        double d2 = 0;
        float centre[3];
        for (int k = 0; k < 3; ++k) {
            d2 += double(m.bounds_max[k] - m.bounds_min[k]) * double(m.bounds_max[k] - m.bounds_min[k]);
            centre[k] = 0.5f * (m.bounds_min[k] + m.bounds_max[k]);
        }
        const float scale = radius / float(0.5 * std::sqrt(d2));
        // column-major scale, then the turn, then the move that puts the centre at (x, y, 0)
        const float c = std::cos(yaw), sn = std::sin(yaw);
        Placed p;
        const float rs[3] = {scale * (c * centre[0] + sn * centre[2]), scale * centre[1], scale * (-sn * centre[0] + c * centre[2])};
        const float matrix[16] = {scale * c, 0, -scale * sn, 0, 0, scale, 0, 0, scale * sn, 0, scale * c, 0, x - rs[0], y - rs[1], -rs[2], 1};
        std::copy(matrix, matrix + 16, p.model);
        p.capture.valid = true;
        p.capture.centre[0] = x, p.capture.centre[1] = y, p.capture.centre[2] = 0;
        std::copy(eye, eye + 3, p.capture.eye);
        p.capture.radius = radius;
        p.capture.texture_px = side;
        return p;
    }
    walk::Renderer::Draw geometry(const Placed& p) const {
        return walk::Renderer::Draw{handle, p.model, 0, uint32_t(indices.size()), {0.8f, 0.7f, 0.5f}};
    }
    std::vector<unsigned char> direct(const std::vector<Placed>& objects) {
        std::vector<walk::Renderer::Draw> draws;
        for (const Placed& p : objects) draws.push_back(geometry(p));
        renderer.render(view, projection, draws, indices, indices.size());
        return renderer.read_pixels();
    }
    // each object captured into slot `first_slot + i` this frame and drawn as its quad alone, or
    // with a `grid`, over its depth mesh
    std::vector<unsigned char> as_imposters(const std::vector<Placed>& objects, uint32_t first_slot, uint32_t grid = 0) {
        std::vector<walk::Renderer::Draw> draws;
        std::vector<walk::Renderer::Capture> captures;
        for (size_t i = 0; i < objects.size(); ++i) {
            walk::Renderer::Capture c{first_slot + uint32_t(i), objects[i].capture.texture_px, {}, {}, grid};
            tcr::imposter_camera(objects[i].capture, c.view, c.projection);
            captures.push_back(c);
            walk::Renderer::Draw g = geometry(objects[i]);
            g.capture = int32_t(i);
            draws.push_back(g);
            walk::Renderer::Draw quad = g;
            quad.capture = -1;
            quad.shading = walk::Renderer::Shading::imposter;
            quad.texture = first_slot + uint32_t(i);
            if (grid) quad.shading = walk::Renderer::Shading::meshed;
            tcr::imposter_quad(objects[i].capture, quad.corners);
            draws.push_back(quad);
        }
        renderer.render(view, projection, draws, indices, indices.size(), captures);
        return renderer.read_pixels();
    }
    // the captures already in slots `first_slot + i` drawn from this frame's viewpoint, as
    // quads or (`meshed`) over their depth meshes
    std::vector<unsigned char> kept(const std::vector<Placed>& objects, uint32_t first_slot, bool meshed) {
        std::vector<walk::Renderer::Draw> draws;
        for (size_t i = 0; i < objects.size(); ++i) {
            walk::Renderer::Draw d = geometry(objects[i]);
            d.shading = meshed ? walk::Renderer::Shading::meshed : walk::Renderer::Shading::imposter;
            d.texture = first_slot + uint32_t(i);
            tcr::imposter_quad(objects[i].capture, d.corners);
            draws.push_back(d);
        }
        renderer.render(view, projection, draws, indices, indices.size());
        return renderer.read_pixels();
    }
};

// What the imposter frame shares with the direct one: the overlap of their foregrounds (pixels
// unlike the corner's background) over their union, and the mean colour difference (0-255)
// where both are foreground.
struct Agreement {
    double overlap = 0, colour = 0;
    size_t direct_pixels = 0;
};
Agreement agreement(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b) {
    auto differs = [](const unsigned char* p, const unsigned char* q) { return std::abs(p[0] - q[0]) + std::abs(p[1] - q[1]) + std::abs(p[2] - q[2]) > 12; };
    size_t both = 0, either = 0;
    double colour = 0;
    Agreement out;
    for (size_t i = 0; i < a.size(); i += 4) {
        const bool fa = differs(&a[i], &a[0]), fb = differs(&b[i], &b[0]);
        out.direct_pixels += fa;
        either += fa || fb;
        if (!(fa && fb)) continue;
        ++both;
        colour += (std::abs(a[i] - b[i]) + std::abs(a[i + 1] - b[i + 1]) + std::abs(a[i + 2] - b[i + 2])) / 3.0;
    }
    out.overlap = either ? double(both) / double(either) : 1.0;
    out.colour = both ? colour / double(both) : 0.0;
    return out;
}

} // namespace

TEST_CASE("walk renderer: imposters of several sides in one layer draw their objects", "[walk][renderer][imposters]") {
    Scene s;
    const std::vector<Placed> objects = {s.place(-1.6f, 0, 0.7f, 64), s.place(0, 0.1f, 0.7f, 128, 1.0f), s.place(1.6f, 0, 0.7f, 256, 2.0f), s.place(0, -1.2f, 0.4f, 32, 3.0f)};
    const std::vector<unsigned char> direct = s.direct(objects);
    const std::vector<unsigned char> imposters = s.as_imposters(objects, 0);
    const Agreement a = agreement(direct, imposters);
    INFO("overlap " << a.overlap << " colour difference " << a.colour << " foreground " << a.direct_pixels);
    REQUIRE(a.direct_pixels > 1500);  // the objects are in view
    CHECK(a.overlap > 0.93);  // measured 0.97 and 4 (the 32-texel cell is magnified)
    CHECK(a.colour < 8);
    // the cells of a layer: 256 takes one, 128, 64 and 32 share a second
    CHECK(s.renderer.texture_bytes() == size_t(32) * 256 * 256 * 4);
    // the same slots captured again at other sides: freed cells are taken again, same picture
    std::vector<Placed> resized = objects;
    const uint32_t sides[4] = {256, 64, 128, 64};
    for (size_t i = 0; i < resized.size(); ++i) resized[i].capture.texture_px = sides[i];
    const Agreement again = agreement(direct, s.as_imposters(resized, 0));
    INFO("resized: overlap " << again.overlap << " colour difference " << again.colour);
    CHECK(again.overlap > 0.93);
    CHECK(again.colour < 8);
}

TEST_CASE("walk renderer: forty captures of a full layer each spill into a second array texture", "[walk][renderer][imposters]") {
    Scene s;
    std::vector<Placed> objects;
    for (int i = 0; i < 40; ++i)  // each turned its own way: a capture shown in another's place would not match
        objects.push_back(s.place(-2.7f + 0.6f * float(i % 10), -1.2f + 0.8f * float(i / 10), 0.28f, 256, 0.157f * float(i)));
    const std::vector<unsigned char> direct = s.direct(objects);
    const Agreement a = agreement(direct, s.as_imposters(objects, 100));
    INFO("overlap " << a.overlap << " colour difference " << a.colour << " foreground " << a.direct_pixels);
    REQUIRE(a.direct_pixels > 2500);
    CHECK(a.overlap > 0.95);  // measured 0.99 and 1.3
    CHECK(a.colour < 5);
    CHECK(s.renderer.texture_bytes() == size_t(2) * 32 * 256 * 256 * 4);  // 40 layers of 32 a texture
}

TEST_CASE("walk renderer: a meshed imposter keeps its object's shape as the viewer walks around it", "[walk][renderer][imposters][meshed]") {
    Scene s;
    // three bunnies, each turned its own way, captured from the eye as meshed imposters (slots
    // 0..2, a grid of 16) and as simple ones (slots 10..12)
    const std::vector<Placed> objects = {s.place(-1.7f, 0, 0.8f, 256, 0.6f), s.place(0, 0, 0.8f, 256, 2.0f), s.place(1.7f, 0, 0.8f, 256, 4.0f)};
    const std::vector<unsigned char> direct = s.direct(objects);
    const Agreement at_capture = agreement(direct, s.as_imposters(objects, 0, 16));
    INFO("from the capture's eye: overlap " << at_capture.overlap << " colour difference " << at_capture.colour);
    REQUIRE(at_capture.direct_pixels > 1500);
    CHECK(at_capture.overlap > 0.93);
    CHECK(at_capture.colour < 8);
    s.as_imposters(objects, 10, 0);
    // the viewer walks about the scene's centre, 25 degrees around and a little up: each
    // object is seen from the side its capture did not face
    const double a = 25.0 * 3.14159265 / 180.0;
    const float moved[3] = {float(7.0 * std::sin(a)), 0.9f, float(7.0 * std::cos(a))};
    s.look_from(moved);
    const std::vector<unsigned char> truth = s.direct(objects);
    const Agreement meshed = agreement(truth, s.kept(objects, 0, true));
    const Agreement simple = agreement(truth, s.kept(objects, 10, false));
    INFO("walked around: meshed overlap " << meshed.overlap << " colour " << meshed.colour << "; simple overlap " << simple.overlap << " colour " << simple.colour);
    // measured: meshed 0.85 and 13, simple 0.72 and 25 (the quad is flat: its outline and its
    // texels slide over the object's)
    CHECK(meshed.overlap > simple.overlap + 0.05);
    CHECK(meshed.overlap > 0.8);
    CHECK(meshed.colour < 0.7 * simple.colour);
}

namespace {

// A square [-1, 1]^2 in the plane z = 0 facing +z, a grid of 4 x 4 cells, texture coordinates
// (x + 1) / 2, (y + 1) / 2.
std::vector<uint8_t> textured_square() {
    tom::Mesh m;
    const int n = 4;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const float x = -1.0f + 2.0f * float(i) / n, y = -1.0f + 2.0f * float(j) / n;
            m.positions.insert(m.positions.end(), {x, y, 0.0f});
            m.normals.insert(m.normals.end(), {0.0f, 0.0f, 1.0f});
            m.texcoords.insert(m.texcoords.end(), {0.5f * (x + 1.0f), 0.5f * (y + 1.0f)});
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n) + 1, d = c + 1;
            m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
        }
    tom::clean_mesh(m);
    return tom::serialize({tom::build(m)});
}

} // namespace

TEST_CASE("walk renderer: a texture-mapped mesh shows its image where its texture coordinates put it", "[walk][renderer][textured]") {
    walk::Renderer renderer(kWidth, kHeight);
    const std::vector<uint8_t> bytes = textured_square();
    const tom::File file = tom::File::from_bytes(bytes.data(), bytes.size());
    const tom::MeshView& mesh = file.mesh(0);
    REQUIRE(mesh.texcoords != nullptr);
    const uint32_t handle = renderer.add_mesh(mesh);
    // a 2 x 2 checker, rows from the bottom: red, green / blue, white
    const unsigned char checker[16] = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255};
    const uint32_t image = renderer.add_image(2, 2, checker);
    std::vector<uint32_t> indices(size_t(mesh.triangle_count) * 3);
    tom::extract(mesh, mesh.vertex_count, indices.data(), indices.size());
    float view[16], projection[16], vp[16];
    const float eye[3] = {0, 0, 3}, target[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    tcr::look_at(eye, target, up, view);
    tcr::perspective(50.0f * 3.14159265f / 180.0f, float(kWidth) / float(kHeight), 0.1f, 100.0f, projection);
    tcr::multiply(projection, view, vp);
    static const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    walk::Renderer::Draw d{handle, identity, 0, uint32_t(indices.size()), {1, 1, 1}};
    // the pixel at the centre of each quadrant, (+-0.5, +-0.5, 0)
    auto at = [&](const std::vector<unsigned char>& pixels, float x, float y) {
        const float cx = vp[0] * x + vp[4] * y + vp[12], cy = vp[1] * x + vp[5] * y + vp[13], cw = vp[3] * x + vp[7] * y + vp[15];
        const size_t px = size_t((cx / cw + 1.0f) * 0.5f * kWidth), py = size_t((cy / cw + 1.0f) * 0.5f * kHeight);
        return std::array<int, 3>{pixels[4 * (py * kWidth + px)], pixels[4 * (py * kWidth + px) + 1], pixels[4 * (py * kWidth + px) + 2]};
    };
    d.shading = walk::Renderer::Shading::textured;
    d.image = image;
    renderer.render(view, projection, {d}, indices, indices.size());
    const std::vector<unsigned char> textured = renderer.read_pixels();
    const auto red = at(textured, -0.5f, -0.5f), green = at(textured, 0.5f, -0.5f), blue = at(textured, -0.5f, 0.5f), white = at(textured, 0.5f, 0.5f);
    INFO("red " << red[0] << "," << red[1] << "," << red[2] << " green " << green[0] << "," << green[1] << "," << green[2] << " blue " << blue[0] << ","
                << blue[1] << "," << blue[2] << " white " << white[0] << "," << white[1] << "," << white[2]);
    // lit by the front light's 0.47 (its 0.65 x cos), the image's colour at each quadrant
    CHECK(red[0] > 90);
    CHECK(red[1] + red[2] < 20);
    CHECK(green[1] > 90);
    CHECK(green[0] + green[2] < 20);
    CHECK(blue[2] > 90);
    CHECK(blue[0] + blue[1] < 20);
    CHECK(std::min({white[0], white[1], white[2]}) > 90);
    // the same draw smooth-shaded: one colour all over
    d.shading = walk::Renderer::Shading::smooth;
    renderer.render(view, projection, {d}, indices, indices.size());
    const std::vector<unsigned char> plain = renderer.read_pixels();
    CHECK(at(plain, -0.5f, -0.5f) == at(plain, 0.5f, 0.5f));
    CHECK(at(plain, 0.5f, -0.5f) == at(plain, -0.5f, 0.5f));
}

TEST_CASE("walk renderer: an image that cannot be read is an error naming it", "[walk][renderer][textured]") {
    walk::Renderer renderer(kWidth, kHeight);
    const std::string missing = "/nonexistent/texture.png";
    CHECK_THROWS_WITH(renderer.add_image(missing), Catch::Contains(missing));
    const std::string broken = (std::filesystem::temp_directory_path() / "tom_walk_broken.png").string();
    {
        std::ofstream out(broken, std::ios::binary);
        out << "\x89PNG\r\n\x1a\nnot a png at all";
    }
    CHECK_THROWS_WITH(renderer.add_image(broken), Catch::Contains(broken));
    std::filesystem::remove(broken);
}
