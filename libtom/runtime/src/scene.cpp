// Scenes: the MATL and INST sections (docs/FORMAT.md) and the draw list.

#include <cmath>
#include <cstring>

#include "format_layout.h"
#include "scene_codec.h"
#include "tom/errors.h"

namespace tom {

using namespace layout;

const char* to_string(TextureRole role) noexcept {
    switch (role) {
    case TextureRole::base_color: return "baseColor";
    case TextureRole::metallic_roughness: return "metallicRoughness";
    case TextureRole::normal: return "normal";
    case TextureRole::occlusion: return "occlusion";
    case TextureRole::emissive: return "emissive";
    }
    return "unknown";
}

std::vector<Instance> draw_list(const Scene& scene, uint32_t mesh_count) {
    if (!scene.instances.empty()) return scene.instances;
    std::vector<Instance> all(mesh_count);
    for (uint32_t i = 0; i < mesh_count; ++i) all[i].mesh = all[i].node = i;
    return all;
}

void multiply_4x4(const float a[16], const float b[16], float out[16]) noexcept {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            float s = 0;
            for (int k = 0; k < 4; ++k) s += a[4 * k + r] * b[4 * c + k];
            out[4 * c + r] = s;
        }
}

namespace detail {

namespace {

constexpr uint32_t scene_header_bytes = 16, material_record_bytes = 64, texture_record_bytes = 24, instance_record_bytes = 80;
constexpr uint32_t image_record_bytes = 32, no_image = 0xFFFFFFFFu, stream_record_bytes = 40;

// Strings follow the fixed records; a record holds (offset from the section start, bytes).
class StringArea {
public:
    explicit StringArea(std::vector<uint8_t>& out) : out_(out) {}
    void put(uint8_t* slot, const std::string& s) {  // slot: the record's offset field, then bytes
        pending_.push_back({size_t(slot - out_.data()), s});
    }
    void finish() {
        for (const auto& [slot, s] : pending_) {
            store_u32(&out_[slot], uint32_t(out_.size()));
            store_u32(&out_[slot + 4], uint32_t(s.size()));
            out_.insert(out_.end(), s.begin(), s.end());
        }
        while (out_.size() % 4) out_.push_back(0);
    }
    // after finish(): a block of bytes at a multiple of 16 from the section start (which is
    // itself 16-aligned in the file), its (u64 offset, u64 bytes) stored at `slot`
    void put_block(size_t slot, const uint8_t* data, uint64_t bytes) {
        while (out_.size() % 16) out_.push_back(0);
        store_u64(&out_[slot], uint64_t(out_.size()));
        store_u64(&out_[slot + 8], bytes);
        if (bytes) out_.insert(out_.end(), data, data + bytes);
    }

private:
    std::vector<uint8_t>& out_;
    std::vector<std::pair<size_t, std::string>> pending_;
};

// Reading side: every range is checked before a byte of it is used.
struct SectionReader {
    const uint8_t* data;
    uint64_t bytes, offset;
    const std::string& path;
    const char* type;
    int rule;

    [[noreturn]] void fail(uint64_t at, const std::string& field, const std::string& detail) const {
        throw FormatError(path, offset + at, std::string(type) + " " + field, rule, detail);
    }
    void need(uint64_t at, uint64_t n, const std::string& field) const {
        if (at > bytes || n > bytes - at) fail(std::min(at, bytes), field, "runs past the end of the section (" + std::to_string(bytes) + " bytes)");
    }
    std::string string_at(uint64_t record, uint64_t records_end, const std::string& field) const {
        const uint64_t at = load_u32(data + record), n = load_u32(data + record + 4);
        if (at < records_end || at > bytes || n > bytes - at)
            fail(record, field, "string of " + std::to_string(n) + " bytes at " + std::to_string(at) + " is not in the string area");
        return std::string(reinterpret_cast<const char*>(data + at), size_t(n));
    }
    float finite(uint64_t at, const std::string& field) const {
        const float f = load_f32(data + at);
        if (!std::isfinite(f)) fail(at, field, "is not finite");
        return f;
    }
};

} // namespace

std::vector<uint8_t> encode_materials(const std::vector<Material>& materials) {
    uint32_t textures = 0;
    for (const Material& m : materials) textures += uint32_t(m.textures.size());
    std::vector<uint8_t> out(scene_header_bytes + material_record_bytes * materials.size() + texture_record_bytes * size_t(textures), 0);
    store_u32(&out[0], uint32_t(materials.size()));
    store_u32(&out[4], textures);
    StringArea strings(out);
    uint32_t next_texture = 0;
    for (size_t i = 0; i < materials.size(); ++i) {
        const Material& m = materials[i];
        uint8_t* r = &out[scene_header_bytes + material_record_bytes * i];
        for (int k = 0; k < 4; ++k) store_f32(r + 4 * k, m.base_color[k]);
        store_f32(r + 16, m.metallic);
        store_f32(r + 20, m.roughness);
        for (int k = 0; k < 3; ++k) store_f32(r + 24 + 4 * k, m.emissive[k]);
        store_u32(r + 36, uint32_t(m.alpha_mode));
        store_f32(r + 40, m.alpha_cutoff);
        store_u32(r + 44, m.double_sided ? 1u : 0u);
        strings.put(r + 48, m.name);
        store_u32(r + 56, next_texture);
        store_u32(r + 60, uint32_t(m.textures.size()));
        for (const TextureRef& t : m.textures) {
            uint8_t* q = &out[scene_header_bytes + material_record_bytes * materials.size() + texture_record_bytes * size_t(next_texture++)];
            store_u32(q, uint32_t(t.role));
            store_u32(q + 4, t.texcoord);
            strings.put(q + 8, t.uri);
            strings.put(q + 16, t.mime_type);
        }
    }
    strings.finish();
    return out;
}

std::vector<uint8_t> encode_instances(const std::vector<Instance>& instances) {
    std::vector<uint8_t> out(scene_header_bytes + instance_record_bytes * instances.size(), 0);
    store_u32(&out[0], uint32_t(instances.size()));
    StringArea strings(out);
    for (size_t i = 0; i < instances.size(); ++i) {
        const Instance& inst = instances[i];
        uint8_t* r = &out[scene_header_bytes + instance_record_bytes * i];
        store_u32(r, inst.mesh);
        store_u32(r + 4, inst.node);
        strings.put(r + 8, inst.name);
        for (int k = 0; k < 16; ++k) store_f32(r + 16 + 4 * k, inst.transform[k]);
    }
    strings.finish();
    return out;
}

std::vector<uint8_t> encode_images(const Scene& scene) {
    if (scene.images.empty()) return {};
    uint32_t textures = 0;
    for (const Material& m : scene.materials) textures += uint32_t(m.textures.size());
    const size_t records = scene_header_bytes + 4 * size_t(textures);
    std::vector<uint8_t> out(records + image_record_bytes * scene.images.size(), 0);
    store_u32(&out[0], uint32_t(scene.images.size()));
    store_u32(&out[4], textures);
    size_t at = scene_header_bytes;
    for (const Material& m : scene.materials)
        for (const TextureRef& t : m.textures) {
            store_u32(&out[at], t.image < 0 ? no_image : uint32_t(t.image));
            at += 4;
        }
    StringArea strings(out);
    for (size_t i = 0; i < scene.images.size(); ++i) {
        strings.put(&out[records + image_record_bytes * i + 16], scene.images[i].mime_type);
        strings.put(&out[records + image_record_bytes * i + 24], scene.images[i].name);
    }
    strings.finish();
    for (size_t i = 0; i < scene.images.size(); ++i) strings.put_block(records + image_record_bytes * i, scene.images[i].data, scene.images[i].bytes);
    return out;
}

std::vector<uint8_t> encode_extra_streams(const std::vector<VertexStreamView>& streams, uint32_t vertex_count) {
    std::vector<uint8_t> out(scene_header_bytes + stream_record_bytes * streams.size(), 0);
    store_u32(&out[0], uint32_t(streams.size()));
    StringArea strings(out);
    for (size_t k = 0; k < streams.size(); ++k) {
        uint8_t* r = &out[scene_header_bytes + stream_record_bytes * k];
        strings.put(r, std::string(streams[k].name));
        store_u32(r + 8, streams[k].component_type);
        store_u32(r + 12, streams[k].components);
        store_u32(r + 16, streams[k].normalized ? 1u : 0u);
    }
    strings.finish();
    for (size_t k = 0; k < streams.size(); ++k) {
        const uint64_t bytes = uint64_t(vertex_count) * streams[k].components * component_bytes(streams[k].component_type);
        strings.put_block(scene_header_bytes + stream_record_bytes * k + 24, streams[k].data, bytes);
    }
    return out;
}

std::vector<Material> decode_materials(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path) {
    const SectionReader in{data, bytes, offset, path, "MATL", 17};
    in.need(0, scene_header_bytes, "header");
    const uint64_t count = load_u32(data), textures = load_u32(data + 4);
    const uint64_t texture_base = scene_header_bytes + material_record_bytes * count;
    const uint64_t records_end = texture_base + texture_record_bytes * textures;
    in.need(scene_header_bytes, records_end - scene_header_bytes, std::to_string(count) + " materials and " + std::to_string(textures) + " textures");
    std::vector<Material> out(count);
    for (uint64_t i = 0; i < count; ++i) {
        const uint64_t r = scene_header_bytes + material_record_bytes * i;
        const std::string field = "material " + std::to_string(i);
        Material& m = out[i];
        for (int k = 0; k < 4; ++k) m.base_color[k] = in.finite(r + 4 * k, field + " base_color");
        m.metallic = in.finite(r + 16, field + " metallic");
        m.roughness = in.finite(r + 20, field + " roughness");
        for (int k = 0; k < 3; ++k) m.emissive[k] = in.finite(r + 24 + 4 * k, field + " emissive");
        const uint32_t alpha = load_u32(data + r + 36);
        if (alpha > 2) in.fail(r + 36, field + " alpha_mode", "is " + std::to_string(alpha) + ", not 0, 1 or 2");
        m.alpha_mode = AlphaMode(alpha);
        m.alpha_cutoff = in.finite(r + 40, field + " alpha_cutoff");
        const uint32_t flags = load_u32(data + r + 44);
        if (flags & ~1u) in.fail(r + 44, field + " flags", "unknown flags");
        m.double_sided = flags & 1u;
        m.name = in.string_at(r + 48, records_end, field + " name");
        const uint64_t first = load_u32(data + r + 56), n = load_u32(data + r + 60);
        if (first > textures || n > textures - first)
            in.fail(r + 56, field + " textures", "textures " + std::to_string(first) + " + " + std::to_string(n) + " exceed the " + std::to_string(textures) + " stored");
        for (uint64_t t = first; t < first + n; ++t) {
            const uint64_t q = texture_base + texture_record_bytes * t;
            const std::string tf = "texture " + std::to_string(t);
            const uint32_t role = load_u32(data + q);
            if (role >= texture_role_count) in.fail(q, tf + " role", "is " + std::to_string(role) + ", not a known texture role");
            TextureRef ref;
            ref.role = TextureRole(role);
            ref.texcoord = load_u32(data + q + 4);
            ref.uri = in.string_at(q + 8, records_end, tf + " uri");
            ref.mime_type = in.string_at(q + 16, records_end, tf + " mime_type");
            m.textures.push_back(std::move(ref));
        }
    }
    return out;
}

std::vector<Instance> decode_instances(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path, uint32_t mesh_count) {
    const SectionReader in{data, bytes, offset, path, "INST", 18};
    in.need(0, scene_header_bytes, "header");
    const uint64_t count = load_u32(data);
    const uint64_t records_end = scene_header_bytes + instance_record_bytes * count;
    in.need(scene_header_bytes, records_end - scene_header_bytes, std::to_string(count) + " instances");
    std::vector<Instance> out(count);
    for (uint64_t i = 0; i < count; ++i) {
        const uint64_t r = scene_header_bytes + instance_record_bytes * i;
        const std::string field = "instance " + std::to_string(i);
        Instance& inst = out[i];
        inst.mesh = load_u32(data + r);
        if (inst.mesh >= mesh_count)
            in.fail(r, field + " mesh", "mesh " + std::to_string(inst.mesh) + " does not exist (the file has " + std::to_string(mesh_count) + ")");
        inst.node = load_u32(data + r + 4);
        inst.name = in.string_at(r + 8, records_end, field + " name");
        for (int k = 0; k < 16; ++k) inst.transform[k] = in.finite(r + 16 + 4 * k, field + " transform");
    }
    return out;
}

std::vector<uint8_t> encode_source_gltf(const SourceGltf& gltf) {
    const uint64_t json_end = (16 + uint64_t(gltf.json.size()) + 15) / 16 * 16;
    std::vector<uint8_t> out(size_t(json_end + gltf.bytes), 0);
    store_u64(&out[0], gltf.json.size());
    store_u64(&out[8], gltf.bytes);
    std::memcpy(&out[16], gltf.json.data(), gltf.json.size());
    if (gltf.bytes) std::memcpy(&out[size_t(json_end)], gltf.data, size_t(gltf.bytes));
    return out;
}

SourceGltf decode_source_gltf(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path) {
    const SectionReader in{data, bytes, offset, path, "GLTF", 23};
    in.need(0, 16, "header");
    const uint64_t json = load_u64(data), binary = load_u64(data + 8);
    if (json == 0) in.fail(0, "json_bytes", "is 0");
    in.need(16, json, "JSON");
    const uint64_t json_end = (16 + json + 15) / 16 * 16;
    if (json_end > bytes || binary != bytes - json_end)
        in.fail(8, "data_bytes", std::to_string(binary) + " bytes of data after " + std::to_string(json) + " of JSON do not fill the section's " + std::to_string(bytes));
    SourceGltf out;
    out.json.assign(reinterpret_cast<const char*>(data + 16), size_t(json));
    out.data = data + json_end;
    out.bytes = binary;
    return out;
}

std::vector<VertexStreamView> decode_extra_streams(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path, const std::string& mesh_field,
                                                   uint32_t vertex_count) {
    const SectionReader in{data, bytes, offset, path, "XATT", 22};
    in.need(0, scene_header_bytes, mesh_field + " header");
    const uint64_t count = load_u32(data);
    const uint64_t records_end = scene_header_bytes + stream_record_bytes * count;
    in.need(scene_header_bytes, records_end - scene_header_bytes, mesh_field + " " + std::to_string(count) + " stream records");
    std::vector<VertexStreamView> out(count);
    for (uint64_t k = 0; k < count; ++k) {
        const uint64_t r = scene_header_bytes + stream_record_bytes * k;
        const std::string field = mesh_field + " stream " + std::to_string(k);
        VertexStreamView& x = out[k];
        const std::string name = in.string_at(r, records_end, field + " name");
        if (name.empty()) in.fail(r, field + " name", "is empty");
        x.name = std::string_view(reinterpret_cast<const char*>(data + load_u32(data + r)), name.size());
        for (uint64_t j = 0; j < k; ++j)
            if (out[j].name == x.name) in.fail(r, field + " name", "'" + name + "' is also stream " + std::to_string(j));
        x.component_type = load_u32(data + r + 8);
        if (component_bytes(x.component_type) == 0) in.fail(r + 8, field + " component_type", std::to_string(x.component_type) + " is not a glTF component type");
        x.components = load_u32(data + r + 12);
        if (x.components < 1 || x.components > 4) in.fail(r + 12, field + " components", std::to_string(x.components) + " is not 1 to 4");
        const uint32_t flags = load_u32(data + r + 16);
        if (flags & ~1u) in.fail(r + 16, field + " flags", "unknown flags");
        x.normalized = flags & 1u;
        const uint64_t at = load_u64(data + r + 24), n = load_u64(data + r + 32);
        const uint64_t expected = uint64_t(vertex_count) * x.components * component_bytes(x.component_type);
        if (n != expected) in.fail(r + 32, field + " bytes", std::to_string(n) + " where " + std::to_string(vertex_count) + " vertices need " + std::to_string(expected));
        if (at < records_end || at > bytes || n > bytes - at) in.fail(r + 24, field + " data", std::to_string(n) + " bytes at " + std::to_string(at) + " are not in the section's data area");
        x.data = data + at;
        const bool weights = x.name.rfind("WEIGHTS_", 0) == 0;
        if (x.component_type == 5126)  // float values are finite (weights, deltas, coordinates), skin weights non-negative
            for (uint64_t v = 0; v < n; v += 4) {
                const float f = load_f32(data + at + v);
                if (!std::isfinite(f)) in.fail(at + v, field + " value " + std::to_string(v / 4), "is not finite");
                if (weights && f < 0) in.fail(at + v, field + " value " + std::to_string(v / 4), "is a negative skin weight");
            }
    }
    return out;
}

void decode_images(const uint8_t* data, uint64_t bytes, uint64_t offset, const std::string& path, Scene& scene) {
    const SectionReader in{data, bytes, offset, path, "IMAG", 21};
    in.need(0, scene_header_bytes, "header");
    const uint64_t count = load_u32(data), textures = load_u32(data + 4);
    uint64_t stored_textures = 0;
    for (const Material& m : scene.materials) stored_textures += m.textures.size();
    if (textures != stored_textures)
        in.fail(4, "texture_count", std::to_string(textures) + " where MATL stores " + std::to_string(stored_textures) + " textures");
    const uint64_t records = scene_header_bytes + 4 * textures;
    const uint64_t records_end = records + image_record_bytes * count;
    in.need(scene_header_bytes, records_end - scene_header_bytes, std::to_string(textures) + " texture images and " + std::to_string(count) + " image records");
    scene.images.assign(count, Image{});
    for (uint64_t i = 0; i < count; ++i) {
        const uint64_t r = records + image_record_bytes * i;
        const std::string field = "image " + std::to_string(i);
        Image& image = scene.images[i];
        const uint64_t at = load_u64(data + r), n = load_u64(data + r + 8);
        if (at < records_end || at > bytes || n > bytes - at)
            in.fail(r, field + " data", std::to_string(n) + " bytes at " + std::to_string(at) + " are not in the section's data area");
        image.data = data + at;
        image.bytes = n;
        image.mime_type = in.string_at(r + 16, records_end, field + " mime_type");
        if (image.mime_type.empty()) in.fail(r + 16, field + " mime_type", "is empty");
        image.name = in.string_at(r + 24, records_end, field + " name");
    }
    uint64_t at = scene_header_bytes;
    for (Material& m : scene.materials)
        for (TextureRef& t : m.textures) {
            const uint32_t image = load_u32(data + at);
            if (image != no_image && image >= count)
                in.fail(at, "texture " + std::to_string((at - scene_header_bytes) / 4) + " image",
                        "image " + std::to_string(image) + " is not among the " + std::to_string(count) + " stored");
            t.image = image == no_image ? -1 : int32_t(image);
            at += 4;
        }
}

} // namespace detail

Image make_image(std::string name, std::string mime_type, std::vector<uint8_t> bytes) {
    auto held = std::make_shared<const std::vector<uint8_t>>(std::move(bytes));
    Image image;
    image.name = std::move(name);
    image.mime_type = std::move(mime_type);
    image.data = held->data();
    image.bytes = held->size();
    image.owner = std::move(held);
    return image;
}

const char* sniff_image_type(const uint8_t* p, uint64_t n) noexcept {
    auto starts = [&](const char* signature, uint64_t len, uint64_t at = 0) { return n >= at + len && std::memcmp(p + at, signature, len) == 0; };
    if (starts("\x89PNG\r\n\x1a\n", 8)) return "image/png";
    if (starts("\xFF\xD8\xFF", 3)) return "image/jpeg";
    if (starts("RIFF", 4) && starts("WEBP", 4, 8)) return "image/webp";
    if (starts("\xABKTX 20\xBB\r\n\x1A\n", 12)) return "image/ktx2";
    if (starts("GIF8", 4)) return "image/gif";
    if (starts("BM", 2)) return "image/bmp";
    return "";
}

} // namespace tom
