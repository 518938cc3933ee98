#pragma once
// The platform layer: what differs between POSIX and Windows and between compilers, behind one
// interface with a portable fallback (runtime/src/platform.cpp). Everything else in the runtime,
// the builder and libtcr is standard C++17.

#include <cstddef>
#include <cstdint>
#include <string>

// GCC-style target attributes and x86 intrinsics: the AVX2 paths are compiled where both exist
// and chosen at run time by cpu_has_avx2(); elsewhere only the scalar paths are built.
#if (defined(__GNUC__) || defined(__clang__)) && (defined(__x86_64__) || defined(__i386__))
#define TOM_X86_SIMD 1
#define TOM_TARGET_AVX2 __attribute__((target("avx2")))
#else
#define TOM_X86_SIMD 0
#define TOM_TARGET_AVX2
#endif

namespace tom::detail {

/// A whole file, read-only: mapped (POSIX mmap, Windows file mapping) or, where neither is
/// available, read into memory. Move-only.
class MappedFile {
  public:
    /// \throw IoError naming the path when it cannot be opened, is not a regular file or cannot
    ///        be mapped.
    static MappedFile open(const std::string& path);
    MappedFile() = default;
    MappedFile(MappedFile&& other) noexcept;
    MappedFile& operator=(MappedFile&& other) noexcept;
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    ~MappedFile();

    const uint8_t* data() const noexcept { return data_; }  ///< never null, even for an empty file
    size_t size() const noexcept { return size_; }

  private:
    void release() noexcept;
    const uint8_t* data_ = reinterpret_cast<const uint8_t*>("");
    size_t size_ = 0;
    void* mapping_ = nullptr;  // the platform's handle or the fallback's buffer
};

/// Whether this CPU runs AVX2 (false where it cannot be asked or TOM_X86_SIMD is 0).
bool cpu_has_avx2() noexcept;

/// This process's id, for names of temporary files.
unsigned long process_id() noexcept;

/// Renames `from` to `to`, replacing `to` if it exists, in one step where the platform allows.
/// \return an empty string, or the system's reason for the failure.
std::string replace_file(const std::string& from, const std::string& to);

/// Hints that `p` will be read (prefetch) or written (prefetch_write) soon; no-ops elsewhere.
inline void prefetch(const void* p) noexcept {
#if defined(__GNUC__) || defined(__clang__)
    __builtin_prefetch(p);
#else
    (void)p;
#endif
}
inline void prefetch_write(const void* p) noexcept {
#if defined(__GNUC__) || defined(__clang__)
    __builtin_prefetch(p, 1);
#else
    (void)p;
#endif
}

/// A spin-wait hint to the CPU.
inline void cpu_relax() noexcept {
#if TOM_X86_SIMD
    __builtin_ia32_pause();
#endif
}

inline int popcount32(uint32_t x) noexcept {
#if defined(__GNUC__) || defined(__clang__)
    return __builtin_popcount(x);
#else
    int n = 0;
    for (; x; x &= x - 1) ++n;
    return n;
#endif
}

/// \pre x != 0
inline int trailing_zeros32(uint32_t x) noexcept {
#if defined(__GNUC__) || defined(__clang__)
    return __builtin_ctz(x);
#else
    int n = 0;
    for (; !(x & 1u); x >>= 1) ++n;
    return n;
#endif
}

} // namespace tom::detail
