// The platform layer (internal/platform.h): POSIX, Windows, and a portable fallback.

#include "platform.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

#include "tom/errors.h"

#if defined(_WIN32)
#define TOM_PLATFORM_WINDOWS 1
#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#endif
#include <windows.h>
#elif defined(__unix__) || defined(__APPLE__)
#define TOM_PLATFORM_POSIX 1
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#endif

namespace tom::detail {

MappedFile::MappedFile(MappedFile&& other) noexcept { *this = std::move(other); }

MappedFile& MappedFile::operator=(MappedFile&& other) noexcept {
    if (this != &other) {
        release();
        data_ = other.data_;
        size_ = other.size_;
        mapping_ = other.mapping_;
        other.data_ = reinterpret_cast<const uint8_t*>("");
        other.size_ = 0;
        other.mapping_ = nullptr;
    }
    return *this;
}

MappedFile::~MappedFile() { release(); }

#if defined(TOM_PLATFORM_POSIX)

MappedFile MappedFile::open(const std::string& path) {
    MappedFile f;
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw IoError("cannot open '" + path + "': " + std::strerror(errno));
    struct stat st;
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        throw IoError("cannot read '" + path + "': not a regular file");
    }
    if (st.st_size > 0) {
        void* p = ::mmap(nullptr, size_t(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
        if (p == MAP_FAILED) {
            const int e = errno;
            ::close(fd);
            throw IoError("cannot map '" + path + "': " + std::strerror(e));
        }
        f.mapping_ = p;
        f.data_ = static_cast<const uint8_t*>(p);
        f.size_ = size_t(st.st_size);
    }
    ::close(fd);
    return f;
}

void MappedFile::release() noexcept {
    if (mapping_) ::munmap(mapping_, size_);
    mapping_ = nullptr;
}

#elif defined(TOM_PLATFORM_WINDOWS)

namespace {
std::string windows_error(DWORD code) {
    char buffer[256] = {};
    const DWORD n = FormatMessageA(FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS, nullptr, code, 0, buffer, sizeof buffer, nullptr);
    std::string s(buffer, n);
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ' || s.back() == '.')) s.pop_back();
    return s.empty() ? "error " + std::to_string(code) : s;
}
} // namespace

MappedFile MappedFile::open(const std::string& path) {
    MappedFile f;
    HANDLE file = CreateFileA(path.c_str(), GENERIC_READ, FILE_SHARE_READ, nullptr, OPEN_EXISTING, FILE_ATTRIBUTE_NORMAL, nullptr);
    if (file == INVALID_HANDLE_VALUE) throw IoError("cannot open '" + path + "': " + windows_error(GetLastError()));
    LARGE_INTEGER size;
    if (!GetFileSizeEx(file, &size) || GetFileType(file) != FILE_TYPE_DISK) {
        CloseHandle(file);
        throw IoError("cannot read '" + path + "': not a regular file");
    }
    if (size.QuadPart > 0) {
        HANDLE mapping = CreateFileMappingA(file, nullptr, PAGE_READONLY, 0, 0, nullptr);
        const DWORD e = GetLastError();
        CloseHandle(file);
        if (!mapping) throw IoError("cannot map '" + path + "': " + windows_error(e));
        const void* p = MapViewOfFile(mapping, FILE_MAP_READ, 0, 0, 0);
        const DWORD e2 = GetLastError();
        CloseHandle(mapping);  // the view keeps the mapping alive
        if (!p) throw IoError("cannot map '" + path + "': " + windows_error(e2));
        f.mapping_ = const_cast<void*>(p);
        f.data_ = static_cast<const uint8_t*>(p);
        f.size_ = size_t(size.QuadPart);
    } else {
        CloseHandle(file);
    }
    return f;
}

void MappedFile::release() noexcept {
    if (mapping_) UnmapViewOfFile(mapping_);
    mapping_ = nullptr;
}

#else  // the portable fallback: the whole file in memory

MappedFile MappedFile::open(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError("cannot open '" + path + "'");
    auto* buffer = new std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) {
        delete buffer;
        throw IoError("cannot read '" + path + "'");
    }
    MappedFile f;
    f.mapping_ = buffer;
    f.size_ = buffer->size();
    if (!buffer->empty()) f.data_ = buffer->data();
    return f;
}

void MappedFile::release() noexcept {
    delete static_cast<std::vector<uint8_t>*>(mapping_);
    mapping_ = nullptr;
}

#endif

bool cpu_has_avx2() noexcept {
#if TOM_X86_SIMD
    return __builtin_cpu_supports("avx2");
#else
    return false;
#endif
}

unsigned long process_id() noexcept {
#if defined(TOM_PLATFORM_WINDOWS)
    return GetCurrentProcessId();
#elif defined(TOM_PLATFORM_POSIX)
    return static_cast<unsigned long>(::getpid());
#else
    return 0;
#endif
}

std::string replace_file(const std::string& from, const std::string& to) {
#if defined(TOM_PLATFORM_WINDOWS)
    // rename() fails on Windows when the target exists
    if (MoveFileExA(from.c_str(), to.c_str(), MOVEFILE_REPLACE_EXISTING | MOVEFILE_WRITE_THROUGH)) return {};
    return windows_error(GetLastError());
#else
    if (std::rename(from.c_str(), to.c_str()) == 0) return {};
    return std::strerror(errno);
#endif
}

} // namespace tom::detail
