// One mesh importer on hostile bytes (compiled once per format: TOM_FUZZ_EXTENSION names it):
// the bytes as a file of that extension, imported, then cleaned as tombuild does. A bad file
// must give an MeshError, never a crash, a hang or an allocation the input cannot justify.
// An OBJ input may carry its material library: the bytes after a line "@mtl" are the file
// input.mtl beside it (which `mtllib input.mtl` names).

#include <cstdint>
#include <cstring>
#include <string_view>

#include "fuzz_support.h"
#include "tom/builder/mesh.h"
#include "tom/errors.h"
#include "tom/io/import.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (std::strcmp(TOM_FUZZ_EXTENSION, "obj") == 0) {
        const std::string_view all(reinterpret_cast<const char*>(data), size);
        const size_t at = all.find("\n@mtl\n");
        const std::string_view library = at == std::string_view::npos ? std::string_view() : all.substr(at + 6);
        fuzz::as_file(reinterpret_cast<const uint8_t*>(library.data()), library.size(), "mtl");
        if (at != std::string_view::npos) size = at + 1;
    }
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
