#pragma once
// What the fuzz targets share: the bytes of one input as a file with a given extension, for the
// readers that take a path. Each process writes into a folder of its own under /tmp.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

namespace fuzz {

// This process's folder for its inputs.
inline const std::string& folder() {
    static const std::string made_folder = [] {
        char pattern[] = "/tmp/tom-fuzz-XXXXXX";
        const char* made = ::mkdtemp(pattern);
        return std::string(made ? made : "/tmp");
    }();
    return made_folder;
}

// Writes `size` bytes to PROCESS_FOLDER/input.EXTENSION and returns the path.
inline std::string as_file(const uint8_t* data, size_t size, const std::string& extension) {
    const std::string path = folder() + "/input." + extension;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return path;
    if (size > 0) std::fwrite(data, 1, size, f);
    std::fclose(f);
    return path;
}

} // namespace fuzz
