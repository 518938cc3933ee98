// Maps a .tom file and prints, per mesh, the index count at 10% of its triangles; with a
// fraction, prints instead the first mesh's triangles at that fraction as OBJ faces (1-based),
// the lines tomextract writes.
// Usage: tom_consumer FILE.tom [FRACTION]

#include <cstdio>
#include <cstdlib>
#include <vector>

#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"

int main(int argc, char** argv) {
    if (argc != 2 && argc != 3) {
        std::fprintf(stderr, "usage: %s FILE.tom [FRACTION]\n", argv[0]);
        return 2;
    }
    try {
        const tom::File file = tom::File::open(argv[1]);  // mapped in place and validated
        const double fraction = argc == 3 ? std::atof(argv[2]) : 0.10;
        for (uint32_t i = 0; i < file.mesh_count(); ++i) {
            const tom::MeshView& mesh = file.mesh(i);
            std::vector<uint32_t> indices(size_t(mesh.triangle_count) * 3);  // once; reused every frame
            const uint32_t n = tom::vertex_count_for_fraction(mesh, fraction);
            const tom::Extracted level = tom::extract(mesh, n, indices.data(), indices.size());
            // draw: vertices [0, level.vertex_count) of mesh.positions/normals, level.triangle_count * 3 indices
            if (argc == 3) {
                for (uint32_t t = 0; t < level.triangle_count; ++t)
                    std::printf("f %u//%u %u//%u %u//%u\n", indices[3 * t] + 1, indices[3 * t] + 1, indices[3 * t + 1] + 1, indices[3 * t + 1] + 1,
                                indices[3 * t + 2] + 1, indices[3 * t + 2] + 1);
                return 0;
            }
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
