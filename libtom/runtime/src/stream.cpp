// Decoding streamed .tom files (docs/FORMAT.md, "Streamed files", rules 31 to 36): the directory,
// then each chunk as its last byte arrives, into per-mesh state from which tom_bytes() assembles
// an ordinary .tom of the resolutions received.

#include "tom/stream.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "format_layout.h"
#include "scene_codec.h"
#include "stream_layout.h"
#include "tom/errors.h"

namespace tom {

namespace {

using namespace stream_layout;
using layout::load_f32;
using layout::load_u32;
using layout::load_u64;

/// A carried stream (XATT) of a mesh: its record and the elements decoded so far.
struct Carried {
    VertexStreamView record;  // name, type, components, normalized (data unused)
    std::string name;
    uint32_t element_bytes = 0;
    std::vector<uint8_t> data;
};

/// Per vertex, the live corners holding it (3 t + k in the file's TRIS). A split reads the lists
/// of two vertices at random places, so each vertex has a line of 16 values in one array (its
/// count, then up to 15 corners: one or two cache lines, no pointer to follow); a vertex with more
/// corners, rare outside the coarsest levels, moves them to a list of its own, and its line then
/// holds the count and that list's index.
class CornerLists {
public:
    void resize(uint32_t vertices) { lines_.resize(size_t(vertices) * line, 0); }
    uint32_t size(uint32_t v) const { return lines_[size_t(v) * line]; }
    uint32_t* begin(uint32_t v) { return spilled(v) ? spill_[lines_[size_t(v) * line + 1]].data() : &lines_[size_t(v) * line + 1]; }
    uint32_t* end(uint32_t v) { return begin(v) + size(v); }
    void push(uint32_t v, uint32_t g) {
        uint32_t* l = &lines_[size_t(v) * line];
        if (l[0] < room) {
            l[1 + l[0]++] = g;
            return;
        }
        push_spilled(l, g);
    }
    /// Keeps the first n corners of v's list (the caller moved the kept ones there).
    void truncate(uint32_t v, uint32_t n) {
        uint32_t* l = &lines_[size_t(v) * line];
        if (spilled(v)) {
            std::vector<uint32_t>& list = spill_[l[1]];
            list.resize(n);
            if (n <= room) {  // back into its line
                std::copy(list.begin(), list.end(), l + 1);
                std::vector<uint32_t>().swap(list);
            }
        }
        l[0] = n;
    }

private:
    /// push() past the line's room (kept out of line: the usual push is a store and an increment).
#if defined(__GNUC__)
    __attribute__((noinline))
#endif
    void push_spilled(uint32_t* l, uint32_t g) {
        if (l[0] == room) {  // spill: the line's corners to a list of their own
            spill_.emplace_back(l + 1, l + 1 + room);
            l[1] = uint32_t(spill_.size() - 1);
        }
        spill_[l[1]].push_back(g);
        ++l[0];
    }
    static constexpr size_t line = 16;
    static constexpr uint32_t room = line - 1;
    bool spilled(uint32_t v) const { return lines_[size_t(v) * line] > room; }
    std::vector<uint32_t> lines_;
    std::vector<std::vector<uint32_t>> spill_;
};

/// The neighbourhood of a split (p into p and v) as its born triangles' candidates need it: p's
/// neighbours through the corners it kept (`near_p`, each marked `mark_p` in `seen`), and v's
/// through the corners it took, those also near p (`common`, remarked `mark_v`) and the others
/// (`v_only`, marked `mark_v`). The candidates (stream_layout::order_candidates) are `common`
/// ascending, then the rest ascending, which is listed only when a born triangle reaches past
/// `common` (a manifold split's third corners are both in it).
struct SplitScratch {
    Seen seen;
    uint32_t mark_p = 0, mark_v = 0;
    std::vector<uint32_t> near_p, common, v_only, rest;
    bool rest_listed = false;
    size_t born_from = 0;  // where the born third corners start in the ring being listed
    // per vertex u, `split` when a live triangle of this split's p has the edge (p, u) in its
    // order: stream_layout::predicted_orientation's answer for u, kept as the triangles are
    // listed and born instead of searched for each born triangle
    std::vector<uint32_t> after_p;
    uint32_t split = 0;
    uint32_t candidate_count() const { return uint32_t(near_p.size() + v_only.size()); }
    /// A new split's stamp for after_p (the array cleared when the stamps wrap around).
    void next_split() {
        if (++split == 0) std::fill(after_p.begin(), after_p.end(), 0), split = 1;
    }
    /// Notes the edge from p in triangle c, which holds p.
    void note_after_p(const uint32_t* c, uint32_t p) {
        const int k = c[0] == p ? 0 : c[1] == p ? 1 : 2;
        after_p[c[(k + 1) % 3]] = split;
    }
};

constexpr uint32_t none = UINT32_MAX;  // no vertex

/// How the chunk being decoded codes its splits' substitutes: since 1.3 a bit opens the splits
/// block, set when each is a difference from the one before (FORMAT.md), else index_bits(v) bits.
struct SubstituteCode {
    bool differences = false;
    uint32_t previous = 0;  // the chunk's last substitute read, 0 before its first
};

struct Residuals;  // an attribute's residuals in a chunk, below

/// A chunk's record as the directory's table holds it, with the file offsets of its fields (for
/// the errors that name them).
struct TableRecord {
    ChunkRecord r;
    uint64_t at_mesh = 0, at_vertex_end = 0, at_triangle_end = 0, at_bytes = 0;
};

/// A section that only grows as chunks arrive (a stream's values per vertex, the substitutes), as
/// stored, with the checksum of what it holds: an image copies it instead of making it again.
struct GrowingSection {
    std::vector<uint8_t> bytes;
    uint32_t checksum = 0;
    /// Room for n more bytes, to be written, then counted by grown().
    uint8_t* extend(size_t n) {
        bytes.resize(bytes.size() + n);
        return bytes.data() + bytes.size() - n;
    }
    void grown(size_t n) { checksum = crc32(bytes.data() + bytes.size() - n, n, checksum); }
};

/// A mesh as the directory declares it and as far as its chunks are decoded.
struct MeshState {
    // declared
    uint32_t vertex_count = 0, triangle_count = 0, min_vertex_count = 0, index_size = 4, attributes = 0;
    std::vector<Part> parts;               // the full ranges; one part of all triangles without PART
    std::vector<uint8_t> header, metadata, pair_bits;
    std::vector<Carried> carried;
    StreamQuantization quantization;
    // decoded: vertices [0, resolution), each part's live triangles at it
    uint32_t resolution = 0;
    std::vector<uint32_t> substitute;
    std::vector<uint16_t> positions;       // 3 per vertex, grid values
    std::vector<int16_t> normals, tangents;  // octahedral pairs; tangents add w
    std::vector<uint16_t> texcoords[2];    // 2 per vertex, grid values
    std::vector<uint8_t> colors;           // 4 per vertex
    std::vector<std::vector<uint32_t>> corners;  // per part, 3 per live triangle, mapped to resolution
    std::vector<uint64_t> part_ends;             // per part, first_triangle + triangle_count
    CornerLists incident;                        // per vertex: the live corners holding it
    // per vertex a + i of the chunk being decoded: its neighbours just after its split, in any
    // order (the prediction is their mean), at [ring_ends[i - 1], ring_ends[i]) of ring_items
    std::vector<uint32_t> ring_items;
    std::vector<size_t> ring_ends;
    SplitScratch split;                          // the neighbourhood of the split being decoded
    SubstituteCode substitute_code;              // the chunk being decoded's
    std::vector<std::pair<uint32_t, uint32_t>> rewritten;  // the chunk being decoded's corner writes: (3 t + k, old vertex)
    std::vector<uint32_t> births;                // scratch: a split's born triangles per part
    // the sections of the vertices [0, resolution) that only grow: the streams dequantized, the
    // substitutes; and the grid's bounds of the positions (extended after each chunk)
    GrowingSection positions_out, normals_out, texcoords_out[2], colors_out, tangents_out, substitutes_out;
    uint16_t grid_min[3] = {0, 0, 0}, grid_max[3] = {0, 0, 0};
};

/// A mesh's decoded state before a chunk: the streams' lengths. With the corners the chunk
/// rewrote (MeshState::rewritten) it puts the mesh back when the chunk turns out bad, so that what
/// was decoded before stays a valid prefix. The incident lists are not put back: a failed decoder
/// decodes nothing more, and assembling needs only the corners and streams.
struct MeshUndo {
    size_t substitute, positions, normals, tangents, texcoords[2], colors;
    std::vector<size_t> corners, carried;

    explicit MeshUndo(MeshState& m)
        : substitute(m.substitute.size()), positions(m.positions.size()), normals(m.normals.size()), tangents(m.tangents.size()),
          texcoords{m.texcoords[0].size(), m.texcoords[1].size()}, colors(m.colors.size()) {
        for (const auto& c : m.corners) corners.push_back(c.size());
        for (const Carried& c : m.carried) carried.push_back(c.data.size());
        m.rewritten.clear();
    }
    void restore(MeshState& m) const;
};

/// A bounded view of the bytes of one chunk, read front to back.
struct ChunkReader {
    const uint8_t* data;
    uint64_t bytes, at = 0, file_offset;
    const std::string* path;
    const std::string* field;
    [[noreturn]] void fail(const std::string& detail, int rule = 35) const {
        throw FormatError(*path, file_offset + at, *field, rule, detail);
    }
    uint32_t u32() {
        if (bytes - at < 4) fail("ends inside a count");
        const uint32_t v = load_u32(data + at);
        at += 4;
        return v;
    }
    /// The next block: its u32 length, then that many bytes.
    std::pair<const uint8_t*, uint64_t> block(const char* what) {
        const uint32_t n = u32();
        if (n > bytes - at) fail(std::string(what) + " block of " + std::to_string(n) + " bytes runs past the chunk's end");
        const uint8_t* p = data + at;
        at += n;
        return {p, n};
    }
};

/// Bits, least significant first, within a block; reading past it is an error.
struct BitReader {
    const uint8_t* data;
    uint64_t bytes, at = 0;
    ChunkReader* in;
    /// The next n <= 32 bits: the (at most five) bytes holding them, shifted into place.
    uint32_t bits(uint32_t n) {
        if (n == 0) return 0;
        if (8 * bytes - at < n) fail("runs past the splits block");
        const uint32_t value = uint32_t(window() >> (at % 8)) & (n == 32 ? ~0u : (1u << n) - 1);
        at += n;
        return value;
    }
    /// Elias gamma: n >= 1 (its zeros counted in the window, not a bit at a time).
    uint32_t gamma() {
        const uint64_t ahead = window() >> (at % 8);  // at least 57 bits, zero past the block's end
        const uint32_t zeros = ahead ? uint32_t(__builtin_ctzll(ahead)) : 64;
        if (zeros > 31) fail(8 * bytes - at < 32 ? "runs past the splits block" : "holds a gamma code of more than 32 bits");
        at += zeros + 1;  // the zeros and the leading 1 (a 1 is never past the block)
        return (1u << zeros) | bits(zeros);
    }
    /// The eight bytes from the one holding bit `at`, least significant first; bytes past the
    /// block read as zero.
    uint64_t window() const {
        const uint64_t first = at / 8;
        uint64_t word = 0;
        if (bytes - first >= 8) {
            std::memcpy(&word, data + first, 8);  // little-endian hosts (x86, wasm, arm64)
            return word;
        }
        for (uint64_t i = first; i < bytes; ++i) word |= uint64_t(data[i]) << (8 * (i - first));
        return word;
    }
    [[noreturn]] void fail(const std::string& detail) const;
};

void BitReader::fail(const std::string& detail) const { in->fail("splits block bit " + std::to_string(at) + " " + detail); }

} // namespace

bool is_stream(const void* bytes, size_t size) noexcept { return size >= 8 && std::memcmp(bytes, magic, 8) == 0; }

struct StreamDecoder::Impl {
    StreamCodecs codecs;
    std::string path;
    std::vector<uint8_t> pending;     // received bytes not yet consumed
    uint64_t received = 0, consumed = 0;
    bool failed = false, directory = false, verify = true;
    uint64_t declared_bytes = 0;
    uint32_t meshes_declared = 0, chunks_declared = 0, minor = 0;
    uint64_t directory_bytes = 0;
    std::vector<layout::PendingSection> file_sections;  // MATL, INST, PROV, IMAG, GLTF as stored
    std::vector<uint32_t> file_checksums;               // theirs, computed once
    std::vector<MeshState> meshes;
    std::vector<StreamChunk> chunks;
    std::vector<uint32_t> chunk_checksums;
    size_t decoded = 0;
    /// The deferred block: its sections' entries, where it stands, its CRC.
    struct DeferredEntry {
        uint32_t type = 0, mesh = 0;
        uint64_t bytes = 0;
    };
    std::vector<DeferredEntry> deferred_entries;
    StreamDeferred deferred;
    uint32_t deferred_checksum = 0;
    bool deferred_read = false;

    [[noreturn]] void fail(uint64_t offset, const std::string& field, int rule, const std::string& detail) const {
        throw FormatError(path, offset, field, rule, detail);
    }

    void take(const uint8_t* bytes, size_t size);
    void read_header();
    void read_directory();
    void read_kept_section(uint32_t type, uint32_t mesh, const uint8_t* data, uint64_t bytes, uint64_t offset);
    void read_quantization(MeshState& m, const uint8_t* q, uint64_t offset, const std::string& field);
    uint64_t read_table_records(const uint8_t* d, uint64_t table, std::vector<TableRecord>& records);
    void read_chunk_table(const std::vector<TableRecord>& records, uint64_t offset, uint64_t deferred_bytes);
    void read_deferred(const uint8_t* data);
    void decode_chunk(const StreamChunk& chunk, const uint8_t* data, uint64_t bytes);
    void decode_chunk_blocks(MeshState& m, const StreamChunk& chunk, const uint8_t* data, uint64_t bytes);
    void decode_base(MeshState& m, ChunkReader& in, const std::vector<uint32_t>& base);
    void decode_splits(MeshState& m, ChunkReader& in, uint32_t a, uint32_t b, const std::vector<uint32_t>& born);
    void split_vertex(MeshState& m, ChunkReader& in, BitReader& r, uint32_t v, std::vector<uint32_t>& left);
    uint64_t born_counts(MeshState& m, ChunkReader& in, BitReader& r, uint32_t v, std::vector<uint32_t>& left);
    void bear(MeshState& m, ChunkReader& in, BitReader& r, uint32_t p, uint32_t v, size_t part, uint32_t paired);
    void decode_vertices(MeshState& m, ChunkReader& in, uint32_t a, uint32_t b);
    void decode_attributes(MeshState& m, ChunkReader& in, const Residuals* r, uint32_t a, uint32_t b);
    void rotate_back(ChunkReader& in, uint32_t* corners, uint32_t triangles);
    std::vector<uint8_t> assemble() const;
    void mesh_sections(const MeshState& m, uint32_t index, std::vector<std::vector<uint8_t>>& storage, std::vector<layout::SectionView>& views) const;
};

StreamDecoder::StreamDecoder(const StreamCodecs& codecs, std::string name, const OpenOptions& options) : impl_(std::make_unique<Impl>()) {
    if (!codecs.decode_vertices || !codecs.decode_indices) throw ArgumentError("StreamDecoder: both codecs are required");
    impl_->codecs = codecs;
    impl_->verify = options.verify_checksums;
    impl_->path = std::move(name);
}
StreamDecoder::StreamDecoder(StreamDecoder&&) noexcept = default;
StreamDecoder& StreamDecoder::operator=(StreamDecoder&&) noexcept = default;
StreamDecoder::~StreamDecoder() = default;

void StreamDecoder::append(const void* bytes, size_t size) {
    if (impl_->failed) throw ArgumentError("StreamDecoder: " + impl_->path + " failed to decode; it takes no more bytes");
    try {
        impl_->take(static_cast<const uint8_t*>(bytes), size);
    } catch (...) {
        impl_->failed = true;
        throw;
    }
}

bool StreamDecoder::has_directory() const noexcept { return impl_->directory; }
uint64_t StreamDecoder::bytes_received() const noexcept { return impl_->received; }
uint64_t StreamDecoder::file_bytes() const noexcept { return impl_->declared_bytes; }
uint32_t StreamDecoder::mesh_count() const noexcept { return uint32_t(impl_->meshes.size()); }
const std::vector<StreamChunk>& StreamDecoder::chunks() const noexcept { return impl_->chunks; }
size_t StreamDecoder::decoded_chunks() const noexcept { return impl_->decoded; }
bool StreamDecoder::complete() const noexcept { return impl_->directory && impl_->decoded == impl_->chunks.size() && impl_->deferred_read; }
const StreamDeferred& StreamDecoder::deferred() const noexcept { return impl_->deferred; }
bool StreamDecoder::deferred_received() const noexcept { return impl_->deferred_read; }
uint64_t StreamDecoder::next_boundary() const noexcept {
    const Impl& d = *impl_;
    if (!d.declared_bytes) return header_bytes;
    if (!d.directory) return header_bytes + d.directory_bytes;
    if (!d.deferred_read && d.decoded == d.deferred.after_chunk) return d.deferred.end_byte;
    return d.decoded < d.chunks.size() ? d.chunks[d.decoded].end_byte : d.declared_bytes;
}
uint32_t StreamDecoder::vertex_count(uint32_t mesh) const noexcept { return mesh < impl_->meshes.size() ? impl_->meshes[mesh].resolution : 0; }
const StreamQuantization& StreamDecoder::quantization(uint32_t mesh) const noexcept { return impl_->meshes[mesh].quantization; }
void StreamDecoder::declared_bounds(uint32_t mesh, float min[3], float max[3]) const noexcept {
    const std::vector<uint8_t>& h = impl_->meshes[mesh].header;  // at least the 64-byte header (rule 32)
    for (int k = 0; k < 3; ++k) min[k] = layout::load_f32(&h[layout::m_bounds_min + 4 * k]), max[k] = layout::load_f32(&h[layout::m_bounds_max + 4 * k]);
}

std::vector<uint8_t> StreamDecoder::tom_bytes() const {
    if (!impl_->directory) impl_->fail(impl_->received, "directory", 31, "the directory has not arrived (" + std::to_string(impl_->received) + " bytes received)");
    return impl_->assemble();
}

File StreamDecoder::file() const {
    OpenOptions no_checksums;
    no_checksums.verify_checksums = false;  // just computed
    return File::adopt(tom_bytes(), impl_->path, no_checksums);
}

// Appends the bytes, then consumes whatever is complete: the header and directory once, then
// chunks in order.
void StreamDecoder::Impl::take(const uint8_t* bytes, size_t size) {
    pending.insert(pending.end(), bytes, bytes + size);
    received += size;
    if (declared_bytes && received > declared_bytes) fail(declared_bytes, "file_bytes", 31, "the stream has bytes past its declared end of " + std::to_string(declared_bytes));
    if (!directory) {
        if (received >= header_bytes && !declared_bytes) read_header();
        if (!declared_bytes || received < header_bytes + directory_bytes) return;
        read_directory();
    }
    size_t used = 0;
    for (;;) {
        if (!deferred_read && decoded == deferred.after_chunk) {  // the deferred block's turn
            if (deferred.end_byte > received) break;
            read_deferred(pending.data() + (deferred.begin_byte - consumed));
            used = deferred.end_byte - consumed;
            continue;
        }
        if (decoded == chunks.size()) break;
        const StreamChunk& c = chunks[decoded];
        if (c.end_byte > received) break;
        const uint8_t* data = pending.data() + (c.begin_byte - consumed);
        const uint64_t n = c.end_byte - c.begin_byte;
        if (verify && crc32(data, n) != chunk_checksums[decoded])
            fail(c.begin_byte, "chunk " + std::to_string(decoded), 34, "checksum mismatch: the chunk is corrupt");
        decode_chunk(c, data, n);
        ++decoded;
        used = c.end_byte - consumed;
    }
    pending.erase(pending.begin(), pending.begin() + used);
    consumed += used;
}

// rule 31: the header
void StreamDecoder::Impl::read_header() {
    const uint8_t* h = pending.data();
    if (std::memcmp(h, magic, 8) != 0) fail(0, "magic", 31, "not a streamed .tom file (bad magic)");
    const uint32_t major = load_u32(h + h_version_major);
    if (major != version_major)
        fail(h_version_major, "version_major", 31, "unsupported stream version " + std::to_string(major) + "." + std::to_string(load_u32(h + h_version_minor)) + " (this reader reads 1.x)");
    if (verify && crc32(h, h_header_checksum) != load_u32(h + h_header_checksum)) fail(h_header_checksum, "header_checksum", 31, "header checksum mismatch");
    minor = load_u32(h + h_version_minor);
    const uint64_t file = load_u64(h + h_file_bytes);
    directory_bytes = load_u64(h + h_directory_bytes);
    meshes_declared = load_u32(h + h_mesh_count);
    chunks_declared = load_u32(h + h_chunk_count);
    if (directory_bytes > file || file - directory_bytes < header_bytes)
        fail(h_directory_bytes, "directory_bytes", 31, "a directory of " + std::to_string(directory_bytes) + " bytes does not fit in a file of " + std::to_string(file));
    // every mesh takes at least its kept MESH entry and quantization record, every chunk its record
    const uint64_t record_bytes = minor >= 2 ? compact_record_min_bytes : chunk_record_bytes;
    if (uint64_t(meshes_declared) * (kept_entry_bytes + quantization_bytes) + uint64_t(chunks_declared) * record_bytes > directory_bytes)
        fail(h_mesh_count, "mesh_count", 31, std::to_string(meshes_declared) + " meshes and " + std::to_string(chunks_declared) + " chunks do not fit in a directory of " + std::to_string(directory_bytes) + " bytes");
    declared_bytes = file;
    if (received > declared_bytes) fail(declared_bytes, "file_bytes", 31, "the stream has bytes past its declared end of " + std::to_string(declared_bytes));
}

// rule 32: the directory (kept sections, quantization, chunk table)
void StreamDecoder::Impl::read_directory() {
    const uint8_t* d = pending.data() + header_bytes;
    const uint64_t base = header_bytes;
    if (verify && crc32(d, directory_bytes) != load_u32(pending.data() + h_directory_checksum)) fail(h_directory_checksum, "directory_checksum", 32, "directory checksum mismatch");
    if (directory_bytes < directory_header_bytes) fail(base, "directory", 32, "shorter than its 16-byte header");
    const uint64_t kept = load_u32(d + d_kept_count), deferred_count = load_u32(d + d_deferred_count);
    deferred.after_chunk = load_u32(d + d_deferred_after);
    deferred_checksum = load_u32(d + d_deferred_checksum);
    if (deferred_count > kept)
        fail(base + d_deferred_count, "directory deferred_count", 32,
             std::to_string(deferred_count) + " deferred of " + std::to_string(kept) + " kept sections");
    if (deferred.after_chunk > chunks_declared)
        fail(base + d_deferred_after, "directory deferred_after", 32,
             "the deferred block follows chunk " + std::to_string(deferred.after_chunk) + " of " + std::to_string(chunks_declared));
    if (!deferred_count && (deferred.after_chunk || deferred_checksum))
        fail(base + d_deferred_after, "directory deferred_after", 32, "nonzero without deferred sections");
    meshes.resize(meshes_declared);
    const uint64_t entries = directory_header_bytes, quant = entries + kept * kept_entry_bytes, table = quant + uint64_t(meshes_declared) * quantization_bytes;
    if (table > directory_bytes) fail(base, "directory kept_count", 32, std::to_string(kept) + " kept sections do not fit in the directory");
    std::vector<TableRecord> records;
    uint64_t data = read_table_records(d, table, records);
    uint64_t deferred_bytes = 0;
    for (uint64_t k = 0; k < kept; ++k) {
        const uint8_t* e = d + entries + k * kept_entry_bytes;
        const uint32_t type = load_u32(e), mesh = load_u32(e + 4);
        const uint64_t bytes = load_u64(e + 8), entry = base + entries + k * kept_entry_bytes;
        if (k >= kept - deferred_count) {  // its data in the deferred block
            if (mesh != layout::file_level || !deferrable(type))
                fail(entry, "kept section " + std::to_string(k), 32, "only PROV, IMAG and GLTF may be deferred");
            if (bytes > declared_bytes - deferred_bytes)
                fail(entry + 8, "kept section " + std::to_string(k) + " bytes", 32, "the deferred block runs past the file's end");
            deferred_entries.push_back({type, mesh, bytes});
            deferred.sections.push_back(layout::fourcc_name(type));
            deferred_bytes += bytes;
            continue;
        }
        if (bytes > directory_bytes - data) fail(entry + 8, "kept section " + std::to_string(k) + " bytes", 32, "runs past the directory's end");
        read_kept_section(type, mesh, d + data, bytes, base + data);
        data += bytes;
    }
    deferred_read = !deferred_count;
    if (data != directory_bytes) fail(base + data, "directory", 32, std::to_string(directory_bytes - data) + " bytes after the kept sections");
    for (uint32_t m = 0; m < meshes_declared; ++m) {
        const std::string field = "mesh " + std::to_string(m);
        if (meshes[m].header.empty()) fail(base, field + " MESH", 32, "the directory keeps no MESH section for the mesh");
        if (!meshes[m].pair_bits.empty() && meshes[m].pair_bits.size() != (uint64_t(meshes[m].vertex_count) + 7) / 8)
            fail(base, field + " PAIR", 32, std::to_string(meshes[m].pair_bits.size()) + " bytes where the mesh's vertices require " + std::to_string((uint64_t(meshes[m].vertex_count) + 7) / 8));
        read_quantization(meshes[m], d + quant + uint64_t(m) * quantization_bytes, base + quant + uint64_t(m) * quantization_bytes, field + " quantization");
    }
    read_chunk_table(records, base + table, deferred_bytes);
    pending.erase(pending.begin(), pending.begin() + header_bytes + directory_bytes);
    consumed = header_bytes + directory_bytes;
    directory = true;
}

// A section the directory keeps whole: a file-level one as stored, or a mesh's header, metadata,
// groups, parts or carried streams' records.
void StreamDecoder::Impl::read_kept_section(uint32_t type, uint32_t mesh, const uint8_t* data, uint64_t bytes, uint64_t offset) {
    using namespace layout;
    if (mesh == file_level) {
        file_sections.push_back({type, mesh, std::vector<uint8_t>(data, data + bytes)});
        file_checksums.push_back(crc32(data, bytes));
        return;
    }
    if (mesh >= meshes.size()) fail(offset, "kept section", 32, "names mesh " + std::to_string(mesh) + " of " + std::to_string(meshes.size()));
    MeshState& m = meshes[mesh];
    const std::string field = "mesh " + std::to_string(mesh);
    if (type == sec_mesh) {
        if (bytes < mesh_header_bytes) fail(offset, field + " MESH", 32, "shorter than the 64-byte mesh header");
        m.header.assign(data, data + bytes);
        m.vertex_count = load_u32(data + m_vertex_count);
        m.triangle_count = load_u32(data + m_triangle_count);
        m.min_vertex_count = load_u32(data + m_min_vertex_count);
        m.index_size = load_u32(data + m_index_size);
        m.attributes = load_u32(data + m_attributes);
        if (m.vertex_count > 0 && (m.min_vertex_count < 1 || m.min_vertex_count > m.vertex_count))
            fail(offset + m_min_vertex_count, field + " min_vertex_count", 32, std::to_string(m.min_vertex_count) + " is not in [1, " + std::to_string(m.vertex_count) + "]");
        if (m.index_size != 2 && m.index_size != 4) fail(offset + m_index_size, field + " index_size", 32, "is " + std::to_string(m.index_size) + ", not 2 or 4");
        if (m.attributes & ~known_attributes) fail(offset + m_attributes, field + " attributes", 32, "has unknown bits");
        if (m.parts.empty()) m.parts.push_back({0, m.triangle_count, int32_t(load_u32(data + m_material)), m.attributes & stream_attributes});
    } else if (type == sec_metadata) {
        m.metadata.assign(data, data + bytes);
    } else if (type == sec_pairs) {
        m.pair_bits.assign(data, data + bytes);
    } else if (type == sec_parts) {
        if (bytes < parts_header_bytes || (bytes - parts_header_bytes) % part_record_bytes || load_u32(data) != (bytes - parts_header_bytes) / part_record_bytes)
            fail(offset, field + " PART", 32, "is not a header and its part records");
        m.parts.clear();
        for (uint64_t k = 0; k < (bytes - parts_header_bytes) / part_record_bytes; ++k) {
            const uint8_t* r = data + parts_header_bytes + k * part_record_bytes;
            m.parts.push_back({load_u32(r), load_u32(r + 4), int32_t(load_u32(r + 8)), load_u32(r + 12)});
        }
    } else if (type == sec_extra_streams) {
        for (const VertexStreamView& s : detail::decode_extra_streams(data, bytes, offset, path, field, 0)) {
            Carried c;
            c.record = s;
            c.name = std::string(s.name);
            c.element_bytes = s.components * component_bytes(s.component_type);
            m.carried.push_back(std::move(c));
        }
        for (Carried& c : m.carried) c.record.name = c.name;
    } else {
        fail(offset, field + " kept section", 32, "a mesh keeps only MESH, META, PAIR, PART and XATT in the directory");
    }
}

void StreamDecoder::Impl::read_quantization(MeshState& m, const uint8_t* q, uint64_t offset, const std::string& field) {
    StreamQuantization& s = m.quantization;
    s.position_bits = load_u32(q + q_position_bits);
    s.normal_bits = load_u32(q + q_normal_bits);
    s.texcoord_bits = load_u32(q + q_texcoord_bits);
    if (s.position_bits < 1 || s.position_bits > 16) fail(offset + q_position_bits, field + " position_bits", 32, std::to_string(s.position_bits) + " is not in [1, 16]");
    if (s.normal_bits < 2 || s.normal_bits > 16) fail(offset + q_normal_bits, field + " normal_bits", 32, std::to_string(s.normal_bits) + " is not in [2, 16]");
    if (s.texcoord_bits < 1 || s.texcoord_bits > 16) fail(offset + q_texcoord_bits, field + " texcoord_bits", 32, std::to_string(s.texcoord_bits) + " is not in [1, 16]");
    auto finite = [&](uint32_t at, const char* name, bool positive) {
        const float v = load_f32(q + at);
        if (!std::isfinite(v) || (positive && !(v > 0))) fail(offset + at, field + " " + name, 32, positive ? "is not a finite positive step" : "is not finite");
        return v;
    };
    for (int k = 0; k < 3; ++k) s.position_min[k] = finite(q_position_min + 4 * k, "position_min", false);
    s.position_step = finite(q_position_step, "position_step", true);
    for (int t = 0; t < 2; ++t)
        for (int k = 0; k < 2; ++k) {
            s.texcoord_min[t][k] = finite((t ? q_texcoord1_min : q_texcoord0_min) + 4 * k, "texcoord_min", false);
            s.texcoord_step[t][k] = finite((t ? q_texcoord1_step : q_texcoord0_step) + 4 * k, "texcoord_step", true);
        }
    m.corners.resize(m.parts.size());
    // the parts tile the triangles: a corner's place in TRIS names its part
    uint64_t end = 0;
    for (const Part& p : m.parts) {
        if (p.first_triangle != end) fail(offset, field + " PART", 32, "the parts do not tile the mesh's triangles in order");
        end += p.triangle_count;
        m.part_ends.push_back(end);
    }
    if (end != m.triangle_count) fail(offset, field + " PART", 32, "the parts hold " + std::to_string(end) + " triangles, not the mesh's " + std::to_string(m.triangle_count));
}

// rules 32 and 33: the chunk table's records, 24 bytes each in 1.0 and 1.1, compact since 1.2
// (stream_layout::put_chunk_table), each naming an existing mesh; returns where the table ends in
// the directory `d`, the table starting at `table`
uint64_t StreamDecoder::Impl::read_table_records(const uint8_t* d, uint64_t table, std::vector<TableRecord>& records) {
    const uint64_t base = header_bytes;
    records.resize(chunks_declared);
    if (minor < 2) {
        if (uint64_t(chunks_declared) * chunk_record_bytes > directory_bytes - table) fail(base + table, "chunk table", 32, "runs past the directory's end");
        for (uint32_t k = 0; k < chunks_declared; ++k) {
            const uint64_t at = table + uint64_t(k) * chunk_record_bytes;
            TableRecord& t = records[k];
            const uint8_t* r = d + at;
            t.r = {load_u32(r + r_mesh), load_u32(r + r_vertex_end), load_u32(r + r_triangle_end), load_u32(r + r_bytes), load_u32(r + r_checksum)};
            t.at_mesh = base + at + r_mesh;
            t.at_vertex_end = base + at + r_vertex_end;
            t.at_triangle_end = base + at + r_triangle_end;
            t.at_bytes = base + at + r_bytes;
            if (t.r.mesh >= meshes_declared)
                fail(t.at_mesh, "chunk " + std::to_string(k) + " mesh", 33, "mesh " + std::to_string(t.r.mesh) + " does not exist");
        }
        return table + uint64_t(chunks_declared) * chunk_record_bytes;
    }
    std::vector<ChunkRecord> last(meshes_declared);
    uint64_t at = table;
    for (uint32_t k = 0; k < chunks_declared; ++k) {
        TableRecord& t = records[k];
        const std::string field = "chunk " + std::to_string(k);
        auto varint = [&](uint64_t& field_at, const char* name) {
            field_at = base + at;
            uint32_t v = 0;
            if (!get_varint(d, directory_bytes, at, v)) fail(field_at, field + " " + name, 32, "not a varint of at most 32 bits within the directory");
            return v;
        };
        t.r.mesh = varint(t.at_mesh, "mesh");
        if (t.r.mesh >= meshes_declared) fail(t.at_mesh, field + " mesh", 33, "mesh " + std::to_string(t.r.mesh) + " does not exist");
        const ChunkRecord& before = last[t.r.mesh];
        const uint64_t vertex_end = uint64_t(before.vertex_end) + varint(t.at_vertex_end, "vertex_end");
        const uint64_t triangle_end = uint64_t(before.triangle_end) + varint(t.at_triangle_end, "triangle_end");
        if (vertex_end > UINT32_MAX) fail(t.at_vertex_end, field + " vertex_end", 33, "past 2^32 - 1");
        if (triangle_end > UINT32_MAX) fail(t.at_triangle_end, field + " triangle_end", 33, "past 2^32 - 1");
        t.r.vertex_end = uint32_t(vertex_end), t.r.triangle_end = uint32_t(triangle_end);
        t.r.bytes = varint(t.at_bytes, "bytes");
        if (directory_bytes - at < 4) fail(base + at, field + " checksum", 32, "runs past the directory's end");
        t.r.checksum = load_u32(d + at);
        at += 4;
        last[t.r.mesh] = t.r;
    }
    return at;
}

// rule 33: every chunk adds vertices to one mesh, from where its previous chunk ended, without
// splitting a group of copies; the first reaches the survivors, the last the whole mesh
void StreamDecoder::Impl::read_chunk_table(const std::vector<TableRecord>& records, uint64_t offset, uint64_t deferred_bytes) {
    std::vector<uint32_t> end(meshes.size(), 0);
    uint64_t at = header_bytes + directory_bytes;
    auto place_deferred = [&] {
        if (deferred_bytes > declared_bytes - at) fail(offset, "deferred block", 33, "runs past the file's end");
        deferred.begin_byte = at, deferred.end_byte = at + deferred_bytes;
        at = deferred.end_byte;
    };
    for (uint32_t k = 0; k < chunks_declared; ++k) {
        if (k == deferred.after_chunk) place_deferred();
        const TableRecord& r = records[k];
        const std::string field = "chunk " + std::to_string(k);
        StreamChunk c;
        c.mesh = r.r.mesh;  // (an existing one: read_table_records)
        const MeshState& m = meshes[c.mesh];
        MeshView groups;  // the mesh's groups of copies (PAIR, its size checked with the directory)
        groups.vertex_count = m.vertex_count;
        groups.pair_bits = m.pair_bits.empty() ? nullptr : m.pair_bits.data();
        c.vertex_begin = end[c.mesh];
        c.vertex_end = r.r.vertex_end;
        c.triangles = r.r.triangle_end;
        if (c.vertex_end <= c.vertex_begin || c.vertex_end > m.vertex_count)
            fail(r.at_vertex_end, field + " vertex_end", 33,
                 std::to_string(c.vertex_end) + " is not in (" + std::to_string(c.vertex_begin) + ", " + std::to_string(m.vertex_count) + "]");
        if (c.vertex_end < m.min_vertex_count)
            fail(r.at_vertex_end, field + " vertex_end", 33, "the mesh's first chunk holds its " + std::to_string(m.min_vertex_count) + " survivors");
        if (groups.splits_pair(c.vertex_end)) fail(r.at_vertex_end, field + " vertex_end", 33, "ends inside a group of copies");
        if (c.triangles > m.triangle_count)
            fail(r.at_triangle_end, field + " triangle_end", 33, "past the mesh's " + std::to_string(m.triangle_count) + " triangles");
        end[c.mesh] = c.vertex_end;
        c.begin_byte = at;
        c.end_byte = at + r.r.bytes;
        if (c.end_byte > declared_bytes) fail(r.at_bytes, field + " bytes", 33, "runs past the file's end");
        at = c.end_byte;
        chunks.push_back(c);
        chunk_checksums.push_back(r.r.checksum);
    }
    if (deferred.after_chunk == chunks_declared) place_deferred();
    if (at != declared_bytes) fail(h_file_bytes, "file_bytes", 33, "the chunks end at byte " + std::to_string(at) + ", not at the file's " + std::to_string(declared_bytes));
    for (uint32_t m = 0; m < meshes.size(); ++m)
        if (end[m] != meshes[m].vertex_count)
            fail(offset, "mesh " + std::to_string(m) + " chunks", 33, "reach vertex " + std::to_string(end[m]) + " of " + std::to_string(meshes[m].vertex_count));
}

// rule 34: the deferred block's checksum; then its sections join the file's
void StreamDecoder::Impl::read_deferred(const uint8_t* data) {
    if (verify && crc32(data, deferred.end_byte - deferred.begin_byte) != deferred_checksum)
        fail(deferred.begin_byte, "deferred block", 34, "checksum mismatch: the block is corrupt");
    uint64_t at = 0;
    for (const DeferredEntry& e : deferred_entries) {
        read_kept_section(e.type, e.mesh, data + at, e.bytes, deferred.begin_byte + at);
        at += e.bytes;
    }
    deferred_read = true;
}

namespace {

// The growing sections extended by vertices [from, to), decoded (MeshState::positions_out ...).
void extend_sections(MeshState& m, uint32_t from, uint32_t to) {
    using namespace layout;
    const StreamQuantization& q = m.quantization;
    // `lanes` floats per vertex, value(v, k) each
    auto floats = [&](GrowingSection& section, int lanes, auto&& value) {
        const size_t n = size_t(to - from) * size_t(lanes) * 4;
        uint8_t* out = section.extend(n);
        for (uint32_t v = from; v < to; ++v)
            for (int k = 0; k < lanes; ++k, out += 4) store_f32(out, value(v, k));
        section.grown(n);
    };
    for (uint32_t v = from; v < to; ++v)
        for (int k = 0; k < 3; ++k) {
            const uint16_t g = m.positions[3 * size_t(v) + size_t(k)];
            m.grid_min[k] = v == 0 ? g : std::min(m.grid_min[k], g);
            m.grid_max[k] = v == 0 ? g : std::max(m.grid_max[k], g);
        }
    floats(m.positions_out, 3, [&](uint32_t v, int k) { return dequantize(m.positions[3 * size_t(v) + size_t(k)], q.position_min[k], q.position_step); });
    if (m.attributes & attr_normals) {
        float n[3] = {0, 0, 0};
        floats(m.normals_out, 3, [&](uint32_t v, int k) {
            if (k == 0) octahedral_decode(m.normals[2 * size_t(v)], m.normals[2 * size_t(v) + 1], q.normal_bits, n);
            return n[k];
        });
    }
    for (int t = 0; t < 2; ++t)
        if (m.attributes & (t ? attr_texcoords1 : attr_texcoords))
            floats(m.texcoords_out[t], 2,
                   [&](uint32_t v, int k) { return dequantize(m.texcoords[t][2 * size_t(v) + size_t(k)], q.texcoord_min[t][k], q.texcoord_step[t][k]); });
    if (m.attributes & attr_colors) floats(m.colors_out, 4, [&](uint32_t v, int k) { return float(m.colors[4 * size_t(v) + size_t(k)]) / 255.0f; });
    if (m.attributes & attr_tangents) {
        float t[4] = {0, 0, 0, 0};
        floats(m.tangents_out, 4, [&](uint32_t v, int k) {
            if (k == 0) {
                octahedral_decode(m.tangents[3 * size_t(v)], m.tangents[3 * size_t(v) + 1], q.normal_bits, t);
                t[3] = m.tangents[3 * size_t(v) + 2] < 0 ? -1.0f : 1.0f;
            }
            return t[k];
        });
    }
    store_indices(m.substitutes_out.extend(size_t(to - from) * m.index_size), m.substitute.data() + from, to - from, m.index_size);
    m.substitutes_out.grown(size_t(to - from) * m.index_size);
}

}  // namespace

// rules 35 and 36: a chunk's counts, its blocks and the values they decode to; a bad chunk leaves
// its mesh as it was
void StreamDecoder::Impl::decode_chunk(const StreamChunk& chunk, const uint8_t* data, uint64_t bytes) {
    MeshState& m = meshes[chunk.mesh];
    const MeshUndo undo(m);
    try {
        decode_chunk_blocks(m, chunk, data, bytes);
    } catch (...) {
        undo.restore(m);
        throw;
    }
    extend_sections(m, m.resolution, chunk.vertex_end);
    m.resolution = chunk.vertex_end;
}

void StreamDecoder::Impl::decode_chunk_blocks(MeshState& m, const StreamChunk& chunk, const uint8_t* data, uint64_t bytes) {
    const std::string field = "chunk " + std::to_string(&chunk - chunks.data());
    ChunkReader in{data, bytes, 0, chunk.begin_byte, &path, &field};
    // a block of count elements holds at least count / 16 bytes, a split at least a bit: a bound
    // on what a chunk makes the decoder allocate
    const uint64_t plausible = 16 * bytes + 16;
    if (chunk.vertex_end - chunk.vertex_begin > plausible) in.fail(std::to_string(chunk.vertex_end - chunk.vertex_begin) + " vertices cannot fit in " + std::to_string(bytes) + " bytes");
    std::vector<uint32_t> base(m.parts.size()), born(m.parts.size());
    for (size_t p = 0; p < m.parts.size(); ++p) {
        base[p] = in.u32();
        born[p] = in.u32();
        const uint64_t live = m.corners[p].size() / 3;
        if (base[p] && chunk.vertex_begin > 0) in.fail("part " + std::to_string(p) + " has coarsest triangles outside the mesh's first chunk");
        if (uint64_t(base[p]) + born[p] > m.parts[p].triangle_count - live)
            in.fail("part " + std::to_string(p) + " adds " + std::to_string(uint64_t(base[p]) + born[p]) + " triangles to its " + std::to_string(live) + " of " + std::to_string(m.parts[p].triangle_count));
        if (base[p] > plausible || born[p] > plausible) in.fail("part " + std::to_string(p) + "'s counts cannot fit in " + std::to_string(bytes) + " bytes");
    }
    m.incident.resize(chunk.vertex_end);
    m.split.seen.cover(chunk.vertex_end);
    if (m.split.after_p.size() < chunk.vertex_end) m.split.after_p.resize(chunk.vertex_end, 0);
    decode_base(m, in, base);
    decode_splits(m, in, chunk.vertex_begin, chunk.vertex_end, born);
    decode_vertices(m, in, chunk.vertex_begin, chunk.vertex_end);
    if (in.at != bytes) in.fail(std::to_string(bytes - in.at) + " bytes after the last block");
    uint64_t live = 0;
    for (const auto& c : m.corners) live += c.size() / 3;
    if (live != chunk.triangles) in.fail("decodes to " + std::to_string(live) + " live triangles where the chunk table says " + std::to_string(chunk.triangles), 36);
}

namespace {

/// Decodes a block of `count` elements of `size` bytes with the vertex codec.
std::vector<uint8_t> vertex_block(const StreamCodecs& codecs, ChunkReader& in, size_t count, size_t size, const char* what) {
    const auto [p, n] = in.block(what);
    std::vector<uint8_t> out(count * size);
    if (!codecs.decode_vertices(codecs.context, out.data(), count, size, p, n)) in.fail(std::string(what) + " block does not decode (meshopt vertex codec)");
    return out;
}

/// An attribute's prediction (stream_layout::predict_neighbours, predict_byte_form) and its
/// residuals as decoded: element i at base + i * stride, in byte form with the lanes' sums taken
/// back.
struct Residuals {
    uint32_t prediction = 0, offset = 0;
    uint8_t* base = nullptr;
    uint32_t stride = 0;
    const uint8_t* at(uint32_t i) const { return base + size_t(i) * stride; }
};

template <class T>
T residual(const Residuals& r, const uint8_t* at) {
    if (r.prediction & predict_byte_form) return residual_from_bytes<T>(at);
    T z;
    std::memcpy(&z, at, sizeof(T));
    return unzigzag(z);
}

/// Adds residuals to the predicted grid values, `lanes` values of type T per vertex; `m` gives the
/// substitutes and, for a neighbours' prediction, the rings the chunk's splits listed. (`lanes` a
/// constant: the ring's sums and the residuals' lanes unrolled.)
template <int lanes, class T>
void predict(std::vector<T>& values, const MeshState& m, const Residuals& r, uint32_t a, uint32_t b) {
    values.resize(size_t(b) * lanes);  // (vertices below a are decoded: the stream's length was a * lanes)
    const bool rings = r.prediction & predict_neighbours;
    for (uint32_t v = a; v < b; ++v) {
        T* out = &values[size_t(v) * lanes];
        const size_t i = v - a, from = !rings || !i ? 0 : m.ring_ends[i - 1], to = rings ? m.ring_ends[i] : 0;
        prediction(values.data(), lanes, v, m.substitute[v], rings ? m.ring_items.data() + from : nullptr, to - from, out);
        const uint8_t* in = r.at(v - a);
        for (int k = 0; k < lanes; ++k) out[k] = T(out[k] + residual<T>(r, in + k * sizeof(T)));
    }
}

/// corner() below, of a mesh with several parts: the part's range first.
uint32_t* corner_in_parts(MeshState& m, uint32_t g) {
    const uint64_t t = g / 3;
    const size_t p = size_t(std::upper_bound(m.part_ends.begin(), m.part_ends.end(), t) - m.part_ends.begin());
    if (p >= m.parts.size()) return nullptr;
    const uint64_t slot = g - 3 * uint64_t(m.parts[p].first_triangle);
    return slot < m.corners[p].size() ? &m.corners[p][slot] : nullptr;
}

/// The live corner `g` (3 t + k in the file's TRIS) of a mesh; null when no live triangle has it.
inline uint32_t* corner(MeshState& m, uint32_t g) {
    if (m.parts.size() == 1) return g < m.corners[0].size() ? &m.corners[0][g] : nullptr;  // the usual mesh: no search
    return corner_in_parts(m, g);
}

void MeshUndo::restore(MeshState& m) const {
    m.substitute.resize(substitute), m.positions.resize(positions), m.normals.resize(normals), m.tangents.resize(tangents);
    m.texcoords[0].resize(texcoords[0]), m.texcoords[1].resize(texcoords[1]), m.colors.resize(colors);
    for (size_t p = 0; p < corners.size(); ++p) m.corners[p].resize(corners[p]);
    for (size_t c = 0; c < carried.size(); ++c) m.carried[c].data.resize(carried[c]);
    // latest first: a corner rewritten twice gets its oldest value; one of a new triangle is gone
    for (auto r = m.rewritten.rbegin(); r != m.rewritten.rend(); ++r)
        if (uint32_t* c = corner(m, r->first)) *c = r->second;
}

/// Corner `g` of a live triangle (one an incident list holds): corner() without the check.
inline uint32_t* live_corner(MeshState& m, uint32_t g) { return m.parts.size() == 1 ? &m.corners[0][g] : corner_in_parts(m, g); }

/// The three corners of the live triangle holding corner `g`.
const uint32_t* triangle_of(MeshState& m, uint32_t g) { return live_corner(m, g - g % 3); }

/// Appends a triangle to part p and lists its corners at their vertices.
void add_triangle(MeshState& m, size_t p, const uint32_t c[3]) {
    const uint32_t g = 3 * (m.parts[p].first_triangle + uint32_t(m.corners[p].size() / 3));
    for (int k = 0; k < 3; ++k) {
        m.corners[p].push_back(c[k]);
        m.incident.push(c[k], g + uint32_t(k));
    }
}

} // namespace

// The triangles live at the coarsest resolution, in the mesh's first chunk: meshoptimizer's
// index codec per part, and the rotations that undo its turns.
void StreamDecoder::Impl::decode_base(MeshState& m, ChunkReader& in, const std::vector<uint32_t>& base) {
    for (size_t p = 0; p < m.parts.size(); ++p) {
        if (!base[p]) continue;
        const auto [data, n] = in.block("TRIS");
        std::vector<uint32_t> c(3 * size_t(base[p]));
        if (!codecs.decode_indices(codecs.context, c.data(), c.size(), data, n)) in.fail("TRIS block does not decode (meshopt index codec)");
        rotate_back(in, c.data(), base[p]);
        for (size_t t = 0; t < base[p]; ++t) {
            for (int k = 0; k < 3; ++k)
                if (c[3 * t + k] >= m.min_vertex_count)
                    in.fail("part " + std::to_string(p) + " coarsest triangle " + std::to_string(t) + " holds vertex " + std::to_string(c[3 * t + k]) + ", not a survivor", 36);
            add_triangle(m, p, &c[3 * t]);
        }
    }
}

namespace {

/// Reads which of p's live corners (in TRIS order) v takes, a bit each, up to 32 at a time, and
/// moves them.
void move_corners(MeshState& m, BitReader& r, uint32_t p, uint32_t v) {
    uint32_t* around = m.incident.begin(p);
    const uint32_t corners = m.incident.size(p);
    // a mesh of one part appends every corner past the others (its lists stay ascending); one of
    // several adds a part's triangles before the next part's
    if (m.parts.size() > 1) sort_short(around, around + corners);
    uint32_t kept = 0;
    for (uint32_t i = 0; i < corners; i += 32) {
        const uint32_t n = std::min(corners - i, 32u), moves = r.bits(n);
        for (uint32_t j = 0; j < n; ++j) {
            const uint32_t g = around[i + j];
            if (moves >> j & 1u) {
                uint32_t* c = live_corner(m, g);
                m.rewritten.emplace_back(g, *c);
                *c = v;
                m.incident.push(v, g);
            } else {
                around[kept++] = g;
            }
        }
    }
    m.incident.truncate(p, kept);
}

/// Appends to `ring` the vertices sharing a live triangle with v, but v, each once.
void ring_of(MeshState& m, uint32_t v, std::vector<uint32_t>& ring) {
    append_neighbours(m.incident.begin(v), m.incident.end(v), [&](uint32_t g) { return triangle_of(m, g); }, v, v, m.split.seen, ring);
}

/// Lists the neighbourhood of the split of p into p and v (SplitScratch) from the corners each
/// holds before the births, and appends v's neighbours (without p) to `ring`.
void list_neighbourhood(MeshState& m, uint32_t p, uint32_t v, std::vector<uint32_t>& ring) {
    SplitScratch& s = m.split;
    std::vector<uint32_t>& by = s.seen.by;
    s.mark_p = s.seen.reserve(2), s.mark_v = s.mark_p + 1;
    s.near_p.clear(), s.common.clear(), s.v_only.clear(), s.rest_listed = false;
    s.next_split();
    for (const uint32_t* g = m.incident.begin(p); g != m.incident.end(p); ++g) {
        const uint32_t* c = triangle_of(m, *g);
        s.after_p[c[(*g + 1) % 3]] = s.split;  // c[*g % 3] is p
        for (int k = 0; k < 3; ++k)
            if (c[k] != p && c[k] != v && by[c[k]] != s.mark_p) by[c[k]] = s.mark_p, s.near_p.push_back(c[k]);
    }
    for (const uint32_t* g = m.incident.begin(v); g != m.incident.end(v); ++g) {
        const uint32_t* c = triangle_of(m, *g);
        for (int k = 0; k < 3; ++k) {
            const uint32_t u = c[k];
            if (u == p || u == v || by[u] == s.mark_v) continue;
            (by[u] == s.mark_p ? s.common : s.v_only).push_back(u);
            by[u] = s.mark_v;
            ring.push_back(u);
        }
    }
    sort_short(s.common.data(), s.common.data() + s.common.size());
}

/// Candidate `index` (below SplitScratch::candidate_count()) for a born triangle's third corner.
uint32_t candidate(SplitScratch& s, uint32_t index) {
    if (index < s.common.size()) return s.common[index];
    if (!s.rest_listed) {  // p's neighbours not near v, and v's not near p, ascending
        s.rest.clear();
        for (const uint32_t u : s.near_p)
            if (s.seen.by[u] == s.mark_p) s.rest.push_back(u);
        s.rest.insert(s.rest.end(), s.v_only.begin(), s.v_only.end());
        sort_short(s.rest.data(), s.rest.data() + s.rest.size());
        s.rest_listed = true;
    }
    return s.rest[index - s.common.size()];
}

/// Vertex v's substitute, below v.
uint32_t read_substitute(SubstituteCode& code, ChunkReader& in, BitReader& r, uint32_t v) {
    const uint64_t p = code.differences ? add_zigzag(code.previous, r.gamma() - 1) : r.bits(index_bits(v));
    if (p >= v)
        in.fail("vertex " + std::to_string(v) + " substitute " + (p == UINT64_MAX ? std::string("below 0") : std::to_string(p)) + " is not below it", 36);
    code.previous = uint32_t(p);
    return uint32_t(p);
}

}  // namespace

// The splits of vertices [a, b) (FORMAT.md): each vertex's substitute, which of its corners take
// the vertex, and the triangles born with it; and each vertex's ring for the attributes.
void StreamDecoder::Impl::decode_splits(MeshState& m, ChunkReader& in, uint32_t a, uint32_t b, const std::vector<uint32_t>& born) {
    const auto [data, n] = in.block("splits");
    BitReader r{data, n, 0, &in};
    std::vector<uint32_t> left = born;
    m.ring_items.clear(), m.ring_ends.clear();
    m.substitute_code = {minor >= 3 && r.bits(1) != 0, 0};
    for (uint32_t v = a; v < b; ++v) split_vertex(m, in, r, v, left);
    for (size_t q = 0; q < m.parts.size(); ++q)
        if (left[q]) in.fail("part " + std::to_string(q) + " bears " + std::to_string(born[q] - left[q]) + " triangles where the chunk says " + std::to_string(born[q]), 36);
    if ((r.at + 7) / 8 != n) in.fail("splits block has " + std::to_string(n - (r.at + 7) / 8) + " bytes after its last split");
}

// The split of vertex v: its substitute, the corners it takes, the triangles born with it; and
// v's ring just after (the vertices it shares a triangle with), for the attributes' prediction.
void StreamDecoder::Impl::split_vertex(MeshState& m, ChunkReader& in, BitReader& r, uint32_t v, std::vector<uint32_t>& left) {
    if (v < m.min_vertex_count) {  // a survivor: its own substitute, no ring
        m.substitute.push_back(v);
        m.ring_ends.push_back(m.ring_items.size());
        return;
    }
    const uint32_t p = read_substitute(m.substitute_code, in, r, v);
    m.substitute.push_back(p);
    move_corners(m, r, p, v);
    const uint64_t births = born_counts(m, in, r, v, left);
    if (!births) {  // v's triangles are the ones it took from p
        ring_of(m, v, m.ring_items);
    } else {  // the ring: v's neighbours before the births, p, the third corners born
        list_neighbourhood(m, p, v, m.ring_items);
        m.ring_items.push_back(p);
        m.split.born_from = m.ring_items.size();
        // since 1.2 a manifold split's two born triangles take the two candidates near both p and v,
        // one bit saying which the first takes (FORMAT.md: the pair bit)
        SplitScratch& s = m.split;
        const bool pair = minor >= 2 && births == 2 && s.common.size() == 2 && r.bits(1);
        const uint32_t first = pair ? r.bits(1) : 0;
        for (size_t q = 0, k = 0; q < m.parts.size(); ++q)
            for (uint32_t i = 0; i < m.births[q]; ++i, ++k) bear(m, in, r, p, v, q, pair ? s.common[k ^ first] : none);
    }
    m.ring_ends.push_back(m.ring_items.size());
}

// The triangles v bears per part (MeshState::births), within what the chunk has left; their sum.
uint64_t StreamDecoder::Impl::born_counts(MeshState& m, ChunkReader& in, BitReader& r, uint32_t v, std::vector<uint32_t>& left) {
    std::vector<uint32_t>& count = m.births;
    count.assign(m.parts.size(), 0);
    uint64_t births = 0;
    const bool usual = m.parts.size() == 1 && r.bits(1);  // one part: a 1 bit for the usual two
    for (size_t q = 0; q < m.parts.size(); ++q) {
        count[q] = usual ? 2 : r.gamma() - 1;
        if (count[q] > left[q]) in.fail("vertex " + std::to_string(v) + " bears more triangles in part " + std::to_string(q) + " than the chunk's count", 36);
        left[q] -= count[q];
        births += count[q];
    }
    return births;
}

// One triangle born with v in part q: its order and third corner, added to the part and, when
// new, the corner to v's ring (the ring's last entries since p).
void StreamDecoder::Impl::bear(MeshState& m, ChunkReader& in, BitReader& r, uint32_t p, uint32_t v, size_t q, uint32_t paired) {
    SplitScratch& s = m.split;
    uint32_t order = minor < 2 ? r.bits(order_bits) : 0;  // (since 1.2 after x, below)
    const uint32_t index = paired != none ? 0 : r.gamma() - 1, candidates = s.candidate_count();
    uint32_t x = 0;
    if (paired != none) {
        x = paired;
    } else if (index < candidates) {
        x = candidate(s, index);
    } else if (index == candidates) {
        x = r.bits(index_bits(v));
        if (x >= v || x == p) in.fail("vertex " + std::to_string(v) + " born triangle corner " + std::to_string(x) + " is not another vertex below it", 36);
    } else {
        in.fail("vertex " + std::to_string(v) + " born triangle names candidate " + std::to_string(index) + " of " + std::to_string(candidates), 36);
    }
    if (minor >= 2) {  // the turn, after two bits of 3 when the orientation is not the predicted one
        const uint32_t predicted = s.after_p[x] == s.split;  // predicted_orientation(p's corners, p, x)
        uint32_t turn = r.bits(turn_bits);
        order = 3 * predicted;
        if (turn == other_orientation) turn = r.bits(turn_bits), order = 3 * (1 - predicted);
        if (turn > 2) in.fail("vertex " + std::to_string(v) + " born triangle turn " + std::to_string(turn) + " is not 0 to 2", 36);
        order += turn;
    }
    if (order > 5) in.fail("vertex " + std::to_string(v) + " born triangle order " + std::to_string(order) + " is not 0 to 5", 36);
    const uint32_t role[3] = {v, p, x};
    const uint32_t c[3] = {role[born_orders[order][0]], role[born_orders[order][1]], role[born_orders[order][2]]};
    add_triangle(m, q, c);
    s.note_after_p(c, p);
    std::vector<uint32_t>& ring = m.ring_items;
    if (s.seen.by[x] != s.mark_v && std::find(ring.begin() + s.born_from, ring.end(), x) == ring.end()) ring.push_back(x);
}

void StreamDecoder::Impl::decode_vertices(MeshState& m, ChunkReader& in, uint32_t a, uint32_t b) {
    const size_t count = b - a;
    // each attribute's residuals: since 1.2 every prediction, then one block of all the
    // attributes' elements side by side; in 1.0 and 1.1 a prediction and a block each
    Residuals r[6];
    std::vector<uint8_t> blocks[6];
    uint32_t stride = 0;
    for (int i = 0; i < 6; ++i) {
        const AttributeSlot& s = attribute_slots[i];
        if (s.bit && !(m.attributes & s.bit)) continue;
        r[i].prediction = in.u32();
        if (r[i].prediction >= (minor >= 2 ? prediction_count : predict_byte_form))
            in.fail(std::string(s.name) + " prediction " + std::to_string(r[i].prediction) + " is not 0 to " + std::to_string(minor >= 2 ? 3 : 1) +
                    " (stream version 1." + std::to_string(minor) + ")");
        if (minor >= 2) {
            r[i].offset = stride, stride += s.element;
            continue;
        }
        blocks[i] = vertex_block(codecs, in, count, s.element, s.name);
        r[i].base = blocks[i].data(), r[i].stride = s.element;
    }
    if (minor >= 2) blocks[0] = vertex_block(codecs, in, count, stride, "attributes");
    // the byte form's differences, of whole elements at once when every attribute is in it
    bool whole = minor >= 2;
    for (int i = 0; i < 6; ++i)
        if ((!attribute_slots[i].bit || (m.attributes & attribute_slots[i].bit)) && !(r[i].prediction & predict_byte_form)) whole = false;
    if (whole) difference_lanes(blocks[0].data(), count, stride, stride);
    for (int i = 0; i < 6; ++i) {
        if (minor >= 2) r[i].base = blocks[0].data() + r[i].offset, r[i].stride = stride;
        if ((r[i].prediction & predict_byte_form) && !whole) difference_lanes(r[i].base, count, r[i].stride, attribute_slots[i].element);
    }
    decode_attributes(m, in, r, a, b);
    for (Carried& c : m.carried) {
        const uint32_t size = padded_element(c.element_bytes);
        const std::vector<uint8_t> raw = vertex_block(codecs, in, count, size, "XATT");
        for (size_t v = 0; v < count; ++v) c.data.insert(c.data.end(), raw.begin() + v * size, raw.begin() + v * size + c.element_bytes);
    }
}

// The grid values of the chunk's vertices [a, b): each attribute's residuals added to its
// prediction, in the order of stream_layout::attribute_slots.
void StreamDecoder::Impl::decode_attributes(MeshState& m, ChunkReader& in, const Residuals* r, uint32_t a, uint32_t b) {
    using namespace layout;
    const StreamQuantization& q = m.quantization;
    predict<3>(m.positions, m, r[0], a, b);
    for (size_t i = size_t(a) * 3; i < m.positions.size(); ++i)
        if (m.positions[i] >> q.position_bits) in.fail("vertex " + std::to_string(i / 3) + " position is off its " + std::to_string(q.position_bits) + "-bit grid", 36);
    if (m.attributes & attr_normals) predict<2>(m.normals, m, r[1], a, b);
    for (int t = 0; t < 2; ++t) {
        if (!(m.attributes & (t ? attr_texcoords1 : attr_texcoords))) continue;
        predict<2>(m.texcoords[t], m, r[t ? 4 : 2], a, b);
        for (size_t i = size_t(a) * 2; i < m.texcoords[t].size(); ++i)
            if (m.texcoords[t][i] >> q.texcoord_bits) in.fail("vertex " + std::to_string(i / 2) + " texture coordinate is off its grid", 36);
    }
    if (m.attributes & attr_colors) predict<4>(m.colors, m, r[3], a, b);
    if (m.attributes & attr_tangents) predict<3>(m.tangents, m, r[5], a, b);
}

// The rotation block after an index block: the index codec may turn a triangle's corners, and
// the file's order is restored (an empty block: nothing turned).
void StreamDecoder::Impl::rotate_back(ChunkReader& in, uint32_t* corners, uint32_t triangles) {
    const auto [data, n] = in.block("rotations");
    if (n == 0) return;
    const size_t elements = (size_t(triangles) + 3) / 4;
    std::vector<uint8_t> turns(elements * rotation_element);
    if (!codecs.decode_vertices(codecs.context, turns.data(), elements, rotation_element, data, n))
        in.fail("rotations block does not decode (meshopt vertex codec)");
    for (size_t t = 0; t < triangles; ++t) {
        const uint8_t r = turns[t];
        if (r > 2) in.fail("triangle " + std::to_string(t) + " of the block turns by " + std::to_string(r) + ", not 0 to 2", 36);
        uint32_t* c = corners + 3 * t;
        const uint32_t d[3] = {c[0], c[1], c[2]};
        for (int k = 0; k < 3; ++k) c[k] = d[(r + k) % 3];
    }
}

// The .tom of what is decoded: the file-level sections as stored, then every mesh.
// (The file-level sections, images among them, are viewed where they lie, with the checksums
// computed when they arrived: a viewer assembles an image after every chunk.)
std::vector<uint8_t> StreamDecoder::Impl::assemble() const {
    std::vector<layout::SectionView> views;
    for (size_t i = 0; i < file_sections.size(); ++i) {
        const layout::PendingSection& s = file_sections[i];
        views.push_back({s.type, s.mesh, s.bytes.data(), s.bytes.size(), true, file_checksums[i]});
    }
    std::vector<std::vector<uint8_t>> storage;  // (moving a vector keeps its bytes where they are)
    for (uint32_t i = 0; i < meshes.size(); ++i) mesh_sections(meshes[i], i, storage, views);
    return layout::assemble_file(views, uint32_t(meshes.size()));
}

namespace {

/// META with its usable floor lowered to the decoded resolution (a floor above it would make
/// every decoded level "below the floor", and readers ignore a floor past the vertex count).
std::vector<uint8_t> clamped_metadata(std::vector<uint8_t> meta, uint32_t resolution) {
    if (meta.size() < 4) return meta;
    uint64_t at = 4;
    for (uint32_t e = 0, count = layout::load_u32(meta.data()); e < count && meta.size() - at >= 8; ++e) {
        const uint32_t key = layout::load_u32(&meta[at]), value = layout::load_u32(&meta[at + 4]);
        const uint64_t key_at = at + 8, value_at = key_at + (uint64_t(key) + 3) / 4 * 4;
        if (value_at > meta.size() || meta.size() - value_at < value) break;
        if (std::string_view(reinterpret_cast<const char*>(&meta[key_at]), key) == "usable_floor" && value >= 8 &&
            layout::load_u32(&meta[value_at + 4]) > resolution)
            layout::store_u32(&meta[value_at + 4], resolution);
        at = value_at + (uint64_t(value) + 3) / 4 * 4;
    }
    return meta;
}

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
constexpr bool little_endian_host = true;
#else
constexpr bool little_endian_host = false;
#endif

}  // namespace

// The mesh's sections at its decoded resolution, appended to `views`: the growing ones (streams,
// substitutes) as the chunks left them, a one-part mesh's corners viewed where the state holds
// them when they are stored as they lie (32-bit indices on a little-endian host), the others made
// in `storage`.
void StreamDecoder::Impl::mesh_sections(const MeshState& m, uint32_t index, std::vector<std::vector<uint8_t>>& storage,
                                        std::vector<layout::SectionView>& views) const {
    using namespace layout;
    const uint32_t n = m.resolution;
    const StreamQuantization& q = m.quantization;
    auto keep = [&](uint32_t type, std::vector<uint8_t>&& bytes) {
        storage.push_back(std::move(bytes));
        views.push_back({type, index, storage.back().data(), storage.back().size()});
    };
    auto indices = [&](uint32_t type, const std::vector<uint32_t>& values) {
        if (little_endian_host && m.index_size == 4)
            views.push_back({type, index, reinterpret_cast<const uint8_t*>(values.data()), 4 * values.size()});
        else
            keep(type, index_bytes(values, m.index_size));
    };
    auto grown = [&](uint32_t type, const GrowingSection& g) { views.push_back({type, index, g.bytes.data(), g.bytes.size(), true, g.checksum}); };
    // the bounds: the grid's extremes dequantized (dequantizing keeps the order)
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    if (n > 0)
        for (int k = 0; k < 3; ++k)
            lo[k] = dequantize(m.grid_min[k], q.position_min[k], q.position_step), hi[k] = dequantize(m.grid_max[k], q.position_min[k], q.position_step);
    uint32_t live = 0;
    for (const std::vector<uint32_t>& c : m.corners) live += uint32_t(c.size() / 3);
    std::vector<uint8_t> head = m.header;
    store_u32(&head[m_vertex_count], n);
    store_u32(&head[m_triangle_count], live);
    store_u32(&head[m_min_vertex_count], n ? m.min_vertex_count : 0);
    for (int k = 0; k < 3; ++k) store_f32(&head[m_bounds_min + 4 * k], lo[k]), store_f32(&head[m_bounds_max + 4 * k], hi[k]);
    keep(sec_mesh, std::move(head));
    grown(sec_positions, m.positions_out);
    // the other streams, in the order of layout::attribute_streams
    if (m.attributes & attr_normals) grown(sec_normals, m.normals_out);
    if (m.attributes & attr_texcoords) grown(sec_texcoords, m.texcoords_out[0]);
    if (m.attributes & attr_colors) grown(sec_colors, m.colors_out);
    if (m.attributes & attr_texcoords1) grown(sec_texcoords1, m.texcoords_out[1]);
    if (m.attributes & attr_tangents) grown(sec_tangents, m.tangents_out);
    grown(sec_substitute, m.substitutes_out);
    if (m.corners.size() == 1) {
        indices(sec_triangles, m.corners[0]);
    } else {  // the parts' live triangles, one after another
        std::vector<uint32_t> tris;
        for (const std::vector<uint32_t>& c : m.corners) tris.insert(tris.end(), c.begin(), c.end());
        keep(sec_triangles, index_bytes(tris, m.index_size));
    }
    if (!m.metadata.empty()) keep(sec_metadata, clamped_metadata(m.metadata, n));
    if (!m.pair_bits.empty() && n > 0) {
        std::vector<uint8_t> bits(m.pair_bits.begin(), m.pair_bits.begin() + (n + 7) / 8);
        for (uint32_t i = n - 1; i < (n + 7) / 8 * 8; ++i) bits[i / 8] &= uint8_t(~(1u << (i % 8)));  // no group past the last vertex
        keep(sec_pairs, std::move(bits));
    }
    if (m.parts.size() > 1) {
        std::vector<uint8_t> parts(parts_header_bytes + part_record_bytes * m.parts.size(), 0);
        store_u32(parts.data(), uint32_t(m.parts.size()));
        uint32_t first = 0;
        for (size_t p = 0; p < m.parts.size(); ++p) {
            uint8_t* r = &parts[parts_header_bytes + part_record_bytes * p];
            const uint32_t count = uint32_t(m.corners[p].size() / 3);
            store_u32(r, first), store_u32(r + 4, count), store_u32(r + 8, uint32_t(m.parts[p].material)), store_u32(r + 12, m.parts[p].attributes);
            first += count;
        }
        keep(sec_parts, std::move(parts));
    }
    if (!m.carried.empty()) {
        std::vector<VertexStreamView> carried;
        for (const Carried& c : m.carried) {
            VertexStreamView v = c.record;
            v.data = c.data.data();
            carried.push_back(v);
        }
        keep(sec_extra_streams, detail::encode_extra_streams(carried, n));
    }
}

} // namespace tom
