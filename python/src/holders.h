#pragma once
// What the Python objects of a .tom file hold, shared by the module's translation units.

#include <pybind11/pybind11.h>

#include <memory>

#include "tom/format.h"

namespace tom_python {

namespace py = pybind11;

// A mapped file, or one that borrows a Python buffer (kept alive by `owner`).
struct FileHolder {
    tom::File file;
    py::object owner;
};

// One mesh of a file: its arrays keep the file alive through `holder`.
struct FileMesh {
    std::shared_ptr<FileHolder> holder;
    uint32_t index = 0;
    const tom::MeshView& view() const { return holder->file.mesh(index); }
};

// tom.tcr: libtcr's runtime, frame governor and simulated renderer (tcr_module.cpp).
void add_tcr(py::module_& m);

} // namespace tom_python
