// One mesh importer on hostile bytes (compiled once per format: TOM_FUZZ_EXTENSION names it):
// the bytes as a file of that extension, imported, then cleaned as tombuild does. A bad file
// must give an ImportError, never a crash, a hang or an allocation the input cannot justify.

#include <cstdint>

#include "fuzz_support.h"
#include "tom/builder/mesh.h"
#include "tom/errors.h"
#include "tom/io/import.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = fuzz::as_file(data, size, TOM_FUZZ_EXTENSION);
    try {
        tom::ImportResult r = tom::import_file(path);
        for (tom::Mesh& m : r.meshes) {
            tom::clean_mesh(m);
            for (const uint32_t i : m.indices)
                if (i >= m.vertex_count()) __builtin_trap();  // a cleaned mesh's indices are in range
        }
    } catch (const tom::Error&) {
    }
    return 0;
}
