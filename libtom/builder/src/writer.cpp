// Serialisation of TOM meshes into the .tom format (docs/FORMAT.md).

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>


#include "coarse.h"
#include "format_layout.h"
#include "platform.h"
#include "scene_codec.h"
#include "tom/errors.h"
#include "tom/builder/writer.h"
#include "tom/format.h"

namespace tom {

namespace {

using namespace layout;

void pad4(std::vector<uint8_t>& v) {
    while (v.size() % 4) v.push_back(0);
}

std::vector<uint8_t> metadata_bytes(const std::vector<MetadataEntry>& entries) {
    std::vector<uint8_t> out(4);
    store_u32(out.data(), uint32_t(entries.size()));
    for (const MetadataEntry& e : entries) {
        uint8_t head[8];
        store_u32(head, uint32_t(e.first.size()));
        store_u32(head + 4, uint32_t(e.second.size()));
        out.insert(out.end(), head, head + 8);
        out.insert(out.end(), e.first.begin(), e.first.end());
        pad4(out);
        out.insert(out.end(), e.second.begin(), e.second.end());
        pad4(out);
    }
    return out;
}

// PART: the header and one record per part (empty: a mesh of one part)
std::vector<uint8_t> part_bytes(const TomMesh& mesh) {
    if (mesh.parts.empty()) return {};
    std::vector<uint8_t> out(parts_header_bytes + mesh.parts.size() * part_record_bytes, 0);
    store_u32(out.data(), uint32_t(mesh.parts.size()));
    for (size_t k = 0; k < mesh.parts.size(); ++k) {
        uint8_t* r = &out[parts_header_bytes + k * part_record_bytes];
        store_u32(r, mesh.parts[k].first_triangle);
        store_u32(r + 4, mesh.parts[k].triangle_count);
        store_u32(r + 8, uint32_t(mesh.parts[k].material));
        store_u32(r + 12, mesh.parts[k].attributes);
    }
    return out;
}

// COAR: the corners of the triangles active at a coarse resolution, mapped to it (empty: none,
// and always for a mesh with parts, whose live triangles are one prefix per part)
std::vector<uint8_t> coarse_bytes(const TomMesh& mesh) {
    if (!mesh.parts.empty()) return {};
    const MeshView view = mesh.view();
    const uint32_t resolution = detail::coarse_resolution(view);
    if (resolution == 0) return {};
    const uint32_t triangles = detail::active_prefix(view, resolution);
    if (triangles == 0) return {};
    const uint32_t index_size = detail::coarse_index_size(resolution);
    std::vector<uint32_t> corners(size_t(triangles) * 3);
    for (uint32_t c = 0; c < corners.size(); ++c) corners[c] = detail::map_corner(view, c, resolution);
    std::vector<uint8_t> out(coarse_header_bytes, 0);
    store_u32(&out[c_resolution], resolution);
    store_u32(&out[c_triangle_count], triangles);
    store_u32(&out[c_index_size], index_size);
    const std::vector<uint8_t> body = index_bytes(corners, index_size);
    out.insert(out.end(), body.begin(), body.end());
    return out;
}

// The largest material index the meshes name (mesh or part), -1 for none.
int32_t largest_material(const std::vector<TomMesh>& meshes) {
    int32_t top = -1;
    for (const TomMesh& m : meshes) {
        top = std::max(top, m.material);
        for (const Part& p : m.parts) top = std::max(top, p.material);
    }
    return top;
}

// Meshes that name materials of a scene that stores none (the builder's own arrays, an
// engine's material ids) get default materials "material K" up to the largest, so that every
// index in the file names a stored material (rule 17). \throw ArgumentError past 65536.
Scene with_placeholder_materials(const Scene& scene, int32_t top) {
    constexpr int32_t max_placeholders = 65536;
    if (top >= max_placeholders)
        throw ArgumentError("serialize: a mesh names material " + std::to_string(top) + " but the scene stores none; at most " +
                            std::to_string(max_placeholders) + " default materials are written in their place");
    Scene out = scene;
    for (int32_t k = 0; k <= top; ++k) {
        out.materials.emplace_back();
        out.materials.back().name = "material " + std::to_string(k);
    }
    return out;
}

uint32_t choose_index_size(const TomMesh& mesh, IndexSize requested) {
    if (requested == IndexSize::bits32) return 4;
    return mesh.vertex_count() <= 65536 ? 2 : 4;
}

} // namespace

std::vector<uint8_t> serialize(const std::vector<TomMesh>& meshes, const WriteOptions& options) { return serialize(meshes, Scene{}, options); }

std::vector<uint8_t> serialize(const std::vector<TomMesh>& meshes, const Scene& given_scene, const WriteOptions& options) {
    const int32_t top_material = largest_material(meshes);
    std::optional<Scene> placeholders;
    if (given_scene.materials.empty() && top_material >= 0) placeholders = with_placeholder_materials(given_scene, top_material);
    const Scene& scene = placeholders ? *placeholders : given_scene;
    for (const Instance& inst : scene.instances)
        if (inst.mesh >= meshes.size())
            throw ArgumentError("serialize: an instance names mesh " + std::to_string(inst.mesh) + " of " + std::to_string(meshes.size()));
    for (const Material& m : scene.materials)
        for (const TextureRef& t : m.textures)
            if (t.image >= 0 && size_t(t.image) >= scene.images.size())
                throw ArgumentError("serialize: material '" + m.name + "' shows image " + std::to_string(t.image) + " of " + std::to_string(scene.images.size()));
    std::vector<PendingSection> sections;
    if (!scene.materials.empty()) sections.push_back({sec_materials, file_level, detail::encode_materials(scene.materials)});
    if (!scene.instances.empty()) sections.push_back({sec_instances, file_level, detail::encode_instances(scene.instances)});
    if (!scene.images.empty()) sections.push_back({sec_images, file_level, detail::encode_images(scene)});
    if (!scene.gltf.empty()) sections.push_back({sec_source_gltf, file_level, detail::encode_source_gltf(scene.gltf)});
    if (!options.provenance.empty())
        sections.push_back({sec_provenance, file_level, std::vector<uint8_t>(options.provenance.begin(), options.provenance.end())});
    for (uint32_t mi = 0; mi < meshes.size(); ++mi) {
        const TomMesh& m = meshes[mi];
        const uint32_t index_size = choose_index_size(m, options.index_size);
        std::vector<uint8_t> head(mesh_header_bytes, 0);
        store_u32(&head[m_vertex_count], m.vertex_count());
        store_u32(&head[m_triangle_count], m.triangle_count());
        store_u32(&head[m_min_vertex_count], m.min_vertex_count);
        store_u32(&head[m_index_size], index_size);
        store_u32(&head[m_material], uint32_t(m.material));
        // the optional streams, in the order of layout::attribute_streams
        std::vector<PendingSection> streams;
        uint32_t attributes = 0;
        int stream = 0;
        for_each_attribute_stream(m, [&](const std::vector<float>& values, size_t, const char*) {
            const AttributeStream& spec = attribute_streams[stream++];
            if (values.empty()) return;
            attributes |= spec.flag;
            streams.push_back({spec.section, mi, float_bytes(values)});
        });
        std::vector<uint8_t> parts = part_bytes(m);
        if (!parts.empty()) attributes |= attr_parts;
        store_u32(&head[m_attributes], attributes);
        for (int k = 0; k < 3; ++k) {
            store_f32(&head[m_bounds_min + 4 * k], m.bounds_min[k]);
            store_f32(&head[m_bounds_max + 4 * k], m.bounds_max[k]);
        }
        store_u32(&head[m_name_bytes], uint32_t(m.name.size()));
        head.insert(head.end(), m.name.begin(), m.name.end());
        sections.push_back({sec_mesh, mi, std::move(head)});
        sections.push_back({sec_positions, mi, float_bytes(m.positions)});
        for (PendingSection& section : streams) sections.push_back(std::move(section));
        sections.push_back({sec_substitute, mi, index_bytes(m.substitute, index_size)});
        sections.push_back({sec_triangles, mi, index_bytes(m.triangles, index_size)});
        std::vector<uint8_t> coarse = coarse_bytes(m);
        if (!coarse.empty()) sections.push_back({sec_coarse, mi, std::move(coarse)});
        if (!m.metadata.empty()) sections.push_back({sec_metadata, mi, metadata_bytes(m.metadata)});
        if (!m.pair_bits.empty()) sections.push_back({sec_pairs, mi, m.pair_bits});
        if (!parts.empty()) sections.push_back({sec_parts, mi, std::move(parts)});
        if (!m.extra_streams.empty()) {
            std::vector<VertexStreamView> views;
            for (const VertexStream& x : m.extra_streams) {
                if (x.element_bytes() == 0 || x.data.size() != size_t(m.vertex_count()) * x.element_bytes())
                    throw ArgumentError("serialize: mesh '" + m.name + "': carried stream '" + x.name + "' has " + std::to_string(x.data.size()) +
                                        " bytes for " + std::to_string(m.vertex_count()) + " vertices of type " + std::to_string(x.component_type) + " x " +
                                        std::to_string(x.components));
                views.push_back({x.name, x.component_type, x.components, x.normalized, x.data.data()});
            }
            sections.push_back({sec_extra_streams, mi, detail::encode_extra_streams(views, m.vertex_count())});
        }
    }
    std::vector<uint8_t> file = assemble_file(sections, uint32_t(meshes.size()));
    // the writer never produces what the reader rejects: a mesh the builder got wrong, or a
    // scene whose references do not hold, fails here instead of in an engine
    OpenOptions no_checksums;
    no_checksums.verify_checksums = false;  // just computed
    try {
        validate_bytes(file.data(), file.size(), "<serialized>", no_checksums);
    } catch (const FormatError& e) {
        throw ArgumentError(std::string("serialize: the meshes would make a file the reader rejects: ") + e.what());
    }
    return file;
}

void write_bytes_atomically(const std::string& path, const void* data, size_t bytes) {
    static std::atomic<unsigned> counter{0};
    const std::string tmp = path + ".tmp." + std::to_string(detail::process_id()) + "." + std::to_string(counter++);
    FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw IoError("cannot create '" + tmp + "': " + std::strerror(errno));
    const bool ok = std::fwrite(data, 1, bytes, f) == bytes && std::fflush(f) == 0;
    const int write_errno = errno;
    if (std::fclose(f) != 0 || !ok) {
        std::remove(tmp.c_str());
        throw IoError("cannot write '" + tmp + "': " + std::strerror(write_errno));
    }
    const std::string failure = detail::replace_file(tmp, path);
    if (!failure.empty()) {
        std::remove(tmp.c_str());
        throw IoError("cannot rename '" + tmp + "' to '" + path + "': " + failure);
    }
}

void write_file(const std::string& path, const std::vector<TomMesh>& meshes, const WriteOptions& options) {
    write_file(path, meshes, Scene{}, options);
}

void write_file(const std::string& path, const std::vector<TomMesh>& meshes, const Scene& scene, const WriteOptions& options) {
    const std::vector<uint8_t> bytes = serialize(meshes, scene, options);
    write_bytes_atomically(path, bytes.data(), bytes.size());
}

} // namespace tom
