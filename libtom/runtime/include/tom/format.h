#pragma once
// Reading .tom files: a validated, mapped file and its meshes. The format is specified in
// docs/FORMAT.md; writing is the builder's (tom/builder/writer.h).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tom/scene.h"
#include "tom/view.h"

namespace tom {

constexpr uint32_t format_version_major = 1;
constexpr uint32_t format_version_minor = 8;

struct OpenOptions {
    bool verify_checksums = true;  ///< CRC-32 of every section; costs one pass over the file
};

/// One entry of the section table, for inspection (tominfo).
struct SectionInfo {
    static constexpr uint32_t file_level = 0xFFFFFFFFu;  ///< `mesh` of a section of the whole file (MATL, INST)
    char type[5] = {0, 0, 0, 0, 0};
    uint32_t mesh = 0;
    uint64_t offset = 0;
    uint64_t bytes = 0;
    uint32_t checksum = 0;
};

/// A validated .tom file, mapped read-only (or held in memory), used in place.
/// Move-only. Every view it hands out stays valid while the File lives.
class File {
public:
    /// Maps and validates `path` (every rule of FORMAT.md).
    /// \throw FormatError naming the path, byte offset, field and rule; IoError when unreadable.
    static File open(const std::string& path, const OpenOptions& options = {});
    /// Validates a copy of `bytes`; `name` stands for the path in messages. \throw FormatError.
    static File from_bytes(const void* bytes, size_t size, const std::string& name = "<memory>", const OpenOptions& options = {});
    /// Validates `bytes` and uses them in place, without a copy: the caller keeps them alive
    /// and unchanged while the File lives. \throw FormatError.
    static File borrow(const void* bytes, size_t size, const std::string& name = "<memory>", const OpenOptions& options = {});
    /// Validates `bytes` and keeps them, moved in without a copy (an image built in memory, as
    /// StreamDecoder::file() builds one). \throw FormatError.
    static File adopt(std::vector<uint8_t>&& bytes, const std::string& name = "<memory>", const OpenOptions& options = {});

    File(File&&) noexcept;
    File& operator=(File&&) noexcept;
    ~File();

    const std::string& path() const noexcept;
    uint32_t version_major() const noexcept;
    uint32_t version_minor() const noexcept;
    uint64_t file_bytes() const noexcept;
    uint32_t mesh_count() const noexcept;
    const MeshView& mesh(uint32_t index) const noexcept;  ///< \pre index < mesh_count() (asserted)
    /// Materials, instances and stored images (empty when the file has none; see tom::draw_list).
    /// The images' bytes are views into the file, valid while it lives.
    const Scene& scene() const noexcept;
    /// What made the file (section PROV, since 1.5): text the writer chose, for tombuild a JSON
    /// object with the input's digest, the files it read and the options (docs/FORMAT.md); empty
    /// when the file has none. Readers do not interpret it.
    std::string_view provenance() const noexcept;
    const std::vector<SectionInfo>& sections() const noexcept;

private:
    struct Impl;
    friend void validate_bytes(const void*, size_t, const std::string&, const OpenOptions&);
    explicit File(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

/// Checks `bytes` against every rule of FORMAT.md in place, keeping nothing: what File::open
/// would accept. `name` stands for the path in messages. \throw FormatError.
void validate_bytes(const void* bytes, size_t size, const std::string& name, const OpenOptions& options = {});

/// CRC-32 (IEEE 802.3, reflected, as zlib's crc32) of a byte range.
uint32_t crc32(const void* data, size_t bytes, uint32_t crc = 0) noexcept;

} // namespace tom
