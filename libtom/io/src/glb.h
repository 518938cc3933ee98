#pragma once
// The binary glTF container (glTF 2.0 specification, "GLB File Format"): what the exporter
// writes and the EXT_meshopt_compression preparation rewrites. Private to tom::io.

#include <cstdint>
#include <string>
#include <vector>

namespace tom::detail {

inline uint32_t le32(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24; }

/// The chunk after a GLB's JSON chunk (the BIN chunk, when the file is well formed), as an
/// offset and a length in `glb`, and its type; found is false when there is none or it runs
/// past the end. \pre `glb` holds at least the 20 bytes of the headers.
struct GlbChunk {
    bool found = false;
    size_t offset = 0, length = 0;
    uint32_t type = 0;
};
inline GlbChunk glb_second_chunk(const std::vector<uint8_t>& glb) {
    GlbChunk c;
    const size_t at = 20 + size_t(le32(&glb[12]));
    if (at < 20 || at + 8 > glb.size()) return c;
    c.length = le32(&glb[at]);
    if (c.length > glb.size() - at - 8) return c;
    c.type = le32(&glb[at + 4]);
    c.offset = at + 8;
    c.found = true;
    return c;
}
constexpr uint32_t kGlbBin = 0x004E4942u;

/// A GLB file: the 12-byte header, the JSON chunk (padded with spaces to 4 bytes) and, when
/// `bin` is given, the BIN chunk (padded with zeros to 4 bytes).
inline std::vector<uint8_t> glb_bytes(std::string json, const std::vector<uint8_t>* bin) {
    while (json.size() % 4) json.push_back(' ');
    const size_t bin_padded = bin ? (bin->size() + 3) / 4 * 4 : 0;
    std::vector<uint8_t> out = {'g', 'l', 'T', 'F'};
    out.reserve(12 + 8 + json.size() + (bin ? 8 + bin_padded : 0));
    auto put32 = [&](uint32_t v) {
        for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
    };
    put32(2);
    put32(uint32_t(12 + 8 + json.size() + (bin ? 8 + bin_padded : 0)));
    put32(uint32_t(json.size()));
    put32(0x4E4F534Au);  // JSON
    out.insert(out.end(), json.begin(), json.end());
    if (bin) {
        put32(uint32_t(bin_padded));
        put32(kGlbBin);
        out.insert(out.end(), bin->begin(), bin->end());
        out.resize(out.size() + (bin_padded - bin->size()), 0);
    }
    return out;
}

} // namespace tom::detail
