// tom.tcr: libtcr for Python engines and tools. A runtime of objects on a file's meshes, the frame
// governor around it, the calibration file and the simulated renderer; matrices are 4x4 numpy
// arrays, row-major as numpy prints them (the library's column-major order inside).

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "holders.h"
#include "tcr/calibrate.h"
#include "tcr/governor.h"
#include "tcr/model.h"
#include "tcr/runtime.h"
#include "tcr/select.h"
#include "tom/errors.h"

namespace tom_python {

namespace {

// A runtime and the meshes its objects draw (kept alive with their files).
struct PyRuntime {
    std::unique_ptr<tcr::Runtime> runtime;
    std::vector<py::object> meshes;
};

// A 4x4 matrix (row-major, as numpy prints it) into the library's column-major 16 floats.
void column_major(const py::object& matrix, const char* what, float out[16]) {
    const py::array_t<float, py::array::c_style | py::array::forcecast> a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(matrix);
    if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) throw tom::ArgumentError(std::string(what) + " must be a 4x4 matrix");
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out[c * 4 + r] = a.at(r, c);
}

py::array_t<float> row_major(const float m[16]) {
    py::array_t<float> out({4, 4});
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out.mutable_at(r, c) = m[c * 4 + r];
    return out;
}

tcr::FrameParams frame_params(const py::object& view, const py::object& projection, uint32_t width, uint32_t height) {
    tcr::FrameParams f;
    column_major(view, "view", f.camera.view);
    column_major(projection, "projection", f.camera.projection);
    if (width == 0 || height == 0) throw tom::ArgumentError("the viewport needs a width and a height");
    f.camera.viewport_width = width;
    f.camera.viewport_height = height;
    return f;
}

py::dict report_dict(const tcr::FrameReport& r) {
    return py::dict(py::arg("predicted_ms") = r.predicted_ms, py::arg("benefit") = r.benefit, py::arg("gap") = r.gap, py::arg("max_error_px") = r.max_error_px,
                    py::arg("visible") = r.visible, py::arg("drawn") = r.drawn, py::arg("triangles") = r.triangles, py::arg("cull_ms") = r.cull_ms,
                    py::arg("optimize_ms") = r.optimize_ms, py::arg("correction") = r.correction, py::arg("feasible") = r.feasible);
}

// A Python object as calibration's renderer: its `width` and `height`, its
// time_frame(camera, draws, way) and, when it has one, time_imposters(camera, captures,
// imposters). A camera is a dict (view, projection, width, height), a draw a dict (mesh, indices,
// model), the way "smooth", "flat" or "textured"; each level's indices are one array per call.
class PyCalibrationRenderer final : public tcr::CalibrationRenderer {
public:
    explicit PyCalibrationRenderer(py::object r)
        : r_(std::move(r)), width_(r_.attr("width").cast<uint32_t>()), height_(r_.attr("height").cast<uint32_t>()) {}
    uint32_t width() const override { return width_; }
    uint32_t height() const override { return height_; }
    double time_frame(const tcr::Camera& camera, const std::vector<tcr::CalibrationDraw>& draws, tcr::Representation way) override {
        levels_.clear();
        py::list list;
        for (const tcr::CalibrationDraw& d : draws) list.append(draw_dict(d));
        return r_.attr("time_frame")(camera_dict(camera), list, tcr::representation_name(way)).cast<double>();
    }
    double time_imposters(const tcr::Camera& camera, const std::vector<tcr::CalibrationCapture>& captures,
                          const std::vector<tcr::CalibrationImposter>& imposters) override {
        if (!py::hasattr(r_, "time_imposters")) return -1;
        levels_.clear();
        py::list caps, quads;
        for (const tcr::CalibrationCapture& c : captures)
            caps.append(py::dict(py::arg("slot") = c.slot, py::arg("side") = c.side, py::arg("view") = row_major(c.view),
                                 py::arg("projection") = row_major(c.projection), py::arg("grid") = c.grid, py::arg("draw") = draw_dict(c.draw)));
        for (const tcr::CalibrationImposter& q : imposters) {
            py::array_t<float> corners({4, 3});
            std::copy(q.corners, q.corners + 12, corners.mutable_data());
            quads.append(py::dict(py::arg("slot") = q.slot, py::arg("meshed") = q.meshed, py::arg("corners") = corners));
        }
        return r_.attr("time_imposters")(camera_dict(camera), caps, quads).cast<double>();
    }

private:
    static py::dict camera_dict(const tcr::Camera& c) {
        return py::dict(py::arg("view") = row_major(c.view), py::arg("projection") = row_major(c.projection), py::arg("width") = c.viewport_width,
                        py::arg("height") = c.viewport_height);
    }
    py::dict draw_dict(const tcr::CalibrationDraw& d) {
        auto known = levels_.find({d.indices, d.index_count});
        if (known == levels_.end()) {
            py::array_t<uint32_t> a(d.index_count);
            std::copy(d.indices, d.indices + d.index_count, a.mutable_data());
            known = levels_.emplace(std::make_pair(d.indices, d.index_count), a).first;
        }
        return py::dict(py::arg("mesh") = d.mesh, py::arg("indices") = known->second, py::arg("model") = row_major(d.model));
    }
    py::object r_;
    uint32_t width_, height_;
    std::map<std::pair<const uint32_t*, uint32_t>, py::array_t<uint32_t>> levels_;
};

tcr::SelectorKind selector_of(const std::string& name) {
    tcr::SelectorKind kind;
    if (!tcr::parse_selector(name, kind)) throw tom::ArgumentError("selector '" + name + "' is not one of static, stress, greedy, barrier, exact");
    return kind;
}

} // namespace

void add_tcr(py::module_& m) {
    py::class_<tcr::CostModel> model(m, "CostModel", "The calibrated frame cost model (docs/CALIBRATION.md), in milliseconds.");
    model.def(py::init<>());
#define TOM_TCR_FIELD(name) model.def_readwrite(#name, &tcr::CostModel::name)
    TOM_TCR_FIELD(t_init_ms);
    TOM_TCR_FIELD(t_final_ms);
    TOM_TCR_FIELD(t_setup_ms);
    TOM_TCR_FIELD(t_tri_ms);
    TOM_TCR_FIELD(t_vert_ms);
    TOM_TCR_FIELD(t_pix_ms);
    TOM_TCR_FIELD(safety_ms);
    TOM_TCR_FIELD(noise_rel);
    TOM_TCR_FIELD(flat_t_tri_ms);
    TOM_TCR_FIELD(flat_t_vert_ms);
    TOM_TCR_FIELD(flat_t_pix_ms);
    TOM_TCR_FIELD(textured_t_tri_ms);
    TOM_TCR_FIELD(textured_t_vert_ms);
    TOM_TCR_FIELD(textured_t_pix_ms);
    TOM_TCR_FIELD(imposter_t_setup_ms);
    TOM_TCR_FIELD(imposter_t_pix_ms);
    TOM_TCR_FIELD(refresh_t_setup_ms);
    TOM_TCR_FIELD(meshed_t_tri_ms);
    TOM_TCR_FIELD(meshed_refresh_t_setup_ms);
#undef TOM_TCR_FIELD
    m.def("read_cost_model", &tcr::read_cost_model, py::arg("path"), "Reads a calibration file; raises tom.ParseError naming the line, tom.IoError.");
    m.def("look_at", [](std::vector<float> eye, std::vector<float> target, std::vector<float> up) {
        if (eye.size() != 3 || target.size() != 3 || up.size() != 3) throw tom::ArgumentError("look_at: eye, target and up are 3-vectors");
        float v[16];
        tcr::look_at(eye.data(), target.data(), up.data(), v);
        return row_major(v);
    }, py::arg("eye"), py::arg("target"), py::arg("up"), "A view matrix (world to eye).");
    m.def("perspective", [](float fov_y, float aspect, float z_near, float z_far) {
        float p[16];
        tcr::perspective(fov_y, aspect, z_near, z_far, p);
        return row_major(p);
    }, py::arg("fov_y"), py::arg("aspect"), py::arg("z_near"), py::arg("z_far"), "A perspective projection (fov_y in radians).");

    py::class_<PyRuntime>(m, "Runtime", "Objects on a file's meshes; each frame, their resolutions within the budget.")
        .def(py::init([](const tcr::CostModel& cost, const std::string& selector) {
                 return PyRuntime{std::make_unique<tcr::Runtime>(cost, selector_of(selector)), {}};
             }), py::arg("model"), py::arg("selector") = "exact")
        .def("add_object", [](PyRuntime& self, py::object mesh, py::object transform, float weight) {
                 const FileMesh& fm = mesh.cast<const FileMesh&>();
                 float t[16];
                 column_major(transform, "transform", t);
                 if (!(weight > 0)) throw tom::ArgumentError("add_object: weight must be positive");
                 self.meshes.push_back(mesh);
                 return self.runtime->add_object(fm.view(), t, weight);
             }, py::arg("mesh"), py::arg("transform"), py::arg("weight") = 1.0f, "Adds an object drawing a file's mesh; returns its id.")
        .def("__len__", [](const PyRuntime& self) { return self.runtime->object_count(); })
        .def("plan_frame", [](PyRuntime& self, py::object view, py::object projection, uint32_t width, uint32_t height, double budget_ms, double previous_frame_ms) {
                 tcr::FrameParams f = frame_params(view, projection, width, height);
                 f.budget_ms = budget_ms;
                 f.previous_frame_ms = previous_frame_ms;
                 return report_dict(self.runtime->plan_frame(f));
             }, py::arg("view"), py::arg("projection"), py::arg("width"), py::arg("height"), py::arg("budget_ms") = 16.0, py::arg("previous_frame_ms") = 0.0,
             "Plans a frame without a governor; the report as a dict.")
        .def("object", [](const PyRuntime& self, uint32_t id) {
                 if (id >= self.runtime->object_count()) throw tom::ArgumentError("object " + std::to_string(id) + " of a runtime with " + std::to_string(self.runtime->object_count()));
                 const tcr::ObjectResult& o = self.runtime->object(id);
                 return py::dict(py::arg("visible") = o.visible, py::arg("drawn") = o.drawn, py::arg("vertices") = o.vertices, py::arg("triangles") = o.triangles,
                                 py::arg("coverage_px") = o.coverage_px, py::arg("error_px") = o.error_px, py::arg("predicted_ms") = o.predicted_ms);
             }, py::arg("id"))
        .def("indices", [](const PyRuntime& self, uint32_t id) {
                 if (id >= self.runtime->object_count()) throw tom::ArgumentError("object " + std::to_string(id) + " of a runtime with " + std::to_string(self.runtime->object_count()));
                 py::array_t<uint32_t> out(std::vector<py::ssize_t>{py::ssize_t(self.runtime->object(id).triangles), 3});
                 const tom::Extracted e = self.runtime->indices(id, out.mutable_data(), size_t(out.size()));
                 return py::make_tuple(out, e.vertex_count);
             }, py::arg("id"), "The chosen level of object id: (indices (t, 3) uint32, vertex count); empty for an object not drawn.");

    py::class_<tcr::FrameGovernor>(m, "FrameGovernor", "The frame policy around a runtime: planning reserve, feedback, noise allowance, extraction cost.")
        .def(py::init([](PyRuntime& runtime, const tcr::CostModel& calibrated, double budget_ms, double safety_sigma, bool follow_noise) {
                 tcr::GovernorParams g;
                 g.budget_ms = budget_ms;
                 g.safety_sigma = safety_sigma;
                 g.follow_noise = follow_noise;
                 return std::make_unique<tcr::FrameGovernor>(*runtime.runtime, calibrated, g);
             }), py::arg("runtime"), py::arg("model"), py::arg("budget_ms") = 16.0, py::arg("safety_sigma") = 0.75, py::arg("follow_noise") = true,
             py::keep_alive<1, 2>())
        .def("plan_frame", [](tcr::FrameGovernor& g, py::object view, py::object projection, uint32_t width, uint32_t height) {
                 return report_dict(g.plan_frame(frame_params(view, projection, width, height)));
             }, py::arg("view"), py::arg("projection"), py::arg("width"), py::arg("height"))
        .def("frame_done", [](tcr::FrameGovernor& g, double extract_ms, double render_ms, double frame_ms) { g.frame_done({extract_ms, render_ms, frame_ms}); },
             py::arg("extract_ms"), py::arg("render_ms"), py::arg("frame_ms") = -1.0)
        .def_property_readonly("warming_up", &tcr::FrameGovernor::warming_up)
        .def_property_readonly("planning_reserve_ms", &tcr::FrameGovernor::planning_reserve_ms)
        .def_property_readonly("model", [](const tcr::FrameGovernor& g) { return g.model(); });

    m.def("calibrate", [](py::object renderer, const std::vector<py::object>& meshes, const std::string& path) {
              std::vector<const tom::MeshView*> views;
              for (const py::object& mesh : meshes) views.push_back(&mesh.cast<const FileMesh&>().view());
              PyCalibrationRenderer timer(renderer);
              tcr::CalibrationParams params;
              params.path = path;
              params.comment = path.empty() ? "" : "tom.tcr.calibrate";
              return tcr::calibrate(timer, views, params).model;
          }, py::arg("renderer"), py::arg("meshes"), py::arg("path") = "",
          "Times `renderer` drawing `meshes` (time_frame(camera, draws, way); optional time_imposters) and fits the cost model; "
          "writes it to `path` when given. Raises tom.ArgumentError, tom.IoError, or what the renderer raises.");
    py::class_<tcr::SimulatedRenderer>(m, "SimulatedRenderer", "Frames timed from the cost model, slower or faster than calibrated, with noise.")
        .def(py::init<double, double, uint64_t, bool>(), py::arg("noise_rel"), py::arg("slowdown") = 1.0, py::arg("seed") = 1, py::arg("within_allowance") = true)
        .def("frame_ms", [](tcr::SimulatedRenderer& r, const py::dict& report, const tcr::CostModel& cost) {
                 tcr::FrameReport fr;
                 fr.predicted_ms = report["predicted_ms"].cast<double>();
                 fr.correction = report["correction"].cast<double>();
                 return r.frame_ms(fr, cost);
             }, py::arg("report"), py::arg("model"));
}

} // namespace tom_python
