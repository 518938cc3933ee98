// Every component of the installed package in one program: imports a mesh file (tom::io),
// builds and writes it (tom::builder), maps the written file (tom::tom), measures its 10% level
// (tom::metrics), and lets a libtcr selector fit two copies of it into a budget (tom::tcr).
// Usage: tom_pipeline MESH_FILE OUT.tom

#include <cstdio>
#include <vector>

#include "tcr/select.h"
#include "tom/builder/builder.h"
#include "tom/builder/writer.h"
#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/io/import.h"
#include "tom/metrics/report.h"

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: %s MESH_FILE OUT.tom\n", argv[0]);
        return 2;
    }
    try {
        tom::ImportResult imported = tom::import_file(argv[1]);
        tom::Mesh& mesh = imported.meshes.at(0);
        tom::clean_mesh(mesh);
        const tom::TomMesh built = tom::build(mesh);
        tom::write_file(argv[2], {built});

        const tom::File file = tom::File::open(argv[2]);
        const tom::MeshView& view = file.mesh(0);
        std::vector<uint32_t> indices(size_t(view.triangle_count) * 3);
        const tom::Extracted level = tom::extract(view, tom::vertex_count_for_fraction(view, 0.1), indices.data(), indices.size());

        tom::ReportParams params;
        params.levels = {0.1};
        params.error_curve = false;
        const tom::MeshReport report = tom::make_report(mesh, built, params);

        tcr::Problem problem;
        problem.resize(2);
        problem.budget_ms = 1.0;
        for (size_t i = 0; i < 2; ++i) {
            problem.importance[i] = 1.0 + double(i);
            problem.error[i] = report.bbox_diagonal;
            problem.per_tri_ms[i] = 1e-4;
            problem.setup_ms[i] = 0.01;
            problem.lo[i] = view.triangle_count / 100 + 1;
            problem.hi[i] = view.triangle_count;
        }
        tcr::Plan plan;
        tcr::select(tcr::SelectorKind::exact, problem, {}, plan);

        std::printf("%s: %u vertices, %u triangles; at 10%%: %u vertices, %u triangles, Hausdorff %.4f%% of the diagonal; "
                    "a 1 ms budget draws %.0f + %.0f triangles (%.3f ms)\n",
                    built.name.c_str(), view.vertex_count, view.triangle_count, level.vertex_count, level.triangle_count,
                    report.levels.at(0).error.percent(report.levels.at(0).error.hausdorff), plan.triangles[0], plan.triangles[1], plan.cost_ms);
        return 0;
    } catch (const tom::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
