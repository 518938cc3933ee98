// OBJ and PLY output of one resolution of one or more meshes.

#include "tom/io/export.h"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <set>
#include <string>

#include "import_backends.h"
#include "tom/errors.h"
#include "tom/builder/writer.h"
#include "tom/format.h"

namespace tom {

namespace {

std::string extension_of(const std::string& path) {
    const size_t dot = path.find_last_of('.');
    std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

void append(std::string& out, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
void append(std::string& out, const char* fmt, ...) {
    char buf[256];
    va_list args;
    va_start(args, fmt);
    const int len = std::vsnprintf(buf, sizeof buf, fmt, args);
    va_end(args);
    out.append(buf, size_t(std::max(0, std::min(len, int(sizeof buf) - 1))));
}

struct Streams {
    bool normals = true, texcoords = true, colors = true;
    size_t vertices = 0, triangles = 0;
};

Streams common_streams(const std::vector<ExportPart>& parts) {
    Streams s;
    for (const ExportPart& p : parts) {
        s.normals &= p.mesh->normals != nullptr;
        s.texcoords &= p.mesh->texcoords != nullptr;
        s.colors &= p.mesh->colors != nullptr;
        s.vertices += p.vertex_count;
        s.triangles += p.indices.size() / 3;
    }
    return s;
}

// A mesh's groups of triangles in its `indices`: its parts' draws, or one of all with its material.
std::vector<PartDraw> groups_of(const ExportPart& part) {
    if (!part.draws.empty()) return part.draws;
    return {PartDraw{0, uint32_t(part.indices.size()), part.mesh->material}};
}

int max_material(const std::vector<ExportPart>& parts) {
    int top = -1;
    for (const ExportPart& part : parts)
        for (const PartDraw& d : groups_of(part)) top = std::max(top, d.material);
    return top;
}

// OBJ material names: the stored names with white space replaced, unique; material_k for none.
std::vector<std::string> material_names(const Scene& scene, int count) {
    std::vector<std::string> names;
    std::set<std::string> taken;
    for (int k = 0; k < count; ++k) {
        std::string name = size_t(k) < scene.materials.size() ? scene.materials[size_t(k)].name : std::string();
        for (char& c : name)
            if (std::isspace(static_cast<unsigned char>(c))) c = '_';
        if (name.empty() || taken.count(name)) name = "material_" + std::to_string(k);
        taken.insert(name);
        names.push_back(name);
    }
    return names;
}

// Whether a group of the parts has no material (-1).
bool any_without_material(const std::vector<ExportPart>& parts) {
    for (const ExportPart& part : parts)
        for (const PartDraw& d : groups_of(part))
            if (d.material < 0 && d.index_count > 0) return true;
    return false;
}

// A name not among `names`: `base`, or base_2, base_3, ...
std::string unused_name(const std::string& base, const std::vector<std::string>& names) {
    std::string name = base;
    for (int k = 2; std::find(names.begin(), names.end(), name) != names.end(); ++k) name = base + "_" + std::to_string(k);
    return name;
}

// OBJ keeps textures as files: stored image k of the scene is written beside the OBJ as
// STEM.image-K.EXT (EXT from its MIME type) by write_stored_images, and named so in the .mtl.
std::filesystem::path stored_image_file(const std::string& obj_path, int32_t k, const Image& image) {
    const std::string& mime = image.mime_type;
    const std::string ext = mime == "image/png" ? "png" : mime == "image/jpeg" ? "jpg" : mime == "image/webp" ? "webp" : mime == "image/ktx2" ? "ktx2"
                          : mime == "image/avif" ? "avif" : mime == "image/gif" ? "gif" : mime == "image/bmp" ? "bmp" : "bin";
    std::filesystem::path p(obj_path);
    return p.replace_filename(p.stem().string() + ".image-" + std::to_string(k) + "." + ext);
}

// The stored images that the first `used` materials show, each once.
void write_stored_images(const Scene& scene, size_t used, const std::string& obj_path) {
    std::set<int32_t> written;
    for (size_t k = 0; k < used && k < scene.materials.size(); ++k)
        for (const TextureRef& t : scene.materials[k].textures)
            if (t.image >= 0 && written.insert(t.image).second) {
                const Image& image = scene.images[size_t(t.image)];
                write_bytes_atomically(stored_image_file(obj_path, t.image, image).string(), image.data, size_t(image.bytes));
            }
}

// The .mtl of `names`: the scene's first `stored` materials, then default entries (the
// materials the scene lacks, the groups without one).
std::string mtl_text(const Scene& scene, const std::vector<std::string>& names, size_t stored, const std::string& texture_dir, const std::string& obj_path) {
    namespace fs = std::filesystem;
    const fs::path out_dir = fs::absolute(fs::path(obj_path)).parent_path();
    std::string out = "# written by libtom\n";
    for (size_t k = 0; k < names.size(); ++k) {
        append(out, "\nnewmtl %s\n", names[k].c_str());
        if (k >= scene.materials.size() || k >= stored) {
            out += "Kd 0.8 0.8 0.8\n";
            continue;
        }
        const Material& m = scene.materials[k];
        append(out, "Kd %.6g %.6g %.6g\nd %.6g\n", m.base_color[0], m.base_color[1], m.base_color[2], m.base_color[3]);
        if (m.emissive[0] != 0 || m.emissive[1] != 0 || m.emissive[2] != 0) append(out, "Ke %.6g %.6g %.6g\n", m.emissive[0], m.emissive[1], m.emissive[2]);
        for (const TextureRef& t : m.textures) {
            std::string uri = t.image >= 0 ? stored_image_file(obj_path, t.image, scene.images[size_t(t.image)]).filename().string() : t.uri;
            if (uri.empty()) continue;
            if (t.image < 0 && !texture_dir.empty() && uri.find("://") == std::string::npos)
                uri = fs::relative(fs::absolute(fs::path(texture_dir) / uri), out_dir).generic_string();
            const char* key = t.role == TextureRole::base_color ? "map_Kd"
                            : t.role == TextureRole::normal     ? "norm"
                            : t.role == TextureRole::emissive   ? "map_Ke"
                            : t.role == TextureRole::occlusion  ? "map_Ka"
                                                                : "map_Pr";
            append(out, "%s %s\n", key, uri.c_str());
        }
    }
    return out;
}

// `materials`: a name per material index, and, when a group has none, a last one for those
// (OBJ has no "no material" once a usemtl has been given).
std::string obj_text(const std::vector<ExportPart>& parts, const std::vector<std::string>& materials, const std::string& mtl_name) {
    const Streams s = common_streams(parts);
    std::string out;
    out.reserve(s.vertices * 100 + s.triangles * 30);
    append(out, "# %zu vertices, %zu triangles (written by libtom)\n", s.vertices, s.triangles);
    if (!materials.empty()) append(out, "mtllib %s\n", mtl_name.c_str());
    for (const ExportPart& part : parts) {
        const MeshView& m = *part.mesh;
        for (uint32_t v = 0; v < part.vertex_count; ++v) {
            const float* p = m.positions + 3 * size_t(v);
            if (s.colors) {
                const float* c = m.colors + 4 * size_t(v);
                append(out, "v %.9g %.9g %.9g %.6g %.6g %.6g\n", p[0], p[1], p[2], c[0], c[1], c[2]);
            } else {
                append(out, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
            }
        }
    }
    if (s.texcoords)
        for (const ExportPart& part : parts)
            for (uint32_t v = 0; v < part.vertex_count; ++v)
                append(out, "vt %.9g %.9g\n", part.mesh->texcoords[2 * size_t(v)], detail::flip_v(part.mesh->texcoords[2 * size_t(v) + 1]));
    if (s.normals)
        for (const ExportPart& part : parts)
            for (uint32_t v = 0; v < part.vertex_count; ++v) {
                const float* q = part.mesh->normals + 3 * size_t(v);
                append(out, "vn %.7g %.7g %.7g\n", q[0], q[1], q[2]);
            }
    size_t base = 1;  // OBJ indices start at 1
    for (const ExportPart& part : parts) {
        append(out, "o %.*s\n", int(part.mesh->name.size()), part.mesh->name.data());
        for (const PartDraw& group : groups_of(part)) {
            if (group.index_count == 0) continue;
            if (!materials.empty()) append(out, "usemtl %s\n", (group.material >= 0 ? materials[size_t(group.material)] : materials.back()).c_str());
            for (size_t t = group.first_index; t + 2 < size_t(group.first_index) + group.index_count; t += 3) {
                out += 'f';
                for (int k = 0; k < 3; ++k) {
                    const size_t i = part.indices[t + size_t(k)] + base;
                    if (s.texcoords && s.normals)
                        append(out, " %zu/%zu/%zu", i, i, i);
                    else if (s.texcoords)
                        append(out, " %zu/%zu", i, i);
                    else if (s.normals)
                        append(out, " %zu//%zu", i, i);
                    else
                        append(out, " %zu", i);
                }
                out += '\n';
            }
        }
        base += part.vertex_count;
    }
    return out;
}

std::string ply_bytes(const std::vector<ExportPart>& parts) {
    const Streams s = common_streams(parts);
    const bool with_materials = max_material(parts) >= 0;
    std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by libtom\n";
    append(out, "element vertex %zu\nproperty float x\nproperty float y\nproperty float z\n", s.vertices);
    if (s.normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
    if (s.texcoords) out += "property float s\nproperty float t\n";
    if (s.colors) out += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
    append(out, "element face %zu\nproperty list uchar uint vertex_indices\n%send_header\n", s.triangles,
           with_materials ? "property int material_index\n" : "");
    auto put = [&](const void* p, size_t bytes) { out.append(static_cast<const char*>(p), bytes); };
    for (const ExportPart& part : parts) {
        const MeshView& m = *part.mesh;
        for (uint32_t v = 0; v < part.vertex_count; ++v) {
            put(m.positions + 3 * size_t(v), 12);
            if (s.normals) put(m.normals + 3 * size_t(v), 12);
            if (s.texcoords) {
                const float st[2] = {m.texcoords[2 * size_t(v)], detail::flip_v(m.texcoords[2 * size_t(v) + 1])};
                put(st, 8);
            }
            if (s.colors)
                for (int k = 0; k < 4; ++k) {
                    const float c = std::min(1.0f, std::max(0.0f, m.colors[4 * size_t(v) + size_t(k)]));
                    const uint8_t b = uint8_t(c * 255.0f + 0.5f);
                    put(&b, 1);
                }
        }
    }
    uint32_t base = 0;
    for (const ExportPart& part : parts) {
        for (const PartDraw& group : groups_of(part))
            for (size_t t = group.first_index; t + 2 < size_t(group.first_index) + group.index_count; t += 3) {
                const uint8_t three = 3;
                put(&three, 1);
                for (int k = 0; k < 3; ++k) {
                    const uint32_t i = part.indices[t + size_t(k)] + base;
                    put(&i, 4);
                }
                if (with_materials) put(&group.material, 4);
            }
        base += part.vertex_count;
    }
    return out;
}

} // namespace

void export_meshes(const std::string& path, const std::vector<ExportPart>& parts, const Scene& scene, const std::string& texture_dir) {
    const std::string ext = extension_of(path);
    std::string bytes;
    if (ext == "obj") {
        // the names are as many as the materials referenced, and every reference must be stored:
        // a count the meshes merely declare is never looped over
        const int top = max_material(parts);
        if (top >= 0 && size_t(top) >= scene.materials.size())
            throw IoError("cannot write '" + path + "': a mesh refers to material " + std::to_string(top) + ", but " +
                          std::to_string(scene.materials.size()) + " are stored");
        std::vector<std::string> materials = material_names(scene, top + 1);
        const size_t stored = materials.size();
        if (!materials.empty() && any_without_material(parts)) materials.push_back(unused_name("default", materials));
        const std::filesystem::path mtl = std::filesystem::path(path).replace_extension(".mtl");
        if (!materials.empty()) {
            const std::string text = mtl_text(scene, materials, stored, texture_dir, path);
            write_stored_images(scene, stored, path);
            write_bytes_atomically(mtl.string(), text.data(), text.size());
        }
        bytes = obj_text(parts, materials, mtl.filename().string());
    } else if (ext == "ply")
        bytes = ply_bytes(parts);
    else
        throw IoError("cannot write '" + path + "': unsupported output type '." + ext + "' (use .obj or .ply)");
    write_bytes_atomically(path, bytes.data(), bytes.size());
}

} // namespace tom
