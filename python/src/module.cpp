// The Python package's native module, tom._tom (pybind11 on numpy): files mapped with their
// streams as zero-copy read-only arrays, extraction into caller arrays, building, writing,
// importing and reports. The GIL is released while the library works.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "holders.h"
#include "tom/metrics/report_json.h"
#include "tom/builder/builder.h"
#include "tom/builder/mesh.h"
#include "tom/builder/refit.h"
#include "tom/builder/writer.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/stream/stream_file.h"
#include "tom/format.h"
#include "tom/io/import.h"
#include "tom/metrics/report.h"
#include "tom/tom.h"

namespace py = pybind11;

namespace {

// ---- what the Python objects hold ---------------------------------------------------------

using tom_python::FileHolder;
using tom_python::FileMesh;

// A source mesh (imported, or made from arrays).
struct SourceMesh {
    std::shared_ptr<tom::Mesh> mesh;
};

// A built mesh and its view (pointers into `built`, which never moves).
struct BuiltMesh {
    std::shared_ptr<tom::TomMesh> built;
    tom::MeshView view;
};

// ---- arrays -----------------------------------------------------------------------------

// A read-only (rows x columns) array over `data`, alive as long as `base` is.
template <class T>
py::object readonly_array(const T* data, size_t rows, size_t columns, py::handle base) {
    if (!data) return py::none();
    py::array_t<T> a({rows, columns}, {sizeof(T) * columns, sizeof(T)}, data, base);
    a.attr("setflags")(py::arg("write") = false);
    return std::move(a);
}

py::object index_array(const void* data, uint32_t index_size, size_t rows, size_t columns, py::handle base) {
    return index_size == 2 ? readonly_array(static_cast<const uint16_t*>(data), rows, columns, base)
                           : readonly_array(static_cast<const uint32_t*>(data), rows, columns, base);
}

// A float array of shape (n, columns) copied into `out` (empty for None).
void take_floats(const py::object& array, size_t columns, const char* what, std::vector<float>& out, std::optional<size_t> rows = std::nullopt) {
    if (array.is_none()) return;
    auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(array);
    if (!a || a.ndim() != 2 || size_t(a.shape(1)) != columns)
        throw tom::ArgumentError(std::string(what) + " must be an array of shape (n, " + std::to_string(columns) + ")");
    if (rows && size_t(a.shape(0)) != *rows)
        throw tom::ArgumentError(std::string(what) + " has " + std::to_string(a.shape(0)) + " rows, the positions " + std::to_string(*rows));
    out.assign(a.data(), a.data() + a.size());
}

std::shared_ptr<tom::Mesh> make_mesh(const py::object& positions, const py::object& triangles, const py::object& normals, const py::object& uv, const std::string& name) {
    auto m = std::make_shared<tom::Mesh>();
    m->name = name;
    take_floats(positions, 3, "positions", m->positions);
    const size_t n = m->positions.size() / 3;
    take_floats(normals, 3, "normals", m->normals, n);
    take_floats(uv, 2, "uv", m->texcoords, n);
    auto t = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(triangles);
    if (!t || t.ndim() != 2 || t.shape(1) != 3) throw tom::ArgumentError("triangles must be an integer array of shape (t, 3)");
    m->indices.resize(size_t(t.size()));
    for (size_t c = 0; c < m->indices.size(); ++c) {
        const int64_t i = t.data()[c];
        if (i < 0 || uint64_t(i) >= n) throw tom::ArgumentError("triangles: index " + std::to_string(i) + " at corner " + std::to_string(c) + " is not one of the " + std::to_string(n) + " vertices");
        m->indices[c] = uint32_t(i);
    }
    return m;
}

// ---- extraction ---------------------------------------------------------------------------

// The resolution the keywords ask for: one of a fraction of the triangles, a vertex count or a
// triangle count; none gives the full mesh.
// A fraction or a triangle count goes no lower than `floor` (tom::floor_vertex_count); a vertex
// count is taken as asked.
uint32_t resolution(const tom::MeshView& v, const py::object& fraction, const py::object& vertices, const py::object& triangles,
                    tom::Floor floor = tom::Floor::usable) {
    const int given = int(!fraction.is_none()) + int(!vertices.is_none()) + int(!triangles.is_none());
    if (given > 1) throw tom::ArgumentError("extract: give one of fraction, vertices and triangles");
    if (!fraction.is_none()) {
        const double f = fraction.cast<double>();
        if (!(f >= 0.0 && f <= 1.0)) throw tom::ArgumentError("extract: fraction " + std::to_string(f) + " is outside [0, 1]");
        return tom::vertex_count_for_fraction(v, f, floor);
    }
    if (!vertices.is_none()) return vertices.cast<uint32_t>();
    if (!triangles.is_none()) return tom::vertex_count_for_triangles(v, triangles.cast<uint32_t>(), floor);
    return v.vertex_count;
}

template <class Index>
uint32_t extract_into(const tom::MeshView& v, uint32_t n, py::array& out, tom::Extracted& e) {
    const size_t capacity = size_t(out.size());
    if (capacity / 3 < v.triangle_count) {
        const uint32_t needed = tom::active_triangle_count(v, n);
        if (capacity / 3 < needed)
            throw tom::ArgumentError("extract: the level has " + std::to_string(needed) + " triangles, out holds " + std::to_string(capacity) + " indices");
    }
    Index* data = static_cast<Index*>(out.mutable_data());
    {
        py::gil_scoped_release release;
        e = tom::extract(v, n, data, capacity);
    }
    return e.triangle_count;
}

py::tuple extract(const tom::MeshView& v, const py::object& fraction, const py::object& vertices, const py::object& triangles, const py::object& out) {
    const uint32_t n = resolution(v, fraction, vertices, triangles);
    py::array target;
    if (out.is_none()) {
        target = py::array_t<uint32_t>(std::vector<py::ssize_t>{py::ssize_t(v.triangle_count), 3});
    } else {
        if (!py::isinstance<py::array>(out)) throw tom::ArgumentError("extract: out must be a numpy array of uint32 or uint16");
        target = py::reinterpret_borrow<py::array>(out);
        if (!(target.flags() & py::array::c_style) || !target.writeable()) throw tom::ArgumentError("extract: out must be C-contiguous and writeable");
    }
    tom::Extracted e;
    if (target.dtype().is(py::dtype::of<uint32_t>())) {
        extract_into<uint32_t>(v, n, target, e);
    } else if (target.dtype().is(py::dtype::of<uint16_t>())) {
        const uint32_t clamped = std::min(std::max(n, v.min_vertex_count), v.vertex_count);
        if (clamped > 65536) throw tom::ArgumentError("extract: resolution " + std::to_string(clamped) + " has more vertices than uint16 indices address");
        extract_into<uint16_t>(v, n, target, e);
    } else {
        throw tom::ArgumentError("extract: out must be a numpy array of uint32 or uint16");
    }
    // a (k, 3) view of the first 3k indices of `target`: no copy
    const py::ssize_t k = py::ssize_t(e.triangle_count);
    const py::ssize_t item = target.itemsize();
    py::array level(target.dtype(), std::vector<py::ssize_t>{k, 3}, std::vector<py::ssize_t>{3 * item, item}, target.mutable_data(), target);
    return py::make_tuple(level, e.vertex_count);
}

const char* kExtractDoc = R"(Index buffer of one level: (indices, vertex_count).

Give at most one of fraction (of the triangles, in [0, 1]), vertices (the resolution) and
triangles (at least that many); none gives the full mesh. indices is a (k, 3) array of
vertex numbers, all < vertex_count: draw vertices [0, vertex_count) with it. With out (a
C-contiguous uint32 or uint16 array of at least 3 * k elements) the indices are written
into out and the returned array is a view of it: nothing is allocated.)";

// ---- building, writing, reports -----------------------------------------------------------

tom::Predicate parse_predicate(const std::string& s) {
    if (s == "quadric") return tom::Predicate::quadric;
    if (s == "memoryless") return tom::Predicate::memoryless;
    throw tom::ArgumentError("predicate '" + s + "' is neither 'quadric' nor 'memoryless'");
}

tom::Strategy parse_strategy(const std::string& s) {
    if (s == "passes") return tom::Strategy::passes;
    if (s == "heap") return tom::Strategy::heap;
    throw tom::ArgumentError("strategy '" + s + "' is neither 'passes' nor 'heap'");
}

tom::WriteOptions write_options(const std::string& index_size) {
    tom::WriteOptions o;
    if (index_size == "auto") o.index_size = tom::IndexSize::automatic;
    else if (index_size == "16") o.index_size = tom::IndexSize::bits16;
    else if (index_size == "32") o.index_size = tom::IndexSize::bits32;
    else throw tom::ArgumentError("index_size '" + index_size + "' is not 'auto', '16' or '32'");
    return o;
}

BuiltMesh build_mesh(const tom::Mesh& source, const tom::BuildParams& params, const tom::CleanOptions& clean) {
    BuiltMesh out;
    {
        py::gil_scoped_release release;
        tom::Mesh cleaned = source;
        tom::clean_mesh(cleaned, clean);
        out.built = std::make_shared<tom::TomMesh>(tom::build(cleaned, params));
    }
    out.view = out.built->view();
    return out;
}

std::vector<tom::TomMesh> built_meshes(const std::vector<BuiltMesh>& meshes) {
    std::vector<tom::TomMesh> out;
    for (const BuiltMesh& m : meshes) out.push_back(*m.built);
    return out;
}

// The report of `built` against `original`, cleaned as tom.build cleans its input.
py::object report(const tom::Mesh& original, const BuiltMesh& built, const std::vector<double>& levels, bool error_curve) {
    tom::ReportParams params;
    params.levels = levels;
    params.error_curve = error_curve;
    tom::ReportContext context;
    context.file = original.name;
    context.params = params;
    std::string text;
    {
        py::gil_scoped_release release;
        tom::Mesh cleaned = original;
        tom::clean_mesh(cleaned);
        const auto start = std::chrono::steady_clock::now();
        const tom::MeshReport r = tom::make_report(cleaned, *built.built, params);
        context.report_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        text = tom::report_json(r, context).dump();
    }
    return py::module_::import("json").attr("loads")(text);
}

// ---- a mesh view's properties, shared by file meshes and built meshes ---------------------

template <class Class, class ViewOf>
void mesh_properties(Class& c, ViewOf view_of) {
    c.def_property_readonly("name", [view_of](py::object self) { return std::string(view_of(self).name); })
        .def_property_readonly("vertex_count", [view_of](py::object self) { return view_of(self).vertex_count; })
        .def_property_readonly("triangle_count", [view_of](py::object self) { return view_of(self).triangle_count; })
        .def_property_readonly("min_vertex_count", [view_of](py::object self) { return view_of(self).min_vertex_count; }, "The coarsest resolution.")
        .def_property_readonly("material", [view_of](py::object self) { return view_of(self).material; })
        .def_property_readonly("positions", [view_of](py::object self) { const tom::MeshView& v = view_of(self); return readonly_array(v.positions, v.vertex_count, 3, self); },
                               "(n, 3) float32, read-only, in resolution order: the first k rows are the mesh at resolution k.")
        .def_property_readonly("normals", [view_of](py::object self) { const tom::MeshView& v = view_of(self); return readonly_array(v.normals, v.vertex_count, 3, self); })
        .def_property_readonly("uv", [view_of](py::object self) { const tom::MeshView& v = view_of(self); return readonly_array(v.texcoords, v.vertex_count, 2, self); },
                               "(n, 2) float32 TEXCOORD_0, or None.")
        .def_property_readonly("colors", [view_of](py::object self) { const tom::MeshView& v = view_of(self); return readonly_array(v.colors, v.vertex_count, 4, self); })
        .def_property_readonly("triangles", [view_of](py::object self) { const tom::MeshView& v = view_of(self); return index_array(v.triangles, v.index_size, v.triangle_count, 3, self); },
                               "(t, 3) uint16 or uint32, read-only, in death order (the original corners).")
        .def_property_readonly("substitute", [view_of](py::object self) { const tom::MeshView& v = view_of(self); return index_array(v.substitute, v.index_size, v.vertex_count, 1, self).attr("reshape")(-1); },
                               "(n,) each vertex's substitute: substitute[i] < i for i >= min_vertex_count.")
        .def_property_readonly("usable_floor", [view_of](py::object self) { return tom::floor_vertex_count(view_of(self)); },
                               "The coarsest resolution a fraction or triangle count picks: the usable floor tombuild stored (--floor-error), "
                               "or min_vertex_count.")
        .def("vertex_count_for", [view_of](py::object self, py::object fraction, py::object triangles, bool below_floor) {
                 return resolution(view_of(self), fraction, py::none(), triangles, below_floor ? tom::Floor::coarsest : tom::Floor::usable);
             }, py::arg("fraction") = py::none(), py::arg("triangles") = py::none(), py::arg("below_floor") = false,
             "The resolution for a fraction of the triangles, or for at least a triangle count; not below usable_floor unless below_floor.")
        .def("active_triangles", [view_of](py::object self, uint32_t n) { return tom::active_triangle_count(view_of(self), n); }, py::arg("vertices"),
             "Triangles alive at a resolution.")
        .def_property_readonly("carried_streams", [view_of](py::object self) {
                 const tom::MeshView& v = view_of(self);
                 py::dict out;
                 for (uint32_t k = 0; k < v.extra_stream_count; ++k) {
                     const tom::VertexStreamView& x = v.extra_streams[k];
                     const size_t rows = v.vertex_count, cols = x.components;
                     py::object a;
                     switch (x.component_type) {
                     case 5120: a = readonly_array(reinterpret_cast<const int8_t*>(x.data), rows, cols, self); break;
                     case 5121: a = readonly_array(reinterpret_cast<const uint8_t*>(x.data), rows, cols, self); break;
                     case 5122: a = readonly_array(reinterpret_cast<const int16_t*>(x.data), rows, cols, self); break;
                     case 5123: a = readonly_array(reinterpret_cast<const uint16_t*>(x.data), rows, cols, self); break;
                     case 5125: a = readonly_array(reinterpret_cast<const uint32_t*>(x.data), rows, cols, self); break;
                     default: a = readonly_array(reinterpret_cast<const float*>(x.data), rows, cols, self); break;
                     }
                     out[py::str(std::string(x.name))] = a;
                 }
                 return out;
             }, "{name: (n, components) read-only array} of the glTF attributes carried unread (JOINTS_0, WEIGHTS_0, TEXCOORD_2, ...) and the morph targets' deltas ('TARGET0/POSITION'), in resolution order; empty for a built mesh.")
        .def_property_readonly("parts", [view_of](py::object self) {
                 const tom::MeshView& v = view_of(self);
                 py::list out;
                 for (uint32_t p = 0; p < tom::part_count(v); ++p) {
                     const tom::Part part = tom::part_at(v, p);
                     out.append(py::make_tuple(part.first_triangle, part.triangle_count, part.material));
                 }
                 return out;
             }, "[(first_triangle, triangle_count, material)] per part (one for a mesh without parts): ranges of `triangles`.")
        .def("draws", [view_of](py::object self, py::object fraction, py::object vertices, py::object triangles) {
                 const tom::MeshView& v = view_of(self);
                 const uint32_t n = resolution(v, fraction, vertices, triangles);
                 py::list out;
                 uint32_t first = 0;
                 for (uint32_t p = 0; p < tom::part_count(v); ++p) {
                     const uint32_t count = tom::active_part_triangle_count(v, p, n);
                     out.append(py::make_tuple(first, count, tom::part_at(v, p).material));
                     first += count;
                 }
                 return out;
             }, py::kw_only(), py::arg("fraction") = py::none(), py::arg("vertices") = py::none(), py::arg("triangles") = py::none(),
             "[(first_row, row_count, material)] per part: where each part's triangles lie in what extract() returns for the same level.")
        .def("extract", [view_of](py::object self, py::object fraction, py::object vertices, py::object triangles, py::object out) {
                 return extract(view_of(self), fraction, vertices, triangles, out);
             }, py::kw_only(), py::arg("fraction") = py::none(), py::arg("vertices") = py::none(), py::arg("triangles") = py::none(), py::arg("out") = py::none(), kExtractDoc)
        .def("refit", [view_of](py::object self, py::object fraction, py::object vertices, py::object triangles) {
                 const tom::MeshView v = view_of(self);
                 const tom::RefitLevel r = tom::refit_level(v, resolution(v, fraction, vertices, triangles));
                 const uint32_t n = r.resolution;
                 py::dict out;
                 auto put = [&](const char* key, const std::vector<float>& x, py::ssize_t width) {
                     if (x.empty()) return;
                     py::array_t<float> a(std::vector<py::ssize_t>{py::ssize_t(n), width});
                     std::copy(x.begin(), x.begin() + ptrdiff_t(width) * n, a.mutable_data());
                     out[key] = a;
                 };
                 put("positions", r.positions, 3), put("normals", r.normals, 3), put("uv", r.texcoords, 2), put("uv1", r.texcoords1, 2);
                 put("colors", r.colors, 4), put("tangents", r.tangents, 4);
                 return out;
             }, py::kw_only(), py::arg("fraction") = py::none(), py::arg("vertices") = py::none(), py::arg("triangles") = py::none(),
             "One level re-fitted to be written on its own, as tomextract --refit: a dict of (n, k) float32 arrays for the n vertices "
             "extract() draws at the same level, 'positions' and those of 'normals', 'uv', 'uv1', 'colors', 'tangents' the mesh has. "
             "Its vertices move to where they best stand for the surface they replaced, their attributes the source's there; seams, "
             "hard edges, open edges and where parts meet stay joined.");
}

// tom.Error and one subclass per kind the library throws, with its message.
void add_errors(py::module_& m) {
    static py::exception<tom::Error> error(m, "Error");
    static py::exception<tom::FormatError> format_error(m, "FormatError", error.ptr());
    static py::exception<tom::MeshError> import_error(m, "MeshError", error.ptr());
    static py::exception<tom::IoError> io_error(m, "IoError", error.ptr());
    static py::exception<tom::ArgumentError> argument_error(m, "ArgumentError", error.ptr());
    static py::exception<tom::ParseError> parse_error(m, "ParseError", error.ptr());
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const tom::FormatError& e) {
            format_error(e.what());
        } catch (const tom::MeshError& e) {
            import_error(e.what());
        } catch (const tom::IoError& e) {
            io_error(e.what());
        } catch (const tom::ArgumentError& e) {
            argument_error(e.what());
        } catch (const tom::ParseError& e) {
            parse_error(e.what());
        } catch (const tom::Error& e) {
            error(e.what());
        }
    });

}

// tom.File, tom.FileMesh, tom.open and tom.open_bytes: mapped files and views into them.
void add_files(py::module_& m) {
    py::class_<FileHolder, std::shared_ptr<FileHolder>> file(m, "File", "A validated .tom file, mapped read-only; its arrays keep it alive.");
    py::class_<FileMesh> file_mesh(m, "FileMesh", "One mesh of a .tom file. Its arrays are views into the file: no copy.");
    mesh_properties(file_mesh, [](py::object self) -> const tom::MeshView& { return self.cast<const FileMesh&>().view(); });

    file.def_property_readonly("path", [](const FileHolder& f) { return f.file.path(); })
        .def_property_readonly("provenance", [](const FileHolder& f) -> py::object {
            if (f.file.provenance().empty()) return py::none();
            return py::str(f.file.provenance().data(), f.file.provenance().size());
        }, "What made the file (PROV: tombuild's JSON text with the input's digest, sources and options), or None")
        .def_property_readonly("meshes", [](const std::shared_ptr<FileHolder>& f) {
            std::vector<FileMesh> out;
            for (uint32_t i = 0; i < f->file.mesh_count(); ++i) out.push_back({f, i});
            return out;
        })
        .def_property_readonly("materials", [](const FileHolder& f) {
            py::list out;
            for (const tom::Material& mat : f.file.scene().materials) {
                py::list textures;
                for (const tom::TextureRef& t : mat.textures)
                    textures.append(py::dict(py::arg("role") = tom::to_string(t.role), py::arg("texcoord") = t.texcoord, py::arg("uri") = t.uri, py::arg("mime_type") = t.mime_type,
                                             py::arg("image") = t.image >= 0 ? py::object(py::int_(t.image)) : py::object(py::none())));
                out.append(py::dict(py::arg("name") = mat.name, py::arg("base_color") = std::vector<float>(mat.base_color, mat.base_color + 4),
                                    py::arg("metallic") = mat.metallic, py::arg("roughness") = mat.roughness, py::arg("double_sided") = mat.double_sided,
                                    py::arg("textures") = textures));
            }
            return out;
        }, "The materials, as dicts; a texture's image is an index into images, or None when it is a file (its uri).")
        .def_property_readonly("images", [](const std::shared_ptr<FileHolder>& f) {
            py::list out;
            const py::object base = py::cast(f);
            for (const tom::Image& image : f->file.scene().images) {
                py::array_t<uint8_t> bytes({size_t(image.bytes)}, {sizeof(uint8_t)}, image.data, base);
                bytes.attr("setflags")(py::arg("write") = false);
                out.append(py::dict(py::arg("name") = image.name, py::arg("mime_type") = image.mime_type, py::arg("data") = bytes));
            }
            return out;
        }, "The images embedded in the source and stored in the file, as dicts; data is a read-only uint8 view into the file (no copy).")
        .def_property_readonly("instances", [](const FileHolder& f) {
            py::list out;
            for (const tom::Instance& i : tom::draw_list(f.file.scene(), f.file.mesh_count())) {
                py::array_t<float> t({4, 4});
                for (int c = 0; c < 16; ++c) t.mutable_data()[(c % 4) * 4 + c / 4] = i.transform[c];  // row-major, as numpy prints it
                out.append(py::dict(py::arg("mesh") = i.mesh, py::arg("node") = i.node, py::arg("name") = i.name, py::arg("transform") = t));
            }
            return out;
        }, "What to draw: the instances, or every mesh once untransformed; transform is a 4x4 object-to-world matrix.")
        .def("__len__", [](const FileHolder& f) { return f.file.mesh_count(); });

    m.def("open", [](const std::string& path, std::optional<uint64_t> byte_limit) {
        std::optional<tom::File> f;
        {
            py::gil_scoped_release release;
            f.emplace(byte_limit ? tom::open_any(path, *byte_limit) : tom::open_any(path));
        }
        return std::make_shared<FileHolder>(FileHolder{std::move(*f), py::none()});
    }, py::arg("path"), py::arg("byte_limit") = py::none(),
          "Maps and validates a .tom file (every rule of docs/FORMAT.md); a streamed one (tombuild --stream) is decoded, only its first "
          "byte_limit bytes when given (the meshes a viewer shows after that many bytes). Raises tom.FormatError, tom.IoError, or "
          "tom.ArgumentError for a byte limit on an ordinary file.");
    m.def("open_bytes", [](py::buffer bytes, const std::string& name) {
        const py::buffer_info info = bytes.request();
        if (info.itemsize != 1 || info.ndim != 1) throw tom::ArgumentError("open_bytes: a one-dimensional buffer of bytes is needed");
        tom::File f = tom::File::borrow(info.ptr, size_t(info.size), name);
        return std::make_shared<FileHolder>(FileHolder{std::move(f), bytes});
    }, py::arg("data"), py::arg("name") = "<memory>", "Validates a .tom image in a bytes-like object and uses it in place (it is kept alive and must not change).");
}

// tom.Mesh, tom.BuiltMesh, tom.import_file, tom.build, tom.serialize, tom.write, tom.report.
void add_building(py::module_& m) {
    py::class_<SourceMesh>(m, "Mesh", "A source mesh: positions, triangles and optional normals and uv, as imported or given.")
        .def(py::init([](py::object positions, py::object triangles, py::object normals, py::object uv, const std::string& name) {
                 return SourceMesh{make_mesh(positions, triangles, normals, uv, name)};
             }), py::arg("positions"), py::arg("triangles"), py::arg("normals") = py::none(), py::arg("uv") = py::none(), py::arg("name") = "mesh")
        .def_property_readonly("name", [](const SourceMesh& s) { return s.mesh->name; })
        .def_property_readonly("vertex_count", [](const SourceMesh& s) { return s.mesh->vertex_count(); })
        .def_property_readonly("triangle_count", [](const SourceMesh& s) { return s.mesh->triangle_count(); })
        .def_property_readonly("positions", [](py::object self) { const tom::Mesh& s = *self.cast<const SourceMesh&>().mesh; return readonly_array(s.positions.data(), s.vertex_count(), 3, self); })
        .def_property_readonly("normals", [](py::object self) { const tom::Mesh& s = *self.cast<const SourceMesh&>().mesh; return readonly_array(s.normals.empty() ? nullptr : s.normals.data(), s.vertex_count(), 3, self); })
        .def_property_readonly("uv", [](py::object self) { const tom::Mesh& s = *self.cast<const SourceMesh&>().mesh; return readonly_array(s.texcoords.empty() ? nullptr : s.texcoords.data(), s.vertex_count(), 2, self); })
        .def_property_readonly("triangles", [](py::object self) { const tom::Mesh& s = *self.cast<const SourceMesh&>().mesh; return readonly_array(s.indices.data(), s.triangle_count(), 3, self); });

    py::class_<BuiltMesh> built(m, "BuiltMesh", "A mesh in TOM order, as tom.build made it; write it with tom.write.");
    mesh_properties(built, [](py::object self) -> const tom::MeshView& { return self.cast<const BuiltMesh&>().view; });

    m.def("import_file", [](const std::string& path) {
        std::vector<tom::Mesh> meshes;
        {
            py::gil_scoped_release release;
            meshes = tom::import_file(path).meshes;
        }
        std::vector<SourceMesh> out;
        for (tom::Mesh& mesh : meshes) out.push_back({std::make_shared<tom::Mesh>(std::move(mesh))});
        return out;
    }, py::arg("path"), "Reads OBJ, PLY, OFF, STL, glTF or GLB (Draco and meshopt included) as tombuild does: one Mesh per primitive. Raises tom.MeshError.");

    m.def("build", [](py::object positions, py::object triangles, py::object normals, py::object uv, const std::string& name, const std::string& predicate,
                      const std::string& strategy, float pair_threshold, float attribute_weight, float max_rotation_degrees, unsigned threads, bool foresight,
                      bool lock_borders, float animation_weight, bool weld, bool keep_topology) {
        const std::shared_ptr<tom::Mesh> source = py::isinstance<SourceMesh>(positions) ? positions.cast<SourceMesh>().mesh : make_mesh(positions, triangles, normals, uv, name);
        tom::BuildParams p;
        p.predicate = parse_predicate(predicate);
        p.strategy = parse_strategy(strategy);
        p.pair_threshold = pair_threshold;
        p.attribute_weight = attribute_weight;
        p.max_rotation_degrees = max_rotation_degrees;
        p.threads = threads;
        p.foresight = foresight;
        p.lock_borders = lock_borders;
        p.keep_topology = keep_topology;
        p.animation_weight = animation_weight;
        return build_mesh(*source, p, tom::CleanOptions{weld});
    }, py::arg("positions"), py::arg("triangles") = py::none(), py::arg("normals") = py::none(), py::arg("uv") = py::none(), py::kw_only(), py::arg("name") = "mesh",
       py::arg("predicate") = "quadric", py::arg("strategy") = "passes", py::arg("pair_threshold") = 0.0f, py::arg("attribute_weight") = 1.0f,
       py::arg("max_rotation_degrees") = 60.0f, py::arg("threads") = 0u, py::arg("foresight") = true, py::arg("lock_borders") = false,
       py::arg("animation_weight") = 1.0f, py::arg("weld") = true, py::arg("keep_topology") = false,
       "Simplifies a mesh into TOM order: positions (n, 3) and triangles (t, 3), or a tom.Mesh as the first argument\n"
       "(which keeps its parts: an OBJ's usemtl groups, a glTF mesh's primitives).\n"
       "The keywords are tombuild's options (docs/TOOLS.md); the result is the same for any thread count.");

    m.def("serialize", [](const std::vector<BuiltMesh>& meshes, const std::string& index_size) {
        std::vector<uint8_t> bytes;
        {
            py::gil_scoped_release release;
            bytes = tom::serialize(built_meshes(meshes), write_options(index_size));
        }
        return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    }, py::arg("meshes"), py::arg("index_size") = "auto", "The .tom image of built meshes, as bytes.");
    m.def("write", [](const std::string& path, const std::vector<BuiltMesh>& meshes, const std::string& index_size) {
        py::gil_scoped_release release;
        tom::write_file(path, built_meshes(meshes), write_options(index_size));
    }, py::arg("path"), py::arg("meshes"), py::arg("index_size") = "auto", "Writes built meshes to a .tom file, atomically.");

    m.def("report", [](const SourceMesh& original, const BuiltMesh& b, const std::vector<double>& levels, bool error_curve) {
        return report(*original.mesh, b, levels, error_curve);
    }, py::arg("original"), py::arg("built"), py::arg("levels") = std::vector<double>{0.5, 0.25, 0.1, 0.05, 0.02, 0.01, 0.005}, py::arg("error_curve") = true,
       "Metro-style report of a built mesh against the tom.Mesh it was built from, as a dict with the figures of tombuild's JSON report (docs/REPORT.md).");
}

// For scripts/bench-bindings.py: seconds per call of `batch` extractions through the C++ or the
// C API, in this process, so that its rounds interleave with the Python calls'.
void add_bench(py::module_& m) {
    m.def("_bench_native", [](const FileMesh& mesh, uint32_t vertices, py::array_t<uint32_t, py::array::c_style> out, int batch, const std::string& api) {
        const tom::MeshView& v = mesh.view();
        tom_mesh_view c{};
        c.vertex_count = v.vertex_count;
        c.triangle_count = v.triangle_count;
        c.min_vertex_count = v.min_vertex_count;
        c.internal = &v;
        uint32_t* data = out.mutable_data();
        const size_t capacity = size_t(out.size());
        volatile uint32_t sink = 0;
        const auto start = std::chrono::steady_clock::now();
        if (api == "c") {
            for (int i = 0; i < batch; ++i) {
                tom_extracted e;
                tom_extract_u32(&c, vertices, data, capacity, &e);
                sink = sink + e.triangle_count;
            }
        } else {
            for (int i = 0; i < batch; ++i) sink = sink + tom::extract(v, vertices, data, capacity).triangle_count;
        }
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / batch;
    });
}

} // namespace

PYBIND11_MODULE(_tom, m) {
    m.doc() = "Totally Ordered Meshes: .tom files, extraction at any resolution, building and reports.";
    add_errors(m);
    add_files(m);
    add_building(m);
    add_bench(m);
    m.attr("format_version") = py::make_tuple(tom::format_version_major, tom::format_version_minor);
    py::module_ tcr = m.def_submodule("tcr", "Time-critical rendering (libtcr): each frame, every object's resolution within a time budget.");
    tom_python::add_tcr(tcr);
}
