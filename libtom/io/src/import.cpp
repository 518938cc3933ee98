// Dispatch of import_file() by file extension.

#include "tom/io/import.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

#include <sys/stat.h>

#include "import_backends.h"
#include "tom/errors.h"

namespace tom {

namespace {

std::string lower_extension(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    const size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    std::string ext = path.substr(dot + 1);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

} // namespace

namespace detail {

std::vector<uint8_t> read_whole_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError("cannot open '" + path + "': " + std::strerror(errno));
    std::vector<uint8_t> bytes;
    // in blocks (the size may change under us; a block at a time also reads pipes)
    constexpr size_t kBlock = size_t(1) << 20;
    for (;;) {
        const size_t at = bytes.size();
        bytes.resize(at + kBlock);
        in.read(reinterpret_cast<char*>(bytes.data() + at), std::streamsize(kBlock));
        bytes.resize(at + size_t(in.gcount()));
        if (!in) break;
    }
    if (in.bad()) throw IoError("cannot read '" + path + "'");
    return bytes;
}

} // namespace detail

bool is_importable(const std::string& path) {
    const std::string ext = lower_extension(path);
    return ext == "obj" || ext == "ply" || ext == "off" || ext == "stl" || ext == "gltf" || ext == "glb";
}

ImportResult import_file(const std::string& path) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) throw IoError("cannot open '" + path + "': " + std::strerror(errno));
    if (!S_ISREG(st.st_mode)) throw IoError("cannot read '" + path + "': not a regular file");
    if (st.st_size == 0) throw MeshError(path + ": the file is empty");
    const std::string ext = lower_extension(path);
    ImportResult result;
    if (ext == "gltf" || ext == "glb") {
        result = detail::import_gltf(path, ext == "glb");
    } else if (ext == "ply") {
        std::optional<ImportResult> simple = detail::read_simple_binary_ply(path, detail::read_whole_file(path));
        result = simple ? std::move(*simple) : detail::import_openmesh(path, ext);
    } else if (ext == "obj" || ext == "off" || ext == "stl") {
        result = detail::import_openmesh(path, ext);
    } else {
        throw MeshError(path + ": unsupported file type '." + ext + "' (supported: obj, ply, off, stl, gltf, glb)");
    }
    result.format = ext;
    return result;
}

} // namespace tom
