// The whole time-critical loop an engine runs, on tom::tcr: objects into a runtime, a governor
// around it, and each frame planned, extracted and drawn within the budget. The renderer is
// simulated from the cost model (1.3x slower than calibrated, 3% noise), so it runs anywhere;
// an engine draws the index buffers instead and times its frame.
// Usage: tom_governed FILE.tom [BUDGET_MS]

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "tcr/governor.h"
#include "tcr/runtime.h"
#include "tcr/view.h"
#include "tom/errors.h"
#include "tom/format.h"

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s FILE.tom [BUDGET_MS]\n", argv[0]);
        return 2;
    }
    try {
        const tom::File file = tom::File::open(argv[1]);
        tcr::CostModel model;  // an engine reads its calibration: tcr::read_cost_model(path)
        model.t_init_ms = model.t_final_ms = 0.5;
        model.t_setup_ms = 0.02;
        model.t_tri_ms = 2e-5;
        model.t_vert_ms = 1e-5;
        model.t_pix_ms = 1e-6;
        model.safety_ms = 0.2;
        model.noise_rel = 0.03;

        // a grid of 8 x 8 copies of the file's first mesh
        tcr::Runtime runtime(model, tcr::SelectorKind::exact);
        for (int i = 0; i < 64; ++i) {
            float transform[16];
            tcr::translation_scale(float(i % 8 - 4), float(i / 8 - 4), -2.0f * float(i % 3), 1.0f, transform);
            runtime.add_object(file.mesh(0), transform);
        }
        tcr::GovernorParams params;
        params.budget_ms = argc > 2 ? std::atof(argv[2]) : 10.0;
        tcr::FrameGovernor governor(runtime, model, params);
        tcr::SimulatedRenderer renderer(0.03, 1.3);

        std::vector<uint32_t> indices;
        int frames = 0, over = 0;
        double total_ms = 0, triangles = 0;
        for (int f = 0; f < 300; ++f) {
            tcr::FrameParams request;  // the camera walks toward the grid
            const float eye[3] = {0, 0, 12.0f - 0.02f * float(f)}, target[3] = {0, 0, -20}, up[3] = {0, 1, 0};
            tcr::look_at(eye, target, up, request.camera.view);
            tcr::perspective(1.0f, 16.0f / 9.0f, 0.1f, 100.0f, request.camera.projection);
            request.camera.viewport_width = 1280;
            request.camera.viewport_height = 720;
            const bool warming_up = governor.warming_up();
            const double reserve_ms = governor.planning_reserve_ms();
            const tcr::FrameReport& report = governor.plan_frame(request);

            const auto start = std::chrono::steady_clock::now();  // extraction: each drawn object's level
            indices.resize(size_t(report.triangles) * 3);
            size_t at = 0;
            for (uint32_t id = 0; id < runtime.object_count(); ++id)
                if (runtime.object(id).drawn) at += 3 * size_t(runtime.indices(id, indices.data() + at, indices.size() - at).triangle_count);
            const double extract_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
            // the simulated frame holds extraction once the warm-up has put it in the model
            const double render_ms = renderer.frame_ms(report, governor.model());
            governor.frame_done({warming_up ? extract_ms : 0.0, render_ms});
            if (warming_up || f < 30) continue;  // the correction settles
            const double frame_ms = reserve_ms + render_ms;
            ++frames;
            over += frame_ms > 1.1 * params.budget_ms;
            total_ms += frame_ms;
            triangles += double(report.triangles);
        }
        std::printf("%u objects, %d frames at %.1f ms: %d over 1.1x the budget, mean %.2f ms, %.0f triangles a frame\n",
                    uint32_t(runtime.object_count()), frames, params.budget_ms, over, total_ms / frames, triangles / frames);
        return 0;
    } catch (const tom::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
