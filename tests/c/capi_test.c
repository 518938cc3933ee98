/* The C API (tom/tom.h), compiled as C99 with -Wall -Wextra -pedantic -Werror: builds a mesh
 * from strided arrays through a counting allocator, opens the image in place and from a file,
 * extracts every level the report uses with both index widths, and checks the failures' statuses
 * and messages. With a .tom path argument (a real mesh built by tombuild), runs the extraction
 * checks on each of its meshes too, and drives libtcr (tom/tcr.h) over copies of its first mesh.
 * Usage: capi_test WORK_DIR [FILE.tom] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tom/tcr.h"
#include "tom/tom.h"

#include "check.h"

/* An allocator that counts what it hands out. */
typedef struct counting {
    size_t allocations, releases, bytes;
} counting;

static void* counting_allocate(void* user, size_t bytes) {
    counting* c = (counting*)user;
    ++c->allocations;
    c->bytes += bytes;
    return malloc(bytes);
}

static void counting_release(void* user, void* pointer) {
    ++((counting*)user)->releases;
    free(pointer);
}

/* A height field of n x n vertices, positions and normals interleaved (a stride of 6 floats). */
typedef struct grid {
    uint32_t n, vertex_count, triangle_count;
    float* vertices;
    uint16_t* indices;
} grid;

static grid make_grid(uint32_t n) {
    grid g;
    uint32_t i, j, t = 0;
    g.n = n;
    g.vertex_count = n * n;
    g.triangle_count = 2 * (n - 1) * (n - 1);
    g.vertices = malloc(sizeof(float) * 6 * g.vertex_count);
    g.indices = malloc(sizeof(uint16_t) * 3 * g.triangle_count);
    for (j = 0; j < n; ++j)
        for (i = 0; i < n; ++i) {
            float* v = g.vertices + 6 * (j * n + i);
            v[0] = (float)i / (float)(n - 1);
            v[1] = (float)j / (float)(n - 1);
            v[2] = 0.1f * (float)sin(6.0 * v[0]) * (float)cos(4.0 * v[1]);
            v[3] = 0.0f, v[4] = 0.0f, v[5] = 1.0f;
        }
    for (j = 0; j + 1 < n; ++j)
        for (i = 0; i + 1 < n; ++i) {
            const uint16_t a = (uint16_t)(j * n + i);
            const uint16_t quad[6] = {a, (uint16_t)(a + 1), (uint16_t)(a + n + 1), a, (uint16_t)(a + n + 1), (uint16_t)(a + n)};
            memcpy(g.indices + 6 * t++, quad, sizeof quad);
        }
    return g;
}

static tom_build_mesh build_input(const grid* g) {
    tom_build_mesh m;
    memset(&m, 0, sizeof m);
    m.name = "grid";
    m.vertex_count = g->vertex_count;
    m.triangle_count = g->triangle_count;
    m.positions = g->vertices;
    m.position_stride = 6 * sizeof(float);
    m.normals = g->vertices + 3;
    m.normal_stride = 6 * sizeof(float);
    m.indices = g->indices;
    m.index_size = 2;
    m.material = -1;
    return m;
}

/* Every level of the report's fractions: counts as the queries say, indices in range, no
 * degenerate triangle, fewer triangles at each coarser level, the same indices in both widths. */
static void check_levels(const tom_mesh_view* mesh) {
    static const double fractions[] = {1.0, 0.5, 0.25, 0.1, 0.05, 0.02, 0.01};
    const size_t capacity = 3 * (size_t)mesh->triangle_count;
    uint32_t* out32 = malloc(sizeof(uint32_t) * (capacity + 3));
    uint16_t* out16 = malloc(sizeof(uint16_t) * (capacity + 3));
    uint32_t previous = mesh->triangle_count + 1;
    size_t f, c;
    for (f = 0; f < sizeof fractions / sizeof fractions[0]; ++f) {
        tom_extracted e, e16;
        const uint32_t n = tom_vertex_count_for_fraction(mesh, fractions[f]);
        int in_range = 1, distinct = 1, same = 1;
        CHECK(n >= mesh->min_vertex_count && n <= mesh->vertex_count);
        CHECK(tom_extract_u32(mesh, n, out32, capacity, &e) == TOM_OK);
        CHECK(e.triangle_count == tom_active_triangle_count(mesh, n));
        CHECK(e.triangle_count <= previous);
        CHECK(e.triangle_count >= fractions[f] * mesh->triangle_count - 0.5 || n == mesh->usable_floor);
        previous = e.triangle_count;
        for (c = 0; c < 3 * (size_t)e.triangle_count; ++c) in_range &= out32[c] < e.vertex_count;
        for (c = 0; c < e.triangle_count; ++c)
            distinct &= out32[3 * c] != out32[3 * c + 1] && out32[3 * c + 1] != out32[3 * c + 2] && out32[3 * c] != out32[3 * c + 2];
        CHECK(in_range);
        CHECK(distinct);
        if (e.vertex_count <= 65536) {
            CHECK(tom_extract_u16(mesh, n, out16, capacity, &e16) == TOM_OK);
            CHECK(e16.vertex_count == e.vertex_count && e16.triangle_count == e.triangle_count);
            for (c = 0; c < 3 * (size_t)e.triangle_count; ++c) same &= out16[c] == out32[c];
            CHECK(same);
        }
        /* the parts' draws tile the same buffer, in order, each with its part's material */
        {
            tom_part_draw draws[64];
            tom_extracted ep;
            const uint32_t parts = tom_mesh_part_count(mesh);
            uint32_t p, next = 0, sum = 0;
            CHECK(parts >= 1 && parts <= 64);
            CHECK(tom_extract_parts_u32(mesh, n, out32, capacity, draws, parts, &ep) == TOM_OK);
            CHECK(ep.triangle_count == e.triangle_count);
            for (p = 0; p < parts && p < 64; ++p) {
                tom_part part;
                CHECK(tom_mesh_part(mesh, p, &part) == TOM_OK);
                CHECK(draws[p].first_index == next && draws[p].material == part.material);
                CHECK(draws[p].index_count <= 3 * part.triangle_count);
                next += draws[p].index_count;
                sum += draws[p].index_count;
            }
            CHECK(sum == 3 * e.triangle_count);
            if (parts > 0) {
                CHECK(tom_extract_parts_u32(mesh, n, out32, capacity, draws, parts - 1, &ep) == TOM_ERROR_CAPACITY);
                CHECK(strstr(tom_last_error(), "parts") != NULL);
            }
            CHECK(tom_mesh_part(mesh, parts, &(tom_part){0, 0, 0, 0}) == TOM_ERROR_ARGUMENT);
        }
        /* a buffer one triangle too small for this level is refused; an exact one is enough */
        if (e.triangle_count > 0 && e.triangle_count < mesh->triangle_count) {
            tom_extracted small;
            CHECK(tom_extract_u32(mesh, n, out32, 3 * (size_t)e.triangle_count - 3, &small) == TOM_ERROR_CAPACITY);
            CHECK(strstr(tom_last_error(), "indices") != NULL);
            CHECK(tom_extract_u32(mesh, n, out32, 3 * (size_t)e.triangle_count, &small) == TOM_OK);
            CHECK(small.triangle_count == e.triangle_count);
        }
    }
    free(out32);
    free(out16);
}

static void check_real_file(const char* path) {
    tom_file* file = NULL;
    uint32_t i;
    CHECK(tom_file_open(path, &file) == TOM_OK);
    if (!file) {
        fprintf(stderr, "%s\n", tom_last_error());
        return;
    }
    CHECK(tom_file_mesh_count(file) >= 1);
    {  /* tombuild records what made the file */
        size_t length = 0;
        const char* prov = tom_file_provenance(file, &length);
        CHECK(prov != NULL && length > 40 && strncmp(prov, "{\"tool\":\"tombuild", 17) == 0 && prov[length - 1] == '}');
    }
    for (i = 0; i < tom_file_mesh_count(file); ++i) {
        tom_mesh_view mesh;
        CHECK(tom_file_mesh(file, i, &mesh) == TOM_OK);
        CHECK(mesh.positions != NULL && mesh.normals != NULL);
        CHECK(mesh.min_vertex_count < mesh.vertex_count / 10);
        /* the bunny's file has a usable floor (the mean error within 1%), the others none:
         * selections stop there */
        if (i == 0 && strstr(path, "bunny00") != NULL) CHECK(mesh.usable_floor > mesh.min_vertex_count && mesh.usable_floor < mesh.vertex_count / 10);
        if (strstr(path, "bunny00") == NULL) CHECK(mesh.usable_floor == mesh.min_vertex_count);
        CHECK(tom_vertex_count_for_fraction(&mesh, 0.0) == mesh.usable_floor);
        CHECK(tom_vertex_count_for_triangles(&mesh, 1) == mesh.usable_floor);
        check_levels(&mesh);
    }
    tom_file_close(file);
}

/* A renderer whose frame takes 0.4 ms plus 0.004 ms a draw and 8e-5 ms a triangle, smooth
 * shading only; it counts its frames. */
static double geometry_frame(void* user, const tcr_camera* camera, const tcr_calibration_draw* draws, size_t count, tcr_way way) {
    size_t k;
    double t = 0.4;
    (void)camera;
    if (way != TCR_WAY_SMOOTH) return -1.0;
    for (k = 0; k < count; ++k) t += 0.004 + 8e-5 * (double)(draws[k].index_count / 3);
    ++*(uint32_t*)user;
    return t;
}

/* tcr_calibrate drives the callbacks, recovers the renderer's costs and writes the file. */
static void check_calibrate(const tom_mesh_view* mesh, const char* work) {
    uint32_t frames = 0;
    tcr_calibration_renderer r;
    tcr_cost_model m, read;
    char path[4096];
    const tom_mesh_view* meshes[1];
    meshes[0] = mesh;
    memset(&r, 0, sizeof r);
    r.user = &frames;
    r.width = 640;
    r.height = 480;
    r.time_frame = geometry_frame;
    snprintf(path, sizeof path, "%s/c-calibration.txt", work);
    CHECK(tcr_calibrate(&r, meshes, 1, path, &m) == TOM_OK);
    CHECK(frames > 100);
    CHECK(fabs(m.t_init_ms + m.t_final_ms - 0.4) < 1e-9);
    CHECK(fabs(m.t_tri_ms + 0.5 * m.t_vert_ms - 8e-5) < 0.1 * 8e-5);
    CHECK(fabs(m.t_setup_ms - 0.004) < 0.002);
    CHECK(m.flat_t_tri_ms == 0 && m.textured_t_pix_ms == 0 && m.imposter_t_setup_ms == 0);
    CHECK(tcr_read_cost_model(path, &read) == TOM_OK && fabs(read.t_tri_ms - m.t_tri_ms) <= 1e-8 * m.t_tri_ms);
    CHECK(tcr_calibrate(NULL, meshes, 1, NULL, &m) == TOM_ERROR_ARGUMENT && strstr(tom_last_error(), "renderer is NULL") != NULL);
    CHECK(tcr_calibrate(&r, meshes, 0, NULL, &m) == TOM_ERROR_ARGUMENT && strstr(tom_last_error(), "no meshes") != NULL);
    snprintf(path, sizeof path, "%s/no-such-folder/c-calibration.txt", work);
    frames = 0;
    CHECK(tcr_calibrate(&r, meshes, 1, path, &m) == TOM_ERROR_IO && frames == 0);
}

/* libtcr through tom/tcr.h: 24 copies of the file's first mesh, a governor holding 8 ms over a
 * renderer whose frames take 1.2x the prediction; each drawn object's level extracts as reported;
 * the warm-up folds extraction into t_tri; bad calls fail with their status and message. */
static void check_tcr(const char* path, const char* work) {
    tom_file* file = NULL;
    tom_mesh_view mesh;
    tcr_cost_model model;
    tcr_runtime* rt = NULL;
    tcr_governor* governor = NULL;
    tcr_governor_params gp;
    tcr_frame_params fp;
    tcr_frame_report report;
    tcr_object_result object;
    tom_extracted e;
    uint32_t i, id = 0, drawn_frames = 0;
    uint32_t* buffer;
    char model_path[4096];
    FILE* bad;
    CHECK(tom_file_open(path, &file) == TOM_OK);
    if (!file) return;
    CHECK(tom_file_mesh(file, 0, &mesh) == TOM_OK);
    buffer = malloc(sizeof(uint32_t) * 3 * (size_t)mesh.triangle_count);
    memset(&model, 0, sizeof model);
    model.t_init_ms = model.t_final_ms = 0.5;
    model.t_setup_ms = 0.02;
    model.t_tri_ms = 2e-5;
    model.t_vert_ms = 1e-5;
    model.t_pix_ms = 1e-6;
    model.safety_ms = 0.2;
    CHECK(tcr_runtime_create(&model, TCR_SELECTOR_EXACT, &rt) == TOM_OK);
    for (i = 0; i < 24; ++i) {
        float t[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -3, 1};
        t[12] = 0.3f * (float)(i % 6) - 0.75f;
        t[13] = 0.3f * (float)(i / 6) - 0.45f;
        CHECK(tcr_runtime_add_object(rt, &mesh, t, 1.0f, &id) == TOM_OK && id == i);
    }
    CHECK(tcr_runtime_object_count(rt) == 24);
    tcr_governor_params_default(&gp);
    gp.budget_ms = 8.0;
    CHECK(tcr_governor_create(rt, &model, &gp, &governor) == TOM_OK);
    tcr_frame_params_default(&fp);
    fp.camera.projection[0] = fp.camera.projection[5] = 1.5f; /* a perspective, eye at the origin looking down -z */
    fp.camera.projection[10] = -1.0f;
    fp.camera.projection[11] = -1.0f;
    fp.camera.projection[14] = -0.2f;
    fp.camera.projection[15] = 0.0f;
    fp.camera.viewport_width = 800;
    fp.camera.viewport_height = 600;
    for (i = 0; i < 40; ++i) {
        uint32_t k, triangles = 0, in_range = 1;
        CHECK(tcr_governor_plan_frame(governor, &fp, &report) == TOM_OK);
        for (k = 0; k < tcr_runtime_object_count(rt); ++k) {
            size_t c;
            CHECK(tcr_runtime_object(rt, k, &object) == TOM_OK);
            if (!object.drawn) continue;
            CHECK(tcr_runtime_indices_u32(rt, k, buffer, 3 * (size_t)mesh.triangle_count, &e) == TOM_OK);
            CHECK(e.triangle_count == object.triangles && e.vertex_count == object.vertices);
            for (c = 0; c < 3 * (size_t)e.triangle_count; ++c) in_range &= buffer[c] < e.vertex_count;
            triangles += e.triangle_count;
        }
        CHECK(in_range);
        CHECK(triangles == report.triangles);
        drawn_frames += report.drawn > 0;
        /* extraction 1e-6 ms a triangle; the renderer 1.2x slower than predicted */
        CHECK(tcr_governor_frame_done(governor, 1e-6 * triangles, 1.2 * report.predicted_ms, -1.0) == TOM_OK);
    }
    CHECK(drawn_frames == 40);
    CHECK(!tcr_governor_warming_up(governor));
    CHECK(tcr_governor_planning_reserve_ms(governor) >= 0.02 * gp.budget_ms);
    {
        tcr_cost_model now;
        CHECK(tcr_governor_model(governor, &now) == TOM_OK);
        CHECK(fabs(now.t_tri_ms - (model.t_tri_ms + 1.25e-6)) < 1e-12);
    }
    CHECK(report.predicted_ms <= gp.budget_ms * 1.01);

    /* failures: their status and message */
    CHECK(tcr_runtime_object(rt, 24, &object) == TOM_ERROR_ARGUMENT && strstr(tom_last_error(), "object 24") != NULL);
    {
        const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        CHECK(tcr_runtime_add_object(NULL, &mesh, identity, 1.0f, &id) == TOM_ERROR_ARGUMENT && strstr(tom_last_error(), "runtime is NULL") != NULL);
        CHECK(tcr_runtime_add_object(rt, &mesh, identity, 0.0f, &id) == TOM_ERROR_ARGUMENT && strstr(tom_last_error(), "weight") != NULL);
    }
    CHECK(tcr_runtime_create(&model, (tcr_selector)9, &rt) == TOM_ERROR_ARGUMENT && strstr(tom_last_error(), "selector 9") != NULL);
    for (i = 0; i < 24; ++i) { /* a buffer of 2 indices holds no drawn object's level */
        CHECK(tcr_runtime_object(rt, i, &object) == TOM_OK);
        if (object.drawn) {
            CHECK(tcr_runtime_indices_u32(rt, i, buffer, 2, &e) == TOM_ERROR_CAPACITY && strstr(tom_last_error(), "the buffer holds 2") != NULL);
            break;
        }
    }
    snprintf(model_path, sizeof model_path, "%s/no-such-calibration.txt", work);
    CHECK(tcr_read_cost_model(model_path, &model) == TOM_ERROR_IO && strstr(tom_last_error(), "no-such-calibration.txt") != NULL);
    snprintf(model_path, sizeof model_path, "%s/bad-calibration.txt", work);
    bad = fopen(model_path, "w");
    if (bad) {
        fputs("t_init_ms 0.5\nt_tri_ms lots\n", bad);
        fclose(bad);
    }
    CHECK(tcr_read_cost_model(model_path, &model) == TOM_ERROR_PARSE && strstr(tom_last_error(), "bad-calibration.txt") != NULL);
    CHECK(strcmp(tom_status_name(TOM_ERROR_PARSE), "TOM_ERROR_PARSE") == 0);
    check_calibrate(&mesh, work);

    tcr_governor_destroy(governor);
    tcr_runtime_destroy(rt);
    free(buffer);
    tom_file_close(file);
}

int main(int argc, char** argv) {
    char path[4096];
    grid g = make_grid(40);
    tom_build_mesh input = build_input(&g);
    tom_build_params params;
    counting count = {0, 0, 0};
    tom_allocator allocator;
    void* bytes = NULL;
    size_t size = 0;
    tom_file *memory = NULL, *mapped = NULL;
    tom_mesh_view mesh, mesh_mapped;
    tom_instance instance;
    tom_morphed_vertex morph;
    if (argc < 2) {
        fprintf(stderr, "usage: capi_test WORK_DIR [FILE.tom]\n");
        return 2;
    }
    allocator.allocate = counting_allocate;
    allocator.release = counting_release;
    allocator.user = &count;
    tom_build_params_default(&params);
    params.threads = 2;
    CHECK(strcmp(tom_status_name(TOM_ERROR_CAPACITY), "TOM_ERROR_CAPACITY") == 0);
    CHECK(tom_format_version_major() == 1);

    /* building: the image comes from the caller's allocator, once */
    CHECK(tom_build_memory(&input, 1, &params, &allocator, &bytes, &size) == TOM_OK);
    CHECK(count.allocations == 1 && count.bytes == size && bytes != NULL);

    /* in place: the streams point into the caller's bytes */
    CHECK(tom_file_open_memory(bytes, size, "grid-image", &memory) == TOM_OK);
    CHECK(tom_file_mesh_count(memory) == 1);
    {  /* the builder alone records nothing */
        size_t length = 7;
        CHECK(tom_file_provenance(memory, &length) == NULL && length == 0);
    }
    CHECK(tom_file_mesh(memory, 0, &mesh) == TOM_OK);
    CHECK(mesh.vertex_count == g.vertex_count && mesh.triangle_count == g.triangle_count);
    CHECK(mesh.name_length == 4 && memcmp(mesh.name, "grid", 4) == 0);
    CHECK((const char*)mesh.positions > (const char*)bytes && (const char*)mesh.positions < (const char*)bytes + size);
    CHECK(mesh.index_size == 2 && mesh.normals != NULL && mesh.texcoords == NULL);
    CHECK(mesh.min_vertex_count < mesh.vertex_count / 10);
    CHECK(mesh.usable_floor == mesh.min_vertex_count); /* no floor stored: the chain's */
    check_levels(&mesh);
    CHECK(tom_file_mesh(memory, 1, &mesh_mapped) == TOM_ERROR_ARGUMENT);
    CHECK(strstr(tom_last_error(), "mesh 1 of a file with 1") != NULL);

    /* the scene of a file without one: each mesh once, untransformed */
    CHECK(tom_file_material_count(memory) == 0);
    CHECK(tom_file_instance_count(memory) == 1);
    CHECK(tom_file_instance(memory, 0, &instance) == TOM_OK);
    CHECK(instance.mesh == 0 && instance.transform[0] == 1.0f && instance.transform[12] == 0.0f);

    /* a geomorph ends at the vertex's own position and starts at its substitute's */
    {
        const uint32_t n = mesh.min_vertex_count + 1;
        const uint32_t s = mesh.index_size == 2 ? ((const uint16_t*)mesh.substitute)[n] : ((const uint32_t*)mesh.substitute)[n];
        CHECK(tom_geomorph(&mesh, n, 1.0f, &morph) == TOM_OK);
        CHECK(morph.index == n && morph.position[0] == mesh.positions[3 * n] && morph.position[2] == mesh.positions[3 * n + 2]);
        CHECK(tom_geomorph(&mesh, n, 0.0f, &morph) == TOM_OK);
        CHECK(morph.position[0] == mesh.positions[3 * s] && morph.position[1] == mesh.positions[3 * s + 1]);
        CHECK(tom_geomorph(&mesh, mesh.vertex_count, 0.5f, &morph) == TOM_ERROR_ARGUMENT);
    }

    /* the same mesh written to a file and mapped gives the same bytes and the same levels */
    snprintf(path, sizeof path, "%s/capi-grid.tom", argv[1]);
    CHECK(tom_build_file(&input, 1, &params, path) == TOM_OK);
    CHECK(tom_file_open(path, &mapped) == TOM_OK);
    if (mapped) {
        uint32_t* a = malloc(sizeof(uint32_t) * 3 * mesh.triangle_count);
        uint32_t* b = malloc(sizeof(uint32_t) * 3 * mesh.triangle_count);
        tom_extracted ea, eb;
        const uint32_t n = tom_vertex_count_for_fraction(&mesh, 0.3);
        CHECK(tom_file_mesh(mapped, 0, &mesh_mapped) == TOM_OK);
        CHECK(memcmp(mesh_mapped.positions, mesh.positions, sizeof(float) * 3 * mesh.vertex_count) == 0);
        CHECK(tom_extract_u32(&mesh, n, a, 3 * (size_t)mesh.triangle_count, &ea) == TOM_OK);
        CHECK(tom_extract_u32(&mesh_mapped, n, b, 3 * (size_t)mesh.triangle_count, &eb) == TOM_OK);
        CHECK(ea.triangle_count == eb.triangle_count && memcmp(a, b, sizeof(uint32_t) * 3 * ea.triangle_count) == 0);
        free(a);
        free(b);
        tom_file_close(mapped);
    }

    /* two parts (materials 0 and 1, the first and second half of the triangles), and locked
     * borders: the parts come back with their ranges, every level draws both, and the grid's
     * 4 (n - 1) border vertices survive to the coarsest level */
    {
        tom_build_mesh parted = input;
        tom_build_params locked = params;
        const tom_part halves[2] = {{0, input.triangle_count / 2, 0, 1}, {input.triangle_count / 2, input.triangle_count - input.triangle_count / 2, 1, 1}};
        void* image = NULL;
        size_t image_size = 0;
        tom_file* pf = NULL;
        tom_mesh_view pm;
        parted.parts = halves;
        parted.part_count = 2;
        locked.lock_borders = 1;
        CHECK(tom_build_memory(&parted, 1, &locked, NULL, &image, &image_size) == TOM_OK);
        CHECK(tom_file_open_memory(image, image_size, "parts", &pf) == TOM_OK);
        if (pf && tom_file_mesh(pf, 0, &pm) == TOM_OK) {
            tom_part part;
            CHECK(tom_mesh_part_count(&pm) == 2);
            CHECK(tom_mesh_part(&pm, 1, &part) == TOM_OK && part.material == 1 && part.first_triangle == input.triangle_count / 2);
            CHECK(pm.min_vertex_count >= 4 * (40 - 1));
            check_levels(&pm);
        }
        tom_file_close(pf);
        free(image);
        parted.parts = NULL; /* part_count 2 without the parts */
        CHECK(tom_build_memory(&parted, 1, &locked, NULL, &image, &image_size) == TOM_ERROR_ARGUMENT);
        CHECK(strstr(tom_last_error(), "parts is NULL") != NULL);
    }

    /* a closed octahedron: kept, its topology stops at a tetrahedron (4 vertices, 4 triangles);
     * by default its last step joins two sheets (a double-sided triangle) */
    {
        static const float octahedron[18] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
        static const uint16_t faces[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
        tom_build_mesh closed;
        tom_build_params kept = params;
        uint32_t floors[2] = {0, 0};
        int k;
        memset(&closed, 0, sizeof closed);
        closed.vertex_count = 6;
        closed.triangle_count = 8;
        closed.positions = octahedron;
        closed.position_stride = 3 * sizeof(float);
        closed.indices = faces;
        closed.index_size = 2;
        closed.material = -1;
        CHECK(params.keep_topology == 0);
        for (k = 0; k < 2; ++k) {
            void* image = NULL;
            size_t image_size = 0;
            tom_file* of = NULL;
            tom_mesh_view om;
            kept.keep_topology = k;
            CHECK(tom_build_memory(&closed, 1, &kept, NULL, &image, &image_size) == TOM_OK);
            CHECK(tom_file_open_memory(image, image_size, "octahedron", &of) == TOM_OK);
            if (of && tom_file_mesh(of, 0, &om) == TOM_OK) floors[k] = tom_active_triangle_count(&om, om.min_vertex_count) * 10 + om.min_vertex_count;
            tom_file_close(of);
            free(image);
        }
        CHECK(floors[1] == 44);           /* 4 triangles on 4 vertices */
        CHECK(floors[0] == 23);           /* 2 triangles on 3 vertices */
    }

    /* a changed byte is a format error naming the buffer and the rule; the file stays unopened */
    {
        unsigned char* copy = malloc(size);
        tom_file* broken = NULL;
        memcpy(copy, bytes, size);
        copy[size / 2] ^= 0x40;
        CHECK(tom_file_open_memory(copy, size, "flipped", &broken) == TOM_ERROR_FORMAT);
        CHECK(broken == NULL);
        CHECK(strncmp(tom_last_error(), "flipped: byte ", 14) == 0 && strstr(tom_last_error(), "rule") != NULL);
        free(copy);
    }
    snprintf(path, sizeof path, "%s/no-such-file.tom", argv[1]);
    CHECK(tom_file_open(path, &mapped) == TOM_ERROR_IO);
    CHECK(strstr(tom_last_error(), "no-such-file.tom") != NULL);

    /* a mesh whose index passes its vertices is refused, naming it; nothing is allocated */
    {
        const size_t before = count.allocations;
        void* none = NULL;
        size_t none_size = 0;
        g.indices[5] = (uint16_t)g.vertex_count;
        CHECK(tom_build_memory(&input, 1, &params, &allocator, &none, &none_size) == TOM_ERROR_MESH);
        CHECK(strstr(tom_last_error(), "grid") != NULL);
        CHECK(none == NULL && count.allocations == before);
        input.position_stride = 8; /* less than a position */
        CHECK(tom_build_memory(&input, 1, &params, &allocator, &none, &none_size) == TOM_ERROR_ARGUMENT);
        CHECK(strstr(tom_last_error(), "position stride") != NULL);
    }
    CHECK(tom_file_open(NULL, &mapped) == TOM_ERROR_ARGUMENT);

    if (argc > 2) check_real_file(argv[2]);
    if (argc > 2) check_tcr(argv[2], argv[1]);
    if (argc > 3) { /* a file with multi-part meshes (2CylinderEngine: four meshes of several primitives) */
        tom_file* parts_file = NULL;
        uint32_t i, multi = 0;
        CHECK(tom_file_open(argv[3], &parts_file) == TOM_OK);
        for (i = 0; i < tom_file_mesh_count(parts_file); ++i) {
            tom_mesh_view v;
            CHECK(tom_file_mesh(parts_file, i, &v) == TOM_OK);
            if (tom_mesh_part_count(&v) < 2) continue;
            ++multi;
            check_levels(&v);
        }
        CHECK(multi == 4);
        CHECK(tom_file_image_count(parts_file) == 0);
        tom_file_close(parts_file);
    }
    if (argc > 4) { /* a GLB whose texture's PNG lives in its binary buffer: stored, handed out in place */
        tom_file* box = NULL;
        tom_image image;
        int32_t shown = -2;
        CHECK(tom_file_open(argv[4], &box) == TOM_OK);
        CHECK(tom_file_image_count(box) == 1);
        CHECK(tom_file_image(box, 0, &image) == TOM_OK);
        CHECK(strcmp(image.mime_type, "image/png") == 0);
        CHECK(image.bytes > 8 && memcmp(image.data, "\x89PNG\r\n\x1a\n", 8) == 0);
        CHECK(tom_file_texture_image(box, 0, 0, &shown) == TOM_OK && shown == 0);
        CHECK(tom_file_image(box, 1, &image) == TOM_ERROR_ARGUMENT);
        CHECK(tom_file_texture_image(box, 0, 1, &shown) == TOM_ERROR_ARGUMENT);
        tom_file_close(box);
    }

    tom_file_close(memory);
    allocator.release(allocator.user, bytes);
    CHECK(count.releases == 1);
    free(g.vertices);
    free(g.indices);
    printf("%d of %d checks passed\n", checks - failures, checks);
    return failures == 0 ? 0 : 1;
}
