#pragma once
// Decoding streamed .tom files (docs/FORMAT.md, "Streamed files"): a directory, then chunks in
// resolution order, each decodable given the earlier ones. Any prefix of the file that ends on a
// chunk boundary decodes to a .tom whose meshes are the levels at the vertex counts received:
// index for index the triangles extraction gives from the whole file at those counts, positions
// within the stated quantization.
//
// The chunks' blocks are compressed with meshoptimizer's vertex and index codecs. The runtime
// has no dependency, so the decoder takes the two decoding functions from its caller: tom::stream
// gives libmeshoptimizer's (tom::meshopt_codecs), a browser build can give the npm decoder's.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tom/format.h"

namespace tom {

/// The two decoders of meshoptimizer's formats. Each returns false for malformed input, never
/// reads outside [in, in + in_bytes) nor writes past its output; each gets `context` unchanged
/// (what a C or script binding needs to reach its own decoders).
struct StreamCodecs {
    /// meshopt_decodeVertexBuffer: `count` elements of `size` bytes (a multiple of 4) into `out`.
    bool (*decode_vertices)(void* context, void* out, size_t count, size_t size, const uint8_t* in, size_t in_bytes) = nullptr;
    /// meshopt_decodeIndexBuffer: `index_count` (a multiple of 3) 32-bit indices into `out`.
    bool (*decode_indices)(void* context, uint32_t* out, size_t index_count, const uint8_t* in, size_t in_bytes) = nullptr;
    void* context = nullptr;
};

/// One chunk of the directory, in file order.
struct StreamChunk {
    uint32_t mesh = 0;
    uint32_t vertex_begin = 0, vertex_end = 0;  ///< the vertices it adds: the mesh's resolution goes to vertex_end
    uint32_t triangles = 0;                     ///< the mesh's live triangles (all parts) at vertex_end
    uint64_t begin_byte = 0, end_byte = 0;      ///< its bytes in the file: a prefix of end_byte bytes decodes it
};

/// The deferred block (since stream 1.1): the file's sections no frame needs to draw (its
/// provenance, embedded images and source glTF scene), stored whole among the chunks, right after
/// every mesh's first one. `after_chunk` chunks precede it; begin_byte == end_byte when the file
/// has none.
struct StreamDeferred {
    size_t after_chunk = 0;
    uint64_t begin_byte = 0, end_byte = 0;
    std::vector<std::string> sections;  ///< their types in file order: "PROV", "IMAG", "GLTF"
};

/// How a mesh of a streamed file was quantized (the grid the decoded values lie on).
struct StreamQuantization {
    uint32_t position_bits = 0, normal_bits = 0, texcoord_bits = 0;
    float position_min[3] = {0, 0, 0};
    float position_step = 0;                     ///< grid step, the same on every axis: error < one step per axis
    float texcoord_min[2][2] = {{0, 0}, {0, 0}}; ///< TEXCOORD_0 and TEXCOORD_1
    float texcoord_step[2][2] = {{0, 0}, {0, 0}};
};

/// True when `bytes` start with a streamed file's magic (`\x89TOS\r\n\x1a\n`).
bool is_stream(const void* bytes, size_t size) noexcept;

/// Decodes a streamed file as its bytes arrive: feed them in order with append(); each chunk is
/// decoded as soon as its last byte is in. Memory grows with what is decoded, never with what the
/// directory merely declares.
class StreamDecoder {
public:
    /// `name` stands for the file in messages; `options.verify_checksums` false skips the CRC-32
    /// of the header, directory and chunks (the other checks stay). \pre both codecs set
    /// (\throw ArgumentError).
    explicit StreamDecoder(const StreamCodecs& codecs, std::string name = "<stream>", const OpenOptions& options = {});
    StreamDecoder(StreamDecoder&&) noexcept;
    StreamDecoder& operator=(StreamDecoder&&) noexcept;
    ~StreamDecoder();

    /// Takes the next `size` bytes of the file and decodes every chunk they complete.
    /// \throw FormatError naming the file, the byte offset, the field and the problem; the decoder
    /// then refuses further bytes and keeps what it decoded before.
    void append(const void* bytes, size_t size);

    bool has_directory() const noexcept;
    uint64_t bytes_received() const noexcept;
    uint64_t file_bytes() const noexcept;               ///< declared by the header (0 before it)
    uint32_t mesh_count() const noexcept;
    const std::vector<StreamChunk>& chunks() const noexcept;  ///< the directory's (empty before it)
    size_t decoded_chunks() const noexcept;             ///< chunks()[0, decoded_chunks()) are decoded
    bool complete() const noexcept;                     ///< every chunk decoded, the deferred block read
    const StreamDeferred& deferred() const noexcept;    ///< where the deferred block is (from the directory on)
    bool deferred_received() const noexcept;            ///< the deferred block is read (its sections are in tom_bytes())
    /// The byte count at which the next decoding step can run: the header's end before it is in,
    /// the directory's end before that, then the next chunk's or the deferred block's end;
    /// file_bytes() when complete.
    /// A client fetching by ranges asks for the bytes up to it.
    uint64_t next_boundary() const noexcept;
    uint32_t vertex_count(uint32_t mesh) const noexcept;      ///< decoded resolution of a mesh (0 before its first chunk)
    const StreamQuantization& quantization(uint32_t mesh) const noexcept;  ///< \pre mesh < mesh_count()
    /// The full-detail mesh's bounds as the directory declares them (a viewer frames the whole
    /// mesh from the first chunk on). \pre mesh < mesh_count()
    void declared_bounds(uint32_t mesh, float min[3], float max[3]) const noexcept;

    /// The .tom image of what is decoded (FORMAT.md): every mesh at its decoded resolution with
    /// its levels below, and the file's scene, materials and metadata, with its images,
    /// provenance and source glTF once the deferred block is in; a mesh before its first chunk
    /// is empty. \throw FormatError before the directory is in.
    std::vector<uint8_t> tom_bytes() const;
    /// tom_bytes() validated and held as a File.
    File file() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace tom
