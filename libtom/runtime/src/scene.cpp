// Scenes: the MATL and INST sections (docs/FORMAT.md) and the draw list.

#include <cmath>

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

} // namespace detail

} // namespace tom
