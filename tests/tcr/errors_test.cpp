// One error family: each public entry point of libtom's libraries and libtcr, handed broken
// input, throws a tom::Error (the test catches nothing else, so a std:: exception fails it), with
// a message naming what is wrong.

#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>
#include <vector>
#include <catch2/catch.hpp>
#include "support.h"
#include "tcr/model.h"
#include "tcr/scene_budget.h"
#include "tcr/select.h"
#include "tom/builder/builder.h"
#include "tom/builder/generate.h"
#include "tom/builder/writer.h"
#include "tom/errors.h"
#include "tom/format.h"
#include "tom/io/export.h"
#include "tom/io/import.h"
#include "tom/metrics/report.h"

using Catch::Contains;

namespace {

// The message of the tom::Error `call` throws ("" and a failed check when it throws none).
template <class Call>
std::string error_of(Call&& call) {
    try {
        call();
    } catch (const tom::Error& e) {
        return e.what();
    }
    FAIL_CHECK("no tom::Error thrown");
    return "";
}

std::string write_text(const std::string& name, const std::string& text) {
    const std::string path = std::string(std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp") + "/tom-errors-" + name;
    std::ofstream(path) << text;
    return path;
}

} // namespace

TEST_CASE("every public entry point reports broken input as a tom::Error", "[errors]") {
    const test::NamedMesh fandisk = test::real_meshes()[1];
    tom::Mesh cube = tom::make_sphere(8, 8);
    tom::clean_mesh(cube);

    // files: unreadable, truncated, not a .tom at all
    CHECK_THAT(error_of([] { tom::File::open("/nonexistent/x.tom"); }), Contains("x.tom"));
    const std::vector<uint8_t> bytes = tom::serialize({tom::build(tom::Mesh(cube))});
    CHECK_THAT(error_of([&] { tom::File::from_bytes(bytes.data(), bytes.size() / 2, "half"); }), Contains("half"));
    CHECK_THAT(error_of([] { tom::File::from_bytes("not a tom file at all", 21, "text"); }), Contains("text"));
    // import: a missing file, an OBJ with an index past its vertices
    CHECK_THAT(error_of([] { tom::import_file("/nonexistent/m.obj"); }), Contains("m.obj"));
    const std::string bad_obj = write_text("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    CHECK_THAT(error_of([&] { tom::import_file(bad_obj); }), Contains("bad.obj"));
    // meshes handed in: an index out of range, a non-finite position
    tom::Mesh broken = cube;
    broken.name = "broken";
    broken.indices[4] = broken.vertex_count() + 3;
    CHECK_THAT(error_of([&] { tom::clean_mesh(broken); }), Contains("broken"));
    tom::Mesh nan = cube;
    nan.name = "nan";
    nan.positions[1] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THAT(error_of([&] { tom::clean_mesh(nan); }), Contains("nan"));
    // a TomMesh without its map to the input; a report on meshes that do not belong together
    tom::TomMesh unmapped = tom::build(tom::Mesh(cube));
    unmapped.original_index.clear();
    CHECK_THAT(error_of([&] { tom::original_mesh(unmapped); }), Contains("original_mesh"));
    CHECK_THAT(error_of([&] { tom::make_report(fandisk.mesh, tom::build(tom::Mesh(cube))); }), Contains("report"));
    // writing: an instance naming a missing mesh, an unwritable path, an unknown extension
    tom::Scene scene;
    scene.instances.push_back({});
    scene.instances.back().mesh = 5;
    CHECK_THAT(error_of([&] { tom::serialize({tom::build(tom::Mesh(cube))}, scene); }), Contains("5"));
    CHECK_THAT(error_of([&] { tom::write_file("/nonexistent/dir/x.tom", {tom::build(tom::Mesh(cube))}, tom::Scene{}); }), Contains("x.tom"));
    const tom::File file = tom::File::from_bytes(bytes.data(), bytes.size());
    tom::ExportPart part;
    part.mesh = &file.mesh(0);
    CHECK_THAT(error_of([&] { tom::export_meshes("/tmp/x.unknown", {part}); }), Contains("x.unknown"));

    // libtcr: a calibration file that does not parse, a menu whose arrays do not fit, a budget
    // mesh without a view
    const std::string bad_model = write_text("bad.tcr", "t_tri_ms not-a-number\n");
    CHECK_THAT(error_of([&] { tcr::read_cost_model(bad_model); }), Contains("bad.tcr"));
    tcr::Problem p;
    p.resize(2);
    p.way_begin = {0, 3};  // two objects need three entries
    CHECK_THAT(error_of([&] { p.check_menu(); }), Contains("way_begin"));
    CHECK_THAT(error_of([] { tcr::share_budget({tcr::BudgetMesh{}}, 100.0); }), Contains("mesh 0"));
}
