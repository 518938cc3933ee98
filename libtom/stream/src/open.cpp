// Opening streamed and ordinary .tom files alike, with libmeshoptimizer's decoders.

#include <meshoptimizer.h>

#include <cstdio>
#include <memory>
#include <optional>

#include "tom/errors.h"
#include "tom/stream/stream_file.h"

namespace tom {

namespace {

bool decode_vertices(void*, void* out, size_t count, size_t size, const uint8_t* in, size_t in_bytes) {
    return meshopt_decodeVertexBuffer(out, count, size, in, in_bytes) == 0;
}
bool decode_indices(void*, uint32_t* out, size_t index_count, const uint8_t* in, size_t in_bytes) {
    return meshopt_decodeIndexBuffer(out, index_count, sizeof(uint32_t), in, in_bytes) == 0;
}

struct CloseFile {
    void operator()(std::FILE* f) const { std::fclose(f); }
};

/// Whether the file at `path` starts with a stream's magic; empty when it cannot be opened.
std::optional<bool> stream_magic(const std::string& path) {
    const std::unique_ptr<std::FILE, CloseFile> f(std::fopen(path.c_str(), "rb"));
    if (!f) return std::nullopt;
    uint8_t head[8] = {0};
    return is_stream(head, std::fread(head, 1, sizeof head, f.get()));
}

} // namespace

StreamCodecs meshopt_codecs() {
    StreamCodecs c;
    c.decode_vertices = decode_vertices;
    c.decode_indices = decode_indices;
    return c;
}

StreamDecoder read_stream(const std::string& path, uint64_t byte_limit) {
    const std::unique_ptr<std::FILE, CloseFile> f(std::fopen(path.c_str(), "rb"));
    if (!f) throw IoError("cannot open " + path);
    StreamDecoder decoder(meshopt_codecs(), path);
    std::vector<uint8_t> buffer(1 << 20);
    uint64_t left = byte_limit;
    while (left > 0) {
        const size_t n = std::fread(buffer.data(), 1, size_t(std::min<uint64_t>(buffer.size(), left)), f.get());
        if (n == 0) break;
        decoder.append(buffer.data(), n);  // decodes each chunk as it completes: memory holds one chunk
        left -= n;
    }
    if (std::ferror(f.get())) throw IoError("cannot read " + path);
    if (decoder.file_bytes() == 0)
        throw FormatError(path, decoder.bytes_received(), "header", 31, "the " + std::to_string(decoder.bytes_received()) + " bytes read do not hold the 64-byte header");
    const bool limited = byte_limit < decoder.file_bytes();
    if (!limited && !decoder.complete())
        throw FormatError(path, decoder.bytes_received(), "file_bytes", 31,
                          "file is truncated: " + std::to_string(decoder.bytes_received()) + " bytes of " + std::to_string(decoder.file_bytes()));
    return decoder;
}

bool is_stream_file(const std::string& path) { return stream_magic(path).value_or(false); }

File open_any(const std::string& path, uint64_t byte_limit, const OpenOptions& options) {
    const std::optional<bool> stream = stream_magic(path);
    if (!stream) throw IoError("cannot open " + path);
    if (!*stream) {
        if (byte_limit != std::numeric_limits<uint64_t>::max())
            throw ArgumentError(path + " is not a streamed .tom file: a byte limit applies only to streams (tombuild --stream)");
        return File::open(path, options);
    }
    return read_stream(path, byte_limit).file();
}

} // namespace tom
