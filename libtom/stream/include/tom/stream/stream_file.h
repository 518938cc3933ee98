#pragma once
// Streamed .tom files (docs/FORMAT.md, "Streamed files"): writing them from an ordinary .tom, and
// opening either kind. Any prefix of a streamed file that ends on a chunk boundary is a coarser
// mesh: tom::StreamDecoder (tom/stream.h) decodes it as the bytes arrive.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "tom/format.h"
#include "tom/stream.h"

namespace tom {

struct StreamOptions {
    /// Bits of the grid positions go to, over the mesh's box (the same step on every axis): each
    /// to the grid point of the cell around it nearest the planes of its triangles (at full
    /// detail and at the coarsest level it is in), at most a step away per axis (coincident
    /// copies to one point). gltfpack's default is 14.
    uint32_t position_bits = 14;
    uint32_t normal_bits = 8;     ///< per octahedral component of normals and tangents (gltfpack: 8)
    uint32_t texcoord_bits = 12;  ///< per texture coordinate, over its range (gltfpack: 12)
    /// The first chunk of a mesh holds this share of its vertices and of its triangles at least
    /// (and its survivors); each next one grows the resolution by `growth` (a group of copies is
    /// never split).
    double first_share = 0.01;
    double growth = 1.25;
    /// Keep the source's vertex order. By default each chunk's vertices are renumbered, its
    /// splits ordered by their substitutes (stream_order): the substitutes then code as small
    /// differences, a smaller file, and the levels at chunk boundaries are the same meshes, but
    /// the resolutions inside a chunk take its splits in that order, not the builder's.
    bool keep_order = false;
};

/// The streamed form of the .tom file image `bytes` (validated first; `name` stands for it in
/// messages). Deterministic: equal inputs and options give equal bytes.
/// \throw FormatError for an invalid image, ArgumentError for options out of range.
std::vector<uint8_t> encode_stream(const void* bytes, size_t size, const StreamOptions& options = {}, const std::string& name = "<memory>");

/// The ordinary .tom image that the stream encode_stream(bytes, size, options) writes decodes to
/// (its quantization aside): `bytes` itself with `options.keep_order`, else its meshes' vertices
/// renumbered within each chunk (see StreamOptions::keep_order), `COAR` left out.
/// \throw as encode_stream.
std::vector<uint8_t> stream_order(const void* bytes, size_t size, const StreamOptions& options = {}, const std::string& name = "<memory>");
/// libmeshoptimizer's vertex and index decoders, for tom::StreamDecoder.
StreamCodecs meshopt_codecs();

/// The first `byte_limit` bytes of the streamed file at `path` fed to a decoder (all of them by
/// default). \throw IoError when unreadable, FormatError when the bytes are not a valid stream
/// (all of a file must be all of its stream: a truncated file is an error unless a limit is set).
StreamDecoder read_stream(const std::string& path, uint64_t byte_limit = std::numeric_limits<uint64_t>::max());

/// True when the file at `path` starts with a streamed file's magic (false when unreadable).
bool is_stream_file(const std::string& path);

/// Opens `path` whether it holds an ordinary or a streamed .tom; a streamed one is decoded (its
/// first `byte_limit` bytes: the mesh a viewer shows after that many bytes). \throw as File::open
/// and read_stream; ArgumentError for a byte limit on an ordinary file.
File open_any(const std::string& path, uint64_t byte_limit = std::numeric_limits<uint64_t>::max(), const OpenOptions& options = {});

} // namespace tom
