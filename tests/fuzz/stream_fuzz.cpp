// The stream decoder on hostile bytes: fed in two pieces (the cut taken from the input), then
// everything a viewer does with what it decoded: the .tom of the prefix (validated by the
// reader), and extraction of every mesh at several resolutions. Nothing may read or write out
// of bounds, and the decoder may allocate only what the bytes received justify.

#include <cstdint>
#include <vector>

#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/stream.h"
#include "tom/stream/stream_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    tom::OpenOptions options;
    options.verify_checksums = size % 2 == 0;  // half the inputs reach the checks behind the checksums
    tom::StreamDecoder decoder(tom::meshopt_codecs(), "fuzz.tom", options);
    try {
        const size_t cut = size ? data[size - 1] * size / 256 : 0;
        decoder.append(data, cut);
        decoder.append(data + cut, size - cut);
    } catch (const tom::Error&) {
    }
    if (!decoder.has_directory()) return 0;
    try {
        const tom::File file = decoder.file();
        std::vector<uint32_t> indices;
        for (uint32_t i = 0; i < file.mesh_count(); ++i) {
            const tom::MeshView& m = file.mesh(i);
            indices.assign(size_t(m.triangle_count) * 3, 0);
            for (const uint32_t n : {m.min_vertex_count, m.vertex_count / 2, m.vertex_count}) {
                const tom::Extracted e = tom::extract(m, n, indices.data(), indices.size());
                for (size_t c = 0; c < size_t(e.triangle_count) * 3; ++c)
                    if (indices[c] >= e.vertex_count) __builtin_trap();  // an index past the level's vertices
            }
        }
    } catch (const tom::Error&) {
    }
    return 0;
}
