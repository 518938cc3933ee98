// The C API (tom/tom.h) over the C++ libraries: every entry point catches what the C++ side
// throws and turns it into a tom_status and this thread's message.

#include "tom/tom.h"

#include "capi_common.h"

#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "tom/builder/builder.h"
#include "tom/builder/mesh.h"
#include "tom/builder/writer.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/scene.h"
#include "tom/stream.h"

#ifndef TOM_VERSION_STRING
#define TOM_VERSION_STRING "0.0.0"
#endif

// A file and the C forms of its scene, made once at open so that lookups allocate nothing.
struct tom_file {
    explicit tom_file(tom::File f) : file(std::move(f)) {}
    tom::File file;
    std::vector<std::vector<tom_texture>> textures;  // per material
    std::vector<tom::Instance> draw;                 // tom::draw_list
};

// A stream decoder with the caller's codecs, which the runtime's decoder reaches through
// `codecs` (their address is the runtime codecs' context: the object never moves).
struct tom_stream {
    tom_stream_codecs codecs{};
    std::unique_ptr<tom::StreamDecoder> decoder;
};

namespace tom::capi {

thread_local std::string last_error;

tom_status fail(tom_status status, const std::string& message) {
    last_error = message;
    return status;
}

tom_status null_argument(const char* function, const char* argument) {
    return fail(TOM_ERROR_ARGUMENT, std::string(function) + ": " + argument + " is NULL");
}

} // namespace tom::capi

namespace {

using namespace tom::capi;

tom_file* make_file(tom::File f) {
    auto* out = new tom_file(std::move(f));
    const tom::Scene& scene = out->file.scene();
    for (const tom::Material& m : scene.materials) {
        std::vector<tom_texture> c;
        for (const tom::TextureRef& t : m.textures) c.push_back({uint32_t(t.role), t.texcoord, t.uri.c_str(), t.mime_type.c_str()});
        out->textures.push_back(std::move(c));
    }
    out->draw = tom::draw_list(scene, out->file.mesh_count());
    return out;
}

template <class Index>
tom_status extract_into(const char* function, const tom_mesh_view* mesh, uint32_t vertex_count, Index* out, size_t capacity, tom_extracted* result,
                        tom_part_draw* draws = nullptr, size_t draw_capacity = 0, bool with_draws = false) {
    const tom::MeshView* v = view_of(mesh);
    if (!v) return null_argument(function, "mesh");
    if (!out && capacity > 0) return null_argument(function, "out");
    if (!result) return null_argument(function, "result");
    if (with_draws && !draws) return null_argument(function, "draws");
    if (with_draws && draw_capacity < tom::part_count(*v))
        return fail(TOM_ERROR_CAPACITY, std::string(function) + ": the mesh has " + std::to_string(tom::part_count(*v)) + " parts, the draw array holds " +
                                            std::to_string(draw_capacity));
    // a buffer of 3 T always suffices; a smaller one must hold this level's triangles
    if (capacity / 3 < v->triangle_count) {
        const uint32_t needed = tom::active_triangle_count(*v, vertex_count);
        if (capacity / 3 < needed)
            return fail(TOM_ERROR_CAPACITY, std::string(function) + ": the level has " + std::to_string(needed) + " triangles (" + std::to_string(3 * uint64_t(needed)) +
                                                " indices), the buffer holds " + std::to_string(capacity) + " indices");
    }
    if (sizeof(Index) == 2) {
        const uint32_t n = std::min(std::max(vertex_count, v->min_vertex_count), v->vertex_count);
        if (n > 65536) return fail(TOM_ERROR_ARGUMENT, std::string(function) + ": resolution " + std::to_string(n) + " has more vertices than 16-bit indices address");
    }
    const tom::Extracted e = tom::extract(*v, vertex_count, out, capacity);
    // extract() wrote the parts one after another, whole (the capacity was checked above): each
    // draw is its part's live count after the previous ones, with nothing allocated
    uint32_t first = 0;
    for (uint32_t p = 0; with_draws && p < tom::part_count(*v); ++p) {
        const uint32_t count = 3 * tom::active_part_triangle_count(*v, p, e.vertex_count);
        draws[p] = {first, count, tom::part_at(*v, p).material, 0};
        first += count;
    }
    result->vertex_count = e.vertex_count;
    result->triangle_count = e.triangle_count;
    return TOM_OK;
}

// A strided stream of `components` floats per vertex into a packed vector (empty for NULL).
tom_status gather(const float* data, size_t stride, uint32_t components, uint32_t vertices, std::vector<float>& out, const char* what) {
    if (!data) return TOM_OK;
    const size_t step = stride ? stride : components * sizeof(float);
    if (step < components * sizeof(float))
        return fail(TOM_ERROR_ARGUMENT, std::string("tom_build: the ") + what + " stride of " + std::to_string(stride) + " bytes is less than a vertex's " +
                                            std::to_string(components * sizeof(float)));
    out.resize(size_t(vertices) * components);
    const auto* bytes = reinterpret_cast<const unsigned char*>(data);
    for (uint32_t v = 0; v < vertices; ++v) std::memcpy(&out[size_t(v) * components], bytes + size_t(v) * step, components * sizeof(float));
    return TOM_OK;
}

tom_status to_mesh(const tom_build_mesh& in, uint32_t which, const tom::CleanOptions& clean, tom::Mesh& m) {
    const std::string where = "tom_build: mesh " + std::to_string(which);
    if (!in.positions) return fail(TOM_ERROR_ARGUMENT, where + ": positions is NULL");
    if (!in.indices && in.triangle_count > 0) return fail(TOM_ERROR_ARGUMENT, where + ": indices is NULL");
    if (in.index_size != 2 && in.index_size != 4) return fail(TOM_ERROR_ARGUMENT, where + ": index_size is " + std::to_string(in.index_size) + ", not 2 or 4");
    m.name = in.name ? in.name : "mesh" + std::to_string(which);
    m.material = in.material;
    const uint32_t n = in.vertex_count;
    tom_status s;
    if ((s = gather(in.positions, in.position_stride, 3, n, m.positions, "position")) != TOM_OK) return s;
    if ((s = gather(in.normals, in.normal_stride, 3, n, m.normals, "normal")) != TOM_OK) return s;
    if ((s = gather(in.texcoords, in.texcoord_stride, 2, n, m.texcoords, "texcoord")) != TOM_OK) return s;
    if ((s = gather(in.colors, in.color_stride, 4, n, m.colors, "color")) != TOM_OK) return s;
    if ((s = gather(in.texcoords1, in.texcoord1_stride, 2, n, m.texcoords1, "texcoord1")) != TOM_OK) return s;
    if ((s = gather(in.tangents, in.tangent_stride, 4, n, m.tangents, "tangent")) != TOM_OK) return s;
    m.indices.resize(size_t(in.triangle_count) * 3);
    for (size_t c = 0; c < m.indices.size(); ++c)
        m.indices[c] = in.index_size == 2 ? static_cast<const uint16_t*>(in.indices)[c] : static_cast<const uint32_t*>(in.indices)[c];
    if (in.part_count > 0 && !in.parts) return fail(TOM_ERROR_ARGUMENT, where + ": parts is NULL with part_count " + std::to_string(in.part_count));
    for (uint32_t p = 0; p < in.part_count; ++p)
        m.parts.push_back({in.parts[p].first_triangle, in.parts[p].triangle_count, in.parts[p].material, in.parts[p].attributes & tom::attribute_bits(m)});
    if (m.parts.size() == 1) m.material = m.parts[0].material, m.parts.clear();
    tom::clean_mesh(m, clean);  // throws MeshError naming the mesh for an index past its vertices or parts that do not tile
    return TOM_OK;
}

tom_status build_image(const tom_build_mesh* meshes, uint32_t mesh_count, const tom_build_params* params, std::vector<uint8_t>& image) {
    if (!meshes && mesh_count > 0) return null_argument("tom_build", "meshes");
    tom_build_params p;
    tom_build_params_default(&p);
    if (params) p = *params;
    if (p.predicate > 1 || p.strategy > 1) return fail(TOM_ERROR_ARGUMENT, "tom_build: predicate or strategy out of range");
    if (p.index_size != 0 && p.index_size != 16 && p.index_size != 32)
        return fail(TOM_ERROR_ARGUMENT, "tom_build: index_size is " + std::to_string(p.index_size) + ", not 0, 16 or 32");
    tom::BuildParams bp;
    bp.predicate = p.predicate == TOM_PREDICATE_MEMORYLESS ? tom::Predicate::memoryless : tom::Predicate::quadric;
    bp.strategy = p.strategy == TOM_STRATEGY_HEAP ? tom::Strategy::heap : tom::Strategy::passes;
    bp.pair_threshold = p.pair_threshold;
    bp.pass_fraction = p.pass_fraction;
    bp.attribute_weight = p.attribute_weight;
    bp.max_rotation_degrees = p.max_rotation_degrees;
    bp.threads = p.threads;
    bp.foresight = p.foresight != 0;
    bp.lock_borders = p.lock_borders != 0;
    bp.keep_topology = p.keep_topology != 0;
    bp.animation_weight = p.animation_weight;
    std::vector<tom::TomMesh> built;
    for (uint32_t i = 0; i < mesh_count; ++i) {
        tom::Mesh m;
        const tom_status s = to_mesh(meshes[i], i, tom::CleanOptions{p.weld != 0}, m);
        if (s != TOM_OK) return s;
        built.push_back(tom::build(m, bp));
    }
    tom::WriteOptions wo;
    wo.index_size = p.index_size == 16 ? tom::IndexSize::bits16 : p.index_size == 32 ? tom::IndexSize::bits32 : tom::IndexSize::automatic;
    image = tom::serialize(built, wo);
    return TOM_OK;
}

} // namespace

extern "C" {

const char* tom_last_error(void) { return tom::capi::last_error.c_str(); }

const char* tom_status_name(tom_status status) {
    switch (status) {
    case TOM_OK: return "TOM_OK";
    case TOM_ERROR_FORMAT: return "TOM_ERROR_FORMAT";
    case TOM_ERROR_IO: return "TOM_ERROR_IO";
    case TOM_ERROR_ARGUMENT: return "TOM_ERROR_ARGUMENT";
    case TOM_ERROR_MESH: return "TOM_ERROR_MESH";
    case TOM_ERROR_CAPACITY: return "TOM_ERROR_CAPACITY";
    case TOM_ERROR_MEMORY: return "TOM_ERROR_MEMORY";
    case TOM_ERROR_INTERNAL: return "TOM_ERROR_INTERNAL";
    case TOM_ERROR_PARSE: return "TOM_ERROR_PARSE";
    }
    return "TOM_ERROR_UNKNOWN";
}

const char* tom_version(void) { return TOM_VERSION_STRING; }
uint32_t tom_format_version_major(void) { return tom::format_version_major; }
uint32_t tom_format_version_minor(void) { return tom::format_version_minor; }

tom_status tom_file_open(const char* path, tom_file** out) {
    if (!path) return null_argument("tom_file_open", "path");
    if (!out) return null_argument("tom_file_open", "out");
    return guarded([&] {
        *out = make_file(tom::File::open(path));
        return TOM_OK;
    });
}

tom_status tom_file_open_memory(const void* bytes, size_t size, const char* name, tom_file** out) {
    if (!bytes && size > 0) return null_argument("tom_file_open_memory", "bytes");
    if (!out) return null_argument("tom_file_open_memory", "out");
    return guarded([&] {
        *out = make_file(tom::File::borrow(bytes, size, name ? name : "<memory>"));
        return TOM_OK;
    });
}

void tom_file_close(tom_file* file) { delete file; }

uint32_t tom_file_mesh_count(const tom_file* file) { return file ? file->file.mesh_count() : 0; }

const char* tom_file_provenance(const tom_file* file, size_t* bytes) {
    const std::string_view text = file ? file->file.provenance() : std::string_view();
    if (bytes) *bytes = text.size();
    return text.empty() ? nullptr : text.data();
}

tom_status tom_file_mesh(const tom_file* file, uint32_t index, tom_mesh_view* out) {
    if (!file) return null_argument("tom_file_mesh", "file");
    if (!out) return null_argument("tom_file_mesh", "out");
    if (index >= file->file.mesh_count())
        return fail(TOM_ERROR_ARGUMENT, "tom_file_mesh: mesh " + std::to_string(index) + " of a file with " + std::to_string(file->file.mesh_count()));
    const tom::MeshView& v = file->file.mesh(index);
    tom_mesh_view c{};
    c.name = v.name.data();
    c.name_length = v.name.size();
    c.vertex_count = v.vertex_count;
    c.triangle_count = v.triangle_count;
    c.min_vertex_count = v.min_vertex_count;
    c.usable_floor = tom::floor_vertex_count(v);
    c.index_size = v.index_size;
    c.material = v.material;
    c.positions = v.positions;
    c.normals = v.normals;
    c.texcoords = v.texcoords;
    c.colors = v.colors;
    c.texcoords1 = v.texcoords1;
    c.tangents = v.tangents;
    c.substitute = v.substitute;
    c.triangles = v.triangles;
    std::memcpy(c.bounds_min, v.bounds_min, sizeof c.bounds_min);
    std::memcpy(c.bounds_max, v.bounds_max, sizeof c.bounds_max);
    c.internal = &v;
    *out = c;
    return TOM_OK;
}

uint32_t tom_vertex_count_for_fraction(const tom_mesh_view* mesh, double fraction) {
    const tom::MeshView* v = view_of(mesh);
    return v ? tom::vertex_count_for_fraction(*v, fraction) : 0;
}

uint32_t tom_vertex_count_for_triangles(const tom_mesh_view* mesh, uint32_t triangle_count) {
    const tom::MeshView* v = view_of(mesh);
    return v ? tom::vertex_count_for_triangles(*v, triangle_count) : 0;
}

uint32_t tom_active_triangle_count(const tom_mesh_view* mesh, uint32_t vertex_count) {
    const tom::MeshView* v = view_of(mesh);
    return v ? tom::active_triangle_count(*v, vertex_count) : 0;
}

tom_status tom_extract_u32(const tom_mesh_view* mesh, uint32_t vertex_count, uint32_t* out, size_t capacity, tom_extracted* result) {
    return extract_into("tom_extract_u32", mesh, vertex_count, out, capacity, result);
}

tom_status tom_extract_u16(const tom_mesh_view* mesh, uint32_t vertex_count, uint16_t* out, size_t capacity, tom_extracted* result) {
    return extract_into("tom_extract_u16", mesh, vertex_count, out, capacity, result);
}

uint32_t tom_mesh_part_count(const tom_mesh_view* mesh) {
    const tom::MeshView* v = view_of(mesh);
    return v ? tom::part_count(*v) : 0;
}

tom_status tom_mesh_part(const tom_mesh_view* mesh, uint32_t index, tom_part* out) {
    const tom::MeshView* v = view_of(mesh);
    if (!v) return null_argument("tom_mesh_part", "mesh");
    if (!out) return null_argument("tom_mesh_part", "out");
    if (index >= tom::part_count(*v))
        return fail(TOM_ERROR_ARGUMENT, "tom_mesh_part: part " + std::to_string(index) + " of " + std::to_string(tom::part_count(*v)));
    const tom::Part p = tom::part_at(*v, index);
    *out = {p.first_triangle, p.triangle_count, p.material, p.attributes};
    return TOM_OK;
}

tom_status tom_extract_parts_u32(const tom_mesh_view* mesh, uint32_t vertex_count, uint32_t* out, size_t capacity, tom_part_draw* draws, size_t draw_capacity,
                                 tom_extracted* result) {
    return extract_into("tom_extract_parts_u32", mesh, vertex_count, out, capacity, result, draws, draw_capacity, true);
}

tom_status tom_extract_parts_u16(const tom_mesh_view* mesh, uint32_t vertex_count, uint16_t* out, size_t capacity, tom_part_draw* draws, size_t draw_capacity,
                                 tom_extracted* result) {
    return extract_into("tom_extract_parts_u16", mesh, vertex_count, out, capacity, result, draws, draw_capacity, true);
}

tom_status tom_geomorph(const tom_mesh_view* mesh, uint32_t n, float a, tom_morphed_vertex* out) {
    const tom::MeshView* v = view_of(mesh);
    if (!v) return null_argument("tom_geomorph", "mesh");
    if (!out) return null_argument("tom_geomorph", "out");
    if (n < v->min_vertex_count || n >= v->vertex_count)
        return fail(TOM_ERROR_ARGUMENT, "tom_geomorph: n = " + std::to_string(n) + " is outside [" + std::to_string(v->min_vertex_count) + ", " + std::to_string(v->vertex_count) + ")");
    const tom::MorphedVertex m = tom::geomorph(*v, n, a);
    out->index = m.index;
    std::memcpy(out->position, m.position, sizeof out->position);
    std::memcpy(out->normal, m.normal, sizeof out->normal);
    std::memcpy(out->texcoord, m.texcoord, sizeof out->texcoord);
    std::memcpy(out->color, m.color, sizeof out->color);
    std::memcpy(out->texcoord1, m.texcoord1, sizeof out->texcoord1);
    std::memcpy(out->tangent, m.tangent, sizeof out->tangent);
    return TOM_OK;
}

uint32_t tom_file_material_count(const tom_file* file) { return file ? uint32_t(file->file.scene().materials.size()) : 0; }

tom_status tom_file_material(const tom_file* file, uint32_t index, tom_material* out) {
    if (!file) return null_argument("tom_file_material", "file");
    if (!out) return null_argument("tom_file_material", "out");
    const std::vector<tom::Material>& materials = file->file.scene().materials;
    if (index >= materials.size())
        return fail(TOM_ERROR_ARGUMENT, "tom_file_material: material " + std::to_string(index) + " of a file with " + std::to_string(materials.size()));
    const tom::Material& m = materials[index];
    tom_material c{};
    c.name = m.name.c_str();
    std::memcpy(c.base_color, m.base_color, sizeof c.base_color);
    c.metallic = m.metallic;
    c.roughness = m.roughness;
    std::memcpy(c.emissive, m.emissive, sizeof c.emissive);
    c.alpha_mode = uint32_t(m.alpha_mode);
    c.alpha_cutoff = m.alpha_cutoff;
    c.double_sided = m.double_sided ? 1 : 0;
    c.textures = file->textures[index].empty() ? nullptr : file->textures[index].data();
    c.texture_count = uint32_t(file->textures[index].size());
    *out = c;
    return TOM_OK;
}

uint32_t tom_mesh_carried_stream_count(const tom_mesh_view* mesh) {
    const tom::MeshView* v = view_of(mesh);
    return v ? v->extra_stream_count : 0;
}

tom_status tom_mesh_carried_stream(const tom_mesh_view* mesh, uint32_t index, tom_carried_stream* out) {
    const tom::MeshView* v = view_of(mesh);
    if (!v) return null_argument("tom_mesh_carried_stream", "mesh");
    if (!out) return null_argument("tom_mesh_carried_stream", "out");
    if (index >= v->extra_stream_count)
        return fail(TOM_ERROR_ARGUMENT, "tom_mesh_carried_stream: stream " + std::to_string(index) + " of a mesh with " + std::to_string(v->extra_stream_count));
    const tom::VertexStreamView& x = v->extra_streams[index];
    *out = {x.name.data(), uint32_t(x.name.size()), x.component_type, x.components, x.normalized ? 1u : 0u, x.data};
    return TOM_OK;
}

uint32_t tom_file_image_count(const tom_file* file) { return file ? uint32_t(file->file.scene().images.size()) : 0; }

tom_status tom_file_image(const tom_file* file, uint32_t index, tom_image* out) {
    if (!file) return null_argument("tom_file_image", "file");
    if (!out) return null_argument("tom_file_image", "out");
    const std::vector<tom::Image>& images = file->file.scene().images;
    if (index >= images.size())
        return fail(TOM_ERROR_ARGUMENT, "tom_file_image: image " + std::to_string(index) + " of a file with " + std::to_string(images.size()));
    const tom::Image& image = images[index];
    *out = {image.name.c_str(), image.mime_type.c_str(), image.data, image.bytes};
    return TOM_OK;
}

tom_status tom_file_texture_image(const tom_file* file, uint32_t material, uint32_t texture, int32_t* image) {
    if (!file) return null_argument("tom_file_texture_image", "file");
    if (!image) return null_argument("tom_file_texture_image", "image");
    const std::vector<tom::Material>& materials = file->file.scene().materials;
    if (material >= materials.size() || texture >= materials[material].textures.size())
        return fail(TOM_ERROR_ARGUMENT, "tom_file_texture_image: texture " + std::to_string(texture) + " of material " + std::to_string(material) +
                                            " is not stored (" + std::to_string(materials.size()) + " materials)");
    *image = materials[material].textures[texture].image;
    return TOM_OK;
}

uint32_t tom_file_instance_count(const tom_file* file) { return file ? uint32_t(file->draw.size()) : 0; }

tom_status tom_file_instance(const tom_file* file, uint32_t index, tom_instance* out) {
    if (!file) return null_argument("tom_file_instance", "file");
    if (!out) return null_argument("tom_file_instance", "out");
    if (index >= file->draw.size())
        return fail(TOM_ERROR_ARGUMENT, "tom_file_instance: instance " + std::to_string(index) + " of " + std::to_string(file->draw.size()));
    const tom::Instance& i = file->draw[index];
    out->mesh = i.mesh;
    out->node = i.node;
    out->name = i.name.c_str();
    std::memcpy(out->transform, i.transform, sizeof out->transform);
    return TOM_OK;
}

void tom_build_params_default(tom_build_params* params) {
    if (!params) return;
    const tom::BuildParams d;
    params->predicate = TOM_PREDICATE_QUADRIC;
    params->strategy = TOM_STRATEGY_PASSES;
    params->pair_threshold = d.pair_threshold;
    params->pass_fraction = d.pass_fraction;
    params->attribute_weight = d.attribute_weight;
    params->max_rotation_degrees = d.max_rotation_degrees;
    params->threads = d.threads;
    params->foresight = d.foresight ? 1 : 0;
    params->index_size = 0;
    params->lock_borders = d.lock_borders ? 1 : 0;
    params->keep_topology = d.keep_topology ? 1 : 0;
    params->animation_weight = d.animation_weight;
    params->weld = tom::CleanOptions{}.weld ? 1 : 0;
}

tom_status tom_build_memory(const tom_build_mesh* meshes, uint32_t mesh_count, const tom_build_params* params, const tom_allocator* allocator, void** out_bytes,
                            size_t* out_size) {
    if (!out_bytes) return null_argument("tom_build_memory", "out_bytes");
    if (!out_size) return null_argument("tom_build_memory", "out_size");
    return guarded([&] {
        std::vector<uint8_t> image;
        const tom_status s = build_image(meshes, mesh_count, params, image);
        if (s != TOM_OK) return s;
        void* bytes = allocator && allocator->allocate ? allocator->allocate(allocator->user, image.size()) : std::malloc(image.size());
        if (!bytes) return fail(TOM_ERROR_MEMORY, "tom_build_memory: the allocator gave no block of " + std::to_string(image.size()) + " bytes");
        std::memcpy(bytes, image.data(), image.size());
        *out_bytes = bytes;
        *out_size = image.size();
        return TOM_OK;
    });
}

tom_status tom_build_file(const tom_build_mesh* meshes, uint32_t mesh_count, const tom_build_params* params, const char* path) {
    if (!path) return null_argument("tom_build_file", "path");
    return guarded([&] {
        std::vector<uint8_t> image;
        const tom_status s = build_image(meshes, mesh_count, params, image);
        if (s != TOM_OK) return s;
        tom::write_bytes_atomically(path, image.data(), image.size());
        return TOM_OK;
    });
}

} // extern "C"

namespace {

// The runtime's codecs calling the caller's C ones (0 is success in C, as in meshoptimizer).
bool stream_vertices(void* context, void* out, size_t count, size_t size, const uint8_t* in, size_t in_bytes) {
    const tom_stream_codecs& c = *static_cast<const tom_stream_codecs*>(context);
    return c.decode_vertices(c.context, out, count, size, in, in_bytes) == 0;
}
bool stream_indices(void* context, uint32_t* out, size_t index_count, const uint8_t* in, size_t in_bytes) {
    const tom_stream_codecs& c = *static_cast<const tom_stream_codecs*>(context);
    return c.decode_indices(c.context, out, index_count, in, in_bytes) == 0;
}

} // namespace

extern "C" {

tom_status tom_stream_create(const tom_stream_codecs* codecs, const char* name, tom_stream** out) {
    if (!codecs || !codecs->decode_vertices || !codecs->decode_indices) return null_argument("tom_stream_create", "codecs (or one of its decoders)");
    if (!out) return null_argument("tom_stream_create", "out");
    return guarded([&] {
        auto s = std::make_unique<tom_stream>();
        s->codecs = *codecs;
        tom::StreamCodecs runtime;
        runtime.decode_vertices = stream_vertices, runtime.decode_indices = stream_indices, runtime.context = &s->codecs;
        s->decoder = std::make_unique<tom::StreamDecoder>(runtime, name ? name : "<stream>");
        *out = s.release();
        return TOM_OK;
    });
}

tom_status tom_stream_append(tom_stream* stream, const void* bytes, size_t size) {
    if (!stream) return null_argument("tom_stream_append", "stream");
    if (!bytes && size > 0) return null_argument("tom_stream_append", "bytes");
    return guarded([&] {
        stream->decoder->append(bytes, size);
        return TOM_OK;
    });
}

uint64_t tom_stream_next_boundary(const tom_stream* stream) { return stream ? stream->decoder->next_boundary() : 0; }
uint64_t tom_stream_bytes_received(const tom_stream* stream) { return stream ? stream->decoder->bytes_received() : 0; }
uint64_t tom_stream_file_bytes(const tom_stream* stream) { return stream ? stream->decoder->file_bytes() : 0; }
int tom_stream_has_directory(const tom_stream* stream) { return stream && stream->decoder->has_directory() ? 1 : 0; }
size_t tom_stream_chunk_count(const tom_stream* stream) { return stream ? stream->decoder->chunks().size() : 0; }
size_t tom_stream_decoded_chunks(const tom_stream* stream) { return stream ? stream->decoder->decoded_chunks() : 0; }
int tom_stream_complete(const tom_stream* stream) { return stream && stream->decoder->complete() ? 1 : 0; }

tom_status tom_stream_chunk_at(const tom_stream* stream, size_t index, tom_stream_chunk* out) {
    if (!stream) return null_argument("tom_stream_chunk_at", "stream");
    if (!out) return null_argument("tom_stream_chunk_at", "out");
    const std::vector<tom::StreamChunk>& chunks = stream->decoder->chunks();
    if (index >= chunks.size())
        return fail(TOM_ERROR_ARGUMENT, "tom_stream_chunk_at: chunk " + std::to_string(index) + " of " + std::to_string(chunks.size()) +
                                            (stream->decoder->has_directory() ? "" : " (the directory is not in)"));
    const tom::StreamChunk& c = chunks[index];
    *out = tom_stream_chunk{c.mesh, c.vertex_begin, c.vertex_end, c.triangles, c.begin_byte, c.end_byte};
    return TOM_OK;
}

tom_status tom_stream_snapshot(const tom_stream* stream, tom_file** out) {
    if (!stream) return null_argument("tom_stream_snapshot", "stream");
    if (!out) return null_argument("tom_stream_snapshot", "out");
    return guarded([&] {
        *out = make_file(stream->decoder->file());
        return TOM_OK;
    });
}

void tom_stream_destroy(tom_stream* stream) { delete stream; }

} // extern "C"
