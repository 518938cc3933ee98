// OBJ material libraries (.mtl): the materials an OBJ's `usemtl` groups name, as the file's
// scene materials. MTL is Phong-era; what maps onto glTF's model is kept: Kd (base colour),
// d or Tr (opacity), Ke (emission), Ns (roughness, as sqrt(2 / (Ns + 2))), the PBR extension's
// Pm and Pr, and the maps map_Kd, map_Ke, bump/map_Bump/norm and map_Pr. Texture URIs are made
// relative to the OBJ, as .tom stores them (the MTL's own are relative to the MTL).

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>

#include "import_backends.h"
#include "tom/errors.h"

namespace tom::detail {

namespace {

namespace fs = std::filesystem;

// The words of an MTL line, without its comment.
std::vector<std::string> words_of(const std::string& line) {
    std::vector<std::string> w;
    std::istringstream in(line.substr(0, line.find('#')));
    for (std::string word; in >> word;) w.push_back(word);
    return w;
}

// A factor: a finite number clamped to [lo, hi], or `fallback` with a warning.
float factor(const std::string& word, float lo, float hi, float fallback, const std::string& where, std::vector<std::string>& warnings) {
    char* end = nullptr;
    const float x = std::strtof(word.c_str(), &end);
    if (end == word.c_str() || !std::isfinite(x)) {
        warnings.push_back(where + ": '" + word + "' is not a number; " + std::to_string(fallback) + " used");
        return fallback;
    }
    return std::min(hi, std::max(lo, x));
}

struct Library {
    std::map<std::string, Material> materials;
};

// Reads one .mtl into `lib`; `prefix` is the MTL's folder relative to the OBJ's.
void read_library(const fs::path& file, const fs::path& prefix, Library& lib, std::vector<std::string>& warnings) {
    const std::vector<uint8_t> bytes = read_whole_file(file.string());
    std::istringstream in(std::string(bytes.begin(), bytes.end()));
    Material* current = nullptr;
    size_t line_number = 0;
    for (std::string line; std::getline(in, line);) {
        ++line_number;
        const std::vector<std::string> w = words_of(line);
        if (w.empty()) continue;
        const std::string where = file.string() + ":" + std::to_string(line_number);
        std::string key = w[0];
        std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return char(std::tolower(c)); });
        if (key == "newmtl") {
            std::string name = w.size() > 1 ? w[1] : std::string();
            for (size_t k = 2; k < w.size(); ++k) name += " " + w[k];
            current = &lib.materials[name];
            *current = Material{};
            current->name = name;
            current->metallic = 0.0f;  // MTL describes dielectrics unless Pm says otherwise
            continue;
        }
        if (!current) continue;
        Material& m = *current;
        if (key == "kd" && w.size() >= 4) {
            for (int k = 0; k < 3; ++k) m.base_color[k] = factor(w[size_t(k) + 1], 0, 1, 1, where, warnings);
        } else if (key == "ke" && w.size() >= 4) {
            for (int k = 0; k < 3; ++k) m.emissive[k] = factor(w[size_t(k) + 1], 0, 1, 0, where, warnings);
        } else if (key == "d" && w.size() >= 2) {
            m.base_color[3] = factor(w.back(), 0, 1, 1, where, warnings);
        } else if (key == "tr" && w.size() >= 2) {
            m.base_color[3] = 1.0f - factor(w.back(), 0, 1, 0, where, warnings);
        } else if (key == "ns" && w.size() >= 2) {
            m.roughness = std::sqrt(2.0f / (factor(w[1], 0, 1e6f, 0, where, warnings) + 2.0f));
        } else if (key == "pm" && w.size() >= 2) {
            m.metallic = factor(w[1], 0, 1, 0, where, warnings);
        } else if (key == "pr" && w.size() >= 2) {
            m.roughness = factor(w[1], 0, 1, 1, where, warnings);
        } else if ((key == "map_kd" || key == "map_ke" || key == "bump" || key == "map_bump" || key == "norm" || key == "map_pr") && w.size() >= 2) {
            // options (-bm 0.5, -s 1 1 1, ...) come before the file name: the last word is it
            std::string name = w.back();
            std::replace(name.begin(), name.end(), '\\', '/');
            TextureRef t;
            t.role = key == "map_kd" ? TextureRole::base_color
                   : key == "map_ke" ? TextureRole::emissive
                   : key == "map_pr" ? TextureRole::metallic_roughness
                                     : TextureRole::normal;
            t.uri = (prefix / name).lexically_normal().generic_string();
            m.textures.erase(std::remove_if(m.textures.begin(), m.textures.end(), [&](const TextureRef& o) { return o.role == t.role; }), m.textures.end());
            m.textures.push_back(t);
        }
    }
}

// Valid UTF-8 as it is; otherwise every byte taken as Latin-1 (.tom strings are UTF-8, MTL files
// are often Latin-1).
std::string utf8_or_latin1(const std::string& s) {
    for (size_t i = 0; i < s.size();) {
        const unsigned char c = static_cast<unsigned char>(s[i]);
        const size_t extra = c < 0x80 ? 0 : (c & 0xE0) == 0xC0 ? 1 : (c & 0xF0) == 0xE0 ? 2 : (c & 0xF8) == 0xF0 ? 3 : s.size();
        bool ok = i + extra < s.size();
        for (size_t k = 1; ok && k <= extra; ++k) ok = (static_cast<unsigned char>(s[i + k]) & 0xC0) == 0x80;
        if (!ok) {
            std::string out;
            for (const char ch : s) {
                const unsigned char b = static_cast<unsigned char>(ch);
                if (b < 0x80) {
                    out += ch;
                } else {
                    out += char(0xC0 | (b >> 6));
                    out += char(0x80 | (b & 0x3F));
                }
            }
            return out;
        }
        i += extra + 1;
    }
    return s;
}

} // namespace

std::vector<Material> read_obj_materials(const std::string& obj_path, const std::vector<std::string>& libraries,
                                         const std::vector<std::string>& names, std::vector<std::string>& warnings) {
    const fs::path obj_dir = fs::path(obj_path).parent_path();
    Library lib;
    for (const std::string& name : libraries) {
        std::string relative = name;
        std::replace(relative.begin(), relative.end(), '\\', '/');
        const fs::path file = obj_dir / relative;
        std::error_code ec;
        if (!fs::is_regular_file(file, ec)) {
            warnings.push_back(obj_path + ": material library '" + file.string() + "' (mtllib " + name + ") is missing; its materials get default values");
            continue;
        }
        try {
            read_library(file, fs::path(relative).parent_path(), lib, warnings);
        } catch (const Error& e) {
            warnings.push_back(obj_path + ": material library '" + file.string() + "' cannot be read (" + e.what() + "); its materials get default values");
        }
    }
    std::vector<Material> out;
    for (const std::string& name : names) {
        const auto it = lib.materials.find(name);
        if (it == lib.materials.end()) {
            if (!libraries.empty()) warnings.push_back(obj_path + ": usemtl " + name + ": no material library defines it; default values used");
            Material m;
            m.name = name;
            m.metallic = 0.0f;
            out.push_back(m);
            continue;
        }
        Material m = it->second;
        if (m.base_color[3] < 1.0f) m.alpha_mode = AlphaMode::blend;
        out.push_back(m);
    }
    for (Material& m : out) {
        m.name = utf8_or_latin1(m.name);
        for (TextureRef& t : m.textures) t.uri = utf8_or_latin1(t.uri);
    }
    return out;
}

} // namespace tom::detail
