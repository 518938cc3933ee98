// A whole scene as an engine draws it: every instance of the file's scene (a glTF's node tree;
// without one, each mesh once, untransformed), and of its mesh every part (one material each)
// at a fraction of its triangles. Prints one line per draw.
// Usage: tom_scene FILE.tom [FRACTION]

#include <cstdio>
#include <cstdlib>
#include <vector>

#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/scene.h"

int main(int argc, char** argv) {
    if (argc != 2 && argc != 3) {
        std::fprintf(stderr, "usage: %s FILE.tom [FRACTION]\n", argv[0]);
        return 2;
    }
    try {
        const tom::File file = tom::File::open(argv[1]);
        const double fraction = argc == 3 ? std::atof(argv[2]) : 0.10;
        std::vector<uint32_t> indices;
        std::vector<tom::PartDraw> draws;
        for (const tom::Instance& inst : tom::draw_list(file.scene(), file.mesh_count())) {
            const tom::MeshView& m = file.mesh(inst.mesh);
            indices.resize(size_t(m.triangle_count) * 3);
            draws.resize(tom::part_count(m));
            const uint32_t n = tom::vertex_count_for_fraction(m, fraction);
            const tom::Extracted e = tom::extract_parts(m, n, indices.data(), indices.size(), draws.data());
            for (const tom::PartDraw& d : draws) {
                const tom::Material* material = d.material >= 0 ? &file.scene().materials[size_t(d.material)] : nullptr;
                std::printf("mesh %u at (%g, %g, %g): vertices [0, %u), indices [%u, +%u), material %s\n", inst.mesh, inst.transform[12],
                            inst.transform[13], inst.transform[14], e.vertex_count, d.first_index, d.index_count,
                            material ? ("'" + material->name + "'").c_str() : "none");
            }
        }
        return 0;
    } catch (const tom::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
