// The binary PLY files of scanners and photogrammetry (a vertex element of float positions,
// optionally float normals and uchar colours, and a face element holding only its index lists),
// read straight into a Mesh. OpenMesh's reader builds a half-edge mesh behind a checked copy of
// the file, which on large scans costs a good part of the build's time and most of the
// import's memory. Any other layout goes to OpenMesh (import_openmesh) as before.
//
// Reads nothing past the bytes it was given: every count is checked against the bytes left
// before anything is reserved, every index against the vertex count.

#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "import_backends.h"
#include "tom/errors.h"

namespace tom::detail {

namespace {

// What a simple file holds: per vertex, the byte offset of each property read (-1: absent).
struct SimpleLayout {
    uint64_t vertices = 0, faces = 0;
    size_t body = 0;          // offset of the first vertex
    uint32_t stride = 0;      // bytes per vertex
    int position[3] = {-1, -1, -1}, normal[3] = {-1, -1, -1}, color[4] = {-1, -1, -1, -1};
    int count_bytes = 0;      // of a face's corner count: 1 or 4
    bool count_signed = false;
    size_t vertex_line = 0, face_line = 0;  // the element lines, for messages (as check_ply's)
    std::string list_name;
};

// The header's lines (up to end_header), as words; false when it is not a simple layout.
bool parse_simple_header(std::string_view text, SimpleLayout& l) {
    size_t at = 0, line_number = 0;
    auto next_line = [&](std::vector<std::string_view>& words) {
        words.clear();
        if (at >= text.size() || at > (size_t(1) << 20)) return false;
        ++line_number;
        size_t end = text.find('\n', at);
        if (end == std::string_view::npos) return false;
        std::string_view line = text.substr(at, end - at);
        at = end + 1;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        for (size_t i = 0; i < line.size();) {
            while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
            size_t j = i;
            while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
            if (j > i) words.push_back(line.substr(i, j - i));
            i = j;
        }
        return true;
    };
    auto count_of = [](std::string_view s, uint64_t& n) {
        if (s.empty() || s.size() > 10) return false;
        n = 0;
        for (char c : s) {
            if (c < '0' || c > '9') return false;
            n = n * 10 + uint64_t(c - '0');
        }
        return n <= 0xFFFFFFFFull;
    };
    std::vector<std::string_view> w;
    if (!next_line(w) || w.size() != 1 || w[0] != "ply") return false;
    if (!next_line(w) || w.size() != 3 || w[0] != "format" || w[1] != "binary_little_endian" || w[2] != "1.0") return false;
    int element = 0;  // 1 vertex, 2 face
    bool face_list = false;
    for (;;) {
        if (!next_line(w)) return false;
        if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "end_header") break;
        if (w[0] == "element" && w.size() == 3) {
            ++element;
            if (element == 1 && w[1] == "vertex" && count_of(w[2], l.vertices)) {
                l.vertex_line = line_number;
                continue;
            }
            if (element == 2 && w[1] == "face" && count_of(w[2], l.faces)) {
                l.face_line = line_number;
                continue;
            }
            return false;
        }
        if (w[0] != "property") return false;
        if (element == 1 && w.size() == 3) {
            static constexpr std::string_view names[] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha"};
            int k = 0;
            while (k < 10 && w[2] != names[k]) ++k;
            const bool is_float = w[1] == "float" || w[1] == "float32", is_uchar = w[1] == "uchar" || w[1] == "uint8";
            if (k == 10 || (k < 6 ? !is_float : !is_uchar)) return false;
            int* slot = k < 3 ? &l.position[k] : k < 6 ? &l.normal[k - 3] : &l.color[k - 6];
            if (*slot >= 0) return false;
            *slot = int(l.stride);
            l.stride += k < 6 ? 4 : 1;
            continue;
        }
        if (element == 2 && w.size() == 5 && w[1] == "list" && !face_list && (w[4] == "vertex_indices" || w[4] == "vertex_index") &&
            (w[3] == "int" || w[3] == "int32" || w[3] == "uint" || w[3] == "uint32")) {
            if (w[2] == "uchar" || w[2] == "uint8") l.count_bytes = 1;
            else if (w[2] == "char" || w[2] == "int8") l.count_bytes = 1, l.count_signed = true;
            else if (w[2] == "int" || w[2] == "int32") l.count_bytes = 4, l.count_signed = true;
            else if (w[2] == "uint" || w[2] == "uint32") l.count_bytes = 4;
            else return false;
            face_list = true;
            l.list_name = std::string(w[4]);
            continue;
        }
        return false;
    }
    const bool positions = l.position[0] >= 0 && l.position[1] >= 0 && l.position[2] >= 0;
    const bool normals = l.normal[0] >= 0 && l.normal[1] >= 0 && l.normal[2] >= 0, no_normals = l.normal[0] < 0 && l.normal[1] < 0 && l.normal[2] < 0;
    const bool colors = l.color[0] >= 0 && l.color[1] >= 0 && l.color[2] >= 0, no_colors = l.color[0] < 0 && l.color[1] < 0 && l.color[2] < 0 && l.color[3] < 0;
    l.body = at;
    return element == 2 && face_list && positions && (normals || no_normals) && (colors || no_colors);
}

float load_float(const uint8_t* p) {
    float f;
    std::memcpy(&f, p, 4);
    return f;
}

} // namespace

std::optional<ImportResult> read_simple_binary_ply(const std::string& path, const std::vector<uint8_t>& bytes) {
    const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    SimpleLayout l;
    if (!parse_simple_header(text, l)) return std::nullopt;
    const uint64_t size = bytes.size();
    const std::string vertex_at = path + ":" + std::to_string(l.vertex_line) + ": ", face_at = path + ":" + std::to_string(l.face_line) + ": ";
    if (l.vertices == 0 && l.faces > 0) throw MeshError(face_at + "faces without a vertex element before them");
    if (l.stride == 0 || l.vertices > (size - l.body) / l.stride)
        throw MeshError(vertex_at + std::to_string(l.vertices) + " vertex elements of at least " + std::to_string(l.stride) + " bytes cannot fit in the " +
                          std::to_string(size - l.body) + " bytes left");
    Mesh mesh;
    mesh.name = file_stem(path);
    const size_t nv = size_t(l.vertices);
    mesh.positions.resize(nv * 3);
    const bool normals = l.normal[0] >= 0, colors = l.color[0] >= 0;
    if (normals) mesh.normals.resize(nv * 3);
    if (colors) mesh.colors.resize(nv * 4);
    const uint8_t* v = bytes.data() + l.body;
    for (size_t i = 0; i < nv; ++i, v += l.stride) {
        for (int k = 0; k < 3; ++k) mesh.positions[3 * i + size_t(k)] = load_float(v + l.position[k]);
        if (normals)
            for (int k = 0; k < 3; ++k) mesh.normals[3 * i + size_t(k)] = load_float(v + l.normal[k]);
        if (colors)
            for (int k = 0; k < 4; ++k) mesh.colors[4 * i + size_t(k)] = l.color[k] >= 0 ? float(v[l.color[k]]) / 255.0f : 1.0f;
    }
    // faces: a corner count, then that many 32-bit indices; polygons become fans (as OpenMesh's)
    size_t at = size_t(v - bytes.data());
    const uint64_t least_face = uint64_t(l.count_bytes) + 12;  // a triangle's bytes
    mesh.indices.reserve(size_t(std::min<uint64_t>(l.faces, (size - at) / least_face)) * 3);
    uint64_t short_faces = 0;
    uint32_t corner[3];
    for (uint64_t f = 0; f < l.faces; ++f) {
        if (at + size_t(l.count_bytes) > size) throw MeshError(face_at + "the data ends inside face " + std::to_string(f));
        int64_t n = 0;
        if (l.count_bytes == 1) {
            n = l.count_signed ? int64_t(int8_t(bytes[at])) : int64_t(bytes[at]);
        } else {
            uint32_t u;
            std::memcpy(&u, &bytes[at], 4);
            n = l.count_signed ? int64_t(int32_t(u)) : int64_t(u);
        }
        at += size_t(l.count_bytes);
        if (n < 0 || uint64_t(n) > (size - at) / 4)
            throw MeshError(face_at + "face " + std::to_string(f) + ": the list " + l.list_name + " announces " + std::to_string(n) + " items, the file holds fewer");
        if (n < 3) {
            ++short_faces;
            at += size_t(n) * 4;
            continue;
        }
        for (int64_t j = 0; j < n; ++j, at += 4) {
            uint32_t index;
            std::memcpy(&index, &bytes[at], 4);
            if (index >= l.vertices)
                throw MeshError(face_at + "face " + std::to_string(f) + " refers to vertex " + std::to_string(int32_t(index)) + ", the file has " + std::to_string(l.vertices));
            if (j < 2) {
                corner[j] = index;
                continue;
            }
            corner[2] = index;
            mesh.indices.insert(mesh.indices.end(), corner, corner + 3);
            corner[1] = index;
        }
    }
    if (mesh.indices.empty()) throw MeshError(path + ": no triangles or polygons in the file");
    ImportResult result;
    if (short_faces) result.warnings.push_back(path + ": " + std::to_string(short_faces) + " faces of fewer than 3 corners skipped");
    result.meshes.push_back(std::move(mesh));
    return result;
}

} // namespace tom::detail
