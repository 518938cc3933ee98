// glTF 2.0 import through tinygltf, with Draco (KHR_draco_mesh_compression) decoding.
//
// tinygltf ignores a failed Draco decode and leaves the accessors without data, and checks
// little of what accessors claim; so every accessor used here is validated against its
// buffer view and buffer before a byte is read: a primitive that cannot be decoded is an
// error that names it, never an empty mesh.

#define TINYGLTF_IMPLEMENTATION
#include "gltf_model.h"

#include <algorithm>
#include <deque>
#include <cmath>
#include <iterator>
#include <optional>

#include "gltf_carried.h"
#include "gltf_meshopt.h"
#include "gltf_references.h"
#include "gltf_schema.h"
#include "gltf_source.h"
#include "import_backends.h"
#include "tom/errors.h"

namespace tom::detail {

namespace {

// Images are not decoded: each embedded one (a buffer view, a data: URI) is kept byte for byte,
// by its index in the document.
bool keep_image(tinygltf::Image*, const int index, std::string*, std::string*, int, int, const unsigned char* bytes, int size, void* user) {
    auto& kept = *static_cast<EmbeddedImages*>(user);
    if (index >= 0 && size > 0) kept[index].assign(bytes, bytes + size);
    return true;
}

std::string one_line(std::string s) {
    for (char& c : s)
        if (c == '\n' || c == '\r') c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s;
}

int component_count(int type) {
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT4: return 16;  // inverse bind matrices
    default: return 0;
    }
}

int component_bytes(int component_type) {
    switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
    }
}

class PrimitiveReader {
public:
    PrimitiveReader(const tinygltf::Model& model, std::string where, bool quantized)
        : model_(model), where_(std::move(where)), quantized_(quantized) {}

    [[noreturn]] void fail(const std::string& what) const { throw MeshError(where_ + ": " + what); }

    // Validates accessor `index` and returns a pointer to element 0 plus the stride. A sparse
    // accessor is made dense first (`expect`: the element count it must have, 0 for any; one
    // without a buffer view must have an expected count, so that no count the file merely
    // declares sizes an allocation).
    const uint8_t* locate(int index, const char* role, size_t& count, size_t& stride, int& components, int& ctype, size_t expect = 0) const {
        const std::string name = std::string(role) + " accessor " + std::to_string(index);
        if (index < 0 || size_t(index) >= model_.accessors.size()) fail(name + " does not exist");
        const tinygltf::Accessor& a = model_.accessors[size_t(index)];
        if (a.sparse.isSparse) return densify(a, name, expect, count, stride, components, ctype);
        return dense(a, name, count, stride, components, ctype);
    }

    // A sparse accessor's elements: its base (its buffer view's, or zeros) with the substitutes
    // its sparse indices and values give, held by the reader.
    const uint8_t* densify(const tinygltf::Accessor& a, const std::string& name, size_t expect, size_t& count, size_t& stride, int& components,
                           int& ctype) const {
        components = component_count(a.type);
        ctype = a.componentType;
        const size_t elem = size_t(components) * size_t(component_bytes(ctype));
        if (elem == 0) fail(name + " has an invalid type or component type");
        if (expect && a.count != expect)
            fail(name + " has " + std::to_string(a.count) + " elements but POSITION has " + std::to_string(expect));
        if (a.bufferView < 0 && !expect) fail(name + " is sparse without a buffer view, and nothing bounds its element count");
        std::vector<uint8_t> out(a.count * elem, 0);
        if (a.bufferView >= 0) {
            size_t n, base_stride;
            int c, t;
            const uint8_t* base = dense(a, name, n, base_stride, c, t);
            for (size_t i = 0; i < n; ++i) std::memcpy(&out[i * elem], base + i * base_stride, elem);
        }
        const auto& sp = a.sparse;
        const size_t index_bytes = size_t(component_bytes(sp.indices.componentType));
        if (sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            fail(name + ": sparse indices have component type " + std::to_string(sp.indices.componentType) + ", not an unsigned integer");
        const uint8_t* indices = view_range(sp.indices.bufferView, sp.indices.byteOffset, size_t(sp.count) * index_bytes, name + " sparse indices");
        const uint8_t* values = view_range(sp.values.bufferView, sp.values.byteOffset, size_t(sp.count) * elem, name + " sparse values");
        for (size_t i = 0; i < size_t(sp.count); ++i) {
            uint32_t at = 0;
            std::memcpy(&at, indices + i * index_bytes, index_bytes);  // little-endian
            if (at >= a.count) fail(name + ": sparse index " + std::to_string(i) + " is " + std::to_string(at) + ", past its " + std::to_string(a.count) + " elements");
            std::memcpy(&out[size_t(at) * elem], values + i * elem, elem);
        }
        count = a.count;
        stride = elem;
        dense_.push_back(std::move(out));
        return dense_.back().data();
    }

    // `bytes` bytes at `offset` of buffer view `view`, checked to lie in it and its buffer
    const uint8_t* view_range(int view, size_t offset, size_t bytes, const std::string& what) const {
        if (view < 0 || size_t(view) >= model_.bufferViews.size()) fail(what + ": buffer view " + std::to_string(view) + " does not exist");
        const tinygltf::BufferView& v = model_.bufferViews[size_t(view)];
        if (v.buffer < 0 || size_t(v.buffer) >= model_.buffers.size()) fail(what + ": buffer view " + std::to_string(view) + " refers to a missing buffer");
        const std::vector<unsigned char>& data = model_.buffers[size_t(v.buffer)].data;
        if (v.byteOffset > data.size() || v.byteLength > data.size() - v.byteOffset || offset > v.byteLength || bytes > v.byteLength - offset)
            fail(what + ": " + std::to_string(bytes) + " bytes at " + std::to_string(offset) + " do not fit buffer view " + std::to_string(view));
        return data.data() + v.byteOffset + offset;
    }

    // a dense accessor's element 0 and stride
    const uint8_t* dense(const tinygltf::Accessor& a, const std::string& name, size_t& count, size_t& stride, int& components, int& ctype) const {
        if (a.bufferView < 0 || size_t(a.bufferView) >= model_.bufferViews.size())
            fail(name + " has no data (buffer view " + std::to_string(a.bufferView) + "; a failed Draco decode leaves it so)");
        const tinygltf::BufferView& view = model_.bufferViews[size_t(a.bufferView)];
        if (view.buffer < 0 || size_t(view.buffer) >= model_.buffers.size())
            fail(name + ": buffer view " + std::to_string(a.bufferView) + " refers to missing buffer " + std::to_string(view.buffer));
        const tinygltf::Buffer& buffer = model_.buffers[size_t(view.buffer)];
        components = component_count(a.type);
        ctype = a.componentType;
        const size_t elem = size_t(components) * size_t(component_bytes(ctype));
        if (elem == 0) fail(name + " has an invalid type or component type");
        count = a.count;
        if (count == 0) fail(name + " is empty");
        stride = view.byteStride ? view.byteStride : elem;
        if (stride < elem) fail(name + ": byte stride " + std::to_string(stride) + " is smaller than an element (" + std::to_string(elem) + ")");
        if (view.byteOffset > buffer.data.size() || view.byteLength > buffer.data.size() - view.byteOffset)
            fail(name + ": buffer view " + std::to_string(a.bufferView) + " lies outside buffer " + std::to_string(view.buffer) + " (" +
                 std::to_string(buffer.data.size()) + " bytes)");
        const size_t need = a.byteOffset + stride * (count - 1) + elem;
        if (a.byteOffset > view.byteLength || need > view.byteLength || (count - 1) > (SIZE_MAX - elem) / stride)
            fail(name + ": " + std::to_string(count) + " elements need " + std::to_string(need) + " bytes but buffer view " +
                 std::to_string(a.bufferView) + " has " + std::to_string(view.byteLength));
        return buffer.data.data() + view.byteOffset + a.byteOffset;
    }

    // Which component types an attribute may have: the core specification's, or with
    // KHR_mesh_quantization (what gltfpack writes) also integers, normalized or not.
    enum class Kind { position, vector, texcoord, color };
    static bool allowed(Kind kind, int ctype, bool normalized, bool quantized) {
        if (ctype == TINYGLTF_COMPONENT_TYPE_FLOAT) return true;
        const bool ubyte_or_ushort = ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
        const bool byte_or_short = ctype == TINYGLTF_COMPONENT_TYPE_BYTE || ctype == TINYGLTF_COMPONENT_TYPE_SHORT;
        switch (kind) {
        case Kind::color: return ubyte_or_ushort && normalized;
        case Kind::texcoord: return (ubyte_or_ushort && normalized) || (quantized && (ubyte_or_ushort || byte_or_short));
        case Kind::position: return quantized && (ubyte_or_ushort || byte_or_short);
        case Kind::vector: return quantized && byte_or_short && normalized;
        }
        return false;
    }

    // Reads a float attribute of want_min..want_max components, converting integer components
    // (normalized: to [0, 1] or [-1, 1] as glTF defines; otherwise their value).
    std::vector<float> read_floats(int index, const char* role, int want_min, int want_max, Kind kind, size_t expect_count) const {
        size_t count, stride;
        int components, ctype;
        const uint8_t* p = locate(index, role, count, stride, components, ctype, expect_count);
        const std::string name = std::string(role) + " accessor " + std::to_string(index);
        if (components < want_min || components > want_max) fail(name + " has " + std::to_string(components) + " components");
        if (expect_count && count != expect_count)
            fail(name + " has " + std::to_string(count) + " elements but POSITION has " + std::to_string(expect_count));
        const bool normalized = model_.accessors[size_t(index)].normalized;
        if (!allowed(kind, ctype, normalized, quantized_))
            fail(name + " has component type " + std::to_string(ctype) + (normalized ? " (normalized)" : "") + ", which glTF does not allow here" +
                 (quantized_ ? "" : " without KHR_mesh_quantization"));
        std::vector<float> out(count * size_t(components));
        for (size_t i = 0; i < count; ++i) {
            const uint8_t* e = p + i * stride;
            for (int k = 0; k < components; ++k) {
                float x;
                switch (ctype) {
                case TINYGLTF_COMPONENT_TYPE_FLOAT: std::memcpy(&x, e + 4 * k, 4); break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: x = normalized ? float(e[k]) / 255.0f : float(e[k]); break;
                case TINYGLTF_COMPONENT_TYPE_BYTE: {
                    const float c = float(int8_t(e[k]));
                    x = normalized ? std::max(c / 127.0f, -1.0f) : c;
                    break;
                }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                    uint16_t u;
                    std::memcpy(&u, e + 2 * k, 2);
                    x = normalized ? float(u) / 65535.0f : float(u);
                    break;
                }
                default: {  // SHORT
                    int16_t v;
                    std::memcpy(&v, e + 2 * k, 2);
                    x = normalized ? std::max(float(v) / 32767.0f, -1.0f) : float(v);
                    break;
                }
                }
                out[i * size_t(components) + size_t(k)] = x;
            }
        }
        return out;
    }

    // An attribute the importer does not interpret, its elements copied as they are (no
    // conversion; a sparse accessor made dense).
    VertexStream read_carried(int index, const std::string& name, size_t expect_count) const {
        size_t count, stride;
        int components, ctype;
        const uint8_t* p = locate(index, name.c_str(), count, stride, components, ctype, expect_count);
        if (count != expect_count)
            fail(name + " accessor " + std::to_string(index) + " has " + std::to_string(count) + " elements but POSITION has " + std::to_string(expect_count));
        if (components > 4) fail(name + " accessor " + std::to_string(index) + " is not a SCALAR or VEC2-4");
        VertexStream out{name, uint32_t(ctype), uint32_t(components), model_.accessors[size_t(index)].normalized, {}};
        const size_t elem = out.element_bytes();
        out.data.resize(count * elem);
        for (size_t i = 0; i < count; ++i) std::memcpy(&out.data[i * elem], p + i * stride, elem);
        return out;
    }

    // The bind-pose position of each joint of skin `s` in the skinned mesh's space: the point
    // its inverse bind matrix takes to the joint's origin. Empty without inverse bind matrices
    // (every joint then binds at the origin, and the skinning term has nothing to tell apart).
    std::vector<float> joint_positions(int s) const {
        const tinygltf::Skin& skin = model_.skins[size_t(s)];
        if (skin.inverseBindMatrices < 0) return {};
        const std::string name = "skin " + std::to_string(s) + " inverseBindMatrices";
        size_t count, stride;
        int components, ctype;
        const uint8_t* p = locate(skin.inverseBindMatrices, name.c_str(), count, stride, components, ctype);
        if (components != 16 || ctype != TINYGLTF_COMPONENT_TYPE_FLOAT) fail(name + " is not MAT4 FLOAT");
        if (count < skin.joints.size())
            fail(name + " has " + std::to_string(count) + " matrices for " + std::to_string(skin.joints.size()) + " joints");
        std::vector<float> out(3 * skin.joints.size());
        for (size_t j = 0; j < skin.joints.size(); ++j) {
            float m[16];  // column-major: the 3x3 A in m[0..2], m[4..6], m[8..10]; t in m[12..14]
            std::memcpy(m, p + j * stride, sizeof m);
            // the joint's origin maps from x with A x + t = 0: x = -A^-1 t, by Cramer's rule
            auto det3 = [](const double c0[3], const double c1[3], const double c2[3]) {
                return c0[0] * (c1[1] * c2[2] - c1[2] * c2[1]) - c1[0] * (c0[1] * c2[2] - c0[2] * c2[1]) + c2[0] * (c0[1] * c1[2] - c0[2] * c1[1]);
            };
            const double a0[3] = {m[0], m[1], m[2]}, a1[3] = {m[4], m[5], m[6]}, a2[3] = {m[8], m[9], m[10]}, b[3] = {-m[12], -m[13], -m[14]};
            const double d = det3(a0, a1, a2);
            if (!(std::fabs(d) > 1e-30) || !std::isfinite(d)) fail(name + ": matrix " + std::to_string(j) + " is singular or not finite");
            const double x[3] = {det3(b, a1, a2) / d, det3(a0, b, a2) / d, det3(a0, a1, b) / d};
            for (int k = 0; k < 3; ++k) {
                if (!std::isfinite(x[k])) fail(name + ": matrix " + std::to_string(j) + " is not finite");
                out[3 * j + size_t(k)] = float(x[k]);
            }
        }
        return out;
    }

    std::vector<uint32_t> read_indices(int index, size_t vertex_count) const {
        size_t count, stride;
        int components, ctype;
        const uint8_t* p = locate(index, "indices", count, stride, components, ctype);
        const std::string name = "indices accessor " + std::to_string(index);
        if (components != 1) fail(name + " is not SCALAR");
        if (ctype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ctype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            ctype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            fail(name + " has component type " + std::to_string(ctype) + ", expected an unsigned integer");
        std::vector<uint32_t> out(count);
        for (size_t i = 0; i < count; ++i) {
            const uint8_t* e = p + i * stride;
            uint32_t v;
            if (ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
                v = e[0];
            } else if (ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
                uint16_t u;
                std::memcpy(&u, e, 2);
                v = u;
            } else {
                std::memcpy(&v, e, 4);
            }
            if (v >= vertex_count)
                fail(name + ": index " + std::to_string(v) + " at position " + std::to_string(i) + " is out of range (" +
                     std::to_string(vertex_count) + " vertices)");
            out[i] = v;
        }
        return out;
    }

private:
    const tinygltf::Model& model_;
    std::string where_;
    bool quantized_;  // the file uses KHR_mesh_quantization
    mutable std::deque<std::vector<uint8_t>> dense_;  // sparse accessors made dense, while the reader lives
};

// Triangle lists from TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN index sequences.
std::vector<uint32_t> to_triangle_list(const std::vector<uint32_t>& in, int mode) {
    std::vector<uint32_t> out;
    if (mode == TINYGLTF_MODE_TRIANGLES) {
        out = in;
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (size_t i = 2; i < in.size(); ++i) {
            if (i % 2 == 0)
                out.insert(out.end(), {in[i - 2], in[i - 1], in[i]});
            else
                out.insert(out.end(), {in[i - 1], in[i - 2], in[i]});  // keep the winding
        }
    } else {  // fan
        for (size_t i = 2; i < in.size(); ++i) out.insert(out.end(), {in[0], in[i - 1], in[i]});
    }
    return out;
}

const char* mode_name(int mode) {
    switch (mode) {
    case TINYGLTF_MODE_POINTS: return "POINTS";
    case TINYGLTF_MODE_LINE: return "LINES";
    case TINYGLTF_MODE_LINE_LOOP: return "LINE_LOOP";
    case TINYGLTF_MODE_LINE_STRIP: return "LINE_STRIP";
    default: return "unknown";
    }
}

// A primitive's triangle list: its indices (or 0..n-1 without), strips and fans converted.
std::vector<uint32_t> primitive_triangles(const PrimitiveReader& reader, const tinygltf::Primitive& prim, int mode, size_t n) {
    std::vector<uint32_t> seq;
    if (prim.indices >= 0) {
        seq = reader.read_indices(prim.indices, n);
    } else {
        seq.resize(n);
        for (size_t v = 0; v < n; ++v) seq[v] = uint32_t(v);
    }
    if (mode == TINYGLTF_MODE_TRIANGLES && seq.size() % 3 != 0)
        reader.fail(std::string("mode TRIANGLES needs a multiple of 3 ") + (prim.indices >= 0 ? "indices" : "vertices") + ", found " +
                    std::to_string(seq.size()));
    std::vector<uint32_t> triangles = to_triangle_list(seq, mode);
    if (triangles.empty()) reader.fail("has no complete triangle");
    return triangles;
}

// A TEXCOORD_n attribute's (u, v). glTF allows VEC2 only, but assimp's exporter writes the UVW
// channels of Collada, FBX and 3ds files as VEC3: their u and v are read, and a third component
// that is not zero everywhere is named in `dropped` (once per attribute name), since the .tom
// keeps two.
std::vector<float> read_texcoords(const PrimitiveReader& reader, int index, const char* role, size_t n, std::vector<std::string>& dropped) {
    std::vector<float> uv = reader.read_floats(index, role, 2, 3, PrimitiveReader::Kind::texcoord, n);
    if (uv.size() != 3 * n) return uv;
    bool lost = false;
    for (size_t v = 0; v < n; ++v) {  // in place: element v moves down from 3 v to 2 v
        lost = lost || uv[3 * v + 2] != 0.0f;
        uv[2 * v] = uv[3 * v], uv[2 * v + 1] = uv[3 * v + 1];
    }
    uv.resize(2 * n);
    const std::string what = std::string("the third component of ") + role + " (3-component texture coordinates)";
    if (lost && std::find(dropped.begin(), dropped.end(), what) == dropped.end()) dropped.push_back(what);
    return uv;
}

// The attributes the importer does not interpret (TEXCOORD_2.., COLOR_1.., JOINTS_n, WEIGHTS_n,
// "_CUSTOM") and every morph target's deltas ("TARGET<k>/<ATTRIBUTE>"), carried unread.
void read_carried_streams(const PrimitiveReader& reader, const tinygltf::Primitive& prim, size_t n, Mesh& mesh) {
    auto carry = [&](int index, const std::string& name) { mesh.extra_streams.push_back(reader.read_carried(index, name, n)); };
    for (const auto& [name, index] : prim.attributes)
        if (!is_interpreted_attribute(name)) carry(index, name);
    for (size_t k = 0; k < prim.targets.size(); ++k)
        for (const auto& [name, index] : prim.targets[k]) carry(index, "TARGET" + std::to_string(k) + "/" + name);
}

// Parts made of primitives that share vertices carry the streams of those vertices.
void mark_own_attributes(std::vector<Mesh>& primitives) {
    for (Mesh& m : primitives)
        for (Part& part : m.parts) part.attributes = attribute_bits(m);
}

// Each skinned mesh's joints in its bind pose, from the skin of the first node that draws it
// with one (Mesh::joint_positions; clean_mesh checks its JOINTS_n against them).
void read_joint_positions(const tinygltf::Model& model, const std::vector<std::vector<uint32_t>>& mesh_parts, const std::string& path, bool quantized,
                          std::vector<Mesh>& meshes) {
    for (size_t ni = 0; ni < model.nodes.size(); ++ni) {
        const tinygltf::Node& node = model.nodes[ni];
        if (node.mesh < 0 || size_t(node.mesh) >= mesh_parts.size() || node.skin < 0) continue;
        const std::string where = path + ": node " + std::to_string(ni);
        if (size_t(node.skin) >= model.skins.size()) throw MeshError(where + " refers to skin " + std::to_string(node.skin) + ", which does not exist");
        for (const uint32_t mi : mesh_parts[size_t(node.mesh)])
            if (meshes[mi].joint_positions.empty()) meshes[mi].joint_positions = PrimitiveReader(model, where, quantized).joint_positions(node.skin);
    }
}

} // namespace

ImportResult import_gltf(const std::string& path, bool binary) {
    tinygltf::TinyGLTF loader;
    EmbeddedImages embedded;
    loader.SetImageLoader(keep_image, &embedded);
    std::vector<uint8_t> bytes = read_whole_file(path);
    nlohmann::json doc = check_gltf_schema(bytes, binary, path);
    const size_t slash = path.find_last_of('/');
    const std::string base_dir = slash == std::string::npos ? "." : path.substr(0, slash);
    check_gltf_references(doc, bytes, binary, base_dir, path);  // tinygltf follows indices unchecked
    const bool meshopt = prepare_meshopt(doc, bytes, binary, path);
    tinygltf::Model model;
    std::string err, warn;
    const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), unsigned(bytes.size()), base_dir)
                           : loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes.data()), unsigned(bytes.size()), base_dir);
    if (!ok) {
        std::string reason = one_line(err.empty() ? warn : err);
        // tinygltf names only the accessor; say which primitive it belongs to
        const size_t at = reason.find("accessor[");
        if (at != std::string::npos) {
            const int accessor = std::atoi(reason.c_str() + at + 9);
            const std::string users = primitives_using_accessor(doc, accessor);
            const bool draco = bytes.size() > 0 && std::string(bytes.begin(), bytes.end()).find("KHR_draco_mesh_compression") != std::string::npos;
            if (!users.empty())
                throw MeshError(path + ": " + users + ": accessor " + std::to_string(accessor) + " has no data" +
                                  (draco ? " (its KHR_draco_mesh_compression data did not decode)" : "") + " [tinygltf: " + reason + "]");
        }
        throw MeshError(path + ": cannot read glTF: " + reason);
    }
    ImportResult result;
    if (!warn.empty()) result.warnings.push_back(one_line(warn));
    for (const tinygltf::Buffer& b : model.buffers)  // external buffers (images are not read)
        if (!b.uri.empty() && !tinygltf::IsDataURI(b.uri)) result.sources.push_back(b.uri);
    for (const std::string& ext : model.extensionsRequired)
        if (!can_read_required(ext)) throw MeshError(path + ": requires extension " + ext + ", which this reader does not decode");
    if (meshopt) decode_meshopt(model, doc, path);
    const bool quantized = std::find(model.extensionsUsed.begin(), model.extensionsUsed.end(), "KHR_mesh_quantization") != model.extensionsUsed.end();

    const std::string stem = file_stem(path);
    std::vector<std::vector<uint32_t>> mesh_parts(model.meshes.size());  // glTF mesh -> imported meshes (one, or none)
    for (size_t mi = 0; mi < model.meshes.size(); ++mi) {
        const tinygltf::Mesh& gm = model.meshes[mi];
        const std::string mesh_name = gm.name.empty() ? "mesh" + std::to_string(mi) : gm.name;
        // the mesh's triangle primitives, each a part; consecutive primitives reading the same
        // vertex accessors share one copy of the vertices (one Mesh with several parts)
        std::vector<Mesh> primitives;
        const std::map<std::string, int>* previous_attributes = nullptr;
        const std::vector<std::map<std::string, int>>* previous_targets = nullptr;
        for (size_t pi = 0; pi < gm.primitives.size(); ++pi) {
            const tinygltf::Primitive& prim = gm.primitives[pi];
            const std::string where = path + ": mesh " + std::to_string(mi) + " '" + mesh_name + "' primitive " + std::to_string(pi);
            const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
            if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN) {
                result.skipped.push_back("mesh " + std::to_string(mi) + " '" + mesh_name + "' primitive " + std::to_string(pi) + ": mode " +
                                         mode_name(mode) + " has no triangles");
                continue;
            }
            PrimitiveReader reader(model, where, quantized);
            auto attr = [&](const char* key) {
                auto it = prim.attributes.find(key);
                return it == prim.attributes.end() ? -1 : it->second;
            };
            const int pos_index = attr("POSITION");
            if (pos_index < 0) reader.fail("has no POSITION attribute");
            std::vector<uint32_t> seq;
            const bool shares = previous_attributes && *previous_attributes == prim.attributes && previous_targets && *previous_targets == prim.targets &&
                                !has_texture_transform(model, prim.material) &&
                                !has_texture_transform(model, primitives.back().parts.empty() ? primitives.back().material : primitives.back().parts[0].material);
            if (shares) {
                // same vertices as the previous primitive: append its triangles as a part of that mesh
                Mesh& shared = primitives.back();
                if (shared.parts.empty()) shared.parts.push_back({0, shared.triangle_count(), shared.material, 0});
                seq = primitive_triangles(reader, prim, mode, shared.vertex_count());
                shared.parts.push_back({shared.triangle_count(), uint32_t(seq.size() / 3), prim.material, shared.parts[0].attributes});
                shared.indices.insert(shared.indices.end(), seq.begin(), seq.end());
                continue;
            }
            previous_attributes = &prim.attributes;
            previous_targets = &prim.targets;
            Mesh mesh;
            mesh.name = stem + "/" + mesh_name;
            mesh.material = prim.material;
            mesh.positions = reader.read_floats(pos_index, "POSITION", 3, 3, PrimitiveReader::Kind::position, 0);
            const size_t n = mesh.positions.size() / 3;
            if (attr("NORMAL") >= 0) mesh.normals = reader.read_floats(attr("NORMAL"), "NORMAL", 3, 3, PrimitiveReader::Kind::vector, n);
            if (attr("TEXCOORD_0") >= 0) mesh.texcoords = read_texcoords(reader, attr("TEXCOORD_0"), "TEXCOORD_0", n, result.dropped);
            if (attr("TEXCOORD_1") >= 0) mesh.texcoords1 = read_texcoords(reader, attr("TEXCOORD_1"), "TEXCOORD_1", n, result.dropped);
            if (attr("TANGENT") >= 0) mesh.tangents = reader.read_floats(attr("TANGENT"), "TANGENT", 4, 4, PrimitiveReader::Kind::vector, n);
            if (attr("COLOR_0") >= 0) {
                std::vector<float> c = reader.read_floats(attr("COLOR_0"), "COLOR_0", 3, 4, PrimitiveReader::Kind::color, n);
                if (c.size() == n * 3) {
                    mesh.colors.resize(n * 4);
                    for (size_t v = 0; v < n; ++v) {
                        for (int k = 0; k < 3; ++k) mesh.colors[4 * v + size_t(k)] = c[3 * v + size_t(k)];
                        mesh.colors[4 * v + 3] = 1.0f;
                    }
                } else {
                    mesh.colors.swap(c);
                }
            }
            read_carried_streams(reader, prim, n, mesh);
            if (const std::string w = bake_texture_transform(model, prim.material, mesh); !w.empty())
                result.warnings.push_back(mesh.name + ": " + w);
            mesh.indices = primitive_triangles(reader, prim, mode, n);
            for (size_t i = 0; i < mesh.positions.size(); ++i)
                if (!std::isfinite(mesh.positions[i])) reader.fail("POSITION of vertex " + std::to_string(i / 3) + " is not finite");
            primitives.push_back(std::move(mesh));
        }
        if (primitives.empty()) continue;
        mark_own_attributes(primitives);
        mesh_parts[mi].push_back(uint32_t(result.meshes.size()));
        result.meshes.push_back(join_parts(primitives, stem + "/" + mesh_name));
    }
    read_joint_positions(model, mesh_parts, path, quantized, result.meshes);
    TextureSources textures;
    result.scene = gltf_scene(model, doc, mesh_parts, embedded, path, textures);
    result.scene.gltf = source_gltf(model, doc, mesh_parts, textures);
    result.dropped = gltf_dropped(doc, !result.scene.gltf.empty(), std::move(result.dropped));
    if (result.meshes.empty() && result.skipped.empty()) throw MeshError(path + ": the glTF file has no meshes");
    return result;
}

} // namespace tom::detail
