/* A C engine's whole time-critical loop on tom/tcr.h: it calibrates its renderer (here a CPU
 * "renderer" that fetches and transforms every index's vertex, timed by clock()), then draws 64
 * copies of a mesh under the exact selector and the frame governor, each frame planned,
 * extracted, drawn and timed for real. Prints the calibrated per-triangle cost, how the budget
 * held and the share of the full-detail triangles drawn.
 * Usage: tom_c_governed FILE.tom [BUDGET_MS] */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "tom/tcr.h"

typedef struct cpu_renderer { const float* positions; double sink; } cpu_renderer;

static double now_ms(void) { return 1000.0 * (double)clock() / CLOCKS_PER_SEC; }

/* "Draws" a level: every index's vertex through the object's model matrix. */
static void draw(cpu_renderer* r, const uint32_t* indices, size_t count, const float m[16]) {
    size_t k;
    for (k = 0; k < count; ++k) {
        const float* p = r->positions + 3 * (size_t)indices[k];
        r->sink += m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12] + m[2] * p[0] + m[6] * p[1] + m[10] * p[2] + m[14];
    }
}

static double time_frame(void* user, const tcr_camera* camera, const tcr_calibration_draw* draws, size_t count, tcr_way way) {
    const double start = now_ms();
    size_t k;
    (void)camera;
    if (way != TCR_WAY_SMOOTH) return -1.0; /* one way only: the other ways stay uncalibrated */
    for (k = 0; k < count; ++k) draw(user, draws[k].indices, draws[k].index_count, draws[k].model);
    return now_ms() - start;
}

int main(int argc, char** argv) {
    tom_file* file = NULL;
    tom_mesh_view mesh;
    const tom_mesh_view* meshes[1];
    cpu_renderer cpu = {NULL, 0.0};
    tcr_calibration_renderer timer = {NULL, 1280, 720, time_frame, NULL};
    tcr_cost_model model;
    tcr_runtime* rt = NULL;
    tcr_governor* governor = NULL;
    tcr_governor_params gp;
    tcr_frame_params request;
    tcr_frame_report report;
    uint32_t* indices = NULL;
    int f, frames = 0, over = 0;
    uint32_t id, added;
    float transforms[64][16];
    double total_ms = 0, triangles = 0;
    if (argc < 2) return fprintf(stderr, "usage: %s FILE.tom [BUDGET_MS]\n", argv[0]), 2;
    if (tom_file_open(argv[1], &file) != TOM_OK || tom_file_mesh(file, 0, &mesh) != TOM_OK) goto failed;
    cpu.positions = mesh.positions;
    timer.user = &cpu;
    meshes[0] = &mesh;
    if (tcr_calibrate(&timer, meshes, 1, NULL, &model) != TOM_OK) goto failed;
    if (tcr_runtime_create(&model, TCR_SELECTOR_EXACT, &rt) != TOM_OK) goto failed;
    for (id = 0; id < 64; ++id) { /* an 8 x 8 grid, 3 to 7 units ahead */
        float* t = transforms[id];
        int k;
        for (k = 0; k < 16; ++k) t[k] = k % 5 == 0 ? 1.0f : 0.0f;
        t[12] = 0.6f * (float)(id % 8) - 2.1f, t[13] = 0.6f * (float)(id / 8) - 2.1f, t[14] = -3.0f - (float)(id % 5);
        if (tcr_runtime_add_object(rt, &mesh, t, 1.0f, &added) != TOM_OK) goto failed;
    }
    tcr_governor_params_default(&gp);
    gp.budget_ms = argc > 2 ? atof(argv[2]) : 2.0;
    if (tcr_governor_create(rt, &model, &gp, &governor) != TOM_OK) goto failed;
    tcr_frame_params_default(&request);
    request.camera.projection[0] = 1.0f, request.camera.projection[5] = 1.7f; /* 90 degrees across, 16:9, eye at the origin down -z */
    request.camera.projection[10] = request.camera.projection[11] = -1.0f, request.camera.projection[14] = -0.2f;
    request.camera.viewport_width = 1280, request.camera.viewport_height = 720;
    indices = malloc(sizeof(uint32_t) * 3 * (size_t)mesh.triangle_count);
    for (f = 0; f < 200 && indices; ++f) {
        double extract_ms = 0, render_ms = 0, start = now_ms(), reserve = tcr_governor_planning_reserve_ms(governor);
        const int warming_up = tcr_governor_warming_up(governor);
        if (tcr_governor_plan_frame(governor, &request, &report) != TOM_OK) goto failed;
        for (id = 0; id < 64; ++id) { /* each drawn object's level, extracted and drawn */
            tcr_object_result o;
            tom_extracted e;
            double drawn_at;
            if (tcr_runtime_object(rt, id, &o) != TOM_OK || !o.drawn) continue;
            start = now_ms();
            tcr_runtime_indices_u32(rt, id, indices, 3 * (size_t)mesh.triangle_count, &e);
            drawn_at = now_ms();
            draw(&cpu, indices, 3 * (size_t)e.triangle_count, transforms[id]);
            extract_ms += drawn_at - start, render_ms += now_ms() - drawn_at;
        }
        tcr_governor_frame_done(governor, extract_ms, render_ms, -1.0);
        if (warming_up || f < 30) continue; /* the correction settles */
        ++frames, over += reserve + extract_ms + render_ms > 1.1 * gp.budget_ms, total_ms += reserve + extract_ms + render_ms;
        triangles += report.triangles;
    }
    printf("calibrated %.3g ms a triangle; 64 objects, %d frames at %.1f ms: %d over 1.1x the budget, mean %.2f ms, %.0f%% of the triangles "
           "(checksum %.0f)\n", model.t_tri_ms + 0.5 * model.t_vert_ms, frames, gp.budget_ms, over, total_ms / (frames ? frames : 1),
           100.0 * triangles / (frames ? frames : 1) / (64.0 * mesh.triangle_count), cpu.sink);
    free(indices);
    tcr_governor_destroy(governor);
    tcr_runtime_destroy(rt);
    tom_file_close(file);
    return 0;
failed:
    fprintf(stderr, "error: %s\n", tom_last_error());
    tcr_governor_destroy(governor);
    tcr_runtime_destroy(rt);
    tom_file_close(file);
    return 1;
}
