// tomextract: writes a .tom file's meshes at one resolution as OBJ (with a .mtl and a usemtl
// group per part) or PLY, or at one or more resolutions as binary glTF with the file's materials
// and instances (a primitive per part).

#include <cstdio>
#include <filesystem>
#include <optional>

#include "tom/errors.h"
#include "tom/io/export.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tool_common.h"

int main(int argc, char** argv) {
    std::string path, output;
    std::optional<double> fraction;
    std::optional<uint64_t> triangles, vertices;
    std::optional<uint32_t> mesh_index;
    CLI::App app{"tomextract: write the meshes of a .tom file at one resolution as OBJ or PLY"};
    app.set_version_flag("--version", "tomextract 0.1.0");
    app.add_option("file", path, "A .tom file")->required();
    auto* f = app.add_option("-f,--fraction", fraction, "Fraction of each mesh's triangles, in [0,1]")->check(CLI::Range(0.0, 1.0));
    auto* t = app.add_option("-t,--triangles", triangles, "Triangle count (for several meshes: in total, shared in proportion)");
    auto* v = app.add_option("-n,--vertices", vertices, "Vertex count (per mesh, clamped to its range)");
    f->excludes(t)->excludes(v);
    t->excludes(v);
    std::vector<double> lods;
    auto* l = app.add_option("--lods", lods, "Levels in % of the triangles, finest first, into one .glb with MSFT_lod (e.g. 100,50,25,10)")
                  ->delimiter(',')
                  ->check(CLI::Range(0.0, 100.0));
    l->excludes(f)->excludes(t)->excludes(v);
    app.add_option("-m,--mesh", mesh_index, "Only this mesh (index as tominfo lists it); default: all meshes in one file");
    app.add_option("-o,--output", output, "Output .obj, .ply or .glb (binary glTF, with the file's materials and instances)")->required();
    std::string texture_dir;
    app.add_option("--texture-dir", texture_dir,
                   "For .glb and .obj: the folder the stored texture URIs are relative to (the source asset's); they are rewritten relative to the output");
    bool embed_images = false;
    app.add_flag("--embed-images", embed_images,
                 "For .glb: also embed the images that are files (read from --texture-dir); images stored in the .tom are always embedded");
    app.footer("Exit codes: 0 ok, 1 unreadable input or unwritable output, 2 usage error.\n"
               "Examples: tomextract out/bunny00.tom --fraction 0.1 -o bunny10.obj\n"
               "          tomextract out/bunny00.tom --lods 100,50,25,10 -o bunny-lods.glb");
    if (const int code = tools::parse(app, argc, argv); code >= 0) return code;
    if (!fraction && !triangles && !vertices && lods.empty()) {
        std::fprintf(stderr, "error: give one of --fraction, --triangles, --vertices or --lods\n");
        return tools::exit_usage;
    }
    auto is_glb = [&] { return output.size() > 4 && (output.substr(output.size() - 4) == ".glb" || output.substr(output.size() - 4) == ".GLB"); };
    if (embed_images && !is_glb()) {
        std::fprintf(stderr, "error: --embed-images writes images into a .glb; '%s' is not one\n", output.c_str());
        return tools::exit_usage;
    }
    if (!lods.empty() && !is_glb()) {
        std::fprintf(stderr, "error: --lods writes a .glb (MSFT_lod); '%s' is not one\n", output.c_str());
        return tools::exit_usage;
    }
    try {
        const tom::File file = tom::File::open(path);
        if (const std::filesystem::path parent = std::filesystem::path(output).parent_path(); !parent.empty()) {
            std::error_code ec;
            std::filesystem::create_directories(parent, ec);  // a failure shows when the file is written
        }
        if (mesh_index && *mesh_index >= file.mesh_count()) {
            std::fprintf(stderr, "error: %s has %u meshes; --mesh %u does not exist\n", path.c_str(), file.mesh_count(), *mesh_index);
            return tools::exit_usage;
        }
        uint64_t total_tris = 0;
        for (uint32_t i = 0; i < file.mesh_count(); ++i)
            if (!mesh_index || *mesh_index == i) total_tris += file.mesh(i).triangle_count;
        if (is_glb()) {
            std::vector<tom::GlbMesh> glb;
            uint64_t written = 0;
            tom::Scene scene = file.scene();  // with --mesh: that mesh's instances, renumbered
            if (mesh_index) {
                scene.gltf = tom::SourceGltf{};  // the source's node tree names every mesh: one mesh gets its instances' nodes
                std::vector<tom::Instance> kept;
                for (tom::Instance inst : scene.instances)
                    if (inst.mesh == *mesh_index) inst.mesh = 0, kept.push_back(inst);
                scene.instances.swap(kept);
            }
            for (uint32_t i = 0; i < file.mesh_count(); ++i) {
                if (mesh_index && *mesh_index != i) continue;
                const tom::MeshView& m = file.mesh(i);
                tom::GlbMesh g;
                g.mesh = &m;
                if (!lods.empty()) {
                    for (double pct : lods) g.vertex_counts.push_back(tom::vertex_count_for_fraction(m, pct / 100.0));
                } else if (fraction) {
                    g.vertex_counts.push_back(tom::vertex_count_for_fraction(m, *fraction));
                } else if (triangles) {
                    g.vertex_counts.push_back(tom::vertex_count_for_fraction(m, total_tris ? double(*triangles) / double(total_tris) : 1.0));
                } else {
                    g.vertex_counts.push_back(uint32_t(std::min<uint64_t>(*vertices, m.vertex_count)));
                }
                written += tom::active_triangle_count(m, g.vertex_counts.front());
                glb.push_back(g);
            }
            tom::export_glb(output, glb, scene, texture_dir, embed_images);
            std::printf("%s: %zu mesh%s, %zu level%s, %llu triangles at the finest, %zu material%s, %zu instance%s -> %s\n", path.c_str(), glb.size(),
                        glb.size() == 1 ? "" : "es", lods.empty() ? size_t(1) : lods.size(), lods.size() > 1 ? "s" : "",
                        static_cast<unsigned long long>(written), scene.materials.size(), scene.materials.size() == 1 ? "" : "s",
                        tom::draw_list(scene, uint32_t(glb.size())).size(), tom::draw_list(scene, uint32_t(glb.size())).size() == 1 ? "" : "s",
                        output.c_str());
            return tools::exit_ok;
        }
        std::vector<tom::ExportPart> parts;
        uint64_t out_tris = 0, out_verts = 0;
        for (uint32_t i = 0; i < file.mesh_count(); ++i) {
            if (mesh_index && *mesh_index != i) continue;
            const tom::MeshView& m = file.mesh(i);
            uint32_t n;
            if (fraction)
                n = tom::vertex_count_for_fraction(m, *fraction);
            else if (triangles)
                n = tom::vertex_count_for_fraction(m, total_tris ? double(*triangles) / double(total_tris) : 1.0);
            else
                n = uint32_t(std::min<uint64_t>(*vertices, m.vertex_count));
            tom::ExportPart part;
            part.mesh = &m;
            part.indices.resize(size_t(tom::active_triangle_count(m, n)) * 3);
            part.draws.resize(tom::part_count(m));
            const tom::Extracted r = tom::extract_parts(m, n, part.indices.data(), part.indices.size(), part.draws.data());
            part.vertex_count = r.vertex_count;
            part.indices.resize(size_t(r.triangle_count) * 3);
            out_tris += r.triangle_count;
            out_verts += r.vertex_count;
            parts.push_back(std::move(part));
        }
        tom::export_meshes(output, parts, file.scene(), texture_dir);
        std::printf("%s: %zu mesh%s, %llu vertices, %llu triangles (%.2f%% of %llu) -> %s\n", path.c_str(), parts.size(),
                    parts.size() == 1 ? "" : "es", static_cast<unsigned long long>(out_verts), static_cast<unsigned long long>(out_tris),
                    total_tris ? 100.0 * double(out_tris) / double(total_tris) : 0.0, static_cast<unsigned long long>(total_tris), output.c_str());
        return tools::exit_ok;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}
