#pragma once
// A GLB file's JSON and binary chunk, read and written with nothing but the container's layout:
// the tests' way to look inside exported files and to make the assets they need.

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

namespace test {

inline std::vector<uint8_t> file_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A GLB's JSON and binary chunk, read with nothing but the container's layout.
struct Glb {
    nlohmann::json doc;
    std::vector<uint8_t> bin;

    Glb() = default;
    explicit Glb(const std::vector<uint8_t>& b) {
        REQUIRE(b.size() >= 20);
        uint32_t json_bytes;
        std::memcpy(&json_bytes, &b[12], 4);
        doc = nlohmann::json::parse(b.begin() + 20, b.begin() + 20 + json_bytes);
        if (b.size() > 28 + size_t(json_bytes)) bin.assign(b.begin() + 28 + json_bytes, b.end());
    }
    // the bytes of image `i` (from its buffer view)
    std::vector<uint8_t> image(size_t i) const {
        const nlohmann::json& view = doc["bufferViews"][doc["images"][i]["bufferView"].get<size_t>()];
        const size_t at = view.value("byteOffset", size_t(0)), n = view["byteLength"].get<size_t>();
        REQUIRE(at + n <= bin.size());
        return std::vector<uint8_t>(bin.begin() + long(at), bin.begin() + long(at + n));
    }
    // the image that material `m`'s base colour texture shows
    size_t base_color_image(size_t m) const {
        const nlohmann::json& texture = doc["textures"][doc["materials"][m]["pbrMetallicRoughness"]["baseColorTexture"]["index"].get<size_t>()];
        if (texture.contains("source")) return texture["source"].get<size_t>();
        return texture["extensions"].begin().value()["source"].get<size_t>();
    }
    // Appends `count` elements of `values` (a bufferView and an accessor of `type` and glTF
    // component type `component`) to the binary chunk; returns the accessor's index.
    template <class T>
    size_t add(const std::vector<T>& values, const char* type, uint32_t component, size_t count, bool normalized = false) {
        while (bin.size() % 4) bin.push_back(0);
        const size_t at = bin.size(), n = values.size() * sizeof(T);
        bin.resize(at + n);
        std::memcpy(&bin[at], values.data(), n);
        doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", n}});
        nlohmann::json a = {{"bufferView", doc["bufferViews"].size() - 1}, {"componentType", component}, {"count", count}, {"type", type}};
        if (normalized) a["normalized"] = true;
        doc["accessors"].push_back(a);
        doc["buffers"] = nlohmann::json::array({{{"byteLength", bin.size()}}});
        return doc["accessors"].size() - 1;
    }
    std::vector<uint8_t> bytes() const {
        std::string json = doc.dump();
        json.append((4 - json.size() % 4) % 4, ' ');
        auto le32 = [](std::vector<uint8_t>& out, uint32_t v) { out.insert(out.end(), reinterpret_cast<uint8_t*>(&v), reinterpret_cast<uint8_t*>(&v) + 4); };
        std::vector<uint8_t> out;
        le32(out, 0x46546C67);
        le32(out, 2);
        le32(out, uint32_t(12 + 8 + json.size() + 8 + bin.size()));
        le32(out, uint32_t(json.size()));
        le32(out, 0x4E4F534A);
        out.insert(out.end(), json.begin(), json.end());
        le32(out, uint32_t(bin.size()));
        le32(out, 0x004E4942);
        out.insert(out.end(), bin.begin(), bin.end());
        return out;
    }
};

} // namespace test
