// The .tom reader on hostile bytes: open from memory, then everything an engine does with a file
// it accepted: extraction at several resolutions into 32- and 16-bit buffers (from the coarse
// corners too), the scene's draw list, the stored error curve and its estimates, geomorphs, and
// every byte of the carried streams, stored images and stored glTF scene it hands out.
// A file the reader accepts must never make any of these read or write out of bounds.

#include <cstdint>
#include <vector>

#include "tom/error_curve.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        tom::OpenOptions options;
        options.verify_checksums = size % 2 == 0;  // half the inputs reach the structural rules past a broken checksum
        const tom::File file = tom::File::from_bytes(data, size, "fuzz.tom", options);
        std::vector<uint32_t> wide;
        std::vector<uint16_t> narrow;
        std::vector<tom::PartDraw> draws;
        for (uint32_t i = 0; i < file.mesh_count(); ++i) {
            const tom::MeshView& m = file.mesh(i);
            wide.assign(size_t(m.triangle_count) * 3, 0);
            const uint32_t ns[] = {0, m.min_vertex_count, m.coarse_resolution / 2, m.coarse_resolution, m.coarse_resolution + 1, m.vertex_count / 2,
                                   m.vertex_count, tom::vertex_count_for_fraction(m, 0.1), tom::vertex_count_for_triangles(m, 7)};
            for (const uint32_t n : ns) {
                const tom::Extracted e = tom::extract(m, n, wide.data(), wide.size());
                for (size_t c = 0; c < size_t(e.triangle_count) * 3; ++c)
                    if (wide[c] >= e.vertex_count) __builtin_trap();  // an index past the level's vertices
                if (m.vertex_count <= 65536) {
                    narrow.assign(wide.size(), 0);
                    tom::extract(m, n, narrow.data(), narrow.size());
                }
                if (n < m.vertex_count) (void)tom::geomorph(m, n, 0.5f);
                // the parts' draws tile the same level, each within its part
                draws.assign(tom::part_count(m), {});
                const tom::Extracted p = tom::extract_parts(m, n, wide.data(), wide.size(), draws.data());
                uint64_t next = 0;
                for (uint32_t k = 0; k < draws.size(); ++k) {
                    if (draws[k].first_index != next || draws[k].index_count > 3 * uint64_t(tom::part_at(m, k).triangle_count)) __builtin_trap();
                    next += draws[k].index_count;
                }
                if (next != 3 * uint64_t(p.triangle_count) || p.triangle_count != e.triangle_count) __builtin_trap();
            }
            if (const auto curve = tom::read_error_curve(m)) {
                for (const double t : {0.0, 1.0, 100.0, double(m.triangle_count), 1e9})
                    if (!(tom::estimate_error(*curve, t) >= 0)) __builtin_trap();  // never negative, never NaN
            }
        }
        for (const tom::Instance& inst : tom::draw_list(file.scene(), file.mesh_count()))
            if (inst.mesh >= file.mesh_count()) __builtin_trap();
        // every byte the reader hands out in place lies inside the input (ASan reports a read past it)
        volatile uint8_t sink = 0;
        for (uint32_t i = 0; i < file.mesh_count(); ++i) {
            const tom::MeshView& m = file.mesh(i);
            for (uint32_t k = 0; k < m.extra_stream_count; ++k) {
                const tom::VertexStreamView& x = m.extra_streams[k];
                const size_t bytes = size_t(m.vertex_count) * x.components * tom::component_bytes(x.component_type);
                for (size_t b = 0; b < bytes; ++b) sink = sink ^ x.data[b];
            }
        }
        for (const tom::Image& image : file.scene().images)
            for (uint64_t b = 0; b < image.bytes; ++b) sink = sink ^ image.data[b];
        for (uint64_t b = 0; b < file.scene().gltf.bytes; ++b) sink = sink ^ file.scene().gltf.data[b];
        for (const tom::Material& material : file.scene().materials)
            for (const tom::TextureRef& t : material.textures)
                if (t.image >= int32_t(file.scene().images.size())) __builtin_trap();
    } catch (const tom::FormatError&) {
    }
    return 0;
}
