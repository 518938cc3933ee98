// The runtime's WebAssembly face (libtom/web/tom.mjs wraps it): a source takes a .tom's bytes as
// they arrive (streamed files chunk by chunk through tom::StreamDecoder, ordinary files whole),
// snapshots what it holds as a validated tom::File, and hands JavaScript the scene as JSON, the
// vertex streams as pointers into the wasm heap and index buffers extracted at any resolution.
//
// The meshopt codecs are JavaScript's: the decoders of the npm package `meshoptimizer`, set on
// the module as `Module.meshopt` before the first chunk (tom.mjs does it).
//
// Every function returns a status or a value and never throws into JavaScript: errors are kept
// on the source, tomw_error() gives the message (file, byte offset, field, rule).

#include <emscripten/emscripten.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tom/error_curve.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/stream.h"

// meshopt_decodeVertexBuffer and meshopt_decodeIndexBuffer of the npm decoder, on views of the heap
EM_JS(int, tomw_js_decode_vertices, (void* out, size_t count, size_t size, const uint8_t* src, size_t src_bytes), {
    try {
        Module.meshopt.decodeVertexBuffer(HEAPU8.subarray(out, out + count * size), count, size, HEAPU8.subarray(src, src + src_bytes));
        return 1;
    } catch (e) {
        return 0;
    }
});
EM_JS(int, tomw_js_decode_indices, (uint32_t* out, size_t index_count, const uint8_t* src, size_t src_bytes), {
    try {
        Module.meshopt.decodeIndexBuffer(HEAPU8.subarray(out, out + index_count * 4), index_count, 4, HEAPU8.subarray(src, src + src_bytes));
        return 1;
    } catch (e) {
        return 0;
    }
});

namespace {

bool decode_vertices(void*, void* out, size_t count, size_t size, const uint8_t* in, size_t in_bytes) {
    return tomw_js_decode_vertices(out, count, size, in, in_bytes) != 0;
}
bool decode_indices(void*, uint32_t* out, size_t index_count, const uint8_t* in, size_t in_bytes) {
    return tomw_js_decode_indices(out, index_count, in, in_bytes) != 0;
}

/// A string as a JSON string literal.
std::string quoted(std::string_view s) {
    std::string out = "\"";
    for (const char c : s) {
        if (c == '"' || c == '\\') out += '\\', out += c;
        else if (static_cast<unsigned char>(c) < 0x20) {
            char u[8];
            std::snprintf(u, sizeof u, "\\u%04x", c);
            out += u;
        } else out += c;
    }
    return out + "\"";
}

std::string number(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.9g", v);
    return b;
}

template <class T, class F>
std::string array(const std::vector<T>& items, F&& item) {
    std::string out = "[";
    for (size_t i = 0; i < items.size(); ++i) out += (i ? "," : "") + item(items[i]);
    return out + "]";
}

} // namespace

/// A .tom being received: a stream decoder, or the bytes of an ordinary file until they are all in.
struct tomw_source {
    std::string name;
    std::unique_ptr<tom::StreamDecoder> decoder;  // set once the magic says "stream"
    std::vector<uint8_t> whole;                   // an ordinary file's bytes
    std::optional<tom::File> file;                // the last snapshot
    std::string error, json;
    std::vector<uint32_t> indices;
    std::vector<tom::PartDraw> draws;
    uint32_t extracted_vertices = 0;

    template <class F>
    int guarded(F&& f) {
        try {
            f();
            return 1;
        } catch (const std::exception& e) {
            error = e.what();
            return 0;
        }
    }
};

extern "C" {

EMSCRIPTEN_KEEPALIVE tomw_source* tomw_new(const char* name) {
    auto* s = new tomw_source;
    s->name = name;
    return s;
}

EMSCRIPTEN_KEEPALIVE void tomw_delete(tomw_source* s) { delete s; }

EMSCRIPTEN_KEEPALIVE const char* tomw_error(const tomw_source* s) { return s->error.c_str(); }

/// Takes the next bytes; a stream decodes every chunk they complete. 1 on success, 0 on an error
/// (the source keeps what it decoded and takes no more bytes).
EMSCRIPTEN_KEEPALIVE int tomw_append(tomw_source* s, const uint8_t* bytes, size_t size) {
    return s->guarded([&] {
        if (!s->error.empty()) throw tom::ArgumentError(s->name + ": failed before; it takes no more bytes");
        if (!s->decoder && s->whole.size() < 8) {
            const size_t take = std::min(size, 8 - s->whole.size());
            s->whole.insert(s->whole.end(), bytes, bytes + take);
            bytes += take, size -= take;
            if (s->whole.size() == 8 && tom::is_stream(s->whole.data(), 8)) {
                s->decoder = std::make_unique<tom::StreamDecoder>(tom::StreamCodecs{decode_vertices, decode_indices}, s->name);
                s->decoder->append(s->whole.data(), 8);
                s->whole.clear();
            }
        }
        if (s->decoder) s->decoder->append(bytes, size);
        else s->whole.insert(s->whole.end(), bytes, bytes + size);
    });
}

EMSCRIPTEN_KEEPALIVE int tomw_is_stream(const tomw_source* s) { return s->decoder ? 1 : 0; }
EMSCRIPTEN_KEEPALIVE double tomw_bytes_received(const tomw_source* s) { return double(s->decoder ? s->decoder->bytes_received() : s->whole.size()); }
EMSCRIPTEN_KEEPALIVE int tomw_has_directory(const tomw_source* s) { return s->decoder && s->decoder->has_directory() ? 1 : 0; }
/// A stream's next boundary (tom::StreamDecoder::next_boundary); 0 for an ordinary file.
EMSCRIPTEN_KEEPALIVE double tomw_next_boundary(const tomw_source* s) { return s->decoder ? double(s->decoder->next_boundary()) : (s->whole.size() < 8 ? 8 : 0); }
EMSCRIPTEN_KEEPALIVE int tomw_decoded_chunks(const tomw_source* s) { return s->decoder ? int(s->decoder->decoded_chunks()) : 0; }
/// 1 when a stream is decoded whole: every chunk and the deferred block.
EMSCRIPTEN_KEEPALIVE int tomw_complete(const tomw_source* s) { return s->decoder && s->decoder->complete() ? 1 : 0; }
/// 1 when a stream's deferred block (its images, provenance, source glTF) is in.
EMSCRIPTEN_KEEPALIVE int tomw_deferred_received(const tomw_source* s) { return s->decoder && s->decoder->deferred_received() ? 1 : 0; }

/// A stream's directory: the declared size, each mesh's full-detail bounds as
/// [min x, y, z, max x, y, z], and its chunks in file order as
/// [mesh, vertex_begin, vertex_end, triangles, begin_byte, end_byte], and its deferred block as
/// [after_chunk, begin_byte, end_byte]. "null" before it is in.
EMSCRIPTEN_KEEPALIVE const char* tomw_directory_json(tomw_source* s) {
    s->json = "null";
    if (!s->decoder || !s->decoder->has_directory()) return s->json.c_str();
    const tom::StreamDecoder& d = *s->decoder;
    std::string bounds = "[";
    for (uint32_t m = 0; m < d.mesh_count(); ++m) {
        float lo[3], hi[3];
        d.declared_bounds(m, lo, hi);
        bounds += (m ? ",[" : "[") + number(lo[0]) + "," + number(lo[1]) + "," + number(lo[2]) + "," + number(hi[0]) + "," + number(hi[1]) + "," + number(hi[2]) + "]";
    }
    const tom::StreamDeferred& block = d.deferred();
    const std::string deferred = "[" + std::to_string(block.after_chunk) + "," + number(double(block.begin_byte)) + "," + number(double(block.end_byte)) + "]";
    const std::string chunks = array(d.chunks(), [](const tom::StreamChunk& c) {
        return "[" + std::to_string(c.mesh) + "," + std::to_string(c.vertex_begin) + "," + std::to_string(c.vertex_end) + "," + std::to_string(c.triangles) +
               "," + number(double(c.begin_byte)) + "," + number(double(c.end_byte)) + "]";
    });
    s->json = "{\"file_bytes\":" + number(double(d.file_bytes())) + ",\"bounds\":" + bounds + "],\"chunks\":" + chunks + ",\"deferred\":" + deferred + "}";
    return s->json.c_str();
}

/// Makes a validated File of what the source holds (a stream: what is decoded; an ordinary file:
/// all of it, which must be complete). 1 on success, 0 on an error.
EMSCRIPTEN_KEEPALIVE int tomw_snapshot(tomw_source* s) {
    return s->guarded([&] {
        s->file.reset();
        if (s->decoder) s->file = s->decoder->file();
        else s->file = tom::File::from_bytes(s->whole.data(), s->whole.size(), s->name);
    });
}

/// The snapshot's scene and meshes: materials, the draw list, images (MIME type and size; bytes
/// through tomw_image_data), per mesh its counts, streams, parts, bounds and error curve.
EMSCRIPTEN_KEEPALIVE const char* tomw_scene_json(tomw_source* s) {
    s->json = "null";
    if (!s->file) return s->json.c_str();
    const tom::File& f = *s->file;
    const tom::Scene& scene = f.scene();
    auto floats = [](const float* v, int n) {
        std::string out = "[";
        for (int i = 0; i < n; ++i) out += (i ? "," : "") + number(v[i]);
        return out + "]";
    };
    const std::string materials = array(scene.materials, [&](const tom::Material& m) {
        return "{\"name\":" + quoted(m.name) + ",\"base_color\":" + floats(m.base_color, 4) + ",\"metallic\":" + number(m.metallic) +
               ",\"roughness\":" + number(m.roughness) + ",\"emissive\":" + floats(m.emissive, 3) + ",\"alpha_mode\":" +
               std::to_string(uint32_t(m.alpha_mode)) + ",\"alpha_cutoff\":" + number(m.alpha_cutoff) + ",\"double_sided\":" +
               (m.double_sided ? "true" : "false") + ",\"textures\":" + array(m.textures, [](const tom::TextureRef& t) {
                   return "{\"role\":" + quoted(tom::to_string(t.role)) + ",\"texcoord\":" + std::to_string(t.texcoord) + ",\"uri\":" + quoted(t.uri) +
                          ",\"image\":" + std::to_string(t.image) + "}";
               }) +
               "}";
    });
    const std::string instances = array(tom::draw_list(scene, f.mesh_count()), [&](const tom::Instance& i) {
        return "{\"mesh\":" + std::to_string(i.mesh) + ",\"name\":" + quoted(i.name) + ",\"transform\":" + floats(i.transform, 16) + "}";
    });
    const std::string images = array(scene.images, [](const tom::Image& i) {
        return "{\"name\":" + quoted(i.name) + ",\"mime_type\":" + quoted(i.mime_type) + ",\"bytes\":" + number(double(i.bytes)) + "}";
    });
    std::string meshes = "[";
    for (uint32_t i = 0; i < f.mesh_count(); ++i) {
        const tom::MeshView& m = f.mesh(i);
        std::string parts = "[";
        for (uint32_t p = 0; p < tom::part_count(m); ++p) {
            const tom::Part part = tom::part_at(m, p);
            parts += (p ? ",{" : "{") + std::string("\"material\":") + std::to_string(part.material) + ",\"triangles\":" + std::to_string(part.triangle_count) + "}";
        }
        std::string curve = "null";
        if (const std::optional<tom::ErrorCurve> c = tom::read_error_curve(m))
            curve = "{\"diagonal\":" + number(c->diagonal) + ",\"k_mean\":" + number(c->k_mean) + ",\"points\":" +
                    array(c->points, [](const tom::ErrorCurvePoint& p) { return "[" + std::to_string(p.triangles) + "," + number(p.mean) + "," + number(p.max) + "]"; }) + "}";
        meshes += (i ? ",{" : "{") + std::string("\"name\":") + quoted(m.name) + ",\"vertices\":" + std::to_string(m.vertex_count) +
                  ",\"triangles\":" + std::to_string(m.triangle_count) + ",\"min_vertices\":" + std::to_string(m.min_vertex_count) +
                  ",\"floor\":" + std::to_string(m.vertex_count ? tom::floor_vertex_count(m) : 0) + ",\"normals\":" + (m.normals ? "true" : "false") +
                  ",\"texcoords\":" + (m.texcoords ? "true" : "false") + ",\"colors\":" + (m.colors ? "true" : "false") +
                  ",\"bounds_min\":" + floats(m.bounds_min, 3) + ",\"bounds_max\":" + floats(m.bounds_max, 3) + ",\"parts\":" + parts + "],\"curve\":" + curve + "}";
    }
    meshes += "]";
    s->json = "{\"materials\":" + materials + ",\"instances\":" + instances + ",\"images\":" + images + ",\"meshes\":" + meshes + "}";
    return s->json.c_str();
}

/// A vertex stream of the snapshot's mesh m: 0 positions (xyz), 1 normals (xyz), 2 texture
/// coordinates (uv), 3 colours (rgba); null when absent.
EMSCRIPTEN_KEEPALIVE const float* tomw_stream(const tomw_source* s, uint32_t m, int which) {
    if (!s->file || m >= s->file->mesh_count()) return nullptr;
    const tom::MeshView& v = s->file->mesh(m);
    const float* streams[4] = {v.positions, v.normals, v.texcoords, v.colors};
    return which >= 0 && which < 4 ? streams[which] : nullptr;
}

EMSCRIPTEN_KEEPALIVE const uint8_t* tomw_image_data(const tomw_source* s, uint32_t i) {
    return s->file && i < s->file->scene().images.size() ? s->file->scene().images[i].data : nullptr;
}

/// The resolution of mesh m with at least `triangles` live triangles (never below its usable floor).
EMSCRIPTEN_KEEPALIVE uint32_t tomw_vertex_count_for_triangles(const tomw_source* s, uint32_t m, uint32_t triangles) {
    return s->file && m < s->file->mesh_count() ? tom::vertex_count_for_triangles(s->file->mesh(m), triangles) : 0;
}

/// Mesh m's estimated error at `triangles` in object units (its stored curve's relative error
/// times the diagonal): the mean distance, or with `use_max` the Hausdorff distance; -1 when it
/// stores no curve.
EMSCRIPTEN_KEEPALIVE double tomw_estimate_error(const tomw_source* s, uint32_t m, double triangles, int use_max) {
    if (!s->file || m >= s->file->mesh_count()) return -1;
    const std::optional<tom::ErrorCurve> curve = tom::read_error_curve(s->file->mesh(m));
    return curve ? tom::estimate_error(*curve, triangles, use_max != 0) * curve->diagonal : -1;
}

/// Extracts mesh m at resolution n into the source's index buffer (tomw_indices) and its parts'
/// draws (tomw_draws: per part first_index, index_count, material). Returns the triangles
/// written; the resolution drawn is tomw_extracted_vertices(). -1 without a snapshot.
EMSCRIPTEN_KEEPALIVE int tomw_extract(tomw_source* s, uint32_t m, uint32_t n) {
    if (!s->file || m >= s->file->mesh_count()) return -1;
    const tom::MeshView& v = s->file->mesh(m);
    s->indices.resize(size_t(v.triangle_count) * 3);
    s->draws.resize(tom::part_count(v));
    const tom::Extracted e = tom::extract_parts(v, n, s->indices.data(), s->indices.size(), s->draws.data());
    s->extracted_vertices = e.vertex_count;
    return int(e.triangle_count);
}
EMSCRIPTEN_KEEPALIVE uint32_t tomw_extracted_vertices(const tomw_source* s) { return s->extracted_vertices; }
EMSCRIPTEN_KEEPALIVE const uint32_t* tomw_indices(const tomw_source* s) { return s->indices.data(); }
EMSCRIPTEN_KEEPALIVE const tom::PartDraw* tomw_draws(const tomw_source* s) { return s->draws.data(); }

} // extern "C"
