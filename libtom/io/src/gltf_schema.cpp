// Type check of a glTF 2.0 document against the core schema (glTF 2.0 specification,
// section 5, "Properties Reference"), before tinygltf reads it: tinygltf silently ignores a
// property of the wrong type and substitutes a default, which turns a broken file into a
// wrong mesh. Every property the core schema defines is checked for its JSON type, integer
// ranges, required presence and fixed array lengths; extensions must be objects.

#include <cstring>
#include <memory>

#include <nlohmann/json.hpp>

#include "gltf_schema.h"

#include "glb.h"
#include "tom/errors.h"

namespace tom::detail {

namespace {

using nlohmann::json;

struct Rule;
using RulePtr = std::shared_ptr<Rule>;

struct Rule {
    enum Kind { Integer, UnsignedInt, Number, String, Boolean, Object, Array, Map, Anything } kind;
    std::vector<std::pair<std::string, RulePtr>> properties;  // Object
    std::vector<std::string> required;                        // Object
    RulePtr item;                                             // Array, Map
    size_t min_items = 0, exact_items = 0;                    // Array
};

RulePtr make(Rule::Kind k) {
    auto r = std::make_shared<Rule>();
    r->kind = k;
    return r;
}
RulePtr integer() { return make(Rule::Integer); }
RulePtr uint() { return make(Rule::UnsignedInt); }
RulePtr number() { return make(Rule::Number); }
RulePtr string() { return make(Rule::String); }
RulePtr boolean() { return make(Rule::Boolean); }
RulePtr array(RulePtr item, size_t exact = 0, size_t min_items = 0) {
    auto r = make(Rule::Array);
    r->item = std::move(item);
    r->exact_items = exact;
    r->min_items = min_items;
    return r;
}
RulePtr map(RulePtr item) {
    auto r = make(Rule::Map);
    r->item = std::move(item);
    return r;
}
RulePtr object(std::vector<std::pair<std::string, RulePtr>> props, std::vector<std::string> required = {}) {
    auto r = make(Rule::Object);
    r->properties = std::move(props);
    r->properties.push_back({"name", string()});
    r->properties.push_back({"extensions", map(make(Rule::Object))});
    r->properties.push_back({"extras", make(Rule::Anything)});
    r->required = std::move(required);
    return r;
}

RulePtr gltf_schema() {
    auto texture_info = [](std::vector<std::pair<std::string, RulePtr>> extra) {
        extra.push_back({"index", uint()});
        extra.push_back({"texCoord", uint()});
        return object(std::move(extra), {"index"});
    };
    auto pbr = object({{"baseColorFactor", array(number(), 4)},
                       {"baseColorTexture", texture_info({})},
                       {"metallicFactor", number()},
                       {"roughnessFactor", number()},
                       {"metallicRoughnessTexture", texture_info({})}});
    auto material = object({{"pbrMetallicRoughness", pbr},
                            {"normalTexture", texture_info({{"scale", number()}})},
                            {"occlusionTexture", texture_info({{"strength", number()}})},
                            {"emissiveTexture", texture_info({})},
                            {"emissiveFactor", array(number(), 3)},
                            {"alphaMode", string()},
                            {"alphaCutoff", number()},
                            {"doubleSided", boolean()}});
    auto sparse = object({{"count", uint()},
                          {"indices", object({{"bufferView", uint()}, {"byteOffset", uint()}, {"componentType", integer()}}, {"bufferView", "componentType"})},
                          {"values", object({{"bufferView", uint()}, {"byteOffset", uint()}}, {"bufferView"})}},
                         {"count", "indices", "values"});
    auto accessor = object({{"bufferView", uint()},
                            {"byteOffset", uint()},
                            {"componentType", integer()},
                            {"normalized", boolean()},
                            {"count", uint()},
                            {"type", string()},
                            {"max", array(number())},
                            {"min", array(number())},
                            {"sparse", sparse}},
                           {"componentType", "count", "type"});
    auto animation = object({{"channels", array(object({{"sampler", uint()}, {"target", object({{"node", uint()}, {"path", string()}}, {"path"})}},
                                                       {"sampler", "target"}),
                                                0, 1)},
                             {"samplers", array(object({{"input", uint()}, {"interpolation", string()}, {"output", uint()}}, {"input", "output"}), 0, 1)}},
                            {"channels", "samplers"});
    auto asset = object({{"copyright", string()}, {"generator", string()}, {"version", string()}, {"minVersion", string()}}, {"version"});
    auto buffer = object({{"uri", string()}, {"byteLength", uint()}}, {"byteLength"});
    auto buffer_view = object({{"buffer", uint()}, {"byteOffset", uint()}, {"byteLength", uint()}, {"byteStride", uint()}, {"target", integer()}},
                              {"buffer", "byteLength"});
    auto camera = object({{"orthographic", object({{"xmag", number()}, {"ymag", number()}, {"zfar", number()}, {"znear", number()}})},
                          {"perspective", object({{"aspectRatio", number()}, {"yfov", number()}, {"zfar", number()}, {"znear", number()}})},
                          {"type", string()}},
                         {"type"});
    auto image = object({{"uri", string()}, {"mimeType", string()}, {"bufferView", uint()}});
    auto primitive = object({{"attributes", map(uint())}, {"indices", uint()}, {"material", uint()}, {"mode", integer()}, {"targets", array(map(uint()))}},
                            {"attributes"});
    auto mesh = object({{"primitives", array(primitive, 0, 1)}, {"weights", array(number())}}, {"primitives"});
    auto node = object({{"camera", uint()},
                        {"children", array(uint())},
                        {"skin", uint()},
                        {"matrix", array(number(), 16)},
                        {"mesh", uint()},
                        {"rotation", array(number(), 4)},
                        {"scale", array(number(), 3)},
                        {"translation", array(number(), 3)},
                        {"weights", array(number())}});
    auto sampler = object({{"magFilter", integer()}, {"minFilter", integer()}, {"wrapS", integer()}, {"wrapT", integer()}});
    auto scene = object({{"nodes", array(uint())}});
    auto skin = object({{"inverseBindMatrices", uint()}, {"skeleton", uint()}, {"joints", array(uint(), 0, 1)}}, {"joints"});
    auto texture = object({{"sampler", uint()}, {"source", uint()}});
    return object({{"extensionsUsed", array(string())},
                   {"extensionsRequired", array(string())},
                   {"accessors", array(accessor)},
                   {"animations", array(animation)},
                   {"asset", asset},
                   {"buffers", array(buffer)},
                   {"bufferViews", array(buffer_view)},
                   {"cameras", array(camera)},
                   {"images", array(image)},
                   {"materials", array(material)},
                   {"meshes", array(mesh)},
                   {"nodes", array(node)},
                   {"samplers", array(sampler)},
                   {"scene", uint()},
                   {"scenes", array(scene)},
                   {"skins", array(skin)},
                   {"textures", array(texture)}},
                  {"asset"});
}

const char* type_of(const json& j) {
    switch (j.type()) {
    case json::value_t::null: return "null";
    case json::value_t::object: return "an object";
    case json::value_t::array: return "an array";
    case json::value_t::string: return "a string";
    case json::value_t::boolean: return "a boolean";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned: return "an integer";
    case json::value_t::number_float: return "a number";
    default: return "something else";
    }
}

void check(const json& j, const Rule& rule, const std::string& path, const std::string& file) {
    auto fail = [&](const std::string& expected) {
        throw MeshError(file + ": " + path + ": expected " + expected + ", found " + type_of(j) +
                          (j.is_primitive() ? " (" + j.dump().substr(0, 40) + ")" : ""));
    };
    switch (rule.kind) {
    case Rule::Anything: return;
    case Rule::Integer:
        if (!j.is_number_integer()) fail("an integer");
        return;
    case Rule::UnsignedInt:
        if (!j.is_number_integer() || (j.is_number_integer() && !j.is_number_unsigned() && j.get<int64_t>() < 0)) fail("a non-negative integer");
        return;
    case Rule::Number:
        if (!j.is_number()) fail("a number");
        return;
    case Rule::String:
        if (!j.is_string()) fail("a string");
        return;
    case Rule::Boolean:
        if (!j.is_boolean()) fail("a boolean");
        return;
    case Rule::Array:
        if (!j.is_array()) fail("an array");
        if (rule.exact_items && j.size() != rule.exact_items) fail("an array of " + std::to_string(rule.exact_items) + " elements");
        if (j.size() < rule.min_items) fail("an array of at least " + std::to_string(rule.min_items) + " element(s)");
        for (size_t i = 0; i < j.size(); ++i) check(j[i], *rule.item, path + "[" + std::to_string(i) + "]", file);
        return;
    case Rule::Map:
        if (!j.is_object()) fail("an object");
        for (auto it = j.begin(); it != j.end(); ++it) check(it.value(), *rule.item, path + "." + it.key(), file);
        return;
    case Rule::Object:
        if (!j.is_object()) fail("an object");
        for (const std::string& r : rule.required)
            if (!j.contains(r)) throw MeshError(file + ": " + path + ": required property '" + r + "' is missing");
        for (const auto& [key, sub] : rule.properties) {
            auto it = j.find(key);
            if (it != j.end()) check(*it, *sub, path + "." + key, file);
        }
        return;
    }
}

} // namespace

nlohmann::json check_gltf_schema(const std::vector<uint8_t>& bytes, bool binary, const std::string& file) {
    const uint8_t* json_begin = bytes.data();
    size_t json_size = bytes.size();
    if (binary) {
        // GLB: 12-byte header (magic, version, length), then a JSON chunk (length, type)
        if (bytes.size() < 20) throw MeshError(file + ": GLB file of " + std::to_string(bytes.size()) + " bytes is shorter than its headers");
        if (std::memcmp(bytes.data(), "glTF", 4) != 0) throw MeshError(file + ": not a GLB file (bad magic)");
        if (le32(&bytes[4]) != 2) throw MeshError(file + ": GLB version " + std::to_string(le32(&bytes[4])) + " is not 2");
        if (le32(&bytes[8]) > bytes.size())
            throw MeshError(file + ": GLB header declares " + std::to_string(le32(&bytes[8])) + " bytes, the file has " + std::to_string(bytes.size()));
        const uint32_t chunk = le32(&bytes[12]);
        if (le32(&bytes[16]) != 0x4E4F534Au) throw MeshError(file + ": the first GLB chunk is not JSON");
        if (chunk > bytes.size() - 20) throw MeshError(file + ": GLB JSON chunk of " + std::to_string(chunk) + " bytes runs past the end of the file");
        json_begin = bytes.data() + 20;
        json_size = chunk;
    }
    json doc;
    try {
        doc = json::parse(json_begin, json_begin + json_size);
    } catch (const json::parse_error& e) {
        throw MeshError(file + ": the glTF JSON does not parse at byte " + std::to_string(e.byte) + (binary ? " of the JSON chunk" : ""));
    } catch (const json::exception& e) {  // a number past double's range (out_of_range.406), ...
        std::string what = e.what();
        const size_t close = what.find("] ");
        throw MeshError(file + ": the glTF JSON does not parse: " + (close == std::string::npos ? what : what.substr(close + 2)));
    }
    static const RulePtr schema = gltf_schema();
    check(doc, *schema, "$", file);
    return doc;
}

std::string primitives_using_accessor(const nlohmann::json& doc, int accessor) {
    std::string out;
    if (!doc.contains("meshes")) return out;
    const json& meshes = doc["meshes"];
    for (size_t m = 0; m < meshes.size(); ++m) {
        const std::string name = meshes[m].value("name", "mesh" + std::to_string(m));
        const json& prims = meshes[m]["primitives"];
        for (size_t p = 0; p < prims.size(); ++p) {
            std::vector<std::string> roles;
            if (prims[p].contains("indices") && prims[p]["indices"] == accessor) roles.push_back("indices");
            for (auto it = prims[p]["attributes"].begin(); it != prims[p]["attributes"].end(); ++it)
                if (it.value() == accessor) roles.push_back(it.key());
            if (roles.empty()) continue;
            std::string r;
            for (const std::string& x : roles) r += (r.empty() ? "" : ", ") + x;
            out += (out.empty() ? "" : "; ") + std::string("mesh ") + std::to_string(m) + " '" + name + "' primitive " + std::to_string(p) + " (" + r + ")";
        }
    }
    return out;
}

} // namespace tom::detail
