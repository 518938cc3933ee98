// tomview: draws a whole .tom scene headless (OSMesa) at one resolution and writes a PNG: every
// instance of the file's scene with its world transform and its material's base colour (or, with
// --lod-colors, coloured by the fraction of triangles drawn). The smallest integration of
// File::scene(), tom::draw_list and extraction with a renderer.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

#include "images.h"
#include "renderer.h"
#include "tcr/view.h"
#include "tom/stream/stream_file.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/scene.h"
#include "cli.h"

int main(int argc, char** argv) {
    std::string path, output;
    double fraction = 1.0;
    uint32_t width = 800, height = 600;
    bool lod_colors = false, below_floor = false;
    CLI::App app{"tomview: render a .tom file's scene (materials, instances) at one resolution to a PNG"};
    app.set_version_flag("--version", "tomview 0.1.0");
    app.add_option("file", path, "A .tom file")->required();
    app.add_option("-f,--fraction", fraction, "Fraction of each mesh's triangles (default 1)")->check(CLI::Range(0.0, 1.0));
    app.add_option("-o,--output", output, "Output .png")->required();
    app.add_option("--width", width, "Image width (default 800)")->check(CLI::Range(16u, 8192u));
    app.add_option("--height", height, "Image height (default 600)")->check(CLI::Range(16u, 8192u));
    app.add_flag("--lod-colors", lod_colors, "Colour each object by its drawn fraction instead of its material");
    app.add_flag("--below-floor", below_floor,
                 "Let --fraction go below each mesh's usable floor (tombuild --floor-error) to the coarsest level of its chain, as tomextract --below-floor");
    app.footer("Exit codes: 0 ok, 1 unreadable input, no OpenGL or unwritable output, 2 usage error.\n"
               "Example: tomview out/2CylinderEngine.tom --fraction 0.1 -o engine10.png");
    if (const int code = walk::parse_command_line(app, argc, argv); code >= 0) return code;
    try {
        const tom::File file = tom::open_any(path);  // an ordinary or a streamed .tom
        const std::vector<tom::Instance> instances = tom::draw_list(file.scene(), file.mesh_count());
        walk::Renderer renderer(width, height);
        // each mesh's level extracted once into the frame's index array, with a draw per part
        // (material); instances share it
        std::vector<uint32_t> handles, first(file.mesh_count()), counts(file.mesh_count());
        std::vector<std::vector<tom::PartDraw>> parts(file.mesh_count());
        std::vector<uint32_t> indices;
        uint64_t full = 0, drawn = 0;
        // each part's base-colour image (stored in the file, or a file beside it), drawn
        // texture-mapped where the mesh has texture coordinates
        std::vector<std::vector<int32_t>> part_images(file.mesh_count());
        std::map<std::string, int32_t> loaded;
        for (uint32_t i = 0; i < file.mesh_count(); ++i) {
            const tom::MeshView& m = file.mesh(i);
            handles.push_back(renderer.add_mesh(m));
            for (const walk::PartImage& image : walk::find_part_images(file, i, path))
                part_images[i].push_back(lod_colors || !m.texcoords ? -1 : walk::load_image(image, renderer, loaded));
            first[i] = uint32_t(indices.size());
            indices.resize(indices.size() + size_t(m.triangle_count) * 3);
            parts[i].resize(tom::part_count(m));
            const tom::Extracted e = tom::extract_parts(m, tom::vertex_count_for_fraction(m, fraction, below_floor ? tom::Floor::coarsest : tom::Floor::usable), indices.data() + first[i],
                                                        size_t(m.triangle_count) * 3, parts[i].data());
            counts[i] = e.triangle_count * 3;
            indices.resize(first[i] + counts[i]);
        }
        // the world bounds of every instance's box, for the camera
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        std::vector<walk::Renderer::Draw> draws;
        for (const tom::Instance& inst : instances) {
            const tom::MeshView& m = file.mesh(inst.mesh);
            for (int corner = 0; corner < 8; ++corner) {
                const float p[3] = {corner & 1 ? m.bounds_max[0] : m.bounds_min[0], corner & 2 ? m.bounds_max[1] : m.bounds_min[1],
                                    corner & 4 ? m.bounds_max[2] : m.bounds_min[2]};
                for (int k = 0; k < 3; ++k) {
                    const float w = inst.transform[k] * p[0] + inst.transform[4 + k] * p[1] + inst.transform[8 + k] * p[2] + inst.transform[12 + k];
                    lo[k] = std::min(lo[k], w), hi[k] = std::max(hi[k], w);
                }
            }
            for (uint32_t p = 0; p < parts[inst.mesh].size(); ++p) {
                const tom::PartDraw& part = parts[inst.mesh][p];
                walk::Renderer::Draw d{handles[inst.mesh], inst.transform, first[inst.mesh] + part.first_index, part.index_count, {0.7f, 0.7f, 0.7f}};
                if (part_images[inst.mesh][p] >= 0) d.shading = walk::Renderer::Shading::textured, d.image = uint32_t(part_images[inst.mesh][p]);
                if (lod_colors) {
                    const float t = m.triangle_count ? float(counts[inst.mesh] / 3) / float(m.triangle_count) : 1.0f;  // red coarse .. blue fine
                    d.color[0] = 1.0f - t, d.color[1] = 0.3f, d.color[2] = t;
                } else if (part.material >= 0 && size_t(part.material) < file.scene().materials.size()) {
                    for (int k = 0; k < 3; ++k) d.color[k] = file.scene().materials[size_t(part.material)].base_color[k];
                }
                draws.push_back(d);
            }
            full += m.triangle_count;
            drawn += counts[inst.mesh] / 3;
        }
        if (draws.empty()) throw tom::Error(path + ": nothing to draw");
        float centre[3], radius = 0;
        for (int k = 0; k < 3; ++k) centre[k] = 0.5f * (lo[k] + hi[k]), radius += 0.25f * (hi[k] - lo[k]) * (hi[k] - lo[k]);
        radius = std::max(1e-6f, std::sqrt(radius));
        const float eye[3] = {centre[0] + 1.3f * radius, centre[1] + 0.9f * radius, centre[2] + 1.8f * radius}, up[3] = {0, 1, 0};
        float view[16], projection[16];
        tcr::look_at(eye, centre, up, view);
        tcr::perspective(50.0f * 3.14159265f / 180.0f, float(width) / float(height), 0.05f * radius, 10.0f * radius, projection);
        const auto t0 = std::chrono::steady_clock::now();
        renderer.render(view, projection, draws, indices, indices.size());
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        if (!renderer.save_png(output)) throw tom::IoError("cannot write '" + output + "'");
        std::printf("%s: %zu instances of %u meshes, %zu materials; %llu of %llu triangles drawn (%.1f%%) in %.1f ms -> %s\n", path.c_str(),
                    instances.size(), file.mesh_count(), file.scene().materials.size(), static_cast<unsigned long long>(drawn),
                    static_cast<unsigned long long>(full), full ? 100.0 * double(drawn) / double(full) : 0.0, ms, output.c_str());
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
