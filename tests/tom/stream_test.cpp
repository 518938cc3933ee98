// Streamed .tom files (docs/FORMAT.md, "Streamed files"): every prefix that ends on a chunk
// boundary decodes to the level at the vertex counts received, index for index what extraction
// gives from the ordinary file the stream stands for (the source renumbered within its chunks,
// tom::stream_order: at each chunk boundary the same mesh), with positions and attributes within
// the stated quantization; bad bytes are errors that name the place, never a crash.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>

#include <unistd.h>

#include <catch2/catch.hpp>

#include "support.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/builder/generate.h"
#include "tom/builder/writer.h"
#include "tom/io/import.h"
#include "tom/stream/stream_file.h"
#include "format_layout.h"
#include "stream_layout.h"

namespace {

namespace fs = std::filesystem;

/// The ordinary .tom image of a mesh file: every mesh cleaned and built, with its scene.
std::vector<uint8_t> tom_image(const std::string& path) {
    tom::ImportResult r = tom::import_file(path);
    std::vector<tom::TomMesh> built;
    for (tom::Mesh& m : r.meshes) {
        tom::clean_mesh(m);
        built.push_back(tom::build(m));
    }
    return tom::serialize(built, r.scene);
}

/// The triangles of a mesh at resolution n, as extraction gives them (parts one after another).
std::vector<uint32_t> level(const tom::MeshView& m, uint32_t n) {
    std::vector<uint32_t> out(3 * size_t(m.triangle_count));
    const tom::Extracted e = tom::extract(m, n, out.data(), out.size());
    out.resize(3 * size_t(e.triangle_count));
    return out;
}

float distance3(const float* a, const float* b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/// Mesh `d` (decoded from a prefix) against mesh `o` (the ordinary file's) at d's resolution n:
/// the same triangles at n and at two coarser resolutions, the same substitutes, groups and
/// carried streams, and values within the quantization's bounds.
void check_prefix_mesh(const tom::MeshView& o, const tom::MeshView& d, const tom::StreamQuantization& q) {
    const uint32_t n = d.vertex_count;
    INFO("mesh '" << std::string(o.name) << "' at " << n << " of " << o.vertex_count << " vertices");
    if (n == 0) {
        CHECK(d.triangle_count == 0);
        return;
    }
    CHECK(d.min_vertex_count == o.min_vertex_count);
    CHECK(level(d, n) == level(o, n));
    for (const uint32_t coarser : {o.min_vertex_count, d.whole_groups_below(std::max(o.min_vertex_count, n / 2))}) CHECK(level(d, coarser) == level(o, coarser));
    REQUIRE(tom::part_count(d) == tom::part_count(o));
    for (uint32_t p = 0; p < tom::part_count(d); ++p) CHECK(tom::part_at(d, p).material == tom::part_at(o, p).material);
    float worst_position = 0, worst_normal = 0, worst_uv = 0, worst_color = 0, worst_tangent = 0;
    for (uint32_t v = 0; v < n; ++v) {
        REQUIRE(d.substitute_at(v) == o.substitute_at(v));
        CHECK(d.splits_pair(v) == (v < n && o.splits_pair(v)));
        for (int k = 0; k < 3; ++k) worst_position = std::max(worst_position, std::fabs(d.positions[3 * v + k] - o.positions[3 * v + k]));
        if (o.normals) worst_normal = std::max(worst_normal, distance3(d.normals + 3 * v, o.normals + 3 * v));
        for (int t = 0; t < 2; ++t) {
            const float *dt = t ? d.texcoords1 : d.texcoords, *ot = t ? o.texcoords1 : o.texcoords;
            REQUIRE(!dt == !ot);
            if (ot)
                for (int k = 0; k < 2; ++k) worst_uv = std::max(worst_uv, std::fabs(dt[2 * v + k] - ot[2 * v + k]) / q.texcoord_step[t][k]);
        }
        REQUIRE(!d.colors == !o.colors);
        if (o.colors)
            for (int k = 0; k < 4; ++k) worst_color = std::max(worst_color, std::fabs(d.colors[4 * v + k] - o.colors[4 * v + k]));
        REQUIRE(!d.tangents == !o.tangents);
        if (o.tangents) {
            worst_tangent = std::max(worst_tangent, distance3(d.tangents + 4 * v, o.tangents + 4 * v));
            CHECK(d.tangents[4 * v + 3] == o.tangents[4 * v + 3]);  // handedness kept exactly
        }
    }
    // a grid point of the cell around it (one step at most on each axis), and the float rounding
    // of the step's multiples
    CHECK(worst_position <=
          q.position_step * 1.001f + 1e-6f * (1 + std::fabs(q.position_min[0]) + std::fabs(q.position_min[1]) + std::fabs(q.position_min[2])));
    // coincident vertices (a seam's copies) on one grid point: the seam stays closed
    std::vector<uint32_t> by_position(n);
    std::iota(by_position.begin(), by_position.end(), 0u);
    auto at = [&](const tom::MeshView& x, uint32_t v) { return std::array<float, 3>{x.positions[3 * v], x.positions[3 * v + 1], x.positions[3 * v + 2]}; };
    std::sort(by_position.begin(), by_position.end(), [&](uint32_t a, uint32_t b) { return at(o, a) < at(o, b); });
    uint32_t apart = 0;
    for (uint32_t i = 1; i < n; ++i) apart += at(o, by_position[i]) == at(o, by_position[i - 1]) && at(d, by_position[i]) != at(d, by_position[i - 1]);
    CHECK(apart == 0);
    // octahedral pairs of b bits: a unit vector within 2.5 grid steps of 1 / (2^(b-1) - 1) (chord)
    CHECK(worst_normal <= 2.5f / float((1 << (q.normal_bits - 1)) - 1));
    CHECK(worst_uv <= 0.5001f);
    CHECK(worst_color <= 0.5f / 255.0f + 1e-6f);  // 8-bit colours
    CHECK(worst_tangent <= 2.5f / float((1 << (q.normal_bits - 1)) - 1));  // octahedral, as normals
    REQUIRE(d.extra_stream_count == o.extra_stream_count);
    for (uint32_t s = 0; s < d.extra_stream_count; ++s) {
        const tom::VertexStreamView &x = d.extra_streams[s], &y = o.extra_streams[s];
        CHECK(x.name == y.name);
        const size_t bytes = size_t(n) * x.components * tom::component_bytes(x.component_type);
        CHECK(std::equal(x.data, x.data + bytes, y.data));
    }
}

/// A triangle as the values of its corners (position, then every attribute), turned to start
/// at its smallest corner: equal for the same triangle of two numberings of one mesh.
using Corner = std::vector<float>;
using ValueTriangle = std::array<Corner, 3>;

Corner corner_values(const tom::MeshView& m, uint32_t v) {
    Corner c(m.positions + 3 * v, m.positions + 3 * v + 3);
    for (const auto& [data, lanes] : {std::pair{m.normals, 3}, {m.texcoords, 2}, {m.colors, 4}, {m.texcoords1, 2}, {m.tangents, 4}})
        if (data) c.insert(c.end(), data + size_t(lanes) * v, data + size_t(lanes) * (v + 1));
    return c;
}

/// The level of `m` at resolution n as a sorted list of triangles by value, part by part.
std::vector<ValueTriangle> level_by_value(const tom::MeshView& m, uint32_t n) {
    const std::vector<uint32_t> corners = level(m, n);
    std::vector<ValueTriangle> out;
    for (size_t t = 0; t < corners.size() / 3; ++t) {
        ValueTriangle x{corner_values(m, corners[3 * t]), corner_values(m, corners[3 * t + 1]), corner_values(m, corners[3 * t + 2])};
        std::rotate(x.begin(), std::min_element(x.begin(), x.end()), x.end());
        out.push_back(std::move(x));
    }
    std::sort(out.begin(), out.end());
    return out;
}

/// The stream's ordinary file (renumbered within chunks unless the options keep the order)
/// against the source's at every chunk boundary: the same triangles by value, and within each
/// chunk the splits' substitutes ascending but within groups of copies (what codes them small).
void check_stream_order(const tom::File& source, const tom::File& ordered, const std::vector<tom::StreamChunk>& chunks, const tom::StreamOptions& options) {
    for (uint32_t i = 0; i < source.mesh_count(); ++i) {
        const tom::MeshView &s = source.mesh(i), &o = ordered.mesh(i);
        REQUIRE((o.vertex_count == s.vertex_count && o.triangle_count == s.triangle_count && o.min_vertex_count == s.min_vertex_count));
        CHECK(level_by_value(o, o.min_vertex_count) == level_by_value(s, s.min_vertex_count));
        uint32_t a = s.min_vertex_count, descents = 0, splits = 0;
        for (const tom::StreamChunk& c : chunks) {
            if (c.mesh != i) continue;
            INFO("mesh " << i << " at " << c.vertex_end << " vertices");
            CHECK(level_by_value(o, c.vertex_end) == level_by_value(s, c.vertex_end));
            // each group of copies (or single vertex) keyed by its members' largest substitute
            // outside it: the keys ascend
            uint32_t last_key = 0;
            for (uint32_t first = std::max(a, s.min_vertex_count), end = first; first < c.vertex_end; first = end, ++splits) {
                uint32_t key = 0;
                for (end = first + 1; end < c.vertex_end && o.splits_pair(end);) ++end;
                for (uint32_t v = first; v < end; ++v)
                    if (o.substitute_at(v) < first) key = std::max(key, o.substitute_at(v));
                descents += key < last_key;
                last_key = key;
            }
            a = c.vertex_end;
        }
        if (options.keep_order)
            CHECK(std::equal(o.positions, o.positions + 3 * size_t(o.vertex_count), s.positions));
        else
            CHECK(descents == 0);
        std::printf("  mesh %u: %u of %u splits (or groups) with a substitute below the one before within a chunk\n", i, descents, splits);
    }
}

/// Feeds the stream chunk by chunk, checking each decoded prefix against the ordinary file it
/// stands for (tom::stream_order), and that file against the source.
void check_every_prefix(const std::string& what, const std::vector<uint8_t>& image, const tom::StreamOptions& options = {}) {
    INFO(what);
    const std::vector<uint8_t> ordered = tom::stream_order(image.data(), image.size(), options, what);
    const tom::File original = tom::File::from_bytes(ordered.data(), ordered.size(), what);
    const std::vector<uint8_t> stream = tom::encode_stream(image.data(), image.size(), options, what);
    CHECK(tom::encode_stream(image.data(), image.size(), options, what) == stream);  // deterministic
    tom::StreamDecoder decoder(tom::meshopt_codecs(), what);
    CHECK(decoder.next_boundary() == 64);  // a range client asks for the header first
    decoder.append(stream.data(), 64);
    CHECK_FALSE(decoder.has_directory());
    uint64_t fed = 64;
    const uint64_t directory_end = 64 + [&] { tom::StreamDecoder d(tom::meshopt_codecs()); d.append(stream.data(), stream.size()); return d.chunks()[0].begin_byte - 64; }();
    CHECK(decoder.next_boundary() == directory_end);  // then the directory
    decoder.append(stream.data() + fed, directory_end - fed);
    fed = directory_end;
    REQUIRE(decoder.has_directory());
    REQUIRE(decoder.mesh_count() == original.mesh_count());
    const std::vector<tom::StreamChunk> chunks = decoder.chunks();
    check_stream_order(tom::File::from_bytes(image.data(), image.size(), what), original, chunks, options);
    std::printf("%s: %zu bytes as .tom, %zu streamed (%.1f%%) in %zu chunks; the first chunk ends at byte %llu (%.1f%%)\n", what.c_str(), image.size(),
                stream.size(), 100.0 * double(stream.size()) / double(image.size()), chunks.size(), (unsigned long long)chunks[0].end_byte,
                100.0 * double(chunks[0].end_byte) / double(stream.size()));
    const tom::StreamDeferred deferred = decoder.deferred();
    const size_t images = original.scene().images.size();
    // the deferred block (images, provenance, source glTF) right after every mesh's first chunk
    if (deferred.end_byte > deferred.begin_byte) CHECK(deferred.after_chunk == std::min<size_t>(original.mesh_count(), chunks.size()));
    auto feed_deferred = [&](size_t k) {
        if (k != deferred.after_chunk || decoder.deferred_received()) return;
        CHECK(decoder.file().scene().images.empty());  // a frame before the block: no images yet
        CHECK(decoder.next_boundary() == deferred.end_byte);
        decoder.append(stream.data() + fed, deferred.end_byte - fed);
        fed = deferred.end_byte;
        REQUIRE(decoder.deferred_received());
        CHECK(decoder.file().scene().images.size() == images);
        CHECK(decoder.file().provenance() == original.provenance());
    };
    for (size_t k = 0; k < chunks.size(); ++k) {
        feed_deferred(k);
        // a chunk in two pieces: nothing is decoded until its last byte
        const uint64_t middle = (chunks[k].begin_byte + chunks[k].end_byte) / 2;
        CHECK(decoder.next_boundary() == chunks[k].end_byte);  // then each chunk
        decoder.append(stream.data() + fed, middle - fed);
        CHECK(decoder.decoded_chunks() == k);
        decoder.append(stream.data() + middle, chunks[k].end_byte - middle);
        fed = chunks[k].end_byte;
        REQUIRE(decoder.decoded_chunks() == k + 1);
        CHECK(decoder.vertex_count(chunks[k].mesh) == chunks[k].vertex_end);
        const tom::File prefix = decoder.file();
        const std::vector<uint8_t> prefix_image = decoder.tom_bytes();  // its checksums hold (the kept sections' computed on arrival)
        CHECK_NOTHROW(tom::File::from_bytes(prefix_image.data(), prefix_image.size(), what));
        CHECK(prefix.mesh(chunks[k].mesh).triangle_count == chunks[k].triangles);
        CHECK(prefix.scene().materials.size() == original.scene().materials.size());
        CHECK(prefix.scene().instances.size() == original.scene().instances.size());
        CHECK(prefix.scene().images.size() == (decoder.deferred_received() ? images : 0));
        for (uint32_t i = 0; i < original.mesh_count(); ++i) check_prefix_mesh(original.mesh(i), prefix.mesh(i), decoder.quantization(i));
    }
    feed_deferred(chunks.size());
    CHECK(decoder.complete());
    CHECK(decoder.next_boundary() == stream.size());
    CHECK(fed == stream.size());
}

/// The directory's chunk table (FORMAT.md: after the header, the kept entries and the
/// quantization records): where it starts and ends, and its records.
struct Table {
    uint64_t begin = 0, end = 0;
    std::vector<tom::stream_layout::ChunkRecord> records;
};

Table chunk_table(const std::vector<uint8_t>& s) {
    using namespace tom::layout;
    using tom::stream_layout::get_varint;
    Table t;
    t.begin = 64 + 16 + 16 * uint64_t(load_u32(&s[64])) + 64 * uint64_t(load_u32(&s[24]));
    const uint64_t directory_end = 64 + load_u64(&s[32]);
    std::vector<tom::stream_layout::ChunkRecord> last(load_u32(&s[24]));
    uint64_t at = t.begin;
    for (uint32_t k = 0; k < load_u32(&s[28]); ++k) {
        tom::stream_layout::ChunkRecord r;
        uint32_t vertices = 0, triangles = 0;
        REQUIRE((get_varint(s.data(), directory_end, at, r.mesh) && r.mesh < last.size()));
        REQUIRE((get_varint(s.data(), directory_end, at, vertices) && get_varint(s.data(), directory_end, at, triangles)));
        REQUIRE(get_varint(s.data(), directory_end, at, r.bytes));
        r.vertex_end = last[r.mesh].vertex_end + vertices, r.triangle_end = last[r.mesh].triangle_end + triangles;
        r.checksum = load_u32(&s[at]);
        at += 4;
        t.records.push_back(last[r.mesh] = r);
    }
    t.end = at;
    return t;
}

/// Puts a changed table in place of the stream's, the directory and the file growing or
/// shrinking with it (reseal() then mends the checksums).
void put_table(std::vector<uint8_t>& s, const Table& t) {
    using namespace tom::layout;
    std::vector<uint8_t> bytes;
    tom::stream_layout::put_chunk_table(bytes, t.records, load_u32(&s[24]));
    s.erase(s.begin() + int64_t(t.begin), s.begin() + int64_t(t.end));
    s.insert(s.begin() + int64_t(t.begin), bytes.begin(), bytes.end());
    const uint64_t grown = bytes.size() - (t.end - t.begin);  // (modulo 2^64: it may shrink)
    store_u64(&s[32], load_u64(&s[32]) + grown);
    store_u64(&s[16], load_u64(&s[16]) + grown);
}

/// The deferred block's size: the data of the directory's last deferred_count kept entries.
uint64_t deferred_bytes(const std::vector<uint8_t>& s) {
    using namespace tom::layout;
    const uint32_t kept = load_u32(&s[64]);
    uint64_t bytes = 0;
    for (uint32_t k = kept - load_u32(&s[68]); k < kept; ++k) bytes += load_u64(&s[64 + 16 + 16 * uint64_t(k) + 8]);
    return bytes;
}

/// Recomputes every checksum of a stream after a test changed its bytes, so that the checks
/// behind the checksums are what refuses them.
void reseal(std::vector<uint8_t>& s) {
    using namespace tom::layout;
    const uint64_t directory = load_u64(&s[32]), deferred = deferred_bytes(s);
    Table table = chunk_table(s);
    uint64_t at = 64 + directory;
    for (uint32_t k = 0; k <= table.records.size(); ++k) {
        if (k == load_u32(&s[72]) && deferred) {
            store_u32(&s[76], tom::crc32(&s[at], deferred));
            at += deferred;
        }
        if (k == table.records.size()) break;
        const uint32_t bytes = table.records[k].bytes;
        if (at + bytes <= s.size()) table.records[k].checksum = tom::crc32(&s[at], bytes);
        at += bytes;
    }
    put_table(s, table);  // the same size: checksums are raw u32
    store_u32(&s[40], tom::crc32(&s[64], directory));
    store_u32(&s[44], tom::crc32(s.data(), 44));
}

} // namespace

TEST_CASE("residuals in byte form come back exactly, small ones in small bytes", "[stream]") {
    using namespace tom::stream_layout;
    // every 16-bit residual, unsigned (positions, texture coordinates) and signed (normals)
    std::vector<uint8_t> lanes;
    for (uint32_t x = 0; x < 65536; ++x) {
        uint8_t b[2];
        residual_to_bytes(uint16_t(x), b);
        CHECK(residual_from_bytes<uint16_t>(b) == uint16_t(x));
        residual_to_bytes(int16_t(x), b);
        CHECK(residual_from_bytes<int16_t>(b) == int16_t(x));
        const int r = int16_t(x);
        if (r >= -128 && r <= 127) CHECK((int8_t(b[0]) == r && b[1] == 0));  // the codec sees r itself, no high byte
        lanes.insert(lanes.end(), b, b + 2);
    }
    for (uint32_t x = 0; x < 256; ++x) {
        uint8_t b;
        residual_to_bytes(uint8_t(x), &b);
        CHECK(residual_from_bytes<uint8_t>(&b) == uint8_t(x));
    }
    // a block's lanes summed and taken back: all of an element's, or one attribute's among others
    const std::vector<uint8_t> kept = lanes;
    sum_lanes(lanes.data(), lanes.size() / 4, 4, 4);
    CHECK(lanes != kept);
    difference_lanes(lanes.data(), lanes.size() / 4, 4, 4);
    CHECK(lanes == kept);
    sum_lanes(lanes.data() + 2, lanes.size() / 4, 4, 2);
    for (size_t i = 0; i < lanes.size(); i += 4) CHECK((lanes[i] == kept[i] && lanes[i + 1] == kept[i + 1]));
    difference_lanes(lanes.data() + 2, lanes.size() / 4, 4, 2);
    CHECK(lanes == kept);
    // whole elements of every size, eight bytes at a time where they reach: each byte's
    // difference from the one an element before, as one lane at a time takes it
    for (size_t stride = 1; stride <= 19; ++stride)
        for (size_t count : {size_t(1), size_t(2), size_t(7), size_t(33)}) {
            std::vector<uint8_t> block(kept.begin() + stride, kept.begin() + stride + stride * count), expected = block;
            for (size_t k = stride; k < block.size(); ++k) expected[k] = uint8_t(block[k] - block[k - stride]);
            difference_lanes(block.data(), count, stride, stride);
            CHECK(block == expected);
        }
}

TEST_CASE("every chunk of a streamed scanned mesh decodes to its level", "[stream]") {
    const std::vector<uint8_t> image = tom_image(test::sample("meshes/bunny00.off"));
    check_every_prefix("bunny00", image);
    tom::StreamOptions keep;
    keep.keep_order = true;
    check_every_prefix("bunny00 in the builder's order", image, keep);
    // substitutes ascending within a chunk code as small differences: the file shrinks
    const size_t ordered = tom::encode_stream(image.data(), image.size()).size(), kept = tom::encode_stream(image.data(), image.size(), keep).size();
    std::printf("bunny00 streamed: %zu bytes, %zu in the builder's order\n", ordered, kept);
    CHECK(double(ordered) < 0.9 * double(kept));
}

TEST_CASE("streamed positions lie nearer the surface than rounding each coordinate", "[stream]") {
    // the quantized bunny against the same grid rounded coordinate by coordinate: the mean
    // distance of its vertices from the planes of their triangles (the full mesh's normals)
    const std::vector<uint8_t> image = tom_image(test::sample("meshes/bunny00.off"));
    tom::StreamOptions keep;
    keep.keep_order = true;  // vertex for vertex the source's
    const std::vector<uint8_t> stream = tom::encode_stream(image.data(), image.size(), keep);
    tom::StreamDecoder d(tom::meshopt_codecs());
    d.append(stream.data(), stream.size());
    const tom::File decoded = d.file(), original = tom::File::from_bytes(image.data(), image.size());
    const tom::MeshView &o = original.mesh(0), &x = decoded.mesh(0);
    const tom::StreamQuantization& q = d.quantization(0);
    REQUIRE(o.normals);
    double surface = 0, rounded = 0;
    for (uint32_t v = 0; v < o.vertex_count; ++v) {
        double off_surface = 0, off_rounded = 0;
        for (int k = 0; k < 3; ++k) {
            const float nearest = tom::stream_layout::dequantize(
                tom::stream_layout::quantize(o.positions[3 * v + k], q.position_min[k], q.position_step, q.position_bits), q.position_min[k], q.position_step);
            off_surface += double(x.positions[3 * v + k] - o.positions[3 * v + k]) * o.normals[3 * v + k];
            off_rounded += double(nearest - o.positions[3 * v + k]) * o.normals[3 * v + k];
        }
        surface += std::fabs(off_surface), rounded += std::fabs(off_rounded);
    }
    std::printf("bunny00 quantized: %.3g mean distance off the vertex normal's plane, %.3g rounding each coordinate (step %.3g)\n", surface / o.vertex_count,
                rounded / o.vertex_count, double(q.position_step));
    CHECK(surface < 0.7 * rounded);
}

TEST_CASE("streamed meshes made here, at every precision, decode to their levels", "[stream]") {
    for (const test::NamedMesh& m : test::generated_meshes()) {
        const std::vector<uint8_t> image = tom::serialize({tom::build(m.mesh)});
        check_every_prefix(m.name, image);
        tom::StreamOptions fine;
        fine.position_bits = 16, fine.normal_bits = 16, fine.texcoord_bits = 16, fine.growth = 2;
        check_every_prefix(m.name + " at 16 bits", image, fine);
    }
}

TEST_CASE("a streamed mesh with every attribute decodes each to its own", "[stream]") {
    // normals, both texture coordinate sets, colours and tangents, each a different function of
    // the position, so that one read in another's place differs
    tom::Mesh m = tom::make_sphere(16, 20, 1.0f, 0.05f);
    const size_t n = m.vertex_count();
    for (size_t v = 0; v < n; ++v) {
        const float x = m.positions[3 * v], y = m.positions[3 * v + 1], z = m.positions[3 * v + 2];
        m.texcoords.insert(m.texcoords.end(), {0.5f + 0.4f * x, 0.5f + 0.4f * y});
        m.texcoords1.insert(m.texcoords1.end(), {0.25f * z + 0.5f, 0.1f + 0.3f * x * y});
        m.colors.insert(m.colors.end(), {0.5f + 0.45f * y, 0.5f + 0.45f * z, 0.5f - 0.45f * x, 1.0f});  // in [0, 1]
        // a unit tangent orthogonal to the radial normal: the direction of growing longitude
        const float r = std::sqrt(x * x + y * y);
        if (r > 1e-6f)
            m.tangents.insert(m.tangents.end(), {-y / r, x / r, 0.0f, v % 2 ? 1.0f : -1.0f});
        else  // a pole
            m.tangents.insert(m.tangents.end(), {1.0f, 0.0f, 0.0f, 1.0f});
    }
    tom::compute_normals(m);
    check_every_prefix("sphere with every attribute", tom::serialize({tom::build(m)}));
}

/// A file of tests/data/stream.
std::vector<uint8_t> stream_data(const char* name) {
    std::ifstream in(std::string(TOM_TEST_DATA_DIR) + "/stream/" + name, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// A stream of grid9.tom written by an earlier version (in the builder's order: the versions
/// before 1.3 kept it) decodes at every chunk to grid9.tom's levels.
void check_old_stream(const char* name, uint32_t minor) {
    INFO(name);
    const std::vector<uint8_t> stream = stream_data(name), image = stream_data("grid9.tom");
    REQUIRE(stream.size() > 64);
    REQUIRE(tom::layout::load_u32(&stream[12]) == minor);  // version_minor
    const tom::File original = tom::File::from_bytes(image.data(), image.size(), "grid9.tom");
    REQUIRE((original.mesh(0).normals && original.mesh(0).texcoords));
    tom::StreamDecoder d(tom::meshopt_codecs(), name);
    d.append(stream.data(), 64);
    d.append(stream.data() + 64, d.next_boundary() - 64);
    REQUIRE(d.has_directory());
    const std::vector<tom::StreamChunk> chunks = d.chunks();
    uint64_t fed = chunks[0].begin_byte;  // the header and the directory
    REQUIRE(chunks.size() > 2);
    for (const tom::StreamChunk& c : chunks) {
        d.append(stream.data() + fed, c.end_byte - fed);
        fed = c.end_byte;
        check_prefix_mesh(original.mesh(0), d.file().mesh(0), d.quantization(0));
    }
    d.append(stream.data() + fed, stream.size() - fed);
    CHECK(d.complete());
}

TEST_CASE("streams written at versions 1.1 and 1.2 decode to their levels", "[stream]") {
    // tests/data/stream: grid9.obj (normals, texture coordinates) built by the toolkit of stream
    // version 1.1 (a prediction and a block per attribute, no byte form), streamed and ordinary,
    // and grid9.tom streamed by version 1.2 (substitutes in index_bits(v) bits, no opening bit)
    check_old_stream("grid9-stream-1.2.tom", 2);
    check_old_stream("grid9-stream-1.1.tom", 1);
    const std::vector<uint8_t> stream = stream_data("grid9-stream-1.1.tom");
    tom::StreamDecoder d(tom::meshopt_codecs());
    d.append(stream.data(), stream.size());
    const std::vector<tom::StreamChunk> chunks = d.chunks();
    // the byte form (predictions 2 and 3) is new in 1.2: chunk 1's POSI prediction set to 2,
    // after its part's (base, born) and its splits block, and the chunk's checksum mended in its
    // 24-byte record
    std::vector<uint8_t> bad = stream;
    const uint64_t at = chunks[1].begin_byte + 8, prediction = at + 4 + tom::layout::load_u32(&bad[at]);
    tom::layout::store_u32(&bad[prediction], 2);
    const uint64_t record = 64 + 16 + 16 * uint64_t(tom::layout::load_u32(&bad[64])) + 64 + 24;
    tom::layout::store_u32(&bad[record + 20], tom::crc32(&bad[chunks[1].begin_byte], chunks[1].end_byte - chunks[1].begin_byte));
    tom::layout::store_u32(&bad[40], tom::crc32(&bad[64], tom::layout::load_u64(&bad[32])));
    tom::layout::store_u32(&bad[44], tom::crc32(bad.data(), 44));
    CHECK_THROWS_WITH(tom::StreamDecoder(tom::meshopt_codecs(), "o.tom").append(bad.data(), bad.size()),
                      Catch::Contains("o.tom") && Catch::Contains("POSI prediction 2 is not 0 to 1 (stream version 1.1)"));
}

TEST_CASE("streamed scenes keep parts, materials, textures, groups and carried streams", "[stream]") {
    for (const char* path : {"assimp/OBJ/spider.obj", "assimp/glTF2/ClearCoat-glTF/ClearCoatTest.gltf", "assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb",
                             "assimp/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf", "assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"}) {
        const std::vector<uint8_t> image = tom_image(test::sample(path));
        check_every_prefix(path, image);
        // the whole stream keeps the file's scene: its images and source glTF byte for byte
        const std::vector<uint8_t> stream = tom::encode_stream(image.data(), image.size());
        tom::StreamDecoder d(tom::meshopt_codecs());
        d.append(stream.data(), stream.size());
        const tom::File whole = d.file(), original = tom::File::from_bytes(image.data(), image.size());
        REQUIRE(whole.scene().images.size() == original.scene().images.size());
        for (size_t i = 0; i < whole.scene().images.size(); ++i)
            CHECK(std::equal(whole.scene().images[i].data, whole.scene().images[i].data + whole.scene().images[i].bytes, original.scene().images[i].data));
        CHECK(whole.scene().gltf.json == original.scene().gltf.json);
        CHECK(whole.provenance() == original.provenance());
    }
}

TEST_CASE("a stream fed in random pieces decodes as when fed whole", "[stream]") {
    const std::vector<uint8_t> image = tom_image(test::sample("assimp/OBJ/spider.obj"));
    const std::vector<uint8_t> stream = tom::encode_stream(image.data(), image.size());
    tom::StreamDecoder whole(tom::meshopt_codecs());
    whole.append(stream.data(), stream.size());
    std::mt19937 rng(7);
    for (int run = 0; run < 5; ++run) {
        tom::StreamDecoder pieces(tom::meshopt_codecs());
        for (size_t at = 0; at < stream.size();) {
            const size_t n = std::min(stream.size() - at, size_t(rng() % 3000));
            pieces.append(stream.data() + at, n);
            at += n;
        }
        CHECK(pieces.tom_bytes() == whole.tom_bytes());
    }
}

TEST_CASE("bad streams are errors naming the place, and keep what was decoded", "[stream][errors]") {
    tom::Mesh fandisk = tom::import_file(test::sample("meshes/fandisk.off")).meshes.at(0);
    tom::clean_mesh(fandisk);
    tom::WriteOptions with_provenance;  // (a deferred block to corrupt)
    with_provenance.provenance = "{\"tool\": \"stream_test\"}";
    const std::vector<uint8_t> image = tom::serialize({tom::build(fandisk)}, with_provenance);
    const std::vector<uint8_t> stream = tom::encode_stream(image.data(), image.size());
    tom::StreamDecoder reference(tom::meshopt_codecs());
    reference.append(stream.data(), stream.size());
    const std::vector<tom::StreamChunk> chunks = reference.chunks();
    const uint64_t directory_end = chunks[0].begin_byte;

    SECTION("a flipped byte anywhere is refused by a checksum") {
        const tom::StreamDeferred deferred = reference.deferred();
        REQUIRE(deferred.end_byte > deferred.begin_byte);  // (its provenance)
        for (const uint64_t at :
             {uint64_t(20), uint64_t(70), directory_end - 3, chunks[0].begin_byte + 5, deferred.begin_byte + 7, chunks[3].begin_byte + 9, stream.size() - 1}) {
            std::vector<uint8_t> bad = stream;
            bad[at] ^= 0x40;
            tom::StreamDecoder d(tom::meshopt_codecs(), "bad.tom");
            INFO("byte " << at);
            try {
                d.append(bad.data(), bad.size());
                FAIL("accepted");
            } catch (const tom::FormatError& e) {
                CHECK(e.path() == "bad.tom");
                CHECK(e.rule() >= 31);
                CHECK(e.rule() <= 34);
            }
            // what came before the bad chunk is kept, and the decoder takes no more bytes
            if (at >= chunks[0].end_byte) CHECK(d.file().mesh(0).vertex_count > 0);
            CHECK_THROWS_AS(d.append(bad.data(), 1), tom::ArgumentError);
        }
    }
    SECTION("a chunk or a table that lies behind valid checksums is refused by the decoder's checks") {
        std::vector<uint8_t> bad = stream;
        for (uint64_t i = chunks[2].begin_byte + 8; i < chunks[2].end_byte; ++i) bad[i] = uint8_t(bad[i] * 31 + 7);
        reseal(bad);
        tom::StreamDecoder d(tom::meshopt_codecs(), "lying.tom");
        try {
            d.append(bad.data(), bad.size());
            FAIL("accepted");
        } catch (const tom::FormatError& e) {
            INFO(e.what());
            CHECK(e.rule() >= 35);
            CHECK(e.offset() >= chunks[2].begin_byte);
            CHECK(e.offset() <= chunks[2].end_byte);
        }
        CHECK(d.decoded_chunks() == 2);
        // a chunk that decodes whole and only then is found to lie (its live triangle count, the
        // last check): its splits are undone, and what came before is the prefix it was
        std::vector<uint8_t> late = stream;
        Table lying = chunk_table(late);
        ++lying.records[3].triangle_end;
        put_table(late, lying);
        reseal(late);
        tom::StreamDecoder undone(tom::meshopt_codecs(), "late.tom");
        CHECK_THROWS_WITH(undone.append(late.data(), late.size()), Catch::Contains("late.tom") && Catch::Contains("live triangles"));
        REQUIRE(undone.decoded_chunks() == 3);
        const tom::File kept = undone.file();  // validated by the reader
        tom::StreamDecoder three(tom::meshopt_codecs());
        three.append(stream.data(), chunks[2].end_byte);
        const tom::File expected = three.file();
        CHECK(kept.mesh(0).vertex_count == chunks[2].vertex_end);
        CHECK(kept.mesh(0).triangle_count == chunks[2].triangles);
        CHECK(undone.tom_bytes() == three.tom_bytes());
        // a substitute coded as a difference below 0: chunk 3's splits block opens with the bit for
        // differences, then its first split's gamma(2), a difference of -1 from 0
        std::vector<uint8_t> below = stream;
        const uint64_t splits = chunks[3].begin_byte + 8 + 4;  // past its part's (base, born) and the block's length
        REQUIRE((below[splits] & 1u) == 1u);
        below[splits] = uint8_t((below[splits] & 0xF0u) | 0x05u);
        reseal(below);
        CHECK_THROWS_WITH(tom::StreamDecoder(tom::meshopt_codecs(), "b.tom").append(below.data(), below.size()),
                          Catch::Contains("b.tom") && Catch::Contains("chunk 3") && Catch::Contains("substitute below 0 is not below it (FORMAT.md rule 36)"));
        // a chunk table entry past the mesh's vertices
        std::vector<uint8_t> table = stream;
        Table past = chunk_table(table);
        past.records.back().vertex_end = 1u << 30;
        put_table(table, past);
        reseal(table);
        const std::string last = "chunk " + std::to_string(past.records.size() - 1) + " vertex_end";
        CHECK_THROWS_WITH(tom::StreamDecoder(tom::meshopt_codecs(), "t.tom").append(table.data(), table.size()), Catch::Contains("t.tom") && Catch::Contains(last));
        // a table entry that is not a varint of 32 bits: chunk 0's mesh in six bytes
        std::vector<uint8_t> wide = stream;
        const Table whole = chunk_table(wide);
        wide.erase(wide.begin() + int64_t(whole.begin));  // mesh 0's one byte
        const uint8_t six[6] = {0x80, 0x80, 0x80, 0x80, 0x80, 0x01};
        wide.insert(wide.begin() + int64_t(whole.begin), six, six + 6);
        tom::layout::store_u64(&wide[32], tom::layout::load_u64(&wide[32]) + 5);
        tom::layout::store_u64(&wide[16], tom::layout::load_u64(&wide[16]) + 5);
        tom::layout::store_u32(&wide[40], tom::crc32(&wide[64], tom::layout::load_u64(&wide[32])));
        tom::layout::store_u32(&wide[44], tom::crc32(wide.data(), 44));
        CHECK_THROWS_WITH(tom::StreamDecoder(tom::meshopt_codecs(), "w.tom").append(wide.data(), wide.size()),
                          Catch::Contains("w.tom") && Catch::Contains("chunk 0 mesh") && Catch::Contains("not a varint"));
        // a deferred block placed past the chunks, and a deferred section a frame needs
        std::vector<uint8_t> placed = stream;
        tom::layout::store_u32(&placed[72], tom::layout::load_u32(&placed[28]) + 1);
        reseal(placed);
        CHECK_THROWS_WITH(tom::StreamDecoder(tom::meshopt_codecs(), "p.tom").append(placed.data(), placed.size()),
                          Catch::Contains("p.tom") && Catch::Contains("deferred_after"));
        std::vector<uint8_t> needed = stream;
        std::memcpy(&needed[64 + 16 + 16 * uint64_t(tom::layout::load_u32(&needed[64]) - 1)], "MATL", 4);
        reseal(needed);
        CHECK_THROWS_WITH(tom::StreamDecoder(tom::meshopt_codecs(), "n.tom").append(needed.data(), needed.size()),
                          Catch::Contains("only PROV, IMAG and GLTF may be deferred"));
    }
    SECTION("an attribute block's prediction outside the version's is refused") {
        // chunk 2: its part's (base, born), the splits block, then POSI's prediction
        const uint64_t at = chunks[2].begin_byte + 8, prediction = at + 4 + tom::layout::load_u32(&stream[at]);
        std::vector<uint8_t> bad = stream;
        tom::layout::store_u32(&bad[prediction], 4);
        reseal(bad);
        CHECK_THROWS_WITH(tom::StreamDecoder(tom::meshopt_codecs(), "q.tom").append(bad.data(), bad.size()),
                          Catch::Contains("q.tom") && Catch::Contains("POSI prediction 4 is not 0 to 3"));
    }
    SECTION("a truncated file is an error unless a byte limit asks for a prefix") {
        const fs::path dir = fs::temp_directory_path() / ("tom_stream_" + std::to_string(::getpid()));
        fs::create_directories(dir);
        const fs::path path = dir / "cut.tom";
        std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(stream.data()), std::streamsize(chunks[4].end_byte + 10));
        CHECK_THROWS_WITH(tom::open_any(path.string()), Catch::Contains("cut.tom") && Catch::Contains("truncated"));
        const tom::File prefix = tom::open_any(path.string(), chunks[4].end_byte + 10);
        CHECK(prefix.mesh(0).vertex_count == chunks[4].vertex_end);
        CHECK_THROWS_WITH(tom::open_any(test::sample("meshes/fandisk.off"), 100), Catch::Contains("not a streamed .tom"));
        // a reader of ordinary files handed a stream says what it is and what decodes it
        CHECK_THROWS_WITH(tom::File::from_bytes(stream.data(), stream.size(), "s.tom"),
                          Catch::Contains("s.tom") && Catch::Contains("a streamed .tom") && Catch::Contains("tom_stream_create"));
        fs::remove_all(dir);
    }
}
