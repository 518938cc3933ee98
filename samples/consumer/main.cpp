// Maps a .tom file and prints, per mesh, the index count at 10% of its triangles.
// Usage: tom_consumer FILE.tom

#include <cstdio>
#include <vector>

#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s FILE.tom\n", argv[0]);
        return 2;
    }
    try {
        const tom::File file = tom::File::open(argv[1]);  // mapped in place and validated
        for (uint32_t i = 0; i < file.mesh_count(); ++i) {
            const tom::MeshView& mesh = file.mesh(i);
            std::vector<uint32_t> indices(size_t(mesh.triangle_count) * 3);  // once; reused every frame
            const uint32_t n = tom::vertex_count_for_fraction(mesh, 0.10);
            const tom::Extracted level = tom::extract(mesh, n, indices.data(), indices.size());
            // draw: vertices [0, level.vertex_count) of mesh.positions/normals, level.triangle_count * 3 indices
            std::printf("%.*s: %u vertices, %u triangles; at 10%%: %u vertices, %u triangles, %u indices\n", int(mesh.name.size()),
                        mesh.name.data(), mesh.vertex_count, mesh.triangle_count, level.vertex_count, level.triangle_count,
                        level.triangle_count * 3);
        }
        return 0;
    } catch (const tom::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
