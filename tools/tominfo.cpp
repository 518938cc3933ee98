// tominfo: prints what a .tom file holds: header, sections, meshes, counts and sizes.

#include <cstdio>
#include <optional>

#include <nlohmann/json.hpp>

#include "tom/error_curve.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/stream/stream_file.h"
#include "tool_common.h"

namespace {

struct Options {
    std::string path;
    bool json = false, sections = false, no_verify = false, show_curve = false, show_scene = false;
};

int parse_options(Options& o, int argc, char** argv) {
    std::string path;
    CLI::App app{"tominfo: show the header, meshes, counts and sizes of a .tom file"};
    app.set_version_flag("--version", "tominfo 0.1.0");
    app.add_option("file", o.path, "A .tom file")->required();
    app.add_flag("--json", o.json, "Print one JSON object instead of text");
    app.add_flag("--sections", o.sections, "Also list the section table");
    app.add_flag("--curve", o.show_curve, "Also print each mesh's stored error curve");
    app.add_flag("--scene", o.show_scene, "Also list the materials (with texture references) and the instances (node, mesh, position)");
    app.add_flag("--no-verify", o.no_verify, "Skip the checksum pass (the structure is still validated)");
    app.footer("Exit codes: 0 ok, 1 the file is unreadable or invalid (the reason is printed), 2 usage error.");
    return tools::parse(app, argc, argv);
}

// A mesh's parts (FORMAT.md, PART): their ranges, materials and own attributes.
nlohmann::ordered_json parts_json(const tom::File& file, const tom::MeshView& m) {
    nlohmann::ordered_json parts = nlohmann::json::array();
    for (uint32_t p = 0; p < tom::part_count(m); ++p) {
        const tom::Part part = tom::part_at(m, p);
        nlohmann::ordered_json pj;
        pj["first_triangle"] = part.first_triangle;
        pj["triangles"] = part.triangle_count;
        pj["min_triangles"] = tom::active_part_triangle_count(m, p, m.min_vertex_count);
        pj["material"] = part.material;
        pj["material_name"] = part.material >= 0 && size_t(part.material) < file.scene().materials.size()
                                  ? nlohmann::json(file.scene().materials[size_t(part.material)].name)
                                  : nlohmann::json(nullptr);
        std::vector<std::string> own;
        const char* names[5] = {"normal", "texcoord0", "color0", "texcoord1", "tangent"};
        for (int k = 0; k < 5; ++k)
            if (part.attributes & (1u << k)) own.push_back(names[k]);
        pj["attributes"] = own;
        parts.push_back(pj);
    }
    return parts;
}

// A mesh's stored error curve, or null.
nlohmann::ordered_json curve_json(const tom::MeshView& m) {
    if (const std::optional<tom::ErrorCurve> curve = tom::read_error_curve(m)) {
        nlohmann::ordered_json cj;
        cj["diagonal"] = curve->diagonal;
        cj["k_mean"] = curve->k_mean;
        cj["k_max"] = curve->k_max;
        cj["points"] = nlohmann::json::array();
        for (const tom::ErrorCurvePoint& p : curve->points)
            cj["points"].push_back({{"vertices", p.vertices}, {"triangles", p.triangles}, {"mean_percent", 100.0 * p.mean}, {"max_percent", 100.0 * p.max}});
        return cj;
    }
    return nullptr;
}

// One mesh: counts, floors, attributes, bounds, bytes, parts and curve.
nlohmann::ordered_json mesh_json(const tom::File& file, uint32_t i) {
    nlohmann::ordered_json mj;
    const tom::MeshView& m = file.mesh(i);
    mj["name"] = std::string(m.name);
    mj["vertices"] = m.vertex_count;
    mj["triangles"] = m.triangle_count;
    mj["min_vertices"] = m.min_vertex_count;
    mj["min_triangles"] = tom::active_triangle_count(m, m.min_vertex_count);
    if (const std::optional<tom::UsableFloor> floor = tom::read_usable_floor(m)) {
        const uint32_t n = tom::floor_vertex_count(m);
        mj["usable_floor"] = {{"vertices", n}, {"triangles", tom::active_triangle_count(m, n)}, {"mean_bound_percent", 100.0 * floor->mean_bound}};
    } else {
        mj["usable_floor"] = nullptr;
    }
    mj["index_bytes"] = m.index_size;
    if (m.coarse_corners)  // FORMAT.md, COAR: extraction at or below this resolution starts from them
        mj["coarse_corners"] = {{"resolution", m.coarse_resolution}, {"triangles", m.coarse_triangle_count}};
    else
        mj["coarse_corners"] = nullptr;
    mj["material"] = m.material;
    if (m.parts) mj["parts"] = parts_json(file, m);  // FORMAT.md, PART: one draw per part, each with its material
    std::vector<std::string> attrs = {"position"};
    if (m.normals) attrs.push_back("normal");
    if (m.texcoords) attrs.push_back("texcoord0");
    if (m.colors) attrs.push_back("color0");
    if (m.texcoords1) attrs.push_back("texcoord1");
    if (m.tangents) attrs.push_back("tangent");
    mj["attributes"] = attrs;
    std::vector<std::string> carried;  // section XATT: glTF attributes and morph deltas carried unread
    for (uint32_t k = 0; k < m.extra_stream_count; ++k) carried.emplace_back(m.extra_streams[k].name);
    mj["carried_streams"] = carried;
    mj["bounds_min"] = {m.bounds_min[0], m.bounds_min[1], m.bounds_min[2]};
    mj["bounds_max"] = {m.bounds_max[0], m.bounds_max[1], m.bounds_max[2]};
    uint64_t bytes = 0;
    for (const tom::SectionInfo& s : file.sections())
        if (s.mesh == i) bytes += s.bytes;
    mj["bytes"] = bytes;
    mj["face_vertex_bytes"] = tools::face_vertex_bytes(m.vertex_count, m.triangle_count);
    mj["error_curve"] = curve_json(m);
    return mj;
}

// The file as tominfo --json prints it (docs/TOOLS.md).
nlohmann::ordered_json file_json(const tom::File& file, const std::string& path, bool sections) {
    nlohmann::ordered_json j;
    j["file"] = path;
    j["version"] = std::to_string(file.version_major()) + "." + std::to_string(file.version_minor());
    j["bytes"] = file.file_bytes();
    j["mesh_count"] = file.mesh_count();
    uint64_t total_fv = 0;
    j["meshes"] = nlohmann::json::array();
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        j["meshes"].push_back(mesh_json(file, i));
        total_fv += j["meshes"].back()["face_vertex_bytes"].get<uint64_t>();
    }
    const tom::Scene& scene = file.scene();
    j["materials"] = nlohmann::json::array();
    for (const tom::Material& m : scene.materials) {
        nlohmann::ordered_json mj = {{"name", m.name},
                                     {"base_color", m.base_color},
                                     {"metallic", m.metallic},
                                     {"roughness", m.roughness},
                                     {"alpha_mode", int(m.alpha_mode)},
                                     {"double_sided", m.double_sided}};
        mj["textures"] = nlohmann::json::array();
        for (const tom::TextureRef& t : m.textures)
            mj["textures"].push_back({{"role", tom::to_string(t.role)}, {"texcoord", t.texcoord}, {"uri", t.uri}, {"mime_type", t.mime_type}});
        j["materials"].push_back(mj);
    }
    j["instances"] = nlohmann::json::array();
    for (const tom::Instance& inst : scene.instances)
        j["instances"].push_back({{"mesh", inst.mesh}, {"node", inst.node}, {"name", inst.name}, {"transform", inst.transform}});
    // what made the file (PROV): tombuild's JSON, or the writer's text as a string
    if (file.provenance().empty()) {
        j["provenance"] = nullptr;
    } else {
        const std::string text(file.provenance());
        const nlohmann::ordered_json parsed = nlohmann::ordered_json::parse(text, nullptr, false);
        j["provenance"] = parsed.is_discarded() ? nlohmann::ordered_json(text) : parsed;
    }
    j["face_vertex_bytes"] = total_fv;
    j["percent_of_face_vertex"] = total_fv ? 100.0 * double(file.file_bytes()) / double(total_fv) : 0.0;
    if (sections) {
        j["sections"] = nlohmann::json::array();
        for (const tom::SectionInfo& s : file.sections())
            j["sections"].push_back({{"type", std::string(s.type)}, {"mesh", s.mesh == tom::SectionInfo::file_level ? nlohmann::json("file") : nlohmann::json(s.mesh)},
                                     {"offset", s.offset}, {"bytes", s.bytes}});
    }
    return j;
}

// The text view: the header line, a row per mesh, the parts, the scene and the provenance.
void print_summary(const tom::File& file, const std::string& path, const nlohmann::ordered_json& j) {
    const tom::Scene& scene = file.scene();
    std::printf("%s: TOM %s, %s, %u mesh%s, %.1f%% of face-vertex (positions+normals, 32-bit indices)\n", path.c_str(),
                j["version"].get<std::string>().c_str(), tools::human_bytes(file.file_bytes()).c_str(), file.mesh_count(),
                file.mesh_count() == 1 ? "" : "es", j["percent_of_face_vertex"].get<double>());
    std::printf("  %-4s %-32s %10s %10s %10s %10s %10s %5s %8s %8s %8s  %s\n", "#", "name", "vertices", "triangles", "min verts", "min tris",
                "floor tris", "index", "coarse", "k_mean", "k_max", "attributes");
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        const auto& mj = j["meshes"][i];
        std::string attrs;
        for (const auto& a : mj["attributes"]) attrs += (attrs.empty() ? "" : ",") + a.get<std::string>();
        for (const auto& a : mj["carried_streams"]) attrs += "," + a.get<std::string>();
        const bool has_curve = !mj["error_curve"].is_null();
        const bool has_coarse = !mj["coarse_corners"].is_null();
        const bool has_floor = !mj["usable_floor"].is_null();
        std::printf("  %-4u %-32.32s %10u %10u %10u %10u %10s %4ub %8s %8s %8s  %s\n", i, mj["name"].get<std::string>().c_str(), mj["vertices"].get<uint32_t>(),
                    mj["triangles"].get<uint32_t>(), mj["min_vertices"].get<uint32_t>(), mj["min_triangles"].get<uint32_t>(),
                    has_floor ? std::to_string(mj["usable_floor"]["triangles"].get<uint32_t>()).c_str() : "-",
                    8 * mj["index_bytes"].get<uint32_t>(),
                    has_coarse ? std::to_string(mj["coarse_corners"]["resolution"].get<uint32_t>()).c_str() : "-",
                    has_curve ? std::to_string(mj["error_curve"]["k_mean"].get<double>()).substr(0, 7).c_str() : "-",
                    has_curve ? std::to_string(mj["error_curve"]["k_max"].get<double>()).substr(0, 7).c_str() : "-", attrs.c_str());
    }
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        const auto& mj = j["meshes"][i];
        if (!mj.contains("parts")) continue;
        std::printf("  mesh %u: %zu parts\n", i, mj["parts"].size());
        for (size_t p = 0; p < mj["parts"].size(); ++p) {
            const auto& pj = mj["parts"][p];
            std::printf("    part %zu: material %d%s%s%s, %u triangles (%u at the coarsest)\n", p, pj["material"].get<int>(),
                        pj["material_name"].is_null() ? "" : " '", pj["material_name"].is_null() ? "" : pj["material_name"].get<std::string>().c_str(),
                        pj["material_name"].is_null() ? "" : "'", pj["triangles"].get<uint32_t>(), pj["min_triangles"].get<uint32_t>());
        }
    }
    std::printf("  scene: %zu material%s, %zu instance%s%s\n", scene.materials.size(), scene.materials.size() == 1 ? "" : "s",
                scene.instances.size(), scene.instances.size() == 1 ? "" : "s",
                scene.instances.empty() ? " (each mesh is drawn once, untransformed)" : "");
    if (const auto& pj = j["provenance"]; pj.is_object() && pj.contains("input")) {
        std::string sources;
        for (const auto& src : pj.value("sources", nlohmann::ordered_json::array())) sources += ", " + src.value("file", std::string("?"));
        std::printf("  made by %s from %s bytes (%s)%s%s\n", pj.value("tool", std::string("?")).c_str(),
                    std::to_string(pj["input"].value("bytes", uint64_t(0))).c_str(), pj["input"].value("digest", std::string("?")).c_str(),
                    sources.empty() ? "" : " with", sources.empty() ? "" : sources.c_str() + 1);
    } else if (pj.is_string()) {
        std::printf("  provenance: %s\n", pj.get<std::string>().c_str());
    }
}

// --scene: the materials with their textures, the instances.
void print_scene(const tom::File& file) {
    const tom::Scene& scene = file.scene();
    for (size_t i = 0; i < scene.materials.size(); ++i) {
        const tom::Material& m = scene.materials[i];
        std::printf("    material %zu '%s': base colour %.3g %.3g %.3g %.3g, metallic %.3g, roughness %.3g%s%s\n", i, m.name.c_str(), m.base_color[0],
                    m.base_color[1], m.base_color[2], m.base_color[3], m.metallic, m.roughness, m.double_sided ? ", double-sided" : "",
                    m.alpha_mode == tom::AlphaMode::blend ? ", blend" : m.alpha_mode == tom::AlphaMode::mask ? ", mask" : "");
        for (const tom::TextureRef& t : m.textures)
            std::printf("      %s texture (TEXCOORD_%u): %s\n", tom::to_string(t.role), t.texcoord,
                        t.uri.empty() ? ("embedded " + t.mime_type).c_str() : t.uri.c_str());
    }
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        const tom::Instance& inst = scene.instances[i];
        std::printf("    instance %zu: mesh %u '%.*s' at node %u '%s', translation %.4g %.4g %.4g\n", i, inst.mesh,
                    int(file.mesh(inst.mesh).name.size()), file.mesh(inst.mesh).name.data(), inst.node, inst.name.c_str(), inst.transform[12],
                    inst.transform[13], inst.transform[14]);
    }
}

// --curve: each mesh's stored error curve.
void print_curves(const tom::File& file, const nlohmann::ordered_json& j) {
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        const auto& cj = j["meshes"][i]["error_curve"];
        if (cj.is_null()) {
            std::printf("  mesh %u: no error curve stored\n", i);
            continue;
        }
        std::printf("  mesh %u error curve (%% of the diagonal %.6g): k_mean %.4g, k_max %.4g (D = k/N, N triangles)\n", i, cj["diagonal"].get<double>(),
                    cj["k_mean"].get<double>(), cj["k_max"].get<double>());
        std::printf("    %10s %10s %10s %10s\n", "vertices", "triangles", "mean %", "max %");
        for (const auto& p : cj["points"])
            std::printf("    %10u %10u %10.5f %10.4f\n", p["vertices"].get<uint32_t>(), p["triangles"].get<uint32_t>(), p["mean_percent"].get<double>(),
                        p["max_percent"].get<double>());
    }
}

// --sections: the section table.
void print_sections(const tom::File& file) {
    std::printf("  sections:\n");
    for (const tom::SectionInfo& s : file.sections())
        std::printf("    %-4s mesh %-4s offset %10llu  %12llu bytes  crc %08x\n", s.type,
                    s.mesh == tom::SectionInfo::file_level ? "file" : std::to_string(s.mesh).c_str(), static_cast<unsigned long long>(s.offset),
                    static_cast<unsigned long long>(s.bytes), s.checksum);
}

// A streamed file's chunks (docs/FORMAT.md, "Streamed files"), in file order, and its meshes'
// quantization.
nlohmann::ordered_json stream_json(const tom::StreamDecoder& d) {
    nlohmann::ordered_json j;
    j["file_bytes"] = d.file_bytes();
    j["chunks"] = nlohmann::ordered_json::array();
    for (const tom::StreamChunk& c : d.chunks())
        j["chunks"].push_back({{"end_byte", c.end_byte}, {"mesh", c.mesh}, {"vertices", c.vertex_end}, {"triangles", c.triangles}});
    const tom::StreamDeferred& deferred = d.deferred();
    j["deferred"] = {{"after_chunk", deferred.after_chunk}, {"begin_byte", deferred.begin_byte}, {"end_byte", deferred.end_byte}};
    j["quantization"] = nlohmann::ordered_json::array();
    for (uint32_t m = 0; m < d.mesh_count(); ++m) {
        const tom::StreamQuantization& q = d.quantization(m);
        j["quantization"].push_back({{"position_bits", q.position_bits}, {"position_step", q.position_step}, {"normal_bits", q.normal_bits}, {"texcoord_bits", q.texcoord_bits}});
    }
    return j;
}

void print_stream(const nlohmann::ordered_json& s) {
    const auto& chunks = s["chunks"];
    const double bytes = s["file_bytes"].get<double>();
    std::printf("  streamed: %zu chunks, %.0f bytes; the first ends at byte %llu (%.1f%%)\n", chunks.size(), bytes,
                static_cast<unsigned long long>(chunks[0]["end_byte"].get<uint64_t>()), 100.0 * chunks[0]["end_byte"].get<double>() / bytes);
    const auto& deferred = s["deferred"];
    if (deferred["end_byte"] != deferred["begin_byte"])
        std::printf("  deferred (provenance, images, source glTF): bytes %llu to %llu, after chunk %zu\n",
                    static_cast<unsigned long long>(deferred["begin_byte"].get<uint64_t>()),
                    static_cast<unsigned long long>(deferred["end_byte"].get<uint64_t>()), deferred["after_chunk"].get<size_t>());
    for (size_t m = 0; m < s["quantization"].size(); ++m) {
        const auto& q = s["quantization"][m];
        std::printf("  mesh %zu quantized: positions %u bits (step %.4g), normals %u bits, texture coordinates %u bits\n", m, q["position_bits"].get<uint32_t>(),
                    q["position_step"].get<double>(), q["normal_bits"].get<uint32_t>(), q["texcoord_bits"].get<uint32_t>());
    }
}

} // namespace

int main(int argc, char** argv) {
    Options o;
    if (const int code = parse_options(o, argc, argv); code >= 0) return code;
    try {
        tom::OpenOptions oo;
        oo.verify_checksums = !o.no_verify;
        std::optional<tom::StreamDecoder> stream;
        if (tom::is_stream_file(o.path)) stream.emplace(tom::read_stream(o.path));
        const tom::File file = stream ? stream->file() : tom::File::open(o.path, oo);
        nlohmann::ordered_json j = file_json(file, o.path, o.sections || o.json);
        if (stream) j["stream"] = stream_json(*stream);
        if (o.json) {
            std::printf("%s\n", j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
            return tools::exit_ok;
        }
        print_summary(file, o.path, j);
        if (stream) print_stream(j["stream"]);
        if (o.show_scene) print_scene(file);
        if (o.show_curve) print_curves(file, j);
        if (o.sections) print_sections(file);
        return tools::exit_ok;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}
