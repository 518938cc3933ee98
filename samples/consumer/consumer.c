/* The C API's consumer: maps a .tom file and prints, per mesh, the index count at 10% of its
 * triangles; with a fraction, prints instead the first mesh's triangles at that fraction as OBJ
 * faces (1-based), the lines tomextract writes. Builds with a plain C compiler:
 *   cc consumer.c $(pkg-config --cflags --libs tom)
 * Usage: tom_c_consumer FILE.tom [FRACTION] */
#include <stdio.h>
#include <stdlib.h>

#include "tom/tom.h"

int main(int argc, char** argv) {
    tom_file* file = NULL;
    uint32_t i, t;
    if (argc != 2 && argc != 3) {
        fprintf(stderr, "usage: %s FILE.tom [FRACTION]\n", argv[0]);
        return 2;
    }
    if (tom_file_open(argv[1], &file) != TOM_OK) {
        fprintf(stderr, "error: %s\n", tom_last_error());
        return 1;
    }
    for (i = 0; i < tom_file_mesh_count(file); ++i) {
        tom_mesh_view mesh;
        tom_extracted level;
        uint32_t* indices;
        uint32_t n;
        tom_file_mesh(file, i, &mesh);
        indices = malloc(sizeof(uint32_t) * 3 * (size_t)mesh.triangle_count + 1); /* once; reused every frame */
        n = tom_vertex_count_for_fraction(&mesh, argc == 3 ? atof(argv[2]) : 0.10);
        if (!indices || tom_extract_u32(&mesh, n, indices, 3 * (size_t)mesh.triangle_count, &level) != TOM_OK) {
            fprintf(stderr, "error: %s\n", indices ? tom_last_error() : "out of memory");
            free(indices);
            tom_file_close(file);
            return 1;
        }
        if (argc == 3) {
            for (t = 0; t < level.triangle_count; ++t)
                printf("f %u//%u %u//%u %u//%u\n", indices[3 * t] + 1, indices[3 * t] + 1, indices[3 * t + 1] + 1, indices[3 * t + 1] + 1,
                       indices[3 * t + 2] + 1, indices[3 * t + 2] + 1);
            free(indices);
            break;
        }
        printf("%.*s: %u vertices, %u triangles; at 10%%: %u vertices, %u triangles, %u indices\n", (int)mesh.name_length, mesh.name,
               mesh.vertex_count, mesh.triangle_count, level.vertex_count, level.triangle_count, level.triangle_count * 3);
        free(indices);
    }
    tom_file_close(file);
    return 0;
}
