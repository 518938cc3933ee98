// The builder on small hostile meshes: the bytes read as an OFF file (the importer's checks),
// cleaned, built with every strategy's code paths, written and read back. The writer must never
// produce a file the reader rejects, and the read file must extract in range.

#include <cstdint>
#include <vector>

#include "fuzz_support.h"
#include "tom/builder/builder.h"
#include "tom/builder/mesh.h"
#include "tom/builder/writer.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/io/import.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size > 4096) return 0;  // small meshes: the builder's logic, not its speed
    const std::string path = fuzz::as_file(data, size, "off");
    tom::ImportResult r;
    try {
        r = tom::import_file(path);
    } catch (const tom::Error&) {
        return 0;
    }
    for (tom::Mesh& m : r.meshes) {
        try {
            tom::clean_mesh(m);
        } catch (const tom::Error&) {
            continue;
        }
        if (m.vertex_count() > 512) continue;
        tom::BuildParams params;
        params.threads = 1;
        params.strategy = size % 3 == 0 ? tom::Strategy::heap : tom::Strategy::passes;
        params.predicate = size % 5 == 0 ? tom::Predicate::memoryless : tom::Predicate::quadric;
        params.pair_threshold = size % 7 == 0 ? 0.1f : 0.0f;
        const tom::TomMesh built = tom::build(m, params);
        const std::vector<uint8_t> bytes = tom::serialize({built});  // throws if the reader would reject it: a crash here
        const tom::File file = tom::File::from_bytes(bytes.data(), bytes.size(), "built.tom");
        const tom::MeshView& v = file.mesh(0);
        std::vector<uint32_t> out(size_t(v.triangle_count) * 3);
        for (uint32_t n = v.min_vertex_count; n <= v.vertex_count; ++n) {
            const tom::Extracted e = tom::extract(v, n, out.data(), out.size());
            for (size_t c = 0; c < size_t(e.triangle_count) * 3; ++c)
                if (out[c] >= e.vertex_count) __builtin_trap();
        }
    }
    return 0;
}
