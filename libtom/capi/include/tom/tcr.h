/* libtcr's C API (C99): time-critical rendering for engines that bind a C ABI. Each frame the
 * runtime chooses every visible object's resolution so the frame fits a time budget with the best
 * image; the governor around it holds that budget on a real, noisy machine (docs/TCR.md).
 *
 *   tcr_cost_model model;  tcr_read_cost_model("calibration.txt", &model);
 *   tcr_runtime* rt;       tcr_runtime_create(&model, TCR_SELECTOR_EXACT, &rt);
 *   for each object:       tcr_runtime_add_object(rt, &mesh_view, transform, 1.0f, &id);
 *   tcr_governor_params gp; tcr_governor_params_default(&gp); gp.budget_ms = 16.0;
 *   tcr_governor* g;       tcr_governor_create(rt, &model, &gp, &g);
 *   each frame:
 *     tcr_frame_params f;  tcr_frame_params_default(&f);  (fill f.camera)
 *     tcr_governor_plan_frame(g, &f, &report);
 *     for each id with tcr_runtime_object(rt, id, &o) and o.drawn: tcr_runtime_indices_u32(...), draw
 *     tcr_governor_frame_done(g, extract_ms, render_ms, -1.0);
 *
 * The conventions of tom/tom.h hold: a function that can fail returns a tom_status and leaves a
 * message in tom_last_error(); nothing C++ crosses the header. A runtime keeps pointers into the
 * tom_file its objects' views came from: close the file after destroying the runtime. Planning,
 * the governor's calls and extraction allocate nothing once the runtime has planned a frame.
 */
#ifndef TOM_TCR_H
#define TOM_TCR_H

#include "tom/tom.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The calibrated frame cost model (docs/CALIBRATION.md; tcr::CostModel): milliseconds. */
typedef struct tcr_cost_model {
    double t_init_ms, t_final_ms, t_setup_ms, t_tri_ms, t_vert_ms, t_pix_ms, safety_ms, noise_rel;
    double flat_t_tri_ms, flat_t_vert_ms, flat_t_pix_ms;
    double textured_t_tri_ms, textured_t_vert_ms, textured_t_pix_ms;
    double imposter_t_setup_ms, imposter_t_pix_ms, refresh_t_setup_ms, meshed_t_tri_ms, meshed_refresh_t_setup_ms;
} tcr_cost_model;

/* Reads a calibration file (TOM_ERROR_IO unreadable, TOM_ERROR_PARSE naming the line). */
tom_status tcr_read_cost_model(const char* path, tcr_cost_model* out);

typedef enum tcr_selector {
    TCR_SELECTOR_STATIC = 0, /* triangles proportional to screen coverage */
    TCR_SELECTOR_STRESS = 1, /* the TOM paper's load feedback */
    TCR_SELECTOR_GREEDY = 2, /* Funkhouser's incremental greedy */
    TCR_SELECTOR_BARRIER = 3, /* Gobbetti & Bouvier's interior point, certified */
    TCR_SELECTOR_EXACT = 4    /* Lagrange multiplier by bisection, certified */
} tcr_selector;

typedef struct tcr_camera {
    float view[16];       /* world -> eye, column-major */
    float projection[16]; /* eye -> clip */
    uint32_t viewport_width, viewport_height;
} tcr_camera;

/* One frame's request (tcr::FrameParams). With the governor, budget_ms, previous_frame_ms and
 * deadline_ms are its own. */
typedef struct tcr_frame_params {
    tcr_camera camera;
    double budget_ms;         /* the whole frame */
    double previous_frame_ms; /* measured time of the last frame; 0 unknown */
    double deadline_ms;       /* the optimiser's (barrier, exact); 0 none */
    double max_error_px;      /* cap on each object's projected error; 0 none */
    int error_bounded;        /* nonzero: ignore the budget, each object within max_error_px */
    double hysteresis;        /* relative dead band against the previous frame's choice */
} tcr_frame_params;
/* The defaults: a 16 ms budget, an identity camera on a 1 x 1 viewport, no cap. */
void tcr_frame_params_default(tcr_frame_params* params);

typedef struct tcr_frame_report {
    double predicted_ms; /* the plan's extraction and rendering, with the safety allowance */
    double benefit, gap; /* gap: certified relative distance to the optimum (NaN: none) */
    double max_error_px;
    uint32_t visible, drawn;
    uint64_t triangles;
    double cull_ms, optimize_ms;
    int feasible;
} tcr_frame_report;

typedef struct tcr_object_result {
    int visible, drawn;
    uint32_t vertices;  /* the resolution to draw: vertices [0, vertices) */
    uint32_t triangles; /* its triangles */
    float coverage_px;
    double error_px;    /* projected error at that resolution */
    double predicted_ms;
} tcr_object_result;

typedef struct tcr_runtime tcr_runtime;

tom_status tcr_runtime_create(const tcr_cost_model* model, tcr_selector selector, tcr_runtime** out);
void tcr_runtime_destroy(tcr_runtime* runtime); /* NULL is ignored */
/* Adds an object drawing `mesh` (a view filled by tom_file_mesh) with a 4x4 column-major
 * transform; `*id` receives its id (0, 1, 2, ... in order). Its levels stop at the mesh's usable
 * floor. */
tom_status tcr_runtime_add_object(tcr_runtime* runtime, const tom_mesh_view* mesh, const float transform[16], float weight, uint32_t* id);
tom_status tcr_runtime_set_transform(tcr_runtime* runtime, uint32_t id, const float transform[16]);
uint32_t tcr_runtime_object_count(const tcr_runtime* runtime); /* 0 for NULL */
/* Plans a frame without a governor: culls, measures, selects. */
tom_status tcr_runtime_plan_frame(tcr_runtime* runtime, const tcr_frame_params* params, tcr_frame_report* report);
tom_status tcr_runtime_object(const tcr_runtime* runtime, uint32_t id, tcr_object_result* out);
/* The chosen level's index buffer of object `id` (nothing for an object not drawn); 3 x the
 * mesh's triangle count always suffices. */
tom_status tcr_runtime_indices_u32(const tcr_runtime* runtime, uint32_t id, uint32_t* out, size_t capacity, tom_extracted* result);

/* The frame governor (tcr::FrameGovernor, docs/TCR.md). */
typedef struct tcr_governor_params {
    double budget_ms;       /* the whole frame */
    double safety_sigma;    /* allowance in frame-to-frame noise */
    int follow_noise;       /* nonzero: the allowance follows the frames' noise */
    double optimize_share;  /* the optimiser's deadline, a share of the budget */
    uint32_t warm_up_frames;
} tcr_governor_params;
void tcr_governor_params_default(tcr_governor_params* params);

typedef struct tcr_governor tcr_governor;

/* `runtime` must outlive the governor. */
tom_status tcr_governor_create(tcr_runtime* runtime, const tcr_cost_model* calibrated, const tcr_governor_params* params, tcr_governor** out);
void tcr_governor_destroy(tcr_governor* governor); /* NULL is ignored */
tom_status tcr_governor_plan_frame(tcr_governor* governor, const tcr_frame_params* params, tcr_frame_report* report);
/* What the frame planned last took; frame_ms < 0: the planning reserve + extract + render. */
tom_status tcr_governor_frame_done(tcr_governor* governor, double extract_ms, double render_ms, double frame_ms);
int tcr_governor_warming_up(const tcr_governor* governor);
double tcr_governor_planning_reserve_ms(const tcr_governor* governor);
/* The model the runtime plans with now (the allowance and t_tri as the governor keeps them). */
tom_status tcr_governor_model(const tcr_governor* governor, tcr_cost_model* out);

/* Calibration (tcr::calibrate, tcr/calibrate.h): fits the cost model to the engine's renderer by
 * timing frames it draws. The engine fills a tcr_calibration_renderer with its drawing and its
 * clock: each callback draws one cleared frame, waits until it is finished and returns the
 * milliseconds since the call began, or < 0 when the renderer does not draw that way (those
 * coefficients then stay 0). The meshes are the engine's, uploaded in the order given. */
typedef enum tcr_way {
    TCR_WAY_SMOOTH = 0,  /* Gouraud shading: required */
    TCR_WAY_FLAT = 1,
    TCR_WAY_TEXTURED = 4 /* any texture bound */
} tcr_way;

typedef struct tcr_calibration_draw {
    uint32_t mesh;            /* index into tcr_calibrate's meshes */
    const uint32_t* indices;  /* the level's triangles, into that mesh's vertices */
    uint32_t index_count;
    float model[16];          /* object to world, column-major */
} tcr_calibration_draw;

typedef struct tcr_calibration_capture {
    uint32_t slot;            /* an imposter texture slot, 0 to 47 */
    uint32_t side;            /* texels a side */
    float view[16], projection[16];
    uint32_t grid;            /* > 0: a meshed imposter's: its depth read back into grid x grid cells */
    tcr_calibration_draw draw;
} tcr_calibration_capture;

typedef struct tcr_calibration_imposter {
    uint32_t slot;
    int meshed;               /* nonzero: the slot's depth mesh where it was captured */
    float corners[12];        /* simple: world corners of texture (0,0), (1,0), (1,1), (0,1) */
} tcr_calibration_imposter;

typedef struct tcr_calibration_renderer {
    void* user;               /* passed to the callbacks */
    uint32_t width, height;   /* the viewport, pixels */
    double (*time_frame)(void* user, const tcr_camera* camera, const tcr_calibration_draw* draws, size_t count, tcr_way way);
    /* NULL: no imposters. Renders the captures into their slots, then the imposters into the frame. */
    double (*time_imposters)(void* user, const tcr_camera* camera, const tcr_calibration_capture* captures, size_t capture_count,
                             const tcr_calibration_imposter* imposters, size_t imposter_count);
} tcr_calibration_renderer;

/* Times the renderer on `meshes` (about a minute on a software rasterizer) and fits the model
 * into `out`; writes it to `path` when not NULL (TOM_ERROR_IO when its folder is missing,
 * checked first). */
tom_status tcr_calibrate(const tcr_calibration_renderer* renderer, const tom_mesh_view* const* meshes, size_t mesh_count, const char* path,
                         tcr_cost_model* out);

#ifdef __cplusplus
}
#endif

#endif
