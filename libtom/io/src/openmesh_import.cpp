// OBJ, PLY, OFF and STL import through OpenMesh (its readers triangulate polygons as fans and
// give non-manifold faces vertices of their own). OpenMesh reports problems on its omerr()
// stream; that stream is captured here so the reasons reach the caller instead of stderr.

// GCC 12 reports -Wmaybe-uninitialized inside OpenMesh's PropertyT<Vec3f>::push_back (a
// value-initialised vector it cannot see through); the warning is about OpenMesh's header code,
// instantiated in this file.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <algorithm>
#include <array>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <vector>

#include "import_backends.h"
#include "mesh_file_check.h"
#include "platform.h"
#include "tom/errors.h"

namespace tom::detail {

namespace {

struct Traits : OpenMesh::DefaultTraits {
    typedef OpenMesh::Vec4f Color;
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<Traits>;

// OpenMesh's importer, with two things done differently:
// - every attribute a file may leave out starts defined (OpenMesh's vectors default to
//   uninitialised memory: an OBJ face without `vt` among faces with, or a vertex no face gives a
//   normal, would carry whatever was there, and the output would change from run to run);
// - a face's texture coordinates go to the corners they belong to, by vertex: OpenMesh writes
//   them around the first triangle only, which misplaces them on a polygon it fans into
//   triangles and on a non-manifold face it re-adds with fresh copies of its vertices.
class Importer : public OpenMesh::IO::ImporterT<OmMesh> {
  public:
    using Base = OpenMesh::IO::ImporterT<OmMesh>;
    Importer(OmMesh& mesh, const ObjGroups* groups) : Base(mesh), mesh_(mesh), groups_(groups) {}

    OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3f& p) override { return defined(Base::add_vertex(p)); }
    OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3d& p) override { return defined(Base::add_vertex(p)); }
    OpenMesh::VertexHandle add_vertex() override { return defined(Base::add_vertex()); }

    OpenMesh::FaceHandle add_face(const VHandles& polygon) override {
        first_face_ = mesh_.n_faces();
        first_copy_ = mesh_.n_vertices();
        polygon_ = polygon;
        const OpenMesh::FaceHandle fh = Base::add_face(polygon);
        for (size_t v = first_copy_; v < mesh_.n_vertices(); ++v)  // copies of the corners, in order
            copies_.push_back({OpenMesh::VertexHandle(int(v)), polygon_[v - first_copy_]});
        if (groups_) face_material_.resize(mesh_.n_faces(), material_of(polygon));
        for (size_t f = first_face_; f < mesh_.n_faces(); ++f)
            for (auto h : mesh_.fh_range(OpenMesh::FaceHandle(int(f)))) mesh_.set_texcoord2D(h, OmMesh::TexCoord2D(0, 0));
        return fh;
    }
    void add_face_texcoords(OpenMesh::FaceHandle, OpenMesh::VertexHandle, const std::vector<OpenMesh::Vec2f>& uv) override {
        for (size_t f = first_face_; f < mesh_.n_faces(); ++f)
            for (auto h : mesh_.fh_range(OpenMesh::FaceHandle(int(f)))) {
                const OpenMesh::VertexHandle v = mesh_.to_vertex_handle(h);
                // the polygon's own vertex, or the copy OpenMesh made of its corner (in order)
                size_t corner = size_t(std::find(polygon_.begin(), polygon_.end(), v) - polygon_.begin());
                if (corner == polygon_.size() && size_t(v.idx()) >= first_copy_) corner = size_t(v.idx()) - first_copy_;
                // v flipped into glTF's convention here, so that a corner without one keeps (0, 0)
                if (corner < uv.size()) mesh_.set_texcoord2D(h, OmMesh::TexCoord2D(uv[corner][0], flip_v(uv[corner][1])));
            }
    }

    // the vertices OpenMesh made for faces it could only add with vertices of their own
    // (non-manifold input), each with the file's vertex it copies
    const std::vector<std::pair<OpenMesh::VertexHandle, OpenMesh::VertexHandle>>& copies() const { return copies_; }
    /// OBJ: per OpenMesh face, the material group (ObjGroups::materials index) of its face line
    const std::vector<int32_t>& face_material() const { return face_material_; }

  private:
    // The face line a polygon came from: the next line, from the last one matched, whose vertices
    // include all of the polygon's (OpenMesh may drop repeated corners or a line it cannot add).
    // The search looks a bounded way ahead, so no input makes it quadratic; a polygon matched
    // nowhere takes the group of the line after the last match.
    int32_t material_of(const VHandles& polygon) {
        const ObjGroups& g = *groups_;
        constexpr size_t kLookAhead = 64;
        const size_t end_line = std::min(g.face_material.size(), cursor_ + kLookAhead);
        for (size_t line = cursor_; line < end_line; ++line) {
            const uint32_t* begin = g.face_vertices.data() + g.face_first[line];
            const uint32_t* end = g.face_vertices.data() + g.face_first[line + 1];
            bool all = true;
            for (const OpenMesh::VertexHandle& v : polygon) all = all && std::find(begin, end, uint32_t(v.idx())) != end;
            if (all) {
                cursor_ = line + 1;
                return g.face_material[line];
            }
        }
        return cursor_ < g.face_material.size() ? g.face_material[cursor_] : g.face_material.empty() ? -1 : g.face_material.back();
    }

    OmMesh& mesh_;
    const ObjGroups* groups_;
    size_t cursor_ = 0;
    std::vector<int32_t> face_material_;
    size_t first_face_ = 0, first_copy_ = 0;
    VHandles polygon_;
    std::vector<std::pair<OpenMesh::VertexHandle, OpenMesh::VertexHandle>> copies_;
    OpenMesh::VertexHandle defined(OpenMesh::VertexHandle v) {
        if (!v.is_valid()) return v;
        mesh_.set_normal(v, OmMesh::Normal(0, 0, 0));  // a zero normal is recomputed by clean_mesh
        mesh_.set_texcoord2D(v, OmMesh::TexCoord2D(0, 0));
        mesh_.set_color(v, OmMesh::Color(1, 1, 1, 1));
        return v;
    }
};

// OpenMesh's streams and reader registry are global: one reader at a time.
std::mutex& openmesh_mutex() {
    static std::mutex m;
    return m;
}

// Collapses OpenMesh's messages into "message (N times)" lines.
std::vector<std::string> summarize(const std::string& text) {
    std::map<std::string, int> counts;
    std::vector<std::string> order;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty()) continue;
        if (counts[line]++ == 0) order.push_back(line);
    }
    std::vector<std::string> out;
    for (const std::string& l : order) out.push_back(counts[l] > 1 ? l + " (" + std::to_string(counts[l]) + " times)" : l);
    return out;
}

// The canonical text in a temporary file of the same extension, removed with this object.
// OpenMesh reads files, not streams, here: its readers keep the options they sniffed from the
// last file (an OFF stream read after a binary OFF file took its text for binary).
struct CanonicalFile {
    std::string path;
    CanonicalFile(const std::string& text, const std::string& extension) {
        static std::atomic<unsigned> counter{0};
        path = (std::filesystem::temp_directory_path() /
                ("tom-import-" + std::to_string(detail::process_id()) + "-" + std::to_string(counter++) + "." + extension)).string();
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(text.data(), std::streamsize(text.size()));
        if (!out.flush()) {
            std::error_code ignored;
            std::filesystem::remove(path, ignored);
            throw IoError("cannot write the temporary file '" + path + "' OpenMesh reads");
        }
    }
    ~CanonicalFile() {
        std::error_code ignored;
        std::filesystem::remove(path, ignored);
    }
    CanonicalFile(const CanonicalFile&) = delete;
    CanonicalFile& operator=(const CanonicalFile&) = delete;
};

// OBJ `usemtl` groups as parts: the triangles sorted by material (stable; faces before any usemtl
// first), one part per material used; one material alone is the mesh's.
void group_by_material(Mesh& mesh, const std::vector<int32_t>& face_material) {
    const uint32_t m = mesh.triangle_count();
    std::vector<uint32_t> order(m);
    for (uint32_t t = 0; t < m; ++t) order[t] = t;
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return face_material[a] < face_material[b]; });
    std::vector<uint32_t> indices(mesh.indices.size());
    for (uint32_t t = 0; t < m; ++t) std::copy_n(&mesh.indices[3 * size_t(order[t])], 3, &indices[3 * size_t(t)]);
    mesh.indices.swap(indices);
    const uint32_t own = attribute_bits(mesh);
    for (uint32_t t = 0; t < m; ++t) {
        const int32_t material = face_material[order[t]];
        if (mesh.parts.empty() || mesh.parts.back().material != material) mesh.parts.push_back({t, 0, material, own});
        ++mesh.parts.back().triangle_count;
    }
    mesh.material = mesh.parts.empty() ? -1 : mesh.parts[0].material;
    if (mesh.parts.size() == 1) mesh.parts.clear();
}

} // namespace

std::string file_stem(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
    const size_t dot = name.find_last_of('.');
    return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

ImportResult import_openmesh(const std::string& path, const std::string& extension) {
    // OpenMesh's readers trust what the file announces: they read the checked, canonical form
    // (from a temporary file) or, for binary OFF and STL, the checked file itself
    ObjGroups groups;
    const std::string canonical = check_mesh_file(path, extension, extension == "obj" ? &groups : nullptr);
    OmMesh om;
    om.request_vertex_normals();
    om.request_vertex_texcoords2D();
    om.request_halfedge_texcoords2D();  // OBJ: a texture coordinate per face corner (UV seams)
    om.request_vertex_colors();
    OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexNormal | OpenMesh::IO::Options::VertexTexCoord |
                                OpenMesh::IO::Options::FaceTexCoord | OpenMesh::IO::Options::VertexColor | OpenMesh::IO::Options::ColorFloat;
    std::string messages;
    Importer importer(om, extension == "obj" && !groups.materials.empty() ? &groups : nullptr);
    bool ok;
    {
        std::lock_guard<std::mutex> lock(openmesh_mutex());
        // one sink, connected once: OpenMesh's stream multiplexer allocates a target on every
        // connect and never frees it, so a connect per import would leak in a long process
        static std::ostringstream sink;
        static const bool connected = [] {
            ::omerr().disconnect(std::cerr);
            ::omlog().disable();
            ::omout().disable();
            ::omerr().connect(sink);
            return true;
        }();
        (void)connected;
        sink.str("");
        sink.clear();
        if (canonical.empty()) {
            ok = OpenMesh::IO::IOManager().read(path, importer, opt);
        } else {
            const CanonicalFile file(canonical, extension);
            ok = OpenMesh::IO::IOManager().read(file.path, importer, opt);
        }
        ::omerr().flush();
        messages = sink.str();
    }
    // STL holds positions (and face normals) only, but its reader leaves the requested vertex
    // attribute flags set: never trust them for STL
    if (extension == "stl") {
        opt -= OpenMesh::IO::Options::VertexNormal;
        opt -= OpenMesh::IO::Options::VertexTexCoord;
        opt -= OpenMesh::IO::Options::FaceTexCoord;
        opt -= OpenMesh::IO::Options::VertexColor;
    }
    ImportResult result;
    result.warnings = summarize(messages);
    if (!ok) {
        std::string reason = result.warnings.empty() ? "the " + extension + " reader rejected it" : result.warnings.front();
        throw MeshError(path + ": cannot read as ." + extension + ": " + reason);
    }
    if (om.n_faces() == 0) throw MeshError(path + ": no triangles or polygons in the file");

    // OpenMesh gives a face it cannot add (non-manifold) vertices of its own, with uninitialised
    // attributes: they take their original's
    for (const auto& [copy, original] : importer.copies()) {
        om.set_normal(copy, om.normal(original));
        om.set_texcoord2D(copy, om.texcoord2D(original));
        om.set_color(copy, om.color(original));
    }
    if (!importer.copies().empty()) result.warnings.push_back(std::to_string(importer.copies().size()) + " vertices duplicated for non-manifold faces");
    // Texture coordinates per face corner (OBJ's v/vt): a vertex with different ones on different
    // faces is split into one vertex per distinct coordinate (a UV seam), never smeared into one.
    const bool corner_uv = opt.check(OpenMesh::IO::Options::FaceTexCoord);
    std::vector<uint32_t> corners;  // per face corner: the output vertex
    std::vector<std::pair<uint32_t, std::array<float, 2>>> wedges;  // output vertex -> (OpenMesh vertex, uv)
    corners.reserve(om.n_faces() * 3);
    if (corner_uv) {
        std::map<std::pair<int, std::array<float, 2>>, uint32_t> wedge_of;
        for (auto fh : om.faces())
            for (auto h : om.fh_range(fh)) {  // each corner with the coordinate the Importer put there
                const std::array<float, 2> t{float(om.texcoord2D(h)[0]), float(om.texcoord2D(h)[1])};
                const int v = om.to_vertex_handle(h).idx();
                const auto [it, fresh] = wedge_of.emplace(std::make_pair(v, t), uint32_t(wedges.size()));
                if (fresh) wedges.push_back({uint32_t(v), t});
                corners.push_back(it->second);
            }
    } else {
        for (auto vh : om.vertices()) wedges.push_back({uint32_t(vh.idx()), {0.0f, 0.0f}});
        for (auto fh : om.faces())
            for (auto vh : om.fv_range(fh)) corners.push_back(uint32_t(vh.idx()));
    }
    Mesh mesh;
    mesh.name = file_stem(path);
    const size_t n = wedges.size();
    mesh.positions.resize(n * 3);
    for (size_t w = 0; w < n; ++w) {
        const auto p = om.point(OmMesh::VertexHandle(int(wedges[w].first)));
        for (int k = 0; k < 3; ++k) mesh.positions[3 * w + size_t(k)] = float(p[k]);
    }
    if (opt.check(OpenMesh::IO::Options::VertexNormal)) {
        mesh.normals.resize(n * 3);
        for (size_t w = 0; w < n; ++w) {
            const auto q = om.normal(OmMesh::VertexHandle(int(wedges[w].first)));
            for (int k = 0; k < 3; ++k) mesh.normals[3 * w + size_t(k)] = float(q[k]);
        }
    }
    if (corner_uv || opt.check(OpenMesh::IO::Options::VertexTexCoord)) {
        mesh.texcoords.resize(n * 2);
        for (size_t w = 0; w < n; ++w) {
            const auto t = corner_uv ? OmMesh::TexCoord2D(wedges[w].second[0], wedges[w].second[1]) : om.texcoord2D(OmMesh::VertexHandle(int(wedges[w].first)));
            mesh.texcoords[2 * w] = float(t[0]);
            // OBJ's and PLY's v grows up the image, glTF's and the .tom's down (corners: flipped as read)
            mesh.texcoords[2 * w + 1] = corner_uv ? float(t[1]) : flip_v(float(t[1]));
        }
    }
    if (opt.check(OpenMesh::IO::Options::VertexColor)) {
        mesh.colors.resize(n * 4);
        for (size_t w = 0; w < n; ++w) {
            const auto c = om.color(OmMesh::VertexHandle(int(wedges[w].first)));
            for (int k = 0; k < 4; ++k) mesh.colors[4 * w + size_t(k)] = float(c[k]);
            // files without alpha leave it 0 in a float colour: treat as opaque
            if (!opt.check(OpenMesh::IO::Options::ColorAlpha)) mesh.colors[4 * w + 3] = 1.0f;
        }
    }
    mesh.indices = std::move(corners);
    if (importer.face_material().size() == mesh.triangle_count()) group_by_material(mesh, importer.face_material());
    if (extension == "obj" && (!groups.materials.empty() || !groups.libraries.empty()))
        result.scene.materials = read_obj_materials(path, groups.libraries, groups.materials, result.warnings);
    if (extension == "obj")
        for (std::string name : groups.libraries) {
            std::replace(name.begin(), name.end(), '\\', '/');  // as read_obj_materials opens it
            result.sources.push_back(name);
        }
    result.meshes.push_back(std::move(mesh));
    return result;
}

} // namespace tom::detail
