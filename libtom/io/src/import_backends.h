#pragma once
// The readers behind import_file(); private to tom::io.

#include <cstdint>
#include <string>
#include <vector>

#include "tom/io/import.h"

namespace tom::detail {

ImportResult import_openmesh(const std::string& path, const std::string& extension);
ImportResult import_gltf(const std::string& path, bool binary);
std::string file_stem(const std::string& path);
/// The whole file; IoError when it cannot be read.
std::vector<uint8_t> read_whole_file(const std::string& path);

} // namespace tom::detail
