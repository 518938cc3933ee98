// The C API (tom/tom.h) on hostile bytes: tom_file_open_memory borrows them, then every call an
// engine makes on a file it accepted: each mesh's view, the resolution queries, extraction in
// both widths into exact, short and empty buffers, geomorphs, materials and instances. Nothing
// may read or write out of bounds, and every status must be one the header names.

#include <cstdint>
#include <cstring>
#include <vector>

#include "tom/tom.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    tom_file* file = nullptr;
    if (tom_file_open_memory(data, size, "fuzz.tom", &file) != TOM_OK) {
        if (file || tom_last_error()[0] == '\0') __builtin_trap();  // a failure leaves no file and says why
        return 0;
    }
    std::vector<uint32_t> wide;
    std::vector<uint16_t> narrow;
    volatile uint8_t sink = 0;  // the first and last byte of everything handed out in place
    for (uint32_t i = 0; i < tom_file_mesh_count(file); ++i) {
        tom_mesh_view m;
        if (tom_file_mesh(file, i, &m) != TOM_OK) __builtin_trap();
        wide.assign(size_t(m.triangle_count) * 3 + 1, 0);
        narrow.assign(size_t(m.triangle_count) * 3 + 1, 0);
        const uint32_t ns[] = {0, m.min_vertex_count, m.vertex_count / 2, m.vertex_count, tom_vertex_count_for_fraction(&m, 0.1),
                               tom_vertex_count_for_triangles(&m, 5)};
        for (const uint32_t n : ns) {
            tom_extracted e;
            const size_t capacities[] = {size_t(m.triangle_count) * 3, size_t(tom_active_triangle_count(&m, n)) * 3, size % 7, 0};
            for (const size_t capacity : capacities) {
                const tom_status s = tom_extract_u32(&m, n, wide.data(), capacity, &e);
                if (s == TOM_OK) {
                    if (size_t(e.triangle_count) * 3 > capacity) __builtin_trap();
                    for (size_t c = 0; c < size_t(e.triangle_count) * 3; ++c)
                        if (wide[c] >= e.vertex_count) __builtin_trap();
                } else if (s != TOM_ERROR_CAPACITY) {
                    __builtin_trap();
                }
                const tom_status s16 = tom_extract_u16(&m, n, narrow.data(), capacity, &e);
                if (s16 == TOM_OK)
                    for (size_t c = 0; c < size_t(e.triangle_count) * 3; ++c)
                        if (narrow[c] >= e.vertex_count) __builtin_trap();
            }
        }
        tom_morphed_vertex v;
        if (m.vertex_count > m.min_vertex_count && tom_geomorph(&m, m.min_vertex_count, 0.5f, &v) != TOM_OK) __builtin_trap();
        for (uint32_t k = 0; k < tom_mesh_carried_stream_count(&m); ++k) {
            tom_carried_stream x;
            if (tom_mesh_carried_stream(&m, k, &x) != TOM_OK || x.components < 1 || x.components > 4 || x.name_bytes == 0) __builtin_trap();
            const uint8_t* bytes = static_cast<const uint8_t*>(x.data);
            if (m.vertex_count > 0) sink = sink ^ bytes[0] ^ bytes[size_t(m.vertex_count) * x.components * (x.component_type == 5126 || x.component_type == 5125 ? 4 : x.component_type >= 5122 ? 2 : 1) - 1];
        }
    }
    for (uint32_t i = 0; i < tom_file_image_count(file); ++i) {
        tom_image image;
        if (tom_file_image(file, i, &image) != TOM_OK || image.mime_type[0] == '\0') __builtin_trap();
        if (image.bytes > 0) sink = sink ^ image.data[0] ^ image.data[image.bytes - 1];
    }
    for (uint32_t i = 0; i < tom_file_material_count(file); ++i) {
        tom_material mat;
        if (tom_file_material(file, i, &mat) != TOM_OK) __builtin_trap();
        for (uint32_t t = 0; t < mat.texture_count; ++t)
            if (std::strlen(mat.textures[t].uri) > size) __builtin_trap();
    }
    for (uint32_t i = 0; i < tom_file_instance_count(file); ++i) {
        tom_instance inst;
        if (tom_file_instance(file, i, &inst) != TOM_OK || inst.mesh >= tom_file_mesh_count(file)) __builtin_trap();
    }
    tom_file_close(file);
    return 0;
}
