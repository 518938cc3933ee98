// A broken precondition (\pre) is caught where the libraries assert it (debug and sanitizer
// builds): each case breaks one and must abort with the assertion's message; ctest expects it.
// Usage: precondition_test CASE   (mesh, part, set_transform)

#include <cstdio>
#include <cstring>
#include <vector>

#include "tcr/runtime.h"
#include "tom/builder/generate.h"
#include "tom/builder/mesh.h"
#include "tom/builder/builder.h"
#include "tom/builder/writer.h"
#include "tom/extract.h"
#include "tom/format.h"

int main(int argc, char** argv) {
    if (argc != 2) return 2;
    tom::Mesh sphere = tom::make_sphere(6, 6);
    tom::clean_mesh(sphere);
    const std::vector<uint8_t> bytes = tom::serialize({tom::build(std::move(sphere))});
    const tom::File file = tom::File::from_bytes(bytes.data(), bytes.size());
    if (std::strcmp(argv[1], "mesh") == 0) {
        std::printf("%u\n", file.mesh(1).vertex_count);  // a file of one mesh
    } else if (std::strcmp(argv[1], "part") == 0) {
        std::printf("%u\n", tom::part_at(file.mesh(0), 1).triangle_count);  // a mesh of one part
    } else if (std::strcmp(argv[1], "set_transform") == 0) {
        tcr::Runtime rt(tcr::CostModel{}, tcr::SelectorKind::exact);
        const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        rt.add_object(file.mesh(0), identity);
        rt.set_transform(1, identity);  // one object: id 0
    }
    std::printf("no assertion\n");
    return 0;
}
