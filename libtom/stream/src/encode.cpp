// Writing streamed .tom files (docs/FORMAT.md, "Streamed files"): an ordinary .tom's meshes cut
// into chunks of resolution, quantized, predicted and compressed with meshoptimizer's codecs.

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "format_layout.h"
#include "scene_codec.h"
#include "stream_layout.h"
#include "tom/errors.h"
#include "tom/stream/stream_file.h"

namespace tom {

namespace {

using namespace stream_layout;
using layout::store_f32;
using layout::store_u32;
using layout::store_u64;

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
}

/// A mesh's values on the stream's grids, one array per stream (as the decoder rebuilds them).
struct Quantized {
    StreamQuantization q;
    std::vector<uint16_t> positions;  // 3 per vertex
    std::vector<int16_t> normals;     // 2 per vertex
    std::vector<uint16_t> texcoords[2];
    std::vector<uint8_t> colors;      // 4 per vertex
    std::vector<int16_t> tangents;    // 3 per vertex: octahedral pair, w
};

Quantized quantize_mesh(const MeshView& m, const StreamOptions& o) {
    Quantized out;
    StreamQuantization& q = out.q;
    q.position_bits = o.position_bits, q.normal_bits = o.normal_bits, q.texcoord_bits = o.texcoord_bits;
    const size_t n = m.vertex_count;
    float extent = 0;
    for (int k = 0; k < 3; ++k) {
        q.position_min[k] = m.bounds_min[k];
        extent = std::max(extent, m.bounds_max[k] - m.bounds_min[k]);
    }
    q.position_step = grid_step(extent, o.position_bits);
    for (size_t i = 0; i < 3 * n; ++i) out.positions.push_back(uint16_t(quantize(m.positions[i], q.position_min[i % 3], q.position_step, o.position_bits)));
    if (m.normals)
        for (size_t v = 0; v < n; ++v) {
            int16_t e[2];
            octahedral_encode(m.normals + 3 * v, o.normal_bits, e);
            out.normals.insert(out.normals.end(), e, e + 2);
        }
    const float* uvs[2] = {m.texcoords, m.texcoords1};
    for (int t = 0; t < 2; ++t) {
        if (!uvs[t]) continue;
        for (int k = 0; k < 2; ++k) {
            float lo = n ? uvs[t][k] : 0, hi = lo;
            for (size_t v = 0; v < n; ++v) lo = std::min(lo, uvs[t][2 * v + k]), hi = std::max(hi, uvs[t][2 * v + k]);
            q.texcoord_min[t][k] = lo;
            q.texcoord_step[t][k] = grid_step(hi - lo, o.texcoord_bits);
        }
        for (size_t i = 0; i < 2 * n; ++i) out.texcoords[t].push_back(uint16_t(quantize(uvs[t][i], q.texcoord_min[t][i % 2], q.texcoord_step[t][i % 2], o.texcoord_bits)));
    }
    for (int t = 0; t < 2; ++t)
        for (int k = 0; k < 2; ++k)
            if (!uvs[t]) q.texcoord_step[t][k] = 1;
    if (m.colors)
        for (size_t i = 0; i < 4 * n; ++i) out.colors.push_back(uint8_t(std::nearbyint(std::clamp(m.colors[i], 0.0f, 1.0f) * 255.0f)));
    if (m.tangents)
        for (size_t v = 0; v < n; ++v) {
            int16_t e[2];
            octahedral_encode(m.tangents + 4 * v, o.normal_bits, e);
            out.tangents.insert(out.tangents.end(), {e[0], e[1], int16_t(m.tangents[4 * v + 3] < 0 ? -1 : 1)});
        }
    return out;
}

/// The resolutions chunks end at: the first holding about `first_share` of the vertices and the
/// survivors, each next `growth` times the last, none inside a group of copies, the last V.
std::vector<uint32_t> chunk_ends(const MeshView& m, const StreamOptions& o) {
    std::vector<uint32_t> ends;
    const uint32_t V = m.vertex_count;
    if (V == 0) return ends;
    double target = std::max<double>({double(m.min_vertex_count), std::ceil(o.first_share * V), 1.0});
    while (true) {
        uint32_t b = m.whole_groups_above(uint32_t(std::min<double>(target, V)));
        if (!ends.empty() && b <= ends.back()) b = m.whole_groups_above(ends.back() + 1);
        ends.push_back(b);
        if (b >= V) break;
        target = std::max(double(b) * o.growth, double(b) + 16);
    }
    return ends;
}

/// The residuals of vertices [a, b) against their predictions (stream_layout::predictor), each
/// element `lanes` values of T padded to `element` bytes: what the decoder adds back.
template <class T>
std::vector<uint8_t> residuals(const std::vector<T>& values, const MeshView& m, uint32_t a, uint32_t b, int lanes, uint32_t element) {
    std::vector<uint8_t> out(size_t(b - a) * element, 0);
    for (uint32_t v = a; v < b; ++v) {
        const int64_t from = predictor(v, m.substitute_at(v));
        for (int k = 0; k < lanes; ++k) {
            const T base = from < 0 ? T(0) : values[size_t(from) * lanes + k];
            const T r = T(values[size_t(v) * lanes + k] - base);
            std::memcpy(&out[size_t(v - a) * element + k * sizeof(T)], &r, sizeof(T));
        }
    }
    return out;
}

void put_vertex_block(std::vector<uint8_t>& out, const std::vector<uint8_t>& elements, size_t count, size_t size) {
    std::vector<uint8_t> encoded(meshopt_encodeVertexBufferBound(count, size));
    encoded.resize(meshopt_encodeVertexBuffer(encoded.data(), encoded.size(), elements.data(), count, size));
    put_u32(out, uint32_t(encoded.size()));
    out.insert(out.end(), encoded.begin(), encoded.end());
}

/// The index codec may rotate a triangle's corners (it keeps the winding); a rotation block
/// after it says, per triangle, by how much to turn the decoded corners back (0 to 2, four
/// triangles to a 4-byte element), or is empty when none turned.
void put_index_block(std::vector<uint8_t>& out, const uint32_t* corners, size_t count, uint32_t vertex_count) {
    std::vector<uint8_t> encoded(meshopt_encodeIndexBufferBound(count, vertex_count));
    encoded.resize(meshopt_encodeIndexBuffer(encoded.data(), encoded.size(), corners, count));
    put_u32(out, uint32_t(encoded.size()));
    out.insert(out.end(), encoded.begin(), encoded.end());
    std::vector<uint32_t> decoded(count);
    if (meshopt_decodeIndexBuffer(decoded.data(), count, sizeof(uint32_t), encoded.data(), encoded.size()) != 0)
        throw InternalError("encode_stream: meshoptimizer does not decode the index block it encoded");
    std::vector<uint8_t> turns((count / 3 + 3) / 4 * 4, 0);
    bool any = false;
    for (size_t t = 0; t < count / 3; ++t) {
        const uint32_t* d = &decoded[3 * t];
        const uint32_t* o = corners + 3 * t;
        uint8_t r = 0;
        while (r < 3 && !(d[r] == o[0] && d[(r + 1) % 3] == o[1] && d[(r + 2) % 3] == o[2])) ++r;
        if (r == 3) throw InternalError("encode_stream: meshoptimizer's index codec changed a triangle beyond a rotation");
        turns[t] = r;
        any = any || r != 0;
    }
    if (any) {
        put_vertex_block(out, turns, turns.size() / rotation_element, rotation_element);
    } else {
        put_u32(out, 0);
    }
}

/// One chunk of a mesh before it is placed in the file.
struct Chunk {
    uint32_t mesh = 0, round = 0, vertex_end = 0, triangles = 0;
    std::vector<uint8_t> bytes;
};

/// A mesh's corners mapped to one resolution, per part, and each part's live prefix there.
struct Level {
    uint32_t resolution = 0;
    std::vector<uint32_t> corners;   // all of TRIS, mapped
    std::vector<uint32_t> live;      // per part
};

Level map_level(const MeshView& m, const std::vector<uint32_t>& from, uint32_t b) {
    Level l{b, from, {}};
    for (uint32_t& c : l.corners)
        while (c >= b) c = m.substitute_at(c);
    for (uint32_t p = 0; p < part_count(m); ++p) {
        const Part part = part_at(m, p);
        uint32_t t = 0;
        while (t < part.triangle_count) {
            const uint32_t* c = &l.corners[3 * size_t(part.first_triangle + t)];
            if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) break;
            ++t;
        }
        l.live.push_back(t);
    }
    return l;
}

/// The payload of the chunk that takes mesh `m` from level `before` (null for the first) to `at`.
std::vector<uint8_t> chunk_payload(const MeshView& m, const Quantized& q, const Level* before, const Level& at) {
    const uint32_t a = before ? before->resolution : 0, b = at.resolution, count = b - a, parts = part_count(m);
    std::vector<uint8_t> out;
    // per part: triangles added, corners updated (slots within the part's range, ascending)
    std::vector<std::vector<uint8_t>> updates(parts);
    for (uint32_t p = 0; p < parts; ++p) {
        const Part part = part_at(m, p);
        const uint32_t old = before ? before->live[p] : 0;
        for (uint32_t s = 0; s < 3 * old; ++s) {
            const size_t c = 3 * size_t(part.first_triangle) + s;
            if (at.corners[c] == before->corners[c]) continue;
            put_u32(updates[p], s);
            put_u32(updates[p], at.corners[c]);
        }
        put_u32(out, at.live[p] - old);
        put_u32(out, uint32_t(updates[p].size() / update_element));
    }
    std::vector<uint8_t> subs(size_t(count) * 4);
    for (uint32_t v = a; v < b; ++v) store_u32(&subs[size_t(v - a) * 4], v - m.substitute_at(v));
    put_vertex_block(out, subs, count, substitute_element);
    put_vertex_block(out, residuals(q.positions, m, a, b, 3, position_element), count, position_element);
    if (m.normals) put_vertex_block(out, residuals(q.normals, m, a, b, 2, normal_element), count, normal_element);
    if (m.texcoords) put_vertex_block(out, residuals(q.texcoords[0], m, a, b, 2, texcoord_element), count, texcoord_element);
    if (m.colors) put_vertex_block(out, residuals(q.colors, m, a, b, 4, color_element), count, color_element);
    if (m.texcoords1) put_vertex_block(out, residuals(q.texcoords[1], m, a, b, 2, texcoord_element), count, texcoord_element);
    if (m.tangents) put_vertex_block(out, residuals(q.tangents, m, a, b, 3, tangent_element), count, tangent_element);
    for (uint32_t s = 0; s < m.extra_stream_count; ++s) {
        const VertexStreamView& x = m.extra_streams[s];
        const uint32_t element = x.components * component_bytes(x.component_type), size = padded_element(element);
        std::vector<uint8_t> raw(size_t(count) * size, 0);
        for (uint32_t v = a; v < b; ++v) std::memcpy(&raw[size_t(v - a) * size], x.data + size_t(v) * element, element);
        put_vertex_block(out, raw, count, size);
    }
    for (uint32_t p = 0; p < parts; ++p) {
        const Part part = part_at(m, p);
        const uint32_t old = before ? before->live[p] : 0;
        if (at.live[p] > old) put_index_block(out, &at.corners[3 * (size_t(part.first_triangle) + old)], 3 * size_t(at.live[p] - old), b);
        if (!updates[p].empty()) put_vertex_block(out, updates[p], updates[p].size() / update_element, update_element);
    }
    return out;
}

/// Every chunk of mesh `index`, finest first computed (each level walks on from the finer one).
std::vector<Chunk> mesh_chunks(const MeshView& m, uint32_t index, const Quantized& q, const StreamOptions& o) {
    const std::vector<uint32_t> ends = chunk_ends(m, o);
    std::vector<uint32_t> corners(3 * size_t(m.triangle_count));
    for (size_t c = 0; c < corners.size(); ++c) corners[c] = m.corner(uint32_t(c));
    std::vector<Chunk> out(ends.size());
    Level at = map_level(m, corners, m.vertex_count);
    for (size_t k = ends.size(); k-- > 0;) {
        Chunk& c = out[k];
        c.mesh = index, c.round = uint32_t(k), c.vertex_end = ends[k];
        for (uint32_t t : at.live) c.triangles += t;
        if (k == 0) {
            c.bytes = chunk_payload(m, q, nullptr, at);
            break;
        }
        Level before = map_level(m, at.corners, ends[k - 1]);
        c.bytes = chunk_payload(m, q, &before, at);
        at = std::move(before);
    }
    return out;
}

std::vector<uint8_t> quantization_record(const StreamQuantization& q) {
    std::vector<uint8_t> r(quantization_bytes, 0);
    store_u32(&r[q_position_bits], q.position_bits);
    store_u32(&r[q_normal_bits], q.normal_bits);
    store_u32(&r[q_texcoord_bits], q.texcoord_bits);
    for (int k = 0; k < 3; ++k) store_f32(&r[q_position_min + 4 * k], q.position_min[k]);
    store_f32(&r[q_position_step], q.position_step);
    for (int k = 0; k < 2; ++k) {
        store_f32(&r[q_texcoord0_min + 4 * k], q.texcoord_min[0][k]);
        store_f32(&r[q_texcoord0_step + 4 * k], q.texcoord_step[0][k]);
        store_f32(&r[q_texcoord1_min + 4 * k], q.texcoord_min[1][k]);
        store_f32(&r[q_texcoord1_step + 4 * k], q.texcoord_step[1][k]);
    }
    return r;
}

/// The sections the directory keeps whole: the file's own as stored, and per mesh its header,
/// metadata, groups and parts as stored and its carried streams' records (without elements).
std::vector<layout::PendingSection> kept_sections(const File& file, const uint8_t* bytes) {
    using namespace layout;
    std::vector<PendingSection> kept;
    for (const SectionInfo& s : file.sections()) {
        const char name[5] = {s.type[0], s.type[1], s.type[2], s.type[3], 0};
        const uint32_t type = fourcc(name);
        const bool whole = s.mesh == file_level || type == sec_mesh || type == sec_metadata || type == sec_pairs || type == sec_parts;
        if (whole) kept.push_back({type, s.mesh, std::vector<uint8_t>(bytes + s.offset, bytes + s.offset + s.bytes)});
    }
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        const MeshView& m = file.mesh(i);
        if (!m.extra_stream_count) continue;
        const std::vector<VertexStreamView> records(m.extra_streams, m.extra_streams + m.extra_stream_count);
        kept.push_back({sec_extra_streams, i, detail::encode_extra_streams(records, 0)});
    }
    return kept;
}

void check_options(const StreamOptions& o) {
    if (o.position_bits < 1 || o.position_bits > 16) throw ArgumentError("encode_stream: position_bits " + std::to_string(o.position_bits) + " is not in [1, 16]");
    if (o.normal_bits < 2 || o.normal_bits > 16) throw ArgumentError("encode_stream: normal_bits " + std::to_string(o.normal_bits) + " is not in [2, 16]");
    if (o.texcoord_bits < 1 || o.texcoord_bits > 16) throw ArgumentError("encode_stream: texcoord_bits " + std::to_string(o.texcoord_bits) + " is not in [1, 16]");
    if (!(o.first_share > 0 && o.first_share <= 1)) throw ArgumentError("encode_stream: first_share is not in (0, 1]");
    if (!(o.growth > 1 && o.growth <= 16)) throw ArgumentError("encode_stream: growth is not in (1, 16]");
}

} // namespace

std::vector<uint8_t> encode_stream(const void* bytes, size_t size, const StreamOptions& options, const std::string& name) {
    check_options(options);
    const File file = File::borrow(bytes, size, name);
    // the directory: kept sections, quantization per mesh, then (below) the chunk table
    const std::vector<layout::PendingSection> kept = kept_sections(file, static_cast<const uint8_t*>(bytes));
    std::vector<uint8_t> directory;
    put_u32(directory, uint32_t(kept.size()));
    directory.resize(directory_header_bytes, 0);
    for (const layout::PendingSection& s : kept) {
        put_u32(directory, s.type);
        put_u32(directory, s.mesh);
        directory.resize(directory.size() + 8);
        store_u64(&directory[directory.size() - 8], s.bytes.size());
    }
    // chunks: every mesh's, in rounds (round k of every mesh before round k + 1 of any)
    std::vector<Chunk> chunks;
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        const MeshView& m = file.mesh(i);
        const Quantized q = quantize_mesh(m, options);
        const std::vector<uint8_t> record = quantization_record(q.q);
        directory.insert(directory.end(), record.begin(), record.end());
        for (Chunk& c : mesh_chunks(m, i, q, options)) chunks.push_back(std::move(c));
    }
    std::stable_sort(chunks.begin(), chunks.end(), [](const Chunk& x, const Chunk& y) { return x.round < y.round; });
    for (const Chunk& c : chunks) {
        const size_t r = directory.size();
        directory.resize(r + chunk_record_bytes, 0);
        store_u32(&directory[r + r_mesh], c.mesh);
        store_u32(&directory[r + r_vertex_end], c.vertex_end);
        store_u32(&directory[r + r_triangle_end], c.triangles);
        store_u32(&directory[r + r_bytes], uint32_t(c.bytes.size()));
        store_u32(&directory[r + r_checksum], crc32(c.bytes.data(), c.bytes.size()));
    }
    for (const layout::PendingSection& s : kept) directory.insert(directory.end(), s.bytes.begin(), s.bytes.end());
    // header, directory, chunks
    std::vector<uint8_t> out(header_bytes, 0);
    std::memcpy(out.data(), magic, 8);
    store_u32(&out[h_version_major], version_major);
    store_u32(&out[h_version_minor], version_minor);
    store_u32(&out[h_mesh_count], file.mesh_count());
    store_u32(&out[h_chunk_count], uint32_t(chunks.size()));
    store_u64(&out[h_directory_bytes], directory.size());
    store_u32(&out[h_directory_checksum], crc32(directory.data(), directory.size()));
    out.insert(out.end(), directory.begin(), directory.end());
    for (const Chunk& c : chunks) out.insert(out.end(), c.bytes.begin(), c.bytes.end());
    store_u64(&out[h_file_bytes], out.size());
    store_u32(&out[h_header_checksum], crc32(out.data(), h_header_checksum));
    return out;
}

} // namespace tom
