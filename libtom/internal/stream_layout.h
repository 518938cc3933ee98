#pragma once
// Byte layout and quantization of streamed .tom files (docs/FORMAT.md, "Streamed files"), shared
// by the encoder (tom::stream) and the decoder (the runtime's tom::StreamDecoder). Every function
// here is the one definition both sides use, so that the decoder rebuilds exactly the values the
// encoder predicted from.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <type_traits>
#include <vector>

#include "format_layout.h"

namespace tom::stream_layout {

constexpr uint8_t magic[8] = {0x89, 'T', 'O', 'S', 0x0D, 0x0A, 0x1A, 0x0A};
constexpr uint32_t version_major = 1, version_minor = 3;
constexpr uint32_t header_bytes = 64;
// header field offsets
constexpr uint32_t h_version_major = 8, h_version_minor = 12, h_file_bytes = 16, h_mesh_count = 24, h_chunk_count = 28,
                   h_directory_bytes = 32, h_directory_checksum = 40, h_header_checksum = 44;

constexpr uint32_t directory_header_bytes = 16;  // u32 kept_count, deferred_count, deferred_after, deferred_checksum
// directory header field offsets (the deferred fields since 1.1: zero in 1.0)
constexpr uint32_t d_kept_count = 0, d_deferred_count = 4, d_deferred_after = 8, d_deferred_checksum = 12;
constexpr uint32_t kept_entry_bytes = 16;         // u32 type, u32 mesh, u64 bytes
constexpr uint32_t quantization_bytes = 64;       // per mesh, below
constexpr uint32_t chunk_record_bytes = 24;       // u32 mesh, vertex_end, triangle_end, reserved, bytes, checksum
// quantization record field offsets
constexpr uint32_t q_position_bits = 0, q_normal_bits = 4, q_texcoord_bits = 8, q_position_min = 16, q_position_step = 28,
                   q_texcoord0_min = 32, q_texcoord0_step = 40, q_texcoord1_min = 48, q_texcoord1_step = 56;
// chunk record field offsets (1.0 and 1.1; since 1.2 the table is compact, below)
constexpr uint32_t r_mesh = 0, r_vertex_end = 4, r_triangle_end = 8, r_bytes = 16, r_checksum = 20;
constexpr uint32_t compact_record_min_bytes = 8;  // four one-byte varints and the checksum

/// A chunk's record in the directory's chunk table.
struct ChunkRecord {
    uint32_t mesh = 0, vertex_end = 0, triangle_end = 0, bytes = 0, checksum = 0;
};

/// An unsigned LEB128 varint: seven bits a byte, low first, the high bit set on every byte but
/// the last.
inline void put_varint(std::vector<uint8_t>& out, uint32_t v) {
    for (; v >= 0x80; v >>= 7) out.push_back(uint8_t(v | 0x80));
    out.push_back(uint8_t(v));
}
/// The varint at data[at] (at moves past it); false when it runs past `size` or holds more than
/// 32 bits.
inline bool get_varint(const uint8_t* data, uint64_t size, uint64_t& at, uint32_t& v) {
    uint64_t value = 0;
    for (int shift = 0; shift < 35 && at < size; shift += 7) {
        const uint8_t b = data[at++];
        value |= uint64_t(b & 0x7F) << shift;
        if (!(b & 0x80)) {
            v = uint32_t(value);
            return value <= UINT32_MAX;
        }
    }
    return false;
}

/// The compact chunk table (since 1.2): per chunk, varints of its mesh, its vertex_end less the
/// previous vertex_end of its mesh (0 before the first), its triangle_end less the previous
/// triangle_end of its mesh, its bytes, then its checksum as a u32: about 11 bytes a chunk where
/// 1.0 and 1.1 records take 24, and the table stands before the first frame.
inline void put_chunk_table(std::vector<uint8_t>& out, const std::vector<ChunkRecord>& records, uint32_t mesh_count) {
    std::vector<ChunkRecord> last(mesh_count);
    for (const ChunkRecord& r : records) {
        put_varint(out, r.mesh);
        put_varint(out, r.vertex_end - last[r.mesh].vertex_end);
        put_varint(out, r.triangle_end - last[r.mesh].triangle_end);
        put_varint(out, r.bytes);
        for (int k = 0; k < 4; ++k) out.push_back(uint8_t(r.checksum >> (8 * k)));
        last[r.mesh] = r;
    }
}

/// File-level sections no frame needs to draw (provenance, embedded images, the source's glTF
/// scene): since 1.1 they travel in the deferred block after every mesh's first chunk, so that the
/// first frame does not wait for a textured asset's images.
inline bool deferrable(uint32_t type) { return type == layout::sec_provenance || type == layout::sec_images || type == layout::sec_source_gltf; }

/// Element sizes of the quantized blocks (the meshopt vertex codec takes multiples of 4).
constexpr uint32_t position_element = 8;     // u16 x, y, z, 0: residuals against the prediction
constexpr uint32_t normal_element = 4;       // i16 octahedral u, v: residuals
constexpr uint32_t texcoord_element = 4;     // u16 u, v: residuals
constexpr uint32_t color_element = 4;        // u8 r, g, b, a: residuals
constexpr uint32_t tangent_element = 8;      // i16 octahedral u, v: residuals; i16 w (+1 or -1 as stored); 0
constexpr uint32_t rotation_element = 4;     // u8 per triangle: turns of its decoded corners (0 to 2)

/// Carried (XATT) elements travel raw, padded to a multiple of 4 bytes.
inline uint32_t padded_element(uint32_t element_bytes) { return (element_bytes + 3) / 4 * 4; }

/// Grid of `bits` bits over [min, min + extent]: the step between grid values.
inline float grid_step(float extent, uint32_t bits) {
    const float steps = float((1u << bits) - 1);
    return extent > 0 ? extent / steps : 1.0f;
}
/// The grid value nearest to x (clamped to the grid).
inline uint32_t quantize(float x, float min, float step, uint32_t bits) {
    const double q = std::nearbyint((double(x) - double(min)) / double(step));
    return uint32_t(std::clamp(q, 0.0, double((1u << bits) - 1)));
}
/// The value of grid point q: computed in double and rounded once, so every platform agrees.
inline float dequantize(uint32_t q, float min, float step) { return float(double(min) + double(q) * double(step)); }

/// Octahedral encoding of a unit vector to two signed integers of `bits` bits (at most 16).
inline void octahedral_encode(const float* n, uint32_t bits, int16_t out[2]) {
    const float len = std::fabs(n[0]) + std::fabs(n[1]) + std::fabs(n[2]);
    float u = len > 0 ? n[0] / len : 1.0f, v = len > 0 ? n[1] / len : 0.0f;
    if (len > 0 && n[2] < 0) {
        const float fu = (1 - std::fabs(v)) * (u >= 0 ? 1.0f : -1.0f), fv = (1 - std::fabs(u)) * (v >= 0 ? 1.0f : -1.0f);
        u = fu, v = fv;
    }
    const float scale = float((1 << (bits - 1)) - 1);
    out[0] = int16_t(std::nearbyint(std::clamp(u, -1.0f, 1.0f) * scale));
    out[1] = int16_t(std::nearbyint(std::clamp(v, -1.0f, 1.0f) * scale));
}
/// The unit vector of an octahedral pair (any pair of values decodes to a unit vector).
inline void octahedral_decode(int16_t qu, int16_t qv, uint32_t bits, float* n) {
    const float scale = float((1 << (bits - 1)) - 1);
    float u = std::clamp(float(qu) / scale, -1.0f, 1.0f), v = std::clamp(float(qv) / scale, -1.0f, 1.0f);
    float z = 1 - std::fabs(u) - std::fabs(v);
    if (z < 0) {
        const float fu = (1 - std::fabs(v)) * (u >= 0 ? 1.0f : -1.0f), fv = (1 - std::fabs(u)) * (v >= 0 ? 1.0f : -1.0f);
        u = fu, v = fv;
    }
    const float len = std::sqrt(u * u + v * v + z * z);
    n[0] = u / len, n[1] = v / len, n[2] = z / len;
}

/// Residuals travel zigzag-coded (0, -1, 1, -2, ... as 0, 1, 2, 3, ...), so that small ones of
/// either sign have their high bits clear, which the vertex codec packs.
template <class T>
T zigzag(T r) {
    using U = std::make_unsigned_t<T>;
    const U u = U(r);
    constexpr int top = int(sizeof(T) * 8 - 1);
    return T(U(u << 1) ^ U(0 - U(u >> top)));
}
template <class T>
T unzigzag(T z) {
    using U = std::make_unsigned_t<T>;
    const U u = U(z);
    return T(U(u >> 1) ^ U(0 - U(u & 1u)));
}

/// An attribute block's prediction (the u32 before it): bit 0 says what predicts (0 the
/// substitute's values, 1 the neighbours' mean), bit 1 (since 1.2) how the residuals travel:
/// zigzag-coded (clear), or in byte form with their lanes summed (set, below).
constexpr uint32_t predict_neighbours = 1, predict_byte_form = 2, prediction_count = 4;

/// The byte form of a residual (since 1.2): its value as signed bytes, low first, each in
/// [-128, 127] (the last takes what is left, modulo the lane's width), so that a small residual of
/// either sign has small bytes and zero high bytes. A block sums each byte lane over its elements
/// (sum_lanes), so that the vertex codec, which codes each byte as the difference from the one
/// before, codes the residual's own bytes; a zigzag-coded block makes it code the difference of
/// two residuals, about twice as large.
template <class T>
void residual_to_bytes(T r, uint8_t* out) {
    int64_t x = int64_t(std::make_signed_t<T>(r));
    for (size_t j = 0; j < sizeof(T); ++j) {
        const int8_t low = int8_t(uint8_t(x & 0xFF));
        out[j] = uint8_t(low);
        x = (x - low) / 256;
    }
}
template <class T>
T residual_from_bytes(const uint8_t* in) {
    using U = std::make_unsigned_t<T>;
    U r = 0;
    for (size_t j = sizeof(T); j-- > 0;) r = U(U(r << 8) + U(int64_t(int8_t(in[j]))));
    return T(r);
}
/// The byte lanes [0, width) of `count` elements `stride` bytes apart, each summed over the
/// elements (modulo 256), in place; and back.
inline void sum_lanes(uint8_t* first, size_t count, size_t stride, size_t width) {
    for (size_t i = 1; i < count; ++i)
        for (size_t j = 0; j < width; ++j) first[i * stride + j] = uint8_t(first[i * stride + j] + first[(i - 1) * stride + j]);
}
inline void difference_lanes(uint8_t* first, size_t count, size_t stride, size_t width) {
    if (width == stride) {  // every lane: one run over the bytes, last first, eight at a time
        size_t k = count * stride;
        for (; k >= stride + 8; k -= 8) {  // bytes [k - 8, k) less [k - 8 - stride, k - stride), both read before the store
            uint64_t a, b;
            std::memcpy(&a, first + k - 8, 8);
            std::memcpy(&b, first + k - 8 - stride, 8);
            constexpr uint64_t high = 0x8080808080808080ull;  // each byte's difference without a borrow into the next
            const uint64_t d = ((a | high) - (b & ~high)) ^ ((a ^ ~b) & high);
            std::memcpy(first + k - 8, &d, 8);
        }
        for (; k-- > stride;) first[k] = uint8_t(first[k] - first[k - stride]);
        return;
    }
    for (size_t i = count; i-- > 1;)
        for (size_t j = 0; j < width; ++j) first[i * stride + j] = uint8_t(first[i * stride + j] - first[(i - 1) * stride + j]);
}

/// The attribute streams of a chunk, in their order there (FORMAT.md, "Streamed files"): the
/// mesh's attribute bit (0 for positions, always present), element size and section name.
struct AttributeSlot {
    uint32_t bit, element;
    const char* name;
};
constexpr AttributeSlot attribute_slots[6] = {{0, position_element, "POSI"},
                                              {layout::attr_normals, normal_element, "NORM"},
                                              {layout::attr_texcoords, texcoord_element, "TEX0"},
                                              {layout::attr_colors, color_element, "COL0"},
                                              {layout::attr_texcoords1, texcoord_element, "TEX1"},
                                              {layout::attr_tangents, tangent_element, "TANG"}};

/// Bits of a vertex index below v (values 0 to v - 1): 0 for v <= 1.
inline uint32_t index_bits(uint32_t v) { return v <= 1 ? 0 : 32 - uint32_t(__builtin_clz(v - 1)); }

/// A substitute's difference from the previous one, zigzag-coded as residuals are (since 1.3
/// the splits block may code substitutes so: FORMAT.md), in 64 bits: it may not fit in 32.
inline uint64_t zigzag_difference(uint32_t p, uint32_t previous) {
    const int64_t d = int64_t(p) - int64_t(previous);
    return d >= 0 ? uint64_t(2 * d) : uint64_t(-2 * d - 1);
}
/// The vertex `previous` plus the difference z codes (z from zigzag_difference), or UINT64_MAX
/// when below zero.
inline uint64_t add_zigzag(uint32_t previous, uint32_t z) {
    const int64_t d = z & 1u ? -(int64_t(z) + 1) / 2 : int64_t(z) / 2;
    return int64_t(previous) + d < 0 ? UINT64_MAX : uint64_t(int64_t(previous) + d);
}
/// The bits of gamma(n), n >= 1.
inline uint32_t gamma_bits(uint64_t n) { return 2 * uint32_t(63 - __builtin_clzll(n)) + 1; }

/// Sorts a list ascending; a short one (a vertex's corners or neighbours: about 6, rarely past
/// 20) by insertion, where std::sort's set-up cost more than the sorting.
inline void sort_short(uint32_t* first, uint32_t* last) {
    if (last - first > 32) return std::sort(first, last);  // (a crafted file's hub vertex)
    for (uint32_t* i = first + (first != last); i < last; ++i) {
        const uint32_t x = *i;
        uint32_t* j = i;
        for (; j != first && *(j - 1) > x; --j) *j = *(j - 1);
        *j = x;
    }
}

/// The six orders of a born triangle's corners: entry o gives, for each stored corner, which of
/// (v, p, x) it is, v the split vertex, p its substitute, x the third corner. Orders 0-2 turn
/// v -> p -> x, orders 3-5 p -> v -> x.
constexpr uint8_t born_orders[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {1, 0, 2}, {0, 2, 1}, {2, 1, 0}};
constexpr uint32_t order_bits = 3;  // 1.0 and 1.1: the order in three bits

/// Since 1.2 a born triangle's order is coded against the orientation its neighbours predict:
/// on a consistently oriented surface the live triangle across its edge (p, x) runs that edge the
/// other way. Predicted: 1 (orders 3-5, p -> v -> x, which runs x -> p) when a live triangle
/// holding p, of the corners [first, last) (3 t + k, `triangle(g)` its three corners), holds x
/// right after p; else 0. The code: two bits of the turn (order % 3) when the orientation is the
/// predicted one, else two bits of 3 and two of the turn.
constexpr uint32_t turn_bits = 2, other_orientation = 3;
template <class Triangle>
uint32_t predicted_orientation(const uint32_t* first, const uint32_t* last, Triangle&& triangle, uint32_t p, uint32_t x) {
    for (const uint32_t* g = first; g != last; ++g) {
        const uint32_t* c = triangle(*g);
        const uint32_t k = *g % 3;
        if (c[k] == p && c[(k + 1) % 3] == x) return 1;
    }
    return 0;
}

/// Scratch of gather_neighbours: per vertex, the gathering that last listed it, so that each
/// neighbour is listed once without sorting the repeats (a vertex's ~18 corners name ~6 others;
/// sorting the repeats away cost most of a split's decoding).
struct Seen {
    std::vector<uint32_t> by;
    uint32_t gathering = 0;
    /// Room for the vertices below `vertices` (once per mesh or chunk, not per gathering).
    void cover(size_t vertices) {
        if (by.size() < vertices) by.resize(vertices, 0);
    }
    /// A new gathering.
    void start() { reserve(1); }
    /// `n` new marks, the first returned and the last current (so that first() goes on with it):
    /// a split's decoder marks p's neighbours with one and v's with the next.
    uint32_t reserve(uint32_t n) {
        if (gathering > UINT32_MAX - n) std::fill(by.begin(), by.end(), 0), gathering = 0;
        gathering += n;
        return gathering - n + 1;
    }
    /// True the first time vertex u is seen in this gathering.
    bool first(uint32_t u) {
        if (by[u] == gathering) return false;
        by[u] = gathering;
        return true;
    }
};

/// Appends to `out` the vertices that share a triangle with vertex u, each once in the order met,
/// leaving out `skip_a` and `skip_b` (arguments as gather_neighbours'): the decoder's rings,
/// whose mean needs no order.
template <class Triangle>
void append_neighbours(const uint32_t* first, const uint32_t* last, Triangle triangle, uint32_t skip_a, uint32_t skip_b, Seen& seen, std::vector<uint32_t>& out) {
    seen.start();
    for (const uint32_t* g = first; g != last; ++g) {
        const uint32_t* c = triangle(*g);
        for (int k = 0; k < 3; ++k)
            if (c[k] != skip_a && c[k] != skip_b && seen.first(c[k])) out.push_back(c[k]);
    }
}

/// The vertices that share a triangle with vertex u, ascending without repeats, leaving out
/// `skip_a` and `skip_b`: [first, last) lists u's live corners (3 t + k in TRIS),
/// `triangle(g)` gives the three corners of the triangle holding corner g, all vertices `seen`
/// covers. The encoder and the decoder gather a vertex's ring and a split's candidates with it,
/// so that both see one order.
template <class Triangle>
void gather_neighbours(const uint32_t* first, const uint32_t* last, Triangle triangle, uint32_t skip_a, uint32_t skip_b, Seen& seen, std::vector<uint32_t>& out) {
    out.clear();
    append_neighbours(first, last, triangle, skip_a, skip_b, seen, out);
    sort_short(out.data(), out.data() + out.size());
}
template <class Triangle>
void gather_neighbours(const std::vector<uint32_t>& incident, Triangle triangle, uint32_t skip_a, uint32_t skip_b, Seen& seen, std::vector<uint32_t>& out) {
    gather_neighbours(incident.data(), incident.data() + incident.size(), triangle, skip_a, skip_b, seen, out);
}

/// The candidates for a born triangle's third corner x: the vertices that share a live triangle
/// with both p and v (`around_p` and `around_v`: each one's neighbours, ascending, without p and
/// v) first, where a manifold split's x lies, then the others; each group ascending. Returns the
/// size of the first group.
inline size_t order_candidates(const std::vector<uint32_t>& around_p, const std::vector<uint32_t>& around_v, std::vector<uint32_t>& out) {
    out.clear();
    std::set_intersection(around_p.begin(), around_p.end(), around_v.begin(), around_v.end(), std::back_inserter(out));
    const size_t common = out.size();
    std::set_symmetric_difference(around_p.begin(), around_p.end(), around_v.begin(), around_v.end(), std::back_inserter(out));
    sort_short(out.data() + common, out.data() + out.size());
    return common;
}

/// The prediction of vertex v's grid values, its `lanes` lanes into `out`: for positions (`ring`,
/// `ring_size` vertices) the rounded mean of its neighbours' when it has any (the vertices it
/// shares a triangle with just after its split, all below v, in any order); else its
/// substitute's for a removed vertex (normals, texture coordinates and colours: across a hard
/// edge or a seam the neighbours' mean is a poor guess, its copy's a good one), the previous
/// vertex's for a survivor, zero for vertex 0. `values` holds `lanes` values per vertex; every
/// vertex below v is decoded.
template <class T>
void prediction(const T* values, int lanes, uint32_t v, uint32_t substitute, const uint32_t* ring, size_t ring_size, T* out) {
    if (ring_size) {
        int64_t sum[4] = {0, 0, 0, 0};  // (at most 4 lanes: colours)
        for (size_t i = 0; i < ring_size; ++i)
            for (int k = 0; k < lanes; ++k) sum[k] += int64_t(values[size_t(ring[i]) * lanes + k]);
        const int64_t n = int64_t(ring_size);
        for (int k = 0; k < lanes; ++k) out[k] = T(sum[k] >= 0 ? (sum[k] + n / 2) / n : -((-sum[k] + n / 2) / n));
        return;
    }
    const int64_t from = substitute < v ? int64_t(substitute) : int64_t(v) - 1;
    for (int k = 0; k < lanes; ++k) out[k] = from < 0 ? T(0) : values[size_t(from) * lanes + k];
}

} // namespace tom::stream_layout
