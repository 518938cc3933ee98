// The exporters on hostile .tom files: every file the reader accepts is written as OBJ (with its
// .mtl), PLY and binary glTF (plain and compressed) at its finest and coarsest resolutions. An
// exporter may refuse a file with tom::IoError, but never read out of bounds, loop by a count the file merely
// declares (a material index, a texture count) or allocate what the file's size cannot justify.

#include <cstdint>
#include <vector>

#include "fuzz_support.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/io/export.h"

namespace {

// One level of every mesh of `file` at `fraction` of its vertices, as export_meshes takes it.
std::vector<tom::ExportPart> level_of(const tom::File& file, double fraction) {
    std::vector<tom::ExportPart> parts;
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        const tom::MeshView& m = file.mesh(i);
        tom::ExportPart part;
        part.mesh = &m;
        part.indices.resize(size_t(m.triangle_count) * 3);
        part.draws.resize(tom::part_count(m));
        const tom::Extracted e = tom::extract_parts(m, tom::vertex_count_for_fraction(m, fraction), part.indices.data(), part.indices.size(), part.draws.data());
        part.vertex_count = e.vertex_count;
        part.indices.resize(size_t(e.triangle_count) * 3);
        if (!m.parts) part.draws.clear();
        parts.push_back(std::move(part));
    }
    return parts;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        const tom::File file = tom::File::from_bytes(data, size, "fuzz.tom");
        const std::string base = fuzz::folder() + "/out";
        for (const char* ext : {".obj", ".ply"}) {
            try {
                tom::export_meshes(base + ext, level_of(file, 0.0), file.scene(), fuzz::folder());
            } catch (const tom::IoError&) {
            }
        }
        std::vector<tom::GlbMesh> meshes;
        for (uint32_t i = 0; i < file.mesh_count(); ++i) meshes.push_back({&file.mesh(i), {file.mesh(i).vertex_count, file.mesh(i).min_vertex_count}});
        for (const bool compress : {false, true}) {  // plain, and quantized and compressed (tomextract -c)
            try {
                tom::export_glb(base + ".glb", meshes, file.scene(), fuzz::folder(), false, compress);
            } catch (const tom::IoError&) {
            }
        }
    } catch (const tom::FormatError&) {
    }
    return 0;
}
